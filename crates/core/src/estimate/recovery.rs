//! Averaging recovery of the generalised stresses (theory §15.1; Zienkiewicz & Zhu 1987): the
//! discrete stresses interpolated within each element from its stress points, averaged at the
//! mesh's nodes with the elements' volumes as weights, and interpolated back with the mesh's
//! shape functions (P1 on four nodes, P2 on ten). The indicator of an element is the energy norm
//! of the recovered minus the discrete field over it.

use super::quadrature;
use crate::fem::Discretisation;
use crate::mesh::TET_EDGES;
use crate::problem::fields::StressField;
use crate::problem::lagrangian::Lagrangian;
use crate::problem::stresses::energy_inner;
use crate::problem::tensor::Sym;
use nalgebra::Matrix4;
use rayon::prelude::*;

/// The discrete generalised stresses as a field within each element: values at the vertices
/// of an affine interpolant when the element has four affinely independent stress points, the
/// element mean otherwise (one point: P0). `m` values per vertex: σ (6), then q.
pub struct ElementField {
    /// Values per element, vertex and component: `[e][a][c]` at `(e·4 + a)·m + c`.
    vertex: Vec<f64>,
    /// Components per value: 6 + dim q.
    m: usize,
}

impl ElementField {
    /// The field of `stress` on `element`'s mesh.
    pub fn new(element: &dyn Discretisation, l: &Lagrangian<'_>, stress: &StressField) -> Self {
        let m = 6 + l.data.hardening_dim().min(stress.q.dim());
        Self::of_points(element, m, |i, c| if c < 6 { stress.sigma[i][c] } else { stress.q(i)[c - 6] })
    }

    /// The field through values at `element`'s stress points: `value(i, c)` is component `c` of
    /// `m` at point `i` (element e's points are `e·k..(e + 1)·k`, k points per element). Any
    /// pointwise quantity (stresses, strains) becomes a field within the elements this way.
    pub fn of_points(element: &dyn Discretisation, m: usize, value: impl Fn(usize, usize) -> f64 + Sync) -> Self {
        let k = element.points_per_element();
        let to_vertices = interpolation(&element.point_barycentrics());
        let n = element.mesh().n_elements();
        let mut vertex = vec![0.0; n * 4 * m];
        vertex.par_chunks_mut(4 * m).enumerate().for_each(|(e, out)| {
            for a in 0..4 {
                for c in 0..m {
                    out[a * m + c] = (0..k).map(|q| to_vertices[a][q] * value(e * k + q, c)).sum();
                }
            }
        });
        Self { vertex, m }
    }

    /// Components per value.
    pub fn components(&self) -> usize {
        self.m
    }

    /// The value at barycentric coordinates `lambda` of element `e` (in the order of the
    /// element's vertices in the mesh), into `out` (m entries).
    #[inline]
    pub fn at(&self, e: usize, lambda: &[f64; 4], out: &mut [f64]) {
        let v = &self.vertex[e * 4 * self.m..(e + 1) * 4 * self.m];
        for (c, o) in out.iter_mut().enumerate() {
            *o = (0..4).map(|a| lambda[a] * v[a * self.m + c]).sum();
        }
    }
}

/// The weights that take the values at the stress points to the vertex values of the element
/// field: `w[a][q]`. Four affinely independent points: the inverse of their barycentric matrix
/// (the affine interpolant); otherwise the mean.
fn interpolation(points: &[[f64; 4]]) -> Vec<Vec<f64>> {
    let k = points.len();
    let mean = || vec![vec![1.0 / k as f64; k]; 4];
    if k != 4 {
        return mean();
    }
    let m = Matrix4::from_fn(|q, a| points[q][a]);
    match m.try_inverse() {
        Some(inv) => (0..4).map(|a| (0..4).map(|q| inv[(a, q)]).collect()).collect(),
        None => mean(),
    }
}

