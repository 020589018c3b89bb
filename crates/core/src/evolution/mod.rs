//! Load paths: the Prandtl–Reuss evolution in load steps (theory §11).
//!
//! Backward Euler in the load turns every step into the saddle problem of theory §3 with the
//! local law shifted by the previous step's state: σ̂ = P_D(C(ε − ε_p), q_n) ([`PlasticState`],
//! [`crate::AdmissibleStresses::step_law`]). So a step is L itself with a state and the step's
//! loads ([`LoadStep`]), and every solver runs it unchanged, warm-started from the previous step
//! ([`crate::Solver::solve_warm`]). One step from the zero state is the stationary (Hencky)
//! problem.
//!
//! * [`step`] — [`LoadStep`]: L at a load factor with a state;
//! * [`reduced`] — [`Reduced`]: L without the rows and extras of obstacles that carry no load
//!   (a force-controlled obstacle at zero force leaves its extras undetermined, theory §11.3);
//! * [`path`] — [`Evolution`]: the steps of a load path one after another, the state carried;
//! * [`cutting`] — [`Increment`]: a failed step halved and retried (theory §11.5);
//! * [`secant`] — [`SecantPredictor`]: the start of a sweep's point from the points before
//!   (theory §11.2);
//! * [`LoadFactors`] (in the problem layer, `problem::load_factors`, which the obstacles read): a
//!   step's factor of every load, and of named loads their own.
//!
//! [`PlasticState`]: crate::PlasticState

pub mod cutting;
pub mod path;
pub mod reduced;
pub mod secant;
pub mod step;

pub use crate::problem::load_factors::LoadFactors;
pub use cutting::{Increment, StepCutting};
pub use path::{Evolution, PathError, StepSolution, step_factors};
pub use reduced::Reduced;
pub use secant::SecantPredictor;
pub use step::LoadStep;
