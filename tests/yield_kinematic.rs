//! Von Mises with kinematic hardening (`type = "von_mises_kinematic"`, theory §9.3) in whole
//! scenes, through every solver:
//!
//! * (a) homogeneous compression (theory §7.1) above yield against its closed form, σ, ξ, the
//!   back stress χ, U and the nodal displacements;
//! * (b) pure kinematic hardening (h = 0) with modulus c gives the σ and u of isotropic hardening
//!   with h = c on the small default scene (one-step loading, theory §9.3);
//! * (c) the four solvers agree on the small default scene with kinematic and isotropic
//!   hardening (SOCP on the cone `k₀ + ξ ≥ |dev σ − χ|`).

mod common;
use common::*;
use saddle::core::{Solution, Solver};
use saddle::solvers::conformance::agreement;
use saddle::solvers::{Newton, Penalty, Uzawa};

/// The `[yield]` table of kinematic hardening.
fn kinematic(k0: f64, h: f64, c: f64) -> toml::Value {
    yield_table("von_mises_kinematic", &[("k0", k0), ("h", h), ("c", c)])
}

/// The solvers of the tests, tight enough for 1e-8 on the closed form.
fn solvers() -> Vec<(&'static str, Box<dyn Solver>)> {
    solvers_with(1e-12, 1e-11, 1e-10, 1e-11)
}

/// Homogeneous compression with kinematic hardening (theory §9.3): σ = −F e₃⊗e₃,
/// s = diag(F/3, F/3, −2F/3), |s| = √(2/3)F, n = s/|s| = diag(1, 1, −2)/√6 (the second vector
/// of the deviatoric basis). The local law gives |s| = r − 2Gλ and r − k₀ = (2G + h + c)λ,
/// so λ = (|s| − k₀)/(h + c) = |p|, p = λn, ξ = hλ, χ = cλn = c p, and ε = Aσ + p:
/// ε₁₁ = νF/E + λ/√6, ε₃₃ = −F/E − 2λ/√6, U = −ε₃₃. Returns (U, ξ, χ coordinates, ε₁₁, ε₃₃).
fn closed_form(e: f64, nu: f64, k0: f64, h: f64, c: f64, f: f64) -> (f64, f64, [f64; 5], f64, f64) {
    let s_norm = (2.0f64 / 3.0).sqrt() * f;
    let lambda = ((s_norm - k0) / (h + c)).max(0.0);
    let r6 = 6.0f64.sqrt();
    let e11 = nu * f / e + lambda / r6;
    let e33 = -f / e - 2.0 * lambda / r6;
    (-e33, h * lambda, [0.0, c * lambda, 0.0, 0.0, 0.0], e11, e33)
}

fn homogeneous(h: f64, c: f64, f: f64) {
    let mut t = example("homogeneous.toml");
    t.insert("yield".into(), kinematic(1.0, h, c));
    set(&mut t, "obstacle.F", toml::Value::Float(f));
    let (l, _) = build(&t);
    let (u_exact, xi, chi, e11, e33) = closed_form(100.0, 0.3, 1.0, h, c, f);
    assert!(chi[1] > 0.1, "clearly plastic: |χ| = {}", chi[1]);
    let tol = 1e-8;
    for (name, s) in solvers() {
        let sol = solve_converged(&l, name, s.as_ref());
        let u = sol.extras[0];
        let (es, eu) = compression_errors(&l, &sol, f, e11, e33, u_exact);
        let mut eq = 0.0f64;
        for i in 0..l.element.n_points() {
            let q = sol.stress.q(i);
            eq = eq.max((q[0] - xi).abs() / (xi.abs() + chi[1]));
            for k in 0..5 {
                eq = eq.max((q[1 + k] - chi[k]).abs() / chi[1]);
            }
        }
        let e_u = (u - u_exact).abs() / u_exact;
        println!(
            "homogeneous h = {h}, c = {c}, F = {f}: {name:>7} | {:>3} it | U {e_u:.1e} | σ {es:.1e} | ξ, χ {eq:.1e} | u {eu:.1e}",
            sol.report.iterations
        );
        assert!(e_u <= tol, "{name}: U = {u:.12e}, closed form {u_exact:.12e}");
        assert!(es <= tol && eq <= tol && eu <= tol, "{name}: σ {es:e}, (ξ, χ) {eq:e}, u {eu:e}");
        assert_eq!(sol.stress.n_plastic(), l.element.n_points(), "{name}: every element plastic");
    }
}

#[test]
fn homogeneous_compression_with_kinematic_hardening_matches_the_closed_form() {
    homogeneous(2.0, 3.0, 2.0);
}

