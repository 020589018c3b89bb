//! The conic solver of theory §4.4: the dual (stress) form 3 of theory §3 handed to Clarabel's
//! interior point method, then polished by active-set Newton.
//!
//! **The cone programme** (theory §3 form 3). Variables `x = [σ̂_T for every stress point T
//! (6 Mandel entries of σ_T and the hardening entries q_T), λ_i for every row of K_h]`:
//!
//! * objective `½[σ̂, σ̂] + Σ_i λ_i c_i`: P is block diagonal with `w_T A` (A the elastic
//!   compliance as a 6×6 Mandel matrix) and `w_T H⁻¹` (the hardening metric), upper triangle;
//! * Clarabel's `A x + s = b, s ∈ cone`, row blocks in this order:
//!   1. zero cone, one row per free dof j: `Σ_T w_T (B_Tᵀσ_T)_j − (Gᵀλ)_j = 0` (internal forces
//!      equal the contact forces);
//!   2. zero cone, one row per extra unknown k: `−(Hᵀλ)_k = f_k` (Σλ = F for the punch);
//!   3. nonnegative cone: `s = λ ≥ 0`;
//!   4. one second-order cone per point and per block of `P::cone()`:
//!      `s = offset + map·(σ_T, q_T)` (theory §3: D is a second-order cone in (k₀ + ξ, dev σ)).
//!
//!   An elastic problem has no blocks 4: a QP.
//!
//! It is built in stages (`ConeProgramme::build`): P's cone blocks (`yield_cones`) and
//! hardening metric (`hardening_metric`), the layout of x (`Layout::new`), the units
//! (`Scales::new`), the objective's quadratic and linear terms (`quadratic_term`,
//! `linear_term`), the cone maps of one point (`ConeMap::new`), the columns of A by block
//! (`equilibrium_rows`, `contact_columns`, `cone_rows`), b (`right_hand_side`) and the cones
//! (`cones`).
//!
//! **The primal from the dual.** Clarabel's stationarity is `P x + q + Aᵀz = 0`. In the σ_T
//! rows of an elastic point it reads `w_T(Aσ_T + B_T z_eq) = 0`, i.e. `Aσ_T = ε_T(−z_eq)`; in
//! the λ_i rows `c_i − (G z_eq)_i − (H z_load)_i − z_λ,i = 0`, i.e. the multiplier of `λ_i ≥ 0`
//! is the gap `g_i(−z_eq, −z_load)`. Hence `u = −z_eq` and `V = −z_load`: complementarity
//! `z_λ · λ = 0` is then exactly `λ_i g_i = 0` (checked against Newton in the tests).
//!
//! **Units.** The data are non-dimensionalised before Clarabel sees them (Clarabel's
//! equilibration stays on as well), so that the iteration does not depend on the units of the
//! scene: a stress scale S (the largest cone offset — k₀ for von Mises —, else max|f|/L², else
//! E·10⁻³), a length L = (Σ_T w_T)^{1/3}, the stiffness E (Young's modulus), and derived from
//! them the displacement `D = S L / E`, the force `S L²` and the energy `S² L³ / E`. Stress
//! variables are divided by S, contact forces by S L², the equilibrium, load and sign rows by
//! S L², the cone rows by S, the objective by S² L³ / E; everything is mapped back.
//!
//! **Perfect plasticity.** A hardening variable whose metric is infinite
//! (`hardening_inner(e_k, e_k) = ∞`, von Mises with h = 0) is fixed at 0, as the local law of
//! theory §2 does: it is eliminated from the programme (no column; its entries of the cone maps
//! are dropped) and returned as 0.
//!
//! **Polishing.** The interior point method alone gives stresses to about 10⁻⁵; its (u, V, λ)
//! start [`Newton::solve_from`], which converges in a few iterations to `tol`.

use crate::linear::{self, InSolver};
use crate::newton::{Newton, Start};
use crate::triplets::{Triplets, programme_json};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SecondOrderConeT, SolverStatus, SupportedConeT,
    ZeroConeT,
};
use saddle_core::error::{ParameterError, check, join};
use saddle_core::problem::fields::StressField;
use saddle_core::problem::kkt::{KktResiduals, kkt_with_stress};
use saddle_core::problem::lagrangian::{Iterate, Lagrangian, Workspace};
use saddle_core::problem::operators::Material;
use saddle_core::problem::solver::{Monitor, PhaseTimer, Solution, SolveError, SolveReport, Solver, StopReason};
use saddle_core::problem::stresses::{MAX_HARDENING_DIM, SocBlock};
use saddle_core::problem::tensor::Sym;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The solver's type name.
const NAME: &str = "socp";

/// The default refinement tolerance of the KKT solves is this fraction of `ipm_tol` (clamped
/// to [`REFINEMENT_TOL_RANGE`]): the solves then stay four orders more accurate than the
/// iteration's own stopping test. On a 19.8k-dof unstructured mesh (ipm_tol = 1e-5) the
/// interior point takes 13.1 s at 1e-9 instead of 17.9 s with Clarabel's 1e-13, with the same
/// iterations and the same polished answer; 1e-7 (11.0 s there) lets the unpolished iteration
/// stagnate before 1e-5 on the small default scene.
pub const REFINEMENT_PER_IPM_TOL: f64 = 1e-4;

/// The range of the default refinement tolerance: never looser than 1e-7 (looser solves cost
/// interior-point iterations), never tighter than Clarabel's own 1e-13.
pub const REFINEMENT_TOL_RANGE: (f64, f64) = (1e-13, 1e-7);

/// With friction and no polish, the interior point's tolerance is this fraction of `tol`: its
/// gap and feasibility tolerances are absolute in the programme's units, the KKT residual of
/// theory §3.4 relative, and the nodes between stick and slip converge slowly. Measured on the
/// partial-slip scene of `tests/friction.rs`: the KKT residual is 1.2e-7 at ipm_tol = 1e-10 and
/// 2.8e-8 at 1e-13 (Clarabel's floor there); the default tol = 1e-8 is then not met, and says so.
pub const FRICTION_IPM_PER_TOL: f64 = 1e-5;

/// The default relative change of the normal multipliers that ends Coulomb's fixed point of
/// Tresca problems (theory §8.3). Measured on the partial-slip scene of `tests/friction.rs`
/// (μ = 0.3, ipm_tol = 1e-13): the change falls about 20× per solve (6 solves to 6e-9, 8 to
/// 1.2e-11), and tightening 1e-8 to 1e-10 leaves the answer's distance from uzawa's at 8.0e-8
/// in λ: beyond 1e-8 the interior point's own accuracy, not the fixed point, limits it.
pub const COULOMB_TOL: f64 = 1e-8;

