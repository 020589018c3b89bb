//! # saddle-yield
//!
//! Yield surfaces — implementations of **P**, the admissible generalised stresses of theory §1
//! ([`AdmissibleStresses`]) — and the conformance kit every implementation must pass.
//!
//! A generalised stress is σ̂ = (σ, q): a stress σ (Mandel vector, see
//! [`saddle_core::problem::tensor`]) and `hardening_dim()` hardening variables q. P is the set of
//! fields with σ̂(x) ∈ D at every point, for a closed convex set D, and the energy inner
//! product is `[σ̂, τ̂] = Aσ:τ + q·H⁻¹r`. Everything a solver needs follows from the
//! projection onto D in that metric (theory §2): the local law σ̂ = P_D(Cε, 0), its derivative
//! (the consistent tangent), the reduced energy ψ(ε) with ∂ψ/∂ε = σ, and for conic solvers a
//! description of D by second-order cones (theory §3).
//!
//! Provided here, chosen by `type` in the `[yield]` table of a scene:
//!
//! * [`VonMises`] (`type = "von_mises"`, `k0`, `h`): `D = {|dev σ| ≤ k₀ + ξ}`, metric ξη/h —
//!   the material of theory §1;
//! * [`DruckerPrager`] (`type = "drucker_prager"`, `k0`, `alpha`, `h`):
//!   `D = {|dev σ| + α tr σ ≤ k₀ + ξ}` (theory §9.1);
//! * [`Tresca`] (`type = "tresca"`, `sigma0`, `h`): `D = {σ₁ − σ₃ ≤ σ₀ + ξ}` (theory §9.2), no
//!   second-order-cone description;
//! * [`VonMisesKinematic`] (`type = "von_mises_kinematic"`, `k0`, `h`, `c`):
//!   `D = {|dev σ − χ| ≤ k₀ + ξ}` with a back stress χ (theory §9.3);
//! * [`Elastic`] (`type = "elastic"`): D is the whole space.
//!
//! ## Adding a yield surface
//!
//! Write one small file with a serde struct for the parameters and an
//! `#[typetag::serde(name = "...")] impl AdmissibleStresses`, and run the
//! [`conformance`] kit in its tests. For example, von Mises without hardening (a plugin with no
//! hardening variable):
//!
//! ```
//! use saddle_core::error::{ParameterError, check};
//! use saddle_core::problem::return_mapping::{DeviatoricTrial, elastic_step, radial_tangent};
//! use saddle_core::problem::tensor::{Sym, deviator, identity, trace};
//! use saddle_core::{AdmissibleStresses, Elasticity, StepInput, StepOutput};
//! use saddle_yield::conformance::{KitConfig, check_all};
//! use serde::{Deserialize, Serialize};
//!
//! /// D = {|dev σ| ≤ k}: perfect plasticity with no hardening variable.
//! #[derive(Clone, Debug, Serialize, Deserialize)]
//! #[serde(deny_unknown_fields)]
//! struct PerfectMises {
//!     k: f64,
//! }
//!
//! #[typetag::serde(name = "perfect_mises")]
//! impl AdmissibleStresses for PerfectMises {
//!     fn validate(&self, path: &str) -> Result<(), ParameterError> {
//!         check::positive(path, "k", self.k).map(|_| ())
//!     }
//!     fn hardening_dim(&self) -> usize {
//!         0
//!     }
//!     fn hardening_inner(&self, _q: &[f64], _r: &[f64]) -> f64 {
//!         0.0
//!     }
//!     fn contains(&self, sigma: &Sym, _q: &[f64], tol: f64) -> bool {
//!         deviator(sigma).norm() <= self.k + tol * self.k.max(sigma.norm())
//!     }
//!     fn project(&self, _law: &Elasticity, sigma: &mut Sym, _q: &mut [f64]) -> bool {
//!         let (s, r) = (deviator(sigma), deviator(sigma).norm());
//!         if r <= self.k {
//!             return false;
//!         }
//!         *sigma = identity() * (trace(sigma) / 3.0) + s * (self.k / r);
//!         true
//!     }
//!     /// The radial return from the trial C(ε − ε_p) (theory §11.1) and its tangent.
//!     fn step_law(&self, law: &Elasticity, step: StepInput<'_>, mut out: StepOutput<'_>) -> bool {
//!         let trial = DeviatoricTrial::new(law, &step);
//!         if trial.r <= self.k {
//!             return elastic_step(law, trial.stress(), step.q_n, out);
//!         }
//!         *out.sigma = trial.s * (self.k / trial.r) + identity() * trial.p;
//!         out.set_tangent(|| radial_tangent(trial.kb, &(trial.s / trial.r), trial.g2 * self.k / trial.r, 0.0));
//!         true
//!     }
//! }
//!
//! // in the plugin's tests:
//! let law = Elasticity::new(100.0, 0.3).unwrap();
//! check_all(&PerfectMises { k: 1.0 }, &KitConfig::new(law, 1.0)).unwrap();
//! // and it can be read from a scene:
//! let p: Box<dyn AdmissibleStresses> = toml::from_str("type = \"perfect_mises\"\nk = 1.0").unwrap();
//! assert_eq!(p.name(), "perfect_mises");
//! ```
//!
//! The kit checks (theory §2) that the projection lies in D, is idempotent, satisfies the
//! variational inequality and is non-expansive in the energy metric; that ∂ψ/∂ε = σ and the
//! tangent is the derivative of σ(ε) (finite differences); that ψ is convex, equals
//! ε:σ − ½[σ̂, σ̂], and that the local law is the projection of (Cε, 0); that the cone
//! description, if any, describes D; and that the step law of a load step (theory §11.1) is the
//! projection of (C(ε − ε_p), q_n), with its tangent and ∂ψ_n/∂ε = σ checked by finite
//! differences. The step law is the one law a plugin provides (the local law is the step law
//! from the zero state); without a closed form it may call
//! `saddle_core::problem::stresses::step_law_by_differences`, which differentiates projections
//! numerically. Also give `energy` a closed form where one is known, and `warnings` for legal
//! but delicate parameters.
//!
//! A binary reads plugins by name only if this crate is linked into it: refer to it somewhere
//! (e.g. `use saddle_yield as _;`), or the `von_mises` / `elastic` names are unknown.

pub mod conformance;
mod drucker_prager;
mod elastic;
mod hardening;
pub mod mutant;
#[cfg(test)]
mod testing;
mod tresca;
mod von_mises;
mod von_mises_kinematic;

pub use drucker_prager::DruckerPrager;
pub use elastic::Elastic;
pub use saddle_core::problem::stresses::AdmissibleStresses;
pub use tresca::{Tresca, TrescaReturn};
pub use von_mises::VonMises;
pub use von_mises_kinematic::VonMisesKinematic;
