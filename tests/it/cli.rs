//! The `multibody` tool, run as a user runs it: from a temporary folder outside the repository,
//! with no cargo or rustc on `PATH`, on built-in models and on a model the project has never
//! seen; every model evaluated in-process.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common::{multibody, ok};

/// A folder outside the repository holding `my_model.ron`: the downstream example's gantry
/// crane under another name, a model the project's tool has never seen.
fn user_model() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let crane = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/downstream/models/gantry_crane.ron")).unwrap();
    let path = dir.path().join("my_model.ron");
    std::fs::write(&path, crane.replace("name: \"gantry_crane\"", "name: \"my_model\"")).unwrap();
    (dir, path)
}

#[test]
fn compare_prints_the_four_formulations_of_a_model_never_seen() {
    let (dir, _) = user_model();
    let table = ok(&multibody(dir.path(), &["compare", "my_model.ron", "--repeats", "1", "--json", "out.json"]));
    for row in ["| lagrange | 6 | 3 |", "| maggi | 6 | 3 |", "| kane | 6 | 3 |", "| reduced_volterra | 5 | 2 |"] {
        assert!(table.contains(row), "{row} in\n{table}");
    }
    // A user's model gets tight settings, and the table says which.
    assert!(table.starts_with("my_model: DOP853, rtol 1e-10, atol 1e-10"), "{table}");
    let records: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("out.json")).unwrap()).unwrap();
    let records = records.as_array().unwrap();
    assert_eq!(records.len(), 4);
    assert!(records.iter().all(|r| r["scene"] == "my_model" && r["momenta"][0]["coordinate"] == "x"));
    assert!(records[3]["momentum_error_norm"].as_f64().unwrap() < 1e-12);
    // Parameters and initial values from the command line: a heavier trolley is another run.
    let heavy = ok(&multibody(dir.path(), &["compare", "my_model.ron", "--repeats", "1", "--formulations", "kane", "--param", "mt=50", "--json", "-"]));
    let heavy: serde_json::Value = serde_json::from_str(&heavy).unwrap();
    assert_ne!(heavy[0]["energy_error_norm"], records[2]["energy_error_norm"]);
    let bad = multibody(dir.path(), &["compare", "my_model.ron", "--param", "mass=1"]);
    assert!(
        !bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("no parameter `mass` (known: mt, mc, L"),
        "{}",
        String::from_utf8_lossy(&bad.stderr)
    );
}

#[test]
fn the_paper_s_scenes_use_the_paper_s_settings_and_the_same_numbers_as_compiled_code() {
    let dir = tempfile::tempdir().unwrap();
    let out = ok(&multibody(dir.path(), &["compare", "satellite_boom", "--repeats", "1", "--json", "-"]));
    let records: serde_json::Value = serde_json::from_str(&out).unwrap();
    // The paper's state counts for scene 3, the work integral included: 15, 15, 15, 12.
    let states: Vec<u64> = records.as_array().unwrap().iter().map(|r| r["states"].as_u64().unwrap()).collect();
    assert_eq!(states, vec![15, 15, 15, 12]);
    // The compiled module through the runtime, at the same settings: the same steps, calls and
    // errors (in-process evaluation gives the compiled module's numbers).
    let compiled = generated::find("satellite_boom").unwrap();
    let runs = runtime::compare::compare(&compiled, &runtime::compare::Options { repeats: 1, ..runtime::compare::Options::paper(&compiled) }).unwrap();
    for (r, c) in records.as_array().unwrap().iter().zip(&runs) {
        assert_eq!(r["method"], c.record.method.as_str());
        assert_eq!(r["steps"].as_u64().unwrap() as usize, c.record.steps);
        assert_eq!(r["rhs_calls"].as_u64().unwrap() as usize, c.record.rhs_calls);
        let (a, b) = (r["energy_error_norm"].as_f64().unwrap(), c.record.energy_error_norm);
        assert!((a - b).abs() <= 1e-9 * b.abs(), "{}: {a} against {b}", c.record.method);
    }
    // `--paper` anywhere: the crane at the paper's settings.
    let (dir, _) = user_model();
    let table = ok(&multibody(dir.path(), &["compare", "my_model.ron", "--repeats", "1", "--paper", "--formulations", "kane"]));
    assert!(table.starts_with("my_model: DOPRI5, rtol 1e-3, atol 1e-6"), "{table}");
}

