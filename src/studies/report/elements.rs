//! P1 against P2 on one scene (theory §10): the mesh convergence study of [`super::convergence`]
//! run with both elements on meshes with the same nodes (P2 on half the cells of P1), U of every
//! level measured against one reference — the Richardson extrapolation of P2's three finest
//! levels, else P2's finest U — and the wall time each element needs to bring U within a given
//! accuracy. σ̂ converges per element against its own finest level (`convergence` rates of each
//! study; P2's stresses enter by their element means).

use super::convergence::ConvergenceStudy;
use crate::io::csv::csv_num;
use std::fmt::Write;

/// The accuracies of U the comparison asks each element to reach (relative).
pub const ACCURACIES: [f64; 3] = [1e-2, 3e-3, 1e-3];

/// Both elements' studies and the common reference of U.
#[derive(Clone, Debug)]
pub struct ElementComparison {
    /// (element type, its study), P1 first.
    pub studies: Vec<(String, ConvergenceStudy)>,
    /// The reference U.
    pub reference_u: f64,
    /// Its uncertainty (absolute; the Richardson extrapolation's, [`super::convergence::extrapolate`];
    /// NaN for a finest level taken as the reference, whose error is unknown).
    pub reference_uncertainty: f64,
    /// How the reference was made.
    pub reference: String,
    /// The name of the quantity of interest U (the P2 study's).
    pub quantity: String,
}

/// The cells of the P2 levels with the nodes of the P1 levels `p1` (half the cells, at least
/// one), without repeats.
pub fn p2_levels(p1: &[[usize; 3]]) -> Vec<[usize; 3]> {
    let mut out: Vec<[usize; 3]> = p1.iter().map(|c| c.map(|n| n.div_ceil(2).max(1))).collect();
    out.dedup();
    out
}

/// [`p2_levels`] within a mesh family of base `family`: the P1 levels with an even multiple
/// 2k of the base give P2 level k (the same nodes); the others have no P2 level of the family.
pub fn p2_family_levels(p1: &[[usize; 3]], family: [usize; 3]) -> Vec<[usize; 3]> {
    p1.iter().filter(|c| (c[0] / family[0].max(1)).is_multiple_of(2)).map(|c| c.map(|n| n / 2)).collect()
}

/// A relative error for a markdown table; – where none is claimed (NaN: within the reference's
/// uncertainty).
fn error_or_dash(x: f64) -> String {
    if x.is_finite() { format!("{x:.1e}") } else { "–".into() }
}

/// The cells of the P1 levels with the nodes of the P2 levels `p2` (twice the cells).
pub fn p1_levels(p2: &[[usize; 3]]) -> Vec<[usize; 3]> {
    p2.iter().map(|c| c.map(|n| 2 * n)).collect()
}

impl ElementComparison {
    /// The comparison of a P1 and a P2 study of the same scene.
    pub fn new(p1: ConvergenceStudy, p2: ConvergenceStudy) -> Self {
        // an extrapolation whose order is implausible for the element is not trusted
        let richardson = p2.richardson.filter(|r| p2.plausible_order(r.order));
        let (reference_u, reference_uncertainty, reference) = match (&richardson, p2.levels.last()) {
            (Some(r), _) => (
                r.value,
                r.uncertainty,
                format!(
                    "the Richardson extrapolation of P2's three finest levels (order {:.2}, uncertainty ±{:.1e} = {:.2} %)",
                    r.order,
                    r.uncertainty,
                    100.0 * r.uncertainty / r.value.abs()
                ),
            ),
            (None, Some(l)) => (
                l.u,
                f64::NAN,
                format!("P2's finest level ({}×{}×{} cells; uncertainty unknown)", l.cells[0], l.cells[1], l.cells[2]),
            ),
            (None, None) => (f64::NAN, f64::NAN, "none (no P2 level)".into()),
        };
        let quantity = p2.quantity.clone();
        Self {
            studies: vec![("p1".into(), p1), ("p2".into(), p2)],
            reference_u,
            reference_uncertainty,
            reference,
            quantity,
        }
    }

    /// |U − U_ref| / |U_ref| of a level's U; NaN when it lies within the reference's
    /// uncertainty (no error is claimed below it).
    pub fn err_u(&self, u: f64) -> f64 {
        let e = (u - self.reference_u).abs();
        if e > self.reference_uncertainty || self.reference_uncertainty.is_nan() {
            e / self.reference_u.abs()
        } else {
            f64::NAN
        }
    }

    /// Whether U is within `accuracy` (relative) of the exact value for sure: its distance to the
    /// reference plus the reference's uncertainty (an accuracy below that is never claimed).
    fn within(&self, u: f64, accuracy: f64) -> bool {
        let unc = if self.reference_uncertainty.is_nan() { 0.0 } else { self.reference_uncertainty };
        ((u - self.reference_u).abs() + unc) / self.reference_u.abs() <= accuracy
    }

