//! Smoothed-aggregation algebraic multigrid (Vaněk, Mandel, Brezina 1996) for symmetric
//! positive definite matrices with a known near-nullspace — the elastic stiffness with its
//! rigid-body modes is the case it was tuned on: a V-cycle that is a symmetric positive definite
//! preconditioner for conjugate gradients ([`super::pcg`]), with an iteration count nearly
//! independent of the mesh size. It knows matrices, blocks and vectors only; the caller
//! computes the near-nullspace ([`NearNullSpace`]) from whatever geometry it has.
//!
//! # The idea
//!
//! Relaxation (here a Chebyshev polynomial in D⁻¹A) removes the oscillatory part of the error
//! quickly; what survives is *smooth* error e with A e ≈ 0 — locally, a rigid-body motion. A
//! coarse space must therefore represent the six rigid-body modes (the *near-nullspace* B:
//! three translations and three rotations) on every patch of the mesh. Smoothed aggregation
//! builds such a space from the matrix and B alone:
//!
//! 1. **Strength of connection.** On the graph of nodes (the 3×3 blocks of A; fewer rows where
//!    components are fixed) node j is strongly coupled to i when
//!    ‖A_ij‖_F ≥ θ √(‖A_ii‖_F ‖A_jj‖_F). Weak couplings (across the thin direction of
//!    stretched elements, say) are ignored by the aggregation.
//! 2. **Aggregation.** Pass 1 makes every node whose strong neighbourhood is still untouched
//!    the root of an aggregate {i} ∪ N_i; pass 2 attaches each leftover node to the aggregate
//!    it is most strongly coupled to; pass 3 groups what remains (isolated nodes) with their
//!    free neighbours. Aggregates are disjoint and cover all nodes.
//! 3. **Tentative prolongator.** Restrict B to the rows of each aggregate and factor it,
//!    B_a = Q_a R_a (local QR, dependent columns dropped). The columns of Q_a are the coarse
//!    basis functions of aggregate a, and the rows of R_a the coarse near-nullspace, so that
//!    P_tent B_c = B holds exactly: the coarse space contains the rigid-body modes. Every
//!    aggregate has up to six coarse unknowns, the next level's block.
//! 4. **Prolongator smoothing.** P_tent is piecewise constant (it has energy ∝ h⁻²); one damped
//!    Jacobi step P = (I − ω D⁻¹A) P_tent, ω = 4/(3 ρ(D⁻¹A)), makes the basis functions
//!    overlap and lowers their energy to that of a smooth function, which is what makes the
//!    convergence independent of h. ρ(D⁻¹A) is estimated by Lanczos on D^(−½) A D^(−½).
//! 5. **Galerkin coarse operator.** A_c = Pᵀ A P (two sparse products), and recursively on
//!    A_c with B_c until a few thousand unknowns remain, which are solved by sparse Cholesky.
//!
//! The cycle is a V-cycle with the same Chebyshev polynomial (degree 2–3, on the interval
//! [ρ/30, 1.1 ρ] of the spectrum of D⁻¹A) before and after the coarse correction. A polynomial
//! in D⁻¹A is self-adjoint in the energy inner product, so the cycle is a symmetric positive
//! definite operator: exactly what conjugate gradients needs.
//!
//! # Use
//!
//! ```no_run
//! # use saddle_core::linalg::*;
//! # fn demo(a: &Csr, near_null: &NearNullSpace, b: &[f64]) -> Result<(), Box<dyn std::error::Error>> {
//! let amg = SmoothedAggregation::new(a, near_null, &AmgParams::default())?;
//! let mut pcg = Pcg::new(a.nrows);
//! let mut x = vec![0.0; a.nrows];
//! let report = pcg.solve(&a, &amg, b, &mut x, 1e-8, 200)?;
//! # Ok(()) }
//! ```
//!
//! # Parameters and cost
//!
//! The defaults ([`AmgParams::default`]) were tuned on the default scene's elastic stiffness
//! (graded box, Kuhn tetrahedra): θ = 0.02, Chebyshev degree 2. A larger θ (0.06–0.08)
//! drops the weak couplings of the Kuhn tetrahedra's diagonals, which leaves small aggregates
//! and dense coarse operators (operator complexity 2–4 instead of 1.4) and triples the set-up
//! time for a few iterations less. Degree 3 saves iterations but not time. With the defaults
//! the 45k-, 157k- and 378k-dof versions of the scene take 21, 28 and 28 iterations to
//! 10⁻⁸; set-up is dominated by the two sparse products of the Galerkin operator on the two
//! finest levels, the solve by memory traffic of the fine matrix (four passes per cycle plus
//! the restriction and prolongation). Run `examples/amg_bench.rs` to measure.
//!
//! A new matrix with the same near-nullspace (the next Newton tangent) is taken by
//! [`SmoothedAggregation::refresh`], which keeps the aggregates and tentative prolongators
//! and recomputes the smoothing, the Galerkin products and the coarse factorisation; from then
//! on the cycle smooths with [`AmgParams::tangent_smoother_degree`] (4): the soft modes of a
//! plastic or nearly incompressible tangent are not in the coarse space, and a higher-degree
//! Chebyshev polynomial damps more of the low spectrum of D⁻¹A per cycle (Adams, Brezina, Hu,
//! Tuminaro, "Parallel multigrid smoothing: polynomial versus Gauss–Seidel", J. Comput. Phys.
//! 188, 2003; measured in docs/plastic_tangent.md).

use super::cholesky::SparseCholesky;
use super::csr::{Csr, LowerCsc};
use super::csr32::Csr32;
use super::error::AmgError;
use super::pcg::Preconditioner;
use crate::error::{ParameterError, check};
use rayon::prelude::*;
use std::sync::Mutex;

