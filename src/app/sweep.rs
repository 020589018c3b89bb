//! `saddle sweep`: a scene solved at a ladder of load factors — every load multiplied by the
//! factor (tractions, body forces, each obstacle's prescribed force or displacement;
//! [`saddle_core::LoadStep`], as a load path scales it) — each point the stationary problem of theory §1 solved from
//! zero. For a displacement-controlled punch with h = 0 this is the force–displacement curve
//! whose plateau is the limit load (theory §10). Writes `sweep.csv` (per factor: the solver's
//! status, iterations, KKT residual, contact and plastic counts, every quantity the obstacles
//! report), `sweep.md` with the plateau indicator, and (feature `report`) `sweep.png`/`.svg`:
//! one reported quantity against another (default `force` against `U`).
//!
//! ```text
//! saddle sweep examples/strip_punch.toml --factors 0.25,0.5,1,2,4 --out out/strip
//! ```

use super::setup::{RunError, default_solver, solver_by_type};
use crate::io::outdir::{OutDir, OutError};
use crate::io::scene::{Scene, element_by_type};
use crate::io::summary::{Summary, check_quantity, reaction_quantities, reported_quantities};
use saddle_core::error::{check, number};
use saddle_core::evolution::SecantPredictor;
use saddle_core::{DiscreteProblem, Evolution, SceneError, Silent, Solver, Start};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;
use thiserror::Error;

