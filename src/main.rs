//! The `saddle` command line: `saddle run SCENE.toml [--out DIR] [--solver TYPE]`.

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use saddle::run::{self, RunError};
use saddle_core::{Lagrangian, Monitor, Summary};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

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
    /// Solve a scene: prints a summary, writes DIR/summary.json and DIR/solution.vtu.
    /// Exit status: 0 converged, 2 stopped without converging (outputs flagged), 1 error.
    Run {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Output folder [default: out/<scene name>].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Use this solver type with its default parameters instead of the scene's.
        #[arg(long)]
        solver: Option<String>,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
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

fn print_summary(s: &Summary) {
    let opt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.6e}"));
    let rows = [
        ("solver", s.solver.clone()),
        ("converged", format!("{} ({:?})", s.converged, s.stop_reason)),
        ("U", opt(s.U)),
        ("contact force", opt(s.force)),
        ("contact nodes", format!("{} of {}", s.contact_nodes, s.contact_rows)),
        ("contact radius", format!("{:.4}", s.contact_radius)),
        ("plastic elements", format!("{} of {}", s.plastic_elements, s.elements)),
        ("max von Mises stress", format!("{:.6}", s.max_von_mises)),
        ("J", format!("{:.10e}", s.J)),
        ("KKT residual", format!("{:.2e} (tolerance {:.0e})", s.kkt_residual, s.tolerance)),
        ("iterations", s.iterations.to_string()),
        ("wall time", format!("{:.2} s", s.wall_s)),
        ("dofs / elements", format!("{} / {}", s.dofs, s.elements)),
    ];
    for (k, v) in rows {
        println!("  {k:<22} {v}");
    }
    for w in &s.warnings {
        println!("  warning: {w}");
    }
}

fn run(scene: PathBuf, out: Option<PathBuf>, solver: Option<String>, quiet: bool) -> Result<ExitCode, RunError> {
    let out = out.unwrap_or_else(|| PathBuf::from("out").join(scene.file_stem().unwrap_or_default()));
    let loaded = run::load(&scene, solver.as_deref())?;
    if !quiet {
        eprintln!(
            "{}: {} dofs, {} elements, {} contact rows, solver {}",
            scene.display(),
            loaded.problem.n_dofs(),
            loaded.problem.n_points(),
            loaded.problem.constraints().n_rows(),
            loaded.solver.name()
        );
    }
    let mut bar = Bar::new(quiet);
    let result = run::solve_and_write(&loaded, &out, &mut bar);
    bar.bar.finish_and_clear();
    let outcome = result?;
    print_summary(&outcome.summary);
    println!("  wrote {}/summary.json and solution.vtu", outcome.out_dir.display());
    Ok(if outcome.summary.converged { ExitCode::SUCCESS } else { ExitCode::from(2) })
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run { scene, out, solver, quiet } => run(scene, out, solver, quiet),
    };
    result.unwrap_or_else(|e| {
        eprintln!("error: {e}");
        ExitCode::FAILURE
    })
}
