//! The rigid punch of theory §1: a rigid body below the contact face, moving only vertically by U,
//! with gap function φ. K = { (v, V) : v₃ + φ − V ≥ 0 on Γ₀ }; on a mesh one row per contact
//! node, `g_i = u₃(x_i) + φ(x_i) − U ≥ 0` (theory §3).
//!
//! * [`RigidPunch`] (`type = "rigid_punch"`): force control, U is an extra unknown loaded by F
//!   (the term F·V of the Lagrangian (1.11)); at a solution Σλ_i = F (theory §3, KKT form).
//! * [`RigidPunchDisplacement`] (`type = "rigid_punch_displacement"`): U prescribed, no extra
//!   unknown; the resulting force Σλ_i is reported.
//!
//! Both share zone selection, rows, the direct gap and the report (a private `Punch`).
//!
//! **Friction** (theory §8.3). With a `friction` law each contact node's row is followed by two
//! tangential rows, the slip `s_i = (u₁, u₂)(x_i) − W` of the node against the punch's face
//! (the punch's axis is e₃, so (e₁, e₂) = (x₁, x₂) and every node's frame is (e₁, e₂)), and the
//! punch also moves across its axis by `W = [Wx, Wy]` (prescribed) or by the extras `Ux`, `Uy`
//! loaded by the force `Q = [Qx, Qy]`; the weights are the nodes' shares of the facets below
//! the body. Without `friction`, `Q` and `W` the rows are exactly the frictionless ones.

use crate::gap::{GapShape, validate_gap};
use crate::tangential::{
    Tangential, TangentialPair, dot, finish_friction, frame, friction_quantities, push_tangential, row_directions,
    tangential_axes,
};
use crate::zone::{candidate_nodes, node_areas_below, rim_rows, rim_warning, row_areas};
use saddle_core::error::{check, join};
use saddle_core::{
    AdmissibleDisplacements, ConstraintRows, ContactReport, DofMap, FrictionLaw, LoadFactors, ParameterError, Region,
    SceneError, TetMesh, normal_contact_set,
};
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

/// `type = "rigid_punch"`: the force-controlled punch of theory §1, pushed up by F ≥ 0 (F = 0:
/// the punch carries no load, its U is undetermined, theory §11.3).
///
/// ```toml
/// [obstacle]
/// type = "rigid_punch"
/// F = 0.3
/// zone = { all = [ { group = "zmin" }, { disc = { center = [0.0, 0.0], radius = 0.5 } } ] }
/// gap = { type = "paraboloid", R = 5.0 }
/// ```
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
pub struct RigidPunch {
    /// The upward force F ≥ 0 on the punch (theory §1).
    pub F: f64,
    /// The candidate contact zone Γ₀ (boundary nodes; theory §1, §3).
    pub zone: Region,
    /// The gap function φ.
    pub gap: Box<dyn GapShape>,
    /// The friction law on the contact (theory §8.3); absent: frictionless.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<Box<dyn FrictionLaw>>,
    /// The tangential force Q = [Qx, Qy] along (x₁, x₂): the punch's motion across its axis is
    /// then the extras `Ux`, `Uy`. Needs `friction`; exclusive with `W`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub Q: Option<[f64; 2]>,
    /// The prescribed motion W = [Wx, Wy] across the axis, along (x₁, x₂). Needs `friction`;
    /// exclusive with `Q`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub W: Option<[f64; 2]>,
}

/// `type = "rigid_punch_displacement"`: the punch of theory §1 moved by a prescribed U instead of
/// a prescribed force; the rows are `g_i = u₃(x_i) + φ(x_i) − U ≥ 0`, there is no extra unknown
/// and no load, and the contact force Σλ_i is an output.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
pub struct RigidPunchDisplacement {
    /// The prescribed vertical displacement U of the punch (finite; positive moves it up into
    /// the body).
    pub U: f64,
    /// The candidate contact zone Γ₀.
    pub zone: Region,
    /// The gap function φ.
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

/// How U enters the rows.
#[derive(Clone, Copy, Debug)]
enum Approach {
    /// U is the extra unknown V₀ (force control).
    Unknown,
    /// U is given.
    Prescribed(f64),
}

/// The code common to both punches: a zone, a gap shape, how U enters, and the tangential
/// fields.
#[derive(Clone, Copy, Debug)]
struct Punch<'a> {
    zone: &'a Region,
    gap: &'a dyn GapShape,
    approach: Approach,
    friction: PunchFriction<'a>,
}

