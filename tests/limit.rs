//! Limit analysis (issue 26, theory §13): the collapse multiplier as one conic solve, against
//! closed forms, the incremental sweep's plateau, and bad input.

mod common;
use common::*;
use saddle::solvers::{LimitAnalysis, LimitError};

/// The collapse of a scene table at Clarabel's tolerance 1e-8.
fn collapse(t: &toml::Table) -> Result<saddle::solvers::Collapse, LimitError> {
    let (problem, _) = build(t);
    LimitAnalysis { tol: 1e-8, ..LimitAnalysis::default() }.solve(&problem)
}

/// The homogeneous compression of `examples/homogeneous.toml` (unit cube on rollers, flat
/// punch over the whole bottom face) with yield surface `yield_table`, element `element`, punch
/// force F.
fn compression(yield_table: &str, element: &str, force: f64) -> toml::Table {
    let mut t = example("homogeneous.toml");
    t.insert("yield".into(), toml::Value::Table(toml::from_str(yield_table).unwrap()));
    set(&mut t, "obstacle.F", toml::Value::Float(force));
    t.insert("discretisation".into(), toml::Value::Table(toml::from_str(&format!("type = {element:?}")).unwrap()));
    t
}

/// Relative difference.
fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn homogeneous_compression_collapses_at_the_closed_form_for_von_mises_and_drucker_prager() {
    // von Mises: σ₃₃ = −λF, |s| = √(2/3) λF = k₀ ⇒ λ* = √(3/2) k₀ / F (theory §7.1). The
    // homogeneous flow (ε₃₃ = −1, ε₁₁ = ε₂₂ = ½) fits the rollers, so both bounds are exact and
    // P1 and P2 represent it: the answer is exact up to Clarabel's tolerance (1e-8; measured
    // relative errors below 1e-8).
    let k0 = 1.5;
    let f = 2.0;
    for element in ["p1", "p2"] {
        let c = collapse(&compression(&format!("type = \"von_mises\"\nk0 = {k0}\nh = 0.0"), element, f)).unwrap();
        let exact = (1.5f64).sqrt() * k0 / f;
        println!("von Mises {element}: {} {} (exact {exact})", c.multiplier, c.dual_multiplier);
        assert!(rel(c.multiplier, exact) < 1e-6 && rel(c.dual_multiplier, exact) < 1e-6, "{element}");
        assert!(c.relative_gap().abs() < 1e-6);
        // the punch's collapse force is λ*·F
        let force = c.obstacles[0].report.get("force").unwrap();
        assert!(rel(force, exact * f) < 1e-6, "force {force}");
    }
    // Drucker–Prager |s| + α tr σ ≤ k₀ under σ₃₃ = −p: √(2/3) p − α p = k₀ ⇒ p = k₀/(√(2/3) − α);
    // the homogeneous mechanism is the associated flow (dilatant), which the rollers allow.
    let alpha = 0.2;
    let exact = k0 / ((2.0f64 / 3.0).sqrt() - alpha) / f;
    let dp = format!("type = \"drucker_prager\"\nk0 = {k0}\nalpha = {alpha}\nh = 0.0");
    let c = collapse(&compression(&dp, "p1", f)).unwrap();
    println!("Drucker–Prager p1: {} {} (exact {exact})", c.multiplier, c.dual_multiplier);
    assert!(rel(c.multiplier, exact) < 1e-6 && rel(c.dual_multiplier, exact) < 1e-6);
    // with P2 the pointwise pressure is invisible to B̄'s equilibrium rows and only bounded above
    // by the cone: the static optimum is not unique, the interior point stalls and reruns
    // regularised (theory §13.3). λ⁻ stays a static bound and exact (measured 1.2e-10); λ⁺ is
    // then off by O(δ) = 1e-4 (measured −1.6e-4), and the warning says so.
    let c = collapse(&compression(&dp, "p2", f)).unwrap();
    println!("Drucker–Prager p2: {} {} (exact {exact}) {:?}", c.multiplier, c.dual_multiplier, c.warnings);
    assert!(rel(c.dual_multiplier, exact) < 1e-6 && rel(c.multiplier, exact) < 1e-3);
    assert!(c.warnings.iter().any(|w| w.contains("regularisation")), "{:?}", c.warnings);
}

#[test]
fn drucker_prager_steeper_than_the_compression_meridian_never_collapses() {
    // α ≥ √(2/3): uniaxial compression stays inside the cone for every p, so no multiplier
    // collapses the cube: the programme is unbounded and the error says so
    let t = compression("type = \"drucker_prager\"\nk0 = 1.0\nalpha = 0.9\nh = 0.0", "p1", 1.0);
    let e = collapse(&t).unwrap_err();
    assert!(matches!(e, LimitError::Unbounded { .. }), "{e}");
    assert!(e.to_string().contains("cannot cause collapse"), "{e}");
}

