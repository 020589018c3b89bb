//! `saddle report`: accuracy and cost of the solvers on a scene (theory §4, §5) and the mesh
//! convergence of the discretisation (theory §3 Theorem 2, §7).
//!
//! [`generate()`] writes into a folder:
//!
//! * `work_precision.csv`, `work_precision.png`, `work_precision.svg` — every solver along a
//!   ladder of settings ([`runs::ladder`]), each run's wall time and its errors against a tightly
//!   converged reference of the same discrete problem (Newton to 1e-13, [`runs::reference_solver`]);
//! * `convergence.csv`, `convergence.png`, `convergence.svg` — the scene on a sequence of refined
//!   box meshes ([`convergence`], [`measure::LEVELS`], or a mesh family's levels named by
//!   [`measure::ReportOptions::levels`]), each solved by the reference solver; errors against
//!   the finest level through the transfer of P0 fields ([`transfer`]), observed rates next to
//!   Theorem 2's guaranteed 1/2, a Richardson extrapolation of the quantity of interest U (the
//!   scene's first extra unknown by the name its obstacle gives it, or the quantity named by
//!   [`measure::ReportOptions::quantity`], `--quantity`). A scene whose mesh is not a
//!   `box` gets no study: `convergence.csv` holds its header only and `report.md` says why;
//! * `elements.csv`, `elements.png`, `elements.svg` — P1 against P2 ([`elements`], theory §10):
//!   the convergence study repeated with the other element on meshes with the same nodes, U of
//!   every level against one reference, wall times, and which element reaches an accuracy of U
//!   sooner;
//! * `report.md` — the tables, the observed σ̂ rate against 1/2, each solver at its tightest
//!   setting, links to the images.
//!
//! The plots need the cargo feature `report` (on by default; `figures`); without it the CSV files
//! and `report.md` are written and `report.md` says that the images were not drawn.
//!
//! The modules, each using only those above it: [`transfer`], [`pointwise`] (fields compared at
//! points, for P2: theory §15.4), [`convergence`], [`runs`]
//! (the ladder and error measures), [`elements`], [`measure`] (the runs and studies),
//! [`tables`], `figures`, [`generate`](mod@generate) (all of it into a folder).
//!
//! The parts are public so that tests can check them: the error measures ([`runs::errors`],
//! [`transfer::field_distance`]), point location ([`transfer::Locator`]), rates and Richardson
//! ([`convergence`]), the writers ([`tables`]).

pub mod convergence;
pub mod elements;
#[cfg(feature = "report")]
pub mod figures;
pub mod generate;
pub mod measure;
pub mod pointwise;
pub mod runs;
pub mod tables;
pub mod transfer;

pub use generate::generate;
pub use measure::{
    LEVELS, Progress, QUICK_LEVELS, Report, ReportError, ReportOptions, SceneSource, convergence_study,
    convergence_study_of, work_precision,
};
pub use transfer::OutsideMesh;
