//! **P** — the admissible generalised stresses (theory §1, §2).
//!
//! A generalised stress σ̂ = (σ, q) is a stress σ (Mandel vector) and `hardening_dim()`
//! hardening variables q (one, ξ, for isotropic hardening). P = {τ̂ : τ̂(x) ∈ D a.e.} for a
//! closed convex set D, and the energy inner product is `[σ̂, τ̂] = Aσ:τ + q·H⁻¹r` with the
//! elastic compliance A and a hardening metric H⁻¹ (ξη/h for isotropic hardening).
//!
//! Everything a solver needs from P follows from the projection onto D in that metric: the
//! local law σ̂ = P_D(Cε, 0), its derivative (the consistent tangent) and the reduced energy
//! ψ(ε) = sup_{τ̂∈D} (ε:τ − ½[τ̂, τ̂]) with ∂ψ/∂ε = σ. A plugin provides the projection and the
//! law of a load step ([`AdmissibleStresses::step_law`], theory §11.1); the local law of the
//! stationary problem is the step law from the zero state. Implementations must pass the
//! conformance kit of `saddle-yield`.

use crate::error::ParameterError;
use crate::problem::elasticity::Elasticity;
use crate::problem::tensor::{Sym, SymOp};
use nalgebra::ArrayStorage;
use std::fmt::Debug;

/// Upper bound on `hardening_dim()`, so that hot loops keep q on the stack.
pub const MAX_HARDENING_DIM: usize = 8;

/// ε_p = 0 of the zero state.
static ZERO_STRAIN: Sym = Sym::from_array_storage(ArrayStorage([[0.0; 6]; 1]));
/// q_n = 0 of the zero state.
static ZERO_HARDENING: [f64; MAX_HARDENING_DIM] = [0.0; MAX_HARDENING_DIM];

/// What the law of a load step reads at one point (theory §11.1): the strain ε, and the
/// previous step's plastic strain ε_p and hardening variables q_n, whose trial is
/// (C(ε − ε_p), q_n).
#[derive(Clone, Copy, Debug)]
pub struct StepInput<'a> {
    /// ε.
    pub eps: &'a Sym,
    /// ε_p.
    pub plastic_strain: &'a Sym,
    /// q_n, `hardening_dim()` entries.
    pub q_n: &'a [f64],
}

impl<'a> StepInput<'a> {
    /// The strain `eps` from the state (`plastic_strain`, `q_n`).
    pub fn new(eps: &'a Sym, plastic_strain: &'a Sym, q_n: &'a [f64]) -> Self {
        Self { eps, plastic_strain, q_n }
    }

    /// The strain `eps` from the zero state ε_p = 0, q_n = 0 (`hardening_dim` zeros): the
    /// stationary problem's local law (theory §2).
    pub fn from_zero_state(eps: &'a Sym, hardening_dim: usize) -> Self {
        Self::new(eps, &ZERO_STRAIN, &ZERO_HARDENING[..hardening_dim])
    }

    /// True when ε_p = 0 and q_n = 0.
    pub fn is_zero_state(&self) -> bool {
        self.q_n.iter().all(|x| *x == 0.0) && self.plastic_strain.iter().all(|x| *x == 0.0)
    }

    /// ε − ε_p, the strain of the elastic trial.
    #[inline]
    pub fn elastic_strain(&self) -> Sym {
        self.eps - self.plastic_strain
    }
}

/// What a law writes at one point (theory §2, §11.1): the generalised stress σ̂ = (σ, q) and,
/// when asked, the consistent tangent dσ/dε.
#[derive(Debug)]
pub struct StepOutput<'a> {
    /// σ.
    pub sigma: &'a mut Sym,
    /// q, `hardening_dim()` entries.
    pub q: &'a mut [f64],
    /// dσ/dε, where asked.
    pub tangent: Option<&'a mut SymOp>,
}

impl<'a> StepOutput<'a> {
    /// σ into `sigma`, q into `q`, the tangent into `tangent` if given.
    pub fn new(sigma: &'a mut Sym, q: &'a mut [f64], tangent: Option<&'a mut SymOp>) -> Self {
        Self { sigma, q, tangent }
    }

    /// The tangent `f()`, computed only where it is asked for.
    #[inline]
    pub fn set_tangent(&mut self, f: impl FnOnce() -> SymOp) {
        if let Some(t) = self.tangent.as_deref_mut() {
            *t = f();
        }
    }
}

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

/// One positive-semidefinite block of a semidefinite description: `offset + map · (σ, q, a)` is
/// the scaled upper triangle of a symmetric n × n matrix that must be ⪰ 0 (stacked by columns,
/// off-diagonal entries times √2: for n = 3 `(X₁₁, √2X₁₂, X₂₂, √2X₁₃, √2X₂₃, X₃₃)`).
#[derive(Clone, Debug, PartialEq)]
pub struct PsdBlock {
    /// The matrix size n (the block has n(n + 1)/2 entries).
    pub n: usize,
    /// Constant part, n(n + 1)/2 entries.
    pub offset: Vec<f64>,
    /// Linear part, n(n + 1)/2 × (6 + hardening_dim + auxiliary) row-major, acting on (σ Mandel,
    /// q, the auxiliary variables a).
    pub map: Vec<f64>,
}

