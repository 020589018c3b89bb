//! Every solver on general contact rows (theory §8): the same elasto-plastic punch problem
//! written in a rotated frame. Rotating the body by Q turns the punch's rows `u₃ + φ − U ≥ 0`
//! into rows `(Q e₃)·u + φ − U ≥ 0` that act on all three dofs of their node; isotropic
//! elasticity and von Mises plasticity are invariant, so the rotated discrete problem is the
//! axis-aligned one in other coordinates and U, Σλ, J and the plastic set must come out the
//! same — an exact answer that a wrong change of basis or a wrong general-row step cannot meet.

use saddle_contact::zone::candidate_nodes;
use saddle_core::P1P0Element;
use saddle_core::error::ParameterError;
use saddle_core::{
    AdmissibleDisplacements, BoxMesh, ConstraintRows, ContactReport, Dirichlet, DiscreteProblem, DofMap, Elasticity,
    Region, SceneError, Solution, Solver, TetMesh, contact_set,
};
use saddle_solvers::{LinearSolver, Newton, Penalty, Uzawa};
use saddle_yield::VonMises;
use serde::{Deserialize, Serialize};

/// The paraboloid punch of radius `r` pushed by `f` along `q e₃`, on the rotated bottom face:
/// rows `(Q e₃)·u_i + φ(Qᵀx_i) − U ≥ 0`.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct RotatedPunch {
    q: [[f64; 3]; 3],
    r: f64,
    f: f64,
}

impl RotatedPunch {
    fn normal(&self) -> [f64; 3] {
        [self.q[0][2], self.q[1][2], self.q[2][2]]
    }
    /// φ at the unrotated position Qᵀx.
    fn phi(&self, x: [f64; 3]) -> f64 {
        let xh: Vec<f64> = (0..2).map(|k| (0..3).map(|i| self.q[i][k] * x[i]).sum()).collect();
        (xh[0] * xh[0] + xh[1] * xh[1]) / (2.0 * self.r)
    }
}

#[typetag::serde(name = "test_rotated_punch")]
impl AdmissibleDisplacements for RotatedPunch {
    fn validate(&self, _: &str) -> Result<(), ParameterError> {
        Ok(())
    }
    fn extra_names(&self) -> Vec<String> {
        vec!["U".into()]
    }
    fn load(&self) -> Vec<f64> {
        vec![self.f]
    }
    fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError> {
        let zone = candidate_nodes(&Region::Group("zmin".into()), mesh, dofs, path)?;
        let mut rows = ConstraintRows::new(1);
        let nrm = self.normal();
        for &n in &zone.nodes {
            let entries: Vec<(usize, f64)> = (0..3).filter_map(|k| dofs.free(n, k).map(|j| (j, nrm[k]))).collect();
            rows.push(&entries, &[-1.0], self.phi(mesh.nodes[n]), n);
        }
        Ok(rows)
    }
    fn gap(&self, mesh: &TetMesh, dofs: &DofMap, rows: &ConstraintRows, u: &[f64], v: &[f64], out: &mut [f64]) {
        let nrm = self.normal();
        for (g, &n) in out.iter_mut().zip(&rows.node) {
            let un: f64 = (0..3).map(|k| dofs.free(n, k).map_or(0.0, |j| u[j]) * nrm[k]).sum();
            *g = un + self.phi(mesh.nodes[n]) - v[0];
        }
    }
    fn report(&self, _: &TetMesh, _: &ConstraintRows, extras: &[f64], lambda: &[f64]) -> ContactReport {
        ContactReport {
            quantities: vec![("U".into(), extras[0]), ("force".into(), lambda.iter().sum())],
            contact_nodes: contact_set(lambda).len(),
            ..Default::default()
        }
    }
}

/// Q = R_x(25°) R_y(−40°): no axis stays an axis.
fn rotation() -> [[f64; 3]; 3] {
    let (a, b) = (25f64.to_radians(), (-40f64).to_radians());
    let rx = [[1.0, 0.0, 0.0], [0.0, a.cos(), -a.sin()], [0.0, a.sin(), a.cos()]];
    let ry = [[b.cos(), 0.0, b.sin()], [0.0, 1.0, 0.0], [-b.sin(), 0.0, b.cos()]];
    let mut q = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            q[i][j] = (0..3).map(|k| rx[i][k] * ry[k][j]).sum();
        }
    }
    q
}

