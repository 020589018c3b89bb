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
//!
//! **Friction** (theory §8.3). With a `friction` law each node's normal row is followed by two
//! tangential rows, the slip of the node against the sphere in its tangent plane,
//! `s_i = T_iᵀ(u_i − V d − W)` with T_i = [t₁, t₂] orthonormal and ⊥ n_i ([`RigidSphere::frame`]),
//! and a block naming them with the node's share w_i of the faces that look at the centre. The
//! sphere then also moves across d, by `W = W_x e₁ + W_y e₂` ((e₁, e₂) ⊥ d,
//! [`RigidSphere::tangential_axes`]): prescribed (`W`), or extras `Ux`, `Uy` loaded by the force
//! `Q = [Qx, Qy]`. The normal rows see that motion too: the sphere's centre is c + V d + W.
//! Without `friction`, `Q` and `W` the rows are exactly the frictionless ones.

use crate::tangential::{
    Tangential, TangentialPair, add, dot, finish_friction, frame, friction_quantities, norm, push_tangential,
    row_directions, sub, tangential_axes,
};
use crate::zone::node_areas_facing;
use crate::zone::{Selection, candidate_nodes_with, rim_rows_facing, rim_warning};
use saddle_core::error::{check, join};
use saddle_core::mesh::signed_volume;
use saddle_core::{
    AdmissibleDisplacements, ConstraintRows, ContactReport, DofMap, FrictionLaw, LoadFactors, ParameterError, Region,
    SceneError, TetMesh, normal_contact_set,
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
    /// The friction law on the contact (theory §8.3); absent: frictionless.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<Box<dyn FrictionLaw>>,
    /// The tangential force Q = [Qx, Qy] along (e₁, e₂) ⊥ d: the sphere's motion across d is
    /// then the extras `Ux`, `Uy`. Needs `friction`; exclusive with `W`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub Q: Option<[f64; 2]>,
    /// The prescribed motion W = [Wx, Wy] across d, along (e₁, e₂). Needs `friction`;
    /// exclusive with `Q`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub W: Option<[f64; 2]>,
}

impl RigidSphere {
    /// A sphere pushed along `direction` by the force `force` (V unknown).
    pub fn pushed(center: [f64; 3], radius: f64, direction: [f64; 3], force: f64, zone: Region) -> Self {
        Self { center, R: radius, direction, F: Some(force), V: None, zone, friction: None, Q: None, W: None }
    }

    /// A sphere moved along `direction` by the prescribed `v`.
    pub fn moved(center: [f64; 3], radius: f64, direction: [f64; 3], v: f64, zone: Region) -> Self {
        Self { center, R: radius, direction, F: None, V: Some(v), zone, friction: None, Q: None, W: None }
    }

    /// The same sphere with the friction law `law` (theory §8.3).
    pub fn with_friction(self, law: Box<dyn FrictionLaw>) -> Self {
        Self { friction: Some(law), ..self }
    }

    /// The sphere with F, V, Q and W each multiplied by its factor (theory §11.2).
    fn with_load_factors(&self, factors: &LoadFactors) -> Self {
        Self {
            F: self.F.map(|f| f * factors.of("F")),
            V: self.V.map(|v| v * factors.of("V")),
            Q: self.Q.map(|q| q.map(|x| x * factors.of("Q"))),
            W: self.W.map(|w| w.map(|x| x * factors.of("W"))),
            ..self.clone()
        }
    }

