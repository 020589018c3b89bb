//! The penalty method: the regularised Lagrangian L_μ of the paper's existence proof (theory §4.3),
//! maximised without constraints by Newton's method.
//!
//! # L_μ in physical units
//!
//! The paper writes `L_μ = L − (1/(2μ))∫_{Γ₀}[(v₃ + φ − V)⁻]² − (μ/2)‖ε(v)‖² − (μ/2)V²`
//! (theory §4.3) in its scaled units. Here μ is a *dimensionless* number that means the same thing in any
//! units and on any mesh: every term is measured against the elastic stiffness
//! K_el = Σ_T |T| B_Tᵀ C B_T where it acts. With the rows g(u, V) = G u + H V + c ≥ 0 of K_h
//! (theory §3), each acting on one coordinate s_i of its own with coefficient a_i (the
//! displacement dof itself for the punch; for general rows the coordinates of
//! [`crate::row_basis::RowBasis`], theory §8, in which the Newton systems below are solved),
//! maximising L_μ over (v, V) ∈ W_h × R is minimising
//!
//! ```text
//! J_μ(u, V) = Σ_T |T| ψ(ε_T(u)) − f·V  +  Σ_i ½ k_i (g_i⁻)²  +  (μ/2) uᵀK_el u  +  (μ/2) Σ_k k_V,k V_k²
//! ```
//!
//! with g⁻ = max(0, −g) and
//!
//! * `k_i = (K_el)_{s_i s_i} / (μ a_i²)` — the contact penalty stiffness: 1/μ times the elastic
//!   stiffness of the node in the row's direction (≈ E·h, so μ is relative to the local mesh size,
//!   also on graded meshes); a_i = 1 for the punch;
//! * `(μ/2) uᵀK_el u = (μ/2)(Cε(u), ε(u))` — the paper's (μ/2)‖ε(v)‖² in the energy metric;
//! * `k_V,k = E · L · mean_i H_ik²` over the rows touching extra k, L = |Ω|^{1/3} — the paper's
//!   (μ/2)V² with V weighted by the stiffness of the body as a whole (a mesh-independent scale:
//!   summing the nodal stiffnesses instead grows like 1/h under refinement and with it the load
//!   carried by the regularisation, μ k_V V).
//!
//! The penalty contact pressure of the paper's (1.16) (theory §4.3) is `χ_i = k_i g_i⁻ ≥ 0`; it is returned as λ.
//!
//! # Algorithm
//!
//! J_μ is convex and C¹ with the semismooth gradient `∇_u J_μ = Bᵀ(σ(u) + μCε(u)) − Gᵀχ`,
//! `∇_V J_μ = −f − Hᵀχ + μ k_V V`; for a set A of rows its generalised Hessian is
//!
//! ```text
//! [ K_t + μK_el + Σ_{i∈A} k_i a_i² e_s e_sᵀ     Σ_{i∈A} k_i a_i e_s H_iᵀ         ]
//! [ Σ_{i∈A} k_i a_i H_i e_sᵀ                    μ diag(k_V) + Σ_{i∈A} k_i H_i H_iᵀ ]
//! ```
//!
//! (K_t: the consistent tangent of theory §2). The contact rows only add to the diagonal, so the
//! u-block lives on the fixed pattern of L: one symbolic analysis per solve, numeric
//! factorisations on it. The extras are coupled through an n_extras × n_extras Schur complement
//! from one solve with 1 + n_extras right-hand sides, formed without the catastrophic
//! cancellation of the textbook `C − BᵀA⁻¹B` ([`PenaltySystem`]).
//!
//! Each Newton iteration runs in named stages (one method of the private `Run` each):
//!
//! 1. **local law** (`Run::local_law`): the pressures χ = k g⁻ and the local law with its
//!    consistent tangent at every element (theory §2.5);
//! 2. **residual** (`Run::residual`): the KKT residual of the *true* problem (theory §3.4);
//! 3. **gradient** (`Run::gradient`): ∇J_μ and its size relative to its terms;
//! 4. **convergence** (`Run::stop`): J_μ minimised to `gradient_tol` or `step_tol`, or out of
//!    budget;
//! 5. **assembly** (`Run::assemble`): K' = K_t + μK_el;
//! 6. **model step** (`Run::model_step`): the step d minimises the model `∇S·d + ½dᵀ(K_t + μK_el)d + Σ_i ½k_i((g_i + Δg_i(d))⁻)²` of
//!    J_μ = S + (contact term): the smooth part expanded to second order, the piecewise quadratic
//!    contact term kept *exactly*. It is found by an active-set loop on the model (A = rows that
//!    penetrate after the step; one factorisation each; usually one, two when the contact zone
//!    moves). Linearising the contact term instead (A = rows penetrating now) would let the first
//!    row that a step pushes into the obstacle, with its 1/μ stiffness, stop the line search: on
//!    fine meshes one row per iteration would enter;
//! 7. **line search** (`Run::step_length`): an Armijo backtracking line search on J_μ along d — a descent direction of J_μ since the
//!    model is convex with the same directional derivative — with safeguarded quadratic
//!    interpolation; the full step is taken when the predicted decrease is below the round-off of
//!    J_μ;
//! 8. **update** (`Run::advance`): (u, V) and the carried gaps along the step.
//!
//! From a cold start the first iteration uses the *elastic* tangent and takes the full step (as
//! [`crate::Newton`] does): its model is then exact, so it lands on the elastic penalty solution,
//! its active-set loop started from every candidate row (the punch imprints its shape instead of
//! pushing one node through the body, which would drive it plastic). The inner problem is solved
//! when the relative gradient of J_μ falls to `gradient_tol` or the Newton step to `step_tol`
//! (by default round-off, [`GRADIENT_TOL`] and [`STEP_TOL`]): J_μ is then minimised to machine
//! precision.
//!
//! **The gaps are carried, not recomputed.** χ = k g⁻ multiplies the gap by 1/μ, and g = u_s + φ −
//! V recomputed from (u, V) is known only to ε_mach·|u|: χ would carry a round-off error
//! ε_mach·k·|u| ∝ 1/μ (measured on the small default scene: a KKT floor of 1e-6 at μ = 1e-10,
//! optimum 3e-7 near μ = 1e-8 — the classical √ε_mach limit of penalty methods). The solver keeps
//! g alongside (u, V), starting from g(0, 0) = c. On the model's active rows the Newton step gives
//! the new gap directly, `ĝ_i = −a_i(y⁰ − Y dV)_s` (of size χ/k, computed from quantities of that
//! size), elsewhere `ĝ = g + G du + H dV`; along the line search `g(α) = (1 − α)g + αĝ`. The carried
//! gaps differ from G u + H V + c by a few ulps of |u| (counter `gap_drift_relative`): the problem
//! solved is the one with the obstacle offsets c perturbed at round-off level. With this and the
//! cancellation-free Schur complement, round-off never takes over: measured (the μ study in
//! `tests/penalty.rs`), the error falls like μ until it meets the reference's own accuracy, and
//! for μ from 1e-12 down to 1e-300 the solve takes the same iterations and U agrees with Newton to
//! round-off below μ = 1e-15; only a μ whose stiffness overflows is refused. The
//! `condition_estimate` grows like 1/μ nonetheless: it describes the matrix, not the accuracy of
//! these structured solves.
//!
//! # Honesty
//!
//! The penalty solves a regularised problem: its error against the solution of (2.1) is O(μ)
//! (penetration χ/k, the load carried by the regularisation, the stiffening μK_el). The report
//! therefore carries the residual of the *true* problem: `kkt` = [`Lagrangian::kkt`] on
//! (u, V, σ(u), χ), `tol` is a tolerance on that residual, and a solve whose inner problem is
//! solved but whose penalty error exceeds `tol` returns its solution with `converged = false`,
//! [`StopReason::ApproximationLimit`] and the counter `approximation_limit = 1`. The counters
//! carry the penalty's own error indicators: `max_penetration` (max g⁻, absolute and relative to
//! the displacement scale), `load_defect` = ‖f + Hᵀχ‖ (|Σχ − F| for the punch; absolute and
//! relative to ‖f‖), `mu`, and `condition_estimate` (see [`PenaltySystem`]).

