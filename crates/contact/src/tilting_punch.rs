//! The tilting punch of theory §8: the rigid punch of theory §1 that may also rotate (small
//! rotations) about its pivot c, the gap's centre ([`GapShape::center`]). Its face rises at
//! (x₁, x₂) by
//!
//! ```text
//! w(x) = U + slope_x1 (x₁ − c₁) + slope_x2 (x₂ − c₂)
//! ```
//!
//! with three extra unknowns (U, slope_x1, slope_x2), and the contact rows are
//! `g_i = u₃(x_i) + φ(x_i) − w(x_i) ≥ 0`: G = e₃ at the node,
//! `H_i = (−1, −(x_i1 − c₁), −(x_i2 − c₂))`, `c_i = φ(x_i)`. The force F acts at the point a
//! (`at`, the pivot by default), so the load term is F·w(a), `f = F (1, a₁ − c₁, a₂ − c₂)`. At a
//! solution `Σλ_i = F` and `Σλ_i (x_i − c) = F (a − c)` (force and moment balance, theory §8):
//! the resultant of the contact forces passes through a, which must therefore lie in the convex
//! hull of the contact nodes — otherwise the punch tips over and there is no solution, which
//! [`TiltingPunch`]'s `discretise` reports as an error on `{path}.at`.
//!
//! **Friction** (theory §8.3) as for the rigid punch ([`crate::punch`]): with a `friction` law
//! each node's row is followed by its tangential rows `(u₁, u₂)(x_i) − W`, W prescribed or the
//! extras `Ux`, `Uy` (after U and the slopes) loaded by `Q`. The tilt moves the face's points
//! along e₃ only (to first order, about a pivot on the face), so the tangential rows have no
//! entry on U and the slopes, and the normal rows none on Ux, Uy. A tangential force at the face
//! has no moment about the pivot's horizontal axes: force and moment balance are unchanged.

use crate::gap::{GapShape, validate_gap};
use crate::punch::PunchFriction;
use crate::tangential::Tangential;
use crate::zone::{candidate_nodes, rim_rows, rim_warning};
use saddle_core::error::{check, join};
use saddle_core::{
    AdmissibleDisplacements, ConstraintRows, ContactReport, DofMap, FrictionLaw, LoadFactors, ParameterError, Region,
    SceneError, TetMesh, normal_contact_set,
};
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

/// Relative tolerance (of the zone's extent in the (x₁, x₂) plane) of the convex-hull test on
/// `at`: a point on the hull's boundary within round-off is inside (the punch balances on an
/// edge of the zone).
const HULL_TOL: f64 = 1e-10;

/// `type = "tilting_punch"`: a force-controlled punch that moves up by U and tilts by the slopes
/// (slope_x1, slope_x2) about its pivot, the gap's centre (theory §8).
///
/// ```toml
/// [obstacle]
/// type = "tilting_punch"
/// F = 0.3
/// at = [0.1, 0.0]
/// zone = { all = [ { group = "zmin" }, { disc = { center = [0.0, 0.0], radius = 0.5 } } ] }
/// gap = { type = "paraboloid", R = 5.0 }
/// ```
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
pub struct TiltingPunch {
    /// The upward force F ≥ 0 on the punch (0: no load, its extras undetermined).
    pub F: f64,
    /// Where the force acts, (a₁, a₂); the gap's centre (the pivot) when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<[f64; 2]>,
    /// The candidate contact zone Γ₀ (boundary nodes with u₃ free on a flat face, as for the
    /// rigid punch).
    pub zone: Region,
    /// The gap function φ; its centre is the pivot c.
    pub gap: Box<dyn GapShape>,
    /// The friction law on the contact (theory §8.3); absent: frictionless.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<Box<dyn FrictionLaw>>,
    /// The tangential force Q = [Qx, Qy] (extras `Ux`, `Uy`), as for `rigid_punch`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub Q: Option<[f64; 2]>,
    /// The prescribed motion W = [Wx, Wy] across the axis, as for `rigid_punch`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub W: Option<[f64; 2]>,
}

impl TiltingPunch {
    /// A punch pushed by `force` at its pivot (the centre of `gap`) against the nodes of `zone`,
    /// validated (errors name `obstacle.F`, `obstacle.zone`, `obstacle.gap`).
    pub fn new(force: f64, zone: Region, gap: Box<dyn GapShape>) -> Result<Self, ParameterError> {
        let k = Self { F: force, at: None, zone, gap, friction: None, Q: None, W: None };
        k.validate("obstacle")?;
        Ok(k)
    }

