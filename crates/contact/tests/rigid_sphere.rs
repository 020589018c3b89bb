//! The rigid sphere (theory §8) on the coarse default scene and on a side face: the kit, rows and
//! gap in closed form, zone selection (rollers, non-planar zones), parameter errors, a node
//! inside the sphere, the report and its rim warning, broken copies, TOML.

mod common;

use common::*;
use saddle_contact::{RigidSphere, check_all, zone};
use saddle_core::{
    AdmissibleDisplacements, Component, ConstraintRows, ContactReport, Dirichlet, DofMap, ParameterError, Region,
    SceneError, TetMesh,
};
use serde::{Deserialize, Serialize};

/// The closed-form sphere: centre (−0.5, −0.75, −3), R = 3, direction (3, 0, 4)/5 = (0.6, 0, 0.8).
/// For the node (0.25, 0.25, 0): x − c = (0.75, 1, 3) = 3.25·(3, 4, 12)/13, so n = (3, 4, 12)/13,
/// |x − c| − R = 0.25 and n·d = (1.8 + 9.6)/13 = 11.4/13.
const CENTER: [f64; 3] = [-0.5, -0.75, -3.0];

/// n·d about the centre moved by V along d, for a node with |x − c|² = r2 and (x − c)·d = rd:
/// (rd − V)/|x − c − V d|.
fn nd_moved(r2: f64, rd: f64, v: f64) -> f64 {
    (rd - v) / (r2 - 2.0 * v * rd + v * v).sqrt()
}
const DIRECTION: [f64; 3] = [3.0, 0.0, 4.0];

fn pushed() -> RigidSphere {
    RigidSphere::pushed(CENTER, 3.0, DIRECTION, 0.3, disc(0.5))
}

fn moved(v: f64) -> RigidSphere {
    RigidSphere::moved(CENTER, 3.0, DIRECTION, v, disc(0.5))
}

/// The node at (x₁, x₂, x₃).
fn node_xyz(m: &TetMesh, p: [f64; 3]) -> usize {
    (0..m.n_nodes()).find(|&n| (0..3).all(|c| (m.nodes[n][c] - p[c]).abs() < 1e-12)).unwrap()
}

fn row_of(rows: &ConstraintRows, n: usize) -> usize {
    rows.node.iter().position(|&x| x == n).unwrap()
}

/// Clamped on the top face only.
fn top_clamped(m: &TetMesh) -> DofMap {
    DofMap::new(m, &[Dirichlet::clamped(Region::Group("zmax".into()))]).unwrap()
}

/// A sphere to the right of the face x₁ = 1, moving left.
fn side(zone: Region) -> RigidSphere {
    RigidSphere::pushed([3.0, 0.0, 0.5], 2.0, [-1.0, 0.0, 0.0], 0.3, zone)
}

#[test]
fn the_kit_passes_pushed_and_moved_on_the_bottom_a_side_and_rollers() {
    let m = mesh();
    let d = dofs(&m);
    let top = top_clamped(&m);
    let rollers = DofMap::new(
        &m,
        &[
            Dirichlet::clamped(Region::Group("zmax".into())),
            Dirichlet::roller(Region::Group("zmin".into()), Component::Z),
        ],
    )
    .unwrap();
    let cases: Vec<(RigidSphere, &DofMap)> = vec![
        (RigidSphere::pushed([0.0, 0.0, -5.0], 5.0, [0.0, 0.0, 1.0], 0.3, disc(0.5)), &d),
        (RigidSphere::moved([0.0, 0.0, -5.0], 5.0, [0.0, 0.0, 1.0], 0.004, disc(0.5)), &d),
        (pushed(), &d),
        (moved(0.01), &d),
        (RigidSphere::pushed([0.1, -0.2, -3.0], 3.0, [0.3, -0.2, 1.0], 1.5, Region::Group("zmin".into())), &d),
        (side(Region::Group("xmax".into())), &top),
        (RigidSphere::moved([3.0, 0.1, 0.5], 2.0, [-1.0, 0.0, 0.2], 0.02, Region::Group("xmax".into())), &top),
        // u₃ fixed on the bottom: rows on u₁, u₂ only
        (RigidSphere::pushed([0.1, 0.2, -4.0], 4.0, [0.0, 0.0, 1.0], 0.3, disc(0.5)), &rollers),
        // the whole boundary but the top: a curved, non-planar zone
        (
            RigidSphere::pushed(
                [0.0, 0.0, -5.0],
                5.0,
                [0.0, 0.0, 1.0],
                0.3,
                Region::Not(Box::new(Region::Group("zmax".into()))),
            ),
            &top,
        ),
    ];
    for (i, (k, dofs)) in cases.iter().enumerate() {
        for (seed, scale) in [(1, 0.01), (2, 0.003), (3, 0.05)] {
            check_all(k, &m, dofs, seed, scale).unwrap_or_else(|e| panic!("case {i} ({k:?}), seed {seed}: {e}"));
        }
    }
}

