//! Meshes and what lives on them: the tetrahedral mesh T_h (theory §3) — nodes, positively
//! oriented tetrahedra, the boundary facets and named groups of them, validated on construction
//! (a zero-volume or inverted tetrahedron is an error that names the element) — its sources
//! ([`box_mesh`], [`inline`], [`gmsh`]), boundary [`region`]s, and the numbering of the nodal
//! displacement dofs with Dirichlet conditions ([`dofs`]).

pub mod box_mesh;
pub mod dofs;
pub mod frames;
#[cfg(feature = "gmsh")]
pub mod gmsh;
pub mod inline;
pub mod region;

use crate::error::{MeshError, ParameterError};
use std::collections::BTreeMap;
use std::fmt::Debug;
use std::path::Path;

/// A conforming mesh of tetrahedra with its boundary.
#[derive(Clone, Debug)]
pub struct TetMesh {
    /// Node coordinates.
    pub nodes: Vec<[f64; 3]>,
    /// Tetrahedra (node indices), positively oriented.
    pub tets: Vec<[usize; 4]>,
    /// Boundary facets (faces of exactly one tetrahedron), oriented outward.
    pub boundary: Vec<[usize; 3]>,
    /// Named groups of boundary facets, as indices into `boundary`.
    pub groups: BTreeMap<String, Vec<usize>>,
    /// The edge nodes of a second-order mesh (10-node tetrahedra, 6-node triangles); `None` for
    /// a first-order mesh. See [`TetMesh::second_order`].
    pub second_order: Option<SecondOrder>,
}

/// The edges of a tetrahedron [v₀, v₁, v₂, v₃] in the order of VTK's quadratic tetrahedron
/// (type 24): local nodes 4…9 of a 10-node tetrahedron sit on these edges.
pub const TET_EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [0, 2], [0, 3], [1, 3], [2, 3]];

/// The edges of a triangle [a, b, c] in the order of VTK's quadratic triangle (type 22):
/// (a, b), (b, c), (c, a).
pub const TRI_EDGES: [[usize; 2]; 3] = [[0, 1], [1, 2], [2, 0]];

/// The edge nodes of a second-order mesh: one node per edge of the tetrahedra, shared by the
/// elements around the edge. The elements stay straight-sided (subparametric): the geometry is
/// the vertices', and an edge node is the midpoint of its edge.
#[derive(Clone, Debug, PartialEq)]
pub struct SecondOrder {
    /// The number of vertices (the other nodes are edge nodes).
    pub n_vertices: usize,
    /// The six edge nodes of each tetrahedron, edges in the order of [`TET_EDGES`].
    pub tet_edges: Vec<[usize; 6]>,
    /// The three edge nodes of each boundary facet, edges in the order of [`TRI_EDGES`].
    pub facet_edges: Vec<[usize; 3]>,
}

/// The faces of a tetrahedron [a, b, c, d], each opposite one vertex and oriented outward
/// when the tetrahedron is positively oriented.
const LOCAL_FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

impl TetMesh {
    /// Builds and validates a mesh. `named_facets` are facet groups given by their nodes (any
    /// orientation); every facet must be a boundary face of the tetrahedra.
    pub fn new(
        nodes: Vec<[f64; 3]>,
        tets: Vec<[usize; 4]>,
        named_facets: Vec<(String, Vec<[usize; 3]>)>,
    ) -> Result<Self, MeshError> {
        if tets.is_empty() {
            return Err(MeshError::Empty);
        }
        for (node, x) in nodes.iter().enumerate() {
            if x.iter().any(|c| !c.is_finite()) {
                return Err(MeshError::NonFiniteNode { node, coords: *x });
            }
        }
        for (element, t) in tets.iter().enumerate() {
            if let Some(&node) = t.iter().find(|&&n| n >= nodes.len()) {
                return Err(MeshError::DanglingNode { element, node, n_nodes: nodes.len() });
            }
            let volume = signed_volume(&nodes, t);
            let l = max_edge(&nodes, t);
            if volume.abs() <= 1e-12 * l * l * l {
                return Err(MeshError::Degenerate { element, nodes: *t, volume });
            }
            if volume < 0.0 {
                return Err(MeshError::Inverted { element, nodes: *t, volume });
            }
        }
        let boundary = boundary_facets(&tets);
        let mut index: std::collections::HashMap<[usize; 3], usize> =
            boundary.iter().enumerate().map(|(i, f)| (sorted(*f), i)).collect();
        let mut groups = BTreeMap::new();
        for (name, facets) in named_facets {
            let mut ids = Vec::with_capacity(facets.len());
            for f in facets {
                match index.get_mut(&sorted(f)) {
                    Some(i) => ids.push(*i),
                    None => return Err(MeshError::NotABoundaryFacet { group: name, facet: f }),
                }
            }
            ids.sort_unstable();
            ids.dedup();
            groups.entry(name).or_insert_with(Vec::new).extend(ids);
        }
        Ok(Self { nodes, tets, boundary, groups, second_order: None })
    }

