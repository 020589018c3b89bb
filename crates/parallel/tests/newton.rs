//! Newton on the small default scene (theory §6) distributed over the ranks of `mpirun -n N`
//! agrees with the serial solve every rank also runs: U and J to 1e-8 relative, the contact and
//! plastic counts exactly, the KKT residual (recomputed globally) within the tolerance.

use saddle_contact::{Paraboloid, RigidPunch};
use saddle_core::problem::comm::Comm;
use saddle_core::{
    BoxMesh, Dirichlet, DiscreteProblem, Elasticity, Obstacles, P1, P1P0Element, Region, Silent, Solution, Solver,
    TetMesh, Workspace, kkt,
};
use saddle_parallel::distribute;
use saddle_parallel::saddle_mpi::Petsc;
use saddle_solvers::Newton;
use saddle_yield::VonMises;

fn mesh() -> TetMesh {
    BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], [12, 12, 6])
        .graded([0.0; 3], 3.0)
        .aligned(0, &[-0.75, 0.75])
        .aligned(1, &[-0.75, 0.75])
        .mesh()
        .unwrap()
}

fn dirichlet() -> Vec<Dirichlet> {
    let gamma1 = Region::All(vec![
        Region::Group("zmin".into()),
        Region::Box { min: [-0.75, -0.75, -1.0], max: [0.75, 0.75, 1.0] },
    ]);
    vec![Dirichlet::clamped(Region::Not(Box::new(gamma1)))]
}

fn obstacles() -> Obstacles {
    let zone = Region::All(vec![Region::Group("zmin".into()), Region::Disc { center: [0.0, 0.0], radius: 0.5 }]);
    Obstacles::one(Box::new(RigidPunch::new(0.3, zone, Box::new(Paraboloid::new(5.0))).unwrap()))
}

fn law() -> Elasticity {
    Elasticity::new(100.0, 0.3).unwrap()
}

fn yield_surface() -> Option<Box<dyn saddle_core::AdmissibleStresses>> {
    Some(Box::new(VonMises::new(1.0, 5.0).unwrap()))
}

/// Contact rows: λ_i > 1e-8 max λ, max over every rank's rows.
fn contacts(comm: &dyn Comm, lambda: &[f64]) -> usize {
    let lmax = comm.max(lambda.iter().copied().fold(0.0, f64::max));
    comm.sum_count(lambda.iter().filter(|&&l| lmax > 0.0 && l > 1e-8 * lmax).count())
}

fn main() {
    let session = Petsc::initialize().unwrap();
    let newton = Newton { tol: 1e-10, ..Newton::default() };
    // the serial reference, on every rank
    let element = P1P0Element::new(mesh(), &dirichlet()).unwrap();
    let serial = DiscreteProblem::new(Box::new(element), law(), yield_surface(), obstacles(), &[]).unwrap();
    let reference: Solution = newton.solve(&serial.lagrangian(), &mut Silent).unwrap();
    // distributed
    let rank0_mesh = (session.rank() == 0).then(mesh);
    let rp = distribute(&session, rank0_mesh, &P1::default(), &dirichlet(), law(), yield_surface(), obstacles(), &[])
        .unwrap();
    let l = rp.problem.lagrangian();
    let sol = newton.solve(&l, &mut Silent).unwrap();
    let comm = l.comm();
    let recomputed = kkt(&l, &sol.iterate(), &mut Workspace::new(&l)).max();
    let (u, u_ref) = (sol.extras[0], reference.extras[0]);
    let j = saddle_core::energy(&l, &sol.u, &sol.extras, &mut Workspace::new(&l));
    let j_ref = saddle_core::energy(
        &serial.lagrangian(),
        &reference.u,
        &reference.extras,
        &mut Workspace::new(&serial.lagrangian()),
    );
    let plastic = comm.sum_count(sol.stress.n_plastic());
    let contact = contacts(comm, &sol.lambda);
    let contact_ref = contacts(&saddle_core::problem::comm::SERIAL, &reference.lambda);
    if comm.rank() == 0 {
        println!(
            "{} ranks: U {u:.15e} (serial {u_ref:.15e}, {:.1e}), J {j:.15e} ({:.1e}), plastic {plastic} ({}), contact \
             {contact} ({contact_ref}), KKT {recomputed:.1e}, {} iterations ({} serial)",
            comm.size(),
            (u - u_ref).abs() / u_ref,
            (j - j_ref).abs() / j_ref.abs(),
            reference.stress.n_plastic(),
            sol.report.iterations,
            reference.report.iterations
        );
    }
    assert!(sol.report.converged, "{:?}", sol.report.stop_reason);
    assert!(recomputed <= newton.tol, "recomputed KKT {recomputed:e}");
    assert!((u - u_ref).abs() <= 1e-8 * u_ref, "U {u} vs {u_ref}");
    assert!((j - j_ref).abs() <= 1e-8 * j_ref.abs(), "J {j} vs {j_ref}");
    assert_eq!(plastic, reference.stress.n_plastic(), "plastic points");
    assert_eq!(contact, contact_ref, "contact rows");
}
