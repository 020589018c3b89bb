//! Mesh convergence (theory §3 Theorem 2, §7): a sequence of refined box meshes of one scene, each
//! solved tightly, errors against the finest level, observed rates and a Richardson
//! extrapolation of U.
//!
//! **Mesh size.** The rates are taken with respect to the mean element size
//! h = (|Ω| / #elements)^{1/3}. On the graded box family every measure of the mesh size scales
//! like 1/cells; the mean does so smoothly, whereas the largest element touching the contact
//! zone Γ₀ jumps with the position of the zone's rim among the graded cells (it is reported
//! alongside, `h_contact`, to compare with theory §6's resolution requirement).
//!
//! **Against the finest level.** Errors measured against the finest level rather than the exact
//! solution are too small on the levels next to it, so rates between the finer levels come out
//! too high; the rates of the coarsest pairs are the least affected. The differences between
//! *consecutive* levels do not depend on the finest level; their rates are reported as well.

use saddle_core::DiscreteProblem;

/// The levels of a mesh family (`mesh.base`, theory §7.3): `family_base` times each factor of
/// the scene's own multiple k (rounded, at least 1), ascending, repeats merged. Every level is a
/// multiple of the base, so every level has the same grading and alignment.
pub fn family_levels(family_base: [usize; 3], scene: [usize; 3], factors: &[f64]) -> Vec<[usize; 3]> {
    let k = (scene[0] / family_base[0].max(1)).max(1) as f64;
    let ks: Vec<usize> =
        factors.iter().filter(|f| f.is_finite() && **f > 0.0).map(|f| ((k * f).round() as usize).max(1)).collect();
    family_cells(family_base, &ks)
}

/// The cells `k·family_base` of the levels `ks` of a mesh family (theory §7.3), ascending,
/// repeats merged.
pub fn family_cells(family_base: [usize; 3], ks: &[usize]) -> Vec<[usize; 3]> {
    let mut ks = ks.to_vec();
    ks.sort_unstable();
    ks.dedup();
    ks.into_iter().map(|k| family_base.map(|n| k * n)).collect()
}

/// The cells of each refinement level: `base` scaled by each factor (rounded, at least 1),
/// ascending, levels with the same cells merged.
pub fn refinement_levels(base: [usize; 3], factors: &[f64]) -> Vec<[usize; 3]> {
    let mut levels: Vec<[usize; 3]> = factors
        .iter()
        .filter(|f| f.is_finite() && **f > 0.0)
        .map(|f| base.map(|c| ((c as f64 * f).round() as usize).max(1)))
        .collect();
    levels.sort_by_key(|c| c[0] * c[1] * c[2]);
    levels.dedup();
    levels
}

/// Mesh sizes of a problem.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshSize {
    /// Largest edge of the elements touching a node of the candidate contact zone (None
    /// without contact rows).
    pub contact: Option<f64>,
    /// (|Ω| / #elements)^{1/3}.
    pub mean: f64,
}

impl MeshSize {
    /// The h of the rates: the mean element size (module docs).
    pub fn h(&self) -> f64 {
        self.mean
    }
}

/// The mesh sizes of `l` (module docs).
pub fn mesh_size(problem: &DiscreteProblem) -> MeshSize {
    let (l, element) = (&problem.lagrangian(), &*problem.element);
    let mesh = element.mesh();
    let volume: f64 = l.weights().iter().sum();
    let mean = (volume / mesh.n_elements() as f64).cbrt();
    let rows = l.data.rows;
    let contact = if rows.n_rows() == 0 {
        None
    } else {
        let mut zone = vec![false; mesh.n_nodes()];
        for &n in &rows.node {
            zone[n] = true;
        }
        (0..mesh.n_elements())
            .filter(|&e| mesh.tets[e].iter().any(|&n| zone[n]))
            .map(|e| mesh.element_size(e))
            .fold(None, |m: Option<f64>, s| Some(m.map_or(s, |m| m.max(s))))
    };
    MeshSize { contact, mean }
}

