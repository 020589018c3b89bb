//! The P2 element (theory §10): continuous piecewise-quadratic displacements on
//! 10-node tetrahedra, generalised stresses at the four Gauss points of every element, and the
//! mean-dilatation strain operator B̄.
//!
//! B̄ replaces the volumetric strain tr ε at each point by its mean over the element (the L²
//! projection of div u onto P0): `ε̄ = ε(u) + ⅓(θ̄_T − tr ε(u)) I`, θ̄_T = (1/|T|)∫_T div u.
//! Nearly incompressible elasticity and isochoric plastic flow then constrain one volume change
//! per element instead of one per point, and P2–P0 is inf-sup stable, so the element does not
//! lock. B̄ is linear, so L keeps the form of theory §3 with B̄ in place of B: every yield
//! surface, obstacle and solver works unchanged.
//!
//! The four-point rule integrates the energy of a P2 field exactly (ε(u) is linear on an
//! element, the energy quadratic). Elements are straight-sided (the geometry is the vertices').
//! Hot loops gather, as in [`super::p1p0`]: strains over elements, Bᵀσ over dofs, assembly
//! over matrix columns.

use super::dual_quadratic::{ContactRows, dual_quadratic_rows};
use super::p1p0::{strain_of_unit, strain_of_unit_dot};
use super::topology::{NodalParts, assemble_columns, element_topology};
use super::{Discretisation, VtkCell};
use crate::error::SceneError;
use crate::mesh::dofs::{Dirichlet, DofMap, FIXED};
use crate::mesh::{TET_EDGES, TetMesh};
use crate::problem::displacements::ConstraintRows;
use crate::problem::elasticity::Elasticity;
use crate::problem::operators::{ElementOperators, Material, PressureRows, RigidBodyModes};
use crate::problem::pattern::SymmetricPattern;
use crate::problem::tensor::{SQRT2, Sym, SymOp};
use rayon::prelude::*;

/// Stress points per element: the four-point Gauss rule of degree 2.
pub const POINTS: usize = 4;
/// Nodes per element.
const NODES: usize = 10;
/// Barycentric coordinates of Gauss point q: `A` at vertex q, `B` at the other three.
const A: f64 = 0.585_410_196_624_968_5;
const B: f64 = 0.138_196_601_125_010_5;

/// The P2 element as a scene's choice: `[discretisation] type = "p2"`, with
/// `mean_dilatation = true` (B̄, the default) or `false` (plain P2, which locks as ν → ½; for
/// studies).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct P2 {
    /// B̄: the volumetric strain is the element mean.
    #[serde(default = "yes")]
    pub mean_dilatation: bool,
    /// The contact rows: `nodal` (the default) or `dual_quadratic` (theory §10.1).
    #[serde(default, skip_serializing_if = "ContactRows::is_nodal")]
    pub contact_rows: ContactRows,
}

fn yes() -> bool {
    true
}

impl Default for P2 {
    fn default() -> Self {
        Self { mean_dilatation: true, contact_rows: ContactRows::default() }
    }
}

#[typetag::serde(name = "p2")]
impl super::FiniteElement for P2 {
    /// The second-order mesh (a node at the midpoint of every edge of a first-order one).
    fn prepare_mesh(&self, mesh: TetMesh) -> TetMesh {
        if mesh.is_second_order() { mesh } else { mesh.second_order() }
    }

    fn build_with_dofs(&self, mesh: TetMesh, dofs: DofMap) -> Box<dyn Discretisation> {
        Box::new(
            P2Element::with_dofs(mesh, dofs)
                .with_mean_dilatation(self.mean_dilatation)
                .with_contact_rows(self.contact_rows),
        )
    }

    fn recombines_contact_rows(&self) -> bool {
        self.contact_rows != ContactRows::Nodal
    }
}

