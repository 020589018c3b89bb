//! `saddle run`: a loaded scene solved and written — `summary.json` and `solution.vtu` for one
//! step; a scene with a `[load_path]` step by step ([`super::path`]). Nothing is written unless
//! the solve returns a solution.

use super::path;
use super::setup::{Loaded, Outcome, RunError, finish};
use crate::io::summary::estimate::EstimateSummary;
use crate::io::vtu::CellField;
use saddle_core::{Evolution, Monitor, PathError, ProblemView};
use std::path::Path;

/// Solves a loaded problem and writes `out_dir/summary.json` and `out_dir/solution.vtu`. The
/// folder is claimed before the solve ([`OutDir::claim`]: an unusable `--out` fails before any
/// work) and, once written, holds only this run's files of saddle ([`OutDir::finish`]). The
/// summary's `end_to_end` holds the wall time of every phase the user waits for: `read` and
/// `setup` (from [`load`](super::setup::load)), `solve`, `summary` (the KKT residuals and
/// energies recomputed from the solution) and `write` (solution.vtu; summary.json is written
/// last, after the clock).
pub fn solve_and_write(loaded: &Loaded, out_dir: &Path, monitor: &mut dyn Monitor) -> Result<Outcome, RunError> {
    solve_and_write_with(loaded, out_dir, monitor, &mut |_| {})
}

/// [`solve_and_write`], with a line per load step to `progress`. A scene with a `[load_path]` is
/// solved step by step ([`path::solve_and_write`]: `solution_NNNN.vtu`, `solution.pvd`,
/// `load_path.csv`, `summary.json` with `steps`).
pub fn solve_and_write_with(
    loaded: &Loaded,
    out_dir: &Path,
    monitor: &mut dyn Monitor,
    progress: &mut dyn FnMut(&str),
) -> Result<Outcome, RunError> {
    if let Some(path) = &loaded.load_path {
        return path::solve_and_write(loaded, path, out_dir, monitor, progress);
    }
    let ranks = loaded.ranks.as_ref();
    let out = RunError::agree(ranks, ranks.claim(out_dir).map_err(RunError::from))?;
    let mut timer = loaded.timer.clone();
    // one step at the scene's load from the zero state: the stationary problem, through the same
    // load-scaling path as sweeps and load paths (an obstacle without load leaves its extras
    // undetermined, theory §11.3)
    let mut evolution = Evolution::new(&loaded.problem);
    let step = timer.time("solve", || evolution.step(1.0, loaded.solver.as_ref(), monitor)).map_err(|e| match e {
        PathError::Solve { source, .. } => RunError::Solve(source),
        PathError::Scene { source, .. } => RunError::Scene(source),
    });
    let step = match RunError::agree(ranks, step) {
        Ok(step) => step,
        Err(e) => {
            out.abandon();
            return Err(e);
        }
    };
    let view = step.problem.view();
    let mut summary = timer.time("summary", || ranks.summary(view, &step.solution, loaded.title.clone()));
    summary.warnings.extend(step.warnings.iter().cloned());
    // the a posteriori estimate (theory §15), on one machine
    let estimate = (loaded.output.error_estimate && ranks.size() == 1)
        .then(|| timer.time("estimate", || saddle_core::estimate(view.element, &view.l, &step.solution.stress)));
    if let Some(w) = estimate.as_ref().and_then(|e| goal_estimate_warning(view, &step.solution.u, e)) {
        summary.warnings.push(w);
    }
    let cells: Vec<CellField<'_>> = estimate.iter().map(|e| ("error_indicator", &e.indicators[..])).collect();
    let files = timer.time("write", || ranks.write_solution(out_dir, "solution", view, &step.solution, &cells));
    let files = RunError::agree(ranks, files.map_err(io_error(&out_dir.join("solution"))))?;
    summary.end_to_end = timer.into_phases().into_iter().collect();
    summary.end_to_end_s = summary.end_to_end.values().sum();
    summary.error_estimate = estimate.map(|e| {
        let phase = |k: &str| summary.end_to_end.get(k).copied().unwrap_or(0.0);
        EstimateSummary::new(&e, view.extra_names(), phase("estimate"), phase("solve"))
    });
    ranks.describe(&mut summary);
    let written = finish(ranks, out, &summary, &files, out_dir)?;
    Ok(Outcome { solution: step.solution, summary, out_dir: out_dir.to_path_buf(), written })
}

/// The extras' compliance estimates η²/|f| assume the element's energy is the continuous one
/// on its space (theory §15.2); where the element's strain is not ε(u) (B̄), its consistency
/// energy δ = (a − a_h)(u, u) enters the identity. A warning when δ exceeds a tenth of η².
fn goal_estimate_warning(view: ProblemView<'_>, u: &[f64], e: &saddle_core::ErrorEstimate) -> Option<String> {
    if e.extras.iter().all(Option::is_none) {
        return None;
    }
    let delta = view.element.strain_consistency_energy(view.l.data.elasticity, u);
    let eta2 = e.energy * e.energy;
    (delta > 0.1 * eta2).then(|| {
        format!(
            "error_estimate: the element's strain is not the strain of its displacements (its \
             consistency energy {delta:.3e} is {:.1} η²), so the extras' estimates η²/|f| are loose: \
             from 0.6 to 15 times the true error where measured (theory §15.4); the energy \
             estimate is not affected",
            delta / eta2.max(f64::MIN_POSITIVE)
        )
    })
}

fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> RunError + use<> {
    let path = path.to_path_buf();
    move |source| RunError::Io { path, source }
}
