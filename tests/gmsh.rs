//! Gmsh MSH 4.1 meshes (`type = "gmsh"`): the committed mesh of the default scene made by the
//! real Gmsh (tests/data/make_punch_mesh.py), its physical groups, the node rules on the rims
//! between groups, the contact problem solved on it, malformed files and `saddle run`; and
//! second-order meshes (10-node tetrahedra, 6-node triangles) made by the real Gmsh
//! (tests/data/make_p2_meshes.py): a box at order 1 and 2, and a curved cylinder.
#![cfg(feature = "gmsh")]

mod common;
use common::*;
use saddle::core::mesh::gmsh::{GmshImport, GmshMesh, read_msh};
use saddle::core::mesh::{TET_EDGES, TRI_EDGES};
use saddle::core::{MeshSource, Region, Silent, Solver, TetMesh};
use saddle::io::scene::Scene;
use saddle::solvers::Newton;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;
use std::process::Command;
use std::sync::OnceLock;

/// The default scene (theory §6) solved by Newton on a box mesh.
#[derive(Clone, Copy, Debug)]
struct BoxSolution {
    /// The punch's displacement U.
    u: f64,
    /// The contact radius (distance of the farthest contact node).
    radius: f64,
    /// The mesh's element sizes ([`sizes`]).
    sizes: (f64, f64),
}

/// The default scene solved by Newton to 1e-12 on the box mesh with `cells` (graded 3 toward
/// the punch centre, the edges of Γ₁ on grid lines).
fn box_solution(cells: [i64; 3]) -> BoxSolution {
    let mut t = small_johnson();
    set(&mut t, "mesh.cells", toml::Value::try_from(cells).unwrap());
    let (l, _) = build(&t);
    let sol = Newton { tol: 1e-12, ..Newton::default() }.solve(&l.lagrangian(), &mut Silent).unwrap();
    assert!(sol.report.converged, "box mesh {cells:?}: {:?}", sol.report.stop_reason);
    let report =
        l.view().obstacle().unwrap().report(l.element.mesh(), l.lagrangian().data.rows, &sol.extras, &sol.lambda);
    BoxSolution { u: sol.extras[0], radius: report.contact_radius, sizes: sizes(l.element.mesh()) }
}

/// The box-mesh references, solved once per test binary: the 12×12×6 mesh (5 184 tetrahedra)
/// and the twice finer 24×24×12 mesh (41 472 tetrahedra).
fn box_references() -> &'static [BoxSolution; 2] {
    static BOX: OnceLock<[BoxSolution; 2]> = OnceLock::new();
    BOX.get_or_init(|| {
        let t0 = std::time::Instant::now();
        let r = [box_solution([12, 12, 6]), box_solution([24, 24, 12])];
        println!("box meshes: 12×12×6 {:?}; 24×24×12 {:?}; {:.1} s", r[0], r[1], t0.elapsed().as_secs_f64());
        r
    })
}

/// Element sizes of a mesh of the block: (the longest edge of the bottom facets within r ≤ 0.3,
/// the patch where the punch touches — contact radius ≈ 0.23; the longest edge of any element).
fn sizes(m: &TetMesh) -> (f64, f64) {
    let on_patch = |n: usize| m.nodes[n][2].abs() < 1e-12 && m.nodes[n][0].hypot(m.nodes[n][1]) <= 0.3;
    let dist = |a: usize, b: usize| {
        let (p, q) = (m.nodes[a], m.nodes[b]);
        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
    };
    let patch = m
        .boundary
        .iter()
        .filter(|f| f.iter().all(|&n| on_patch(n)))
        .flat_map(|&[a, b, c]| [dist(a, b), dist(b, c), dist(c, a)])
        .fold(0.0, f64::max);
    (patch, (0..m.n_elements()).map(|e| m.element_size(e)).fold(0.0, f64::max))
}

fn punch() -> GmshImport {
    read_msh(&repo("tests/data/punch.msh"), 1.0).unwrap()
}

/// Area of boundary facet `f`.
fn area(m: &TetMesh, f: usize) -> f64 {
    let [a, b, c] = m.boundary[f].map(|i| m.nodes[i]);
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
    0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
}

/// The nodes of a facet group.
fn group_nodes(m: &TetMesh, g: &str) -> BTreeSet<usize> {
    m.groups[g].iter().flat_map(|&f| m.boundary[f]).collect()
}