/// The P2 element: P2 displacements with the B̄ strain and stresses at four points per element.
#[derive(Debug)]
pub struct P2Element {
    /// Mesh (second order), dofs, gradients, adjacency, pattern.
    parts: NodalParts,
    /// |T|/4 at each of the four points of every element.
    weights: Vec<f64>,
    /// The ten nodes of each element: vertices, then edge nodes in the order of [`TET_EDGES`].
    nodes: Vec<[usize; NODES]>,
    /// Whether the volumetric strain is the element mean (B̄; the default) or pointwise (plain
    /// P2, which locks as ν → ½).
    mean_dilatation: bool,
    /// The contact rows (theory §10.1).
    contact_rows: ContactRows,
}

/// ∇N_a at Gauss point q, from the gradients g of the barycentric coordinates: vertex functions
/// λ_a(2λ_a − 1), edge functions 4λ_iλ_j.
#[inline]
fn shape_gradient(g: &[[f64; 3]; 4], a: usize, q: usize) -> [f64; 3] {
    let l = |i: usize| if i == q { A } else { B };
    if a < 4 {
        let s = 4.0 * l(a) - 1.0;
        g[a].map(|x| s * x)
    } else {
        let [i, j] = TET_EDGES[a - 4];
        let (li, lj) = (l(i), l(j));
        std::array::from_fn(|k| 4.0 * (li * g[j][k] + lj * g[i][k]))
    }
}

/// (1/|T|)∫_T ∇N_a: zero for a vertex function, ∇λ_i + ∇λ_j for the edge (i, j).
#[inline]
fn mean_gradient(g: &[[f64; 3]; 4], a: usize) -> [f64; 3] {
    if a < 4 {
        [0.0; 3]
    } else {
        let [i, j] = TET_EDGES[a - 4];
        std::array::from_fn(|k| g[i][k] + g[j][k])
    }
}

/// The B̄ column of dof (a, c) at point q: ε(N_a e_c) + δ I, with δ = ⅓(mean − point value) of
/// ∂_c N_a (zero without mean dilatation). Returns the pointwise gradient and δ.
#[inline]
fn column(g: &[[f64; 3]; 4], a: usize, c: usize, q: usize, mean_dilatation: bool) -> ([f64; 3], f64) {
    let ga = shape_gradient(g, a, q);
    let delta = if mean_dilatation { (mean_gradient(g, a)[c] - ga[c]) / 3.0 } else { 0.0 };
    (ga, delta)
}

/// The B̄ column of dof (a, c) at point q as a strain: ε(N_a e_c) + δ I ([`column`]).
#[inline]
fn column_strain(g: &[[f64; 3]; 4], a: usize, c: usize, q: usize, mean_dilatation: bool) -> Sym {
    let (ga, delta) = column(g, a, c, q, mean_dilatation);
    let mut col = strain_of_unit(&ga, c);
    for k in 0..3 {
        col[k] += delta;
    }
    col
}

impl P2Element {
    /// The element on the second-order mesh of `mesh` (a first-order mesh gets a node at the
    /// midpoint of every edge, [`TetMesh::second_order`]) with the Dirichlet conditions
    /// `dirichlet`, and the mean-dilatation B̄ strain.
    pub fn new(mesh: TetMesh, dirichlet: &[Dirichlet]) -> Result<Self, SceneError> {
        let mesh = super::FiniteElement::prepare_mesh(&P2::default(), mesh);
        let dofs = DofMap::new(&mesh, dirichlet)?;
        Ok(Self::with_dofs(mesh, dofs))
    }

    /// The element on the second-order `mesh` with the dof numbering `dofs` (a rank's part of
    /// a distributed problem numbers its own, theory §12), with the mean-dilatation B̄ strain.
    pub fn with_dofs(mesh: TetMesh, dofs: DofMap) -> Self {
        let so = mesh.second_order.as_ref().expect("P2 takes a second-order mesh (FiniteElement::prepare_mesh)");
        let nodes: Vec<[usize; NODES]> = mesh
            .tets
            .iter()
            .zip(&so.tet_edges)
            .map(|(t, ed)| std::array::from_fn(|a| if a < 4 { t[a] } else { ed[a - 4] }))
            .collect();
        let (parts, volumes) = NodalParts::new(mesh, dofs, |m, d| element_topology(&nodes, m.n_nodes(), d));
        let weights = volumes.iter().flat_map(|v| [v / POINTS as f64; POINTS]).collect();
        Self { parts, weights, nodes, mean_dilatation: true, contact_rows: ContactRows::default() }
    }

