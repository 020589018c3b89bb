//! The rigid punches on the coarse default scene: rows, errors, warnings, report, TOML.

mod common;

use common::*;
use saddle_contact::{EllipticParaboloid, Flat, Paraboloid, RigidPunch, RigidPunchDisplacement, check_all};
use saddle_core::{AdmissibleDisplacements, Dirichlet, DofMap, Region, SceneError};

fn punches() -> Vec<Box<dyn AdmissibleDisplacements>> {
    let mut k: Vec<Box<dyn AdmissibleDisplacements>> = Vec::new();
    for gap in shapes() {
        k.push(Box::new(RigidPunch::new(0.3, disc(0.5), gap).unwrap()));
    }
    for gap in shapes() {
        k.push(Box::new(RigidPunchDisplacement::new(0.004, disc(0.5), gap).unwrap()));
    }
    k
}

#[test]
fn the_kit_passes_for_both_punches_and_every_gap_shape() {
    let (m, d) = (mesh(), dofs(&mesh()));
    for (i, k) in punches().iter().enumerate() {
        for (seed, scale) in [(1, 0.01), (2, 0.003), (3, 0.1)] {
            check_all(k.as_ref(), &m, &d, seed, scale)
                .unwrap_or_else(|e| panic!("punch {i} ({k:?}), seed {seed}: {e}"));
        }
    }
}

#[test]
fn one_row_per_bottom_node_in_the_disc_with_phi_offsets() {
    let m = mesh();
    let d = dofs(&m);
    let expected = bottom_nodes_in_disc(&m, 0.5);
    // the 0.25 grid points with x² + y² ≤ 0.25: the centre, 4 at distance 0.25, 4 at 0.5, 4 diagonal
    assert_eq!(expected.len(), 13);
    for (i, k) in punches().iter().enumerate() {
        let force_controlled = i < 3;
        let gap = &shapes()[i % 3];
        let rows = k.discretise(&m, &d, "obstacle").unwrap();
        assert_eq!(rows.n_rows(), 13);
        assert_eq!(rows.node, expected, "rows in node order");
        assert!(rows.warnings.is_empty(), "{:?}", rows.warnings);
        assert_eq!(rows.n_extras, usize::from(force_controlled));
        for (r, &n) in rows.node.iter().enumerate() {
            let x = m.nodes[n];
            let (cols, vals) = rows.row(r);
            assert_eq!((cols, vals), (&[d.free(n, 2).unwrap()][..], &[1.0][..]));
            let shift = if force_controlled { 0.0 } else { 0.004 };
            assert_eq!(rows.offset[r], gap.phi(x[0], x[1]) - shift);
            assert_eq!(rows.extra_row(r), if force_controlled { &[-1.0][..] } else { &[][..] });
        }
        assert_eq!(k.extra_names(), if force_controlled { vec!["U".to_string()] } else { vec![] });
        assert_eq!(k.load(), if force_controlled { vec![0.3] } else { vec![] });
    }
    // the default paraboloid: φ(0.5, 0) = 0.25/10
    let k = RigidPunch::new(0.3, disc(0.5), Box::new(Paraboloid::new(5.0))).unwrap();
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    let r = rows.node.iter().position(|&n| n == node_at(&m, 0.5, 0.0)).unwrap();
    assert_eq!(rows.offset[r], 0.025);
}

#[test]
fn elliptic_paraboloid_off_centre_by_hand() {
    let m = mesh();
    let d = dofs(&m);
    let gap = EllipticParaboloid { R1: 2.0, R2: 8.0, c1: 0.25, c2: -0.125 };
    let k = RigidPunch::new(0.3, disc(0.5), Box::new(gap)).unwrap();
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    let offset = |x1, x2| rows.offset[rows.node.iter().position(|&n| n == node_at(&m, x1, x2)).unwrap()];
    // (0.5 − 0.25)²/4 + (0 + 0.125)²/16 = 0.015625 + 0.0009765625
    assert_eq!(offset(0.5, 0.0), 0.0166015625);
    // (0.25 − 0.25)²/4 + (0.25 + 0.125)²/16 = 0 + 0.0087890625
    assert_eq!(offset(0.25, 0.25), 0.0087890625);
    // (−0.5 − 0.25)²/4 + (0 + 0.125)²/16 = 0.140625 + 0.0009765625
    assert_eq!(offset(-0.5, 0.0), 0.1416015625);
    // (0 − 0.25)²/4 + (−0.5 + 0.125)²/16 = 0.015625 + 0.0087890625
    assert_eq!(offset(0.0, -0.5), 0.0244140625);
    // at the row's (u, U): g = u₃ + φ − U
    let mut u = vec![0.0; d.n_free];
    let n = node_at(&m, -0.5, 0.0);
    u[d.free(n, 2).unwrap()] = 0.01;
    let mut g = vec![0.0; rows.n_rows()];
    k.gap(&m, &d, &rows, &u, &[0.05], &mut g);
    let r = rows.node.iter().position(|&x| x == n).unwrap();
    assert!((g[r] - (0.01 + 0.1416015625 - 0.05)).abs() < 1e-16);
}

