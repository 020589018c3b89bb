//! A sparse matrix assembled as (row, column, value) triplets, for the cone programmes handed
//! to Clarabel (theory §4.4, §13).

use clarabel::algebra::CscMatrix;

/// A sparse matrix as (row, column, value) triplets in the order pushed.
pub(crate) struct Triplets {
    rows: Vec<usize>,
    cols: Vec<usize>,
    vals: Vec<f64>,
}

impl Triplets {
    /// Room for `nnz` entries.
    pub(crate) fn with_capacity(nnz: usize) -> Self {
        Self { rows: Vec::with_capacity(nnz), cols: Vec::with_capacity(nnz), vals: Vec::with_capacity(nnz) }
    }

    /// Entry (i, j) = v.
    pub(crate) fn push(&mut self, i: usize, j: usize, v: f64) {
        self.rows.push(i);
        self.cols.push(j);
        self.vals.push(v);
    }

    /// Entry (i, j) = v unless v = 0.
    pub(crate) fn push_nonzero(&mut self, i: usize, j: usize, v: f64) {
        if v != 0.0 {
            self.push(i, j, v);
        }
    }

    /// The m × n matrix in compressed columns.
    pub(crate) fn into_csc(self, m: usize, n: usize) -> CscMatrix<f64> {
        CscMatrix::new_from_triplets(m, n, self.rows, self.cols, self.vals)
    }
}
