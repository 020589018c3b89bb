//! The P1–P0 element (theory §3): continuous piecewise-linear displacements on
//! tetrahedra, stresses and hardening constant per element. The strain of a P1 field is
//! constant per tetrahedron, so one stress point per element is exact.
//!
//! Hot loops gather rather than scatter, so they run in parallel without locks or colouring:
//! the strain loops over elements, the internal force Bᵀσ over degrees of freedom (summing the
//! elements around the node), and assembly over matrix columns (each column owns its slice of
//! the values; the sparsity pattern is built once).

use super::topology::{NodalParts, assemble_columns, element_topology};
use super::{Discretisation, VtkCell};
use crate::error::SceneError;
use crate::mesh::TetMesh;
use crate::mesh::dofs::{Dirichlet, DofMap, FIXED};
use crate::problem::operators::{ElementOperators, Material, RigidBodyModes};
use crate::problem::pattern::SymmetricPattern;
use crate::problem::tensor::{SQRT2, Sym, SymOp};
use rayon::prelude::*;

/// The P1–P0 element as a scene's choice: `[discretisation] type = "p1"` (the paper's; a scene
/// without the table gets P2).
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct P1 {}

#[typetag::serde(name = "p1")]
impl super::FiniteElement for P1 {
    /// The vertices of a second-order mesh: P1 has no edge nodes.
    fn prepare_mesh(&self, mesh: TetMesh) -> TetMesh {
        if mesh.is_second_order() { mesh.first_order() } else { mesh }
    }

    fn build_with_dofs(&self, mesh: TetMesh, dofs: DofMap) -> Box<dyn Discretisation> {
        Box::new(P1P0Element::with_dofs(mesh, dofs))
    }
}

/// The P1–P0 element on a tetrahedral mesh: P1 displacements, P0 generalised stresses.
#[derive(Debug)]
pub struct P1P0Element {
    /// Mesh, dofs, gradients, adjacency, pattern.
    parts: NodalParts,
    /// |T|.
    weights: Vec<f64>,
}

impl P1P0Element {
    /// The element on the vertices of `mesh` (a second-order mesh's edge nodes are dropped)
    /// with the Dirichlet conditions `dirichlet`.
    pub fn new(mesh: TetMesh, dirichlet: &[Dirichlet]) -> Result<Self, SceneError> {
        let mesh = super::FiniteElement::prepare_mesh(&P1::default(), mesh);
        let dofs = DofMap::new(&mesh, dirichlet)?;
        Ok(Self::with_dofs(mesh, dofs))
    }

    /// The element on the first-order `mesh` with the dof numbering `dofs` (a rank's part of a
    /// distributed problem numbers its own, theory §12).
    pub fn with_dofs(mesh: TetMesh, dofs: DofMap) -> Self {
        assert!(!mesh.is_second_order(), "P1 takes a first-order mesh (FiniteElement::prepare_mesh)");
        let (parts, weights) = NodalParts::new(mesh, dofs, |m, d| element_topology(&m.tets, m.n_nodes(), d));
        Self { parts, weights }
    }

    /// Column j of Σ_T |T| B_Tᵀ C_T B_T (rows ≥ j), gathered from the elements around its node.
    fn assemble_column(&self, j: usize, col: &mut [f64], material: &Material<'_>) {
        col.iter_mut().for_each(|v| *v = 0.0);
        let cp = self.parts.pattern.col_ptr();
        let rows = &self.parts.pattern.row_idx()[cp[j]..cp[j + 1]];
        let (b, c) = (self.parts.dof_node[j] as usize, self.parts.dof_comp[j] as usize);
        for &(e, lb) in &self.parts.adj[self.parts.adj_ptr[b]..self.parts.adj_ptr[b + 1]] {
            let e = e as usize;
            let g = &self.parts.grads[e];
            let dofs = &self.parts.dofs;
            let cb = material.at(e) * dofs.along(b, c, |c| strain_of_unit(&g[lb as usize], c)) * self.weights[e];
            for (a, &na) in self.parts.mesh.tets[e].iter().enumerate() {
                let da = self.parts.dofs.dof[na];
                // the free dofs of node a that are ≥ j are consecutive rows of the column
                let Some(first) = (0..3).find(|&k| da[k] != FIXED && da[k] as usize >= j) else { continue };
                let mut pos = rows.binary_search(&(da[first] as usize)).expect("pattern holds every element coupling");
                for (k, &dk) in da.iter().enumerate().skip(first) {
                    if dk != FIXED {
                        col[pos] += dofs.along(na, k, |k| strain_of_unit_dot(&g[a], k, &cb));
                        pos += 1;
                    }
                }
            }
        }
    }
}

