//! Hertz verification (theory §7) on the elastic quarter model of `examples/hertz.toml`:
//! contact radius a, peak pressure p₀ and approach δ within 3 % of Hertz, and F ∝ δ^{3/2}
//! (exponent within 2 %).
//!
//! * a from the second moment of the contact forces: for Hertz's pressure
//!   Σλ_i r_i² / Σλ_i = (2/5) a² (robust: no areas, no fit, exact for linear interpolation up to
//!   O(h²));
//! * p₀ from the nodal pressures p_i = λ_i / A_i (A_i the node's share of the contact face) of
//!   the inner contact nodes, fitted to Hertz's profile p² = p₀² (1 − r²/a²), a line in r²;
//! * δ is the approach of distant points. The block is finite and clamped, which makes it
//!   stiffer than the half-space by a smooth field of size O(a/L) (4 % here); measuring the
//!   punch against an axis point at depth d and adding that point's half-space displacement
//!   under Hertz's pressure, δ ≈ U − u₃(0, 0, d) + u₃^{half-space}(0, 0, d), cancels that field
//!   up to O(d/L).

mod common;
use common::*;
use saddle::core::DiscreteProblem;
use saddle::core::{Silent, Solution, Solver};
use std::f64::consts::PI;
use std::sync::OnceLock;

const E: f64 = 100.0;
const NU: f64 = 0.3;
const R: f64 = 5.0;

/// Hertz's a, p₀, δ for the whole force `f` (theory §7).
fn hertz(f: f64) -> (f64, f64, f64) {
    let e_star = E / (1.0 - NU * NU);
    let a = (3.0 * f * R / (4.0 * e_star)).cbrt();
    (a, 3.0 * f / (2.0 * PI * a * a), a * a / R)
}

/// Vertical displacement of the half-space on the axis at depth z under Hertz's pressure:
/// the Boussinesq kernel (1+ν)/(2πE) [2(1−ν)/s + z²/s³] integrated over p₀√(1 − ρ²/a²).
fn half_space_axis_displacement(a: f64, p0: f64, z: f64) -> f64 {
    // ρ = a sin θ: p dA = p₀ cos θ · 2π a sin θ · a cos θ dθ, smooth in θ ∈ [0, π/2]
    let n = 4000;
    let h = PI / 2.0 / n as f64;
    let f = |t: f64| {
        let rho = a * t.sin();
        let s = (rho * rho + z * z).sqrt();
        // 2πρ K(ρ, z), written with ρ/s so that the surface z = 0 is exact
        let ros = if s > 0.0 { rho / s } else { 1.0 };
        let two_pi_rho_k = (1.0 + NU) / E * (2.0 * (1.0 - NU) * ros + z * z * ros / (s * s).max(f64::MIN_POSITIVE));
        p0 * t.cos() * a * t.cos() * two_pi_rho_k
    };
    // Simpson
    (0..=n)
        .map(|k| {
            f(k as f64 * h)
                * if k == 0 || k == n {
                    1.0
                } else if k % 2 == 1 {
                    4.0
                } else {
                    2.0
                }
        })
        .sum::<f64>()
        * h
        / 3.0
}

/// The quarter model with whole force 0.3, solved once for all tests.
fn default_solution() -> &'static (DiscreteProblem, Solution) {
    static SOLVED: OnceLock<(DiscreteProblem, Solution)> = OnceLock::new();
    SOLVED.get_or_init(|| solve(0.3))
}

/// The quarter model with whole force `f`.
fn solve(f: f64) -> (DiscreteProblem, Solution) {
    let mut t = example("hertz.toml");
    set(&mut t, "obstacle.F", toml::Value::Float(f / 4.0));
    let (l, solver) = build(&t);
    let sol = solver.unwrap().solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged);
    (l, sol)
}

/// p₀ of the least-squares fit of Hertz's profile p² = p₀² (1 − r²/a²), a line in r², to the
/// points (r², p²) (theory §7).
fn hertz_profile_peak(pts: &[(f64, f64)]) -> f64 {
    let n = pts.len() as f64;
    let (sx, sy) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    let slope =
        pts.iter().map(|p| (p.0 - sx) * (p.1 - sy)).sum::<f64>() / pts.iter().map(|p| (p.0 - sx).powi(2)).sum::<f64>();
    (sy - slope * sx).sqrt()
}

