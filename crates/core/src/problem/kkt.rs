//! The KKT residuals of theory §3 (form 2) of any iterate, recomputed from scratch by the
//! operators and data of L — independently of the solver that produced the iterate.

use crate::problem::comm::Comm;
use crate::problem::displacements::ConstraintRows;
use crate::problem::elasticity::Elasticity;
use crate::problem::energies::hardening_increment;
use crate::problem::fields::PlasticState;
use crate::problem::friction::friction_residual;
use crate::problem::lagrangian::{Iterate, Lagrangian, Workspace};
use crate::problem::operators::ElementOperators;
use crate::problem::stresses::energy_inner;
use crate::problem::tensor::Sym;
use rayon::prelude::*;
use serde::Serialize;

/// The KKT residuals of theory §3 (form 2), each relative and dimensionless.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct KktResiduals {
    /// ‖Bᵀσ(u) − f_u − Gᵀλ‖ / max(‖Bᵀσ(u)‖, ‖Gᵀλ + f_u‖, ‖BᵀCε_p‖): internal forces against
    /// contact forces and loads (and, in a load step, the forces locked in by the plastic
    /// strain ε_p, theory §11.2).
    pub equilibrium: f64,
    /// ‖f + Hᵀλ‖ / max(‖f‖, ‖Hᵀλ‖): the load on the extra unknowns (Σλ = F for the punch).
    pub load_balance: f64,
    /// max_i |min(λ_i/λ_s, g_i/g_s)|: feasibility g ≥ 0, sign λ ≥ 0 and λ_i g_i = 0 in one
    /// natural residual; λ_s = max|λ|, g_s the displacement scale.
    pub complementarity: f64,
    /// [σ̂ − P_D(Cε(u), 0)]^{1/2} / [P_D(Cε(u), 0)]^{1/2}: the returned stresses against the
    /// local law of theory §2 in the energy norm.
    pub constitutive: f64,
}

impl KktResiduals {
    /// The largest residual; NaN if any residual is NaN.
    pub fn max(&self) -> f64 {
        let r = [self.equilibrium, self.load_balance, self.complementarity, self.constitutive];
        if r.iter().any(|x| x.is_nan()) { f64::NAN } else { r.iter().copied().fold(0.0, f64::max) }
    }
}

/// The KKT residuals of an iterate (theory §3 form 2), recomputed from scratch: σ(u) by the
/// local law, internal forces, gaps.
pub fn kkt(l: &Lagrangian<'_>, it: &Iterate<'_>, ws: &mut Workspace) -> KktResiduals {
    l.strain(it.u, &mut ws.eps);
    l.data.local_law(&ws.eps, &mut ws.stress, None);
    kkt_with_stress(l, it, ws)
}

/// As [`kkt`], with `ws.stress` already holding the local law's stresses at ε(`it.u`). On
/// return `ws.force` holds Bᵀσ(u) − f_u, the gradient of J in u without the contact forces.
pub fn kkt_with_stress(l: &Lagrangian<'_>, it: &Iterate<'_>, ws: &mut Workspace) -> KktResiduals {
    let equilibrium = equilibrium(l, it, ws);
    let load_balance = load_balance(l, ws);
    let complementarity = complementarity(l, it, ws);
    let constitutive = constitutive(l, it, ws);
    KktResiduals { equilibrium, load_balance, complementarity, constitutive }
}

/// ‖Bᵀσ − f_u − Gᵀλ‖ / max(‖Bᵀσ‖, ‖Gᵀλ + f_u‖, ‖BᵀCε_p‖); leaves Bᵀσ − f_u in `ws.force`,
/// Gᵀλ in `ws.gu` and Hᵀλ in `ws.gv`.
fn equilibrium(l: &Lagrangian<'_>, it: &Iterate<'_>, ws: &mut Workspace) -> f64 {
    let comm = l.comm();
    l.divergence(&ws.stress.sigma, &mut ws.force);
    let internal = global_norm(comm, &ws.force);
    ws.gu.iter_mut().for_each(|x| *x = 0.0);
    ws.gv.iter_mut().for_each(|x| *x = 0.0);
    l.data.rows.add_transpose(it.lambda, &mut ws.gu, &mut ws.gv);
    // Hᵀλ over every rank's rows (the extras are the same on all)
    comm.sum_in_place(&mut ws.gv);
    let fu = l.data.nodal_load;
    let external = if fu.is_empty() {
        global_norm(comm, &ws.gu)
    } else {
        for (f, l) in ws.force.iter_mut().zip(fu) {
            *f -= l;
        }
        comm.sum(ws.gu.iter().zip(fu).map(|(a, b)| (a + b) * (a + b)).sum::<f64>()).sqrt()
    };
    let difference = comm.sum(ws.force.iter().zip(&ws.gu).map(|(a, b)| (a - b) * (a - b)).sum::<f64>()).sqrt();
    relative(difference, internal.max(external).max(l.data.locked_in))
}

/// ‖f + Hᵀλ‖ / max(‖f‖, ‖Hᵀλ‖), with Hᵀλ in `ws.gv`.
fn load_balance(l: &Lagrangian<'_>, ws: &Workspace) -> f64 {
    let f = l.data.load;
    let sum = f.iter().zip(&ws.gv).map(|(a, b)| (a + b) * (a + b)).sum::<f64>().sqrt();
    relative(sum, norm(f).max(norm(&ws.gv)))
}

