//! The linearised problem of active-set Newton methods (theory §3–§4.2): for a set A of active
//! contact rows, solve
//!
//! ```text
//! K du − G_Aᵀ λ_A = −∇E(u)          (equilibrium, linearised)
//!      − H_Aᵀ λ_A = f               (load on the extra unknowns)
//! G_A du + H_A dV = −g_A(u, V)      (the active rows touch after the step)
//! ```
//!
//! The system is solved in the coordinates of [`RowBasis`] (theory §8), in which each contact
//! row acts on one coordinate s of its own (for the axis-aligned punch the coordinates are the
//! dofs themselves and nothing is transformed), so an active row fixes dy_s in terms of dV. The
//! fixed coordinates are imposed on the *fixed* sparsity pattern of TᵀKT by identity rows and
//! columns (the diagonal kept for scaling), so the symbolic Cholesky analysis is done once; dy
//! depends affinely on dV, `dy = dy⁰ + W dV`, from one solve with 1 + n_extras right-hand sides,
//! and dV follows from an n_extras × n_extras system. The contact forces are the reactions at
//! the fixed coordinates, and du = T dy.
//!
//! The systems are solved by one of two [`LinearBackend`]s: a sparse Cholesky factorisation of
//! every tangent (symbolic analysis once), or conjugate gradients preconditioned by a
//! smoothed-aggregation multigrid of the elastic stiffness, built once, whose values follow the
//! tangent when CG slows down on it (its aggregates kept; the fixed dofs are handled by the
//! preconditioner as a diagonal block), to a relative tolerance the caller sets per step
//! (inexact Newton).

use crate::fixed_dofs::FixedDofs;
use crate::linear::{self, InSolver, lower, near_null_space};
use crate::newton_friction::{SlipPair, friction_active_set};
use crate::pressure_block::{BlockResidual, BlockRule, PressureBlock, incompressibility};
use crate::row_basis::RowBasis;
use nalgebra::{DMatrix, DVector};
use saddle_core::linalg::{AmgParams, Csr, LinalgError, Pcg, SmoothedAggregation, SparseCholesky};
use saddle_core::{ConstraintRows, Lagrangian, Material, SolveError, SymmetricPattern};
use serde::{Deserialize, Serialize};
use std::sync::Mutex;

/// `linear = "direct" | "amg" | "auto"`: how a solver's linear systems are solved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LinearSolver {
    /// Sparse Cholesky (faer, supernodal): exact, memory ~ N^1.5.
    Direct,
    /// CG with smoothed-aggregation AMG of the elastic stiffness: memory ~ N, inexact.
    Amg,
    /// By estimated cost ([`direct_is_cheaper`]): the symbolic analysis of the tangent's
    /// pattern (cheap) gives the factor's fill and flops, and the direct backend is taken when
    /// its estimated cost is below the multigrid's; above Newton's `auto_amg_dofs` (default
    /// [`AUTO_AMG_DOFS`]) free dofs AMG without analysing (the default).
    #[default]
    Auto,
}

/// The smallest relative residual asked of CG: its round-off limit in double precision.
pub const CG_TOL_MIN: f64 = 1e-14;

/// The default of Newton's `auto_amg_dofs`: above this many free dofs `auto` picks AMG without
/// a symbolic analysis. Measured on the default scene family (2 cores), the multigrid Newton
/// is already 1.9× faster than the direct one at 18.5k dofs and 3× at 45k, and the fill of a
/// 3D factor only grows from there (at 156k dofs the rule's direct estimate is 25× the
/// multigrid's); the analysis that the rule needs (0.1 s at 45k dofs, 0.65 s or 7 % of the
/// whole run at 156k) is skipped where its answer is known. Below, thin quasi-2D meshes, whose
/// factors fill like 2D ones, still get the rule.
pub const AUTO_AMG_DOFS: usize = 100_000;

/// The cost rule of `auto`: factorisations a direct Newton solve performs (measured 4–5 on the
/// default scene family, 5 on an unstructured mesh: the elastic start's and one per step).
pub const DIRECT_FACTORISATIONS: f64 = 5.0;

/// The cost rule of `auto`: a triangular solve pair's multiply–add against a factorisation's.
/// Solves run at memory speed, factorisations at matrix–matrix speed; measured ≈ 10 (3.5e-10
/// s per row and nonzero of L for the Delassus columns of the elastic start, 3.4e-11 s per
/// factorisation multiply–add, on 10k–30k-dof meshes, structured and unstructured).
pub const SOLVE_WEIGHT: f64 = 10.0;

/// The cost rule of `auto`: a multigrid Newton solve, in factorisation multiply–adds per
/// nonzero of the stiffness. Measured 1.6–2.7 µs per nonzero for whole AMG Newton solves on
/// 5k–20k-dof meshes (structured and unstructured, with the single-precision cycle of issue
/// 14; 3.4–5.8 µs before it) at 3.4e-11 s per multiply–add: ≈ 6e4. The direct backend then
/// wins up to about 5k dofs on the default scene family (a tie there: 0.18 s each), AMG from
/// 10.6k (0.36 s against 0.54 s).
pub const AMG_COST_PER_NONZERO: f64 = 6e4;

/// The cost rule of `auto`: the CG iterations of the multigrid Newton solve that
/// [`AMG_COST_PER_NONZERO`] stands for (the default scene: 263 over 12 Newton steps, Newton's
/// `cg_max_iter` docs), so that one CG iteration costs `AMG_COST_PER_NONZERO / 263` per nonzero.
pub const AMG_CG_ITERATIONS_PER_SOLVE: f64 = 263.0;

