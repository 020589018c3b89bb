//! The solver conformance kit: runs any [`Solver`] on small scenes — homogeneous compression
//! (closed form, SPEC §7), an elastic Hertz contact, and the default scene of SPEC §6 with
//! plasticity and contact, with weak hardening and with an off-centre elliptic punch — and
//! checks, for each:
//!
//! * the run converged, and the KKT residual recomputed from the solution by L (independently
//!   of the solver) is within the solver's own tolerance;
//! * homogeneous compression matches the closed form;
//! * the solution agrees with a reference solver's: U, σ̂ in the energy norm, the contact set,
//!   and the plastic set except elements within 1e-8 of the yield surface.
//!
//! ```no_run
//! use saddle::conformance::{Tolerances, check_solver};
//! use saddle::solvers::{Newton, Uzawa};
//! let reference = Newton { tol: 1e-12, ..Newton::default() };
//! let report = check_solver(&Uzawa { tol: 1e-10, ..Uzawa::default() }, &reference, &Tolerances::default())?;
//! for r in &report {
//!     println!("{}: U error {:.1e}, σ̂ error {:.1e}", r.scene, r.agreement.u_rel, r.agreement.stress_rel);
//! }
//! # Ok::<(), saddle::conformance::KitFailure>(())
//! ```

use crate::scene::Scene;
use saddle_core::problem::stresses::energy_inner;
use saddle_core::{
    Lagrangian, P1P0Lagrangian, SceneError, Silent, Solution, Solver, StressField, Sym, Workspace, contact_set,
};
use std::path::Path;
use thiserror::Error;

/// A failed check: which scene, which check, with the numbers.
#[derive(Debug, Clone, Error, PartialEq)]
#[error("solver conformance: scene `{scene}`, check `{check}`: {message}")]
pub struct KitFailure {
    /// The scene.
    pub scene: String,
    /// The check that failed.
    pub check: &'static str,
    /// What was measured.
    pub message: String,
}

/// Agreement thresholds against the reference.
#[derive(Clone, Copy, Debug)]
pub struct Tolerances {
    /// |U − U_ref| / |U_ref|.
    pub u_rel: f64,
    /// [σ̂ − σ̂_ref] / [σ̂_ref] in the energy norm.
    pub stress_rel: f64,
}

impl Default for Tolerances {
    /// The solvers issue's thresholds: 1e-7 in U, 1e-6 in σ̂.
    fn default() -> Self {
        Self { u_rel: 1e-7, stress_rel: 1e-6 }
    }
}

/// How two solutions of the same problem compare.
#[derive(Clone, Debug, PartialEq)]
pub struct Agreement {
    /// Relative difference in the extras (U), or in u (max norm) without extras.
    pub u_rel: f64,
    /// Relative energy-norm difference of σ̂.
    pub stress_rel: f64,
    /// Rows in one contact set and not the other.
    pub contact_mismatch: Vec<usize>,
    /// Elements plastic in one and elastic in the other, not within 1e-8 of the yield surface.
    pub plastic_mismatch: Vec<usize>,
}

/// The result of one scene.
#[derive(Clone, Debug)]
pub struct SceneResult {
    /// Scene name.
    pub scene: &'static str,
    /// Iterations of the solver.
    pub iterations: usize,
    /// Independently recomputed KKT residual.
    pub kkt: f64,
    /// Agreement with the reference.
    pub agreement: Agreement,
}

/// A named small problem of the kit.
pub struct KitScene {
    /// Name.
    pub name: &'static str,
    /// L.
    pub problem: P1P0Lagrangian,
    /// For homogeneous compression: the closed-form U.
    pub exact_u: Option<f64>,
}

const JOHNSON: &str = include_str!("../examples/johnson.toml");
const HOMOGENEOUS: &str = include_str!("../examples/homogeneous.toml");
const HERTZ: &str = include_str!("../examples/hertz.toml");

/// `text` (a scene) with `edits` applied (dotted paths, e.g. `("yield.h", 0.5)`), as TOML text.
pub fn edited(text: &str, edits: &[(&str, toml::Value)]) -> String {
    let mut table: toml::Table = toml::from_str(text).expect("kit scenes parse");
    for (path, value) in edits {
        let mut keys: Vec<&str> = path.split('.').collect();
        let last = keys.pop().unwrap();
        let mut cur = &mut table;
        for k in keys {
            cur = cur.get_mut(k).and_then(|v| v.as_table_mut()).expect("kit edits name existing tables");
        }
        cur.insert(last.to_string(), value.clone());
    }
    toml::to_string(&table).unwrap()
}

