//! theory §15: the a posteriori error estimate. Its effectivity index (estimate / true error) on
//! scenes with a known answer: homogeneous compression (exact: the estimate must vanish to
//! round-off), elastic Hertz and the plastic default scene on nested levels, P1 and P2, the true
//! error from the finest level corrected by its own extrapolated error (energy norm) or
//! Richardson's extrapolation (U). Levels are compared at points (P2's affine stresses, not
//! their element means: `studies::report::pointwise`), which is checked first against a closed
//! form and, for P1, against the element-mean transfer of theory §5.

mod common;
use common::*;
use saddle::core::{DiscreteProblem, ErrorEstimate, Solution, StressField, Sym, estimate};
use saddle::studies::report::pointwise::{PointFields, PointMap, point_distance};
use saddle::studies::report::transfer::{self, Metric, Quadrature, SampleMap};

/// A solved level: the problem, the solution, its estimate, its mean element size and its
/// fields within the elements (for distances between levels).
struct Level {
    p: DiscreteProblem,
    sol: Solution,
    est: ErrorEstimate,
    h: f64,
    fields: PointFields,
}

/// The scene `t` with `cells`, solved by Newton to a KKT residual of 1e-11, and estimated.
fn level(t: &toml::Table, cells: [i64; 3]) -> Level {
    let mut t = t.clone();
    set(&mut t, "mesh.cells", toml::Value::try_from(cells).unwrap());
    let (p, _) = build(&t);
    let clock = std::time::Instant::now();
    let sol = solve_converged(&p, "newton", &*solver("type = \"newton\"\ntol = 1e-11"));
    let solve_s = clock.elapsed().as_secs_f64();
    let l = p.lagrangian();
    let clock = std::time::Instant::now();
    let est = estimate(&*p.element, &l, &sol.stress);
    let estimate_s = clock.elapsed().as_secs_f64();
    println!(
        "{} cells {cells:?}: {} dofs, U = {:.8e}, η = {:.4e}, η_U = {:.4e}, δ = {:.4e}, Newton {} iterations {solve_s:.2} s, estimate {estimate_s:.3} s ({:.2} % of the solve)",
        p.element.name(),
        l.n_dofs(),
        sol.extras[0],
        est.energy,
        est.extras[0].unwrap_or(f64::NAN),
        p.element.strain_consistency_energy(l.data.elasticity, &sol.u),
        sol.report.iterations,
        100.0 * estimate_s / solve_s
    );
    let h = (l.weights().iter().sum::<f64>() / p.element.mesh().n_elements() as f64).cbrt();
    let fields = PointFields::of(&p, &sol.u, &sol.stress);
    Level { p, sol, est, h, fields }
}

/// ‖σ̂_c − σ̂_f‖_E, the coarse level's stresses sampled at the fine mesh's quadrature points.
fn distance(coarse: &Level, fine: &Level) -> f64 {
    let map = PointMap::new(coarse.p.element.mesh(), fine.p.element.mesh()).unwrap();
    point_distance(&Metric::of(&fine.p), &fine.fields, &coarse.fields, &map).stress_energy
}

/// `t` with the element `element` (`[discretisation] type`, and `contact_rows` when given).
fn with_element(t: &toml::Table, element: &str, rows: Option<&str>) -> toml::Table {
    let mut t = t.clone();
    let mut d = toml::Table::new();
    d.insert("type".into(), element.into());
    if let Some(r) = rows {
        d.insert("contact_rows".into(), r.into());
    }
    t.insert("discretisation".into(), toml::Value::Table(d));
    t
}

/// `f(x)` at the coordinates x of each of `p`'s stress points, in the points' order.
fn at_points<T>(p: &DiscreteProblem, f: impl Fn([f64; 3]) -> T) -> Vec<T> {
    let mesh = p.element.mesh();
    let bary = p.element.point_barycentrics();
    let mut out = Vec::with_capacity(mesh.n_elements() * bary.len());
    for e in 0..mesh.n_elements() {
        let x = mesh.tets[e].map(|v| mesh.nodes[v]);
        for l in &bary {
            let point: [f64; 3] = std::array::from_fn(|k| (0..4).map(|a| l[a] * x[a][k]).sum());
            out.push(f(point));
        }
    }
    out
}

