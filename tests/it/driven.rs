//! Energy that means something for driven systems: with a prescribed motion the energy column
//! is Jacobi's integral `h = T2 - T0 + V` less the work `W` of the explicit time dependence,
//! which is constant along every formulation's motion; `T + V` is not (the motor's work), and
//! the column no longer reports that work as an error. With a moving constraint (`b` not zero:
//! a motor holding a rate, a rope reeled by a winch) the constraint's forces do work too, which
//! every formulation adds to `W` from its accelerations, so `h - W` stays constant there as well.

use runtime::compare::{Options, compare};
use runtime::integrate::Settings;
use seam::EnergyBalance;

/// A bead on a circular hoop of radius R turned at the constant rate Omega about the vertical:
/// time-independent in the hoop's frame, so `h` itself is conserved (and W has nothing to count).
const HOOP: &str = r#"Model(
    name: "hoop",
    parameters: { "m": 0.3, "R": 0.5, "g": 9.81, "Omega": 6.0 },
    coordinates: ["th"],
    frames: [
        Frame(name: "hoop", parent: "world", rotation: [Y("Omega*t")]),
        Frame(name: "arm", parent: "hoop", rotation: [Z("th")]),
    ],
    bodies: [Body(name: "bead", frame: "arm", mass: "m", com: ["0", "-R", "0"], inertia: PointMass)],
    forces: [Gravity(vector: ["0", "-g", "0"])],
    quasi_velocities: QuasiVelocities(full: ["th'"], reduced: ["th'"]),
    ignorable: Auto,
    initial: Initial(q: {"th": "0.4"}, qdot: {"th": "0"}),
    simulation: Simulation(t_end: 5.0, dt_out: 0.01),
)"#;

/// A pendulum whose pivot is shaken sideways, `x = A sin(w t)`: the Lagrangian depends on t,
/// and W integrates `-dL/dt`.
const SHAKEN: &str = r#"Model(
    name: "shaken",
    parameters: { "m": 1.0, "l": 0.7, "g": 9.81, "A": 0.05, "w": 9.0 },
    coordinates: ["th"],
    frames: [
        Frame(name: "pivot", parent: "world", translation: ["A*sin(w*t)", "0", "0"]),
        Frame(name: "arm", parent: "pivot", rotation: [Z("th")]),
    ],
    bodies: [Body(name: "bob", frame: "arm", mass: "m", com: ["0", "-l", "0"], inertia: PointMass)],
    forces: [Gravity(vector: ["0", "-g", "0"])],
    quasi_velocities: QuasiVelocities(full: ["th'"], reduced: ["th'"]),
    ignorable: Auto,
    initial: Initial(q: {"th": "0.3"}, qdot: {"th": "0"}),
    simulation: Simulation(t_end: 5.0, dt_out: 0.01),
)"#;

/// A bead free to slide on a rod that a motor turns at the constant rate Omega (the constraint
/// `phi' = Omega`, `b = -Omega`), no gravity: `r'' = Omega^2 r`, so `r = r0 cosh(Omega t) + (r0' /
/// Omega) sinh(Omega t)`, and the motor's work is `T(t) - T(0) = m Omega^2 (r^2 - r0^2) / 2 + m (r'^2 -
/// r0'^2) / 2` = `m Omega^2 (r^2 - r0^2)` (as `r'^2 - Omega^2 r^2` is constant).
const ROD: &str = r#"Model(
    name: "rod",
    parameters: { "m": 0.5, "I": 0.2, "Omega": 1.5 },
    coordinates: ["phi", "r"],
    frames: [Frame(name: "rod", parent: "world", rotation: [Z("phi")])],
    bodies: [
        Body(name: "hub", frame: "rod", mass: "1", com: ["0", "0", "0"], inertia: Diagonal(["I", "I", "I"])),
        Body(name: "bead", frame: "rod", mass: "m", com: ["r", "0", "0"], inertia: PointMass),
    ],
    constraints: [Velocity(name: "motor", expr: "phi' - Omega")],
    quasi_velocities: QuasiVelocities(full: ["r'"], reduced: ["r'"]),
    ignorable: Auto,
    initial: Initial(q: {"phi": "0", "r": "0.2"}, qdot: {"phi": "Omega", "r": "0.1"}),
    simulation: Simulation(t_end: 2.0, dt_out: 0.01),
)"#;

