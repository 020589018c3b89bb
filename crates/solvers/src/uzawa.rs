//! The paper's algorithm: Uzawa / Arrow–Hurwicz (theory §4.1), exactly as stated there.
//!
//! For n = 0, 1, …
//!  1. σ̂ⁿ⁺¹ = P_D(C ε(uⁿ), 0) element by element (the local law, theory §2);
//!  2. (uⁿ⁺¹, Vⁿ⁺¹) ∈ K_h is the projected gradient step
//!     `(uⁿ⁺¹ − uⁿ, v − uⁿ⁺¹)_M + m (Vⁿ⁺¹ − Vⁿ)(V − Vⁿ⁺¹) ≥ ρ [f·(V − Vⁿ⁺¹) − (σⁿ⁺¹, ε(v − uⁿ⁺¹))]`
//!     for all (v, V) ∈ K_h — a projection onto K_h in the metric diag(M, m), solved exactly for
//!     the contact rows ([`MetricProjection`]).
//!
//! M is the elastic energy metric (Cε(·), ε(·)) by default — better conditioned than the
//! paper's (ε(·), ε(·)), which is selectable — and is factorised once (symbolic and numeric)
//! and reused by every iteration: one triangular solve pair per iteration. ρ is given relative
//! to 1/L, L ≥ λ_max(M⁻¹K) (L = 1 in the energy metric, max(2G, 3K_b) in the strain metric), so
//! the method is stable for ρ < 2 whatever the units. The extras' weight m defaults to 0: V is
//! then eliminated exactly inside the projection (m = 1 is the paper's choice, selectable as a
//! multiple of V's natural stiffness). The iteration stops on the relative KKT residual of the
//! iterate, never on the step length; divergence and NaN are detected and reported.
//!
//! On a distributed problem (theory §12.4) step (ii) is the same projection, solved by Newton's
//! distributed active set ([`DistributedProjection`]) with V eliminated exactly; stage 3 then
//! has nothing to do (the projection needs no z).
//!
//! The iteration runs in named stages (one method of the private `Run` each):
//!
//! 0. **set-up** (`Run::set_up`): M assembled and factorised, the projection onto K_h set up
//!    (its Delassus matrix), the start;
//! 1. **local law** (`Run::local_law`): step (i) and the KKT residual of the iterate
//!    (uⁿ, Vⁿ, σ̂ⁿ⁺¹, λⁿ) (theory §3.4);
//! 2. **stopping** (`Run::stop`): converged, the divergence guard (`Run::divergence_guard`),
//!    the budget, stagnation;
//! 3. **gradient step** (`Run::gradient_step`): z = uⁿ − ρM⁻¹Bᵀσ̂ⁿ⁺¹;
//! 4. **projection** (`Run::project`): (uⁿ⁺¹, Vⁿ⁺¹) and the multipliers μ, the projection of z
//!    onto K_h;
//! 5. **step length** (`Run::measure_step`): ‖xⁿ⁺¹ − xⁿ‖ in diag(M, m), for the guard;
//! 6. **update** (`Run::advance`): λⁿ⁺¹ = μ/ρ.

use crate::distributed_projection::DistributedProjection;
use crate::kh_projection::MetricProjection;
use crate::linear::{self, InSolver};
use crate::local_law::{IterateMut, local_law_and_residual};
use crate::residual::History;
use crate::warm_start::warm_solve;
use saddle_core::energy_of_stress;
use saddle_core::error::{ParameterError, check};
use saddle_core::linalg::SparseCholesky;
use saddle_core::problem::fields::StressField;
use saddle_core::problem::kkt::KktResiduals;
use saddle_core::problem::lagrangian::{Lagrangian, Workspace};
use saddle_core::problem::operators::Material;
use saddle_core::problem::solver::{Monitor, PhaseTimer, Solution, SolveError, Solver, Start, StopReason};
use saddle_core::{Elasticity, SymOp};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The metric M of step (ii).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum UzawaMetric {
    /// (Cε(u), ε(v)): the elastic energy (default).
    Energy,
    /// (ε(u), ε(v)): the paper's choice.
    Strain,
}

/// The acceleration of the projected gradient step (theory §4.1, acceleration).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum UzawaAcceleration {
    /// The plain step from the iterate: the paper's method.
    None,
    /// Nesterov's momentum (FISTA) with adaptive restart and a monotone safeguard, for ρ ≤ 1
    /// (default).
    Fista,
}

/// `type = "uzawa"`: the paper's Uzawa / Arrow–Hurwicz method (theory §4.1).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Uzawa {
    /// Step ρ in units of 1/L; stable for 0 < ρ < 2.
    pub rho: f64,
    /// The metric M.
    pub metric: UzawaMetric,
    /// Weight m of the extra unknowns relative to their natural stiffness; 0 eliminates them
    /// exactly.
    pub extra_metric: f64,
    /// Relative KKT tolerance.
    pub tol: f64,
    /// Iteration budget.
    pub max_iter: usize,
    /// The acceleration: FISTA with restart (default) or none.
    pub acceleration: UzawaAcceleration,
}

