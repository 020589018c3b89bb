//! A posteriori error estimates of a solution (theory §15): the energy-norm estimate of the
//! stress error by averaging recovery (Zienkiewicz–Zhu), its per-element indicators, and
//! goal-oriented estimates of the extra unknowns from the compliance identity.
//!
//! * [`quadrature`] — the rule the indicators are integrated with;
//! * [`recovery`] — the recovered (averaged, continuous) generalised stresses;
//! * [`goal`] — the estimates of the extras' errors.
//!
//! Everything here is generic: the element enters through [`Discretisation`] (its mesh, its
//! stress points' barycentric coordinates), the material through L's data, the extras through
//! their loads. No element, yield surface or obstacle is named.

pub mod goal;
pub mod quadrature;
pub mod recovery;

use crate::fem::Discretisation;
use crate::problem::energies::stress_energy;
use crate::problem::fields::StressField;
use crate::problem::lagrangian::Lagrangian;
use recovery::{ElementField, RecoveredField};

/// The estimate of one solution (theory §15).
#[derive(Clone, Debug, PartialEq)]
pub struct ErrorEstimate {
    /// η = (Σ_T η_T²)^{1/2}: the estimate of ‖σ̂ − σ̂_h‖_E.
    pub energy: f64,
    /// η / ‖σ̂_h‖_E (0 for a zero stress field).
    pub relative: f64,
    /// η_T per element, in the mesh's order.
    pub indicators: Vec<f64>,
    /// The estimate of |V_k − V_{h,k}| per extra unknown; `None` where the compliance identity
    /// does not apply (theory §15.2).
    pub extras: Vec<Option<f64>>,
}

/// The estimate of the solution with stresses `stress` of `l` on `element` (theory §15): the
/// stages recover, compare, sum.
pub fn estimate(element: &dyn Discretisation, l: &Lagrangian<'_>, stress: &StressField) -> ErrorEstimate {
    let field = ElementField::new(element, l, stress);
    let recovered = RecoveredField::average(element, &field);
    let indicators = recovery::indicators(element, l, &field, &recovered);
    let energy = indicators.iter().map(|e| e * e).sum::<f64>().sqrt();
    let norm = (2.0 * stress_energy(l, stress)).max(0.0).sqrt();
    let relative = if norm > 0.0 { energy / norm } else { 0.0 };
    let extras = goal::extra_estimates(energy, l.data.load);
    ErrorEstimate { energy, relative, indicators, extras }
}