/// The barycentric coordinates of the nodes of an element: four vertices, then (second order)
/// the midpoints of the edges in the order of [`TET_EDGES`].
fn node_barycentrics(second_order: bool) -> Vec<[f64; 4]> {
    let vertex = |a: usize| -> [f64; 4] { std::array::from_fn(|k| (k == a) as u8 as f64) };
    let mut nodes: Vec<[f64; 4]> = (0..4).map(vertex).collect();
    if second_order {
        nodes.extend(
            TET_EDGES.iter().map(|&[i, j]| std::array::from_fn(|k| 0.5 * ((k == i) as u8 + (k == j) as u8) as f64)),
        );
    }
    nodes
}

/// The shape functions of the mesh's nodes at `lambda`: λ_a (four nodes), or λ_a(2λ_a − 1) and
/// 4λ_iλ_j (ten).
#[inline]
fn shape(lambda: &[f64; 4], second_order: bool, out: &mut [f64; 10]) {
    if !second_order {
        out[..4].copy_from_slice(lambda);
        return;
    }
    for a in 0..4 {
        out[a] = lambda[a] * (2.0 * lambda[a] - 1.0);
    }
    for (e, [i, j]) in TET_EDGES.iter().enumerate() {
        out[4 + e] = 4.0 * lambda[*i] * lambda[*j];
    }
}

/// The recovered field: one value per mesh node, the volume-weighted mean of the element
/// fields of the elements around it.
pub struct RecoveredField {
    /// `m` values per node.
    nodal: Vec<f64>,
}

impl RecoveredField {
    /// The average of `field` at `element`'s mesh nodes.
    pub fn average(element: &dyn Discretisation, field: &ElementField) -> Self {
        let mesh = element.mesh();
        let m = field.components();
        let nodes = node_barycentrics(mesh.is_second_order());
        let mut nodal = vec![0.0; mesh.n_nodes() * m];
        let mut weight = vec![0.0; mesh.n_nodes()];
        let mut value = vec![0.0; m];
        for e in 0..mesh.n_elements() {
            let vol = mesh.volume(e);
            for (n, lambda) in mesh.element_nodes(e).zip(&nodes) {
                field.at(e, lambda, &mut value);
                weight[n] += vol;
                for (x, v) in nodal[n * m..(n + 1) * m].iter_mut().zip(&value) {
                    *x += vol * v;
                }
            }
        }
        for (chunk, w) in nodal.chunks_mut(m).zip(&weight) {
            if *w > 0.0 {
                chunk.iter_mut().for_each(|x| *x /= w);
            }
        }
        Self { nodal }
    }
}

/// η_T = ‖σ̂* − σ̂_h‖_{E,T} of every element (theory §15.1), integrated with
/// [`quadrature::points`].
pub fn indicators(
    element: &dyn Discretisation,
    l: &Lagrangian<'_>,
    field: &ElementField,
    recovered: &RecoveredField,
) -> Vec<f64> {
    let mesh = element.mesh();
    let m = field.components();
    let second_order = mesh.is_second_order();
    let rule = quadrature::points();
    let (law, p) = (*l.data.elasticity, l.data.plasticity());
    (0..mesh.n_elements())
        .into_par_iter()
        .map(|e| {
            let mut nodes = [0usize; 10];
            let mut count = 0;
            for (slot, node) in nodes.iter_mut().zip(mesh.element_nodes(e)) {
                *slot = node;
                count += 1;
            }
            let (mut discrete, mut n) = ([0.0; 6 + crate::problem::stresses::MAX_HARDENING_DIM], [0.0; 10]);
            let mut sum = 0.0;
            for lambda in &rule {
                field.at(e, lambda, &mut discrete[..m]);
                shape(lambda, second_order, &mut n);
                // d = σ̂* − σ̂_h at the point
                let mut d = [0.0; 6 + crate::problem::stresses::MAX_HARDENING_DIM];
                for (x, y) in d[..m].iter_mut().zip(&discrete[..m]) {
                    *x = -y;
                }
                for (a, &node) in nodes[..count].iter().enumerate() {
                    for (x, r) in d[..m].iter_mut().zip(&recovered.nodal[node * m..(node + 1) * m]) {
                        *x += n[a] * r;
                    }
                }
                let s = Sym::from_column_slice(&d[..6]);
                sum += energy_inner(p, &law, &s, &d[6..m], &s, &d[6..m]);
            }
            (mesh.volume(e) * sum / quadrature::POINTS as f64).max(0.0).sqrt()
        })
        .collect()
}
