//! The sparse change of basis of recombined contact rows (theory §8.1, §10.1): P2's dual
//! quadratic rows, whose edge rows act on three nodes, solved by the active-set solvers through
//! T = T_D T_C, against the dense change of basis of the same rows (a small zone, one connected
//! block of at most 48 dofs) and against the solvers that take the rows as they are.

use saddle_contact::{Paraboloid, RigidPunch};
use saddle_core::fem::dual_quadratic::ContactRows;
use saddle_core::{BoxMesh, Data, Dirichlet, DiscreteProblem, Elasticity, P2Element, Region, Silent, Solution, Solver};
use saddle_solvers::{Newton, Penalty, Uzawa};
use saddle_yield::VonMises;

/// The default scene (theory §6) on `cells` with P2 and the dual quadratic rows: clamped off
/// the bottom square |x₁|, |x₂| < 0.75, von Mises k₀ = 1, h = 5, E = 100, ν = 0.3, a paraboloid
/// punch R = 5 pushed by F = 0.3 on the zone of radius `zone`.
fn scene(cells: [usize; 3], zone: f64) -> DiscreteProblem {
    let zone = Region::All(vec![Region::Group("zmin".into()), Region::Disc { center: [0.0, 0.0], radius: zone }]);
    with_obstacle(cells, Box::new(RigidPunch::new(0.3, zone, Box::new(Paraboloid::new(5.0))).unwrap()))
}

/// [`scene`] with the obstacle `k`.
fn with_obstacle(cells: [usize; 3], k: Box<dyn saddle_core::AdmissibleDisplacements>) -> DiscreteProblem {
    let mesh = BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], cells).graded([0.0; 3], 4.0).mesh().unwrap();
    let gamma1 = Region::All(vec![
        Region::Group("zmin".into()),
        Region::Box { min: [-0.75, -0.75, -1.0], max: [0.75, 0.75, 1.0] },
    ]);
    let clamped = Dirichlet::clamped(Region::Not(Box::new(gamma1)));
    DiscreteProblem::new(
        Box::new(P2Element::new(mesh, &[clamped]).unwrap().with_contact_rows(ContactRows::DualQuadratic)),
        Elasticity::new(100.0, 0.3).unwrap(),
        Some(Box::new(VonMises::new(1.0, 5.0).unwrap())),
        saddle_core::Obstacles::one(k),
        &[],
    )
    .unwrap()
}

fn solve(s: &dyn Solver, l: &saddle_core::Lagrangian<'_>) -> Solution {
    let sol = s.solve(l, &mut Silent).unwrap_or_else(|e| panic!("{}: {e}", s.name()));
    assert!(sol.report.converged, "{}: {:?}", s.name(), sol.report.stop_reason);
    sol
}

fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, v| m.max(v.abs()))
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0, |m, (x, y)| m.max((x - y).abs()))
}

/// Newton on `p`'s recombined rows through the sparse basis and through the dense basis of the
/// same rows without their recombination (one block of at most 48 dofs): the same solution to
/// round-off.
fn sparse_against_dense(p: &DiscreteProblem) {
    let l = p.lagrangian();
    let rows = l.data.rows;
    let c = rows.combination.as_deref().expect("dual quadratic rows are recombined");
    let combined = (0..rows.n_rows()).filter(|&i| c.t[i].len() > 1).count();
    let block: std::collections::BTreeSet<usize> = (0..rows.n_rows()).flat_map(|i| rows.row(i).0.to_vec()).collect();
    println!("{} rows, {combined} recombined, one block of {} dofs", rows.n_rows(), block.len());
    assert!(combined > 0 && block.len() <= saddle_solvers::row_basis::MAX_BLOCK_DOFS);
    let mut plain = rows.clone();
    plain.combination = None;
    let dense_l = l.with_data(Data { rows: &plain, ..l.data });
    let basis = |rows| saddle_solvers::row_basis::RowBasis::new(rows, l.n_dofs(), l.pattern(), "newton").unwrap();
    let (bs, bd) = (basis(rows), basis(&plain));
    println!(
        "cond(T): sparse ≤ {:.3}, dense {:.3}; entries of TᵀKT: sparse {}, dense {}, K {}",
        bs.condition(),
        bd.condition(),
        bs.pattern(l.pattern()).nnz(),
        bd.pattern(l.pattern()).nnz(),
        l.pattern().nnz()
    );
    // the sparse TᵀKT keeps K's pattern (an edge node and its vertices share every element)
    assert_eq!(bs.pattern(l.pattern()).nnz(), l.pattern().nnz());
    let newton = Newton { tol: 1e-12, ..Newton::default() };
    let (sparse, dense) = (solve(&newton, &l), solve(&newton, &dense_l));
    assert!(sparse.stress.n_plastic() > 0, "the scene must be plastic");
    let scale = max_abs(&dense.lambda);
    let (du, dl) = (max_diff(&sparse.u, &dense.u) / max_abs(&dense.u), max_diff(&sparse.lambda, &dense.lambda) / scale);
    let dv = (sparse.extras[0] - dense.extras[0]).abs() / dense.extras[0].abs();
    println!("sparse against dense: u {du:.2e}, λ {dl:.2e}, V {dv:.2e} (relative)");
    // both solve the KKT system to a residual of 1e-12 through bases of condition < 10:
    // measured ≤ 1e-13 (0 for the punch, whose dense T⁻¹ = G̃ inverts to the same sparse T)
    assert!(du < 1e-10 && dl < 1e-10 && dv < 1e-10, "u {du:e}, λ {dl:e}, V {dv:e}");
}

