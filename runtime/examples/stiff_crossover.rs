//! The stiff extreme's crossover: `cargo run --release -p runtime --example stiff_crossover`.
//! For spring stiffnesses 1e3 to 1e9 (`models/stiff_pendulum.ron`, damping ratio 5), DOPRI5
//! and the Rosenbrock 2(3) method with the exact Jacobian at rtol = atol = 1e-4 on Kane's
//! equations over 2 s: steps, right-hand-side calls (Jacobians counted apart), CPU time
//! (median of 5) and the largest coordinate error against a Rosenbrock run at 1e-9. Prints a
//! Markdown table for docs/work-precision.md.

use runtime::integrate::{Method, Settings, Solution, integrate_with_jacobian};
use runtime::system::System;
use std::time::Instant;

fn solve(sys: &System, y0: &[f64], times: &[f64], method: Method, tol: f64) -> (Solution, f64) {
    let s = Settings { method, rtol: tol, atol: tol, h_max: 0.2, ..Settings::default() };
    let mut cpu = Vec::new();
    let mut out = None;
    for _ in 0..5 {
        let start = Instant::now();
        let mut exact = |t: f64, y: &[f64], dy: &mut [f64], j: &mut [f64]| sys.jacobian(t, y, dy, j);
        let sol = integrate_with_jacobian(&mut |t, y, dy| sys.rhs(t, y, dy), Some(&mut exact), None, y0, times, &s).expect("the run finishes");
        cpu.push(start.elapsed().as_secs_f64());
        out = Some(sol);
    }
    cpu.sort_by(f64::total_cmp);
    (out.expect("ran"), cpu[2])
}

fn main() {
    let model = generated::find("stiff_pendulum").expect("committed");
    let (q0, qd0) = model.initial.clone().expect("an initial state");
    let k_index = model.parameter_index("k").expect("k");
    let times: Vec<f64> = (0..=200).map(|i| i as f64 * 0.01).collect();
    println!(
        "| k | DOPRI5 steps | DOPRI5 rhs calls | DOPRI5 ms | DOPRI5 error | ROS23 steps | ROS23 rhs calls + Jacobians | ROS23 ms | ROS23 error | CPU DOPRI5 / ROS23 |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for e in 3..=9 {
        let k = 10f64.powi(e);
        let mut params = model.default_params.clone();
        params[k_index] = k;
        let (sys, y0) = System::start(&model, seam::FormulationKind::Kane, params, &q0, &qd0).expect("starts");
        let (reference, _) = solve(&sys, &y0, &times, Method::Rosenbrock23, 1e-9);
        let error =
            |s: &Solution| s.states.iter().zip(&reference.states).flat_map(|(a, b)| a[..3].iter().zip(&b[..3]).map(|(x, y)| (x - y).abs())).fold(0.0, f64::max);
        let (d, dt) = solve(&sys, &y0, &times, Method::Dopri5, 1e-4);
        let (r, rt) = solve(&sys, &y0, &times, Method::Rosenbrock23, 1e-4);
        println!(
            "| 1e{e} | {} | {} | {:.2} | {:.1e} | {} | {} + {} | {:.2} | {:.1e} | {:.2} |",
            d.stats.steps,
            d.stats.rhs_calls,
            dt * 1e3,
            error(&d),
            r.stats.steps,
            r.stats.rhs_calls,
            r.stats.jacobians,
            rt * 1e3,
            error(&r),
            dt / rt
        );
    }
}
