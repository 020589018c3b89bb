//! Tresca with linear isotropic hardening (theory §9.2): D = {(σ, ξ) : σ₁ − σ₃ ≤ σ₀ + ξ}
//! (principal stresses σ₁ ≥ σ₂ ≥ σ₃), hardening metric ξη/h.
//!
//! D is isotropic and so is A, so the projection of (σ, ξ) in the metric `Aσ:τ + ξη/h` keeps the
//! principal directions of σ and its mean stress, and moves the sorted principal values
//! s₁ ≥ s₂ ≥ s₃ only (the projection of a sorted point onto a permutation-symmetric convex set is
//! sorted). On trace-free changes A is 1/(2G). Unsorted, D is the intersection of the six
//! half-spaces σᵢ − σⱼ ≤ σ₀ + ξ with normals n = eᵢ − eⱼ (in principal values); for a sorted
//! point at most the three of the sorted chamber are active:
//!
//! * a = (1,3), `n_a = e₁ − e₃`, the face;
//! * b = (2,3), `n_b = e₂ − e₃`, which meets a on the edge σ₁ = σ₂;
//! * c = (1,2), `n_c = e₁ − e₂`, which meets a on the edge σ₂ = σ₃.
//!
//! With active set S and t₀ = σ₀ + ξ, the KKT conditions of
//! `min |σ' − σ|²/(4G) + (ξ' − ξ)²/(2h)` s.t. the active constraints are
//! `σ' = σ − 2G Σ_k γ_k n_k`, `ξ' = ξ + h Σ_k γ_k`, `γ_k ≥ 0`, and the active constraints hold
//! with equality: `M γ = Δ` with `M_kl = 2G n_k·n_l + h` and `Δ_k = n_k·s − t₀`. Hence
//!
//! * **elastic** when `s₁ − s₃ ≤ t₀`;
//! * **face**: `γ = Δ_a/(4G + h)`, `σ₁ = s₁ − 2Gγ`, `σ₃ = s₃ + 2Gγ`, `σ₂ = s₂`, valid while
//!   `2Gγ ≤ min(s₁ − s₂, s₂ − s₃)`;
//! * **edge** σ₁ = σ₂ (when `2Gγ > s₁ − s₂`, the face would reorder σ₁ and σ₂): M =
//!   `[[4G + h, 2G + h], [2G + h, 4G + h]]`, det = 4G(3G + h),
//!   `γ_a = ((4G + h)Δ_a − (2G + h)Δ_b)/det`, `γ_b = ((4G + h)Δ_b − (2G + h)Δ_a)/det`,
//!   `γ_a + γ_b = (Δ_a + Δ_b)/(6G + 2h)`; σ₃ = s₃ + 2G(γ_a + γ_b), σ₁ = σ₂ = the rest of the
//!   trace. `γ_b > 0` is exactly the failure of the face's condition, and γ_a > 0 whenever the
//!   trial is outside; the edge σ₂ = σ₃ is the mirror image with c for b;
//! * **apex** (s = 0, ξ = −σ₀): the vertex of D, where all six constraints hold with equality.
//!   It is the projection iff `s/(2G) = Σ μ_ij (eᵢ − eⱼ)` with μ ≥ 0 and Σμ = −t₀/h; the least
//!   Σμ representing a trace-free s is `max(s₁, −s₃)` (a linear programme in the sorted chamber),
//!   so the apex is reached iff `h max(s₁ − m, m − s₃) + 2G t₀ ≤ 0` (m the mean stress). Only a
//!   general point with ξ < −σ₀ gets there.
//!
//! For h = 0 the metric is infinite in ξ, which is frozen: the same formulas with h = 0 and ξ
//! unchanged; if σ₀ + ξ < 0 the slice of D is empty and the point goes to the apex (s = 0,
//! ξ = −σ₀), the limit h → 0, as for von Mises.
//!
//! The local law is the projection of (Cε, 0) (t₀ = σ₀ > 0: never the apex). Its tangent is the
//! derivative of the isotropic tensor function σ(ε) = Σ σᵢ(ε₁, ε₂, ε₃) Eᵢ:
//! `Σ_ij ∂σᵢ/∂εⱼ Eᵢ⊗Eⱼ + Σ_{i<j} θ_ij N_ij⊗N_ij`, with Eᵢ the eigenprojections,
//! `N_ij = (vᵢ⊗vⱼ + vⱼ⊗vᵢ)/√2` and `θ_ij = (σᵢ − σⱼ)/(εᵢ − εⱼ) = 2G(σᵢ − σⱼ)/(sᵢ − sⱼ)`. In
//! principal values `∂σ/∂ε = C_p − (2G)² N M⁻¹ Nᵀ`, `C_p = λ 1⊗1 + 2G I`, N the active normals
//! as columns. On an edge σᵢ = σⱼ for the merged pair, so θ_ij = 0 and the rows and columns of
//! the pair in ∂σ/∂ε are equal: the tangent needs only Eᵢ + Eⱼ, which is well defined for
//! (nearly) repeated trial eigenvalues; it is the derivative inside the edge region (σ(ε) is
//! smooth there, also at exactly axisymmetric trials) and a generalised (semismooth) derivative
//! on the boundaries between regions.
//!
//! On an edge the exact tangent is singular along the merged pair's in-plane deviators (the
//! normal cone is two-dimensional: the flow moves freely between the two faces, and a body with
//! every element on the same edge has a zero-stiffness mechanism and a non-unique displacement),
//! so the tangent keeps a stiffness δ·2G there ([`Tresca::EDGE_REGULARISATION`]) for Newton's
//! Cholesky factorisation.
//!
//! ψ(ε) = ½Cε:ε − ½ dist²((Cε, 0), D) (Moreau), and dist² = γᵀMγ = γ·Δ, so
//! `ψ = ½Cε:ε − ½ Σ_k γ_k Δ_k`.
//!
//! The step law of theory §11.1 is the same return of the trial (C(ε − ε_p), ξ_n): t₀ = σ₀ + ξ_n
//! moves the faces, and the tangent formula is unchanged (it depends on the active normals, M
//! and the returned principal values only). Only ξ_n < −σ₀ (never an admissible state) reaches
//! the apex, where σ is the trial's mean stress and the tangent is `K_b I⊗I`.

use crate::hardening::{check_modulus, isotropic_inner};
use nalgebra::{Matrix3, Vector3};
use saddle_core::error::{ParameterError, check};
use saddle_core::problem::elasticity::Elasticity;
use saddle_core::problem::return_mapping::elastic_step;
use saddle_core::problem::stresses::{
    AdmissibleStresses, ConeDescription, PsdBlock, SemidefiniteDescription, StepInput, StepOutput,
};
use saddle_core::problem::tensor::{SQRT2, Sym, SymOp, from_matrix, identity, to_matrix, trace, volumetric_projector};
use serde::{Deserialize, Serialize};

