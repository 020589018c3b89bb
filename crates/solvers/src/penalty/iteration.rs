//! Newton on J_μ (theory §4.3) in named stages, one method of the private `Run` each (module
//! docs): local law, residual, gradient, convergence, assembly, model step, line search,
//! update; then the honest report.

use super::system::{Direction, PenaltySystem, Point};
use super::{
    COLLAPSE_SHARE, COLLAPSE_SHARE_PER_MU, MAX_BACKTRACKS, Penalty, SHRINK_MAX, SHRINK_MIN, STUCK_STEP, non_finite,
};
use crate::armijo::{ARMIJO, SLOPE_ROUND_OFF};
use crate::residual::History;
use crate::vector::{axpy, axpy_into, blend, dot};
use rayon::prelude::*;
use saddle_core::problem::fields::StressField;
use saddle_core::problem::kkt::{KktResiduals, kkt_with_stress, max_abs, norm};
use saddle_core::problem::lagrangian::{Iterate, Lagrangian, Workspace};
use saddle_core::problem::operators::Material;
use saddle_core::problem::solver::{Monitor, PhaseTimer, Solution, SolveError, Start, StopReason};
use saddle_core::{Sym, SymOp};
use std::collections::BTreeMap;

impl Penalty {
    /// Newton on J_μ (module docs, theory §4.3) from `start` (cold if `None`): the Newton
    /// system set up, the stages, then the honest report.
    pub(super) fn newton(
        &self,
        l: &Lagrangian<'_>,
        start: Option<&Start>,
        monitor: &mut dyn Monitor,
    ) -> Result<Solution, SolveError> {
        let mut timer = PhaseTimer::default();
        monitor.phase("set-up");
        let sys = timer.time("set-up", || PenaltySystem::new(l, self.mu, self.update_share))?;
        let mut run = Run::new(self, l, sys);
        if let Some(start) = start {
            run.warm_start(start);
        }
        monitor.phase("iterations");
        let (end, kkt) = loop {
            run.local_law(&mut timer);
            let kkt = run.residual(&mut timer);
            run.history.record(run.state.it, kkt.max(), monitor)?;
            run.gradient(&mut timer)?;
            run.beyond_collapse()?;
            if let Some(end) = run.stop() {
                break (end, kkt);
            }
            run.assemble(&mut timer);
            run.model_step(&mut timer)?;
            let alpha = run.step_length(&mut timer);
            run.advance(alpha);
        };
        Ok(run.finish(end, kkt, timer))
    }
}

/// Why Newton on J_μ ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum End {
    /// J_μ minimised to round-off: the inner problem is solved.
    Minimised,
    /// No measurable decrease along a step that is not small: the iteration is stuck.
    Stuck,
    /// Out of iterations.
    Budget,
}

/// The iteration state of Newton on J_μ (theory §4.3): the iterate, its carried gaps and
/// pressures, the model's active set, and where the iteration stands.
struct State {
    /// u.
    u: Vec<f64>,
    /// V.
    v: Vec<f64>,
    /// The carried gaps g (module docs), g(0, 0) = c at the start.
    gap: Vec<f64>,
    /// χ = k g⁻, the penalty contact pressures.
    chi: Vec<f64>,
    /// σ̂ = P_D(Cε(u), 0), from the last local law.
    stress: StressField,
    /// The contact model's active set, and the previous iteration's.
    model: Vec<bool>,
    previous: Vec<bool>,
    /// Iterations done.
    it: usize,
    /// The last step was at round-off, or the line search failed: evaluate once more, stop.
    finished: bool,
    /// ... and the line search failed on a step that is not small.
    stuck: bool,
    /// ‖∇J_μ‖ relative to the size of its terms, at the iterate.
    grad_rel: f64,
    /// The Newton decrement −∇J_μ·d relative to |J_μ|, of the last line search.
    decrement_rel: f64,
    /// The share of the loads' work taken by the regularisation (theory §4.6).
    regularisation_share: f64,
}

/// What a penalty run counts for its report.
#[derive(Default)]
struct Counts {
    /// Shrinkings of the line search.
    backtracks: usize,
    /// Rows that entered or left the model's active set.
    active_changes: usize,
    /// Points at which P's return mapping ran, as the local law reports them.
    return_mappings: usize,
    /// Active-set sweeps of the contact model.
    sweeps: usize,
    /// Newton steps whose model did not settle.
    unsettled: usize,
    /// Line searches that found no decrease.
    line_search_failures: usize,
}