/// Default [`AmgParams::tangent_smoother_degree`] (measured: docs/plastic_tangent.md, issue 27).
pub const TANGENT_SMOOTHER_DEGREE: usize = 4;

/// Rows per parallel task of the smoother.
const CHUNK: usize = 4096;

/// The Chebyshev interval ends at this multiple of the Lanczos estimate of ρ(D⁻¹A).
const UPPER_SAFETY: f64 = 1.1;

/// The near-nullspace of a matrix with a block structure: the vectors a coarse space must
/// reproduce (for elasticity, the rigid-body modes), and the block of every unknown (for
/// elasticity, its node). Linear algebra only: whoever knows the geometry computes the vectors.
#[derive(Clone, Debug, PartialEq)]
pub struct NearNullSpace {
    /// Block (0, 1, …) of every unknown; unknowns of one block are aggregated together.
    pub block: Vec<u32>,
    /// The vectors, row-major `n × dim`: row d holds the d-th entry of every vector.
    pub vectors: Vec<f64>,
    /// Number of vectors.
    pub dim: usize,
}

impl NearNullSpace {
    /// Checks the sizes: `vectors.len() == block.len() · dim`, `dim ≥ 1`.
    pub fn new(block: Vec<u32>, vectors: Vec<f64>, dim: usize) -> Result<Self, AmgError> {
        if dim == 0 || vectors.len() != block.len() * dim {
            return Err(AmgError::DimensionMismatch {
                what: format!("near-nullspace ({dim} vectors)"),
                expected: block.len() * dim.max(1),
                found: vectors.len(),
            });
        }
        Ok(Self { block, vectors, dim })
    }

    /// Number of unknowns.
    pub fn n(&self) -> usize {
        self.block.len()
    }

    /// The unknowns grouped by block (block numbers compacted, empty blocks left out).
    fn blocks(&self) -> Blocks {
        let n_ids = self.block.iter().map(|&b| b as usize + 1).max().unwrap_or(0);
        let mut id = vec![u32::MAX; n_ids];
        let mut of_dof = vec![0u32; self.n()];
        let mut nb = 0u32;
        for (d, &b) in self.block.iter().enumerate() {
            if id[b as usize] == u32::MAX {
                id[b as usize] = nb;
                nb += 1;
            }
            of_dof[d] = id[b as usize];
        }
        Blocks::from_owner(of_dof, nb as usize)
    }
}

/// Parameters of the smoothed-aggregation hierarchy and its V-cycle. As a scene table (a
/// solver's `amg`) every field is optional, its default below.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AmgParams {
    /// θ of the strength of connection ‖A_ij‖_F ≥ θ √(‖A_ii‖_F ‖A_jj‖_F).
    pub strength_threshold: f64,
    /// Degree of the Chebyshev smoother (matrix–vector products per smoothing).
    pub smoother_degree: usize,
    /// Degree of the Chebyshev smoother once the hierarchy has been rebuilt on a tangent
    /// ([`SmoothedAggregation::refresh`]): the soft, nearly isochoric modes of a plastic or
    /// nearly incompressible tangent, absent from the rigid-body coarse space, are left to the
    /// smoother (theory §4.2).
    pub tangent_smoother_degree: usize,
    /// λ_max / λ_min of the Chebyshev interval [ρ / range, ρ] (1.1 × the estimate of ρ).
    pub smoother_range: f64,
    /// Lanczos steps for ρ(D⁻¹A).
    pub eigen_steps: usize,
    /// Coarsen until at most this many unknowns remain, then factorise.
    pub coarse_size: usize,
    /// At most this many levels (the last one solved directly).
    pub max_levels: usize,
}

impl Default for AmgParams {
    fn default() -> Self {
        Self {
            strength_threshold: 0.02,
            smoother_degree: 2,
            tangent_smoother_degree: TANGENT_SMOOTHER_DEGREE,
            smoother_range: 30.0,
            eigen_steps: 12,
            coarse_size: 3000,
            max_levels: 10,
        }
    }
}

impl AmgParams {
    /// Checks the ranges; errors name the field (`amg.strength_threshold`, …).
    pub fn validate(&self) -> Result<(), ParameterError> {
        check::non_negative("amg", "strength_threshold", self.strength_threshold)?;
        if self.strength_threshold >= 1.0 {
            return Err(ParameterError::new("amg.strength_threshold", self.strength_threshold, "must be < 1"));
        }
        if !(self.smoother_range.is_finite() && self.smoother_range > 1.0) {
            return Err(ParameterError::new("amg.smoother_range", self.smoother_range, "must be a finite number > 1"));
        }
        for (field, v, min) in [
            ("smoother_degree", self.smoother_degree, 1),
            ("tangent_smoother_degree", self.tangent_smoother_degree, 1),
            ("eigen_steps", self.eigen_steps, 2),
            ("coarse_size", self.coarse_size, 1),
            ("max_levels", self.max_levels, 1),
        ] {
            if v < min {
                return Err(ParameterError::new(format!("amg.{field}"), v, format!("must be >= {min}")));
            }
        }
        Ok(())
    }
}

/// A partition of one level's unknowns into blocks: nodes on the finest level, aggregates
/// (up to six coarse unknowns each) below.
#[derive(Clone, Debug)]
struct Blocks {
    ptr: Vec<usize>,
    dofs: Vec<u32>,
    of_dof: Vec<u32>,
}