use crate::linear::{self, InSolver};
use crate::newton::{ARMIJO, SLOPE_ROUND_OFF};
use crate::residual;
use crate::row_basis::RowBasis;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use saddle_core::error::{ParameterError, check};
use saddle_core::linalg::SparseCholesky;
use saddle_core::problem::energies::energy;
use saddle_core::problem::fields::StressField;
use saddle_core::problem::kkt::{KktResiduals, kkt_with_stress, max_abs, norm};
use saddle_core::problem::lagrangian::{Iterate, Lagrangian, Workspace};
use saddle_core::problem::operators::Material;
use saddle_core::problem::solver::{Monitor, PhaseTimer, Solution, SolveError, SolveReport, Solver, Start, StopReason};
use saddle_core::{Sym, SymOp};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The default of `gradient_tol`: the inner problem is solved when ‖∇J_μ‖ falls below this
/// fraction of the size of its terms. Its terms are sums over thousands of elements, each known
/// to ε_mach of its size: 1e-12 (≈ 5000 ε_mach) is the round-off level, J_μ is then minimised to
/// machine precision.
pub const GRADIENT_TOL: f64 = 1e-12;
/// The default of `step_tol`: ... or when the Newton step falls below this fraction of the
/// displacement scale, a few hundred ulps of u: further steps would only move u in its
/// round-off.
pub const STEP_TOL: f64 = 1e-13;
/// Active-set sweeps of the contact model per Newton step before falling back to the plain
/// semismooth Newton direction. The model settles in one sweep, two when the contact zone
/// moves (module docs); ten sweeps without settling means its active set cycles.
pub const MODEL_SWEEPS: usize = 10;
/// Shrinkings before the line search gives up: each shrinks α by at least half, so 60 of them
/// take it below 2⁻⁶⁰ ≈ 1e-18, beneath any step that changes J_μ measurably.
pub const MAX_BACKTRACKS: usize = 60;
/// The safeguard of the line search's quadratic interpolation: the next trial α lies in
/// [0.1, 0.5] times the last one (at least halved, at most cut tenfold), the usual bounds that
/// keep interpolation from stalling or from collapsing the step.
pub const SHRINK_MIN: f64 = 0.1;
/// The upper bound of that safeguard, and the plain halving when the parabola is degenerate.
pub const SHRINK_MAX: f64 = 0.5;
/// A line search that finds no decrease along a step larger than this fraction of the
/// displacement scale means the iteration is stuck (`stagnated`). Below it, the step is under
/// √ε_mach ≈ 1.5e-8 of u, where the change of J_μ (quadratic near its minimum) is at the
/// round-off of J_μ itself: the inner problem is then solved.
pub const STUCK_STEP: f64 = 1e-8;

/// `type = "penalty"`: the regularised Lagrangian L_μ of the existence proof (theory §4.3), solved
/// by Newton's method.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Penalty {
    /// The dimensionless regularisation μ: penalty stiffness = elastic stiffness / μ. The error
    /// against the discrete problem of theory §3 is O(μ): measured, the true KKT residual is ≈ 4.2μ
    /// on the small default scene and ≈ 4.4μ on `examples/johnson.toml` (mesh-independent: the
    /// regularisation of V uses the body's stiffness E·|Ω|^{1/3}). The default 1e-12 meets the
    /// default `tol` with a margin of ~1000.
    pub mu: f64,
    /// Tolerance on the relative KKT residual of the *true* problem (theory §3, §5).
    pub tol: f64,
    /// Newton iteration budget.
    pub max_iter: usize,
    /// The inner problem (minimising J_μ) is solved when ‖∇J_μ‖ relative to the size of its
    /// terms falls to this (default [`GRADIENT_TOL`], round-off) ...
    pub gradient_tol: f64,
    /// ... or when the Newton step falls to this fraction of the displacement scale (default
    /// [`STEP_TOL`], round-off). Loosening either trades the inner accuracy for iterations; the
    /// report's residual is that of the true problem either way.
    pub step_tol: f64,
}

