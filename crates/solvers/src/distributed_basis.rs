//! The change of basis of general contact rows (theory §8.1) on a distributed problem (theory
//! §12.2). A rank holds the rows of its owned nodes, so it builds the blocks T_D of its owned
//! dofs itself; but its elements also couple its ghost dofs, and its share of `TᵀKT` on its local
//! pattern needs T there too (T is block diagonal, so `TᵀKT = Σ_ranks T_rᵀ K_r T_r` with T_r the
//! blocks at a rank's local dofs). The owners send them through the ghost exchange of the
//! distributed solver, one vector over the dofs per item:
//!
//! * the block's identity (`1 + rank + size · block`, exact in a double), its size d and the
//!   position a of the dof in it;
//! * row a of T_D, one vector per column (as many as the largest block of any rank).
//!
//! A rank then groups its ghost dofs by block and sorts them, with T_D's rows and columns, into
//! its own numbering. A block must reach a rank whole: its dofs are one node's (node-to-obstacle
//! rows), and a rank holds every free dof of its ghost nodes. Rows whose blocks span nodes owned
//! by different ranks, or reach a ghost dof of their own rank, are refused.

use crate::row_basis::{DenseBlock, RowBasis};
use saddle_core::linalg::{DistributedError, DistributedSpd};
use saddle_core::problem::comm::Comm;
use std::collections::BTreeMap;

/// What the exchange of the blocks found wrong on a rank.
#[derive(Debug, thiserror::Error)]
pub enum GhostBlockError {
    /// The ghost exchange itself failed.
    #[error("ghost exchange of the change of basis: {0}")]
    Exchange(DistributedError),
    /// A block of this rank's rows acts on a dof it does not own.
    #[error("contact rows act on dof {dof}, a ghost of this rank (rows act on the dofs of their own node)")]
    GhostDof {
        /// The local dof.
        dof: usize,
    },
    /// A block reached this rank in part.
    #[error(
        "the change of basis of a block of {size} dofs reached this rank at {received} of them: rows coupling the \
         dofs of several nodes need one process"
    )]
    Partial {
        /// The block's dofs.
        size: usize,
        /// How many of them this rank holds as ghosts.
        received: usize,
    },
}

