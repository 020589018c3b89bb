//! Work–precision runs (theory §4, §5): every solver along a ladder of settings on one mesh, each
//! run timed and compared with a tightly converged reference of the same discrete problem.
//!
//! Errors (theory §5), all relative to the reference:
//! * the quantity of interest q (the scene's first extra unknown, or one named by `--quantity`;
//!   [`crate::io::summary::named_quantity`]): |q − q_ref| / |q_ref|; where q is not finite at
//!   both, the largest over the extra unknowns (without extras the max-norm of u), as in
//!   [`saddle_solvers::conformance::agreement`];
//! * σ̂: [σ̂ − σ̂_ref]^{1/2} / [σ̂_ref]^{1/2} in the energy norm of theory §1
//!   ([`saddle_solvers::conformance::energy_distance`]) — the σ̂ the solver returns;
//! * ε(u): ‖ε(u − u_ref)‖_{L²} / ‖ε(u_ref)‖_{L²}, element volumes as weights.
//!
//! The KKT residual is recomputed from the returned solution by L, independently of the solver.

use super::transfer::{l2_distance, strains};
use crate::io::summary::named_quantity;
use saddle_core::{
    DiscreteProblem, Lagrangian, Monitor, PhaseTimer, Solution, SolveError, Solver, StopReason, Workspace, kkt,
};
use saddle_solvers::conformance::agreement;
use saddle_solvers::{Newton, Penalty, Start, Uzawa};
use std::time::Instant;

/// The reference: semismooth Newton to a relative KKT residual of 1e-13.
pub fn reference_solver() -> Newton {
    // the direct backend: exact linear solves down to round-off
    Newton {
        tol: 1e-13,
        max_iter: 50,
        line_search: true,
        linear: saddle_solvers::LinearSolver::Direct,
        ..Newton::default()
    }
}

/// A level of a mesh convergence study: the reference's Newton to 1e-13 on `auto`'s linear
/// backend (theory §4.2), which takes the multigrid where a factor would not fit (the default
/// scene's P2 level of 741k dofs needs a 36 GB factor).
pub fn level_solver() -> Newton {
    Newton { linear: saddle_solvers::LinearSolver::Auto, ..reference_solver() }
}

/// What a rung runs.
#[derive(Debug)]
pub enum RungKind {
    /// A solver.
    Solve(Box<dyn Solver>),
    /// Newton polishing started from the solution of rung `from`, its time added to that
    /// rung's: exactly what `socp` with `polish = true` does after its interior point
    /// (`Newton { tol, max_iter: polish_max_iter, line_search: true }` from the recovered
    /// (u, U, λ)), without paying for the interior point twice.
    Polish {
        /// The rung whose solution starts the polish.
        from: usize,
        /// The polishing Newton.
        newton: Newton,
    },
    /// The reference run itself (not repeated): its row reports error 0 by definition.
    Reference,
}

/// One setting of one solver.
#[derive(Debug)]
pub struct Rung {
    /// The solver's type name.
    pub solver: &'static str,
    /// Its setting, as scene parameters (`tol = 1e-4`).
    pub setting: String,
    /// What to run.
    pub kind: RungKind,
}

impl Rung {
    /// `solver setting`.
    pub fn label(&self) -> String {
        format!("{} {}", self.solver, self.setting)
    }

    fn solve(solver: &'static str, setting: String, s: impl Solver + 'static) -> Self {
        Self { solver, setting, kind: RungKind::Solve(Box::new(s)) }
    }
}

