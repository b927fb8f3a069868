//! The `compare` command: its table, JSON records and plots, and its errors.

use std::process::Command;

fn compare(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_compare")).args(args).output().unwrap()
}

#[test]
fn json_records_carry_the_documented_fields() {
    let out = compare(&["satellite_boom", "--repeats", "1", "--json", "-"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // stdout is the JSON alone; the table went to stderr.
    let records: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let text = String::from_utf8_lossy(&out.stderr);
    let records = records.as_array().unwrap();
    assert_eq!(records.len(), 4);
    for r in records {
        for field in ["scene", "method", "states", "equations", "cpu_seconds", "energy_error_norm", "constraint_error_norm", "momentum_error_norm"] {
            assert!(r.get(field).is_some(), "missing `{field}` in {r}");
        }
        assert_eq!(r["scene"], "satellite_boom");
        let names: Vec<&str> = r["momenta"].as_array().unwrap().iter().map(|m| m["coordinate"].as_str().unwrap()).collect();
        assert_eq!(names, ["X", "Y", "Z"], "one momentum record per ignorable coordinate");
    }
    // The paper's state counts for scene 3, the work integral included: 15, 15, 15, 12.
    let states: Vec<u64> = records.iter().map(|r| r["states"].as_u64().unwrap()).collect();
    assert_eq!(states, vec![15, 15, 15, 12]);
    assert!(text.contains("| reduced_volterra | 12 | 4 |"), "{text}");
    assert!(text.contains("momentum err (X) | (rel) | momentum err (Y)"), "{text}");
}

#[test]
fn plots_are_written_as_svg() {
    let dir = std::env::temp_dir().join(format!("compare-plots-{}", std::process::id()));
    let out = compare(&["three_body", "--repeats", "1", "--method", "dop853", "--rtol", "1e-8", "--atol", "1e-8", "--plots", dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for name in ["three_body_coordinates.svg", "three_body_errors.svg"] {
        let svg = std::fs::read_to_string(dir.join(name)).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("reduced_volterra") && svg.contains("<polyline"), "{name}");
    }
}

#[test]
fn bad_arguments_are_refused_with_the_reason() {
    let out = compare(&["no_such_model"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no model `no_such_model`") && err.contains("cart_pendulum"), "{err}");
    let out = compare(&["cart_pendulum", "--rtol", "-1"]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("positive number"));
    let out = compare(&["cart_pendulum", "--method", "rk4"]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("--h"));
    let out = compare(&["cart_pendulum", "--formulations", "hamilton"]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("reduced_volterra"));
}

#[test]
fn the_sweep_writes_its_table_and_diagram_and_shows_progress() {
    let dir = std::env::temp_dir().join(format!("sweep-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_sweep")).args(["satellite_boom", "--quick", "--repeats", "1", "--out", dir.to_str().unwrap()]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stderr).contains("[ 35/36]"), "progress on stderr");
    let csv = std::fs::read_to_string(dir.join("satellite_boom_work_precision.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    // 4 formulations x (3 DOPRI5 + 3 DOP853 + 3 RK4) settings.
    assert_eq!(rows.len(), 36);
    // Tighter tolerance, smaller error against the reference (DOP853, reduced Volterra).
    let errors: Vec<f64> = rows.iter().filter(|r| r[1] == "reduced_volterra" && r[2] == "DOP853").map(|r| r[7].parse().unwrap()).collect();
    assert_eq!(errors.len(), 3);
    assert!(errors[0] > errors[1] && errors[1] > errors[2], "{errors:?}");
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("satellite_boom_work_precision.json")).unwrap()).unwrap();
    assert_eq!(json.as_array().unwrap().len(), 36);
    let svg = std::fs::read_to_string(dir.join("satellite_boom_work_precision.svg")).unwrap();
    assert!(svg.contains("work-precision") && svg.contains("reduced_volterra DOP853"));
}

/// A scratch directory outside the repository holding `my_model.ron`: the downstream example's
/// crane under another name, a model the project has never compiled.
fn user_model(tag: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("user-model-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let crane = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/downstream/models/gantry_crane.ron")).unwrap();
    std::fs::write(dir.join("my_model.ron"), crane.replace("name: \"gantry_crane\"", "name: \"my_model\"")).unwrap();
    dir
}

#[test]
fn a_model_file_of_the_user_s_own_is_compared_from_compiled_code_and_cached_by_content() {
    let dir = user_model("compare");
    let model = dir.join("my_model.ron");
    let run = |extra: &[&str]| Command::new(env!("CARGO_BIN_EXE_compare")).arg(&model).args(["--repeats", "1"]).args(extra).current_dir(&dir).output().unwrap();
    let out = run(&["--json", "out.json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let table = String::from_utf8_lossy(&out.stdout);
    for row in ["| lagrange | 6 | 3 |", "| maggi | 6 | 3 |", "| kane | 6 | 3 |", "| reduced_volterra | 5 | 2 |"] {
        assert!(table.contains(row), "{row} in\n{table}");
    }
    assert!(table.starts_with("my_model: DOPRI5"), "{table}");
    let records: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("out.json")).unwrap()).unwrap();
    let records = records.as_array().unwrap();
    assert_eq!(records.len(), 4);
    assert!(records.iter().all(|r| r["scene"] == "my_model" && r["momenta"][0]["coordinate"] == "x"));
    // The reduced method holds the trolley's momentum exactly.
    assert!(records[3]["momentum_error_norm"].as_f64().unwrap() < 1e-12);

    // Unchanged: nothing is generated anew or compiled.
    let again = run(&["--formulations", "reduced"]);
    assert!(again.status.success(), "{}", String::from_utf8_lossy(&again.stderr));
    assert!(!String::from_utf8_lossy(&again.stderr).contains("compiling"), "{}", String::from_utf8_lossy(&again.stderr));
    assert!(String::from_utf8_lossy(&again.stdout).contains("| reduced_volterra | 5 | 2 |"));

    // Changed content: rebuilt, and the new parameters are what runs.
    let text = std::fs::read_to_string(&model).unwrap().replace("\"mt\": 5.0", "\"mt\": 50.0");
    std::fs::write(&model, text).unwrap();
    let changed = run(&["--json", "-", "--formulations", "kane"]);
    assert!(changed.status.success(), "{}", String::from_utf8_lossy(&changed.stderr));
    assert!(String::from_utf8_lossy(&changed.stderr).contains("compiling"));
    let heavy: serde_json::Value = serde_json::from_slice(&changed.stdout).unwrap();
    assert_ne!(heavy[0]["energy_error_norm"], records[2]["energy_error_norm"], "a heavier trolley is a different run");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_model_file_is_swept_the_same_way() {
    let dir = user_model("sweep");
    let out = Command::new(env!("CARGO_BIN_EXE_sweep"))
        .arg(dir.join("my_model.ron"))
        .args(["--quick", "--repeats", "1", "--formulations", "kane,reduced", "--out"])
        .arg(dir.join("results"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let csv = std::fs::read_to_string(dir.join("results/my_model_work_precision.csv")).unwrap();
    // 2 formulations x 9 settings.
    assert_eq!(csv.lines().count(), 1 + 18, "{csv}");
    assert!(csv.lines().skip(1).all(|l| l.starts_with("my_model,kane,") || l.starts_with("my_model,reduced_volterra,")), "{csv}");
    assert!(std::fs::read_to_string(dir.join("results/my_model_work_precision.svg")).unwrap().contains("<svg"));
    // And linearized, from the same compiled program: hanging at rest, nothing grows or decays
    // (a conservative system: the pendulum mode is a purely imaginary pair; the free trolley's
    // drift a double zero, split by the differences' round-off) and the trolley's position is
    // set aside; a sweep of the rope length writes its table, data and figure.
    let linearize = |extra: &[&str]| Command::new(env!("CARGO_BIN_EXE_linearize")).arg(dir.join("my_model.ron")).args(extra).output().unwrap();
    let rest = ["--q", "phi=0", "--q", "psi=0", "--qdot", "x=0", "--qdot", "phi=0", "--qdot", "psi=0"];
    let out = linearize(&[&rest[..], &["--input", "g"]].concat());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
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
    assert!(text.contains("B (finite differences), columns g:"), "{text}");
    let out = linearize(&[&rest[..], &["--sweep", "L", "--from", "1", "--to", "3", "--steps", "5", "--out"], &[dir.join("lin").to_str().unwrap()]].concat());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let csv = std::fs::read_to_string(dir.join("lin/my_model_eigenvalues.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 5, "{csv}");
    assert!(csv.starts_with("L,re_1,im_1"), "{csv}");
    assert!(std::fs::read_to_string(dir.join("lin/my_model_eigenvalues.svg")).unwrap().contains("<svg"));
    // Names it does not know are refused with what it knows.
    let bad = linearize(&["--sweep", "length", "--from", "1", "--to", "2"]);
    assert!(!bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("parameters: mt, mc, L"), "{}", String::from_utf8_lossy(&bad.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_wrong_model_file_gets_the_generator_s_located_error_and_no_build_log() {
    let dir = user_model("bad");
    let bad = dir.join("my_model.ron");
    let text = std::fs::read_to_string(&bad).unwrap().replace("forces: [Gravity", "forcse: [Gravity");
    std::fs::write(&bad, text).unwrap();
    for bin in [env!("CARGO_BIN_EXE_compare"), env!("CARGO_BIN_EXE_sweep")] {
        let out = Command::new(bin).arg(&bad).output().unwrap();
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("my_model.ron:") && err.contains("forcse") && err.contains("help:"), "{err}");
        assert!(!err.contains("Compiling") && !err.contains("error[E"), "no build log:\n{err}");
    }
    let missing = Command::new(env!("CARGO_BIN_EXE_compare")).arg(dir.join("nothing.ron")).output().unwrap();
    assert!(!missing.status.success());
    assert!(String::from_utf8_lossy(&missing.stderr).contains("cannot read model file"), "{}", String::from_utf8_lossy(&missing.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn help_and_version_answer_on_stdout_before_anything_is_built() {
    for bin in [env!("CARGO_BIN_EXE_compare"), env!("CARGO_BIN_EXE_sweep"), env!("CARGO_BIN_EXE_linearize")] {
        let help = Command::new(bin).arg("--help").output().unwrap();
        assert!(help.status.success());
        let text = String::from_utf8_lossy(&help.stdout);
        assert!(text.contains("Usage:") && text.contains("<MODEL>") && text.contains("[default: "), "{text}");
        assert!(text.contains("work-precision") || text.contains("paper's Tables") || text.contains("eigenvalues"), "a sentence on what it does: {text}");
        let version = Command::new(bin).arg("--version").output().unwrap();
        assert!(version.status.success() && String::from_utf8_lossy(&version.stdout).contains(env!("CARGO_PKG_VERSION")));
        // A repeated single-valued option is refused.
        let repeated = if bin == env!("CARGO_BIN_EXE_linearize") { "--steps" } else { "--repeats" };
        let twice = Command::new(bin).args(["cart_pendulum", repeated, "3", repeated, "4"]).output().unwrap();
        assert!(!twice.status.success() && String::from_utf8_lossy(&twice.stderr).contains("cannot be used multiple times"));
    }
}
