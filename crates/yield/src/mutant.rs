//! A yield surface with some of its laws replaced: the broken plugins that show the
//! [`crate::conformance`] kit catches each kind of mistake. A plugin author who adds a check, or
//! wants to see the kit reject a plausible bug of their own surface, wraps the surface and
//! replaces one law:
//!
//! ```
//! use saddle_yield::VonMises;
//! use saddle_yield::conformance::{KitConfig, names, tangent};
//! use saddle_yield::mutant::Mutant;
//! use saddle_core::{Elasticity, StepOutput};
//!
//! // the tangent of the local law is C even where the point is plastic
//! let broken = Mutant::of(VonMises::new(1.0, 5.0).unwrap()).with_local_law(|m, law, eps, mut out| {
//!     let plastic = m.inner.local_law(law, eps, StepOutput::new(out.sigma, out.q, None));
//!     out.set_tangent(|| law.stiffness_matrix());
//!     plastic
//! });
//! let cfg = KitConfig::new(Elasticity::new(100.0, 0.3).unwrap(), 1.0);
//! assert_eq!(tangent(&broken, &cfg).unwrap_err().check, names::TANGENT);
//! ```
//!
//! Every law not replaced is the wrapped surface's. A mutant is not a scene plugin: it cannot be
//! read from a scene file (its type name exists for the trait's registry only).

use saddle_core::error::ParameterError;
use saddle_core::problem::elasticity::Elasticity;
use saddle_core::problem::stresses::{
    AdmissibleStresses, ConeDescription, SemidefiniteDescription, StepInput, StepOutput,
};
use saddle_core::problem::tensor::Sym;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;
use std::sync::Arc;

/// A replaced [`AdmissibleStresses::project`].
pub type ProjectFn = dyn Fn(&Mutant, &Elasticity, &mut Sym, &mut [f64]) -> bool + Send + Sync;
/// A replaced [`AdmissibleStresses::local_law`]: (mutant, law, ε, out).
pub type LocalLawFn = dyn Fn(&Mutant, &Elasticity, &Sym, StepOutput<'_>) -> bool + Send + Sync;
/// A replaced [`AdmissibleStresses::step_law`]: (mutant, law, step, out).
pub type StepLawFn = dyn Fn(&Mutant, &Elasticity, StepInput<'_>, StepOutput<'_>) -> bool + Send + Sync;
/// A replaced [`AdmissibleStresses::energy`].
pub type EnergyFn = dyn Fn(&Mutant, &Elasticity, &Sym) -> f64 + Send + Sync;
/// A replaced [`AdmissibleStresses::step_energy`]: (mutant, law, step).
pub type StepEnergyFn = dyn Fn(&Mutant, &Elasticity, StepInput<'_>) -> f64 + Send + Sync;
/// A replaced [`AdmissibleStresses::cone`].
pub type ConeFn = dyn Fn(&Mutant) -> Option<ConeDescription> + Send + Sync;
/// A replaced [`AdmissibleStresses::hardening_inner`].
pub type HardeningInnerFn = dyn Fn(&Mutant, &[f64], &[f64]) -> f64 + Send + Sync;

/// `inner` with the laws given replaced; each replacement receives the mutant, so that it can
/// call the wrapped surface (`m.inner`) or another replaced law (`m.project(…)`).
#[derive(Clone)]
pub struct Mutant {
    /// The wrapped surface.
    pub inner: Box<dyn AdmissibleStresses>,
    project: Option<Arc<ProjectFn>>,
    local_law: Option<Arc<LocalLawFn>>,
    step_law: Option<Arc<StepLawFn>>,
    energy: Option<Arc<EnergyFn>>,
    step_energy: Option<Arc<StepEnergyFn>>,
    cone: Option<Arc<ConeFn>>,
    hardening_inner: Option<Arc<HardeningInnerFn>>,
}

impl Mutant {
    /// `inner` unchanged.
    pub fn of(inner: impl AdmissibleStresses + 'static) -> Self {
        Self::boxed(Box::new(inner))
    }

    /// A boxed `inner` unchanged.
    pub fn boxed(inner: Box<dyn AdmissibleStresses>) -> Self {
        Self {
            inner,
            project: None,
            local_law: None,
            step_law: None,
            energy: None,
            step_energy: None,
            cone: None,
            hardening_inner: None,
        }
    }

    /// With the projection replaced.
    pub fn with_project(
        mut self,
        f: impl Fn(&Mutant, &Elasticity, &mut Sym, &mut [f64]) -> bool + Send + Sync + 'static,
    ) -> Self {
        self.project = Some(Arc::new(f));
        self
    }

    /// With the local law replaced.
    pub fn with_local_law(
        mut self,
        f: impl Fn(&Mutant, &Elasticity, &Sym, StepOutput<'_>) -> bool + Send + Sync + 'static,
    ) -> Self {
        self.local_law = Some(Arc::new(f));
        self
    }

    /// With the step law replaced.
    pub fn with_step_law(
        mut self,
        f: impl Fn(&Mutant, &Elasticity, StepInput<'_>, StepOutput<'_>) -> bool + Send + Sync + 'static,
    ) -> Self {
        self.step_law = Some(Arc::new(f));
        self
    }

    /// With the energy replaced.
    pub fn with_energy(mut self, f: impl Fn(&Mutant, &Elasticity, &Sym) -> f64 + Send + Sync + 'static) -> Self {
        self.energy = Some(Arc::new(f));
        self
    }

    /// With the energy of a load step replaced.
    pub fn with_step_energy(
        mut self,
        f: impl Fn(&Mutant, &Elasticity, StepInput<'_>) -> f64 + Send + Sync + 'static,
    ) -> Self {
        self.step_energy = Some(Arc::new(f));
        self
    }

    /// With the cone description replaced.
    pub fn with_cone(mut self, f: impl Fn(&Mutant) -> Option<ConeDescription> + Send + Sync + 'static) -> Self {
        self.cone = Some(Arc::new(f));
        self
    }

    /// With the hardening part of the energy metric replaced.
    pub fn with_hardening_inner(mut self, f: impl Fn(&Mutant, &[f64], &[f64]) -> f64 + Send + Sync + 'static) -> Self {
        self.hardening_inner = Some(Arc::new(f));
        self
    }

    /// The local law as a careless author would write it from a (replaced) projection: σ̂ =
    /// `self.project`(Cε, 0), with the wrapped surface's tangent.
    pub fn local_law_from_projection(&self, law: &Elasticity, eps: &Sym, out: StepOutput<'_>) -> bool {
        let StepOutput { sigma, q, tangent } = out;
        *sigma = law.stress(eps);
        q.iter_mut().for_each(|x| *x = 0.0);
        let plastic = self.project(law, sigma, q);
        if let Some(t) = tangent {
            let (mut s, mut r) = (Sym::zeros(), q.to_vec());
            self.inner.local_law(law, eps, StepOutput::new(&mut s, &mut r, Some(t)));
        }
        plastic
    }
}

impl fmt::Debug for Mutant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Mutant({:?})", self.inner)
    }
}

/// A mutant is written as its wrapped surface's name, for messages.
impl Serialize for Mutant {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&format!("mutant of {}", self.inner.name()))
    }
}

