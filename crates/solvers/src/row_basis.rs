//! General contact rows made slave coordinates (theory §8): a change of basis of the displacement
//! dofs, `x = T y`, in which every contact row acts on one coordinate of its own,
//! `g_i = a_i y_{s_i} + H_i V + c_i`. Active-set methods (Newton, the penalty's Newton) then
//! impose an active row by fixing one coordinate, exactly as for the axis-aligned punch, and
//! stay exact and sparse for rows that act on several dofs (a normal that is not an axis) and
//! for dofs shared by several rows (two obstacles touching one node).
//!
//! The rows are grouped into **blocks**: connected sets of rows and the dofs they act on (two
//! rows are connected when they share a dof). A block of one row on one dof needs no change of
//! basis: its coordinate is the dof itself, its coefficient a_i = G_{i s}. That is the punch, and
//! then T = I and nothing here costs anything. In any other block, with dofs D (d of them) and
//! rows R (r ≤ d, linearly independent), the new coordinates of D are
//!
//! ```text
//! y_D = T_D⁻¹ x_D,   T_D⁻¹ = [ G_R ]   (the rows themselves, a_i = 1)
//!                            [ N   ]   (an orthonormal basis of the complement of their span)
//! ```
//!
//! so that y_i = G_i x for the block's rows. In the new coordinates the stiffness is `TᵀKT` and
//! the gradient `Tᵀ∇E`. T is block diagonal, so `TᵀKT` couples what K couples, widened to whole
//! blocks: for node-to-obstacle rows (a block is the dofs of one node) the pattern of L is
//! unchanged. Its pattern and the recipe of its values are built once (symbolic/numeric
//! split): each step only re-weights K's values.
//!
//! **Recombined rows** (`rows.combination`, theory §8.1, §10.1: P2's dual quadratic rows) are
//! `g̃ = T⁻¹ g` of nodal rows g, with a sparse T of one level. An edge row then acts on three
//! nodes, and a contact zone would be one block; instead the blocks are built for the nodal
//! rows, and a sparse second factor T_C recombines their coordinates: `x = T_D T_C z`, with
//! `z_{s_i} = G̃_i x`. T_C couples a row's coordinate with those of the rows it combines (an
//! edge node and its two vertices, which share every element), so TᵀKT keeps K's pattern.
//!
//! Rows that cannot be given coordinates of their own are refused with the rows named: rows
//! acting on no displacement dof, linearly dependent rows in a block (parallel normals of two
//! obstacles at one node: the contact forces are then not unique), and blocks of more than
//! [`MAX_BLOCK_DOFS`] dofs (a row coupling a whole surface; the change of basis would be dense
//! there).

use saddle_core::problem::displacements::RowCombination;
use saddle_core::{ConstraintRows, SolveError, SymmetricPattern};

/// The largest block (dofs coupled through shared rows) given a dense change of basis. Node-to-
/// obstacle rows give blocks of at most 3 dofs (one node); a node-to-segment rule a few nodes'
/// worth. Beyond this the dense d × d blocks of T and of TᵀKT would cost more than they save.
pub const MAX_BLOCK_DOFS: usize = 48;

/// Relative size below which a row's component outside the span of the block's other rows
/// counts as zero (linearly dependent rows): far above the round-off of the Gram–Schmidt
/// sweep (ε_mach ≈ 2e-16 times a few rows), far below any real angle between contact normals
/// (1e-8 rad).
pub const DEPENDENCE_TOL: f64 = 1e-8;

/// A block's dofs (sorted) and its T_D (row-major, x_D = T_D y_D).
pub type DenseBlock = (Vec<usize>, Vec<f64>);

/// A block of dofs with a dense change of basis.
#[derive(Clone, Debug)]
struct Block {
    /// Its dofs, sorted; the new coordinates reuse these indices (rows first).
    dofs: Vec<usize>,
    /// T_D (x_D = T_D y_D), row-major d × d.
    t: Vec<f64>,
    /// T_D⁻¹, row-major d × d.
    t_inv: Vec<f64>,
}

/// The sparse change of basis T_C of rows recombined from nodal rows, `g̃ = T⁻¹ g` (theory
/// §8.1, §10.1): after the blocks have made every nodal row k a coordinate, `G_k x = a_k y_{s_k}`,
/// a recombined row i gets the coordinate `z_{s_i} = G̃_i x = Σ_k S_ik a_k y_{s_k}` (S = T⁻¹);
/// kept rows keep theirs. A combined row mixes only kept rows' coordinates and its own, so
/// T_C and T_C⁻¹ are applied in place, in any order.
#[derive(Clone, Debug, Default)]
struct Mix {
    /// For each recombined row: its coordinate s_i, the row s_i of T_C (y = T_C z) and of T_C⁻¹.
    rows: Vec<MixRow>,
    /// The entry of `rows` of each coordinate (`usize::MAX`: a coordinate T_C keeps).
    of: Vec<usize>,
}

