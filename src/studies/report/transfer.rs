//! Comparing P0 fields across meshes (theory §5 errors in a mesh convergence study, §7 Theorem 2):
//! a point locator for tetrahedral meshes and the transfer of a coarse P0 field to a fine mesh.
//!
//! The coarse field is evaluated at sample points of every fine element (the element of the
//! coarse mesh containing each is found by [`Locator`]) and the squared difference is
//! integrated over the fine mesh with the fine element volumes as weights ([`SampleMap`],
//! [`field_distance`]). With one point, the centroid, a fine element that straddles a coarse
//! face takes the coarse value on one side only; on graded meshes that are not nested the
//! centroids fall on the coarse elements with a bias, and the measured distances changed by
//! up to 10 % (default scene, 16×16×8 against 32×32×16 cells). The default samples the
//! centroids of the 8 children of one red refinement of each fine element: within 3 % of a
//! 64-point sampling there.

use saddle_core::problem::stresses::energy_inner;
use saddle_core::{Lagrangian, StressField, Sym, TetMesh};
use thiserror::Error;

/// A point of a fine mesh that lies in no element of the coarse mesh.
#[derive(Debug, Clone, Error, PartialEq)]
#[error(
    "the centroid {point:?} of fine element {element} lies outside the coarse mesh (the meshes must cover the same domain)"
)]
pub struct OutsideMesh {
    /// The fine element.
    pub element: usize,
    /// Its centroid.
    pub point: [f64; 3],
}

/// Barycentric coordinates of `p` need to be ≥ −`INSIDE_TOL` for `p` to count as inside.
const INSIDE_TOL: f64 = 1e-9;

/// Point location in a tetrahedral mesh by a bucket grid.
///
/// The buckets follow the mesh: along each axis their boundaries are quantiles of the node
/// coordinates, so a mesh graded toward a point gets small buckets there (on a structured box
/// mesh the boundaries are grid planes). Each element is listed in every bucket its bounding box
/// overlaps; a query tests the elements of its bucket by barycentric coordinates, and those of
/// the neighbouring buckets when none contains the point.
#[derive(Debug, Clone)]
pub struct Locator<'a> {
    mesh: &'a TetMesh,
    /// Bucket boundaries per axis (strictly increasing, at least two).
    axes: [Vec<f64>; 3],
    /// CSR: the elements of bucket b are `items[start[b]..start[b + 1]]`.
    start: Vec<usize>,
    items: Vec<u32>,
}

impl<'a> Locator<'a> {
    /// Builds the bucket grid of `mesh`, about one bucket per element.
    pub fn new(mesh: &'a TetMesh) -> Self {
        let per_axis = ((mesh.n_elements() as f64).cbrt().ceil() as usize).clamp(1, 512);
        let axes: [Vec<f64>; 3] = std::array::from_fn(|k| quantile_axis(mesh, k, per_axis));
        let dims = axes.clone().map(|a| a.len() - 1);
        let n_buckets = dims[0] * dims[1] * dims[2];
        let ranges: Vec<[(usize, usize); 3]> = (0..mesh.n_elements())
            .map(|e| {
                let (lo, hi) = element_box(mesh, e);
                std::array::from_fn(|k| {
                    let pad = 1e-9 * (hi[k] - lo[k]).max(f64::MIN_POSITIVE);
                    (bucket_of(&axes[k], lo[k] - pad), bucket_of(&axes[k], hi[k] + pad))
                })
            })
            .collect();
        let index = |i: usize, j: usize, k: usize| i + dims[0] * (j + dims[1] * k);
        let mut start = vec![0usize; n_buckets + 1];
        for r in &ranges {
            for k in r[2].0..=r[2].1 {
                for j in r[1].0..=r[1].1 {
                    for i in r[0].0..=r[0].1 {
                        start[index(i, j, k) + 1] += 1;
                    }
                }
            }
        }
        for b in 0..n_buckets {
            start[b + 1] += start[b];
        }
        let mut fill = start.clone();
        let mut items = vec![0u32; start[n_buckets]];
        for (e, r) in ranges.iter().enumerate() {
            for k in r[2].0..=r[2].1 {
                for j in r[1].0..=r[1].1 {
                    for i in r[0].0..=r[0].1 {
                        let b = index(i, j, k);
                        items[fill[b]] = e as u32;
                        fill[b] += 1;
                    }
                }
            }
        }
        Self { mesh, axes, start, items }
    }

    /// The mesh searched.
    pub fn mesh(&self) -> &TetMesh {
        self.mesh
    }

