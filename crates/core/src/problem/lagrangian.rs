//! **L** — the discrete Lagrangian (theory §1 (1.11), §3):
//! `L(τ̂, (v, V)) = ½[τ̂, τ̂] − (ε(v), τ) + f·V` on P_h × K_h.
//!
//! Every solver consumes the discrete problem through this trait, in algebraic terms: stress
//! points with weights w_T (the volumes |T|), the strain operator ε = B u and its transpose,
//! the local law of P at each point, the rows of K_h, the load f, and sparse assembly of
//! `Σ_T w_T B_Tᵀ C_T B_T` on a fixed pattern. From these the provided methods evaluate the
//! primal energy J (theory §3 form 1), the dual energy (form 3) and the KKT residuals (form 2) of
//! any iterate — independently of the solver that produced it.

use crate::problem::displacements::ConstraintRows;
use crate::problem::elasticity::Elasticity;
use crate::problem::pattern::SymmetricPattern;
use crate::problem::state::PlasticState;
use crate::problem::stresses::{AdmissibleStresses, energy_inner};
use crate::problem::tensor::{Sym, SymOp};
use rayon::prelude::*;
use serde::Serialize;

/// Generalised stresses σ̂_T = (σ_T, q_T) at every stress point, and the plastic flags.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StressField {
    /// σ_T (Mandel).
    pub sigma: Vec<Sym>,
    /// q_T, `stride` entries per point of which the first `q_dim` are used.
    pub q: Vec<f64>,
    /// Number of hardening variables.
    pub q_dim: usize,
    /// Whether the local law was plastic at the point.
    pub plastic: Vec<bool>,
}

impl StressField {
    /// Zero stresses at `n` points with `q_dim` hardening variables each.
    pub fn new(n: usize, q_dim: usize) -> Self {
        Self { sigma: vec![Sym::zeros(); n], q: vec![0.0; n * q_dim.max(1)], q_dim, plastic: vec![false; n] }
    }

    /// Storage stride of q (at least 1, so that chunks are never empty).
    pub fn stride(&self) -> usize {
        self.q_dim.max(1)
    }

    /// q at point i.
    pub fn q(&self, i: usize) -> &[f64] {
        let s = self.stride();
        &self.q[i * s..i * s + self.q_dim]
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.sigma.len()
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.sigma.is_empty()
    }

    /// Number of plastic points.
    pub fn n_plastic(&self) -> usize {
        self.plastic.iter().filter(|p| **p).count()
    }
}

/// Number of rigid-body motions in 3D: three translations, three rotations.
pub const RIGID_BODY_MODES: usize = 6;

/// The rigid-body motions restricted to the free dofs, with the node each dof belongs to.
#[derive(Clone, Debug, PartialEq)]
pub struct RigidBodyModes {
    /// The node of every free dof: the dofs of one node form a block.
    pub node: Vec<u32>,
    /// Row-major `n × 6`: translations e_x, e_y, e_z and rotations ω × (x − x̄) about the axes
    /// through the centroid x̄ of the nodes.
    pub modes: Vec<f64>,
}

impl RigidBodyModes {
    /// The modes of the free dofs with nodes `node` and components `comp`, the nodes at `coords`.
    pub fn new(node: Vec<u32>, comp: &[u8], coords: &[[f64; 3]]) -> Self {
        let n = node.len();
        let mut centroid = [0.0; 3];
        for &nd in &node {
            for (c, x) in centroid.iter_mut().zip(coords[nd as usize]) {
                *c += x / n.max(1) as f64;
            }
        }
        let mut modes = vec![0.0; n * RIGID_BODY_MODES];
        for (d, row) in modes.chunks_exact_mut(RIGID_BODY_MODES).enumerate() {
            let x = coords[node[d] as usize];
            let [x, y, z] = [x[0] - centroid[0], x[1] - centroid[1], x[2] - centroid[2]];
            let c = comp[d] as usize;
            row[c] = 1.0;
            // ω × x for ω = e_x, e_y, e_z: (0, −z, y), (z, 0, −x), (−y, x, 0)
            row[3] = [0.0, -z, y][c];
            row[4] = [z, 0.0, -x][c];
            row[5] = [-y, x, 0.0][c];
        }
        Self { node, modes }
    }

    /// Number of free dofs.
    pub fn n(&self) -> usize {
        self.node.len()
    }
}

