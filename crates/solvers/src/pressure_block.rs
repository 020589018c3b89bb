//! The pressure block (theory §10.1, "The pressure block"): for an element whose volumetric
//! strain is one value per element (B̄, [`PressureRows`]), the tangent splits as
//! K = A + Bᵀ C⁻¹ B, and K x = b is the symmetric indefinite system
//!
//! ```text
//! [ A   Bᵀ ] [ x ]   [ b ]
//! [ B  −C  ] [ p ] = [ 0 ]
//! ```
//!
//! (p = C⁻¹ B x, the element pressures), solved by MINRES preconditioned with
//! diag(AMG(A), S̃), S̃ = diag(|T| (1/(2μ_T) + 1/λ_T)) (Silvester & Wathen 1994; Klawonn 1998:
//! iteration counts bounded independently of λ/μ for an inf-sup-stable pair, and P2–P0 is one).
//! The split takes λ = κ − 2μ/3 into the pressure, so that A is, for an elastic point,
//! λ = 0 elasticity 2μ ε̄:ε̄: compressible, its near-null space the rigid-body modes, which the
//! multigrid represents at any ν where it cannot represent K's soft, nearly divergence-free
//! modes as ν → ½. (Taking all of κ would leave the deviatoric 2μ|dev ε̄|², whose kernel on a
//! free body also holds the dilation and the other conformal motions, not in the multigrid's
//! coarse space.)
//!
//! The split is read from the tangents ([`moduli`]): at each point κ_q = I:C_q:I / 9 where
//! C_q I ∥ I (the volumetric response uncoupled, as in elasticity and isochoric plasticity),
//! otherwise the largest κ with C_q − κ I ⊗ I positive semidefinite, 1 / (I:C_q⁻¹:I); μ_q from
//! the trace of the rest; λ_T the points' mean of κ_q − 2μ_q/3, so C_q − λ_q I ⊗ I =
//! (C_q − κ_q I ⊗ I) + (2μ_q/3) I ⊗ I stays positive semidefinite. Any C > 0 gives the same x:
//! A is never formed for the operator, which is applied as A x = K x − Bᵀ C⁻¹ B x from the
//! system matrix itself, so the answer is that of K x = b whatever the split; the split only
//! decides how well the preconditioner fits.
//!
//! Newton's system is in the rows' coordinates y = T⁻¹u with the active coordinates fixed
//! (identity rows and columns, [`crate::active_set`]): the pressure rows act on them as
//! B̃ = B T P, P zeroing the fixed coordinates, so the fixed coordinates stay decoupled.

use crate::fixed_dofs::FixedDofs;
use crate::linear::lower;
use crate::row_basis::RowBasis;
use saddle_core::linalg::pcg::dot;
use saddle_core::linalg::{Csr, Minres, MinresReport, PcgError, Preconditioner, Residual, SymmetricOperator};
use saddle_core::problem::operators::PressureRows;
use saddle_core::problem::tensor::identity;
use saddle_core::{Material, SymOp, SymmetricPattern};
use serde::{Deserialize, Serialize};
use std::sync::Mutex;

/// Newton's `pressure_block_residual`: where the pressure block's MINRES stops.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BlockResidual {
    /// MINRES's own: ‖r‖_{𝓜⁻¹} of the saddle system at the tolerance times that of the start
    /// (the default; Newton's KKT residual judges the answer either way).
    #[default]
    Saddle,
    /// CG's: ‖b − K x‖ at the tolerance times ‖b‖, the displacement system's residual, in which
    /// the pressure equation's residual r_p counts as Bᵀ C⁻¹ r_p, λ/|T| times.
    Displacement,
}

/// When Newton's multigrid takes the pressure block and where its solves stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockRule {
    /// κ/(2μ) of the elastic material above which the block is used (`pressure_block_ratio`).
    pub ratio: f64,
    /// The stopping test (`pressure_block_residual`).
    pub residual: BlockResidual,
}

