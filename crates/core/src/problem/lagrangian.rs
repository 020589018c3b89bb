//! **L** — the discrete Lagrangian (theory §1 (1.11), §3):
//! `L(τ̂, (v, V)) = ½[τ̂, τ̂] − (ε(v), τ) + f·V` on P_h × K_h.
//!
//! L is the pair of the element's operators ([`ElementOperators`]: stress points, ε = B u, Bᵀσ,
//! assembly) and the problem's data ([`Data`]: the material and P, the rows of K_h with their
//! load, the loads on u, a load step's state). Every solver consumes it; the energies
//! ([`crate::problem::energies`]) and the KKT residuals ([`crate::problem::kkt`]) of any iterate
//! are free functions of it, independent of the solver that produced the iterate. A load step or
//! a reduced problem is the same operators with other data: nothing forwards.

use crate::problem::displacements::ConstraintRows;
use crate::problem::elasticity::Elasticity;
use crate::problem::fields::{PlasticState, StressField};
use crate::problem::lifting::Lifting;
use crate::problem::operators::ElementOperators;
use crate::problem::stresses::{AdmissibleStresses, StepOutput};
use crate::problem::tensor::{Sym, SymOp};
use rayon::prelude::*;
use std::ops::Deref;

/// The problem's data (theory §3, §11.1): what L adds to the element's operators.
#[derive(Clone, Copy, Debug)]
pub struct Data<'a> {
    /// The elasticity of the energy metric.
    pub elasticity: &'a Elasticity,
    /// P, or `None` for an elastic problem.
    pub stresses: Option<&'a dyn AdmissibleStresses>,
    /// K_h: the rows g(u, V) = G u + H V + c ≥ 0.
    pub rows: &'a ConstraintRows,
    /// The load f on the extra unknowns (the term f·V of (1.11)).
    pub load: &'a [f64],
    /// Consistent nodal forces f_u on the free dofs (tractions, body forces); empty for none.
    pub nodal_load: &'a [f64],
    /// The state of the previous load step, ε_p and q_n per point (theory §11.1); `None` for
    /// the stationary problem, whose state is zero.
    pub state: Option<&'a PlasticState>,
    /// ‖BᵀCε_p‖: the size of the internal forces the state's plastic strain holds locked in (0
    /// without a state; [`locked_in_force`](crate::problem::kkt::locked_in_force)). The equilibrium residual is measured against it
    /// too, so that a step whose answer is zero stress has a scale (theory §11.2).
    pub locked_in: f64,
    /// The lifting u_D of prescribed displacements at the load factor (theory §14): the
    /// unknown u of the solvers is w, and `state` is already shifted by ε(u_D) (none: empty).
    pub lifting: Lifting<'a>,
}

impl<'a> Data<'a> {
    /// Data without a state (the stationary problem).
    pub fn stationary(
        elasticity: &'a Elasticity,
        stresses: Option<&'a dyn AdmissibleStresses>,
        rows: &'a ConstraintRows,
        load: &'a [f64],
        nodal_load: &'a [f64],
    ) -> Self {
        Self { elasticity, stresses, rows, load, nodal_load, state: None, locked_in: 0.0, lifting: Lifting::default() }
    }

    /// Number of extra unknowns V.
    pub fn n_extras(&self) -> usize {
        self.rows.n_extras
    }

    /// P when it actually bounds the stresses; `None` for elastic problems, which then pay
    /// nothing for plasticity.
    pub fn plasticity(&self) -> Option<&'a dyn AdmissibleStresses> {
        self.stresses.filter(|p| !p.is_unbounded())
    }

    /// Number of hardening variables per point.
    pub fn hardening_dim(&self) -> usize {
        self.plasticity().map_or(0, |p| p.hardening_dim())
    }

    /// The elastic trial stresses C(ε_T − ε_p,T) (Cε_T for the stationary problem): the
    /// stresses of the elastic response from the step's state, for elastic starts (theory §11.1).
    pub fn elastic_stress(&self, eps: &[Sym], out: &mut [Sym]) {
        let c = self.elasticity.stiffness_matrix();
        match self.state {
            None => out.par_iter_mut().zip(eps.par_iter()).for_each(|(s, e)| *s = c * e),
            Some(st) => out
                .par_iter_mut()
                .zip(eps.par_iter())
                .zip(st.plastic_strain.par_iter())
                .for_each(|((s, e), p)| *s = c * (e - p)),
        }
    }

    /// The local law at every point: σ̂_T = P_D(Cε_T, 0) and, if asked, the consistent
    /// tangents (theory §2); from a step's state σ̂_T = P_D(C(ε_T − ε_p), q_n) (theory §11.1).
    /// Returns how many points were plastic and at how many P's return mapping ran (none for an
    /// elastic problem: σ = Cε, no call of P at all).
    pub fn local_law(&self, eps: &[Sym], out: &mut StressField, tangents: Option<&mut [SymOp]>) -> LocalLaw {
        let law = *self.elasticity;
        let Some(p) = self.plasticity() else {
            let c = law.stiffness_matrix();
            self.elastic_stress(eps, &mut out.sigma);
            out.plastic.par_iter_mut().for_each(|f| *f = false);
            if let Some(t) = tangents {
                t.par_iter_mut().for_each(|t| *t = c);
            }
            return LocalLaw::default();
        };
        let (m, stride) = (out.q.dim(), out.q.stride());
        let state = self.state;
        let points = out
            .sigma
            .par_iter_mut()
            .zip(out.q.par_chunks_mut(stride))
            .zip(out.plastic.par_iter_mut())
            .zip(eps.par_iter())
            .enumerate();
        // each point counts its own return mapping, where it runs
        let law_at = |i: usize, e: &Sym, out: StepOutput<'_>| match state {
            None => p.local_law(&law, e, out),
            Some(st) => p.step_law(&law, st.step(i, e), out),
        };
        let (plastic, projected) = match tangents {
            None => points
                .map(|(i, (((s, q), pl), e))| {
                    *pl = law_at(i, e, StepOutput::new(s, &mut q[..m], None));
                    (*pl as usize, 1)
                })
                .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1)),
            Some(t) => points
                .zip(t.par_iter_mut())
                .map(|((i, (((s, q), pl), e)), t)| {
                    *pl = law_at(i, e, StepOutput::new(s, &mut q[..m], Some(t)));
                    (*pl as usize, 1)
                })
                .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1)),
        };
        LocalLaw { plastic, projected }
    }
}

