//! Linear solves through PETSc's KSP: conjugate gradients preconditioned by GAMG by default,
//! hypre's BoomerAMG or MUMPS (a direct LU) by choice; PETSc's options (command line, scene,
//! with the solver's prefix) override the defaults set here, as `KSPSetFromOptions` does.

use crate::error::{Error, Result, check, discard};
use crate::ffi;
use crate::matrix::Matrix;
use crate::session::{Petsc, finalized, petsc_comm_world};
use crate::vector::GhostVector;
use std::ffi::{CStr, CString};
use std::ptr;

/// The solver and preconditioner.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// Conjugate gradients, PETSc's smoothed-aggregation multigrid (uses the near-null space).
    #[default]
    CgGamg,
    /// Conjugate gradients, hypre's BoomerAMG (ignores the near-null space unless its nodal
    /// options are set: `-pc_hypre_boomeramg_nodal_coarsen`, `-pc_hypre_boomeramg_vec_interp_variant`).
    CgBoomerAmg,
    /// MUMPS's distributed LU (`-pc_type lu -pc_factor_mat_solver_type mumps`), no iterations.
    Mumps,
}

/// The defaults of a solver, set before PETSc's options are read.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Solver and preconditioner.
    pub method: Method,
    /// Relative tolerance on the (preconditioned, for CG) residual norm.
    pub rtol: f64,
    /// Absolute tolerance on it.
    pub atol: f64,
    /// Maximum number of iterations.
    pub max_iterations: usize,
    /// The options prefix (`"elastic_"` reads `-elastic_ksp_type`); empty for none.
    pub prefix: String,
}

impl Default for Settings {
    fn default() -> Self {
        Self { method: Method::CgGamg, rtol: 1e-8, atol: 1e-50, max_iterations: 10_000, prefix: String::new() }
    }
}

/// What a converged solve reports.
#[derive(Clone, Debug, PartialEq)]
pub struct SolveReport {
    /// Krylov iterations (1 for MUMPS's `preonly`).
    pub iterations: usize,
    /// The final residual norm PETSc's test used.
    pub residual_norm: f64,
    /// PETSc's name of the converged reason (`CONVERGED_RTOL`, `CONVERGED_ITS` for `preonly`).
    pub reason: String,
}

/// A Krylov solver with its preconditioner.
pub struct Ksp {
    raw: ffi::KSP,
    prefix: String,
}

impl Ksp {
    /// A solver with `settings`, then PETSc's options (with the prefix) applied. Collective.
    pub fn new(session: &Petsc, settings: &Settings) -> Result<Self> {
        let mut raw = ptr::null_mut();
        // SAFETY: creates a KSP on PETSc's world communicator.
        check("KSPCreate", unsafe { ffi::KSPCreate(petsc_comm_world(session), &mut raw) })?;
        let this = Self { raw, prefix: settings.prefix.clone() };
        if !settings.prefix.is_empty() {
            let prefix = CString::new(settings.prefix.as_str())
                .map_err(|_| Error::Nul { what: "the options prefix", value: settings.prefix.clone() })?;
            // SAFETY: NUL-terminated; PETSc copies it.
            check("KSPSetOptionsPrefix", unsafe { ffi::KSPSetOptionsPrefix(raw, prefix.as_ptr()) })?;
        }
        let (ksp_type, pc_type) = match settings.method {
            Method::CgGamg => (c"cg", c"gamg"),
            Method::CgBoomerAmg => (c"cg", c"hypre"),
            Method::Mumps => (c"preonly", c"lu"),
        };
        // SAFETY: `raw` is live; type names are NUL-terminated literals.
        check("KSPSetType", unsafe { ffi::KSPSetType(raw, ksp_type.as_ptr()) })?;
        let mut pc = ptr::null_mut();
        // SAFETY: the KSP owns its PC.
        check("KSPGetPC", unsafe { ffi::KSPGetPC(raw, &mut pc) })?;
        // SAFETY: as above.
        check("PCSetType", unsafe { ffi::PCSetType(pc, pc_type.as_ptr()) })?;
        if settings.method == Method::Mumps {
            // SAFETY: as above; the PC is a factorisation.
            check("PCFactorSetMatSolverType", unsafe { ffi::PCFactorSetMatSolverType(pc, c"mumps".as_ptr()) })?;
        }
        let max_it = ffi::PetscInt::try_from(settings.max_iterations).unwrap_or(ffi::PetscInt::MAX);
        // SAFETY: `raw` is live; dtol left at PETSc's default (PETSC_DEFAULT = -2).
        check("KSPSetTolerances", unsafe { ffi::KSPSetTolerances(raw, settings.rtol, settings.atol, -2.0, max_it) })?;
        // SAFETY: as above.
        check("KSPSetFromOptions", unsafe { ffi::KSPSetFromOptions(raw) })?;
        Ok(this)
    }

    /// Sets the operator (and the matrix the preconditioner is built from). Call again after its
    /// values change (same pattern): the next solve rebuilds the preconditioner, unless
    /// [`Ksp::reuse_preconditioner`] keeps the old one.
    pub fn set_operator(&mut self, a: &Matrix) -> Result<()> {
        // SAFETY: both live; the KSP takes its own references to the matrix.
        check("KSPSetOperators", unsafe { ffi::KSPSetOperators(self.raw, a.raw, a.raw) })
    }

