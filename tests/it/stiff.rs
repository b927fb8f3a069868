//! The stiff extreme: a pendulum carrying a mass on a stiff damped spring (`models/
//! stiff_pendulum.ron`). At k = 1e8 the spring's mode is at 1.4e4 rad/s (damping ratio 5): DOPRI5 is held to
//! steps of about 2e-4 s by stability, the Rosenbrock method with the exact Jacobian is not,
//! and both give the same slow motion; the energy balance (E = T + V - W with the damper's
//! work W) holds for both as the tolerance tightens.

use runtime::compare::{Reference, Run, run_with};
use runtime::integrate::{Method, Settings};
use runtime::system::Drift;
use seam::FormulationKind;

/// The committed module with its spring stiffness set to `k`.
fn with_stiffness(k: f64) -> generated::Model {
    let mut model = generated::find("stiff_pendulum").unwrap();
    let at = model.parameter_index("k").unwrap();
    model.default_params[at] = k;
    model
}

fn run(model: &generated::Model, form: &str, method: Method, tol: f64) -> Run {
    let s = Settings { method, rtol: tol, atol: tol, h_max: 0.5, ..Settings::default() };
    let kind = FormulationKind::from_name(form).unwrap();
    run_with(model, &Reference::of(model).unwrap(), kind, &s, 1, Drift::None).unwrap_or_else(|e| panic!("{form} {method}: {e}"))
}

#[test]
fn the_implicit_method_takes_far_fewer_steps_at_the_same_slow_motion() {
    let model = with_stiffness(1e8);
    for form in ["kane", "reduced_volterra"] {
        let explicit = run(&model, form, Method::Dopri5, 1e-4);
        let implicit = run(&model, form, Method::Rosenbrock23, 1e-4);
        let (e, i) = (&explicit.record, &implicit.record);
        assert!(e.steps > 10 * i.steps, "{form}: DOPRI5 {} steps against ROS23 {}", e.steps, i.steps);
        assert!(e.rhs_calls > 5 * i.rhs_calls, "{form}: DOPRI5 {} calls against ROS23 {}", e.rhs_calls, i.rhs_calls);
        // The swing agrees (the spring's stretch is m g / k, 5e-8 m).
        let (a, b) = (explicit.invariants.coordinates.last().unwrap(), implicit.invariants.coordinates.last().unwrap());
        assert!((a[0] - b[0]).abs() < 2e-3, "{form}: th {} against {}", a[0], b[0]);
    }
}

/// The energy balance `T + V - W` (W the damper's work) holds as the tolerance tightens, for
/// both methods: the stiff damper's dissipation is integrated, not lost.
#[test]
fn the_energy_balance_holds_at_tight_tolerances() {
    let model = with_stiffness(1e6);
    for method in [Method::Dopri5, Method::Rosenbrock23] {
        let (loose, tight) = (run(&model, "kane", method, 1e-4).record, run(&model, "kane", method, 1e-7).record);
        eprintln!("{method}: relative energy error {:e} at 1e-4, {:e} at 1e-7", loose.energy_error_rel, tight.energy_error_rel);
        assert!(tight.energy_error_rel < 1e-3, "{method}: {:e}", tight.energy_error_rel);
        assert!(tight.energy_error_rel < loose.energy_error_rel / 10.0, "{method}: {:e} against {:e}", tight.energy_error_rel, loose.energy_error_rel);
    }
}

/// DOPRI5's cost grows with sqrt(k) (its stable step shrinks with the spring's period); the
/// Rosenbrock method's grows far slower (about k^0.25: its error estimate still sees the
/// stiff mode, see docs/work-precision.md).
#[test]
fn explicit_cost_grows_with_stiffness_and_implicit_cost_does_not() {
    let steps = |k: f64, method| run(&with_stiffness(k), "kane", method, 1e-4).record.steps;
    let (e6, e8) = (steps(1e6, Method::Dopri5), steps(1e8, Method::Dopri5));
    let (i6, i8) = (steps(1e6, Method::Rosenbrock23), steps(1e8, Method::Rosenbrock23));
    let (explicit, implicit) = (e8 as f64 / e6 as f64, i8 as f64 / i6 as f64);
    assert!(explicit > 7.0, "DOPRI5: {e6} steps at 1e6, {e8} at 1e8");
    assert!(implicit < explicit / 2.0, "ROS23: {i6} steps at 1e6, {i8} at 1e8; DOPRI5 grew {explicit}x");
}