#[test]
fn ascii_and_binary_files_hold_the_same_mesh() {
    let a = punch();
    let b = read_msh(&repo("tests/data/punch_binary.msh"), 1.0).unwrap();
    assert_eq!(a.node_tags, b.node_tags);
    assert_eq!(a.element_tags, b.element_tags);
    assert_eq!(a.mesh.tets, b.mesh.tets);
    assert_eq!(a.mesh.boundary, b.mesh.boundary);
    assert_eq!(a.mesh.groups, b.mesh.groups);
    assert_eq!(a.surface_groups, b.surface_groups);
    assert_eq!(a.ignored_groups, b.ignored_groups);
    // Gmsh prints ASCII coordinates with 16 significant digits (%.16g); the binary file holds the
    // doubles themselves. The coordinates lie in [−1, 1], so a printed one differs from its double
    // by at most half a unit in the 16th digit (5e-17) plus the rounding of the parsed decimal
    // (half an ulp of 1, 5.6e-17): 1.1e-16. Measured 5.6e-17; tolerance 1.2e-16, that bound and
    // about 2× the measured difference.
    let worst = a
        .mesh
        .nodes
        .iter()
        .zip(&b.mesh.nodes)
        .flat_map(|(x, y)| (0..3).map(move |k| (x[k] - y[k]).abs()))
        .fold(0.0, f64::max);
    println!("largest coordinate difference ASCII − binary: {worst:e}");
    assert!(worst <= 1.2e-16, "largest coordinate difference {worst:e}");
}

#[test]
fn physical_surfaces_become_facet_groups() {
    let imp = punch();
    let m = &imp.mesh;
    println!(
        "punch.msh: {} nodes, {} tetrahedra, {} boundary facets; groups {:?}; ignored {:?}",
        m.n_nodes(),
        m.n_elements(),
        m.boundary.len(),
        imp.surface_groups.iter().map(|g| (g.name.as_str(), g.tag, g.elements)).collect::<Vec<_>>(),
        imp.ignored_groups
    );
    assert_eq!(m.group_names(), vec!["clamped", "contact", "free"]);
    assert!(imp.ignored_groups.iter().any(|g| g.dim == 3 && g.name == "body" && g.elements == m.n_elements()));
    assert_eq!(imp.unused_nodes, 0);
    assert!((1000..=5000).contains(&m.n_elements()), "a few thousand tetrahedra: {}", m.n_elements());
    // the block (−1, 1)² × (−1, 0) has volume 4; the sum of ~4 000 element volumes rounds:
    // measured |vol − 4| = 7.1e-15 (8 ulps of 4), tolerance 2× that
    let vol: f64 = (0..m.n_elements()).map(|e| m.volume(e)).sum();
    println!("volume − 4 = {:e}", vol - 4.0);
    assert!((vol - 4.0).abs() <= 1.5e-14, "volume {vol}");

    // every boundary facet in exactly one group
    let mut count = vec![0; m.boundary.len()];
    for fs in m.groups.values() {
        for &f in fs {
            count[f] += 1;
        }
    }
    assert!(count.iter().all(|&c| c == 1), "the three groups partition the boundary");

    // the areas of the three surfaces. The contact disc is meshed as the polygon inscribed in
    // the circle r = 0.5 through its rim nodes (those it shares with "free"), whose area is
    // ½ r² Σ sin Δθ over the angles Δθ between consecutive rim nodes: computed from the rim
    // nodes alone, independent of the facets. The square 1.5 × 1.5 (2.25) is "contact" and
    // "free"; the rest of the block's boundary, 4 − 2.25 + 8 + 4, is "clamped". Sums of some
    // hundred facet areas, exact up to rounding: measured deviations 1.0e-15 (the disc's
    // polygon, 0.24 % below the disc π r² itself), 8.9e-16 (the square) and 3.6e-15 (clamped);
    // tolerances 2× those.
    let group_area = |g: &str| m.groups[g].iter().map(|&f| area(m, f)).sum::<f64>();
    let rim: BTreeSet<usize> = group_nodes(m, "contact").intersection(&group_nodes(m, "free")).copied().collect();
    let mut angles: Vec<f64> = rim.iter().map(|&n| m.nodes[n][1].atan2(m.nodes[n][0])).collect();
    angles.sort_by(f64::total_cmp);
    angles.push(angles[0] + 2.0 * std::f64::consts::PI);
    let polygon: f64 = angles.windows(2).map(|w| 0.5 * 0.25 * (w[1] - w[0]).sin()).sum();
    let deviations = [
        group_area("contact") - polygon,
        group_area("contact") + group_area("free") - 2.25,
        group_area("clamped") - (4.0 - 2.25 + 8.0 + 4.0),
    ];
    let shown: Vec<String> = deviations.iter().map(|d| format!("{d:.1e}")).collect();
    println!(
        "areas − closed forms (disc's polygon through {} rim nodes, square, clamped): {shown:?}; the polygon is \
         {:+.3} % from the disc",
        rim.len(),
        100.0 * (polygon / (std::f64::consts::PI * 0.25) - 1.0)
    );
    for (d, tol) in deviations.iter().zip([2e-15, 1.8e-15, 7.2e-15]) {
        assert!(d.abs() <= tol, "area deviations {shown:?}");
    }
    let n_contact = m.groups["contact"].len();
    assert!((200..=2000).contains(&n_contact), "{n_contact} facets on the contact disc");
    assert!(m.groups["free"].len() >= 100 && m.groups["clamped"].len() >= 100);

    // the contact facets lie on the disc r < 0.5 of x₃ = 0, the free ones on the rest of the
    // square: their centroids on either side of the circle and inside the square, with no slack
    // (measured: contact r ≤ 0.4872, free r ≥ 0.5143 and max(|x₁|, |x₂|) ≤ 0.7228), and on the
    // plane exactly (Gmsh writes x₃ = 0 for the nodes of the plane face)
    for &f in &m.groups["contact"] {
        let c = m.facet_centroid(f);
        assert!(c[2] == 0.0 && c[0].hypot(c[1]) < 0.5, "contact facet at {c:?}");
    }
    for &f in &m.groups["free"] {
        let c = m.facet_centroid(f);
        assert!(c[2] == 0.0 && c[0].hypot(c[1]) > 0.5 && c[0].abs().max(c[1].abs()) < 0.75, "{c:?}");
    }
    // the mesh resolves the contact zone: tests/data/make_punch_mesh.py asks Gmsh for size 0.06
    // on the disc (theory §6 asks ≲ 0.055 for 8 elements across the contact zone); the longest
    // edge there measures 0.078 (+30 %), bounded by 0.1 (+67 %, about 2× the measured excess)
    let h = m.groups["contact"]
        .iter()
        .flat_map(|&f| {
            let [a, b, c] = m.boundary[f].map(|i| m.nodes[i]);
            [(a, b), (b, c), (c, a)]
        })
        .map(|(p, q)| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt())
        .fold(0.0, f64::max);
    assert!(h < 0.1, "longest edge on the contact disc {h}");
}

