//! The first stage of the primal iterations (theory §4.1 step 1, §4.2 step 1): the local law
//! at every point, then the KKT residuals of the iterate (theory §3.4).

use saddle_core::SymOp;
use saddle_core::problem::fields::StressField;
use saddle_core::problem::kkt::{KktResiduals, kkt_with_stress};
use saddle_core::problem::lagrangian::{Iterate, Lagrangian, Workspace};
use saddle_core::problem::solver::PhaseTimer;

/// An iterate (u, V, λ) and the stress field σ̂ that the local law writes for it.
pub(crate) struct IterateMut<'a> {
    /// u.
    pub u: &'a [f64],
    /// V.
    pub extras: &'a [f64],
    /// λ.
    pub lambda: &'a [f64],
    /// σ̂ = P_D(Cε(u), 0), written.
    pub stress: &'a mut StressField,
}

/// σ̂ = P_D(Cε(u), 0) at every point (theory §2), with the consistent tangents into `tangents`
/// when given (theory §2.5), then the KKT residuals of (u, V, σ̂, λ) (theory §3.4), timed as
/// the phases "local law" and "residual". Afterwards `ws.eps` holds ε(u), `ws.stress` σ̂ and
/// `ws.force` Bᵀσ̂ − f_u. Returns the points at which P's return mapping ran, and the residuals.
pub(crate) fn local_law_and_residual(
    l: &Lagrangian<'_>,
    it: IterateMut<'_>,
    tangents: Option<&mut [SymOp]>,
    ws: &mut Workspace,
    timer: &mut PhaseTimer,
) -> (usize, KktResiduals) {
    let law = timer.time("local law", || {
        l.strain(it.u, &mut ws.eps);
        let law = l.data.local_law(&ws.eps, it.stress, tangents);
        ws.stress.clone_from(it.stress);
        law
    });
    let iterate = Iterate { u: it.u, extras: it.extras, stress: it.stress, lambda: it.lambda };
    let kkt = timer.time("residual", || kkt_with_stress(l, &iterate, ws));
    (law.projected, kkt)
}