impl Mix {
    /// T_C for the recombination `c` of nodal rows made coordinates `dof` with coefficients
    /// `coef` (module docs); the recombined rows' coefficients become 1.
    fn new(c: &RowCombination, n: usize, dof: &[usize], coef: &mut [f64]) -> Self {
        let mut mix = Self { rows: Vec::new(), of: vec![usize::MAX; n] };
        for (i, t) in c.t.iter().enumerate().filter(|&(i, _)| !c.is_kept(i)) {
            // y_{s_i} = (T_ii z_{s_i} + Σ_k T_ik a_k z_{s_k}) / a_i,  z_{s_i} = Σ_k S_ik a_k y_{s_k}
            let forward = t.iter().map(|&(k, w)| (dof[k], if k == i { w } else { w * coef[k] } / coef[i])).collect();
            let inverse = c.inverse_row(i).map(|(k, s)| (dof[k], s * coef[k])).collect();
            mix.of[dof[i]] = mix.rows.len();
            mix.rows.push(MixRow { s: dof[i], forward, inverse });
            // only row i itself reads a_i (the others combine kept rows), so it can change now
            coef[i] = 1.0;
        }
        mix
    }

    /// v ← M v with M = T_C (`inverse` false) or T_C⁻¹ (true).
    fn apply(&self, v: &mut [f64], inverse: bool) {
        for r in &self.rows {
            v[r.s] = r.of(inverse).iter().map(|&(c, w)| w * v[c]).sum();
        }
    }

    /// v ← Mᵀ v with M = T_C (`inverse` false) or T_C⁻¹ (true).
    fn apply_transpose(&self, v: &mut [f64], inverse: bool) {
        // a row adds to kept coordinates and its own only: the rows never read each other's
        for r in &self.rows {
            let x = std::mem::take(&mut v[r.s]);
            r.of(inverse).iter().for_each(|&(c, w)| v[c] += w * x);
        }
    }

    /// An upper bound of cond₂(T_C): (‖T_C‖₁‖T_C‖_∞‖T_C⁻¹‖₁‖T_C⁻¹‖_∞)^{1/2}, 1 without rows.
    fn condition(&self) -> f64 {
        (self.norms(false) * self.norms(true)).sqrt()
    }

    /// ‖M‖₁‖M‖_∞ of M = T_C (`inverse` false) or T_C⁻¹ (true); kept coordinates are unit rows.
    fn norms(&self, inverse: bool) -> f64 {
        let mut col: std::collections::HashMap<usize, f64> = Default::default();
        let mut row_max: f64 = 1.0;
        for r in &self.rows {
            let m = r.of(inverse);
            row_max = row_max.max(m.iter().map(|e| e.1.abs()).sum());
            for &(c, w) in m {
                *col.entry(c).or_insert(if self.of[c] == usize::MAX { 1.0 } else { 0.0 }) += w.abs();
            }
        }
        row_max * col.values().copied().fold(1.0, f64::max)
    }
}

/// A recombined row's coordinate s_i and the rows s_i of T_C (`forward`, y = T_C z) and of
/// T_C⁻¹ (`inverse`), as (coordinate, weight), its own first.
#[derive(Clone, Debug)]
struct MixRow {
    s: usize,
    forward: Vec<(usize, f64)>,
    inverse: Vec<(usize, f64)>,
}

impl MixRow {
    /// The row of T_C⁻¹ (`inverse`) or of T_C.
    fn of(&self, inverse: bool) -> &[(usize, f64)] {
        if inverse { &self.inverse } else { &self.forward }
    }
}

/// How each entry of TᵀKT is computed from the entries of K (built once).
#[derive(Clone, Debug)]
struct Recipe {
    /// Position in the new pattern of each entry of K that touches no block (else `usize::MAX`).
    copy: Vec<usize>,
    /// Sums for the entries that touch a block: (new entry, entry of K, weight).
    terms: Vec<(usize, usize, f64)>,
}