#[test]
fn node_rules_on_the_rims_between_groups() {
    let scene = Scene::from_file(&repo("examples/gmsh_punch.toml")).unwrap();
    let (l, _) = scene.into_problem().unwrap();
    assert!(l.view().warnings().is_empty(), "{:?}", l.view().warnings());
    let m = l.element.mesh();
    let (contact, free, clamped) = (group_nodes(m, "contact"), group_nodes(m, "free"), group_nodes(m, "clamped"));
    let disc_rim: Vec<usize> = contact.intersection(&free).copied().collect();
    let square_rim: Vec<usize> = free.intersection(&clamped).copied().collect();
    println!(
        "nodes: {} contact, {} free, {} clamped; {} on the disc's rim, {} on the square's rim",
        contact.len(),
        free.len(),
        clamped.len(),
        disc_rim.len(),
        square_rim.len()
    );
    assert!(disc_rim.len() >= 20 && square_rim.len() >= 20, "{} {}", disc_rim.len(), square_rim.len());
    assert!(contact.is_disjoint(&clamped), "the disc lies strictly inside the square");

    // contact nodes: every node of the "contact" facets, its rim with "free" included
    let rows: BTreeSet<usize> = l.lagrangian().data.rows.node.iter().copied().collect();
    assert_eq!(rows, contact);
    assert!(disc_rim.iter().all(|n| rows.contains(n)));
    for &n in &disc_rim {
        let x = m.nodes[n];
        // on the circle r = 0.5 to the rounding of the file's 16 digits and of the hypotenuse:
        // measured 1.1e-16 (1 ulp of 0.5), tolerance 2× that
        assert!((x[0].hypot(x[1]) - 0.5).abs() <= 2.2e-16 && x[2] == 0.0, "rim node at {x:?}");
    }
    // clamped: every node of the "clamped" facets, its rim with "free" included; nothing else
    let dofs = l.element.dofs();
    for n in 0..m.n_nodes() {
        let fixed = (0..3).filter(|&c| dofs.free(n, c).is_none()).count();
        assert_eq!(fixed, if clamped.contains(&n) { 3 } else { 0 }, "node {n} at {:?}", m.nodes[n]);
    }
    for &n in &square_rim {
        let x = m.nodes[n];
        // on the square's sides |x₁| = 0.75 or |x₂| = 0.75 exactly (Gmsh writes ±0.75; measured 0)
        assert!(x[0].abs().max(x[1].abs()) == 0.75 && x[2] == 0.0, "rim node at {x:?}");
    }
}

#[test]
fn geometric_regions_give_the_same_problem_as_the_groups() {
    // the predicates shown in the comments of examples/gmsh_punch.toml
    let mut t = example("gmsh_punch.toml");
    set(&mut t, "mesh.file", toml::Value::String(repo("tests/data/punch.msh").display().to_string()));
    let (by_group, _) = build(&t);
    let region = |s: &str| -> toml::Value { toml::from_str::<toml::Table>(&format!("r = {s}")).unwrap()["r"].clone() };
    let dirichlet = t["dirichlet"].as_array().unwrap()[0].clone();
    let mut d = dirichlet.as_table().unwrap().clone();
    d.insert("on".into(), region("{ not = { box = { min = [-0.75, -0.75, -1e-9], max = [0.75, 0.75, 1e-9] } } }"));
    t.insert("dirichlet".into(), toml::Value::Array(vec![toml::Value::Table(d)]));
    set(
        &mut t,
        "obstacle.zone",
        region(
            "{ all = [ { box = { min = [-1.0, -1.0, -1e-9], max = [1.0, 1.0, 1e-9] } }, \
             { disc = { center = [0.0, 0.0], radius = 0.5 } } ] }",
        ),
    );
    let (by_geometry, _) = build(&t);
    assert_eq!(by_group.element.dofs().dof, by_geometry.element.dofs().dof);
    assert_eq!(by_group.lagrangian().data.rows.node, by_geometry.lagrangian().data.rows.node);
    // and the same facets as the groups
    let m = by_group.element.mesh();
    let square = Region::Box { min: [-0.75, -0.75, -1e-9], max: [0.75, 0.75, 1e-9] };
    let expected: BTreeSet<usize> = m.groups["contact"].iter().chain(&m.groups["free"]).copied().collect();
    assert_eq!(square.facets(m).into_iter().collect::<BTreeSet<_>>(), expected);
}