#[test]
fn parameters_name_the_field_and_the_value() {
    let k = |f| RigidPunch::new(f, disc(0.5), Box::new(Paraboloid::new(5.0)));
    for (f, shown) in [(-0.3, "-0.3"), (f64::NAN, "NaN"), (f64::INFINITY, "inf")] {
        let e = k(f).unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), ("obstacle.F", shown));
    }
    // F = 0 is a punch without load (its U undetermined, theory §11.3): one rule, F ≥ 0, for a
    // scene, a sweep factor and a load-path factor alike
    assert!(k(0.0).is_ok());
    for r in [0.0, -5.0] {
        let e = RigidPunch::new(0.3, disc(0.5), Box::new(Paraboloid::new(r))).unwrap_err();
        assert_eq!((e.field.as_str(), e.value.clone()), ("obstacle.gap.R", r.to_string()));
        assert!(e.to_string().contains("obstacle.gap.R = ") && e.to_string().contains("> 0"), "{e}");
    }
    let e = RigidPunch::new(0.3, disc(0.5), Box::new(EllipticParaboloid { R1: 1.0, R2: 0.0, c1: 0.0, c2: 0.0 }))
        .unwrap_err();
    assert_eq!(e.field, "obstacle.gap.R2");
    let e = RigidPunchDisplacement::new(f64::NAN, disc(0.5), Box::new(Flat::default())).unwrap_err();
    assert_eq!((e.field.as_str(), e.value.as_str()), ("obstacle.U", "NaN"));
    let bad_zone = Region::All(vec![Region::Group("zmin".into()), Region::Disc { center: [0.0, 0.0], radius: -1.0 }]);
    let e = RigidPunch::new(0.3, bad_zone, Box::new(Flat::default())).unwrap_err();
    assert_eq!((e.field.as_str(), e.value.as_str()), ("obstacle.zone.all[1].disc.radius", "-1"));
    // a negative prescribed U is a legal position (the punch pulled away)
    RigidPunchDisplacement::new(-0.01, disc(0.5), Box::new(Flat::default())).unwrap();
    // the rows do not depend on F (a load path at factor 0, theory §11.3)
    let m = mesh();
    let (zero, one) = (
        k(0.0).unwrap().discretise(&m, &dofs(&m), "obstacle").unwrap(),
        k(0.3).unwrap().discretise(&m, &dofs(&m), "obstacle").unwrap(),
    );
    assert_eq!(zero, one);
}

#[test]
fn empty_and_unknown_zones_are_region_errors() {
    let m = mesh();
    let d = dofs(&m);
    let far = Region::All(vec![Region::Group("zmin".into()), Region::Disc { center: [5.0, 5.0], radius: 0.5 }]);
    let err =
        RigidPunch::new(0.3, far, Box::new(Paraboloid::new(5.0))).unwrap().discretise(&m, &d, "obstacle").unwrap_err();
    match &err {
        SceneError::Region { field, message } => {
            assert_eq!(field, "obstacle.zone");
            assert!(message.contains("no boundary node"), "{message}");
        }
        other => panic!("{other}"),
    }
    let zone = Region::All(vec![Region::Group("bottom".into()), Region::Disc { center: [0.0, 0.0], radius: 0.5 }]);
    let err = RigidPunchDisplacement::new(0.0, zone, Box::new(Flat::default()))
        .unwrap()
        .discretise(&m, &d, "obstacle")
        .unwrap_err();
    match &err {
        SceneError::Region { field, message } => {
            assert_eq!(field, "obstacle.zone");
            assert!(message.contains("\"bottom\""), "{message}");
            assert!(message.contains("\"zmin\"") && message.contains("\"xmax\""), "lists the mesh's groups: {message}");
        }
        other => panic!("{other}"),
    }
    // a zone of clamped nodes only: the bottom corner x, y ≥ 0.8 lies in Γ₂
    let corner =
        Region::All(vec![Region::Group("zmin".into()), Region::Box { min: [0.8, 0.8, -1.0], max: [1.0, 1.0, 1.0] }]);
    let err =
        RigidPunch::new(0.3, corner, Box::new(Flat::default())).unwrap().discretise(&m, &d, "obstacle").unwrap_err();
    match &err {
        SceneError::Region { field, message } => {
            assert_eq!(field, "obstacle.zone");
            // on the 0.25 grid only (1, 1, 0) has x, y ≥ 0.8
            assert!(message.contains("all 1 of its 1 nodes"), "{message}");
            assert!(message.contains("no contact node is left"), "{message}");
        }
        other => panic!("{other}"),
    }
}

