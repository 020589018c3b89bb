//! Von Mises with linear isotropic hardening (theory §1–§2): D = {(σ, ξ) : |dev σ| ≤ k₀ + ξ},
//! hardening metric ξη/h.
//!
//! In the energy metric `Aσ:τ + ξη/h` the volumetric part of σ is orthogonal to everything D
//! constrains, and on deviators A is 1/(2G). With the scaled coordinates `x = s/√(2G)`,
//! `y = (k₀ + ξ)/√h`, D becomes the second-order cone `{|x| ≤ √(h/2G) y}` and the metric becomes
//! Euclidean, so the projection is the classical projection onto a cone. Written back in
//! (s, ξ): with `r = |dev σ|`, `t₀ = k₀ + ξ`, the KKT conditions of
//! `min |s' − s|²/(4G) + (ξ' − ξ)²/(2h)` s.t. `|s'| ≤ k₀ + ξ'` give `s' = s − 2Gλ n`,
//! `ξ' = ξ + hλ` with `n = s/r` and `λ = (r − t₀)/(2G + h) ≥ 0`, hence
//!
//! * inside when `r ≤ t₀`;
//! * on the cone when `t = (2G t₀ + h r)/(2G + h) > 0`: `s' = s t/r`, `ξ' = t − k₀`;
//! * at the apex (`s' = 0`, `ξ' = −k₀`) when `2G t₀ + h r ≤ 0`, i.e. `t₀ ≤ −h r/(2G)`.
//!
//! For ξ = 0 (the local law) `t₀ = k₀ ≥ 0`, the apex is never reached and
//! `t = (h r + 2G k₀)/(h + 2G)` is exactly theory §2.
//!
//! The step law of theory §11.1 projects the trial (C(ε − ε_p), ξ_n) of a load step: the same
//! return with `t₀ = k₀ + ξ_n` and `r = 2G|dev(ε − ε_p)|`, so its tangent is the local law's
//! with that t. The apex needs `ξ_n < −k₀`, which admissible states never have; there σ is the
//! trial's mean stress and the tangent is `K_b I⊗I`.

use crate::hardening::{check_modulus, isotropic_inner};
use saddle_core::error::{ParameterError, check};
use saddle_core::problem::elasticity::Elasticity;
use saddle_core::problem::return_mapping::{DeviatoricTrial, elastic_step, radial_tangent};
use saddle_core::problem::stresses::{AdmissibleStresses, ConeDescription, SocBlock, StepInput, StepOutput};
use saddle_core::problem::tensor::{Sym, deviator, identity, trace, volumetric_projector};
use serde::{Deserialize, Serialize};

/// Von Mises yield with linear isotropic hardening (theory §1): `D = {|dev σ| ≤ k₀ + ξ}`,
/// `[σ̂, τ̂] = Aσ:τ + ξη/h`. Scene table: `type = "von_mises"`, `k0`, `h`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VonMises {
    /// Initial yield radius k₀ ≥ 0 of |dev σ| (`k₀ = √(2/3) σ_y`; the paper scales k₀ = 1).
    pub k0: f64,
    /// Hardening modulus h ≥ 0 of the metric ξη/h (`H = 3h/2` in `σ_eq = σ_y + H ε̄_p`);
    /// h = 0 is perfect plasticity.
    pub h: f64,
}

impl VonMises {
    /// Von Mises with yield radius `k0` and hardening modulus `h`, validated (errors name
    /// `yield.k0`, `yield.h`).
    pub fn new(k0: f64, h: f64) -> Result<Self, ParameterError> {
        let p = Self { k0, h };
        p.validate("yield")?;
        Ok(p)
    }

    /// The orthonormal basis of the deviatoric subspace of Mandel space used by [`Self::cone`]:
    /// five unit vectors orthogonal to each other and to I, so `Σ_k (e_k·σ)² = |dev σ|²`.
    pub fn deviatoric_basis() -> [Sym; 5] {
        let a = std::f64::consts::FRAC_1_SQRT_2;
        let b = 1.0 / 6.0f64.sqrt();
        [
            Sym::new(a, -a, 0.0, 0.0, 0.0, 0.0),
            Sym::new(b, b, -2.0 * b, 0.0, 0.0, 0.0),
            Sym::new(0.0, 0.0, 0.0, 1.0, 0.0, 0.0),
            Sym::new(0.0, 0.0, 0.0, 0.0, 1.0, 0.0),
            Sym::new(0.0, 0.0, 0.0, 0.0, 0.0, 1.0),
        ]
    }
}