/// The change of basis of theory §8 for a set of contact rows (module docs).
#[derive(Clone, Debug)]
pub struct RowBasis {
    n: usize,
    /// The coordinate s_i of each row.
    pub dof: Vec<usize>,
    /// a_i: g_i = a_i y_{s_i} + H_i V + c_i.
    pub coef: Vec<f64>,
    blocks: Vec<Block>,
    /// Block of each dof (`usize::MAX`: none).
    block_of: Vec<usize>,
    /// The rows recombined from nodal rows (theory §8.1, §10.1), after the blocks: T_C (boxed:
    /// a basis travels inside the solvers' projectors, which stay small without recombination).
    mix: Box<Mix>,
    /// The pattern of TᵀKT and the recipe of its values (`None`: T = I).
    transformed: Option<(SymmetricPattern, Recipe)>,
    /// The largest condition number of a block's T (1 when T = I).
    condition: f64,
}

impl RowBasis {
    /// The change of basis for `rows` on `n` dofs with L's pattern `p`; errors name `solver`
    /// and the rows it cannot handle.
    pub fn new(rows: &ConstraintRows, n: usize, p: &SymmetricPattern, solver: &str) -> Result<Self, SolveError> {
        let unsupported = |message: String| SolveError::Unsupported { solver: solver.into(), message };
        let combination = rows.combination.as_deref();
        // recombined rows: the blocks make the nodal rows coordinates, T_C recombines them
        let rows = combination.map_or(rows, |c| &c.nodal);
        let nr = rows.n_rows();
        // rows and dofs connected through shared dofs: union–find over dofs
        let mut parent: Vec<usize> = (0..n).collect();
        fn root(parent: &mut [usize], mut x: usize) -> usize {
            while parent[x] != x {
                parent[x] = parent[parent[x]];
                x = parent[x];
            }
            x
        }
        let nonzero = |i: usize| {
            let (cols, vals) = rows.row(i);
            cols.iter().zip(vals).filter(|(_, v)| **v != 0.0).map(|(&c, &v)| (c, v))
        };
        let mut rows_on = vec![0usize; n];
        for i in 0..nr {
            let mut first = None;
            for (c, _) in nonzero(i) {
                rows_on[c] += 1;
                match first {
                    None => first = Some(c),
                    Some(f) => {
                        let (a, b) = (root(&mut parent, f), root(&mut parent, c));
                        parent[a] = b;
                    }
                }
            }
            if first.is_none() {
                return Err(unsupported(format!(
                    "contact row {i} (node {}) acts on no displacement dof: a constraint on the extra unknowns alone \
                     cannot be given a coordinate of its own",
                    rows.node[i]
                )));
            }
        }
        let mut dof = vec![usize::MAX; nr];
        let mut coef = vec![0.0; nr];
        // trivial blocks: one row on one dof of its own
        let mut block_rows: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for i in 0..nr {
            let nz: Vec<(usize, f64)> = nonzero(i).collect();
            if nz.len() == 1 && rows_on[nz[0].0] == 1 {
                (dof[i], coef[i]) = nz[0];
            } else {
                block_rows.entry(root(&mut parent, nz[0].0)).or_default().push(i);
            }
        }
        let mut block_dofs: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for j in (0..n).filter(|&j| rows_on[j] > 0) {
            let r = root(&mut parent, j);
            if block_rows.contains_key(&r) {
                block_dofs.entry(r).or_default().push(j);
            }
        }
        let mut blocks = Vec::with_capacity(block_rows.len());
        let mut block_of = vec![usize::MAX; n];
        for (r, members) in &block_rows {
            let dofs = &block_dofs[r];
            let block = Self::block(rows, members, dofs).map_err(unsupported)?;
            for (k, &i) in members.iter().enumerate() {
                (dof[i], coef[i]) = (dofs[k], 1.0);
            }
            for &j in dofs {
                block_of[j] = blocks.len();
            }
            blocks.push(block);
        }
        let mix = Box::new(combination.map_or_else(Mix::default, |c| Mix::new(c, n, &dof, &mut coef)));
        let condition = blocks
            .iter()
            .map(|b| {
                let d = b.dofs.len();
                let sv = nalgebra::DMatrix::from_row_slice(d, d, &b.t).singular_values();
                sv.max() / sv.min()
            })
            .fold(1.0, f64::max)
            * mix.condition();
        let mut basis = Self { n, dof, coef, blocks, block_of, mix, transformed: None, condition };
        if !basis.blocks.is_empty() || !basis.mix.rows.is_empty() {
            basis.transformed = Some(basis.recipe(p));
        }
        Ok(basis)
    }

