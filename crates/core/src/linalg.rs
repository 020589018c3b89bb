//! Sparse symmetric matrices stored as their lower triangle, and a sparse Cholesky
//! factorisation split into the symbolic analysis (AMD ordering, supernodal structure: once per
//! sparsity pattern) and the numeric factorisation (once per set of values) — faer underneath.

use crate::error::LinalgError;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

/// The sparsity pattern of a symmetric matrix: its lower triangle in compressed columns, rows
/// sorted in each column, the diagonal first.
#[derive(Clone, Debug)]
pub struct SymmetricPattern {
    symbolic: SymbolicSparseColMat<usize>,
}

impl SymmetricPattern {
    /// A pattern from column pointers and sorted row indices (rows ≥ column in each column).
    pub fn new(n: usize, col_ptr: Vec<usize>, row_idx: Vec<usize>) -> Self {
        debug_assert!((0..n).all(|j| row_idx[col_ptr[j]..col_ptr[j + 1]].first() == Some(&j)));
        Self { symbolic: SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx) }
    }

    /// Order of the matrix.
    pub fn n(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Number of stored entries (lower triangle).
    pub fn nnz(&self) -> usize {
        self.symbolic.row_idx().len()
    }

    /// Column pointers.
    pub fn col_ptr(&self) -> &[usize] {
        self.symbolic.col_ptr()
    }

    /// Row indices.
    pub fn row_idx(&self) -> &[usize] {
        self.symbolic.row_idx()
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

    fn faer_ref<'a>(&'a self, values: &'a [f64]) -> SparseColMatRef<'a, usize, f64> {
        SparseColMatRef::new(self.symbolic.as_ref(), values)
    }
}

/// Sparse Cholesky A = LLᵀ: the symbolic analysis is done once for a pattern; `factorise` is
/// called for each new set of values and `solve` reuses the factor as often as needed.
pub struct SparseCholesky {
    what: String,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    scratch: MemBuffer,
    scratch_cols: usize,
    factorised: bool,
    par: Par,
}

impl std::fmt::Debug for SparseCholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseCholesky")
            .field("what", &self.what)
            .field("n", &self.n())
            .field("nnz_l", &self.l_values.len())
            .finish()
    }
}

impl SparseCholesky {
    /// Symbolic analysis of `pattern` (AMD fill-reducing ordering). `what` names the matrix in
    /// error messages ("elastic stiffness", "tangent").
    pub fn analyse(pattern: &SymmetricPattern, what: &str) -> Result<Self, LinalgError> {
        let symbolic = factorize_symbolic_cholesky(
            pattern.symbolic.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| LinalgError::Backend { what: what.into(), message: format!("{e:?}") })?;
        // Two threads pay off only on large factors (measured: slower below ~20k unknowns).
        let par = if pattern.n() > 20_000 { Par::rayon(0) } else { Par::Seq };
        let l_values = vec![0.0; symbolic.len_val()];
        let mut this = Self {
            what: what.into(),
            symbolic,
            l_values,
            scratch: MemBuffer::new(StackReq::EMPTY),
            scratch_cols: 0,
            factorised: false,
            par,
        };
        this.reserve(1);
        Ok(this)
    }

    fn reserve(&mut self, cols: usize) {
        if cols <= self.scratch_cols {
            return;
        }
        let req = StackReq::any_of(&[
            self.symbolic.factorize_numeric_llt_scratch::<f64>(self.par, Default::default()),
            self.symbolic.solve_in_place_scratch::<f64>(cols, self.par),
        ]);
        self.scratch = MemBuffer::new(req);
        self.scratch_cols = cols;
    }

    /// Order of the matrix.
    pub fn n(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Number of stored entries of L.
    pub fn nnz_l(&self) -> usize {
        self.l_values.len()
    }

    /// Numeric factorisation of the matrix with `values` on the analysed pattern.
    pub fn factorise(&mut self, pattern: &SymmetricPattern, values: &[f64]) -> Result<(), LinalgError> {
        assert_eq!(pattern.n(), self.n(), "pattern does not match the analysed one");
        if values.iter().any(|v| !v.is_finite()) {
            self.factorised = false;
            return Err(LinalgError::Backend {
                what: self.what.clone(),
                message: "matrix has NaN or infinite entries".into(),
            });
        }
        let stack = MemStack::new(&mut self.scratch);
        let result = self.symbolic.factorize_numeric_llt::<f64>(
            &mut self.l_values,
            pattern.faer_ref(values),
            Side::Lower,
            LltRegularization::default(),
            self.par,
            stack,
            Default::default(),
        );
        self.factorised = result.is_ok();
        result.map(|_| ()).map_err(|_| LinalgError::NotPositiveDefinite { what: self.what.clone(), n: self.n() })
    }

    /// Solves A x = b in place (`x` holds b on entry).
    pub fn solve(&mut self, x: &mut [f64]) {
        self.solve_columns(x, 1);
    }

    /// Solves A X = B in place for `ncols` right-hand sides stored column after column in `x`.
    pub fn solve_columns(&mut self, x: &mut [f64], ncols: usize) {
        assert!(self.factorised, "solve before a successful factorisation");
        let n = self.n();
        assert_eq!(x.len(), n * ncols);
        self.reserve(ncols);
        let llt = LltRef::new(&self.symbolic, &self.l_values);
        let rhs = MatMut::from_column_major_slice_mut(x, n, ncols);
        llt.solve_in_place_with_conj(Conj::No, rhs, self.par, MemStack::new(&mut self.scratch));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 1D Laplacian tridiag(−1, 2, −1) of order n, lower triangle.
    fn laplacian(n: usize) -> (SymmetricPattern, Vec<f64>) {
        let mut cp = vec![0];
        let mut ri = vec![];
        let mut v = vec![];
        for j in 0..n {
            ri.push(j);
            v.push(2.0);
            if j + 1 < n {
                ri.push(j + 1);
                v.push(-1.0);
            }
            cp.push(ri.len());
        }
        (SymmetricPattern::new(n, cp, ri), v)
    }

    #[test]
    fn cholesky_solves_and_refactorises() {
        let n = 50;
        let (p, v) = laplacian(n);
        let mut chol = SparseCholesky::analyse(&p, "test").unwrap();
        chol.factorise(&p, &v).unwrap();
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin()).collect();
        let mut b = vec![0.0; n];
        p.matvec(&v, &x_true, &mut b);
        chol.solve(&mut b);
        let err = b.iter().zip(&x_true).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(err < 1e-12, "{err}");
        // new values on the same pattern, two right-hand sides at once
        let v2: Vec<f64> = v.iter().map(|a| 3.0 * a).collect();
        chol.factorise(&p, &v2).unwrap();
        let mut rhs = vec![0.0; 2 * n];
        p.matvec(&v2, &x_true, &mut rhs[..n]);
        p.matvec(&v2, &x_true, &mut rhs[n..]);
        chol.solve_columns(&mut rhs, 2);
        assert!(rhs.iter().zip(x_true.iter().chain(&x_true)).all(|(a, b)| (a - b).abs() < 1e-12));
    }

    #[test]
    fn indefinite_matrix_is_an_error_not_a_panic() {
        let (p, mut v) = laplacian(5);
        v[0] = -1.0;
        let mut chol = SparseCholesky::analyse(&p, "stiffness").unwrap();
        let e = chol.factorise(&p, &v).unwrap_err();
        assert!(matches!(e, LinalgError::NotPositiveDefinite { .. }));
        assert!(e.to_string().contains("rigid-body"));
    }
}
