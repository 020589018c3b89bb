//! Failures reach every rank as typed errors with PETSc's message, never a hang: an error on one
//! rank through `agree`, options PETSc rejects, a PETSc error raised on one rank only, a diverged
//! solve, a misuse caught before PETSc; and the precedence of command-line options over a
//! scene's. Run under `mpirun -n N` (.ci/run-mpi-tests); the program adds `-cli_ksp_max_it 3` to
//! its own arguments, as a user would on the command line.

mod common;

use common::distributed::{Case, ensure, run};
use saddle_mpi::{Error, GhostVector, Index, Ksp, Matrix, Method, Petsc, Settings, agree};
use std::process::ExitCode;

/// Unknowns per rank of the 1D Laplacian.
const PER_RANK: usize = 10;

/// The 1D Laplacian tridiag(−1, 2, −1) of order 10·P, preallocated exactly, and b = 1.
fn laplacian(petsc: &Petsc) -> Result<(Matrix, GhostVector, GhostVector), Error> {
    let n = PER_RANK * petsc.size();
    let start = PER_RANK * petsc.rank();
    let rows = start..start + PER_RANK;
    let (mut d, mut o) = (vec![0 as Index; PER_RANK], vec![0 as Index; PER_RANK]);
    for (k, i) in rows.clone().enumerate() {
        for j in [i.wrapping_sub(1), i, i + 1].into_iter().filter(|&j| j < n) {
            if rows.contains(&j) { d[k] += 1 } else { o[k] += 1 }
        }
    }
    let mut a = Matrix::new(petsc, PER_RANK, 1, &d, &o)?;
    for i in rows {
        for j in [i.wrapping_sub(1), i, i + 1].into_iter().filter(|&j| j < n) {
            a.add_values(&[i as Index], &[j as Index], &[if i == j { 2.0 } else { -1.0 }])?;
        }
    }
    a.assemble()?;
    let mut b = GhostVector::new(petsc, PER_RANK, &[])?;
    b.set(1.0)?;
    let x = b.duplicate()?;
    Ok((a, b, x))
}

/// An error on the last rank only reaches every rank through `agree`, with its rank and message;
/// with errors on the upper half of the ranks, the lowest failing rank's message is reported.
fn error_on_one_rank(petsc: &Petsc) -> Result<(), String> {
    let (rank, size) = (petsc.rank(), petsc.size());
    let last = size - 1;
    let local: Result<usize, String> =
        if rank == last { Err(format!("cannot read mesh part {rank}")) } else { Ok(rank) };
    match agree(petsc.world(), local) {
        Err(Error::Rank { rank: r, failed: 1, size: s, message }) if r == last && s == size => {
            ensure(message == format!("cannot read mesh part {last}"), format!("message {message:?}"))?
        }
        other => return Err(format!("rank {rank}: expected the last rank's error, got {other:?}")),
    }
    let half = size / 2;
    let local: Result<(), String> = if rank >= half { Err(format!("rank {rank} failed")) } else { Ok(()) };
    match agree(petsc.world(), local) {
        Err(Error::Rank { rank: r, failed, message, .. }) if r == half && failed == size - half => {
            ensure(message == format!("rank {half} failed"), format!("message {message:?}"))
        }
        other => Err(format!("rank {rank}: expected rank {half}'s error, got {other:?}")),
    }
}

/// `-bad_ksp_type nonsense`: KSPSetFromOptions fails on every rank with PETSc's message.
fn bad_options(petsc: &Petsc) -> Result<(), String> {
    petsc.insert_options("-bad_ksp_type nonsense").map_err(|e| e.to_string())?;
    let settings = Settings { prefix: "bad_".into(), ..Settings::default() };
    match Ksp::new(petsc, &settings) {
        Err(Error::Petsc(e)) if e.call == "KSPSetFromOptions" && e.message.contains("nonsense") => {
            if petsc.rank() == 0 {
                println!("    {e}");
            }
            Ok(())
        }
        Err(other) => Err(format!("unexpected error {other}")),
        Ok(_) => Err("-bad_ksp_type nonsense was accepted".into()),
    }
}