/// The Mandel strain of the unit displacement e_c at a node with barycentric gradient g:
/// the column of B for that dof.
#[inline]
pub(super) fn strain_of_unit(g: &[f64; 3], c: usize) -> Sym {
    let s = 1.0 / SQRT2;
    match c {
        0 => Sym::new(g[0], 0.0, 0.0, 0.0, s * g[2], s * g[1]),
        1 => Sym::new(0.0, g[1], 0.0, s * g[2], 0.0, s * g[0]),
        _ => Sym::new(0.0, 0.0, g[2], s * g[1], s * g[0], 0.0),
    }
}

/// strain_of_unit(g, c) · v without forming the vector: row c of the tensor v applied to g.
#[inline]
pub(super) fn strain_of_unit_dot(g: &[f64; 3], c: usize, v: &Sym) -> f64 {
    let s = 1.0 / SQRT2;
    match c {
        0 => g[0] * v[0] + s * (g[2] * v[4] + g[1] * v[5]),
        1 => g[1] * v[1] + s * (g[2] * v[3] + g[0] * v[5]),
        _ => g[2] * v[2] + s * (g[1] * v[3] + g[0] * v[4]),
    }
}

impl Discretisation for P1P0Element {
    fn mesh(&self) -> &TetMesh {
        &self.parts.mesh
    }
    fn unconstrained(&self) -> Option<Box<dyn Discretisation>> {
        let dofs = DofMap::from_fixed(&vec![[false; 3]; self.parts.mesh.n_nodes()]);
        Some(Box::new(Self::with_dofs(self.parts.mesh.clone(), dofs)))
    }
    fn dofs(&self) -> &DofMap {
        &self.parts.dofs
    }
    fn name(&self) -> &'static str {
        "p1"
    }
    /// VTK_TETRA.
    fn vtk_cell(&self) -> VtkCell {
        VtkCell { type_id: 10, nodes: 4 }
    }
}

impl ElementOperators for P1P0Element {
    fn n_dofs(&self) -> usize {
        self.parts.dofs.n_free
    }

    fn rigid_body_modes(&self) -> Option<RigidBodyModes> {
        Some(self.parts.rigid_body_modes())
    }

    fn pattern(&self) -> &SymmetricPattern {
        &self.parts.pattern
    }

    fn n_points(&self) -> usize {
        self.parts.mesh.n_elements()
    }

    fn weights(&self) -> &[f64] {
        &self.weights
    }

    fn strain(&self, u: &[f64], eps: &mut [Sym]) {
        eps.par_iter_mut().enumerate().for_each(|(e, out)| {
            let g = &self.parts.grads[e];
            // ∇u = Σ_a u_a ⊗ ∇λ_a
            let mut m = [[0.0; 3]; 3];
            for (a, &n) in self.parts.mesh.tets[e].iter().enumerate() {
                let ua = self.parts.nodal(u, n);
                for i in 0..3 {
                    for k in 0..3 {
                        m[i][k] += ua[i] * g[a][k];
                    }
                }
            }
            let s = 1.0 / SQRT2;
            *out = Sym::new(
                m[0][0],
                m[1][1],
                m[2][2],
                s * (m[1][2] + m[2][1]),
                s * (m[0][2] + m[2][0]),
                s * (m[0][1] + m[1][0]),
            );
        });
    }

