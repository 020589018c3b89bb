//! Semismooth Newton with a primal–dual active set (theory §4.2, beyond the paper; deal.II's
//! step-42 is the classic relative).
//!
//! Newton on the primal form min J(u, V) = Σ_T |T| ψ(ε_T(u)) − f·V over K_h (theory §3.3, form 1), in
//! named stages (one method of the private `Run` each):
//!
//! 0. **start** (`Run::set_up`): from a cold start, first the *elastic* contact problem, solved
//!    exactly with one factorisation of the elastic stiffness K: the projection of K⁻¹f onto K_h
//!    in the energy metric (Uzawa's step 2 of theory §4.1, see `elastic_contact_start`).
//!    Plasticity is then switched on. (Plastic steps from the first touching node alone push it
//!    through the body and drive everything plastic.) Should that projection be unavailable
//!    (dependent rows, or the AMG backend), the elastic problem is solved by full active-set
//!    steps with the elastic tangent from every candidate row active until the active set
//!    settles, a step changing at most `elastic_phase_settled` of its rows (the *elastic
//!    phase*, its solves to `cg_forcing`);
//!    A warm start from the previous load step (`Solver::solve_warm`, theory §11.2) takes the
//!    linear backend's set-up that step kept ([`SetupCache`]) when the problem's pattern,
//!    elastic stiffness and rows are the same, and starts from the step's (u, V, λ);
//! 1. **local law** (`Run::local_law`): the local law with its consistent tangent at every
//!    element (theory §2.5) and the KKT residual of the iterate (theory §3.4);
//! 2. **convergence** (`Newton::stop`): stop on the relative KKT residual (theory §4.5);
//! 3. **active set** (`Run::update_active_set`): A = {i : λ_i − c_i g_i > 0} (c_i: the
//!    elastic stiffness at the row's dof, so that forces and gaps are compared in the units of
//!    the problem);
//! 4. **assembly** (`Run::assemble`): the tangent and the gradient of J;
//! 5. **solve** (`Run::solve`): the linearised problem for A ([`ActiveSetSystem`]): one numeric
//!    factorisation on the pattern analysed once, or CG to the forcing term, with 1 + n_extras
//!    right-hand sides;
//! 6. **line search** (`Run::line_search`): a backtracking (Armijo) line search on J plus
//!    ν Σ_{i∈A} |g_i|, the violation of the active rows that the Newton step removes; rows that a
//!    step drives into the obstacle join A at the next iteration instead of blocking the step.
//!    Once the active rows touch, it is a line search on J alone;
//! 7. **update** (`Run::advance`).
//!
//! **Globalisation** (theory §4.2.1): when the KKT residual has not halved for `stall_window`
//! iterations (an active set that cycles), or a step fails for its active set (no active row
//! holds a loaded extra, a singular tangent), a bounded run of the penalty method
//! (`Run::fall_back`, at most `max_fallbacks` times) gives the next iterate, and Newton goes on
//! from it.
//!
//! Once the active set and the plastic set settle, convergence is quadratic.
//! [`Newton::solve_from`] starts from another solver's iterate (SOCP polishing).

use crate::active_set::{
    AUTO_AMG_DOFS, ActiveSetSystem, LinearSolver, Step, active_set_with_friction, analysis_due, direct_budget,
    direct_is_cheaper, primal_dual_update, touch_loaded_extras, touch_loaded_extras_with_friction,
};
use crate::distributed_system::DistributedSystem;
use crate::fallback::{FallbackLinearAlgebra, StallGuard, caused_by_the_active_set, robust_steps};
use crate::forcing::{ForcingRule, ForcingTerms};
use crate::kh_projection::MetricProjection;
use crate::linear::InSolver;
use crate::local_law::{IterateMut, local_law_and_residual};
use crate::penalty::Penalty;
use crate::pressure_block::{BlockResidual, BlockRule};
use crate::residual::History;
use crate::row_basis::RowBasis;
use crate::vector::{axpy, axpy_into};
use crate::warm_start::warm_solve;
use saddle_core::error::{ParameterError, check, join};
use saddle_core::linalg::error::LinalgError;
use saddle_core::linalg::{AmgParams, SparseCholesky};
use saddle_core::problem::energies::energy;
use saddle_core::problem::fields::StressField;
use saddle_core::problem::kkt::{KktResiduals, locked_in_forces, max_abs};
use saddle_core::problem::lagrangian::{Lagrangian, Workspace};
pub use saddle_core::problem::solver::Start;
use saddle_core::problem::solver::{Monitor, PhaseTimer, Solution, SolveError, Solver, StopReason};
use saddle_core::{Material, Sym, SymOp};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

