//! A small dense convex quadratic programme with non-negative variables and a few equality
//! constraints, `min ½ xᵀ S x + qᵀ x` subject to `x ≥ 0`, `E x = e`, solved exactly by a finite
//! primal active-set method, warm-started from the previous call and reusing the Cholesky
//! factor of the free block while the active set does not change. Degenerate vertices (fewer
//! free variables than equalities, or free columns of E that span less than its rows) are
//! handled by keeping the working set linearly independent, completed by column-pivoted
//! Gram–Schmidt, and by Bland's least-index rule after a step of length zero (theory §4.1).
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
    /// The equality rows restricted to the free variables stay rank-deficient (numerically
    /// dependent columns of E even after completing the working set, theory §4.1).
    #[error(
        "the equality constraints of the K_h projection (E x = e) are numerically dependent on every set of free \
         multipliers"
    )]
    DependentEqualities,
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

    /// Solves for linear term `q`, warm-started from the previous solution: the primal
    /// active-set method with a linearly independent working set (Nocedal & Wright, Numerical
    /// Optimization, 2nd ed. 2006, §16.5, Algorithm 16.3; Fletcher, Practical Methods of
    /// Optimization, 2nd ed. 1987, §10.3). The working set is the equalities and the bounds of
    /// the bound variables; a degenerate vertex (more zero variables than its dimension needs,
    /// E_F of rank below m) is first completed to an independent set by freeing zero variables
    /// ([`Self::span_equalities`]); a blocked step binds one variable, which keeps it
    /// independent. After the first step of length zero both choices follow the least-index
    /// rule (Bland 1977), against cycling among degenerate working sets.
    pub fn solve(&mut self, q: &DVector<f64>) -> Result<QpSolution<'_>, QpError> {
        let n = self.n();
        let budget = 10 * n + 50;
        let scale = q.amax() + self.s.amax() * self.x.amax();
        let tol = 1e-13 * scale.max(f64::MIN_POSITIVE);
        let mut least_index = false;
        for step in 0..budget {
            let (xf, y, terms) = self.solve_free(q)?;
            let idx: Vec<usize> = (0..n).filter(|&i| self.free[i]).collect();
            match Self::blocking(&self.x, &idx, &xf, -ROUND_OFF * terms) {
                None => {
                    self.take_free_minimiser(&idx, &xf);
                    match self.released(q, &y, tol, least_index) {
                        Some(i) => self.free[i] = true,
                        None => {
                            self.last_steps = step + 1;
                            return Ok(QpSolution { x: &self.x, y });
                        }
                    }
                }
                Some((alpha, block)) => {
                    // step toward the free minimiser until `block` reaches 0; it alone is bound
                    for (k, &i) in idx.iter().enumerate() {
                        self.x[i] = (self.x[i] + alpha * (xf[k] - self.x[i])).max(0.0);
                    }
                    self.x[block] = 0.0;
                    self.free[block] = false;
                    least_index |= alpha == 0.0;
                }
            }
        }
        Err(QpError::NoTermination(budget))
    }

    /// The ratio test: the step length α < 1 toward the free minimiser `xf` (on the free
    /// indices `idx`) at which the first variable reaches 0, and that variable (the least index
    /// among ties); `None` when `xf` is feasible. A component above `floor` (round-off below
    /// 0) counts as 0, not as a block.
    fn blocking(x: &DVector<f64>, idx: &[usize], xf: &DVector<f64>, floor: f64) -> Option<(f64, usize)> {
        let mut best: Option<(f64, usize)> = None;
        for (k, &i) in idx.iter().enumerate() {
            if xf[k] < floor {
                let r = x[i] / (x[i] - xf[k]);
                if best.is_none_or(|(a, _)| r < a) {
                    best = Some((r, i));
                }
            }
        }
        best
    }

    /// x := the free minimiser `xf` on `idx` (round-off below 0 cut to 0), 0 on the bound set.
    fn take_free_minimiser(&mut self, idx: &[usize], xf: &DVector<f64>) {
        self.x.fill(0.0);
        for (k, &i) in idx.iter().enumerate() {
            self.x[i] = xf[k].max(0.0);
        }
    }

    /// The bound variable to release at a minimiser of the working set: one whose multiplier
    /// w = S x + q + Eᵀ y is below −`tol` — the most negative (Dantzig), or the least index
    /// (Bland) once a degenerate step was taken; `None` at the optimum.
    fn released(&self, q: &DVector<f64>, y: &DVector<f64>, tol: f64, least_index: bool) -> Option<usize> {
        let w = &self.s * &self.x + q + self.e_mat.transpose() * y;
        let mut candidates = (0..self.n()).filter(|&i| !self.free[i] && w[i] < -tol);
        if least_index { candidates.next() } else { candidates.min_by(|&a, &b| w[a].total_cmp(&w[b])) }
    }

    /// Completes the working set to a linearly independent one (theory §4.1, the dense QP): when
    /// the columns E_F of the free variables span less than the m dimensions of the equalities
    /// (a degenerate vertex: the tilting punch held along a line of nodes), zero variables are
    /// freed, each the bound column farthest from the span so far — Gram–Schmidt with column
    /// pivoting (Businger & Golub 1965) on E with rows scaled to unit maximum, run first over
    /// the free columns (the rank of E_F), then over the bound ones. x does not move: a freed
    /// variable is 0. Then E_F has rank m and the Schur complement E_F S_FF⁻¹ E_Fᵀ is definite.
    fn span_equalities(&mut self) -> Result<(), QpError> {
        let (m, n) = self.e_mat.shape();
        if m == 0 {
            return Ok(());
        }
        let scaled = scaled_rows(&self.e_mat);
        let reference = (0..n).map(|j| scaled.column(j).norm()).fold(0.0, f64::max);
        let mut basis: Vec<DVector<f64>> = Vec::with_capacity(m);
        for from_free in [true, false] {
            loop {
                if basis.len() == m {
                    return Ok(());
                }
                let candidates = (0..n).filter(|&j| self.free[j] == from_free);
                let farthest = candidates
                    .map(|j| (j, residual(&basis, scaled.column(j).into_owned())))
                    .filter(|(_, r)| r.norm() > RANK_TOL * reference)
                    .max_by(|a, b| a.1.norm().total_cmp(&b.1.norm()));
                let Some((j, r)) = farthest else { break };
                basis.push(r.normalize());
                if !from_free {
                    self.free[j] = true;
                }
            }
        }
        Err(QpError::DependentEqualities)
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
    /// multipliers y, from the (cached) Cholesky factor of S_FF and the small Schur system; and
    /// the size of the two terms whose difference x_F is, by which its round-off scales.
    fn solve_free(&mut self, q: &DVector<f64>) -> Result<(DVector<f64>, DVector<f64>, f64), QpError> {
        let m = self.e_mat.nrows();
        let fresh = !matches!(&self.cached, Some(b) if b.free == self.free);
        if fresh {
            self.span_equalities()?;
        }
        let idx: Vec<usize> = (0..self.n()).filter(|&i| self.free[i]).collect();
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
            let schur = schur.ok_or(QpError::DependentEqualities)?;
            self.cached = Some(FreeBlock { free: self.free.clone(), chol, ef, schur });
        }
        let FreeBlock { chol, ef, schur, .. } = self.cached.as_ref().unwrap();
        let qf = DVector::from_iterator(idx.len(), idx.iter().map(|&i| q[i]));
        let sq = chol.solve(&qf);
        let y = if m == 0 { DVector::zeros(0) } else { schur.solve(&(-(ef * &sq) - &self.e_rhs)) };
        let sy = chol.solve(&(ef.transpose() * &y));
        let terms = sq.amax() + sy.amax();
        let xf = -(sq + sy);
        Ok((xf, y, terms))
    }
}

