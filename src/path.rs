//! `saddle run` of a scene with a `[load_path]` (theory §11): the steps solved one after
//! another ([`saddle_core::Evolution`]), each written as it is done — `solution_NNNN.vtu`, the
//! `solution.pvd` series, `load_path.csv`, `summary.json` with a `steps` entry per step — and at
//! the end `solution.vtu` (the last step) and, with the feature `report`, the force–displacement
//! plot `load_path.{png,svg}`. A step that fails or does not converge stops the path: the steps
//! before it stay written, the failed one is marked in `summary.json` and `load_path.csv`.
//!
//! The same steps in Rust, without output files:
//!
//! ```no_run
//! use saddle::core::{Evolution, Silent, step_factors};
//! use saddle::scene::Scene;
//!
//! let scene = Scene::from_file("examples/indentation.toml".as_ref()).unwrap();
//! let (l, solver) = scene.into_problem().unwrap();
//! let solver = solver.unwrap();
//! let mut path = Evolution::new(&l);
//! for f in step_factors(&[0.0, 1.0, 0.0], 4) {
//!     let step = path.step(f, solver.as_ref(), &mut Silent).unwrap();
//!     assert!(step.converged());
//!     println!("factor {f}: U = {:?}, undetermined extras {:?}", step.solution.extras, step.solution.undetermined);
//! }
//! ```

use crate::output::{StepSummary, Summary, write_vtu};
use crate::run::{Loaded, Outcome, RunError};
use crate::scene::LoadPath;
use saddle_core::{Evolution, Monitor, PathError, Solution};
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// The load path as a whole, in `summary.json` under `load_path`.
#[derive(Clone, Debug, Serialize)]
pub struct PathSummary {
    /// The scene's factors.
    pub factors: Vec<f64>,
    /// Sub-steps between factors.
    pub substeps: usize,
    /// The factor of every planned step.
    pub step_factors: Vec<f64>,
    /// Steps solved (the failed one included).
    pub steps_done: usize,
    /// True when every step converged.
    pub completed: bool,
    /// The step that stopped the path (failed or not converged).
    pub failed_step: Option<usize>,
    /// Why it stopped.
    pub error: Option<String>,
    /// Outer iterations of all steps.
    pub total_iterations: usize,
    /// Wall time of all steps (set-up, solve, summary, output).
    pub total_wall_s: f64,
    /// The residual state, when the path ends converged at load factor 0 (theory §11.4).
    pub residual: Option<ResidualState>,
}

/// What unloading leaves (theory §11.4), summarised.
#[derive(Clone, Debug, Serialize)]
pub struct ResidualState {
    /// Each obstacle's imprint: the largest displacement of its candidate nodes away from it
    /// (`imprint`, or `name.imprint`).
    pub imprint: BTreeMap<String, f64>,
    /// The largest von Mises stress of the residual stresses.
    pub max_von_mises: f64,
    /// The largest equivalent plastic strain.
    pub max_equivalent_plastic_strain: f64,
}

