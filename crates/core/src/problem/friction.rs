//! Friction laws (theory §8.3): a variational inequality of the second kind on the tangential
//! rows of an obstacle.
//!
//! An obstacle with friction gives each contact node i, besides its normal row g_i ≥ 0, two
//! tangential rows s_i = G_t u + H_t V + c_t ∈ R² (the slip of the node against the obstacle
//! in the obstacle's tangent plane). Their multipliers λ_t,i (the tangential contact forces)
//! do not lie in R₊ but in the law's **dual set** D_i, a disc
//!
//! ```text
//! D_i = { λ_t ∈ R² : |λ_t| ≤ r_i },     r_i = radius(w_i, λ_n,i),
//! ```
//!
//! w_i the node's share of the contact face (its weight) and λ_n,i its normal multiplier:
//! Tresca `r_i = g w_i` (a given bound: convex, a VI of the second kind), Coulomb
//! `r_i = μ λ_n,i` (a quasi-variational inequality). The friction conditions are
//! `λ_t,i ∈ D_i` and `−s_i ∈ N_{D_i}(λ_t,i)` — stick (s_i = 0) inside the disc, slip opposite
//! to the force on its rim — in one natural residual `λ_t,i = P_{D_i}(λ_t,i − κ s_i)`, κ > 0.
//!
//! A law provides its dual set (the radius), the projection onto it and its generalised
//! derivative ([`FrictionLaw`]); the rows say which rows are tangential ([`FrictionRows`]).
//! A frictionless obstacle has no tangential row and an empty [`FrictionRows`].

use crate::error::ParameterError;
use std::fmt::Debug;

/// A friction law (theory §8.3), chosen by `type` in the `friction` table of an obstacle.
#[typetag::serde(tag = "type")]
pub trait FrictionLaw: Debug + Send + Sync + dyn_clone::DynClone {
    /// The `type` name of the law in scene files.
    fn name(&self) -> &'static str {
        self.typetag_name()
    }

    /// Checks the parameters; `path` is the table's path in the scene (`obstacle.friction`).
    fn validate(&self, path: &str) -> Result<(), ParameterError>;

    /// The radius r(w, λ_n) of the dual set D at a node of weight `weight` (its share of the
    /// contact face) and normal multiplier `lambda_n`.
    fn radius(&self, weight: f64, lambda_n: f64) -> f64;

    /// ∂r/∂λ_n: 0 for a given bound (Tresca), μ for Coulomb. A law with a nonzero slope is a
    /// quasi-variational inequality: the solvers run it as a fixed point of given bounds.
    fn radius_slope(&self, weight: f64) -> f64;

    /// The projection P_D(t) onto the dual set at a node (a disc: [`project_disc`]).
    fn project(&self, weight: f64, lambda_n: f64, t: [f64; 2]) -> [f64; 2] {
        project_disc(self.radius(weight, lambda_n), t)
    }

    /// A generalised derivative of [`FrictionLaw::project`]: (∂P/∂t, ∂P/∂λ_n).
    fn project_derivative(&self, weight: f64, lambda_n: f64, t: [f64; 2]) -> ([[f64; 2]; 2], [f64; 2]) {
        let r = self.radius(weight, lambda_n);
        let (dt, dr) = project_disc_derivative(r, t);
        let slope = if r > 0.0 { self.radius_slope(weight) } else { 0.0 };
        (dt, [dr[0] * slope, dr[1] * slope])
    }
}

dyn_clone::clone_trait_object!(FrictionLaw);

/// The projection of t onto the disc |x| ≤ r (r ≥ 0; r < 0 is the empty disc's nearest point 0).
pub fn project_disc(r: f64, t: [f64; 2]) -> [f64; 2] {
    let n = t[0].hypot(t[1]);
    if n <= r {
        t
    } else if r <= 0.0 {
        [0.0, 0.0]
    } else {
        [t[0] * r / n, t[1] * r / n]
    }
}

