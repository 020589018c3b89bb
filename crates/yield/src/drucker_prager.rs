//! Drucker–Prager with linear isotropic hardening (theory §9): D = {(σ, ξ) : |dev σ| + α tr σ ≤
//! k₀ + ξ}, hardening metric ξη/h. α = 0 is von Mises ([`crate::VonMises`]).
//!
//! In the energy metric `Aσ:τ + ξη/h` the deviator, the trace and ξ are orthogonal: with
//! `s = dev σ`, `T = tr σ`, `Aσ:σ = |s|²/(2G) + T²/(9K_b)`. Projecting a general point (σ, ξ)
//! with `r = |s|`, `n = s/r`, `t₀ = k₀ + ξ` means solving
//! `min ½[|s' − s|²/(2G) + (T' − T)²/(9K_b) + (ξ' − ξ)²/h]` s.t. `|s'| + α T' ≤ k₀ + ξ'`.
//! The KKT conditions, with a multiplier γ ≥ 0 and `ν ∈ ∂|s'|`, are
//! `s' = s − 2Gγ ν`, `T' = T − 9K_b α γ`, `ξ' = ξ + hγ`. Write `v = 9K_b α² + h`.
//!
//! * Inside when `f = r + α T − t₀ ≤ 0`.
//! * Smooth return (`s' ≠ 0`, ν = n): the constraint active gives `γ = f/(2G + v)` and
//!   `|s'| = t = r − 2Gγ = (v r + 2G(t₀ − αT))/(2G + v)`; valid while `t > 0`. Then `s' = s t/r`,
//!   `T' = T − 9K_b α γ`, `ξ' = ξ + hγ`.
//! * Apex return (`s' = 0`, |ν| ≤ 1, so `r ≤ 2Gγ`): the constraint `α T' = k₀ + ξ'` gives
//!   `γ = (αT − t₀)/v`, and `r ≤ 2Gγ` is exactly `t ≤ 0`. Then `s' = 0`,
//!   `T' = (hT + 9K_b α t₀)/v`, `ξ' = ξ + hγ`: hydrostatic tension on the apex.
//!
//! The two cases meet continuously at `t = 0`. For h = 0 the metric is infinite in ξ: ξ is
//! frozen and the same formulas hold with h = 0 (the apex then has `T' = t₀/α`). When also
//! α = 0 (v = 0) this is perfect von Mises: radial return to `|s| = t₀`, and if `t₀ < 0` the
//! slice is empty and the point goes to `s = 0`, `ξ = −k₀` as [`crate::VonMises`] does.
//!
//! For the local law (ξ = 0, `t₀ = k₀ ≥ 0`) the apex is reached when
//! `v r < 2G(α T − k₀)`: hydrostatic tension beyond `k₀/α`, with little deviator.
//!
//! The step law of theory §11.1 projects the trial (C(ε − ε_p), ξ_n): the same returns with
//! `t₀ = k₀ + ξ_n` (v does not depend on ξ), ξ' from the yield condition `t + αT' = k₀ + ξ'`
//! (= ξ_n + hγ), and the same tangents, since t₀ is a constant of the step.

use saddle_core::error::{ParameterError, check};
use saddle_core::problem::elasticity::Elasticity;
use saddle_core::problem::return_mapping::{DeviatoricTrial, elastic_step, radial_tangent};
use saddle_core::problem::stresses::{AdmissibleStresses, ConeDescription, SocBlock, StepInput, StepOutput};
use saddle_core::problem::tensor::{Sym, deviator, identity, trace, volumetric_projector};
use serde::{Deserialize, Serialize};

use crate::VonMises;
use crate::hardening::{check_modulus, isotropic_inner};

/// Drucker–Prager yield with linear isotropic hardening (theory §9):
/// `D = {|dev σ| + α tr σ ≤ k₀ + ξ}`, `[σ̂, τ̂] = Aσ:τ + ξη/h`. Scene table:
/// `type = "drucker_prager"`, `k0`, `alpha`, `h`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DruckerPrager {
    /// Yield radius k₀ ≥ 0 of |dev σ| at tr σ = 0 (von Mises: `k₀ = √(2/3) σ_y`).
    pub k0: f64,
    /// Pressure sensitivity α ≥ 0: the admissible |dev σ| grows by α per unit of −tr σ
    /// (compression strengthens); α = 0 is von Mises.
    pub alpha: f64,
    /// Hardening modulus h ≥ 0 of the metric ξη/h; h = 0 is perfect plasticity.
    pub h: f64,
}

impl DruckerPrager {
    /// Drucker–Prager with yield radius `k0`, pressure sensitivity `alpha` and hardening
    /// modulus `h`, validated (errors name `yield.k0`, `yield.alpha`, `yield.h`).
    pub fn new(k0: f64, alpha: f64, h: f64) -> Result<Self, ParameterError> {
        let p = Self { k0, alpha, h };
        p.validate("yield")?;
        Ok(p)
    }