/// `type = "newton"`: semismooth Newton with a primal–dual active set (theory §4.2).
///
/// Every field has a default, so a scene names only what it changes; the settings of the
/// iterative backend (`auto_amg_dofs`, `cg_forcing`, `cg_max_iter`, `[solver.amg]`) matter only
/// when it is chosen. The line search's constants are [`ARMIJO`], [`MAX_HALVINGS`] and
/// [`NU_FACTOR`]; the CG tolerances' floors [`CG_TOL_FLOOR`] and [`CG_TOL_MIN`].
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
    /// with the elastic multigrid, inexact Newton) or `auto` (by estimated cost from the
    /// symbolic analysis, [`direct_is_cheaper`]; AMG above `auto_amg_dofs` free dofs).
    pub linear: LinearSolver,
    /// `linear = "auto"` picks AMG without analysing above this many free dofs (default
    /// [`AUTO_AMG_DOFS`]) times the multigrid's slow-down as ν → ½
    /// ([`crate::active_set::incompressibility_factor`]); below, the cost rule decides.
    pub auto_amg_dofs: usize,
    /// The forcing term of inexact Newton with AMG (theory §4.2): each CG solve stops at the
    /// relative residual `cg_forcing · min(r, 1)`, r the current KKT residual (floored at
    /// [`CG_TOL_FLOOR`]). 1e-2 keeps the outer convergence quadratic to the end on the default
    /// scene while the first steps, far from the solution, cost few CG iterations.
    pub cg_forcing: f64,
    /// How the forcing term follows Newton's progress (theory §4.2, [`ForcingRule`]):
    /// `residual` (default, `cg_forcing · min(r, 1)`) or `eisenstat_walker` (η_max =
    /// `cg_forcing`; fewer CG iterations on some scenes, more on others:
    /// `docs/plastic_tangent.md`).
    pub forcing: ForcingRule,
    /// While the KKT residual falls by less than this factor per step (r_k > `slow_contraction`
    /// · r_{k−1}: the active or plastic set still changing, Newton's fast phase not begun), each
    /// CG solve stops at `cg_forcing` whatever the rule: the outer residual is then limited by
    /// the sets, not by the linear solve (theory §4.2, forcing terms). Once r falls faster, the
    /// rule's term applies, so the last steps' tolerances are the rule's. 0: the rule throughout.
    pub slow_contraction: f64,
    /// In the fast phase, a step whose quadratic model of the next residual, r_k (r_k /
    /// r_{k−1})², lies above `last_step_margin` · `tol` is not the last: its CG solve stops at
    /// Eisenstat–Walker's γ (r_k / r_{k−1})² where that is looser than the rule's term (theory
    /// §4.2, forcing terms); a step that may be the last keeps the rule's term, so the answer's
    /// last digits are the rule's. 0: the rule in every fast step.
    pub last_step_margin: f64,
    /// CG iterations per solve before giving up on the forcing term (the last iterate is used
    /// and counted in `pcg_unconverged`). On the default scene a solve takes about ten (README:
    /// 263 for 12 Newton steps of two solves each): 2000 is a safety net, not a working limit.
    pub cg_max_iter: usize,
    /// The smoothed-aggregation multigrid of `linear = "amg"` (`[solver.amg]`: fields
    /// `strength_threshold`, `smoother_degree`, `smoother_range`, `eigen_steps`, `coarse_size`,
    /// `max_levels`; defaults those of [`AmgParams`]).
    pub amg: AmgParams,
    /// The elastic phase ends once a step changes at most this fraction of the active rows
    /// (theory §4.2, elastic start; 0: only once A no longer changes): the plastic steps that
    /// follow move A as well, and the elastic phase's last steps, which change a few rows at the
    /// contact's edge, cost a full solve each.
    pub elastic_phase_settled: f64,
    /// The multigrid follows the tangent (theory §4.2): when a CG solve took more than this
    /// many iterations, the next one's hierarchy is rebuilt on the current tangent, its
    /// aggregates kept (0: every step; a large number: never, the elastic hierarchy throughout).
    /// The elastic hierarchy takes 20–30 iterations on elastic tangents (module docs of
    /// `amg`); on a perfectly plastic P2 strip punch (56 896 dofs, h = 0) it took 216 per solve,
    /// the refreshed one 71 with this default (`docs/plastic_tangent.md`).
    pub amg_refresh_cg: usize,
    /// The pressure block (theory §10.1): with the multigrid, an element that offers pressure
    /// rows (B̄) and an elastic κ/(2μ) above this ratio, each system K x = b is solved as the
    /// saddle system [A Bᵀ; B −C] by MINRES with the multigrid of A (λ = 0 elasticity for an elastic point) and a
    /// diagonal pressure block, whose iterations do not grow as ν → ½ (they are counted in
    /// `pcg_iterations`, the solves in `pressure_block_solves`). Default
    /// [`PRESSURE_BLOCK_RATIO`]; a huge value (1e300): never.
    pub pressure_block_ratio: f64,
    /// Where the pressure block's MINRES stops (theory §10.1): `saddle` (default; its own
    /// residual ‖r‖_{𝓜⁻¹} of the saddle system at the forcing term) or `displacement` (CG's
    /// ‖b − K x‖ / ‖b‖, in which the pressure equation's residual counts λ/|T| times over).
    pub pressure_block_residual: BlockResidual,
    /// Iterations without the KKT residual falling below half its best before Newton is
    /// declared stalled and falls back on the penalty method (theory §4.2.1; 0: never).
    /// Newton near the solution gains orders of magnitude per step: 8 steps without halving
    /// the residual mean an active set that cycles.
    pub stall_window: usize,
    /// Fallbacks on the penalty method per solve (theory §4.2.1; 0: none).
    pub max_fallbacks: usize,
    /// Penalty iterations per fallback: 400, since a perfectly plastic Tresca P2 punch needs
    /// 53–172 of them (theory §10.3); a hopeless one stops earlier on its collapse check (§4.6).
    pub fallback_max_iter: usize,
    /// The linear system's set-up kept between the warm-started solves of a load path
    /// ([`SetupCache`]); not a setting.
    #[serde(skip)]
    pub setup_cache: SetupCache,
}

/// The set-up of Newton's linear systems — the backend chosen, the symbolic analysis or the
/// multigrid hierarchy of the elastic stiffness, the rows' coordinates and stiffnesses — kept
/// between the warm-started solves of a load path (theory §11.2), whose steps share L's
/// operators and rows and differ only in loads and state. It is reused only when the next
/// problem has the same pattern, the same elastic stiffness (compared by a hash of its values)
/// and the same rows G, H; otherwise it is rebuilt. On the 45k-dof indentation the set-up is
/// ≈ 0.27 s of a warm step's ≈ 0.5 s solve. Clones of a Newton share the cache.
#[derive(Clone, Default)]
pub struct SetupCache(Arc<Mutex<Option<CachedSetup>>>);

impl std::fmt::Debug for SetupCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let held = self.0.lock().map(|c| c.is_some()).unwrap_or(false);
        write!(f, "SetupCache({})", if held { "held" } else { "empty" })
    }
}

impl SetupCache {
    /// The kept set-up, if it was built for `key` (it leaves the cache either way).
    fn take(&self, key: &SetupKey) -> Option<CachedSetup> {
        let mut held = self.0.lock().unwrap_or_else(|e| e.into_inner());
        held.take().filter(|c| &c.key == key)
    }

    /// Keeps `setup` for the next warm solve.
    fn keep(&self, setup: CachedSetup) {
        *self.0.lock().unwrap_or_else(|e| e.into_inner()) = Some(setup);
    }
}

/// A kept set-up and what it was built for.
struct CachedSetup {
    key: SetupKey,
    system: ActiveSetSystem,
    row_stiffness: Vec<f64>,
    cost_estimates: Option<(f64, f64)>,
}

/// What a set-up depends on: the dofs, the pattern, the elastic stiffness's values, the rows.
#[derive(Clone, Debug, PartialEq)]
struct SetupKey {
    n_dofs: usize,
    pattern: u64,
    stiffness: u64,
    rows: (Vec<usize>, Vec<usize>, Vec<u64>, Vec<u64>),
}

impl SetupKey {
    /// The key of `l`, from its assembled elastic stiffness `k_el`.
    fn new(l: &Lagrangian<'_>, k_el: &[f64]) -> Self {
        use std::hash::{Hash, Hasher};
        let hash = |f: &mut dyn FnMut(&mut std::collections::hash_map::DefaultHasher)| {
            let mut h = std::collections::hash_map::DefaultHasher::new();
            f(&mut h);
            h.finish()
        };
        let p = l.pattern();
        let rows = l.data.rows;
        Self {
            n_dofs: l.n_dofs(),
            pattern: hash(&mut |h| {
                p.col_ptr().hash(h);
                p.row_idx().hash(h);
            }),
            stiffness: hash(&mut |h| k_el.iter().for_each(|v| v.to_bits().hash(h))),
            rows: (
                rows.row_ptr.clone(),
                rows.col.clone(),
                rows.val.iter().map(|v| v.to_bits()).collect(),
                rows.extra.iter().map(|v| v.to_bits()).collect(),
            ),
        }
    }
}