impl Default for Penalty {
    fn default() -> Self {
        Self { mu: 1e-12, tol: 1e-8, max_iter: 50, gradient_tol: GRADIENT_TOL, step_tol: STEP_TOL }
    }
}

#[typetag::serde(name = "penalty")]
impl Solver for Penalty {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::positive(path, "mu", self.mu)?;
        check::open_interval(path, "tol", self.tol, 0.0, 1.0)?;
        check::at_least_one(path, "max_iter", self.max_iter)?;
        check::open_interval(path, "gradient_tol", self.gradient_tol, 0.0, 1.0)?;
        check::open_interval(path, "step_tol", self.step_tol, 0.0, 1.0)?;
        Ok(())
    }

    fn tolerance(&self) -> f64 {
        self.tol
    }

    fn solve(&self, l: &Lagrangian<'_>, monitor: &mut dyn Monitor) -> Result<Solution, SolveError> {
        let mut timer = PhaseTimer::default();
        monitor.phase("set-up");
        let sys = timer.time("set-up", || PenaltySystem::new(l, self.mu))?;
        self.newton(l, sys, None, monitor, timer)
    }

    /// Newton on J_μ from the previous step's (u, V), without the elastic iteration (theory
    /// §11.2).
    fn solve_warm(&self, l: &Lagrangian<'_>, start: &Start, monitor: &mut dyn Monitor) -> Result<Solution, SolveError> {
        start.check(l, "penalty")?;
        let mut timer = PhaseTimer::default();
        monitor.phase("set-up");
        let sys = timer.time("set-up", || PenaltySystem::new(l, self.mu))?;
        let mut sol = self.newton(l, sys, Some(start), monitor, timer)?;
        sol.report.counters.insert("warm_start".into(), 1.0);
        Ok(sol)
    }
}

/// The penalty scales of J_μ and its Newton system.
///
/// For a set A of rows, with D_A = diag(k_i a_i²) at the slave dofs, z_s = −g_i/a_i and
/// `P_k[s] = H_ik/a_i` on A, the u-block is A = K' + D_A (K' = K_t + μK_el) and the coupling to
/// the extras is D_A P. Since `A⁻¹D_A x = x − A⁻¹K'x`, eliminating du needs
/// `[y⁰ Y] = A⁻¹[r + K'z, K'P]` (r = Bᵀ(σ + μCε), right-hand sides of moderate size), and then
///
/// ```text
/// S = μ diag(k_V) + Pᵀ D_A Y,   S dV = f − μ k_V V + Pᵀ D_A y⁰,   du = z − y⁰ − (P − Y) dV,
/// ```
///
/// free of the cancellation of `C − BᵀA⁻¹B` (two terms of size 1/μ whose difference is of size 1).
///
/// `condition_estimate` is max/min of the diagonal of the last factorised u-block: a lower
/// bound of its spectral condition number, which the penalty raises by ~1/μ.
pub struct PenaltySystem {
    mu: f64,
    /// The rows' coordinates (theory §8): each row acts on one coordinate s_i, a_i = G_{i s_i}.
    slaves: RowBasis,
    /// k_i = (K_el)_{ss} / (μ a_i²).
    k: Vec<f64>,
    /// k_V,k = Σ_i H_ik² (K_el)_{ss}.
    k_v: Vec<f64>,
    c_el: SymOp,
    chol: SparseCholesky,
    /// K' = K_t + μK_el on L's pattern.
    kprime: Vec<f64>,
    /// TᵀK'T in the rows' coordinates, and Tᵀr (empty when T = I).
    kprime_t: Vec<f64>,
    r_t: Vec<f64>,
    /// K' + D_A, factorised.
    hess: Vec<f64>,
    /// n × (1 + n_extras): [z, P_1, …].
    cols: Vec<f64>,
    /// n × (1 + n_extras): [r + K'z, K'P_1, …], then [y⁰, Y_1, …].
    kcols: Vec<f64>,
    /// The model's next active set.
    next: Vec<bool>,
    /// Symbolic analyses of L's pattern so far (one, in [`PenaltySystem::new`]).
    pub symbolic_analyses: usize,
    /// Numeric factorisations so far.
    pub factorisations: usize,
    /// Triangular solve pairs so far.
    pub solves: usize,
    /// max/min diagonal of the last factorised matrix.
    pub condition_estimate: f64,
}

impl std::fmt::Debug for PenaltySystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PenaltySystem").field("mu", &self.mu).field("rows", &self.k.len()).finish()
    }
}

/// The current iterate as the Newton step sees it.
struct Point<'a> {
    /// Bᵀ(σ + μCε) − f_u: the gradient of the smooth part.
    r: &'a [f64],
    /// The carried gaps g.
    gap: &'a [f64],
    /// V.
    v: &'a [f64],
}

/// The Newton step and the gaps it leads to.
struct Direction<'a> {
    du: &'a mut [f64],
    dv: &'a mut [f64],
    /// ĝ = g(u + du, V + dV).
    g_next: &'a mut [f64],
}

