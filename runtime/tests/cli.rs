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
    }
    // The paper's state counts for scene 3, the work integral included: 15, 15, 15, 12.
    let states: Vec<u64> = records.iter().map(|r| r["states"].as_u64().unwrap()).collect();
    assert_eq!(states, vec![15, 15, 15, 12]);
    assert!(text.contains("| reduced_volterra | 12 | 4 |"), "{text}");
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