impl Default for Uzawa {
    fn default() -> Self {
        Self {
            rho: 1.0,
            metric: UzawaMetric::Energy,
            extra_metric: 0.0,
            tol: 1e-8,
            max_iter: 20_000,
            acceleration: UzawaAcceleration::Fista,
        }
    }
}

/// The stable range of ρ (in units of 1/L): 0 < ρ < 2 (theory §4.1: the projected gradient
/// method converges for ρ < 2/L).
pub const RHO_BOUND: f64 = 2.0;

/// Divergence (theory §4.1): a step length in diag(M, m) this many times the smallest one seen
/// since the first step. Below the bound the step length never grows, so any growth is
/// instability; 10 leaves room for round-off once the steps are tiny, and above the bound the
/// growth |1 − ρ|ⁿ passes 10 within a few iterations.
pub const DIVERGENCE_GROWTH: f64 = 10.0;

/// Steps below this fraction of the first one are round-off: the smallest step is floored
/// there, so that tiny steps of a converging iteration are not taken for growth.
pub const STEP_ROUND_OFF: f64 = 1e-12;

/// The accelerated step needs ρ at most this (theory §4.1, acceleration: FISTA's step 1/L).
pub const ACCELERATION_RHO_BOUND: f64 = 1.0;

/// The safeguard's round-off (theory §4.1, acceleration): J is summed over every point and dof,
/// so its value wanders by a few 1e-15 of its terms between iterates that differ by less
/// (measured on the perfectly plastic P2 strip near its solution: rises up to 1.2e-15 on
/// J = 0.18, where this allowance is 3.7e-14); a rise
/// below this fraction of |J| + |u·Bᵀσ̂| is not a rise.
pub const ENERGY_ROUND_OFF: f64 = 1e-13;

/// The first iteration at which divergence is judged: the test compares the last step with the
/// smallest one after the first, so it needs steps 1 and 2.
pub const DIVERGENCE_WARM_UP: usize = 3;

/// Stagnation (theory §4.1): no new best residual for max(this, n/4) iterations. Uzawa's
/// residual is not monotone, so the window is deliberately long: it only decides when a run
/// that cannot improve (a round-off floor above `tol`) is stopped, so a long window costs time,
/// never a solution.
pub const STAGNATION_WINDOW: usize = 500;

/// Escape (theory §4.6): the iterates are judged at iterations 2ᵏ ≥ this, over the last two
/// doublings of the count. Until then the first, elastic steps dominate the path.
pub const ESCAPE_START: usize = 256;

/// Escape: the chord ‖xⁿ − xⁿᐟ²‖ is at least this fraction of the path Σ‖xᵏ⁺¹ − xᵏ‖ between
/// (a straight line). A converging iteration near its round-off floor, or one turning between
/// active sets, falls far below it.
pub const ESCAPE_STRAIGHTNESS: f64 = 0.99;

/// Escape: the step length δₙ is at least this fraction of δₙ/₂ (an undiminished speed).
/// Near a solution that a perfectly plastic body reaches sublinearly δ falls like n^(−1/2),
/// to 0.71 of itself per doubling; with hardening it falls geometrically.
pub const ESCAPE_SPEED: f64 = 0.9;

#[typetag::serde(name = "uzawa")]
impl Solver for Uzawa {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::positive(path, "rho", self.rho)?;
        check::non_negative(path, "extra_metric", self.extra_metric)?;
        check::open_interval(path, "tol", self.tol, 0.0, 1.0)?;
        check::at_least_one(path, "max_iter", self.max_iter)?;
        Ok(())
    }

    fn tolerance(&self) -> f64 {
        self.tol
    }

    /// Step 2's projection by the distributed active set, decisions from sums over the ranks
    /// (theory §12.4).
    fn runs_distributed(&self) -> bool {
        true
    }

    fn solve(&self, l: &Lagrangian<'_>, monitor: &mut dyn Monitor) -> Result<Solution, SolveError> {
        self.iterate(l, None, monitor)
    }

    /// The iteration from the previous step's (u, V, λ) (theory §11.2).
    fn solve_warm(&self, l: &Lagrangian<'_>, start: &Start, monitor: &mut dyn Monitor) -> Result<Solution, SolveError> {
        warm_solve(l, start, "uzawa", || self.iterate(l, Some(start), monitor))
    }
}

impl Uzawa {
    /// The iteration of theory §4.1 from `start` (zero if `None`), in the stages of the module
    /// docs.
    fn iterate(
        &self,
        l: &Lagrangian<'_>,
        start: Option<&Start>,
        monitor: &mut dyn Monitor,
    ) -> Result<Solution, SolveError> {
        let mut run = Run::set_up(self, l, start, monitor)?;
        monitor.phase("iterations");
        let (stop, kkt) = loop {
            let kkt = run.local_law();
            let r = kkt.max();
            run.history.record(run.state.it, r, monitor)?;
            if let Some(stop) = run.stop(r)? {
                break (stop, kkt);
            }
            run.safeguard();
            run.extrapolate();
            run.gradient_step();
            run.project()?;
            run.measure_step();
            run.restart_test();
            run.advance();
        };
        Ok(run.finish(stop, kkt))
    }

