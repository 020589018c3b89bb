//! The report's text outputs: `work_precision.csv`, `convergence.csv` and `report.md`.
//!
//! CSV: one header line, comma separated, fields quoted when they hold a comma or a quote, a
//! missing or undefined number left empty. Column names carry their units: `_s` seconds,
//! `_us` microseconds, `_rel` a dimensionless relative quantity; h is in the scene's length
//! unit. The columns `U` hold the report's quantity of interest (the scene's first extra unknown
//! or the one named by `--quantity`; `report.md` names it), in its own unit.

use super::convergence::{ConvergenceStudy, GCI_SAFETY};
use super::measure::Report;
use super::runs::RunRecord;
use crate::io::csv::{csv_field, csv_num};
use std::fmt::Write;

/// The header of `work_precision.csv`.
pub const WORK_PRECISION_HEADER: &str = "solver,setting,reference,status,converged,iterations,wall_time_s,\
solver_time_s,U,err_U_rel,err_stress_energy_rel,err_strain_L2_rel,kkt_rel,contact_rows_differing,note";

/// The header of `convergence.csv`.
pub const CONVERGENCE_HEADER: &str = "level,cells,dofs,elements,h,h_contact,wall_time_s,time_per_dof_us,\
status,converged,iterations,kkt_rel,U,err_U_rel,err_U_richardson_rel,err_stress_energy_rel,err_strain_L2_rel,\
diff_stress_energy_next_rel,rate_U,rate_stress,rate_strain,rate_stress_consecutive";

/// `work_precision.csv`: one row per run.
pub fn work_precision_csv(runs: &[RunRecord]) -> String {
    let mut s = String::from(WORK_PRECISION_HEADER);
    s.push('\n');
    for r in runs {
        let e = r.errors;
        let row = [
            csv_field(&r.solver),
            csv_field(&r.setting),
            r.reference.to_string(),
            csv_field(&r.status),
            r.converged.to_string(),
            r.iterations.to_string(),
            csv_num(r.wall_s),
            csv_num(r.solver_s),
            csv_num(r.u),
            csv_num(e.map_or(f64::NAN, |e| e.u_rel)),
            csv_num(e.map_or(f64::NAN, |e| e.stress_rel)),
            csv_num(e.map_or(f64::NAN, |e| e.strain_rel)),
            csv_num(r.kkt),
            e.map_or(String::new(), |e| e.contact_mismatch.to_string()),
            csv_field(&r.note),
        ];
        s.push_str(&row.join(","));
        s.push('\n');
    }
    s
}

/// `convergence.csv`: one row per level, coarse to fine; the rates on the finer level of each
/// pair. Only the header when there is no study.
pub fn convergence_csv(study: Option<&ConvergenceStudy>) -> String {
    let mut s = String::from(CONVERGENCE_HEADER);
    s.push('\n');
    let Some(study) = study else { return s };
    for (i, l) in study.levels.iter().enumerate() {
        let rate = i.checked_sub(1).and_then(|j| study.rates.get(j));
        let r = |f: fn(&super::convergence::Rates) -> f64| csv_num(rate.map_or(f64::NAN, f));
        let row = [
            i.to_string(),
            format!("{}x{}x{}", l.cells[0], l.cells[1], l.cells[2]),
            l.dofs.to_string(),
            l.elements.to_string(),
            csv_num(l.size.h()),
            csv_num(l.size.contact.unwrap_or(f64::NAN)),
            csv_num(l.wall_s),
            csv_num(l.time_per_dof_us()),
            csv_field(&l.status),
            l.converged.to_string(),
            l.iterations.to_string(),
            csv_num(l.kkt),
            csv_num(l.u),
            csv_num(l.err_u),
            csv_num(l.err_u_richardson),
            csv_num(l.err_stress),
            csv_num(l.err_strain),
            csv_num(l.diff_stress_next),
            r(|r| r.u),
            r(|r| r.stress),
            r(|r| r.strain),
            r(|r| r.stress_consecutive),
        ];
        s.push_str(&row.join(","));
        s.push('\n');
    }
    s
}

