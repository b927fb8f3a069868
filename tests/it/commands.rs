//! The command line's cells of the matrix (the issue "Every path works"): every command
//! (`generate`, `inspect`, `compare`, `simulate` with `--animate`, `sweep --quick`, `linearize`)
//! on every model of `models/`, by its built-in name, and the model read from a file by path;
//! `simulate` and `linearize` in every formulation. Each cell asserts its outcome: success with
//! its invariants, no warning on a built-in model, the files it names written; or a refusal it
//! expects. A cell that hangs is killed (and fails) by [`crate::common::multibody`].

use crate::common::{multibody, ok};
use std::path::Path;

const FORMULATIONS: [&str; 4] = ["lagrange", "maggi", "kane", "reduced_volterra"];

/// `multibody ARGS` succeeded without a warning; its stdout.
fn quiet(dir: &Path, args: &[&str]) -> String {
    let out = multibody(dir, args);
    let text = ok(&out);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("warning"), "{args:?}: a built-in model warns: {err}");
    text
}

fn cells(name: &str) {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = format!("{name}.ron");
    std::fs::copy(format!("{}/models/{file}", env!("CARGO_MANIFEST_DIR")), d.join(&file)).unwrap();
    let model = load::model(name).unwrap();
    let kinds: Vec<&str> = generator::emit::Options::from_model(&model).formulations.iter().map(|f| f.kind().name()).collect();
    let (t0, t_end, dt) = model.simulation.as_ref().map(|s| (s.t_start, s.t_end, s.dt_out)).unwrap();
    let end = (t0 + (t_end - t0).min(40.0 * dt).min(1.0)).to_string();
    for by in [name, file.as_str()] {
        // generate: the module, by name and by path.
        quiet(d, &["generate", by, "-o", "module.rs", "--quiet"]);
        let code = std::fs::read_to_string(d.join("module.rs")).unwrap();
        assert!(code.contains("pub fn model()"), "{by}: a module");
        std::fs::remove_file(d.join("module.rs")).unwrap();
        // compare: the four formulations' records, each with its invariants.
        quiet(d, &["compare", by, "--t-end", &end, "--repeats", "1", "--json", "records.json"]);
        let records: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join("records.json")).unwrap()).unwrap();
        let records = records.as_array().unwrap();
        assert_eq!(records.len(), kinds.len(), "{by}");
        for r in records {
            assert!(r["failure"].is_null(), "{by}: {r}");
            let energy = r["energy_error_norm"].as_f64().unwrap();
            assert!(energy < 1e-3, "{by} {}: energy error {energy:e}", r["method"]);
        }
    }
    quiet(d, &["inspect", name]);
    for f in FORMULATIONS {
        if !kinds.contains(&f) {
            continue;
        }
        // simulate, with the page: the table's invariants and a page that names the model.
        let text = quiet(d, &["simulate", name, "--formulation", f, "--t-end", &end, "--out", "out", "--animate", "page.html"]);
        assert!(text.contains("max |"), "{name} {f}: {text}");
        let page = std::fs::read_to_string(d.join("page.html")).unwrap();
        assert!(page.starts_with("<!DOCTYPE html>") && page.contains(&format!("\"model\":\"{name}\"")), "{name} {f}");
        // linearize: A and its eigenvalues, with what the point is.
        let text = quiet(d, &["linearize", name, "--formulation", f]);
        assert!(text.contains(&format!("{name} {f}: A is")), "{name} {f}: {text}");
        assert!(text.contains("an equilibrium") || text.contains("a steady motion") || text.contains("not an equilibrium nor a steady motion"), "{text}");
    }
    // sweep: every run it makes runs (RK4 is left out of a model with events, and says so),
    // but on the stiff model, where RK4's fixed steps beyond its stability limit diverge, and
    // each such run says so.
    let text = quiet(d, &["sweep", name, "--quick", "--repeats", "1", "--t-end", &end, "--formulations", "kane", "--out", "sweep"]);
    let points: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join(format!("sweep/{name}_work_precision.json"))).unwrap()).unwrap();
    for p in points.as_array().unwrap() {
        match p["failure"].as_str() {
            None => assert!(p["error"].as_f64().is_some_and(|e| e.is_finite()), "{name}: {p}"),
            Some(why) => assert!(
                name == "stiff_pendulum" && p["integrator"] == "RK4" && why.contains("non-finite value"),
                "{name}: a run the sweep should run stopped: {p}\n{text}"
            ),
        }
    }
}

macro_rules! every_model {
    ($($name:ident),* $(,)?) => {
        $(
            #[test]
            fn $name() {
                cells(stringify!($name));
            }
        )*
        /// The list above is the models of `models/`.
        #[test]
        fn every_model_has_its_cells() {
            let mut listed = vec![$(stringify!($name)),*];
            listed.sort();
            assert_eq!(listed, generator::model::built_in().collect::<Vec<_>>());
        }
    };
}

every_model!(
    bicycle,
    bouncing_ball,
    cart_pendulum,
    cartesian_pendulum,
    inverted_pendulum,
    pendulum_on_cart_5,
    rolling_disk,
    satellite_boom,
    satellite_boom_quaternion,
    spring_cart,
    stiff_pendulum,
    three_body,
    three_body_quaternion,
    tumbling_body,
    winch,
);
