//! # saddle
//!
//! Variational inequalities in solid mechanics: a convex set **P** of admissible stresses (a
//! yield surface), a constraint set **K** of admissible displacements (an obstacle with its own
//! unknowns) and the saddle **Lagrangian L** coupling them drive interchangeable solvers. The
//! elasto-plastic contact problem of C. Johnson (1977) is one assembled configuration.
//!
//! This facade re-exports the workspace crates, runs scene files ([`run`]) and measures the
//! accuracy and cost of the solvers and the mesh convergence of a scene ([`report`]); the
//! `saddle` binary is its command line.
//!
//! ```no_run
//! use saddle::core::Silent;
//! use saddle::scene::Scene;
//! let scene = Scene::from_file("examples/johnson.toml".as_ref())?;
//! let (problem, solver) = scene.into_problem()?;
//! let solver = solver.unwrap_or_else(saddle::run::default_solver);
//! let solution = solver.solve(&problem.lagrangian(), &mut Silent)?;
//! println!("U = {:?}, KKT = {:e}", solution.extras, solution.report.kkt.max());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub use saddle_contact as contact;
pub use saddle_core as core;
pub use saddle_solvers as solvers;
pub use saddle_yield as yield_surfaces;

pub mod bench;
pub mod conformance;
pub mod locking;
pub mod outdir;
pub mod output;
pub mod path;
#[cfg(feature = "gmsh")]
pub mod peer;
pub mod report;
pub mod run;
pub mod scene;
mod scene_de;
pub mod stability;
pub mod sweep;