/// A column of the row-scaled E whose distance from the span of the others is below this
/// fraction of the longest column counts as dependent on them ([`DenseQp::span_equalities`]):
/// the Schur complement squares E_F's condition, so columns closer than 1e-8 would leave it
/// with a condition near 1e16, where its Cholesky factor carries no digit.
const RANK_TOL: f64 = 1e-8;

/// A component of the free minimiser x_F = −S_FF⁻¹(q_F + E_Fᵀ y) less than this fraction of its
/// two terms below 0 is their cancellation's round-off, not a blocking variable. Measured on the
/// tilting punch held along a line of nodes (tests/robust_newton.rs): a vertex variable freed
/// to complete the working set, exactly 0, came out −1.1e-16 from terms of 0.90 (half an ulp);
/// 1e-14 allows ~45 ulps for the conditioning of the small systems.
const ROUND_OFF: f64 = 1e-14;

/// E with every row scaled to unit maximum modulus: the ranks of its column sets then do not
/// depend on the units of the equalities (a force and moments about an axis).
fn scaled_rows(e: &DMatrix<f64>) -> DMatrix<f64> {
    let mut scaled = e.clone();
    for mut row in scaled.row_iter_mut() {
        let amax = row.amax();
        if amax > 0.0 {
            row /= amax;
        }
    }
    scaled
}