/// The default cap on Coulomb's fixed-point iterations (each one interior point solve).
pub const COULOMB_MAX_ITER: usize = 50;

/// `type = "socp"`: the stress form of theory §3 as a second-order cone programme solved by
/// Clarabel (theory §4.4), polished by active-set Newton.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Socp {
    /// Relative KKT tolerance of the returned solution (after polishing).
    pub tol: f64,
    /// Clarabel's duality gap (absolute and relative) and feasibility tolerances. The polish
    /// sets the final accuracy (`tol`), so the interior point only needs to find the contact
    /// and plastic sets roughly: on a 19.8k-dof unstructured mesh 1e-2 costs 8 interior-point
    /// iterations and 4 polish steps (8.3 s) where 1e-8 costs 14 and 2 (15.2 s), with the same
    /// U to 1e-15 and a final KKT residual of 1.5e-13. Without polish, set it to the accuracy
    /// wanted (1e-8 or tighter).
    pub ipm_tol: f64,
    /// The relative tolerance of Clarabel's iterative refinement of each KKT solve (absent:
    /// with polish [`REFINEMENT_PER_IPM_TOL`] · `ipm_tol` clamped to [1e-13, 1e-7], without
    /// 1e-13; see [`Socp::refinement_tol`]). Clarabel's own default,
    /// 1e-13, spends a quarter of the interior point in refinement solves far more accurate
    /// than the iteration needs.
    pub ipm_refinement_tol: Option<f64>,
    /// Clarabel's iteration budget.
    pub ipm_max_iter: usize,
    /// Polish the interior point solution by active-set Newton.
    pub polish: bool,
    /// Newton's iteration budget for polishing.
    pub polish_max_iter: usize,
    /// Clarabel's threads (0: Clarabel chooses); 1 measured fastest on these problems.
    pub threads: usize,
    /// Coulomb's law (theory §8.3): the fixed point of Tresca problems (bounds g_i w_i := μ λ_n,i
    /// of the last solve) stops when no normal multiplier changes by more than this fraction of
    /// the largest one.
    pub coulomb_tol: f64,
    /// Coulomb's law: the cap on the fixed point's interior point solves; reaching it is
    /// reported (a warning, and the KKT residual of the last solve).
    pub coulomb_max_iter: usize,
}

impl Socp {
    /// The relative tolerance of Clarabel's iterative refinement: `ipm_refinement_tol`, or
    /// with polish [`REFINEMENT_PER_IPM_TOL`] · `ipm_tol` within [`REFINEMENT_TOL_RANGE`],
    /// without polish Clarabel's own 1e-13 (the interior point's answer is then the answer,
    /// and looser solves can make its last iterations stagnate).
    pub fn refinement_tol(&self) -> f64 {
        let (lo, hi) = REFINEMENT_TOL_RANGE;
        let auto = if self.polish { (REFINEMENT_PER_IPM_TOL * self.ipm_tol).clamp(lo, hi) } else { lo };
        self.ipm_refinement_tol.unwrap_or(auto)
    }
}

impl Default for Socp {
    fn default() -> Self {
        Self {
            tol: 1e-10,
            ipm_tol: 1e-2,
            ipm_refinement_tol: None,
            ipm_max_iter: 200,
            polish: true,
            polish_max_iter: 20,
            threads: 1,
            coulomb_tol: COULOMB_TOL,
            coulomb_max_iter: COULOMB_MAX_ITER,
        }
    }
}

#[typetag::serde(name = "socp")]
impl Solver for Socp {
    /// `tol` and `ipm_tol` in (0, 1); `ipm_max_iter` and `polish_max_iter` ≥ 1; all counts fit
    /// Clarabel's u32. Errors name `{path}.<field>` and the value.
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::open_interval(path, "tol", self.tol, 0.0, 1.0)?;
        check::open_interval(path, "ipm_tol", self.ipm_tol, 0.0, 1.0)?;
        check::open_interval(path, "coulomb_tol", self.coulomb_tol, 0.0, 1.0)?;
        if let Some(t) = self.ipm_refinement_tol {
            check::open_interval(path, "ipm_refinement_tol", t, 0.0, 1.0)?;
        }
        let count = |field: &str, v: usize, lo: usize| {
            if v < lo || v > u32::MAX as usize {
                Err(ParameterError::new(join(path, field), v, format!("must lie in [{lo}, {}]", u32::MAX)))
            } else {
                Ok(())
            }
        };
        count("ipm_max_iter", self.ipm_max_iter, 1)?;
        count("polish_max_iter", self.polish_max_iter, 1)?;
        count("coulomb_max_iter", self.coulomb_max_iter, 1)?;
        count("threads", self.threads, 0)?;
        Ok(())
    }

    /// The relative KKT tolerance of the returned solution.
    fn tolerance(&self) -> f64 {
        self.tol
    }

    /// Builds the cone programme, runs Clarabel, recovers (u, V, σ̂, λ) and polishes them, in
    /// stages.
    fn solve(&self, l: &Lagrangian<'_>, monitor: &mut dyn Monitor) -> Result<Solution, SolveError> {
        saddle_core::one_rank("socp", l)?;
        if l.data.rows.has_friction() && self.polish {
            return self.with_friction(l, monitor);
        }
        let mut timer = PhaseTimer::default();
        let (prog, ipm) = self.interior_point(l, monitor, &mut timer)?;
        beyond_collapse(l, &ipm)?;
        let found = Found::recover(l, &prog, &ipm, &mut timer);
        let r_ipm = found.kkt.max();
        monitor.iteration(ipm.iterations, r_ipm, self.tol);
        if !r_ipm.is_finite() {
            return Err(SolveError::NonFinite {
                solver: NAME.into(),
                what: "the KKT residual of the interior point solution".into(),
                iteration: ipm.iterations,
            });
        }
        let mut report = IpmReport::new(&prog, &ipm, r_ipm, found.return_mappings);
        if let Some((it, change)) = prog.coulomb.filter(|c| c.1 > self.coulomb_tol) {
            report.warnings.push(format!(
                "Coulomb's fixed point of Tresca problems (theory §8.3) stopped at solver.coulomb_max_iter = {it} with \
                 the normal multipliers still changing by {change:.2e} > solver.coulomb_tol = {:e}",
                self.coulomb_tol
            ));
        }
        if self.polish {
            self.polished(l, found, report, monitor, timer)
        } else {
            Ok(self.unpolished(found, report, timer))
        }
    }
}