/// A number for a markdown table: 3 significant digits, `–` when undefined.
fn md(x: f64) -> String {
    if x.is_finite() { format!("{x:.2e}") } else { "–".into() }
}

/// A rate for a markdown table.
fn md_rate(x: f64) -> String {
    if x.is_finite() { format!("{x:.2}") } else { "–".into() }
}

/// A time for a markdown table.
fn md_time(x: f64) -> String {
    if x.is_finite() { format!("{x:.1}") } else { "–".into() }
}

/// Escapes `|` in a markdown table cell.
fn cell(s: &str) -> String {
    s.replace('|', "\\|")
}

/// The work–precision table of `report.md`, the error of the quantity of interest labelled
/// `quantity`.
pub fn work_precision_table(runs: &[RunRecord], quantity: &str) -> String {
    let mut s = format!(
        "| solver | setting | status | iterations | wall time (s) | {quantity} error | σ̂ error (energy) | ε(u) error | KKT residual |\n\
         |---|---|---|---|---|---|---|---|---|\n",
    );
    for r in runs {
        let e = r.errors;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.solver,
            cell(&r.setting),
            cell(&r.status),
            r.iterations,
            md_time(r.wall_s),
            e.map_or("–".into(), |e| md(e.u_rel)),
            e.map_or("–".into(), |e| md(e.stress_rel)),
            e.map_or("–".into(), |e| md(e.strain_rel)),
            md(r.kkt),
        );
    }
    s
}

/// Each solver's converged run with the smallest σ̂ error (its tightest setting): solver,
/// record.
pub fn tightest(runs: &[RunRecord]) -> Vec<&RunRecord> {
    let mut solvers: Vec<&str> = Vec::new();
    for r in runs {
        if !solvers.contains(&r.solver.as_str()) {
            solvers.push(&r.solver);
        }
    }
    solvers
        .iter()
        .filter_map(|s| {
            // the last converged rung of the ladder, which is ordered loose to tight
            runs.iter().rfind(|r| r.solver == *s && r.converged && r.errors.is_some())
        })
        .collect()
}

/// The convergence table of `report.md`; the level with `scene_cells` is marked as the scene's.
pub fn convergence_table(study: &ConvergenceStudy, scene_cells: Option<[usize; 3]>) -> String {
    let q = &study.quantity;
    let against = if study.richardson.is_some() { format!("vs Richardson {q}*") } else { "vs finest".into() };
    let mut s = format!(
        "| cells | dofs | h | time (s) | µs/dof | status | {q} | {q} error ({against}) | σ̂ error (energy) | ε(u) error | \
         rate {q} | rate σ̂ | rate ε(u) | rate σ̂ (consecutive) |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for (i, l) in study.levels.iter().enumerate() {
        let rate = i.checked_sub(1).and_then(|j| study.rates.get(j));
        let r = |f: fn(&super::convergence::Rates) -> f64| md_rate(rate.map_or(f64::NAN, f));
        let finest = i + 1 == study.levels.len();
        let mark = if Some(l.cells) == scene_cells { " (scene)" } else { "" };
        let err = |x: f64| if finest { "(reference)".to_string() } else { md(x) };
        let _ = writeln!(
            s,
            "| {}×{}×{}{mark} | {} | {:.4} | {} | {:.1} | {} | {:.7e} | {} | {} | {} | {} | {} | {} | {} |",
            l.cells[0],
            l.cells[1],
            l.cells[2],
            l.dofs,
            l.size.h(),
            md_time(l.wall_s),
            l.time_per_dof_us(),
            cell(&l.status),
            l.u,
            if study.richardson.is_some() { md(l.err_u_richardson) } else { err(l.err_u) },
            err(l.err_stress),
            err(l.err_strain),
            r(|r| r.u),
            r(|r| r.stress),
            r(|r| r.strain),
            r(|r| r.stress_consecutive),
        );
    }
    s
}