    /// `v = 9K_b α² + h`, the stiffness of the apex return (module docs).
    fn apex_modulus(&self, law: &Elasticity) -> f64 {
        9.0 * law.bulk_modulus() * self.alpha * self.alpha + self.h
    }
}

#[typetag::serde(name = "drucker_prager")]
impl AdmissibleStresses for DruckerPrager {
    /// k₀ ≥ 0 and α ≥ 0 with magnitudes ≤ [`check::MAX_MAGNITUDE`]; h ≥ 0, 0 or a scale in
    /// [1e-50, 1e50] ([`check::scale`]: 1/h enters the hardening metric), so that the solvers'
    /// products stay finite.
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::non_negative(path, "k0", self.k0)?;
        check::bounded(path, "k0", self.k0)?;
        check::non_negative(path, "alpha", self.alpha)?;
        check::bounded(path, "alpha", self.alpha)?;
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

    /// `|dev σ| + α tr σ ≤ k₀ + ξ + tol · max(k₀, |σ|, α|tr σ|, |ξ|)`: the tolerance is relative
    /// to the largest magnitude involved, floored at the smallest positive normal number.
    fn contains(&self, sigma: &Sym, q: &[f64], tol: f64) -> bool {
        let xi = q[0];
        let at = self.alpha * trace(sigma);
        let scale = self.k0.max(sigma.norm()).max(at.abs()).max(xi.abs()).max(f64::MIN_POSITIVE);
        deviator(sigma).norm() + at <= self.k0 + xi + tol * scale
    }

    /// Projection onto D in the energy metric (theory §9.1) for a general point (σ, ξ): the
    /// smooth return to the cone or the apex return, see the module docs. For h = 0 ξ is frozen.
    fn project(&self, law: &Elasticity, sigma: &mut Sym, q: &mut [f64]) -> bool {
        let s = deviator(sigma);
        let r = s.norm();
        let tr = trace(sigma);
        let t0 = self.k0 + q[0];
        if r + self.alpha * tr <= t0 {
            return false;
        }
        let kb = law.bulk_modulus();
        let g2 = 2.0 * law.shear_modulus();
        let v = self.apex_modulus(law);
        // |s'| of the smooth return; with α = 0 exactly the von Mises arithmetic
        let t = if v > 0.0 { (v * r + g2 * (t0 - self.alpha * tr)) / (g2 + v) } else { t0 };
        if t > 0.0 {
            let gamma = (r - t) / g2;
            let tr_new = tr - 9.0 * kb * self.alpha * gamma;
            *sigma = identity() * (tr_new / 3.0) + s * (t / r);
            if self.h > 0.0 {
                q[0] = t + self.alpha * tr_new - self.k0;
            }
        } else if v > 0.0 {
            // apex: γ = (αT − t₀)/v ≥ r/(2G)
            let gamma = (self.alpha * tr - t0) / v;
            let tr_new = tr - 9.0 * kb * self.alpha * gamma;
            *sigma = identity() * (tr_new / 3.0);
            if self.h > 0.0 {
                q[0] = self.alpha * tr_new - self.k0;
            }
        } else {
            // α = 0, h = 0 and k₀ + ξ ≤ 0: the slice of D is empty; the limit h → 0, as von Mises
            *sigma = identity() * (tr / 3.0);
            q[0] = -self.k0;
        }
        true
    }

    /// σ̂ = P_D(C(ε − ε_p), ξ_n) in closed form (theory §11.1): the local law's smooth or apex
    /// return with k₀ + ξ_n for k₀, ξ from the yield condition (frozen for h = 0), and the same
    /// tangents; when α = h = 0 and k₀ + ξ_n ≤ 0 (empty slice) the trial's mean stress with
    /// `K_b I⊗I`, as [`AdmissibleStresses::project`].
    fn step_law(&self, law: &Elasticity, step: StepInput<'_>, mut out: StepOutput<'_>) -> bool {
        let trial = DeviatoricTrial::new(law, &step);
        let DeviatoricTrial { g2, kb, s: s_tr, r, p } = trial;
        let (a, q_n) = (self.alpha, step.q_n);
        let t0 = self.k0 + q_n[0];
        if r + a * (3.0 * p) <= t0 {
            return elastic_step(law, trial.stress(), q_n, out);
        }
        let v = self.apex_modulus(law);
        let t = if v > 0.0 { (v * r + g2 * (t0 - a * (3.0 * p))) / (v + g2) } else { t0 };
        if t > 0.0 {
            let gamma = (r - t) / g2;
            let p_new = p - 3.0 * kb * a * gamma;
            *out.sigma = s_tr * (t / r) + identity() * p_new;
            out.q[0] = if self.h > 0.0 { t + a * (3.0 * p_new) - self.k0 } else { q_n[0] };
            out.set_tangent(|| {
                let n = s_tr / r;
                let i = identity();
                let dd = v + g2;
                radial_tangent(kb, &n, g2 * t / r, g2 * v / dd)
                    - (n * i.transpose() + i * n.transpose()) * (g2 * 3.0 * kb * a / dd)
                    - i * i.transpose() * (9.0 * kb * kb * a * a / dd)
            });
        } else if v > 0.0 {
            // apex: γ = (αT − t₀)/v ≥ r/(2G), T' = T − 9K_b α γ
            let gamma = (a * (3.0 * p) - t0) / v;
            let p_new = p - 3.0 * kb * a * gamma;
            *out.sigma = identity() * p_new;
            out.q[0] = if self.h > 0.0 { a * (3.0 * p_new) - self.k0 } else { q_n[0] };
            out.set_tangent(|| volumetric_projector() * (3.0 * kb * self.h / v));
        } else {
            // α = 0, h = 0 and k₀ + ξ_n ≤ 0: the slice of D is empty; the limit h → 0
            *out.sigma = identity() * p;
            out.q[0] = -self.k0;
            out.set_tangent(|| volumetric_projector() * (3.0 * kb));
        }
        true
    }

