//! Distributed vectors with ghosts (`VecCreateGhost`): each rank owns a contiguous range of the
//! global entries and keeps copies of some others' (its ghosts). The local form is one slice,
//! the owned entries then the ghosts in the order given at creation. Forward update: owners →
//! ghosts (insert); reverse update: ghosts → owners (add), the assembly of a vector from the
//! elements of each rank.

use crate::Index;
use crate::error::{Result, check, check_len, discard, petsc_int};
use crate::ffi;
use crate::session::{Petsc, finalized, petsc_comm_world};
use std::ops::{Deref, DerefMut, Range};
use std::ptr::{self, NonNull};

/// PETSc's `PETSC_DECIDE`/`PETSC_DETERMINE`: a size PETSc computes.
pub(crate) const DECIDE: ffi::PetscInt = -1;

/// A distributed vector of f64 with ghost entries.
pub struct GhostVector {
    pub(crate) raw: ffi::Vec,
    owned: Range<usize>,
    global_len: usize,
    ghosts: usize,
}

impl GhostVector {
    /// A zero vector owning `owned` consecutive entries on this rank (ranks in order), with copies
    /// of the entries at the global indices `ghosts` (none of them owned by this rank).
    /// Collective.
    pub fn new(session: &Petsc, owned: usize, ghosts: &[Index]) -> Result<Self> {
        let mut raw = ptr::null_mut();
        // SAFETY: `ghosts` holds `ghosts.len()` indices; PETSc copies them.
        check("VecCreateGhost", unsafe {
            ffi::VecCreateGhost(
                petsc_comm_world(session),
                petsc_int("owned entries", owned)?,
                DECIDE,
                petsc_int("ghost entries", ghosts.len())?,
                ghosts.as_ptr(),
                &mut raw,
            )
        })?;
        Self::wrap(raw, ghosts.len())
    }

    /// Takes ownership of a ghosted vector created by PETSc; reads its layout.
    fn wrap(raw: ffi::Vec, ghosts: usize) -> Result<Self> {
        let mut this = Self { raw, owned: 0..0, global_len: 0, ghosts };
        let (mut lo, mut hi, mut n): (ffi::PetscInt, ffi::PetscInt, ffi::PetscInt) = (0, 0, 0);
        // SAFETY: `raw` is a live vector.
        check("VecGetOwnershipRange", unsafe { ffi::VecGetOwnershipRange(raw, &mut lo, &mut hi) })?;
        // SAFETY: as above.
        check("VecGetSize", unsafe { ffi::VecGetSize(raw, &mut n) })?;
        this.owned = lo as usize..hi as usize;
        this.global_len = n as usize;
        Ok(this)
    }

    /// A new zero vector with the same layout and ghosts. Collective.
    pub fn duplicate(&self) -> Result<Self> {
        let mut raw = ptr::null_mut();
        // SAFETY: `self.raw` is live; the duplicate of a ghosted vector is ghosted alike.
        check("VecDuplicate", unsafe { ffi::VecDuplicate(self.raw, &mut raw) })?;
        Self::wrap(raw, self.ghosts)
    }

    /// The global indices this rank owns.
    pub fn owned_range(&self) -> Range<usize> {
        self.owned.clone()
    }

    /// The number of owned entries.
    pub fn owned_len(&self) -> usize {
        self.owned.len()
    }

    /// The number of ghost entries.
    pub fn ghost_len(&self) -> usize {
        self.ghosts
    }

    /// The global length.
    pub fn global_len(&self) -> usize {
        self.global_len
    }