/// An iterate of the saddle problem: primal (u, V) and dual (σ̂, λ).
#[derive(Clone, Copy, Debug)]
pub struct Iterate<'a> {
    /// Free displacement dofs.
    pub u: &'a [f64],
    /// Extra unknowns V.
    pub extras: &'a [f64],
    /// Generalised stresses.
    pub stress: &'a StressField,
    /// Contact multipliers (nodal contact forces), one per row of K_h.
    pub lambda: &'a [f64],
}

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

/// What one evaluation of [`Lagrangian::local_law`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LocalLaw {
    /// Points whose trial stress Cε lay outside D.
    pub plastic: usize,
    /// Points at which P's return mapping ran ([`AdmissibleStresses::local_law`] called): all of
    /// them for a bounded P, none for an elastic problem.
    pub projected: usize,
}

/// The material of an assembly: one tensor for all points, or one per point.
#[derive(Clone, Copy, Debug)]
pub enum Material<'a> {
    /// The same 6×6 Mandel matrix at every point.
    Uniform(&'a SymOp),
    /// One matrix per stress point (consistent tangents).
    PerPoint(&'a [SymOp]),
}

impl Material<'_> {
    /// The matrix at point `i`.
    #[inline]
    pub fn at(&self, i: usize) -> &SymOp {
        match self {
            Material::Uniform(c) => c,
            Material::PerPoint(cs) => &cs[i],
        }
    }
}

/// Scratch vectors for evaluations of L, allocated once per solve.
#[derive(Clone, Debug)]
pub struct Workspace {
    /// Strains per point.
    pub eps: Vec<Sym>,
    /// Stresses of the local law.
    pub stress: StressField,
    /// Internal forces minus loads, Bᵀσ − f_u (after [`Lagrangian::kkt`]).
    pub force: Vec<f64>,
    /// Gᵀλ.
    pub gu: Vec<f64>,
    /// Hᵀλ.
    pub gv: Vec<f64>,
    /// Gaps g(u, V).
    pub gap: Vec<f64>,
}

impl Workspace {
    /// Scratch sized for `l`.
    pub fn new(l: &(impl Lagrangian + ?Sized)) -> Self {
        Self {
            eps: vec![Sym::zeros(); l.n_points()],
            stress: StressField::new(l.n_points(), l.hardening_dim()),
            force: vec![0.0; l.n_dofs()],
            gu: vec![0.0; l.n_dofs()],
            gv: vec![0.0; l.n_extras()],
            gap: vec![0.0; l.constraints().n_rows()],
        }
    }
}

