//! The linearised problem of active-set Newton methods (theory §3–§4.2): for a set A of active
//! contact rows, solve
//!
//! ```text
//! K du − G_Aᵀ λ_A = −∇E(u)          (equilibrium, linearised)
//!      − H_Aᵀ λ_A = f               (load on the extra unknowns)
//! G_A du + H_A dV = −g_A(u, V)      (the active rows touch after the step)
//! ```
//!
//! Each contact row acts on one displacement dof s (node-to-rigid-obstacle along an axis), so an
//! active row fixes du_s in terms of dV. The fixed dofs are imposed on the *fixed* sparsity
//! pattern of L by identity rows and columns (the diagonal kept for scaling), so the symbolic
//! Cholesky analysis is done once; du depends affinely on dV, `du = du⁰ + W dV`, from one solve
//! with 1 + n_extras right-hand sides, and dV follows from an n_extras × n_extras system. The
//! contact forces are the reactions at the fixed dofs.
//!
//! The systems are solved by one of two [`LinearBackend`]s: a sparse Cholesky factorisation of
//! every tangent (symbolic analysis once), or conjugate gradients preconditioned by a
//! smoothed-aggregation multigrid of the *elastic* stiffness, built once and reused for every
//! tangent (the fixed dofs are handled by the preconditioner as a diagonal block), to a
//! relative tolerance the caller sets per step (inexact Newton).

use crate::linear::{self, InSolver, lower, near_null_space};
use nalgebra::{DMatrix, DVector};
use saddle_core::linalg::{AmgParams, Csr, Pcg, Preconditioner, SmoothedAggregation, SparseCholesky};
use saddle_core::{ConstraintRows, Lagrangian, Material, SolveError, SymmetricPattern};
use serde::{Deserialize, Serialize};
use std::sync::Mutex;

/// `linear = "direct" | "amg" | "auto"`: how a solver's linear systems are solved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LinearSolver {
    /// Sparse Cholesky (faer, supernodal): exact, memory ~ N^1.5.
    Direct,
    /// CG with smoothed-aggregation AMG of the elastic stiffness: memory ~ N, inexact.
    Amg,
    /// Direct up to a number of free dofs (Newton's `auto_amg_dofs`, default
    /// [`AUTO_AMG_DOFS`]), AMG above (the default).
    #[default]
    Auto,
}

/// The default of Newton's `auto_amg_dofs`: above this many free dofs `auto` picks AMG. It is
/// the crossover measured with `saddle bench` on the default scene family (2 cores): there the
/// direct and the AMG Newton cost the same wall time; below it the factorisation is cheaper
/// than the CG iterations, above it the factorisation's N^1.5 memory and time take over.
pub const AUTO_AMG_DOFS: usize = 20_000;

impl LinearSolver {
    /// Direct or AMG for a problem with `n` free dofs, `auto` switching to AMG above
    /// `auto_amg_dofs`.
    pub fn resolve(self, n: usize, auto_amg_dofs: usize) -> LinearSolver {
        match self {
            LinearSolver::Auto if n > auto_amg_dofs => LinearSolver::Amg,
            LinearSolver::Auto => LinearSolver::Direct,
            other => other,
        }
    }
}

/// The solver of the linearised systems.
pub enum LinearBackend {
    /// A numeric Cholesky factorisation per system on the pattern analysed once.
    Direct(Box<SparseCholesky>),
    /// PCG with the elastic multigrid hierarchy.
    Amg(Box<IterativeSolve>),
}

/// CG preconditioned by smoothed aggregation of the elastic stiffness (module docs).
pub struct IterativeSolve {
    amg: SmoothedAggregation,
    pcg: Pcg,
    /// The system matrix, on L's pattern: built once, its values re-assigned per step.
    a: Csr,
    /// Scratch of [`Csr::assign_symmetric_lower`], of the preconditioner and of one column.
    fill: Vec<usize>,
    scratch: Mutex<Vec<f64>>,
    col: Vec<f64>,
    /// CG iteration budget per solve.
    pub max_iter: usize,
    /// CG iterations so far.
    pub iterations: usize,
    /// Solves that stopped at the budget before the tolerance.
    pub unconverged: usize,
    /// The last solutions of the extras' columns (W = K⁻¹(−K δ_V)): they change little from
    /// one Newton step to the next and start the next CG solves.
    previous: Vec<f64>,
}

