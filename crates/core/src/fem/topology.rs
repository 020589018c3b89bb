//! What every nodal element shares: [`NodalParts`] (mesh, dofs, the gradients of the
//! barycentric coordinates, the node → element adjacency and the sparsity pattern of the
//! stiffness, for elements of N nodes each: 4 for P1, 10 for P2), and column assembly.

use crate::mesh::TetMesh;
use crate::mesh::dofs::DofMap;
use crate::problem::operators::{Material, RigidBodyModes};
use crate::problem::pattern::SymmetricPattern;
use crate::problem::tensor::SymOp;
use nalgebra::Matrix3;
use rayon::prelude::*;

/// Node → (element, local node) adjacency in CSR form: the elements around node n are
/// `adj[ptr[n]..ptr[n + 1]]`.
pub fn node_element_adjacency<const N: usize>(n_nodes: usize, elements: &[[usize; N]]) -> (Vec<usize>, Vec<(u32, u8)>) {
    let mut ptr = vec![0usize; n_nodes + 1];
    for t in elements {
        for &n in t {
            ptr[n + 1] += 1;
        }
    }
    for i in 0..n_nodes {
        ptr[i + 1] += ptr[i];
    }
    let mut fill = ptr.clone();
    let mut adj = vec![(0u32, 0u8); ptr[n_nodes]];
    for (e, t) in elements.iter().enumerate() {
        for (a, &n) in t.iter().enumerate() {
            adj[fill[n]] = (e as u32, a as u8);
            fill[n] += 1;
        }
    }
    (ptr, adj)
}

/// The lower-triangle pattern coupling every pair of free dofs of nodes sharing an element.
pub fn stiffness_pattern<const N: usize>(
    elements: &[[usize; N]],
    dofs: &DofMap,
    adj_ptr: &[usize],
    adj: &[(u32, u8)],
) -> SymmetricPattern {
    let neighbours: Vec<Vec<usize>> = (0..dofs.n_nodes())
        .into_par_iter()
        .map(|b| {
            let mut nb: Vec<usize> = adj[adj_ptr[b]..adj_ptr[b + 1]]
                .iter()
                .flat_map(|&(e, _)| elements[e as usize])
                .filter(|&a| a >= b)
                .collect();
            nb.sort_unstable();
            nb.dedup();
            nb
        })
        .collect();
    let mut col_ptr = Vec::with_capacity(dofs.n_free + 1);
    col_ptr.push(0);
    let mut row_idx = Vec::new();
    for (b, nb) in neighbours.iter().enumerate() {
        for c in 0..3 {
            let Some(j) = dofs.free(b, c) else { continue };
            for &a in nb {
                for k in 0..3 {
                    if let Some(i) = dofs.free(a, k).filter(|&i| i >= j) {
                        row_idx.push(i);
                    }
                }
            }
            col_ptr.push(row_idx.len());
        }
    }
    SymmetricPattern::new(dofs.n_free, col_ptr, row_idx)
}

/// Fills the values of the columns lo..hi of `pattern` (`vals` is their part of the values) by
/// `column(j, values of column j)`, halving the range in parallel until it has at most `leaf`
/// columns: each column owns its slice, so no two threads write the same value.
pub fn assemble_columns(
    pattern: &SymmetricPattern,
    lo: usize,
    hi: usize,
    vals: &mut [f64],
    leaf: usize,
    column: &(impl Fn(usize, &mut [f64]) + Sync),
) {
    let cp = pattern.col_ptr();
    if hi - lo <= leaf {
        let base = cp[lo];
        for j in lo..hi {
            column(j, &mut vals[cp[j] - base..cp[j + 1] - base]);
        }
    } else {
        let mid = (lo + hi) / 2;
        let (a, b) = vals.split_at_mut(cp[mid] - cp[lo]);
        rayon::join(
            || assemble_columns(pattern, lo, mid, a, leaf, column),
            || assemble_columns(pattern, mid, hi, b, leaf, column),
        );
    }
}

