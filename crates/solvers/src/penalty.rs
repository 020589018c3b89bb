//! The penalty method: the regularised Lagrangian L_μ of the paper's existence proof (SPEC §4),
//! maximised without constraints by Newton's method.
//!
//! # L_μ in physical units
//!
//! SPEC §4 writes `L_μ = L − (1/(2μ))∫_{Γ₀}[(v₃ + φ − V)⁻]² − (μ/2)‖ε(v)‖² − (μ/2)V²` in the
//! paper's scaled units. Here μ is a *dimensionless* number that means the same thing in any
//! units and on any mesh: every term is measured against the elastic stiffness
//! K_el = Σ_T |T| B_Tᵀ C B_T where it acts. With the rows g(u, V) = G u + H V + c ≥ 0 of K_h
//! (SPEC §3), each acting on one displacement dof s_i with coefficient a_i = G_{i s_i},
//! maximising L_μ over (v, V) ∈ W_h × R is minimising
//!
//! ```text
//! J_μ(u, V) = Σ_T |T| ψ(ε_T(u)) − f·V  +  Σ_i ½ k_i (g_i⁻)²  +  (μ/2) uᵀK_el u  +  (μ/2) Σ_k k_V,k V_k²
//! ```
//!
//! with g⁻ = max(0, −g) and
//!
//! * `k_i = (K_el)_{s_i s_i} / (μ a_i²)` — the contact penalty stiffness: 1/μ times the elastic
//!   stiffness of the node in the row's direction (≈ E·h, so μ is relative to the local mesh size,
//!   also on graded meshes); a_i = 1 for the punch;
//! * `(μ/2) uᵀK_el u = (μ/2)(Cε(u), ε(u))` — the SPEC's (μ/2)‖ε(v)‖² in the energy metric;
//! * `k_V,k = E · L · mean_i H_ik²` over the rows touching extra k, L = |Ω|^{1/3} — the SPEC's
//!   (μ/2)V² with V weighted by the stiffness of the body as a whole (a mesh-independent scale:
//!   summing the nodal stiffnesses instead grows like 1/h under refinement and with it the load
//!   carried by the regularisation, μ k_V V).
//!
//! The penalty contact pressure of SPEC (1.16) is `χ_i = k_i g_i⁻ ≥ 0`; it is returned as λ.
//!
//! # Algorithm
//!
//! J_μ is convex and C¹ with the semismooth gradient `∇_u J_μ = Bᵀ(σ(u) + μCε(u)) − Gᵀχ`,
//! `∇_V J_μ = −f − Hᵀχ + μ k_V V`; for a set A of rows its generalised Hessian is
//!
//! ```text
//! [ K_t + μK_el + Σ_{i∈A} k_i a_i² e_s e_sᵀ     Σ_{i∈A} k_i a_i e_s H_iᵀ         ]
//! [ Σ_{i∈A} k_i a_i H_i e_sᵀ                    μ diag(k_V) + Σ_{i∈A} k_i H_i H_iᵀ ]
//! ```
//!
//! (K_t: the consistent tangent of SPEC §2). The contact rows only add to the diagonal, so the
//! u-block lives on the fixed pattern of L: one symbolic analysis per solve, numeric
//! factorisations on it. The extras are coupled through an n_extras × n_extras Schur complement
//! from one solve with 1 + n_extras right-hand sides, formed without the catastrophic
//! cancellation of the textbook `C − BᵀA⁻¹B` ([`PenaltySystem`]).
//!
//! Each Newton iteration:
//!
//! 1. the local law with its consistent tangent at every element (SPEC §2);
//! 2. the step d minimises the model `∇S·d + ½dᵀ(K_t + μK_el)d + Σ_i ½k_i((g_i + Δg_i(d))⁻)²` of
//!    J_μ = S + (contact term): the smooth part expanded to second order, the piecewise quadratic
//!    contact term kept *exactly*. It is found by an active-set loop on the model (A = rows that
//!    penetrate after the step; one factorisation each; usually one, two when the contact zone
//!    moves). Linearising the contact term instead (A = rows penetrating now) would let the first
//!    row that a step pushes into the obstacle, with its 1/μ stiffness, stop the line search: on
//!    fine meshes one row per iteration would enter;
//! 3. an Armijo backtracking line search on J_μ along d — a descent direction of J_μ since the
//!    model is convex with the same directional derivative — with safeguarded quadratic
//!    interpolation; the full step is taken when the predicted decrease is below the round-off of
//!    J_μ.
//!
//! From a cold start the first iteration uses the *elastic* tangent and takes the full step (as
//! [`crate::Newton`] does): its model is then exact, so it lands on the elastic penalty solution,
//! its active-set loop started from every candidate row (the punch imprints its shape instead of
//! pushing one node through the body, which would drive it plastic). The inner problem is solved
//! when the relative gradient of J_μ is at round-off ([`GRADIENT_TOL`]) or the Newton step is
//! ([`STEP_TOL`]): J_μ is then minimised to machine precision.
//!
//! **The gaps are carried, not recomputed.** χ = k g⁻ multiplies the gap by 1/μ, and g = u_s + φ −
//! V recomputed from (u, V) is known only to ε_mach·|u|: χ would carry a round-off error
//! ε_mach·k·|u| ∝ 1/μ (measured on the small default scene: a KKT floor of 1e-6 at μ = 1e-10,
//! optimum 3e-7 near μ = 1e-8 — the classical √ε_mach limit of penalty methods). The solver keeps
//! g alongside (u, V), starting from g(0, 0) = c. On the model's active rows the Newton step gives
//! the new gap directly, `ĝ_i = −a_i(y⁰ − Y dV)_s` (of size χ/k, computed from quantities of that
//! size), elsewhere `ĝ = g + G du + H dV`; along the line search `g(α) = (1 − α)g + αĝ`. The carried
//! gaps differ from G u + H V + c by a few ulps of |u| (counter `gap_drift_relative`): the problem
//! solved is the one with the obstacle offsets c perturbed at round-off level. With this and the
//! cancellation-free Schur complement, round-off never takes over: measured (the μ study in
//! `tests/penalty.rs`), the error falls like μ until it meets the reference's own accuracy, and
//! for μ from 1e-12 down to 1e-300 the solve takes the same iterations and U agrees with Newton to
//! round-off below μ = 1e-15; only a μ whose stiffness overflows is refused. The
//! `condition_estimate` grows like 1/μ nonetheless: it describes the matrix, not the accuracy of
//! these structured solves.
//!
//! # Honesty
//!
//! The penalty solves a regularised problem: its error against the solution of (2.1) is O(μ)
//! (penetration χ/k, the load carried by the regularisation, the stiffening μK_el). The report
//! therefore carries the residual of the *true* problem: `kkt` = [`Lagrangian::kkt`] on
//! (u, V, σ(u), χ), `tol` is a tolerance on that residual, and a solve whose inner problem is
//! solved but whose penalty error exceeds `tol` returns its solution with `converged = false`,
//! [`StopReason::ApproximationLimit`] and the counter `approximation_limit = 1`. The counters
//! carry the penalty's own error indicators: `max_penetration` (max g⁻, absolute and relative to
//! the displacement scale), `load_defect` = ‖f + Hᵀχ‖ (|Σχ − F| for the punch; absolute and
//! relative to ‖f‖), `mu`, and `condition_estimate` (see [`PenaltySystem`]).