    /// The same problem with the volumetric strain pointwise (`false`: plain P2, which locks as
    /// ν → ½) or the element mean (`true`, B̄: the default).
    pub fn with_mean_dilatation(mut self, on: bool) -> Self {
        self.mean_dilatation = on;
        self
    }

    /// The same element with the contact rows `rows` (theory §10.1).
    pub fn with_contact_rows(mut self, rows: ContactRows) -> Self {
        self.contact_rows = rows;
        self
    }

    /// ∇u at the four points of element `e`: Σ_a u_a ⊗ ∇N_a(x_q).
    #[inline]
    fn point_gradients(&self, e: usize, u: &[f64]) -> [[[f64; 3]; 3]; POINTS] {
        let g = &self.parts.grads[e];
        let mut m = [[[0.0; 3]; 3]; POINTS];
        for (a, &n) in self.nodes[e].iter().enumerate() {
            let ua = self.parts.nodal(u, n);
            if ua == [0.0; 3] {
                continue;
            }
            for (q, mq) in m.iter_mut().enumerate() {
                let ga = shape_gradient(g, a, q);
                for i in 0..3 {
                    for k in 0..3 {
                        mq[i][k] += ua[i] * ga[k];
                    }
                }
            }
        }
        m
    }

    /// Column j of Σ_T Σ_q w_q B̄_qᵀ C_q B̄_q (rows ≥ j), gathered from the elements around its
    /// node.
    fn assemble_column(&self, j: usize, col: &mut [f64], material: &Material<'_>) {
        col.iter_mut().for_each(|v| *v = 0.0);
        let cp = self.parts.pattern.col_ptr();
        let rows = &self.parts.pattern.row_idx()[cp[j]..cp[j + 1]];
        let (b, c) = (self.parts.dof_node[j] as usize, self.parts.dof_comp[j] as usize);
        let md = self.mean_dilatation;
        for &(e, lb) in &self.parts.adj[self.parts.adj_ptr[b]..self.parts.adj_ptr[b + 1]] {
            let e = e as usize;
            let g = &self.parts.grads[e];
            // C B̄ of the column at each point, weighted, and its trace
            let mut cb = [Sym::zeros(); POINTS];
            let mut tr = [0.0; POINTS];
            for q in 0..POINTS {
                let bq = self.parts.dofs.along(b, c, |c| column_strain(g, lb as usize, c, q, md));
                cb[q] = material.at(POINTS * e + q) * bq * self.weights[POINTS * e + q];
                tr[q] = cb[q][0] + cb[q][1] + cb[q][2];
            }
            for a in 0..NODES {
                let da = self.parts.dofs.dof[self.nodes[e][a]];
                let Some(first) = (0..3).find(|&k| da[k] != FIXED && da[k] as usize >= j) else { continue };
                let mut pos = rows.binary_search(&(da[first] as usize)).expect("pattern holds every element coupling");
                let ga: [[f64; 3]; POINTS] = std::array::from_fn(|q| shape_gradient(g, a, q));
                let mean = mean_gradient(g, a);
                let of_axis = |k: usize| -> f64 {
                    let mut v = 0.0;
                    for q in 0..POINTS {
                        v += strain_of_unit_dot(&ga[q], k, &cb[q]);
                        if md {
                            v += (mean[k] - ga[q][k]) / 3.0 * tr[q];
                        }
                    }
                    v
                };
                for (k, &dk) in da.iter().enumerate().skip(first) {
                    if dk != FIXED {
                        col[pos] += self.parts.dofs.along(self.nodes[e][a], k, of_axis);
                        pos += 1;
                    }
                }
            }
        }
    }
}

impl Discretisation for P2Element {
    fn mesh(&self) -> &TetMesh {
        &self.parts.mesh
    }

