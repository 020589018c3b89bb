//! Running a scene file end to end: read and validate, assemble, solve, summarise, write
//! `summary.json` and `solution.vtu`. Nothing is written unless the solve returns a solution.

use crate::outdir::{OutDir, OutError};
use crate::output::{Summary, write_vtu};
use crate::scene::Scene;
use saddle_core::{
    DiscreteProblem, Evolution, Monitor, PathError, PhaseTimer, ProblemView, SceneError, Solution, SolveError, Solver,
};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why a run failed.
#[derive(Debug, Error)]
pub enum RunError {
    /// The scene is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The solver failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// `--solver` names no known solver.
    #[error("--solver {name}: {message}")]
    UnknownSolver { name: String, message: String },
    /// Output could not be written.
    #[error("cannot write {path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// The first step of a load path failed (a later one is recorded in the summary).
    #[error("load path: {0}")]
    Path(#[from] saddle_core::PathError),
    /// `--out` cannot be used, or a file in it cannot be written.
    #[error(transparent)]
    Out(#[from] OutError),
}

/// The solver used when a scene names none: the paper's Uzawa method.
pub fn default_solver() -> Box<dyn Solver> {
    Box::new(saddle_solvers::Uzawa::default())
}

/// A solver of type `name` with its default parameters (as `[solver] type = "name"`): the
/// registered solver types are looked up by their `type` tag, so solvers added by plugins are
/// found too; an unknown name lists the known ones.
pub fn solver_by_type(name: &str) -> Result<Box<dyn Solver>, RunError> {
    let table = toml::Table::from_iter([("type".to_string(), toml::Value::String(name.to_string()))]);
    toml::Value::Table(table)
        .try_into::<Box<dyn Solver>>()
        .map_err(|e| RunError::UnknownSolver { name: name.to_string(), message: e.message().to_string() })
}

/// A loaded problem: the discrete problem, the solver to use, and the scene's title.
pub struct Loaded {
    /// The discrete problem: the element and the problem's data.
    pub problem: DiscreteProblem,
    /// The solver (the scene's, the override, or the default).
    pub solver: Box<dyn Solver>,
    /// Scene title.
    pub title: Option<String>,
    /// The scene's `[load_path]`, if any.
    pub load_path: Option<crate::scene::LoadPath>,
    /// Wall time of the phases so far: `read` (the scene file, and the mesh built or read) and
    /// `setup` (L assembled).
    pub timer: PhaseTimer,
}

/// Reads a scene, applies a `--solver` override, and assembles L.
pub fn load(scene: &Path, solver_override: Option<&str>) -> Result<Loaded, RunError> {
    load_with(scene, solver_override, |_| {})
}

/// [`load`], with `edit` applied to the scene after it is read (for example another mesh
/// file, as `saddle bench --meshes` does); the time of the edit counts as `read`.
pub fn load_with(
    scene: &Path,
    solver_override: Option<&str>,
    edit: impl FnOnce(&mut Scene),
) -> Result<Loaded, RunError> {
    let mut timer = PhaseTimer::default();
    let (scene, mesh) = timer.time("read", || -> Result<_, RunError> {
        let mut scene = Scene::from_file(scene)?;
        edit(&mut scene);
        let mesh = scene.build_mesh()?;
        Ok((scene, mesh))
    })?;
    let title = scene.title.clone();
    let load_path = scene.load_path.clone();
    let override_solver = solver_override.map(solver_by_type).transpose()?;
    let (problem, solver) = timer.time("setup", || scene.assemble(mesh))?;
    let solver = override_solver.or(solver).unwrap_or_else(default_solver);
    Ok(Loaded { problem, solver, title, load_path, timer })
}

/// The result of a run.
pub struct Outcome {
    /// The solution.
    pub solution: Solution,
    /// Its summary (also written as `summary.json`).
    pub summary: Summary,
    /// Where the files went.
    pub out_dir: PathBuf,
    /// The files written into it, in order (the folder's manifest, [`crate::outdir`]).
    pub written: Vec<String>,
}

/// Solves a loaded problem and writes `out_dir/summary.json` and `out_dir/solution.vtu`. The
/// folder is claimed before the solve ([`OutDir::claim`]: an unusable `--out` fails before any
/// work) and, once written, holds only this run's files of saddle ([`OutDir::finish`]). The
/// summary's `end_to_end` holds the wall time of every phase the user waits for: `read` and
/// `setup` (from [`load`]), `solve`, `summary` (the KKT residuals and energies recomputed from
/// the solution) and `write` (solution.vtu; summary.json is written last, after the clock).
pub fn solve_and_write(loaded: &Loaded, out_dir: &Path, monitor: &mut dyn Monitor) -> Result<Outcome, RunError> {
    solve_and_write_with(loaded, out_dir, monitor, &mut |_| {})
}

/// [`solve_and_write`], with a line per load step to `progress`. A scene with a `[load_path]` is
/// solved step by step ([`crate::path::solve_and_write`]: `solution_NNNN.vtu`, `solution.pvd`,
/// `load_path.csv`, `summary.json` with `steps`).
pub fn solve_and_write_with(
    loaded: &Loaded,
    out_dir: &Path,
    monitor: &mut dyn Monitor,
    progress: &mut dyn FnMut(&str),
) -> Result<Outcome, RunError> {
    if let Some(path) = &loaded.load_path {
        return crate::path::solve_and_write(loaded, path, out_dir, monitor, progress);
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