fn evaluated(name: &str, text: &str) -> seam::Model {
    let model = generator::model::from_source(&format!("{name}.ron"), text).unwrap();
    generator::evaluate(&model).unwrap()
}

/// The emitted energy function is Jacobi's integral in closed form.
#[test]
fn the_hoop_s_energy_function_is_jacobi_s_integral() {
    let model = evaluated("hoop", HOOP);
    assert_eq!(model.energy_balance, EnergyBalance::Jacobi);
    let (m, r, g, omega) = (0.3, 0.5, 9.81, 6.0);
    for (th, thd, t) in [(0.4, 0.0, 0.0), (1.1, -2.0, 0.7), (-2.5, 3.3, 4.2)] {
        let mut out = [0.0];
        model.energy(t, &[th], &[thd], &model.default_params, &mut out).unwrap();
        let h = 0.5 * m * r * r * (thd * thd - omega * omega * f64::sin(th).powi(2)) - m * g * r * f64::cos(th);
        assert!((out[0] - h).abs() <= 1e-14 * h.abs().max(1.0), "h({th}, {thd}) = {} against {h}", out[0]);
    }
}

/// Along a motion, at tight settings, the column stays at the integration error for every
/// formulation, while `T + V` swings by the motor's work.
#[test]
fn the_balance_holds_along_driven_motions() {
    for (name, text) in [("hoop", HOOP), ("shaken", SHAKEN)] {
        let model = evaluated(name, text);
        assert_eq!(model.energy_balance, EnergyBalance::Jacobi, "{name}");
        let runs = compare(&model, &Options { settings: Settings::tight(5.0), repeats: 1, ..Options::paper(&model) }).unwrap();
        assert_eq!(runs.len(), 4, "{name}");
        for run in &runs {
            let worst = run.invariants.energy_error.iter().fold(0.0f64, |a, e| a.max(e.abs()));
            let scale = run.invariants.energy.iter().fold(0.0f64, |a, e| a.max(e.abs()));
            assert!(worst <= 1e-8 * scale, "{name} {}: |h - W - (h - W)(0)| up to {worst:e} of {scale:e}", run.record.method);
            assert_eq!(run.record.energy_column, "jacobi err");
        }
        // T + V along the same motion (the bead's or bob's speed in the world and its height):
        // what the column would have reported as an error.
        let run = &runs[0];
        let p = &model.default_params;
        let total: Vec<f64> = run
            .solution
            .times
            .iter()
            .zip(&run.invariants.coordinates)
            .zip(&run.invariants.rates)
            .map(|((t, q), qd)| match name {
                "hoop" => {
                    let (m, r, g, omega) = (p[0], p[1], p[2], p[3]);
                    0.5 * m * r * r * (qd[0] * qd[0] + omega * omega * q[0].sin().powi(2)) - m * g * r * q[0].cos()
                }
                _ => {
                    let (m, l, g, a, w) = (p[0], p[1], p[2], p[3], p[4]);
                    let (vx, vy) = (a * w * (w * t).cos() + l * q[0].cos() * qd[0], l * q[0].sin() * qd[0]);
                    0.5 * m * (vx * vx + vy * vy) - m * g * l * q[0].cos()
                }
            })
            .collect();
        let swing = total.iter().cloned().fold(f64::NEG_INFINITY, f64::max) - total.iter().cloned().fold(f64::INFINITY, f64::min);
        assert!(swing > 1e-3 * total[0].abs().max(1.0), "{name}: T + V swings by {swing:e} only");
    }
}

