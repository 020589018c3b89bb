//! Stages 2–3 of a limit analysis (theory §13.3): the static problem as Clarabel's conic
//! programme, and its solve.
//!
//! Variables `x = [y_T for every stress point T, p_e for every element, λ_i for every closed
//! row, μ]`: the coordinates of the point's unknowns z_T = (σ_T, a_T) (Mandel σ, the cone's
//! auxiliary variables) in the basis of `lineality.rs` — `z_T = Σ_i y_T,i q_i + Σ_k p_e,k d_k`,
//! the d_k the directions of the cones' lineality space merged per element (B̄'s pressure under
//! von Mises or Tresca), else z_T itself —, non-dimensional: σ/S, λ/(S L²), μ F/(S L²) with the
//! stress scale S (the largest cone offset, k₀ for von Mises), the length L = (Σ_T w_T)^{1/3}
//! and the force scale F (the largest reference load). Minimise −μ subject to, as `A x + s = b`,
//! `s` in the cones, row blocks:
//!
//! 1. zero cone, per free dof j: `Σ_T w_T (B_Tᵀσ_T)_j − (Gᵀλ)_j − μ f_u,j = 0`;
//! 2. zero cone, per extra k: `−(Hᵀλ)_k − μ f_k = 0`, and with prescribed displacements one row
//!    `−ĉᵀλ − μ = 0` with the normalised rates ĉ = ċ/max|ċ| (`ReferenceLoads::rate`: μ is the
//!    reaction per unit of the largest prescribed displacement rate);
//! 3. nonnegative cone: `λ ≥ 0`;
//! 4. per point and per block of the yield surface's cones (`cones.rs`, the hardening columns
//!    dropped: q = 0): `offset + map·z_T` in the block's second-order or semidefinite cone.
//!
//! Its dual is the kinematic problem (theory §13.2): `v = −z₁/F`, `V = −z₂/F` with ℓ(v, V) = 1,
//! `G v + H V + ĉ τ = z₃ ≥ 0`, and the dissipation Σ_T offset·z₄,T.

use super::cones::{YieldBlock, YieldCones};
use super::lineality::StressBasis;
use super::{LimitAnalysis, LimitError, ReferenceLoads};
use crate::triplets::{Triplets, programme_json};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, SupportedConeT, ZeroConeT,
};
use saddle_core::DiscreteProblem;

/// The static problem of theory §13.3 in Clarabel's standard form (module docs).
pub struct StaticProgramme {
    /// Constraint matrix.
    a: CscMatrix<f64>,
    /// Right-hand side.
    b: Vec<f64>,
    /// The cones of the row blocks.
    cones: Vec<SupportedConeT<f64>>,
    /// Where the unknowns sit.
    pub(super) layout: Layout,
    /// Stress S, length L and force F scales.
    pub(super) scales: [f64; 3],
    /// The yield surface's warnings for a limit analysis (hardening ignored).
    pub(super) warnings: Vec<String>,
    /// The stress points' weights over L³.
    weights: Vec<f64>,
    /// The coordinates of the stress unknowns.
    pub(super) basis: StressBasis,
}

/// Where the unknowns and rows sit.
#[derive(Clone, Copy, Debug)]
pub(super) struct Layout {
    /// Stress points.
    pub n_points: usize,
    /// Coordinates y_T per point.
    pub per_point: usize,
    /// Elements (of `points_per_element` points each) and their merged unknowns p_e.
    pub n_elements: usize,
    /// Merged unknowns per element.
    pub per_element: usize,
    /// Free dofs (equilibrium rows).
    pub n_dofs: usize,
    /// Load rows on the extras (with the rate row).
    pub n_extra_rows: usize,
    /// Closed rows (λ columns, sign rows).
    pub n_closed: usize,
    /// Cone rows per point.
    pub cone_rows: usize,
    /// Second-order cones per point.
    pub cones_per_point: usize,
}

impl Layout {
    /// Column of the coordinate y_T,i.
    pub fn y_col(&self, t: usize, i: usize) -> usize {
        self.per_point * t + i
    }
    /// Column of element e's merged unknown p_e,k.
    pub fn p_col(&self, e: usize, k: usize) -> usize {
        self.per_point * self.n_points + self.per_element * e + k
    }
    /// Column of the k-th closed row's λ.
    pub fn lambda_col(&self, k: usize) -> usize {
        self.p_col(self.n_elements, 0) + k
    }
    /// Column of μ.
    pub fn mu_col(&self) -> usize {
        self.lambda_col(self.n_closed)
    }
    /// First cone row.
    pub fn cone_row0(&self) -> usize {
        self.n_dofs + self.n_extra_rows + self.n_closed
    }
    /// Number of rows.
    pub fn n_rows(&self) -> usize {
        self.cone_row0() + self.n_points * self.cone_rows
    }
}

