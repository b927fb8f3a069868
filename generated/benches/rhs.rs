//! Nanoseconds per right-hand-side call, per scene and formulation, through the typed
//! functions of each emitted module (no slices, no conversions).
//!
//! `cargo bench -p generated --bench rhs`

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

macro_rules! bench_rhs {
    ($c:expr, $m:ident, $label:expr, [$($f:ident),*]) => {{
        use generated::$m as model;
        let mut group = $c.benchmark_group(format!("rhs/{}", $label));
        let params = model::Params::default();
        $(
            let (state, g_i) = model::$f::initial_state(0.0, &model::INITIAL_Q, &model::INITIAL_QDOT, &params).unwrap();
            let mut dstate = [0.0; model::$f::STATES];
            group.bench_function(stringify!($f), |b| {
                b.iter(|| model::$f::rhs(black_box(0.0), black_box(&state), black_box(&params), black_box(&g_i), &mut dstate))
            });
        )*
        group.finish();
    }};
}

fn rhs(c: &mut Criterion) {
    bench_rhs!(c, cart_pendulum, "cart_pendulum", [lagrange, maggi, kane, reduced_volterra]);
    bench_rhs!(c, cart_pendulum_baked, "cart_pendulum_baked", [reduced_volterra, kane]);
    bench_rhs!(c, three_body, "three_body", [lagrange, maggi, kane, reduced_volterra]);
    bench_rhs!(c, three_body_drop, "three_body_drop", [reduced_volterra]);
    bench_rhs!(c, three_body_split, "three_body_split", [reduced_volterra, kane]);
    bench_rhs!(c, satellite_boom, "satellite_boom", [lagrange, maggi, kane, reduced_volterra]);
}

criterion_group!(benches, rhs);
criterion_main!(benches);