/// L: the element's operators with the problem's data (theory §3). It dereferences to the
/// operators, so `l.strain(u, eps)` applies B; the data are `l.data`.
#[derive(Clone, Copy, Debug)]
pub struct Lagrangian<'a> {
    /// The element's operators.
    pub ops: &'a dyn ElementOperators,
    /// The problem's data.
    pub data: Data<'a>,
}

impl<'a> Lagrangian<'a> {
    /// L of `ops` with `data`.
    pub fn new(ops: &'a dyn ElementOperators, data: Data<'a>) -> Self {
        Self { ops, data }
    }

    /// The same operators with other data (a load step, a reduced problem).
    pub fn with_data(&self, data: Data<'a>) -> Self {
        Self { ops: self.ops, data }
    }

    /// Number of extra unknowns V.
    pub fn n_extras(&self) -> usize {
        self.data.n_extras()
    }

    /// Number of rows of K_h.
    pub fn n_rows(&self) -> usize {
        self.data.rows.n_rows()
    }

    /// Forces are prescribed (on the extras or the body, on any rank): only then can a load
    /// exceed what a perfectly plastic body carries (theory §4.6).
    pub fn forced(&self) -> bool {
        self.comm().any(self.data.load.iter().chain(self.data.nodal_load).any(|f| *f != 0.0))
    }

    /// ε(u) = ε(w) + ε(u_D) of the displacement u whose free part is `w` (theory §14): the
    /// strain of the body, where [`ElementOperators::strain`] gives that of w.
    pub fn total_strain(&self, w: &[f64], eps: &mut [Sym]) {
        self.ops.strain(w, eps);
        self.data.lifting.add_strain(eps);
    }
}

impl<'a> Deref for Lagrangian<'a> {
    type Target = dyn ElementOperators + 'a;
    fn deref(&self) -> &Self::Target {
        self.ops
    }
}

/// An iterate of the saddle problem: primal (u, V) and dual (σ̂, λ).
#[derive(Clone, Copy, Debug)]
pub struct Iterate<'a> {
    /// Free displacement dofs.
    pub u: &'a [f64],
    /// Extra unknowns V.
    pub extras: &'a [f64],
    /// Generalised stresses.
    pub stress: &'a StressField,
    /// Contact multipliers (nodal contact forces), one per row of K_h.
    pub lambda: &'a [f64],
}

/// What one evaluation of [`Data::local_law`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LocalLaw {
    /// Points whose trial stress Cε lay outside D.
    pub plastic: usize,
    /// Points at which P's return mapping ran ([`AdmissibleStresses::step_law`] called): all of
    /// them for a bounded P, none for an elastic problem.
    pub projected: usize,
}

/// Scratch vectors for evaluations of L, allocated once per solve.
#[derive(Clone, Debug)]
pub struct Workspace {
    /// Strains per point.
    pub eps: Vec<Sym>,
    /// Stresses of the local law.
    pub stress: StressField,
    /// Internal forces minus loads, Bᵀσ − f_u (after [`crate::problem::kkt::kkt`]).
    pub force: Vec<f64>,
    /// Gᵀλ.
    pub gu: Vec<f64>,
    /// Hᵀλ.
    pub gv: Vec<f64>,
    /// Gaps g(u, V).
    pub gap: Vec<f64>,
}

impl Workspace {
    /// Scratch sized for `l`.
    pub fn new(l: &Lagrangian<'_>) -> Self {
        Self {
            eps: vec![Sym::zeros(); l.n_points()],
            stress: StressField::new(l.n_points(), l.data.hardening_dim()),
            force: vec![0.0; l.n_dofs()],
            gu: vec![0.0; l.n_dofs()],
            gv: vec![0.0; l.n_extras()],
            gap: vec![0.0; l.n_rows()],
        }
    }
}
