//! Discretisations of L: [`p1p0`] (continuous P1 displacements on tetrahedra, P0 stresses;
//! theory §3), and [`loads`], tractions and body forces turned into consistent nodal forces.

pub mod loads;
pub mod p1p0;

use crate::mesh::TetMesh;
use crate::problem::displacements::AdmissibleDisplacements;
use crate::problem::lagrangian::Lagrangian;
use crate::problem::obstacles::{ObstacleReport, Obstacles};

/// A discretisation of L on a tetrahedral mesh: L itself, and what reports and output files
/// need besides it — the mesh, nodal vectors of dof values, the obstacles, set-up warnings.
/// Output is written through this trait, so it knows no particular element.
pub trait Discretisation: Lagrangian {
    /// The mesh.
    fn mesh(&self) -> &TetMesh;
    /// Nodal vectors of a field of free-dof values (displacements, nodal forces), fixed
    /// components zero.
    fn nodal_vectors(&self, u: &[f64]) -> Vec<[f64; 3]>;
    /// K = K₁ ∩ K₂ ∩ … (theory §8): none, one or several obstacles.
    fn obstacles(&self) -> &Obstacles;
    /// The only obstacle when there is exactly one; None without obstacle **and with several**
    /// (use [`Discretisation::obstacles`] and [`Discretisation::contact_reports`] then).
    fn obstacle(&self) -> Option<&dyn AdmissibleDisplacements> {
        self.obstacles().only()
    }
    /// The names of the extra unknowns, in the order of the solution's extras: each obstacle's
    /// names, prefixed `name.` when it is named (`left.U`).
    fn extra_names(&self) -> Vec<String> {
        self.obstacles().extra_names()
    }
    /// Each obstacle's report on its own rows, extras and multipliers (`extras` and `lambda` are
    /// the concatenated vectors of a solution).
    fn contact_reports(&self, extras: &[f64], lambda: &[f64]) -> Vec<ObstacleReport>;
    /// Warnings about the set-up (P's parameters, nodes dropped from K_h).
    fn warnings(&self) -> Vec<String>;
}