#[test]
fn newton_solves_the_default_scene_on_the_gmsh_mesh() {
    let [coarse, fine] = *box_references();
    let (u_coarse, r_coarse, h_coarse) = (coarse.u, coarse.radius, coarse.sizes);
    let (u_fine, r_fine) = (fine.u, fine.radius);
    for file in ["punch.msh", "punch_binary.msh"] {
        let mut t = example("gmsh_punch.toml");
        set(&mut t, "mesh.file", toml::Value::String(repo(&format!("tests/data/{file}")).display().to_string()));
        let (l, solver) = build(&t);
        let solver = solver.unwrap();
        let sol = solver.solve(&l.lagrangian(), &mut Silent).unwrap();
        let report =
            l.view().obstacle().unwrap().report(l.element.mesh(), l.lagrangian().data.rows, &sol.extras, &sol.lambda);
        let u = sol.extras[0];
        let h = sizes(l.element.mesh());
        println!(
            "{file}: U = {u:.6e} ({:+.2} % against the 12×12×6 box mesh, {:+.2} % against the 24×24×12 one), KKT \
             {:.2e}, {} iterations, {} contact nodes of {}, contact radius {:.4}, sizes (contact patch, bulk) {h:.4?}, \
             {} plastic elements of {}",
            100.0 * (u / u_coarse - 1.0),
            100.0 * (u / u_fine - 1.0),
            sol.report.kkt.max(),
            sol.report.iterations,
            report.contact_nodes,
            l.lagrangian().data.rows.n_rows(),
            report.contact_radius,
            sol.stress.n_plastic(),
            l.element.mesh().n_elements()
        );
        assert!(sol.report.converged, "{:?}", sol.report.stop_reason);
        assert!(sol.report.kkt.max() <= 1e-10, "{:?}", sol.report.kkt);
        // U against the same scene on the 12×12×6 box mesh, solved in this test
        // (`box_references`): another mesh of the same problem, made without the Gmsh reader.
        // The Gmsh mesh has a comparable resolution: finer on the contact patch (edges 0.068
        // against 0.158), coarser in the bulk (largest element 0.55 against 0.44; both checked
        // below). The two U differ by the difference of two discretisation errors, fixed for
        // these two meshes (both solves are converged to KKT ≤ 1e-10, which moves U by far less):
        // measured U = 7.812e-3, 0.405 % below U(12×12×6) = 7.844e-3; tolerance 0.81 %, 2× the
        // measured difference, so a change of the mesh read or of the problem built on it that
        // moves U by another 0.4 % fails. For scale: one refinement of the box mesh raises U by
        // δ = U(24×24×12) − U(12×12×6) = 4.5 % (P1 tetrahedra are too stiff, so U rises on
        // every refinement: the mesh convergence of docs/accuracy.md), so the difference is well within the
        // discretisation error of either mesh.
        let delta = u_fine - u_coarse;
        assert!(delta > 0.0, "U rises from the 12×12×6 box mesh ({u_coarse:e}) to the 24×24×12 one ({u_fine:e})");
        assert!(
            h.0 <= h_coarse.0 && h.1 <= 1.5 * h_coarse.1,
            "resolution (contact patch, bulk) {h:?} not comparable to the 12×12×6 box mesh's {h_coarse:?}"
        );
        assert!((u / u_coarse - 1.0).abs() <= 8.1e-3, "U = {u:e}, 12×12×6 box mesh {u_coarse:e}");
        // The contact radius, the distance of the farthest contact node, against the box
        // meshes' (theory §6: about 0.23, Hertz 0.22). Each mesh knows it to its node spacing on
        // the contact patch (0.068 here, 0.158 and 0.087 on the box meshes), but the measured
        // differences are far smaller: 0.2241 against 0.2207 (3.4e-3) and 0.2169 (7.2e-3);
        // tolerances 2× those.
        for (r_box, tol) in [(r_coarse, 6.8e-3), (r_fine, 1.44e-2)] {
            let d = report.contact_radius - r_box;
            println!("{file}: contact radius − box mesh's = {d:.3e} (tolerance {tol:e})");
            assert!(d.abs() <= tol, "contact radius {} against the box mesh's {r_box}", report.contact_radius);
        }
        assert!(sol.stress.n_plastic() > 0);
        assert!(report.warnings.is_empty() && l.view().warnings().is_empty(), "{:?}", report.warnings);
    }
}

