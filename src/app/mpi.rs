//! `saddle run` under `mpirun` (feature `mpi`, theory §12): the scene read on rank 0 and shared,
//! the mesh read or built on rank 0 and distributed over the ranks ([`saddle_parallel::distribute`]:
//! METIS, a ghost layer), each rank's part solved by a solver that runs distributed (`newton`),
//! and the output written as on one machine — `summary.json` once, by rank 0, with the same keys
//! and global counts plus `ranks` and `per_rank`; the solution as `solution.pvtu` with one piece
//! per rank (`solution_rNNNN.vtu`); a load path's steps as `solution_NNNN.pvtu` in
//! `solution.pvd`. An error on any rank ends every rank with its message ([`Ranks::agree`]).

use super::ranks::{Ranks, write_in_place};
use super::setup::{Loaded, RunError, solver_by_type};
use crate::io::outdir::{OutDir, OutError};
use crate::io::scene::{Scene, default_element, element_by_type};
use crate::io::summary::{RankSummary, Summary, Whole, complete_reports, imprints};
use crate::io::vtu::{CellField, write_piece, write_pvtu};
use saddle_core::problem::comm::Comm;
use saddle_core::{ParameterError, PhaseTimer, ProblemView, SceneError, Solution, Solver};
use saddle_parallel::distribute::{RankProblem, Whole as WholeProblem, whole_rows};
use saddle_parallel::saddle_mpi::{self, Petsc};
use saddle_parallel::{MpiComm, distribute};
use std::path::Path;

/// True when this process was started by an MPI launcher (`mpirun`, `mpiexec`, `srun`): OpenMPI,
/// MPICH/Hydra and PMIx say so in the environment.
pub fn launched_by_mpirun() -> bool {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"].iter().any(|v| std::env::var_os(v).is_some())
}

/// The program's arguments split into saddle's and PETSc's (the program name first in both):
/// PETSc's are the words of a single dash and at least two letters (`-ksp_view`, `-log_view`,
/// `-ksp_monitor`, `-pc_type hypre`), each with the next word as its value when that word does
/// not begin with `-` and is not a scene file (`.toml`), and every word after `--`.
pub fn split_petsc_args(args: Vec<String>) -> (Vec<String>, Vec<String>) {
    let mut args = args.into_iter();
    let program = args.next().unwrap_or_else(|| "saddle".into());
    let (mut ours, mut petsc) = (vec![program.clone()], vec![program]);
    let is_petsc = |a: &str| {
        a.len() > 2
            && a.starts_with('-')
            && !a.starts_with("--")
            && a[1..].starts_with(|c: char| c.is_ascii_alphabetic())
    };
    let mut rest = args.peekable();
    while let Some(a) = rest.next() {
        if a == "--" {
            petsc.extend(rest.by_ref());
        } else if is_petsc(&a) {
            petsc.push(a);
            if let Some(v) = rest.next_if(|v| !v.starts_with('-') && !v.ends_with(".toml")) {
                petsc.push(v);
            }
        } else {
            ours.push(a);
        }
    }
    (ours, petsc)
}

/// The problem over the ranks: the reductions, where this rank's rows sit among the whole
/// problem's, what rank 0 keeps of the whole problem for the reports, and this rank's share.
pub struct MpiRanks {
    comm: MpiComm,
    global_rows: Vec<usize>,
    /// The whole problem's rows.
    n_rows: usize,
    whole: Option<WholeProblem>,
    share: RankSummary,
}

impl Ranks for MpiRanks {
    fn size(&self) -> usize {
        self.comm.size()
    }

    fn is_root(&self) -> bool {
        self.comm.rank() == 0
    }

    /// The root claims the folder; the others follow it (the caller's [`RunError::agree`] is
    /// the barrier after which they write into it).
    fn claim(&self, dir: &Path) -> Result<OutDir, OutError> {
        if self.is_root() { OutDir::claim(dir) } else { Ok(OutDir::follow(dir)) }
    }

