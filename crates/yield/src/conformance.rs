//! The conformance kit: checks that ANY implementation of [`AdmissibleStresses`] must pass
//! (theory §1–§3). A plugin author calls [`check_all`] (or the single checks) from the tests of
//! their own crate:
//!
//! ```
//! use saddle_core::Elasticity;
//! use saddle_yield::VonMises;
//! use saddle_yield::conformance::{KitConfig, check_all};
//!
//! let law = Elasticity::new(100.0, 0.3).unwrap();
//! let cfg = KitConfig::new(law, 1.0); // stress scale: k0
//! check_all(&VonMises { k0: 1.0, h: 5.0 }, &cfg).unwrap();
//! ```
//!
//! # Samples
//!
//! Every check draws its own seeded samples ([`KitConfig::seed`]), so a failure is
//! reproducible and the checks do not depend on each other's order. With `S` the stress scale
//! ([`KitConfig::stress_scale`], e.g. k₀):
//!
//! * a random *stress* has a deviator of norm uniform in `[0, 5S]` and a mean stress uniform in
//!   `[−2S, 2S]`, so trial stresses fall both inside and outside any yield surface of size
//!   about S. The deviator's direction is random (half the draws), or has principal values
//!   with an exactly repeated pair — axisymmetric stress states, which reach the edges and
//!   corners of surfaces with non-smooth meridians such as Tresca's (a sixth), or a nearly
//!   repeated pair, which lands next to them (a sixth); a sixth of the draws are purely
//!   hydrostatic (no deviator), with the mean stress up to `5S`, which reaches the apex of
//!   pressure-dependent surfaces such as Drucker–Prager's. Every such state is turned by a
//!   random rotation;
//! * a random *strain* is `A σ` for such a stress (its trial stress `Cε` is that stress);
//! * random *hardening variables* are 0 with probability ¼ (the local-law state), else each
//!   uniform in `[−2S, 2S]`, negative values included (the projection of a general point
//!   must handle them: for von Mises ξ < −k₀ reaches the apex of the cone);
//! * a random *load-step state* (ε_p, q_n) for the step law of theory §11.1 is, by kind: 0 the
//!   virgin state (0, 0); 1 a plastic strain ε_p = ½ A σ for a random stress σ, with q_n = 0;
//!   2 such an ε_p with the hardening variables of the projection of a random point (admissible:
//!   the slice of D at q_n is not empty); 3 such an ε_p with random hardening variables (general
//!   points, which may reach the apex). The strain of a step is ε_p plus a random strain, so the
//!   trial C(ε − ε_p) is a random stress.
//!
//! # Metric and tolerances
//!
//! Projection checks use the energy metric `[σ̂, τ̂] = Aσ:τ + q·H⁻¹r` of the plugin
//! ([`saddle_core::problem::stresses::energy_inner`]). The metric may be infinite in some directions
//! (h = 0: ξ is frozen): pairs at infinite distance are not compared, and tolerances are built
//! from the finite part of the norms only. Exact identities are checked to
//! [`KitConfig::exact_tol`] relative to the magnitudes involved (plus a floor at the stress
//! scale); finite-difference checks use central differences with a step
//! [`KitConfig::fd_step`] relative to |ε| and a tolerance [`KitConfig::fd_tol`] relative to
//! |σ| (gradient) or to the largest eigenvalue of C (tangent). NaN always fails.

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use saddle_core::problem::elasticity::Elasticity;
use saddle_core::problem::stresses::{AdmissibleStresses, MAX_HARDENING_DIM, StepInput, StepOutput, energy_inner};
use saddle_core::problem::tensor::{Sym, SymOp, deviator, from_matrix, identity};
use thiserror::Error;

/// The names of the checks, as reported in [`KitFailure::check`].
pub mod names {
    /// The plugin and the configuration are usable at all (valid parameters,
    /// `hardening_dim() ≤ MAX_HARDENING_DIM`, positive scales).
    pub const SETUP: &str = "setup";
    /// (a) the projection lies in D.
    pub const PROJECTION_IN_SET: &str = "projection_in_set";
    /// (b) the projection is idempotent and leaves points of D in place.
    pub const IDEMPOTENT: &str = "idempotent";
    /// (c) the variational inequality of theory §2.
    pub const VARIATIONAL_INEQUALITY: &str = "variational_inequality";
    /// (d) the projection is non-expansive in the energy metric.
    pub const NON_EXPANSIVE: &str = "non_expansive";
    /// (e) ∂ψ/∂ε = σ.
    pub const ENERGY_GRADIENT: &str = "energy_gradient";
    /// (f) the consistent tangent is the derivative of ε ↦ σ(ε).
    pub const TANGENT: &str = "tangent";
    /// (g) ψ is convex along segments.
    pub const CONVEXITY: &str = "convexity";
    /// (h) the local law is the projection of (Cε, 0).
    pub const LOCAL_LAW_IS_PROJECTION: &str = "local_law_is_projection";
    /// (i) the cone description describes D.
    pub const CONE_MEMBERSHIP: &str = "cone_membership";
    /// (j) ψ(ε) = ε:σ − ½[σ̂, σ̂].
    pub const ENERGY_IDENTITY: &str = "energy_identity";
    /// (k) the step law is the projection of (C(ε − ε_p), q_n), and the local law at the
    /// virgin state.
    pub const STEP_LAW_IS_PROJECTION: &str = "step_law_is_projection";
    /// (l) the step law's tangent is the derivative of ε ↦ σ(ε) at a fixed state.
    pub const STEP_TANGENT: &str = "step_tangent";
    /// (m) ∂ψ_n/∂ε = σ of the step law.
    pub const STEP_ENERGY_GRADIENT: &str = "step_energy_gradient";
}

/// How the kit samples and what it tolerates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KitConfig {
    /// The elasticity C (and A = C⁻¹) of the energy metric.
    pub law: Elasticity,
    /// The stress scale S of the yield surface (k₀ for von Mises; any typical stress for an
    /// unbounded D): samples range over a few S.
    pub stress_scale: f64,
    /// Samples per check.
    pub samples: usize,
    /// Seed of the random samples.
    pub seed: u64,
    /// Relative tolerance of exact identities (projection, energy identity): 1e-12.
    pub exact_tol: f64,
    /// Relative tolerance of finite-difference checks: 1e-5.
    pub fd_tol: f64,
    /// Central-difference step relative to |ε|: 1e-6.
    pub fd_step: f64,
}

impl KitConfig {
    /// The default configuration for elasticity `law` and stress scale `stress_scale`:
    /// 200 samples per check, seed 1977, tolerances 1e-12 (exact) and 1e-5 (finite
    /// differences, step 1e-6).
    pub fn new(law: Elasticity, stress_scale: f64) -> Self {
        Self { law, stress_scale, samples: 200, seed: 1977, exact_tol: 1e-12, fd_tol: 1e-5, fd_step: 1e-6 }
    }

    /// The same with `samples` samples per check.
    pub fn with_samples(mut self, samples: usize) -> Self {
        self.samples = samples;
        self
    }

    /// The same with another seed.
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }
}

impl Default for KitConfig {
    /// The default scene of theory §6: E = 100, ν = 0.3, stress scale k₀ = 1.
    fn default() -> Self {
        Self::new(Elasticity { young: 100.0, poisson: 0.3 }, 1.0)
    }
}

/// A failed check: which one, and the numbers that failed it.
#[derive(Clone, Debug, Error, PartialEq)]
#[error("conformance check `{check}` failed: {message}")]
pub struct KitFailure {
    /// The check's name, one of [`names`].
    pub check: &'static str,
    /// What was compared, with the numbers and the sample.
    pub message: String,
}

