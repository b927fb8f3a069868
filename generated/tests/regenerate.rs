//! Every committed module is exactly what the generator makes of its model today.
//! `REGENERATE=1 cargo test -p generated --test regenerate` rewrites them instead.

use generator::emit::Options;

use generator::generate;

mod common {
    pub mod variants;
}
use common::variants::variants;

#[test]
fn committed_modules_match_the_generator() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let rewrite = std::env::var_os("REGENERATE").is_some();
    let mut stale = Vec::new();
    let mut counters = String::from("# Work counters of the committed modules (regenerated with them).\n");
    for (module, model, edit) in variants() {
        let m = generator::model::load(format!("{root}/models/{model}.ron")).unwrap();
        // The committed modules carry their Jacobians (`--jacobian`): the tests check them.
        let mut options = Options { module_name: Some(module.to_string()), jacobian: true, ..Options::from_model(&m) };
        edit(&mut options);
        let out = generate(&m, &options).unwrap();
        counters += &format!("\n[{module}]\n{}", out.summary.work_counters());
        let code = out.code;
        let path = format!("{root}/generated/src/{module}.rs");
        let committed = std::fs::read_to_string(&path).unwrap_or_default();
        if committed != code {
            if rewrite {
                std::fs::write(&path, &code).unwrap();
            } else {
                stale.push(module);
            }
        }
    }
    // Op counts as a golden file: a change in emitted work shows in review.
    let path = format!("{root}/generated/op-counts.txt");
    if std::fs::read_to_string(&path).unwrap_or_default() != counters {
        if rewrite {
            std::fs::write(&path, &counters).unwrap();
        } else {
            stale.push("op-counts.txt");
        }
    }
    assert!(stale.is_empty(), "stale generated modules {stale:?}: run `REGENERATE=1 cargo test -p generated --test regenerate`");
}

#[test]
fn generation_is_deterministic_across_threads() {
    const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let root = ROOT;
    let run = move || {
        let m = generator::model::load(format!("{root}/models/three_body.ron")).unwrap();
        generate(&m, &Options::from_model(&m)).unwrap().code
    };
    let a = std::thread::spawn(run).join().unwrap();
    // A second pool that has seen other expressions first.
    let b = std::thread::spawn(move || {
        let m = generator::model::load(format!("{root}/models/cart_pendulum.ron")).unwrap();
        let _ = generate(&m, &Options::from_model(&m)).unwrap();
        run()
    })
    .join()
    .unwrap();
    assert_eq!(a, b);
}
