//! The obstacle plugin of `examples/rigid_cone.rs` — written for one machine, knowing nothing of
//! MPI — solved distributed under `mpirun -n N` (theory §12) by `newton`, against the serial
//! solve every rank also runs: V and J to 1e-8 relative, the force Σλ to 1e-8, the contact and
//! plastic counts exactly, the KKT residual recomputed over the ranks within the tolerance.
//! Run by `.ci/run-mpi-tests` at 2 ranks; alone as one rank.

#[path = "../examples/rigid_cone.rs"]
#[allow(dead_code)]
mod rigid_cone;

use saddle_core::{
    AdmissibleDisplacements, DiscreteProblem, Elasticity, Lagrangian, Obstacles, P1, P1P0Element, Silent, Solution,
    Solver, Workspace, energy, kkt,
};
use saddle_parallel::distribute;
use saddle_parallel::saddle_mpi::Petsc;
use saddle_solvers::Newton;
use saddle_yield::VonMises;

/// V, J, Σλ, contact rows, plastic points and the KKT residual, each over the ranks.
fn numbers(l: &Lagrangian<'_>, s: &Solution) -> (f64, f64, f64, usize, usize, f64) {
    let comm = l.comm();
    let lmax = comm.max(s.lambda.iter().copied().fold(0.0, f64::max));
    let contact = comm.sum_count(s.lambda.iter().filter(|&&x| x > 1e-8 * lmax).count());
    let j = energy(l, &s.u, &s.extras, &mut Workspace::new(l));
    let r = kkt(l, &s.iterate(), &mut Workspace::new(l)).max();
    (s.extras[0], j, comm.sum(s.lambda.iter().sum()), contact, comm.sum_count(s.stress.n_plastic()), r)
}

fn main() {
    let session = Petsc::initialize().unwrap();
    let newton = Newton { tol: 1e-10, ..Newton::default() };
    let (mesh, dirichlet, cone) = rigid_cone::problem([10, 10, 5]);
    let law = Elasticity::new(100.0, 0.3).unwrap();
    let stresses = || Some(Box::new(VonMises::new(1.0, 5.0).unwrap()) as Box<dyn saddle_core::AdmissibleStresses>);
    let obstacles = || Obstacles::one(Box::new(cone.clone()) as Box<dyn AdmissibleDisplacements>);
    let serial = DiscreteProblem::new(
        Box::new(P1P0Element::new(mesh.clone(), &dirichlet).unwrap()),
        law,
        stresses(),
        obstacles(),
        &[],
    )
    .unwrap();
    let sl = serial.lagrangian();
    let reference = numbers(&sl, &newton.solve(&sl, &mut Silent).unwrap());
    let rank = session.rank();
    let rp = distribute(
        &session,
        (rank == 0).then_some(mesh),
        &P1::default(),
        &dirichlet,
        law,
        stresses(),
        obstacles(),
        &[],
    )
    .unwrap();
    let dl = rp.problem.lagrangian();
    let sol = newton.solve(&dl, &mut Silent).unwrap();
    assert!(sol.report.converged);
    let d = numbers(&dl, &sol);
    if rank == 0 {
        println!(
            "{} ranks, rigid cone: (V, J, force, contact, plastic, KKT) {d:?}, serial {reference:?}",
            session.size()
        );
    }
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-8 * a.abs().max(b.abs());
    assert!(close(d.0, reference.0), "V {} vs {}", d.0, reference.0);
    assert!(close(d.1, reference.1), "J {} vs {}", d.1, reference.1);
    assert!(close(d.2, reference.2), "force {} vs {}", d.2, reference.2);
    assert_eq!((d.3, d.4), (reference.3, reference.4), "contact rows, plastic points");
    assert!(d.5 <= newton.tol, "KKT {}", d.5);
}
