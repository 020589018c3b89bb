//! Scenes: a whole problem in one TOML file, every plugin chosen by `type` (typetag), unknown
//! types and fields rejected with the list of known ones.
//!
//! ```toml
//! title = "Johnson 1977: elasto-plastic punch"
//! [discretisation]             # optional: "p2" (quadratic, B̄; the default; theory §10) or "p1"
//! type = "p1"
//! [mesh]                       # MeshSource: "box", "inline", "gmsh" (feature `gmsh`)
//! type = "box"
//! min = [-1.0, -1.0, 0.0]
//! max = [1.0, 1.0, 1.0]
//! cells = [24, 24, 12]
//! grading = { toward = [0.0, 0.0, 0.0], ratio = 4.0 }
//! [material]                   # isotropic elasticity
//! E = 100.0
//! nu = 0.3
//! [yield]                      # P; omit the table for an elastic body
//! type = "von_mises"
//! k0 = 1.0
//! h = 5.0
//! [[dirichlet]]                # u = 0 on the closure of the selected facets
//! on = { not = { all = [ { group = "zmin" }, { box = { min = [-0.75, -0.75, -1.0], max = [0.75, 0.75, 1.0] } } ] } }
//! [[load]]                     # optional: tractions and body forces
//! type = "traction"            # or: type = "body_force", b = [0.0, 0.0, -1e-3]
//! on = { group = "xmax" }
//! t = [0.0, 0.0, 0.01]
//! [obstacle]                   # K; omit for no contact
//! type = "rigid_punch"
//! F = 0.3
//! zone = { all = [ { group = "zmin" }, { disc = { center = [0.0, 0.0], radius = 0.5 } } ] }
//! gap = { type = "paraboloid", R = 5.0 }
//! [solver]                     # optional
//! type = "uzawa"
//! [load_path]                  # optional: load steps (Prandtl–Reuss, theory §11)
//! factors = [0.0, 1.0, 0.0]
//! [output]                     # optional: the a posteriori estimate (theory §15), on by default
//! error_estimate = true
//! ```
//!
//! Several obstacles (K = K₁ ∩ K₂ ∩ …, theory §8) are an array of tables, each with a unique
//! `name`; their extras are named `name.U`, … and their errors `obstacle[i].…`. A single
//! `[obstacle]` table may carry a `name` too. The `name` is set aside as the plugin reads the rest
//! of its table ([`saddle_core::Obstacles`]).
//!
//! ```toml
//! [[obstacle]]
//! name = "left"
//! type = "rigid_punch"
//! F = 0.1
//! zone = { all = [ { group = "zmin" }, { disc = { center = [-0.5, 0.0], radius = 0.3 } } ] }
//! gap = { type = "paraboloid", R = 5.0, center = [-0.5, 0.0] }
//! [[obstacle]]
//! name = "right"
//! type = "rigid_punch_displacement"
//! U = 0.001
//! zone = { all = [ { group = "zmin" }, { disc = { center = [0.5, 0.0], radius = 0.3 } } ] }
//! gap = { type = "paraboloid", R = 5.0, center = [0.5, 0.0] }
//! ```

