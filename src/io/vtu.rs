//! `solution.vtu`: the fields of a solve for ParaView — u, σ, von Mises stress, the hardening
//! variables, the plastic flag and strain, the contact force — as a VTK XML unstructured grid;
//! [`write_grid`] writes any point and cell fields on an element's cells (`mechanism.vtu` of
//! `saddle limit`).

use super::summary::plastic_strains;
use saddle_core::problem::tensor::{to_vtk, von_mises};
use saddle_core::{Discretisation, ProblemView, Solution};
use std::io::Write;
use std::path::Path;

/// Writes `solution.vtu`: a VTK XML unstructured grid with raw appended binary data, with
/// linear tetrahedra (VTK type 10) for `p1` and quadratic ones (type 24, the edge nodes in
/// VTK's order) on a second-order mesh. Point data: `displacement`, `contact_force` (Gᵀλ at the
/// nodes), with friction `contact_status` (0 separated, 1 stick, 2 slip; theory §8.3). Cell data, the mean over the element's stress points when it has several: `stress`
/// (symmetric tensor, VTK order xx yy zz xy yz xz), `von_mises` (of the mean stress), the
/// hardening variables under the names the yield surface gives them (`xi` for von Mises),
/// `plastic` (0/1: one of the element's points is plastic), and with plasticity
/// `plastic_strain` (tensor, ε(u) − Aσ) and `equivalent_plastic_strain` (√(2/3)|ε_p|). A run adds
/// `error_indicator` (theory §15) through [`write_piece`]'s `cells`.
pub fn write_vtu(path: &Path, p: ProblemView<'_>, sol: &Solution) -> std::io::Result<()> {
    write_piece(path, p, sol, &[]).map(drop)
}

/// A cell field computed outside the solution (the error indicators of theory §15): its name
/// and one value per element.
pub type CellField<'a> = (&'static str, &'a [f64]);

