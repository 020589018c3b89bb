//! A scene's problem distributed over the ranks (theory §12). Rank 0 holds the mesh (it read or
//! built it), partitions its elements with METIS, numbers the whole problem's dofs, discretises
//! the obstacles and the loads on the whole mesh (regions are the whole mesh's boundary, not a
//! part's) and counts every row's couplings; then it cuts the problem into the ranks' parts and
//! sends each rank its own, one after the other ([`saddle_mpi::scatter_bytes`]): its elements,
//! their nodes (owned, then the ghost layer), its dofs, the contact rows of its owned nodes, the
//! loads at its owned dofs. No other rank ever holds the whole mesh. Rank 0 then drops the whole
//! problem but the mesh's surface, its quality and the obstacles' rows, which the obstacles'
//! reports and the summary read.
//!
//! Rank 0's errors (a bad partition, region or load) are every rank's ([`saddle_mpi::agree`]),
//! the other ranks saying "rank 0: …"; the caller shares the errors of the ranks' own set-up
//! after. The PETSc session must outlive the problem.

use crate::comm::MpiComm;
use crate::element::DistributedElement;
use crate::layout::Layout;
use saddle_core::distributed::{MeshPart, Partition};
use saddle_core::error::SceneError;
use saddle_core::fem::loads::{Load, nodal_loads};
use saddle_core::fem::{DiscreteProblem, FiniteElement};
use saddle_core::mesh::dofs::{Dirichlet, DofMap, FIXED};
use saddle_core::mesh::{MeshQuality, SecondOrder, TetMesh};
use saddle_core::problem::comm::Comm;
use saddle_core::problem::displacements::ConstraintRows;
use saddle_core::problem::elasticity::Elasticity;
use saddle_core::problem::obstacles::{DiscreteObstacles, OBSTACLE_PATH, Obstacles};
use saddle_core::problem::stresses::AdmissibleStresses;
use std::collections::BTreeMap;
use std::sync::Arc;

/// What rank 0 keeps of the whole problem once the parts are sent: what the obstacles' reports
/// and the summary read.
#[derive(Debug)]
pub struct Whole {
    /// The whole mesh's surface: its boundary facets on the nodes they and the obstacles' rows
    /// touch (renumbered), no tetrahedra.
    pub mesh: TetMesh,
    /// The whole mesh's quality.
    pub quality: MeshQuality,
    /// The obstacles: every row, in the whole problem's order, at the surface's nodes.
    pub obstacles: DiscreteObstacles,
    /// The whole problem's sizes.
    pub totals: Totals,
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
    let rank = comm.rank();
    // rank 0: the whole problem; its error on every rank
    let whole = mesh.map(|mesh| whole_problem(mesh, element, dirichlet, obstacles.clone(), loads, comm.size()));
    let shared = saddle_mpi::agree(comm.world(), whole.transpose());
    let whole = match shared {
        Ok(whole) => whole,
        Err(e) => return Err(whole_error(rank, e)),
    };
    // each rank its part, then rank 0 drops the whole problem but what its reports need
    let bytes = saddle_mpi::scatter_bytes(comm.world(), 0, |r| {
        whole.as_ref().map(|w| encode_part(&w.part(r))).expect("rank 0 holds the whole problem")
    });
    let whole = whole.map(WholeProblem::into_reported);
    let RankPart { part, rows, global_rows, nodal_load, totals } = decode_part(&bytes);
    drop(bytes);
    let obstacles = DiscreteObstacles::from_restricted(obstacles, rows);
    let layout = Arc::new(Layout::new(&part));
    let MeshPart { mesh, dofs, elements, n_owned_nodes, .. } = part;
    let local = element.build_with_dofs(mesh, dofs);
    let operators = DistributedElement::new(session, local, layout)
        .map_err(|e| SceneError::Region { field: "mesh".into(), message: format!("distributed vectors: {e}") })?;
    let problem = DiscreteProblem::from_discretised(Box::new(operators), elasticity, stresses, obstacles, nodal_load);
    Ok(RankProblem { problem, comm, global_rows, elements, owned_nodes: n_owned_nodes, totals, whole })
}

