//! # saddle-contact
//!
//! Obstacles: the convex sets **K** of admissible displacements of *saddle* (theory §1, §3; the
//! trait is [`saddle_core::AdmissibleDisplacements`]).
//!
//! K is a closed convex set of displacements v together with the obstacle's own extra unknowns
//! V and a load term f·V in the Lagrangian (1.11). For the rigid punch of theory §1,
//! `K = { (v, V) ∈ W × R : v₃ + φ − V ≥ 0 on Γ₀ }`, V is the punch's displacement U and the load
//! is F·V. On a mesh, K_h is polyhedral: one affine row per contact node,
//! `g_i(u, U) = u₃(x_i) + φ(x_i) − U ≥ 0` (theory §3), returned by `discretise` as
//! [`saddle_core::ConstraintRows`] — exactly what every solver of theory §4 consumes.
//!
//! This crate provides
//!
//! * [`RigidPunch`] (`type = "rigid_punch"`, force F) and [`RigidPunchDisplacement`]
//!   (`type = "rigid_punch_displacement"`, prescribed U) in [`punch`];
//! * [`TiltingPunch`] (`type = "tilting_punch"`, force F acting at a point `at`; extras U,
//!   slope_x1, slope_x2: the punch also tilts about the gap's centre, theory §8) in
//!   [`tilting_punch`];
//! * [`RigidSphere`] (`type = "rigid_sphere"`, a ball of centre c and radius R moving along a
//!   direction d, pushed by F or moved by a prescribed V; rows along the sphere's normals, each
//!   acting on up to three dofs, theory §8) in [`rigid_sphere`];
//! * friction laws ([`Tresca`], [`Coulomb`]) in [`friction`], and in [`tangential`] what the
//!   rigid obstacles with friction share (theory §8.3): the fields `friction`, `Q`, `W`, the
//!   tangential rows and extras `Ux`, `Uy`, the stick/slip counts — the punches and the sphere
//!   take them alike;
//! * gap shapes φ, themselves plugins chosen by `type` ([`GapShape`]: [`Paraboloid`],
//!   [`EllipticParaboloid`], [`Flat`]) in [`gap`];
//! * contact-zone helpers for node-based obstacles ([`zone::candidate_nodes`],
//!   [`zone::candidate_nodes_with`], [`zone::rim_rows`], [`zone::rim_rows_facing`]) in [`zone`];
//! * the [`conformance`] kit every K plugin must pass ([`conformance::check_all`]).
//!
//! The scene table of the default scene (theory §6):
//!
//! ```toml
//! [obstacle]
//! type = "rigid_punch"
//! F = 0.3
//! zone = { all = [ { group = "zmin" }, { disc = { center = [0.0, 0.0], radius = 0.5 } } ] }
//! gap = { type = "paraboloid", R = 5.0 }
//! ```
//!
//! Plugins register themselves with `typetag` at link time: a binary that reads scenes must
//! link this crate (any use of it, or `use saddle_contact as _;`).
//!
//! ## Adding an obstacle plugin
//!
//! Write one small file: a struct with `serde` derives (`deny_unknown_fields`), an
//! `impl AdmissibleDisplacements` tagged `#[typetag::serde(name = "...")]` — the name is the
//! `type` of the scene table — and a test that runs the [`conformance`] kit on a small mesh. The
//! rows of `discretise` must be the linearisation of `gap()`, the load must match the extra
//! unknowns, the report's `force` must be the resultant −(Hᵀλ)₀ on the first extra (Σλ for a
//! punch): the kit checks all of it. A rigid wall at a prescribed distance `d` below the zone,
//! g_i = u₃(x_i) + d ≥ 0:
//!
//! ```
//! use saddle_contact::{conformance, zone};
//! use saddle_core::error::check;
//! use saddle_core::{
//!     AdmissibleDisplacements, BoxMesh, ConstraintRows, ContactReport, Dirichlet, DofMap,
//!     ParameterError, Region, SceneError, TetMesh, contact_set,
//! };
//! use serde::{Deserialize, Serialize};
//!
//! /// `type = "wall"`: u₃ ≥ −d on the zone.
//! #[derive(Clone, Debug, Serialize, Deserialize)]
//! #[serde(deny_unknown_fields)]
//! struct Wall {
//!     d: f64,
//!     zone: Region,
//! }
//!
//! #[typetag::serde(name = "wall")]
//! impl AdmissibleDisplacements for Wall {
//!     fn validate(&self, path: &str) -> Result<(), ParameterError> {
//!         check::non_negative(path, "d", self.d)?;
//!         self.zone.validate(&format!("{path}.zone"))
//!     }
//!     fn extra_names(&self) -> Vec<String> {
//!         vec![]
//!     }
//!     fn load(&self) -> Vec<f64> {
//!         vec![]
//!     }
//!     fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError> {
//!         let zone = zone::candidate_nodes(&self.zone, mesh, dofs, path)?;
//!         let mut rows = ConstraintRows::new(0);
//!         for &n in &zone.nodes {
//!             rows.push(&[(dofs.free(n, 2).unwrap(), 1.0)], &[], self.d, n);
//!         }
//!         rows.warnings = zone.warnings;
//!         Ok(rows)
//!     }
//!     fn gap(&self, _: &TetMesh, dofs: &DofMap, rows: &ConstraintRows, u: &[f64], _: &[f64], out: &mut [f64]) {
//!         for (g, &n) in out.iter_mut().zip(&rows.node) {
//!             *g = dofs.free(n, 2).map_or(0.0, |j| u[j]) + self.d;
//!         }
//!     }
//!     fn report(&self, _: &TetMesh, _: &ConstraintRows, _: &[f64], lambda: &[f64]) -> ContactReport {
//!         ContactReport {
//!             quantities: vec![("force".into(), lambda.iter().sum())],
//!             contact_nodes: contact_set(lambda).len(),
//!             ..Default::default()
//!         }
//!     }
//! }
//!
//! fn main() {
//!     // in the plugin's tests:
//!     let mesh = BoxMesh::new([0.0; 3], [1.0; 3], [4, 4, 2]).mesh().unwrap();
//!     let dofs = DofMap::new(&mesh, &[Dirichlet::clamped(Region::Group("zmax".into()))]).unwrap();
//!     let wall = Wall { d: 0.005, zone: Region::Group("zmin".into()) };
//!     conformance::check_all(&wall, &mesh, &dofs, 7, 0.01).unwrap();
//!     // and it reads from a scene
//!     let k: Box<dyn AdmissibleDisplacements> =
//!         toml::from_str("type = \"wall\"\nd = 0.005\nzone = { group = \"zmin\" }").unwrap();
//!     assert_eq!(k.discretise(&mesh, &dofs, "obstacle").unwrap().n_rows(), 25);
//! }
//! ```

pub mod conformance;
pub mod friction;
pub mod gap;
pub mod projection;
pub mod punch;
pub mod rigid_sphere;
pub mod tangential;
pub mod tilting_punch;
pub mod zone;

pub use conformance::{KitFailure, check_all};
pub use friction::{Coulomb, Tresca};
pub use gap::{EllipticParaboloid, Flat, GapShape, Paraboloid};
pub use punch::{RigidPunch, RigidPunchDisplacement};
pub use rigid_sphere::RigidSphere;
pub use tilting_punch::TiltingPunch;
pub use zone::{CandidateNodes, Selection, candidate_nodes, candidate_nodes_with};
