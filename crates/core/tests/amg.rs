//! The multigrid of `saddle_core::linalg` on the elastic stiffness of the P1–P0
//! discretisation: the rigid-body modes of L are its near-nullspace, PCG with it matches sparse
//! Cholesky in a bounded number of iterations, and a refreshed hierarchy takes new values.

use saddle_core::linalg::{
    AmgError, AmgParams, Csr, Jacobi, LowerCsc, NearNullSpace, Pcg, SmoothedAggregation, SparseCholesky,
};
use saddle_core::mesh::dofs::FIXED;
use saddle_core::problem::operators::RIGID_BODY_MODES;
use saddle_core::{BoxMesh, Dirichlet, Discretisation, Elasticity, ElementOperators, Material, P1P0Element, Region};

/// The elastic block of the default scene (graded, clamped but for the bottom square).
fn problem(cells: [usize; 3]) -> P1P0Element {
    let mesh = BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], cells)
        .graded([0.0; 3], 4.0)
        .aligned(0, &[-0.75, 0.75])
        .aligned(1, &[-0.75, 0.75])
        .mesh()
        .unwrap();
    let gamma1 = Region::All(vec![
        Region::Group("zmin".into()),
        Region::Box { min: [-0.75, -0.75, -1.0], max: [0.75, 0.75, 1.0] },
    ]);
    let clamp = Dirichlet::clamped(Region::Not(Box::new(gamma1)));
    P1P0Element::new(mesh, &[clamp]).unwrap()
}

fn stiffness(l: &P1P0Element) -> (Vec<f64>, Csr) {
    let c = Elasticity::new(100.0, 0.3).unwrap().stiffness_matrix();
    let v = l.stiffness(Material::Uniform(&c));
    let a = Csr::from_symmetric_lower(lower(l), &v);
    (v, a)
}

fn lower(l: &P1P0Element) -> LowerCsc<'_> {
    let p = l.pattern();
    LowerCsc::new(p.n(), p.col_ptr(), p.row_idx())
}

fn near_null(l: &P1P0Element) -> NearNullSpace {
    let m = l.rigid_body_modes().unwrap();
    NearNullSpace::new(m.node, m.modes, RIGID_BODY_MODES).unwrap()
}