/// The stiff pendulum does not read `t` (the seam says so): the Rosenbrock method skips its
/// `df/dt` difference, one right-hand side per Jacobian, with the same steps and states (the
/// difference of a function that does not read `t` is exactly zero).
#[test]
fn the_rosenbrock_method_skips_df_dt_for_a_model_that_does_not_read_t() {
    use runtime::integrate::integrate_with_jacobian;
    use runtime::system::System;
    let model = with_stiffness(1e6);
    let form = model.formulation(FormulationKind::Kane).unwrap();
    assert!(!form.depends_on_time);
    assert!(generated::find("satellite_boom").unwrap().formulations.iter().all(|f| f.depends_on_time), "scene 3's F(t) reads t");
    let r = Reference::of(&model).unwrap();
    let (sys, y0) = System::start(&model, FormulationKind::Kane, r.params.clone(), &r.q0, &r.qd0).unwrap();
    let times = r.times().unwrap();
    let run = |time_independent: bool| {
        let s = Settings { method: Method::Rosenbrock23, rtol: 1e-6, atol: 1e-6, h_max: 0.5, time_independent, ..Settings::default() };
        let mut exact = |t: f64, y: &[f64], dy: &mut [f64], j: &mut [f64]| sys.jacobian(t, y, dy, j);
        integrate_with_jacobian(&mut |t, y, dy| sys.rhs(t, y, dy), Some(&mut exact), None, &y0, &times, &s).unwrap()
    };
    let (with, without) = (run(false), run(true));
    assert_eq!(with.states, without.states);
    assert_eq!((with.stats.steps, with.stats.jacobians), (without.stats.steps, without.stats.jacobians));
    assert!(with.stats.jacobians > 10);
    assert_eq!(with.stats.rhs_calls - without.stats.rhs_calls, with.stats.jacobians);
}

/// Hairer's stiffness test in DOPRI5 and DOP853: the stiff pendulum at k = 1e8 is found stiff
/// early by both, and the command line names the stiff method, with the default method too
/// (DOP853); scene 2 at the paper's settings and scene 3 at tight ones are not.
#[test]
fn the_explicit_pairs_detect_stiffness_and_the_command_line_names_the_stiff_method() {
    for method in [Method::Dopri5, Method::Dop853] {
        let stiff = run(&with_stiffness(1e8), "kane", method, 1e-4);
        let t = stiff.record.stiff_at.unwrap_or_else(|| panic!("{method}: stiff at k = 1e8"));
        assert!(t < 0.1, "{method}: detected at t = {t}");
    }
    let scene2 = generated::find("three_body").unwrap();
    let calm = runtime::compare::run(&scene2, FormulationKind::ReducedVolterra, &Settings::paper(50.0), 1).unwrap();
    assert_eq!(calm.record.stiff_at, None);
    let scene3 = generated::find("bicycle").unwrap();
    assert_eq!(runtime::compare::run(&scene3, FormulationKind::Kane, &Settings::tight(5.0), 1).unwrap().record.stiff_at, None);
    let dir = tempfile::tempdir().unwrap();
    for method in [&["--method", "dopri5"][..], &[]] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_multibody"))
            .args(["simulate", "stiff_pendulum", "--param", "k=1e8", "--rtol", "1e-4", "--atol", "1e-4", "--t-end", "0.5", "--out"])
            .arg(dir.path())
            .args(method)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success() && err.contains("looks stiff from t =") && err.contains("--method ros23"), "{method:?}: {err}");
        // The run's file says so too, for what reads it.
        let written = dir.path().join("stiff_pendulum_reduced_volterra.json");
        let record: serde_json::Value = serde_json::from_slice(&std::fs::read(&written).unwrap()).unwrap();
        assert!(record["stiff_at"].as_f64().is_some_and(|t| t < 0.1), "{method:?}: {}", record["stiff_at"]);
    }
    // A calm run's file: null.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_multibody"))
        .args(["simulate", "tumbling_body", "--t-end", "1", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let record: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.path().join("tumbling_body_reduced_volterra.json")).unwrap()).unwrap();
    assert!(record["stiff_at"].is_null(), "{}", record["stiff_at"]);
}
