//! solution.vtu decodes back to the solution; the default scene's mesh resolves the contact
//! zone as SPEC §6 asks.

mod common;
use common::*;
use saddle::core::{Lagrangian, Silent};
use saddle::output::write_vtu;
use saddle::scene::Scene;

/// The Float64 array `name` of a VTU file with raw appended data.
fn read_array(vtu: &[u8], name: &str) -> Vec<f64> {
    let text = String::from_utf8_lossy(vtu);
    let decl = text.find(&format!("Name=\"{name}\"")).unwrap_or_else(|| panic!("no array {name}"));
    let tail = &text[decl..];
    let off_at = tail.find("offset=\"").unwrap() + 8;
    let offset: usize = tail[off_at..tail[off_at..].find('"').unwrap() + off_at].parse().unwrap();
    let start = vtu.windows(2).position(|w| w == b"\n_").unwrap() + 2 + offset;
    let len = u64::from_le_bytes(vtu[start..start + 8].try_into().unwrap()) as usize;
    vtu[start + 8..start + 8 + len].chunks(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect()
}

#[test]
fn vtu_arrays_decode_to_the_solution() {
    let (l, solver) = build(&small_johnson());
    let sol = solver.unwrap().solve(&l, &mut Silent).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.vtu");
    write_vtu(&path, &l, &sol).unwrap();
    let vtu = std::fs::read(&path).unwrap();
    let disp = read_array(&vtu, "displacement");
    let exact: Vec<f64> = l.nodal_displacements(&sol.u).into_iter().flatten().collect();
    assert_eq!(disp, exact);
    let points = read_array(&vtu, "Points");
    assert_eq!(points.len(), 3 * l.mesh().n_nodes());
    assert_eq!(points[3..6], l.mesh().nodes[1]);
    // the contact force field sums to F in x₃
    let force = read_array(&vtu, "contact_force");
    let fz: f64 = force.chunks(3).map(|c| c[2]).sum();
    assert!((fz - 0.3).abs() < 1e-9, "Σ contact force = {fz}");
    // von Mises stress of element 0, and σ in VTK order (xx yy zz xy yz xz)
    let vm = read_array(&vtu, "von_mises");
    assert_eq!(vm.len(), l.n_points());
    assert!((vm[0] - saddle::core::problem::tensor::von_mises(&sol.stress.sigma[0])).abs() < 1e-15);
    let sigma = read_array(&vtu, "stress");
    let s0 = saddle::core::problem::tensor::to_matrix(&sol.stress.sigma[0]);
    assert!((sigma[3] - s0[(0, 1)]).abs() < 1e-15 && (sigma[4] - s0[(1, 2)]).abs() < 1e-15);
}

#[test]
fn default_scene_resolves_the_contact_zone() {
    // SPEC §6: at least 8 elements across the contact diameter (≈ 0.46), i.e. an element size
    // of at most about 0.055 there.
    let scene = Scene::from_file(&repo("examples/johnson.toml")).unwrap();
    let mesh = scene.mesh.build(&repo("examples")).unwrap();
    let mut largest: f64 = 0.0;
    let mut across = 0;
    for (e, t) in mesh.tets.iter().enumerate() {
        let c: Vec<[f64; 3]> = t.iter().map(|&n| mesh.nodes[n]).collect();
        let on_bottom = c.iter().filter(|x| x[2] == 0.0).count() == 3;
        let r = c.iter().map(|x| x[0].hypot(x[1])).fold(0.0, f64::max);
        if on_bottom && r <= 0.23 {
            largest = largest.max(mesh.element_size(e));
        }
    }
    // distinct grid lines along x₁ inside the contact diameter
    let mut xs: Vec<f64> =
        mesh.nodes.iter().filter(|x| x[1] == 0.0 && x[2] == 0.0 && x[0].abs() <= 0.23).map(|x| x[0]).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    across += xs.len() - 1;
    assert!(largest <= 0.055 * 3f64.sqrt(), "largest bottom element in the contact zone: {largest}");
    assert!(across >= 8, "only {across} element edges across the contact diameter");
}