/// Scratch of the stages, allocated once per solve.
struct Scratch {
    ws: Workspace,
    /// Consistent tangents per point (plus μC after assembly).
    tangents: Vec<SymOp>,
    /// σ + μCε.
    sig_mu: Vec<Sym>,
    /// Bᵀ(σ + μCε) − f_u: the gradient of the smooth part.
    r: Vec<f64>,
    /// ∇J_μ.
    grad_u: Vec<f64>,
    grad_v: Vec<f64>,
    /// Gᵀχ and Hᵀχ.
    gt_chi: Vec<f64>,
    ht_chi: Vec<f64>,
    /// The Newton step and the gaps after it.
    du: Vec<f64>,
    dv: Vec<f64>,
    g_next: Vec<f64>,
    /// The line search's trial point and its gaps.
    u_trial: Vec<f64>,
    v_trial: Vec<f64>,
    gap_trial: Vec<f64>,
}

/// One penalty solve: what it reads, its Newton system, state, counters and scratch.
struct Run<'a> {
    settings: &'a Penalty,
    l: &'a Lagrangian<'a>,
    sys: PenaltySystem,
    /// P bounds the stresses (else no tangents are needed).
    plastic: bool,
    /// (1 + μ)C: the elastic tangent of J_μ.
    c_el_mu: SymOp,
    /// Started from a previous solution (no elastic iteration).
    warm: bool,
    state: State,
    count: Counts,
    work: Scratch,
    /// The true problem's KKT residual of every iterate.
    history: History,
}

impl State {
    /// The cold start (theory §4.3): u = 0, V = 0, the carried gaps g(0, 0) = c, every row in
    /// the contact model.
    fn cold(l: &Lagrangian<'_>) -> Self {
        let rows = l.data.rows;
        let nr = rows.n_rows();
        Self {
            u: vec![0.0; l.n_dofs()],
            v: vec![0.0; l.n_extras()],
            gap: rows.offset.clone(),
            chi: vec![0.0; nr],
            stress: StressField::new(l.n_points(), l.data.hardening_dim()),
            model: vec![true; nr],
            previous: vec![true; nr],
            it: 0,
            finished: false,
            stuck: false,
            grad_rel: f64::NAN,
            decrement_rel: f64::NAN,
            regularisation_share: 0.0,
        }
    }
}

impl Scratch {
    /// The scratch of the stages for `l`.
    fn new(l: &Lagrangian<'_>) -> Self {
        let (n, ne, nr, np) = (l.n_dofs(), l.n_extras(), l.data.rows.n_rows(), l.n_points());
        Self {
            ws: Workspace::new(l),
            tangents: vec![SymOp::zeros(); np],
            sig_mu: vec![Sym::zeros(); np],
            r: vec![0.0; n],
            grad_u: vec![0.0; n],
            grad_v: vec![0.0; ne],
            gt_chi: vec![0.0; n],
            ht_chi: vec![0.0; ne],
            du: vec![0.0; n],
            dv: vec![0.0; ne],
            g_next: vec![0.0; nr],
            u_trial: vec![0.0; n],
            v_trial: vec![0.0; ne],
            gap_trial: vec![0.0; nr],
        }
    }
}

impl<'a> Run<'a> {
    /// A run from the cold start ([`State::cold`]) with the Newton system `sys`.
    fn new(settings: &'a Penalty, l: &'a Lagrangian<'a>, sys: PenaltySystem) -> Self {
        Self {
            settings,
            l,
            plastic: l.data.plasticity().is_some(),
            c_el_mu: sys.c_el * (1.0 + settings.mu),
            warm: false,
            sys,
            state: State::cold(l),
            count: Counts::default(),
            work: Scratch::new(l),
            history: History::new("penalty", settings.tol),
        }
    }

    /// The cold iteration is elastic: its model is exact, its step full (module docs). A warm
    /// start has none.
    fn elastic(&self) -> bool {
        self.state.it == 0 && !self.warm
    }

    /// Starts from the previous step's (u, V) (theory §11.2): the gaps recomputed there, the
    /// model's rows those that penetrate.
    fn warm_start(&mut self, start: &Start) {
        let rows = self.l.data.rows;
        let s = &mut self.state;
        s.u.copy_from_slice(&start.u);
        s.v.copy_from_slice(&start.extras);
        rows.gap(&s.u, &s.v, &mut s.gap);
        for ((a, g), t) in s.model.iter_mut().zip(&s.gap).zip(&self.sys.friction.tangential) {
            *a = *g < 0.0 && !t;
        }
        s.previous.copy_from_slice(&s.model);
        self.warm = true;
    }

