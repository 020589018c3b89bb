//! Goal-oriented estimates of the extra unknowns (theory §15.2): the compliance identity.
//! For an extra V_k that carries the only load f_k of the problem, the dual problem of the goal
//! f_k V_k is the primal one (Becker & Rannacher 2001, §2 "energy functional"). With the element's
//! form a_h (its strain Bu in place of ε(u)) and e = u − u_h, f_k (V_k − V_{h,k}) = a(e, e) − δ,
//! δ = (a − a_h)(u_h, u_h) = ∫ w:Cw + 2∫ σ_h:w (σ_h = CBu_h), w = ε(u_h) − Bu_h the strain defect.
//! a(e, e) is the error of the exact-strain stress σ_h + Cw; estimated with the recovered σ*,
//! a(e, e) ≈ ‖σ* − σ_h − Cw‖²_{C⁻¹} = η² − 2∫(σ* − σ_h):w + ∫ w:Cw, so
//! f_k (V_k − V_{h,k}) ≈ η² − 2∫ σ*:w (η² where the strain is ε(u_h): w = 0).

/// The estimate of |V_k − V_{h,k}| for every extra, from the energy estimate `energy`, the
/// cross term `defect_cross` = ∫ σ*:w and the loads `load` on the extras:
/// |η² − 2·cross| / |f_k| for the only loaded extra, `None` for the others (an unloaded extra, or
/// several loaded ones: the compliance identity bounds only their joint work).
pub fn extra_estimates(energy: f64, defect_cross: f64, load: &[f64]) -> Vec<Option<f64>> {
    let loaded: Vec<usize> = (0..load.len()).filter(|&k| load[k] != 0.0).collect();
    let work = (energy * energy - 2.0 * defect_cross).abs();
    (0..load.len()).map(|k| (loaded == [k]).then(|| work / load[k].abs())).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One loaded extra gets |η² − 2·cross|/|f|; unloaded extras and several loaded ones get
    /// none.
    #[test]
    fn only_the_only_loaded_extra_has_a_compliance_estimate() {
        assert_eq!(extra_estimates(0.1, 0.0, &[-0.5, 0.0, 0.0]), vec![Some(0.1 * 0.1 / 0.5), None, None]);
        // the cross term: (0.01 − 2·0.002)/0.5 = 0.012, and its absolute value where it exceeds η²/2
        assert!((extra_estimates(0.1, 0.002, &[-0.5])[0].unwrap() - 0.012).abs() < 1e-15);
        assert!((extra_estimates(0.1, 0.01, &[-0.5])[0].unwrap() - 0.02).abs() < 1e-15);
        assert_eq!(extra_estimates(0.1, 0.0, &[0.5, 1.0]), vec![None, None]);
        assert_eq!(extra_estimates(0.1, 0.0, &[]), Vec::<Option<f64>>::new());
    }
}