use super::scene_de::TypeFirst;
use saddle_core::error::ParameterError;
use saddle_core::{
    AdmissibleStresses, Dirichlet, DiscreteProblem, Elasticity, FiniteElement, Load, MeshSource, Obstacles, P2,
    SceneError, Solver, TetMesh,
};
use saddle_core::{LoadFactors, StepCutting};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What a scene assembles into: the discrete problem (the scene's finite element with the
/// problem's data) and the scene's solver, if it names one.
pub type Assembled = (DiscreteProblem, Option<Box<dyn Solver>>);

/// A problem as written in a scene file: a typed value, validated once when it is read.
/// Variants (a refined mesh, another solver) are made by changing the value — it is `Clone`,
/// plugins included — never by editing TOML text.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// A title for reports.
    #[serde(default)]
    pub title: Option<String>,
    /// Where the mesh comes from.
    pub mesh: Box<dyn MeshSource>,
    /// The finite element (`[discretisation] type = "p1"` or `"p2"`); absent: [`default_element`].
    #[serde(default)]
    pub discretisation: Option<Box<dyn FiniteElement>>,
    /// Elasticity.
    pub material: Elasticity,
    /// P; absent for an elastic body (which then pays nothing for plasticity).
    #[serde(default, rename = "yield")]
    pub yield_surface: Option<Box<dyn AdmissibleStresses>>,
    /// Dirichlet conditions.
    #[serde(default)]
    pub dirichlet: Vec<Dirichlet>,
    /// Tractions and body forces (`[[load]]`).
    #[serde(default)]
    pub load: Vec<Load>,
    /// K: absent for no contact, one `[obstacle]` table, or several named `[[obstacle]]` tables
    /// (K = K₁ ∩ K₂ ∩ …, theory §8).
    #[serde(default)]
    pub obstacle: Obstacles,
    /// The solver; the command line supplies a default when absent.
    #[serde(default)]
    pub solver: Option<Box<dyn Solver>>,
    /// A load path (`[load_path]`, theory §11): the scene solved in load steps, Prandtl–Reuss;
    /// absent: one step from zero (the stationary problem).
    #[serde(default)]
    pub load_path: Option<LoadPath>,
    /// `[output]`: what a run writes besides the solution; absent: the defaults.
    #[serde(default)]
    pub output: OutputSettings,
    /// The folder relative file names are resolved against.
    #[serde(skip)]
    pub base_dir: PathBuf,
    /// `[solver.petsc] options = "-pc_gamg_threshold 0.02 …"`: PETSc options for a run under
    /// `mpirun` (theory §12), parsed as PETSc parses its command line, which has the last word;
    /// unused on one machine.
    #[serde(skip)]
    pub petsc_options: Option<String>,
}

impl Scene {
    /// Reads and validates a scene file.
    pub fn from_file(path: &Path) -> Result<Self, SceneError> {
        let text =
            std::fs::read_to_string(path).map_err(|source| SceneError::Io { path: path.to_path_buf(), source })?;
        let mut scene = Self::from_toml(&text, path)?;
        scene.base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Ok(scene)
    }

    /// Parses and validates scene text; `origin` names it in error messages. The text is parsed
    /// once, to a [`toml::Value`]: every number of it is checked finite (no field of a scene takes
    /// NaN or ±inf), then the typed scene is read from that value with the path of the field it
    /// fails on (`scene_de`: also inside plugins), then validated.
    pub fn from_toml(text: &str, origin: &Path) -> Result<Self, SceneError> {
        let parse_error = |message: String| SceneError::Parse { path: origin.to_path_buf(), message };
        let mut root = toml::Value::Table(
            toml::from_str(text).map_err(|e: toml::de::Error| parse_error(e.to_string().trim_end().into()))?,
        );
        non_finite_number(&root, &mut String::new())?;
        let petsc_options = take_petsc_options(&mut root)?;
        let mut scene: Scene =
            serde_path_to_error::deserialize(TypeFirst(&root)).map_err(|e| parse_error(field_error(&root, e)))?;
        scene.petsc_options = petsc_options;
        scene.validate()?;
        Ok(scene)
    }

    /// Checks every parameter; errors name the field path and value.
    pub fn validate(&self) -> Result<(), SceneError> {
        self.mesh.validate("mesh")?;
        if let Some(d) = &self.discretisation {
            d.validate("discretisation")?;
        }
        self.material.validate("material")?;
        if let Some(p) = &self.yield_surface {
            p.validate("yield")?;
        }
        for (i, d) in self.dirichlet.iter().enumerate() {
            d.validate(&format!("dirichlet[{i}]"))?;
        }
        for (i, l) in self.load.iter().enumerate() {
            l.validate(&format!("load[{i}]"))?;
        }
        self.obstacle.validate("obstacle")?;
        if let Some(s) = &self.solver {
            s.validate("solver")?;
        }
        if let Some(p) = &self.load_path {
            p.validate(self)?;
        }
        Ok(())
    }

    /// Checks that every obstacle takes the load factor `factor` (theory §11.2: a load path's
    /// step, a sweep's point): its load scaled is a valid parameter. The error names `field`
    /// (`load_path.factors[2]`, `--factors[0]`), the factor, and the obstacle's field with the
    /// scene's own value and the scaled one.
    pub fn check_load_factor(&self, factor: f64, field: &str) -> Result<(), SceneError> {
        self.check_load_factors(&LoadFactors::uniform(factor), field)
    }

