//! # saddle
//!
//! Variational inequalities in solid mechanics: a convex set **P** of admissible stresses (a
//! yield surface), a constraint set **K** of admissible displacements (an obstacle with its own
//! unknowns) and the saddle **Lagrangian L** coupling them drive interchangeable solvers. The
//! elasto-plastic contact problem of C. Johnson (1977) is one assembled configuration.
//!
//! This facade re-exports the workspace crates, reads and writes files ([`io`]), runs scene
//! files ([`app`]) and measures the accuracy and cost of the solvers and the mesh convergence of
//! a scene ([`studies`]); the `saddle` binary is its command line. Its layers, each using only
//! those below it (checked by `tests/layers.rs`, with no circle among the modules):
//!
//! | layer | modules | what |
//! |---|---|---|
//! | `main.rs` | | the command line |
//! | [`studies`] | [`report`](studies::report), [`bench`](studies::bench), `peer`, [`stability`](studies::stability) | measurements |
//! | [`app`] | [`setup`](app::setup), [`run`](app::run), [`path`](app::path), [`sweep`](app::sweep), [`limit`](app::limit) | the commands on a scene |
//! | [`io`] | [`scene`](io::scene), [`summary`](io::summary), [`vtu`](io::vtu), [`outdir`](io::outdir), `plot`, [`csv`](io::csv) | files in and out |
//! | crates | [`core`], [`yield_surfaces`], [`contact`], [`solvers`] (with the solvers' conformance kit, [`solvers::conformance`]) | the framework |
//!
//! ```no_run
//! use saddle::core::Silent;
//! use saddle::io::scene::Scene;
//! let scene = Scene::from_file("examples/johnson.toml".as_ref())?;
//! let (problem, solver) = scene.into_problem()?;
//! let solver = solver.unwrap_or_else(saddle::app::setup::default_solver);
//! let solution = solver.solve(&problem.lagrangian(), &mut Silent)?;
//! println!("U = {:?}, KKT = {:e}", solution.extras, solution.report.kkt.max());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub use saddle_contact as contact;
pub use saddle_core as core;
pub use saddle_solvers as solvers;
pub use saddle_yield as yield_surfaces;

pub mod app;
pub mod io;
pub mod studies;