/// The distance at points against a closed form, P2 (B̄) on the unit cube at 2³ cells (coarse)
/// and 3³ (fine: not nested, so the coarse field's elements cut the fine ones): a coarse field
/// σ₁₁ = x₁, ε₁₂ = x₂/2 — affine, so the coarse element fields reproduce it everywhere — against
/// a zero fine field is ‖σ‖_E² = ∫ σ₁₁²/E = 1/(3E), ‖ε‖² = ∫ 2ε₁₂² = 1/6 (the rule is exact for
/// quadratics); against the same field on the fine mesh it is 0. Element means would give
/// neither (their distance to the zero field is ∫ x̄_T²/E < 1/(3E)).
#[test]
fn the_distance_at_points_is_exact_for_affine_fields() {
    let t = with_element(&example("homogeneous.toml"), "p2", None);
    let problem = |n: i64| {
        let mut t = t.clone();
        set(&mut t, "mesh.cells", toml::Value::try_from([n, n, n]).unwrap());
        build(&t).0
    };
    let fields = |p: &DiscreteProblem, scale: f64| {
        let mut stress = StressField::new(p.lagrangian().n_points(), p.lagrangian().data.hardening_dim());
        let x = at_points(p, |x| x);
        for (s, x) in stress.sigma.iter_mut().zip(&x) {
            s[0] = scale * x[0];
        }
        // Mandel: the last component is √2 ε₁₂
        let strain: Vec<Sym> = x
            .iter()
            .map(|x| Sym::new(0.0, 0.0, 0.0, 0.0, 0.0, scale * std::f64::consts::SQRT_2 * x[1] / 2.0))
            .collect();
        PointFields::new(p, &stress, &strain)
    };
    let (coarse, fine) = (problem(2), problem(3));
    let map = PointMap::new(coarse.element.mesh(), fine.element.mesh()).unwrap();
    let metric = Metric::of(&fine);
    let e = 100.0;
    let d = point_distance(&metric, &fields(&fine, 0.0), &fields(&coarse, 1.0), &map);
    println!(
        "against zero: ‖σ‖_E² = {:.15e} (1/(3E) = {:.15e}), ‖ε‖² = {:.15e} (1/6)",
        d.stress_energy.powi(2),
        1.0 / (3.0 * e),
        d.strain_l2.powi(2)
    );
    assert!((d.stress_energy.powi(2) * 3.0 * e - 1.0).abs() < 1e-12, "{d:?}");
    assert!((d.strain_l2.powi(2) * 6.0 - 1.0).abs() < 1e-12, "{d:?}");
    let d = point_distance(&metric, &fields(&fine, 1.0), &fields(&coarse, 1.0), &map);
    println!("against itself: {d:?}");
    assert!(d.stress_energy < 1e-12 * d.fine_stress_energy && d.strain_l2 < 1e-12 * d.fine_strain_l2, "{d:?}");
}

