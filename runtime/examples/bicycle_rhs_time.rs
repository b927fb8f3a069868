//! One right-hand-side call of the bicycle (`models/bicycle.ron`), per formulation, at the
//! upright 5 m/s state with a lean rate: `cargo run --release -p runtime --example bicycle_rhs_time`.
//! Best of 7 rounds of 20000 calls; prints nanoseconds per call.

use runtime::linearize::Operating;
use runtime::system::System;
use std::time::Instant;

fn main() {
    let model = generated::find("bicycle").expect("committed");
    let m = model.coordinates.len();
    let idx = |n: &str| model.coordinate_index(n).expect("a coordinate");
    let mut qdot = vec![0.0; m];
    qdot[idx("x")] = 5.0;
    qdot[idx("phi")] = 0.05;
    let at = Operating { q: vec![0.0; m], qdot, params: model.default_params.clone(), held: vec![idx("x"), idx("phi"), idx("delta")] };
    let qd = at.consistent_rates(&model).expect("consistent");
    for form in &model.formulations {
        let (sys, y0) = System::start(&model, form.kind, at.params.clone(), &at.q, &qd).expect("starts");
        let mut dy = vec![0.0; y0.len()];
        let mut best = f64::INFINITY;
        for _ in 0..7 {
            let start = Instant::now();
            for _ in 0..20000 {
                sys.rhs(0.0, std::hint::black_box(&y0), &mut dy).expect("evaluates");
            }
            best = best.min(start.elapsed().as_secs_f64() * 1e9 / 20000.0);
        }
        println!("{}: {best:.0} ns per call", form.name());
    }
}
