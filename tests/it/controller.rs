//! A controller drives a model's input: `examples/inverted_pendulum.rs` balances the pole of
//! `models/inverted_pendulum.ron` with an LQR gain designed on `linearize`'s A and B, which are
//! first checked against the cart-pole's closed form; without the controller the pole falls.

#[path = "../../examples/inverted_pendulum.rs"]
mod example;

use runtime::linearize::{Operating, input_matrix, linearize};
use seam::FormulationKind;

const MC: f64 = 1.0;
const MP: f64 = 0.2;
const L: f64 = 0.6;
const G: f64 = 9.81;

fn model() -> seam::Model {
    let m = generator::model::load(concat!(env!("CARGO_MANIFEST_DIR"), "/models/inverted_pendulum.ron")).unwrap();
    generator::evaluate_with(&m, &generator::emit::Options { jacobian: true, parameter_jacobian: true, ..generator::emit::Options::from_model(&m) }).unwrap()
}

/// At the upright pole, `x'' = (F + mp g th) / mc` and `th'' = (F + (mc + mp) g th) / (mc l)`: `B` and the
/// gravity column of `A` in closed form.
#[test]
fn the_input_matrix_is_the_cart_pole_s_closed_form() {
    let model = model();
    assert_eq!(model.inputs.iter().map(|&i| model.parameter_names[i].as_str()).collect::<Vec<_>>(), ["F"]);
    let at = Operating { q: vec![0.0, 0.0], qdot: vec![0.0, 0.0], params: model.default_params.clone(), held: vec![] };
    let (b, exact) = input_matrix(&model, FormulationKind::Kane, &at, &model.inputs).unwrap();
    assert!(exact);
    let expected = [0.0, 0.0, 1.0 / MC, 1.0 / (MC * L)];
    for (k, e) in expected.iter().enumerate() {
        assert!((b[(k, 0)] - e).abs() < 1e-12, "B[{k}] = {} against {e}", b[(k, 0)]);
    }
    let a = linearize(&model, FormulationKind::Kane, &at).unwrap().a;
    let rate = (MC + MP) * G / (MC * L);
    assert!((a[(3, 1)] - rate).abs() < 1e-12 && (a[(2, 1)] - MP * G / MC).abs() < 1e-12, "{a}");
}

/// The regulator stabilizes the linear model (every closed-loop eigenvalue in the left half
/// plane) and balances the nonlinear one from a tilt of 0.3 rad: the cart comes back and the
/// pole stands still at the top.
#[test]
fn the_regulator_balances_the_pole() {
    let b = example::balance(0.3);
    assert!(b.closed_loop.iter().all(|l| l.re < -0.5), "{:?}", b.closed_loop);
    let last = b.times.len() - 1;
    assert_eq!(b.times[last], 10.0);
    assert!(b.th[last].abs() < 1e-4 && b.x[last].abs() < 1e-3, "th = {}, x = {}", b.th[last], b.x[last]);
    assert!(b.th.iter().all(|th| th.abs() < 0.35), "the pole never tips further than its start");
    // The force is the law's: -K x at the start, pushing the cart under the pole.
    let f0 = -(b.gain[1] * 0.3);
    assert!((b.force[0] - f0).abs() < 1e-12 && f0.abs() > 1.0, "{} against {f0}", b.force[0]);
}

/// Without a controller the input keeps its nominal 0 and the pole falls past the horizontal.
#[test]
fn without_control_the_pole_falls() {
    let model = model();
    let (sys, y0) = runtime::system::System::start(&model, FormulationKind::Kane, model.default_params.clone(), &[0.0, 0.3], &[0.0, 0.0]).unwrap();
    let times: Vec<f64> = (0..=200).map(|i| i as f64 * 0.01).collect();
    let run = runtime::events::run(&sys, &y0, &times, &runtime::integrate::Settings::tight(2.0), &mut |_| {}).unwrap();
    let fell = run.solution.states.iter().any(|y| y[1].abs() > std::f64::consts::FRAC_PI_2);
    assert!(fell);
}

/// Inputs are checked as parameters are: a name taken twice or a value that is not finite is
/// refused with its place in the file; and a module with inputs keeps its parameters at run time.
#[test]
fn bad_inputs_get_located_errors() {
    let good = include_str!("../../models/inverted_pendulum.ron");
    for (to, message, place) in [
        (r#"inputs: { "g": 0.0 },"#, "the name `g` is already taken", "inputs.g"),
        (r#"inputs: { "F": inf },"#, "input `F` has no finite nominal value", "inputs.F"),
    ] {
        let text = good.replacen(r#"inputs: { "F": 0.0 },"#, to, 1);
        let e = generator::model::from_source("models/pole.ron", &text).unwrap_err().to_string();
        let line = text.lines().position(|l| l.contains(to)).unwrap() + 1;
        assert!(e.contains(message) && e.contains(place) && e.contains(&format!("models/pole.ron:{line}:")), "{to}: {e}");
    }
    let m = generator::model::from_source("models/pole.ron", good).unwrap();
    let baked = generator::emit::Options { parameters: generator::emit::Parameters::Baked, ..generator::emit::Options::from_model(&m) };
    let e = generator::generate(&m, &baked).unwrap_err().to_string();
    assert!(e.contains("cannot bake its parameters in"), "{e}");
}