#[test]
fn rows_in_closed_form() {
    let m = mesh();
    let d = dofs(&m);
    let n = node_xyz(&m, [0.25, 0.25, 0.0]);
    let dofs_of_n: Vec<usize> = (0..3).map(|c| d.free(n, c).unwrap()).collect();
    let normal = [3.0 / 13.0, 4.0 / 13.0, 12.0 / 13.0];
    let nd = 11.4 / 13.0;
    let close = |a: f64, b: f64| (a - b).abs() < 1e-15;

    let k = pushed();
    assert_eq!(k.unit_direction(), Some([0.6, 0.0, 0.8]));
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    assert_eq!(rows.node, bottom_nodes_in_disc(&m, 0.5));
    assert!(rows.warnings.is_empty(), "{:?}", rows.warnings);
    let r = row_of(&rows, n);
    let (cols, vals) = rows.row(r);
    assert_eq!(cols, &dofs_of_n[..]);
    assert!(vals.iter().zip(normal).all(|(a, b)| close(*a, b)), "{vals:?}");
    assert_eq!(rows.extra_row(r).len(), 1);
    assert!(close(rows.extra_row(r)[0], -nd), "{:?}", rows.extra_row(r));
    assert!(close(rows.offset[r], 0.25), "{}", rows.offset[r]);
    assert_eq!(k.extra_names(), vec!["V"]);
    assert_eq!(k.load(), vec![0.3]);

    // V = 0.01 prescribed: no extra; linearised about the moved centre c + V d, where
    // x − c − V d = (0.75 − 0.006, 1, 3 − 0.008)
    let k = moved(0.01);
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    let r = row_of(&rows, n);
    assert_eq!(rows.n_extras, 0);
    let y = [0.744, 1.0, 2.992];
    let dist = (0.744f64 * 0.744 + 1.0 + 2.992 * 2.992).sqrt();
    assert!(rows.row(r).1.iter().zip(y).all(|(a, b)| close(*a, b / dist)), "{:?}", rows.row(r).1);
    assert!(close(rows.offset[r], dist - 3.0), "{}", rows.offset[r]);
    // to first order in V it is the undisplaced sphere's 0.25 − V n·d (theory §8): the difference
    // is V² (1 − (n·d)²)/(2|x − c|) ≈ 3.6e-6
    let second_order = rows.offset[r] - (0.25 - 0.01 * nd);
    assert!(second_order > 3e-6 && second_order < 4e-6, "{second_order}");
    assert!(k.extra_names().is_empty() && k.load().is_empty());

    // the exact gap at u = (0.01, −0.02, 0.03) on that node, V = 0.05:
    // x + u − c − V d = (0.75 + 0.01 − 0.03, 1 − 0.02, 3 + 0.03 − 0.04)
    let k = pushed();
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    let r = row_of(&rows, n);
    let mut u = vec![0.0; d.n_free];
    for (j, v) in dofs_of_n.iter().zip([0.01, -0.02, 0.03]) {
        u[*j] = v;
    }
    let mut g = vec![0.0; rows.n_rows()];
    k.gap(&m, &d, &rows, &u, &[0.05], &mut g);
    let exact = (0.73f64 * 0.73 + 0.98 * 0.98 + 2.99 * 2.99).sqrt() - 3.0;
    assert!((g[r] - exact).abs() < 1e-14, "{} vs {exact}", g[r]);
    // the row: 0.25 + n·u − 0.05 n·d, first-order close to the exact gap (and below it: |y| ≥ n·y)
    let mut gr = vec![0.0; rows.n_rows()];
    rows.gap(&u, &[0.05], &mut gr);
    let linear = 0.25 + (3.0 * 0.01 - 4.0 * 0.02 + 12.0 * 0.03) / 13.0 - 0.05 * nd;
    assert!(close(gr[r], linear), "{} vs {linear}", gr[r]);
    assert!(gr[r] <= g[r] && g[r] - gr[r] < 1e-3, "{} {}", gr[r], g[r]);
}

