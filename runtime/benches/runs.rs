//! Whole runs: each scene's 50 s reference run at the paper's settings, per formulation, and
//! the modelling choices that trade (baked parameters, ignorable coordinates left out, drift
//! control). Target: every 50 s run under 5 ms on one core.
//!
//! `cargo bench -p runtime --bench runs`

use criterion::{Criterion, criterion_group, criterion_main};
use runtime::compare::Reference;
use runtime::integrate::{Projector, Settings, integrate, integrate_projected};
use runtime::system::{Drift, System};
use std::hint::black_box;

fn whole_runs(c: &mut Criterion) {
    for scene in ["cart_pendulum", "cart_pendulum_baked", "three_body", "three_body_drop", "satellite_boom"] {
        let model = generated::find(scene).unwrap();
        let mut group = c.benchmark_group(format!("run/{scene}"));
        group.sample_size(20);
        let r = Reference::of(&model).unwrap();
        let settings = Settings::paper(r.t_end - r.t_start);
        let times = r.times().unwrap();
        for form in &model.formulations {
            let (sys, y0) = System::start(&model, form.kind, r.params.clone(), &r.q0, &r.qd0).unwrap();
            group.bench_function(form.name(), |b| {
                b.iter(|| integrate(&mut |t, y, dy| sys.rhs(t, y, dy), black_box(&y0), &times, &settings).unwrap().stats.rhs_calls)
            });
        }
        group.finish();
    }
    // Drift control costs time (and buys constraint accuracy): scene 1, Lagrange, integration
    // only (no monitors).
    let model = generated::find("cart_pendulum").unwrap();
    let settings = Settings::paper(50.0);
    let r = Reference::of(&model).unwrap();
    let times = r.times().unwrap();
    let mut group = c.benchmark_group("run/cart_pendulum_drift");
    group.sample_size(20);
    for (label, drift) in [("none", Drift::None), ("baumgarte", Drift::Baumgarte { alpha: 10.0, beta: 10.0 }), ("projection", Drift::Projection)] {
        let (sys, y0) = System::start(&model, seam::FormulationKind::Lagrange, r.params.clone(), &r.q0, &r.qd0).unwrap();
        let sys = sys.with_drift(drift).unwrap();
        group.bench_function(label, |b| {
            b.iter(|| {
                let mut project = |t: f64, y: &mut [f64]| sys.project(t, y);
                let projector: Option<Projector> = if drift == Drift::Projection { Some(&mut project) } else { None };
                integrate_projected(&mut |t, y, dy| sys.rhs(t, y, dy), projector, black_box(&y0), &times, &settings).unwrap().stats.rhs_calls
            })
        });
    }
    group.finish();
}

criterion_group!(benches, whole_runs);
criterion_main!(benches);
