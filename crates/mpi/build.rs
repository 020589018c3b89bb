//! Build script: with the `petsc` feature, finds PETSc (`PETSC_DIR`/`PETSC_ARCH`, else pkg-config
//! `PETSc`), checks its configuration (version ≥ 3.18, real double scalars, the width of
//! `PetscInt`) and generates the bindings of exactly the functions the crate wraps. Without the
//! feature it does nothing.

fn main() {
    #[cfg(feature = "petsc")]
    petsc::main();
}

#[cfg(feature = "petsc")]
mod petsc {
    use std::collections::BTreeMap;
    use std::env;
    use std::fs;
    use std::path::{Path, PathBuf};

    /// The oldest PETSc the bindings are written against (`KSPGetConvergedReasonString`,
    /// `PetscCall`-era error codes, `PCFactorSetMatSolverType`).
    const MIN_VERSION: (u32, u32) = (3, 18);

    /// The PETSc functions the crate calls: the allowlist handed to bindgen.
    const FUNCTIONS: &[&str] = &[
        // sys: init, errors, options
        "PetscInitialize",
        "PetscFinalize",
        "PetscPushErrorHandler",
        "PetscPopErrorHandler",
        "PetscErrorMessage",
        "PetscOptionsCreate",
        "PetscOptionsDestroy",
        "PetscOptionsInsertString",
        "PetscOptionsLeftGet",
        "PetscOptionsLeftRestore",
        "PetscOptionsHasName",
        "PetscOptionsSetValue",
        // Vec
        "VecCreateGhost",
        "VecCreateMPIWithArray",
        "VecDuplicate",
        "VecDestroy",
        "VecGetLocalSize",
        "VecGetSize",
        "VecGetOwnershipRange",
        "VecGhostGetLocalForm",
        "VecGhostRestoreLocalForm",
        "VecGhostUpdateBegin",
        "VecGhostUpdateEnd",
        "VecGetArray",
        "VecRestoreArray",
        "VecGetArrayRead",
        "VecRestoreArrayRead",
        "VecSet",
        "VecCopy",
        "VecAXPY",
        "VecDot",
        "VecNorm",
        // Mat
        "MatCreate",
        "MatDestroy",
        "MatSetSizes",
        "MatSetType",
        "MatSetBlockSize",
        "MatSetOption",
        "MatSeqAIJSetPreallocation",
        "MatMPIAIJSetPreallocation",
        "MatSetValues",
        "MatAssemblyBegin",
        "MatAssemblyEnd",
        "MatZeroEntries",
        "MatZeroRowsColumns",
        "MatGetOwnershipRange",
        "MatGetSize",
        "MatMult",
        "MatNullSpaceCreateRigidBody",
        "MatNullSpaceCreate",
        "MatNullSpaceDestroy",
        "MatSetNearNullSpace",
        // KSP and PC
        "KSPCreate",
        "KSPDestroy",
        "KSPSetOperators",
        "KSPSetType",
        "KSPGetType",
        "KSPGetPC",
        "KSPSetOptionsPrefix",
        "KSPSetFromOptions",
        "KSPSetTolerances",
        "KSPSetReusePreconditioner",
        "KSPSetInitialGuessNonzero",
        "PCGAMGSetUseSAEstEig",
        "KSPSolve",
        "KSPGetIterationNumber",
        "KSPGetResidualNorm",
        "KSPGetConvergedReason",
        "KSPGetConvergedReasonString",
        "PCSetType",
        "PCFactorSetMatSolverType",
    ];

    /// Global variables read by the crate.
    const VARIABLES: &[&str] = &["PETSC_COMM_WORLD", "PetscFinalizeCalled"];

    /// Where PETSc was found.
    struct Install {
        /// Directories holding the headers (`petscksp.h`, `petscconf.h`).
        include_dirs: Vec<PathBuf>,
        /// How it was found, for error messages.
        origin: String,
    }

    pub fn main() {
        println!("cargo:rerun-if-changed=wrapper.h");
        println!("cargo:rustc-check-cfg=cfg(petsc_int64)");
        let install = locate();
        let conf = read_defines(&find_header(&install, "petscconf.h"));
        let version = read_defines(&find_header(&install, "petscversion.h"));
        check_version(&version, &install);
        check_scalar(&conf, &install);
        let int64 = conf.contains_key("PETSC_USE_64BIT_INDICES");
        if int64 {
            println!("cargo:rustc-cfg=petsc_int64");
        }
        let mpi = build_probe_mpi::probe().unwrap_or_else(|errors| {
            let reasons: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
            panic!("saddle-mpi: no MPI found (rsmpi's probe: mpicc, pkg-config): {}", reasons.join("; "))
        });
        check_mpi_flavour(&install, &mpi.include_paths);
        generate(&install, &mpi.include_paths);
    }

