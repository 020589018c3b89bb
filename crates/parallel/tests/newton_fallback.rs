//! Newton's fallback on the penalty method (theory §4.2.1) on a distributed problem: on the
//! perfectly plastic strip under a flat punch (P2, h = 0; `examples/strip_punch.toml` coarsened
//! to 16 × 1 × 8 cells, with the scene matrix's E = 100 and ten times the punch's travel, U =
//! 0.8: the stresses of E = 1000, U = 0.08, displacements ×10), Newton stalls and falls back on one process; distributed over the ranks
//! of `mpirun -n N` it falls back as often, and agrees with the serial run as the scene matrix's
//! scenes do ([`scene_matrix`]).

mod scene_matrix;

use saddle_core::P2;
use saddle_parallel::saddle_mpi::Petsc;
use saddle_solvers::Newton;
use saddle_yield::VonMises;
use scene_matrix::{Geometry, Scene, agree_with_serial_on, strip_punch};

fn main() {
    let session = Petsc::initialize().unwrap();
    let strip = Scene {
        name: "perfectly plastic P2 strip",
        geometry: Geometry::Strip([16, 1, 8]),
        element: Box::new(P2::default()),
        stresses: Box::new(VonMises::new(1.0, 0.0).unwrap()),
        obstacles: strip_punch(0.8),
        path: vec![],
    };
    let newton = Newton { tol: 1e-10, max_iter: 200, ..Newton::default() };
    let serial = agree_with_serial_on(&session, &newton, vec![strip]);
    // the scene needs the fallback
    let (fallbacks, plastic) = (serial[0][0].fallbacks, serial[0][0].plastic);
    assert!(fallbacks > 0, "the serial Newton did not fall back ({plastic} plastic points)");
}
