//! Rows entering the contact model's active set, solved on the last factor (theory §4.3): a
//! sweep of the model's active-set loop changes K' + D_A only by the penalty terms d_i = k_i a_i²
//! of the rows that enter or leave A. When rows only enter, the new matrix is A₀ + E D Eᵀ (E the
//! unit columns of the entering rows' coordinates) and the Woodbury identity solves it with the
//! factor of A₀ and a dense r × r system, r the entering rows:
//!
//! ```text
//! W = A₀⁻¹E,  C = D⁻¹ + EᵀW,  w = A₀⁻¹b,  t = C⁻¹Eᵀw,  x = w − W t,  Eᵀx = D⁻¹t.
//! ```
//!
//! C is the sum of two positive definite matrices, so no cancellation; and the entering rows'
//! values Eᵀx (of size χ/k, the gaps of theory §4.3's carried-gap argument) are taken from
//! D⁻¹t, not from the difference w − W t of two terms of size u. A row leaving A would need
//! D⁻¹ − … with d ∝ 1/μ on both sides: that sweep is factorised.

use nalgebra::{DMatrix, DVector};
use saddle_core::linalg::SparseCholesky;

/// A factorised matrix: its Newton step (value of K'), active rows and pair Hessians.
type Factorised = (usize, Vec<bool>, Vec<[[f64; 2]; 2]>);

/// The stiff terms of the last factorisation and the scratch of the update (module docs).
#[derive(Debug, Default)]
pub(super) struct EnteringRows {
    /// The Newton step (value of K') of the factorised matrix, its active rows and pair
    /// Hessians; `None` before the first factorisation.
    factor: Option<Factorised>,
    /// The entering rows' coordinates and penalty terms d.
    dofs: Vec<usize>,
    d: Vec<f64>,
    /// W = A₀⁻¹E, column after column.
    w: Vec<f64>,
    /// Systems solved by the update.
    pub updates: usize,
}

impl EnteringRows {
    /// Records the matrix of Newton step `step` with rows `active` and pair Hessians `pairs`
    /// as the factorised one.
    pub(super) fn factorised(&mut self, step: usize, active: &[bool], pairs: &[[[f64; 2]; 2]]) {
        self.factor = Some((step, active.to_vec(), pairs.to_vec()));
    }

    /// Whether the matrix of Newton step `step` with rows `active` and pair Hessians `pairs` is
    /// the factorised one plus at most `max_rank` entering rows; `dof_term(i)` gives row i's
    /// coordinate and penalty term. Sets the entering rows when so.
    pub(super) fn applies(
        &mut self,
        step: usize,
        active: &[bool],
        pairs: &[[[f64; 2]; 2]],
        max_rank: usize,
        dof_term: impl Fn(usize) -> (usize, f64),
    ) -> bool {
        let Some((fstep, rows, fpairs)) = &self.factor else { return false };
        if *fstep != step || fpairs.as_slice() != pairs || active.iter().zip(rows).any(|(a, f)| *f && !a) {
            return false;
        }
        self.dofs.clear();
        self.d.clear();
        for i in (0..active.len()).filter(|&i| active[i] && !rows[i]) {
            let (s, d) = dof_term(i);
            self.dofs.push(s);
            self.d.push(d);
        }
        !self.dofs.is_empty() && self.dofs.len() <= max_rank
    }

    /// The number of entering rows (of the last [`Self::applies`]).
    pub(super) fn dofs(&self) -> usize {
        self.dofs.len()
    }