    /// `ψ(ε) = ½Cε:ε − ½ dist²((Cε, 0), D)` (theory §9.1): with `f = r + αT − k₀`,
    /// `dist² = f²/(2G + v)` on the smooth return and `r²/(2G) + (αT − k₀)²/v` at the apex.
    fn energy(&self, law: &Elasticity, eps: &Sym) -> f64 {
        let g2 = 2.0 * law.shear_modulus();
        let r = g2 * deviator(eps).norm();
        let tr = 3.0 * law.bulk_modulus() * trace(eps);
        let elastic = 0.5 * eps.dot(&law.stress(eps));
        let over = self.alpha * tr - self.k0;
        let f = r + over;
        if f <= 0.0 {
            return elastic;
        }
        let v = self.apex_modulus(law);
        if v * r >= g2 * over {
            elastic - f * f / (2.0 * (g2 + v))
        } else {
            elastic - r * r / (2.0 * g2) - over * over / (2.0 * v)
        }
    }

    /// One second-order cone of dimension 6 (theory §3, §9): `t = k₀ + ξ − α tr σ`,
    /// `x = (e_k·σ)_{k=1..5}` in the orthonormal deviatoric basis
    /// [`VonMises::deviatoric_basis`], so `|x| = |dev σ|`. The map is 6 × 7 row-major on (σ, ξ).
    fn cone(&self) -> Option<ConeDescription> {
        let mut offset = vec![0.0; 6];
        offset[0] = self.k0;
        let mut map = vec![0.0; 6 * 7];
        for m in map.iter_mut().take(3) {
            *m = -self.alpha;
        }
        map[6] = 1.0;
        for (k, e) in VonMises::deviatoric_basis().iter().enumerate() {
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
                if self.k0 == 0.0 {
                    ", but with k0 = 0 the admissible stresses form a cone with apex at σ = 0"
                } else {
                    ""
                }
            ));
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::conformance::{self, KitConfig, names};
    use crate::mutant::Mutant;
    use crate::testing::{assert_tangent_by_differences, close, law};
    use nalgebra::Matrix3;
    use saddle_core::problem::tensor::{SymOp, from_matrix};

    #[test]
    fn kit_passes_for_several_parameter_sets() {
        for &(k0, alpha, h) in &[
            (1.0f64, 0.0, 5.0),
            (1.0, 0.05, 5.0),
            (1.0, 0.3, 5.0),
            (1.0, 1.5, 5.0),
            (1.0, 0.3, 0.0),
            (1.0, 0.0, 0.0),
            (0.0, 0.2, 3.0),
            (0.0, 0.5, 0.0),
            (0.5, 0.1, 2000.0),
            (1.0, 0.2, 1e-4),
        ] {
            let cfg = KitConfig::new(law(), k0.max(0.1)).with_samples(150).with_seed(11);
            let dp = DruckerPrager::new(k0, alpha, h).unwrap();
            if let Err(e) = conformance::check_all(&dp, &cfg) {
                panic!("k0 = {k0}, alpha = {alpha}, h = {h}: {e}");
            }
        }
        let cfg = KitConfig::new(Elasticity::new(210e3, 0.49).unwrap(), 300.0).with_samples(150).with_seed(3);
        conformance::check_all(&DruckerPrager::new(300.0, 0.2, 1e3).unwrap(), &cfg).unwrap();
    }