/// D as the projection of a set of semidefinite blocks: (σ, q) ∈ D iff some auxiliary
/// variables a make every block hold (theory §13.1: Tresca, ∃a: aI ⪯ σ ⪯ (a + σ₀)I).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SemidefiniteDescription {
    /// Number of auxiliary variables per point.
    pub auxiliary: usize,
    /// The blocks; D = {(σ, q) : ∃a, every block holds}.
    pub blocks: Vec<PsdBlock>,
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

    /// The law of a load step (theory §11.1) — the one law a plugin must provide:
    /// σ̂ = P_D(C(ε − ε_p), q_n), the projection of the trial built from the previous step's
    /// plastic strain ε_p and hardening variables q_n, and its consistent tangent dσ/dε when
    /// asked. Returns true when the trial was outside D. A plugin without a closed form may
    /// call [`step_law_by_differences`]; the return-mapping helpers of
    /// [`crate::problem::return_mapping`] hold the steps plugins share.
    fn step_law(&self, law: &Elasticity, step: StepInput<'_>, out: StepOutput<'_>) -> bool;

    /// The local law (theory §2): σ̂ = P_D(Cε, 0), and its consistent tangent dσ/dε when asked
    /// — the step law from the zero state. Returns true when the point is plastic.
    fn local_law(&self, law: &Elasticity, eps: &Sym, out: StepOutput<'_>) -> bool {
        self.step_law(law, StepInput::from_zero_state(eps, self.hardening_dim()), out)
    }

    /// The reduced energy density of a load step (theory §11.1),
    /// `ψ_n(ε) = (ε − ε_p):σ − ½Aσ:σ − ½(q − q_n)·H⁻¹(q − q_n)` at σ̂ = the step law's stresses.
    /// With ε_p = 0 and q_n = 0 it is [`AdmissibleStresses::energy`] (and calls it).
    fn step_energy(&self, law: &Elasticity, step: StepInput<'_>) -> f64 {
        if step.is_zero_state() {
            return self.energy(law, step.eps);
        }
        let mut sigma = Sym::zeros();
        let mut q = [0.0; MAX_HARDENING_DIM];
        let m = self.hardening_dim();
        self.step_law(law, step, StepOutput::new(&mut sigma, &mut q[..m], None));
        let dq: [f64; MAX_HARDENING_DIM] = std::array::from_fn(|k| if k < m { q[k] - step.q_n[k] } else { 0.0 });
        step.elastic_strain().dot(&sigma)
            - 0.5 * (law.compliance(&sigma).dot(&sigma) + self.hardening_inner(&dq[..m], &dq[..m]))
    }

    /// The reduced energy density ψ(ε) = ε:σ − ½[σ̂, σ̂] at σ̂ = P_D(Cε, 0) (theory §2).
    /// Override with a closed form where one is known.
    fn energy(&self, law: &Elasticity, eps: &Sym) -> f64 {
        let mut sigma = Sym::zeros();
        let mut q = [0.0; MAX_HARDENING_DIM];
        let q = &mut q[..self.hardening_dim()];
        self.local_law(law, eps, StepOutput::new(&mut sigma, q, None));
        eps.dot(&sigma) - 0.5 * (law.compliance(&sigma).dot(&sigma) + self.hardening_inner(q, q))
    }

    /// D as second-order cones, for conic solvers; `None` if D has no such description.
    fn cone(&self) -> Option<ConeDescription> {
        None
    }

    /// D as semidefinite blocks with auxiliary variables, for conic solvers with semidefinite
    /// cones (limit analysis, theory §13.1); `None` if D has none or has a second-order-cone one.
    fn semidefinite_cone(&self) -> Option<SemidefiniteDescription> {
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

/// The step law by projection, with the tangent by central differences (theory §11.1): for a
/// plugin without a closed form of [`AdmissibleStresses::step_law`]. The trial
/// T = (C(ε − ε_p), q_n) is projected; the tangent's column j is
/// `(P_σ(T + δ C e_j) − P_σ(T − δ C e_j)) / 2δ` with δ = 1e-6 · max(|ε − ε_p|, k/2G), k the
/// size of the projected stress. It is exact where the projection is smooth up to O(δ²) and
/// round-off ε_mach/δ, about 1e-8 relative: Newton then converges fast but not quadratically
/// below that. Plugins should give the step law's closed form where they know it.
pub fn step_law_by_differences(
    p: &(impl AdmissibleStresses + ?Sized),
    law: &Elasticity,
    step: StepInput<'_>,
    out: StepOutput<'_>,
) -> bool {
    let m = p.hardening_dim();
    let e = step.elastic_strain();
    let project = |e: &Sym, s: &mut Sym, q: &mut [f64]| {
        *s = law.stress(e);
        q[..m].copy_from_slice(&step.q_n[..m]);
        p.project(law, s, &mut q[..m])
    };
    let StepOutput { sigma, q, tangent } = out;
    let plastic = project(&e, sigma, q);
    if let Some(t) = tangent {
        if !plastic {
            *t = law.stiffness_matrix();
        } else {
            let scale = e.norm().max(sigma.norm() / (2.0 * law.shear_modulus())).max(f64::MIN_POSITIVE);
            let delta = 1e-6 * scale;
            let mut qs = [0.0; MAX_HARDENING_DIM];
            for j in 0..6 {
                let mut d = Sym::zeros();
                d[j] = delta;
                let (mut plus, mut minus) = (Sym::zeros(), Sym::zeros());
                project(&(e + d), &mut plus, &mut qs);
                project(&(e - d), &mut minus, &mut qs);
                let col = (plus - minus) / (2.0 * delta);
                t.set_column(j, &col);
            }
            // the tangent of a projection in the energy metric is C-symmetric: symmetrise the
            // differences' round-off away
            *t = (*t + t.transpose()) * 0.5;
        }
    }
    plastic
}

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