/// A generalised derivative of [`project_disc`] at t: (∂P/∂t, ∂P/∂r). Inside the disc (I, 0);
/// outside `(r/|t|)(I − t̂t̂ᵀ)` and t̂ (t̂ = t/|t|); on the rim the inside branch.
pub fn project_disc_derivative(r: f64, t: [f64; 2]) -> ([[f64; 2]; 2], [f64; 2]) {
    let n = t[0].hypot(t[1]);
    if n <= r {
        ([[1.0, 0.0], [0.0, 1.0]], [0.0, 0.0])
    } else if r <= 0.0 {
        ([[0.0; 2]; 2], if n > 0.0 { [t[0] / n, t[1] / n] } else { [1.0, 0.0] })
    } else {
        let e = [t[0] / n, t[1] / n];
        let s = r / n;
        ([[s * (1.0 - e[0] * e[0]), -s * e[0] * e[1]], [-s * e[0] * e[1], s * (1.0 - e[1] * e[1])]], e)
    }
}

/// One node's friction: its normal row, its two tangential rows `tangent`, `tangent + 1`, its
/// weight (share of the contact face) and its law among [`FrictionRows::laws`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrictionBlock {
    /// The law's index in [`FrictionRows::laws`].
    pub law: usize,
    /// The node's normal row.
    pub normal: usize,
    /// The first of its two tangential rows (the second is `tangent + 1`).
    pub tangent: usize,
    /// Its share w_i of the contact face.
    pub weight: f64,
}

/// Which rows of a [`crate::ConstraintRows`] are tangential, node by node, and their laws.
/// Empty for frictionless rows (every row then a normal row g_i ≥ 0 with λ_i ≥ 0).
#[derive(Clone, Debug, Default)]
pub struct FrictionRows {
    /// The laws (one per obstacle with friction).
    pub laws: Vec<Box<dyn FrictionLaw>>,
    /// One block per node with friction.
    pub blocks: Vec<FrictionBlock>,
}

impl PartialEq for FrictionRows {
    /// The same blocks and laws of the same parameters (a law is a plain parameter struct: its
    /// `Debug` form is its value).
    fn eq(&self, other: &Self) -> bool {
        self.blocks == other.blocks
            && self.laws.len() == other.laws.len()
            && self.laws.iter().zip(&other.laws).all(|(a, b)| format!("{a:?}") == format!("{b:?}"))
    }
}

impl FrictionRows {
    /// No friction.
    pub fn is_empty(&self) -> bool {
        self.blocks.is_empty()
    }

    /// The law of `block`.
    pub fn law(&self, block: &FrictionBlock) -> &dyn FrictionLaw {
        self.laws[block.law].as_ref()
    }

    /// For each of `n_rows` rows, true when it is tangential.
    pub fn tangential_mask(&self, n_rows: usize) -> Vec<bool> {
        let mut mask = vec![false; n_rows];
        for b in &self.blocks {
            mask[b.tangent] = true;
            mask[b.tangent + 1] = true;
        }
        mask
    }

    /// The largest [`FrictionLaw::radius_slope`] of a block's law (0: every law a given bound,
    /// a convex problem).
    pub fn max_radius_slope(&self) -> f64 {
        self.blocks.iter().map(|b| self.law(b).radius_slope(b.weight).abs()).fold(0.0, f64::max)
    }

    /// The first law whose radius depends on λ_n (a quasi-VI), if any.
    pub fn quasi_law(&self) -> Option<&'static str> {
        self.blocks.iter().find(|b| self.law(b).radius_slope(b.weight) != 0.0).map(|b| self.law(b).name())
    }

    /// Appends `other`'s laws and blocks, its rows counted from `row_offset`.
    pub fn extend_shifted(&mut self, other: &FrictionRows, row_offset: usize) {
        let law0 = self.laws.len();
        self.laws.extend(other.laws.iter().cloned());
        self.blocks.extend(other.blocks.iter().map(|b| FrictionBlock {
            law: b.law + law0,
            normal: b.normal + row_offset,
            tangent: b.tangent + row_offset,
            weight: b.weight,
        }));
    }

    /// The blocks whose rows `new_row` maps all to `Some` new row, renumbered; the laws kept.
    pub fn renumbered(&self, new_row: impl Fn(usize) -> Option<usize>) -> Self {
        let blocks = self
            .blocks
            .iter()
            .filter_map(|b| {
                let (n, t, t1) = (new_row(b.normal)?, new_row(b.tangent)?, new_row(b.tangent + 1)?);
                debug_assert_eq!(t1, t + 1);
                Some(FrictionBlock { normal: n, tangent: t, ..*b })
            })
            .collect();
        Self { laws: self.laws.clone(), blocks }
    }
}

