//! The rigid sphere of theory §8: a ball of centre c and radius R that moves along the unit
//! direction d by V, pushed by a force F (V an extra unknown) or with V prescribed.
//!
//! The exact gap of node i is `|x_i + u_i − c − V d| − R`. Linearised at the reference
//! configuration (u, V) = (0, 0), with `n_i = (x_i − c)/|x_i − c|`,
//!
//! ```text
//! g_i = n_i·(x_i + u_i − c − V d) − R = (|x_i − c| − R) + n_i·u_i − (n_i·d) V ≥ 0:
//! ```
//!
//! G has the components of n_i on the free dofs of node i (a row acts on up to three dofs;
//! components on fixed dofs are dropped, the fixed displacement being 0), `H_i = −n_i·d` when V
//! is unknown, `c_i = |x_i − c| − R`. The load is F·V, so at a solution `Σλ_i n_i·d = F`, the
//! resultant of the contact forces along d. Since `|y| ≥ n·y`, a point feasible for the rows is
//! feasible for the exact gap: the rows are an inner approximation of the exact K, valid for
//! displacements small against R.
//!
//! With V prescribed there is no extra unknown, and the reference configuration of the unknowns
//! is u = 0 with the sphere already at c̃ = c + V d: the rows are the linearisation there,
//! `n_i = (x_i − c̃)/|x_i − c̃|`, `c_i = |x_i − c̃| − R`, so that `gap()` (which contains the
//! prescribed V) linearises to them at u = 0, as the conformance kit requires. To first order
//! in V this is `|x_i − c| − R − V n_i·d` with the normals of the undisplaced sphere (theory §8);
//! the two differ by O(V²/|x_i − c|).
//!
//! Unlike the punches, the zone need not be flat or horizontal: any boundary node of the zone
//! with a free dof carries a row ([`Selection::AnyFreeDof`]).

use crate::zone::{Selection, candidate_nodes_with, rim_rows_facing, rim_warning};
use saddle_core::error::{check, join};
use saddle_core::mesh::signed_volume;
use saddle_core::{
    AdmissibleDisplacements, ConstraintRows, ContactReport, DofMap, ParameterError, Region, SceneError, TetMesh,
    contact_set,
};
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

/// Relative round-off (of R) below which a zone node at distance < R from the centre still
/// counts as touching the sphere rather than inside it.
const INSIDE_TOL: f64 = 1e-10;

/// Relative distance (of R) from the linearisation centre below which a zone node has no
/// contact normal.
const CENTRE_ON_NODE: f64 = 1e-12;

/// Relative tolerance on a facet's normal towards the centre when deciding whether the facet
/// faces the sphere (for the rim warning).
const FACING_TOL: f64 = 1e-8;

/// `type = "rigid_sphere"`: a rigid ball of centre `center` and radius `R` moving along
/// `direction` by V, pushed by `F` (V unknown) or moved by a prescribed `V` — exactly one of the
/// two (theory §8).
///
/// ```toml
/// [obstacle]
/// type = "rigid_sphere"
/// center = [0.0, 0.0, -5.0]
/// R = 5.0
/// direction = [0.0, 0.0, 1.0]
/// F = 0.3
/// zone = { all = [ { group = "zmin" }, { disc = { center = [0.0, 0.0], radius = 0.5 } } ] }
/// ```
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
pub struct RigidSphere {
    /// The centre c of the sphere at the reference configuration (V = 0).
    pub center: [f64; 3],
    /// The radius R > 0.
    pub R: f64,
    /// The direction d of motion (normalised by the code; finite and nonzero).
    pub direction: [f64; 3],
    /// The force F ≥ 0 along d (force control: V is an extra unknown; 0: no load, V
    /// undetermined). Exclusive with `V`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub F: Option<f64>,
    /// The prescribed displacement V along d (no extra unknown). Exclusive with `F`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub V: Option<f64>,
    /// The candidate contact zone (boundary nodes with at least one free dof).
    pub zone: Region,
}

impl RigidSphere {
    /// A sphere pushed along `direction` by the force `force` (V unknown).
    pub fn pushed(center: [f64; 3], radius: f64, direction: [f64; 3], force: f64, zone: Region) -> Self {
        Self { center, R: radius, direction, F: Some(force), V: None, zone }
    }

