//! The report's images (cargo feature `report`), drawn by [`crate::io::plot`]:
//!
//! * `work_precision.{png,svg}`: error against wall time (theory §5), σ̂ in the energy norm and the
//!   quantity of interest (by its name) in two panels, one line with markers per solver through its converged runs; runs that stopped
//!   short are open markers off the line; errors of exactly 0 (the reference) are not drawn.
//! * `convergence.{png,svg}`: errors against the mesh size h (theory §3 Theorem 2) with a reference
//!   line of slope 1/2.
//! * `elements.{png,svg}`: the error of the quantity of interest against wall time, one line per
//!   element (theory §10).

use super::convergence::{ConvergenceStudy, LevelResult};
use super::measure::Report;
use super::runs::{Errors, RunRecord};
use crate::io::plot::{COLORS, Figure, GREY, MARKERS, Marker, Panel, PlotError, Series, lines, render};
use std::path::Path;

/// Errors below this are not drawn (exactly 0 is the reference itself).
const ERROR_FLOOR: f64 = 1e-300;

/// The solvers in ladder order.
fn solvers(runs: &[RunRecord]) -> Vec<&str> {
    let mut out: Vec<&str> = Vec::new();
    for r in runs {
        if !out.contains(&r.solver.as_str()) {
            out.push(&r.solver);
        }
    }
    out
}

/// `work_precision.png` and `.svg` (module docs).
pub fn work_precision(report: &Report, png: &Path, svg: &Path) -> Result<(), PlotError> {
    let names = solvers(&report.runs);
    let panel = |caption: &str, err: fn(&Errors) -> f64| Panel {
        caption: caption.into(),
        x_desc: "wall time (s)".into(),
        y_desc: "relative error".into(),
        series: names
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let pts = |converged: bool| {
                    let v: Vec<(f64, f64)> = report
                        .runs
                        .iter()
                        .filter(|r| r.solver == *name && r.converged == converged)
                        .filter_map(|r| r.errors.map(|e| (r.wall_s, err(&e))))
                        .filter(|p| p.0 > 0.0 && p.1 > ERROR_FLOOR && p.1.is_finite())
                        .collect();
                    // in ladder order: loose to tight settings
                    v
                };
                Series {
                    name: name.to_string(),
                    color: COLORS[i % COLORS.len()],
                    marker: MARKERS[i % MARKERS.len()],
                    line: pts(true),
                    open: pts(false),
                    dashed: false,
                    bars: vec![],
                }
            })
            .collect(),
    };
    let panels = vec![
        panel("stress (σ, ξ) in the energy norm, relative to the reference", |e| e.stress_rel),
        panel(
            &format!("{}, relative to the reference", report.quantity.as_ref().map_or("quantity", |(n, _)| n.as_str())),
            |e| e.u_rel,
        ),
    ];
    let legend = panels[0].series.clone();
    let reference = report.reference().map(|r| {
        let setting = r.setting.trim_end_matches(" (reference)");
        format!("; the reference ({} {setting}, {:.1} s) has error 0 and is not drawn", r.solver, r.wall_s)
    });
    let any_open = panels[0].series.iter().any(|s| !s.open.is_empty());
    let note = format!(
        "{}{}",
        if any_open {
            "open markers: runs that stopped short of their tolerance"
        } else {
            "filled markers: converged runs"
        },
        reference.unwrap_or_default()
    );
    let fig = Figure {
        title: format!("Work–precision: {} ({} dofs, {} cores)", report.title, report.dofs, report.cores),
        panels,
        legend,
        legend_note: Some(note),
        note_marker: any_open,
        size: (1500, 680),
    };
    render(&fig, png, svg)
}

