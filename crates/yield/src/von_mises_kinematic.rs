//! Von Mises with linear kinematic (Prager) and isotropic hardening (theory §9.3): generalised
//! stress (σ, ξ, χ) with a deviatoric back stress χ,
//! `D = {(σ, ξ, χ) : |dev σ − χ| ≤ k₀ + ξ}`, hardening metric `ξη/h + χ:ω/c`.
//!
//! χ is stored as its five coordinates in the orthonormal deviatoric basis
//! [`VonMises::deviatoric_basis`] (so `χ:ω` is the Euclidean product of the coordinates), after
//! ξ: `q = (ξ, χ₁, …, χ₅)`, `hardening_dim() = 6`.
//!
//! **Projection.** Write s = dev σ, the relative stress `a = s − χ`, `r = |a|`, `t₀ = k₀ + ξ`.
//! The projection minimises `|s' − s|²/(4G) + (ξ' − ξ)²/(2h) + |χ' − χ|²/(2c)` (the volumetric
//! part of σ is orthogonal to everything D constrains and stays) subject to
//! `|s' − χ'| ≤ k₀ + ξ'`. In the scaled coordinates `x = s/√(2G)`, `z = χ/√c`, `y = ξ/√h` the
//! metric is Euclidean and the constraint only sees the combination `√(2G) x − √c z = s − χ`;
//! the orthogonal combination `c s + 2G χ` is free and therefore unchanged. On the constrained
//! line D is the von Mises cone with 2G replaced by 2G + c, so the KKT conditions
//! `(s' − s)/(2G) + λn = 0`, `(χ' − χ)/c − λn = 0`, `(ξ' − ξ)/h − λ = 0`, `n = (s' − χ')/|s' − χ'|`
//! give `s' − χ' = a − (2G + c)λn`, hence n = a/r (a radial return of the relative stress) and
//!
//! * `s' = s − 2Gλn`, `χ' = χ + cλn`, `ξ' = ξ + hλ`, `λ = (r − t₀)/(2G + c + h)`;
//! * inside when `r ≤ t₀`;
//! * on the cone when `t = ((2G + c) t₀ + h r)/(2G + c + h) > 0`: `s' − χ' = t n`, `ξ' = t − k₀`,
//!   `(2G + c)λ = r − t`;
//! * at the apex (`s' = χ' = (c s + 2G χ)/(2G + c)`, `ξ' = −k₀`) when `(2G + c) t₀ + h r ≤ 0`.
//!
//! For h = 0 ξ is frozen (infinite metric): t = t₀, and if t₀ ≤ 0 the slice of D is empty and
//! the point goes to the apex with ξ' = −k₀, the limit h → 0 (as [`VonMises`] does).
//!
//! **Local law.** From (Cε, 0, 0) the relative trial is s_tr = 2G dev ε, t₀ = k₀ ≥ 0, so the
//! apex is never reached and `λ = (r − k₀)/(2G + h + c)`: σ is exactly the isotropic radial
//! return of theory §2.2 with hardening modulus h + c, with `ξ = hλ`, `χ = cλn`, so
//! `ξ + |χ| = (h + c)λ` is the isotropic ξ. Hence the tangent and ψ are those of [`VonMises`]
//! with h + c (theory §9.3).
//!
//! **Step law.** A load step (theory §11.1) projects the trial (C(ε − ε_p), ξ_n, χ_n): the
//! relative trial is `a = s_tr − χ_n` with `s_tr = 2G dev(ε − ε_p)`, so a reversed load yields
//! once `|s_tr − χ_n| = k₀ + ξ_n` (the Bauschinger effect), earlier than the isotropic law.
//! Differentiating `s' = s_tr − 2Gλn` with `dλ = dr/(2G + c + h)`, `dr = n:ds_tr` and
//! `dn = (I_dev − n⊗n) ds_tr / r` gives the tangent
//! `K_b I⊗I + 2G[(1 − 2Gλ/r)(I_dev − n⊗n) + (h + c)/(2G + c + h) n⊗n]`; for χ_n = 0 it is the
//! local law's, `1 − 2Gλ/r = |s'|/r`. Where t does not move with r (h = 0, or the apex, where
//! t = 0) the same formula holds with h = 0: at the apex `s' = (c s_tr + 2Gχ_n)/(2G + c)` and
//! the deviatoric tangent is `2G c/(2G + c) I_dev`.

use crate::VonMises;
use crate::hardening::{check_modulus, isotropic_inner};
use saddle_core::error::{ParameterError, check};
use saddle_core::problem::elasticity::Elasticity;
use saddle_core::problem::return_mapping::{DeviatoricTrial, elastic_step, radial_tangent};
use saddle_core::problem::stresses::{AdmissibleStresses, ConeDescription, SocBlock, StepInput, StepOutput};
use saddle_core::problem::tensor::{Sym, deviator, identity, trace};
use serde::{Deserialize, Serialize};

/// Von Mises yield with linear kinematic and isotropic hardening (theory §9.3):
/// `D = {|dev σ − χ| ≤ k₀ + ξ}`, `[σ̂, τ̂] = Aσ:τ + ξη/h + χ:ω/c`. Scene table:
/// `type = "von_mises_kinematic"`, `k0`, `h`, `c`. Hardening variables `(ξ, χ₁, …, χ₅)`, χ in
/// the basis [`VonMises::deviatoric_basis`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VonMisesKinematic {
    /// Initial yield radius k₀ ≥ 0 of |dev σ − χ| (`k₀ = √(2/3) σ_y`).
    pub k0: f64,
    /// Isotropic hardening modulus h ≥ 0 of the metric ξη/h; h = 0 freezes ξ at 0 (pure
    /// kinematic hardening).
    pub h: f64,
    /// Kinematic hardening modulus c > 0 of the metric χ:ω/c (Prager: `χ = c p`).
    pub c: f64,
}

