//! The active-set systems of Newton on a distributed problem (theory §4.2, §12): the same
//! linearised problem as [`crate::active_set`], solved by the distributed solver the operators
//! bring ([`saddle_core::linalg::DistributedSpd`]: PETSc's CG with GAMG by default).
//!
//! Each rank holds its owned dofs and the rows of its owned nodes. The tangent is assembled from
//! every rank's elements with the active rows' dofs fixed (identity rows and columns); the
//! prescribed values δ of the fixed dofs enter the right-hand sides through K δ, and the contact
//! forces are the reactions (∇E + K dy)_s — both products of the *unfixed* tangent, computed
//! from the operators, K x = Bᵀ(C_t B x), so that no second matrix is stored. The extras' small
//! system is reduced over the ranks and solved the same on every one. Rows must act on one dof
//! each (T = I in the notation of theory §8.1: the punches, the tilting punch); general rows
//! (a sphere's normals) are refused with a clear error.

use crate::active_set::{Step, step_from_reactions};
use crate::row_basis::RowBasis;
use nalgebra::DMatrix;
use saddle_core::linalg::DistributedSpd;
use saddle_core::{Lagrangian, Material, SolveError, Sym};

/// Newton's linearised systems on a distributed problem (module docs).
pub struct DistributedSystem {
    spd: Box<dyn DistributedSpd>,
    basis: RowBasis,
    solver: String,
    /// Tangent assemblies so far.
    pub assemblies: usize,
    /// Krylov solves so far.
    pub solves: usize,
    /// Krylov iterations so far.
    pub iterations: usize,
    /// Solves that stopped before their tolerance.
    pub unconverged: usize,
    eps: Vec<Sym>,
    sigma: Vec<Sym>,
}

impl DistributedSystem {
    /// The system of `l`, whose operators are distributed, for `solver` (errors name it).
    pub fn new(l: &Lagrangian<'_>, solver: &str) -> Result<Self, SolveError> {
        let spd = l
            .distributed_solver()
            .expect("a distributed L")
            .map_err(|e| SolveError::LinearAlgebra { solver: solver.into(), source: e })?;
        let basis = RowBasis::new(l.data.rows, l.pattern().n(), l.pattern(), solver)?;
        if !l.comm().any(!basis.is_identity()) {
            let np = l.n_points();
            return Ok(Self {
                spd,
                basis,
                solver: solver.into(),
                assemblies: 0,
                solves: 0,
                iterations: 0,
                unconverged: 0,
                eps: vec![Sym::zeros(); np],
                sigma: vec![Sym::zeros(); np],
            });
        }
        Err(SolveError::Unsupported {
            solver: solver.into(),
            message: "on several ranks, contact rows must act on one displacement component each (the punches, the \
                      tilting punch); rows along general normals (a rigid sphere) need one process"
                .into(),
        })
    }

    /// The rows' coordinates (the identity: every row on a dof of its own).
    pub fn basis(&self) -> &RowBasis {
        &self.basis
    }

    /// c_i of the active-set test: the elastic stiffness at row i's dof, K_ss / a_i², from the
    /// matrix `k_elastic` (this rank's values) summed over the ranks.
    pub fn row_stiffness(&mut self, l: &Lagrangian<'_>, k_elastic: &[f64]) -> Result<Vec<f64>, SolveError> {
        let mut diag = vec![0.0; l.n_dofs()];
        self.spd.diagonal(k_elastic, &mut diag).map_err(|e| self.error(e))?;
        Ok(self.basis.dof.iter().zip(&self.basis.coef).map(|(&s, a)| diag[s] / (a * a)).collect())
    }

    fn error(&self, e: saddle_core::linalg::DistributedError) -> SolveError {
        SolveError::LinearAlgebra { solver: self.solver.clone(), source: e }
    }

    /// y = K x with the unfixed tangent `material` from the operators: Bᵀ(C B x).
    fn tangent_times(&mut self, l: &Lagrangian<'_>, material: Material<'_>, x: &[f64], y: &mut [f64]) {
        l.strain(x, &mut self.eps);
        for (i, (s, e)) in self.sigma.iter_mut().zip(&self.eps).enumerate() {
            *s = material.at(i) * e;
        }
        l.divergence(&self.sigma, y);
    }

    /// The step for active set `active` with tangent `material` (its values `k` on this rank's
    /// pattern), ∇E(u) `grad` and gaps `gap`, each Krylov solve to the relative residual
    /// `rtol` (module docs; the same step as [`crate::active_set::ActiveSetSystem::step`]).
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &mut self,
        l: &Lagrangian<'_>,
        material: Material<'_>,
        k: &[f64],
        active: &[bool],
        grad: &[f64],
        gap: &[f64],
        rtol: f64,
    ) -> Result<Step, SolveError> {
        let rows = l.data.rows;
        let (n, ne, nr) = (l.n_dofs(), l.n_extras(), rows.n_rows());
        let fixed: Vec<usize> = (0..nr).filter(|&i| active[i]).map(|i| self.basis.dof[i]).collect();
        self.spd.assemble(k, &fixed).map_err(|e| self.error(e))?;
        self.assemblies += 1;
        // the prescribed values δ at the fixed dofs: column 0 for the gaps, 1 + k for dV_k
        let nc = 1 + ne;
        let mut delta = vec![0.0; n * nc];
        for i in (0..nr).filter(|&i| active[i]) {
            let (s, a) = (self.basis.dof[i], self.basis.coef[i]);
            delta[s] = -gap[i] / a;
            for (kx, h) in rows.extra_row(i).iter().enumerate() {
                delta[(1 + kx) * n + s] = -h / a;
            }
        }
        // right-hand sides −∇E − K δ (column 0), −K δ (the others), δ at the fixed dofs (the
        // identity rows); then the solves
        let mut x = vec![0.0; n * nc];
        let mut b = vec![0.0; n];
        for c in 0..nc {
            let dcol = &delta[c * n..(c + 1) * n];
            self.tangent_times(l, material, dcol, &mut b);
            for j in 0..n {
                b[j] = -b[j] - if c == 0 { grad[j] } else { 0.0 };
            }
            for &s in &fixed {
                b[s] = dcol[s];
            }
            let xcol = &mut x[c * n..(c + 1) * n];
            xcol.copy_from_slice(dcol);
            let report = self.spd.solve(&b, xcol, rtol).map_err(|e| self.error(e))?;
            self.iterations += report.iterations;
            self.unconverged += !report.converged as usize;
            self.solves += 1;
        }
        // the reactions at the fixed dofs: λ = (∇E + K dy)_s / a, affine in dV
        let mut kx = vec![0.0; n];
        let mut lam0 = vec![0.0; nr];
        let mut lam_v = DMatrix::zeros(nr, ne);
        for c in 0..nc {
            let xc = x[c * n..(c + 1) * n].to_vec();
            self.tangent_times(l, material, &xc, &mut kx);
            for i in (0..nr).filter(|&i| active[i]) {
                let (s, a) = (self.basis.dof[i], self.basis.coef[i]);
                if c == 0 {
                    lam0[i] = (grad[s] + kx[s]) / a;
                } else {
                    lam_v[(i, c - 1)] = kx[s] / a;
                }
            }
        }
        step_from_reactions(l, active, &x, &lam0, &lam_v, &self.solver)
    }
}
