//! `saddle bench --meshes`: one scene run end to end on a family of Gmsh meshes, side by side
//! with a peer code's runs on the very same meshes (issue 14).
//!
//! Each mesh replaces the scene's `[mesh]` (as `type = "gmsh"`, scale 1) and is run exactly as
//! `saddle run` runs it — read, set-up, solve, summary, `solution.vtu` — into `OUT/<mesh stem>/`.
//! The wall time is taken around all of it, the peak resident memory from the kernel. A peer's
//! run is read from the JSON that `examples/peers/dolfinx/punch.py --json` writes: its free DOFs,
//! Newton and Krylov iterations, force, contact and plastic counts, the wall time of its
//! elastic and plastic solves (what the comparison counts, as in the issue's table) and of its
//! whole script. Writes `OUT/meshes.csv` and `OUT/meshes.md`.
//!
//! ```text
//! examples/peers/compare.sh 16 24 32     # the peer, then saddle, on the same meshes
//! saddle bench examples/peers/punch.toml --out docs/peer --meshes box24.msh --peer peer24.json
//! ```

use super::bench::{load_average, peak_memory_mib, reset_peak_memory};
use crate::app::run::solve_and_write;
use crate::app::setup::{RunError, load_with};
use saddle_core::Silent;
use saddle_core::mesh::gmsh::GmshMesh;
use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;
use thiserror::Error;

/// Why a mesh bench failed.
#[derive(Debug, Error)]
pub enum PeerError {
    /// A run failed.
    #[error("{mesh}: {source}")]
    Run {
        /// The mesh file.
        mesh: PathBuf,
        /// Why.
        source: RunError,
    },
    /// A peer's JSON could not be read or lacks a field.
    #[error("peer run {path}: {message}")]
    Peer {
        /// The JSON file.
        path: PathBuf,
        /// What is wrong (the missing or malformed field).
        message: String,
    },
    /// `--peer` was given, but not one file per mesh.
    #[error("--peer: {peers} files for {meshes} meshes (give one peer JSON per mesh, in the same order)")]
    PeerCount {
        /// Peer files.
        peers: usize,
        /// Meshes.
        meshes: usize,
    },
    /// A table could not be written.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// saddle on one mesh, end to end.
#[derive(Clone, Debug)]
pub struct MeshRun {
    /// The mesh file.
    pub mesh: PathBuf,
    /// Free displacement DOFs.
    pub dofs: usize,
    /// Tetrahedra.
    pub elements: usize,
    /// Wall time from reading the scene to the last byte of output.
    pub wall_s: f64,
    /// The end-to-end phases of `summary.json` (`read`, `setup`, `solve`, `summary`, `write`).
    pub phases: Vec<(String, f64)>,
    /// Outer (Newton) iterations.
    pub iterations: usize,
    /// Inner iterations (CG), when the solver counts them.
    pub inner_iterations: Option<f64>,
    /// The obstacle's `force` (None without one).
    pub force: Option<f64>,
    /// Contact nodes.
    pub contact_nodes: usize,
    /// Plastic elements.
    pub plastic_elements: usize,
    /// The recomputed relative KKT residual.
    pub kkt_residual: f64,
    /// Whether the solver converged.
    pub converged: bool,
    /// Peak resident memory of the process during the run, MiB.
    pub peak_mib: f64,
    /// The 1-minute load average when the run started.
    pub load_before: f64,
}

impl MeshRun {
    /// The time of one end-to-end phase (0 when absent).
    pub fn phase(&self, name: &str) -> f64 {
        self.phases.iter().find(|(k, _)| k == name).map_or(0.0, |(_, t)| *t)
    }