/// A model with nothing moving keeps `E = T + V`, and its table says "energy err".
#[test]
fn a_model_with_nothing_driven_keeps_the_energy() {
    let model = generated::find("three_body").unwrap();
    assert_eq!(model.energy_balance, EnergyBalance::Energy);
    let records: Vec<runtime::compare::Record> =
        serde_json::from_str(&std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/comparisons/three_body.json")).unwrap()).unwrap();
    assert!(records.iter().all(|r| r.energy_column == "energy err"));
}

/// The worst `|h - W - (h - W)(0)|` of a run, and its scale: the largest of `|h - W|` and `|W|`
/// (the balance is a difference of the two, each that large).
fn worst_and_scale(model: &seam::Model, run: &runtime::compare::Run) -> (f64, f64) {
    let worst = run.invariants.energy_error.iter().fold(0.0f64, |a, e| a.max(e.abs()));
    let w_at = model.formulation(run.kind).unwrap().layout.work_index().expect("the constraint's work is a state");
    let work = run.solution.states.iter().map(|y| y[w_at].abs());
    let scale = run.invariants.energy.iter().map(|e| e.abs()).chain(work).fold(0.0f64, f64::max);
    (worst, scale)
}

/// The motor's work is `W`: in every formulation, `W(t)` and `r(t)` follow the closed form, and
/// `h - W` (here `T - W`) stays at the integration error while `T` grows by the work.
#[test]
fn a_motor_holding_a_rate_does_the_work_the_closed_form_gives() {
    let model = evaluated("rod", ROD);
    assert_eq!(model.energy_balance, EnergyBalance::MovingConstraints);
    let (m, omega, r0, rd0) = (0.5, 1.5, 0.2, 0.1);
    let runs = compare(&model, &Options { settings: Settings::tight(2.0), repeats: 1, ..Options::paper(&model) }).unwrap();
    assert_eq!(runs.len(), 4);
    for run in &runs {
        let kind = run.record.method.as_str();
        assert_eq!(run.record.energy_column, "h - W err", "{kind}");
        let form = model.formulation(run.kind).unwrap();
        let w_at = form.layout.work_index().expect("the motor's work is a state");
        let (t, y) = (*run.solution.times.last().unwrap(), run.solution.states.last().unwrap());
        let r = r0 * (omega * t).cosh() + rd0 / omega * (omega * t).sinh();
        let work = m * omega * omega * (r * r - r0 * r0);
        let q = run.invariants.coordinates.last().unwrap();
        assert!((q[1] - r).abs() <= 1e-9 * r, "{kind}: r({t}) = {} against {r}", q[1]);
        assert!((y[w_at] - work).abs() <= 1e-9 * work, "{kind}: W({t}) = {} against {work}", y[w_at]);
        let (worst, scale) = worst_and_scale(&model, run);
        assert!(worst <= 1e-9 * scale, "{kind}: h - W drifts by {worst:e} of {scale:e}");
        // What the column would report without the motor's work: T(t) - T(0) = W.
        assert!(work > 1e6 * worst, "{kind}: the motor's work {work:e} is within the drift {worst:e}");
    }
}

/// The winch's rope (a moving holonomic constraint, with gravity): the committed module and the
/// in-process evaluation keep `h - W` in every formulation, and `W`, the rope's work, is no small
/// part of it.
#[test]
fn a_rope_reeled_by_a_winch_keeps_h_minus_w() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/models/winch.ron")).unwrap();
    for model in [generated::find("winch").unwrap(), evaluated("winch", &text)] {
        assert_eq!(model.energy_balance, EnergyBalance::MovingConstraints);
        let runs = compare(&model, &Options { settings: Settings::tight(10.0), repeats: 1, ..Options::paper(&model) }).unwrap();
        assert_eq!(runs.len(), 4);
        for run in &runs {
            let kind = run.record.method.as_str();
            let (worst, scale) = worst_and_scale(&model, run);
            assert!(worst <= 1e-8 * scale, "{kind}: h - W drifts by {worst:e} of {scale:e}");
            let form = model.formulation(run.kind).unwrap();
            let w_at = form.layout.work_index().expect("the rope's work is a state");
            let swing = run.solution.states.iter().map(|y| y[w_at]).fold(0.0f64, |a, w| a.max(w.abs()));
            assert!(swing > 0.1 * scale, "{kind}: the rope's work reaches {swing:e} only, against {scale:e}");
        }
    }
}