/// L: the discrete saddle problem every solver consumes.
pub trait Lagrangian: Sync {
    /// Number of free displacement dofs (the dimension of W_h).
    fn n_dofs(&self) -> usize;
    /// Number of stress points (elements, for P0 stresses).
    fn n_points(&self) -> usize;
    /// The elasticity of the energy metric.
    fn elasticity(&self) -> &Elasticity;
    /// P, or `None` for an elastic problem.
    fn stresses(&self) -> Option<&dyn AdmissibleStresses>;
    /// K_h.
    fn constraints(&self) -> &ConstraintRows;
    /// The load f on the extra unknowns.
    fn load(&self) -> &[f64];
    /// Quadrature weights w_T (= |T|).
    fn weights(&self) -> &[f64];
    /// ε_T = (B u)_T at every point.
    fn strain(&self, u: &[f64], eps: &mut [Sym]);
    /// f = Σ_T w_T B_Tᵀ σ_T: the internal forces of a stress field (Bᵀ of theory §3).
    fn divergence(&self, sigma: &[Sym], f: &mut [f64]);
    /// The strain operator B as explicit entries `(point, component, dof, value)`:
    /// `ε_T[c] = Σ value · u[dof]` (Mandel components), for solvers that need B as a matrix
    /// (conic formulations).
    fn strain_entries(&self) -> Vec<(usize, usize, usize, f64)>;
    /// Sparsity pattern of assembled matrices (lower triangle).
    fn pattern(&self) -> &SymmetricPattern;
    /// values = Σ_T w_T B_Tᵀ C_T B_T on [`Lagrangian::pattern`].
    fn assemble(&self, material: Material<'_>, values: &mut [f64]);

    /// The rigid-body motions on the free dofs (the near-nullspace of the elastic stiffness,
    /// what a multigrid preconditioner must reproduce); `None` when the discretisation has no
    /// nodal dofs.
    fn rigid_body_modes(&self) -> Option<RigidBodyModes> {
        None
    }

    /// Consistent nodal forces f_u on the free dofs (tractions, body forces); empty for none.
    fn nodal_load(&self) -> &[f64] {
        &[]
    }

    /// Number of extra unknowns V.
    fn n_extras(&self) -> usize {
        self.constraints().n_extras
    }

    /// Number of hardening variables per point.
    fn hardening_dim(&self) -> usize {
        self.plasticity().map_or(0, |p| p.hardening_dim())
    }

    /// P when it actually bounds the stresses; `None` for elastic problems, which then pay
    /// nothing for plasticity.
    fn plasticity(&self) -> Option<&dyn AdmissibleStresses> {
        self.stresses().filter(|p| !p.is_unbounded())
    }

    /// The assembled matrix Σ_T w_T B_Tᵀ C_T B_T (values on the pattern).
    fn stiffness(&self, material: Material<'_>) -> Vec<f64> {
        let mut v = vec![0.0; self.pattern().nnz()];
        self.assemble(material, &mut v);
        v
    }

    /// The state of the previous load step, ε_p and q_n per point (theory §11.1); `None` for
    /// the stationary problem, whose state is zero. Only the step layer
    /// ([`crate::evolution::LoadStep`]) returns one.
    fn state(&self) -> Option<&PlasticState> {
        None
    }

    /// ‖BᵀCε_p‖: the size of the internal forces the step's plastic strain holds locked in (0
    /// for the stationary problem). The equilibrium residual is measured against it too, so
    /// that a step whose answer is zero stress (an unloaded, stress-free body with a plastic
    /// strain) has a scale (theory §11.2). Computed on every call; [`crate::evolution::LoadStep`]
    /// keeps it.
    fn state_force_norm(&self) -> f64 {
        self.state().map_or(0.0, |st| locked_in_force(self, st))
    }

    /// The elastic trial stresses C(ε_T − ε_p,T) (Cε_T for the stationary problem): the
    /// stresses of the elastic response from the step's state, for elastic starts (theory §11.1).
    fn elastic_stress(&self, eps: &[Sym], out: &mut [Sym]) {
        let c = self.elasticity().stiffness_matrix();
        match self.state() {
            None => out.par_iter_mut().zip(eps.par_iter()).for_each(|(s, e)| *s = c * e),
            Some(st) => out
                .par_iter_mut()
                .zip(eps.par_iter())
                .zip(st.plastic_strain.par_iter())
                .for_each(|((s, e), p)| *s = c * (e - p)),
        }
    }

    /// The local law at every point: σ̂_T = P_D(Cε_T, 0) and, if asked, the consistent
    /// tangents (theory §2); from a step's state σ̂_T = P_D(C(ε_T − ε_p), q_n) (theory §11.1).
    /// Returns how many points were plastic and at how many P's return mapping ran (none for an
    /// elastic problem: σ = Cε, no call of P at all).
    fn local_law(&self, eps: &[Sym], out: &mut StressField, tangents: Option<&mut [SymOp]>) -> LocalLaw {
        let law = *self.elasticity();
        let Some(p) = self.plasticity() else {
            let c = law.stiffness_matrix();
            self.elastic_stress(eps, &mut out.sigma);
            out.plastic.par_iter_mut().for_each(|f| *f = false);
            if let Some(t) = tangents {
                t.par_iter_mut().for_each(|t| *t = c);
            }
            return LocalLaw::default();
        };
        let (m, stride) = (out.q_dim, out.stride());
        let state = self.state();
        let points = out
            .sigma
            .par_iter_mut()
            .zip(out.q.par_chunks_mut(stride))
            .zip(out.plastic.par_iter_mut())
            .zip(eps.par_iter())
            .enumerate();
        // each point counts its own return mapping, where it runs
        let law_at = |i: usize, e: &Sym, s: &mut Sym, q: &mut [f64], t: Option<&mut SymOp>| match state {
            None => p.local_law(&law, e, s, q, t),
            Some(st) => p.step_law(&law, e, &st.plastic_strain[i], st.q(i), s, q, t),
        };
        let (plastic, projected) = match tangents {
            None => points
                .map(|(i, (((s, q), pl), e))| {
                    *pl = law_at(i, e, s, &mut q[..m], None);
                    (*pl as usize, 1)
                })
                .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1)),
            Some(t) => points
                .zip(t.par_iter_mut())
                .map(|((i, (((s, q), pl), e)), t)| {
                    *pl = law_at(i, e, s, &mut q[..m], Some(t));
                    (*pl as usize, 1)
                })
                .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1)),
        };
        LocalLaw { plastic, projected }
    }

    /// Σ_T w_T ψ(ε_T): the stored energy of a strain field (theory §2); from a step's state
    /// Σ_T w_T ψ_n(ε_T) (theory §11.1).
    fn energy_of_strain(&self, eps: &[Sym]) -> f64 {
        let law = *self.elasticity();
        let w = self.weights();
        match (self.plasticity(), self.state()) {
            (None, None) => eps.par_iter().zip(w.par_iter()).map(|(e, w)| 0.5 * w * e.dot(&law.stress(e))).sum(),
            (Some(p), None) => eps.par_iter().zip(w.par_iter()).map(|(e, w)| w * p.energy(&law, e)).sum(),
            (None, Some(st)) => (eps, &st.plastic_strain[..], w)
                .into_par_iter()
                .map(|(e, ep, w)| {
                    let x = e - ep;
                    0.5 * w * x.dot(&law.stress(&x))
                })
                .sum(),
            (Some(p), Some(st)) => (0..eps.len())
                .into_par_iter()
                .map(|i| w[i] * p.step_energy(&law, &eps[i], &st.plastic_strain[i], st.q(i)))
                .sum(),
        }
    }

    /// The primal energy J(u, V) = Σ_T |T| ψ(ε_T(u)) − f_u·u − f·V (theory §3 form 1).
    fn energy(&self, u: &[f64], extras: &[f64], ws: &mut Workspace) -> f64 {
        self.strain(u, &mut ws.eps);
        self.energy_of_strain(&ws.eps)
            - self.nodal_load().iter().zip(u).map(|(f, x)| f * x).sum::<f64>()
            - self.load().iter().zip(extras).map(|(f, v)| f * v).sum::<f64>()
    }

    /// ½[σ̂, σ̂] = ½ Σ_T |T| (Aσ_T:σ_T + q_T·H⁻¹q_T); from a step's state the hardening part is
    /// centred at q_n: ½ Σ_T |T| (Aσ_T:σ_T + (q_T − q_n)·H⁻¹(q_T − q_n)) (theory §11.1).
    fn stress_energy(&self, stress: &StressField) -> f64 {
        let law = *self.elasticity();
        let p = self.plasticity();
        let w = self.weights();
        let state = self.state();
        (0..stress.len())
            .into_par_iter()
            .map(|i| {
                let (s, q) = (&stress.sigma[i], stress.q(i));
                match state {
                    None => 0.5 * w[i] * energy_inner(p, &law, s, q, s, q),
                    Some(st) => {
                        let qn = st.q(i);
                        let dq: [f64; crate::problem::stresses::MAX_HARDENING_DIM] =
                            std::array::from_fn(|k| if k < q.len() { q[k] - qn[k] } else { 0.0 });
                        let dq = &dq[..q.len()];
                        0.5 * w[i] * energy_inner(p, &law, s, dq, s, dq)
                    }
                }
            })
            .sum()
    }

    /// The dual energy −(½[σ̂, σ̂] + λ·c) (theory §3 form 3); from a step's state
    /// −(½[σ̂, σ̂]_n + (ε_p, σ) + λ·c) with the centred ½[σ̂, σ̂]_n of
    /// [`Lagrangian::stress_energy`] (theory §11.1). For a dual-feasible pair it is a lower bound
    /// of J, with equality at the solution: J − dual is the duality gap.
    fn dual_energy(&self, stress: &StressField, lambda: &[f64]) -> f64 {
        let c = &self.constraints().offset;
        let prestrain: f64 = self.state().map_or(0.0, |st| {
            let w = self.weights();
            (0..stress.len()).into_par_iter().map(|i| w[i] * st.plastic_strain[i].dot(&stress.sigma[i])).sum()
        });
        -(self.stress_energy(stress) + prestrain + lambda.iter().zip(c).map(|(l, c)| l * c).sum::<f64>())
    }

    /// The KKT residuals of an iterate (theory §3 form 2), recomputed from scratch: σ(u) by the
    /// local law, internal forces, gaps.
    fn kkt(&self, it: &Iterate<'_>, ws: &mut Workspace) -> KktResiduals {
        self.strain(it.u, &mut ws.eps);
        self.local_law(&ws.eps, &mut ws.stress, None);
        self.kkt_with_stress(it, ws)
    }

    /// As [`Lagrangian::kkt`], with `ws.stress` already holding P_D(Cε(u), 0) for `it.u`. On
    /// return `ws.force` holds Bᵀσ(u) − f_u, the gradient of J in u without the contact forces.
    fn kkt_with_stress(&self, it: &Iterate<'_>, ws: &mut Workspace) -> KktResiduals {
        let rows = self.constraints();
        self.divergence(&ws.stress.sigma, &mut ws.force);
        let internal = norm(&ws.force);
        ws.gu.iter_mut().for_each(|x| *x = 0.0);
        ws.gv.iter_mut().for_each(|x| *x = 0.0);
        rows.add_transpose(it.lambda, &mut ws.gu, &mut ws.gv);
        let fu = self.nodal_load();
        let external = if fu.is_empty() {
            norm(&ws.gu)
        } else {
            for (f, l) in ws.force.iter_mut().zip(fu) {
                *f -= l;
            }
            ws.gu.iter().zip(fu).map(|(a, b)| (a + b) * (a + b)).sum::<f64>().sqrt()
        };
        // ‖Bᵀσ − f_u − Gᵀλ‖ / max(‖Bᵀσ‖, ‖Gᵀλ + f_u‖, ‖BᵀCε_p‖)
        let equilibrium = relative(norm_diff(&ws.force, &ws.gu), internal.max(external).max(self.state_force_norm()));
        let f = self.load();
        let load_sum: Vec<f64> = f.iter().zip(&ws.gv).map(|(a, b)| a + b).collect();
        let load_balance = relative(norm(&load_sum), norm(f).max(norm(&ws.gv)));
        rows.gap(it.u, it.extras, &mut ws.gap);
        let lambda_s = max_abs(it.lambda);
        let g_s = max_abs(it.u).max(max_abs(it.extras)).max(max_abs(&rows.offset));
        let mut complementarity: f64 = 0.0;
        for (l, g) in it.lambda.iter().zip(&ws.gap) {
            let a = if lambda_s > 0.0 { l / lambda_s } else { *l };
            let b = if g_s > 0.0 { g / g_s } else { *g };
            let r = a.min(b).abs();
            complementarity = if r.is_nan() || complementarity.is_nan() { f64::NAN } else { complementarity.max(r) };
        }
        let law = *self.elasticity();
        let p = self.plasticity();
        let w = self.weights();
        let (num, den) = (0..self.n_points())
            .into_par_iter()
            .map(|i| {
                let (s0, q0) = (&ws.stress.sigma[i], ws.stress.q(i));
                let ds = it.stress.sigma[i] - s0;
                let dq: [f64; crate::problem::stresses::MAX_HARDENING_DIM] =
                    std::array::from_fn(|k| if k < q0.len() { it.stress.q(i)[k] - q0[k] } else { 0.0 });
                let dq = &dq[..q0.len()];
                (w[i] * energy_inner(p, &law, &ds, dq, &ds, dq), w[i] * energy_inner(p, &law, s0, q0, s0, q0))
            })
            .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
        let constitutive = relative(num.sqrt(), den.sqrt());
        KktResiduals { equilibrium, load_balance, complementarity, constitutive }
    }
}

/// f = BᵀCε_p of L's operators and the plastic strain of `state` (theory §11.2): the internal
/// forces that ε_p alone locks in (the load of an elastic start from the state).
pub fn locked_in_forces(l: &(impl Lagrangian + ?Sized), state: &PlasticState, f: &mut [f64]) {
    let c = l.elasticity().stiffness_matrix();
    let s0: Vec<Sym> = state.plastic_strain.iter().map(|p| c * p).collect();
    l.divergence(&s0, f);
}

/// ‖BᵀCε_p‖ ([`locked_in_forces`]): the scale of a step's equilibrium residual.
pub fn locked_in_force(l: &(impl Lagrangian + ?Sized), state: &PlasticState) -> f64 {
    let mut f = vec![0.0; l.n_dofs()];
    locked_in_forces(l, state, &mut f);
    norm(&f)
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

fn norm_diff(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt()
}

/// Largest absolute entry (NaN if any entry is NaN).
pub fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m: f64, v| if v.is_nan() || m.is_nan() { f64::NAN } else { m.max(v.abs()) })
}