impl Blocks {
    /// The blocks of `owner[d]` (every owner in 0..n used).
    fn from_owner(owner: Vec<u32>, n: usize) -> Self {
        let mut ptr = vec![0usize; n + 1];
        for &o in &owner {
            ptr[o as usize + 1] += 1;
        }
        for i in 0..n {
            ptr[i + 1] += ptr[i];
        }
        let mut fill = ptr.clone();
        let mut dofs = vec![0u32; owner.len()];
        for (d, &o) in owner.iter().enumerate() {
            dofs[fill[o as usize]] = d as u32;
            fill[o as usize] += 1;
        }
        Self { ptr, dofs, of_dof: owner }
    }

    fn len(&self) -> usize {
        self.ptr.len() - 1
    }

    fn of(&self, b: usize) -> &[u32] {
        &self.dofs[self.ptr[b]..self.ptr[b + 1]]
    }
}

/// One level of the hierarchy with its transfer to the next coarser one. The operators of the
/// cycle are stored in single precision
/// ([`Csr32`]: a V-cycle is bound by memory traffic); the set-up works in double precision.
#[derive(Debug)]
struct Level {
    a: Csr32,
    inv_diag: Vec<f64>,
    /// Estimate of ρ(D⁻¹A).
    lambda_max: f64,
    p_tent: Csr,
    /// P = (I − ω D⁻¹A) P_tent.
    p: Csr32,
    /// Pᵀ.
    r: Csr32,
}

/// Scratch of one level's cycle: Chebyshev direction, residual, coarse right-hand side and
/// correction.
#[derive(Debug)]
struct LevelWork {
    d: Vec<f64>,
    t: Vec<f64>,
    bc: Vec<f64>,
    xc: Vec<f64>,
}

#[derive(Debug)]
struct Work {
    levels: Vec<LevelWork>,
    coarse: SparseCholesky,
}

/// The smoothed-aggregation hierarchy: levels, transfers, smoother bounds, the factorised
/// coarsest matrix, and the V-cycle's scratch (behind a mutex so that `apply` takes `&self`).
#[derive(Debug)]
pub struct SmoothedAggregation {
    levels: Vec<Level>,
    coarse_a: Csr,
    params: AmgParams,
    /// Degree of the cycle's Chebyshev smoother: `smoother_degree` as built,
    /// `tangent_smoother_degree` once refreshed.
    degree: usize,
    work: Mutex<Work>,
}

/// Size and fill of one level, for reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelInfo {
    /// Unknowns.
    pub n: usize,
    /// Stored entries of the level's matrix.
    pub nnz: usize,
}

impl SmoothedAggregation {
    /// Builds the hierarchy for the SPD matrix `a` (full storage) with the near-nullspace
    /// `near_null` (for elasticity: the rigid-body modes, blocks the nodes).
    pub fn new(a: &Csr, near_null: &NearNullSpace, params: &AmgParams) -> Result<Self, AmgError> {
        params.validate()?;
        check_square(a, near_null.n())?;
        let dim = near_null.dim;
        let mut blocks = near_null.blocks();
        let mut ns = near_null.vectors.clone();
        let mut levels = Vec::new();
        let mut a = a.clone();
        loop {
            let l = levels.len();
            if a.nrows <= params.coarse_size || l + 1 >= params.max_levels {
                break;
            }
            let theta = params.strength_threshold;
            let graph = strength_graph(&a, &blocks, theta);
            let (agg, n_agg) = aggregate(&graph);
            let (p_tent, ns_c, blocks_c) = tentative_prolongator(&blocks, &agg, n_agg, &ns, dim);
            if p_tent.ncols as f64 > 0.8 * a.nrows as f64 {
                break; // no real coarsening: stop here and factorise
            }
            let (level, a_c) = Level::build(a, p_tent, l, params)?;
            levels.push(level);
            (a, blocks, ns) = (a_c, blocks_c, ns_c);
        }
        let coarse = factorise_coarse(&a, levels.len())?;
        let work = Mutex::new(Work { levels: levels.iter().map(LevelWork::new).collect(), coarse });
        Ok(Self { levels, coarse_a: a, params: params.clone(), degree: params.smoother_degree, work })
    }

    /// Takes new values of the matrix (e.g. the next Newton tangent; same size, same
    /// near-nullspace): keeps the aggregates and tentative prolongators, recomputes ρ(D⁻¹A),
    /// the smoothed prolongators, the Galerkin products and the coarse factorisation, and
    /// smooths with `tangent_smoother_degree` from then on. On an error (a coarse matrix that is not positive definite, say) the hierarchy is left
    /// as it was.
    pub fn refresh(&mut self, a: &Csr) -> Result<(), AmgError> {
        check_square(a, self.n())?;
        let mut a = a.clone();
        let mut levels = Vec::with_capacity(self.levels.len());
        for (l, lv) in self.levels.iter().enumerate() {
            let (level, a_c) = Level::build(a, lv.p_tent.clone(), l, &self.params)?;
            levels.push(level);
            a = a_c;
        }
        let coarse = factorise_coarse(&a, levels.len())?;
        (self.levels, self.coarse_a, self.degree) = (levels, a, self.params.tangent_smoother_degree);
        let work = self.work.get_mut().unwrap_or_else(|e| e.into_inner());
        work.coarse = coarse;
        Ok(())
    }

    /// Unknowns on the finest level.
    pub fn n(&self) -> usize {
        self.levels.first().map_or(self.coarse_a.nrows, |l| l.a.nrows())
    }

    /// Sizes of all levels, finest first (the last one is factorised).
    pub fn level_info(&self) -> Vec<LevelInfo> {
        self.levels
            .iter()
            .map(|l| LevelInfo { n: l.a.nrows(), nnz: l.a.nnz() })
            .chain(std::iter::once(LevelInfo { n: self.coarse_a.nrows, nnz: self.coarse_a.nnz() }))
            .collect()
    }