/// Tresca yield with linear isotropic hardening (theory §9.2): `D = {σ₁ − σ₃ ≤ σ₀ + ξ}`,
/// `[σ̂, τ̂] = Aσ:τ + ξη/h`. Scene table: `type = "tresca"`, `sigma0`, `h`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tresca {
    /// Initial yield stress σ₀ > 0 of σ₁ − σ₃ (the uniaxial yield stress σ_y; the von Mises k₀
    /// of the same uniaxial yield is √(2/3) σ₀, of the same shear yield σ₀/√2).
    pub sigma0: f64,
    /// Hardening modulus h ≥ 0 of the metric ξη/h; h = 0 is perfect plasticity.
    pub h: f64,
}

/// Which part of D the return of [`Tresca::return_kind`] (or of a projection) lands on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TrescaReturn {
    /// The trial is in D: no return.
    Elastic,
    /// One-vector return onto the face σ₁ − σ₃ = σ₀ + ξ, principal values stay distinct.
    Face,
    /// Two-vector return onto an edge of the hexagon: σ₁ = σ₂ or σ₂ = σ₃ afterwards.
    Edge,
    /// The vertex s = 0, ξ = −σ₀ (only general points with ξ < −σ₀; never the local law).
    Apex,
}

/// The sorted principal values (descending) and the unit eigenvectors (columns, same order).
struct Principal {
    values: [f64; 3],
    vectors: Matrix3<f64>,
}

fn principal(s: &Sym) -> Principal {
    if !s.iter().all(|v| v.is_finite()) {
        // NaN propagates through the return instead of stalling the eigen-solver
        return Principal { values: [f64::NAN; 3], vectors: Matrix3::identity() };
    }
    let e = to_matrix(s).symmetric_eigen();
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&a, &b| e.eigenvalues[b].total_cmp(&e.eigenvalues[a]));
    let values = idx.map(|i| e.eigenvalues[i]);
    let vectors = Matrix3::from_columns(&idx.map(|i| e.eigenvectors.column(i).into_owned()));
    Principal { values, vectors }
}

/// A return in principal values: the kind, the returned sorted principal values, ξ, and the
/// active normals with their multipliers γ and constraint excesses Δ (for the tangent and ψ).
struct PrincipalReturn {
    kind: TrescaReturn,
    sigma: [f64; 3],
    xi: f64,
    normals: [[f64; 3]; 2],
    gamma: [f64; 2],
    delta: [f64; 2],
    n_active: usize,
}

const N_A: [f64; 3] = [1.0, 0.0, -1.0];
const N_B: [f64; 3] = [0.0, 1.0, -1.0];
const N_C: [f64; 3] = [1.0, -1.0, 0.0];

impl Tresca {
    /// The relative stiffness δ the tangent keeps on an edge along the two in-plane deviators of
    /// the merged principal pair (v₁⊗v₁ − v₂⊗v₂)/√2 and N₁₂ (for σ₁ = σ₂), where the exact
    /// derivative is zero: δ·2G times the projector onto them, which does not depend on the
    /// choice of eigenvectors in a repeated eigenspace. The normal cone of an edge is
    /// two-dimensional, so the flow may move freely between its two faces: a body whose every
    /// element sits on the same edge (homogeneous compression, theory §9.2) has a mechanism of
    /// zero tangent stiffness and the displacement is not unique, and Newton's Cholesky
    /// factorisation of the exact tangent fails. δ = 1e-8 is far below the conformance kit's
    /// finite-difference tolerance (1e-5 of C) and only perturbs Newton steps along directions in
    /// which σ(ε) does not change.
    pub const EDGE_REGULARISATION: f64 = 1e-8;

    /// Tresca with yield stress `sigma0` and hardening modulus `h`, validated (errors name
    /// `yield.sigma0`, `yield.h`).
    pub fn new(sigma0: f64, h: f64) -> Result<Self, ParameterError> {
        let p = Self { sigma0, h };
        p.validate("yield")?;
        Ok(p)
    }

    /// Where the local law at ε returns the trial (Cε, 0): elastic, face or edge (module docs).
    /// For tests and reports, e.g. counting the elements of a solution returned to an edge.
    pub fn return_kind(&self, law: &Elasticity, eps: &Sym) -> TrescaReturn {
        self.projection_kind(law, &law.stress(eps), &[0.0])
    }

    /// Where the projection of the general point (σ, q) lands.
    pub fn projection_kind(&self, law: &Elasticity, sigma: &Sym, q: &[f64]) -> TrescaReturn {
        let p = principal(sigma);
        self.principal_return(2.0 * law.shear_modulus(), &p.values, q[0]).kind
    }

    /// The return of sorted principal values `s` with hardening variable `xi` (module docs);
    /// `g2` = 2G.
    fn principal_return(&self, g2: f64, s: &[f64; 3], xi: f64) -> PrincipalReturn {
        let h = self.h;
        let t0 = self.sigma0 + xi;
        let [s1, s2, s3] = *s;
        let mut r = PrincipalReturn {
            kind: TrescaReturn::Elastic,
            sigma: *s,
            xi,
            normals: [N_A, N_A],
            gamma: [0.0; 2],
            delta: [0.0; 2],
            n_active: 0,
        };
        if s1 - s3 <= t0 {
            return r;
        }
        let m = (s1 + s2 + s3) / 3.0;
        if h * (s1 - m).max(m - s3) + g2 * t0 <= 0.0 {
            r.kind = TrescaReturn::Apex;
            r.sigma = [m; 3];
            r.xi = -self.sigma0;
            return r;
        }
        let (da, db, dc) = (s1 - s3 - t0, s2 - s3 - t0, s1 - s2 - t0);
        let (m11, m12) = (2.0 * g2 + h, g2 + h);
        let det = g2 * (3.0 * g2 + 2.0 * h);
        let gamma_b = (m11 * db - m12 * da) / det;
        let gamma_c = (m11 * dc - m12 * da) / det;
        let sum_b = (da + db) / (3.0 * g2 + 2.0 * h);
        let sum_c = (da + dc) / (3.0 * g2 + 2.0 * h);
        if gamma_b > 0.0 && t0 + h * sum_b >= 0.0 {
            // edge σ₁ = σ₂: faces a and b
            let s3n = s3 + g2 * sum_b;
            let top = 0.5 * (s1 + s2) - 0.5 * g2 * sum_b;
            r.kind = TrescaReturn::Edge;
            r.sigma = [top, top, s3n];
            r.xi = xi + h * sum_b;
            r.normals = [N_A, N_B];
            r.gamma = [sum_b - gamma_b, gamma_b];
            r.delta = [da, db];
            r.n_active = 2;
        } else if gamma_c > 0.0 && t0 + h * sum_c >= 0.0 {
            // edge σ₂ = σ₃: faces a and c
            let s1n = s1 - g2 * sum_c;
            let bottom = 0.5 * (s2 + s3) + 0.5 * g2 * sum_c;
            r.kind = TrescaReturn::Edge;
            r.sigma = [s1n, bottom, bottom];
            r.xi = xi + h * sum_c;
            r.normals = [N_A, N_C];
            r.gamma = [sum_c - gamma_c, gamma_c];
            r.delta = [da, dc];
            r.n_active = 2;
        } else {
            let gamma = da / m11;
            r.kind = TrescaReturn::Face;
            r.sigma = [s1 - g2 * gamma, s2, s3 + g2 * gamma];
            r.xi = xi + h * gamma;
            r.gamma = [gamma, 0.0];
            r.delta = [da, 0.0];
            r.n_active = 1;
        }
        r
    }