/// The CG iterations after which `auto`, having picked the multigrid, takes the direct path
/// instead (theory §4.2): those whose cost, at [`AMG_CG_ITERATIONS_PER_SOLVE`] per multigrid
/// estimate, equals the `direct` estimate of a whole solve. The rule sees the tangent through
/// CG's iterations on it (the set-up saw only the elastic stiffness): a tangent the multigrid
/// no longer approximates (perfect plasticity) spends the budget, and from then on the
/// factorisation, estimated no dearer than what was spent, is used. At most twice the cost of
/// the cheaper choice made with hindsight.
pub fn direct_budget(direct: f64, stiffness_nonzeros: usize) -> f64 {
    AMG_CG_ITERATIONS_PER_SOLVE * direct / (AMG_COST_PER_NONZERO * stiffness_nonzeros as f64)
}

/// How much dearer a multigrid solve gets as ν → ½: `sqrt(max(1, (λ/μ)/1.5))`, λ/μ = 2ν/(1 − 2ν)
/// (1 up to ν = 0.3). The multigrid is built on the rigid-body modes, not on the nearly
/// divergence-free modes that soften as λ/μ grows, so CG's iterations grow like the square
/// root of the condition number: measured on the elastic default scene with P2 (18.5k dofs),
/// 173 CG iterations at ν = 0.3, 778 at 0.49 (factor 5.7 here) and 18 088 at 0.4999 (58 here;
/// with `cg_forcing` = 1e-5, which it needs to converge at all) against a direct solve of 0.7 s.
pub fn incompressibility_factor(nu: f64) -> f64 {
    let ratio = if nu < 0.5 { 2.0 * nu / (1.0 - 2.0 * nu) } else { f64::INFINITY };
    (ratio / 1.5).max(1.0).sqrt()
}

/// The cost rule of `auto` (Newton): the direct backend's estimated cost,
/// `DIRECT_FACTORISATIONS · F + SOLVE_WEIGHT · rows · nnz(L)` (F the multiply–adds of one
/// factorisation, rows × nnz(L) the Delassus columns of the exact elastic start), against the
/// multigrid's, `AMG_COST_PER_NONZERO · nnz(K) · [`incompressibility_factor`](ν)`. Returns
/// (direct is cheaper, direct estimate, multigrid estimate), in multiply–adds.
pub fn direct_is_cheaper(
    chol: &SparseCholesky,
    contact_rows: usize,
    stiffness_nonzeros: usize,
    nu: f64,
) -> (bool, f64, f64) {
    let direct = DIRECT_FACTORISATIONS * chol.factor_flops() + SOLVE_WEIGHT * (contact_rows * chol.nnz_l()) as f64;
    let amg = AMG_COST_PER_NONZERO * stiffness_nonzeros as f64 * incompressibility_factor(nu);
    (direct <= amg, direct, amg)
}

/// When `auto` picked the multigrid without analysing (above `auto_amg_dofs`), the CG
/// iterations after which it analyses the pattern after all (theory §4.2): those of the whole
/// multigrid solve its size rule stood for, [`AMG_CG_ITERATIONS_PER_SOLVE`] times
/// [`incompressibility_factor`]`(nu)`, provided CG also took more per solve than the
/// hierarchy takes on elastic tangents (Newton's `amg_refresh_cg`). A tangent the elastic
/// hierarchy approximates never spends them (the default scene: about 11 per solve at any
/// size); one it does not (perfect plasticity: 72–76 per solve) is then priced as a direct
/// solve too.
pub fn analysis_due(nu: f64) -> f64 {
    AMG_CG_ITERATIONS_PER_SOLVE * incompressibility_factor(nu)
}

impl LinearSolver {
    /// Direct or AMG as far as the size decides: `auto` is AMG above `auto_amg_dofs` free dofs
    /// times [`incompressibility_factor`]`(nu)`, and stays `Auto` below (the cost rule decides
    /// after the symbolic analysis).
    pub fn resolve(self, n: usize, auto_amg_dofs: usize, nu: f64) -> LinearSolver {
        match self {
            LinearSolver::Auto if n as f64 > auto_amg_dofs as f64 * incompressibility_factor(nu) => LinearSolver::Amg,
            other => other,
        }
    }
}

/// The solver of the linearised systems.
pub enum LinearBackend {
    /// A numeric Cholesky factorisation per system on the pattern analysed once.
    Direct(Box<SparseCholesky>),
    /// PCG with the elastic multigrid hierarchy.
    Amg(Box<IterativeSolve>),
}

impl LinearBackend {
    /// The factor that solves this step's systems: the direct backend's, or `auto`'s reserve
    /// once taken (then from this step on).
    fn cholesky(&mut self) -> Option<&mut SparseCholesky> {
        match self {
            LinearBackend::Direct(chol) => Some(chol),
            LinearBackend::Amg(it) => {
                if let Some((_, budget)) = &it.reserve
                    && !it.switched
                    && it.spent_cost >= *budget
                {
                    it.switched = true;
                }
                if it.switched { it.reserve.as_mut().map(|(c, _)| &mut **c) } else { None }
            }
        }
    }

    /// Drops `auto`'s reserve (its factor does not fit in memory) and stays with the
    /// multigrid; false on the direct backend, which has no other way.
    fn give_up_reserve(&mut self) -> bool {
        match self {
            LinearBackend::Direct(_) => false,
            LinearBackend::Amg(it) => {
                it.reserve = None;
                it.switched = false;
                it.analyse_after = None;
                true
            }
        }
    }
}

