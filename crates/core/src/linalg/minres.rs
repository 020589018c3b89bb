//! Preconditioned MINRES (Paige & Saunders 1975) for symmetric, possibly indefinite systems
//! 𝒜 z = b with a symmetric positive definite preconditioner 𝓜 (theory §10.1, the pressure
//! block).
//!
//! MINRES minimises ‖b − 𝒜 z‖_{𝓜⁻¹} over the Krylov space of 𝓜⁻¹𝒜 by a three-term Lanczos
//! recurrence and Givens rotations; unlike CG it needs 𝒜 symmetric only, so it solves saddle-point
//! systems [A Bᵀ; B −C] with a block-diagonal preconditioner (Silvester & Wathen 1994). The
//! iteration stops on MINRES's own estimate ‖b − 𝒜 z‖_{𝓜⁻¹} ≤ tol ‖b − 𝒜 z₀‖_{𝓜⁻¹} (z₀ the
//! start), or on a residual of
//! the caller's ([`Residual`]; for the pressure block: that of the displacement system K x = b
//! the saddle system is equivalent to), checked whenever the estimate has fallen by the
//! tolerance, the iteration going on with the estimate's target lowered until the caller's is
//! met.

use super::error::PcgError;
use super::pcg::{Preconditioner, dot};
use rayon::prelude::*;

/// Entries per parallel task in the vector updates.
const CHUNK: usize = 8192;

/// y = 𝒜 x for a symmetric 𝒜.
pub trait SymmetricOperator: Sync {
    /// y = 𝒜 x (`y` is overwritten).
    fn apply(&self, x: &[f64], y: &mut [f64]);
}

/// The caller's measure of convergence: the relative residual of the system that the iterate
/// `z` is meant to solve (for an unchanged problem: ‖b − 𝒜 z‖ / ‖b‖).
pub trait Residual {
    /// The relative residual of `z`.
    fn relative(&mut self, z: &[f64]) -> f64;
}

/// What a MINRES solve achieved: CG's report (its iterations are products with 𝒜 in the
/// Lanczos loop, its residual the caller's [`Residual`] of the returned iterate).
pub type MinresReport = super::pcg::PcgReport;

/// MINRES with its work vectors allocated once.
#[derive(Clone, Debug)]
pub struct Minres {
    r1: Vec<f64>,
    r2: Vec<f64>,
    y: Vec<f64>,
    v: Vec<f64>,
    w: Vec<f64>,
    w1: Vec<f64>,
    w2: Vec<f64>,
}

/// Times the estimate's target is lowered before the solve gives up on the caller's residual.
const MAX_TIGHTENINGS: usize = 8;

impl Minres {
    /// Work vectors for systems with `n` unknowns.
    pub fn new(n: usize) -> Self {
        let z = vec![0.0; n];
        Self { r1: z.clone(), r2: z.clone(), y: z.clone(), v: z.clone(), w: z.clone(), w1: z.clone(), w2: z }
    }

    /// Order of the systems this workspace solves.
    pub fn n(&self) -> usize {
        self.r1.len()
    }