use crate::active_set::SlaveRows;
use crate::linear::{InSolver, lower};
use crate::residual;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use saddle_core::error::{ParameterError, check};
use saddle_core::linalg::SparseCholesky;
use saddle_core::problem::lagrangian::{Iterate, Lagrangian, Material, StressField, Workspace, max_abs, norm};
use saddle_core::problem::solver::{Monitor, PhaseTimer, Solution, SolveError, SolveReport, Solver, StopReason};
use saddle_core::{Sym, SymOp};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The inner problem is solved when ‖∇J_μ‖ falls below this fraction of the size of its terms.
pub const GRADIENT_TOL: f64 = 1e-12;
/// ... or when the Newton step falls below this fraction of the displacement scale.
pub const STEP_TOL: f64 = 1e-13;
/// Active-set sweeps of the contact model per Newton step before falling back to the plain
/// semismooth Newton direction.
const MODEL_SWEEPS: usize = 10;
/// Backtracking steps before the line search gives up.
const MAX_BACKTRACKS: usize = 60;

/// `type = "penalty"`: the regularised Lagrangian L_μ of the existence proof (SPEC §4), solved
/// by Newton's method.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Penalty {
    /// The dimensionless regularisation μ: penalty stiffness = elastic stiffness / μ. The error
    /// against the discrete problem of SPEC §3 is O(μ): measured, the true KKT residual is ≈ 4.2μ
    /// on the small default scene and ≈ 4.4μ on `examples/johnson.toml` (mesh-independent: the
    /// regularisation of V uses the body's stiffness E·|Ω|^{1/3}). The default 1e-12 meets the
    /// default `tol` with a margin of ~1000.
    pub mu: f64,
    /// Tolerance on the relative KKT residual of the *true* problem (SPEC §3, §5).
    pub tol: f64,
    /// Newton iteration budget.
    pub max_iter: usize,
}