    /// Ways to get the apex return wrong.
    #[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
    enum ApexBreakage {
        /// s = 0 but tr σ of the trial kept (the von Mises apex): outside D.
        KeepsTrace,
        /// s = 0 with the trace and ξ of the smooth-return γ (clamping the radial return): outside D.
        RadialClamp,
        /// s = 0, tr σ = (k₀ + ξ)/α with ξ frozen even for h > 0: in D, idempotent, not nearest.
        IgnoresHardening,
        /// the projection right, but the local law keeps the trial trace at the apex.
        LocalLawKeepsTrace,
        /// everything right but the tangent at the apex, zero as for h = 0.
        ApexTangentZero,
    }

    /// `dp` broken at the apex as `how` says.
    fn broken_apex(dp: DruckerPrager, how: ApexBreakage) -> Mutant {
        let m = Mutant::of(dp);
        match how {
            ApexBreakage::LocalLawKeepsTrace => m.with_local_law(move |_, law, eps, out| {
                let StepOutput { sigma, q, tangent } = out;
                let plastic = dp.local_law(law, eps, StepOutput::new(sigma, q, tangent));
                if plastic && deviator(sigma).norm() == 0.0 {
                    *sigma = identity() * (trace(&law.stress(eps)) / 3.0);
                }
                plastic
            }),
            ApexBreakage::ApexTangentZero => m.with_local_law(move |_, law, eps, mut out| {
                let mut c = SymOp::zeros();
                let plastic = dp.local_law(law, eps, StepOutput::new(out.sigma, out.q, Some(&mut c)));
                let at_apex = plastic && deviator(out.sigma).norm() == 0.0;
                out.set_tangent(|| if at_apex { SymOp::zeros() } else { c });
                plastic
            }),
            _ => m
                .with_project(move |_, law, sigma, q| {
                    let (x, xi) = (*sigma, q[0]);
                    let out = dp.project(law, sigma, q);
                    if !(out && deviator(sigma).norm() == 0.0 && deviator(&x).norm() > 0.0) {
                        return out;
                    }
                    let (kb, g2, a) = (law.bulk_modulus(), 2.0 * law.shear_modulus(), dp.alpha);
                    let (r, tr, t0) = (deviator(&x).norm(), trace(&x), dp.k0 + xi);
                    match how {
                        ApexBreakage::KeepsTrace => *sigma = identity() * (tr / 3.0),
                        ApexBreakage::RadialClamp => {
                            let gamma = (r + a * tr - t0) / (g2 + dp.apex_modulus(law));
                            *sigma = identity() * ((tr - 9.0 * kb * a * gamma) / 3.0);
                            if dp.h > 0.0 {
                                q[0] = xi + dp.h * gamma;
                            }
                        }
                        _ => {
                            *sigma = identity() * (t0 / a / 3.0);
                            q[0] = xi;
                        }
                    }
                    true
                })
                .with_local_law(|m, law, eps, out| m.local_law_from_projection(law, eps, out)),
        }
    }

    #[test]
    fn kit_catches_wrong_apex_returns() {
        let cfg = KitConfig::new(law(), 1.0).with_samples(150);
        let dp = DruckerPrager::new(1.0, 0.3, 5.0).unwrap();
        for (how, first) in [
            (ApexBreakage::KeepsTrace, names::PROJECTION_IN_SET),
            (ApexBreakage::RadialClamp, names::PROJECTION_IN_SET),
            (ApexBreakage::IgnoresHardening, names::VARIATIONAL_INEQUALITY),
            (ApexBreakage::LocalLawKeepsTrace, names::ENERGY_GRADIENT),
            (ApexBreakage::ApexTangentZero, names::TANGENT),
        ] {
            let e = conformance::check_all(&broken_apex(dp, how), &cfg).unwrap_err();
            println!("{how:?}: {e}");
            assert_eq!(e.check, first, "{how:?}: {e}");
        }
        conformance::check_all(&dp, &cfg).unwrap();
    }

