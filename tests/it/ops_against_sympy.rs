//! The scaling goal "assembly operations at most SymPy's cse'd Kane count, at every n", held as
//! a test at the sizes that generate in well under a second: Kane's emitted assembly (what a
//! right-hand side computes before its solve) against `count_ops(cse([M, F]))` of SymPy's
//! `KanesMethod` on the same model, recorded in `docs/scaling/sympy.json` by the scaling
//! benchmark (`cargo bench --bench scaling -- --sympy`).

use generator::emit::{Formulation, Options};

use generator::generate;
use generator::model::examples::{floating_chain, n_link_pendulum_on_cart};

/// `(model, n, SymPy's assembly operations)` from the committed record.
fn sympy_counts() -> Vec<(String, usize, usize)> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/scaling/sympy.json");
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).expect("docs/scaling/sympy.json")).expect("valid JSON");
    let mut out = Vec::new();
    for kind in ["pendulum", "floating"] {
        for r in json[kind].as_array().expect("records per model") {
            out.push((kind.to_string(), r["n"].as_u64().unwrap() as usize, r["assembly_ops"].as_u64().unwrap() as usize));
        }
    }
    out
}

#[test]
fn kane_assembly_is_no_larger_than_sympy_s_cse_count() {
    let counts = sympy_counts();
    let small: Vec<_> = counts.iter().filter(|(kind, n, _)| *n <= if kind == "pendulum" { 10 } else { 4 }).collect();
    // The record covers the smallest sizes of both models, where the margin is thinnest.
    assert!(small.iter().any(|(k, n, _)| k == "pendulum" && *n == 2) && small.iter().any(|(k, n, _)| k == "floating" && *n == 2), "{counts:?}");
    for (kind, n, sympy) in small {
        let model = if kind == "pendulum" { n_link_pendulum_on_cart(*n) } else { floating_chain(*n) }.build().unwrap();
        let options = Options { formulations: vec![Formulation::Kane], ..Options::from_model(&model) };
        let out = generate(&model, &options).unwrap();
        let ours = out.summary.ops("kane::rhs").expect("Kane's right-hand side").ops.total();
        assert!(ours <= *sympy, "{kind} n = {n}: Kane's assembly has {ours} operations, SymPy's cse'd Kane {sympy}");
    }
}
