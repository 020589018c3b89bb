//! Which solvers run friction (theory §8.3): uzawa (the projection onto the discs,
//! [`crate::friction_qp`]), socp (second-order cones), newton (the semismooth Newton of
//! [`crate::newton_friction`]) and penalty (the regularised law of `penalty/friction.rs`) run
//! Tresca's and Coulomb's laws on one process; newton and penalty refuse rows with friction on
//! a distributed problem by name, rather than treat tangential rows as unilateral ones.

use saddle_core::{ConstraintRows, SolveError};

/// An error naming `solver` and the first friction law of `rows`, if `rows` have friction.
pub fn refuse_friction(rows: &ConstraintRows, solver: &str) -> Result<(), SolveError> {
    let Some(law) = rows.friction.laws.first() else { return Ok(()) };
    Err(SolveError::Unsupported {
        solver: solver.into(),
        message: format!(
            "does not run friction laws here (the obstacle's friction = {{ type = {:?} }}, theory §8.3): run it on one \
             process, or use uzawa or socp",
            law.name()
        ),
    })
}
