//! **K** — the admissible displacements (theory §1, §3): a closed convex set of displacements
//! together with its own extra unknowns V (the punch's U) and the load term ℓ(V) = f·V of the
//! Lagrangian (F·V for the punch).
//!
//! On a mesh, K_h is polyhedral: affine rows `g_i(u, V) = Σ_j G_ij u_j + Σ_k H_ik V_k + c_i ≥ 0`,
//! one per contact node (theory §3). Rows are exactly what solvers need: projecting onto K_h in a
//! metric (Uzawa), linearising it (it is its own linearisation), penalising its violation.

use crate::error::{ParameterError, SceneError};
use crate::mesh::TetMesh;
use crate::mesh::dofs::DofMap;
use crate::problem::friction::{ContactStatus, FrictionRows, SLIP_TOL};
use crate::problem::row_combination::RowCombination;
use std::borrow::Cow;
use std::fmt::Debug;

/// K_h as affine rows g(u, V) = G u + H V + c ≥ 0, G sparse (CSR), H dense.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ConstraintRows {
    /// Number of extra unknowns V (columns of H).
    pub n_extras: usize,
    /// CSR row pointers of G.
    pub row_ptr: Vec<usize>,
    /// Column (free displacement dof) of each entry of G.
    pub col: Vec<usize>,
    /// Value of each entry of G.
    pub val: Vec<f64>,
    /// H, row-major, `n_rows × n_extras`.
    pub extra: Vec<f64>,
    /// c.
    pub offset: Vec<f64>,
    /// The mesh node each row belongs to.
    pub node: Vec<usize>,
    /// Things the user should know about the discretisation (nodes dropped, ...).
    pub warnings: Vec<String>,
    /// Which rows are tangential, and their friction laws (theory §8.3); empty without
    /// friction, every row then a normal row with λ_i ≥ 0.
    pub friction: FrictionRows,
    /// `Some` when these rows are nodal rows recombined, `g = T⁻¹ g_nodal` (theory §10.1): the
    /// nodal rows and T, from which the active-set solvers build a sparse change of basis.
    pub combination: Option<Box<RowCombination>>,
}

impl ConstraintRows {
    /// No rows, `n_extras` extra unknowns.
    pub fn new(n_extras: usize) -> Self {
        Self { n_extras, row_ptr: vec![0], ..Default::default() }
    }

    /// Number of rows.
    pub fn n_rows(&self) -> usize {
        self.offset.len()
    }

    /// Appends the row Σ entries·u + extras·V + offset ≥ 0 of `node`.
    pub fn push(&mut self, entries: &[(usize, f64)], extras: &[f64], offset: f64, node: usize) {
        assert_eq!(extras.len(), self.n_extras);
        for &(j, v) in entries {
            self.col.push(j);
            self.val.push(v);
        }
        self.row_ptr.push(self.col.len());
        self.extra.extend_from_slice(extras);
        self.offset.push(offset);
        self.node.push(node);
    }

    /// True when some rows are tangential rows of a friction law (theory §8.3).
    pub fn has_friction(&self) -> bool {
        !self.friction.is_empty()
    }

    /// Row i of G as (columns, values).
    pub fn row(&self, i: usize) -> (&[usize], &[f64]) {
        let r = self.row_ptr[i]..self.row_ptr[i + 1];
        (&self.col[r.clone()], &self.val[r])
    }

    /// Row i of H.
    pub fn extra_row(&self, i: usize) -> &[f64] {
        &self.extra[i * self.n_extras..(i + 1) * self.n_extras]
    }

    /// (G u)_i: row i's part in u, the displacement of its node along the row's normal, away
    /// from the obstacle.
    pub fn row_times(&self, i: usize, u: &[f64]) -> f64 {
        let (cols, vals) = self.row(i);
        cols.iter().zip(vals).map(|(&j, a)| a * u[j]).sum()
    }

    /// g = G u + H V + c.
    pub fn gap(&self, u: &[f64], v: &[f64], g: &mut [f64]) {
        for (i, gi) in g.iter_mut().enumerate() {
            let gv: f64 = self.extra_row(i).iter().zip(v).map(|(h, x)| h * x).sum();
            *gi = self.row_times(i, u) + gv + self.offset[i];
        }
    }

    /// fu += Gᵀλ, fv += Hᵀλ.
    pub fn add_transpose(&self, lambda: &[f64], fu: &mut [f64], fv: &mut [f64]) {
        for (i, &l) in lambda.iter().enumerate() {
            let (cols, vals) = self.row(i);
            for (&j, a) in cols.iter().zip(vals) {
                fu[j] += a * l;
            }
            for (f, h) in fv.iter_mut().zip(self.extra_row(i)) {
                *f += h * l;
            }
        }
    }
}

/// The contact set of the normal rows of `rows` with multipliers `lambda` (theory §8.3): as
/// [`contact_set`], tangential rows left out.
pub fn normal_contact_set(rows: &ConstraintRows, lambda: &[f64]) -> Vec<usize> {
    if !rows.has_friction() {
        return contact_set(lambda);
    }
    let tangential = rows.friction.tangential_mask(rows.n_rows());
    let lmax = lambda.iter().zip(&tangential).filter(|(_, t)| !**t).map(|(l, _)| *l).fold(0.0, f64::max);
    (0..lambda.len()).filter(|&i| !tangential[i] && lmax > 0.0 && lambda[i] > 1e-8 * lmax).collect()
}

