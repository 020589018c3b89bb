//! Discretisations of L: [`p1p0`] (continuous P1 displacements on tetrahedra, P0 stresses;
//! theory §3), and [`loads`], tractions and body forces turned into consistent nodal forces.

pub mod loads;
pub mod p1p0;

use crate::mesh::TetMesh;
use crate::problem::displacements::AdmissibleDisplacements;
use crate::problem::lagrangian::Lagrangian;

/// A discretisation of L on a tetrahedral mesh: L itself, and what reports and output files
/// need besides it — the mesh, nodal vectors of dof values, the obstacle, set-up warnings.
/// Output is written through this trait, so it knows no particular element.
pub trait Discretisation: Lagrangian {
    /// The mesh.
    fn mesh(&self) -> &TetMesh;
    /// Nodal vectors of a field of free-dof values (displacements, nodal forces), fixed
    /// components zero.
    fn nodal_vectors(&self, u: &[f64]) -> Vec<[f64; 3]>;
    /// K, if the problem has contact: it reports on its own rows, extras and multipliers.
    fn obstacle(&self) -> Option<&dyn AdmissibleDisplacements>;
    /// Warnings about the set-up (P's parameters, nodes dropped from K_h).
    fn warnings(&self) -> Vec<String>;
}
