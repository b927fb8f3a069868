//! The net under every change (the issue "Every path works"): every model of `models/` and the
//! families the benchmarks use (the pendulum on a cart at n = 1..24, the spatial floating chain at
//! n = 1..10), in every formulation, on every evaluation route (interpreted, the JIT, and code
//! built by rustc for a few), each cell asserting its outcome:
//!
//! - the exact Jacobian against central differences of the right-hand side, at the initial
//!   state and at three random states (the articulated-body and Schur routes among them);
//! - a short run whose invariants hold: the energy or its work balance, the conserved momenta,
//!   the constraints;
//! - or a refusal the cell expects, by name.
//!
//! The command line's cells (every command on every model, by name and by path) are
//! `tests/it/commands.rs`; Python's are `python/tests/test_matrix.py`.

use generator::emit::Options;
use generator::model::examples::{floating_chain, n_link_pendulum_on_cart};
use generator::symbolic::SplitMix;
use runtime::integrate::Settings;
use runtime::system::System;
use seam::Model;

/// A model of the matrix: its name and the generator's model.
struct Case {
    name: String,
    model: generator::model::Model,
}

fn built_in() -> Vec<Case> {
    generator::model::built_in().map(|name| Case { name: name.to_string(), model: generator::model::source(name.as_ref()).unwrap().model().unwrap() }).collect()
}

fn families() -> Vec<Case> {
    let carts = (1..=24).map(|n| Case { name: format!("pendulum_on_cart({n})"), model: n_link_pendulum_on_cart(n).build().unwrap() });
    let chains = (1..=10).map(|n| Case { name: format!("floating_chain({n})"), model: floating_chain(n).build().unwrap() });
    carts.chain(chains).collect()
}

