//! Rows recombined from nodal rows (theory §10.1, §8.1): `g̃ = T⁻¹ g`, where g are an
//! obstacle's nodal rows and T a sparse, explicitly invertible matrix that an element supplies
//! (the dual quadratic rows of P2: vertex rows kept, an edge row `(g_e − α(g_a + g_b))/(1 − 2α)`).
//!
//! T has one level: each row of T is either the unit row of its own row (the row is **kept**)
//! or a combination `T_ii e_i + Σ_k T_ik e_k` of kept rows k with `T_ii ≠ 0`. Then T⁻¹ is as
//! sparse as T (`S_ii = 1/T_ii`, `S_ik = −T_ik/T_ii`), and so are the forces `λ = T⁻ᵀ λ̃` and the
//! change of basis of the active-set solvers built from it (theory §8.1).

use crate::problem::displacements::ConstraintRows;

/// The nodal rows of recombined rows and T: `g_nodal = T g̃` (module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RowCombination {
    /// The nodal rows (G, H, c as the obstacle discretised them).
    pub nodal: ConstraintRows,
    /// Row i of T as (row k, T_ik), its own entry first; `[(i, 1.0)]` for a kept row.
    pub t: Vec<Vec<(usize, f64)>>,
}

impl RowCombination {
    /// Checks that `t` has one level (module docs) on `n` rows; the error names the row.
    pub fn check(t: &[Vec<(usize, f64)>], n: usize) -> Result<(), String> {
        if t.len() != n {
            return Err(format!("T has {} rows for {n} rows", t.len()));
        }
        let kept = |k: usize| t[k].len() == 1 && t[k][0] == (k, 1.0);
        for (i, r) in t.iter().enumerate() {
            match r.first() {
                Some(&(k, d)) if k == i && d != 0.0 => {}
                _ => return Err(format!("row {i} of T does not start with its own non-zero entry: {r:?}")),
            }
            if let Some(&(k, _)) = r[1..].iter().find(|&&(k, _)| k >= n || !kept(k)) {
                return Err(format!("row {i} of T combines row {k}, which is not a kept row"));
            }
        }
        Ok(())
    }

    /// Row i of T⁻¹ as (row k, S_ik), its own entry first.
    pub fn inverse_row(&self, i: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let r = &self.t[i];
        let d = r[0].1;
        std::iter::once((i, 1.0 / d)).chain(r[1..].iter().map(move |&(k, w)| (k, -w / d)))
    }

    /// `out` = T⁻¹ `nodal`: the recombined rows' values from the nodal rows' (gaps).
    pub fn from_nodal(&self, nodal: &[f64], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.inverse_row(i).map(|(k, s)| s * nodal[k]).sum();
        }
    }

    /// Tᵀ w: weights of the nodal rows (∫N_k) carried to the recombined rows (∫Ñ_j =
    /// Σ_k T_kj ∫N_k, theory §10.1).
    pub fn weights_from_nodal(&self, w: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; w.len()];
        for (k, r) in self.t.iter().enumerate() {
            for &(j, t) in r {
                out[j] += t * w[k];
            }
        }
        out
    }

    /// λ = T⁻ᵀ λ̃: the nodal rows' multipliers (nodal forces) of the recombined rows' `lambda`.
    pub fn nodal_multipliers(&self, lambda: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; lambda.len()];
        for (i, &l) in lambda.iter().enumerate() {
            for (k, s) in self.inverse_row(i) {
                out[k] += s * l;
            }
        }
        out
    }

    /// The rows T⁻¹ g of the nodal rows `nodal`, which remember `nodal` and `t`. An error
    /// (naming the row) when `t` is not of one level, or when the rows carry friction (a
    /// friction block pairs a node's normal and tangential rows; recombining them is not built).
    pub fn recombine(nodal: ConstraintRows, t: Vec<Vec<(usize, f64)>>) -> Result<ConstraintRows, String> {
        let n = nodal.n_rows();
        Self::check(&t, n)?;
        if nodal.has_friction() {
            return Err("rows with friction cannot be recombined (friction blocks pair nodal rows)".into());
        }
        let c = Self { nodal, t };
        let nodal = &c.nodal;
        let mut rows = ConstraintRows::new(nodal.n_extras);
        let mut entries: Vec<(usize, f64)> = Vec::new();
        let mut h = vec![0.0; nodal.n_extras];
        for i in 0..n {
            entries.clear();
            h.iter_mut().for_each(|x| *x = 0.0);
            let mut offset = 0.0;
            for (k, s) in c.inverse_row(i) {
                let (cols, vals) = nodal.row(k);
                entries.extend(cols.iter().zip(vals).map(|(&j, &v)| (j, s * v)));
                h.iter_mut().zip(nodal.extra_row(k)).for_each(|(x, y)| *x += s * y);
                offset += s * nodal.offset[k];
            }
            merge_entries(&mut entries);
            rows.push(&entries, &h, offset, nodal.node[i]);
        }
        rows.warnings = nodal.warnings.clone();
        rows.combination = Some(Box::new(c));
        Ok(rows)
    }
}