    /// Solves (A₀ + E D Eᵀ) X = B in place for the `nc` columns of `x` (module docs), with
    /// `chol` the factor of A₀; false (x untouched) when C is not numerically positive definite.
    pub(super) fn solve(&mut self, chol: &mut SparseCholesky, x: &mut [f64], nc: usize) -> bool {
        let (n, r) = (chol.n(), self.dofs.len());
        self.w.clear();
        self.w.resize(n * r, 0.0);
        for (j, &s) in self.dofs.iter().enumerate() {
            self.w[j * n + s] = 1.0;
        }
        chol.solve_columns(&mut self.w, r);
        let c = DMatrix::from_fn(r, r, |i, j| {
            let f = 0.5 * (self.w[j * n + self.dofs[i]] + self.w[i * n + self.dofs[j]]);
            if i == j { f + 1.0 / self.d[i] } else { f }
        });
        let Some(c) = c.cholesky() else { return false };
        chol.solve_columns(x, nc);
        for xc in x.chunks_exact_mut(n) {
            let t = c.solve(&DVector::from_iterator(r, self.dofs.iter().map(|&s| xc[s])));
            for (j, tj) in t.iter().enumerate() {
                for (xi, wi) in xc.iter_mut().zip(&self.w[j * n..(j + 1) * n]) {
                    *xi -= wi * tj;
                }
            }
            for ((&s, d), tj) in self.dofs.iter().zip(&self.d).zip(t.iter()) {
                xc[s] = tj / d;
            }
        }
        self.updates += 1;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::EnteringRows;
    use saddle_core::linalg::{LowerCsc, SparseCholesky};

    /// tridiag(−1, 2, −1) of order n plus `stiff` on the diagonal at the dofs in `rows`: the lower
    /// triangle (col_ptr, row_idx, values).
    fn penalised(n: usize, rows: &[usize], stiff: f64) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let (mut cp, mut ri, mut v) = (vec![0], vec![], vec![]);
        for j in 0..n {
            ri.push(j);
            v.push(2.0 + if rows.contains(&j) { stiff } else { 0.0 });
            if j + 1 < n {
                ri.push(j + 1);
                v.push(-1.0);
            }
            cp.push(ri.len());
        }
        (cp, ri, v)
    }

    #[test]
    fn entering_rows_on_the_last_factor_give_the_fresh_factors_solution() {
        // the penalty's scale: d = 1e14 against an O(1) stiffness (k = K_ss / μ, μ = 1e-12 … 1e-14)
        let (n, d) = (40, 1e14);
        let (cp, ri, v0) = penalised(n, &[3], d);
        let mut chol = SparseCholesky::analyse(LowerCsc::new(n, &cp, &ri), "A0").unwrap();
        chol.factorise(&v0).unwrap();
        let mut update = EnteringRows::default();
        let mut active = vec![false; n];
        active[3] = true;
        update.factorised(1, &active, &[]);
        // rows 10 and 25 enter
        active[10] = true;
        active[25] = true;
        assert!(update.applies(1, &active, &[], 2, |i| (i, d)));
        let b: Vec<f64> = (0..2 * n).map(|i| (0.37 * i as f64).cos()).collect();
        let mut x = b.clone();
        assert!(update.solve(&mut chol, &mut x, 2));
        // against a fresh factorisation of A1
        let (_, _, v1) = penalised(n, &[3, 10, 25], d);
        let mut fresh = SparseCholesky::analyse(LowerCsc::new(n, &cp, &ri), "A1").unwrap();
        fresh.factorise(&v1).unwrap();
        let mut y = b.clone();
        fresh.solve_columns(&mut y, 2);
        let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (i, (a, e)) in x.iter().zip(&y).enumerate() {
            // the stiff dofs hold values of size b/d (the carried gaps' size): relative to their own;
            // measured: 4.3e-14 there, 2.5e-15 of the largest elsewhere
            let tol = if [3, 10, 25].contains(&(i % n)) { 1e-10 * e.abs() } else { 1e-10 * scale };
            assert!((a - e).abs() <= tol, "dof {i}: {a} against {e}");
        }
        // a stiff entering value is b_s/d to first order, not the round-off of w − W t
        assert!(x[10].abs() > 1e-16 && x[10].abs() < 1e-13, "{}", x[10]);
        // a row leaving, another Newton step, or more rows than the rank bound: factorise
        assert!(!update.applies(2, &active, &[], 2, |i| (i, d)));
        assert!(!update.applies(1, &active, &[], 1, |i| (i, d)));
        active[3] = false;
        assert!(!update.applies(1, &active, &[], 2, |i| (i, d)));
    }
}