#[test]
fn hardening_is_ignored_with_a_warning_and_p1_is_warned_as_locking() {
    // h = 5: the limit load of the initial yield set, the same closed form √(3/2) k₀/F
    let c = collapse(&compression("type = \"von_mises\"\nk0 = 1.0\nh = 5.0", "p1", 1.0)).unwrap();
    assert!(rel(c.multiplier, 1.5f64.sqrt()) < 1e-6, "{}", c.multiplier);
    assert!(c.warnings.iter().any(|w| w.contains("hardening is ignored") && w.contains("xi")), "{:?}", c.warnings);
    assert!(c.warnings.iter().any(|w| w.contains("\"p1\" locks")), "{:?}", c.warnings);
    let c = collapse(&compression("type = \"von_mises\"\nk0 = 1.0\nh = 0.0", "p2", 1.0)).unwrap();
    assert!(c.warnings.is_empty(), "{:?}", c.warnings);
}

#[test]
fn bad_input_gives_typed_errors_naming_the_cause() {
    // an elastic scene: no yield surface, no collapse
    let mut t = compression("type = \"von_mises\"\nk0 = 1.0\nh = 0.0", "p1", 1.0);
    t.remove("yield");
    let e = collapse(&t).unwrap_err();
    assert!(matches!(e, LimitError::Elastic { .. }) && e.to_string().contains("elastic"), "{e}");
    // Tresca has no second-order-cone form (theory §13.1): without the feature `sdp` its
    // semidefinite form is refused, named, with the plugin's reason and the feature to build
    if cfg!(not(feature = "sdp")) {
        let e = collapse(&compression("type = \"tresca\"\nsigma0 = 2.0\nh = 0.0", "p1", 1.0)).unwrap_err();
        assert!(matches!(e, LimitError::NoConicForm { .. }), "{e}");
        let text = e.to_string();
        assert!(text.contains("\"tresca\"") && text.contains("semidefinite") && text.contains("`sdp`"), "{e}");
    }
    // no load
    let e = collapse(&compression("type = \"von_mises\"\nk0 = 1.0\nh = 0.0", "p1", 0.0)).unwrap_err();
    assert!(matches!(e, LimitError::NoLoad), "{e}");
    // friction: tangential rows have no place in the kinematic problem (theory §13.1), refused
    // with the count of nodes that carry them rather than read as normal rows
    let mut t = compression("type = \"von_mises\"\nk0 = 1.0\nh = 0.0", "p1", 1.0);
    let sphere = "type = \"rigid_sphere\"\ncenter = [0.5, 0.5, -5.0]\nR = 5.0\ndirection = [0.0, 0.0, 1.0]\n\
                  F = 1.0\nW = [0.001, 0.0]\nfriction = { type = \"tresca\", g = 0.1 }\nzone = { group = \"zmin\" }";
    t.insert("obstacle".into(), toml::Value::Table(toml::from_str(sphere).unwrap()));
    let e = collapse(&t).unwrap_err();
    assert!(matches!(e, LimitError::Friction { blocks } if blocks > 0) && e.to_string().contains("friction"), "{e}");
}

/// `saddle limit` on a scene table written to a temporary folder: (exit code, stderr, the
/// folder with `out/` in it).
fn limit_cli(t: &toml::Table, extra: &[&str]) -> (i32, String, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, toml::to_string(t).unwrap()).unwrap();
    let out = dir.path().join("out");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_saddle"))
        .args(["limit", scene.to_str().unwrap(), "--out", out.to_str().unwrap()])
        .args(extra)
        .output()
        .unwrap();
    (o.status.code().unwrap(), String::from_utf8_lossy(&o.stderr).into_owned(), dir)
}

