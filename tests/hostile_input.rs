//! Issue 31, hostile input: one test per finding — each input, its exit status and the message
//! naming the field and the value — and a property test that mutates the example scenes. Exit
//! statuses (README, command line): 0 converged, 1 bad input or usage (nothing written), 2
//! stopped without converging with the outputs written.

mod common;
use common::*;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestCaseError, TestRunner};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The default scene on a 4×4×2 mesh (one candidate node under the punch): milliseconds a solve.
fn tiny_johnson() -> toml::Table {
    let mut t = example("johnson.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from([4, 4, 2]).unwrap());
    set(&mut t, "mesh.grading.ratio", toml::Value::Float(2.0));
    t
}

/// The indentation (a 9-step load path) on the same mesh.
fn tiny_indentation() -> toml::Table {
    let mut t = example("indentation.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from([4, 4, 2]).unwrap());
    set(&mut t, "mesh.grading.ratio", toml::Value::Float(2.0));
    t
}

fn text(t: &toml::Table) -> String {
    toml::to_string(t).unwrap()
}

/// The tiny default scene with `path` set to `value`.
fn edited(path: &str, value: toml::Value) -> String {
    let mut t = tiny_johnson();
    set(&mut t, path, value);
    text(&t)
}

/// A TOML value from its text (`{ group = "zmin" }`).
fn value(v: &str) -> toml::Value {
    toml::from_str::<toml::Table>(&format!("v = {v}")).unwrap()["v"].clone()
}

/// `saddle ARGS` in `dir`: (exit status, stdout, stderr).
fn saddle(dir: &Path, args: &[&str]) -> (i32, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_saddle")).current_dir(dir).args(args).output().unwrap();
    let s = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (o.status.code().expect("exited, not killed"), s(&o.stdout), s(&o.stderr))
}

/// A temporary folder holding `scene.toml` with `text`.
fn scene_dir(text: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.toml"), text).unwrap();
    dir
}

/// The files of a folder, sorted.
fn files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

// ---- 1. one error path: type and length errors name the field and the value ----

#[test]
fn type_and_length_errors_name_the_field_and_the_value() {
    assert_rejected(
        &edited("mesh.cells", value("[12, 12]")),
        &["mesh.cells = [12, 12]", "invalid length 2", "length 3"],
    );
    assert_rejected(
        &edited("mesh.max", value("[1.0, 1.0, 1.0, 1.0]")),
        &["mesh.max = [1.0, 1.0, 1.0, 1.0]", "invalid length 4"],
    );
    assert_rejected(&edited("obstacle.F", value("[0.3]")), &["obstacle.F = [0.3]", "expected f64"]);
    let mut t = tiny_johnson();
    t.insert("discretisation".into(), value("{ type = \"p2\", mean_dilatation = \"yes\" }"));
    assert_rejected(&text(&t), &["discretisation.mean_dilatation = \"yes\"", "expected a boolean"]);
    // inside an array of obstacles (the name set aside as the plugin reads its table)
    let mut t = tiny_johnson();
    let punch = t.remove("obstacle").unwrap();
    let named = |name: &str, f: toml::Value| {
        let mut p = punch.as_table().unwrap().clone();
        p.insert("name".into(), name.into());
        p.insert("F".into(), f);
        toml::Value::Table(p)
    };
    t.insert("obstacle".into(), toml::Value::Array(vec![named("a", 0.1.into()), named("b", "much".into())]));
    assert_rejected(&text(&t), &["obstacle[1].F = \"much\"", "expected f64"]);
    // inside a [[load]] (serde buffers its table: the field is found by the length named)
    let mut t = tiny_johnson();
    t.insert("load".into(), value("[ { type = \"body_force\", b = [0.0, -1e-3] } ]"));
    assert_rejected(&text(&t), &["load[0].b = [0.0, -0.001]", "invalid length 2"]);
}

#[test]
fn a_negative_grading_ratio_with_align_is_a_ratio_error() {
    let (code, err, _) = run_scene(&edited("mesh.grading.ratio", (-2.0).into()));
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("mesh.grading.ratio = -2") && err.contains("[1, 1e6]"), "{err}");
    assert!(!err.contains("align"), "blames align: {err}");
}

// ---- 2. meaningless magnitudes, refused before any solve by the plugin that owns the value ----

#[test]
fn meaningless_magnitudes_are_refused_by_their_plugin() {
    // not "matrix has NaN or infinite entries" (newton) nor a default the user never set (penalty)
    for solver in ["uzawa", "newton", "penalty"] {
        let mut t = tiny_johnson();
        set(&mut t, "material.E", 1e308.into());
        set(&mut t, "solver", value(&format!("{{ type = \"{solver}\" }}")));
        assert_rejected(&text(&t), &["material.E = 1e308", "[1e-50, 1e50]"]);
    }
    assert_rejected(&edited("material.E", 1e-300.into()), &["material.E = 1e-300", "[1e-50, 1e50]"]);
    // not "non-finite value in the KKT residual at iteration 0"
    assert_rejected(&edited("obstacle.F", 1e308.into()), &["obstacle.F = 1e308", "1e50"]);
    assert_rejected(&edited("yield.k0", 1e300.into()), &["yield.k0 = 1e300", "1e50"]);
    assert_rejected(&edited("yield.h", 1e-300.into()), &["yield.h = 1e-300", "0 or in [1e-50, 1e50]"]);
    assert_rejected(&edited("obstacle.gap.R", 1e-300.into()), &["obstacle.gap.R = 1e-300"]);
    let mut t = tiny_johnson();
    t.insert("load".into(), value("[ { type = \"body_force\", b = [0.0, 0.0, -1e300] } ]"));
    assert_rejected(&text(&t), &["load[0].b[2] = -1e300", "1e50"]);
    let mut t = tiny_johnson();
    set(&mut t, "yield", value("{ type = \"von_mises_kinematic\", k0 = 1.0, h = 1.0, c = 1e-300 }"));
    assert_rejected(&text(&t), &["yield.c = 1e-300"]);
    let mut t = tiny_johnson();
    set(&mut t, "yield", value("{ type = \"tresca\", sigma0 = 1e60, h = 1.0 }"));
    assert_rejected(&text(&t), &["yield.sigma0 = 1e60"]);
}

/// Found by the property test below: k₀ = h = 0 (no deviatoric stress at all) made Newton fail
/// on a singular tangent.
#[test]
fn a_body_without_any_shear_strength_is_refused() {
    let mut t = tiny_johnson();
    set(&mut t, "yield.k0", 0.0.into());
    set(&mut t, "yield.h", 0.0.into());
    assert_rejected(&text(&t), &["yield.k0 = 0", "yield.h = 0", "no deviatoric stress"]);
}

/// The range is numerically meaningful: at its corners the solvers stay finite and exact. An
/// elastic cube on rollers pushed by a flat punch is in uniaxial stress, U = F L/(E A) = F/E
/// exactly in P1 (theory §7); measured deviation 2.8e-15 relative, tolerance 1e-12.
#[test]
fn values_at_the_magnitude_bounds_solve_exactly() {
    for (e, f) in [(1e50, 1e-50), (1e-50, 1e50)] {
        for solver in ["uzawa", "newton"] {
            let mut t = example("homogeneous.toml");
            t.remove("yield");
            set(&mut t, "material.E", e.into());
            set(&mut t, "obstacle.F", f.into());
            set(&mut t, "solver", value(&format!("{{ type = \"{solver}\", tol = 1e-10 }}")));
            let (code, err, dir) = run_scene_kept(&text(&t));
            assert_eq!(code, 0, "E = {e}, F = {f}, {solver}: {err}");
            let s: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap()).unwrap();
            let u = s["U"].as_f64().unwrap();
            assert!((u / (f / e) - 1.0).abs() <= 1e-12, "E = {e}, F = {f}, {solver}: U = {u}, F/E = {}", f / e);
        }
    }
}