    /// A sphere moved along `direction` by the prescribed `v`.
    pub fn moved(center: [f64; 3], radius: f64, direction: [f64; 3], v: f64, zone: Region) -> Self {
        Self { center, R: radius, direction, F: None, V: Some(v), zone }
    }

    /// The unit direction d, or `None` when `direction` is not finite or zero.
    pub fn unit_direction(&self) -> Option<[f64; 3]> {
        let d = self.direction;
        // scale first so that huge finite components do not overflow the norm
        let s = d.iter().map(|x| x.abs()).fold(0.0, f64::max);
        if !(s.is_finite() && s > 0.0) || d.iter().any(|x| !x.is_finite()) {
            return None;
        }
        let e = d.map(|x| x / s);
        let n = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
        Some(e.map(|x| x / n))
    }

    /// d for validated parameters.
    fn d(&self) -> [f64; 3] {
        self.unit_direction().expect("validated: the direction is finite and nonzero")
    }

    /// V for the extras `extras`: the prescribed V, or the extra unknown.
    fn v(&self, extras: &[f64]) -> f64 {
        self.V.unwrap_or_else(|| extras[0])
    }

    /// (x_i − c, |x_i − c|) for mesh node `n`.
    fn radial(&self, mesh: &TetMesh, n: usize) -> ([f64; 3], f64) {
        let x = mesh.nodes[n];
        let r = [x[0] - self.center[0], x[1] - self.center[1], x[2] - self.center[2]];
        (r, norm(r))
    }

    /// The centre c̃ about which the rows are linearised: c, or c + V d with V prescribed.
    fn linearisation_centre(&self) -> [f64; 3] {
        let d = self.d();
        let v = self.V.unwrap_or(0.0);
        std::array::from_fn(|k| self.center[k] + v * d[k])
    }

    /// (n_i, |x_i − c̃|) for mesh node `n`: the row's normal and distance from c̃.
    fn normal(&self, mesh: &TetMesh, n: usize, centre: [f64; 3]) -> ([f64; 3], f64) {
        let x = mesh.nodes[n];
        let y = [x[0] - centre[0], x[1] - centre[1], x[2] - centre[2]];
        let dist = norm(y);
        (y.map(|v| v / dist), dist)
    }

    /// The element that holds the centre c (its closure: a centre on the body's surface is half
    /// embedded too), if any (barycentric coordinates by signed volumes, each at least
    /// −[`INSIDE_TOL`] of the element's volume).
    fn element_holding_centre(&self, mesh: &TetMesh) -> Option<usize> {
        let c = self.center;
        (0..mesh.n_elements()).find(|&e| {
            let t = mesh.tets[e];
            let vol = signed_volume(&mesh.nodes, &t);
            (0..4).all(|k| {
                let mut nodes = t.map(|n| mesh.nodes[n]);
                nodes[k] = c;
                signed_volume(&nodes, &[0, 1, 2, 3]) >= -INSIDE_TOL * vol
            })
        })
    }

    /// A zone node strictly inside the sphere (the deepest one) is an error on `{path}.center`,
    /// and so is a centre inside the body (the sphere would start embedded in the material,
    /// whatever the zone).
    fn check_outside(&self, mesh: &TetMesh, nodes: &[usize], path: &str) -> Result<(), SceneError> {
        self.check_zone_outside(mesh, nodes, path)?;
        let Some(e) = self.element_holding_centre(mesh) else {
            return Ok(());
        };
        let c = self.center;
        Err(SceneError::Parameter(ParameterError::new(
            join(path, "center"),
            format!("[{}, {}, {}]", c[0], c[1], c[2]),
            format!(
                "lies in the body (in element {e}): the sphere would start embedded in the material, penetrating \
                 it at the reference configuration; the body must start outside the obstacle (theory §8): move {} \
                 outside the mesh",
                join(path, "center")
            ),
        )))
    }