#[test]
fn saddle_limit_writes_limit_json_and_mechanism_vtu() {
    // the homogeneous compression with F = 2: λ* = √(3/2)/2, the punch's collapse force √(3/2)
    let t = compression("type = \"von_mises\"\nk0 = 1.0\nh = 0.0", "p1", 2.0);
    let (code, err, dir) = limit_cli(&t, &["--discretisation", "p2"]);
    assert_eq!(code, 0, "{err}");
    let out = dir.path().join("out");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("limit.json")).unwrap()).unwrap();
    for key in ["multiplier", "dual_multiplier", "gap", "wall_s", "dofs", "cones", "obstacles"] {
        assert!(json.get(key).is_some(), "limit.json lacks {key}: {json}");
    }
    // the default tolerance is 1e-5 (measured relative errors below 1e-6 here)
    let exact = 1.5f64.sqrt();
    assert!(rel(json["multiplier"].as_f64().unwrap(), exact / 2.0) < 1e-5, "{json}");
    assert!(rel(json["obstacles"]["obstacle"]["force"].as_f64().unwrap(), exact) < 1e-5, "{json}");
    assert_eq!(json["discretisation"], "p2");
    let bytes = std::fs::read(out.join("mechanism.vtu")).unwrap();
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(2000)]);
    for field in ["\"velocity\"", "\"dissipation\"", "\"stress\""] {
        assert!(head.contains(field), "mechanism.vtu lacks {field}");
    }
    // an elastic scene: exit 1, the reason, nothing written
    let mut t = t;
    t.remove("yield");
    let (code, err, dir) = limit_cli(&t, &[]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("elastic"), "{err}");
    assert!(!dir.path().join("out").join("limit.json").exists());
}