impl Socp {
    /// With friction (theory §8.3) the polish (Newton from the interior point) is not wired: the
    /// interior point's answer is the answer, run to `min(ipm_tol, tol ×`
    /// [`FRICTION_IPM_PER_TOL`]`)` without polish (the report says so).
    fn with_friction(&self, l: &Lagrangian<'_>, monitor: &mut dyn Monitor) -> Result<Solution, SolveError> {
        let ipm_tol = self.ipm_tol.min(FRICTION_IPM_PER_TOL * self.tol);
        let unpolished = Socp { polish: false, ipm_tol, ..self.clone() };
        let mut sol = unpolished.solve(l, monitor)?;
        sol.report.warnings.push(format!(
            "friction: no polish (not wired for friction); the interior point ran to ipm_tol = {:e}",
            unpolished.ipm_tol
        ));
        Ok(sol)
    }

    /// Stage 1 (theory §4.4): the cone programme of `l` built and solved by Clarabel; an error
    /// if its solution is not finite.
    fn interior_point(
        &self,
        l: &Lagrangian<'_>,
        monitor: &mut dyn Monitor,
        timer: &mut PhaseTimer,
    ) -> Result<(ConeProgramme, IpmResult), SolveError> {
        monitor.phase("cone programme");
        let mut prog = timer.time("cone programme", || ConeProgramme::build(l))?;
        let quasi = l.data.rows.friction.quasi_law().is_some();
        if quasi {
            prog.set_radii(l, &vec![coulomb_start(l); l.data.rows.friction.blocks.len()]);
        }
        monitor.phase("interior point");
        let ipm = timer.time("interior point", || prog.solve(self))?;
        if quasi {
            sliding(l, &ipm, 0)?;
        }
        finite(&ipm)?;
        if !quasi {
            return Ok((prog, ipm));
        }
        let ipm = timer.time("interior point", || self.coulomb_fixed_point(l, &mut prog, ipm, monitor))?;
        Ok((prog, ipm))
    }

    /// Stage 1c (theory §8.3, a law whose bound depends on λ_n: Coulomb): the fixed point of
    /// Tresca problems. From the solve `ipm` (the first: bounds at [`coulomb_start`]), each
    /// disc's bound is set to the law's radius at the last solve's normal
    /// multiplier, r_i = μ λ_n,i, and the programme solved again, until no λ_n changes by more
    /// than `coulomb_tol` of the largest; at `coulomb_max_iter` solves the last one is returned
    /// with a warning in the programme's counters (its KKT residual then says how far it is).
    fn coulomb_fixed_point(
        &self,
        l: &Lagrangian<'_>,
        prog: &mut ConeProgramme,
        mut ipm: IpmResult,
        monitor: &mut dyn Monitor,
    ) -> Result<IpmResult, SolveError> {
        let mut normal = prog.normal_multipliers(l, &ipm);
        for it in 1..=self.coulomb_max_iter {
            prog.set_radii(l, &normal);
            ipm = prog.solve(self)?;
            sliding(l, &ipm, it)?;
            finite(&ipm)?;
            let next = prog.normal_multipliers(l, &ipm);
            let change = next.iter().zip(&normal).fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
            let size = next.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            normal = next;
            let relative = change / size.max(f64::MIN_POSITIVE);
            prog.coulomb = Some((it, relative));
            monitor.iteration(it, relative, self.coulomb_tol);
            if change <= self.coulomb_tol * size {
                break;
            }
        }
        Ok(ipm)
    }

    /// Stage 3a (theory §4.4, `polish = false`): the interior point's solution is the answer,
    /// converged if its residual meets `tol`.
    fn unpolished(&self, found: Found, mut ipm: IpmReport, timer: PhaseTimer) -> Solution {
        ipm.counters.insert("polish_iterations".into(), 0.0);
        let converged = ipm.residual <= self.tol;
        let stop_reason = match (converged, ipm.status) {
            (true, _) => StopReason::Converged,
            (false, SolverStatus::MaxIterations) => StopReason::MaxIterations,
            (false, _) => StopReason::Stagnated,
        };
        let report = SolveReport {
            solver: NAME.into(),
            converged,
            stop_reason,
            iterations: ipm.iterations,
            tolerance: self.tol,
            kkt: found.kkt,
            residual_history: vec![ipm.residual],
            phases: timer.into_phases(),
            counters: ipm.counters,
            warnings: ipm.warnings,
        };
        let Found { u, extras, stress, lambda, .. } = found;
        Solution { u, extras, stress, lambda, report, undetermined: Vec::new() }
    }

    /// Stage 3b (theory §4.4, polish): Newton (theory §4.2) from the interior point's (u, V, λ);
    /// the report joins both, the interior point's residual first in the history.
    fn polished(
        &self,
        l: &Lagrangian<'_>,
        found: Found,
        ipm: IpmReport,
        monitor: &mut dyn Monitor,
        mut timer: PhaseTimer,
    ) -> Result<Solution, SolveError> {
        let IpmReport { iterations, residual, mut counters, mut warnings, .. } = ipm;
        let newton = Newton { tol: self.tol, max_iter: self.polish_max_iter, line_search: true, ..Newton::default() };
        let start = Start { u: found.u, extras: found.extras, lambda: found.lambda };
        let mut sol = newton.solve_from(l, Some(start), monitor, &mut timer, NAME)?;
        let report = &mut sol.report;
        counters.insert("polish_iterations".into(), report.iterations as f64);
        // the return mappings of the residual above and of the polish
        let ipm_return_mappings = counters["return_mappings"];
        counters.append(&mut report.counters);
        *counters.entry("return_mappings".into()).or_insert(0.0) += ipm_return_mappings;
        report.counters = counters;
        report.residual_history.insert(0, residual);
        warnings.append(&mut report.warnings);
        report.warnings = warnings;
        report.iterations += iterations;
        Ok(sol)
    }
}

/// The normal force at which Coulomb's fixed point sets its first bounds (theory §8.3): the
/// largest prescribed force (on the extras or the body), a bound of every node's normal force
/// under one load, so that the first Tresca problem can balance a tangential load; 0 (the
/// frictionless problem) when every load is a prescribed motion.
fn coulomb_start(l: &Lagrangian<'_>) -> f64 {
    l.data.load.iter().chain(l.data.nodal_load).fold(0.0, |m, f| m.max(f.abs()))
}

