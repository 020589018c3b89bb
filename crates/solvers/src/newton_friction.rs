//! Newton's friction (theory §4.2, §8.3): the semismooth Newton step of the natural residual
//! `λ_t,i = P_{D_i}(λ_t,i − κ_i s_i)` of each node's tangential pair beside the normal rows'
//! `min(λ_i, c_i g_i)` — the primal–dual active set of Hüeber, Stadler and Wohlmuth, "A
//! primal-dual active set algorithm for three-dimensional contact problems with Coulomb
//! friction", SIAM J. Sci. Comput. 30 (2008), an Alart–Curnier-type formulation.
//!
//! At the iterate (λ, s) with the trial `t = λ_t − κ s` (κ the pair's elastic row stiffness, as
//! c_i of the normal rows: forces and slips compared in consistent units):
//!
//! * **stick** (|t| ≤ r): the pair's rows join the active set as equalities s + Δs = 0, their
//!   forces the reactions — exactly as an active normal row;
//! * **slip** (|t| > r): the linearised disc condition. With M = ∂P/∂t = (r/|t|)(I − t̂t̂ᵀ) and
//!   F = λ_t − P_D(t), Newton's equation `(I − M) δλ + κ M δs = −F` gives
//!   `λ_t + δλ = F₀ − N δs`, `N = κ (I − M)⁻¹ M` (symmetric, positive semidefinite: eigenvalues
//!   0 along t̂ and κ r/(|t| − r) across), `F₀ = λ_t − (I − M)⁻¹F`: a Robin condition on the
//!   pair's free coordinates, N added to the tangent and F₀ to the forces ([`SlipPair`]).
//!
//! The radius r is the law's at the iterate's λ_n: Tresca's given bound, and for Coulomb
//! r = μ λ_n of the iterate — a fixed point on r interleaved with the Newton steps, ∂r/∂λ_n
//! left out of the step (it would make the system non-symmetric), so that Coulomb converges
//! linearly where the radius still moves; the iteration stops on the KKT residual, whose
//! friction part uses μ λ_n of the iterate itself.

use saddle_core::ConstraintRows;
use saddle_core::problem::friction::{project_disc, project_disc_derivative};

/// A slipping pair's Robin condition: its forces after the step are `force − n δs`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlipPair {
    /// The pair's first tangential row (the second is `tangent + 1`).
    pub tangent: usize,
    /// N = κ (I − M)⁻¹ M.
    pub n: [[f64; 2]; 2],
    /// F₀ = λ_t − (I − M)⁻¹ (λ_t − P_D(λ_t − κ s)).
    pub force: [f64; 2],
}

/// The friction part of the active set (module docs): each pair of `rows` stick (both rows in
/// `active`) or slip (out of it, its [`SlipPair`] in `slips`), from the multipliers `lambda`,
/// the rows' values `gap` and the rows' elastic stiffnesses `c`.
pub(crate) fn friction_active_set(
    rows: &ConstraintRows,
    lambda: &[f64],
    gap: &[f64],
    c: &[f64],
    active: &mut [bool],
    slips: &mut Vec<SlipPair>,
) {
    slips.clear();
    for b in &rows.friction.blocks {
        let t = b.tangent;
        let kappa = 0.5 * (c[t] + c[t + 1]);
        let r = rows.friction.law(b).radius(b.weight, lambda[b.normal]).max(0.0);
        let lt = [lambda[t], lambda[t + 1]];
        let trial = [lt[0] - kappa * gap[t], lt[1] - kappa * gap[t + 1]];
        let stick = r > 0.0 && trial[0].hypot(trial[1]) <= r;
        active[t] = stick;
        active[t + 1] = stick;
        if !stick {
            slips.push(slip_pair(t, r, kappa, lt, trial));
        }
    }
}

/// The Robin condition of a pair slipping at the trial `trial` = λ_t − κ s (module docs).
fn slip_pair(tangent: usize, r: f64, kappa: f64, lt: [f64; 2], trial: [f64; 2]) -> SlipPair {
    if r <= 0.0 {
        // an empty disc: no force, whatever the slip (also at t = 0, where P's derivative is I)
        return SlipPair { tangent, n: [[0.0; 2]; 2], force: [0.0; 2] };
    }
    let (m, _) = project_disc_derivative(r, trial);
    let p = project_disc(r, trial);
    let f = [lt[0] - p[0], lt[1] - p[1]];
    // (I − M)⁻¹: I − M is symmetric with eigenvalues 1 (along t̂) and 1 − r/|t| > 0 (across)
    let (a, b, d) = (1.0 - m[0][0], -m[0][1], 1.0 - m[1][1]);
    let det = a * d - b * b;
    let inv = [[d / det, -b / det], [-b / det, a / det]];
    let mul = |x: [[f64; 2]; 2], y: [[f64; 2]; 2]| {
        [
            [x[0][0] * y[0][0] + x[0][1] * y[1][0], x[0][0] * y[0][1] + x[0][1] * y[1][1]],
            [x[1][0] * y[0][0] + x[1][1] * y[1][0], x[1][0] * y[0][1] + x[1][1] * y[1][1]],
        ]
    };
    let n = mul(inv, m).map(|row| row.map(|x| kappa * x));
    let g = [inv[0][0] * f[0] + inv[0][1] * f[1], inv[1][0] * f[0] + inv[1][1] * f[1]];
    SlipPair { tangent, n, force: [lt[0] - g[0], lt[1] - g[1]] }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Robin condition is the linearisation of the natural residual: at a slipping solution
    /// (λ on the rim, s = −½λ), the forces `force − n δs` of a slip change δs keep
    /// `λ − P(λ − κ s)` zero to second order — the exact residual falls like |δs|².
    #[test]
    fn slip_pair_linearises_the_natural_residual() {
        let (r, kappa) = (0.7, 3.0);
        let lt = [0.6 * r, 0.8 * r];
        let s = [-0.5 * lt[0], -0.5 * lt[1]];
        let trial = [lt[0] - kappa * s[0], lt[1] - kappa * s[1]];
        let pair = slip_pair(0, r, kappa, lt, trial);
        // N symmetric
        assert!((pair.n[0][1] - pair.n[1][0]).abs() < 1e-15);
        let defect = |h: f64| {
            let ds = [h * 0.6, -h * 0.8];
            let s1 = [s[0] + ds[0], s[1] + ds[1]];
            let l1 = [
                pair.force[0] - pair.n[0][0] * ds[0] - pair.n[0][1] * ds[1],
                pair.force[1] - pair.n[1][0] * ds[0] - pair.n[1][1] * ds[1],
            ];
            let p = project_disc(r, [l1[0] - kappa * s1[0], l1[1] - kappa * s1[1]]);
            (l1[0] - p[0]).hypot(l1[1] - p[1])
        };
        // second order: halving δs quarters the defect (to 10 %)
        let (d1, d2) = (defect(1e-3), defect(5e-4));
        assert!(d1 < 1e-5 && (d1 / d2 - 4.0).abs() < 0.4, "{d1:e} {d2:e}");
    }
}
