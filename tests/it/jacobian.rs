//! Every emitted `jacobian` (every committed module, every formulation) against central finite
//! differences of its own `rhs`, at random states around the model's initial state.

use generator::symbolic::SplitMix;

/// `(rhs, jac)` at `state`, through the slice interface.
fn exact(f: &generated::Formulation, params: &[f64], g: &[f64], state: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = f.states();
    let (mut ds, mut jac) = (vec![0.0; n], vec![0.0; n * n]);
    f.jacobian(0.3, state, params, g, &mut ds, &mut jac).expect("emitted with its jacobian");
    (ds, jac)
}

fn rhs(f: &generated::Formulation, params: &[f64], g: &[f64], state: &[f64]) -> Vec<f64> {
    let mut ds = vec![0.0; f.states()];
    f.rhs(0.3, state, params, g, &mut ds).unwrap();
    ds
}

/// The state from the model's initial `(q, q')`, each entry moved by up to `spread`.
fn random_state(m: &generated::Model, f: &generated::Formulation, rng: &mut SplitMix, spread: f64) -> (Vec<f64>, Vec<f64>) {
    let (q, qd) = m.initial.clone().expect("committed models have an initial state");
    let mut state = vec![0.0; f.states()];
    let mut g = vec![0.0; m.ignorable.len()];
    f.initial_state(0.0, &q, &qd, &m.default_params, &mut state, &mut g).unwrap();
    for x in state.iter_mut() {
        *x += rng.uniform(-spread, spread);
    }
    (state, g)
}

#[test]
fn jacobians_match_finite_differences_on_every_model() {
    let mut rng = SplitMix(12);
    let mut checked = 0;
    for m in generated::models().iter() {
        for f in &m.formulations {
            // Every committed module carries its Jacobians but the bicycle's (250000 operations
            // each; its linearization differences the right-hand side).
            if !f.has_jacobian {
                assert_eq!(m.module, "bicycle", "{} {} has no jacobian", m.module, f.name());
                continue;
            }
            for _ in 0..4 {
                let (state, g) = random_state(m, f, &mut rng, 0.05);
                let params = &m.default_params;
                let (ds, jac) = exact(f, params, &g, &state);
                let plain = rhs(f, params, &g, &state);
                for (a, b) in ds.iter().zip(&plain) {
                    assert!((a - b).abs() <= 1e-12 * (1.0 + b.abs()), "{} {}: jacobian's rates {ds:?} differ from rhs {plain:?}", m.module, f.name());
                }
                let n = f.states();
                let scale = jac.iter().fold(1.0f64, |a, x| a.max(x.abs()));
                for k in 0..n {
                    let h = 1e-6 * (1.0 + state[k].abs());
                    let (mut up, mut down) = (state.clone(), state.clone());
                    up[k] += h;
                    down[k] -= h;
                    let (a, b) = (rhs(f, params, &g, &up), rhs(f, params, &g, &down));
                    for i in 0..n {
                        let fd = (a[i] - b[i]) / (2.0 * h);
                        let err = (fd - jac[i * n + k]).abs();
                        assert!(err <= 1e-6 * scale, "{} {}: d dstate[{i}] / d state[{k}] = {} exact, {fd} by differences", m.module, f.name(), jac[i * n + k]);
                    }
                }
                checked += 1;
            }
        }
    }
    assert!(checked >= 4 * 4 * 10, "only {checked} states checked");
}

/// Every emitted `parameter_jacobian` against central differences over the parameters.
#[test]
fn parameter_jacobians_match_finite_differences() {
    let mut rng = SplitMix(5);
    let mut modules = Vec::new();
    for m in generated::models().iter() {
        for f in &m.formulations {
            if !f.has_parameter_jacobian {
                continue;
            }
            modules.push(m.module.clone());
            let (n, np) = (f.states(), m.default_params.len());
            for _ in 0..3 {
                let (state, g) = random_state(m, f, &mut rng, 0.05);
                let params = m.default_params.clone();
                let (mut ds, mut jac) = (vec![0.0; n], vec![0.0; n * np]);
                f.parameter_jacobian(0.3, &state, &params, &g, &mut ds, &mut jac).unwrap();
                let scale = jac.iter().fold(1.0f64, |a, x| a.max(x.abs()));
                for k in 0..np {
                    let h = 1e-6 * (1.0 + params[k].abs());
                    let (mut up, mut down) = (params.clone(), params.clone());
                    up[k] += h;
                    down[k] -= h;
                    let (a, b) = (rhs(f, &up, &g, &state), rhs(f, &down, &g, &state));
                    for i in 0..n {
                        let fd = (a[i] - b[i]) / (2.0 * h);
                        assert!(
                            (fd - jac[i * np + k]).abs() <= 1e-6 * scale,
                            "{} {}: d dstate[{i}] / d {} = {} exact, {fd} by differences",
                            m.module,
                            f.name(),
                            m.parameter_names[k],
                            jac[i * np + k]
                        );
                    }
                }
            }
        }
    }
    modules.dedup();
    assert_eq!(modules, ["cart_pendulum", "satellite_boom", "rolling_disk", "spring_cart", "stiff_pendulum", "bouncing_ball", "inverted_pendulum", "winch"]);
}
