//! Issue 5, case 8: **no NaN or Inf escapes.** A property test draws material parameters, the
//! punch force and the gap over wide finite ranges and runs every solver on a tiny version of the
//! default scene (theory §6 geometry, 6×6×3 graded cells, 1 296 tetrahedra). Each run must end in
//! one of three honest ways:
//!
//! * converged, with the KKT residual recomputed from the solution by L (independently of the
//!   solver) within the solver's tolerance;
//! * a clearly flagged result: `converged = false` with a stop reason other than `Converged`;
//! * a typed error (`SolveError`) with a message, of a kind expected for the draw: a numerical
//!   failure (`NonFinite`, `Diverged`, `LinearAlgebra`) only for perfect plasticity (h = 0,
//!   where beyond the limit load there is no solution), never `Parameter` or `Unsupported`
//!   (`Case::extreme`);
//!
//! and in every case without a panic and without NaN or Inf anywhere in the returned solution
//! (u, U, σ, ξ, λ, the reported KKT residuals and the residual history). Each solver must also
//! converge on a stated fraction of the draws (`property`), so that a solver that always stops
//! short or always fails does not pass.
//!
//! Ranges: E log-uniform in [1e-3, 1e12]; ν uniform in [−0.9, 0.4999]; k₀/E log-uniform in
//! [1e-6, 1e-1]; h/E log-uniform in [1e-6, 10], or 0 (perfect plasticity) one time in six; one
//! body in eight elastic (no `[yield]`); F log-uniform over six decades around the first-yield
//! scale F_y (Hertz: p₀ = 1.98 k₀ at first yield, F_y = π³R²p₀³/(6E*²), capped at the load that
//! yields the whole candidate zone); R log-uniform in [0.1, 1e3]; a flat punch one time in five.
//!
//! The cases come from a fixed seed, so CI is reproducible; `PROPTEST_RNG_SEED=<u64>` explores
//! other draws and `PROPTEST_CASES=<n>` changes the number of cases per solver, e.g.
//! `PROPTEST_CASES=200 PROPTEST_RNG_SEED=7 cargo test --release --test proptest_solvers -- --nocapture`.
//! Each test prints its outcome counts (converged / flagged / error).

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestCaseError, TestRunner};
use saddle::core::{DiscreteProblem, kkt};
use saddle::core::{Silent, Solution, SolveError, Solver, StopReason, Workspace};
use saddle::io::scene::Scene;
use std::collections::BTreeMap;
use std::path::Path;

/// The seed of the CI draws.
const SEED: u64 = 0x005a_dd1e_0005;

/// One drawn problem.
#[derive(Clone, Debug)]
struct Case {
    young: f64,
    nu: f64,
    /// k₀/E.
    k0_rel: f64,
    /// h/E; 0 for perfect plasticity.
    h_rel: f64,
    /// No `[yield]` table.
    elastic: bool,
    /// F / F_y (F_y: the first-yield scale, module docs).
    f_rel: f64,
    /// Paraboloid radius R (unused by the flat punch).
    radius: f64,
    flat: bool,
}

impl Case {
    fn k0(&self) -> f64 {
        self.k0_rel * self.young
    }

    /// The first-yield scale of the force (module docs).
    fn first_yield_force(&self) -> f64 {
        let e_star = self.young / (1.0 - self.nu * self.nu);
        let p0 = 1.98 * self.k0();
        let zone_area = std::f64::consts::PI * 0.25;
        let hertz = if self.flat {
            f64::INFINITY
        } else {
            std::f64::consts::PI.powi(3) * self.radius.powi(2) * p0.powi(3) / (6.0 * e_star * e_star)
        };
        hertz.min(p0 * zone_area)
    }

    /// Why this draw may legitimately end in a typed numerical error (`NonFinite`, `Diverged`,
    /// `LinearAlgebra`), or `None` where every solver must return a solution, converged or
    /// flagged. Perfect plasticity (h = 0) is the one such draw: beyond the limit load J is
    /// unbounded below and there is no solution (theory §10), the hardening block of the cone
    /// programme degenerates and the consistent tangent is singular along the flow direction.
    /// Measured (6 × 300 draws per solver, seeds 1–6): 7 errors, all SOCP `NonFinite` with
    /// h = 0; none for the CI seed.
    fn extreme(&self) -> Option<&'static str> {
        (!self.elastic && self.h_rel == 0.0).then_some("perfect plasticity (h = 0)")
    }

    fn force(&self) -> f64 {
        self.f_rel * self.first_yield_force()
    }

    fn scene(&self) -> DiscreteProblem {
        let yield_table = if self.elastic {
            String::new()
        } else {
            format!("[yield]\ntype = \"von_mises\"\nk0 = {:e}\nh = {:e}\n", self.k0(), self.h_rel * self.young)
        };
        let gap = if self.flat {
            "{ type = \"flat\" }".to_string()
        } else {
            format!("{{ type = \"paraboloid\", R = {:e} }}", self.radius)
        };
        // P1–P0, stated: the converged shares of the properties below were measured on it
        let text = format!(
            r#"
[discretisation]
type = "p1"
[mesh]
type = "box"
min = [-1.0, -1.0, 0.0]
max = [1.0, 1.0, 1.0]
cells = [6, 6, 3]
grading = {{ toward = [0.0, 0.0, 0.0], ratio = 2.0 }}
align = [[-0.75, 0.75], [-0.75, 0.75], []]
[material]
E = {young:e}
nu = {nu:e}
{yield_table}
[[dirichlet]]
on = {{ not = {{ all = [ {{ group = "zmin" }}, {{ box = {{ min = [-0.75, -0.75, -1.0], max = [0.75, 0.75, 1.0] }} }} ] }} }}
[obstacle]
type = "rigid_punch"
F = {force:e}
zone = {{ all = [ {{ group = "zmin" }}, {{ disc = {{ center = [0.0, 0.0], radius = 0.5 }} }} ] }}
gap = {gap}
"#,
            young = self.young,
            nu = self.nu,
            force = self.force(),
        );
        let scene = Scene::from_toml(&text, Path::new("proptest.toml"))
            .unwrap_or_else(|e| panic!("drawn scene {self:?} is invalid: {e}\n{text}"));
        scene.into_problem().unwrap_or_else(|e| panic!("drawn scene {self:?} does not assemble: {e}")).0
    }
}

fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo.log10()..=hi.log10()).prop_map(|x| 10f64.powf(x))
}

fn cases() -> impl Strategy<Value = Case> {
    (
        log_uniform(1e-3, 1e12),
        -0.9f64..=0.4999,
        log_uniform(1e-6, 1e-1),
        prop_oneof![1 => Just(0.0), 5 => log_uniform(1e-6, 10.0)],
        proptest::bool::weighted(0.125),
        log_uniform(1e-3, 1e3),
        log_uniform(0.1, 1e3),
        proptest::bool::weighted(0.2),
    )
        .prop_map(|(young, nu, k0_rel, h_rel, elastic, f_rel, radius, flat)| Case {
            young,
            nu,
            k0_rel,
            h_rel,
            elastic,
            f_rel,
            radius,
            flat,
        })
}

/// Every number the solution carries, by name, for the non-finite check.
fn non_finite_fields(sol: &Solution) -> Vec<&'static str> {
    let k = &sol.report.kkt;
    let fields: [(&'static str, bool); 9] = [
        ("u", sol.u.iter().all(|x| x.is_finite())),
        ("extras", sol.extras.iter().all(|x| x.is_finite())),
        ("stress.sigma", sol.stress.sigma.iter().all(|s| s.iter().all(|x| x.is_finite()))),
        ("stress.q", sol.stress.q.iter().all(|x| x.is_finite())),
        ("lambda", sol.lambda.iter().all(|x| x.is_finite())),
        (
            "report.kkt",
            [k.equilibrium, k.load_balance, k.complementarity, k.constitutive].iter().all(|x| x.is_finite()),
        ),
        ("report.residual_history", sol.report.residual_history.iter().all(|x| x.is_finite())),
        ("report.phases", sol.report.phases.iter().all(|(_, t)| t.is_finite())),
        ("report.tolerance", sol.report.tolerance.is_finite()),
    ];
    fields.iter().filter(|(_, ok)| !ok).map(|(name, _)| *name).collect()
}

/// Outcome counts of one solver over the drawn cases.
#[derive(Default, Debug)]
struct Tally {
    converged: usize,
    flagged: BTreeMap<String, usize>,
    errors: BTreeMap<String, usize>,
    /// The draws that ended in an error, with the error (printed at the end).
    failed_draws: Vec<String>,
}

impl Tally {
    fn total(&self) -> usize {
        self.converged + self.flagged.values().sum::<usize>() + self.errors.values().sum::<usize>()
    }
}

/// The variant of a solve error, without its fields.
fn kind(e: &SolveError) -> &'static str {
    match e {
        SolveError::LinearAlgebra { .. } => "LinearAlgebra",
        SolveError::Diverged { .. } => "Diverged",
        SolveError::NonFinite { .. } => "NonFinite",
        SolveError::Parameter(_) => "Parameter",
        SolveError::Unsupported { .. } => "Unsupported",
        SolveError::BeyondCollapse { .. } => "BeyondCollapse",
    }
}