/// Kane's and the reduced form's speeds are named in the state as the model writes its
/// quasi-velocities (they were `u1, u2, ...`, the derivation's own symbols): the trajectory's
/// columns, and `linearize`'s note on the entry moving fastest.
#[test]
fn the_state_names_the_quasi_velocities_as_the_model_writes_them() {
    let dir = tempfile::tempdir().unwrap();
    let header = |file: &str| std::fs::read_to_string(dir.path().join(file)).unwrap().lines().next().unwrap().to_string();
    let states = |file: &str| header(file).split(',').filter_map(|c| c.strip_prefix("state:").map(str::to_string)).collect::<Vec<_>>();
    ok(&multibody(dir.path(), &["simulate", "three_body", "--formulation", "kane", "--t-end", "0.1", "--dt-out", "0.05", "--out", "k"]));
    let speeds = ["omega_x(middle)", "omega_y(middle)", "omega_z(middle)", "gamma1'", "gamma2'", "X'", "Y'", "Z'"];
    assert_eq!(states("k/three_body_kane.csv")[8..], speeds.map(String::from), "{}", header("k/three_body_kane.csv"));
    ok(&multibody(dir.path(), &["simulate", "three_body", "--formulation", "reduced", "--t-end", "0.1", "--dt-out", "0.05", "--out", "r"]));
    assert_eq!(states("r/three_body_reduced_volterra.csv")[8..], speeds[..5].iter().map(|s| s.to_string()).collect::<Vec<_>>());
    // Lagrange's speeds are the rates.
    ok(&multibody(dir.path(), &["simulate", "cart_pendulum", "--formulation", "lagrange", "--t-end", "0.1", "--dt-out", "0.05", "--out", "l"]));
    assert_eq!(states("l/cart_pendulum_lagrange.csv")[3..6], ["theta1'", "theta2'", "x'"].map(String::from));
    // A URDF robot's: its base's angular velocity and its joints' rates.
    let tree = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/urdf/tree.urdf");
    ok(&multibody(dir.path(), &["simulate", tree, "--base", "floating", "--formulation", "kane", "--t-end", "0.1", "--dt-out", "0.05", "--out", "t"]));
    let names = states("t/tree_kane.csv");
    assert!(names.iter().any(|n| n == "omega_z(base)") && names.iter().any(|n| n == "left_elbow'") && !names.iter().any(|n| n.starts_with('u')), "{names:?}");
    // linearize names the entry moving fastest by the same names (here the fall, in Kane's z').
    let text = ok(&multibody(dir.path(), &["linearize", tree, "--base", "floating", "--formulation", "kane"]));
    assert!(text.contains("not an equilibrium nor a steady motion: base_z'' = -9.81"), "{text}");
    // B's rows by the same names, their colons in one column however long the names run.
    let text = ok(&multibody(dir.path(), &["linearize", tree, "--formulation", "kane", "--input", "damping_waist"]));
    let rows: Vec<&str> = text.lines().skip_while(|l| !l.starts_with("B (")).skip(1).collect();
    assert!(rows.iter().any(|r| r.trim_start().starts_with("right_shoulder':")), "{text}");
    let colons: std::collections::BTreeSet<usize> = rows.iter().map(|r| r.find(": ").unwrap()).collect();
    assert!(rows.len() == 10 && colons.len() == 1, "{text}");
}

#[test]
fn simulate_writes_the_trajectory_and_its_plots() {
    let (dir, _) = user_model();
    let out = ok(&multibody(dir.path(), &["simulate", "my_model.ron", "--out", "run", "--t-end", "4", "--dt-out", "0.5", "--qdot", "x=0.3"]));
    assert!(out.contains("my_model reduced_volterra: 9 outputs from t = 0 to 4"), "{out}");
    let csv = std::fs::read_to_string(dir.path().join("run/my_model_reduced_volterra.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(&header[..7], ["t", "x", "phi", "psi", "x'", "phi'", "psi'"], "{csv}");
    assert!(header.contains(&"energy_error") && header.contains(&"momentum:x") && header.contains(&"constraint_residual"), "{header:?}");
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), 9);
    assert_eq!((rows[0][0], rows[8][0]), (0.0, 4.0));
    assert_eq!(rows[0][4], 0.3, "the given initial rate");
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    // The conserved momentum of the trolley and the energy hold along the written trajectory.
    let g0 = rows[0][col("momentum:x")];
    assert!(g0.abs() > 0.1 && rows.iter().all(|r| (r[col("momentum:x")] - g0).abs() <= 1e-12 * g0.abs()), "{csv}");
    assert!(rows.iter().all(|r| r[col("energy_error")].abs() < 1e-8), "{csv}");
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("run/my_model_reduced_volterra.json")).unwrap()).unwrap();
    assert_eq!(json["settings"], "DOP853, rtol 1e-10, atol 1e-10, h_max 0.4");
    assert_eq!(json["rows"].as_array().unwrap().len(), 9);
    for plot in ["my_model_reduced_volterra_coordinates.svg", "my_model_reduced_volterra_invariants.svg"] {
        let svg = std::fs::read_to_string(dir.path().join("run").join(plot)).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("<polyline"), "{plot}");
    }
    // Another formulation, by any of its names.
    ok(&multibody(dir.path(), &["simulate", "my_model.ron", "--formulation", "lagrange", "--out", "run", "--t-end", "1"]));
    assert!(dir.path().join("run/my_model_lagrange.csv").is_file());
}

