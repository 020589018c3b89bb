//! One rank's part of a partitioned mesh and its dofs (theory §12).
//!
//! Elements belong to the rank the partition gives them. A node belongs to one of the ranks among
//! its elements' ([`owners`]: the only one inside a part; on an interface, the one owning the
//! fewest nodes so far, so that the ranks' rows balance); a rank's *owned* nodes come first in
//! its local numbering (in the mesh's order), then its *ghost* nodes (touched by its elements, owned by another rank; in the partitioned
//! order). The *partitioned* node numbering puts rank 0's owned nodes first, then rank 1's, …, so
//! that every rank owns a contiguous range: a dof's global row in distributed linear algebra is
//! `3 · partitioned index + component`, fixed components included (they are identity rows).

use crate::mesh::dofs::{DofMap, FIXED};
use crate::mesh::{SecondOrder, TetMesh};
use std::collections::BTreeMap;
use thiserror::Error;

/// Why a partition cannot be used.
#[derive(Debug, Clone, Error, PartialEq)]
pub enum PartitionError {
    /// A rank was given no element.
    #[error("{ranks} ranks for {elements} elements: rank {rank} has no element (use fewer ranks)")]
    EmptyRank {
        /// The rank without elements.
        rank: usize,
        /// Number of ranks.
        ranks: usize,
        /// Number of elements.
        elements: usize,
    },
    /// The partition does not fit the mesh.
    #[error("the partition gives {given} element ranks for a mesh of {elements} elements, or a rank ≥ {ranks}")]
    Mismatch {
        /// Ranks given.
        given: usize,
        /// Elements of the mesh.
        elements: usize,
        /// Number of ranks.
        ranks: usize,
    },
}

/// The ranks of a mesh's elements and nodes, and the partitioned node numbering.
#[derive(Clone, Debug, PartialEq)]
pub struct Partition {
    /// Number of ranks.
    pub ranks: usize,
    /// The rank of every element.
    pub element_rank: Vec<usize>,
    /// The rank that owns every node: one among its elements' ([`owners`]).
    pub node_rank: Vec<usize>,
    /// Every node's index in the partitioned numbering.
    pub node_index: Vec<usize>,
    /// The first partitioned index of each rank's owned nodes, and the number of nodes last.
    pub node_offsets: Vec<usize>,
}

impl Partition {
    /// The partition of `mesh` (of the element's order: its edge nodes are nodes too) whose
    /// element `e` is on rank `element_rank[e]`. Every rank must have an element.
    pub fn new(mesh: &TetMesh, element_rank: Vec<usize>, ranks: usize) -> Result<Self, PartitionError> {
        let elements = mesh.n_elements();
        if element_rank.len() != elements || element_rank.iter().any(|&r| r >= ranks) {
            return Err(PartitionError::Mismatch { given: element_rank.len(), elements, ranks });
        }
        let mut count = vec![0usize; ranks];
        for &r in &element_rank {
            count[r] += 1;
        }
        if let Some(rank) = count.iter().position(|&c| c == 0) {
            return Err(PartitionError::EmptyRank { rank, ranks, elements });
        }
        let node_rank = owners(mesh, &element_rank, ranks);
        let mut node_offsets = vec![0usize; ranks + 1];
        for &r in node_rank.iter().filter(|&&r| r < ranks) {
            node_offsets[r + 1] += 1;
        }
        for r in 0..ranks {
            node_offsets[r + 1] += node_offsets[r];
        }
        let mut fill = node_offsets.clone();
        let node_index = node_rank
            .iter()
            .map(|&r| {
                if r < ranks {
                    fill[r] += 1;
                    fill[r] - 1
                } else {
                    // a node of no element (unused): numbered after every rank's
                    usize::MAX
                }
            })
            .collect();
        Ok(Self { ranks, element_rank, node_rank, node_index, node_offsets })
    }

    /// The owned nodes of `rank` in the partitioned numbering.
    pub fn owned_range(&self, rank: usize) -> std::ops::Range<usize> {
        self.node_offsets[rank]..self.node_offsets[rank + 1]
    }