/// A PETSc error raised on one rank only (an entry outside the preallocation, on the last rank)
/// is a typed error with PETSc's message there, and through `agree` on every rank.
fn petsc_error_on_one_rank(petsc: &Petsc) -> Result<(), String> {
    let (mut a, _, _) = laplacian(petsc).map_err(|e| e.to_string())?;
    let last = petsc.size() - 1;
    let local = if petsc.rank() == last {
        let (row, col) = (PER_RANK * last, PER_RANK * last + PER_RANK - 1);
        a.add_values(&[row as Index], &[col as Index], &[1.0])
    } else {
        Ok(())
    };
    if let Err(Error::Petsc(e)) = &local {
        println!("    rank {last}: {e}");
    }
    match agree(petsc.world(), local) {
        Err(Error::Rank { rank, message, .. })
            if rank == last && message.contains("MatSetValues") && message.contains("malloc") =>
        {
            Ok(())
        }
        other => Err(format!("expected the last rank's MatSetValues error, got {other:?}")),
    }
}

/// The iteration limit: `Error::Diverged` named `DIVERGED_ITS` after exactly the limit.
fn diverged(petsc: &Petsc) -> Result<(), String> {
    let (a, b, mut x) = laplacian(petsc).map_err(|e| e.to_string())?;
    petsc.insert_options("-div_pc_type jacobi").map_err(|e| e.to_string())?;
    let settings = Settings { rtol: 1e-14, max_iterations: 2, prefix: "div_".into(), ..Settings::default() };
    let mut ksp = Ksp::new(petsc, &settings).map_err(|e| e.to_string())?;
    ksp.set_operator(&a).map_err(|e| e.to_string())?;
    match ksp.solve(&b, &mut x) {
        Err(e @ Error::Diverged { iterations: 2, .. }) if e.to_string().contains("DIVERGED_ITS") => {
            if petsc.rank() == 0 {
                println!("    {e}");
            }
            Ok(())
        }
        other => Err(format!("expected DIVERGED_ITS after 2 iterations, got {other:?}")),
    }
}

/// The command line's `-cli_ksp_max_it 3` wins over the scene's `-cli_ksp_max_it 1000`; the
/// scene's other options apply (Jacobi, rtol 1e-14): the solve stops after exactly 3 iterations.
fn command_line_wins(petsc: &Petsc) -> Result<(), String> {
    let (a, b, mut x) = laplacian(petsc).map_err(|e| e.to_string())?;
    petsc.insert_options("-cli_ksp_max_it 1000 -cli_pc_type jacobi -cli_ksp_rtol 1e-14").map_err(|e| e.to_string())?;
    let settings = Settings { method: Method::CgGamg, prefix: "cli_".into(), ..Settings::default() };
    let mut ksp = Ksp::new(petsc, &settings).map_err(|e| e.to_string())?;
    ksp.set_operator(&a).map_err(|e| e.to_string())?;
    match ksp.solve(&b, &mut x) {
        Err(Error::Diverged { iterations: 3, reason, .. }) if reason.contains("DIVERGED_ITS") => Ok(()),
        other => Err(format!("expected DIVERGED_ITS after the command line's 3 iterations, got {other:?}")),
    }
}

/// Misuse caught before PETSc: preallocation arrays of the wrong length.
fn wrong_length(petsc: &Petsc) -> Result<(), String> {
    match Matrix::new(petsc, 4, 1, &[1; 3], &[0; 4]) {
        Err(Error::Length { what: "diagonal_nnz", got: 3, expected: 4 }) => Ok(()),
        Err(other) => Err(format!("unexpected error {other}")),
        Ok(_) => Err("accepted 3 counts for 4 rows".into()),
    }
}

fn main() -> ExitCode {
    let args = std::env::args().chain(["-cli_ksp_max_it".to_string(), "3".to_string()]);
    let petsc = Petsc::initialize_with_args(args).expect("MPI and PETSc initialise");
    let cases: [Case; 6] = [
        ("error_on_one_rank_reaches_all", &error_on_one_rank),
        ("bad_ksp_type_is_a_clear_error", &bad_options),
        ("petsc_error_on_one_rank_reaches_all", &petsc_error_on_one_rank),
        ("diverged_solve_names_its_reason", &diverged),
        ("command_line_options_win_over_scene", &command_line_wins),
        ("wrong_length_caught_before_petsc", &wrong_length),
    ];
    let code = run(&petsc, &cases);
    drop(petsc);
    code
}