    fn unconstrained(&self) -> Option<Box<dyn Discretisation>> {
        let dofs = DofMap::from_fixed(&vec![[false; 3]; self.parts.mesh.n_nodes()]);
        Some(Box::new(
            Self::with_dofs(self.parts.mesh.clone(), dofs)
                .with_mean_dilatation(self.mean_dilatation)
                .with_contact_rows(self.contact_rows),
        ))
    }

    fn dofs(&self) -> &DofMap {
        &self.parts.dofs
    }

    fn name(&self) -> &'static str {
        "p2"
    }

    /// B̄ (theory §10.1) leaves out of the energy the volumetric strain's deviation from its
    /// element mean: ε(u):Cε(u) − ε̄:Cε̄ = K((tr ε)² − θ̄²) pointwise (the deviators agree), whose
    /// integral over T is K∫_T (tr ε − θ̄_T)², tr ε linear, so the four-point rule is exact.
    fn strain_consistency_energy(&self, law: &Elasticity, u: &[f64]) -> f64 {
        if !self.mean_dilatation {
            return 0.0;
        }
        let bulk = law.bulk_modulus();
        (0..self.nodes.len())
            .into_par_iter()
            .map(|e| {
                let m = self.point_gradients(e, u);
                let theta: [f64; POINTS] = std::array::from_fn(|q| m[q][0][0] + m[q][1][1] + m[q][2][2]);
                let mean = theta.iter().sum::<f64>() / POINTS as f64;
                let w = &self.weights[e * POINTS..(e + 1) * POINTS];
                bulk * theta.iter().zip(w).map(|(t, w)| w * (t - mean) * (t - mean)).sum::<f64>()
            })
            .sum()
    }

    /// VTK_QUADRATIC_TETRA: vertices, then the edge nodes in VTK's order.
    fn degree(&self) -> usize {
        2
    }
    fn vtk_cell(&self) -> VtkCell {
        VtkCell { type_id: 24, nodes: NODES }
    }

    fn points_per_element(&self) -> usize {
        POINTS
    }

    /// The four Gauss points: `A` at vertex q, `B` at the other three.
    fn point_barycentrics(&self) -> Vec<[f64; 4]> {
        (0..POINTS).map(|q| std::array::from_fn(|a| if a == q { A } else { B })).collect()
    }

    /// Plain P2 (without B̄) locks as ν → ½; with B̄ it does not.
    fn locks(&self) -> bool {
        !self.mean_dilatation
    }

    fn contact_rows(&self, nodal: ConstraintRows) -> Result<ConstraintRows, String> {
        match self.contact_rows {
            ContactRows::Nodal => Ok(nodal),
            ContactRows::DualQuadratic => dual_quadratic_rows(self.mesh(), nodal),
        }
    }
}

impl ElementOperators for P2Element {
    fn n_dofs(&self) -> usize {
        self.parts.dofs.n_free
    }

    fn rigid_body_modes(&self) -> Option<RigidBodyModes> {
        Some(self.parts.rigid_body_modes())
    }

    fn pattern(&self) -> &SymmetricPattern {
        &self.parts.pattern
    }

    /// With B̄ the trace of ε̄ at the four points of T is θ̄_T = (1/|T|)∫_T div u: B's row T holds
    /// ∫_T ∂_c N_a = |T| (∇λ_i + ∇λ_j)_c for the edge node (i, j) and nothing for a vertex
    /// ([`mean_gradient`]). Plain P2 has no element-constant trace.
    fn pressure_rows(&self) -> Option<PressureRows> {
        if !self.mean_dilatation {
            return None;
        }
        let ne = self.nodes.len();
        let mut rows = PressureRows {
            ptr: Vec::with_capacity(ne + 1),
            dof: Vec::with_capacity(18 * ne),
            val: Vec::with_capacity(18 * ne),
            volume: Vec::with_capacity(ne),
            points: POINTS,
        };
        rows.ptr.push(0);
        for (e, t) in self.nodes.iter().enumerate() {
            let volume: f64 = self.weights[POINTS * e..POINTS * (e + 1)].iter().sum();
            let g = &self.parts.grads[e];
            for (a, &n) in t.iter().enumerate().skip(4) {
                let mean = mean_gradient(g, a);
                for k in 0..3 {
                    if let Some(j) = self.parts.dofs.free(n, k) {
                        rows.dof.push(j as u32);
                        rows.val.push(volume * self.parts.dofs.along(n, k, |c| mean[c]));
                    }
                }
            }
            rows.ptr.push(rows.dof.len());
            rows.volume.push(volume);
        }
        Some(rows)
    }

