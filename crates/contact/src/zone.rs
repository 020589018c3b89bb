//! The candidate contact zone Γ₀ on a mesh (theory §1, §3): which boundary nodes carry a contact
//! row, and where the contact set meets the rim of the zone. Shared by every node-based
//! obstacle (the punches of this crate, the rigid sphere, and plugins: see the crate docs). The
//! punches select nodes with a free u₃ on a flat face ([`Selection::Vertical`]); an obstacle with
//! a general normal selects nodes with any free dof ([`Selection::AnyFreeDof`]).

use saddle_core::error::join;
use saddle_core::{ConstraintRows, DofMap, Region, SceneError, TetMesh};

/// The contact nodes selected by a zone, with what the user should know about the selection.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CandidateNodes {
    /// Boundary nodes of the zone the [`Selection`] keeps (u₃ free for the punches), sorted: one
    /// contact row each (theory §3).
    pub nodes: Vec<usize>,
    /// Nodes dropped because a Dirichlet condition fixes their u₃ (or all their dofs), a
    /// non-planar zone, ...
    pub warnings: Vec<String>,
}

/// Which boundary nodes of a zone can carry a contact row: what the obstacle's rows act on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Selection {
    /// The vertical gap `u₃ + φ − w` of the punches (theory §1, §3): a row acts on u₃ only, so
    /// nodes with u₃ fixed are dropped, and a zone not lying in one horizontal plane is warned
    /// about (the gap measures vertical distance from a flat contact face).
    #[default]
    Vertical,
    /// A gap along a normal that varies from node to node (the rigid sphere, theory §8): a row
    /// acts on the free dofs among u₁, u₂, u₃ of its node, so only nodes with all three fixed
    /// are dropped, and the zone may be curved or span several faces (no planarity warning).
    AnyFreeDof,
}

impl Selection {
    /// Whether node `n` keeps a row.
    fn keeps(self, dofs: &DofMap, n: usize) -> bool {
        match self {
            Selection::Vertical => dofs.free(n, 2).is_some(),
            Selection::AnyFreeDof => (0..3).any(|c| dofs.free(n, c).is_some()),
        }
    }

    /// What the dropped nodes have fixed.
    fn fixed_what(self) -> &'static str {
        match self {
            Selection::Vertical => "u₃",
            Selection::AnyFreeDof => "all of u₁, u₂, u₃",
        }
    }
}

/// The contact nodes x_i ∈ Γ₀ of `zone` for the punches' vertical gap (theory §3):
/// [`candidate_nodes_with`] and [`Selection::Vertical`]. `path` is the obstacle's table; errors
/// and warnings name `{path}.zone`.
///
/// Errors ([`SceneError::Region`]): a zone naming a facet group the mesh lacks (the message
/// lists the mesh's groups), a zone selecting no boundary node, and a zone whose every node has
/// u₃ fixed. Nodes with u₃ fixed by a Dirichlet condition cannot be contact nodes — Γ₀ must lie
/// strictly inside Γ₁ (theory §1) — so they are dropped with a warning. A zone whose nodes do not
/// share one x₃ level gets a warning: the gap u₃ + φ − U measures vertical distance from a flat
/// contact face (theory §1: Γ₁ lies in a plane).
pub fn candidate_nodes(zone: &Region, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<CandidateNodes, SceneError> {
    candidate_nodes_with(zone, mesh, dofs, path, Selection::Vertical)
}

/// The contact nodes of `zone` under `selection` (see [`Selection`]; [`candidate_nodes`] for
/// the errors). Nodes the selection cannot use (u₃ fixed, or all three dofs fixed) are dropped
/// with a warning; every node dropped is an error.
pub fn candidate_nodes_with(
    zone: &Region,
    mesh: &TetMesh,
    dofs: &DofMap,
    path: &str,
    selection: Selection,
) -> Result<CandidateNodes, SceneError> {
    let field = join(path, "zone");
    let missing = zone.missing_groups(mesh);
    if !missing.is_empty() {
        return Err(SceneError::Region {
            field,
            message: format!("no facet group named {:?}; the mesh has {:?}", missing, mesh.group_names()),
        });
    }
    let selected = zone.nodes(mesh);
    if selected.is_empty() {
        return Err(SceneError::Region {
            field,
            message: "selects no boundary node: there is no candidate contact node".into(),
        });
    }
    let (nodes, fixed): (Vec<usize>, Vec<usize>) = selected.iter().partition(|&&n| selection.keeps(dofs, n));
    let mut warnings = Vec::new();
    if !fixed.is_empty() {
        let x = mesh.nodes[fixed[0]];
        let what = format!(
            "{} of its {} nodes (e.g. node {} at ({}, {}, {})) have {} fixed by a Dirichlet condition",
            fixed.len(),
            selected.len(),
            fixed[0],
            x[0],
            x[1],
            x[2],
            selection.fixed_what()
        );
        if nodes.is_empty() {
            return Err(SceneError::Region {
                field,
                message: format!("all {what}; no contact node is left (Γ₀ must lie strictly inside Γ₁, theory §1)"),
            });
        }
        warnings.push(format!(
            "{field}: {what} and were dropped: clamped nodes cannot be contact nodes (Γ₀ must lie strictly inside Γ₁, theory §1); \
             {} contact nodes remain",
            nodes.len()
        ));
    }
    if selection == Selection::Vertical {
        let (lo, hi) = nodes.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &n| {
            (lo.min(mesh.nodes[n][2]), hi.max(mesh.nodes[n][2]))
        });
        if hi - lo > 1e-9 * mesh.diameter() {
            warnings.push(format!(
                "{field}: the contact nodes span x₃ ∈ [{lo}, {hi}]; the gap u₃ + φ − U assumes a flat contact face \
                 (theory §1: Γ₁ lies in a plane), so the zone should select one horizontal face"
            ));
        }
    }
    Ok(CandidateNodes { nodes, warnings })
}

