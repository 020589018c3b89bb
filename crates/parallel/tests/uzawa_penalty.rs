//! Uzawa and the penalty method on the scene matrix of issue 24 ([`scene_matrix`]) distributed
//! over the ranks of `mpirun -n N` agree with the same solver on one process, which every rank
//! also runs (theory §12.4).

mod scene_matrix;

use saddle_parallel::saddle_mpi::Petsc;
use saddle_solvers::{Penalty, Uzawa};

fn main() {
    let session = Petsc::initialize().unwrap();
    scene_matrix::agree_with_serial(&session, &Uzawa::default());
    scene_matrix::agree_with_serial(&session, &Penalty::default());
}
