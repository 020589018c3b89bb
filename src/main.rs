//! The `saddle` command line: `saddle run SCENE.toml [--out DIR] [--solver TYPE]` and
//! `saddle report SCENE.toml --out DIR [--quick] [--levels K,..] [--quantity NAME]` and `saddle bench SCENE.toml [--out DIR] [--sizes N,..]
//! [--solvers T,..]`.

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use saddle::app::run::solve_and_write_with;
use saddle::app::setup::{Loaded, RunError, load_with};
use saddle::app::sweep;
use saddle::io::outdir;
use saddle::io::scene::element_by_type;
use saddle::io::summary::Summary;
use saddle::studies::bench;
use saddle::studies::report::{self, Progress, ReportOptions};
use saddle_core::Monitor;
use saddle_core::{ParameterError, SceneError};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

#[derive(Parser)]
#[command(
    name = "saddle",
    version,
    about = "Variational inequalities in solid mechanics: elasto-plastic contact and friends"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Solve a scene: prints a summary, writes DIR/summary.json and DIR/solution.vtu; with a
    /// [load_path] also DIR/solution_NNNN.vtu per step, solution.pvd, load_path.csv and
    /// load_path.{png,svg}. Exit status: 0 converged, 2 stopped without converging or a load
    /// path stopped by a failed step (outputs flagged), 1 error.
    Run {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Output folder [default: out/<scene name>].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Use this solver type with its default parameters instead of the scene's.
        #[arg(long)]
        solver: Option<String>,
        /// Use this finite element (`p1`, `p2`) instead of the scene's `[discretisation]`.
        #[arg(long)]
        discretisation: Option<String>,
        /// Cells per axis NX,NY,NZ instead of the scene's `mesh.cells` (a `box` mesh; with
        /// `mesh.base`, a level of its family).
        #[arg(long, value_delimiter = ',', value_name = "NX,NY,NZ")]
        cells: Option<Vec<usize>>,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Accuracy and cost: every solver along a ladder of settings against a tight reference
    /// (work–precision), the mesh convergence of the scene's box mesh, and P1 against P2 on
    /// meshes with the same nodes. Writes DIR/ work_precision.{csv,png,svg},
    /// convergence.{csv,png,svg}, elements.{csv,png,svg} and report.md.
    Report {
        /// The scene file (TOML); its [solver] table is ignored.
        scene: PathBuf,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Fewer settings and mesh levels (tests, CI).
        #[arg(long)]
        quick: bool,
        /// On a mesh family (`mesh.base`): the levels k of the convergence study (cells
        /// k·base), e.g. 2,3,4,5; the reference is the extrapolation of the finest three.
        #[arg(long, value_delimiter = ',')]
        levels: Option<Vec<usize>>,
        /// The quantity of interest (the `U` columns, the Richardson extrapolation, P1 against
        /// P2): one the scene reports (`force`, `left.U`, `sym.Fz`, …) [default: the scene's
        /// first extra unknown].
        #[arg(long)]
        quantity: Option<String>,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
    },
    /// A load sweep: the scene solved at each load factor (every load, and each obstacle's force
    /// or prescribed displacement, times the factor), each point from zero; writes DIR/sweep.csv,
    /// sweep.md and sweep.{png,svg} (one reported quantity against another) with the plateau
    /// indicator d ln y / d ln x of the last interval (a limit load when it nears 0).
    Sweep {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Load factors, comma-separated, in the order solved.
        #[arg(long, value_delimiter = ',', required = true, allow_hyphen_values = true)]
        factors: Vec<f64>,
        /// Use this solver type with its default parameters instead of the scene's.
        #[arg(long)]
        solver: Option<String>,
        /// Use this finite element (`p1`, `p2`) instead of the scene's `[discretisation]`.
        #[arg(long)]
        discretisation: Option<String>,
        /// The quantity on the plot's x axis: one the obstacle reports, or `factor`.
        #[arg(long, default_value = "U")]
        x: String,
        /// The quantity on the plot's y axis.
        #[arg(long, default_value = "force")]
        y: String,
    },
    /// Limit analysis (theory §13): the collapse multiplier of the scene's loads for its yield
    /// surface taken perfectly plastic, as one conic solve with both bounds (kinematic and
    /// static) and their gap; writes DIR/limit.json and DIR/mechanism.vtu. Exit status: 0 done,
    /// 1 error (an elastic scene, a yield surface without a conic form, loads that cannot
    /// cause collapse, …).
    Limit {
        /// The scene file (TOML); its [solver] table is ignored.
        scene: PathBuf,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Use this finite element (`p1`, `p2`) instead of the scene's `[discretisation]`.
        #[arg(long)]
        discretisation: Option<String>,
        /// Clarabel's gap and feasibility tolerance.
        #[arg(long, default_value_t = 1e-5)]
        tol: f64,
        /// Print Clarabel's iteration log and its timers (factorisation `kkt update`, solves
        /// `kkt solve`) to stdout.
        #[arg(long)]
        verbose: bool,
    },
    /// Cost against problem size: the scene's box mesh scaled to each size; per-phase times,
    /// one elastic linear solve as the baseline, every solver's total and its ratio to that
    /// solve, iterations, peak memory. Writes DIR/bench.{csv,md,png,svg}.
    Bench {
        /// The scene file (TOML) with a `box` mesh; its [solver] table is ignored.
        scene: PathBuf,
        /// Output folder.
        #[arg(long, default_value = "docs/bench")]
        out: PathBuf,
        /// Target numbers of DOFs, comma-separated.
        #[arg(long, value_delimiter = ',', value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..),
              default_values_t = vec![10_000usize, 50_000, 100_000, 200_000, 400_000])]
        sizes: Vec<usize>,
        /// Solvers, comma-separated: a type (`uzawa`) or TYPE-LINEAR (`newton-amg`, `newton-direct`).
        #[arg(long, value_delimiter = ',', default_values_t = vec!["newton-amg".to_string(), "newton-direct".to_string(), "uzawa".to_string()])]
        solvers: Vec<String>,
        /// Above this many DOFs the Cholesky baseline and the factorising solvers are skipped.
        #[arg(long, default_value_t = 250_000)]
        direct_max_dofs: usize,
        /// Mesh mode: run the scene end to end (as `saddle run`, its own solver) on each of
        /// these Gmsh files instead of scaling a box mesh; writes DIR/meshes.{csv,md}.
        #[arg(long, value_delimiter = ',')]
        meshes: Vec<PathBuf>,
        /// With --meshes: a peer code's JSON per mesh (examples/peers/dolfinx/punch.py --json), in
        /// the same order, for the side-by-side table.
        #[arg(long, value_delimiter = ',', requires = "meshes")]
        peer: Vec<PathBuf>,
    },
}