#[test]
fn homogeneous_compression_with_pure_kinematic_hardening_matches_the_closed_form() {
    homogeneous(0.0, 5.0, 2.0);
}

/// Max over the nodal displacement vectors of |u_a − u_b| / max |u_b|.
fn u_distance(a: &Solution, b: &Solution) -> f64 {
    let d = a.u.iter().zip(&b.u).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
    d / b.u.iter().map(|x| x.abs()).fold(f64::MIN_POSITIVE, f64::max)
}

/// Theory §9.3: under one-step loading from the zero state, kinematic hardening with h = 0 and
/// modulus c has the local law (σ, tangent, ψ) of isotropic hardening with h = c, so the
/// discrete problems have the same σ and u; only the hardening variable differs (|χ| = ξ_iso).
#[test]
fn pure_kinematic_hardening_gives_the_stresses_of_isotropic_hardening_with_h_equal_c() {
    let h0 = 5.0;
    let iso = small_johnson();
    let mut kin = small_johnson();
    kin.insert("yield".into(), kinematic(1.0, 0.0, h0));
    let (li, _) = build(&iso);
    let (lk, _) = build(&kin);
    assert_eq!(lk.lagrangian().data.plasticity().unwrap().name(), "von_mises_kinematic");
    let pairs = solvers_with(1e-12, 1e-12, 1e-12, 1e-12).into_iter().filter(|(name, _)| *name != "penalty");
    for (name, s) in pairs {
        let a = solve_converged(&li, name, s.as_ref());
        let b = solve_converged(&lk, name, s.as_ref());
        let ds = a.stress.sigma.iter().zip(&b.stress.sigma).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max)
            / a.stress.sigma.iter().map(|x| x.norm()).fold(0.0, f64::max);
        let du = u_distance(&b, &a);
        let d_big_u = (a.extras[0] - b.extras[0]).abs() / a.extras[0].abs();
        // ξ_iso = |χ| element by element
        let dq = (0..li.element.n_points())
            .map(|i| {
                let chi = b.stress.q(i)[1..6].iter().map(|x| x * x).sum::<f64>().sqrt();
                (a.stress.q(i)[0] - chi).abs()
            })
            .fold(0.0, f64::max);
        println!(
            "kinematic h = 0, c = {h0} vs isotropic h = {h0}: {name:>6} | {} / {} it | σ {ds:.1e} | u {du:.1e} | U {d_big_u:.1e} | ξ_iso − |χ| {dq:.1e} | plastic {}",
            a.report.iterations,
            b.report.iterations,
            b.stress.n_plastic()
        );
        assert!(b.stress.n_plastic() > 0, "{name}: plastic elements expected");
        assert!(ds <= 1e-8 && du <= 1e-8 && d_big_u <= 1e-8, "{name}: σ {ds:e}, u {du:e}, U {d_big_u:e}");
        assert!(dq <= 1e-8, "{name}: ξ_iso − |χ| = {dq:e}");
        assert!(b.stress.sigma.iter().zip(0..).all(|(_, i)| b.stress.q(i)[0] == 0.0), "{name}: ξ frozen at 0");
    }
}

/// All four solvers agree on the small default scene with kinematic and isotropic hardening:
/// U within 1e-7, σ̂ within 1e-6 in the energy norm (with the metric ξη/h + χ:ω/c), against
/// Newton at 1e-12.
#[test]
fn all_solvers_agree_on_the_small_default_scene_with_kinematic_hardening() {
    let mut t = small_johnson();
    t.insert("yield".into(), kinematic(1.0, 2.0, 3.0));
    let (l, _) = build(&t);
    let reference = solve_converged(&l, "newton", &Newton { tol: 1e-12, ..Newton::default() });
    assert!(reference.stress.n_plastic() > 0);
    let mut list: Vec<(&str, Box<dyn Solver>)> = vec![
        ("newton", Box::new(Newton::default())),
        ("uzawa", Box::new(Uzawa::default())),
        ("penalty", Box::new(Penalty::default())),
    ];
    #[cfg(feature = "socp")]
    list.push(("socp", Box::new(saddle::solvers::Socp::default())));
    for (name, s) in list {
        let sol = solve_converged(&l, name, s.as_ref());
        let a = agreement(&l.lagrangian(), &sol, &reference);
        println!(
            "kinematic (h, c) = (2, 3), small default scene: {name:>7} vs newton 1e-12 | {:>4} it | KKT {:.1e} | U {:.1e} | σ̂ {:.1e} | plastic {}",
            sol.report.iterations,
            sol.report.kkt.max(),
            a.u_rel,
            a.stress_rel,
            sol.stress.n_plastic()
        );
        assert!(a.u_rel <= 1e-7 && a.stress_rel <= 1e-6, "{name}: U {:e}, σ̂ {:e}", a.u_rel, a.stress_rel);
        assert!(a.contact_mismatch.is_empty() && a.plastic_mismatch.is_empty(), "{name}: {a:?}");
    }
}