// ---- 3. output hygiene ----

/// `--out` naming a file fails before the solve: no load step is reported.
#[test]
fn an_out_that_is_a_file_fails_before_any_solve() {
    let dir = scene_dir(&text(&tiny_indentation()));
    std::fs::write(dir.path().join("taken"), "mine").unwrap();
    let (code, _, err) = saddle(dir.path(), &["run", "scene.toml", "--out", "taken"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--out taken") && err.contains("not a folder"), "{err}");
    assert!(!err.lines().any(|l| l.trim_start().starts_with("step ")), "a step was solved first: {err}");
    assert_eq!(std::fs::read_to_string(dir.path().join("taken")).unwrap(), "mine");
}

/// A 9-step path, then a 3-step one, then a plain run into one folder: each leaves exactly its
/// own files (and the manifest), the series lists its own steps, and a file saddle did not write
/// is kept.
#[test]
fn rerunning_into_the_same_out_leaves_exactly_the_new_runs_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let run = |t: &toml::Table| {
        std::fs::write(dir.path().join("scene.toml"), text(t)).unwrap();
        let (code, stdout, err) = saddle(dir.path(), &["run", "scene.toml", "--quiet", "--out", "out"]);
        assert_eq!(code, 0, "{err}");
        stdout
    };
    let manifest = || -> Vec<String> {
        let mut m: Vec<String> =
            std::fs::read_to_string(out.join(".saddle-files")).unwrap().lines().map(String::from).collect();
        m.sort();
        m
    };
    let nine = tiny_indentation();
    run(&nine);
    assert!(out.join("solution_0008.vtu").exists());
    std::fs::write(out.join("notes.txt"), "kept").unwrap();
    let mut three = tiny_indentation();
    set(&mut three, "load_path.substeps", toml::Value::Integer(1));
    run(&three);
    let mut expected: Vec<String> = (0..3).map(|k| format!("solution_{k:04}.vtu")).collect();
    expected.extend(["load_path.csv", "solution.pvd", "solution.vtu", "summary.json"].map(String::from));
    #[cfg(feature = "report")]
    expected.extend(["load_path.png", "load_path.svg"].map(String::from));
    expected.sort();
    assert_eq!(manifest(), expected);
    let mut on_disk: Vec<String> =
        files(&out).into_iter().filter(|f| f != ".saddle-files" && f != "notes.txt").collect();
    on_disk.sort();
    assert_eq!(on_disk, expected, "stale files of the 9-step path");
    let pvd = std::fs::read_to_string(out.join("solution.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 3, "{pvd}");
    assert_eq!(csv_rows(&std::fs::read_to_string(out.join("load_path.csv")).unwrap()).len(), 3);
    run(&tiny_johnson());
    assert_eq!(files(&out), [".saddle-files", "notes.txt", "solution.vtu", "summary.json"]);
    assert_eq!(manifest(), ["solution.vtu", "summary.json"]);
    assert_eq!(std::fs::read_to_string(out.join("notes.txt")).unwrap(), "kept");
}

/// The `wrote` line names only files that exist: a one-step path and a one-point sweep draw no
/// plot (fewer than two points) and do not claim one.
#[test]
fn nothing_is_claimed_that_was_not_written() {
    let mut t = tiny_indentation();
    set(&mut t, "load_path", value("{ factors = [1.0] }"));
    let dir = scene_dir(&text(&t));
    let (code, stdout, err) = saddle(dir.path(), &["run", "scene.toml", "--quiet", "--out", "out"]);
    assert_eq!(code, 0, "{err}");
    let wrote = stdout.lines().find(|l| l.contains("wrote")).expect("a wrote line");
    assert!(!wrote.contains("load_path.png") && !dir.path().join("out/load_path.png").exists(), "{wrote}");
    for name in ["summary.json", "solution.vtu", "solution_0000.vtu", "load_path.csv", "solution.pvd"] {
        assert!(wrote.contains(name) && dir.path().join("out").join(name).exists(), "{name}: {wrote}");
    }
    let dir = scene_dir(&text(&tiny_johnson()));
    let (code, stdout, err) = saddle(dir.path(), &["sweep", "scene.toml", "--out", "out", "--factors", "1"]);
    assert_eq!(code, 0, "{err}");
    let wrote = stdout.lines().find(|l| l.contains("wrote")).expect("a wrote line");
    assert!(wrote.ends_with("sweep.csv, sweep.md"), "{wrote}");
    assert_eq!(files(&dir.path().join("out")), [".saddle-files", "sweep.csv", "sweep.md"]);
}

#[test]
fn unknown_plot_quantities_are_errors_listing_the_known_ones() {
    let mut t = tiny_indentation();
    set(&mut t, "load_path.plot", value("[\"imprint\", \"bogus_quantity\"]"));
    let dir = scene_dir(&text(&t));
    let (code, _, err) = saddle(dir.path(), &["run", "scene.toml", "--out", "out"]);
    assert_eq!(code, 1, "{err}");
    for piece in ["load_path.plot[1] = \"bogus_quantity\"", "known: U, ", "imprint", "factor"] {
        assert!(err.contains(piece), "{piece}: {err}");
    }
    assert!(!err.lines().any(|l| l.trim_start().starts_with("step ")), "decided after solving: {err}");
    assert!(!dir.path().join("out").exists());
}

#[test]
fn unknown_sweep_axes_are_errors_listing_the_known_ones() {
    let dir = scene_dir(&text(&tiny_johnson()));
    for axis in ["--x", "--y"] {
        let (code, _, err) =
            saddle(dir.path(), &["sweep", "scene.toml", "--out", "out", "--factors", "1,2", axis, "bogus"]);
        assert_eq!(code, 1, "{err}");
        assert!(
            err.contains(&format!("{axis} = \"bogus\"")) && err.contains("known: U, ") && err.contains("force"),
            "{err}"
        );
        assert!(!err.contains("factor 1:"), "a point was solved first: {err}");
        assert!(!dir.path().join("out").exists());
    }
}

#[test]
fn a_huge_sweep_factor_is_refused_in_short() {
    let dir = scene_dir(&text(&tiny_johnson()));
    let (code, _, err) = saddle(dir.path(), &["sweep", "scene.toml", "--out", "out", "--factors", "1,1e308"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--factors: 1e308 exceeds 1e50"), "{err}");
    assert!(!err.contains("0000000000"), "a factor printed digit by digit: {err}");
    assert!(!dir.path().join("out").exists());
}

/// `--factors 1,2,2`: the indicator skips the repeated factor (no 0/0), the interval 1 → 2 as in
/// `--factors 1,2`.
#[test]
fn a_repeated_sweep_factor_gives_the_indicator_of_the_last_interval() {
    let indicator = |factors: &str| -> f64 {
        let dir = scene_dir(&text(&tiny_johnson()));
        let (code, _, err) = saddle(dir.path(), &["sweep", "scene.toml", "--out", "out", "--factors", factors]);
        assert_eq!(code, 0, "{err}");
        let md = std::fs::read_to_string(dir.path().join("out/sweep.md")).unwrap();
        assert!(!md.contains("NaN"), "{md}");
        md.split("over the last interval: ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap()
    };
    let (k, k_repeated) = (indicator("1,2"), indicator("1,2,2"));
    assert!(k.is_finite() && k == k_repeated, "{k} vs {k_repeated}");
}

// ---- 4. geometry that cannot work ----

/// Two punches on the same zone push its nodes in one direction: refused naming both, before any
/// solver, without advice to use a solver (none can solve it).
#[test]
fn overlapping_obstacle_zones_are_refused_before_any_solver() {
    let mut t = tiny_johnson();
    let punch = t.remove("obstacle").unwrap();
    let named = |name: &str| {
        let mut p = punch.as_table().unwrap().clone();
        p.insert("name".into(), name.into());
        toml::Value::Table(p)
    };
    t.insert("obstacle".into(), toml::Value::Array(vec![named("a"), named("b")]));
    for solver in ["uzawa", "newton"] {
        set(&mut t, "solver", value(&format!("{{ type = \"{solver}\" }}")));
        let (code, err, wrote) = run_scene(&text(&t));
        assert_eq!(code, 1, "{err}");
        assert!(!wrote);
        for piece in ["obstacle[1]: pushes", "obstacle[0] (\"a\")", "same direction", "node"] {
            assert!(err.contains(piece), "{piece}: {err}");
        }
        assert!(!err.contains("handles them") && !err.contains("Delassus"), "{err}");
    }
}

#[test]
fn a_sphere_centred_in_the_body_is_refused() {
    let sphere = value(
        "{ type = \"rigid_sphere\", center = [0.0, 0.0, 0.5], R = 0.1, direction = [0.0, 0.0, 1.0], F = 0.3, \
         zone = { all = [ { group = \"zmin\" }, { disc = { center = [0.0, 0.0], radius = 0.5 } } ] } }",
    );
    assert_rejected(&edited("obstacle", sphere), &["obstacle.center = [0, 0, 0.5]", "lies in the body", "element"]);
}

#[test]
fn an_align_coordinate_outside_the_box_is_refused() {
    assert_rejected(
        &edited("mesh.align", value("[[-0.75, 5.0], [-0.75, 0.75], []]")),
        &["mesh.align[0] = [-0.75, 5.0]", "5 lies outside", "[-1, 1]"],
    );
}

#[test]
fn empty_components_are_refused() {
    let mut t = tiny_johnson();
    let d = t.get_mut("dirichlet").unwrap().as_array_mut().unwrap();
    d[0].as_table_mut().unwrap().insert("components".into(), toml::Value::Array(vec![]));
    assert_rejected(&text(&t), &["dirichlet[0].components = []", "fixes no component"]);
}

#[test]
fn a_component_listed_twice_is_refused() {
    let mut t = tiny_johnson();
    let d = t.get_mut("dirichlet").unwrap().as_array_mut().unwrap();
    d[0].as_table_mut().unwrap().insert("components".into(), value(r#"["z", "x", "z"]"#));
    assert_rejected(&text(&t), &[r#"dirichlet[0].components[2] = ["z", "x", "z"]"#, "lists a component twice"]);
}

/// Found by the property test below: `all = []` selected the whole boundary as the contact zone.
#[test]
fn an_empty_region_list_is_refused() {
    assert_rejected(&edited("obstacle.zone", value("{ all = [] }")), &["obstacle.zone.all = []", "empty list"]);
    let mut t = tiny_johnson();
    let d = t.get_mut("dirichlet").unwrap().as_array_mut().unwrap();
    d[0].as_table_mut().unwrap().insert("on".into(), value("{ any = [] }"));
    assert_rejected(&text(&t), &["dirichlet[0].on.any = []"]);
}

/// The default scene clamps its top face: a traction there would do nothing.
#[test]
fn a_load_on_clamped_facets_is_refused() {
    let mut t = tiny_johnson();
    t.insert("load".into(), value("[ { type = \"traction\", on = { group = \"zmax\" }, t = [0.0, 0.0, 0.01] } ]"));
    assert_rejected(&text(&t), &["load[0].on", "t = [0.0, 0.0, 0.01]", "would do nothing"]);
    // on the free bottom it acts
    set(&mut t, "load", value("[ { type = \"traction\", on = { group = \"zmin\" }, t = [0.0, 0.0, 0.01] } ]"));
    let (code, err, _) = run_scene(&text(&t));
    assert_eq!(code, 0, "{err}");
}

// ---- 5. load paths: linear cost, bounded output ----

/// 301 steps: every step in summary.json and load_path.csv, at most 100 (+ the last) step VTU
/// files (every 4th here), and the series lists exactly the files written.
#[test]
fn a_long_path_writes_a_bounded_number_of_step_files() {
    let mut t = tiny_indentation();
    set(&mut t, "load_path.substeps", toml::Value::Integer(150));
    let (code, err, dir) = run_scene_kept(&text(&t));
    assert_eq!(code, 0, "{err}");
    let out = dir.path().join("out");
    let vtus: Vec<String> = files(&out).into_iter().filter(|f| f.starts_with("solution_")).collect();
    let bound = saddle::app::path::MAX_STEP_FILES;
    assert!(vtus.len() <= bound + 1 && vtus.len() >= bound / 2, "{} step files", vtus.len());
    assert!(vtus.contains(&"solution_0300.vtu".to_string()), "the last step has its file");
    let pvd = std::fs::read_to_string(out.join("solution.pvd")).unwrap();
    let listed: Vec<&str> =
        pvd.lines().filter_map(|l| l.split("file=\"").nth(1)).map(|f| f.trim_end_matches("\"/>")).collect();
    assert_eq!(listed, vtus);
    assert!(pvd.ends_with("  </Collection>\n</VTKFile>\n"));
    assert_eq!(csv_rows(&std::fs::read_to_string(out.join("load_path.csv")).unwrap()).len(), 301);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let steps = s["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 301);
    let with_file = steps.iter().filter(|st| st["file"].is_string()).count();
    assert_eq!(with_file, vtus.len());
}

#[test]
fn a_path_of_too_many_steps_is_refused() {
    let mut t = tiny_indentation();
    set(&mut t, "load_path.substeps", toml::Value::Integer(1_000_000_000_000));
    assert_rejected(&text(&t), &["load_path.substeps = 1000000000000", "100000"]);
}

// ---- 6. exit codes ----

#[test]
fn usage_errors_exit_1_and_2_means_not_converged_with_outputs() {
    let dir = scene_dir(&text(&tiny_johnson()));
    let (code, _, err) = saddle(dir.path(), &["run", "scene.toml", "--out", ""]);
    assert_eq!(code, 1, "--out \"\": {err}");
    let (code, _, err) = saddle(dir.path(), &["sweep", "scene.toml", "--out", "out", "--factors", "-1,1"]);
    assert_eq!(code, 1, "{err}");
    // the factor and the scaled value, against the scene's own (one rule for sweeps and paths)
    assert!(err.contains("--factors[0] = -1") && err.contains("obstacle.F = 0.3 × -1 = -0.3"), "{err}");
    let (code, _, err) = saddle(dir.path(), &["run", "scene.toml", "--bogus"]);
    assert_eq!(code, 1, "{err}");
    let (code, _, err) = saddle(dir.path(), &[]);
    assert_eq!(code, 1, "{err}");
    let (code, stdout, _) = saddle(dir.path(), &["--help"]);
    assert_eq!(code, 0, "{stdout}");
    assert!(!dir.path().join("out").exists());
    // 2: stopped without converging, outputs written
    let mut t = small_johnson();
    set(&mut t, "solver", value("{ type = \"uzawa\", max_iter = 1 }"));
    let (code, err, dir) = run_scene_kept(&text(&t));
    assert_eq!(code, 2, "{err}");
    assert!(dir.path().join("out/summary.json").exists() && dir.path().join("out/solution.vtu").exists());
}

// ---- the property: mutated example scenes ----

/// The examples on tiny meshes (seconds in all), as tables to mutate; a path of three steps.
fn base_scenes() -> Vec<(&'static str, toml::Table)> {
    let tiny = |name: &'static str, cells: [i64; 3]| {
        let mut t = example(name);
        set(&mut t, "mesh.cells", toml::Value::try_from(cells).unwrap());
        (name, t)
    };
    let mut scenes = vec![
        tiny("johnson.toml", [4, 4, 2]),
        tiny("hertz.toml", [3, 3, 3]),
        tiny("homogeneous.toml", [2, 2, 2]),
        tiny("strip_punch.toml", [8, 1, 4]),
        tiny("circular_punch.toml", [4, 4, 3]),
        tiny("indentation.toml", [4, 4, 2]),
        tiny("tensile_bar.toml", [2, 1, 1]),
    ];
    set(&mut scenes[5].1, "load_path.substeps", toml::Value::Integer(1));
    scenes
}

/// Every path of a table (tables, arrays and leaves), with its value.
fn paths(v: &toml::Value, path: String, out: &mut Vec<String>) {
    if !path.is_empty() {
        out.push(path.clone());
    }
    match v {
        toml::Value::Table(t) => {
            t.iter().for_each(|(k, x)| paths(x, if path.is_empty() { k.clone() } else { format!("{path}.{k}") }, out))
        }
        toml::Value::Array(a) => a.iter().enumerate().for_each(|(i, x)| paths(x, format!("{path}[{i}]"), out)),
        _ => {}
    }
}

/// The parent of a path and the last step into it: (`mesh`, key `cells`), (`mesh.cells`, index 0).
fn split(path: &str) -> (String, Result<String, usize>) {
    if path.ends_with(']') {
        let i = path.rfind('[').unwrap();
        (path[..i].to_string(), Err(path[i + 1..path.len() - 1].parse().unwrap()))
    } else {
        match path.rfind('.') {
            Some(i) if path[i..].find('[').is_none() => (path[..i].to_string(), Ok(path[i + 1..].to_string())),
            _ => (String::new(), Ok(path.to_string())),
        }
    }
}

fn at<'a>(root: &'a mut toml::Value, path: &str) -> &'a mut toml::Value {
    if path.is_empty() {
        return root;
    }
    let (parent, last) = split(path);
    let p = at(root, &parent);
    match last {
        Ok(k) => p.as_table_mut().unwrap().get_mut(&k).unwrap(),
        Err(i) => &mut p.as_array_mut().unwrap()[i],
    }
}

/// A mutation of one path: another type, another length, a meaningless magnitude, or removed.
#[derive(Clone, Debug)]
enum Mutation {
    Type(u8),
    Length(bool),
    Magnitude(u8),
    Remove,
}

fn mutations() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (0u8..5).prop_map(Mutation::Type),
        any::<bool>().prop_map(Mutation::Length),
        (0u8..8).prop_map(Mutation::Magnitude),
        Just(Mutation::Remove),
    ]
}

/// `root` with `mutation` applied at `path` (a length or magnitude mutation of a value that has
/// none changes its type instead).
fn mutate(root: &toml::Table, path: &str, mutation: &Mutation) -> toml::Table {
    let mut root = toml::Value::Table(root.clone());
    let retype = |k: u8| -> toml::Value {
        match k {
            0 => "x".into(),
            1 => true.into(),
            2 => toml::Value::Array(vec![]),
            3 => toml::Value::Table(toml::Table::new()),
            _ => toml::Value::Array(vec![1.5.into(), "x".into()]),
        }
    };
    match mutation {
        Mutation::Remove => {
            let (parent, last) = split(path);
            match last {
                Ok(k) => drop(at(&mut root, &parent).as_table_mut().unwrap().remove(&k)),
                Err(i) => drop(at(&mut root, &parent).as_array_mut().unwrap().remove(i)),
            }
        }
        Mutation::Type(k) => *at(&mut root, path) = retype(*k),
        Mutation::Length(longer) => {
            let v = at(&mut root, path);
            match v.as_array_mut() {
                Some(a) if *longer => a.push(a.last().cloned().unwrap_or(1.0.into())),
                Some(a) => drop(a.pop()),
                None => *v = retype(4),
            }
        }
        Mutation::Magnitude(k) => {
            let v = at(&mut root, path);
            let floats = [1e300, -1e300, 0.0, -1.0, 1e-300, 1e51, -1e-51, 1e308];
            let ints = [0, -1, i64::MAX, 1 << 40, -(1 << 40), 3, 1_000_000_000, i64::MIN];
            *v = match v {
                toml::Value::Integer(_) => ints[*k as usize].into(),
                toml::Value::Float(_) => floats[*k as usize].into(),
                _ => retype(*k % 5),
            };
        }
    }
    match root {
        toml::Value::Table(t) => t,
        _ => unreachable!(),
    }
}

/// `saddle run --quiet` on `t`, killed after `limit`: (exit status, stderr, whether `out/` exists).
fn run_limited(t: &toml::Table, limit: Duration) -> Result<(i32, String, bool), String> {
    let dir = scene_dir(&text(t));
    let mut child = Command::new(env!("CARGO_BIN_EXE_saddle"))
        .current_dir(dir.path())
        .args(["run", "scene.toml", "--quiet", "--out", "out"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let started = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if started.elapsed() > limit {
            child.kill().unwrap();
            return Err(format!("still running after {limit:?}"));
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let mut err = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut err).unwrap();
    let code = status.code().ok_or_else(|| format!("killed by a signal: {status:?}"))?;
    Ok((code, err, dir.path().join("out").exists()))
}

/// True when `err` names a path of one of `scenes` as an error does: `path = value` or `path:`
/// (`mesh.cells[0] = 0`, `obstacle.zone: …`, `material: missing`).
fn names_a_scene_path(err: &str, scenes: &[&toml::Table]) -> bool {
    let mut all = vec![];
    for t in scenes {
        paths(&toml::Value::Table((*t).clone()), String::new(), &mut all);
    }
    all.iter().any(|p| err.contains(&format!("{p} = ")) || err.contains(&format!("{p}: ")))
}

/// Mutated example scenes (a type, a length, a magnitude or a removal at one path, drawn over
/// every path of every example on a tiny mesh) never panic and exit 0, 1 or 2 (README); an
/// exit 1 names the mutated field or a table holding it, and writes nothing. 160 cases from a
/// fixed seed (about 20 s); `PROPTEST_CASES`, `PROPTEST_RNG_SEED` explore more.
#[test]
fn mutated_example_scenes_fail_cleanly() {
    let scenes = base_scenes();
    for (name, t) in &scenes {
        let (code, err, _) = run_limited(t, Duration::from_secs(60)).unwrap();
        assert!(code == 0 || code == 2, "base scene {name}: {err}");
    }
    let mut config = Config { failure_persistence: None, max_shrink_iters: 20, ..Config::default() };
    if std::env::var_os("PROPTEST_CASES").is_none() {
        config.cases = 160;
    }
    if config.rng_seed == RngSeed::Random {
        config.rng_seed = RngSeed::Fixed(0x0031_0031);
    }
    let mut runner = TestRunner::new(config);
    let strategy = (0..scenes.len(), any::<prop::sample::Index>(), mutations());
    let counts = std::cell::RefCell::new([0usize; 3]);
    let result = runner.run(&strategy, |(s, index, mutation)| {
        let (name, base) = &scenes[s];
        let mut all = vec![];
        paths(&toml::Value::Table(base.clone()), String::new(), &mut all);
        let path = index.get(&all).clone();
        let t = mutate(base, &path, &mutation);
        let case = format!("{name}: {path} {mutation:?}");
        let (code, err, wrote) =
            run_limited(&t, Duration::from_secs(120)).map_err(|e| TestCaseError::fail(format!("{case}: {e}")))?;
        prop_assert!(!err.contains("panicked"), "{case}: {err}");
        prop_assert!((0..=2).contains(&code), "{case}: exit {code}: {err}");
        counts.borrow_mut()[code as usize] += 1;
        if code == 1 {
            prop_assert!(!wrote, "{case}: exit 1 wrote output: {err}");
            prop_assert!(names_a_scene_path(&err, &[base, &t]), "{case}: the error names no field: {err}");
        }
        Ok(())
    });
    println!("exit 0 / 1 / 2: {:?}", counts.borrow());
    if let Err(e) = result {
        panic!("{e}");
    }
}

/// Every number of every example scene (on its tiny mesh) set to NaN, and to +∞, is refused
/// before any solve — exit 1, nothing written — by an error naming the number's path and its
/// value (`material.E = NaN`, `obstacle.zone.all[1].disc.radius = inf`). The property test above
/// draws finite magnitudes only; TOML's `nan` and `inf` are hostile input of their own.
#[test]
fn every_number_set_to_nan_or_infinity_is_refused_naming_it() {
    let mut checked = 0;
    for (name, base) in base_scenes() {
        let mut all = vec![];
        paths(&toml::Value::Table(base.clone()), String::new(), &mut all);
        for path in all {
            let mut root = toml::Value::Table(base.clone());
            if !at(&mut root, &path).is_float() {
                continue;
            }
            for (v, shown) in [(f64::NAN, "NaN"), (f64::INFINITY, "inf")] {
                *at(&mut root, &path) = v.into();
                let (code, err, wrote) = run_limited(root.as_table().unwrap(), Duration::from_secs(60)).unwrap();
                let case = format!("{name}: {path} = {shown}: exit {code}: {err}");
                assert!(code == 1 && !wrote && !err.contains("panicked"), "{case}");
                assert!(err.contains(&format!("{path} = {shown}")), "{case}");
                checked += 1;
            }
        }
    }
    println!("{checked} numbers refused");
    assert!(checked > 0, "the examples hold numbers");
}

// ---- issue 28: supports ----

/// The tensile bar with `edit` applied to its list of `[[dirichlet]]` entries.
fn tensile_with(edit: impl FnOnce(&mut Vec<toml::Value>)) -> String {
    let mut t = example("tensile_bar.toml");
    set(&mut t, "mesh.cells", toml::Value::try_from([2, 1, 1]).unwrap());
    edit(t.get_mut("dirichlet").and_then(|d| d.as_array_mut()).unwrap());
    text(&t)
}

#[test]
fn bad_supports_are_errors_naming_the_field_and_the_value() {
    let grip = |v: &str| tensile_with(|d| drop(d[3].as_table_mut().unwrap().insert("value".into(), value(v))));
    assert_rejected(&grip("[0.1, 0.2]"), &["dirichlet[3].value = [0.1, 0.2]", "has 2 entries"]);
    assert_rejected(&grip("[0.1, 0.2, 0.0]"), &["dirichlet[3].value[1] = 0.2", "does not constrain", "\"y\""]);
    assert_rejected(&grip("[\"a\"]"), &["dirichlet[3].value", "\"a\""]);
    let named = tensile_with(|d| drop(d[3].as_table_mut().unwrap().insert("name".into(), value("\" \""))));
    assert_rejected(&named, &["dirichlet[3].name = \" \"", "must not be empty"]);
    // without the roller on y = 0 the bar may slide along y: the existing check names it
    assert_rejected(&tensile_with(|d| drop(d.remove(1))), &["dirichlet", "rigid-body motion free", "translation"]);
    // a reaction that is not reported cannot be a plot axis
    let mut t: toml::Table = toml::from_str(&tensile_with(|_| ())).unwrap();
    set(&mut t, "load_path.plot", value("[\"factor\", \"clamp.Fx\"]"));
    assert_rejected(&text(&t), &["load_path.plot", "clamp.Fx", "grip.Fx"]);
}

#[test]
fn bad_inclined_supports_are_errors_naming_the_field_and_the_value() {
    // the roller on z = 0 made an inclined support with `normal = n` and `extra` keys
    let inclined = |n: &str, extra: &[(&str, &str)]| {
        tensile_with(|d| {
            let e = d[2].as_table_mut().unwrap();
            e.remove("components");
            e.insert("normal".into(), value(n));
            for (k, v) in extra {
                e.insert((*k).into(), value(v));
            }
        })
    };
    assert_rejected(&inclined("[0.0, 0.0, 0.0]", &[]), &["dirichlet[2].normal = [0.0, 0.0, 0.0]", "is zero"]);
    assert_rejected(&inclined("[0.0, 1.0]", &[]), &["dirichlet[2].normal = [0.0, 1.0]", "has 2 entries"]);
    assert_rejected(&inclined("[0.0, 1.0, 0.0, 1.0]", &[]), &["dirichlet[2].normal", "has 4 entries"]);
    assert_rejected(&inclined("[0.0, nan, 1.0]", &[]), &["dirichlet[2].normal[1]", "NaN"]);
    assert_rejected(&inclined("[0.0, 1.0, inf]", &[]), &["dirichlet[2].normal[2]", "inf"]);
    assert_rejected(
        &inclined("[0.0, 0.0, 1.0]", &[("components", "[\"z\"]")]),
        &["dirichlet[2].components = [Z]", "cannot go with `normal`"],
    );
    assert_rejected(
        &inclined("[0.0, 0.0, 1.0]", &[("value", "[0.1]")]),
        &["dirichlet[2].value = [0.1]", "cannot go with `normal`"],
    );
    // every roller made a support along the one inclined normal (1, 0, 1): the bar may slide
    // along y and in the plane, and the check along the held directions names it
    let parallel = tensile_with(|d| {
        for e in d.iter_mut().take(3) {
            let e = e.as_table_mut().unwrap();
            e.remove("components");
            e.insert("normal".into(), value("[1.0, 0.0, 1.0]"));
        }
    });
    assert_rejected(&parallel, &["dirichlet", "rigid-body motion free"]);
    // the roller on x = 0 of homogeneous compression inclined: its nodes on z = 0 carry the
    // punch's contact rows, which are written on the axes' dofs
    let mut t = example("homogeneous.toml");
    let d = t.get_mut("dirichlet").and_then(|d| d.as_array_mut()).unwrap()[0].as_table_mut().unwrap();
    d.remove("components");
    d.insert("normal".into(), value("[1.0, 0.0, 0.2]"));
    assert_rejected(&text(&t), &["dirichlet[0].normal", "contact row", "inclined support"]);
}
