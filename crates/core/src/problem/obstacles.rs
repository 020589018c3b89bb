//! Several obstacles: K = K₁ ∩ K₂ ∩ … (theory §8). Each obstacle is a plugin
//! ([`AdmissibleDisplacements`]) with its own rows, extra unknowns and load; the intersection
//! concatenates the rows and the extras, and each extra keeps its obstacle's name (`left.U`).
//!
//! In a scene, one obstacle is a table and several are an array of tables, each then named:
//!
//! ```toml
//! [[obstacle]]
//! name = "left"
//! type = "rigid_punch"
//! F = 0.1
//! zone = { all = [ { group = "zmin" }, { disc = { center = [-0.5, 0.0], radius = 0.3 } } ] }
//! gap = { type = "paraboloid", R = 5.0 }
//! [[obstacle]]
//! name = "right"
//! type = "rigid_punch"
//! F = 0.2
//! zone = { all = [ { group = "zmin" }, { disc = { center = [0.5, 0.0], radius = 0.3 } } ] }
//! gap = { type = "paraboloid", R = 5.0, center = [0.5, 0.0] }
//! ```
//!
//! The `name` key is set aside here as the plugin reads the rest of its table, so plugins keep
//! `deny_unknown_fields`. Nothing in this module knows a particular plugin: every
//! obstacle reports its own quantities on its own rows, extras and multipliers
//! ([`DiscreteObstacles::reports`]).

use crate::error::{ParameterError, SceneError};
use crate::mesh::TetMesh;
use crate::mesh::dofs::DofMap;
use crate::problem::displacements::RowCombination;
use crate::problem::displacements::{AdmissibleDisplacements, ConstraintRows, ContactReport};
use crate::problem::load_factors::LoadFactors;
use crate::problem::slip::{SlipHistory, dissipation};
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::ser::{SerializeSeq, Serializer};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::ops::Range;

/// The path of the scene's obstacle table(s): errors of [`Obstacles::new`] name
/// `obstacle[i].name`.
pub const OBSTACLE_PATH: &str = "obstacle";

/// One obstacle with an optional name (required when a scene has several).
#[derive(Clone, Debug)]
pub struct NamedObstacle {
    /// The name: the prefix of its extras (`left.U`) and of its quantities in reports.
    pub name: Option<String>,
    /// The obstacle.
    pub k: Box<dyn AdmissibleDisplacements>,
}

impl NamedObstacle {
    /// An obstacle called `name`.
    pub fn new(name: impl Into<String>, k: Box<dyn AdmissibleDisplacements>) -> Self {
        Self { name: Some(name.into()), k }
    }

    /// An obstacle without a name (allowed when it is the only one).
    pub fn unnamed(k: Box<dyn AdmissibleDisplacements>) -> Self {
        Self { name: None, k }
    }
}

/// K = K₁ ∩ K₂ ∩ … (theory §8): no obstacle, one, or several named ones. Remembers whether it was
/// written as one table (`[obstacle]`, paths `obstacle.…`) or as an array of tables
/// (`[[obstacle]]`, paths `obstacle[i].…`), and is written back in the same shape.
#[derive(Clone, Debug, Default)]
pub struct Obstacles {
    list: Vec<NamedObstacle>,
    array: bool,
}

/// Checks the names of `list`: a given name is non-empty; with two or more obstacles every one
/// has a name and the names are unique. Errors name `obstacle[i].name` and the value.
fn check_names(list: &[NamedObstacle]) -> Result<(), ParameterError> {
    for (i, o) in list.iter().enumerate() {
        let field = format!("{OBSTACLE_PATH}[{i}].name");
        match &o.name {
            Some(n) if n.trim().is_empty() => {
                return Err(ParameterError::new(field, format!("{n:?}"), "a name must not be empty"));
            }
            Some(n) if n.contains('.') => {
                return Err(ParameterError::new(
                    field,
                    format!("{n:?}"),
                    "a name must not contain '.' (it prefixes the obstacle's extras: name.U)",
                ));
            }
            Some(n) => {
                if let Some(j) = list[..i].iter().position(|p| p.name.as_deref() == Some(n)) {
                    return Err(ParameterError::new(
                        field,
                        format!("{n:?}"),
                        format!("names must be unique; {OBSTACLE_PATH}[{j}].name is {n:?} too"),
                    ));
                }
            }
            None if list.len() > 1 => {
                return Err(ParameterError::new(
                    field,
                    "(none)",
                    format!(
                        "with {} obstacles every one needs a unique name (obstacle[{i}] is a {:?})",
                        list.len(),
                        o.k.name()
                    ),
                ));
            }
            None => {}
        }
    }
    Ok(())
}