impl Default for Penalty {
    fn default() -> Self {
        Self { mu: 1e-12, tol: 1e-8, max_iter: 50 }
    }
}

#[typetag::serde(name = "penalty")]
impl Solver for Penalty {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::positive(path, "mu", self.mu)?;
        check::open_interval(path, "tol", self.tol, 0.0, 1.0)?;
        check::at_least_one(path, "max_iter", self.max_iter)?;
        Ok(())
    }

    fn tolerance(&self) -> f64 {
        self.tol
    }

    fn solve(&self, l: &dyn Lagrangian, monitor: &mut dyn Monitor) -> Result<Solution, SolveError> {
        self.validate("solver")?;
        let mut timer = PhaseTimer::default();
        monitor.phase("set-up");
        let mut sys = timer.time("set-up", || PenaltySystem::new(l, self.mu))?;
        self.newton(l, &mut sys, monitor, timer)
    }
}

/// The penalty scales of J_μ and its Newton system.
///
/// For a set A of rows, with D_A = diag(k_i a_i²) at the slave dofs, z_s = −g_i/a_i and
/// `P_k[s] = H_ik/a_i` on A, the u-block is A = K' + D_A (K' = K_t + μK_el) and the coupling to
/// the extras is D_A P. Since `A⁻¹D_A x = x − A⁻¹K'x`, eliminating du needs
/// `[y⁰ Y] = A⁻¹[r + K'z, K'P]` (r = Bᵀ(σ + μCε), right-hand sides of moderate size), and then
///
/// ```text
/// S = μ diag(k_V) + Pᵀ D_A Y,   S dV = f − μ k_V V + Pᵀ D_A y⁰,   du = z − y⁰ − (P − Y) dV,
/// ```
///
/// free of the cancellation of `C − BᵀA⁻¹B` (two terms of size 1/μ whose difference is of size 1).
///
/// `condition_estimate` is max/min of the diagonal of the last factorised u-block: a lower
/// bound of its spectral condition number, which the penalty raises by ~1/μ.
pub struct PenaltySystem {
    mu: f64,
    slaves: SlaveRows,
    /// k_i = (K_el)_{ss} / (μ a_i²).
    k: Vec<f64>,
    /// k_V,k = Σ_i H_ik² (K_el)_{ss}.
    k_v: Vec<f64>,
    c_el: SymOp,
    chol: SparseCholesky,
    /// K' = K_t + μK_el on L's pattern.
    kprime: Vec<f64>,
    /// K' + D_A, factorised.
    hess: Vec<f64>,
    /// n × (1 + n_extras): [z, P_1, …].
    cols: Vec<f64>,
    /// n × (1 + n_extras): [r + K'z, K'P_1, …], then [y⁰, Y_1, …].
    kcols: Vec<f64>,
    /// The model's next active set.
    next: Vec<bool>,
    /// Numeric factorisations so far.
    pub factorisations: usize,
    /// Triangular solve pairs so far.
    pub solves: usize,
    /// max/min diagonal of the last factorised matrix.
    pub condition_estimate: f64,
}

impl std::fmt::Debug for PenaltySystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PenaltySystem").field("mu", &self.mu).field("rows", &self.k.len()).finish()
    }
}

/// The current iterate as the Newton step sees it.
struct Point<'a> {
    /// Bᵀ(σ + μCε) − f_u: the gradient of the smooth part.
    r: &'a [f64],
    /// The carried gaps g.
    gap: &'a [f64],
    /// V.
    v: &'a [f64],
}

/// The Newton step and the gaps it leads to.
struct Direction<'a> {
    du: &'a mut [f64],
    dv: &'a mut [f64],
    /// ĝ = g(u + du, V + dV).
    g_next: &'a mut [f64],
}

