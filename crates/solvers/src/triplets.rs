//! The cone programmes handed to Clarabel (theory §4.4, §13): a sparse matrix assembled as
//! (row, column, value) triplets, and a programme written as JSON for other conic solvers.

use clarabel::algebra::CscMatrix;
use clarabel::solver::SupportedConeT;

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

/// A cone programme `minimise ½xᵀPx + qᵀx subject to Ax + s = b, s in the cones` as JSON, for
/// other conic solvers (`examples/export_cone.rs`, the cvxpy comparison of `examples/peers/`):
/// `{"n", "m", "P": {"colptr", "rowval", "nzval"} (upper triangle, CSC), "q", "A": {…} (m × n,
/// CSC), "b", "cones": [["zero" | "nonneg" | "soc" | "psd_triangle", dim or n], …]}`.
pub(crate) fn programme_json(
    p: &CscMatrix<f64>,
    q: &[f64],
    a: &CscMatrix<f64>,
    b: &[f64],
    cones: &[SupportedConeT<f64>],
) -> String {
    let csc = |m: &CscMatrix<f64>| serde_json::json!({ "m": m.m, "n": m.n, "colptr": m.colptr, "rowval": m.rowval, "nzval": m.nzval });
    let cones: Vec<(&str, usize)> = cones
        .iter()
        .map(|c| match c {
            SupportedConeT::ZeroConeT(d) => ("zero", *d),
            SupportedConeT::NonnegativeConeT(d) => ("nonneg", *d),
            SupportedConeT::SecondOrderConeT(d) => ("soc", *d),
            #[cfg(feature = "sdp")]
            SupportedConeT::PSDTriangleConeT(n) => ("psd_triangle", *n),
            _ => ("other", 0),
        })
        .collect();
    serde_json::json!({ "n": a.n, "m": a.m, "P": csc(p), "q": q, "A": csc(a), "b": b, "cones": cones }).to_string()
}
