//! `saddle bench`: cost against problem size (issue 6). The scene's box mesh is scaled to a
//! ladder of sizes (the default scene family: cells 2n × 2n × n); at each size it measures the
//! phases of building the problem (mesh, L with its pattern and stiffness, one re-assembly of
//! the stiffness values), **one elastic linear solve** of that mesh with faer's supernodal
//! Cholesky (symbolic analysis, numeric factorisation, one solve) as the baseline, an elastic
//! scene without contact run through each solver (what a scene pays for the framework: ratio
//! to the baseline, issue 5), and each solver on the scene itself: wall time, per-phase times,
//! iterations, the KKT residual, peak resident memory, and the ratio *solver total / baseline*.
//! Writes `bench.csv`, `bench.md` and (feature `report`) `bench.png`/`bench.svg`: time against
//! DOFs on log–log axes with the fitted slopes.
//!
//! ```text
//! cargo run --release -- bench examples/johnson.toml --out docs/bench
//! cargo run --release -- bench examples/johnson.toml --sizes 10000,50000,100000 --solvers newton,uzawa
//! ```

use super::report::convergence::fitted_rate;
use super::report::measure::{ReportError, SceneSource};
use crate::app::setup::solver_by_type;
use saddle_core::linalg::{AmgParams, Csr, LowerCsc, NearNullSpace, Pcg, SmoothedAggregation, SparseCholesky};
use saddle_core::problem::operators::RIGID_BODY_MODES;
use saddle_core::{DiscreteProblem, Load, Material, Obstacles, P1P0Element, Silent, Solver, Workspace, kkt};
use saddle_solvers::{LinearSolver, Newton};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What to run.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// Target numbers of free DOFs (the nearest size of the mesh family is used).
    pub sizes: Vec<usize>,
    /// Solvers: a type with its defaults (`uzawa`), or `TYPE-LINEAR` for a solver with a
    /// `linear` option (`newton-direct`, `newton-amg`).
    pub solvers: Vec<String>,
    /// Above this many DOFs the direct baseline and the solvers that factorise are skipped
    /// (faer's Cholesky needs > 2 minutes and 10 GB at 400k DOFs).
    pub direct_max_dofs: usize,
}

impl Default for BenchOptions {
    fn default() -> Self {
        Self {
            sizes: vec![10_000, 50_000, 100_000, 200_000, 400_000],
            solvers: vec!["newton-amg".into(), "newton-direct".into(), "uzawa".into()],
            direct_max_dofs: 250_000,
        }
    }
}

/// The solver a bench name stands for (`uzawa`, `newton-amg`, …) and whether it factorises.
pub fn solver_spec(name: &str) -> Result<(Box<dyn Solver>, bool), String> {
    let (kind, linear) = match name.split_once('-') {
        Some((k, lin)) => (k, Some(lin)),
        None => (name, None),
    };
    let solver: Box<dyn Solver> = match linear {
        None => solver_by_type(kind).map_err(|e| format!("bench solver {name:?}: {e}"))?,
        Some(lin) => {
            let linear = match lin {
                "direct" => LinearSolver::Direct,
                "amg" => LinearSolver::Amg,
                "auto" => LinearSolver::Auto,
                other => {
                    return Err(format!("bench solver {name:?}: unknown linear backend `{other}` (direct, amg, auto)"));
                }
            };
            if kind != "newton" {
                return Err(format!("bench solver {name:?}: only `newton` takes a linear backend"));
            }
            Box::new(Newton { linear, ..Newton::default() })
        }
    };
    Ok((solver, linear != Some("amg")))
}

/// Peak resident memory since the last [`reset_peak_memory`], in MiB (Linux; 0 elsewhere).
pub fn peak_memory_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(0.0, |kib| kib / 1024.0)
}

/// Resets the peak resident memory to the current one (Linux ≥ 4.0: `clear_refs` = 5).
pub fn reset_peak_memory() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// One elastic linear solve of K u = f with faer's supernodal Cholesky: the baseline.
#[derive(Clone, Debug, Default)]
pub struct LinearSolve {
    /// Symbolic analysis (AMD ordering, supernodes), s.
    pub analyse_s: f64,
    /// Numeric factorisation, s.
    pub factorise_s: f64,
    /// One forward and back substitution, s.
    pub solve_s: f64,
    /// Stored entries of L.
    pub nnz_l: usize,
    /// Peak resident memory, MiB.
    pub peak_mib: f64,
}

