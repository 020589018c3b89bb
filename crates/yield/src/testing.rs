//! What the plugins' unit tests share: the test material, a relative comparison, and the
//! check of a closed-form step tangent against the tangent by differences (theory §11.1).

use saddle_core::problem::elasticity::Elasticity;
use saddle_core::problem::stresses::{
    AdmissibleStresses, MAX_HARDENING_DIM, StepInput, StepOutput, step_law_by_differences,
};
use saddle_core::problem::tensor::{Sym, SymOp};

/// The test material: E = 100, ν = 0.3.
pub fn law() -> Elasticity {
    Elasticity::new(100.0, 0.3).unwrap()
}

/// |a − b| ≤ tol · max(|a|, |b|) (floored at 1e-300).
pub fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * a.abs().max(b.abs()).max(1e-300)
}

/// Fails unless the closed-form tangent `c` of `p`'s step law at `step` is the tangent by
/// central differences of its projection ([`step_law_by_differences`]) to 1e-6 relative: the
/// differences are good to about 1e-8 relative (their docs), the rest is margin for trials near
/// the boundary between two returns.
#[track_caller]
pub fn assert_tangent_by_differences(p: &dyn AdmissibleStresses, law: &Elasticity, step: StepInput<'_>, c: &SymOp) {
    let (mut s, mut q, mut fd) = (Sym::zeros(), [0.0; MAX_HARDENING_DIM], SymOp::zeros());
    step_law_by_differences(p, law, step, StepOutput::new(&mut s, &mut q[..p.hardening_dim()], Some(&mut fd)));
    assert!((fd - c).norm() <= 1e-6 * c.norm(), "{}: closed form {c}, by differences {fd}", p.name());
}