/// For P1–P0 both rulers are exact on nested meshes (piecewise constant fields, every fine
/// element inside one coarse one), so the distance at points and the element-mean transfer of
/// theory §5 (`transfer::field_distance`) must agree to round-off: the small default scene's
/// box without grading and alignment (Kuhn cells, nested at 4×4×2 and 8×8×4), solved by Newton.
#[test]
fn for_p1_the_distance_at_points_is_the_element_mean_distance() {
    let mut t = small_johnson();
    let mesh = t.get_mut("mesh").and_then(|m| m.as_table_mut()).unwrap();
    mesh.remove("grading");
    mesh.remove("align");
    let solve = |n: i64| {
        let lv = level(&t, [2 * n, 2 * n, n]);
        let (s, e) = transfer::p0_fields(&lv.p, &lv.sol.u, &lv.sol.stress);
        (lv, s, e)
    };
    let ((c, cs, ce), (f, fs, fe)) = (solve(2), solve(4));
    let means = transfer::field_distance(
        &Metric::of(&f.p),
        &fs,
        &fe,
        &cs,
        &ce,
        &SampleMap::new(c.p.element.mesh(), f.p.element.mesh(), Quadrature::Children).unwrap(),
    );
    let points = point_distance(
        &Metric::of(&f.p),
        &f.fields,
        &c.fields,
        &PointMap::new(c.p.element.mesh(), f.p.element.mesh()).unwrap(),
    );
    let (stress, strain) = (points.stress_energy / points.fine_stress_energy, points.strain_l2 / points.fine_strain_l2);
    println!(
        "relative distances: stress {stress:.15e} and {:.15e}, strain {strain:.15e} and {:.15e}",
        means.stress_energy, means.strain_l2
    );
    assert!(stress > 1e-3 && (stress / means.stress_energy - 1.0).abs() < 1e-10, "{points:?} against {means:?}");
    assert!(strain > 1e-3 && (strain / means.strain_l2 - 1.0).abs() < 1e-10, "{points:?} against {means:?}");
}

/// One row of the effectivity table.
#[derive(Debug)]
struct Row {
    h: f64,
    dofs: usize,
    eta: f64,
    error: f64,
    eta_u: f64,
    error_u: f64,
}

/// The effectivity of the estimate on every level but the finest (the reference). The true
/// energy error of level i is (d_i² + e_f²)^{1/2}, d_i its distance to the finest level and e_f
/// the finest level's own error extrapolated from the last two differences (nested Galerkin
/// errors are orthogonal in linear elasticity: e_i² = d_i² + e_f²; the order p from the
/// consecutive differences). The true error of U is against `u_ref` when given (a reference
/// from a finer study), else Richardson's extrapolation of the last three levels with the order
/// from the data.
fn effectivity(levels: &[Level], u_ref: Option<f64>) -> (Vec<Row>, f64, f64) {
    let n = levels.len();
    assert!(n >= 3, "three levels at least");
    let step = |i: usize| distance(&levels[i], &levels[i + 1]);
    let (d1, d2) = (step(n - 3), step(n - 2));
    let r1 = levels[n - 3].h / levels[n - 2].h;
    let r2 = levels[n - 2].h / levels[n - 1].h;
    let p = (d1 / d2).ln() / r1.ln();
    let e_f = d2 / (r2.powf(2.0 * p) - 1.0).sqrt();
    let u = |i: usize| levels[i].sol.extras[0];
    let (u0, u1, u2) = (u(n - 3), u(n - 2), u(n - 1));
    let q = ((u0 - u1) / (u1 - u2)).ln() / r1.ln();
    let u_inf = u_ref.unwrap_or(u2 + (u2 - u1) / (r2.powf(q) - 1.0));
    let rows = levels[..n - 1]
        .iter()
        .map(|lv| {
            let d = distance(lv, &levels[n - 1]);
            Row {
                h: lv.h,
                dofs: lv.p.lagrangian().n_dofs(),
                eta: lv.est.energy,
                error: (d * d + e_f * e_f).sqrt(),
                eta_u: lv.est.extras[0].unwrap_or(f64::NAN),
                error_u: (lv.sol.extras[0] - u_inf).abs(),
            }
        })
        .collect();
    (rows, p, q)
}

/// Prints the table and returns the effectivities (energy, U) of every row; `u_ref` as in
/// [`effectivity`].
fn table(name: &str, levels: &[Level], u_ref: Option<f64>) -> Vec<(f64, f64)> {
    let (rows, p, q) = effectivity(levels, u_ref);
    println!("{name}: observed order of the stress differences {p:.2}, of U {q:.2}");
    println!("| h | dofs | η | true error | η / error | η_U | |U − U_∞| | η_U / error |");
    for r in &rows {
        println!(
            "| {:.4} | {} | {:.3e} | {:.3e} | {:.2} | {:.3e} | {:.3e} | {:.2} |",
            r.h,
            r.dofs,
            r.eta,
            r.error,
            r.eta / r.error,
            r.eta_u,
            r.error_u,
            r.eta_u / r.error_u
        );
    }
    rows.iter().map(|r| (r.eta / r.error, r.eta_u / r.error_u)).collect()
}

