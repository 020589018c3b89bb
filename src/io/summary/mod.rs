//! `summary.json`: the numbers of a solve that scripts read (the fields for ParaView are
//! [`super::vtu`]'s).
//!
//! The summary knows no particular obstacle: every obstacle reports its own quantities by name
//! ([`saddle_core::ObstacleReport`]), listed under `obstacles`; the extra unknowns are listed by
//! name under `extras`. The older keys `U`, `force`, `contact_nodes`, `contact_radius` and
//! `contact` are filled from the obstacle's report when the scene has exactly one.

pub mod estimate;
pub mod locking;

use saddle_core::fem::supports::Reaction;
use saddle_core::problem::tensor::von_mises;
use saddle_core::{
    Discretisation, Elasticity, KktResiduals, MeshQuality, ObstacleReport, ProblemView, Solution, StopReason,
    Workspace, dual_energy, energy, kkt,
};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// The numbers of a solve, written as `summary.json`. The keys are an interface: extend, do
/// not rename.
#[derive(Clone, Debug, Serialize)]
#[allow(non_snake_case)]
pub struct Summary {
    /// Scene title.
    pub title: Option<String>,
    /// Solver type.
    pub solver: String,
    /// True when the solver met its tolerance.
    pub converged: bool,
    /// Why it stopped.
    pub stop_reason: StopReason,
    /// Outer iterations.
    pub iterations: usize,
    /// Wall time of the solve in seconds (set-up of the problem excluded).
    pub wall_s: f64,
    /// The quantity `U` of the obstacle's report (null without obstacle, with several
    /// obstacles, or when the obstacle reports no `U`; see `obstacles`).
    pub U: Option<f64>,
    /// The quantity `force` of the obstacle's report (null as `U`).
    pub force: Option<f64>,
    /// Number of contact nodes (the total over the obstacles).
    pub contact_nodes: usize,
    /// Largest distance of a contact node from its obstacle's centre (the largest over the
    /// obstacles).
    pub contact_radius: f64,
    /// Number of plastic elements (an element is plastic when one of its stress points is).
    pub plastic_elements: usize,
    /// Number of plastic stress points (equal to `plastic_elements` for `p1`, one point per
    /// element).
    pub plastic_points: usize,
    /// Largest von Mises stress sqrt(3/2)|dev σ| (after unloading: of the residual stresses).
    pub max_von_mises: f64,
    /// Largest equivalent plastic strain √(2/3)|ε_p| over the stress points, ε_p = ε(u) − Aσ
    /// (theory §11.1; Hencky's plastic strain for a one-step solve).
    pub max_equivalent_plastic_strain: f64,
    /// Primal energy J(u, U).
    pub J: f64,
    /// Dual energy −(½[σ̂,σ̂] + λ·c).
    pub dual_energy: f64,
    /// The largest relative KKT residual, recomputed independently of the solver.
    pub kkt_residual: f64,
    /// Its components.
    pub kkt: KktResiduals,
    /// The tolerance asked of the solver.
    pub tolerance: f64,
    /// Free displacement dofs.
    pub dofs: usize,
    /// Tetrahedra.
    pub elements: usize,
    /// Stress points (the elements for `p1`, four per element for `p2`).
    pub stress_points: usize,
    /// The finite element (`p1`, `p2`).
    pub discretisation: String,
    /// Nodes (vertices, and the edge nodes of a second-order mesh).
    pub nodes: usize,
    /// The locking indicator (theory §10): the volume fraction of the body whose response at
    /// the solution is nearly incompressible (effective Poisson ratio of the tangent ≥ 0.49,
    /// [`locking`]). Above 0.1 a `p1` solution is warned about.
    pub near_incompressible_fraction: f64,
    /// Rows of K_h (candidate contact nodes).
    pub contact_rows: usize,
    /// Everything the obstacle reports (U, force, peak and mean contact pressure, ...); with
    /// several obstacles every quantity as `name.quantity`.
    pub contact: BTreeMap<String, f64>,
    /// The extra unknowns V by name (`U`; with several obstacles `left.U`, ...); null when
    /// undetermined (a force-controlled obstacle without load in a load step, theory §11.3).
    pub extras: BTreeMap<String, Option<f64>>,
    /// One entry per obstacle, in the scene's order.
    pub obstacles: Vec<ObstacleSummary>,
    /// The reaction of every `[[dirichlet]]` entry (theory §14), keyed by its `name` or
    /// `dirichlet[i]`: `force` = Σ(Bᵀσ − f) over the dofs it fixes, `moment` about the origin.
    /// Empty under `mpirun`.
    pub reactions: BTreeMap<String, Reaction>,
    /// Element shape statistics (aspect ratio: 1 for a regular tetrahedron).
    pub mesh_quality: MeshQuality,
    /// Wall time per solver phase.
    pub phases: BTreeMap<String, f64>,
    /// Wall time of a `saddle run` end to end, per phase: `read` (scene file and mesh),
    /// `setup` (L assembled), `solve`, `summary` (residuals recomputed), `write`
    /// (solution.vtu). Empty when the summary is made outside a run.
    pub end_to_end: BTreeMap<String, f64>,
    /// Their sum: what the user waited for (summary.json itself excluded).
    pub end_to_end_s: f64,
    /// Solver-specific counters.
    pub counters: BTreeMap<String, f64>,
    /// Relative KKT residual per iteration.
    pub residual_history: Vec<f64>,
    /// Warnings from the plugins and the solver.
    pub warnings: Vec<String>,
    /// The a posteriori error estimate (theory §15): `energy`, one entry per extra by name, its
    /// cost; null when `[output] error_estimate = false`, under `mpirun` and for load paths.
    pub error_estimate: Option<estimate::EstimateSummary>,
    /// With a `[load_path]`: one entry per step solved (theory §11); the keys above describe
    /// the last step. Absent for a one-step solve.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub steps: Vec<StepSummary>,
    /// With a `[load_path]`: the path as a whole (factors, whether it completed, totals, the
    /// residual state after unloading). Absent for a one-step solve.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub load_path: Option<PathSummary>,
    /// Under `mpirun` (theory §12): the number of ranks. Absent on one machine.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ranks: Option<usize>,
    /// Under `mpirun`: each rank's part, time and memory, in rank order. Absent on one machine.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub per_rank: Vec<RankSummary>,
}

