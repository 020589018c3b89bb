//! The measurements of `saddle report`: the work–precision runs of every solver against a tight
//! reference ([`work_precision`]) and the mesh convergence study ([`convergence_study`]), with
//! the scene they are made on ([`SceneSource`]) and everything measured ([`Report`]).

use super::convergence::{ConvergenceStudy, LevelResult, mesh_size};
use super::elements::ElementComparison;
use super::runs::{self, RunRecord, Rung, RungKind, Timed, record, reference_solver, timed_polish, timed_solve};
use super::transfer::{self, OutsideMesh, Quadrature, SampleMap};
#[cfg(feature = "report")]
use crate::io::plot::PlotError;
use crate::io::scene::Scene;
use crate::io::summary::{first_quantity, named_quantity};
use saddle_core::{DiscreteProblem, Monitor, SceneError, Silent, Solution, SolveError, Workspace, kkt};
use std::path::{Path, PathBuf};
use thiserror::Error;

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
    /// `--levels` that name no levels of a mesh family.
    #[error("--levels {levels:?}: {why} ({scene})")]
    Levels {
        /// The levels asked for.
        levels: Vec<usize>,
        /// What is wrong with them.
        why: &'static str,
        /// The scene file.
        scene: PathBuf,
    },
    /// `--quantity` that names no quantity the scene reports.
    #[error("--quantity {name:?} is not a quantity the scene reports; known: {known} ({scene})")]
    Quantity {
        /// The name asked for.
        name: String,
        /// The quantities the scene reports, comma-separated.
        known: String,
        /// The scene file.
        scene: PathBuf,
    },
    /// A plot could not be drawn.
    #[cfg(feature = "report")]
    #[error(transparent)]
    Plot(#[from] PlotError),
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
#[derive(Clone, Debug, Default)]
pub struct ReportOptions {
    /// Fewer rungs and levels (tests, CI).
    pub quick: bool,
    /// The levels k of the convergence study on a mesh family (`mesh.base`, theory §7.3), in
    /// place of [`LEVELS`]: the family's levels whose extrapolation is the reference (`--levels`).
    pub levels: Option<Vec<usize>>,
    /// The quantity of interest by name (`--quantity`; [`named_quantity`]): an obstacle's
    /// quantity, an extra unknown or a reaction component. None: the scene's first extra unknown
    /// ([`first_quantity`]).
    pub quantity: Option<String>,
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
    /// The family levels asked for (`--levels`).
    pub levels: Option<Vec<usize>>,
    /// The quantity of interest (the `U` columns of the CSV files): its name, and whether it was
    /// asked for (`--quantity`) rather than the scene's first extra unknown; None when the scene
    /// reports none.
    pub quantity: Option<(String, bool)>,
    /// Cores available (`std::thread::available_parallelism`).
    pub cores: usize,
    /// The work–precision runs, the reference among them.
    pub runs: Vec<RunRecord>,
    /// The cells of the scene's box mesh (None for other meshes).
    pub scene_cells: Option<[usize; 3]>,
    /// The convergence study, or why there is none.
    pub convergence: Result<ConvergenceStudy, String>,
    /// P1 against P2 on meshes with the same nodes ([`super::elements`]), or why there is none.
    pub element_comparison: Result<ElementComparison, String>,
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
/// then every other rung, each recording the quantity of interest `quantity`. Returns the records
/// in ladder order (the [`RungKind::Reference`] rung reports the reference run). `counter`
/// numbers the runs for `progress`.
pub fn work_precision(
    problem: &DiscreteProblem,
    rungs: &[Rung],
    quantity: Option<&str>,
    progress: &mut dyn Progress,
    counter: &mut usize,
) -> Result<Vec<RunRecord>, ReportError> {
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
            records.push(record(problem, rung, &reference_timed, reference, quantity));
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
        let mut rec = record(problem, rung, &timed, reference, quantity);
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
    Ok(records)
}

/// A level's solve and its fields, kept while the next coarser level is compared with it.
struct Solved {
    l: DiscreteProblem,
    stress: saddle_core::StressField,
    strain: Vec<saddle_core::Sym>,
}

/// The mesh convergence study of `source` on the box meshes `levels` (ascending; the last is
/// the finest and the reference of the errors), of the scene's first extra unknown
/// ([`convergence_study_of`] with no quantity named).
pub fn convergence_study(
    source: &SceneSource,
    levels: &[[usize; 3]],
    progress: &mut dyn Progress,
    counter: &mut usize,
) -> Result<ConvergenceStudy, ReportError> {
    convergence_study_of(source, levels, None, progress, counter)
}

/// The mesh convergence study of `source` on the box meshes `levels` (ascending; the last is
/// the finest and the reference of the errors), its quantity of interest `quantity` by name
/// ([`named_quantity`]; None: the scene's first extra unknown, [`first_quantity`]). Every level
/// is solved by [`runs::level_solver`]. Levels are processed from fine to coarse, so that only
/// the finest and the next finer level are kept in memory.
pub fn convergence_study_of(
    source: &SceneSource,
    levels: &[[usize; 3]],
    quantity: Option<&str>,
    progress: &mut dyn Progress,
    counter: &mut usize,
) -> Result<ConvergenceStudy, ReportError> {
    let solver = runs::level_solver();
    let mut solve_level = |cells: [usize; 3], progress: &mut dyn Progress| -> Result<_, ReportError> {
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
    let Some((&finest_cells, coarser)) = levels.split_last() else {
        return Ok(ConvergenceStudy::from_levels(vec![]));
    };
    let (fl, finest_timed) = solve_level(finest_cells, progress)?;
    // the quantity of interest, by name
    let name = quantity.map(str::to_string).or_else(|| first_quantity(fl.view()));
    let u_of = |p: &DiscreteProblem, s: &Solution| {
        name.as_deref().and_then(|n| named_quantity(p.view(), s, n)).unwrap_or(f64::NAN)
    };
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
    let degree = fl.element.degree();
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
    let study = ConvergenceStudy::from_levels(results).of_degree(degree);
    Ok(match name {
        Some(n) => study.of_quantity(n),
        None => study,
    })
}
