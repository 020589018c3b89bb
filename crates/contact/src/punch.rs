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

use crate::gap::{GapShape, validate_gap};
use crate::zone::{candidate_nodes, rim_rows, rim_warning, row_areas};
use saddle_core::error::{check, join};
use saddle_core::{
    AdmissibleDisplacements, ConstraintRows, ContactReport, DofMap, ParameterError, Region, SceneError, TetMesh,
    contact_set,
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
}

/// How U enters the rows.
#[derive(Clone, Copy, Debug)]
enum Approach {
    /// U is the extra unknown V₀ (force control).
    Unknown,
    /// U is given.
    Prescribed(f64),
}

/// The code common to both punches: a zone, a gap shape and how U enters.
#[derive(Clone, Copy, Debug)]
struct Punch<'a> {
    zone: &'a Region,
    gap: &'a dyn GapShape,
    approach: Approach,
}

impl Punch<'_> {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        self.zone.validate(&join(path, "zone"))?;
        validate_gap(self.gap, path)
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
        let mut rows = ConstraintRows::new(n_extras);
        for &n in &zone.nodes {
            let d = dofs.free(n, 2).expect("candidate nodes have a free u₃");
            rows.push(&[(d, 1.0)], extras, self.phi(mesh, n) - shift, n);
        }
        rows.warnings = zone.warnings;
        Ok(rows)
    }

    /// g_i = u₃(x_i) + φ(x_i) − U from the node coordinates, independently of the rows' numbers.
    fn gap(&self, mesh: &TetMesh, dofs: &DofMap, rows: &ConstraintRows, u: &[f64], extras: &[f64], out: &mut [f64]) {
        let big_u = self.u(extras);
        for (g, &n) in out.iter_mut().zip(&rows.node) {
            let u3 = dofs.free(n, 2).map_or(0.0, |d| u[d]);
            *g = u3 + self.phi(mesh, n) - big_u;
        }
    }

    /// U, the force Σλ_i, the contact set, its radius about the punch's centre and a warning
    /// when the contact set reaches the rim of the zone.
    fn report(&self, mesh: &TetMesh, rows: &ConstraintRows, extras: &[f64], lambda: &[f64]) -> ContactReport {
        debug_assert_eq!(lambda.len(), rows.n_rows());
        let contact = contact_set(lambda);
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
        let force: f64 = lambda.iter().sum();
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
        ContactReport {
            quantities: vec![
                ("U".into(), self.u(extras)),
                ("force".into(), force),
                ("peak_pressure".into(), peak),
                ("mean_pressure".into(), mean),
                ("contact_area".into(), contact_area),
                ("rim_pressure_ratio".into(), rim_ratio),
            ],
            contact_nodes: contact.len(),
            contact_radius,
            warnings,
        }
    }
}

impl RigidPunch {
    /// A punch pushed by `force` against the nodes of `zone`, validated (errors name
    /// `obstacle.F`, `obstacle.zone`, `obstacle.gap`).
    pub fn new(force: f64, zone: Region, gap: Box<dyn GapShape>) -> Result<Self, ParameterError> {
        let k = Self { F: force, zone, gap };
        k.validate("obstacle")?;
        Ok(k)
    }

    fn punch(&self) -> Punch<'_> {
        Punch { zone: &self.zone, gap: self.gap.as_ref(), approach: Approach::Unknown }
    }
}

impl RigidPunchDisplacement {
    /// A punch moved by `u` against the nodes of `zone`, validated (errors name `obstacle.U`,
    /// `obstacle.zone`, `obstacle.gap`).
    pub fn new(u: f64, zone: Region, gap: Box<dyn GapShape>) -> Result<Self, ParameterError> {
        let k = Self { U: u, zone, gap };
        k.validate("obstacle")?;
        Ok(k)
    }

    fn punch(&self) -> Punch<'_> {
        Punch { zone: &self.zone, gap: self.gap.as_ref(), approach: Approach::Prescribed(self.U) }
    }
}

#[typetag::serde(name = "rigid_punch")]
impl AdmissibleDisplacements for RigidPunch {
    /// F × factor.
    fn scaled_load(&self, factor: f64) -> Option<Box<dyn AdmissibleDisplacements>> {
        Some(Box::new(Self { F: self.F * factor, ..self.clone() }))
    }

    /// F finite and ≥ 0 (`{path}.F`; 0: no load, U undetermined), at most
    /// [`check::MAX_MAGNITUDE`] (a force enters the solvers' products with the moduli and
    /// lengths), the zone and the gap shape.
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::non_negative(path, "F", self.F)?;
        check::bounded(path, "F", self.F)?;
        self.punch().validate(path)
    }

    /// The punch's displacement U.
    fn extra_names(&self) -> Vec<String> {
        vec!["U".into()]
    }

    /// F·V (theory §1, (1.11)).
    fn load(&self) -> Vec<f64> {
        vec![self.F]
    }

    /// g_i = u₃(x_i) + φ(x_i) − U ≥ 0: G = e₃ at the node, H = −1, c = φ(x_i) (theory §3).
    fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError> {
        self.punch().discretise(mesh, dofs, path)
    }

    /// The rows do not depend on F: the same rows.
    fn rows_at_factor<'r>(
        &self,
        _factor: f64,
        rows: &'r ConstraintRows,
        _mesh: &TetMesh,
        _dofs: &DofMap,
        _path: &str,
    ) -> Result<Cow<'r, ConstraintRows>, SceneError> {
        Ok(Cow::Borrowed(rows))
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
    /// U × factor.
    fn scaled_load(&self, factor: f64) -> Option<Box<dyn AdmissibleDisplacements>> {
        Some(Box::new(Self { U: self.U * factor, ..self.clone() }))
    }

    /// U finite with |U| ≤ [`check::MAX_MAGNITUDE`] (`{path}.U`), the zone and the gap shape.
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::bounded(path, "U", self.U)?;
        self.punch().validate(path)
    }

    fn extra_names(&self) -> Vec<String> {
        vec![]
    }

    fn load(&self) -> Vec<f64> {
        vec![]
    }

    /// g_i = u₃(x_i) + φ(x_i) − U ≥ 0 with U given: G = e₃ at the node, c = φ(x_i) − U.
    fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError> {
        self.punch().discretise(mesh, dofs, path)
    }

    /// The same rows with the offsets c_i = φ(x_i) − U of the scaled U.
    fn rows_at_factor<'r>(
        &self,
        factor: f64,
        rows: &'r ConstraintRows,
        mesh: &TetMesh,
        _dofs: &DofMap,
        _path: &str,
    ) -> Result<Cow<'r, ConstraintRows>, SceneError> {
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
