//! Coulomb's friction law (theory §8.3): the tangential multiplier of a contact node lies in
//! the disc |λ_t| ≤ μ λ_n of its own normal multiplier — the friction cone. The bound depends
//! on the solution: with the slip rule of the disc (non-associated: the slip is normal to the
//! disc, not to the cone) the problem is a quasi-variational inequality, solved as a fixed point
//! of Tresca problems (uzawa: inside the projection's sweeps; socp: across interior-point solves).
//!
//! ```toml
//! friction = { type = "coulomb", mu = 0.3 }
//! ```

use saddle_core::FrictionLaw;
use saddle_core::ParameterError;
use saddle_core::error::check;
use serde::{Deserialize, Serialize};

/// `type = "coulomb"`: |λ_t| ≤ μ λ_n at every contact node (theory §8.3).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Coulomb {
    /// The friction coefficient μ ≥ 0 (dimensionless).
    pub mu: f64,
}

#[typetag::serde(name = "coulomb")]
impl FrictionLaw for Coulomb {
    /// μ finite and ≥ 0, within [`check::MAX_MAGNITUDE`]; errors name `{path}.mu` and the value.
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::non_negative(path, "mu", self.mu)?;
        check::bounded(path, "mu", self.mu)?;
        Ok(())
    }

    /// μ max(λ_n, 0): the node's normal force times μ (an iterate's negative λ_n gives the
    /// empty disc's point 0).
    fn radius(&self, _weight: f64, lambda_n: f64) -> f64 {
        self.mu * lambda_n.max(0.0)
    }

    /// μ: the disc grows with the normal force.
    fn radius_slope(&self, _weight: f64) -> f64 {
        self.mu
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Negative and non-finite μ are errors naming the field and the value.
    #[test]
    fn bad_coefficients_are_named() {
        for (mu, shown) in [(-0.3, "-0.3"), (f64::NAN, "NaN"), (f64::NEG_INFINITY, "-inf")] {
            let e = Coulomb { mu }.validate("obstacle.friction").unwrap_err();
            assert_eq!(e.field, "obstacle.friction.mu");
            assert_eq!(e.value, shown, "{e}");
        }
        Coulomb { mu: 0.0 }.validate("obstacle.friction").unwrap();
    }

    /// The scene table: unknown fields refused; the disc's radius is μ λ_n whatever the weight
    /// (the point (3, 4) of norm 5 lands at radius 0.5 · 2 = 1 on (0.6, 0.8)), and its
    /// derivative in λ_n is μ t̂ outside the disc.
    #[test]
    fn reads_from_a_scene_and_projects_onto_mu_times_lambda_n() {
        let law: Box<dyn FrictionLaw> = toml::from_str("type = \"coulomb\"\nmu = 0.5").unwrap();
        assert_eq!(law.name(), "coulomb");
        for weight in [0.1, 7.0] {
            let p = law.project(weight, 2.0, [3.0, 4.0]);
            assert!((p[0] - 0.6).abs() < 1e-15 && (p[1] - 0.8).abs() < 1e-15, "{p:?}");
        }
        let (_, dn) = law.project_derivative(1.0, 2.0, [3.0, 4.0]);
        assert!((dn[0] - 0.3).abs() < 1e-15 && (dn[1] - 0.4).abs() < 1e-15, "{dn:?}");
        assert_eq!(law.project(1.0, -1.0, [3.0, 4.0]), [0.0, 0.0]);
        let e = toml::from_str::<Box<dyn FrictionLaw>>("type = \"coulomb\"\nmu = 0.3\ng = 1.0").unwrap_err();
        assert!(e.to_string().contains('g'), "{e}");
    }
}
