//! The first phases of a run (`read`, `setup`): a scene file read, validated and assembled into
//! a [`Loaded`] problem with its solver; and what a run returns ([`Outcome`], [`RunError`]) —
//! shared by a one-step run ([`super::run`]) and a load path ([`super::path`]).

use super::ranks::{OneMachine, Ranks, write_in_place};
use crate::io::outdir::{OutDir, OutError};
use crate::io::scene::{LoadPath, OutputSettings, Scene};
use crate::io::summary::Summary;
use saddle_core::{DiscreteProblem, PhaseTimer, SceneError, Solution, SolveError, Solver};
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
    /// Another rank of a distributed run failed (theory §12): its message.
    #[error("{0}")]
    Ranks(String),
}

impl RunError {
    /// `result` on every rank ([`Ranks::agree`]): an error on any rank is an error on all, this
    /// rank's own where it failed, the failing rank's message on the others. Collective.
    pub fn agree<T>(ranks: &dyn Ranks, result: Result<T, RunError>) -> Result<T, RunError> {
        let shared = ranks.agree(result.as_ref().map(|_| ()).map_err(|e| e.to_string()));
        match (result, shared) {
            (Err(e), _) => Err(e),
            (Ok(_), Err(message)) => Err(RunError::Ranks(message)),
            (Ok(x), Ok(())) => Ok(x),
        }
    }
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
    pub load_path: Option<LoadPath>,
    /// Wall time of the phases so far: `read` (the scene file, and the mesh built or read) and
    /// `setup` (L assembled).
    pub timer: PhaseTimer,
    /// Where the problem lives: this process ([`OneMachine`]) or the ranks of `mpirun`.
    pub ranks: Box<dyn Ranks>,
    /// The scene's `[output]` settings.
    pub output: OutputSettings,
}

/// Reads a scene, applies a `--solver` override, and assembles L.
pub fn load(scene: &Path, solver_override: Option<&str>) -> Result<Loaded, RunError> {
    load_with(scene, solver_override, |_| Ok(()))
}

/// [`load`], with `edit` applied to the scene after it is read (for example another mesh
/// file, as `saddle bench --meshes` does, or `--cells`); the time of the edit counts as `read`.
pub fn load_with(
    scene: &Path,
    solver_override: Option<&str>,
    edit: impl FnOnce(&mut Scene) -> Result<(), SceneError>,
) -> Result<Loaded, RunError> {
    let mut timer = PhaseTimer::default();
    let (scene, mesh) = timer.time("read", || -> Result<_, RunError> {
        let mut scene = Scene::from_file(scene)?;
        edit(&mut scene)?;
        let mesh = scene.build_mesh()?;
        Ok((scene, mesh))
    })?;
    let title = scene.title.clone();
    let load_path = scene.load_path.clone();
    let output = scene.output.clone();
    let override_solver = solver_override.map(solver_by_type).transpose()?;
    let (problem, solver) = timer.time("setup", || scene.assemble(mesh))?;
    let solver = override_solver.or(solver).unwrap_or_else(default_solver);
    Ok(Loaded { problem, solver, title, load_path, timer, ranks: Box::new(OneMachine), output })
}

/// The result of a run.
pub struct Outcome {
    /// The solution.
    pub solution: Solution,
    /// Its summary (also written as `summary.json`).
    pub summary: Summary,
    /// Where the files went.
    pub out_dir: PathBuf,
    /// The files written into it, in order (the folder's manifest, [`crate::io::outdir`]).
    pub written: Vec<String>,
}

/// The end of a run on the root: the solution's files and `summary.json` (under a temporary
/// name first) entered in the manifest, the folder cleaned of the earlier run's files; every
/// rank learns whether it worked. Collective.
pub fn finish(
    ranks: &dyn Ranks,
    mut out: OutDir,
    summary: &Summary,
    files: &[String],
    out_dir: &Path,
) -> Result<Vec<String>, RunError> {
    let written = if ranks.is_root() {
        (|| {
            for f in files {
                out.wrote(f)?;
            }
            let json = out_dir.join("summary.json");
            write_in_place(out_dir, "summary.json", |p| summary.write(p))
                .map_err(|source| RunError::Io { path: json.clone(), source })?;
            out.wrote("summary.json")?;
            Ok(out.finish()?)
        })()
    } else {
        Ok(out.finish()?)
    };
    RunError::agree(ranks, written)
}
