//! The active-set systems of Newton on a distributed problem (theory §4.2, §12.2): the same
//! linearised problem as [`crate::active_set`], solved by the distributed solver the operators
//! bring ([`saddle_core::linalg::DistributedSpd`]: PETSc's CG with GAMG by default).
//!
//! Each rank holds its owned dofs and the rows of its owned nodes. The system is solved in the
//! coordinates y of [`RowBasis`] (theory §8.1, x = T y), in which each row acts on one
//! coordinate of its own; for rows on one dof each (the punches, the tilting punch) T = I and
//! nothing is transformed. The tangent `TᵀKT` is assembled from every rank's elements, each
//! rank's values re-weighted with T at its local dofs — its owned blocks and its ghost nodes'
//! ([`crate::distributed_basis`]) — with the active rows' coordinates fixed (identity rows and
//! columns), the multigrid's near-null space the rigid-body modes in the same coordinates; the prescribed values δ of the fixed coordinates enter the right-hand sides through
//! `TᵀKT δ`, and the contact forces are the reactions `(Tᵀ∇E + TᵀKT dy)_s` — both products of
//! the *unfixed* tangent, computed from the operators, `TᵀKT y = Tᵀ Bᵀ(C_t B T y)` with T
//! applied at the owned dofs, so that no second matrix is stored. The extras' small system is
//! reduced over the ranks and solved the same on every one; `du = T dy`.

use crate::active_set::{CG_TOL_MIN, Step, step_from_reactions};
use crate::distributed_basis::ghost_blocks;
use crate::row_basis::RowBasis;
use nalgebra::DMatrix;
use saddle_core::linalg::DistributedSpd;
use saddle_core::{Lagrangian, Material, SolveError, Sym};

/// Newton's linearised systems on a distributed problem (module docs).
pub struct DistributedSystem {
    spd: Box<dyn DistributedSpd>,
    /// The rows' coordinates at the owned dofs (the vectors').
    basis: RowBasis,
    /// The coordinates at the local dofs, the ghost nodes' blocks too (the stiffness'); `None`
    /// when T = I on every rank.
    local: Option<Box<RowBasis>>,
    /// The largest cond(T) over the ranks (theory §8.1).
    condition: f64,
    solver: String,
    /// Tangent assemblies so far.
    pub assemblies: usize,
    /// The tangent's values are the same at every step (a metric, theory §4.1): the matrix is
    /// assembled again only when the fixed coordinates change on some rank.
    pub constant_tangent: bool,
    /// The fixed coordinates of the last assembly.
    assembled: Option<Vec<usize>>,
    /// Krylov solves so far.
    pub solves: usize,
    /// Krylov iterations so far.
    pub iterations: usize,
    /// Solves that stopped before their tolerance.
    pub unconverged: usize,
    /// ε = B T y, then C_t ε in its place (one field per point).
    eps: Vec<Sym>,
    /// `TᵀKT` on the local pattern (empty when T = I everywhere).
    kt: Vec<f64>,
    /// Tᵀ∇E, T y and K T y at the owned dofs.
    grad_t: Vec<f64>,
    ty: Vec<f64>,
    kty: Vec<f64>,
}

/// `result` of every rank, agreed: an error on any rank is an error on every one (the others'
/// naming no rows of theirs), so that every rank takes the same path (theory §12.1).
fn agreed<T>(l: &Lagrangian<'_>, solver: &str, result: Result<T, SolveError>) -> Result<T, SolveError> {
    match (l.comm().any(result.is_err()), result) {
        (false, r) | (true, r @ Err(_)) => r,
        (true, Ok(_)) => Err(SolveError::Unsupported {
            solver: solver.into(),
            message: "another rank's contact rows cannot be given coordinates of their own (its error says why)".into(),
        }),
    }
}

