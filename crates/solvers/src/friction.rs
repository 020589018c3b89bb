//! Which solvers run friction (theory §8.3): uzawa (the projection onto the discs,
//! [`crate::friction_qp`]) and socp (second-order cones) run laws with a given bound (Tresca);
//! the others refuse rows with friction by name, rather than treat tangential rows as
//! unilateral ones.

use saddle_core::{ConstraintRows, SolveError};

/// An error naming `solver` and the first friction law of `rows`, if `rows` have friction.
pub fn refuse_friction(rows: &ConstraintRows, solver: &str) -> Result<(), SolveError> {
    let Some(law) = rows.friction.laws.first() else { return Ok(()) };
    Err(SolveError::Unsupported {
        solver: solver.into(),
        message: format!(
            "does not run friction laws yet (the obstacle's friction = {{ type = {:?} }}, theory §8.3): use uzawa or socp",
            law.name()
        ),
    })
}
