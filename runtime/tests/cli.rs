//! The `compare` command: its table, JSON records and plots, and its errors.

use std::process::Command;

fn compare(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_compare")).args(args).output().unwrap()
}

#[test]
fn json_records_carry_the_documented_fields() {
    let out = compare(&["satellite_boom", "--repeats", "1", "--json", "-"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    let json_start = text.find('[').unwrap();
    let records: serde_json::Value = serde_json::from_str(&text[json_start..]).unwrap();
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
    assert!(err.contains("no emitted model `no_such_model`") && err.contains("cart_pendulum"), "{err}");
    let out = compare(&["cart_pendulum", "--rtol", "-1"]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("positive number"));
    let out = compare(&["cart_pendulum", "--method", "rk4"]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("needs `--h`"));
}

#[test]
fn the_sweep_writes_its_table_and_diagram_and_shows_progress() {
    let dir = std::env::temp_dir().join(format!("sweep-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_sweep"))
        .args(["satellite_boom", "--quick", "--repeats", "1", "--out", dir.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stderr).contains("[ 35/36]"), "progress on stderr");
    let csv = std::fs::read_to_string(dir.join("satellite_boom_work_precision.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    // 4 formulations x (3 DOPRI5 + 3 DOP853 + 3 RK4) settings.
    assert_eq!(rows.len(), 36);
    // Tighter tolerance, smaller error against the reference (DOP853, reduced Volterra).
    let errors: Vec<f64> = rows
        .iter()
        .filter(|r| r[1] == "reduced_volterra" && r[2] == "DOP853")
        .map(|r| r[7].parse().unwrap())
        .collect();
    assert_eq!(errors.len(), 3);
    assert!(errors[0] > errors[1] && errors[1] > errors[2], "{errors:?}");
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("satellite_boom_work_precision.json")).unwrap()).unwrap();
    assert_eq!(json.as_array().unwrap().len(), 36);
    let svg = std::fs::read_to_string(dir.join("satellite_boom_work_precision.svg")).unwrap();
    assert!(svg.contains("work-precision") && svg.contains("reduced_volterra DOP853"));
}