/// `simulate --animate` writes the page with the run's times and every frame's pose at each
/// (the browser test of the page itself is in `python/tests/test_animate.py`); a directory in
/// its place is never replaced.
#[test]
fn simulate_animates_the_run() {
    let (dir, _) = user_model();
    let out = ok(&multibody(dir.path(), &["simulate", "my_model.ron", "--out", "run", "--t-end", "2", "--dt-out", "0.5", "--animate", "show/motion.html"]));
    assert!(out.contains("show/motion.html"), "{out}");
    let html = std::fs::read_to_string(dir.path().join("show/motion.html")).unwrap();
    let start = html.find(r#"<script type="application/json" id="data">"#).unwrap();
    let json = &html[start..];
    let json = &json[json.find('>').unwrap() + 1..json.find("</script>").unwrap()];
    let data: serde_json::Value = serde_json::from_str(json).unwrap();
    assert_eq!(data["times"], serde_json::json!([0.0, 0.5, 1.0, 1.5, 2.0]));
    assert_eq!(data["poses"].as_array().unwrap().len(), 5);
    assert_eq!(data["poses"][0].as_array().unwrap().len(), data["frames"].as_array().unwrap().len());
    // Self-contained: no address at all, but the XHTML namespace's name, with which three.js
    // makes its canvas (a name, never fetched).
    let addresses = html.replace("http://www.w3.org/1999/xhtml", "");
    assert!(!addresses.contains("http://") && !addresses.contains("https://"), "self-contained");
    std::fs::create_dir(dir.path().join("taken.html")).unwrap();
    let refused = multibody(dir.path(), &["simulate", "my_model.ron", "--out", "run", "--t-end", "1", "--animate", "taken.html"]);
    assert!(!refused.status.success());
    assert!(dir.path().join("taken.html").is_dir());
}

/// `compare --animate`: every formulation's run in one page, the default one as the bodies and
/// the others over it, each at the coordinates its own run gave.
#[test]
fn compare_animates_the_formulations_over_each_other() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["compare", "cart_pendulum", "--t-end", "1", "--dt-out", "0.25", "--rtol", "1e-2", "--atol", "1e-2", "--repeats", "1"];
    let out = multibody(dir.path(), &[&args[..], &["--animate", "all.html", "--json", "runs.json"]].concat());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let html = std::fs::read_to_string(dir.path().join("all.html")).unwrap();
    let start = html.find(r#"<script type="application/json" id="data">"#).unwrap();
    let json = &html[start..];
    let data: serde_json::Value = serde_json::from_str(&json[json.find('>').unwrap() + 1..json.find("</script>").unwrap()]).unwrap();
    assert_eq!(data["formulation"], "reduced_volterra");
    let overlays: Vec<&str> = data["overlays"].as_array().unwrap().iter().map(|o| o["formulation"].as_str().unwrap()).collect();
    assert_eq!(overlays, ["lagrange", "maggi", "kane"]);
    // Each overlay's cart (frame 1's origin, x) at each time is its own run's x.
    let runs: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.path().join("runs.json")).unwrap()).unwrap();
    assert_eq!(runs.as_array().unwrap().len(), 4);
    for o in data["overlays"].as_array().unwrap() {
        assert_eq!(o["times"], data["times"]);
        assert_eq!(o["poses"].as_array().unwrap().len(), 5);
    }
    // Loose tolerances: the runs part, so the drawings differ somewhere.
    let carts = |poses: &serde_json::Value| poses.as_array().unwrap().iter().map(|p| p[1][0].as_f64().unwrap()).collect::<Vec<_>>();
    let base = carts(&data["poses"]);
    assert!(data["overlays"].as_array().unwrap().iter().any(|o| carts(&o["poses"]) != base), "the overlays are the same run");
    // A page over what is not a regular file is refused before anything runs.
    std::fs::create_dir(dir.path().join("taken.html")).unwrap();
    let refused = multibody(dir.path(), &[&args[..], &["--animate", "taken.html"]].concat());
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("not a regular file"), "{}", String::from_utf8_lossy(&refused.stderr));
    assert!(dir.path().join("taken.html").is_dir());
}