/// Whether `a` and `b` are the same matrix bit for bit.
fn same_bits(a: &SymOp, b: &SymOp) -> bool {
    a.iter().zip(b.iter()).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// The elements with `points` stress points each (numbered element by element) at some point
/// of which `material` is not `reference` bit for bit.
fn elements_off(material: &Material<'_>, reference: &SymOp, n_elements: usize, points: usize) -> Vec<bool> {
    match material {
        Material::Uniform(c) => vec![!same_bits(c, reference); n_elements],
        Material::PerPoint(_) => (0..n_elements)
            .into_par_iter()
            .map(|e| (0..points).any(|q| !same_bits(material.at(points * e + q), reference)))
            .collect(),
    }
}

/// The node → element adjacency (pointers, entries) and the stiffness pattern of a mesh's
/// elements.
pub type Topology = (Vec<usize>, Vec<(u32, u8)>, SymmetricPattern);

/// The [`Topology`] of elements with the nodes `elements`, on `n_nodes` nodes numbered by `dofs`.
pub fn element_topology<const N: usize>(elements: &[[usize; N]], n_nodes: usize, dofs: &DofMap) -> Topology {
    let (adj_ptr, adj) = node_element_adjacency(n_nodes, elements);
    let pattern = stiffness_pattern(elements, dofs, &adj_ptr, &adj);
    (adj_ptr, adj, pattern)
}

/// What every nodal element is built on (theory §3, §10): the mesh (of the order the element
/// needs), the numbering of its nodal dofs, the gradients of the barycentric coordinates, the
/// node → element adjacency, each free dof's node and component, and the stiffness pattern. An
/// element adds its own strain operator to it.
#[derive(Debug)]
pub struct NodalParts {
    /// The mesh.
    pub mesh: TetMesh,
    /// The nodal dofs.
    pub dofs: DofMap,
    /// Gradients of the barycentric coordinates of each element.
    pub grads: Vec<[[f64; 3]; 4]>,
    /// Node → (element, local node) adjacency, CSR.
    pub adj_ptr: Vec<usize>,
    /// Its entries.
    pub adj: Vec<(u32, u8)>,
    /// Free dof → node.
    pub dof_node: Vec<u32>,
    /// Free dof → component.
    pub dof_comp: Vec<u8>,
    /// The lower-triangle pattern of assembled matrices.
    pub pattern: SymmetricPattern,
}

impl NodalParts {
    /// The parts on `mesh` with the dof numbering `dofs`, and the element volumes; `topology`
    /// gives the adjacency and the pattern of the element's nodes ([`element_topology`] of the
    /// vertices for P1, of the ten nodes for P2).
    pub fn new(mesh: TetMesh, dofs: DofMap, topology: impl FnOnce(&TetMesh, &DofMap) -> Topology) -> (Self, Vec<f64>) {
        let (grads, volumes): (Vec<_>, Vec<_>) =
            (0..mesh.n_elements()).into_par_iter().map(|e| element_gradients(&mesh, e)).unzip();
        let (adj_ptr, adj, pattern) = topology(&mesh, &dofs);
        let (dof_node, dof_comp) = dofs.owners();
        (Self { mesh, dofs, grads, adj_ptr, adj, dof_node, dof_comp, pattern }, volumes)
    }

    /// The displacement of node `n` on the axes from the free dofs `u` (fixed components 0; a
    /// node's frame applied, theory §14.4).
    #[inline]
    pub fn nodal(&self, u: &[f64], n: usize) -> [f64; 3] {
        self.dofs.displacement(u, n)
    }

    /// [`crate::problem::operators::ElementOperators::reassemble`] for an element with `points`
    /// stress points per element whose `column(j, values of column j)` gathers column j from the
    /// elements around its node: the columns of nodes with no element off `reference` now or
    /// before are kept, the others assembled (by [`assemble_columns`] with `leaf`).
    #[allow(clippy::too_many_arguments)]
    pub fn reassemble(
        &self,
        material: &Material<'_>,
        reference: &SymOp,
        points: usize,
        was_off: &mut Vec<bool>,
        values: &mut [f64],
        leaf: usize,
        column: &(impl Fn(usize, &mut [f64]) + Sync),
    ) {
        let n_elements = self.mesh.n_elements();
        let off = elements_off(material, reference, n_elements, points);
        let n = self.dofs.n_free;
        if was_off.len() != n_elements {
            assemble_columns(&self.pattern, 0, n, values, leaf, column);
        } else {
            let touched = |b: usize| {
                self.adj[self.adj_ptr[b]..self.adj_ptr[b + 1]]
                    .iter()
                    .any(|&(e, _)| off[e as usize] || was_off[e as usize])
            };
            let changed = |j: usize, col: &mut [f64]| {
                if touched(self.dof_node[j] as usize) {
                    column(j, col);
                }
            };
            assemble_columns(&self.pattern, 0, n, values, leaf, &changed);
        }
        *was_off = off;
    }

    /// The rigid-body motions at the nodes of the free dofs, along their directions.
    pub fn rigid_body_modes(&self) -> RigidBodyModes {
        let directions: Vec<[f64; 3]> = (self.dof_node.iter().zip(&self.dof_comp))
            .map(|(&n, &k)| self.dofs.direction(n as usize, k as usize))
            .collect();
        RigidBodyModes::along(self.dof_node.clone(), &directions, &self.mesh.nodes)
    }
}

/// Gradients of the barycentric coordinates and the volume of element e.
fn element_gradients(mesh: &TetMesh, e: usize) -> ([[f64; 3]; 4], f64) {
    let x = mesh.tets[e].map(|n| mesh.nodes[n]);
    let jac = Matrix3::from_fn(|i, k| x[k + 1][i] - x[0][i]);
    let inv = jac.try_inverse().expect("validated mesh has no degenerate element");
    let mut g = [[0.0; 3]; 4];
    for a in 1..4 {
        for i in 0..3 {
            g[a][i] = inv[(a - 1, i)];
            g[0][i] -= inv[(a - 1, i)];
        }
    }
    (g, jac.determinant() / 6.0)
}
