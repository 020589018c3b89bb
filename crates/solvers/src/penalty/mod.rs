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
//! factorisations on it; a sweep of the contact model whose rows only enter A is solved on the
//! last factor by the Woodbury identity (`update.rs`). The extras are coupled through an
//! n_extras × n_extras Schur complement from one solve with 1 + n_extras right-hand sides, formed
//! without the catastrophic cancellation of the textbook `C − BᵀA⁻¹B` ([`PenaltySystem`]).
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
//! # Friction
//!
//! A node's tangential pair (theory §8.3) carries the Moreau–Yosida regularisation φ_k of its
//! friction term r|s| with the pair's penalty stiffness k (`friction.rs`): the force
//! χ_t = P_D(−k s), its generalised Hessian in the Newton system as a 2 × 2 block on the pair's
//! coordinates (it adds to D_A and to the extras' Schur complement). The model step keeps it as
//! its Taylor model, except that a slipping pair whose step reverses its slip is bonded in the
//! next sweep (the exact stick quadratic): the Taylor model has no curvature along the slip, and
//! without this the steps of the nodes that stick at the solution overshoot and the line search
//! stalls (measured on the partial-slip scene: 50 iterations at a relative gradient of 2e-3;
//! with it, 7). Coulomb's discs are those of the iterate's χ_n (`friction.rs`).
//!
//! # Honesty
//!
//! The penalty solves a regularised problem: its error against the solution of (2.1) is O(μ)
//! (penetration χ/k, the load carried by the regularisation, the stiffening μK_el). The report
//! therefore carries the residual of the *true* problem: `kkt` = [`kkt`](saddle_core::problem::kkt::kkt) on
//! (u, V, σ(u), χ), `tol` is a tolerance on that residual, and a solve whose inner problem is
//! solved but whose penalty error exceeds `tol` returns its solution with `converged = false`,
//! [`StopReason::ApproximationLimit`](saddle_core::problem::solver::StopReason::ApproximationLimit) and the counter `approximation_limit = 1`. The counters
//! carry the penalty's own error indicators: `max_penetration` (max g⁻, absolute and relative to
//! the displacement scale), `load_defect` = ‖f + Hᵀχ‖ (|Σχ − F| for the punch; absolute and
//! relative to ‖f‖), `mu`, and `condition_estimate` (see [`PenaltySystem`]).
//!
//! On a distributed problem (theory §12.4) the u-block is solved by the operators' distributed
//! solver instead of the factorisation, K' applied through the operators, and every sum, norm
//! and decision above is reduced over the ranks.
//!
//! # Files
//!
//! This file holds the settings ([`Penalty`], every tuning constant) and the solver's entry
//! points; `system.rs` the Newton system ([`PenaltySystem`]: the penalty scales, J_μ, the
//! step of the contact model); `update.rs` the sweeps solved on the last factor; `iteration.rs`
//! the loop in its stages and the honest report.

mod friction;
mod iteration;
mod system;
mod update;

pub use system::PenaltySystem;

use crate::warm_start::warm_solve;
use saddle_core::error::{ParameterError, check};
use saddle_core::problem::lagrangian::Lagrangian;
use saddle_core::problem::solver::{Monitor, Solution, SolveError, Solver, Start};
use serde::{Deserialize, Serialize};

/// The default of `gradient_tol`: the inner problem is solved when ‖∇J_μ‖ falls below this
/// fraction of the size of its terms. Its terms are sums over thousands of elements, each known
/// to ε_mach of its size: 1e-12 (≈ 5000 ε_mach) is the round-off level, J_μ is then minimised to
/// machine precision.
pub const GRADIENT_TOL: f64 = 1e-12;
/// The default of `step_tol`: ... or when the Newton step falls below this fraction of the
/// displacement scale, a few hundred ulps of u: further steps would only move u in its
/// round-off.
pub const STEP_TOL: f64 = 1e-13;
/// The default of `update_share`: entering rows are solved on the last factor while their solve
/// pairs cost at most this share of a factorisation's multiply–adds. A solve pair streams the
/// factor from memory while a factorisation runs dense blocks several times faster per
/// multiply–add, hence a share well below 1: on the 56 896-dof P2 strip (r ≤ 18 rows) 18 of the
/// 38 re-sweeps of a cold solve are updates, 73 rows in all, and the solve's CPU time falls by
/// 8 % (`docs/plastic_tangent.md`).
pub const UPDATE_SHARE: f64 = 0.1;
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

/// The share of the loads' work taken by the regularisation beyond which the load exceeds what
/// the body can carry (theory §4.6), at least. A carried load leaves the regularisation about μ
/// times (displacement / elastic displacement) of it, while beyond collapse the share tends to
/// 1 − F_lim/F whatever μ: 1e-3 flags loads more than 0.1 % above the limit.
pub const COLLAPSE_SHARE: f64 = 1e-3;

/// ... and at least this multiple of μ: a carried load would need a displacement this many
/// times the elastic one to reach it (at μ = 1e-3, hardening h = 5, the default scene's share
/// is 5μ).
pub const COLLAPSE_SHARE_PER_MU: f64 = 1e3;

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
    /// A sweep of the contact model whose rows only enter A is solved on the last factor by
    /// the Woodbury identity (theory §4.3, `update.rs`) when its r entering rows cost at most
    /// this share of a factorisation: r solve pairs of 2 `nnz_l` multiply–adds against the
    /// factor's `factor_flops`. 0: every sweep factorised. Default [`UPDATE_SHARE`].
    pub update_share: f64,
}

impl Default for Penalty {
    fn default() -> Self {
        Self {
            mu: 1e-12,
            tol: 1e-8,
            max_iter: 50,
            gradient_tol: GRADIENT_TOL,
            step_tol: STEP_TOL,
            update_share: UPDATE_SHARE,
        }
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
        check::non_negative(path, "update_share", self.update_share)?;
        Ok(())
    }

    fn tolerance(&self) -> f64 {
        self.tol
    }

    /// Newton on J_μ with its systems through the distributed solver, its sums and decisions
    /// over the ranks (theory §12.4).
    fn runs_distributed(&self) -> bool {
        true
    }

    fn solve(&self, l: &Lagrangian<'_>, monitor: &mut dyn Monitor) -> Result<Solution, SolveError> {
        self.newton(l, None, monitor)
    }

    /// Newton on J_μ from the previous step's (u, V), without the elastic iteration (theory
    /// §11.2).
    fn solve_warm(&self, l: &Lagrangian<'_>, start: &Start, monitor: &mut dyn Monitor) -> Result<Solution, SolveError> {
        warm_solve(l, start, "penalty", || self.newton(l, Some(start), monitor))
    }
}

/// A non-finite `what` at iteration `iteration`: an error of this solver.
fn non_finite(what: &str, iteration: usize) -> SolveError {
    SolveError::NonFinite { solver: "penalty".into(), what: what.into(), iteration }
}