/// What Clarabel returned, non-dimensional.
pub struct IpmResult {
    /// Termination status.
    pub status: SolverStatus,
    /// Iterations.
    pub iterations: usize,
    /// Primal x and dual z.
    pub x: Vec<f64>,
    /// Dual solution.
    pub z: Vec<f64>,
    /// Clarabel's primal and dual residuals.
    pub r_prim: f64,
    /// Dual residual.
    pub r_dual: f64,
}

impl StaticProgramme {
    /// Stage 2 (theory §13.3): the programme of `problem` with the reference loads `loads`, in
    /// stages: the yield cones, the coordinates of the stress unknowns, the scales, the columns
    /// of A by block, b and the cones.
    pub fn build(problem: &DiscreteProblem, loads: &ReferenceLoads) -> Result<Self, LimitError> {
        let YieldCones { blocks, width, warnings } = YieldCones::new(problem)?;
        let el = &*problem.element;
        let strain = el.strain_entries();
        let maps: Vec<f64> = blocks.iter().flat_map(|b| b.map.iter().copied()).collect();
        let k = problem.element.points_per_element();
        let basis = StressBasis::new(&maps, width, &strain, el.n_points(), k);
        let layout = Layout {
            n_points: el.n_points(),
            per_point: basis.per_point,
            n_elements: if basis.per_element > 0 { el.n_points() / k } else { 0 },
            per_element: basis.per_element,
            n_dofs: el.n_dofs(),
            n_extra_rows: loads.n_extra_rows(),
            n_closed: loads.closed.len(),
            cone_rows: blocks.iter().map(|b| b.offset.len()).sum(),
            cones_per_point: blocks.len(),
        };
        let scales = scales(problem, &blocks, loads);
        let cone_nnz: usize = blocks.iter().map(|b| b.map.iter().filter(|v| **v != 0.0).count()).sum();
        let nnz =
            2 * strain.len() + 2 * problem.obstacles.rows().val.len() + layout.n_dofs + layout.n_points * cone_nnz;
        let mut a = Triplets::with_capacity(nnz);
        equilibrium_columns(problem, strain, &basis, &layout, scales, &mut a);
        contact_columns(problem, loads, &layout, &mut a);
        multiplier_column(loads, &layout, &mut a);
        cone_rows(&blocks, &basis, &layout, &mut a);
        let a = a.into_csc(layout.n_rows(), layout.mu_col() + 1);
        let b = right_hand_side(&blocks, &layout, scales[0]);
        let cones = cones(&blocks, &layout);
        let vol = scales[1].powi(3);
        let weights = el.weights().iter().map(|w| w / vol).collect();
        Ok(Self { a, b, cones, layout, scales, warnings, weights, basis })
    }

    /// σ_T (non-dimensional, Mandel) from the solution x: its coordinates and its element's
    /// merged unknowns in the basis (module docs).
    pub(super) fn stress(&self, x: &[f64], t: usize) -> [f64; 6] {
        let lay = &self.layout;
        let y = &x[lay.y_col(t, 0)..lay.y_col(t, 0) + lay.per_point];
        let p = match lay.per_element {
            0 => &[][..],
            m => &x[lay.p_col(t / self.basis.points_per_element, 0)..][..m],
        };
        std::array::from_fn(|c| self.basis.entry(y, p, c))
    }

