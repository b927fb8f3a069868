//! Energy that means something for driven systems: with a prescribed motion the energy column
//! is Jacobi's integral `h = T2 - T0 + V` less the work `W` of the explicit time dependence,
//! which is constant along every formulation's motion; `T + V` is not (the motor's work), and
//! the column no longer reports that work as an error.

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

fn evaluated(name: &str, text: &str) -> seam::Model {
    let model = generator::model::from_source(&format!("{name}.ron"), text).unwrap();
    generator::eval::evaluate(&model).unwrap()
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
