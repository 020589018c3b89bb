//! Goal-oriented estimates of the extra unknowns (theory §15.2): the compliance identity.
//! For an extra V_k that carries the only load f_k of the problem, the dual problem of the goal
//! f_k V_k is the primal one (Becker & Rannacher 2001, §2 "energy functional"), and
//! f_k (V_k − V_{h,k}) ≈ ‖σ̂ − σ̂_h‖_E², so |V_k − V_{h,k}| ≈ η² / |f_k|.

/// The estimate of |V_k − V_{h,k}| for every extra, from the energy estimate `energy` and the
/// loads `load` on the extras: η²/|f_k| for the only loaded extra, `None` for the others (an
/// unloaded extra, or several loaded ones: the compliance identity bounds only their joint work).
pub fn extra_estimates(energy: f64, load: &[f64]) -> Vec<Option<f64>> {
    let loaded: Vec<usize> = (0..load.len()).filter(|&k| load[k] != 0.0).collect();
    (0..load.len()).map(|k| (loaded == [k]).then(|| energy * energy / load[k].abs())).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One loaded extra gets η²/|f|; unloaded extras and several loaded ones get none.
    #[test]
    fn only_the_only_loaded_extra_has_a_compliance_estimate() {
        assert_eq!(extra_estimates(0.1, &[-0.5, 0.0, 0.0]), vec![Some(0.1 * 0.1 / 0.5), None, None]);
        assert_eq!(extra_estimates(0.1, &[0.5, 1.0]), vec![None, None]);
        assert_eq!(extra_estimates(0.1, &[]), Vec::<Option<f64>>::new());
    }
}