    fn n_points(&self) -> usize {
        POINTS * self.parts.mesh.n_elements()
    }

    fn weights(&self) -> &[f64] {
        &self.weights
    }

    fn strain(&self, u: &[f64], eps: &mut [Sym]) {
        let md = self.mean_dilatation;
        eps.par_chunks_mut(POINTS).enumerate().for_each(|(e, out)| {
            let m = self.point_gradients(e, u);
            let theta: [f64; POINTS] = std::array::from_fn(|q| m[q][0][0] + m[q][1][1] + m[q][2][2]);
            let mean = theta.iter().sum::<f64>() / POINTS as f64;
            let s = 1.0 / SQRT2;
            for (q, (o, m)) in out.iter_mut().zip(&m).enumerate() {
                let d = if md { (mean - theta[q]) / 3.0 } else { 0.0 };
                *o = Sym::new(
                    m[0][0] + d,
                    m[1][1] + d,
                    m[2][2] + d,
                    s * (m[1][2] + m[2][1]),
                    s * (m[0][2] + m[2][0]),
                    s * (m[0][1] + m[1][0]),
                );
            }
        });
    }

    fn divergence(&self, sigma: &[Sym], f: &mut [f64]) {
        let md = self.mean_dilatation;
        f.par_iter_mut().enumerate().for_each(|(j, fj)| {
            let (n, c) = (self.parts.dof_node[j] as usize, self.parts.dof_comp[j] as usize);
            *fj = self.parts.adj[self.parts.adj_ptr[n]..self.parts.adj_ptr[n + 1]]
                .iter()
                .map(|&(e, a)| {
                    let (e, a) = (e as usize, a as usize);
                    let g = &self.parts.grads[e];
                    let of_axis = |c: usize| -> f64 {
                        (0..POINTS)
                            .map(|q| {
                                let p = POINTS * e + q;
                                let (ga, delta) = column(g, a, c, q, md);
                                let s = &sigma[p];
                                self.weights[p] * (strain_of_unit_dot(&ga, c, s) + delta * (s[0] + s[1] + s[2]))
                            })
                            .sum::<f64>()
                    };
                    self.parts.dofs.along(n, c, of_axis)
                })
                .sum();
        });
    }

    fn strain_entries(&self) -> Vec<(usize, usize, usize, f64)> {
        let mut out = Vec::with_capacity(self.n_points() * 90);
        for (e, t) in self.nodes.iter().enumerate() {
            for q in 0..POINTS {
                for (a, &n) in t.iter().enumerate() {
                    for c in 0..3 {
                        let Some(j) = self.parts.dofs.free(n, c) else { continue };
                        let md = self.mean_dilatation;
                        let col = self.parts.dofs.along(n, c, |c| column_strain(&self.parts.grads[e], a, c, q, md));
                        out.extend((0..6).filter(|&k| col[k] != 0.0).map(|k| (POINTS * e + q, k, j, col[k])));
                    }
                }
            }
        }
        out
    }

    fn assemble(&self, material: Material<'_>, values: &mut [f64]) {
        assert_eq!(values.len(), self.parts.pattern.nnz());
        let column = |j: usize, col: &mut [f64]| self.assemble_column(j, col, &material);
        assemble_columns(&self.parts.pattern, 0, self.parts.dofs.n_free, values, 64, &column);
    }