/// The elastic Hertz quarter model (examples/hertz.toml).
fn hertz() -> toml::Table {
    example("hertz.toml")
}

/// The estimate vanishes where the discrete solution is exact (theory §7.1): homogeneous
/// compression, elastic (F = 1) and plastic (F = 2), P1 and P2. Measured: η/‖σ̂_h‖_E 1.2e-15 to
/// 3.3e-15, η_U ≤ 6.5e-31; the bound 1e-11 leaves room for the solver's tolerance (1e-11).
#[test]
fn the_estimate_vanishes_on_homogeneous_compression() {
    for element in ["p1", "p2"] {
        for f in [1.0, 2.0] {
            let mut t = example("homogeneous.toml");
            set(&mut t, "obstacle.F", toml::Value::Float(f));
            let mut d = toml::Table::new();
            d.insert("type".into(), element.into());
            t.insert("discretisation".into(), toml::Value::Table(d));
            let lv = level(&t, [3, 3, 3]);
            println!(
                "{element}, F = {f}: η/‖σ̂_h‖_E = {:.2e}, η_U = {:.2e}",
                lv.est.relative,
                lv.est.extras[0].unwrap_or(f64::NAN)
            );
            assert!(lv.est.relative < 1e-11, "{element}, F = {f}: η/‖σ̂‖ = {:.3e}", lv.est.relative);
            let u = lv.sol.extras[0];
            let eta_u = lv.est.extras[0].expect("the punch's U carries the only load");
            assert!(eta_u < 1e-11 * u, "{element}, F = {f}: η_U = {eta_u:.3e} against U = {u:.3e}");
        }
    }
}

/// `saddle run` writes the estimate: `error_estimate` in summary.json (≈ 0 for homogeneous
/// compression, its cost a share of the solve), `error_indicator` in solution.vtu; `[output]
/// error_estimate = false` leaves both out.
#[test]
fn a_run_writes_the_estimate_unless_switched_off() {
    let text = std::fs::read_to_string(repo("examples/homogeneous.toml")).unwrap();
    for on in [true, false] {
        let scene = if on { text.clone() } else { format!("{text}\n[output]\nerror_estimate = false\n") };
        let (code, err, dir) = run_scene_kept(&scene);
        assert_eq!(code, 0, "{err}");
        let out = dir.path().join("out");
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
        let vtu = std::fs::read(out.join("solution.vtu")).unwrap();
        let head = String::from_utf8_lossy(&vtu[..vtu.len().min(4000)]).into_owned();
        let e = &summary["error_estimate"];
        if !on {
            assert!(e.is_null(), "{e}");
            assert!(!head.contains("error_indicator"));
            continue;
        }
        assert!(head.contains("Name=\"error_indicator\""), "{head}");
        // exact solution (theory §7.1): measured η/‖σ̂_h‖_E = 2e-15 after Uzawa to 1e-10
        assert!(e["energy_relative"].as_f64().unwrap() < 1e-11, "{e}");
        assert!(e["U"].as_f64().unwrap() < 1e-11, "{e}");
        let (cost, solve) = (e["cost_s"].as_f64().unwrap(), summary["end_to_end"]["solve"].as_f64().unwrap());
        assert!((e["cost_share"].as_f64().unwrap() - cost / solve).abs() <= 1e-12, "{e}");
        assert_eq!(cost, summary["end_to_end"]["estimate"].as_f64().unwrap());
    }
}