/// `convergence.png` and `.svg` (module docs).
pub fn convergence(report: &Report, study: &ConvergenceStudy, png: &Path, svg: &Path) -> Result<(), PlotError> {
    let below = study.levels.len().saturating_sub(1);
    let levels = &study.levels[..below];
    let pts = |f: fn(&LevelResult) -> f64| -> Vec<(f64, f64)> {
        levels.iter().map(|l| (l.size.h(), f(l))).filter(|p| p.1 > ERROR_FLOOR && p.1.is_finite()).collect()
    };
    let mut series = vec![
        Series {
            name: "stress (σ, ξ), energy norm, vs finest".into(),
            color: COLORS[0],
            marker: Marker::Circle,
            line: pts(|l| l.err_stress),
            open: vec![],
            dashed: false,
            bars: vec![],
        },
        Series {
            name: "stress (σ, ξ), difference to the next level".into(),
            color: COLORS[3],
            marker: Marker::Cross,
            line: pts(|l| l.diff_stress_next),
            open: vec![],
            dashed: false,
            bars: vec![],
        },
        Series {
            name: "strain ε(u), L², vs finest".into(),
            color: COLORS[2],
            marker: Marker::Square,
            line: pts(|l| l.err_strain),
            open: vec![],
            dashed: false,
            bars: vec![],
        },
    ];
    if let Some(r) = study.richardson {
        // errors within the extrapolation's uncertainty are NaN (not claimed); the bars span
        // the error ± the uncertainty (relative)
        let line: Vec<(f64, f64)> = study
            .levels
            .iter()
            .map(|l| (l.size.h(), l.err_u_richardson))
            .filter(|p| p.1 > ERROR_FLOOR && p.1.is_finite())
            .collect();
        let u = r.uncertainty / r.value.abs();
        let bars = line.iter().map(|&(h, e)| (h, (e - u).max(ERROR_FLOOR), e + u)).collect();
        series.push(Series {
            name: format!("{} vs Richardson extrapolation (bars: its uncertainty ±{:.1e})", study.quantity, u),
            color: COLORS[1],
            marker: Marker::Triangle,
            line,
            open: vec![],
            dashed: false,
            bars,
        });
    } else {
        series.push(Series {
            name: format!("{} vs finest", study.quantity),
            color: COLORS[1],
            marker: Marker::Triangle,
            line: pts(|l| l.err_u),
            open: vec![],
            dashed: false,
            bars: vec![],
        });
    }
    // the other element of the P1–P2 comparison: its σ̂ errors against its own finest level
    if let Ok(c) = &report.element_comparison {
        // (the scene's own element is `study` itself: the same levels)
        let dofs = |s: &ConvergenceStudy| s.levels.iter().map(|l| l.dofs).collect::<Vec<_>>();
        for (i, (name, other)) in c.studies.iter().enumerate().filter(|(_, (_, s))| dofs(s) != dofs(study)) {
            let below = other.levels.len().saturating_sub(1);
            series.push(Series {
                name: format!("{name}: stress (σ, ξ), energy norm, vs its finest (element means)"),
                color: COLORS[(4 + i) % COLORS.len()],
                marker: Marker::Circle,
                line: other.levels[..below]
                    .iter()
                    .map(|l| (l.size.h(), l.err_stress))
                    .filter(|p| p.1 > ERROR_FLOOR && p.1.is_finite())
                    .collect(),
                open: vec![],
                dashed: true,
                bars: vec![],
            });
        }
    }
    // slope 1/2 through the coarsest σ̂ error (Theorem 2's guarantee)
    if let (Some(first), Some(h_min)) =
        (series[0].line.first().copied(), study.levels.iter().map(|l| l.size.h()).reduce(f64::min))
    {
        let (h0, e0) = first;
        series.push(Series {
            name: "slope 1/2 (Theorem 2)".into(),
            color: GREY,
            marker: Marker::Circle,
            line: vec![(h0, e0), (h_min, e0 * (h_min / h0).sqrt())],
            open: vec![],
            dashed: true,
            bars: vec![],
        });
    }
    let x_desc = "h: mean element size (|Ω|/elements)^(1/3), length units";
    let panel = Panel {
        caption: "relative errors against the finest level".into(),
        x_desc: x_desc.into(),
        y_desc: "relative error".into(),
        series,
    };
    let legend = panel.series.clone();
    let fig = Figure {
        title: format!("Mesh convergence: {}", report.title),
        panels: vec![panel],
        legend,
        legend_note: None,
        note_marker: false,
        size: (1000, 760),
    };
    render(&fig, png, svg)
}

/// `elements.png` and `.svg`: the error of the quantity of interest `quantity` against the wall
/// time of each level, one line per element (theory §10).
pub fn elements(series: &[(String, Vec<(f64, f64)>)], quantity: &str, png: &Path, svg: &Path) -> Result<(), PlotError> {
    let (caption, y) = (format!("error of {quantity} against wall time"), format!("relative error of {quantity}"));
    let labels = ["saddle report: p1 against p2", caption.as_str(), "wall time of the solve (s)", y.as_str()];
    lines(series, labels, false, png, svg)
}