/// A mutant is never read from a scene.
impl<'de> Deserialize<'de> for Mutant {
    fn deserialize<D: Deserializer<'de>>(_: D) -> Result<Self, D::Error> {
        Err(serde::de::Error::custom("a mutant (a test wrapper) cannot be read from a scene"))
    }
}

#[typetag::serde(name = "conformance_mutant")]
impl AdmissibleStresses for Mutant {
    /// The wrapped surface's name: messages about a mutant name the surface it breaks.
    fn name(&self) -> &'static str {
        self.inner.name()
    }
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        self.inner.validate(path)
    }
    fn hardening_dim(&self) -> usize {
        self.inner.hardening_dim()
    }
    fn hardening_fields(&self) -> Vec<(&'static str, usize)> {
        self.inner.hardening_fields()
    }
    fn is_unbounded(&self) -> bool {
        self.inner.is_unbounded()
    }
    fn hardening_inner(&self, q: &[f64], r: &[f64]) -> f64 {
        match &self.hardening_inner {
            Some(f) => f(self, q, r),
            None => self.inner.hardening_inner(q, r),
        }
    }
    fn contains(&self, sigma: &Sym, q: &[f64], tol: f64) -> bool {
        self.inner.contains(sigma, q, tol)
    }
    fn project(&self, law: &Elasticity, sigma: &mut Sym, q: &mut [f64]) -> bool {
        match &self.project {
            Some(f) => f(self, law, sigma, q),
            None => self.inner.project(law, sigma, q),
        }
    }
    fn step_law(&self, law: &Elasticity, step: StepInput<'_>, out: StepOutput<'_>) -> bool {
        match &self.step_law {
            Some(f) => f(self, law, step, out),
            None => self.inner.step_law(law, step, out),
        }
    }
    fn local_law(&self, law: &Elasticity, eps: &Sym, out: StepOutput<'_>) -> bool {
        match &self.local_law {
            Some(f) => f(self, law, eps, out),
            None => self.inner.local_law(law, eps, out),
        }
    }
    fn step_energy(&self, law: &Elasticity, step: StepInput<'_>) -> f64 {
        match &self.step_energy {
            Some(f) => f(self, law, step),
            None => self.inner.step_energy(law, step),
        }
    }
    fn energy(&self, law: &Elasticity, eps: &Sym) -> f64 {
        match &self.energy {
            Some(f) => f(self, law, eps),
            None => self.inner.energy(law, eps),
        }
    }
    fn cone(&self) -> Option<ConeDescription> {
        match &self.cone {
            Some(f) => f(self),
            None => self.inner.cone(),
        }
    }
    fn semidefinite_cone(&self) -> Option<SemidefiniteDescription> {
        self.inner.semidefinite_cone()
    }
    fn cone_unavailable(&self) -> String {
        self.inner.cone_unavailable()
    }
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings()
    }
}