    /// Solves 𝒜 z = b from the initial guess z₀ in `z` until ‖b − 𝒜 z‖_{𝓜⁻¹} ≤ `tol`
    /// ‖b − 𝒜 z₀‖_{𝓜⁻¹} (MINRES's own estimate; `residual` None) or the caller's `residual` of z is at most
    /// `tol`, or `max_iter` iterations. With a caller's residual, it is evaluated whenever the
    /// estimate has met its target (at first `tol`), and if it is not met yet the target is
    /// lowered by the ratio and the iteration goes on. Not converging is reported; a breakdown
    /// (𝓜 not positive definite, non-finite data) is an error.
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &mut self,
        a: &(impl SymmetricOperator + ?Sized),
        m: &(impl Preconditioner + ?Sized),
        b: &[f64],
        z: &mut [f64],
        mut residual: Option<&mut dyn Residual>,
        tol: f64,
        max_iter: usize,
    ) -> Result<MinresReport, PcgError> {
        let n = self.n();
        for (what, len) in [("b", b.len()), ("z", z.len())] {
            if len != n {
                return Err(PcgError::DimensionMismatch { what: what.into(), expected: n, found: len });
            }
        }
        let Self { r1, r2, y, v, w, w1, w2 } = self;
        // ‖b‖_{𝓜⁻¹}, the scale of the estimate
        m.apply(b, y);
        let norm_b = dot(b, y);
        if !(norm_b >= 0.0 && norm_b.is_finite()) {
            return Err(PcgError::Breakdown {
                iteration: 0,
                quantity: "b·M⁻¹b (is M positive definite?)".into(),
                value: norm_b,
            });
        }
        let norm_b = norm_b.sqrt();
        let mut rel = match residual.as_deref_mut() {
            Some(res) => res.relative(z),
            None if norm_b == 0.0 => 0.0,
            None => f64::INFINITY,
        };
        if rel.is_nan() {
            return Err(PcgError::NonFinite { what: "the initial residual".into() });
        }
        if rel <= tol || max_iter == 0 {
            return Ok(MinresReport { iterations: 0, relative_residual: rel, converged: rel <= tol });
        }
        // r1 = b − 𝒜 z, y = 𝓜⁻¹ r1, β₁ = ‖r1‖_{𝓜⁻¹}
        a.apply(z, r1);
        r1.par_iter_mut().zip(b.par_iter()).for_each(|(r, b)| *r = b - *r);
        m.apply(r1, y);
        let beta1 = dot(r1, y);
        if !(beta1 > 0.0 && beta1.is_finite()) {
            return Err(PcgError::Breakdown {
                iteration: 0,
                quantity: "r·M⁻¹r (is M positive definite?)".into(),
                value: beta1,
            });
        }
        let beta1 = beta1.sqrt();
        if residual.is_none() && beta1 <= tol * norm_b {
            return Ok(MinresReport { iterations: 0, relative_residual: beta1 / norm_b, converged: true });
        }
        r2.copy_from_slice(r1);
        for x in [&mut *w, &mut *w1, &mut *w2] {
            x.iter_mut().for_each(|x| *x = 0.0);
        }
        let (mut beta, mut oldb, mut dbar, mut epsln, mut phibar) = (beta1, 0.0, 0.0, 0.0, beta1);
        let (mut cs, mut sn) = (-1.0, 0.0);
        let mut target = tol;
        let mut tightenings = 0;
        let mut it = 0;
        while it < max_iter {
            it += 1;
            // Lanczos: v = y/β, y = 𝒜v − (β/β_old) r1 − (α/β) r2
            let s = 1.0 / beta;
            v.par_iter_mut().zip(y.par_iter()).for_each(|(v, y)| *v = s * y);
            a.apply(v, y);
            if it >= 2 {
                let f = beta / oldb;
                y.par_iter_mut().zip(r1.par_iter()).for_each(|(y, r)| *y -= f * r);
            }
            let alfa = dot(v, y);
            let f = alfa / beta;
            y.par_chunks_mut(CHUNK).zip(r2.par_chunks(CHUNK)).zip(r1.par_chunks_mut(CHUNK)).for_each(
                |((y, r2), r1)| {
                    for ((y, r2), r1) in y.iter_mut().zip(r2).zip(r1) {
                        *y -= f * r2;
                        *r1 = *r2;
                    }
                },
            );
            r2.copy_from_slice(y);
            m.apply(r2, y);
            oldb = beta;
            let bb = dot(r2, y);
            if !(bb >= 0.0 && bb.is_finite()) {
                return Err(PcgError::Breakdown {
                    iteration: it,
                    quantity: "r·M⁻¹r (is M positive definite?)".into(),
                    value: bb,
                });
            }
            beta = bb.sqrt();
            // the QR factorisation of the tridiagonal matrix by Givens rotations
            let oldeps = epsln;
            let delta = cs * dbar + sn * alfa;
            let gbar = sn * dbar - cs * alfa;
            epsln = sn * beta;
            dbar = -cs * beta;
            let gamma = gbar.hypot(beta).max(f64::EPSILON);
            cs = gbar / gamma;
            sn = beta / gamma;
            let phi = cs * phibar;
            phibar *= sn;
            // w = (v − ε w1 − δ w2)/γ with the last two w's; z += φ w
            std::mem::swap(w1, w2);
            std::mem::swap(w2, w);
            let denom = 1.0 / gamma;
            w.par_chunks_mut(CHUNK)
                .zip(v.par_chunks(CHUNK))
                .zip(w1.par_chunks(CHUNK).zip(w2.par_chunks(CHUNK)))
                .zip(z.par_chunks_mut(CHUNK))
                .for_each(|(((w, v), (w1, w2)), z)| {
                    for ((((w, v), w1), w2), z) in w.iter_mut().zip(v).zip(w1).zip(w2).zip(z.iter_mut()) {
                        *w = (v - oldeps * w1 - delta * w2) * denom;
                        *z += phi * *w;
                    }
                });
            if !phibar.is_finite() {
                return Err(PcgError::NonFinite { what: "the MINRES residual estimate".into() });
            }
            let Some(res) = residual.as_deref_mut() else {
                if phibar <= tol * beta1 || beta == 0.0 {
                    return Ok(MinresReport { iterations: it, relative_residual: phibar / norm_b, converged: true });
                }
                continue;
            };
            if phibar <= target * beta1 || beta == 0.0 {
                rel = res.relative(z);
                if rel <= tol || beta == 0.0 {
                    return Ok(MinresReport { iterations: it, relative_residual: rel, converged: rel <= tol });
                }
                tightenings += 1;
                if tightenings > MAX_TIGHTENINGS {
                    break;
                }
                // the estimate's target lowered by how far the caller's residual is off
                target *= (0.5 * tol / rel).min(0.5);
            }
        }
        rel = match residual {
            Some(res) => res.relative(z),
            None => phibar / norm_b,
        };
        Ok(MinresReport { iterations: it, relative_residual: rel, converged: rel <= tol })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::pcg::Identity;

    /// A symmetric indefinite saddle matrix [A Bᵀ; B −C] with A the 1D Laplacian, dense.
    struct Dense {
        n: usize,
        a: Vec<f64>,
    }

    impl SymmetricOperator for Dense {
        fn apply(&self, x: &[f64], y: &mut [f64]) {
            for (y, row) in y.iter_mut().zip(self.a.chunks_exact(self.n)) {
                *y = row.iter().zip(x).map(|(a, x)| a * x).sum();
            }
        }
    }

    struct Plain<'a> {
        op: &'a Dense,
        b: &'a [f64],
    }

    impl Residual for Plain<'_> {
        fn relative(&mut self, z: &[f64]) -> f64 {
            let mut r = vec![0.0; z.len()];
            self.op.apply(z, &mut r);
            (r.iter().zip(self.b).map(|(r, b)| (b - r) * (b - r)).sum::<f64>() / dot(self.b, self.b)).sqrt()
        }
    }

    fn saddle(nu: usize, np: usize) -> Dense {
        let n = nu + np;
        let mut a = vec![0.0; n * n];
        for i in 0..nu {
            a[i * n + i] = 2.0;
            if i + 1 < nu {
                a[i * n + i + 1] = -1.0;
                a[(i + 1) * n + i] = -1.0;
            }
        }
        for p in 0..np {
            // B: differences of neighbouring unknowns; C = 0.1 I
            let (i, j) = (2 * p, 2 * p + 1);
            for (k, v) in [(i, 1.0), (j, -1.0)] {
                a[(nu + p) * n + k] = v;
                a[k * n + nu + p] = v;
            }
            a[(nu + p) * n + nu + p] = -0.1;
        }
        Dense { n, a }
    }

    #[test]
    fn minres_solves_a_saddle_system_to_the_callers_residual() {
        // exact arithmetic: at most n iterations; the answer against a product with 𝒜
        let op = saddle(30, 10);
        let x_true: Vec<f64> = (0..op.n).map(|i| (0.3 * i as f64).cos()).collect();
        let mut b = vec![0.0; op.n];
        op.apply(&x_true, &mut b);
        let mut z = vec![0.0; op.n];
        let mut minres = Minres::new(op.n);
        let rep = minres.solve(&op, &Identity, &b, &mut z, Some(&mut Plain { op: &op, b: &b }), 1e-10, 200).unwrap();
        assert!(rep.converged && rep.relative_residual <= 1e-10, "{rep:?}");
        assert!(z.iter().zip(&x_true).all(|(a, b)| (a - b).abs() < 1e-7));
        // from the answer: no iteration
        let rep = minres.solve(&op, &Identity, &b, &mut z, Some(&mut Plain { op: &op, b: &b }), 1e-6, 200).unwrap();
        assert_eq!(rep.iterations, 0);
        // a budget too small is reported, not an error
        z.iter_mut().for_each(|v| *v = 0.0);
        let rep = minres.solve(&op, &Identity, &b, &mut z, Some(&mut Plain { op: &op, b: &b }), 1e-12, 3).unwrap();
        assert!(!rep.converged && rep.iterations == 3, "{rep:?}");
        // on its own estimate from z₀ = 0: ‖b − 𝒜z‖ ≤ 1e-10 ‖b‖ in the 𝓜⁻¹ = I norm, checked afterwards
        z.iter_mut().for_each(|v| *v = 0.0);
        let rep = minres.solve(&op, &Identity, &b, &mut z, None, 1e-10, 200).unwrap();
        let true_rel = Plain { op: &op, b: &b }.relative(&z);
        assert!(rep.converged && true_rel <= 1.01e-10, "{rep:?}, {true_rel:e}");
    }
}