/// Runs every check, in the order (setup, a … m), and returns the first failure.
pub fn check_all(p: &dyn AdmissibleStresses, cfg: &KitConfig) -> Result<(), KitFailure> {
    setup(p, cfg)?;
    projection_in_set(p, cfg)?;
    idempotent(p, cfg)?;
    variational_inequality(p, cfg)?;
    non_expansive(p, cfg)?;
    energy_gradient(p, cfg)?;
    tangent(p, cfg)?;
    convexity(p, cfg)?;
    local_law_is_projection(p, cfg)?;
    cone_membership(p, cfg)?;
    energy_identity(p, cfg)?;
    step_law_is_projection(p, cfg)?;
    step_tangent(p, cfg)?;
    step_energy_gradient(p, cfg)?;
    Ok(())
}

/// The plugin's parameters validate, `hardening_dim() ≤ MAX_HARDENING_DIM`, and the
/// configuration is usable (valid elasticity, positive finite scale and tolerances, samples).
pub fn setup(p: &dyn AdmissibleStresses, cfg: &KitConfig) -> Result<(), KitFailure> {
    let fail = |message: String| Err(KitFailure { check: names::SETUP, message });
    if let Err(e) = p.validate("yield") {
        return fail(format!("the plugin's parameters do not validate: {e}"));
    }
    if p.hardening_dim() > MAX_HARDENING_DIM {
        return fail(format!(
            "hardening_dim() = {} exceeds MAX_HARDENING_DIM = {MAX_HARDENING_DIM}",
            p.hardening_dim()
        ));
    }
    if let Err(e) = cfg.law.validate("law") {
        return fail(format!("KitConfig: {e}"));
    }
    for (name, v) in [
        ("stress_scale", cfg.stress_scale),
        ("exact_tol", cfg.exact_tol),
        ("fd_tol", cfg.fd_tol),
        ("fd_step", cfg.fd_step),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return fail(format!("KitConfig.{name} = {v} must be finite and > 0"));
        }
    }
    if cfg.samples == 0 {
        return fail("KitConfig.samples = 0: nothing would be checked".into());
    }
    Ok(())
}

/// (a) P_D(x) ∈ D: `contains(P x, exact_tol)` for random generalised stresses x, and P x is
/// finite.
pub fn projection_in_set(p: &dyn AdmissibleStresses, cfg: &KitConfig) -> Result<(), KitFailure> {
    let mut kit = Kit::new(p, cfg, names::PROJECTION_IN_SET)?;
    for i in 0..cfg.samples {
        let x = kit.point();
        let (px, _) = kit.project(&x);
        if !kit.is_finite(&px) {
            return kit.fail(format!(
                "sample {i}: the projection of {} is not finite: {}",
                kit.show(&x),
                kit.show(&px)
            ));
        }
        if !p.contains(&px.s, kit.q(&px), cfg.exact_tol) {
            return kit.fail(format!(
                "sample {i}: the projection {} of {} is not in D (contains with tol {:e} says no)",
                kit.show(&px),
                kit.show(&x),
                cfg.exact_tol
            ));
        }
    }
    Ok(())
}

/// (b) P(P x) = P x, and P y = y for points y that `contains` accepts, to `exact_tol`
/// relative to the energy norm of the point (plus a floor at the stress scale).
pub fn idempotent(p: &dyn AdmissibleStresses, cfg: &KitConfig) -> Result<(), KitFailure> {
    let mut kit = Kit::new(p, cfg, names::IDEMPOTENT)?;
    for i in 0..cfg.samples {
        let x = kit.point();
        let (px, _) = kit.project(&x);
        let (ppx, _) = kit.project(&px);
        let d = kit.sq(&kit.sub(&ppx, &px)).sqrt();
        let bound = cfg.exact_tol * (kit.finite_norm(&px) + kit.norm_floor());
        if d.is_nan() || d > bound {
            return kit.fail(format!(
                "sample {i}: P(Px) differs from Px by {d:e} in the energy norm (tolerance {bound:e}); x = {}, Px = {}, P(Px) = {}",
                kit.show(&x),
                kit.show(&px),
                kit.show(&ppx)
            ));
        }
        if p.contains(&x.s, kit.q(&x), 0.0) {
            let d = kit.sq(&kit.sub(&px, &x)).sqrt();
            let bound = cfg.exact_tol * (kit.finite_norm(&x) + kit.norm_floor());
            if d.is_nan() || d > bound {
                return kit.fail(format!(
                    "sample {i}: x is in D but Px moved it by {d:e} in the energy norm (tolerance {bound:e}); x = {}, Px = {}",
                    kit.show(&x),
                    kit.show(&px)
                ));
            }
        }
    }
    Ok(())
}

/// (c) The variational inequality of theory §2: `[x − Px, y − Px] ≤ tol` for admissible y —
/// projections of random points, projections of random stresses with the hardening variables
/// of Px, projections of points near Px, and random points that `contains` accepts. Pairs with
/// `[y − Px] = ∞` are skipped; the tolerance is `exact_tol` times the square of the sum of the
/// (finite) norms of x, Px, y and the stress-scale floor.
pub fn variational_inequality(p: &dyn AdmissibleStresses, cfg: &KitConfig) -> Result<(), KitFailure> {
    let mut kit = Kit::new(p, cfg, names::VARIATIONAL_INEQUALITY)?;
    let mut compared = 0;
    for i in 0..cfg.samples {
        let x = kit.point();
        let (px, _) = kit.project(&x);
        let dx = kit.sub(&x, &px);
        for kind in 0..4 {
            let y = match kind {
                0 => {
                    let y = kit.point();
                    kit.project(&y).0
                }
                1 => {
                    let y = Point { s: kit.stress(), q: px.q };
                    kit.project(&y).0
                }
                2 => {
                    let y = kit.near(&px, 0.05);
                    kit.project(&y).0
                }
                _ => match kit.admissible_point() {
                    Some(y) => y,
                    None => continue,
                },
            };
            let dy = kit.sub(&y, &px);
            if !kit.sq(&dy).is_finite() {
                continue;
            }
            compared += 1;
            let v = kit.ip(&dx, &dy);
            let a = kit.finite_norm(&x) + kit.finite_norm(&px) + kit.finite_norm(&y) + kit.norm_floor();
            let bound = cfg.exact_tol * a * a;
            if v.is_nan() || v > bound {
                return kit.fail(format!(
                    "sample {i}: [x − Px, y − Px] = {v:e} > {bound:e} for the admissible y = {} (kind {kind}); x = {}, Px = {}",
                    kit.show(&y),
                    kit.show(&x),
                    kit.show(&px)
                ));
            }
        }
    }
    kit.require_some(compared, "pairs (x, y) at finite distance")
}

