//! Compressed sparse rows with both triangles stored: the format of the iterative path
//! (matrix–vector products in parallel over rows, transposes, and the sparse products of an
//! algebraic multigrid set-up).

use rayon::prelude::*;

/// A sparse matrix in compressed rows; column indices sorted within each row.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Csr {
    /// Rows.
    pub nrows: usize,
    /// Columns.
    pub ncols: usize,
    /// Row pointers.
    pub ptr: Vec<usize>,
    /// Column indices.
    pub idx: Vec<u32>,
    /// Values.
    pub val: Vec<f64>,
}

/// The lower triangle of a symmetric matrix in compressed columns, borrowed: its order, the
/// column pointers and the sorted row indices (the diagonal first in each column).
#[derive(Clone, Copy, Debug)]
pub struct LowerCsc<'a> {
    /// Order of the matrix.
    pub n: usize,
    /// Column pointers, `n + 1` of them.
    pub col_ptr: &'a [usize],
    /// Row indices (≥ the column) of each column, sorted.
    pub row_idx: &'a [usize],
}

impl<'a> LowerCsc<'a> {
    /// The pattern of order `n` with these column pointers and row indices.
    pub fn new(n: usize, col_ptr: &'a [usize], row_idx: &'a [usize]) -> Self {
        assert_eq!(col_ptr.len(), n + 1, "one column pointer per column and one past the end");
        Self { n, col_ptr, row_idx }
    }

    /// Stored entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }
}

/// Σ_k val_k x\[idx_k\] in double precision, in four independent partial sums: one chain of
/// additions would wait on each addition's latency (the products of the iterative path ran at
/// a quarter of the machine's speed).
#[inline]
pub fn sparse_dot<T: Copy + Into<f64>>(idx: &[u32], val: &[T], x: &[f64]) -> f64 {
    let mut s = [0.0f64; 4];
    let (ic, vc) = (idx.chunks_exact(4), val.chunks_exact(4));
    let (it, vt) = (ic.remainder(), vc.remainder());
    for (i, v) in ic.zip(vc) {
        for k in 0..4 {
            s[k] += v[k].into() * x[i[k] as usize];
        }
    }
    for (&j, &a) in it.iter().zip(vt) {
        s[0] += a.into() * x[j as usize];
    }
    (s[0] + s[1]) + (s[2] + s[3])
}

/// Rows per parallel task: large enough to amortise scheduling, small enough to balance.
const CHUNK: usize = 2048;

/// y_r = f(r, y_r) for every row r, in parallel chunks of [`CHUNK`] rows: the loop of the
/// matrix–vector products of [`Csr`] and [`super::Csr32`].
pub(super) fn rows_into(y: &mut [f64], f: impl Fn(usize, f64) -> f64 + Sync) {
    y.par_chunks_mut(CHUNK).enumerate().for_each(|(c, ys)| {
        let r0 = c * CHUNK;
        for (k, yi) in ys.iter_mut().enumerate() {
            *yi = f(r0 + k, *yi);
        }
    });
}

/// Rows per parallel task of the sparse product (rows of coarse matrices are long).
const PRODUCT_CHUNK: usize = 256;

/// Visits every entry of the full symmetric matrix whose lower triangle is `values` on
/// `pattern` as (position in the rows `ptr`, column, value). Columns in increasing order: row i
/// receives (i, j) for j ≤ i in increasing j, then its own column's (i, i′) for i′ > i in
/// increasing i′ — sorted without a sort.
fn scatter_lower(
    pattern: LowerCsc<'_>,
    values: &[f64],
    ptr: &[usize],
    fill: &mut [usize],
    mut put: impl FnMut(usize, u32, f64),
) {
    let (cp, ri) = (pattern.col_ptr, pattern.row_idx);
    fill.copy_from_slice(&ptr[..pattern.n]);
    for j in 0..pattern.n {
        for k in cp[j]..cp[j + 1] {
            let i = ri[k];
            put(fill[i], j as u32, values[k]);
            fill[i] += 1;
            if i != j {
                put(fill[j], i as u32, values[k]);
                fill[j] += 1;
            }
        }
    }
}