    /// `PETSC_DIR`/`PETSC_ARCH` (a cluster's or a source build) when set, else pkg-config `PETSc`
    /// (distribution packages, Spack, a prefix install); emits the link instructions.
    fn locate() -> Install {
        for var in ["PETSC_DIR", "PETSC_ARCH", "PKG_CONFIG_PATH"] {
            println!("cargo:rerun-if-env-changed={var}");
        }
        if let Some(dir) = env::var_os("PETSC_DIR").filter(|d| !d.is_empty()) {
            let dir = PathBuf::from(dir);
            let arch = env::var("PETSC_ARCH").unwrap_or_default();
            let arch_dir = if arch.is_empty() { dir.clone() } else { dir.join(&arch) };
            let origin = format!("PETSC_DIR={} PETSC_ARCH={arch}", dir.display());
            let variables = arch_dir.join("lib/petsc/conf/petscvariables");
            let vars = fs::read_to_string(&variables).unwrap_or_default();
            let var = |name: &str| {
                vars.lines()
                    .filter_map(|l| l.split_once('='))
                    .find(|(k, _)| k.trim() == name)
                    .map(|(_, v)| v.trim().to_string())
                    .unwrap_or_default()
            };
            let mut include_dirs = vec![dir.join("include"), arch_dir.join("include")];
            include_dirs.extend(flags(&var("PETSC_CC_INCLUDES"), "-I").map(PathBuf::from));
            include_dirs.dedup();
            let lib_dir = arch_dir.join("lib");
            println!("cargo:rustc-link-search=native={}", lib_dir.display());
            let libs: Vec<String> = flags(&var("PETSC_LIB_BASIC"), "-l").map(String::from).collect();
            let libs = if libs.is_empty() { vec!["petsc".to_string()] } else { libs };
            let shared = libs
                .iter()
                .any(|l| lib_dir.join(format!("lib{l}.so")).exists() || lib_dir.join(format!("lib{l}.dylib")).exists());
            for lib in &libs {
                println!("cargo:rustc-link-lib={lib}");
            }
            if !shared {
                // A static PETSc: its own dependencies (BLAS, hypre, MUMPS, …) must be linked too.
                let external = var("PETSC_EXTERNAL_LIB_BASIC");
                for path in flags(&external, "-L") {
                    println!("cargo:rustc-link-search=native={path}");
                }
                for lib in flags(&external, "-l") {
                    println!("cargo:rustc-link-lib={lib}");
                }
            }
            return Install { include_dirs, origin };
        }
        let found = ["PETSc", "petsc"]
            .iter()
            .find_map(|name| pkg_config::Config::new().probe(name).ok())
            .unwrap_or_else(|| {
                panic!(
                    "saddle-mpi: PETSc not found. Set PETSC_DIR (and PETSC_ARCH) to a PETSc build, or make \
                     `pkg-config PETSc` work (PKG_CONFIG_PATH=<prefix>/lib/pkgconfig); on Debian/Ubuntu: \
                     apt-get install libpetsc-real-dev libopenmpi-dev openmpi-bin libclang-dev pkg-config"
                )
            });
        Install { include_dirs: found.include_paths, origin: "pkg-config PETSc".into() }
    }

