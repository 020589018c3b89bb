//! **K** — the admissible displacements (theory §1, §3): a closed convex set of displacements
//! together with its own extra unknowns V (the punch's U) and the load term ℓ(V) = f·V of the
//! Lagrangian (F·V for the punch).
//!
//! On a mesh, K_h is polyhedral: affine rows `g_i(u, V) = Σ_j G_ij u_j + Σ_k H_ik V_k + c_i ≥ 0`,
//! one per contact node (theory §3). Rows are exactly what solvers need: projecting onto K_h in a
//! metric (Uzawa), linearising it (it is its own linearisation), penalising its violation.

use crate::error::{ParameterError, SceneError};
use crate::mesh::TetMesh;
use crate::mesh::dofs::DofMap;
use crate::problem::friction::{ContactStatus, FrictionRows, SLIP_TOL};
use crate::problem::load_factors::LoadFactors;
use std::borrow::Cow;
use std::fmt::Debug;

/// K_h as affine rows g(u, V) = G u + H V + c ≥ 0, G sparse (CSR), H dense.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ConstraintRows {
    /// Number of extra unknowns V (columns of H).
    pub n_extras: usize,
    /// CSR row pointers of G.
    pub row_ptr: Vec<usize>,
    /// Column (free displacement dof) of each entry of G.
    pub col: Vec<usize>,
    /// Value of each entry of G.
    pub val: Vec<f64>,
    /// H, row-major, `n_rows × n_extras`.
    pub extra: Vec<f64>,
    /// c.
    pub offset: Vec<f64>,
    /// The mesh node each row belongs to.
    pub node: Vec<usize>,
    /// Things the user should know about the discretisation (nodes dropped, ...).
    pub warnings: Vec<String>,
    /// Which rows are tangential, and their friction laws (theory §8.3); empty without
    /// friction, every row then a normal row with λ_i ≥ 0.
    pub friction: FrictionRows,
    /// `Some` when these rows are nodal rows recombined, `g = T⁻¹ g_nodal` (theory §10.1): the
    /// nodal rows and T, from which the active-set solvers build a sparse change of basis.
    pub combination: Option<Box<RowCombination>>,
}

impl ConstraintRows {
    /// No rows, `n_extras` extra unknowns.
    pub fn new(n_extras: usize) -> Self {
        Self { n_extras, row_ptr: vec![0], ..Default::default() }
    }

    /// Number of rows.
    pub fn n_rows(&self) -> usize {
        self.offset.len()
    }

    /// Appends the row Σ entries·u + extras·V + offset ≥ 0 of `node`.
    pub fn push(&mut self, entries: &[(usize, f64)], extras: &[f64], offset: f64, node: usize) {
        assert_eq!(extras.len(), self.n_extras);
        for &(j, v) in entries {
            self.col.push(j);
            self.val.push(v);
        }
        self.row_ptr.push(self.col.len());
        self.extra.extend_from_slice(extras);
        self.offset.push(offset);
        self.node.push(node);
    }

    /// Appends row i of `other` (its G row, offset and node) with the H row `extras`: a row
    /// kept or moved from other rows, without an entry list per row.
    pub fn push_row_of(&mut self, other: &ConstraintRows, i: usize, extras: &[f64]) {
        assert_eq!(extras.len(), self.n_extras);
        let (cols, vals) = other.row(i);
        self.col.extend_from_slice(cols);
        self.val.extend_from_slice(vals);
        self.row_ptr.push(self.col.len());
        self.extra.extend_from_slice(extras);
        self.offset.push(other.offset[i]);
        self.node.push(other.node[i]);
    }

    /// True when some rows are tangential rows of a friction law (theory §8.3).
    pub fn has_friction(&self) -> bool {
        !self.friction.is_empty()
    }

    /// Row i of G as (columns, values).
    pub fn row(&self, i: usize) -> (&[usize], &[f64]) {
        let r = self.row_ptr[i]..self.row_ptr[i + 1];
        (&self.col[r.clone()], &self.val[r])
    }

    /// Row i of H.
    pub fn extra_row(&self, i: usize) -> &[f64] {
        &self.extra[i * self.n_extras..(i + 1) * self.n_extras]
    }

    /// (G u)_i: row i's part in u, the displacement of its node along the row's normal, away
    /// from the obstacle.
    pub fn row_times(&self, i: usize, u: &[f64]) -> f64 {
        let (cols, vals) = self.row(i);
        cols.iter().zip(vals).map(|(&j, a)| a * u[j]).sum()
    }

    /// g = G u + H V + c.
    pub fn gap(&self, u: &[f64], v: &[f64], g: &mut [f64]) {
        for (i, gi) in g.iter_mut().enumerate() {
            let gv: f64 = self.extra_row(i).iter().zip(v).map(|(h, x)| h * x).sum();
            *gi = self.row_times(i, u) + gv + self.offset[i];
        }
    }