    /// [`MeshPart::couplings`] of every node of `mesh` with the free dofs `dofs`: the free dofs
    /// of the nodes sharing an element with it, split by whether they have its owner.
    pub fn couplings(&self, mesh: &TetMesh, dofs: &DofMap) -> Vec<[u32; 2]> {
        // the elements around every node (compressed rows)
        let mut start = vec![0usize; mesh.n_nodes() + 1];
        for e in 0..mesh.n_elements() {
            mesh.element_nodes(e).for_each(|n| start[n + 1] += 1);
        }
        for n in 0..mesh.n_nodes() {
            start[n + 1] += start[n];
        }
        let mut fill = start.clone();
        let mut around = vec![0u32; start[mesh.n_nodes()]];
        for e in 0..mesh.n_elements() {
            for n in mesh.element_nodes(e) {
                around[fill[n]] = e as u32;
                fill[n] += 1;
            }
        }
        drop(fill);
        let free = |n: usize| dofs.dof[n].iter().filter(|&&d| d != FIXED).count() as u32;
        let mut seen = vec![usize::MAX; mesh.n_nodes()];
        (0..mesh.n_nodes())
            .map(|n| {
                let mut count = [0u32; 2];
                for &e in &around[start[n]..start[n + 1]] {
                    for m in mesh.element_nodes(e as usize) {
                        if seen[m] != n {
                            seen[m] = n;
                            count[usize::from(self.node_rank[m] != self.node_rank[n])] += free(m);
                        }
                    }
                }
                count
            })
            .collect()
    }
}

/// The rank owning every node of `mesh` whose elements are on `element_rank` (theory §12.1;
/// `usize::MAX` at a node of no element): a node inside a part belongs to its rank; the nodes on
/// the interfaces, in the mesh's order, each to the rank among its elements' that owns the
/// fewest nodes so far (the lowest of those on a tie). The ranks' owned nodes — their rows of
/// the distributed matrices — then differ by no more than the interfaces allow, where "the
/// lowest rank" gave them all to one side. Deterministic: rank 0 computes it once for all.
pub fn owners(mesh: &TetMesh, element_rank: &[usize], ranks: usize) -> Vec<usize> {
    // the lowest and highest rank around every node: equal inside a part
    let mut span = vec![[usize::MAX, 0]; mesh.n_nodes()];
    for (e, &r) in element_rank.iter().enumerate() {
        for n in mesh.element_nodes(e) {
            span[n] = [span[n][0].min(r), span[n][1].max(r)];
        }
    }
    let mut owned = vec![0usize; ranks];
    let mut interface: Vec<(usize, usize)> = Vec::new();
    for (e, &r) in element_rank.iter().enumerate() {
        interface.extend(mesh.element_nodes(e).filter(|&n| span[n][0] != span[n][1]).map(|n| (n, r)));
    }
    interface.sort_unstable();
    interface.dedup();
    let mut node_rank: Vec<usize> = span.iter().map(|&[lo, hi]| if lo == hi { lo } else { usize::MAX }).collect();
    for &r in node_rank.iter().filter(|&&r| r < ranks) {
        owned[r] += 1;
    }
    for around in interface.chunk_by(|a, b| a.0 == b.0) {
        let (n, _) = around[0];
        let r = around.iter().map(|&(_, r)| r).min_by_key(|&r| (owned[r], r)).expect("a node of an element");
        node_rank[n] = r;
        owned[r] += 1;
    }
    node_rank
}

/// One rank's part of a partitioned mesh and its dof numbering (module docs).
#[derive(Clone, Debug)]
pub struct MeshPart {
    /// The rank.
    pub rank: usize,
    /// The local mesh: the rank's elements on its local nodes (no boundary: regions are
    /// evaluated on the whole mesh).
    pub mesh: TetMesh,
    /// The global index of every local element.
    pub elements: Vec<usize>,
    /// The global index of every local node: owned nodes first, then ghosts.
    pub nodes: Vec<usize>,
    /// Number of owned nodes (the first local nodes).
    pub n_owned_nodes: usize,
    /// The partitioned index of every local node.
    pub node_index: Vec<usize>,
    /// The local dof numbering: the owned nodes' free dofs first, then the ghosts'.
    pub dofs: DofMap,
    /// Number of owned free dofs (the first local dofs).
    pub n_owned_dofs: usize,
    /// Per owned node, the free dofs coupled to it through the elements of every rank (its
    /// own included): those of nodes this rank owns, then the others' — the nonzeros of each
    /// of its free rows in the distributed matrix's diagonal and off-diagonal blocks, counted
    /// before assembly so that no rank's additions fall outside the preallocation.
    pub couplings: Vec<[u32; 2]>,
}