/// A deterministic pseudo-random number in [−1, 1].
fn pseudo_random(i: usize) -> f64 {
    let x = (i as u64).wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    ((x >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

/// A load: a smooth body force plus a point-like push, so that all scales are present.
fn rhs(n: usize) -> Vec<f64> {
    (0..n).map(|i| if i % 3 == 2 { -1.0 } else { 0.3 * (i as f64 * 0.01).sin() } + 0.2 * pseudo_random(i)).collect()
}

#[test]
fn csr_from_the_assembled_stiffness_multiplies_like_the_pattern() {
    let l = problem([4, 4, 2]);
    let (v, a) = stiffness(&l);
    let x: Vec<f64> = (0..a.nrows).map(pseudo_random).collect();
    let (mut y1, mut y2) = (vec![0.0; a.nrows], vec![0.0; a.nrows]);
    l.pattern().matvec(&v, &x, &mut y1);
    a.spmv(&x, &mut y2);
    let scale = y1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(y1.iter().zip(&y2).all(|(p, q)| (p - q).abs() <= 1e-13 * scale));
    assert_eq!(a.diagonal(), l.pattern().diagonal(&v));
    // back to the lower triangle: the same pattern and values
    let (cp, ri, w) = a.to_symmetric_lower();
    assert_eq!((cp.as_slice(), ri.as_slice()), (l.pattern().col_ptr(), l.pattern().row_idx()));
    assert_eq!(w, v);
}

#[test]
fn rigid_body_modes_are_in_the_kernel_away_from_the_dirichlet_boundary() {
    let l = problem([4, 4, 4]);
    let (_, a) = stiffness(&l);
    let modes = l.rigid_body_modes().unwrap();
    let b = &modes.modes;
    // nodes none of whose elements touches a fixed component
    let dofs = l.dofs();
    let mut near_fixed = vec![false; dofs.n_nodes()];
    for t in &l.mesh().tets {
        if t.iter().any(|&n| dofs.dof[n].contains(&FIXED)) {
            t.iter().for_each(|&n| near_fixed[n] = true);
        }
    }
    let n = a.nrows;
    let norm_a = a.val.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut interior = 0;
    for k in 0..RIGID_BODY_MODES {
        let col: Vec<f64> = (0..n).map(|d| b[d * RIGID_BODY_MODES + k]).collect();
        let mut y = vec![0.0; n];
        a.spmv(&col, &mut y);
        let size = col.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut boundary_max = 0.0f64;
        for d in 0..n {
            if near_fixed[modes.node[d] as usize] {
                boundary_max = boundary_max.max(y[d].abs());
            } else {
                interior += 1;
                assert!(y[d].abs() <= 1e-12 * norm_a * size, "mode {k}, dof {d}: {}", y[d]);
            }
        }
        // and the modes are not trivially in the kernel: the Dirichlet condition shows
        assert!(boundary_max > 1e-3 * norm_a * size, "mode {k}");
    }
    assert!(interior > 0);
}

/// PCG with AMG and with Jacobi on the default scene's elastic stiffness, compared with
/// sparse Cholesky. Returns the AMG iteration count.
fn solve_and_compare(cells: [usize; 3]) -> usize {
    let l = problem(cells);
    let (v, a) = stiffness(&l);
    let n = a.nrows;
    let b = rhs(n);
    // a small coarse size, so that even the small meshes have three levels or more
    let params = AmgParams { coarse_size: 50, ..AmgParams::default() };
    let amg = SmoothedAggregation::new(&a, &near_null(&l), &params).unwrap();
    assert!(amg.level_info().len() >= if n > 1000 { 3 } else { 2 }, "{:?}", amg.level_info());
    let mut pcg = Pcg::new(n);
    let mut x = vec![0.0; n];
    let rep = pcg.solve(&a, &amg, &b, &mut x, 1e-8, 200).unwrap();
    assert!(rep.converged && rep.relative_residual <= 1e-8, "{rep:?}");
    let mut chol = SparseCholesky::analyse(lower(&l), "test").unwrap();
    chol.factorise(&v).unwrap();
    let mut x_direct = b.clone();
    chol.solve(&mut x_direct);
    let err = x.iter().zip(&x_direct).map(|(p, q)| (p - q) * (p - q)).sum::<f64>().sqrt()
        / x_direct.iter().map(|q| q * q).sum::<f64>().sqrt();
    let mut y = vec![0.0; n];
    let jac = pcg.solve(&a, &Jacobi::new(&a).unwrap(), &b, &mut y, 1e-8, 5000).unwrap();
    println!(
        "cells {cells:?}: {n} dofs, levels {:?}, operator complexity {:.2}; AMG-PCG {} iterations \
         (residual {:.1e}, error vs Cholesky {err:.1e}); Jacobi-PCG {} iterations",
        amg.level_info().iter().map(|i| i.n).collect::<Vec<_>>(),
        amg.operator_complexity(),
        rep.iterations,
        rep.relative_residual,
        jac.iterations,
    );
    assert!(jac.converged);
    assert!(err < 1e-7, "relative error {err:e} against Cholesky");
    assert!(rep.iterations * 3 < jac.iterations, "AMG {} vs Jacobi {}", rep.iterations, jac.iterations);
    rep.iterations
}

#[test]
fn amg_pcg_matches_cholesky_with_bounded_iterations_under_refinement() {
    let coarse = solve_and_compare([8, 8, 4]);
    let fine = solve_and_compare([16, 16, 8]);
    assert!(fine <= 40, "{fine} iterations on the fine mesh");
    assert!(fine <= coarse + 8, "iterations grow from {coarse} to {fine}");
}

#[test]
fn refresh_takes_new_values_on_the_same_hierarchy() {
    let l = problem([8, 8, 4]);
    let (_, a) = stiffness(&l);
    let n = a.nrows;
    let b = rhs(n);
    let params = AmgParams { coarse_size: 100, ..AmgParams::default() };
    let mut amg = SmoothedAggregation::new(&a, &near_null(&l), &params).unwrap();
    let mut pcg = Pcg::new(n);
    // a softer material (E/10 with ν = 0.45: nearly incompressible) on the same pattern
    let soft = Elasticity::new(10.0, 0.45).unwrap().stiffness_matrix();
    let a2 = Csr::from_symmetric_lower(lower(&l), &l.stiffness(Material::Uniform(&soft)));
    amg.refresh(&a2).unwrap();
    let mut x = vec![0.0; n];
    let rep = pcg.solve(&a2, &amg, &b, &mut x, 1e-8, 200).unwrap();
    assert!(rep.converged, "{rep:?}");
    let mut r = vec![0.0; n];
    a2.residual(&b, &x, &mut r);
    let rel = r.iter().map(|v| v * v).sum::<f64>().sqrt() / b.iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!(rel <= 1e-8, "{rel}");
    // the old hierarchy on the new matrix would be a poor (but SPD) preconditioner; a wrong
    // size is an error
    let e = amg.refresh(&Csr { nrows: 3, ncols: 3, ptr: vec![0; 4], idx: vec![], val: vec![] }).unwrap_err();
    assert!(matches!(e, AmgError::DimensionMismatch { .. }), "{e}");
}
