//! Preconditioned conjugate gradients for symmetric positive definite systems A x = b, with the
//! [`Preconditioner`] interface that algebraic multigrid ([`super::amg`]) and Jacobi implement.
//!
//! CG minimises the energy norm of the error over the Krylov space of M⁻¹A; with an SPD
//! preconditioner M the iteration count grows like √κ(M⁻¹A). The iteration stops when the
//! relative residual ‖b − A x‖ / ‖b‖ falls below the tolerance; the *true* residual is
//! recomputed then, and CG restarted from it should rounding have let the recursively updated
//! residual drift. A breakdown (pᵀAp ≤ 0, rᵀM⁻¹r ≤ 0, NaN) is an error, never a silent NaN.
//!
//! The vectors of the iteration live in [`Pcg`], allocated once and reused by every solve; the
//! loops run in parallel over chunks of plain slices.

use super::csr::Csr;
use super::error::PcgError;
use super::reduce::{tree_sum, tree_sum_mut};
use rayon::prelude::*;

/// Entries per parallel task in the vector updates.
const CHUNK: usize = 8192;

/// z = M⁻¹ r for a symmetric positive definite M ≈ A.
pub trait Preconditioner: Sync {
    /// z = M⁻¹ r (`z` is overwritten).
    fn apply(&self, r: &[f64], z: &mut [f64]);
}

/// M = I: plain conjugate gradients.
#[derive(Clone, Copy, Debug, Default)]
pub struct Identity;

impl Preconditioner for Identity {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        z.copy_from_slice(r);
    }
}

/// M = diag(A): the Jacobi preconditioner.
#[derive(Clone, Debug)]
pub struct Jacobi {
    inv_diag: Vec<f64>,
}

impl Jacobi {
    /// D⁻¹ of `a`; a non-positive diagonal entry is an error naming the row.
    pub fn new(a: &Csr) -> Result<Self, PcgError> {
        let d = a.diagonal();
        if let Some((row, &value)) = d.iter().enumerate().find(|(_, v)| !(**v > 0.0 && v.is_finite())) {
            return Err(PcgError::NonPositiveDiagonal { row, value });
        }
        Ok(Self { inv_diag: d.iter().map(|v| 1.0 / v).collect() })
    }
}

impl Preconditioner for Jacobi {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        z.par_chunks_mut(CHUNK).zip(r.par_chunks(CHUNK)).zip(self.inv_diag.par_chunks(CHUNK)).for_each(
            |((z, r), d)| {
                for ((z, r), d) in z.iter_mut().zip(r).zip(d) {
                    *z = r * d;
                }
            },
        );
    }
}

/// What a Krylov solve achieved (CG here, MINRES in [`super::minres`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PcgReport {
    /// Iterations (matrix–vector products with A in the Krylov loop).
    pub iterations: usize,
    /// The relative residual of the returned x: for CG ‖b − A x‖ / ‖b‖, recomputed from scratch
    /// (0 when b = 0); for MINRES the caller's [`super::minres::Residual`].
    pub relative_residual: f64,
    /// Whether the relative residual reached the tolerance.
    pub converged: bool,
}

/// Preconditioned conjugate gradients with its work vectors (r, z, p, Ap) allocated once.
#[derive(Clone, Debug)]
pub struct Pcg {
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
}

/// Recomputations of the true residual after the recursive one converged.
const MAX_RESTARTS: usize = 3;

impl Pcg {
    /// Work vectors for systems with `n` unknowns.
    pub fn new(n: usize) -> Self {
        Self { r: vec![0.0; n], z: vec![0.0; n], p: vec![0.0; n], q: vec![0.0; n] }
    }

    /// Order of the systems this workspace solves.
    pub fn n(&self) -> usize {
        self.r.len()
    }