impl VonMisesKinematic {
    /// Von Mises with isotropic (`h`) and kinematic (`c`) hardening and yield radius `k0`,
    /// validated (errors name `yield.k0`, `yield.h`, `yield.c`).
    pub fn new(k0: f64, h: f64, c: f64) -> Result<Self, ParameterError> {
        let p = Self { k0, h, c };
        p.validate("yield")?;
        Ok(p)
    }

    /// The back stress χ (a deviatoric Mandel vector) from its coordinates `q[1..6]`.
    pub fn back_stress(q: &[f64]) -> Sym {
        VonMises::deviatoric_basis().iter().zip(&q[1..6]).fold(Sym::zeros(), |acc, (e, x)| acc + e * *x)
    }

    /// The coordinates of the deviator of `a` in [`VonMises::deviatoric_basis`].
    pub fn coordinates(a: &Sym) -> [f64; 5] {
        let basis = VonMises::deviatoric_basis();
        std::array::from_fn(|k| basis[k].dot(a))
    }

    /// h + c: the isotropic modulus with the same local law (theory §9.3).
    fn total(&self) -> f64 {
        self.h + self.c
    }
}

#[typetag::serde(name = "von_mises_kinematic")]
impl AdmissibleStresses for VonMisesKinematic {
    /// k₀ ≥ 0 with k₀ ≤ [`check::MAX_MAGNITUDE`]; h ≥ 0, 0 or a scale in [1e-50, 1e50]; c > 0,
    /// a scale in [1e-50, 1e50] ([`check::scale`]: 1/h and 1/c enter the hardening metric), so
    /// that the solvers' products stay finite.
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::non_negative(path, "k0", self.k0)?;
        check::bounded(path, "k0", self.k0)?;
        check_modulus(path, self.h)?;
        check::positive(path, "c", self.c)?;
        check::scale(path, "c", self.c, false)?;
        Ok(())
    }

    /// ξ, then the five coordinates of the back stress χ in [`VonMises::deviatoric_basis`].
    fn hardening_fields(&self) -> Vec<(&'static str, usize)> {
        vec![("xi", 1), ("back_stress", 5)]
    }

    /// ξ and the five coordinates of χ.
    fn hardening_dim(&self) -> usize {
        6
    }

    /// `ξη/h + χ:ω/c`. For h = 0 the metric is infinite in ξ: the ξ part is 0 when ξη = 0,
    /// else ±∞ with the sign of ξη.
    fn hardening_inner(&self, q: &[f64], r: &[f64]) -> f64 {
        let kin: f64 = q[1..6].iter().zip(&r[1..6]).map(|(a, b)| a * b).sum();
        isotropic_inner(self.h, q[0], r[0]) + kin / self.c
    }

    /// `|dev σ − χ| ≤ k₀ + ξ + tol · max(k₀, |σ|, |ξ|, |χ|)`: the tolerance is relative to the
    /// largest stress magnitude involved, floored at the smallest positive normal number.
    fn contains(&self, sigma: &Sym, q: &[f64], tol: f64) -> bool {
        let chi = Self::back_stress(q);
        let scale = self.k0.max(sigma.norm()).max(q[0].abs()).max(chi.norm()).max(f64::MIN_POSITIVE);
        (deviator(sigma) - chi).norm() <= self.k0 + q[0] + tol * scale
    }

    /// Projection onto D in the energy metric, for a general point (σ, ξ, χ) — see the module
    /// docs for the derivation. The volumetric part is unchanged; the relative stress s − χ is
    /// returned radially, s by 2Gλ and χ by cλ.
    fn project(&self, law: &Elasticity, sigma: &mut Sym, q: &mut [f64]) -> bool {
        let s = deviator(sigma);
        let chi = Self::back_stress(q);
        let a = s - chi;
        let r = a.norm();
        let t0 = self.k0 + q[0];
        if r <= t0 {
            return false;
        }
        let m = trace(sigma) / 3.0;
        let g2 = 2.0 * law.shear_modulus();
        let gc = g2 + self.c;
        let t = if self.h > 0.0 { (gc * t0 + self.h * r) / (gc + self.h) } else { t0 };
        // apex: (2G + c) t₀ + h r ≤ 0 (h = 0: k₀ + ξ ≤ 0); s' − χ' = 0, ξ' = −k₀
        let t = t.max(0.0);
        let lambda = (r - t) / gc;
        let n = a / r;
        let s_new = s - n * (g2 * lambda);
        let chi_new = chi + n * (self.c * lambda);
        *sigma = identity() * m + s_new;
        let x = Self::coordinates(&chi_new);
        q[1..6].copy_from_slice(&x);
        if self.h > 0.0 || t == 0.0 {
            q[0] = t - self.k0;
        }
        true
    }

    /// Theory §11.1 in closed form: σ̂ = P_D(C(ε − ε_p), ξ_n, χ_n), the return of the relative
    /// trial `a = s_tr − χ_n` (module docs), and the consistent tangent
    /// `K_b I⊗I + 2G[(1 − 2Gλ/r)(I_dev − n⊗n) + (h + c)/(2G + c + h) n⊗n]` when plastic, with
    /// h → 0 where t does not move with r (h = 0, or the apex: there `2G c/(2G + c) I_dev`); C
    /// when elastic.
    fn step_law(&self, law: &Elasticity, step: StepInput<'_>, mut out: StepOutput<'_>) -> bool {
        let trial = DeviatoricTrial::new(law, &step);
        let DeviatoricTrial { g2, kb, s: s_tr, p, .. } = trial;
        let q_n = step.q_n;
        let chi = Self::back_stress(q_n);
        let a = s_tr - chi;
        let r = a.norm();
        let t0 = self.k0 + q_n[0];
        if r <= t0 {
            return elastic_step(law, trial.stress(), q_n, out);
        }
        let gc = g2 + self.c;
        let t = if self.h > 0.0 { (gc * t0 + self.h * r) / (gc + self.h) } else { t0 };
        // apex: (2G + c) t₀ + h r ≤ 0 (h = 0: k₀ + ξ_n ≤ 0); s' − χ' = 0, ξ' = −k₀
        let apex = t <= 0.0;
        let t = t.max(0.0);
        let lambda = (r - t) / gc;
        let n = a / r;
        *out.sigma = s_tr - n * (g2 * lambda) + identity() * p;
        let x = Self::coordinates(&(chi + n * (self.c * lambda)));
        out.q[1..6].copy_from_slice(&x);
        out.q[0] = if self.h > 0.0 || apex { t - self.k0 } else { q_n[0] };
        // t moves with r only on the cone with h > 0: dλ = dr/(2G + c + h_eff)
        let h_eff = if apex { 0.0 } else { self.h };
        out.set_tangent(|| radial_tangent(kb, &n, g2 * (1.0 - g2 * lambda / r), g2 * (h_eff + self.c) / (gc + h_eff)));
        true
    }

    /// `ψ(ε) = ½Cε:ε − (2G|dev ε| − k₀)₊² / (2(2G + h + c))` (theory §9.3): the isotropic ψ with
    /// modulus h + c.
    fn energy(&self, law: &Elasticity, eps: &Sym) -> f64 {
        let g2 = 2.0 * law.shear_modulus();
        let over = (g2 * deviator(eps).norm() - self.k0).max(0.0);
        0.5 * eps.dot(&law.stress(eps)) - over * over / (2.0 * (g2 + self.total()))
    }

    /// One second-order cone of dimension 6: `t = k₀ + ξ`, `x_k = e_k·σ − χ_k` with e_k the
    /// basis [`VonMises::deviatoric_basis`] (χ_k are stored in it), so `|x| = |dev σ − χ|`. The
    /// map is 6 × 12 row-major on (σ Mandel, ξ, χ₁, …, χ₅).
    fn cone(&self) -> Option<ConeDescription> {
        const W: usize = 12;
        let mut offset = vec![0.0; 6];
        offset[0] = self.k0;
        let mut map = vec![0.0; 6 * W];
        map[6] = 1.0;
        for (k, e) in VonMises::deviatoric_basis().iter().enumerate() {
            for j in 0..6 {
                map[(k + 1) * W + j] = e[j];
            }
            map[(k + 1) * W + 7 + k] = -1.0;
        }
        Some(ConeDescription { blocks: vec![SocBlock { dim: 6, offset, map }] })
    }

    /// k₀ = 0: every point with a deviatoric strain is plastic, and the law is linear elastic
    /// with the reduced shear modulus G(h + c)/(2G + h + c) (theory §9.3). (h = 0 needs no
    /// warning: c > 0 keeps the solution unique, as isotropic hardening with h = c does.)
    fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if self.k0 == 0.0 {
            w.push(
                "yield.k0 = 0: every point with a deviatoric strain is plastic; the law is then linear elastic \
                 with the reduced shear modulus G(h + c)/(2G + h + c) (theory §9.3)"
                    .to_string(),
            );
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::conformance::{self, KitConfig, KitFailure, names};
    use crate::mutant::Mutant;
    use crate::testing::{assert_tangent_by_differences, close, law};
    use saddle_core::problem::tensor::{SymOp, deviatoric_projector, volumetric_projector};

    #[test]
    fn kinematic_kit_passes_for_several_parameter_sets() {
        for &(k0, h, c) in
            &[(1.0f64, 5.0, 3.0), (1.0, 0.0, 5.0), (0.0, 2.0, 3.0), (0.5, 1e-4, 2000.0), (1.0, 40.0, 1e-3)]
        {
            let cfg = KitConfig::new(law(), k0.max(0.1)).with_samples(150).with_seed(11);
            let p = VonMisesKinematic::new(k0, h, c).unwrap();
            if let Err(e) = conformance::check_all(&p, &cfg) {
                panic!("k0 = {k0}, h = {h}, c = {c}: {e}");
            }
        }
        let cfg = KitConfig::new(Elasticity::new(210e3, 0.49).unwrap(), 300.0).with_samples(150).with_seed(3);
        conformance::check_all(&VonMisesKinematic::new(300.0, 1e3, 5e3).unwrap(), &cfg).unwrap();
    }

    /// The hand-checkable point of theory §9.3, chosen so that h + c = 20 reproduces the
    /// isotropic example of `von_mises.rs` (theory §2). Every number is a short decimal:
    ///
    /// * E = 100, ν = 1/4: 2G = 80, 3K_b = 200; k₀ = 1, h = 8, c = 12, so 2G + h + c = 100.
    /// * ε = 0.01 I + 0.025 M with M = [[1,0,0],[0,−1,1],[0,1,0]] (tr M = 0, |M| = 2):
    ///   s_tr = 2M, r = 4, n = M/2, tr σ = 200 · 0.03 = 6.
    /// * λ = (r − k₀)/(2G + h + c) = 3/100 = 0.03; s = s_tr − 2Gλ n = 2M − 1.2M = 0.8M,
    ///   σ = 0.8M + 2I = [[2.8, 0, 0], [0, 1.2, 0.8], [0, 0.8, 2.0]] (the isotropic h = 20 σ).
    /// * ξ = hλ = 0.24; χ = cλ n = 0.36 · M/2 = 0.18M, whose coordinates in the deviatoric basis
    ///   are 0.18 · (√2, 0, √2, 0, 0) (M = (1, −1, 0, √2, 0, 0) in Mandel notation).
    /// * |s − χ| = 0.62 · 2 = 1.24 = k₀ + ξ: on the yield surface. ξ + |χ| = 0.24 + 0.36 = 0.6 =
    ///   the isotropic ξ of h = 20.
    /// * p = (s_tr − s)/(2G) = 0.015M, |p| = 0.03 = λ: χ = c p, ξ = h|p| (Prager).
    /// * ½(ξ²/h + |χ|²/c) = ½(0.0576/8 + 0.1296/12) = ½(0.0072 + 0.0108) = 0.009 = (h + c)λ²/2.
    /// * ψ = ½Cε:ε − (r − k₀)²/(2(2G + h + c)) = 0.13 − 9/200 = 0.085.
    /// * Tangent: along n 2G(h + c)/(2G + h + c) = 16; across n (deviators ⟂ M) 2G|s|/r = 32.
    #[test]
    fn kinematic_local_law_matches_a_point_worked_by_hand() {
        use nalgebra::Matrix3;
        use saddle_core::problem::tensor::{SQRT2, from_matrix, to_matrix};
        let law = Elasticity::new(100.0, 0.25).unwrap();
        let p = VonMisesKinematic::new(1.0, 8.0, 12.0).unwrap();
        let mm = Matrix3::new(1.0, 0.0, 0.0, 0.0, -1.0, 1.0, 0.0, 1.0, 0.0);
        let eps = from_matrix(&(Matrix3::identity() * 0.01 + mm * 0.025));
        let tol = 1e-13;
        let near = |a: f64, b: f64| (a - b).abs() <= tol;
        let (mut s, mut q, mut ct) = (Sym::zeros(), [0.0; 6], SymOp::zeros());
        assert!(p.local_law(&law, &eps, StepOutput::new(&mut s, &mut q, Some(&mut ct))), "r = 4 > k0 = 1: plastic");
        let expected = Matrix3::new(2.8, 0.0, 0.0, 0.0, 1.2, 0.8, 0.0, 0.8, 2.0);
        assert!((to_matrix(&s) - expected).abs().max() <= tol, "σ = {}, by hand {expected}", to_matrix(&s));
        assert!(near(q[0], 0.24), "ξ = {}, by hand 0.24", q[0]);
        let x = 0.18 * SQRT2;
        for (k, want) in [x, 0.0, x, 0.0, 0.0].into_iter().enumerate() {
            assert!(near(q[1 + k], want), "χ_{} = {}, by hand {want}", k + 1, q[1 + k]);
        }
        let chi = VonMisesKinematic::back_stress(&q);
        assert!((to_matrix(&chi) - mm * 0.18).abs().max() <= tol, "χ = {}, by hand 0.18 M", to_matrix(&chi));
        assert!(near((deviator(&s) - chi).norm(), 1.24), "|s − χ| = k0 + ξ = 1.24");
        assert!(near(q[0] + chi.norm(), 0.6), "ξ + |χ| = 0.6, the isotropic ξ of h + c = 20");
        let plastic_strain = eps - law.compliance(&s);
        assert!((to_matrix(&plastic_strain) - mm * 0.015).abs().max() <= tol, "p = 0.015 M");
        assert!((chi - plastic_strain * 12.0).norm() <= tol, "χ = c p");
        assert!(near(p.hardening_inner(&q, &q) / 2.0, 0.009), "½ q·H⁻¹q = 0.009");
        assert!(near(p.energy(&law, &eps), 0.085), "ψ = {}, by hand 0.085", p.energy(&law, &eps));
        let n = from_matrix(&(mm * 0.5));
        let m = Sym::new(1.0, 1.0, -2.0, 0.0, 0.0, 0.0) / 6.0f64.sqrt();
        assert!(near(n.dot(&(ct * n)), 16.0) && near(m.dot(&(ct * m)), 32.0) && near(n.dot(&(ct * m)), 0.0));
        assert!(near(identity().dot(&(ct * identity())) / 3.0, 200.0));
        // the general projection of (Cε, 0, 0) is the same point
        let (mut s2, mut q2) = (law.stress(&eps), [0.0; 6]);
        assert!(p.project(&law, &mut s2, &mut q2));
        assert!((s2 - s).norm() <= tol && q2.iter().zip(&q).all(|(a, b)| near(*a, *b)), "{s2} {q2:?}");
        // below yield: elastic, no hardening, tangent C
        let small = from_matrix(&(Matrix3::identity() * 0.01 + mm * 0.005));
        assert!(!p.local_law(&law, &small, StepOutput::new(&mut s, &mut q, Some(&mut ct))));
        assert!(q == [0.0; 6] && ct == law.stiffness_matrix() && s == law.stress(&small));
    }

    /// Reverse loading after the forward step of `kinematic_local_law_matches_a_point_worked_by_hand`
    /// (theory §11.1, §9.3): E = 100, ν = 1/4 (2G = 80, 3K_b = 200), k₀ = 1, h = 8, c = 12,
    /// M = [[1,0,0],[0,−1,1],[0,1,0]] (|M| = 2). The state is ε_p = 0.015M, ξ_n = 0.24,
    /// χ_n = 0.18M (k₀ + ξ_n = 1.24). A trial ε = ε_p + 0.01 I + (β/2G) M has s_tr = βM and
    /// relative trial a = (β − 0.18)M, |a| = 2|β − 0.18|:
    ///
    /// * reverse yield exactly at the Bauschinger point |a| = 1.24, β = −0.44, where
    ///   |s_tr| = 0.88 is below the initial yield radius k₀ = 1; the isotropic law with the same
    ///   hardening (h = 20, ξ_n = ξ + |χ| = 0.6) is still elastic there and yields at β = −0.8;
    /// * β = −0.82 (ε = 0.01 I + 0.00475 M): r = 2, n = −M/2, λ = (r − t₀)/(2G + c + h) =
    ///   0.76/100 = 0.0076, s' = s_tr − 2Gλn = −0.82M + 0.304M = −0.516M, χ' = χ_n + cλn =
    ///   0.18M − 0.0456M = 0.1344M, ξ' = ξ_n + hλ = 0.3008, and |s' − χ'| = 1.3008 = k₀ + ξ';
    /// * the new plastic strain ε − Aσ = 0.00475M + 0.00645M = 0.0112M: χ' = c ε_p' (Prager)
    ///   and ξ' = h(0.03 + 0.0076), h times the accumulated plastic strain;
    /// * tangent: along n 2G(h + c)/(2G + c + h) = 16, across n 2G(1 − 2Gλ/r) = 80 · 0.696 =
    ///   55.68 (the isotropic law would give 2G|s'|/r), on I 3K_b = 200.
    #[test]
    fn kinematic_step_law_reverse_yields_at_the_bauschinger_point() {
        use nalgebra::Matrix3;
        use saddle_core::problem::tensor::from_matrix;
        let law = Elasticity::new(100.0, 0.25).unwrap();
        let p = VonMisesKinematic::new(1.0, 8.0, 12.0).unwrap();
        let m = from_matrix(&Matrix3::new(1.0, 0.0, 0.0, 0.0, -1.0, 1.0, 0.0, 1.0, 0.0));
        let i3 = identity();
        let tol = 1e-13;
        let near = |a: f64, b: f64| (a - b).abs() <= tol;
        // the forward step from the virgin state
        let (mut s, mut qn) = (Sym::zeros(), [0.0; 6]);
        let eps1 = i3 * 0.01 + m * 0.025;
        assert!(p.step_law(
            &law,
            StepInput::new(&eps1, &Sym::zeros(), &[0.0; 6]),
            StepOutput::new(&mut s, &mut qn, None)
        ));
        let ep = eps1 - law.compliance(&s);
        assert!((ep - m * 0.015).norm() <= tol && near(qn[0], 0.24));
        assert!((VonMisesKinematic::back_stress(&qn) - m * 0.18).norm() <= tol);
        let reverse = |beta: f64| ep + i3 * 0.01 + m * (beta / 80.0);

        // the Bauschinger point: elastic just before, plastic just beyond
        let (mut q, mut c) = ([0.0; 6], SymOp::zeros());
        let before = reverse(-0.44 * (1.0 - 1e-9));
        assert!(!p.step_law(&law, StepInput::new(&before, &ep, &qn), StepOutput::new(&mut s, &mut q, Some(&mut c))));
        assert!(s == law.stress(&(before - ep)) && q == qn && c == law.stiffness_matrix());
        assert!(p.step_law(
            &law,
            StepInput::new(&reverse(-0.44 * (1.0 + 1e-9)), &ep, &qn),
            StepOutput::new(&mut s, &mut q, None)
        ));
        // isotropic hardening to the same size: elastic until |s_tr| = 1.6
        let iso = VonMises::new(1.0, 20.0).unwrap();
        let mut qi = [0.0];
        assert!(!iso.step_law(
            &law,
            StepInput::new(&reverse(-0.44 * (1.0 + 1e-9)), &ep, &[0.6]),
            StepOutput::new(&mut s, &mut qi, None)
        ));
        assert!(!iso.step_law(
            &law,
            StepInput::new(&reverse(-0.8 * (1.0 - 1e-9)), &ep, &[0.6]),
            StepOutput::new(&mut s, &mut qi, None)
        ));
        assert!(iso.step_law(
            &law,
            StepInput::new(&reverse(-0.8 * (1.0 + 1e-9)), &ep, &[0.6]),
            StepOutput::new(&mut s, &mut qi, None)
        ));

        // β = −0.82
        let eps = reverse(-0.82);
        assert!((eps - (i3 * 0.01 + m * 0.00475)).norm() <= 1e-16);
        assert!(p.step_law(&law, StepInput::new(&eps, &ep, &qn), StepOutput::new(&mut s, &mut q, Some(&mut c))));
        assert!((s - (m * -0.516 + i3 * 2.0)).norm() <= tol, "σ = {s}");
        let chi = VonMisesKinematic::back_stress(&q);
        assert!((chi - m * 0.1344).norm() <= tol && near(q[0], 0.3008), "χ = {chi}, ξ = {}", q[0]);
        assert!(near((deviator(&s) - chi).norm(), 1.3008));
        let new_ep = eps - law.compliance(&s);
        assert!((new_ep - m * 0.0112).norm() <= tol && (chi - new_ep * 12.0).norm() <= tol);
        let (n, cross) = (m * -0.5, Sym::new(1.0, 1.0, -2.0, 0.0, 0.0, 0.0) / 6.0f64.sqrt());
        assert!(near(n.dot(&(c * n)), 16.0), "along n: {}", n.dot(&(c * n)));
        assert!(near(cross.dot(&(c * cross)), 55.68), "across n: {}", cross.dot(&(c * cross)));
        assert!(near(n.dot(&(c * cross)), 0.0) && near(i3.dot(&(c * i3)) / 3.0, 200.0));
        // the projection of the trial, and the tangent by differences of the projection
        let (mut s2, mut q2) = (law.stress(&(eps - ep)), qn);
        assert!(p.project(&law, &mut s2, &mut q2));
        assert!((s2 - s).norm() <= tol && q2.iter().zip(&q).all(|(a, b)| near(*a, *b)));
        assert_tangent_by_differences(&p, &law, StepInput::new(&eps, &ep, &qn), &c);

        // h = 0 freezes ξ; from ξ_n = −1.5 (t₀ < 0, not admissible) the apex
        // s' = χ' = (c s_tr + 2Gχ_n)/(2G + c) with the deviatoric tangent 2G c/(2G + c)
        let pk = VonMisesKinematic::new(1.0, 0.0, 12.0).unwrap();
        assert!(pk.step_law(&law, StepInput::new(&eps, &ep, &qn), StepOutput::new(&mut s, &mut q, Some(&mut c))));
        assert!(q[0] == 0.24 && near((deviator(&s) - VonMisesKinematic::back_stress(&q)).norm(), 1.24));
        let mut q_apex = qn;
        q_apex[0] = -1.5;
        assert!(pk.step_law(&law, StepInput::new(&eps, &ep, &q_apex), StepOutput::new(&mut s, &mut q, Some(&mut c))));
        let apex = m * ((12.0 * -0.82 + 80.0 * 0.18) / 92.0);
        assert!((s - (apex + i3 * 2.0)).norm() <= tol && (VonMisesKinematic::back_stress(&q) - apex).norm() <= tol);
        assert_eq!(q[0], -1.0);
        let want = volumetric_projector() * 200.0 + deviatoric_projector() * (80.0 * 12.0 / 92.0);
        assert!((c - want).norm() <= 1e-12, "{c}");
        assert_tangent_by_differences(&pk, &law, StepInput::new(&eps, &ep, &q_apex), &c);
    }

    /// Theory §9.3: from the zero state the local law with (h, c) is the isotropic law with
    /// h + c — the same σ, tangent and ψ to round-off — and the isotropic ξ_iso = (h + c)λ splits
    /// into ξ = h λ and |χ| = c λ, χ along n = s_tr/|s_tr|. With h = 0 (ξ frozen) it is the
    /// isotropic law with modulus c.
    #[test]
    fn kinematic_local_law_is_isotropic_with_h_plus_c() {
        let law = law();
        let g2 = 2.0 * law.shear_modulus();
        for &(k0, h, c) in &[(1.0, 0.0, 5.0), (1.0, 2.0, 3.0), (0.0, 4.0, 0.5), (0.3, 40.0, 1e-3)] {
            let kin = VonMisesKinematic::new(k0, h, c).unwrap();
            let iso = VonMises::new(k0, h + c).unwrap();
            let mut plastic = 0;
            for i in 0..40 {
                let t = i as f64;
                // amplitudes from 0 to 1.5× those below: both regimes when k₀ > 0
                let eps = (t / 40.0 * 1.5)
                    * Sym::new(
                        0.03 * (0.7 * t).sin(),
                        -0.01 * (1.3 * t).cos(),
                        0.02 * (0.4 * t + 1.0).sin(),
                        0.015 * (2.1 * t).cos(),
                        -0.005 * (0.9 * t).sin(),
                        0.01 * (1.7 * t + 0.5).cos(),
                    );
                let (mut sk, mut qk, mut ck) = (Sym::zeros(), [0.0; 6], SymOp::zeros());
                let (mut si, mut qi, mut ci) = (Sym::zeros(), [0.0], SymOp::zeros());
                let pk = kin.local_law(&law, &eps, StepOutput::new(&mut sk, &mut qk, Some(&mut ck)));
                let pi = iso.local_law(&law, &eps, StepOutput::new(&mut si, &mut qi, Some(&mut ci)));
                assert_eq!(pk, pi);
                plastic += pk as usize;
                assert!((sk - si).norm() <= 1e-14 * si.norm(), "σ: {sk} vs {si}");
                assert!((ck - ci).norm() <= 1e-13 * ci.norm(), "tangent");
                assert!(close(kin.energy(&law, &eps), iso.energy(&law, &eps), 1e-14));
                let chi = VonMisesKinematic::back_stress(&qk);
                let xi_iso = qi[0];
                assert!((qk[0] + chi.norm() - xi_iso).abs() <= 1e-14 * (1.0 + xi_iso), "ξ + |χ| = ξ_iso");
                assert!((qk[0] - h / (h + c) * xi_iso).abs() <= 1e-14 * (1.0 + xi_iso), "ξ = h/(h+c) ξ_iso");
                assert!((chi.norm() - c / (h + c) * xi_iso).abs() <= 1e-14 * (1.0 + xi_iso), "|χ| = c/(h+c) ξ_iso");
                if pk {
                    let s_tr = deviator(&eps) * g2;
                    let n = s_tr / s_tr.norm();
                    assert!((chi - n * chi.norm()).norm() <= 1e-14 * (1.0 + chi.norm()), "χ ∥ n");
                }
            }
            let want = if k0 > 0.0 { 10..39 } else { 39..41 };
            assert!(want.contains(&plastic), "{plastic} plastic of 40");
        }
    }

    /// The general projection on points worked by hand (E = 100, ν = 1/4: 2G = 80; k₀ = 1,
    /// h = 8, c = 12: 2G + c = 92, 2G + c + h = 100). d, m are orthonormal deviators, the
    /// volumetric part 0.7 I stays.
    #[test]
    fn kinematic_projection_of_general_points() {
        let law = Elasticity::new(100.0, 0.25).unwrap();
        let p = VonMisesKinematic::new(1.0, 8.0, 12.0).unwrap();
        let basis = VonMises::deviatoric_basis();
        let (d, m) = (basis[0], basis[3]);
        let vol = identity() * 0.7;
        let q_of = |xi: f64, chi: &Sym| {
            let x = VonMisesKinematic::coordinates(chi);
            [xi, x[0], x[1], x[2], x[3], x[4]]
        };
        let tol = 1e-14;
        // on the cone: s = 4d + 0.5m, χ = 0.5m, ξ = 0.5: a = 4d, r = 4, t₀ = 1.5,
        // λ = 2.5/100 = 0.025, s' = s − 2d, χ' = χ + 0.3d, ξ' = 0.7, s' − χ' = 1.7 d
        let chi = m * 0.5;
        let (mut s, mut q) = (vol + d * 4.0 + chi, q_of(0.5, &chi));
        assert!(p.project(&law, &mut s, &mut q));
        assert!((s - (vol + d * 2.0 + m * 0.5)).norm() < tol, "σ' = {s}");
        assert!((VonMisesKinematic::back_stress(&q) - (m * 0.5 + d * 0.3)).norm() < tol);
        assert!(
            (q[0] - 0.7).abs() < tol && ((deviator(&s) - VonMisesKinematic::back_stress(&q)).norm() - 1.7).abs() < tol
        );

        // inside: |a| = 1.2 ≤ 1.5, unchanged
        let (mut s, mut q) = (vol + d * 1.2 + chi, q_of(0.5, &chi));
        let (s0, q0) = (s, q);
        assert!(!p.project(&law, &mut s, &mut q));
        assert_eq!((s, q), (s0, q0));

        // apex: ξ = −2, t₀ = −1: (2G + c)t₀ + h r = −92 + 32 ≤ 0; s' = χ' = (c s + 2Gχ)/(2G + c)
        // = (48 d + 6 m + 40 m)/92 = (12/23) d + 0.5 m, ξ' = −k₀ = −1
        let (mut s, mut q) = (vol + d * 4.0 + chi, q_of(-2.0, &chi));
        assert!(p.project(&law, &mut s, &mut q));
        let apex = d * (12.0 / 23.0) + m * 0.5;
        assert!((s - (vol + apex)).norm() < tol && (VonMisesKinematic::back_stress(&q) - apex).norm() < tol);
        assert_eq!(q[0], -1.0);
        // the apex is the nearest point: obtuse angle with a point of D
        let x = (vol + d * 4.0 + chi, q_of(-2.0, &chi));
        let y = (vol + d * 0.3, q_of(0.0, &Sym::zeros()));
        let dx = (x.0 - s, std::array::from_fn::<f64, 6, _>(|k| x.1[k] - q[k]));
        let dy = (y.0 - s, std::array::from_fn::<f64, 6, _>(|k| y.1[k] - q[k]));
        let ip = law.compliance(&dx.0).dot(&dy.0) + p.hardening_inner(&dx.1, &dy.1);
        assert!(ip <= 0.0, "{ip}");

        // h = 0: ξ frozen, λ = (4 − 1.25)/92; apex with ξ' = −k0 when k0 + ξ ≤ 0
        let pk = VonMisesKinematic::new(1.0, 0.0, 12.0).unwrap();
        let (mut s, mut q) = (vol + d * 4.0 + chi, q_of(0.25, &chi));
        assert!(pk.project(&law, &mut s, &mut q));
        let lambda = 2.75 / 92.0;
        assert!(q[0] == 0.25 && (s - (vol + d * (4.0 - 80.0 * lambda) + chi)).norm() < tol);
        assert!(((deviator(&s) - VonMisesKinematic::back_stress(&q)).norm() - 1.25).abs() < tol);
        let (mut s, mut q) = (vol + d * 4.0 + chi, q_of(-1.5, &chi));
        assert!(pk.project(&law, &mut s, &mut q));
        assert!(q[0] == -1.0 && (s - (vol + apex)).norm() < tol);
        assert!(pk.hardening_inner(&[0.0, 1.0, 0.0, 0.0, 0.0, 0.0], &[3.0, 2.0, 0.0, 0.0, 0.0, 0.0]) == 2.0 / 12.0);
        assert!(pk.hardening_inner(&[1.0; 6], &[1.0; 6]) == f64::INFINITY);
        assert!(p.hardening_inner(&[2.0, 1.0, 1.0, 0.0, 0.0, 0.0], &[3.0, 1.0, 2.0, 0.0, 0.0, 0.0]) == 0.75 + 0.25);
    }

    #[test]
    fn kinematic_cone_block_measures_the_relative_stress() {
        let p = VonMisesKinematic::new(1.5, 5.0, 2.0).unwrap();
        assert_eq!((p.hardening_dim(), p.hardening_fields()), (6, vec![("xi", 1), ("back_stress", 5)]));
        let cone = p.cone().unwrap();
        assert_eq!(cone.blocks.len(), 1);
        let b = &cone.blocks[0];
        assert_eq!((b.dim, b.offset.len(), b.map.len()), (6, 6, 72));
        let sigma = Sym::new(3.0, -1.0, 0.5, 0.7, -0.2, 0.9);
        let q = [0.25, 0.3, -0.2, 0.1, 0.0, 0.4];
        let z: Vec<f64> = sigma.iter().copied().chain(q).collect();
        let v: Vec<f64> =
            (0..6).map(|i| b.offset[i] + (0..12).map(|j| b.map[i * 12 + j] * z[j]).sum::<f64>()).collect();
        assert!((v[0] - 1.75).abs() < 1e-15);
        let x = v[1..].iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!((x - (deviator(&sigma) - VonMisesKinematic::back_stress(&q)).norm()).abs() < 1e-14);
        let chi = deviator(&Sym::new(0.3, -0.1, 0.7, 0.2, -0.5, 0.1));
        let back = VonMisesKinematic::back_stress(&{
            let x = VonMisesKinematic::coordinates(&chi);
            [0.0, x[0], x[1], x[2], x[3], x[4]]
        });
        assert!((back - chi).norm() < 1e-15, "coordinates and back_stress are inverse on deviators");
    }

    #[test]
    fn kinematic_validation_warnings_and_toml() {
        let ok = VonMisesKinematic::new(1.0, 0.0, 5.0).unwrap();
        assert!(ok.validate("yield").is_ok() && ok.warnings().is_empty(), "h = 0 is unique with c > 0");
        let e = VonMisesKinematic::new(-1.0, 5.0, 1.0).unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), ("yield.k0", "-1"));
        let e = VonMisesKinematic::new(1.0, -0.5, 1.0).unwrap_err();
        assert_eq!(e.field, "yield.h");
        let e = VonMisesKinematic::new(1.0, 5.0, 0.0).unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), ("yield.c", "0"));
        assert!(e.to_string().contains("> 0"), "{e}");
        let e = VonMisesKinematic::new(1.0, 5.0, f64::NAN).unwrap_err();
        assert!(e.field == "yield.c" && e.to_string().contains("finite"), "{e}");
        let w = VonMisesKinematic::new(0.0, 1.0, 1.0).unwrap().warnings();
        assert!(w.len() == 1 && w[0].contains("k0 = 0"), "{w:?}");

        let p: Box<dyn AdmissibleStresses> =
            toml::from_str("type = \"von_mises_kinematic\"\nk0 = 1.0\nh = 5.0\nc = 4.0").unwrap();
        assert_eq!((p.name(), p.hardening_dim()), ("von_mises_kinematic", 6));
        assert!(p.hardening_inner(&[0.0, 1.0, 0.0, 0.0, 0.0, 0.0], &[0.0, 1.0, 0.0, 0.0, 0.0, 0.0]) == 0.25);
        let back: Box<dyn AdmissibleStresses> = toml::from_str(&toml::to_string(&p).unwrap()).unwrap();
        assert_eq!(format!("{back:?}"), format!("{p:?}"));
        let err = toml::from_str::<Box<dyn AdmissibleStresses>>("type = \"von_mises_kinematic\"\nk0 = 1.0\nh = 5.0")
            .unwrap_err();
        assert!(err.to_string().contains('c'), "c is required: {err}");
        let err = toml::from_str::<Box<dyn AdmissibleStresses>>(
            "type = \"von_mises_kinematic\"\nk0 = 1.0\nh = 5.0\nc = 1.0\nC = 2.0",
        )
        .unwrap_err();
        assert!(err.to_string().contains("unknown field"), "{err}");
    }

    /// Ways to break the plugin, each a plausible slip of an author.
    #[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
    enum Breakage {
        /// the back stress moves by 2cλ instead of cλ, in the projection and in the local law
        /// derived from it (ψ and the tangent stay right): the relative stress s' − χ' =
        /// (r − (2G + 2c)λ) n overshoots through 0 when cλ > 2t, out of D.
        DoubleBackStress,
        /// the metric weight of χ is c instead of 1/c (projection unchanged): the projection is
        /// no longer the nearest point.
        WrongMetricWeight,
        /// the local law forgets the kinematic part (isotropic h only), consistent ψ and
        /// tangent; the projection is right.
        LocalLawWithoutC,
        /// the cone measures |dev σ| instead of |dev σ − χ| (the −1 entries on χ dropped).
        ConeWithoutBackStress,
    }

    /// `p` broken as `how` says.
    fn broken(p: VonMisesKinematic, how: Breakage) -> Mutant {
        let m = Mutant::of(p);
        match how {
            Breakage::DoubleBackStress => m
                .with_project(move |_, law, sigma, q| {
                    let chi0 = VonMisesKinematic::back_stress(q);
                    let out = p.project(law, sigma, q);
                    if out {
                        // χ' = χ + 2cλn: add the increment once more
                        let dchi = VonMisesKinematic::back_stress(q) - chi0;
                        let x = VonMisesKinematic::coordinates(&(chi0 + dchi * 2.0));
                        q[1..6].copy_from_slice(&x);
                    }
                    out
                })
                .with_local_law(move |m, law, eps, out| {
                    let StepOutput { sigma, q, tangent } = out;
                    let plastic = p.local_law(law, eps, StepOutput::new(sigma, q, tangent));
                    *sigma = law.stress(eps);
                    q.fill(0.0);
                    m.project(law, sigma, q);
                    plastic
                }),
            Breakage::WrongMetricWeight => m.with_hardening_inner(move |_, q, r| {
                let kin: f64 = q[1..6].iter().zip(&r[1..6]).map(|(a, b)| a * b).sum();
                q[0] * r[0] / p.h + kin * p.c
            }),
            Breakage::LocalLawWithoutC => {
                let iso = VonMises { k0: p.k0, h: p.h };
                m.with_local_law(move |_, law, eps, out| {
                    let mut xi = [0.0];
                    let plastic = iso.local_law(law, eps, StepOutput::new(out.sigma, &mut xi, out.tangent));
                    out.q.fill(0.0);
                    out.q[0] = xi[0];
                    plastic
                })
                .with_energy(move |_, law, eps| iso.energy(law, eps))
            }
            Breakage::ConeWithoutBackStress => m.with_cone(move |_| {
                let mut c = p.cone()?;
                for row in c.blocks[0].map.chunks_mut(12) {
                    row[7..].fill(0.0);
                }
                Some(c)
            }),
        }
    }

    #[test]
    fn kinematic_kit_catches_broken_copies() {
        let cfg = KitConfig::new(law(), 1.0).with_samples(120);
        let p = VonMisesKinematic::new(1.0, 5.0, 3.0).unwrap();
        for (how, first) in [
            (Breakage::DoubleBackStress, names::PROJECTION_IN_SET),
            (Breakage::WrongMetricWeight, names::VARIATIONAL_INEQUALITY),
            (Breakage::LocalLawWithoutC, names::LOCAL_LAW_IS_PROJECTION),
            (Breakage::ConeWithoutBackStress, names::CONE_MEMBERSHIP),
        ] {
            let e: KitFailure = conformance::check_all(&broken(p, how), &cfg).unwrap_err();
            assert_eq!(e.check, first, "{how:?}: {e}");
        }
        conformance::check_all(&p, &cfg).unwrap();
    }
}