    /// The metric M of step (ii) and the Lipschitz bound L ≥ λ_max(M⁻¹K) of theory §4.1.
    fn metric(&self, law: &Elasticity) -> (SymOp, f64) {
        match self.metric {
            UzawaMetric::Energy => (law.stiffness_matrix(), 1.0),
            UzawaMetric::Strain => (SymOp::identity(), law.max_eigenvalue()),
        }
    }

    /// The momentum is used: FISTA asked for, with ρ within its bound (theory §4.1,
    /// acceleration).
    fn accelerated(&self) -> bool {
        self.acceleration == UzawaAcceleration::Fista && self.rho <= ACCELERATION_RHO_BOUND
    }
}

/// The iteration state of theory §4.1: the iterate and the projection's multipliers.
struct State {
    /// uⁿ.
    u: Vec<f64>,
    /// Vⁿ.
    v: Vec<f64>,
    /// μ = ρλ, the multipliers of the projection step.
    mu: Vec<f64>,
    /// λⁿ = μ/ρ.
    lambda: Vec<f64>,
    /// σ̂ⁿ⁺¹ = P_D(Cε(uⁿ), 0), from the last local law.
    stress: StressField,
    /// Iterations done.
    it: usize,
    /// The momentum of the accelerated step (theory §4.1, acceleration): FISTA's tₖ, 1 after a
    /// restart.
    t: f64,
    /// The extrapolation factor βₙ of the last step (0: the plain step).
    beta: f64,
    /// J(xⁿ) of the last accepted iterate (+∞ before the first).
    energy: f64,
}

/// What the divergence and stagnation tests of theory §4.1 watch. For ρ < 2 the iteration map
/// is averaged in diag(M, m), so the step length δₙ = ‖xⁿ⁺¹ − xⁿ‖ never increases; above the
/// bound it grows like |1 − ρ|ⁿ. (The relative KKT residual cannot tell: it saturates near 1
/// when the iterate blows up.)
struct Watch {
    /// The best residual so far and its iteration.
    best: (f64, usize),
    /// The smallest step length after the first.
    smallest_step: f64,
    /// The first step length.
    first_step: f64,
    /// The last step length.
    last_step: f64,
    /// The Euclidean path length Σ‖xᵏ⁺¹ − xᵏ‖ since the last escape mark.
    path: f64,
    /// The step length at the last escape mark.
    mark_step: f64,
    /// The interval before the last mark was a straight line at undiminished speed.
    escaping: bool,
}

/// What an Uzawa run counts for its report.
#[derive(Default)]
struct Counts {
    /// Steps taken from an extrapolated point (β > 0).
    momentum_steps: usize,
    /// Restarts of the momentum by the gradient test.
    restarts: usize,
    /// Momentum steps rejected by the safeguard (J rose) and replaced by the plain step.
    rejected_steps: usize,
    /// Symbolic analyses of M's pattern.
    symbolic_analyses: usize,
    /// Numeric factorisations of M.
    factorisations: usize,
    /// Triangular solve pairs of the iterations.
    solves: usize,
    /// Points at which P's return mapping ran, as the local law reports them.
    return_mappings: usize,
}

/// Scratch of the stages, allocated once per solve.
struct Scratch {
    ws: Workspace,
    /// The unprojected step z = uⁿ − ρM⁻¹Bᵀσⁿ⁺¹, then Gᵀμ.
    z: Vec<f64>,
    /// The point yⁿ the gradient step starts from (the iterate (uⁿ, Vⁿ) for the plain step).
    u_prev: Vec<f64>,
    v_prev: Vec<f64>,
    /// The iterate xⁿ the step was taken from, λⁿ and ∇J(xⁿ), for the momentum and the safeguard
    /// (empty without acceleration).
    u_last: Vec<f64>,
    v_last: Vec<f64>,
    lambda_last: Vec<f64>,
    force_last: Vec<f64>,
    /// σ̂ at the extrapolated point.
    stress_y: StressField,
    /// Hᵀμ (unused).
    ht_mu: Vec<f64>,
    /// The iterate (u, V) at the last escape mark.
    u_mark: Vec<f64>,
    v_mark: Vec<f64>,
}

impl Scratch {
    /// The scratch of the stages for `l`, the escape mark at the iterate `start` (zero if
    /// `None`).
    fn new(l: &Lagrangian<'_>, start: Option<&Start>, accelerated: bool) -> Self {
        let (n, ne, nr) = (l.n_dofs(), l.n_extras(), l.n_rows());
        let k = usize::from(accelerated);
        Self {
            ws: Workspace::new(l),
            z: vec![0.0; n],
            u_prev: vec![0.0; n],
            v_prev: vec![0.0; ne],
            u_last: vec![0.0; n * k],
            v_last: vec![0.0; ne * k],
            lambda_last: vec![0.0; nr * k],
            force_last: vec![0.0; n * k],
            stress_y: StressField::new(l.n_points() * k, l.data.hardening_dim()),
            ht_mu: vec![0.0; ne],
            u_mark: start.map_or_else(|| vec![0.0; n], |s| s.u.clone()),
            v_mark: start.map_or_else(|| vec![0.0; ne], |s| s.extras.clone()),
        }
    }
}

