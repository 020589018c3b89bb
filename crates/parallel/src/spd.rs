//! Core's distributed SPD matrix as a PETSc matrix and Krylov solver (theory §12): AIJ with block
//! size 3 (three rows per node, [`crate::Layout`]), assembled by adding every rank's lower-triangle
//! values on its local pattern at global rows (and their transposes), the Dirichlet-fixed and the
//! caller's fixed rows and columns replaced by the identity, the rigid-body modes of the owned
//! nodes as GAMG's near-null space (in the coordinates of general contact rows once they are
//! changed, [`DistributedSpd::change_coordinates`]). The solver is CG with GAMG unless PETSc's options say
//! otherwise (`-ksp_type`, `-pc_type hypre`, `-pc_type lu -pc_factor_mat_solver_type mumps`, …).

use crate::funneled::{Funneled, Session};
use crate::layout::Layout;
use saddle_core::linalg::{DistributedError, DistributedSolve, DistributedSpd};
use saddle_mpi::{Error, GhostVector, Index, Ksp, Matrix, Method, Settings};
use std::sync::Arc;

/// The Krylov iteration budget of one solve (a safety net, as Newton's `cg_max_iter`).
pub const MAX_ITERATIONS: usize = 2000;

/// PETSc options set unless the command line or the scene set them: GAMG's Chebyshev smoothers
/// estimate the largest eigenvalue of each level's operator themselves (not from the smoothed
/// aggregation's estimate) and bound the spectrum by 1.2 times it instead of PETSc's 1.1. On a
/// strongly plastic tangent (the DOLFINx peer's punch: E = 1000, h = 100, U = 0.02) PETSc's
/// defaults made CG stop with DIVERGED_INDEFINITE_PC at 1 and 2 ranks (on 8×8×4 hexahedra the
/// bound alone sufficed, on 24×24×12 both are needed); with both it converges to the peer's force.
pub const DEFAULT_OPTIONS: &str = "-pc_gamg_use_sa_esteig false -mg_levels_ksp_chebyshev_esteig 0,0.2,0,1.2";

/// A distributed SPD matrix and its solver (module docs).
pub struct PetscSpd {
    session: Session,
    layout: Arc<Layout>,
    matrix: Funneled<Matrix>,
    ksp: Funneled<Ksp>,
    b: Funneled<GhostVector>,
    x: Funneled<GhostVector>,
    /// A ghosted vector for the diagonal's sums and the ghost exchange.
    sums: Funneled<GhostVector>,
}

fn boxed(e: Error) -> DistributedError {
    Box::new(e)
}

impl PetscSpd {
    /// The matrix of `layout`, preallocated exactly from the layout's
    /// counts of every owned row's couplings, the other ranks' additions included (allowing new
    /// entries instead cost a reallocation of the matrix in the first assembly: rank 0, which owns
    /// the interface's nodes, peaked at 187 MB against rank 1's 118 MB on a 48k-dof P2 scene).
    /// Collective.
    pub fn new(session: &saddle_mpi::Petsc, layout: Arc<Layout>) -> saddle_mpi::Result<Self> {
        let owned_rows = 3 * layout.n_owned_nodes;
        let [d_nnz, o_nnz] = &layout.row_nonzeros;
        let mut matrix = Matrix::new(session, owned_rows, 3, d_nnz, o_nnz)?;
        matrix.set_symmetric()?;
        matrix.set_rigid_body_near_null_space(session, &layout.owned_coordinates)?;
        session.insert_options(DEFAULT_OPTIONS)?;
        let settings = Settings { method: Method::CgGamg, max_iterations: MAX_ITERATIONS, ..Settings::default() };
        let ksp = Ksp::new(session, &settings)?;
        let b = saddle_mpi::GhostVector::new(session, owned_rows, &[])?;
        let x = b.duplicate()?;
        let sums = layout.vector(session)?;
        Ok(Self {
            session: Session(session),
            layout,
            matrix: Funneled(matrix),
            ksp: Funneled(ksp),
            b: Funneled(b),
            x: Funneled(x),
            sums: Funneled(sums),
        })
    }

    /// Adds this rank's lower-triangle `values` on the local pattern (`cp`, `ri`: column
    /// pointers and row indices) and their transposes at the global rows.
    fn add(&mut self, cp: &[usize], ri: &[usize], values: &[f64]) -> saddle_mpi::Result<()> {
        let rows = &self.layout.dof_row;
        let mut global = Vec::new();
        for j in 0..cp.len() - 1 {
            let range = cp[j]..cp[j + 1];
            global.clear();
            global.extend(ri[range.clone()].iter().map(|&i| rows[i]));
            // column j (rows ≥ j), then row j (columns > j): the symmetric matrix's entries
            self.matrix.0.add_values(&global, &[rows[j]], &values[range.clone()])?;
            if range.len() > 1 {
                self.matrix.0.add_values(&[rows[j]], &global[1..], &values[range.start + 1..range.end])?;
            }
        }
        // the diagonal of the Dirichlet rows, which no element adds to: a zero keeps it in the
        // nonzero structure, so that the identity set there after assembly needs no new entry
        // (PETSc drops unused preallocation at assembly; each later insertion reallocates the
        // whole matrix: 3 939 of them cost 2 s on 10k dofs, measured with `-info`)
        for &r in &self.layout.dirichlet_rows {
            self.matrix.0.add_values(&[r], &[r], &[0.0])?;
        }
        Ok(())
    }
}