impl Obstacles {
    /// No obstacle: no contact.
    pub fn none() -> Self {
        Self::default()
    }

    /// One unnamed obstacle, as a single `[obstacle]` table.
    pub fn one(k: Box<dyn AdmissibleDisplacements>) -> Self {
        Self { list: vec![NamedObstacle::unnamed(k)], array: false }
    }

    /// One obstacle, possibly named, as a single `[obstacle]` table. Errors name
    /// `obstacle[0].name` (an empty name).
    pub fn single(obstacle: NamedObstacle) -> Result<Self, ParameterError> {
        let list = vec![obstacle];
        check_names(&list)?;
        Ok(Self { list, array: false })
    }

    /// Several obstacles, as an array of `[[obstacle]]` tables. With two or more every one
    /// needs a name; names are non-empty and unique. Errors name `obstacle[i].name` and the value.
    pub fn new(list: Vec<NamedObstacle>) -> Result<Self, ParameterError> {
        check_names(&list)?;
        Ok(Self { list, array: true })
    }

    /// True when written as an array of tables (`[[obstacle]]`).
    pub fn is_array(&self) -> bool {
        self.array
    }

    /// The obstacles in order.
    pub fn iter(&self) -> std::slice::Iter<'_, NamedObstacle> {
        self.list.iter()
    }

    /// Number of obstacles.
    pub fn len(&self) -> usize {
        self.list.len()
    }

    /// True without obstacle.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// The only obstacle, when there is exactly one (None without obstacle or with several).
    pub fn only(&self) -> Option<&dyn AdmissibleDisplacements> {
        match self.list.as_slice() {
            [o] => Some(o.k.as_ref()),
            _ => None,
        }
    }

    /// The path of obstacle `i` under `root`: `root` for a single table, `root[i]` in an array.
    pub fn path(&self, root: &str, i: usize) -> String {
        if self.array { format!("{root}[{i}]") } else { root.to_string() }
    }

    /// The names of the extra unknowns: each obstacle's `extra_names()`, prefixed `name.` when
    /// the obstacle has a name (`left.U`), plain otherwise.
    pub fn extra_names(&self) -> Vec<String> {
        self.prefixed(|k| k.extra_names())
    }

    /// Each obstacle's `names`, prefixed `name.` when the obstacle has a name.
    fn prefixed(&self, names: impl Fn(&dyn AdmissibleDisplacements) -> Vec<String>) -> Vec<String> {
        self.list
            .iter()
            .flat_map(|o| {
                names(o.k.as_ref()).into_iter().map(move |x| match &o.name {
                    Some(n) => format!("{n}.{x}"),
                    None => x,
                })
            })
            .collect()
    }

    /// Every obstacle with its load multiplied by `factor`
    /// ([`AdmissibleDisplacements::scaled_load`]). An error names the obstacle (`obstacle`,
    /// `obstacle[i]`) whose plugin has no load to scale.
    pub fn scaled_load(&self, factor: f64) -> Result<Self, ParameterError> {
        self.scaled_loads(&LoadFactors::uniform(factor))
    }

    /// Every obstacle with each of its loads multiplied by its factor
    /// ([`AdmissibleDisplacements::scaled_loads`]; the loads named `name.F` or, unnamed, `F`,
    /// theory §11.2). An error names the obstacle whose plugin has no load to scale.
    pub fn scaled_loads(&self, factors: &LoadFactors) -> Result<Self, ParameterError> {
        let list = self
            .list
            .iter()
            .enumerate()
            .map(|(i, o)| {
                let k = o.k.scaled_loads(&factors.of_obstacle(o.name.as_deref())).ok_or_else(|| {
                    ParameterError::new(
                        self.path(OBSTACLE_PATH, i),
                        format!("type = {:?}", o.k.name()),
                        "this obstacle plugin cannot scale its load (AdmissibleDisplacements::scaled_load is None)",
                    )
                })?;
                Ok(NamedObstacle { name: o.name.clone(), k })
            })
            .collect::<Result<_, ParameterError>>()?;
        Ok(Self { list, array: self.array })
    }

    /// The names of the loads a load path may give factors of their own: each obstacle's
    /// [`AdmissibleDisplacements::load_names`], prefixed `name.` as its extras are.
    pub fn load_names(&self) -> Vec<String> {
        self.prefixed(|k| k.load_names())
    }

    /// The load term's coefficients f, concatenated.
    pub fn load(&self) -> Vec<f64> {
        self.list.iter().flat_map(|o| o.k.load()).collect()
    }

    /// Checks every obstacle's parameters under its own path: `path` for a single table,
    /// `path[i]` in an array. (The names were checked when the list was made: [`Obstacles::new`],
    /// [`Obstacles::single`].)
    pub fn validate(&self, path: &str) -> Result<(), ParameterError> {
        for (i, o) in self.list.iter().enumerate() {
            o.k.validate(&self.path(path, i))?;
        }
        Ok(())
    }

    /// K_h on a mesh: every obstacle's rows (discretised under its own path), concatenated, each
    /// obstacle's H columns at its own offset among the concatenated extras; the loads
    /// concatenated; the warnings concatenated, each naming its obstacle's path.
    pub fn discretise(self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<DiscreteObstacles, SceneError> {
        self.discretise_with(mesh, dofs, path, Ok)
    }

    /// [`Obstacles::discretise`] with every obstacle's rows passed through `rows` (the
    /// element's contact rows, [`crate::Discretisation::contact_rows`]: the nodal rows, or
    /// rows recombined from them, theory §10.1). Its error names the obstacle's path.
    pub fn discretise_with(
        self,
        mesh: &TetMesh,
        dofs: &DofMap,
        path: &str,
        rows: impl Fn(ConstraintRows) -> Result<ConstraintRows, String>,
    ) -> Result<DiscreteObstacles, SceneError> {
        let rows = (self.list.iter().enumerate())
            .map(|(i, o)| {
                let field = self.path(path, i);
                let nodal = o.k.discretise(mesh, dofs, &field)?;
                rows(nodal).map_err(|message| SceneError::Region { field, message })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let discrete = DiscreteObstacles::concatenate(self, rows, path);
        discrete.obstacles.check_independent_at_shared_nodes(&discrete.parts, mesh, path)?;
        Ok(discrete)
    }
}

/// Relative tolerance of the parallel test of two rows: |a·b| ≥ (1 − tol)|a||b|.
const PARALLEL_TOL: f64 = 1e-10;

impl Obstacles {
    /// Two obstacles whose rows at a shared candidate node are parallel (two punches on
    /// overlapping zones push the node in the same direction) are an error naming both: the two
    /// rows are linearly dependent, their multipliers (contact forces) are not unique, and none of
    /// the solvers accepts such rows (the Delassus matrix G M⁻¹ Gᵀ is singular, and the
    /// solvers that factor the rows refuse dependent ones). Rows of different obstacles at one
    /// node with independent directions (a floor and an oblique sphere) are fine (theory §8).
    fn check_independent_at_shared_nodes(
        &self,
        parts: &[ObstacleRows],
        mesh: &TetMesh,
        path: &str,
    ) -> Result<(), SceneError> {
        if parts.len() < 2 {
            return Ok(());
        }
        // (node, obstacle, row) sorted by node: the rows of one node are adjacent
        let mut at: Vec<(usize, usize, usize)> = parts
            .iter()
            .enumerate()
            .flat_map(|(o, p)| (0..p.rows.n_rows()).map(move |i| (p.rows.node[i], o, i)))
            .collect();
        at.sort_unstable();
        let row = |o: usize, i: usize| parts[o].rows.row(i);
        let dot = |(ca, va): (&[usize], &[f64]), (cb, vb): (&[usize], &[f64])| -> f64 {
            ca.iter().zip(va).map(|(j, x)| cb.iter().position(|k| k == j).map_or(0.0, |p| x * vb[p])).sum()
        };
        let mut dependent: Option<(usize, usize, usize)> = None; // (node, first obstacle, second obstacle)
        let mut count = 0;
        for group in at.chunk_by(|a, b| a.0 == b.0) {
            let pair = group.iter().enumerate().find_map(|(k, &(n, oa, ia))| {
                group[k + 1..].iter().filter(|b| b.1 != oa).find_map(|&(_, ob, ib)| {
                    let (a, b) = (row(oa, ia), row(ob, ib));
                    let (aa, bb, ab) = (dot(a, a), dot(b, b), dot(a, b));
                    (aa > 0.0 && bb > 0.0 && ab.abs() >= (1.0 - PARALLEL_TOL) * (aa * bb).sqrt()).then_some((
                        n,
                        oa.min(ob),
                        oa.max(ob),
                    ))
                })
            });
            if let Some(p) = pair {
                count += 1;
                dependent.get_or_insert(p);
            }
        }
        let Some((n, first, second)) = dependent else {
            return Ok(());
        };
        let name = |o: usize| {
            let p = self.path(path, o);
            self.list[o].name.as_ref().map_or(p.clone(), |name| format!("{p} ({name:?})"))
        };
        let x = mesh.nodes[n];
        Err(SceneError::Region {
            field: self.path(path, second),
            message: format!(
                "pushes {count} node(s) in the same direction as {}, e.g. node {n} at ({}, {}, {}): the candidate \
                 zones overlap, so the two rows at such a node are linearly dependent and the contact forces there \
                 are not unique; no solver can solve this. Make the obstacles' candidate zones disjoint",
                name(first),
                x[0],
                x[1],
                x[2]
            ),
        })
    }
}

/// The rows `rows_of(part)` of every part concatenated, each part's H columns at its extras'
/// offset among `n_extras`, its friction blocks shifted to its rows, its warnings appended.
fn concatenated(
    parts: &[ObstacleRows],
    n_extras: usize,
    rows_of: impl Fn(&ConstraintRows) -> &ConstraintRows,
) -> ConstraintRows {
    let mut all = ConstraintRows::new(n_extras);
    let mut h = vec![0.0; n_extras];
    for part in parts {
        let rows = rows_of(&part.rows);
        for i in 0..rows.n_rows() {
            h.iter_mut().for_each(|x| *x = 0.0);
            h[part.extra_range.clone()].copy_from_slice(rows.extra_row(i));
            all.push_row_of(rows, i, &h);
        }
        all.friction.extend_shifted(&rows.friction, part.row_range.start);
        all.warnings.extend(rows.warnings.iter().cloned());
    }
    all
}

/// `warning`, prefixed `path: ` unless it already names the path (`obstacle.zone: …`).
fn naming_path(path: &str, warning: String) -> String {
    if warning.contains(&format!("{path}.")) || warning.contains(&format!("{path}:")) {
        warning
    } else {
        format!("{path}: {warning}")
    }
}

impl From<Box<dyn AdmissibleDisplacements>> for Obstacles {
    fn from(k: Box<dyn AdmissibleDisplacements>) -> Self {
        Self::one(k)
    }
}

impl From<Option<Box<dyn AdmissibleDisplacements>>> for Obstacles {
    fn from(k: Option<Box<dyn AdmissibleDisplacements>>) -> Self {
        k.map_or_else(Self::none, Self::one)
    }
}

/// One obstacle's part of the concatenated rows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObstacleRows {
    /// The obstacle's own rows (its own extras as the columns of H).
    pub rows: ConstraintRows,
    /// Its rows among the concatenated rows (and multipliers λ).
    pub row_range: Range<usize>,
    /// Its extras among the concatenated extras.
    pub extra_range: Range<usize>,
}

/// What one obstacle reports about a solution.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObstacleReport {
    /// The obstacle's name (None for a single unnamed obstacle).
    pub name: Option<String>,
    /// The plugin's `type` ([`AdmissibleDisplacements::name`]).
    pub type_name: String,
    /// Its report on its own rows, extras and multipliers.
    pub report: ContactReport,
}