/// Relative size (of |λ_t| against the disc's radius) above which a contact node slips.
pub const SLIP_TOL: f64 = 1e-6;

/// The status of a node with friction (theory §8.3): out of contact, sticking (|λ_t| below the
/// disc's radius by more than [`SLIP_TOL`] of it) or slipping (on the rim).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactStatus {
    /// Not in contact (its normal row not in the normal contact set): 0.
    Separated = 0,
    /// In contact, |λ_t| inside the disc: 1.
    Stick = 1,
    /// In contact, |λ_t| on the disc's rim: 2.
    Slip = 2,
}

/// The friction part of the natural residual of an iterate (theory §8.3): for each block
/// `|a − P_{D/λ_s}(a − b)|` with a = λ_t/λ_s, b = s/g_s (s the tangential rows' values in `gap`,
/// λ_s and g_s the scales of the normal residual); it vanishes exactly when every λ_t ∈ D_i and
/// −s_i ∈ N_{D_i}(λ_t,i). NaN propagates.
pub fn friction_residual(friction: &FrictionRows, lambda: &[f64], gap: &[f64], lambda_s: f64, g_s: f64) -> f64 {
    let ls = if lambda_s > 0.0 { lambda_s } else { 1.0 };
    let gs = if g_s > 0.0 { g_s } else { 1.0 };
    let mut worst: f64 = 0.0;
    for b in &friction.blocks {
        let law = friction.law(b);
        let (t, n) = (b.tangent, b.normal);
        let a = [lambda[t] / ls, lambda[t + 1] / ls];
        let trial = [a[0] - gap[t] / gs, a[1] - gap[t + 1] / gs];
        let p = project_disc(law.radius(b.weight, lambda[n]) / ls, trial);
        let r = (a[0] - p[0]).hypot(a[1] - p[1]);
        worst = if r.is_nan() || worst.is_nan() { f64::NAN } else { worst.max(r) };
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The disc projection against its closed form: inside unchanged, outside scaled onto the rim.
    #[test]
    fn disc_projection_is_the_closest_point() {
        assert_eq!(project_disc(2.0, [1.0, 1.0]), [1.0, 1.0]);
        let p = project_disc(1.0, [3.0, 4.0]);
        assert!((p[0] - 0.6).abs() < 1e-15 && (p[1] - 0.8).abs() < 1e-15);
        assert_eq!(project_disc(0.0, [3.0, 4.0]), [0.0, 0.0]);
    }

    /// The derivative against central differences of the projection, outside the disc.
    #[test]
    fn disc_derivative_matches_finite_differences() {
        let (r, t) = (0.7, [0.9, -1.3]);
        let (dt, dr) = project_disc_derivative(r, t);
        let h = 1e-6;
        for k in 0..2 {
            let mut tp = t;
            let mut tm = t;
            tp[k] += h;
            tm[k] -= h;
            let (p, m) = (project_disc(r, tp), project_disc(r, tm));
            for i in 0..2 {
                // central differences of a smooth map: O(h²) ≈ 1e-12, round-off 1e-10
                assert!(((p[i] - m[i]) / (2.0 * h) - dt[i][k]).abs() < 1e-8);
            }
        }
        let (p, m) = (project_disc(r + h, t), project_disc(r - h, t));
        for i in 0..2 {
            assert!(((p[i] - m[i]) / (2.0 * h) - dr[i]).abs() < 1e-8);
        }
    }
}
