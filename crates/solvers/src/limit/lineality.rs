//! Stage 2, continued (theory §13.3): the coordinates of the stress unknowns, adapted to
//! the lineality space of the yield surface's cones.
//!
//! The unknowns of a point are `z_T = (σ_T, a_T)` (Mandel σ, then the cone's auxiliary variables,
//! if any). A direction d with `map·d = 0` in every cone block (the kernel of the maps: for von
//! Mises and Tresca the hydrostatic axis) is a line in D: the cones never see the coordinate of
//! z_T along d. If moreover the equilibrium column of that coordinate, `B_Tᵀ d_σ`, is the same
//! at every point of an element (B̄'s pressure: its volumetric strain is the element mean), then
//! equilibrium sees only the weighted sum of those coordinates over the element, and the static
//! programme is unchanged when they are replaced by one unknown per element (their weighted
//! mean): `z_T = Σ_i y_T,i q_i + Σ_k p_e,k d_k` with (q_i) an orthonormal basis of the maps' row
//! space and (d_k) of their kernel. Otherwise the coordinates are z_T itself (the identity basis).

/// Relative size below which a Gram–Schmidt remainder is linearly dependent, and below which an
/// entry of a column or a map in the new coordinates is round-off.
const DEPENDENT: f64 = 1e-10;

/// The coordinates of the stress unknowns (module docs).
#[derive(Clone, Debug)]
pub(super) struct StressBasis {
    /// Entries of z_T per point (6 + auxiliary variables).
    pub width: usize,
    /// The per-point basis (q_i), `per_point × width`, row-major.
    pub basis: Vec<f64>,
    /// Coordinates per point.
    pub per_point: usize,
    /// The directions merged per element (d_k), `per_element × width`, row-major.
    pub merged: Vec<f64>,
    /// Unknowns per element.
    pub per_element: usize,
    /// Stress points per element: the points of element e are `e·k .. (e+1)·k`.
    pub points_per_element: usize,
}

impl StressBasis {
    /// The identity basis: every entry of z_T its own unknown, nothing merged.
    fn identity(width: usize, points_per_element: usize) -> Self {
        let basis = (0..width * width).map(|k| (k / width == k % width) as usize as f64).collect();
        Self { width, basis, per_point: width, merged: Vec::new(), per_element: 0, points_per_element }
    }

    /// The basis for the cone maps `maps` (rows of `width` entries, stacked over the blocks), the
    /// strain entries `(point, component, dof, value)` of the element and its points per element
    /// `k`: the merged one when the kernel is not trivial and its equilibrium columns coincide
    /// on every element, else the identity.
    pub fn new(maps: &[f64], width: usize, strain: &[(usize, usize, usize, f64)], n_points: usize, k: usize) -> Self {
        let rows = orthonormal(maps.chunks_exact(width).map(<[f64]>::to_vec), &[]);
        let units = (0..width).map(|c| (0..width).map(|j| (j == c) as usize as f64).collect());
        let kernel = orthonormal(units, &rows);
        if kernel.is_empty() || !columns_coincide(&kernel, strain, n_points, k) {
            return Self::identity(width, k);
        }
        Self {
            width,
            per_point: rows.len(),
            basis: rows.concat(),
            per_element: kernel.len(),
            merged: kernel.concat(),
            points_per_element: k,
        }
    }

    /// Basis vector i.
    pub fn q(&self, i: usize) -> &[f64] {
        &self.basis[i * self.width..(i + 1) * self.width]
    }

    /// Merged direction k.
    pub fn d(&self, k: usize) -> &[f64] {
        &self.merged[k * self.width..(k + 1) * self.width]
    }

    /// A map row (`width` entries) in the per-point coordinates: its products with the q_i, with
    /// round-off set to 0 (the products with the d_k vanish by construction).
    pub fn map_row(&self, row: &[f64]) -> Vec<f64> {
        let scale = row.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        (0..self.per_point)
            .map(|i| dot(row, self.q(i)))
            .map(|v| if v.abs() <= DEPENDENT * scale { 0.0 } else { v })
            .collect()
    }

    /// Entry c of z_T from its coordinates y_T and its element's merged unknowns p_e.
    pub fn entry(&self, y: &[f64], p: &[f64], c: usize) -> f64 {
        let from_q: f64 = y.iter().enumerate().map(|(i, yi)| yi * self.q(i)[c]).sum();
        from_q + p.iter().enumerate().map(|(k, pk)| pk * self.d(k)[c]).sum::<f64>()
    }
}