/// The obstacles discretised on a mesh: the concatenated rows and load every solver consumes,
/// and each obstacle's own rows with its row and extra ranges.
#[derive(Clone, Debug, Default)]
pub struct DiscreteObstacles {
    obstacles: Obstacles,
    rows: ConstraintRows,
    load: Vec<f64>,
    parts: Vec<ObstacleRows>,
    /// The slip carried from a load path's previous step (theory §11.6; zero: the total form).
    history: SlipHistory,
}

impl DiscreteObstacles {
    /// The obstacles `obstacles` with their rows `rows` (one entry each, in order): the
    /// concatenation every solver consumes, each obstacle's H columns at its own offset among
    /// the concatenated extras, the loads concatenated, the warnings each naming its
    /// obstacle's path under `path`.
    fn concatenate(obstacles: Obstacles, rows: Vec<ConstraintRows>, path: &str) -> Self {
        let mut parts = Vec::with_capacity(rows.len());
        let (mut n_rows, mut n_extras) = (0, 0);
        for (i, (o, mut rows)) in obstacles.list.iter().zip(rows).enumerate() {
            let p = obstacles.path(path, i);
            let n = o.k.extra_names().len();
            assert!(
                rows.n_extras == n && o.k.load().len() == n,
                "obstacle plugin {:?}: {} extra names, {} load coefficients, {} columns of H",
                o.k.name(),
                n,
                o.k.load().len(),
                rows.n_extras
            );
            rows.warnings = rows.warnings.into_iter().map(|w| naming_path(&p, w)).collect();
            let row_range = n_rows..n_rows + rows.n_rows();
            n_rows = row_range.end;
            parts.push(ObstacleRows { row_range, extra_range: n_extras..n_extras + n, rows });
            n_extras += n;
        }
        let mut all = concatenated(&parts, n_extras, |r| r);
        if parts.iter().any(|p| p.rows.combination.is_some()) {
            let nodal = concatenated(&parts, n_extras, |r| r.combination.as_ref().map_or(r, |c| &c.nodal));
            let t = (parts.iter())
                .flat_map(|p| {
                    let shift = p.row_range.start;
                    (0..p.rows.n_rows()).map(move |i| match &p.rows.combination {
                        Some(c) => c.t[i].iter().map(|&(k, w)| (k + shift, w)).collect(),
                        None => vec![(i + shift, 1.0)],
                    })
                })
                .collect();
            all.combination = Some(Box::new(RowCombination { nodal, t }));
        }
        let load = obstacles.load();
        Self { obstacles, rows: all, load, parts, history: SlipHistory::default() }
    }

