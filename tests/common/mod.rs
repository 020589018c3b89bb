//! Helpers shared by the integration tests: scenes from the examples with edits.
#![allow(dead_code)]

use saddle::core::DiscreteProblem;
use saddle::core::Solver;
use saddle::io::scene::Scene;
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