#[test]
fn the_sparse_basis_gives_the_dense_basis_solution_on_a_small_zone() {
    // the punch: rows on u₃, 25 nodes
    sparse_against_dense(&scene([4, 4, 2], 0.55));
}

#[test]
fn newton_on_a_rigid_spheres_dual_rows_agrees_with_uzawa_and_socp() {
    // rows along normals that vary from node to node, on all three dofs of the 9 nodes of the
    // central cell's bottom facets: T = T_D (one block per node) times T_C. (The dense basis of
    // these rows, one block of 27 dofs, makes Newton's tangent fail to factorise: not pursued.)
    let sphere = saddle_contact::RigidSphere::pushed(
        [0.1, 0.1, -2.0],
        2.0,
        [0.0, 0.0, 1.0],
        0.05,
        Region::All(vec![Region::Group("zmin".into()), Region::Disc { center: [0.1, 0.1], radius: 0.15 }]),
    );
    let p = with_obstacle([4, 4, 2], Box::new(sphere));
    let l = p.lagrangian();
    assert!((0..l.n_rows()).all(|i| l.data.rows.row(i).0.len() >= 3));
    agree_with_uzawa_and_socp(&l);
}

/// Newton (and the penalty's Newton) on `l` against Uzawa and SOCP, which take the rows as
/// they are: U and λ̃ to 1e-8 (measured: below 1e-10).
fn agree_with_uzawa_and_socp(l: &saddle_core::Lagrangian<'_>) {
    let reference = solve(&Newton { tol: 1e-12, ..Newton::default() }, l);
    let solvers: Vec<Box<dyn Solver>> = vec![
        Box::new(Penalty::default()),
        Box::new(Uzawa { tol: 1e-11, ..Uzawa::default() }),
        #[cfg(feature = "socp")]
        Box::new(saddle_solvers::Socp::default()),
    ];
    for s in solvers {
        let sol = solve(s.as_ref(), l);
        let du = (sol.extras[0] - reference.extras[0]).abs() / reference.extras[0];
        let dl = max_diff(&sol.lambda, &reference.lambda) / max_abs(&reference.lambda);
        println!(
            "{:>8}: V = {:.12e} (newton {:.12e}), λ off by {dl:.2e}",
            s.name(),
            sol.extras[0],
            reference.extras[0]
        );
        assert!(du <= 1e-8 && dl <= 1e-8, "{}: V off by {du:e}, λ by {dl:e}", s.name());
    }
}

#[test]
fn newton_and_penalty_on_dual_rows_agree_with_uzawa_and_socp() {
    let p = scene([8, 8, 4], 0.5);
    let l = p.lagrangian();
    let reference = solve(&Newton { tol: 1e-12, ..Newton::default() }, &l);
    let force: f64 = reference.lambda.iter().sum();
    assert!((force - 0.3).abs() < 1e-10, "Σλ̃ = {force} (the resultant of the recombined rows is F)");
    // the areas ∫Ñ_j = Σ_k T_kj ∫N_k partition the contact face as the nodal ∫N_k do (Σ_j T_kj = 1),
    // and give the vertex rows the area the nodal ones lack (∫N_v = 0)
    let mesh = p.element.mesh();
    let (dual, nodal) = (
        saddle_contact::zone::row_areas(mesh, l.data.rows),
        saddle_contact::zone::row_areas(mesh, &l.data.rows.combination.as_ref().unwrap().nodal),
    );
    let (sd, sn) = (dual.iter().sum::<f64>(), nodal.iter().sum::<f64>());
    assert!((sd - sn).abs() < 1e-14 * sn, "Σ∫Ñ = {sd}, Σ∫N = {sn}");
    let positive = |a: &[f64]| a.iter().filter(|&&x| x > 0.0).count();
    println!("rows with area: dual {} of {}, nodal {}", positive(&dual), dual.len(), positive(&nodal));
    assert!(positive(&dual) > positive(&nodal));
    agree_with_uzawa_and_socp(&l);
}