/// The observed rate between two levels: ln(e₁/e₂) / ln(h₁/h₂); NaN when undefined (an error
/// that is zero, negative or not finite, or equal mesh sizes).
pub fn observed_rate(h1: f64, e1: f64, h2: f64, e2: f64) -> f64 {
    if e1 > 0.0 && e2 > 0.0 && h1 > 0.0 && h2 > 0.0 && h1 != h2 && e1.is_finite() && e2.is_finite() {
        (e1 / e2).ln() / (h1 / h2).ln()
    } else {
        f64::NAN
    }
}

/// The least-squares slope of ln e against ln h over the points with e > 0; `None` for fewer
/// than two such points.
pub fn fitted_rate(h: &[f64], e: &[f64]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = h
        .iter()
        .zip(e)
        .filter(|(h, e)| **h > 0.0 && **e > 0.0 && h.is_finite() && e.is_finite())
        .map(|(h, e)| (h.ln(), e.ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// A Richardson extrapolation v(h) ≈ v* + C h^p from three levels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Richardson {
    /// The extrapolated value v*.
    pub value: f64,
    /// The observed order p.
    pub order: f64,
    /// C.
    pub constant: f64,
    /// The uncertainty of v* (an absolute value): Roache's grid convergence index of the finest
    /// level with the observed order, `F_s |v* − v₃|`, F_s = [`GCI_SAFETY`] (Roache 1994, J.
    /// Fluids Eng. 116:405; Celik et al. 2008, J. Fluids Eng. 130:078001), and with a fourth
    /// level at least the change of v* from the previous triple ([`extrapolate`]).
    pub uncertainty: f64,
}

/// Roache's safety factor of the grid convergence index for three or more levels with the
/// order observed from them (Roache 1998, Verification and Validation in Computational Science
/// and Engineering, §5.6; Celik et al. 2008).
pub const GCI_SAFETY: f64 = 1.25;

/// The Richardson extrapolation of the three finest of `(h, v)` (any order), its uncertainty
/// raised to the change of v* from the previous triple when there is a fourth level (the
/// extrapolation's own dependence on the levels: a triple still outside the asymptotic range
/// moves v* by more than the GCI). `None` when the finest triple admits no extrapolation.
pub fn extrapolate(h: &[f64], v: &[f64]) -> Option<Richardson> {
    let mut idx: Vec<usize> = (0..h.len().min(v.len())).collect();
    idx.sort_by(|&a, &b| h[b].total_cmp(&h[a]));
    let n = idx.len();
    if n < 3 {
        return None;
    }
    let triple = |t: &[usize]| richardson([h[t[0]], h[t[1]], h[t[2]]], [v[t[0]], v[t[1]], v[t[2]]]);
    let mut r = triple(&idx[n - 3..])?;
    if n >= 4 {
        match triple(&idx[n - 4..n - 1]) {
            Some(previous) => r.uncertainty = r.uncertainty.max((r.value - previous.value).abs()),
            // the previous triple oscillates: the spread of the last three levels is the honest bound
            None => r.uncertainty = r.uncertainty.max((v[idx[n - 3]] - v[idx[n - 1]]).abs()),
        }
    }
    Some(r)
}

/// Fits v = v* + C h^p exactly through three levels (h₁ > h₂ > h₃ in any order of input, any
/// ratios): p solves (v₁ − v₂)/(v₂ − v₃) = (h₁^p − h₂^p)/(h₂^p − h₃^p). `None` when the
/// differences do not decrease monotonically with one sign (no p > 0 fits), or the sizes are
/// not distinct.
pub fn richardson(h: [f64; 3], v: [f64; 3]) -> Option<Richardson> {
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&a, &b| h[b].total_cmp(&h[a]));
    let (h, v) = (idx.map(|i| h[i]), idx.map(|i| v[i]));
    if !(h[0] > h[1] && h[1] > h[2] && h[2] > 0.0) || v.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let (d1, d2) = (v[0] - v[1], v[1] - v[2]);
    if d1 == 0.0 || d2 == 0.0 || d1.signum() != d2.signum() {
        return None;
    }
    let target = (d1 / d2).ln();
    // f(p) = ln((1 − r₂^p)/(r₂^p − r₃^p)), r = h/h₁ < 1: increasing in p from
    // ln(ln r₂ / (ln r₃ − ln r₂)) at p → 0
    let (r2, r3) = (h[1] / h[0], h[2] / h[0]);
    let f = |p: f64| ((1.0 - r2.powf(p)) / (r2.powf(p) - r3.powf(p))).ln();
    let (mut lo, mut hi) = (1e-9, 60.0);
    if !(f(lo) < target && target < f(hi)) {
        return None;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let p = 0.5 * (lo + hi);
    let constant = d2 / (h[1].powf(p) - h[2].powf(p));
    let correction = constant * h[2].powf(p);
    Some(Richardson { value: v[2] - correction, order: p, constant, uncertainty: GCI_SAFETY * correction.abs() })
}

/// One level of a convergence study.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelResult {
    /// Cells of the box mesh.
    pub cells: [usize; 3],
    /// Free displacement dofs.
    pub dofs: usize,
    /// Tetrahedra.
    pub elements: usize,
    /// Mesh sizes.
    pub size: MeshSize,
    /// Wall time of the solve (s), measured around it.
    pub wall_s: f64,
    /// "converged", the stop reason, or the error.
    pub status: String,
    /// True when the solve met its tolerance.
    pub converged: bool,
    /// Solver iterations.
    pub iterations: usize,
    /// The recomputed relative KKT residual.
    pub kkt: f64,
    /// The quantity of interest U, by its name ([`ConvergenceStudy::quantity`]; NaN without
    /// such a quantity).
    pub u: f64,
    /// |U − U_finest| / |U_finest|.
    pub err_u: f64,
    /// |U − U*| / |U*| against the Richardson extrapolation; NaN without one, and when the error
    /// lies within the extrapolation's uncertainty (no error is claimed below it).
    pub err_u_richardson: f64,
    /// [σ̂ − σ̂_finest] / [σ̂_finest] in the energy norm on the finest mesh.
    pub err_stress: f64,
    /// ‖ε(u) − ε(u_finest)‖ / ‖ε(u_finest)‖ on the finest mesh.
    pub err_strain: f64,
    /// [σ̂ − σ̂_next] / [σ̂_next] against the next finer level, on its mesh (NaN on the finest).
    pub diff_stress_next: f64,
}

impl LevelResult {
    /// Microseconds of wall time per dof.
    pub fn time_per_dof_us(&self) -> f64 {
        1e6 * self.wall_s / self.dofs.max(1) as f64
    }
}

/// Rates between two consecutive levels (coarse → fine).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rates {
    /// Index of the coarser level.
    pub coarse: usize,
    /// Of the errors in U against the Richardson extrapolation (against the finest level
    /// without one).
    pub u: f64,
    /// Of the σ̂ energy errors against the finest level.
    pub stress: f64,
    /// Of the ε(u) errors against the finest level.
    pub strain: f64,
    /// Of the σ̂ differences between consecutive levels.
    pub stress_consecutive: f64,
}