/// Writes `bytes` as `dir/name` and a scene using it; returns the scene-level error message.
fn scene_error(dir: &Path, name: &str, bytes: &[u8], edit: impl FnOnce(&mut toml::Table)) -> String {
    let mesh = dir.join(name);
    std::fs::write(&mesh, bytes).unwrap();
    let mut t = example("gmsh_punch.toml");
    set(&mut t, "mesh.file", toml::Value::String(name.into()));
    edit(&mut t);
    let scene_path = dir.join(format!("{name}.toml"));
    std::fs::write(&scene_path, toml::to_string(&t).unwrap()).unwrap();
    let scene = Scene::from_file(&scene_path).unwrap();
    let err = scene.into_problem().unwrap_err().to_string();
    println!("{name}: {err}");
    err
}

fn assert_contains(err: &str, expected: &[&str]) {
    for e in expected {
        assert!(err.contains(e), "error {err:?} lacks {e:?}");
    }
}

#[test]
fn malformed_files_give_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let ascii = std::fs::read_to_string(repo("tests/data/punch.msh")).unwrap();
    let binary = std::fs::read(repo("tests/data/punch_binary.msh")).unwrap();
    let none = |_: &mut toml::Table| {};

    // truncated, ASCII and binary
    let cut = &ascii[..ascii.len() * 2 / 3];
    let err = scene_error(dir.path(), "cut.msh", cut.as_bytes(), none);
    assert_contains(&err, &["mesh: ", "cut.msh", "cannot parse the file as MSH 4.1", "truncated", "element section"]);
    let err = scene_error(dir.path(), "cut_binary.msh", &binary[..binary.len() / 2], none);
    assert_contains(&err, &["cut_binary.msh", "truncated"]);

    // a tetrahedron referring to a node tag the file does not define
    let mut lines: Vec<String> = ascii.lines().map(str::to_string).collect();
    let header = lines.iter().position(|l| l.starts_with("3 ") && l.split(' ').nth(2) == Some("4")).unwrap();
    let mut fields: Vec<String> = lines[header + 1].split_whitespace().map(str::to_string).collect();
    let element = fields[0].clone();
    fields[2] = "999999".into();
    lines[header + 1] = fields.join(" ");
    let err = scene_error(dir.path(), "dangling.msh", lines.join("\n").as_bytes(), none);
    assert_contains(&err, &[&format!("tetrahedron {element} refers to node 999999"), "no node has tag 999999"]);

    // another MSH version
    let err = scene_error(dir.path(), "v22.msh", ascii.replacen("4.1 0 8", "2.2 0 8", 1).as_bytes(), none);
    assert_contains(&err, &["v22.msh", "MSH version 2.2 found", "only version 4.1"]);

    // a missing file names its path
    let mut t = example("gmsh_punch.toml");
    set(&mut t, "mesh.file", toml::Value::String("nowhere/none.msh".into()));
    let scene_path = dir.path().join("missing.toml");
    std::fs::write(&scene_path, toml::to_string(&t).unwrap()).unwrap();
    let err = Scene::from_file(&scene_path).unwrap().into_problem().unwrap_err().to_string();
    assert_contains(&err, &["nowhere/none.msh", "cannot read the Gmsh mesh file"]);

    // without $PhysicalNames the groups are physical_<tag>, and the scene's names are missing
    let start = ascii.find("$PhysicalNames").unwrap();
    let end = ascii.find("$EndPhysicalNames\n").unwrap() + "$EndPhysicalNames\n".len();
    let unnamed = format!("{}{}", &ascii[..start], &ascii[end..]);
    let err = scene_error(dir.path(), "unnamed.msh", unnamed.as_bytes(), none);
    assert_contains(&err, &["dirichlet[0].on", "\"clamped\"", "physical_1", "physical_2", "physical_3"]);
}

#[test]
fn a_missing_group_lists_the_physical_names_of_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let ascii = std::fs::read(repo("tests/data/punch.msh")).unwrap();
    let nope = || toml::from_str::<toml::Table>("r = { group = \"nope\" }").unwrap()["r"].clone();
    let err = scene_error(dir.path(), "a.msh", &ascii, |t| {
        let d = t["dirichlet"].as_array_mut().unwrap()[0].as_table_mut().unwrap();
        d.insert("on".into(), nope());
    });
    assert_contains(
        &err,
        &["dirichlet[0].on", "no facet group named [\"nope\"]", "[\"clamped\", \"contact\", \"free\"]"],
    );
    let err = scene_error(dir.path(), "b.msh", &ascii, |t| set(t, "obstacle.zone", nope()));
    assert_contains(&err, &["obstacle.zone", "\"nope\"", "[\"clamped\", \"contact\", \"free\"]"]);
}