/// The strip punch of `examples/strip_punch.toml` (P2, plane strain, displacement-controlled,
/// h = 0) on `cells`.
fn strip(cells: [usize; 3]) -> toml::Table {
    let mut t = example("strip_punch.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from(cells).unwrap());
    t
}

#[test]
fn strip_punch_collapses_at_prandtls_force_and_at_the_sweeps_plateau() {
    // Prandtl's limit force on the strip: (2 + π) k B t, k = k₀/√2, B = 1, t = 0.25 (theory §10)
    let prandtl = (2.0 + std::f64::consts::PI) / 2f64.sqrt() * 0.25;
    let t = strip([32, 1, 16]);
    let (problem, solver) = build(&t);
    let c = LimitAnalysis::default().solve(&problem).unwrap();
    // the displacement-controlled punch: the multiplier is its collapse force (theory §13.1)
    let force = c.obstacles[0].report.get("force").unwrap();
    println!("limit {} {} force {force} gap {:e}; Prandtl {prandtl}", c.multiplier, c.dual_multiplier, c.gap);
    assert!(rel(force, c.dual_multiplier) < 1e-12);
    // the default tolerance 1e-5: measured relative gap 1.6e-5
    assert!(c.relative_gap() >= 0.0 && c.relative_gap() < 1e-4, "{}", c.relative_gap());
    // 14k dofs: measured +1.25 % above Prandtl (+0.50 % on the 57k-dof example mesh,
    // docs/limit_analysis.md)
    assert!(rel(c.multiplier, prandtl) < 0.015 && c.multiplier > prandtl, "{}", c.multiplier);
    // the incremental solve's plateau on the same mesh: Newton at U = 0.2 (twenty times the
    // scene's U) is on it (tests/p2.rs: doubling U changes the force by < 0.1 %); measured
    // agreement 0.01 %
    let mut t2 = t.clone();
    set(&mut t2, "obstacle.U", toml::Value::Float(0.2));
    let (p2, _) = build(&t2);
    let sol = solver.unwrap().solve(&p2.lagrangian(), &mut saddle::core::Silent).unwrap();
    let plateau: f64 = sol.lambda.iter().sum();
    println!("plateau {plateau}");
    assert!(rel(c.multiplier, plateau) < 0.005, "limit {} against the plateau {plateau}", c.multiplier);
}

#[test]
fn two_named_punches_each_report_their_collapse_force() {
    // the homogeneous compression with the bottom face split between two force-controlled
    // punches, `left` (x ≤ 0.4: the nodes x = 0, 1/3) and `right` (x ≥ 0.6: x = 2/3, 1), F = 1
    // each: each carries half of the face (its nodes' tributary area is 1/2), the homogeneous
    // stress σ₃₃ = −2λ is admissible and the homogeneous flow a mechanism, so
    // λ* = √(3/2) k₀ / 2 exactly, and each punch's collapse force is λ*·1
    let mut t = compression("type = \"von_mises\"\nk0 = 1.0\nh = 0.0", "p1", 1.0);
    let punch = |name: &str, lo: f64, hi: f64| -> toml::Value {
        toml::from_str(&format!(
            "name = {name:?}\ntype = \"rigid_punch\"\nF = 1.0\ngap = {{ type = \"flat\" }}\n\
             zone = {{ all = [ {{ group = \"zmin\" }}, {{ box = {{ min = [{lo}, -1.0, -1.0], max = [{hi}, 2.0, 1e-9] }} }} ] }}"
        ))
        .unwrap()
    };
    t.insert("obstacle".into(), toml::Value::Array(vec![punch("left", -1.0, 0.4), punch("right", 0.6, 2.0)]));
    let c = collapse(&t).unwrap();
    let exact = 1.5f64.sqrt() / 2.0;
    println!(
        "two punches: {} {:?}",
        c.multiplier,
        c.obstacles.iter().map(|o| o.report.get("force")).collect::<Vec<_>>()
    );
    assert!(rel(c.multiplier, exact) < 1e-6, "{}", c.multiplier);
    for o in &c.obstacles {
        assert!(rel(o.report.get("force").unwrap(), exact) < 1e-6, "{:?}: {:?}", o.name, o.report);
    }
    assert_eq!(c.obstacles.iter().map(|o| o.name.clone().unwrap()).collect::<Vec<_>>(), ["left", "right"]);
}

#[cfg(feature = "sdp")]
#[test]
fn tresca_homogeneous_compression_collapses_at_sigma0_over_f() {
    // uniaxial compression σ₃₃ = −λF has the principal spread λF, so λ* = σ₀/F; the homogeneous
    // flow ε = (½, ½, −1) is in the normal cone of the edge σ₁ = σ₂ = 0 and fits the rollers, so
    // both bounds are exact (semidefinite cones ∃a: aI ⪯ σ ⪯ (a + σ₀)I, theory §13.1), for P1 and
    // P2 (measured relative errors below 1e-8 at tol 1e-8)
    let (sigma0, f) = (3.0, 2.0);
    for element in ["p1", "p2"] {
        let c = collapse(&compression(&format!("type = \"tresca\"\nsigma0 = {sigma0}\nh = 0.0"), element, f)).unwrap();
        println!("Tresca {element}: {} {} (exact {})", c.multiplier, c.dual_multiplier, sigma0 / f);
        assert!(rel(c.multiplier, sigma0 / f) < 1e-6 && rel(c.dual_multiplier, sigma0 / f) < 1e-6, "{element}");
    }
}

#[cfg(feature = "sdp")]
#[test]
fn tresca_strip_punch_lies_between_the_inscribed_and_circumscribed_von_mises() {
    // D_in ⊂ D_Tresca ⊂ D_circ, von Mises with k₀ = σ₀/√2 inscribed in Tresca's prism and
    // k₀ = √(2/3) σ₀ circumscribed: on the same discretisation the static problem's feasible set
    // grows, so λ_in ≤ λ_T ≤ λ_circ exactly (up to the gaps, tol 1e-7: relative gaps ≤ 2e-7).
    // In plane strain the inscribed one has Tresca's shear yield stress σ₀/2 and its dissipation
    // on ε = (e, −e, 0), so λ_T → λ_in under refinement; B̄'s point strains are trace-free only in
    // the element mean, not plane, and Tresca dissipates more on them: measured λ_T/λ_in − 1 =
    // 3.3 % on 16 × 1 × 8 cells, 1.9 % on 32 × 1 × 16 (docs/limit_analysis.md).
    let sigma0 = 2.0;
    let settings = LimitAnalysis { tol: 1e-7, ..LimitAnalysis::default() };
    let on = |yield_table: String| {
        let mut t = strip([16, 1, 8]);
        t.insert("yield".into(), toml::Value::Table(toml::from_str(&yield_table).unwrap()));
        settings.solve(&build(&t).0).unwrap()
    };
    let mises = |k0: f64| on(format!("type = \"von_mises\"\nk0 = {k0}\nh = 0.0"));
    let inscribed = mises(sigma0 / 2f64.sqrt());
    let circumscribed = mises((2.0f64 / 3.0).sqrt() * sigma0);
    let tresca = on(format!("type = \"tresca\"\nsigma0 = {sigma0}\nh = 0.0"));
    println!(
        "Tresca {} {} gap {:e}; von Mises inscribed {}, circumscribed {}; Tresca/inscribed {}",
        tresca.multiplier,
        tresca.dual_multiplier,
        tresca.gap,
        inscribed.multiplier,
        circumscribed.multiplier,
        tresca.multiplier / inscribed.multiplier
    );
    let slack = 1e-6 * tresca.multiplier;
    assert!(
        inscribed.dual_multiplier <= tresca.multiplier + slack,
        "{} {}",
        inscribed.dual_multiplier,
        tresca.multiplier
    );
    assert!(tresca.dual_multiplier <= circumscribed.multiplier + slack);
    // and near the inscribed one (measured +3.3 %), far from the circumscribed (+15.5 %)
    assert!(tresca.multiplier / inscribed.multiplier < 1.04, "{}", tresca.multiplier / inscribed.multiplier);
}

#[test]
#[ignore = "about 40 min on the loaded 2-core machine: cargo test --release --test limit -- --ignored shield"]
fn circular_punch_mean_pressure_is_near_shields() {
    // examples/circular_punch.toml (quarter model, box mesh, P2 with B̄, von Mises with σ_y = 2):
    // Shield's 5.69 k (1955) is Tresca's; von Mises with the same σ_y contains Tresca's prism,
    // so its mean pressure is at least 5.69 σ_y/2 (theory §13.5; the comparison with Shield is
    // `tresca_circular_punch_mean_pressure_is_shields_…`, with Tresca on a mesh fitted to the
    // rim). The multiplier of the displacement-controlled punch is its collapse force. Measured
    // at a92cf2f: 4.61744, mean pressure 5.879 k, +3.3 % over 5.69 k, relative gap 2.2e-5 (on the
    // Gmsh meshes of examples/shield_punch.toml von Mises gives 6.03–6.06 k)
    let t = example("circular_punch.toml");
    let (problem, _) = build(&t);
    let c = LimitAnalysis::default().solve(&problem).unwrap();
    let pressure = c.multiplier / (std::f64::consts::PI / 4.0);
    println!(
        "circular punch: {} {} gap {:e}, {} iterations, {:.0} s; mean pressure {pressure} k against 5.69 k",
        c.multiplier, c.dual_multiplier, c.gap, c.iterations, c.wall_s
    );
    assert!(c.relative_gap() < 1e-4, "{}", c.relative_gap());
    assert!(rel(pressure, 5.69) < 0.035 && pressure > 5.69, "{pressure}");
}

#[cfg(feature = "sdp")]
#[test]
fn tresca_circular_punch_mean_pressure_is_shields_and_von_mises_lies_between_the_hexagons() {
    // examples/shield_punch.toml on its coarse mesh (tests/data/shield_coarse.msh, 7 422 dofs,
    // the punch's rim on element edges): Shield (1955) gives the mean pressure 5.69 k under a
    // smooth flat circular punch on a Tresca half-space, k = σ₀/2. With σ₀ = 2 the quarter force
    // tends to 5.69 π/4. Measured +0.39 % here, +0.12 % on the example's 22 515-dof mesh (theory
    // §13.5); the issue asks for 3 %.
    let mut t = example("shield_punch.toml");
    set(&mut t, "mesh.file", toml::Value::String(repo("tests/data/shield_coarse.msh").display().to_string()));
    let solve = |yield_table: &str| {
        let mut t = t.clone();
        t.insert("yield".into(), toml::Value::Table(toml::from_str(yield_table).unwrap()));
        LimitAnalysis::default().solve(&build(&t).0).unwrap()
    };
    let quarter = std::f64::consts::PI / 4.0;
    let tresca = solve("type = \"tresca\"\nsigma0 = 2.0\nh = 0.0");
    let pressure = tresca.multiplier / quarter;
    println!(
        "Shield, Tresca: {} {} gap {:e}, mean pressure {pressure} k against 5.69 k",
        tresca.multiplier, tresca.dual_multiplier, tresca.gap
    );
    assert!(tresca.relative_gap().abs() < 1e-4, "{}", tresca.relative_gap());
    assert!(rel(pressure, 5.69) < 0.03, "{pressure}");
    // von Mises with σ_y = σ₀ circumscribes Tresca's prism and is inscribed in the prism with
    // σ₀' = 2σ_y/√3, so on the same discretisation λ_T(σ₀) ≤ λ_vM ≤ (2/√3) λ_T(σ₀) exactly (the
    // static feasible sets are nested; slack: the gaps, relative ≤ 1e-4). Shield's value is not
    // von Mises' (measured 6.08 k here, 6.05 k on the example's mesh): Haar–Kármán fixes the
    // stress on Tresca's edges, where the two surfaces touch, but not the flow rule there.
    let mises = solve(&format!("type = \"von_mises\"\nk0 = {}\nh = 0.0", (2.0f64 / 3.0).sqrt() * 2.0));
    println!("Shield, von Mises σ_y = 2: {} (mean pressure {} k)", mises.multiplier, mises.multiplier / quarter);
    let slack = 1e-4 * mises.multiplier;
    assert!(tresca.dual_multiplier <= mises.multiplier + slack, "{} {}", tresca.dual_multiplier, mises.multiplier);
    assert!(mises.dual_multiplier <= 2.0 / 3f64.sqrt() * tresca.multiplier + slack);
}