#[test]
fn sweep_and_linearize_run_on_a_model_file() {
    let (dir, _) = user_model();
    ok(&multibody(dir.path(), &["sweep", "my_model.ron", "--quick", "--repeats", "1", "--formulations", "kane,reduced", "--out", "results"]));
    let csv = std::fs::read_to_string(dir.path().join("results/my_model_work_precision.csv")).unwrap();
    // 2 formulations x 9 settings.
    assert_eq!(csv.lines().count(), 1 + 18, "{csv}");
    assert!(csv.lines().skip(1).all(|l| l.starts_with("my_model,kane,") || l.starts_with("my_model,reduced_volterra,")), "{csv}");
    // Hanging at rest nothing grows or decays (the pendulum mode is an imaginary pair).
    let rest = ["--q", "phi=0", "--q", "psi=0", "--qdot", "x=0", "--qdot", "phi=0", "--qdot", "psi=0"];
    let text = ok(&multibody(dir.path(), &[&["linearize", "my_model.ron"][..], &rest, &["--input", "g"]].concat()));
    let eigen: Vec<(f64, f64)> = text
        .lines()
        .filter_map(|l| l.trim().strip_suffix('i'))
        .map(|l| {
            let mut it = l.split_whitespace().map(|x| x.parse::<f64>().unwrap());
            (it.next().unwrap(), it.next().unwrap())
        })
        .collect();
    assert!(!eigen.is_empty() && eigen.iter().all(|(re, _)| re.abs() < 1e-4), "{text}");
    assert!(eigen.iter().any(|(_, im)| *im > 0.1), "{text}");
    // In-process, the formulation linearized carries its exact Jacobians: A and B to round-off.
    assert!(text.contains("(exact Jacobian)") && text.contains("B (exact), columns g:"), "{text}");
    ok(&multibody(
        dir.path(),
        &[&["linearize", "my_model.ron"][..], &rest, &["--sweep", "L", "--from", "1", "--to", "3", "--steps", "5", "--out", "lin"]].concat(),
    ));
    let csv = std::fs::read_to_string(dir.path().join("lin/my_model_eigenvalues.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 5, "{csv}");
}

/// The bicycle linearized in-process by Kane's exact Jacobian (by the state only: the one by
/// the parameters, which only `--input` needs, passes the node budget, and the run would fall
/// back to differences), its weave and capsize speeds to the benchmark's published digits (the
/// differenced equations give 10 of them, `docs/bicycle.md`).
#[test]
fn the_bicycle_linearizes_by_its_exact_jacobian() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = ["linearize", "bicycle", "--sweep", "x'", "--from", "4", "--to", "6.5", "--steps", "6", "--qdot", "phi=0", "--qdot", "delta=0", "--out", "."];
    let out = multibody(dir.path(), &sweep);
    let text = ok(&out);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("the exact Jacobians need more expression nodes"), "{}", String::from_utf8_lossy(&out.stderr));
    let crossings: Vec<f64> = text.lines().filter_map(|l| l.split("crosses zero at x' = ").nth(1)).map(|x| x.trim().parse().unwrap()).collect();
    // Meijaard et al. (2007), Table 2.
    let published = [4.29238253634111, 6.02426201538837];
    assert_eq!(crossings.len(), 2, "{text}");
    for (c, p) in crossings.iter().zip(published) {
        assert!((c - p).abs() < 1e-11 * p, "crossing at {c}, published {p}");
    }
}

/// A stiff run whose exact Jacobians exceed `--max-nodes` goes on with differenced ones and
/// says so: the same steps, more right-hand-side calls (a column of the Jacobian per state).
#[test]
fn exact_jacobians_over_the_node_budget_fall_back_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["compare", "cart_pendulum", "--method", "ros23", "--rtol", "1e-4", "--atol", "1e-4", "--repeats", "1", "--formulations", "kane", "--json", "-"];
    let exact = multibody(dir.path(), &args);
    let budget: Vec<&str> = args.iter().copied().chain(["--max-nodes", "3000"]).collect();
    let differenced = multibody(dir.path(), &budget);
    let warning = "the exact Jacobians need more expression nodes than the budget allows";
    assert!(!String::from_utf8_lossy(&exact.stderr).contains(warning));
    assert!(String::from_utf8_lossy(&differenced.stderr).contains(warning), "{}", String::from_utf8_lossy(&differenced.stderr));
    let record = |out: &Output| -> serde_json::Value { serde_json::from_str(&ok(out)).unwrap() };
    let (e, d) = (record(&exact), record(&differenced));
    assert_eq!(e[0]["steps"], d[0]["steps"]);
    let calls = |r: &serde_json::Value| r[0]["rhs_calls"].as_u64().unwrap();
    assert!(calls(&d) > calls(&e), "differenced {} against exact {}", calls(&d), calls(&e));
}

#[test]
fn the_stiff_integrator_is_selected_in_compare_and_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let out = ok(&multibody(
        dir.path(),
        &["compare", "stiff_pendulum", "--method", "ros23", "--rtol", "1e-4", "--atol", "1e-4", "--repeats", "1", "--formulations", "kane", "--json", "-"],
    ));
    let r: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(r[0]["integrator"], "ROS23");
    let steps = r[0]["steps"].as_u64().unwrap();
    assert!(steps > 0 && steps < 20_000, "{steps}");
    ok(&multibody(dir.path(), &["sweep", "stiff_pendulum", "--quick", "--repeats", "1", "--formulations", "kane", "--methods", "dopri5,ros23", "--out", "."]));
    let csv = std::fs::read_to_string(dir.path().join("stiff_pendulum_work_precision.csv")).unwrap();
    let integrators: Vec<&str> = csv.lines().skip(1).map(|l| l.split(',').nth(2).unwrap()).collect();
    assert_eq!(integrators, ["DOPRI5", "DOPRI5", "DOPRI5", "ROS23", "ROS23", "ROS23"], "{csv}");
}