/// Effectivity on elastic Hertz, P1, levels 6³ and 12³ cells against 24³ (examples/hertz.toml's
/// grading): the estimate of the energy error and of U within [0.5, 3] of the true error.
/// Measured: see the report table of [`effectivity_table`].
#[test]
fn the_effectivity_on_elastic_hertz_lies_within_half_to_three() {
    let levels: Vec<Level> = [6, 12, 24].iter().map(|&n| level(&hertz(), [n, n, n])).collect();
    for (i, (e, eu)) in table("Hertz P1", &levels, None).into_iter().enumerate() {
        assert!((0.5..=3.0).contains(&e), "level {i}: energy effectivity {e:.3}");
        assert!((0.5..=3.0).contains(&eu), "level {i}: U effectivity {eu:.3}");
    }
}

/// Level `k` of the nested family of `t` whose coarsest level has `base` cells (theory §7.3:
/// levels k and 2k are nested).
fn family_level(t: &toml::Table, base: [i64; 3], k: i64) -> Level {
    let mut t = t.clone();
    set(&mut t, "mesh.base", toml::Value::try_from(base).unwrap());
    level(&t, base.map(|n| k * n))
}

/// Elastic Hertz on tests/hertz.rs's nested family (a uniform core: base 5³ cells, grading ratio
/// 40, core 0.3), P2 with B̄ and the dual quadratic contact rows (theory §10.1).
fn hertz_family_p2() -> toml::Table {
    let mut t = with_element(&hertz(), "p2", Some("dual_quadratic"));
    let grading: toml::Table = toml::from_str("toward = [0.0, 0.0, 0.0]\nratio = 40.0\ncore = 0.3").unwrap();
    set(&mut t, "mesh.grading", toml::Value::Table(grading));
    t
}

/// P2's Hertz rows of the effectivity table (theory §15.4): P2 (B̄, dual quadratic rows),
/// levels 1 and 2 of the nested family with a uniform core ([`hertz_family_p2`]) against level
/// 4 (189k dofs: 21 min on the loaded 2-core machine). The energy estimate lies within
/// [0.5, 3] of the true error (measured 0.70, 0.75); U's does not (8.2 and ≥ 9.4 against
/// [`HERTZ_U_BOX`]: B̄'s U converges faster than the compliance identity's η²/F says on this
/// family, theory §15.4), printed, not asserted.
#[test]
#[ignore]
fn effectivity_table_p2_hertz() {
    let levels: Vec<Level> = [1, 2, 4].iter().map(|&k| family_level(&hertz_family_p2(), [5, 5, 5], k)).collect();
    for (i, (e, eu)) in table("Hertz P2", &levels, None).into_iter().enumerate() {
        println!("level {i}: U effectivity {eu:.3} (not asserted: theory §15.4)");
        assert!((0.5..=3.0).contains(&e), "level {i}: energy effectivity {e:.3}");
    }
}

/// The effectivity table of the report (theory §15.4), P1: Hertz on the levels 8, 16 against 32
/// cells a side, the plastic default scene on 8×8×4 and 16×16×8 against 32×32×16. Slow
/// (minutes). P2's rows: [`effectivity_table_p2_hertz`] and
/// [`the_energy_effectivity_of_p2_on_the_plastic_default_scene_lies_within_half_to_three`].
#[test]
#[ignore]
fn effectivity_table() {
    let levels: Vec<Level> = [8, 16, 32].iter().map(|&n| level(&hertz(), [n, n, n])).collect();
    table("Hertz P1", &levels, None);
    let johnson = example("johnson.toml");
    let levels: Vec<Level> = [8, 16, 32].iter().map(|&n| level(&johnson, [n, n, n / 2])).collect();
    table("default scene (plastic) P1", &levels, None);
}

/// The Hertz rows of P2 without B̄ (`mean_dilatation = false`, plain P2, which does not lock
/// at ν = 0.3), to separate B̄ from the rest in the effectivity of U (theory §15.4; its levels
/// 1 and 2 were measured, level 4 not run to the end). Slow (about 20 min).
#[test]
#[ignore]
fn effectivity_table_p2_without_mean_dilatation() {
    let mut t = hertz_family_p2();
    set(&mut t, "discretisation.mean_dilatation", toml::Value::Boolean(false));
    let levels: Vec<Level> = [1, 2, 4].iter().map(|&k| family_level(&t, [5, 5, 5], k)).collect();
    table("Hertz P2 without B̄", &levels, None);
}

