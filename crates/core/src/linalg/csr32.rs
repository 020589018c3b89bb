//! A [`Csr`] with its values rounded to single precision, for the operators of a preconditioner
//! (the multigrid's levels, smoothers and transfers). Products accumulate in double precision;
//! only the stored values are single. The products of a V-cycle are bound by memory traffic,
//! 12 bytes per entry in double precision (value and index) and 8 here; rounding the values
//! perturbs the preconditioner by a relative 6e-8, far below what it approximates anyway, and
//! leaves it a fixed, symmetric linear operator, so CG keeps its convergence (the outer
//! iteration's matrix stays the double-precision one).

use super::csr::{Csr, rows_into, sparse_dot};

/// Compressed rows with single-precision values: the rows, columns, row pointers and sorted
/// column indices of the [`Csr`] it was rounded from, and its values rounded to the nearest
/// single.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Csr32 {
    nrows: usize,
    ncols: usize,
    ptr: Vec<usize>,
    idx: Vec<u32>,
    val: Vec<f32>,
}

impl From<&Csr> for Csr32 {
    fn from(a: &Csr) -> Self {
        Self {
            nrows: a.nrows,
            ncols: a.ncols,
            ptr: a.ptr.clone(),
            idx: a.idx.clone(),
            val: a.val.iter().map(|&v| v as f32).collect(),
        }
    }
}

impl Csr32 {
    /// Stored entries.
    pub fn nnz(&self) -> usize {
        self.idx.len()
    }

    /// Rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// (A x)_r in double precision ([`sparse_dot`]).
    #[inline]
    pub fn row_dot(&self, r: usize, x: &[f64]) -> f64 {
        let (lo, hi) = (self.ptr[r], self.ptr[r + 1]);
        sparse_dot(&self.idx[lo..hi], &self.val[lo..hi], x)
    }

    /// y = A x.
    pub fn spmv(&self, x: &[f64], y: &mut [f64]) {
        debug_assert_eq!((x.len(), y.len()), (self.ncols, self.nrows));
        rows_into(y, |r, _| self.row_dot(r, x));
    }

    /// y += α A x.
    pub fn spmv_add(&self, alpha: f64, x: &[f64], y: &mut [f64]) {
        debug_assert_eq!((x.len(), y.len()), (self.ncols, self.nrows));
        rows_into(y, |r, y| y + alpha * self.row_dot(r, x));
    }

    /// y = b − A x.
    pub fn residual(&self, b: &[f64], x: &[f64], y: &mut [f64]) {
        debug_assert_eq!((x.len(), b.len(), y.len()), (self.ncols, self.nrows, self.nrows));
        rows_into(y, |r, _| b[r] - self.row_dot(r, x));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn products_match_the_double_precision_matrix_to_single_rounding() {
        // a 3 × 4 matrix with values that single precision cannot hold exactly
        let a = Csr {
            nrows: 3,
            ncols: 4,
            ptr: vec![0, 2, 3, 5],
            idx: vec![0, 3, 1, 0, 2],
            val: vec![0.1, -1.0 / 3.0, 2.0, 1e-9, std::f64::consts::PI],
        };
        let s = Csr32::from(&a);
        let x = [1.0, -2.0, 0.5, 3.0];
        let (mut y64, mut y32) = (vec![0.0; 3], vec![0.0; 3]);
        a.spmv(&x, &mut y64);
        s.spmv(&x, &mut y32);
        let scale = a.val.iter().map(|v| v.abs()).sum::<f64>() * 3.0;
        for (p, q) in y64.iter().zip(&y32) {
            assert!((p - q).abs() <= 1e-7 * scale && (p - q).abs() > 0.0 || p == q, "{p} {q}");
        }
        // y = 0.1·1 − 3/3 = −0.9; 2·(−2) = −4; 1e-9 + π/2
        assert!(
            (y32[0] + 0.9).abs() < 1e-7
                && y32[1] == -4.0
                && (y32[2] - (1e-9 + 0.5 * std::f64::consts::PI)).abs() < 1e-7
        );
        let b = [1.0, 1.0, 1.0];
        let mut r = vec![0.0; 3];
        s.residual(&b, &x, &mut r);
        for k in 0..3 {
            assert_eq!(r[k], b[k] - y32[k]);
        }
        let mut z = vec![1.0; 3];
        s.spmv_add(2.0, &x, &mut z);
        for k in 0..3 {
            assert!((z[k] - (1.0 + 2.0 * y32[k])).abs() < 1e-15);
        }
    }
}