impl LinearSolve {
    /// analyse + factorise + solve.
    pub fn total_s(&self) -> f64 {
        self.analyse_s + self.factorise_s + self.solve_s
    }
}

/// One solver run.
#[derive(Clone, Debug)]
pub struct SolverRun {
    /// Solver type.
    pub solver: String,
    /// `scene` (the benchmark scene) or `elastic` (no yield, no contact, a body force).
    pub variant: &'static str,
    /// Converged to its tolerance.
    pub converged: bool,
    /// Iterations.
    pub iterations: usize,
    /// Relative KKT residual recomputed from the solution.
    pub kkt: f64,
    /// Wall time of `solve`, s.
    pub total_s: f64,
    /// Per-phase times, s.
    pub phases: Vec<(String, f64)>,
    /// Factorisations and triangular solve pairs (the solver's counters).
    pub factorisations: f64,
    /// Triangular solve pairs.
    pub solve_pairs: f64,
    /// Peak resident memory, MiB.
    pub peak_mib: f64,
    /// The error, if the solver failed.
    pub error: Option<String>,
}

/// One elastic solve by CG with the smoothed-aggregation multigrid (relative residual 1e-8).
#[derive(Clone, Debug, Default)]
pub struct IterativeSolve {
    /// Multigrid set-up (CSR conversion, aggregation, Galerkin products), s.
    pub setup_s: f64,
    /// CG, s.
    pub solve_s: f64,
    /// CG iterations.
    pub iterations: usize,
    /// Peak resident memory, MiB.
    pub peak_mib: f64,
}

impl IterativeSolve {
    /// set-up + solve.
    pub fn total_s(&self) -> f64 {
        self.setup_s + self.solve_s
    }
}

/// Everything measured at one size.
#[derive(Clone, Debug)]
pub struct SizeResult {
    /// Box cells.
    pub cells: [usize; 3],
    /// Free DOFs.
    pub dofs: usize,
    /// Tetrahedra.
    pub elements: usize,
    /// Contact rows.
    pub contact_rows: usize,
    /// Mesh generation, s.
    pub mesh_s: f64,
    /// L: DOFs, pattern, stiffness, constraints, s.
    pub problem_s: f64,
    /// One re-assembly of the stiffness values on the fixed pattern, s.
    pub reassembly_s: f64,
    /// The direct baseline (skipped above `direct_max_dofs`).
    pub linear: Option<LinearSolve>,
    /// The iterative baseline.
    pub iterative: IterativeSolve,
    /// The runs (elastic variants first).
    pub runs: Vec<SolverRun>,
}

/// The whole benchmark.
#[derive(Clone, Debug)]
pub struct Bench {
    /// Scene title.
    pub title: String,
    /// One entry per size.
    pub sizes: Vec<SizeResult>,
    /// Machine load (1-minute average) before and after.
    pub load: (f64, f64),
}

/// The 1-minute load average (Linux).
pub fn load_average() -> f64 {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(f64::NAN)
}

/// Cells of the scene's box mesh scaled to about `target` free DOFs (free DOFs grow like the
/// number of nodes: the scale factor is the cube root of the ratio).
pub fn cells_for(base: [usize; 3], base_dofs: usize, target: usize) -> [usize; 3] {
    let s = (target as f64 / base_dofs as f64).cbrt();
    base.map(|c| ((c as f64 * s).round() as usize).max(2))
}