/// [`write_vtu`] for a rank's part of a distributed problem (theory §12): its elements on its
/// nodes, ghosts included. Returns the declarations of the data arrays, for the `.pvtu` file
/// that lists the pieces ([`write_pvtu`]). Collective (the ghosts' displacements come from their
/// owners).
/// `cells`: further cell fields, one value per element (`error_indicator`).
pub fn write_piece(
    path: &Path,
    p: ProblemView<'_>,
    sol: &Solution,
    cells: &[CellField<'_>],
) -> std::io::Result<String> {
    let (l, element) = (&p.l, p.element);
    let mesh = element.mesh();
    let k = element.points_per_element();
    let mean_stress: Vec<saddle_core::Sym> =
        sol.stress.sigma.chunks(k).map(|s| s.iter().sum::<saddle_core::Sym>() / k as f64).collect();
    let plastic: Vec<u8> = sol.stress.plastic.chunks(k).map(|p| p.iter().any(|x| *x) as u8).collect();
    let disp = p.displacements(&sol.u);
    let mut gu = vec![0.0; l.n_dofs()];
    let mut gv = vec![0.0; l.n_extras()];
    l.data.rows.add_transpose(&sol.lambda, &mut gu, &mut gv);
    let force = element.nodal_vectors(&gu);
    let mut arrays: Vec<DataArray> = vec![
        ("point", "displacement", 3, f64_bytes(disp.iter().flatten().copied())),
        ("point", "contact_force", 3, f64_bytes(force.iter().flatten().copied())),
        ("cell", "stress", 6, f64_bytes(mean_stress.iter().flat_map(to_vtk))),
        ("cell", "von_mises", 1, f64_bytes(mean_stress.iter().map(von_mises))),
    ];
    // the hardening variables, one cell field per name the yield surface gives them
    if let Some(yield_surface) = l.data.plasticity() {
        let mut first = 0;
        for (name, comps) in yield_surface.hardening_fields() {
            let field = (0..mesh.n_elements()).flat_map(|e| {
                (first..first + comps).map(move |c| (0..k).map(|q| sol.stress.q(e * k + q)[c]).sum::<f64>() / k as f64)
            });
            arrays.push(("cell", name, comps, f64_bytes(field.into_iter())));
            first += comps;
        }
    }
    // with friction (theory §8.3): 0 separated, 1 stick, 2 slip at each node (0 off the rows)
    if l.data.rows.has_friction() {
        let mut status = vec![0.0; mesh.n_nodes()];
        for (n, s) in saddle_core::problem::displacements::contact_status(l.data.rows, &sol.lambda) {
            status[n] = f64::from(s as u8);
        }
        arrays.push(("point", "contact_status", 1, f64_bytes(status.into_iter())));
    }
    arrays.push(("cell", "plastic", 1, plastic));
    // the plastic strain ε_p = ε(u) − Aσ (theory §11.1), element means: after unloading the
    // residual plastic strain
    if l.data.plasticity().is_some() {
        let mut eps = vec![saddle_core::Sym::zeros(); l.n_points()];
        l.total_strain(&sol.u, &mut eps);
        let ep = plastic_strains(l.data.elasticity, &eps, sol);
        let mean: Vec<saddle_core::Sym> = ep.chunks(k).map(|s| s.iter().sum::<saddle_core::Sym>() / k as f64).collect();
        arrays.push(("cell", "plastic_strain", 6, f64_bytes(mean.iter().flat_map(to_vtk))));
        let eq = ep.chunks(k).map(|s| s.iter().map(|p| (2.0f64 / 3.0).sqrt() * p.norm()).sum::<f64>() / k as f64);
        arrays.push(("cell", "equivalent_plastic_strain", 1, f64_bytes(eq.into_iter())));
    }
    for (name, values) in cells {
        arrays.push(("cell", name, 1, f64_bytes(values.iter().copied())));
    }
    write_grid(path, element, arrays)
}

/// A named data array of a VTK grid: (section — `point` or `cell` —, name, components, raw
/// little-endian bytes).
pub type DataArray = (&'static str, &'static str, usize, Vec<u8>);

/// The little-endian bytes of `values`.
pub fn f64_bytes(values: impl Iterator<Item = f64>) -> Vec<u8> {
    values.flat_map(f64::to_le_bytes).collect()
}

/// Writes a VTK XML unstructured grid of `element`'s mesh and cells (raw appended binary) with
/// the point and cell `arrays` (Float64, but `plastic` as UInt8). Returns the arrays'
/// declarations for a `.pvtu` file listing this grid as a piece ([`write_pvtu`]).
pub fn write_grid(path: &Path, element: &dyn Discretisation, mut arrays: Vec<DataArray>) -> std::io::Result<String> {
    let mesh = element.mesh();
    arrays.push(("points", "Points", 3, f64_bytes(mesh.nodes.iter().flatten().copied())));
    // the element's VTK cell, its nodes as the mesh lists them
    let cell = element.vtk_cell();
    let (per_cell, cell_type) = (cell.nodes, cell.type_id);
    let conn: Vec<u8> =
        (0..mesh.n_elements()).flat_map(|e| mesh.element_nodes(e)).flat_map(|n| (n as i64).to_le_bytes()).collect();
    let offs: Vec<u8> = (1..=mesh.n_elements()).flat_map(|e| ((per_cell * e) as i64).to_le_bytes()).collect();
    arrays.push(("cells", "connectivity", 1, conn));
    arrays.push(("cells", "offsets", 1, offs));
    arrays.push(("cells", "types", 1, vec![cell_type; mesh.n_elements()]));

    let vtk_type = |name: &str| match name {
        "plastic" | "types" => "UInt8",
        "connectivity" | "offsets" => "Int64",
        _ => "Float64",
    };
    // the declarations of a .pvtu file, the same arrays without data
    let vectors = arrays.iter().find(|a| a.0 == "point").map_or("", |a| a.1);
    let point_data = format!("PPointData Vectors=\"{vectors}\"");
    let mut parallel = String::new();
    for (which, tag) in [
        ("point", point_data.as_str()),
        ("cell", "PCellData Scalars=\"von_mises\" Tensors=\"stress\""),
        ("points", "PPoints"),
    ] {
        parallel.push_str(&format!("    <{tag}>\n"));
        for (_, name, comps, _) in arrays.iter().filter(|a| a.0 == which) {
            let t = vtk_type(name);
            parallel.push_str(&format!(
                "      <PDataArray type=\"{t}\" Name=\"{name}\" NumberOfComponents=\"{comps}\"/>\n"
            ));
        }
        parallel.push_str(&format!("    </{}>\n", tag.split(' ').next().unwrap_or(tag)));
    }
    let mut xml = String::new();
    let mut offset = 0usize;
    let mut section = |xml: &mut String, which: &str| {
        for (_, name, comps, bytes) in arrays.iter().filter(|a| a.0 == which) {
            xml.push_str(&format!(
                "        <DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"appended\" offset=\"{}\"/>\n",
                vtk_type(name),
                name,
                comps,
                offset
            ));
            offset += 8 + bytes.len();
        }
    };
    xml.push_str("<?xml version=\"1.0\"?>\n");
    xml.push_str(
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
    );
    xml.push_str("  <UnstructuredGrid>\n");
    xml.push_str(&format!(
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n",
        mesh.n_nodes(),
        mesh.n_elements()
    ));
    xml.push_str(&format!("      <PointData Vectors=\"{vectors}\">\n"));
    section(&mut xml, "point");
    xml.push_str("      </PointData>\n      <CellData Scalars=\"von_mises\" Tensors=\"stress\">\n");
    section(&mut xml, "cell");
    xml.push_str("      </CellData>\n      <Points>\n");
    section(&mut xml, "points");
    xml.push_str("      </Points>\n      <Cells>\n");
    section(&mut xml, "cells");
    xml.push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n_");
    let mut file = std::io::BufWriter::new(std::fs::File::create(path)?);
    file.write_all(xml.as_bytes())?;
    // appended blocks in the order the XML declares them
    for which in ["point", "cell", "points", "cells"] {
        for (_, _, _, bytes) in arrays.iter().filter(|a| a.0 == which) {
            file.write_all(&(bytes.len() as u64).to_le_bytes())?;
            file.write_all(bytes)?;
        }
    }
    file.write_all(b"\n  </AppendedData>\n</VTKFile>\n")?;
    file.flush()?;
    Ok(parallel)
}

/// A `.pvtu` file (VTK's parallel unstructured grid, which ParaView opens as one grid): the
/// data arrays `declarations` ([`write_piece`]'s) and one piece per rank, its file named
/// relative to the `.pvtu`'s folder.
pub fn write_pvtu(path: &Path, declarations: &str, pieces: &[String]) -> std::io::Result<()> {
    let mut xml = String::from("<?xml version=\"1.0\"?>\n");
    xml.push_str(
        "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
    );
    xml.push_str("  <PUnstructuredGrid GhostLevel=\"0\">\n");
    xml.push_str(declarations);
    for piece in pieces {
        xml.push_str(&format!("    <Piece Source=\"{piece}\"/>\n"));
    }
    xml.push_str("  </PUnstructuredGrid>\n</VTKFile>\n");
    std::fs::write(path, xml)
}