    #[test]
    fn alpha_zero_is_von_mises() {
        use rand::{Rng, SeedableRng, rngs::StdRng};
        let law = law();
        let mut rng = StdRng::seed_from_u64(5);
        for &(k0, h) in &[(1.0, 5.0), (1.0, 0.0), (0.0, 3.0), (0.5, 2000.0)] {
            let (dp, vm) = (DruckerPrager::new(k0, 0.0, h).unwrap(), VonMises::new(k0, h).unwrap());
            let mut plastic = 0;
            for _ in 0..500 {
                let eps = Sym::from_fn(|_, _| rng.random_range(-0.05..0.05));
                let (mut s1, mut q1, mut c1) = (Sym::zeros(), [0.0], SymOp::zeros());
                let (mut s2, mut q2, mut c2) = (Sym::zeros(), [0.0], SymOp::zeros());
                let p1 = dp.local_law(&law, &eps, StepOutput::new(&mut s1, &mut q1, Some(&mut c1)));
                let p2 = vm.local_law(&law, &eps, StepOutput::new(&mut s2, &mut q2, Some(&mut c2)));
                assert_eq!(p1, p2);
                plastic += p1 as usize;
                let scale = s2.norm().max(k0).max(1.0);
                assert!((s1 - s2).norm() <= 1e-14 * scale, "{s1:?} vs {s2:?}");
                assert!((q1[0] - q2[0]).abs() <= 1e-14 * scale);
                assert!((c1 - c2).norm() <= 1e-13 * c2.norm());
                let (e1, e2) = (dp.energy(&law, &eps), vm.energy(&law, &eps));
                assert!((e1 - e2).abs() <= 1e-14 * e2.abs().max(1e-3), "{e1} vs {e2}");
                // general points
                let sig = law.stress(&eps);
                let xi = rng.random_range(-2.0..2.0);
                let (mut a, mut qa, mut b, mut qb) = (sig, [xi], sig, [xi]);
                assert_eq!(dp.project(&law, &mut a, &mut qa), vm.project(&law, &mut b, &mut qb));
                assert!((a - b).norm() <= 1e-14 * sig.norm().max(1.0) && (qa[0] - qb[0]).abs() <= 1e-14 * scale);
            }
            assert!(plastic > 100, "plastic {plastic}/500");
        }
        assert_eq!(DruckerPrager::new(1.5, 0.0, 5.0).unwrap().cone(), VonMises::new(1.5, 5.0).unwrap().cone());
    }

    /// Hydrostatic tension trials ε = e I reach the apex for every e with α·3K_b·3e > k₀ (s_tr = 0,
    /// r = 0: t = 2G(k₀ − αT)/(2G + v) < 0); tension with a small deviator too.
    #[test]
    fn hydrostatic_tension_returns_to_the_apex() {
        let law = law();
        let kb = law.bulk_modulus();
        let dp = DruckerPrager::new(1.0, 0.3, 5.0).unwrap();
        let dev = deviator(&Sym::new(1.0, -0.3, 0.2, 0.1, 0.0, -0.2));
        let dev = dev / dev.norm();
        let (mut apex, mut plastic, n) = (0, 0, 200);
        for k in 0..n {
            let e = -0.01 + 0.05 * k as f64 / n as f64;
            let eps = identity() * e + dev * (1e-4 * (k % 3) as f64);
            let (mut s, mut q, mut c) = (Sym::zeros(), [0.0], SymOp::zeros());
            let pl = dp.local_law(&law, &eps, StepOutput::new(&mut s, &mut q, Some(&mut c)));
            plastic += pl as usize;
            if pl && deviator(&s).norm() == 0.0 {
                apex += 1;
                // on the apex: α tr σ = k₀ + ξ, and the tangent is volumetric
                assert!(close(0.3 * trace(&s), 1.0 + q[0], 1e-13), "{s:?} {q:?}");
                assert!(close(identity().dot(&(c * identity())) / 9.0, kb * 5.0 / dp.apex_modulus(&law), 1e-13));
            }
        }
        println!("apex returns: {apex} of {n} hydrostatic-tension trials ({plastic} plastic)");
        assert!(apex > n / 3, "apex {apex}");
    }