    fn divergence(&self, sigma: &[Sym], f: &mut [f64]) {
        f.par_iter_mut().enumerate().for_each(|(j, fj)| {
            let (n, c) = (self.parts.dof_node[j] as usize, self.parts.dof_comp[j] as usize);
            let of_axis = |c: usize| -> f64 {
                self.parts.adj[self.parts.adj_ptr[n]..self.parts.adj_ptr[n + 1]]
                    .iter()
                    .map(|&(e, a)| {
                        self.weights[e as usize]
                            * strain_of_unit_dot(&self.parts.grads[e as usize][a as usize], c, &sigma[e as usize])
                    })
                    .sum()
            };
            *fj = self.parts.dofs.along(n, c, of_axis);
        });
    }

    fn strain_entries(&self) -> Vec<(usize, usize, usize, f64)> {
        let mut out = Vec::with_capacity(self.parts.mesh.n_elements() * 36);
        for (e, t) in self.parts.mesh.tets.iter().enumerate() {
            for (a, &n) in t.iter().enumerate() {
                for c in 0..3 {
                    let Some(j) = self.parts.dofs.free(n, c) else { continue };
                    let col = self.parts.dofs.along(n, c, |c| strain_of_unit(&self.parts.grads[e][a], c));
                    out.extend((0..6).filter(|&k| col[k] != 0.0).map(|k| (e, k, j, col[k])));
                }
            }
        }
        out
    }

    fn assemble(&self, material: Material<'_>, values: &mut [f64]) {
        assert_eq!(values.len(), self.parts.pattern.nnz());
        let column = |j: usize, col: &mut [f64]| self.assemble_column(j, col, &material);
        assemble_columns(&self.parts.pattern, 0, self.parts.dofs.n_free, values, 128, &column);
    }

