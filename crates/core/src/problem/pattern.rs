//! The sparsity pattern of the matrices a Lagrangian assembles (theory §3): the lower triangle
//! of a symmetric matrix in compressed columns. Plain data, so that the contracts name no
//! linear-algebra type; solvers hand its slices to the factorisation of their choice.

/// The sparsity pattern of a symmetric matrix: its lower triangle in compressed columns, rows
/// sorted in each column, the diagonal first.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SymmetricPattern {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
}

impl SymmetricPattern {
    /// A pattern from column pointers and sorted row indices (rows ≥ column in each column).
    pub fn new(n: usize, col_ptr: Vec<usize>, row_idx: Vec<usize>) -> Self {
        debug_assert!((0..n).all(|j| row_idx[col_ptr[j]..col_ptr[j + 1]].first() == Some(&j)));
        assert_eq!(col_ptr.len(), n + 1, "one column pointer per column and one past the end");
        assert_eq!(col_ptr[n], row_idx.len(), "the last column pointer is the number of entries");
        Self { n, col_ptr, row_idx }
    }

    /// Order of the matrix.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of stored entries (lower triangle).
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Column pointers.
    pub fn col_ptr(&self) -> &[usize] {
        &self.col_ptr
    }

    /// Row indices.
    pub fn row_idx(&self) -> &[usize] {
        &self.row_idx
    }

    /// y = A x for the symmetric matrix with these `values`.
    pub fn matvec(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        let (cp, ri) = (self.col_ptr(), self.row_idx());
        y.iter_mut().for_each(|v| *v = 0.0);
        for j in 0..self.n() {
            let xj = x[j];
            let mut acc = 0.0;
            for k in cp[j]..cp[j + 1] {
                let i = ri[k];
                let a = values[k];
                if i == j {
                    acc += a * xj;
                } else {
                    y[i] += a * xj;
                    acc += a * x[i];
                }
            }
            y[j] += acc;
        }
    }

    /// The diagonal entries.
    pub fn diagonal(&self, values: &[f64]) -> Vec<f64> {
        self.col_ptr()[..self.n()].iter().map(|&k| values[k]).collect()
    }
}