impl Default for Newton {
    fn default() -> Self {
        Self {
            tol: 1e-10,
            max_iter: 50,
            line_search: true,
            linear: LinearSolver::Auto,
            auto_amg_dofs: AUTO_AMG_DOFS,
            cg_forcing: 1e-2,
            forcing: ForcingRule::default(),
            slow_contraction: SLOW_CONTRACTION,
            last_step_margin: LAST_STEP_MARGIN,
            cg_max_iter: 2000,
            amg: AmgParams::default(),
            amg_refresh_cg: AMG_REFRESH_CG,
            pressure_block_ratio: PRESSURE_BLOCK_RATIO,
            pressure_block_residual: BlockResidual::Saddle,
            elastic_phase_settled: ELASTIC_PHASE_SETTLED,
            stall_window: 8,
            max_fallbacks: 2,
            fallback_max_iter: 400,
            setup_cache: SetupCache::default(),
        }
    }
}

pub use crate::armijo::{ARMIJO, SLOPE_ROUND_OFF};
pub use crate::forcing::{LAST_STEP_MARGIN, SLOW_CONTRACTION};

/// The default of `elastic_phase_settled`.
pub const ELASTIC_PHASE_SETTLED: f64 = 0.05;

/// The default of `pressure_block_ratio`: κ/(2μ) = (1 + ν)/(3(1 − 2ν)) = 10 at ν ≈ 0.475
/// (`docs/plastic_tangent.md`, "The pressure block").
pub const PRESSURE_BLOCK_RATIO: f64 = 10.0;

/// The default of `amg_refresh_cg`: above the 20–30 iterations the elastic hierarchy takes on
/// elastic tangents, so that only tangents it no longer approximates trigger a rebuild.
pub const AMG_REFRESH_CG: usize = 40;
/// Steps of the elastic phase (full steps with the elastic tangent while the contact set
/// settles) before it ends anyway and the line search takes over. The punch settles in 2–4;
/// with several obstacles at the same nodes (theory §8) undamped active-set steps can cycle,
/// and 10 steps without settling means they do.
pub const ELASTIC_PHASE_MAX_STEPS: usize = 10;

/// Halvings of the step before the line search gives up and takes the last one: 2⁻⁴⁰ ≈ 1e-12
/// is below any step that changes J measurably.
pub const MAX_HALVINGS: usize = 40;

/// The merit weight ν of the line search is at least this multiple of max|λ| (theory §4.2
/// step 4): an exact penalty of the active rows' violation needs ν > max|λ|; the factor 2 is
/// the margin.
pub const NU_FACTOR: f64 = 2.0;

/// The floor of the inexact-Newton CG tolerance (theory §4.2): the forcing term would ask for
/// ever smaller residuals near the solution, but CG's relative residual stalls near the
/// round-off of its matrix–vector products; 1e-13 stays above that and still makes the final
/// steps three orders more accurate than Newton's default `tol` = 1e-10.
pub const CG_TOL_FLOOR: f64 = 1e-13;

/// A linear problem (no plasticity, no contact) is solved in one step with CG to this fraction
/// of `tol`, so that its recomputed KKT residual meets `tol` with a margin …
pub const LINEAR_CG_MARGIN: f64 = 0.1;

/// … but never below [`CG_TOL_MIN`], the round-off limit of CG in double precision.
pub use crate::active_set::CG_TOL_MIN;

#[typetag::serde(name = "newton")]
impl Solver for Newton {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::open_interval(path, "tol", self.tol, 0.0, 1.0)?;
        check::at_least_one(path, "max_iter", self.max_iter)?;
        check::open_interval(path, "cg_forcing", self.cg_forcing, 0.0, 1.0)?;
        check::non_negative(path, "slow_contraction", self.slow_contraction)?;
        check::non_negative(path, "last_step_margin", self.last_step_margin)?;
        check::non_negative(path, "elastic_phase_settled", self.elastic_phase_settled)?;
        check::at_least_one(path, "cg_max_iter", self.cg_max_iter)?;
        check::at_least_one(path, "fallback_max_iter", self.fallback_max_iter)?;
        check::non_negative(path, "pressure_block_ratio", self.pressure_block_ratio)?;
        // AmgParams names its fields `amg.<field>`: under this table's path
        self.amg.validate().map_err(|e| ParameterError { field: join(path, &e.field), ..e })?;
        Ok(())
    }

    fn tolerance(&self) -> f64 {
        self.tol
    }

    /// Every stage's decision is taken from sums over the ranks (theory §12).
    fn runs_distributed(&self) -> bool {
        true
    }

    fn solve(&self, l: &Lagrangian<'_>, monitor: &mut dyn Monitor) -> Result<Solution, SolveError> {
        self.solve_from(l, None, monitor, &mut PhaseTimer::default(), "newton")
    }

    /// Newton from the previous step's (u, V, λ): its active set and plastic set are the
    /// first guesses (theory §11.2).
    fn solve_warm(&self, l: &Lagrangian<'_>, start: &Start, monitor: &mut dyn Monitor) -> Result<Solution, SolveError> {
        warm_solve(l, start, "newton", || {
            self.iterate(l, Some(start.clone()), true, monitor, &mut PhaseTimer::default(), "newton")
        })
    }
}

impl Newton {
    /// Newton from `start` (zero if `None`); phases are added to `timer` and the report carries
    /// the solver name `name`.
    pub fn solve_from(
        &self,
        l: &Lagrangian<'_>,
        start: Option<Start>,
        monitor: &mut dyn Monitor,
        timer: &mut PhaseTimer,
        name: &str,
    ) -> Result<Solution, SolveError> {
        self.iterate(l, start, false, monitor, timer, name)
    }

