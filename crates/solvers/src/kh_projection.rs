//! Step 2 of Uzawa (theory §4.1): the projection onto K_h in the metric diag(M, m), solved
//! exactly for the contact rows. Newton's exact elastic start (theory §4.2) is one such
//! projection in the energy metric; errors name the solver that asked for it.
//!
//! With Y = M⁻¹Gᵀ computed once (one multi-column solve with the factor of M) the projection of
//! a trial (z, Z) is the dense QP over the row multipliers μ ≥ 0
//!
//! `min ½ μᵀ S μ + μᵀ (G z + H₊ Z₊ + c)` with `S = G Y + H₊ m₊⁻¹ H₊ᵀ`, `H₀ᵀ μ = −ρ f₀`,
//!
//! where H₊ are the extras with a metric weight m > 0 and H₀ those with m = 0, whose V is then
//! eliminated exactly (it is the multiplier of the equality). The new point is
//! `w = z + Y μ`, `V₊ = Z₊ + m₊⁻¹ H₊ᵀ μ`, `V₀ = y`.
//!
//! With friction (theory §8.3) the tangential rows' multipliers lie in discs, not in R₊: the
//! same programme over R₊ × discs, solved by [`FrictionQp`]; the extras then need a metric
//! weight (`extra_metric > 0`), the equality of eliminated extras being outside that solver.

use crate::friction_qp::FrictionQp;
use nalgebra::{DMatrix, DVector};
use saddle_core::linalg::SparseCholesky;
use saddle_core::linalg::{DenseQp, QpError};
use saddle_core::{ConstraintRows, SolveError};

/// Above this many bytes M⁻¹Gᵀ is not kept; each projection then costs one more triangular
/// solve pair (theory §4.1). Keeping Y saves that pair, about half of an Uzawa iteration's
/// linear algebra, for n × rows doubles. 512 MiB is a memory budget, not a measured optimum:
/// Y grows like the number of dofs times the number of contact rows; the budget bounds what a
/// scene with very many contact rows adds to the memory of the factor.
pub const MAX_STORED_BYTES: usize = 512 << 20;

/// Right-hand sides per multi-column solve when Y = M⁻¹Gᵀ is set up: enough columns for the
/// blocked triangular solves to run at matrix–matrix speed, few enough that the block
/// (n × 64 doubles) stays small beside the factor.
pub const SETUP_BLOCK: usize = 64;

/// The dual programme of the projection: over μ ≥ 0 with the eliminated extras' equality
/// (frictionless rows), or over R₊ × discs (friction, theory §8.3).
#[derive(Debug)]
enum Dual {
    Polyhedral(Box<DenseQp>),
    Friction(FrictionQp),
}

/// Exact projection onto K_h in the metric diag(M, m).
#[derive(Debug)]
pub struct MetricProjection {
    n: usize,
    /// M⁻¹Gᵀ, column-major n × rows, if kept.
    y: Option<Vec<f64>>,
    qp: Dual,
    /// Metric weights of the extras (0: eliminated exactly).
    m: Vec<f64>,
    /// ρ f: the load's step on the extras.
    step_load: Vec<f64>,
    q: DVector<f64>,
    /// Scratch: the trial extras with the eliminated ones zeroed, and M⁻¹Gᵀμ when Y is not kept.
    zv: Vec<f64>,
    gtmu: Vec<f64>,
    gv: Vec<f64>,
    /// Triangular solve pairs spent in set-up.
    pub setup_solves: usize,
    /// The solver this projection serves, for error messages.
    solver: String,
}

impl MetricProjection {
    /// Set-up for rows `rows` with the factor `chol` of M, extras' weights `m_rel` relative to
    /// their natural stiffness H_kᵀ (G M⁻¹ Gᵀ)⁻¹ H_k, step `rho` and load `f`; errors name
    /// `solver`.
    pub fn new(
        rows: &ConstraintRows,
        chol: &mut SparseCholesky,
        m_rel: f64,
        rho: f64,
        f: &[f64],
        solver: &str,
    ) -> Result<Self, SolveError> {
        let n = chol.n();
        let nr = rows.n_rows();
        let ne = rows.n_extras;
        let mut s = DMatrix::zeros(nr, nr);
        let keep = n * nr * 8 <= MAX_STORED_BYTES;
        let mut y = keep.then(|| vec![0.0; n * nr]);
        // Y = M⁻¹Gᵀ in blocks of columns; S = G Y
        let block = SETUP_BLOCK;
        let mut buf = vec![0.0; n * block.min(nr.max(1))];
        let mut setup_solves = 0;
        for c0 in (0..nr).step_by(block) {
            let nc = block.min(nr - c0);
            let cols = &mut buf[..n * nc];
            cols.iter_mut().for_each(|x| *x = 0.0);
            for k in 0..nc {
                let (idx, val) = rows.row(c0 + k);
                for (&j, &v) in idx.iter().zip(val) {
                    cols[k * n + j] += v;
                }
            }
            chol.solve_columns(cols, nc);
            setup_solves += nc;
            for k in 0..nc {
                let col = &cols[k * n..(k + 1) * n];
                for i in 0..nr {
                    let (idx, val) = rows.row(i);
                    s[(i, c0 + k)] = idx.iter().zip(val).map(|(&j, v)| v * col[j]).sum();
                }
            }
            if let Some(y) = &mut y {
                y[c0 * n..(c0 + nc) * n].copy_from_slice(cols);
            }
        }
        let s = (&s + s.transpose()) * 0.5;
        let h = DMatrix::from_fn(nr, ne, |i, k| rows.extra_row(i)[k]);
        // natural stiffness of each extra: H_kᵀ S⁻¹ H_k (all rows active)
        let mut m = vec![0.0; ne];
        if m_rel > 0.0 && nr > 0 {
            let chol_s = s.clone().cholesky().ok_or_else(|| SolveError::Unsupported {
                solver: solver.into(),
                message: "the contact rows are linearly dependent (singular Delassus matrix)".into(),
            })?;
            for (k, mk) in m.iter_mut().enumerate() {
                let hk = h.column(k).into_owned();
                *mk = m_rel * hk.dot(&chol_s.solve(&hk));
            }
        }
        let plus: Vec<usize> = (0..ne).filter(|&k| m[k] > 0.0).collect();
        let zero: Vec<usize> = (0..ne).filter(|&k| m[k] == 0.0).collect();
        let mut s = s;
        for &k in &plus {
            let hk = h.column(k);
            s += hk * hk.transpose() / m[k];
        }
        let qp = if rows.has_friction() {
            if !zero.is_empty() {
                return Err(SolveError::Unsupported {
                    solver: solver.into(),
                    message: format!(
                        "friction (theory §8.3) with {} extra unknown(s) eliminated exactly (extra_metric = 0): the \
                         projection with friction needs solver.extra_metric > 0 for force-controlled obstacles",
                        zero.len()
                    ),
                });
            }
            Dual::Friction(FrictionQp::new(s, rows, rho))
        } else {
            let e_mat = DMatrix::from_fn(zero.len(), nr, |r, i| h[(i, zero[r])]);
            let e_rhs = DVector::from_fn(zero.len(), |r, _| -rho * f[zero[r]]);
            Dual::Polyhedral(Box::new(DenseQp::new(s, e_mat, e_rhs).map_err(|e| qp_error(solver, e))?))
        };
        let gtmu = if keep { vec![] } else { vec![0.0; n] };
        let step_load = f.iter().map(|fk| rho * fk).collect();
        Ok(Self {
            n,
            y,
            qp,
            m,
            step_load,
            q: DVector::zeros(nr),
            zv: vec![0.0; ne],
            gtmu,
            gv: vec![0.0; ne],
            setup_solves,
            solver: solver.to_string(),
        })
    }

