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
