//! Fields at the stress points (theory §3, §11.1): the generalised stresses σ̂ = (σ, q) of an
//! iterate and the state (ε_p, q_n) a load step starts from. Both are a symmetric tensor and
//! hardening variables per point, stored the same way ([`Hardening`]).

use crate::problem::elasticity::Elasticity;
use crate::problem::stresses::StepInput;
use crate::problem::tensor::Sym;
use std::ops::{Deref, DerefMut};

/// Hardening variables at every point: `dim` per point, stored with the stride max(dim, 1) so
/// that per-point chunks are never empty (a field without hardening still splits by point).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Hardening {
    values: Vec<f64>,
    dim: usize,
}

impl Hardening {
    /// Zero hardening variables at `n` points, `dim` each.
    pub fn zeros(n: usize, dim: usize) -> Self {
        Self { values: vec![0.0; n * dim.max(1)], dim }
    }

    /// Number of hardening variables per point.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Storage stride (at least 1).
    pub fn stride(&self) -> usize {
        self.dim.max(1)
    }

    /// The variables at point i.
    #[inline]
    pub fn at(&self, i: usize) -> &[f64] {
        let s = self.stride();
        &self.values[i * s..i * s + self.dim]
    }

    /// The variables at point i, mutable.
    #[inline]
    pub fn at_mut(&mut self, i: usize) -> &mut [f64] {
        let s = self.stride();
        &mut self.values[i * s..i * s + self.dim]
    }
}

/// The raw storage, `stride()` entries per point.
impl Deref for Hardening {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        &self.values
    }
}

impl DerefMut for Hardening {
    fn deref_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }
}

/// Generalised stresses σ̂_T = (σ_T, q_T) at every stress point, and the plastic flags.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StressField {
    /// σ_T (Mandel).
    pub sigma: Vec<Sym>,
    /// q_T.
    pub q: Hardening,
    /// Whether the local law was plastic at the point.
    pub plastic: Vec<bool>,
}

impl StressField {
    /// Zero stresses at `n` points with `q_dim` hardening variables each.
    pub fn new(n: usize, q_dim: usize) -> Self {
        Self { sigma: vec![Sym::zeros(); n], q: Hardening::zeros(n, q_dim), plastic: vec![false; n] }
    }

    /// q at point i.
    #[inline]
    pub fn q(&self, i: usize) -> &[f64] {
        self.q.at(i)
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.sigma.len()
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.sigma.is_empty()
    }

    /// Number of plastic points.
    pub fn n_plastic(&self) -> usize {
        self.plastic.iter().filter(|p| **p).count()
    }
}

/// The state a load step starts from (theory §11.1): the plastic strain ε_p and the hardening
/// variables q_n at every stress point. Backward Euler in the load makes each step the saddle
/// problem of theory §3 with the local law σ̂ = P_D(C(ε − ε_p), q_n); the zero state is the
/// stationary (Hencky) problem.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlasticState {
    /// The plastic strain ε_p = ε(u_n) − Aσ_n (Mandel).
    pub plastic_strain: Vec<Sym>,
    /// q_n.
    pub q: Hardening,
}

impl PlasticState {
    /// The zero state at `n` points with `q_dim` hardening variables: the stationary problem.
    pub fn zero(n: usize, q_dim: usize) -> Self {
        Self { plastic_strain: vec![Sym::zeros(); n], q: Hardening::zeros(n, q_dim) }
    }

    /// The state a solution leaves (theory §11.1): ε_p = ε − Aσ at every point from the strains
    /// `eps` of its displacement and its stresses, and its hardening variables.
    pub fn from_solution(law: &Elasticity, eps: &[Sym], stress: &StressField) -> Self {
        let plastic_strain = eps.iter().zip(&stress.sigma).map(|(e, s)| e - law.compliance(s)).collect();
        Self { plastic_strain, q: stress.q.clone() }
    }

    /// True for the zero state (every ε_p and q_n zero): the stationary problem.
    pub fn is_zero(&self) -> bool {
        self.q.iter().all(|x| *x == 0.0) && self.plastic_strain.iter().all(|e| e.iter().all(|x| *x == 0.0))
    }

    /// q_n at point i.
    #[inline]
    pub fn q(&self, i: usize) -> &[f64] {
        self.q.at(i)
    }

    /// The step law's input at point i for the strain `eps` (theory §11.1).
    #[inline]
    pub fn step<'a>(&'a self, i: usize, eps: &'a Sym) -> StepInput<'a> {
        StepInput::new(eps, &self.plastic_strain[i], self.q(i))
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

impl<'a> IntoIterator for &'a Hardening {
    type Item = &'a f64;
    type IntoIter = std::slice::Iter<'a, f64>;
    fn into_iter(self) -> Self::IntoIter {
        self.values.iter()
    }
}

impl<'a> IntoIterator for &'a mut Hardening {
    type Item = &'a mut f64;
    type IntoIter = std::slice::IterMut<'a, f64>;
    fn into_iter(self) -> Self::IntoIter {
        self.values.iter_mut()
    }
}
