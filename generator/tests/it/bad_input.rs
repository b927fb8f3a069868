//! One test per class of bad input: each must give a clear, located error, never a panic.

use generator::formulation::{ignorable, mechanics};
use generator::model::{ErrorKind, ModelError, from_source};

fn scene1() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/cart_pendulum.ron")).unwrap()
}

fn scene2() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/three_body.ron")).unwrap()
}

/// Applies a textual edit that must change the file, loads it, and returns the error.
fn broken(src: &str, from: &str, to: &str) -> ModelError {
    assert!(src.contains(from), "test edit `{from}` not found");
    let text = src.replacen(from, to, 1);
    match from_source("models/broken.ron", &text) {
        Ok(model) => {
            // Some errors are found after loading (Definition 1).
            let mech = mechanics::derive(&model);
            let reports = ignorable::analyze(&model, &mech);
            ignorable::choose(&model, &reports).expect_err("the edited model should be rejected")
        }
        Err(e) => e,
    }
}

fn check(e: &ModelError, kind: ErrorKind, words: &[&str]) {
    let text = e.to_string();
    assert_eq!(e.kind, kind, "{text}");
    assert!(text.starts_with("error: models/broken.ron:"), "names the file: {text}");
    assert!(text.contains("help: "), "gives a fix: {text}");
    for w in words {
        assert!(text.contains(w), "`{w}` missing from: {text}");
    }
}

#[test]
fn malformed_ron_gives_line_and_column() {
    let e = broken(&scene1(), "coordinates: [\"theta1\", \"theta2\", \"x\"],", "coordinates: [\"theta1\" \"theta2\", \"x\"],");
    check(&e, ErrorKind::Syntax, &["malformed model"]);
    assert_eq!(e.location.unwrap().0, 14);
    let e = broken(&scene1(), "description:", "descripton:");
    check(&e, ErrorKind::Syntax, &["descripton"]);
}

#[test]
fn unknown_names_are_located_and_suggested() {
    let e = broken(&scene1(), "com: [\"0\", \"-l/2\", \"0\"]", "com: [\"0\", \"-lx/2\", \"0\"]");
    check(&e, ErrorKind::UnknownName, &["unknown name `lx`", "did you mean `l`", "bodies[1] (bar1).com[1]", "column 2"]);
    assert!(e.location.is_some());
}

#[test]
fn expression_syntax_errors_give_the_column() {
    let e = broken(&scene1(), "\"m1*l^2/12\", \"0\"", "\"m1*l^^2/12\", \"0\"");
    check(&e, ErrorKind::ExpressionSyntax, &["column 6", "m1*l^^2/12"]);
}

#[test]
fn wrong_vector_sizes() {
    let e = broken(&scene1(), "translation: [\"x\", \"0\", \"0\"]", "translation: [\"x\", \"0\"]");
    check(&e, ErrorKind::Dimension, &["3-vector", "2 entries", "frames[0] (cart).translation"]);
    let e = broken(&scene2(), "Diagonal([\"J1\", \"J2\", \"J2\"])", "Matrix([[\"J1\", \"0\"], [\"0\", \"J2\"]])");
    check(&e, ErrorKind::Dimension, &["3x3"]);
}

#[test]
fn body_on_unknown_frame() {
    let e = broken(&scene1(), "Body(name: \"bar2\", frame: \"bar2\"", "Body(name: \"bar2\", frame: \"bar3\"");
    check(&e, ErrorKind::UnknownFrame, &["`bar3`", "bodies[2] (bar2).frame"]);
}

#[test]
fn cycles_in_the_frame_tree() {
    let e = broken(&scene1(), "Frame(name: \"cart\", parent: \"world\"", "Frame(name: \"cart\", parent: \"bar2\"");
    check(&e, ErrorKind::FrameCycle, &["cycle", "cart", "bar1", "bar2"]);
}

#[test]
fn non_positive_mass() {
    let e = broken(&scene1(), "\"m2\": 1.0,", "\"m2\": -1.0,");
    check(&e, ErrorKind::NonPositiveMass, &["bar2", "not positive"]);
}