    /// Stage 1 (theory §4.3; the local law of theory §2): the pressures χ = k g⁻, the stresses
    /// σ(u) and, when Newton needs them, the consistent tangents.
    fn local_law(&mut self, timer: &mut PhaseTimer) {
        let want_tangents = !self.elastic() && !self.state.finished && self.plastic;
        let (l, s, w) = (self.l, &mut self.state, &mut self.work);
        self.sys.pressures(&s.gap, &mut s.chi);
        let law = timer.time("local law", || {
            l.strain(&s.u, &mut w.ws.eps);
            l.data.local_law(&w.ws.eps, &mut s.stress, if want_tangents { Some(&mut w.tangents) } else { None })
        });
        self.count.return_mappings += law.projected;
    }

    /// Stage 2 (theory §4.3, honesty; theory §3.4): the KKT residuals of the *true* problem
    /// on (u, V, σ(u), χ).
    fn residual(&mut self, timer: &mut PhaseTimer) -> KktResiduals {
        let (l, s, w) = (self.l, &self.state, &mut self.work);
        timer.time("residual", || {
            w.ws.stress.clone_from(&s.stress);
            kkt_with_stress(l, &Iterate { u: &s.u, extras: &s.v, stress: &s.stress, lambda: &s.chi }, &mut w.ws)
        })
    }

    /// Stage 3 (theory §4.3): ∇J_μ — of the elastic J_μ in the cold iteration — and its size
    /// relative to its terms.
    fn gradient(&mut self, timer: &mut PhaseTimer) -> Result<(), SolveError> {
        let elastic = self.elastic();
        let (l, sys, s, w) = (self.l, &self.sys, &mut self.state, &mut self.work);
        let (mu, c_el) = (self.settings.mu, sys.c_el);
        let rows = l.data.rows;
        timer.time("gradient", || {
            let eps = &w.ws.eps;
            if elastic {
                // C(ε − ε_p) + μCε: the elastic response from the step's state (theory §11.1)
                l.data.elastic_stress(eps, &mut w.sig_mu);
                w.sig_mu.par_iter_mut().zip(eps.par_iter()).for_each(|(s, e)| *s += c_el * e * mu);
            } else {
                let sigma = s.stress.sigma.par_iter();
                w.sig_mu.par_iter_mut().zip(sigma).zip(eps.par_iter()).for_each(|((s, sg), e)| *s = sg + c_el * e * mu);
            }
            l.divergence(&w.sig_mu, &mut w.r);
            // the loads on u belong to the smooth part
            for (ri, f) in w.r.iter_mut().zip(l.data.nodal_load) {
                *ri -= f;
            }
            w.gt_chi.iter_mut().for_each(|x| *x = 0.0);
            w.ht_chi.iter_mut().for_each(|x| *x = 0.0);
            rows.add_transpose(&s.chi, &mut w.gt_chi, &mut w.ht_chi);
            // Hᵀχ of every rank's rows (theory §12.4)
            l.comm().sum_in_place(&mut w.ht_chi);
            for ((g, a), b) in w.grad_u.iter_mut().zip(&w.r).zip(&w.gt_chi) {
                *g = a - b;
            }
            for kx in 0..l.n_extras() {
                w.grad_v[kx] = -l.data.load[kx] - w.ht_chi[kx] + mu * sys.k_v[kx] * s.v[kx];
            }
        });
        // norms of vectors over the dofs, over every rank's (on one process the norm itself)
        let comm = l.comm();
        let owned = |x: &[f64]| if comm.size() == 1 { norm(x) } else { comm.sum(norm(x).powi(2)).sqrt() };
        let grad_norm = (owned(&w.grad_u).powi(2) + norm(&w.grad_v).powi(2)).sqrt();
        let grad_scale =
            owned(&w.r).max(owned(&w.gt_chi)).max(norm(l.data.load)).max(norm(&w.ht_chi)).max(owned(l.data.nodal_load));
        s.grad_rel = if grad_scale > 0.0 { grad_norm / grad_scale } else { grad_norm };
        if !s.grad_rel.is_finite() {
            return Err(non_finite("the gradient of J_μ", s.it));
        }
        Ok(())
    }