#[test]
fn bad_input_gets_the_located_error_and_a_non_zero_exit() {
    let (dir, path) = user_model();
    let text = std::fs::read_to_string(&path).unwrap().replace("forces: [Gravity", "forcse: [Gravity");
    std::fs::write(&path, text).unwrap();
    for command in ["compare", "simulate", "sweep", "linearize"] {
        let out = multibody(dir.path(), &[command, "my_model.ron"]);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("my_model.ron:") && err.contains("forcse") && err.contains("help:"), "{command}: {err}");
    }
    let out = multibody(dir.path(), &["compare", "no_such_model"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("no model `no_such_model`") && err.contains("three_body"), "{err}");
    let out = multibody(dir.path(), &["compare", "cart_pendulum", "--rtol", "-1"]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("positive number"));
    let out = multibody(dir.path(), &["compare", "cart_pendulum", "--formulations", "hamilton"]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("reduced_volterra"));
    // A run that would not fit in memory, or integrate nothing, is refused before it starts.
    let out = multibody(dir.path(), &["simulate", "cart_pendulum", "--t-end", "1e7"]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("output times"), "{}", String::from_utf8_lossy(&out.stderr));
    let out = multibody(dir.path(), &["simulate", "cart_pendulum", "--t-end", "1", "--dt-out", "100"]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("longer than the run"));
}

#[test]
fn help_version_and_the_generator_s_commands() {
    let dir = tempfile::tempdir().unwrap();
    let help = ok(&multibody(dir.path(), &["--help"]));
    for command in ["generate", "inspect", "simulate", "compare", "sweep", "linearize"] {
        assert!(help.contains(command), "{help}");
    }
    assert!(ok(&multibody(dir.path(), &["--version"])).contains(env!("CARGO_PKG_VERSION")));
    let help = ok(&multibody(dir.path(), &["simulate", "--help"]));
    assert!(help.contains("--param <NAME=VALUE>") && help.contains("--t-end") && help.contains("--paper"), "{help}");
    std::fs::copy(concat!(env!("CARGO_MANIFEST_DIR"), "/models/cart_pendulum.ron"), dir.path().join("cart_pendulum.ron")).unwrap();
    let code = ok(&multibody(dir.path(), &["generate", "cart_pendulum.ron", "--quiet"]));
    assert!(code.contains("pub fn model()"));
    let inspect = ok(&multibody(dir.path(), &["inspect", concat!(env!("CARGO_MANIFEST_DIR"), "/models/cart_pendulum.ron")]));
    assert!(inspect.contains("m = 3, r = 1, p = 2, s = 1"), "{inspect}");
}

/// Parameters given on the command line are checked as the file's are: a negative mass is
/// refused on every command, located in the file and naming the value given.
#[test]
fn parameters_from_the_command_line_are_validated_like_the_file_s() {
    let (dir, _) = user_model();
    for args in [
        &["linearize", "my_model.ron", "--param", "mt=-1"][..],
        &["compare", "my_model.ron", "--param", "mt=-1"],
        &["simulate", "my_model.ron", "--param", "mt=-1"],
    ] {
        let out = multibody(dir.path(), args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("mt = -1.0 (given on the command line)") && err.contains("my_model.ron:"), "{args:?}: {err}");
    }
}

