//! The steps of a load path one after another (theory §11.2): each step is solved from the
//! state the previous one left (the plastic state and the friction rows' slip, theory §11.6),
//! warm-started from its solution, and leaves its own state.

use crate::error::SceneError;
use crate::evolution::LoadFactors;
use crate::evolution::reduced::Reduced;
use crate::evolution::step::LoadStep;
use crate::fem::DiscreteProblem;
use crate::problem::fields::{PlasticState, StressField};
use crate::problem::lagrangian::Lagrangian;
use crate::problem::obstacles::OBSTACLE_PATH;
use crate::problem::slip::SlipHistory;
use crate::problem::solver::{Monitor, Solution, SolveError, Solver, Start};
use crate::problem::tensor::Sym;
use thiserror::Error;

/// The factors of a load path's steps: the first factor, then `substeps` equal steps from each
/// factor to the next (theory §11.2). `substeps` = 1 gives the factors themselves.
pub fn step_factors(factors: &[f64], substeps: usize) -> Vec<f64> {
    let n = substeps.max(1);
    let mut out: Vec<f64> = factors.first().copied().into_iter().collect();
    for w in factors.windows(2) {
        let (a, b) = (w[0], w[1]);
        out.extend((1..=n).map(|k| if k == n { b } else { a + (b - a) * k as f64 / n as f64 }));
    }
    out
}

/// Why a step of a load path could not be solved.
#[derive(Debug, Error)]
pub enum PathError {
    /// The step's problem could not be set up (an obstacle rejects its scaled load).
    #[error("step {step} (load factor {factor}): {source}")]
    Scene {
        /// The step's index.
        step: usize,
        /// Its load factor.
        factor: f64,
        /// Why.
        source: SceneError,
    },
    /// The solver failed on the step.
    #[error("step {step} (load factor {factor}): {source}")]
    Solve {
        /// The step's index.
        step: usize,
        /// Its load factor.
        factor: f64,
        /// The solver's error.
        source: SolveError,
    },
}

/// A solved step: its problem (L at the factor, from the state before it) and its solution in
/// the problem's numbering.
#[derive(Debug)]
pub struct StepSolution<'a> {
    /// The step's index (from 0).
    pub index: usize,
    /// L of the step.
    pub problem: LoadStep<'a>,
    /// The solution: every row's multiplier (0 on the rows of an unloaded obstacle) and every
    /// extra (an undetermined one, listed in `solution.undetermined`, holds the position where
    /// its obstacle just touches).
    pub solution: Solution,
    /// What the user should know about the step (undetermined extras).
    pub warnings: Vec<String>,
}

impl StepSolution<'_> {
    /// True when the solver met its tolerance: the path may go on from this step.
    pub fn converged(&self) -> bool {
        self.solution.report.converged
    }
}

/// A load path under way (theory §11.2): the discretisation, the state the next step starts
/// from, and the last solution (the next step's warm start).
#[derive(Debug)]
pub struct Evolution<'a> {
    base: &'a DiscreteProblem,
    state: PlasticState,
    /// The friction rows' slip and dissipation so far (theory §11.6).
    slip: SlipHistory,
    start: Option<Start>,
    steps: usize,
}

impl<'a> Evolution<'a> {
    /// A path of `base` from the zero state (the first step is the stationary problem).
    pub fn new(base: &'a DiscreteProblem) -> Self {
        let l = base.lagrangian();
        Self {
            base,
            state: PlasticState::zero(l.n_points(), l.data.hardening_dim()),
            slip: SlipHistory::default(),
            start: None,
            steps: 0,
        }
    }

    /// The same path with its first solve started from `start` (the iterate only: the state
    /// stays zero, so the step is still the stationary problem; theory §11.2). A start whose
    /// sizes do not fit the step is ignored, as a load step's is.
    pub fn starting_from(mut self, start: Option<Start>) -> Self {
        self.start = start;
        self
    }

    /// The state the next step starts from.
    pub fn state(&self) -> &PlasticState {
        &self.state
    }

    /// The friction rows' slip history the next step starts from (theory §11.6).
    pub fn slip_history(&self) -> &SlipHistory {
        &self.slip
    }

