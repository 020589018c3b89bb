//! Step 2 of Uzawa (theory §4.1) on a distributed problem (theory §12.4): the projection of
//! z = uⁿ − ρM⁻¹(Bᵀσ̂ − f_u) onto K_h in the metric M, with V eliminated exactly (m = 0), is
//! the quadratic programme
//!
//! `min (1/2ρ)(u − z)ᵀM(u − z) − f·V` over g(u, V) ≥ 0,
//!
//! an elastic contact problem with the stiffness M/ρ. It is solved by the primal–dual active
//! set of Newton on the distributed operators ([`DistributedSystem`], theory §4.2, §12.2): its
//! gradient `(1/ρ)M(u − uⁿ) + Bᵀσ̂ − f_u` needs no z (no solve), each sweep solves the
//! equality-constrained problem of its active set exactly, and the sweeps stop when the active
//! set {λ_i − c_i g_i > 0} no longer changes on any rank — the KKT conditions of the programme.
//! Its multipliers are the contact forces λⁿ⁺¹ themselves (the serial projection's μ/ρ). The
//! first sweep starts from the previous iteration's λ and active set, so that once the contact
//! zone has settled one sweep is one solve per column (1 + n_extras).

use crate::active_set::{CG_TOL_MIN, primal_dual_update, touch_loaded_extras};
use crate::distributed_system::DistributedSystem;
use crate::vector::axpy;
use saddle_core::problem::lagrangian::Lagrangian;
use saddle_core::problem::operators::Material;
use saddle_core::problem::solver::SolveError;
use saddle_core::{Sym, SymOp};

/// Sweeps of the active set per projection before it is refused: the contact zone of one
/// Uzawa step moves by a few rows, the punch from a cold start settles in 2–4 sweeps (Newton's
/// elastic phase, [`crate::newton::ELASTIC_PHASE_MAX_STEPS`]); 50 without settling means the
/// active set cycles.
pub const MAX_SWEEPS: usize = 50;

/// The projection onto K_h in the metric M on a distributed problem (module docs).
pub struct DistributedProjection {
    system: DistributedSystem,
    /// M/ρ.
    metric: SymOp,
    /// M/ρ's values on this rank's pattern.
    k: Vec<f64>,
    /// c_i of the active-set test: (M/ρ) in row i's coordinate.
    row_stiffness: Vec<f64>,
    /// The active set of the last sweep.
    active: Vec<bool>,
    /// u − uⁿ, ε(u − uⁿ), (M/ρ)ε(u − uⁿ), the gradient, the gaps.
    du: Vec<f64>,
    eps: Vec<Sym>,
    sigma: Vec<Sym>,
    grad: Vec<f64>,
    gap: Vec<f64>,
    /// Active-set sweeps so far.
    pub sweeps: usize,
    /// The solver that asked for the projection (errors name it).
    solver: String,
}

impl DistributedProjection {
    /// The projection for `l` in the metric `metric` with step `rho`, for `solver` (errors name
    /// it). Collective.
    pub fn new(l: &Lagrangian<'_>, metric: &SymOp, rho: f64, solver: &str) -> Result<Self, SolveError> {
        let mut system = DistributedSystem::new(l, solver)?;
        system.constant_tangent = true;
        let metric = metric * (1.0 / rho);
        let k = l.stiffness(Material::Uniform(&metric));
        let row_stiffness = system.row_stiffness(l, &k)?;
        let (n, np, nr) = (l.n_dofs(), l.n_points(), l.data.rows.n_rows());
        Ok(Self {
            system,
            metric,
            k,
            row_stiffness,
            active: vec![false; nr],
            du: vec![0.0; n],
            eps: vec![Sym::zeros(); np],
            sigma: vec![Sym::zeros(); np],
            grad: vec![0.0; n],
            gap: vec![0.0; nr],
            sweeps: 0,
            solver: solver.into(),
        })
    }

    /// The linear system's counts: assemblies, Krylov solves, Krylov iterations, unconverged
    /// solves.
    pub fn counts(&self) -> [usize; 4] {
        let s = &self.system;
        [s.assemblies, s.solves, s.iterations, s.unconverged]
    }

    /// (u, V) ← the projection of uⁿ − ρM⁻¹`force` onto K_h (`force` = Bᵀσ̂ − f_u) from
    /// `u` = uⁿ, `v` = Vⁿ, and `lambda` ← its multipliers, λ on entry the first sweep's guess.
    /// Collective.
    pub fn project(
        &mut self,
        l: &Lagrangian<'_>,
        force: &[f64],
        u: &mut [f64],
        v: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), SolveError> {
        let rows = l.data.rows;
        self.du.iter_mut().for_each(|x| *x = 0.0);
        for sweep in 0..=MAX_SWEEPS {
            rows.gap(u, v, &mut self.gap);
            let mut changed = primal_dual_update(lambda, &self.row_stiffness, &self.gap, &mut self.active);
            changed += touch_loaded_extras(l, &mut self.active, &self.gap);
            if sweep > 0 && l.comm().sum_count(changed) == 0 {
                return Ok(());
            }
            if sweep == MAX_SWEEPS {
                break;
            }
            self.gradient(l, force);
            let metric = Material::Uniform(&self.metric);
            let step = self.system.step(l, metric, &self.k, &self.active, &self.grad, &self.gap, CG_TOL_MIN)?;
            axpy(&mut self.du, 1.0, &step.du);
            axpy(u, 1.0, &step.du);
            axpy(v, 1.0, &step.dv);
            lambda.copy_from_slice(&step.lambda);
            self.sweeps += 1;
        }
        Err(SolveError::Unsupported {
            solver: self.solver.clone(),
            message: format!("the active set of the projection onto K_h did not settle in {MAX_SWEEPS} sweeps"),
        })
    }

    /// The programme's gradient at u = uⁿ + du: (M/ρ) du + `force`, through the operators.
    fn gradient(&mut self, l: &Lagrangian<'_>, force: &[f64]) {
        l.strain(&self.du, &mut self.eps);
        for (s, e) in self.sigma.iter_mut().zip(&self.eps) {
            *s = self.metric * e;
        }
        l.divergence(&self.sigma, &mut self.grad);
        axpy(&mut self.grad, 1.0, force);
    }
}
