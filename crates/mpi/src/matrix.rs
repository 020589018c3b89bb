//! Distributed sparse matrices (PETSc AIJ: MPIAIJ on several ranks, SeqAIJ on one): rows
//! distributed in contiguous ranges like [`GhostVector`]'s entries, preallocated per owned row,
//! assembled by adding element blocks at global indices (entries of rows another rank owns are
//! sent to it at assembly), constrained rows and columns replaced by a diagonal.

use crate::Index;
use crate::error::{Result, check, check_len, discard, petsc_int};
use crate::ffi;
use crate::session::{Petsc, finalized, petsc_comm_world};
use crate::vector::{DECIDE, GhostVector};
use std::ops::Range;
use std::ptr;

/// A distributed square sparse matrix.
pub struct Matrix {
    pub(crate) raw: ffi::Mat,
    owned: Range<usize>,
    global: usize,
}

impl Matrix {
    /// A square matrix with `owned_rows` rows on this rank (and as many columns of the diagonal
    /// block), block size `block_size` (3 for displacements in 3D: GAMG aggregates nodes), and
    /// per owned row the number of nonzeros in the columns this rank owns (`diagonal_nnz`) and in
    /// the others (`off_diagonal_nnz`). Adding outside this preallocation is an error. Collective.
    pub fn new(
        session: &Petsc,
        owned_rows: usize,
        block_size: usize,
        diagonal_nnz: &[Index],
        off_diagonal_nnz: &[Index],
    ) -> Result<Self> {
        check_len("diagonal_nnz", diagonal_nnz.len(), owned_rows)?;
        check_len("off_diagonal_nnz", off_diagonal_nnz.len(), owned_rows)?;
        let n = petsc_int("owned rows", owned_rows)?;
        let bs = petsc_int("block size", block_size)?;
        let mut raw = ptr::null_mut();
        // SAFETY: creates a matrix on PETSc's world communicator.
        check("MatCreate", unsafe { ffi::MatCreate(petsc_comm_world(session), &mut raw) })?;
        let mut this = Self { raw, owned: 0..0, global: 0 };
        // SAFETY: `raw` is live; the type name is a NUL-terminated literal.
        check("MatSetSizes", unsafe { ffi::MatSetSizes(raw, n, n, DECIDE, DECIDE) })?;
        // SAFETY: as above.
        check("MatSetType", unsafe { ffi::MatSetType(raw, c"aij".as_ptr()) })?;
        // SAFETY: as above.
        check("MatSetBlockSize", unsafe { ffi::MatSetBlockSize(raw, bs) })?;
        // SAFETY: per-row counts of `owned_rows` entries; only the call matching the type acts.
        check("MatSeqAIJSetPreallocation", unsafe { ffi::MatSeqAIJSetPreallocation(raw, 0, diagonal_nnz.as_ptr()) })?;
        // SAFETY: as above.
        check("MatMPIAIJSetPreallocation", unsafe {
            ffi::MatMPIAIJSetPreallocation(raw, 0, diagonal_nnz.as_ptr(), 0, off_diagonal_nnz.as_ptr())
        })?;
        let (mut lo, mut hi, mut rows, mut cols): (ffi::PetscInt, ffi::PetscInt, ffi::PetscInt, ffi::PetscInt) =
            (0, 0, 0, 0);
        // SAFETY: the matrix is preallocated.
        check("MatGetOwnershipRange", unsafe { ffi::MatGetOwnershipRange(raw, &mut lo, &mut hi) })?;
        // SAFETY: as above.
        check("MatGetSize", unsafe { ffi::MatGetSize(raw, &mut rows, &mut cols) })?;
        this.owned = lo as usize..hi as usize;
        this.global = rows as usize;
        Ok(this)
    }

    /// The global rows this rank owns.
    pub fn owned_rows(&self) -> Range<usize> {
        self.owned.clone()
    }

    /// The global order.
    pub fn global_len(&self) -> usize {
        self.global
    }

    /// Tells PETSc the matrix is symmetric, for good (GAMG then skips symmetrising its graph).
    pub fn set_symmetric(&mut self) -> Result<()> {
        for option in [ffi::MatOption::MAT_SYMMETRIC, ffi::MatOption::MAT_SYMMETRY_ETERNAL] {
            // SAFETY: `self.raw` is live.
            check("MatSetOption", unsafe { ffi::MatSetOption(self.raw, option, ffi::PetscBool::PETSC_TRUE) })?;
        }
        Ok(())
    }

