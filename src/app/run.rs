//! `saddle run`: a loaded scene solved and written — `summary.json` and `solution.vtu` for one
//! step; a scene with a `[load_path]` step by step ([`super::path`]). Nothing is written unless
//! the solve returns a solution.

use super::path;
use super::setup::{Loaded, Outcome, RunError};
use crate::io::outdir::OutDir;
use crate::io::summary::Summary;
use crate::io::vtu::write_vtu;
use saddle_core::{Evolution, Monitor, PathError, ProblemView, Solution};
use std::path::{Path, PathBuf};

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
    let mut out = OutDir::claim(out_dir)?;
    let mut timer = loaded.timer.clone();
    // one step at the scene's load from the zero state: the stationary problem, through the same
    // load-scaling path as sweeps and load paths (an obstacle without load leaves its extras
    // undetermined, theory §11.3)
    let mut evolution = Evolution::new(&loaded.problem);
    let step = match timer.time("solve", || evolution.step(1.0, loaded.solver.as_ref(), monitor)) {
        Ok(step) => step,
        Err(e) => {
            out.abandon();
            return Err(match e {
                PathError::Solve { source, .. } => RunError::Solve(source),
                PathError::Scene { source, .. } => RunError::Scene(source),
            });
        }
    };
    let view = step.problem.view();
    let mut summary = timer.time("summary", || Summary::new(view, &step.solution, loaded.title.clone()));
    summary.warnings.extend(step.warnings.iter().cloned());
    let (vtu_tmp, vtu) = timer.time("write", || write_vtu_file(out_dir, view, &step.solution))?;
    summary.end_to_end = timer.into_phases().into_iter().collect();
    summary.end_to_end_s = summary.end_to_end.values().sum();
    write_summary(out_dir, &summary, &vtu_tmp, &vtu)?;
    out.wrote("solution.vtu")?;
    out.wrote("summary.json")?;
    let written = out.finish()?;
    Ok(Outcome { solution: step.solution, summary, out_dir: out_dir.to_path_buf(), written })
}

fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> RunError + use<> {
    let path = path.to_path_buf();
    move |source| RunError::Io { path, source }
}

/// Writes solution.vtu under a temporary name in `out_dir`: (temporary, final) path.
fn write_vtu_file(out_dir: &Path, p: ProblemView<'_>, sol: &Solution) -> Result<(PathBuf, PathBuf), RunError> {
    let vtu = out_dir.join("solution.vtu");
    let vtu_tmp = out_dir.join(".solution.vtu.partial");
    write_vtu(&vtu_tmp, p, sol).map_err(io_error(&vtu))?;
    Ok((vtu_tmp, vtu))
}

/// Writes summary.json under a temporary name, then moves both files into place, so that a
/// failure leaves no half-written file.
fn write_summary(out_dir: &Path, summary: &Summary, vtu_tmp: &Path, vtu: &Path) -> Result<(), RunError> {
    let json = out_dir.join("summary.json");
    let json_tmp = out_dir.join(".summary.json.partial");
    summary.write(&json_tmp).map_err(io_error(&json))?;
    std::fs::rename(vtu_tmp, vtu).map_err(io_error(vtu))?;
    std::fs::rename(&json_tmp, &json).map_err(io_error(&json))?;
    Ok(())
}