    /// The local form for reading: owned entries, then ghosts (as last updated).
    pub fn local(&self) -> Result<Local<'_>> {
        let form = LocalForm::get(self.raw)?;
        let mut data = ptr::null();
        // SAFETY: `form.0` is the live local form; the array stays valid until restored in Drop.
        check("VecGetArrayRead", unsafe { ffi::VecGetArrayRead(form.0, &mut data) })?;
        Ok(Local { form, data, len: self.owned.len() + self.ghosts, _vector: self })
    }

    /// The local form for writing: owned entries, then ghosts.
    pub fn local_mut(&mut self) -> Result<LocalMut<'_>> {
        let form = LocalForm::get(self.raw)?;
        let mut data = ptr::null_mut();
        // SAFETY: as in `local`; `&mut self` makes this the only access.
        check("VecGetArray", unsafe { ffi::VecGetArray(form.0, &mut data) })?;
        let len = self.owned.len() + self.ghosts;
        Ok(LocalMut { form, data, len, _vector: self })
    }

    /// Forward update: each ghost takes its owner's value (`INSERT_VALUES`, `SCATTER_FORWARD`).
    /// Collective.
    pub fn update_ghosts(&mut self) -> Result<()> {
        self.scatter(ffi::InsertMode::INSERT_VALUES, ffi::ScatterMode::SCATTER_FORWARD)
    }

    /// Reverse update: each owner adds the values of its ghost copies to its own (`ADD_VALUES`,
    /// `SCATTER_REVERSE`); the ghosts keep their values. Collective.
    pub fn accumulate_ghosts(&mut self) -> Result<()> {
        self.scatter(ffi::InsertMode::ADD_VALUES, ffi::ScatterMode::SCATTER_REVERSE)
    }

    fn scatter(&mut self, insert: ffi::InsertMode, mode: ffi::ScatterMode) -> Result<()> {
        // SAFETY: `self.raw` is a live ghosted vector.
        check("VecGhostUpdateBegin", unsafe { ffi::VecGhostUpdateBegin(self.raw, insert, mode) })?;
        // SAFETY: as above, after the matching begin.
        check("VecGhostUpdateEnd", unsafe { ffi::VecGhostUpdateEnd(self.raw, insert, mode) })
    }

    /// Sets every owned entry to `value` (ghosts unchanged until the next forward update).
    pub fn set(&mut self, value: f64) -> Result<()> {
        // SAFETY: `self.raw` is live.
        check("VecSet", unsafe { ffi::VecSet(self.raw, value) })
    }

    /// Copies the owned entries of `other` (the same layout) into `self`.
    pub fn copy_from(&mut self, other: &GhostVector) -> Result<()> {
        check_len("copy_from: owned entries", other.owned_len(), self.owned_len())?;
        // SAFETY: both live, with the same layout.
        check("VecCopy", unsafe { ffi::VecCopy(other.raw, self.raw) })
    }

    /// `self += alpha x` on the owned entries.
    pub fn axpy(&mut self, alpha: f64, x: &GhostVector) -> Result<()> {
        check_len("axpy: owned entries", x.owned_len(), self.owned_len())?;
        // SAFETY: both live, with the same layout.
        check("VecAXPY", unsafe { ffi::VecAXPY(self.raw, alpha, x.raw) })
    }

    /// The global dot product Σ self_i other_i over owned entries of every rank. Collective.
    pub fn dot(&self, other: &GhostVector) -> Result<f64> {
        check_len("dot: owned entries", other.owned_len(), self.owned_len())?;
        let mut d = 0.0;
        // SAFETY: both live, with the same layout.
        check("VecDot", unsafe { ffi::VecDot(self.raw, other.raw, &mut d) })?;
        Ok(d)
    }

    /// The global Euclidean norm. Collective.
    pub fn norm2(&self) -> Result<f64> {
        self.norm(ffi::NormType::NORM_2)
    }

    /// The global maximum norm. Collective.
    pub fn norm_max(&self) -> Result<f64> {
        self.norm(ffi::NormType::NORM_INFINITY)
    }

    fn norm(&self, kind: ffi::NormType) -> Result<f64> {
        let mut n = 0.0;
        // SAFETY: `self.raw` is live.
        check("VecNorm", unsafe { ffi::VecNorm(self.raw, kind, &mut n) })?;
        Ok(n)
    }
}

impl Drop for GhostVector {
    fn drop(&mut self) {
        if !finalized() {
            // SAFETY: `self.raw` is owned by `self` and not used afterwards.
            discard(unsafe { ffi::VecDestroy(&mut self.raw) });
        }
    }
}

/// The sequential local form of a ghosted vector (owned + ghosts), restored on drop.
struct LocalForm(ffi::Vec, ffi::Vec);

impl LocalForm {
    fn get(global: ffi::Vec) -> Result<Self> {
        let mut local = ptr::null_mut();
        // SAFETY: `global` is a live ghosted vector.
        check("VecGhostGetLocalForm", unsafe { ffi::VecGhostGetLocalForm(global, &mut local) })?;
        Ok(Self(local, global))
    }
}

impl Drop for LocalForm {
    fn drop(&mut self) {
        // SAFETY: restores the form obtained in `get`.
        discard(unsafe { ffi::VecGhostRestoreLocalForm(self.1, &mut self.0) });
    }
}

fn slice_parts<T>(data: *mut T, len: usize) -> *mut T {
    if len == 0 { NonNull::dangling().as_ptr() } else { data }
}

/// The local form of a [`GhostVector`] for reading (derefs to `&[f64]`).
pub struct Local<'a> {
    form: LocalForm,
    data: *const f64,
    len: usize,
    _vector: &'a GhostVector,
}

impl Deref for Local<'_> {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        // SAFETY: PETSc's array of the local form, `len` entries, valid until Drop.
        unsafe { std::slice::from_raw_parts(slice_parts(self.data.cast_mut(), self.len), self.len) }
    }
}

impl Drop for Local<'_> {
    fn drop(&mut self) {
        // SAFETY: restores the array obtained in `GhostVector::local`.
        discard(unsafe { ffi::VecRestoreArrayRead(self.form.0, &mut self.data) });
    }
}

/// The local form of a [`GhostVector`] for writing (derefs to `&mut [f64]`).
pub struct LocalMut<'a> {
    form: LocalForm,
    data: *mut f64,
    len: usize,
    _vector: &'a mut GhostVector,
}

impl Deref for LocalMut<'_> {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        // SAFETY: as in `Local`.
        unsafe { std::slice::from_raw_parts(slice_parts(self.data, self.len), self.len) }
    }
}

impl DerefMut for LocalMut<'_> {
    fn deref_mut(&mut self) -> &mut [f64] {
        // SAFETY: as in `Local`; the vector is borrowed mutably.
        unsafe { std::slice::from_raw_parts_mut(slice_parts(self.data, self.len), self.len) }
    }
}

impl Drop for LocalMut<'_> {
    fn drop(&mut self) {
        // SAFETY: restores the array obtained in `GhostVector::local_mut`.
        discard(unsafe { ffi::VecRestoreArray(self.form.0, &mut self.data) });
    }
}