/// CG preconditioned by smoothed aggregation of the elastic stiffness (module docs).
pub struct IterativeSolve {
    amg: SmoothedAggregation,
    pcg: Pcg,
    /// The system matrix, on L's pattern: built once, its values re-assigned per step.
    a: Csr,
    /// Scratch of [`Csr::assign_symmetric_lower`], of the preconditioner and of one column.
    fill: Vec<usize>,
    scratch: Mutex<Vec<f64>>,
    col: Vec<f64>,
    /// CG iteration budget per solve.
    pub max_iter: usize,
    /// CG iterations so far.
    pub iterations: usize,
    /// Rebuilds of the hierarchy's values on the tangent so far.
    pub refreshes: usize,
    /// The hierarchy follows the tangent (its values rebuilt on it, the aggregates kept) when
    /// the last CG solve took more than this many iterations (Newton's `amg_refresh_cg`).
    pub refresh_above: usize,
    /// The tangent in the dofs' own coordinates (when the rows' coordinates differ), for the
    /// hierarchy's refresh.
    tangent: Csr,
    /// The values of the matrix of the last rebuild (empty: the elastic stiffness).
    built_on: Vec<f64>,
    /// CG iterations of the last solve.
    last_iterations: usize,
    /// CG iterations and solves since the set-up (kept across warm solves, unlike `iterations`).
    spent: usize,
    spent_solves: usize,
    /// `spent` at the price of an iteration of the cycle as built (the one `auto`'s constants
    /// were measured with): an iteration of a refreshed cycle with a higher smoother degree
    /// counts by its products ([`iteration_cost`]).
    spent_cost: f64,
    /// [`SmoothedAggregation::products_per_cycle`] of the hierarchy as built.
    built_products: f64,
    /// Solves that stopped at the budget before the tolerance.
    pub unconverged: usize,
    /// `auto`'s direct path in reserve, analysed, and the CG iterations after which it is taken
    /// ([`direct_budget`]); taken once, it solves every later system.
    reserve: Option<(Box<SparseCholesky>, f64)>,
    /// `auto` above `auto_amg_dofs`, which picked the multigrid unanalysed: the CG iterations
    /// after which the pattern is analysed and the reserve kept ([`analysis_due`]).
    analyse_after: Option<f64>,
    /// The cost rule's estimates (direct, multigrid) of the deferred analysis, once done.
    pub cost_estimates: Option<(f64, f64)>,
    /// The reserve has been taken.
    pub switched: bool,
    /// The last solutions of the extras' columns (W = K⁻¹(−K δ_V)): they change little from
    /// one Newton step to the next and start the next CG solves.
    previous: Vec<f64>,
    /// The pressure block (theory §10.1): when present, `amg` is the multigrid of the
    /// part A of the split (λ = 0 elasticity for an elastic point) and the systems are solved by MINRES on the saddle system
    /// ([`PressureBlock`]), its iterations counted in `iterations` like CG's.
    block: Option<Box<PressureBlock>>,
    /// Solves by the pressure block.
    pub block_solves: usize,
}

/// The multigrid rebuilt on the tangent (theory §4.2): the aggregates and tentative
/// prolongators of the elastic hierarchy kept, the smoothed prolongators, Galerkin operators and
/// coarse factor recomputed ([`SmoothedAggregation::refresh`]). With T = I the matrix is the
/// system's `a` itself (the fixed dofs decoupled); otherwise the tangent in the dofs' own
/// coordinates, `k` on L's `pattern`, which the preconditioner transforms around. A tangent
/// that has not [`changed_enough`] since the last rebuild (`built_on`) or whose coarse
/// operator is not positive definite keeps the last hierarchy.
#[allow(clippy::too_many_arguments)]
fn follow_the_tangent(
    amg: &mut SmoothedAggregation,
    basis: &RowBasis,
    a: &Csr,
    tangent: &mut Csr,
    pattern: &SymmetricPattern,
    k: &[f64],
    fill: &mut Vec<usize>,
    built_on: &mut Vec<f64>,
    refreshes: &mut usize,
) {
    let m = if basis.is_identity() {
        a
    } else {
        if tangent.nrows == 0 {
            *tangent = Csr::from_symmetric_lower(lower(pattern), k);
        } else {
            tangent.assign_symmetric_lower(lower(pattern), k, fill);
        }
        &*tangent
    };
    if !changed_enough(built_on, &m.val) {
        return;
    }
    if amg.refresh(m).is_ok() {
        *refreshes += 1;
        built_on.clear();
        built_on.extend_from_slice(&m.val);
    }
}

/// [`follow_the_tangent`] for the pressure block: the multigrid rebuilt on the part
/// A of the tangent `k` (values on L's `pattern`, the dofs' own coordinates).
fn follow_the_split_tangent(
    amg: &mut SmoothedAggregation,
    block: &PressureBlock,
    pattern: &SymmetricPattern,
    k: &[f64],
    built_on: &mut Vec<f64>,
    refreshes: &mut usize,
) {
    let a = block.split_part(pattern, k);
    if !changed_enough(built_on, &a.val) {
        return;
    }
    if amg.refresh(&a).is_ok() {
        *refreshes += 1;
        built_on.clear();
        built_on.extend_from_slice(&a.val);
    }
}

/// The price of one CG iteration with `amg` in iterations of the cycle as built, whose
/// [`SmoothedAggregation::products_per_cycle`] were `built` (theory §4.2): products with the
/// fine matrix, CG's own one and the cycle's. A refreshed hierarchy smooths with
/// `tangent_smoother_degree` and costs more per iteration.
fn iteration_cost(amg: &SmoothedAggregation, built: f64) -> f64 {
    (1.0 + amg.products_per_cycle()) / (1.0 + built)
}

/// A rebuild pays only when the tangent moved since the last one: by more than this fraction
/// of its largest entry anywhere (an element entering or leaving the plastic set changes its
/// entries by a fraction of the elastic moduli; a near-incompressible elastic tangent, which
/// the rebuild cannot help, does not change at all).
pub const REFRESH_CHANGE: f64 = 1e-2;