    /// The same punch with the friction law `law` (theory §8.3).
    pub fn with_friction(self, law: Box<dyn FrictionLaw>) -> Self {
        Self { friction: Some(law), ..self }
    }

    /// The tangential rows and extras (after U and the slopes).
    fn friction(&self) -> PunchFriction<'_> {
        PunchFriction::new(Tangential::new(&self.friction, self.Q, self.W), 3)
    }

    /// The punch with F, Q and W each multiplied by its factor (theory §11.2).
    fn with_load_factors(&self, factors: &LoadFactors) -> Self {
        let (q, w) = Tangential::new(&self.friction, self.Q, self.W).scaled(factors);
        Self { F: self.F * factors.of("F"), Q: q, W: w, ..self.clone() }
    }

    /// The same punch with the force acting at `a` = (a₁, a₂), validated (`obstacle.at`).
    pub fn at(mut self, a: [f64; 2]) -> Result<Self, ParameterError> {
        self.at = Some(a);
        self.validate("obstacle")?;
        Ok(self)
    }

    /// The pivot c: the gap's centre.
    pub fn pivot(&self) -> [f64; 2] {
        self.gap.center()
    }

    /// Where the force acts: `at`, or the pivot.
    pub fn point_of_action(&self) -> [f64; 2] {
        self.at.unwrap_or_else(|| self.pivot())
    }

    /// x − c in the plane for mesh node `n`.
    fn arm(&self, mesh: &TetMesh, n: usize) -> [f64; 2] {
        let x = mesh.nodes[n];
        let [c1, c2] = self.pivot();
        [x[0] - c1, x[1] - c2]
    }

    /// `at` (or its default) inside the convex hull of the contact nodes, and those nodes not
    /// collinear (else the tilt about their line is undetermined).
    fn check_hull(&self, mesh: &TetMesh, nodes: &[usize], path: &str) -> Result<(), SceneError> {
        let points: Vec<[f64; 2]> = nodes.iter().map(|&n| [mesh.nodes[n][0], mesh.nodes[n][1]]).collect();
        let hull = convex_hull(points);
        let extent = hull_extent(&hull);
        let area2 = polygon_area2(&hull);
        if hull.len() < 3 || area2 <= HULL_TOL * extent * extent {
            return Err(SceneError::Region {
                field: join(path, "zone"),
                message: format!(
                    "its {} contact nodes lie on one line in the (x₁, x₂) plane: the tilting punch could rotate freely \
                     about it (the slopes are undetermined, theory §8); use a zone with nodes off that line",
                    nodes.len()
                ),
            });
        }
        let a = self.point_of_action();
        let tol = HULL_TOL * extent;
        let outside = hull.iter().zip(hull.iter().cycle().skip(1)).any(|(p, q)| {
            let edge = [q[0] - p[0], q[1] - p[1]];
            let cross = edge[0] * (a[1] - p[1]) - edge[1] * (a[0] - p[0]);
            cross < -tol * edge[0].hypot(edge[1])
        });
        if outside {
            let (lo, hi) = bounds(&hull);
            let default = if self.at.is_none() { " (the default: the gap's centre)" } else { "" };
            return Err(SceneError::Parameter(ParameterError::new(
                join(path, "at"),
                format!("[{}, {}]{default}", a[0], a[1]),
                format!(
                    "must lie inside the convex hull of the {} contact nodes of {} (within x₁ ∈ [{}, {}], x₂ ∈ [{}, {}]): \
                     the contact forces cannot balance a force acting outside it, the punch would tip over and there \
                     is no solution (theory §8)",
                    nodes.len(),
                    join(path, "zone"),
                    lo[0],
                    hi[0],
                    lo[1],
                    hi[1]
                ),
            )));
        }
        Ok(())
    }
}

/// The convex hull of points in the plane, counter-clockwise, without repeated or collinear
/// vertices (Andrew's monotone chain).
fn convex_hull(mut p: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    let chain = |points: &mut dyn Iterator<Item = [f64; 2]>| {
        let mut c: Vec<[f64; 2]> = Vec::new();
        for q in points {
            while c.len() >= 2 && cross(c[c.len() - 2], c[c.len() - 1], q) <= 0.0 {
                c.pop();
            }
            c.push(q);
        }
        c.pop(); // the last point of each chain starts the other
        c
    };
    let mut hull = chain(&mut p.iter().copied());
    hull.extend(chain(&mut p.iter().rev().copied()));
    hull
}