    /// The names of the loads a load path may give factors of their own (`[load_path.loads]`,
    /// theory §11.2): the obstacles' ([`Obstacles::load_names`]).
    pub fn load_names(&self) -> Vec<String> {
        self.obstacle.load_names()
    }

    /// [`Scene::check_load_factor`] with named loads at factors of their own; the obstacle's
    /// error then names the step's factors.
    pub fn check_load_factors(&self, factors: &LoadFactors, field: &str) -> Result<(), SceneError> {
        let factor = factors.all;
        if !factor.is_finite() {
            return Err(ParameterError::new(field, factor, "must be finite").into());
        }
        // the prescribed displacements and the loads on u scale too (theory §14)
        let scaled_dirichlet = self.dirichlet.iter().enumerate().filter_map(|(i, d)| {
            let v = d.value.as_ref()?.iter().map(|x| x * factor).collect::<Vec<_>>();
            Some(d.clone().with_value(v).validate(&format!("dirichlet[{i}]")))
        });
        let scaled_loads = self.load.iter().enumerate().map(|(i, l)| l.scaled(factor).validate(&format!("load[{i}]")));
        if let Some(Err(e)) = scaled_dirichlet.chain(scaled_loads).find(Result::is_err) {
            let message = format!("at this load factor {} = {} {}", e.field, e.value, e.requirement);
            return Err(ParameterError::new(field, factor, message).into());
        }
        if (factor == 1.0 && factors.is_uniform()) || self.obstacle.is_empty() {
            return Ok(());
        }
        let scaled = self.obstacle.scaled_loads(factors).map_err(|e| {
            ParameterError::new(field, factor, format!("{} ({} = {}): {}", e.field, e.field, e.value, e.requirement))
        })?;
        scaled.validate("obstacle").map_err(|e| {
            // with factors of their own the field's factor is not `factor`: its value alone
            let own = scene_value(&self.obstacle, &e.field).filter(|_| factors.is_uniform());
            ParameterError::new(
                field,
                factor,
                format!(
                    "the obstacle at this load factor is invalid: {} = {}{} {}",
                    e.field,
                    own.map_or(String::new(), |v| format!("{v} × {factor} = ")),
                    e.value,
                    e.requirement
                ),
            )
            .into()
        })
    }

    /// The same scene on its structured mesh with `cells` per axis (a refinement study). An
    /// error naming `mesh.cells` when the mesh source has no cell counts (a file, an inline
    /// mesh) or a count is 0.
    pub fn with_cells(&self, cells: [usize; 3]) -> Result<Self, SceneError> {
        if let Some(k) = (0..3).find(|&k| cells[k] == 0) {
            return Err(ParameterError::new(format!("mesh.cells[{k}]"), 0, "must be >= 1").into());
        }
        let mesh = self.mesh.with_cells(cells).ok_or_else(|| SceneError::Region {
            field: "mesh.cells".into(),
            message: format!("a `{}` mesh cannot be refined by cell counts; use a `box` mesh", self.mesh.name()),
        })?;
        // a count outside the mesh's family (`base`) is refused here, naming `mesh.cells`
        mesh.validate("mesh")?;
        Ok(Self { mesh, ..self.clone() })
    }

    /// Builds the mesh and assembles L; returns it with the scene's solver (if any). A scene
    /// whose Dirichlet conditions leave a rigid-body motion free is an error here.
    pub fn into_problem(self) -> Result<Assembled, SceneError> {
        let mesh = self.build_mesh()?;
        self.assemble(mesh)
    }

    /// The mesh: built by a mesher or read from its file (the `read` phase of a run).
    pub fn build_mesh(&self) -> Result<TetMesh, SceneError> {
        Ok(self.mesh.build(&self.base_dir)?)
    }

    /// The discrete problem on `mesh` (the `setup` phase of a run: the element's dofs and
    /// pattern, the obstacles' rows, the loads), with the scene's solver. A scene whose
    /// Dirichlet conditions leave a rigid-body motion free is an error here.
    pub fn assemble(self, mesh: TetMesh) -> Result<Assembled, SceneError> {
        let element = self.discretisation.unwrap_or_else(default_element);
        let element = element.build(mesh, &self.dirichlet)?;
        element.dofs().check_rigid_motions(element.mesh())?;
        let problem = DiscreteProblem::new(element, self.material, self.yield_surface, self.obstacle, &self.load)?
            .with_supports(&self.dirichlet, &self.load)?;
        Ok((problem, self.solver))
    }