impl Punch<'_> {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        self.zone.validate(&join(path, "zone"))?;
        validate_gap(self.gap, path)?;
        self.friction.tangential.validate(path, "the punch")
    }

    /// U for the extras `extras`.
    fn u(&self, extras: &[f64]) -> f64 {
        match self.approach {
            Approach::Unknown => extras[0],
            Approach::Prescribed(u) => u,
        }
    }

    /// φ at mesh node `n`.
    fn phi(&self, mesh: &TetMesh, n: usize) -> f64 {
        let x = mesh.nodes[n];
        self.gap.phi(x[0], x[1])
    }

    /// g_i = u₃(x_i) + φ(x_i) − U ≥ 0 at the contact nodes of the zone (theory §3), for validated
    /// parameters.
    fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError> {
        let zone = candidate_nodes(self.zone, mesh, dofs, path)?;
        let (n_extras, extras, shift) = match self.approach {
            Approach::Unknown => (1, &[-1.0][..], 0.0),
            Approach::Prescribed(u) => (0, &[][..], u),
        };
        let f = self.friction;
        let mut rows = ConstraintRows::new(n_extras + f.n_across());
        let normal_extras = f.normal_entries(extras);
        let weights = f.weights(mesh, &zone.nodes);
        let (mut h, mut without_plane) = (Vec::with_capacity(n_extras + 2), 0);
        for (a, &n) in zone.nodes.iter().enumerate() {
            let d = dofs.free(n, 2).expect("candidate nodes have a free u₃");
            let row = rows.n_rows();
            rows.push(&[(d, 1.0)], &normal_extras, self.phi(mesh, n) - shift, n);
            if f.is_on() && !f.push(&mut rows, dofs, n, row, weights[a], &mut h) {
                without_plane += 1;
            }
        }
        rows.warnings = zone.warnings;
        f.finish(&mut rows, without_plane, path)?;
        Ok(rows)
    }

    /// g_i = u₃(x_i) + φ(x_i) − U from the node coordinates, independently of the rows' numbers.
    fn gap(&self, mesh: &TetMesh, dofs: &DofMap, rows: &ConstraintRows, u: &[f64], extras: &[f64], out: &mut [f64]) {
        let big_u = self.u(extras);
        for (g, &n) in out.iter_mut().zip(&rows.node) {
            let u3 = dofs.free(n, 2).map_or(0.0, |d| u[d]);
            *g = u3 + self.phi(mesh, n) - big_u;
        }
        self.friction.slips(dofs, rows, u, self.across_extras(extras), out);
    }

    /// The extras (Ux, Uy) after U's (none when U is prescribed).
    fn across_extras<'e>(&self, extras: &'e [f64]) -> &'e [f64] {
        match self.approach {
            Approach::Unknown => &extras[1..],
            Approach::Prescribed(_) => extras,
        }
    }

    /// U, the force Σλ_i, the contact set, its radius about the punch's centre and a warning
    /// when the contact set reaches the rim of the zone.
    fn report(&self, mesh: &TetMesh, rows: &ConstraintRows, extras: &[f64], lambda: &[f64]) -> ContactReport {
        debug_assert_eq!(lambda.len(), rows.n_rows());
        let contact = normal_contact_set(rows, lambda);
        let normal = self.friction.normal_mask(rows);
        let [c1, c2] = self.gap.center();
        let contact_radius = contact
            .iter()
            .map(|&i| {
                let x = mesh.nodes[rows.node[i]];
                (x[0] - c1).hypot(x[1] - c2)
            })
            .fold(0.0, f64::max);
        let rim = rim_rows(mesh, rows, &contact);
        // contact pressures: each row's force over its share of the contact face
        let area = row_areas(mesh, rows);
        let force: f64 = lambda.iter().zip(&normal).filter(|x| *x.1).map(|x| x.0).sum();
        // (rows without area — P2 vertices, ∫N = 0 — carry no pressure of their own)
        let peak = contact.iter().filter(|&&i| area[i] > 0.0).map(|&i| lambda[i] / area[i]).fold(0.0, f64::max);
        let contact_area: f64 = contact.iter().map(|&i| area[i]).sum();
        let mean = if contact_area > 0.0 { force / contact_area } else { 0.0 };
        // the pressure concentration at the rim: mean pressure of the rim rows over the mean
        let rim_area: f64 = rim.iter().map(|&i| area[i]).sum();
        let rim_force: f64 = rim.iter().map(|&i| lambda[i]).sum();
        let rim_ratio = if rim_area > 0.0 && mean > 0.0 { rim_force / rim_area / mean } else { 0.0 };
        let warnings =
            if self.gap.has_edge() { None } else { rim_warning("obstacle", mesh, rows, &rim) }.into_iter().collect();
        let mut quantities = vec![
            ("U".into(), self.u(extras)),
            ("force".into(), force),
            ("peak_pressure".into(), peak),
            ("mean_pressure".into(), mean),
            ("contact_area".into(), contact_area),
            ("rim_pressure_ratio".into(), rim_ratio),
        ];
        quantities.extend(self.friction.quantities(rows, lambda, self.across_extras(extras)));
        ContactReport { quantities, contact_nodes: contact.len(), contact_radius, warnings }
    }
}