/// The punch scene on (−1,1)²×(0,1) with 8×8×4 cells, clamped except on the bottom face, von
/// Mises k₀ = 1, h = 5, E = 100, ν = 0.3, F = 0.3, R = 5; rotated by `q` (identity: the
/// axis-aligned problem).
fn scene(q: [[f64; 3]; 3]) -> DiscreteProblem {
    let mut mesh = BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], [8, 8, 4]).graded([0.0; 3], 2.0).mesh().unwrap();
    for x in &mut mesh.nodes {
        *x = [0, 1, 2].map(|i| (0..3).map(|k| q[i][k] * x[k]).sum());
    }
    let clamped = Dirichlet::clamped(Region::Not(Box::new(Region::Group("zmin".into()))));
    let p = VonMises::new(1.0, 5.0).unwrap();
    DiscreteProblem::new(
        Box::new(P1P0Element::new(mesh, &[clamped]).unwrap()),
        Elasticity::new(100.0, 0.3).unwrap(),
        Some(Box::new(p)),
        saddle_core::Obstacles::one(Box::new(RotatedPunch { q, r: 5.0, f: 0.3 })),
        &[],
    )
    .unwrap()
}

const IDENTITY: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

fn solve(s: &dyn Solver, l: &DiscreteProblem) -> Solution {
    let sol = s.solve(&l.lagrangian(), &mut saddle_core::Silent).unwrap_or_else(|e| panic!("{}: {e}", s.name()));
    assert!(sol.report.converged, "{}: {:?}", s.name(), sol.report.stop_reason);
    sol
}

#[test]
fn every_solver_solves_the_rotated_punch_as_the_axis_aligned_one() {
    let reference = solve(&Newton { tol: 1e-12, ..Newton::default() }, &scene(IDENTITY));
    let (u_ref, plastic_ref) = (reference.extras[0], reference.stress.n_plastic());
    assert!(plastic_ref > 0, "the scene must be plastic to test the tangent");
    let l = scene(rotation());
    // every row acts on three dofs
    assert!((0..l.lagrangian().data.rows.n_rows()).all(|i| l.lagrangian().data.rows.row(i).0.len() == 3));
    let solvers: Vec<(Box<dyn Solver>, f64)> = vec![
        (Box::new(Newton { tol: 1e-11, linear: LinearSolver::Direct, ..Newton::default() }), 1e-9),
        (Box::new(Newton { tol: 1e-11, linear: LinearSolver::Amg, ..Newton::default() }), 1e-9),
        (Box::new(Penalty::default()), 1e-9),
        (Box::new(Uzawa { tol: 1e-10, ..Uzawa::default() }), 1e-7),
        #[cfg(feature = "socp")]
        (Box::new(saddle_solvers::Socp::default()), 1e-9),
    ];
    for (s, tol) in solvers {
        let sol = solve(s.as_ref(), &l);
        let u = sol.extras[0];
        let force: f64 = sol.lambda.iter().sum();
        println!("{:>8}: U = {u:.15e} (axis-aligned {u_ref:.15e}), Σλ = {force:.12e}", s.name());
        assert!((u - u_ref).abs() <= tol * u_ref, "{}: U = {u} vs {u_ref}", s.name());
        assert!((force - 0.3).abs() <= 1e-9 * 0.3, "{}: Σλ = {force}", s.name());
        assert_eq!(sol.stress.n_plastic(), plastic_ref, "{}: plastic elements", s.name());
        assert_eq!(contact_set(&sol.lambda), contact_set(&reference.lambda), "{}: contact set", s.name());
    }
}

#[test]
fn newton_takes_as_many_steps_in_the_rotated_frame() {
    let newton = Newton { tol: 1e-10, linear: LinearSolver::Direct, ..Newton::default() };
    let a = solve(&newton, &scene(IDENTITY));
    let b = solve(&newton, &scene(rotation()));
    assert!(b.report.iterations <= a.report.iterations + 1, "{} vs {}", b.report.iterations, a.report.iterations);
}