/// Whether `now` differs from `before` (values on the same pattern; empty: never built on a
/// tangent) by more than [`REFRESH_CHANGE`] of max |now|.
fn changed_enough(before: &[f64], now: &[f64]) -> bool {
    if before.len() != now.len() {
        return true;
    }
    let scale = now.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    before.iter().zip(now).any(|(b, v)| (b - v).abs() > REFRESH_CHANGE * scale)
}

/// Positions of the entries of each row i in the columns j < i of a lower-triangular pattern,
/// to zero a row as well as a column.
#[derive(Clone, Debug)]
struct TransposeIndex {
    ptr: Vec<usize>,
    pos: Vec<usize>,
}

impl TransposeIndex {
    fn new(p: &SymmetricPattern) -> Self {
        let (cp, ri) = (p.col_ptr(), p.row_idx());
        let mut ptr = vec![0usize; p.n() + 1];
        for j in 0..p.n() {
            for &i in &ri[cp[j] + 1..cp[j + 1]] {
                ptr[i + 1] += 1;
            }
        }
        for i in 0..p.n() {
            ptr[i + 1] += ptr[i];
        }
        let mut fill = ptr.clone();
        let mut pos = vec![0usize; ptr[p.n()]];
        for j in 0..p.n() {
            for (k, &i) in ri.iter().enumerate().take(cp[j + 1]).skip(cp[j] + 1) {
                pos[fill[i]] = k;
                fill[i] += 1;
            }
        }
        Self { ptr, pos }
    }
}

/// The step of one active-set Newton iteration.
#[derive(Clone, Debug)]
pub struct Step {
    /// du.
    pub du: Vec<f64>,
    /// dV.
    pub dv: Vec<f64>,
    /// Contact forces after the step (zero on inactive rows).
    pub lambda: Vec<f64>,
}

/// The primal–dual active set (theory §4.2 step 2): `active` ← {i : λ_i − c_i g_i > 0}; the
/// number of this rank's rows that changed.
pub(crate) fn primal_dual_update(lambda: &[f64], c: &[f64], gap: &[f64], active: &mut [bool]) -> usize {
    let mut changed = 0;
    for (i, a) in active.iter_mut().enumerate() {
        let next = lambda[i] - c[i] * gap[i] > 0.0;
        changed += (next != *a) as usize;
        *a = next;
    }
    changed
}

/// Every extra with a load needs a touching row (theory §4.2 step 2): where none of `active` holds
/// it, the row with the smallest gap in `gap` joins (over every rank's rows; on a tie of gaps,
/// the lowest rank's). Returns the rows this rank added. Collective.
pub(crate) fn touch_loaded_extras(l: &Lagrangian<'_>, active: &mut [bool], gap: &[f64]) -> usize {
    let (rows, comm) = (l.data.rows, l.comm());
    let mut added = 0;
    for (kx, f) in l.data.load.iter().enumerate() {
        let touching = (0..rows.n_rows()).filter(|&i| rows.extra_row(i)[kx] != 0.0);
        if *f == 0.0 || comm.any(touching.clone().any(|i| active[i])) {
            continue;
        }
        let closest = touching.min_by(|&a, &b| gap[a].total_cmp(&gap[b]));
        let least = comm.min(closest.map_or(f64::INFINITY, |i| gap[i]));
        let mine = closest.filter(|&i| gap[i] == least);
        let first = comm.min(if mine.is_some() { comm.rank() as f64 } else { f64::INFINITY });
        if let Some(i) = mine.filter(|_| first == comm.rank() as f64) {
            active[i] = true;
            added += 1;
        }
    }
    added
}

/// The active set with friction (theory §4.2 step 2, §8.3) at the multipliers, rows' values and
/// rows' elastic stiffnesses `(lambda, gap, c)`: the normal rows by PDAS and the pairs by
/// [`friction_active_set`]; at a `cold` start the closest normal row of each block of `basis`
/// (as without friction), each pair bonded (stick) with its node's normal row.
pub(crate) fn active_set_with_friction(
    rows: &ConstraintRows,
    basis: &RowBasis,
    (lambda, gap, c): (&[f64], &[f64], &[f64]),
    cold: bool,
    active: &mut [bool],
    slips: &mut Vec<SlipPair>,
) {
    if cold {
        let normal_gaps = normal_gaps(gap, &rows.friction.tangential_mask(rows.n_rows()));
        active.copy_from_slice(&basis.closest_in_blocks(&normal_gaps));
        for b in &rows.friction.blocks {
            active[b.tangent] = active[b.normal];
            active[b.tangent + 1] = active[b.normal];
        }
        slips.clear();
    } else {
        primal_dual_update(lambda, c, gap, active);
        friction_active_set(rows, lambda, gap, c, active, slips);
    }
}

/// The rows' values with the tangential rows' set to +∞: what "the closest row" reads, which is
/// always a normal row.
fn normal_gaps(gap: &[f64], tangential: &[bool]) -> Vec<f64> {
    gap.iter().zip(tangential).map(|(g, t)| if *t { f64::INFINITY } else { *g }).collect()
}

/// Every loaded extra needs a row that determines it (theory §4.2 step 2): a slipping pair's
/// Robin condition does, as an active row does; where neither holds it, the normal row with the
/// smallest gap joins `active` (a tangential row alone is never made active: its pair is
/// sorted by its own residual).
pub(crate) fn touch_loaded_extras_with_friction(
    l: &Lagrangian<'_>,
    active: &mut [bool],
    slips: &[SlipPair],
    gap: &[f64],
) {
    let rows = l.data.rows;
    let tangential = rows.friction.tangential_mask(rows.n_rows());
    let mut holding = active.to_vec();
    for sp in slips {
        holding[sp.tangent] = true;
        holding[sp.tangent + 1] = true;
    }
    touch_loaded_extras(l, &mut holding, &normal_gaps(gap, &tangential));
    for (i, h) in holding.iter().enumerate().filter(|(i, _)| !tangential[*i]) {
        active[i] = *h;
    }
}

