//! Stages 2–3 of a limit analysis (theory §13.3): the static problem as Clarabel's conic
//! programme, and its solve.
//!
//! Variables `x = [σ_T (6 Mandel entries) for every stress point T, λ_i for every closed row,
//! μ]`, non-dimensional: σ/S, λ/(S L²), μ F/(S L²) with the stress scale S (the largest cone
//! offset, k₀ for von Mises), the length L = (Σ_T w_T)^{1/3} and the force scale F (the largest
//! reference load). Minimise −μ subject to, as `A x + s = b`, `s` in the cones, row blocks:
//!
//! 1. zero cone, per free dof j: `Σ_T w_T (B_Tᵀσ_T)_j − (Gᵀλ)_j − μ f_u,j = 0`;
//! 2. zero cone, per extra k: `−(Hᵀλ)_k − μ f_k = 0`, and with prescribed displacements one row
//!    `−ĉᵀλ − μ = 0` with the normalised rates ĉ = ċ/max|ċ| (`ReferenceLoads::rate`: μ is the
//!    reaction per unit of the largest prescribed displacement rate);
//! 3. nonnegative cone: `λ ≥ 0`;
//! 4. per point and per block of the yield surface's cone (`AdmissibleStresses::cone`, its
//!    hardening columns dropped: q = 0): `offset + map·σ_T ∈ SOC`.
//!
//! Its dual is the kinematic problem (theory §13.2): `v = −z₁/F`, `V = −z₂/F` with ℓ(v, V) = 1,
//! `G v + H V + ĉ τ = z₃ ≥ 0`, and the dissipation Σ_T offset·z₄,T.

use super::{LimitAnalysis, LimitError, ReferenceLoads};
use crate::triplets::{Triplets, programme_json};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SecondOrderConeT, SolverStatus, SupportedConeT,
    ZeroConeT,
};
use saddle_core::{DiscreteProblem, SocBlock};

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
}

