//! L without some rows and extras (theory §11.3): what a solver sees of a step in which a
//! force-controlled obstacle carries no load. Its multipliers are then zero (Hᵀλ = 0 with a
//! column of H of one strict sign and λ ≥ 0 forces λ = 0), its rows drop out, and its extras
//! are undetermined: any position out of contact is admissible.

use crate::problem::displacements::ConstraintRows;
use crate::problem::elasticity::Elasticity;
use crate::problem::lagrangian::{Lagrangian, Material, RigidBodyModes};
use crate::problem::pattern::SymmetricPattern;
use crate::problem::state::PlasticState;
use crate::problem::stresses::AdmissibleStresses;
use crate::problem::tensor::Sym;

/// `inner` with the rows `rows_kept` and the extras `extras_kept` only (both ascending).
#[derive(Debug)]
pub struct Reduced<'a, L: Lagrangian + ?Sized> {
    inner: &'a L,
    rows: ConstraintRows,
    load: Vec<f64>,
    rows_kept: Vec<usize>,
    extras_kept: Vec<usize>,
}

impl<'a, L: Lagrangian + ?Sized> Reduced<'a, L> {
    /// `inner` without the rows and extras not kept.
    pub fn new(inner: &'a L, rows_kept: Vec<usize>, extras_kept: Vec<usize>) -> Self {
        let all = inner.constraints();
        let mut rows = ConstraintRows::new(extras_kept.len());
        for &i in &rows_kept {
            let (cols, vals) = all.row(i);
            let entries: Vec<(usize, f64)> = cols.iter().copied().zip(vals.iter().copied()).collect();
            let h: Vec<f64> = extras_kept.iter().map(|&k| all.extra_row(i)[k]).collect();
            rows.push(&entries, &h, all.offset[i], all.node[i]);
        }
        rows.warnings = all.warnings.clone();
        let load = extras_kept.iter().map(|&k| inner.load()[k]).collect();
        Self { inner, rows, load, rows_kept, extras_kept }
    }

    /// The kept rows of `inner`.
    pub fn rows_kept(&self) -> &[usize] {
        &self.rows_kept
    }

    /// The kept extras of `inner`.
    pub fn extras_kept(&self) -> &[usize] {
        &self.extras_kept
    }

    /// A vector over `inner`'s rows restricted to the kept ones.
    pub fn restrict_rows(&self, x: &[f64]) -> Vec<f64> {
        self.rows_kept.iter().map(|&i| x[i]).collect()
    }

    /// A vector over `inner`'s extras restricted to the kept ones.
    pub fn restrict_extras(&self, x: &[f64]) -> Vec<f64> {
        self.extras_kept.iter().map(|&k| x[k]).collect()
    }
}

impl<L: Lagrangian + ?Sized> Lagrangian for Reduced<'_, L> {
    fn n_dofs(&self) -> usize {
        self.inner.n_dofs()
    }
    fn n_points(&self) -> usize {
        self.inner.n_points()
    }
    fn elasticity(&self) -> &Elasticity {
        self.inner.elasticity()
    }
    fn stresses(&self) -> Option<&dyn AdmissibleStresses> {
        self.inner.stresses()
    }
    fn constraints(&self) -> &ConstraintRows {
        &self.rows
    }
    fn load(&self) -> &[f64] {
        &self.load
    }
    fn weights(&self) -> &[f64] {
        self.inner.weights()
    }
    fn strain(&self, u: &[f64], eps: &mut [Sym]) {
        self.inner.strain(u, eps)
    }
    fn divergence(&self, sigma: &[Sym], f: &mut [f64]) {
        self.inner.divergence(sigma, f)
    }
    fn strain_entries(&self) -> Vec<(usize, usize, usize, f64)> {
        self.inner.strain_entries()
    }
    fn pattern(&self) -> &SymmetricPattern {
        self.inner.pattern()
    }
    fn assemble(&self, material: Material<'_>, values: &mut [f64]) {
        self.inner.assemble(material, values)
    }
    fn rigid_body_modes(&self) -> Option<RigidBodyModes> {
        self.inner.rigid_body_modes()
    }
    fn nodal_load(&self) -> &[f64] {
        self.inner.nodal_load()
    }
    fn state(&self) -> Option<&PlasticState> {
        self.inner.state()
    }
    fn state_force_norm(&self) -> f64 {
        self.inner.state_force_norm()
    }
}
