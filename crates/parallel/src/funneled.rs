//! Values used only from the thread that drives a solve: MPI is initialised "funneled" (rayon
//! may run inside a rank; MPI and PETSc are called from the main thread), and PETSc's objects
//! are neither `Send` nor `Sync`. The framework's traits ask for `Send + Sync` (operators are
//! shared with rayon's workers, which never touch these values); this wrapper states the rule.

/// A value touched from the driving thread only (module docs).
pub(crate) struct Funneled<T>(pub(crate) T);

// SAFETY: the value is only ever used from the thread that drives the solve (the crate's code
// calls MPI and PETSc outside rayon's closures); it is never accessed concurrently.
unsafe impl<T> Send for Funneled<T> {}
// SAFETY: as above.
unsafe impl<T> Sync for Funneled<T> {}

/// A reference to the PETSc session, which the driver creates first and drops last.
#[derive(Clone, Copy)]
pub(crate) struct Session(pub(crate) *const saddle_mpi::Petsc);

// SAFETY: as for `Funneled`; the session outlives every object of this crate (module docs of
// `crate::distribute`).
unsafe impl Send for Session {}
// SAFETY: as above.
unsafe impl Sync for Session {}

impl Session {
    /// The session.
    pub(crate) fn get(&self) -> &saddle_mpi::Petsc {
        // SAFETY: the session outlives every object holding this reference (see above).
        unsafe { &*self.0 }
    }
}