impl MeshPart {
    /// The part of `rank` of `mesh` under `partition`, with the free dofs of `global_dofs` and
    /// every node's `couplings` ([`Partition::couplings`]).
    pub fn new(
        mesh: &TetMesh,
        global_dofs: &DofMap,
        partition: &Partition,
        couplings: &[[u32; 2]],
        rank: usize,
    ) -> Self {
        let elements: Vec<usize> = (0..mesh.n_elements()).filter(|&e| partition.element_rank[e] == rank).collect();
        let mut touched = vec![false; mesh.n_nodes()];
        for &e in &elements {
            for n in mesh.element_nodes(e) {
                touched[n] = true;
            }
        }
        let owned = (0..mesh.n_nodes()).filter(|&n| partition.node_rank[n] == rank);
        let mut ghosts: Vec<usize> =
            (0..mesh.n_nodes()).filter(|&n| touched[n] && partition.node_rank[n] != rank).collect();
        ghosts.sort_by_key(|&n| partition.node_index[n]);
        let nodes: Vec<usize> = owned.chain(ghosts).collect();
        let n_owned_nodes = nodes.iter().take_while(|&&n| partition.node_rank[n] == rank).count();
        let local: BTreeMap<usize, usize> = nodes.iter().enumerate().map(|(l, &g)| (g, l)).collect();
        let at = |n: &usize| local[n];
        let tets = elements.iter().map(|&e| mesh.tets[e].map(|n| at(&n))).collect();
        let second_order = mesh.second_order.as_ref().map(|so| SecondOrder {
            n_vertices: nodes.len(),
            tet_edges: elements.iter().map(|&e| so.tet_edges[e].map(|n| at(&n))).collect(),
            facet_edges: Vec::new(),
        });
        let local_mesh = TetMesh {
            nodes: nodes.iter().map(|&n| mesh.nodes[n]).collect(),
            tets,
            boundary: Vec::new(),
            groups: BTreeMap::new(),
            second_order,
        };
        let fixed: Vec<[bool; 3]> = nodes.iter().map(|&n| global_dofs.dof[n].map(|d| d == FIXED)).collect();
        let dofs = DofMap::from_fixed(&fixed);
        let n_owned_dofs = fixed[..n_owned_nodes].iter().flatten().filter(|f| !**f).count();
        let node_index = nodes.iter().map(|&n| partition.node_index[n]).collect();
        let couplings = nodes[..n_owned_nodes].iter().map(|&n| couplings[n]).collect();
        Self { rank, mesh: local_mesh, elements, nodes, n_owned_nodes, node_index, dofs, n_owned_dofs, couplings }
    }

    /// The global row `3 · partitioned index + component` of every local free dof.
    pub fn dof_rows(&self) -> Vec<usize> {
        let (node, comp) = self.dofs.owners();
        node.iter().zip(&comp).map(|(&n, &c)| 3 * self.node_index[n as usize] + c as usize).collect()
    }

    /// The local dof of every free dof of `global_dofs` (the whole mesh's numbering) that this
    /// rank holds, [`FIXED`] for the others.
    pub fn from_global_dofs(&self, global_dofs: &DofMap) -> Vec<u32> {
        let mut map = vec![FIXED; global_dofs.n_free];
        for (l, &n) in self.nodes.iter().enumerate() {
            for c in 0..3 {
                if let (Some(g), Some(d)) = (global_dofs.free(n, c), self.dofs.free(l, c)) {
                    map[g] = d as u32;
                }
            }
        }
        map
    }

