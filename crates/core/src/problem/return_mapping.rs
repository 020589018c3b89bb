//! Steps that the return mappings of yield surfaces share (theory §2, §11.1): the elastic
//! predictor C(ε − ε_p) split into deviator and mean stress, the elastic step that accepts it,
//! and the consistent tangent of a radial return. A plugin's
//! [`crate::AdmissibleStresses::step_law`] is its own correction between them.

use crate::problem::elasticity::Elasticity;
use crate::problem::stresses::{StepInput, StepOutput};
use crate::problem::tensor::{Sym, SymOp, deviator, deviatoric_projector, identity, trace, volumetric_projector};

/// The elastic predictor of a step (theory §11.1) split by the isotropy of C: for
/// e = ε − ε_p, the trial deviator s = 2G dev e, its norm r and the trial mean stress
/// p = K_b tr e.
#[derive(Clone, Copy, Debug)]
pub struct DeviatoricTrial {
    /// 2G.
    pub g2: f64,
    /// K_b.
    pub kb: f64,
    /// s = 2G dev(ε − ε_p).
    pub s: Sym,
    /// r = |s|.
    pub r: f64,
    /// p = K_b tr(ε − ε_p).
    pub p: f64,
}

impl DeviatoricTrial {
    /// The trial of the step `step`.
    #[inline]
    pub fn new(law: &Elasticity, step: &StepInput<'_>) -> Self {
        let g2 = 2.0 * law.shear_modulus();
        let kb = law.bulk_modulus();
        let e = step.elastic_strain();
        let s = deviator(&e) * g2;
        Self { g2, kb, s, r: s.norm(), p: kb * trace(&e) }
    }

    /// The trial stress s + p I.
    #[inline]
    pub fn stress(&self) -> Sym {
        self.s + identity() * self.p
    }
}

/// The elastic step (theory §11.1): the trial is admissible, so σ = `trial`, q = q_n and the
/// tangent is C. Returns false (not plastic), for `return elastic_step(…)`.
#[inline]
pub fn elastic_step(law: &Elasticity, trial: Sym, q_n: &[f64], mut out: StepOutput<'_>) -> bool {
    *out.sigma = trial;
    let m = out.q.len();
    out.q.copy_from_slice(&q_n[..m]);
    out.set_tangent(|| law.stiffness_matrix());
    false
}

/// The consistent tangent of a radial return along the unit deviator `n` (theory §2):
/// `3K_b (I⊗I)/3 + a (I_dev − n⊗n) + b n⊗n`, with a the modulus across the return direction
/// (2G t/r for a return to radius t) and b the modulus along it.
#[inline]
pub fn radial_tangent(kb: f64, n: &Sym, across: f64, along: f64) -> SymOp {
    let nn = n * n.transpose();
    volumetric_projector() * (3.0 * kb) + (deviatoric_projector() - nn) * across + nn * along
}