/// (d) `[Px − Py] ≤ [x − y]` (energy norm squared) for random pairs: independent, close
/// (stress perturbed by 5 %), and sharing the hardening variables. Pairs with `[x − y] = ∞`
/// are skipped.
pub fn non_expansive(p: &dyn AdmissibleStresses, cfg: &KitConfig) -> Result<(), KitFailure> {
    let mut kit = Kit::new(p, cfg, names::NON_EXPANSIVE)?;
    let mut compared = 0;
    for i in 0..cfg.samples {
        let x = kit.point();
        let y = match i % 3 {
            0 => kit.point(),
            1 => kit.near(&x, 0.05),
            _ => Point { s: kit.stress(), q: x.q },
        };
        let dxy = kit.sq(&kit.sub(&x, &y));
        if !dxy.is_finite() {
            continue;
        }
        compared += 1;
        let ((px, _), (py, _)) = (kit.project(&x), kit.project(&y));
        let dp = kit.sq(&kit.sub(&px, &py));
        let a =
            kit.finite_norm(&x) + kit.finite_norm(&y) + kit.finite_norm(&px) + kit.finite_norm(&py) + kit.norm_floor();
        let bound = dxy + cfg.exact_tol * a * a;
        if dp.is_nan() || dp > bound {
            return kit.fail(format!(
                "sample {i}: [Px − Py] = {dp:e} > [x − y] = {dxy:e} (tolerance {:e}); x = {}, y = {}, Px = {}, Py = {}",
                bound - dxy,
                kit.show(&x),
                kit.show(&y),
                kit.show(&px),
                kit.show(&py)
            ));
        }
    }
    kit.require_some(compared, "pairs at finite distance")
}

/// (e) ∂ψ/∂ε = σ of the local law, by central differences in each Mandel component (step
/// `fd_step·|ε|`), to `fd_tol·(|σ| + S)`.
pub fn energy_gradient(p: &dyn AdmissibleStresses, cfg: &KitConfig) -> Result<(), KitFailure> {
    let mut kit = Kit::new(p, cfg, names::ENERGY_GRADIENT)?;
    let law = &cfg.law;
    for i in 0..cfg.samples {
        let eps = kit.strain();
        let (sigma, _, _) = kit.local_law(&eps, None);
        let h = kit.fd_step(&eps);
        let mut fd = Sym::zeros();
        for k in 0..6 {
            let e = Sym::from_fn(|j, _| if j == k { h } else { 0.0 });
            fd[k] = (p.energy(law, &(eps + e)) - p.energy(law, &(eps - e))) / (2.0 * h);
        }
        let err = (fd - sigma).norm();
        let bound = cfg.fd_tol * (sigma.norm() + cfg.stress_scale);
        if err.is_nan() || err > bound {
            return kit.fail(format!(
                "sample {i}: |∂ψ/∂ε − σ| = {err:e} > {bound:e} at ε = {}: finite differences {}, σ = {}",
                show_sym(&eps),
                show_sym(&fd),
                show_sym(&sigma)
            ));
        }
    }
    Ok(())
}

/// (f) The tangent of the local law equals the central-difference derivative of ε ↦ σ(ε)
/// (step `fd_step·|ε|`) column by column, to `fd_tol` times the largest eigenvalue of C.
/// Points whose plastic flag changes within the stencil (within about the step of the yield
/// surface, where σ(ε) is not differentiable) are skipped; at least one point must be checked.
pub fn tangent(p: &dyn AdmissibleStresses, cfg: &KitConfig) -> Result<(), KitFailure> {
    let mut kit = Kit::new(p, cfg, names::TANGENT)?;
    let scale = cfg.law.max_eigenvalue();
    let mut checked = 0;
    'samples: for i in 0..cfg.samples {
        let eps = kit.strain();
        let mut t = SymOp::from_element(f64::NAN);
        let (_, _, plastic) = kit.local_law(&eps, Some(&mut t));
        let h = kit.fd_step(&eps);
        let mut fd = SymOp::zeros();
        for k in 0..6 {
            let e = Sym::from_fn(|j, _| if j == k { h } else { 0.0 });
            let (sp, _, fp) = kit.local_law(&(eps + e), None);
            let (sm, _, fm) = kit.local_law(&(eps - e), None);
            if fp != plastic || fm != plastic {
                continue 'samples;
            }
            fd.set_column(k, &((sp - sm) / (2.0 * h)));
        }
        checked += 1;
        let err = (0..6).map(|k| (fd.column(k) - t.column(k)).norm()).fold(0.0, nan_max);
        let bound = cfg.fd_tol * scale;
        if err.is_nan() || err > bound {
            return kit.fail(format!(
                "sample {i} ({}): the tangent differs from the finite-difference derivative of σ(ε) by {err:e} > {bound:e} \
                 (largest column error) at ε = {}; tangent {:?}, finite differences {:?}",
                if plastic { "plastic" } else { "elastic" },
                show_sym(&eps),
                t.as_slice(),
                fd.as_slice()
            ));
        }
    }
    kit.require_some(checked, "points away from the yield surface")
}

/// (g) ψ convex along random segments [a, b] (independent and close pairs):
/// `ψ(λa + (1−λ)b) ≤ λψ(a) + (1−λ)ψ(b)` for λ = ¼, ½, ¾, to `exact_tol` relative to |ψ|.
pub fn convexity(p: &dyn AdmissibleStresses, cfg: &KitConfig) -> Result<(), KitFailure> {
    let mut kit = Kit::new(p, cfg, names::CONVEXITY)?;
    let law = &cfg.law;
    for i in 0..cfg.samples {
        let a = kit.strain();
        let b = if i % 2 == 0 { kit.strain() } else { a + kit.strain() * 0.1 };
        let (pa, pb) = (p.energy(law, &a), p.energy(law, &b));
        for lambda in [0.25, 0.5, 0.75] {
            let m = a * lambda + b * (1.0 - lambda);
            let pm = p.energy(law, &m);
            let chord = lambda * pa + (1.0 - lambda) * pb;
            let bound = cfg.exact_tol * (pa.abs() + pb.abs() + pm.abs() + kit.energy_floor());
            if pm.is_nan() || chord.is_nan() || pm > chord + bound {
                return kit.fail(format!(
                    "sample {i}: ψ is not convex: ψ(λa + (1−λ)b) = {pm:e} > λψ(a) + (1−λ)ψ(b) = {chord:e} (λ = {lambda}, \
                     tolerance {bound:e}); a = {}, b = {}",
                    show_sym(&a),
                    show_sym(&b)
                ));
            }
        }
    }
    Ok(())
}

/// (h) `local_law(ε)` returns P_D(Cε, 0): the same generalised stress to `exact_tol` in the
/// energy norm, and the same plastic flag as `project`.
pub fn local_law_is_projection(p: &dyn AdmissibleStresses, cfg: &KitConfig) -> Result<(), KitFailure> {
    let mut kit = Kit::new(p, cfg, names::LOCAL_LAW_IS_PROJECTION)?;
    for i in 0..cfg.samples {
        let eps = kit.strain();
        let (sigma, q, plastic) = kit.local_law(&eps, None);
        let local = Point { s: sigma, q };
        let (proj, outside) = kit.project(&Point { s: cfg.law.stress(&eps), q: [0.0; MAX_HARDENING_DIM] });
        let d = kit.sq(&kit.sub(&local, &proj)).sqrt();
        let bound = cfg.exact_tol * (kit.finite_norm(&proj) + kit.norm_floor());
        if d.is_nan() || d > bound {
            return kit.fail(format!(
                "sample {i}: local_law gives {} but P_D(Cε, 0) = {}: energy distance {d:e} > {bound:e}; ε = {}",
                kit.show(&local),
                kit.show(&proj),
                show_sym(&eps)
            ));
        }
        // the flags may differ only for a trial on the boundary (within round-off), where
        // "plastic" and "elastic" give the same stress
        let trial = Point { s: cfg.law.stress(&eps), q: [0.0; MAX_HARDENING_DIM] };
        let moved = kit.sq(&kit.sub(&trial, &proj)).sqrt();
        if plastic != outside && moved > bound {
            return kit.fail(format!(
                "sample {i}: local_law says plastic = {plastic} but project says outside = {outside}; ε = {}",
                show_sym(&eps)
            ));
        }
    }
    Ok(())
}