/// The blocks of T at this rank's ghost dofs (`n_owned` owned dofs first, then the ghosts, `n_local`
/// in all), each as its sorted local dofs and T_D row-major, from the owners' `basis` through
/// `spd`'s ghost exchange (module docs). Collective: every rank calls it.
pub fn ghost_blocks(
    basis: &RowBasis,
    spd: &mut dyn DistributedSpd,
    comm: &dyn Comm,
    n_owned: usize,
    n_local: usize,
) -> Result<Vec<DenseBlock>, GhostBlockError> {
    // what this rank sends: per owned dof, its block's identity, size and position, row of T_D
    let width = comm.max(basis.blocks().map(|(dofs, _)| dofs.len()).max().unwrap_or(0) as f64) as usize;
    let (rank, size) = (comm.rank() as f64, comm.size() as f64);
    let mut id = vec![0.0; n_owned];
    let mut len = vec![0.0; n_owned];
    let mut pos = vec![0.0; n_owned];
    let mut rows = vec![vec![0.0; n_owned]; width];
    let mut outside = None;
    for (b, (dofs, t)) in basis.blocks().enumerate() {
        let d = dofs.len();
        for (a, &j) in dofs.iter().enumerate() {
            if j >= n_owned {
                outside = Some(j);
                continue;
            }
            (id[j], len[j], pos[j]) = (1.0 + rank + size * b as f64, d as f64, a as f64);
            for (k, row) in rows.iter_mut().enumerate().take(d) {
                row[j] = t[a * d + k];
            }
        }
    }
    // the exchange is collective: every rank takes part before any reports its error
    let mut exchanged = Vec::with_capacity(3 + width);
    for owned in [&id, &len, &pos].into_iter().chain(&rows) {
        let mut local = vec![0.0; n_local];
        spd.ghosted(owned, &mut local).map_err(GhostBlockError::Exchange)?;
        exchanged.push(local);
    }
    if let Some(dof) = outside {
        return Err(GhostBlockError::GhostDof { dof });
    }
    let (id, len, pos, rows) = (&exchanged[0], &exchanged[1], &exchanged[2], &exchanged[3..]);
    // the ghost dofs of each block, in the owner's order
    let mut received: BTreeMap<u64, Vec<(usize, usize)>> = BTreeMap::new();
    for j in (n_owned..n_local).filter(|&j| id[j] != 0.0) {
        received.entry(id[j] as u64).or_default().push((pos[j] as usize, j));
    }
    received
        .into_values()
        .map(|mut members| {
            members.sort_unstable();
            let d = len[members[0].1] as usize;
            if members.len() != d || members.iter().enumerate().any(|(a, &(p, _))| p != a) {
                return Err(GhostBlockError::Partial { size: d, received: members.len() });
            }
            // this rank's numbering: the dofs sorted, T_D's rows and columns with them
            let members = &members;
            let mut order: Vec<usize> = (0..d).collect();
            order.sort_unstable_by_key(|&a| members[a].1);
            let dofs = order.iter().map(|&a| members[a].1).collect();
            let t = order.iter().flat_map(|&a| order.iter().map(move |&c| rows[c][members[a].1])).collect();
            Ok((dofs, t))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use saddle_core::linalg::DistributedSolve;
    use saddle_core::problem::comm::SERIAL;
    use saddle_core::{ConstraintRows, SymmetricPattern};

    /// One rank whose ghost dofs 3.. copy the owned dofs `copies` (the exchange of a ghosted
    /// vector, with the rank standing in for the owner).
    struct Mirror {
        copies: Vec<usize>,
    }

    impl DistributedSpd for Mirror {
        fn assemble(&mut self, _: &[usize], _: &[usize], _: &[f64], _: &[usize]) -> Result<(), DistributedError> {
            unreachable!()
        }
        fn diagonal(&mut self, _: &[usize], _: &[f64], _: &mut [f64]) -> Result<(), DistributedError> {
            unreachable!()
        }
        fn ghosted(&mut self, owned: &[f64], local: &mut [f64]) -> Result<(), DistributedError> {
            local[..owned.len()].copy_from_slice(owned);
            for (g, &j) in self.copies.iter().enumerate() {
                local[owned.len() + g] = owned[j];
            }
            Ok(())
        }
        fn change_coordinates(&mut self, _: &dyn Fn(&mut [f64])) -> Result<(), DistributedError> {
            unreachable!()
        }
        fn solve(&mut self, _: &[f64], _: &mut [f64], _: f64) -> Result<DistributedSolve, DistributedError> {
            unreachable!()
        }
    }

    /// Three owned dofs (one node) with a row along a general normal; dofs 3.. ghosts.
    fn basis(n_local: usize) -> RowBasis {
        let mut rows = ConstraintRows::new(0);
        rows.push(&[(0, 0.36), (1, 0.48), (2, 0.8)], &[], 0.0, 0);
        let diagonal = SymmetricPattern::new(n_local, (0..=n_local).collect(), (0..n_local).collect());
        RowBasis::new(&rows, n_local, &diagonal, "newton").unwrap()
    }

    #[test]
    fn a_ghost_block_is_the_owners_t_in_the_ghosts_numbering() {
        // the ghosts of owned dofs 2, 0, 1 at local dofs 3, 4, 5: x_g = x_{copy(g)} must hold for
        // x = T y and x' = T' y' with y'_g = y_{copy(g)}, T' the received block
        let copies = vec![2, 0, 1];
        let owned = basis(6);
        let blocks = ghost_blocks(&owned, &mut Mirror { copies: copies.clone() }, &SERIAL, 3, 6).unwrap();
        assert_eq!(blocks.len(), 1);
        let (dofs, t) = &blocks[0];
        assert_eq!(dofs, &[3, 4, 5]);
        let y = [0.3, -1.1, 0.7];
        let mut x = y.to_vec();
        owned.displacement_from_coordinates(&mut x);
        for (a, &g) in dofs.iter().enumerate() {
            let xg: f64 = (0..3).map(|b| t[3 * a + b] * y[copies[dofs[b] - 3]]).sum();
            assert!((xg - x[copies[g - 3]]).abs() < 1e-15, "ghost {g}: {xg} vs {}", x[copies[g - 3]]);
        }
    }

    #[test]
    fn a_block_that_reaches_a_rank_in_part_is_refused() {
        let owned = basis(5);
        let e = ghost_blocks(&owned, &mut Mirror { copies: vec![0, 2] }, &SERIAL, 3, 5).unwrap_err();
        assert!(matches!(e, GhostBlockError::Partial { size: 3, received: 2 }), "{e}");
    }
}
