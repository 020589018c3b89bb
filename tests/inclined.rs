//! Inclined supports (issue 28, theory §14.4): a block on three supports, loaded by a traction
//! and a pressure, solved axis-aligned and with its mesh, supports and loads rotated by 30°:
//! the rotated answer is the axis-aligned one rotated (displacements, stresses, reactions), on
//! every solver, P1 and P2, elastic and plastic with hardening.

use saddle::core::fem::supports::Reaction;
use saddle::core::problem::tensor::to_matrix;
use saddle::core::{Silent, Solver, Sym};
use saddle::io::scene::Scene;
use std::path::Path;

/// A rotation, rows.
type Rotation = [[f64; 3]; 3];

/// The rotation by `angle` about the axis `a` (Rodrigues).
fn rotation(a: [f64; 3], angle: f64) -> Rotation {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    let k = a.map(|x| x / n);
    let (s, c) = angle.sin_cos();
    let cross = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
    std::array::from_fn(|i| {
        std::array::from_fn(|j| c * (i == j) as u8 as f64 + s * cross[i][j] + (1.0 - c) * k[i] * k[j])
    })
}

/// r x.
fn turn(r: &Rotation, x: [f64; 3]) -> [f64; 3] {
    r.map(|row| row[0] * x[0] + row[1] * x[1] + row[2] * x[2])
}

/// The nine entries of r σ rᵀ (rows), σ a Mandel vector.
fn turn_stress(r: &Rotation, s: &Sym) -> Vec<f64> {
    let m = to_matrix(s);
    let mut out = Vec::with_capacity(9);
    for i in 0..3 {
        for j in 0..3 {
            out.push(
                (0..3).flat_map(|k| (0..3).map(move |l| (k, l))).map(|(k, l)| r[i][k] * m[(k, l)] * r[j][l]).sum(),
            );
        }
    }
    out
}

/// What a solve gives to compare: nodal displacements, stresses per point, reactions.
struct Answer {
    u: Vec<[f64; 3]>,
    sigma: Vec<Sym>,
    reactions: Vec<Reaction>,
}

/// The block [0, 1] × [0, 1] × [0, 2] of `element` (2 × 2 × 4 cells) held along `r e_x` on
/// xmin, `r e_y` on ymin and `r e_z` on zmin, under the traction r t on zmax and the pressure
/// 0.2 on ymax; E = 100, ν = 0.3, von Mises k₀ = 1, h = 5 when `plastic`. Its mesh is the box
/// rotated by `r` (node by node), and the scene is solved by `solver`.
fn block(r: &Rotation, element: &str, plastic: bool, solver: &str) -> Answer {
    let v = |x: [f64; 3]| {
        let y = turn(r, x);
        format!("[{:.17e}, {:.17e}, {:.17e}]", y[0], y[1], y[2])
    };
    let yield_table = if plastic { "[yield]\ntype = \"von_mises\"\nk0 = 1.0\nh = 5.0\n" } else { "" };
    let text = format!(
        r#"[mesh]
type = "box"
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 2.0]
cells = [2, 2, 4]
[discretisation]
type = "{element}"
[material]
E = 100.0
nu = 0.3
{yield_table}
[[dirichlet]]
name = "left"
on = {{ group = "xmin" }}
normal = {}
[[dirichlet]]
name = "front"
on = {{ group = "ymin" }}
normal = {}
[[dirichlet]]
name = "bottom"
on = {{ group = "zmin" }}
normal = {}
[[load]]
type = "traction"
on = {{ group = "zmax" }}
t = {}
[[load]]
type = "pressure"
on = {{ group = "ymax" }}
p = 0.2
"#,
        v([1.0, 0.0, 0.0]),
        v([0.0, 1.0, 0.0]),
        v([0.0, 0.0, -1.0]),
        v([0.3, 0.1, 1.5]),
    );
    let scene = Scene::from_toml(&text, Path::new("block.toml")).unwrap();
    let mut mesh = scene.build_mesh().unwrap();
    for x in &mut mesh.nodes {
        *x = turn(r, *x);
    }
    let (problem, _) = scene.assemble(mesh).unwrap();
    let solver: Box<dyn Solver> = toml::from_str(solver).unwrap();
    let sol = solver.solve(&problem.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged, "{}: {:?} {:?}", solver.name(), sol.report.stop_reason, sol.report.kkt);
    let view = problem.view();
    if plastic {
        assert!(sol.stress.n_plastic() > 0, "the plastic block yields somewhere");
    }
    Answer { u: view.displacements(&sol.u), reactions: view.reactions(&sol.stress.sigma), sigma: sol.stress.sigma }
}

/// max |a − b| over the entries, and max |b|.
fn gap(a: impl Iterator<Item = f64>, b: impl Iterator<Item = f64>) -> (f64, f64) {
    a.zip(b).fold((0.0, 0.0), |(e, s), (x, y)| (f64::max(e, (x - y).abs()), f64::max(s, y.abs())))
}