/// Measured (a, p₀, δ).
fn measure(l: &DiscreteProblem, sol: &Solution) -> (f64, f64, f64) {
    let mesh = l.element.mesh();
    // each node's share of the contact face x₃ = 0
    let mut area = vec![0.0; mesh.n_nodes()];
    for &f in &mesh.groups["zmin"] {
        let [a, b, c] = mesh.boundary[f].map(|n| mesh.nodes[n]);
        let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        for n in mesh.boundary[f] {
            area[n] += cross.abs() / 6.0;
        }
    }
    let rows = l.lagrangian().data.rows;
    let r2 = |i: usize| {
        let x = mesh.nodes[rows.node[i]];
        x[0] * x[0] + x[1] * x[1]
    };
    let force: f64 = sol.lambda.iter().sum();
    let a = (2.5 * (0..rows.n_rows()).map(|i| sol.lambda[i] * r2(i)).sum::<f64>() / force).sqrt();
    // p² against r² over the contact nodes well inside the contact (the rim ring carries the
    // discretised edge)
    let pts: Vec<(f64, f64)> = (0..rows.n_rows())
        .filter(|&i| sol.lambda[i] > 0.0 && r2(i) <= (0.7 * a).powi(2))
        .map(|i| (r2(i), (sol.lambda[i] / area[rows.node[i]]).powi(2)))
        .collect();
    let p0 = hertz_profile_peak(&pts);
    // δ against the axis node nearest to depth 3a
    let disp = l.element.nodal_vectors(&sol.u);
    let axis = (0..mesh.n_nodes())
        .filter(|&k| mesh.nodes[k][0] == 0.0 && mesh.nodes[k][1] == 0.0)
        .min_by(|&i, &j| (mesh.nodes[i][2] - 3.0 * a).abs().total_cmp(&(mesh.nodes[j][2] - 3.0 * a).abs()))
        .unwrap();
    let d = mesh.nodes[axis][2];
    let (a_h, p0_h, _) = hertz(4.0 * force);
    let delta = sol.extras[0] - disp[axis][2] + half_space_axis_displacement(a_h, p0_h, d);
    (a, p0, delta)
}

#[test]
fn half_space_kernel_gives_the_hertz_approach_at_the_surface() {
    // the integral reproduces δ = a²/R at depth 0⁺ and decays like a point load far away
    let (a, p0, delta) = hertz(0.3);
    assert!((half_space_axis_displacement(a, p0, 0.0) - delta).abs() < 1e-12 * delta);
    let z = 50.0 * a;
    let point = 0.3 * (1.0 + NU) * (3.0 - 2.0 * NU) / (2.0 * PI * E * z);
    assert!((half_space_axis_displacement(a, p0, z) - point).abs() < 1e-3 * point);
}

#[test]
fn contact_radius_peak_pressure_and_approach_match_hertz() {
    let f = 0.3;
    let (l, sol) = default_solution();
    let (a, p0, delta) = measure(l, sol);
    let (a_h, p0_h, delta_h) = hertz(f);
    let err = |x: f64, y: f64| (x - y).abs() / y;
    println!("a {a:.5} (Hertz {a_h:.5}, {:.2}%)", 100.0 * err(a, a_h));
    println!("p0 {p0:.5} (Hertz {p0_h:.5}, {:.2}%)", 100.0 * err(p0, p0_h));
    println!(
        "delta {delta:.6e} (Hertz {delta_h:.6e}, {:.2}%); raw U {:.6e}",
        100.0 * err(delta, delta_h),
        sol.extras[0]
    );
    assert!(err(a, a_h) < 0.03);
    assert!(err(p0, p0_h) < 0.03);
    assert!(err(delta, delta_h) < 0.03);
}

#[test]
fn force_grows_like_the_approach_to_the_three_halves() {
    let fs = [0.3, 0.6, 1.2];
    let deltas: Vec<f64> = fs
        .iter()
        .map(|&f| {
            let (l, sol) = solve(f);
            measure(&l, &sol).2
        })
        .collect();
    // least-squares slope of ln F against ln δ
    let (x, y): (Vec<f64>, Vec<f64>) = deltas.iter().zip(&fs).map(|(d, f)| (d.ln(), f.ln())).unzip();
    let (mx, my) = (x.iter().sum::<f64>() / 3.0, y.iter().sum::<f64>() / 3.0);
    let slope = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum::<f64>()
        / x.iter().map(|a| (a - mx).powi(2)).sum::<f64>();
    println!("exponent of F against δ: {slope:.4} (Hertz 1.5, {:.2}%); δ = {deltas:?}", 100.0 * (slope / 1.5 - 1.0));
    assert!((slope / 1.5 - 1.0).abs() < 0.02);
}

