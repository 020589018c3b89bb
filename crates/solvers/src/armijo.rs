//! The constants of the Armijo test shared by the line searches of Newton (theory §4.2 step 4)
//! and of the penalty method (theory §4.3), apart so that neither solver depends on the other
//! for them (Newton falls back on the penalty method, theory §4.2.1).

/// The Armijo constant of the line search (theory §4.2 step 4): a step is accepted when it
/// achieves this fraction of the decrease predicted by the slope. 1e-4 is the textbook value
/// (Nocedal & Wright): it rejects only steps that barely decrease the merit function.
pub const ARMIJO: f64 = 1e-4;

/// A slope below this fraction of |J| is round-off: the line search takes the full step
/// instead of testing decreases it cannot measure.
pub const SLOPE_ROUND_OFF: f64 = 1e-13;
