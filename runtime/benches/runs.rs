//! Whole runs: each scene's 50 s reference run at the paper's settings, per formulation, and
//! the modelling choices that trade (baked parameters, ignorable coordinates left out, drift
//! control), integration only. Target: every 50 s run under 5 ms on one core. Every run timed
//! interleaved with the others, best of 20 rounds.
//!
//! `cargo bench -p runtime --bench runs` writes `docs/benchmarks/runs.json` and
//! `docs/benchmarks/drift.json` (the tables of `docs/benchmarks.md`, checked by
//! `tests/it/figures.rs`) and prints them.

use runtime::compare::Reference;
use runtime::integrate::{Projector, Settings, integrate, integrate_projected};
use runtime::system::{Drift, System};
use seam::FormulationKind;
use std::hint::black_box;
use std::time::Instant;

const COMMAND: &str = "cargo bench -p runtime --bench runs";

/// One timed run: (row, column, the run).
type Run = (usize, usize, Box<dyn FnMut() -> usize>);

fn seconds(run: &mut dyn FnMut() -> usize) -> f64 {
    let start = Instant::now();
    black_box(run());
    start.elapsed().as_secs_f64()
}

fn write(name: &str, columns: &[&str], rows: &[Vec<String>]) {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let json = serde_json::json!({ "command": COMMAND, "columns": columns, "rows": rows });
    std::fs::write(format!("{root}/docs/benchmarks/{name}.json"), serde_json::to_string_pretty(&json).unwrap() + "\n").unwrap();
    println!("{}", std::iter::once(columns.join(" | ")).chain(rows.iter().map(|r| r.join(" | "))).collect::<Vec<_>>().join("\n"));
}

fn main() {
    let scenes = [
        ("cart_pendulum", "1 cart_pendulum"),
        ("cart_pendulum_baked", "1 cart_pendulum, baked"),
        ("three_body", "2 three_body"),
        ("three_body_drop", "2 three_body, ignorable not integrated"),
        ("satellite_boom", "3 satellite_boom"),
    ];
    let kinds = [FormulationKind::Lagrange, FormulationKind::Maggi, FormulationKind::Kane, FormulationKind::ReducedVolterra];
    let mut runs: Vec<Run> = Vec::new();
    let mut outputs = Vec::new();
    for (row, (scene, _)) in scenes.iter().enumerate() {
        let model = generated::find(scene).unwrap();
        let r = Reference::of(&model).unwrap();
        let settings = Settings::paper(r.t_end - r.t_start);
        let times = r.times().unwrap();
        outputs.push(times.len());
        for (column, kind) in kinds.iter().enumerate() {
            if model.formulation(*kind).is_none() {
                continue;
            }
            let (sys, y0) = System::start(&model, *kind, r.params.clone(), &r.q0, &r.qd0).unwrap();
            let times = times.clone();
            runs.push((row, column, Box::new(move || integrate(&mut |t, y, dy| sys.rhs(t, y, dy), &y0, &times, &settings).unwrap().stats.rhs_calls)));
        }
    }
    // Drift control costs time (and buys constraint accuracy): scene 1, Lagrange.
    let drifts = [
        ("none", Drift::None),
        ("Baumgarte (alpha = beta = 10)", Drift::Baumgarte { alpha: 10.0, beta: 10.0 }),
        ("projection after every step", Drift::Projection),
    ];
    let model = generated::find("cart_pendulum").unwrap();
    let r = Reference::of(&model).unwrap();
    for (k, (_, drift)) in drifts.iter().enumerate() {
        let (sys, y0) = System::start(&model, FormulationKind::Lagrange, r.params.clone(), &r.q0, &r.qd0).unwrap();
        let sys = sys.with_drift(*drift).unwrap();
        let (times, settings, drift) = (r.times().unwrap(), Settings::paper(r.t_end - r.t_start), *drift);
        runs.push((
            scenes.len() + k,
            0,
            Box::new(move || {
                let mut project = |t: f64, y: &mut [f64]| sys.project(t, y);
                let projector: Option<Projector> = if drift == Drift::Projection { Some(&mut project) } else { None };
                integrate_projected(&mut |t, y, dy| sys.rhs(t, y, dy), projector, &y0, &times, &settings).unwrap().stats.rhs_calls
            }),
        ));
    }
    let mut best = vec![f64::INFINITY; runs.len()];
    for _ in 0..20 {
        for (k, run) in runs.iter_mut().enumerate() {
            best[k] = best[k].min(seconds(&mut run.2));
        }
    }
    let at = |row: usize, column: usize| runs.iter().position(|r| r.0 == row && r.1 == column).map(|k| best[k] * 1e6);
    let us = |x: Option<f64>| x.map_or(String::new(), |v| format!("{v:.0} µs"));
    let mut rows = Vec::new();
    for (row, (_, label)) in scenes.iter().enumerate() {
        let label = if !label.contains(',') { format!("{label} ({} outputs)", outputs[row]) } else { label.to_string() };
        let mut cells = vec![label];
        cells.extend((0..4).map(|c| us(at(row, c))));
        cells.push(match (at(row, 3), at(row, 2)) {
            (Some(reduced), Some(kane)) => format!("**{:.2}**", reduced / kane),
            _ => String::new(),
        });
        rows.push(cells);
    }
    write("runs", &["scene", "Lagrange", "Maggi", "Kane", "reduced Volterra", "reduced / Kane"], &rows);
    let none = at(scenes.len(), 0).unwrap();
    let rows: Vec<Vec<String>> = drifts
        .iter()
        .enumerate()
        .map(|(k, (label, _))| {
            let t = at(scenes.len() + k, 0).unwrap();
            vec![label.to_string(), format!("{t:.0} µs"), format!("{:.1}", t / none)]
        })
        .collect();
    write("drift", &["scene 1, Lagrange: drift control", "time per 50 s run", "/ none"], &rows);
}