#[test]
fn fixed_components_are_dropped_from_rows_and_fully_fixed_nodes_from_the_zone() {
    let m = mesh();
    // u₃ fixed on the bottom (a roller): the punch has no contact node left, the sphere acts on u₁, u₂
    let rollers = DofMap::new(
        &m,
        &[
            Dirichlet::clamped(Region::Group("zmax".into())),
            Dirichlet::roller(Region::Group("zmin".into()), Component::Z),
        ],
    )
    .unwrap();
    assert!(zone::candidate_nodes(&disc(0.5), &m, &rollers, "obstacle").is_err());
    let rows = pushed().discretise(&m, &rollers, "obstacle").unwrap();
    assert_eq!(rows.n_rows(), 13);
    assert!(rows.warnings.is_empty(), "{:?}", rows.warnings);
    let n = node_xyz(&m, [0.25, 0.25, 0.0]);
    let (cols, vals) = rows.row(row_of(&rows, n));
    assert_eq!(cols, &[rollers.free(n, 0).unwrap(), rollers.free(n, 1).unwrap()][..]);
    assert!((vals[0] - 3.0 / 13.0).abs() < 1e-15 && (vals[1] - 4.0 / 13.0).abs() < 1e-15, "{vals:?}");
    // the clamped rim of the bottom face: 56 of its 81 nodes have every dof fixed
    let d = dofs(&m);
    let whole = RigidSphere::pushed([0.0, 0.0, -5.0], 5.0, [0.0, 0.0, 1.0], 0.3, Region::Group("zmin".into()));
    let rows = whole.discretise(&m, &d, "obstacle").unwrap();
    assert_eq!(rows.n_rows(), 25);
    assert_eq!(rows.warnings.len(), 1, "{:?}", rows.warnings);
    let w = &rows.warnings[0];
    assert!(w.starts_with("obstacle.zone: 56 of its 81 nodes") && w.contains("all of u₁, u₂, u₃ fixed"), "{w}");
    assert!(w.contains("25 contact nodes remain"), "{w}");
    // a zone of clamped nodes only is an error
    let corner =
        Region::All(vec![Region::Group("zmin".into()), Region::Box { min: [0.8, 0.8, -1.0], max: [1.0, 1.0, 1.0] }]);
    let k = RigidSphere::pushed([0.0, 0.0, -5.0], 5.0, [0.0, 0.0, 1.0], 0.3, corner);
    match k.discretise(&m, &d, "obstacle").unwrap_err() {
        SceneError::Region { field, message } => {
            assert_eq!(field, "obstacle.zone");
            assert!(
                message.contains("all 1 of its 1 nodes") && message.contains("all of u₁, u₂, u₃ fixed"),
                "{message}"
            );
        }
        other => panic!("{other}"),
    }
}

#[test]
fn a_curved_zone_gets_no_planarity_warning() {
    let m = mesh();
    let top = top_clamped(&m);
    let zone = Region::Not(Box::new(Region::Group("zmax".into())));
    let k = RigidSphere::pushed([0.0, 0.0, -5.0], 5.0, [0.0, 0.0, 1.0], 0.3, zone.clone());
    let rows = k.discretise(&m, &top, "obstacle").unwrap();
    assert!(rows.warnings.is_empty(), "{:?}", rows.warnings);
    assert_eq!(rows.node, zone.nodes(&m));
    // the punches' selection warns about the same zone
    let punch = zone::candidate_nodes(&zone, &m, &top, "obstacle").unwrap();
    assert_eq!(punch.warnings.len(), 1, "{:?}", punch.warnings);
    assert!(punch.warnings[0].contains("span x₃"), "{:?}", punch.warnings);
}