/// Twice the (signed, positive counter-clockwise) area of a polygon.
fn polygon_area2(p: &[[f64; 2]]) -> f64 {
    p.iter().zip(p.iter().cycle().skip(1)).map(|(a, b)| a[0] * b[1] - a[1] * b[0]).sum()
}

/// The bounding box of points in the plane.
fn bounds(p: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    p.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), q| {
        ([lo[0].min(q[0]), lo[1].min(q[1])], [hi[0].max(q[0]), hi[1].max(q[1])])
    })
}

/// The larger side of the bounding box (0 for no point).
fn hull_extent(p: &[[f64; 2]]) -> f64 {
    if p.is_empty() {
        return 0.0;
    }
    let (lo, hi) = bounds(p);
    (hi[0] - lo[0]).max(hi[1] - lo[1])
}

#[typetag::serde(name = "tilting_punch")]
impl AdmissibleDisplacements for TiltingPunch {
    /// F × factor, at the same point (and Q or W × factor).
    fn scaled_load(&self, factor: f64) -> Option<Box<dyn AdmissibleDisplacements>> {
        self.scaled_loads(&LoadFactors::uniform(factor))
    }

    /// With `Q` or `W`: `F` and that one, each with factors of its own (theory §11.2); else
    /// none (the whole load follows the path's factor).
    fn load_names(&self) -> Vec<String> {
        self.friction().load_names("F")
    }

    /// F, Q and W each multiplied by its own factor.
    fn scaled_loads(&self, factors: &LoadFactors) -> Option<Box<dyn AdmissibleDisplacements>> {
        Some(Box::new(self.with_load_factors(factors)))
    }