/// The volumetric and shear moduli (κ, μ) of a tangent C (module docs): κ from C I ∥ I or
/// 1 / (I:C⁻¹:I) (0 when C is singular there), μ = (tr C − 3κ) / 10 (the trace of 2μ I_dev is
/// 10μ in Mandel notation).
pub fn moduli(c: &SymOp) -> (f64, f64) {
    let i = identity();
    let ci = c * i;
    let k = i.dot(&ci) / 9.0;
    let kappa = if (ci - 3.0 * k * i).norm() <= 1e-10 * ci.norm() {
        k
    } else {
        c.cholesky().map_or(0.0, |ch| 1.0 / i.dot(&ch.solve(&i)))
    };
    (kappa, ((c.trace() - 3.0 * kappa) / 10.0).max(0.0))
}

/// κ/(2μ) of the material `c` ([`moduli`]): how nearly incompressible it is; the rule of
/// Newton's `pressure_block_ratio` compares it.
pub fn incompressibility(c: &SymOp) -> f64 {
    let (kappa, mu) = moduli(c);
    kappa / (2.0 * mu)
}

/// The pressure rows with their split and the multigrid of A (module docs).
pub struct PressureBlock {
    /// B (elements × free dofs) and Bᵀ.
    b: Csr,
    bt: Csr,
    volume: Vec<f64>,
    points: usize,
    /// C_T = |T| / λ_T and S̃_T = |T| (1/(2μ_T) + 1/λ_T).
    c: Vec<f64>,
    s_inv: Vec<f64>,
    /// A floor for λ_T and μ_T: a millionth of the elastic κ (a tangent singular in its
    /// volumetric direction still gets a positive C, which any value keeps exact).
    floor: f64,
    minres: Minres,
    /// The block right-hand side and iterate, and the scratch of the operator.
    rhs: Vec<f64>,
    z: Vec<f64>,
    scratch: Mutex<(Vec<f64>, Vec<f64>, Vec<f64>)>,
    kres: Vec<f64>,
    /// Where MINRES stops.
    stop: BlockResidual,
}

impl std::fmt::Debug for PressureBlock {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "PressureBlock({} rows)", self.volume.len())
    }
}

impl PressureBlock {
    /// The block of `rows` on `n` free dofs with the split of the uniform material `c`, its
    /// solves stopping at `stop`.
    pub fn new(rows: PressureRows, n: usize, c: &SymOp, stop: BlockResidual) -> Self {
        let m = rows.n_rows();
        let b = Csr { nrows: m, ncols: n, ptr: rows.ptr, idx: rows.dof, val: rows.val };
        let bt = b.transpose();
        let (kappa, _) = moduli(c);
        let mut block = Self {
            b,
            bt,
            volume: rows.volume,
            points: rows.points,
            c: vec![0.0; m],
            s_inv: vec![0.0; m],
            floor: 1e-6 * kappa,
            minres: Minres::new(n + m),
            rhs: vec![0.0; n + m],
            z: vec![0.0; n + m],
            scratch: Mutex::new((vec![0.0; n], vec![0.0; m], vec![0.0; n])),
            kres: vec![0.0; n],
            stop,
        };
        block.follow(Material::Uniform(c));
        block
    }

    /// The split of the tangents `material` (module docs): C_T and S̃_T from the points' κ and μ.
    pub fn follow(&mut self, material: Material<'_>) {
        let per_point = matches!(material, Material::PerPoint(_));
        let uniform = if per_point { None } else { Some(moduli(material.at(0))) };
        for e in 0..self.volume.len() {
            let (mut lambda, mut mu) = (0.0, 0.0);
            for q in self.points * e..self.points * (e + 1) {
                let (k, m) = uniform.unwrap_or_else(|| moduli(material.at(q)));
                lambda += (k - 2.0 * m / 3.0) / self.points as f64;
                mu += m / self.points as f64;
            }
            let lambda = lambda.max(self.floor);
            let mu = mu.max(self.floor);
            self.c[e] = self.volume[e] / lambda;
            self.s_inv[e] = 1.0 / (self.volume[e] * (0.5 / mu + 1.0 / lambda));
        }
    }