#[test]
fn parameters_name_the_field_and_the_value() {
    let err = |k: RigidSphere| k.validate("obstacle").unwrap_err();
    let with = |f: Option<f64>, v: Option<f64>| RigidSphere { F: f, V: v, ..pushed() };
    for (f, shown) in [(-0.3, "-0.3"), (f64::NAN, "NaN")] {
        let e = err(with(Some(f), None));
        assert_eq!((e.field.as_str(), e.value.as_str()), ("obstacle.F", shown));
    }
    // F = 0: no load, V undetermined (theory §11.3)
    with(Some(0.0), None).validate("obstacle").unwrap();
    let e = err(with(None, Some(f64::INFINITY)));
    assert_eq!((e.field.as_str(), e.value.as_str()), ("obstacle.V", "inf"));
    // a negative V is a legal position (the sphere pulled back)
    with(None, Some(-0.01)).validate("obstacle").unwrap();
    // both, neither
    let e = err(with(Some(0.3), Some(0.01)));
    assert_eq!((e.field.as_str(), e.value.as_str()), ("obstacle.F", "0.3"));
    assert!(e.to_string().contains("obstacle.V = 0.01") && e.to_string().contains("exactly one"), "{e}");
    let e = err(with(None, None));
    assert_eq!((e.field.as_str(), e.value.as_str()), ("obstacle.F", "missing"));
    assert!(e.to_string().contains("obstacle.V") && e.to_string().contains("exactly one"), "{e}");
    // the direction: zero, non-finite
    for (dir, shown) in
        [([0.0; 3], "[0, 0, 0]"), ([f64::NAN, 0.0, 1.0], "[NaN, 0, 1]"), ([1.0, f64::INFINITY, 0.0], "[1, inf, 0]")]
    {
        let e = err(RigidSphere { direction: dir, ..pushed() });
        assert_eq!((e.field.as_str(), e.value.as_str()), ("obstacle.direction", shown));
        assert!(e.requirement.contains("nonzero"), "{e}");
    }
    // huge but finite directions are normalised without overflow
    let k = RigidSphere { direction: [3e300, 0.0, 4e300], ..pushed() };
    k.validate("obstacle").unwrap();
    assert_eq!(k.unit_direction(), Some([0.6, 0.0, 0.8]));
    let e = err(RigidSphere { R: 0.0, ..pushed() });
    assert_eq!((e.field.as_str(), e.value.as_str()), ("obstacle.R", "0"));
    let e = err(RigidSphere { center: [0.0, f64::NAN, 0.0], ..pushed() });
    assert_eq!(e.field, "obstacle.center[1]");
}

#[test]
fn a_zone_node_inside_the_sphere_is_an_error() {
    let m = mesh();
    let d = dofs(&m);
    // centre 1.9 below the origin, R = 2: the bottom nodes within √(4 − 3.61) ≈ 0.62 of the
    // origin are inside, the deepest is the origin
    let k = RigidSphere::pushed([0.0, 0.0, -1.9], 2.0, [0.0, 0.0, 1.0], 0.3, disc(0.5));
    match k.discretise(&m, &d, "obstacle").unwrap_err() {
        SceneError::Parameter(ParameterError { field, value, requirement }) => {
            assert_eq!((field.as_str(), value.as_str()), ("obstacle.center", "[0, 0, -1.9]"));
            let origin = node_at(&m, 0.0, 0.0);
            assert!(requirement.contains(&format!("node {origin} at (0, 0, 0)")), "{requirement}");
            assert!(requirement.contains("13 node(s) of obstacle.zone inside the sphere"), "{requirement}");
            assert!(requirement.contains("obstacle.R = 2"), "{requirement}");
        }
        other => panic!("{other}"),
    }
    // touching at the origin is fine: the first point of contact
    let k = RigidSphere::pushed([0.0, 0.0, -2.0], 2.0, [0.0, 0.0, 1.0], 0.3, disc(0.5));
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    assert_eq!(rows.offset[row_of(&rows, node_at(&m, 0.0, 0.0))], 0.0);
}