/// Runs `solver` on `case` and checks the three honest outcomes (module docs).
fn check(solver: &dyn Solver, case: &Case, tally: &mut Tally) -> Result<(), TestCaseError> {
    let l = case.scene();
    match solver.solve(&l.lagrangian(), &mut Silent) {
        Ok(sol) => {
            let bad = non_finite_fields(&sol);
            prop_assert!(bad.is_empty(), "{}: non-finite {:?} in the solution of {:?}", solver.name(), bad, case);
            let r = &sol.report;
            let recomputed = kkt(&l.lagrangian(), &sol.iterate(), &mut Workspace::new(&l.lagrangian())).max();
            prop_assert!(recomputed.is_finite(), "{}: recomputed KKT {recomputed} for {:?}", solver.name(), case);
            if r.converged {
                prop_assert_eq!(r.stop_reason, StopReason::Converged);
                prop_assert!(
                    recomputed <= solver.tolerance(),
                    "{}: reports convergence but the recomputed KKT residual is {recomputed:e} > tol {:e} \
                     (reported {:?}) for {:?}",
                    solver.name(),
                    solver.tolerance(),
                    r.kkt,
                    case
                );
                tally.converged += 1;
            } else {
                prop_assert_ne!(r.stop_reason, StopReason::Converged, "{}: {:?}", solver.name(), case);
                *tally.flagged.entry(format!("{:?}", r.stop_reason)).or_default() += 1;
            }
        }
        Err(e) => {
            let message = e.to_string();
            prop_assert!(!message.is_empty());
            let legitimate = match &e {
                SolveError::LinearAlgebra { .. }
                | SolveError::Diverged { .. }
                | SolveError::NonFinite { .. }
                | SolveError::BeyondCollapse { .. } => case.extreme().is_some(),
                // the solvers' parameters are fixed and valid, and every solver handles these
                // problems (one contact row per x₃ dof, a von Mises cone)
                SolveError::Parameter(_) | SolveError::Unsupported { .. } => false,
            };
            prop_assert!(
                legitimate,
                "{}: a {} error where none is expected: {message}\nfor {:?}",
                solver.name(),
                kind(&e),
                case
            );
            *tally.errors.entry(kind(&e).to_string()).or_default() += 1;
            tally.failed_draws.push(format!("{message} ({}) for {case:?}", case.extreme().unwrap_or_default()));
        }
    }
    Ok(())
}

/// Runs the property for `solver` over `default_cases` drawn cases (module docs), prints the
/// outcome counts and checks that at least the fraction `min_converged` of the draws converged
/// (the rest are flagged or errors of the kinds `check` allows): a solver that always stopped
/// short or always failed would otherwise pass.
fn property(solver: &dyn Solver, default_cases: u32, min_converged: f64) {
    let mut config = Config { failure_persistence: None, max_shrink_iters: 40, ..Config::default() };
    if std::env::var_os("PROPTEST_CASES").is_none() {
        config.cases = default_cases;
    }
    if config.rng_seed == RngSeed::Random {
        config.rng_seed = RngSeed::Fixed(SEED);
    }
    let seed = config.rng_seed;
    let cases_run = config.cases;
    let mut runner = TestRunner::new(config);
    let tally = std::cell::RefCell::new(Tally::default());
    let t0 = std::time::Instant::now();
    let result = runner.run(&cases(), |case| check(solver, &case, &mut tally.borrow_mut()));
    let tally = tally.into_inner();
    println!(
        "{}: {cases_run} cases (seed {seed}) in {:.1} s: {} converged, flagged {:?}, errors {:?}",
        solver.name(),
        t0.elapsed().as_secs_f64(),
        tally.converged,
        tally.flagged,
        tally.errors
    );
    for d in &tally.failed_draws {
        println!("  {}: {d}", solver.name());
    }
    if let Err(e) = result {
        panic!("{}: {e}", solver.name());
    }
    // every drawn case was run once and counted (a passing run neither shrinks nor rejects)
    assert_eq!(tally.total(), cases_run as usize, "{}: {tally:?}", solver.name());
    let fraction = tally.converged as f64 / cases_run as f64;
    assert!(
        fraction >= min_converged,
        "{}: {} of {cases_run} draws converged ({:.0} %), fewer than the {:.0} % required; flagged {:?}, errors {:?}",
        solver.name(),
        tally.converged,
        100.0 * fraction,
        100.0 * min_converged,
        tally.flagged,
        tally.errors
    );
}

// The converged fractions required below, against those measured over 6 × 300 draws (seeds 1–6)
// and the CI seed's draws: Newton 99.7–100 % (CI 64/64), the penalty 100 % (64/64), SOCP
// 99–100 % (32/32), Uzawa 93–96 % (47/48; the rest flagged `max_iterations`). Each threshold
// leaves a margin of about 5 to 10 points.

/// Uzawa with an explicit budget: 3000 iterations (the tiny mesh converges in tens to hundreds
/// where the problem is well conditioned; the rest is flagged `max_iterations` or `stagnated`).
/// At least 85 % converge.
#[test]
fn uzawa_never_lets_nan_escape() {
    property(&saddle::solvers::Uzawa { max_iter: 3000, ..Default::default() }, 48, 0.85);
}

/// Newton with its default budget of 50 iterations. At least 95 % converge.
#[test]
fn newton_never_lets_nan_escape() {
    property(&saddle::solvers::Newton { max_iter: 50, ..Default::default() }, 64, 0.95);
}

/// The penalty with its default μ = 1e-12 and budget of 50 Newton iterations. At least 95 %
/// converge.
#[test]
fn penalty_never_lets_nan_escape() {
    property(&saddle::solvers::Penalty { max_iter: 50, ..Default::default() }, 64, 0.95);
}

/// SOCP with 100 interior-point iterations and 20 polish iterations. At least 90 % converge.
#[cfg(feature = "socp")]
#[test]
fn socp_never_lets_nan_escape() {
    property(&saddle::solvers::Socp { ipm_max_iter: 100, polish_max_iter: 20, ..Default::default() }, 32, 0.90);
}