    /// `values` (K's lower triangle on L's `pattern`, the dofs' own coordinates) minus Bᵀ C⁻¹ B:
    /// the part A of the split (module docs), on which the multigrid is built.
    fn subtract_volumetric(&self, pattern: &SymmetricPattern, values: &mut [f64]) {
        let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
        for e in 0..self.b.nrows {
            let r = self.b.ptr[e]..self.b.ptr[e + 1];
            let (idx, val) = (&self.b.idx[r.clone()], &self.b.val[r]);
            let c_inv = 1.0 / self.c[e];
            for (&i, &vi) in idx.iter().zip(val) {
                for (&j, &vj) in idx.iter().zip(val) {
                    let (i, j) = (i as usize, j as usize);
                    if i < j {
                        continue;
                    }
                    let at = ri[cp[j]..cp[j + 1]].binary_search(&i).expect("B's rows couple dofs of one element");
                    values[cp[j] + at] -= c_inv * vi * vj;
                }
            }
        }
    }

    /// The part A of the split of the tangent `k` (values on L's `pattern`) as a full matrix.
    pub fn split_part(&self, pattern: &SymmetricPattern, k: &[f64]) -> Csr {
        let mut a = k.to_vec();
        self.subtract_volumetric(pattern, &mut a);
        Csr::from_symmetric_lower(lower(pattern), &a)
    }

    /// Solves `a` x = `b` (the system matrix in the rows' coordinates of `basis`, the `fixed`
    /// coordinates decoupled) through the saddle system of the module docs, from the initial
    /// guess in `x`, to the relative residual `tol` ([`BlockResidual`]) or `max_iter` MINRES
    /// iterations; `top` is the preconditioner of the displacement block.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn solve(
        &mut self,
        a: &Csr,
        basis: &RowBasis,
        fixed: &[(usize, f64)],
        top: &FixedDofs<'_>,
        b: &[f64],
        x: &mut [f64],
        tol: f64,
        max_iter: usize,
    ) -> Result<MinresReport, PcgError> {
        let n = a.nrows;
        let norm_b = dot(b, b).sqrt();
        if norm_b == 0.0 {
            x.iter_mut().for_each(|v| *v = 0.0);
            return Ok(MinresReport { iterations: 0, relative_residual: 0.0, converged: true });
        }
        let Self { b: rows, bt, c, s_inv, minres, rhs, z, scratch, kres, stop, .. } = self;
        let op = Saddle { a, basis, fixed, b: rows, bt, c, scratch };
        rhs[..n].copy_from_slice(b);
        rhs[n..].iter_mut().for_each(|v| *v = 0.0);
        // the consistent pressure of the initial guess, p = C⁻¹ B̃ x
        z[..n].copy_from_slice(x);
        {
            let (t, q, _) = &mut *op.scratch.lock().unwrap_or_else(|e| e.into_inner());
            op.pressure_rows(x, t, q);
            for ((p, q), c) in z[n..].iter_mut().zip(q.iter()).zip(c.iter()) {
                *p = q / c;
            }
        }
        let pre = Diagonal { top, s_inv, n };
        let mut res = Displacement { a, b, tmp: kres, norm_b };
        let residual: Option<&mut dyn Residual> = match stop {
            BlockResidual::Saddle => None,
            BlockResidual::Displacement => Some(&mut res),
        };
        let report = minres.solve(&op, &pre, rhs, z, residual, tol, max_iter)?;
        x.copy_from_slice(&z[..n]);
        Ok(report)
    }
}