    /// The hand-checkable cases (E = 100, ν = 1/4, so 2G = 80, 3K_b = 200, 9K_b = 600;
    /// k₀ = 1, α = 0.1, h = 14: v = 9K_b α² + h = 6 + 14 = 20, 2G + v = 100).
    ///
    /// Smooth return. ε = 0.01 I + 0.025 M, M = [[1,0,0],[0,−1,1],[0,1,0]] (tr M = 0, |M| = 2):
    /// s_tr = 80 · 0.025 M = 2M, r = 4; tr σ_tr = 200 · 0.03 = 6; f = 4 + 0.6 − 1 = 3.6 > 0;
    /// γ = 3.6/100 = 0.036; t = r − 2Gγ = 4 − 2.88 = 1.12 > 0; tr σ = 6 − 600 · 0.1 · 0.036
    /// = 3.84; ξ = 14 · 0.036 = 0.504; check |s| + α tr σ = 1.12 + 0.384 = 1.504 = k₀ + ξ.
    /// σ = 0.56 M + 1.28 I. ψ = ½Cε:ε − f²/(2 · 100) with Cε:ε = 2M:0.025M + 6 · 0.01 = 0.26:
    /// ψ = 0.13 − 0.0648 = 0.0652.
    ///
    /// Apex return. ε = 0.05 I + 0.0025 M: s_tr = 0.2 M, r = 0.4; tr σ_tr = 30, α tr σ_tr = 3;
    /// t = (20 · 0.4 + 80 (1 − 3))/100 = −1.52 < 0: apex. γ = (3 − 1)/20 = 0.1 (≥ r/2G = 0.005);
    /// tr σ = 30 − 60 · 0.1 = 24, σ = 8 I, ξ = 1.4 (α tr σ = 2.4 = k₀ + ξ). With
    /// Cε:ε = 0.2M:0.0025M + 30 · 0.05 = 0.002 + 1.5 = 1.502,
    /// ψ = 0.751 − r²/(4G) − 2²/(2v) = 0.751 − 0.001 − 0.1 = 0.65. The tangent is (K_b h/v) I⊗I:
    /// I:C_t:I/9 = K_b h/v = (200/3) · 14/20 = 140/3, and C_t M = 0.
    #[test]
    fn local_law_matches_returns_worked_by_hand() {
        let law = Elasticity::new(100.0, 0.25).unwrap();
        let dp = DruckerPrager::new(1.0, 0.1, 14.0).unwrap();
        let mm = Matrix3::new(1.0, 0.0, 0.0, 0.0, -1.0, 1.0, 0.0, 1.0, 0.0);
        let m = from_matrix(&mm);
        let (mut s, mut q, mut c) = (Sym::zeros(), [0.0], SymOp::zeros());

        let eps = from_matrix(&(Matrix3::identity() * 0.01 + mm * 0.025));
        assert!(dp.local_law(&law, &eps, StepOutput::new(&mut s, &mut q, Some(&mut c))));
        assert!((s - (m * 0.56 + identity() * 1.28)).norm() < 1e-13, "{s:?}");
        assert!((q[0] - 0.504).abs() < 1e-14, "{q:?}");
        assert!((dp.energy(&law, &eps) - 0.0652).abs() < 1e-14);
        assert!((c - c.transpose()).norm() < 1e-12);

        let eps = from_matrix(&(Matrix3::identity() * 0.05 + mm * 0.0025));
        assert!(dp.local_law(&law, &eps, StepOutput::new(&mut s, &mut q, Some(&mut c))));
        assert!((s - identity() * 8.0).norm() < 1e-13, "{s:?}");
        assert!((q[0] - 1.4).abs() < 1e-13, "{q:?}");
        assert!((dp.energy(&law, &eps) - 0.65).abs() < 1e-13, "{}", dp.energy(&law, &eps));
        assert!((identity().dot(&(c * identity())) / 9.0 - 140.0 / 3.0).abs() < 1e-12);
        assert!((c * m).norm() < 1e-12, "no deviatoric stiffness at the apex");
        // the projection of the trial with ξ = 0 gives the same
        let (mut s2, mut q2) = (law.stress(&eps), [0.0]);
        assert!(dp.project(&law, &mut s2, &mut q2));
        assert!((s2 - s).norm() < 1e-13 && (q2[0] - 1.4).abs() < 1e-13);
    }