    /// The element containing `p` (with a tolerance of 1e-9 in barycentric coordinates), or
    /// `None` when `p` lies outside the mesh. A point on a shared face or edge gets one of the
    /// elements around it.
    pub fn locate(&self, p: [f64; 3]) -> Option<usize> {
        let (i, j, k) = self.cell(p);
        let best = self.best_in(p, i..=i, j..=j, k..=k);
        if best.is_some_and(|(_, m)| m >= -INSIDE_TOL) {
            return best.map(|b| b.0);
        }
        // the point may sit on a bucket boundary that rounding put on the wrong side
        let around = |c: usize, n: usize| c.saturating_sub(1)..=(c + 1).min(n - 1);
        let dims = self.dims();
        self.best_in(p, around(i, dims[0]), around(j, dims[1]), around(k, dims[2]))
            .filter(|&(_, m)| m >= -INSIDE_TOL)
            .map(|b| b.0)
    }

    fn dims(&self) -> [usize; 3] {
        std::array::from_fn(|k| self.axes[k].len() - 1)
    }

    fn cell(&self, p: [f64; 3]) -> (usize, usize, usize) {
        (bucket_of(&self.axes[0], p[0]), bucket_of(&self.axes[1], p[1]), bucket_of(&self.axes[2], p[2]))
    }

    /// The candidate with the largest smallest barycentric coordinate, and that coordinate.
    fn best_in(
        &self,
        p: [f64; 3],
        is: std::ops::RangeInclusive<usize>,
        js: std::ops::RangeInclusive<usize>,
        ks: std::ops::RangeInclusive<usize>,
    ) -> Option<(usize, f64)> {
        let dims = self.dims();
        let mut best: Option<(usize, f64)> = None;
        for k in ks {
            for j in js.clone() {
                for i in is.clone() {
                    let b = i + dims[0] * (j + dims[1] * k);
                    for &e in &self.items[self.start[b]..self.start[b + 1]] {
                        let m = min_barycentric(self.mesh, e as usize, p);
                        if best.is_none_or(|(_, bm)| m > bm) {
                            best = Some((e as usize, m));
                        }
                    }
                }
            }
        }
        best
    }
}

/// Bucket boundaries along axis `k`: `n` quantiles of the node coordinates, deduplicated, the
/// first and last at the extremes.
fn quantile_axis(mesh: &TetMesh, k: usize, n: usize) -> Vec<f64> {
    let mut xs: Vec<f64> = mesh.nodes.iter().map(|x| x[k]).collect();
    xs.sort_unstable_by(f64::total_cmp);
    let last = xs.len() - 1;
    let mut axis: Vec<f64> = (0..=n).map(|i| xs[(i * last + n / 2) / n.max(1)]).collect();
    axis[0] = xs[0];
    axis[n] = xs[last];
    axis.dedup();
    if axis.len() < 2 {
        // a flat mesh along this axis (cannot happen for valid tetrahedra): one bucket
        axis = vec![xs[0] - 1.0, xs[0] + 1.0];
    }
    axis
}

/// The bucket of coordinate x (clamped to the grid).
fn bucket_of(axis: &[f64], x: f64) -> usize {
    axis.partition_point(|&a| a <= x).saturating_sub(1).min(axis.len() - 2)
}

fn element_box(mesh: &TetMesh, e: usize) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &n in &mesh.tets[e] {
        for k in 0..3 {
            lo[k] = lo[k].min(mesh.nodes[n][k]);
            hi[k] = hi[k].max(mesh.nodes[n][k]);
        }
    }
    (lo, hi)
}

/// The smallest barycentric coordinate of `p` in element `e` (≥ 0 inside).
fn min_barycentric(mesh: &TetMesh, e: usize, p: [f64; 3]) -> f64 {
    barycentric(mesh, e, p).into_iter().fold(f64::INFINITY, f64::min)
}

/// The barycentric coordinates of `p` in element `e`, in the order of its vertices.
pub fn barycentric(mesh: &TetMesh, e: usize, p: [f64; 3]) -> [f64; 4] {
    let [a, b, c, d] = mesh.tets[e].map(|n| mesh.nodes[n]);
    let sub = |x: [f64; 3], y: [f64; 3]| [x[0] - y[0], x[1] - y[1], x[2] - y[2]];
    let (u, v, w, r) = (sub(b, a), sub(c, a), sub(d, a), sub(p, a));
    let det = |x: [f64; 3], y: [f64; 3], z: [f64; 3]| {
        x[0] * (y[1] * z[2] - y[2] * z[1]) - x[1] * (y[0] * z[2] - y[2] * z[0]) + x[2] * (y[0] * z[1] - y[1] * z[0])
    };
    let vol = det(u, v, w);
    let (l1, l2, l3) = (det(r, v, w) / vol, det(u, r, w) / vol, det(u, v, r) / vol);
    [1.0 - l1 - l2 - l3, l1, l2, l3]
}