    /// True for a local node this rank owns.
    pub fn owns(&self, local_node: usize) -> bool {
        local_node < self.n_owned_nodes
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::FiniteElement;
    use crate::mesh::box_mesh::BoxMesh;
    use crate::mesh::dofs::Dirichlet;
    use crate::mesh::region::Region;
    use crate::problem::operators::Material;
    use crate::problem::tensor::Sym;
    use crate::{Elasticity, P1, P2};

    /// The ranks of slabs of elements along the element order (a crude partition: every rank
    /// gets elements, parts touch along faces, some nodes have three owners' elements around).
    fn slabs(n: usize, ranks: usize) -> Vec<usize> {
        (0..n).map(|e| (e * ranks / n).min(ranks - 1)).collect()
    }

    fn value(i: usize) -> f64 {
        ((i as f64) * 0.731).sin()
    }

    /// The operators on the parts reproduce the whole mesh's: a rank's strains are the whole
    /// mesh's at its elements, and the ranks' internal forces and stiffness diagonals summed
    /// at every dof are the whole mesh's — for P1 and P2, with 1, 2 and 3 ranks.
    #[test]
    fn parts_reproduce_the_whole_mesh_operators() {
        let elements: [Box<dyn FiniteElement>; 2] = [Box::new(P1::default()), Box::new(P2::default())];
        for element in elements {
            let mesh = element.prepare_mesh(BoxMesh::new([0.0; 3], [1.0, 1.0, 0.5], [3, 3, 2]).mesh().unwrap());
            let bc = [Dirichlet::clamped(Region::Group("zmin".into()))];
            let dofs = DofMap::new(&mesh, &bc).unwrap();
            let whole = element.build_with_dofs(mesh.clone(), dofs.clone());
            let u: Vec<f64> = (0..whole.n_dofs()).map(value).collect();
            let k = whole.points_per_element();
            let mut eps = vec![Sym::zeros(); whole.n_points()];
            whole.strain(&u, &mut eps);
            let sigma: Vec<Sym> = (0..whole.n_points()).map(|i| Sym::from_fn(|r, _| value(7 * i + r))).collect();
            let mut f = vec![0.0; whole.n_dofs()];
            whole.divergence(&sigma, &mut f);
            let c = Elasticity::new(100.0, 0.3).unwrap().stiffness_matrix();
            let kv = whole.stiffness(Material::Uniform(&c));
            let diag: Vec<f64> = (0..whole.n_dofs()).map(|j| kv[whole.pattern().col_ptr()[j]]).collect();
            for ranks in 1..=3 {
                let partition = Partition::new(&mesh, slabs(mesh.n_elements(), ranks), ranks).unwrap();
                let (mut f_sum, mut diag_sum) = (vec![0.0; whole.n_dofs()], vec![0.0; whole.n_dofs()]);
                let mut owned = 0;
                let couplings = partition.couplings(&mesh, &dofs);
                for rank in 0..ranks {
                    let part = MeshPart::new(&mesh, &dofs, &partition, &couplings, rank);
                    owned += part.n_owned_dofs;
                    // the couplings of every owned free row are the whole matrix's nonzeros in
                    // that row, split by the owner of their column's node
                    let (owner, _) = dofs.owners();
                    let (cp, ri) = (whole.pattern().col_ptr(), whole.pattern().row_idx());
                    let mut row_counts = vec![[0u32; 2]; whole.n_dofs()];
                    for j in 0..whole.n_dofs() {
                        for &i in &ri[cp[j]..cp[j + 1]] {
                            let other = |a: usize, b: usize| {
                                usize::from(
                                    partition.node_rank[owner[a] as usize] != partition.node_rank[owner[b] as usize],
                                )
                            };
                            row_counts[i][other(i, j)] += 1;
                            if i != j {
                                row_counts[j][other(j, i)] += 1;
                            }
                        }
                    }
                    for (l, &n) in part.nodes[..part.n_owned_nodes].iter().enumerate() {
                        for c in 0..3 {
                            if let Some(d) = dofs.free(n, c) {
                                assert_eq!(part.couplings[l], row_counts[d], "{ranks} ranks: node {n}");
                            }
                        }
                    }
                    let local = element.build_with_dofs(part.mesh.clone(), part.dofs.clone());
                    let map = part.from_global_dofs(&dofs);
                    let mut to_global = vec![usize::MAX; local.n_dofs()];
                    for (g, &l) in map.iter().enumerate().filter(|(_, l)| **l != FIXED) {
                        to_global[l as usize] = g;
                    }
                    let u_local: Vec<f64> = to_global.iter().map(|&g| u[g]).collect();
                    let mut eps_local = vec![Sym::zeros(); local.n_points()];
                    local.strain(&u_local, &mut eps_local);
                    for (le, &ge) in part.elements.iter().enumerate() {
                        for q in 0..k {
                            assert!((eps_local[le * k + q] - eps[ge * k + q]).norm() < 1e-14);
                        }
                    }
                    let sigma_local: Vec<Sym> = part
                        .elements
                        .iter()
                        .flat_map(|&ge| (0..k).map(move |q| ge * k + q))
                        .map(|i| sigma[i])
                        .collect();
                    let mut f_local = vec![0.0; local.n_dofs()];
                    local.divergence(&sigma_local, &mut f_local);
                    let kl = local.stiffness(Material::Uniform(&c));
                    for (l, &g) in to_global.iter().enumerate() {
                        f_sum[g] += f_local[l];
                        diag_sum[g] += kl[local.pattern().col_ptr()[l]];
                    }
                }
                assert_eq!(owned, whole.n_dofs(), "every free dof owned once ({ranks} ranks)");
                let err = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
                assert!(err(&f_sum, &f) < 1e-12, "{} ranks: Bᵀσ off by {:e}", ranks, err(&f_sum, &f));
                assert!(err(&diag_sum, &diag) < 1e-10, "{} ranks: diagonal off by {:e}", ranks, err(&diag_sum, &diag));
            }
        }
    }

    /// Every node is owned by a rank among its elements', and on two ranks the interface evens
    /// out the owned nodes: with d the difference of the parts' inner nodes and m the interface
    /// nodes, the owned counts differ by d − m when m < d, else by the parity of m − d ("the
    /// lowest rank" gave rank 0 the whole interface: d + m).
    #[test]
    fn interface_nodes_balance_the_owned_nodes() {
        let mesh = BoxMesh::new([0.0; 3], [1.0, 1.0, 0.5], [6, 5, 4]).mesh().unwrap();
        for (ranks, cut) in [(2, 0.5), (2, 0.3), (3, 0.5)] {
            let n = mesh.n_elements();
            // slabs, the first `cut` of the elements on rank 0, the rest evenly on the others
            let first = (cut * n as f64) as usize;
            let element_rank: Vec<usize> =
                (0..n).map(|e| if e < first { 0 } else { 1 + (e - first) * (ranks - 1) / (n - first) }).collect();
            let owner = owners(&mesh, &element_rank, ranks);
            let mut around = vec![Vec::new(); mesh.n_nodes()];
            for (e, &r) in element_rank.iter().enumerate() {
                mesh.element_nodes(e).for_each(|m| around[m].push(r));
            }
            let (mut inner, mut interface, mut owned) = (vec![0usize; ranks], 0, vec![0usize; ranks]);
            for (m, ranks_around) in around.iter().enumerate() {
                assert!(ranks_around.contains(&owner[m]), "node {m}: owner {} not among {ranks_around:?}", owner[m]);
                owned[owner[m]] += 1;
                if ranks_around.iter().all(|&r| r == ranks_around[0]) {
                    inner[ranks_around[0]] += 1;
                } else {
                    interface += 1;
                }
            }
            assert_eq!(owned.iter().sum::<usize>(), mesh.n_nodes());
            if ranks == 2 {
                let d = inner[0].abs_diff(inner[1]);
                let expected = if interface < d { d - interface } else { (interface - d) % 2 };
                assert_eq!(
                    owned[0].abs_diff(owned[1]),
                    expected,
                    "cut {cut}: inner {inner:?}, {interface} on the interface"
                );
            }
        }
    }

    #[test]
    fn a_rank_without_elements_is_an_error() {
        let mesh = BoxMesh::new([0.0; 3], [1.0; 3], [1, 1, 1]).mesh().unwrap();
        let e = Partition::new(&mesh, vec![0; mesh.n_elements()], 2).unwrap_err();
        assert_eq!(e, PartitionError::EmptyRank { rank: 1, ranks: 2, elements: 6 });
        assert!(e.to_string().contains("use fewer ranks"), "{e}");
    }
}
