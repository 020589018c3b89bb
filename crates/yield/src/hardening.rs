//! Linear isotropic hardening (theory §1): the hardening variable ξ with the metric ξη/h, and
//! the rule for its modulus h, which every surface with isotropic hardening shares.

use saddle_core::error::{ParameterError, check};

/// h ≥ 0, either 0 (perfect plasticity: ξ frozen) or a scale in [1e-50, 1e50]
/// ([`check::scale`]: 1/h enters the hardening metric ξη/h), so that the solvers' products stay
/// finite; errors name `{path}.h`.
pub(crate) fn check_modulus(path: &str, h: f64) -> Result<(), ParameterError> {
    check::non_negative(path, "h", h)?;
    check::scale(path, "h", h, true)?;
    Ok(())
}

/// ξη/h (theory §1). For h = 0 the metric is infinite in ξ: 0 when ξη = 0, else ±∞ with the
/// sign of ξη.
pub(crate) fn isotropic_inner(h: f64, xi: f64, eta: f64) -> f64 {
    let p = xi * eta;
    if h > 0.0 {
        p / h
    } else if p == 0.0 {
        0.0
    } else {
        p * f64::INFINITY
    }
}
