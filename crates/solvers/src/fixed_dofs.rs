//! The AMG preconditioner of Newton's active-set systems (theory §4.2), the active (fixed)
//! coordinates split off: used by CG on the tangent ([`crate::active_set`]) and as the top block
//! of the pressure block's preconditioner ([`crate::pressure_block`]).

use crate::row_basis::RowBasis;
use saddle_core::linalg::{Preconditioner, SmoothedAggregation};
use std::sync::Mutex;

/// The AMG preconditioner with the active (fixed) coordinates split off as a diagonal block:
/// z_F = T⁻¹M⁻¹T⁻ᵀ r_F (r zero on the fixed coordinates; M the multigrid of K, TᵀKT in the
/// coordinates of the rows), z_s = r_s / d_s on a fixed coordinate s.
pub(crate) struct FixedDofs<'a> {
    pub(crate) amg: &'a SmoothedAggregation,
    pub(crate) basis: &'a RowBasis,
    /// The fixed dofs s with their diagonal entries d_s.
    pub(crate) fixed: &'a [(usize, f64)],
    pub(crate) scratch: &'a Mutex<Vec<f64>>,
}

impl Preconditioner for FixedDofs<'_> {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let mut t = self.scratch.lock().unwrap_or_else(|e| e.into_inner());
        t.copy_from_slice(r);
        for &(s, _) in self.fixed {
            t[s] = 0.0;
        }
        self.basis.force_from_coordinates(&mut t);
        self.amg.apply(&t, z);
        self.basis.displacement_to_coordinates(z);
        for &(s, d) in self.fixed {
            z[s] = r[s] / d;
        }
    }
}