/// The model derived once with its exact Jacobians, as tapes, then evaluated by the interpreter
/// and by the JIT. `None` where the Jacobians exceed the node budget (the bicycle's: its
/// linearization differences them, as `load` does).
fn routes(case: &Case) -> Option<[(&'static str, Model); 2]> {
    let options = Options { jacobian: true, tapes: true, source: false, max_lets_per_function: usize::MAX, ..Options::from_model(&case.model) };
    let generated = match generator::generate(&case.model, &options) {
        Err(e) if e.kind == generator::model::ErrorKind::Budget => return None,
        other => other.unwrap_or_else(|e| panic!("{}: {e}", case.name)),
    };
    let program = generated.program.expect("tapes were asked for");
    let interpreted = generator::eval::model::Evaluated::model(program.clone());
    let jit = generator::eval::model::Evaluated::model_with(program, &jit::Jit::default());
    Some([("interpreted", interpreted), ("jit", jit)])
}

/// The exact Jacobian of `sys` at `y` against central differences of its right-hand side.
fn check_jacobian(what: &str, sys: &System, y: &[f64]) {
    let n = y.len();
    let (mut dy, mut jac) = (vec![0.0; n], vec![0.0; n * n]);
    sys.jacobian(0.3, y, &mut dy, &mut jac).unwrap_or_else(|e| panic!("{what}: the exact Jacobian fails where rhs works: {e}"));
    let mut plain = vec![0.0; n];
    sys.rhs(0.3, y, &mut plain).unwrap();
    for (a, b) in dy.iter().zip(&plain) {
        assert!((a - b).abs() <= 1e-12 * (1.0 + b.abs()), "{what}: the Jacobian's rates {dy:?} against rhs {plain:?}");
    }
    let scale = jac.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    let (mut up, mut down) = (vec![0.0; n], vec![0.0; n]);
    for k in 0..n {
        let h = 1e-6 * (1.0 + y[k].abs());
        let (mut yp, mut ym) = (y.to_vec(), y.to_vec());
        yp[k] += h;
        ym[k] -= h;
        sys.rhs(0.3, &yp, &mut up).unwrap();
        sys.rhs(0.3, &ym, &mut down).unwrap();
        for i in 0..n {
            let fd = (up[i] - down[i]) / (2.0 * h);
            assert!((fd - jac[i * n + k]).abs() <= 1e-6 * scale, "{what}: d dstate[{i}] / d state[{k}] is {} exact, {fd} by differences", jac[i * n + k]);
        }
    }
}

/// A short run of `sys` from `y0` whose invariants hold: the energy (or its balance), the
/// conserved momenta and the constraints, each to what the tolerance allows.
fn check_run(what: &str, model: &Model, sys: &System, y0: &[f64]) {
    let (t0, t_end, dt) = model.run.unwrap_or((0.0, 1.0, 0.01));
    let span = (t_end - t0).min(0.5).min(40.0 * dt);
    let times: Vec<f64> = (0..=20).map(|i| t0 + span * i as f64 / 20.0).collect();
    let settings = Settings { rtol: 1e-10, atol: 1e-10, ..Settings::tight(span) };
    let run = runtime::trajectory::simulate(sys, y0, &times, &settings, &mut |_| {}).unwrap_or_else(|e| panic!("{what}: {e}"));
    let inv = &run.invariants;
    let worst = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let energy_scale = 1.0 + inv.energy0.abs() + worst(&inv.energy);
    assert!(worst(&inv.energy_error) < 1e-7 * energy_scale, "{what}: energy error {:e} of {energy_scale:e}", worst(&inv.energy_error));
    for (k, drift) in inv.momentum_error.iter().enumerate() {
        assert!(worst(drift) < 1e-7 * (1.0 + inv.momentum0[k].abs()), "{what}: momentum {k} drifts by {:e}", worst(drift));
    }
    let rates = inv.rates.iter().flatten().fold(1.0f64, |m, x| m.max(x.abs()));
    assert!(worst(&inv.velocity_constraint) < 1e-7 * rates, "{what}: velocity constraints off by {:e}", worst(&inv.velocity_constraint));
    assert!(worst(&inv.position_constraint) < 1e-7, "{what}: position constraints off by {:e}", worst(&inv.position_constraint));
}

/// Three states near `y0`: each entry moved by up to 5 % (of itself, or of 0.05).
fn near(y0: &[f64], rng: &mut SplitMix) -> Vec<Vec<f64>> {
    (0..3).map(|_| y0.iter().map(|y| y + rng.uniform(-0.05, 0.05) * (1.0 + y.abs())).collect()).collect()
}

/// Every cell of one case: each route, each formulation.
fn check_case(case: &Case, rng: &mut SplitMix) -> usize {
    let Some(routes) = routes(case) else {
        assert_eq!(case.name, "bicycle", "only the bicycle's exact Jacobians exceed the node budget");
        return 0;
    };
    let mut cells = 0;
    for (route, model) in &routes {
        let (q0, qd0) = model.initial.clone().unwrap_or_else(|| (vec![0.0; model.coordinates.len()], vec![0.0; model.coordinates.len()]));
        for form in &model.formulations {
            let what = format!("{} {} {route}", case.name, form.kind);
            let (sys, y0) = System::start(model, form.kind, model.default_params.clone(), &q0, &qd0).unwrap_or_else(|e| panic!("{what}: {e}"));
            assert!(sys.has_exact_jacobian(), "{what}");
            check_jacobian(&format!("{what} at the initial state"), &sys, &y0);
            for (k, y) in near(&y0, rng).iter().enumerate() {
                check_jacobian(&format!("{what} at random state {k}"), &sys, y);
            }
            check_run(&what, model, &sys, &y0);
            cells += 1;
        }
    }
    cells
}

#[test]
fn every_built_in_model_in_every_formulation_and_route() {
    let mut rng = SplitMix(43);
    let cells: usize = built_in().iter().map(|case| check_case(case, &mut rng)).sum();
    assert!(cells >= 2 * 4 * 13, "{cells} cells");
}

#[test]
fn the_pendulum_on_a_cart_at_every_size_to_24() {
    let mut rng = SplitMix(44);
    let cells: usize = families().iter().filter(|c| c.name.starts_with("pendulum")).map(|case| check_case(case, &mut rng)).sum();
    assert_eq!(cells, 24 * 4 * 2);
}

#[test]
fn the_floating_chain_at_every_size_to_10() {
    let mut rng = SplitMix(45);
    let cells: usize = families().iter().filter(|c| c.name.starts_with("floating")).map(|case| check_case(case, &mut rng)).sum();
    assert_eq!(cells, 10 * 4 * 2);
}

/// The route built by rustc (`--compiled`), on the sizes where the articulated-body route
/// starts (the pendulum at 9 links, whose exact Jacobian failed) and on a floating chain: the
/// library gives the in-process Jacobians and runs.
#[test]
fn the_compiled_route_on_the_families() {
    let cache = tempfile::tempdir().unwrap();
    let mut rng = SplitMix(46);
    for case in [
        Case { name: "pendulum_on_cart(9)".into(), model: n_link_pendulum_on_cart(9).build().unwrap() },
        Case { name: "floating_chain(3)".into(), model: floating_chain(3).build().unwrap() },
    ] {
        let options = Options { jacobian: true, tapes: true, ..Options::from_model(&case.model) };
        let generated = generator::generate(&case.model, &options).unwrap();
        let description = generator::eval::model::Evaluated::model(generated.program.expect("tapes"));
        let library = native::build(&generated.code, cache.path(), &mut |_| {}).unwrap();
        let model = library.model(description).unwrap();
        let (q0, qd0) = model.initial.clone().unwrap();
        for form in &model.formulations {
            let what = format!("{} {} compiled", case.name, form.kind);
            let (sys, y0) = System::start(&model, form.kind, model.default_params.clone(), &q0, &qd0).unwrap();
            check_jacobian(&what, &sys, &y0);
            for y in near(&y0, &mut rng) {
                check_jacobian(&what, &sys, &y);
            }
            check_run(&what, &model, &sys, &y0);
        }
    }
}