    /// Stage 3b (theory §4.6): the regularisation, meant to carry O(μ) of the load, takes
    /// [`COLLAPSE_SHARE`] or more of the loads' work (and [`COLLAPSE_SHARE_PER_MU`] times μ) on
    /// a plastic body under prescribed forces:
    /// no admissible stress carries the load, [`SolveError::BeyondCollapse`].
    fn beyond_collapse(&mut self) -> Result<(), SolveError> {
        let (l, s) = (self.l, &mut self.state);
        s.regularisation_share = self.sys.regularisation_share(l, &s.u, &s.v, &self.work.ws.eps);
        let threshold = COLLAPSE_SHARE.max(COLLAPSE_SHARE_PER_MU * self.settings.mu);
        // a plastic body forms a mechanism; friction lets an obstacle slide (theory §8.3)
        let can_escape = self.plastic || l.data.rows.has_friction();
        if !(can_escape && s.regularisation_share >= threshold && l.forced()) {
            return Ok(());
        }
        Err(SolveError::BeyondCollapse {
            solver: "penalty".into(),
            evidence: format!(
                "at iteration {} the regularisation (μ = {:e}), which carries O(μ) of any load the body can carry, \
                 takes {:.3} of the loads' work: the displacement runs away along a collapse mechanism",
                s.it, self.settings.mu, s.regularisation_share
            ),
        })
    }

    /// Stage 4 (theory §4.3, §4.5): J_μ minimised to round-off (relative gradient at most
    /// `gradient_tol`, or the last step at round-off), or out of budget; `None`: go on.
    fn stop(&self) -> Option<End> {
        let s = &self.state;
        if s.finished || (!self.elastic() && s.grad_rel <= self.settings.gradient_tol) {
            Some(if s.stuck { End::Stuck } else { End::Minimised })
        } else if s.it >= self.settings.max_iter {
            Some(End::Budget)
        } else {
            None
        }
    }

    /// Stage 5 (theory §4.3): K' = K_t + μK_el on L's pattern — (1 + μ)K_el in the cold
    /// iteration or without plasticity.
    fn assemble(&mut self, timer: &mut PhaseTimer) {
        let elastic_tangent = self.elastic_tangent();
        let (l, sys, w) = (self.l, &mut self.sys, &mut self.work);
        let (c_el, mu) = (sys.c_el, self.settings.mu);
        if elastic_tangent {
            timer.time("assembly", || l.assemble(Material::Uniform(&self.c_el_mu), &mut sys.kprime));
        } else {
            timer.time("assembly", || {
                w.tangents.par_iter_mut().for_each(|t| *t += c_el * mu);
                l.assemble(Material::PerPoint(&w.tangents), &mut sys.kprime);
            });
        }
    }

    /// K' is the elastic (1 + μ)K_el: in the cold iteration or without plasticity.
    fn elastic_tangent(&self) -> bool {
        self.elastic() || !self.plastic
    }

    /// Stage 6 (theory §4.3): the Newton step of the contact model, its active-set loop started
    /// from every row (cold) or from the rows penetrating now, and the gaps ĝ after it.
    fn model_step(&mut self, timer: &mut PhaseTimer) -> Result<(), SolveError> {
        let elastic = self.elastic();
        let elastic_tangent = self.elastic_tangent();
        let (l, sys, s, w) = (self.l, &mut self.sys, &mut self.state, &mut self.work);
        // K' as the operators apply it (the distributed products; theory §12.4)
        let material = if elastic_tangent { Material::Uniform(&self.c_el_mu) } else { Material::PerPoint(&w.tangents) };
        if !elastic {
            // the normal rows that penetrate; the friction pairs by their Hessians (not bonded)
            for ((a, g), t) in s.model.iter_mut().zip(&s.gap).zip(&sys.friction.tangential) {
                *a = *g < 0.0 && !t;
            }
        }
        let (sweeps, settled) = timer.time("factorisation and solves", || {
            let at = Point { r: &w.r, gap: &s.gap, chi: &s.chi, v: &s.v };
            let mut d = Direction { du: &mut w.du, dv: &mut w.dv, g_next: &mut w.g_next };
            sys.model_step(l, material, &mut s.model, &at, &mut d, !elastic)
        })?;
        self.count.sweeps += sweeps;
        self.count.unsettled += !settled as usize;
        self.count.active_changes += s.model.iter().zip(&s.previous).filter(|(a, b)| a != b).count();
        s.previous.copy_from_slice(&s.model);
        if l.comm().any(w.du.iter().chain(&w.dv).any(|x| !x.is_finite())) {
            return Err(non_finite("the Newton step", s.it));
        }
        Ok(())
    }