/// One rank's share of a distributed run (theory §12), in `summary.json`'s `per_rank`.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct RankSummary {
    /// The rank.
    pub rank: usize,
    /// Its elements.
    pub elements: usize,
    /// The dofs it owns.
    pub owned_dofs: usize,
    /// The nodes of its elements it does not own (its ghost layer).
    pub ghost_nodes: usize,
    /// Its wall time of the whole run so far (read, set-up, solve, summary, write), seconds.
    pub wall_s: f64,
    /// Its wall time in the solver, seconds.
    pub solve_s: f64,
    /// Its peak resident memory (the kernel's VmHWM), MB; 0 where the system does not say.
    pub peak_memory_mb: f64,
}

/// What a summary takes from the whole problem (theory §12): the obstacles' reports
/// ([`imprints`] and [`complete_reports`] added), the mesh's quality and its number of nodes. On
/// one machine the problem's own; under `mpirun`, rank 0's, made from what it kept of the whole
/// problem (the other ranks' summary is not written: they pass no reports and their part's
/// quality).
pub struct Whole {
    /// Each obstacle's report.
    pub reports: Vec<ObstacleReport>,
    /// The mesh's quality.
    pub quality: saddle_core::mesh::MeshQuality,
    /// The mesh's nodes.
    pub nodes: usize,
}