    /// A zone node strictly inside the sphere (the deepest one) is an error on `{path}.center`.
    fn check_zone_outside(&self, mesh: &TetMesh, nodes: &[usize], path: &str) -> Result<(), SceneError> {
        let inside: Vec<(usize, f64)> = nodes
            .iter()
            .map(|&n| (n, self.radial(mesh, n).1))
            .filter(|&(_, dist)| dist < self.R * (1.0 - INSIDE_TOL))
            .collect();
        let Some(&(n, dist)) = inside.iter().min_by(|a, b| a.1.total_cmp(&b.1)) else {
            return Ok(());
        };
        let x = mesh.nodes[n];
        let c = self.center;
        Err(SceneError::Parameter(ParameterError::new(
            join(path, "center"),
            format!("[{}, {}, {}]", c[0], c[1], c[2]),
            format!(
                "puts {} node(s) of {} inside the sphere at the reference configuration, e.g. node {n} at ({}, {}, {}) at \
                 distance {dist} from the centre < {} = {}: the body must start outside the obstacle (g_i ≥ 0 at u = 0, \
                 V = 0; theory §8); move {} or reduce {}",
                inside.len(),
                join(path, "zone"),
                x[0],
                x[1],
                x[2],
                join(path, "R"),
                self.R,
                join(path, "center"),
                join(path, "R")
            ),
        )))
    }
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[typetag::serde(name = "rigid_sphere")]
impl AdmissibleDisplacements for RigidSphere {
    /// F × factor or V × factor, whichever is given.
    fn scaled_load(&self, factor: f64) -> Option<Box<dyn AdmissibleDisplacements>> {
        Some(Box::new(Self { F: self.F.map(|f| f * factor), V: self.V.map(|v| v * factor), ..self.clone() }))
    }

    /// `center` finite, R finite and > 0, `direction` finite and nonzero (`{path}.direction`
    /// with the vector), exactly one of F (finite, ≥ 0) and V (finite) — both or neither is an
    /// error on `{path}.F` whose message names `{path}.V` — and the zone. Lengths, F and V lie
    /// within [`check::MAX_MAGNITUDE`] (they enter the solvers' products).
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::bounded_all(path, "center", &self.center)?;
        check::positive(path, "R", self.R)?;
        check::bounded(path, "R", self.R)?;
        if self.unit_direction().is_none() {
            let d = self.direction;
            return Err(ParameterError::new(
                join(path, "direction"),
                format!("[{}, {}, {}]", d[0], d[1], d[2]),
                "must be a finite nonzero vector: the direction in which the sphere moves (it is normalised)",
            ));
        }
        let (f_field, v_field) = (join(path, "F"), join(path, "V"));
        match (self.F, self.V) {
            (Some(f), None) => {
                check::non_negative(path, "F", f)?;
                check::bounded(path, "F", f)?;
            }
            (None, Some(v)) => {
                check::bounded(path, "V", v)?;
            }
            (Some(f), Some(v)) => {
                return Err(ParameterError::new(
                    f_field.clone(),
                    f,
                    format!(
                        "cannot be given together with {v_field} = {v}: give exactly one of {f_field} (the force; V is \
                         then unknown) and {v_field} (the prescribed displacement)"
                    ),
                ));
            }
            (None, None) => {
                return Err(ParameterError::new(
                    f_field.clone(),
                    "missing",
                    format!(
                        "give exactly one of {f_field} (the force along the direction; V is then unknown) and {v_field} \
                         (the prescribed displacement along the direction)"
                    ),
                ));
            }
        }
        self.zone.validate(&join(path, "zone"))
    }

    /// `["V"]` under force control, none when V is prescribed.
    fn extra_names(&self) -> Vec<String> {
        if self.V.is_some() { vec![] } else { vec!["V".into()] }
    }

    /// F·V (theory §8); nothing when V is prescribed.
    fn load(&self) -> Vec<f64> {
        match (self.F, self.V) {
            (_, Some(_)) => vec![],
            (f, None) => vec![f.unwrap_or(0.0)],
        }
    }