/// The Newton step from the solves `x` = [du⁰, W_1, …] (n × (1 + n_extras)) and the reactions
/// λ = λ⁰ + Λ dV of the `active` rows (theory §4.2 step 3): dV from −H_Aᵀ(λ⁰ + Λ dV) = f, with
/// H_AᵀΛ and H_Aᵀλ⁰ summed over every rank's rows (theory §12), then du = du⁰ + W dV (in the
/// coordinates of the solves) and λ. An error naming `solver` when dV is undetermined.
pub(crate) fn step_from_reactions(
    l: &Lagrangian<'_>,
    active: &[bool],
    x: &[f64],
    lam0: &[f64],
    lam_v: &DMatrix<f64>,
    solver: &str,
) -> Result<Step, SolveError> {
    let (rows, comm) = (l.data.rows, l.comm());
    let (n, ne, nr) = (l.n_dofs(), l.n_extras(), rows.n_rows());
    let mut dv = vec![0.0; ne];
    if ne > 0 {
        let h = DMatrix::from_fn(nr, ne, |i, kx| if active[i] { rows.extra_row(i)[kx] } else { 0.0 });
        let mut s = h.transpose() * lam_v;
        let mut hl = h.transpose() * DVector::from_column_slice(lam0);
        comm.sum_in_place(s.as_mut_slice());
        comm.sum_in_place(hl.as_mut_slice());
        let rhs = -DVector::from_column_slice(l.data.load) - hl;
        let sol = extras_step(&s, &rhs).ok_or_else(|| SolveError::Unsupported {
            solver: solver.into(),
            message: "an extra unknown with a load has no active contact row that determines it (the obstacle \
                          does not touch, or touches where it cannot hold that extra)"
                .into(),
        })?;
        dv.copy_from_slice(sol.as_slice());
    }
    let mut du = x[..n].to_vec();
    for (kx, d) in dv.iter().enumerate() {
        for (u, w) in du.iter_mut().zip(&x[(1 + kx) * n..(2 + kx) * n]) {
            *u += d * w;
        }
    }
    let mut lambda = vec![0.0; nr];
    for i in (0..nr).filter(|&i| active[i]) {
        lambda[i] = lam0[i] + (0..ne).map(|kx| lam_v[(i, kx)] * dv[kx]).sum::<f64>();
    }
    Ok(Step { du, dv, lambda })
}

/// Below this fraction of the largest singular value of H_AᵀΛ a singular value is zero: the
/// active rows leave that combination of extras undetermined (a punch touching along a line
/// cannot tilt about it), measured in round-off of the n_extras × n_extras system.
pub const EXTRAS_RANK_TOL: f64 = 1e-10;

/// dV from S dV = b (theory §4.2.1): the solution when S = H_AᵀΛ is regular; when the active
/// rows leave a combination of extras undetermined and b has no component along it (the load
/// does not push that way), the minimum-norm solution — the undetermined extras keep their
/// values; `None` when b has such a component (no active row can hold the load).
fn extras_step(s: &DMatrix<f64>, b: &DVector<f64>) -> Option<DVector<f64>> {
    let svd = s.clone().svd(true, true);
    let largest = svd.singular_values.max();
    if !largest.is_finite() {
        return None;
    }
    let dv = svd.solve(b, EXTRAS_RANK_TOL * largest).ok()?;
    let defect = (s * &dv - b).norm();
    (dv.iter().all(|x| x.is_finite()) && defect <= EXTRAS_RANK_TOL.sqrt() * b.norm().max(f64::MIN_POSITIVE))
        .then_some(dv)
}

/// The linearised problem for one active set, and the solver of its systems.
pub struct ActiveSetSystem {
    basis: RowBasis,
    /// The tangent TᵀKT in the rows' coordinates, on the basis's pattern (empty when T = I).
    kt: Vec<f64>,
    /// Tᵀ∇E (empty when T = I).
    grad_t: Vec<f64>,
    /// The solver this system serves, for error messages.
    solver: String,
    transpose: TransposeIndex,
    /// How the systems are solved.
    pub backend: LinearBackend,
    work: Vec<f64>,
    /// Symbolic analyses of L's pattern so far (one for the direct backend, none for AMG).
    pub symbolic_analyses: usize,
    /// Numeric factorisations so far.
    pub factorisations: usize,
    /// Triangular solve pairs (direct) or CG solves (AMG) so far.
    pub solves: usize,
    /// The slipping friction pairs of the next step (theory §8.3, [`crate::newton_friction`]):
    /// their Robin conditions enter the tangent and the forces; empty without friction.
    pub slips: Vec<SlipPair>,
}

impl ActiveSetSystem {
    /// The direct backend: the symbolic analysis of L's pattern, once; `solver` names the
    /// solver this system serves in errors.
    pub fn new(l: &Lagrangian<'_>, solver: &str) -> Result<Self, SolveError> {
        let basis = RowBasis::new(l.data.rows, l.n_dofs(), l.pattern(), solver)?;
        let mut symbolic_analyses = 0;
        let chol = linear::analyse(basis.pattern(l.pattern()), "tangent stiffness", solver, &mut symbolic_analyses)?;
        let mut system = Self::with(l, solver, basis, LinearBackend::Direct(Box::new(chol)));
        system.symbolic_analyses = symbolic_analyses;
        Ok(system)
    }