#[test]
fn saddle_run_on_the_gmsh_scene() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("gmsh");
    let o = Command::new(env!("CARGO_BIN_EXE_saddle"))
        .args(["run", repo("examples/gmsh_punch.toml").to_str().unwrap(), "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("newton") && stdout.contains("contact nodes"), "{stdout}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["solver"], "newton");
    assert_eq!(summary["converged"], true);
    assert_eq!(summary["elements"], punch().mesh.n_elements());
    assert!(summary["kkt_residual"].as_f64().unwrap() <= 1e-10);
    // the same U as the library's solve of the same scene (the CLI reads the scene file, solves
    // with its solver and writes the JSON). The same computation: measured difference 0; the
    // tolerance 1e-12 U leaves room only for rounding (parallel sums in another order), 100×
    // below the solver's tolerance 1e-10
    let (l, scene_solver) = Scene::from_file(&repo("examples/gmsh_punch.toml")).unwrap().into_problem().unwrap();
    let expected = scene_solver.unwrap().solve(&l.lagrangian(), &mut Silent).unwrap().extras[0];
    let u = summary["U"].as_f64().unwrap();
    println!("U from `saddle run` − U from the library: {:e}", u - expected);
    assert!((u - expected).abs() <= 1e-12 * expected, "U = {u:e} from `saddle run`, {expected:e} from the library");
    let vtu = std::fs::read(out.join("solution.vtu")).unwrap();
    let head = String::from_utf8_lossy(&vtu[..vtu.len().min(3000)]);
    assert!(head.contains(&format!("NumberOfCells=\"{}\"", punch().mesh.n_elements())), "{head}");
}

/// The node coordinates of an ASCII MSH 4.1 file by tag, read here from the `$Nodes` section
/// (independent of the reader, which moves edge nodes to their midpoints): per block
/// `dim tag parametric n`, the n tags, then the n coordinate lines.
fn file_coordinates(path: &Path) -> HashMap<u64, [f64; 3]> {
    let text = std::fs::read_to_string(path).unwrap();
    let section = text.split("$Nodes\n").nth(1).unwrap().split("$EndNodes").next().unwrap();
    let mut lines = section.lines();
    let header: Vec<usize> = lines.next().unwrap().split_whitespace().map(|t| t.parse().unwrap()).collect();
    let mut coords = HashMap::new();
    for _ in 0..header[0] {
        let block: Vec<usize> = lines.next().unwrap().split_whitespace().map(|t| t.parse().unwrap()).collect();
        assert_eq!(block[2], 0, "parametric node block");
        let tags: Vec<u64> = (0..block[3]).map(|_| lines.next().unwrap().trim().parse().unwrap()).collect();
        for tag in tags {
            let x: Vec<f64> = lines.next().unwrap().split_whitespace().map(|t| t.parse().unwrap()).collect();
            assert!(coords.insert(tag, [x[0], x[1], x[2]]).is_none());
        }
    }
    assert_eq!(coords.len(), header[1]);
    coords
}

fn dist(p: [f64; 3], q: [f64; 3]) -> f64 {
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
}

fn midpoint(p: [f64; 3], q: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|k| 0.5 * (p[k] + q[k]))
}

fn total_volume(m: &TetMesh) -> f64 {
    (0..m.n_elements()).map(|e| m.volume(e)).sum()
}

#[test]
fn second_order_box_has_the_vertices_and_tets_of_the_first_order_one() {
    let p1 = read_msh(&repo("tests/data/box_p1.msh"), 1.0).unwrap();
    let p2 = read_msh(&repo("tests/data/box_p2.msh"), 1.0).unwrap();
    let (m1, m2) = (&p1.mesh, &p2.mesh);
    assert!(!m1.is_second_order() && p1.warnings.is_empty());
    let so = m2.second_order.as_ref().expect("box_p2.msh is a second-order mesh");
    println!(
        "box_p1.msh: {} nodes, {} tetrahedra; box_p2.msh: {} nodes ({} vertices), {} tetrahedra, {} boundary facets",
        m1.n_nodes(),
        m1.n_elements(),
        m2.n_nodes(),
        so.n_vertices,
        m2.n_elements(),
        m2.boundary.len()
    );
    assert!((100..=1000).contains(&m2.n_elements()), "a small mesh: {} tetrahedra", m2.n_elements());
    assert!(p2.warnings.is_empty(), "{:?}", p2.warnings);
    assert_eq!((p1.unused_nodes, p2.unused_nodes), (0, 0));
    // (a) the same tetrahedra and vertices
    assert_eq!(m2.n_elements(), m1.n_elements());
    assert_eq!(so.n_vertices, m1.n_nodes());
    assert_eq!(m2.first_order().n_nodes(), m1.n_nodes());
    // the box (0, 2) × (0, 1)²: volume 2 up to the rounding of the sum (measured 8.9e-16,
    // tolerance 2×); the second-order mesh sums the same volumes in the same order: equal
    // (measured 0)
    let (v1, v2) = (total_volume(m1), total_volume(m2));
    println!("volume − 2: {:e}; second-order − first-order: {:e}", v1 - 2.0, v2 - v1);
    assert!((v1 - 2.0).abs() <= 1.8e-15 && v2 == v1, "volumes {v1} and {v2}");
    // Gmsh renumbers the nodes when it raises the order but keeps the element tags: element by
    // element, the same vertex positions in the same local order
    let vertices = |imp: &GmshImport| -> BTreeMap<u64, [[f64; 3]; 4]> {
        imp.element_tags.iter().zip(&imp.mesh.tets).map(|(&e, t)| (e, t.map(|n| imp.mesh.nodes[n]))).collect()
    };
    assert_eq!(vertices(&p2), vertices(&p1));
    // the vertices come first in the numbering: the first-order mesh keeps their indices
    assert!(m2.tets.iter().flatten().all(|&n| n < so.n_vertices));
    assert_eq!(m2.first_order().nodes[..], m2.nodes[..so.n_vertices]);
    // the same facet groups, of the same facets: the same areas, summed in the same order
    // (measured difference 0)
    assert_eq!(m2.group_names(), vec!["bottom", "sides", "top"]);
    assert_eq!(m2.group_names(), m1.group_names());
    for (g, facets) in &m1.groups {
        assert_eq!(m2.groups[g].len(), facets.len(), "group {g}");
        let a1: f64 = facets.iter().map(|&f| area(m1, f)).sum();
        let a2: f64 = m2.groups[g].iter().map(|&f| area(m2, f)).sum();
        assert_eq!(a1, a2, "group {g}: areas");
    }
    // and `type = "gmsh"` builds the second-order mesh
    let built = GmshMesh::new("box_p2.msh").build(&repo("tests/data")).unwrap();
    assert_eq!(built.second_order, m2.second_order);
}