/// A nested Hertz family: `examples/hertz.toml`'s box on `base` cells per axis, graded toward
/// the contact with a uniform core (theory §7.3); level k cuts every base cell into k, so every
/// level has the same grading and alignment and levels k and 2k are nested.
#[derive(Clone, Copy, Debug)]
struct Family {
    base: [usize; 3],
    ratio: f64,
    core: f64,
}

impl Family {
    /// Level `k` of the family in the scene table `t`.
    fn level(&self, t: &mut toml::Table, k: usize) {
        let mut grading = toml::Table::new();
        grading.insert("toward".into(), toml::Value::try_from([0.0, 0.0, 0.0]).unwrap());
        grading.insert("ratio".into(), self.ratio.into());
        grading.insert("core".into(), self.core.into());
        set(t, "mesh.grading", toml::Value::Table(grading));
        set(t, "mesh.base", toml::Value::try_from(self.base).unwrap());
        set(t, "mesh.cells", toml::Value::try_from(self.base.map(|n| n * k)).unwrap());
    }

    /// The base grid's nodes along x₃ on the axis x₁ = x₂ = 0 (those of every level).
    fn base_axis_depths(&self) -> Vec<f64> {
        let mut t = example("hertz.toml");
        self.level(&mut t, 1);
        let (l, _) = build(&t);
        let m = l.element.mesh();
        let mut z: Vec<f64> =
            (0..m.n_nodes()).filter(|&n| m.nodes[n][0] == 0.0 && m.nodes[n][1] == 0.0).map(|n| m.nodes[n][2]).collect();
        z.sort_by(f64::total_cmp);
        z
    }

    /// The depth against which δ is measured: the base axis node at the end of the uniform
    /// core (a node of every level, inside the resolved region; the base axis nodes nearest 3a
    /// lie in the graded cells beyond it, whose far-field error does not cancel, docs/accuracy.md).
    fn delta_depth(&self) -> f64 {
        let z = self.base_axis_depths();
        let h = z[1] - z[0];
        let end = z.windows(2).take_while(|w| ((w[1] - w[0]) - h).abs() < 1e-9 * h).count();
        z[end]
    }
}

/// The nested Hertz family of the study: 6 base cells per axis, ratio 70.5 and core 0.28
/// (theory §7.3): four uniform core cells h = a/3 = 0.07238 (Hertz's a = 0.21714 for the
/// whole force 0.3), then cells 8.4h and 70.5h (base nodes 0, a/3, 2a/3, a, 4a/3, 0.8972, 6).
/// The ratio is chosen so that a base node lies at Hertz's a: on every level the contact edge
/// crosses the symmetry planes at a node, the same relative position in its cell, with three
/// core cells inside it and one beyond.
const NESTED: Family = Family { base: [6, 6, 6], ratio: 70.5, core: 0.28 };

/// One level's measurements (theory §7).
#[derive(Clone, Copy, Debug)]
struct Level {
    dofs: usize,
    /// Newton's iterations.
    iterations: usize,
    /// The punch's displacement U (the finite box's, stiffer than the half-space).
    u: f64,
    /// The approach: U against the axis node at the family's depth d plus the half-space's
    /// displacement there, δ = U − u₃(0, 0, d) + u₃^{half-space}(0, 0, d).
    delta: f64,
    /// The force-weighted contact radius: Σλ_k r_k² / Σλ_k = (2/5) a² over the consistent
    /// nodal forces (T⁻ᵀλ̃ for recombined rows: Σλ_k r_k² = ∫p I_h(r²)).
    a: f64,
    /// The reported `peak_pressure` (the largest row pressure λ_j / ∫N_j, λ̃_j / ∫Ñ_j).
    p0: f64,
    /// p₀ of Hertz's profile fitted to the row pressures inside 0.7a.
    p0_fit: f64,
    /// The reported `contact_radius` (the farthest contact row's node).
    radius: f64,
    /// δ against every base axis node below the surface: (depth, δ) (for choosing the depth).
    deltas: [(f64, f64); 8],
}

