//! The dual of Uzawa's projection with friction (theory §8.3, §4.1): the dense programme
//!
//! `min ½ μᵀ S μ + μᵀ q`  over  μ_i ≥ 0 (normal rows),  |μ_t,b| ≤ R_b (each node's tangential
//! pair, R_b = ρ r(w_b, μ_n,b/ρ), the law's radius at the pair's current normal multiplier),
//!
//! S the Delassus matrix. Solved by block Gauss–Seidel: a normal row is the scalar step
//! `μ_i = max(0, μ_i − (Sμ + q)_i / S_ii)`, a tangential pair the exact minimiser of its 2 × 2
//! quadratic over its disc ([`disc_qp`]), the disc's radius taken from its normal row's current
//! multiplier. For a given bound (Tresca: R_b = ρ g w_b) each block step lowers the convex
//! objective and the blocks are the programme's own product structure, so the sweeps converge
//! to its minimiser. For Coulomb (R_b = μ_c μ_n,b) the sweeps are a fixed-point iteration whose
//! fixed points are exactly the discrete Coulomb conditions (theory §8.3: it converges when the
//! normal–tangential coupling of S times μ_c is small enough, and is reported as not converged
//! otherwise). They are warm-started from the last solution (the projections of successive Uzawa
//! iterations differ little) and stop when a sweep moves no multiplier by more than
//! [`SWEEP_TOL`] of the largest one.

use nalgebra::DMatrix;
use saddle_core::{ConstraintRows, FrictionLaw, SolveError};

/// A sweep that changes no multiplier by more than this fraction of max|μ| ends the iteration:
/// a hundred times the round-off of the residual update.
pub const SWEEP_TOL: f64 = 1e-14;

/// Sweeps before the iteration is reported as not converged.
pub const MAX_SWEEPS: usize = 200_000;

/// One block of the programme: a normal row, or a tangential pair (its first row) with its
/// normal row, its law (index into [`FrictionQp`]'s laws) and its weight.
#[derive(Clone, Copy, Debug)]
enum Block {
    Normal(usize),
    Pair { tangent: usize, normal: usize, law: usize, weight: f64 },
}

/// The programme's matrix, its blocks and the last solution.
#[derive(Debug)]
pub struct FrictionQp {
    s: DMatrix<f64>,
    blocks: Vec<Block>,
    laws: Vec<Box<dyn FrictionLaw>>,
    /// ρ: the multipliers μ are ρ times the contact forces.
    rho: f64,
    mu: Vec<f64>,
    /// Scratch: Sμ + q.
    r: Vec<f64>,
    /// Sweeps of the last solve.
    pub last_sweeps: usize,
}

impl FrictionQp {
    /// The programme with Delassus matrix `s` on `rows` (friction blocks from their laws), discs
    /// of radius `rho` × the law's radius at the normal force μ_n/ρ.
    pub fn new(s: DMatrix<f64>, rows: &ConstraintRows, rho: f64) -> Self {
        let n = rows.n_rows();
        let tangential = rows.friction.tangential_mask(n);
        let mut blocks: Vec<Block> = (0..n).filter(|&i| !tangential[i]).map(Block::Normal).collect();
        blocks.extend(rows.friction.blocks.iter().map(|b| Block::Pair {
            tangent: b.tangent,
            normal: b.normal,
            law: b.law,
            weight: b.weight,
        }));
        let laws = rows.friction.laws.clone();
        Self { s, blocks, laws, rho, mu: vec![0.0; n], r: vec![0.0; n], last_sweeps: 0 }
    }

    /// The minimiser for the linear term `q`, from the last one.
    pub fn solve(&mut self, q: &[f64], solver: &str) -> Result<&[f64], SolveError> {
        for (i, (r, qi)) in self.r.iter_mut().zip(q).enumerate() {
            *r = qi + self.s.row(i).iter().zip(&self.mu).map(|(s, m)| s * m).sum::<f64>();
        }
        for sweep in 1..=MAX_SWEEPS {
            let mut change: f64 = 0.0;
            for k in 0..self.blocks.len() {
                change = change.max(self.block_step(self.blocks[k]));
            }
            let size = self.mu.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            if change <= SWEEP_TOL * size || size == 0.0 && change == 0.0 {
                self.last_sweeps = sweep;
                return Ok(&self.mu);
            }
            if !change.is_finite() {
                break;
            }
        }
        Err(SolveError::Unsupported {
            solver: solver.into(),
            message: format!(
                "the projection onto K_h with friction did not converge in {MAX_SWEEPS} Gauss–Seidel sweeps (theory \
                 §8.3; with Coulomb's law the sweeps are a fixed point, which a large μ can keep from converging)"
            ),
        })
    }