    /// σ − Σᵢ (sᵢ − σᵢ') vᵢ⊗vᵢ: the trial with its principal values corrected (trace-free
    /// correction, so the mean stress is kept up to round-off).
    fn rebuild(sigma: &Sym, p: &Principal, new: &[f64; 3]) -> Sym {
        let mut out = *sigma;
        for (i, (old, new)) in p.values.iter().zip(new).enumerate() {
            let c = old - new;
            if c != 0.0 {
                let v = p.vectors.column(i);
                out -= from_matrix(&(v * v.transpose())) * c;
            }
        }
        out
    }

    /// The consistent (generalised on region boundaries) tangent of the local law at a plastic
    /// return `r` of the trial with principal decomposition `p` (module docs).
    fn tangent(&self, law: &Elasticity, p: &Principal, r: &PrincipalReturn) -> SymOp {
        let h = self.h;
        let g2 = 2.0 * law.shear_modulus();
        let lame = law.bulk_modulus() - g2 / 3.0;
        // ∂σ/∂ε in principal values: C_p − (2G)² N M⁻¹ Nᵀ
        let mut d = Matrix3::from_element(lame) + Matrix3::identity() * g2;
        let n: Vec<Vector3<f64>> = r.normals[..r.n_active].iter().map(|v| Vector3::from(*v)).collect();
        match r.n_active {
            1 => d -= n[0] * n[0].transpose() * (g2 * g2 / (2.0 * g2 + h)),
            2 => {
                let m = nalgebra::Matrix2::new(
                    g2 * n[0].dot(&n[0]) + h,
                    g2 * n[0].dot(&n[1]) + h,
                    g2 * n[1].dot(&n[0]) + h,
                    g2 * n[1].dot(&n[1]) + h,
                );
                let mi = m.try_inverse().expect("the edge matrix is positive definite");
                for k in 0..2 {
                    for l in 0..2 {
                        d -= n[k] * n[l].transpose() * (g2 * g2 * mi[(k, l)]);
                    }
                }
            }
            _ => {}
        }
        // the merged pair of an edge: zero stiffness on its in-plane deviators, regularised
        let merged = match r.kind {
            TrescaReturn::Edge if r.normals[1] == N_B => Some((0, 1)),
            TrescaReturn::Edge => Some((1, 2)),
            _ => None,
        };
        let reg = Self::EDGE_REGULARISATION * g2;
        if let Some((i, j)) = merged {
            d[(i, i)] += 0.5 * reg;
            d[(j, j)] += 0.5 * reg;
            d[(i, j)] -= 0.5 * reg;
            d[(j, i)] -= 0.5 * reg;
        }
        let v = &p.vectors;
        let e: [Sym; 3] = std::array::from_fn(|i| from_matrix(&(v.column(i) * v.column(i).transpose())));
        let mut t = SymOp::zeros();
        for i in 0..3 {
            for j in 0..3 {
                t += e[i] * e[j].transpose() * d[(i, j)];
            }
        }
        for (i, j) in [(0, 1), (0, 2), (1, 2)] {
            let (ds, dn) = (p.values[i] - p.values[j], r.sigma[i] - r.sigma[j]);
            let theta = if merged == Some((i, j)) {
                reg
            } else if dn == 0.0 {
                0.0
            } else if ds > 0.0 {
                (g2 * dn / ds).clamp(0.0, g2)
            } else {
                g2
            };
            let a = v.column(i) * v.column(j).transpose();
            let nij = from_matrix(&(a + a.transpose())) / SQRT2;
            t += nij * nij.transpose() * theta;
        }
        t
    }
}