impl DistributedSystem {
    /// The system of `l`, whose operators are distributed, for `solver` (errors name it).
    /// Collective.
    pub fn new(l: &Lagrangian<'_>, solver: &str) -> Result<Self, SolveError> {
        let comm = l.comm();
        let mut spd = l
            .distributed_solver()
            .expect("a distributed L")
            .map_err(|e| SolveError::LinearAlgebra { solver: solver.into(), source: e })?;
        let p = l.pattern();
        let basis = agreed(l, solver, RowBasis::new(l.data.rows, p.n(), p, solver))?;
        let local = if comm.any(!basis.is_identity()) {
            let unsupported = |message: String| SolveError::Unsupported { solver: solver.into(), message };
            let local = ghost_blocks(&basis, spd.as_mut(), comm, l.n_dofs(), p.n())
                .map_err(|e| e.to_string())
                .and_then(|more| basis.with_blocks(more, p))
                // node blocks keep K's pattern (theory §8.1): the distributed matrix's
                .and_then(|local| match local.pattern(p) == p {
                    true => Ok(local),
                    false => Err("contact rows whose change of basis widens the stiffness' pattern (rows coupling \
                                  several nodes) need one process"
                        .into()),
                })
                .map_err(unsupported);
            let local = agreed(l, solver, local)?;
            // the multigrid's near-null space in the same coordinates: y = T⁻¹ x of rigid motions
            spd.change_coordinates(&|x: &mut [f64]| basis.displacement_to_coordinates(x))
                .map_err(|e| error(solver, e))?;
            Some(Box::new(local))
        } else {
            None
        };
        let (n, np) = (l.n_dofs(), l.n_points());
        Ok(Self {
            spd,
            condition: comm.max(basis.condition()),
            kt: vec![0.0; if local.is_some() { p.nnz() } else { 0 }],
            basis,
            local,
            solver: solver.into(),
            assemblies: 0,
            constant_tangent: false,
            assembled: None,
            solves: 0,
            iterations: 0,
            unconverged: 0,
            eps: vec![Sym::zeros(); np],
            grad_t: vec![0.0; n],
            ty: vec![0.0; n],
            kty: vec![0.0; n],
        })
    }

    /// The rows' coordinates at the owned dofs (theory §8.1).
    pub fn basis(&self) -> &RowBasis {
        &self.basis
    }

    /// This rank's values of `TᵀKT` on its local pattern from those of K, `k`, into `kt`
    /// (`k` itself when T = I everywhere).
    fn transformed<'s>(local: &Option<Box<RowBasis>>, k: &'s [f64], kt: &'s mut [f64]) -> &'s [f64] {
        match local {
            None => k,
            Some(local) => {
                local.stiffness(k, kt);
                kt
            }
        }
    }

    /// c_i of the active-set test: the elastic stiffness in row i's coordinate, (TᵀKT)_ss / a_i²,
    /// from the matrix `k_elastic` (this rank's values) summed over the ranks.
    pub fn row_stiffness(&mut self, l: &Lagrangian<'_>, k_elastic: &[f64]) -> Result<Vec<f64>, SolveError> {
        let mut diag = vec![0.0; l.n_dofs()];
        let values = Self::transformed(&self.local, k_elastic, &mut self.kt);
        self.spd.diagonal(l.pattern().col_ptr(), values, &mut diag).map_err(|e| error(&self.solver, e))?;
        Ok(self.basis.dof.iter().zip(&self.basis.coef).map(|(&s, a)| diag[s] / (a * a)).collect())
    }

    /// `out` = TᵀKT y with the unfixed tangent `material` from the operators: Tᵀ Bᵀ(C B T y),
    /// T at the owned dofs.
    pub fn tangent_times(&mut self, l: &Lagrangian<'_>, material: Material<'_>, y: &[f64], out: &mut [f64]) {
        self.ty.copy_from_slice(y);
        self.basis.displacement_from_coordinates(&mut self.ty);
        // ε, then σ = C_t ε in its place
        l.strain(&self.ty, &mut self.eps);
        for (i, e) in self.eps.iter_mut().enumerate() {
            *e = material.at(i) * *e;
        }
        l.divergence(&self.eps, &mut self.kty);
        self.basis.force_to_coordinates(&self.kty, out);
    }