    /// K_h with every obstacle's load multiplied by `factor` (theory §11.2): the obstacles
    /// scaled ([`AdmissibleDisplacements::scaled_load`]) and their rows from these
    /// ([`AdmissibleDisplacements::rows_at_factor`]: the same rows with the load alone changed,
    /// where the plugin can). Factor 1 is these obstacles. Errors name the obstacle whose plugin
    /// cannot scale its load, or whose rows at the scaled load cannot be made.
    pub fn at_factor(&self, factor: f64, mesh: &TetMesh, dofs: &DofMap) -> Result<Self, SceneError> {
        self.at_factors(&LoadFactors::uniform(factor), mesh, dofs)
    }

    /// [`DiscreteObstacles::at_factor`] with named loads at factors of their own
    /// ([`AdmissibleDisplacements::scaled_loads`], [`AdmissibleDisplacements::rows_at_factors`]).
    pub fn at_factors(&self, factors: &LoadFactors, mesh: &TetMesh, dofs: &DofMap) -> Result<Self, SceneError> {
        if factors.is_uniform() && factors.all == 1.0 {
            return Ok(self.clone());
        }
        let scaled = self.obstacles.scaled_loads(factors)?;
        let rows = (self.obstacles.list.iter().zip(&self.parts).enumerate())
            .map(|(i, (o, part))| {
                let path = self.obstacles.path(OBSTACLE_PATH, i);
                let own = factors.of_obstacle(o.name.as_deref());
                let Some(c) = &part.rows.combination else {
                    return o.k.rows_at_factors(&own, &part.rows, mesh, dofs, &path).map(|r| r.into_owned());
                };
                // the plugin scales its own (nodal) rows; they are recombined as before
                let nodal = o.k.rows_at_factors(&own, &c.nodal, mesh, dofs, &path)?.into_owned();
                RowCombination::recombine(nodal, c.t.clone())
                    .map_err(|message| SceneError::Region { field: path.clone(), message })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self::concatenate(scaled, rows, OBSTACLE_PATH))
    }

    /// The rows one rank holds of a distributed problem (theory §12): those of the nodes
    /// `local_node` maps to `Some` local node (its owned nodes), their columns renumbered by
    /// `column` (the rank's dof of a free dof of the whole problem). Each obstacle keeps its
    /// extras, load and parameters; its row range is its rows on this rank.
    pub fn restrict(&self, local_node: impl Fn(usize) -> Option<usize>, column: impl Fn(usize) -> usize) -> Self {
        Self::from_restricted(self.obstacles.clone(), self.restricted_rows(local_node, column))
    }

    /// Each obstacle's rows of [`Self::restrict`], before they are concatenated: what a rank is
    /// sent of the whole problem's obstacles (theory §12).
    pub fn restricted_rows(
        &self,
        local_node: impl Fn(usize) -> Option<usize>,
        column: impl Fn(usize) -> usize,
    ) -> Vec<ConstraintRows> {
        self.parts
            .iter()
            .map(|part| {
                let mut rows = ConstraintRows::new(part.rows.n_extras);
                let mut new_row = vec![None; part.rows.n_rows()];
                for (i, kept) in new_row.iter_mut().enumerate() {
                    let Some(node) = local_node(part.rows.node[i]) else { continue };
                    let (cols, vals) = part.rows.row(i);
                    let entries: Vec<(usize, f64)> =
                        cols.iter().map(|&j| column(j)).zip(vals.iter().copied()).collect();
                    *kept = Some(rows.n_rows());
                    rows.push(&entries, part.rows.extra_row(i), part.rows.offset[i], node);
                }
                // a node's normal and tangential rows share its node: kept or dropped together
                rows.friction = part.rows.friction.renumbered(|i| new_row[i]);
                rows.warnings = part.rows.warnings.clone();
                rows
            })
            .collect()
    }

    /// The obstacles `obstacles` on their [`Self::restricted_rows`] `rows` (one entry each).
    pub fn from_restricted(obstacles: Obstacles, rows: Vec<ConstraintRows>) -> Self {
        Self::concatenate(obstacles, rows, OBSTACLE_PATH)
    }

    /// The obstacles.
    pub fn obstacles(&self) -> &Obstacles {
        &self.obstacles
    }

    /// The concatenated rows g(u, V) = G u + H V + c ≥ 0.
    pub fn rows(&self) -> &ConstraintRows {
        &self.rows
    }

    /// The concatenated load coefficients f.
    pub fn load(&self) -> &[f64] {
        &self.load
    }

    /// Each obstacle's rows and ranges, in the order of [`Obstacles::iter`].
    pub fn parts(&self) -> &[ObstacleRows] {
        &self.parts
    }

    /// These obstacles with the slip history `history` of a load path's previous step (theory
    /// §11.6): every tangential row's offset, in the concatenation and in its obstacle's rows,
    /// lowered by the slip it carries, so that the rows give the step's slip increments. A
    /// history of other rows (another problem's) is an error of the caller: it panics.
    pub fn with_history(mut self, history: SlipHistory) -> Self {
        if !history.slip.is_empty() {
            assert_eq!(history.slip.len(), self.rows.n_rows(), "a slip history of other rows");
            history.shift_offsets(&mut self.rows, 0);
            for part in &mut self.parts {
                history.shift_offsets(&mut part.rows, part.row_range.start);
            }
        }
        self.history = history;
        self
    }

    /// Each obstacle's energy dissipated by friction up to the solution (u, V, λ) of these rows:
    /// the history's, plus the step's `−Σ λ_t·Δs` ([`dissipation`]); 0 without friction.
    pub fn dissipated(&self, u: &[f64], extras: &[f64], lambda: &[f64]) -> Vec<f64> {
        if !self.rows.has_friction() {
            return vec![0.0; self.parts.len()];
        }
        let mut increments = vec![0.0; self.rows.n_rows()];
        self.rows.gap(u, extras, &mut increments);
        self.dissipated_with(&increments, lambda)
    }

    /// [`Self::dissipated`] from the rows' values `increments` at the solution.
    fn dissipated_with(&self, increments: &[f64], lambda: &[f64]) -> Vec<f64> {
        self.parts
            .iter()
            .enumerate()
            .map(|(o, p)| {
                let r = p.row_range.clone();
                let before = self.history.dissipated.get(o).copied().unwrap_or(0.0);
                before + dissipation(&p.rows, &lambda[r.clone()], &increments[r])
            })
            .collect()
    }

    /// The slip history after the solution (u, V, λ) of these rows: every tangential row's
    /// slip S + Δs, and [`Self::dissipated`].
    pub fn history_after(&self, u: &[f64], extras: &[f64], lambda: &[f64]) -> SlipHistory {
        if !self.rows.has_friction() {
            return SlipHistory::default();
        }
        let mut increments = vec![0.0; self.rows.n_rows()];
        self.rows.gap(u, extras, &mut increments);
        let dissipated = self.dissipated_with(&increments, lambda);
        let tangential = self.rows.friction.tangential_mask(increments.len());
        let slip = (increments.iter().enumerate())
            .map(|(i, ds)| if tangential[i] { ds + self.history.slip.get(i).copied().unwrap_or(0.0) } else { 0.0 })
            .collect();
        SlipHistory { slip, dissipated }
    }

    /// g(u, V) of the concatenation evaluated directly from the geometry: each obstacle's
    /// [`AdmissibleDisplacements::gap`] on its own rows, extras and slice of `out`.
    pub fn gap(&self, mesh: &TetMesh, dofs: &DofMap, u: &[f64], extras: &[f64], out: &mut [f64]) {
        for (o, p) in self.obstacles.iter().zip(&self.parts) {
            let (v, out) = (&extras[p.extra_range.clone()], &mut out[p.row_range.clone()]);
            match &p.rows.combination {
                None => o.k.gap(mesh, dofs, &p.rows, u, v, out),
                // the plugin's gap is nodal: g̃ = T⁻¹ g (theory §10.1)
                Some(c) => {
                    let mut nodal = vec![0.0; out.len()];
                    o.k.gap(mesh, dofs, &c.nodal, u, v, &mut nodal);
                    c.from_nodal(&nodal, out);
                }
            }
        }
    }

    /// Each obstacle's report on its own rows, extras and multipliers.
    pub fn reports(&self, mesh: &TetMesh, extras: &[f64], lambda: &[f64]) -> Vec<ObstacleReport> {
        self.reports_of(&self.obstacles, mesh, extras, lambda)
    }

    /// Each obstacle of `obstacles` (these rows' obstacles at another load: a load step's) reporting
    /// on these rows — the whole problem's, on rank 0 of a distributed run (theory §12).
    pub fn reports_of(
        &self,
        obstacles: &Obstacles,
        mesh: &TetMesh,
        extras: &[f64],
        lambda: &[f64],
    ) -> Vec<ObstacleReport> {
        obstacles
            .iter()
            .zip(&self.parts)
            .map(|(o, p)| ObstacleReport {
                name: o.name.clone(),
                type_name: o.k.name().to_string(),
                report: o.k.report(mesh, &p.rows, &extras[p.extra_range.clone()], &lambda[p.row_range.clone()]),
            })
            .collect()
    }
}

// ---- scene files: absent, one table, or an array of tables ----

/// An obstacle's table as the plugin sees it: every key but `name`, which is set aside as the
/// keys go by. The plugin reads the table in one pass from the scene's own deserializer (no
/// table rebuilt, the path of a bad field kept), and keeps `deny_unknown_fields`.
struct WithoutName<A> {
    map: A,
    name: Option<String>,
}

impl<'de, A: MapAccess<'de>> MapAccess<'de> for WithoutName<A> {
    type Error = A::Error;

