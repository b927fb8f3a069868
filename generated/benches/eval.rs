//! In-process evaluation against the compiled module, side by side in one run: ns per
//! right-hand-side call of every formulation of the paper's scenes and the 5-link pendulum on
//! a cart, compiled by rustc, interpreted from tapes, and compiled from the tapes by cranelift
//! (`jit`, what the `multibody` tool runs), and the module built by rustc into a library loaded
//! through a C ABI (`native`, what `multibody --compiled` runs) (interleaved, best of 30 rounds
//! of 2,000 calls each),
//! and the time from a model file to scene 2's first comparison table as the tool makes it (load,
//! derive, tapes, the JIT, four runs; best of 5).
//!
//! `cargo bench -p generated --bench eval` writes `docs/benchmarks/eval.json` and prints the
//! table that `docs/benchmarks.md` quotes.

use std::hint::black_box;
use std::time::Instant;

fn ns_per_call(form: &seam::Formulation, state: &[f64], params: &[f64], g: &[f64]) -> f64 {
    let mut d = vec![0.0; state.len()];
    let calls = 2000;
    let start = Instant::now();
    for _ in 0..calls {
        form.rhs(0.1, black_box(state), params, g, &mut d).unwrap();
    }
    start.elapsed().as_secs_f64() * 1e9 / calls as f64
}

fn main() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let mut rows = Vec::new();
    let mut table = String::from(
        "| model | formulation | compiled ns | interpreted ns | ratio | JIT ns | ratio | --compiled ns | ratio |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    let cache = tempfile::tempdir().unwrap();
    for name in ["cart_pendulum", "three_body", "satellite_boom", "pendulum_on_cart_5"] {
        let compiled = generated::find(name).unwrap();
        let m = generator::model::load(format!("{root}/models/{name}.ron")).unwrap();
        let evaluated = generator::evaluate(&m).unwrap();
        let jitted = generator::evaluate_with_backend(&m, &generator::emit::Options::from_model(&m), &jit::Jit::default()).unwrap().0;
        jit::settle();
        let generated = generator::generate(&m, &generator::emit::Options { tapes: true, ..generator::emit::Options::from_model(&m) }).unwrap();
        let library = native::build(&generated.code, cache.path(), &mut |_| {}).unwrap();
        let built = library.model(generator::eval::model::Evaluated::model(generated.program.unwrap())).unwrap();
        let (q0, qd0) = compiled.initial.clone().unwrap();
        let params = compiled.default_params.clone();
        for (((fc, fe), fj), fn_) in compiled.formulations.iter().zip(&evaluated.formulations).zip(&jitted.formulations).zip(&built.formulations) {
            let (mut y, mut g) = (vec![0.0; fc.states()], vec![0.0; compiled.ignorable.len()]);
            fc.initial_state(0.0, &q0, &qd0, &params, &mut y, &mut g).unwrap();
            let (mut best_c, mut best_e, mut best_j, mut best_n) = (f64::INFINITY, f64::INFINITY, f64::INFINITY, f64::INFINITY);
            for _ in 0..30 {
                best_c = best_c.min(ns_per_call(fc, &y, &params, &g));
                best_e = best_e.min(ns_per_call(fe, &y, &params, &g));
                best_j = best_j.min(ns_per_call(fj, &y, &params, &g));
                best_n = best_n.min(ns_per_call(fn_, &y, &params, &g));
            }
            table += &format!(
                "| {name} | {} | {best_c:.0} | {best_e:.0} | {:.2} | {best_j:.0} | {:.2} | {best_n:.0} | {:.2} |\n",
                fc.name(),
                best_e / best_c,
                best_j / best_c,
                best_n / best_c
            );
            rows.push(serde_json::json!({
                "model": name, "formulation": fc.name(), "compiled_ns": best_c, "evaluated_ns": best_e, "ratio": best_e / best_c, "jit_ns": best_j, "jit_ratio": best_j / best_c,
                "native_ns": best_n, "native_ratio": best_n / best_c
            }));
        }
    }
    // From the model file to the first table, in-process: load, derive, tapes, four runs.
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let start = Instant::now();
        let m = generator::model::load(format!("{root}/models/three_body.ron")).unwrap();
        let model = generator::evaluate_with_backend(&m, &generator::emit::Options::from_model(&m), &jit::Jit::default()).unwrap().0;
        let runs = runtime::compare::compare(&model, &runtime::compare::Options { repeats: 1, ..runtime::compare::Options::paper(&model) }).unwrap();
        black_box(runtime::compare::table(&runs));
        best = best.min(start.elapsed().as_secs_f64());
    }
    table += &format!("\nscene 2 from its model file to the first comparison table, in-process: {:.0} ms (best of 5)\n", best * 1e3);
    print!("{table}");
    let json = serde_json::json!({ "rhs": rows, "scene2_file_to_table_seconds": best });
    let dir = format!("{root}/docs/benchmarks");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(format!("{dir}/eval.json"), serde_json::to_string_pretty(&json).unwrap()).unwrap();
}