    /// Solves A x = b by CG preconditioned with `m`, from the initial guess in `x`, until
    /// ‖b − A x‖ ≤ `tol` ‖b‖ or `max_iter` iterations. Not converging is reported, not an error;
    /// a breakdown or non-finite data is an error (x then holds the iterate reached).
    pub fn solve(
        &mut self,
        a: &Csr,
        m: &(impl Preconditioner + ?Sized),
        b: &[f64],
        x: &mut [f64],
        tol: f64,
        max_iter: usize,
    ) -> Result<PcgReport, PcgError> {
        let n = self.n();
        for (what, len) in [("matrix rows", a.nrows), ("matrix columns", a.ncols), ("b", b.len()), ("x", x.len())] {
            if len != n {
                return Err(PcgError::DimensionMismatch { what: what.into(), expected: n, found: len });
            }
        }
        let norm_b = dot(b, b).sqrt();
        if !norm_b.is_finite() {
            return Err(PcgError::NonFinite { what: "right-hand side b".into() });
        }
        if !dot(x, x).is_finite() {
            return Err(PcgError::NonFinite { what: "initial guess x".into() });
        }
        if norm_b == 0.0 {
            x.iter_mut().for_each(|v| *v = 0.0);
            return Ok(PcgReport { iterations: 0, relative_residual: 0.0, converged: true });
        }
        let target = tol * norm_b;
        let mut iterations = 0;
        let mut restarts = 0;
        loop {
            a.residual(b, x, &mut self.r);
            let res = dot(&self.r, &self.r).sqrt();
            if !res.is_finite() {
                return Err(PcgError::NonFinite { what: "residual b − A x (A has NaN or infinite entries?)".into() });
            }
            if res <= target || iterations >= max_iter || restarts > MAX_RESTARTS {
                return Ok(PcgReport { iterations, relative_residual: res / norm_b, converged: res <= target });
            }
            restarts += 1;
            iterations = self.iterate(a, m, x, target, max_iter, iterations)?;
        }
    }

    /// The CG loop from r = b − A x (in `self.r`) until the recursive residual reaches
    /// `target` or `max_iter` total iterations; returns the iteration count.
    fn iterate(
        &mut self,
        a: &Csr,
        m: &(impl Preconditioner + ?Sized),
        x: &mut [f64],
        target: f64,
        max_iter: usize,
        mut it: usize,
    ) -> Result<usize, PcgError> {
        let Self { r, z, p, q } = self;
        m.apply(r, z);
        p.copy_from_slice(z);
        let mut rz = dot(r, z);
        check_positive(rz, "r·M⁻¹r (is the preconditioner positive definite?)", it)?;
        while it < max_iter {
            it += 1;
            a.spmv(p, q);
            let pq = dot(p, q);
            check_positive(pq, "p·Ap (is A positive definite?)", it)?;
            let alpha = rz / pq;
            let rr = update_x_r(alpha, p, q, x, r);
            if !rr.is_finite() {
                return Err(PcgError::Breakdown { iteration: it, quantity: "r·r".into(), value: rr });
            }
            if rr.sqrt() <= target {
                break;
            }
            m.apply(r, z);
            let rz_new = dot(r, z);
            check_positive(rz_new, "r·M⁻¹r (is the preconditioner positive definite?)", it)?;
            let beta = rz_new / rz;
            rz = rz_new;
            p.par_chunks_mut(CHUNK).zip(z.par_chunks(CHUNK)).for_each(|(p, z)| {
                for (p, z) in p.iter_mut().zip(z) {
                    *p = z + beta * *p;
                }
            });
        }
        Ok(it)
    }
}

fn check_positive(value: f64, quantity: &str, iteration: usize) -> Result<(), PcgError> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(PcgError::Breakdown { iteration, quantity: quantity.into(), value })
    }
}

/// x += α p, r −= α q; returns r·r.
fn update_x_r(alpha: f64, p: &[f64], q: &[f64], x: &mut [f64], r: &mut [f64]) -> f64 {
    tree_sum_mut(x, r, &|x, r, leaf| {
        let mut s = 0.0;
        for (((x, r), p), q) in x.iter_mut().zip(r.iter_mut()).zip(&p[leaf.clone()]).zip(&q[leaf.clone()]) {
            *x += alpha * p;
            *r -= alpha * q;
            s += *r * *r;
        }
        s
    })
}