/// A scene from TOML text with `edits` applied, or the error that makes it invalid.
pub fn try_scene_with(text: &str, edits: &[(&str, toml::Value)]) -> Result<P1P0Lagrangian, SceneError> {
    let scene = Scene::from_toml(&edited(text, edits), Path::new("kit.toml"))?;
    Ok(scene.into_problem()?.0)
}

/// A scene from TOML text with `edits` applied (dotted paths, e.g. `("yield.h", 0.5)`).
pub fn scene_with(text: &str, edits: &[(&str, toml::Value)]) -> P1P0Lagrangian {
    try_scene_with(text, edits).expect("kit scenes are valid")
}

fn cells(c: [i64; 3]) -> toml::Value {
    toml::Value::Array(c.iter().map(|&x| toml::Value::Integer(x)).collect())
}

/// The TOML text of the small default scene of SPEC §6 (12×12×6 cells graded 3) with `edits`.
pub fn small_johnson_text(edits: &[(&str, toml::Value)]) -> String {
    let mut all = vec![("mesh.cells", cells([12, 12, 6])), ("mesh.grading.ratio", toml::Value::Float(3.0))];
    all.extend(edits.iter().cloned());
    edited(JOHNSON, &all)
}

/// The small default scene of SPEC §6 (12×12×6 cells graded 3): plasticity and contact.
pub fn small_johnson(edits: &[(&str, toml::Value)]) -> P1P0Lagrangian {
    scene_with(&small_johnson_text(edits), &[])
}

/// U of homogeneous compression (SPEC §7) for E = 100, ν = 0.3, k₀ = 1, h = 5.
pub fn homogeneous_u(f: f64) -> f64 {
    let (e, k0, h) = (100.0, 1.0, 5.0);
    let s = (2.0f64 / 3.0).sqrt() * f;
    f / e + if s > k0 { (s - k0) / h * (2.0 * f / 3.0) / s } else { 0.0 }
}

/// The kit's scenes.
pub fn scenes() -> Vec<KitScene> {
    let float = toml::Value::Float;
    let elliptic: toml::Value = toml::from_str::<toml::Table>(
        "g = { type = \"elliptic_paraboloid\", R1 = 4.0, R2 = 6.5, c1 = 0.08, c2 = -0.05 }",
    )
    .unwrap()["g"]
        .clone();
    vec![
        KitScene {
            name: "homogeneous, elastic (F = 1)",
            problem: scene_with(HOMOGENEOUS, &[("obstacle.F", float(1.0))]),
            exact_u: Some(homogeneous_u(1.0)),
        },
        KitScene {
            name: "homogeneous, plastic (F = 2)",
            problem: scene_with(HOMOGENEOUS, &[]),
            exact_u: Some(homogeneous_u(2.0)),
        },
        KitScene {
            name: "Hertz, elastic",
            problem: scene_with(HERTZ, &[("mesh.cells", cells([8, 8, 8])), ("mesh.grading.ratio", float(20.0))]),
            exact_u: None,
        },
        KitScene { name: "Johnson (SPEC §6)", problem: small_johnson(&[]), exact_u: None },
        KitScene {
            name: "Johnson, weak hardening h = 0.5",
            problem: small_johnson(&[("yield.h", float(0.5))]),
            exact_u: None,
        },
        KitScene {
            name: "Johnson, off-centre elliptic punch",
            problem: small_johnson(&[("obstacle.gap", elliptic)]),
            exact_u: None,
        },
    ]
}

/// Compares `a` with the reference `b` on `l`.
pub fn agreement(l: &dyn Lagrangian, a: &Solution, b: &Solution) -> Agreement {
    let u_rel = if b.extras.is_empty() {
        let d = a.u.iter().zip(&b.u).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
        d / b.u.iter().map(|x| x.abs()).fold(f64::MIN_POSITIVE, f64::max)
    } else {
        a.extras.iter().zip(&b.extras).map(|(x, y)| (x - y).abs() / y.abs().max(f64::MIN_POSITIVE)).fold(0.0, f64::max)
    };
    let stress_rel = energy_distance(l, &a.stress, &b.stress);
    let (ca, cb) = (contact_set(&a.lambda), contact_set(&b.lambda));
    let contact_mismatch = symmetric_difference(&ca, &cb);
    // elements whose trial stress lies within 1e-8 of the yield surface may flip either way
    let mut eps = vec![Sym::zeros(); l.n_points()];
    l.strain(&b.u, &mut eps);
    let law = *l.elasticity();
    let q0 = vec![0.0; l.hardening_dim()];
    let plastic_mismatch = (0..l.n_points())
        .filter(|&e| a.stress.plastic[e] != b.stress.plastic[e])
        .filter(|&e| match l.plasticity() {
            Some(p) => {
                let tr = law.stress(&eps[e]);
                p.contains(&tr, &q0, 1e-8) == p.contains(&tr, &q0, -1e-8)
            }
            None => true,
        })
        .collect();
    Agreement { u_rel, stress_rel, contact_mismatch, plastic_mismatch }
}