#[test]
fn clamped_zone_nodes_are_dropped_with_a_warning() {
    let m = mesh();
    let d = dofs(&m);
    let in_disc = bottom_nodes_in_disc(&m, 0.8);
    let free: Vec<usize> =
        in_disc.iter().copied().filter(|&n| m.nodes[n][0].abs() < 0.7 && m.nodes[n][1].abs() < 0.7).collect();
    // grid points with i² + j² ≤ 10 (37), of which those with |i| = 3 or |j| = 3 (12) are clamped
    assert_eq!((in_disc.len(), free.len()), (37, 25));
    let k = RigidPunch::new(0.3, disc(0.8), Box::new(Paraboloid::new(5.0))).unwrap();
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    assert_eq!(rows.node, free);
    assert_eq!(rows.warnings.len(), 1);
    let w = &rows.warnings[0];
    assert!(w.starts_with("obstacle.zone: 12 of its 37 nodes"), "{w}");
    assert!(w.contains("Dirichlet") && w.contains("25 contact nodes remain"), "{w}");
    check_all(&k, &m, &d, 5, 0.01).unwrap();
}

#[test]
fn a_zone_off_the_contact_plane_is_warned_about() {
    let m = mesh();
    let d = DofMap::new(&m, &[Dirichlet::clamped(Region::Group("zmax".into()))]).unwrap();
    let k =
        RigidPunch::new(0.3, Region::Not(Box::new(Region::Group("zmax".into()))), Box::new(Flat::default())).unwrap();
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    assert_eq!(rows.warnings.len(), 1, "{:?}", rows.warnings);
    assert!(rows.warnings[0].contains("span x₃ ∈ [0, 0.75]"), "{}", rows.warnings[0]);
    // the plane face alone is not
    let k = RigidPunch::new(0.3, Region::Group("zmin".into()), Box::new(Flat::default())).unwrap();
    assert!(k.discretise(&m, &d, "obstacle").unwrap().warnings.is_empty());
}

#[test]
fn report_gives_u_force_contact_set_and_radius() {
    let m = mesh();
    let d = dofs(&m);
    let gap = EllipticParaboloid { R1: 2.0, R2: 8.0, c1: 0.25, c2: -0.125 };
    let k = RigidPunch::new(0.3, disc(0.5), Box::new(gap)).unwrap();
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    let row = |x1, x2| rows.node.iter().position(|&n| n == node_at(&m, x1, x2)).unwrap();
    let mut lambda = vec![0.0; rows.n_rows()];
    lambda[row(0.0, 0.0)] = 0.2;
    lambda[row(-0.25, 0.0)] = 0.1;
    lambda[row(0.0, 0.25)] = 1e-12; // below the contact-set threshold
    let r = k.report(&m, &rows, &[0.0083], &lambda);
    assert_eq!(r.get("U"), Some(0.0083));
    assert!((r.get("force").unwrap() - 0.300000000001).abs() < 1e-15);
    assert_eq!(r.contact_nodes, 2);
    // farthest contact node from the apex (0.25, −0.125): (−0.25, 0)
    assert!((r.contact_radius - 0.5f64.hypot(0.125)).abs() < 1e-15, "{}", r.contact_radius);
    let k = RigidPunchDisplacement::new(0.004, disc(0.5), Box::new(Paraboloid::new(5.0))).unwrap();
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    let mut lambda = vec![0.0; rows.n_rows()];
    lambda[0] = 0.5;
    lambda[5] = 0.25;
    let r = k.report(&m, &rows, &[], &lambda);
    assert_eq!((r.get("U"), r.get("force")), (Some(0.004), Some(0.75)));
    assert_eq!(r.contact_nodes, 2);
}

