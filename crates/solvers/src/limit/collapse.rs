//! Stage 4 of a limit analysis (theory §13.4): what the conic solve says about the collapse —
//! both bounds and their gap, the collapse stresses and contact forces, the mechanism and its
//! dissipation.

use super::ReferenceLoads;
use super::programme::{IpmResult, StaticProgramme};
use saddle_core::{DiscreteProblem, ObstacleReport, Sym};

/// The collapse of a discrete problem (theory §13).
#[derive(Clone, Debug)]
pub struct Collapse {
    /// λ⁺, the kinematic value: the dissipation of the mechanism at unit external power (the
    /// dual objective). The collapse load is this times the scene's loads.
    pub multiplier: f64,
    /// λ⁻, the static value: the largest multiplier carried by the stresses found (the primal
    /// objective).
    pub dual_multiplier: f64,
    /// λ⁺ − λ⁻.
    pub gap: f64,
    /// The mechanism: velocities of the free dofs, normalised to unit external power ℓ(v) = 1.
    pub velocity: Vec<f64>,
    /// The velocities of the obstacles' extras.
    pub extras_velocity: Vec<f64>,
    /// The collapse stresses per point, in equilibrium with λ⁻ times the loads.
    pub stress: Vec<Sym>,
    /// The contact forces at collapse per row of K_h (0 on rows open in the reference
    /// configuration).
    pub lambda: Vec<f64>,
    /// The dissipation density per point, π(ε(v)) (its weighted sum is λ⁺).
    pub dissipation: Vec<f64>,
    /// Each obstacle's report at collapse (its `force` is its collapse force; its extras are
    /// velocities).
    pub obstacles: Vec<ObstacleReport>,
    /// Clarabel's status and iterations.
    pub status: String,
    /// Interior-point iterations.
    pub iterations: usize,
    /// Clarabel's relative primal and dual residuals.
    pub residuals: [f64; 2],
    /// Free dofs, variables and second-order cones of the programme, and closed rows.
    pub dofs: usize,
    /// Variables of the programme.
    pub variables: usize,
    /// Its stress unknowns: coordinates per point and merged per element (theory §13.3).
    pub stress_unknowns: usize,
    /// Second-order cones.
    pub cones: usize,
    /// Rows of K_h closed in the reference configuration (constraining the mechanism).
    pub closed_rows: usize,
    /// Wall time per stage, s.
    pub phases: Vec<(String, f64)>,
    /// Total wall time, s.
    pub wall_s: f64,
    /// Things the user should know: hardening ignored, a locking element, open rows.
    pub warnings: Vec<String>,
}

impl Collapse {
    /// Stage 4 (theory §13.4): the bounds from Clarabel's objectives — λ⁻ = μ from x, λ⁺ =
    /// bᵀz (the dissipation of the dual's mechanism) — back in the units of `problem`; σ and λ
    /// from x; v, V from z; the dissipation density per point from its cone duals.
    pub fn recover(problem: &DiscreteProblem, loads: &ReferenceLoads, prog: &StaticProgramme, ipm: &IpmResult) -> Self {
        let lay = prog.layout;
        let [s, l, f] = prog.scales;
        let power = s * l * l / f;
        let (x, z, b) = (&ipm.x, &ipm.z, prog.b());
        let dual_multiplier = x[lay.mu_col()] * power;
        let w = problem.element.weights();
        let dissipation: Vec<f64> = (0..lay.n_points)
            .map(|t| {
                let r = lay.cone_row0() + t * lay.cone_rows..lay.cone_row0() + (t + 1) * lay.cone_rows;
                let d: f64 = b[r.clone()].iter().zip(&z[r]).map(|(b, z)| b * z).sum();
                d * power / w[t]
            })
            .collect();
        let multiplier: f64 = dissipation.iter().zip(w).map(|(d, w)| d * w).sum();
        let velocity: Vec<f64> = z[..lay.n_dofs].iter().map(|z| -z / f).collect();
        let n_extras = loads.extras.len();
        let extras_velocity: Vec<f64> = z[lay.n_dofs..lay.n_dofs + n_extras].iter().map(|z| -z / f).collect();
        let stress: Vec<Sym> = (0..lay.n_points)
            .map(|t| {
                let sigma = prog.stress(x, t);
                Sym::from_fn(|c, _| s * sigma[c])
            })
            .collect();
        let mut lambda = vec![0.0; problem.obstacles.rows().n_rows()];
        for (k, &i) in loads.closed.iter().enumerate() {
            lambda[i] = s * l * l * x[lay.lambda_col(k)];
        }
        let obstacles = problem.obstacles.reports(problem.element.mesh(), &extras_velocity, &lambda);
        let mut warnings = loads.warnings.clone();
        warnings.extend(prog.warnings.iter().cloned());
        if problem.element.locks() {
            warnings.push(format!(
                "discretisation: type = {:?} locks where plastic flow is isochoric (theory §10): its collapse \
                 multiplier is too high; use type = \"p2\"",
                problem.element.name()
            ));
        }
        Self {
            multiplier,
            dual_multiplier,
            gap: multiplier - dual_multiplier,
            velocity,
            extras_velocity,
            stress,
            lambda,
            dissipation,
            obstacles,
            status: format!("{:?}", ipm.status),
            iterations: ipm.iterations,
            residuals: [ipm.r_prim, ipm.r_dual],
            dofs: lay.n_dofs,
            variables: prog.n_variables(),
            stress_unknowns: prog.n_stress_unknowns(),
            cones: prog.n_cones(),
            closed_rows: lay.n_closed,
            phases: Vec::new(),
            wall_s: 0.0,
            warnings,
        }
    }

    /// The relative gap (λ⁺ − λ⁻)/λ⁺.
    pub fn relative_gap(&self) -> f64 {
        self.gap / self.multiplier.abs()
    }
}
