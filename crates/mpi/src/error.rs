//! Errors of the distributed layer: PETSc's error codes with PETSc's own message, a diverged
//! Krylov solve, an error agreed on by every rank, and misuse caught before calling PETSc.
//!
//! PETSc reports an error by calling its error handler, then returning a nonzero code up the
//! call stack. [`install_handler`] replaces PETSc's default handler (which prints a traceback, and
//! for some errors aborts) by one that only records the first message and the functions it passed
//! through; [`check`] turns a nonzero code into a [`PetscError`] carrying that record.

use crate::ffi;
use std::ffi::{CStr, c_char, c_int, c_void};
use std::sync::Mutex;
use thiserror::Error;

/// The errors of saddle-mpi.
#[derive(Debug, Error)]
pub enum Error {
    /// A PETSc call returned an error code.
    #[error(transparent)]
    Petsc(#[from] PetscError),
    /// The Krylov solve stopped without converging.
    #[error(
        "the linear solve ({prefix}) diverged: {reason} after {iterations} iterations, residual norm {residual:.3e}"
    )]
    Diverged {
        /// PETSc's name of the reason (`DIVERGED_ITS`, `DIVERGED_INDEFINITE_PC`, …).
        reason: String,
        /// Iterations done.
        iterations: usize,
        /// The last residual norm.
        residual: f64,
        /// The solver's options prefix (`default` for none).
        prefix: String,
    },
    /// An error on one or more ranks, agreed on by every rank ([`crate::agree`]).
    #[error("rank {rank} failed ({failed} of {size} ranks failed): {message}")]
    Rank {
        /// The lowest failing rank, whose message this is.
        rank: usize,
        /// The number of failing ranks.
        failed: usize,
        /// The number of ranks.
        size: usize,
        /// The failing rank's error message.
        message: String,
    },
    /// MPI was already initialised in this process (saddle-mpi initialises it, once).
    #[error("MPI is already initialised in this process: initialise it once, through Petsc::initialize")]
    AlreadyInitialized,
    /// A count or index does not fit PETSc's `PetscInt`.
    #[error("{what} = {value} does not fit PETSc's {bits}-bit PetscInt")]
    IndexOverflow {
        /// What the number is.
        what: &'static str,
        /// The number.
        value: usize,
        /// The width of `PetscInt` in this build.
        bits: u32,
    },
    /// An array of the wrong length.
    #[error("{what}: length {got}, expected {expected}")]
    Length {
        /// The array.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The length expected.
        expected: usize,
    },
    /// A string handed to PETSc contains a NUL byte.
    #[error("{what} contains a NUL byte: {value:?}")]
    Nul {
        /// The string's role.
        what: &'static str,
        /// The string.
        value: String,
    },
}

/// Results of saddle-mpi.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A PETSc error: the code, the call that returned it, and PETSc's message.
#[derive(Clone, Debug, Error, PartialEq)]
#[error("PETSc error {code} in {call}: {message} [raised in {origin}]")]
pub struct PetscError {
    /// PETSc's error code (`PETSC_ERR_*`).
    pub code: i32,
    /// The PETSc function saddle called (`KSPSetFromOptions`).
    pub call: &'static str,
    /// PETSc's message for the error (the specific one when PETSc gave one).
    pub message: String,
    /// Where PETSc raised it: `function() at file:line`.
    pub origin: String,
    /// The PETSc functions the error passed through, innermost first.
    pub traceback: Vec<String>,
}

/// What the handler has seen since the last [`check`]: the first message and the functions the
/// error passed through. PETSc is called from one thread only (MPI "funneled").
#[derive(Default)]
struct Record {
    message: String,
    origin: String,
    traceback: Vec<String>,
}

static RECORD: Mutex<Option<Record>> = Mutex::new(None);

fn text(p: *const c_char) -> String {
    if p.is_null() {
        return String::new();
    }
    // SAFETY: PETSc passes NUL-terminated strings (function, file, message) or null.
    unsafe { CStr::from_ptr(p) }.to_string_lossy().trim().to_string()
}

/// PETSc's error handler, replaced: records the error and returns its code (no printing, no
/// abort). Called by PETSc with `PETSC_ERROR_INITIAL` where the error is raised, then with
/// `PETSC_ERROR_REPEAT` in each function it returns through.
unsafe extern "C" fn record(
    _comm: ffi::MPI_Comm,
    line: c_int,
    function: *const c_char,
    file: *const c_char,
    code: ffi::PetscErrorCode,
    kind: ffi::PetscErrorType,
    message: *const c_char,
    _ctx: *mut c_void,
) -> ffi::PetscErrorCode {
    let mut guard = RECORD.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    let function = text(function);
    if kind == ffi::PetscErrorType::PETSC_ERROR_INITIAL || guard.is_none() {
        *guard = Some(Record {
            message: text(message),
            origin: format!("{function}() at {}:{line}", text(file)),
            traceback: vec![function],
        });
    } else if let Some(record) = guard.as_mut() {
        record.traceback.push(function);
    }
    code
}

/// Installs the recording handler ([`record`]) on top of PETSc's handler stack.
pub(crate) fn install_handler() -> Result<()> {
    // SAFETY: `record` has the handler's signature and no context.
    check("PetscPushErrorHandler", unsafe { ffi::PetscPushErrorHandler(Some(record), std::ptr::null_mut()) })
}

/// PETSc's generic text for an error code (`"Unknown type. Check for miss-spelling …"`).
fn generic_message(code: i32) -> String {
    let mut generic: *const c_char = std::ptr::null();
    // SAFETY: PetscErrorMessage writes a pointer to a static string; `specific` may be null.
    let status = unsafe { ffi::PetscErrorMessage(code, &mut generic, std::ptr::null_mut()) };
    if status != 0 || generic.is_null() { format!("error code {code}") } else { text(generic) }
}

/// Turns the return code of the PETSc function `call` into a result; a nonzero code becomes a
/// [`PetscError`] with the message the handler recorded.
pub(crate) fn check(call: &'static str, code: ffi::PetscErrorCode) -> Result<()> {
    if code == 0 {
        return Ok(());
    }
    let record = RECORD.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).take().unwrap_or_default();
    let generic = generic_message(code);
    let message = if record.message.is_empty() { generic } else { format!("{generic}: {}", record.message) };
    Err(PetscError {
        code,
        call,
        message,
        origin: if record.origin.is_empty() { call.to_string() } else { record.origin },
        traceback: record.traceback,
    }
    .into())
}

/// For calls whose failure cannot be reported (in `Drop`): forgets what the handler recorded, so
/// that it is not attributed to a later error.
pub(crate) fn discard(code: ffi::PetscErrorCode) {
    if code != 0 {
        RECORD.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).take();
    }
}

/// A Rust count or index as a `PetscInt`.
pub(crate) fn petsc_int(what: &'static str, value: usize) -> Result<ffi::PetscInt> {
    ffi::PetscInt::try_from(value).map_err(|_| Error::IndexOverflow { what, value, bits: ffi::PetscInt::BITS })
}

/// Checks that an array has the expected length.
pub(crate) fn check_len(what: &'static str, got: usize, expected: usize) -> Result<()> {
    if got == expected { Ok(()) } else { Err(Error::Length { what, got, expected }) }
}
