//! The discrete problem of theory §3 assembled: an element (its operators on a mesh with its
//! dofs) and the problem's data — elasticity, P, K discretised (rows and load, theory §8), the
//! consistent nodal forces of tractions and body forces. [`DiscreteProblem::lagrangian`] is L;
//! [`ProblemView`] is what output and reports read of it, or of a load step.

use crate::error::SceneError;
use crate::fem::Discretisation;
use crate::fem::loads::{Load, nodal_loads};
use crate::problem::displacements::AdmissibleDisplacements;
use crate::problem::elasticity::Elasticity;
use crate::problem::lagrangian::{Data, Lagrangian};
use crate::problem::obstacles::{DiscreteObstacles, OBSTACLE_PATH, ObstacleReport, Obstacles};
use crate::problem::stresses::{AdmissibleStresses, MAX_HARDENING_DIM};

/// An element with the problem's data: what a scene assembles (theory §3).
#[derive(Debug)]
pub struct DiscreteProblem {
    /// The element: mesh, dofs and operators.
    pub element: Box<dyn Discretisation>,
    /// Elasticity.
    pub elasticity: Elasticity,
    /// P (`None`: elastic).
    pub stresses: Option<Box<dyn AdmissibleStresses>>,
    /// K = K₁ ∩ K₂ ∩ … discretised: the concatenated rows and load, each obstacle's own part.
    pub obstacles: DiscreteObstacles,
    /// Consistent nodal forces of tractions and body forces (empty: none).
    pub nodal_load: Vec<f64>,
}

impl DiscreteProblem {
    /// The problem on `element` with elasticity, P (`None`: elastic), K — [`Obstacles`], or
    /// anything that converts into it: `None` (no contact), one boxed obstacle,
    /// `Some(obstacle)` — and the loads on u. The parameters are taken as valid (a scene
    /// validates every plugin once, when it is read; plugins' constructors validate). K's rows
    /// are discretised here, every obstacle's concatenated (theory §8), and errors name the
    /// scene's paths (`obstacle.zone`, `obstacle[1].zone`, `load[0].on`).
    pub fn new(
        element: Box<dyn Discretisation>,
        elasticity: Elasticity,
        stresses: Option<Box<dyn AdmissibleStresses>>,
        obstacles: impl Into<Obstacles>,
        loads: &[Load],
    ) -> Result<Self, SceneError> {
        if let Some(p) = &stresses {
            assert!(p.hardening_dim() <= MAX_HARDENING_DIM, "hardening_dim() exceeds MAX_HARDENING_DIM");
        }
        let obstacles = obstacles.into().discretise(element.mesh(), element.dofs(), OBSTACLE_PATH)?;
        let nodal_load =
            if loads.is_empty() { Vec::new() } else { nodal_loads(element.mesh(), element.dofs(), loads)? };
        Ok(Self { element, elasticity, stresses, obstacles, nodal_load })
    }

    /// The problem on `element` with K already discretised on it and the nodal loads `nodal_load`
    /// on its dofs (a rank's part of a distributed problem, theory §12).
    pub fn from_discretised(
        element: Box<dyn Discretisation>,
        elasticity: Elasticity,
        stresses: Option<Box<dyn AdmissibleStresses>>,
        obstacles: DiscreteObstacles,
        nodal_load: Vec<f64>,
    ) -> Self {
        Self { element, elasticity, stresses, obstacles, nodal_load }
    }

    /// L: the element's operators with the problem's data (the stationary problem).
    pub fn lagrangian(&self) -> Lagrangian<'_> {
        let data = Data::stationary(
            &self.elasticity,
            self.stresses.as_deref(),
            self.obstacles.rows(),
            self.obstacles.load(),
            &self.nodal_load,
        );
        Lagrangian::new(&*self.element, data)
    }

    /// The problem seen whole, for output and reports.
    pub fn view(&self) -> ProblemView<'_> {
        ProblemView { element: &*self.element, obstacles: &self.obstacles, l: self.lagrangian() }
    }
}

/// A discrete problem seen whole: the element (mesh, dofs, operators), the obstacles
/// discretised and L — what output and reports read, of a [`DiscreteProblem`] or of a load
/// step of it ([`crate::evolution::LoadStep::view`]).
#[derive(Clone, Copy, Debug)]
pub struct ProblemView<'a> {
    /// The element.
    pub element: &'a dyn Discretisation,
    /// K discretised.
    pub obstacles: &'a DiscreteObstacles,
    /// L.
    pub l: Lagrangian<'a>,
}

impl<'a> ProblemView<'a> {
    /// The only obstacle when there is exactly one; None without obstacle **and with several**
    /// (use [`ProblemView::contact_reports`] then).
    pub fn obstacle(&self) -> Option<&'a dyn AdmissibleDisplacements> {
        self.obstacles.obstacles().only()
    }

    /// The names of the extra unknowns, in the order of the solution's extras: each obstacle's
    /// names, prefixed `name.` when it is named (`left.U`).
    pub fn extra_names(&self) -> Vec<String> {
        self.obstacles.obstacles().extra_names()
    }

    /// Each obstacle's report on its own rows, extras and multipliers (`extras` and `lambda` are
    /// the concatenated vectors of a solution).
    pub fn contact_reports(&self, extras: &[f64], lambda: &[f64]) -> Vec<ObstacleReport> {
        self.obstacles.reports(self.element.mesh(), extras, lambda)
    }

    /// Warnings about the set-up (P's parameters, nodes dropped from K_h).
    pub fn warnings(&self) -> Vec<String> {
        let mut w = self.l.data.stresses.map_or(vec![], |p| p.warnings());
        w.extend(self.l.data.rows.warnings.iter().cloned());
        w
    }
}
