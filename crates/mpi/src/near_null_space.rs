//! The near-null space of elasticity for algebraic multigrid: the six rigid-body modes (three
//! translations, three rotations about the centroid), built by PETSc from the coordinates of the
//! owned nodes and orthonormalised (`MatNullSpaceCreateRigidBody`), attached with
//! `MatSetNearNullSpace`. GAMG builds its coarse spaces from them; without them it sees only the
//! constants of each block (the translations) and converges more slowly on elasticity. A matrix
//! in other coordinates than the displacements' takes the modes in its coordinates
//! ([`Matrix::set_near_null_space`]).

use crate::collective::sum_in_place;
use crate::error::{Result, check, check_len, discard};
use crate::ffi;
use crate::matrix::Matrix;
use crate::session::{Petsc, petsc_comm_world};
use crate::vector::{DECIDE, GhostVector};
use std::ptr;

/// The dimension of the displacement field (and the block size of its matrix).
const DIM: usize = 3;

impl Matrix {
    /// Sets the rigid-body modes of the owned nodes as the near-null space. `owned_coordinates`
    /// holds x, y, z of each node whose three displacement rows this rank owns, in the order of
    /// the rows (one value per owned row). Collective.
    pub fn set_rigid_body_near_null_space(&mut self, session: &Petsc, owned_coordinates: &[f64]) -> Result<()> {
        check_len("owned_coordinates (one per owned row)", owned_coordinates.len(), self.owned_rows().len())?;
        let mut coords = ptr::null_mut();
        // SAFETY: wraps the caller's array (not copied, not written), alive until destroyed below.
        check("VecCreateMPIWithArray", unsafe {
            ffi::VecCreateMPIWithArray(
                petsc_comm_world(session),
                DIM as ffi::PetscInt,
                owned_coordinates.len() as ffi::PetscInt,
                DECIDE,
                owned_coordinates.as_ptr(),
                &mut coords,
            )
        })?;
        let mut space = ptr::null_mut();
        // SAFETY: `coords` is live with block size 3; the space copies what it needs.
        let created =
            check("MatNullSpaceCreateRigidBody", unsafe { ffi::MatNullSpaceCreateRigidBody(coords, &mut space) });
        // SAFETY: `coords` is no longer used.
        discard(unsafe { ffi::VecDestroy(&mut coords) });
        created?;
        // SAFETY: the matrix takes its own reference to the space.
        let set = check("MatSetNearNullSpace", unsafe { ffi::MatSetNearNullSpace(self.raw, space) });
        // SAFETY: drops this function's reference.
        discard(unsafe { ffi::MatNullSpaceDestroy(&mut space) });
        set
    }

    /// Sets the span of `modes` as the near-null space: each mode one value per owned row (in
    /// the order of the rows), orthonormalised here over the ranks (modified Gram–Schmidt, twice;
    /// a mode dependent on the others is dropped). Collective.
    pub fn set_near_null_space(&mut self, session: &Petsc, modes: &[Vec<f64>]) -> Result<()> {
        let rows = self.owned_rows().len();
        let mut basis: Vec<Vec<f64>> = Vec::with_capacity(modes.len());
        for mode in modes {
            check_len("a near-null mode (one value per owned row)", mode.len(), rows)?;
            let size = global_dots(session, mode, &[mode])[0].sqrt();
            let mut v = mode.clone();
            for _ in 0..2 {
                for (b, c) in basis.iter().zip(global_dots(session, &v, &basis)) {
                    v.iter_mut().zip(b).for_each(|(x, y)| *x -= c * y);
                }
            }
            let rest = global_dots(session, &v, &[&v])[0].sqrt();
            // dependent on the modes before it (to round-off): nothing new
            if rest > 1e-10 * size {
                v.iter_mut().for_each(|x| *x /= rest);
                basis.push(v);
            }
        }
        // PETSc's own vectors: the space keeps references to them, not copies
        let mut vecs = Vec::with_capacity(basis.len());
        for v in &basis {
            let mut vec = GhostVector::new(session, rows, &[])?;
            vec.local_mut()?.copy_from_slice(v);
            vecs.push(vec);
        }
        let raws: Vec<ffi::Vec> = vecs.iter().map(|v| v.raw).collect();
        let mut space = ptr::null_mut();
        // SAFETY: the vectors are live and orthonormal; the space takes its own references.
        let created = check("MatNullSpaceCreate", unsafe {
            ffi::MatNullSpaceCreate(
                petsc_comm_world(session),
                ffi::PetscBool::PETSC_FALSE,
                raws.len() as ffi::PetscInt,
                raws.as_ptr(),
                &mut space,
            )
        });
        drop(vecs);
        created?;
        // SAFETY: the matrix takes its own reference to the space.
        let set = check("MatSetNearNullSpace", unsafe { ffi::MatSetNearNullSpace(self.raw, space) });
        // SAFETY: drops this function's reference.
        discard(unsafe { ffi::MatNullSpaceDestroy(&mut space) });
        set
    }

    /// Removes the near-null space (GAMG falls back to the constants of each block).
    pub fn clear_near_null_space(&mut self) -> Result<()> {
        // SAFETY: a null space removes the attached one.
        check("MatSetNearNullSpace", unsafe { ffi::MatSetNearNullSpace(self.raw, ptr::null_mut()) })
    }
}

/// The dot products of `v` with each of `others`, summed over the ranks.
fn global_dots<B: AsRef<[f64]>>(session: &Petsc, v: &[f64], others: &[B]) -> Vec<f64> {
    let mut dots: Vec<f64> = others.iter().map(|b| v.iter().zip(b.as_ref()).map(|(x, y)| x * y).sum()).collect();
    sum_in_place(session.world(), &mut dots);
    dots
}
