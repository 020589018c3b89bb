//! The discrete problem of theory §3 assembled: an element (its operators on a mesh with its
//! dofs) and the problem's data — elasticity, P, K discretised (rows and load, theory §8), the
//! consistent nodal forces of tractions and body forces. [`DiscreteProblem::lagrangian`] is L;
//! [`ProblemView`] is what output and reports read of it, or of a load step.

use crate::error::SceneError;
use crate::fem::Discretisation;
use crate::fem::loads::{Load, nodal_loads};
use crate::fem::supports::Supports;
use crate::mesh::dofs::Dirichlet;
use crate::problem::displacements::AdmissibleDisplacements;
use crate::problem::elasticity::Elasticity;
use crate::problem::fields::PlasticState;
use crate::problem::kkt::locked_in_force;
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
    /// The `[[dirichlet]]` entries with their lifting and reactions (theory §14); `None` when
    /// the problem was made without them ([`DiscreteProblem::with_supports`]).
    pub supports: Option<Supports>,
    /// With a lifting: the zero state shifted by −ε(u_D) and its ‖BᵀCε_p‖ (theory §14).
    lifted: Option<(PlasticState, f64)>,
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
        let obstacles = obstacles
            .into()
            .discretise_with(element.mesh(), element.dofs(), OBSTACLE_PATH, |rows| element.contact_rows(rows))?;
        let nodal_load =
            if loads.is_empty() { Vec::new() } else { nodal_loads(element.mesh(), element.dofs(), loads)? };
        Ok(Self { element, elasticity, stresses, obstacles, nodal_load, supports: None, lifted: None })
    }

    /// The problem with its supports `dirichlet` (the entries the element's dofs were made
    /// with) and the loads `loads` it was made with: prescribed displacements as a lifting, and
    /// reactions (theory §14). A prescribed value, or an inclined support, at a node an
    /// obstacle's row acts on is an error: the rows see w only, on the axes.
    pub fn with_supports(mut self, dirichlet: &[Dirichlet], loads: &[Load]) -> Result<Self, SceneError> {
        let supports = Supports::new(&*self.element, dirichlet, loads)?;
        let dofs = self.element.dofs();
        if let Some(&n) = self.obstacles.rows().node.iter().find(|&&n| dofs.frame(n).is_some()) {
            let i = supports.inclined_entry(n).unwrap_or(0);
            return Err(SceneError::Region {
                field: format!("dirichlet[{i}].normal"),
                message: format!(
                    "holds node {n} on an inclined plane, where an obstacle's contact row acts: contact at nodes of \
                     an inclined support is not supported"
                ),
            });
        }
        if supports.is_lifted() {
            let rows = self.obstacles.rows();
            let lifted: Vec<usize> = supports.lifted_nodes().collect();
            if let Some(&n) = rows.node.iter().find(|n| lifted.binary_search(n).is_ok()) {
                let i = dirichlet.iter().position(Dirichlet::is_inhomogeneous).unwrap_or(0);
                return Err(SceneError::Region {
                    field: format!("dirichlet[{i}].value"),
                    message: format!(
                        "prescribes a displacement at node {n}, where an obstacle's contact row acts: contact at \
                         nodes with prescribed displacements is not supported"
                    ),
                });
            }
            let l = self.lagrangian();
            let zero = PlasticState::zero(l.n_points(), l.data.hardening_dim());
            let state = supports.shifted_state(zero, 1.0);
            let locked_in = locked_in_force(&*self.element, &self.elasticity, &state);
            self.lifted = Some((state, locked_in));
        }
        self.supports = Some(supports);
        Ok(self)
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
        Self { element, elasticity, stresses, obstacles, nodal_load, supports: None, lifted: None }
    }

    /// L: the element's operators with the problem's data (the stationary problem; with
    /// prescribed displacements, its state is the lifting's, theory §14).
    pub fn lagrangian(&self) -> Lagrangian<'_> {
        let mut data = Data::stationary(
            &self.elasticity,
            self.stresses.as_deref(),
            self.obstacles.rows(),
            self.obstacles.load(),
            &self.nodal_load,
        );
        if let (Some((state, locked_in)), Some(s)) = (&self.lifted, &self.supports) {
            data.state = Some(state);
            data.locked_in = *locked_in;
            data.lifting = s.lifting(1.0);
        }
        Lagrangian::new(&*self.element, data)
    }

    /// The problem seen whole, for output and reports.
    pub fn view(&self) -> ProblemView<'_> {
        ProblemView {
            element: &*self.element,
            obstacles: &self.obstacles,
            l: self.lagrangian(),
            supports: self.supports.as_ref(),
        }
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
    /// The supports (`None`: a problem made without them, or a rank's part).
    pub supports: Option<&'a Supports>,
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

    /// The reaction of every `[[dirichlet]]` entry to the stresses `sigma` (theory §14), at the
    /// view's load factor; empty without supports or where they cannot be computed.
    pub fn reactions(&self, sigma: &[crate::problem::tensor::Sym]) -> Vec<crate::fem::supports::Reaction> {
        let factor = self.l.data.lifting.factor;
        self.supports.and_then(|s| s.reactions(self.element, sigma, factor)).unwrap_or_default()
    }

    /// Nodal displacements u = w + u_D of the free values `w` (theory §14).
    pub fn displacements(&self, w: &[f64]) -> Vec<[f64; 3]> {
        let mut d = self.element.nodal_vectors(w);
        self.l.data.lifting.add_nodal(&mut d);
        d
    }

    /// Warnings about the set-up (P's parameters, nodes dropped from K_h).
    pub fn warnings(&self) -> Vec<String> {
        let mut w = self.l.data.stresses.map_or(vec![], |p| p.warnings());
        w.extend(self.l.data.rows.warnings.iter().cloned());
        w
    }
}
