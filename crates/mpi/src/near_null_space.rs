//! The near-null space of elasticity for algebraic multigrid: the six rigid-body modes (three
//! translations, three rotations about the centroid), built by PETSc from the coordinates of the
//! owned nodes and orthonormalised (`MatNullSpaceCreateRigidBody`), attached with
//! `MatSetNearNullSpace`. GAMG builds its coarse spaces from them; without them it sees only the
//! constants of each block (the translations) and converges more slowly on elasticity.

use crate::error::{Result, check, check_len, discard};
use crate::ffi;
use crate::matrix::Matrix;
use crate::session::{Petsc, petsc_comm_world};
use crate::vector::DECIDE;
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

    /// Removes the near-null space (GAMG falls back to the constants of each block).
    pub fn clear_near_null_space(&mut self) -> Result<()> {
        // SAFETY: a null space removes the attached one.
        check("MatSetNearNullSpace", unsafe { ffi::MatSetNearNullSpace(self.raw, ptr::null_mut()) })
    }
}
