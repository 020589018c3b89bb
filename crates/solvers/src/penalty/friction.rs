//! The penalty's friction (theory §4.3, §8.3): the Moreau–Yosida regularisation of the friction
//! term r|s| of each node's tangential pair, its forces, energy and generalised Hessian.
//!
//! The term `r_i|s_i|` of Tresca's primal problem (theory §8.3) is replaced by its Moreau
//! envelope with the pair's penalty stiffness k (the Huber function of |s|)
//!
//! ```text
//! φ_k(s) = ½ k |s|²           if k|s| ≤ r   (stick: the regularised pair is a spring),
//!          r|s| − r²/(2k)     otherwise     (slip: the force on the disc's rim),
//! ```
//!
//! C¹ and convex, with the force `λ_t = −∇φ_k(s) = P_D(−k s)` — the penalty's friction force,
//! as χ = k g⁻ is its normal force — and the generalised Hessian `k ∂P_D/∂t(−k s)` of the
//! projection's derivative (theory §8.3): kI in stick, `(r/|s|)(I − ŝŝᵀ)` in slip, symmetric
//! for a given r. A sticking node moves |s| = |λ_t|/k ≤ r/k: O(μ), the regularisation's error as
//! the normal rows' penetration χ/k is (counter `max_stick_slip`).
//!
//! Coulomb's radius r = μ λ_n depends on the normal force: each Newton iteration takes the discs
//! of the iterate's own χ_n (a fixed point on r = μ χ_n interleaved with the Newton steps, the
//! discs held fixed along one step's line search); its Hessian leaves ∂r/∂χ_n out, which
//! keeps the systems symmetric (Cholesky) and makes the convergence linear where the radius
//! moves. The iteration stops on the gradient of J_μ with the discs of the point itself, so a
//! solved inner problem is a fixed point: the regularised Coulomb conditions hold.

use saddle_core::FrictionRows;
use saddle_core::problem::friction::{project_disc, project_disc_derivative};

/// The friction pairs of the rows and their current discs.
#[derive(Clone, Debug, Default)]
pub(super) struct RegularisedFriction {
    /// The rows' friction (blocks and laws).
    rows: FrictionRows,
    /// For each row, true when it is tangential.
    pub tangential: Vec<bool>,
    /// The current radius r_b of each block's disc.
    pub radii: Vec<f64>,
}

impl RegularisedFriction {
    /// The friction of `rows` on `n_rows` rows, discs of radius 0 until [`Self::forces`].
    pub fn new(rows: &FrictionRows, n_rows: usize) -> Self {
        Self { rows: rows.clone(), tangential: rows.tangential_mask(n_rows), radii: vec![0.0; rows.blocks.len()] }
    }

    /// Each block's (first tangential row, normal row).
    pub fn pairs(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.rows.blocks.iter().map(|b| (b.tangent, b.normal))
    }

    /// The discs of the normal forces in `chi` (r = the law's radius at χ_n), and the friction
    /// forces χ_t = P_D(−k s) of the slips s in `gap` (k the pair's stiffness in `k`).
    pub fn forces(&mut self, k: &[f64], gap: &[f64], chi: &mut [f64]) {
        for (b, r) in self.rows.blocks.iter().zip(&mut self.radii) {
            *r = self.rows.law(b).radius(b.weight, chi[b.normal]).max(0.0);
            let (t, kt) = (b.tangent, k[b.tangent]);
            let f = project_disc(*r, [-kt * gap[t], -kt * gap[t + 1]]);
            chi[t] = f[0];
            chi[t + 1] = f[1];
        }
    }

    /// Σ φ_k(s) over the pairs, with the current discs.
    pub fn energy(&self, k: &[f64], gap: &[f64]) -> f64 {
        self.rows
            .blocks
            .iter()
            .zip(&self.radii)
            .map(|(b, &r)| {
                let (kt, s) = (k[b.tangent], gap[b.tangent].hypot(gap[b.tangent + 1]));
                if kt * s <= r { 0.5 * kt * s * s } else { r * s - r * r / (2.0 * kt) }
            })
            .sum()
    }

    /// The generalised Hessian of φ_k at block `b`'s slip, in the slip's coordinates.
    pub fn hessian(&self, b: usize, k: &[f64], gap: &[f64]) -> [[f64; 2]; 2] {
        let t = self.rows.blocks[b].tangent;
        let kt = k[t];
        let (dp, _) = project_disc_derivative(self.radii[b], [-kt * gap[t], -kt * gap[t + 1]]);
        dp.map(|row| row.map(|x| kt * x))
    }

    /// Block `b`'s slip is outside its stick ball (k|s| > r).
    pub fn is_slipping(&self, b: usize, k: &[f64], gap: &[f64]) -> bool {
        let t = self.rows.blocks[b].tangent;
        k[t] * gap[t].hypot(gap[t + 1]) > self.radii[b]
    }

    /// The largest slip |s| of a sticking pair (|χ_t| inside its disc): the regularisation's
    /// error on the tangential rows.
    pub fn max_stick_slip(&self, gap: &[f64], chi: &[f64]) -> f64 {
        let stick = |(b, r): &(&saddle_core::FrictionBlock, &f64)| {
            chi[b.tangent].hypot(chi[b.tangent + 1]) < (1.0 - saddle_core::problem::friction::SLIP_TOL) * **r
        };
        self.rows
            .blocks
            .iter()
            .zip(&self.radii)
            .filter(stick)
            .map(|(b, _)| gap[b.tangent].hypot(gap[b.tangent + 1]))
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use saddle_core::FrictionBlock;

    /// The forces are −∇φ_k and the Hessian ∇²φ_k: central differences of the energy and of
    /// the forces, in stick and in slip.
    #[test]
    fn forces_and_hessian_are_the_derivatives_of_the_energy() {
        let rows = FrictionRows {
            laws: vec![Box::new(saddle_contact::Tresca { g: 0.3 })],
            blocks: vec![FrictionBlock { law: 0, normal: 0, tangent: 1, weight: 2.0 }],
        };
        let mut f = RegularisedFriction::new(&rows, 3);
        let k = [0.0, 10.0, 10.0];
        // r = 0.6: |k s| = 0.5 sticks, 5.0 slips
        for s in [[0.03, -0.04], [0.3, -0.4]] {
            let gap = [0.0, s[0], s[1]];
            let mut chi = [0.0; 3];
            f.forces(&k, &gap, &mut chi);
            let h = 1e-7;
            for d in 0..2 {
                let (mut p, mut m) = (gap, gap);
                p[1 + d] += h;
                m[1 + d] -= h;
                // central differences of a C¹ piecewise-smooth map away from its kink: O(h²)
                // plus round-off 1e-16/1e-7 ≈ 1e-9
                let grad = (f.energy(&k, &p) - f.energy(&k, &m)) / (2.0 * h);
                assert!((grad + chi[1 + d]).abs() < 1e-7, "{s:?}: {grad} against {}", -chi[1 + d]);
                let (mut cp, mut cm) = ([0.0; 3], [0.0; 3]);
                f.forces(&k, &p, &mut cp);
                f.forces(&k, &m, &mut cm);
                let hess = f.hessian(0, &k, &gap);
                for e in 0..2 {
                    let fd = -(cp[1 + e] - cm[1 + e]) / (2.0 * h);
                    assert!((fd - hess[e][d]).abs() < 1e-6, "{s:?}: {fd} against {}", hess[e][d]);
                }
            }
        }
    }
}
