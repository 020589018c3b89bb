//! Checks every element's operators must pass (theory §3), for the elements' unit tests: the
//! divergence is the transpose of the strain, the strain's entries reproduce it, and the
//! assembled stiffness is the operator BᵀCB with the energy ½uᵀKu = Σ|T| ½ε:Cε.

use crate::problem::elasticity::Elasticity;
use crate::problem::operators::{ElementOperators, Material};
use crate::problem::tensor::{Sym, SymOp};
use rand::{Rng, SeedableRng, rngs::StdRng};

/// A random displacement, uniform in [−1, 1) per dof.
fn random_u(l: &dyn ElementOperators, rng: &mut StdRng) -> Vec<f64> {
    (0..l.n_dofs()).map(|_| rng.random_range(-1.0..1.0)).collect()
}

/// Σ|T| ε(u):σ = (Bᵀσ)·u for random u and σ, to 1e-12 relative (round-off of the sums).
pub fn divergence_is_the_transpose_of_strain(l: &dyn ElementOperators) {
    let mut rng = StdRng::seed_from_u64(7);
    let u = random_u(l, &mut rng);
    let sigma: Vec<Sym> = (0..l.n_points()).map(|_| Sym::from_fn(|_, _| rng.random_range(-1.0..1.0))).collect();
    let mut eps = vec![Sym::zeros(); l.n_points()];
    l.strain(&u, &mut eps);
    let lhs: f64 = eps.iter().zip(&sigma).zip(l.weights()).map(|((e, s), w)| w * e.dot(s)).sum();
    let mut f = vec![0.0; l.n_dofs()];
    l.divergence(&sigma, &mut f);
    let rhs: f64 = f.iter().zip(&u).map(|(a, b)| a * b).sum();
    assert!((lhs - rhs).abs() < 1e-12 * lhs.abs().max(1.0), "{lhs} vs {rhs}");
}

/// The strain from `strain_entries` equals the operator's for a random u, to `tol` absolute.
pub fn strain_entries_reproduce_the_strain(l: &dyn ElementOperators, tol: f64) {
    let mut rng = StdRng::seed_from_u64(9);
    let u = random_u(l, &mut rng);
    let mut eps = vec![Sym::zeros(); l.n_points()];
    l.strain(&u, &mut eps);
    let mut from_entries = vec![Sym::zeros(); l.n_points()];
    for (p, c, j, v) in l.strain_entries() {
        from_entries[p][c] += v * u[j];
    }
    let err = eps.iter().zip(&from_entries).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
    assert!(err < tol, "{err}");
}

/// K u = Bᵀ(C B u) for a random u, against the matrix-free operator, and ½uᵀKu = Σ|T| ½ε:Cε,
/// both to 1e-12 relative (round-off of the assembly's sums).
pub fn assembled_stiffness_matches_the_operator(l: &dyn ElementOperators) {
    let c = Elasticity::new(10.0, 0.3).unwrap().stiffness_matrix();
    let values = l.stiffness(Material::Uniform(&c));
    let mut rng = StdRng::seed_from_u64(3);
    let u = random_u(l, &mut rng);
    let mut ku = vec![0.0; l.n_dofs()];
    l.pattern().matvec(&values, &u, &mut ku);
    let mut eps = vec![Sym::zeros(); l.n_points()];
    l.strain(&u, &mut eps);
    let sigma: Vec<Sym> = eps.iter().map(|e| c * e).collect();
    let mut f = vec![0.0; l.n_dofs()];
    l.divergence(&sigma, &mut f);
    let err = ku.iter().zip(&f).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    let scale = f.iter().map(|a| a.abs()).fold(0.0, f64::max);
    assert!(err < 1e-12 * scale, "{err} vs {scale}");
    let e1: f64 = 0.5 * ku.iter().zip(&u).map(|(a, b)| a * b).sum::<f64>();
    let e2: f64 = eps.iter().zip(l.weights()).map(|(e, w)| 0.5 * w * e.dot(&(c * e))).sum();
    assert!((e1 - e2).abs() < 1e-12 * e1);
}

/// `reassemble` from the elastic stiffness, with the matrices of a random third of the elements
/// (`points` per element) changed, twice (the elements changed the first time and elastic the
/// second test what the kept columns remember), equals `assemble` of the same material bit for
/// bit each time (a kept column that a changed element touches would miss its contribution).
pub fn reassembly_equals_the_assembly(l: &dyn ElementOperators, points: usize) {
    let c = Elasticity::new(10.0, 0.3).unwrap().stiffness_matrix();
    let mut rng = StdRng::seed_from_u64(5);
    let n_elements = l.n_points() / points;
    let (mut values, mut was_off) = (vec![0.0; l.pattern().nnz()], Vec::new());
    l.reassemble(Material::Uniform(&c), &c, &mut was_off, &mut values);
    assert_eq!(values, l.stiffness(Material::Uniform(&c)));
    let mut tangents = vec![c; l.n_points()];
    for _ in 0..2 {
        for e in 0..n_elements {
            let draw: f64 = rng.random_range(0.0..1.0);
            for q in 0..points {
                tangents[points * e + q] = if draw < 1.0 / 3.0 {
                    let d = SymOp::from_fn(|_, _| rng.random_range(-1.0..1.0));
                    c + d * d.transpose() * 0.1
                } else {
                    c
                };
            }
        }
        l.reassemble(Material::PerPoint(&tangents), &c, &mut was_off, &mut values);
        let full = l.stiffness(Material::PerPoint(&tangents));
        let differing = values.iter().zip(&full).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
        assert_eq!(differing, 0, "of {} values", full.len());
    }
    assert!(was_off.iter().any(|o| *o) && was_off.iter().any(|o| !*o));
}