    fn reassemble(&self, material: Material<'_>, reference: &SymOp, was_off: &mut Vec<bool>, values: &mut [f64]) {
        assert_eq!(values.len(), self.parts.pattern.nnz());
        let column = |j: usize, col: &mut [f64]| self.assemble_column(j, col, &material);
        self.parts.reassemble(&material, reference, POINTS, was_off, values, 64, &column);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::operator_checks;
    use crate::mesh::box_mesh::BoxMesh;
    use crate::mesh::region::Region;
    use nalgebra::Matrix3;
    use rand::{Rng, SeedableRng, rngs::StdRng};

    fn problem(mean_dilatation: bool) -> P2Element {
        let mesh =
            BoxMesh::new([0.0, 0.0, 0.0], [1.0, 2.0, 1.0], [2, 3, 2]).graded([0.2, 0.0, 0.0], 2.0).mesh().unwrap();
        let bc = [
            Dirichlet::clamped(Region::Group("zmax".into())),
            Dirichlet::roller(Region::Group("xmin".into()), crate::mesh::dofs::Component::X),
        ];
        P2Element::new(mesh, &bc).unwrap().with_mean_dilatation(mean_dilatation)
    }

    /// u(x) with components quadratic in x: u_i = G_ij x_j + ½ H_ijk x_j x_k.
    fn quadratic_field(l: &P2Element, grad: &Matrix3<f64>, hess: &[[[f64; 3]; 3]; 3]) -> Vec<f64> {
        let mut u = vec![0.0; l.n_dofs()];
        for (n, x) in l.parts.mesh.nodes.iter().enumerate() {
            for i in 0..3 {
                let mut v = 0.0;
                for j in 0..3 {
                    v += grad[(i, j)] * x[j];
                    for k in 0..3 {
                        v += 0.5 * hess[i][j][k] * x[j] * x[k];
                    }
                }
                u[l.parts.dofs.free(n, i).unwrap()] = v;
            }
        }
        u
    }

    /// The Gauss points of element e.
    fn points(l: &P2Element, e: usize) -> [[f64; 3]; POINTS] {
        let x = l.parts.mesh.tets[e].map(|n| l.parts.mesh.nodes[n]);
        std::array::from_fn(|q| std::array::from_fn(|k| (0..4).map(|i| if i == q { A } else { B } * x[i][k]).sum()))
    }

    #[test]
    fn strain_of_a_quadratic_field_is_exact_at_the_points() {
        // without B̄ ε(u) of a quadratic u is reproduced exactly at every Gauss point; with B̄
        // its deviatoric part is, and the trace is the element mean of div u
        let mesh = BoxMesh::new([0.0; 3], [1.0; 3], [2, 2, 2]).mesh().unwrap();
        let grad = Matrix3::new(0.1, 0.2, -0.3, 0.05, -0.4, 0.7, 0.3, 0.0, 0.25);
        let mut rng = StdRng::seed_from_u64(5);
        let hess: [[[f64; 3]; 3]; 3] = std::array::from_fn(|_| {
            let h: [[f64; 3]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| rng.random_range(-1.0..1.0)));
            std::array::from_fn(|j| std::array::from_fn(|k| h[j][k] + h[k][j]))
        });
        for md in [false, true] {
            let l = P2Element::new(mesh.clone(), &[]).unwrap().with_mean_dilatation(md);
            let u = quadratic_field(&l, &grad, &hess);
            let mut eps = vec![Sym::zeros(); l.n_points()];
            l.strain(&u, &mut eps);
            let exact = |x: &[f64; 3]| {
                let g = Matrix3::from_fn(|i, j| grad[(i, j)] + (0..3).map(|k| hess[i][j][k] * x[k]).sum::<f64>());
                crate::problem::tensor::from_matrix(&g)
            };
            let mut worst: f64 = 0.0;
            for e in 0..l.parts.mesh.n_elements() {
                let xs = points(&l, e);
                let exact_q: Vec<Sym> = xs.iter().map(exact).collect();
                let mean_tr: f64 = exact_q.iter().map(|s| s[0] + s[1] + s[2]).sum::<f64>() / 4.0;
                for q in 0..POINTS {
                    let mut want = exact_q[q];
                    if md {
                        let d = (mean_tr - (want[0] + want[1] + want[2])) / 3.0;
                        for k in 0..3 {
                            want[k] += d;
                        }
                    }
                    worst = worst.max((eps[POINTS * e + q] - want).norm());
                }
            }
            assert!(worst < 1e-13, "mean dilatation {md}: {worst}");
        }
    }