/// Coulomb's fixed point (theory §8.3, §4.6): a Tresca problem of the fixed point (`iteration`
/// solves after the first) certified infeasible — no tangential forces within the discs
/// μ λ_n of the last normal forces balance the prescribed loads — is the error
/// [`SolveError::BeyondCollapse`]: the obstacle slides, the force-controlled problem has no
/// solution.
fn sliding(l: &Lagrangian<'_>, ipm: &IpmResult, iteration: usize) -> Result<(), SolveError> {
    if !matches!(ipm.status, SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible) || !l.forced() {
        return Ok(());
    }
    Err(SolveError::BeyondCollapse {
        solver: NAME.into(),
        evidence: format!(
            "Coulomb's fixed point (theory §8.3): after {iteration} update(s) of the friction discs to μ λ_n, \
             Clarabel certifies ({:?}) that no contact forces within them balance the loads: the tangential load \
             exceeds the friction μ Σλ_n the contact can give, and the obstacle slides",
            ipm.status
        ),
    })
}

/// An error unless the interior point's solution is finite.
fn finite(ipm: &IpmResult) -> Result<(), SolveError> {
    if ipm.x.iter().chain(&ipm.z).any(|v| !v.is_finite()) {
        return Err(SolveError::NonFinite {
            solver: NAME.into(),
            what: format!("the interior point solution (Clarabel status {:?})", ipm.status),
            iteration: ipm.iterations,
        });
    }
    Ok(())
}

/// Stage 1b (theory §4.6): Clarabel's certificate that the cone programme is infeasible —
/// no stress in P balances the prescribed forces on a plastic body — is the error
/// [`SolveError::BeyondCollapse`]: the certificate is a collapse mechanism, once the body is
/// known to be held (else the singular elastic stiffness's error: no body without supports
/// carries a force). Otherwise `Ok`.
fn beyond_collapse(l: &Lagrangian<'_>, ipm: &IpmResult) -> Result<(), SolveError> {
    let infeasible = matches!(ipm.status, SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible);
    if !(infeasible && l.data.plasticity().is_some() && l.forced()) {
        return Ok(());
    }
    let k = l.stiffness(Material::Uniform(&l.data.elasticity.stiffness_matrix()));
    linear::analyse(l.pattern(), "elastic stiffness", NAME, &mut 0)?.factorise(&k).in_solver(NAME)?;
    Err(SolveError::BeyondCollapse {
        solver: NAME.into(),
        evidence: format!(
            "the conic solver certifies that no stress in P balances the loads (Clarabel {:?} after {} iterations; \
             its certificate is a collapse mechanism whose loads' power exceeds its plastic dissipation)",
            ipm.status, ipm.iterations
        ),
    })
}

/// The interior point's solution in the units of `l`, with the residual of theory §3.4.
struct Found {
    u: Vec<f64>,
    extras: Vec<f64>,
    /// σ̂ from Clarabel's x, with the plastic flags of the local law at ε(u).
    stress: StressField,
    lambda: Vec<f64>,
    /// The KKT residuals of (u, V, σ̂, λ).
    kkt: KktResiduals,
    /// Points at which P's return mapping ran for σ(u).
    return_mappings: usize,
}

impl Found {
    /// Stage 2 (theory §4.4, primal from dual; theory §3.4): (u, V, σ̂, λ) from Clarabel's x and
    /// z, and their residual with σ(u) by the local law.
    fn recover(l: &Lagrangian<'_>, prog: &ConeProgramme, ipm: &IpmResult, timer: &mut PhaseTimer) -> Self {
        let (u, extras, mut stress, lambda) = prog.recover(l, ipm);
        let mut ws = Workspace::new(l);
        let (law, kkt) = timer.time("residual", || {
            l.strain(&u, &mut ws.eps);
            let law = l.data.local_law(&ws.eps, &mut ws.stress, None);
            (law, kkt_with_stress(l, &Iterate { u: &u, extras: &extras, stress: &stress, lambda: &lambda }, &mut ws))
        });
        stress.plastic.clone_from(&ws.stress.plastic);
        Self { u, extras, stress, lambda, kkt, return_mappings: law.projected }
    }
}

/// The interior point's part of the report.
struct IpmReport {
    /// Clarabel's iterations and status.
    iterations: usize,
    status: SolverStatus,
    /// The relative KKT residual of its solution.
    residual: f64,
    counters: BTreeMap<String, f64>,
    warnings: Vec<String>,
}

impl IpmReport {
    /// The sizes and scales of `prog`, Clarabel's figures from `ipm` in the units of the scene,
    /// the residual `r_ipm` and the `return_mappings` of σ(u); a warning unless Clarabel solved.
    fn new(prog: &ConeProgramme, ipm: &IpmResult, r_ipm: f64, return_mappings: usize) -> Self {
        let mut counters = prog.counters();
        let mut put = |k: &str, x: f64| counters.insert(k.to_string(), x);
        put("ipm_iterations", ipm.iterations as f64);
        put("ipm_duality_gap", ipm.gap_abs * prog.scales.energy());
        put("ipm_relative_gap", ipm.gap_rel);
        put("ipm_objective", ipm.objective * prog.scales.energy());
        put("ipm_primal_residual", ipm.r_prim);
        put("ipm_dual_residual", ipm.r_dual);
        put("ipm_kkt_residual", r_ipm);
        put("ipm_status", ipm.status as u32 as f64);
        put("return_mappings", return_mappings as f64);
        let mut warnings = Vec::new();
        if ipm.status != SolverStatus::Solved {
            warnings.push(format!("the interior point method ended {:?} (status {})", ipm.status, ipm.status as u32));
        }
        Self { iterations: ipm.iterations, status: ipm.status, residual: r_ipm, counters, warnings }
    }
}

/// The scales of the non-dimensionalisation (module docs): stress S, length L, stiffness E.
#[derive(Clone, Copy, Debug)]
struct Scales {
    /// S.
    stress: f64,
    /// L = (Σ_T w_T)^{1/3}.
    length: f64,
    /// E.
    stiffness: f64,
}