    /// The iterative backend: the multigrid hierarchy of the elastic stiffness with the
    /// parameters `amg`, and CG with at most `cg_max_iter` iterations per solve; the hierarchy
    /// follows the tangent once a solve takes more than `refresh_above` iterations.
    pub fn multigrid(
        l: &Lagrangian<'_>,
        solver: &str,
        amg: &AmgParams,
        cg_max_iter: usize,
        refresh_above: usize,
    ) -> Result<Self, SolveError> {
        let never = BlockRule { ratio: f64::INFINITY, residual: BlockResidual::default() };
        Self::multigrid_with(l, solver, amg, cg_max_iter, refresh_above, never)
    }

    /// [`ActiveSetSystem::multigrid`], with the pressure block (theory §10.1) when the element
    /// has pressure rows and the elastic κ/(2μ) is above `block.ratio` (Newton's
    /// `pressure_block_ratio`): the multigrid is then built on the part A of the split of the
    /// elastic stiffness and the systems are solved by MINRES ([`PressureBlock`]).
    pub fn multigrid_with(
        l: &Lagrangian<'_>,
        solver: &str,
        amg: &AmgParams,
        cg_max_iter: usize,
        refresh_above: usize,
        rule: BlockRule,
    ) -> Result<Self, SolveError> {
        let basis = RowBasis::new(l.data.rows, l.n_dofs(), l.pattern(), solver)?;
        let near_null = near_null_space(l).ok_or_else(|| SolveError::Unsupported {
            solver: solver.into(),
            message: "linear = \"amg\" needs the nodes of the dofs (rigid-body modes); this L has none".into(),
        })?;
        let c = l.data.elasticity.stiffness_matrix();
        let k_values = l.stiffness(Material::Uniform(&c));
        let k = Csr::from_symmetric_lower(lower(l.pattern()), &k_values);
        let block = (incompressibility(&c) > rule.ratio)
            .then(|| l.pressure_rows())
            .flatten()
            .map(|rows| Box::new(PressureBlock::new(rows, l.n_dofs(), &c, rule.residual)));
        let split = block.as_ref().map(|b| b.split_part(l.pattern(), &k_values));
        let amg = SmoothedAggregation::new(split.as_ref().unwrap_or(&k), &near_null, amg).map_err(|e| {
            SolveError::Unsupported { solver: solver.into(), message: format!("multigrid set-up: {e}") }
        })?;
        let n = l.n_dofs();
        let built_products = amg.products_per_cycle();
        // the system matrix lives on the pattern of TᵀKT
        let a = if basis.is_identity() {
            k
        } else {
            let mut kt = vec![0.0; basis.pattern(l.pattern()).nnz()];
            basis.stiffness(&k_values, &mut kt);
            Csr::from_symmetric_lower(lower(basis.pattern(l.pattern())), &kt)
        };
        let iterative = IterativeSolve {
            amg,
            pcg: Pcg::new(n),
            a,
            fill: Vec::new(),
            scratch: Mutex::new(vec![0.0; n]),
            col: vec![0.0; n],
            max_iter: cg_max_iter,
            iterations: 0,
            refreshes: 0,
            refresh_above,
            tangent: Csr::default(),
            built_on: Vec::new(),
            reserve: None,
            analyse_after: None,
            cost_estimates: None,
            switched: false,
            last_iterations: 0,
            spent: 0,
            spent_solves: 0,
            spent_cost: 0.0,
            built_products,
            unconverged: 0,
            previous: Vec::new(),
            block,
            block_solves: 0,
        };
        Ok(Self::with(l, solver, basis, LinearBackend::Amg(Box::new(iterative))))
    }

    /// `auto`'s reserve for the multigrid backend: the direct backend of `direct` (the same
    /// L), taken once CG has spent `budget` iterations ([`direct_budget`]).
    pub fn keep_in_reserve(&mut self, direct: ActiveSetSystem, budget: f64) {
        if let (LinearBackend::Amg(it), LinearBackend::Direct(chol)) = (&mut self.backend, direct.backend) {
            it.reserve = Some((chol, budget));
        }
        self.symbolic_analyses += direct.symbolic_analyses;
    }

    /// `auto`'s multigrid chosen without an analysis (above `auto_amg_dofs`): the pattern is
    /// analysed, and the direct path kept in reserve by [`direct_budget`], once CG has spent
    /// `after` iterations ([`analysis_due`]) at more than `refresh_above` per solve.
    pub fn analyse_when_due(&mut self, after: f64) {
        if let LinearBackend::Amg(it) = &mut self.backend {
            it.analyse_after = Some(after);
        }
    }

    /// The deferred analysis of `auto` (theory §4.2), when CG has spent its iterations: the
    /// symbolic analysis of the pattern, the cost rule's estimates, and the direct path in
    /// reserve with its budget (counted from the set-up, so a budget already spent takes it at
    /// once).
    fn analyse_if_due(&mut self, l: &Lagrangian<'_>) -> Result<(), SolveError> {
        let LinearBackend::Amg(it) = &mut self.backend else { return Ok(()) };
        let slow = it.spent > it.refresh_above.saturating_mul(it.spent_solves);
        if !(slow && it.analyse_after.is_some_and(|after| it.spent_cost >= after)) {
            return Ok(());
        }
        it.analyse_after = None;
        let p = self.basis.pattern(l.pattern());
        let chol = linear::analyse(p, "tangent stiffness", &self.solver, &mut self.symbolic_analyses)?;
        let nu = l.data.elasticity.poisson;
        let (_, direct, amg) = direct_is_cheaper(&chol, l.data.rows.n_rows(), l.pattern().nnz(), nu);
        it.cost_estimates = Some((direct, amg));
        it.reserve = Some((Box::new(chol), direct_budget(direct, l.pattern().nnz())));
        Ok(())
    }

