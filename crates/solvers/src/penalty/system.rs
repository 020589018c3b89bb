//! The Newton system of J_μ (theory §4.3): the penalty scales, J_μ itself, and the step of the
//! contact model — an active-set loop of Newton steps on the fixed pattern of L, the extras
//! coupled through a Schur complement free of cancellation ([`PenaltySystem`]).

use super::friction::RegularisedFriction;
use super::update::EnteringRows;
use super::{MODEL_SWEEPS, non_finite};
use crate::active_set::CG_TOL_MIN;
use crate::distributed_system::DistributedSystem;
use crate::linear::{self, InSolver};
use crate::row_basis::RowBasis;
use nalgebra::{DMatrix, DVector};
use saddle_core::error::ParameterError;
use saddle_core::linalg::SparseCholesky;
use saddle_core::linalg::reduce::tree_sum;
use saddle_core::problem::energies::energy;
use saddle_core::problem::lagrangian::{Lagrangian, Workspace};
use saddle_core::problem::operators::Material;
use saddle_core::problem::solver::SolveError;
use saddle_core::{Sym, SymOp};

/// The penalty scales of J_μ and its Newton system.
///
/// For a set A of rows, with D_A = diag(k_i a_i²) at the slave dofs, z_s = −g_i/a_i and
/// `P_k[s] = H_ik/a_i` on A, the u-block is A = K' + D_A (K' = K_t + μK_el) and the coupling to
/// the extras is D_A P. Since `A⁻¹D_A x = x − A⁻¹K'x`, eliminating du needs
/// `[y⁰ Y] = A⁻¹[r + K'z, K'P]` (r = Bᵀ(σ + μCε), right-hand sides of moderate size), and then
///
/// ```text
/// S = μ diag(k_V) + Pᵀ D_A Y,   S dV = f − μ k_V V + Pᵀ D_A y⁰,   du = z − y⁰ − (P − Y) dV,
/// ```
///
/// free of the cancellation of `C − BᵀA⁻¹B` (two terms of size 1/μ whose difference is of size 1).
///
/// `condition_estimate` is max/min of the diagonal of the last factorised u-block: a lower
/// bound of its spectral condition number, which the penalty raises by ~1/μ.
pub struct PenaltySystem {
    /// μ.
    mu: f64,
    /// The rows' coordinates (theory §8): each row acts on one coordinate s_i, a_i = G_{i s_i}.
    slaves: RowBasis,
    /// k_i = (K_el)_{ss} / (μ a_i²).
    pub(super) k: Vec<f64>,
    /// k_V,k = E · |Ω|^{1/3} · mean_i H_ik² over the rows touching extra k.
    pub(super) k_v: Vec<f64>,
    /// The elastic stiffness C.
    pub(super) c_el: SymOp,
    /// The solver of K' + D_A.
    linear: Linear,
    /// K' = K_t + μK_el on L's pattern.
    pub(super) kprime: Vec<f64>,
    /// TᵀK'T in the rows' coordinates, and Tᵀr (empty when T = I).
    kprime_t: Vec<f64>,
    r_t: Vec<f64>,
    /// K' + D_A, factorised.
    hess: Vec<f64>,
    /// n × (1 + n_extras): [z, P_1, …].
    cols: Vec<f64>,
    /// n × (1 + n_extras): [r + K'z, K'P_1, …], then [y⁰, Y_1, …].
    kcols: Vec<f64>,
    /// The model's next active set.
    next: Vec<bool>,
    /// The friction pairs' regularised law (theory §8.3; empty without friction).
    pub(super) friction: RegularisedFriction,
    /// The generalised Hessian of each pair's φ_k at the iterate (zero for a pair in the
    /// model's active set: the cold iteration's bonded pairs).
    pair_hess: Vec<[[f64; 2]; 2]>,
    /// Symbolic analyses of L's pattern so far (one, in [`PenaltySystem::new`]).
    pub symbolic_analyses: usize,
    /// Numeric factorisations so far.
    pub factorisations: usize,
    /// The rows entering A solved on the last factor (`update.rs`), and their largest number
    /// for which that is cheaper than a factorisation.
    entering: EnteringRows,
    max_entering: usize,
    /// Newton steps (values of K') so far: the update applies within one.
    kprime_step: usize,
    /// Triangular solve pairs so far.
    pub solves: usize,
    /// max/min diagonal of the last factorised matrix.
    pub condition_estimate: f64,
}