    /// True for a second-order mesh (10-node tetrahedra).
    pub fn is_second_order(&self) -> bool {
        self.second_order.is_some()
    }

    /// The nodes of boundary facet `f`: its three vertices, then (second order) its three edge
    /// nodes.
    pub fn facet_nodes(&self, f: usize) -> impl Iterator<Item = usize> + '_ {
        self.boundary[f].into_iter().chain(self.second_order.iter().flat_map(move |s| s.facet_edges[f]))
    }

    /// The nodes of element `e`: its four vertices, then (second order) its six edge nodes.
    pub fn element_nodes(&self, e: usize) -> impl Iterator<Item = usize> + '_ {
        self.tets[e].into_iter().chain(self.second_order.iter().flat_map(move |s| s.tet_edges[e]))
    }

    /// The second-order mesh of the same tetrahedra (10-node tetrahedra, 6-node triangles): a
    /// node at the midpoint of every edge, appended after the vertices in the order the edges
    /// are first met. A second-order mesh is returned as it is.
    pub fn second_order(&self) -> TetMesh {
        if self.is_second_order() {
            return self.clone();
        }
        let mut nodes = self.nodes.clone();
        let mut edge_node = std::collections::HashMap::with_capacity(7 * self.nodes.len());
        let mut node_of = |a: usize, b: usize, nodes: &mut Vec<[f64; 3]>| -> usize {
            *edge_node.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (x, y) = (self.nodes[a], self.nodes[b]);
                nodes.push(std::array::from_fn(|k| 0.5 * (x[k] + y[k])));
                nodes.len() - 1
            })
        };
        let tet_edges: Vec<[usize; 6]> =
            self.tets.iter().map(|t| TET_EDGES.map(|[i, j]| node_of(t[i], t[j], &mut nodes))).collect();
        let facet_edges =
            self.boundary.iter().map(|f| TRI_EDGES.map(|[i, j]| node_of(f[i], f[j], &mut nodes))).collect();
        TetMesh {
            nodes,
            second_order: Some(SecondOrder { n_vertices: self.nodes.len(), tet_edges, facet_edges }),
            ..self.clone()
        }
    }

    /// The second-order mesh whose edge nodes are given (a file's 10-node tetrahedra):
    /// `tet_edges[e]` are the nodes on the edges of element e in the order of [`TET_EDGES`],
    /// indices into `self.nodes`, which must hold them. Errors: an edge given two different
    /// nodes by two elements, an edge node that is also a vertex. The edge nodes are moved to
    /// their edges' midpoints (straight-sided elements); the largest distance moved, relative to
    /// the edge's length, is returned with the mesh.
    pub fn with_edge_nodes(mut self, tet_edges: Vec<[usize; 6]>) -> Result<(TetMesh, f64), MeshError> {
        let mut is_vertex = vec![false; self.nodes.len()];
        self.tets.iter().flatten().for_each(|&n| is_vertex[n] = true);
        let mut edge_node = std::collections::HashMap::with_capacity(7 * self.nodes.len());
        let mut moved: f64 = 0.0;
        for (element, (t, edges)) in self.tets.iter().zip(&tet_edges).enumerate() {
            for (k, &[i, j]) in TET_EDGES.iter().enumerate() {
                let (a, b, node) = (t[i].min(t[j]), t[i].max(t[j]), edges[k]);
                if node >= self.nodes.len() || is_vertex[node] {
                    return Err(MeshError::BadEdgeNode { element, node, reason: "it is a vertex or does not exist" });
                }
                if *edge_node.entry((a, b)).or_insert(node) != node {
                    return Err(MeshError::BadEdgeNode {
                        element,
                        node,
                        reason: "another element puts another node on this edge",
                    });
                }
                let (x, y) = (self.nodes[a], self.nodes[b]);
                let mid: [f64; 3] = std::array::from_fn(|k| 0.5 * (x[k] + y[k]));
                let d = sub(self.nodes[node], mid);
                let l = sub(x, y);
                moved = moved.max(
                    ((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / (l[0] * l[0] + l[1] * l[1] + l[2] * l[2])).sqrt(),
                );
            }
        }
        for (&(a, b), &node) in &edge_node {
            let (x, y) = (self.nodes[a], self.nodes[b]);
            self.nodes[node] = std::array::from_fn(|k| 0.5 * (x[k] + y[k]));
        }
        let facet_edges = self
            .boundary
            .iter()
            .map(|f| TRI_EDGES.map(|[i, j]| edge_node[&(f[i].min(f[j]), f[i].max(f[j]))]))
            .collect();
        let n_vertices = is_vertex.iter().filter(|v| **v).count();
        self.second_order = Some(SecondOrder { n_vertices, tet_edges, facet_edges });
        Ok((self, moved))
    }

    /// The first-order mesh of the same tetrahedra: the edge nodes dropped and the vertices
    /// renumbered densely in their order. A first-order mesh is returned as it is.
    pub fn first_order(&self) -> TetMesh {
        if !self.is_second_order() {
            return self.clone();
        }
        let mut new_index = vec![usize::MAX; self.nodes.len()];
        self.tets.iter().flatten().for_each(|&n| new_index[n] = 0);
        let mut nodes = Vec::new();
        for (n, i) in new_index.iter_mut().enumerate() {
            if *i == 0 {
                *i = nodes.len();
                nodes.push(self.nodes[n]);
            }
        }
        TetMesh {
            nodes,
            tets: self.tets.iter().map(|t| t.map(|n| new_index[n])).collect(),
            boundary: self.boundary.iter().map(|f| f.map(|n| new_index[n])).collect(),
            groups: self.groups.clone(),
            second_order: None,
        }
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Number of tetrahedra.
    pub fn n_elements(&self) -> usize {
        self.tets.len()
    }

    /// |T| of element `e`.
    pub fn volume(&self, e: usize) -> f64 {
        signed_volume(&self.nodes, &self.tets[e])
    }

    /// Lower and upper corners of the bounding box.
    pub fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for x in &self.nodes {
            for k in 0..3 {
                lo[k] = lo[k].min(x[k]);
                hi[k] = hi[k].max(x[k]);
            }
        }
        (lo, hi)
    }

    /// Diameter of the bounding box: the length scale of the body.
    pub fn diameter(&self) -> f64 {
        let (lo, hi) = self.bounding_box();
        ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt()
    }

    /// Centroid of boundary facet `f`.
    pub fn facet_centroid(&self, f: usize) -> [f64; 3] {
        let [a, b, c] = self.boundary[f];
        std::array::from_fn(|k| (self.nodes[a][k] + self.nodes[b][k] + self.nodes[c][k]) / 3.0)
    }

    /// Largest edge length of element `e` (the local mesh size h_T).
    pub fn element_size(&self, e: usize) -> f64 {
        max_edge(&self.nodes, &self.tets[e])
    }

    /// Shape quality: the worst aspect ratio (longest edge over shortest altitude, scaled so
    /// that a regular tetrahedron has 1; slivers and needles have large values) and where.
    pub fn quality(&self) -> MeshQuality {
        let mut q = MeshQuality { max_aspect_ratio: 0.0, worst_element: 0, min_volume: f64::INFINITY, max_volume: 0.0 };
        for (e, t) in self.tets.iter().enumerate() {
            let v = signed_volume(&self.nodes, t);
            let x = t.map(|n| self.nodes[n]);
            let largest_face = LOCAL_FACES
                .iter()
                .map(|f| {
                    let (u, w) = (sub(x[f[1]], x[f[0]]), sub(x[f[2]], x[f[0]]));
                    let n = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
                    0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
                })
                .fold(0.0, f64::max);
            let shortest_altitude = 3.0 * v / largest_face;
            let ar = max_edge(&self.nodes, t) / shortest_altitude / 1.5f64.sqrt();
            if ar > q.max_aspect_ratio {
                q.max_aspect_ratio = ar;
                q.worst_element = e;
            }
            q.min_volume = q.min_volume.min(v);
            q.max_volume = q.max_volume.max(v);
        }
        q
    }

    /// Names of the facet groups, for error messages.
    pub fn group_names(&self) -> Vec<&str> {
        self.groups.keys().map(|s| s.as_str()).collect()
    }
}