    /// Steps solved so far (converged or not).
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Solves the next step, at load factor `factor`, with `solver` warm-started from the last
    /// solution. A converged step's state becomes the next step's; a step that did not converge
    /// is returned flagged and leaves the state as it was (the path should stop there).
    pub fn step(
        &mut self,
        factor: f64,
        solver: &dyn Solver,
        monitor: &mut dyn Monitor,
    ) -> Result<StepSolution<'a>, PathError> {
        self.step_at(&LoadFactors::uniform(factor), solver, monitor)
    }

    /// [`Evolution::step`] with named loads at factors of their own (theory §11.2; errors and
    /// reports name `factors.all`).
    pub fn step_at(
        &mut self,
        factors: &LoadFactors,
        solver: &dyn Solver,
        monitor: &mut dyn Monitor,
    ) -> Result<StepSolution<'a>, PathError> {
        let factor = factors.all;
        let index = self.steps;
        self.steps += 1;
        let problem = LoadStep::at(self.base, factors, self.state.clone())
            .map_err(|source| PathError::Scene { step: index, factor, source })?
            .with_slip_history(self.slip.clone());
        let l = problem.lagrangian();
        let unloaded = unloaded_obstacles(&problem);
        let start = self.start.as_ref().filter(|s| s.check(&l, solver.name()).is_ok());
        let mut solve = |l: &Lagrangian<'_>, start: Option<&Start>| {
            match start {
                Some(s) => solver.solve_warm(l, s, monitor),
                None => solver.solve(l, monitor),
            }
            .map_err(|source| PathError::Solve { step: index, factor, source })
        };
        let (solution, warnings) = if unloaded.is_empty() {
            (solve(&l, start)?, Vec::new())
        } else {
            let (rows_kept, extras_kept) = kept(&problem, &unloaded);
            let reduced = Reduced::new(&l, rows_kept, extras_kept);
            let restricted = start.map(|s| Start {
                u: s.u.clone(),
                extras: reduced.restrict_extras(&s.extras),
                lambda: reduced.restrict_rows(&s.lambda),
            });
            let sol = solve(&reduced.lagrangian(&l), restricted.as_ref())?;
            let previous = self.start.as_ref().map(|s| s.extras.clone());
            expand(&problem, &reduced, &unloaded, sol, previous, factor)
        };
        if solution.report.converged {
            self.state = state_after(&l, &solution.u);
            self.slip = problem.obstacles().history_after(&solution.u, &solution.extras, &solution.lambda);
            self.start = Some(Start::from_solution(&solution));
        }
        Ok(StepSolution { index, problem, solution, warnings })
    }
}

/// The state a step leaves at displacement `u` (theory §11.1): ε_p = ε(u) − Aσ with σ̂ the
/// step's local law at ε(u) (so that the next step's trial C(ε − ε_p) is σ + C(ε − ε(u))). The
/// law reads ε(w) against the shifted state, ε_p the strain of u = w + u_D (theory §14).
fn state_after(l: &Lagrangian<'_>, u: &[f64]) -> PlasticState {
    let mut eps = vec![Sym::zeros(); l.n_points()];
    l.strain(u, &mut eps);
    let mut stress = StressField::new(l.n_points(), l.data.hardening_dim());
    l.data.local_law(&eps, &mut stress, None);
    l.data.lifting.add_strain(&mut eps);
    PlasticState::from_solution(l.data.elasticity, &eps, &stress)
}

/// An obstacle without load in a step: its index, and the extra whose column of H has one
/// strict sign over its rows (theory §11.3).
#[derive(Clone, Copy, Debug)]
struct Unloaded {
    obstacle: usize,
    /// The extra (index into all extras) that moves the obstacle off or onto the body.
    extra: usize,
}

/// The obstacles with extras whose loads are all zero and with a column of H of one strict
/// sign: their multipliers vanish (Hᵀλ = 0, λ ≥ 0) and their extras are undetermined. The rows
/// may be split over ranks: every test is over all of them, so every rank finds the same.
fn unloaded_obstacles(problem: &LoadStep<'_>) -> Vec<Unloaded> {
    let rows = problem.obstacles().rows();
    let load = problem.obstacles().load();
    let parts = problem.obstacles().parts();
    let comm = problem.base().element.comm();
    parts
        .iter()
        .enumerate()
        .filter(|(_, p)| !p.extra_range.is_empty() && comm.any(!p.row_range.is_empty()))
        .filter(|(_, p)| load[p.extra_range.clone()].iter().all(|f| *f == 0.0))
        .filter_map(|(o, p)| {
            let one_signed = |k: usize| {
                let mut h = p.row_range.clone().map(|i| rows.extra_row(i)[k]);
                let (not_negative, not_positive) = (h.clone().any(|x| x >= 0.0), h.any(|x| x <= 0.0));
                !comm.any(not_negative) || !comm.any(not_positive)
            };
            p.extra_range.clone().find(|&k| one_signed(k)).map(|extra| Unloaded { obstacle: o, extra })
        })
        .collect()
}