impl RigidPunch {
    /// A punch pushed by `force` against the nodes of `zone`, validated (errors name
    /// `obstacle.F`, `obstacle.zone`, `obstacle.gap`).
    pub fn new(force: f64, zone: Region, gap: Box<dyn GapShape>) -> Result<Self, ParameterError> {
        let k = Self { F: force, zone, gap, friction: None, Q: None, W: None };
        k.validate("obstacle")?;
        Ok(k)
    }

    /// The same punch with the friction law `law` (theory §8.3).
    pub fn with_friction(self, law: Box<dyn FrictionLaw>) -> Self {
        Self { friction: Some(law), ..self }
    }

    fn punch(&self) -> Punch<'_> {
        let friction = PunchFriction::new(Tangential::new(&self.friction, self.Q, self.W), 1);
        Punch { zone: &self.zone, gap: self.gap.as_ref(), approach: Approach::Unknown, friction }
    }

    /// The punch with F, Q and W each multiplied by its factor (theory §11.2).
    fn with_load_factors(&self, factors: &LoadFactors) -> Self {
        let (q, w) = Tangential::new(&self.friction, self.Q, self.W).scaled(factors);
        Self { F: self.F * factors.of("F"), Q: q, W: w, ..self.clone() }
    }
}

impl RigidPunchDisplacement {
    /// A punch moved by `u` against the nodes of `zone`, validated (errors name `obstacle.U`,
    /// `obstacle.zone`, `obstacle.gap`).
    pub fn new(u: f64, zone: Region, gap: Box<dyn GapShape>) -> Result<Self, ParameterError> {
        let k = Self { U: u, zone, gap, friction: None, Q: None, W: None };
        k.validate("obstacle")?;
        Ok(k)
    }

    /// The same punch with the friction law `law` (theory §8.3).
    pub fn with_friction(self, law: Box<dyn FrictionLaw>) -> Self {
        Self { friction: Some(law), ..self }
    }

    fn punch(&self) -> Punch<'_> {
        let friction = PunchFriction::new(Tangential::new(&self.friction, self.Q, self.W), 0);
        Punch { zone: &self.zone, gap: self.gap.as_ref(), approach: Approach::Prescribed(self.U), friction }
    }

    /// The punch with U, Q and W each multiplied by its factor (theory §11.2).
    fn with_load_factors(&self, factors: &LoadFactors) -> Self {
        let (q, w) = Tangential::new(&self.friction, self.Q, self.W).scaled(factors);
        Self { U: self.U * factors.of("U"), Q: q, W: w, ..self.clone() }
    }
}

#[typetag::serde(name = "rigid_punch")]
impl AdmissibleDisplacements for RigidPunch {
    /// F × factor (and Q or W × factor).
    fn scaled_load(&self, factor: f64) -> Option<Box<dyn AdmissibleDisplacements>> {
        self.scaled_loads(&LoadFactors::uniform(factor))
    }

    /// With `Q` or `W`: `F` and that one, each with factors of its own (theory §11.2); else
    /// none (the whole load follows the path's factor).
    fn load_names(&self) -> Vec<String> {
        self.punch().friction.load_names("F")
    }

    /// F, Q and W each multiplied by its own factor.
    fn scaled_loads(&self, factors: &LoadFactors) -> Option<Box<dyn AdmissibleDisplacements>> {
        Some(Box::new(self.with_load_factors(factors)))
    }