    /// Stage 7 (theory §4.3): the step length α — full in the cold iteration; afterwards an
    /// Armijo line search on J_μ ([`Run::backtrack`]), the full step when the predicted
    /// decrease is below the round-off of J_μ, and the end of the iteration when the step is at
    /// the round-off of u or no decrease is found.
    fn step_length(&mut self, timer: &mut PhaseTimer) -> f64 {
        if self.elastic() {
            return 1.0;
        }
        let (l, sys, s, w) = (self.l, &self.sys, &mut self.state, &mut self.work);
        let comm = l.comm();
        let slope = comm.sum(dot(&w.grad_u, &w.du)) + dot(&w.grad_v, &w.dv);
        let x_scale = comm.max(max_abs(&s.u).max(max_abs(&l.data.rows.offset))).max(max_abs(&s.v));
        let step_rel = comm.max(max_abs(&w.du)).max(max_abs(&w.dv)) / x_scale.max(f64::MIN_POSITIVE);
        let j0 = timer.time("line search", || sys.energy(l, &s.u, &s.v, &s.gap, &mut w.ws));
        let j_scale = j0.abs().max(l.data.load.iter().zip(&s.v).map(|(f, v)| (f * v).abs()).sum());
        s.decrement_rel = (-slope).max(0.0) / j_scale.max(f64::MIN_POSITIVE);
        if step_rel <= self.settings.step_tol {
            // the step is at the round-off of u: take it, re-evaluate, stop
            s.finished = true;
            return 1.0;
        }
        if !(slope < 0.0 && -slope > SLOPE_ROUND_OFF * j_scale) {
            // the predicted decrease is below the round-off of J_μ: the full step
            return 1.0;
        }
        self.backtrack(j0, slope, timer).unwrap_or_else(|| {
            // no measurable decrease along a descent direction: J_μ is at its round-off if the
            // step is tiny, else the iteration is stuck
            self.count.line_search_failures += 1;
            self.state.finished = true;
            self.state.stuck = step_rel > STUCK_STEP;
            0.0
        })
    }

    /// The line search of stage 7 (theory §4.3) from J_μ = `j0` with slope `slope`: the first
    /// α from 1 with Armijo's decrease, shrunk by safeguarded quadratic interpolation (the
    /// gaps along the step g(α) = (1 − α)g + αĝ); `None` after [`MAX_BACKTRACKS`] shrinkings.
    fn backtrack(&mut self, j0: f64, slope: f64, timer: &mut PhaseTimer) -> Option<f64> {
        let (l, sys, s, w) = (self.l, &self.sys, &self.state, &mut self.work);
        let backtracks = &mut self.count.backtracks;
        timer.time("line search", || {
            let mut alpha = 1.0;
            for _ in 0..MAX_BACKTRACKS {
                axpy_into(&mut w.u_trial, &s.u, alpha, &w.du);
                axpy_into(&mut w.v_trial, &s.v, alpha, &w.dv);
                blend(&mut w.gap_trial, &s.gap, alpha, &w.g_next);
                let j = sys.energy(l, &w.u_trial, &w.v_trial, &w.gap_trial, &mut w.ws);
                if j <= j0 + ARMIJO * alpha * slope {
                    return Some(alpha);
                }
                // safeguarded minimiser of the parabola through J(0), J'(0), J(α)
                let q = -slope * alpha * alpha / (2.0 * (j - j0 - slope * alpha));
                alpha =
                    if q.is_finite() { q.clamp(SHRINK_MIN * alpha, SHRINK_MAX * alpha) } else { SHRINK_MAX * alpha };
                *backtracks += 1;
            }
            None
        })
    }

    /// (u, V) += α (du, dV) and the carried gaps along the step, g ← (1 − α)g + αĝ.
    fn advance(&mut self, alpha: f64) {
        let (s, w) = (&mut self.state, &self.work);
        axpy(&mut s.u, alpha, &w.du);
        axpy(&mut s.v, alpha, &w.dv);
        for (g, gn) in s.gap.iter_mut().zip(&w.g_next) {
            *g = (1.0 - alpha) * *g + alpha * gn;
        }
        s.it += 1;
    }