/// Runs one size; `progress` gets a line per finished step.
pub fn measure(
    source: &SceneSource,
    cells: [usize; 3],
    opts: &BenchOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<SizeResult, ReportError> {
    let scene = source.scene(Some(cells))?;
    let t = Instant::now();
    let mesh = scene.mesh.build(&scene.base_dir).map_err(saddle_core::SceneError::from)?;
    let mesh_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let element = Box::new(P1P0Element::new(mesh, &scene.dirichlet)?);
    let problem = DiscreteProblem::new(element, scene.material, scene.yield_surface, scene.obstacle, &scene.load)?;
    let problem_s = t.elapsed().as_secs_f64();
    let l = &problem.lagrangian();
    let c = l.data.elasticity.stiffness_matrix();
    let mut k = vec![0.0; l.pattern().nnz()];
    let t = Instant::now();
    l.assemble(Material::Uniform(&c), &mut k);
    let reassembly_s = t.elapsed().as_secs_f64();
    progress(&format!("{} dofs: mesh {mesh_s:.2} s, L {problem_s:.2} s, re-assembly {reassembly_s:.3} s", l.n_dofs()));
    // the baselines: one elastic solve, a vertical unit body load, by Cholesky and by AMG-CG
    let b: Vec<f64> = (0..l.n_dofs()).map(|i| if i % 3 == 2 { -1.0 } else { 0.0 }).collect();
    let direct = l.n_dofs() <= opts.direct_max_dofs;
    let linear = if direct {
        reset_peak_memory();
        let mut linear = LinearSolve::default();
        let t = Instant::now();
        let mut chol = SparseCholesky::analyse(lower(&problem), "elastic stiffness").map_err(bench_error)?;
        linear.analyse_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        chol.factorise(&k).map_err(bench_error)?;
        linear.factorise_s = t.elapsed().as_secs_f64();
        let mut x = b.clone();
        let t = Instant::now();
        chol.solve(&mut x);
        linear.solve_s = t.elapsed().as_secs_f64();
        linear.nnz_l = chol.nnz_l();
        linear.peak_mib = peak_memory_mib();
        progress(&format!(
            "{} dofs: elastic solve, Cholesky {:.2} s (analyse {:.2}, factorise {:.2}, solve {:.3})",
            l.n_dofs(),
            linear.total_s(),
            linear.analyse_s,
            linear.factorise_s,
            linear.solve_s
        ));
        Some(linear)
    } else {
        None
    };
    let iterative = {
        reset_peak_memory();
        let t = Instant::now();
        let modes = l.rigid_body_modes().ok_or_else(|| bench_error("no rigid-body modes"))?;
        let near_null = NearNullSpace::new(modes.node, modes.modes, RIGID_BODY_MODES).map_err(bench_error)?;
        let a = Csr::from_symmetric_lower(lower(&problem), &k);
        let amg = SmoothedAggregation::new(&a, &near_null, &AmgParams::default()).map_err(bench_error)?;
        let setup_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut x = vec![0.0; l.n_dofs()];
        let report = Pcg::new(l.n_dofs()).solve(&a, &amg, &b, &mut x, 1e-8, 1000).map_err(bench_error)?;
        let solve_s = t.elapsed().as_secs_f64();
        let it = IterativeSolve { setup_s, solve_s, iterations: report.iterations, peak_mib: peak_memory_mib() };
        progress(&format!(
            "{} dofs: elastic solve, AMG-CG {:.2} s (set-up {:.2}, {} CG iterations {:.2})",
            l.n_dofs(),
            it.total_s(),
            it.setup_s,
            it.iterations,
            it.solve_s
        ));
        it
    };
    let mut runs = vec![];
    // the elastic scene without contact: what the framework costs over one linear solve
    let elastic = elastic_variant(source, cells)?;
    let wanted = |name: &String| direct || !solver_spec(name).map(|s| s.1).unwrap_or(true);
    for name in opts.solvers.iter().filter(|n| wanted(n)) {
        let run = run_solver(&elastic, name, "elastic")?;
        progress(&format!("{} dofs: elastic scene, {name}: {:.2} s", l.n_dofs(), run.total_s));
        runs.push(run);
    }
    for name in opts.solvers.iter().filter(|n| wanted(n)) {
        let run = run_solver(&problem, name, "scene")?;
        progress(&format!(
            "{} dofs: {name}: {:.2} s, {} iterations, KKT {:.1e}{}",
            l.n_dofs(),
            run.total_s,
            run.iterations,
            run.kkt,
            run.error.as_deref().map_or(String::new(), |e| format!(" ERROR {e}"))
        ));
        runs.push(run);
    }
    Ok(SizeResult {
        cells,
        dofs: l.n_dofs(),
        elements: l.n_points(),
        contact_rows: l.data.rows.n_rows(),
        mesh_s,
        problem_s,
        reassembly_s,
        linear,
        iterative,
        runs,
    })
}

fn bench_error(e: impl std::fmt::Display) -> ReportError {
    ReportError::Scene(saddle_core::SceneError::Parse { path: "bench".into(), message: e.to_string() })
}

/// The scene at `cells` without yield surface and obstacle, loaded by a body force instead.
fn elastic_variant(source: &SceneSource, cells: [usize; 3]) -> Result<DiscreteProblem, ReportError> {
    let mut scene = source.scene(Some(cells))?;
    scene.yield_surface = None;
    scene.obstacle = Obstacles::none();
    scene.solver = None;
    scene.load = vec![Load::BodyForce { b: [0.0, 0.0, -1e-3] }];
    Ok(scene.into_problem()?.0)
}

/// The lower triangle of L's matrices as the linear algebra takes it.
fn lower(problem: &DiscreteProblem) -> LowerCsc<'_> {
    let p = problem.element.pattern();
    LowerCsc::new(p.n(), p.col_ptr(), p.row_idx())
}