/// A progress bar driven by the KKT residual on a log scale, from the first residual to the
/// tolerance.
struct Bar {
    bar: ProgressBar,
    first: Option<f64>,
}

impl Bar {
    fn new(quiet: bool) -> Self {
        let bar = if quiet { ProgressBar::hidden() } else { ProgressBar::new(1000) };
        bar.set_style(ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:30} {msg}").unwrap());
        bar.enable_steady_tick(Duration::from_millis(200));
        Self { bar, first: None }
    }
}

impl Monitor for Bar {
    fn phase(&mut self, name: &str) {
        self.bar.set_message(name.to_string());
    }

    fn iteration(&mut self, it: usize, residual: f64, tolerance: f64) {
        let r0 = *self.first.get_or_insert(residual.max(tolerance * 10.0));
        let frac = ((r0 / residual).ln() / (r0 / tolerance).ln()).clamp(0.0, 1.0);
        if frac.is_finite() {
            self.bar.set_position((1000.0 * frac) as u64);
        }
        self.bar.set_message(format!("iteration {it}: KKT {residual:.2e} (target {tolerance:.0e})"));
    }
}

/// A progress bar over the runs of a report; the message follows the current solve.
struct RunsBar {
    bar: ProgressBar,
    label: String,
    started: Instant,
    quiet: bool,
}

impl RunsBar {
    fn new(quiet: bool) -> Self {
        let bar = if quiet { ProgressBar::hidden() } else { ProgressBar::new(0) };
        bar.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} runs  {msg}").unwrap(),
        );
        bar.enable_steady_tick(Duration::from_millis(200));
        Self { bar, label: String::new(), started: Instant::now(), quiet }
    }
}

impl Monitor for RunsBar {
    fn phase(&mut self, name: &str) {
        self.bar.set_message(format!("{}: {name}", self.label));
    }

    fn iteration(&mut self, it: usize, residual: f64, _tolerance: f64) {
        self.bar.set_message(format!("{}: iteration {it}, KKT {residual:.1e}", self.label));
    }
}