/// Step (ii)'s linear algebra: on one process M factorised and the exact projection onto K_h in
/// diag(M, m) (`None` without contact rows, where step (ii) is a plain gradient step); on a
/// distributed problem the projection by the distributed active set (theory §12.4).
enum Projector {
    Serial { chol: SparseCholesky, proj: Option<MetricProjection> },
    Distributed(DistributedProjection),
}

/// One Uzawa solve: what it reads, the factorised metric, the projection onto K_h, state,
/// counters and scratch.
struct Run<'a> {
    settings: &'a Uzawa,
    l: &'a Lagrangian<'a>,
    /// The step ρ/L.
    rho: f64,
    /// M and the projection onto K_h.
    projector: Projector,
    state: State,
    watch: Watch,
    count: Counts,
    work: Scratch,
    timer: PhaseTimer,
    /// The KKT residual of every iterate.
    history: History,
}

impl<'a> Run<'a> {
    /// Stage 0 (theory §4.1): M assembled and factorised once, the projection onto K_h set up,
    /// the iterate from `start` (zero if `None`, μ = ρλ) and the scratch.
    fn set_up(
        settings: &'a Uzawa,
        l: &'a Lagrangian<'a>,
        start: Option<&Start>,
        monitor: &mut dyn Monitor,
    ) -> Result<Self, SolveError> {
        let mut timer = PhaseTimer::default();
        let mut count = Counts::default();
        let (metric, lip) = settings.metric(l.data.elasticity);
        let rho = settings.rho / lip;
        let projector = if l.is_distributed() {
            Self::distributed(settings, l, &metric, rho, monitor, &mut timer)?
        } else {
            let mut chol = Self::factorise_metric(l, &metric, monitor, &mut timer, &mut count)?;
            let rows = l.data.rows;
            let proj = if rows.n_rows() > 0 {
                monitor.phase("contact set-up");
                Some(timer.time("contact set-up", || {
                    MetricProjection::new(rows, &mut chol, settings.extra_metric, rho, l.data.load, "uzawa")
                })?)
            } else {
                None
            };
            Projector::Serial { chol, proj }
        };
        Ok(Self {
            settings,
            l,
            rho,
            projector,
            state: Self::start(l, start, rho),
            watch: Watch {
                best: (f64::INFINITY, 0),
                smallest_step: f64::INFINITY,
                first_step: 0.0,
                last_step: 0.0,
                path: 0.0,
                mark_step: f64::INFINITY,
                escaping: false,
            },
            count,
            work: Scratch::new(l, start, settings.accelerated()),
            timer,
            history: History::new("uzawa", settings.tol),
        })
    }

    /// Stage 0 on a distributed problem (theory §12.4): the projection by the distributed active
    /// set in the metric M with step `rho`; the extras eliminated exactly (`extra_metric` = 0).
    fn distributed(
        settings: &Uzawa,
        l: &Lagrangian<'_>,
        metric: &SymOp,
        rho: f64,
        monitor: &mut dyn Monitor,
        timer: &mut PhaseTimer,
    ) -> Result<Projector, SolveError> {
        if settings.extra_metric != 0.0 {
            return Err(SolveError::Unsupported {
                solver: "uzawa".into(),
                message: format!(
                    "solver.extra_metric = {} on a distributed problem: the extras are eliminated exactly there \
                     (extra_metric = 0), or run on one process",
                    settings.extra_metric
                ),
            });
        }
        monitor.phase("analysis");
        let p = timer.time("analysis", || DistributedProjection::new(l, metric, rho, "uzawa"))?;
        Ok(Projector::Distributed(p))
    }

    /// M = (metric ε(·), ε(·)) assembled on L's pattern, analysed and factorised once (theory
    /// §4.1: one triangular solve pair per iteration).
    fn factorise_metric(
        l: &Lagrangian<'_>,
        metric: &SymOp,
        monitor: &mut dyn Monitor,
        timer: &mut PhaseTimer,
        count: &mut Counts,
    ) -> Result<SparseCholesky, SolveError> {
        monitor.phase("assembly");
        let m_values = timer.time("assembly", || l.stiffness(Material::Uniform(metric)));
        monitor.phase("factorisation");
        timer.time("factorisation", || {
            let mut chol = linear::analyse(l.pattern(), "Uzawa metric", "uzawa", &mut count.symbolic_analyses)?;
            chol.factorise(&m_values).in_solver("uzawa")?;
            count.factorisations += 1;
            Ok(chol)
        })
    }