#[typetag::serde(name = "von_mises")]
impl AdmissibleStresses for VonMises {
    /// k₀ ≥ 0 with k₀ ≤ [`check::MAX_MAGNITUDE`]; h ≥ 0, either 0 (perfect plasticity) or a
    /// scale in [1e-50, 1e50] ([`check::scale`]: 1/h enters the hardening metric ξη/h), so that
    /// the solvers' products stay finite; not both 0 (a body that carries no deviatoric stress at
    /// all has no shear stiffness: its displacement is not determined).
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::non_negative(path, "k0", self.k0)?;
        check::bounded(path, "k0", self.k0)?;
        check_modulus(path, self.h)?;
        if self.k0 == 0.0 && self.h == 0.0 {
            return Err(ParameterError::new(
                format!("{path}.k0"),
                0,
                format!(
                    "with {path}.h = 0 the body carries no deviatoric stress at all (no resistance to shear, its \
                     displacement undetermined): give k0 > 0 or h > 0"
                ),
            ));
        }
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

    /// ξη/h (theory §1). For h = 0 the metric is infinite in ξ: 0 when ξη = 0, else ±∞ with
    /// the sign of ξη.
    fn hardening_inner(&self, q: &[f64], r: &[f64]) -> f64 {
        isotropic_inner(self.h, q[0], r[0])
    }

    /// `|dev σ| ≤ k₀ + ξ + tol · max(k₀, |σ|, |ξ|)`: the tolerance is relative to the largest
    /// stress magnitude involved (the size of the rounding errors of dev σ and of k₀ + ξ),
    /// floored at the smallest positive normal number.
    fn contains(&self, sigma: &Sym, q: &[f64], tol: f64) -> bool {
        let xi = q[0];
        let scale = self.k0.max(sigma.norm()).max(xi.abs()).max(f64::MIN_POSITIVE);
        deviator(sigma).norm() <= self.k0 + xi + tol * scale
    }

    /// Projection onto D in the energy metric (theory §2), for a general point (σ, ξ) — see the
    /// module docs for the derivation. The volumetric part is unchanged. For h = 0 ξ is frozen
    /// (infinite metric) and s is returned radially to |s| = k₀ + ξ; if k₀ + ξ < 0 the slice of
    /// D is empty and the point goes to the apex (s = 0, ξ = −k₀), the limit h → 0.
    fn project(&self, law: &Elasticity, sigma: &mut Sym, q: &mut [f64]) -> bool {
        let s = deviator(sigma);
        let r = s.norm();
        let t0 = self.k0 + q[0];
        if r <= t0 {
            return false;
        }
        let m = trace(sigma) / 3.0;
        let g2 = 2.0 * law.shear_modulus();
        let t = if self.h > 0.0 { (g2 * t0 + self.h * r) / (g2 + self.h) } else { t0 };
        if t <= 0.0 {
            // apex: 2G t₀ + h r ≤ 0 (h = 0: k₀ + ξ ≤ 0)
            *sigma = identity() * m;
            q[0] = -self.k0;
        } else {
            *sigma = identity() * m + s * (t / r);
            if self.h > 0.0 {
                q[0] = t - self.k0;
            }
        }
        true
    }

    /// theory §11.1 in closed form: σ̂ = P_D(C(ε − ε_p), ξ_n), the radial return of the module
    /// docs with `t₀ = k₀ + ξ_n`, and the consistent tangent
    /// `K_b I⊗I + 2G[(t/r)(I_dev − n⊗n) + h/(h+2G) n⊗n]` when on the cone (h = 0: ξ frozen, no
    /// n⊗n term), `K_b I⊗I` at the apex, C when elastic.
    fn step_law(&self, law: &Elasticity, step: StepInput<'_>, mut out: StepOutput<'_>) -> bool {
        let trial = DeviatoricTrial::new(law, &step);
        let DeviatoricTrial { g2, kb, s: s_tr, r, p } = trial;
        let q_n = step.q_n;
        let t0 = self.k0 + q_n[0];
        if r <= t0 {
            return elastic_step(law, trial.stress(), q_n, out);
        }
        let t = if self.h > 0.0 { (g2 * t0 + self.h * r) / (g2 + self.h) } else { t0 };
        if t <= 0.0 {
            // apex: 2G t₀ + h r ≤ 0 (h = 0: k₀ + ξ_n ≤ 0), only from ξ_n < −k₀
            *out.sigma = identity() * p;
            out.q[0] = -self.k0;
            out.set_tangent(|| volumetric_projector() * (3.0 * kb));
            return true;
        }
        *out.sigma = s_tr * (t / r) + identity() * p;
        out.q[0] = if self.h > 0.0 { t - self.k0 } else { q_n[0] };
        out.set_tangent(|| radial_tangent(kb, &(s_tr / r), g2 * t / r, g2 * self.h / (self.h + g2)));
        true
    }

    /// `ψ(ε) = ½Cε:ε − (2G|dev ε| − k₀)₊² / (2(2G + h))` (theory §2).
    fn energy(&self, law: &Elasticity, eps: &Sym) -> f64 {
        let g2 = 2.0 * law.shear_modulus();
        let over = (g2 * deviator(eps).norm() - self.k0).max(0.0);
        0.5 * eps.dot(&law.stress(eps)) - over * over / (2.0 * (g2 + self.h))
    }

