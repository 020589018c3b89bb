//! The paper's algorithm: Uzawa / Arrow–Hurwicz (theory §4.1), exactly as stated there.
//!
//! For n = 0, 1, …
//!  1. σ̂ⁿ⁺¹ = P_D(C ε(uⁿ), 0) element by element (the local law, theory §2);
//!  2. (uⁿ⁺¹, Vⁿ⁺¹) ∈ K_h is the projected gradient step
//!     `(uⁿ⁺¹ − uⁿ, v − uⁿ⁺¹)_M + m (Vⁿ⁺¹ − Vⁿ)(V − Vⁿ⁺¹) ≥ ρ [f·(V − Vⁿ⁺¹) − (σⁿ⁺¹, ε(v − uⁿ⁺¹))]`
//!     for all (v, V) ∈ K_h — a projection onto K_h in the metric diag(M, m), solved exactly for
//!     the contact rows ([`MetricProjection`]).
//!
//! M is the elastic energy metric (Cε(·), ε(·)) by default — better conditioned than the
//! paper's (ε(·), ε(·)), which is selectable — and is factorised once (symbolic and numeric)
//! and reused by every iteration: one triangular solve pair per iteration. ρ is given relative
//! to 1/L, L ≥ λ_max(M⁻¹K) (L = 1 in the energy metric, max(2G, 3K_b) in the strain metric), so
//! the method is stable for ρ < 2 whatever the units. The extras' weight m defaults to 0: V is
//! then eliminated exactly inside the projection (m = 1 is the paper's choice, selectable as a
//! multiple of V's natural stiffness). The iteration stops on the relative KKT residual of the
//! iterate, never on the step length; divergence and NaN are detected and reported.

use crate::kh_projection::MetricProjection;
use crate::linear::{self, InSolver};
use crate::residual;
use saddle_core::SymOp;
use saddle_core::error::{ParameterError, check};
use saddle_core::problem::fields::StressField;
use saddle_core::problem::kkt::kkt_with_stress;
use saddle_core::problem::lagrangian::{Iterate, Lagrangian, Workspace};
use saddle_core::problem::operators::Material;
use saddle_core::problem::solver::{Monitor, PhaseTimer, Solution, SolveError, SolveReport, Solver, Start, StopReason};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The metric M of step (ii).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum UzawaMetric {
    /// (Cε(u), ε(v)): the elastic energy (default).
    Energy,
    /// (ε(u), ε(v)): the paper's choice.
    Strain,
}

/// `type = "uzawa"`: the paper's Uzawa / Arrow–Hurwicz method (theory §4.1).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Uzawa {
    /// Step ρ in units of 1/L; stable for 0 < ρ < 2.
    pub rho: f64,
    /// The metric M.
    pub metric: UzawaMetric,
    /// Weight m of the extra unknowns relative to their natural stiffness; 0 eliminates them
    /// exactly.
    pub extra_metric: f64,
    /// Relative KKT tolerance.
    pub tol: f64,
    /// Iteration budget.
    pub max_iter: usize,
}

impl Default for Uzawa {
    fn default() -> Self {
        Self { rho: 1.0, metric: UzawaMetric::Energy, extra_metric: 0.0, tol: 1e-8, max_iter: 20_000 }
    }
}

/// The stable range of ρ (in units of 1/L): 0 < ρ < 2 (theory §4.1: the projected gradient
/// method converges for ρ < 2/L).
pub const RHO_BOUND: f64 = 2.0;

/// Divergence (theory §4.1): a step length in diag(M, m) this many times the smallest one seen
/// since the first step. Below the bound the step length never grows, so any growth is
/// instability; 10 leaves room for round-off once the steps are tiny, and above the bound the
/// growth |1 − ρ|ⁿ passes 10 within a few iterations.
pub const DIVERGENCE_GROWTH: f64 = 10.0;

/// Steps below this fraction of the first one are round-off: the smallest step is floored
/// there, so that tiny steps of a converging iteration are not taken for growth.
pub const STEP_ROUND_OFF: f64 = 1e-12;

/// The first iteration at which divergence is judged: the test compares the last step with the
/// smallest one after the first, so it needs steps 1 and 2.
pub const DIVERGENCE_WARM_UP: usize = 3;

/// Stagnation (theory §4.1): no new best residual for max(this, n/4) iterations. Uzawa's
/// residual is not monotone, so the window is deliberately long: it only decides when a run
/// that cannot improve (a round-off floor above `tol`) is stopped, so a long window costs time,
/// never a solution.
pub const STAGNATION_WINDOW: usize = 500;

