//! `saddle report` end to end: the measurements ([`super::measure`]) on the scene and its
//! refined meshes, written as CSV files, images and `report.md` (the files of the module docs of
//! [`super`]).

use super::convergence::{family_cells, family_levels, refinement_levels};
use super::elements::{self, ElementComparison};
#[cfg(feature = "report")]
use super::figures;
use super::measure::{
    LEVELS, Progress, QUICK_LEVELS, Report, ReportError, ReportOptions, SceneSource, convergence_study_of,
    work_precision,
};
use super::runs::{RungKind, ladder};
use super::tables;
use crate::io::summary::{first_quantity, reported_quantities};
use std::path::Path;
use std::time::Instant;

/// Makes the report of the scene file `scene` in `out` (module docs).
pub fn generate(
    scene: &Path,
    out: &Path,
    options: &ReportOptions,
    progress: &mut dyn Progress,
) -> Result<Report, ReportError> {
    let t0 = Instant::now();
    let source = SceneSource::read(scene)?;
    let l = source.problem(None)?;
    let quantity = quantity_of(&source, &l, options)?;
    let q = quantity.as_ref().map(|(n, _)| n.as_str());
    let rungs = ladder(options.quick);
    let base = source.box_cells();
    let asked = asked_levels(&source, options)?;
    let levels: Result<Vec<[usize; 3]>, String> = base.clone().map(|base| {
        let factors: &[f64] = if options.quick { &QUICK_LEVELS } else { &LEVELS };
        // a mesh family's levels are multiples of its base (same grading and alignment)
        let mut levels = match (source.scene.mesh.family_base(), &asked) {
            (Some(family), Some(ks)) => family_cells(family, ks),
            (Some(family), None) => family_levels(family, base, factors),
            (None, _) => refinement_levels(base, factors),
        };
        if !levels.contains(&base) {
            levels.push(base);
            levels.sort_by_key(|c| c[0] * c[1] * c[2]);
        }
        levels
    });
    // every level, the scene's own too, is solved by the level solver (its time is what the
    // P1–P2 comparison weighs; the work–precision reference runs on the direct backend)
    let other_levels = levels.as_ref().map_or(0, |v| v.len());
    // the other element's levels, on meshes with the same nodes (theory §10)
    let own = source.scene.element_name();
    let other = if own == "p2" { "p1" } else { "p2" };
    let other_levels_cells = levels
        .as_ref()
        .ok()
        .filter(|v| v.len() >= 2)
        .map(|v| match (other, source.scene.mesh.family_base()) {
            ("p2", Some(family)) => elements::p2_family_levels(v, family),
            ("p2", None) => elements::p2_levels(v),
            _ => elements::p1_levels(v),
        })
        .filter(|v| !v.is_empty());
    let solves = 1
        + rungs.iter().filter(|r| !matches!(r.kind, RungKind::Reference)).count()
        + other_levels
        + other_levels_cells.as_ref().map_or(0, |v| v.len());
    progress.plan(solves);
    let mut counter = 0;
    std::fs::create_dir_all(out).map_err(|source| ReportError::Io { path: out.to_path_buf(), source })?;
    let runs = work_precision(&l, &rungs, q, progress, &mut counter)?;
    let (dofs, elements, contact_rows) = (l.element.n_dofs(), l.element.n_points(), l.obstacles.rows().n_rows());
    let convergence = match levels {
        Ok(levels) if levels.len() >= 2 => Ok(convergence_study_of(&source, &levels, q, progress, &mut counter)?),
        Ok(_) => Err("the scene's mesh is too coarse to coarsen (fewer than two distinct levels)".to_string()),
        Err(why) => Err(why),
    };
    let comparison = match (&convergence, other_levels_cells) {
        (Ok(own_study), Some(cells)) => {
            let element: Box<dyn saddle_core::FiniteElement> =
                if other == "p2" { Box::new(saddle_core::P2::default()) } else { Box::new(saddle_core::P1::default()) };
            let other_source = SceneSource { scene: source.scene.with_element(element), ..source.clone() };
            let other_study = convergence_study_of(&other_source, &cells, q, progress, &mut counter)?;
            Ok(if other == "p2" {
                ElementComparison::new(own_study.clone(), other_study)
            } else {
                ElementComparison::new(other_study, own_study.clone())
            })
        }
        (Err(why), _) => Err(why.clone()),
        (Ok(_), None) => Err("no levels to compare".to_string()),
    };
    let mut report = Report {
        scene: scene.to_path_buf(),
        title: source.title(),
        dofs,
        elements,
        contact_rows,
        quick: options.quick,
        levels: asked,
        quantity,
        cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
        runs,
        scene_cells: base.ok(),
        convergence,
        element_comparison: comparison,
        total_s: 0.0,
        plots: cfg!(feature = "report"),
    };
    write_outputs(&mut report, out, t0)?;
    Ok(report)
}

