//! Linearization against a known characteristic polynomial: the spring cart (a cart on a spring
//! and a damper, carrying a pendulum) about its rest state has
//! `det(s^2 M + s C + K) = 0` with `M = [[mc + mp, mp lp], [mp lp, mp lp^2]]`,
//! `C = diag(c, 0)`, `K = diag(k, mp g lp)`.

use nalgebra::Complex;
use runtime::linearize::{Operating, Swept, crossings, growth, linearize, sweep};
use seam::FormulationKind;

fn rest(model: &seam::Model) -> Operating {
    let m = model.coordinates.len();
    Operating { q: vec![0.0; m], qdot: vec![0.0; m], params: model.default_params.to_vec(), held: vec![] }
}

fn param(model: &seam::Model, at: &Operating, name: &str) -> f64 {
    at.params[model.parameter_index(name).unwrap()]
}

/// `det(s^2 M + s C + K)` relative to the size of its terms.
fn characteristic(model: &seam::Model, at: &Operating, s: Complex<f64>) -> f64 {
    let p = |n| param(model, at, n);
    let (mc, mp, lp, k, c, g) = (p("mc"), p("mp"), p("lp"), p("k"), p("c"), p("g"));
    let s2 = s * s;
    let a11 = s2 * (mc + mp) + s * c + k;
    let a12 = s2 * (mp * lp);
    let a22 = s2 * (mp * lp * lp) + mp * g * lp;
    let det = a11 * a22 - a12 * a12;
    let scale = (s2.norm() * (mc + mp) + s.norm() * c + k) * (s2.norm() * mp * lp * lp + mp * g * lp);
    det.norm() / scale
}

#[test]
fn every_formulation_gives_the_roots_of_the_characteristic_polynomial() {
    let model = generated::find("spring_cart").unwrap();
    let at = rest(&model);
    for f in &model.formulations {
        let lin = linearize(&model, f.kind, &at).unwrap();
        assert!(lin.exact, "the committed modules carry their Jacobians");
        assert_eq!(lin.eigenvalues.len(), 4, "{}: W is left out", f.name());
        assert!(lin.rates.iter().all(|r| r.abs() < 1e-12), "{}: the rest state is an equilibrium", f.name());
        for l in &lin.eigenvalues {
            assert!(characteristic(&model, &at, *l) < 1e-10, "{}: {l} is not a root ({:e})", f.name(), characteristic(&model, &at, *l));
            assert!(l.re < 0.0, "{}: the damper makes every mode decay: {l}", f.name());
        }
        // Two oscillatory pairs: conjugates.
        assert_eq!(lin.eigenvalues.iter().filter(|l| l.im > 0.0).count(), 2);
    }
}

/// Negative damping destabilizes the cart: the largest real part crosses zero at `c = 0`.
#[test]
fn a_sweep_finds_the_stability_boundary() {
    let model = generated::find("spring_cart").unwrap();
    let at = rest(&model);
    let swept = Swept::find(&model, "c").unwrap();
    let values: Vec<f64> = (0..=10).map(|i| -0.45 + 0.1 * i as f64).collect();
    let rows = sweep(&model, FormulationKind::Kane, &at, swept, &values).unwrap();
    assert!(growth(&rows[0].eigenvalues) > 0.0 && growth(&rows[10].eigenvalues) < 0.0);
    let cross = crossings(&model, FormulationKind::Kane, &at, swept, &rows).unwrap();
    assert_eq!(cross.len(), 1);
    assert!(cross[0].abs() < 1e-9, "{}", cross[0]);
    // A rate is a sweep too; an unknown name says what there is.
    assert_eq!(Swept::find(&model, "x'").unwrap(), Swept::Rate(0));
    let e = Swept::find(&model, "speed").unwrap_err().to_string();
    assert!(e.contains("parameters: mc, mp") && e.contains("coordinates: x, th"), "{e}");
}

/// Without an exact Jacobian the same eigenvalues come from finite differences.
#[test]
fn finite_differences_agree_with_the_exact_jacobian() {
    let model = generated::find("spring_cart").unwrap();
    let mut plain = model.clone();
    for f in &mut plain.formulations {
        f.has_jacobian = false;
    }
    let at = rest(&model);
    let (a, b) = (linearize(&model, FormulationKind::Maggi, &at).unwrap(), linearize(&plain, FormulationKind::Maggi, &at).unwrap());
    assert!(a.exact && !b.exact);
    for (x, y) in a.eigenvalues.iter().zip(&b.eigenvalues) {
        assert!((x - y).norm() < 1e-6 * x.norm(), "{x} against {y}");
    }
}

/// The input matrix from the emitted parameter Jacobian equals the differenced one.
#[test]
fn the_input_matrix_is_the_same_exact_or_differenced() {
    let model = generated::find("cart_pendulum").unwrap();
    let (q0, qd0) = model.initial.clone().unwrap();
    let at = Operating { q: q0, qdot: qd0, params: model.default_params.clone(), held: vec![] };
    let tau = model.parameter_index("tau").unwrap();
    let mut plain = model.clone();
    for f in &mut plain.formulations {
        f.has_parameter_jacobian = false;
    }
    for f in &model.formulations {
        let (exact, e) = runtime::linearize::input_matrix(&model, f.kind, &at, &[tau]).unwrap();
        let (differenced, d) = runtime::linearize::input_matrix(&plain, f.kind, &at, &[tau]).unwrap();
        assert!(e && !d);
        assert!((&exact - &differenced).amax() < 1e-7 * exact.amax().max(1.0), "{}: {exact} against {differenced}", f.name());
        assert!(exact.amax() > 1e-3, "{}: the torque drives the bars", f.name());
    }
}