/// How the u-block is solved: on one process a Cholesky factorisation analysed once; on a
/// distributed problem the operators' distributed solver, with K' applied through the operators
/// (theory §12.4).
enum Linear {
    Serial(SparseCholesky),
    Distributed(DistributedSystem),
}

/// The relative residual of the distributed Krylov solves of the penalty's Newton systems: the
/// round-off floor of CG in double precision ([`CG_TOL_MIN`]), so that the steps are those of
/// the serial factorisation to that accuracy.
pub const DISTRIBUTED_RTOL: f64 = CG_TOL_MIN;

impl std::fmt::Debug for PenaltySystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PenaltySystem").field("mu", &self.mu).field("rows", &self.k.len()).finish()
    }
}

/// The current iterate as the Newton step sees it.
pub(super) struct Point<'a> {
    /// Bᵀ(σ + μCε) − f_u: the gradient of the smooth part.
    pub r: &'a [f64],
    /// The carried gaps g.
    pub gap: &'a [f64],
    /// The pressures χ (the friction forces on the tangential rows).
    pub chi: &'a [f64],
    /// V.
    pub v: &'a [f64],
}

/// The Newton step and the gaps it leads to.
pub(super) struct Direction<'a> {
    /// du.
    pub du: &'a mut [f64],
    /// dV.
    pub dv: &'a mut [f64],
    /// ĝ = g(u + du, V + dV).
    pub g_next: &'a mut [f64],
}

impl PenaltySystem {
    /// The penalty scales from the elastic stiffness diagonal, and the symbolic analysis of L's
    /// pattern (once).
    pub fn new(l: &Lagrangian<'_>, mu: f64, update_share: f64) -> Result<Self, SolveError> {
        let rows = l.data.rows;
        let c_el = l.data.elasticity.stiffness_matrix();
        let mut kprime = l.stiffness(Material::Uniform(&c_el));
        let mut symbolic_analyses = 0;
        if l.is_distributed() {
            crate::friction::refuse_friction(rows, "penalty (distributed, theory §12.4)")?;
        }
        let (slaves, row_stiffness, linear) = if l.is_distributed() {
            let mut system = DistributedSystem::new(l, "penalty")?;
            let row_stiffness = system.row_stiffness(l, &kprime)?;
            (system.basis().clone(), row_stiffness, Linear::Distributed(system))
        } else {
            let slaves = RowBasis::new(rows, l.n_dofs(), l.pattern(), "penalty")?;
            let row_stiffness = slaves.row_stiffness(l.pattern(), &kprime);
            let pattern = slaves.pattern(l.pattern());
            let chol = linear::analyse(pattern, "penalty Hessian", "penalty", &mut symbolic_analyses)?;
            (slaves, row_stiffness, Linear::Serial(chol))
        };
        let mut k = contact_stiffness(row_stiffness, mu)?;
        // a pair's Huber function needs one stiffness for both its rows: their mean
        for b in &rows.friction.blocks {
            let kb = 0.5 * (k[b.tangent] + k[b.tangent + 1]);
            k[b.tangent] = kb;
            k[b.tangent + 1] = kb;
        }
        let k_v = extra_stiffness(l)?;
        let (n, ne) = (l.n_dofs(), l.n_extras());
        kprime.iter_mut().for_each(|x| *x = 0.0);
        let nnz = slaves.pattern(l.pattern()).nnz();
        // a solve pair costs 2 nnz_l multiply–adds against the factorisation's factor_flops
        let max_entering = match &linear {
            Linear::Serial(chol) => (update_share * chol.factor_flops() / (2.0 * chol.nnz_l() as f64)) as usize,
            Linear::Distributed(_) => 0,
        };
        let transformed = !slaves.is_identity() && matches!(linear, Linear::Serial(_));
        Ok(Self {
            mu,
            slaves,
            k,
            k_v,
            c_el,
            linear,
            hess: vec![0.0; nnz],
            kprime_t: if transformed { vec![0.0; nnz] } else { Vec::new() },
            r_t: if transformed { vec![0.0; n] } else { Vec::new() },
            kprime,
            cols: vec![0.0; n * (1 + ne)],
            kcols: vec![0.0; n * (1 + ne)],
            next: vec![false; rows.n_rows()],
            friction: RegularisedFriction::new(&rows.friction, rows.n_rows()),
            pair_hess: vec![[[0.0; 2]; 2]; rows.friction.blocks.len()],
            symbolic_analyses,
            factorisations: 0,
            entering: EnteringRows::default(),
            max_entering,
            kprime_step: 0,
            solves: 0,
            condition_estimate: f64::NAN,
        })
    }

