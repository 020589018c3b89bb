//! Discretisations: the elements [`p1p0`] (continuous P1 displacements on tetrahedra, P0
//! stresses; theory §3) and [`p2`] (P2 displacements on 10-node tetrahedra with the
//! mean-dilatation B̄, stresses at four points per element; theory §10), what they share
//! ([`topology`]), [`loads`] (tractions and body forces turned into consistent nodal forces),
//! and the discrete problem — an element with the problem's data ([`discrete_problem`]).

pub mod discrete_problem;
pub mod dual_quadratic;
pub mod loads;
#[cfg(test)]
mod operator_checks;
pub mod p1p0;
pub mod p2;
pub mod supports;
pub mod topology;

use crate::error::{ParameterError, SceneError};
use crate::mesh::TetMesh;
use crate::mesh::dofs::{Dirichlet, DofMap};
use crate::problem::displacements::ConstraintRows;
use crate::problem::elasticity::Elasticity;
use crate::problem::operators::ElementOperators;
use std::fmt::Debug;

pub use discrete_problem::{DiscreteProblem, ProblemView};

/// The finite element of a scene, chosen by `type` in its `[discretisation]` table: `p1`
/// (P1 displacements, P0 stresses) or `p2` (P2 displacements with B̄, theory §10; a scene
/// without the table gets it).
/// It builds the element's operators on a mesh; [`DiscreteProblem`] adds the problem's data.
#[typetag::serde(tag = "type")]
pub trait FiniteElement: Debug + Send + Sync + dyn_clone::DynClone {
    /// The `type` name in scene files.
    fn name(&self) -> &'static str {
        self.typetag_name()
    }
    /// Checks the parameters; `path` is the table's path (`discretisation`).
    fn validate(&self, _path: &str) -> Result<(), ParameterError> {
        Ok(())
    }
    /// The mesh of the order the element needs (P1 drops a second-order mesh's edge nodes, P2
    /// adds them to a first-order one).
    fn prepare_mesh(&self, mesh: TetMesh) -> TetMesh;
    /// The element on a mesh of its order ([`FiniteElement::prepare_mesh`]) with the dof
    /// numbering `dofs`.
    fn build_with_dofs(&self, mesh: TetMesh, dofs: DofMap) -> Box<dyn Discretisation>;
    /// The element on `mesh` (either order: each element takes the nodes it needs) with the
    /// Dirichlet conditions `dirichlet`.
    fn build(&self, mesh: TetMesh, dirichlet: &[Dirichlet]) -> Result<Box<dyn Discretisation>, SceneError> {
        let mesh = self.prepare_mesh(mesh);
        let dofs = DofMap::with_values(&mesh, dirichlet)?;
        Ok(self.build_with_dofs(mesh, dofs))
    }
    /// Whether the element's contact rows are the obstacles' nodal rows recombined
    /// ([`Discretisation::contact_rows`]; false, the default: the nodal rows themselves).
    fn recombines_contact_rows(&self) -> bool {
        false
    }
}

dyn_clone::clone_trait_object!(FiniteElement);

/// A VTK cell type, by its VTK number and node count (the node order is VTK's).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VtkCell {
    /// The VTK cell type number (10: tetrahedron, 24: quadratic tetrahedron).
    pub type_id: u8,
    /// Nodes per cell.
    pub nodes: usize,
}

/// A discretisation on a tetrahedral mesh: the element's operators, and what output needs
/// besides them — the mesh, the dof numbering, nodal vectors of dof values, the VTK cell the
/// element writes. Output is written through this trait, so it knows no particular element. A
/// new element implements [`ElementOperators`] and this trait (README, "Adding an element").
pub trait Discretisation: ElementOperators {
    /// The mesh.
    fn mesh(&self) -> &TetMesh;
    /// The numbering of the nodal dofs.
    fn dofs(&self) -> &DofMap;
    /// The `type` of the discretisation in scene files (`p1`, `p2`).
    fn name(&self) -> &'static str;
    /// The VTK cell of the element's output: one cell per element of [`Discretisation::mesh`],
    /// its nodes as [`TetMesh::element_nodes`] lists them (vertices, then the edge nodes in
    /// VTK's order on a second-order mesh).
    fn vtk_cell(&self) -> VtkCell;
    /// Nodal vectors of a field of free-dof values (displacements, nodal forces), fixed
    /// components zero.
    fn nodal_vectors(&self, u: &[f64]) -> Vec<[f64; 3]> {
        self.dofs().nodal(u)
    }
    /// Stress points per element: the points of element e are `e·k .. (e+1)·k`, k this number
    /// (1 for P0 stresses).
    fn points_per_element(&self) -> usize {
        1
    }
    /// The barycentric coordinates of an element's stress points, in their order (the same in
    /// every element; theory §15): the centroid for one point per element.
    fn point_barycentrics(&self) -> Vec<[f64; 4]> {
        vec![[0.25; 4]; self.points_per_element()]
    }
    /// The polynomial degree of the displacements (1 for P1, 2 for P2): what a convergence
    /// study expects of its observed orders (theory §7.3).
    fn degree(&self) -> usize {
        1
    }
    /// Whether the element locks where the response is nearly incompressible (theory §10):
    /// true for P1 tetrahedra, false for P2 with B̄. Reports warn about a locked answer by it.
    fn locks(&self) -> bool {
        true
    }
    /// The same element on the same mesh with every dof free: its B reaches the fixed dofs,
    /// for the strain of a lifting and the reactions of the supports (theory §14). `None` (the
    /// default) for a rank's part of a distributed problem.
    fn unconstrained(&self) -> Option<Box<dyn Discretisation>> {
        None
    }
    /// (a − a_h)(u, u) for the displacement `u`: the elastic energy ∫ ε(u):Cε(u) of the exact
    /// strain minus that of the element's strain operator, ∫ (Bu):C(Bu) (theory §15.2: the
    /// compliance identity of the goal estimate carries it for an element whose B is not ε).
    /// Zero, the default, for an element whose B is the strain of its displacements.
    fn strain_consistency_energy(&self, _law: &Elasticity, _u: &[f64]) -> f64 {
        0.0
    }
    /// The element's contact rows of an obstacle's nodal rows `nodal`: the nodal rows (the
    /// default), or rows recombined from them (P2's dual quadratic rows, theory §10.1). An error
    /// says why the rows cannot be recombined.
    fn contact_rows(&self, nodal: ConstraintRows) -> Result<ConstraintRows, String> {
        Ok(nodal)
    }
}