/// Level `k` of `family` with `element` (and its `contact_rows`), solved by Newton to 1e-10;
/// δ measured against the axis node at `depth`.
fn nested_level(family: &Family, element: &str, rows: Option<&str>, k: usize, depth: f64) -> Level {
    let mut t = example("hertz.toml");
    let mut d = toml::Table::new();
    d.insert("type".into(), element.into());
    if let Some(r) = rows {
        d.insert("contact_rows".into(), r.into());
    }
    t.insert("discretisation".into(), toml::Value::Table(d));
    family.level(&mut t, k);
    let (l, _) = build(&t);
    let sol = saddle::solvers::Newton { tol: 1e-10, ..Default::default() }.solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged, "{element} {rows:?} level {k}: {:?}", sol.report.stop_reason);
    let mesh = l.element.mesh();
    let rows_k = l.lagrangian().data.rows;
    let r2 = |i: usize| {
        let x = mesh.nodes[rows_k.node[i]];
        x[0] * x[0] + x[1] * x[1]
    };
    let lambda: Vec<f64> = rows_k.combination.as_ref().map_or(sol.lambda.clone(), |c| c.nodal_multipliers(&sol.lambda));
    let force: f64 = lambda.iter().sum();
    let a = f64::sqrt(2.5 * (0..rows_k.n_rows()).map(|i| lambda[i] * r2(i)).sum::<f64>() / force);
    let contact = &l.view().contact_reports(&sol.extras, &sol.lambda)[0].report;
    // the row pressures the report's peak is the largest of, inside 0.7a (the rim ring carries
    // the discretised edge)
    let area = saddle::contact::zone::row_areas(mesh, rows_k);
    let pts: Vec<(f64, f64)> = (0..rows_k.n_rows())
        .filter(|&i| sol.lambda[i] > 0.0 && area[i] > 0.0 && r2(i) <= (0.7 * a).powi(2))
        .map(|i| (r2(i), (sol.lambda[i] / area[i]).powi(2)))
        .collect();
    let axis = (0..mesh.n_nodes())
        .find(|&n| {
            let x = mesh.nodes[n];
            x[0] == 0.0 && x[1] == 0.0 && (x[2] - depth).abs() < 1e-12
        })
        .expect("the axis node of the base grid is a node of every nested level");
    let (a_h, p0_h, _) = hertz(4.0 * force);
    let disp = l.element.nodal_vectors(&sol.u);
    let axis_delta = |d: f64| {
        let n = (0..mesh.n_nodes()).find(|&n| {
            let x = mesh.nodes[n];
            x[0] == 0.0 && x[1] == 0.0 && (x[2] - d).abs() < 1e-12
        });
        n.map_or(f64::NAN, |n| sol.extras[0] - disp[n][2] + half_space_axis_displacement(a_h, p0_h, d))
    };
    let mut deltas = [(f64::NAN, f64::NAN); 8];
    for (slot, d) in deltas.iter_mut().zip(family.base_axis_depths().into_iter().skip(1)) {
        *slot = (d, axis_delta(d));
    }
    Level {
        deltas,
        dofs: l.lagrangian().n_dofs(),
        iterations: sol.report.iterations,
        u: sol.extras[0],
        delta: sol.extras[0] - disp[axis][2] + half_space_axis_displacement(a_h, p0_h, depth),
        a,
        p0: contact.get("peak_pressure").unwrap(),
        p0_fit: hertz_profile_peak(&pts),
        radius: contact.contact_radius,
    }
}

/// Prints a level as a row of the study's table.
fn print_level(name: &str, k: usize, l: &Level, seconds: f64) {
    println!(
        "| {name} | {k} | {} | {} | {:.6e} | {:.6e} | {:.6} | {:.5} | {:.5} | {:.5} | {seconds:.0} s |",
        l.dofs, l.iterations, l.u, l.delta, l.a, l.p0, l.p0_fit, l.radius
    );
}

