//! `saddle report`: accuracy and cost of the solvers on a scene (theory §4, §5) and the mesh
//! convergence of the discretisation (theory §3 Theorem 2, §7).
//!
//! [`generate`] writes into a folder:
//!
//! * `work_precision.csv`, `work_precision.png`, `work_precision.svg` — every solver along a
//!   ladder of settings ([`runs::ladder`]), each run's wall time and its errors against a tightly
//!   converged reference of the same discrete problem (Newton to 1e-13, [`runs::reference_solver`]);
//! * `convergence.csv`, `convergence.png`, `convergence.svg` — the scene on a sequence of refined
//!   box meshes ([`convergence`], [`LEVELS`]), each solved by the reference solver; errors against
//!   the finest level through the transfer of P0 fields ([`transfer`]), observed rates next to
//!   Theorem 2's guaranteed 1/2, a Richardson extrapolation of U. A scene whose mesh is not a
//!   `box` gets no study: `convergence.csv` holds its header only and `report.md` says why;
//! * `elements.csv`, `elements.png`, `elements.svg` — P1 against P2 ([`elements`], theory §10):
//!   the convergence study repeated with the other element on meshes with the same nodes, U of
//!   every level against one reference, wall times, and which element reaches an accuracy of U
//!   sooner;
//! * `report.md` — the tables, the observed σ̂ rate against 1/2, each solver at its tightest
//!   setting, links to the images.
//!
//! The plots need the cargo feature `report` (on by default; [`plot`]); without it the CSV files
//! and `report.md` are written and `report.md` says that the images were not drawn.
//!
//! The parts are public so that tests can check them: the error measures ([`runs::errors`],
//! [`transfer::field_distance`]), point location ([`transfer::Locator`]), rates and Richardson
//! ([`convergence`]), the writers ([`tables`]).

pub mod convergence;
pub mod elements;
#[cfg(feature = "report")]
pub mod plot;
pub mod runs;
pub mod tables;
pub mod transfer;

use crate::scene::Scene;
use convergence::{ConvergenceStudy, LevelResult, mesh_size, refinement_levels};
use runs::{RunRecord, Rung, RungKind, Timed, ladder, record, reference_solver, timed_polish, timed_solve};
use saddle_core::{DiscreteProblem, Monitor, SceneError, Silent, Solution, SolveError, Workspace, kkt};
use std::path::{Path, PathBuf};
use std::time::Instant;
use thiserror::Error;
pub use transfer::OutsideMesh;
use transfer::{Quadrature, SampleMap};