    /// The iterate (u⁰, V⁰, λ⁰): zero, or the previous load step's (theory §11.2), with the
    /// projection's multipliers μ = ρλ.
    fn start(l: &Lagrangian<'_>, start: Option<&Start>, rho: f64) -> State {
        let (n, ne, nr) = (l.n_dofs(), l.n_extras(), l.data.rows.n_rows());
        let mut s = State {
            u: vec![0.0; n],
            v: vec![0.0; ne],
            mu: vec![0.0; nr],
            lambda: vec![0.0; nr],
            stress: StressField::new(l.n_points(), l.data.hardening_dim()),
            it: 0,
            t: 1.0,
            beta: 0.0,
            energy: f64::INFINITY,
        };
        if let Some(st) = start {
            s.u.copy_from_slice(&st.u);
            s.v.copy_from_slice(&st.extras);
            s.lambda.copy_from_slice(&st.lambda);
            for (m, l) in s.mu.iter_mut().zip(&st.lambda) {
                *m = rho * l;
            }
        }
        s
    }

    /// Stage 1 (theory §4.1 step 1): σ̂ⁿ⁺¹ = P_D(Cε(uⁿ), 0) at every point, then the KKT
    /// residuals of the iterate (uⁿ, Vⁿ, σ̂ⁿ⁺¹, λⁿ) (theory §3.4); `ws.force` holds Bᵀσ̂ⁿ⁺¹ − f_u
    /// afterwards.
    fn local_law(&mut self) -> KktResiduals {
        let (l, s, w) = (self.l, &mut self.state, &mut self.work);
        let it = IterateMut { u: &s.u, extras: &s.v, lambda: &s.lambda, stress: &mut s.stress };
        let (projected, kkt) = local_law_and_residual(l, it, None, &mut w.ws, &mut self.timer);
        self.count.return_mappings += projected;
        kkt
    }

    /// Stage 2 (theory §4.1, stopping): converged when the residual `r` meets `tol`; an error
    /// when the step length grew (the divergence guard); else out of budget, or stagnated when
    /// the best residual has not improved for max([`STAGNATION_WINDOW`], n/4) iterations; else
    /// `None` (go on).
    fn stop(&mut self, r: f64) -> Result<Option<StopReason>, SolveError> {
        let (it, wt) = (self.state.it, &mut self.watch);
        if r <= self.settings.tol {
            return Ok(Some(StopReason::Converged));
        }
        if r < wt.best.0 {
            wt.best = (r, it);
        }
        if !self.settings.accelerated() {
            self.divergence_guard(r)?;
        }
        self.escape_guard(r)?;
        Ok(if it >= self.settings.max_iter {
            Some(StopReason::MaxIterations)
        } else if it - self.watch.best.1 > STAGNATION_WINDOW.max(it / 4) {
            Some(StopReason::Stagnated)
        } else {
            None
        })
    }

    /// The divergence guard (theory §4.1, stopping): from iteration [`DIVERGENCE_WARM_UP`], a
    /// step length [`DIVERGENCE_GROWTH`] times the smallest one since the first (floored at
    /// [`STEP_ROUND_OFF`] of the first) is an error with a hint on ρ.
    fn divergence_guard(&self, r: f64) -> Result<(), SolveError> {
        let (it, wt) = (self.state.it, &self.watch);
        if it >= DIVERGENCE_WARM_UP
            && wt.smallest_step < f64::INFINITY
            && wt.last_step > DIVERGENCE_GROWTH * wt.smallest_step.max(STEP_ROUND_OFF * wt.first_step)
        {
            return Err(SolveError::Diverged {
                solver: "uzawa".into(),
                iteration: it,
                residual: r,
                hint: self.settings.divergence_hint(),
            });
        }
        Ok(())
    }

    /// The escape guard (theory §4.6): at iterations n = 2ᵏ, whether the iterates moved from
    /// xⁿᐟ² to xⁿ along a straight line ([`ESCAPE_STRAIGHTNESS`]) at undiminished speed
    /// ([`ESCAPE_SPEED`]); the mark moves to xⁿ. Twice running from [`ESCAPE_START`], on a plastic
    /// body under prescribed forces, the iterates run away along a collapse mechanism:
    /// [`SolveError::BeyondCollapse`].
    fn escape_guard(&mut self, r: f64) -> Result<(), SolveError> {
        let (l, it, s, w, wt) = (self.l, self.state.it, &self.state, &mut self.work, &mut self.watch);
        if it < ESCAPE_START / 4 || !it.is_power_of_two() {
            return Ok(());
        }
        let comm = l.comm();
        let chord = comm.sum(s.u.iter().zip(&w.u_mark).map(|(a, b)| (a - b).powi(2)).sum::<f64>())
            + s.v.iter().zip(&w.v_mark).map(|(a, b)| (a - b).powi(2)).sum::<f64>();
        let (chord, path) = (chord.sqrt(), wt.path);
        let escaping = path > 0.0 && chord >= ESCAPE_STRAIGHTNESS * path && wt.last_step >= ESCAPE_SPEED * wt.mark_step;
        // a perfectly plastic body, or friction (theory §8.3: a tangential force above the
        // friction the contact can give slides the obstacle away), under prescribed forces
        let can_escape = l.data.plasticity().is_some() || l.data.rows.has_friction();
        if escaping && wt.escaping && it >= ESCAPE_START && can_escape && l.forced() {
            return Err(SolveError::BeyondCollapse {
                solver: "uzawa".into(),
                evidence: format!(
                    "from iteration {} to {it} the iterates ran along a straight line at undiminished speed (step \
                     length {:.3e} in the metric, {:.3e} at iteration {}; chord {:.4} of the path), the KKT residual \
                     still {r:.3e}: the displacement runs away along a collapse mechanism (with friction: the obstacle \
                     slides, no tangential force within the friction discs balancing its load)",
                    it / 4,
                    wt.last_step,
                    wt.mark_step,
                    it / 2,
                    chord / path
                ),
            });
        }
        wt.escaping = escaping;
        (wt.path, wt.mark_step) = (0.0, wt.last_step);
        w.u_mark.copy_from_slice(&s.u);
        w.v_mark.copy_from_slice(&s.v);
        Ok(())
    }

