//! A scene's problem distributed over the ranks (theory §12). Rank 0 holds the mesh (it read or
//! built it) and partitions its elements with METIS; the mesh and the partition are broadcast;
//! every rank then numbers the whole problem's dofs, discretises the obstacles and the loads on
//! the whole mesh (regions are the whole mesh's boundary, not a part's), keeps its own part —
//! its elements, their nodes (owned, then ghosts), its dofs, the contact rows of its owned nodes,
//! the loads at its owned dofs — and drops the rest. Rank 0 keeps the whole mesh and obstacles for
//! the reports of the obstacles and for the output's master file.
//!
//! Every step but the mesh's and the partition's is computed by every rank from the same data,
//! so an error in it is the same error on every rank; the caller shares rank 0's own errors
//! first ([`saddle_mpi::agree`]). The PETSc session must outlive the problem.

use crate::comm::MpiComm;
use crate::element::DistributedElement;
use crate::layout::Layout;
use saddle_core::distributed::{MeshPart, Partition};
use saddle_core::error::SceneError;
use saddle_core::fem::loads::{Load, nodal_loads};
use saddle_core::fem::{DiscreteProblem, FiniteElement};
use saddle_core::mesh::dofs::{Dirichlet, DofMap, FIXED};
use saddle_core::mesh::{SecondOrder, TetMesh};
use saddle_core::problem::comm::Comm;
use saddle_core::problem::elasticity::Elasticity;
use saddle_core::problem::obstacles::{DiscreteObstacles, OBSTACLE_PATH, Obstacles};
use saddle_core::problem::stresses::AdmissibleStresses;
use std::collections::BTreeMap;
use std::sync::Arc;

/// The whole problem's mesh and obstacles, on rank 0.
#[derive(Debug)]
pub struct Whole {
    /// The mesh (of the element's order).
    pub mesh: TetMesh,
    /// The obstacles on the whole mesh: every row, in the whole problem's order.
    pub obstacles: DiscreteObstacles,
}

/// Sizes of the whole problem.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Totals {
    /// Free dofs.
    pub dofs: usize,
    /// Elements.
    pub elements: usize,
    /// Nodes.
    pub nodes: usize,
    /// Contact rows.
    pub rows: usize,
}

/// A rank's part of a distributed problem.
#[derive(Debug)]
pub struct RankProblem {
    /// The rank's problem: its element operators ([`DistributedElement`]) and its data.
    pub problem: DiscreteProblem,
    /// The reductions.
    pub comm: MpiComm,
    /// The index among the whole problem's rows of every row this rank holds.
    pub global_rows: Vec<usize>,
    /// The global index of every local element.
    pub elements: Vec<usize>,
    /// The nodes this rank owns (its part's other nodes are ghosts).
    pub owned_nodes: usize,
    /// Sizes of the whole problem.
    pub totals: Totals,
    /// The whole mesh and obstacles, on rank 0.
    pub whole: Option<Whole>,
}

impl RankProblem {
    /// The whole problem's row vector of the values `local` this rank holds at its rows (the
    /// multipliers λ), on every rank: each rank's rows summed into place. Collective.
    pub fn whole_rows(&self, local: &[f64]) -> Vec<f64> {
        whole_rows(&self.comm, &self.global_rows, self.totals.rows, local)
    }
}

/// The whole problem's row vector (`n_rows` rows) of the values `local` a rank holds at its rows
/// `global_rows`, on every rank: each rank's rows summed into place. Collective.
pub fn whole_rows(comm: &MpiComm, global_rows: &[usize], n_rows: usize, local: &[f64]) -> Vec<f64> {
    let mut whole = vec![0.0; n_rows];
    for (&g, &x) in global_rows.iter().zip(local) {
        whole[g] = x;
    }
    comm.sum_in_place(&mut whole);
    whole
}