/// [σ̂_a − σ̂_b] / [σ̂_b] in the energy norm of SPEC §1.
pub fn energy_distance(l: &dyn Lagrangian, a: &StressField, b: &StressField) -> f64 {
    let law = *l.elasticity();
    let p = l.plasticity();
    let (mut num, mut den) = (0.0, 0.0);
    for (e, w) in l.weights().iter().enumerate() {
        let ds = a.sigma[e] - b.sigma[e];
        let dq: Vec<f64> = a.q(e).iter().zip(b.q(e)).map(|(x, y)| x - y).collect();
        num += w * energy_inner(p, &law, &ds, &dq, &ds, &dq);
        den += w * energy_inner(p, &law, &b.sigma[e], b.q(e), &b.sigma[e], b.q(e));
    }
    if den > 0.0 { (num / den).sqrt() } else { num.sqrt() }
}

/// x ≤ bound, false for NaN.
fn within(x: f64, bound: f64) -> bool {
    x <= bound
}

fn symmetric_difference(a: &[usize], b: &[usize]) -> Vec<usize> {
    let mut d: Vec<usize> =
        a.iter().filter(|x| !b.contains(x)).chain(b.iter().filter(|x| !a.contains(x))).copied().collect();
    d.sort_unstable();
    d
}

/// Runs `solver` and `reference` on every kit scene and checks convergence, the recomputed KKT
/// residual, the closed forms and the agreement. Returns the measurements, or the first failure.
pub fn check_solver(
    solver: &dyn Solver,
    reference: &dyn Solver,
    tol: &Tolerances,
) -> Result<Vec<SceneResult>, KitFailure> {
    let mut out = Vec::new();
    for s in scenes() {
        let fail = |check: &'static str, message: String| KitFailure { scene: s.name.into(), check, message };
        let l = &s.problem;
        let sol = solver.solve(l, &mut Silent).map_err(|e| fail("solve", e.to_string()))?;
        if !sol.report.converged {
            return Err(fail(
                "converged",
                format!("stopped: {:?} at KKT {:.2e}", sol.report.stop_reason, sol.report.kkt.max()),
            ));
        }
        let kkt = l.kkt(&sol.iterate(), &mut Workspace::new(l)).max();
        if !within(kkt, solver.tolerance()) {
            return Err(fail(
                "kkt",
                format!("recomputed KKT residual {kkt:.3e} > tolerance {:.1e}", solver.tolerance()),
            ));
        }
        if let Some(exact) = s.exact_u {
            let err = (sol.extras[0] - exact).abs() / exact;
            if err > tol.u_rel {
                return Err(fail(
                    "closed form",
                    format!("U = {:.12e}, closed form {exact:.12e}: error {err:.2e}", sol.extras[0]),
                ));
            }
        }
        let reference_sol = reference.solve(l, &mut Silent).map_err(|e| fail("reference", e.to_string()))?;
        let agreement = agreement(l, &sol, &reference_sol);
        if !within(agreement.u_rel, tol.u_rel) {
            return Err(fail("U", format!("relative difference {:.2e} > {:.0e}", agreement.u_rel, tol.u_rel)));
        }
        if !within(agreement.stress_rel, tol.stress_rel) {
            return Err(fail(
                "stress",
                format!("energy-norm difference {:.2e} > {:.0e}", agreement.stress_rel, tol.stress_rel),
            ));
        }
        if !agreement.contact_mismatch.is_empty() {
            return Err(fail("contact set", format!("rows differ: {:?}", agreement.contact_mismatch)));
        }
        if !agreement.plastic_mismatch.is_empty() {
            return Err(fail("plastic set", format!("elements differ: {:?}", agreement.plastic_mismatch)));
        }
        out.push(SceneResult { scene: s.name, iterations: sol.report.iterations, kkt, agreement });
    }
    Ok(out)
}
