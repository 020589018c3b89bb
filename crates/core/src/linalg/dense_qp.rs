//! A small dense convex quadratic programme with non-negative variables and a few equality
//! constraints, `min ½ xᵀ S x + qᵀ x` subject to `x ≥ 0`, `E x = e`, solved exactly by a finite
//! primal active-set method, warm-started from the previous call and reusing the Cholesky
//! factor of the free block while the active set does not change.
//!
//! Solvers use it for projections onto polyhedral sets by duality: the variables are the
//! multipliers of the constraint rows and S their Delassus matrix (theory §4.1).

use nalgebra::{DMatrix, DVector, linalg::Cholesky};
use thiserror::Error;

/// Failure of the dense QP.
#[derive(Debug, Clone, Error, PartialEq)]
pub enum QpError {
    /// The equality constraints E x = e have no solution with x ≥ 0 from the start we know.
    #[error("no feasible starting point for the equality constraints of the K_h projection (E x = e, x >= 0)")]
    Infeasible,
    /// A block of S that should be positive definite is not (dependent rows in K_h).
    #[error("the Delassus matrix of K_h is singular on the active rows (linearly dependent constraint rows)")]
    Singular,
    /// The active-set iteration did not terminate within its budget (cycling).
    #[error("the active-set iteration did not terminate in {0} steps")]
    NoTermination(usize),
}

/// min ½ xᵀ S x + qᵀ x subject to x ≥ 0 and E x = e, for a dense SPD S and few equalities.
#[derive(Clone, Debug)]
pub struct DenseQp {
    s: DMatrix<f64>,
    e_mat: DMatrix<f64>,
    e_rhs: DVector<f64>,
    x: DVector<f64>,
    free: Vec<bool>,
    cached: Option<FreeBlock>,
    /// Active-set steps of the last solve.
    pub last_steps: usize,
    /// Cholesky factorisations of free blocks so far (not counting O(n²) updates by one
    /// variable).
    pub factorisations: usize,
}

/// The factorised free block of the last solve: reused while the free set is unchanged.
#[derive(Clone, Debug)]
struct FreeBlock {
    free: Vec<bool>,
    /// Cholesky factor of S_FF.
    chol: Cholesky<f64, nalgebra::Dyn>,
    /// E_F.
    ef: DMatrix<f64>,
    /// Cholesky factor of the Schur complement E_F S_FF⁻¹ E_Fᵀ.
    schur: Cholesky<f64, nalgebra::Dyn>,
}

/// The solution of a [`DenseQp`].
#[derive(Clone, Debug)]
pub struct QpSolution<'a> {
    /// x ≥ 0.
    pub x: &'a DVector<f64>,
    /// Multipliers y of the equalities: S x + q + Eᵀ y ≥ 0, = 0 where x > 0.
    pub y: DVector<f64>,
}

impl DenseQp {
    /// The programme with Hessian `s` and equalities `e_mat x = e_rhs` (`e_mat` may have 0 rows).
    pub fn new(s: DMatrix<f64>, e_mat: DMatrix<f64>, e_rhs: DVector<f64>) -> Result<Self, QpError> {
        let n = s.nrows();
        assert_eq!(e_mat.ncols(), n);
        // a feasible start: the least-norm point of E x = e when it is ≥ 0 (the punch: uniform
        // μ), else a point of E x = e, x ≥ 0 by non-negative least squares (the tilting punch
        // loaded off-centre: the least-norm μ is affine in x_i and negative on the far side)
        let x = if e_mat.nrows() == 0 {
            DVector::zeros(n)
        } else {
            let eet = &e_mat * e_mat.transpose();
            let y = eet.cholesky().ok_or(QpError::Infeasible)?.solve(&e_rhs);
            let x = e_mat.transpose() * y;
            if x.iter().any(|v| *v < -1e-14 * x.amax().max(1e-300)) {
                let x = nnls(&e_mat, &e_rhs);
                let residual = (&e_mat * &x - &e_rhs).amax();
                if residual > FEASIBILITY_TOL * (e_rhs.amax() + e_mat.amax() * x.amax()) {
                    return Err(QpError::Infeasible);
                }
                x
            } else {
                x
            }
        };
        let x = x.map(|v| v.max(0.0));
        let free = x.iter().map(|v| *v > 0.0).collect();
        Ok(Self { s, e_mat, e_rhs, x, free, cached: None, last_steps: 0, factorisations: 0 })
    }