impl Scales {
    /// Stage 4 (theory §4.4, units): L = (Σ_T w_T)^{1/3}; S the largest offset of the cone
    /// `blocks`, else max|f|/L², else E·10⁻³; E Young's modulus. An error without volume.
    fn new(l: &Lagrangian<'_>, blocks: &[SocBlock]) -> Result<Self, SolveError> {
        let young = l.data.elasticity.young;
        let volume: f64 = l.weights().iter().sum();
        if !(volume.is_finite() && volume > 0.0) {
            return Err(unsupported(format!("the total weight of the stress points is {volume}: nothing to solve")));
        }
        let length = volume.cbrt();
        let offsets = blocks.iter().flat_map(|b| b.offset.iter()).fold(0.0f64, |m, v| m.max(v.abs()));
        let fmax = l.data.load.iter().chain(l.data.nodal_load).fold(0.0f64, |m, v| m.max(v.abs()));
        let stress = if offsets > 0.0 {
            offsets
        } else if fmax > 0.0 {
            fmax / (length * length)
        } else {
            1e-3 * young
        };
        Ok(Self { stress, length, stiffness: young })
    }

    /// D = S L / E.
    fn displacement(&self) -> f64 {
        self.stress * self.length / self.stiffness
    }

    /// S L².
    fn force(&self) -> f64 {
        self.stress * self.length * self.length
    }

    /// S² L³ / E = force × displacement.
    fn energy(&self) -> f64 {
        self.force() * self.displacement()
    }
}

/// Where the unknowns of theory §3 form 3 sit in Clarabel's x and z.
#[derive(Clone, Debug)]
struct Layout {
    /// Stress points.
    n_points: usize,
    /// Hardening variables per point in the Lagrangian.
    q_dim: usize,
    /// The hardening variables kept (finite metric); the others are fixed at 0.
    free_q: Vec<usize>,
    /// Free displacement dofs (equilibrium rows).
    n_dofs: usize,
    /// Extra unknowns (load rows).
    n_extras: usize,
    /// Rows of K_h (λ columns).
    n_rows: usize,
    /// The constraint row of each λ_i in the contact block: its sign row (normal rows,
    /// nonnegative cone) or its entry of its node's friction disc (theory §8.3).
    sign_row: Vec<usize>,
    /// Normal rows (the nonnegative cone's dimension).
    n_normal: usize,
    /// Each friction disc's first constraint row and radius (the law's at λ_n = 0; Coulomb's
    /// fixed point resets them).
    discs: Vec<(usize, f64)>,
    /// Second-order cones.
    n_soc: usize,
}

/// B as explicit entries (point, Mandel component, dof, value).
type StrainEntry = (usize, usize, usize, f64);

impl Layout {
    /// Stage 3 (theory §4.4, the layout of the variables): x = [(σ_T, kept q_T) per point, λ],
    /// with the kept hardening variables `free_q` and `n_blocks` cones per point.
    /// The contact block's rows (theory §4.4 block 3, §8.3): first the normal rows' sign rows
    /// (all rows without friction), then a disc (R_b; λ_t1, λ_t2) per friction block.
    fn new(l: &Lagrangian<'_>, free_q: Vec<usize>, n_blocks: usize) -> Self {
        let rows = l.data.rows;
        let (nr, row0) = (rows.n_rows(), l.n_dofs() + l.n_extras());
        let tangential = rows.friction.tangential_mask(nr);
        let mut sign_row = vec![0; nr];
        let mut next = row0;
        for i in (0..nr).filter(|&i| !tangential[i]) {
            sign_row[i] = next;
            next += 1;
        }
        let n_normal = next - row0;
        let mut discs = Vec::with_capacity(rows.friction.blocks.len());
        for b in &rows.friction.blocks {
            discs.push((next, rows.friction.law(b).radius(b.weight, 0.0)));
            (sign_row[b.tangent], sign_row[b.tangent + 1]) = (next + 1, next + 2);
            next += 3;
        }
        Self {
            n_points: l.n_points(),
            q_dim: l.data.hardening_dim(),
            free_q,
            n_dofs: l.n_dofs(),
            n_extras: l.n_extras(),
            n_rows: nr,
            sign_row,
            n_normal,
            n_soc: l.n_points() * n_blocks + discs.len(),
            discs,
        }
    }

    /// Constraint rows of the contact block: a sign row per normal row, three per disc.
    fn n_contact_rows(&self) -> usize {
        self.n_normal + 3 * self.discs.len()
    }

    /// The hardening variables fixed at their state value (infinite metric).
    fn fixed_q(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.q_dim).filter(|k| !self.free_q.contains(k))
    }

    /// The nonzeros of A: `n_strain` entries of B, the rows' G, H and signs, the cone maps.
    fn constraint_nonzeros(&self, l: &Lagrangian<'_>, n_strain: usize, cone_map: &ConeMap) -> usize {
        let (ne, nr) = (self.n_extras, self.n_rows);
        n_strain + l.data.rows.val.len() + nr * ne + nr + self.n_points * cone_map.entries.len()
    }

    /// Columns per point: σ (6) and the kept q.
    fn stride(&self) -> usize {
        6 + self.free_q.len()
    }

    /// Column of entry `c` of (σ, kept q) at point `t`.
    fn point_col(&self, t: usize, c: usize) -> usize {
        t * self.stride() + c
    }

    /// Column of λ_i.
    fn lambda_col(&self, i: usize) -> usize {
        self.n_points * self.stride() + i
    }

    /// Number of variables.
    fn n_vars(&self) -> usize {
        self.n_points * self.stride() + self.n_rows
    }
}

/// The non-dimensional cone programme in Clarabel's standard form (module docs).
struct ConeProgramme {
    /// P, upper triangle.
    p: CscMatrix<f64>,
    /// Linear term of the objective.
    q: Vec<f64>,
    /// Constraint matrix.
    a: CscMatrix<f64>,
    /// Right-hand side.
    b: Vec<f64>,
    /// Cones of the row blocks.
    cones: Vec<SupportedConeT<f64>>,
    /// Units.
    scales: Scales,
    /// Positions of the unknowns.
    layout: Layout,
    /// Coulomb's fixed point (theory §8.3): its solves after the first and the last relative
    /// change of the normal multipliers; `None` for laws with a given bound.
    coulomb: Option<(usize, f64)>,
}

/// The cone programme that `socp` hands Clarabel for `l` (theory §4.4, module docs), as JSON,
/// for other conic solvers (`examples/export_cone.rs`, the cvxpy comparison of
/// `examples/peers/`): `{"n", "m", "P": {"colptr", "rowval", "nzval"} (upper triangle, CSC),
/// "q", "A": {…} (m × n, CSC), "b", "cones": [["zero" | "nonneg" | "soc", dim], …]}` for
/// minimise ½xᵀPx + qᵀx subject to Ax + s = b, s in the cones (rows in order), non-dimensional.
pub fn cone_programme_json(l: &Lagrangian<'_>) -> Result<String, SolveError> {
    let prog = ConeProgramme::build(l)?;
    Ok(programme_json(&prog.p, &prog.q, &prog.a, &prog.b, &prog.cones))
}