/// Shape and size statistics of a mesh ([`TetMesh::quality`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct MeshQuality {
    /// Largest aspect ratio (1 for a regular tetrahedron).
    pub max_aspect_ratio: f64,
    /// The element where it occurs.
    pub worst_element: usize,
    /// Smallest element volume.
    pub min_volume: f64,
    /// Largest element volume.
    pub max_volume: f64,
}

/// A source of meshes chosen by `type` in the `[mesh]` table of a scene (the structured box
/// mesher `box`; file readers).
#[typetag::serde(tag = "type")]
pub trait MeshSource: Debug + Send + Sync + dyn_clone::DynClone {
    /// The `type` name of the source in scene files.
    fn name(&self) -> &'static str {
        self.typetag_name()
    }
    /// Checks the parameters; `path` is the table's path in the scene (`mesh`).
    fn validate(&self, path: &str) -> Result<(), ParameterError>;
    /// Builds the mesh; relative file names are resolved against `base_dir` (the scene's folder).
    fn build(&self, base_dir: &Path) -> Result<TetMesh, MeshError>;
    /// The cells per axis of a structured source (refinement studies scale them); `None` for a
    /// source that cannot be refined by cell counts (a file, an inline mesh).
    fn cells(&self) -> Option<[usize; 3]> {
        None
    }
    /// The coarsest level of the source's mesh family (theory §7.3), when its levels must be
    /// multiples of it (`base` of a box); `None`: any cells.
    fn family_base(&self) -> Option<[usize; 3]> {
        None
    }
    /// The same source with `cells` per axis, where [`MeshSource::cells`] is `Some`.
    fn with_cells(&self, _cells: [usize; 3]) -> Option<Box<dyn MeshSource>> {
        None
    }
}