impl Csr {
    /// The full symmetric matrix whose lower triangle is `values` on `pattern`.
    pub fn from_symmetric_lower(pattern: LowerCsc<'_>, values: &[f64]) -> Self {
        let n = pattern.n;
        let (cp, ri) = (pattern.col_ptr, pattern.row_idx);
        let mut len = vec![0usize; n];
        for j in 0..n {
            for &i in &ri[cp[j]..cp[j + 1]] {
                len[i] += 1;
                if i != j {
                    len[j] += 1;
                }
            }
        }
        let mut ptr = vec![0usize; n + 1];
        for i in 0..n {
            ptr[i + 1] = ptr[i] + len[i];
        }
        let nnz = ptr[n];
        let (mut idx, mut val) = (vec![0u32; nnz], vec![0.0; nnz]);
        scatter_lower(pattern, values, &ptr, &mut vec![0; n], |q, col, v| {
            idx[q] = col;
            val[q] = v;
        });
        Self { nrows: n, ncols: n, ptr, idx, val }
    }

    /// New `values` of the lower triangle on the `pattern` this matrix was built from
    /// ([`Csr::from_symmetric_lower`]), without touching the structure; `fill` is scratch.
    pub fn assign_symmetric_lower(&mut self, pattern: LowerCsc<'_>, values: &[f64], fill: &mut Vec<usize>) {
        assert_eq!(pattern.n, self.nrows, "not the pattern this matrix was built from");
        fill.resize(self.nrows, 0);
        let val = &mut self.val;
        scatter_lower(pattern, values, &self.ptr, fill, |q, _, v| val[q] = v);
    }

    /// Stored entries.
    pub fn nnz(&self) -> usize {
        self.idx.len()
    }

    /// y = A x.
    pub fn spmv(&self, x: &[f64], y: &mut [f64]) {
        debug_assert_eq!((x.len(), y.len()), (self.ncols, self.nrows));
        rows_into(y, |r, _| self.row_dot(r, x));
    }

    /// y = b − A x.
    pub fn residual(&self, b: &[f64], x: &[f64], y: &mut [f64]) {
        rows_into(y, |r, _| b[r] - self.row_dot(r, x));
    }

    /// y += α A x.
    pub fn spmv_add(&self, alpha: f64, x: &[f64], y: &mut [f64]) {
        debug_assert_eq!((x.len(), y.len()), (self.ncols, self.nrows));
        rows_into(y, |r, y| y + alpha * self.row_dot(r, x));
    }

    /// (A x)_r: the dot product of row `r` with `x` ([`sparse_dot`]).
    #[inline]
    pub fn row_dot(&self, r: usize, x: &[f64]) -> f64 {
        let (lo, hi) = (self.ptr[r], self.ptr[r + 1]);
        sparse_dot(&self.idx[lo..hi], &self.val[lo..hi], x)
    }

    /// The diagonal (zero where a row stores no diagonal entry).
    pub fn diagonal(&self) -> Vec<f64> {
        (0..self.nrows.min(self.ncols))
            .map(|r| {
                let row = &self.idx[self.ptr[r]..self.ptr[r + 1]];
                row.binary_search(&(r as u32)).map_or(0.0, |q| self.val[self.ptr[r] + q])
            })
            .collect()
    }