    /// The iteration of [`Newton::solve_from`]; with `reuse` the set-up is taken from and kept
    /// in the [`SetupCache`].
    fn iterate(
        &self,
        l: &Lagrangian<'_>,
        start: Option<Start>,
        reuse: bool,
        monitor: &mut dyn Monitor,
        timer: &mut PhaseTimer,
        name: &str,
    ) -> Result<Solution, SolveError> {
        if l.is_distributed() {
            crate::friction::refuse_friction(l.data.rows, &format!("{name} (distributed, theory §12.2)"))?;
        }
        let robust_start = start.clone();
        let mut run = Run::set_up(self, l, start, reuse, name, monitor, timer)?;
        let mut guard = StallGuard::new(self.stall_window);
        monitor.phase("iterations");
        let (stop, kkt) = loop {
            let kkt = run.local_law(timer);
            let r = kkt.max();
            run.history.record(run.state.it, r, monitor)?;
            if let Some(stop) = self.stop(r, run.state.it) {
                break (stop, kkt);
            }
            if run.state.elastic_phase {
                guard.reset();
            } else if guard.stalled(r, run.state.it)
                && run.can_fall_back()
                && run.fall_back(robust_start.as_ref(), monitor, timer)?
            {
                guard.reset();
                continue;
            }
            run.update_active_set();
            run.assemble(timer);
            let step = match run.solve(r, timer) {
                Ok(step) => step,
                Err(e) if caused_by_the_active_set(&e) && run.can_fall_back() => {
                    if !run.fall_back(robust_start.as_ref(), monitor, timer)? {
                        return Err(run.collapse_or(e));
                    }
                    guard.reset();
                    continue;
                }
                Err(e) => return Err(run.collapse_or(e)),
            };
            let alpha = run.line_search(&step, timer);
            run.advance(&step, alpha);
        };
        Ok(run.finish(stop, kkt, timer))
    }

    /// Stage 2 (theory §4.5): converged when the relative KKT residual `r` meets `tol`, else
    /// out of budget after `max_iter` iterations, else `None` (go on).
    fn stop(&self, r: f64, it: usize) -> Option<StopReason> {
        if r <= self.tol {
            Some(StopReason::Converged)
        } else if it >= self.max_iter {
            Some(StopReason::MaxIterations)
        } else {
            None
        }
    }

    /// The forcing terms of a solve (theory §4.2).
    fn forcing_terms(&self) -> ForcingTerms {
        ForcingTerms::new(self.forcing, self.cg_forcing, self.tol)
            .slow_below(self.slow_contraction)
            .relaxed_before_the_last(self.last_step_margin)
    }

    /// The CG tolerance of the step from an iterate with KKT residual `r` (theory §4.2, linear
    /// backends): the forcing term of `forcing`, or a margin below `tol` for a linear problem.
    fn cg_tol(&self, forcing: &mut ForcingTerms, r: f64, linear_problem: bool) -> f64 {
        if linear_problem { (LINEAR_CG_MARGIN * self.tol).max(CG_TOL_MIN) } else { forcing.next(r).max(CG_TOL_FLOOR) }
    }
}

/// The iteration state of Newton (theory §4.2): the iterate and what the method carries from
/// one iteration to the next.
struct State {
    /// u.
    u: Vec<f64>,
    /// V.
    v: Vec<f64>,
    /// λ.
    lambda: Vec<f64>,
    /// σ̂ = P_D(Cε(u), 0), from the last local law.
    stress: StressField,
    /// The active set A.
    active: Vec<bool>,
    /// Iterations done.
    it: usize,
    /// The weight ν of the merit function J + ν Σ_A |g_i| (non-decreasing).
    nu: f64,
    /// In the elastic phase: the elastic tangent and full steps until A settles.
    elastic_phase: bool,
}

/// What a Newton run counts for its report.
#[derive(Default)]
struct Counts {
    /// The cost rule of `linear = "auto"`: the direct and the multigrid estimates.
    cost_estimates: Option<(f64, f64)>,
    /// Halvings of the line search.
    backtracks: usize,
    /// Rows that entered or left A.
    active_changes: usize,
    /// Points at which P's return mapping ran, as the local law reports them.
    return_mappings: usize,
    /// Iterations of the elastic phase.
    elastic_phase_steps: usize,
    /// Triangular solve pairs of the exact elastic start (0 without it).
    elastic_contact_solves: usize,
    /// The set-up was the previous warm solve's (a load path).
    setup_reused: bool,
    /// Fallbacks on the penalty method (theory §4.2.1).
    fallbacks: usize,
    /// The penalty method's iterations in them.
    fallback_iterations: usize,
    /// ... and their linear algebra.
    fallback_linear: FallbackLinearAlgebra,
}

/// Scratch of the stages, allocated once per solve.
struct Scratch {
    ws: Workspace,
    /// Consistent tangents per point.
    tangents: Vec<SymOp>,
    /// The tangent stiffness on L's pattern.
    k: Vec<f64>,
    /// The elements whose tangent in `k` is not the elastic C (empty: `k` not assembled yet):
    /// the next assembly recomputes only the columns these and the newly plastic elements touch
    /// ([`saddle_core::ElementOperators::reassemble`]); the elastic phase's steps reuse `k`.
    k_off: Vec<bool>,
    /// ∇J(u) (the elastic one in the elastic phase).
    grad: Vec<f64>,
    /// g(u, V).
    gap: Vec<f64>,
    /// The line search's trial point and its gaps.
    u_trial: Vec<f64>,
    v_trial: Vec<f64>,
    g_trial: Vec<f64>,
    /// Cε in the elastic phase (empty without one).
    elastic_sigma: Vec<Sym>,
}

impl Scratch {
    /// `k` := the elastic stiffness (the columns that plastic elements touched re-assembled).
    fn assemble_elastic(&mut self, l: &Lagrangian<'_>, c: &SymOp) {
        l.reassemble(Material::Uniform(c), c, &mut self.k_off, &mut self.k);
    }
}

/// One Newton solve: what it reads, its linear system, state, counters and scratch.
struct Run<'a> {
    settings: &'a Newton,
    l: &'a Lagrangian<'a>,
    name: &'a str,
    system: Systems,
    /// The elastic stiffness C.
    c_elastic: SymOp,
    /// c_i of the active-set test (theory §4.2 step 2): the elastic stiffness at row i's dof.
    row_stiffness: Vec<f64>,
    /// With a warm start: what the set-up was built for; `finish` keeps it in the cache.
    key: Option<SetupKey>,
    /// No start was given and no exact elastic start was found: every candidate row starts
    /// active.
    cold: bool,
    state: State,
    count: Counts,
    work: Scratch,
    /// The KKT residual of every iterate.
    history: History,
    /// The forcing terms of the linear solves (theory §4.2).
    forcing: ForcingTerms,
}

/// Newton's linear systems: on one process the direct or multigrid backend, on a distributed
/// problem the operators' distributed solver (theory §12).
enum Systems {
    Serial(ActiveSetSystem),
    Distributed(DistributedSystem),
}

impl Systems {
    /// The rows' coordinates (theory §8.1).
    fn basis(&self) -> &RowBasis {
        match self {
            Systems::Serial(s) => s.basis(),
            Systems::Distributed(d) => d.basis(),
        }
    }