    /// The change of basis of one block: rows `members` on the sorted `dofs` (module docs).
    fn block(rows: &ConstraintRows, members: &[usize], dofs: &[usize]) -> Result<Block, String> {
        let (d, r) = (dofs.len(), members.len());
        let nodes = || members.iter().map(|&i| rows.node[i]).collect::<Vec<_>>();
        if d > MAX_BLOCK_DOFS {
            return Err(format!(
                "contact rows {members:?} (nodes {:?}) couple {d} displacement dofs through shared dofs, more than \
                 {MAX_BLOCK_DOFS}: rows acting on whole surfaces are not supported by this solver (uzawa handles them)",
                nodes()
            ));
        }
        let dependent = || {
            format!(
                "contact rows {members:?} (nodes {:?}) are linearly dependent (e.g. two obstacles with parallel normals \
                 at one node, or more rows than dofs): their contact forces are not unique, and this solver needs \
                 independent rows; uzawa handles them",
                nodes()
            )
        };
        if r > d {
            return Err(dependent());
        }
        let local = |j: usize| dofs.binary_search(&j).expect("a row's dof is in its block");
        // T⁻¹ = [G_R; N]: the rows, then an orthonormal completion (modified Gram–Schmidt with
        // re-orthogonalisation over an orthonormal basis q of the span so far)
        let mut t_inv = vec![0.0; d * d];
        let mut q: Vec<Vec<f64>> = Vec::with_capacity(d);
        let project_out = |v: &mut [f64], q: &[Vec<f64>]| {
            for _ in 0..2 {
                for b in q {
                    let c: f64 = v.iter().zip(b).map(|(x, y)| x * y).sum();
                    v.iter_mut().zip(b).for_each(|(x, y)| *x -= c * y);
                }
            }
        };
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        for (k, &i) in members.iter().enumerate() {
            let (cols, vals) = rows.row(i);
            let mut g = vec![0.0; d];
            for (&c, &v) in cols.iter().zip(vals) {
                if v != 0.0 {
                    g[local(c)] += v;
                }
            }
            t_inv[k * d..(k + 1) * d].copy_from_slice(&g);
            let size = norm(&g);
            project_out(&mut g, &q);
            let rest = norm(&g);
            if rest <= DEPENDENCE_TOL * size {
                return Err(dependent());
            }
            g.iter_mut().for_each(|x| *x /= rest);
            q.push(g);
        }
        // completion: the unit vectors that keep the most outside the span, in turn
        for k in r..d {
            let best = (0..d)
                .map(|e| {
                    let mut v = vec![0.0; d];
                    v[e] = 1.0;
                    project_out(&mut v, &q);
                    (norm(&v), v)
                })
                .max_by(|a, b| a.0.total_cmp(&b.0))
                .expect("a block has dofs");
            let (size, mut v) = best;
            v.iter_mut().for_each(|x| *x /= size);
            t_inv[k * d..(k + 1) * d].copy_from_slice(&v);
            q.push(v);
        }
        let m = nalgebra::DMatrix::from_row_slice(d, d, &t_inv);
        let t =
            m.try_inverse().ok_or_else(|| format!("the change of basis of contact rows {members:?} is singular"))?;
        let t: Vec<f64> = (0..d).flat_map(|a| (0..d).map(move |b| (a, b))).map(|(a, b)| t[(a, b)]).collect();
        Ok(Block { dofs: dofs.to_vec(), t, t_inv })
    }

    /// Each block's dofs (sorted) and T_D (row-major, x_D = T_D y_D).
    pub fn blocks(&self) -> impl Iterator<Item = (&[usize], &[f64])> {
        self.blocks.iter().map(|b| (&b.dofs[..], &b.t[..]))
    }

    /// This basis with the further blocks `more` (their dofs, sorted, and T_D row-major, on
    /// dofs of no block of this one), and the recipe of TᵀKT on `p`: a rank's change of basis
    /// on its local dofs, its ghost nodes' blocks received from their owners (theory §12.2).
    /// An error when a T_D is singular.
    pub fn with_blocks(&self, more: Vec<DenseBlock>, p: &SymmetricPattern) -> Result<Self, String> {
        if !self.mix.rows.is_empty() {
            return Err("recombined contact rows (theory §10.1) are not distributed".into());
        }
        let mut basis = self.clone();
        for (dofs, t) in more {
            let d = dofs.len();
            let t_inv = nalgebra::DMatrix::from_row_slice(d, d, &t)
                .try_inverse()
                .ok_or_else(|| format!("the change of basis received for dofs {dofs:?} is singular"))?;
            let t_inv = (0..d).flat_map(|a| (0..d).map(move |b| (a, b))).map(|(a, b)| t_inv[(a, b)]).collect();
            for &j in &dofs {
                debug_assert_eq!(basis.block_of[j], usize::MAX, "dof {j} is in two blocks");
                basis.block_of[j] = basis.blocks.len();
            }
            basis.blocks.push(Block { dofs, t, t_inv });
        }
        basis.transformed = (!basis.blocks.is_empty()).then(|| basis.recipe(p));
        Ok(basis)
    }