    /// The metric weights m of the extra unknowns (0: eliminated).
    pub fn extra_weights(&self) -> &[f64] {
        &self.m
    }

    /// True when M⁻¹Gᵀ is kept and a projection costs no triangular solve.
    pub fn keeps_delassus_columns(&self) -> bool {
        self.y.is_some()
    }

    /// Active-set steps and factorisations of the dense QP so far.
    pub fn qp_work(&self) -> (usize, usize) {
        match &self.qp {
            Dual::Polyhedral(qp) => (qp.last_steps, qp.factorisations),
            Dual::Friction(qp) => (qp.last_sweeps, 0),
        }
    }

    /// Step (ii) from the trial z = uⁿ − ρM⁻¹Bᵀσⁿ⁺¹ and `v` = Vⁿ: on return `w` holds uⁿ⁺¹,
    /// `v` holds Vⁿ⁺¹ and `mu` the row multipliers (ρ times the contact forces). Returns the
    /// triangular solves spent (0 or 1).
    pub fn project(
        &mut self,
        rows: &ConstraintRows,
        chol: &mut SparseCholesky,
        z: &[f64],
        v: &mut [f64],
        w: &mut [f64],
        mu: &mut [f64],
    ) -> Result<usize, SolveError> {
        let nr = rows.n_rows();
        w.copy_from_slice(z);
        if nr == 0 {
            return Ok(0);
        }
        // q = G z + H₊ Z₊ + c
        // the extras' trial Z₊ = V₊ⁿ + ρ f₊ / m₊ (the eliminated ones enter through the equality)
        for (k, m) in self.m.iter().enumerate() {
            self.zv[k] = if *m == 0.0 { 0.0 } else { v[k] + self.step_load[k] / m };
        }
        rows.gap(z, &self.zv, self.q.as_mut_slice());
        let y = match &mut self.qp {
            Dual::Polyhedral(qp) => {
                let sol = qp.solve(&self.q).map_err(|e| qp_error(&self.solver, e))?;
                mu.copy_from_slice(sol.x.as_slice());
                sol.y
            }
            Dual::Friction(qp) => {
                mu.copy_from_slice(qp.solve(self.q.as_slice(), &self.solver)?);
                DVector::zeros(0)
            }
        };
        // V₊ = Z₊ + m⁻¹ H₊ᵀ μ, V₀ = y
        let mut r = 0;
        for (k, (vk, &mk)) in v.iter_mut().zip(&self.m).enumerate() {
            if mk > 0.0 {
                let htmu: f64 = (0..nr).map(|i| rows.extra_row(i)[k] * mu[i]).sum();
                *vk = self.zv[k] + htmu / mk;
            } else {
                *vk = y[r];
                r += 1;
            }
        }
        // w = z + M⁻¹Gᵀμ
        match &self.y {
            Some(ycols) => {
                for (i, &m) in mu.iter().enumerate() {
                    if m != 0.0 {
                        for (wj, yj) in w.iter_mut().zip(&ycols[i * self.n..(i + 1) * self.n]) {
                            *wj += m * yj;
                        }
                    }
                }
                Ok(0)
            }
            None => {
                self.gtmu.iter_mut().for_each(|x| *x = 0.0);
                rows.add_transpose(mu, &mut self.gtmu, &mut self.gv);
                chol.solve(&mut self.gtmu);
                for (wj, d) in w.iter_mut().zip(&self.gtmu) {
                    *wj += d;
                }
                Ok(1)
            }
        }
    }
}

/// A failure of the dense QP of the projection, attributed to `solver`.
fn qp_error(solver: &str, e: QpError) -> SolveError {
    SolveError::Unsupported { solver: solver.into(), message: format!("projection onto K_h failed: {e}") }
}