/// The saddle operator [A B̃ᵀ; B̃ −C] with A y = a y − B̃ᵀ C⁻¹ B̃ y (module docs).
struct Saddle<'a> {
    a: &'a Csr,
    basis: &'a RowBasis,
    fixed: &'a [(usize, f64)],
    b: &'a Csr,
    bt: &'a Csr,
    c: &'a [f64],
    scratch: &'a Mutex<(Vec<f64>, Vec<f64>, Vec<f64>)>,
}

impl Saddle<'_> {
    /// q = B̃ y = B T P y (`t` scratch of the dofs).
    fn pressure_rows(&self, y: &[f64], t: &mut [f64], q: &mut [f64]) {
        t.copy_from_slice(y);
        for &(s, _) in self.fixed {
            t[s] = 0.0;
        }
        if !self.basis.is_identity() {
            self.basis.displacement_from_coordinates(t);
        }
        self.b.spmv(t, q);
    }
}

impl SymmetricOperator for Saddle<'_> {
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        let n = self.a.nrows;
        let (xu, xp) = x.split_at(n);
        let (yu, yp) = y.split_at_mut(n);
        let mut guard = self.scratch.lock().unwrap_or_else(|e| e.into_inner());
        let (t, q, f) = &mut *guard;
        self.pressure_rows(xu, t, q);
        // bottom: B̃ x − C p; top: a x + B̃ᵀ (p − C⁻¹ B̃ x)
        for (((yp, q), p), c) in yp.iter_mut().zip(q.iter_mut()).zip(xp).zip(self.c) {
            *yp = *q - c * p;
            *q = p - *q / c;
        }
        self.a.spmv(xu, yu);
        self.bt.spmv(q, t);
        if !self.basis.is_identity() {
            f.copy_from_slice(t);
            self.basis.force_to_coordinates(f, t);
        }
        for &(s, _) in self.fixed {
            t[s] = 0.0;
        }
        for (y, t) in yu.iter_mut().zip(t.iter()) {
            *y += t;
        }
    }
}

/// diag(M_A, S̃): the displacement block's multigrid (fixed coordinates split off) and the
/// pressures' diagonal.
struct Diagonal<'a> {
    top: &'a FixedDofs<'a>,
    s_inv: &'a [f64],
    n: usize,
}

impl Preconditioner for Diagonal<'_> {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let (ru, rp) = r.split_at(self.n);
        let (zu, zp) = z.split_at_mut(self.n);
        self.top.apply(ru, zu);
        for ((z, r), s) in zp.iter_mut().zip(rp).zip(self.s_inv) {
            *z = r * s;
        }
    }
}

/// The caller's residual: ‖b − a x‖ / ‖b‖ of the displacement part of the iterate.
struct Displacement<'a> {
    a: &'a Csr,
    b: &'a [f64],
    tmp: &'a mut [f64],
    norm_b: f64,
}

impl Residual for Displacement<'_> {
    fn relative(&mut self, z: &[f64]) -> f64 {
        self.a.residual(self.b, &z[..self.a.nrows], self.tmp);
        dot(self.tmp, self.tmp).sqrt() / self.norm_b
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use saddle_core::problem::elasticity::Elasticity;

    #[test]
    fn the_moduli_of_isotropic_elasticity_are_its_own() {
        // κ = E/(3(1 − 2ν)), μ = E/(2(1 + ν)): closed forms
        for nu in [0.0, 0.3, 0.49, 0.4999] {
            let el = Elasticity::new(200.0, nu).unwrap();
            let (kappa, mu) = moduli(&el.stiffness_matrix());
            let (k_exact, mu_exact) = (200.0 / (3.0 * (1.0 - 2.0 * nu)), 200.0 / (2.0 * (1.0 + nu)));
            assert!((kappa - k_exact).abs() <= 1e-9 * k_exact, "{nu}: {kappa} against {k_exact}");
            assert!((mu - mu_exact).abs() <= 1e-6 * mu_exact, "{nu}: {mu} against {mu_exact}");
        }
    }
}