    /// The `type` of the scene's finite element ([`default_element`]'s when the scene names none).
    pub fn element_name(&self) -> &'static str {
        self.discretisation.as_ref().map_or_else(|| default_element().name(), |d| d.name())
    }

    /// The same scene with another finite element.
    pub fn with_element(&self, element: Box<dyn FiniteElement>) -> Self {
        Self { discretisation: Some(element), ..self.clone() }
    }
}

/// The finite element of a scene without `[discretisation]`: P2 with B̄ (theory §10), the one
/// users should use — it reaches limit loads and nearly incompressible responses where P1 locks
/// (docs/locking.md); a scene that wants P1–P0 (the paper's, `examples/johnson.toml`) says so.
pub fn default_element() -> Box<dyn FiniteElement> {
    Box::new(P2::default())
}

/// Takes `[solver.petsc]` out of the parsed scene (the solvers know no PETSc): its `options`, a
/// string, the table's only key. A `[solver]` table left empty goes too (no solver named).
fn take_petsc_options(root: &mut toml::Value) -> Result<Option<String>, SceneError> {
    let Some(solver) = root.get_mut("solver").and_then(toml::Value::as_table_mut) else {
        return Ok(None);
    };
    let Some(petsc) = solver.remove("petsc") else {
        return Ok(None);
    };
    let field = |key: &str, value: &dyn std::fmt::Display, message: &str| {
        SceneError::from(saddle_core::ParameterError::new(format!("solver.petsc{key}"), value.to_string(), message))
    };
    let toml::Value::Table(mut table) = petsc else {
        return Err(field("", &petsc, "must be a table: [solver.petsc] options = \"-ksp_monitor …\""));
    };
    let options = match table.remove("options") {
        Some(toml::Value::String(s)) => s,
        Some(other) => return Err(field(".options", &other, "must be a string of PETSc options")),
        None => return Err(field("", &"{}", "needs `options`, a string of PETSc options")),
    };
    if let Some(key) = table.keys().next() {
        return Err(field(&format!(".{key}"), &table[key], "unknown key: [solver.petsc] takes `options` only"));
    }
    if solver.is_empty() {
        root.as_table_mut().map(|t| t.remove("solver"));
    }
    Ok(Some(options))
}

/// The most steps a load path may have: 100 000. A step costs a solve and about 1.4 KB of
/// `summary.json` and `load_path.csv` (measured: 4 001 steps on a 4×4×2 mesh wrote 4.6 MB and
/// 0.9 MB in 5 s; the VTU files are bounded by [`crate::app::path::MAX_STEP_FILES`]), so the longest
/// path writes about 140 MB besides its VTU files.
pub const MAX_STEPS: usize = 100_000;

/// `[load_path]`: every load of the scene (tractions, body forces, each obstacle's force or
/// prescribed displacement) multiplied by each factor in turn, one load step each (theory §11):
///
/// ```toml
/// [load_path]
/// factors = [0.0, 0.5, 1.0, 0.5, 0.0]   # load, then unload
/// substeps = 4                          # optional: equal steps between factors (default 1)
/// plot = ["imprint", "force"]           # optional: the load_path.png axes (the default)
/// max_cuts = 5                          # optional: halvings of a failed step (theory §11.5)
/// min_step = 1e-6                       # optional: the smallest increment tried
/// [load_path.loads]                     # optional: loads with factors of their own
/// Q = [0.0, 0.0, 1.0, -1.0, 1.0]        # e.g. a sphere's tangential force (Mindlin's loop)
/// ```
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LoadPath {
    /// The load factors, in order; the first is a step of its own (0: the unloaded start).
    pub factors: Vec<f64>,
    /// Equal sub-steps from each factor to the next (≥ 1).
    #[serde(default = "one")]
    pub substeps: usize,
    /// The quantities on the axes of `load_path.png` (x, y): any quantity the obstacles report
    /// (`U`, `force`, `imprint` — the largest displacement of the contact zone away from the
    /// obstacle, defined also at zero load), an extra, or `factor`; a name the scene does not
    /// report is an error before any solve. Absent: imprint and force, the load–depth loop of an
    /// indentation, drawn when the obstacles report both ([`LoadPath::axes`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plot: Option<[String; 2]>,
    /// A step that fails is retried with half the increment, up to this many times per planned
    /// step (theory §11.5; default [`StepCutting::default`]); 0: the path stops at it.
    #[serde(default = "default_max_cuts")]
    pub max_cuts: usize,
    /// No increment of the load factor below this is tried (theory §11.5).
    #[serde(default = "default_min_step")]
    pub min_step: f64,
    /// `[load_path.loads]`: loads with factors of their own, one per entry of `factors`, by the
    /// names their plugins give them (an obstacle's `F`, `Q`, …, `name.F` for a named one;
    /// theory §11.2); every other load follows `factors`. Sub-steps and step cutting divide
    /// every list alike.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub loads: BTreeMap<String, Vec<f64>>,
}