#[test]
fn the_rim_warning_fires_only_for_contact_at_the_rim() {
    let m = mesh();
    let d = dofs(&m);
    let k = RigidPunch::new(0.3, disc(0.5), Box::new(Paraboloid::new(5.0))).unwrap();
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    let row = |x1, x2| rows.node.iter().position(|&n| n == node_at(&m, x1, x2)).unwrap();
    let centre = row(0.0, 0.0);
    let rim = row(0.5, 0.0); // next to (0.75, 0), outside the disc
    let mut lambda = vec![0.0; rows.n_rows()];
    lambda[centre] = 0.3;
    let r = k.report(&m, &rows, &[0.0], &lambda);
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    assert_eq!((r.contact_nodes, r.contact_radius), (1, 0.0));
    // positive but outside the contact set (relative 1e-8): still no warning
    lambda[rim] = 1e-10;
    assert!(k.report(&m, &rows, &[0.0], &lambda).warnings.is_empty());
    lambda[rim] = 0.01;
    let r = k.report(&m, &rows, &[0.0], &lambda);
    assert_eq!(r.warnings.len(), 1);
    let w = &r.warnings[0];
    assert!(
        w.contains("rim of obstacle.zone at 1 node(s)")
            && w.contains("(0.5, 0, 0)")
            && w.contains("enlarge obstacle.zone"),
        "{w}"
    );
    assert_eq!(r.contact_radius, 0.5);
    // a zone covering the whole face facing the punch has no rim (homogeneous compression, theory §7)
    let d = DofMap::new(&m, &[Dirichlet::clamped(Region::Group("zmax".into()))]).unwrap();
    let k = RigidPunch::new(0.3, Region::Group("zmin".into()), Box::new(Flat::default())).unwrap();
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    assert_eq!(rows.n_rows(), 81);
    let r = k.report(&m, &rows, &[0.0], &vec![1.0; 81]);
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    assert_eq!(r.contact_nodes, 81);
    assert!((r.contact_radius - 2f64.sqrt()).abs() < 1e-15);
}

#[test]
fn scene_tables_parse_and_unknown_fields_are_rejected() {
    let src = "type = \"rigid_punch\"\nF = 0.3\nzone = { all = [ { group = \"zmin\" }, { disc = { center = [0.0, 0.0], radius = 0.5 } } ] }\ngap = { type = \"paraboloid\", R = 5.0 }";
    let k: Box<dyn AdmissibleDisplacements> = toml::from_str(src).unwrap();
    assert_eq!(k.name(), "rigid_punch");
    k.validate("obstacle").unwrap();
    assert_eq!(k.load(), vec![0.3]);
    let m = mesh();
    let d = dofs(&m);
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    assert_eq!(rows.n_rows(), 13);
    assert_eq!(rows.offset.iter().copied().fold(0.0, f64::max), 0.025);
    // round trip through TOML
    let again: Box<dyn AdmissibleDisplacements> = toml::from_str(&toml::to_string(&k).unwrap()).unwrap();
    assert_eq!(again.discretise(&m, &d, "obstacle").unwrap(), rows);

    let err = toml::from_str::<Box<dyn AdmissibleDisplacements>>(&format!("{src}\nforce = 1.0")).unwrap_err();
    assert!(err.to_string().contains("force"), "{err}");
    let err =
        toml::from_str::<Box<dyn AdmissibleDisplacements>>(&src.replace("R = 5.0", "R = 5.0, r = 2.0")).unwrap_err();
    assert!(err.to_string().contains("unknown field `r`"), "{err}");
    let err = toml::from_str::<Box<dyn AdmissibleDisplacements>>(&src.replace("paraboloid", "sphere")).unwrap_err();
    assert!(err.to_string().contains("sphere"), "{err}");

    let ell = "type = \"rigid_punch_displacement\"\nU = 0.01\nzone = { group = \"zmin\" }\n\
               gap = { type = \"elliptic_paraboloid\", R1 = 2.0, R2 = 8, c1 = 0.25 }";
    let k: Box<dyn AdmissibleDisplacements> = toml::from_str(ell).unwrap();
    assert_eq!(k.name(), "rigid_punch_displacement");
    let rows = k.discretise(&m, &d, "obstacle").unwrap();
    // Γ₁ nodes of the bottom face (|x|, |y| < 0.75): 5 × 5; offset at (0.5, −0.5) = 0.25²/4 + 0.5²/16 − 0.01
    assert_eq!(rows.n_rows(), 25);
    let r = rows.node.iter().position(|&n| n == node_at(&m, 0.5, -0.5)).unwrap();
    assert!((rows.offset[r] - (0.015625 + 0.015625 - 0.01)).abs() < 1e-16);
    let flat: Box<dyn AdmissibleDisplacements> =
        toml::from_str("type = \"rigid_punch\"\nF = 1\nzone = { group = \"zmin\" }\ngap = { type = \"flat\" }")
            .unwrap();
    assert_eq!(flat.load(), vec![1.0]);
    let err = toml::from_str::<Box<dyn AdmissibleDisplacements>>(
        "type = \"rigid_punch\"\nF = 1\nzone = { group = \"zmin\" }\ngap = { type = \"flat\", R = 1.0 }",
    )
    .unwrap_err();
    assert!(err.to_string().contains("unknown field `R`"), "{err}");
}