    /// One second-order cone of dimension 6 (theory §3): `t = k₀ + ξ`, `x = (e_k·σ)_{k=1..5}`
    /// in the orthonormal deviatoric basis [`VonMises::deviatoric_basis`], so `|x| = |dev σ|`.
    /// The map is 6 × 7 row-major on (σ Mandel, ξ).
    fn cone(&self) -> Option<ConeDescription> {
        let mut offset = vec![0.0; 6];
        offset[0] = self.k0;
        let mut map = vec![0.0; 6 * 7];
        map[6] = 1.0;
        for (k, e) in Self::deviatoric_basis().iter().enumerate() {
            for j in 0..6 {
                map[(k + 1) * 7 + j] = e[j];
            }
        }
        Some(ConeDescription { blocks: vec![SocBlock { dim: 6, offset, map }] })
    }

    /// h = 0 (perfect plasticity): the solution need not be unique (theory §1, Theorem 1).
    fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if self.h == 0.0 {
            w.push(format!(
                "yield.h = 0 (perfect plasticity): the solution need not be unique and displacements may be \
                 discontinuous (theory §1, Theorem 1); stresses are still determined{}",
                if self.k0 == 0.0 { ", but with k0 = 0 the deviatoric stress vanishes identically" } else { "" }
            ));
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::conformance::{self, KitConfig};
    use crate::testing::{assert_tangent_by_differences, close, law};
    use saddle_core::problem::tensor::SymOp;

    /// The hand-checkable case of the theory §2 radial return (theory §2). Every expected number
    /// below is a short decimal worked out by hand from E, ν, k₀, h and the trial strain:
    ///
    /// * E = 100, ν = 1/4: G = E/(2(1+ν)) = 40, so 2G = 80; 3K_b = E/(1−2ν) = 200.
    /// * k₀ = 1, h = 20, so h + 2G = 100.
    /// * Trial strain ε = 0.01 I + 0.025 M with M = [[1,0,0],[0,−1,1],[0,1,0]]: tr M = 0 and
    ///   |M|² = 1 + 1 + 1 + 1 = 4, so |M| = 2. In components
    ///   ε = [[0.035, 0, 0], [0, −0.015, 0.025], [0, 0.025, 0.01]], tr ε = 0.03, dev ε = 0.025 M.
    /// * s_tr = 2G dev ε = 80 · 0.025 M = 2 M, r = |s_tr| = 4 > k₀ = 1: plastic.
    ///   tr σ_tr = 3K_b tr ε = 200 · 0.03 = 6.
    /// * t = (h r + 2G k₀)/(h + 2G) = (20·4 + 80·1)/100 = 1.6;
    ///   ξ = h (r − k₀)/(h + 2G) = 20 · 3/100 = 0.6 (= t − k₀).
    /// * s = s_tr t/r = 2M · 0.4 = 0.8 M; tr σ = tr σ_tr = 6, so σ = 0.8 M + 2 I
    ///   = [[2.8, 0, 0], [0, 1.2, 0.8], [0, 0.8, 2.0]].
    /// * p = (s_tr − s)/(2G) = 1.2 M/80 = 0.015 M, |p| = 0.03 = (r − k₀)/(h + 2G); h|p| = 0.6 = ξ;
    ///   |s| = 0.8 · 2 = 1.6 = k₀ + ξ.
    /// * ψ(ε) = ½ Cε:ε − (r − k₀)²/(2(2G + h)) with Cε:ε = s_tr:dev ε + tr σ_tr tr ε/3
    ///   = 2 · 0.025 · |M|² + 6 · 0.03/3 = 0.2 + 0.06 = 0.26, so ψ = 0.13 − 9/200 = 0.085.
    /// * Below yield: ε' = 0.01 I + 0.005 M gives s_tr = 0.4 M, r = 0.8 ≤ k₀: σ = 0.4 M + 2 I
    ///   = [[2.4, 0, 0], [0, 1.6, 0.4], [0, 0.4, 2.0]], ξ = 0.
    #[test]
    fn local_law_matches_a_radial_return_worked_by_hand() {
        use nalgebra::Matrix3;
        use saddle_core::problem::tensor::{from_matrix, to_matrix};
        let law = Elasticity::new(100.0, 0.25).unwrap();
        let vm = VonMises::new(1.0, 20.0).unwrap();
        let mm = Matrix3::new(1.0, 0.0, 0.0, 0.0, -1.0, 1.0, 0.0, 1.0, 0.0);
        let eps = from_matrix(&Matrix3::new(0.035, 0.0, 0.0, 0.0, -0.015, 0.025, 0.0, 0.025, 0.01));
        // every expected value is O(1); the inputs carry decimal rounding of ~1e-16
        let tol = 1e-13;
        let near = |a: f64, b: f64| (a - b).abs() <= tol;
        let same = |a: &Matrix3<f64>, b: &Matrix3<f64>| (a - b).abs().max() <= tol;

        let (mut s, mut q) = (Sym::zeros(), [0.0]);
        assert!(vm.local_law(&law, &eps, StepOutput::new(&mut s, &mut q, None)), "r = 4 > k0 = 1: plastic");
        let sigma = to_matrix(&s);
        let expected = Matrix3::new(2.8, 0.0, 0.0, 0.0, 1.2, 0.8, 0.0, 0.8, 2.0);
        assert!(same(&sigma, &expected), "σ = {sigma}, by hand {expected}");
        assert!(near(q[0], 0.6), "ξ = {}, by hand 0.6", q[0]);
        assert!(near(trace(&s), 6.0), "tr σ = {}, by hand 6", trace(&s));
        assert!(near(deviator(&s).norm(), 1.6), "|s| = {}, by hand 1.6 = k0 + ξ", deviator(&s).norm());
        // the plastic strain p = ε − Aσ (its deviator: tr p = 0), by hand 0.015 M
        let p = to_matrix(&(eps - law.compliance(&s)));
        assert!(same(&p, &(mm * 0.015)), "p = {p}, by hand 0.015 M");
        assert!(near(q[0], 20.0 * p.norm()), "ξ = h|p| = 20 · 0.03");
        assert!(near(vm.energy(&law, &eps), 0.085), "ψ = {}, by hand 0.085", vm.energy(&law, &eps));

        // the general projection of (σ_tr, 0) = (2M + 2I, 0) gives the same point
        let (mut s2, mut q2) = (from_matrix(&(mm * 2.0 + Matrix3::identity() * 2.0)), [0.0]);
        assert!(vm.project(&law, &mut s2, &mut q2));
        assert!(same(&to_matrix(&s2), &expected) && near(q2[0], 0.6), "P_D(σ_tr, 0) = ({s2}, {})", q2[0]);

        // below yield the law is linear elastic: σ = 0.4 M + 2 I, ξ = 0
        let small = from_matrix(&(Matrix3::identity() * 0.01 + mm * 0.005));
        assert!(!vm.local_law(&law, &small, StepOutput::new(&mut s, &mut q, None)), "r = 0.8 ≤ k0 = 1: elastic");
        let elastic = Matrix3::new(2.4, 0.0, 0.0, 0.0, 1.6, 0.4, 0.0, 0.4, 2.0);
        assert!(same(&to_matrix(&s), &elastic) && q[0] == 0.0, "σ = {}, ξ = {}", to_matrix(&s), q[0]);
        assert!(
            near(vm.energy(&law, &small), 0.5 * (0.4 * 0.005 * 4.0 + 0.06)),
            "ψ = ½Cε:ε = ½(0.4 · 0.005 · 4 + 0.06) = 0.034"
        );
    }

    #[test]
    fn energy_equals_primal_minimum_over_plastic_strains() {
        // ψ(ε) = min_p ½C(ε−p):(ε−p) + k0|p| + ½h|p|², p deviatoric, minimised numerically.
        let law = law();
        let cmat = law.stiffness_matrix();
        for &(k0, h) in &[(1.0, 5.0), (1.0, 0.0), (0.3, 40.0), (0.0, 2.0)] {
            let vm = VonMises::new(k0, h).unwrap();
            for eps in [
                Sym::new(0.03, -0.01, -0.01, 0.0, 0.0, 0.0),
                Sym::new(0.004, 0.001, -0.002, 0.01, -0.003, 0.002),
                Sym::new(0.001, 0.0, 0.0, 0.0, 0.0, 0.0),
            ] {
                let primal = |p: &Sym| {
                    let e = eps - p;
                    0.5 * e.dot(&(cmat * e)) + k0 * p.norm() + 0.5 * h * p.norm_squared()
                };
                let d = deviator(&eps);
                let n = d / d.norm();
                // golden-section search over p = α n, α ∈ [0, |dev ε|]
                let (mut a, mut b) = (0.0, d.norm());
                let phi = (5.0f64.sqrt() - 1.0) / 2.0;
                for _ in 0..200 {
                    let (c, dd) = (b - phi * (b - a), a + phi * (b - a));
                    if primal(&(n * c)) < primal(&(n * dd)) {
                        b = dd;
                    } else {
                        a = c;
                    }
                }
                let alpha = 0.5 * (a + b);
                let best = primal(&(n * alpha));
                let psi = vm.energy(&law, &eps);
                assert!(close(psi, best, 1e-12), "k0={k0} h={h}: closed form {psi} vs primal {best}");
                // α is the plastic strain magnitude |p| = (r − k0)₊/(h + 2G) of theory §2
                let r = 2.0 * law.shear_modulus() * d.norm();
                let expected = (r - k0).max(0.0) / (h + 2.0 * law.shear_modulus());
                assert!((alpha - expected).abs() < 1e-7 * d.norm(), "α = {alpha}, expected {expected}");
                // other deviatoric directions do not do better
                for dir in [Sym::new(1.0, -1.0, 0.0, 0.0, 0.0, 0.0), Sym::new(0.0, 0.0, 0.0, 1.0, 1.0, -1.0)] {
                    let dir = deviator(&dir) * (1e-3 * d.norm());
                    assert!(primal(&(n * alpha + dir)) >= best - 1e-12 * best.abs());
                }
                // and ψ = ε:σ − ½[σ̂, σ̂]
                let (mut s, mut q) = (Sym::zeros(), [0.0]);
                vm.local_law(&law, &eps, StepOutput::new(&mut s, &mut q, None));
                let dual = eps.dot(&s) - 0.5 * (law.compliance(&s).dot(&s) + vm.hardening_inner(&q, &q));
                assert!(close(psi, dual, 1e-12), "{psi} vs {dual}");
            }
        }
    }

    #[test]
    fn projection_of_general_points() {
        let law = law();
        let g2 = 2.0 * law.shear_modulus();
        let vm = VonMises::new(1.0, 5.0).unwrap();
        let dir = deviator(&Sym::new(1.0, 0.2, -0.5, 0.3, 0.0, -0.4));
        let dir = dir / dir.norm();
        let vol = identity() * 0.7;

        // inside: unchanged, false
        let (mut s, mut q) = (vol + dir * 1.2, [0.5]);
        assert!(!vm.project(&law, &mut s, &mut q));
        assert_eq!((s, q[0]), (vol + dir * 1.2, 0.5));

        // onto the cone with ξ ≠ 0: r = 3, t0 = k0 + ξ = 1.5
        let (mut s, mut q) = (vol + dir * 3.0, [0.5]);
        assert!(vm.project(&law, &mut s, &mut q));
        let t = (g2 * 1.5 + 5.0 * 3.0) / (g2 + 5.0);
        assert!(close(deviator(&s).norm(), t, 1e-14) && close(q[0], t - 1.0, 1e-14));
        assert!(close(deviator(&s).norm(), 1.0 + q[0], 1e-14), "on the boundary");
        assert!((deviator(&s) / t - dir).norm() < 1e-14, "radial");
        assert!(close(trace(&s), 2.1, 1e-14), "volumetric part unchanged");
        // λ equal in both parts: (r − |s'|)/(2G) = (ξ' − ξ)/h
        assert!(close((3.0 - t) / g2, (q[0] - 0.5) / 5.0, 1e-12));

        // ξ < −k0 but still on the cone: t0 = −0.05 > −h r/(2G) = −5·3/76.9
        let (mut s, mut q) = (vol + dir * 3.0, [-1.05]);
        assert!(vm.project(&law, &mut s, &mut q));
        let t = (g2 * -0.05 + 15.0) / (g2 + 5.0);
        assert!(t > 0.0 && close(deviator(&s).norm(), t, 1e-13) && close(q[0], t - 1.0, 1e-13));

        // apex: t0 = −0.5 ≤ −h r/(2G) ≈ −0.195
        let (mut s, mut q) = (vol + dir * 3.0, [-1.5]);
        assert!(vm.project(&law, &mut s, &mut q));
        assert_eq!(deviator(&s).norm(), 0.0);
        assert_eq!(q[0], -1.0);
        assert!(close(trace(&s), 2.1, 1e-14));
        // the apex is the nearest point: the segment to any point of D makes an obtuse angle
        let y = (dir * 0.4, 0.0); // |s| = 0.4 ≤ k0 + 0, no volumetric part
        let ip = law.compliance(&(vol + dir * 3.0 - s)).dot(&(y.0 - s)) + (-1.5 - q[0]) * (y.1 - q[0]) / 5.0;
        assert!(ip <= 0.0, "{ip}");

        // h = 0: ξ frozen, radial return to k0 + ξ; apex when k0 + ξ < 0
        let pp = VonMises::new(1.0, 0.0).unwrap();
        let (mut s, mut q) = (vol + dir * 3.0, [0.25]);
        assert!(pp.project(&law, &mut s, &mut q));
        assert!(close(deviator(&s).norm(), 1.25, 1e-14) && q[0] == 0.25);
        let (mut s, mut q) = (vol + dir * 3.0, [-1.25]);
        assert!(pp.project(&law, &mut s, &mut q));
        assert!(deviator(&s).norm() == 0.0 && q[0] == -1.0);
        let (mut s, mut q) = (vol + dir * 1.1, [0.25]);
        assert!(!pp.project(&law, &mut s, &mut q));
        assert!(pp.hardening_inner(&[0.0], &[3.0]) == 0.0 && pp.hardening_inner(&[2.0], &[3.0]) == f64::INFINITY);
        assert!(vm.hardening_inner(&[2.0], &[3.0]) == 1.2);
    }

    #[test]
    fn projection_with_zero_xi_is_the_local_law() {
        let law = law();
        let vm = VonMises::new(1.0, 5.0).unwrap();
        let eps = Sym::new(0.02, -0.005, 0.001, 0.004, -0.002, 0.003);
        let (mut s1, mut q1) = (Sym::zeros(), [0.0]);
        let plastic = vm.local_law(&law, &eps, StepOutput::new(&mut s1, &mut q1, None));
        let (mut s2, mut q2) = (law.stress(&eps), [0.0]);
        assert!(plastic && vm.project(&law, &mut s2, &mut q2));
        assert!((s1 - s2).norm() < 1e-13 * s1.norm() && (q1[0] - q2[0]).abs() < 1e-14);
        assert!(q1[0] > 0.02, "clearly plastic: ξ = {}", q1[0]);
    }

    /// The consistent tangent on the hand-worked point of
    /// `local_law_matches_a_radial_return_worked_by_hand` (E = 100, ν = 1/4, k₀ = 1, h = 20,
    /// 2G = 80, 3K_b = 200, r = 4, t = 1.6): along n = M/|M| the deviatoric stiffness is
    /// 2G h/(h + 2G) = 80 · 20/100 = 16; across it (any deviator m ⟂ n) 2G t/r = 80 · 0.4 = 32;
    /// on I it is 3K_b = 200; below yield it is C.
    #[test]
    fn tangent_is_c_when_elastic_and_hardening_modulus_along_n() {
        use nalgebra::Matrix3;
        use saddle_core::problem::tensor::from_matrix;
        let law = Elasticity::new(100.0, 0.25).unwrap();
        let vm = VonMises::new(1.0, 20.0).unwrap();
        let mm = Matrix3::new(1.0, 0.0, 0.0, 0.0, -1.0, 1.0, 0.0, 1.0, 0.0);
        let eps = from_matrix(&(Matrix3::identity() * 0.01 + mm * 0.025));
        let (mut s, mut q, mut c) = (Sym::zeros(), [0.0], SymOp::zeros());
        vm.local_law(&law, &eps, StepOutput::new(&mut s, &mut q, Some(&mut c)));
        let n = from_matrix(&(mm * 0.5));
        let near = |a: f64, b: f64| (a - b).abs() <= 1e-12;
        assert!(near(n.dot(&(c * n)), 16.0), "n:C_t:n = {}, by hand 16", n.dot(&(c * n)));
        assert!(near(identity().dot(&(c * identity())) / 3.0, 200.0), "I:C_t:I/3, by hand 3K_b = 200");
        // m = diag(1, 1, −2)/√6: deviatoric, |m| = 1, m:M = 1 − 1 + 0 = 0
        let m = Sym::new(1.0, 1.0, -2.0, 0.0, 0.0, 0.0) / 6.0f64.sqrt();
        assert!(m.dot(&n).abs() < 1e-15 && trace(&m) == 0.0);
        assert!(near(m.dot(&(c * m)), 32.0), "m:C_t:m = {}, by hand 32", m.dot(&(c * m)));
        // a shear direction orthogonal to M (the 1–2 shear, Mandel component 5) is also 32
        let w = Sym::new(0.0, 0.0, 0.0, 0.0, 0.0, 1.0);
        assert!(near(w.dot(&(c * w)), 32.0) && near(n.dot(&(c * m)), 0.0));
        assert!((c - c.transpose()).norm() < 1e-12);
        vm.local_law(&law, &(eps * 0.1), StepOutput::new(&mut s, &mut q, Some(&mut c)));
        assert_eq!(c, law.stiffness_matrix());
    }

    /// A load step from a hardened state worked by hand (theory §11.1). E = 100, ν = 1/4
    /// (2G = 80, 3K_b = 200), k₀ = 1, h = 20, M = [[1,0,0],[0,−1,1],[0,1,0]] (tr M = 0, |M| = 2):
    ///
    /// * state ε_p = 0.0125 M, ξ_n = h|ε_p| = 20 · 0.025 = 0.5, so t₀ = k₀ + ξ_n = 1.5;
    /// * ε = 0.01 I + 0.05 M: ε − ε_p = 0.01 I + 0.0375 M, s_tr = 80 · 0.0375 M = 3M, r = 6,
    ///   tr σ = 200 · 0.03 = 6;
    /// * t = (2G t₀ + h r)/(2G + h) = (120 + 120)/100 = 2.4, ξ = t − k₀ = 1.4,
    ///   σ = 3M · 2.4/6 + 2I = 1.2M + 2I = [[3.2, 0, 0], [0, 0.8, 1.2], [0, 1.2, 2]];
    /// * the new plastic strain ε − Aσ = 0.05M − 1.2M/80 = 0.035M, and h|0.035M| = 1.4 = ξ;
    /// * tangent: along n = M/2 2G h/(2G + h) = 16, across 2G t/r = 32, on I 3K_b = 200.
    ///
    /// From the same state the trial s_tr = 0.72M (r = 1.44 ∈ (k₀, k₀ + ξ_n]) is elastic, though
    /// the local law at that strain is plastic. With h = 0 ξ stays 0.5: |s| = t₀ = 1.5,
    /// σ = 0.75M + 2I, tangent 0 along n and 2G t₀/r = 20 across. With ξ_n = −3 (not admissible)
    /// 2G t₀ + h r = −160 + 120 ≤ 0: the apex σ = 2I, ξ = −k₀ = −1, tangent K_b I⊗I.
    #[test]
    fn step_law_from_a_hardened_state_worked_by_hand() {
        use nalgebra::Matrix3;
        use saddle_core::problem::tensor::{from_matrix, to_matrix};
        let law = Elasticity::new(100.0, 0.25).unwrap();
        let vm = VonMises::new(1.0, 20.0).unwrap();
        let mm = Matrix3::new(1.0, 0.0, 0.0, 0.0, -1.0, 1.0, 0.0, 1.0, 0.0);
        let (m, i3) = (from_matrix(&mm), identity());
        let n = m * 0.5;
        let cross = Sym::new(1.0, 1.0, -2.0, 0.0, 0.0, 0.0) / 6.0f64.sqrt(); // deviatoric, ⟂ M
        let tol = 1e-13;
        let near = |a: f64, b: f64| (a - b).abs() <= tol;
        let ep = m * 0.0125;
        let eps = i3 * 0.01 + m * 0.05;
        let (mut s, mut q, mut c) = (Sym::zeros(), [0.0], SymOp::zeros());

        assert!(
            vm.step_law(&law, StepInput::new(&eps, &ep, &[0.5]), StepOutput::new(&mut s, &mut q, Some(&mut c))),
            "r = 6 > t₀ = 1.5"
        );
        let expected = Matrix3::new(3.2, 0.0, 0.0, 0.0, 0.8, 1.2, 0.0, 1.2, 2.0);
        assert!((to_matrix(&s) - expected).abs().max() <= tol, "σ = {}, by hand {expected}", to_matrix(&s));
        assert!(near(q[0], 1.4), "ξ = {}, by hand 1.4", q[0]);
        let new_ep = eps - law.compliance(&s);
        assert!((new_ep - m * 0.035).norm() <= tol && near(20.0 * new_ep.norm(), q[0]), "ε_p' = {new_ep}");
        assert!(near(n.dot(&(c * n)), 16.0) && near(cross.dot(&(c * cross)), 32.0) && near(n.dot(&(c * cross)), 0.0));
        assert!(near(i3.dot(&(c * i3)) / 3.0, 200.0));
        // the projection of the trial, and the tangent by differences of the projection
        let (mut s2, mut q2) = (law.stress(&(eps - ep)), [0.5]);
        assert!(vm.project(&law, &mut s2, &mut q2) && (s2 - s).norm() <= tol && near(q2[0], 1.4));
        assert_tangent_by_differences(&vm, &law, StepInput::new(&eps, &ep, &[0.5]), &c);

        // hardened: elastic from the state, plastic for the local law at the same ε − ε_p
        let small = ep + i3 * 0.01 + m * 0.009;
        assert!(!vm.step_law(&law, StepInput::new(&small, &ep, &[0.5]), StepOutput::new(&mut s, &mut q, Some(&mut c))));
        assert!((s - (m * 0.72 + i3 * 2.0)).norm() <= tol && q[0] == 0.5 && c == law.stiffness_matrix());
        assert!(vm.local_law(&law, &(small - ep), StepOutput::new(&mut s, &mut q, None)), "r = 1.44 > k₀ = 1");

        // h = 0: ξ frozen at ξ_n, radial return to t₀
        let pp = VonMises::new(1.0, 0.0).unwrap();
        assert!(pp.step_law(&law, StepInput::new(&eps, &ep, &[0.5]), StepOutput::new(&mut s, &mut q, Some(&mut c))));
        assert!((s - (m * 0.75 + i3 * 2.0)).norm() <= tol && q[0] == 0.5, "σ = {s}, ξ = {}", q[0]);
        assert!(near(n.dot(&(c * n)), 0.0) && near(cross.dot(&(c * cross)), 20.0));

        // apex from ξ_n = −3
        assert!(vm.step_law(&law, StepInput::new(&eps, &ep, &[-3.0]), StepOutput::new(&mut s, &mut q, Some(&mut c))));
        assert!((s - i3 * 2.0).norm() <= tol && q[0] == -1.0, "σ = {s}, ξ = {}", q[0]);
        assert!((c - volumetric_projector() * 200.0).norm() <= 1e-12, "{c}");
    }

    #[test]
    fn cone_block_measures_the_deviator() {
        let vm = VonMises::new(1.5, 5.0).unwrap();
        let cone = vm.cone().unwrap();
        assert_eq!(cone.blocks.len(), 1);
        let b = &cone.blocks[0];
        assert_eq!((b.dim, b.offset.len(), b.map.len()), (6, 6, 42));
        let basis = VonMises::deviatoric_basis();
        for (i, a) in basis.iter().enumerate() {
            assert!(a.dot(&identity()).abs() < 1e-15);
            for (j, c) in basis.iter().enumerate() {
                assert!((a.dot(c) - if i == j { 1.0 } else { 0.0 }).abs() < 1e-15);
            }
        }
        let sigma = Sym::new(3.0, -1.0, 0.5, 0.7, -0.2, 0.9);
        let xi = 0.25;
        let z: Vec<f64> = sigma.iter().copied().chain([xi]).collect();
        let v: Vec<f64> = (0..6).map(|i| b.offset[i] + (0..7).map(|j| b.map[i * 7 + j] * z[j]).sum::<f64>()).collect();
        assert!((v[0] - 1.75).abs() < 1e-15);
        let x = (v[1..].iter().map(|x| x * x).sum::<f64>()).sqrt();
        assert!((x - deviator(&sigma).norm()).abs() < 1e-14);
    }

    #[test]
    fn validation_names_the_field_and_value() {
        let ok = VonMises::new(1.0, 5.0).unwrap();
        assert!(ok.validate("yield").is_ok() && ok.warnings().is_empty());
        let e = VonMises::new(-1.0, 5.0).unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), ("yield.k0", "-1"));
        let e = VonMises::new(1.0, -0.5).unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), ("yield.h", "-0.5"));
        assert!(e.to_string().contains(">= 0"), "{e}");
        let e = VonMises::new(f64::NAN, 5.0).unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), ("yield.k0", "NaN"));
        assert!(e.to_string().contains("finite"), "{e}");
        let e = VonMises::new(1.0, f64::INFINITY).unwrap_err();
        assert_eq!(e.field, "yield.h");
        // h = 0 is legal but warns about uniqueness
        let pp = VonMises::new(1.0, 0.0).unwrap();
        assert!(pp.validate("yield").is_ok());
        let w = pp.warnings();
        assert_eq!(w.len(), 1);
        assert!(w[0].contains("unique") && w[0].contains("Theorem 1"), "{}", w[0]);
    }

    #[test]
    fn toml_round_trip_and_unknown_fields() {
        let p: Box<dyn AdmissibleStresses> = toml::from_str("type = \"von_mises\"\nk0 = 1.0\nh = 5.0").unwrap();
        assert_eq!(p.name(), "von_mises");
        assert_eq!(p.hardening_dim(), 1);
        assert!(p.hardening_inner(&[1.0], &[1.0]) == 0.2, "h = 5 read back");
        assert!(p.contains(&Sym::new(0.0, 0.0, 0.0, 1.0, 0.0, 0.0), &[0.0], 0.0));
        assert!(!p.contains(&Sym::new(0.0, 0.0, 0.0, 1.01, 0.0, 0.0), &[0.0], 0.0), "k0 = 1 read back");
        let text = toml::to_string(&p).unwrap();
        let back: Box<dyn AdmissibleStresses> = toml::from_str(&text).unwrap();
        assert_eq!(format!("{back:?}"), format!("{p:?}"));
        let err = toml::from_str::<Box<dyn AdmissibleStresses>>("type = \"von_mises\"\nk0 = 1.0\nh = 5.0\nH = 2.0")
            .unwrap_err();
        assert!(err.to_string().contains("unknown field"), "{err}");
        assert!(err.to_string().contains('H'), "{err}");
        assert!(
            toml::from_str::<Box<dyn AdmissibleStresses>>("type = \"von_mises\"\nk0 = 1.0").is_err(),
            "h is required"
        );
        let bad: Box<dyn AdmissibleStresses> = toml::from_str("type = \"von_mises\"\nk0 = -2.0\nh = 5.0").unwrap();
        let e = bad.validate("yield").unwrap_err();
        assert_eq!(e.to_string(), "yield.k0 = -2: must be >= 0");
    }

    #[test]
    fn kit_passes_for_several_parameter_sets() {
        for &(k0, h) in &[(1.0f64, 5.0), (1.0, 1e-4), (0.5, 2000.0), (0.0, 3.0), (1.0, 0.0)] {
            let cfg = KitConfig::new(law(), k0.max(0.1)).with_samples(150).with_seed(7);
            let vm = VonMises::new(k0, h).unwrap();
            if let Err(e) = conformance::check_all(&vm, &cfg) {
                panic!("k0 = {k0}, h = {h}: {e}");
            }
        }
        // h = 0 with a k₀ for which (2G k₀)/2G ≠ k₀ in floating point: ξ must stay exactly 0
        let k0 = 7.387156424190203;
        let cfg = KitConfig::new(law(), k0).with_samples(150);
        conformance::check_all(&VonMises::new(k0, 0.0).unwrap(), &cfg).unwrap();
        // another elasticity, nearly incompressible, and a high-strength scale
        let cfg = KitConfig::new(Elasticity::new(210e3, 0.49).unwrap(), 300.0).with_samples(150).with_seed(3);
        conformance::check_all(&VonMises::new(300.0, 1e3).unwrap(), &cfg).unwrap();
    }
}