impl PenaltySystem {
    /// The penalty scales from the elastic stiffness diagonal, and the symbolic analysis of L's
    /// pattern (once).
    pub fn new(l: &Lagrangian<'_>, mu: f64) -> Result<Self, SolveError> {
        let rows = l.data.rows;
        let slaves = RowBasis::new(rows, l.n_dofs(), l.pattern(), "penalty")?;
        let c_el = l.data.elasticity.stiffness_matrix();
        let mut kprime = l.stiffness(Material::Uniform(&c_el));
        let k: Vec<f64> = slaves.row_stiffness(l.pattern(), &kprime).iter().map(|k| k / mu).collect();
        if let Some(i) = k.iter().position(|k| !k.is_finite()) {
            let why =
                format!("is too small: the penalty stiffness (elastic stiffness / mu) of contact row {i} overflows");
            return Err(ParameterError::new("solver.mu", mu, why).into());
        }
        let ne = l.n_extras();
        let body_stiffness = l.data.elasticity.young * l.weights().iter().sum::<f64>().cbrt();
        let k_v: Vec<f64> = (0..ne)
            .map(|kx| {
                let h2: Vec<f64> =
                    (0..rows.n_rows()).map(|i| rows.extra_row(i)[kx].powi(2)).filter(|h| *h > 0.0).collect();
                if h2.is_empty() { 0.0 } else { body_stiffness * h2.iter().sum::<f64>() / h2.len() as f64 }
            })
            .collect();
        for (kx, kv) in k_v.iter().enumerate() {
            if *kv <= 0.0 && l.data.load[kx] != 0.0 {
                return Err(SolveError::Unsupported {
                    solver: "penalty".into(),
                    message: format!("extra unknown {kx} carries a load but no contact row acts on it"),
                });
            }
        }
        let n = l.n_dofs();
        kprime.iter_mut().for_each(|x| *x = 0.0);
        let mut symbolic_analyses = 0;
        let pattern = slaves.pattern(l.pattern());
        let chol = linear::analyse(pattern, "penalty Hessian", "penalty", &mut symbolic_analyses)?;
        let nnz = pattern.nnz();
        let transformed = !slaves.is_identity();
        Ok(Self {
            mu,
            slaves,
            k,
            k_v,
            c_el,
            chol,
            hess: vec![0.0; nnz],
            kprime_t: if transformed { vec![0.0; nnz] } else { Vec::new() },
            r_t: if transformed { vec![0.0; n] } else { Vec::new() },
            kprime,
            cols: vec![0.0; n * (1 + ne)],
            kcols: vec![0.0; n * (1 + ne)],
            next: vec![false; rows.n_rows()],
            symbolic_analyses,
            factorisations: 0,
            solves: 0,
            condition_estimate: f64::NAN,
        })
    }

    /// χ_i = k_i g_i⁻.
    fn pressures(&self, gap: &[f64], chi: &mut [f64]) {
        for ((c, g), k) in chi.iter_mut().zip(gap).zip(&self.k) {
            *c = k * (-g).max(0.0);
        }
    }

    /// J_μ(u, V) with the gaps `gap` = g(u, V); `ws.eps` holds ε(u) afterwards.
    fn energy(&self, l: &Lagrangian<'_>, u: &[f64], v: &[f64], gap: &[f64], ws: &mut Workspace) -> f64 {
        let j = energy(l, u, v, ws);
        let c = &self.c_el;
        let reg: f64 = ws.eps.par_iter().zip(l.weights().par_iter()).map(|(e, w)| w * e.dot(&(c * e))).sum();
        let pen: f64 = gap.iter().zip(&self.k).map(|(g, k)| k * (-g).max(0.0).powi(2)).sum();
        let reg_v: f64 = self.k_v.iter().zip(v).map(|(k, v)| k * v * v).sum();
        j + 0.5 * (self.mu * (reg + reg_v) + pen)
    }

    /// The Newton step of the contact model (module docs, step 2) with K' in `self.kprime`: an
    /// active-set loop from `model`, which holds the final set on return. Returns the number of
    /// sweeps and whether the set settled; if not, and `descent` asks for a descent direction of
    /// J_μ, d is the plain semismooth Newton direction (A = {g < 0}), else the last sweep's.
    fn model_step(
        &mut self,
        l: &Lagrangian<'_>,
        model: &mut [bool],
        at: &Point<'_>,
        d: &mut Direction<'_>,
        descent: bool,
    ) -> Result<(usize, bool), SolveError> {
        if !self.slaves.is_identity() {
            // K' and r in the rows' coordinates, once for all the sweeps
            self.slaves.stiffness(&self.kprime, &mut self.kprime_t);
            self.slaves.force_to_coordinates(at.r, &mut self.r_t);
        }
        for sweep in 1..=MODEL_SWEEPS {
            self.step(l, model, at, d)?;
            let mut settled = true;
            for ((next, g), a) in self.next.iter_mut().zip(d.g_next.iter()).zip(model.iter()) {
                *next = *g < 0.0;
                settled &= *next == *a;
            }
            if settled {
                return Ok((sweep, true));
            }
            if sweep == MODEL_SWEEPS && !descent {
                return Ok((sweep, false));
            }
            model.copy_from_slice(&self.next);
        }
        for (a, g) in model.iter_mut().zip(at.gap) {
            *a = *g < 0.0;
        }
        self.step(l, model, at, d)?;
        Ok((MODEL_SWEEPS + 1, false))
    }

