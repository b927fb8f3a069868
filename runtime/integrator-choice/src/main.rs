//! Our DOPRI5 against `ode_solvers`' on scene 2 (reduced Volterra, 13 states), same
//! tolerances, same output times: time per 50 s run (median of 21) and the agreement.
//!
//! `cargo run --release --manifest-path runtime/integrator-choice/Cargo.toml` writes
//! `docs/benchmarks/integrators.json` (the table of `docs/benchmarks.md`, checked by
//! `tests/it/figures.rs`) and prints it.

use ode_solvers::{Dopri5, SVector, System};
use runtime::compare::Reference;
use runtime::integrate::{Method, Settings, integrate};
use std::time::Instant;

type State = SVector<f64, 13>;

struct Scene2 {
    params: generated::three_body::Params,
    g_i: [f64; 3],
}

impl System<f64, State> for Scene2 {
    fn system(&self, t: f64, y: &State, dy: &mut State) {
        let state: [f64; 13] = y.as_slice().try_into().unwrap();
        let mut out = [0.0; 13];
        generated::three_body::reduced_volterra::rhs(t, &state, &self.params, &self.g_i, &mut out).unwrap();
        dy.copy_from_slice(&out);
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    use generated::three_body as model;
    let params = model::Params::default();
    let (y0, g_i) = model::reduced_volterra::initial_state(0.0, &model::INITIAL_Q, &model::INITIAL_QDOT, &params).unwrap();
    let registry = generated::find("three_body").unwrap();
    let times = Reference::of(&registry).unwrap().times().unwrap();
    let mut rows = Vec::new();
    for tol in [1e-3, 1e-6, 1e-9] {
        let settings = Settings { method: Method::Dopri5, rtol: tol, atol: tol, h_max: 50.0, ..Settings::default() };
        let mut ours = Vec::new();
        let mut last = Vec::new();
        let mut our_calls = 0;
        for _ in 0..21 {
            let start = Instant::now();
            let sol = integrate(
                &mut |t, y, dy| model::reduced_volterra::rhs(t, y.try_into().unwrap(), &params, &g_i, dy.try_into().unwrap()),
                &y0,
                &times,
                &settings,
            )
            .unwrap();
            ours.push(start.elapsed().as_secs_f64());
            last = sol.states.last().unwrap().to_vec();
            our_calls = sol.stats.rhs_calls;
        }
        let mut theirs = Vec::new();
        let mut their_last = State::zeros();
        let mut their_calls = 0;
        for _ in 0..21 {
            let start = Instant::now();
            let mut solver = Dopri5::new(Scene2 { params, g_i }, 0.0, 50.0, 0.1, State::from_column_slice(&y0), tol, tol);
            their_calls = solver.integrate().unwrap().num_eval;
            theirs.push(start.elapsed().as_secs_f64());
            their_last = *solver.y_out().last().unwrap();
        }
        let diff = last.iter().zip(their_last.iter()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        let (a, b) = (median(ours) * 1e3, median(theirs) * 1e3);
        rows.push(vec![
            format!("{tol:e}"),
            format!("{a:.3} ({our_calls} calls, {:.0} ns/call)", a * 1e6 / our_calls as f64),
            format!("{b:.3} ({their_calls} calls, {:.0} ns/call)", b * 1e6 / their_calls as f64),
            format!("{:.2}", b / a),
            format!("{diff:.1e}"),
        ]);
    }
    let columns = [
        "rtol = atol",
        "ours: ms (rhs calls, ns per call incl. stepping)",
        "ode_solvers 0.6: ms (rhs calls, ns per call)",
        "time ode_solvers / ours",
        "max difference at t_end",
    ];
    let command = "cargo run --release --manifest-path runtime/integrator-choice/Cargo.toml";
    let json = serde_json::json!({ "command": command, "columns": columns, "rows": rows });
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/benchmarks/integrators.json");
    std::fs::write(path, serde_json::to_string_pretty(&json).unwrap() + "\n").unwrap();
    println!("{}", std::iter::once(columns.join(" | ")).chain(rows.iter().map(|r| r.join(" | "))).collect::<Vec<_>>().join("\n"));
}