/// a·b.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// An orthonormal basis of the span of `vectors` orthogonal to the orthonormal `against`
/// (modified Gram–Schmidt, dropping remainders below [`DEPENDENT`] of the vector's size).
fn orthonormal(vectors: impl Iterator<Item = Vec<f64>>, against: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = Vec::new();
    for mut v in vectors {
        let size = dot(&v, &v).sqrt();
        for q in against.iter().chain(&out) {
            let c = dot(&v, q);
            v.iter_mut().zip(q).for_each(|(x, y)| *x -= c * y);
        }
        let norm = dot(&v, &v).sqrt();
        if norm > DEPENDENT * size && size > 0.0 {
            v.iter_mut().for_each(|x| *x /= norm);
            out.push(v);
        }
    }
    out
}

/// Whether every direction's equilibrium column `B_Tᵀ d_σ` (per unit weight) is the same at the
/// points of each element, to [`DEPENDENT`] of its largest entry.
fn columns_coincide(kernel: &[Vec<f64>], strain: &[(usize, usize, usize, f64)], n_points: usize, k: usize) -> bool {
    if k == 0 || !n_points.is_multiple_of(k) {
        return false;
    }
    // the strain entries by point
    let mut start = vec![0usize; n_points + 1];
    for &(t, ..) in strain {
        start[t + 1] += 1;
    }
    for t in 0..n_points {
        start[t + 1] += start[t];
    }
    let mut by_point = vec![(0usize, 0usize, 0.0f64); strain.len()];
    let mut next = start.clone();
    for &(t, c, j, v) in strain {
        by_point[next[t]] = (c, j, v);
        next[t] += 1;
    }
    let column = |t: usize, d: &[f64], out: &mut Vec<(usize, f64)>| {
        out.clear();
        out.extend(by_point[start[t]..start[t + 1]].iter().filter(|(c, ..)| *c < 6).map(|&(c, j, v)| (j, v * d[c])));
        out.sort_unstable_by_key(|e| e.0);
        out.dedup_by(|b, a| {
            let same = a.0 == b.0;
            if same {
                a.1 += b.1;
            }
            same
        });
    };
    let (mut first, mut other) = (Vec::new(), Vec::new());
    kernel.iter().all(|d| {
        (0..n_points / k).all(|e| {
            column(e * k, d, &mut first);
            let scale = first.iter().fold(0.0f64, |m, (_, v)| m.max(v.abs()));
            let tol = DEPENDENT * scale.max(f64::MIN_POSITIVE);
            first.retain(|(_, v)| v.abs() > tol);
            (1..k).all(|q| {
                column(e * k + q, d, &mut other);
                other.retain(|(_, v)| v.abs() > tol);
                other.len() == first.len()
                    && other.iter().zip(&first).all(|(a, b)| a.0 == b.0 && (a.1 - b.1).abs() <= tol)
            })
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The von Mises map (the deviatoric basis as rows, a zero row for the cone's t) has the
    /// hydrostatic axis as kernel: two points whose B columns differ only in the deviator (the
    /// same trace row) merge; different trace rows do not.
    #[test]
    fn the_hydrostatic_axis_merges_when_the_trace_columns_coincide() {
        let (a, b) = (std::f64::consts::FRAC_1_SQRT_2, 1.0 / 6f64.sqrt());
        let mut maps = vec![0.0; 6];
        maps.extend([a, -a, 0.0, 0.0, 0.0, 0.0, b, b, -2.0 * b, 0.0, 0.0, 0.0]);
        for c in 3..6 {
            maps.extend((0..6).map(|j| (j == c) as usize as f64));
        }
        // two points of one element: ε₁₁ = u₀ + u₁, ε₂₂ = −u₁ at point 0 and ε₁₁ = u₀,
        // ε₃₃ = 0 at point 1 … the traces are u₀ at both
        let same = [(0, 0, 0, 1.0), (0, 0, 1, 1.0), (0, 1, 1, -1.0), (1, 0, 0, 1.0), (1, 3, 1, 2.0)];
        let s = StressBasis::new(&maps, 6, &same, 2, 2);
        assert_eq!((s.per_point, s.per_element), (5, 1));
        let d = s.d(0);
        let third = 1.0 / 3f64.sqrt();
        assert!(d.iter().zip([third, third, third, 0.0, 0.0, 0.0]).all(|(x, y)| (x.abs() - y).abs() < 1e-15), "{d:?}");
        // a map row in the new coordinates: the deviator rows become unit rows
        assert!(
            s.map_row(&maps[6..12]).iter().zip([1.0, 0.0, 0.0, 0.0, 0.0]).all(|(x, y)| (x.abs() - y).abs() < 1e-15)
        );
        let differ = [(0, 0, 0, 1.0), (1, 0, 0, 1.0), (1, 1, 1, 1.0)];
        let s = StressBasis::new(&maps, 6, &differ, 2, 2);
        assert_eq!((s.per_point, s.per_element), (6, 0));
        // z from coordinates: the identity basis reads y itself
        assert_eq!(s.entry(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0], &[], 4), 5.0);
    }
}