impl PenaltySystem {
    /// The penalty scales from the elastic stiffness diagonal, and the symbolic analysis of L's
    /// pattern (once).
    pub fn new(l: &dyn Lagrangian, mu: f64) -> Result<Self, SolveError> {
        let rows = l.constraints();
        let slaves = SlaveRows::new(rows, l.n_dofs(), "penalty")?;
        let c_el = l.elasticity().stiffness_matrix();
        let mut kprime = l.stiffness(Material::Uniform(&c_el));
        let diag = l.pattern().diagonal(&kprime);
        let k: Vec<f64> = (0..rows.n_rows()).map(|i| diag[slaves.dof[i]] / (mu * slaves.coef[i].powi(2))).collect();
        if let Some(i) = k.iter().position(|k| !k.is_finite()) {
            let why =
                format!("is too small: the penalty stiffness (elastic stiffness / mu) of contact row {i} overflows");
            return Err(ParameterError::new("solver.mu", mu, why).into());
        }
        let ne = l.n_extras();
        let body_stiffness = l.elasticity().young * l.weights().iter().sum::<f64>().cbrt();
        let k_v: Vec<f64> = (0..ne)
            .map(|kx| {
                let h2: Vec<f64> =
                    (0..rows.n_rows()).map(|i| rows.extra_row(i)[kx].powi(2)).filter(|h| *h > 0.0).collect();
                if h2.is_empty() { 0.0 } else { body_stiffness * h2.iter().sum::<f64>() / h2.len() as f64 }
            })
            .collect();
        for (kx, kv) in k_v.iter().enumerate() {
            if *kv <= 0.0 && l.load()[kx] != 0.0 {
                return Err(SolveError::Unsupported {
                    solver: "penalty".into(),
                    message: format!("extra unknown {kx} carries a load but no contact row acts on it"),
                });
            }
        }
        let n = l.n_dofs();
        kprime.iter_mut().for_each(|x| *x = 0.0);
        Ok(Self {
            mu,
            slaves,
            k,
            k_v,
            c_el,
            chol: SparseCholesky::analyse(lower(l.pattern()), "penalty Hessian").in_solver("penalty")?,
            hess: vec![0.0; kprime.len()],
            kprime,
            cols: vec![0.0; n * (1 + ne)],
            kcols: vec![0.0; n * (1 + ne)],
            next: vec![false; rows.n_rows()],
            factorisations: 0,
            solves: 0,
            condition_estimate: f64::NAN,
        })
    }

    /// χ_i = k_i g_i⁻.
    fn pressures(&self, gap: &[f64], chi: &mut [f64]) {
        for ((c, g), k) in chi.iter_mut().zip(gap).zip(&self.k) {
            *c = k * (-g).max(0.0);
        }
    }

    /// J_μ(u, V) with the gaps `gap` = g(u, V); `ws.eps` holds ε(u) afterwards.
    fn energy(&self, l: &dyn Lagrangian, u: &[f64], v: &[f64], gap: &[f64], ws: &mut Workspace) -> f64 {
        let j = l.energy(u, v, ws);
        let c = &self.c_el;
        let reg: f64 = ws.eps.par_iter().zip(l.weights().par_iter()).map(|(e, w)| w * e.dot(&(c * e))).sum();
        let pen: f64 = gap.iter().zip(&self.k).map(|(g, k)| k * (-g).max(0.0).powi(2)).sum();
        let reg_v: f64 = self.k_v.iter().zip(v).map(|(k, v)| k * v * v).sum();
        j + 0.5 * (self.mu * (reg + reg_v) + pen)
    }

    /// The Newton step of the contact model (module docs, step 2) with K' in `self.kprime`: an
    /// active-set loop from `model`, which holds the final set on return. Returns the number of
    /// sweeps and whether the set settled; if not, and `descent` asks for a descent direction of
    /// J_μ, d is the plain semismooth Newton direction (A = {g < 0}), else the last sweep's.
    fn model_step(
        &mut self,
        l: &dyn Lagrangian,
        model: &mut [bool],
        at: &Point<'_>,
        d: &mut Direction<'_>,
        descent: bool,
    ) -> Result<(usize, bool), SolveError> {
        for sweep in 1..=MODEL_SWEEPS {
            self.step(l, model, at, d)?;
            let mut settled = true;
            for ((next, g), a) in self.next.iter_mut().zip(d.g_next.iter()).zip(model.iter()) {
                *next = *g < 0.0;
                settled &= *next == *a;
            }
            if settled {
                return Ok((sweep, true));
            }
            if sweep == MODEL_SWEEPS && !descent {
                return Ok((sweep, false));
            }
            model.copy_from_slice(&self.next);
        }
        for (a, g) in model.iter_mut().zip(at.gap) {
            *a = *g < 0.0;
        }
        self.step(l, model, at, d)?;
        Ok((MODEL_SWEEPS + 1, false))
    }