    /// The serial system, if that is the one.
    fn serial(&mut self) -> Option<&mut ActiveSetSystem> {
        match self {
            Systems::Serial(s) => Some(s),
            Systems::Distributed(_) => None,
        }
    }
}

impl<'a> Run<'a> {
    /// Stage 0 (theory §4.2, elastic start): the linear backend (symbolic analysis or multigrid
    /// set-up), the exact elastic start from a cold start with the direct backend, the state
    /// and the scratch.
    fn set_up(
        settings: &'a Newton,
        l: &'a Lagrangian<'a>,
        start: Option<Start>,
        reuse: bool,
        name: &'a str,
        monitor: &mut dyn Monitor,
        timer: &mut PhaseTimer,
    ) -> Result<Self, SolveError> {
        let nr = l.data.rows.n_rows();
        monitor.phase("analysis");
        let mut count = Counts::default();
        let c_elastic = l.data.elasticity.stiffness_matrix();
        if l.is_distributed() {
            return Self::set_up_distributed(settings, l, start, name, count, timer);
        }
        // a warm start may take the set-up the previous step kept (a load path, theory §11.2)
        let (key, k_el, kept) = if reuse {
            let k_el = timer.time("assembly", || l.stiffness(Material::Uniform(&c_elastic)));
            let key = SetupKey::new(l, &k_el);
            let kept = settings.setup_cache.take(&key);
            (Some(key), Some(k_el), kept)
        } else {
            (None, None, None)
        };
        count.setup_reused = kept.is_some();
        let (mut system, row_stiffness) = match kept {
            Some(mut kept) => {
                kept.system.reset_counts();
                count.cost_estimates = kept.cost_estimates;
                (kept.system, kept.row_stiffness)
            }
            None => {
                let system = Self::backend(settings, l, name, &mut count, timer)?;
                // PDAS compares forces with gaps through each row's elastic stiffness
                // (force/length)
                let k_el = k_el.unwrap_or_else(|| l.stiffness(Material::Uniform(&c_elastic)));
                let row_stiffness = system.basis().row_stiffness(l.pattern(), &k_el);
                (system, row_stiffness)
            }
        };
        // (with the iterative backend the Delassus columns would cost a CG solve per row: the
        // elastic contact set is then found by the elastic phase)
        let mut elastic_start = None;
        if let Some(chol) = system.direct().filter(|_| start.is_none() && nr > 0) {
            monitor.phase("elastic contact");
            match timer.time("elastic contact", || elastic_contact_start(l, chol, name)) {
                Ok((s, solves)) => {
                    elastic_start = Some(s);
                    count.elastic_contact_solves = solves;
                }
                // dependent rows and the like: fall back on the elastic phase
                Err(SolveError::Unsupported { .. }) => {}
                Err(e) => return Err(e),
            }
        }
        let cold = start.is_none() && elastic_start.is_none();
        let (state, work) = Self::state_and_scratch(l, elastic_start.or(start), cold);
        Ok(Self {
            settings,
            l,
            name,
            system: Systems::Serial(system),
            c_elastic,
            row_stiffness,
            key,
            cold,
            state,
            count,
            work,
            history: History::new(name, settings.tol),
            forcing: settings.forcing_terms(),
        })
    }

    /// Stage 0 on a distributed problem (theory §12): the operators' distributed solver, and no
    /// exact elastic start (its Delassus columns would cost a solve per row): from a cold start
    /// the elastic phase finds the elastic contact set.
    fn set_up_distributed(
        settings: &'a Newton,
        l: &'a Lagrangian<'a>,
        start: Option<Start>,
        name: &'a str,
        count: Counts,
        timer: &mut PhaseTimer,
    ) -> Result<Self, SolveError> {
        let c_elastic = l.data.elasticity.stiffness_matrix();
        let mut system = timer.time("analysis", || DistributedSystem::new(l, name))?;
        let k_el = timer.time("assembly", || l.stiffness(Material::Uniform(&c_elastic)));
        let row_stiffness = system.row_stiffness(l, &k_el)?;
        let cold = start.is_none();
        let (state, work) = Self::state_and_scratch(l, start, cold);
        Ok(Self {
            settings,
            l,
            name,
            system: Systems::Distributed(system),
            c_elastic,
            row_stiffness,
            key: None,
            cold,
            state,
            count,
            work,
            history: History::new(name, settings.tol),
            forcing: settings.forcing_terms(),
        })
    }

    /// The state at `start` (zero without one; in the elastic phase from a `cold` start with
    /// plasticity) and the scratch of the stages.
    fn state_and_scratch(l: &Lagrangian<'_>, start: Option<Start>, cold: bool) -> (State, Scratch) {
        let nr = l.data.rows.n_rows();
        let (n, ne, np) = (l.n_dofs(), l.n_extras(), l.n_points());
        let Start { u, extras: v, lambda } =
            start.unwrap_or(Start { u: vec![0.0; n], extras: vec![0.0; ne], lambda: vec![0.0; nr] });
        let elastic_phase = cold && l.data.plasticity().is_some();
        let state = State {
            u,
            v,
            lambda,
            stress: StressField::new(np, l.data.hardening_dim()),
            active: vec![false; nr],
            it: 0,
            nu: 0.0,
            elastic_phase,
        };
        let work = Scratch {
            ws: Workspace::new(l),
            tangents: vec![SymOp::zeros(); np],
            k: vec![0.0; l.pattern().nnz()],
            k_off: Vec::new(),
            grad: vec![0.0; n],
            gap: vec![0.0; nr],
            u_trial: vec![0.0; n],
            v_trial: vec![0.0; ne],
            g_trial: vec![0.0; nr],
            elastic_sigma: vec![Sym::zeros(); if elastic_phase { np } else { 0 }],
        };
        (state, work)
    }

