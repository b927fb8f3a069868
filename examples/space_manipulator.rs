//! The paper's method on a robot: the free-floating space manipulator of
//! `docs/robots/space_manipulator.ron` (a 200 kg satellite with a 7-joint arm, from its URDF,
//! no gravity), its joints driven by a PD law towards sinusoidal targets (torques set at every
//! call by a `Controller`). The satellite's position is ignorable: its linear momentum is
//! conserved while the arm moves, which the reduced method keeps exactly. Every formulation runs
//! the same motion at the paper's settings (DOPRI5, rtol 1e-3, atol 1e-6) and at tight ones;
//! for each: the cost of a right-hand side, the error against the tight reduced run, the drift
//! of the momentum and of the energy balance (the motors' work taken out). Writes
//! `docs/robots/space_manipulator.json` (`docs/robots.md` quotes it) and, with `--animate
//! PAGE`, the motion as the project's page.
//!
//! `cargo run --release --example space_manipulator [-- --animate space_manipulator.html]`

use runtime::inputs::Controller;
use runtime::integrate::Settings;
use runtime::system::System;
use seam::FormulationKind;
use std::time::Instant;

/// The joints' targets: `q_k(t) = 0.6 sin(0.8 t + k)`, and the PD gains.
fn controller(model: &seam::Model) -> Controller {
    let joints: Vec<usize> = (1..=7).map(|k| model.coordinate_index(&format!("joint{k}")).expect("the arm's joints")).collect();
    Controller::new(move |t, q, qd, u| {
        for (k, (&j, u)) in joints.iter().zip(u.iter_mut()).enumerate() {
            let target = 0.6 * (0.8 * t + k as f64).sin();
            let rate = 0.48 * (0.8 * t + k as f64).cos();
            *u = 40.0 * (target - q[j]) + 8.0 * (rate - qd[j]);
        }
    })
}

/// The largest drift over the run of the angular momentum about the world's three axes.
fn angular_momentum_drift(model: &seam::Model, inv: &runtime::monitor::Invariants) -> f64 {
    let axes = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let at = |q: &[f64], qd: &[f64], axis| {
        runtime::monitor::momentum_along(
            model,
            0.0,
            &model.default_params,
            q,
            qd,
            &generator::model::world_rotation(&model.coordinates, q, axis).expect("a floating base"),
        )
        .expect("the energy")
    };
    let start: Vec<f64> = axes.iter().map(|&a| at(&inv.coordinates[0], &inv.rates[0], a)).collect();
    inv.coordinates
        .iter()
        .zip(&inv.rates)
        .flat_map(|(q, qd)| axes.iter().zip(&start).map(move |(&a, l0)| (at(q, qd, a) - l0).abs()).collect::<Vec<_>>())
        .fold(0.0, f64::max)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let page = args.iter().position(|a| a == "--animate").and_then(|i| args.get(i + 1));
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/robots/space_manipulator.ron");
    let source = generator::model::load(file).expect("the model loads");
    let model = load::evaluate(&source, load::Jacobians::Differenced, load::Route::Jit, &mut |_| {}).expect("derives").model;
    let (q0, qd0) = model.initial.clone().expect("an initial state");
    let times: Vec<f64> = (0..=500).map(|i| 0.02 * i as f64).collect();
    let run = |kind: FormulationKind, settings: &Settings| {
        let (sys, y0) = System::start(&model, kind, model.default_params.clone(), &q0, &qd0).expect("starts");
        let sys = sys.with_controller(controller(&model));
        let start = Instant::now();
        let out = runtime::trajectory::simulate(&sys, &y0, &times, settings, &mut |_| {}).expect("runs");
        (out, start.elapsed().as_secs_f64())
    };
    let tight = Settings { rtol: 1e-12, atol: 1e-12, ..Settings::tight(10.0) };
    let (reference, _) = run(FormulationKind::ReducedVolterra, &tight);
    let end = reference.invariants.coordinates.last().expect("outputs").clone();
    let mut records = Vec::new();
    for (label, settings) in [("paper", Settings::paper(10.0)), ("tight", Settings { rtol: 1e-10, atol: 1e-10, ..Settings::tight(10.0) })] {
        for form in &model.formulations {
            let (out, seconds) = run(form.kind, &settings);
            let inv = &out.invariants;
            let worst = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let error = out.invariants.coordinates.last().unwrap().iter().zip(&end).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            // A right-hand side's cost: the mean of many calls at the initial state.
            let (sys, y0) = System::start(&model, form.kind, model.default_params.clone(), &q0, &qd0).unwrap();
            let sys = sys.with_controller(controller(&model));
            let mut dy = vec![0.0; y0.len()];
            let calls = 20_000;
            let start = Instant::now();
            for _ in 0..calls {
                sys.rhs(0.1, std::hint::black_box(&y0), &mut dy).unwrap();
            }
            let ns = start.elapsed().as_secs_f64() * 1e9 / calls as f64;
            let record = serde_json::json!({
                "settings": label,
                "formulation": form.kind.name(),
                "states": form.states(),
                "equations": form.equations,
                "ns_per_call": ns,
                "rhs_calls": out.solution.stats.rhs_calls,
                "seconds": seconds,
                "error_at_the_end": error,
                "momentum_drift": inv.momentum_error.iter().map(|d| worst(d)).fold(0.0, f64::max),
                "angular_momentum_drift": angular_momentum_drift(&model, inv),
                "energy_balance_drift": worst(&inv.energy_error),
            });
            eprintln!(
                "{label:6} {:17} {ns:8.0} ns/call, {:6} calls, error {error:.1e}, momentum drift {:.1e}, angular {:.1e}",
                form.kind.name(),
                out.solution.stats.rhs_calls,
                record["momentum_drift"].as_f64().unwrap_or(f64::NAN),
                record["angular_momentum_drift"].as_f64().unwrap_or(f64::NAN),
            );
            records.push(record);
        }
    }
    let out = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/robots/space_manipulator.json");
    let angular_momentum = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].map(|axis| {
        let (q, qd) = (&reference.invariants.coordinates[0], &reference.invariants.rates[0]);
        runtime::monitor::momentum_along(
            &model,
            0.0,
            &model.default_params,
            q,
            qd,
            &generator::model::world_rotation(&model.coordinates, q, axis).expect("a floating base"),
        )
        .expect("the energy")
    });
    let json = serde_json::json!({
        "command": "cargo run --release --example space_manipulator",
        "about": "docs/robots/space_manipulator.ron: a 200 kg satellite with a 7-joint arm, no gravity, the joints driven by a PD law towards 0.6 sin(0.8 t + k) for 10 s; each formulation at the paper's settings (DOPRI5, rtol 1e-3, atol 1e-6) and tight ones (DOP853, 1e-10); error against the reduced method at 1e-12; momentum drift the largest of the three linear momenta (the ignorable translations'); angular momentum drift the largest about the world's axes (Noether's charge of a world rotation, not an ignorable coordinate's: kept by no formulation exactly); energy balance T + V less the motors' work",
        "linear_momentum": reference.invariants.momentum0,
        "angular_momentum": angular_momentum,
        "records": records,
    });
    std::fs::write(&out, serde_json::to_string_pretty(&json).unwrap() + "\n").unwrap();
    eprintln!("wrote {}", out.display());
    if let Some(page) = page {
        let q: Vec<f64> = reference.invariants.coordinates.concat();
        animate::write(
            page.as_ref(),
            &source,
            &model.default_params,
            &animate::Motion { formulation: "reduced_volterra", times: &reference.solution.times, q: &q },
        )
        .expect("the page");
        eprintln!("wrote {page}");
    }
}