    /// Keeps the current preconditioner when the operator's values change (`true`), or rebuilds
    /// it at the next solve (`false`, the default). A kept preconditioner costs iterations, saves
    /// its set-up (GAMG's aggregation, MUMPS's factorisation).
    pub fn reuse_preconditioner(&mut self, keep: bool) -> Result<()> {
        let flag = if keep { ffi::PetscBool::PETSC_TRUE } else { ffi::PetscBool::PETSC_FALSE };
        // SAFETY: `self.raw` is live.
        check("KSPSetReusePreconditioner", unsafe { ffi::KSPSetReusePreconditioner(self.raw, flag) })
    }

    /// Sets the relative tolerance of the next solves (the absolute one and the iteration budget
    /// kept).
    pub fn set_relative_tolerance(&mut self, rtol: f64) -> Result<()> {
        // SAFETY: `self.raw` is live; PETSC_DEFAULT (−2) keeps the other tolerances.
        check("KSPSetTolerances", unsafe { ffi::KSPSetTolerances(self.raw, rtol, -2.0, -2.0, -2) })
    }

    /// GAMG's smoothers estimate their own largest eigenvalue (`false`) instead of reusing the
    /// estimate made for smoothing the prolongator (`true`, PETSc's default;
    /// `-pc_gamg_use_sa_esteig`). No effect with another preconditioner.
    pub fn gamg_reuse_prolongator_estimate(&mut self, reuse: bool) -> Result<()> {
        let flag = if reuse { ffi::PetscBool::PETSC_TRUE } else { ffi::PetscBool::PETSC_FALSE };
        let mut pc = ptr::null_mut();
        // SAFETY: the KSP owns its PC.
        check("KSPGetPC", unsafe { ffi::KSPGetPC(self.raw, &mut pc) })?;
        // SAFETY: `pc` is live; PETSc ignores the call for a PC that is not GAMG.
        check("PCGAMGSetUseSAEstEig", unsafe { ffi::PCGAMGSetUseSAEstEig(pc, flag) })
    }

    /// Starts from the values in `x` (`true`) instead of zero (`false`, the default).
    pub fn initial_guess_nonzero(&mut self, nonzero: bool) -> Result<()> {
        // a direct solve (`preonly`, as MUMPS runs) takes no guess: PETSc refuses one
        let nonzero = nonzero && self.method_name()? != "preonly";
        let flag = if nonzero { ffi::PetscBool::PETSC_TRUE } else { ffi::PetscBool::PETSC_FALSE };
        // SAFETY: `self.raw` is live.
        check("KSPSetInitialGuessNonzero", unsafe { ffi::KSPSetInitialGuessNonzero(self.raw, flag) })
    }

    /// PETSc's name of the Krylov method (`cg`, `preonly`, …), the options applied.
    pub fn method_name(&self) -> Result<String> {
        let mut name = ptr::null();
        // SAFETY: `self.raw` is live; PETSc returns a pointer to its own string.
        check("KSPGetType", unsafe { ffi::KSPGetType(self.raw, &mut name) })?;
        // SAFETY: a NUL-terminated string owned by the KSP, copied at once.
        Ok(if name.is_null() { String::new() } else { unsafe { CStr::from_ptr(name) }.to_string_lossy().into_owned() })
    }

    /// Solves A x = b. A diverged solve (iteration limit, breakdown, indefinite preconditioner)
    /// is [`Error::Diverged`] with PETSc's reason. Collective.
    pub fn solve(&mut self, b: &GhostVector, x: &mut GhostVector) -> Result<SolveReport> {
        // SAFETY: all live; layouts are the operator's (PETSc checks them).
        check("KSPSolve", unsafe { ffi::KSPSolve(self.raw, b.raw, x.raw) })?;
        let (mut its, mut rnorm, mut reason) = (0, 0.0, ffi::KSPConvergedReason(0));
        // SAFETY: `self.raw` is live.
        check("KSPGetIterationNumber", unsafe { ffi::KSPGetIterationNumber(self.raw, &mut its) })?;
        // SAFETY: as above.
        check("KSPGetResidualNorm", unsafe { ffi::KSPGetResidualNorm(self.raw, &mut rnorm) })?;
        // SAFETY: as above.
        check("KSPGetConvergedReason", unsafe { ffi::KSPGetConvergedReason(self.raw, &mut reason) })?;
        let mut name = ptr::null();
        // SAFETY: as above; PETSc returns a pointer to a static string.
        check("KSPGetConvergedReasonString", unsafe { ffi::KSPGetConvergedReasonString(self.raw, &mut name) })?;
        let reason_name = if name.is_null() {
            format!("reason {}", reason.0)
        } else {
            // SAFETY: a NUL-terminated static string.
            unsafe { CStr::from_ptr(name) }.to_string_lossy().into_owned()
        };
        let iterations = its.max(0) as usize;
        if reason.0 < 0 {
            let prefix = if self.prefix.is_empty() { "default".to_string() } else { self.prefix.clone() };
            return Err(Error::Diverged { reason: reason_name, iterations, residual: rnorm, prefix });
        }
        Ok(SolveReport { iterations, residual_norm: rnorm, reason: reason_name })
    }
}

impl Drop for Ksp {
    fn drop(&mut self) {
        if !finalized() {
            // SAFETY: `self.raw` is owned by `self`.
            discard(unsafe { ffi::KSPDestroy(&mut self.raw) });
        }
    }
}
