//! Newton on the scene matrix of issue 24 ([`scene_matrix`]) distributed over the ranks of
//! `mpirun -n N` agrees with the serial Newton every rank also runs (theory §12).

mod scene_matrix;

use saddle_parallel::saddle_mpi::Petsc;
use saddle_solvers::Newton;

fn main() {
    let session = Petsc::initialize().unwrap();
    scene_matrix::agree_with_serial(&session, &Newton { tol: 1e-10, ..Newton::default() });
}