/// A failure of rank 0's whole problem on `rank`: rank 0's own error, the others its message.
fn whole_error(rank: usize, shared: saddle_mpi::Error) -> SceneError {
    let message = rank_message(shared);
    let field = if rank == 0 { "mesh" } else { "rank 0" };
    SceneError::Region { field: field.into(), message }
}

/// The whole problem, on rank 0 while it is cut into the ranks' parts.
struct WholeProblem {
    mesh: TetMesh,
    partition: Partition,
    dofs: DofMap,
    couplings: Vec<[u32; 2]>,
    obstacles: DiscreteObstacles,
    load: Vec<f64>,
    totals: Totals,
}

/// Rank 0's whole problem (module docs): the mesh of the element's order, its partition over
/// `ranks`, the dofs, the obstacles' rows and the loads.
fn whole_problem(
    mesh: TetMesh,
    element: &dyn FiniteElement,
    dirichlet: &[Dirichlet],
    obstacles: Obstacles,
    loads: &[Load],
    ranks: usize,
) -> Result<WholeProblem, SceneError> {
    let mesh = element.prepare_mesh(mesh);
    let element_rank =
        partition(&mesh, ranks).map_err(|message| SceneError::Region { field: "mesh".into(), message })?;
    let partition = Partition::new(&mesh, element_rank, ranks)
        .map_err(|e| SceneError::Region { field: "mesh".into(), message: e.to_string() })?;
    let dofs = DofMap::new(&mesh, dirichlet)?;
    dofs.check_rigid_motions(&mesh)?;
    if element.recombines_contact_rows() {
        return Err(SceneError::Region {
            field: "discretisation.contact_rows".into(),
            message: "recombined contact rows (theory §10.1) are not distributed yet: their change of basis couples \
                      nodes across ranks; use contact_rows = \"nodal\" or run the scene on one process"
                .into(),
        });
    }
    let obstacles = obstacles.discretise(&mesh, &dofs, OBSTACLE_PATH)?;
    if obstacles.rows().has_friction() {
        return Err(SceneError::Region {
            field: OBSTACLE_PATH.into(),
            message: "friction (theory §8.3) is not distributed yet: its tangential rows are not sent to the ranks; \
                      run the scene on one process"
                .into(),
        });
    }
    let load = if loads.is_empty() { Vec::new() } else { nodal_loads(&mesh, &dofs, loads)? };
    let couplings = partition.couplings(&mesh, &dofs);
    let totals = Totals {
        dofs: dofs.n_free,
        elements: mesh.n_elements(),
        nodes: mesh.n_nodes(),
        rows: obstacles.rows().n_rows(),
    };
    Ok(WholeProblem { mesh, partition, dofs, couplings, obstacles, load, totals })
}

/// What rank 0 sends a rank: its part of the mesh and dofs, its obstacles' rows (per obstacle,
/// [`DiscreteObstacles::restricted_rows`]), their indices among the whole problem's rows, the
/// loads at its owned dofs, and the whole problem's sizes.
struct RankPart {
    part: MeshPart,
    rows: Vec<ConstraintRows>,
    global_rows: Vec<usize>,
    nodal_load: Vec<f64>,
    totals: Totals,
}

impl WholeProblem {
    /// Rank `rank`'s part.
    fn part(&self, rank: usize) -> RankPart {
        let part = MeshPart::new(&self.mesh, &self.dofs, &self.partition, &self.couplings, rank);
        let local_dof = part.from_global_dofs(&self.dofs);
        let local_node: BTreeMap<usize, usize> =
            part.nodes[..part.n_owned_nodes].iter().enumerate().map(|(l, &g)| (g, l)).collect();
        let rows = self.obstacles.restricted_rows(|n| local_node.get(&n).copied(), |j| local_dof[j] as usize);
        let all = self.obstacles.rows();
        let global_rows = (0..all.n_rows()).filter(|&i| local_node.contains_key(&all.node[i])).collect();
        let mut nodal_load = vec![0.0; if self.load.is_empty() { 0 } else { part.n_owned_dofs }];
        for (g, &l) in local_dof.iter().enumerate() {
            if l != FIXED && (l as usize) < nodal_load.len() {
                nodal_load[l as usize] = self.load[g];
            }
        }
        RankPart { part, rows, global_rows, nodal_load, totals: self.totals }
    }