/// A mesh convergence study.
#[derive(Clone, Debug, PartialEq)]
pub struct ConvergenceStudy {
    /// Levels, coarse to fine; the last is the reference.
    pub levels: Vec<LevelResult>,
    /// The extrapolation of U from the three finest levels.
    pub richardson: Option<Richardson>,
    /// Rates between consecutive levels (one fewer than levels).
    pub rates: Vec<Rates>,
    /// Least-squares rate of the σ̂ errors over the levels below the finest.
    pub stress_rate_fit: Option<f64>,
    /// Least-squares rate of the consecutive σ̂ differences.
    pub stress_consecutive_rate_fit: Option<f64>,
    /// What h is (module docs): [`H_MEAN`].
    pub h_definition: &'static str,
    /// The polynomial degree p of the element's displacements: orders of U in 0.25 ..= 2p + ½
    /// are plausible ([`ConvergenceStudy::plausible_order`]).
    pub degree: usize,
    /// The name of the quantity of interest U of the levels (`quantity` when none was named).
    pub quantity: String,
}

/// What h is (module docs).
pub const H_MEAN: &str = "the mean element size (|Ω|/elements)^(1/3)";

/// |v − v*| / |v*| when it exceeds the reference's relative uncertainty, else NaN: no error is
/// claimed (or plotted) below what the reference itself is known to.
pub fn error_above_uncertainty(v: f64, r: &Richardson) -> f64 {
    let e = (v - r.value).abs();
    if e > r.uncertainty { e / r.value.abs() } else { f64::NAN }
}

