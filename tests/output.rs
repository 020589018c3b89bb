//! solution.vtu reads back, through an independent reader (vtkio), to the solution; the default
//! scene's mesh resolves the contact zone as theory §6 asks.

mod common;
use common::*;
use saddle::core::DiscreteProblem;
use saddle::core::problem::tensor::to_matrix;
use saddle::core::{Silent, Solution};
use saddle::io::scene::Scene;
use saddle::io::vtu::write_vtu;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;
use vtkio::model::{Attribute, CellType, DataSet, ElementType, ScalarType, UnstructuredGridPiece, Vtk};

/// Reads a VTU file with raw appended data through vtkio's XML model.
///
/// vtkio's own `Vtk::import` parses the whole file with quick-xml, which cannot read raw appended
/// bytes (they are not XML text: any `<` byte among them ends the text node, and
/// `Vtk::import` fails with `UnexpectedEof`). So the file is handed to vtkio in the two parts
/// the VTK XML format defines: the XML document before `<AppendedData encoding="raw">`,
/// deserialised into `vtkio::xml::VTKFile` by quick-xml 0.22 configured as vtkio's import
/// configures it; and the appended bytes, which "begin with the first character after the
/// underscore" and run to the closing tag. Everything else is vtkio's: the offsets, the
/// `header_type`, the byte order, the scalar types, `NumberOfComponents`, and the byte-count
/// header of each block, which vtkio checks against NumberOfPoints/NumberOfCells ×
/// NumberOfComponents × the type's size. The test knows nothing of how `write_vtu` lays out the
/// blocks.
fn read_vtu(path: &Path) -> UnstructuredGridPiece {
    let bytes = std::fs::read(path).unwrap();
    let find = |pat: &[u8]| bytes.windows(pat.len()).position(|w| w == pat);
    let open = b"<AppendedData encoding=\"raw\">";
    let start = find(open).expect("an <AppendedData encoding=\"raw\"> element");
    let xml = format!("{}</VTKFile>\n", std::str::from_utf8(&bytes[..start]).expect("the XML part is text"));
    let after = start + open.len();
    let underscore = after + bytes[after..].iter().position(|&b| b == b'_').expect("the `_` of the appended data");
    let close = b"</AppendedData>";
    let end = bytes.windows(close.len()).rposition(|w| w == close).expect("</AppendedData>");

    let mut reader = quick_xml::Reader::from_str(&xml);
    reader.expand_empty_elements(true).check_end_names(true).trim_text(true).trim_text_end(false);
    let mut file = vtkio::xml::VTKFile::deserialize(&mut quick_xml::de::Deserializer::new(reader))
        .unwrap_or_else(|e| panic!("vtkio cannot parse the XML part: {e}\n{xml}"));
    // vtkio's RawData drops the leading `_` itself
    let raw = vtkio::xml::RawData::deserialize(serde::de::value::BytesDeserializer::<serde::de::value::Error>::new(
        &bytes[underscore..end],
    ))
    .unwrap();
    file.appended_data = Some(vtkio::xml::AppendedData { encoding: vtkio::xml::Encoding::Raw, data: raw });
    let vtk = Vtk::try_from(file).unwrap_or_else(|e| panic!("vtkio rejects the file: {e:?}"));
    match vtk.data {
        DataSet::UnstructuredGrid { mut pieces, .. } => {
            assert_eq!(pieces.len(), 1, "one piece");
            pieces.remove(0).into_loaded_piece_data(None).unwrap()
        }
        other => panic!("not an unstructured grid: {other:?}"),
    }
}

/// The arrays of one section by name: (element type, values as f64 — exact for the UInt8 flags).
fn arrays(attributes: &[Attribute]) -> BTreeMap<String, (ElementType, Vec<f64>)> {
    attributes
        .iter()
        .map(|a| match a {
            Attribute::DataArray(d) => {
                (d.name.clone(), (d.elem.clone(), d.data.clone().cast_into::<f64>().expect("numeric")))
            }
            Attribute::Field { name, .. } => panic!("unexpected field data {name}"),
        })
        .collect()
}

/// Solves the scene `t` with its solver, writes its solution.vtu and reads it back.
fn solve_write_read(t: &toml::Table) -> (DiscreteProblem, Solution, UnstructuredGridPiece) {
    let (l, solver) = build(t);
    let sol = solver.unwrap().solve(&l.lagrangian(), &mut Silent).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.vtu");
    write_vtu(&path, l.view(), &sol).unwrap();
    let piece = read_vtu(&path);
    (l, sol, piece)
}