/// `report.md`.
pub fn markdown(report: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Accuracy and cost: {}\n", report.title);
    let levels = report.levels.as_ref().map_or(String::new(), |ks| {
        format!(" --levels {}", ks.iter().map(|k| k.to_string()).collect::<Vec<_>>().join(","))
    });
    let asked = match &report.quantity {
        Some((n, true)) => format!(" --quantity {n}"),
        _ => String::new(),
    };
    let quick = format!("{}{levels}{asked}", if report.quick { " --quick" } else { "" });
    let _ = writeln!(
        s,
        "Scene `{}`: {} dofs, {} tetrahedra, {} candidate contact nodes. Machine: {} cores. \
         The whole report took {:.0} s (`saddle report {}{quick}`).\n",
        report.scene.display(),
        report.dofs,
        report.elements,
        report.contact_rows,
        report.cores,
        report.total_s,
        report.scene.display(),
    );
    let q = report.quantity.as_ref().map_or("quantity", |(n, _)| n.as_str());
    let _ = match &report.quantity {
        Some((n, true)) => writeln!(s, "Quantity of interest: `{n}` (`--quantity`); the CSV columns `U` hold it.\n"),
        Some((n, false)) => writeln!(
            s,
            "Quantity of interest: `{n}`, the scene's first extra unknown (another: `--quantity NAME`); the CSV \
             columns `U` hold it.\n"
        ),
        None => writeln!(s, "Quantity of interest: none (the scene reports no quantity); its columns are empty.\n"),
    };
    let _ = writeln!(s, "## Work–precision\n");
    if report.plots {
        let _ = writeln!(
            s,
            "![work–precision](work_precision.png)\n\n([SVG](work_precision.svg), data: \
             [work_precision.csv](work_precision.csv))\n"
        );
    } else {
        let _ = writeln!(
            s,
            "(Images not drawn: built without the cargo feature `report`.) Data: [work_precision.csv](work_precision.csv)\n"
        );
    }
    if let Some(r) = report.reference() {
        let _ = writeln!(
            s,
            "Errors are relative and measured against the reference, {} ({}: KKT residual {}, {q} = {:.12e}, \
             {:.1} s), which solves the same discrete problem (theory §3, §5): {q}; σ̂ in the energy norm \
             [σ̂ − σ̂_ref]^½/[σ̂_ref]^½; ε(u) in L². Wall time is measured around each solve. Runs that stop short are listed with their status and drawn as open markers off \
             the lines; the reference itself has error 0 and is not drawn.\n",
            r.label(),
            r.status,
            md(r.kkt),
            r.u,
            r.wall_s
        );
    }
    s.push_str(&work_precision_table(&report.runs, q));
    let _ = writeln!(s, "\n### Each solver at its tightest setting\n");
    let _ = writeln!(
        s,
        "| solver | setting | σ̂ error (energy) | {q} error | ε(u) error | wall time (s) |\n|---|---|---|---|---|---|"
    );
    for r in tightest(&report.runs) {
        let e = r.errors.expect("tightest() keeps runs with errors");
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} |",
            r.solver,
            cell(&r.setting),
            if r.reference { "0 (reference)".into() } else { md(e.stress_rel) },
            if r.reference { "0 (reference)".into() } else { md(e.u_rel) },
            if r.reference { "0 (reference)".into() } else { md(e.strain_rel) },
            md_time(r.wall_s)
        );
    }
    let _ = writeln!(s, "\n## Mesh convergence (theory §3 Theorem 2, §7)\n");
    match &report.convergence {
        Err(why) => {
            let _ = writeln!(s, "Skipped: {why}.");
        }
        Ok(study) => {
            if report.plots {
                let _ = writeln!(
                    s,
                    "![convergence](convergence.png)\n\n([SVG](convergence.svg), data: [convergence.csv](convergence.csv))\n"
                );
            } else {
                let _ = writeln!(s, "Data: [convergence.csv](convergence.csv)\n");
            }
            let _ = writeln!(
                s,
                "The scene's box mesh with its cells scaled (same grading ratio), each level solved by Newton to \
                 1e-13. σ̂ and ε(u) errors are against the finest level: the coarse P0 fields are sampled at the \
                 centroids of the 8 red-refinement children of every fine element and the squared difference is \
                 integrated over the fine mesh. h = {}. Rates are between consecutive levels. The graded meshes \
                 are not nested, so the error of a level against the finest one also contains the finest level's \
                 own error: the rates of the pairs next to the finest level are the least reliable. The \
                 differences between *consecutive* levels ([σ̂_h − σ̂_h'], last column) do not involve the finest \
                 level and give a second estimate.\n",
                study.h_definition
            );
            s.push_str(&convergence_table(study, report.scene_cells));
            s.push('\n');
            let fit = study.stress_rate_fit.map_or("–".into(), |r| format!("{r:.2}"));
            let fit_c = study.stress_consecutive_rate_fit.map_or("–".into(), |r| format!("{r:.2}"));
            let min_rate = study
                .rates
                .iter()
                .flat_map(|r| [r.stress, r.stress_consecutive])
                .filter(|r| r.is_finite())
                .fold(f64::INFINITY, f64::min);
            let verdict = match study.stress_rate_fit {
                Some(r) if r >= 0.5 => "at least",
                Some(_) => "**below**",
                None => "not measurable against",
            };
            let _ = writeln!(
                s,
                "**Observed σ̂ rate** (energy norm): {fit} fitted over the levels below the finest, {fit_c} from the \
                 consecutive differences, smallest pairwise rate {} — {verdict} the 1/2 that Theorem 2 guarantees.\n",
                md_rate(min_rate)
            );
            match study.richardson {
                Some(r) => {
                    let caution = if study.plausible_order(r.order) {
                        String::new()
                    } else {
                        format!(
                            " The order is outside the range plausible for elements of degree {} (0.25 to {}): the \
                             three levels are not in the asymptotic range, or {q} does not converge monotonically; \
                             treat {q}* with caution.",
                            study.degree,
                            study.plausible_order_max()
                        )
                    };
                    let _ = writeln!(
                        s,
                        "Richardson extrapolation of {q} from the three finest levels: {q}* = {:.9e} ± {:.1e} ({:.2} %: \
                         Roache's grid convergence index, safety factor {GCI_SAFETY}, at least the change of {q}* from \
                         the previous triple), observed order p = {:.2} ({q}(h) ≈ {q}* + C h^p with C = {:.3e}); the {q} \
                         errors and rates above are against {q}*, and an error within the uncertainty is not claimed \
                         (–).{caution}",
                        r.value,
                        r.uncertainty,
                        100.0 * r.uncertainty / r.value.abs(),
                        r.order,
                        r.constant
                    );
                }
                None => {
                    let why = if study.levels.iter().filter(|l| l.converged).count() < 3 {
                        "fewer than three converged levels"
                    } else {
                        "the differences of the three finest levels do not decrease with one sign"
                    };
                    let _ = writeln!(s, "No Richardson extrapolation of {q}: {why}.");
                }
            }
        }
    }
    let _ = writeln!(s, "\n## P1 against P2 (theory §10)\n");
    match &report.element_comparison {
        Err(why) => {
            let _ = writeln!(s, "Skipped: {why}.");
        }
        Ok(c) => {
            if report.plots {
                let _ = writeln!(
                    s,
                    "![elements](elements.png)\n\n([SVG](elements.svg), data: [elements.csv](elements.csv))\n"
                );
            } else {
                let _ = writeln!(s, "Data: [elements.csv](elements.csv)\n");
            }
            s.push_str(&c.markdown());
        }
    }
    let _ = writeln!(
        s,
        "\nColumns of the CSV files: times in seconds (`_s`) or microseconds (`_us`), errors and residuals \
         relative (`_rel`), h in the scene's length unit, the columns `U` (`u` in elements.csv) the quantity \
         of interest `{q}` in its own."
    );
    s
}