dyn_clone::clone_trait_object!(MeshSource);

/// Signed volume of the tetrahedron `t`: positive when (b−a, c−a, d−a) is right-handed.
pub fn signed_volume(nodes: &[[f64; 3]], t: &[usize; 4]) -> f64 {
    let [a, b, c, d] = t.map(|i| nodes[i]);
    let u = sub(b, a);
    let v = sub(c, a);
    let w = sub(d, a);
    (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0])) / 6.0
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn max_edge(nodes: &[[f64; 3]], t: &[usize; 4]) -> f64 {
    let mut l: f64 = 0.0;
    for i in 0..4 {
        for j in i + 1..4 {
            let d = sub(nodes[t[i]], nodes[t[j]]);
            l = l.max((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
        }
    }
    l
}

fn sorted(mut f: [usize; 3]) -> [usize; 3] {
    f.sort_unstable();
    f
}

/// Faces that belong to exactly one tetrahedron, oriented outward.
fn boundary_facets(tets: &[[usize; 4]]) -> Vec<[usize; 3]> {
    let mut faces: Vec<([usize; 3], [usize; 3])> = Vec::with_capacity(4 * tets.len());
    for t in tets {
        for lf in LOCAL_FACES {
            let f = lf.map(|i| t[i]);
            faces.push((sorted(f), f));
        }
    }
    faces.sort_unstable_by_key(|x| x.0);
    let mut out = Vec::new();
    let mut i = 0;
    while i < faces.len() {
        let mut j = i + 1;
        while j < faces.len() && faces[j].0 == faces[i].0 {
            j += 1;
        }
        if j - i == 1 {
            out.push(faces[i].1);
        }
        i = j;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_tet() -> (Vec<[f64; 3]>, Vec<[usize; 4]>) {
        (vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], vec![[0, 1, 2, 3]])
    }

    #[test]
    fn single_tet_has_four_outward_facets() {
        let (n, t) = unit_tet();
        let m = TetMesh::new(n, t, vec![("bottom".into(), vec![[0, 1, 2]])]).unwrap();
        assert!((m.volume(0) - 1.0 / 6.0).abs() < 1e-15);
        assert_eq!(m.boundary.len(), 4);
        // outward: the facet on z = 0 has a normal pointing to −z
        let f = m.boundary[m.groups["bottom"][0]];
        let [a, b, c] = f.map(|i| m.nodes[i]);
        let (u, v) = (sub(b, a), sub(c, a));
        assert!(u[0] * v[1] - u[1] * v[0] < 0.0);
    }

    #[test]
    fn aspect_ratio_is_one_for_a_regular_tet_and_large_for_a_sliver() {
        let s = (8.0f64 / 9.0).sqrt();
        let regular = vec![
            [0.0, 0.0, 1.0],
            [s, 0.0, -1.0 / 3.0],
            [-s / 2.0, (2.0f64 / 3.0).sqrt(), -1.0 / 3.0],
            [-s / 2.0, -(2.0f64 / 3.0).sqrt(), -1.0 / 3.0],
        ];
        let t = if signed_volume(&regular, &[0, 1, 2, 3]) > 0.0 { [0, 1, 2, 3] } else { [0, 2, 1, 3] };
        let m = TetMesh::new(regular, vec![t], vec![]).unwrap();
        assert!((m.quality().max_aspect_ratio - 1.0).abs() < 1e-12);
        // a unit right tetrahedron squashed to height 0.01
        let m = TetMesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.01]],
            vec![[0, 1, 2, 3]],
            vec![],
        )
        .unwrap();
        let ar = m.quality().max_aspect_ratio;
        assert!(ar > 80.0 && ar < 150.0, "{ar}");
    }

    #[test]
    fn inverted_and_degenerate_elements_are_named() {
        let (n, _) = unit_tet();
        let err = TetMesh::new(n.clone(), vec![[0, 2, 1, 3]], vec![]).unwrap_err();
        assert!(matches!(err, MeshError::Inverted { element: 0, .. }), "{err}");
        let mut flat = n.clone();
        flat[3] = [0.3, 0.3, 0.0];
        let err = TetMesh::new(flat, vec![[0, 1, 2, 3]], vec![]).unwrap_err();
        assert!(matches!(err, MeshError::Degenerate { element: 0, .. }), "{err}");
        assert!(err.to_string().contains("element 0"));
        let err = TetMesh::new(n, vec![[0, 1, 2, 9]], vec![]).unwrap_err();
        assert!(matches!(err, MeshError::DanglingNode { node: 9, .. }));
    }

    #[test]
    fn a_group_facet_must_lie_on_the_boundary() {
        // two tets sharing the face [1, 2, 3]
        let nodes = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]];
        let tets = vec![[0, 1, 2, 3], [1, 2, 3, 4]];
        let tets = tets
            .into_iter()
            .map(|t| if signed_volume(&nodes, &t) < 0.0 { [t[0], t[2], t[1], t[3]] } else { t })
            .collect();
        let err = TetMesh::new(nodes, tets, vec![("inner".into(), vec![[3, 2, 1]])]).unwrap_err();
        assert!(matches!(err, MeshError::NotABoundaryFacet { .. }));
    }
}