    fn reassemble(&self, material: Material<'_>, reference: &SymOp, was_off: &mut Vec<bool>, values: &mut [f64]) {
        assert_eq!(values.len(), self.parts.pattern.nnz());
        let column = |j: usize, col: &mut [f64]| self.assemble_column(j, col, &material);
        self.parts.reassemble(&material, reference, 1, was_off, values, 128, &column);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::operator_checks;
    use crate::mesh::box_mesh::BoxMesh;
    use crate::mesh::region::Region;
    use nalgebra::Matrix3;

    fn problem() -> P1P0Element {
        let mesh =
            BoxMesh::new([0.0, 0.0, 0.0], [1.0, 2.0, 1.0], [3, 4, 2]).graded([0.2, 0.0, 0.0], 2.0).mesh().unwrap();
        let bc = [
            Dirichlet::clamped(Region::Group("zmax".into())),
            Dirichlet::roller(Region::Group("xmin".into()), crate::mesh::dofs::Component::X),
        ];
        P1P0Element::new(mesh, &bc).unwrap()
    }

    #[test]
    fn strain_of_a_linear_field_is_exact() {
        let mesh = BoxMesh::new([0.0; 3], [1.0; 3], [2, 2, 2]).mesh().unwrap();
        let l = P1P0Element::new(mesh, &[]).unwrap();
        let grad = Matrix3::new(0.1, 0.2, -0.3, 0.05, -0.4, 0.7, 0.3, 0.0, 0.25);
        let mut u = vec![0.0; l.n_dofs()];
        for (n, x) in l.parts.mesh.nodes.iter().enumerate() {
            let v = grad * nalgebra::Vector3::from(*x);
            for c in 0..3 {
                u[l.parts.dofs.free(n, c).unwrap()] = v[c];
            }
        }
        let mut eps = vec![Sym::zeros(); l.n_points()];
        l.strain(&u, &mut eps);
        let exact = crate::problem::tensor::from_matrix(&grad);
        assert!(eps.iter().all(|e| (e - exact).norm() < 1e-14));
    }

    /// The element of [`problem`] with an inclined support on ymin and another on xmax
    /// meeting it along an edge (nodal frames, theory §14.4).
    fn inclined() -> P1P0Element {
        let mesh = BoxMesh::new([0.0; 3], [1.0, 2.0, 1.0], [3, 4, 2]).mesh().unwrap();
        let bc = [
            Dirichlet::clamped(Region::Group("zmax".into())),
            Dirichlet::inclined(Region::Group("ymin".into()), [0.3, -1.0, 0.2]),
            Dirichlet::inclined(Region::Group("xmax".into()), [1.0, 0.4, 0.0]),
        ];
        let mesh = super::super::FiniteElement::prepare_mesh(&P1::default(), mesh);
        P1P0Element::with_dofs(mesh.clone(), DofMap::with_values(&mesh, &bc).unwrap())
    }

    #[test]
    fn divergence_is_the_transpose_of_strain() {
        operator_checks::divergence_is_the_transpose_of_strain(&problem());
        operator_checks::divergence_is_the_transpose_of_strain(&inclined());
    }

    #[test]
    fn strain_entries_reproduce_the_strain() {
        operator_checks::strain_entries_reproduce_the_strain(&problem(), 1e-13);
        operator_checks::strain_entries_reproduce_the_strain(&inclined(), 1e-13);
    }

    #[test]
    fn assembled_stiffness_matches_the_operator() {
        operator_checks::assembled_stiffness_matches_the_operator(&problem());
        operator_checks::assembled_stiffness_matches_the_operator(&inclined());
    }

    #[test]
    fn reassembly_equals_the_assembly() {
        operator_checks::reassembly_equals_the_assembly(&problem(), 1);
        operator_checks::reassembly_equals_the_assembly(&inclined(), 1);
    }

    #[test]
    fn a_frame_holds_the_normal_component_and_keeps_the_others() {
        // a nodal field from free values has no component along the normal at the supported
        // nodes, and the rigid-body modes are the motions' components in the nodes' frames
        let l = inclined();
        assert!(l.parts.dofs.has_frames());
        let n = [0.3, -1.0, 0.2];
        let norm = (0.09f64 + 1.0 + 0.04).sqrt();
        let u: Vec<f64> = (0..l.n_dofs()).map(|j| (j as f64 * 0.37).sin()).collect();
        let modes = l.rigid_body_modes().unwrap();
        let rot: Vec<f64> = (0..modes.n()).map(|d| modes.modes[6 * d + 5]).collect();
        let (nodal, rot_nodal) = (l.nodal_vectors(&u), l.nodal_vectors(&rot));
        let mut on_plane = 0;
        for f in Region::Group("ymin".into()).facets(&l.parts.mesh) {
            for v in l.parts.mesh.facet_nodes(f) {
                let un: f64 = (0..3).map(|c| nodal[v][c] * n[c]).sum::<f64>() / norm;
                assert!(un.abs() < 1e-15, "node {v}: n·u = {un}");
                on_plane += 1;
            }
        }
        assert!(on_plane > 0);
        // at a node free of supports the rotation about z is (−y, x, 0) about the centroid of
        // the free dofs' nodes: its differences between two free nodes are exact
        let dofs = &l.parts.dofs;
        let free: Vec<usize> =
            (0..l.parts.mesh.n_nodes()).filter(|&v| dofs.dof[v].iter().all(|&d| d != FIXED)).collect();
        let (a, b) = (free[0], free[free.len() - 1]);
        let (xa, xb) = (l.parts.mesh.nodes[a], l.parts.mesh.nodes[b]);
        assert!((rot_nodal[a][0] - rot_nodal[b][0] + (xa[1] - xb[1])).abs() < 1e-14);
        // at a framed node the mode is the motion's projection on the free directions
        // a node of ymin only: held along n alone
        let only_ymin = |v: &usize| {
            let x = l.parts.mesh.nodes[*v];
            x[1] == 0.0 && x[0] < 1.0 && x[2] < 1.0
        };
        let v = (0..l.parts.mesh.n_nodes()).find(only_ymin).unwrap();
        assert!(dofs.frame(v).is_some());
        let x = l.parts.mesh.nodes[v];
        let m: [f64; 3] = std::array::from_fn(|c| [-(x[1] - xb[1]), x[0] - xb[0], 0.0][c] + rot_nodal[b][c]);
        let un: f64 = (0..3).map(|c| rot_nodal[v][c] * n[c]).sum::<f64>() / norm;
        let mn: f64 = (0..3).map(|c| m[c] * n[c]).sum::<f64>() / norm;
        for c in 0..3 {
            let want = m[c] - mn * n[c] / norm;
            assert!((rot_nodal[v][c] - want).abs() < 1e-14 && un.abs() < 1e-15, "{:?} vs {m:?}", rot_nodal[v]);
        }
    }
}