impl ConvergenceStudy {
    /// Completes a study from its levels (errors against the finest filled in): the Richardson
    /// extrapolation of U from the three finest converged levels, the errors against it, and
    /// the rates.
    pub fn from_levels(mut levels: Vec<LevelResult>) -> Self {
        let hs: Vec<f64> = levels.iter().map(|l| l.size.h()).collect();
        let good: Vec<usize> = (0..levels.len()).filter(|&i| levels[i].converged && levels[i].u.is_finite()).collect();
        let richardson = extrapolate(
            &good.iter().map(|&i| hs[i]).collect::<Vec<_>>(),
            &good.iter().map(|&i| levels[i].u).collect::<Vec<_>>(),
        );
        for l in &mut levels {
            l.err_u_richardson = richardson.map_or(f64::NAN, |r| error_above_uncertainty(l.u, &r));
        }
        let rates = (0..levels.len().saturating_sub(1))
            .map(|i| {
                let (a, b) = (&levels[i], &levels[i + 1]);
                let (ua, ub) =
                    if richardson.is_some() { (a.err_u_richardson, b.err_u_richardson) } else { (a.err_u, b.err_u) };
                let next_diff = levels.get(i + 2).map_or(f64::NAN, |_| b.diff_stress_next);
                Rates {
                    coarse: i,
                    u: observed_rate(hs[i], ua, hs[i + 1], ub),
                    stress: observed_rate(hs[i], a.err_stress, hs[i + 1], b.err_stress),
                    strain: observed_rate(hs[i], a.err_strain, hs[i + 1], b.err_strain),
                    stress_consecutive: observed_rate(hs[i], a.diff_stress_next, hs[i + 1], next_diff),
                }
            })
            .collect();
        let below = levels.len().saturating_sub(1);
        let stress_rate_fit =
            fitted_rate(&hs[..below], &levels[..below].iter().map(|l| l.err_stress).collect::<Vec<_>>());
        let stress_consecutive_rate_fit =
            fitted_rate(&hs[..below], &levels[..below].iter().map(|l| l.diff_stress_next).collect::<Vec<_>>());
        Self {
            levels,
            richardson,
            rates,
            stress_rate_fit,
            stress_consecutive_rate_fit,
            h_definition: H_MEAN,
            degree: 1,
            quantity: "quantity".into(),
        }
    }

    /// The same study of the quantity of interest named `name`.
    pub fn of_quantity(self, name: String) -> Self {
        Self { quantity: name, ..self }
    }

    /// The same study of an element of displacement degree `degree`.
    pub fn of_degree(self, degree: usize) -> Self {
        Self { degree, ..self }
    }

    /// The largest observed order of U taken as asymptotic: 2p + ½ (a functional such as U
    /// converges at up to twice the energy norm's order p; theory §7.3).
    pub fn plausible_order_max(&self) -> f64 {
        2.0 * self.degree as f64 + 0.5
    }

    /// Whether an observed order of U is plausible for the element (0.25 ..= 2p + ½).
    pub fn plausible_order(&self, order: f64) -> bool {
        (0.25..=self.plausible_order_max()).contains(&order)
    }
}