/// What Clarabel returned, still non-dimensional.
struct IpmResult {
    /// Termination status.
    status: SolverStatus,
    /// Iterations.
    iterations: usize,
    /// Absolute duality gap.
    gap_abs: f64,
    /// Relative duality gap.
    gap_rel: f64,
    /// Primal objective.
    objective: f64,
    /// Clarabel's relative primal residual.
    r_prim: f64,
    /// Clarabel's relative dual residual.
    r_dual: f64,
    /// Primal solution.
    x: Vec<f64>,
    /// Dual solution.
    z: Vec<f64>,
}

/// The unsupported-problem error of this solver.
fn unsupported(message: String) -> SolveError {
    SolveError::Unsupported { solver: NAME.into(), message }
}

/// A unit vector of length `n` in direction `k`.
fn unit(n: usize, k: usize) -> [f64; MAX_HARDENING_DIM] {
    let mut e = [0.0; MAX_HARDENING_DIM];
    if k < n {
        e[k] = 1.0;
    }
    e
}

/// Checks a cone block's sizes against the point's (σ, q) dimension `width`.
fn check_block(name: &str, k: usize, blk: &SocBlock, width: usize) -> Result<(), SolveError> {
    if blk.dim == 0 || blk.offset.len() != blk.dim || blk.map.len() != blk.dim * width {
        return Err(unsupported(format!(
            "cone block {k} of the yield surface `{name}` is malformed: dim {}, {} offsets, {} map entries \
             (expected dim ≥ 1, dim offsets and dim × {width} map entries)",
            blk.dim,
            blk.offset.len(),
            blk.map.len()
        )));
    }
    if blk.offset.iter().chain(&blk.map).any(|v| !v.is_finite()) {
        return Err(unsupported(format!("cone block {k} of the yield surface `{name}` has non-finite entries")));
    }
    Ok(())
}

/// Stage 1 (theory §4.4, the cone blocks): the second-order cones of P's set D at one point
/// (none for an elastic problem), checked; an error if D has none.
fn yield_cones(l: &Lagrangian<'_>) -> Result<Vec<SocBlock>, SolveError> {
    let Some(p) = l.data.plasticity() else {
        return Ok(Vec::new());
    };
    let cone = p.cone().ok_or_else(|| {
        unsupported(format!(
            "cannot solve the yield surface `{}`: {} (AdmissibleStresses::cone is None); \
             use newton, uzawa or penalty, which need only the projection onto D",
            p.name(),
            p.cone_unavailable()
        ))
    })?;
    let width = 6 + l.data.hardening_dim();
    for (k, blk) in cone.blocks.iter().enumerate() {
        check_block(p.name(), k, blk, width)?;
    }
    Ok(cone.blocks)
}

/// Stage 2 (theory §4.4, perfect plasticity): the hardening variables kept — those of finite
/// metric; an infinite one fixes q_k (module docs) — and the metric H⁻¹ on them, row-major.
fn hardening_metric(l: &Lagrangian<'_>) -> Result<(Vec<usize>, Vec<f64>), SolveError> {
    let q_dim = l.data.hardening_dim();
    let mut free_q = Vec::with_capacity(q_dim);
    let Some(p) = l.data.plasticity() else {
        return Ok((free_q, Vec::new()));
    };
    let inner = |a: usize, b: usize| p.hardening_inner(&unit(q_dim, a)[..q_dim], &unit(q_dim, b)[..q_dim]);
    for k in 0..q_dim {
        let d = inner(k, k);
        if d == f64::INFINITY {
            continue;
        }
        if !(d.is_finite() && d > 0.0) {
            return Err(unsupported(format!(
                "the hardening metric of `{}` is {d} on variable {k}: it must be positive (or +∞ to fix it)",
                p.name()
            )));
        }
        free_q.push(k);
    }
    let hinv = free_q.iter().flat_map(|&a| free_q.iter().map(move |&b| inner(a, b))).collect();
    Ok((free_q, hinv))
}

/// Stage 5 (theory §4.4, the objective's quadratic term): P per point, (w/L³)·E·A on σ and
/// (w/L³)·E·H⁻¹ on the kept q, upper triangle.
fn quadratic_term(l: &Lagrangian<'_>, layout: &Layout, hinv: &[f64], scales: &Scales) -> CscMatrix<f64> {
    let law = *l.data.elasticity;
    // E·A on the unit vectors: columns of a symmetric matrix, so also its rows
    let compliance: [Sym; 6] = std::array::from_fn(|j| {
        let mut e = Sym::zeros();
        e[j] = 1.0;
        law.compliance(&e) * law.young
    });
    let nq = layout.free_q.len();
    let mut p = Triplets::with_capacity(layout.n_points * (21 + nq * (nq + 1) / 2));
    let vol_scale = scales.length * scales.length * scales.length;
    for (t, wt) in l.weights().iter().enumerate() {
        let wt = wt / vol_scale;
        for (a, row) in compliance.iter().enumerate() {
            for (b, e_ab) in row.iter().enumerate().skip(a) {
                p.push_nonzero(layout.point_col(t, a), layout.point_col(t, b), wt * e_ab);
            }
        }
        for a in 0..nq {
            for b in a..nq {
                let v = wt * law.young * hinv[a * nq + b];
                p.push_nonzero(layout.point_col(t, 6 + a), layout.point_col(t, 6 + b), v);
            }
        }
    }
    p.into_csc(layout.n_vars(), layout.n_vars())
}

/// Stage 6 (theory §4.4, the objective's linear term): the obstacle offsets c_i on λ, and for a
/// load step's state (theory §11.1), whose objective ½Aσ:σ + ½(q − q_n)·H⁻¹(q − q_n) + (ε_p, σ)
/// adds w ε_p·σ and −w q_n·H⁻¹q (scaled as P).
fn linear_term(l: &Lagrangian<'_>, layout: &Layout, hinv: &[f64], scales: &Scales) -> Vec<f64> {
    let mut q = vec![0.0; layout.n_vars()];
    let s_d = scales.displacement();
    for (i, c) in l.data.rows.offset.iter().enumerate() {
        q[layout.lambda_col(i)] = c / s_d;
    }
    let Some(st) = l.data.state else {
        return q;
    };
    let (young, stress, nq) = (l.data.elasticity.young, scales.stress, layout.free_q.len());
    let vol_scale = scales.length * scales.length * scales.length;
    for (t, wt) in l.weights().iter().enumerate() {
        let wt = wt / vol_scale;
        for c in 0..6 {
            q[layout.point_col(t, c)] = wt * young / stress * st.plastic_strain[t][c];
        }
        let qn = st.q(t);
        for (a, _) in layout.free_q.iter().enumerate() {
            let lin: f64 = layout.free_q.iter().enumerate().map(|(b, &k)| hinv[a * nq + b] * qn[k]).sum();
            q[layout.point_col(t, 6 + a)] = -wt * young * lin / stress;
        }
    }
    q
}

