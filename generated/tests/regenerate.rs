//! Every committed module is exactly what the generator makes of its model today.
//! `REGENERATE=1 cargo test -p generated --test regenerate` rewrites them instead.

use generator::emit::{Formulation, Options, Parameters, generate};

/// (module, model, how its options differ from the model's own).
fn variants() -> Vec<(&'static str, &'static str, fn(&mut Options))> {
    vec![
        // `--parameter-jacobian` where the module is small.
        ("cart_pendulum", "cart_pendulum", |o| o.parameter_jacobian = true),
        ("three_body", "three_body", |_| {}),
        ("satellite_boom", "satellite_boom", |o| o.parameter_jacobian = true),
        ("cartesian_pendulum", "cartesian_pendulum", |_| {}),
        ("rolling_disk", "rolling_disk", |o| o.parameter_jacobian = true),
        ("spring_cart", "spring_cart", |o| o.parameter_jacobian = true),
        ("pendulum_on_cart_5", "pendulum_on_cart_5", |_| {}),
        ("stiff_pendulum", "stiff_pendulum", |o| o.parameter_jacobian = true),
        // The bicycle's exact Jacobians would be 250000 operations each: left out.
        ("bicycle", "bicycle", |o| o.jacobian = false),
        // `--formulations lagrange --jacobian`: the bicycle's multiplier form with its exact
        // Jacobian (12136 operations), for linearization to round-off.
        ("bicycle_lagrange", "bicycle", |o| o.formulations = vec![Formulation::Lagrange]),
        // `--baked`
        ("cart_pendulum_baked", "cart_pendulum", |o| o.parameters = Parameters::Baked),
        // `--max-lets 40`
        ("three_body_split", "three_body", |o| o.max_lets_per_function = 40),
        // `--drop-ignorable --formulations reduced_volterra`
        ("three_body_drop", "three_body", |o| {
            o.integrate_ignorable = false;
            o.formulations = vec![Formulation::ReducedVolterra];
        }),
    ]
}

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
