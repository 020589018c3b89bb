//! Where a run's problem lives (theory §12): on this process alone ([`OneMachine`]), or in parts
//! over the ranks of `mpirun` (the feature `mpi`, [`super::mpi`]). A command ([`super::run`],
//! [`super::path`]) runs the same stages on every rank and asks its [`Ranks`] for what differs:
//! who writes the shared files, the summary of the parts, the solution's files, and whether every
//! rank got through a stage.

use crate::io::outdir::{OutDir, OutError};
use crate::io::summary::Summary;
use crate::io::vtu::{CellField, write_piece};
use saddle_core::{ProblemView, Solution};
use std::path::Path;

/// What a command asks of where its problem lives (module docs). Every method marked collective
/// is called by every rank in the same order.
pub trait Ranks {
    /// The number of ranks (1 on one machine).
    fn size(&self) -> usize {
        1
    }

    /// True on the rank that writes the shared files (`summary.json`, `load_path.csv`, the
    /// series, the plots, the folder's manifest): rank 0.
    fn is_root(&self) -> bool {
        true
    }

    /// Claims the output folder ([`OutDir::claim`]) on the root; the other ranks follow it once
    /// the root has claimed it ([`OutDir::follow`]). Collective.
    fn claim(&self, dir: &Path) -> Result<OutDir, OutError> {
        OutDir::claim(dir)
    }

    /// The summary of a solution of the (rank's part of the) problem. Collective.
    fn summary(&self, view: ProblemView<'_>, sol: &Solution, title: Option<String>) -> Summary {
        Summary::new(view, sol, title)
    }

    /// Writes the solution as `<stem>.vtu` (one machine) or `<stem>.pvtu` with a piece per rank
    /// (each rank writes its own): the files' names, the one a series names first; on the root
    /// every rank's files, so that the manifest lists them. Each file is written under a
    /// temporary name and then moved into place; `cells` are further cell fields (one value per
    /// element of the rank's part). Collective.
    fn write_solution(
        &self,
        dir: &Path,
        stem: &str,
        view: ProblemView<'_>,
        sol: &Solution,
        cells: &[CellField<'_>],
    ) -> std::io::Result<Vec<String>> {
        let name = format!("{stem}.vtu");
        write_in_place(dir, &name, |path| write_piece(path, view, sol, cells).map(drop))?;
        Ok(vec![name])
    }

    /// A stage's result on every rank: an error on any rank becomes an error on every rank
    /// (its message), so that all end together instead of waiting in the next collective.
    /// Collective.
    fn agree(&self, result: Result<(), String>) -> Result<(), String> {
        result
    }

    /// Adds what a summary says of the ranks (`ranks`, `per_rank`: each rank's `end_to_end`
    /// times, its part and its memory). Collective.
    fn describe(&self, summary: &mut Summary) {
        let _ = summary;
    }
}

/// The problem on this process alone: every method the trait's default.
#[derive(Clone, Copy, Debug, Default)]
pub struct OneMachine;

impl Ranks for OneMachine {}

/// Writes `dir/name` through `write` under a temporary name first, so that a failure leaves no
/// half-written file under the final name.
pub fn write_in_place(dir: &Path, name: &str, write: impl FnOnce(&Path) -> std::io::Result<()>) -> std::io::Result<()> {
    let tmp = dir.join(format!(".{name}.partial"));
    write(&tmp)?;
    std::fs::rename(&tmp, dir.join(name))
}