/// The family's base is where the study's design puts it: a base node at Hertz's a, the core
/// uniform around it (cells h = a/3 up to 4a/3) and δ measured at the core's end.
#[test]
fn the_nested_family_puts_a_base_node_at_the_contact_edge() {
    let a = hertz(0.3).0;
    let z = NESTED.base_axis_depths();
    for (i, x) in z.iter().take(5).enumerate() {
        assert!((x - i as f64 * a / 3.0).abs() < 1e-4 * a, "base node {i} at {x}, not {}", i as f64 * a / 3.0);
    }
    assert_eq!(z.len(), 7);
    assert_eq!(NESTED.delta_depth(), z[4]);
    // the previous family (base 5, ratio 45.517, core 0.3: h = a/2) measured δ at 1.5a, its core's end
    let previous = Family { base: [5, 5, 5], ratio: 45.517, core: 0.3 };
    assert!((previous.delta_depth() - 1.5 * a).abs() < 1e-4 * a);
}

/// Exploration of a nested Hertz family (not the study; for choosing one): the family from
/// `HERTZ_FAMILY` = "base,ratio,core" (default [`NESTED`]) and the levels from `HERTZ_LEVELS` =
/// "p2:1,2,3;p1:2,4" (P2 with the dual quadratic rows); one table row per level, each checked
/// within 5 % of Hertz in a, fitted p₀ and δ.
/// `HERTZ_FAMILY=5,45.517,0.3 HERTZ_LEVELS="p2:1,2" cargo test --release --test hertz -- --ignored --nocapture probe`
#[test]
#[ignore]
fn nested_family_probe() {
    let family = std::env::var("HERTZ_FAMILY").map_or(NESTED, |s| {
        let v: Vec<f64> = s.split(',').map(|x| x.trim().parse().unwrap()).collect();
        let n = v[0] as usize;
        Family { base: [n, n, n], ratio: v[1], core: v[2] }
    });
    let levels = std::env::var("HERTZ_LEVELS").unwrap_or_else(|_| "p2:1;p1:2".into());
    let depth = family.delta_depth();
    let (a_h, p0_h, delta_h) = hertz(0.3);
    println!("family {family:?}: base axis nodes {:?}; delta against depth {depth:.4}", family.base_axis_depths());
    println!("| element | k | dofs | Newton | U | delta | a | p0 (peak) | p0 (fit) | contact_radius | time |");
    for part in levels.split(';') {
        let (element, ks) = part.split_once(':').unwrap();
        let rows = (element == "p2").then_some("dual_quadratic");
        for k in ks.split(',').map(|k| k.trim().parse::<usize>().unwrap()) {
            let start = std::time::Instant::now();
            let l = nested_level(&family, element, rows, k, depth);
            print_level(element, k, &l, start.elapsed().as_secs_f64());
            println!("  {element} {k} delta at base axis depths: {:?}", l.deltas);
            for (q, x, exact) in [("a", l.a, a_h), ("p0 fit", l.p0_fit, p0_h), ("delta", l.delta, delta_h)] {
                assert!((x - exact).abs() < 0.05 * exact, "{element} level {k}: {q} = {x}, Hertz {exact}");
            }
        }
    }
}