impl Progress for RunsBar {
    fn plan(&mut self, runs: usize) {
        self.bar.set_length(runs as u64);
    }

    fn start(&mut self, _index: usize, label: &str) {
        self.label = label.to_string();
        self.started = Instant::now();
        self.bar.set_message(label.to_string());
    }

    fn finish(&mut self, _index: usize, label: &str, status: &str) {
        let line = format!("  {label}: {status} ({:.1} s)", self.started.elapsed().as_secs_f64());
        if !self.quiet && self.bar.is_hidden() {
            // not a terminal: a log line per run instead of the bar
            eprintln!("{line}");
        } else {
            self.bar.println(line);
        }
        self.bar.inc(1);
    }
}

fn print_summary(s: &Summary) {
    let mut rows = vec![("solver".to_string(), s.solver.clone())];
    rows.push(("converged".into(), format!("{} ({:?})", s.converged, s.stop_reason)));
    // each obstacle's own quantities by name: the summary assumes no particular obstacle
    for o in &s.obstacles {
        let label = o.name.as_ref().map_or_else(|| "obstacle".to_string(), |n| format!("obstacle {n}"));
        rows.push((
            label.clone(),
            format!("{} ({} contact nodes, radius {:.4})", o.type_name, o.contact_nodes, o.contact_radius),
        ));
        let prefix = o.name.as_ref().map_or_else(String::new, |n| format!("{n}."));
        for (q, v) in &o.quantities {
            let shown = if v.is_nan() { "undetermined (null)".to_string() } else { format!("{v:.6e}") };
            rows.push((format!("  {prefix}{q}"), shown));
        }
    }
    // each support's reaction (theory §14)
    for (k, r) in &s.reactions {
        let v = |x: [f64; 3]| format!("[{:.6e}, {:.6e}, {:.6e}]", x[0], x[1], x[2]);
        rows.push((format!("reaction {k}"), format!("force {}, moment {}", v(r.force), v(r.moment))));
    }
    rows.extend([
        ("contact nodes".into(), format!("{} of {}", s.contact_nodes, s.contact_rows)),
        ("contact radius".into(), format!("{:.4}", s.contact_radius)),
        ("plastic elements".into(), format!("{} of {}", s.plastic_elements, s.elements)),
        ("max von Mises stress".into(), format!("{:.6}", s.max_von_mises)),
        ("J".into(), format!("{:.10e}", s.J)),
        ("KKT residual".into(), format!("{:.2e} (tolerance {:.0e})", s.kkt_residual, s.tolerance)),
        ("iterations".into(), s.iterations.to_string()),
        ("wall time".into(), format!("{:.2} s", s.wall_s)),
        ("end to end".into(), {
            let phases: Vec<String> = ["read", "setup", "solve", "summary", "estimate", "write"]
                .iter()
                .filter_map(|k| s.end_to_end.get(*k).map(|t| format!("{k} {t:.2}")))
                .collect();
            format!("{:.2} s ({})", s.end_to_end_s, phases.join(", "))
        }),
        ("dofs / elements".into(), format!("{} / {}", s.dofs, s.elements)),
    ]);
    // the a posteriori estimate (theory §15) and its cost
    if let Some(e) = &s.error_estimate {
        let extras: Vec<String> = e.extras.iter().filter_map(|(k, v)| v.map(|v| format!(", {k} ± {v:.2e}"))).collect();
        rows.push((
            "error estimate".into(),
            format!(
                "{:.3e} energy ({:.2} % of the stress){}; cost {:.1} % of the solve",
                e.energy,
                100.0 * e.energy_relative,
                extras.concat(),
                100.0 * e.cost_share
            ),
        ));
    }
    for (k, v) in rows {
        println!("  {k:<22} {v}");
    }
    for w in &s.warnings {
        println!("  warning: {w}");
    }
}

/// `saddle run`'s replacements of the scene's solver, element and cell counts.
type Overrides = (Option<String>, Option<String>, Option<Vec<usize>>);

/// The counts of `--cells`: three, each at least 1 (the scene checks them against its mesh).
fn cell_counts(cells: Option<&[usize]>) -> Result<Option<[usize; 3]>, RunError> {
    cells
        .map(|c| {
            <[usize; 3]>::try_from(c).map_err(|_| {
                let value = c.iter().map(usize::to_string).collect::<Vec<_>>().join(",");
                SceneError::from(ParameterError::new("--cells", value, "needs three counts NX,NY,NZ")).into()
            })
        })
        .transpose()
}