    /// Operator complexity Σ_l nnz(A_l) / nnz(A_0): the memory and work of a cycle relative
    /// to the fine matrix.
    pub fn operator_complexity(&self) -> f64 {
        let info = self.level_info();
        info.iter().map(|l| l.nnz as f64).sum::<f64>() / info[0].nnz as f64
    }

    /// Matrix–vector products of one V-cycle, counted in products with the finest matrix:
    /// 2 × the smoother's degree per level (smoothing from zero, the residual, smoothing
    /// again), weighted by nnz(A_l) / nnz(A_0); the transfers and the coarse solve left out.
    pub fn products_per_cycle(&self) -> f64 {
        let nnz0 = self.level_info()[0].nnz as f64;
        self.levels.iter().map(|l| 2.0 * self.degree as f64 * l.a.nnz() as f64 / nnz0).sum()
    }

    /// One V-cycle on level `l` for A_l x = b from x = 0.
    fn vcycle(&self, l: usize, b: &[f64], x: &mut [f64], work: &mut [LevelWork], coarse: &mut SparseCholesky) {
        let Some(lv) = self.levels.get(l) else {
            x.copy_from_slice(b);
            coarse.solve(x);
            return;
        };
        let (w, rest) = work.split_first_mut().expect("one scratch per level");
        let degree = self.degree;
        let range = self.params.smoother_range;
        chebyshev(lv, b, x, &mut w.d, true, degree, range);
        lv.a.residual(b, x, &mut w.t);
        lv.r.spmv(&w.t, &mut w.bc);
        self.vcycle(l + 1, &w.bc, &mut w.xc, rest, coarse);
        lv.p.spmv_add(1.0, &w.xc, x);
        chebyshev(lv, b, x, &mut w.d, false, degree, range);
    }
}

impl Preconditioner for SmoothedAggregation {
    /// z = one V-cycle applied to r.
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let mut guard = self.work.lock().unwrap_or_else(|e| e.into_inner());
        let Work { levels, coarse } = &mut *guard;
        self.vcycle(0, r, z, levels, coarse);
    }
}

impl LevelWork {
    fn new(l: &Level) -> Self {
        let (n, nc) = (l.a.nrows(), l.p.ncols());
        Self { d: vec![0.0; n], t: vec![0.0; n], bc: vec![0.0; nc], xc: vec![0.0; nc] }
    }
}

impl Level {
    /// The level of `a` with tentative prolongator `p_tent`, and the Galerkin matrix PᵀAP of
    /// the next one.
    fn build(a: Csr, p_tent: Csr, level: usize, params: &AmgParams) -> Result<(Self, Csr), AmgError> {
        let inv_diag = inverse_diagonal(&a, level)?;
        let lambda_max = spectral_radius(&a, &inv_diag, params.eigen_steps);
        let p = smooth_prolongator(&a, &inv_diag, 4.0 / (3.0 * lambda_max), &p_tent);
        let r = p.transpose();
        let a_c = r.matmul(&a.matmul(&p));
        let (a, p, r) = (Csr32::from(&a), Csr32::from(&p), Csr32::from(&r));
        Ok((Self { a, inv_diag, lambda_max, p_tent, p, r }, a_c))
    }
}

fn check_square(a: &Csr, n: usize) -> Result<(), AmgError> {
    for (what, found) in [("matrix rows", a.nrows), ("matrix columns", a.ncols)] {
        if found != n {
            return Err(AmgError::DimensionMismatch { what: what.into(), expected: n, found });
        }
    }
    Ok(())
}

/// D⁻¹, or an error naming a non-positive diagonal entry.
fn inverse_diagonal(a: &Csr, level: usize) -> Result<Vec<f64>, AmgError> {
    let d = a.diagonal();
    if let Some((row, &value)) = d.iter().enumerate().find(|(_, v)| !(**v > 0.0 && v.is_finite())) {
        return Err(AmgError::NonPositiveDiagonal { level, row, value });
    }
    Ok(d.iter().map(|v| 1.0 / v).collect())
}

/// Sparse Cholesky of the coarsest matrix.
fn factorise_coarse(a: &Csr, level: usize) -> Result<SparseCholesky, AmgError> {
    inverse_diagonal(a, level)?;
    let (col_ptr, row_idx, values) = a.to_symmetric_lower();
    let mut chol = SparseCholesky::analyse(LowerCsc::new(a.nrows, &col_ptr, &row_idx), "coarsest AMG level")?;
    chol.factorise(&values)?;
    Ok(chol)
}

/// The strong block couplings: for each block i, the blocks j ≠ i with
/// s_ij = ‖A_ij‖_F / √(‖A_ii‖_F ‖A_jj‖_F) ≥ θ, as a graph in compressed rows with s_ij.
struct StrengthGraph {
    ptr: Vec<usize>,
    adj: Vec<u32>,
    s: Vec<f64>,
}

fn strength_graph(a: &Csr, blocks: &Blocks, theta: f64) -> StrengthGraph {
    let nb = blocks.len();
    // block Frobenius norms, row block by row block, each task with its own accumulator
    let norms: Vec<Vec<(u32, f64)>> = (0..nb)
        .into_par_iter()
        .map_init(
            || (vec![0.0; nb], vec![u32::MAX; nb]),
            |(acc, mark), i| {
                let mut cols = Vec::new();
                for &d in blocks.of(i) {
                    let r = d as usize;
                    for q in a.ptr[r]..a.ptr[r + 1] {
                        let j = blocks.of_dof[a.idx[q] as usize] as usize;
                        if mark[j] != i as u32 {
                            mark[j] = i as u32;
                            acc[j] = 0.0;
                            cols.push(j as u32);
                        }
                        acc[j] += a.val[q] * a.val[q];
                    }
                }
                cols.into_iter().map(|j| (j, acc[j as usize].sqrt())).collect()
            },
        )
        .collect();
    let diag: Vec<f64> = norms
        .iter()
        .enumerate()
        .map(|(i, row)| row.iter().find(|(j, _)| *j as usize == i).map_or(0.0, |e| e.1))
        .collect();
    let mut ptr = Vec::with_capacity(nb + 1);
    ptr.push(0);
    let (mut adj, mut s) = (Vec::new(), Vec::new());
    for (i, row) in norms.iter().enumerate() {
        for &(j, f) in row {
            let scale = (diag[i] * diag[j as usize]).sqrt();
            if j as usize != i && scale > 0.0 && f >= theta * scale {
                adj.push(j);
                s.push(f / scale);
            }
        }
        ptr.push(adj.len());
    }
    StrengthGraph { ptr, adj, s }
}