    /// Stage 2b (theory §4.1, acceleration): J(xⁿ) from the local law's output; a momentum step
    /// that raised J is rejected — the iterate goes back to xⁿ⁻¹, the one it was taken from,
    /// with its λ and gradient, and the momentum restarts, so the next step is the plain one.
    fn safeguard(&mut self) {
        if !self.settings.accelerated() {
            return;
        }
        let (l, s, w) = (self.l, &mut self.state, &mut self.work);
        let j = energy_of_stress(l, &s.u, &s.v, &s.stress, &w.ws.force);
        // J's round-off: its largest term u·Bᵀσ̂ and J itself, times ENERGY_ROUND_OFF
        let work = l.comm().sum(s.u.iter().zip(&w.ws.force).map(|(x, f)| x * f).sum::<f64>());
        let round_off = ENERGY_ROUND_OFF * (j.abs() + work.abs());
        if s.beta > 0.0 && j > s.energy + round_off {
            self.reject_momentum();
        } else {
            s.energy = j;
        }
    }

    /// A momentum step thrown away (theory §4.1, acceleration): the iterate goes back to the
    /// point xⁿ it was taken from, with its λ and ∇J(xⁿ), and the momentum restarts.
    fn reject_momentum(&mut self) {
        let (s, w) = (&mut self.state, &mut self.work);
        s.u.copy_from_slice(&w.u_last);
        s.v.copy_from_slice(&w.v_last);
        s.lambda.copy_from_slice(&w.lambda_last);
        for (m, x) in s.mu.iter_mut().zip(&s.lambda) {
            *m = self.rho * x;
        }
        w.ws.force.copy_from_slice(&w.force_last);
        (s.t, s.beta) = (1.0, 0.0);
        self.count.rejected_steps += 1;
    }

    /// Stage 2c (theory §4.1, acceleration): the point of the gradient step,
    /// yⁿ = xⁿ + βₙ(xⁿ − xⁿ⁻¹) with FISTA's βₙ = (tₙ − 1)/tₙ₊₁, tₙ₊₁ = (1 + √(1 + 4tₙ²))/2, and
    /// ∇J(yⁿ) by the local law at yⁿ into `ws.force`; xⁿ, λⁿ and ∇J(xⁿ) are kept for the
    /// safeguard. The plain step (β = 0, after a restart) needs no second local law.
    fn extrapolate(&mut self) {
        if !self.settings.accelerated() {
            return;
        }
        let (l, s, w) = (self.l, &mut self.state, &mut self.work);
        let t_next = 0.5 * (1.0 + (1.0 + 4.0 * s.t * s.t).sqrt());
        s.beta = (s.t - 1.0) / t_next;
        s.t = t_next;
        w.lambda_last.copy_from_slice(&s.lambda);
        if s.beta == 0.0 {
            w.u_last.copy_from_slice(&s.u);
            w.v_last.copy_from_slice(&s.v);
            return;
        }
        let beta = s.beta;
        for (x, last) in s.u.iter_mut().zip(w.u_last.iter_mut()).chain(s.v.iter_mut().zip(w.v_last.iter_mut())) {
            let xn = *x;
            *x += beta * (xn - *last);
            *last = xn;
        }
        w.force_last.copy_from_slice(&w.ws.force);
        let projected = self.timer.time("local law", || {
            l.strain(&s.u, &mut w.ws.eps);
            let law = l.data.local_law(&w.ws.eps, &mut w.stress_y, None);
            l.divergence(&w.stress_y.sigma, &mut w.ws.force);
            for (f, b) in w.ws.force.iter_mut().zip(l.data.nodal_load) {
                *f -= b;
            }
            law.projected
        });
        self.count.return_mappings += projected;
        self.count.momentum_steps += 1;
    }

