//! `error_estimate` in `summary.json`: the a posteriori estimate of theory §15 — the energy-norm
//! estimate, one entry per extra by name, and what it cost.

use saddle_core::ErrorEstimate;
use serde::Serialize;
use std::collections::BTreeMap;

/// The method's name in `summary.json`.
pub const METHOD: &str = "averaging recovery (Zienkiewicz-Zhu), compliance goal";

/// The estimate as `summary.json` holds it. The keys are an interface: extend, do not rename.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct EstimateSummary {
    /// The method (theory §15).
    pub method: String,
    /// η, the estimate of ‖σ̂ − σ̂_h‖_E (theory §15.1).
    pub energy: f64,
    /// η / ‖σ̂_h‖_E.
    pub energy_relative: f64,
    /// The largest element indicator η_T.
    pub max_indicator: f64,
    /// The estimate of each extra's error by the extra's name (`U`, `left.U`, …; theory §15.2),
    /// null where the compliance identity does not apply.
    #[serde(flatten)]
    pub extras: BTreeMap<String, Option<f64>>,
    /// Wall time of the estimate, seconds.
    pub cost_s: f64,
    /// `cost_s` over the wall time of the solve.
    pub cost_share: f64,
}

impl EstimateSummary {
    /// The summary of `e`, the extras named `names`, computed in `cost_s` after a solve of
    /// `solve_s`.
    pub fn new(e: &ErrorEstimate, names: Vec<String>, cost_s: f64, solve_s: f64) -> Self {
        Self {
            method: METHOD.into(),
            energy: e.energy,
            energy_relative: e.relative,
            max_indicator: e.indicators.iter().copied().fold(0.0, f64::max),
            extras: names.into_iter().zip(e.extras.iter().copied()).collect(),
            cost_s,
            cost_share: if solve_s > 0.0 { cost_s / solve_s } else { 0.0 },
        }
    }
}