    /// Systems solved on the last factor with rows entering A (`update.rs`).
    pub fn entering_row_updates(&self) -> usize {
        self.entering.updates
    }

    /// The distributed solver's Krylov iterations and unconverged solves so far; `None` on one
    /// process.
    pub fn krylov(&self) -> Option<(usize, usize)> {
        match &self.linear {
            Linear::Serial(_) => None,
            Linear::Distributed(system) => Some((system.iterations, system.unconverged)),
        }
    }

    /// χ_i = k_i g_i⁻ on the normal rows; on the tangential pairs the friction forces
    /// P_D(−k s), the discs set from the normal χ (theory §8.3, [`RegularisedFriction`]).
    pub(super) fn pressures(&mut self, gap: &[f64], chi: &mut [f64]) {
        for ((c, g), k) in chi.iter_mut().zip(gap).zip(&self.k) {
            *c = k * (-g).max(0.0);
        }
        self.friction.forces(&self.k, gap, chi);
    }

    /// J_μ(u, V) with the gaps `gap` = g(u, V); `ws.eps` holds ε(u) afterwards.
    pub(super) fn energy(&self, l: &Lagrangian<'_>, u: &[f64], v: &[f64], gap: &[f64], ws: &mut Workspace) -> f64 {
        let j = energy(l, u, v, ws);
        let normal = |i: &usize| self.friction.tangential.get(*i) != Some(&true);
        let pen: f64 = (0..gap.len()).filter(normal).map(|i| self.k[i] * (-gap[i]).max(0.0).powi(2)).sum();
        // a rank's rows summed over the ranks (theory §12; one process: themselves)
        let pen = l.comm().sum(pen) + 2.0 * self.friction.energy(&self.k, gap);
        j + 0.5 * (self.mu * self.regularisation(l, v, &ws.eps) + pen)
    }

    /// uᵀK_el u + Σ k_V V² with `eps` = ε(u): twice the regularisation's energy over μ.
    fn regularisation(&self, l: &Lagrangian<'_>, v: &[f64], eps: &[Sym]) -> f64 {
        let c = &self.c_el;
        let w = l.weights();
        let reg = tree_sum(0..eps.len(), &|r| r.map(|i| w[i] * eps[i].dot(&(c * eps[i]))).sum());
        // a rank's points summed over the ranks (theory §12; one process: themselves)
        l.comm().sum(reg) + self.k_v.iter().zip(v).map(|(k, x)| k * x * x).sum::<f64>()
    }

    /// The share of the loads' work f_u·u + f·V that the regularisation takes,
    /// μ(uᵀK_el u + Σ k_V V²)/(f_u·u + f·V), with `eps` = ε(u) (theory §4.6): O(μ) when the
    /// load is carried, the fraction of the load no admissible stress carries beyond collapse;
    /// 0 while the loads do no work.
    pub(super) fn regularisation_share(&self, l: &Lagrangian<'_>, u: &[f64], v: &[f64], eps: &[Sym]) -> f64 {
        // a rank's dofs summed over the ranks (theory §12; one process: themselves)
        let work_u = l.comm().sum(l.data.nodal_load.iter().zip(u).map(|(f, x)| f * x).sum());
        let work = work_u + l.data.load.iter().zip(v).map(|(f, x)| f * x).sum::<f64>();
        if work > 0.0 { self.mu * self.regularisation(l, v, eps) / work } else { 0.0 }
    }

