//! L without some rows and extras (theory §11.3): what a solver sees of a step in which a
//! force-controlled obstacle carries no load. Its multipliers are then zero (Hᵀλ = 0 with a
//! column of H of one strict sign and λ ≥ 0 forces λ = 0), its rows drop out, and its extras
//! are undetermined: any position out of contact is admissible.

use crate::problem::displacements::ConstraintRows;
use crate::problem::displacements::RowCombination;
use crate::problem::lagrangian::{Data, Lagrangian};

/// The rows `rows_kept` of `all` on the extras `extras_kept`.
fn kept(all: &ConstraintRows, rows_kept: &[usize], extras_kept: &[usize]) -> ConstraintRows {
    let mut rows = ConstraintRows::new(extras_kept.len());
    let mut h = vec![0.0; extras_kept.len()];
    for &i in rows_kept {
        h.iter_mut().zip(extras_kept).for_each(|(x, &k)| *x = all.extra_row(i)[k]);
        rows.push_row_of(all, i, &h);
    }
    rows.warnings = all.warnings.clone();
    rows
}

/// The rows `rows_kept` and the extras `extras_kept` (both ascending) of a problem's K_h, and
/// their load: the data a reduced L replaces ([`Reduced::lagrangian`]).
#[derive(Debug)]
pub struct Reduced {
    rows: ConstraintRows,
    load: Vec<f64>,
    rows_kept: Vec<usize>,
    extras_kept: Vec<usize>,
}

impl Reduced {
    /// The kept rows and extras of `l`'s K_h.
    pub fn new(l: &Lagrangian<'_>, rows_kept: Vec<usize>, extras_kept: Vec<usize>) -> Self {
        let all = l.data.rows;
        let mut rows = kept(all, &rows_kept, &extras_kept);
        if let Some(c) = &all.combination {
            // whole obstacles are dropped, and T combines rows of one obstacle only
            let mut index = vec![usize::MAX; all.n_rows()];
            rows_kept.iter().enumerate().for_each(|(k, &i)| index[i] = k);
            let t = rows_kept.iter().map(|&i| c.t[i].iter().map(|&(k, w)| (index[k], w)).collect()).collect();
            let nodal = kept(&c.nodal, &rows_kept, &extras_kept);
            rows.combination = Some(Box::new(RowCombination { nodal, t }));
        }
        let load = extras_kept.iter().map(|&k| l.data.load[k]).collect();
        Self { rows, load, rows_kept, extras_kept }
    }

    /// `l` with the kept rows and extras only: the same operators and other data.
    pub fn lagrangian<'a>(&'a self, l: &Lagrangian<'a>) -> Lagrangian<'a> {
        l.with_data(Data { rows: &self.rows, load: &self.load, ..l.data })
    }

    /// The kept rows.
    pub fn rows_kept(&self) -> &[usize] {
        &self.rows_kept
    }

    /// The kept extras.
    pub fn extras_kept(&self) -> &[usize] {
        &self.extras_kept
    }

    /// A vector over all rows restricted to the kept ones.
    pub fn restrict_rows(&self, x: &[f64]) -> Vec<f64> {
        self.rows_kept.iter().map(|&i| x[i]).collect()
    }

    /// A vector over all extras restricted to the kept ones.
    pub fn restrict_extras(&self, x: &[f64]) -> Vec<f64> {
        self.extras_kept.iter().map(|&k| x[k]).collect()
    }
}
