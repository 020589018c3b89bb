//! The MPI and PETSc session: MPI initialised by rsmpi (threading level "funneled": rayon may
//! run inside a rank, MPI and PETSc are called from the main thread only), then PETSc with the
//! program's arguments, so that `-ksp_view`, `-log_view`, `-ksp_monitor` … work as PETSc users
//! expect; finalised in the reverse order when dropped.

use crate::error::{Error, Result, check, discard, install_handler};
use crate::ffi;
use mpi::Threading;
use mpi::environment::Universe;
use mpi::topology::{Communicator, SimpleCommunicator};
use std::ffi::{CStr, CString, c_char, c_int};
use std::ptr;

/// The session guard: while it lives, MPI and PETSc are initialised. Create it once per process,
/// first thing in `main`; PETSc objects ([`crate::GhostVector`], [`crate::Matrix`],
/// [`crate::Ksp`]) are created from it. Dropping it finalises PETSc (printing `-log_view`), then
/// MPI; PETSc objects still alive then are left to the process's exit. Every rank must drop it
/// (finalising is collective): share an error with [`crate::agree`] before returning it from one
/// rank; a panic unwinding through it aborts every rank.
pub struct Petsc {
    world: SimpleCommunicator,
    threading: Threading,
    /// The arguments handed to `PetscInitialize`; PETSc keeps pointers into them.
    _args: Vec<CString>,
    _argv: Vec<*mut c_char>,
    /// Dropped last: `MPI_Finalize`.
    _universe: Universe,
}

impl Petsc {
    /// Initialises MPI and PETSc with the program's own arguments (`std::env::args`).
    pub fn initialize() -> Result<Self> {
        Self::initialize_with_args(std::env::args())
    }

    /// Initialises MPI (rsmpi, threading funneled) and PETSc with `args` (the program name first):
    /// PETSc reads its options (`-ksp_type`, `-log_view`, …) from them and ignores the rest.
    /// Fails with [`Error::AlreadyInitialized`] when MPI was initialised before.
    pub fn initialize_with_args<I, S>(args: I) -> Result<Self>
    where
        I: IntoIterator<Item = S>,
        S: Into<String>,
    {
        let args = args
            .into_iter()
            .map(|a| {
                let a: String = a.into();
                CString::new(a.clone()).map_err(|_| Error::Nul { what: "a program argument", value: a })
            })
            .collect::<Result<Vec<_>>>()?;
        let (universe, threading) =
            mpi::initialize_with_threading(Threading::Funneled).ok_or(Error::AlreadyInitialized)?;
        let mut argv: Vec<*mut c_char> = args.iter().map(|a| a.as_ptr().cast_mut()).chain([ptr::null_mut()]).collect();
        let mut argc = c_int::try_from(args.len()).unwrap_or(c_int::MAX);
        let mut argv_ptr = argv.as_mut_ptr();
        // SAFETY: argc/argv describe NUL-terminated strings kept alive in `Self`; MPI is initialised,
        // so PETSc will neither initialise nor finalise it.
        check("PetscInitialize", unsafe { ffi::PetscInitialize(&mut argc, &mut argv_ptr, ptr::null(), ptr::null()) })?;
        let session = Self { world: universe.world(), threading, _args: args, _argv: argv, _universe: universe };
        install_handler()?;
        Ok(session)
    }

    /// This process's rank in the world communicator.
    pub fn rank(&self) -> usize {
        self.world.rank() as usize
    }

    /// The number of ranks.
    pub fn size(&self) -> usize {
        self.world.size() as usize
    }

    /// The world communicator (rsmpi), the one PETSc's objects live on (`PETSC_COMM_WORLD`).
    pub fn world(&self) -> &SimpleCommunicator {
        &self.world
    }

    /// The threading level MPI provides (at least funneled on common MPIs).
    pub fn threading(&self) -> Threading {
        self.threading
    }

    /// Ends every rank at once (`MPI_Abort`) with `code`: for an error one rank cannot share
    /// through a collective (a panic).
    pub fn abort(&self, code: i32) -> ! {
        self.world.abort(code)
    }

