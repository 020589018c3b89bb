//! Writes the cone programme that `socp` hands Clarabel for a scene, as JSON
//! ([`saddle::solvers::socp::cone_programme_json`]), so that another conic solver can solve
//! the very same problem — `examples/peers/cvxpy_socp.py` does, with cvxpy + Clarabel.
//!
//! With `--limit`, the static programme of the scene's limit analysis instead
//! ([`saddle::solvers::LimitAnalysis::programme_json`], theory §13).
//!
//! ```text
//! cargo run --release --example export_cone -- examples/gmsh_punch.toml cone.json
//! cargo run --release --example export_cone -- --limit examples/strip_punch.toml limit.json
//! ```

use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let limit = args.first().is_some_and(|a| a == "--limit");
    if limit {
        args.remove(0);
    }
    let [scene, out] = args.as_slice() else {
        eprintln!("usage: export_cone [--limit] SCENE.toml OUT.json");
        return ExitCode::FAILURE;
    };
    let run = || -> Result<(), Box<dyn std::error::Error>> {
        let loaded = saddle::app::setup::load(&PathBuf::from(scene), None)?;
        let json = if limit {
            saddle::solvers::LimitAnalysis::programme_json(&loaded.problem)?
        } else {
            saddle::solvers::socp::cone_programme_json(&loaded.problem.lagrangian())?
        };
        std::fs::write(out, json).map_err(|e| format!("cannot write {out}: {e}"))?;
        Ok(())
    };
    match run() {
        Ok(()) => {
            eprintln!("wrote {out}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