/// The contact set of a multiplier vector: rows with λ_i > 1e-8 · max λ. The relative
/// threshold makes the set the same for solvers that agree to 1e-8.
pub fn contact_set(lambda: &[f64]) -> Vec<usize> {
    let lmax = lambda.iter().copied().fold(0.0, f64::max);
    (0..lambda.len()).filter(|&i| lmax > 0.0 && lambda[i] > 1e-8 * lmax).collect()
}

/// What an obstacle reports about a solution.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContactReport {
    /// Named scalars, each obstacle its own (`U`, `force`, …); reports list them by name.
    pub quantities: Vec<(String, f64)>,
    /// Number of contact nodes (see [`contact_set`]).
    pub contact_nodes: usize,
    /// Largest distance of a contact node from the obstacle's own centre (as the obstacle
    /// defines it; 0 without contact).
    pub contact_radius: f64,
    /// Things the user should know (contact reaching the rim of the candidate zone, ...).
    pub warnings: Vec<String>,
}

impl ContactReport {
    /// The quantity named `name`, if reported.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.quantities.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
    }
}

/// K: admissible displacements with extra unknowns and a load term, chosen by `type` in the
/// `[obstacle]` table of a scene.
#[typetag::serde(tag = "type")]
pub trait AdmissibleDisplacements: Debug + Send + Sync + dyn_clone::DynClone {
    /// The `type` name of the plugin in scene files.
    fn name(&self) -> &'static str {
        self.typetag_name()
    }

    /// Checks the parameters; `path` is the table's path in the scene (`obstacle`).
    fn validate(&self, path: &str) -> Result<(), ParameterError>;

    /// Names of the extra unknowns V (the force-controlled punch: `["U"]`).
    fn extra_names(&self) -> Vec<String>;

    /// The load term ℓ(V) = f·V of the Lagrangian (1.11): the coefficients f (`[F]`).
    fn load(&self) -> Vec<f64>;

    /// K_h on a mesh (theory §3): the rows g(u, V) ≥ 0. Errors name `path`'s fields (a contact
    /// zone with no nodes, a missing group).
    fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError>;

    /// g(u, V) evaluated directly from the geometry at the nodes of `rows` (the current position
    /// of each node against the obstacle). The rows of [`AdmissibleDisplacements::discretise`]
    /// must be its linearisation; the conformance kit of `saddle-contact` checks this.
    fn gap(&self, mesh: &TetMesh, dofs: &DofMap, rows: &ConstraintRows, u: &[f64], extras: &[f64], out: &mut [f64]);

    /// What to report about a solution (U, force, contact set and radius, warnings).
    fn report(&self, mesh: &TetMesh, rows: &ConstraintRows, extras: &[f64], lambda: &[f64]) -> ContactReport;

    /// The same obstacle with its load multiplied by `factor` (a prescribed force, or a
    /// prescribed displacement of a displacement-controlled obstacle), for load sweeps and
    /// load paths; `None` (the default) when the plugin has no load to scale.
    fn scaled_load(&self, factor: f64) -> Option<Box<dyn AdmissibleDisplacements>> {
        let _ = factor;
        None
    }

    /// K_h of this obstacle with its load multiplied by `factor` (theory §11.2), from `rows`, its
    /// rows at its own load: what a load step or a sweep point solves. The default discretises
    /// the scaled obstacle ([`AdmissibleDisplacements::scaled_load`]) again, which is always
    /// right. An obstacle whose rows do not depend on its load (force control: only f scales)
    /// returns `rows` borrowed; one whose offsets carry a prescribed displacement recomputes only
    /// those. The K conformance kit checks the result against the default.
    fn rows_at_factor<'r>(
        &self,
        factor: f64,
        rows: &'r ConstraintRows,
        mesh: &TetMesh,
        dofs: &DofMap,
        path: &str,
    ) -> Result<Cow<'r, ConstraintRows>, SceneError> {
        let _ = rows;
        let scaled = self.scaled_load(factor).ok_or_else(|| {
            ParameterError::new(
                path,
                format!("type = {:?}", self.name()),
                "this obstacle plugin cannot scale its load (AdmissibleDisplacements::scaled_load is None)",
            )
        })?;
        scaled.discretise(mesh, dofs, path).map(Cow::Owned)
    }
}

dyn_clone::clone_trait_object!(AdmissibleDisplacements);

/// (node, status) of every friction block (theory §8.3) of `rows` for the multipliers `lambda`.
pub fn contact_status(rows: &ConstraintRows, lambda: &[f64]) -> Vec<(usize, ContactStatus)> {
    let mut in_contact = vec![false; rows.n_rows()];
    normal_contact_set(rows, lambda).into_iter().for_each(|i| in_contact[i] = true);
    let fr = &rows.friction;
    fr.blocks
        .iter()
        .map(|b| {
            let r = fr.law(b).radius(b.weight, lambda[b.normal]);
            let status = if !in_contact[b.normal] {
                ContactStatus::Separated
            } else if lambda[b.tangent].hypot(lambda[b.tangent + 1]) < (1.0 - SLIP_TOL) * r {
                ContactStatus::Stick
            } else {
                ContactStatus::Slip
            };
            (rows.node[b.normal], status)
        })
        .collect()
}