/// A mass pushed by a force that follows a time series, `x'' = F(t) / m` with `F` linear between
/// its samples: the run stops and starts again at each sample (stepping across the kinks cost
/// thousands of steps and the accuracy the tolerance asks for), and meets the closed form.
#[test]
fn an_input_series_is_integrated_sample_to_sample() {
    use runtime::inputs::{Controller, TimeSeries};
    const PUSHED: &str = r#"Model(
        name: "pushed",
        parameters: { "m": 2.0 },
        inputs: { "F": 0.0 },
        coordinates: ["x"],
        frames: [Frame(name: "cart", parent: "world", translation: ["x", "0", "0"])],
        bodies: [Body(name: "cart", frame: "cart", mass: "m", inertia: PointMass)],
        forces: [PointForce(name: "push", frame: "cart", point: ["0", "0", "0"], force: ["F", "0", "0"])],
        quasi_velocities: QuasiVelocities(full: ["x'"], reduced: ["x'"]),
        ignorable: Declared([]),
        initial: Initial(q: {"x": "0"}, qdot: {"x": "0"}),
        simulation: Simulation(t_end: 10.0, dt_out: 0.5),
    )"#;
    let source = generator::model::from_source("pushed.ron", PUSHED).unwrap();
    let model = load::evaluate(&source, load::Jacobians::Differenced, load::Route::Jit, &mut |_| {}).unwrap().model;
    // A sawtooth of kinks: F at t_k alternates 0, 3, -1, 2, ...
    let samples: Vec<(f64, f64)> = (0..=20).map(|k| (0.5 * k as f64 + 0.13, [0.0, 3.0, -1.0, 2.0][k % 4])).collect();
    let text: String = std::iter::once("t,F\n".to_string()).chain(samples.iter().map(|(t, f)| format!("{t},{f}\n"))).collect();
    let series = TimeSeries::parse(&text).unwrap();
    // The closed form: x(t) = integral of the velocity, each piece a cubic.
    let exact = |t: f64| -> (f64, f64) {
        let (mut x, mut v, mut t0, mut f0) = (0.0, 0.0, 0.0, samples[0].1);
        for &(t1, f1) in samples.iter().chain([&(f64::INFINITY, samples[20].1)]) {
            let end = t.min(t1);
            let h = end - t0;
            let slope = if t1.is_finite() && t1 > t0 && t0 >= samples[0].0 { (f1 - f0) / (t1 - t0) } else { 0.0 };
            // a(s) = (f0 + slope s) / m on [t0, t0 + h].
            x += v * h + (f0 / 2.0 * h * h + slope / 6.0 * h * h * h) / 2.0;
            v += (f0 * h + slope / 2.0 * h * h) / 2.0;
            if t <= t1 {
                return (x, v);
            }
            (t0, f0) = (t1, f1);
        }
        (x, v)
    };
    let (sys, y0) = runtime::system::System::start(&model, seam::FormulationKind::Kane, model.default_params.clone(), &[0.0], &[0.0]).unwrap();
    let sys = sys.with_controller(Controller::series(vec![series]));
    let times: Vec<f64> = (0..=20).map(|i| 0.5 * i as f64).collect();
    let settings = Settings { rtol: 1e-12, atol: 1e-12, ..Settings::tight(10.0) };
    let run = runtime::events::run(&sys, &y0, &times, &settings, &mut |_| {}).unwrap();
    assert_eq!(run.solution.times, times);
    for (t, y) in run.solution.times.iter().zip(run.solution.states.iter()) {
        let (x, v) = exact(*t);
        assert!((y[0] - x).abs() < 1e-11 * (1.0 + x.abs()) && (y[1] - v).abs() < 1e-11 * (1.0 + v.abs()), "t = {t}: {y:?} against ({x}, {v})");
    }
    // A few steps per smooth piece (each piece a cubic), not thousands across the kinks.
    assert!(run.solution.stats.steps < 10 * samples.len(), "{:?}", run.solution.stats);
}