impl DistributedSpd for PetscSpd {
    fn assemble(
        &mut self,
        col_ptr: &[usize],
        row_idx: &[usize],
        values: &[f64],
        fixed: &[usize],
    ) -> Result<(), DistributedError> {
        self.matrix.0.zero_entries().map_err(boxed)?;
        self.add(col_ptr, row_idx, values).map_err(boxed)?;
        self.matrix.0.assemble().map_err(boxed)?;
        let mut rows: Vec<Index> = self.layout.dirichlet_rows.clone();
        rows.extend(fixed.iter().map(|&s| self.layout.dof_row[s]));
        self.matrix.0.zero_rows_columns(&rows, 1.0).map_err(boxed)?;
        self.ksp.0.set_operator(&self.matrix.0).map_err(boxed)
    }

    fn diagonal(&mut self, cp: &[usize], values: &[f64], out: &mut [f64]) -> Result<(), DistributedError> {
        let v = &mut self.sums.0;
        {
            let mut form = v.local_mut().map_err(boxed)?;
            form.iter_mut().for_each(|x| *x = 0.0);
            for (d, &s) in self.layout.dof_slot.iter().enumerate() {
                form[s] += values[cp[d]];
            }
        }
        v.accumulate_ghosts().map_err(boxed)?;
        let form = v.local().map_err(boxed)?;
        for (d, x) in out.iter_mut().enumerate() {
            *x = form[self.layout.dof_slot[d]];
        }
        Ok(())
    }

    fn ghosted(&mut self, owned: &[f64], local: &mut [f64]) -> Result<(), DistributedError> {
        let v = &mut self.sums.0;
        {
            let mut form = v.local_mut().map_err(boxed)?;
            form.iter_mut().for_each(|x| *x = 0.0);
            for (&x, &s) in owned.iter().zip(&self.layout.dof_slot) {
                form[s] = x;
            }
        }
        v.update_ghosts().map_err(boxed)?;
        let form = v.local().map_err(boxed)?;
        for (x, &s) in local.iter_mut().zip(&self.layout.dof_slot) {
            *x = form[s];
        }
        Ok(())
    }

    fn change_coordinates(&mut self, to_coordinates: &dyn Fn(&mut [f64])) -> Result<(), DistributedError> {
        let layout = &self.layout;
        let mut modes = rigid_body_modes(&layout.owned_coordinates);
        let mut owned = vec![0.0; layout.n_owned_dofs];
        for mode in &mut modes {
            for (x, &s) in owned.iter_mut().zip(&layout.dof_slot) {
                *x = mode[s];
            }
            to_coordinates(&mut owned);
            for (&x, &s) in owned.iter().zip(&layout.dof_slot) {
                mode[s] = x;
            }
        }
        self.matrix.0.set_near_null_space(self.session.get(), &modes).map_err(boxed)?;
        // measured on the rigid cone (tests/mpi_cone.rs, 1–3 ranks): with the estimate made for
        // the prolongator GAMG's Chebyshev smoothers see too small a largest eigenvalue in these
        // coordinates and CG stops at DIVERGED_INDEFINITE_PC; their own estimates converge
        self.ksp.0.gamg_reuse_prolongator_estimate(false).map_err(boxed)
    }

    fn solve(&mut self, b: &[f64], x: &mut [f64], rtol: f64) -> Result<DistributedSolve, DistributedError> {
        let slots = &self.layout.dof_slot;
        for (vector, values) in [(&mut self.b.0, b), (&mut self.x.0, &*x)] {
            let mut form = vector.local_mut().map_err(boxed)?;
            form.iter_mut().for_each(|v| *v = 0.0);
            for (d, &v) in values.iter().enumerate() {
                form[slots[d]] = v;
            }
        }
        self.ksp.0.initial_guess_nonzero(true).map_err(boxed)?;
        self.ksp.0.set_relative_tolerance(rtol).map_err(boxed)?;
        let result = match self.ksp.0.solve(&self.b.0, &mut self.x.0) {
            Ok(report) => DistributedSolve { iterations: report.iterations, converged: true },
            // the budget ran out: the last iterate is used and counted (inexact Newton)
            Err(Error::Diverged { reason, iterations, .. }) if reason.contains("DIVERGED_ITS") => {
                DistributedSolve { iterations, converged: false }
            }
            Err(e) => return Err(boxed(e)),
        };
        let form = self.x.0.local().map_err(boxed)?;
        for (d, v) in x.iter_mut().enumerate() {
            *v = form[slots[d]];
        }
        Ok(result)
    }
}

/// The six rigid-body motions at the owned rows (three per node): the translations e_x, e_y,
/// e_z and the rotations ω × x about the axes, from the nodes' `coordinates` (x, y, z per node).
fn rigid_body_modes(coordinates: &[f64]) -> Vec<Vec<f64>> {
    let mut modes = vec![vec![0.0; coordinates.len()]; 6];
    for (node, x) in coordinates.chunks_exact(3).enumerate() {
        let r = 3 * node;
        for c in 0..3 {
            modes[c][r + c] = 1.0;
        }
        // ω × x for ω = e_x, e_y, e_z: (0, −z, y), (z, 0, −x), (−y, x, 0)
        for (mode, w) in modes[3..].iter_mut().zip([[0.0, -x[2], x[1]], [x[2], 0.0, -x[0]], [-x[1], x[0], 0.0]]) {
            mode[r..r + 3].copy_from_slice(&w);
        }
    }
    modes
}