/// (i) If `cone()` is `Some`, its blocks are well formed (`offset` has `dim` entries, `map`
/// `dim × (6 + hardening_dim)`, all finite) and membership by the blocks agrees with
/// `contains(·, 0)` at random points and at points just outside and inside the boundary
/// (Px ± 10⁻³(x − Px)), except within a relative margin 10⁻⁸ of a block's boundary.
pub fn cone_membership(p: &dyn AdmissibleStresses, cfg: &KitConfig) -> Result<(), KitFailure> {
    let mut kit = Kit::new(p, cfg, names::CONE_MEMBERSHIP)?;
    let Some(cone) = p.cone() else { return Ok(()) };
    let cols = 6 + kit.m;
    for (b, block) in cone.blocks.iter().enumerate() {
        if block.dim == 0 || block.offset.len() != block.dim || block.map.len() != block.dim * cols {
            return kit.fail(format!(
                "block {b}: dim = {}, offset has {} entries (expected {}), map has {} (expected {} × {cols})",
                block.dim,
                block.offset.len(),
                block.dim,
                block.map.len(),
                block.dim
            ));
        }
        if block.offset.iter().chain(&block.map).any(|v| !v.is_finite()) {
            return kit.fail(format!("block {b}: non-finite entries in offset or map"));
        }
    }
    let mut compared = 0;
    for i in 0..cfg.samples {
        let x = kit.point();
        let (px, outside) = kit.project(&x);
        let mut candidates = vec![x];
        if outside {
            let d = kit.sub(&x, &px);
            candidates.push(kit.axpy(1e-3, &d, &px));
            candidates.push(kit.axpy(-1e-3, &d, &px));
        }
        for z in candidates {
            let mut z_vec: Vec<f64> = z.s.iter().copied().collect();
            z_vec.extend_from_slice(kit.q(&z));
            let z_norm = z_vec.iter().map(|v| v * v).sum::<f64>().sqrt();
            let mut margin = f64::INFINITY;
            for block in &cone.blocks {
                let v: Vec<f64> = (0..block.dim)
                    .map(|r| block.offset[r] + (0..cols).map(|c| block.map[r * cols + c] * z_vec[c]).sum::<f64>())
                    .collect();
                let x_norm = v[1..].iter().map(|a| a * a).sum::<f64>().sqrt();
                let scale = block.offset.iter().map(|a| a * a).sum::<f64>().sqrt()
                    + block.map.iter().map(|a| a * a).sum::<f64>().sqrt() * z_norm;
                margin = margin.min((v[0] - x_norm) / scale.max(f64::MIN_POSITIVE));
            }
            if margin.is_nan() {
                return kit.fail(format!("sample {i}: the cone blocks give NaN at {}", kit.show(&z)));
            }
            if margin.abs() < 1e-8 {
                continue;
            }
            compared += 1;
            let by_cone = margin > 0.0;
            let by_contains = p.contains(&z.s, kit.q(&z), 0.0);
            if by_cone != by_contains {
                return kit.fail(format!(
                    "sample {i}: the cone blocks say {} (relative margin {margin:e}) but contains says {} at {}",
                    if by_cone { "inside" } else { "outside" },
                    if by_contains { "inside" } else { "outside" },
                    kit.show(&z)
                ));
            }
        }
    }
    kit.require_some(compared, "points away from the cone boundaries")
}

/// (j) `energy(ε) = ε:σ − ½[σ̂, σ̂]` at σ̂ = local_law(ε) (theory §2), to `exact_tol` relative
/// to the sum of the magnitudes of the terms.
pub fn energy_identity(p: &dyn AdmissibleStresses, cfg: &KitConfig) -> Result<(), KitFailure> {
    let mut kit = Kit::new(p, cfg, names::ENERGY_IDENTITY)?;
    let law = &cfg.law;
    for i in 0..cfg.samples {
        let eps = kit.strain();
        let (sigma, q, _) = kit.local_law(&eps, None);
        let work = eps.dot(&sigma);
        let elastic = law.compliance(&sigma).dot(&sigma);
        let hard = p.hardening_inner(&q[..kit.m], &q[..kit.m]);
        let psi = p.energy(law, &eps);
        let rhs = work - 0.5 * (elastic + hard);
        let bound = cfg.exact_tol * (work.abs() + elastic.abs() + hard.abs() + psi.abs() + kit.energy_floor());
        let err = (psi - rhs).abs();
        if !hard.is_finite() || err.is_nan() || err > bound {
            return kit.fail(format!(
                "sample {i}: energy(ε) = {psi:e} but ε:σ − ½[σ̂, σ̂] = {rhs:e} (ε:σ = {work:e}, Aσ:σ = {elastic:e}, \
                 q·H⁻¹q = {hard:e}); difference {err:e} > {bound:e}; ε = {}",
                show_sym(&eps)
            ));
        }
    }
    Ok(())
}

/// (k) The step law of theory §11.1 at random load-step states (module docs) returns
/// P_D(C(ε − ε_p), q_n) — the same generalised stress as `project` of that trial, to
/// `exact_tol` in the energy norm, and the same plastic flag — and at the virgin state
/// (ε_p = 0, q_n = 0) the same as `local_law(ε)`. The flags may differ only for a trial on the
/// boundary (within round-off).
pub fn step_law_is_projection(p: &dyn AdmissibleStresses, cfg: &KitConfig) -> Result<(), KitFailure> {
    let mut kit = Kit::new(p, cfg, names::STEP_LAW_IS_PROJECTION)?;
    let zero = [0.0; MAX_HARDENING_DIM];
    for i in 0..cfg.samples {
        let (ep, qn) = kit.step_state(i % 4);
        let eps = ep + kit.strain();
        let (sigma, q, plastic) = kit.step_law(&eps, &ep, &qn, None);
        let trial = Point { s: cfg.law.stress(&(eps - ep)), q: qn };
        let (proj, outside) = kit.project(&trial);
        kit.same_return(
            i,
            (&Point { s: sigma, q }, plastic, "step_law"),
            (&proj, outside, "P_D(C(ε − ε_p), q_n)"),
            &trial,
            &format!("ε = {}, ε_p = {}, q_n = {:?}", show_sym(&eps), show_sym(&ep), kit.q(&trial)),
        )?;
        // the virgin state is the local law
        let (sigma, q, plastic) = kit.step_law(&eps, &Sym::zeros(), &zero, None);
        let (ls, lq, lplastic) = kit.local_law(&eps, None);
        let trial = Point { s: cfg.law.stress(&eps), q: zero };
        kit.same_return(
            i,
            (&Point { s: sigma, q }, plastic, "step_law at ε_p = 0, q_n = 0"),
            (&Point { s: ls, q: lq }, lplastic, "local_law"),
            &trial,
            &format!("ε = {}", show_sym(&eps)),
        )?;
    }
    Ok(())
}

