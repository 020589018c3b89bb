//! Discretisations of L: [`p1p0`] (continuous P1 displacements on tetrahedra, P0 stresses;
//! theory §3), [`p2`] (P2 displacements on 10-node tetrahedra with the mean-dilatation B̄,
//! stresses at four points per element; theory §10), and [`loads`], tractions and body forces
//! turned into consistent nodal forces.

/// The accessors of [`Lagrangian`] (`lagrangian`) or of [`Discretisation`] (`discretisation`)
/// that read an element's [`topology::NodalParts`] in its field `parts`: one definition for
/// every nodal element.
macro_rules! nodal_parts_accessors {
    (lagrangian) => {
        fn n_dofs(&self) -> usize {
            self.parts.dofs.n_free
        }
        fn rigid_body_modes(&self) -> Option<RigidBodyModes> {
            Some(self.parts.rigid_body_modes())
        }
        fn elasticity(&self) -> &Elasticity {
            &self.parts.law
        }
        fn stresses(&self) -> Option<&dyn AdmissibleStresses> {
            self.parts.stresses.as_deref()
        }
        fn constraints(&self) -> &ConstraintRows {
            self.parts.obstacles.rows()
        }
        fn load(&self) -> &[f64] {
            self.parts.obstacles.load()
        }
        fn nodal_load(&self) -> &[f64] {
            &self.parts.nodal_load
        }
        fn pattern(&self) -> &SymmetricPattern {
            &self.parts.pattern
        }
    };
    (discretisation) => {
        fn mesh(&self) -> &TetMesh {
            &self.parts.mesh
        }
        fn dofs(&self) -> &DofMap {
            &self.parts.dofs
        }
        fn discrete_obstacles(&self) -> &DiscreteObstacles {
            &self.parts.obstacles
        }
    };
}

pub mod loads;
pub mod p1p0;
pub mod p2;
pub mod topology;

use crate::error::{ParameterError, SceneError};
use crate::fem::loads::Load;
use crate::mesh::TetMesh;
use crate::mesh::dofs::{Dirichlet, DofMap};
use crate::problem::displacements::AdmissibleDisplacements;
use crate::problem::elasticity::Elasticity;
use crate::problem::lagrangian::Lagrangian;
use crate::problem::obstacles::{ObstacleReport, Obstacles};
use crate::problem::stresses::AdmissibleStresses;
use std::fmt::Debug;

/// The finite element of a scene, chosen by `type` in its `[discretisation]` table: `p1`
/// (P1 displacements, P0 stresses; the default) or `p2` (P2 displacements with B̄, theory §10).
/// It builds L from the parts of a problem.
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
    /// L on `mesh` (either order: each element takes the nodes it needs) with Dirichlet
    /// conditions, elasticity, P, K and the loads on u.
    fn build(
        &self,
        mesh: TetMesh,
        dirichlet: &[Dirichlet],
        law: Elasticity,
        stresses: Option<Box<dyn AdmissibleStresses>>,
        obstacles: Obstacles,
        loads: &[Load],
    ) -> Result<Box<dyn Discretisation>, SceneError>;
}

dyn_clone::clone_trait_object!(FiniteElement);

