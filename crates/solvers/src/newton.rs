//! Semismooth Newton with a primal–dual active set (SPEC §4, beyond the paper; deal.II's
//! step-42 is the classic relative).
//!
//! Newton on the primal form min J(u, V) = Σ_T |T| ψ(ε_T(u)) − f·V over K_h (SPEC §3 form 1):
//!
//! 0. from a cold start, first the *elastic* contact problem, solved exactly with one
//!    factorisation of the elastic stiffness K: the projection of K⁻¹f onto K_h in the energy
//!    metric (Uzawa's step (ii) of SPEC §4, see `elastic_contact_start`). Plasticity is then
//!    switched on. (Plastic steps from the first touching node alone push it through the body
//!    and drive everything plastic.) Should that projection be unavailable (dependent rows),
//!    the elastic problem is solved by full active-set steps with the elastic tangent from
//!    every candidate row active until the active set settles.
//! 1. the local law with its consistent tangent at every element (SPEC §2);
//! 2. the active set A = {i : λ_i − c_i g_i > 0} (c_i: the elastic stiffness at the row's dof,
//!    so that forces and gaps are compared in the units of the problem);
//! 3. the linearised problem for A ([`ActiveSetSystem`]): one numeric factorisation on the
//!    pattern analysed once, one solve with 1 + n_extras right-hand sides;
//! 4. a backtracking (Armijo) line search on J plus ν Σ_{i∈A} |g_i|, the violation of the active
//!    rows that the Newton step removes; rows that a step drives into the obstacle join A at the
//!    next iteration instead of blocking the step. Once the active rows touch, it is a line
//!    search on J alone.
//!
//! It stops on the relative KKT residual of the iterate. Once the active set and the plastic
//! set settle, convergence is quadratic. [`Newton::solve_from`] starts from another solver's
//! iterate (SOCP polishing).

use crate::active_set::{ActiveSetSystem, LinearSolver};
use crate::kh_projection::MetricProjection;
use crate::linear::InSolver;
use crate::residual;
use saddle_core::error::{ParameterError, check};
use saddle_core::linalg::SparseCholesky;
use saddle_core::problem::lagrangian::{Iterate, Lagrangian, StressField, Workspace, max_abs};
use saddle_core::problem::solver::{Monitor, PhaseTimer, Solution, SolveError, SolveReport, Solver, StopReason};
use saddle_core::{Material, SymOp};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// `type = "newton"`: semismooth Newton with a primal–dual active set.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Newton {
    /// Relative KKT tolerance.
    pub tol: f64,
    /// Iteration budget.
    pub max_iter: usize,
    /// Backtracking line search on J (off: full Newton steps).
    pub line_search: bool,
    /// How the linearised systems are solved: `direct` (Cholesky per iteration), `amg` (CG
    /// with the elastic multigrid, inexact Newton) or `auto` (direct up to 20 000 dofs, where
    /// the two cost the same; measured with `saddle bench`).
    pub linear: LinearSolver,
}

impl Default for Newton {
    fn default() -> Self {
        Self { tol: 1e-10, max_iter: 50, line_search: true, linear: LinearSolver::Auto }
    }
}

/// A starting point: displacements, extras and contact forces.
#[derive(Clone, Debug)]
pub struct Start {
    /// u.
    pub u: Vec<f64>,
    /// V.
    pub extras: Vec<f64>,
    /// λ.
    pub lambda: Vec<f64>,
}

#[typetag::serde(name = "newton")]
impl Solver for Newton {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::open_interval(path, "tol", self.tol, 0.0, 1.0)?;
        check::at_least_one(path, "max_iter", self.max_iter)?;
        Ok(())
    }

    fn tolerance(&self) -> f64 {
        self.tol
    }

    fn solve(&self, l: &dyn Lagrangian, monitor: &mut dyn Monitor) -> Result<Solution, SolveError> {
        self.solve_from(l, None, monitor, &mut PhaseTimer::default(), "newton")
    }
}