/// Solves the steps of `path` for `loaded` and writes every output into `out_dir` (module docs);
/// `progress` gets a line per step. The outcome holds the last step's solution and summary (its
/// `steps` and `load_path` filled). Errors: output that cannot be written, and a first step that
/// fails (nothing to summarise); a later failure is recorded in the summary, not an error.
pub fn solve_and_write(
    loaded: &Loaded,
    path: &LoadPath,
    out_dir: &Path,
    monitor: &mut dyn Monitor,
    progress: &mut dyn FnMut(&str),
) -> Result<Outcome, RunError> {
    let io = |p: &Path| {
        let p = p.to_path_buf();
        move |source| RunError::Io { path: p, source }
    };
    let created = !out_dir.exists();
    std::fs::create_dir_all(out_dir).map_err(io(out_dir))?;
    let mut timer = loaded.timer.clone();
    let factors = path.step_factors();
    let mut evolution = Evolution::new(&loaded.problem);
    let mut steps: Vec<StepSummary> = Vec::new();
    let mut last: Option<(Summary, Solution)> = None;
    let mut failure: Option<(usize, String)> = None;
    for (k, &factor) in factors.iter().enumerate() {
        let started = Instant::now();
        let step = match timer.time("solve", || evolution.step(factor, loaded.solver.as_ref(), monitor)) {
            Ok(step) => step,
            Err(e) => {
                let why = match &e {
                    PathError::Solve { source, .. } => source.to_string(),
                    PathError::Scene { source, .. } => source.to_string(),
                };
                progress(&format!("step {k} (factor {factor}): failed: {why}"));
                steps.push(StepSummary::failed(k, factor, why.clone(), started.elapsed().as_secs_f64()));
                failure = Some((k, why));
                if last.is_none() {
                    // nothing was written: leave no empty folder behind (as a failed one-step run)
                    if created {
                        let _ = std::fs::remove_dir(out_dir);
                    }
                    return Err(RunError::Path(e));
                }
                break;
            }
        };
        let mut s = timer.time("summary", || Summary::new(step.problem.view(), &step.solution, loaded.title.clone()));
        s.warnings.extend(step.warnings.iter().cloned());
        let file = format!("solution_{k:04}.vtu");
        timer
            .time("write", || write_vtu(&out_dir.join(&file), step.problem.view(), &step.solution))
            .map_err(io(&out_dir.join(&file)))?;
        let entry = StepSummary::new(k, factor, &s, Some(file), started.elapsed().as_secs_f64());
        progress(&step_line(&entry, path));
        steps.push(entry);
        let converged = step.converged();
        if !converged {
            failure = Some((k, format!("the solver stopped without converging ({:?})", s.stop_reason)));
        }
        last = Some((s, step.solution));
        // the series and the table so far, so that an interrupted path leaves them readable
        timer.time("write", || write_series(out_dir, &steps)).map_err(io(out_dir))?;
        if !converged {
            break;
        }
    }
    let (mut summary, solution) = last.expect("a first step that fails returns above");
    let completed = failure.is_none();
    if let Some((k, why)) = &failure {
        summary.converged = false;
        summary.warnings.push(format!(
            "the load path stopped at step {k} (load factor {}): {why}; the steps before it are written ({} of {} steps)",
            factors[*k],
            steps.len(),
            factors.len()
        ));
    }
    let residual = (completed && factors.last() == Some(&0.0)).then(|| ResidualState {
        imprint: summary.contact.iter().filter(|(k, _)| k.ends_with("imprint")).map(|(k, v)| (k.clone(), *v)).collect(),
        max_von_mises: summary.max_von_mises,
        max_equivalent_plastic_strain: summary.max_equivalent_plastic_strain,
    });
    summary.load_path = Some(PathSummary {
        factors: path.factors.clone(),
        substeps: path.substeps,
        step_factors: factors.clone(),
        steps_done: steps.len(),
        completed,
        failed_step: failure.as_ref().map(|f| f.0),
        error: failure.map(|f| f.1),
        total_iterations: steps.iter().map(|s| s.iterations).sum(),
        total_wall_s: steps.iter().map(|s| s.wall_s).sum(),
        residual,
    });
    summary.steps = steps;
    // solution.vtu: the last step solved, as a one-step run writes it
    let last_file = summary.steps.iter().rev().find_map(|s| s.file.clone());
    if let Some(f) = last_file {
        timer
            .time("write", || std::fs::copy(out_dir.join(&f), out_dir.join("solution.vtu")))
            .map_err(io(&out_dir.join("solution.vtu")))?;
    }
    #[cfg(feature = "report")]
    plot(&summary, path, out_dir)?;
    summary.end_to_end = timer.into_phases().into_iter().collect();
    summary.end_to_end_s = summary.end_to_end.values().sum();
    let json = out_dir.join("summary.json");
    summary.write(&json).map_err(io(&json))?;
    Ok(Outcome { solution, summary, out_dir: out_dir.to_path_buf() })
}

