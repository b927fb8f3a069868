//! Events from a model file (`models/bouncing_ball.ron`): a floor that resets the ball's normal
//! speed to `-e` times itself, each apex recorded, a wall that stops the run. Checked against
//! the closed form in every formulation, in-process and compiled: impact times, apex heights,
//! the stop, the impacts' energy loss; the energy balance (with the impacts' jumps taken out)
//! and the ignorable momentum `m x'` held to round-off across every impact.

use crate::common;
use runtime::integrate::{EventAction, Method, Settings};
use seam::Model;

const H0: f64 = 1.0;
const G: f64 = 9.81;
const E: f64 = 0.9;
const M: f64 = 0.5;
const WALL: f64 = 5.0;

fn tight() -> Settings {
    Settings { method: Method::Dop853, rtol: 1e-12, atol: 1e-12, h_max: 1.0, ..Settings::default() }
}

/// The closed form: the ball released at rest is at its first apex at the start; impacts at
/// `t_1 (1 + 2 (e + ... + e^(k-1)))` with `t_1 = sqrt(2 h / g)`, the apex after impact `k` a
/// time `t_1 e^k` later at height `h e^(2k)`, up to the wall at `x = t`.
fn closed_form() -> Vec<(&'static str, f64, f64)> {
    let t1 = (2.0 * H0 / G).sqrt();
    let mut out = vec![("apex", 0.0, H0)];
    let (mut t, mut k) = (t1, 1);
    while t < WALL {
        out.push(("floor", t, 0.0));
        let apex = t + t1 * E.powi(k);
        if apex < WALL {
            out.push(("apex", apex, H0 * E.powi(2 * k)));
        }
        t += 2.0 * t1 * E.powi(k);
        k += 1;
    }
    out.push(("wall", WALL, f64::NAN));
    out
}

fn check(model: &Model, label: &str) {
    let expected = closed_form();
    for form in &model.formulations {
        let r = runtime::compare::Reference::of(model).unwrap();
        let (sys, y0) = runtime::system::System::start(model, form.kind, r.params.clone(), &r.q0, &r.qd0).unwrap();
        let times = r.times().unwrap();
        let run = runtime::events::run(&sys, &y0, &times, &tight(), &mut |_| {}).unwrap();
        let sol = &run.solution;
        let what = format!("{label} {}", form.kind);
        assert!(sol.stopped, "{what}");
        assert_eq!(sol.events.len(), expected.len(), "{what}: {:?}", sol.events.iter().map(|o| (o.event, o.t)).collect::<Vec<_>>());
        for (o, (name, t, height)) in sol.events.iter().zip(&expected) {
            assert_eq!(model.events[o.event].name, *name, "{what}");
            assert!((o.t - t).abs() < 1e-10, "{what}: {name} at {} against {t}", o.t);
            let (q, qd) = runtime::events::system_before(&sys, &run.jumps, o.t).velocities(o.t, &o.state).unwrap();
            match *name {
                "floor" => assert!(q[1].abs() < 1e-10, "{what}: y = {} at an impact", q[1]),
                "apex" => assert!((q[1] - height).abs() < 1e-10 && qd[1].abs() < 1e-9, "{what}: apex {} against {height}", q[1]),
                _ => assert!((q[0] - WALL).abs() < 1e-10, "{what}: x = {} at the wall", q[0]),
            }
        }
        // Each impact loses (1 - e^2) of the normal kinetic energy, m g h e^(2 (k - 1)).
        let impacts: Vec<_> = run.jumps.iter().collect();
        assert_eq!(impacts.len(), expected.iter().filter(|e| e.0 == "floor").count(), "{what}");
        for (k, j) in impacts.iter().enumerate() {
            assert_eq!(model.events[j.event].action, EventAction::Reset);
            let loss = -M * G * H0 * E.powi(2 * k as i32) * (1.0 - E * E);
            assert!((j.energy - loss).abs() < 1e-9, "{what}: impact {k} changes the energy by {} against {loss}", j.energy);
            assert!(j.momenta.iter().all(|p| p.abs() < 1e-15), "{what}: {:?}", j.momenta);
        }
        // The outputs end before the stop; with the impacts taken out, the balances hold.
        let stop = sol.events.last().unwrap().t;
        assert_eq!(sol.times.len(), times.iter().filter(|t| **t < stop).count(), "{what}");
        assert!(sol.times.len() >= 500, "{what}");
        let inv = runtime::monitor::monitor_with_jumps(&sys, sol, &run.jumps).unwrap();
        let worst = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        assert!(worst(&inv.energy_error) < 1e-11 * inv.energy0.abs(), "{what}: energy drift {}", worst(&inv.energy_error));
        assert!(worst(&inv.momentum_error[0]) < 1e-14 * M, "{what}: momentum drift {}", worst(&inv.momentum_error[0]));
        // Without the jumps, the energy balance would show the impacts as an error.
        let naive = runtime::monitor::monitor(&sys, sol);
        if let Ok(naive) = naive {
            assert!(worst(&naive.energy_error) > 0.1, "{what}");
        }
    }
}