    /// The pattern of TᵀKT and the recipe of its values from K's (module docs).
    fn recipe(&self, p: &SymmetricPattern) -> (SymmetricPattern, Recipe) {
        let (cp, ri) = (p.col_ptr(), p.row_idx());
        // x_j = Σ_a T_ja y_a: the coordinates a dof is made of
        let coords = |j: usize| -> Vec<(usize, f64)> {
            let y: Vec<(usize, f64)> = match self.block_of[j] {
                usize::MAX => vec![(j, 1.0)],
                b => {
                    let blk = &self.blocks[b];
                    let (d, lj) = (blk.dofs.len(), blk.dofs.binary_search(&j).unwrap());
                    (0..d).map(|a| (blk.dofs[a], blk.t[lj * d + a])).filter(|(_, w)| *w != 0.0).collect()
                }
            };
            // then y = T_C z
            y.into_iter()
                .flat_map(|(a, w)| match self.mix.of.get(a).copied().unwrap_or(usize::MAX) {
                    usize::MAX => vec![(a, w)],
                    m => self.mix.rows[m].forward.iter().map(|&(c, v)| (c, w * v)).collect(),
                })
                .collect()
        };
        // (K')_ab += T_ia K_ij T_jb over both triangles of K, kept for a ≥ b
        let mut touched: Vec<(usize, usize, usize, f64)> = Vec::new(); // (column b, row a, entry, weight)
        let mut plain: Vec<(usize, usize, usize)> = Vec::new(); // (column, row, entry)
        for j in 0..p.n() {
            for (q, &i) in ri.iter().enumerate().take(cp[j + 1]).skip(cp[j]) {
                let kept =
                    |k: usize| self.block_of[k] == usize::MAX && self.mix.of.get(k).is_none_or(|&m| m == usize::MAX);
                if kept(i) && kept(j) {
                    plain.push((j, i, q));
                    continue;
                }
                let (ci, cj) = (coords(i), coords(j));
                let mut put = |x: &[(usize, f64)], y: &[(usize, f64)]| {
                    for &(a, ta) in x {
                        for &(b, tb) in y {
                            if a >= b {
                                touched.push((b, a, q, ta * tb));
                            }
                        }
                    }
                };
                put(&ci, &cj);
                if i != j {
                    put(&cj, &ci);
                }
            }
        }
        // the new pattern: K's entries and the touched ones, by column, rows sorted
        let mut keys: Vec<(usize, usize)> =
            plain.iter().map(|&(c, r, _)| (c, r)).chain(touched.iter().map(|&(c, r, _, _)| (c, r))).collect();
        keys.sort_unstable();
        keys.dedup();
        let mut col_ptr = vec![0usize; p.n() + 1];
        for &(c, _) in &keys {
            col_ptr[c + 1] += 1;
        }
        for c in 0..p.n() {
            col_ptr[c + 1] += col_ptr[c];
        }
        let row_idx: Vec<usize> = keys.iter().map(|&(_, r)| r).collect();
        let at = |c: usize, r: usize| col_ptr[c] + row_idx[col_ptr[c]..col_ptr[c + 1]].binary_search(&r).unwrap();
        let mut copy = vec![usize::MAX; p.nnz()];
        for &(c, r, q) in &plain {
            copy[q] = at(c, r);
        }
        let terms = touched.iter().map(|&(c, r, q, w)| (at(c, r), q, w)).collect();
        // every column keeps its diagonal first (T's diagonal blocks are regular)
        let pattern = SymmetricPattern::new(p.n(), col_ptr, row_idx);
        (pattern, Recipe { copy, terms })
    }

    /// For each row: true unless it shares a block with a row of smaller `gap` (ties: the
    /// first). Rows on dofs of their own are always true.
    pub fn closest_in_blocks(&self, gap: &[f64]) -> Vec<bool> {
        let mut best = vec![usize::MAX; self.blocks.len()];
        for (i, &s) in self.dof.iter().enumerate() {
            let b = self.block_of[s];
            if b != usize::MAX && (best[b] == usize::MAX || gap[i] < gap[best[b]]) {
                best[b] = i;
            }
        }
        self.dof
            .iter()
            .enumerate()
            .map(|(i, &s)| self.block_of[s] == usize::MAX || best[self.block_of[s]] == i)
            .collect()
    }