/// The ladder of settings of every solver. Costs on the default scene (45k dofs, 2 cores):
/// Uzawa 5–8 s a run (one factorisation, then cheap iterations), Newton and penalty 18–20 s
/// (about a dozen factorisations whatever the tolerance), SOCP ~100 s of interior point
/// whatever its tolerance — so SOCP gets one interior point run, reported alone and polished.
/// `quick` keeps two rungs per solver (tests, CI).
pub fn ladder(quick: bool) -> Vec<Rung> {
    let mut rungs = Vec::new();
    let uzawa_tols: &[f64] = if quick { &[1e-3, 1e-8] } else { &[1e-2, 1e-4, 1e-6, 1e-8, 1e-10] };
    for &tol in uzawa_tols {
        rungs.push(Rung::solve("uzawa", format!("tol = {tol:.0e}"), Uzawa { tol, ..Uzawa::default() }));
    }
    let newton_tols: &[f64] = if quick { &[1e-2] } else { &[1e-1, 1e-2, 1e-4] };
    for &tol in newton_tols {
        rungs.push(Rung::solve("newton", format!("tol = {tol:.0e}"), Newton { tol, ..Newton::default() }));
    }
    let r = reference_solver();
    rungs.push(Rung {
        solver: "newton",
        setting: format!("tol = {:.0e} (reference)", r.tol),
        kind: RungKind::Reference,
    });
    // the penalty's error is O(μ) (true KKT ≈ 4.4μ on the default scene): its tolerance on the
    // true residual is set to 100μ, so that each rung converges to its own approximation
    let mus: &[f64] = if quick { &[1e-4, 1e-10] } else { &[1e-2, 1e-4, 1e-6, 1e-9, 1e-12] };
    for &mu in mus {
        let tol = (100.0 * mu).min(0.5);
        rungs.push(Rung::solve(
            "penalty",
            format!("mu = {mu:.0e}, tol = {tol:.0e}"),
            Penalty { mu, tol, ..Penalty::default() },
        ));
    }
    #[cfg(feature = "socp")]
    {
        use saddle_solvers::Socp;
        let base = Socp::default();
        // the interior point alone (to 1e-8, as a user without polish would ask) reaches a KKT
        // residual of ~1e-5: judged against 1e-4
        let ipm = Socp { polish: false, tol: 1e-4, ipm_tol: 1e-8, ..base.clone() };
        rungs.push(Rung::solve("socp", format!("ipm_tol = {:.0e}, polish = false, tol = 1e-4", ipm.ipm_tol), ipm));
        let from = rungs.len() - 1;
        rungs.push(Rung {
            solver: "socp",
            setting: format!("ipm_tol = {:.0e}, polish = true, tol = {:.0e}", base.ipm_tol, base.tol),
            kind: RungKind::Polish {
                from,
                newton: Newton {
                    tol: base.tol,
                    max_iter: base.polish_max_iter,
                    line_search: true,
                    ..Newton::default()
                },
            },
        });
    }
    rungs
}

/// Errors of a solution against the reference (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Errors {
    /// The quantity of interest, relative (module docs; `U` in the CSV columns).
    pub u_rel: f64,
    /// σ̂ in the energy norm, relative.
    pub stress_rel: f64,
    /// ε(u) in L², relative.
    pub strain_rel: f64,
    /// Contact rows in one active set and not the other.
    pub contact_mismatch: usize,
}

/// The errors of `sol` against `reference` on `l` (module docs).
pub fn errors(l: &Lagrangian<'_>, sol: &Solution, reference: &Solution) -> Errors {
    let a = agreement(l, sol, reference);
    Errors {
        u_rel: a.u_rel,
        stress_rel: a.stress_rel,
        strain_rel: strain_distance(l, &sol.u, &reference.u),
        contact_mismatch: a.contact_mismatch.len(),
    }
}

/// ‖ε(u_a − u_b)‖_{L²} / ‖ε(u_b)‖_{L²} with the element volumes as weights.
pub fn strain_distance(l: &Lagrangian<'_>, u_a: &[f64], u_b: &[f64]) -> f64 {
    l2_distance(l.weights(), &strains(l, u_a), &strains(l, u_b))
}

/// The outcome of one run.
#[derive(Clone, Debug, PartialEq)]
pub struct RunRecord {
    /// Solver type.
    pub solver: String,
    /// Its setting.
    pub setting: String,
    /// True for the reference row.
    pub reference: bool,
    /// True when the solver met its tolerance.
    pub converged: bool,
    /// `converged`, the stop reason (`max_iterations`, `stagnated`, `approximation_limit`), or
    /// `error: <message>`.
    pub status: String,
    /// Iterations (0 after an error).
    pub iterations: usize,
    /// Wall time measured around the solve, seconds.
    pub wall_s: f64,
    /// The solver's own time: the sum of its reported phases, seconds (NaN after an error).
    pub solver_s: f64,
    /// The quantity of interest, by its name ([`named_quantity`]; NaN without a solution or
    /// without a quantity).
    pub u: f64,
    /// Errors against the reference (None after an error).
    pub errors: Option<Errors>,
    /// The recomputed relative KKT residual (NaN after an error).
    pub kkt: f64,
    /// Anything else (how the time was composed, warnings).
    pub note: String,
}