    /// The linear backend for `l` (theory §4.2): the multigrid, the symbolic analysis, or the
    /// cheaper of the two by the cost rule of `auto` (its estimates go to `count`).
    fn backend(
        settings: &Newton,
        l: &Lagrangian<'_>,
        name: &str,
        count: &mut Counts,
        timer: &mut PhaseTimer,
    ) -> Result<ActiveSetSystem, SolveError> {
        let nr = l.data.rows.n_rows();
        let nu = l.data.elasticity.poisson;
        let linear = settings.linear.resolve(l.n_dofs(), settings.auto_amg_dofs, nu);
        let multigrid = |timer: &mut PhaseTimer| {
            timer.time("multigrid set-up", || {
                ActiveSetSystem::multigrid_with(
                    l,
                    name,
                    &settings.amg,
                    settings.cg_max_iter,
                    settings.amg_refresh_cg,
                    BlockRule { ratio: settings.pressure_block_ratio, residual: settings.pressure_block_residual },
                )
            })
        };
        Ok(match linear {
            // `auto` above `auto_amg_dofs`: the analysis deferred until CG shows the tangent
            LinearSolver::Amg if settings.linear == LinearSolver::Auto && l.rigid_body_modes().is_some() => {
                let mut amg = multigrid(timer)?;
                amg.analyse_when_due(analysis_due(nu));
                amg
            }
            LinearSolver::Amg => multigrid(timer)?,
            LinearSolver::Direct => timer.time("analysis", || ActiveSetSystem::new(l, name))?,
            LinearSolver::Auto => {
                // the cost rule: the symbolic analysis gives the factor's fill and flops
                let mut direct = timer.time("analysis", || ActiveSetSystem::new(l, name))?;
                let chol = direct.direct().expect("the direct backend");
                let (cheaper, d, a) = direct_is_cheaper(chol, nr, l.pattern().nnz(), nu);
                count.cost_estimates = Some((d, a));
                // without nodal dofs (no rigid-body modes) there is no multigrid: stay direct
                if cheaper || l.rigid_body_modes().is_none() {
                    direct
                } else {
                    // the reserve: taken once CG on the tangent has spent the direct estimate
                    let mut amg = multigrid(timer)?;
                    amg.keep_in_reserve(direct, direct_budget(d, l.pattern().nnz()));
                    amg
                }
            }
        })
    }

    /// Stage 1 (theory §4.2 step 1): the local law with consistent tangents at every point
    /// (theory §2.5), then the KKT residuals of the iterate (theory §3.4); `ws.force` holds
    /// ∇J(u) without the contact forces afterwards.
    fn local_law(&mut self, timer: &mut PhaseTimer) -> KktResiduals {
        let (s, w) = (&mut self.state, &mut self.work);
        let it = IterateMut { u: &s.u, extras: &s.v, lambda: &s.lambda, stress: &mut s.stress };
        let (projected, kkt) = local_law_and_residual(self.l, it, Some(&mut w.tangents), &mut w.ws, timer);
        self.count.return_mappings += projected;
        kkt
    }

    /// Stage 3 (theory §4.2 step 2): the active set A = {i : λ_i − c_i g_i > 0} (every row at a
    /// cold start), a touching row for every loaded extra, and the end of the elastic phase
    /// once A has settled.
    fn update_active_set(&mut self) {
        let (l, s, w) = (self.l, &mut self.state, &mut self.work);
        let rows = l.data.rows;
        rows.gap(&s.u, &s.v, &mut w.gap);
        // cold start: every candidate row active (the punch imprints its shape), tensile rows
        // are released at the next iteration — but of rows that share dofs (two obstacles at
        // one node, theory §8.1) only the closest: activating all of them would pin the node
        // to every obstacle at once
        let mut changed = if rows.has_friction() {
            // the normal rows by PDAS, the pairs by their natural residual (theory §8.3)
            let before = s.active.clone();
            let (cold, mut slips) = (self.cold && s.it == 0, Vec::new());
            let at = (&s.lambda[..], &w.gap[..], &self.row_stiffness[..]);
            active_set_with_friction(rows, self.system.basis(), at, cold, &mut s.active, &mut slips);
            touch_loaded_extras_with_friction(l, &mut s.active, &slips, &w.gap);
            if let Some(system) = self.system.serial() {
                system.slips = slips;
            }
            s.active.iter().zip(&before).filter(|(a, b)| a != b).count()
        } else if self.cold && s.it == 0 {
            let closest = self.system.basis().closest_in_blocks(&w.gap);
            let changed = closest.iter().zip(&s.active).filter(|(a, b)| a != b).count();
            s.active.copy_from_slice(&closest);
            changed
        } else {
            primal_dual_update(&s.lambda, &self.row_stiffness, &w.gap, &mut s.active)
        };
        if !rows.has_friction() {
            changed += touch_loaded_extras(l, &mut s.active, &w.gap);
        }
        let changed = l.comm().sum_count(changed);
        // the elastic phase ends once its active set has settled: the last step solved it
        let settled =
            changed as f64 <= self.settings.elastic_phase_settled * l.comm().sum_count(active_rows(&s.active)) as f64;
        if s.elastic_phase && s.it > 0 && (settled || s.it >= ELASTIC_PHASE_MAX_STEPS) {
            s.elastic_phase = false;
            self.count.elastic_phase_steps = s.it;
        }
        self.count.active_changes += changed;
    }

    /// Stage 4 (theory §4.2 step 3): the tangent K_t on L's pattern and the gradient ∇J(u) —
    /// the elastic ones in the elastic phase (K assembled once there: it does not change).
    fn assemble(&mut self, timer: &mut PhaseTimer) {
        let (l, c, w) = (self.l, &self.c_elastic, &mut self.work);
        if self.state.elastic_phase {
            timer.time("assembly", || {
                w.assemble_elastic(l, c);
                // C(ε − ε_p): the elastic response from the step's state (Cε without one)
                l.data.elastic_stress(&w.ws.eps, &mut w.elastic_sigma);
                l.divergence(&w.elastic_sigma, &mut w.grad);
                for (g, f) in w.grad.iter_mut().zip(l.data.nodal_load) {
                    *g -= f;
                }
            });
        } else {
            timer.time("assembly", || l.reassemble(Material::PerPoint(&w.tangents), c, &mut w.k_off, &mut w.k));
            w.grad.copy_from_slice(&w.ws.force);
        }
    }

    /// Stage 5 (theory §4.2 step 3, linear backends): the Newton step for A from an iterate
    /// with KKT residual `r` — exact with the direct backend, to the forcing term with CG.
    fn solve(&mut self, r: f64, timer: &mut PhaseTimer) -> Result<Step, SolveError> {
        let l = self.l;
        // a linear problem (no plasticity, no contact) is solved in one step to the tolerance
        let linear_problem = l.data.plasticity().is_none() && l.comm().sum_count(l.data.rows.n_rows()) == 0;
        let cg_tol = self.settings.cg_tol(&mut self.forcing, r, linear_problem);
        let (s, w) = (&self.state, &self.work);
        // the elastic phase's r is the plastic problem's: its solves stop at η_max
        let cg_tol = if s.elastic_phase && !linear_problem { self.settings.cg_forcing } else { cg_tol };
        let step = match &mut self.system {
            Systems::Serial(system) => {
                // the tangent of the stage's assembly: elastic in the elastic phase
                system.follow_material(if s.elastic_phase {
                    Material::Uniform(&self.c_elastic)
                } else {
                    Material::PerPoint(&w.tangents)
                });
                let phase = if system.iterative().is_some_and(|it| !it.switched) {
                    "CG solves"
                } else {
                    "factorisation and solves"
                };
                timer.time(phase, || system.step(l, &w.k, &s.active, &w.grad, &w.gap, cg_tol))?
            }
            Systems::Distributed(system) => {
                // the tangent of the stage's assembly: elastic in the elastic phase
                let material =
                    if s.elastic_phase { Material::Uniform(&self.c_elastic) } else { Material::PerPoint(&w.tangents) };
                timer
                    .time("distributed solves", || system.step(l, material, &w.k, &s.active, &w.grad, &w.gap, cg_tol))?
            }
        };
        if step.du.iter().chain(&step.dv).chain(&step.lambda).any(|x| !x.is_finite()) {
            return Err(SolveError::NonFinite {
                solver: self.name.into(),
                what: "the Newton step".into(),
                iteration: s.it,
            });
        }
        Ok(step)
    }