    /// Adds PETSc options from a string (a scene's `[solver.petsc] options = "-pc_gamg_threshold
    /// 0.02 …"`), parsed as PETSc parses the command line. An option the command line (or
    /// `PETSC_OPTIONS`) already set keeps its value there: the command line has the last word, as
    /// it has over PETSc's options files. Call it on every rank with the same string, before
    /// creating the objects that read the options.
    pub fn insert_options(&self, options: &str) -> Result<()> {
        let text =
            CString::new(options).map_err(|_| Error::Nul { what: "the PETSc options", value: options.into() })?;
        let scratch = Scratch::new()?;
        // SAFETY: `scratch.0` is a live options database; `text` is NUL-terminated.
        check("PetscOptionsInsertString", unsafe { ffi::PetscOptionsInsertString(scratch.0, text.as_ptr()) })?;
        let mut n: ffi::PetscInt = 0;
        let mut names: *mut *mut c_char = ptr::null_mut();
        let mut values: *mut *mut c_char = ptr::null_mut();
        // SAFETY: fills arrays of n names and values owned by `scratch` until restored.
        check("PetscOptionsLeftGet", unsafe { ffi::PetscOptionsLeftGet(scratch.0, &mut n, &mut names, &mut values) })?;
        let result = (0..n.max(0) as usize).try_for_each(|i| {
            // SAFETY: i < n; names are NUL-terminated (stored without the leading '-'), values may be null.
            let (name, value) = unsafe { (CStr::from_ptr(*names.add(i)), *values.add(i)) };
            let key = CString::new([b"-", name.to_bytes()].concat()).expect("from a C string");
            let mut set = ffi::PetscBool::PETSC_FALSE;
            // SAFETY: the global database (null), a NUL-terminated key.
            check("PetscOptionsHasName", unsafe {
                ffi::PetscOptionsHasName(ptr::null_mut(), ptr::null(), key.as_ptr(), &mut set)
            })?;
            if set == ffi::PetscBool::PETSC_FALSE {
                // SAFETY: as above; a null value sets a flag without value.
                check("PetscOptionsSetValue", unsafe {
                    ffi::PetscOptionsSetValue(ptr::null_mut(), key.as_ptr(), value)
                })?;
            }
            Ok(())
        });
        // SAFETY: restores what PetscOptionsLeftGet allocated.
        discard(unsafe { ffi::PetscOptionsLeftRestore(scratch.0, &mut n, &mut names, &mut values) });
        result
    }
}

impl Drop for Petsc {
    /// Finalises PETSc then MPI. Unwinding from a panic, it aborts every rank instead: finalising
    /// is collective, and the other ranks would wait for this one in their next collective.
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.world.abort(101);
        }
        // SAFETY: PETSc was initialised by `initialize_with_args`; MPI is finalised after (field drop).
        discard(unsafe { ffi::PetscFinalize() });
    }
}

/// A private options database, destroyed on drop.
struct Scratch(ffi::PetscOptions);

impl Scratch {
    fn new() -> Result<Self> {
        let mut options = ptr::null_mut();
        // SAFETY: creates an empty database.
        check("PetscOptionsCreate", unsafe { ffi::PetscOptionsCreate(&mut options) })?;
        Ok(Self(options))
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        // SAFETY: the database was created by `Scratch::new`.
        discard(unsafe { ffi::PetscOptionsDestroy(&mut self.0) });
    }
}

/// PETSc's world communicator, for creating objects: `_session` proves PETSc is initialised.
pub(crate) fn petsc_comm_world(_session: &Petsc) -> ffi::MPI_Comm {
    // SAFETY: set by PetscInitialize and never written afterwards.
    unsafe { ffi::PETSC_COMM_WORLD }
}

/// Whether PETSc has been finalised: objects dropped afterwards are not destroyed (PETSc's memory
/// is gone with it).
pub(crate) fn finalized() -> bool {
    // SAFETY: a flag PETSc writes only in PetscInitialize/PetscFinalize, on this thread.
    unsafe { ffi::PetscFinalizeCalled == ffi::PetscBool::PETSC_TRUE }
}