    /// The Newton step of the contact model (module docs, step 6) with K' in `self.kprime`: an
    /// active-set loop from `model`, which holds the final set on return. Returns the number of
    /// sweeps and whether the set settled; if not, and `descent` asks for a descent direction of
    /// J_μ, d is the plain semismooth Newton direction (A = {g < 0}), else the last sweep's.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn model_step(
        &mut self,
        l: &Lagrangian<'_>,
        material: Material<'_>,
        model: &mut [bool],
        at: &Point<'_>,
        d: &mut Direction<'_>,
        descent: bool,
    ) -> Result<(usize, bool), SolveError> {
        self.kprime_step += 1;
        if !self.slaves.is_identity() {
            // K' (on one process) and r in the rows' coordinates, once for all the sweeps
            if !self.kprime_t.is_empty() {
                self.slaves.stiffness(&self.kprime, &mut self.kprime_t);
            }
            self.r_t.resize(l.n_dofs(), 0.0);
            self.slaves.force_to_coordinates(at.r, &mut self.r_t);
        }
        for sweep in 1..=MODEL_SWEEPS {
            self.pair_hessians(model, at.gap);
            self.step(l, material, model, at, d)?;
            let mut settled = true;
            for (i, ((next, g), a)) in self.next.iter_mut().zip(d.g_next.iter()).zip(model.iter()).enumerate() {
                // a tangential row stays (or is bonded below): its term is not piecewise quadratic
                *next = if self.friction.tangential[i] { *a } else { *g < 0.0 };
            }
            self.bond_reversing_pairs(model, at.gap, d.g_next);
            for (next, a) in self.next.iter().zip(model.iter()) {
                settled &= *next == *a;
            }
            // settled on every rank (theory §12: one decision)
            if !l.comm().any(!settled) {
                return Ok((sweep, true));
            }
            if sweep == MODEL_SWEEPS && !descent {
                return Ok((sweep, false));
            }
            model.copy_from_slice(&self.next);
        }
        for (i, (a, g)) in model.iter_mut().zip(at.gap).enumerate() {
            *a = !self.friction.tangential[i] && *g < 0.0;
        }
        self.pair_hessians(model, at.gap);
        self.step(l, material, model, at, d)?;
        Ok((MODEL_SWEEPS + 1, false))
    }

    /// Each friction pair's generalised Hessian at the iterate; zero for a pair the model bonds
    /// (its term then the exact stick quadratic ½k|s + Δs|² of the active rows).
    fn pair_hessians(&mut self, model: &[bool], gap: &[f64]) {
        for (b, (t, _)) in self.friction.pairs().enumerate() {
            self.pair_hess[b] = if model[t] { [[0.0; 2]; 2] } else { self.friction.hessian(b, &self.k, gap) };
        }
    }

    /// The model's friction pairs (theory §4.3): a pair slipping at the iterate whose step
    /// reverses its slip (ŝ·(s + Δs) ≤ 0, `g_next` = s + Δs) passed through the stick ball,
    /// where its Taylor model (no curvature along ŝ) is wrong: the next sweep bonds it (in
    /// `self.next`), with the exact stick quadratic.
    fn bond_reversing_pairs(&mut self, model: &[bool], gap: &[f64], g_next: &[f64]) {
        for (b, (t, _)) in self.friction.pairs().enumerate() {
            let slipping = self.friction.is_slipping(b, &self.k, gap);
            if !model[t] && slipping && gap[t] * g_next[t] + gap[t + 1] * g_next[t + 1] <= 0.0 {
                self.next[t] = true;
                self.next[t + 1] = true;
            }
        }
    }

    /// The Newton step for the quadratic model in which the rows `active` carry ½k_i g_i²
    /// (formulas in the type's docs), and the gaps ĝ after it, in stages: the right-hand sides,
    /// the factorisation and solves, dV from the extras' Schur complement, du, ĝ.
    fn step(
        &mut self,
        l: &Lagrangian<'_>,
        material: Material<'_>,
        active: &[bool],
        at: &Point<'_>,
        d: &mut Direction<'_>,
    ) -> Result<(), SolveError> {
        self.right_hand_sides(l, material, active, at);
        self.factorise_and_solve(l, active)?;
        if l.n_extras() > 0 {
            self.extras_step(l, active, at, d.dv)?;
        }
        self.displacement_step(d);
        self.next_gaps(l, active, at, d);
        // du = T dy
        self.slaves.displacement_from_coordinates(d.du);
        Ok(())
    }

    /// The columns [z, P] on the active slave dofs (z_s = −g_i/a_i, P_k[s] = H_ik/a_i) and
    /// [r + K'z, K'P], with K' and r in the rows' coordinates (transformed once per Newton step,
    /// [`Self::model_step`]).
    fn right_hand_sides(&mut self, l: &Lagrangian<'_>, material: Material<'_>, active: &[bool], at: &Point<'_>) {
        let rows = l.data.rows;
        let n = l.n_dofs();
        let (kprime, r): (&[f64], &[f64]) =
            if self.slaves.is_identity() { (&self.kprime, at.r) } else { (&self.kprime_t, &self.r_t) };
        self.cols.iter_mut().for_each(|x| *x = 0.0);
        // the active rows' z and P; a friction pair's P only (its Hessian enters without z)
        let pairs = self.friction.pairs().filter(|&(t, _)| !active[t]).flat_map(|(t, _)| [t, t + 1]);
        for i in (0..rows.n_rows()).filter(|&i| active[i]).chain(pairs) {
            let (s, a) = (self.slaves.dof[i], self.slaves.coef[i]);
            if active[i] {
                self.cols[s] = -at.gap[i] / a;
            }
            for (kx, h) in rows.extra_row(i).iter().enumerate() {
                self.cols[(1 + kx) * n + s] = h / a;
            }
        }
        for c in 0..1 + l.n_extras() {
            let (col, kcol) = (&self.cols[c * n..(c + 1) * n], &mut self.kcols[c * n..(c + 1) * n]);
            match &mut self.linear {
                Linear::Serial(_) => self.slaves.pattern(l.pattern()).matvec(kprime, col, kcol),
                // TᵀK'T through the operators: a rank's K' values are its elements' only
                Linear::Distributed(system) => system.tangent_times(l, material, col, kcol),
            }
        }
        for (x, ri) in self.kcols[..n].iter_mut().zip(r) {
            *x += ri;
        }
        // the friction term's gradient −Gᵀχ_t belongs to the right-hand side
        for (t, _) in self.friction.pairs().filter(|&(t, _)| !active[t]) {
            for i in [t, t + 1] {
                self.kcols[self.slaves.dof[i]] -= self.slaves.coef[i] * at.chi[i];
            }
        }
    }

    /// A = K' + D_A on the fixed pattern, its condition estimate, its numeric factorisation,
    /// and [y⁰ Y] = A⁻¹[r + K'z, K'P] in place of the right-hand sides.
    fn factorise_and_solve(&mut self, l: &Lagrangian<'_>, active: &[bool]) -> Result<(), SolveError> {
        let nc = 1 + l.n_extras();
        let chol = match &mut self.linear {
            Linear::Serial(chol) => chol,
            Linear::Distributed(system) => {
                let rows = 0..l.data.rows.n_rows();
                let diagonal: Vec<(usize, f64)> = rows
                    .filter(|&i| active[i])
                    .map(|i| (self.slaves.dof[i], self.k[i] * self.slaves.coef[i].powi(2)))
                    .collect();
                self.condition_estimate =
                    system.solve_columns(l, &self.kprime, &diagonal, &mut self.kcols, nc, DISTRIBUTED_RTOL)?;
                self.factorisations += 1;
                self.solves += nc;
                return Ok(());
            }
        };
        let cp = self.slaves.pattern(l.pattern()).col_ptr();
        let n = l.n_dofs();
        self.hess.copy_from_slice(if self.slaves.is_identity() { &self.kprime } else { &self.kprime_t });
        for i in (0..l.data.rows.n_rows()).filter(|&i| active[i]) {
            self.hess[cp[self.slaves.dof[i]]] += self.k[i] * self.slaves.coef[i].powi(2);
        }
        // the friction pairs' Hessians D_f (a_i a_j ∂²φ_k/∂s_i∂s_j on their coordinates)
        for (b, (t, _)) in self.friction.pairs().enumerate() {
            self.slaves.add_pair_block(l.pattern(), t, self.pair_hess[b], &mut self.hess);
        }
        let (dmin, dmax) = cp[..n].iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &q| {
            let x = self.hess[q];
            (lo.min(x), hi.max(x))
        });
        self.condition_estimate = dmax / dmin;
        let (slaves, k) = (&self.slaves, &self.k);
        let dof_term = |i: usize| (slaves.dof[i], k[i] * slaves.coef[i].powi(2));
        let entering = &mut self.entering;
        if entering.applies(self.kprime_step, active, &self.pair_hess, self.max_entering, dof_term)
            && entering.solve(chol, &mut self.kcols, nc)
        {
            self.solves += nc + entering.dofs();
            return Ok(());
        }
        chol.factorise(&self.hess).in_solver("penalty")?;
        self.factorisations += 1;
        self.entering.factorised(self.kprime_step, active, &self.pair_hess);
        chol.solve_columns(&mut self.kcols, nc);
        self.solves += nc;
        Ok(())
    }

    /// dV from the extras' Schur complement S dV = f − μ k_V V + Pᵀ D_A y⁰, S = μ diag(k_V) +
    /// Pᵀ D_A Y (symmetrised), by a dense LU; the rows' terms summed over the ranks, the same
    /// small solve on every rank (theory §12.4).
    fn extras_step(
        &self,
        l: &Lagrangian<'_>,
        active: &[bool],
        at: &Point<'_>,
        dv: &mut [f64],
    ) -> Result<(), SolveError> {
        let rows = l.data.rows;
        let (n, ne) = (l.n_dofs(), l.n_extras());
        let (y0, y) = self.kcols.split_at(n);
        let mut s = DMatrix::<f64>::zeros(ne, ne);
        let mut b = DVector::<f64>::zeros(ne);
        // the extras' own terms once (rank 0's), then every rank's rows
        let comm = l.comm();
        if comm.rank() == 0 {
            for kx in 0..ne {
                s[(kx, kx)] = self.mu * self.k_v[kx];
                b[kx] = l.data.load[kx] - self.mu * self.k_v[kx] * at.v[kx];
            }
        }
        for i in (0..rows.n_rows()).filter(|&i| active[i]) {
            let (sd, ka) = (self.slaves.dof[i], self.k[i] * self.slaves.coef[i]);
            for (kx, h) in rows.extra_row(i).iter().enumerate() {
                b[kx] += ka * h * y0[sd];
                for ly in 0..ne {
                    s[(kx, ly)] += ka * h * y[ly * n + sd];
                }
            }
        }
        // the friction pairs: Pᵀ D_f Y, Pᵀ D_f y⁰ and their forces Hᵀχ_t
        for (pb, (t, _)) in self.friction.pairs().enumerate() {
            for p in 0..2 {
                let h = rows.extra_row(t + p);
                for q in 0..2 {
                    let (sq, w) = (self.slaves.dof[t + q], self.pair_hess[pb][p][q] * self.slaves.coef[t + q]);
                    for (kx, hk) in h.iter().enumerate().filter(|(_, h)| **h != 0.0) {
                        b[kx] += hk * w * y0[sq];
                        for ly in 0..ne {
                            s[(kx, ly)] += hk * w * y[ly * n + sq];
                        }
                    }
                }
                if !active[t] {
                    for (kx, hk) in h.iter().enumerate() {
                        b[kx] += hk * at.chi[t + p];
                    }
                }
            }
        }
        comm.sum_in_place(s.as_mut_slice());
        comm.sum_in_place(b.as_mut_slice());
        let s = (&s + s.transpose()) * 0.5;
        let sol = s.lu().solve(&b).filter(|x| x.iter().all(|x| x.is_finite()));
        let sol = sol.ok_or_else(|| non_finite("the extras' Schur complement", self.factorisations))?;
        dv.copy_from_slice(sol.as_slice());
        Ok(())
    }

    /// du = z − y⁰ − (P − Y) dV, in the rows' coordinates.
    fn displacement_step(&self, d: &mut Direction<'_>) {
        let n = d.du.len();
        let (y0, y) = self.kcols.split_at(n);
        for j in 0..n {
            let mut x = self.cols[j] - y0[j];
            for (kx, dv) in d.dv.iter().enumerate() {
                x -= (self.cols[(1 + kx) * n + j] - y[kx * n + j]) * dv;
            }
            d.du[j] = x;
        }
    }

    /// ĝ: on the active rows from the model, ĝ_i = g_i + a_i du_s + H_i dV = −a_i(y⁰ − Y dV)_s,
    /// which is of size χ/k and would be lost in the rounding of g + G du + H dV at μ ≲ 1e-14;
    /// on the others by the increment.
    fn next_gaps(&self, l: &Lagrangian<'_>, active: &[bool], at: &Point<'_>, d: &mut Direction<'_>) {
        let rows = l.data.rows;
        let n = l.n_dofs();
        let (y0, y) = self.kcols.split_at(n);
        for (i, gn) in d.g_next.iter_mut().enumerate() {
            let (s, a) = (self.slaves.dof[i], self.slaves.coef[i]);
            *gn = if active[i] {
                -a * (y0[s] - d.dv.iter().enumerate().map(|(kx, dv)| y[kx * n + s] * dv).sum::<f64>())
            } else {
                at.gap[i] + a * d.du[s] + rows.extra_row(i).iter().zip(d.dv.iter()).map(|(h, x)| h * x).sum::<f64>()
            };
        }
    }
}