const UNAGGREGATED: u32 = u32::MAX;

/// Greedy aggregation of the strength graph: the aggregate of every block, and their number.
fn aggregate(g: &StrengthGraph) -> (Vec<u32>, usize) {
    let n = g.ptr.len() - 1;
    let nbrs = |i: usize| &g.adj[g.ptr[i]..g.ptr[i + 1]];
    let mut agg = vec![UNAGGREGATED; n];
    let mut count = 0u32;
    // pass 1: roots whose whole strong neighbourhood is free
    for i in 0..n {
        let nb = nbrs(i);
        if agg[i] == UNAGGREGATED && !nb.is_empty() && nb.iter().all(|&j| agg[j as usize] == UNAGGREGATED) {
            agg[i] = count;
            nb.iter().for_each(|&j| agg[j as usize] = count);
            count += 1;
        }
    }
    // pass 2: leftovers join the pass-1 aggregate they are most strongly coupled to
    let first = agg.clone();
    for (i, a) in agg.iter_mut().enumerate() {
        if *a != UNAGGREGATED {
            continue;
        }
        let best = (g.ptr[i]..g.ptr[i + 1])
            .filter(|&k| first[g.adj[k] as usize] != UNAGGREGATED)
            .max_by(|&k, &m| g.s[k].total_cmp(&g.s[m]));
        if let Some(k) = best {
            *a = first[g.adj[k] as usize];
        }
    }
    // pass 3: what remains (isolated blocks, pockets) forms aggregates with its free neighbours
    for i in 0..n {
        if agg[i] == UNAGGREGATED {
            agg[i] = count;
            for &j in nbrs(i) {
                if agg[j as usize] == UNAGGREGATED {
                    agg[j as usize] = count;
                }
            }
            count += 1;
        }
    }
    (agg, count as usize)
}

/// Local QR B_a = Q_a R_a of the near-nullspace rows `rows` of an aggregate (modified
/// Gram–Schmidt, twice; numerically dependent columns dropped): Q column-major m × k and
/// R row-major k × dim, for the `dim` near-nullspace vectors `ns` (row-major).
fn local_qr(rows: &[u32], ns: &[f64], dim: usize) -> (Vec<f64>, Vec<f64>, usize) {
    let m = rows.len();
    let mut q: Vec<f64> = Vec::with_capacity(m * dim);
    let mut r = vec![0.0; dim * dim];
    let mut k = 0;
    let mut v = vec![0.0; m];
    for j in 0..dim {
        for (v, &d) in v.iter_mut().zip(rows) {
            *v = ns[d as usize * dim + j];
        }
        let norm0 = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        for _ in 0..2 {
            for i in 0..k {
                let qi = &q[i * m..(i + 1) * m];
                let h: f64 = qi.iter().zip(&v).map(|(a, b)| a * b).sum();
                r[i * dim + j] += h;
                v.iter_mut().zip(qi).for_each(|(v, q)| *v -= h * q);
            }
        }
        let nv = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if k < m && nv > 1e-8 * norm0 && nv > 0.0 {
            r[k * dim + j] = nv;
            q.extend(v.iter().map(|x| x / nv));
            k += 1;
        }
    }
    r.truncate(k * dim);
    (q, r, k)
}

/// The tentative prolongator of the aggregates `agg` of `blocks` (one local QR of the
/// near-nullspace `ns` per aggregate), the coarse near-nullspace (the R factors), and the
/// coarse blocks (one per aggregate).
fn tentative_prolongator(
    blocks: &Blocks,
    agg: &[u32],
    n_agg: usize,
    ns: &[f64],
    dim: usize,
) -> (Csr, Vec<f64>, Blocks) {
    let n = blocks.of_dof.len();
    let owner: Vec<u32> = blocks.of_dof.iter().map(|&b| agg[b as usize]).collect();
    let members = Blocks::from_owner(owner, n_agg);
    let qr: Vec<(Vec<f64>, Vec<f64>, usize)> =
        (0..n_agg).into_par_iter().map(|a| local_qr(members.of(a), ns, dim)).collect();
    let mut cptr = vec![0usize; n_agg + 1];
    for a in 0..n_agg {
        cptr[a + 1] = cptr[a] + qr[a].2;
    }
    let nc = cptr[n_agg];
    let mut ptr = vec![0usize; n + 1];
    for d in 0..n {
        ptr[d + 1] = ptr[d] + qr[members.of_dof[d] as usize].2;
    }
    let mut idx = vec![0u32; ptr[n]];
    let mut val = vec![0.0; ptr[n]];
    let mut ns_c = vec![0.0; nc * dim];
    for (a, (q, r, k)) in qr.iter().enumerate() {
        let rows = members.of(a);
        let m = rows.len();
        for (t, &d) in rows.iter().enumerate() {
            for c in 0..*k {
                idx[ptr[d as usize] + c] = (cptr[a] + c) as u32;
                val[ptr[d as usize] + c] = q[c * m + t];
            }
        }
        ns_c[cptr[a] * dim..cptr[a + 1] * dim].copy_from_slice(r);
    }
    let coarse_owner: Vec<u32> = (0..n_agg).flat_map(|a| std::iter::repeat_n(a as u32, qr[a].2)).collect();
    (Csr { nrows: n, ncols: nc, ptr, idx, val }, ns_c, Blocks::from_owner(coarse_owner, n_agg))
}