/// Why a sweep failed (a point whose solver fails is recorded, not an error).
#[derive(Debug, Error)]
pub enum SweepError {
    /// The scene, or the scene at a factor, is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// `--solver` names no solver.
    #[error(transparent)]
    Run(#[from] RunError),
    /// `--out` cannot be used, or a file in it cannot be written.
    #[error(transparent)]
    Out(#[from] OutError),
    /// `--x` or `--y` names no reported quantity.
    #[error("{0}")]
    Axis(String),
    /// No factors, or a factor that is not finite and ≥ 0.
    #[error("--factors: {0}")]
    Factors(String),
    /// A table or plot could not be written.
    #[error("cannot write {path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

/// What to sweep.
#[derive(Clone, Debug)]
pub struct SweepOptions {
    /// The load factors, in the order solved.
    pub factors: Vec<f64>,
    /// A solver type instead of the scene's.
    pub solver: Option<String>,
    /// A finite element type (`p1`, `p2`) instead of the scene's.
    pub element: Option<String>,
    /// The reported quantities plotted: (x, y), e.g. (`U`, `force`); `factor` is one too.
    pub axes: (String, String),
}

/// One point of the sweep.
#[derive(Clone, Debug)]
pub struct SweepPoint {
    /// The load factor.
    pub factor: f64,
    /// True when the solver met its tolerance.
    pub converged: bool,
    /// Why it stopped (`Converged`, `MaxIterations`, …), or the solver's error.
    pub status: String,
    /// Outer iterations (0 after an error).
    pub iterations: usize,
    /// The recomputed relative KKT residual (NaN after an error).
    pub kkt_residual: f64,
    /// Contact nodes.
    pub contact_nodes: usize,
    /// Plastic elements.
    pub plastic_elements: usize,
    /// Every quantity the obstacles report (`U`, `force`, …; `name.U` with several).
    pub quantities: BTreeMap<String, f64>,
    /// Wall time of the solve and its summary.
    pub wall_s: f64,
}

impl SweepPoint {
    /// The quantity `name`: a reported one, or `factor`.
    pub fn get(&self, name: &str) -> Option<f64> {
        if name == "factor" { Some(self.factor) } else { self.quantities.get(name).copied() }
    }
}

/// A finished sweep.
#[derive(Clone, Debug)]
pub struct Sweep {
    /// The scene's title.
    pub title: String,
    /// The points, in the order of the factors.
    pub points: Vec<SweepPoint>,
    /// The plotted quantities.
    pub axes: (String, String),
    /// The files written (`sweep.csv`, `sweep.md`, and the plot when it was drawn).
    pub written: Vec<String>,
}

impl Sweep {
    /// The converged points' (x, y).
    pub fn curve(&self) -> Vec<(f64, f64)> {
        let (x, y) = (&self.axes.0, &self.axes.1);
        self.points.iter().filter(|p| p.converged).filter_map(|p| Some((p.get(x)?, p.get(y)?))).collect()
    }

    /// The plateau indicator: d ln y / d ln x over the last interval of converged points (1 for
    /// a linear response through the origin, → 0 on a plateau): between the last point and the
    /// last one before it at another x, both with x, y > 0 (a repeated factor adds no interval);
    /// None without two such points.
    pub fn last_log_slope(&self) -> Option<f64> {
        let c: Vec<(f64, f64)> = self.curve().into_iter().filter(|&(x, y)| x > 0.0 && y > 0.0).collect();
        let &(x1, y1) = c.last()?;
        let &(x0, y0) = c.iter().rev().find(|p| p.0 != x1)?;
        Some((y1 / y0).ln() / (x1 / x0).ln()).filter(|k| k.is_finite())
    }
}

/// Solves the scene at each factor; `progress` gets a line per point.
pub fn generate(
    scene_path: &Path,
    opts: &SweepOptions,
    out: &Path,
    progress: &mut dyn FnMut(&str),
) -> Result<Sweep, SweepError> {
    if opts.factors.is_empty() {
        return Err(SweepError::Factors("give at least one factor".into()));
    }
    if let Some(f) = opts.factors.iter().find(|f| f.abs() > check::MAX_MAGNITUDE) {
        return Err(SweepError::Factors(format!(
            "{} exceeds {:e} in magnitude, the largest a scene's value may have (larger ones overflow the solvers)",
            number(*f),
            check::MAX_MAGNITUDE
        )));
    }
    let mut scene = Scene::from_file(scene_path)?;
    if let Some(name) = &opts.element {
        scene.discretisation = Some(element_by_type(name)?);
    }
    let solver = match &opts.solver {
        Some(name) => Some(solver_by_type(name)?),
        None => None,
    };
    let title = scene.title.clone().unwrap_or_else(|| scene_path.display().to_string());
    // every factor is checked before the first solve
    for (i, &f) in opts.factors.iter().enumerate() {
        scene.check_load_factor(f, &format!("--factors[{i}]"))?;
    }
    let mesh = scene.build_mesh()?;
    let (problem, own) = scene.assemble(mesh)?;
    let solver = solver.or(own).unwrap_or_else(default_solver);
    // the folder is claimed before the first solve; left as it was if no point can be solved
    let mut out_dir: Option<OutDir> = None;
    let points = match solve_points(&problem, solver.as_ref(), opts, out, &mut out_dir, progress) {
        Ok(points) => points,
        Err(e) => {
            if let Some(o) = out_dir {
                o.abandon();
            }
            return Err(e);
        }
    };
    let mut sweep = Sweep { title, points, axes: opts.axes.clone(), written: Vec::new() };
    let mut out = out_dir.expect("at least one factor: claimed before its solve");
    write(&sweep, &mut out)?;
    sweep.written = out.finish()?;
    Ok(sweep)
}

/// Solves `problem` at each factor in turn, each point from zero: one load step at the factor
/// from the zero state, the load scaled as a load path scales it (theory §11.2). Before the
/// first solve, checks the axes and claims `out` into `out_dir`.
fn solve_points(
    problem: &DiscreteProblem,
    solver: &dyn Solver,
    opts: &SweepOptions,
    out: &Path,
    out_dir: &mut Option<OutDir>,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<SweepPoint>, SweepError> {
    // the axes name reported quantities, the folder is usable
    let known = reported_quantities(problem.view());
    for (flag, q) in [("--x", &opts.axes.0), ("--y", &opts.axes.1)] {
        check_quantity(flag, q, &known).map_err(|e| SweepError::Axis(e.to_string()))?;
    }
    *out_dir = Some(OutDir::claim(out)?);
    let mut points = Vec::with_capacity(opts.factors.len());
    let mut predictor = SecantPredictor::default();
    for &factor in &opts.factors {
        let started = Instant::now();
        let mut path = Evolution::new(problem).starting_from(predictor.predict(factor));
        let point = match path.step(factor, solver, &mut Silent) {
            Ok(step) => {
                if step.solution.report.converged {
                    predictor.record(factor, Start::from_solution(&step.solution));
                }
                let s = Summary::new(step.problem.view(), &step.solution, None);
                SweepPoint {
                    factor,
                    converged: s.converged,
                    status: format!("{:?}", s.stop_reason),
                    iterations: s.iterations,
                    kkt_residual: s.kkt_residual,
                    contact_nodes: s.contact_nodes,
                    plastic_elements: s.plastic_elements,
                    // an undetermined quantity (theory §11.3) is not reported: empty in the CSV
                    quantities: (s.contact.into_iter().chain(reaction_quantities(&s.reactions)))
                        .filter(|(_, v)| v.is_finite())
                        .collect(),
                    wall_s: started.elapsed().as_secs_f64(),
                }
            }
            Err(e) => SweepPoint {
                factor,
                converged: false,
                status: format!("error: {e}"),
                iterations: 0,
                kkt_residual: f64::NAN,
                contact_nodes: 0,
                plastic_elements: 0,
                quantities: BTreeMap::new(),
                wall_s: started.elapsed().as_secs_f64(),
            },
        };
        let shown: Vec<String> = point.quantities.iter().map(|(k, v)| format!("{k} {v:.6e}")).collect();
        progress(&format!(
            "factor {}: {} in {} iterations, {} plastic, {}",
            number(factor),
            point.status,
            point.iterations,
            point.plastic_elements,
            shown.join(", ")
        ));
        points.push(point);
    }
    Ok(points)
}

/// Writes `sweep.csv`, `sweep.md` and (feature `report`) the plot, when it has two points.
fn write(sweep: &Sweep, out: &mut OutDir) -> Result<(), SweepError> {
    let io = |path: PathBuf| move |e: std::io::Error| SweepError::Io { path, message: e.to_string() };
    for (name, text) in [("sweep.csv", csv(sweep)), ("sweep.md", markdown(sweep))] {
        let path = out.path(name);
        std::fs::write(&path, text).map_err(io(path.clone()))?;
        out.wrote(name)?;
    }
    #[cfg(feature = "report")]
    {
        let (x, y) = &sweep.axes;
        let points: Vec<(f64, f64, bool)> =
            sweep.points.iter().filter_map(|p| Some((p.get(x)?, p.get(y)?, p.converged))).collect();
        if points.len() >= 2 {
            let title = format!("saddle sweep: {}", sweep.title);
            crate::io::plot::curve(&title, (x, y), &points, &out.path("sweep.png"), &out.path("sweep.svg"))
                .map_err(|e| SweepError::Io { path: out.path("sweep.png"), message: e.to_string() })?;
            out.wrote("sweep.png")?;
            out.wrote("sweep.svg")?;
        }
    }
    Ok(())
}

/// The reported quantity names of all points, sorted.
fn quantity_names(sweep: &Sweep) -> Vec<String> {
    let mut names: Vec<String> = sweep.points.iter().flat_map(|p| p.quantities.keys().cloned()).collect();
    names.sort();
    names.dedup();
    names
}

/// `sweep.csv`: one row per factor; a quantity a point does not report is left empty.
pub fn csv(sweep: &Sweep) -> String {
    let names = quantity_names(sweep);
    let mut s = String::from("factor,converged,status,iterations,kkt_residual,contact_nodes,plastic_elements,wall_s");
    for n in &names {
        let _ = write!(s, ",{n}");
    }
    s.push('\n');
    for p in &sweep.points {
        let status = p.status.replace([',', '\n'], ";");
        let _ = write!(
            s,
            "{},{},{status},{},{:.3e},{},{},{:.3}",
            number(p.factor),
            p.converged,
            p.iterations,
            p.kkt_residual,
            p.contact_nodes,
            p.plastic_elements,
            p.wall_s
        );
        for n in &names {
            let _ = write!(s, ",{}", p.quantities.get(n).map_or(String::new(), |v| format!("{v:.12e}")));
        }
        s.push('\n');
    }
    s
}

/// `sweep.md`: the table and the plateau indicator.
pub fn markdown(sweep: &Sweep) -> String {
    let (x, y) = &sweep.axes;
    let mut s = format!("# Load sweep: {}\n\n", sweep.title);
    let _ = writeln!(s, "| factor | {x} | {y} | status | iterations | KKT | contact | plastic |");
    s.push_str("|---|---|---|---|---|---|---|---|\n");
    let show = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.6e}"));
    for p in &sweep.points {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {:.1e} | {} | {} |",
            number(p.factor),
            show(p.get(x)),
            show(p.get(y)),
            p.status,
            p.iterations,
            p.kkt_residual,
            p.contact_nodes,
            p.plastic_elements
        );
    }
    match sweep.last_log_slope() {
        Some(k) => {
            let _ = writeln!(
                s,
                "\nd ln {y} / d ln {x} over the last interval: {k:.3} (1: proportional; below 0.05: a plateau, the \
                 limit load when the material is perfectly plastic)."
            );
        }
        None => s.push_str(
            "\nNo plateau indicator: it needs two converged points at different positive x with positive y.\n",
        ),
    }
    s
}