    /// The largest condition number of T's blocks: 1 for rows on dofs of their own, about
    /// 1/θ for two rows at a node whose normals are θ apart. Forces computed through T⁻ᵀ (the
    /// contact reactions) carry the residual of an inexact solve amplified by up to this.
    pub fn condition(&self) -> f64 {
        self.condition
    }

    /// True when T = I (every row on a dof of its own): nothing is transformed.
    pub fn is_identity(&self) -> bool {
        self.transformed.is_none()
    }

    /// The pattern of TᵀKT: `p` (L's) when T = I.
    pub fn pattern<'a>(&'a self, p: &'a SymmetricPattern) -> &'a SymmetricPattern {
        self.transformed.as_ref().map_or(p, |(q, _)| q)
    }

    /// Adds a 2 × 2 block `b` in the units of rows `t`, `t + 1` (a friction pair's slips, theory
    /// §8.3) to `values` on [`RowBasis::pattern`] of L's pattern `p`: `a_i b_ij a_j` at their
    /// coordinates, on the lower triangle (a node's coordinates are coupled in L).
    pub fn add_pair_block(&self, p: &SymmetricPattern, t: usize, b: [[f64; 2]; 2], values: &mut [f64]) {
        let pattern = self.pattern(p);
        let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
        for (i, j) in [(0, 0), (1, 1), (1, 0)] {
            let (si, sj) = (self.dof[t + i], self.dof[t + j]);
            let (row, col) = (si.max(sj), si.min(sj));
            let at = ri[cp[col]..cp[col + 1]].binary_search(&row).expect("a node's coordinates are coupled in L");
            values[cp[col] + at] += self.coef[t + i] * b[i][j] * self.coef[t + j];
        }
    }

    /// `out` = TᵀKT on [`RowBasis::pattern`] from K's values `k` on L's pattern.
    pub fn stiffness(&self, k: &[f64], out: &mut [f64]) {
        match &self.transformed {
            None => out.copy_from_slice(k),
            Some((_, recipe)) => {
                out.iter_mut().for_each(|x| *x = 0.0);
                for (q, &at) in recipe.copy.iter().enumerate() {
                    if at != usize::MAX {
                        out[at] = k[q];
                    }
                }
                for &(at, q, w) in &recipe.terms {
                    out[at] += w * k[q];
                }
            }
        }
    }

    /// `out` = Tᵀ f: a force (gradient) in the new coordinates.
    pub fn force_to_coordinates(&self, f: &[f64], out: &mut [f64]) {
        out.copy_from_slice(f);
        for b in &self.blocks {
            let d = b.dofs.len();
            for a in 0..d {
                out[b.dofs[a]] = (0..d).map(|j| b.t[j * d + a] * f[b.dofs[j]]).sum();
            }
        }
        self.mix.apply_transpose(out, false);
    }

    /// `x` = T y in place: a displacement from the new coordinates.
    pub fn displacement_from_coordinates(&self, y: &mut [f64]) {
        self.mix.apply(y, false);
        self.apply_blocks(y, |b| &b.t);
    }

    /// `y` = T⁻¹ x in place: a displacement in the new coordinates.
    pub fn displacement_to_coordinates(&self, x: &mut [f64]) {
        self.apply_blocks(x, |b| &b.t_inv);
        self.mix.apply(x, true);
    }

    /// `r` = T⁻ᵀ r in place: a force from the new coordinates.
    pub fn force_from_coordinates(&self, r: &mut [f64]) {
        self.mix.apply_transpose(r, true);
        let mut tmp = [0.0; MAX_BLOCK_DOFS];
        for b in &self.blocks {
            let d = b.dofs.len();
            for (j, t) in tmp[..d].iter_mut().enumerate() {
                *t = (0..d).map(|a| b.t_inv[a * d + j] * r[b.dofs[a]]).sum();
            }
            for (&j, t) in b.dofs.iter().zip(&tmp) {
                r[j] = *t;
            }
        }
    }

    /// v_D ← M v_D for every block, with M = `m(block)` row-major. `v` may stop after the
    /// blocks' dofs (a rank's owned dofs, theory §12.2).
    fn apply_blocks(&self, v: &mut [f64], m: impl Fn(&Block) -> &Vec<f64>) {
        debug_assert!(v.len() <= self.n && self.blocks.iter().all(|b| b.dofs.iter().all(|&j| j < v.len())));
        let mut tmp = [0.0; MAX_BLOCK_DOFS];
        for b in &self.blocks {
            let (d, m) = (b.dofs.len(), m(b));
            for (a, t) in tmp[..d].iter_mut().enumerate() {
                *t = (0..d).map(|j| m[a * d + j] * v[b.dofs[j]]).sum();
            }
            for (&j, t) in b.dofs.iter().zip(&tmp) {
                v[j] = *t;
            }
        }
    }