    /// Stage 6 (theory §4.2 step 4): the step length α — a backtracking Armijo line search on
    /// J + ν Σ_{i∈A} |g_i|; the full step in the elastic phase, with `line_search = false`, or
    /// when the predicted decrease is below the round-off of J.
    fn line_search(&mut self, step: &Step, timer: &mut PhaseTimer) -> f64 {
        let (l, s, w) = (self.l, &mut self.state, &mut self.work);
        let comm = l.comm();
        s.nu = s.nu.max(NU_FACTOR * comm.max(max_abs(&step.lambda)));
        // with friction the full semismooth step (J is not the merit of the friction conditions)
        if !self.settings.line_search || s.elastic_phase || l.data.rows.has_friction() {
            return 1.0;
        }
        let rows = l.data.rows;
        let (active, nu) = (&s.active, s.nu);
        // ℓ₁ violation of the *active* rows only: rows that a full step drives into the
        // obstacle join the active set at the next iteration (PDAS), they do not block
        let violation =
            |g: &[f64]| comm.sum((0..rows.n_rows()).filter(|&i| active[i]).map(|i| g[i].abs()).sum::<f64>());
        let backtracks = &mut self.count.backtracks;
        timer.time("line search", || {
            let j0 = energy(l, &s.u, &s.v, &mut w.ws) + nu * violation(&w.gap);
            let slope = comm.sum(w.grad.iter().zip(&step.du).map(|(a, b)| a * b).sum::<f64>())
                - l.data.load.iter().zip(&step.dv).map(|(a, b)| a * b).sum::<f64>()
                - nu * violation(&w.gap);
            let mut alpha = 1.0;
            // below round-off of J the test is noise: take the full step
            if slope.abs() <= SLOPE_ROUND_OFF * j0.abs().max(f64::MIN_POSITIVE) || slope >= 0.0 {
                return alpha;
            }
            for _ in 0..MAX_HALVINGS {
                axpy_into(&mut w.u_trial, &s.u, alpha, &step.du);
                axpy_into(&mut w.v_trial, &s.v, alpha, &step.dv);
                rows.gap(&w.u_trial, &w.v_trial, &mut w.g_trial);
                let j = energy(l, &w.u_trial, &w.v_trial, &mut w.ws) + nu * violation(&w.g_trial);
                if j <= j0 + ARMIJO * alpha * slope {
                    break;
                }
                alpha *= 0.5;
                *backtracks += 1;
            }
            alpha
        })
    }

    /// A fallback is possible: fewer than `max_fallbacks` so far (on a distributed problem too:
    /// the penalty method runs there, theory §12.4, and the stall and the step's failure that
    /// call for it are decided on reduced residuals and a collective solve, alike on every rank).
    fn can_fall_back(&self) -> bool {
        self.count.fallbacks < self.settings.max_fallbacks
    }

    /// The globalisation (theory §4.2.1): a bounded run of the penalty method from the solve's
    /// `start` gives the next iterate (u, V, λ), converged or not; Newton goes on from it with
    /// the active set its λ and gaps give. Counts as one iteration. False when the penalty
    /// method failed with an error (nothing to go on from; the fallback is counted all the same);
    /// its finding of a load beyond collapse (theory §4.6) is Newton's error.
    fn fall_back(
        &mut self,
        start: Option<&Start>,
        monitor: &mut dyn Monitor,
        timer: &mut PhaseTimer,
    ) -> Result<bool, SolveError> {
        let settings = self.settings;
        let tol = settings.tol.max(Penalty::default().tol);
        let robust = robust_steps(self.l, start, tol, settings.fallback_max_iter, monitor, timer);
        self.count.fallbacks += 1;
        let robust = match robust {
            Ok(robust) => robust,
            Err(SolveError::BeyondCollapse { solver, evidence }) => {
                return Err(SolveError::BeyondCollapse {
                    solver: self.name.into(),
                    evidence: format!(
                        "at iteration {}, fallback {} on the {solver} method found it (theory §4.2.1): {evidence}",
                        self.state.it, self.count.fallbacks
                    ),
                });
            }
            Err(_) => return Ok(false),
        };
        self.count.fallback_iterations += robust.report.iterations;
        self.count.fallback_linear.add(&robust.report.counters);
        let s = &mut self.state;
        s.u = robust.u;
        s.v = robust.extras;
        s.lambda = robust.lambda;
        s.elastic_phase = false;
        s.it += 1;
        self.cold = false;
        Ok(true)
    }

    /// The error `e` of a step, or the collapse it shows (theory §4.2.1): a plastic tangent that
    /// is not positive definite under prescribed forces (on the extras or the body), where the
    /// elastic tangent with the same active set is, means the plastic body offers no stiffness
    /// against them — a mechanism, the load beyond the limit.
    fn collapse_or(&mut self, e: SolveError) -> SolveError {
        let l = self.l;
        let forced = l.forced();
        let singular = matches!(&e, SolveError::LinearAlgebra { source, .. }
            if matches!(source.downcast_ref::<LinalgError>(), Some(LinalgError::NotPositiveDefinite { .. })));
        let plastic = !self.state.elastic_phase && l.data.plasticity().is_some();
        if singular && forced && plastic && self.elastic_tangent_is_regular() {
            SolveError::BeyondCollapse {
                solver: self.name.into(),
                evidence: format!(
                    "at iteration {} the tangent stiffness of the plastic body is singular under the prescribed \
                     forces (a collapse mechanism; {} fallbacks on the penalty method did not find a solution either)",
                    self.state.it, self.count.fallbacks
                ),
            }
        } else {
            e
        }
    }

    /// The Newton system with the elastic tangent and the current active set can be solved: the
    /// body is held (an unrestrained body's stiffness is singular already; theory §4.2.1).
    fn elastic_tangent_is_regular(&mut self) -> bool {
        let (l, c, s, w) = (self.l, &self.c_elastic, &self.state, &mut self.work);
        w.assemble_elastic(l, c);
        match &mut self.system {
            Systems::Serial(system) => system.step(l, &w.k, &s.active, &w.grad, &w.gap, CG_TOL_MIN).is_ok(),
            Systems::Distributed(system) => {
                system.step(l, Material::Uniform(c), &w.k, &s.active, &w.grad, &w.gap, CG_TOL_MIN).is_ok()
            }
        }
    }