/// The AMG preconditioner with the active (fixed) dofs split off as a diagonal block:
/// z_F = M⁻¹ r_F (r zero on the fixed dofs), z_s = r_s / d_s on a fixed dof s.
struct FixedDofs<'a> {
    amg: &'a SmoothedAggregation,
    /// The fixed dofs s with their diagonal entries d_s.
    fixed: &'a [(usize, f64)],
    scratch: &'a Mutex<Vec<f64>>,
}

impl Preconditioner for FixedDofs<'_> {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let mut t = self.scratch.lock().unwrap_or_else(|e| e.into_inner());
        t.copy_from_slice(r);
        for &(s, _) in self.fixed {
            t[s] = 0.0;
        }
        self.amg.apply(&t, z);
        for &(s, d) in self.fixed {
            z[s] = r[s] / d;
        }
    }
}

/// The slave dof and coefficient of each contact row.
#[derive(Clone, Debug)]
pub struct SlaveRows {
    /// dof s_i of row i.
    pub dof: Vec<usize>,
    /// G_{i s_i}.
    pub coef: Vec<f64>,
}

impl SlaveRows {
    /// Checks that each row acts on exactly one dof and no two rows share one.
    pub fn new(rows: &ConstraintRows, n_dofs: usize, solver: &str) -> Result<Self, SolveError> {
        let mut taken = vec![false; n_dofs];
        let mut dof = Vec::with_capacity(rows.n_rows());
        let mut coef = Vec::with_capacity(rows.n_rows());
        for i in 0..rows.n_rows() {
            let (cols, vals) = rows.row(i);
            let nz: Vec<(usize, f64)> =
                cols.iter().zip(vals).filter(|(_, v)| **v != 0.0).map(|(c, v)| (*c, *v)).collect();
            if nz.len() != 1 || taken[nz[0].0] {
                return Err(SolveError::Unsupported {
                    solver: solver.into(),
                    message: format!(
                        "contact row {i} (node {}) acts on {} displacement dofs{}; this solver needs each row to act on one dof \
                         of its own (node-to-rigid-obstacle contact along an axis)",
                        rows.node[i],
                        nz.len(),
                        if nz.len() == 1 { " already used by another row" } else { "" }
                    ),
                });
            }
            taken[nz[0].0] = true;
            dof.push(nz[0].0);
            coef.push(nz[0].1);
        }
        Ok(Self { dof, coef })
    }
}

/// Positions of the entries of each row i in the columns j < i of a lower-triangular pattern,
/// to zero a row as well as a column.
#[derive(Clone, Debug)]
struct TransposeIndex {
    ptr: Vec<usize>,
    pos: Vec<usize>,
}

impl TransposeIndex {
    fn new(p: &SymmetricPattern) -> Self {
        let (cp, ri) = (p.col_ptr(), p.row_idx());
        let mut ptr = vec![0usize; p.n() + 1];
        for j in 0..p.n() {
            for &i in &ri[cp[j] + 1..cp[j + 1]] {
                ptr[i + 1] += 1;
            }
        }
        for i in 0..p.n() {
            ptr[i + 1] += ptr[i];
        }
        let mut fill = ptr.clone();
        let mut pos = vec![0usize; ptr[p.n()]];
        for j in 0..p.n() {
            for (k, &i) in ri.iter().enumerate().take(cp[j + 1]).skip(cp[j] + 1) {
                pos[fill[i]] = k;
                fill[i] += 1;
            }
        }
        Self { ptr, pos }
    }
}

