//! The gap function φ of the punch (theory §1): the punch occupies {x : −x₃ ≥ φ(x₁, x₂)} below
//! the plane of the contact face, with φ ≥ 0 and φ(x̄) = 0 at its lowest point x̄
//! ([`GapShape::center`]). Shapes are plugins chosen by `type` in the `gap` table of the
//! obstacle, e.g. `gap = { type = "paraboloid", R = 5.0 }`.

use saddle_core::ParameterError;
use saddle_core::error::{check, join};
use serde::{Deserialize, Serialize};
use std::fmt::Debug;

/// φ(x₁, x₂) ≥ 0: the initial distance between the contact face and the punch (theory §1).
#[typetag::serde(tag = "type")]
pub trait GapShape: Debug + Send + Sync + dyn_clone::DynClone {
    /// Checks the parameters; `path` is the table's path in the scene (`obstacle.gap`).
    fn validate(&self, path: &str) -> Result<(), ParameterError>;

    /// φ(x₁, x₂) (theory §1).
    fn phi(&self, x1: f64, x2: f64) -> f64;

    /// Where φ is smallest (the first point of contact x̄); the contact radius is measured from
    /// here.
    fn center(&self) -> [f64; 2];

    /// Whether the punch's face has an edge inside the zone: true for a flat punch, whose face
    /// is the candidate zone itself, so contact at the zone's rim is the punch's edge (where the
    /// pressure concentrates), not a sign of a zone too small. False by default.
    fn has_edge(&self) -> bool {
        false
    }
}

/// `type = "paraboloid"`: the sphere of radius R near its apex,
/// φ = ((x₁ − c₁)² + (x₂ − c₂)²)/(2R) (theory §6, R = 5 in the default scene).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
pub struct Paraboloid {
    /// Radius of curvature R > 0.
    pub R: f64,
    /// The apex (c₁, c₂); [0, 0] by default.
    #[serde(default)]
    pub center: [f64; 2],
}

impl Paraboloid {
    /// Radius `r`, apex at the origin.
    pub fn new(r: f64) -> Self {
        Self { R: r, center: [0.0, 0.0] }
    }
}

#[typetag::serde(name = "paraboloid")]
impl GapShape for Paraboloid {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::positive(path, "R", self.R)?;
        check::scale(path, "R", self.R, false)?;
        check::bounded_all(path, "center", &self.center)
    }

    fn phi(&self, x1: f64, x2: f64) -> f64 {
        ((x1 - self.center[0]).powi(2) + (x2 - self.center[1]).powi(2)) / (2.0 * self.R)
    }

    fn center(&self) -> [f64; 2] {
        self.center
    }
}

/// `type = "elliptic_paraboloid"`: principal radii R₁ along x₁ and R₂ along x₂,
/// φ = (x₁ − c₁)²/(2R₁) + (x₂ − c₂)²/(2R₂); c₁ and c₂ default to 0.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
pub struct EllipticParaboloid {
    /// Radius of curvature along x₁, > 0.
    pub R1: f64,
    /// Radius of curvature along x₂, > 0.
    pub R2: f64,
    /// x₁ of the apex.
    #[serde(default)]
    pub c1: f64,
    /// x₂ of the apex.
    #[serde(default)]
    pub c2: f64,
}

#[typetag::serde(name = "elliptic_paraboloid")]
impl GapShape for EllipticParaboloid {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::positive(path, "R1", self.R1)?;
        check::positive(path, "R2", self.R2)?;
        check::scale(path, "R1", self.R1, false)?;
        check::scale(path, "R2", self.R2, false)?;
        check::bounded(path, "c1", self.c1)?;
        check::bounded(path, "c2", self.c2)?;
        Ok(())
    }

    fn phi(&self, x1: f64, x2: f64) -> f64 {
        (x1 - self.c1).powi(2) / (2.0 * self.R1) + (x2 - self.c2).powi(2) / (2.0 * self.R2)
    }

    fn center(&self) -> [f64; 2] {
        [self.c1, self.c2]
    }
}

/// `type = "flat"`: a flat punch, φ ≡ 0 (the homogeneous compression test of theory §7). The
/// optional `center` (default [0, 0]) is where the contact radius is measured from.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Flat {
    /// Reference point of the contact radius.
    #[serde(default)]
    pub center: [f64; 2],
}

#[typetag::serde(name = "flat")]
impl GapShape for Flat {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::bounded_all(path, "center", &self.center)
    }

    fn phi(&self, _x1: f64, _x2: f64) -> f64 {
        0.0
    }

    fn center(&self) -> [f64; 2] {
        self.center
    }

    fn has_edge(&self) -> bool {
        true
    }
}

/// Validates a gap shape under `{path}.gap`.
pub(crate) fn validate_gap(gap: &dyn GapShape, path: &str) -> Result<(), ParameterError> {
    gap.validate(&join(path, "gap"))
}

dyn_clone::clone_trait_object!(GapShape);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phi_values_and_centres() {
        let p = Paraboloid { R: 5.0, center: [0.25, -0.5] };
        // (0.75² + 1²)/10 = 1.5625/10
        assert!((p.phi(1.0, 0.5) - 0.15625).abs() < 1e-16);
        assert_eq!(p.phi(0.25, -0.5), 0.0);
        assert_eq!(p.center(), [0.25, -0.5]);
        let e = EllipticParaboloid { R1: 2.0, R2: 8.0, c1: 0.5, c2: 0.0 };
        // 0.5²/4 + 1²/16
        assert!((e.phi(1.0, 1.0) - 0.125).abs() < 1e-16);
        assert_eq!(e.center(), [0.5, 0.0]);
        assert_eq!(Flat::default().phi(3.0, -7.0), 0.0);
        assert_eq!(Paraboloid::new(2.0).phi(2.0, 0.0), 1.0);
    }

    #[test]
    fn radii_must_be_positive_and_finite() {
        let e = Paraboloid::new(0.0).validate("obstacle.gap").unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), ("obstacle.gap.R", "0"));
        let e = Paraboloid::new(f64::INFINITY).validate("obstacle.gap").unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), ("obstacle.gap.R", "inf"));
        let e = EllipticParaboloid { R1: 1.0, R2: -2.5, c1: 0.0, c2: 0.0 }.validate("obstacle.gap").unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), ("obstacle.gap.R2", "-2.5"));
        let e = EllipticParaboloid { R1: 1.0, R2: 1.0, c1: f64::NAN, c2: 0.0 }.validate("obstacle.gap").unwrap_err();
        assert_eq!(e.field, "obstacle.gap.c1");
        let e = Flat { center: [0.0, f64::NAN] }.validate("obstacle.gap").unwrap_err();
        assert_eq!(e.field, "obstacle.gap.center[1]");
    }
}