    /// The values of the flags `-X<value>` (or `-X <value>`) in a command line.
    fn flags<'a>(line: &'a str, flag: &'a str) -> impl Iterator<Item = &'a str> + 'a {
        let mut words = line.split_whitespace().peekable();
        std::iter::from_fn(move || {
            while let Some(w) = words.next() {
                if w == flag {
                    return words.next();
                }
                if let Some(v) = w.strip_prefix(flag) {
                    return Some(v);
                }
            }
            None
        })
    }

    fn find_header(install: &Install, name: &str) -> PathBuf {
        install.include_dirs.iter().map(|d| d.join(name)).find(|p| p.exists()).unwrap_or_else(|| {
            panic!(
                "saddle-mpi: {name} not found in the include directories of PETSc ({}): {:?}",
                install.origin, install.include_dirs
            )
        })
    }

    /// The `#define NAME VALUE` lines of a header.
    fn read_defines(path: &Path) -> BTreeMap<String, String> {
        println!("cargo:rerun-if-changed={}", path.display());
        let text =
            fs::read_to_string(path).unwrap_or_else(|e| panic!("saddle-mpi: cannot read {}: {e}", path.display()));
        text.lines()
            .filter_map(|l| l.trim().strip_prefix("#define "))
            .filter_map(|rest| {
                let mut parts = rest.trim().splitn(2, char::is_whitespace);
                let name = parts.next()?.to_string();
                (!name.contains('(')).then(|| (name, parts.next().unwrap_or("").trim().to_string()))
            })
            .collect()
    }

    fn check_version(version: &BTreeMap<String, String>, install: &Install) {
        let number = |k: &str| version.get(k).and_then(|v| v.parse::<u32>().ok()).unwrap_or(0);
        let found = (number("PETSC_VERSION_MAJOR"), number("PETSC_VERSION_MINOR"));
        if found < MIN_VERSION {
            panic!(
                "saddle-mpi: PETSc {}.{} found ({}); PETSc ≥ {}.{} is needed",
                found.0, found.1, install.origin, MIN_VERSION.0, MIN_VERSION.1
            );
        }
    }

    /// PETSc must use real double scalars (`PetscScalar` = `PetscReal` = f64).
    fn check_scalar(conf: &BTreeMap<String, String>, install: &Install) {
        if conf.contains_key("PETSC_USE_COMPLEX") {
            panic!(
                "saddle-mpi: the PETSc found ({}) has complex scalars (PETSC_USE_COMPLEX); saddle needs real double \
                 scalars: configure PETSc with --with-scalar-type=real --with-precision=double (Debian: \
                 libpetsc-real-dev, not libpetsc-complex-dev)",
                install.origin
            );
        }
        if !conf.contains_key("PETSC_USE_REAL_DOUBLE") {
            let precision = ["PETSC_USE_REAL_SINGLE", "PETSC_USE_REAL___FLOAT128", "PETSC_USE_REAL___FP16"]
                .into_iter()
                .find(|k| conf.contains_key(*k))
                .unwrap_or("PETSC_USE_REAL_DOUBLE undefined");
            panic!(
                "saddle-mpi: the PETSc found ({}) does not use double precision ({precision}); configure PETSc with \
                 --with-precision=double",
                install.origin
            );
        }
    }

    /// PETSc and rsmpi must use the same MPI: a warning when mpi.h (rsmpi's) and PETSc's own
    /// configuration clearly name different implementations (OpenMPI against MPICH).
    fn check_mpi_flavour(install: &Install, mpi_includes: &[PathBuf]) {
        let mpi_h = mpi_includes.iter().map(|d| d.join("mpi.h")).find(|p| p.exists());
        let Some(text) = mpi_h.and_then(|p| fs::read_to_string(p).ok()) else { return };
        let rsmpi = if text.contains("define OPEN_MPI") {
            "OpenMPI"
        } else if text.contains("define MPICH_VERSION") {
            "MPICH"
        } else {
            return;
        };
        let variables: Vec<PathBuf> = install
            .include_dirs
            .iter()
            .filter_map(|d| d.parent())
            .map(|p| p.join("lib/petsc/conf/petscvariables"))
            .filter(|p| p.exists())
            .collect();
        let Some(vars) = variables.first().and_then(|p| fs::read_to_string(p).ok()) else { return };
        let petsc = if vars.contains("-lopen-rte") || vars.contains("openmpi") {
            "OpenMPI"
        } else if vars.contains("-lmpich") || vars.contains("mpich") {
            "MPICH"
        } else {
            return;
        };
        if petsc != rsmpi {
            println!(
                "cargo:warning=saddle-mpi: rsmpi builds against {rsmpi} but PETSc ({}) appears linked to {petsc}; \
                 both must use the same MPI (set MPI_PKG_CONFIG or put the right mpicc first on PATH)",
                install.origin
            );
        }
    }

    fn generate(install: &Install, mpi_includes: &[PathBuf]) {
        let mut builder = bindgen::builder()
            .header("wrapper.h")
            .clang_args(install.include_dirs.iter().chain(mpi_includes).map(|d| format!("-I{}", d.display())))
            // MPI's types are rsmpi's, so a communicator passes between both without a cast.
            .blocklist_type("MPI_Comm")
            .blocklist_type("ompi_communicator_t")
            .raw_line("pub use mpi::ffi::MPI_Comm;")
            // An int, or from PETSc 3.19 with --with-strict-petscerrorcode an enum spanning int's
            // range: an int at the ABI either way.
            .blocklist_type("PetscErrorCode")
            .raw_line("pub type PetscErrorCode = ::std::os::raw::c_int;")
            .default_enum_style(bindgen::EnumVariation::NewType { is_bitfield: false, is_global: false })
            .prepend_enum_name(false)
            .derive_default(false)
            .layout_tests(false)
            .generate_comments(false)
            .allowlist_recursively(true);
        for f in FUNCTIONS {
            builder = builder.allowlist_function(f);
        }
        for v in VARIABLES {
            builder = builder.allowlist_var(v);
        }
        let bindings = builder
            .generate()
            .unwrap_or_else(|e| panic!("saddle-mpi: bindgen failed on PETSc's headers ({}): {e}", install.origin));
        let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("petsc.rs");
        bindings.write_to_file(&out).unwrap_or_else(|e| panic!("saddle-mpi: cannot write {}: {e}", out.display()));
    }
}