/// The step of one active-set Newton iteration.
#[derive(Clone, Debug)]
pub struct Step {
    /// du.
    pub du: Vec<f64>,
    /// dV.
    pub dv: Vec<f64>,
    /// Contact forces after the step (zero on inactive rows).
    pub lambda: Vec<f64>,
}

/// The linearised problem for one active set, and the solver of its systems.
pub struct ActiveSetSystem {
    slaves: SlaveRows,
    /// The solver this system serves, for error messages.
    solver: String,
    transpose: TransposeIndex,
    /// How the systems are solved.
    pub backend: LinearBackend,
    work: Vec<f64>,
    /// Symbolic analyses of L's pattern so far (one for the direct backend, none for AMG).
    pub symbolic_analyses: usize,
    /// Numeric factorisations so far.
    pub factorisations: usize,
    /// Triangular solve pairs (direct) or CG solves (AMG) so far.
    pub solves: usize,
}

impl ActiveSetSystem {
    /// The direct backend: the symbolic analysis of L's pattern, once; `solver` names the
    /// solver this system serves in errors.
    pub fn new(l: &dyn Lagrangian, solver: &str) -> Result<Self, SolveError> {
        let slaves = SlaveRows::new(l.constraints(), l.n_dofs(), solver)?;
        let mut symbolic_analyses = 0;
        let chol = linear::analyse(l.pattern(), "tangent stiffness", solver, &mut symbolic_analyses)?;
        let mut system = Self::with(l, solver, slaves, LinearBackend::Direct(Box::new(chol)));
        system.symbolic_analyses = symbolic_analyses;
        Ok(system)
    }

    /// The iterative backend: the multigrid hierarchy of the elastic stiffness with the
    /// parameters `amg`, and CG with at most `cg_max_iter` iterations per solve.
    pub fn multigrid(
        l: &dyn Lagrangian,
        solver: &str,
        amg: &AmgParams,
        cg_max_iter: usize,
    ) -> Result<Self, SolveError> {
        let slaves = SlaveRows::new(l.constraints(), l.n_dofs(), solver)?;
        let near_null = near_null_space(l).ok_or_else(|| SolveError::Unsupported {
            solver: solver.into(),
            message: "linear = \"amg\" needs the nodes of the dofs (rigid-body modes); this L has none".into(),
        })?;
        let c = l.elasticity().stiffness_matrix();
        let k = Csr::from_symmetric_lower(lower(l.pattern()), &l.stiffness(Material::Uniform(&c)));
        let amg = SmoothedAggregation::new(&k, &near_null, amg).map_err(|e| SolveError::Unsupported {
            solver: solver.into(),
            message: format!("multigrid set-up: {e}"),
        })?;
        let n = l.n_dofs();
        let iterative = IterativeSolve {
            amg,
            pcg: Pcg::new(n),
            a: k,
            fill: Vec::new(),
            scratch: Mutex::new(vec![0.0; n]),
            col: vec![0.0; n],
            max_iter: cg_max_iter,
            iterations: 0,
            unconverged: 0,
            previous: Vec::new(),
        };
        Ok(Self::with(l, solver, slaves, LinearBackend::Amg(Box::new(iterative))))
    }

    /// The system for the rows' `slaves` on `backend`.
    fn with(l: &dyn Lagrangian, solver: &str, slaves: SlaveRows, backend: LinearBackend) -> Self {
        Self {
            slaves,
            solver: solver.to_string(),
            transpose: TransposeIndex::new(l.pattern()),
            backend,
            work: vec![0.0; l.pattern().nnz()],
            symbolic_analyses: 0,
            factorisations: 0,
            solves: 0,
        }
    }

    /// The Cholesky factor of the direct backend, if that is the one in use.
    pub fn direct(&mut self) -> Option<&mut SparseCholesky> {
        match &mut self.backend {
            LinearBackend::Direct(chol) => Some(chol),
            LinearBackend::Amg(_) => None,
        }
    }

