//! The Whipple bicycle benchmark (Meijaard, Papadopoulos, Ruina, Schwab, Proc. R. Soc. A 463
//! (2007) 1955-1982) from the generated nonlinear equations of `models/bicycle.ron`: the
//! linearized lean and steer eigenvalues at 0, 5 and 10 m/s against the published ones, the
//! weave and capsize speeds, and nonlinear runs where a small lean perturbation decays (5 m/s)
//! and grows (2 m/s). From central differences of the emitted Kane and Lagrange right-hand
//! sides the eigenvalues match the published values to about 10 significant digits; from the
//! exact Jacobian of `bicycle_lagrange`, to the 13 to 15 digits published.

use runtime::integrate::{Method, Settings, integrate};
use runtime::linearize::{Operating, Swept, crossings, linearize, sweep};
use runtime::system::System;
use seam::FormulationKind;

fn bicycle() -> generated::Model {
    generated::find("bicycle").unwrap()
}

fn index(model: &generated::Model, name: &str) -> usize {
    model.coordinates.iter().position(|c| *c == name).unwrap()
}

/// Upright and straight ahead at speed `v`, with lean rate `lean_rate`: the other rates from
/// the contact constraints.
fn upright(model: &generated::Model, v: f64, lean_rate: f64) -> Operating {
    let m = model.coordinates.len();
    let mut qdot = vec![0.0; m];
    qdot[index(model, "x")] = v;
    qdot[index(model, "phi")] = lean_rate;
    Operating { q: vec![0.0; m], qdot, params: model.default_params.to_vec(), held: vec![index(model, "x"), index(model, "phi"), index(model, "delta")] }
}

/// Published eigenvalues (Table 2 of the benchmark), `(re, im)`, sorted as `linearize` sorts.
fn published(v: f64) -> Vec<(f64, f64)> {
    match v {
        0.0 => vec![(5.53094371765393, 0.0), (3.13164324790656, 0.0), (-3.13164324790656, 0.0), (-5.53094371765393, 0.0)],
        5.0 => vec![(-0.32286642900409, 0.0), (-0.77534188219585, 4.46486771378823), (-0.77534188219585, -4.46486771378823), (-14.07838969279822, 0.0)],
        10.0 => vec![(0.16105338653172, 0.0), (-3.72016840437287, 10.90681139476287), (-3.72016840437287, -10.90681139476287), (-24.62459635017404, 0.0)],
        _ => unreachable!(),
    }
}

#[test]
fn eigenvalues_match_the_benchmark_to_nine_digits() {
    let model = bicycle();
    for v in [0.0, 5.0, 10.0] {
        for form in [FormulationKind::Kane, FormulationKind::Lagrange] {
            let lin = linearize(&model, form, &upright(&model, v, 0.0)).unwrap();
            assert!(lin.rates.iter().enumerate().all(|(i, r)| lin.cyclic.contains(&i) || r.abs() < 1e-9), "{form} at {v}: a steady motion");
            // Zero eigenvalues beside the four: the speed of the steady motion, the front
            // contact's height (Lagrange keeps more of them).
            let nonzero: Vec<_> = lin.eigenvalues.iter().filter(|l| l.norm() > 1e-6).collect();
            let want = published(v);
            assert_eq!(nonzero.len(), 4, "{form} at {v} m/s: {:?}", lin.eigenvalues);
            for (got, want) in nonzero.iter().zip(&want) {
                let err = (got.re - want.0).hypot(got.im - want.1);
                assert!(err < 1e-9 * want.0.hypot(want.1).max(1.0), "{form} at {v} m/s: {got} against {want:?} ({err:e})");
            }
        }
    }
}