/// The progress line of a step.
fn step_line(s: &StepSummary, path: &LoadPath) -> String {
    let [x, y] = &path.plot;
    let show = |n: &str| s.get(n).map_or("-".to_string(), |v| format!("{v:.6e}"));
    format!(
        "step {} (factor {}): {} in {} iterations, KKT {:.1e}, {} plastic, {x} {}, {y} {}",
        s.step,
        s.factor,
        s.stop_reason,
        s.iterations,
        s.kkt_residual.unwrap_or(f64::NAN),
        s.plastic_points,
        show(x),
        show(y)
    )
}

/// `solution.pvd` (the steps' VTU files as a ParaView series, the step index as time) and
/// `load_path.csv`.
fn write_series(out_dir: &Path, steps: &[StepSummary]) -> std::io::Result<()> {
    let mut pvd = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for s in steps {
        if let Some(f) = &s.file {
            let _ = writeln!(pvd, "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{f}\"/>", s.step);
        }
    }
    pvd.push_str("  </Collection>\n</VTKFile>\n");
    std::fs::write(out_dir.join("solution.pvd"), pvd)?;
    std::fs::write(out_dir.join("load_path.csv"), csv(steps))
}

/// `load_path.csv`: one row per step; an undetermined or unreported value is left empty.
pub fn csv(steps: &[StepSummary]) -> String {
    let mut extras: Vec<String> = steps.iter().flat_map(|s| s.extras.keys().cloned()).collect();
    extras.sort();
    extras.dedup();
    let mut quantities: Vec<String> =
        steps.iter().flat_map(|s| s.contact.keys().cloned()).filter(|k| !extras.contains(k)).collect();
    quantities.sort();
    quantities.dedup();
    let mut out = String::from(
        "step,factor,converged,stop_reason,iterations,kkt_residual,contact_nodes,plastic_points,plastic_elements,\
         max_von_mises,max_equivalent_plastic_strain,wall_s",
    );
    for n in extras.iter().chain(&quantities) {
        let _ = write!(out, ",{n}");
    }
    out.push('\n');
    let num = |v: Option<f64>| v.filter(|v| v.is_finite()).map_or(String::new(), |v| format!("{v:.12e}"));
    for s in steps {
        let _ = write!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},{:.3}",
            s.step,
            s.factor,
            s.converged,
            s.stop_reason,
            s.iterations,
            num(s.kkt_residual),
            s.contact_nodes,
            s.plastic_points,
            s.plastic_elements,
            num(Some(s.max_von_mises)),
            num(Some(s.max_equivalent_plastic_strain)),
            s.wall_s
        );
        for n in &extras {
            let _ = write!(out, ",{}", num(s.extras.get(n).copied().flatten()));
        }
        for n in &quantities {
            let _ = write!(out, ",{}", num(s.contact.get(n).copied()));
        }
        out.push('\n');
    }
    out
}

/// `load_path.{png,svg}`: the path's y against x in step order (the hysteresis loop of an
/// indentation), steps where either is undetermined left out; nothing with fewer than two
/// points.
#[cfg(feature = "report")]
fn plot(summary: &Summary, path: &LoadPath, out_dir: &Path) -> Result<(), RunError> {
    let [x, y] = &path.plot;
    let points: Vec<(f64, f64, bool)> =
        summary.steps.iter().filter_map(|s| Some((s.get(x)?, s.get(y)?, s.converged))).collect();
    if points.len() < 2 {
        return Ok(());
    }
    let title = format!("load path: {}", summary.title.clone().unwrap_or_default());
    let (png, svg) = (out_dir.join("load_path.png"), out_dir.join("load_path.svg"));
    crate::report::plot::curve(&title, (x, y), &points, &png, &svg)
        .map_err(|e| RunError::Io { path: png, source: std::io::Error::other(e.to_string()) })
}