fn run(scene: PathBuf, out: Option<PathBuf>, overrides: Overrides, quiet: bool) -> Result<ExitCode, RunError> {
    let (solver, element, cells) = overrides;
    let element = element.as_deref().map(element_by_type).transpose()?;
    let cells = cell_counts(cells.as_deref())?;
    let loaded = load_with(&scene, solver.as_deref(), |s| {
        if let Some(e) = element {
            s.discretisation = Some(e);
        }
        if let Some(c) = cells {
            *s = s.with_cells(c)?;
        }
        Ok(())
    })?;
    if !quiet {
        eprintln!(
            "{}: {} dofs, {} elements, {} stress points, {} contact rows, solver {}",
            scene.display(),
            loaded.problem.element.n_dofs(),
            loaded.problem.element.mesh().n_elements(),
            loaded.problem.element.n_points(),
            loaded.problem.obstacles.rows().n_rows(),
            loaded.solver.name()
        );
    }
    run_loaded(&scene, &loaded, out, quiet)
}

/// Solves and writes a loaded scene, with a progress bar unless `quiet`; prints the summary.
fn run_loaded(
    scene: &std::path::Path,
    loaded: &Loaded,
    out: Option<PathBuf>,
    quiet: bool,
) -> Result<ExitCode, RunError> {
    let out = out.unwrap_or_else(|| PathBuf::from("out").join(scene.file_stem().unwrap_or_default()));
    let mut bar = Bar::new(quiet);
    let lines = bar.bar.clone();
    let result = solve_and_write_with(loaded, &out, &mut bar, &mut |line| {
        if quiet {
        } else if lines.is_hidden() {
            eprintln!("  {line}");
        } else {
            lines.println(format!("  {line}"));
        }
    });
    bar.bar.finish_and_clear();
    let outcome = result?;
    if !loaded.ranks.is_root() {
        return Ok(if outcome.summary.converged { ExitCode::SUCCESS } else { ExitCode::from(2) });
    }
    if let Some(n) = outcome.summary.ranks {
        println!("  {:<22} {n}", "ranks");
    }
    print_summary(&outcome.summary);
    if let Some(p) = &outcome.summary.load_path {
        let stopped = if p.completed { "" } else { ", stopped" };
        println!("  load path: {} of {} steps{stopped}", p.steps_done, p.step_factors.len());
    }
    println!("  wrote {}: {}", outcome.out_dir.display(), outdir::describe(&outcome.written));
    Ok(if outcome.summary.converged { ExitCode::SUCCESS } else { ExitCode::from(2) })
}

fn report(scene: PathBuf, out: PathBuf, options: ReportOptions, quiet: bool) -> Result<ExitCode, report::ReportError> {
    let quick = options.quick;
    if !quiet {
        eprintln!("{}: report into {}{}", scene.display(), out.display(), if quick { " (quick)" } else { "" });
    }
    let mut bar = RunsBar::new(quiet);
    let result = report::generate(&scene, &out, &options, &mut bar);
    bar.bar.finish_and_clear();
    let r = result?;
    let q = r.quantity.as_ref().map_or("quantity", |(n, _)| n.as_str());
    println!("  {} ({} dofs): {} runs in {:.0} s", r.title, r.dofs, r.runs.len(), r.total_s);
    for t in report::tables::tightest(&r.runs) {
        let e = t.errors.expect("tightest runs have errors");
        println!(
            "  {:<8} {:<44} σ̂ error {:.2e}  {} error {:.2e}  {:.1} s",
            t.solver, t.setting, e.stress_rel, q, e.u_rel, t.wall_s
        );
    }
    match &r.convergence {
        Ok(study) => println!(
            "  mesh convergence: {} levels, fitted σ̂ rate {} (Theorem 2: at least 0.5)",
            study.levels.len(),
            study.stress_rate_fit.map_or("-".into(), |x| format!("{x:.2}"))
        ),
        Err(why) => println!("  mesh convergence skipped: {why}"),
    }
    println!("  wrote {}/report.md, work_precision.*, convergence.*", out.display());
    Ok(ExitCode::SUCCESS)
}

