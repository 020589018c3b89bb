//! The slip history of the friction rows along a load path (theory §11.6): the total slip each
//! tangential row has carried up to the last converged step, and the energy friction has
//! dissipated up to it. A step's tangential rows are the slip **increments** against that
//! state, `Δs_i = s_i(u, V) − S_i`: their offsets are lowered by S_i
//! ([`SlipHistory::shift_offsets`]), so that the law's conditions hold for the increment
//! (backward Euler on the slip rule). The zero history leaves the rows as they are: a one-step
//! scene is the total (Hencky-like) form, `Δs = s`.

use crate::problem::displacements::ConstraintRows;

/// The state of the friction rows after a converged step (theory §11.6).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SlipHistory {
    /// The total slip S_i of every row in the rows' own (unshifted) form: the tangential rows'
    /// values at the last converged step; 0 on normal rows. Empty: the zero history.
    pub slip: Vec<f64>,
    /// The energy dissipated by friction up to the last converged step, per obstacle.
    pub dissipated: Vec<f64>,
}

impl SlipHistory {
    /// Lowers the offset of every tangential row of `rows` by its carried slip S (rows `first..`
    /// of the history's numbering): the rows then give the increments Δs = s − S.
    pub fn shift_offsets(&self, rows: &mut ConstraintRows, first: usize) {
        if self.slip.is_empty() {
            return;
        }
        for b in &rows.friction.blocks {
            for t in [b.tangent, b.tangent + 1] {
                rows.offset[t] -= self.slip[first + t];
            }
        }
    }
}

/// The energy friction dissipates in a step on the rows `rows` (the step's, giving the slip
/// increments Δs in `increments`, their values at the solution): `−Σ_i λ_t,i·Δs_i` over the
/// friction blocks, ≥ 0 at a solution (−Δs_i lies in the normal cone of the disc at λ_t,i:
/// λ_t,i·Δs_i = −r_i|Δs_i| on the rim, Δs_i = 0 inside).
pub fn dissipation(rows: &ConstraintRows, lambda: &[f64], increments: &[f64]) -> f64 {
    rows.friction
        .blocks
        .iter()
        .map(|b| -(lambda[b.tangent] * increments[b.tangent] + lambda[b.tangent + 1] * increments[b.tangent + 1]))
        .sum()
}