/// Numbers at the edge of f64 are named as such: a parameter of 1e300 stops the run with the
/// overflowing entry, not with "tolerance too tight"; a length of 1e200 with the inertia entry
/// that overflows, not with "not positive semi-definite".
#[test]
fn overflow_is_named_as_overflow() {
    let dir = tempfile::tempdir().unwrap();
    for p in ["g=1e300", "k=1e300"] {
        let out = multibody(dir.path(), &["simulate", "spring_cart", "--param", p, "--out", "o"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("at the edge of f64") && !err.contains("tolerance too tight"), "{p}: {err}");
    }
    let out = multibody(dir.path(), &["simulate", "cart_pendulum", "--param", "l=1e200", "--out", "o"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("overflows f64") && !err.contains("semi-definite"), "{err}");
}

/// Two runs at once, of two models whose paths differ only slightly, each get their own
/// results: nothing is cached or shared between runs (every model is evaluated in-process).
#[test]
fn concurrent_runs_of_different_models_keep_their_own_results() {
    concurrent_runs_keep_their_own_results(&["--repeats", "3"], &[]);
}

/// `compare ARGS` on two models whose paths differ by one letter (`my_model`, and `my_modem`
/// with a heavier trolley), both at once, with the environment `env`: each gets its own records.
fn concurrent_runs_keep_their_own_results(args: &[&str], env: &[(&str, &std::ffi::OsStr)]) {
    let (dir, path) = user_model();
    let heavy = std::fs::read_to_string(&path).unwrap().replace("name: \"my_model\"", "name: \"my_modem\"").replace("\"mt\": 5.0", "\"mt\": 50.0");
    std::fs::write(dir.path().join("my_modem.ron"), heavy).unwrap();
    let spawn = |file: &str| {
        Command::new(env!("CARGO_BIN_EXE_multibody"))
            .args(["compare", file, "--json", "-"])
            .args(args)
            .envs(env.iter().map(|(k, v)| (*k, *v)))
            .current_dir(dir.path())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (a, b) = (spawn("my_model.ron"), spawn("my_modem.ron"));
    let (a, b) = (a.wait_with_output().unwrap(), b.wait_with_output().unwrap());
    let (a, b): (serde_json::Value, serde_json::Value) = (serde_json::from_str(&ok(&a)).unwrap(), serde_json::from_str(&ok(&b)).unwrap());
    assert!(a.as_array().unwrap().iter().all(|r| r["scene"] == "my_model"));
    assert!(b.as_array().unwrap().iter().all(|r| r["scene"] == "my_modem"));
    assert_ne!(a[0]["energy_error_norm"], b[0]["energy_error_norm"]);
}

/// What the derivation could not decide and that changes the model's equations (here: the
/// automatic choice of ignorable coordinates left `x` out) reaches stderr as a warning, and
/// the run goes on.
#[test]
fn undecided_questions_are_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let model = include_str!("../fixtures/kink.ron");
    std::fs::write(dir.path().join("kink.ron"), model).unwrap();
    let out = multibody(dir.path(), &["compare", "kink.ron"]);
    ok(&out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("warning: `x` is not taken as ignorable: whether the equations depend on it could not be decided exactly"), "{stderr}");
}

/// The rustc beside the cargo that runs these tests (the compiled route's only need).
fn rustc() -> PathBuf {
    let rustc = Path::new(env!("CARGO")).with_file_name(format!("rustc{}", std::env::consts::EXE_SUFFIX));
    assert!(rustc.is_file(), "no rustc beside {}", env!("CARGO"));
    rustc
}

/// `multibody ARGS` in `dir` with the compiled route's cache in `cache` and `rustc` as its
/// compiler, `PATH` again the system's folders only.
fn multibody_compiled(dir: &Path, cache: &Path, rustc: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_multibody"))
        .args(args)
        .current_dir(dir)
        .env_clear()
        .env("PATH", "/usr/bin:/bin")
        .env("MULTIBODY_CACHE_DIR", cache)
        .env("RUSTC", rustc)
        .output()
        .unwrap()
}

/// The table without its time column (the only one that differs from run to run).
fn without_times(table: &str) -> String {
    table.lines().skip(1).map(|l| l.split('|').enumerate().filter(|(k, _)| *k != 4).map(|(_, c)| c).collect::<Vec<_>>().join("|") + "\n").collect()
}

/// `--compiled`: the model's module built by rustc once, into the cache folder, then loaded from
/// it with no rustc at all; the numbers are the in-process route's.
#[test]
fn the_compiled_route_builds_once_and_gives_the_same_table() {
    let (dir, _) = user_model();
    let cache = dir.path().join("cache");
    let args = ["compare", "my_model.ron", "--repeats", "1", "--compiled"];
    let first = multibody_compiled(dir.path(), &cache, &rustc(), &args);
    let table = ok(&first);
    assert!(String::from_utf8_lossy(&first.stderr).contains("compiling the model with rustc into"), "{}", String::from_utf8_lossy(&first.stderr));
    assert!(table.lines().next().unwrap().ends_with("(wall clock, built by rustc, --compiled)"), "{table}");
    // The second run needs no rustc: it loads the library the first one built.
    let second = multibody_compiled(dir.path(), &cache, Path::new("/nonexistent/rustc"), &args);
    assert_eq!(without_times(&ok(&second)), without_times(&table));
    assert!(!String::from_utf8_lossy(&second.stderr).contains("compiling"), "{}", String::from_utf8_lossy(&second.stderr));
    let in_process = ok(&multibody(dir.path(), &["compare", "my_model.ron", "--repeats", "1"]));
    assert_eq!(without_times(&in_process), without_times(&table));
    // Another model (a parameter changed) is another library; without rustc it cannot be built,
    // and the error says what to do.
    let other = multibody_compiled(dir.path(), &cache, Path::new("/nonexistent/rustc"), &["compare", "my_model.ron", "--compiled", "--param", "mt=50"]);
    let err = String::from_utf8_lossy(&other.stderr);
    assert!(!other.status.success() && err.contains("needs rustc") && err.contains("leave out --compiled"), "{err}");
    let libraries =
        std::fs::read_dir(&cache).unwrap().filter(|e| e.as_ref().unwrap().file_name().to_string_lossy().ends_with(std::env::consts::DLL_SUFFIX)).count();
    assert_eq!(libraries, 1);
}

/// Two compiled runs at once, of two models whose paths differ by one letter, each get their own
/// results: the cache is keyed by the module's content, never by a path.
#[test]
fn concurrent_compiled_runs_keep_their_own_results() {
    let cache = tempfile::tempdir().unwrap();
    let rustc = rustc();
    concurrent_runs_keep_their_own_results(
        &["--repeats", "1", "--compiled"],
        &[("MULTIBODY_CACHE_DIR", cache.path().as_os_str()), ("RUSTC", rustc.as_os_str())],
    );
}

/// `simulate` watches a model's events and reports them (stdout and JSON), in-process and
/// `--compiled` alike: the bouncing ball's impacts, apexes and the wall that stops it.
#[test]
fn simulate_reports_the_model_s_events() {
    let dir = tempfile::tempdir().unwrap();
    let out = ok(&multibody(dir.path(), &["simulate", "bouncing_ball", "--out", "o"]));
    assert!(out.contains("18 events (the last stopped the run)") && out.contains("floor (reset)") && out.contains("wall (stop)"), "{out}");
    assert!(out.contains("(stopped there by event `wall`)"), "{out}");
    let read = |sub: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.path().join(sub).join("bouncing_ball_reduced_volterra.json")).unwrap()).unwrap()
    };
    let json = read("o");
    assert_eq!(json["stopped_by_event"], true);
    let events = json["events"].as_array().unwrap();
    assert_eq!(events.len(), 18);
    // Released at rest, the ball is at an apex at the start.
    assert_eq!((events[0]["event"].as_str(), events[0]["t"].as_f64()), (Some("apex"), Some(0.0)));
    assert_eq!((events[1]["event"].as_str(), events[1]["action"].as_str()), (Some("floor"), Some("reset")));
    assert!((events[1]["t"].as_f64().unwrap() - (2.0f64 / 9.81).sqrt()).abs() < 1e-9);
    assert!((events[2]["q"][1].as_f64().unwrap() - 0.81).abs() < 1e-9, "the apex after the first impact is at e^2 h");
    let compiled = multibody_compiled(dir.path(), &dir.path().join("cache"), &rustc(), &["simulate", "bouncing_ball", "--compiled", "--out", "c"]);
    ok(&compiled);
    let theirs = read("c");
    for (a, b) in events.iter().zip(theirs["events"].as_array().unwrap()) {
        assert_eq!(a["event"], b["event"]);
        assert!((a["t"].as_f64().unwrap() - b["t"].as_f64().unwrap()).abs() < 1e-12, "{a} against {b}");
    }
}