/// Stage 8 (theory §4.4, constraint block 1, equilibrium): the columns of σ in the rows of the
/// free dofs, Σ_T w_T B_Tᵀσ_T (scaled by 1/L²).
/// `strain` holds B's entries ([`saddle_core::ElementOperators::strain_entries`]).
fn equilibrium_rows(l: &Lagrangian<'_>, strain: Vec<StrainEntry>, layout: &Layout, scales: &Scales, a: &mut Triplets) {
    let (w, len2) = (l.weights(), scales.length * scales.length);
    for (t, c, j, v) in strain {
        a.push(j, layout.point_col(t, c), w[t] * v / len2);
    }
}

/// Stage 9 (theory §4.4, the contact rows): the column of each λ_i, −G_iᵀ in the equilibrium
/// rows (block 1), −H_iᵀ in the load rows (block 2) and −1 in its sign row or its friction
/// disc (block 3, theory §8.3).
fn contact_columns(l: &Lagrangian<'_>, layout: &Layout, a: &mut Triplets) {
    let rows = l.data.rows;
    let n = layout.n_dofs;
    for i in 0..layout.n_rows {
        let col = layout.lambda_col(i);
        let (cols, vals) = rows.row(i);
        for (&j, &g) in cols.iter().zip(vals) {
            a.push(j, col, -g);
        }
        for (k, &h) in rows.extra_row(i).iter().enumerate() {
            if h != 0.0 {
                a.push(n + k, col, -h);
            }
        }
        a.push(layout.sign_row[i], col, -1.0);
    }
}

/// Stage 10 (theory §4.4, constraint block 4): each point's cone maps on its (σ, kept q), in the
/// rows after the equilibrium, load and sign rows.
fn cone_rows(layout: &Layout, cone_map: &ConeMap, a: &mut Triplets) {
    let cone_row0 = layout.n_dofs + layout.n_extras + layout.n_contact_rows();
    for t in 0..layout.n_points {
        let row0 = cone_row0 + t * cone_map.rows;
        for &(r, c, v) in &cone_map.entries {
            a.push(row0 + r, layout.point_col(t, c), v);
        }
    }
}

/// Stage 11 (theory §4.4, the right-hand side b of length `m`): the loads f_u and f in the
/// equilibrium and load rows, and each point's cone offsets, into which a fixed hardening
/// variable moves with its state value q_n (0 without a state).
fn right_hand_side(l: &Lagrangian<'_>, layout: &Layout, blocks: &[SocBlock], scales: &Scales, m: usize) -> Vec<f64> {
    let (n, ne, s_f) = (layout.n_dofs, layout.n_extras, scales.force());
    let mut b = vec![0.0; m];
    for (j, f) in l.data.nodal_load.iter().enumerate() {
        b[j] = f / s_f;
    }
    for (k, f) in l.data.load.iter().enumerate() {
        b[n + k] = f / s_f;
    }
    for &(row, radius) in &layout.discs {
        b[row] = radius / s_f;
    }
    let width = 6 + layout.q_dim;
    let mut r0 = n + ne + layout.n_contact_rows();
    for t in 0..layout.n_points {
        let fixed: Vec<(usize, f64)> = match l.data.state {
            Some(st) => layout.fixed_q().map(|k| (k, st.q(t)[k])).collect(),
            None => Vec::new(),
        };
        for blk in blocks {
            for (r, (bi, o)) in b[r0..r0 + blk.dim].iter_mut().zip(&blk.offset).enumerate() {
                let shift: f64 = fixed.iter().map(|&(k, qk)| blk.map[r * width + 6 + k] * qk).sum();
                *bi = (o + shift) / scales.stress;
            }
            r0 += blk.dim;
        }
    }
    b
}

/// Stage 12 (theory §4.4): the cones of the row blocks in order — zero (equilibrium and load
/// rows), nonnegative (λ ≥ 0 on the normal rows), a 3-dimensional second-order cone per
/// friction disc (|λ_t| ≤ R, theory §8.3), and P's second-order cones at every point.
fn cones(layout: &Layout, blocks: &[SocBlock]) -> Vec<SupportedConeT<f64>> {
    let (n, ne) = (layout.n_dofs, layout.n_extras);
    let mut cones = Vec::with_capacity(2 + layout.n_soc);
    if n + ne > 0 {
        cones.push(ZeroConeT(n + ne));
    }
    if layout.n_normal > 0 {
        cones.push(NonnegativeConeT(layout.n_normal));
    }
    cones.extend(layout.discs.iter().map(|_| SecondOrderConeT(3)));
    for _ in 0..layout.n_points {
        cones.extend(blocks.iter().map(|blk| SecondOrderConeT(blk.dim)));
    }
    cones
}

/// The cone maps of one point on its kept columns, negated (s = b − A x): (row, local column,
/// value) over all blocks, and the number of rows.
struct ConeMap {
    entries: Vec<(usize, usize, f64)>,
    rows: usize,
}

impl ConeMap {
    /// Stage 7 (theory §4.4, the cone blocks per yield surface): the maps of `blocks` on (σ, q),
    /// with the columns of fixed hardening variables dropped.
    fn new(blocks: &[SocBlock], layout: &Layout) -> Self {
        let width = 6 + layout.q_dim;
        let mut local_col = [usize::MAX; 6 + MAX_HARDENING_DIM];
        for (c, lc) in local_col.iter_mut().enumerate().take(6) {
            *lc = c;
        }
        for (kk, &k) in layout.free_q.iter().enumerate() {
            local_col[6 + k] = 6 + kk;
        }
        let (mut entries, mut rows) = (Vec::new(), 0);
        for blk in blocks {
            for (r, map_row) in blk.map.chunks_exact(width).enumerate() {
                for (&v, &c) in map_row.iter().zip(&local_col) {
                    if v != 0.0 && c != usize::MAX {
                        entries.push((rows + r, c, -v));
                    }
                }
            }
            rows += blk.dim;
        }
        Self { entries, rows }
    }
}