    /// Number of variables.
    pub fn n(&self) -> usize {
        self.s.nrows()
    }

    /// The Hessian S.
    pub fn hessian(&self) -> &DMatrix<f64> {
        &self.s
    }

    /// Solves for linear term `q`, warm-started from the previous solution.
    pub fn solve(&mut self, q: &DVector<f64>) -> Result<QpSolution<'_>, QpError> {
        let n = self.n();
        let m = self.e_mat.nrows();
        let budget = 10 * n + 50;
        let scale = q.amax() + self.s.amax() * self.x.amax();
        let tol = 1e-13 * scale.max(f64::MIN_POSITIVE);
        for step in 0..budget {
            let (xf, y) = self.solve_free(q)?;
            let idx: Vec<usize> = (0..n).filter(|&i| self.free[i]).collect();
            let blocking = idx.iter().zip(xf.iter()).any(|(_, v)| *v < 0.0);
            if !blocking {
                for (k, &i) in idx.iter().enumerate() {
                    self.x[i] = xf[k];
                }
                for i in 0..n {
                    if !self.free[i] {
                        self.x[i] = 0.0;
                    }
                }
                // optimality on the bound set: w = S x + q + Eᵀ y ≥ 0
                let w = &self.s * &self.x + q + self.e_mat.transpose() * &y;
                let worst = (0..n).filter(|&i| !self.free[i]).min_by(|&a, &b| w[a].total_cmp(&w[b]));
                match worst {
                    Some(i) if w[i] < -tol => self.free[i] = true,
                    _ => {
                        self.last_steps = step + 1;
                        return Ok(QpSolution { x: &self.x, y });
                    }
                }
            } else {
                // step toward the free solution until the first variable hits zero; it leaves
                let mut alpha = 1.0f64;
                let mut block = 0;
                for (k, &i) in idx.iter().enumerate() {
                    if xf[k] < 0.0 {
                        let r = self.x[i] / (self.x[i] - xf[k]);
                        if r < alpha {
                            alpha = r;
                            block = i;
                        }
                    }
                }
                for (k, &i) in idx.iter().enumerate() {
                    self.x[i] = (self.x[i] + alpha * (xf[k] - self.x[i])).max(0.0);
                }
                self.x[block] = 0.0;
                for i in idx {
                    if self.x[i] == 0.0 {
                        self.free[i] = false;
                    }
                }
            }
            if m > 0 && !self.free.iter().any(|f| *f) {
                return Err(QpError::Infeasible);
            }
        }
        Err(QpError::NoTermination(budget))
    }

    /// The Cholesky factor of S_FF for the free set `free` (indices `idx`) from the cached
    /// block, when they differ by one variable: nalgebra's column removal or insertion, O(n²).
    /// `None` (factorise afresh) otherwise, or when the update loses positive definiteness.
    fn updated(
        block: FreeBlock,
        free: &[bool],
        idx: &[usize],
        s: &DMatrix<f64>,
    ) -> Option<Cholesky<f64, nalgebra::Dyn>> {
        let mut changed = (0..free.len()).filter(|&i| free[i] != block.free[i]);
        let (i, None) = (changed.next()?, changed.next()) else { return None };
        let chol = if block.free[i] {
            let k = block.free[..i].iter().filter(|f| **f).count();
            block.chol.remove_column(k)
        } else {
            let k = free[..i].iter().filter(|f| **f).count();
            let col = DVector::from_iterator(idx.len(), idx.iter().map(|&r| s[(r, i)]));
            block.chol.insert_column(k, col)
        };
        chol.l_dirty().diagonal().iter().all(|d| d.is_finite() && *d > 0.0).then_some(chol)
    }

    /// Minimiser on the free set with the bound variables at 0: x_F and the equality
    /// multipliers y, from the (cached) Cholesky factor of S_FF and the small Schur system.
    fn solve_free(&mut self, q: &DVector<f64>) -> Result<(DVector<f64>, DVector<f64>), QpError> {
        let idx: Vec<usize> = (0..self.n()).filter(|&i| self.free[i]).collect();
        let m = self.e_mat.nrows();
        let fresh = !matches!(&self.cached, Some(b) if b.free == self.free);
        if fresh {
            // one variable more or less than the cached block: an O(n²) update of its factor
            // (the active-set steps move one variable at a time); else a new factorisation
            let updated = self.cached.take().and_then(|b| Self::updated(b, &self.free, &idx, &self.s));
            let chol = match updated {
                Some(chol) => chol,
                None => {
                    self.factorisations += 1;
                    self.s.select_rows(&idx).select_columns(&idx).cholesky().ok_or(QpError::Singular)?
                }
            };
            let ef = self.e_mat.select_columns(&idx);
            // Schur complement E_F S_FF⁻¹ E_Fᵀ of the equality block
            let z = chol.solve(&ef.transpose());
            let schur =
                (&ef * z).cholesky().or_else(|| if m == 0 { DMatrix::<f64>::zeros(0, 0).cholesky() } else { None });
            let schur = schur.ok_or(QpError::Infeasible)?;
            self.cached = Some(FreeBlock { free: self.free.clone(), chol, ef, schur });
        }
        let FreeBlock { chol, ef, schur, .. } = self.cached.as_ref().unwrap();
        let qf = DVector::from_iterator(idx.len(), idx.iter().map(|&i| q[i]));
        let sq = chol.solve(&qf);
        let y = if m == 0 { DVector::zeros(0) } else { schur.solve(&(-(ef * &sq) - &self.e_rhs)) };
        let xf = -(sq + chol.solve(&(ef.transpose() * &y)));
        Ok((xf, y))
    }
}