/// `[output]`: what a run writes besides the solution.
///
/// ```toml
/// [output]
/// error_estimate = false   # no a posteriori estimate (theory §15); default: true
/// ```
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct OutputSettings {
    /// The a posteriori error estimate of theory §15 in `summary.json` (`error_estimate`) and
    /// `solution.vtu` (`error_indicator`). On by default: it costs well under 10 % of a solve
    /// (theory §15.3).
    #[serde(default = "yes")]
    pub error_estimate: bool,
}

impl Default for OutputSettings {
    fn default() -> Self {
        Self { error_estimate: true }
    }
}

fn yes() -> bool {
    true
}

fn default_max_cuts() -> usize {
    StepCutting::default().max_cuts
}

fn default_min_step() -> f64 {
    StepCutting::default().min_step
}

fn one() -> usize {
    1
}

impl LoadPath {
    /// The plotted quantities (x, y): `plot`, or imprint and force when absent.
    pub fn axes(&self) -> [String; 2] {
        self.plot.clone().unwrap_or_else(|| ["imprint".to_string(), "force".to_string()])
    }

    /// The step cutting settings (theory §11.5).
    pub fn cutting(&self) -> StepCutting {
        StepCutting { max_cuts: self.max_cuts, min_step: self.min_step }
    }

    /// The factors of the steps, sub-steps included.
    pub fn step_factors(&self) -> Vec<f64> {
        saddle_core::step_factors(&self.factors, self.substeps)
    }

    /// Every load's factor at each step, sub-steps included: `factors` for all, and each list of
    /// `loads` for its load (theory §11.2).
    pub fn step_loads(&self) -> Vec<LoadFactors> {
        let named: Vec<(&String, Vec<f64>)> =
            self.loads.iter().map(|(k, list)| (k, saddle_core::step_factors(list, self.substeps))).collect();
        (self.step_factors().into_iter().enumerate())
            .map(|(i, all)| LoadFactors { all, named: named.iter().map(|(k, l)| ((*k).clone(), l[i])).collect() })
            .collect()
    }

    /// The planned factors of the steps in `[load_path.loads]` (each list's entry `i` with
    /// `factors[i]`): what [`Scene::check_load_factors`] checks.
    fn planned_loads(&self, i: usize) -> LoadFactors {
        LoadFactors { all: self.factors[i], named: self.loads.iter().map(|(k, l)| (k.clone(), l[i])).collect() }
    }

    /// `[load_path.loads]`: every name one the scene's loads have, every list as long as
    /// `factors` and finite. Errors name `load_path.loads.NAME` (and the entry).
    fn validate_loads(&self, scene: &Scene) -> Result<(), SceneError> {
        let known = scene.load_names();
        for (name, list) in &self.loads {
            let field = format!("load_path.loads.{name}");
            if !known.contains(name) {
                let known = if known.is_empty() { "none".to_string() } else { known.join(", ") };
                return Err(ParameterError::new(
                    field,
                    format!("{name:?}"),
                    format!("is not a load of the scene that may have factors of its own; known: {known}"),
                )
                .into());
            }
            if list.len() != self.factors.len() {
                return Err(ParameterError::new(
                    field,
                    format!("{} entries", list.len()),
                    format!("must have one factor per entry of load_path.factors ({})", self.factors.len()),
                )
                .into());
            }
            if let Some((i, x)) = list.iter().enumerate().find(|(_, x)| !x.is_finite()) {
                return Err(ParameterError::new(format!("{field}[{i}]"), x, "must be finite").into());
            }
        }
        Ok(())
    }