    /// What rank 0 keeps for the obstacles' reports once the parts are sent ([`Whole`]).
    fn into_reported(self) -> Whole {
        let quality = self.mesh.quality();
        let Self { mesh, obstacles, totals, .. } = self;
        let (surface, node) = surface(mesh, &obstacles);
        let obstacles = obstacles.restrict(|n| (node[n] != usize::MAX).then_some(node[n]), |j| j);
        Whole { mesh: surface, quality, obstacles, totals }
    }
}

/// The surface of `mesh` an obstacle's report reads: its boundary facets (their edge nodes and
/// groups too) on the nodes they and the obstacles' rows touch, renumbered in the mesh's order
/// (no tetrahedra); and the surface's index of every node of `mesh` (`usize::MAX` off it).
fn surface(mesh: TetMesh, obstacles: &DiscreteObstacles) -> (TetMesh, Vec<usize>) {
    let mut node = vec![usize::MAX; mesh.n_nodes()];
    let facet_edges = mesh.second_order.as_ref().map(|so| so.facet_edges.as_slice()).unwrap_or_default();
    let touched = mesh.boundary.iter().flatten().chain(facet_edges.iter().flatten()).chain(&obstacles.rows().node);
    for &n in touched {
        node[n] = 0;
    }
    let mut nodes = Vec::new();
    for (n, index) in node.iter_mut().enumerate().filter(|(_, i)| **i == 0) {
        *index = nodes.len();
        nodes.push(mesh.nodes[n]);
    }
    let at = |f: &[usize; 3]| f.map(|n| node[n]);
    let boundary = mesh.boundary.iter().map(at).collect();
    let second_order = mesh.second_order.as_ref().map(|so| SecondOrder {
        n_vertices: nodes.len(),
        tet_edges: Vec::new(),
        facet_edges: so.facet_edges.iter().map(at).collect(),
    });
    (TetMesh { nodes, tets: Vec::new(), boundary, groups: mesh.groups, second_order }, node)
}

/// The message of an error shared by [`saddle_mpi::agree`]: the failing rank's own.
fn rank_message(e: saddle_mpi::Error) -> String {
    match e {
        saddle_mpi::Error::Rank { message, .. } => message,
        other => other.to_string(),
    }
}

/// The ranks of the elements of `mesh`: METIS on its face dual graph (rank 0).
fn partition(mesh: &TetMesh, ranks: usize) -> Result<Vec<usize>, String> {
    let connectivity: Vec<usize> = mesh.tets.iter().flatten().copied().collect();
    saddle_mpi::partition_elements(&connectivity, 4, ranks)
        .map_err(|e| format!("cannot partition the mesh's {} elements over {ranks} ranks: {e}", mesh.n_elements()))
}

// ---- a rank's part as bytes, for the scatter ----

/// Little-endian words: counts and indices as u64, reals by their bits, lists after their length.
#[derive(Default)]
struct Writer(Vec<u8>);

impl Writer {
    fn word(&mut self, x: usize) {
        self.0.extend_from_slice(&(x as u64).to_le_bytes());
    }

    fn words(&mut self, xs: impl ExactSizeIterator<Item = usize>) {
        self.word(xs.len());
        xs.for_each(|x| self.word(x));
    }

    fn reals(&mut self, xs: &[f64]) {
        self.word(xs.len());
        xs.iter().for_each(|x| self.0.extend_from_slice(&x.to_le_bytes()));
    }

    fn text(&mut self, s: &str) {
        self.word(s.len());
        self.0.extend_from_slice(s.as_bytes());
    }
}

/// A cursor over [`Writer`]'s bytes.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn word(&mut self) -> usize {
        let w = u64::from_le_bytes(self.bytes[self.at..self.at + 8].try_into().expect("8 bytes"));
        self.at += 8;
        w as usize
    }

    fn words(&mut self) -> Vec<usize> {
        let n = self.word();
        (0..n).map(|_| self.word()).collect()
    }

    fn reals(&mut self) -> Vec<f64> {
        let n = self.word();
        (0..n).map(|_| f64::from_bits(self.word() as u64)).collect()
    }

    fn text(&mut self) -> String {
        let len = self.word();
        let s = String::from_utf8_lossy(&self.bytes[self.at..self.at + len]).into_owned();
        self.at += len;
        s
    }
}