    /// The solution and its honest report (module docs): the true residual `kkt` decides
    /// `converged`, the counters carry the penalty's error indicators.
    fn finish(mut self, end: End, kkt: KktResiduals, timer: PhaseTimer) -> Solution {
        let inner_solved = end == End::Minimised;
        let converged = inner_solved && kkt.max() <= self.settings.tol;
        let stop = match end {
            End::Minimised if converged => StopReason::Converged,
            End::Minimised => StopReason::ApproximationLimit,
            End::Stuck => StopReason::Stagnated,
            End::Budget => StopReason::MaxIterations,
        };
        let mut counters = self.error_indicators();
        let (sys, s, c) = (&self.sys, &self.state, &self.count);
        let mut put = |k: &str, x: f64| counters.insert(k.to_string(), x);
        put("factorisations", sys.factorisations as f64);
        put("symbolic_analyses", sys.symbolic_analyses as f64);
        put("triangular_solve_pairs", sys.solves as f64);
        put("entering_row_updates", sys.entering_row_updates() as f64);
        if let Some((iterations, unconverged)) = sys.krylov() {
            put("distributed_solves", sys.solves as f64);
            put("krylov_iterations", iterations as f64);
            put("krylov_unconverged", unconverged as f64);
        }
        put("contact_model_sweeps", c.sweeps as f64);
        put("contact_model_unsettled", c.unsettled as f64);
        put("line_search_backtracks", c.backtracks as f64);
        put("line_search_failures", c.line_search_failures as f64);
        // a rank's counts summed over the ranks (theory §12; on one process the count itself)
        let comm = self.l.comm();
        put("active_set_changes", comm.sum_count(c.active_changes) as f64);
        let normal_active = s.chi.iter().zip(&sys.friction.tangential).filter(|(c, t)| **c > 0.0 && !**t).count();
        put("contact_rows_active", comm.sum_count(normal_active) as f64);
        put("return_mappings", comm.sum_count(c.return_mappings) as f64);
        put("inner_converged", inner_solved as u8 as f64);
        put("inner_gradient_relative", s.grad_rel);
        put("newton_decrement_relative", s.decrement_rel);
        put("approximation_limit", (stop == StopReason::ApproximationLimit) as u8 as f64);
        put("regularisation_share", s.regularisation_share);
        let State { u, v, chi, stress, it, .. } = self.state;
        let report = self.history.report(stop, it, kkt, timer.into_phases(), counters);
        Solution { u, extras: v, stress, lambda: chi, report, undetermined: Vec::new() }
    }

    /// The penalty's own error indicators (theory §4.3, honesty): μ, the penetration max g⁻,
    /// the load defect ‖f + Hᵀχ‖ (absolute and relative), the condition estimate, the largest
    /// penalty stiffness and the drift of the carried gaps from G u + H V + c.
    fn error_indicators(&mut self) -> BTreeMap<String, f64> {
        let (l, sys, s, w) = (self.l, &self.sys, &self.state, &mut self.work);
        let rows = l.data.rows;
        // the largest values over every rank's dofs and rows (Hᵀχ is summed already)
        let comm = l.comm();
        let x_scale = comm.max(max_abs(&s.u).max(max_abs(&rows.offset))).max(max_abs(&s.v));
        let relative = |x: f64, scale: f64| if scale > 0.0 { x / scale } else { x };
        let normal = s.gap.iter().zip(&sys.friction.tangential).filter(|(_, t)| !**t);
        let max_pen = comm.max(normal.fold(0.0f64, |m, (g, _)| m.max(-g)));
        let load_def = l.data.load.iter().zip(&w.ht_chi).map(|(f, h)| (f + h).powi(2)).sum::<f64>().sqrt();
        rows.gap(&s.u, &s.v, &mut w.ws.gap);
        let drift = comm.max(s.gap.iter().zip(&w.ws.gap).fold(0.0f64, |m, (a, b)| m.max((a - b).abs())));
        let mut counters = BTreeMap::new();
        let mut put = |k: &str, x: f64| counters.insert(k.to_string(), x);
        put("mu", self.settings.mu);
        put("max_penetration", max_pen);
        put("max_penetration_relative", relative(max_pen, x_scale));
        put("load_defect", load_def);
        put("load_defect_relative", relative(load_def, norm(l.data.load)));
        put("condition_estimate", sys.condition_estimate);
        put("penalty_stiffness_max", comm.max(sys.k.iter().copied().fold(0.0, f64::max)));
        put("gap_drift_relative", relative(drift, x_scale));
        if rows.has_friction() {
            // the tangential rows' regularisation error: a sticking pair slips |λ_t|/k (theory §4.3)
            let stick_slip = sys.friction.max_stick_slip(&s.gap, &s.chi);
            put("max_stick_slip", stick_slip);
            put("max_stick_slip_relative", relative(stick_slip, x_scale));
        }
        counters
    }
}