/// The centroid of element `e`.
pub fn centroid(mesh: &TetMesh, e: usize) -> [f64; 3] {
    let t = mesh.tets[e];
    std::array::from_fn(|k| t.iter().map(|&n| mesh.nodes[n][k]).sum::<f64>() / 4.0)
}

/// Where a coarse field is sampled on a fine element.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Quadrature {
    /// At the centroid (one point).
    Centroid,
    /// At the centroids of the 8 equal-volume children of one red refinement of the element
    /// (the default): a fine element that straddles a coarse face is split in proportion.
    #[default]
    Children,
}

impl Quadrature {
    /// Sample points per fine element.
    pub fn points(self) -> usize {
        match self {
            Quadrature::Centroid => 1,
            Quadrature::Children => 8,
        }
    }

    /// The sample points of element `e` (equal weights).
    pub fn sample_points(self, mesh: &TetMesh, e: usize) -> Vec<[f64; 3]> {
        match self {
            Quadrature::Centroid => vec![centroid(mesh, e)],
            Quadrature::Children => {
                red_children(mesh.tets[e].map(|n| mesh.nodes[n])).iter().map(tet_centroid).collect()
            }
        }
    }
}

/// The 8 children of a tetrahedron under red refinement (4 corners, the octahedron cut along
/// one diagonal into 4), all of volume |T|/8.
pub fn red_children(t: [[f64; 3]; 4]) -> [[[f64; 3]; 4]; 8] {
    let m = |i: usize, j: usize| -> [f64; 3] { std::array::from_fn(|k| 0.5 * (t[i][k] + t[j][k])) };
    let [a, b, c, d] = t;
    let (ab, ac, ad, bc, bd, cd) = (m(0, 1), m(0, 2), m(0, 3), m(1, 2), m(1, 3), m(2, 3));
    [
        [a, ab, ac, ad],
        [ab, b, bc, bd],
        [ac, bc, c, cd],
        [ad, bd, cd, d],
        [ab, ac, ad, bd],
        [ab, ac, bc, bd],
        [ac, ad, bd, cd],
        [ac, bc, bd, cd],
    ]
}

fn tet_centroid(t: &[[f64; 3]; 4]) -> [f64; 3] {
    std::array::from_fn(|k| (t[0][k] + t[1][k] + t[2][k] + t[3][k]) / 4.0)
}

/// For every sample point of every fine element ([`Quadrature`]), the coarse element that
/// contains it: the sample points of fine element e are `coarse[e * per_element..][..per_element]`.
#[derive(Clone, Debug, PartialEq)]
pub struct SampleMap {
    /// Sample points per fine element (equal weights).
    pub per_element: usize,
    /// The coarse element of each sample point.
    pub coarse: Vec<usize>,
}

impl SampleMap {
    /// Locates the sample points of every element of `fine` in `coarse`.
    pub fn new(coarse: &TetMesh, fine: &TetMesh, quadrature: Quadrature) -> Result<Self, OutsideMesh> {
        let locator = Locator::new(coarse);
        let mut map = Vec::with_capacity(fine.n_elements() * quadrature.points());
        for e in 0..fine.n_elements() {
            for point in quadrature.sample_points(fine, e) {
                map.push(locator.locate(point).ok_or(OutsideMesh { element: e, point })?);
            }
        }
        Ok(Self { per_element: quadrature.points(), coarse: map })
    }

    /// The coarse elements sampled by fine element `e`.
    pub fn of(&self, e: usize) -> &[usize] {
        &self.coarse[e * self.per_element..(e + 1) * self.per_element]
    }
}

/// ‖a − b‖ / ‖b‖ in L²(Ω) for P0 tensor fields on one mesh (Frobenius norm, volume weights `w`);
/// the absolute norm when b = 0.
pub fn l2_distance(w: &[f64], a: &[Sym], b: &[Sym]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for ((w, a), b) in w.iter().zip(a).zip(b) {
        num += w * (a - b).norm_squared();
        den += w * b.norm_squared();
    }
    if den > 0.0 { (num / den).sqrt() } else { num.sqrt() }
}

/// The strains ε(u) of a displacement on `l`.
pub fn strains(l: &Lagrangian<'_>, u: &[f64]) -> Vec<Sym> {
    let mut eps = vec![Sym::zeros(); l.n_points()];
    l.strain(u, &mut eps);
    eps
}