    /// The fields `friction`, `Q`, `W` (theory §8.3).
    fn tangential(&self) -> Tangential<'_> {
        Tangential::new(&self.friction, self.Q, self.W)
    }

    /// (e₁, e₂): the axes of the motion across d ([`tangential_axes`]; for d = e₃: (x₁, x₂)).
    pub fn tangential_axes(&self) -> ([f64; 3], [f64; 3]) {
        tangential_axes(self.d())
    }

    /// (t₁, t₂): the tangent plane at a node of normal `n` ([`frame`]).
    pub fn frame(&self, n: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        frame(self.tangential_axes(), n)
    }

    /// The sphere's motion across d: W e (prescribed), or the extras (Ux, Uy), or 0.
    fn across(&self, extras: &[f64]) -> [f64; 3] {
        let k = usize::from(self.V.is_none()).min(extras.len());
        self.tangential().across(self.tangential_axes(), &extras[k..])
    }

    /// The H entries of a row of direction `a` (n or t): −a·d for V unknown, −a·e₁, −a·e₂ for
    /// (Ux, Uy) unknown.
    fn extra_entries(&self, a: [f64; 3], out: &mut Vec<f64>) {
        out.clear();
        if self.V.is_none() {
            out.push(-dot(a, self.d()));
        }
        self.tangential().extra_entries(a, self.tangential_axes(), out);
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

    /// The centre c̃ about which the rows are linearised: c, moved by V d with V prescribed and
    /// by W with W prescribed.
    fn linearisation_centre(&self) -> [f64; 3] {
        let d = self.d();
        let v = self.V.unwrap_or(0.0);
        let w = self.tangential().prescribed(self.tangential_axes());
        std::array::from_fn(|k| self.center[k] + v * d[k] + w[k])
    }

    /// The prescribed motion of the sphere's points at the linearisation: V d (V prescribed)
    /// + W (W prescribed).
    fn prescribed_motion(&self) -> [f64; 3] {
        let d = self.d();
        let v = self.V.unwrap_or(0.0);
        let w = self.tangential().prescribed(self.tangential_axes());
        std::array::from_fn(|k| v * d[k] + w[k])
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

#[typetag::serde(name = "rigid_sphere")]
impl AdmissibleDisplacements for RigidSphere {
    /// F × factor or V × factor, whichever is given.
    fn scaled_load(&self, factor: f64) -> Option<Box<dyn AdmissibleDisplacements>> {
        self.scaled_loads(&LoadFactors::uniform(factor))
    }

    /// Those of `F`, `V`, `Q`, `W` that are given: the normal load and the tangential one may
    /// follow factors of their own (Mindlin's loop: F held, Q back and forth; theory §11.2).
    fn load_names(&self) -> Vec<String> {
        let given =
            [("F", self.F.is_some()), ("V", self.V.is_some()), ("Q", self.Q.is_some()), ("W", self.W.is_some())];
        given.into_iter().filter(|g| g.1).map(|g| g.0.to_string()).collect()
    }

    /// F, V, Q and W each multiplied by its own factor.
    fn scaled_loads(&self, factors: &LoadFactors) -> Option<Box<dyn AdmissibleDisplacements>> {
        Some(Box::new(self.with_load_factors(factors)))
    }

    /// The same rows under force control (only the load term changes); with V or W prescribed,
    /// the rows about the moved sphere.
    fn rows_at_factors<'r>(
        &self,
        factors: &LoadFactors,
        rows: &'r ConstraintRows,
        mesh: &TetMesh,
        dofs: &DofMap,
        path: &str,
    ) -> Result<Cow<'r, ConstraintRows>, SceneError> {
        if self.V.is_none() && self.W.is_none() {
            return Ok(Cow::Borrowed(rows));
        }
        self.with_load_factors(factors).discretise(mesh, dofs, path).map(Cow::Owned)
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
        self.tangential().validate(path, "the sphere")?;
        self.zone.validate(&join(path, "zone"))
    }

    /// `["V"]` under force control, none when V is prescribed; then `Ux`, `Uy` under a
    /// tangential force Q.
    fn extra_names(&self) -> Vec<String> {
        let mut names = if self.V.is_some() { vec![] } else { vec!["V".to_string()] };
        if self.Q.is_some() {
            names.extend(["Ux".to_string(), "Uy".to_string()]);
        }
        names
    }

    /// F·V (theory §8), nothing when V is prescribed; then Qx Ux + Qy Uy under Q.
    fn load(&self) -> Vec<f64> {
        let mut f = match (self.F, self.V) {
            (_, Some(_)) => vec![],
            (f, None) => vec![f.unwrap_or(0.0)],
        };
        f.extend(self.Q.into_iter().flatten());
        f
    }

    /// g_i = n_i·(x_i + u_i − c − V d − W) − R ≥ 0 (theory §8): G = n_i on the free dofs of
    /// node i, H_i = −n_i·d (V unknown) and −n_i·e₁, −n_i·e₂ ((Ux, Uy) unknown),
    /// c_i = |x_i − c| − R; with V or W prescribed, n_i and c_i are taken about c + V d + W (see
    /// the module docs). With friction each normal row is followed by the node's two tangential
    /// rows (theory §8.3). Errors: the zone (no node with a free dof), a zone node inside the
    /// sphere at V = 0 (`{path}.center`), a prescribed V that puts the sphere's centre on a zone
    /// node (`{path}.V`), and a friction law where no zone node has a free tangent plane
    /// (`{path}.friction`).
    fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError> {
        let zone = candidate_nodes_with(&self.zone, mesh, dofs, path, Selection::AnyFreeDof)?;
        self.check_outside(mesh, &zone.nodes, path)?;
        let centre = self.linearisation_centre();
        let mut rows = ConstraintRows::new(self.extra_names().len());
        let weights = match &self.friction {
            Some(_) => node_areas_facing(mesh, &zone.nodes, |normal, x| dot(normal, sub(centre, x)) > 0.0),
            None => Vec::new(),
        };
        let (mut entries, mut h) = ([(0, 0.0); 3], Vec::with_capacity(3));
        let mut without_plane = 0;
        for (a, &n) in zone.nodes.iter().enumerate() {
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
            self.extra_entries(normal, &mut h);
            let row = rows.n_rows();
            rows.push(&entries[..k], &h, dist - self.R, n);
            if self.friction.is_some() {
                let pair = TangentialPair { node: n, frame: self.frame(normal), normal: row, weight: weights[a] };
                let entries = |t: [f64; 3], h: &mut Vec<f64>| self.extra_entries(t, h);
                if !push_tangential(&mut rows, dofs, pair, self.prescribed_motion(), entries, &mut h) {
                    without_plane += 1;
                }
            }
        }
        rows.warnings = zone.warnings;
        if let Some(law) = &self.friction {
            finish_friction(&mut rows, law.as_ref(), without_plane, path)?;
        }
        Ok(rows)
    }

    /// Under force control (F, Q) the rows do not depend on the load: the same rows. With V or
    /// W prescribed they are linearised about the displaced centre (module docs): discretised
    /// again.
    fn rows_at_factor<'r>(
        &self,
        factor: f64,
        rows: &'r ConstraintRows,
        mesh: &TetMesh,
        dofs: &DofMap,
        path: &str,
    ) -> Result<Cow<'r, ConstraintRows>, SceneError> {
        self.rows_at_factors(&LoadFactors::uniform(factor), rows, mesh, dofs, path)
    }

    /// The exact gap |x_i + u_i − c − V d − W| − R on the normal rows; on the tangential rows
    /// the slip t_k·(u_i − V d − W) (theory §8.3), t_k the frame of the row's normal.
    fn gap(&self, mesh: &TetMesh, dofs: &DofMap, rows: &ConstraintRows, u: &[f64], extras: &[f64], out: &mut [f64]) {
        let d = self.d();
        let v = self.v(extras);
        let w = self.across(extras);
        let motion: [f64; 3] = std::array::from_fn(|c| v * d[c] + w[c]);
        let displacement =
            |n: usize| -> [f64; 3] { std::array::from_fn(|c| dofs.free(n, c).map_or(0.0, |j| u[j]) - motion[c]) };
        for (g, &n) in out.iter_mut().zip(&rows.node) {
            let (r, _) = self.radial(mesh, n);
            *g = norm(add(r, displacement(n))) - self.R;
        }
        let centre = self.linearisation_centre();
        for b in &rows.friction.blocks {
            let n = rows.node[b.normal];
            let (t1, t2) = self.frame(self.normal(mesh, n, centre).0);
            let y = displacement(n);
            out[b.tangent] = dot(t1, y);
            out[b.tangent + 1] = dot(t2, y);
        }
    }

    /// `V` (the extra or the prescribed value), `force` = Σλ_i a_i·d with the rows' directions
    /// a_i (normals and tangents; = F at a solution), the contact set of the normal rows, its
    /// radius about the sphere's own centre — the largest distance of a contact node from the
    /// axis {c + t d} — and a warning when the contact set reaches the rim of the zone. The rim
    /// is measured on the boundary facets facing the sphere (outward normal towards c): unlike
    /// the punch's (facets with n₃ < 0) this works whichever face the sphere touches; facets
    /// looking away from c never count. With friction also `Ux`, `Uy` (the motion across d),
    /// `force_x`, `force_y` = Σλ_i a_i·e₁, Σλ_i a_i·e₂ (= Q at a solution), `stick_nodes` and
    /// `slip_nodes` (contact nodes with |λ_t| below, at the disc's radius: [`contact_status`];
    /// theory §8.3).
    fn report(&self, mesh: &TetMesh, rows: &ConstraintRows, extras: &[f64], lambda: &[f64]) -> ContactReport {
        debug_assert_eq!(lambda.len(), rows.n_rows());
        let d = self.d();
        let centre = self.linearisation_centre();
        let contact = normal_contact_set(rows, lambda);
        let directions = self.row_directions(mesh, rows);
        let resultant = |e: [f64; 3]| -> f64 { lambda.iter().zip(&directions).map(|(&l, &a)| l * dot(a, e)).sum() };
        let force = resultant(d);
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
        let mut quantities = vec![("V".into(), self.v(extras)), ("force".into(), force)];
        if self.friction.is_some() {
            let across = self.across(extras);
            quantities.extend(friction_quantities(rows, lambda, &directions, self.tangential_axes(), across));
        }
        ContactReport {
            quantities,
            contact_nodes: contact.len(),
            contact_radius,
            warnings: rim_warning("obstacle", mesh, rows, &rim).into_iter().collect(),
        }
    }
}

impl RigidSphere {
    /// The direction of every row: n_i for a normal row, t₁, t₂ of n_i for its tangential rows.
    fn row_directions(&self, mesh: &TetMesh, rows: &ConstraintRows) -> Vec<[f64; 3]> {
        let centre = self.linearisation_centre();
        row_directions(rows, self.tangential_axes(), |n| self.normal(mesh, n, centre).0)
    }
}
