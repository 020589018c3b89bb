//! Sparse Cholesky factorisation of a symmetric positive definite matrix given by its lower
//! triangle in compressed columns, split into the symbolic analysis (AMD ordering, supernodal
//! structure: once per sparsity pattern) and the numeric factorisation (once per set of values)
//! — faer underneath.

use super::csr::LowerCsc;
use super::error::LinalgError;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

/// Above this order the factorisation runs on all threads (measured: slower below about 20k
/// unknowns, where the supernodes are too small to share).
const PARALLEL_MIN_ORDER: usize = 20_000;

/// Sparse Cholesky A = LLᵀ: the symbolic analysis is done once for a pattern; `factorise` is
/// called for each new set of values and `solve` reuses the factor as often as needed.
pub struct SparseCholesky {
    what: String,
    /// The analysed pattern (lower triangle, compressed columns).
    pattern: SymbolicSparseColMat<usize>,
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
            .field("nnz_l", &self.nnz_l())
            .finish()
    }
}

impl SparseCholesky {
    /// Symbolic analysis (AMD fill-reducing ordering) of the lower-triangle pattern. `what`
    /// names the matrix in error messages ("elastic stiffness", "tangent").
    pub fn analyse(pattern: LowerCsc<'_>, what: &str) -> Result<Self, LinalgError> {
        let n = pattern.n;
        let pattern = SymbolicSparseColMat::new_checked(n, n, pattern.col_ptr.to_vec(), None, pattern.row_idx.to_vec());
        let symbolic = factorize_symbolic_cholesky(
            pattern.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| LinalgError::Backend { what: what.into(), message: format!("{e:?}") })?;
        // Two threads pay off only on large factors (measured: slower below ~20k unknowns).
        let par = if n > PARALLEL_MIN_ORDER { Par::rayon(0) } else { Par::Seq };
        // the factor's storage is taken at the first factorisation, fallibly: an analysis
        // only prices the factor (`auto` may never factorise, theory §4.2)
        Ok(Self {
            what: what.into(),
            pattern,
            symbolic,
            l_values: Vec::new(),
            scratch: MemBuffer::new(StackReq::EMPTY),
            scratch_cols: 0,
            factorised: false,
            par,
        })
    }

    /// The scratch of a factorisation and of solves with `cols` right-hand sides.
    fn scratch_req(&self, cols: usize) -> StackReq {
        StackReq::any_of(&[
            self.symbolic.factorize_numeric_llt_scratch::<f64>(self.par, Default::default()),
            self.symbolic.solve_in_place_scratch::<f64>(cols, self.par),
        ])
    }

    fn reserve(&mut self, cols: usize) {
        if cols <= self.scratch_cols {
            return;
        }
        self.scratch = MemBuffer::new(self.scratch_req(cols));
        self.scratch_cols = cols;
    }

    /// Takes the factor's storage and the factorisation's scratch, or reports their size
    /// when the machine cannot give it (an error, not an abort).
    fn allocate(&mut self) -> Result<(), LinalgError> {
        let len = self.symbolic.len_val();
        if self.l_values.len() != len {
            let mut values = Vec::new();
            if values.try_reserve_exact(len).is_err() {
                return Err(self.out_of_memory(self.factor_bytes()));
            }
            values.resize(len, 0.0);
            self.l_values = values;
        }
        if self.scratch_cols == 0 {
            let req = self.scratch_req(1);
            self.scratch = MemBuffer::try_new(req).map_err(|_| self.out_of_memory(req.size_bytes()))?;
            self.scratch_cols = 1;
        }
        Ok(())
    }

    /// The error of an allocation of `bytes` the machine refused.
    fn out_of_memory(&self, bytes: usize) -> LinalgError {
        LinalgError::OutOfMemory { what: self.what.clone(), n: self.n(), bytes }
    }

    /// Bytes of the factor's storage (L's entries), known from the analysis alone.
    pub fn factor_bytes(&self) -> usize {
        self.symbolic.len_val() * std::mem::size_of::<f64>()
    }

