//! The scaling benchmark's chains evaluated in-process give their compiled modules' numbers:
//! the 20-link pendulum on a cart and the spatial chain of 8 links on a floating base, each
//! module compiled here with rustc into a program that prints every formulation's right-hand
//! side at fixed states, to 1e-13 relative against `generator::eval`.

use crate::support;

use generator::emit::Options;

use generator::generate;
use generator::model::examples::{floating_chain, n_link_pendulum_on_cart};

/// The states both sides evaluate at (the same formula in the compiled program).
fn state(n: usize, k: usize) -> Vec<f64> {
    (0..n).map(|i| 0.3 * ((i as f64) * 1.7 + k as f64).sin()).collect()
}

#[test]
fn chains_evaluated_in_process_equal_their_compiled_modules() {
    let dir = tempfile::tempdir().unwrap();
    for builder in [n_link_pendulum_on_cart(20), floating_chain(8)] {
        let model = builder.build().unwrap();
        let code = generate(&model, &Options::from_model(&model)).unwrap().code;
        let printed = support::rustc::printed_rates(dir.path(), &model.name, &code, &["-C", "opt-level=1"]);
        let evaluated = generator::evaluate(&model).unwrap();
        let mut compared = 0;
        for (name, k, rates) in printed {
            let name = name.as_str();
            let form = evaluated.formulations.iter().find(|f| f.name() == name).unwrap();
            let y = state(form.states(), k);
            let g: Vec<f64> = (0..evaluated.ignorable.len()).map(|i| 0.1 * (i + k + 1) as f64).collect();
            let mut d = vec![0.0; y.len()];
            let result = form.rhs(0.25, &y, &evaluated.default_params, &g, &mut d);
            let Some(rates) = rates else {
                assert!(result.is_err(), "{} {name} #{k}: the compiled module refused, the evaluation did not", model.name);
                continue;
            };
            result.unwrap_or_else(|e| panic!("{} {name} #{k}: {e}", model.name));
            assert_eq!(rates.len(), d.len());
            for (i, (&c, x)) in rates.iter().zip(&d).enumerate() {
                assert!((c - x).abs() <= 1e-13 * c.abs().max(x.abs()) || c == *x, "{} {name} #{k} [{i}]: compiled {c:e}, evaluated {x:e}", model.name);
                compared += 1;
            }
        }
        assert!(compared > 100, "{}: {compared} values", model.name);
    }
}

/// Maggi's `rhs` on the planar chain in absolute angles (no constraints: `W` reorders the
/// speeds, `c` is zero) reuses the body of Lagrange's, its outputs reordered: both give the
/// same rates of `[q; q']` at the same states, with the same operation counts.
#[test]
fn maggi_reusing_lagranges_body_gives_lagranges_rates() {
    use generator::model::examples::planar_chain_absolute;
    let model = planar_chain_absolute(4).build().unwrap();
    let summary = generate(&model, &Options::from_model(&model)).unwrap().summary;
    let (lagrange, maggi) = (summary.ops("lagrange::rhs").unwrap(), summary.ops("maggi::rhs").unwrap());
    assert_eq!((lagrange.lets, &lagrange.ops), (maggi.lets, &maggi.ops));
    let evaluated = generator::evaluate(&model).unwrap();
    let form = |name: &str| evaluated.formulations.iter().find(|f| f.name() == name).unwrap();
    let (lagrange, maggi) = (form("lagrange"), form("maggi"));
    assert_eq!(lagrange.states(), maggi.states());
    let mut compared = 0;
    for k in 0..5 {
        let y = state(lagrange.states(), k);
        let g: Vec<f64> = (0..evaluated.ignorable.len()).map(|i| 0.2 * (i + k) as f64 - 0.1).collect();
        let (mut dl, mut dm) = (vec![0.0; y.len()], vec![0.0; y.len()]);
        lagrange.rhs(0.0, &y, &evaluated.default_params, &g, &mut dl).unwrap();
        maggi.rhs(0.0, &y, &evaluated.default_params, &g, &mut dm).unwrap();
        for (i, (l, m)) in dl.iter().zip(&dm).enumerate() {
            assert!((l - m).abs() <= 1e-12 * l.abs().max(1.0), "state #{k} [{i}]: Lagrange {l:e}, Maggi {m:e}");
            compared += usize::from(*l != 0.0);
        }
    }
    assert!(compared > 20, "{compared} nonzero rates");
}

/// Kane's `rhs` on the same chain (its quasi-velocities are the rates in another order) reuses
/// Lagrange's body with the speeds renamed and rebound to their places in Kane's state: at the
/// same `q, q'`, Kane's `u'`, turned into `q''` by its own `velocities`, is Lagrange's `q''`.
#[test]
fn kane_reusing_lagranges_body_under_its_speeds_names_gives_lagranges_accelerations() {
    use generator::model::examples::planar_chain_absolute;
    let model = planar_chain_absolute(4).build().unwrap();
    let summary = generate(&model, &Options::from_model(&model)).unwrap().summary;
    let (lagrange, kane) = (summary.ops("lagrange::rhs").unwrap(), summary.ops("kane::rhs").unwrap());
    assert_eq!((lagrange.lets, &lagrange.ops), (kane.lets, &kane.ops), "Kane's body is Lagrange's");
    let evaluated = generator::evaluate(&model).unwrap();
    let form = |name: &str| evaluated.formulations.iter().find(|f| f.name() == name).unwrap();
    let (lagrange, kane) = (form("lagrange"), form("kane"));
    let (m, p) = (model.m(), &evaluated.default_params);
    let mut compared = 0;
    for k in 0..5 {
        let q = state(m, k);
        let qdot = state(m, k + 7);
        let states = |f: &seam::Formulation| {
            let (mut y, mut g) = (vec![0.0; f.states()], vec![0.0; evaluated.ignorable.len()]);
            f.initial_state(0.0, &q, &qdot, p, &mut y, &mut g).unwrap();
            let mut d = vec![0.0; y.len()];
            f.rhs(0.0, &y, p, &g, &mut d).unwrap();
            (y, g, d)
        };
        let (_, _, dl) = states(lagrange);
        let (mut y, g, dk) = states(kane);
        assert_ne!(y[m..], qdot[..], "Kane's speeds are the rates in another order");
        y[m..].copy_from_slice(&dk[m..]);
        let (mut q_back, mut qddot) = (vec![0.0; m], vec![0.0; m]);
        kane.velocities(0.0, &y, p, &g, &mut q_back, &mut qddot).unwrap();
        for (i, (l, c)) in dl[m..].iter().zip(&qddot).enumerate() {
            assert!((l - c).abs() <= 1e-12 * l.abs().max(1.0), "state #{k} q''[{i}]: Lagrange {l:e}, Kane {c:e}");
            compared += usize::from(*l != 0.0);
        }
    }
    assert!(compared > 15, "{compared} nonzero accelerations");
}