    /// fu += Gᵀλ, fv += Hᵀλ.
    pub fn add_transpose(&self, lambda: &[f64], fu: &mut [f64], fv: &mut [f64]) {
        for (i, &l) in lambda.iter().enumerate() {
            let (cols, vals) = self.row(i);
            for (&j, a) in cols.iter().zip(vals) {
                fu[j] += a * l;
            }
            for (f, h) in fv.iter_mut().zip(self.extra_row(i)) {
                *f += h * l;
            }
        }
    }
}

/// The contact set of the normal rows of `rows` with multipliers `lambda` (theory §8.3): as
/// [`contact_set`], tangential rows left out.
pub fn normal_contact_set(rows: &ConstraintRows, lambda: &[f64]) -> Vec<usize> {
    if !rows.has_friction() {
        return contact_set(lambda);
    }
    let tangential = rows.friction.tangential_mask(rows.n_rows());
    let lmax = lambda.iter().zip(&tangential).filter(|(_, t)| !**t).map(|(l, _)| *l).fold(0.0, f64::max);
    (0..lambda.len()).filter(|&i| !tangential[i] && lmax > 0.0 && lambda[i] > 1e-8 * lmax).collect()
}

/// The contact set of a multiplier vector: rows with λ_i > 1e-8 · max λ. The relative
/// threshold makes the set the same for solvers that agree to 1e-8.
pub fn contact_set(lambda: &[f64]) -> Vec<usize> {
    let lmax = lambda.iter().copied().fold(0.0, f64::max);
    (0..lambda.len()).filter(|&i| lmax > 0.0 && lambda[i] > 1e-8 * lmax).collect()
}

/// What an obstacle reports about a solution.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContactReport {
    /// Named scalars, each obstacle its own (`U`, `force`, …); reports list them by name.
    pub quantities: Vec<(String, f64)>,
    /// Number of contact nodes (see [`contact_set`]).
    pub contact_nodes: usize,
    /// Largest distance of a contact node from the obstacle's own centre (as the obstacle
    /// defines it; 0 without contact).
    pub contact_radius: f64,
    /// Things the user should know (contact reaching the rim of the candidate zone, ...).
    pub warnings: Vec<String>,
}

impl ContactReport {
    /// The quantity named `name`, if reported.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.quantities.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
    }
}

/// K: admissible displacements with extra unknowns and a load term, chosen by `type` in the
/// `[obstacle]` table of a scene.
#[typetag::serde(tag = "type")]
pub trait AdmissibleDisplacements: Debug + Send + Sync + dyn_clone::DynClone {
    /// The `type` name of the plugin in scene files.
    fn name(&self) -> &'static str {
        self.typetag_name()
    }

    /// Checks the parameters; `path` is the table's path in the scene (`obstacle`).
    fn validate(&self, path: &str) -> Result<(), ParameterError>;

    /// Names of the extra unknowns V (the force-controlled punch: `["U"]`).
    fn extra_names(&self) -> Vec<String>;

    /// The load term ℓ(V) = f·V of the Lagrangian (1.11): the coefficients f (`[F]`).
    fn load(&self) -> Vec<f64>;

    /// K_h on a mesh (theory §3): the rows g(u, V) ≥ 0. Errors name `path`'s fields (a contact
    /// zone with no nodes, a missing group).
    fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError>;

    /// g(u, V) evaluated directly from the geometry at the nodes of `rows` (the current position
    /// of each node against the obstacle). The rows of [`AdmissibleDisplacements::discretise`]
    /// must be its linearisation; the conformance kit of `saddle-contact` checks this.
    fn gap(&self, mesh: &TetMesh, dofs: &DofMap, rows: &ConstraintRows, u: &[f64], extras: &[f64], out: &mut [f64]);

    /// What to report about a solution (U, force, contact set and radius, warnings).
    fn report(&self, mesh: &TetMesh, rows: &ConstraintRows, extras: &[f64], lambda: &[f64]) -> ContactReport;

    /// The same obstacle with its load multiplied by `factor` (a prescribed force, or a
    /// prescribed displacement of a displacement-controlled obstacle), for load sweeps and
    /// load paths; `None` (the default) when the plugin has no load to scale.
    fn scaled_load(&self, factor: f64) -> Option<Box<dyn AdmissibleDisplacements>> {
        let _ = factor;
        None
    }

    /// The names of this obstacle's loads that a load path may give factors of their own
    /// ([`AdmissibleDisplacements::scaled_loads`], theory §11.2: a sphere's `F` and `Q`); none
    /// (the default): the whole load follows the path's one factor.
    fn load_names(&self) -> Vec<String> {
        Vec::new()
    }

    /// The same obstacle with each load of [`AdmissibleDisplacements::load_names`] multiplied by
    /// its factor `factors.of(name)` (theory §11.2); the default scales the whole load by
    /// `factors.all` ([`AdmissibleDisplacements::scaled_load`]), right for a plugin without
    /// load names.
    fn scaled_loads(&self, factors: &LoadFactors) -> Option<Box<dyn AdmissibleDisplacements>> {
        self.scaled_load(factors.all)
    }

    /// [`AdmissibleDisplacements::rows_at_factor`] for loads with factors of their own: with one
    /// factor for all, that; else (the default) the obstacle of
    /// [`AdmissibleDisplacements::scaled_loads`] discretised again, which is always right.
    fn rows_at_factors<'r>(
        &self,
        factors: &LoadFactors,
        rows: &'r ConstraintRows,
        mesh: &TetMesh,
        dofs: &DofMap,
        path: &str,
    ) -> Result<Cow<'r, ConstraintRows>, SceneError> {
        if factors.is_uniform() {
            return self.rows_at_factor(factors.all, rows, mesh, dofs, path);
        }
        discretise_scaled(self.scaled_loads(factors), self.name(), mesh, dofs, path)
    }

    /// K_h of this obstacle with its load multiplied by `factor` (theory §11.2), from `rows`, its
    /// rows at its own load: what a load step or a sweep point solves. The default discretises
    /// the scaled obstacle ([`AdmissibleDisplacements::scaled_load`]) again, which is always
    /// right. An obstacle whose rows do not depend on its load (force control: only f scales)
    /// returns `rows` borrowed; one whose offsets carry a prescribed displacement recomputes only
    /// those. The K conformance kit checks the result against the default.
    fn rows_at_factor<'r>(
        &self,
        factor: f64,
        rows: &'r ConstraintRows,
        mesh: &TetMesh,
        dofs: &DofMap,
        path: &str,
    ) -> Result<Cow<'r, ConstraintRows>, SceneError> {
        let _ = rows;
        discretise_scaled(self.scaled_load(factor), self.name(), mesh, dofs, path)
    }
}