    /// F finite and ≥ 0 (`{path}.F`; 0: no load, U undetermined), at most
    /// [`check::MAX_MAGNITUDE`] (a force enters the solvers' products with the moduli and
    /// lengths), the zone and the gap shape.
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::non_negative(path, "F", self.F)?;
        check::bounded(path, "F", self.F)?;
        self.punch().validate(path)
    }

    /// The punch's displacement U; then `Ux`, `Uy` under a tangential force Q.
    fn extra_names(&self) -> Vec<String> {
        let mut names = vec!["U".to_string()];
        names.extend(self.punch().friction.tangential.extra_names());
        names
    }

    /// F·V (theory §1, (1.11)); then Qx Ux + Qy Uy under Q.
    fn load(&self) -> Vec<f64> {
        let mut f = vec![self.F];
        f.extend(self.punch().friction.tangential.load());
        f
    }

    /// g_i = u₃(x_i) + φ(x_i) − U ≥ 0: G = e₃ at the node, H = −1, c = φ(x_i) (theory §3); with
    /// friction each followed by the node's tangential rows (module docs).
    fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError> {
        self.punch().discretise(mesh, dofs, path)
    }

    /// The rows do not depend on F nor Q: the same rows; with W prescribed the tangential rows'
    /// offsets −W·t do: discretised again.
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
        self.punch().gap(mesh, dofs, rows, u, extras, out)
    }

    /// `U` = `extras[0]`, `force` = Σλ_i (= F at a solution).
    fn report(&self, mesh: &TetMesh, rows: &ConstraintRows, extras: &[f64], lambda: &[f64]) -> ContactReport {
        self.punch().report(mesh, rows, extras, lambda)
    }
}

#[typetag::serde(name = "rigid_punch_displacement")]
impl AdmissibleDisplacements for RigidPunchDisplacement {
    /// U × factor (and Q or W × factor).
    fn scaled_load(&self, factor: f64) -> Option<Box<dyn AdmissibleDisplacements>> {
        self.scaled_loads(&LoadFactors::uniform(factor))
    }

    /// With `Q` or `W`: `U` and that one, each with factors of its own (theory §11.2); else
    /// none (the whole load follows the path's factor).
    fn load_names(&self) -> Vec<String> {
        self.punch().friction.load_names("U")
    }

    /// U, Q and W each multiplied by its own factor.
    fn scaled_loads(&self, factors: &LoadFactors) -> Option<Box<dyn AdmissibleDisplacements>> {
        Some(Box::new(self.with_load_factors(factors)))
    }

    /// U finite with |U| ≤ [`check::MAX_MAGNITUDE`] (`{path}.U`), the zone and the gap shape.
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::bounded(path, "U", self.U)?;
        self.punch().validate(path)
    }

    /// None; `Ux`, `Uy` under a tangential force Q.
    fn extra_names(&self) -> Vec<String> {
        self.punch().friction.tangential.extra_names().collect()
    }

    /// None; Qx Ux + Qy Uy under Q.
    fn load(&self) -> Vec<f64> {
        self.punch().friction.tangential.load().collect()
    }

    /// g_i = u₃(x_i) + φ(x_i) − U ≥ 0 with U given: G = e₃ at the node, c = φ(x_i) − U.
    fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError> {
        self.punch().discretise(mesh, dofs, path)
    }

    /// The same rows with the offsets c_i = φ(x_i) − U of the scaled U; with friction the
    /// punch discretised again at the scaled loads.
    fn rows_at_factor<'r>(
        &self,
        factor: f64,
        rows: &'r ConstraintRows,
        mesh: &TetMesh,
        dofs: &DofMap,
        path: &str,
    ) -> Result<Cow<'r, ConstraintRows>, SceneError> {
        if rows.has_friction() {
            let scaled = self.with_load_factors(&LoadFactors::uniform(factor));
            return scaled.discretise(mesh, dofs, path).map(Cow::Owned);
        }
        let u = self.U * factor;
        let mut rows = rows.clone();
        for (c, &n) in rows.offset.iter_mut().zip(&rows.node) {
            *c = self.punch().phi(mesh, n) - u;
        }
        Ok(Cow::Owned(rows))
    }

    fn gap(&self, mesh: &TetMesh, dofs: &DofMap, rows: &ConstraintRows, u: &[f64], extras: &[f64], out: &mut [f64]) {
        self.punch().gap(mesh, dofs, rows, u, extras, out)
    }

    /// `U` (prescribed), `force` = Σλ_i.
    fn report(&self, mesh: &TetMesh, rows: &ConstraintRows, extras: &[f64], lambda: &[f64]) -> ContactReport {
        self.punch().report(mesh, rows, extras, lambda)
    }
}

/// The tangential rows of a punch whose axis is e₃ (theory §8.3; module docs): the rigid punch,
/// the displacement-controlled one and the tilting punch, whose normal extras (U, the slopes)
/// come first, `n_normal` of them, and do not move the face across its axis.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PunchFriction<'a> {
    /// The fields `friction`, `Q`, `W`.
    pub tangential: Tangential<'a>,
    /// The number of the normal motion's extras, before `Ux`, `Uy`.
    n_normal: usize,
}

/// The punch's axis e₃: its rows' normal.
const E3: [f64; 3] = [0.0, 0.0, 1.0];