/// Relative tolerance on a facet's normal component when deciding whether it faces the obstacle.
const FACING_TOL: f64 = 1e-8;

/// The rows of `contact` (row indices) whose node lies on the rim of the candidate zone: it
/// shares a boundary facet facing the punch (outward normal with n₃ < 0) with a boundary node
/// that carries no row. Contact there means the contact set was clipped by the zone (or by the
/// clamped boundary next to it) and the zone should be enlarged. Facets not facing the punch
/// (the sides of the body) do not count, so a zone covering a whole face has no rim.
/// [`rim_rows_facing`] with "facing" = n₃ < 0.
pub fn rim_rows(mesh: &TetMesh, rows: &ConstraintRows, contact: &[usize]) -> Vec<usize> {
    rim_rows_facing(mesh, rows, contact, |normal, _| normal[2] < -FACING_TOL * norm(normal))
}

/// [`rim_rows`] for an obstacle that is not below the body: `faces(normal, centroid)` says
/// whether a boundary facet, with outward normal `normal` (length twice the facet's area) and
/// centroid `centroid`, faces the obstacle. The rigid sphere (theory §8) uses
/// `normal·(c − centroid) > 0`: the facet looks towards the sphere's centre c.
pub fn rim_rows_facing(
    mesh: &TetMesh,
    rows: &ConstraintRows,
    contact: &[usize],
    faces: impl Fn([f64; 3], [f64; 3]) -> bool,
) -> Vec<usize> {
    let mut in_zone = vec![false; mesh.n_nodes()];
    for &n in &rows.node {
        in_zone[n] = true;
    }
    let mut on_rim = vec![false; mesh.n_nodes()];
    for (fi, f) in mesh.boundary.iter().enumerate() {
        let [a, b, c] = f.map(|i| mesh.nodes[i]);
        let centroid = std::array::from_fn(|k| (a[k] + b[k] + c[k]) / 3.0);
        if !faces(tri_normal(a, b, c), centroid) {
            continue;
        }
        // the triangles whose nodes are neighbours: the facet itself, or on a second-order mesh
        // its four corner-and-midpoint triangles (a facet of P2 spans two of P1's, so its far
        // corner is not a neighbour of the node it is measured from)
        let (triangles, count) = match &mesh.second_order {
            None => ([*f; 4], 1),
            Some(so) => {
                let [ab, bc, ca] = so.facet_edges[fi];
                ([[f[0], ab, ca], [f[1], bc, ab], [f[2], ca, bc], [ab, bc, ca]], 4)
            }
        };
        for t in &triangles[..count] {
            if t.iter().any(|&n| !in_zone[n]) {
                t.iter().for_each(|&n| on_rim[n] = true);
            }
        }
    }
    contact.iter().copied().filter(|&i| on_rim[rows.node[i]]).collect()
}