/// `part` as bytes: the local mesh (nodes, tetrahedra, edge nodes), the numbering, the fixed
/// components, the couplings, the obstacles' rows, the loads and the sizes.
fn encode_part(part: &RankPart) -> Vec<u8> {
    let mut w = Writer::default();
    let p = &part.part;
    w.word(p.rank);
    w.reals(&p.mesh.nodes.iter().flatten().copied().collect::<Vec<_>>());
    w.words(p.mesh.tets.iter().flatten().copied().collect::<Vec<_>>().into_iter());
    match &p.mesh.second_order {
        None => w.word(0),
        Some(so) => {
            w.word(1);
            w.words(so.tet_edges.iter().flatten().copied().collect::<Vec<_>>().into_iter());
        }
    }
    w.words(p.elements.iter().copied());
    w.words(p.nodes.iter().copied());
    w.word(p.n_owned_nodes);
    w.words(p.node_index.iter().copied());
    w.words(p.dofs.dof.iter().map(|d| (0..3).filter(|&c| d[c] == FIXED).map(|c| 1 << c).sum()));
    w.word(p.n_owned_dofs);
    w.words(p.couplings.iter().flatten().map(|&c| c as usize).collect::<Vec<_>>().into_iter());
    w.word(part.rows.len());
    for rows in &part.rows {
        w.word(rows.n_extras);
        w.words(rows.row_ptr.iter().copied());
        w.words(rows.col.iter().copied());
        w.reals(&rows.val);
        w.reals(&rows.extra);
        w.reals(&rows.offset);
        w.words(rows.node.iter().copied());
        w.word(rows.warnings.len());
        rows.warnings.iter().for_each(|t| w.text(t));
    }
    w.words(part.global_rows.iter().copied());
    w.reals(&part.nodal_load);
    let t = part.totals;
    [t.dofs, t.elements, t.nodes, t.rows].into_iter().for_each(|x| w.word(x));
    w.0
}

/// The part of [`encode_part`]'s bytes.
fn decode_part(bytes: &[u8]) -> RankPart {
    let mut r = Reader { bytes, at: 0 };
    let rank = r.word();
    let nodes = r.reals().chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect::<Vec<_>>();
    let tets = r.words().chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
    let second_order = (r.word() == 1).then(|| SecondOrder {
        n_vertices: nodes.len(),
        tet_edges: r.words().chunks_exact(6).map(|c| std::array::from_fn(|i| c[i])).collect(),
        facet_edges: Vec::new(),
    });
    let mesh = TetMesh { nodes, tets, boundary: Vec::new(), groups: BTreeMap::new(), second_order };
    let elements = r.words();
    let node_ids = r.words();
    let n_owned_nodes = r.word();
    let node_index = r.words();
    let fixed: Vec<[bool; 3]> = r.words().into_iter().map(|f| std::array::from_fn(|c| f & (1 << c) != 0)).collect();
    let n_owned_dofs = r.word();
    let couplings = r.words().chunks_exact(2).map(|c| [c[0] as u32, c[1] as u32]).collect();
    let part = MeshPart {
        rank,
        mesh,
        elements,
        nodes: node_ids,
        n_owned_nodes,
        node_index,
        dofs: DofMap::from_fixed(&fixed),
        n_owned_dofs,
        couplings,
    };
    let rows = (0..r.word())
        .map(|_| ConstraintRows {
            n_extras: r.word(),
            row_ptr: r.words(),
            col: r.words(),
            val: r.reals(),
            extra: r.reals(),
            offset: r.reals(),
            node: r.words(),
            warnings: (0..r.word()).map(|_| r.text()).collect(),
            friction: Default::default(),
            combination: None,
        })
        .collect();
    let global_rows = r.words();
    let nodal_load = r.reals();
    let totals = Totals { dofs: r.word(), elements: r.word(), nodes: r.word(), rows: r.word() };
    RankPart { part, rows, global_rows, nodal_load, totals }
}