#[test]
fn vtu_reads_back_with_vtkio() {
    let (l, sol, piece) = solve_write_read(&small_johnson());
    let mesh = l.element.mesh();
    let (n_nodes, n_elements) = (mesh.n_nodes(), mesh.n_elements());

    // geometry and topology
    let points = piece.points.clone().cast_into::<f64>().unwrap();
    assert_eq!(points, mesh.nodes.iter().flatten().copied().collect::<Vec<_>>());
    let (connectivity, offsets) = piece.cells.cell_verts.clone().into_xml();
    assert_eq!(connectivity, mesh.tets.iter().flatten().map(|&n| n as u64).collect::<Vec<_>>());
    assert_eq!(offsets, (1..=n_elements as u64).map(|e| 4 * e).collect::<Vec<_>>());
    assert!(piece.cells.types.len() == n_elements && piece.cells.types.iter().all(|t| *t == CellType::Tetra));

    // every array the writer documents, with its number of components, and nothing dropped (vtkio
    // silently leaves out an attribute it cannot decode)
    let point = arrays(&piece.data.point);
    let cell = arrays(&piece.data.cell);
    let names = |m: &BTreeMap<String, (ElementType, Vec<f64>)>| m.keys().cloned().collect::<Vec<_>>();
    assert_eq!(names(&point), ["contact_force", "displacement"]);
    assert_eq!(names(&cell), ["equivalent_plastic_strain", "plastic", "plastic_strain", "stress", "von_mises", "xi"]);
    assert_eq!(point["displacement"].0, ElementType::Vectors, "PointData Vectors=\"displacement\"");
    // the declared types as vtkio decoded them: Float64 fields, UInt8 flags
    for a in piece.data.point.iter().chain(&piece.data.cell) {
        if let Attribute::DataArray(d) = a {
            let expected = if d.name == "plastic" { ScalarType::U8 } else { ScalarType::F64 };
            assert_eq!(d.data.scalar_type(), expected, "type of {}", d.name);
        }
    }
    assert_eq!(piece.points.scalar_type(), ScalarType::F64, "Points");
    let len = |m: &BTreeMap<String, (ElementType, Vec<f64>)>, k: &str| m[k].1.len();
    assert_eq!((len(&point, "displacement"), len(&point, "contact_force")), (3 * n_nodes, 3 * n_nodes));
    assert_eq!((len(&cell, "stress"), len(&cell, "von_mises")), (6 * n_elements, n_elements));
    assert_eq!((len(&cell, "xi"), len(&cell, "plastic")), (n_elements, n_elements));

    // displacement: the solution's free dofs at their nodes, 0 at the clamped ones
    let disp = &point["displacement"].1;
    let dofs = l.element.dofs();
    let mut clamped = 0;
    for n in 0..n_nodes {
        for c in 0..3 {
            let expected = dofs.free(n, c).map_or(0.0, |d| sol.u[d]);
            clamped += dofs.free(n, c).is_none() as usize;
            assert_eq!(disp[3 * n + c], expected, "u of node {n}, component {c}");
        }
    }
    assert!(clamped > 0 && clamped < 3 * n_nodes);

    // contact force: λ_i e₃ at the node of each contact row (the punch pushes along x₃, theory §3),
    // 0 elsewhere; Σ λ_i = F = 0.3
    let force = &point["contact_force"].1;
    let mut expected = vec![0.0; 3 * n_nodes];
    for (i, &n) in l.lagrangian().data.rows.node.iter().enumerate() {
        expected[3 * n + 2] += sol.lambda[i];
    }
    assert_eq!(force, &expected);
    let fz: f64 = force.chunks(3).map(|c| c[2]).sum();
    assert!((fz - 0.3).abs() < 1e-9, "Σ contact force = {fz}");
    assert!(force.iter().filter(|f| **f > 0.0).count() >= 10, "a contact patch of several nodes");

    // stress in VTK's component order xx yy zz xy yz xz, from the 3×3 tensor; the von Mises
    // stress sqrt(3/2)|dev σ| from the same tensor; ξ and the plastic flag as solved
    let (stress, vm, xi, plastic) = (&cell["stress"].1, &cell["von_mises"].1, &cell["xi"].1, &cell["plastic"].1);
    for e in 0..n_elements {
        let m = to_matrix(&sol.stress.sigma[e]);
        let vtk_order = [m[(0, 0)], m[(1, 1)], m[(2, 2)], m[(0, 1)], m[(1, 2)], m[(0, 2)]];
        for (k, x) in vtk_order.iter().enumerate() {
            assert!((stress[6 * e + k] - x).abs() <= 1e-15 * m.abs().max(), "σ of element {e}, component {k}");
        }
        let mut dev = m;
        for i in 0..3 {
            dev[(i, i)] -= m.trace() / 3.0;
        }
        let von_mises = (1.5 * dev.component_mul(&dev).sum()).sqrt();
        assert!((vm[e] - von_mises).abs() <= 1e-13 * von_mises.max(1e-300), "von Mises of element {e}");
        assert_eq!(xi[e], sol.stress.q(e)[0], "ξ of element {e}");
        assert_eq!(plastic[e], if sol.stress.plastic[e] { 1.0 } else { 0.0 }, "plastic flag of element {e}");
    }
    let n_plastic = plastic.iter().filter(|p| **p == 1.0).count();
    assert!(n_plastic > 0 && n_plastic < n_elements, "{n_plastic} plastic elements");
    // the plastic strain ε(u) − Aσ (theory §11.1), recomputed here from u and σ: zero where the
    // element is elastic, along dev σ where it is plastic (the flow rule), √(2/3)|ε_p| its size
    let (ep, eq) = (&cell["plastic_strain"].1, &cell["equivalent_plastic_strain"].1);
    let mut eps = vec![saddle::core::Sym::zeros(); n_elements];
    l.element.strain(&sol.u, &mut eps);
    let largest = eq.iter().fold(0.0f64, |m, x| m.max(*x));
    for e in 0..n_elements {
        let p = to_matrix(&(eps[e] - l.lagrangian().data.elasticity.compliance(&sol.stress.sigma[e])));
        let vtk_order = [p[(0, 0)], p[(1, 1)], p[(2, 2)], p[(0, 1)], p[(1, 2)], p[(0, 2)]];
        for (k, x) in vtk_order.iter().enumerate() {
            assert!((ep[6 * e + k] - x).abs() <= 1e-12 * largest, "ε_p of element {e}, component {k}");
        }
        assert!((eq[e] - (2.0f64 / 3.0).sqrt() * p.norm()).abs() <= 1e-12 * largest);
        if plastic[e] == 0.0 {
            assert!(eq[e] <= 1e-10 * largest, "elastic element {e} with ε_p = {}", eq[e]);
        } else {
            assert!(
                eq[e] > 1e-6 * largest && p.trace().abs() <= 1e-9 * p.norm(),
                "plastic element {e}: ε_p deviatoric"
            );
        }
    }
    // the shear components are not all alike, so a swap of two of them shows
    let (xy, yz): (Vec<f64>, Vec<f64>) = stress.chunks(6).map(|s| (s[3], s[4])).unzip();
    assert_ne!(xy, yz);
}

