//! Isotropic linear elasticity: the stiffness C and the compliance A = C⁻¹ of the energy
//! inner product (theory §1).

use crate::error::{ParameterError, check};
use crate::problem::tensor::{Sym, SymOp, deviatoric_projector, identity, trace, volumetric_projector};
use serde::{Deserialize, Serialize};

/// Isotropic elasticity `Cε = 2G dev ε + K_b tr(ε) I`, `Aσ = ((1+ν)σ − ν tr(σ) I)/E` (theory §1–§2).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Elasticity {
    /// Young's modulus E > 0.
    #[serde(rename = "E")]
    pub young: f64,
    /// Poisson's ratio ν ∈ (−1, 1/2).
    #[serde(rename = "nu")]
    pub poisson: f64,
}

impl Elasticity {
    /// Elasticity with Young's modulus `young` and Poisson's ratio `poisson`, validated.
    pub fn new(young: f64, poisson: f64) -> Result<Self, ParameterError> {
        let e = Self { young, poisson };
        e.validate("material")?;
        Ok(e)
    }

    /// E > 0 within the moduli's range ([`check::scale`]: E and 1/E both enter the solvers, C
    /// and A = C⁻¹) and −1 < ν < 1/2, naming the field under `path` otherwise.
    pub fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::positive(path, "E", self.young)?;
        check::scale(path, "E", self.young, false)?;
        check::open_interval(path, "nu", self.poisson, -1.0, 0.5)?;
        Ok(())
    }

    /// Shear modulus G = E / (2(1+ν)).
    pub fn shear_modulus(&self) -> f64 {
        self.young / (2.0 * (1.0 + self.poisson))
    }

    /// Bulk modulus K_b = E / (3(1−2ν)).
    pub fn bulk_modulus(&self) -> f64 {
        self.young / (3.0 * (1.0 - 2.0 * self.poisson))
    }

    /// σ = C ε.
    #[inline]
    pub fn stress(&self, eps: &Sym) -> Sym {
        let g2 = 2.0 * self.shear_modulus();
        let lam = self.bulk_modulus() - g2 / 3.0;
        eps * g2 + identity() * (lam * trace(eps))
    }

    /// ε = A σ.
    #[inline]
    pub fn compliance(&self, sigma: &Sym) -> Sym {
        (sigma * (1.0 + self.poisson) - identity() * (self.poisson * trace(sigma))) / self.young
    }

    /// The 6×6 Mandel matrix of C = 2G I_dev + 3K_b (I⊗I)/3.
    pub fn stiffness_matrix(&self) -> SymOp {
        deviatoric_projector() * (2.0 * self.shear_modulus()) + volumetric_projector() * (3.0 * self.bulk_modulus())
    }

    /// The largest eigenvalue of C, max(2G, 3K_b): the Lipschitz constant of ε ↦ Cε.
    pub fn max_eigenvalue(&self) -> f64 {
        (2.0 * self.shear_modulus()).max(3.0 * self.bulk_modulus())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compliance_inverts_stiffness() {
        let law = Elasticity::new(210.0, 0.28).unwrap();
        let eps = Sym::new(1e-3, -2e-3, 5e-4, 3e-4, -1e-4, 2e-4);
        assert!((law.compliance(&law.stress(&eps)) - eps).norm() < 1e-15);
        assert!((law.stiffness_matrix() * eps - law.stress(&eps)).norm() < 1e-12);
    }

    #[test]
    fn uniaxial_stress_gives_young_and_poisson() {
        let law = Elasticity::new(100.0, 0.3).unwrap();
        let eps = law.compliance(&Sym::new(0.0, 0.0, -1.0, 0.0, 0.0, 0.0));
        assert!((eps[2] + 0.01).abs() < 1e-15);
        assert!((eps[0] - 0.003).abs() < 1e-15);
    }

    #[test]
    fn rejects_out_of_range_values_naming_the_field() {
        let e = Elasticity::new(-1.0, 0.3).unwrap_err();
        assert_eq!(e.field, "material.E");
        assert_eq!(e.value, "-1");
        let e = Elasticity::new(1.0, 0.5).unwrap_err();
        assert_eq!(e.field, "material.nu");
        let e = Elasticity::new(f64::NAN, 0.3).unwrap_err();
        assert!(e.to_string().contains("finite"), "{e}");
    }
}