    /// Order of the matrix.
    pub fn n(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Number of stored entries of L.
    pub fn nnz_l(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Multiply–adds of one numeric factorisation, from the symbolic structure: Σ_j c_j² over
    /// the columns of L, c_j the entries of column j (diagonal included). The cost model of
    /// the `auto` backend choice; a triangular solve pair costs 2·`nnz_l` multiply–adds.
    pub fn factor_flops(&self) -> f64 {
        use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => s.col_ptr().windows(2).map(|w| ((w[1] - w[0]) as f64).powi(2)).sum(),
            SymbolicCholeskyRaw::Supernodal(s) => (0..s.n_supernodes())
                .map(|k| {
                    let w = s.supernode_end()[k] - s.supernode_begin()[k];
                    let r = s.supernode(k).pattern().len();
                    // the supernode's columns hold w, w − 1, …, 1 rows of its diagonal block
                    (0..w).map(|c| ((w - c + r) as f64).powi(2)).sum::<f64>()
                })
                .sum(),
        }
    }

    /// Numeric factorisation of the matrix with `values` (one per entry of the analysed pattern).
    pub fn factorise(&mut self, values: &[f64]) -> Result<(), LinalgError> {
        assert_eq!(values.len(), self.pattern.row_idx().len(), "values do not match the analysed pattern");
        if values.iter().any(|v| !v.is_finite()) {
            self.factorised = false;
            return Err(LinalgError::Backend {
                what: self.what.clone(),
                message: "matrix has NaN or infinite entries".into(),
            });
        }
        self.allocate()?;
        let stack = MemStack::new(&mut self.scratch);
        let result = self.symbolic.factorize_numeric_llt::<f64>(
            &mut self.l_values,
            SparseColMatRef::new(self.pattern.as_ref(), values),
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

    /// The 1D Laplacian tridiag(−1, 2, −1) of order n, lower triangle: (col_ptr, row_idx, values).
    fn laplacian(n: usize) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
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
        (cp, ri, v)
    }

    /// y = A x for the tridiagonal matrix with diagonal d and off-diagonal o (independent of
    /// the compressed storage).
    fn tridiag_times(d: f64, o: f64, x: &[f64]) -> Vec<f64> {
        let n = x.len();
        (0..n)
            .map(|i| d * x[i] + if i > 0 { o * x[i - 1] } else { 0.0 } + if i + 1 < n { o * x[i + 1] } else { 0.0 })
            .collect()
    }

    #[test]
    fn cholesky_solves_and_refactorises() {
        let n = 50;
        let (cp, ri, v) = laplacian(n);
        let mut chol = SparseCholesky::analyse(LowerCsc::new(n, &cp, &ri), "test").unwrap();
        chol.factorise(&v).unwrap();
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin()).collect();
        let mut b = tridiag_times(2.0, -1.0, &x_true);
        chol.solve(&mut b);
        let err = b.iter().zip(&x_true).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(err < 1e-12, "{err}");
        // new values on the same pattern, two right-hand sides at once
        let v2: Vec<f64> = v.iter().map(|a| 3.0 * a).collect();
        chol.factorise(&v2).unwrap();
        let mut rhs = tridiag_times(6.0, -3.0, &x_true);
        rhs.extend(tridiag_times(6.0, -3.0, &x_true));
        chol.solve_columns(&mut rhs, 2);
        assert!(rhs.iter().zip(x_true.iter().chain(&x_true)).all(|(a, b)| (a - b).abs() < 1e-12));
    }

    #[test]
    fn indefinite_matrix_is_an_error_not_a_panic() {
        let (cp, ri, mut v) = laplacian(5);
        v[0] = -1.0;
        let mut chol = SparseCholesky::analyse(LowerCsc::new(5, &cp, &ri), "stiffness").unwrap();
        let e = chol.factorise(&v).unwrap_err();
        assert!(matches!(e, LinalgError::NotPositiveDefinite { .. }));
        assert!(e.to_string().contains("stiffness"));
    }

    #[test]
    fn factor_flops_match_the_closed_forms_of_dense_and_tridiagonal_factors() {
        // a full n × n pattern: column j of L has n − j entries, Σ (n − j)² = n(n+1)(2n+1)/6
        let n = 40;
        let mut cp = vec![0];
        let mut ri = vec![];
        for j in 0..n {
            ri.extend(j..n);
            cp.push(ri.len());
        }
        let chol = SparseCholesky::analyse(LowerCsc::new(n, &cp, &ri), "dense").unwrap();
        let expected = (n * (n + 1) * (2 * n + 1) / 6) as f64;
        assert_eq!((chol.factor_flops(), chol.nnz_l()), (expected, n * (n + 1) / 2));
        // the tridiagonal Laplacian has no fill whatever the ordering: n − 1 columns of 2
        // entries and one of 1
        let (cp, ri, _) = laplacian(n);
        let chol = SparseCholesky::analyse(LowerCsc::new(n, &cp, &ri), "tridiagonal").unwrap();
        assert_eq!((chol.factor_flops(), chol.nnz_l()), ((4 * (n - 1) + 1) as f64, 2 * n - 1));
    }
}