    /// The system for the rows' coordinates `basis` on `backend`.
    fn with(l: &Lagrangian<'_>, solver: &str, basis: RowBasis, backend: LinearBackend) -> Self {
        let p = basis.pattern(l.pattern());
        Self {
            solver: solver.to_string(),
            transpose: TransposeIndex::new(p),
            backend,
            work: vec![0.0; p.nnz()],
            kt: if basis.is_identity() { Vec::new() } else { vec![0.0; p.nnz()] },
            grad_t: if basis.is_identity() { Vec::new() } else { vec![0.0; l.n_dofs()] },
            basis,
            symbolic_analyses: 0,
            factorisations: 0,
            solves: 0,
            slips: Vec::new(),
        }
    }

    /// Zeroes the counts (analyses, factorisations, solves, CG iterations) for a new solve on
    /// a kept set-up.
    pub fn reset_counts(&mut self) {
        self.symbolic_analyses = 0;
        self.factorisations = 0;
        self.solves = 0;
        if let LinearBackend::Amg(it) = &mut self.backend {
            it.iterations = 0;
            it.unconverged = 0;
            it.refreshes = 0;
            it.block_solves = 0;
        }
    }

    /// The tangents the next [`ActiveSetSystem::step`]'s matrix was assembled with: the pressure
    /// block's split follows them (theory §10.1); nothing to do without one.
    pub fn follow_material(&mut self, material: Material<'_>) {
        if let LinearBackend::Amg(it) = &mut self.backend
            && let Some(block) = &mut it.block
        {
            block.follow(material);
        }
    }

    /// The Cholesky factor of the direct backend, if that is the one in use.
    pub fn direct(&mut self) -> Option<&mut SparseCholesky> {
        match &mut self.backend {
            LinearBackend::Direct(chol) => Some(chol),
            LinearBackend::Amg(_) => None,
        }
    }

    /// The iterative backend, if that is the one in use.
    pub fn iterative(&mut self) -> Option<&mut IterativeSolve> {
        match &mut self.backend {
            LinearBackend::Amg(it) => Some(it),
            LinearBackend::Direct(_) => None,
        }
    }

    /// The coordinates of the rows (theory §8).
    pub fn basis(&self) -> &RowBasis {
        &self.basis
    }