impl ConeProgramme {
    /// Builds the programme of theory §3 form 3 for `l`, non-dimensionalised (module docs), in
    /// stages: P's cones and hardening metric, the layout of x, the units, the objective, the
    /// constraints and their cones. A friction law whose radius depends on λ_n (Coulomb) gets
    /// the discs of λ_n = 0 ([`Socp::coulomb_fixed_point`] sets them).
    fn build(l: &Lagrangian<'_>) -> Result<Self, SolveError> {
        let blocks = yield_cones(l)?;
        let (free_q, hinv) = hardening_metric(l)?;
        let layout = Layout::new(l, free_q, blocks.len());
        let scales = Scales::new(l, &blocks)?;
        let p = quadratic_term(l, &layout, &hinv, &scales);
        let q = linear_term(l, &layout, &hinv, &scales);
        let cone_map = ConeMap::new(&blocks, &layout);
        let strain = l.strain_entries();
        let mut a = Triplets::with_capacity(layout.constraint_nonzeros(l, strain.len(), &cone_map));
        equilibrium_rows(l, strain, &layout, &scales, &mut a);
        contact_columns(l, &layout, &mut a);
        cone_rows(&layout, &cone_map, &mut a);
        let m = layout.n_dofs + layout.n_extras + layout.n_contact_rows() + layout.n_points * cone_map.rows;
        let a = a.into_csc(m, layout.n_vars());
        let b = right_hand_side(l, &layout, &blocks, &scales, m);
        let cones = cones(&layout, &blocks);
        Ok(Self { p, q, a, b, cones, scales, layout, coulomb: None })
    }

    /// Runs Clarabel with the settings of `s`.
    fn solve(&self, s: &Socp) -> Result<IpmResult, SolveError> {
        let settings = DefaultSettingsBuilder::default()
            .direct_solve_method("faer".to_owned())
            .max_threads(s.threads as u32)
            .verbose(false)
            .equilibrate_enable(true)
            .iterative_refinement_reltol(s.refinement_tol())
            .tol_gap_abs(s.ipm_tol)
            .tol_gap_rel(s.ipm_tol)
            .tol_feas(s.ipm_tol)
            .max_iter(s.ipm_max_iter as u32)
            .build()
            .map_err(|e| unsupported(format!("Clarabel settings rejected: {e}")))?;
        let mut solver = DefaultSolver::new(&self.p, &self.q, &self.a, &self.b, &self.cones, settings)
            .map_err(|e| unsupported(format!("Clarabel rejected the cone programme: {e}")))?;
        solver.solve();
        let sol = &solver.solution;
        Ok(IpmResult {
            status: sol.status,
            iterations: sol.iterations as usize,
            gap_abs: solver.info.gap_abs,
            gap_rel: solver.info.gap_rel,
            objective: sol.obj_val,
            r_prim: sol.r_prim,
            r_dual: sol.r_dual,
            x: sol.x.clone(),
            z: sol.z.clone(),
        })
    }

    /// (u, V, σ̂, λ) in the units of `l` from Clarabel's x and z: σ̂ and λ from x, u = −z_eq and
    /// V = −z_load (module docs). The plastic flags are left false.
    fn recover(&self, l: &Lagrangian<'_>, r: &IpmResult) -> (Vec<f64>, Vec<f64>, StressField, Vec<f64>) {
        let lay = &self.layout;
        let (s, d, f) = (self.scales.stress, self.scales.displacement(), self.scales.force());
        let u: Vec<f64> = r.z[..lay.n_dofs].iter().map(|z| -d * z).collect();
        let extras: Vec<f64> = r.z[lay.n_dofs..lay.n_dofs + lay.n_extras].iter().map(|z| -d * z).collect();
        let lambda: Vec<f64> = (0..lay.n_rows).map(|i| f * r.x[lay.lambda_col(i)]).collect();
        let mut stress = StressField::new(l.n_points(), lay.q_dim);
        let stride = stress.q.stride();
        for t in 0..lay.n_points {
            for c in 0..6 {
                stress.sigma[t][c] = s * r.x[lay.point_col(t, c)];
            }
            for (kk, &k) in lay.free_q.iter().enumerate() {
                stress.q[t * stride + k] = s * r.x[lay.point_col(t, 6 + kk)];
            }
            // fixed hardening variables stay at the state's value (theory §11.1)
            if let Some(st) = l.data.state {
                for k in lay.fixed_q() {
                    stress.q[t * stride + k] = st.q(t)[k];
                }
            }
        }
        (u, extras, stress, lambda)
    }

    /// The normal multiplier λ_n of every friction block (in the units of `l`) of the solve `r`.
    fn normal_multipliers(&self, l: &Lagrangian<'_>, r: &IpmResult) -> Vec<f64> {
        let f = self.scales.force();
        l.data.rows.friction.blocks.iter().map(|b| f * r.x[self.layout.lambda_col(b.normal)]).collect()
    }

    /// Each friction disc's bound set to its law's radius at the normal multiplier `normal` of
    /// its block (theory §8.3: the Tresca problem of Coulomb's fixed point).
    fn set_radii(&mut self, l: &Lagrangian<'_>, normal: &[f64]) {
        let fr = &l.data.rows.friction;
        let s_f = self.scales.force();
        for ((disc, b), &ln) in self.layout.discs.iter_mut().zip(&fr.blocks).zip(normal) {
            disc.1 = fr.law(b).radius(b.weight, ln);
            self.b[disc.0] = disc.1 / s_f;
        }
    }

    /// Sizes and scales of the programme, for the report.
    fn counters(&self) -> BTreeMap<String, f64> {
        let lay = &self.layout;
        let mut c = BTreeMap::new();
        if let Some((iterations, change)) = self.coulomb {
            c.insert("coulomb_iterations".into(), iterations as f64);
            c.insert("coulomb_change".into(), change);
        }
        c.insert("ipm_variables".into(), lay.n_vars() as f64);
        c.insert("ipm_constraints".into(), self.b.len() as f64);
        c.insert("ipm_soc_cones".into(), lay.n_soc as f64);
        c.insert("ipm_fixed_hardening_variables".into(), (lay.q_dim - lay.free_q.len()) as f64);
        c.insert("scale_stress".into(), self.scales.stress);
        c.insert("scale_length".into(), self.scales.length);
        c.insert("scale_displacement".into(), self.scales.displacement());
        c
    }
}