    /// Stage 7: (u, V) += α (du, dV), λ from the step.
    fn advance(&mut self, step: &Step, alpha: f64) {
        let s = &mut self.state;
        axpy(&mut s.u, alpha, &step.du);
        axpy(&mut s.v, alpha, &step.dv);
        s.lambda.copy_from_slice(&step.lambda);
        s.it += 1;
    }

    /// The solution and its report (theory §5): the iterate, `stop` and the last residuals
    /// `kkt`, the counters, and the phases of `timer`.
    fn finish(mut self, stop: StopReason, kkt: KktResiduals, timer: &mut PhaseTimer) -> Solution {
        // `auto`'s deferred analysis, if it ran, priced the direct path only now
        if let Some(e) = self.system.serial().and_then(|s| s.iterative()).and_then(|it| it.cost_estimates) {
            self.count.cost_estimates = Some(e);
        }
        let c = &self.count;
        let elastic_factorisations = (c.elastic_contact_solves > 0) as usize;
        let mut counters = BTreeMap::new();
        let mut put = |k: &str, x: usize| counters.insert(k.to_string(), x as f64);
        match &mut self.system {
            Systems::Serial(sys) => {
                put("factorisations", sys.factorisations + elastic_factorisations);
                put("symbolic_analyses", sys.symbolic_analyses);
                put("triangular_solve_pairs", sys.solves + c.elastic_contact_solves);
                put("elastic_contact_solves", c.elastic_contact_solves);
                if let Some(iterative) = sys.iterative() {
                    put("pcg_iterations", iterative.iterations);
                    put("pcg_unconverged", iterative.unconverged);
                    put("multigrid_refreshes", iterative.refreshes);
                    put("pressure_block_solves", iterative.block_solves);
                    put("auto_switched_to_direct", iterative.switched as usize);
                }
            }
            Systems::Distributed(d) => {
                put("distributed_assemblies", d.assemblies);
                put("distributed_solves", d.solves);
                put("krylov_iterations", d.iterations);
                put("krylov_unconverged", d.unconverged);
            }
        }
        put("line_search_backtracks", c.backtracks);
        put("fallbacks", c.fallbacks);
        put("fallback_iterations", c.fallback_iterations);
        c.fallback_linear.report(|k, x| {
            put(k, x);
        });
        put("active_set_changes", c.active_changes);
        // a rank's counts summed over the ranks (theory §12; on one process the count itself)
        let comm = self.l.comm();
        put("return_mappings", comm.sum_count(c.return_mappings));
        put("elastic_phase_steps", c.elastic_phase_steps);
        // the normal rows in A (a sticking pair's tangential rows are in A too)
        let tangential = self.l.data.rows.friction.tangential_mask(self.state.active.len());
        let normal_active = self.state.active.iter().zip(&tangential).filter(|(a, t)| **a && !**t).count();
        put("contact_rows_active", comm.sum_count(normal_active));
        put("setup_reused", c.setup_reused as usize);
        put("stiffness_nonzeros", comm.sum_count(self.l.pattern().nnz()));
        if let Some(chol) = self.system.serial().and_then(|s| s.direct()) {
            counters.insert("factor_nonzeros".into(), chol.nnz_l() as f64);
            counters.insert("factor_flops".into(), chol.factor_flops());
        }
        if let Some((direct, amg)) = c.cost_estimates {
            counters.insert("auto_direct_cost".into(), direct);
            counters.insert("auto_amg_cost".into(), amg);
        }
        if let (Some(key), Systems::Serial(system)) = (self.key.take(), self.system) {
            let cost_estimates = self.count.cost_estimates;
            self.settings.setup_cache.keep(CachedSetup {
                key,
                system,
                row_stiffness: self.row_stiffness,
                cost_estimates,
            });
        }
        let State { u, v, lambda, stress, it, .. } = self.state;
        let report = self.history.report(stop, it, kkt, std::mem::take(timer).into_phases(), counters);
        Solution { u, extras: v, stress, lambda, report, undetermined: Vec::new() }
    }
}

/// The elastic contact problem solved exactly (theory §4.2, elastic start): the projection onto
/// K_h, in the energy metric of the elastic stiffness K, of the unconstrained elastic solution
/// z = K⁻¹f (Uzawa's step 2 of theory §4.1 with ρ = 1 from u = 0, which for an elastic body is
/// the solution). One factorisation of K into `chol` (analysed on L's pattern), one solve per
/// contact row for the Delassus matrix G K⁻¹ Gᵀ (in blocks of columns) and a dense QP over the
/// rows. Returns the start and the triangular solves spent; errors name `solver`.
fn elastic_contact_start(
    l: &Lagrangian<'_>,
    chol: &mut SparseCholesky,
    solver: &str,
) -> Result<(Start, usize), SolveError> {
    let (n, ne, nr) = (l.n_dofs(), l.n_extras(), l.data.rows.n_rows());
    let c = l.data.elasticity.stiffness_matrix();
    chol.factorise(&l.stiffness(Material::Uniform(&c))).in_solver(solver)?;
    // z = K⁻¹(f_u + BᵀCε_p) (zero without loads on u and without a step's plastic strain):
    // the elastic response from the state, σ = C(ε − ε_p), balances f_u when Kz = f_u + BᵀCε_p
    let mut z = vec![0.0; n];
    let f_u = l.data.nodal_load;
    if !f_u.is_empty() {
        z.copy_from_slice(f_u);
    }
    if let Some(st) = l.data.state {
        let mut f0 = vec![0.0; n];
        locked_in_forces(l.ops, l.data.elasticity, st, &mut f0);
        for (zi, f) in z.iter_mut().zip(&f0) {
            *zi += f;
        }
    }
    if z.iter().any(|f| *f != 0.0) {
        chol.solve(&mut z);
    }
    let rows = l.data.rows;
    let mut projection = MetricProjection::new(rows, chol, 0.0, 1.0, l.data.load, solver)?;
    let (mut u, mut extras, mut lambda) = (vec![0.0; n], vec![0.0; ne], vec![0.0; nr]);
    let solves = projection.setup_solves + projection.project(rows, chol, &z, &mut extras, &mut u, &mut lambda)?;
    Ok((Start { u, extras, lambda }, solves))
}

/// The rows in the active set `active`.
fn active_rows(active: &[bool]) -> usize {
    active.iter().filter(|a| **a).count()
}