    /// g_i = n_i·(x_i + u_i − c − V d) − R ≥ 0 (theory §8): G = n_i on the free dofs of node i,
    /// H_i = −n_i·d (V unknown), c_i = |x_i − c| − R; with V prescribed, n_i and c_i are taken
    /// about c + V d (see the module docs). Errors: the zone (no node with a free dof), a zone
    /// node inside the sphere at V = 0 (`{path}.center`), and a prescribed V
    /// that puts the sphere's centre on a zone node (`{path}.V`).
    fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError> {
        let zone = candidate_nodes_with(&self.zone, mesh, dofs, path, Selection::AnyFreeDof)?;
        self.check_outside(mesh, &zone.nodes, path)?;
        let d = self.d();
        let centre = self.linearisation_centre();
        let mut rows = ConstraintRows::new(usize::from(self.V.is_none()));
        let mut entries = [(0, 0.0); 3];
        for &n in &zone.nodes {
            let (normal, dist) = self.normal(mesh, n, centre);
            if dist <= CENTRE_ON_NODE * self.R {
                let x = mesh.nodes[n];
                return Err(SceneError::Parameter(ParameterError::new(
                    join(path, "V"),
                    self.V.unwrap_or(0.0),
                    format!(
                        "moves the sphere's centre onto node {n} at ({}, {}, {}) of {}: the contact normal there is \
                         undefined",
                        x[0],
                        x[1],
                        x[2],
                        join(path, "zone")
                    ),
                )));
            }
            let mut k = 0;
            for (c, &nc) in normal.iter().enumerate() {
                if let Some(j) = dofs.free(n, c) {
                    entries[k] = (j, nc);
                    k += 1;
                }
            }
            match self.V {
                None => rows.push(&entries[..k], &[-dot(normal, d)], dist - self.R, n),
                Some(_) => rows.push(&entries[..k], &[], dist - self.R, n),
            }
        }
        rows.warnings = zone.warnings;
        Ok(rows)
    }

    /// The exact gap |x_i + u_i − c − V d| − R.
    /// Under force control the rows do not depend on F: the same rows. With V prescribed they
    /// are linearised about the displaced centre (module docs): discretised again.
    fn rows_at_factor<'r>(
        &self,
        factor: f64,
        rows: &'r ConstraintRows,
        mesh: &TetMesh,
        dofs: &DofMap,
        path: &str,
    ) -> Result<Cow<'r, ConstraintRows>, SceneError> {
        match self.V {
            None => Ok(Cow::Borrowed(rows)),
            Some(v) => Self { V: Some(v * factor), ..self.clone() }.discretise(mesh, dofs, path).map(Cow::Owned),
        }
    }

    fn gap(&self, mesh: &TetMesh, dofs: &DofMap, rows: &ConstraintRows, u: &[f64], extras: &[f64], out: &mut [f64]) {
        let d = self.d();
        let v = self.v(extras);
        for (g, &n) in out.iter_mut().zip(&rows.node) {
            let (r, _) = self.radial(mesh, n);
            let y: [f64; 3] = std::array::from_fn(|c| r[c] + dofs.free(n, c).map_or(0.0, |j| u[j]) - v * d[c]);
            *g = norm(y) - self.R;
        }
    }

    /// `V` (the extra or the prescribed value), `force` = Σλ_i n_i·d with the rows' normals (= F
    /// at a solution), the
    /// contact set, its radius about the sphere's own centre — the largest distance of a
    /// contact node from the axis {c + t d} — and a warning when the contact set reaches the rim
    /// of the zone. The rim is measured on the boundary facets facing the sphere (outward normal
    /// towards c): unlike the punch's (facets with n₃ < 0) this works whichever face the
    /// sphere touches; facets looking away from c never count.
    fn report(&self, mesh: &TetMesh, rows: &ConstraintRows, extras: &[f64], lambda: &[f64]) -> ContactReport {
        debug_assert_eq!(lambda.len(), rows.n_rows());
        let d = self.d();
        let centre = self.linearisation_centre();
        let contact = contact_set(lambda);
        let force: f64 = lambda.iter().zip(&rows.node).map(|(&l, &n)| l * dot(self.normal(mesh, n, centre).0, d)).sum();
        let contact_radius = contact
            .iter()
            .map(|&i| {
                let (r, _) = self.radial(mesh, rows.node[i]);
                let along = dot(r, d);
                norm([r[0] - along * d[0], r[1] - along * d[1], r[2] - along * d[2]])
            })
            .fold(0.0, f64::max);
        let c = centre;
        let rim = rim_rows_facing(mesh, rows, &contact, |normal, x| {
            let to_c = [c[0] - x[0], c[1] - x[1], c[2] - x[2]];
            dot(normal, to_c) > FACING_TOL * norm(normal) * norm(to_c)
        });
        ContactReport {
            quantities: vec![("V".into(), self.v(extras)), ("force".into(), force)],
            contact_nodes: contact.len(),
            contact_radius,
            warnings: rim_warning("obstacle", mesh, rows, &rim).into_iter().collect(),
        }
    }
}