/// Relative residual of E x = e below which the non-negative least-squares start counts as
/// feasible: a few hundred ulps of the equations' size (they are sums over the rows).
const FEASIBILITY_TOL: f64 = 1e-12;

/// A point of `min ‖A x − b‖ subject to x ≥ 0` by the active-set method of Lawson and Hanson
/// (Solving Least Squares Problems, 1974, ch. 23): variables enter by the largest gradient
/// component and leave when the unconstrained least-squares step would make them negative.
/// For the few rows of the equalities here the passive set stays small (at most a vertex).
fn nnls(a: &DMatrix<f64>, b: &DVector<f64>) -> DVector<f64> {
    let n = a.ncols();
    let mut x = DVector::<f64>::zeros(n);
    let mut passive = vec![false; n];
    let tol = 1e-14 * a.amax() * b.amax().max(f64::MIN_POSITIVE) * (n as f64);
    let lstsq = |passive: &[bool]| -> Option<DVector<f64>> {
        let idx: Vec<usize> = (0..n).filter(|&j| passive[j]).collect();
        let ap = DMatrix::from_fn(a.nrows(), idx.len(), |r, k| a[(r, idx[k])]);
        let z = ap.svd(true, true).solve(b, 1e-14).ok()?;
        let mut full = DVector::zeros(n);
        for (k, &j) in idx.iter().enumerate() {
            full[j] = z[k];
        }
        Some(full)
    };
    for _ in 0..3 * n + 10 {
        let w = a.transpose() * (b - a * &x);
        let Some(j) = (0..n).filter(|&j| !passive[j] && w[j] > tol).max_by(|&p, &q| w[p].total_cmp(&w[q])) else {
            break;
        };
        passive[j] = true;
        for _ in 0..n {
            let Some(z) = lstsq(&passive) else { return x };
            let negative: Vec<usize> = (0..n).filter(|&k| passive[k] && z[k] <= 0.0).collect();
            if negative.is_empty() {
                x = z;
                break;
            }
            let alpha = negative.iter().map(|&k| x[k] / (x[k] - z[k])).fold(f64::INFINITY, f64::min);
            x += (z - &x) * alpha;
            for k in 0..n {
                if passive[k] && x[k] <= 1e-15 * x.amax() {
                    passive[k] = false;
                    x[k] = 0.0;
                }
            }
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng, rngs::StdRng};

    fn random_spd(n: usize, rng: &mut StdRng) -> DMatrix<f64> {
        let a = DMatrix::from_fn(n, n, |_, _| rng.random_range(-1.0..1.0));
        &a * a.transpose() + DMatrix::identity(n, n) * 0.1
    }

    /// KKT of the QP checked directly: x ≥ 0, E x = e, w = Sx + q + Eᵀy ≥ 0, x·w = 0.
    fn assert_kkt(
        s: &DMatrix<f64>,
        e: &DMatrix<f64>,
        rhs: &DVector<f64>,
        q: &DVector<f64>,
        x: &DVector<f64>,
        y: &DVector<f64>,
    ) {
        let w = s * x + q + e.transpose() * y;
        let sc = q.amax().max(1.0);
        assert!(x.iter().all(|v| *v >= 0.0));
        assert!((e * x - rhs).amax() < 1e-10 * sc);
        assert!(w.iter().all(|v| *v > -1e-10 * sc), "{w}");
        assert!(x.iter().zip(w.iter()).all(|(a, b)| (a * b).abs() < 1e-10 * sc * sc));
    }

    #[test]
    fn bound_constrained_qp_meets_kkt_and_warm_starts() {
        let mut rng = StdRng::seed_from_u64(11);
        for n in [1, 5, 30] {
            let s = random_spd(n, &mut rng);
            let mut qp = DenseQp::new(s.clone(), DMatrix::zeros(0, n), DVector::zeros(0)).unwrap();
            for _ in 0..5 {
                let q = DVector::from_fn(n, |_, _| rng.random_range(-1.0..1.0));
                let sol = qp.solve(&q).unwrap();
                let (x, y) = (sol.x.clone(), sol.y.clone());
                assert_kkt(&s, &DMatrix::zeros(0, n), &DVector::zeros(0), &q, &x, &y);
            }
        }
    }

    #[test]
    fn equality_constrained_qp_meets_kkt() {
        let mut rng = StdRng::seed_from_u64(5);
        let n = 25;
        let s = random_spd(n, &mut rng);
        let e = DMatrix::from_element(1, n, -1.0);
        let rhs = DVector::from_element(1, -0.7);
        let mut qp = DenseQp::new(s.clone(), e.clone(), rhs.clone()).unwrap();
        for _ in 0..5 {
            let q = DVector::from_fn(n, |_, _| rng.random_range(-1.0..1.0));
            let sol = qp.solve(&q).unwrap();
            let (x, y) = (sol.x.clone(), sol.y.clone());
            assert_kkt(&s, &e, &rhs, &q, &x, &y);
            assert!((x.sum() - 0.7).abs() < 1e-12);
        }
        // an unchanged active set reuses the factor
        let q = DVector::from_fn(n, |i, _| i as f64 * 1e-3);
        qp.solve(&q).unwrap();
        let f = qp.factorisations;
        qp.solve(&(q * 1.0000001)).unwrap();
        assert_eq!(qp.factorisations, f);
    }

    #[test]
    fn a_feasible_start_is_found_when_the_least_norm_point_is_negative() {
        // Σx = 1 and x₂ + 2x₃ = 1.9: the least-norm point has x₁ < 0, feasible points exist
        let e = DMatrix::from_row_slice(2, 3, &[1.0, 1.0, 1.0, 0.0, 1.0, 2.0]);
        let rhs = DVector::from_column_slice(&[1.0, 1.9]);
        let least_norm = e.transpose() * (&e * e.transpose()).cholesky().unwrap().solve(&rhs);
        assert!(least_norm[0] < 0.0, "{least_norm}");
        let s = DMatrix::identity(3, 3);
        let mut qp = DenseQp::new(s.clone(), e.clone(), rhs.clone()).unwrap();
        let q = DVector::from_column_slice(&[0.3, -0.2, 0.1]);
        let sol = qp.solve(&q).unwrap();
        let (x, y) = (sol.x.clone(), sol.y.clone());
        // KKT of the QP, checked here: feasible, w = Sx + q + Eᵀy ≥ 0, w_i x_i = 0
        assert!((&e * &x - &rhs).amax() < 1e-13 && x.iter().all(|v| *v >= 0.0), "{x}");
        let w = &s * &x + &q + e.transpose() * &y;
        for i in 0..3 {
            assert!(w[i] >= -1e-13 && (w[i] * x[i]).abs() < 1e-13, "i = {i}: w = {w}, x = {x}");
        }
        // no point at all: x₂ + 2x₃ = 2.5 > 2 max(x) with Σx = 1
        let rhs = DVector::from_column_slice(&[1.0, 2.5]);
        assert_eq!(DenseQp::new(s, e, rhs).unwrap_err(), QpError::Infeasible);
    }
}