#[test]
fn second_order_box_edge_nodes_sit_on_their_edges() {
    let path = repo("tests/data/box_p2.msh");
    let imp = read_msh(&path, 1.0).unwrap();
    let m = &imp.mesh;
    let so = m.second_order.as_ref().unwrap();
    // (b) in the file's own coordinates (before the reader moves anything), every edge node of
    // every tetrahedron is the midpoint of the two vertices of its edge TET_EDGES[k]: the map
    // from Gmsh's local order. Gmsh's midpoints, printed with 16 digits, agree with the ones
    // computed here to rounding: measured 2.5e-15 of the edge's length, tolerance 2× that (a
    // wrong map puts the node a whole half-edge or more away)
    let file = file_coordinates(&path);
    let x = |n: usize| file[&imp.node_tags[n]];
    let mut worst: f64 = 0.0;
    for (t, edges) in m.tets.iter().zip(&so.tet_edges) {
        for (k, &[i, j]) in TET_EDGES.iter().enumerate() {
            let (a, b) = (x(t[i]), x(t[j]));
            worst = worst.max(dist(x(edges[k]), midpoint(a, b)) / dist(a, b));
        }
    }
    println!("largest distance of an edge node from its midpoint, relative to the edge: {worst:e}");
    assert!(worst <= 4.9e-15, "{worst:e}");
    // and in the mesh, where the reader set each to ½ (a + b), computed here the same way:
    // equal (measured 0)
    for (t, edges) in m.tets.iter().zip(&so.tet_edges) {
        for (k, &[i, j]) in TET_EDGES.iter().enumerate() {
            assert_eq!(m.nodes[edges[k]], midpoint(m.nodes[t[i]], m.nodes[t[j]]));
        }
    }

    // (c) the facet edge nodes of each group on the group's plane, each the midpoint of its
    // edge TRI_EDGES[k] of the facet: on the plane exactly (Gmsh writes the planes' coordinates
    // 0, 1, 2 exactly, and the midpoint of two equal numbers is that number; measured 0), at the
    // midpoint to the rounding of (b)
    let on_plane = |g: &str, p: [f64; 3]| match g {
        "bottom" => p[2] == 0.0,
        "top" => p[2] == 1.0,
        "sides" => p[0] == 0.0 || p[0] == 2.0 || p[1] == 0.0 || p[1] == 1.0,
        _ => unreachable!(),
    };
    for (g, facets) in &m.groups {
        for &f in facets {
            let corners = m.boundary[f];
            let edges = so.facet_edges[f];
            // the plane of the facet: the coordinate its three vertices share
            let axis = (0..3).find(|&c| corners.iter().all(|&n| x(n)[c] == x(corners[0])[c]));
            let axis = axis.unwrap_or_else(|| panic!("facet {f} of {g} is not axis-aligned"));
            for (k, &[i, j]) in TRI_EDGES.iter().enumerate() {
                let e = edges[k];
                assert!(on_plane(g, x(e)) && on_plane(g, m.nodes[e]), "group {g}: edge node at {:?}", x(e));
                assert!(x(e)[axis] == x(corners[0])[axis], "group {g}: off the facet's plane");
                let (a, b) = (x(corners[i]), x(corners[j]));
                assert!(dist(x(e), midpoint(a, b)) <= 4.9e-15 * dist(a, b), "group {g}: facet edge {k}");
            }
        }
    }

    // (d) one edge node per edge: as many distinct edge nodes as distinct edges, each edge with
    // one node, every node not a vertex an edge node
    let mut node_of_edge: HashMap<(usize, usize), usize> = HashMap::new();
    for (t, edges) in m.tets.iter().zip(&so.tet_edges) {
        for (k, &[i, j]) in TET_EDGES.iter().enumerate() {
            let key = (t[i].min(t[j]), t[i].max(t[j]));
            assert_eq!(*node_of_edge.entry(key).or_insert(edges[k]), edges[k], "edge {key:?}");
        }
    }
    let edge_nodes: BTreeSet<usize> = so.tet_edges.iter().flatten().copied().collect();
    println!("{} edges, {} edge nodes, {} nodes", node_of_edge.len(), edge_nodes.len(), m.n_nodes());
    assert_eq!(edge_nodes.len(), node_of_edge.len());
    assert_eq!(edge_nodes, (so.n_vertices..m.n_nodes()).collect());
}