/// k_i = (K_el)_{s_i s_i} / (μ a_i²) from the rows' elastic stiffnesses (K_el)_{s_i s_i} / a_i²
/// `row_stiffness` (module docs); an error naming `solver.mu` if one overflows.
fn contact_stiffness(row_stiffness: Vec<f64>, mu: f64) -> Result<Vec<f64>, SolveError> {
    let k: Vec<f64> = row_stiffness.iter().map(|k| k / mu).collect();
    if let Some(i) = k.iter().position(|k| !k.is_finite()) {
        let why = format!("is too small: the penalty stiffness (elastic stiffness / mu) of contact row {i} overflows");
        return Err(ParameterError::new("solver.mu", mu, why).into());
    }
    Ok(k)
}

/// k_V,k = E · |Ω|^{1/3} · mean_i H_ik² over the rows touching extra k (module docs); an error
/// if a loaded extra has no row.
fn extra_stiffness(l: &Lagrangian<'_>) -> Result<Vec<f64>, SolveError> {
    let rows = l.data.rows;
    let comm = l.comm();
    let body_stiffness = l.data.elasticity.young * comm.sum(l.weights().iter().sum::<f64>()).cbrt();
    let k_v: Vec<f64> = (0..l.n_extras())
        .map(|kx| {
            let h2: Vec<f64> = (0..rows.n_rows()).map(|i| rows.extra_row(i)[kx].powi(2)).filter(|h| *h > 0.0).collect();
            // every rank's rows
            let (sum, count) = (comm.sum(h2.iter().sum::<f64>()), comm.sum_count(h2.len()));
            if count == 0 { 0.0 } else { body_stiffness * sum / count as f64 }
        })
        .collect();
    for (kx, kv) in k_v.iter().enumerate() {
        if *kv <= 0.0 && l.data.load[kx] != 0.0 {
            return Err(SolveError::Unsupported {
                solver: "penalty".into(),
                message: format!("extra unknown {kx} carries a load but no contact row acts on it"),
            });
        }
    }
    Ok(k_v)
}
