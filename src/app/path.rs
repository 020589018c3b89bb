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
//! use saddle::io::scene::Scene;
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

use super::setup::{Loaded, Outcome, RunError};
use crate::io::outdir::OutDir;
use crate::io::scene::LoadPath;
use crate::io::summary::{
    CutAttempt, PathSummary, ResidualState, StepSummary, Summary, check_quantity, reaction_names, reaction_quantities,
    reported_quantities,
};
use saddle_core::{
    Evolution, Increment, LoadFactors, Monitor, PathError, SceneError, SolveError, StepCutting, StepSolution,
};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::fs::{File, OpenOptions};
use std::io::{Seek, SeekFrom, Write as _};
use std::path::Path;
use std::time::Instant;

/// The most `solution_NNNN.vtu` files a load path writes: with more planned steps, every k-th
/// step's (k = ⌈steps / 100⌉), the last planned step's and the step that stops the path; a step
/// without a file has `file` null in `summary.json`. `load_path.csv` and `summary.json` keep
/// every step (a few hundred bytes each), so a path writes O(steps) in all.
pub const MAX_STEP_FILES: usize = 100;

/// Whether step `k` of `n` planned steps writes its VTU file ([`MAX_STEP_FILES`]); a step that
/// stops the path always does.
fn writes_step_file(k: usize, n: usize) -> bool {
    let stride = n.div_ceil(MAX_STEP_FILES).max(1);
    k.is_multiple_of(stride) || k + 1 == n
}