impl RunRecord {
    /// `solver setting`.
    pub fn label(&self) -> String {
        format!("{} {}", self.solver, self.setting)
    }
}

/// The status word of a stop reason.
pub fn status_of(reason: StopReason) -> &'static str {
    match reason {
        StopReason::Converged => "converged",
        StopReason::MaxIterations => "max_iterations",
        StopReason::Stagnated => "stagnated",
        StopReason::ApproximationLimit => "approximation_limit",
    }
}

/// A timed solve: the solution (or error) and the wall time around it.
pub struct Timed {
    /// The result.
    pub result: Result<Solution, SolveError>,
    /// Seconds.
    pub wall_s: f64,
}

/// Runs `solver` on `l`, timed.
pub fn timed_solve(solver: &dyn Solver, l: &Lagrangian<'_>, monitor: &mut dyn Monitor) -> Timed {
    let t0 = Instant::now();
    let result = solver.solve(l, monitor);
    Timed { result, wall_s: t0.elapsed().as_secs_f64() }
}

/// Polishes `start` by `newton` (see [`RungKind::Polish`]), timed.
pub fn timed_polish(newton: &Newton, l: &Lagrangian<'_>, start: &Solution, monitor: &mut dyn Monitor) -> Timed {
    let t0 = Instant::now();
    let s = Start { u: start.u.clone(), extras: start.extras.clone(), lambda: start.lambda.clone() };
    let result = newton.solve_from(l, Some(s), monitor, &mut PhaseTimer::default(), "socp");
    Timed { result, wall_s: t0.elapsed().as_secs_f64() }
}

/// The record of a run: its status, time, the quantity of interest `quantity`, errors against
/// `reference` and recomputed KKT residual.
pub fn record(
    problem: &DiscreteProblem,
    rung: &Rung,
    timed: &Timed,
    reference: &Solution,
    quantity: Option<&str>,
) -> RunRecord {
    let l = &problem.lagrangian();
    let mut rec = RunRecord {
        solver: rung.solver.to_string(),
        setting: rung.setting.clone(),
        reference: matches!(rung.kind, RungKind::Reference),
        converged: false,
        status: String::new(),
        iterations: 0,
        wall_s: timed.wall_s,
        solver_s: f64::NAN,
        u: f64::NAN,
        errors: None,
        kkt: f64::NAN,
        note: String::new(),
    };
    match &timed.result {
        Err(e) => rec.status = format!("error: {e}"),
        Ok(sol) => {
            rec.converged = sol.report.converged;
            rec.status = status_of(sol.report.stop_reason).to_string();
            rec.iterations = sol.report.iterations;
            rec.solver_s = sol.report.wall_s();
            let q = |s: &Solution| quantity.and_then(|n| named_quantity(problem.view(), s, n)).unwrap_or(f64::NAN);
            rec.u = q(sol);
            let mut e = errors(l, sol, reference);
            let q_ref = q(reference);
            if rec.u.is_finite() && q_ref.is_finite() {
                e.u_rel = (rec.u - q_ref).abs() / q_ref.abs().max(f64::MIN_POSITIVE);
            }
            rec.errors = Some(e);
            rec.kkt = kkt(l, &sol.iterate(), &mut Workspace::new(l)).max();
            rec.note = sol.report.warnings.join("; ");
        }
    }
    rec
}

/// Adds the time of the run a polish started from (see [`RungKind::Polish`]).
pub fn add_start_time(rec: &mut RunRecord, start: &RunRecord) {
    rec.wall_s += start.wall_s;
    rec.solver_s += start.solver_s;
    rec.iterations += start.iterations;
    let what = format!("time and iterations include the interior point of `{}`", start.label());
    rec.note = if rec.note.is_empty() { what } else { format!("{what}; {}", rec.note) };
}