    /// The Newton step for the quadratic model in which the rows `active` carry ½k_i g_i²
    /// (formulas in the type's docs), and the gaps ĝ after it.
    fn step(
        &mut self,
        l: &Lagrangian<'_>,
        active: &[bool],
        at: &Point<'_>,
        d: &mut Direction<'_>,
    ) -> Result<(), SolveError> {
        let p = self.slaves.pattern(l.pattern());
        let rows = l.data.rows;
        let (n, ne, nr) = (l.n_dofs(), l.n_extras(), rows.n_rows());
        let nc = 1 + ne;
        // K' and r in the rows' coordinates (transformed once per Newton step, [`Self::model_step`])
        let (kprime, r): (&[f64], &[f64]) =
            if self.slaves.is_identity() { (&self.kprime, at.r) } else { (&self.kprime_t, &self.r_t) };
        // z and P on the active slave dofs; K' times them, plus r in column 0
        self.cols.iter_mut().for_each(|x| *x = 0.0);
        for i in (0..nr).filter(|&i| active[i]) {
            let (s, a) = (self.slaves.dof[i], self.slaves.coef[i]);
            self.cols[s] = -at.gap[i] / a;
            for (kx, h) in rows.extra_row(i).iter().enumerate() {
                self.cols[(1 + kx) * n + s] = h / a;
            }
        }
        for c in 0..nc {
            p.matvec(kprime, &self.cols[c * n..(c + 1) * n], &mut self.kcols[c * n..(c + 1) * n]);
        }
        for (x, ri) in self.kcols[..n].iter_mut().zip(r) {
            *x += ri;
        }
        // A = K' + D_A on the fixed pattern
        let cp = p.col_ptr();
        self.hess.copy_from_slice(kprime);
        for i in (0..nr).filter(|&i| active[i]) {
            self.hess[cp[self.slaves.dof[i]]] += self.k[i] * self.slaves.coef[i].powi(2);
        }
        let (dmin, dmax) = cp[..n].iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &q| {
            let x = self.hess[q];
            (lo.min(x), hi.max(x))
        });
        self.condition_estimate = dmax / dmin;
        self.chol.factorise(&self.hess).in_solver("penalty")?;
        self.factorisations += 1;
        self.chol.solve_columns(&mut self.kcols, nc);
        self.solves += nc;
        let (y0, y) = self.kcols.split_at(n);
        // the extras: S dV = b
        if ne > 0 {
            let mut s = DMatrix::<f64>::zeros(ne, ne);
            let mut b = DVector::<f64>::zeros(ne);
            for kx in 0..ne {
                s[(kx, kx)] = self.mu * self.k_v[kx];
                b[kx] = l.data.load[kx] - self.mu * self.k_v[kx] * at.v[kx];
            }
            for i in (0..nr).filter(|&i| active[i]) {
                let (sd, ka) = (self.slaves.dof[i], self.k[i] * self.slaves.coef[i]);
                for (kx, h) in rows.extra_row(i).iter().enumerate() {
                    b[kx] += ka * h * y0[sd];
                    for ly in 0..ne {
                        s[(kx, ly)] += ka * h * y[ly * n + sd];
                    }
                }
            }
            let s = (&s + s.transpose()) * 0.5;
            let sol = s.lu().solve(&b).filter(|x| x.iter().all(|x| x.is_finite()));
            let sol = sol.ok_or_else(|| non_finite("the extras' Schur complement", self.factorisations))?;
            d.dv.copy_from_slice(sol.as_slice());
        }
        // du = z − y⁰ − (P − Y) dV
        for j in 0..n {
            let mut x = self.cols[j] - y0[j];
            for (kx, dv) in d.dv.iter().enumerate() {
                x -= (self.cols[(1 + kx) * n + j] - y[kx * n + j]) * dv;
            }
            d.du[j] = x;
        }
        // ĝ: on the active rows from the model, ĝ_i = g_i + a_i du_s + H_i dV = −a_i(y⁰ − Y dV)_s,
        // which is of size χ/k and would be lost in the rounding of g + G du + H dV at μ ≲ 1e-14;
        // on the others by the increment
        for (i, gn) in d.g_next.iter_mut().enumerate() {
            let (s, a) = (self.slaves.dof[i], self.slaves.coef[i]);
            *gn = if active[i] {
                -a * (y0[s] - d.dv.iter().enumerate().map(|(kx, dv)| y[kx * n + s] * dv).sum::<f64>())
            } else {
                at.gap[i] + a * d.du[s] + rows.extra_row(i).iter().zip(d.dv.iter()).map(|(h, x)| h * x).sum::<f64>()
            };
        }
        // du = T dy
        self.slaves.displacement_from_coordinates(d.du);
        Ok(())
    }
}

impl Penalty {
    /// Newton on J_μ (module docs, theory §4.3) in stages, then the honest report.
    fn newton(
        &self,
        l: &Lagrangian<'_>,
        sys: PenaltySystem,
        start: Option<&Start>,
        monitor: &mut dyn Monitor,
        mut timer: PhaseTimer,
    ) -> Result<Solution, SolveError> {
        let mut run = Run::new(self, l, sys);
        if let Some(start) = start {
            run.warm_start(start);
        }
        monitor.phase("iterations");
        let (end, kkt) = loop {
            run.local_law(&mut timer);
            let kkt = run.residual(&mut timer);
            residual::record("penalty", run.state.it, kkt.max(), self.tol, &mut run.history, monitor)?;
            run.gradient(&mut timer)?;
            if let Some(end) = run.stop() {
                break (end, kkt);
            }
            run.assemble(&mut timer);
            run.model_step(&mut timer)?;
            let alpha = run.step_length(&mut timer);
            run.advance(alpha);
        };
        Ok(run.finish(end, kkt, timer))
    }
}

/// Why Newton on J_μ ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum End {
    /// J_μ minimised to round-off: the inner problem is solved.
    Minimised,
    /// No measurable decrease along a step that is not small: the iteration is stuck.
    Stuck,
    /// Out of iterations.
    Budget,
}

/// The iteration state of Newton on J_μ (theory §4.3): the iterate, its carried gaps and
/// pressures, the model's active set, and where the iteration stands.
struct State {
    /// u.
    u: Vec<f64>,
    /// V.
    v: Vec<f64>,
    /// The carried gaps g (module docs), g(0, 0) = c at the start.
    gap: Vec<f64>,
    /// χ = k g⁻, the penalty contact pressures.
    chi: Vec<f64>,
    /// σ̂ = P_D(Cε(u), 0), from the last local law.
    stress: StressField,
    /// The contact model's active set, and the previous iteration's.
    model: Vec<bool>,
    previous: Vec<bool>,
    /// Iterations done.
    it: usize,
    /// The last step was at round-off, or the line search failed: evaluate once more, stop.
    finished: bool,
    /// ... and the line search failed on a step that is not small.
    stuck: bool,
    /// ‖∇J_μ‖ relative to the size of its terms, at the iterate.
    grad_rel: f64,
    /// The Newton decrement −∇J_μ·d relative to |J_μ|, of the last line search.
    decrement_rel: f64,
}

/// What a penalty run counts for its report.
#[derive(Default)]
struct Counts {
    /// Shrinkings of the line search.
    backtracks: usize,
    /// Rows that entered or left the model's active set.
    active_changes: usize,
    /// Points at which P's return mapping ran, as the local law reports them.
    return_mappings: usize,
    /// Active-set sweeps of the contact model.
    sweeps: usize,
    /// Newton steps whose model did not settle.
    unsettled: usize,
    /// Line searches that found no decrease.
    line_search_failures: usize,
}