    fn next_key_seed<K: de::DeserializeSeed<'de>>(&mut self, seed: K) -> Result<Option<K::Value>, A::Error> {
        while let Some(key) = self.map.next_key::<String>()? {
            if key == "name" {
                self.name = Some(self.map.next_value()?);
                continue;
            }
            return seed.deserialize(de::IntoDeserializer::<A::Error>::into_deserializer(key)).map(Some);
        }
        Ok(None)
    }

    fn next_value_seed<V: de::DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, A::Error> {
        self.map.next_value_seed(seed)
    }
}

/// An obstacle table: its `name`, the rest read by the plugin.
fn named_from_map<'de, A: MapAccess<'de>>(map: A) -> Result<NamedObstacle, A::Error> {
    let mut rest = WithoutName { map, name: None };
    let k = Box::<dyn AdmissibleDisplacements>::deserialize(de::value::MapAccessDeserializer::new(&mut rest))?;
    Ok(NamedObstacle { name: rest.name, k })
}

/// One element of `[[obstacle]]`.
struct Entry(NamedObstacle);

impl<'de> Deserialize<'de> for Entry {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct EntryVisitor;
        impl<'de> Visitor<'de> for EntryVisitor {
            type Value = Entry;

            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an [[obstacle]] table")
            }

            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Entry, A::Error> {
                named_from_map(map).map(Entry)
            }
        }
        d.deserialize_map(EntryVisitor)
    }
}