/// (l) The tangent of the step law equals the central-difference derivative of ε ↦ σ(ε) at a
/// fixed random state (ε_p, q_n) (step `fd_step·|ε − ε_p|`) column by column, to `fd_tol`
/// times the largest eigenvalue of C. Points where σ(ε) is not differentiable within the stencil
/// are skipped: those whose plastic flag changes in it; plastic points whose trial is within
/// ten stencil widths of D in the energy norm (a trial on a kink of ∂D, e.g. hydrostatic at the
/// apex of a state with k₀ + ξ_n = 0, where the projection is positively homogeneous and has no
/// derivative, yet its differences do not depend on the step); and those whose differences with
/// the step and twice the step disagree by more than half the tolerance (a face, edge or apex
/// boundary crossed without a change of the flag). At least half the points must be checked.
pub fn step_tangent(p: &dyn AdmissibleStresses, cfg: &KitConfig) -> Result<(), KitFailure> {
    let mut kit = Kit::new(p, cfg, names::STEP_TANGENT)?;
    let bound = cfg.fd_tol * cfg.law.max_eigenvalue();
    let mut checked = 0;
    'samples: for i in 0..cfg.samples {
        let (ep, qn) = kit.step_state(i % 4);
        let eps = ep + kit.strain();
        let mut t = SymOp::from_element(f64::NAN);
        let (sigma, q, plastic) = kit.step_law(&eps, &ep, &qn, Some(&mut t));
        let h = kit.fd_step(&(eps - ep));
        // the energy norm of the stencil's largest change of the trial is 2h √(max eig C)
        let trial = Point { s: cfg.law.stress(&(eps - ep)), q: qn };
        let moved = kit.sq(&kit.sub(&trial, &Point { s: sigma, q })).sqrt();
        if plastic && moved <= 20.0 * h * cfg.law.max_eigenvalue().sqrt() {
            continue;
        }
        let mut fd = [SymOp::zeros(); 2];
        for (w, step) in [h, 2.0 * h].into_iter().enumerate() {
            for k in 0..6 {
                let e = Sym::from_fn(|j, _| if j == k { step } else { 0.0 });
                let (sp, _, fp) = kit.step_law(&(eps + e), &ep, &qn, None);
                let (sm, _, fm) = kit.step_law(&(eps - e), &ep, &qn, None);
                if fp != plastic || fm != plastic {
                    continue 'samples;
                }
                fd[w].set_column(k, &((sp - sm) / (2.0 * step)));
            }
        }
        let spread = (0..6).map(|k| (fd[0].column(k) - fd[1].column(k)).norm()).fold(0.0, nan_max);
        if spread > 0.5 * bound {
            continue;
        }
        checked += 1;
        let err = (0..6).map(|k| (fd[0].column(k) - t.column(k)).norm()).fold(0.0, nan_max);
        if err.is_nan() || err > bound {
            return kit.fail(format!(
                "sample {i} ({}): the step law's tangent differs from the finite-difference derivative of σ(ε) by \
                 {err:e} > {bound:e} (largest column error) at ε = {}, ε_p = {}, q_n = {:?}; tangent {:?}, finite \
                 differences {:?}",
                if plastic { "plastic" } else { "elastic" },
                show_sym(&eps),
                show_sym(&ep),
                &qn[..kit.m],
                t.as_slice(),
                fd[0].as_slice()
            ));
        }
    }
    if 2 * checked < cfg.samples {
        return kit.fail(format!(
            "only {checked} of {} samples have a step law differentiable within the finite-difference stencil: \
             σ(ε) is not smooth almost everywhere",
            cfg.samples
        ));
    }
    Ok(())
}

/// (m) ∂ψ_n/∂ε = σ of the step law, by central differences of `step_energy` in each Mandel
/// component (step `fd_step·|ε − ε_p|`), to `fd_tol·(|σ| + S)`, at admissible load-step states
/// (kinds 0–2 of the module docs: ψ_n is −∞ from hardening variables outside D with h = 0).
pub fn step_energy_gradient(p: &dyn AdmissibleStresses, cfg: &KitConfig) -> Result<(), KitFailure> {
    let mut kit = Kit::new(p, cfg, names::STEP_ENERGY_GRADIENT)?;
    let law = &cfg.law;
    let m = kit.m;
    for i in 0..cfg.samples {
        let (ep, qn) = kit.step_state(i % 3);
        let eps = ep + kit.strain();
        let (sigma, _, _) = kit.step_law(&eps, &ep, &qn, None);
        let h = kit.fd_step(&(eps - ep));
        let mut fd = Sym::zeros();
        for k in 0..6 {
            let e = Sym::from_fn(|j, _| if j == k { h } else { 0.0 });
            let (plus, minus) = (eps + e, eps - e);
            fd[k] = (p.step_energy(law, StepInput::new(&plus, &ep, &qn[..m]))
                - p.step_energy(law, StepInput::new(&minus, &ep, &qn[..m])))
                / (2.0 * h);
        }
        let err = (fd - sigma).norm();
        let bound = cfg.fd_tol * (sigma.norm() + cfg.stress_scale);
        if err.is_nan() || err > bound {
            return kit.fail(format!(
                "sample {i}: |∂ψ_n/∂ε − σ| = {err:e} > {bound:e} at ε = {}, ε_p = {}, q_n = {:?}: finite differences \
                 {}, σ = {}",
                show_sym(&eps),
                show_sym(&ep),
                &qn[..m],
                show_sym(&fd),
                show_sym(&sigma)
            ));
        }
    }
    Ok(())
}

/// A generalised stress (σ, q); only the first `hardening_dim()` entries of q are used.
#[derive(Clone, Copy, Debug)]
struct Point {
    s: Sym,
    q: [f64; MAX_HARDENING_DIM],
}

/// Sampling and metric helpers shared by the checks.
struct Kit<'a> {
    p: &'a dyn AdmissibleStresses,
    cfg: &'a KitConfig,
    check: &'static str,
    m: usize,
    rng: StdRng,
}