/// Solves the steps of `path` for `loaded` and writes every output into `out_dir` (module docs);
/// `progress` gets a line per step. The outcome holds the last step's solution and summary (its
/// `steps` and `load_path` filled). Before any solve: the plotted quantities the scene names are
/// checked (an unknown one is an error on `load_path.plot[i]` listing the known ones; the
/// default axes are plotted when reported) and the folder is
/// claimed ([`OutDir::claim`]). Errors: output that cannot be written, and a first step that
/// fails (nothing to summarise; the folder is left as it was); a later failure is recorded in
/// the summary, not an error. Each step costs O(1) output besides its VTU file: the series and
/// the table are appended to, not rewritten.
pub fn solve_and_write(
    loaded: &Loaded,
    path: &LoadPath,
    out_dir: &Path,
    monitor: &mut dyn Monitor,
    progress: &mut dyn FnMut(&str),
) -> Result<Outcome, RunError> {
    let known = reported_quantities(loaded.problem.view());
    for (i, q) in path.plot.iter().flatten().enumerate() {
        check_quantity(&format!("load_path.plot[{i}]"), q, &known).map_err(SceneError::from)?;
    }
    let ranks = loaded.ranks.as_ref();
    let mut out = RunError::agree(ranks, ranks.claim(out_dir).map_err(RunError::from))?;
    let mut timer = loaded.timer.clone();
    let factors = path.step_factors();
    let names = loaded.problem.view().extra_names();
    let mut evolution = Evolution::new(&loaded.problem);
    let mut series = Series::new(&known, &names, &reaction_names(loaded.problem.view()));
    let mut steps: Vec<StepSummary> = Vec::new();
    let mut last: Option<(Summary, StepSolution)> = None;
    let mut failure: Option<(usize, String)> = None;
    let cutting = path.cutting();
    let mut cuts: Vec<CutAttempt> = Vec::new();
    let mut smallest_step: Option<f64> = None;
    // the zero state is the state at factor 0, of every load
    let planned = path.step_loads();
    let mut solved = LoadFactors { all: 0.0, named: planned[0].named.keys().map(|k| (k.clone(), 0.0)).collect() };
    'planned: for target in &planned {
        // the planned step in fractions of its increment: a cut halves every load's alike
        let (start, span) = (solved.clone(), LoadFactors::span(&solved, target));
        let mut increment = Increment::new(0.0, 1.0);
        let cutting = StepCutting { min_step: cutting.min_step / span, ..cutting };
        while let Some(fraction) = increment.next() {
            let loads = match fraction {
                1.0 => target.clone(),
                _ => solved.moved(fraction - increment.from(), &start, target),
            };
            let factor = loads.all;
            let k = steps.len();
            let started = Instant::now();
            let attempt = timer.time("solve", || evolution.step_at(&loads, loaded.solver.as_ref(), monitor));
            // a step failed on one rank only ends every rank (a distributed solver's failures are
            // every rank's: the cuts below are taken alike everywhere)
            if let (Ok(_), Err(message)) =
                (&attempt, ranks.agree(attempt.as_ref().map(|_| ()).map_err(|e| e.to_string())))
            {
                out.abandon();
                return Err(RunError::Ranks(message));
            }
            if let Some(why) = cuttable_failure(&attempt) {
                let from = solved.all;
                if increment.cut(&cutting) {
                    let next = increment.next().expect("a cut step has somewhere to go");
                    let retry = solved.moved(next - increment.from(), &start, target).all;
                    progress(&format!(
                        "step {k} (factor {factor}): failed: {why}; cut {}: retrying at factor {retry} (step {:e})",
                        increment.cuts(),
                        increment.step() * span
                    ));
                    smallest_step = Some(increment.step() * span);
                    cuts.push(CutAttempt { step: k, factor, from, retry, reason: why });
                    continue;
                }
            }
            let step = match attempt {
                Ok(step) => step,
                Err(e) => {
                    let mut why = match &e {
                        PathError::Solve { source, .. } => source.to_string(),
                        PathError::Scene { source, .. } => source.to_string(),
                    };
                    if let PathError::Solve { source: SolveError::BeyondCollapse { .. }, .. } = &e {
                        let _ = write!(why, "; the last load factor carried is {}", solved.all);
                    }
                    progress(&format!("step {k} (factor {factor}): failed: {why}"));
                    if last.is_none() {
                        // nothing was written: the folder is left as it was (as a failed one-step run)
                        out.abandon();
                        return Err(RunError::Path(e));
                    }
                    let mut entry = StepSummary::failed(k, factor, why.clone(), started.elapsed().as_secs_f64());
                    entry.loads = loads.named.clone();
                    steps.push(entry);
                    if ranks.is_root() {
                        timer.time("write", || series.append(&mut out, &steps))?;
                    }
                    failure = Some((k, why));
                    break 'planned;
                }
            };
            let mut s =
                timer.time("summary", || ranks.summary(step.problem.view(), &step.solution, loaded.title.clone()));
            s.warnings.extend(step.warnings.iter().cloned());
            let converged = step.converged();
            let mut file = None;
            if writes_step_file(k, factors.len()) || !converged {
                let stem = format!("solution_{k:04}");
                let view = step.problem.view();
                let files = timer.time("write", || ranks.write_solution(out.dir(), &stem, view, &step.solution, &[]));
                let files = RunError::agree(ranks, files.map_err(io(&out.path(&stem))))?;
                for f in &files {
                    out.wrote(f)?;
                }
                file = files.into_iter().next();
            }
            let mut entry = StepSummary::new(k, factor, &s, file, started.elapsed().as_secs_f64());
            entry.cuts = increment.cuts();
            entry.loads = loads.named.clone();
            progress(&step_line(&entry, path));
            steps.push(entry);
            // the series and the table so far, so that an interrupted path leaves them readable
            if ranks.is_root() {
                timer.time("write", || series.append(&mut out, &steps))?;
            }
            if !converged {
                failure = Some((k, format!("the solver stopped without converging ({:?})", s.stop_reason)));
            }
            last = Some((s, step));
            if !converged {
                break 'planned;
            }
            increment.solved(fraction);
            solved = loads;
        }
        if failure.is_some() {
            break;
        }
    }
    // a path that cannot go on names the smallest step it tried
    if let Some((_, why)) = failure.as_mut().filter(|_| !cuts.is_empty()) {
        let _ = write!(why, " (smallest step tried {:e})", smallest_step.unwrap_or(f64::NAN));
    }
    let (mut summary, step) = last.expect("a first step that fails returns above");
    let completed = failure.is_none();
    if let Some((k, why)) = &failure {
        summary.converged = false;
        summary.warnings.push(format!(
            "the load path stopped at step {k} (load factor {}): {why}; the steps before it are written ({} of {} steps)",
            steps[*k].factor,
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
        loads: path.loads.clone(),
        substeps: path.substeps,
        step_factors: factors.clone(),
        steps_done: steps.len(),
        completed,
        failed_step: failure.as_ref().map(|f| f.0),
        error: failure.map(|f| f.1),
        total_iterations: steps.iter().map(|s| s.iterations).sum(),
        total_wall_s: steps.iter().map(|s| s.wall_s).sum(),
        residual,
        max_cuts: cutting.max_cuts,
        min_step: cutting.min_step,
        cuts,
        smallest_step,
    });
    summary.steps = steps;
    // solution.vtu: the last step solved, as a one-step run writes it
    let files =
        timer.time("write", || ranks.write_solution(out.dir(), "solution", step.problem.view(), &step.solution, &[]));
    let files = RunError::agree(ranks, files.map_err(io(&out.path("solution"))))?;
    #[cfg(feature = "report")]
    if ranks.is_root() && plot(&summary, path, out.dir())? {
        out.wrote("load_path.png")?;
        out.wrote("load_path.svg")?;
    }
    summary.end_to_end = timer.into_phases().into_iter().collect();
    summary.end_to_end_s = summary.end_to_end.values().sum();
    ranks.describe(&mut summary);
    let written = super::setup::finish(ranks, out, &summary, &files, out_dir)?;
    Ok(Outcome { solution: step.solution, summary, out_dir: out_dir.to_path_buf(), written })
}

