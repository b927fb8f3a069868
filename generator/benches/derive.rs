//! Time to derive and emit each scene's module, from a cold start: every iteration runs in a
//! fresh thread, so the thread-local expression pool and its memos start empty.
//!
//! `cargo bench -p generator --bench derive`

use criterion::{Criterion, criterion_group, criterion_main};
use generator::emit::{Options, generate};

fn derive(c: &mut Criterion) {
    let mut group = c.benchmark_group("derive_and_emit");
    group.sample_size(10);
    for scene in ["cart_pendulum", "three_body", "satellite_boom"] {
        let path = format!("{}/../models/{scene}.ron", env!("CARGO_MANIFEST_DIR"));
        group.bench_function(scene, |b| {
            b.iter(|| {
                let path = path.clone();
                std::thread::spawn(move || {
                    let model = generator::model::load(&path).unwrap();
                    generate(&model, &Options::from_model(&model)).unwrap().code.len()
                })
                .join()
                .unwrap()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, derive);
criterion_main!(benches);