/// The measure of [`field_distance`] on a mesh: the elements' volumes and the energy metric
/// (elasticity and P, for the norm of q).
pub struct Metric<'a> {
    /// Element volumes.
    pub weights: Vec<f64>,
    /// Elasticity.
    pub law: saddle_core::Elasticity,
    /// P.
    pub plasticity: Option<&'a dyn saddle_core::AdmissibleStresses>,
}

impl<'a> Metric<'a> {
    /// The metric of `l`'s mesh.
    pub fn of(problem: &'a saddle_core::DiscreteProblem) -> Self {
        let (l, element) = (&problem.lagrangian(), &*problem.element);
        let k = element.points_per_element();
        Self {
            weights: l.weights().chunks(k).map(|w| w.iter().sum()).collect(),
            law: *l.data.elasticity,
            plasticity: l.data.plasticity(),
        }
    }
}

/// A solution's fields as P0 fields on its mesh: for an element with several stress points
/// (P2) the weighted means over its points (the L² projection onto P0); P1–P0 fields as they
/// are. The convergence study compares these ([`field_distance`]), so both elements are
/// measured alike (P2's stresses are measured by their element means, which caps their
/// observed rate at that of P0).
pub fn p0_fields(problem: &saddle_core::DiscreteProblem, u: &[f64], stress: &StressField) -> (StressField, Vec<Sym>) {
    let (l, element) = (&problem.lagrangian(), &*problem.element);
    let k = element.points_per_element();
    let strain = strains(l, u);
    if k == 1 {
        return (stress.clone(), strain);
    }
    let w = l.weights();
    let n = element.mesh().n_elements();
    let mut out = StressField::new(n, stress.q.dim());
    let mut mean_strain = vec![Sym::zeros(); n];
    let stride = out.q.stride();
    for e in 0..n {
        let we: f64 = w[e * k..(e + 1) * k].iter().sum();
        for i in e * k..(e + 1) * k {
            let f = w[i] / we;
            out.sigma[e] += f * stress.sigma[i];
            mean_strain[e] += f * strain[i];
            for c in 0..stress.q.dim() {
                out.q[e * stride + c] += f * stress.q(i)[c];
            }
            out.plastic[e] |= stress.plastic[i];
        }
    }
    (out, mean_strain)
}

/// The differences of a coarse solution to a fine one on the fine mesh (theory §5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldDistance {
    /// [σ̂_c − σ̂_f]^{1/2} / [σ̂_f]^{1/2}, the energy norm of theory §1 on the fine mesh.
    pub stress_energy: f64,
    /// ‖ε(u_c) − ε(u_f)‖_{L²} / ‖ε(u_f)‖_{L²}.
    pub strain_l2: f64,
}

/// Compares a coarse solution (stresses, strains) with a fine one on the fine mesh: the coarse
/// P0 fields are sampled through `map` and the squared differences integrated over the fine
/// elements (each sample point carries |T|/points).
pub fn field_distance(
    fine: &Metric<'_>,
    fine_stress: &StressField,
    fine_strain: &[Sym],
    coarse_stress: &StressField,
    coarse_strain: &[Sym],
    map: &SampleMap,
) -> FieldDistance {
    let (law, p) = (fine.law, fine.plasticity);
    debug_assert_eq!(fine.weights.len(), fine_stress.len(), "P0 fields ([`p0_fields`])");
    let m = fine_stress.q.dim();
    let (mut s_num, mut s_den, mut e_num, mut e_den) = (0.0, 0.0, 0.0, 0.0);
    let mut dq = vec![0.0; m];
    for (e, &w) in fine.weights.iter().enumerate() {
        let (sf, qf, ef) = (&fine_stress.sigma[e], fine_stress.q(e), &fine_strain[e]);
        let wq = w / map.per_element as f64;
        for &c in map.of(e) {
            let ds = coarse_stress.sigma[c] - sf;
            for (k, d) in dq.iter_mut().enumerate() {
                *d = coarse_stress.q(c)[k] - qf[k];
            }
            s_num += wq * energy_inner(p, &law, &ds, &dq, &ds, &dq);
            e_num += wq * (coarse_strain[c] - ef).norm_squared();
        }
        s_den += w * energy_inner(p, &law, sf, qf, sf, qf);
        e_den += w * ef.norm_squared();
    }
    let rel = |num: f64, den: f64| if den > 0.0 { (num / den).sqrt() } else { num.sqrt() };
    FieldDistance { stress_energy: rel(s_num, s_den), strain_l2: rel(e_num, e_den) }
}
