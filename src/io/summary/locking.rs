//! A locking indicator (theory §10): where the response at a solution is nearly incompressible,
//! an element that locks (P1 tetrahedra) gives converged but wrong answers.
//!
//! The response at a stress point is read off the consistent tangent C_t of the local law at
//! the solution, whatever the yield surface: the shear stiffness along the deviatoric direction
//! n of the stress, μ_t = ½ n : C_t : n (the elastic μ at an elastic point; small where the flow
//! is plastic with little hardening), against the elastic bulk modulus κ, as an effective
//! Poisson ratio ν_t = (3κ − 2μ_t) / (2(3κ + μ_t)). Plastic flow of a von Mises material with
//! h = 0 gives ν_t = ½; elasticity with ν = 0.4999 gives 0.4999 everywhere.
//!
//! The indicator is the volume fraction of the body where ν_t ≥ [`NEAR_INCOMPRESSIBLE_NU`]; a
//! solution of an element that locks ([`saddle_core::Discretisation::locks`]) is warned about
//! when it exceeds [`LOCKING_FRACTION`].

use saddle_core::{Discretisation, Lagrangian, Sym, SymOp};

/// ν_t at or above which a point counts as nearly incompressible. On the small default scene,
/// elastic, P1's U is 4 % below P2's at ν = 0.45, 26 % at 0.49 and 67 % at 0.499 (P1 on 12×12×6
/// cells against P2 on 6×6×3, the same nodes).
pub const NEAR_INCOMPRESSIBLE_NU: f64 = 0.485;

/// The volume fraction above which a solution of a locking element is warned about.
pub const LOCKING_FRACTION: f64 = 0.1;

/// ν_t of the tangent `c_t` at a point with stress `sigma` (see the module docs).
pub fn effective_poisson(c_t: &SymOp, sigma: &Sym, bulk: f64, shear: f64) -> f64 {
    let tr = (sigma[0] + sigma[1] + sigma[2]) / 3.0;
    let mut n = *sigma;
    for k in 0..3 {
        n[k] -= tr;
    }
    let norm = n.norm();
    let mu_t = if norm > 1e-12 * sigma.norm().max(f64::MIN_POSITIVE) {
        n /= norm;
        0.5 * n.dot(&(c_t * n))
    } else {
        // no deviatoric stress: a unit pure shear (the Mandel xy component)
        let mut s = Sym::zeros();
        s[5] = 1.0;
        0.5 * s.dot(&(c_t * s))
    };
    let mu_t = mu_t.clamp(0.0, shear.max(0.0));
    (3.0 * bulk - 2.0 * mu_t) / (2.0 * (3.0 * bulk + mu_t))
}

/// The volume fraction of the body where the response at a solution with strains `eps`
/// (ε(u) at every stress point) is nearly incompressible (ν_t ≥ [`NEAR_INCOMPRESSIBLE_NU`]).
pub fn near_incompressible_fraction(l: &Lagrangian<'_>, eps: &[Sym]) -> f64 {
    let law = *l.data.elasticity;
    let (e, nu) = (law.young, law.poisson);
    let (bulk, shear) = (e / (3.0 * (1.0 - 2.0 * nu)), e / (2.0 * (1.0 + nu)));
    let mut stress = saddle_core::StressField::new(l.n_points(), l.data.hardening_dim());
    let mut tangents = vec![SymOp::zeros(); l.n_points()];
    l.data.local_law(eps, &mut stress, Some(&mut tangents));
    let w = l.weights();
    let (mut near, mut total) = (0.0, 0.0);
    for i in 0..l.n_points() {
        total += w[i];
        if effective_poisson(&tangents[i], &stress.sigma[i], bulk, shear) >= NEAR_INCOMPRESSIBLE_NU {
            near += w[i];
        }
    }
    let (near, total) = (l.comm().sum(near), l.comm().sum(total));
    if total > 0.0 { near / total } else { 0.0 }
}

/// The warning for a solution of an element that locks, when the indicator fires.
pub fn locking_warning(l: &dyn Discretisation, fraction: f64) -> Option<String> {
    (l.locks() && fraction > LOCKING_FRACTION).then(|| {
        format!(
            "{:.0} % of the body responds nearly incompressibly (effective Poisson ratio of the tangent ≥ {}: \
             plastic flow with little hardening, or ν near ½): `{}` elements lock there, so the answer can be \
             converged and wrong (too stiff; theory §10). Use `[discretisation] type = \"p2\"`",
            100.0 * fraction,
            NEAR_INCOMPRESSIBLE_NU,
            l.name()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use saddle_core::Elasticity;

    #[test]
    fn effective_poisson_of_elastic_and_ideally_plastic_tangents() {
        let law = Elasticity::new(100.0, 0.3).unwrap();
        let (bulk, shear) = (100.0 / (3.0 * 0.4), 100.0 / 2.6);
        let c = law.stiffness_matrix();
        let sigma = Sym::new(1.0, -0.5, 0.2, 0.3, 0.0, 0.1);
        // the elastic tangent gives ν back
        assert!((effective_poisson(&c, &sigma, bulk, shear) - 0.3).abs() < 1e-12);
        // the tangent of ideal plasticity has no stiffness along n: ν_t = ½
        let mut n = sigma;
        let tr = (n[0] + n[1] + n[2]) / 3.0;
        for k in 0..3 {
            n[k] -= tr;
        }
        n /= n.norm();
        let c_t = c - (2.0 * shear) * (n * n.transpose());
        assert!((effective_poisson(&c_t, &sigma, bulk, shear) - 0.5).abs() < 1e-12);
    }
}
