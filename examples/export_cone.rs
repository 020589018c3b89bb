//! Writes the cone programme that `socp` hands Clarabel for a scene, as JSON
//! ([`saddle::solvers::socp::cone_programme_json`]), so that another conic solver can solve
//! the very same problem — `examples/peers/cvxpy_socp.py` does, with cvxpy + Clarabel.
//!
//! ```text
//! cargo run --release --example export_cone -- examples/gmsh_punch.toml cone.json
//! ```

use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, out] = args.as_slice() else {
        eprintln!("usage: export_cone SCENE.toml OUT.json");
        return ExitCode::FAILURE;
    };
    let run = || -> Result<(), Box<dyn std::error::Error>> {
        let loaded = saddle::app::setup::load(&PathBuf::from(scene), None)?;
        let json = saddle::solvers::socp::cone_programme_json(&loaded.problem.lagrangian())?;
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