    /// The lower triangle of a (numerically) symmetric matrix as column pointers, row indices
    /// and values (see [`LowerCsc`]), for [`super::SparseCholesky`]: column j of the lower
    /// triangle is row j's entries at columns ≥ j. Every row must store its diagonal.
    pub fn to_symmetric_lower(&self) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        assert_eq!(self.nrows, self.ncols, "a symmetric matrix is square");
        let mut col_ptr = Vec::with_capacity(self.nrows + 1);
        col_ptr.push(0);
        let (mut row_idx, mut values) = (Vec::new(), Vec::new());
        for j in 0..self.nrows {
            for q in self.ptr[j]..self.ptr[j + 1] {
                if self.idx[q] as usize >= j {
                    row_idx.push(self.idx[q] as usize);
                    values.push(self.val[q]);
                }
            }
            col_ptr.push(row_idx.len());
        }
        (col_ptr, row_idx, values)
    }

    /// α A + β B (same shape; the union of the two patterns, sorted).
    pub fn add(&self, alpha: f64, b: &Csr, beta: f64) -> Csr {
        assert_eq!((self.nrows, self.ncols), (b.nrows, b.ncols));
        let mut ptr = Vec::with_capacity(self.nrows + 1);
        ptr.push(0);
        let (mut idx, mut val) = (Vec::with_capacity(self.nnz()), Vec::with_capacity(self.nnz()));
        for r in 0..self.nrows {
            let (mut p, pe, mut q, qe) = (self.ptr[r], self.ptr[r + 1], b.ptr[r], b.ptr[r + 1]);
            while p < pe || q < qe {
                let cp = if p < pe { self.idx[p] } else { u32::MAX };
                let cq = if q < qe { b.idx[q] } else { u32::MAX };
                if cp < cq {
                    idx.push(cp);
                    val.push(alpha * self.val[p]);
                    p += 1;
                } else if cq < cp {
                    idx.push(cq);
                    val.push(beta * b.val[q]);
                    q += 1;
                } else {
                    idx.push(cp);
                    val.push(alpha * self.val[p] + beta * b.val[q]);
                    p += 1;
                    q += 1;
                }
            }
            ptr.push(idx.len());
        }
        Csr { nrows: self.nrows, ncols: self.ncols, ptr, idx, val }
    }

    /// Aᵀ.
    pub fn transpose(&self) -> Self {
        let mut len = vec![0usize; self.ncols];
        for &c in &self.idx {
            len[c as usize] += 1;
        }
        let mut ptr = vec![0usize; self.ncols + 1];
        for c in 0..self.ncols {
            ptr[c + 1] = ptr[c] + len[c];
        }
        let mut fill = ptr.clone();
        let mut idx = vec![0u32; self.nnz()];
        let mut val = vec![0.0; self.nnz()];
        for r in 0..self.nrows {
            for q in self.ptr[r]..self.ptr[r + 1] {
                let c = self.idx[q] as usize;
                idx[fill[c]] = r as u32;
                val[fill[c]] = self.val[q];
                fill[c] += 1;
            }
        }
        Self { nrows: self.ncols, ncols: self.nrows, ptr, idx, val }
    }

    /// A B (Gustavson's row-by-row product, rows in parallel, each task with its own dense
    /// accumulator over the columns of B).
    pub fn matmul(&self, b: &Csr) -> Csr {
        assert_eq!(self.ncols, b.nrows);
        let chunks: Vec<(Vec<usize>, Vec<u32>, Vec<f64>)> = (0..self.nrows.div_ceil(PRODUCT_CHUNK))
            .into_par_iter()
            .map_init(
                || (vec![0.0; b.ncols], vec![u32::MAX; b.ncols]),
                |(acc, mark), c| {
                    let (r0, r1) = (c * PRODUCT_CHUNK, ((c + 1) * PRODUCT_CHUNK).min(self.nrows));
                    let mut cols: Vec<u32> = Vec::new();
                    let (mut lens, mut idx, mut val) = (Vec::with_capacity(r1 - r0), Vec::new(), Vec::new());
                    for r in r0..r1 {
                        cols.clear();
                        let (lo, hi) = (self.ptr[r], self.ptr[r + 1]);
                        for (&k, &a) in self.idx[lo..hi].iter().zip(&self.val[lo..hi]) {
                            let (blo, bhi) = (b.ptr[k as usize], b.ptr[k as usize + 1]);
                            for (&j, &v) in b.idx[blo..bhi].iter().zip(&b.val[blo..bhi]) {
                                let ju = j as usize;
                                if mark[ju] != r as u32 {
                                    mark[ju] = r as u32;
                                    acc[ju] = a * v;
                                    cols.push(j);
                                } else {
                                    acc[ju] += a * v;
                                }
                            }
                        }
                        cols.sort_unstable();
                        lens.push(cols.len());
                        idx.extend_from_slice(&cols);
                        val.extend(cols.iter().map(|&j| acc[j as usize]));
                    }
                    (lens, idx, val)
                },
            )
            .collect();
        let mut ptr = Vec::with_capacity(self.nrows + 1);
        ptr.push(0);
        let total: usize = chunks.iter().map(|c| c.1.len()).sum();
        let (mut idx, mut val) = (Vec::with_capacity(total), Vec::with_capacity(total));
        for (lens, i, v) in chunks {
            for l in lens {
                ptr.push(ptr.last().unwrap() + l);
            }
            idx.extend(i);
            val.extend(v);
        }
        Csr { nrows: self.nrows, ncols: b.ncols, ptr, idx, val }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dense(a: &Csr) -> Vec<Vec<f64>> {
        let mut d = vec![vec![0.0; a.ncols]; a.nrows];
        for (r, row) in d.iter_mut().enumerate() {
            for q in a.ptr[r]..a.ptr[r + 1] {
                row[a.idx[q] as usize] += a.val[q];
            }
        }
        d
    }

    fn sample() -> Csr {
        // 3×4
        Csr { nrows: 3, ncols: 4, ptr: vec![0, 2, 3, 5], idx: vec![0, 3, 1, 0, 2], val: vec![1.0, 2.0, 3.0, 4.0, 5.0] }
    }

    #[test]
    fn transpose_and_product_agree_with_dense() {
        let a = sample();
        let at = a.transpose();
        assert_eq!(dense(&at)[3][0], 2.0);
        let ata = at.matmul(&a);
        let (da, dd) = (dense(&a), dense(&ata));
        for i in 0..4 {
            for j in 0..4 {
                let s: f64 = (0..3).map(|k| da[k][i] * da[k][j]).sum();
                assert_eq!(dd[i][j], s);
            }
        }
        let x = [1.0, -1.0, 2.0, 0.5];
        let mut y = vec![0.0; 3];
        a.spmv(&x, &mut y);
        assert_eq!(y, vec![2.0, -3.0, 14.0]);
    }

    #[test]
    fn symmetric_lower_becomes_full_and_sorted() {
        // [[4, 1, 0], [1, 5, 2], [0, 2, 6]]
        let (cp, ri) = ([0, 2, 4, 5], [0, 1, 1, 2, 2]);
        let p = LowerCsc::new(3, &cp, &ri);
        let a = Csr::from_symmetric_lower(p, &[4.0, 1.0, 5.0, 2.0, 6.0]);
        assert_eq!(dense(&a), vec![vec![4.0, 1.0, 0.0], vec![1.0, 5.0, 2.0], vec![0.0, 2.0, 6.0]]);
        assert!((0..3).all(|r| a.idx[a.ptr[r]..a.ptr[r + 1]].windows(2).all(|w| w[0] < w[1])));
        assert_eq!(a.diagonal(), vec![4.0, 5.0, 6.0]);
        // new values on the same pattern, structure kept
        let mut b = a.clone();
        b.assign_symmetric_lower(p, &[7.0, -1.0, 8.0, 3.0, 9.0], &mut Vec::new());
        assert_eq!((&b.ptr, &b.idx), (&a.ptr, &a.idx));
        assert_eq!(dense(&b), vec![vec![7.0, -1.0, 0.0], vec![-1.0, 8.0, 3.0], vec![0.0, 3.0, 9.0]]);
    }

    /// A random m × n matrix with up to `per_row` entries per row (sorted, distinct columns).
    fn random(m: usize, n: usize, per_row: usize, seed: u64) -> Csr {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let mut ptr = vec![0];
        let (mut idx, mut val) = (vec![], vec![]);
        for _ in 0..m {
            let mut cols: Vec<u32> = (0..per_row).map(|_| rng.random_range(0..n as u32)).collect();
            cols.sort_unstable();
            cols.dedup();
            for c in cols {
                idx.push(c);
                val.push(rng.random_range(-1.0..1.0));
            }
            ptr.push(idx.len());
        }
        Csr { nrows: m, ncols: n, ptr, idx, val }
    }

    fn sorted_rows(a: &Csr) -> bool {
        (0..a.nrows).all(|r| a.idx[a.ptr[r]..a.ptr[r + 1]].windows(2).all(|w| w[0] < w[1]))
    }

    #[test]
    fn products_across_parallel_tasks_agree_with_vector_products() {
        // more rows than one task holds, so that the parallel splits are exercised
        let (a, b) = (random(5000, 3000, 7, 1), random(3000, 900, 5, 2));
        let x: Vec<f64> = (0..900).map(|i| (i as f64 * 0.7).sin()).collect();
        let ab = a.matmul(&b);
        assert!(sorted_rows(&ab) && ab.ptr.len() == 5001 && ab.ncols == 900);
        let (mut bx, mut abx, mut ab_x) = (vec![0.0; 3000], vec![0.0; 5000], vec![0.0; 5000]);
        b.spmv(&x, &mut bx);
        a.spmv(&bx, &mut abx);
        ab.spmv(&x, &mut ab_x);
        assert!(abx.iter().zip(&ab_x).all(|(p, q)| (p - q).abs() < 1e-12), "(AB)x ≠ A(Bx)");
        // yᵀ(A z) = (Aᵀ y)ᵀ z, and the transpose is sorted
        let at = a.transpose();
        assert!(sorted_rows(&at) && at.transpose() == a);
        let y: Vec<f64> = (0..5000).map(|i| (i as f64 * 0.3).cos()).collect();
        let z: Vec<f64> = (0..3000).map(|i| (i as f64 * 0.1).sin()).collect();
        let (mut az, mut aty) = (vec![0.0; 5000], vec![0.0; 3000]);
        a.spmv(&z, &mut az);
        at.spmv(&y, &mut aty);
        let (l, r): (f64, f64) =
            (y.iter().zip(&az).map(|(p, q)| p * q).sum(), aty.iter().zip(&z).map(|(p, q)| p * q).sum());
        assert!((l - r).abs() < 1e-10 * l.abs().max(1.0));
        // y += 2 A z and b − A z
        let mut w = y.clone();
        a.spmv_add(2.0, &z, &mut w);
        let mut res = vec![0.0; 5000];
        a.residual(&y, &z, &mut res);
        assert!((0..5000).all(|i| (w[i] - y[i] - 2.0 * az[i]).abs() < 1e-12 && (res[i] - y[i] + az[i]).abs() < 1e-12));
        // α A + β B on the union of the patterns
        let c = random(5000, 3000, 7, 3);
        let sum = a.add(2.0, &c, -0.5);
        let mut sz = vec![0.0; 5000];
        sum.spmv(&z, &mut sz);
        let mut cz = vec![0.0; 5000];
        c.spmv(&z, &mut cz);
        assert!(sorted_rows(&sum) && (0..5000).all(|i| (sz[i] - 2.0 * az[i] + 0.5 * cz[i]).abs() < 1e-12));
    }

    #[test]
    fn lower_triangle_round_trip() {
        let (cp, ri) = ([0, 2, 4, 5], [0, 1, 1, 2, 2]);
        let p = LowerCsc::new(3, &cp, &ri);
        let v = [4.0, 1.0, 5.0, 2.0, 6.0];
        let (q, r, w) = Csr::from_symmetric_lower(p, &v).to_symmetric_lower();
        assert_eq!((q.as_slice(), r.as_slice(), w.as_slice()), (&cp[..], &ri[..], &v[..]));
        // [[4, 1, 0], [1, 5, 2], [0, 2, 6]] · (1, 2, 3)
        let mut y = vec![0.0; 3];
        Csr::from_symmetric_lower(p, &v).spmv(&[1.0, 2.0, 3.0], &mut y);
        assert_eq!(y, vec![6.0, 17.0, 22.0]);
    }
}