/// Runs solver `name` (defaults) on `l`, measuring time and peak memory.
fn run_solver(problem: &DiscreteProblem, name: &str, variant: &'static str) -> Result<SolverRun, ReportError> {
    let l = &problem.lagrangian();
    let solver = solver_spec(name).map_err(bench_error)?.0;
    reset_peak_memory();
    let t = Instant::now();
    let result = solver.solve(l, &mut Silent);
    let total_s = t.elapsed().as_secs_f64();
    let peak_mib = peak_memory_mib();
    Ok(match result {
        Ok(sol) => {
            let kkt = kkt(l, &sol.iterate(), &mut Workspace::new(l)).max();
            let r = &sol.report;
            SolverRun {
                solver: name.into(),
                variant,
                converged: r.converged,
                iterations: r.iterations,
                kkt,
                total_s,
                phases: r.phases.clone(),
                factorisations: r.counters.get("factorisations").copied().unwrap_or(f64::NAN),
                solve_pairs: r.counters.get("triangular_solve_pairs").copied().unwrap_or(f64::NAN),
                peak_mib,
                error: None,
            }
        }
        Err(e) => SolverRun {
            solver: name.into(),
            variant,
            converged: false,
            iterations: 0,
            kkt: f64::NAN,
            total_s,
            phases: vec![],
            factorisations: f64::NAN,
            solve_pairs: f64::NAN,
            peak_mib,
            error: Some(e.to_string()),
        },
    })
}