    /// The step for active set `active`, tangent `k` (values on L's pattern), internal force
    /// `grad` = ∇E(u) and current gaps `gap`; the iterative backend solves to the relative
    /// residual `cg_tol` (the direct one is exact). The extras' system must be regular: every
    /// extra with a load needs an active row. Solved in the rows' coordinates y (module docs).
    pub fn step(
        &mut self,
        l: &Lagrangian<'_>,
        k: &[f64],
        active: &[bool],
        grad: &[f64],
        gap: &[f64],
        cg_tol: f64,
    ) -> Result<Step, SolveError> {
        self.analyse_if_due(l)?;
        let rows = l.data.rows;
        let (n, ne, nr) = (l.n_dofs(), l.n_extras(), rows.n_rows());
        let basis = &self.basis;
        let p = basis.pattern(l.pattern());
        let cp = p.col_ptr();
        // the tangent TᵀKT and the force Tᵀ∇E in the rows' coordinates (T = I: K and ∇E)
        let k_dofs = k;
        let (k, grad): (&[f64], &[f64]) = if basis.is_identity() {
            (k, grad)
        } else {
            basis.stiffness(k, &mut self.kt);
            basis.force_to_coordinates(grad, &mut self.grad_t);
            (&self.kt, &self.grad_t)
        };
        // TᵀKT with the active coordinates fixed: identity rows and columns, diagonal kept
        self.work.copy_from_slice(k);
        for i in (0..nr).filter(|&i| active[i]) {
            let s = basis.dof[i];
            self.work[cp[s] + 1..cp[s + 1]].iter_mut().for_each(|v| *v = 0.0);
            for &q in &self.transpose.pos[self.transpose.ptr[s]..self.transpose.ptr[s + 1]] {
                self.work[q] = 0.0;
            }
        }
        // the slipping pairs' Robin conditions: a N a on their (free) coordinates
        for sp in &self.slips {
            basis.add_pair_block(l.pattern(), sp.tangent, sp.n, &mut self.work);
        }
        let factorised = self.backend.cholesky().map(|chol| chol.factorise(&self.work));
        match factorised {
            None => {}
            // `auto`'s reserve that the machine cannot hold: the multigrid goes on
            Some(Err(LinalgError::OutOfMemory { .. })) if self.backend.give_up_reserve() => {}
            Some(result) => {
                result.in_solver(&self.solver)?;
                self.factorisations += 1;
            }
        }
        // prescribed values δ at the fixed coordinates: column 0 for the gaps, 1 + k for dV_k
        let nc = 1 + ne;
        let mut delta = vec![0.0; n * nc];
        for i in (0..nr).filter(|&i| active[i]) {
            let (s, a) = (basis.dof[i], basis.coef[i]);
            delta[s] = -gap[i] / a;
            for (kx, h) in rows.extra_row(i).iter().enumerate() {
                delta[(1 + kx) * n + s] = -h / a;
            }
        }
        // right-hand sides: −∇E − K δ (column 0), −K δ (others), then δ·diag at the fixed ones
        let mut x = vec![0.0; n * nc];
        for c in 0..nc {
            let (dcol, xcol) = (&delta[c * n..(c + 1) * n], &mut x[c * n..(c + 1) * n]);
            p.matvec(k, dcol, xcol);
            for j in 0..n {
                xcol[j] = -xcol[j] - if c == 0 { grad[j] } else { 0.0 };
            }
            for i in (0..nr).filter(|&i| active[i]) {
                let s = basis.dof[i];
                xcol[s] = self.work[cp[s]] * dcol[s];
            }
            // a slipping pair's forces F₀ (column 0) and its coupling −a N h to the extras
            for sp in &self.slips {
                for pi in 0..2 {
                    let i = sp.tangent + pi;
                    let (s, a) = (basis.dof[i], basis.coef[i]);
                    xcol[s] += a * if c == 0 {
                        sp.force[pi]
                    } else {
                        -(0..2).map(|q| sp.n[pi][q] * rows.extra_row(sp.tangent + q)[c - 1]).sum::<f64>()
                    };
                }
            }
        }
        let switched = matches!(&self.backend, LinearBackend::Amg(it) if it.switched);
        match &mut self.backend {
            LinearBackend::Direct(chol) => chol.solve_columns(&mut x, nc),
            LinearBackend::Amg(it) if switched => {
                it.reserve.as_mut().expect("taken only when kept").0.solve_columns(&mut x, nc)
            }
            LinearBackend::Amg(it) => {
                let IterativeSolve {
                    amg,
                    pcg,
                    a,
                    fill,
                    scratch,
                    col,
                    previous,
                    max_iter,
                    iterations,
                    unconverged,
                    refreshes,
                    refresh_above,
                    tangent,
                    built_on,
                    last_iterations,
                    spent,
                    spent_solves,
                    spent_cost,
                    built_products,
                    block,
                    block_solves,
                    ..
                } = &mut **it;
                a.assign_symmetric_lower(lower(p), &self.work, fill);
                let use_block = block.is_some();
                if *last_iterations > *refresh_above {
                    match block.as_deref() {
                        None => {
                            follow_the_tangent(amg, basis, a, tangent, l.pattern(), k_dofs, fill, built_on, refreshes)
                        }
                        Some(block) => follow_the_split_tangent(amg, block, l.pattern(), k_dofs, built_on, refreshes),
                    }
                }
                let fixed: Vec<(usize, f64)> =
                    (0..nr).filter(|&i| active[i]).map(|i| (basis.dof[i], self.work[cp[basis.dof[i]]])).collect();
                let pre = FixedDofs { amg, basis, fixed: &fixed, scratch };
                // the reactions come through T⁻ᵀ, which amplifies CG's residual by up to cond(T)
                let cg_tol = (cg_tol / basis.condition()).max(CG_TOL_MIN.min(cg_tol));
                previous.resize(n * (nc - 1), 0.0);
                for c in 0..nc {
                    let b = &x[c * n..(c + 1) * n];
                    // the displacement column from zero, the extras' columns from their last value
                    match c {
                        0 => col.iter_mut().for_each(|v| *v = 0.0),
                        _ => col.copy_from_slice(&previous[(c - 1) * n..c * n]),
                    }
                    // the Krylov solve's iterations and whether it reached its tolerance
                    let (its, converged) = match block.as_deref_mut() {
                        None => pcg.solve(a, &pre, b, col, cg_tol, *max_iter).map(|r| (r.iterations, r.converged)),
                        Some(block) => {
                            *block_solves += 1;
                            block
                                .solve(a, basis, &fixed, &pre, b, col, cg_tol, *max_iter)
                                .map(|r| (r.iterations, r.converged))
                        }
                    }
                    .map_err(|e| SolveError::Unsupported {
                        solver: self.solver.clone(),
                        message: format!("{} on the tangent: {e}", if use_block { "MINRES" } else { "CG" }),
                    })?;
                    *iterations += its;
                    *spent += its;
                    *spent_cost += its as f64 * iteration_cost(amg, *built_products);
                    *spent_solves += 1;
                    *last_iterations = its;
                    *unconverged += !converged as usize;
                    x[c * n..(c + 1) * n].copy_from_slice(col);
                    if c > 0 {
                        previous[(c - 1) * n..c * n].copy_from_slice(col);
                    }
                }
            }
        }
        self.solves += nc;
        // reactions at the fixed coordinates: λ = (Tᵀ∇E + TᵀKT dy)_s / a, affine in dV
        let mut kx = vec![0.0; n];
        let mut lam0 = vec![0.0; nr];
        let mut lam_v = DMatrix::zeros(nr, ne);
        for c in 0..nc {
            p.matvec(k, &x[c * n..(c + 1) * n], &mut kx);
            for i in (0..nr).filter(|&i| active[i]) {
                let (s, a) = (basis.dof[i], basis.coef[i]);
                if c == 0 {
                    lam0[i] = (grad[s] + kx[s]) / a;
                } else {
                    lam_v[(i, c - 1)] = kx[s] / a;
                }
            }
        }
        // the slipping pairs' forces F₀ − N δs, δs = a dy + H dV with dy = dy⁰ + W dV
        let mut carried = active.to_vec();
        for sp in &self.slips {
            for pi in 0..2 {
                let i = sp.tangent + pi;
                carried[i] = true;
                let at = |q: usize, c: usize| x[c * n + basis.dof[sp.tangent + q]] * basis.coef[sp.tangent + q];
                lam0[i] = sp.force[pi] - (0..2).map(|q| sp.n[pi][q] * at(q, 0)).sum::<f64>();
                for kx in 0..ne {
                    let h = |q: usize| rows.extra_row(sp.tangent + q)[kx];
                    lam_v[(i, kx)] = -(0..2).map(|q| sp.n[pi][q] * (at(q, 1 + kx) + h(q))).sum::<f64>();
                }
            }
        }
        let mut step = step_from_reactions(l, &carried, &x, &lam0, &lam_v, &self.solver)?;
        basis.displacement_from_coordinates(&mut step.du);
        Ok(step)
    }
}