/// One step of a load path in `summary.json` (theory §11): the keys of a one-step summary.
#[derive(Clone, Debug, Serialize)]
#[allow(non_snake_case)]
pub struct StepSummary {
    /// The step's index (from 0; the number in its `solution_NNNN.vtu`).
    pub step: usize,
    /// The load factor.
    pub factor: f64,
    /// The factors of the loads with factors of their own (`[load_path.loads]`, theory §11.2).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub loads: BTreeMap<String, f64>,
    /// True when the solver met its tolerance.
    pub converged: bool,
    /// Why it stopped, or `error` when the solver failed (see `error`).
    pub stop_reason: String,
    /// The solver's error, when it failed.
    pub error: Option<String>,
    /// Outer iterations.
    pub iterations: usize,
    /// The recomputed relative KKT residual of the step (null after an error).
    pub kkt_residual: Option<f64>,
    /// The obstacle's `U` (null when undetermined or not reported).
    pub U: Option<f64>,
    /// The obstacle's `force`.
    pub force: Option<f64>,
    /// The extras by name (null when undetermined).
    pub extras: BTreeMap<String, Option<f64>>,
    /// Everything the obstacles report, with `imprint` (null when undetermined).
    pub contact: BTreeMap<String, f64>,
    /// The supports' reactions, as in a one-step summary.
    pub reactions: BTreeMap<String, Reaction>,
    /// Contact nodes.
    pub contact_nodes: usize,
    /// Plastic elements (a stress point of the element plastic in this step).
    pub plastic_elements: usize,
    /// Plastic stress points.
    pub plastic_points: usize,
    /// Largest von Mises stress.
    pub max_von_mises: f64,
    /// Largest equivalent plastic strain (accumulated along the path).
    pub max_equivalent_plastic_strain: f64,
    /// Primal energy of the step problem.
    pub J: Option<f64>,
    /// Wall time of the step: set-up, solve, summary and output.
    pub wall_s: f64,
    /// The step's VTU file (null when the solver failed, or beyond 100 steps for a step whose
    /// file is not written: `app::path::MAX_STEP_FILES`).
    pub file: Option<String>,
    /// Warnings of the step.
    pub warnings: Vec<String>,
    /// Halvings of the planned increment before this step was solved (theory §11.5; 0: as
    /// planned); the attempts that failed are in `load_path.cuts`.
    pub cuts: usize,
}

impl StepSummary {
    /// The step entry of a step's full summary.
    pub fn new(step: usize, factor: f64, s: &Summary, file: Option<String>, wall_s: f64) -> Self {
        Self {
            step,
            factor,
            loads: BTreeMap::new(),
            converged: s.converged,
            stop_reason: serde_json::to_value(s.stop_reason)
                .ok()
                .and_then(|v| v.as_str().map(String::from))
                .unwrap_or_default(),
            error: None,
            iterations: s.iterations,
            kkt_residual: Some(s.kkt_residual),
            U: s.U,
            force: s.force,
            extras: s.extras.clone(),
            contact: s.contact.clone(),
            reactions: s.reactions.clone(),
            contact_nodes: s.contact_nodes,
            plastic_elements: s.plastic_elements,
            plastic_points: s.plastic_points,
            max_von_mises: s.max_von_mises,
            max_equivalent_plastic_strain: s.max_equivalent_plastic_strain,
            J: Some(s.J),
            wall_s,
            file,
            warnings: s.warnings.clone(),
            cuts: 0,
        }
    }

    /// The entry of a step whose solver failed with `error`.
    pub fn failed(step: usize, factor: f64, error: String, wall_s: f64) -> Self {
        Self {
            step,
            factor,
            loads: BTreeMap::new(),
            converged: false,
            stop_reason: "error".into(),
            error: Some(error),
            iterations: 0,
            kkt_residual: None,
            U: None,
            force: None,
            extras: BTreeMap::new(),
            contact: BTreeMap::new(),
            reactions: BTreeMap::new(),
            contact_nodes: 0,
            plastic_elements: 0,
            plastic_points: 0,
            max_von_mises: f64::NAN,
            max_equivalent_plastic_strain: f64::NAN,
            J: None,
            wall_s,
            file: None,
            warnings: Vec::new(),
            cuts: 0,
        }
    }

    /// The quantity `name`: a reported one (`U`, `force`, `imprint`, …), an extra, a reaction's
    /// component (`grip.Fx`, [`reaction_quantities`]), or `factor`.
    pub fn get(&self, name: &str) -> Option<f64> {
        if name == "factor" {
            return Some(self.factor);
        }
        (self.contact.get(name).copied())
            .or_else(|| self.extras.get(name).copied().flatten())
            .or_else(|| reaction_quantities(&self.reactions).find(|(n, _)| n == name).map(|(_, v)| v))
            .filter(|v| v.is_finite())
    }
}