    /// Lets additions fall outside the preallocation (PETSc allocates the entries then, at the
    /// cost of a copy in the first assembly; later assemblies on the same pattern are at full
    /// speed): for rows whose couplings other ranks add and this one cannot count.
    pub fn allow_new_nonzeros(&mut self) -> Result<()> {
        // SAFETY: `self.raw` is live.
        check("MatSetOption", unsafe {
            ffi::MatSetOption(self.raw, ffi::MatOption::MAT_NEW_NONZERO_ALLOCATION_ERR, ffi::PetscBool::PETSC_FALSE)
        })
    }

    /// Adds the dense block `values` (row-major, `rows.len()` × `cols.len()`) at the global
    /// indices `rows` × `cols` (any rows: entries of other ranks' rows are sent at assembly;
    /// negative indices are skipped). Not collective.
    pub fn add_values(&mut self, rows: &[Index], cols: &[Index], values: &[f64]) -> Result<()> {
        check_len("add_values: values", values.len(), rows.len() * cols.len())?;
        // SAFETY: `rows`, `cols` and `values` have the lengths passed.
        check("MatSetValues", unsafe {
            ffi::MatSetValues(
                self.raw,
                rows.len() as ffi::PetscInt,
                rows.as_ptr(),
                cols.len() as ffi::PetscInt,
                cols.as_ptr(),
                values.as_ptr(),
                ffi::InsertMode::ADD_VALUES,
            )
        })
    }

    /// Final assembly: sends the entries added to other ranks' rows. Collective.
    pub fn assemble(&mut self) -> Result<()> {
        // SAFETY: `self.raw` is live.
        check("MatAssemblyBegin", unsafe {
            ffi::MatAssemblyBegin(self.raw, ffi::MatAssemblyType::MAT_FINAL_ASSEMBLY)
        })?;
        // SAFETY: as above, after the matching begin.
        check("MatAssemblyEnd", unsafe { ffi::MatAssemblyEnd(self.raw, ffi::MatAssemblyType::MAT_FINAL_ASSEMBLY) })
    }

    /// Sets every stored entry to zero, keeping the pattern (before adding new values).
    pub fn zero_entries(&mut self) -> Result<()> {
        // SAFETY: `self.raw` is live.
        check("MatZeroEntries", unsafe { ffi::MatZeroEntries(self.raw) })
    }

    /// Zeroes the rows and columns `rows` (global indices; each rank passes the ones it knows,
    /// usually its owned constrained rows) and puts `diagonal` on their diagonal: constrained
    /// (Dirichlet, active) rows. The matrix stays symmetric; the pattern is kept. Collective.
    pub fn zero_rows_columns(&mut self, rows: &[Index], diagonal: f64) -> Result<()> {
        // SAFETY: `rows` has the length passed; no vectors to adjust.
        check("MatZeroRowsColumns", unsafe {
            ffi::MatZeroRowsColumns(
                self.raw,
                rows.len() as ffi::PetscInt,
                rows.as_ptr(),
                diagonal,
                ptr::null_mut(),
                ptr::null_mut(),
            )
        })
    }

    /// [`Matrix::zero_rows_columns`], adjusting the right-hand side for prescribed values `x` on
    /// those rows: `b_i = diagonal·x_i` on the rows, `b -= A[:, rows] x[rows]` elsewhere.
    /// Collective.
    pub fn zero_rows_columns_lifting(
        &mut self,
        rows: &[Index],
        diagonal: f64,
        x: &GhostVector,
        b: &mut GhostVector,
    ) -> Result<()> {
        // SAFETY: `rows` has the length passed; `x` and `b` are live vectors of the matrix's layout.
        check("MatZeroRowsColumns", unsafe {
            ffi::MatZeroRowsColumns(self.raw, rows.len() as ffi::PetscInt, rows.as_ptr(), diagonal, x.raw, b.raw)
        })
    }

    /// `y = A x`. Collective.
    pub fn mult(&self, x: &GhostVector, y: &mut GhostVector) -> Result<()> {
        check_len("mult: owned entries of x", x.owned_len(), self.owned.len())?;
        check_len("mult: owned entries of y", y.owned_len(), self.owned.len())?;
        // SAFETY: all live, layouts checked.
        check("MatMult", unsafe { ffi::MatMult(self.raw, x.raw, y.raw) })
    }
}

impl Drop for Matrix {
    fn drop(&mut self) {
        if !finalized() {
            // SAFETY: `self.raw` is owned by `self` (a KSP using it holds its own reference).
            discard(unsafe { ffi::MatDestroy(&mut self.raw) });
        }
    }
}