#[typetag::serde(name = "uzawa")]
impl Solver for Uzawa {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::positive(path, "rho", self.rho)?;
        check::non_negative(path, "extra_metric", self.extra_metric)?;
        check::open_interval(path, "tol", self.tol, 0.0, 1.0)?;
        check::at_least_one(path, "max_iter", self.max_iter)?;
        Ok(())
    }

    fn tolerance(&self) -> f64 {
        self.tol
    }

    fn solve(&self, l: &Lagrangian<'_>, monitor: &mut dyn Monitor) -> Result<Solution, SolveError> {
        self.iterate(l, None, monitor)
    }

    /// The iteration from the previous step's (u, V, λ) (theory §11.2).
    fn solve_warm(&self, l: &Lagrangian<'_>, start: &Start, monitor: &mut dyn Monitor) -> Result<Solution, SolveError> {
        start.check(l, "uzawa")?;
        let mut sol = self.iterate(l, Some(start), monitor)?;
        sol.report.counters.insert("warm_start".into(), 1.0);
        Ok(sol)
    }
}

impl Uzawa {
    /// The iteration of theory §4.1 from `start` (zero if `None`).
    fn iterate(
        &self,
        l: &Lagrangian<'_>,
        start: Option<&Start>,
        monitor: &mut dyn Monitor,
    ) -> Result<Solution, SolveError> {
        let mut timer = PhaseTimer::default();
        let law = *l.data.elasticity;
        // M and its Lipschitz bound L
        let (metric, lip) = match self.metric {
            UzawaMetric::Energy => (law.stiffness_matrix(), 1.0),
            UzawaMetric::Strain => (SymOp::identity(), law.max_eigenvalue()),
        };
        let rho = self.rho / lip;
        monitor.phase("assembly");
        let m_values = timer.time("assembly", || l.stiffness(Material::Uniform(&metric)));
        monitor.phase("factorisation");
        let (mut symbolic_analyses, mut factorisations) = (0usize, 0usize);
        let mut chol = timer.time("factorisation", || -> Result<_, SolveError> {
            let mut chol = linear::analyse(l.pattern(), "Uzawa metric", "uzawa", &mut symbolic_analyses)?;
            chol.factorise(&m_values).in_solver("uzawa")?;
            factorisations += 1;
            Ok(chol)
        })?;
        drop(m_values);
        // without contact rows step (ii) is a plain gradient step: no contact structures at all
        let rows = l.data.rows;
        let mut proj = if rows.n_rows() > 0 {
            monitor.phase("contact set-up");
            Some(timer.time("contact set-up", || {
                MetricProjection::new(rows, &mut chol, self.extra_metric, rho, l.data.load, "uzawa")
            })?)
        } else {
            None
        };

        let (n, ne, nr) = (l.n_dofs(), l.n_extras(), rows.n_rows());
        let mut u = vec![0.0; n];
        let mut v = vec![0.0; ne];
        let mut mu = vec![0.0; nr];
        let mut lambda = vec![0.0; nr];
        if let Some(st) = start {
            u.copy_from_slice(&st.u);
            v.copy_from_slice(&st.extras);
            lambda.copy_from_slice(&st.lambda);
            // μ = ρλ: the multipliers of the projection step (λ = μ/ρ below)
            for (m, l) in mu.iter_mut().zip(&st.lambda) {
                *m = rho * l;
            }
        }
        let mut z = vec![0.0; n];
        let mut ws = Workspace::new(l);
        let mut stress = StressField::new(l.n_points(), l.data.hardening_dim());
        let mut history = Vec::new();
        let mut solves = 0usize;
        // Divergence: for ρ < 2 the iteration map is averaged in diag(M, m), so the step length
        // δₙ = ‖xⁿ⁺¹ − xⁿ‖ never increases; above the bound it grows like |1 − ρ|ⁿ. (The relative
        // KKT residual cannot tell: it saturates near 1 when the iterate blows up.)
        let mut best = (f64::INFINITY, 0usize);
        let mut smallest_step = f64::INFINITY;
        let mut first_step = 0.0;
        let (mut u_prev, mut v_prev) = (vec![0.0; n], vec![0.0; ne]);
        let mut scratch_v = vec![0.0; ne];
        let mut return_mappings = 0usize;
        monitor.phase("iterations");
        let mut it = 0;
        let mut last_step = 0.0;
        let (stop, kkt) = loop {
            // (i) σ̂ⁿ⁺¹ = P_D(Cε(uⁿ), 0); the KKT residual of the iterate (uⁿ, Vⁿ, σ̂ⁿ⁺¹, λⁿ)
            let law = timer.time("local law", || {
                l.strain(&u, &mut ws.eps);
                let law = l.data.local_law(&ws.eps, &mut stress, None);
                ws.stress.clone_from(&stress);
                law
            });
            return_mappings += law.projected;
            let kkt = timer.time("residual", || {
                kkt_with_stress(l, &Iterate { u: &u, extras: &v, stress: &stress, lambda: &lambda }, &mut ws)
            });
            let r = kkt.max();
            residual::record("uzawa", it, r, self.tol, &mut history, monitor)?;
            if r <= self.tol {
                break (StopReason::Converged, kkt);
            }
            if r < best.0 {
                best = (r, it);
            }
            if it >= DIVERGENCE_WARM_UP
                && smallest_step < f64::INFINITY
                && last_step > DIVERGENCE_GROWTH * smallest_step.max(STEP_ROUND_OFF * first_step)
            {
                return Err(SolveError::Diverged {
                    solver: "uzawa".into(),
                    iteration: it,
                    residual: r,
                    hint: self.divergence_hint(),
                });
            }
            if it >= self.max_iter {
                break (StopReason::MaxIterations, kkt);
            }
            if it - best.1 > STAGNATION_WINDOW.max(it / 4) {
                break (StopReason::Stagnated, kkt);
            }
            // (ii) z = uⁿ − ρ M⁻¹ Bᵀσⁿ⁺¹ (ws.force holds Bᵀσⁿ⁺¹), then project onto K_h in M
            timer.time("linear solves", || {
                for (zi, fi) in z.iter_mut().zip(&ws.force) {
                    *zi = -rho * fi;
                }
                chol.solve(&mut z);
                for (zi, ui) in z.iter_mut().zip(&u) {
                    *zi += ui;
                }
            });
            solves += 1;
            u_prev.clone_from(&u);
            v_prev.clone_from(&v);
            solves += match &mut proj {
                Some(p) => timer.time("projection", || p.project(rows, &mut chol, &z, &mut v, &mut u, &mut mu))?,
                None => {
                    u.copy_from_slice(&z);
                    0
                }
            };
            // δₙ² = Δuᵀ M Δu + Σ m ΔV², with M Δu = Gᵀμ − ρ Bᵀσ (z is free again: it takes Gᵀμ)
            z.iter_mut().for_each(|x| *x = 0.0);
            rows.add_transpose(&mu, &mut z, &mut scratch_v);
            let du_m_du: f64 = (0..n).map(|j| (u[j] - u_prev[j]) * (z[j] - rho * ws.force[j])).sum();
            let weights = proj.as_ref().map_or(&[][..], |p| p.extra_weights());
            let dv_m_dv: f64 = weights.iter().zip(v.iter().zip(&v_prev)).map(|(m, (a, b))| m * (a - b) * (a - b)).sum();
            last_step = (du_m_du + dv_m_dv).max(0.0).sqrt();
            if it == 0 {
                first_step = last_step;
            } else {
                smallest_step = smallest_step.min(last_step);
            }
            for (l, m) in lambda.iter_mut().zip(&mu) {
                *l = m / rho;
            }
            it += 1;
        };
        let mut counters = BTreeMap::new();
        counters.insert("rho".into(), self.rho);
        counters.insert("rho_bound".into(), RHO_BOUND);
        counters.insert("symbolic_analyses".into(), symbolic_analyses as f64);
        counters.insert("factorisations".into(), factorisations as f64);
        counters.insert("setup_solves".into(), proj.as_ref().map_or(0, |p| p.setup_solves) as f64);
        counters.insert("triangular_solve_pairs".into(), solves as f64);
        counters.insert("qp_factorisations".into(), proj.as_ref().map_or(0, |p| p.qp_work().1) as f64);
        counters.insert("return_mappings".into(), return_mappings as f64);
        counters.insert("contact_structures".into(), proj.is_some() as u8 as f64);
        counters.insert(
            "delassus_columns_kept".into(),
            proj.as_ref().is_some_and(|p| p.keeps_delassus_columns()) as u8 as f64,
        );
        let report = SolveReport {
            solver: "uzawa".into(),
            converged: stop == StopReason::Converged,
            stop_reason: stop,
            iterations: it,
            tolerance: self.tol,
            kkt,
            residual_history: history,
            phases: timer.into_phases(),
            counters,
            warnings: Vec::new(),
        };
        Ok(Solution { u, extras: v, stress, lambda, report, undetermined: Vec::new() })
    }
}

impl Uzawa {
    /// What to change when the iteration diverges.
    fn divergence_hint(&self) -> String {
        if self.rho >= RHO_BOUND {
            format!(
                "solver.rho = {} is at or above the stable bound {RHO_BOUND} (the step ρ/L needs ρ < 2, L ≥ λ_max(M⁻¹K)); use rho < {RHO_BOUND}",
                self.rho
            )
        } else {
            format!(
                "solver.rho = {} is below the stable bound {RHO_BOUND}: the problem data may be inconsistent",
                self.rho
            )
        }
    }
}