/// The load path as a whole, in `summary.json` under `load_path`.
#[derive(Clone, Debug, Serialize)]
pub struct PathSummary {
    /// The scene's factors.
    pub factors: Vec<f64>,
    /// The scene's `[load_path.loads]`: the loads with factors of their own.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub loads: BTreeMap<String, Vec<f64>>,
    /// Sub-steps between factors.
    pub substeps: usize,
    /// The factor of every planned step.
    pub step_factors: Vec<f64>,
    /// Steps solved (the failed one included).
    pub steps_done: usize,
    /// True when every step converged.
    pub completed: bool,
    /// The step that stopped the path (failed or not converged).
    pub failed_step: Option<usize>,
    /// Why it stopped.
    pub error: Option<String>,
    /// Outer iterations of all steps.
    pub total_iterations: usize,
    /// Wall time of all steps (set-up, solve, summary, output).
    pub total_wall_s: f64,
    /// The residual state, when the path ends converged at load factor 0 (theory §11.4).
    pub residual: Option<ResidualState>,
    /// The step cutting settings (theory §11.5).
    pub max_cuts: usize,
    /// The smallest increment step cutting may try.
    pub min_step: f64,
    /// Every attempt that failed and was retried with half the increment, in order.
    pub cuts: Vec<CutAttempt>,
    /// The smallest increment of the load factor tried (null without cuts).
    pub smallest_step: Option<f64>,
}

/// A step that failed and was retried with half the increment (theory §11.5).
#[derive(Clone, Debug, Serialize)]
pub struct CutAttempt {
    /// The index the retried step has in `steps`.
    pub step: usize,
    /// The factor the failed attempt was at ...
    pub factor: f64,
    /// ... from this one (the last solved) ...
    pub from: f64,
    /// ... and the factor retried.
    pub retry: f64,
    /// Why the attempt failed.
    pub reason: String,
}

/// What unloading leaves (theory §11.4), summarised.
#[derive(Clone, Debug, Serialize)]
pub struct ResidualState {
    /// Each obstacle's imprint: the largest displacement of its candidate nodes away from it
    /// (`imprint`, or `name.imprint`).
    pub imprint: BTreeMap<String, f64>,
    /// The largest von Mises stress of the residual stresses.
    pub max_von_mises: f64,
    /// The largest equivalent plastic strain.
    pub max_equivalent_plastic_strain: f64,
}

/// The components of the reactions as named quantities: `key.Fx`, `key.Fy`, `key.Fz`, `key.Mx`,
/// `key.My`, `key.Mz` of every entry (a plot axis, a column of `load_path.csv`).
pub fn reaction_quantities(reactions: &BTreeMap<String, Reaction>) -> impl Iterator<Item = (String, f64)> + '_ {
    reactions.iter().flat_map(|(k, r)| {
        let values = r.force.iter().chain(&r.moment);
        ["Fx", "Fy", "Fz", "Mx", "My", "Mz"].into_iter().zip(values).map(move |(c, v)| (format!("{k}.{c}"), *v))
    })
}

/// The reactions of a view's supports to the stresses `sigma`, keyed (theory §14).
fn reactions_of(p: ProblemView<'_>, sigma: &[saddle_core::Sym]) -> BTreeMap<String, Reaction> {
    p.reactions(sigma).into_iter().map(|r| (r.key.clone(), r)).collect()
}

/// What one obstacle reports, as written in `summary.json`: its name, type, contact set, and
/// every quantity of its report as its own key (`force`, `U`, ...).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ObstacleSummary {
    /// The obstacle's name (null for a single unnamed obstacle).
    pub name: Option<String>,
    /// The plugin's `type`.
    #[serde(rename = "type")]
    pub type_name: String,
    /// Number of its contact nodes.
    pub contact_nodes: usize,
    /// Largest distance of its contact nodes from its centre.
    pub contact_radius: f64,
    /// Its quantities by name (a quantity named like one of the keys above is left out here
    /// and kept in `contact`).
    #[serde(flatten)]
    pub quantities: BTreeMap<String, f64>,
}

impl ObstacleSummary {
    /// The summary of one report.
    pub fn new(r: &ObstacleReport) -> Self {
        let fixed = ["name", "type", "contact_nodes", "contact_radius"];
        Self {
            name: r.name.clone(),
            type_name: r.type_name.clone(),
            contact_nodes: r.report.contact_nodes,
            contact_radius: r.report.contact_radius,
            quantities: r.report.quantities.iter().filter(|(k, _)| !fixed.contains(&k.as_str())).cloned().collect(),
        }
    }

    /// The quantity `name`, if reported.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.quantities.get(name).copied()
    }
}

