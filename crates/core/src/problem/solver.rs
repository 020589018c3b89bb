//! The solver interface (theory §4–§5): a solver takes the Lagrangian L and returns a
//! [`Solution`] with an honest [`SolveReport`] — residuals, per-phase wall time and why it
//! stopped — or a typed [`SolveError`]. NaN or Inf never leaves a solver unreported.

use crate::error::ParameterError;
use crate::problem::fields::StressField;
use crate::problem::kkt::KktResiduals;
use crate::problem::lagrangian::{Iterate, Lagrangian};
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Debug;
use std::time::Instant;
use thiserror::Error;

/// Why a solver stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The relative KKT residual reached the tolerance.
    Converged,
    /// The iteration budget ran out first.
    MaxIterations,
    /// The residual stopped decreasing (round-off floor above the tolerance).
    Stagnated,
    /// The solver solved its own approximation of the problem (a penalty, a regularisation)
    /// to round-off, but that approximation's error is above the tolerance.
    ApproximationLimit,
}

/// What a solve reports (theory §5).
#[derive(Clone, Debug, Serialize)]
pub struct SolveReport {
    /// Solver type name.
    pub solver: String,
    /// True when the tolerance was met.
    pub converged: bool,
    /// Why the solver stopped.
    pub stop_reason: StopReason,
    /// Outer iterations.
    pub iterations: usize,
    /// The relative KKT tolerance asked for.
    pub tolerance: f64,
    /// KKT residuals of the returned iterate.
    pub kkt: KktResiduals,
    /// The relative KKT residual after each iteration.
    pub residual_history: Vec<f64>,
    /// Wall time per phase in seconds, in order of first use.
    pub phases: Vec<(String, f64)>,
    /// Solver-specific numbers: step sizes, factorisations, triangular solves, duality gap, ...
    pub counters: BTreeMap<String, f64>,
    /// Things the user should know about this solve (an interior point that ended early, ...).
    pub warnings: Vec<String>,
}

impl SolveReport {
    /// Total wall time of the phases.
    pub fn wall_s(&self) -> f64 {
        self.phases.iter().map(|p| p.1).sum()
    }
}

/// A solution of the discrete problem with its report.
#[derive(Clone, Debug)]
pub struct Solution {
    /// Free displacement dofs u.
    pub u: Vec<f64>,
    /// Extra unknowns V (the punch's U).
    pub extras: Vec<f64>,
    /// Generalised stresses σ̂ per point.
    pub stress: StressField,
    /// Contact forces λ_i per row of K_h.
    pub lambda: Vec<f64>,
    /// How it was obtained.
    pub report: SolveReport,
    /// The extras the problem leaves undetermined (indices into `extras`, ascending): those of
    /// an obstacle that carries no load (theory §11.3). Their entries in `extras` hold an
    /// admissible position (where the obstacle just touches); reports show them as null.
    pub undetermined: Vec<usize>,
}

impl Solution {
    /// The solution as an iterate, for residual evaluations.
    pub fn iterate(&self) -> Iterate<'_> {
        Iterate { u: &self.u, extras: &self.extras, stress: &self.stress, lambda: &self.lambda }
    }
}