    /// The least wall time of a converged level of `element` whose U is within `accuracy` of
    /// the reference, with that level's cells and dofs; None when no level reaches it. P2's
    /// finest level is left out when it is the reference itself.
    pub fn time_to(&self, element: &str, accuracy: f64) -> Option<(f64, [usize; 3], usize)> {
        let (_, study) = self.studies.iter().find(|(e, _)| e == element)?;
        let own_reference = element == "p2" && !self.reference.starts_with("the Richardson");
        let n = study.levels.len() - own_reference as usize;
        study.levels[..n]
            .iter()
            .filter(|l| l.converged && self.within(l.u, accuracy))
            .map(|l| (l.wall_s, l.cells, l.dofs))
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }

    /// `elements.csv`: one row per element and level.
    pub fn csv(&self) -> String {
        let mut s = String::from(
            "element,cells,dofs,stress_points,wall_s,converged,iterations,u,err_u_reference,err_stress_own_finest\n",
        );
        for (e, study) in &self.studies {
            for l in &study.levels {
                let _ = writeln!(
                    s,
                    "{e},{}x{}x{},{},{},{},{},{},{},{},{}",
                    l.cells[0],
                    l.cells[1],
                    l.cells[2],
                    l.dofs,
                    l.elements,
                    csv_num(l.wall_s),
                    l.converged,
                    l.iterations,
                    csv_num(l.u),
                    csv_num(self.err_u(l.u)),
                    csv_num(l.err_stress)
                );
            }
        }
        s
    }

    /// The section of `report.md`.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let q = &self.quantity;
        let _ = writeln!(
            s,
            "Both elements on meshes with the same nodes (P2 on half the cells), each level solved by the \
             reference solver. {q} against {} ({q} = {:.6e}); σ̂ against each element's own finest level (P2 by \
             element means). A {q} error within the reference's uncertainty is not claimed (–).\n",
            self.reference, self.reference_u
        );
        let _ = writeln!(
            s,
            "| element | cells | dofs | wall (s) | {q} | {q} error | σ̂ error (own finest) |\n|---|---|---:|---:|---:|---:|---:|"
        );
        for (e, study) in &self.studies {
            for l in &study.levels {
                let _ = writeln!(
                    s,
                    "| {e} | {}×{}×{} | {} | {:.2} | {:.6e} | {} | {:.1e} |",
                    l.cells[0],
                    l.cells[1],
                    l.cells[2],
                    l.dofs,
                    l.wall_s,
                    l.u,
                    error_or_dash(self.err_u(l.u)),
                    l.err_stress
                );
            }
        }
        for (e, study) in &self.studies {
            if let Some(r) = study.stress_rate_fit {
                let _ = writeln!(s, "\n{e}: σ̂ converges at the fitted rate {r:.2} in h.");
            }
        }
        let _ = writeln!(
            s,
            "\nThe least wall time to bring {q} within an accuracy of the reference:\n\n| accuracy | p1 | p2 | sooner |\n|---:|---|---|---|"
        );
        let show = |t: Option<(f64, [usize; 3], usize)>| {
            t.map_or("not reached".to_string(), |(w, c, d)| format!("{w:.2} s ({}×{}×{}, {d} dofs)", c[0], c[1], c[2]))
        };
        let known_to = self.reference_uncertainty / self.reference_u.abs();
        for a in ACCURACIES {
            if known_to >= a {
                let _ =
                    writeln!(s, "| {a:.0e} | below the reference's uncertainty ({:.2} %) | | – |", 100.0 * known_to);
                continue;
            }
            let (t1, t2) = (self.time_to("p1", a), self.time_to("p2", a));
            let sooner = match (t1, t2) {
                (Some(a), Some(b)) => {
                    if a.0 <= b.0 {
                        "p1"
                    } else {
                        "p2"
                    }
                }
                (Some(_), None) => "p1",
                (None, Some(_)) => "p2",
                (None, None) => "neither",
            };
            let _ = writeln!(s, "| {a:.0e} | {} | {} | {sooner} |", show(t1), show(t2));
        }
        s
    }

    /// (element, points (wall time, U error)) for the plot.
    pub fn series(&self) -> Vec<(String, Vec<(f64, f64)>)> {
        self.studies
            .iter()
            .map(|(e, study)| {
                let pts = study.levels.iter().filter(|l| l.converged).map(|l| (l.wall_s, self.err_u(l.u))).collect();
                (e.clone(), pts)
            })
            .collect()
    }
}