/// Scratch of the stages, allocated once per solve.
struct Scratch {
    ws: Workspace,
    /// Consistent tangents per point (plus μC after assembly).
    tangents: Vec<SymOp>,
    /// σ + μCε.
    sig_mu: Vec<Sym>,
    /// Bᵀ(σ + μCε) − f_u: the gradient of the smooth part.
    r: Vec<f64>,
    /// ∇J_μ.
    grad_u: Vec<f64>,
    grad_v: Vec<f64>,
    /// Gᵀχ and Hᵀχ.
    gt_chi: Vec<f64>,
    ht_chi: Vec<f64>,
    /// The Newton step and the gaps after it.
    du: Vec<f64>,
    dv: Vec<f64>,
    g_next: Vec<f64>,
    /// The line search's trial point and its gaps.
    u_trial: Vec<f64>,
    v_trial: Vec<f64>,
    gap_trial: Vec<f64>,
}

/// One penalty solve: what it reads, its Newton system, state, counters and scratch.
struct Run<'a> {
    settings: &'a Penalty,
    l: &'a Lagrangian<'a>,
    sys: PenaltySystem,
    /// P bounds the stresses (else no tangents are needed).
    plastic: bool,
    /// (1 + μ)C: the elastic tangent of J_μ.
    c_el_mu: SymOp,
    /// Started from a previous solution (no elastic iteration).
    warm: bool,
    state: State,
    count: Counts,
    work: Scratch,
    /// The true problem's KKT residual of every iterate.
    history: Vec<f64>,
}

impl<'a> Run<'a> {
    /// The cold start u = 0, V = 0, g = c, every row in the model, and the scratch.
    fn new(settings: &'a Penalty, l: &'a Lagrangian<'a>, sys: PenaltySystem) -> Self {
        let rows = l.data.rows;
        let (n, ne, nr, np) = (l.n_dofs(), l.n_extras(), rows.n_rows(), l.n_points());
        let state = State {
            u: vec![0.0; n],
            v: vec![0.0; ne],
            gap: rows.offset.clone(),
            chi: vec![0.0; nr],
            stress: StressField::new(np, l.data.hardening_dim()),
            model: vec![true; nr],
            previous: vec![true; nr],
            it: 0,
            finished: false,
            stuck: false,
            grad_rel: f64::NAN,
            decrement_rel: f64::NAN,
        };
        let work = Scratch {
            ws: Workspace::new(l),
            tangents: vec![SymOp::zeros(); np],
            sig_mu: vec![Sym::zeros(); np],
            r: vec![0.0; n],
            grad_u: vec![0.0; n],
            grad_v: vec![0.0; ne],
            gt_chi: vec![0.0; n],
            ht_chi: vec![0.0; ne],
            du: vec![0.0; n],
            dv: vec![0.0; ne],
            g_next: vec![0.0; nr],
            u_trial: vec![0.0; n],
            v_trial: vec![0.0; ne],
            gap_trial: vec![0.0; nr],
        };
        let c_el_mu = sys.c_el * (1.0 + settings.mu);
        Self {
            settings,
            l,
            plastic: l.data.plasticity().is_some(),
            c_el_mu,
            warm: false,
            sys,
            state,
            count: Counts::default(),
            work,
            history: Vec::new(),
        }
    }

    /// The cold iteration is elastic: its model is exact, its step full (module docs). A warm
    /// start has none.
    fn elastic(&self) -> bool {
        self.state.it == 0 && !self.warm
    }

    /// Starts from the previous step's (u, V) (theory §11.2): the gaps recomputed there, the
    /// model's rows those that penetrate.
    fn warm_start(&mut self, start: &Start) {
        let rows = self.l.data.rows;
        let s = &mut self.state;
        s.u.copy_from_slice(&start.u);
        s.v.copy_from_slice(&start.extras);
        rows.gap(&s.u, &s.v, &mut s.gap);
        for (a, g) in s.model.iter_mut().zip(&s.gap) {
            *a = *g < 0.0;
        }
        s.previous.copy_from_slice(&s.model);
        self.warm = true;
    }

    /// Stage 1 (theory §4.3; the local law of theory §2): the pressures χ = k g⁻, the stresses
    /// σ(u) and, when Newton needs them, the consistent tangents.
    fn local_law(&mut self, timer: &mut PhaseTimer) {
        let want_tangents = !self.elastic() && !self.state.finished && self.plastic;
        let (l, s, w) = (self.l, &mut self.state, &mut self.work);
        self.sys.pressures(&s.gap, &mut s.chi);
        let law = timer.time("local law", || {
            l.strain(&s.u, &mut w.ws.eps);
            l.data.local_law(&w.ws.eps, &mut s.stress, if want_tangents { Some(&mut w.tangents) } else { None })
        });
        self.count.return_mappings += law.projected;
    }

    /// Stage 2 (theory §4.3, honesty; theory §3.4): the KKT residuals of the *true* problem
    /// on (u, V, σ(u), χ).
    fn residual(&mut self, timer: &mut PhaseTimer) -> KktResiduals {
        let (l, s, w) = (self.l, &self.state, &mut self.work);
        timer.time("residual", || {
            w.ws.stress.clone_from(&s.stress);
            kkt_with_stress(l, &Iterate { u: &s.u, extras: &s.v, stress: &s.stress, lambda: &s.chi }, &mut w.ws)
        })
    }