#[test]
fn report_by_hand() {
    let m = mesh();
    let d = dofs(&m);
    for k in [pushed(), moved(0.004)] {
        let rows = k.discretise(&m, &d, "obstacle").unwrap();
        let mut lambda = vec![0.0; rows.n_rows()];
        // x − c = (0.75, 1, 3) at (0.25, 0.25): |x − c|² = 10.5625, (x − c)·d = 2.85
        lambda[row_of(&rows, node_xyz(&m, [0.25, 0.25, 0.0]))] = 0.2;
        // x − c = (0.5, 0.75, 3) at the origin: |x − c|² = 9.8125, (x − c)·d = 2.7
        lambda[row_of(&rows, node_at(&m, 0.0, 0.0))] = 0.1;
        // x − c = (0, 0.75, 3) at (−0.5, 0): |x − c|² = 9.5625, (x − c)·d = 2.4
        lambda[row_of(&rows, node_at(&m, -0.5, 0.0))] = 1e-12; // below the contact-set threshold
        let extras: &[f64] = if k.V.is_some() { &[] } else { &[0.0123] };
        let r = k.report(&m, &rows, extras, &lambda);
        assert_eq!(r.get("V"), Some(if k.V.is_some() { 0.004 } else { 0.0123 }));
        // Σλ n·d with the rows' normals: about c, or c + V d when V is prescribed
        let v = k.V.unwrap_or(0.0);
        let force =
            0.2 * nd_moved(10.5625, 2.85, v) + 0.1 * nd_moved(9.8125, 2.7, v) + 1e-12 * nd_moved(9.5625, 2.4, v);
        if v == 0.0 {
            assert!((nd_moved(10.5625, 2.85, 0.0) - 11.4 / 13.0).abs() < 1e-15);
        }
        assert!((r.get("force").unwrap() - force).abs() < 1e-15, "{:?} vs {force}", r.get("force"));
        // the force is not Σλ: the normals are tilted against d
        assert!((r.get("force").unwrap() - 0.3).abs() > 1e-2);
        assert_eq!(r.contact_nodes, 2);
        // distance² from the axis c + t d: |x − c|² − ((x − c)·d)² = 2.44 and 2.5225
        assert!((r.contact_radius - 2.5225f64.sqrt()).abs() < 1e-14, "{}", r.contact_radius);
        // (0.25, 0.25) is next to (0.5, 0.25), outside the disc: contact on the rim
        assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
        assert!(
            r.warnings[0].contains("at 1 node(s)") && r.warnings[0].contains("(0.25, 0.25, 0)"),
            "{:?}",
            r.warnings
        );
        // balanced multipliers: Hᵀλ = −F is Σλ n·d = F, the reported force
        if k.V.is_none() {
            let (mut fu, mut fv) = (vec![0.0; d.n_free], vec![0.0]);
            rows.add_transpose(&lambda, &mut fu, &mut fv);
            assert!((fv[0] + force).abs() < 1e-15);
        }
    }
}

