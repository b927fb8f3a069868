//! A process that generates many models does not grow without bound: each derivation runs in an
//! expression context of its own ([`generator::model::in_own_context`]), freed when it returns;
//! and a symbol read in a context that did not make it is an error, not another symbol's name.

use generator::symbolic::{Context, Symbol};

#[test]
fn generations_leave_only_their_models_in_the_caller_s_context() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/three_body.ron")).unwrap();
    // Distinct names, as a parameter study or a service would have.
    let renamed = |i: usize| text.replace("\"m1\"", &format!("\"mass_{i}\"")).replace("m1*", &format!("mass_{i}*")).replace("m1 ", &format!("mass_{i} "));
    let run = |i: usize| {
        let model = generator::model::from_source("three_body.ron", &renamed(i)).unwrap();
        generator::generate(&model, &generator::emit::Options::from_model(&model)).unwrap();
    };
    let cx = Context::new();
    cx.enter(|| {
        run(0);
        let after_one = Context::current_nodes();
        for i in 1..30 {
            run(i);
        }
        let grown = Context::current_nodes() - after_one;
        // What one derivation builds, for scale: held here, it would be the growth per model.
        let before = Context::current_nodes();
        let model = generator::model::from_source("three_body.ron", &renamed(999)).unwrap();
        let loaded = Context::current_nodes() - before;
        let _ = generator::formulation::derive(&model, &generator::formulation::Request::all()).unwrap();
        let derived = Context::current_nodes() - before - loaded;
        assert!(derived > 20 * loaded, "a derivation builds {derived} nodes, a load {loaded}");
        // 29 more generations add at most their 29 loads.
        assert!(grown <= 29 * loaded, "29 generations grew the caller's context by {grown} nodes; one load is {loaded}");
    });
}

#[test]
fn a_symbol_read_in_another_context_is_an_error() {
    let a = Context::new();
    let s = a.enter(|| Symbol::new("theta"));
    assert_eq!(a.enter(|| s.name()), "theta");
    let b = Context::new();
    let read = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| b.enter(|| s.name())));
    let message = read.expect_err("reading a symbol in another context panics");
    let text = message.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| message.downcast_ref::<String>().cloned()).unwrap_or_default();
    assert!(text.contains("a symbol was used outside the context that made it"), "{text}");
    // Used in an expression there, too.
    assert!(std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| b.enter(|| s.expr()))).is_err());
}