    /// Stage 3 (theory §4.3): ∇J_μ — of the elastic J_μ in the cold iteration — and its size
    /// relative to its terms.
    fn gradient(&mut self, timer: &mut PhaseTimer) -> Result<(), SolveError> {
        let elastic = self.elastic();
        let (l, sys, s, w) = (self.l, &self.sys, &mut self.state, &mut self.work);
        let (mu, c_el) = (self.settings.mu, sys.c_el);
        let rows = l.data.rows;
        timer.time("gradient", || {
            let eps = &w.ws.eps;
            if elastic {
                // C(ε − ε_p) + μCε: the elastic response from the step's state (theory §11.1)
                l.data.elastic_stress(eps, &mut w.sig_mu);
                w.sig_mu.par_iter_mut().zip(eps.par_iter()).for_each(|(s, e)| *s += c_el * e * mu);
            } else {
                let sigma = s.stress.sigma.par_iter();
                w.sig_mu.par_iter_mut().zip(sigma).zip(eps.par_iter()).for_each(|((s, sg), e)| *s = sg + c_el * e * mu);
            }
            l.divergence(&w.sig_mu, &mut w.r);
            // the loads on u belong to the smooth part
            for (ri, f) in w.r.iter_mut().zip(l.data.nodal_load) {
                *ri -= f;
            }
            w.gt_chi.iter_mut().for_each(|x| *x = 0.0);
            w.ht_chi.iter_mut().for_each(|x| *x = 0.0);
            rows.add_transpose(&s.chi, &mut w.gt_chi, &mut w.ht_chi);
            for ((g, a), b) in w.grad_u.iter_mut().zip(&w.r).zip(&w.gt_chi) {
                *g = a - b;
            }
            for kx in 0..l.n_extras() {
                w.grad_v[kx] = -l.data.load[kx] - w.ht_chi[kx] + mu * sys.k_v[kx] * s.v[kx];
            }
        });
        let grad_norm = (norm(&w.grad_u).powi(2) + norm(&w.grad_v).powi(2)).sqrt();
        let grad_scale =
            norm(&w.r).max(norm(&w.gt_chi)).max(norm(l.data.load)).max(norm(&w.ht_chi)).max(norm(l.data.nodal_load));
        s.grad_rel = if grad_scale > 0.0 { grad_norm / grad_scale } else { grad_norm };
        if !s.grad_rel.is_finite() {
            return Err(non_finite("the gradient of J_μ", s.it));
        }
        Ok(())
    }

    /// Stage 4 (theory §4.3, §4.5): J_μ minimised to round-off (relative gradient at most
    /// `gradient_tol`, or the last step at round-off), or out of budget; `None`: go on.
    fn stop(&self) -> Option<End> {
        let s = &self.state;
        if s.finished || (!self.elastic() && s.grad_rel <= self.settings.gradient_tol) {
            Some(if s.stuck { End::Stuck } else { End::Minimised })
        } else if s.it >= self.settings.max_iter {
            Some(End::Budget)
        } else {
            None
        }
    }

    /// Stage 5 (theory §4.3): K' = K_t + μK_el on L's pattern — (1 + μ)K_el in the cold
    /// iteration or without plasticity.
    fn assemble(&mut self, timer: &mut PhaseTimer) {
        let elastic_tangent = self.elastic() || !self.plastic;
        let (l, sys, w) = (self.l, &mut self.sys, &mut self.work);
        let (c_el, mu) = (sys.c_el, self.settings.mu);
        if elastic_tangent {
            timer.time("assembly", || l.assemble(Material::Uniform(&self.c_el_mu), &mut sys.kprime));
        } else {
            timer.time("assembly", || {
                w.tangents.par_iter_mut().for_each(|t| *t += c_el * mu);
                l.assemble(Material::PerPoint(&w.tangents), &mut sys.kprime);
            });
        }
    }

    /// Stage 6 (theory §4.3): the Newton step of the contact model, its active-set loop started
    /// from every row (cold) or from the rows penetrating now, and the gaps ĝ after it.
    fn model_step(&mut self, timer: &mut PhaseTimer) -> Result<(), SolveError> {
        let elastic = self.elastic();
        let (l, sys, s, w) = (self.l, &mut self.sys, &mut self.state, &mut self.work);
        if !elastic {
            for (a, g) in s.model.iter_mut().zip(&s.gap) {
                *a = *g < 0.0;
            }
        }
        let (sweeps, settled) = timer.time("factorisation and solves", || {
            let at = Point { r: &w.r, gap: &s.gap, v: &s.v };
            let mut d = Direction { du: &mut w.du, dv: &mut w.dv, g_next: &mut w.g_next };
            sys.model_step(l, &mut s.model, &at, &mut d, !elastic)
        })?;
        self.count.sweeps += sweeps;
        self.count.unsettled += !settled as usize;
        self.count.active_changes += s.model.iter().zip(&s.previous).filter(|(a, b)| a != b).count();
        s.previous.copy_from_slice(&s.model);
        if w.du.iter().chain(&w.dv).any(|x| !x.is_finite()) {
            return Err(non_finite("the Newton step", s.it));
        }
        Ok(())
    }

    /// Stage 7 (theory §4.3): the step length α — full in the cold iteration; afterwards an
    /// Armijo line search on J_μ with safeguarded quadratic interpolation, the full step when
    /// the predicted decrease is below the round-off of J_μ, and the end of the iteration when
    /// the step is at the round-off of u or no decrease is found.
    fn step_length(&mut self, timer: &mut PhaseTimer) -> f64 {
        let elastic = self.elastic();
        let (l, sys, s, w) = (self.l, &self.sys, &mut self.state, &mut self.work);
        let offset = &l.data.rows.offset;
        let slope = dot(&w.grad_u, &w.du) + dot(&w.grad_v, &w.dv);
        let x_scale = max_abs(&s.u).max(max_abs(&s.v)).max(max_abs(offset));
        let step_rel = max_abs(&w.du).max(max_abs(&w.dv)) / x_scale.max(f64::MIN_POSITIVE);
        let mut alpha = 1.0;
        if elastic {
            return alpha;
        }
        let j0 = timer.time("line search", || sys.energy(l, &s.u, &s.v, &s.gap, &mut w.ws));
        let j_scale = j0.abs().max(l.data.load.iter().zip(&s.v).map(|(f, v)| (f * v).abs()).sum());
        s.decrement_rel = (-slope).max(0.0) / j_scale.max(f64::MIN_POSITIVE);
        if step_rel <= self.settings.step_tol {
            // the step is at the round-off of u: take it, re-evaluate, stop
            s.finished = true;
        } else if slope < 0.0 && -slope > SLOPE_ROUND_OFF * j_scale {
            let backtracks = &mut self.count.backtracks;
            let found = timer.time("line search", || {
                for _ in 0..MAX_BACKTRACKS {
                    axpy_into(&mut w.u_trial, &s.u, alpha, &w.du);
                    axpy_into(&mut w.v_trial, &s.v, alpha, &w.dv);
                    blend(&mut w.gap_trial, &s.gap, alpha, &w.g_next);
                    let j = sys.energy(l, &w.u_trial, &w.v_trial, &w.gap_trial, &mut w.ws);
                    if j <= j0 + ARMIJO * alpha * slope {
                        return true;
                    }
                    // safeguarded minimiser of the parabola through J(0), J'(0), J(α)
                    let q = -slope * alpha * alpha / (2.0 * (j - j0 - slope * alpha));
                    alpha = if q.is_finite() {
                        q.clamp(SHRINK_MIN * alpha, SHRINK_MAX * alpha)
                    } else {
                        SHRINK_MAX * alpha
                    };
                    *backtracks += 1;
                }
                false
            });
            if !found {
                // no measurable decrease along a descent direction: J_μ is at its round-off if
                // the step is tiny, else the iteration is stuck
                self.count.line_search_failures += 1;
                alpha = 0.0;
                s.finished = true;
                s.stuck = step_rel > STUCK_STEP;
            }
        }
        // else: the predicted decrease is below the round-off of J_μ: the full step
        alpha
    }