fn bench(
    scene: PathBuf,
    out: PathBuf,
    sizes: Vec<usize>,
    solvers: Vec<String>,
    direct_max_dofs: usize,
) -> Result<ExitCode, String> {
    for s in &solvers {
        bench::solver_spec(s)?;
    }
    eprintln!("{}: bench at {sizes:?} DOFs with {solvers:?} into {}", scene.display(), out.display());
    let opts = bench::BenchOptions { sizes, solvers, direct_max_dofs };
    let started = Instant::now();
    let b = bench::generate(&scene, &out, &opts, &mut |line| {
        eprintln!("  [{:>6.1} s] {line}", started.elapsed().as_secs_f64())
    })
    .map_err(|e| e.to_string())?;
    println!("{}", bench::markdown(&b));
    println!("  wrote {}/bench.csv, bench.md, bench.png, bench.svg", out.display());
    Ok(ExitCode::SUCCESS)
}

fn sweep(
    scene: PathBuf,
    out: PathBuf,
    factors: Vec<f64>,
    (solver, element): (Option<String>, Option<String>),
    axes: (String, String),
) -> Result<ExitCode, String> {
    eprintln!("{}: sweep over load factors {factors:?} into {}", scene.display(), out.display());
    let started = Instant::now();
    let opts = sweep::SweepOptions { factors, solver, element, axes };
    let s = sweep::generate(&scene, &opts, &out, &mut |line| {
        eprintln!("  [{:>6.1} s] {line}", started.elapsed().as_secs_f64())
    })
    .map_err(|e| e.to_string())?;
    println!("{}", sweep::markdown(&s));
    println!("  wrote {}: {}", out.display(), outdir::describe(&s.written));
    // as `run`: 2 when a point stopped without converging
    Ok(if s.points.iter().all(|p| p.converged) { ExitCode::SUCCESS } else { ExitCode::from(2) })
}

#[cfg(feature = "socp")]
fn limit(
    scene: PathBuf,
    out: PathBuf,
    element: Option<String>,
    (tol, verbose): (f64, bool),
) -> Result<ExitCode, String> {
    use saddle::app::limit;
    use saddle_solvers::LimitAnalysis;
    eprintln!("{}: limit analysis into {}", scene.display(), out.display());
    let settings = LimitAnalysis { tol, verbose, ..LimitAnalysis::default() };
    let o = limit::run(&scene, &out, element.as_deref(), &settings).map_err(|e| e.to_string())?;
    let s = &o.summary;
    println!("  multiplier (kinematic)  {:.8e}", s.multiplier);
    println!("  dual_multiplier (static) {:.8e}", s.dual_multiplier);
    println!("  gap                     {:.2e} (relative {:.2e})", s.gap, s.relative_gap);
    for (name, ob) in &s.obstacles {
        let force = ob.force.map_or("-".to_string(), |f| format!("{f:.8e}"));
        println!("  {name:<23} collapse force {force} ({} contact nodes)", ob.contact_nodes);
    }
    println!("  {:<23} {} / {} cones / {} variables", "dofs", s.dofs, s.cones, s.variables);
    println!("  {:<23} {} after {} iterations, {:.2} s", "Clarabel", s.status, s.iterations, s.wall_s);
    for w in &s.warnings {
        println!("  warning: {w}");
    }
    println!("  wrote {}: {}", out.display(), outdir::describe(&o.written));
    Ok(ExitCode::SUCCESS)
}

#[cfg(not(feature = "socp"))]
fn limit(_: PathBuf, _: PathBuf, _: Option<String>, _: (f64, bool)) -> Result<ExitCode, String> {
    Err("limit analysis needs the conic solver: build with the `socp` feature".into())
}

#[cfg(feature = "gmsh")]
fn bench_meshes(scene: PathBuf, out: PathBuf, meshes: Vec<PathBuf>, peers: Vec<PathBuf>) -> Result<ExitCode, String> {
    eprintln!("{}: end to end on {} meshes into {}", scene.display(), meshes.len(), out.display());
    let started = Instant::now();
    let table = saddle::studies::peer::generate(&scene, &meshes, &peers, &out, &mut |line| {
        eprintln!("  [{:>6.1} s] {line}", started.elapsed().as_secs_f64())
    })
    .map_err(|e| e.to_string())?;
    println!("{table}");
    println!("  wrote {}/meshes.csv, meshes.md", out.display());
    Ok(ExitCode::SUCCESS)
}

