//! The vector updates of the line searches (theory §4.2 step 4, §4.3), on plain slices.

/// a · b.
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// out = x + α d.
pub(crate) fn axpy_into(out: &mut [f64], x: &[f64], alpha: f64, d: &[f64]) {
    for ((o, a), b) in out.iter_mut().zip(x).zip(d) {
        *o = a + alpha * b;
    }
}

/// x += α d.
pub(crate) fn axpy(x: &mut [f64], alpha: f64, d: &[f64]) {
    for (a, b) in x.iter_mut().zip(d) {
        *a += alpha * b;
    }
}

/// out = (1 − α) x + α y: a point along a step, exact at both ends.
pub(crate) fn blend(out: &mut [f64], x: &[f64], alpha: f64, y: &[f64]) {
    for ((o, a), b) in out.iter_mut().zip(x).zip(y) {
        *o = (1.0 - alpha) * a + alpha * b;
    }
}
