//! **P** — the admissible generalised stresses (theory §1, §2).
//!
//! A generalised stress σ̂ = (σ, q) is a stress σ (Mandel vector) and `hardening_dim()`
//! hardening variables q (one, ξ, for isotropic hardening). P = {τ̂ : τ̂(x) ∈ D a.e.} for a
//! closed convex set D, and the energy inner product is `[σ̂, τ̂] = Aσ:τ + q·H⁻¹r` with the
//! elastic compliance A and a hardening metric H⁻¹ (ξη/h for isotropic hardening).
//!
//! Everything a solver needs from P follows from the projection onto D in that metric: the
//! local law σ̂ = P_D(Cε, 0), its derivative (the consistent tangent) and the reduced energy
//! ψ(ε) = sup_{τ̂∈D} (ε:τ − ½[τ̂, τ̂]) with ∂ψ/∂ε = σ. Implementations must pass the
//! conformance kit of `saddle-yield`.

use crate::error::ParameterError;
use crate::problem::elasticity::Elasticity;
use crate::problem::tensor::{Sym, SymOp};
use std::fmt::Debug;

/// Upper bound on `hardening_dim()`, so that hot loops keep q on the stack.
pub const MAX_HARDENING_DIM: usize = 8;

/// One second-order-cone block of a cone description: the affine image
/// `offset + map · (σ, q)` lies in the cone `{(t, x) ∈ R × R^{dim−1} : |x| ≤ t}`.
#[derive(Clone, Debug, PartialEq)]
pub struct SocBlock {
    /// Dimension of the cone (t and x together).
    pub dim: usize,
    /// Constant part, `dim` entries.
    pub offset: Vec<f64>,
    /// Linear part, `dim × (6 + hardening_dim)` row-major, acting on (σ Mandel, q).
    pub map: Vec<f64>,
}

/// D as an intersection of second-order cones, for conic solvers (theory §3).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct ConeDescription {
    /// The cone blocks; D = {(σ, q) : every block holds}.
    pub blocks: Vec<SocBlock>,
}

/// P: a pointwise closed convex set D of generalised stresses with its energy metric, chosen
/// by `type` in the `[yield]` table of a scene.
#[typetag::serde(tag = "type")]
pub trait AdmissibleStresses: Debug + Send + Sync + dyn_clone::DynClone {
    /// The `type` name of the plugin in scene files.
    fn name(&self) -> &'static str {
        self.typetag_name()
    }

    /// Checks the parameters; `path` is the table's path in the scene (`yield`).
    fn validate(&self, path: &str) -> Result<(), ParameterError>;

    /// Number of hardening variables q per point (ξ: 1; none: 0). At most [`MAX_HARDENING_DIM`].
    fn hardening_dim(&self) -> usize;

    /// True when D is the whole space (no yield): σ = Cε, and solvers skip the return mapping.
    fn is_unbounded(&self) -> bool {
        false
    }

    /// The hardening variables by name, with their number of components, in storage order:
    /// von Mises with isotropic hardening `[("xi", 1)]`. Output writes one cell field per name;
    /// the components add up to [`AdmissibleStresses::hardening_dim`]. The default names them
    /// all `q`.
    fn hardening_fields(&self) -> Vec<(&'static str, usize)> {
        match self.hardening_dim() {
            0 => Vec::new(),
            m => vec![("q", m)],
        }
    }

    /// The hardening part of the energy inner product, q·H⁻¹r (ξη/h in theory §1).
    fn hardening_inner(&self, q: &[f64], r: &[f64]) -> f64;

    /// Membership test (σ, q) ∈ D, with a tolerance relative to the material's stress scale.
    fn contains(&self, sigma: &Sym, q: &[f64], tol: f64) -> bool;

    /// Projection onto D in the energy metric (theory §2): (σ, q) is replaced by the point of D
    /// nearest in `[·,·]`. Returns true when the point was outside D.
    fn project(&self, law: &Elasticity, sigma: &mut Sym, q: &mut [f64]) -> bool;

    /// The local law (theory §2): σ̂ = P_D(Cε, 0), and its consistent tangent dσ/dε when asked.
    /// Returns true when the point is plastic (the trial was outside D).
    fn local_law(
        &self,
        law: &Elasticity,
        eps: &Sym,
        sigma: &mut Sym,
        q: &mut [f64],
        tangent: Option<&mut SymOp>,
    ) -> bool;

    /// The reduced energy density ψ(ε) = ε:σ − ½[σ̂, σ̂] at σ̂ = P_D(Cε, 0) (theory §2).
    /// Override with a closed form where one is known.
    fn energy(&self, law: &Elasticity, eps: &Sym) -> f64 {
        let mut sigma = Sym::zeros();
        let mut q = [0.0; MAX_HARDENING_DIM];
        let q = &mut q[..self.hardening_dim()];
        self.local_law(law, eps, &mut sigma, q, None);
        eps.dot(&sigma) - 0.5 * (law.compliance(&sigma).dot(&sigma) + self.hardening_inner(q, q))
    }

    /// D as second-order cones, for conic solvers; `None` if D has no such description.
    fn cone(&self) -> Option<ConeDescription> {
        None
    }

    /// Why D has no second-order-cone description, when [`AdmissibleStresses::cone`] is
    /// `None`: conic solvers quote it in their error (Tresca: polyhedral in principal stresses,
    /// which needs semidefinite cones).
    fn cone_unavailable(&self) -> String {
        "it has no second-order-cone description".to_string()
    }

    /// Warnings about the parameters that are legal but delicate (e.g. h = 0: the solution
    /// need not be unique, theory §1).
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }
}

dyn_clone::clone_trait_object!(AdmissibleStresses);

/// The energy inner product [σ̂, τ̂] = Aσ:τ + q·H⁻¹r at one point (theory §1).
pub fn energy_inner(
    p: Option<&dyn AdmissibleStresses>,
    law: &Elasticity,
    sigma: &Sym,
    q: &[f64],
    tau: &Sym,
    r: &[f64],
) -> f64 {
    law.compliance(sigma).dot(tau) + p.map_or(0.0, |p| p.hardening_inner(q, r))
}