#[test]
fn the_rim_warning_follows_the_face_the_sphere_touches() {
    let m = mesh();
    // the bottom: contact at (0.5, 0, 0), next to (0.75, 0, 0) outside the disc
    let d = dofs(&m);
    let k = pushed();
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    let mut lambda = vec![0.0; rows.n_rows()];
    lambda[row_of(&rows, node_at(&m, 0.0, 0.0))] = 0.3;
    assert!(k.report(&m, &rows, &[0.0], &lambda).warnings.is_empty());
    lambda[row_of(&rows, node_at(&m, 0.5, 0.0))] = 0.01;
    let r = k.report(&m, &rows, &[0.0], &lambda);
    assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
    assert!(r.warnings[0].contains("rim of obstacle.zone at 1 node(s)") && r.warnings[0].contains("(0.5, 0, 0)"));
    // a patch of the side face x₁ = 1: y ∈ {−0.25, 0, 0.25}, z ∈ {0.25, 0.5, 0.75}
    let top = top_clamped(&m);
    let patch =
        Region::All(vec![Region::Group("xmax".into()), Region::Box { min: [0.9, -0.3, 0.2], max: [1.1, 0.3, 0.8] }]);
    let k = side(patch);
    let rows = k.discretise(&m, &top, "obstacle").unwrap();
    assert_eq!(rows.n_rows(), 9);
    let mut lambda = vec![0.0; 9];
    lambda[row_of(&rows, node_xyz(&m, [1.0, 0.0, 0.5]))] = 0.3;
    let r = k.report(&m, &rows, &[0.0], &lambda);
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    assert_eq!((r.contact_nodes, r.contact_radius), (1, 0.0));
    let edge = row_of(&rows, node_xyz(&m, [1.0, 0.25, 0.5]));
    lambda[edge] = 0.01;
    let r = k.report(&m, &rows, &[0.0], &lambda);
    assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
    assert!(r.warnings[0].contains("(1, 0.25, 0.5)"), "{:?}", r.warnings);
    // radius about the axis (3, 0, 0.5) + t(−1, 0, 0): 0.25
    assert!((r.contact_radius - 0.25).abs() < 1e-15);
    // the punch's rim (facets with n₃ < 0) never sees a side face
    let contact = saddle_core::contact_set(&lambda);
    assert!(zone::rim_rows(&m, &rows, &contact).is_empty());
    assert_eq!(zone::rim_rows_facing(&m, &rows, &contact, |n, _| n[0] > 0.0), vec![edge]);
}

/// What is wrong with a [`BrokenSphere`].
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
enum Flaw {
    /// The rows use −n_i: G = −n_i, H = +n_i·d.
    NormalSign,
    /// The rows drop the x₁ component of n_i.
    DropsX1,
    /// The report gives Σλ as the force.
    ForceIsSumLambda,
    /// The report gives Σλ_i² as the force (not linear in λ).
    ForceQuadratic,
}

/// The rigid sphere with a deliberate flaw.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct BrokenSphere {
    sphere: RigidSphere,
    flaw: Flaw,
}

#[typetag::serde(name = "test_broken_sphere")]
impl AdmissibleDisplacements for BrokenSphere {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        self.sphere.validate(path)
    }
    fn extra_names(&self) -> Vec<String> {
        self.sphere.extra_names()
    }
    fn load(&self) -> Vec<f64> {
        self.sphere.load()
    }
    fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError> {
        let mut rows = self.sphere.discretise(mesh, dofs, path)?;
        match self.flaw {
            Flaw::NormalSign => {
                rows.val.iter_mut().for_each(|v| *v = -*v);
                rows.extra.iter_mut().for_each(|h| *h = -*h);
            }
            Flaw::DropsX1 => {
                for i in 0..rows.n_rows() {
                    let x1 = dofs.free(rows.node[i], 0);
                    for k in rows.row_ptr[i]..rows.row_ptr[i + 1] {
                        if Some(rows.col[k]) == x1 {
                            rows.val[k] = 0.0;
                        }
                    }
                }
            }
            Flaw::ForceIsSumLambda | Flaw::ForceQuadratic => {}
        }
        Ok(rows)
    }
    fn gap(&self, mesh: &TetMesh, dofs: &DofMap, rows: &ConstraintRows, u: &[f64], extras: &[f64], out: &mut [f64]) {
        self.sphere.gap(mesh, dofs, rows, u, extras, out)
    }
    fn report(&self, mesh: &TetMesh, rows: &ConstraintRows, extras: &[f64], lambda: &[f64]) -> ContactReport {
        let mut r = self.sphere.report(mesh, rows, extras, lambda);
        match self.flaw {
            Flaw::ForceIsSumLambda => r.quantities[1].1 = lambda.iter().sum(),
            Flaw::ForceQuadratic => r.quantities[1].1 = lambda.iter().map(|l| l * l).sum(),
            _ => {}
        }
        r
    }
}

