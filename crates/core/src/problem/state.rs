//! The state a load step starts from (theory §11.1): the plastic strain ε_p and the hardening
//! variables q_n at every stress point. Backward Euler in the load makes each step the saddle
//! problem of theory §3 with the local law σ̂ = P_D(C(ε − ε_p), q_n); the zero state is the
//! stationary (Hencky) problem.

use crate::problem::elasticity::Elasticity;
use crate::problem::lagrangian::StressField;
use crate::problem::tensor::Sym;

/// ε_p and q_n at every stress point (theory §11.1).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlasticState {
    /// The plastic strain ε_p = ε(u_n) − Aσ_n (Mandel).
    pub plastic_strain: Vec<Sym>,
    /// q_n, `stride` entries per point of which the first `q_dim` are used (as in
    /// [`StressField`]).
    pub q: Vec<f64>,
    /// Number of hardening variables.
    pub q_dim: usize,
}

impl PlasticState {
    /// The zero state at `n` points with `q_dim` hardening variables: the stationary problem.
    pub fn zero(n: usize, q_dim: usize) -> Self {
        Self { plastic_strain: vec![Sym::zeros(); n], q: vec![0.0; n * q_dim.max(1)], q_dim }
    }

    /// The state a solution leaves (theory §11.1): ε_p = ε − Aσ at every point from the strains
    /// `eps` of its displacement and its stresses, and its hardening variables.
    pub fn from_solution(law: &Elasticity, eps: &[Sym], stress: &StressField) -> Self {
        let plastic_strain = eps.iter().zip(&stress.sigma).map(|(e, s)| e - law.compliance(s)).collect();
        Self { plastic_strain, q: stress.q.clone(), q_dim: stress.q_dim }
    }

    /// Storage stride of q (at least 1).
    pub fn stride(&self) -> usize {
        self.q_dim.max(1)
    }

    /// q_n at point i.
    pub fn q(&self, i: usize) -> &[f64] {
        let s = self.stride();
        &self.q[i * s..i * s + self.q_dim]
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.plastic_strain.len()
    }

    /// True without points.
    pub fn is_empty(&self) -> bool {
        self.plastic_strain.is_empty()
    }

    /// The equivalent plastic strain √(2/3)|ε_p| at point i (|dev ε_p| = |ε_p| for a plastic
    /// flow without volume change; the full norm otherwise).
    pub fn equivalent_plastic_strain(&self, i: usize) -> f64 {
        (2.0f64 / 3.0).sqrt() * self.plastic_strain[i].norm()
    }
}