/// Elastic Hertz on nested levels of P2 (dual quadratic rows, theory §10.1) and P1 (levels 2k,
/// the same nodes) of [`NESTED`], issue 30's first point: U, the force-weighted contact radius a
/// and the peak pressure p₀ (the reported `peak_pressure`, and Hertz's profile fitted to the
/// row pressures) each monotone, with Richardson's extrapolation from the finest three levels
/// (observed order, Roache's GCI as its uncertainty: `studies::report::convergence::extrapolate`);
/// a, p₀ and δ (U with the box's correction, see [`Level::delta`]) at Hertz's value within
/// that uncertainty, P1's and P2's limits within the two uncertainties, the finest level within
/// 1.5 % of Hertz. Every claim is checked; those measured not to hold (`NOT_HOLDING`,
/// docs/accuracy.md "Hertz on nested levels") are printed, the others asserted.
/// `cargo test --release --test hertz -- --ignored --nocapture nested_levels` (23 min on the
/// 2-core machine with two threads; P1's k = 10, 640 800 dofs, 12 min of it).
#[test]
#[ignore]
fn nested_levels_converge_to_hertz() {
    use saddle::studies::report::convergence::extrapolate;
    const P2_LEVELS: [usize; 4] = [1, 2, 3, 4];
    const P1_LEVELS: [usize; 5] = [2, 4, 6, 8, 10];
    // measured not to hold (docs/accuracy.md, "Hertz on nested levels"): P1's δ at the core's
    // end is not monotone from its coarsest level (k = 2 lies below k = 4; monotone from k = 4)
    const NOT_HOLDING: [&str; 1] = ["P1 delta monotone"];
    let (a_h, p0_h, delta_h) = hertz(0.3);
    let depth = NESTED.delta_depth();
    println!(
        "{NESTED:?}; Hertz: a {a_h:.5}, p0 {p0_h:.5}, delta {delta_h:.6e}; delta against the axis node at depth {depth:.4}"
    );
    let families: [(&str, &str, Option<&str>, &[usize]); 2] =
        [("P2 dual quadratic", "p2", Some("dual_quadratic"), &P2_LEVELS), ("P1", "p1", None, &P1_LEVELS)];
    let mut failed: Vec<String> = Vec::new();
    let mut check = |ok: bool, claim: String| {
        let known = NOT_HOLDING.iter().any(|k| claim.starts_with(k));
        println!(
            "{} {claim}",
            if ok {
                "holds:"
            } else if known {
                "does not hold (known):"
            } else {
                "FAILS:"
            }
        );
        if !ok && !known {
            failed.push(claim);
        }
    };
    type Quantity = (&'static str, Option<f64>, fn(&Level) -> f64);
    let quantities: [Quantity; 5] = [
        ("U", None, |l| l.u),
        ("delta", Some(delta_h), |l| l.delta),
        ("a", Some(a_h), |l| l.a),
        ("p0", Some(p0_h), |l| l.p0),
        ("p0 fit", Some(p0_h), |l| l.p0_fit),
    ];
    let mut limits = Vec::new();
    println!("| element | k | dofs | Newton | U | delta | a | p0 (peak) | p0 (fit) | contact_radius | time |");
    for (name, element, rows, ks) in families {
        let levels: Vec<Level> = ks
            .iter()
            .map(|&k| {
                let start = std::time::Instant::now();
                let l = nested_level(&NESTED, element, rows, k, depth);
                print_level(name, k, &l, start.elapsed().as_secs_f64());
                println!("  {name} {k} delta at base axis depths: {:?}", l.deltas);
                l
            })
            .collect();
        // h ∝ 1/(cells per base cell) in units of P2's node spacing: P1's level 2k has P2's level k nodes
        let h: Vec<f64> =
            ks.iter().map(|&k| if element == "p2" { 1.0 / (2 * k) as f64 } else { 1.0 / k as f64 }).collect();
        let mut limit = Vec::new();
        for (q, exact, get) in quantities {
            let v: Vec<f64> = levels.iter().map(get).collect();
            if let Some(exact) = exact {
                let x = v[v.len() - 1];
                check(
                    (x - exact).abs() < 0.015 * exact,
                    format!("{name} {q} = {x} on the finest level within 1.5 % of Hertz {exact}"),
                );
            }
            let monotone = v.windows(3).all(|w| (w[1] - w[0]) * (w[2] - w[1]) > 0.0);
            check(monotone, format!("{name} {q} monotone: {v:?}"));
            match extrapolate(&h, &v) {
                Some(r) => {
                    println!(
                        "{name} {q}: order {:.2}, limit {:.6e} ± {:.2e}{}",
                        r.order,
                        r.value,
                        r.uncertainty,
                        exact.map_or(String::new(), |e| format!(
                            "; Hertz {e:.6e} ({:+.2} % of the limit)",
                            100.0 * (e - r.value) / r.value
                        ))
                    );
                    if let Some(exact) = exact {
                        check(
                            (exact - r.value).abs() <= r.uncertainty,
                            format!("{name} {q}: Hertz {exact} within the limit {} ± {:e}", r.value, r.uncertainty),
                        );
                    }
                    limit.push(Some((r.value, r.uncertainty)));
                }
                None => {
                    check(false, format!("{name} {q} extrapolates (a positive order fits the finest three)"));
                    limit.push(None);
                }
            }
        }
        limits.push(limit);
    }
    // P1 and P2 extrapolate to the same limit within the two uncertainties
    for (i, (q, _, _)) in quantities.iter().enumerate() {
        let (x, y) = (limits[0][i], limits[1][i]);
        let agree = matches!((x, y), (Some((vx, ux)), Some((vy, uy))) if (vx - vy).abs() <= ux + uy);
        check(agree, format!("P2 and P1 limits of {q} agree: {x:?}, {y:?}"));
    }
    assert!(failed.is_empty(), "{} claims fail: {failed:#?}", failed.len());
}