/// The quantity `name` of `sol` as a summary of `p` reports it ([`reported_quantities`]): an
/// obstacle's quantity (plain with one obstacle, `name.quantity` with several, as in `contact`),
/// an extra unknown by its name (`left.U`; NaN when undetermined, theory §11.3), or a component of
/// a support's reaction (`key.Fz`, theory §14). None when nothing is so named.
pub fn named_quantity(p: ProblemView<'_>, sol: &Solution, name: &str) -> Option<f64> {
    let reports = reports_with_imprints(p, &sol.u, &sol.extras, &sol.lambda, &sol.undetermined);
    if let Some(v) = contact_entries(p, &reports).get(name) {
        return Some(*v);
    }
    if let Some(i) = p.extra_names().iter().position(|n| n == name) {
        return Some(if sol.undetermined.contains(&i) { f64::NAN } else { sol.extras.get(i).copied()? });
    }
    reaction_quantities(&reactions_of(p, &sol.stress.sigma)).find(|(n, _)| n == name).map(|(_, v)| v)
}

/// The quantity of interest of `p` when none is named: its first extra unknown by the name its
/// obstacle gives it (`extra_names`, prefixed `name.` for a named obstacle), else the first
/// quantity its first obstacle reports (as `contact` names it); None without obstacles.
pub fn first_quantity(p: ProblemView<'_>) -> Option<String> {
    if let Some(n) = p.extra_names().into_iter().next() {
        return Some(n);
    }
    let reports = p.contact_reports(&vec![0.0; p.l.n_extras()], &vec![0.0; p.l.n_rows()]);
    let q = reports.first()?.report.quantities.first()?.0.clone();
    Some(match reports.len() {
        1 => q,
        _ => {
            let name = reports[0].name.clone().unwrap_or_else(|| p.obstacles.obstacles().path("obstacle", 0));
            format!("{name}.{q}")
        }
    })
}

/// Each obstacle's report on the solution (`u`, `extras`, `lambda`), with its imprint
/// max_i (G u)_i over its normal rows, the largest displacement of its candidate nodes away from it
/// (theory §11.4; generic, from the rows), the quantities named like an extra in
/// `undetermined` (theory §11.3) NaN: written null, and with friction `dissipated_energy`, the
/// energy friction has dissipated up to the solution (theory §11.6).
fn reports_with_imprints(
    p: ProblemView<'_>,
    u: &[f64],
    extras: &[f64],
    lambda: &[f64],
    undetermined: &[usize],
) -> Vec<ObstacleReport> {
    let mut reports = p.contact_reports(extras, lambda);
    complete_reports(p, &mut reports, &imprints(p, u), undetermined);
    let dissipated = p.obstacles.dissipated(u, extras, lambda);
    for ((r, part), d) in reports.iter_mut().zip(p.obstacles.parts()).zip(dissipated) {
        if part.rows.has_friction() {
            r.report.quantities.push(("dissipated_energy".into(), d));
        }
    }
    reports
}

/// Each obstacle's imprint max_i (G u)_i over its normal rows (theory §11.4), the maximum over the
/// ranks; −∞ for an obstacle without rows. Collective.
pub fn imprints(p: ProblemView<'_>, u: &[f64]) -> Vec<f64> {
    let comm = p.l.comm();
    let parts = p.obstacles.parts();
    parts
        .iter()
        .map(|part| {
            // the normal rows: a tangential row (theory §8.3) measures slip, not indentation
            let tangential = part.rows.friction.tangential_mask(part.rows.n_rows());
            let normal = (0..part.rows.n_rows()).filter(|&i| !tangential[i]);
            comm.max(normal.map(|i| part.rows.row_times(i, u)).fold(f64::NEG_INFINITY, f64::max))
        })
        .collect()
}

/// Adds each obstacle's imprint ([`imprints`]) to its report and makes the quantities named like
/// an extra in `undetermined` (theory §11.3) NaN: written null.
pub fn complete_reports(p: ProblemView<'_>, reports: &mut [ObstacleReport], imprints: &[f64], undetermined: &[usize]) {
    let names = p.extra_names();
    for ((r, part), &m) in reports.iter_mut().zip(p.obstacles.parts()).zip(imprints) {
        if m.is_finite() {
            r.report.quantities.push(("imprint".into(), m));
        }
        for k in part.extra_range.clone().filter(|k| undetermined.contains(k)) {
            let local = names[k].rsplit_once('.').map_or(names[k].as_str(), |(_, q)| q);
            if let Some(q) = r.report.quantities.iter_mut().find(|(n, _)| n == local) {
                q.1 = f64::NAN;
            }
        }
    }
}