/// (b − a) × (c − a): the outward normal of an outward-oriented facet, of length twice its area.
pub fn tri_normal(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 3] {
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// Each row's share of the contact face, ∫_Γ N_i over the boundary facets facing the punch
/// (outward normal n₃ < 0) — the nodal area that turns a contact force λ_i, the consistent
/// force ∫ N_i p of a pressure p, into that pressure. On a first-order mesh a third of every
/// facet at each of its nodes; on a second-order one ∫N = 0 at a 6-node facet's vertices and a
/// third of the facet at each edge node (theory §10.1): a vertex row carries no force under a
/// smooth pressure and has no area, so its pressure is not defined (and not reported).
/// [`node_areas_facing`] with "facing" = n₃ < 0. Rows recombined from nodal rows get the
/// recombined weights (theory §10.1: 2|F|/15 at a dual quadratic facet's vertices, |F|/5 at
/// its edge nodes).
pub fn row_areas(mesh: &TetMesh, rows: &ConstraintRows) -> Vec<f64> {
    let area = node_areas_below(mesh, &rows.node);
    // recombined rows (P2's dual quadratic rows, theory §10.1): ∫Ñ_j = Σ_k T_kj ∫N_k
    match &rows.combination {
        None => area,
        Some(c) => c.weights_from_nodal(&area),
    }
}

/// The share of the contact face of each node of `nodes` for an obstacle below the body:
/// [`node_areas_facing`] with "facing" = n₃ < 0 (the punches' weights of theory §8.3).
pub fn node_areas_below(mesh: &TetMesh, nodes: &[usize]) -> Vec<f64> {
    node_areas_facing(mesh, nodes, |normal, _| normal[2] < -FACING_TOL * norm(normal))
}

/// The share of the contact face of each node of `nodes`, ∫_Γ N_i over the boundary facets
/// facing the obstacle (`faces(normal, centroid)` as in [`rim_rows_facing`]): a third of every
/// such facet at each corner on a first-order mesh; on a second-order one 0 at a 6-node facet's
/// vertices and a third of the facet at each edge node (theory §10.1).
pub fn node_areas_facing(mesh: &TetMesh, nodes: &[usize], faces: impl Fn([f64; 3], [f64; 3]) -> bool) -> Vec<f64> {
    let mut listed = vec![false; mesh.n_nodes()];
    for &n in nodes {
        listed[n] = true;
    }
    let mut area = vec![0.0; mesh.n_nodes()];
    let mut add = |n: usize, a: f64| {
        if listed[n] {
            area[n] += a;
        }
    };
    for (fi, f) in mesh.boundary.iter().enumerate() {
        let [a, b, c] = f.map(|i| mesh.nodes[i]);
        let centroid = std::array::from_fn(|k| (a[k] + b[k] + c[k]) / 3.0);
        let normal = tri_normal(a, b, c);
        if faces(normal, centroid) {
            let area2 = norm(normal);
            match &mesh.second_order {
                None => f.iter().for_each(|&n| add(n, area2 / 6.0)),
                // ∫N of the 6-node triangle: 0 at the vertices, |F|/3 at the edge nodes
                Some(so) => so.facet_edges[fi].iter().for_each(|&n| add(n, area2 / 6.0)),
            }
        }
    }
    nodes.iter().map(|&n| area[n]).collect()
}

/// The warning for contact rows on the rim (see [`rim_rows`]); `None` when there are none.
pub fn rim_warning(path: &str, mesh: &TetMesh, rows: &ConstraintRows, rim: &[usize]) -> Option<String> {
    let &first = rim.first()?;
    let n = rows.node[first];
    let x = mesh.nodes[n];
    let zone = join(path, "zone");
    Some(format!(
        "the contact set reaches the rim of {zone} at {} node(s) (e.g. node {n} at ({}, {}, {})): the candidate contact \
         zone is too small and the contact pressure is clipped there; enlarge {zone}",
        rim.len(),
        x[0],
        x[1],
        x[2]
    ))
}