/// Where the unknowns and rows sit.
#[derive(Clone, Copy, Debug)]
pub(super) struct Layout {
    /// Stress points.
    pub n_points: usize,
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
    /// Column of σ_T's entry c.
    pub fn sigma_col(&self, t: usize, c: usize) -> usize {
        6 * t + c
    }
    /// Column of the k-th closed row's λ.
    pub fn lambda_col(&self, k: usize) -> usize {
        6 * self.n_points + k
    }
    /// Column of μ.
    pub fn mu_col(&self) -> usize {
        6 * self.n_points + self.n_closed
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

/// Stage 2a (theory §13.3): the second-order cones of the yield surface's set D, each block's
/// map on σ alone (the hardening variables fixed at 0), checked; errors for an elastic scene or
/// a yield surface without a conic form. Warns when a hardening variable has a finite metric
/// (hardening ignored: the limit load of the initial yield set).
fn yield_cones(problem: &DiscreteProblem) -> Result<(Vec<SocBlock>, Vec<String>), LimitError> {
    let Some(p) = problem.stresses.as_deref() else {
        return Err(LimitError::Elastic { what: "no [yield] table".into() });
    };
    if p.is_unbounded() {
        return Err(LimitError::Elastic { what: format!("type = {:?} bounds no stress", p.name()) });
    }
    let cone = p
        .cone()
        .ok_or_else(|| LimitError::NoConicForm { yield_surface: p.name().into(), why: p.cone_unavailable() })?;
    let m = p.hardening_dim();
    let width = 6 + m;
    let mut blocks = Vec::with_capacity(cone.blocks.len());
    for (k, blk) in cone.blocks.iter().enumerate() {
        let bad = |message: String| LimitError::BadCone { yield_surface: p.name().into(), block: k, message };
        if blk.dim == 0 || blk.offset.len() != blk.dim || blk.map.len() != blk.dim * width {
            return Err(bad(format!(
                "dim {}, {} offsets, {} map entries (expected dim ≥ 1, dim offsets, dim × {width} map entries)",
                blk.dim,
                blk.offset.len(),
                blk.map.len()
            )));
        }
        if blk.offset.iter().chain(&blk.map).any(|v| !v.is_finite()) {
            return Err(bad("non-finite entries".into()));
        }
        let map = blk.map.chunks_exact(width).flat_map(|row| row[..6].iter().copied()).collect();
        blocks.push(SocBlock { dim: blk.dim, offset: blk.offset.clone(), map });
    }
    let mut warnings = Vec::new();
    let unit = |k: usize| -> Vec<f64> { (0..m).map(|j| (j == k) as usize as f64).collect() };
    let hardening: Vec<usize> = (0..m).filter(|&k| p.hardening_inner(&unit(k), &unit(k)).is_finite()).collect();
    if !hardening.is_empty() {
        let names: Vec<&str> = p.hardening_fields().iter().map(|(n, _)| *n).collect();
        warnings.push(format!(
            "yield: type = {:?} hardens ({} with a finite hardening metric, e.g. h > 0): the hardening is ignored, \
             the limit load is that of the initial yield set taken perfectly plastic (theory §13.1)",
            p.name(),
            names.join(", ")
        ));
    }
    Ok((blocks, warnings))
}

impl StaticProgramme {
    /// Stage 2 (theory §13.3): the programme of `problem` with the reference loads `loads`, in
    /// stages: the yield cones, the scales, the columns of A by block, b and the cones.
    pub fn build(problem: &DiscreteProblem, loads: &ReferenceLoads) -> Result<Self, LimitError> {
        let (blocks, warnings) = yield_cones(problem)?;
        let el = &*problem.element;
        let layout = Layout {
            n_points: el.n_points(),
            n_dofs: el.n_dofs(),
            n_extra_rows: loads.n_extra_rows(),
            n_closed: loads.closed.len(),
            cone_rows: blocks.iter().map(|b| b.dim).sum(),
            cones_per_point: blocks.len(),
        };
        let scales = scales(problem, &blocks, loads);
        let strain = el.strain_entries();
        let cone_nnz: usize = blocks.iter().map(|b| b.map.iter().filter(|v| **v != 0.0).count()).sum();
        let nnz = strain.len() + 2 * problem.obstacles.rows().val.len() + layout.n_dofs + layout.n_points * cone_nnz;
        let mut a = Triplets::with_capacity(nnz);
        equilibrium_columns(problem, strain, &layout, scales, &mut a);
        contact_columns(problem, loads, &layout, &mut a);
        multiplier_column(loads, &layout, &mut a);
        cone_rows(&blocks, &layout, &mut a);
        let a = a.into_csc(layout.n_rows(), layout.mu_col() + 1);
        let b = right_hand_side(&blocks, &layout, scales[0]);
        let cones = cones(&blocks, &layout);
        let vol = scales[1].powi(3);
        let weights = el.weights().iter().map(|w| w / vol).collect();
        Ok(Self { a, b, cones, layout, scales, warnings, weights })
    }

    /// Stage 3 (theory §13.3): Clarabel on the programme with the settings `s` and the
    /// regularisation `delta`; errors when the multiplier is unbounded (Clarabel finds the static
    /// problem dual infeasible) or Clarabel stops without a solution.
    pub fn solve(&self, s: &LimitAnalysis, delta: f64) -> Result<IpmResult, LimitError> {
        let settings = DefaultSettingsBuilder::default()
            .direct_solve_method("faer".to_owned())
            .max_threads(s.threads as u32)
            .verbose(false)
            .equilibrate_enable(true)
            .tol_gap_abs(s.tol)
            .tol_gap_rel(s.tol)
            .tol_feas(s.tol)
            .max_iter(s.max_iter as u32)
            .build()
            .map_err(|e| LimitError::Rejected { what: "the settings", message: e.to_string() })?;
        let (p, q) = (self.regularisation(delta), self.objective());
        let mut solver = DefaultSolver::new(&p, &q, &self.a, &self.b, &self.cones, settings)
            .map_err(|e| LimitError::Rejected { what: "the programme", message: e.to_string() })?;
        solver.solve();
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

    /// The objective's quadratic term: `δ (w_T/L³)` on every stress entry (module docs,
    /// regularisation), diagonal.
    fn regularisation(&self, delta: f64) -> CscMatrix<f64> {
        let n = self.layout.mu_col() + 1;
        let mut p = Triplets::with_capacity(6 * self.layout.n_points);
        for (t, w) in self.weights.iter().enumerate() {
            for c in 0..6 {
                p.push_nonzero(self.layout.sigma_col(t, c), self.layout.sigma_col(t, c), delta * w);
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

    /// Number of second-order cones.
    pub fn n_cones(&self) -> usize {
        self.layout.n_points * self.layout.cones_per_point
    }
}

/// Stage 2b (theory §13.3, units): S the largest cone offset (else F/L²), L = (Σ w_T)^{1/3}, F
/// the largest reference load.
fn scales(problem: &DiscreteProblem, blocks: &[SocBlock], loads: &ReferenceLoads) -> [f64; 3] {
    let length = problem.element.weights().iter().sum::<f64>().cbrt();
    let offsets = blocks.iter().flat_map(|b| b.offset.iter()).fold(0.0f64, |m, v| m.max(v.abs()));
    let stress = if offsets > 0.0 { offsets } else { loads.scale / (length * length) };
    [stress, length, loads.scale]
}

/// Stage 2c (block 1): the columns of σ in the equilibrium rows, Σ_T w_T B_Tᵀσ_T scaled by 1/L².
fn equilibrium_columns(
    problem: &DiscreteProblem,
    strain: Vec<(usize, usize, usize, f64)>,
    layout: &Layout,
    [_, length, _]: [f64; 3],
    a: &mut Triplets,
) {
    let w = problem.element.weights();
    for (t, c, j, v) in strain {
        a.push(j, layout.sigma_col(t, c), w[t] * v / (length * length));
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

/// Stage 2f (block 4): each point's cone maps on its σ, negated (s = b − A x).
fn cone_rows(blocks: &[SocBlock], layout: &Layout, a: &mut Triplets) {
    for t in 0..layout.n_points {
        let mut row = layout.cone_row0() + t * layout.cone_rows;
        for blk in blocks {
            for map_row in blk.map.chunks_exact(6) {
                for (c, &v) in map_row.iter().enumerate() {
                    a.push_nonzero(row, layout.sigma_col(t, c), -v);
                }
                row += 1;
            }
        }
    }
}

/// Stage 2g: b — each point's cone offsets over S, zero elsewhere.
fn right_hand_side(blocks: &[SocBlock], layout: &Layout, stress: f64) -> Vec<f64> {
    let mut b = vec![0.0; layout.n_rows()];
    let per_point: Vec<f64> = blocks.iter().flat_map(|blk| blk.offset.iter().map(|o| o / stress)).collect();
    for t in 0..layout.n_points {
        let r0 = layout.cone_row0() + t * layout.cone_rows;
        b[r0..r0 + layout.cone_rows].copy_from_slice(&per_point);
    }
    b
}

/// Stage 2h: the cones of the row blocks — zero (equilibrium and load rows), nonnegative
/// (λ ≥ 0), the yield surface's second-order cones at every point.
fn cones(blocks: &[SocBlock], layout: &Layout) -> Vec<SupportedConeT<f64>> {
    let mut cones = Vec::with_capacity(2 + layout.n_points * blocks.len());
    if layout.n_dofs + layout.n_extra_rows > 0 {
        cones.push(ZeroConeT(layout.n_dofs + layout.n_extra_rows));
    }
    if layout.n_closed > 0 {
        cones.push(NonnegativeConeT(layout.n_closed));
    }
    for _ in 0..layout.n_points {
        cones.extend(blocks.iter().map(|blk| SecondOrderConeT(blk.dim)));
    }
    cones
}