/// `simulate --input NAME=FILE.csv` drives a model's input with a time series, interpolated
/// linearly and held at its ends; the trajectory's CSV holds the input's values; a bad file is
/// refused with its line.
#[test]
fn simulate_drives_an_input_from_a_time_series() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("push.csv"), "t,F\n0,0\n1,2\n").unwrap();
    ok(&multibody(dir.path(), &["simulate", "inverted_pendulum", "--formulation", "kane", "--input", "F=push.csv", "--t-end", "2", "--out", "o"]));
    let text = std::fs::read_to_string(dir.path().join("o/inverted_pendulum_kane.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let (t_col, f_col) = (0, header.iter().position(|h| *h == "input:F").expect("an input column"));
    let mut checked = 0;
    for line in lines {
        let cells: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        let t = cells[t_col];
        let expected = if t < 1.0 { 2.0 * t } else { 2.0 };
        assert!((cells[f_col] - expected).abs() < 1e-12, "t = {t}: F = {}", cells[f_col]);
        checked += 1;
    }
    assert_eq!(checked, 201);
    // Without --input, F keeps its nominal 0.
    ok(&multibody(dir.path(), &["simulate", "inverted_pendulum", "--formulation", "kane", "--t-end", "1", "--out", "n"]));
    let nominal = std::fs::read_to_string(dir.path().join("n/inverted_pendulum_kane.csv")).unwrap();
    assert!(nominal.lines().skip(1).all(|l| l.rsplit(',').next() == Some("0e0")), "{}", &nominal[..200]);
    std::fs::write(dir.path().join("bad.csv"), "0,0\n1,2\n0.5,1\n").unwrap();
    let bad = multibody(dir.path(), &["simulate", "inverted_pendulum", "--input", "F=bad.csv", "--out", "b"]);
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success() && err.contains("bad.csv:3:") && err.contains("must increase"), "{err}");
    let unknown = multibody(dir.path(), &["simulate", "inverted_pendulum", "--input", "G=push.csv", "--out", "b"]);
    let err = String::from_utf8_lossy(&unknown.stderr);
    assert!(!unknown.status.success() && err.contains("no input `G` (known: F)"), "{err}");
    // A model with no inputs says so, not an empty list.
    let none = multibody(dir.path(), &["simulate", "cart_pendulum", "--input", "F=push.csv", "--out", "b"]);
    let err = String::from_utf8_lossy(&none.stderr);
    assert!(!none.status.success() && err.contains("no input `F` (the model has none)"), "{err}");
}