/// The obstacles' quantities as `contact` holds them: plain names with one obstacle, else
/// `name.quantity` (`obstacle[i].quantity` for an unnamed one).
fn contact_entries(p: ProblemView<'_>, reports: &[ObstacleReport]) -> BTreeMap<String, f64> {
    match reports {
        [r] => r.report.quantities.iter().cloned().collect(),
        _ => reports
            .iter()
            .enumerate()
            .flat_map(|(i, r)| {
                let name = r.name.clone().unwrap_or_else(|| p.obstacles.obstacles().path("obstacle", i));
                r.report.quantities.iter().map(move |(q, v)| (format!("{name}.{q}"), *v))
            })
            .collect(),
    }
}

/// The quantities a summary of `p` reports by name, known before any solve (the obstacles'
/// reports at zero): the keys of `contact` and of `extras`, sorted. What a load path's plot and a
/// sweep's axes may name, besides `factor`.
pub fn reported_quantities(p: ProblemView<'_>) -> Vec<String> {
    let (u, extras, lambda) = (vec![0.0; p.l.n_dofs()], vec![0.0; p.l.n_extras()], vec![0.0; p.l.n_rows()]);
    let reports = reports_with_imprints(p, &u, &extras, &lambda, &[]);
    let mut names: Vec<String> =
        contact_entries(p, &reports).into_keys().chain(p.extra_names()).chain(reaction_names(p)).collect();
    names.sort();
    names.dedup();
    names
}

/// The names of the reactions' components a summary of `p` reports ([`reaction_quantities`]).
pub fn reaction_names(p: ProblemView<'_>) -> Vec<String> {
    let zero = vec![saddle_core::Sym::zeros(); p.l.n_points()];
    reaction_quantities(&reactions_of(p, &zero)).map(|(n, _)| n).collect()
}

/// `name` is a quantity of `known` or `factor`; otherwise an error on `field` that lists them.
pub fn check_quantity(field: &str, name: &str, known: &[String]) -> Result<(), saddle_core::ParameterError> {
    if name == "factor" || known.iter().any(|k| k == name) {
        return Ok(());
    }
    let mut list: Vec<&str> = known.iter().map(String::as_str).collect();
    list.push("factor");
    Err(saddle_core::ParameterError::new(
        field,
        format!("{name:?}"),
        format!("is not a reported quantity; known: {}", list.join(", ")),
    ))
}

impl Summary {
    /// Summarises `sol`, recomputing J, the dual energy and the KKT residuals from scratch. The
    /// extras the solution marks undetermined (theory §11.3) are null, and so are the obstacles'
    /// quantities of the same name (`U`).
    pub fn new(p: ProblemView<'_>, sol: &Solution, title: Option<String>) -> Self {
        let reports = reports_with_imprints(p, &sol.u, &sol.extras, &sol.lambda, &sol.undetermined);
        Self::of_whole(
            p,
            sol,
            title,
            Whole { reports, quality: p.element.mesh().quality(), nodes: p.element.mesh().n_nodes() },
        )
    }