/// The rows of an obstacle plugin `name` at a scaled load (`scaled`), or the error on `path`
/// that it cannot scale its load.
fn discretise_scaled(
    scaled: Option<Box<dyn AdmissibleDisplacements>>,
    name: &str,
    mesh: &TetMesh,
    dofs: &DofMap,
    path: &str,
) -> Result<Cow<'static, ConstraintRows>, SceneError> {
    let scaled = scaled.ok_or_else(|| {
        ParameterError::new(
            path,
            format!("type = {name:?}"),
            "this obstacle plugin cannot scale its load (AdmissibleDisplacements::scaled_load is None)",
        )
    })?;
    scaled.discretise(mesh, dofs, path).map(Cow::Owned)
}

dyn_clone::clone_trait_object!(AdmissibleDisplacements);

/// (node, status) of every friction block (theory §8.3) of `rows` for the multipliers `lambda`.
pub fn contact_status(rows: &ConstraintRows, lambda: &[f64]) -> Vec<(usize, ContactStatus)> {
    let mut in_contact = vec![false; rows.n_rows()];
    normal_contact_set(rows, lambda).into_iter().for_each(|i| in_contact[i] = true);
    let fr = &rows.friction;
    fr.blocks
        .iter()
        .map(|b| {
            let r = fr.law(b).radius(b.weight, lambda[b.normal]);
            let status = if !in_contact[b.normal] {
                ContactStatus::Separated
            } else if lambda[b.tangent].hypot(lambda[b.tangent + 1]) < (1.0 - SLIP_TOL) * r {
                ContactStatus::Stick
            } else {
                ContactStatus::Slip
            };
            (rows.node[b.normal], status)
        })
        .collect()
}

// ---- rows recombined from nodal rows (theory §10.1, §8.1) ----
//
// `g̃ = T⁻¹ g`, where g are an
// obstacle's nodal rows and T a sparse, explicitly invertible matrix that an element supplies
// (the dual quadratic rows of P2: vertex rows kept, an edge row `(g_e − α(g_a + g_b))/(1 − 2α)`).
//
// T has one level: each row of T is either the unit row of its own row (the row is **kept**)
// or a combination `T_ii e_i + Σ_k T_ik e_k` of kept rows k with `T_ii ≠ 0`. Then T⁻¹ is as
// sparse as T (`S_ii = 1/T_ii`, `S_ik = −T_ik/T_ii`), and so are the forces `λ = T⁻ᵀ λ̃` and the
// change of basis of the active-set solvers built from it (theory §8.1).

/// The nodal rows of recombined rows and T: `g_nodal = T g̃`, T of one level (see the comment above).
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
        let kept = |k: usize| Self::is_kept_row(&t[k], k);
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

    /// Row `r` of T is the unit row of its own row `i`: row i is kept, not recombined.
    fn is_kept_row(r: &[(usize, f64)], i: usize) -> bool {
        r.len() == 1 && r[0] == (i, 1.0)
    }

    /// Row i is kept (its row of T the unit row), not recombined.
    pub fn is_kept(&self, i: usize) -> bool {
        Self::is_kept_row(&self.t[i], i)
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
mod combination_tests {
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