#[test]
fn contact_pressures_of_a_uniform_force_field() {
    // equal forces on every row of a flat zone: pressure = force / nodal area, whose mean over
    // the zone is the total force over the zone's area
    let mesh = common::mesh();
    let dofs = common::dofs(&mesh);
    let zone = saddle_core::Region::Group("zmin".into());
    let punch = saddle_contact::RigidPunch::new(1.0, zone, Box::new(saddle_contact::Flat::default())).unwrap();
    let rows = saddle_core::AdmissibleDisplacements::discretise(&punch, &mesh, &dofs, "obstacle").unwrap();
    let areas = saddle_contact::zone::row_areas(&mesh, &rows);
    let zone_area: f64 = areas.iter().sum();
    let lambda = vec![1.0 / rows.n_rows() as f64; rows.n_rows()];
    let r = saddle_core::AdmissibleDisplacements::report(&punch, &mesh, &rows, &[0.0], &lambda);
    assert!((r.get("contact_area").unwrap() - zone_area).abs() < 1e-12);
    assert!((r.get("mean_pressure").unwrap() - 1.0 / zone_area).abs() < 1e-12);
    let smallest = areas.iter().copied().fold(f64::INFINITY, f64::min);
    assert!((r.get("peak_pressure").unwrap() - lambda[0] / smallest).abs() < 1e-12);
}

#[test]
fn p2_pressures_are_the_consistent_forces_over_their_weights() {
    // on a second-order mesh a uniform pressure p has the consistent forces ∫N p: 0 at a 6-node
    // facet's vertices, p|F|/3 at its edge nodes (theory §10.1). The nodal areas are the same
    // weights, so every edge row reads p back exactly and the vertex rows have no area; with
    // the former 1/12–1/4 split the peak came out 4/3 p
    let mesh = common::mesh().second_order();
    let dofs = common::dofs(&mesh);
    let punch =
        saddle_contact::RigidPunch::new(1.0, common::disc(0.5), Box::new(saddle_contact::Flat::default())).unwrap();
    let rows = saddle_core::AdmissibleDisplacements::discretise(&punch, &mesh, &dofs, "obstacle").unwrap();
    let mut row_of = vec![usize::MAX; mesh.n_nodes()];
    rows.node.iter().enumerate().for_each(|(i, &n)| row_of[n] = i);
    let (p, so) = (2.5, mesh.second_order.as_ref().unwrap());
    let mut lambda = vec![0.0; rows.n_rows()];
    let mut vertex = vec![false; rows.n_rows()];
    for &f in &mesh.groups["zmin"] {
        let [a, b, c] = mesh.boundary[f].map(|i| mesh.nodes[i]);
        let n = saddle_contact::zone::tri_normal(a, b, c);
        let area = 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        mesh.boundary[f].iter().filter(|&&v| row_of[v] != usize::MAX).for_each(|&v| vertex[row_of[v]] = true);
        for &e in so.facet_edges[f].iter().filter(|&&e| row_of[e] != usize::MAX) {
            lambda[row_of[e]] += p * area / 3.0;
        }
    }
    let areas = saddle_contact::zone::row_areas(&mesh, &rows);
    for i in 0..rows.n_rows() {
        if vertex[i] {
            assert_eq!(areas[i], 0.0, "row {i}: a vertex has ∫N = 0");
        } else {
            assert!((lambda[i] / areas[i] - p).abs() < 1e-12 * p, "row {i}: {}", lambda[i] / areas[i]);
        }
    }
    let r = saddle_core::AdmissibleDisplacements::report(&punch, &mesh, &rows, &[0.0], &lambda);
    assert!((r.get("peak_pressure").unwrap() - p).abs() < 1e-12 * p, "{:?}", r.get("peak_pressure"));
    assert!((r.get("mean_pressure").unwrap() - p).abs() < 1e-12 * p, "{:?}", r.get("mean_pressure"));
}