    /// The counts, sums and maxima over the ranks ([`Summary::of_whole`]); the obstacles report on
    /// rank 0 from the whole problem's rows and multipliers, through the step's obstacles (their
    /// load is the step's).
    fn summary(&self, view: ProblemView<'_>, sol: &Solution, title: Option<String>) -> Summary {
        let imprints = imprints(view, &sol.u);
        let lambda = whole_rows(&self.comm, &self.global_rows, self.n_rows, &sol.lambda);
        let whole = match &self.whole {
            Some(w) => {
                let mut reports = w.obstacles.reports_of(view.obstacles.obstacles(), &w.mesh, &sol.extras, &lambda);
                complete_reports(view, &mut reports, &imprints, &sol.undetermined);
                Whole { reports, quality: w.quality, nodes: w.totals.nodes }
            }
            None => Whole { reports: Vec::new(), quality: view.element.mesh().quality(), nodes: 0 },
        };
        Summary::of_whole(view, sol, title, whole)
    }

    /// Each rank's piece `<stem>_rNNNN.vtu`; rank 0 also `<stem>.pvtu`, which lists them.
    fn write_solution(
        &self,
        dir: &Path,
        stem: &str,
        view: ProblemView<'_>,
        sol: &Solution,
        cells: &[CellField<'_>],
    ) -> std::io::Result<Vec<String>> {
        let piece = |r: usize| format!("{stem}_r{r:04}.vtu");
        let mut declarations = String::new();
        write_in_place(dir, &piece(self.comm.rank()), |p| write_piece(p, view, sol, cells).map(|d| declarations = d))?;
        if !self.is_root() {
            return Ok(vec![piece(self.comm.rank())]);
        }
        let pieces: Vec<String> = (0..self.size()).map(piece).collect();
        let pvtu = format!("{stem}.pvtu");
        write_in_place(dir, &pvtu, |p| write_pvtu(p, &declarations, &pieces))?;
        Ok(std::iter::once(pvtu).chain(pieces).collect())
    }

    fn agree(&self, result: Result<(), String>) -> Result<(), String> {
        saddle_mpi::agree(self.comm.world(), result).map_err(|e| match e {
            saddle_mpi::Error::Rank { rank, message, .. } if rank != self.comm.rank() => {
                format!("rank {rank}: {message}")
            }
            saddle_mpi::Error::Rank { message, .. } => message,
            other => other.to_string(),
        })
    }

    /// `ranks`, and `per_rank`: every rank's part, its `end_to_end` time and solve time, and its
    /// peak memory, gathered by sums of vectors with one slot per rank.
    fn describe(&self, summary: &mut Summary) {
        const FIELDS: usize = 6;
        let (rank, size) = (self.comm.rank(), self.size());
        let s = &self.share;
        let mine = [
            s.elements as f64,
            s.owned_dofs as f64,
            s.ghost_nodes as f64,
            summary.end_to_end_s,
            summary.end_to_end.get("solve").copied().unwrap_or_default(),
            peak_memory_mb(),
        ];
        let mut all = vec![0.0; FIELDS * size];
        all[FIELDS * rank..FIELDS * (rank + 1)].copy_from_slice(&mine);
        self.comm.sum_in_place(&mut all);
        summary.ranks = Some(size);
        summary.per_rank = all
            .chunks(FIELDS)
            .enumerate()
            .map(|(rank, v)| RankSummary {
                rank,
                elements: v[0] as usize,
                owned_dofs: v[1] as usize,
                ghost_nodes: v[2] as usize,
                wall_s: v[3],
                solve_s: v[4],
                peak_memory_mb: v[5],
            })
            .collect();
    }
}

/// This process's peak resident memory in MB (`VmHWM` of `/proc/self/status`; 0 where there is
/// none).
pub fn peak_memory_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(0.0, |kb| kb / 1024.0)
}