    /// Stage 3 (theory §13.3): Clarabel on the programme with the settings `s` and the
    /// regularisation `delta`; errors when the multiplier is unbounded (Clarabel finds the static
    /// problem dual infeasible) or Clarabel stops without a solution.
    pub fn solve(&self, s: &LimitAnalysis, delta: f64) -> Result<IpmResult, LimitError> {
        let settings = DefaultSettingsBuilder::default()
            .direct_solve_method("faer".to_owned())
            .max_threads(s.threads as u32)
            .verbose(s.verbose)
            .equilibrate_enable(true)
            .tol_gap_abs(s.tol)
            .tol_gap_rel(s.tol)
            .tol_feas(s.tol)
            .max_iter(s.max_iter as u32)
            .iterative_refinement_reltol(refinement_tol(s.tol))
            .iterative_refinement_abstol((refinement_tol(s.tol) / 10.0).max(1e-12))
            .build()
            .map_err(|e| LimitError::Rejected { what: "the settings", message: e.to_string() })?;
        let (p, q) = (self.regularisation(delta), self.objective());
        let mut solver = DefaultSolver::new(&p, &q, &self.a, &self.b, &self.cones, settings)
            .map_err(|e| LimitError::Rejected { what: "the programme", message: e.to_string() })?;
        solver.solve();
        if let Some(timers) = solver.timers.as_ref().filter(|_| s.verbose) {
            timers.print();
        }
        let sol = &solver.solution;
        let status = format!("{:?}", sol.status);
        match sol.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => {}
            SolverStatus::DualInfeasible | SolverStatus::AlmostDualInfeasible => {
                return Err(LimitError::Unbounded { status });
            }
            _ => {
                return Err(LimitError::NotSolved {
                    status,
                    iterations: sol.iterations as usize,
                    gap: solver.info.gap_rel,
                    r_prim: sol.r_prim,
                    r_dual: sol.r_dual,
                });
            }
        }
        Ok(IpmResult {
            status: sol.status,
            iterations: sol.iterations as usize,
            x: sol.x.clone(),
            z: sol.z.clone(),
            r_prim: sol.r_prim,
            r_dual: sol.r_dual,
        })
    }

    /// The objective's linear term: −1 on μ (maximise λ).
    fn objective(&self) -> Vec<f64> {
        let mut q = vec![0.0; self.n_variables()];
        q[self.layout.mu_col()] = -1.0;
        q
    }

    /// The programme as JSON for other conic solvers (without regularisation; the format of
    /// `socp::cone_programme_json`), for the cvxpy comparison of `examples/peers/`.
    pub fn json(&self) -> String {
        programme_json(&self.regularisation(0.0), &self.objective(), &self.a, &self.b, &self.cones)
    }

    /// The objective's quadratic term `δ Σ_T (w_T/L³)|z_T|²` (module docs, regularisation): the
    /// basis is orthonormal, so it is diagonal, `δ w_T` on y_T and `δ Σ_{T ∈ e} w_T` on p_e.
    fn regularisation(&self, delta: f64) -> CscMatrix<f64> {
        let lay = &self.layout;
        let n = lay.mu_col() + 1;
        let mut p = Triplets::with_capacity(lay.per_point * lay.n_points + lay.per_element * lay.n_elements);
        for (t, w) in self.weights.iter().enumerate() {
            for i in 0..lay.per_point {
                p.push_nonzero(lay.y_col(t, i), lay.y_col(t, i), delta * w);
            }
        }
        for (e, ws) in self.weights.chunks_exact(self.basis.points_per_element).enumerate().take(lay.n_elements) {
            let w: f64 = ws.iter().sum();
            for k in 0..lay.per_element {
                p.push_nonzero(lay.p_col(e, k), lay.p_col(e, k), delta * w);
            }
        }
        p.into_csc(n, n)
    }

    /// The right-hand side b (the cone offsets; zero elsewhere).
    pub(super) fn b(&self) -> &[f64] {
        &self.b
    }

    /// Number of variables of the programme.
    pub fn n_variables(&self) -> usize {
        self.layout.mu_col() + 1
    }

    /// Stress unknowns of the programme (coordinates per point and merged per element).
    pub fn n_stress_unknowns(&self) -> usize {
        self.layout.lambda_col(0)
    }

    /// Number of cones of the yield surface.
    pub fn n_cones(&self) -> usize {
        self.layout.n_points * self.layout.cones_per_point
    }
}

/// Stage 2b (theory §13.3, units): S the largest cone offset (else F/L²), L = (Σ w_T)^{1/3}, F
/// the largest reference load.
fn scales(problem: &DiscreteProblem, blocks: &[YieldBlock], loads: &ReferenceLoads) -> [f64; 3] {
    let length = problem.element.weights().iter().sum::<f64>().cbrt();
    let offsets = blocks.iter().flat_map(|b| b.offset.iter()).fold(0.0f64, |m, v| m.max(v.abs()));
    let stress = if offsets > 0.0 { offsets } else { loads.scale / (length * length) };
    [stress, length, loads.scale]
}

/// Stage 2c (block 1): the columns of the stress coordinates in the equilibrium rows,
/// Σ_T w_T B_Tᵀσ_T scaled by 1/L², with σ_T in the basis: w_T B_Tᵀ q_i,σ for y_T,i and
/// Σ_{T ∈ e} w_T B_Tᵀ d_k,σ for p_e,k (duplicates summed).
fn equilibrium_columns(
    problem: &DiscreteProblem,
    strain: Vec<(usize, usize, usize, f64)>,
    basis: &StressBasis,
    layout: &Layout,
    [_, length, _]: [f64; 3],
    a: &mut Triplets,
) {
    let w = problem.element.weights();
    for (t, c, j, v) in strain {
        let wv = w[t] * v / (length * length);
        for i in 0..layout.per_point {
            a.push_nonzero(j, layout.y_col(t, i), wv * basis.q(i)[c]);
        }
        for k in 0..layout.per_element {
            a.push_nonzero(j, layout.p_col(t / basis.points_per_element, k), wv * basis.d(k)[c]);
        }
    }
}