/// A discretisation of L on a tetrahedral mesh: L itself, and what reports and output files
/// need besides it — the mesh, nodal vectors of dof values, the obstacles, set-up warnings.
/// Output is written through this trait, so it knows no particular element.
pub trait Discretisation: Lagrangian + Send + Debug {
    /// The mesh.
    fn mesh(&self) -> &TetMesh;
    /// Nodal vectors of a field of free-dof values (displacements, nodal forces), fixed
    /// components zero.
    fn nodal_vectors(&self, u: &[f64]) -> Vec<[f64; 3]> {
        self.dofs().nodal(u)
    }
    /// K = K₁ ∩ K₂ ∩ … (theory §8): none, one or several obstacles.
    fn obstacles(&self) -> &Obstacles {
        self.discrete_obstacles().obstacles()
    }
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
    fn contact_reports(&self, extras: &[f64], lambda: &[f64]) -> Vec<ObstacleReport> {
        self.discrete_obstacles().reports(self.mesh(), extras, lambda)
    }
    /// Warnings about the set-up (P's parameters, nodes dropped from K_h).
    fn warnings(&self) -> Vec<String> {
        let mut w = self.stresses().map_or(vec![], |p| p.warnings());
        w.extend(self.constraints().warnings.iter().cloned());
        w
    }
    /// The numbering of the nodal dofs.
    fn dofs(&self) -> &DofMap;
    /// The obstacles discretised: concatenated rows and load, each obstacle's own rows.
    fn discrete_obstacles(&self) -> &crate::problem::obstacles::DiscreteObstacles;
    /// The `type` of the discretisation in scene files (`p1`, `p2`).
    fn name(&self) -> &'static str;
    /// Stress points per element: the points of element e are `e·k .. (e+1)·k`, k this number
    /// (1 for P0 stresses).
    fn points_per_element(&self) -> usize {
        1
    }
    /// Whether the element locks where the response is nearly incompressible (theory §10):
    /// true for P1 tetrahedra, false for P2 with B̄. Reports warn about a locked answer by it.
    fn locks(&self) -> bool {
        true
    }
}

/// A boxed discretisation (what a scene assembles) is L itself: it passes to every solver.
impl Lagrangian for Box<dyn Discretisation> {
    fn n_dofs(&self) -> usize {
        (**self).n_dofs()
    }
    fn n_points(&self) -> usize {
        (**self).n_points()
    }
    fn elasticity(&self) -> &crate::problem::elasticity::Elasticity {
        (**self).elasticity()
    }
    fn stresses(&self) -> Option<&dyn AdmissibleStresses> {
        (**self).stresses()
    }
    fn constraints(&self) -> &crate::problem::displacements::ConstraintRows {
        (**self).constraints()
    }
    fn load(&self) -> &[f64] {
        (**self).load()
    }
    fn weights(&self) -> &[f64] {
        (**self).weights()
    }
    fn strain(&self, u: &[f64], eps: &mut [crate::problem::tensor::Sym]) {
        (**self).strain(u, eps)
    }
    fn divergence(&self, sigma: &[crate::problem::tensor::Sym], f: &mut [f64]) {
        (**self).divergence(sigma, f)
    }
    fn strain_entries(&self) -> Vec<(usize, usize, usize, f64)> {
        (**self).strain_entries()
    }
    fn pattern(&self) -> &crate::problem::pattern::SymmetricPattern {
        (**self).pattern()
    }
    fn assemble(&self, material: crate::problem::lagrangian::Material<'_>, values: &mut [f64]) {
        (**self).assemble(material, values)
    }
    fn rigid_body_modes(&self) -> Option<crate::problem::lagrangian::RigidBodyModes> {
        (**self).rigid_body_modes()
    }
    fn nodal_load(&self) -> &[f64] {
        (**self).nodal_load()
    }
    fn state(&self) -> Option<&crate::problem::state::PlasticState> {
        (**self).state()
    }
    fn state_force_norm(&self) -> f64 {
        (**self).state_force_norm()
    }
}

impl Discretisation for Box<dyn Discretisation> {
    fn mesh(&self) -> &TetMesh {
        (**self).mesh()
    }
    fn dofs(&self) -> &DofMap {
        (**self).dofs()
    }
    fn discrete_obstacles(&self) -> &crate::problem::obstacles::DiscreteObstacles {
        (**self).discrete_obstacles()
    }
    fn name(&self) -> &'static str {
        (**self).name()
    }
    fn points_per_element(&self) -> usize {
        (**self).points_per_element()
    }
    fn locks(&self) -> bool {
        (**self).locks()
    }
}