/// Why a report could not be made.
#[derive(Debug, Error)]
pub enum ReportError {
    /// The scene (or a refined version of it) is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The reference solve failed: no error can be measured.
    #[error("the reference solve (Newton, tol = 1e-13) failed: {0}")]
    Reference(SolveError),
    /// A refined mesh does not cover the same domain.
    #[error("mesh convergence: {0}")]
    Transfer(#[from] OutsideMesh),
    /// A file could not be written.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A plot could not be drawn.
    #[error("cannot draw {path}: {message}")]
    Plot {
        /// The image.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

/// Progress over the runs of a report (a progress bar); it also follows each solve as its
/// [`Monitor`].
pub trait Progress: Monitor {
    /// The number of runs the report will make.
    fn plan(&mut self, _runs: usize) {}
    /// Run `index` (0-based) starts.
    fn start(&mut self, _index: usize, _label: &str) {}
    /// Run `index` ended with `status`.
    fn finish(&mut self, _index: usize, _label: &str, _status: &str) {}
}

impl Progress for Silent {}

/// Options of a report.
#[derive(Clone, Copy, Debug, Default)]
pub struct ReportOptions {
    /// Fewer rungs and levels (tests, CI).
    pub quick: bool,
}

/// Refinement factors of the scene's cells: for the default scene (32×32×16) 4, 6, 8, 11, 16
/// and 22 cells across the half-width — the scene's mesh is one below the finest level. The
/// finest level costs the most: on the default scene 120k dofs, ~130 s and 2.4 GB for Newton.
pub const LEVELS: [f64; 6] = [0.25, 0.375, 0.5, 0.6875, 1.0, 1.375];
/// Refinement factors with `quick` (the scene's mesh is the finest level).
pub const QUICK_LEVELS: [f64; 3] = [0.5, 0.75, 1.0];

/// A scene as loaded from its file, to build it and refined versions of it: variants are made
/// by changing the typed [`Scene`] value (its box mesh's cells), never by editing TOML text.
#[derive(Clone, Debug)]
pub struct SceneSource {
    /// The file (relative mesh files are resolved against its folder).
    pub path: PathBuf,
    /// The scene, validated when it was read.
    pub scene: Scene,
}

impl SceneSource {
    /// Reads and validates a scene file.
    pub fn read(path: &Path) -> Result<Self, ReportError> {
        Ok(Self { path: path.to_path_buf(), scene: Scene::from_file(path)? })
    }

    /// The scene; with `cells`, its structured mesh with those cells (see [`Scene::with_cells`]).
    pub fn scene(&self, cells: Option<[usize; 3]>) -> Result<Scene, ReportError> {
        Ok(match cells {
            None => self.scene.clone(),
            Some(c) => self.scene.with_cells(c)?,
        })
    }

    /// The assembled problem (with `cells`: on the refined box mesh).
    pub fn problem(&self, cells: Option<[usize; 3]>) -> Result<DiscreteProblem, ReportError> {
        Ok(self.scene(cells)?.into_problem()?.0)
    }

    /// The title: the scene's, else the file name.
    pub fn title(&self) -> String {
        self.scene
            .title
            .clone()
            .unwrap_or_else(|| self.path.file_name().map_or("scene".into(), |n| n.to_string_lossy().into_owned()))
    }

    /// The cells of the scene's structured mesh, or why the scene has none (mesh convergence
    /// needs a mesh that refines by cell counts, the `box` mesh).
    pub fn box_cells(&self) -> Result<[usize; 3], String> {
        self.scene.mesh.cells().ok_or_else(|| {
            format!(
                "mesh convergence needs a `box` mesh (refined by scaling `mesh.cells`); this scene's mesh is `{}`",
                self.scene.mesh.name()
            )
        })
    }
}

/// Everything a report measured.
#[derive(Clone, Debug)]
pub struct Report {
    /// The scene file.
    pub scene: PathBuf,
    /// Its title.
    pub title: String,
    /// Free dofs, elements and contact rows of the scene.
    pub dofs: usize,
    /// Tetrahedra.
    pub elements: usize,
    /// Candidate contact nodes (rows of K_h).
    pub contact_rows: usize,
    /// Whether `quick` was set.
    pub quick: bool,
    /// Cores available (`std::thread::available_parallelism`).
    pub cores: usize,
    /// The work–precision runs, the reference among them.
    pub runs: Vec<RunRecord>,
    /// The cells of the scene's box mesh (None for other meshes).
    pub scene_cells: Option<[usize; 3]>,
    /// The convergence study, or why there is none.
    pub convergence: Result<ConvergenceStudy, String>,
    /// P1 against P2 on meshes with the same nodes ([`elements`]), or why there is none.
    pub element_comparison: Result<elements::ElementComparison, String>,
    /// Wall time of the whole report, seconds.
    pub total_s: f64,
    /// Whether the images were drawn (feature `report`).
    pub plots: bool,
}

impl Report {
    /// The reference run.
    pub fn reference(&self) -> Option<&RunRecord> {
        self.runs.iter().find(|r| r.reference)
    }
}

/// Runs the work–precision ladder on `l`: the reference ([`runs::reference_solver`]) first,
/// then every other rung. Returns the records in ladder order (the [`RungKind::Reference`] rung
/// reports the reference run), the reference solution and its wall time. `counter` numbers the
/// runs for `progress`.
pub fn work_precision(
    problem: &DiscreteProblem,
    rungs: &[Rung],
    progress: &mut dyn Progress,
    counter: &mut usize,
) -> Result<(Vec<RunRecord>, Solution, f64), ReportError> {
    let l = &problem.lagrangian();
    let reference_rung = rungs
        .iter()
        .find(|r| matches!(r.kind, RungKind::Reference))
        .map(|r| r.label())
        .unwrap_or_else(|| "newton (reference)".into());
    progress.start(*counter, &reference_rung);
    let timed = timed_solve(&reference_solver(), l, progress);
    let reference_wall = timed.wall_s;
    let reference = timed.result.map_err(ReportError::Reference)?;
    progress.finish(*counter, &reference_rung, runs::status_of(reference.report.stop_reason));
    *counter += 1;
    let reference_timed = Timed { result: Ok(reference), wall_s: reference_wall };
    let mut records: Vec<RunRecord> = Vec::with_capacity(rungs.len());
    // solutions kept for the rungs that a polish starts from
    let mut kept: Vec<Option<Solution>> = (0..rungs.len()).map(|_| None).collect();
    let needed: Vec<usize> = rungs
        .iter()
        .filter_map(|r| match r.kind {
            RungKind::Polish { from, .. } => Some(from),
            _ => None,
        })
        .collect();
    let reference = reference_timed.result.as_ref().expect("checked above");
    for (i, rung) in rungs.iter().enumerate() {
        if matches!(rung.kind, RungKind::Reference) {
            records.push(record(problem, rung, &reference_timed, reference));
            continue;
        }
        let label = rung.label();
        progress.start(*counter, &label);
        let (timed, start) = match &rung.kind {
            RungKind::Solve(solver) => (timed_solve(solver.as_ref(), l, progress), None),
            RungKind::Polish { from, newton } => match kept.get(*from).and_then(|s| s.as_ref()) {
                Some(start) => (timed_polish(newton, l, start, progress), Some(*from)),
                None => (
                    Timed {
                        result: Err(SolveError::Unsupported {
                            solver: rung.solver.into(),
                            message: format!(
                                "no solution to polish: rung {from} ({}) failed or has not run",
                                rungs.get(*from).map_or("none".into(), |r| r.label())
                            ),
                        }),
                        wall_s: 0.0,
                    },
                    None,
                ),
            },
            RungKind::Reference => unreachable!("handled above"),
        };
        let mut rec = record(problem, rung, &timed, reference);
        if let Some(from) = start {
            runs::add_start_time(&mut rec, &records[from]);
        }
        progress.finish(*counter, &label, &rec.status);
        *counter += 1;
        records.push(rec);
        if needed.contains(&i) {
            kept[i] = timed.result.ok();
        }
    }
    let Timed { result, .. } = reference_timed;
    Ok((records, result.expect("checked above"), reference_wall))
}

/// A level whose solve is already known (the work–precision reference on the scene's mesh).
pub struct KnownLevel {
    /// Its cells.
    pub cells: [usize; 3],
    /// The problem.
    pub problem: DiscreteProblem,
    /// Its solution by [`runs::reference_solver`].
    pub solution: Solution,
    /// The solve's wall time, seconds.
    pub wall_s: f64,
}

/// A level's solve and its fields, kept while the next coarser level is compared with it.
struct Solved {
    l: DiscreteProblem,
    stress: saddle_core::StressField,
    strain: Vec<saddle_core::Sym>,
}

/// The mesh convergence study of `source` on the box meshes `levels` (ascending; the last is
/// the finest and the reference of the errors). Every level is solved by
/// [`runs::reference_solver`], except a level given as `known`. Levels are processed from fine
/// to coarse, so that only the finest and the next finer level are kept in memory.
pub fn convergence_study(
    source: &SceneSource,
    levels: &[[usize; 3]],
    known: Option<KnownLevel>,
    progress: &mut dyn Progress,
    counter: &mut usize,
) -> Result<ConvergenceStudy, ReportError> {
    let solver = reference_solver();
    let mut known = known;
    let mut solve_level = |cells: [usize; 3], progress: &mut dyn Progress| -> Result<_, ReportError> {
        if let Some(k) = known.take_if(|k| k.cells == cells) {
            return Ok((k.problem, Timed { result: Ok(k.solution), wall_s: k.wall_s }));
        }
        let l = source.problem(Some(cells))?;
        let label = format!(
            "convergence: newton on {}x{}x{} cells ({} dofs)",
            cells[0],
            cells[1],
            cells[2],
            l.element.n_dofs()
        );
        progress.start(*counter, &label);
        let timed = timed_solve(&solver, &l.lagrangian(), progress);
        let status = match &timed.result {
            Ok(s) => runs::status_of(s.report.stop_reason).to_string(),
            Err(e) => format!("error: {e}"),
        };
        progress.finish(*counter, &label, &status);
        *counter += 1;
        Ok((l, timed))
    };
    // U as the single obstacle reports it, by name
    let u_of = |p: &DiscreteProblem, s: &Solution| crate::output::single_quantity(p.view(), s, "U").unwrap_or(f64::NAN);
    let level_result = |p: &DiscreteProblem, cells: [usize; 3], timed: &Timed| {
        let l = &p.lagrangian();
        let (status, converged, iterations, kkt, u) = match &timed.result {
            Ok(s) => (
                runs::status_of(s.report.stop_reason).to_string(),
                s.report.converged,
                s.report.iterations,
                kkt(l, &s.iterate(), &mut Workspace::new(l)).max(),
                u_of(p, s),
            ),
            Err(e) => (format!("error: {e}"), false, 0, f64::NAN, f64::NAN),
        };
        LevelResult {
            cells,
            dofs: l.n_dofs(),
            elements: l.n_points(),
            size: mesh_size(p),
            wall_s: timed.wall_s,
            status,
            converged,
            iterations,
            kkt,
            u,
            err_u: f64::NAN,
            err_u_richardson: f64::NAN,
            err_stress: f64::NAN,
            err_strain: f64::NAN,
            diff_stress_next: f64::NAN,
        }
    };
    let Some((&finest_cells, coarser)) = levels.split_last() else {
        return Ok(ConvergenceStudy::from_levels(vec![]));
    };
    let (fl, finest_timed) = solve_level(finest_cells, progress)?;
    let mut finest_result = level_result(&fl, finest_cells, &finest_timed);
    let fsol = finest_timed.result.map_err(ReportError::Reference)?;
    finest_result.err_u = 0.0;
    finest_result.err_stress = 0.0;
    finest_result.err_strain = 0.0;
    let fine_metric = transfer::Metric::of(&fl);
    let (fine_stress, fine_strain) = transfer::p0_fields(&fl, &fsol.u, &fsol.stress);
    let u_f = u_of(&fl, &fsol);
    let mut results = vec![finest_result];
    // the next finer level that was solved, for the consecutive differences
    let mut finer: Option<Solved> = None;
    for &cells in coarser.iter().rev() {
        let (l, timed) = solve_level(cells, progress)?;
        let mut res = level_result(&l, cells, &timed);
        if let Ok(sol) = timed.result {
            let (stress, strain) = transfer::p0_fields(&l, &sol.u, &sol.stress);
            let map = SampleMap::new(l.element.mesh(), fl.element.mesh(), Quadrature::default())?;
            let d = transfer::field_distance(&fine_metric, &fine_stress, &fine_strain, &stress, &strain, &map);
            res.err_u = (res.u - u_f).abs() / u_f.abs();
            res.err_stress = d.stress_energy;
            res.err_strain = d.strain_l2;
            res.diff_stress_next = match &finer {
                None => d.stress_energy,
                Some(next) => {
                    let map = SampleMap::new(l.element.mesh(), next.l.element.mesh(), Quadrature::default())?;
                    let metric = transfer::Metric::of(&next.l);
                    transfer::field_distance(&metric, &next.stress, &next.strain, &stress, &strain, &map).stress_energy
                }
            };
            finer = Some(Solved { l, stress, strain });
        }
        results.push(res);
    }
    results.reverse();
    Ok(ConvergenceStudy::from_levels(results))
}

/// Makes the report of the scene file `scene` in `out` (module docs).
pub fn generate(
    scene: &Path,
    out: &Path,
    options: &ReportOptions,
    progress: &mut dyn Progress,
) -> Result<Report, ReportError> {
    let t0 = Instant::now();
    let source = SceneSource::read(scene)?;
    let l = source.problem(None)?;
    let rungs = ladder(options.quick);
    let base = source.box_cells();
    let levels: Result<Vec<[usize; 3]>, String> = base.clone().map(|base| {
        let factors: &[f64] = if options.quick { &QUICK_LEVELS } else { &LEVELS };
        let mut levels = refinement_levels(base, factors);
        if !levels.contains(&base) {
            levels.push(base);
            levels.sort_by_key(|c| c[0] * c[1] * c[2]);
        }
        levels
    });
    // the scene's own level is the work–precision reference: not solved again
    let other_levels = levels.as_ref().map_or(0, |v| v.len().saturating_sub(1));
    // the other element's levels, on meshes with the same nodes (theory §10)
    let own = source.scene.element_name();
    let other = if own == "p2" { "p1" } else { "p2" };
    let other_levels_cells = levels
        .as_ref()
        .ok()
        .filter(|v| v.len() >= 2)
        .map(|v| if other == "p2" { elements::p2_levels(v) } else { elements::p1_levels(v) });
    let solves = 1
        + rungs.iter().filter(|r| !matches!(r.kind, RungKind::Reference)).count()
        + other_levels
        + other_levels_cells.as_ref().map_or(0, |v| v.len());
    progress.plan(solves);
    let mut counter = 0;
    std::fs::create_dir_all(out).map_err(|source| ReportError::Io { path: out.to_path_buf(), source })?;
    let (runs, reference, reference_wall) = work_precision(&l, &rungs, progress, &mut counter)?;
    let (dofs, elements, contact_rows) = (l.element.n_dofs(), l.element.n_points(), l.obstacles.rows().n_rows());
    let convergence = match levels {
        Ok(levels) if levels.len() >= 2 => {
            let cells = *base.as_ref().expect("levels come from the base cells");
            let known = KnownLevel { cells, problem: l, solution: reference, wall_s: reference_wall };
            Ok(convergence_study(&source, &levels, Some(known), progress, &mut counter)?)
        }
        Ok(_) => Err("the scene's mesh is too coarse to coarsen (fewer than two distinct levels)".to_string()),
        Err(why) => Err(why),
    };
    let comparison = match (&convergence, other_levels_cells) {
        (Ok(own_study), Some(cells)) => {
            let element: Box<dyn saddle_core::FiniteElement> =
                if other == "p2" { Box::new(saddle_core::P2::default()) } else { Box::new(saddle_core::P1::default()) };
            let other_source = SceneSource { scene: source.scene.with_element(element), ..source.clone() };
            let other_study = convergence_study(&other_source, &cells, None, progress, &mut counter)?;
            Ok(if other == "p2" {
                elements::ElementComparison::new(own_study.clone(), other_study)
            } else {
                elements::ElementComparison::new(other_study, own_study.clone())
            })
        }
        (Err(why), _) => Err(why.clone()),
        (Ok(_), None) => Err("no levels to compare".to_string()),
    };
    let mut report = Report {
        scene: scene.to_path_buf(),
        title: source.title(),
        dofs,
        elements,
        contact_rows,
        quick: options.quick,
        cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
        runs,
        scene_cells: base.ok(),
        convergence,
        element_comparison: comparison,
        total_s: 0.0,
        plots: cfg!(feature = "report"),
    };
    write_outputs(&mut report, out, t0)?;
    Ok(report)
}

/// Writes the CSV files, the images (feature `report`) and `report.md`; the total time is taken
/// just before `report.md`.
fn write_outputs(report: &mut Report, out: &Path, t0: Instant) -> Result<(), ReportError> {
    let write = |name: &str, text: &str| {
        let path = out.join(name);
        std::fs::write(&path, text).map_err(|source| ReportError::Io { path, source })
    };
    write("work_precision.csv", &tables::work_precision_csv(&report.runs))?;
    write("convergence.csv", &tables::convergence_csv(report.convergence.as_ref().ok()))?;
    if let Ok(c) = &report.element_comparison {
        write("elements.csv", &c.csv())?;
    }
    #[cfg(feature = "report")]
    {
        plot::work_precision(report, &out.join("work_precision.png"), &out.join("work_precision.svg"))?;
        if let Ok(study) = &report.convergence {
            plot::convergence(report, study, &out.join("convergence.png"), &out.join("convergence.svg"))?;
        }
        if let Ok(c) = &report.element_comparison {
            plot::elements(&c.series(), &out.join("elements.png"), &out.join("elements.svg"))?;
        }
    }
    report.total_s = t0.elapsed().as_secs_f64();
    write("report.md", &tables::markdown(report))?;
    Ok(())
}