/// x·y, in parallel, the same bits on any number of threads ([`tree_sum`]).
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    assert_eq!(x.len(), y.len());
    tree_sum(0..x.len(), &|leaf| x[leaf.clone()].iter().zip(&y[leaf]).map(|(a, b)| a * b).sum())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 1D Laplacian tridiag(−1, 2, −1).
    fn laplacian(n: usize) -> Csr {
        let mut ptr = vec![0];
        let (mut idx, mut val) = (vec![], vec![]);
        for i in 0..n {
            if i > 0 {
                idx.push(i as u32 - 1);
                val.push(-1.0);
            }
            idx.push(i as u32);
            val.push(2.0);
            if i + 1 < n {
                idx.push(i as u32 + 1);
                val.push(-1.0);
            }
            ptr.push(idx.len());
        }
        Csr { nrows: n, ncols: n, ptr, idx, val }
    }

    #[test]
    fn cg_solves_the_laplacian_in_n_steps() {
        let n = 100;
        let a = laplacian(n);
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64 * 0.1).sin()).collect();
        let mut b = vec![0.0; n];
        a.spmv(&x_true, &mut b);
        let mut x = vec![0.0; n];
        let mut pcg = Pcg::new(n);
        let rep = pcg.solve(&a, &Identity, &b, &mut x, 1e-10, 1000).unwrap();
        assert!(rep.converged && rep.relative_residual <= 1e-10, "{rep:?}");
        // exact arithmetic: at most n/2 + 1 steps for this spectrum
        assert!(rep.iterations <= n, "{rep:?}");
        assert!(x.iter().zip(&x_true).all(|(a, b)| (a - b).abs() < 1e-7));
        // Jacobi on a constant diagonal is CG again; the workspace is reused
        let mut y = vec![0.0; n];
        let rep2 = pcg.solve(&a, &Jacobi::new(&a).unwrap(), &b, &mut y, 1e-10, 1000).unwrap();
        assert_eq!(rep.iterations, rep2.iterations);
    }

    #[test]
    fn not_converging_is_reported_and_breakdowns_are_errors() {
        let n = 50;
        let mut a = laplacian(n);
        let b = vec![1.0; n];
        let mut x = vec![0.0; n];
        let mut pcg = Pcg::new(n);
        let rep = pcg.solve(&a, &Identity, &b, &mut x, 1e-12, 3).unwrap();
        assert!(!rep.converged && rep.iterations == 3 && rep.relative_residual > 1e-12, "{rep:?}");
        // an indefinite matrix: −A
        a.val.iter_mut().for_each(|v| *v = -*v);
        x.iter_mut().for_each(|v| *v = 0.0);
        let e = pcg.solve(&a, &Identity, &b, &mut x, 1e-12, 100).unwrap_err();
        assert!(matches!(e, PcgError::Breakdown { iteration: 1, .. }), "{e}");
        assert!(Jacobi::new(&a).is_err());
        let e = pcg.solve(&laplacian(n), &Identity, &[f64::NAN; 50], &mut x, 1e-12, 100).unwrap_err();
        assert!(matches!(e, PcgError::NonFinite { .. }), "{e}");
        let e = pcg.solve(&laplacian(n), &Identity, &[1.0; 49], &mut x, 1e-12, 100).unwrap_err();
        assert!(matches!(e, PcgError::DimensionMismatch { .. }), "{e}");
        // b = 0 gives x = 0 at once
        x.iter_mut().for_each(|v| *v = 1.0);
        let rep = pcg.solve(&laplacian(n), &Identity, &[0.0; 50], &mut x, 1e-12, 100).unwrap();
        assert!(rep.converged && rep.iterations == 0 && x.iter().all(|v| *v == 0.0));
    }
}
