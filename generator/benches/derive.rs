//! Time to derive and emit each scene's module, from a cold start: every run in a fresh thread,
//! so the thread-local expression pool and its memos start empty; the scenes interleaved, best
//! of 15 runs each.
//!
//! `cargo bench -p generator --bench derive` writes `docs/benchmarks/derive.json` (the table of
//! `docs/benchmarks.md`, checked by `tests/it/figures.rs`) and prints it.

use generator::emit::Options;

use generator::generate;
use std::time::Instant;

const COMMAND: &str = "cargo bench -p generator --bench derive";

fn main() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let scenes = [("cart_pendulum", "1 cart_pendulum"), ("three_body", "2 three_body"), ("satellite_boom", "3 satellite_boom")];
    let mut best = [f64::INFINITY; 3];
    for _ in 0..15 {
        for (k, (scene, _)) in scenes.iter().enumerate() {
            let path = format!("{root}/models/{scene}.ron");
            let start = Instant::now();
            let bytes = std::thread::spawn(move || {
                let model = generator::model::load(&path).unwrap();
                generate(&model, &Options::from_model(&model)).unwrap().code.len()
            })
            .join()
            .unwrap();
            assert!(bytes > 0);
            best[k] = best[k].min(start.elapsed().as_secs_f64());
        }
    }
    let columns = ["scene", "load + derive + emit (best of 15, fresh thread)"];
    let rows: Vec<Vec<String>> = scenes.iter().zip(best).map(|((_, label), s)| vec![label.to_string(), format!("{:.1} ms", s * 1e3)]).collect();
    let json = serde_json::json!({ "command": COMMAND, "columns": columns, "rows": rows });
    std::fs::write(format!("{root}/docs/benchmarks/derive.json"), serde_json::to_string_pretty(&json).unwrap() + "\n").unwrap();
    println!("{}", std::iter::once(columns.join(" | ")).chain(rows.iter().map(|r| r.join(" | "))).collect::<Vec<_>>().join("\n"));
}