    /// Checks the table: at least one factor, `substeps` ≥ 1 and at most [`MAX_STEPS`] steps;
    /// each factor is checked against the scene's obstacles by [`Scene::check_load_factor`] (a
    /// negative factor reverses the loads; a punch's force cannot, and the error names
    /// `load_path.factors[i]` and the obstacle's field).
    pub fn validate(&self, scene: &Scene) -> Result<(), SceneError> {
        if self.factors.is_empty() {
            return Err(ParameterError::new("load_path.factors", "[]", "give at least one load factor").into());
        }
        if self.substeps == 0 {
            return Err(ParameterError::new("load_path.substeps", 0, "must be >= 1").into());
        }
        if !(self.min_step.is_finite() && self.min_step > 0.0) {
            return Err(ParameterError::new("load_path.min_step", self.min_step, "must be a positive number").into());
        }
        let steps = (self.factors.len() as f64 - 1.0) * self.substeps as f64 + 1.0;
        if steps > MAX_STEPS as f64 {
            return Err(ParameterError::new(
                "load_path.substeps",
                self.substeps,
                format!(
                    "makes {} steps with {} factors, more than the {MAX_STEPS} a load path may have",
                    saddle_core::error::number(steps),
                    self.factors.len()
                ),
            )
            .into());
        }
        self.validate_loads(scene)?;
        for i in 0..self.factors.len() {
            scene.check_load_factors(&self.planned_loads(i), &format!("load_path.factors[{i}]"))?;
        }
        Ok(())
    }
}

/// The scene's own value of the obstacle field `field` (`obstacle.F`, `obstacle[1].U`), when it
/// is a number: what a scaled value is reported against.
fn scene_value(obstacles: &Obstacles, field: &str) -> Option<f64> {
    let value = toml::Value::try_from(obstacles).ok()?;
    let mut parts = field.split('.');
    let mut node = match parts.next()?.split_once('[') {
        Some((_, index)) => value.get(index.trim_end_matches(']').parse::<usize>().ok()?)?,
        None => &value,
    };
    for part in parts {
        let mut pieces = part.split(['[', ']']).filter(|s| !s.is_empty());
        node = node.get(pieces.next()?)?;
        for index in pieces {
            node = node.get(index.parse::<usize>().ok()?)?;
        }
    }
    node.as_float().or_else(|| node.as_integer().map(|i| i as f64))
}

/// The finite element of type `name` with its default options (as `[discretisation] type =
/// "name"`), looked up by its `type` tag; an unknown name lists the known ones.
pub fn element_by_type(name: &str) -> Result<Box<dyn FiniteElement>, SceneError> {
    let table = toml::Table::from_iter([("type".to_string(), toml::Value::String(name.to_string()))]);
    toml::Value::Table(table)
        .try_into::<Box<dyn FiniteElement>>()
        .map_err(|e| SceneError::Parse { path: "--discretisation".into(), message: format!("{name}: {}", e.message()) })
}

/// The first NaN or infinite number in a scene's TOML, as an error naming its path (`mesh.min[0]`).
fn non_finite_number(v: &toml::Value, path: &mut String) -> Result<(), SceneError> {
    match v {
        toml::Value::Float(x) if !x.is_finite() => Err(SceneError::Parameter(ParameterError::new(
            path.clone(),
            x,
            "a finite number (no number in a scene may be NaN or infinite)",
        ))),
        toml::Value::Table(t) => t.iter().try_for_each(|(k, x)| {
            let len = path.len();
            if !path.is_empty() {
                path.push('.');
            }
            path.push_str(k);
            let r = non_finite_number(x, path);
            path.truncate(len);
            r
        }),
        toml::Value::Array(a) => a.iter().enumerate().try_for_each(|(i, x)| {
            let len = path.len();
            path.push_str(&format!("[{i}]"));
            let r = non_finite_number(x, path);
            path.truncate(len);
            r
        }),
        _ => Ok(()),
    }
}