    /// Everything outside the solve: reading, set-up, summary and output, as a fraction of the
    /// wall time.
    pub fn outside_solve_fraction(&self) -> f64 {
        (self.wall_s - self.phase("solve")) / self.wall_s
    }
}

/// A peer's run on one mesh, from its JSON.
#[derive(Clone, Debug, PartialEq)]
pub struct PeerRun {
    /// Free DOFs.
    pub dofs: usize,
    /// Wall time of its elastic and plastic solves.
    pub solve_s: f64,
    /// Wall time of its whole script (mesh, set-up, JIT, solves, export).
    pub total_s: f64,
    /// Newton iterations, elastic + plastic.
    pub newton_iterations: usize,
    /// Krylov iterations, elastic + plastic.
    pub krylov_iterations: usize,
    /// Contact force of the plastic solution.
    pub force: f64,
    /// Contact nodes.
    pub contact_nodes: usize,
    /// Plastic cells.
    pub plastic_cells: usize,
    /// The 1-minute load average at its end, if recorded.
    pub load_end: Option<f64>,
}

/// Reads a peer's JSON (`punch.py --json`).
pub fn read_peer(path: &Path) -> Result<PeerRun, PeerError> {
    let fail = |message: String| PeerError::Peer { path: path.to_path_buf(), message };
    let text = std::fs::read_to_string(path).map_err(|e| fail(e.to_string()))?;
    let v: Value = serde_json::from_str(&text).map_err(|e| fail(format!("not JSON: {e}")))?;
    let num = |field: &str| -> Result<f64, PeerError> {
        let mut x = &v;
        for key in field.split('.') {
            x = x.get(key).ok_or_else(|| fail(format!("no field `{field}`")))?;
        }
        x.as_f64().ok_or_else(|| fail(format!("field `{field}` = {x} is not a number")))
    };
    // the peer records the load at its end (that at its start only in its log)
    let load = v.get("loadavg_end").and_then(|l| l.get(0)).and_then(|x| x.as_str()?.parse().ok());
    Ok(PeerRun {
        dofs: num("free_dofs")? as usize,
        solve_s: num("elastic.time")? + num("plastic.time")?,
        total_s: num("timings.total")?,
        newton_iterations: (num("elastic.newton_its")? + num("plastic.newton_its")?) as usize,
        krylov_iterations: (num("elastic.ksp_its")? + sum_steps(&v, "ksp_its")) as usize,
        force: num("plastic.F")?,
        contact_nodes: num("plastic.n_contact")? as usize,
        plastic_cells: num("plastic.n_plastic_cells")? as usize,
        load_end: load,
    })
}

/// Σ over the plastic load steps of `key` (0 when absent).
fn sum_steps(v: &Value, key: &str) -> f64 {
    v.get("plastic")
        .and_then(|p| p.get("steps"))
        .and_then(Value::as_array)
        .map_or(0.0, |steps| steps.iter().filter_map(|s| s.get(key)?.as_f64()).sum())
}

/// Runs `scene` end to end on each of `meshes` (in order), writing each run's output under
/// `out/<mesh stem>/`; `progress` gets a line per finished run.
pub fn measure(
    scene: &Path,
    meshes: &[PathBuf],
    out: &Path,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<MeshRun>, PeerError> {
    let mut runs = Vec::with_capacity(meshes.len());
    for mesh in meshes {
        let fail = |source| PeerError::Run { mesh: mesh.clone(), source };
        // an absolute path, so that the scene's folder does not re-root it
        let file = std::path::absolute(mesh).map_err(|e| fail(RunError::Io { path: mesh.clone(), source: e }))?;
        let stem = mesh.file_stem().map_or("mesh".into(), |s| s.to_string_lossy().into_owned());
        let load_before = load_average();
        reset_peak_memory();
        let started = Instant::now();
        let loaded = load_with(scene, None, |s| {
            s.mesh = Box::new(GmshMesh::new(file));
            Ok(())
        })
        .map_err(fail)?;
        let outcome = solve_and_write(&loaded, &out.join(&stem), &mut Silent).map_err(fail)?;
        let wall_s = started.elapsed().as_secs_f64();
        let s = outcome.summary;
        let r = MeshRun {
            mesh: mesh.clone(),
            dofs: s.dofs,
            elements: s.elements,
            wall_s,
            phases: s.end_to_end.into_iter().collect(),
            iterations: s.iterations,
            inner_iterations: s.counters.get("pcg_iterations").copied(),
            force: s.force,
            contact_nodes: s.contact_nodes,
            plastic_elements: s.plastic_elements,
            kkt_residual: s.kkt_residual,
            converged: s.converged,
            peak_mib: peak_memory_mib(),
            load_before,
        };
        progress(&format!(
            "{}: {} dofs, {:.2} s end to end (solve {:.2} s), {} iterations, peak {:.0} MiB",
            mesh.display(),
            r.dofs,
            r.wall_s,
            r.phase("solve"),
            r.iterations,
            r.peak_mib
        ));
        runs.push(r);
    }
    Ok(runs)
}

/// `saddle bench --meshes`: [`measure`], the peers' JSON files (one per mesh, or none), and the
/// tables `meshes.csv` and `meshes.md` in `out`. Returns the markdown table.
pub fn generate(
    scene: &Path,
    meshes: &[PathBuf],
    peers: &[PathBuf],
    out: &Path,
    progress: &mut dyn FnMut(&str),
) -> Result<String, PeerError> {
    if !peers.is_empty() && peers.len() != meshes.len() {
        return Err(PeerError::PeerCount { peers: peers.len(), meshes: meshes.len() });
    }
    // read the peers first: a bad file fails before the long runs
    let peers = peers.iter().map(|p| read_peer(p)).collect::<Result<Vec<_>, _>>()?;
    let runs = measure(scene, meshes, out, progress)?;
    let write = |name: &str, text: &str| {
        let path = out.join(name);
        std::fs::write(&path, text).map_err(|source| PeerError::Io { path, source })
    };
    write("meshes.csv", &csv(&runs, &peers))?;
    let md = markdown(&runs, &peers);
    write("meshes.md", &md)?;
    Ok(md)
}

/// `meshes.csv`: one row per mesh.
pub fn csv(runs: &[MeshRun], peers: &[PeerRun]) -> String {
    let mut s = String::from(
        "mesh,dofs,elements,wall_s,read_s,setup_s,solve_s,summary_s,write_s,outside_solve_fraction,iterations,\
         inner_iterations,force,contact_nodes,plastic_elements,kkt_residual,converged,peak_mib,load_before,\
         peer_dofs,peer_solve_s,peer_total_s,peer_newton_iterations,peer_krylov_iterations,peer_force,\
         peer_contact_nodes,peer_plastic_cells,ratio\n",
    );
    for (i, r) in runs.iter().enumerate() {
        let _ = write!(
            s,
            "{},{},{},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{},{},{},{},{},{:.3e},{},{:.1},{:.2}",
            r.mesh.display(),
            r.dofs,
            r.elements,
            r.wall_s,
            r.phase("read"),
            r.phase("setup"),
            r.phase("solve"),
            r.phase("summary"),
            r.phase("write"),
            r.outside_solve_fraction(),
            r.iterations,
            r.inner_iterations.map_or(String::new(), |x| format!("{x:.0}")),
            r.force.map_or(String::new(), |f| format!("{f:.9}")),
            r.contact_nodes,
            r.plastic_elements,
            r.kkt_residual,
            r.converged,
            r.peak_mib,
            r.load_before
        );
        let peer = peers.get(i).map(|p| {
            let counts = [p.dofs, p.newton_iterations, p.krylov_iterations, p.contact_nodes, p.plastic_cells];
            let times = [p.solve_s, p.total_s];
            let [dofs, newton, krylov, contact, plastic] = counts.map(|c| c.to_string());
            let [solve, total] = times.map(|t| format!("{t:.4}"));
            let (force, ratio) = (format!("{:.9}", p.force), format!("{:.3}", p.solve_s / r.wall_s));
            [dofs, solve, total, newton, krylov, force, contact, plastic, ratio].join(",")
        });
        let _ = writeln!(s, ",{}", peer.unwrap_or_else(|| ",".repeat(8)));
    }
    s
}

/// `meshes.md`: the table of the README.
pub fn markdown(runs: &[MeshRun], peers: &[PeerRun]) -> String {
    let mut s = String::new();
    let with_peer = !peers.is_empty();
    s.push_str("| DOFs | saddle end to end | solve | outside the solve | Newton (CG) its | force | contact | plastic | peak MiB |");
    if with_peer {
        s.push_str(" peer solves | peer script | peer Newton (Krylov) its | peer force | peer contact | peer plastic | ratio |");
    }
    s.push('\n');
    let columns = 9 + if with_peer { 7 } else { 0 };
    s.push_str(&"|---".repeat(columns));
    s.push_str("|\n");
    for (i, r) in runs.iter().enumerate() {
        let _ = write!(
            s,
            "| {} | {:.2} s | {:.2} s | {:.1} % | {} ({}) | {} | {} | {} | {:.0} |",
            r.dofs,
            r.wall_s,
            r.phase("solve"),
            100.0 * r.outside_solve_fraction(),
            r.iterations,
            r.inner_iterations.map_or("-".into(), |x| format!("{x:.0}")),
            r.force.map_or("-".into(), |f| format!("{f:.7}")),
            r.contact_nodes,
            r.plastic_elements,
            r.peak_mib
        );
        if let Some(p) = peers.get(i) {
            let _ = write!(
                s,
                " {:.2} s | {:.2} s | {} ({}) | {:.7} | {} | {} | {:.2}× |",
                p.solve_s,
                p.total_s,
                p.newton_iterations,
                p.krylov_iterations,
                p.force,
                p.contact_nodes,
                p.plastic_cells,
                p.solve_s / r.wall_s
            );
        }
        s.push('\n');
    }
    if with_peer {
        s.push_str(
            "\nratio = the peer's elastic + plastic solve time / saddle's end-to-end wall time (reading, set-up, \
             solve, summary, output). ",
        );
    }
    let loads: Vec<String> = runs.iter().map(|r| format!("{:.2}", r.load_before)).collect();
    let _ = write!(s, "Load average before each saddle run: {}.", loads.join(", "));
    let peer_loads: Vec<String> = peers.iter().filter_map(|p| Some(format!("{:.2}", p.load_end?))).collect();
    if !peer_loads.is_empty() {
        let _ = write!(s, " At the end of each peer run: {}.", peer_loads.join(", "));
    }
    s.push('\n');
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_peer_json_is_read_and_a_missing_field_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("peer.json");
        let json = r#"{"free_dofs": 5088, "timings": {"total": 2.5},
            "elastic": {"time": 0.25, "newton_its": 3, "ksp_its": 48},
            "plastic": {"time": 0.5, "newton_its": 5, "F": 4.9, "n_contact": 37, "n_plastic_cells": 8102,
                        "steps": [{"ksp_its": 100}, {"ksp_its": 17}]},
            "loadavg_end": ["0.50", "0.4", "0.3"]}"#;
        std::fs::write(&path, json).unwrap();
        let p = read_peer(&path).unwrap();
        assert_eq!(
            p,
            PeerRun {
                dofs: 5088,
                solve_s: 0.75,
                total_s: 2.5,
                newton_iterations: 8,
                krylov_iterations: 165,
                force: 4.9,
                contact_nodes: 37,
                plastic_cells: 8102,
                load_end: Some(0.5),
            }
        );
        std::fs::write(&path, json.replace("\"n_contact\"", "\"contact\"")).unwrap();
        let e = read_peer(&path).unwrap_err().to_string();
        assert!(e.contains("plastic.n_contact") && e.contains("peer.json"), "{e}");
    }
}
