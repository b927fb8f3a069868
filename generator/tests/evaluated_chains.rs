//! The scaling benchmark's chains evaluated in-process give their compiled modules' numbers:
//! the 20-link pendulum on a cart and the spatial chain of 8 links on a floating base, each
//! module compiled here with rustc into a program that prints every formulation's right-hand
//! side at fixed states, to 1e-13 relative against `generator::eval`.

mod support {
    pub mod rustc;
}

use generator::emit::{Options, generate};
use generator::model::examples::{floating_chain, n_link_pendulum_on_cart};

/// The states both sides evaluate at (the same formula in the compiled program).
fn state(n: usize, k: usize) -> Vec<f64> {
    (0..n).map(|i| 0.3 * ((i as f64) * 1.7 + k as f64).sin()).collect()
}

const MAIN: &str = r#"
fn main() {
    let m = model();
    for f in &m.formulations {
        for k in 0..3usize {
            let n = f.states();
            let y: Vec<f64> = (0..n).map(|i| 0.3 * ((i as f64) * 1.7 + k as f64).sin()).collect();
            let g: Vec<f64> = (0..m.ignorable.len()).map(|i| 0.1 * (i + k + 1) as f64).collect();
            let mut d = vec![0.0; n];
            match f.rhs(0.25, &y, &m.default_params, &g, &mut d) {
                Ok(()) => println!("{} {} {}", f.name(), k, d.iter().map(|x| x.to_bits().to_string()).collect::<Vec<_>>().join(" ")),
                Err(_) => println!("{} {} error", f.name(), k),
            }
        }
    }
}
"#;

#[test]
fn chains_evaluated_in_process_equal_their_compiled_modules() {
    let dir = tempfile::tempdir().unwrap();
    for builder in [n_link_pendulum_on_cart(20), floating_chain(8)] {
        let model = builder.build().unwrap();
        let code = generate(&model, &Options::from_model(&model)).unwrap().code;
        let source = dir.path().join(format!("{}.rs", model.name));
        std::fs::write(&source, code + MAIN).unwrap();
        let binary = dir.path().join(&model.name);
        let out =
            support::rustc::rustc().args(["--crate-type", "bin", "-C", "opt-level=1", "-A", "warnings", "-o"]).arg(&binary).arg(&source).output().unwrap();
        assert!(out.status.success(), "{}: {}", model.name, String::from_utf8_lossy(&out.stderr));
        let printed = std::process::Command::new(&binary).output().unwrap();
        assert!(printed.status.success());
        let evaluated = generator::eval::evaluate(&model).unwrap();
        let mut compared = 0;
        for line in String::from_utf8(printed.stdout).unwrap().lines() {
            let mut words = line.split_whitespace();
            let (name, k) = (words.next().unwrap(), words.next().unwrap().parse::<usize>().unwrap());
            let form = evaluated.formulations.iter().find(|f| f.name() == name).unwrap();
            let y = state(form.states(), k);
            let g: Vec<f64> = (0..evaluated.ignorable.len()).map(|i| 0.1 * (i + k + 1) as f64).collect();
            let mut d = vec![0.0; y.len()];
            let result = form.rhs(0.25, &y, &evaluated.default_params, &g, &mut d);
            let rest: Vec<&str> = words.collect();
            if rest == ["error"] {
                assert!(result.is_err(), "{} {name} #{k}: the compiled module refused, the evaluation did not", model.name);
                continue;
            }
            result.unwrap_or_else(|e| panic!("{} {name} #{k}: {e}", model.name));
            assert_eq!(rest.len(), d.len());
            for (i, (bits, x)) in rest.iter().zip(&d).enumerate() {
                let c = f64::from_bits(bits.parse().unwrap());
                assert!((c - x).abs() <= 1e-13 * c.abs().max(x.abs()) || c == *x, "{} {name} #{k} [{i}]: compiled {c:e}, evaluated {x:e}", model.name);
                compared += 1;
            }
        }
        assert!(compared > 100, "{}: {compared} values", model.name);
    }
}