#[test]
fn broken_copies_fail_the_kit() {
    let m = mesh();
    let d = dofs(&m);
    for sphere in [pushed(), moved(0.01)] {
        for seed in [1, 2, 3] {
            let k = BrokenSphere { sphere: sphere.clone(), flaw: Flaw::NormalSign };
            let e = check_all(&k, &m, &d, seed, 0.01).expect_err("the wrong normal passed the kit");
            assert_eq!(e.check, "gap_derivative", "{e}");
            // the per-component check names the component
            let k = BrokenSphere { sphere: sphere.clone(), flaw: Flaw::DropsX1 };
            let e = check_all(&k, &m, &d, seed, 0.01).expect_err("dropping u₁ passed the kit");
            assert_eq!(e.check, "gap_derivative", "{e}");
            assert!(e.message.starts_with("∂g/∂u along x₁ of node"), "{e}");
        }
    }
    // force control: the kit's force is the resultant Σλ n·d, not Σλ
    let k = BrokenSphere { sphere: pushed(), flaw: Flaw::ForceIsSumLambda };
    let e = check_all(&k, &m, &d, 1, 0.01).expect_err("force = Σλ passed the kit");
    assert_eq!(e.check, "force", "{e}");
    assert!(e.message.contains("−(Hᵀλ)₀ = 3.0000000") || e.message.contains("−(Hᵀλ)₀ = 2.9999999"), "{e}");
    // V prescribed: no extra to balance, but the force must still be linear in λ
    let k = BrokenSphere { sphere: moved(0.01), flaw: Flaw::ForceQuadratic };
    let e = check_all(&k, &m, &d, 1, 0.01).expect_err("a quadratic force passed the kit");
    assert_eq!(e.check, "force", "{e}");
    assert!(e.message.contains("not linear in the multipliers"), "{e}");
}

#[test]
fn scene_tables_parse_and_unknown_fields_are_rejected() {
    let src = "type = \"rigid_sphere\"\ncenter = [-0.5, -0.75, -3.0]\nR = 3.0\ndirection = [3.0, 0.0, 4.0]\nF = 0.3\n\
               zone = { all = [ { group = \"zmin\" }, { disc = { center = [0.0, 0.0], radius = 0.5 } } ] }";
    let k: Box<dyn AdmissibleDisplacements> = toml::from_str(src).unwrap();
    assert_eq!(k.name(), "rigid_sphere");
    k.validate("obstacle").unwrap();
    assert_eq!((k.extra_names(), k.load()), (vec!["V".to_string()], vec![0.3]));
    let m = mesh();
    let d = dofs(&m);
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    assert_eq!(rows, pushed().discretise(&m, &d, "obstacle").unwrap());
    let again: Box<dyn AdmissibleDisplacements> = toml::from_str(&toml::to_string(&k).unwrap()).unwrap();
    assert_eq!(again.discretise(&m, &d, "obstacle").unwrap(), rows);
    // V prescribed
    let with_v = src.replace("F = 0.3", "V = 0.01");
    let k: Box<dyn AdmissibleDisplacements> = toml::from_str(&with_v).unwrap();
    assert!(k.extra_names().is_empty() && k.load().is_empty());
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    assert_eq!(rows, moved(0.01).discretise(&m, &d, "obstacle").unwrap());
    let text = toml::to_string(&k).unwrap();
    assert!(text.contains("V = 0.01") && !text.contains("F ="), "{text}");
    // both parse, and validation names the fields
    let both: Box<dyn AdmissibleDisplacements> = toml::from_str(&format!("{src}\nV = 0.01")).unwrap();
    let e = both.validate("obstacle").unwrap_err();
    assert!(e.field == "obstacle.F" && e.to_string().contains("obstacle.V"), "{e}");
    for bad in ["radius = 3.0", "U = 0.0", "d = [0.0, 0.0, 1.0]"] {
        let err = toml::from_str::<Box<dyn AdmissibleDisplacements>>(&format!("{src}\n{bad}")).unwrap_err();
        let name = bad.split(' ').next().unwrap();
        assert!(err.to_string().contains(&format!("unknown field `{name}`")), "{err}");
    }
    let err = toml::from_str::<Box<dyn AdmissibleDisplacements>>(&src.replace("direction", "dir")).unwrap_err();
    assert!(err.to_string().contains("dir"), "{err}");
}