    /// The element of [`problem`] with inclined supports on ymin and xmax, meeting along an
    /// edge (nodal frames, theory §14.4).
    fn inclined(mean_dilatation: bool) -> P2Element {
        let mesh = BoxMesh::new([0.0; 3], [1.0, 2.0, 1.0], [2, 3, 2]).mesh().unwrap().second_order();
        let bc = [
            Dirichlet::clamped(Region::Group("zmax".into())),
            Dirichlet::inclined(Region::Group("ymin".into()), [0.3, -1.0, 0.2]),
            Dirichlet::inclined(Region::Group("xmax".into()), [1.0, 0.4, 0.0]),
        ];
        let dofs = DofMap::with_values(&mesh, &bc).unwrap();
        assert!(dofs.has_frames());
        P2Element::with_dofs(mesh, dofs).with_mean_dilatation(mean_dilatation)
    }

    #[test]
    fn divergence_is_the_transpose_of_strain_and_entries_reproduce_it() {
        for md in [false, true] {
            for l in [problem(md), inclined(md)] {
                operator_checks::divergence_is_the_transpose_of_strain(&l);
                operator_checks::strain_entries_reproduce_the_strain(&l, 1e-12);
            }
        }
    }

    #[test]
    fn assembled_stiffness_matches_the_operator_and_the_energy() {
        for md in [false, true] {
            operator_checks::assembled_stiffness_matches_the_operator(&problem(md));
            operator_checks::assembled_stiffness_matches_the_operator(&inclined(md));
            operator_checks::reassembly_equals_the_assembly(&problem(md), POINTS);
        }
    }

    #[test]
    fn pressure_rows_give_the_trace_of_the_mean_dilatation_strain() {
        // tr ε̄ at each of an element's four points is (B u)_T / |T| (theory §10.1), for any u,
        // with and without nodal frames; plain P2 has no element-constant trace
        let mut rng = StdRng::seed_from_u64(11);
        for l in [problem(true), inclined(true)] {
            let rows = l.pressure_rows().unwrap();
            assert_eq!(rows.n_rows(), l.parts.mesh.n_elements());
            let u: Vec<f64> = (0..l.n_dofs()).map(|_| rng.random_range(-1.0..1.0)).collect();
            let mut eps = vec![Sym::zeros(); l.n_points()];
            l.strain(&u, &mut eps);
            let mut worst: f64 = 0.0;
            for e in 0..rows.n_rows() {
                let r = rows.ptr[e]..rows.ptr[e + 1];
                let bu: f64 = rows.dof[r.clone()].iter().zip(&rows.val[r]).map(|(&j, v)| v * u[j as usize]).sum();
                for q in 0..POINTS {
                    let t = &eps[POINTS * e + q];
                    worst = worst.max((t[0] + t[1] + t[2] - bu / rows.volume[e]).abs());
                }
            }
            assert!(worst < 1e-12, "{worst}");
        }
        assert!(problem(false).pressure_rows().is_none());
    }

    #[test]
    fn rigid_motions_have_no_strain() {
        let mesh = BoxMesh::new([0.0; 3], [1.0; 3], [2, 2, 2]).mesh().unwrap();
        let l = P2Element::new(mesh, &[]).unwrap();
        let modes = l.rigid_body_modes().unwrap();
        let mut eps = vec![Sym::zeros(); l.n_points()];
        for m in 0..6 {
            let u: Vec<f64> = (0..modes.n()).map(|d| modes.modes[6 * d + m]).collect();
            l.strain(&u, &mut eps);
            assert!(eps.iter().all(|e| e.norm() < 1e-13), "mode {m}");
        }
    }
}