#[typetag::serde(name = "tresca")]
impl AdmissibleStresses for Tresca {
    /// σ₀ > 0 with σ₀ ≤ [`check::MAX_MAGNITUDE`]; h ≥ 0, 0 or a scale in [1e-50, 1e50]
    /// ([`check::scale`]: 1/h enters the hardening metric), so that the solvers' products stay
    /// finite.
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::positive(path, "sigma0", self.sigma0)?;
        check::bounded(path, "sigma0", self.sigma0)?;
        check_modulus(path, self.h)?;
        Ok(())
    }

    /// ξ, the isotropic hardening variable.
    fn hardening_fields(&self) -> Vec<(&'static str, usize)> {
        vec![("xi", 1)]
    }

    /// One hardening variable, ξ.
    fn hardening_dim(&self) -> usize {
        1
    }

    /// ξη/h. For h = 0 the metric is infinite in ξ: 0 when ξη = 0, else ±∞ with the sign of ξη.
    fn hardening_inner(&self, q: &[f64], r: &[f64]) -> f64 {
        isotropic_inner(self.h, q[0], r[0])
    }

    /// `σ₁ − σ₃ ≤ σ₀ + ξ + tol · max(σ₀, |σ|, |ξ|)`: the tolerance is relative to the largest
    /// stress magnitude involved, floored at the smallest positive normal number. With tol = 0
    /// it is exactly the test [`AdmissibleStresses::project`] uses to leave a point in place.
    fn contains(&self, sigma: &Sym, q: &[f64], tol: f64) -> bool {
        let xi = q[0];
        let v = principal(sigma).values;
        let scale = self.sigma0.max(sigma.norm()).max(xi.abs()).max(f64::MIN_POSITIVE);
        v[0] - v[2] <= self.sigma0 + xi + tol * scale
    }

    /// Projection onto D in the energy metric for a general point (σ, ξ): elastic, face, edge
    /// or apex return of the principal values (module docs), principal directions and mean
    /// stress kept. For h = 0 ξ is frozen, and the apex is reached iff σ₀ + ξ ≤ 0.
    fn project(&self, law: &Elasticity, sigma: &mut Sym, q: &mut [f64]) -> bool {
        let p = principal(sigma);
        let r = self.principal_return(2.0 * law.shear_modulus(), &p.values, q[0]);
        match r.kind {
            TrescaReturn::Elastic => return false,
            TrescaReturn::Apex => *sigma = identity() * (trace(sigma) / 3.0),
            _ => *sigma = Self::rebuild(sigma, &p, &r.sigma),
        }
        q[0] = r.xi;
        true
    }

    /// σ̂ = P_D(C(ε − ε_p), ξ_n) (theory §11.1): the local law's return of the trial
    /// C(ε − ε_p) with ξ_n (frozen for h = 0), and its tangent, which depends only on the
    /// return's geometry; at the apex (only from ξ_n < −σ₀) σ is the trial's mean stress and the
    /// tangent `K_b I⊗I`.
    fn step_law(&self, law: &Elasticity, step: StepInput<'_>, mut out: StepOutput<'_>) -> bool {
        let q_n = step.q_n;
        let trial = law.stress(&step.elastic_strain());
        let p = principal(&trial);
        let r = self.principal_return(2.0 * law.shear_modulus(), &p.values, q_n[0]);
        match r.kind {
            TrescaReturn::Elastic => return elastic_step(law, trial, q_n, out),
            TrescaReturn::Apex => {
                *out.sigma = identity() * (trace(&trial) / 3.0);
                out.set_tangent(|| volumetric_projector() * (3.0 * law.bulk_modulus()));
            }
            _ => {
                *out.sigma = Self::rebuild(&trial, &p, &r.sigma);
                out.set_tangent(|| self.tangent(law, &p, &r));
            }
        }
        out.q[0] = if self.h > 0.0 || r.kind == TrescaReturn::Apex { r.xi } else { q_n[0] };
        true
    }

    /// `ψ(ε) = ½Cε:ε − ½ Σ_k γ_k Δ_k` (module docs): the face gives `Δ_a²/(4G + h)`.
    fn energy(&self, law: &Elasticity, eps: &Sym) -> f64 {
        let trial = law.stress(eps);
        let p = principal(&trial);
        let r = self.principal_return(2.0 * law.shear_modulus(), &p.values, 0.0);
        let dist2: f64 = (0..r.n_active).map(|k| r.gamma[k] * r.delta[k]).sum();
        0.5 * eps.dot(&trial) - 0.5 * dist2
    }

    /// None: D is polyhedral in the principal stresses, see
    /// [`AdmissibleStresses::cone_unavailable`].
    fn cone(&self) -> Option<ConeDescription> {
        None
    }

    /// The semidefinite form (theory §13.1): (σ, ξ) ∈ D iff ∃a: σ − aI ⪰ 0 and
    /// (a + σ₀ + ξ)I − σ ⪰ 0 — all principal stresses in [a, a + σ₀ + ξ], a spread σ₁ − σ₃ ≤ σ₀ + ξ.
    /// Two 3 × 3 blocks on (σ, ξ, a); Mandel's √2 on shears is the blocks' √2 off the diagonal.
    fn semidefinite_cone(&self) -> Option<SemidefiniteDescription> {
        // the Mandel component of each entry of the scaled upper triangle (X₁₁, √2X₁₂, X₂₂, …)
        const MANDEL: [usize; 6] = [0, 5, 1, 4, 3, 2];
        const DIAGONAL: [bool; 6] = [true, false, true, false, false, true];
        let block = |sign: f64, offset: f64| {
            let mut map = vec![0.0; 6 * 8];
            for (r, (&m, &diag)) in MANDEL.iter().zip(&DIAGONAL).enumerate() {
                map[8 * r + m] = sign;
                if diag {
                    map[8 * r + 6] = (sign < 0.0) as usize as f64; // ξ widens the upper bound
                    map[8 * r + 7] = -sign; // a
                }
            }
            let offset = DIAGONAL.iter().map(|&d| if d { offset } else { 0.0 }).collect();
            PsdBlock { n: 3, offset, map }
        };
        Some(SemidefiniteDescription { auxiliary: 1, blocks: vec![block(1.0, 0.0), block(-1.0, self.sigma0)] })
    }

    /// D is a hexagonal prism in principal-stress space, not an intersection of second-order
    /// cones; as a set of tensors it is semidefinite-representable.
    fn cone_unavailable(&self) -> String {
        "Tresca's yield set σ₁ − σ₃ ≤ σ₀ + ξ is polyhedral in the principal stresses (a hexagonal \
         prism), not an intersection of second-order cones: a conic solver would need semidefinite \
         cones (∃a: aI ⪯ σ ⪯ (a + σ₀ + ξ)I)"
            .to_string()
    }

    /// h = 0 (perfect plasticity): the solution need not be unique. Also with h > 0 the
    /// displacements need not be unique where stresses sit on an edge (two-dimensional normal
    /// cone), which is not warned about: stresses and hardening are unique.
    fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if self.h == 0.0 {
            w.push(
                "yield.h = 0 (perfect plasticity): the solution need not be unique and displacements may be \
                 discontinuous (theory §1, Theorem 1); stresses are still determined"
                    .to_string(),
            );
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::conformance::{self, KitConfig, names};
    use crate::mutant::Mutant;
    use crate::testing::{assert_tangent_by_differences, law};
    use nalgebra::Matrix3;
    use std::sync::{Arc, Mutex};

    /// E = 100, ν = 1/4: 2G = 80, λ = 40, 3K_b = 200.
    fn hand_law() -> Elasticity {
        Elasticity::new(100.0, 0.25).unwrap()
    }

    /// The rotation of the hand-worked points: a 3-4-5 turn about e₃.
    fn rot() -> Matrix3<f64> {
        Matrix3::new(0.6, -0.8, 0.0, 0.8, 0.6, 0.0, 0.0, 0.0, 1.0)
    }

    fn turned(d: [f64; 3]) -> Sym {
        let q = rot();
        from_matrix(&(q * Matrix3::from_diagonal(&Vector3::from(d)) * q.transpose()))
    }

    /// A face return worked by hand. E = 100, ν = 1/4 (2G = 80, λ = 40), σ₀ = 4, h = 40, so
    /// 4G + h = 200. Principal trial stresses (6, 1, −4) (strains εᵢ = (σᵢ − ν(σⱼ + σₖ))/E =
    /// (0.0675, 0.005, −0.0575)), turned by a 3-4-5 rotation about e₃:
    ///
    /// * Δ = s₁ − s₃ − σ₀ = 10 − 4 = 6, γ = 6/200 = 0.03, 2Gγ = 2.4 ≤ min(s₁ − s₂, s₂ − s₃) = 5:
    ///   a face return;
    /// * σ = (6 − 2.4, 1, −4 + 2.4) = (3.6, 1, −1.6), ξ = hγ = 1.2, σ₁ − σ₃ = 5.2 = σ₀ + ξ;
    /// * ψ = ½ε:σᵗʳ − ½γΔ = ½(0.405 + 0.005 + 0.23) − ½ · 0.18 = 0.32 − 0.09 = 0.23.
    ///
    /// An edge return worked by hand, same material: trial (6, 4, −4) (strains (0.06, 0.035,
    /// −0.065)):
    ///
    /// * the face would give 2Gγ = 2.4 > s₁ − s₂ = 2: edge σ₁ = σ₂; Δ_a = 6, Δ_b = 4,
    ///   det = 4G(3G + h) = 160 · 160 = 25600, γ_a = (200 · 6 − 120 · 4)/25600 = 0.028125,
    ///   γ_b = (200 · 4 − 120 · 6)/25600 = 0.003125, γ_a + γ_b = 10/320 = 0.03125;
    /// * σ₁ = 6 − 80 · 0.028125 = 3.75 = σ₂ = 4 − 80 · 0.003125, σ₃ = −4 + 80 · 0.03125 = −1.5,
    ///   ξ = 40 · 0.03125 = 1.25, σ₁ − σ₃ = 5.25 = σ₀ + ξ, tr σ = 6 unchanged;
    /// * ψ = ½(0.36 + 0.14 + 0.26) − ½(0.028125 · 6 + 0.003125 · 4) = 0.38 − 0.090625 = 0.289375.
    #[test]
    fn face_and_edge_returns_match_points_worked_by_hand() {
        let law = hand_law();
        let t = Tresca::new(4.0, 40.0).unwrap();
        let near = |a: f64, b: f64| (a - b).abs() <= 1e-13;
        let same = |a: &Sym, b: &Sym| (a - b).amax() <= 1e-13;
        for (strain, expected, xi, psi, kind) in [
            ([0.0675, 0.005, -0.0575], [3.6, 1.0, -1.6], 1.2, 0.23, TrescaReturn::Face),
            ([0.06, 0.035, -0.065], [3.75, 3.75, -1.5], 1.25, 0.289375, TrescaReturn::Edge),
        ] {
            let eps = turned(strain);
            let (mut s, mut q, mut c) = (Sym::zeros(), [0.0], SymOp::zeros());
            assert!(t.local_law(&law, &eps, StepOutput::new(&mut s, &mut q, Some(&mut c))), "{kind:?}: plastic");
            assert_eq!(t.return_kind(&law, &eps), kind);
            assert!(
                same(&s, &turned(expected)),
                "{kind:?}: σ = {}, by hand {}",
                to_matrix(&s),
                to_matrix(&turned(expected))
            );
            assert!(near(q[0], xi), "{kind:?}: ξ = {}, by hand {xi}", q[0]);
            assert!(near(t.energy(&law, &eps), psi), "{kind:?}: ψ = {}, by hand {psi}", t.energy(&law, &eps));
            // the general projection of (Cε, 0) is the same point
            let (mut s2, mut q2) = (law.stress(&eps), [0.0]);
            assert!(t.project(&law, &mut s2, &mut q2) && same(&s2, &s) && near(q2[0], xi));
            assert!((c - c.transpose()).amax() < 1e-10);
            if kind == TrescaReturn::Edge {
                // the exact tangent has zero stiffness across the merged pair (the deviator
                // v₁⊗v₁ − v₂⊗v₂ and the shear of v₁, v₂ leave σ unchanged on the edge): only the
                // regularisation δ·2G remains
                let (v1, v2) = (rot().column(0).into_owned(), rot().column(1).into_owned());
                let split = from_matrix(&(v1 * v1.transpose() - v2 * v2.transpose()));
                let shear = from_matrix(&(v1 * v2.transpose() + v2 * v1.transpose())) / SQRT2;
                let reg = Tresca::EDGE_REGULARISATION * 2.0 * law.shear_modulus();
                assert!((c * split - split * reg).amax() < 1e-11, "{}", c * split);
                assert!((c * shear - shear * reg).amax() < 1e-11, "{}", c * shear);
            }
        }
        // below yield: trial (2, 1, −1), s₁ − s₃ = 3 ≤ 4
        let eps = turned([0.02, 0.0075, -0.0175]);
        assert_eq!(t.return_kind(&law, &eps), TrescaReturn::Elastic);
        let (mut s, mut q) = (Sym::zeros(), [0.0]);
        assert!(!t.local_law(&law, &eps, StepOutput::new(&mut s, &mut q, None)) && same(&s, &turned([2.0, 1.0, -1.0])));
    }

    #[test]
    fn projection_of_general_points() {
        let law = law();
        let g2 = 2.0 * law.shear_modulus();
        let t = Tresca::new(1.0, 5.0).unwrap();
        // inside, with ξ > 0: unchanged
        let inside = turned([1.2, 0.5, 0.0]);
        let (mut s, mut q) = (inside, [0.3]);
        assert!(!t.project(&law, &mut s, &mut q) && s == inside && q[0] == 0.3);
        // face with ξ = 0.5: Δ = 3 − 1.5, γ = 1.5/(2·2G + h)
        let (mut s, mut q) = (turned([2.0, 0.5, -1.0]), [0.5]);
        assert_eq!(t.projection_kind(&law, &s, &q), TrescaReturn::Face);
        assert!(t.project(&law, &mut s, &mut q));
        let gamma = 1.5 / (2.0 * g2 + 5.0);
        assert!((s - turned([2.0 - g2 * gamma, 0.5, -1.0 + g2 * gamma])).amax() < 1e-14);
        assert!((q[0] - 0.5 - 5.0 * gamma).abs() < 1e-14);
        // apex: ξ = −1.5, h max(s₁ − m, m − s₃) + 2G t₀ = 5 · 2 − 0.5 · 2G ≤ 0
        let (mut s, mut q) = (turned([3.0, 0.0, -1.0]) + identity() * 0.5, [-1.5]);
        assert_eq!(t.projection_kind(&law, &s, &q), TrescaReturn::Apex);
        assert!(t.project(&law, &mut s, &mut q));
        assert!((s - identity() * (2.0 / 3.0 + 0.5)).amax() < 1e-14 && q[0] == -1.0);
        // ξ < −σ₀ but not the apex: ξ = −1.02, t₀ = −0.02, 5 · 2 − 0.02 · 2G > 0
        let (mut s, mut q) = (turned([3.0, 0.0, -1.0]), [-1.02]);
        assert_ne!(t.projection_kind(&law, &s, &q), TrescaReturn::Apex);
        assert!(t.project(&law, &mut s, &mut q) && t.contains(&s, &q, 1e-12) && q[0] > -1.0);
        // h = 0: ξ frozen; apex iff σ₀ + ξ ≤ 0
        let pp = Tresca::new(1.0, 0.0).unwrap();
        let (mut s, mut q) = (turned([3.0, 0.0, -1.0]), [0.25]);
        assert!(pp.project(&law, &mut s, &mut q) && q[0] == 0.25);
        let v = principal(&s).values;
        assert!((v[0] - v[2] - 1.25).abs() < 1e-14);
        let (mut s, mut q) = (turned([3.0, 0.0, -1.0]), [-1.25]);
        assert!(pp.project(&law, &mut s, &mut q) && q[0] == -1.0);
        assert!((s - identity() * (2.0 / 3.0)).amax() < 1e-14);
        assert!(pp.hardening_inner(&[0.0], &[3.0]) == 0.0 && pp.hardening_inner(&[2.0], &[3.0]) == f64::INFINITY);
        assert!(t.hardening_inner(&[2.0], &[3.0]) == 1.2);
    }

    /// Counts of the kinds of the returns the kit's samples reach: of the local law (row 0), of
    /// projections of general points (row 1) and of the step law (row 2).
    type Counts = Arc<Mutex<[[usize; 4]; 3]>>;

    /// `t`, counting the kinds of its returns into `counts`.
    fn counting(t: Tresca, counts: &Counts) -> Mutant {
        let count = |c: &Counts, row: usize, k: TrescaReturn| c.lock().unwrap()[row][k as usize] += 1;
        let (c0, c1, c2) = (counts.clone(), counts.clone(), counts.clone());
        Mutant::of(t)
            .with_project(move |_, law, sigma, q| {
                count(&c1, 1, t.projection_kind(law, sigma, q));
                t.project(law, sigma, q)
            })
            .with_local_law(move |_, law, eps, out| {
                count(&c0, 0, t.return_kind(law, eps));
                t.local_law(law, eps, out)
            })
            .with_step_law(move |_, law, step, out| {
                count(&c2, 2, t.projection_kind(law, &law.stress(&step.elastic_strain()), step.q_n));
                t.step_law(law, step, out)
            })
    }

    #[test]
    fn kit_passes_for_several_parameter_sets_and_reaches_faces_and_edges() {
        for &(sigma0, h) in &[(1.0f64, 5.0), (1.0, 0.0), (1.0, 1e-4), (0.5, 2000.0), (2.0, 30.0)] {
            let cfg = KitConfig::new(law(), sigma0).with_samples(150).with_seed(7);
            let counts = Counts::default();
            if let Err(e) = conformance::check_all(&counting(Tresca::new(sigma0, h).unwrap(), &counts), &cfg) {
                panic!("σ₀ = {sigma0}, h = {h}: {e}");
            }
            let [law_counts, proj_counts, step_counts] = *counts.lock().unwrap();
            println!(
                "σ₀ = {sigma0}, h = {h}: kit's local law elastic/face/edge/apex {law_counts:?}, projections \
                 {proj_counts:?}, step law {step_counts:?}"
            );
            let [elastic, face, edge, apex] = law_counts;
            assert!(elastic >= 100 && face >= 100 && edge >= 100 && apex == 0, "local law: {law_counts:?}");
            let [elastic, face, edge, apex] = proj_counts;
            assert!(elastic >= 100 && face >= 100 && edge >= 100 && apex >= 10, "projections: {proj_counts:?}");
            let [elastic, face, edge, _] = step_counts;
            assert!(elastic >= 100 && face >= 100 && edge >= 100, "step law: {step_counts:?}");
        }
        for seed in 0..4 {
            let cfg = KitConfig::new(law(), 1.0).with_seed(seed);
            for h in [5.0, 0.0] {
                conformance::check_all(&Tresca::new(1.0, h).unwrap(), &cfg)
                    .unwrap_or_else(|e| panic!("seed {seed}, h = {h}: {e}"));
            }
        }
        let cfg = KitConfig::new(Elasticity::new(210e3, 0.49).unwrap(), 300.0).with_samples(150).with_seed(3);
        conformance::check_all(&Tresca::new(300.0, 1e3).unwrap(), &cfg).unwrap();
    }

    /// Ways to get the edge return wrong.
    #[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
    enum Breakage {
        /// Always the one-vector (face) return, also where it reorders the principal values.
        AlwaysFace,
        /// Lands on the right edge point of σ but with the face's ξ = hΔ_a/(4G + h), σ₃ then set
        /// so that σ₁ − σ₃ = σ₀ + ξ: in D and idempotent, not nearest.
        EdgeWithFaceHardening,
        /// Right stresses, but the face's tangent on edges (the merged pair's θ and the second
        /// multiplier ignored).
        EdgeWithFaceTangent,
    }

    /// `t` with its edge return broken as `how` says.
    fn broken(t: Tresca, how: Breakage) -> Mutant {
        let m = Mutant::of(t);
        if how == Breakage::EdgeWithFaceTangent {
            return m.with_local_law(move |_, law, eps, out| {
                let plastic = t.local_law(law, eps, StepOutput::new(out.sigma, out.q, None));
                if let Some(tg) = out.tangent {
                    let trial = law.stress(eps);
                    let p = principal(&trial);
                    let mut r = t.principal_return(2.0 * law.shear_modulus(), &p.values, 0.0);
                    *tg = law.stiffness_matrix();
                    if r.kind != TrescaReturn::Elastic {
                        if r.kind == TrescaReturn::Edge {
                            r.n_active = 1;
                            r.sigma[1] = p.values[1];
                        }
                        *tg = t.tangent(law, &p, &r);
                    }
                }
                plastic
            });
        }
        m.with_project(move |_, law, sigma, q| {
            let g2 = 2.0 * law.shear_modulus();
            let p = principal(sigma);
            let r = t.principal_return(g2, &p.values, q[0]);
            if r.kind != TrescaReturn::Edge {
                return t.project(law, sigma, q);
            }
            let [s1, s2, s3] = p.values;
            let da = s1 - s3 - t.sigma0 - q[0];
            let gamma = da / (2.0 * g2 + t.h);
            let xi = q[0] + t.h * gamma;
            let new = match how {
                Breakage::AlwaysFace => [s1 - g2 * gamma, s2, s3 + g2 * gamma],
                _ => {
                    // keep the edge's shape and the trace, with the face's ξ (not below −σ₀)
                    let top = (t.sigma0 + xi).max(0.0);
                    q[0] = top - t.sigma0;
                    if r.sigma[0] == r.sigma[1] {
                        let upper = (s1 + s2 + s3 + top) / 3.0;
                        [upper, upper, upper - top]
                    } else {
                        let bottom = (s1 + s2 + s3 - top) / 3.0;
                        [bottom + top, bottom, bottom]
                    }
                }
            };
            *sigma = Tresca::rebuild(sigma, &p, &new);
            if how == Breakage::AlwaysFace {
                q[0] = xi;
            }
            true
        })
        .with_local_law(|m, law, eps, out| m.local_law_from_projection(law, eps, out))
    }

    #[test]
    fn kit_catches_wrong_edge_returns() {
        let cfg = KitConfig::new(law(), 1.0).with_samples(150);
        // with h = 0 ξ is frozen and the edge point is fixed by the trace and σ₁ − σ₃ = σ₀ + ξ
        // alone: the "face's ξ" is then the right one and that copy is not broken
        for (how, name, hs) in [
            (Breakage::AlwaysFace, names::PROJECTION_IN_SET, &[5.0, 0.0][..]),
            (Breakage::EdgeWithFaceHardening, names::VARIATIONAL_INEQUALITY, &[5.0][..]),
            (Breakage::EdgeWithFaceTangent, names::TANGENT, &[5.0, 0.0][..]),
        ] {
            for &h in hs {
                let e = conformance::check_all(&broken(Tresca::new(1.0, h).unwrap(), how), &cfg).unwrap_err();
                println!("{how:?}, h = {h}: {e}");
                assert_eq!(e.check, name, "{how:?}, h = {h}: {e}");
            }
        }
        conformance::check_all(&broken(Tresca::new(1.0, 0.0).unwrap(), Breakage::EdgeWithFaceHardening), &cfg).unwrap();
        conformance::check_all(&Tresca::new(1.0, 5.0).unwrap(), &cfg).unwrap();
    }

    /// Load steps from the state the face return of
    /// `face_and_edge_returns_match_points_worked_by_hand` leaves (theory §11.1): E = 100,
    /// ν = 1/4 (2G = 80), σ₀ = 4, h = 40, plastic strain ε_p = γ n_a = (0.03, 0, −0.03) and
    /// ξ_n = hγ = 1.2, so t₀ = 5.2. Principal trial stresses C(ε − ε_p), all turned by the 3-4-5
    /// rotation:
    ///
    /// * (6, 1, −4): Δ = 10 − 5.2 = 4.8, γ = 4.8/(4G + h) = 0.024, 2Gγ = 1.92 ≤ 5: face,
    ///   σ = (4.08, 1, −2.08), ξ = 1.2 + 40 · 0.024 = 2.16 (σ₁ − σ₃ = 6.16 = σ₀ + ξ);
    /// * (6, 4.5, −4): the face would give 2Gγ = 1.92 > s₁ − s₂ = 1.5: edge σ₁ = σ₂ with
    ///   Δ_a = 4.8, Δ_b = 3.3, γ_a + γ_b = 8.1/320 = 0.0253125; σ₃ = −4 + 2.025 = −1.975,
    ///   σ₁ = σ₂ = 5.25 − 1.0125 = 4.2375, ξ = 1.2 + 1.0125 = 2.2125 (σ₁ − σ₃ = 6.2125);
    /// * (5, 1, −0.1): s₁ − s₃ = 5.1 ≤ 5.2, elastic (the local law, t₀ = 4, is plastic);
    /// * h = 0, (6, 1, −4): ξ stays 1.2, γ = 4.8/4G = 0.03, σ = (3.6, 1, −1.6);
    /// * ξ_n = −7 (not admissible): h max(s₁ − m, m − s₃) + 2G t₀ = 200 − 240 ≤ 0, the apex
    ///   σ = I (the mean stress 1), ξ = −σ₀ = −4, tangent K_b I⊗I.
    #[test]
    fn step_law_from_a_hardened_state_worked_by_hand() {
        let law = hand_law();
        let t = Tresca::new(4.0, 40.0).unwrap();
        let near = |a: f64, b: f64| (a - b).abs() <= 1e-13;
        let same = |a: &Sym, b: &Sym| (a - b).amax() <= 1e-13;
        let ep = turned([0.03, 0.0, -0.03]);
        // ε with the principal trial stresses `trial` from the state
        let strain = |trial: [f64; 3]| ep + law.compliance(&turned(trial));
        let (mut s, mut q, mut c) = (Sym::zeros(), [0.0], SymOp::zeros());
        for (trial, expected, xi, kind) in [
            ([6.0, 1.0, -4.0], [4.08, 1.0, -2.08], 2.16, TrescaReturn::Face),
            ([6.0, 4.5, -4.0], [4.2375, 4.2375, -1.975], 2.2125, TrescaReturn::Edge),
        ] {
            let eps = strain(trial);
            assert_eq!(t.projection_kind(&law, &turned(trial), &[1.2]), kind);
            assert!(
                t.step_law(&law, StepInput::new(&eps, &ep, &[1.2]), StepOutput::new(&mut s, &mut q, Some(&mut c))),
                "{kind:?}"
            );
            assert!(same(&s, &turned(expected)), "{kind:?}: σ = {}", to_matrix(&s));
            assert!(near(q[0], xi), "{kind:?}: ξ = {}, by hand {xi}", q[0]);
            // the projection of the trial, and the tangent by differences of the projection
            let (mut s3, mut q3) = (law.stress(&(eps - ep)), [1.2]);
            assert!(t.project(&law, &mut s3, &mut q3) && same(&s3, &s) && near(q3[0], xi));
            assert_tangent_by_differences(&t, &law, StepInput::new(&eps, &ep, &[1.2]), &c);
        }
        // hardened: elastic from the state, plastic for the local law at the same ε − ε_p
        let eps = strain([5.0, 1.0, -0.1]);
        assert!(!t.step_law(&law, StepInput::new(&eps, &ep, &[1.2]), StepOutput::new(&mut s, &mut q, Some(&mut c))));
        assert!(same(&s, &turned([5.0, 1.0, -0.1])) && q[0] == 1.2 && c == law.stiffness_matrix());
        assert!(t.local_law(&law, &(eps - ep), StepOutput::new(&mut s, &mut q, None)));
        // h = 0: ξ frozen
        let pp = Tresca::new(4.0, 0.0).unwrap();
        let eps = strain([6.0, 1.0, -4.0]);
        assert!(pp.step_law(&law, StepInput::new(&eps, &ep, &[1.2]), StepOutput::new(&mut s, &mut q, Some(&mut c))));
        assert!(same(&s, &turned([3.6, 1.0, -1.6])) && q[0] == 1.2, "σ = {}, ξ = {}", to_matrix(&s), q[0]);
        assert_tangent_by_differences(&pp, &law, StepInput::new(&eps, &ep, &[1.2]), &c);
        // the apex from ξ_n = −7
        assert!(t.step_law(&law, StepInput::new(&eps, &ep, &[-7.0]), StepOutput::new(&mut s, &mut q, Some(&mut c))));
        assert!(same(&s, &identity()) && q[0] == -4.0, "σ = {}, ξ = {}", to_matrix(&s), q[0]);
        assert!((c - volumetric_projector() * 200.0).amax() <= 1e-12, "{c}");
    }

    #[test]
    fn energy_equals_the_primal_form_at_the_returned_plastic_strain() {
        // ψ(ε) = min_p ½C(ε−p):(ε−p) + σ₀ D(p) + ½h D(p)², with D(p) = max(p₁, −p₃) the
        // support function of the hexagon {σᵢ − σⱼ ≤ 1} (theory §9.2), attained at the plastic
        // strain p = ε − Aσ = Σ γ_k n_k of the return, where D(p) = Σγ.
        let law = law();
        let g2 = 2.0 * law.shear_modulus();
        let cm = law.stiffness_matrix();
        for &(sigma0, h) in &[(1.0, 5.0), (1.0, 0.0), (0.5, 40.0)] {
            let t = Tresca::new(sigma0, h).unwrap();
            for eps in [turned([0.03, 0.0, -0.02]), turned([0.02, 0.02, -0.03]), turned([0.03, -0.01, -0.01])] {
                let trial = law.stress(&eps);
                let p = principal(&trial);
                let r = t.principal_return(g2, &p.values, 0.0);
                let gsum = r.gamma[0] + r.gamma[1];
                let (mut s, mut q) = (Sym::zeros(), [0.0]);
                t.local_law(&law, &eps, StepOutput::new(&mut s, &mut q, None));
                let pl = eps - law.compliance(&s);
                let e = eps - pl;
                let primal = 0.5 * e.dot(&(cm * e)) + sigma0 * gsum + 0.5 * h * gsum * gsum;
                assert!((primal - t.energy(&law, &eps)).abs() < 1e-12, "{primal} vs {}", t.energy(&law, &eps));
                let pv = principal(&pl).values;
                assert!((pv[0].max(-pv[2]) - gsum).abs() < 1e-14, "D(p) = {}, Σγ = {gsum}", pv[0].max(-pv[2]));
            }
        }
    }

    #[test]
    fn validation_warnings_cone_and_toml() {
        let ok = Tresca::new(1.0, 5.0).unwrap();
        assert!(ok.validate("yield").is_ok() && ok.warnings().is_empty());
        let e = Tresca::new(0.0, 5.0).unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), ("yield.sigma0", "0"));
        assert!(e.to_string().contains("> 0"), "{e}");
        let e = Tresca::new(1.0, -0.5).unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), ("yield.h", "-0.5"));
        let e = Tresca::new(f64::NAN, 5.0).unwrap_err();
        assert!(e.field == "yield.sigma0" && e.to_string().contains("finite"), "{e}");
        let e = Tresca::new(1.0, f64::INFINITY).unwrap_err();
        assert_eq!(e.field, "yield.h");
        let w = Tresca::new(1.0, 0.0).unwrap().warnings();
        assert!(w.len() == 1 && w[0].contains("yield.h = 0") && w[0].contains("unique"), "{w:?}");
        assert!(ok.cone().is_none());
        semidefinite_blocks_bound_the_principal_spread(&ok);
        let why = ok.cone_unavailable();
        assert!(why.contains("polyhedral") && why.contains("semidefinite"), "{why}");
        assert_eq!(ok.hardening_fields(), vec![("xi", 1)]);

        let p: Box<dyn AdmissibleStresses> = toml::from_str("type = \"tresca\"\nsigma0 = 2.0\nh = 5.0").unwrap();
        assert_eq!(p.name(), "tresca");
        assert!(p.hardening_inner(&[1.0], &[1.0]) == 0.2);
        // uniaxial σ₁₁ = 2 is on the surface, 2.01 outside; pure shear τ = 1 is on it too
        assert!(p.contains(&Sym::new(2.0, 0.0, 0.0, 0.0, 0.0, 0.0), &[0.0], 0.0));
        assert!(!p.contains(&Sym::new(2.01, 0.0, 0.0, 0.0, 0.0, 0.0), &[0.0], 0.0));
        assert!(p.contains(&Sym::new(0.0, 0.0, 0.0, 0.999 * SQRT2, 0.0, 0.0), &[0.0], 0.0));
        assert!(!p.contains(&Sym::new(0.0, 0.0, 0.0, 1.001 * SQRT2, 0.0, 0.0), &[0.0], 0.0));
        let back: Box<dyn AdmissibleStresses> = toml::from_str(&toml::to_string(&p).unwrap()).unwrap();
        assert_eq!(format!("{back:?}"), format!("{p:?}"));
        let err = toml::from_str::<Box<dyn AdmissibleStresses>>("type = \"tresca\"\nsigma0 = 1.0\nh = 5.0\nk0 = 1.0")
            .unwrap_err();
        assert!(err.to_string().contains("unknown field"), "{err}");
        assert!(toml::from_str::<Box<dyn AdmissibleStresses>>("type = \"tresca\"\nsigma0 = 1.0").is_err());
    }

    /// The two blocks of [`Tresca::semidefinite_cone`] at a point (σ, ξ) and auxiliary a: their
    /// smallest eigenvalues are those of σ − aI and (a + σ₀ + ξ)I − σ, from the principal stresses.
    fn semidefinite_blocks_bound_the_principal_spread(t: &Tresca) {
        let d = t.semidefinite_cone().unwrap();
        assert_eq!((d.auxiliary, d.blocks.len()), (1, 2));
        let matrix = |v: &[f64]| {
            let s = 1.0 / SQRT2;
            Matrix3::new(v[0], s * v[1], s * v[3], s * v[1], v[2], s * v[4], s * v[3], s * v[4], v[5])
        };
        let smallest = |sigma: &Sym, xi: f64, a: f64| -> [f64; 2] {
            let z: Vec<f64> = sigma.iter().copied().chain([xi, a]).collect();
            std::array::from_fn(|k| {
                let b = &d.blocks[k];
                let v: Vec<f64> =
                    (0..6).map(|r| b.offset[r] + (0..8).map(|j| b.map[8 * r + j] * z[j]).sum::<f64>()).collect();
                matrix(&v).symmetric_eigenvalues().min()
            })
        };
        // a rotated tensor with principal stresses 1, 0.5, −0.9: σ − aI has the eigenvalues
        // σᵢ − a, (a + σ₀ + ξ)I − σ the eigenvalues a + σ₀ + ξ − σᵢ
        let r = nalgebra::Rotation3::from_euler_angles(0.3, -0.7, 1.1);
        let m = r.matrix() * Matrix3::from_diagonal(&Vector3::new(1.0, 0.5, -0.9)) * r.matrix().transpose();
        let sigma = from_matrix(&m);
        let [lo, hi] = smallest(&sigma, 0.25, -0.9);
        assert!((lo - 0.0).abs() < 1e-12 && (hi - (-0.9 + t.sigma0 + 0.25 - 1.0)).abs() < 1e-12, "{lo} {hi}");
    }
}