    /// One block's exact minimisation, Sμ + q updated; returns the largest change of μ.
    fn block_step(&mut self, b: Block) -> f64 {
        match b {
            Block::Normal(i) => {
                let new = (self.mu[i] - self.r[i] / self.s[(i, i)]).max(0.0);
                let d = new - self.mu[i];
                self.update(i, d);
                d.abs()
            }
            Block::Pair { tangent: t, normal, law, weight } => {
                let radius = self.rho * self.laws[law].radius(weight, self.mu[normal] / self.rho);
                let a = [[self.s[(t, t)], self.s[(t, t + 1)]], [self.s[(t + 1, t)], self.s[(t + 1, t + 1)]]];
                let x = [self.mu[t], self.mu[t + 1]];
                // the block's linear term without its own part: r − A x
                let b = [self.r[t] - a[0][0] * x[0] - a[0][1] * x[1], self.r[t + 1] - a[1][0] * x[0] - a[1][1] * x[1]];
                let new = disc_qp(a, b, radius);
                let d = [new[0] - x[0], new[1] - x[1]];
                self.update(t, d[0]);
                self.update(t + 1, d[1]);
                d[0].abs().max(d[1].abs())
            }
        }
    }

    /// μ_i += d, Sμ + q with it.
    fn update(&mut self, i: usize, d: f64) {
        if d != 0.0 {
            self.mu[i] += d;
            for (r, s) in self.r.iter_mut().zip(self.s.column(i).iter()) {
                *r += s * d;
            }
        }
    }
}

/// The minimiser of ½ xᵀAx + bᵀx over |x| ≤ R (A symmetric positive definite 2 × 2): −A⁻¹b if
/// inside, else x(κ) = −(A + κI)⁻¹b with |x(κ)| = R, κ > 0 found by bisection (|x(κ)| falls
/// monotonically; 200 halvings reach round-off).
pub fn disc_qp(a: [[f64; 2]; 2], b: [f64; 2], radius: f64) -> [f64; 2] {
    let solve = |k: f64| {
        let (p, q, r) = (a[0][0] + k, 0.5 * (a[0][1] + a[1][0]), a[1][1] + k);
        let det = p * r - q * q;
        [-(r * b[0] - q * b[1]) / det, -(p * b[1] - q * b[0]) / det]
    };
    let x = solve(0.0);
    if x[0].hypot(x[1]) <= radius {
        return x;
    }
    if radius <= 0.0 {
        return [0.0, 0.0];
    }
    // |x(κ)| ≤ |b|/κ: at κ = |b|/R it is inside
    let (mut lo, mut hi) = (0.0, b[0].hypot(b[1]) / radius);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        let x = solve(mid);
        if x[0].hypot(x[1]) > radius { lo = mid } else { hi = mid }
    }
    let x = solve(hi);
    // on the rim to round-off: scale onto it
    let n = x[0].hypot(x[1]);
    [x[0] * radius / n, x[1] * radius / n]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The disc QP against its optimality conditions: on the rim, −(Ax + b) = κx with κ ≥ 0
    /// (the gradient points into the disc along the normal).
    #[test]
    fn disc_qp_meets_its_optimality_conditions() {
        let a = [[2.0, 0.5], [0.5, 1.0]];
        let b = [3.0, -4.0];
        let x = disc_qp(a, b, 0.5);
        assert!((x[0].hypot(x[1]) - 0.5).abs() < 1e-14);
        let g = [a[0][0] * x[0] + a[0][1] * x[1] + b[0], a[1][0] * x[0] + a[1][1] * x[1] + b[1]];
        // −g parallel to x, pointing outwards (κ > 0): the cross product vanishes
        let cross = g[0] * x[1] - g[1] * x[0];
        assert!(cross.abs() < 1e-12 * g[0].hypot(g[1]), "{cross}");
        assert!(-(g[0] * x[0] + g[1] * x[1]) > 0.0);
        // inside: the unconstrained minimiser
        let y = disc_qp(a, [0.1, 0.1], 10.0);
        assert!((a[0][0] * y[0] + a[0][1] * y[1] + 0.1).abs() < 1e-15);
    }
}