impl<'a> Kit<'a> {
    fn new(p: &'a dyn AdmissibleStresses, cfg: &'a KitConfig, check: &'static str) -> Result<Self, KitFailure> {
        setup(p, cfg).map_err(|e| KitFailure { check, message: e.message })?;
        // one independent stream per check, so that checks do not depend on each other
        let salt = check.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3));
        Ok(Self { p, cfg, check, m: p.hardening_dim(), rng: StdRng::seed_from_u64(cfg.seed ^ salt) })
    }

    fn fail<T>(&self, message: String) -> Result<T, KitFailure> {
        Err(KitFailure { check: self.check, message })
    }

    fn require_some(&self, n: usize, what: &str) -> Result<(), KitFailure> {
        if n == 0 {
            self.fail(format!("no {what} among {} samples: the check would be vacuous", self.cfg.samples))
        } else {
            Ok(())
        }
    }

    fn q<'b>(&self, x: &'b Point) -> &'b [f64] {
        &x.q[..self.m]
    }

    /// A random unit deviator.
    fn unit_deviator(&mut self) -> Sym {
        loop {
            let d = deviator(&Sym::from_fn(|_, _| self.rng.random_range(-1.0..1.0)));
            let n = d.norm();
            if n > 1e-3 {
                return d / n;
            }
        }
    }

    /// A random rotation (a uniformly drawn unit quaternion).
    fn rotation(&mut self) -> Matrix3<f64> {
        let q = loop {
            let q: [f64; 4] = std::array::from_fn(|_| self.rng.random_range(-1.0..1.0));
            let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            if n > 1e-3 && n <= 1.0 {
                break q.map(|x| x / n);
            }
        };
        UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3])).to_rotation_matrix().into_inner()
    }

    /// A unit deviator with principal values (a, a, −2a)·(1 + δ-perturbation of relative size
    /// `spread`), a random sign, turned by a random rotation: an axisymmetric state (spread 0)
    /// or one next to it.
    fn axisymmetric_deviator(&mut self, spread: f64) -> Sym {
        let sign = if self.rng.random_range(0..2) == 0 { 1.0 } else { -1.0 };
        let d = if spread > 0.0 { self.rng.random_range(-spread..spread) } else { 0.0 };
        let v = Vector3::new(sign * (1.0 + d), sign * (1.0 - d), -2.0 * sign);
        let r = self.rotation();
        let m = r * Matrix3::from_diagonal(&v) * r.transpose();
        let dev = deviator(&from_matrix(&m));
        dev / dev.norm()
    }

    /// A random stress: deviator of norm in [0, 5S] of a random, axisymmetric or nearly
    /// axisymmetric direction, mean stress in [−2S, 2S]; or a hydrostatic stress with mean in
    /// [−2S, 5S] (module docs).
    fn stress(&mut self) -> Sym {
        let s = self.cfg.stress_scale;
        let r = self.rng.random_range(0.0..5.0 * s);
        let mean = self.rng.random_range(-2.0 * s..2.0 * s);
        match self.rng.random_range(0..6) {
            0..=2 => self.unit_deviator() * r + identity() * mean,
            3 => self.axisymmetric_deviator(0.0) * r + identity() * mean,
            4 => self.axisymmetric_deviator(1e-3) * r + identity() * mean,
            _ => identity() * self.rng.random_range(-2.0 * s..5.0 * s),
        }
    }

    /// Random hardening variables: 0 with probability ¼, else uniform in [−2S, 2S].
    fn hardening(&mut self) -> [f64; MAX_HARDENING_DIM] {
        let mut q = [0.0; MAX_HARDENING_DIM];
        if self.rng.random_range(0..4) != 0 {
            let s = self.cfg.stress_scale;
            for v in &mut q[..self.m] {
                *v = self.rng.random_range(-2.0 * s..2.0 * s);
            }
        }
        q
    }

    fn point(&mut self) -> Point {
        Point { s: self.stress(), q: self.hardening() }
    }

    /// A strain whose trial stress Cε is a random stress.
    fn strain(&mut self) -> Sym {
        let s = self.stress();
        self.cfg.law.compliance(&s)
    }

    /// x perturbed by a random stress and random hardening of relative size `rel`.
    fn near(&mut self, x: &Point, rel: f64) -> Point {
        let ds = self.stress() * rel;
        let mut q = x.q;
        let s = self.cfg.stress_scale;
        for v in &mut q[..self.m] {
            *v += rel * self.rng.random_range(-2.0 * s..2.0 * s);
        }
        Point { s: x.s + ds, q }
    }

    /// A random point that `contains` accepts, if one is found in a few draws.
    fn admissible_point(&mut self) -> Option<Point> {
        for _ in 0..20 {
            let y = self.point();
            if self.p.contains(&y.s, &y.q[..self.m], 0.0) {
                return Some(y);
            }
        }
        None
    }

    fn project(&self, x: &Point) -> (Point, bool) {
        let mut y = *x;
        let outside = self.p.project(&self.cfg.law, &mut y.s, &mut y.q[..self.m]);
        (y, outside)
    }

    fn local_law(&self, eps: &Sym, tangent: Option<&mut SymOp>) -> (Sym, [f64; MAX_HARDENING_DIM], bool) {
        let mut s = Sym::from_element(f64::NAN);
        let mut q = [f64::NAN; MAX_HARDENING_DIM];
        let plastic = self.p.local_law(&self.cfg.law, eps, StepOutput::new(&mut s, &mut q[..self.m], tangent));
        (s, q, plastic)
    }

    /// A load-step state (ε_p, q_n) of kind 0–3 (module docs): the virgin state; a random
    /// plastic strain with q_n = 0; with the hardening variables of a projected random point; with
    /// random hardening variables.
    fn step_state(&mut self, kind: usize) -> (Sym, [f64; MAX_HARDENING_DIM]) {
        if kind == 0 {
            return (Sym::zeros(), [0.0; MAX_HARDENING_DIM]);
        }
        let ep = self.strain() * 0.5;
        let qn = match kind {
            1 => [0.0; MAX_HARDENING_DIM],
            2 => {
                let x = self.point();
                self.project(&x).0.q
            }
            _ => self.hardening(),
        };
        (ep, qn)
    }

    fn step_law(
        &self,
        eps: &Sym,
        ep: &Sym,
        qn: &[f64; MAX_HARDENING_DIM],
        tangent: Option<&mut SymOp>,
    ) -> (Sym, [f64; MAX_HARDENING_DIM], bool) {
        let mut s = Sym::from_element(f64::NAN);
        let mut q = [f64::NAN; MAX_HARDENING_DIM];
        let m = self.m;
        let plastic = self.p.step_law(
            &self.cfg.law,
            StepInput::new(eps, ep, &qn[..m]),
            StepOutput::new(&mut s, &mut q[..m], tangent),
        );
        (s, q, plastic)
    }

    /// Fails unless the returns `a` and `b` (point, plastic flag, name) of the same `trial` are
    /// the same generalised stress to `exact_tol` in the energy norm, with the same flag unless
    /// the trial is on the boundary within that tolerance.
    fn same_return(
        &self,
        i: usize,
        (a, a_plastic, a_name): (&Point, bool, &str),
        (b, b_plastic, b_name): (&Point, bool, &str),
        trial: &Point,
        at: &str,
    ) -> Result<(), KitFailure> {
        let d = self.sq(&self.sub(a, b)).sqrt();
        let bound = self.cfg.exact_tol * (self.finite_norm(b) + self.norm_floor());
        if d.is_nan() || d > bound {
            return self.fail(format!(
                "sample {i}: {a_name} gives {} but {b_name} = {}: energy distance {d:e} > {bound:e}; {at}",
                self.show(a),
                self.show(b)
            ));
        }
        let moved = self.sq(&self.sub(trial, b)).sqrt();
        if a_plastic != b_plastic && (moved.is_nan() || moved > bound) {
            return self
                .fail(format!("sample {i}: {a_name} says plastic = {a_plastic} but {b_name} says {b_plastic}; {at}"));
        }
        Ok(())
    }

    fn sub(&self, a: &Point, b: &Point) -> Point {
        Point { s: a.s - b.s, q: std::array::from_fn(|k| a.q[k] - b.q[k]) }
    }

    /// a·d + x.
    fn axpy(&self, a: f64, d: &Point, x: &Point) -> Point {
        Point { s: x.s + d.s * a, q: std::array::from_fn(|k| x.q[k] + a * d.q[k]) }
    }

    /// The energy inner product [a, b].
    fn ip(&self, a: &Point, b: &Point) -> f64 {
        energy_inner(Some(self.p), &self.cfg.law, &a.s, self.q(a), &b.s, self.q(b))
    }

    /// [a, a].
    fn sq(&self, a: &Point) -> f64 {
        self.ip(a, a)
    }

    /// The norm of a with an infinite hardening part (h = 0) left out: a finite scale for
    /// tolerances.
    fn finite_norm(&self, a: &Point) -> f64 {
        let hard = self.p.hardening_inner(self.q(a), self.q(a));
        let hard = if hard.is_finite() { hard.abs() } else { 0.0 };
        (self.cfg.law.compliance(&a.s).dot(&a.s).abs() + hard).sqrt()
    }

    /// The energy of a stress of size S, S²/max eig(C) (a lower bound of Aσ:σ for |σ| = S).
    fn energy_floor(&self) -> f64 {
        self.cfg.stress_scale * self.cfg.stress_scale / self.cfg.law.max_eigenvalue()
    }

    fn norm_floor(&self) -> f64 {
        self.energy_floor().sqrt()
    }

    /// The finite-difference step: fd_step · max(|ε|, S / max eig(C)).
    fn fd_step(&self, eps: &Sym) -> f64 {
        self.cfg.fd_step * eps.norm().max(self.cfg.stress_scale / self.cfg.law.max_eigenvalue())
    }

    fn is_finite(&self, x: &Point) -> bool {
        x.s.iter().chain(self.q(x)).all(|v| v.is_finite())
    }

    fn show(&self, x: &Point) -> String {
        format!("(σ = {}, q = {:?})", show_sym(&x.s), self.q(x))
    }
}