    /// The Newton step for the quadratic model in which the rows `active` carry ½k_i g_i²
    /// (formulas in the type's docs), and the gaps ĝ after it.
    fn step(
        &mut self,
        l: &dyn Lagrangian,
        active: &[bool],
        at: &Point<'_>,
        d: &mut Direction<'_>,
    ) -> Result<(), SolveError> {
        let p = l.pattern();
        let rows = l.constraints();
        let (n, ne, nr) = (l.n_dofs(), l.n_extras(), rows.n_rows());
        let nc = 1 + ne;
        // z and P on the active slave dofs; K' times them, plus r in column 0
        self.cols.iter_mut().for_each(|x| *x = 0.0);
        for i in (0..nr).filter(|&i| active[i]) {
            let (s, a) = (self.slaves.dof[i], self.slaves.coef[i]);
            self.cols[s] = -at.gap[i] / a;
            for (kx, h) in rows.extra_row(i).iter().enumerate() {
                self.cols[(1 + kx) * n + s] = h / a;
            }
        }
        for c in 0..nc {
            p.matvec(&self.kprime, &self.cols[c * n..(c + 1) * n], &mut self.kcols[c * n..(c + 1) * n]);
        }
        for (x, ri) in self.kcols[..n].iter_mut().zip(at.r) {
            *x += ri;
        }
        // A = K' + D_A on the fixed pattern
        let cp = p.col_ptr();
        self.hess.copy_from_slice(&self.kprime);
        for i in (0..nr).filter(|&i| active[i]) {
            self.hess[cp[self.slaves.dof[i]]] += self.k[i] * self.slaves.coef[i].powi(2);
        }
        let (dmin, dmax) = cp[..n].iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &q| {
            let x = self.hess[q];
            (lo.min(x), hi.max(x))
        });
        self.condition_estimate = dmax / dmin;
        self.chol.factorise(&self.hess).in_solver("penalty")?;
        self.factorisations += 1;
        self.chol.solve_columns(&mut self.kcols, nc);
        self.solves += nc;
        let (y0, y) = self.kcols.split_at(n);
        // the extras: S dV = b
        if ne > 0 {
            let mut s = DMatrix::<f64>::zeros(ne, ne);
            let mut b = DVector::<f64>::zeros(ne);
            for kx in 0..ne {
                s[(kx, kx)] = self.mu * self.k_v[kx];
                b[kx] = l.load()[kx] - self.mu * self.k_v[kx] * at.v[kx];
            }
            for i in (0..nr).filter(|&i| active[i]) {
                let (sd, ka) = (self.slaves.dof[i], self.k[i] * self.slaves.coef[i]);
                for (kx, h) in rows.extra_row(i).iter().enumerate() {
                    b[kx] += ka * h * y0[sd];
                    for ly in 0..ne {
                        s[(kx, ly)] += ka * h * y[ly * n + sd];
                    }
                }
            }
            let s = (&s + s.transpose()) * 0.5;
            let sol = s.lu().solve(&b).filter(|x| x.iter().all(|x| x.is_finite()));
            let sol = sol.ok_or_else(|| non_finite("the extras' Schur complement", self.factorisations))?;
            d.dv.copy_from_slice(sol.as_slice());
        }
        // du = z − y⁰ − (P − Y) dV
        for j in 0..n {
            let mut x = self.cols[j] - y0[j];
            for (kx, dv) in d.dv.iter().enumerate() {
                x -= (self.cols[(1 + kx) * n + j] - y[kx * n + j]) * dv;
            }
            d.du[j] = x;
        }
        // ĝ: on the active rows from the model, ĝ_i = g_i + a_i du_s + H_i dV = −a_i(y⁰ − Y dV)_s,
        // which is of size χ/k and would be lost in the rounding of g + G du + H dV at μ ≲ 1e-14;
        // on the others by the increment
        for (i, gn) in d.g_next.iter_mut().enumerate() {
            let (s, a) = (self.slaves.dof[i], self.slaves.coef[i]);
            *gn = if active[i] {
                -a * (y0[s] - d.dv.iter().enumerate().map(|(kx, dv)| y[kx * n + s] * dv).sum::<f64>())
            } else {
                at.gap[i] + a * d.du[s] + rows.extra_row(i).iter().zip(d.dv.iter()).map(|(h, x)| h * x).sum::<f64>()
            };
        }
        Ok(())
    }
}