struct ObstaclesVisitor;

impl<'de> Visitor<'de> for ObstaclesVisitor {
    type Value = Obstacles;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("an [obstacle] table or an array of [[obstacle]] tables")
    }

    fn visit_none<E: de::Error>(self) -> Result<Obstacles, E> {
        Ok(Obstacles::none())
    }

    fn visit_unit<E: de::Error>(self) -> Result<Obstacles, E> {
        Ok(Obstacles::none())
    }

    fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<Obstacles, D::Error> {
        d.deserialize_any(self)
    }

    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Obstacles, A::Error> {
        Obstacles::single(named_from_map(map)?).map_err(de::Error::custom)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Obstacles, A::Error> {
        let mut list = Vec::new();
        while let Some(Entry(o)) = seq.next_element()? {
            list.push(o);
        }
        Obstacles::new(list).map_err(de::Error::custom)
    }
}

impl<'de> Deserialize<'de> for Obstacles {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(ObstaclesVisitor)
    }
}

/// An obstacle written back as its table with `name` first.
struct EntryRef<'a>(&'a NamedObstacle);

impl Serialize for EntryRef<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(Serialize)]
        struct Flat<'a> {
            #[serde(skip_serializing_if = "Option::is_none")]
            name: &'a Option<String>,
            #[serde(flatten)]
            k: &'a dyn AdmissibleDisplacements,
        }
        Flat { name: &self.0.name, k: self.0.k.as_ref() }.serialize(s)
    }
}

impl Serialize for Obstacles {
    /// The shape it was read in: nothing (none), one table, or an array of tables.
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match (self.array, self.list.as_slice()) {
            (_, []) if !self.array => s.serialize_none(),
            (false, [o]) => EntryRef(o).serialize(s),
            _ => {
                let mut seq = s.serialize_seq(Some(self.list.len()))?;
                for o in &self.list {
                    seq.serialize_element(&EntryRef(o))?;
                }
                seq.end()
            }
        }
    }
}