#[test]
fn the_bouncing_ball_meets_the_closed_form_compiled() {
    check(&generated::bouncing_ball::model(), "compiled");
}

#[test]
fn the_bouncing_ball_meets_the_closed_form_in_process() {
    let m = generator::model::load(concat!(env!("CARGO_MANIFEST_DIR"), "/models/bouncing_ball.ron")).unwrap();
    let jit = jit::Jit::default();
    let model = generator::evaluate_with_backend(&m, &generator::emit::Options::from_model(&m), &jit).unwrap().0;
    assert_eq!(jit.interpreted(), 0);
    check(&model, "in-process");
}

/// The events' errors are located on the file: a reset of what is not a coordinate, an event
/// function with an unknown name, two events of one name, a reset that sets nothing.
#[test]
fn bad_events_get_located_errors() {
    let good = include_str!("../../models/bouncing_ball.ron");
    let cases = [
        (r#"Reset(qdot: {"y": "-e*y'"})"#, r#"Reset(qdot: {"z": "-e*y'"})"#, "`z`, which is not a coordinate", "events[0].action.qdot.z"),
        (r#"when: "x - wall""#, r#"when: "x - door""#, "unknown name `door`", "events[2].when"),
        (r#"name: "apex""#, r#"name: "floor""#, "two events are called `floor`", "events[1].name"),
        (r#"Reset(qdot: {"y": "-e*y'"})"#, "Reset()", "resets nothing", "events[0].action"),
    ];
    for (from, to, message, place) in cases {
        assert!(good.contains(from), "{from}");
        let text = good.replacen(from, to, 1);
        let e = generator::model::from_source("models/ball.ron", &text).unwrap_err();
        let shown = e.to_string();
        assert!(shown.contains(message) && shown.contains(place), "{to}: {shown}");
        let line = text.lines().collect::<Vec<_>>().iter().rposition(|l| l.contains(to)).unwrap() + 1;
        assert!(shown.contains(&format!("models/ball.ron:{line}:")), "{to} (line {line}): {shown}");
    }
}

/// A pendulum released from rest at 1 rad is stopped by its event at the bottom after a quarter
/// period, `sqrt(l / g) K(sin^2(1/2))`, to 1e-12 in time, in every formulation.
#[test]
fn a_released_pendulum_stops_at_the_bottom_after_a_quarter_period() {
    let m = generator::model::load(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/released_pendulum.ron")).unwrap();
    let model = generator::evaluate(&m).unwrap();
    let quarter = (1.0f64 / 9.81).sqrt() * common::elliptic_k(0.5f64.sin().powi(2));
    let settings = Settings { method: Method::Dop853, rtol: 1e-14, atol: 1e-14, h_max: 0.5, ..Settings::default() };
    for form in &model.formulations {
        let r = runtime::compare::Reference::of(&model).unwrap();
        let (sys, y0) = runtime::system::System::start(&model, form.kind, r.params.clone(), &r.q0, &r.qd0).unwrap();
        let run = runtime::events::run(&sys, &y0, &r.times().unwrap(), &settings, &mut |_| {}).unwrap();
        let stop = run.solution.events.last().unwrap();
        assert!(run.solution.stopped && run.solution.events.len() == 1, "{}", form.kind);
        assert!((stop.t - quarter).abs() < 1e-12, "{}: stopped at {} against {quarter}", form.kind, stop.t);
        assert_eq!(run.solution.times.len(), 6, "{}: the outputs before the stop (0 to 0.5)", form.kind);
    }
}