#[cfg(not(feature = "gmsh"))]
fn bench_meshes(_: PathBuf, _: PathBuf, _: Vec<PathBuf>, _: Vec<PathBuf>) -> Result<ExitCode, String> {
    Err("--meshes reads Gmsh files: build with the `gmsh` feature".into())
}

/// Exit statuses: 0 done (converged), 1 bad input or usage (the command line included) or any
/// other error, 2 stopped without converging with the outputs written.
fn main() -> ExitCode {
    #[cfg(feature = "mpi")]
    if saddle::app::mpi::launched_by_mpirun() {
        return mpi_main();
    }
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind::{DisplayHelp, DisplayVersion};
            let _ = e.print();
            // usage errors exit 1 (clap's own 2 is the status of a solve that did not converge)
            return if matches!(e.kind(), DisplayHelp | DisplayVersion) {
                ExitCode::SUCCESS
            } else {
                ExitCode::FAILURE
            };
        }
    };
    let result = match cli.command {
        Command::Run { scene, out, solver, discretisation, cells, quiet } => {
            run(scene, out, (solver, discretisation, cells), quiet).map_err(|e| e.to_string())
        }
        Command::Report { scene, out, quick, levels, quantity, quiet } => {
            report(scene, out, ReportOptions { quick, levels, quantity }, quiet).map_err(|e| e.to_string())
        }
        Command::Sweep { scene, out, factors, solver, discretisation, x, y } => {
            sweep(scene, out, factors, (solver, discretisation), (x, y))
        }
        Command::Limit { scene, out, discretisation, tol, verbose } => {
            limit(scene, out, discretisation, (tol, verbose))
        }
        Command::Bench { scene, out, meshes, peer, .. } if !meshes.is_empty() => bench_meshes(scene, out, meshes, peer),
        Command::Bench { scene, out, sizes, solvers, direct_max_dofs, .. } => {
            bench(scene, out, sizes, solvers, direct_max_dofs)
        }
    };
    result.unwrap_or_else(|e| {
        eprintln!("error: {e}");
        ExitCode::FAILURE
    })
}

/// `saddle` under `mpirun` (feature `mpi`, theory §12): MPI and PETSc initialised with PETSc's
/// words of the command line (`-ksp_view`, `-log_view`, …; [`saddle::app::mpi::split_petsc_args`]),
/// then `saddle run` on every rank. A solver that runs on one rank only runs as on one machine
/// when there is one rank. Every rank prints an error it ends with; the progress and the summary
/// are rank 0's.
#[cfg(feature = "mpi")]
fn mpi_main() -> ExitCode {
    use saddle::app::mpi;
    let (ours, petsc) = mpi::split_petsc_args(std::env::args().collect());
    let session = match saddle_parallel::saddle_mpi::Petsc::initialize_with_args(petsc) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: cannot initialise MPI and PETSc: {e}");
            return ExitCode::FAILURE;
        }
    };
    let (rank, size) = (session.rank(), session.size());
    let cli = match Cli::try_parse_from(ours) {
        Ok(cli) => cli,
        Err(e) => {
            if rank == 0 {
                let _ = e.print();
            }
            return ExitCode::FAILURE;
        }
    };
    let Command::Run { scene, out, solver, discretisation, cells, quiet } = cli.command else {
        eprintln!("error: under mpirun saddle runs `saddle run` only; run the other commands without mpirun");
        return ExitCode::FAILURE;
    };
    let quiet = quiet || rank != 0;
    let loaded = cell_counts(cells.as_deref())
        .and_then(|c| mpi::load(&session, &scene, solver.as_deref(), (discretisation.as_deref(), c)));
    let result = match loaded {
        // one rank and a solver that runs on one rank only: as on one machine
        Ok(loaded) if size == 1 && !loaded.solver.runs_distributed() => {
            run(scene, out, (solver, discretisation, cells), quiet)
        }
        Ok(loaded) => {
            if !quiet {
                eprintln!(
                    "{}: {} ranks, {} dofs on rank 0, solver {}",
                    scene.display(),
                    size,
                    loaded.problem.element.n_dofs(),
                    loaded.solver.name()
                );
            }
            run_loaded(&scene, &loaded, out, quiet)
        }
        Err(e) => Err(e),
    };
    result.unwrap_or_else(|e| {
        // one write, so that the ranks' lines do not interleave
        let line = format!("error (rank {rank} of {size}): {e}\n");
        let _ = std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes());
        ExitCode::FAILURE
    })
}