/// Stage 2d (blocks 1–3): the column of each closed row's λ: −G_iᵀ in the equilibrium rows,
/// −H_iᵀ in the extras' rows, −ċ_i in the rate row, −1 in its sign row.
fn contact_columns(problem: &DiscreteProblem, loads: &ReferenceLoads, layout: &Layout, a: &mut Triplets) {
    let rows = problem.obstacles.rows();
    let n = layout.n_dofs;
    let n_extras = loads.extras.len();
    for (k, &i) in loads.closed.iter().enumerate() {
        let col = layout.lambda_col(k);
        let (cols, vals) = rows.row(i);
        for (&j, &g) in cols.iter().zip(vals) {
            a.push(j, col, -g);
        }
        for (e, &h) in rows.extra_row(i).iter().enumerate() {
            a.push_nonzero(n + e, col, -h);
        }
        if let Some(rate) = &loads.rate {
            a.push_nonzero(n + n_extras, col, -rate[i]);
        }
        a.push(n + layout.n_extra_rows + k, col, -1.0);
    }
}

/// Stage 2e (blocks 1–2): the column of μ, −ℓ/F: −f_u/F, −f/F, and −1/F in the rate row.
fn multiplier_column(loads: &ReferenceLoads, layout: &Layout, a: &mut Triplets) {
    let (col, f) = (layout.mu_col(), loads.scale);
    for (j, fj) in loads.nodal.iter().enumerate() {
        a.push_nonzero(j, col, -fj / f);
    }
    for (k, fk) in loads.extras.iter().enumerate() {
        a.push_nonzero(layout.n_dofs + k, col, -fk / f);
    }
    if loads.rate.is_some() {
        a.push(layout.n_dofs + loads.extras.len(), col, -1.0 / f);
    }
}

/// Stage 2f (block 4): each point's cone maps on its coordinates y_T, negated (s = b − A x).
fn cone_rows(blocks: &[YieldBlock], basis: &StressBasis, layout: &Layout, a: &mut Triplets) {
    let per_point: Vec<Vec<f64>> = blocks
        .iter()
        .flat_map(|blk| blk.map.chunks_exact(basis.width).map(|row| basis.map_row(row)).collect::<Vec<_>>())
        .collect();
    for t in 0..layout.n_points {
        let row0 = layout.cone_row0() + t * layout.cone_rows;
        for (r, map_row) in per_point.iter().enumerate() {
            for (i, &v) in map_row.iter().enumerate() {
                a.push_nonzero(row0 + r, layout.y_col(t, i), -v);
            }
        }
    }
}

/// Stage 2g: b — each point's cone offsets over S, zero elsewhere.
fn right_hand_side(blocks: &[YieldBlock], layout: &Layout, stress: f64) -> Vec<f64> {
    let mut b = vec![0.0; layout.n_rows()];
    let per_point: Vec<f64> = blocks.iter().flat_map(|blk| blk.offset.iter().map(|o| o / stress)).collect();
    for t in 0..layout.n_points {
        let r0 = layout.cone_row0() + t * layout.cone_rows;
        b[r0..r0 + layout.cone_rows].copy_from_slice(&per_point);
    }
    b
}

/// Stage 2h: the cones of the row blocks — zero (equilibrium and load rows), nonnegative
/// (λ ≥ 0), the yield surface's cones at every point.
fn cones(blocks: &[YieldBlock], layout: &Layout) -> Vec<SupportedConeT<f64>> {
    let mut cones = Vec::with_capacity(2 + layout.n_points * blocks.len());
    if layout.n_dofs + layout.n_extra_rows > 0 {
        cones.push(ZeroConeT(layout.n_dofs + layout.n_extra_rows));
    }
    if layout.n_closed > 0 {
        cones.push(NonnegativeConeT(layout.n_closed));
    }
    for _ in 0..layout.n_points {
        cones.extend(blocks.iter().map(YieldBlock::cone));
    }
    cones
}

/// The iterative refinement of each KKT solve to `tol`·1e-5 (relative; absolute a tenth of it,
/// at least Clarabel's 1e-12) instead of Clarabel's fixed 1e-13 (theory §13.3): refining the Newton directions far below the tolerance the
/// interior point stops at buys nothing. On the 14k-dof strip punch at tol 1e-3 this halves the
/// solves' time (8.3 s to 3.6 s), with the same 14 iterations and the multiplier within 3e-6
/// (docs/limit_analysis.md).
fn refinement_tol(tol: f64) -> f64 {
    (tol * 1e-5).max(1e-13)
}