/// The component of `v` orthogonal to the orthonormal `basis` (Gram–Schmidt twice, which is
/// enough for orthogonality to working precision: Giraud et al. 2005).
fn residual(basis: &[DVector<f64>], mut v: DVector<f64>) -> DVector<f64> {
    for _ in 0..2 {
        for b in basis {
            v -= b * b.dot(&v);
        }
    }
    v
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

    /// A degenerate programme, the tilting punch's in miniature: multipliers at the points
    /// (0,0), (1,0), (0,1), (1,1), (½,0) carry a unit force at (½, 0), E x = e being the force
    /// and its moments (3 equalities). The moment about the x₁ axis forces x₃ = x₄ = 0, so every
    /// feasible point has at most 3 positive multipliers on a line, whose columns of E span only
    /// 2 dimensions: x = (t, t, 0, 0, 1 − 2t) with t ∈ [0, ½], and for S = I the minimiser of
    /// ½|x|² + qᵀx is t = clamp((2 − q₁ − q₂ + 2q₅)/6, 0, ½) (closed form: the objective on the
    /// line is 3t² − t(2 − q₁ − q₂ + 2q₅) + const). For q₅ large it is the vertex t = ½, two
    /// positive multipliers for three equalities. Before the working set was completed to an
    /// independent one, the first solve failed ("no feasible starting point": a singular Schur
    /// complement of E_F).
    #[test]
    fn a_degenerate_vertex_with_fewer_free_columns_than_equalities_is_solved_exactly() {
        let points = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.0)];
        let e = DMatrix::from_fn(3, 5, |r, j| [1.0, points[j].0, points[j].1][r]);
        let rhs = DVector::from_column_slice(&[1.0, 0.5, 0.0]);
        let s = DMatrix::identity(5, 5);
        let mut qp = DenseQp::new(s.clone(), e.clone(), rhs.clone()).unwrap();
        // q₃, q₄ < 0 pull toward the off-line points, which the moment forbids; warm starts go
        // from the interior of the edge to its degenerate vertex and back
        for q5 in [0.2, 2.0, 0.2, -3.0, 0.2] {
            let q = DVector::from_column_slice(&[0.3, -0.1, -1.0, -2.0, q5]);
            let sol = qp.solve(&q).unwrap();
            let (x, y) = (sol.x.clone(), sol.y.clone());
            let t = ((2.0 - 0.3 + 0.1 + 2.0 * q5) / 6.0).clamp(0.0, 0.5);
            let exact = DVector::from_column_slice(&[t, t, 0.0, 0.0, 1.0 - 2.0 * t]);
            assert!((&x - &exact).amax() < 1e-14, "q₅ = {q5}: x = {x}, expected {exact}");
            assert_kkt(&s, &e, &rhs, &q, &x, &y);
        }
    }

    /// Random programmes of the same kind, with several points on the line of the load among
    /// random ones, warm-started through many linear terms: KKT holds at every solve.
    #[test]
    fn degenerate_programmes_with_collinear_multipliers_meet_kkt() {
        let mut rng = StdRng::seed_from_u64(3);
        for n in [6, 12, 40] {
            let points: Vec<(f64, f64)> = (0..n)
                .map(|j| if j % 3 == 0 { (rng.random_range(0.0..1.0), 0.0) } else { (rng.random(), rng.random()) })
                .collect();
            let e = DMatrix::from_fn(3, n, |r, j| [1.0, points[j].0, points[j].1][r]);
            // the load inside the hull of the collinear points: every feasible x sits on the line
            let (lo, hi) =
                points.iter().filter(|p| p.1 == 0.0).fold((1.0f64, 0.0f64), |(a, b), p| (a.min(p.0), b.max(p.0)));
            let rhs = DVector::from_column_slice(&[2.0, 2.0 * (lo + hi) / 2.0, 0.0]);
            let s = random_spd(n, &mut rng);
            let mut qp = DenseQp::new(s.clone(), e.clone(), rhs.clone()).unwrap();
            for _ in 0..20 {
                let q = DVector::from_fn(n, |_, _| rng.random_range(-3.0..3.0));
                let sol = qp.solve(&q).unwrap();
                let (x, y) = (sol.x.clone(), sol.y.clone());
                assert_kkt(&s, &e, &rhs, &q, &x, &y);
            }
        }
    }
}