/// The quantity of interest of the report on `source` (assembled as `l`): the one named by
/// `--quantity`, checked against the quantities the scene reports ([`reported_quantities`]), else
/// the scene's first extra unknown ([`first_quantity`]); with whether it was asked for.
fn quantity_of(
    source: &SceneSource,
    l: &saddle_core::DiscreteProblem,
    options: &ReportOptions,
) -> Result<Option<(String, bool)>, ReportError> {
    let Some(name) = &options.quantity else { return Ok(first_quantity(l.view()).map(|n| (n, false))) };
    let known = reported_quantities(l.view());
    if known.contains(name) {
        Ok(Some((name.clone(), true)))
    } else {
        Err(ReportError::Quantity { name: name.clone(), known: known.join(", "), scene: source.path.clone() })
    }
}

/// The family levels of `--levels`, checked (at least one, each k ≥ 1, on a scene whose mesh is a
/// family: `mesh.base`, theory §7.3), ascending without repeats.
fn asked_levels(source: &SceneSource, options: &ReportOptions) -> Result<Option<Vec<usize>>, ReportError> {
    let Some(ks) = &options.levels else { return Ok(None) };
    let why = if ks.is_empty() || ks.contains(&0) {
        Some("the levels k of a mesh family are 1, 2, 3, …")
    } else if source.scene.mesh.family_base().is_none() {
        Some("the scene's mesh is not a mesh family (no `mesh.base`)")
    } else {
        None
    };
    match why {
        Some(why) => Err(ReportError::Levels { levels: ks.clone(), why, scene: source.path.clone() }),
        None => {
            let mut ks = ks.clone();
            ks.sort_unstable();
            ks.dedup();
            Ok(Some(ks))
        }
    }
}

/// Writes the CSV files, the images (feature `report`) and `report.md`; the total time is taken
/// just before `report.md`.
fn write_outputs(report: &mut Report, out: &Path, t0: Instant) -> Result<(), ReportError> {
    let write = |name: &str, text: &str| {
        let path = out.join(name);
        std::fs::write(&path, text).map_err(|source| ReportError::Io { path, source })
    };
    write("work_precision.csv", &tables::work_precision_csv(&report.runs))?;
    write("convergence.csv", &tables::convergence_csv(report.convergence.as_ref().ok()))?;
    if let Ok(c) = &report.element_comparison {
        write("elements.csv", &c.csv())?;
    }
    #[cfg(feature = "report")]
    {
        figures::work_precision(report, &out.join("work_precision.png"), &out.join("work_precision.svg"))?;
        if let Ok(study) = &report.convergence {
            figures::convergence(report, study, &out.join("convergence.png"), &out.join("convergence.svg"))?;
        }
        if let Ok(c) = &report.element_comparison {
            figures::elements(&c.series(), &c.quantity, &out.join("elements.png"), &out.join("elements.svg"))?;
        }
    }
    report.total_s = t0.elapsed().as_secs_f64();
    write("report.md", &tables::markdown(report))?;
    Ok(())
}