    /// Stage 3 (theory §4.1 step 2, the gradient step): z = uⁿ − ρM⁻¹Bᵀσ̂ⁿ⁺¹ by one triangular
    /// solve pair with the factorised M (`ws.force` holds Bᵀσ̂ⁿ⁺¹); the distributed projection
    /// needs no z.
    fn gradient_step(&mut self) {
        let Projector::Serial { chol, .. } = &mut self.projector else {
            return;
        };
        let (rho, s, w) = (self.rho, &self.state, &mut self.work);
        self.timer.time("linear solves", || {
            for (zi, fi) in w.z.iter_mut().zip(&w.ws.force) {
                *zi = -rho * fi;
            }
            chol.solve(&mut w.z);
            for (zi, ui) in w.z.iter_mut().zip(&s.u) {
                *zi += ui;
            }
        });
        self.count.solves += 1;
    }

    /// Stage 4 (theory §4.1 step 2, the multipliers): (uⁿ⁺¹, Vⁿ⁺¹) the projection of z onto
    /// K_h in diag(M, m), exactly, with its multipliers μ ≥ 0 (u = z without contact rows).
    fn project(&mut self) -> Result<(), SolveError> {
        let (l, s, w) = (self.l, &mut self.state, &mut self.work);
        w.u_prev.clone_from(&s.u);
        w.v_prev.clone_from(&s.v);
        self.count.solves += match &mut self.projector {
            Projector::Serial { chol, proj: Some(p) } => {
                self.timer.time("projection", || p.project(l.data.rows, chol, &w.z, &mut s.v, &mut s.u, &mut s.mu))?
            }
            Projector::Serial { proj: None, .. } => {
                s.u.copy_from_slice(&w.z);
                0
            }
            Projector::Distributed(p) => {
                // from (uⁿ, Vⁿ, λⁿ); its multipliers are λⁿ⁺¹ = μ/ρ
                self.timer.time("projection", || p.project(l, &w.ws.force, &mut s.u, &mut s.v, &mut s.lambda))?;
                for (m, x) in s.mu.iter_mut().zip(&s.lambda) {
                    *m = self.rho * x;
                }
                0
            }
        };
        Ok(())
    }

    /// Stage 5 (theory §4.1, stopping): the step length δₙ² = Δuᵀ M Δu + Σ m ΔV², with
    /// M Δu = Gᵀμ − ρ Bᵀσ̂ⁿ⁺¹ (z is free again: it takes Gᵀμ), for the divergence guard.
    fn measure_step(&mut self) {
        let (rho, s, w, wt) = (self.rho, &self.state, &mut self.work, &mut self.watch);
        w.z.iter_mut().for_each(|x| *x = 0.0);
        self.l.data.rows.add_transpose(&s.mu, &mut w.z, &mut w.ht_mu);
        let du_m_du: f64 = (0..s.u.len()).map(|j| (s.u[j] - w.u_prev[j]) * (w.z[j] - rho * w.ws.force[j])).sum();
        let du_m_du = self.l.comm().sum(du_m_du);
        let weights = match &self.projector {
            Projector::Serial { proj: Some(p), .. } => p.extra_weights(),
            _ => &[],
        };
        let dv_m_dv: f64 = weights.iter().zip(s.v.iter().zip(&w.v_prev)).map(|(m, (a, b))| m * (a - b) * (a - b)).sum();
        wt.last_step = (du_m_du + dv_m_dv).max(0.0).sqrt();
        // the path runs over the iterates: from xⁿ, which is yⁿ unless the step was accelerated
        let (u_from, v_from) =
            if self.settings.accelerated() { (&w.u_last, &w.v_last) } else { (&w.u_prev, &w.v_prev) };
        let du2: f64 = s.u.iter().zip(u_from).map(|(a, b)| (a - b).powi(2)).sum();
        let dv2: f64 = s.v.iter().zip(v_from).map(|(a, b)| (a - b).powi(2)).sum();
        wt.path += (self.l.comm().sum(du2) + dv2).sqrt();
        if s.it == 0 {
            wt.first_step = wt.last_step;
        } else {
            wt.smallest_step = wt.smallest_step.min(wt.last_step);
        }
    }

    /// Stage 5b (theory §4.1, acceleration; O'Donoghue & Candès 2015): the momentum restarts
    /// when the step from yⁿ points against the motion, (yⁿ − xⁿ⁺¹)ᵀ diag(M, m) (xⁿ⁺¹ − xⁿ) > 0,
    /// with M(uⁿ⁺¹ − yⁿ) = Gᵀμ − ρ∇J(yⁿ) from stage 5 (`z` holds Gᵀμ).
    fn restart_test(&mut self) {
        if !self.settings.accelerated() {
            return;
        }
        let (rho, s, w) = (self.rho, &mut self.state, &self.work);
        let du: f64 = (0..s.u.len()).map(|j| (w.z[j] - rho * w.ws.force[j]) * (s.u[j] - w.u_last[j])).sum();
        let weights = match &self.projector {
            Projector::Serial { proj: Some(p), .. } => p.extra_weights(),
            _ => &[],
        };
        let dv: f64 =
            (weights.iter().enumerate()).map(|(k, m)| m * (s.v[k] - w.v_prev[k]) * (s.v[k] - w.v_last[k])).sum();
        if self.l.comm().sum(du) + dv < 0.0 {
            s.t = 1.0;
            self.count.restarts += 1;
        }
    }