/// Distributes a problem (module docs): `mesh` is rank 0's (`None` on the others), the rest the
/// scene's, the same on every rank. Collective.
#[allow(clippy::too_many_arguments)]
pub fn distribute(
    session: &saddle_mpi::Petsc,
    mesh: Option<TetMesh>,
    element: &dyn FiniteElement,
    dirichlet: &[Dirichlet],
    elasticity: Elasticity,
    stresses: Option<Box<dyn AdmissibleStresses>>,
    obstacles: Obstacles,
    loads: &[Load],
) -> Result<RankProblem, SceneError> {
    let comm = MpiComm::new(session);
    let (rank, size) = (comm.rank(), comm.size());
    // the mesh of the element's order, and its partition, from rank 0
    let mut bytes = mesh.map(|m| encode(&element.prepare_mesh(m))).unwrap_or_default();
    saddle_mpi::broadcast_bytes(comm.world(), 0, &mut bytes);
    let mesh = decode(&bytes);
    drop(bytes);
    // rank 0's partition, or its error on every rank
    let element_rank = if rank == 0 { partition(&mesh, size) } else { Ok(Vec::new()) };
    let mut element_rank = saddle_mpi::agree(comm.world(), element_rank)
        .map_err(|e| SceneError::Region { field: "mesh".into(), message: rank_message(e) })?;
    saddle_mpi::broadcast(comm.world(), 0, &mut element_rank);
    let element_rank: Vec<usize> = element_rank.into_iter().map(|r| r as usize).collect();
    let partition = Partition::new(&mesh, element_rank, size)
        .map_err(|e| SceneError::Region { field: "mesh".into(), message: e.to_string() })?;
    // the whole problem's dofs, rows and loads
    let dofs = DofMap::new(&mesh, dirichlet)?;
    dofs.check_rigid_motions(&mesh)?;
    let whole_obstacles = obstacles.discretise(&mesh, &dofs, OBSTACLE_PATH)?;
    let whole_load = if loads.is_empty() { Vec::new() } else { nodal_loads(&mesh, &dofs, loads)? };
    let totals = Totals {
        dofs: dofs.n_free,
        elements: mesh.n_elements(),
        nodes: mesh.n_nodes(),
        rows: whole_obstacles.rows().n_rows(),
    };
    // this rank's part
    let part = MeshPart::new(&mesh, &dofs, &partition, rank);
    let local_dof = part.from_global_dofs(&dofs);
    let local_node: BTreeMap<usize, usize> =
        part.nodes[..part.n_owned_nodes].iter().enumerate().map(|(l, &g)| (g, l)).collect();
    let obstacles = whole_obstacles.restrict(|n| local_node.get(&n).copied(), |j| local_dof[j] as usize);
    let global_rows = (0..whole_obstacles.rows().n_rows())
        .filter(|&i| local_node.contains_key(&whole_obstacles.rows().node[i]))
        .collect();
    let mut nodal_load = vec![0.0; if whole_load.is_empty() { 0 } else { part.n_owned_dofs }];
    for (g, &l) in local_dof.iter().enumerate() {
        if l != FIXED && (l as usize) < nodal_load.len() {
            nodal_load[l as usize] = whole_load[g];
        }
    }
    let layout = Arc::new(Layout::new(&part));
    let local = element.build_with_dofs(part.mesh.clone(), part.dofs.clone());
    let operators = DistributedElement::new(session, local, layout)
        .map_err(|e| SceneError::Region { field: "mesh".into(), message: format!("distributed vectors: {e}") })?;
    let problem = DiscreteProblem::from_discretised(Box::new(operators), elasticity, stresses, obstacles, nodal_load);
    let whole = (rank == 0).then(|| Whole { mesh, obstacles: whole_obstacles });
    let owned_nodes = part.n_owned_nodes;
    Ok(RankProblem { problem, comm, global_rows, elements: part.elements, owned_nodes, totals, whole })
}

/// The message of an error shared by [`saddle_mpi::agree`]: the failing rank's own.
fn rank_message(e: saddle_mpi::Error) -> String {
    match e {
        saddle_mpi::Error::Rank { message, .. } => message,
        other => other.to_string(),
    }
}

