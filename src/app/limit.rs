//! `saddle limit`: the collapse multiplier of a scene's loads for its yield surface taken
//! perfectly plastic, as one conic solve (theory §13, [`saddle_solvers::limit`]). Writes
//! `limit.json` (both bounds, the gap, the sizes, each obstacle's collapse force) and
//! `mechanism.vtu` (the collapse velocity, the dissipation density, the collapse stress).
//!
//! ```text
//! saddle limit examples/strip_punch.toml --out out/strip_limit
//! ```

use super::setup::{RunError, load_with};
use crate::io::outdir::{OutDir, OutError};
use crate::io::scene::element_by_type;
use crate::io::vtu::{DataArray, f64_bytes, write_grid};
use saddle_core::problem::tensor::{to_vtk, von_mises};
use saddle_core::{DiscreteProblem, Sym};
use saddle_solvers::{Collapse, LimitAnalysis, LimitError};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why `saddle limit` failed.
#[derive(Debug, Error)]
pub enum LimitRunError {
    /// The scene could not be read or assembled, or `--discretisation` names no element.
    #[error(transparent)]
    Run(#[from] RunError),
    /// The limit analysis failed (elastic scene, no conic form, no load, unbounded, …).
    #[error(transparent)]
    Limit(#[from] LimitError),
    /// `--out` cannot be used, or a file in it cannot be written.
    #[error(transparent)]
    Out(#[from] OutError),
    /// A file could not be written.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// One obstacle at collapse, in `limit.json`.
#[derive(Clone, Debug, Serialize)]
pub struct ObstacleCollapse {
    /// Its collapse force (Σ of its contact forces at collapse; null when the plugin reports
    /// none).
    pub force: Option<f64>,
    /// Its contact nodes at collapse.
    pub contact_nodes: usize,
}

/// `limit.json`.
#[derive(Clone, Debug, Serialize)]
pub struct LimitSummary {
    /// The scene's title.
    pub title: Option<String>,
    /// λ⁺, the kinematic value: the collapse load is this times the scene's loads.
    pub multiplier: f64,
    /// λ⁻, the static value.
    pub dual_multiplier: f64,
    /// λ⁺ − λ⁻.
    pub gap: f64,
    /// (λ⁺ − λ⁻)/λ⁺.
    pub relative_gap: f64,
    /// Wall time of the conic solve (programme, interior point, recovery), s.
    pub wall_s: f64,
    /// Wall time per phase of the run, s (`read`, `setup`, `limit`, `write`).
    pub end_to_end: BTreeMap<String, f64>,
    /// Free displacement dofs.
    pub dofs: usize,
    /// Second-order cones.
    pub cones: usize,
    /// Variables of the programme.
    pub variables: usize,
    /// Its stress unknowns (coordinates per point and merged per element, theory §13.3).
    pub stress_unknowns: usize,
    /// Obstacle rows closed in the reference configuration.
    pub closed_rows: usize,
    /// The element (`p1`, `p2`) and the yield surface's `type`.
    pub discretisation: String,
    /// The yield surface's `type`.
    pub yield_surface: String,
    /// Clarabel's status, iterations and relative primal and dual residuals.
    pub status: String,
    /// Interior-point iterations.
    pub iterations: usize,
    /// Clarabel's residuals.
    pub residuals: [f64; 2],
    /// Each obstacle by name (`obstacle` for a single unnamed one) at collapse.
    pub obstacles: BTreeMap<String, ObstacleCollapse>,
    /// The solve's phases, s.
    pub phases: BTreeMap<String, f64>,
    /// Warnings (hardening ignored, a locking element, open rows, regularisation).
    pub warnings: Vec<String>,
}

impl LimitSummary {
    /// The summary of `c` on `problem`.
    pub fn new(problem: &DiscreteProblem, c: &Collapse, title: Option<String>) -> Self {
        let obstacles = c
            .obstacles
            .iter()
            .map(|o| {
                let name = o.name.clone().unwrap_or_else(|| "obstacle".into());
                (name, ObstacleCollapse { force: o.report.get("force"), contact_nodes: o.report.contact_nodes })
            })
            .collect();
        Self {
            title,
            multiplier: c.multiplier,
            dual_multiplier: c.dual_multiplier,
            gap: c.gap,
            relative_gap: c.relative_gap(),
            wall_s: c.wall_s,
            end_to_end: BTreeMap::new(),
            dofs: c.dofs,
            cones: c.cones,
            variables: c.variables,
            stress_unknowns: c.stress_unknowns,
            closed_rows: c.closed_rows,
            discretisation: problem.element.name().into(),
            yield_surface: problem.stresses.as_ref().map_or("none".into(), |p| p.name().into()),
            status: c.status.clone(),
            iterations: c.iterations,
            residuals: c.residuals,
            obstacles,
            phases: c.phases.iter().cloned().collect(),
            warnings: c.warnings.clone(),
        }
    }
}

/// Writes `mechanism.vtu`: point `velocity` (the mechanism, ℓ(v) = 1); cell `dissipation` (the
/// density π(ε(v)), element mean over its points), `stress` and `von_mises` (the collapse
/// stress, element mean).
pub fn write_mechanism(path: &Path, problem: &DiscreteProblem, c: &Collapse) -> std::io::Result<()> {
    let element = &*problem.element;
    let k = element.points_per_element();
    let velocity = element.nodal_vectors(&c.velocity);
    let mean_stress: Vec<Sym> = c.stress.chunks(k).map(|s| s.iter().sum::<Sym>() / k as f64).collect();
    let dissipation = c.dissipation.chunks(k).map(|d| d.iter().sum::<f64>() / k as f64);
    let arrays: Vec<DataArray> = vec![
        ("point", "velocity", 3, f64_bytes(velocity.iter().flatten().copied())),
        ("cell", "dissipation", 1, f64_bytes(dissipation)),
        ("cell", "stress", 6, f64_bytes(mean_stress.iter().flat_map(to_vtk))),
        ("cell", "von_mises", 1, f64_bytes(mean_stress.iter().map(von_mises))),
    ];
    write_grid(path, element, arrays).map(drop)
}

/// What `saddle limit` produced.
pub struct LimitOutcome {
    /// The collapse.
    pub collapse: Collapse,
    /// `limit.json`'s content.
    pub summary: LimitSummary,
    /// The files written.
    pub written: Vec<String>,
}

/// `saddle limit SCENE --out DIR [--discretisation TYPE]`: the scene read (its `[solver]`
/// ignored), its collapse computed with `settings`, `limit.json` and `mechanism.vtu` written.
/// The folder is claimed before the solve; nothing is written when the analysis fails.
pub fn run(
    scene: &Path,
    out_dir: &Path,
    element: Option<&str>,
    settings: &LimitAnalysis,
) -> Result<LimitOutcome, LimitRunError> {
    let element = element.map(element_by_type).transpose().map_err(RunError::from)?;
    let loaded = load_with(scene, None, |s| {
        if let Some(e) = element {
            s.discretisation = Some(e);
        }
        Ok(())
    })?;
    let mut out = OutDir::claim(out_dir)?;
    let mut timer = loaded.timer.clone();
    let collapse = match timer.time("limit", || settings.solve(&loaded.problem)) {
        Ok(c) => c,
        Err(e) => {
            out.abandon();
            return Err(e.into());
        }
    };
    let mut summary = LimitSummary::new(&loaded.problem, &collapse, loaded.title.clone());
    let io = |path: PathBuf| move |source| LimitRunError::Io { path, source };
    let vtu = out_dir.join("mechanism.vtu");
    timer.time("write", || write_mechanism(&vtu, &loaded.problem, &collapse)).map_err(io(vtu.clone()))?;
    out.wrote("mechanism.vtu")?;
    summary.end_to_end = timer.into_phases().into_iter().collect();
    let json = out_dir.join("limit.json");
    let text = serde_json::to_string_pretty(&summary).expect("the summary serialises");
    std::fs::write(&json, text + "\n").map_err(io(json.clone()))?;
    out.wrote("limit.json")?;
    let written = out.finish()?;
    Ok(LimitOutcome { collapse, summary, written })
}
