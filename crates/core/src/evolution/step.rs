//! One load step (theory §11.1): the data of a discrete problem with every load multiplied by
//! a factor (tractions and body forces, each obstacle's prescribed force or displacement,
//! [`crate::AdmissibleDisplacements::scaled_load`]) and the state of the previous step, on the
//! problem's own element. It is L with other data: nothing forwards.

use crate::error::SceneError;
use crate::evolution::LoadFactors;
use crate::fem::{DiscreteProblem, ProblemView};
use crate::problem::fields::PlasticState;
use crate::problem::kkt::locked_in_force;
use crate::problem::lagrangian::{Data, Lagrangian};
use crate::problem::obstacles::DiscreteObstacles;
use crate::problem::slip::SlipHistory;

/// L at load factor `factor` from a state (theory §11.1): the base problem's element and
/// material, its obstacles at the scaled load ([`DiscreteObstacles::at_factor`]: the rows kept
/// where only the load changes), its nodal loads scaled, and the state (ε_p, q_n) that shifts the
/// local law — none for the zero state, so that the first step of a path from zero is the
/// stationary problem exactly.
#[derive(Debug)]
pub struct LoadStep<'a> {
    base: &'a DiscreteProblem,
    factor: f64,
    state: Option<PlasticState>,
    /// ‖BᵀCε_p‖, computed once.
    locked_in: f64,
    obstacles: DiscreteObstacles,
    nodal_load: Vec<f64>,
}

impl<'a> LoadStep<'a> {
    /// The step of `base` at `factor` from `state`. Errors name the obstacle whose plugin cannot
    /// scale its load or whose rows at the scaled load cannot be made. The state must have the
    /// base's points and hardening dimension.
    pub fn new(base: &'a DiscreteProblem, factor: f64, state: PlasticState) -> Result<Self, SceneError> {
        Self::at(base, &LoadFactors::uniform(factor), state)
    }

    /// [`LoadStep::new`] with named loads at factors of their own (theory §11.2): the obstacles'
    /// named loads ([`DiscreteObstacles::at_factors`]); every other load at `factors.all`.
    pub fn at(base: &'a DiscreteProblem, factors: &LoadFactors, state: PlasticState) -> Result<Self, SceneError> {
        let factor = factors.all;
        let l = base.lagrangian();
        assert_eq!(state.len(), l.n_points(), "the state has {} points, L {}", state.len(), l.n_points());
        assert_eq!(state.q.dim(), l.data.hardening_dim(), "the state's hardening dimension");
        let element = &*base.element;
        let obstacles = base.obstacles.at_factors(factors, element.mesh(), element.dofs())?;
        let nodal_load = base.nodal_load.iter().map(|f| factor * f).collect();
        // the local law of w reads the state shifted by the lifting (theory §14)
        let state = match &base.supports {
            Some(s) if s.is_lifted() => s.shifted_state(state, factor),
            _ => state,
        };
        // zero on every rank (a collective decision: the state's force is a global norm)
        let state = element.comm().any(!state.is_zero()).then_some(state);
        let locked_in = state.as_ref().map_or(0.0, |st| locked_in_force(element, &base.elasticity, st));
        Ok(Self { base, factor, state, locked_in, obstacles, nodal_load })
    }

    /// The step with its friction rows giving the slip increments against `history`, the
    /// previous step's slip (theory §11.6; the zero history: the total form).
    pub fn with_slip_history(mut self, history: SlipHistory) -> Self {
        self.obstacles = self.obstacles.with_history(history);
        self
    }

    /// The load factor.
    pub fn factor(&self) -> f64 {
        self.factor
    }

    /// The problem the step is made of.
    pub fn base(&self) -> &'a DiscreteProblem {
        self.base
    }

    /// The state the step starts from (`None`: the zero state).
    pub fn state(&self) -> Option<&PlasticState> {
        self.state.as_ref()
    }

    /// The obstacles at the step's load.
    pub fn obstacles(&self) -> &DiscreteObstacles {
        &self.obstacles
    }

    /// L of the step.
    pub fn lagrangian(&self) -> Lagrangian<'_> {
        let data = Data {
            elasticity: &self.base.elasticity,
            stresses: self.base.stresses.as_deref(),
            rows: self.obstacles.rows(),
            load: self.obstacles.load(),
            nodal_load: &self.nodal_load,
            state: self.state.as_ref(),
            locked_in: self.locked_in,
            lifting: self.base.supports.as_ref().map_or_else(Default::default, |s| s.lifting(self.factor)),
        };
        Lagrangian::new(&*self.base.element, data)
    }

    /// The step seen whole, for output and reports.
    pub fn view(&self) -> ProblemView<'_> {
        ProblemView {
            element: &*self.base.element,
            obstacles: &self.obstacles,
            l: self.lagrangian(),
            supports: self.base.supports.as_ref(),
        }
    }
}