#[test]
fn curved_second_order_mesh_is_straightened_with_a_warning() {
    let path = repo("tests/data/cylinder_p2.msh");
    let imp = read_msh(&path, 1.0).unwrap();
    let m = &imp.mesh;
    let so = m.second_order.as_ref().unwrap();
    // the file's largest move of an edge node to its midpoint, relative to the edge. Gmsh
    // divides the circles of the base and the top into 7 equal arcs of θ = 2π/7 and puts each
    // arc's edge node on the circle: off the chord's midpoint by the sagitta R (1 − cos θ/2), a
    // fraction tan(θ/4)/2 = tan(π/14)/2 = 0.1141 of the chord 2R sin θ/2, the largest move
    // (the side's other edges span smaller angles of the circle). Measured: equal to 1.1e-16;
    // tolerance 2× that.
    let file = file_coordinates(&path);
    let x = |n: usize| file[&imp.node_tags[n]];
    let mut moved: f64 = 0.0;
    for (t, edges) in m.tets.iter().zip(&so.tet_edges) {
        for (k, &[i, j]) in TET_EDGES.iter().enumerate() {
            let (a, b) = (x(t[i]), x(t[j]));
            moved = moved.max(dist(x(edges[k]), midpoint(a, b)) / dist(a, b));
            // the mesh's edge nodes are at the midpoints ½ (a + b), computed here the same way
            assert_eq!(m.nodes[edges[k]], midpoint(m.nodes[t[i]], m.nodes[t[j]]));
        }
    }
    println!("cylinder_p2.msh: {} tetrahedra, largest relative move {moved:e}; {:?}", m.n_elements(), imp.warnings);
    let sagitta = (std::f64::consts::PI / 14.0).tan() / 2.0;
    println!("largest relative move − tan(π/14)/2 = {:e}", moved - sagitta);
    assert!((moved - sagitta).abs() <= 2.2e-16, "largest relative move {moved:e}, expected {sagitta:e}");
    assert_eq!(imp.warnings.len(), 1, "{:?}", imp.warnings);
    let w = &imp.warnings[0];
    assert!(w.contains(&format!("{moved:.2e}")) && w.contains("straight"), "{w}");
    // the straight-sided mesh: inscribed in the cylinder (π R² H = π/4), below its volume by the
    // segments cut off the 7 arcs and more (measured 9.6 %); the lower bound 0.8 π/4 allows 2×
    let v = total_volume(m);
    println!("volume / (π R² H) = {:.4}", v / (0.25 * std::f64::consts::PI));
    assert!(v < 0.25 * std::f64::consts::PI && v > 0.8 * 0.25 * std::f64::consts::PI, "volume {v}");
    assert_eq!(m.group_names(), vec!["base"]);
}

#[test]
fn mixed_order_tetrahedra_are_refused() {
    // (e) box_p2.msh with one more element block: a 4-node tetrahedron (the corners of its first
    // 10-node tetrahedron), after the 10-node block
    let p2 = std::fs::read_to_string(repo("tests/data/box_p2.msh")).unwrap();
    let section = |text: &str, name: &str| -> String {
        let start = text.find(&format!("${name}\n")).unwrap();
        let end = text.find(&format!("$End{name}\n")).unwrap() + name.len() + 5;
        text[start..end].to_string()
    };
    let elements = section(&p2, "Elements");
    let lines: Vec<&str> = elements.lines().collect();
    let header = lines.iter().position(|l| l.split_whitespace().nth(2) == Some("11")).unwrap();
    let n: usize = lines[header].split_whitespace().nth(3).unwrap().parse().unwrap();
    let first: Vec<&str> = lines[header + 1].split_whitespace().collect();
    let counts: Vec<usize> = lines[1].split_whitespace().map(|t| t.parse().unwrap()).collect();
    let mut mixed: Vec<String> =
        vec!["$Elements".into(), format!("{} {} {} {}", counts[0] + 1, counts[1] + 1, counts[2], counts[3] + 1)];
    mixed.extend(lines[2..header + 1 + n].iter().map(|l| l.to_string()));
    mixed.push("3 1 4 1".into());
    mixed.push(format!("{} {}", counts[3] + 1, first[1..5].join(" ")));
    mixed.extend(lines[header + 1 + n..].iter().map(|l| l.to_string()));
    let text = p2.replace(&elements, &(mixed.join("\n") + "\n"));
    assert_ne!(text, p2);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("mixed.msh");
    std::fs::write(&file, &text).unwrap();
    let err = read_msh(&file, 1.0).unwrap_err().to_string();
    println!("{err}");
    assert_contains(
        &err,
        &[
            "mixed.msh",
            "mixes first- and second-order tetrahedra",
            "10-node tetrahedra (element type 11) in volume 1 and 4-node tetrahedra (element type 4) in volume 1",
        ],
    );
}