impl Newton {
    /// Newton from `start` (zero if `None`); phases are added to `timer` and the report carries
    /// the solver name `name`.
    pub fn solve_from(
        &self,
        l: &dyn Lagrangian,
        start: Option<Start>,
        monitor: &mut dyn Monitor,
        timer: &mut PhaseTimer,
        name: &str,
    ) -> Result<Solution, SolveError> {
        self.validate("solver")?;
        let rows = l.constraints();
        let (n, ne, nr) = (l.n_dofs(), l.n_extras(), rows.n_rows());
        let mut start_is_cold = start.is_none();
        let linear = self.linear.resolve(n);
        monitor.phase("analysis");
        let phase = if linear == LinearSolver::Amg { "multigrid set-up" } else { "analysis" };
        let mut system = timer.time(phase, || ActiveSetSystem::with_backend(l, name, linear))?;
        let mut elastic_start = None;
        // (with the iterative backend the Delassus columns would cost a CG solve per row: the
        // elastic contact set is then found by the active-set phase below)
        if let Some(chol) = system.direct().filter(|_| start_is_cold && nr > 0) {
            // 0. the elastic contact problem, exactly, with one factorisation of K on the
            //    tangents' symbolic analysis
            monitor.phase("elastic contact");
            match timer.time("elastic contact", || elastic_contact_start(l, chol)) {
                Ok(s) => elastic_start = Some(s),
                // dependent rows and the like: fall back on the elastic active-set phase
                Err(SolveError::Unsupported { .. }) => {}
                Err(e) => return Err(e),
            }
        }
        let elastic_solves = elastic_start.as_ref().map_or(0, |(_, solves)| *solves);
        let start = match elastic_start {
            Some((s, _)) => {
                start_is_cold = false;
                Some(s)
            }
            None => start,
        };
        let Start { mut u, extras: mut v, mut lambda } =
            start.unwrap_or(Start { u: vec![0.0; n], extras: vec![0.0; ne], lambda: vec![0.0; nr] });
        let mut ws = Workspace::new(l);
        let mut stress = StressField::new(l.n_points(), l.hardening_dim());
        let mut tangents = vec![SymOp::zeros(); l.n_points()];
        let mut k = vec![0.0; l.pattern().nnz()];
        let mut gap = vec![0.0; nr];
        let (mut u_trial, mut v_trial, mut g_trial) = (vec![0.0; n], vec![0.0; ne], vec![0.0; nr]);
        let mut active = vec![false; nr];
        let mut history = Vec::new();
        let mut nu: f64 = 0.0;
        let mut counters = BTreeMap::new();
        let (mut backtracks, mut active_changes, mut return_mappings) = (0usize, 0usize, 0usize);
        let mut elastic_steps = 0usize;
        monitor.phase("iterations");
        let mut it = 0;
        let c_elastic = l.elasticity().stiffness_matrix();
        // PDAS compares forces with gaps through each row's elastic stiffness (units force/length)
        let row_stiffness: Vec<f64> = {
            let diag = l.pattern().diagonal(&l.stiffness(Material::Uniform(&c_elastic)));
            system.slaves().dof.iter().map(|&s| diag[s]).collect()
        };
        let mut elastic_phase = start_is_cold && l.plasticity().is_some();
        let (mut elastic_grad, mut grad) = (vec![0.0; n], vec![0.0; n]);
        let mut elastic_sigma = vec![saddle_core::Sym::zeros(); if elastic_phase { l.n_points() } else { 0 }];
        let (stop, kkt) = loop {
            // 1. local law with tangents; the residual of the iterate
            timer.time("local law", || {
                l.strain(&u, &mut ws.eps);
                l.local_law(&ws.eps, &mut stress, Some(&mut tangents));
                ws.stress.clone_from(&stress);
            });
            if l.plasticity().is_some() {
                return_mappings += l.n_points();
            }
            let kkt = timer.time("residual", || {
                l.kkt_with_stress(&Iterate { u: &u, extras: &v, stress: &stress, lambda: &lambda }, &mut ws)
            });
            let r = kkt.max();
            residual::record(name, it, r, self.tol, &mut history, monitor)?;
            if r <= self.tol {
                break (StopReason::Converged, kkt);
            }
            if it >= self.max_iter {
                break (StopReason::MaxIterations, kkt);
            }
            // 2. active set, scaled by the (fixed) elastic stiffness of each row's dof
            rows.gap(&u, &v, &mut gap);
            let mut changed = 0;
            // cold start: every candidate row active (the punch imprints its shape), tensile
            // rows are released at the next iteration
            let cold = start_is_cold && it == 0;
            for i in 0..nr {
                let a = cold || lambda[i] - row_stiffness[i] * gap[i] > 0.0;
                changed += (a != active[i]) as usize;
                active[i] = a;
            }
            // an extra with a load needs a touching row: the one with the smallest gap
            for (kx, f) in l.load().iter().enumerate() {
                let touching = (0..nr).filter(|&i| rows.extra_row(i)[kx] != 0.0);
                if *f != 0.0
                    && !touching.clone().any(|i| active[i])
                    && let Some(i) = touching.min_by(|&a, &b| gap[a].total_cmp(&gap[b]))
                {
                    active[i] = true;
                    changed += 1;
                }
            }
            // the elastic phase ends once its active set has settled: the last step solved it
            if elastic_phase && it > 0 && changed == 0 {
                elastic_phase = false;
                elastic_steps = it;
            }
            // the tangent (the elastic one in the elastic phase)
            timer.time("assembly", || {
                if elastic_phase {
                    l.assemble(Material::Uniform(&c_elastic), &mut k);
                    for (s, e) in elastic_sigma.iter_mut().zip(&ws.eps) {
                        *s = c_elastic * e;
                    }
                    l.divergence(&elastic_sigma, &mut elastic_grad);
                    for (g, f) in elastic_grad.iter_mut().zip(l.nodal_load()) {
                        *g -= f;
                    }
                } else {
                    l.assemble(Material::PerPoint(&tangents), &mut k);
                }
            });
            active_changes += changed;
            // 3. the Newton step for this active set (inexact with CG: forcing term 1e-2·r)
            // (a linear problem — no plasticity, no contact — is solved in one step to the tolerance)
            let linear_problem = l.plasticity().is_none() && nr == 0;
            if let Some(iterative) = system.iterative() {
                iterative.tol = if linear_problem { 0.1 * self.tol } else { (1e-2 * r.min(1.0)).max(1e-13) }.max(1e-14);
            }
            grad.copy_from_slice(if elastic_phase { &elastic_grad } else { &ws.force });
            let phase = if linear == LinearSolver::Amg { "CG solves" } else { "factorisation and solves" };
            let step = timer.time(phase, || system.step(l, &k, &active, &grad, &gap))?;
            if step.du.iter().chain(&step.dv).chain(&step.lambda).any(|x| !x.is_finite()) {
                return Err(SolveError::NonFinite {
                    solver: name.into(),
                    what: "the Newton step".into(),
                    iteration: it,
                });
            }
            // 4. line search on J + ν Σ_A |g_i|
            nu = nu.max(2.0 * max_abs(&step.lambda));
            // ℓ₁ violation of the *active* rows only: rows that a full step drives into the
            // obstacle join the active set at the next iteration (PDAS), they do not block
            let violation = |g: &[f64]| (0..nr).filter(|&i| active[i]).map(|i| g[i].abs()).sum::<f64>();
            let alpha = if self.line_search && !elastic_phase {
                timer.time("line search", || {
                    let j0 = l.energy(&u, &v, &mut ws) + nu * violation(&gap);
                    let slope = grad.iter().zip(&step.du).map(|(a, b)| a * b).sum::<f64>()
                        - l.load().iter().zip(&step.dv).map(|(a, b)| a * b).sum::<f64>()
                        - nu * (0..nr).filter(|&i| active[i]).map(|i| gap[i].abs()).sum::<f64>();
                    let mut alpha = 1.0;
                    // below round-off of J the test is noise: take the full step
                    if slope.abs() <= 1e-13 * j0.abs().max(f64::MIN_POSITIVE) || slope >= 0.0 {
                        return alpha;
                    }
                    for _ in 0..40 {
                        axpy_into(&mut u_trial, &u, alpha, &step.du);
                        axpy_into(&mut v_trial, &v, alpha, &step.dv);
                        rows.gap(&u_trial, &v_trial, &mut g_trial);
                        let j = l.energy(&u_trial, &v_trial, &mut ws) + nu * violation(&g_trial);
                        if j <= j0 + 1e-4 * alpha * slope {
                            break;
                        }
                        alpha *= 0.5;
                        backtracks += 1;
                    }
                    alpha
                })
            } else {
                1.0
            };
            axpy(&mut u, alpha, &step.du);
            axpy(&mut v, alpha, &step.dv);
            lambda.copy_from_slice(&step.lambda);
            it += 1;
        };
        let elastic_factorisations = (elastic_solves > 0) as usize;
        counters.insert("factorisations".into(), (system.factorisations + elastic_factorisations) as f64);
        counters.insert("symbolic_analyses".into(), 1.0);
        counters.insert("triangular_solve_pairs".into(), (system.solves + elastic_solves) as f64);
        counters.insert("elastic_contact_solves".into(), elastic_solves as f64);
        if let Some(iterative) = system.iterative() {
            counters.insert("pcg_iterations".into(), iterative.iterations as f64);
            counters.insert("pcg_unconverged".into(), iterative.unconverged as f64);
        }
        counters.insert("line_search_backtracks".into(), backtracks as f64);
        counters.insert("active_set_changes".into(), active_changes as f64);
        counters.insert("return_mappings".into(), return_mappings as f64);
        counters.insert("elastic_phase_steps".into(), elastic_steps as f64);
        counters.insert("contact_rows_active".into(), active.iter().filter(|a| **a).count() as f64);
        let report = SolveReport {
            solver: name.into(),
            converged: stop == StopReason::Converged,
            stop_reason: stop,
            iterations: it,
            tolerance: self.tol,
            kkt,
            residual_history: history,
            phases: std::mem::take(timer).into_phases(),
            counters,
            warnings: Vec::new(),
        };
        Ok(Solution { u, extras: v, stress, lambda, report })
    }
}