/// The ranks of the elements of `mesh`: METIS on its face dual graph (rank 0).
fn partition(mesh: &TetMesh, ranks: usize) -> Result<Vec<u64>, String> {
    let connectivity: Vec<usize> = mesh.tets.iter().flatten().copied().collect();
    saddle_mpi::partition_elements(&connectivity, 4, ranks)
        .map(|p| p.into_iter().map(|r| r as u64).collect())
        .map_err(|e| format!("cannot partition the mesh's {} elements over {ranks} ranks: {e}", mesh.n_elements()))
}

// ---- the mesh as bytes, for the broadcast ----

fn put(out: &mut Vec<u8>, x: u64) {
    out.extend_from_slice(&x.to_le_bytes());
}

/// `mesh` as bytes: nodes, tetrahedra, boundary facets, groups, edge nodes.
pub fn encode(mesh: &TetMesh) -> Vec<u8> {
    let mut out = Vec::with_capacity(8 * (3 * mesh.n_nodes() + 10 * mesh.n_elements()));
    put(&mut out, mesh.nodes.len() as u64);
    for x in mesh.nodes.iter().flatten() {
        out.extend_from_slice(&x.to_le_bytes());
    }
    put(&mut out, mesh.tets.len() as u64);
    mesh.tets.iter().flatten().for_each(|&n| put(&mut out, n as u64));
    put(&mut out, mesh.boundary.len() as u64);
    mesh.boundary.iter().flatten().for_each(|&n| put(&mut out, n as u64));
    put(&mut out, mesh.groups.len() as u64);
    for (name, ids) in &mesh.groups {
        put(&mut out, name.len() as u64);
        out.extend_from_slice(name.as_bytes());
        put(&mut out, ids.len() as u64);
        ids.iter().for_each(|&i| put(&mut out, i as u64));
    }
    match &mesh.second_order {
        None => put(&mut out, 0),
        Some(so) => {
            put(&mut out, 1);
            put(&mut out, so.n_vertices as u64);
            so.tet_edges.iter().flatten().for_each(|&n| put(&mut out, n as u64));
            so.facet_edges.iter().flatten().for_each(|&n| put(&mut out, n as u64));
        }
    }
    out
}

/// A cursor over [`encode`]'s bytes.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn word(&mut self) -> u64 {
        let w = u64::from_le_bytes(self.bytes[self.at..self.at + 8].try_into().expect("8 bytes"));
        self.at += 8;
        w
    }

    fn text(&mut self, len: usize) -> String {
        let s = String::from_utf8_lossy(&self.bytes[self.at..self.at + len]).into_owned();
        self.at += len;
        s
    }
}

/// The mesh of [`encode`]'s bytes.
pub fn decode(bytes: &[u8]) -> TetMesh {
    let mut r = Reader { bytes, at: 0 };
    let n = r.word() as usize;
    let nodes = (0..n).map(|_| std::array::from_fn(|_| f64::from_bits(r.word()))).collect();
    let m = r.word() as usize;
    let tets: Vec<[usize; 4]> = (0..m).map(|_| std::array::from_fn(|_| r.word() as usize)).collect();
    let k = r.word() as usize;
    let boundary: Vec<[usize; 3]> = (0..k).map(|_| std::array::from_fn(|_| r.word() as usize)).collect();
    let g = r.word() as usize;
    let mut groups = BTreeMap::new();
    for _ in 0..g {
        let len = r.word() as usize;
        let name = r.text(len);
        let count = r.word() as usize;
        groups.insert(name, (0..count).map(|_| r.word() as usize).collect());
    }
    let second_order = (r.word() == 1).then(|| {
        let n_vertices = r.word() as usize;
        let tet_edges = (0..m).map(|_| std::array::from_fn(|_| r.word() as usize)).collect();
        let facet_edges = (0..k).map(|_| std::array::from_fn(|_| r.word() as usize)).collect();
        SecondOrder { n_vertices, tet_edges, facet_edges }
    });
    TetMesh { nodes, tets, boundary, groups, second_order }
}