#[test]
fn a_support_inclined_at_30_degrees_gives_the_axis_aligned_answer_rotated_on_every_solver() {
    let solvers = [
        "type = \"newton\"\ntol = 1e-12",
        "type = \"uzawa\"\ntol = 1e-11",
        "type = \"penalty\"\ntol = 1e-10",
        "type = \"socp\"\ntol = 1e-11",
    ];
    // 30° about y (the ymin support stays on an axis: a frame next to a plain roller) and about
    // a general axis (every support inclined)
    let rotations = [[0.0, 1.0, 0.0], [1.0, 2.0, 3.0]].map(|a| rotation(a, 30f64.to_radians()));
    let identity = rotation([1.0, 0.0, 0.0], 0.0);
    for element in ["p1", "p2"] {
        for plastic in [false, true] {
            for solver in solvers {
                let reference = block(&identity, element, plastic, solver);
                for r in &rotations {
                    let rotated = block(r, element, plastic, solver);
                    let ru = reference.u.iter().flat_map(|u| turn(r, *u));
                    let (eu, su) = gap(rotated.u.iter().flatten().copied(), ru);
                    let rs = reference.sigma.iter().flat_map(|s| turn_stress(r, s));
                    let (es, ss) = gap(rotated.sigma.iter().flat_map(|s| turn_stress(&identity, s)), rs);
                    let rr = reference.reactions.iter().flat_map(|x| [turn(r, x.force), turn(r, x.moment)].concat());
                    let (er, sr) = gap(rotated.reactions.iter().flat_map(|x| [x.force, x.moment].concat()), rr);
                    println!(
                        "{element} plastic={plastic} {}: |Δu| {:.1e}, |Δσ| {:.1e}, |Δr| {:.1e} (relative)",
                        solver.lines().next().unwrap(),
                        eu / su,
                        es / ss,
                        er / sr
                    );
                    assert_eq!(rotated.reactions.len(), 3);
                    // the reactions balance the loads: the traction on the unit face zmax and
                    // the pressure 0.2 on the face ymax of area 2, F = t − (0, 0.4, 0), turned
                    let load = turn(r, [0.3, 0.1 - 0.4, 1.5]);
                    let total: Vec<f64> =
                        (0..3).map(|c| rotated.reactions.iter().map(|x| x.force[c]).sum::<f64>() + load[c]).collect();
                    // measured ≤ 2e-11 (|F| = 1.6) over the solvers: their equilibrium residuals
                    assert!(
                        total.iter().all(|x| x.abs() <= 1e-9),
                        "{element} {solver}: Σ reactions + loads = {total:?}"
                    );
                    // measured ≤ 3e-14 relative (P2 elastic), ≤ 1e-14 the others: the frames are
                    // exact, the solves agree to round-off; 1e-9 is the issue's bound
                    assert!(
                        eu <= 1e-9 * su && es <= 1e-9 * ss && er <= 1e-9 * sr,
                        "{element} {solver}: {eu} {es} {er}"
                    );
                }
            }
        }
    }
}

/// The conformance kit's bar (theory §14.4): where the grip u₁ = 0.1 meets the support inclined
/// along n = (½, 0, 1), the lifting meets both, u₁ = 0.1 and n·u = 0; every node of the inclined
/// face has n·u = 0; its reaction is along n and balances the grip, the rollers and the pressure.
#[test]
fn a_grip_meeting_an_inclined_support_holds_both() {
    let problem = saddle::solvers::conformance::supported_bar(None).problem().unwrap();
    let sol =
        saddle::solvers::Newton { tol: 1e-12, ..Default::default() }.solve(&problem.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged);
    let view = problem.view();
    let u = view.displacements(&sol.u);
    let n = [0.5, 0.0, 1.0];
    let (mut edge, mut face) = (0, 0);
    for (x, d) in problem.element.mesh().nodes.iter().zip(&u) {
        if x[2] == 0.0 {
            // round-off of the frame and the lifting: measured ≤ 1.4e-17 (both checks)
            assert!((n[0] * d[0] + n[2] * d[2]).abs() <= 1e-15, "{x:?}: {d:?}");
            face += 1;
            if x[0] == 2.0 {
                assert!((d[0] - 0.1).abs() <= 1e-15, "{x:?}: {d:?}");
                edge += 1;
            }
        }
    }
    assert_eq!((edge, face), (3, 15));
    let reactions = view.reactions(&sol.stress.sigma);
    let inclined = &reactions[2];
    // along n: F × n = 0 (measured 0: each node's part is α n exactly)
    let along =
        [inclined.force[1] * n[2], inclined.force[2] * n[0] - inclined.force[0] * n[2], -inclined.force[1] * n[0]];
    assert!(along.iter().all(|x| x.abs() <= 1e-12 * inclined.force[2].abs()), "{inclined:?}");
    // Σ reactions = −(the pressure 0.5 on the face y = 1 of area 2) = (0, 1, 0); measured ≤ 6e-15
    for (c, want) in [0.0, 1.0, 0.0].iter().enumerate() {
        let sum: f64 = reactions.iter().map(|r| r.force[c]).sum();
        assert!((sum - want).abs() <= 1e-10, "Σ F_{c} = {sum}");
    }
}
