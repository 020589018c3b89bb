//! Tresca's friction law (theory §8.3): a given bound g on the tangential traction, so that
//! the tangential multiplier of a contact node of weight w (its share of the contact face) lies
//! in the disc |λ_t| ≤ g w. The bound does not depend on the normal force: the problem is a
//! convex variational inequality of the second kind (Duvaut–Lions), the primal energy gaining
//! the dissipation Σ_i g w_i |s_i| of the slips s_i.
//!
//! ```toml
//! friction = { type = "tresca", g = 0.05 }
//! ```

use saddle_core::FrictionLaw;
use saddle_core::ParameterError;
use saddle_core::error::check;
use serde::{Deserialize, Serialize};

/// `type = "tresca"`: |λ_t| ≤ g w at a node of weight w (theory §8.3).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Tresca {
    /// The slip bound g ≥ 0 (a traction: force per area of the contact face).
    pub g: f64,
}

#[typetag::serde(name = "tresca")]
impl FrictionLaw for Tresca {
    /// g finite and ≥ 0, within [`check::MAX_MAGNITUDE`]; errors name `{path}.g` and the value.
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::non_negative(path, "g", self.g)?;
        check::bounded(path, "g", self.g)?;
        Ok(())
    }

    /// g w: a given bound.
    fn radius(&self, weight: f64, _lambda_n: f64) -> f64 {
        self.g * weight
    }

    /// 0: the bound does not depend on λ_n.
    fn radius_slope(&self, _weight: f64) -> f64 {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Negative and non-finite g are errors naming the field and the value.
    #[test]
    fn bad_bounds_are_named() {
        for (g, shown) in [(-0.1, "-0.1"), (f64::NAN, "NaN"), (f64::INFINITY, "inf")] {
            let e = Tresca { g }.validate("obstacle.friction").unwrap_err();
            assert_eq!(e.field, "obstacle.friction.g");
            assert_eq!(e.value, shown, "{e}");
        }
        Tresca { g: 0.0 }.validate("obstacle.friction").unwrap();
    }

    /// The scene table: unknown fields refused; the projection is onto the disc of radius g w
    /// (the point (3, 4) of norm 5 lands on the rim at radius 2 · 0.5 = 1: (0.6, 0.8)).
    #[test]
    fn reads_from_a_scene_and_projects_onto_g_times_weight() {
        let law: Box<dyn FrictionLaw> = toml::from_str("type = \"tresca\"\ng = 2.0").unwrap();
        assert_eq!(law.name(), "tresca");
        let p = law.project(0.5, 123.0, [3.0, 4.0]);
        assert!((p[0] - 0.6).abs() < 1e-15 && (p[1] - 0.8).abs() < 1e-15);
        let e = toml::from_str::<Box<dyn FrictionLaw>>("type = \"tresca\"\ng = 2.0\nmu = 0.3").unwrap_err();
        assert!(e.to_string().contains("mu"), "{e}");
    }
}
