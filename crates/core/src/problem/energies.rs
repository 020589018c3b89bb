//! The energies of L (theory §3 forms 1 and 3, §11.1) for any iterate, as free functions of L:
//! the primal energy J, the stress energy ½[σ̂, σ̂] and the dual energy. J − dual is the
//! duality gap of a dual-feasible pair.

use crate::linalg::reduce::tree_sum;
use crate::problem::fields::StressField;
use crate::problem::lagrangian::{Lagrangian, Workspace};
use crate::problem::stresses::{MAX_HARDENING_DIM, energy_inner};
use crate::problem::tensor::Sym;

/// Σ_T w_T ψ(ε_T): the stored energy of a strain field (theory §2); from a step's state
/// Σ_T w_T ψ_n(ε_T) (theory §11.1). Summed over the ranks.
pub fn energy_of_strain(l: &Lagrangian<'_>, eps: &[Sym]) -> f64 {
    l.comm().sum(local_energy_of_strain(l, eps))
}

/// [`energy_of_strain`] over this rank's points.
fn local_energy_of_strain(l: &Lagrangian<'_>, eps: &[Sym]) -> f64 {
    let law = *l.data.elasticity;
    let w = l.weights();
    // each sum the same bits on any number of threads (the line search compares energies)
    let points = 0..eps.len();
    match (l.data.plasticity(), l.data.state) {
        (None, None) => tree_sum(points, &|r| r.map(|i| 0.5 * w[i] * eps[i].dot(&law.stress(&eps[i]))).sum()),
        (Some(p), None) => tree_sum(points, &|r| r.map(|i| w[i] * p.energy(&law, &eps[i])).sum()),
        (None, Some(st)) => tree_sum(points, &|r| {
            r.map(|i| {
                let x = eps[i] - st.plastic_strain[i];
                0.5 * w[i] * x.dot(&law.stress(&x))
            })
            .sum()
        }),
        (Some(p), Some(st)) => tree_sum(points, &|r| r.map(|i| w[i] * p.step_energy(&law, st.step(i, &eps[i]))).sum()),
    }
}

/// The primal energy J(u, V) = Σ_T |T| ψ(ε_T(u)) − f_u·u − f·V (theory §3 form 1); the sums
/// over points and dofs are over every rank's, V is the same on all.
pub fn energy(l: &Lagrangian<'_>, u: &[f64], extras: &[f64], ws: &mut Workspace) -> f64 {
    l.strain(u, &mut ws.eps);
    energy_of_strain(l, &ws.eps)
        - l.comm().sum(l.data.nodal_load.iter().zip(u).map(|(f, x)| f * x).sum::<f64>())
        - l.data.load.iter().zip(extras).map(|(f, v)| f * v).sum::<f64>()
}

/// q − q_n at one point (q itself for the stationary problem), on the stack.
#[inline]
pub(crate) fn hardening_increment(q: &[f64], q_n: Option<&[f64]>) -> [f64; MAX_HARDENING_DIM] {
    std::array::from_fn(|k| if k < q.len() { q[k] - q_n.map_or(0.0, |qn| qn[k]) } else { 0.0 })
}

/// ½[σ̂, σ̂] = ½ Σ_T |T| (Aσ_T:σ_T + q_T·H⁻¹q_T); from a step's state the hardening part is
/// centred at q_n: ½ Σ_T |T| (Aσ_T:σ_T + (q_T − q_n)·H⁻¹(q_T − q_n)) (theory §11.1).
pub fn stress_energy(l: &Lagrangian<'_>, stress: &StressField) -> f64 {
    let law = *l.data.elasticity;
    let p = l.data.plasticity();
    let w = l.weights();
    let state = l.data.state;
    let local = tree_sum(0..stress.len(), &|r| {
        r.map(|i| {
            let (s, q) = (&stress.sigma[i], stress.q(i));
            let dq = hardening_increment(q, state.map(|st| st.q(i)));
            let dq = &dq[..q.len()];
            0.5 * w[i] * energy_inner(p, &law, s, dq, s, dq)
        })
        .sum()
    });
    l.comm().sum(local)
}

/// The dual energy −(½[σ̂, σ̂] + λ·c) (theory §3 form 3); from a step's state
/// −(½[σ̂, σ̂]_n + (ε_p, σ) + λ·c) with the centred ½[σ̂, σ̂]_n of [`stress_energy`]
/// (theory §11.1). For a dual-feasible pair it is a lower bound of J, with equality at the
/// solution: J − dual is the duality gap.
pub fn dual_energy(l: &Lagrangian<'_>, stress: &StressField, lambda: &[f64]) -> f64 {
    let c = &l.data.rows.offset;
    let work = l.comm().sum(lambda.iter().zip(c).map(|(l, c)| l * c).sum::<f64>());
    -(complementary_energy(l, stress) + work)
}

/// ½[σ̂, σ̂] (theory §3 form 3); from a step's state ½[σ̂, σ̂]_n + (ε_p, σ) (theory §11.1).
fn complementary_energy(l: &Lagrangian<'_>, stress: &StressField) -> f64 {
    let prestrain: f64 = l.data.state.map_or(0.0, |st| {
        let w = l.weights();
        l.comm().sum(tree_sum(0..stress.len(), &|r| r.map(|i| w[i] * st.plastic_strain[i].dot(&stress.sigma[i])).sum()))
    });
    stress_energy(l, stress) + prestrain
}

/// J(u, V) from the local law's output at u, without running it again (theory §2.3:
/// ψ(ε) = ε:σ − ½[σ̂, σ̂] at σ̂ = P_D(Cε, 0); from a step's state ψ_n = (ε − ε_p):σ − ½[σ̂, σ̂]_n):
/// with `force` = Bᵀσ̂ − f_u, Σ_T |T| ε(u):σ = u·Bᵀσ̂, so J = u·force − f·V − ½[σ̂, σ̂]_n − (ε_p, σ).
/// Equals [`energy`] when `stress` is the local law's at u.
pub fn energy_of_stress(l: &Lagrangian<'_>, u: &[f64], extras: &[f64], stress: &StressField, force: &[f64]) -> f64 {
    l.comm().sum(u.iter().zip(force).map(|(x, f)| x * f).sum::<f64>())
        - l.data.load.iter().zip(extras).map(|(f, v)| f * v).sum::<f64>()
        - complementary_energy(l, stress)
}