    /// Stage 6 (theory §4.1): the contact forces λⁿ⁺¹ = μ/ρ; the next iteration.
    fn advance(&mut self) {
        let s = &mut self.state;
        for (l, m) in s.lambda.iter_mut().zip(&s.mu) {
            *l = m / self.rho;
        }
        s.it += 1;
    }

    /// The solution and its report (theory §5): the iterate, `stop` and the last residuals
    /// `kkt`, the counters and the phases.
    fn finish(self, stop: StopReason, kkt: KktResiduals) -> Solution {
        let c = &self.count;
        let proj = match &self.projector {
            Projector::Serial { proj, .. } => proj.as_ref(),
            Projector::Distributed(_) => None,
        };
        let mut counters = BTreeMap::new();
        let mut put = |k: &str, x: f64| counters.insert(k.to_string(), x);
        put("rho", self.settings.rho);
        put("rho_bound", RHO_BOUND);
        put("symbolic_analyses", c.symbolic_analyses as f64);
        put("factorisations", c.factorisations as f64);
        put("setup_solves", proj.map_or(0, |p| p.setup_solves) as f64);
        put("triangular_solve_pairs", c.solves as f64);
        put("qp_factorisations", proj.map_or(0, |p| p.qp_work().1) as f64);
        put("return_mappings", self.l.comm().sum_count(c.return_mappings) as f64);
        put("momentum_steps", c.momentum_steps as f64);
        put("momentum_restarts", c.restarts as f64);
        put("rejected_steps", c.rejected_steps as f64);
        let distributed = matches!(self.projector, Projector::Distributed(_));
        put("contact_structures", (proj.is_some() || distributed) as u8 as f64);
        put("delassus_columns_kept", proj.is_some_and(|p| p.keeps_delassus_columns()) as u8 as f64);
        if let Projector::Distributed(p) = &self.projector {
            let [assemblies, solves, iterations, unconverged] = p.counts();
            put("projection_sweeps", p.sweeps as f64);
            put("distributed_assemblies", assemblies as f64);
            put("distributed_solves", solves as f64);
            put("krylov_iterations", iterations as f64);
            put("krylov_unconverged", unconverged as f64);
        }
        let mut slow: Vec<String> = self.slow_convergence(stop, kkt.max()).into_iter().collect();
        let s = self.settings;
        if s.acceleration == UzawaAcceleration::Fista && !s.accelerated() {
            slow.push(format!(
                "uzawa ran without acceleration: solver.acceleration = \"fista\" needs rho <= {ACCELERATION_RHO_BOUND} \
                 (FISTA's step 1/L, theory §4.1), and rho = {}",
                s.rho
            ));
        }
        let State { u, v, lambda, stress, it, .. } = self.state;
        let mut report = self.history.report(stop, it, kkt, self.timer.into_phases(), counters);
        report.warnings.extend(slow);
        Solution { u, extras: v, stress, lambda, report, undetermined: Vec::new() }
    }

    /// Why an iteration that stopped short (`stop`, last residual `r`) did not reach `tol`
    /// (theory §4.1, the rate): its residual's contraction per iteration over the last quarter,
    /// the iterations that rate still needs, and the solvers that converge where the tangent is
    /// soft. `None` for a converged run or one without a measurable rate.
    fn slow_convergence(&self, stop: StopReason, r: f64) -> Option<String> {
        if stop == StopReason::Converged {
            return None;
        }
        let q = self.history.contraction()?;
        let more = (r / self.settings.tol).ln() / -q.ln();
        Some(format!(
            "uzawa converges too slowly here: its residual contracted by {q:.6} per iteration over the last quarter of \
             the run, so reaching tol = {:e} would take about {more:.0} more iterations at that rate (more where it keeps falling, \
             as with perfect plasticity); the projected gradient's rate \
             is set by the softest direction of the tangent (theory §4.1: h/(h + 2G) in the energy metric, 0 with \
             perfect plasticity): use newton, penalty or socp",
            self.settings.tol
        ))
    }
}

impl Uzawa {
    /// What to change when the iteration diverges.
    fn divergence_hint(&self) -> String {
        if self.rho >= RHO_BOUND {
            format!(
                "solver.rho = {} is at or above the stable bound {RHO_BOUND} (the step ρ/L needs ρ < 2, L ≥ λ_max(M⁻¹K)); use rho < {RHO_BOUND}",
                self.rho
            )
        } else {
            format!(
                "solver.rho = {} is below the stable bound {RHO_BOUND}: the problem data may be inconsistent",
                self.rho
            )
        }
    }
}