/// With the exact Jacobian (`bicycle_lagrange`: Lagrange's form emitted with `--jacobian`)
/// the eigenvalues agree with the published ones to about 13 digits, as independent
/// implementations do.
#[test]
fn with_the_exact_jacobian_the_eigenvalues_match_to_twelve_digits() {
    let model = generated::find("bicycle_lagrange").unwrap();
    for v in [0.0, 5.0, 10.0] {
        let lin = linearize(&model, FormulationKind::Lagrange, &upright(&model, v, 0.0)).unwrap();
        assert!(lin.exact);
        let nonzero: Vec<_> = lin.eigenvalues.iter().filter(|l| l.norm() > 1e-6).collect();
        assert_eq!(nonzero.len(), 4, "at {v} m/s: {:?}", lin.eigenvalues);
        for (got, want) in nonzero.iter().zip(&published(v)) {
            let err = (got.re - want.0).hypot(got.im - want.1);
            eprintln!("{v} m/s: {got} against {want:?}: {err:e}");
            assert!(err < 1e-12 * want.0.hypot(want.1).max(1.0), "at {v} m/s: {got} against {want:?} ({err:e})");
        }
    }
    let at = upright(&model, 0.0, 0.0);
    let swept = Swept::find(&model, "x'").unwrap();
    let values: Vec<f64> = (0..=20).map(|i| 0.5 * i as f64).collect();
    let rows = sweep(&model, FormulationKind::Lagrange, &at, swept, &values).unwrap();
    let cross = crossings(&model, FormulationKind::Lagrange, &at, swept, &rows).unwrap();
    eprintln!("weave {} capsize {}", cross[0], cross[1]);
    assert!((cross[0] / 4.29238253634111 - 1.0).abs() < 1e-12, "weave speed {}", cross[0]);
    assert!((cross[1] / 6.02426201538837 - 1.0).abs() < 1e-12, "capsize speed {}", cross[1]);
}

#[test]
fn the_weave_and_capsize_speeds_match_the_benchmark() {
    let model = bicycle();
    let at = upright(&model, 0.0, 0.0);
    let swept = Swept::find(&model, "x'").unwrap();
    let values: Vec<f64> = (0..=20).map(|i| 0.5 * i as f64).collect();
    let rows = sweep(&model, FormulationKind::Kane, &at, swept, &values).unwrap();
    let cross = crossings(&model, FormulationKind::Kane, &at, swept, &rows).unwrap();
    // Below the weave speed the weave oscillation grows; beyond the capsize speed the capsize
    // mode does; in between the bicycle is self-stable. (At 0.68 m/s two real roots merge into
    // the weave pair: no sign change there.)
    assert_eq!(cross.len(), 2, "{cross:?}");
    let (weave, capsize) = (cross[0], cross[1]);
    assert!((weave / 4.29238253634111 - 1.0).abs() < 1e-8, "weave speed {weave}");
    assert!((capsize / 6.02426201538837 - 1.0).abs() < 1e-8, "capsize speed {capsize}");
}

/// The nonlinear equations, integrated for `seconds` from upright with a lean rate of
/// 0.05 rad/s: the lean angle every 0.01 s.
fn lean_history(v: f64, seconds: f64) -> Vec<f64> {
    let model = bicycle();
    let at = upright(&model, v, 0.05);
    let qdot = at.consistent_rates(&model).unwrap();
    let (sys, y0) = System::start(&model, FormulationKind::Kane, at.params.clone(), &at.q, &qdot).unwrap();
    let times: Vec<f64> = (0..=(seconds * 100.0).round() as usize).map(|i| i as f64 * 0.01).collect();
    let s = Settings { method: Method::Dopri5, rtol: 1e-9, atol: 1e-11, ..Settings::default() };
    let sol = integrate(&mut |t, y, dy| sys.rhs(t, y, dy), &y0, &times, &s).unwrap();
    let phi = index(&model, "phi");
    sol.states.iter().map(|y| y[phi]).collect()
}

#[test]
fn a_lean_perturbation_decays_at_5_and_grows_at_2_metres_per_second() {
    let peak = |lean: &[f64]| lean.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    // 5 m/s (self-stable): the weave dies out; after 9 s the lean is a small fraction of its
    // first swing.
    let stable = lean_history(5.0, 10.0);
    let (first, late) = (peak(&stable[..200]), peak(&stable[900..]));
    assert!(late < 0.05 * first, "5 m/s: lean {late} after 9 s against {first} in the first 2 s");
    // 2 m/s (below the weave speed): the bicycle falls; within 1.5 s the lean is many times
    // its first swing.
    let unstable = lean_history(2.0, 1.5);
    let (first, late) = (peak(&unstable[..30]), peak(&unstable[100..]));
    assert!(late > 5.0 * first, "2 m/s: lean {late} after 1 s against {first} in the first 0.3 s");
}