impl Penalty {
    /// Newton on J_μ (module docs), then the honest report.
    fn newton(
        &self,
        l: &dyn Lagrangian,
        sys: &mut PenaltySystem,
        monitor: &mut dyn Monitor,
        mut timer: PhaseTimer,
    ) -> Result<Solution, SolveError> {
        let rows = l.constraints();
        let (n, ne, nr, np) = (l.n_dofs(), l.n_extras(), rows.n_rows(), l.n_points());
        let mu = self.mu;
        let plastic = l.plasticity().is_some();
        let c_el = sys.c_el;
        let c_el_mu = c_el * (1.0 + mu);
        let (mut u, mut v) = (vec![0.0; n], vec![0.0; ne]);
        // the gaps are carried along with (u, V) (module docs): g(0, 0) = c
        let mut gap = rows.offset.clone();
        let (mut du, mut dv, mut g_next) = (vec![0.0; n], vec![0.0; ne], vec![0.0; nr]);
        let (mut u_trial, mut v_trial, mut gap_trial) = (vec![0.0; n], vec![0.0; ne], vec![0.0; nr]);
        let mut ws = Workspace::new(l);
        let mut stress = StressField::new(np, l.hardening_dim());
        let mut tangents = vec![SymOp::zeros(); np];
        let mut sig_mu = vec![Sym::zeros(); np];
        let (mut r, mut grad_u, mut grad_v) = (vec![0.0; n], vec![0.0; n], vec![0.0; ne]);
        let (mut gt_chi, mut ht_chi) = (vec![0.0; n], vec![0.0; ne]);
        let mut chi = vec![0.0; nr];
        let (mut model, mut previous) = (vec![true; nr], vec![true; nr]);
        let mut history = Vec::new();
        let (mut backtracks, mut active_changes, mut return_mappings) = (0usize, 0usize, 0usize);
        let (mut sweeps, mut unsettled, mut line_search_failures) = (0usize, 0usize, 0usize);
        let (mut finished, mut stuck) = (false, false);
        let mut grad_rel;
        let mut decrement_rel = f64::NAN;
        monitor.phase("iterations");
        let mut it = 0;
        let (stop, kkt) = loop {
            // the cold iteration is elastic: its model is exact, its step full
            let elastic = it == 0;
            // 1. pressures, the local law (SPEC §2) with tangents when Newton needs them
            sys.pressures(&gap, &mut chi);
            let want_tangents = !elastic && !finished && plastic;
            timer.time("local law", || {
                l.strain(&u, &mut ws.eps);
                l.local_law(&ws.eps, &mut stress, if want_tangents { Some(&mut tangents) } else { None });
            });
            if plastic {
                return_mappings += np;
            }
            // 2. the residual of the *true* problem on (u, V, σ(u), χ)
            let kkt = timer.time("residual", || {
                ws.stress.clone_from(&stress);
                l.kkt_with_stress(&Iterate { u: &u, extras: &v, stress: &stress, lambda: &chi }, &mut ws)
            });
            residual::record("penalty", it, kkt.max(), self.tol, &mut history, monitor)?;
            // 3. ∇J_μ (of the elastic J_μ in the cold iteration)
            timer.time("gradient", || {
                let eps = &ws.eps;
                if elastic {
                    sig_mu.par_iter_mut().zip(eps.par_iter()).for_each(|(s, e)| *s = c_el_mu * e);
                } else {
                    let sigma = stress.sigma.par_iter();
                    sig_mu
                        .par_iter_mut()
                        .zip(sigma)
                        .zip(eps.par_iter())
                        .for_each(|((s, sg), e)| *s = sg + c_el * e * mu);
                }
                l.divergence(&sig_mu, &mut r);
                // the loads on u belong to the smooth part
                for (ri, f) in r.iter_mut().zip(l.nodal_load()) {
                    *ri -= f;
                }
                gt_chi.iter_mut().for_each(|x| *x = 0.0);
                ht_chi.iter_mut().for_each(|x| *x = 0.0);
                rows.add_transpose(&chi, &mut gt_chi, &mut ht_chi);
                for ((g, a), b) in grad_u.iter_mut().zip(&r).zip(&gt_chi) {
                    *g = a - b;
                }
                for kx in 0..ne {
                    grad_v[kx] = -l.load()[kx] - ht_chi[kx] + mu * sys.k_v[kx] * v[kx];
                }
            });
            let grad_norm = (norm(&grad_u).powi(2) + norm(&grad_v).powi(2)).sqrt();
            let grad_scale =
                norm(&r).max(norm(&gt_chi)).max(norm(l.load())).max(norm(&ht_chi)).max(norm(l.nodal_load()));
            grad_rel = if grad_scale > 0.0 { grad_norm / grad_scale } else { grad_norm };
            if !grad_rel.is_finite() {
                return Err(non_finite("the gradient of J_μ", it));
            }
            // 4. stop: J_μ minimised to round-off, or out of budget
            if finished || (!elastic && grad_rel <= GRADIENT_TOL) {
                break (stuck.then_some(StopReason::Stagnated), kkt);
            }
            if it >= self.max_iter {
                break (Some(StopReason::MaxIterations), kkt);
            }
            // 5. the Newton step of the contact model, from every row (cold) or the rows
            // penetrating now
            timer.time("assembly", || {
                if elastic || !plastic {
                    l.assemble(Material::Uniform(&c_el_mu), &mut sys.kprime);
                } else {
                    tangents.par_iter_mut().for_each(|t| *t += c_el * mu);
                    l.assemble(Material::PerPoint(&tangents), &mut sys.kprime);
                }
            });
            if !elastic {
                for (a, g) in model.iter_mut().zip(&gap) {
                    *a = *g < 0.0;
                }
            }
            let (s, settled) = timer.time("factorisation and solves", || {
                let at = Point { r: &r, gap: &gap, v: &v };
                let mut d = Direction { du: &mut du, dv: &mut dv, g_next: &mut g_next };
                sys.model_step(l, &mut model, &at, &mut d, !elastic)
            })?;
            sweeps += s;
            unsettled += !settled as usize;
            active_changes += model.iter().zip(&previous).filter(|(a, b)| a != b).count();
            previous.copy_from_slice(&model);
            if du.iter().chain(&dv).any(|x| !x.is_finite()) {
                return Err(non_finite("the Newton step", it));
            }
            // 6. the step length: full in the cold iteration, Armijo on J_μ afterwards
            let slope = dot(&grad_u, &du) + dot(&grad_v, &dv);
            let x_scale = max_abs(&u).max(max_abs(&v)).max(max_abs(&rows.offset));
            let step_rel = max_abs(&du).max(max_abs(&dv)) / x_scale.max(f64::MIN_POSITIVE);
            let mut alpha = 1.0;
            if !elastic {
                let j0 = timer.time("line search", || sys.energy(l, &u, &v, &gap, &mut ws));
                let j_scale = j0.abs().max(l.load().iter().zip(&v).map(|(f, v)| (f * v).abs()).sum());
                decrement_rel = (-slope).max(0.0) / j_scale.max(f64::MIN_POSITIVE);
                if step_rel <= STEP_TOL {
                    // the step is at the round-off of u: take it, re-evaluate, stop
                    finished = true;
                } else if slope < 0.0 && -slope > 1e-13 * j_scale {
                    let found = timer.time("line search", || {
                        for _ in 0..MAX_BACKTRACKS {
                            axpy_into(&mut u_trial, &u, alpha, &du);
                            axpy_into(&mut v_trial, &v, alpha, &dv);
                            blend(&mut gap_trial, &gap, alpha, &g_next);
                            let j = sys.energy(l, &u_trial, &v_trial, &gap_trial, &mut ws);
                            if j <= j0 + 1e-4 * alpha * slope {
                                return true;
                            }
                            // safeguarded minimiser of the parabola through J(0), J'(0), J(α)
                            let q = -slope * alpha * alpha / (2.0 * (j - j0 - slope * alpha));
                            alpha = if q.is_finite() { q.clamp(0.1 * alpha, 0.5 * alpha) } else { 0.5 * alpha };
                            backtracks += 1;
                        }
                        false
                    });
                    if !found {
                        // no measurable decrease along a descent direction: J_μ is at its
                        // round-off if the step is tiny, else the iteration is stuck
                        line_search_failures += 1;
                        alpha = 0.0;
                        finished = true;
                        stuck = step_rel > 1e-8;
                    }
                }
                // else: the predicted decrease is below the round-off of J_μ: the full step
            }
            axpy(&mut u, alpha, &du);
            axpy(&mut v, alpha, &dv);
            for (g, gn) in gap.iter_mut().zip(&g_next) {
                *g = (1.0 - alpha) * *g + alpha * gn;
            }
            it += 1;
        };
        // the report: the true residual, the penalty's error indicators
        let inner_solved = stop.is_none();
        let converged = inner_solved && kkt.max() <= self.tol;
        let stop = stop.unwrap_or(if converged { StopReason::Converged } else { StopReason::ApproximationLimit });
        let x_scale = max_abs(&u).max(max_abs(&v)).max(max_abs(&rows.offset));
        let relative = |x: f64, scale: f64| if scale > 0.0 { x / scale } else { x };
        let max_pen = gap.iter().fold(0.0f64, |m, g| m.max(-g));
        let load_def = l.load().iter().zip(&ht_chi).map(|(f, h)| (f + h).powi(2)).sum::<f64>().sqrt();
        rows.gap(&u, &v, &mut ws.gap);
        let drift = gap.iter().zip(&ws.gap).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let mut counters = BTreeMap::new();
        let mut put = |k: &str, x: f64| counters.insert(k.to_string(), x);
        put("mu", mu);
        put("max_penetration", max_pen);
        put("max_penetration_relative", relative(max_pen, x_scale));
        put("load_defect", load_def);
        put("load_defect_relative", relative(load_def, norm(l.load())));
        put("condition_estimate", sys.condition_estimate);
        put("penalty_stiffness_max", sys.k.iter().copied().fold(0.0, f64::max));
        put("gap_drift_relative", relative(drift, x_scale));
        put("factorisations", sys.factorisations as f64);
        put("symbolic_analyses", 1.0);
        put("triangular_solve_pairs", sys.solves as f64);
        put("contact_model_sweeps", sweeps as f64);
        put("contact_model_unsettled", unsettled as f64);
        put("line_search_backtracks", backtracks as f64);
        put("line_search_failures", line_search_failures as f64);
        put("active_set_changes", active_changes as f64);
        put("contact_rows_active", chi.iter().filter(|c| **c > 0.0).count() as f64);
        put("return_mappings", return_mappings as f64);
        put("inner_converged", inner_solved as u8 as f64);
        put("inner_gradient_relative", grad_rel);
        put("newton_decrement_relative", decrement_rel);
        put("approximation_limit", (stop == StopReason::ApproximationLimit) as u8 as f64);
        let report = SolveReport {
            solver: "penalty".into(),
            converged,
            stop_reason: stop,
            iterations: it,
            tolerance: self.tol,
            kkt,
            residual_history: history,
            phases: timer.into_phases(),
            counters,
            warnings: Vec::new(),
        };
        Ok(Solution { u, extras: v, stress, lambda: chi, report })
    }
}

fn non_finite(what: &str, iteration: usize) -> SolveError {
    SolveError::NonFinite { solver: "penalty".into(), what: what.into(), iteration }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// out = x + α d.
fn axpy_into(out: &mut [f64], x: &[f64], alpha: f64, d: &[f64]) {
    for ((o, a), b) in out.iter_mut().zip(x).zip(d) {
        *o = a + alpha * b;
    }
}

/// out = (1 − α) x + α y: the gaps along a step, exact at both ends.
fn blend(out: &mut [f64], x: &[f64], alpha: f64, y: &[f64]) {
    for ((o, a), b) in out.iter_mut().zip(x).zip(y) {
        *o = (1.0 - alpha) * a + alpha * b;
    }
}

/// x += α d.
fn axpy(x: &mut [f64], alpha: f64, d: &[f64]) {
    for (a, b) in x.iter_mut().zip(d) {
        *a += alpha * b;
    }
}
