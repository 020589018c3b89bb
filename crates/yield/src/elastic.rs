//! No yield: D is the whole space of stresses (theory §7, the Hertz case with yield switched off).

use saddle_core::error::ParameterError;
use saddle_core::problem::elasticity::Elasticity;
use saddle_core::problem::return_mapping::elastic_step;
use saddle_core::problem::stresses::{AdmissibleStresses, ConeDescription, StepInput, StepOutput};
use saddle_core::problem::tensor::Sym;
use serde::{Deserialize, Serialize};

/// A linear elastic body: D = the whole space, no hardening variables, `[σ̂, τ̂] = Aσ:τ`.
/// Scene table: `type = "elastic"` with no other field. Solvers see
/// [`AdmissibleStresses::is_unbounded`] and skip the return mapping altogether.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Elastic {}

#[typetag::serde(name = "elastic")]
impl AdmissibleStresses for Elastic {
    /// Nothing to check.
    fn validate(&self, _path: &str) -> Result<(), ParameterError> {
        Ok(())
    }

    /// No hardening variables.
    fn hardening_dim(&self) -> usize {
        0
    }

    /// D is the whole space.
    fn is_unbounded(&self) -> bool {
        true
    }

    /// No hardening variables: 0.
    fn hardening_inner(&self, _q: &[f64], _r: &[f64]) -> f64 {
        0.0
    }

    /// Every stress is admissible.
    fn contains(&self, _sigma: &Sym, _q: &[f64], _tol: f64) -> bool {
        true
    }

    /// The identity (theory §2 with D the whole space); never outside.
    fn project(&self, _law: &Elasticity, _sigma: &mut Sym, _q: &mut [f64]) -> bool {
        false
    }

    /// σ = C(ε − ε_p), tangent C (theory §11.1 with D the whole space).
    fn step_law(&self, law: &Elasticity, step: StepInput<'_>, out: StepOutput<'_>) -> bool {
        elastic_step(law, law.stress(&step.elastic_strain()), step.q_n, out)
    }

    /// ψ(ε) = ½Cε:ε.
    fn energy(&self, law: &Elasticity, eps: &Sym) -> f64 {
        0.5 * eps.dot(&law.stress(eps))
    }

    /// No cone blocks: every point is admissible.
    fn cone(&self) -> Option<ConeDescription> {
        Some(ConeDescription { blocks: vec![] })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::conformance::{KitConfig, check_all};
    use saddle_core::problem::tensor::SymOp;

    #[test]
    fn elastic_is_the_identity_with_stiffness_c() {
        let law = Elasticity::new(100.0, 0.3).unwrap();
        let p = Elastic {};
        let eps = Sym::new(1e-3, -2e-3, 5e-4, 3e-4, -1e-4, 2e-4);
        let (mut s, mut c) = (Sym::zeros(), SymOp::zeros());
        assert!(!p.local_law(&law, &eps, StepOutput::new(&mut s, &mut [], Some(&mut c))));
        assert_eq!(s, law.stress(&eps));
        assert_eq!(c, law.stiffness_matrix());
        assert!((p.energy(&law, &eps) - 0.5 * eps.dot(&(law.stiffness_matrix() * eps))).abs() < 1e-18);
        let mut big = Sym::new(1e9, 0.0, -1e9, 0.0, 5e8, 0.0);
        let before = big;
        assert!(!p.project(&law, &mut big, &mut []));
        assert_eq!(big, before);
        assert!(p.contains(&big, &[], 0.0) && p.is_unbounded() && p.hardening_dim() == 0);
        assert_eq!(p.cone().unwrap().blocks.len(), 0);
    }

    #[test]
    fn elastic_passes_the_kit_and_reads_from_toml() {
        let law = Elasticity::new(100.0, 0.3).unwrap();
        check_all(&Elastic {}, &KitConfig::new(law, 1.0)).unwrap();
        let p: Box<dyn AdmissibleStresses> = toml::from_str("type = \"elastic\"").unwrap();
        assert!(p.is_unbounded() && p.name() == "elastic");
        let err = toml::from_str::<Box<dyn AdmissibleStresses>>("type = \"elastic\"\nk0 = 1.0").unwrap_err();
        assert!(err.to_string().contains("unknown field"), "{err}");
    }
}
