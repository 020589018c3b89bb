//! What every nodal element shares: the node → element adjacency and the sparsity pattern of
//! the stiffness, for elements of N nodes each (4 for P1, 10 for P2).

use crate::mesh::dofs::DofMap;
use crate::problem::pattern::SymmetricPattern;
use rayon::prelude::*;

/// Node → (element, local node) adjacency in CSR form: the elements around node n are
/// `adj[ptr[n]..ptr[n + 1]]`.
pub fn node_element_adjacency<const N: usize>(n_nodes: usize, elements: &[[usize; N]]) -> (Vec<usize>, Vec<(u32, u8)>) {
    let mut ptr = vec![0usize; n_nodes + 1];
    for t in elements {
        for &n in t {
            ptr[n + 1] += 1;
        }
    }
    for i in 0..n_nodes {
        ptr[i + 1] += ptr[i];
    }
    let mut fill = ptr.clone();
    let mut adj = vec![(0u32, 0u8); ptr[n_nodes]];
    for (e, t) in elements.iter().enumerate() {
        for (a, &n) in t.iter().enumerate() {
            adj[fill[n]] = (e as u32, a as u8);
            fill[n] += 1;
        }
    }
    (ptr, adj)
}

/// The lower-triangle pattern coupling every pair of free dofs of nodes sharing an element.
pub fn stiffness_pattern<const N: usize>(
    elements: &[[usize; N]],
    dofs: &DofMap,
    adj_ptr: &[usize],
    adj: &[(u32, u8)],
) -> SymmetricPattern {
    let neighbours: Vec<Vec<usize>> = (0..dofs.n_nodes())
        .into_par_iter()
        .map(|b| {
            let mut nb: Vec<usize> = adj[adj_ptr[b]..adj_ptr[b + 1]]
                .iter()
                .flat_map(|&(e, _)| elements[e as usize])
                .filter(|&a| a >= b)
                .collect();
            nb.sort_unstable();
            nb.dedup();
            nb
        })
        .collect();
    let mut col_ptr = Vec::with_capacity(dofs.n_free + 1);
    col_ptr.push(0);
    let mut row_idx = Vec::new();
    for (b, nb) in neighbours.iter().enumerate() {
        for c in 0..3 {
            let Some(j) = dofs.free(b, c) else { continue };
            for &a in nb {
                for k in 0..3 {
                    if let Some(i) = dofs.free(a, k).filter(|&i| i >= j) {
                        row_idx.push(i);
                    }
                }
            }
            col_ptr.push(row_idx.len());
        }
    }
    SymmetricPattern::new(dofs.n_free, col_ptr, row_idx)
}

/// Fills the values of the columns lo..hi of `pattern` (`vals` is their part of the values) by
/// `column(j, values of column j)`, halving the range in parallel until it has at most `leaf`
/// columns: each column owns its slice, so no two threads write the same value.
pub fn assemble_columns(
    pattern: &SymmetricPattern,
    lo: usize,
    hi: usize,
    vals: &mut [f64],
    leaf: usize,
    column: &(impl Fn(usize, &mut [f64]) + Sync),
) {
    let cp = pattern.col_ptr();
    if hi - lo <= leaf {
        let base = cp[lo];
        for j in lo..hi {
            column(j, &mut vals[cp[j] - base..cp[j + 1] - base]);
        }
    } else {
        let mid = (lo + hi) / 2;
        let (a, b) = vals.split_at_mut(cp[mid] - cp[lo]);
        rayon::join(
            || assemble_columns(pattern, lo, mid, a, leaf, column),
            || assemble_columns(pattern, mid, hi, b, leaf, column),
        );
    }
}