/// The interior point alone (no Newton polish, which shares the local law with the reference)
/// on the cone programme built from `VonMisesKinematic::cone` — one 6-dimensional cone per
/// element on (σ, ξ, χ), metric 1/h on ξ and 1/c on χ — agrees with Newton: U within 1e-7, σ̂
/// within 1e-6. With h = 0 the ξ variables are fixed at 0 and the χ stay free.
#[cfg(feature = "socp")]
#[test]
fn the_interior_point_on_the_kinematic_cone_agrees_with_newton() {
    for (h, c) in [(2.0, 3.0), (0.0, 5.0)] {
        let mut t = small_johnson();
        t.insert("yield".into(), kinematic(1.0, h, c));
        let (l, _) = build(&t);
        let reference = solve_converged(&l, "newton", &Newton { tol: 1e-12, ..Newton::default() });
        let ipm =
            saddle::solvers::Socp { polish: false, ipm_tol: 1e-12, tol: 1e-6, ..saddle::solvers::Socp::default() };
        let sol = solve_converged(&l, "interior point", &ipm);
        let counters = &sol.report.counters;
        assert_eq!(counters["ipm_soc_cones"], l.element.n_points() as f64);
        assert_eq!(counters["ipm_fixed_hardening_variables"], if h > 0.0 { 0.0 } else { 1.0 });
        let a = agreement(&l.lagrangian(), &sol, &reference);
        println!(
            "kinematic (h, c) = ({h}, {c}), small default scene: interior point vs newton 1e-12 | {} ipm it | KKT {:.1e} | U {:.1e} | σ̂ {:.1e}",
            counters["ipm_iterations"],
            sol.report.kkt.max(),
            a.u_rel,
            a.stress_rel
        );
        assert!(a.u_rel <= 1e-7 && a.stress_rel <= 1e-6, "h = {h}: U {:e}, σ̂ {:e}", a.u_rel, a.stress_rel);
    }
}

/// Output by name: `solution.vtu` carries the plugin's own hardening fields, `xi` (1 component)
/// and `back_stress` (5), with the values of the closed form — read back from the appended
/// data by their declared offsets.
#[test]
fn the_vtu_names_the_hardening_fields_of_the_plugin() {
    let (h, c, f) = (2.0, 3.0, 2.0);
    let mut t = example("homogeneous.toml");
    t.insert("yield".into(), kinematic(1.0, h, c));
    set(&mut t, "obstacle.F", toml::Value::Float(f));
    let (l, _) = build(&t);
    let sol = solve_converged(&l, "newton", &Newton { tol: 1e-12, ..Newton::default() });
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("solution.vtu");
    saddle::io::vtu::write_vtu(&path, l.view(), &sol).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let start = bytes.windows(2).position(|w| w == b"\n_").unwrap() + 2; // the appended block
    let head = String::from_utf8_lossy(&bytes[..start]).to_string();
    let (_, xi, chi, _, _) = closed_form(100.0, 0.3, 1.0, h, c, f);
    for (name, comps, exact) in [("xi", 1, vec![xi]), ("back_stress", 5, chi.to_vec())] {
        let tag = format!("Name=\"{name}\" NumberOfComponents=\"{comps}\" format=\"appended\" offset=\"");
        let at = head.find(&tag).unwrap_or_else(|| panic!("no {tag} in {head}")) + tag.len();
        let offset: usize = head[at..].split('"').next().unwrap().parse().unwrap();
        let block = &bytes[start + offset..];
        let len = u64::from_le_bytes(block[..8].try_into().unwrap()) as usize;
        assert_eq!(len, 8 * comps * l.element.n_points(), "{name}: byte count");
        let values: Vec<f64> = block[8..8 + len].chunks(8).map(|b| f64::from_le_bytes(b.try_into().unwrap())).collect();
        for cell in values.chunks(comps) {
            for (v, e) in cell.iter().zip(&exact) {
                assert!((v - e).abs() <= 1e-10 * (1.0 + e.abs()), "{name}: {v} against the closed form {e}");
            }
        }
    }
    assert!(!head.contains("Name=\"q\""), "no anonymous hardening field");
}