    /// [`Summary::new`] with the obstacles' reports and the mesh given ([`Whole`]): the summary
    /// of a rank's part of a distributed problem, its counts, sums and maxima over the ranks
    /// (theory §12). Collective.
    pub fn of_whole(p: ProblemView<'_>, sol: &Solution, title: Option<String>, whole: Whole) -> Self {
        let l = &p.l;
        let comm = l.comm();
        let mut ws = Workspace::new(l);
        let kkt = kkt(l, &sol.iterate(), &mut ws);
        let j = energy(l, &sol.u, &sol.extras, &mut ws);
        let reports = whole.reports;
        let single = match reports.as_slice() {
            [r] => Some(&r.report),
            _ => None,
        };
        let contact = contact_entries(p, &reports);
        let extras = (p.extra_names().into_iter().enumerate())
            .map(|(k, n)| (n, (!sol.undetermined.contains(&k)).then_some(sol.extras[k])))
            .collect();
        let mut warnings = p.warnings();
        warnings.extend(sol.report.warnings.iter().cloned());
        // ws.eps holds ε(u), left there by `l.energy` above
        let near_incompressible_fraction = locking::near_incompressible_fraction(l, &ws.eps);
        warnings.extend(locking::locking_warning(p.element, near_incompressible_fraction));
        let mesh_quality = whole.quality;
        if mesh_quality.max_aspect_ratio > 30.0 {
            warnings.push(format!(
                "the mesh has elements of aspect ratio up to {:.0} (element {}): expect larger discretisation errors \
                 and stiffer linear systems there",
                mesh_quality.max_aspect_ratio, mesh_quality.worst_element
            ));
        }
        for (i, r) in reports.iter().enumerate() {
            let path = p.obstacles.obstacles().path("obstacle", i);
            warnings.extend(r.report.warnings.iter().map(|w| {
                if reports.len() > 1 && !w.contains(&format!("{path}.")) { format!("{path}: {w}") } else { w.clone() }
            }));
        }
        Self {
            title,
            solver: sol.report.solver.clone(),
            converged: sol.report.converged,
            stop_reason: sol.report.stop_reason,
            iterations: sol.report.iterations,
            wall_s: sol.report.wall_s(),
            U: single.and_then(|c| c.get("U")).filter(|u| u.is_finite()),
            force: single.and_then(|c| c.get("force")),
            contact_nodes: reports.iter().map(|r| r.report.contact_nodes).sum(),
            contact_radius: reports.iter().map(|r| r.report.contact_radius).fold(0.0, f64::max),
            plastic_elements: comm.sum_count(plastic_elements(p.element, sol)),
            plastic_points: comm.sum_count(sol.stress.n_plastic()),
            max_von_mises: comm.max(sol.stress.sigma.iter().map(von_mises).fold(0.0, f64::max)),
            max_equivalent_plastic_strain: comm.max(max_equivalent_plastic_strain(l, &ws.eps, sol)),
            reactions: reactions_of(p, &sol.stress.sigma),
            J: j,
            dual_energy: dual_energy(l, &sol.stress, &sol.lambda),
            kkt_residual: kkt.max(),
            kkt,
            tolerance: sol.report.tolerance,
            dofs: comm.sum_count(l.n_dofs()),
            elements: comm.sum_count(p.element.mesh().n_elements()),
            stress_points: comm.sum_count(l.n_points()),
            discretisation: p.element.name().to_string(),
            nodes: whole.nodes,
            near_incompressible_fraction,
            contact_rows: comm.sum_count(l.data.rows.n_rows()),
            contact,
            extras,
            obstacles: reports.iter().map(ObstacleSummary::new).collect(),
            mesh_quality,
            phases: sol.report.phases.iter().cloned().collect(),
            end_to_end: BTreeMap::new(),
            end_to_end_s: 0.0,
            counters: sol.report.counters.clone(),
            residual_history: sol.report.residual_history.clone(),
            warnings,
            error_estimate: None,
            steps: Vec::new(),
            load_path: None,
            ranks: None,
            per_rank: Vec::new(),
        }
    }

    /// Writes the summary as pretty JSON.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let text = serde_json::to_string_pretty(self).map_err(std::io::Error::other)?;
        std::fs::write(path, text + "\n")
    }
}

/// The plastic strain ε_p = ε − Aσ at every stress point (theory §11.1), from the strains of
/// the solution's displacement.
pub fn plastic_strains(law: &Elasticity, eps: &[saddle_core::Sym], sol: &Solution) -> Vec<saddle_core::Sym> {
    eps.iter().zip(&sol.stress.sigma).map(|(e, s)| e - law.compliance(s)).collect()
}

/// The largest √(2/3)|ε_p| (0 for an elastic problem); `eps` the strains of w, to which the
/// lifting's are added (theory §14).
fn max_equivalent_plastic_strain(l: &saddle_core::Lagrangian<'_>, eps: &[saddle_core::Sym], sol: &Solution) -> f64 {
    if l.data.plasticity().is_none() {
        return 0.0;
    }
    let mut eps = eps.to_vec();
    l.data.lifting.add_strain(&mut eps);
    plastic_strains(l.data.elasticity, &eps, sol).iter().map(|p| (2.0f64 / 3.0).sqrt() * p.norm()).fold(0.0, f64::max)
}

/// The elements with at least one plastic stress point.
pub fn plastic_elements(element: &dyn Discretisation, sol: &Solution) -> usize {
    sol.stress.plastic.chunks(element.points_per_element()).filter(|p| p.iter().any(|x| *x)).count()
}