/// P = (I − ω D⁻¹A) P_tent.
fn smooth_prolongator(a: &Csr, inv_diag: &[f64], omega: f64, p_tent: &Csr) -> Csr {
    let mut ap = a.matmul(p_tent);
    for (r, s) in inv_diag.iter().enumerate() {
        let (lo, hi) = (ap.ptr[r], ap.ptr[r + 1]);
        ap.val[lo..hi].iter_mut().for_each(|v| *v *= omega * s);
    }
    p_tent.add(1.0, &ap, -1.0)
}

/// A deterministic pseudo-random number in [−1, 1) (a hash of i).
fn pseudo_random(i: usize) -> f64 {
    let mut z = (i as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// ρ(D⁻¹A) estimated by `steps` Lanczos steps on the similar matrix D^(−½) A D^(−½): the
/// largest Ritz value (a lower bound, close after a dozen steps).
fn spectral_radius(a: &Csr, inv_diag: &[f64], steps: usize) -> f64 {
    let n = a.nrows;
    let s: Vec<f64> = inv_diag.iter().map(|d| d.sqrt()).collect();
    let mut v: Vec<f64> = (0..n).map(pseudo_random).collect();
    let nv = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    v.iter_mut().for_each(|x| *x /= nv);
    let (mut v_prev, mut u, mut w) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let (mut alphas, mut betas) = (Vec::new(), Vec::new());
    let mut beta = 0.0;
    for _ in 0..steps.min(n) {
        u.par_iter_mut().zip(&s).zip(&v).for_each(|((u, s), v)| *u = s * v);
        a.spmv(&u, &mut w);
        w.par_iter_mut().zip(&s).for_each(|(w, s)| *w *= s);
        let alpha = super::pcg::dot(&w, &v);
        w.par_iter_mut().zip(&v).zip(&v_prev).for_each(|((w, v), vp)| *w -= alpha * v + beta * vp);
        alphas.push(alpha);
        beta = w.iter().map(|x| x * x).sum::<f64>().sqrt();
        if beta <= 1e-12 * alpha.abs() {
            break;
        }
        betas.push(beta);
        std::mem::swap(&mut v_prev, &mut v);
        v.par_iter_mut().zip(&w).for_each(|(v, w)| *v = w / beta);
    }
    let k = alphas.len();
    let t = nalgebra::DMatrix::from_fn(k, k, |i, j| {
        if i == j {
            alphas[i]
        } else if i == j + 1 {
            betas[j]
        } else if j == i + 1 {
            betas[i]
        } else {
            0.0
        }
    });
    t.symmetric_eigenvalues().iter().copied().fold(0.0, f64::max)
}

/// Chebyshev smoothing of A x = b: `degree` steps of the Chebyshev semi-iteration on D⁻¹A
/// for the interval [ρ̂/range, ρ̂], ρ̂ = 1.1 ρ(D⁻¹A) (Saad, Iterative Methods, Alg. 12.1).
/// With `zero_start` the initial x is taken as zero (and not read).
fn chebyshev(lv: &Level, b: &[f64], x: &mut [f64], d: &mut [f64], zero_start: bool, degree: usize, range: f64) {
    let hi = UPPER_SAFETY * lv.lambda_max;
    let lo = hi / range;
    let (theta, delta) = (0.5 * (hi + lo), 0.5 * (hi - lo));
    let sigma = theta / delta;
    let mut rho = 1.0 / sigma;
    let (a, inv_d) = (&lv.a, &lv.inv_diag);
    if zero_start {
        x.par_chunks_mut(CHUNK).zip(d.par_chunks_mut(CHUNK)).enumerate().for_each(|(c, (x, d))| {
            let r0 = c * CHUNK;
            for (k, (x, d)) in x.iter_mut().zip(d).enumerate() {
                *d = inv_d[r0 + k] * b[r0 + k] / theta;
                *x = *d;
            }
        });
    } else {
        direction_step(a, inv_d, b, x, d, 0.0, 1.0 / theta);
        add_to(x, d);
    }
    for _ in 1..degree {
        let rho_new = 1.0 / (2.0 * sigma - rho);
        direction_step(a, inv_d, b, x, d, rho_new * rho, 2.0 * rho_new / delta);
        add_to(x, d);
        rho = rho_new;
    }
}

/// d = c₁ d + c₂ D⁻¹(b − A x).
fn direction_step(a: &Csr32, inv_d: &[f64], b: &[f64], x: &[f64], d: &mut [f64], c1: f64, c2: f64) {
    d.par_chunks_mut(CHUNK).enumerate().for_each(|(c, d)| {
        let r0 = c * CHUNK;
        for (k, d) in d.iter_mut().enumerate() {
            let r = r0 + k;
            *d = c1 * *d + c2 * inv_d[r] * (b[r] - a.row_dot(r, x));
        }
    });
}

/// x += d.
fn add_to(x: &mut [f64], d: &[f64]) {
    x.par_chunks_mut(CHUNK).zip(d.par_chunks(CHUNK)).for_each(|(x, d)| {
        x.iter_mut().zip(d).for_each(|(x, d)| *x += d);
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vector Laplacian (three unknowns per grid point, the 7-point stencil per component plus
    /// a weak coupling of the components) on an nx × ny × nz grid with the first plane held:
    /// SPD, with one block per point, and the six rigid-body vectors of the grid coordinates as
    /// near-nullspace — linear-algebra data only, no mesh.
    fn grid_problem(nx: usize, ny: usize, nz: usize) -> (Csr, NearNullSpace) {
        let id = |i: usize, j: usize, k: usize| (i * ny + j) * nz + k;
        let np = nx * ny * nz;
        let mut ptr = vec![0];
        let (mut idx, mut val) = (vec![], vec![]);
        for i in 0..nx {
            for j in 0..ny {
                for k in 0..nz {
                    for c in 0..3 {
                        let mut row: Vec<(u32, f64)> = vec![];
                        let p = id(i, j, k);
                        // held first plane: a larger diagonal
                        let diag = 6.0 + if i == 0 { 6.0 } else { 0.0 };
                        row.push(((3 * p + c) as u32, diag));
                        for c2 in 0..3 {
                            if c2 != c {
                                row.push(((3 * p + c2) as u32, 0.1));
                            }
                        }
                        let mut nb = |q: usize| row.push(((3 * q + c) as u32, -1.0));
                        if i > 0 {
                            nb(id(i - 1, j, k))
                        }
                        if i + 1 < nx {
                            nb(id(i + 1, j, k))
                        }
                        if j > 0 {
                            nb(id(i, j - 1, k))
                        }
                        if j + 1 < ny {
                            nb(id(i, j + 1, k))
                        }
                        if k > 0 {
                            nb(id(i, j, k - 1))
                        }
                        if k + 1 < nz {
                            nb(id(i, j, k + 1))
                        }
                        row.sort_by_key(|e| e.0);
                        idx.extend(row.iter().map(|e| e.0));
                        val.extend(row.iter().map(|e| e.1));
                        ptr.push(idx.len());
                    }
                }
            }
        }
        let a = Csr { nrows: 3 * np, ncols: 3 * np, ptr, idx, val };
        let mut vectors = vec![0.0; 3 * np * 6];
        let mut block = vec![0u32; 3 * np];
        for i in 0..nx {
            for j in 0..ny {
                for k in 0..nz {
                    let (x, y, z) = (i as f64, j as f64, k as f64);
                    for c in 0..3 {
                        let d = 3 * id(i, j, k) + c;
                        block[d] = id(i, j, k) as u32;
                        let row = &mut vectors[6 * d..6 * d + 6];
                        row[c] = 1.0;
                        row[3] = [0.0, -z, y][c];
                        row[4] = [z, 0.0, -x][c];
                        row[5] = [-y, x, 0.0][c];
                    }
                }
            }
        }
        (a, NearNullSpace::new(block, vectors, 6).unwrap())
    }

    #[test]
    fn near_nullspace_sizes_are_checked() {
        let e = NearNullSpace::new(vec![0, 0, 1], vec![1.0; 5], 2).unwrap_err();
        assert!(matches!(e, AmgError::DimensionMismatch { expected: 6, found: 5, .. }), "{e}");
        assert!(NearNullSpace::new(vec![0], vec![], 0).is_err());
    }

    #[test]
    fn tentative_prolongator_reproduces_the_near_nullspace() {
        let (a, nns) = grid_problem(10, 10, 6);
        let dim = nns.dim;
        let mut blocks = nns.blocks();
        let mut ns = nns.vectors.clone();
        let mut a = a;
        for level in 0..2 {
            let graph = strength_graph(&a, &blocks, AmgParams::default().strength_threshold);
            let (agg, n_agg) = aggregate(&graph);
            assert!(agg.iter().all(|&g| (g as usize) < n_agg));
            assert!(n_agg > 1 && n_agg * 2 <= blocks.len(), "level {level}: {n_agg} aggregates of {}", blocks.len());
            let (pt, ns_c, blocks_c) = tentative_prolongator(&blocks, &agg, n_agg, &ns, dim);
            // orthonormal columns: P_tentᵀ P_tent = I
            let ptp = pt.transpose().matmul(&pt);
            for r in 0..ptp.nrows {
                for q in ptp.ptr[r]..ptp.ptr[r + 1] {
                    let e = if ptp.idx[q] as usize == r { 1.0 } else { 0.0 };
                    assert!((ptp.val[q] - e).abs() < 1e-12);
                }
            }
            // P_tent B_c = B, column by column
            let scale = ns.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for k in 0..dim {
                let bc: Vec<f64> = (0..pt.ncols).map(|i| ns_c[i * dim + k]).collect();
                let mut y = vec![0.0; pt.nrows];
                pt.spmv(&bc, &mut y);
                for d in 0..pt.nrows {
                    assert!((y[d] - ns[d * dim + k]).abs() < 1e-12 * scale, "level {level} mode {k}");
                }
            }
            let (level, a_c) = Level::build(a, pt, level, &AmgParams::default()).unwrap();
            // the Galerkin matrix is symmetric
            let at = a_c.transpose();
            let big = a_c.val.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert_eq!((at.ptr.clone(), at.idx.clone()), (a_c.ptr.clone(), a_c.idx.clone()));
            assert!(at.val.iter().zip(&a_c.val).all(|(x, y)| (x - y).abs() <= 1e-12 * big));
            // ρ(D⁻¹A) ≤ 2 for a diagonally dominant matrix (Gershgorin), and > 1
            assert!(level.lambda_max > 1.0 && level.lambda_max <= 2.0 + 1e-9, "{}", level.lambda_max);
            (a, blocks, ns) = (a_c, blocks_c, ns_c);
        }
    }
    #[test]
    fn lanczos_estimates_the_spectral_radius() {
        // D⁻¹A of the 1D Laplacian has ρ = 1 + cos(π/(n+1)) ≈ 2
        let n = 400;
        let mut ptr = vec![0];
        let (mut idx, mut val) = (vec![], vec![]);
        for i in 0..n {
            for (j, v) in [(i as i64 - 1, -1.0), (i as i64, 2.0), (i as i64 + 1, -1.0)] {
                if j >= 0 && (j as usize) < n {
                    idx.push(j as u32);
                    val.push(v);
                }
            }
            ptr.push(idx.len());
        }
        let a = Csr { nrows: n, ncols: n, ptr, idx, val };
        let rho = spectral_radius(&a, &vec![0.5; n], 12);
        let exact = 1.0 + (std::f64::consts::PI / (n as f64 + 1.0)).cos();
        assert!(rho <= exact * (1.0 + 1e-12) && rho > 0.95 * exact, "{rho} vs {exact}");
    }

    #[test]
    fn a_refreshed_hierarchy_follows_its_matrix_and_a_failed_refresh_keeps_it() {
        let (a, nns) = grid_problem(10, 10, 6);
        // the smoother's degree kept: the refresh's new degree is the next test's
        let params = AmgParams { coarse_size: 50, tangent_smoother_degree: 2, ..AmgParams::default() };
        let mut amg = SmoothedAggregation::new(&a, &nns, &params).unwrap();
        assert!(amg.levels.len() >= 2, "{:?}", amg.level_info());
        let r: Vec<f64> = (0..a.nrows).map(pseudo_random).collect();
        let mut z1 = vec![0.0; a.nrows];
        amg.apply(&r, &mut z1);
        // the cycle is linear in A⁻¹'s scale: on 2A (same aggregates) it is exactly half, up to
        // round-off (D⁻¹A, ρ and the Chebyshev polynomial are unchanged; every level's
        // operator and the coarse factor are doubled, which binary rounding leaves exact)
        let mut a2 = a.clone();
        a2.val.iter_mut().for_each(|v| *v *= 2.0);
        amg.refresh(&a2).unwrap();
        let mut z2 = vec![0.0; a.nrows];
        amg.apply(&r, &mut z2);
        let scale = z1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let worst = z1.iter().zip(&z2).map(|(p, q)| (p - 2.0 * q).abs()).fold(0.0, f64::max);
        // Lanczos on the doubled matrix rounds differently: 1e-10 relative is far above that
        assert!(worst <= 1e-10 * scale, "{worst} against {scale}");
        // a matrix with a non-positive diagonal is refused, and the hierarchy stays that of 2A
        let mut bad = a2.clone();
        let q = bad.ptr[7] + bad.idx[bad.ptr[7]..bad.ptr[8]].iter().position(|&c| c == 7).unwrap();
        bad.val[q] = -1.0;
        let e = amg.refresh(&bad).unwrap_err();
        assert!(matches!(e, AmgError::NonPositiveDiagonal { level: 0, row: 7, .. }), "{e}");
        let mut z3 = vec![0.0; a.nrows];
        amg.apply(&r, &mut z3);
        assert_eq!(z2, z3);
    }

    #[test]
    fn a_refreshed_hierarchy_smooths_with_the_tangent_degree() {
        // built with degree 2 and refreshed on the same matrix, the cycle is that of a hierarchy
        // built with degree 4 (same aggregates, same levels), and not that of degree 2
        let (a, nns) = grid_problem(10, 10, 6);
        let params =
            AmgParams { coarse_size: 50, smoother_degree: 2, tangent_smoother_degree: 4, ..AmgParams::default() };
        let cycle = |amg: &SmoothedAggregation| {
            let r: Vec<f64> = (0..a.nrows).map(pseudo_random).collect();
            let mut z = vec![0.0; a.nrows];
            amg.apply(&r, &mut z);
            z
        };
        let mut amg = SmoothedAggregation::new(&a, &nns, &params).unwrap();
        let z2 = cycle(&amg);
        amg.refresh(&a).unwrap();
        let z = cycle(&amg);
        let four = SmoothedAggregation::new(&a, &nns, &AmgParams { smoother_degree: 4, ..params }).unwrap();
        let z4 = cycle(&four);
        let scale = z4.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let dist = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max) / scale;
        // the same operations in the same order up to the parallel sums of Lanczos: round-off
        assert!(dist(&z, &z4) <= 1e-12, "{}", dist(&z, &z4));
        assert!(dist(&z2, &z4) > 1e-3, "{}", dist(&z2, &z4));
        // the cycle's products: Σ_l 2·4·nnz_l/nnz_0, by the levels' sizes
        let info = four.level_info();
        let products: f64 = info[..info.len() - 1].iter().map(|l| 8.0 * l.nnz as f64 / info[0].nnz as f64).sum();
        assert!((amg.products_per_cycle() - products).abs() <= 1e-12 * products);
        assert!(products > 8.0, "{products}: one level at least, and a coarser one");
    }

    #[test]
    fn bad_input_is_an_error() {
        let (mut a, nns) = grid_problem(4, 4, 2);
        let params = AmgParams { coarse_size: 10, ..AmgParams::default() };
        a.val[a.ptr[5]..a.ptr[6]].iter_mut().for_each(|v| *v = -v.abs());
        let e = SmoothedAggregation::new(&a, &nns, &params).unwrap_err();
        assert!(matches!(e, AmgError::NonPositiveDiagonal { level: 0, row: 5, .. }), "{e}");
        let e = SmoothedAggregation::new(&a, &nns, &AmgParams { smoother_degree: 0, ..params }).unwrap_err();
        assert!(e.to_string().contains("amg.smoother_degree"), "{e}");
    }
}