    /// Load steps from a hardened state ξ_n = 0.6 (theory §11.1), the material of
    /// `local_law_matches_returns_worked_by_hand` (2G = 80, 3K_b = 200, 9K_b = 600, k₀ = 1,
    /// α = 0.1, h = 14, v = 20, 2G + v = 100), so t₀ = k₀ + ξ_n = 1.6; ε_p = 0.01M − 0.002 I.
    ///
    /// * Smooth: ε − ε_p = 0.01 I + 0.025 M, s_tr = 2M, r = 4, T = 6: f = 4 + 0.6 − 1.6 = 3,
    ///   γ = 3/100 = 0.03, t = 4 − 2.4 = 1.6, T' = 6 − 600 · 0.1 · 0.03 = 4.2, σ = 0.8M + 1.4 I,
    ///   ξ = t + αT' − k₀ = 1.02 = ξ_n + hγ. Tangent (a unit strain δ along I gives dT = 600δ,
    ///   dγ = α dT/100 = 0.6δ, dt = −2G dγ): n:C_t:n = 2G v/(2G + v) = 16, m:C_t:m = 2G t/r = 32
    ///   for deviators m ⟂ n, n:C_t:I = −48, I:C_t:I = 600 − 36 = 564.
    /// * Apex: ε − ε_p = 0.05 I + 0.0025 M, r = 0.4, T = 30: t = (8 + 80(1.6 − 3))/100 = −1.04 < 0;
    ///   γ = (3 − 1.6)/20 = 0.07, T' = 30 − 4.2 = 25.8, σ = 8.6 I, ξ = 1.58 (αT' = 2.58 = k₀ + ξ);
    ///   tangent (K_b h/v) I⊗I, I:C_t:I/9 = 140/3.
    /// * Elastic from the state: ε − ε_p = 0.01 I + 0.006 M, f = 0.96 + 0.6 − 1.6 < 0 (the local
    ///   law, with k₀ = 1, is plastic there).
    #[test]
    fn step_law_from_a_hardened_state_worked_by_hand() {
        let law = Elasticity::new(100.0, 0.25).unwrap();
        let dp = DruckerPrager::new(1.0, 0.1, 14.0).unwrap();
        let m = from_matrix(&Matrix3::new(1.0, 0.0, 0.0, 0.0, -1.0, 1.0, 0.0, 1.0, 0.0));
        let i3 = identity();
        let ep = m * 0.01 - i3 * 0.002;
        let near = |a: f64, b: f64| (a - b).abs() <= 1e-12;
        let (mut s, mut q, mut c) = (Sym::zeros(), [0.0], SymOp::zeros());

        let eps = ep + i3 * 0.01 + m * 0.025;
        assert!(dp.step_law(&law, StepInput::new(&eps, &ep, &[0.6]), StepOutput::new(&mut s, &mut q, Some(&mut c))));
        assert!((s - (m * 0.8 + i3 * 1.4)).norm() < 1e-13 && near(q[0], 1.02), "σ = {s}, ξ = {}", q[0]);
        let (n, cross) = (m * 0.5, Sym::new(1.0, 1.0, -2.0, 0.0, 0.0, 0.0) / 6.0f64.sqrt());
        assert!(near(n.dot(&(c * n)), 16.0) && near(cross.dot(&(c * cross)), 32.0));
        assert!(near(n.dot(&(c * i3)), -48.0) && near(i3.dot(&(c * i3)), 564.0), "{c}");
        assert_tangent_by_differences(&dp, &law, StepInput::new(&eps, &ep, &[0.6]), &c);
        let (mut s3, mut q3) = (law.stress(&(eps - ep)), [0.6]);
        assert!(dp.project(&law, &mut s3, &mut q3) && (s3 - s).norm() < 1e-13 && near(q3[0], 1.02));

        let eps = ep + i3 * 0.05 + m * 0.0025;
        assert!(dp.step_law(&law, StepInput::new(&eps, &ep, &[0.6]), StepOutput::new(&mut s, &mut q, Some(&mut c))));
        assert!((s - i3 * 8.6).norm() < 1e-13 && near(q[0], 1.58), "σ = {s}, ξ = {}", q[0]);
        assert!(near(i3.dot(&(c * i3)) / 9.0, 140.0 / 3.0) && (c * m).norm() < 1e-12);
        assert_tangent_by_differences(&dp, &law, StepInput::new(&eps, &ep, &[0.6]), &c);

        let eps = ep + i3 * 0.01 + m * 0.006;
        assert!(!dp.step_law(&law, StepInput::new(&eps, &ep, &[0.6]), StepOutput::new(&mut s, &mut q, Some(&mut c))));
        assert!(s == law.stress(&(eps - ep)) && q[0] == 0.6 && c == law.stiffness_matrix());
        assert!(dp.local_law(&law, &(eps - ep), StepOutput::new(&mut s, &mut q, None)));

        // h = 0: ξ frozen at ξ_n, on the boundary k₀ + ξ_n
        let pp = DruckerPrager::new(1.0, 0.1, 0.0).unwrap();
        let eps = ep + i3 * 0.01 + m * 0.025;
        assert!(pp.step_law(&law, StepInput::new(&eps, &ep, &[0.6]), StepOutput::new(&mut s, &mut q, Some(&mut c))));
        assert!(q[0] == 0.6 && near(deviator(&s).norm() + 0.1 * trace(&s), 1.6));
        assert_tangent_by_differences(&pp, &law, StepInput::new(&eps, &ep, &[0.6]), &c);
    }