/// A shape's size that is not positive, a box without three sides, a coordinate in a size:
/// each located at its place in the body's `shape`.
#[test]
fn bad_shapes() {
    let e = broken(&scene1(), r#"Cylinder(radius: "0.03""#, r#"Cylinder(radius: "0.03 - l""#);
    check(&e, ErrorKind::BadValue, &["bodies[1] (bar1).shape.radius", "0.03 - l = -0.97", "not a positive number"]);
    assert_eq!(e.location.map(|(line, _)| line), Some(line_of(&scene1(), r#"Cylinder(radius: "0.03""#)), "{e}");
    let e = broken(&scene1(), r#"Box(size: ["0.4", "0.2", "0.2"])"#, r#"Box(size: ["0.4", "0.2"])"#);
    check(&e, ErrorKind::Dimension, &["bodies[0] (cart).shape.size", "three sides; 2 were given"]);
    let e = broken(&scene1(), r#"Box(size: ["0.4", "0.2", "0.2"])"#, r#"Box(size: ["0.4", "x", "0.2"])"#);
    assert!(e.to_string().contains("bodies[0] (cart).shape.size[1]") && e.location.is_some(), "{e}");
}

/// A unit for a name the model does not have, and a unit that is not short plain text (it is
/// shown in plots and pages): each located at its entry of `units`.
#[test]
fn bad_units() {
    let e = broken(&scene1(), r#""x": "m", "M": "kg""#, r#""y": "m", "M": "kg""#);
    check(&e, ErrorKind::UnknownName, &["units.y", "`y` has a unit but is neither a coordinate nor a parameter"]);
    assert!(e.location.is_some(), "{e}");
    let e = broken(&scene1(), r#""x": "m", "M": "kg""#, r#""x": "<script>", "M": "kg""#);
    check(&e, ErrorKind::BadValue, &["units.x", "not short plain text"]);
    assert_eq!(e.location.map(|(line, _)| line), Some(line_of(&scene1(), r#""x": "m", "M": "kg""#)), "{e}");
    let model = generator::model::from_source("models/cart_pendulum.ron", &scene1()).unwrap();
    assert_eq!((model.labelled("x"), model.labelled("g"), model.unit("theta1")), ("x [m]".to_string(), "g [m/s^2]".to_string(), Some("rad")));
}

#[test]
fn inertia_not_positive_semi_definite() {
    let e = broken(&scene2(), "\"Ixy\": 0.05", "\"Ixy\": 5.0");
    check(&e, ErrorKind::InertiaNotPsd, &["middle", "positive semi-definite", "Eq. (75)"]);
}

#[test]
fn wrong_number_of_quasi_velocities() {
    let e = broken(&scene1(), "full: [\"theta1' - theta2'\", \"x'\"]", "full: [\"theta1' - theta2'\"]");
    check(&e, ErrorKind::QuasiVelocityCount, &["1 quasi-velocities given", "3 - 1 = 2"]);
}

#[test]
fn declared_ignorable_that_is_not() {
    let e = broken(&scene1(), "ignorable: Declared([\"x\"])", "ignorable: Declared([\"theta1\", \"x\"])");
    check(&e, ErrorKind::NotIgnorable, &["`theta1` is declared ignorable but is not", "M[1][2]"]);
    // A spring on x breaks it through V.
    let e =
        broken(&scene1(), "Gravity(vector: [\"0\", \"-g\", \"0\"]),", "Gravity(vector: [\"0\", \"-g\", \"0\"]), Potential(name: \"tether\", expr: \"x^2\"),");
    check(&e, ErrorKind::NotIgnorable, &["`x`", "through V"]);
    // A force on x breaks it through Q.
    let e = broken(&scene1(), "{\"theta1\": \"tau\", \"theta2\": \"-tau\"}", "{\"theta1\": \"tau\", \"theta2\": \"-tau\", \"x\": \"tau\"}");
    check(&e, ErrorKind::NotIgnorable, &["generalized force"]);
}

#[test]
fn nonlinear_velocity_constraints() {
    let e = broken(&scene1(), "l*theta2'\"", "l*theta2'^2\"");
    check(&e, ErrorKind::NonlinearConstraint, &["not linear in the velocities"]);
    // Linear away from theta1' = 0 only: its second derivative vanishes there, its coefficient
    // does not lose the velocity.
    let e = broken(&scene1(), "l*cos(theta1 - theta2)*theta1'", "l*cos(theta1 - theta2)*abs(theta1')");
    check(&e, ErrorKind::NonlinearConstraint, &["not linear in the velocities", "coefficient of theta1'"]);
}

/// Generation derives on two threads (the ignorable coordinates on the second); with several
/// stages failing, it reports the one that runs first alone, as inspect does.
#[test]
fn with_two_stages_failing_generation_reports_the_first_as_inspect_does() {
    let not_ignorable = ("ignorable: Declared([\"x\"])", "ignorable: Declared([\"theta1\", \"x\"])");
    let kane_singular = ("full: [\"theta1' - theta2'\", \"x'\"]", "full: [\"theta1' - theta2'\", \"2*theta1' - 2*theta2'\"]");
    let cases = [
        (vec![not_ignorable, kane_singular], ErrorKind::NotIgnorable),
        (vec![kane_singular], ErrorKind::SingularQuasiVelocities),
        (vec![not_ignorable], ErrorKind::NotIgnorable),
    ];
    for (edits, kind) in cases {
        let mut text = scene1();
        for (from, to) in &edits {
            assert!(text.contains(from), "test edit `{from}` not found");
            text = text.replacen(from, to, 1);
        }
        let generated = from_source("models/broken.ron", &text)
            .and_then(|m| generator::generate(&m, &generator::emit::Options::from_model(&m)).map(|_| ()))
            .expect_err("refused");
        let inspected = from_source("models/broken.ron", &text).and_then(|m| generator::inspect(&m, false).map(|_| ())).expect_err("refused");
        assert_eq!(generated.kind, kind, "{edits:?}: {generated}");
        assert_eq!(generated.to_string(), inspected.to_string(), "{edits:?}");
    }
}

#[test]
fn inspect_and_generation_refuse_the_same_models_with_the_same_error() {
    let edits = [
        ("l*cos(theta1 - theta2)*theta1'", "l*cos(theta1 - theta2)*abs(theta1')"),
        ("full: [\"theta1' - theta2'\", \"x'\"]", "full: [\"theta1' - theta2'\", \"2*theta1' - 2*theta2'\"]"),
        ("\"tau\": 0.0,", "\"tau\": 0.0, \"_\": 1.0, \"u1\": 2.0,"),
        ("coordinates: [\"theta1\", \"theta2\", \"x\"],", "coordinates: [\"theta1\", \"theta2\", \"x\"],\n    time_functions: {\"F\": \"F(t) + 1\"},"),
    ];
    for (from, to) in edits {
        let src = scene1();
        assert!(src.contains(from), "test edit `{from}` not found");
        let text = src.replacen(from, to, 1);
        let generated = from_source("models/broken.ron", &text).and_then(|m| generator::generate(&m, &generator::emit::Options::from_model(&m)).map(|_| ()));
        let inspected = from_source("models/broken.ron", &text).and_then(|m| generator::inspect(&m, false).map(|_| ()));
        match (generated, inspected) {
            (Ok(()), Ok(())) => assert!(to.contains("\"_\""), "`{to}` should be refused"),
            (Err(g), Err(i)) => assert_eq!(g.to_string(), i.to_string(), "`{to}`"),
            (g, i) => panic!("`{to}`: generation {:?}, inspect {:?}", g.map_err(|e| e.to_string()), i.map_err(|e| e.to_string())),
        }
    }
}

#[test]
fn velocities_where_positions_are_expected() {
    let e = broken(&scene1(), "com: [\"0\", \"-l/2\", \"0\"]", "com: [\"0\", \"-l/2*theta1'\", \"0\"]");
    check(&e, ErrorKind::ExpressionSyntax, &["position-level"]);
}

#[test]
fn missing_initial_values() {
    let e = broken(&scene1(), ", \"x\": \"0.3\"", "");
    check(&e, ErrorKind::InitialState, &["no initial velocity for coordinate `x`"]);
}

#[test]
fn the_cli_exits_non_zero_with_the_message() {
    let dir = std::env::temp_dir().join(format!("gen-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("broken.ron");
    std::fs::write(&path, scene1().replacen("\"m2\": 1.0,", "\"m2\": 0.0,", 1)).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_generator")).arg("inspect").arg(&path).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("broken.ron:") && err.contains("not positive") && err.contains("help:"), "{err}");
    // A labelled excerpt of the file, without colour codes on a pipe.
    assert!(err.contains("Body(name: \"bar2\", frame: \"bar2\", mass: \"m2\"") && err.contains("╰──"), "{err}");
    assert!(!err.contains('\u{1b}'), "no colour codes when stderr is not a terminal: {err}");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_generator")).arg("inspect").arg(dir.join("missing.ron")).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read the file"));
}

fn run_generator(args: &[&std::ffi::OsStr]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_generator")).args(args).output().unwrap()
}

#[test]
fn generation_writes_the_module_and_a_summary_or_a_clear_error() {
    let dir = std::env::temp_dir().join(format!("gen-out-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/cart_pendulum.ron"));
    let out_path = dir.join("cart_pendulum.rs");
    let out = run_generator(&[model.as_os_str(), "-o".as_ref(), out_path.as_os_str()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let summary = String::from_utf8_lossy(&out.stderr);
    for w in ["m = 3, r = 1, p = 2, s = 1", "reduced_volterra", "5 states", "lagrange::rhs", "kane::rhs", "ops", "derived in"] {
        assert!(summary.contains(w), "`{w}` missing from the summary: {summary}");
    }
    // Every stage of the derivation is named with its time, the recursions over the tree of
    // frames and the hand-off to the emitting thread too.
    let stages = summary.lines().find(|l| l.contains("derived in")).unwrap();
    for stage in ["mechanics", "ignorable", "kane", "reduced", "formulations", "trees", "handoff"] {
        assert!(stages.contains(&format!("{stage} ")), "`{stage}` missing from the derivation's stages: {stages}");
    }
    let code = std::fs::read_to_string(&out_path).unwrap();
    assert!(code.contains("pub fn rhs(") && code.starts_with("// Generated by `generator` from cart_pendulum.ron"));
    // The same bytes on stdout.
    let out = run_generator(&[model.as_os_str()]);
    assert_eq!(String::from_utf8_lossy(&out.stdout), code);
    // Unknown options and formulations are refused with the usage.
    let out = run_generator(&[model.as_os_str(), "--fast".as_ref()]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("unexpected argument '--fast'"));
    let out = run_generator(&[model.as_os_str(), "--formulations".as_ref(), "hamilton".as_ref()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("invalid value 'hamilton'") && err.contains("reduced_volterra"), "{err}");
    // A repeated -o is an error, not the last one winning.
    let out = run_generator(&[model.as_os_str(), "-o".as_ref(), out_path.as_os_str(), "-o".as_ref(), out_path.as_os_str()]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("cannot be used multiple times"));
}

#[test]
fn the_command_line_speaks_like_a_rust_cli() {
    let out = run_generator(&["--help".as_ref()]);
    let help = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && help.contains("Usage: generator") && help.contains("inspect") && help.contains("--max-lets <N>"), "{help}");
    let out = run_generator(&["--version".as_ref()]);
    assert!(out.status.success() && String::from_utf8_lossy(&out.stdout).starts_with("generator "));
    let out = run_generator(&["inspect".as_ref(), "--help".as_ref()]);
    assert!(out.status.success() && String::from_utf8_lossy(&out.stdout).contains("--latex"));
    let out = run_generator(&[]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("a model file is needed"));
}

#[test]
fn output_never_destroys_a_model_or_a_file() {
    let dir = std::env::temp_dir().join(format!("gen-guard-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("m.ron");
    std::fs::write(&model, scene1()).unwrap();
    // The model itself, or any .ron file, is not an output unless forced.
    for target in [model.clone(), dir.join("other.ron")] {
        let out = run_generator(&[model.as_os_str(), "-o".as_ref(), target.as_os_str()]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("help:"), "{err}");
    }
    assert_eq!(std::fs::read_to_string(&model).unwrap(), scene1());
    assert!(!dir.join("other.ron").exists());
    // The model itself stays refused with --force, by any path to it.
    let link = dir.join("link.rs");
    std::os::unix::fs::symlink(&model, &link).unwrap();
    for target in [model.clone(), dir.join("./m.ron"), link] {
        let out = run_generator(&[model.as_os_str(), "-o".as_ref(), target.as_os_str(), "--force".as_ref()]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && (err.contains("model file itself") || err.contains("which this run reads")), "{err}");
    }
    assert_eq!(std::fs::read_to_string(&model).unwrap(), scene1());
    let forced = dir.join("forced.ron");
    let out = run_generator(&[model.as_os_str(), "-o".as_ref(), forced.as_os_str(), "--force".as_ref()]);
    assert!(out.status.success() && std::fs::read_to_string(&forced).unwrap().contains("pub fn rhs("));
    // A write that fails (the target is a directory) leaves the target as it was, and no
    // temporary file behind.
    let blocked = dir.join("blocked.rs");
    std::fs::create_dir_all(blocked.join("inside")).unwrap();
    let out = run_generator(&[model.as_os_str(), "-o".as_ref(), blocked.as_os_str()]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("cannot write"));
    assert!(blocked.join("inside").is_dir());
    let leftovers: Vec<_> = std::fs::read_dir(&dir).unwrap().filter_map(|e| e.ok()).filter(|e| e.file_name().to_string_lossy().ends_with(".tmp")).collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_closed_pipe_ends_the_generator_quietly() {
    use std::io::Read;
    use std::process::{Command, Stdio};
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/three_body.ron");
    let mut child = Command::new(env!("CARGO_BIN_EXE_generator")).arg(model).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    // Read one byte, then close the pipe (as `| head -c 1` does).
    let mut stdout = child.stdout.take().unwrap();
    let mut one = [0u8; 1];
    stdout.read_exact(&mut one).unwrap();
    drop(stdout);
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "exit {:?}: {}", out.status.code(), String::from_utf8_lossy(&out.stderr));
    assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
}

#[test]
fn dropping_an_ignorable_coordinate_that_the_equations_need_is_refused() {
    // The rolling disk's heading psi is ignorable, but the rolling constraint depends on it.
    let model = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/rolling_disk.ron"));
    let out = run_generator(&[model.as_os_str(), "--drop-ignorable".as_ref()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("`psi` cannot leave the state") && err.contains("help: set `integrate_ignorable: true`"), "{err}");
}

#[test]
fn quasi_velocities_dependent_on_the_constraints_are_refused_naming_the_rows() {
    // Scene 1's reduced quasi-velocity replaced by the wheel constraint itself: [Y_NI; M'; a] is
    // singular at every state.
    let src = scene1().replacen("reduced: [\"theta2' - theta1'\"]", "reduced: [\"l*cos(theta1 - theta2)*theta1' + l*theta2'\"]", 1);
    assert_ne!(src, scene1(), "test edit not applied");
    let model = from_source("models/broken.ron", &src).unwrap();
    let options = generator::emit::Options::from_model(&model);
    let e = generator::generate(&model, &options).expect_err("a singular choice must not generate");
    check(
        &e,
        ErrorKind::SingularQuasiVelocities,
        &["constraint `wheel` depends on the other rows", "quasi_velocities.reduced", "choose quasi-velocities independent"],
    );
}

#[test]
fn deep_and_huge_expressions_are_refused_with_the_limit() {
    for (what, expr) in [
        ("parentheses", format!("{}l{}", "(".repeat(10_000), ")".repeat(10_000))),
        ("signs", format!("{}l", "-".repeat(50_000))),
        ("calls", format!("{}l{}", "sin(".repeat(300), ")".repeat(300))),
    ] {
        let e = broken(&scene1(), "\"m1*l^2/12\", \"0\"", &format!("\"{expr}\", \"0\""));
        let text = e.to_string();
        assert_eq!(e.kind, ErrorKind::ExpressionSyntax, "{what}: {text}");
        assert!(text.contains("nested more than 200 levels") || text.contains("bytes, more than the 20000"), "{what}: {text}");
        // The message quotes an excerpt, not the whole input.
        assert!(text.len() < 600, "{what}: {} bytes of error", text.len());
    }
    let e = broken(&scene1(), "\"m1*l^2/12\", \"0\"", "\"m1*l^1e18\", \"0\"");
    check(&e, ErrorKind::ExpressionSyntax, &["exponent", "larger than 1000"]);
}

#[test]
fn numbers_outside_f64_are_refused_at_parse_time() {
    for number in ["1e10000", "1e999999999", "1e400"] {
        let e = broken(&scene1(), "\"m1*l^2/12\", \"0\"", &format!("\"m1*{number}\", \"0\""));
        check(&e, ErrorKind::ExpressionSyntax, &["malformed number", number]);
    }
    let digits = "9".repeat(50_000);
    let e = broken(&scene1(), "\"m1*l^2/12\", \"0\"", &format!("\"m1*{digits}\", \"0\""));
    assert_eq!(e.kind, ErrorKind::ExpressionSyntax);
}

#[test]
fn time_functions_that_call_themselves_are_a_cycle() {
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/satellite_boom.ron")).unwrap();
    let from = "\"F\": \"-0.018*sin(0.089*t) + 0.012*cos(0.0485*t)\"";
    let e = broken(&src, from, "\"F\": \"F(t) + 1\"");
    check(&e, ErrorKind::Cycle, &["`F` calls itself", "F -> F"]);
    let e = broken(&src, from, "\"F\": \"G(t)\", \"G\": \"2*F(t)\"");
    check(&e, ErrorKind::Cycle, &["calls itself"]);
}

#[test]
fn model_names_must_be_identifiers() {
    for name in ["cp\\npub fn evil() -> u32 { 7 }\\n//", "cart\\rpendulum", "1cart", ""] {
        let e = broken(&scene1(), "name: \"cart_pendulum\"", &format!("name: \"{name}\""));
        check(&e, ErrorKind::BadValue, &["is not an identifier"]);
    }
}

#[test]
fn values_without_a_finite_number_are_refused() {
    let e = broken(&scene1(), "t_end: 50.0", "t_end: inf");
    check(&e, ErrorKind::BadValue, &["not a run"]);
    let e = broken(&scene1(), "\"theta1\": \"0.5\"", "\"theta1\": \"sqrt(-1)\"");
    check(&e, ErrorKind::InitialState, &["initial value of `theta1`", "not a finite number"]);
    let e = broken(&scene1(), "\"x\": \"0.3\"", "\"x\": \"ln(0)\"");
    check(&e, ErrorKind::InitialState, &["initial rate of `x`", "not a finite number"]);
}

#[test]
fn a_key_given_twice_is_an_error() {
    let e = broken(&scene1(), "\"M\": 2.0,", "\"M\": 2.0, \"M\": 3.0,");
    check(&e, ErrorKind::Syntax, &["the key `M` is given twice"]);
}

#[test]
fn an_initial_state_off_its_constraint_is_refused() {
    let e = broken(&scene1(), "\"theta2\": \"-cos(theta1 - theta2)*theta1'\"", "\"theta2\": \"0.1\"");
    check(&e, ErrorKind::InitialState, &["in initial.qdot", "the initial rates violate the velocity constraint `wheel`"]);
}

#[test]
fn a_byte_order_mark_is_accepted_and_bad_bytes_are_located_without_echoing_them() {
    let dir = std::env::temp_dir().join(format!("bad-bytes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let write = |name: &str, bytes: &[u8]| {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    };
    // A UTF-8 byte-order mark (written by some editors) is not part of the model.
    let mut with_bom = b"\xEF\xBB\xBF".to_vec();
    with_bom.extend_from_slice(scene1().as_bytes());
    let model = generator::model::load(write("bom.ron", &with_bom)).unwrap();
    assert_eq!(model.name, "cart_pendulum");
    // Latin-1 in a description: the line and column of the first bad byte.
    let latin1 = scene1().replacen("description: \"Cart", "description: \"Caf\u{e9}", 1).replace('\u{e9}', "\u{1}");
    let mut bytes = latin1.into_bytes();
    let at = bytes.iter().position(|b| *b == 1).unwrap();
    bytes[at] = 0xE9;
    let e = generator::model::load(write("latin1.ron", &bytes)).unwrap_err();
    let text = e.to_string();
    assert!(text.contains("latin1.ron:5:") && text.contains("not UTF-8") && text.contains("0xE9") && text.contains("help:"), "{text}");
    // Binary garbage: one short sentence, not the bytes.
    let mut garbage: Vec<u8> = (0..4096u32).map(|i| (i.wrapping_mul(2654435761) >> 13) as u8).collect();
    garbage[100] = 0;
    let e = generator::model::load(write("garbage.ron", &garbage)).unwrap_err();
    let text = e.to_string();
    assert!(text.contains("binary") && text.len() < 300, "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The 1-based line of the first line of `src` containing `text`.
fn line_of(src: &str, text: &str) -> usize {
    src.lines().position(|l| l.contains(text)).unwrap_or_else(|| panic!("`{text}` not in the model")) + 1
}

#[test]
fn errors_point_at_the_value_they_are_about_not_at_the_first_equal_text() {
    let src = scene1();
    // bar1 and bar2 have the same text for mass-like pieces: the error is on bar2's line.
    let e = broken(&src, "Body(name: \"bar2\", frame: \"bar2\", mass: \"m2\"", "Body(name: \"bar2\", frame: \"bar2\", mass: \"0\"");
    assert_eq!(e.location.unwrap().0, line_of(&src, "Body(name: \"bar2\""), "{e}");
    // A two-entry centre of mass on bar2, not bar1 (whose com reads the same).
    let e = broken(&src, "frame: \"bar2\", mass: \"m2\", com: [\"0\", \"-l/2\", \"0\"]", "frame: \"bar2\", mass: \"m2\", com: [\"0\", \"-l/2\"]");
    assert_eq!(e.kind, ErrorKind::Dimension, "{e}");
    assert_eq!(e.location.unwrap().0, line_of(&src, "Body(name: \"bar2\""), "{e}");
    // A coordinate wrongly declared ignorable: at `ignorable`, on the coordinate's name there.
    let e = broken(&src, "ignorable: Declared([\"x\"])", "ignorable: Declared([\"x\", \"theta1\"])");
    assert_eq!(e.kind, ErrorKind::NotIgnorable, "{e}");
    let (line, col) = e.location.unwrap();
    assert_eq!(line, line_of(&src, "ignorable: Declared"), "{e}");
    assert_eq!(col, "    ignorable: Declared([\"x\", ".len() + 1, "{e}");
    // An expression error: the column of the bad character inside the string.
    let e = broken(&src, "\"m1*l^2/12\", \"0\"", "\"m1*l^2/12 + L\", \"0\"");
    let (line, col) = e.location.unwrap();
    let bad = src.lines().nth(line - 1).unwrap();
    assert!(bad.contains("m1*l^2/12"), "{e}");
    assert_eq!(&bad.replacen("m1*l^2/12\"", "m1*l^2/12 + L\"", 1)[col - 1..col], "L", "{e}");
    // `L` with `l` defined: the same name in another case is the suggestion.
    assert!(e.to_string().contains("did you mean `l`?"), "{e}");
}

#[test]
fn constants_beyond_f64_are_located_at_the_extreme_number() {
    let src = scene1();
    let text = src.replacen("com: [\"0\", \"-l/2\", \"0\"]", "com: [\"0\", \"-l/2*1e200\", \"0\"]", 1);
    let model = from_source("models/broken.ron", &text).unwrap();
    let e = generator::generate(&model, &generator::emit::Options::from_model(&model)).unwrap_err();
    check(&e, ErrorKind::Emission, &["10^", "not a finite f64", "bodies[1].com[1]"]);
    let (line, col) = e.location.unwrap();
    assert_eq!(&text.lines().nth(line - 1).unwrap()[col - 1..col + 4], "1e200", "{e}");
    assert!(e.to_string().len() < 400, "{e}");
}

#[test]
fn an_expensive_expression_stays_within_the_simplifier_s_work_budget() {
    // (theta1 + theta2)^30 in a centre of mass: its Fourier form has hundreds of harmonics per
    // entry. The simplifier stops at its term and work limits, keeps those nodes as built
    // (correct, only less compact), reports them, and generation finishes.
    let text = scene1().replacen("com: [\"0\", \"-l/2\", \"0\"]", "com: [\"0\", \"-l/2 + (theta1 + theta2)^30/1000\", \"0\"]", 1);
    let model = from_source("models/heavy.ron", &text).unwrap();
    let out = generator::generate(&model, &generator::emit::Options::from_model(&model)).unwrap();
    let report = &out.summary.simplifier;
    let limits = generator::symbolic::FourierLimits::default();
    assert!(report.work <= limits.max_work + limits.max_terms as u64 * limits.max_terms as u64, "{report:?}");
    assert!(report.over_term_limit > 0 || report.work_limit_reached, "the limits were reached: {report:?}");
    assert!(out.summary.work_counters().contains("kept as built"));
    assert!(!out.code.contains("NAN"));
}

/// `-o` onto device nodes (`mknod` copies in a temporary folder, never the real `/dev`; the
/// tests run as root, as CI does), onto a symlink to one, and `inspect` of an endless device:
/// written through or refused, never replaced, never read without a bound.
#[cfg(unix)]
#[test]
fn devices_and_symlinks_are_written_through_never_replaced() {
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().unwrap();
    let model = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/cart_pendulum.ron"));
    let node = |name: &str, minor: &str| {
        let p = dir.path().join(name);
        assert!(std::process::Command::new("mknod").arg(&p).args(["c", "1", minor]).status().unwrap().success(), "mknod needs root");
        p
    };
    let (null, zero, full) = (node("null", "3"), node("zero", "5"), node("full", "7"));
    let is_char = |p: &std::path::Path| std::fs::symlink_metadata(p).unwrap().file_type().is_char_device();
    let out = run_generator(&[model.as_os_str(), "-o".as_ref(), null.as_os_str()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stderr).contains("wrote through"));
    let out = run_generator(&[model.as_os_str(), "-o".as_ref(), full.as_os_str()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("cannot write") && err.contains("No space left"), "{err}");
    let link = dir.path().join("stdout.rs");
    std::os::unix::fs::symlink(&null, &link).unwrap();
    let out = run_generator(&[model.as_os_str(), "-o".as_ref(), link.as_os_str(), "--quiet".as_ref()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(is_char(&null) && is_char(&zero) && is_char(&full));
    assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
    // An endless model file: the size bound, named, in well under a second of reading.
    let out = run_generator(&["inspect".as_ref(), zero.as_os_str()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("more than 16777216 bytes") && err.contains("help:"), "{err}");
}

/// A line break in the model's file name or folder cannot reach the module as code: the
/// header comment stays one line and the module parses with the same items as the plain one.
#[cfg(unix)]
#[test]
fn control_characters_in_paths_stay_inside_one_comment() {
    let dir = tempfile::tempdir().unwrap();
    let evil = dir.path().join("x\n[target.'cfg(unix)'.dependencies]\nevil = 1");
    std::fs::create_dir_all(&evil).unwrap();
    let model = evil.join("m\nfn injected() {}\n.ron");
    std::fs::write(&model, scene1()).unwrap();
    let out_path = dir.path().join("out.rs");
    let out = run_generator(&[model.as_os_str(), "-o".as_ref(), out_path.as_os_str(), "--quiet".as_ref()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let code = std::fs::read_to_string(&out_path).unwrap();
    let first = code.lines().next().unwrap();
    assert!(first.starts_with("// Generated by `generator` from m\\nfn injected() {}\\n.ron"), "{first}");
    let file = syn::parse_file(&code).unwrap();
    assert!(!code.lines().any(|l| l.starts_with("fn injected")));
    let plain = run_generator(&[std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/cart_pendulum.ron")).as_os_str()]);
    let plain = syn::parse_file(&String::from_utf8(plain.stdout).unwrap()).unwrap();
    assert_eq!(file.items.len(), plain.items.len());
}

/// Run settings that would allocate without bound, integrate nothing, or overflow are refused
/// at load, located on the field, naming the limit.
#[test]
fn run_settings_must_describe_a_run_that_fits_in_memory() {
    let src = scene1();
    for (t_end, dt_out, words) in [
        ("1e300", "0.01", &["more than the 1000001", "dt_out"][..]),
        ("50.0", "1e-300", &["more than the 1000001"][..]),
        ("1e7", "0.01", &["1.000e9 output times"][..]),
        ("1.0", "100.0", &["longer than the run"][..]),
        ("0.0", "0.01", &["is not a run"][..]),
    ] {
        let e = broken(&src, "Simulation(t_end: 50.0, dt_out: 0.01, paper: true)", &format!("Simulation(t_end: {t_end}, dt_out: {dt_out}, paper: true)"));
        check(&e, ErrorKind::BadValue, words);
        let line = src.lines().position(|l| l.contains("Simulation(")).unwrap() + 1;
        assert_eq!(e.location.unwrap().0, line, "{e}");
    }
}

/// A model far too large to derive (a pendulum on a cart with 200 links) ends with the node
/// budget's error, naming the budget and the option that raises it, long before memory runs
/// out; a smaller budget stops a small model the same way, and the default admits the
/// documented 50-link chain (the scaling benchmark).
#[test]
fn a_model_too_large_to_derive_ends_with_the_budget_error() {
    use generator::model::examples::n_link_pendulum_on_cart;
    let huge = n_link_pendulum_on_cart(200).build().unwrap();
    // No unwinding on the way (a library under `panic = "abort"` gets the error too): a hook
    // counts this thread's panics.
    let here = std::thread::current().id();
    let panics = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let counted = panics.clone();
    let previous = std::sync::Arc::new(std::panic::take_hook());
    let chained = previous.clone();
    std::panic::set_hook(Box::new(move |info| {
        if std::thread::current().id() == here || std::thread::current().name() == Some("emit") {
            counted.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        }
        chained(info);
    }));
    let e = generator::generate(&huge, &generator::emit::Options::from_model(&huge)).unwrap_err();
    assert_eq!(panics.load(std::sync::atomic::Ordering::SeqCst), 0, "the budget unwound");
    assert_eq!(e.kind, ErrorKind::Budget, "{e}");
    let text = e.to_string();
    assert!(text.contains("more than 1000000 expression nodes") && text.contains("--max-nodes"), "{text}");
    // The command line says the same, with no panic message.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("three_body.ron");
    std::fs::write(&path, scene2()).unwrap();
    let out = run_generator(&["--max-nodes".as_ref(), "3000".as_ref(), path.as_os_str()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("needs more than 3000 expression nodes") && !err.contains("panicked"), "{err}");
}

/// A coordinate that moves nothing makes every mass matrix singular at every state: refused at
/// generation, naming the coordinate, located on it (not a "singular configuration" at t = 0).
#[test]
fn a_coordinate_that_moves_no_body_is_refused_by_name() {
    let src = scene1()
        .replace("coordinates: [\"theta1\", \"theta2\", \"x\"],", "coordinates: [\"theta1\", \"theta2\", \"x\", \"z\"],")
        .replace("full: [\"theta1' - theta2'\", \"x'\"],", "full: [\"theta1' - theta2'\", \"x'\", \"z'\"],")
        .replace("reduced: [\"theta2' - theta1'\"],", "reduced: [\"theta2' - theta1'\", \"z'\"],")
        .replace("q: {\"theta1\": \"0.5\", \"theta2\": \"1.0\", \"x\": \"0\"},", "q: {\"theta1\": \"0.5\", \"theta2\": \"1.0\", \"x\": \"0\", \"z\": \"0\"},")
        .replace("\"x\": \"0.3\"},", "\"x\": \"0.3\", \"z\": \"0\"},");
    let model = from_source("models/broken.ron", &src).expect("the file itself is well-formed");
    let e = generator::formulation::derive(&model, &generator::formulation::Request::all()).unwrap_err();
    check(&e, ErrorKind::SingularQuasiVelocities, &["coordinate `z` moves no body", "singular at every state", "coordinates[3]"]);
    assert_eq!(e.location.unwrap().0, 14, "{e}");
    assert!(generator::generate(&model, &generator::emit::Options::from_model(&model)).is_err());
}

/// A model written on one line (minified, or by a script), its error past column 65535: the
/// excerpt shows the part of the line around the error, never a panic (the renderer pads to
/// the column, and Rust's formatting panics on a width past 65535). Every class of error of
/// this file, and every model of `models/` with a misspelled field.
#[test]
fn errors_on_a_wide_line_render_an_excerpt_around_the_column() {
    let edits: [(fn() -> String, &str, &str); 14] = [
        (scene1, "coordinates: [\"theta1\", \"theta2\", \"x\"],", "coordinates: [\"theta1\" \"theta2\", \"x\"],"),
        (scene1, "description:", "descripton:"),
        (scene1, "com: [\"0\", \"-l/2\", \"0\"]", "com: [\"0\", \"-lx/2\", \"0\"]"),
        (scene1, "\"m1*l^2/12\", \"0\"", "\"m1*l^^2/12\", \"0\""),
        (scene1, "translation: [\"x\", \"0\", \"0\"]", "translation: [\"x\", \"0\"]"),
        (scene1, "Body(name: \"bar2\", frame: \"bar2\"", "Body(name: \"bar2\", frame: \"bar3\""),
        (scene1, "Frame(name: \"cart\", parent: \"world\"", "Frame(name: \"cart\", parent: \"bar2\""),
        (scene1, "\"m2\": 1.0,", "\"m2\": -1.0,"),
        (scene2, "\"Ixy\": 0.05", "\"Ixy\": 5.0"),
        (scene1, "full: [\"theta1' - theta2'\", \"x'\"]", "full: [\"theta1' - theta2'\"]"),
        (scene1, "ignorable: Declared([\"x\"])", "ignorable: Declared([\"theta1\", \"x\"])"),
        (scene1, "l*theta2'\"", "l*theta2'^2\""),
        (scene1, "com: [\"0\", \"-l/2\", \"0\"]", "com: [\"0\", \"-l/2*theta1'\", \"0\"]"),
        (scene1, ", \"x\": \"0.3\"", ""),
    ];
    let one_line = |text: &str| {
        let without_comments: String = text.lines().map(|l| l.split("//").next().unwrap()).collect::<Vec<_>>().join(" ");
        without_comments.replacen("Model(", &format!("Model({}", " ".repeat(70_000)), 1)
    };
    let mut cases: Vec<String> = edits.iter().map(|(scene, from, to)| one_line(&scene()).replacen(from, to, 1)).collect();
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../models");
    for entry in std::fs::read_dir(dir).unwrap() {
        let text = std::fs::read_to_string(entry.unwrap().path()).unwrap();
        cases.push(one_line(&text).replacen("description:", "descripton:", 1));
    }
    for (k, text) in cases.iter().enumerate() {
        assert!(!text.contains('\n'));
        let e = match from_source("models/broken.ron", text) {
            Ok(model) => {
                let mech = mechanics::derive(&model);
                ignorable::choose(&model, &ignorable::analyze(&model, &mech)).expect_err("refused")
            }
            Err(e) => e,
        };
        let (line, column) = e.location.unwrap_or_else(|| panic!("case {k}: located: {e}"));
        assert!(line == 1 && column > 65_535, "case {k}: at {line}:{column}: {e}");
        let report = e.render(false);
        assert!(report.contains(&format!("models/broken.ron:1:{column}")), "case {k}: {report}");
        assert!(report.contains(&format!("╭─[models/broken.ron:1:{column}]")), "case {k}: {report}");
        // The excerpt: line 1, cut on both sides, narrower than the line, with its label.
        assert!(report.contains(" 1 │ …") && report.contains("╰──"), "case {k}: {report}");
        assert!(report.lines().all(|l| l.chars().count() < 400), "case {k}: {report}");
    }
}

/// Errors that pointed at the wrong place or blamed the wrong thing (the issue "Every path
/// works"): a wrong count in `quasi_velocities.reduced` is located there, with no ignorable
/// coordinate too; a quaternion without its unit norm is blamed on the missing constraint, which
/// the fix writes out; an inertia no rigid body has (Ixx + Iyy < Izz) is refused.
#[test]
fn errors_name_the_place_and_the_fault() {
    let text = scene1().replacen("ignorable: Declared([\"x\"])", "ignorable: Declared([])", 1);
    let edited = text.replacen("reduced: [\"theta2' - theta1'\"]", "reduced: [\"theta2' - theta1'\", \"x'\", \"theta1'\"]", 1);
    let model = from_source("models/broken.ron", &edited).unwrap();
    let e = generator::formulation::derive(&model, &generator::formulation::Request::all()).expect_err("refused");
    check(&e, ErrorKind::QuasiVelocityCount, &["in quasi_velocities.reduced", "3 quasi-velocities given"]);
    let line = text.lines().position(|l| l.contains("reduced: [")).unwrap() + 1;
    assert_eq!(e.location.unwrap().0, line, "{e}");

    let tumbling = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/tumbling_body.ron")).unwrap();
    let e = broken(&tumbling, "Position(name: \"unit\", expr: \"e0^2 + e1^2 + e2^2 + e3^2 - 1\"),", "");
    check(
        &e,
        ErrorKind::QuasiVelocityCount,
        &["quaternion (e0, e1, e2, e3) of frame `body` has no unit-norm constraint", "Position(name: \"unit\", expr: \"e0^2 + e1^2 + e2^2 + e3^2 - 1\")"],
    );
    let line = tumbling.lines().position(|l| l.contains("Quaternion(")).unwrap() + 1;
    assert_eq!(e.location.unwrap().0, line, "{e}");

    let e = broken(&scene2(), "Diagonal([\"J1\", \"J2\", \"J2\"])", "Diagonal([\"J1\", \"J1\", \"3*J1\"])");
    check(&e, ErrorKind::InertiaNotPsd, &["no rigid body's", "triangle inequality"]);
    // On the edge (a thin rod, a flat plate) it is a body.
    from_source("models/ok.ron", &scene2().replacen("Diagonal([\"J1\", \"J2\", \"J2\"])", "Diagonal([\"J1\", \"J1\", \"2*J1\"])", 1)).unwrap();
}

#[test]
fn an_angular_velocity_of_no_body_lists_the_bodies_in_order() {
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/satellite_boom.ron")).unwrap();
    let e = broken(&src, "full: [\"omega_x(satellite)\"", "full: [\"omega_x(satelite)\"");
    // The bodies sorted by name, whatever the order of the map they are kept in.
    check(&e, ErrorKind::UnknownName, &["`satelite` is not a body (bodies: satellite, tip)"]);
}