/// The solver of a distributed run: the override, the scene's, or `newton` (the solver that runs
/// distributed) when neither names one. A solver that runs on one rank only is refused before
/// any work when there are several ranks.
fn solver(scene: &Scene, solver_override: Option<&str>, ranks: usize) -> Result<Box<dyn Solver>, RunError> {
    let solver = match solver_override {
        Some(name) => solver_by_type(name)?,
        None => scene.solver.clone().unwrap_or_else(|| Box::new(saddle_solvers::Newton::default())),
    };
    if ranks > 1 && !solver.runs_distributed() {
        return Err(RunError::Solve(saddle_core::SolveError::Unsupported {
            solver: solver.name().to_string(),
            message: format!(
                "runs on one rank only, and this run has {ranks} ranks: use `newton` (`--solver newton` or \
                 `[solver] type = \"newton\"`), or run without mpirun"
            ),
        }));
    }
    Ok(solver)
}

/// Reads a scene under `mpirun` and distributes its problem (module docs): the scene file read by
/// rank 0 and parsed by every rank (so that every rank holds the same plugins), `--discretisation`
/// and `--cells` applied, the mesh read or built by rank 0 only, PETSc's options of `[solver.petsc]` inserted,
/// then [`distribute`]. Every stage's error is every rank's. Collective.
pub fn load(
    session: &Petsc,
    scene_path: &Path,
    solver_override: Option<&str>,
    (discretisation, cells): (Option<&str>, Option<[usize; 3]>),
) -> Result<Loaded, RunError> {
    let mut ranks = MpiRanks {
        comm: MpiComm::new(session),
        global_rows: Vec::new(),
        n_rows: 0,
        whole: None,
        share: RankSummary::default(),
    };
    let root = ranks.is_root();
    let mut timer = PhaseTimer::default();
    // the scene's text, read by rank 0 and sent to every rank
    let text = if root {
        std::fs::read(scene_path).map_err(|source| SceneError::Io { path: scene_path.to_path_buf(), source }.into())
    } else {
        Ok(Vec::new())
    };
    let mut text = RunError::agree(&ranks, text)?;
    saddle_mpi::broadcast_bytes(ranks.comm.world(), 0, &mut text);
    let read = timer.time("read", || -> Result<_, RunError> {
        let text = String::from_utf8(text)
            .map_err(|e| SceneError::Parse { path: scene_path.to_path_buf(), message: e.to_string() })?;
        let mut scene = Scene::from_toml(&text, scene_path)?;
        scene.base_dir = scene_path.parent().map(Path::to_path_buf).unwrap_or_default();
        if let Some(name) = discretisation {
            scene = scene.with_element(element_by_type(name)?);
        }
        if let Some(c) = cells {
            scene = scene.with_cells(c)?;
        }
        let mesh = if root { Some(scene.build_mesh()?) } else { None };
        Ok((scene, mesh))
    });
    let (scene, mesh) = RunError::agree(&ranks, read)?;
    let solver = RunError::agree(&ranks, solver(&scene, solver_override, ranks.size()))?;
    if let Some(options) = &scene.petsc_options {
        let inserted = session.insert_options(options).map_err(|e| {
            let message = format!("PETSc refused them: {e}");
            SceneError::from(ParameterError::new("solver.petsc.options", format!("{options:?}"), &message)).into()
        });
        RunError::agree(&ranks, inserted)?;
    }
    let element = scene.discretisation.clone().unwrap_or_else(default_element);
    let rp = timer.time("setup", || {
        distribute(
            session,
            mesh,
            element.as_ref(),
            &scene.dirichlet,
            scene.material,
            scene.yield_surface.clone(),
            scene.obstacle.clone(),
            &scene.load,
        )
    });
    let rp = RunError::agree(&ranks, rp.map_err(RunError::from))?;
    let RankProblem { problem, global_rows, elements, owned_nodes, whole, totals, .. } = rp;
    ranks.share = RankSummary {
        rank: ranks.comm.rank(),
        elements: elements.len(),
        owned_dofs: problem.lagrangian().n_dofs(),
        ghost_nodes: problem.element.mesh().n_nodes() - owned_nodes,
        ..RankSummary::default()
    };
    ranks.global_rows = global_rows;
    ranks.n_rows = totals.rows;
    ranks.whole = whole;
    Ok(Loaded {
        problem,
        solver,
        title: scene.title.clone(),
        load_path: scene.load_path.clone(),
        timer,
        ranks: Box::new(ranks),
        output: scene.output.clone(),
    })
}