    /// `cols` (`nc` columns over the owned coordinates) ← (TᵀKT + D)⁻¹ `cols`, K with values `k`
    /// on this rank's pattern and D diagonal, `diagonal` its (owned coordinate, value) pairs;
    /// each Krylov solve to the relative residual `rtol`. Returns max/min of the diagonal of
    /// TᵀKT + D over the ranks, a lower bound of its condition number (theory §4.3, §12.4).
    pub fn solve_columns(
        &mut self,
        l: &Lagrangian<'_>,
        k: &[f64],
        diagonal: &[(usize, f64)],
        cols: &mut [f64],
        nc: usize,
        rtol: f64,
    ) -> Result<f64, SolveError> {
        let mut values = Self::transformed(&self.local, k, &mut self.kt).to_vec();
        let cp = l.pattern().col_ptr();
        for &(s, d) in diagonal {
            values[cp[s]] += d;
        }
        let n = l.n_dofs();
        let mut diag = vec![0.0; n];
        self.spd.diagonal(cp, &values, &mut diag).map_err(|e| error(&self.solver, e))?;
        let (lo, hi) = diag.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &x| (lo.min(x), hi.max(x)));
        let comm = l.comm();
        let condition = comm.max(hi) / comm.min(lo);
        self.spd.assemble(cp, l.pattern().row_idx(), &values, &[]).map_err(|e| error(&self.solver, e))?;
        self.assemblies += 1;
        self.assembled = None;
        let mut x = vec![0.0; n];
        for c in 0..nc {
            let col = &mut cols[c * n..(c + 1) * n];
            x.iter_mut().for_each(|v| *v = 0.0);
            let report = self.spd.solve(col, &mut x, rtol).map_err(|e| error(&self.solver, e))?;
            self.iterations += report.iterations;
            self.unconverged += !report.converged as usize;
            self.solves += 1;
            col.copy_from_slice(&x);
        }
        Ok(condition)
    }

    /// The step for active set `active` with tangent `material` (its values `k` on this rank's
    /// pattern), ∇E(u) `grad` and gaps `gap`, each Krylov solve to the relative residual
    /// `rtol` divided by cond(T) (theory §8.1; module docs; the same step as
    /// [`crate::active_set::ActiveSetSystem::step`]).
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
        // collective: assembled on every rank or on none
        if !self.constant_tangent || l.comm().any(self.assembled.as_ref() != Some(&fixed)) {
            let values = Self::transformed(&self.local, k, &mut self.kt);
            let p = l.pattern();
            self.spd.assemble(p.col_ptr(), p.row_idx(), values, &fixed).map_err(|e| error(&self.solver, e))?;
            self.assemblies += 1;
            self.assembled = Some(fixed.clone());
        }
        self.basis.force_to_coordinates(grad, &mut self.grad_t);
        // the reactions come through T⁻ᵀ, which amplifies the residual by up to cond(T)
        let rtol = (rtol / self.condition).max(CG_TOL_MIN.min(rtol));
        // the prescribed values δ at the fixed coordinates: column 0 for the gaps, 1 + k for dV_k
        let nc = 1 + ne;
        let mut delta = vec![0.0; n * nc];
        for i in (0..nr).filter(|&i| active[i]) {
            let (s, a) = (self.basis.dof[i], self.basis.coef[i]);
            delta[s] = -gap[i] / a;
            for (kx, h) in rows.extra_row(i).iter().enumerate() {
                delta[(1 + kx) * n + s] = -h / a;
            }
        }
        // right-hand sides −Tᵀ∇E − TᵀKT δ (column 0), −TᵀKT δ (the others), δ at the fixed
        // coordinates (the identity rows); then the solves
        let mut x = vec![0.0; n * nc];
        let mut b = vec![0.0; n];
        for c in 0..nc {
            let dcol = &delta[c * n..(c + 1) * n];
            self.tangent_times(l, material, dcol, &mut b);
            b.iter_mut().for_each(|v| *v = -*v);
            if c == 0 {
                b.iter_mut().zip(&self.grad_t).for_each(|(v, g)| *v -= g);
            }
            for &s in &fixed {
                b[s] = dcol[s];
            }
            let xcol = &mut x[c * n..(c + 1) * n];
            xcol.copy_from_slice(dcol);
            let report = self.spd.solve(&b, xcol, rtol).map_err(|e| error(&self.solver, e))?;
            self.iterations += report.iterations;
            self.unconverged += !report.converged as usize;
            self.solves += 1;
        }
        // the reactions at the fixed coordinates: λ = (Tᵀ∇E + TᵀKT dy)_s / a, affine in dV
        let mut ky = vec![0.0; n];
        let mut lam0 = vec![0.0; nr];
        let mut lam_v = DMatrix::zeros(nr, ne);
        for c in 0..nc {
            self.tangent_times(l, material, &x[c * n..(c + 1) * n], &mut ky);
            for i in (0..nr).filter(|&i| active[i]) {
                let (s, a) = (self.basis.dof[i], self.basis.coef[i]);
                if c == 0 {
                    lam0[i] = (self.grad_t[s] + ky[s]) / a;
                } else {
                    lam_v[(i, c - 1)] = ky[s] / a;
                }
            }
        }
        let mut step = step_from_reactions(l, active, &x, &lam0, &lam_v, &self.solver)?;
        self.basis.displacement_from_coordinates(&mut step.du);
        Ok(step)
    }
}

/// A failure of the distributed solver inside `solver`.
fn error(solver: &str, e: saddle_core::linalg::DistributedError) -> SolveError {
    SolveError::LinearAlgebra { solver: solver.into(), source: e }
}