/// Sorts `entries` by column and sums the entries of one column.
fn merge_entries(entries: &mut Vec<(usize, f64)>) {
    entries.sort_by_key(|e| e.0);
    let mut out: Vec<(usize, f64)> = Vec::with_capacity(entries.len());
    for &(j, v) in entries.iter() {
        match out.last_mut() {
            Some(last) if last.0 == j => last.1 += v,
            _ => out.push((j, v)),
        }
    }
    *entries = out;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three punch rows u₃ at dofs 2, 5, 8 (nodes 0, 1, 2), row 2 the edge node between the
    /// other two, α = 1/5.
    fn edge() -> (ConstraintRows, Vec<Vec<(usize, f64)>>) {
        let mut rows = ConstraintRows::new(1);
        for (n, c) in [0.1, 0.4, 0.2].into_iter().enumerate() {
            rows.push(&[(3 * n + 2, 1.0)], &[-1.0], c, n);
        }
        let t = vec![vec![(0, 1.0)], vec![(1, 1.0)], vec![(2, 0.6), (0, 0.2), (1, 0.2)]];
        (rows, t)
    }

    #[test]
    fn recombined_rows_are_t_inverse_of_the_nodal_rows_and_keep_the_resultant() {
        let (nodal, t) = edge();
        let rows = RowCombination::recombine(nodal.clone(), t).unwrap();
        let c = rows.combination.as_deref().unwrap();
        // g̃ = T⁻¹ g at a random (u, V), and g = T g̃ back
        let u: Vec<f64> = (0..9).map(|i| (i as f64 * 0.7).cos()).collect();
        let (mut g, mut gt, mut direct) = (vec![0.0; 3], vec![0.0; 3], vec![0.0; 3]);
        nodal.gap(&u, &[0.3], &mut g);
        c.from_nodal(&g, &mut gt);
        rows.gap(&u, &[0.3], &mut direct);
        assert!(gt.iter().zip(&direct).all(|(a, b)| (a - b).abs() < 1e-15), "{gt:?} vs {direct:?}");
        // the edge row by hand: (g_e − α(g_a + g_b))/(1 − 2α)
        assert!((gt[2] - (g[2] - 0.2 * (g[0] + g[1])) / 0.6).abs() < 1e-15);
        // Gᵀλ = G̃ᵀλ̃ with λ = T⁻ᵀλ̃, and the same resultant (T⁻¹1 = 1 for these weights)
        let lt = [0.3, 0.5, 0.7];
        let l = c.nodal_multipliers(&lt);
        let (mut f1, mut f2, mut v1, mut v2) = (vec![0.0; 9], vec![0.0; 9], vec![0.0], vec![0.0]);
        rows.add_transpose(&lt, &mut f1, &mut v1);
        nodal.add_transpose(&l, &mut f2, &mut v2);
        assert!(f1.iter().zip(&f2).all(|(a, b)| (a - b).abs() < 1e-15));
        assert!((v1[0] - v2[0]).abs() < 1e-15 && (l.iter().sum::<f64>() - 1.5).abs() < 1e-15);
        // weights ∫Ñ = Tᵀ∫N: 0 at the vertices, 1/3 at the edge node → α/3 and (1 − 2α)/3
        let w = c.weights_from_nodal(&[0.0, 0.0, 1.0 / 3.0]);
        assert!((w[0] - 0.2 / 3.0).abs() < 1e-16 && (w[2] - 0.2).abs() < 1e-16, "{w:?}");
    }

    #[test]
    fn a_combination_of_a_combined_row_is_refused() {
        let t = vec![vec![(0, 1.0)], vec![(1, 0.6), (0, 0.2)], vec![(2, 0.6), (1, 0.2)]];
        let e = RowCombination::check(&t, 3).unwrap_err();
        assert!(e.contains("row 2 of T combines row 1"), "{e}");
        assert!(RowCombination::check(&[vec![(0, 0.0)]], 1).unwrap_err().contains("row 0"));
    }
}
