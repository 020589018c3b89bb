//! The dual quadratic contact rows of P2 (theory §10.1; B. Wohlmuth, A. Popp, M. W. Gee,
//! W. A. Wall, *An abstract framework for a priori estimates for contact problems in 3D with
//! quadratic finite elements*, Comput. Mech. 50 (2012) 1–14, α = 1/5): the modified quadratic
//! basis `Ñ_v = N_v + α Σ_{e∋v} N_e`, `Ñ_e = (1 − 2α) N_e` on the contact facets is the change
//! of surface dofs `d = T d̃` (`d_e = (1 − 2α) d̃_e + α(d̃_a + d̃_b)` for the edge node e of the
//! edge ab), and the weighted gaps of the multipliers biorthogonal to Ñ are the nodal rows
//! recombined, `g̃ = T⁻¹ g`: vertex rows kept, an edge row `(g_e − α(g_a + g_b))/(1 − 2α)`.
//! Any node-based obstacle's rows are recombined alike; no obstacle knows of it.

use crate::mesh::{TET_EDGES, TetMesh};
use crate::problem::displacements::ConstraintRows;
use crate::problem::displacements::RowCombination;
use serde::{Deserialize, Serialize};

/// α of the modified quadratic basis: the share of an edge function moved to each of its
/// vertices (Wohlmuth et al. 2012; α = 1/5 makes ∫Ñ positive at vertices and edges alike,
/// 2|F|/15 and |F|/5 of a facet F).
pub const ALPHA: f64 = 0.2;

/// The contact rows of the P2 element: `[discretisation] contact_rows = …`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactRows {
    /// One row per candidate node, vertices and edge nodes alike (theory §10.1, "Contact rows").
    #[default]
    Nodal,
    /// The nodal rows recombined by the dual quadratic basis (module docs).
    DualQuadratic,
}

impl ContactRows {
    /// True for [`ContactRows::Nodal`] (the default, not written back to scenes).
    pub fn is_nodal(&self) -> bool {
        *self == ContactRows::Nodal
    }
}

/// T of the dual quadratic rows for the nodal rows `rows` on the second-order `mesh`: an edge
/// node's row combines the rows of its edge's two vertices when both carry one; every other
/// row is kept. An error when a node carries two rows of one obstacle (friction's tangential
/// rows, or two normals).
pub fn combination(mesh: &TetMesh, rows: &ConstraintRows) -> Result<Vec<Vec<(usize, f64)>>, String> {
    let so = mesh.second_order.as_ref().ok_or("dual quadratic contact rows need a second-order mesh")?;
    let mut row_of = vec![usize::MAX; mesh.n_nodes()];
    for (i, &n) in rows.node.iter().enumerate() {
        if row_of[n] != usize::MAX {
            return Err(format!(
                "node {n} carries rows {} and {i}: dual quadratic contact rows need one row per node and obstacle \
                 (use contact_rows = \"nodal\")",
                row_of[n]
            ));
        }
        row_of[n] = i;
    }
    // the two vertices of each edge node that carries a row
    let mut ends = vec![[usize::MAX; 2]; rows.n_rows()];
    for (t, edges) in mesh.tets.iter().zip(&so.tet_edges) {
        for (k, &e) in edges.iter().enumerate() {
            if row_of[e] != usize::MAX {
                ends[row_of[e]] = TET_EDGES[k].map(|v| t[v]);
            }
        }
    }
    Ok((0..rows.n_rows())
        .map(|i| match ends[i].map(|v| if v == usize::MAX { usize::MAX } else { row_of[v] }) {
            [a, b] if a != usize::MAX && b != usize::MAX => vec![(i, 1.0 - 2.0 * ALPHA), (a, ALPHA), (b, ALPHA)],
            _ => vec![(i, 1.0)],
        })
        .collect())
}

/// The dual quadratic rows of the nodal rows `rows` on the second-order `mesh` (module docs).
pub fn dual_quadratic_rows(mesh: &TetMesh, rows: ConstraintRows) -> Result<ConstraintRows, String> {
    let t = combination(mesh, &rows)?;
    RowCombination::recombine(rows, t)
}