/// The default scene's U with P2 (B̄, dual quadratic rows) extrapolated from the levels 3, 4, 5
/// of examples/johnson_family.toml (Richardson, order 3.32 from the data): 8.41731e-3 ± 0.27 %
/// (docs/accuracy.md, "The default scene on nested levels").
const JOHNSON_U_P2: f64 = 8.41731e-3;

/// P2's energy effectivity on the plastic default scene, cheap levels (theory §15.4): the nested
/// family of examples/johnson_family.toml (B̄, dual quadratic rows, graded, Γ₁'s edges aligned)
/// on the base 4×4×2, levels 1, 2 against 4 (cells 4×4×2, 8×8×4 against 16×16×8; a minute).
/// The energy estimate lies within [0.5, 3] of the true error (measured 0.75, 0.60). U against
/// [`JOHNSON_U_P2`] (these levels' U is not monotone, so they extrapolate to nothing) is
/// printed, not asserted: measured 0.61 and 15.4 (theory §15.4).
#[test]
fn the_energy_effectivity_of_p2_on_the_plastic_default_scene_lies_within_half_to_three() {
    let family = example("johnson_family.toml");
    let levels: Vec<Level> = [1, 2, 4].iter().map(|&k| family_level(&family, [4, 4, 2], k)).collect();
    for (i, (e, eu)) in
        table("default scene (plastic) P2, base 4×4×2", &levels, Some(JOHNSON_U_P2)).into_iter().enumerate()
    {
        println!("level {i}: U effectivity {eu:.3} (not asserted: theory §15.4)");
        assert!((0.5..=3.0).contains(&e), "level {i}: energy effectivity {e:.3}");
    }
}

/// Hertz's U on the finite box, extrapolated from P2's raw U on the study family of
/// tests/hertz.rs (base 6³, ratio 70.5, core 0.28; k = 1..4, monotone, order 4.05):
/// 9.23701e-3 ± 1.3e-5 (docs/accuracy.md, "Hertz on nested levels"; P1's limit agrees).
const HERTZ_U_BOX: (f64, f64) = (9.23701e-3, 1.3e-5);

/// The goal estimate of U with P2 (B̄, dual quadratic rows) on the levels k = 1, 2 of the
/// Hertz study family, against [`HERTZ_U_BOX`]: η²/F within [0.5, 3] of the true error
/// (measured 1.04 and 2.76; with the reference's uncertainty 1.00–1.08 and 2.2–3.7, so k = 2's
/// upper end is not shown within). Theory §15.4.
#[test]
fn the_goal_estimate_of_p2_on_hertz_lies_within_half_to_three_against_the_box_reference() {
    let mut t = with_element(&hertz(), "p2", Some("dual_quadratic"));
    let grading: toml::Table = toml::from_str("toward = [0.0, 0.0, 0.0]\nratio = 70.5\ncore = 0.28").unwrap();
    set(&mut t, "mesh.grading", toml::Value::Table(grading));
    for k in [1, 2] {
        let lv = family_level(&t, [6, 6, 6], k);
        let error = HERTZ_U_BOX.0 - lv.sol.extras[0];
        let eta_u = lv.est.extras[0].unwrap();
        let index = eta_u / error.abs();
        println!(
            "k = {k}: U = {:.6e}, error {error:.3e} ± {:.1e}, η_U = {eta_u:.3e}, index {index:.3} ({:.2} to {:.2})",
            lv.sol.extras[0],
            HERTZ_U_BOX.1,
            eta_u / (error.abs() + HERTZ_U_BOX.1),
            eta_u / (error.abs() - HERTZ_U_BOX.1)
        );
        assert!(error > 2.0 * HERTZ_U_BOX.1, "k = {k}: the error {error:e} is not clear of the reference");
        assert!((0.5..=3.0).contains(&index), "k = {k}: U effectivity {index:.3}");
    }
}
