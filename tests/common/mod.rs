//! Helpers shared by the integration tests: scenes from the examples with edits.
#![allow(dead_code)]

use saddle::core::{DiscreteProblem, Silent, Solution, Solver, Sym};
use saddle::io::scene::Scene;
use saddle::solvers::{Newton, Penalty, Uzawa};
use std::path::{Path, PathBuf};

/// Path of a file in the repository.
pub fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// The TOML of an example scene as a table, to edit.
pub fn example(name: &str) -> toml::Table {
    let text = std::fs::read_to_string(repo(&format!("examples/{name}"))).unwrap();
    toml::from_str(&text).unwrap()
}

/// Sets `table.path = value` for a dotted path (`"mesh.cells"`).
pub fn set(t: &mut toml::Table, path: &str, value: toml::Value) {
    let mut keys: Vec<&str> = path.split('.').collect();
    let last = keys.pop().unwrap();
    let mut cur = t;
    for k in keys {
        cur = cur.get_mut(k).and_then(|v| v.as_table_mut()).unwrap_or_else(|| panic!("no table {k}"));
    }
    cur.insert(last.to_string(), value);
}

/// Assembles a scene table.
pub fn build(t: &toml::Table) -> (DiscreteProblem, Option<Box<dyn Solver>>) {
    let scene = Scene::from_toml(&toml::to_string(t).unwrap(), Path::new("test.toml")).unwrap();
    scene.into_problem().unwrap()
}

/// A small version of the default scene that runs in a second or two.
pub fn small_johnson() -> toml::Table {
    let mut t = example("johnson.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from([12, 12, 6]).unwrap());
    set(&mut t, "mesh.grading.ratio", toml::Value::Float(3.0));
    t
}

/// A `[yield]` table: `type = kind` with the numbers `fields`.
pub fn yield_table(kind: &str, fields: &[(&str, f64)]) -> toml::Value {
    let mut t = toml::Table::new();
    t.insert("type".into(), kind.into());
    for (k, v) in fields {
        t.insert(k.to_string(), (*v).into());
    }
    toml::Value::Table(t)
}

/// Newton, Uzawa, the penalty method and (with the feature) SOCP with these tolerances, by name.
pub fn solvers_with(newton: f64, uzawa: f64, penalty: f64, socp: f64) -> Vec<(&'static str, Box<dyn Solver>)> {
    let mut v: Vec<(&'static str, Box<dyn Solver>)> = vec![
        ("newton", Box::new(Newton { tol: newton, ..Newton::default() })),
        ("uzawa", Box::new(Uzawa { tol: uzawa, ..Uzawa::default() })),
        ("penalty", Box::new(Penalty { tol: penalty, ..Penalty::default() })),
    ];
    #[cfg(feature = "socp")]
    v.push(("socp", Box::new(saddle::solvers::Socp { tol: socp, ..saddle::solvers::Socp::default() })));
    #[cfg(not(feature = "socp"))]
    let _ = socp;
    v
}

/// `s` (called `name` in messages) on `l`; panics unless it converges.
pub fn solve_converged(l: &DiscreteProblem, name: &str, s: &dyn Solver) -> Solution {
    let sol = s.solve(&l.lagrangian(), &mut Silent).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(sol.report.converged, "{name}: {:?}", sol.report.stop_reason);
    sol
}

/// The largest errors of a solution of homogeneous compression (theory §7.1) against the
/// uniaxial stress σ = −F e₃⊗e₃, relative to F, and against the nodal displacements
/// u = (ε₁₁x, ε₁₁y, ε₃₃(z − 1)) of the unit cube, relative to `u_scale`: (σ error, u error).
pub fn compression_errors(l: &DiscreteProblem, sol: &Solution, f: f64, e11: f64, e33: f64, u_scale: f64) -> (f64, f64) {
    let exact = Sym::new(0.0, 0.0, -f, 0.0, 0.0, 0.0);
    let es = sol.stress.sigma.iter().map(|s| (s - exact).norm() / f).fold(0.0f64, f64::max);
    let mut eu = 0.0f64;
    for (x, d) in l.element.mesh().nodes.iter().zip(l.element.nodal_vectors(&sol.u)) {
        let exact = [e11 * x[0], e11 * x[1], e33 * (x[2] - 1.0)];
        for k in 0..3 {
            eu = eu.max((d[k] - exact[k]).abs() / u_scale);
        }
    }
    (es, eu)
}

/// A solver from TOML text.
pub fn solver(text: &str) -> Box<dyn Solver> {
    toml::from_str(text).unwrap()
}

/// Runs `saddle run --quiet` on scene text written to a temporary folder; returns (exit code,
/// stderr, whether the output folder was created).
pub fn run_scene(text: &str) -> (i32, String, bool) {
    let (code, stderr, dir) = run_scene_kept(text);
    (code, stderr, dir.path().join("out").exists())
}

/// [`run_scene`], keeping the temporary folder (its output in `out/`) for the caller to read.
pub fn run_scene_kept(text: &str) -> (i32, String, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.path().join("out");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_saddle"))
        .args(["run", scene.to_str().unwrap(), "--quiet", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    (o.status.code().unwrap(), String::from_utf8_lossy(&o.stderr).into_owned(), dir)
}

/// `saddle run` on scene text fails with exit code 1, writes nothing, and its error holds every
/// piece of `expected` (the field and the value).
pub fn assert_rejected(text: &str, expected: &[&str]) {
    let (code, err, wrote) = run_scene(text);
    assert_eq!(code, 1, "{err}");
    assert!(!wrote, "nothing is written for an invalid scene");
    for e in expected {
        assert!(err.contains(e), "error message {err:?} lacks {e:?}");
    }
}

/// One row of a CSV file written by saddle: column name → field.
pub type CsvRow = std::collections::HashMap<String, String>;

/// The rows of a CSV text with a header line (saddle's CSV fields hold no commas).
pub fn csv_rows(text: &str) -> Vec<CsvRow> {
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines.map(|l| head.iter().map(|h| h.to_string()).zip(l.split(',').map(str::to_string)).collect()).collect()
}

/// The number in column `k` of a CSV row.
pub fn csv_num(r: &CsvRow, k: &str) -> f64 {
    r[k].parse().unwrap_or_else(|_| panic!("{k} = {:?}", r[k]))
}
