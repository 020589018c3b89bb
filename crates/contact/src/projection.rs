//! The Euclidean projection onto K_h (theory §3): the closest point of
//! {g(w, V) = G w + H V + c ≥ 0} to a trial point, with the row multipliers — what the K
//! conformance kit uses to make feasible points of any obstacle's rows.

use nalgebra::{DMatrix, DVector};
use saddle_core::ConstraintRows;
use saddle_core::linalg::{DenseQp, QpError};

/// A point of K_h obtained by projection, with the row multipliers.
#[derive(Clone, Debug, PartialEq)]
pub struct Projected {
    /// Displacement dofs w.
    pub u: Vec<f64>,
    /// Extra unknowns V.
    pub extras: Vec<f64>,
    /// Multipliers μ ≥ 0 of the rows.
    pub multipliers: Vec<f64>,
}

/// The Euclidean projection of (z, Z) onto K_h, with the multipliers μ ≥ 0 of the rows:
/// w = z + Gᵀμ, V = Z + Hᵀμ, g(w, V) ≥ 0, μ_i g_i = 0.
pub fn project_euclidean(rows: &ConstraintRows, z: &[f64], zv: &[f64]) -> Result<Projected, QpError> {
    let nr = rows.n_rows();
    // S = G Gᵀ + H Hᵀ (rows are sparse; form it by a sparse dot per pair)
    let mut dense_g = vec![std::collections::HashMap::new(); nr];
    for (i, d) in dense_g.iter_mut().enumerate() {
        let (cols, vals) = rows.row(i);
        for (&j, &v) in cols.iter().zip(vals) {
            *d.entry(j).or_insert(0.0) += v;
        }
    }
    let s = DMatrix::from_fn(nr, nr, |a, b| {
        let gg: f64 = dense_g[a].iter().map(|(j, v)| v * dense_g[b].get(j).copied().unwrap_or(0.0)).sum();
        let hh: f64 = rows.extra_row(a).iter().zip(rows.extra_row(b)).map(|(x, y)| x * y).sum();
        gg + hh
    });
    let mut g = vec![0.0; nr];
    rows.gap(z, zv, &mut g);
    let mut qp = DenseQp::new(s, DMatrix::zeros(0, nr), DVector::zeros(0))?;
    let mu: Vec<f64> = qp.solve(&DVector::from_vec(g))?.x.iter().copied().collect();
    let mut w = z.to_vec();
    let mut v = zv.to_vec();
    rows.add_transpose(&mu, &mut w, &mut v);
    Ok(Projected { u: w, extras: v, multipliers: mu })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn euclidean_projection_onto_a_half_space_with_an_extra() {
        // one row: u0 + 0.5 − V ≥ 0; project (u0, V) = (0, 1): closest point on u0 − V = −0.5
        let mut rows = ConstraintRows::new(1);
        rows.push(&[(0, 1.0)], &[-1.0], 0.5, 0);
        let Projected { u: w, extras: v, multipliers: mu } = project_euclidean(&rows, &[0.0, 3.0], &[1.0]).unwrap();
        assert!((w[0] - 0.25).abs() < 1e-15 && (v[0] - 0.75).abs() < 1e-15 && w[1] == 3.0);
        assert!((mu[0] - 0.25).abs() < 1e-15);
        // feasible points stay put
        let Projected { u: w, extras: v, multipliers: mu } = project_euclidean(&rows, &[1.0, 0.0], &[0.0]).unwrap();
        assert_eq!((w[0], v[0], mu[0]), (1.0, 0.0, 0.0));
    }
}