/// The rows and extras that stay in the step: all but those of the unloaded obstacles.
fn kept(problem: &LoadStep<'_>, unloaded: &[Unloaded]) -> (Vec<usize>, Vec<usize>) {
    let parts = problem.obstacles().parts();
    let out_rows = |i: usize| unloaded.iter().any(|u| parts[u.obstacle].row_range.contains(&i));
    let out_extras = |k: usize| unloaded.iter().any(|u| parts[u.obstacle].extra_range.contains(&k));
    let rows = (0..problem.obstacles().rows().n_rows()).filter(|&i| !out_rows(i)).collect();
    let extras = (0..problem.obstacles().load().len()).filter(|&k| !out_extras(k)).collect();
    (rows, extras)
}

/// The reduced solution in the step's numbering: zero multipliers on the rows left out, and
/// each unloaded obstacle placed where it just touches the body (its other extras as they
/// were): an admissible position with λ = 0, so the full problem's KKT conditions hold. Its
/// extras are marked undetermined in the solution.
fn expand(
    problem: &LoadStep<'_>,
    reduced: &Reduced,
    unloaded: &[Unloaded],
    sol: Solution,
    previous: Option<Vec<f64>>,
    factor: f64,
) -> (Solution, Vec<String>) {
    let rows = problem.obstacles().rows();
    let n_extras = problem.obstacles().load().len();
    let mut lambda = vec![0.0; rows.n_rows()];
    for (j, &i) in reduced.rows_kept().iter().enumerate() {
        lambda[i] = sol.lambda[j];
    }
    let mut extras = previous.filter(|p| p.len() == n_extras).unwrap_or_else(|| vec![0.0; n_extras]);
    for (j, &k) in reduced.extras_kept().iter().enumerate() {
        extras[k] = sol.extras[j];
    }
    let parts = problem.obstacles().parts();
    let names = problem.obstacles().obstacles().extra_names();
    let mut undetermined = Vec::new();
    let mut warnings = Vec::new();
    let mut gap = vec![0.0; rows.n_rows()];
    rows.gap(&sol.u, &extras, &mut gap);
    for un in unloaded {
        let p = &parts[un.obstacle];
        // g_i + H_ik t ≥ 0 on the obstacle's rows; the t at which the first row closes: the
        // least −g/H when H < 0 (t ≤ −g/H for every row), the largest when H > 0
        // (over every rank's rows: H has one strict sign over all of them)
        let comm = problem.base().element.comm();
        let bounds = p.row_range.clone().map(|i| -gap[i] / rows.extra_row(i)[un.extra]);
        let negative = comm.any(p.row_range.clone().any(|i| rows.extra_row(i)[un.extra] < 0.0));
        let t = if negative {
            comm.min(bounds.fold(f64::INFINITY, f64::min))
        } else {
            comm.max(bounds.fold(f64::NEG_INFINITY, f64::max))
        };
        extras[un.extra] += t;
        undetermined.extend(p.extra_range.clone());
        let path = problem.obstacles().obstacles().path(OBSTACLE_PATH, un.obstacle);
        let which: Vec<&str> = p.extra_range.clone().map(|k| names[k].as_str()).collect();
        warnings.push(format!(
            "{path}: carries no load at load factor {factor}: {} undetermined (any position out of contact is \
             admissible; reported as null) and its contact rows are left out of the step",
            if which.len() == 1 {
                format!("its extra {} is", which[0])
            } else {
                format!("its extras {} are", which.join(", "))
            }
        ));
    }
    undetermined.sort_unstable();
    (Solution { u: sol.u, extras, stress: sol.stress, lambda, report: sol.report, undetermined }, warnings)
}

#[cfg(test)]
mod tests {
    use super::step_factors;

    #[test]
    fn sub_steps_divide_each_interval_equally() {
        assert_eq!(step_factors(&[0.0, 1.0, 0.0], 1), vec![0.0, 1.0, 0.0]);
        assert_eq!(step_factors(&[0.0, 1.0, 0.0], 4), vec![0.0, 0.25, 0.5, 0.75, 1.0, 0.75, 0.5, 0.25, 0.0]);
        assert_eq!(step_factors(&[0.5], 3), vec![0.5]);
        assert!(step_factors(&[], 3).is_empty());
    }
}