/// Runs the benchmark on `scene` into `out`.
pub fn generate(
    scene: &Path,
    out: &Path,
    opts: &BenchOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<Bench, ReportError> {
    let source = SceneSource::read(scene)?;
    let base = source.box_cells().map_err(bench_error)?;
    let base_dofs = source.problem(None)?.element.n_dofs();
    let load0 = load_average();
    let mut sizes = vec![];
    for &target in &opts.sizes {
        let cells = cells_for(base, base_dofs, target);
        sizes.push(measure(&source, cells, opts, progress)?);
    }
    let bench = Bench { title: source.title(), sizes, load: (load0, load_average()) };
    std::fs::create_dir_all(out).map_err(|e| io_error(out, e))?;
    let csv = out.join("bench.csv");
    std::fs::write(&csv, csv_text(&bench)).map_err(|e| io_error(&csv, e))?;
    let md = out.join("bench.md");
    std::fs::write(&md, markdown(&bench)).map_err(|e| io_error(&md, e))?;
    #[cfg(feature = "report")]
    {
        let labels = [
            "saddle bench: the default scene family (2 cores)",
            "wall time against problem size",
            "degrees of freedom",
            "wall time (s)",
        ];
        crate::io::plot::lines(&scaling_series(&bench), labels, true, &out.join("bench.png"), &out.join("bench.svg"))?;
    }
    Ok(bench)
}

fn io_error(path: &Path, source: std::io::Error) -> ReportError {
    ReportError::Io { path: PathBuf::from(path), source }
}

/// Least-squares slope of ln t against ln N.
pub fn fitted_slope(points: &[(f64, f64)]) -> Option<f64> {
    let (n, t): (Vec<f64>, Vec<f64>) = points.iter().copied().unzip();
    fitted_rate(&n, &t)
}

impl SizeResult {
    /// The fastest elastic linear solve of this mesh (Cholesky or AMG-CG).
    pub fn baseline_s(&self) -> f64 {
        self.cholesky_s().min(self.iterative.total_s())
    }

    /// One elastic solve by Cholesky (∞ when skipped).
    pub fn cholesky_s(&self) -> f64 {
        self.linear.as_ref().map_or(f64::INFINITY, LinearSolve::total_s)
    }

    /// The baseline of the same kind as a run's linear algebra: AMG-CG for `*-amg` solvers,
    /// Cholesky for the factorising ones.
    pub fn own_baseline_s(&self, solver: &str) -> f64 {
        if solver.ends_with("-amg") { self.iterative.total_s() } else { self.cholesky_s() }
    }
}

/// Solver names in the order of the runs.
fn solver_names(bench: &Bench) -> Vec<String> {
    let mut names: Vec<String> = vec![];
    for z in &bench.sizes {
        for r in z.runs.iter().filter(|r| r.variant == "scene") {
            if !names.contains(&r.solver) {
                names.push(r.solver.clone());
            }
        }
    }
    names
}

/// (name, points (DOFs, seconds)) per line of the plot: the baselines and each solver.
pub fn scaling_series(bench: &Bench) -> Vec<(String, Vec<(f64, f64)>)> {
    let mut series = vec![
        (
            "one elastic solve, Cholesky (faer)".to_string(),
            bench.sizes.iter().filter_map(|s| Some((s.dofs as f64, s.linear.as_ref()?.total_s()))).collect::<Vec<_>>(),
        ),
        (
            "one elastic solve, AMG-CG to 1e-8".to_string(),
            bench.sizes.iter().map(|s| (s.dofs as f64, s.iterative.total_s())).collect::<Vec<_>>(),
        ),
    ];
    for name in solver_names(bench) {
        let pts: Vec<(f64, f64)> = bench
            .sizes
            .iter()
            .filter_map(|s| {
                s.runs
                    .iter()
                    .find(|r| r.variant == "scene" && r.solver == name && r.converged)
                    .map(|r| (s.dofs as f64, r.total_s))
            })
            .collect();
        series.push((name, pts));
    }
    series
        .into_iter()
        .map(|(name, pts)| {
            let slope = fitted_slope(&pts).map_or(String::new(), |p| format!(" (slope {p:.2})"));
            (format!("{name}{slope}"), pts)
        })
        .collect()
}

/// `t / base` with 3 decimals, or empty when the baseline was skipped.
fn opt_ratio(t: f64, base: f64) -> String {
    if base.is_finite() { format!("{:.3}", t / base) } else { String::new() }
}

fn phase_list(phases: &[(String, f64)]) -> String {
    phases.iter().map(|(k, t)| format!("{k}={t:.3}")).collect::<Vec<_>>().join(";")
}

/// `bench.csv`: one row per size and run; the baselines as solvers `cholesky` and `amg-cg`.
pub fn csv_text(bench: &Bench) -> String {
    let mut s = String::from(
        "dofs,elements,contact_rows,cells,variant,solver,converged,iterations,kkt,total_s,ratio_to_cholesky,ratio_to_amg_cg,\
         factorisations,solve_pairs,peak_mib,mesh_s,problem_s,reassembly_s,phases\n",
    );
    for z in &bench.sizes {
        let cells = format!("{}x{}x{}", z.cells[0], z.cells[1], z.cells[2]);
        let head = format!("{},{},{},{cells}", z.dofs, z.elements, z.contact_rows);
        let tail = format!("{:.4},{:.4},{:.4}", z.mesh_s, z.problem_s, z.reassembly_s);
        let it_total = z.iterative.total_s();
        if let Some(lin) = &z.linear {
            let _ = writeln!(
                s,
                "{head},baseline,cholesky,true,1,,{:.4},1,{:.3},1,1,{:.0},{tail},analyse={:.3};factorise={:.3};solve={:.4}",
                lin.total_s(),
                lin.total_s() / it_total,
                lin.peak_mib,
                lin.analyse_s,
                lin.factorise_s,
                lin.solve_s
            );
        }
        let it = &z.iterative;
        let _ = writeln!(
            s,
            "{head},baseline,amg-cg,true,{},,{:.4},{},1,0,,{:.0},{tail},setup={:.3};solve={:.4}",
            it.iterations,
            it.total_s(),
            opt_ratio(it.total_s(), z.cholesky_s()),
            it.peak_mib,
            it.setup_s,
            it.solve_s
        );
        for r in &z.runs {
            let _ = writeln!(
                s,
                "{head},{},{},{},{},{:.3e},{:.4},{},{:.3},{},{},{:.0},{tail},{}",
                r.variant,
                r.solver,
                r.converged,
                r.iterations,
                r.kkt,
                r.total_s,
                opt_ratio(r.total_s, z.cholesky_s()),
                r.total_s / it_total,
                r.factorisations,
                r.solve_pairs,
                r.peak_mib,
                phase_list(&r.phases)
            );
        }
    }
    s
}

/// "2.0× C, 8.2× A": `t` over the Cholesky and the AMG-CG elastic solve.
fn ratios(t: f64, z: &SizeResult) -> String {
    let c = z.cholesky_s();
    let a = format!("{:.1}× A", t / z.iterative.total_s());
    if c.is_finite() { format!("{:.1}× C, {a}", t / c) } else { a }
}

/// `bench.md`: the tables and the fitted slopes.
pub fn markdown(bench: &Bench) -> String {
    let mut s = format!(
        "Machine: 2 cores; 1-minute load average {:.2} before, {:.2} after. Solver ratios are to one elastic \
         solve of the same mesh by Cholesky (C) and by AMG-CG (A); the elastic scene's ratio is to the solve of \
         its own kind (AMG-CG for `-amg`, else Cholesky).\n\n\
         | DOFs | tets | contact rows | mesh | L (pattern + stiffness) | re-assembly | elastic solve, Cholesky: \
         analyse / factorise / solve, peak | elastic solve, AMG-CG: set-up + solve (iterations), peak |\n\
         |---:|---:|---:|---:|---:|---:|---|---|\n",
        bench.load.0, bench.load.1
    );
    for z in &bench.sizes {
        let chol = z.linear.as_ref().map_or("skipped (too large for a direct solve)".to_string(), |lin| {
            format!(
                "{:.2} s: {:.2} / {:.2} / {:.3}, {:.0} MiB",
                lin.total_s(),
                lin.analyse_s,
                lin.factorise_s,
                lin.solve_s,
                lin.peak_mib
            )
        });
        let it = &z.iterative;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.2} s | {:.2} s | {:.3} s | {chol} | {:.2} s: {:.2} + {:.2} ({}), {:.0} MiB |",
            z.dofs,
            z.elements,
            z.contact_rows,
            z.mesh_s,
            z.problem_s,
            z.reassembly_s,
            it.total_s(),
            it.setup_s,
            it.solve_s,
            it.iterations,
            it.peak_mib
        );
    }
    let names = solver_names(bench);
    s.push_str("\n| DOFs |");
    for n in &names {
        let _ = write!(s, " {n}: total (ratios), iterations, KKT, peak |");
    }
    for n in &names {
        let _ = write!(s, " elastic scene, {n} (ratio) |");
    }
    s.push_str("\n|---:|");
    for _ in 0..2 * names.len() {
        s.push_str("---|");
    }
    s.push('\n');
    for z in &bench.sizes {
        let _ = write!(s, "| {} |", z.dofs);
        for variant in ["scene", "elastic"] {
            for n in &names {
                let cell = match z.runs.iter().find(|r| r.variant == variant && &r.solver == n) {
                    None => "skipped".to_string(),
                    Some(r) if r.error.is_some() => format!("error: {}", r.error.as_deref().unwrap_or_default()),
                    Some(r) if variant == "elastic" => {
                        format!("{:.2} s ({:.2}×)", r.total_s, r.total_s / z.own_baseline_s(n))
                    }
                    Some(r) => format!(
                        "{:.1} s ({}), {} it, {:.0e}{}, {:.0} MiB",
                        r.total_s,
                        ratios(r.total_s, z),
                        r.iterations,
                        r.kkt,
                        if r.converged { "" } else { " NOT CONVERGED" },
                        r.peak_mib
                    ),
                };
                let _ = write!(s, " {cell} |");
            }
        }
        s.push('\n');
    }
    s.push('\n');
    for (name, pts) in scaling_series(bench) {
        if pts.len() >= 2 {
            let _ = writeln!(s, "* {name}: time against DOFs from {:.0} to {:.0}", pts[0].0, pts[pts.len() - 1].0);
        }
    }
    s
}