    /// F finite and ≥ 0 (`{path}.F`) and at most [`check::MAX_MAGNITUDE`] (a force enters the
    /// solvers' products), `at` finite and within that magnitude (`{path}.at[k]`), the zone and
    /// the gap shape.
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::non_negative(path, "F", self.F)?;
        check::bounded(path, "F", self.F)?;
        if let Some(a) = &self.at {
            check::bounded_all(path, "at", a)?;
        }
        self.zone.validate(&join(path, "zone"))?;
        validate_gap(self.gap.as_ref(), path)?;
        self.friction().tangential.validate(path, "the punch")
    }

    /// The punch's rise U at the pivot and its slopes; then `Ux`, `Uy` under Q.
    fn extra_names(&self) -> Vec<String> {
        let mut names = vec!["U".to_string(), "slope_x1".into(), "slope_x2".into()];
        names.extend(self.friction().tangential.extra_names());
        names
    }

    /// F·w(a) = F U + F (a₁ − c₁) slope_x1 + F (a₂ − c₂) slope_x2 (theory §8); then
    /// Qx Ux + Qy Uy under Q.
    fn load(&self) -> Vec<f64> {
        let [a1, a2] = self.point_of_action();
        let [c1, c2] = self.pivot();
        let mut f = vec![self.F, self.F * (a1 - c1), self.F * (a2 - c2)];
        f.extend(self.friction().tangential.load());
        f
    }

    /// g_i = u₃(x_i) + φ(x_i) − w(x_i) ≥ 0: G = e₃ at the node, H_i = (−1, −(x_i1 − c₁),
    /// −(x_i2 − c₂)), c_i = φ(x_i) (theory §8). Errors: the zone (as for the
    /// rigid punch), contact nodes on one line, and `{path}.at` outside their convex hull.
    fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError> {
        let zone = candidate_nodes(&self.zone, mesh, dofs, path)?;
        self.check_hull(mesh, &zone.nodes, path)?;
        let f = self.friction();
        let mut rows = ConstraintRows::new(3 + f.n_across());
        let weights = f.weights(mesh, &zone.nodes);
        let (mut h, mut without_plane) = (Vec::with_capacity(5), 0);
        for (a, &n) in zone.nodes.iter().enumerate() {
            let d = dofs.free(n, 2).expect("candidate nodes have a free u₃");
            let x = mesh.nodes[n];
            let [r1, r2] = self.arm(mesh, n);
            let row = rows.n_rows();
            rows.push(&[(d, 1.0)], &f.normal_entries(&[-1.0, -r1, -r2]), self.gap.phi(x[0], x[1]), n);
            if f.is_on() && !f.push(&mut rows, dofs, n, row, weights[a], &mut h) {
                without_plane += 1;
            }
        }
        rows.warnings = zone.warnings;
        f.finish(&mut rows, without_plane, path)?;
        Ok(rows)
    }

    /// g_i = u₃(x_i) + φ(x_i) − w(x_i) from the node coordinates and the extras.
    /// The rows do not depend on F nor Q: the same rows; with W prescribed the tangential rows'
    /// offsets do: discretised again.
    fn rows_at_factor<'r>(
        &self,
        factor: f64,
        rows: &'r ConstraintRows,
        mesh: &TetMesh,
        dofs: &DofMap,
        path: &str,
    ) -> Result<Cow<'r, ConstraintRows>, SceneError> {
        if self.W.is_none() {
            return Ok(Cow::Borrowed(rows));
        }
        self.with_load_factors(&LoadFactors::uniform(factor)).discretise(mesh, dofs, path).map(Cow::Owned)
    }

    fn gap(&self, mesh: &TetMesh, dofs: &DofMap, rows: &ConstraintRows, u: &[f64], extras: &[f64], out: &mut [f64]) {
        let [big_u, s1, s2] = [extras[0], extras[1], extras[2]];
        for (g, &n) in out.iter_mut().zip(&rows.node) {
            let x = mesh.nodes[n];
            let [r1, r2] = self.arm(mesh, n);
            let u3 = dofs.free(n, 2).map_or(0.0, |d| u[d]);
            *g = u3 + self.gap.phi(x[0], x[1]) - (big_u + s1 * r1 + s2 * r2);
        }
        self.friction().slips(dofs, rows, u, &extras[3..], out);
    }

    /// `U`, `slope_x1`, `slope_x2` (the extras), `force` = Σλ_i (= F at a solution),
    /// `moment_x1`, `moment_x2` = Σλ_i (x_ik − c_k) (= F (a_k − c_k) at a solution); the contact
    /// set, its radius about the pivot, and the rim warning of the rigid punch.
    fn report(&self, mesh: &TetMesh, rows: &ConstraintRows, extras: &[f64], lambda: &[f64]) -> ContactReport {
        debug_assert_eq!(lambda.len(), rows.n_rows());
        let contact = normal_contact_set(rows, lambda);
        let normal = self.friction().normal_mask(rows);
        let (mut force, mut m1, mut m2) = (0.0, 0.0, 0.0);
        for ((&l, &n), _) in lambda.iter().zip(&rows.node).zip(&normal).filter(|x| *x.1) {
            let [r1, r2] = self.arm(mesh, n);
            force += l;
            m1 += l * r1;
            m2 += l * r2;
        }
        let contact_radius = contact
            .iter()
            .map(|&i| {
                let [r1, r2] = self.arm(mesh, rows.node[i]);
                r1.hypot(r2)
            })
            .fold(0.0, f64::max);
        let rim = rim_rows(mesh, rows, &contact);
        let warnings =
            if self.gap.has_edge() { None } else { rim_warning("obstacle", mesh, rows, &rim) }.into_iter().collect();
        let mut quantities = vec![
            ("U".into(), extras[0]),
            ("slope_x1".into(), extras[1]),
            ("slope_x2".into(), extras[2]),
            ("force".into(), force),
            ("moment_x1".into(), m1),
            ("moment_x2".into(), m2),
        ];
        quantities.extend(self.friction().quantities(rows, lambda, &extras[3..]));
        ContactReport { quantities, contact_nodes: contact.len(), contact_radius, warnings }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_a_square_with_inner_and_edge_points() {
        let pts = vec![[0.0, 0.0], [1.0, 0.0], [0.5, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5], [1.0, 1.0]];
        let hull = convex_hull(pts);
        assert_eq!(hull, vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        assert_eq!(polygon_area2(&hull), 2.0);
        assert_eq!(hull_extent(&hull), 1.0);
        // collinear points: the hull is the segment's two ends, area 0
        let line = convex_hull(vec![[0.0, 0.0], [2.0, 1.0], [1.0, 0.5]]);
        assert_eq!(line, vec![[0.0, 0.0], [2.0, 1.0]]);
        assert_eq!(polygon_area2(&line), 0.0);
    }
}