    /// Each row's stiffness in its own direction, (TᵀKT)_{ss} / a_i², from K's values `k`:
    /// force per unit of gap.
    pub fn row_stiffness(&self, p: &SymmetricPattern, k: &[f64]) -> Vec<f64> {
        let mut kt = vec![0.0; self.pattern(p).nnz()];
        self.stiffness(k, &mut kt);
        let diag = self.pattern(p).diagonal(&kt);
        self.dof.iter().zip(&self.coef).map(|(&s, a)| diag[s] / (a * a)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The full 6 × 6 pattern (two nodes of three dofs, every entry coupled).
    fn full(n: usize) -> SymmetricPattern {
        let mut col_ptr = vec![0];
        let mut row_idx = vec![];
        for j in 0..n {
            row_idx.extend(j..n);
            col_ptr.push(row_idx.len());
        }
        SymmetricPattern::new(n, col_ptr, row_idx)
    }

    /// A symmetric positive definite matrix as dense and as lower values on `full(n)`.
    fn spd(n: usize) -> (nalgebra::DMatrix<f64>, Vec<f64>) {
        let b = nalgebra::DMatrix::from_fn(n, n, |i, j| {
            ((i * 7 + j * 3) % 5) as f64 - 1.5 + if i == j { 4.0 } else { 0.0 }
        });
        let k = &b * b.transpose();
        let vals = (0..n).flat_map(|j| (j..n).map(move |i| (i, j))).map(|(i, j)| k[(i, j)]).collect();
        (k, vals)
    }

    /// `basis` is exact for `rows` on the full pattern `p`: G_i x = a_i y_{s_i} for a random x,
    /// T T⁻¹ = I, Tᵀ(Kx) = (TᵀKT)y for a random SPD K, and T⁻ᵀ undoes Tᵀ.
    fn assert_exact(basis: &RowBasis, rows: &ConstraintRows, p: &SymmetricPattern) {
        let n = p.n();
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut y = x.clone();
        basis.displacement_to_coordinates(&mut y);
        let mut g = vec![0.0; rows.n_rows()];
        rows.gap(&x, &vec![0.0; rows.n_extras], &mut g);
        for (i, gi) in g.iter().enumerate() {
            let gx = gi - rows.offset[i];
            assert!((gx - basis.coef[i] * y[basis.dof[i]]).abs() < 1e-14, "row {i}: {gx} vs {}", y[basis.dof[i]]);
        }
        let mut back = y.clone();
        basis.displacement_from_coordinates(&mut back);
        assert!(back.iter().zip(&x).all(|(a, b)| (a - b).abs() < 1e-14));
        // TᵀKT against dense algebra: Tᵀ(Kx) = (TᵀKT)y with x = Ty
        let (k, vals) = spd(n);
        let mut kt = vec![0.0; basis.pattern(p).nnz()];
        basis.stiffness(&vals, &mut kt);
        let mut kty = vec![0.0; n];
        basis.pattern(p).matvec(&kt, &y, &mut kty);
        let kx = &k * nalgebra::DVector::from_column_slice(&x);
        let mut tkx = vec![0.0; n];
        basis.force_to_coordinates(kx.as_slice(), &mut tkx);
        for j in 0..n {
            assert!((tkx[j] - kty[j]).abs() < 1e-12 * kx.amax(), "{j}: {} vs {}", tkx[j], kty[j]);
        }
        // T⁻ᵀ undoes Tᵀ
        basis.force_from_coordinates(&mut tkx);
        assert!(tkx.iter().zip(kx.iter()).all(|(a, b)| (a - b).abs() < 1e-12 * kx.amax()));
    }

    #[test]
    fn rows_become_coordinates_and_the_stiffness_transforms_like_t_transpose_k_t() {
        // dof 0..3 one node, 3..6 another; row 0: a unit normal (0.6, 0, 0.8) on node 0; row 1 on
        // node 0 too (shares dofs): (0, 1, 0.5); row 2: the punch row on dof 5 alone
        let mut rows = ConstraintRows::new(1);
        rows.push(&[(0, 0.6), (2, 0.8)], &[-1.0], 0.1, 0);
        rows.push(&[(1, 1.0), (2, 0.5)], &[0.0], 0.2, 0);
        rows.push(&[(5, 2.0)], &[-1.0], 0.3, 1);
        let p = full(6);
        let basis = RowBasis::new(&rows, 6, &p, "newton").unwrap();
        assert!(!basis.is_identity());
        assert_eq!((basis.dof[2], basis.coef[2]), (5, 2.0));
        assert_exact(&basis, &rows, &p);
    }

    #[test]
    fn recombined_rows_become_coordinates_through_a_sparse_basis() {
        // nodal rows: node 0 a normal (0.6, 0, 0.8) on dofs 0, 2; node 1 the row 2·u₃ (a = 2);
        // node 2 between them (dofs 6..9), a normal (0, 0.6, 0.8); its row recombined as an
        // edge row (g₂ − α(g₀ + g₁))/(1 − 2α) acts on all three nodes
        let mut nodal = ConstraintRows::new(1);
        nodal.push(&[(0, 0.6), (2, 0.8)], &[-1.0], 0.1, 0);
        nodal.push(&[(5, 2.0)], &[-1.0], 0.3, 1);
        nodal.push(&[(7, 0.6), (8, 0.8)], &[-1.0], 0.2, 2);
        let t = vec![vec![(0, 1.0)], vec![(1, 1.0)], vec![(2, 0.6), (0, 0.2), (1, 0.2)]];
        let rows = RowCombination::recombine(nodal, t).unwrap();
        assert_eq!(rows.row(2).0.len(), 5);
        let p = full(9);
        let basis = RowBasis::new(&rows, 9, &p, "newton").unwrap();
        assert_exact(&basis, &rows, &p);
        assert_eq!(basis.coef, vec![1.0, 2.0, 1.0]);
        // cond(T) ≥ 1, bounded by the norms of T_D and T_C
        assert!(basis.condition() >= 1.0 && basis.condition() < 10.0, "{}", basis.condition());
    }

    #[test]
    fn punch_rows_need_no_change_of_basis() {
        let mut rows = ConstraintRows::new(1);
        rows.push(&[(2, 1.0)], &[-1.0], 0.0, 0);
        rows.push(&[(5, 1.0)], &[-1.0], 0.0, 1);
        let p = full(6);
        let basis = RowBasis::new(&rows, 6, &p, "newton").unwrap();
        assert!(basis.is_identity());
        assert_eq!(basis.dof, vec![2, 5]);
    }

    #[test]
    fn dependent_rows_and_rows_without_dofs_are_refused_with_the_rows() {
        let p = full(6);
        let mut rows = ConstraintRows::new(1);
        rows.push(&[(2, 1.0)], &[-1.0], 0.0, 7);
        rows.push(&[(2, 1.0)], &[-2.0], 0.0, 7);
        let e = RowBasis::new(&rows, 6, &p, "newton").unwrap_err().to_string();
        assert!(e.contains("rows [0, 1] (nodes [7, 7]) are linearly dependent"), "{e}");
        let mut rows = ConstraintRows::new(1);
        rows.push(&[(0, 0.6), (2, 0.8)], &[-1.0], 0.0, 3);
        rows.push(&[(0, 1.2), (2, 1.6)], &[0.0], 0.0, 3);
        let e = RowBasis::new(&rows, 6, &p, "penalty").unwrap_err().to_string();
        assert!(e.contains("linearly dependent") && e.contains("penalty"), "{e}");
        let mut rows = ConstraintRows::new(1);
        rows.push(&[], &[-1.0], 0.0, 4);
        let e = RowBasis::new(&rows, 6, &p, "newton").unwrap_err().to_string();
        assert!(e.contains("row 0 (node 4) acts on no displacement dof"), "{e}");
    }

    #[test]
    fn the_condition_is_one_for_single_rows_and_about_one_over_the_angle_for_near_parallel_ones() {
        let p = full(6);
        let mut rows = ConstraintRows::new(0);
        rows.push(&[(0, 0.6), (2, 0.8)], &[], 0.0, 0);
        assert!((RowBasis::new(&rows, 6, &p, "newton").unwrap().condition() - 1.0).abs() < 1e-12);
        let theta: f64 = 1e-3;
        let mut rows2 = ConstraintRows::new(0);
        rows2.push(&[(2, 1.0)], &[], 0.0, 0);
        rows2.push(&[(0, theta.sin()), (2, theta.cos())], &[], 0.0, 0);
        // two unit rows θ apart: T⁻¹ has singular values √(1 ± cos θ) ≈ √2 and θ/√2 on their
        // plane, so cond(T) = cot(θ/2) ≈ 2/θ
        let c = RowBasis::new(&rows2, 6, &p, "newton").unwrap().condition();
        let expected = 1.0 / (theta / 2.0).tan();
        assert!((c - expected).abs() < 1e-6 * expected, "{c} vs {expected}");
    }
}