/// A deserialisation error as `path = value: rule` (`mesh.cells = [12, 12]: invalid length 2,
/// expected an array of length 3`), or `path: rule` when the path is a table (a missing or
/// unknown field).
fn field_error(root: &toml::Value, e: serde_path_to_error::Error<toml::de::Error>) -> String {
    let mut path = e.path().to_string();
    let rule = e.into_inner().message().trim_end().to_string();
    // Serde's internally tagged enums (`[[load]]`) buffer their table, and the path stops at the
    // table: find the field by the value the message quotes (`integer `-3``), or by the length
    // it names (`invalid length 2`).
    let quoted = quoted_value(&rule).map(|v| {
        move |x: &toml::Value| match x {
            toml::Value::Integer(i) => i.to_string() == v,
            toml::Value::Float(f) => v.parse::<f64>().ok() == Some(*f),
            _ => false,
        }
    });
    let length = rule.strip_prefix("invalid length ").and_then(|r| r.split(',').next()?.parse::<usize>().ok());
    let leaf = match (quoted, length) {
        (Some(is), _) => unique_leaf(root, &path, is),
        (None, Some(n)) => unique_leaf(root, &path, |x| x.as_array().is_some_and(|a| a.len() == n)),
        _ => None,
    };
    if let Some(leaf) = leaf {
        path = leaf;
    }
    // a missing field is named by its own path: `mesh.cells: missing (a required field)`
    if let Some(field) = rule.strip_prefix("missing field `").and_then(|r| r.strip_suffix('`')) {
        let field = if path == "." { field.to_string() } else { format!("{path}.{field}") };
        return format!("{field}: missing (a required field)");
    }
    match lookup(root, &path) {
        _ if path == "." => rule,
        Some(v) if !v.is_table() => format!("{path} = {v}: {rule}"),
        _ => format!("{path}: {rule}"),
    }
}

/// The value at a path (`obstacle[1].zone.all[0]`; `.` is the root), if there is one.
fn lookup<'a>(root: &'a toml::Value, path: &str) -> Option<&'a toml::Value> {
    let mut node = root;
    if path != "." {
        for part in path.split('.') {
            let mut pieces = part.split(['[', ']']).filter(|s| !s.is_empty());
            node = node.get(pieces.next()?)?;
            for index in pieces {
                node = node.get(index.parse::<usize>().ok()?)?;
            }
        }
    }
    Some(node)
}

/// The value a serde message quotes between backticks (`invalid value: integer `-3`, …`).
fn quoted_value(message: &str) -> Option<&str> {
    let start = message.find('`')? + 1;
    let len = message[start..].find('`')?;
    Some(&message[start..start + len])
}

/// The path of the only value under `path` (`.` for the root) that `is` picks.
fn unique_leaf(root: &toml::Value, path: &str, is: impl Fn(&toml::Value) -> bool) -> Option<String> {
    fn walk(v: &toml::Value, path: String, is: &dyn Fn(&toml::Value) -> bool, found: &mut Vec<String>) {
        if is(v) {
            found.push(path.clone());
        }
        match v {
            toml::Value::Table(t) => t.iter().for_each(|(k, x)| walk(x, format!("{path}.{k}"), is, found)),
            toml::Value::Array(a) => a.iter().enumerate().for_each(|(i, x)| walk(x, format!("{path}[{i}]"), is, found)),
            _ => {}
        }
    }
    let node = lookup(root, path)?;
    let mut found = vec![];
    walk(node, if path == "." { String::new() } else { path.to_string() }, &is, &mut found);
    let found: Vec<String> = found.into_iter().map(|p| p.trim_start_matches('.').to_string()).collect();
    (found.len() == 1).then(|| found[0].clone())
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCENE: &str = r#"
[mesh]
type = "box"
min = [-1.0, -1.0, 0.0]
max = [1.0, 1.0, 1.0]
cells = [4, 4, 3]
[material]
E = 100.0
nu = 0.3
[[dirichlet]]
on = { group = "zmax" }
"#;

    fn error(text: &str) -> String {
        Scene::from_toml(text, Path::new("s.toml")).unwrap_err().to_string()
    }

    #[test]
    fn parse_errors_name_the_field_inside_plugins_and_arrays() {
        let e = error(&SCENE.replace("[4, 4, 3]", "[4, 4, -3]"));
        assert!(e.starts_with("s.toml: mesh.cells[2] = -3: ") && e.contains("expected usize"), "{e}");
        let e = error(&format!("{SCENE}components = [\"w\"]\n"));
        assert!(e.contains("dirichlet[0].components[0]"), "{e}");
        let e = error(&SCENE.replace("min = [-1.0, -1.0, 0.0]", "min = [-1.0, -inf, 0.0]"));
        assert!(e.contains("mesh.min[1] = -inf") && e.contains("finite"), "{e}");
    }
}
