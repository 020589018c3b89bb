//! # saddle-core
//!
//! The core of *saddle*, a framework for variational inequalities in solid mechanics
//! (`../shared/SPEC.md` is the mathematical contract; section numbers below refer to it).
//!
//! A problem is a saddle point of a Lagrangian **L** (§1, (1.11)) over a convex set **P** of
//! admissible generalised stresses (a yield surface, §2) and a convex set **K** of admissible
//! displacements with its own extra unknowns (an obstacle, §1). The three are traits:
//!
//! * [`AdmissibleStresses`] — P: projection onto D in the energy metric, the local law with its
//!   consistent tangent, the energy ψ, membership, an optional cone description;
//! * [`AdmissibleDisplacements`] — K: extra unknowns (the punch's U), a load term (F·V), and
//!   its discretisation K_h as affine rows g(u, V) ≥ 0;
//! * [`Lagrangian`] — L: the discrete problem every [`Solver`] consumes, able to evaluate the
//!   energy J, the dual energy and the KKT residuals of any iterate.
//!
//! [`P1P0Lagrangian`] assembles L from a tetrahedral [`TetMesh`] (P1 displacements, P0
//! stresses, §3); [`Scene`] reads a whole problem from TOML, plugins chosen by `type`.

pub mod amg;
pub mod box_mesh;
pub mod csr;
pub mod displacements;
pub mod dofs;
pub mod elasticity;
pub mod error;
#[cfg(feature = "gmsh")]
pub mod gmsh;
pub mod inline_mesh;
pub mod lagrangian;
pub mod linalg;
pub mod loads;
pub mod mesh;
pub mod output;
pub mod p1p0;
pub mod pcg;
pub mod projection;
pub mod region;
pub mod scene;
pub mod solver;
pub mod stresses;
pub mod tensor;

pub use amg::{AmgParams, DofLayout, LevelInfo, SmoothedAggregation};
pub use box_mesh::{BoxMesh, Grading};
pub use csr::Csr;
pub use displacements::{AdmissibleDisplacements, ConstraintRows, ContactReport, contact_set};
pub use dofs::{Component, Dirichlet, DofMap};
pub use elasticity::Elasticity;
pub use error::{AmgError, LinalgError, MeshError, ParameterError, PcgError, SceneError};
#[cfg(feature = "gmsh")]
pub use gmsh::{GmshImport, GmshMesh, PhysicalGroup};
pub use inline_mesh::InlineMesh;
pub use lagrangian::{Iterate, KktResiduals, Lagrangian, Material, StressField, Workspace};
pub use linalg::{SparseCholesky, SymmetricPattern};
pub use loads::Load;
pub use mesh::{MeshQuality, MeshSource, TetMesh};
pub use output::{Summary, write_vtu};
pub use p1p0::P1P0Lagrangian;
pub use pcg::{Identity, Jacobi, Pcg, PcgReport, Preconditioner};
pub use region::Region;
pub use scene::Scene;
pub use solver::{Monitor, PhaseTimer, Silent, Solution, SolveError, SolveReport, Solver, StopReason};
pub use stresses::{AdmissibleStresses, ConeDescription, SocBlock};
pub use tensor::{Sym, SymOp};
