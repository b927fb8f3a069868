//! Defects found where two features meet (the issue "Every path works"), each held by a test
//! that failed before its fix: linearizing a spinning top, a steady motion and a sweep of a
//! conservative system; names checked before anything is derived; built-in names everywhere.

use crate::common::{multibody, ok};
use runtime::linearize::{Motion, Operating, Swept, crossings, eigenvalues, linearize, sweep};
use seam::FormulationKind;

fn fixture(name: &str) -> String {
    format!("{}/tests/fixtures/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The model of a fixture, evaluated in-process with its exact Jacobians.
fn evaluated(name: &str) -> seam::Model {
    let model = generator::model::load(fixture(name)).unwrap();
    load::evaluate(&model, load::Jacobians::Exact { only: None, by_parameters: false }, load::Route::Jit, &mut |_| {}).unwrap().model
}

fn at(model: &seam::Model, q: &[(&str, f64)], qdot: &[(&str, f64)]) -> Operating {
    let (mut q0, mut qd0) = model.initial.clone().unwrap();
    for (name, v) in q {
        q0[model.coordinate_index(name).unwrap()] = *v;
    }
    for (name, v) in qdot {
        qd0[model.coordinate_index(name).unwrap()] = *v;
    }
    Operating { q: q0, qdot: qd0, params: model.default_params.clone(), held: vec![] }
}

/// `multibody linearize` on a heavy top spun upright in quaternions never returned (nalgebra's
/// Schur iteration stalls on eigenvalues of one modulus): it answers now, in every formulation,
/// says that the point is not an equilibrium, and its eigenvalues are those of `A`.
#[test]
fn a_spinning_top_linearizes() {
    let dir = tempfile::tempdir().unwrap();
    let top = fixture("heavy_top.ron");
    for f in ["kane", "reduced_volterra", "lagrange", "maggi"] {
        let out = multibody(dir.path(), &["linearize", &top, "--formulation", f, "--q", "e0=1", "--q", "e1=0", "--qdot", "e2=0", "--qdot", "e3=20"]);
        let text = crate::common::ok(&out);
        assert!(text.contains("note: not an equilibrium nor a steady motion: "), "{f}: {text}");
    }
    let model = evaluated("heavy_top.ron");
    let lin = linearize(&model, FormulationKind::Kane, &at(&model, &[("e0", 1.0)], &[("e3", 20.0)])).unwrap();
    assert!(matches!(lin.motion(), Motion::Transient { .. }));
    let n = lin.a.nrows();
    assert_eq!(lin.eigenvalues.len() + lin.cyclic.len(), n);
    let kept: Vec<usize> = (0..n).filter(|i| !lin.cyclic.contains(i)).collect();
    let a = nalgebra::DMatrix::from_fn(kept.len(), kept.len(), |r, c| lin.a[(kept[r], kept[c])]);
    // The eigenvalues sum to the trace, and each makes A - lambda I singular.
    let trace: f64 = lin.eigenvalues.iter().map(|l| l.re).sum();
    assert!((trace - a.trace()).abs() < 1e-10, "{trace} against {}", a.trace());
    for l in &lin.eigenvalues {
        let shifted = nalgebra::DMatrix::from_fn(a.nrows(), a.ncols(), |r, c| nalgebra::Complex::new(a[(r, c)], 0.0) - if r == c { *l } else { 0.0.into() });
        assert!(shifted.singular_values().min() < 1e-10 * a.amax(), "{l}");
    }
    assert_eq!(eigenvalues(&a).unwrap().len(), a.nrows());
}

/// A top spinning upright about its symmetry axis is a steady motion in Lagrange's and Maggi's
/// state (only the cyclic spin angle moves): its sweep over the spin finds the one onset of
/// stability, `w_c = 2 sqrt(m g l (I1 + m l^2)) / I3`, and none of the round-off of the stable
/// side's imaginary eigenvalues (which used to give a dozen crossings). In Kane's and the
/// reduced method's state the body rates turn with the spin: there the point is transient,
/// and the sweep says so.
#[test]
fn a_sleeping_top_s_sweep_finds_its_onset_and_only_it() {
    let model = evaluated("sleeping_top.ron");
    let p = |name: &str| model.default_params[model.parameter_index(name).unwrap()];
    let (m, g, l, i1, i3) = (p("m"), p("g"), p("l"), p("I1"), p("I3"));
    let onset = 2.0 * (m * g * l * (i1 + m * l * l)).sqrt() / i3;
    let start = at(&model, &[], &[]);
    let swept = Swept::find(&model, "phi'").unwrap();
    let values: Vec<f64> = (0..=40).map(|i| 0.25 * i as f64).collect();
    for kind in [FormulationKind::Lagrange, FormulationKind::Maggi] {
        let lin = linearize(&model, kind, &swept.apply(&start, 9.0)).unwrap();
        assert!(matches!(lin.motion(), Motion::Steady { .. }), "{kind}: {:?}", lin.motion());
        let rows = sweep(&model, kind, &start, swept, &values).unwrap();
        assert!(rows.iter().all(|r| !r.transient));
        let cross = crossings(&model, kind, &start, swept, &rows).unwrap();
        assert_eq!(cross.len(), 1, "{kind}: {cross:?}");
        assert!((cross[0] / onset - 1.0).abs() < 1e-9, "{kind}: {} against {onset}", cross[0]);
    }
    for kind in [FormulationKind::Kane, FormulationKind::ReducedVolterra] {
        let lin = linearize(&model, kind, &swept.apply(&start, 9.0)).unwrap();
        assert!(matches!(lin.motion(), Motion::Transient { .. }), "{kind}: {:?}", lin.motion());
        let phi = model.coordinate_index("phi").unwrap();
        assert_eq!(lin.drifting, [phi], "{kind}");
    }
    // At rest upright the top is an equilibrium.
    let rest = linearize(&model, FormulationKind::Lagrange, &swept.apply(&start, 0.0)).unwrap();
    assert_eq!(rest.motion(), Motion::Equilibrium);
    // The command line says the same.
    let dir = tempfile::tempdir().unwrap();
    let out = crate::common::ok(&multibody(
        dir.path(),
        &["linearize", &fixture("sleeping_top.ron"), "--formulation", "lagrange", "--sweep", "phi'", "--from", "0", "--to", "10", "--steps", "41"],
    ));
    assert_eq!(out.matches("crosses zero").count(), 1, "{out}");
    let out = crate::common::ok(&multibody(
        dir.path(),
        &["linearize", &fixture("sleeping_top.ron"), "--formulation", "kane", "--sweep", "phi'", "--from", "0", "--to", "10", "--steps", "41"],
    ));
    assert!(out.contains("note: at 40 of the 41 values"), "{out}");
}

/// A misspelled name on the command line is refused before anything is derived: a model whose
/// derivation the node budget stops names the misspelling, not the budget.
#[test]
fn names_are_checked_before_the_derivation() {
    let dir = tempfile::tempdir().unwrap();
    for args in [
        &["linearize", "bicycle", "--max-nodes", "20000", "--qdot", "speed=3"][..],
        &["linearize", "bicycle", "--max-nodes", "20000", "--sweep", "speed", "--from", "0", "--to", "1"][..],
        &["linearize", "bicycle", "--max-nodes", "20000", "--input", "torque"][..],
        &["simulate", "bicycle", "--max-nodes", "20000", "--q", "lean=3"][..],
        &["compare", "bicycle", "--max-nodes", "20000", "--qdot", "lean=3"][..],
    ] {
        let out = multibody(dir.path(), args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("error: no ") && !err.contains("budget"), "{args:?}: {err}");
    }
    // The same names, spelled right, reach the budget.
    let out = multibody(dir.path(), &["linearize", "bicycle", "--max-nodes", "20000"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("budget"), "{}", String::from_utf8_lossy(&out.stderr));
}

/// The run a command makes is checked before anything is derived: a model whose file gives no
/// run, or settings that make no output times, are refused at once, not after a derivation
/// (which the node budget stops here, to show which came first).
#[test]
fn the_run_is_checked_before_the_derivation() {
    let dir = tempfile::tempdir().unwrap();
    let bicycle = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/models/bicycle.ron")).unwrap();
    let line = "    simulation: Simulation(t_end: 5.0, dt_out: 0.01),\n";
    assert!(bicycle.contains(line), "the bicycle's run");
    let no_run = dir.path().join("no_run.ron");
    std::fs::write(&no_run, bicycle.replace(line, "")).unwrap();
    let no_run = no_run.to_str().unwrap();
    for command in ["simulate", "compare", "sweep"] {
        let out = multibody(dir.path(), &[command, no_run, "--max-nodes", "20000"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("has no `simulation` section: give the run with --t-end and --dt-out"), "{command}: {err}");
        assert!(!err.contains("budget"), "{command}: {err}");
        let out = multibody(dir.path(), &[command, "bicycle", "--max-nodes", "20000", "--dt-out", "10"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("run settings:") && !err.contains("budget"), "{command}: {err}");
    }
    // Given a run, the same model reaches the budget.
    let out = multibody(dir.path(), &["simulate", no_run, "--max-nodes", "20000", "--t-end", "1", "--dt-out", "0.1"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("budget"), "{}", String::from_utf8_lossy(&out.stderr));
}

/// Every command takes a built-in model by name, `generate` too (it refused, pointing into a
/// checkout the user does not have); an unknown name lists the built-in ones.
#[test]
fn every_command_takes_a_built_in_name() {
    let dir = tempfile::tempdir().unwrap();
    let out = multibody(dir.path(), &["generate", "three_body", "-o", "three_body.rs", "--quiet"]);
    crate::common::ok(&out);
    let code = std::fs::read_to_string(dir.path().join("three_body.rs")).unwrap();
    assert!(code.contains("pub mod kane"), "a module");
    for command in ["generate", "inspect", "simulate", "compare", "linearize"] {
        let out = multibody(dir.path(), &[command, "three_bdy"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("no model `three_bdy`") && err.contains("three_body, three_body_quaternion"), "{command}: {err}");
        assert!(!err.contains("models live in"), "{err}");
    }
}

/// An initial state off a constraint is located where it is wrong and says at which level:
/// in the model file (`initial.q` or `initial.qdot`, with line and column) or on the command
/// line (naming what was given), each with a fix.
#[test]
fn an_initial_state_off_a_constraint_is_located_and_leveled() {
    let dir = tempfile::tempdir().unwrap();
    let models = concat!(env!("CARGO_MANIFEST_DIR"), "/models");
    let scene1 = std::fs::read_to_string(format!("{models}/cart_pendulum.ron")).unwrap();
    std::fs::write(dir.path().join("rates.ron"), scene1.replace("\"theta2\": \"-cos(theta1 - theta2)*theta1'\"", "\"theta2\": \"0.3\"")).unwrap();
    let tumbling = std::fs::read_to_string(format!("{models}/tumbling_body.ron")).unwrap();
    std::fs::write(dir.path().join("norm.ron"), tumbling.replace("\"e0\": \"1\"", "\"e0\": \"0.9\"")).unwrap();
    std::fs::write(dir.path().join("norm_rate.ron"), tumbling.replace("qdot: {\"e0\": \"0\"", "qdot: {\"e0\": \"0.3\"")).unwrap();
    for (file, place, words) in [
        ("rates.ron", "initial.qdot", "the initial rates violate the velocity constraint `wheel`"),
        ("norm.ron", "initial.q", "the initial coordinates violate the position constraint `unit`"),
        ("norm_rate.ron", "initial.qdot", "the initial rates violate the position constraint `unit` (its time derivative)"),
    ] {
        let out = multibody(dir.path(), &["simulate", file, "--t-end", "0.1"]);
        let err = String::from_utf8_lossy(&out.stderr);
        let line = std::fs::read_to_string(dir.path().join(file))
            .unwrap()
            .lines()
            .position(|l| l.trim_start().starts_with(&format!("{}: ", place.rsplit('.').next().unwrap())))
            .unwrap()
            + 1;
        assert!(
            !out.status.success() && err.contains(&format!("{file}:{line}:")) && err.contains(&format!("in {place}: {words}")) && err.contains("help: give"),
            "{file}: {err}"
        );
    }
    let out = multibody(dir.path(), &["simulate", "cart_pendulum", "--t-end", "0.1", "--qdot", "theta2=0.3"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("with --qdot theta2=0.3 (given on the command line): the initial rates violate the velocity constraint `wheel`")
            && err.contains("give rates that satisfy it"),
        "{err}"
    );
}

/// `sweep` on a model with events: RK4, which cannot locate events, is left out with a note
/// (it reported "12 stopped early" for runs refused at the start), and every run it makes runs.
#[test]
fn a_sweep_with_events_leaves_out_what_cannot_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = crate::common::ok(&multibody(dir.path(), &["sweep", "bouncing_ball", "--quick", "--repeats", "1", "--out", "."]));
    assert!(out.contains("(0 stopped early)") && out.contains("note: RK4 left out: the model has events"), "{out}");
    let points: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("bouncing_ball_work_precision.json")).unwrap()).unwrap();
    let points = points.as_array().unwrap();
    assert!(
        !points.is_empty() && points.iter().all(|p| p["failure"].is_null() && p["integrator"].as_str().is_some_and(|i| !i.starts_with("RK4"))),
        "{points:?}"
    );
}

/// A node budget spent while `inspect` builds the assemblies (past the derivation) is reported
/// as the budget, as `generate` reports it; it was reported as the emission meeting the
/// budget's placeholder ("symbol `node budget spent` has no value"), at a line of the robot's
/// model text that the URDF does not have. The budgets span the derivation's end on this tree.
#[test]
fn inspect_reports_a_budget_spent_past_the_derivation_as_the_budget() {
    let dir = tempfile::tempdir().unwrap();
    let tree = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/urdf/tree.urdf");
    for budget in ["35000", "40000", "45000"] {
        let out = multibody(dir.path(), &["inspect", tree, "--base", "floating", "--max-nodes", budget]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains(&format!("needs more than {budget} expression nodes, the node budget")), "{budget}: {err}");
        assert!(!err.contains("has no value"), "{budget}: {err}");
    }
}

/// An error found past the reading of a URDF robot names the file and the place in the robot's
/// model, with no line: the model is RON text made from the XML, whose lines are not the URDF's.
/// A RON model's is located in its file.
#[test]
fn a_urdf_robot_s_later_errors_point_at_no_line_of_another_text() {
    use generator::model::ErrorKind;
    let error = |model: &generator::model::Model| model.error(ErrorKind::Emission, "emit", "emit", "a later error".into(), "a fix".into()).to_string();
    let tree = fixture("urdf/tree.urdf");
    let robot = generator::model::source(std::path::Path::new(&tree)).unwrap().model().unwrap();
    let err = error(&robot);
    assert!(err.starts_with(&format!("error: {tree}: in emit: a later error")), "{err}");
    let a_line = (0..10).any(|d| err.contains(&format!("{tree}:{d}")));
    assert!(!err.contains("emit: Emit(") && !a_line, "no line of the model text: {err}");
    let cart = generator::model::load(concat!(env!("CARGO_MANIFEST_DIR"), "/models/cart_pendulum.ron")).unwrap();
    let err = error(&cart);
    assert!(err.contains("models/cart_pendulum.ron:") && err.contains("a later error"), "{err}");
}

/// A seam path that is not a Rust path is an option's mistake: said before the model is read,
/// naming the option (it was located at the model file's `emit` section, which does not hold it).
#[test]
fn a_seam_path_that_is_not_a_path_names_the_option() {
    let dir = tempfile::tempdir().unwrap();
    let out = multibody(dir.path(), &["generate", "no_such_model.ron", "--seam-path", "not a path", "-o", "x.rs"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.starts_with("error: --seam-path: `not a path` is not a Rust path"), "{err}");
    assert!(err.contains("help: give the seam crate's path") && !err.contains("no_such_model"), "{err}");
    assert!(!dir.path().join("x.rs").exists());
    // A path is taken.
    let out = multibody(dir.path(), &["generate", "cart_pendulum", "--seam-path", "runtime::seam", "-o", "cart.rs"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(std::fs::read_to_string(dir.path().join("cart.rs")).unwrap().contains("runtime::seam::"));
}

/// `--base`, `--gravity` and `--limits` given for a model that is not a URDF file were silently
/// ignored (a RON model sets its robot's in its `urdf` section): refused on every command,
/// naming the options given.
#[test]
fn robot_options_for_a_model_that_is_no_urdf_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for command in ["simulate", "compare", "sweep", "linearize", "inspect", "generate"] {
        let out = multibody(dir.path(), &[command, "cart_pendulum", "--base", "floating"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("--base is read for a URDF robot only, and `cart_pendulum` is not a URDF file"), "{command}: {err}");
    }
    let out = multibody(dir.path(), &["simulate", "three_body", "--gravity", "0,0,0", "--limits", "stop"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--gravity, --limits are read for a URDF robot only") && err.contains("urdf: Urdf("), "{err}");
    // A URDF robot takes them.
    let tree = fixture("urdf/tree.urdf");
    let text = ok(&multibody(dir.path(), &["inspect", &tree, "--base", "floating", "--gravity", "0,0,0"]));
    assert!(text.contains("base_qw"), "{text}");
}