    /// (u, V) += α (du, dV) and the carried gaps along the step, g ← (1 − α)g + αĝ.
    fn advance(&mut self, alpha: f64) {
        let (s, w) = (&mut self.state, &self.work);
        axpy(&mut s.u, alpha, &w.du);
        axpy(&mut s.v, alpha, &w.dv);
        for (g, gn) in s.gap.iter_mut().zip(&w.g_next) {
            *g = (1.0 - alpha) * *g + alpha * gn;
        }
        s.it += 1;
    }

    /// The solution and its honest report (module docs): the true residual `kkt` decides
    /// `converged`, the counters carry the penalty's error indicators.
    fn finish(mut self, end: End, kkt: KktResiduals, timer: PhaseTimer) -> Solution {
        let (l, sys, s, w, c) = (self.l, &self.sys, &self.state, &mut self.work, &self.count);
        let rows = l.data.rows;
        let mu = self.settings.mu;
        let inner_solved = end == End::Minimised;
        let converged = inner_solved && kkt.max() <= self.settings.tol;
        let stop = match end {
            End::Minimised if converged => StopReason::Converged,
            End::Minimised => StopReason::ApproximationLimit,
            End::Stuck => StopReason::Stagnated,
            End::Budget => StopReason::MaxIterations,
        };
        let x_scale = max_abs(&s.u).max(max_abs(&s.v)).max(max_abs(&rows.offset));
        let relative = |x: f64, scale: f64| if scale > 0.0 { x / scale } else { x };
        let max_pen = s.gap.iter().fold(0.0f64, |m, g| m.max(-g));
        let load_def = l.data.load.iter().zip(&w.ht_chi).map(|(f, h)| (f + h).powi(2)).sum::<f64>().sqrt();
        rows.gap(&s.u, &s.v, &mut w.ws.gap);
        let drift = s.gap.iter().zip(&w.ws.gap).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let mut counters = BTreeMap::new();
        let mut put = |k: &str, x: f64| counters.insert(k.to_string(), x);
        put("mu", mu);
        put("max_penetration", max_pen);
        put("max_penetration_relative", relative(max_pen, x_scale));
        put("load_defect", load_def);
        put("load_defect_relative", relative(load_def, norm(l.data.load)));
        put("condition_estimate", sys.condition_estimate);
        put("penalty_stiffness_max", sys.k.iter().copied().fold(0.0, f64::max));
        put("gap_drift_relative", relative(drift, x_scale));
        put("factorisations", sys.factorisations as f64);
        put("symbolic_analyses", sys.symbolic_analyses as f64);
        put("triangular_solve_pairs", sys.solves as f64);
        put("contact_model_sweeps", c.sweeps as f64);
        put("contact_model_unsettled", c.unsettled as f64);
        put("line_search_backtracks", c.backtracks as f64);
        put("line_search_failures", c.line_search_failures as f64);
        put("active_set_changes", c.active_changes as f64);
        put("contact_rows_active", s.chi.iter().filter(|c| **c > 0.0).count() as f64);
        put("return_mappings", c.return_mappings as f64);
        put("inner_converged", inner_solved as u8 as f64);
        put("inner_gradient_relative", s.grad_rel);
        put("newton_decrement_relative", s.decrement_rel);
        put("approximation_limit", (stop == StopReason::ApproximationLimit) as u8 as f64);
        let State { u, v, chi, stress, it, .. } = self.state;
        let report = SolveReport {
            solver: "penalty".into(),
            converged,
            stop_reason: stop,
            iterations: it,
            tolerance: self.settings.tol,
            kkt,
            residual_history: self.history,
            phases: timer.into_phases(),
            counters,
            warnings: Vec::new(),
        };
        Solution { u, extras: v, stress, lambda: chi, report, undetermined: Vec::new() }
    }
}

fn non_finite(what: &str, iteration: usize) -> SolveError {
    SolveError::NonFinite { solver: "penalty".into(), what: what.into(), iteration }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// out = x + α d.
fn axpy_into(out: &mut [f64], x: &[f64], alpha: f64, d: &[f64]) {
    for ((o, a), b) in out.iter_mut().zip(x).zip(d) {
        *o = a + alpha * b;
    }
}

/// out = (1 − α) x + α y: the gaps along a step, exact at both ends.
fn blend(out: &mut [f64], x: &[f64], alpha: f64, y: &[f64]) {
    for ((o, a), b) in out.iter_mut().zip(x).zip(y) {
        *o = (1.0 - alpha) * a + alpha * b;
    }
}

/// x += α d.
fn axpy(x: &mut [f64], alpha: f64, d: &[f64]) {
    for (a, b) in x.iter_mut().zip(d) {
        *a += alpha * b;
    }
}