/// max_i |min(λ_i/λ_s, g_i/g_s)|; leaves the gaps in `ws.gap`.
fn complementarity(l: &Lagrangian<'_>, it: &Iterate<'_>, ws: &mut Workspace) -> f64 {
    let (rows, comm) = (l.data.rows, l.comm());
    rows.gap(it.u, it.extras, &mut ws.gap);
    let lambda_s = comm.max(max_abs(it.lambda));
    let g_s = comm.max(max_abs(it.u).max(max_abs(&rows.offset))).max(max_abs(it.extras));
    if rows.has_friction() {
        return comm.max(complementarity_with_friction(rows, it.lambda, &ws.gap, lambda_s, g_s));
    }
    let mut worst: f64 = 0.0;
    for (l, g) in it.lambda.iter().zip(&ws.gap) {
        let a = if lambda_s > 0.0 { l / lambda_s } else { *l };
        let b = if g_s > 0.0 { g / g_s } else { *g };
        let r = a.min(b).abs();
        worst = if r.is_nan() || worst.is_nan() { f64::NAN } else { worst.max(r) };
    }
    comm.max(worst)
}

/// The natural residual of rows with friction (theory §8.3): `min(λ_i/λ_s, g_i/g_s)` on the
/// normal rows, the friction residual of each node's tangential pair
/// ([`friction_residual`]), the larger of the two.
fn complementarity_with_friction(rows: &ConstraintRows, lambda: &[f64], gap: &[f64], lambda_s: f64, g_s: f64) -> f64 {
    let tangential = rows.friction.tangential_mask(rows.n_rows());
    let mut worst: f64 = 0.0;
    for ((l, g), _) in lambda.iter().zip(gap).zip(&tangential).filter(|(_, t)| !**t) {
        let a = if lambda_s > 0.0 { l / lambda_s } else { *l };
        let b = if g_s > 0.0 { g / g_s } else { *g };
        let r = a.min(b).abs();
        worst = if r.is_nan() || worst.is_nan() { f64::NAN } else { worst.max(r) };
    }
    let f = friction_residual(&rows.friction, lambda, gap, lambda_s, g_s);
    if f.is_nan() || worst.is_nan() { f64::NAN } else { worst.max(f) }
}

/// [σ̂ − σ̂(u)]^{1/2} / [σ̂(u)]^{1/2} in the energy norm, σ̂(u) the local law's in `ws.stress`.
fn constitutive(l: &Lagrangian<'_>, it: &Iterate<'_>, ws: &Workspace) -> f64 {
    let law = *l.data.elasticity;
    let p = l.data.plasticity();
    let w = l.weights();
    let (num, den) = (0..l.n_points())
        .into_par_iter()
        .map(|i| {
            let (s0, q0) = (&ws.stress.sigma[i], ws.stress.q(i));
            let ds = it.stress.sigma[i] - s0;
            let dq = hardening_increment(it.stress.q(i), Some(q0));
            let dq = &dq[..q0.len()];
            (w[i] * energy_inner(p, &law, &ds, dq, &ds, dq), w[i] * energy_inner(p, &law, s0, q0, s0, q0))
        })
        .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    relative(l.comm().sum(num).sqrt(), l.comm().sum(den).sqrt())
}

/// f = BᵀCε_p of the operators and the plastic strain of `state` (theory §11.2): the internal
/// forces that ε_p alone locks in (the load of an elastic start from the state).
pub fn locked_in_forces(ops: &dyn ElementOperators, law: &Elasticity, state: &PlasticState, f: &mut [f64]) {
    let c = law.stiffness_matrix();
    let s0: Vec<Sym> = state.plastic_strain.iter().map(|p| c * p).collect();
    ops.divergence(&s0, f);
}

/// ‖BᵀCε_p‖ ([`locked_in_forces`]): the scale of a step's equilibrium residual (over every
/// rank's dofs).
pub fn locked_in_force(ops: &dyn ElementOperators, law: &Elasticity, state: &PlasticState) -> f64 {
    let mut f = vec![0.0; ops.n_dofs()];
    locked_in_forces(ops, law, state, &mut f);
    global_norm(ops.comm(), &f)
}

/// num/den, with 0/0 = 0 and x/0 = 1 for x ≠ 0 (an entirely wrong answer); NaN stays NaN.
fn relative(num: f64, den: f64) -> f64 {
    if num.is_nan() || den.is_nan() {
        f64::NAN
    } else if den > 0.0 {
        num / den
    } else if num == 0.0 {
        0.0
    } else {
        1.0
    }
}

/// Euclidean norm.
pub fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// Euclidean norm of a vector whose entries are split over the ranks of `comm` (each rank its
/// owned dofs or rows).
pub fn global_norm(comm: &dyn Comm, x: &[f64]) -> f64 {
    comm.sum(x.iter().map(|v| v * v).sum::<f64>()).sqrt()
}

/// Largest absolute entry (NaN if any entry is NaN).
pub fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m: f64, v| if v.is_nan() || m.is_nan() { f64::NAN } else { m.max(v.abs()) })
}
