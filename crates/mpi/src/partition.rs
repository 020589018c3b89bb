//! Mesh partitioning: tetrahedra → parts (ranks), by METIS's multilevel k-way partitioning of the
//! mesh's face dual graph.
//!
//! * **METIS through the `metis` crate** (0.2, MIT/Apache-2.0; METIS 5 itself is Apache-2.0),
//!   built from the crate's vendored sources: no system package, no PETSc needed, and the same
//!   partitioner and so the same partition on a laptop and on a cluster. PETSc's own
//!   `MatPartitioning` would depend on what each PETSc build carries (Debian's: PTScotch, no
//!   ParMETIS, which is not free software); the mesh is read on one rank anyway, so a serial
//!   partitioner is all that is needed.
//! * **The dual graph, elements adjacent when they share a face**: a part is a set of elements
//!   (each rank assembles its own), so the graph's vertices are the elements; the weight to
//!   balance is the elements' assembly and local-law work; and the cut faces are the interface
//!   between ranks, whose nodes are the ghosts to exchange. The nodal graph would partition
//!   nodes and leave the elements on the interface to be assigned by a second rule; adjacency by
//!   a shared vertex (METIS's `ncommon = 1`) would give each element tens of neighbours instead
//!   of at most 4, a larger graph for no better interface.
//!
//! Only the four vertices of each element are read, so 10-node tetrahedra partition alike.

use metis::Idx;
use thiserror::Error;

/// The faces of a tetrahedron by local vertex (the vertex opposite each left out).
const FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]];

/// Errors of the partitioner, with the offending values.
#[derive(Debug, Error, PartialEq)]
pub enum PartitionError {
    /// Not a tetrahedron's node count.
    #[error("nodes per element = {0}: tetrahedra have 4 (linear) or 10 (quadratic) nodes")]
    NodesPerElement(usize),
    /// The connectivity is not a whole number of elements.
    #[error("the connectivity has {len} entries, not a multiple of {nodes_per_element} nodes per element")]
    Connectivity {
        /// Its length.
        len: usize,
        /// Nodes per element.
        nodes_per_element: usize,
    },
    /// No parts, or more parts than elements.
    #[error("{parts} parts for {elements} elements: each part (rank) needs at least one element")]
    Parts {
        /// Parts asked for.
        parts: usize,
        /// Elements in the mesh.
        elements: usize,
    },
    /// The mesh is too large for METIS's 32-bit indices.
    #[error("{what} = {value} exceeds METIS's 32-bit index")]
    TooLarge {
        /// What the number is.
        what: &'static str,
        /// The number.
        value: usize,
    },
    /// METIS failed.
    #[error("METIS failed: {0}")]
    Metis(String),
    /// METIS left a part without elements.
    #[error("METIS left part {part} of {parts} empty ({elements} elements)")]
    EmptyPart {
        /// The empty part.
        part: usize,
        /// Parts asked for.
        parts: usize,
        /// Elements in the mesh.
        elements: usize,
    },
}

/// A graph in compressed rows (METIS's `xadj`, `adjncy`): the neighbours of vertex i are
/// `neighbours[offsets[i]..offsets[i + 1]]`, sorted.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Graph {
    /// Row offsets, one per vertex and one past the end.
    pub offsets: Vec<Idx>,
    /// Neighbours of each vertex, sorted.
    pub neighbours: Vec<Idx>,
}

/// The face dual graph of a tetrahedral mesh: elements (rows of `nodes_per_element` node indices
/// in `connectivity`, vertices first) are adjacent when they share a face (three vertices).
pub fn face_dual_graph(connectivity: &[usize], nodes_per_element: usize) -> Result<Graph, PartitionError> {
    let elements = element_count(connectivity, nodes_per_element)?;
    let idx = |what, value: usize| Idx::try_from(value).map_err(|_| PartitionError::TooLarge { what, value });
    idx("elements", elements)?;
    idx("dual graph entries", 4 * elements)?;
    let mut faces: Vec<([usize; 3], usize)> = Vec::with_capacity(4 * elements);
    for (e, cell) in connectivity.chunks_exact(nodes_per_element).enumerate() {
        for face in FACES {
            let mut key = face.map(|i| cell[i]);
            key.sort_unstable();
            faces.push((key, e));
        }
    }
    faces.sort_unstable();
    let mut edges: Vec<(usize, usize)> = Vec::with_capacity(4 * elements);
    for run in faces.chunk_by(|a, b| a.0 == b.0) {
        for (i, &(_, a)) in run.iter().enumerate() {
            for &(_, b) in &run[i + 1..] {
                if a != b {
                    edges.extend([(a, b), (b, a)]);
                }
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    let mut offsets = vec![0 as Idx; elements + 1];
    for &(a, _) in &edges {
        offsets[a + 1] += 1;
    }
    for i in 0..elements {
        offsets[i + 1] += offsets[i];
    }
    let neighbours = edges.iter().map(|&(_, b)| b as Idx).collect();
    Ok(Graph { offsets, neighbours })
}

/// Element → part (0..parts) for a tetrahedral mesh given by its global `connectivity`
/// (`nodes_per_element` = 4 or 10 node indices per element, vertices first): METIS k-way on the
/// face dual graph, every part non-empty, parts balanced in element count within METIS's default
/// 3 %.
pub fn partition_elements(
    connectivity: &[usize],
    nodes_per_element: usize,
    parts: usize,
) -> Result<Vec<usize>, PartitionError> {
    let elements = element_count(connectivity, nodes_per_element)?;
    if parts == 0 || parts > elements {
        return Err(PartitionError::Parts { parts, elements });
    }
    if parts == 1 {
        return Ok(vec![0; elements]);
    }
    let graph = face_dual_graph(connectivity, nodes_per_element)?;
    let nparts = Idx::try_from(parts).map_err(|_| PartitionError::TooLarge { what: "parts", value: parts })?;
    let mut part: Vec<Idx> = vec![0; elements];
    metis::Graph::new(1, nparts, &graph.offsets, &graph.neighbours)
        .map_err(|e| PartitionError::Metis(e.to_string()))?
        .part_kway(&mut part)
        .map_err(|e| PartitionError::Metis(e.to_string()))?;
    let part: Vec<usize> = part.into_iter().map(|p| p as usize).collect();
    let mut sizes = vec![0usize; parts];
    for &p in &part {
        sizes[p] += 1;
    }
    if let Some(empty) = sizes.iter().position(|&s| s == 0) {
        return Err(PartitionError::EmptyPart { part: empty, parts, elements });
    }
    Ok(part)
}

/// The number of elements of a connectivity array, checked.
fn element_count(connectivity: &[usize], nodes_per_element: usize) -> Result<usize, PartitionError> {
    if nodes_per_element != 4 && nodes_per_element != 10 {
        return Err(PartitionError::NodesPerElement(nodes_per_element));
    }
    if !connectivity.len().is_multiple_of(nodes_per_element) {
        return Err(PartitionError::Connectivity { len: connectivity.len(), nodes_per_element });
    }
    Ok(connectivity.len() / nodes_per_element)
}