/// Why a solve failed.
#[derive(Debug, Error)]
pub enum SolveError {
    /// A linear solve failed: a factorisation met a non-positive pivot (the body is not held
    /// against rigid-body motion, or the data make the matrix singular), an iterative solver
    /// broke down. `source` is the linear algebra's own error.
    #[error("{solver}: {source}")]
    LinearAlgebra { solver: String, source: Box<dyn std::error::Error + Send + Sync> },
    /// The iteration diverged; `hint` says which parameter to change.
    #[error("{solver} diverged at iteration {iteration}: KKT residual {residual:.3e}; {hint}")]
    Diverged { solver: String, iteration: usize, residual: f64, hint: String },
    /// NaN or Inf appeared.
    #[error("{solver}: non-finite value (NaN or Inf) in {what} at iteration {iteration}")]
    NonFinite { solver: String, what: String, iteration: usize },
    /// A solver parameter is out of range.
    #[error(transparent)]
    Parameter(#[from] ParameterError),
    /// The problem is outside what this solver handles.
    #[error("{solver}: {message}")]
    Unsupported { solver: String, message: String },
    /// The prescribed forces exceed what the body can carry (plastic collapse, theory §10.3): the
    /// problem has no solution; `evidence` says what the solver met.
    #[error("{solver}: the load exceeds what the body can carry (plastic collapse): {evidence}")]
    BeyondCollapse { solver: String, evidence: String },
}

impl SolveError {
    /// A failure of the linear algebra inside `solver`.
    pub fn linear_algebra(solver: &str, source: impl std::error::Error + Send + Sync + 'static) -> Self {
        Self::LinearAlgebra { solver: solver.to_string(), source: Box::new(source) }
    }
}

/// The error of a solver that runs on one rank only ([`Solver::runs_distributed`] false) given a
/// problem distributed over several (theory §12); `Ok` on one rank.
pub fn one_rank(solver: &str, l: &Lagrangian<'_>) -> Result<(), SolveError> {
    let ranks = l.comm().size();
    if ranks > 1 {
        return Err(SolveError::Unsupported {
            solver: solver.to_string(),
            message: format!(
                "runs on one rank only, and this problem is distributed over {ranks} ranks: use `newton` \
                 (`--solver newton` or `[solver] type = \"newton\"`), or run without mpirun"
            ),
        });
    }
    Ok(())
}

/// Observer of a running solve (progress bars, logs).
pub trait Monitor {
    /// The solver enters a phase ("factorisation", "iterations", ...).
    fn phase(&mut self, _name: &str) {}
    /// Iteration `it` done with relative KKT residual `residual`; the target is `tolerance`.
    fn iteration(&mut self, _it: usize, _residual: f64, _tolerance: f64) {}
}

/// A monitor that does nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;
impl Monitor for Silent {}

/// A solver, chosen by `type` in the `[solver]` table of a scene or by `saddle run --solver`.
#[typetag::serde(tag = "type")]
pub trait Solver: Debug + Send + Sync + dyn_clone::DynClone {
    /// The `type` name of the solver in scene files.
    fn name(&self) -> &'static str {
        self.typetag_name()
    }
    /// Checks the parameters; `path` is the table's path (`solver`). Called once, by whoever
    /// reads the parameters (a scene when it is loaded); `solve` takes them as valid.
    fn validate(&self, path: &str) -> Result<(), ParameterError>;
    /// The relative KKT tolerance it stops at.
    fn tolerance(&self) -> f64;
    /// Solves the discrete problem.
    fn solve(&self, problem: &Lagrangian<'_>, monitor: &mut dyn Monitor) -> Result<Solution, SolveError>;

    /// True when the solver solves a problem distributed over several ranks (theory §12); the
    /// others refuse one ([`one_rank`]).
    fn runs_distributed(&self) -> bool {
        false
    }

    /// Solves the discrete problem from `start`, the previous load step's solution (theory §11.2:
    /// a warm start). A solver that can use a start reports the counter `warm_start` = 1; the
    /// default ignores it and solves from its own start (an interior point method has no use
    /// for one).
    fn solve_warm(
        &self,
        problem: &Lagrangian<'_>,
        start: &Start,
        monitor: &mut dyn Monitor,
    ) -> Result<Solution, SolveError> {
        let _ = start;
        self.solve(problem, monitor)
    }
}

/// A starting point of a solve: displacements, extras and contact forces (theory §11.2).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Start {
    /// u.
    pub u: Vec<f64>,
    /// V.
    pub extras: Vec<f64>,
    /// λ.
    pub lambda: Vec<f64>,
}

impl Start {
    /// The start at a solution.
    pub fn from_solution(sol: &Solution) -> Self {
        Self { u: sol.u.clone(), extras: sol.extras.clone(), lambda: sol.lambda.clone() }
    }

    /// Checks the sizes against `problem`; an error names the solver `solver`.
    pub fn check(&self, problem: &Lagrangian<'_>, solver: &str) -> Result<(), SolveError> {
        let want = (problem.n_dofs(), problem.n_extras(), problem.n_rows());
        let got = (self.u.len(), self.extras.len(), self.lambda.len());
        if want != got {
            return Err(SolveError::Unsupported {
                solver: solver.to_string(),
                message: format!(
                    "the start has {} dofs, {} extras and {} multipliers; the problem {}, {} and {}",
                    got.0, got.1, got.2, want.0, want.1, want.2
                ),
            });
        }
        if let Some(x) = self.u.iter().chain(&self.extras).chain(&self.lambda).find(|x| !x.is_finite()) {
            return Err(SolveError::Unsupported {
                solver: solver.to_string(),
                message: format!("the start holds a non-finite value ({x})"),
            });
        }
        Ok(())
    }
}

dyn_clone::clone_trait_object!(Solver);

/// Accumulates wall time per named phase.
#[derive(Clone, Debug, Default)]
pub struct PhaseTimer {
    phases: Vec<(String, f64)>,
}

impl PhaseTimer {
    /// Runs `f`, adding its wall time to phase `name`.
    pub fn time<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let t0 = Instant::now();
        let out = f();
        self.add(name, t0.elapsed().as_secs_f64());
        out
    }

    /// Adds `seconds` to phase `name`.
    pub fn add(&mut self, name: &str, seconds: f64) {
        match self.phases.iter_mut().find(|p| p.0 == name) {
            Some(p) => p.1 += seconds,
            None => self.phases.push((name.to_string(), seconds)),
        }
    }

    /// The phases and their times.
    pub fn into_phases(self) -> Vec<(String, f64)> {
        self.phases
    }
}
