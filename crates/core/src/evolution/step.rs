//! One load step (theory §11.1): L of a discretisation with every load multiplied by a factor
//! (tractions and body forces, each obstacle's prescribed force or displacement,
//! [`crate::AdmissibleDisplacements::scaled_load`]) and the state of the previous step.

use crate::error::SceneError;
use crate::fem::Discretisation;
use crate::mesh::TetMesh;
use crate::mesh::dofs::DofMap;
use crate::problem::displacements::ConstraintRows;
use crate::problem::elasticity::Elasticity;
use crate::problem::lagrangian::{Lagrangian, Material, RigidBodyModes, locked_in_force};
use crate::problem::obstacles::{DiscreteObstacles, OBSTACLE_PATH};
use crate::problem::pattern::SymmetricPattern;
use crate::problem::state::PlasticState;
use crate::problem::stresses::AdmissibleStresses;
use crate::problem::tensor::Sym;

/// L at load factor `factor` from a state (theory §11.1): the base discretisation's operators,
/// the obstacles re-discretised with their loads scaled, the nodal loads scaled, and the
/// state (ε_p, q_n) that shifts the local law. It is itself a [`Discretisation`], so it passes
/// to every solver and to every report and output of a one-step solve.
#[derive(Debug)]
pub struct LoadStep<'a> {
    base: &'a dyn Discretisation,
    factor: f64,
    state: PlasticState,
    obstacles: DiscreteObstacles,
    nodal_load: Vec<f64>,
    /// ‖BᵀCε_p‖, computed once.
    state_force: f64,
}

impl<'a> LoadStep<'a> {
    /// The step of `base` at `factor` from `state`. The obstacles are discretised at the scaled
    /// load (factor 1: `base`'s own rows); errors name the obstacle whose plugin cannot scale
    /// its load or rejects the scaled value. The state must have `base`'s points and hardening
    /// dimension.
    pub fn new(base: &'a dyn Discretisation, factor: f64, state: PlasticState) -> Result<Self, SceneError> {
        assert_eq!(state.len(), base.n_points(), "the state has {} points, L {}", state.len(), base.n_points());
        assert_eq!(state.q_dim, base.hardening_dim(), "the state's hardening dimension");
        let obstacles = if factor == 1.0 || base.obstacles().is_empty() {
            base.discrete_obstacles().clone()
        } else {
            base.obstacles().scaled_load(factor)?.discretise(base.mesh(), base.dofs(), OBSTACLE_PATH)?
        };
        let nodal_load = base.nodal_load().iter().map(|f| factor * f).collect();
        let state_force = locked_in_force(base, &state);
        Ok(Self { base, factor, state, obstacles, nodal_load, state_force })
    }

    /// The load factor.
    pub fn factor(&self) -> f64 {
        self.factor
    }

    /// The discretisation the step is made of.
    pub fn base(&self) -> &'a dyn Discretisation {
        self.base
    }
}

impl Lagrangian for LoadStep<'_> {
    fn n_dofs(&self) -> usize {
        self.base.n_dofs()
    }
    fn n_points(&self) -> usize {
        self.base.n_points()
    }
    fn elasticity(&self) -> &Elasticity {
        self.base.elasticity()
    }
    fn stresses(&self) -> Option<&dyn AdmissibleStresses> {
        self.base.stresses()
    }
    fn constraints(&self) -> &ConstraintRows {
        self.obstacles.rows()
    }
    fn load(&self) -> &[f64] {
        self.obstacles.load()
    }
    fn weights(&self) -> &[f64] {
        self.base.weights()
    }
    fn strain(&self, u: &[f64], eps: &mut [Sym]) {
        self.base.strain(u, eps)
    }
    fn divergence(&self, sigma: &[Sym], f: &mut [f64]) {
        self.base.divergence(sigma, f)
    }
    fn strain_entries(&self) -> Vec<(usize, usize, usize, f64)> {
        self.base.strain_entries()
    }
    fn pattern(&self) -> &SymmetricPattern {
        self.base.pattern()
    }
    fn assemble(&self, material: Material<'_>, values: &mut [f64]) {
        self.base.assemble(material, values)
    }
    fn rigid_body_modes(&self) -> Option<RigidBodyModes> {
        self.base.rigid_body_modes()
    }
    fn nodal_load(&self) -> &[f64] {
        &self.nodal_load
    }
    fn state(&self) -> Option<&PlasticState> {
        Some(&self.state)
    }
    fn state_force_norm(&self) -> f64 {
        self.state_force
    }
}

impl Discretisation for LoadStep<'_> {
    fn mesh(&self) -> &TetMesh {
        self.base.mesh()
    }
    fn nodal_vectors(&self, u: &[f64]) -> Vec<[f64; 3]> {
        self.base.nodal_vectors(u)
    }
    fn dofs(&self) -> &DofMap {
        self.base.dofs()
    }
    fn discrete_obstacles(&self) -> &DiscreteObstacles {
        &self.obstacles
    }
    fn name(&self) -> &'static str {
        self.base.name()
    }
    fn points_per_element(&self) -> usize {
        self.base.points_per_element()
    }
    fn locks(&self) -> bool {
        self.base.locks()
    }
}