/// The elastic contact problem solved exactly: the projection onto K_h, in the energy metric of
/// the elastic stiffness K, of the unconstrained elastic solution z = K⁻¹f (Uzawa's step (ii) of
/// SPEC §4 with ρ = 1 from u = 0, which for an elastic body is the solution). One factorisation
/// of K into `chol` (analysed on L's pattern), one solve per contact row for the Delassus matrix
/// G K⁻¹ Gᵀ (in blocks of columns) and a dense QP over the rows. Returns the start and the
/// triangular solves spent.
fn elastic_contact_start(l: &dyn Lagrangian, chol: &mut SparseCholesky) -> Result<(Start, usize), SolveError> {
    let (n, ne, nr) = (l.n_dofs(), l.n_extras(), l.constraints().n_rows());
    let c = l.elasticity().stiffness_matrix();
    chol.factorise(&l.stiffness(Material::Uniform(&c))).in_solver("newton")?;
    // z = K⁻¹f_u (zero without loads on u)
    let mut z = vec![0.0; n];
    let f_u = l.nodal_load();
    if !f_u.is_empty() && f_u.iter().any(|f| *f != 0.0) {
        z.copy_from_slice(f_u);
        chol.solve(&mut z);
    }
    let rows = l.constraints();
    let mut projection = MetricProjection::new(rows, chol, 0.0, 1.0, l.load())?;
    let (mut u, mut extras, mut lambda) = (vec![0.0; n], vec![0.0; ne], vec![0.0; nr]);
    let solves = projection.setup_solves + projection.project(rows, chol, &z, &mut extras, &mut u, &mut lambda)?;
    Ok((Start { u, extras, lambda }, solves))
}

/// out = x + α d.
fn axpy_into(out: &mut [f64], x: &[f64], alpha: f64, d: &[f64]) {
    for ((o, a), b) in out.iter_mut().zip(x).zip(d) {
        *o = a + alpha * b;
    }
}

/// x += α d.
fn axpy(x: &mut [f64], alpha: f64, d: &[f64]) {
    for (a, b) in x.iter_mut().zip(d) {
        *a += alpha * b;
    }
}