    /// The iterative backend, if that is the one in use.
    pub fn iterative(&mut self) -> Option<&mut IterativeSolve> {
        match &mut self.backend {
            LinearBackend::Amg(it) => Some(it),
            LinearBackend::Direct(_) => None,
        }
    }

    /// The slave dofs of the rows.
    pub fn slaves(&self) -> &SlaveRows {
        &self.slaves
    }

    /// The step for active set `active`, tangent `k` (values on L's pattern), internal force
    /// `grad` = ∇E(u) and current gaps `gap`; the iterative backend solves to the relative
    /// residual `cg_tol` (the direct one is exact). The extras' system must be regular: every
    /// extra with a load needs an active row.
    pub fn step(
        &mut self,
        l: &dyn Lagrangian,
        k: &[f64],
        active: &[bool],
        grad: &[f64],
        gap: &[f64],
        cg_tol: f64,
    ) -> Result<Step, SolveError> {
        let p = l.pattern();
        let rows = l.constraints();
        let (n, ne, nr) = (l.n_dofs(), l.n_extras(), rows.n_rows());
        let cp = p.col_ptr();
        // K with the active slave dofs fixed: identity rows and columns, diagonal kept
        self.work.copy_from_slice(k);
        for i in (0..nr).filter(|&i| active[i]) {
            let s = self.slaves.dof[i];
            self.work[cp[s] + 1..cp[s + 1]].iter_mut().for_each(|v| *v = 0.0);
            for &q in &self.transpose.pos[self.transpose.ptr[s]..self.transpose.ptr[s + 1]] {
                self.work[q] = 0.0;
            }
        }
        if let LinearBackend::Direct(chol) = &mut self.backend {
            chol.factorise(&self.work).in_solver(&self.solver)?;
            self.factorisations += 1;
        }
        // prescribed values δ at the fixed dofs: column 0 for the gaps, column 1 + k for dV_k
        let nc = 1 + ne;
        let mut delta = vec![0.0; n * nc];
        for i in (0..nr).filter(|&i| active[i]) {
            let (s, a) = (self.slaves.dof[i], self.slaves.coef[i]);
            delta[s] = -gap[i] / a;
            for (kx, h) in rows.extra_row(i).iter().enumerate() {
                delta[(1 + kx) * n + s] = -h / a;
            }
        }
        // right-hand sides: −∇E − K δ (column 0), −K δ (others), then δ·diag at the fixed dofs
        let mut x = vec![0.0; n * nc];
        for c in 0..nc {
            let (dcol, xcol) = (&delta[c * n..(c + 1) * n], &mut x[c * n..(c + 1) * n]);
            p.matvec(k, dcol, xcol);
            for j in 0..n {
                xcol[j] = -xcol[j] - if c == 0 { grad[j] } else { 0.0 };
            }
            for i in (0..nr).filter(|&i| active[i]) {
                let s = self.slaves.dof[i];
                xcol[s] = self.work[cp[s]] * dcol[s];
            }
        }
        match &mut self.backend {
            LinearBackend::Direct(chol) => chol.solve_columns(&mut x, nc),
            LinearBackend::Amg(it) => {
                let IterativeSolve { amg, pcg, a, fill, scratch, col, previous, max_iter, iterations, unconverged } =
                    &mut **it;
                a.assign_symmetric_lower(lower(p), &self.work, fill);
                let fixed: Vec<(usize, f64)> = (0..nr)
                    .filter(|&i| active[i])
                    .map(|i| (self.slaves.dof[i], self.work[cp[self.slaves.dof[i]]]))
                    .collect();
                let pre = FixedDofs { amg, fixed: &fixed, scratch };
                previous.resize(n * (nc - 1), 0.0);
                for c in 0..nc {
                    let b = &x[c * n..(c + 1) * n];
                    // the displacement column from zero, the extras' columns from their last value
                    match c {
                        0 => col.iter_mut().for_each(|v| *v = 0.0),
                        _ => col.copy_from_slice(&previous[(c - 1) * n..c * n]),
                    }
                    let report =
                        pcg.solve(a, &pre, b, col, cg_tol, *max_iter).map_err(|e| SolveError::Unsupported {
                            solver: self.solver.clone(),
                            message: format!("CG on the tangent: {e}"),
                        })?;
                    *iterations += report.iterations;
                    *unconverged += !report.converged as usize;
                    x[c * n..(c + 1) * n].copy_from_slice(col);
                    if c > 0 {
                        previous[(c - 1) * n..c * n].copy_from_slice(col);
                    }
                }
            }
        }
        self.solves += nc;
        // reactions at the fixed dofs: λ = (∇E + K du)_s / a, affine in dV
        let mut kx = vec![0.0; n];
        let mut lam0 = vec![0.0; nr];
        let mut lam_v = DMatrix::zeros(nr, ne);
        for c in 0..nc {
            p.matvec(k, &x[c * n..(c + 1) * n], &mut kx);
            for i in (0..nr).filter(|&i| active[i]) {
                let (s, a) = (self.slaves.dof[i], self.slaves.coef[i]);
                if c == 0 {
                    lam0[i] = (grad[s] + kx[s]) / a;
                } else {
                    lam_v[(i, c - 1)] = kx[s] / a;
                }
            }
        }
        // the extras: −H_Aᵀ(λ⁰ + Λ dV) = f
        let mut dv = vec![0.0; ne];
        if ne > 0 {
            let h = DMatrix::from_fn(nr, ne, |i, kx| if active[i] { rows.extra_row(i)[kx] } else { 0.0 });
            let s = h.transpose() * &lam_v;
            let rhs = -DVector::from_column_slice(l.load()) - h.transpose() * DVector::from_column_slice(&lam0);
            let sol = s.lu().solve(&rhs).filter(|v| v.iter().all(|x| x.is_finite())).ok_or_else(|| {
                SolveError::Unsupported {
                    solver: self.solver.clone(),
                    message: "an extra unknown with a load has no active contact row (the obstacle does not touch)"
                        .into(),
                }
            })?;
            dv.copy_from_slice(sol.as_slice());
        }
        let mut du = x[..n].to_vec();
        for (kx, d) in dv.iter().enumerate() {
            for (u, w) in du.iter_mut().zip(&x[(1 + kx) * n..(2 + kx) * n]) {
                *u += d * w;
            }
        }
        let mut lambda = vec![0.0; nr];
        for i in (0..nr).filter(|&i| active[i]) {
            lambda[i] = lam0[i] + (0..ne).map(|kx| lam_v[(i, kx)] * dv[kx]).sum::<f64>();
        }
        Ok(Step { du, dv, lambda })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_on_several_or_shared_dofs_are_refused_with_the_node() {
        let mut rows = ConstraintRows::new(1);
        rows.push(&[(3, 1.0)], &[-1.0], 0.0, 10);
        rows.push(&[(4, 0.6), (5, 0.8)], &[-1.0], 0.0, 11);
        let e = SlaveRows::new(&rows, 6, "newton").expect_err("two dofs in one row");
        assert!(e.to_string().contains("row 1 (node 11) acts on 2 displacement dofs"), "{e}");
        let mut rows = ConstraintRows::new(1);
        rows.push(&[(3, 1.0)], &[-1.0], 0.0, 10);
        rows.push(&[(3, 1.0)], &[-1.0], 0.0, 12);
        let e = SlaveRows::new(&rows, 6, "newton").expect_err("shared dof");
        assert!(e.to_string().contains("already used by another row"), "{e}");
        let mut rows = ConstraintRows::new(1);
        rows.push(&[(3, 2.0)], &[-1.0], 0.0, 10);
        let s = SlaveRows::new(&rows, 6, "newton").unwrap();
        assert_eq!((s.dof[0], s.coef[0]), (3, 2.0));
    }
}
