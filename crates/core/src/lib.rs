//! # saddle-core
//!
//! The core of *saddle*, a framework for variational inequalities in solid mechanics. The
//! mathematics is in the repository's theory page, `docs/theory.md`; section numbers below
//! (theory §N) refer to it.
//!
//! A problem is a saddle point of a Lagrangian **L** (theory §1) over a convex set **P** of
//! admissible generalised stresses (a yield surface, §2) and a convex set **K** of admissible
//! displacements with its own extra unknowns (an obstacle, §1). The crate is arranged by
//! concern, each layer using only those above it in this list:
//!
//! | module | concern | uses |
//! |---|---|---|
//! | [`error`] | parameter and scene errors that name the field and value | — |
//! | [`linalg`] | sparse Cholesky, CSR, conjugate gradients, smoothed-aggregation multigrid: matrices and vectors only | `error` |
//! | [`mesh`] | tetrahedral meshes, their sources (box, inline, Gmsh), regions, dof numbering and Dirichlet conditions | `error` |
//! | [`problem`] | the contracts: **P** [`AdmissibleStresses`], **K** [`AdmissibleDisplacements`] (several: [`Obstacles`], theory §8), the element's operators [`ElementOperators`], **L** [`Lagrangian`] (operators and data) with its energies and KKT residuals, the [`Solver`] interface | `error`, `mesh` |
//! | [`fem`] | the elements [`P1P0Element`], [`P2Element`]; loads as nodal forces; [`DiscreteProblem`], an element with the problem's data | `error`, `mesh`, `problem` |
//! | [`estimate`] | a posteriori error estimates of a solution (theory §15): averaging recovery of the stresses, indicators per element, the extras' estimates | `mesh`, `problem`, `fem` |
//! | [`distributed`] | a problem split over ranks (theory §12): partitions, a rank's part of the mesh and dofs — plain data, no MPI | `mesh`, `problem` |
//! | [`evolution`] | load paths (theory §11): [`LoadStep`] (L at a load factor from a [`PlasticState`]), [`Evolution`] (the steps one after another) | `problem`, `fem` |
//!
//! Linear algebra knows no mesh and no mechanics (the multigrid takes its near-nullspace as
//! vectors), and the contracts name no linear-algebra type: solvers (crate `saddle-solvers`)
//! bring the two together. Scenes (TOML files) and output files live in the facade crate
//! `saddle`.

pub mod distributed;
pub mod error;
pub mod estimate;
pub mod evolution;
pub mod fem;
pub mod linalg;
pub mod mesh;
pub mod problem;

pub use error::{MeshError, ParameterError, SceneError};
pub use estimate::{ErrorEstimate, estimate};
pub use evolution::{Evolution, Increment, LoadFactors, LoadStep, PathError, StepCutting, StepSolution, step_factors};
pub use fem::loads::Load;
pub use fem::p1p0::{P1, P1P0Element};
pub use fem::p2::{P2, P2Element};
pub use fem::{DiscreteProblem, Discretisation, FiniteElement, ProblemView, VtkCell};
pub use mesh::box_mesh::{BoxMesh, Grading, Subdivision};
pub use mesh::dofs::{Component, Dirichlet, DofMap};
#[cfg(feature = "gmsh")]
pub use mesh::gmsh::{GmshImport, GmshMesh, PhysicalGroup};
pub use mesh::inline::InlineMesh;
pub use mesh::region::Region;
pub use mesh::{MeshQuality, MeshSource, TetMesh};
pub use problem::displacements::{
    AdmissibleDisplacements, ConstraintRows, ContactReport, contact_set, normal_contact_set,
};
pub use problem::elasticity::Elasticity;
pub use problem::energies::{dual_energy, energy, energy_of_strain, energy_of_stress, stress_energy};
pub use problem::fields::{Hardening, PlasticState, StressField};
pub use problem::friction::{FrictionBlock, FrictionLaw, FrictionRows};
pub use problem::kkt::{KktResiduals, kkt, kkt_with_stress};
pub use problem::lagrangian::{Data, Iterate, Lagrangian, LocalLaw, Workspace};
pub use problem::obstacles::{DiscreteObstacles, NamedObstacle, ObstacleReport, ObstacleRows, Obstacles};
pub use problem::operators::{ElementOperators, Material, PressureRows, RigidBodyModes};
pub use problem::pattern::SymmetricPattern;
pub use problem::solver::{
    Monitor, PhaseTimer, Silent, Solution, SolveError, SolveReport, Solver, Start, StopReason, one_rank,
};
pub use problem::stresses::{
    AdmissibleStresses, ConeDescription, PsdBlock, SemidefiniteDescription, SocBlock, StepInput, StepOutput,
};
pub use problem::tensor::{Sym, SymOp};