#[test]
fn default_scene_resolves_the_contact_zone() {
    // theory §6: at least 8 elements across the contact diameter (≈ 0.46), i.e. an element size
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

#[test]
fn p2_vtu_has_quadratic_cells_and_element_means() {
    let mut t = small_johnson();
    set(&mut t, "mesh.cells", toml::Value::try_from([6, 6, 3]).unwrap());
    let mut d = toml::Table::new();
    d.insert("type".into(), toml::Value::String("p2".into()));
    t.insert("discretisation".into(), toml::Value::Table(d));
    let (l, sol, piece) = solve_write_read(&t);
    let mesh = l.element.mesh();
    let (n_nodes, n_elements) = (mesh.n_nodes(), mesh.n_elements());
    assert!(mesh.is_second_order() && l.element.points_per_element() == 4);
    // every node, edge nodes included, with its displacement
    let points = piece.points.clone().cast_into::<f64>().unwrap();
    assert_eq!(points.len(), 3 * n_nodes);
    let (connectivity, offsets) = piece.cells.cell_verts.clone().into_xml();
    assert_eq!(offsets, (1..=n_elements as u64).map(|e| 10 * e).collect::<Vec<_>>());
    assert!(piece.cells.types.iter().all(|t| *t == CellType::QuadraticTetra));
    // VTK's quadratic tetrahedron: node 4 + k at the midpoint of edge k = (0,1), (1,2), (0,2),
    // (0,3), (1,3), (2,3) — checked on the coordinates the file holds
    let x = |n: u64| [0, 1, 2].map(|k| points[3 * n as usize + k]);
    for cell in connectivity.chunks(10) {
        for (k, [a, b]) in [[0, 1], [1, 2], [0, 2], [0, 3], [1, 3], [2, 3]].iter().enumerate() {
            let (xa, xb, xm) = (x(cell[*a]), x(cell[*b]), x(cell[4 + k]));
            assert!((0..3).all(|i| (0.5 * (xa[i] + xb[i]) - xm[i]).abs() < 1e-14), "edge {k} of {cell:?}");
        }
    }
    let point = arrays(&piece.data.point);
    let cell = arrays(&piece.data.cell);
    let disp = &point["displacement"].1;
    let dofs = l.element.dofs();
    for n in 0..n_nodes {
        for c in 0..3 {
            assert_eq!(disp[3 * n + c], dofs.free(n, c).map_or(0.0, |d| sol.u[d]), "u of node {n}");
        }
    }
    // cell stress: the mean over the element's four points; plastic when one point is
    let (stress, plastic) = (&cell["stress"].1, &cell["plastic"].1);
    for e in 0..n_elements {
        let mean =
            (0..4).map(|q| to_matrix(&sol.stress.sigma[4 * e + q])).fold(to_matrix(&Default::default()), |a, b| a + b)
                / 4.0;
        assert!((stress[6 * e] - mean[(0, 0)]).abs() <= 1e-14 * mean.abs().max().max(1e-300), "σxx of element {e}");
        assert!((stress[6 * e + 4] - mean[(1, 2)]).abs() <= 1e-14 * mean.abs().max().max(1e-300), "σyz of element {e}");
        let any = (0..4).any(|q| sol.stress.plastic[4 * e + q]);
        assert_eq!(plastic[e], if any { 1.0 } else { 0.0 });
    }
    assert!(plastic.contains(&1.0));
}