/// max that propagates NaN.
fn nan_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() { f64::NAN } else { a.max(b) }
}

/// A Mandel vector as `[a, b, …]` with six significant digits.
fn show_sym(s: &Sym) -> String {
    let parts: Vec<String> = s.iter().map(|v| format!("{v:.6e}")).collect();
    format!("[{}]", parts.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::VonMises;
    use crate::mutant::Mutant;
    use saddle_core::problem::stresses::step_law_by_differences;
    use serde::{Deserialize, Serialize};

    /// Ways to break von Mises, each aimed at one check.
    #[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
    enum Breakage {
        /// (a) the "projection" overshoots by 10 %: outside D.
        Overshoots,
        /// (b) scales the deviator by 0.9 on every call when |s| > ½(k0 + ξ).
        NotIdempotent,
        /// (c) projects in the metric of another h: in D and idempotent, not nearest.
        WrongMetric,
        /// (d) doubles the mean stress of the points it moves: in D, idempotent, expansive.
        DoublesPressure,
        /// (e) ψ = ½Cε:ε even when plastic.
        ElasticEnergy,
        /// (f) tangent C even when plastic.
        ElasticTangent,
        /// (g) triple the plastic correction of ψ: concave for large strains.
        ConcaveEnergy,
        /// (h) local law and energy of another h, projection right.
        LocalLawOfOtherH,
        /// (i) the cone's radius is 0.9 (k0 + ξ).
        NarrowCone,
        /// (j) ψ off by a constant: gradient, tangent and convexity unaffected.
        EnergyOffset,
        /// (k) the step law ignores q_n (projects (C(ε − ε_p), 0)), tangent consistent with it.
        StepIgnoresHardening,
        /// (l) the step law's tangent is C even when plastic.
        StepElasticTangent,
        /// (m) ψ_n forgets q_n (the energy of the step law from (ε_p, 0)).
        StepEnergyIgnoresHardening,
    }

    /// Von Mises (k₀ = 1, h = 5) broken as `how` says.
    fn broken(how: Breakage) -> Mutant {
        let vm = VonMises::new(1.0, 5.0).unwrap();
        let m = Mutant::of(vm);
        match how {
            Breakage::Overshoots => m
                .with_project(move |_, law, sigma, q| {
                    let out = vm.project(law, sigma, q);
                    if out {
                        *sigma =
                            identity() * (saddle_core::problem::tensor::trace(sigma) / 3.0) + deviator(sigma) * 1.1;
                    }
                    out
                })
                .with_local_law(|m, law, eps, out| m.local_law_from_projection(law, eps, out)),
            Breakage::NotIdempotent => m
                .with_project(move |_, law, sigma, q| {
                    let out = vm.project(law, sigma, q);
                    let s = deviator(sigma);
                    if s.norm() > 0.5 * (vm.k0 + q[0]) {
                        *sigma = identity() * (saddle_core::problem::tensor::trace(sigma) / 3.0) + s * 0.9;
                    }
                    out
                })
                .with_local_law(|m, law, eps, out| m.local_law_from_projection(law, eps, out)),
            Breakage::WrongMetric => m
                .with_project(move |_, law, sigma, q| VonMises { k0: vm.k0, h: 10.0 * vm.h }.project(law, sigma, q))
                .with_local_law(|m, law, eps, out| m.local_law_from_projection(law, eps, out)),
            Breakage::DoublesPressure => m
                .with_project(move |_, law, sigma, q| {
                    let mean = identity() * (saddle_core::problem::tensor::trace(sigma) / 3.0);
                    let out = vm.project(law, sigma, q);
                    if out {
                        *sigma += mean;
                    }
                    out
                })
                .with_local_law(|m, law, eps, out| m.local_law_from_projection(law, eps, out)),
            Breakage::ElasticEnergy => m.with_energy(|_, law, eps| 0.5 * eps.dot(&law.stress(eps))),
            Breakage::ElasticTangent => m.with_local_law(move |_, law, eps, mut out| {
                let plastic = vm.local_law(law, eps, StepOutput::new(out.sigma, out.q, None));
                out.set_tangent(|| law.stiffness_matrix());
                plastic
            }),
            Breakage::ConcaveEnergy => m.with_energy(move |_, law, eps| {
                let elastic = 0.5 * eps.dot(&law.stress(eps));
                elastic + 3.0 * (vm.energy(law, eps) - elastic)
            }),
            Breakage::LocalLawOfOtherH => {
                let other = VonMises { k0: vm.k0, h: 2.0 * vm.h };
                m.with_local_law(move |_, law, eps, out| other.local_law(law, eps, out))
                    .with_energy(move |_, law, eps| other.energy(law, eps))
            }
            Breakage::NarrowCone => m.with_cone(move |_| {
                let mut c = vm.cone()?;
                for v in &mut c.blocks[0].map[7..] {
                    *v /= 0.9;
                }
                Some(c)
            }),
            Breakage::EnergyOffset => m.with_energy(move |_, law, eps| vm.energy(law, eps) + 1e-3),
            Breakage::StepIgnoresHardening => {
                m.with_step_law(move |_, law, step, out| vm.step_law(law, StepInput { q_n: &[0.0], ..step }, out))
            }
            Breakage::StepElasticTangent => m.with_step_law(move |_, law, step, mut out| {
                let plastic = vm.step_law(law, step, StepOutput::new(out.sigma, out.q, None));
                out.set_tangent(|| law.stiffness_matrix());
                plastic
            }),
            Breakage::StepEnergyIgnoresHardening => {
                m.with_step_energy(move |_, law, step| vm.step_energy(law, StepInput { q_n: &[0.0], ..step }))
            }
        }
    }

    fn cfg() -> KitConfig {
        KitConfig::new(Elasticity::new(100.0, 0.3).unwrap(), 1.0).with_samples(120)
    }

    #[test]
    fn kit_catches_each_breakage_in_its_own_check() {
        type Check = fn(&dyn AdmissibleStresses, &KitConfig) -> Result<(), KitFailure>;
        let cases: [(Breakage, &str, Check); 13] = [
            (Breakage::Overshoots, names::PROJECTION_IN_SET, projection_in_set),
            (Breakage::NotIdempotent, names::IDEMPOTENT, idempotent),
            (Breakage::WrongMetric, names::VARIATIONAL_INEQUALITY, variational_inequality),
            (Breakage::DoublesPressure, names::NON_EXPANSIVE, non_expansive),
            (Breakage::ElasticEnergy, names::ENERGY_GRADIENT, energy_gradient),
            (Breakage::ElasticTangent, names::TANGENT, tangent),
            (Breakage::ConcaveEnergy, names::CONVEXITY, convexity),
            (Breakage::LocalLawOfOtherH, names::LOCAL_LAW_IS_PROJECTION, local_law_is_projection),
            (Breakage::NarrowCone, names::CONE_MEMBERSHIP, cone_membership),
            (Breakage::EnergyOffset, names::ENERGY_IDENTITY, energy_identity),
            (Breakage::StepIgnoresHardening, names::STEP_LAW_IS_PROJECTION, step_law_is_projection),
            (Breakage::StepElasticTangent, names::STEP_TANGENT, step_tangent),
            (Breakage::StepEnergyIgnoresHardening, names::STEP_ENERGY_GRADIENT, step_energy_gradient),
        ];
        let cfg = cfg();
        for (how, name, check) in cases {
            let p = broken(how);
            let e = check(&p, &cfg).expect_err(name);
            assert_eq!(e.check, name, "{how:?}: {e}");
            assert!(e.to_string().starts_with(&format!("conformance check `{name}` failed: sample ")), "{e}");
            // the check itself passes for the unbroken plugin
            check(&VonMises::new(1.0, 5.0).unwrap(), &cfg).unwrap();
        }
    }

    #[test]
    fn check_all_names_the_first_failing_check() {
        let cfg = cfg();
        for (how, first) in [
            (Breakage::Overshoots, names::PROJECTION_IN_SET),
            (Breakage::NotIdempotent, names::IDEMPOTENT),
            (Breakage::WrongMetric, names::VARIATIONAL_INEQUALITY),
            (Breakage::ElasticEnergy, names::ENERGY_GRADIENT),
            (Breakage::ElasticTangent, names::TANGENT),
            (Breakage::LocalLawOfOtherH, names::LOCAL_LAW_IS_PROJECTION),
            (Breakage::NarrowCone, names::CONE_MEMBERSHIP),
            (Breakage::EnergyOffset, names::ENERGY_IDENTITY),
            (Breakage::StepIgnoresHardening, names::STEP_LAW_IS_PROJECTION),
            (Breakage::StepElasticTangent, names::STEP_TANGENT),
            (Breakage::StepEnergyIgnoresHardening, names::STEP_ENERGY_GRADIENT),
        ] {
            let e = check_all(&broken(how), &cfg).unwrap_err();
            assert_eq!(e.check, first, "{how:?}: {e}");
        }
    }

    /// `p` with the step law by differences of its projection
    /// ([`step_law_by_differences`]), as a plugin without a closed form gives it.
    fn by_differences(p: Box<dyn AdmissibleStresses>) -> Mutant {
        Mutant::boxed(p).with_step_law(|m, law, step, out| step_law_by_differences(m.inner.as_ref(), law, step, out))
    }

    #[test]
    fn step_law_by_differences_passes_the_kit_and_agrees_with_the_closed_forms() {
        let cfg = cfg();
        let plugins: [Box<dyn AdmissibleStresses>; 5] = [
            Box::new(VonMises::new(1.0, 5.0).unwrap()),
            Box::new(VonMises::new(1.0, 0.0).unwrap()),
            Box::new(crate::VonMisesKinematic::new(1.0, 5.0, 3.0).unwrap()),
            Box::new(crate::DruckerPrager::new(1.0, 0.3, 5.0).unwrap()),
            Box::new(crate::Tresca::new(1.0, 5.0).unwrap()),
        ];
        for p in plugins {
            let name = p.name();
            check_all(&by_differences(p.clone()), &cfg).unwrap_or_else(|e| panic!("{name} by differences: {e}"));
            // the closed form and the default at the same states: same σ̂, tangents to the
            // accuracy of the default's differences
            let mut kit = Kit::new(p.as_ref(), &cfg, "test").unwrap();
            let default = by_differences(p.clone());
            let (mut plastic, mut worst) = (0, 0.0f64);
            for i in 0..200 {
                let (ep, qn) = kit.step_state(i % 4);
                let eps = ep + kit.strain();
                let (mut t1, mut t2) = (SymOp::zeros(), SymOp::zeros());
                let (s1, q1, f1) = kit.step_law(&eps, &ep, &qn, Some(&mut t1));
                let (mut s2, mut q2, m) = (Sym::zeros(), [0.0; MAX_HARDENING_DIM], kit.m);
                let f2 = default.step_law(
                    &cfg.law,
                    StepInput::new(&eps, &ep, &qn[..m]),
                    StepOutput::new(&mut s2, &mut q2[..m], Some(&mut t2)),
                );
                assert_eq!(f1, f2, "{name}, sample {i}");
                plastic += f1 as usize;
                let scale = s1.norm() + 1.0;
                assert!((s1 - s2).norm() <= 1e-12 * scale, "{name}, sample {i}: σ {s1} vs {s2}");
                assert!((0..m).all(|k| (q1[k] - q2[k]).abs() <= 1e-12 * scale), "{name}, sample {i}: q");
                worst = worst.max((t1 - t2).amax() / cfg.law.max_eigenvalue());
            }
            println!("{name}: {plastic}/200 plastic, largest tangent difference {worst:e} of max eig C");
            assert!(plastic >= 50, "{name}: {plastic} plastic");
            // the default's differences are good to ~1e-8 (Tresca: its edge regularisation 1e-8·2G)
            assert!(worst <= 1e-7, "{name}: {worst:e}");
        }
    }

    #[test]
    fn not_idempotent_failure_reports_the_numbers() {
        let e = idempotent(&broken(Breakage::NotIdempotent), &cfg()).unwrap_err();
        // P(Px) is 0.9 Px in the deviator: the distance 0.1 |dev Px| / √(2G) is far above the
        // round-off tolerance the kit reports next to it
        let number_after = |key: &str| -> f64 {
            e.message.split(key).nth(1).unwrap().split([' ', ')']).next().unwrap().parse().unwrap()
        };
        let (d, tol) = (number_after("by "), number_after("(tolerance "));
        assert!(d > 1e6 * tol, "{e}");
        assert!(e.message.contains("P(Px) = "), "{e}");
    }

    #[test]
    fn setup_rejects_bad_plugins_and_configurations() {
        let cfg = cfg();
        let e = check_all(&VonMises { k0: -1.0, h: 5.0 }, &cfg).unwrap_err();
        assert_eq!(e.check, names::SETUP);
        assert!(e.message.contains("yield.k0 = -1"), "{e}");
        let mut bad = cfg;
        bad.stress_scale = 0.0;
        let e = check_all(&VonMises::new(1.0, 5.0).unwrap(), &bad).unwrap_err();
        assert!(e.check == names::SETUP && e.message.contains("stress_scale = 0"), "{e}");
        // a single check reports under its own name, with the setup message
        let e = tangent(&VonMises::new(1.0, 5.0).unwrap(), &bad).unwrap_err();
        assert!(e.check == names::TANGENT && e.message.contains("stress_scale"), "{e}");
        let e = check_all(&VonMises::new(1.0, 5.0).unwrap(), &cfg.with_samples(0)).unwrap_err();
        assert_eq!(e.check, names::SETUP);
    }

    #[test]
    fn samples_span_both_regimes() {
        // the local law sees elastic and plastic points, and projections meet the apex
        let vm = VonMises::new(1.0, 5.0).unwrap();
        let cfg = cfg();
        let mut kit = Kit::new(&vm, &cfg, "test").unwrap();
        let (mut plastic, mut apex, mut inside) = (0, 0, 0);
        for _ in 0..400 {
            let eps = kit.strain();
            let (_, _, pl) = kit.local_law(&eps, None);
            plastic += pl as usize;
            let x = kit.point();
            let (px, out) = kit.project(&x);
            inside += !out as usize;
            apex += (out && deviator(&px.s).norm() == 0.0) as usize;
        }
        assert!((200..380).contains(&plastic), "plastic {plastic}/400");
        assert!((40..300).contains(&inside), "inside {inside}/400");
        assert!(apex >= 20, "apex {apex}/400");
    }

    #[test]
    fn default_config_is_the_default_scene() {
        let c = KitConfig::default();
        assert_eq!((c.law.young, c.law.poisson, c.stress_scale, c.samples), (100.0, 0.3, 1.0, 200));
        assert_eq!((c.exact_tol, c.fd_tol, c.fd_step), (1e-12, 1e-5, 1e-6));
    }
}