impl<'a> PunchFriction<'a> {
    /// The tangential fields `tangential` of a punch with `n_normal` extras of its own.
    pub fn new(tangential: Tangential<'a>, n_normal: usize) -> Self {
        Self { tangential, n_normal }
    }

    /// True with a friction law.
    pub fn is_on(&self) -> bool {
        self.tangential.friction.is_some()
    }

    /// (e₁, e₂) = (x₁, x₂): the axes across e₃, and every node's tangent frame.
    fn axes(&self) -> ([f64; 3], [f64; 3]) {
        tangential_axes(E3)
    }

    /// The number of extras `Ux`, `Uy` (2 under Q, else 0).
    pub fn n_across(&self) -> usize {
        self.tangential.extra_names().count()
    }

    /// The loads a path may give factors of their own: `normal` (the punch's own, `F` or `U`)
    /// and `Q` or `W`, when one of these is given; none otherwise.
    pub fn load_names(&self, normal: &str) -> Vec<String> {
        let across: Vec<String> = self.tangential.load_names().collect();
        if across.is_empty() {
            return across;
        }
        std::iter::once(normal.to_string()).chain(across).collect()
    }

    /// A normal row's H: `normal` (U's and the slopes' entries), then 0, 0 for (Ux, Uy).
    pub fn normal_entries(&self, normal: &[f64]) -> Vec<f64> {
        let mut h = normal.to_vec();
        self.tangential.extra_entries(E3, self.axes(), &mut h);
        h
    }

    /// The nodes' weights, their shares of the facets below the body (none without friction).
    pub fn weights(&self, mesh: &TetMesh, nodes: &[usize]) -> Vec<f64> {
        if self.is_on() { node_areas_below(mesh, nodes) } else { Vec::new() }
    }

    /// Appends node `n`'s tangential rows `(u₁, u₂)(x_n) − W` after its normal row `normal`:
    /// H = 0 on the normal extras, −1 on its own of Ux, Uy; false when u₁ or u₂ is fixed.
    pub fn push(
        &self,
        rows: &mut ConstraintRows,
        dofs: &DofMap,
        n: usize,
        normal: usize,
        weight: f64,
        h: &mut Vec<f64>,
    ) -> bool {
        let axes = self.axes();
        let pair = TangentialPair { node: n, frame: frame(axes, E3), normal, weight };
        let entries = |t: [f64; 3], h: &mut Vec<f64>| {
            h.clear();
            h.extend(std::iter::repeat_n(0.0, self.n_normal));
            self.tangential.extra_entries(t, axes, h);
        };
        push_tangential(rows, dofs, pair, self.tangential.prescribed(axes), entries, h)
    }

    /// The law registered on `rows` and the nodes without tangential rows warned about
    /// ([`finish_friction`]); nothing without friction.
    pub fn finish(&self, rows: &mut ConstraintRows, without_plane: usize, path: &str) -> Result<(), SceneError> {
        match self.tangential.friction {
            Some(law) => finish_friction(rows, law, without_plane, path),
            None => Ok(()),
        }
    }

    /// The tangential rows' values from the geometry: the slips `t_k·(u − W)` with the motion W
    /// across the axis (prescribed, or the extras `across` = (Ux, Uy)).
    pub fn slips(&self, dofs: &DofMap, rows: &ConstraintRows, u: &[f64], across: &[f64], out: &mut [f64]) {
        let axes = self.axes();
        let w = self.tangential.across(axes, across);
        let (t1, t2) = frame(axes, E3);
        for b in &rows.friction.blocks {
            let n = rows.node[b.normal];
            let y: [f64; 3] = std::array::from_fn(|c| dofs.free(n, c).map_or(0.0, |j| u[j]) - w[c]);
            out[b.tangent] = dot(t1, y);
            out[b.tangent + 1] = dot(t2, y);
        }
    }

    /// True at the normal rows of `rows` (every row without friction).
    pub fn normal_mask(&self, rows: &ConstraintRows) -> Vec<bool> {
        rows.friction.tangential_mask(rows.n_rows()).into_iter().map(|t| !t).collect()
    }

    /// The report's friction quantities ([`friction_quantities`]; none without friction).
    pub fn quantities(&self, rows: &ConstraintRows, lambda: &[f64], across: &[f64]) -> Vec<(String, f64)> {
        if !self.is_on() {
            return Vec::new();
        }
        let axes = self.axes();
        let directions = row_directions(rows, axes, |_| E3);
        friction_quantities(rows, lambda, &directions, axes, self.tangential.across(axes, across))
    }
}