/// Scene 2 in quaternions through `simulate` and `inspect` by name: the trajectory's file has the
/// four quaternion coordinates, its unit norm is among the reported constraints, and `inspect`
/// shows the body rates in quaternion rates and the orthogonal inversion.
#[test]
fn a_quaternion_scene_simulates_and_inspects() {
    let dir = tempfile::tempdir().unwrap();
    ok(&multibody(dir.path(), &["simulate", "three_body_quaternion", "--t-end", "2", "--out", "run"]));
    let csv = std::fs::read_to_string(dir.path().join("run/three_body_quaternion_reduced_volterra.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    for column in ["e0", "e1", "e2", "e3", "gamma1", "gamma2", "position_residual"] {
        assert!(header.split(',').any(|c| c == column), "no column {column} in {header}");
    }
    // 2 s at the scene's 0.1 s outputs.
    assert_eq!(csv.lines().count(), 1 + 21, "{header}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("run/three_body_quaternion_reduced_volterra.json")).unwrap()).unwrap();
    assert_eq!(json["stopped_by_event"], serde_json::Value::Bool(false), "{json}");
    let text = ok(&multibody(dir.path(), &["inspect", "tumbling_body"]));
    assert!(text.contains("u1 = -2*e0'*e1 + 2*e0*e1' + 2*e2'*e3 - 2*e2*e3'"), "{text}");
    assert!(text.contains("[Y; M'; a] with orthogonal rows, inverted as its transpose"), "{text}");
}

/// A free rotor whose only coordinate is ignorable: the reduced form has no equation at all
/// (p - s = 0; once a panic in emission and in the condition monitor). Every formulation runs;
/// the rotor turns at its initial rate (theta = t), its momentum I theta' = 0.74 kept exactly.
#[test]
fn a_rotor_whose_every_coordinate_is_ignorable_runs_in_every_formulation() {
    let dir = tempfile::tempdir().unwrap();
    let body = |name: &str, x: &str, y: &str| {
        format!(
            r#"Body(name: "{name}", frame: "disk", mass: "1", com: ["{x}", "{y}", "0"], inertia: Diagonal(["0.01", "0.01", "0.01"]), shape: Sphere(radius: "0.06", origin: ["{x}", "{y}", "0"])),"#
        )
    };
    let model = format!(
        r#"Model(name: "rotor", parameters: {{"g": 9.81}}, coordinates: ["theta"],
  frames: [Frame(name: "disk", parent: "world", rotation: [Z("theta")])],
  bodies: [{} {}],
  forces: [Gravity(vector: ["0", "0", "-g"])],
  quasi_velocities: QuasiVelocities(full: ["theta'"], reduced: []),
  initial: Initial(q: {{"theta": "0"}}, qdot: {{"theta": "1"}}),
)"#,
        body("a", "0.6", "0"),
        body("b", "0", "0.6")
    );
    std::fs::write(dir.path().join("rotor.ron"), model).unwrap();
    let json = ok(&multibody(dir.path(), &["compare", "rotor.ron", "--t-end", "1", "--dt-out", "0.5", "--repeats", "1", "--json", "-"]));
    let records: serde_json::Value = serde_json::from_str(&json).unwrap();
    let shapes: Vec<(String, u64, u64)> = records
        .as_array()
        .unwrap()
        .iter()
        .map(|r| (r["method"].as_str().unwrap().to_string(), r["states"].as_u64().unwrap(), r["equations"].as_u64().unwrap()))
        .collect();
    assert_eq!(shapes, [("lagrange".into(), 2, 1), ("maggi".into(), 2, 1), ("kane".into(), 2, 1), ("reduced_volterra".into(), 1, 0)]);
    assert!(records.as_array().unwrap().iter().all(|r| r["momentum_error_norm"].as_f64().unwrap() < 1e-12), "{json}");
    for form in ["reduced_volterra", "lagrange"] {
        ok(&multibody(dir.path(), &["simulate", "rotor.ron", "--formulation", form, "--out", "run", "--t-end", "1", "--dt-out", "0.5"]));
        let csv = std::fs::read_to_string(dir.path().join(format!("run/rotor_{form}.csv"))).unwrap();
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        let last: Vec<f64> = csv.lines().last().unwrap().split(',').map(|x| x.parse().unwrap()).collect();
        let at = |name: &str| last[header.iter().position(|h| *h == name).unwrap()];
        assert!((at("t") - 1.0).abs() < 1e-15 && (at("theta") - 1.0).abs() < 1e-9 && (at("momentum:theta") - 0.74).abs() < 1e-12, "{form}: {csv}");
    }
}

/// The model file's units label the plots' axes and reach the run's JSON.
#[test]
fn simulate_labels_the_plots_with_the_model_s_units() {
    let dir = tempfile::tempdir().unwrap();
    ok(&multibody(dir.path(), &["simulate", "cart_pendulum", "--out", "run", "--t-end", "0.5"]));
    let svg = std::fs::read_to_string(dir.path().join("run/cart_pendulum_reduced_volterra_coordinates.svg")).unwrap();
    assert!(svg.contains("x [m]") && svg.contains("theta1 [rad]"), "the axes' labels");
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("run/cart_pendulum_reduced_volterra.json")).unwrap()).unwrap();
    assert_eq!((json["units"]["x"].as_str(), json["units"]["tau"].as_str()), (Some("m"), Some("N m")));
}
