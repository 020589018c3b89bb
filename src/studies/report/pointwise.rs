//! The distance between two solutions on different meshes, their fields compared at points
//! rather than by element means (theory §15.4): each solution's stresses and strains as fields
//! within its elements ([`ElementField`]: affine through four stress points — P2's — or the
//! constant of one — P1–P0's), the coarse field sampled at quadrature points of the fine
//! elements and the squared difference integrated over the fine mesh.
//!
//! [`super::transfer::field_distance`] compares element means (P0 fields), which for P2 caps the
//! observed error at that of P0: the affine part of a P2 stress error is invisible to it. Here
//! the rule is the estimator's ([`quadrature::points`]: a degree-2 Gauss rule on the eight children
//! of one red refinement, 32 points), so on nested meshes, where every fine element lies in one
//! coarse element, the squared difference of two affine fields (a quadratic) is integrated
//! exactly; on meshes that are not nested a fine element straddling a coarse face is split
//! between the two sides in proportion to its points.

use super::transfer::{Locator, Metric, barycentric, strains};
use saddle_core::estimate::quadrature;
use saddle_core::estimate::recovery::ElementField;
use saddle_core::problem::stresses::{MAX_HARDENING_DIM, energy_inner};
use saddle_core::{DiscreteProblem, StressField, Sym, TetMesh};
use thiserror::Error;

/// A sample point of a fine element that lies in no element of the coarse mesh.
#[derive(Debug, Clone, Error, PartialEq)]
#[error(
    "the sample point {point:?} of fine element {element} lies outside the coarse mesh (the meshes must cover the same domain)"
)]
pub struct PointOutsideMesh {
    /// The fine element.
    pub element: usize,
    /// The sample point.
    pub point: [f64; 3],
}

/// For every point of [`quadrature::points`] in every fine element, the coarse element that
/// contains it and its barycentric coordinates there: the points of fine element e are
/// `e·POINTS..(e + 1)·POINTS`, each of weight |T_e| / POINTS.
#[derive(Clone, Debug, PartialEq)]
pub struct PointMap {
    /// The coarse element of each point.
    coarse: Vec<usize>,
    /// The point's barycentric coordinates in that coarse element.
    lambda: Vec<[f64; 4]>,
}

impl PointMap {
    /// Locates the quadrature points of every element of `fine` in `coarse`.
    pub fn new(coarse: &TetMesh, fine: &TetMesh) -> Result<Self, PointOutsideMesh> {
        let locator = Locator::new(coarse);
        let rule = quadrature::points();
        let n = fine.n_elements() * quadrature::POINTS;
        let (mut elements, mut lambda) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for e in 0..fine.n_elements() {
            let x = fine.tets[e].map(|v| fine.nodes[v]);
            for l in &rule {
                let point: [f64; 3] = std::array::from_fn(|k| (0..4).map(|a| l[a] * x[a][k]).sum());
                let c = locator.locate(point).ok_or(PointOutsideMesh { element: e, point })?;
                elements.push(c);
                lambda.push(barycentric(coarse, c, point));
            }
        }
        Ok(Self { coarse: elements, lambda })
    }
}

/// A solution's generalised stresses (σ, then q: 6 + dim q components) and strains (6) as fields
/// within the elements of its mesh.
pub struct PointFields {
    stress: ElementField,
    strain: ElementField,
}

impl PointFields {
    /// The fields of the solution (`u`, `stress`) of `problem`: through the values at the
    /// element's stress points.
    pub fn of(problem: &DiscreteProblem, u: &[f64], stress: &StressField) -> Self {
        Self::new(problem, stress, &strains(&problem.lagrangian(), u))
    }

    /// The fields through `stress` and `strain` given at `problem`'s stress points.
    pub fn new(problem: &DiscreteProblem, stress: &StressField, strain: &[Sym]) -> Self {
        let (l, element) = (problem.lagrangian(), &*problem.element);
        Self {
            stress: ElementField::new(element, &l, stress),
            strain: ElementField::of_points(element, 6, |i, c| strain[i][c]),
        }
    }
}

/// The differences of a coarse solution to a fine one, integrated over the fine mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointDistance {
    /// ‖σ̂_c − σ̂_f‖_E = [σ̂_c − σ̂_f, σ̂_c − σ̂_f]^{1/2}, the energy norm of theory §1.
    pub stress_energy: f64,
    /// ‖σ̂_f‖_E.
    pub fine_stress_energy: f64,
    /// ‖ε(u_c) − ε(u_f)‖_{L²}.
    pub strain_l2: f64,
    /// ‖ε(u_f)‖_{L²}.
    pub fine_strain_l2: f64,
}

/// Compares `coarse` with `fine` on the fine mesh: both fields evaluated at the points of
/// `map` (the coarse one at the point's coordinates in its coarse element), the squared
/// differences summed with the weights |T|/POINTS of theory §15.1's rule. `metric` is the fine
/// problem's ([`Metric::of`]): its weights are the fine elements' volumes.
pub fn point_distance(metric: &Metric<'_>, fine: &PointFields, coarse: &PointFields, map: &PointMap) -> PointDistance {
    let (law, p) = (metric.law, metric.plasticity);
    let m = fine.stress.components();
    debug_assert_eq!(m, coarse.stress.components(), "the same material on both levels");
    let rule = quadrature::points();
    let (mut sf, mut sc, mut ef, mut ec) =
        ([0.0; 6 + MAX_HARDENING_DIM], [0.0; 6 + MAX_HARDENING_DIM], [0.0; 6], [0.0; 6]);
    let (mut s_num, mut s_den, mut e_num, mut e_den) = (0.0, 0.0, 0.0, 0.0);
    for (e, &vol) in metric.weights.iter().enumerate() {
        let w = vol / quadrature::POINTS as f64;
        for (j, l) in rule.iter().enumerate() {
            let i = e * quadrature::POINTS + j;
            let (c, lc) = (map.coarse[i], &map.lambda[i]);
            fine.stress.at(e, l, &mut sf[..m]);
            coarse.stress.at(c, lc, &mut sc[..m]);
            fine.strain.at(e, l, &mut ef);
            coarse.strain.at(c, lc, &mut ec);
            let (f, d) =
                (Sym::from_column_slice(&sf[..6]), Sym::from_column_slice(&sc[..6]) - Sym::from_column_slice(&sf[..6]));
            let mut dq = [0.0; MAX_HARDENING_DIM];
            for k in 6..m {
                dq[k - 6] = sc[k] - sf[k];
            }
            s_num += w * energy_inner(p, &law, &d, &dq[..m - 6], &d, &dq[..m - 6]);
            s_den += w * energy_inner(p, &law, &f, &sf[6..m], &f, &sf[6..m]);
            e_num += w * (Sym::from_column_slice(&ec) - Sym::from_column_slice(&ef)).norm_squared();
            e_den += w * Sym::from_column_slice(&ef).norm_squared();
        }
    }
    let root = |x: f64| x.max(0.0).sqrt();
    PointDistance {
        stress_energy: root(s_num),
        fine_stress_energy: root(s_den),
        strain_l2: root(e_num),
        fine_strain_l2: root(e_den),
    }
}