    #[test]
    fn projection_of_general_points() {
        let law = law();
        let (kb, g2) = (law.bulk_modulus(), 2.0 * law.shear_modulus());
        let dp = DruckerPrager::new(1.0, 0.2, 5.0).unwrap();
        let v = 9.0 * kb * 0.04 + 5.0;
        let dir = deviator(&Sym::new(1.0, 0.2, -0.5, 0.3, 0.0, -0.4));
        let dir = dir / dir.norm();
        // smooth return with ξ ≠ 0: r = 3, tr = 2.1, t0 = 1.5
        let x = (identity() * 0.7 + dir * 3.0, 0.5);
        let (mut s, mut q) = (x.0, [x.1]);
        assert!(dp.project(&law, &mut s, &mut q));
        let gamma = (3.0 + 0.2 * 2.1 - 1.5) / (g2 + v);
        assert!(close(deviator(&s).norm(), 3.0 - g2 * gamma, 1e-13));
        assert!(close(trace(&s), 2.1 - 9.0 * kb * 0.2 * gamma, 1e-13));
        assert!(close(q[0], 0.5 + 5.0 * gamma, 1e-13));
        assert!((deviator(&s) / deviator(&s).norm() - dir).norm() < 1e-14, "radial in the deviator");
        // apex with ξ ≠ 0: r = 0.1, tr = 30, t0 = 0.5
        let x = (identity() * 10.0 + dir * 0.1, -0.5);
        let (mut s, mut q) = (x.0, [x.1]);
        assert!(dp.project(&law, &mut s, &mut q));
        let gamma = (0.2 * 30.0 - 0.5) / v;
        assert!(gamma * g2 >= 0.1);
        assert_eq!(deviator(&s).norm(), 0.0);
        assert!(close(trace(&s), 30.0 - 9.0 * kb * 0.2 * gamma, 1e-13) && close(q[0], -0.5 + 5.0 * gamma, 1e-13));
        // nearest: [x − Px, y − Px] ≤ 0 for points y of D
        let ip = |px: &(Sym, f64), y: &(Sym, f64)| {
            law.compliance(&(x.0 - px.0)).dot(&(y.0 - px.0)) + (x.1 - px.1) * (y.1 - px.1) / 5.0
        };
        for y in [(Sym::zeros(), 0.0), (dir * 0.5, 0.0), (identity() * 3.0, 1.0), (identity() * -3.0 + dir, 0.0)] {
            assert!(dp.contains(&y.0, &[y.1], 0.0));
            assert!(ip(&(s, q[0]), &y) <= 1e-12, "{y:?}");
        }
        // h = 0: ξ frozen, apex on α tr σ = k₀ + ξ
        let pp = DruckerPrager::new(1.0, 0.2, 0.0).unwrap();
        let (mut s, mut q) = (x.0, [x.1]);
        assert!(pp.project(&law, &mut s, &mut q));
        assert!(deviator(&s).norm() == 0.0 && q[0] == -0.5 && close(trace(&s), 0.5 / 0.2, 1e-13));
        // inside: unchanged
        let (mut s, mut q) = (identity() * -1.0 + dir * 1.0, [0.0]);
        assert!(!dp.project(&law, &mut s, &mut q));
        assert_eq!(s, identity() * -1.0 + dir * 1.0);
    }

    #[test]
    fn cone_block_is_the_yield_function() {
        let dp = DruckerPrager::new(1.5, 0.3, 5.0).unwrap();
        let b = &dp.cone().unwrap().blocks[0];
        assert_eq!((b.dim, b.offset.len(), b.map.len()), (6, 6, 42));
        let sigma = Sym::new(3.0, -1.0, 0.5, 0.7, -0.2, 0.9);
        let z: Vec<f64> = sigma.iter().copied().chain([0.25]).collect();
        let v: Vec<f64> = (0..6).map(|i| b.offset[i] + (0..7).map(|j| b.map[i * 7 + j] * z[j]).sum::<f64>()).collect();
        assert!((v[0] - (1.75 - 0.3 * 2.5)).abs() < 1e-15);
        let x = (v[1..].iter().map(|x| x * x).sum::<f64>()).sqrt();
        assert!((x - deviator(&sigma).norm()).abs() < 1e-14);
    }

    #[test]
    fn validation_warnings_and_toml() {
        let ok = DruckerPrager::new(1.0, 0.2, 5.0).unwrap();
        assert!(ok.validate("yield").is_ok() && ok.warnings().is_empty());
        for (dp, field, value) in [
            (DruckerPrager::new(-1.0, 0.2, 5.0), "yield.k0", "-1"),
            (DruckerPrager::new(1.0, -0.5, 5.0), "yield.alpha", "-0.5"),
            (DruckerPrager::new(1.0, 0.2, -2.0), "yield.h", "-2"),
            (DruckerPrager::new(1.0, f64::NAN, 5.0), "yield.alpha", "NaN"),
            (DruckerPrager::new(1.0, 0.2, f64::INFINITY), "yield.h", "inf"),
        ] {
            let e = dp.unwrap_err();
            assert_eq!(e.field, field, "{e}");
            assert_eq!(e.value.to_lowercase(), value.to_lowercase(), "{e}");
        }
        let w = DruckerPrager::new(1.0, 0.2, 0.0).unwrap().warnings();
        assert!(w.len() == 1 && w[0].contains("unique"), "{w:?}");
        let p: Box<dyn AdmissibleStresses> =
            toml::from_str("type = \"drucker_prager\"\nk0 = 1.0\nalpha = 0.2\nh = 5.0").unwrap();
        assert_eq!((p.name(), p.hardening_dim()), ("drucker_prager", 1));
        assert_eq!(p.hardening_fields(), vec![("xi", 1)]);
        // the apex is at α tr σ = k₀: tr σ = 5
        assert!(p.contains(&(identity() * (5.0 / 3.0)), &[0.0], 1e-12));
        assert!(!p.contains(&(identity() * 1.67), &[0.0], 0.0));
        let err =
            toml::from_str::<Box<dyn AdmissibleStresses>>("type = \"drucker_prager\"\nk0 = 1.0\nh = 5.0").unwrap_err();
        assert!(err.to_string().contains("alpha"), "{err}");
    }
}