/// Why an attempted step failed, when halving it may help (theory §11.5): it did not converge,
/// or the solver failed on it — not for a parameter, a problem outside what the solver handles,
/// or a step that cannot be set up, which no smaller step changes.
fn cuttable_failure(attempt: &Result<StepSolution<'_>, PathError>) -> Option<String> {
    match attempt {
        Ok(step) if !step.converged() => {
            Some(format!("the solver stopped without converging ({:?})", step.solution.report.stop_reason))
        }
        Ok(_) => None,
        Err(PathError::Solve { source: SolveError::Parameter(_) | SolveError::Unsupported { .. }, .. }) => None,
        Err(PathError::Solve { source, .. }) => Some(source.to_string()),
        Err(PathError::Scene { .. }) => None,
    }
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> RunError + use<> {
    let path = path.to_path_buf();
    move |source| RunError::Io { path, source }
}

/// The progress line of a step.
fn step_line(s: &StepSummary, path: &LoadPath) -> String {
    let [x, y] = &path.axes();
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

/// The closing lines of `solution.pvd`, rewritten after each appended step.
const PVD_TAIL: &str = "  </Collection>\n</VTKFile>\n";

/// `solution.pvd` (the steps' VTU files as a ParaView series, the step index as time) and
/// `load_path.csv`, written as the steps go: each step appends its line (the series' closing
/// lines rewritten after it), so both stay readable and cost O(1) per step. The table's columns
/// are the extras and the reported quantities, known before the first step; a step reporting
/// another quantity (no plugin does) has the table rewritten with a column for it.
struct Series {
    columns: Columns,
    files: Option<(File, File)>,
}

impl Series {
    fn new(known: &[String], extras: &[String], reactions: &[String]) -> Self {
        let mut extras = extras.to_vec();
        extras.sort();
        let quantities = known.iter().filter(|k| !extras.contains(k) && !reactions.contains(k)).cloned().collect();
        let mut reactions = reactions.to_vec();
        reactions.sort();
        Self { columns: Columns { extras, quantities, reactions }, files: None }
    }

    /// Appends the last of `steps` to both files (creating them at the first step).
    fn append(&mut self, out: &mut OutDir, steps: &[StepSummary]) -> Result<(), RunError> {
        let s = steps.last().expect("a step to append");
        let (pvd_path, csv_path) = (out.path("solution.pvd"), out.path("load_path.csv"));
        if self.files.is_none() {
            let pvd = File::create(&pvd_path).map_err(io(&pvd_path))?;
            let csv = File::create(&csv_path).map_err(io(&csv_path))?;
            let mut files = (pvd, csv);
            files.0.write_all(PVD_HEAD.as_bytes()).map_err(io(&pvd_path))?;
            files.0.write_all(PVD_TAIL.as_bytes()).map_err(io(&pvd_path))?;
            files.1.write_all(self.columns.header().as_bytes()).map_err(io(&csv_path))?;
            self.files = Some(files);
            out.wrote("solution.pvd")?;
            out.wrote("load_path.csv")?;
        }
        let (pvd, csv) = self.files.as_mut().expect("created above");
        if let Some(f) = &s.file {
            let line = format!("    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{f}\"/>\n{PVD_TAIL}", s.step);
            pvd.seek(SeekFrom::End(-(PVD_TAIL.len() as i64)))
                .and_then(|_| pvd.write_all(line.as_bytes()))
                .map_err(io(&pvd_path))?;
        }
        if self.columns.covers(s) {
            csv.write_all(self.columns.row(s).as_bytes()).map_err(io(&csv_path))?;
        } else {
            self.columns = Columns::of(steps);
            std::fs::write(&csv_path, self::csv(steps)).map_err(io(&csv_path))?;
            *csv = OpenOptions::new().append(true).open(&csv_path).map_err(io(&csv_path))?;
        }
        Ok(())
    }
}

/// The opening lines of `solution.pvd`.
const PVD_HEAD: &str = "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n";

/// The columns of `load_path.csv` after the fixed ones: the extras, then the other reported
/// quantities, each sorted.
struct Columns {
    extras: Vec<String>,
    quantities: Vec<String>,
    /// The reactions' components (`grip.Fx`, …), after `cuts`.
    reactions: Vec<String>,
}

impl Columns {
    /// The columns every step of `steps` needs.
    fn of(steps: &[StepSummary]) -> Self {
        let mut extras: Vec<String> = steps.iter().flat_map(|s| s.extras.keys().cloned()).collect();
        extras.sort();
        extras.dedup();
        let mut quantities: Vec<String> =
            steps.iter().flat_map(|s| s.contact.keys().cloned()).filter(|k| !extras.contains(k)).collect();
        quantities.sort();
        quantities.dedup();
        let mut reactions: Vec<String> =
            steps.iter().flat_map(|s| reaction_quantities(&s.reactions).map(|(n, _)| n)).collect();
        reactions.sort();
        reactions.dedup();
        Self { extras, quantities, reactions }
    }

    /// True when every value of `s` has its column.
    fn covers(&self, s: &StepSummary) -> bool {
        s.extras.keys().all(|k| self.extras.contains(k))
            && s.contact.keys().all(|k| self.extras.contains(k) || self.quantities.contains(k))
            && reaction_quantities(&s.reactions).all(|(k, _)| self.reactions.contains(&k))
    }

    fn header(&self) -> String {
        let mut out = String::from(
            "step,factor,converged,stop_reason,iterations,kkt_residual,contact_nodes,plastic_points,plastic_elements,\
             max_von_mises,max_equivalent_plastic_strain,wall_s",
        );
        for n in self.extras.iter().chain(&self.quantities) {
            let _ = write!(out, ",{n}");
        }
        // after the columns of the first version of the table (theory §11.5)
        out.push_str(",cuts");
        for n in &self.reactions {
            let _ = write!(out, ",{n}");
        }
        out.push('\n');
        out
    }

    /// The row of step `s`; an undetermined or unreported value is left empty.
    fn row(&self, s: &StepSummary) -> String {
        let num = |v: Option<f64>| v.filter(|v| v.is_finite()).map_or(String::new(), |v| format!("{v:.12e}"));
        let mut out = format!(
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
        for n in &self.extras {
            let _ = write!(out, ",{}", num(s.extras.get(n).copied().flatten()));
        }
        for n in &self.quantities {
            let _ = write!(out, ",{}", num(s.contact.get(n).copied()));
        }
        let _ = write!(out, ",{}", s.cuts);
        let values: BTreeMap<String, f64> = reaction_quantities(&s.reactions).collect();
        for n in &self.reactions {
            let _ = write!(out, ",{}", num(values.get(n).copied()));
        }
        out.push('\n');
        out
    }
}

/// `load_path.csv`: one row per step; an undetermined or unreported value is left empty.
pub fn csv(steps: &[StepSummary]) -> String {
    let columns = Columns::of(steps);
    let mut out = columns.header();
    for s in steps {
        out.push_str(&columns.row(s));
    }
    out
}

/// `load_path.{png,svg}`: the path's y against x in step order (the hysteresis loop of an
/// indentation), steps where either is undetermined left out; nothing with fewer than two
/// points. True when the plot was written.
#[cfg(feature = "report")]
fn plot(summary: &Summary, path: &LoadPath, out_dir: &Path) -> Result<bool, RunError> {
    let [x, y] = &path.axes();
    let points: Vec<(f64, f64, bool)> =
        summary.steps.iter().filter_map(|s| Some((s.get(x)?, s.get(y)?, s.converged))).collect();
    if points.len() < 2 {
        return Ok(false);
    }
    let title = format!("load path: {}", summary.title.clone().unwrap_or_default());
    let (png, svg) = (out_dir.join("load_path.png"), out_dir.join("load_path.svg"));
    crate::io::plot::curve(&title, (x, y), &points, &png, &svg)
        .map_err(|e| RunError::Io { path: png, source: std::io::Error::other(e.to_string()) })?;
    Ok(true)
}
