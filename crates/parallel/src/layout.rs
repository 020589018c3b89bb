//! Where a rank's dofs sit in PETSc's vectors and matrices (theory §12). Every node has three
//! rows, one per component, fixed components included (they are identity rows): the rows of a
//! rank's owned nodes are its contiguous range `3 · (first partitioned index + l) + c`, in the
//! order of its local nodes; the rows of its ghost nodes are ghosts of the vectors. A local free
//! dof of component c at local node l sits at position `3 l + c` of a vector's local form.

use saddle_core::distributed::MeshPart;
use saddle_core::mesh::dofs::FIXED;
use saddle_mpi::Index;

/// A rank's dofs in the distributed vectors and matrices (module docs).
#[derive(Clone, Debug)]
pub struct Layout {
    /// Owned nodes (the first local nodes).
    pub n_owned_nodes: usize,
    /// Local nodes, owned and ghost.
    pub n_local_nodes: usize,
    /// Owned free dofs (the first local dofs).
    pub n_owned_dofs: usize,
    /// The position of every local free dof in a vector's local form: 3 · local node + c.
    pub dof_slot: Vec<usize>,
    /// The global row of every local free dof.
    pub dof_row: Vec<Index>,
    /// The global rows of the ghost nodes' components, in the order of the local form.
    pub ghost_rows: Vec<Index>,
    /// The global rows of the owned nodes' fixed components (Dirichlet conditions).
    pub dirichlet_rows: Vec<Index>,
    /// The owned nodes' coordinates, x, y, z per node (the rigid-body near-null space).
    pub owned_coordinates: Vec<f64>,
    /// Per owned row, its nonzeros in the columns of the owned rows and in the others' (the
    /// matrix's exact preallocation: [`MeshPart::couplings`] at a free row, the diagonal at a
    /// fixed one).
    pub row_nonzeros: [Vec<Index>; 2],
}

impl Layout {
    /// The layout of `part`.
    pub fn new(part: &MeshPart) -> Self {
        let (node, comp) = part.dofs.owners();
        let dof_slot: Vec<usize> = node.iter().zip(&comp).map(|(&n, &c)| 3 * n as usize + c as usize).collect();
        let dof_row = part.dof_rows().into_iter().map(|r| r as Index).collect();
        let n_local_nodes = part.nodes.len();
        let ghost_rows = (part.n_owned_nodes..n_local_nodes)
            .flat_map(|l| (0..3).map(move |c| (3 * part.node_index[l] + c) as Index))
            .collect();
        let dirichlet_rows = (0..part.n_owned_nodes)
            .flat_map(|l| (0..3).filter(move |&c| part.dofs.dof[l][c] == FIXED).map(move |c| (l, c)))
            .map(|(l, c)| (3 * part.node_index[l] + c) as Index)
            .collect();
        let owned_coordinates = part.mesh.nodes[..part.n_owned_nodes].iter().flatten().copied().collect();
        let (mut diagonal, mut off_diagonal) = (Vec::new(), Vec::new());
        for (l, &[d, o]) in part.couplings.iter().enumerate() {
            for c in 0..3 {
                let fixed = part.dofs.dof[l][c] == FIXED;
                diagonal.push(if fixed { 1 } else { d as Index });
                off_diagonal.push(if fixed { 0 } else { o as Index });
            }
        }
        Self {
            n_owned_nodes: part.n_owned_nodes,
            n_local_nodes,
            n_owned_dofs: part.n_owned_dofs,
            dof_slot,
            dof_row,
            ghost_rows,
            dirichlet_rows,
            owned_coordinates,
            row_nonzeros: [diagonal, off_diagonal],
        }
    }

    /// Number of local free dofs, owned and ghost.
    pub fn n_local_dofs(&self) -> usize {
        self.dof_slot.len()
    }

    /// A ghosted vector of this layout (three entries per node). Collective.
    pub fn vector(&self, session: &saddle_mpi::Petsc) -> saddle_mpi::Result<saddle_mpi::GhostVector> {
        saddle_mpi::GhostVector::new(session, 3 * self.n_owned_nodes, &self.ghost_rows)
    }
}
