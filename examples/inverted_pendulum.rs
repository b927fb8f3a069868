//! Balancing the pole of `models/inverted_pendulum.ron` with a linear-quadratic regulator:
//! `linearize` gives A and B of Kane's form at the upright pole (B for the model's input `F`),
//! a Riccati iteration gives the gain `K`, and the runtime integrates the nonlinear model with
//! the control law `F = -K [x, th, x', th']` evaluated at every call (`System::with_controller`).
//!
//! `cargo run --release --example inverted_pendulum`

use nalgebra::{Complex, DMatrix};
use runtime::inputs::Controller;
use runtime::integrate::Settings;
use runtime::linearize::{Operating, input_matrix, linearize};
use runtime::system::System;
use seam::FormulationKind;

/// What a balancing run gives: the gain, the closed loop's eigenvalues, and the trajectory.
pub struct Balanced {
    pub gain: Vec<f64>,
    pub closed_loop: Vec<Complex<f64>>,
    pub times: Vec<f64>,
    pub x: Vec<f64>,
    pub th: Vec<f64>,
    pub force: Vec<f64>,
}

/// The infinite-horizon LQR gain of `x' = A x + B u` for the costs `Q`, `R`: the discrete
/// Riccati recursion of the system sampled every `dt` (`exp(A dt)`, `B dt`, costs times `dt`),
/// iterated to its fixed point; for small `dt` it is the continuous gain.
pub fn lqr(a: &DMatrix<f64>, b: &DMatrix<f64>, q: &DMatrix<f64>, r: &DMatrix<f64>, dt: f64) -> DMatrix<f64> {
    let ad = (a * dt).exp();
    let bd = b * dt;
    let (qd, rd) = (q * dt, r * dt);
    let mut p = qd.clone();
    let mut k = DMatrix::zeros(b.ncols(), a.nrows());
    for _ in 0..200_000 {
        let s = &rd + bd.transpose() * &p * &bd;
        k = s.try_inverse().expect("R + B^T P B is positive definite") * bd.transpose() * &p * &ad;
        let next = &qd + ad.transpose() * &p * (&ad - &bd * &k);
        let change = (&next - &p).amax() / next.amax();
        p = next;
        if change < 1e-14 {
            break;
        }
    }
    k
}

/// Designs the regulator and runs the model for 10 s from the pole tilted by `tilt` (rad).
pub fn balance(tilt: f64) -> Balanced {
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/models/inverted_pendulum.ron");
    let m = generator::model::load(file).expect("the model loads");
    let options = generator::emit::Options { jacobian: true, parameter_jacobian: true, ..generator::emit::Options::from_model(&m) };
    let model = generator::evaluate_with(&m, &options).expect("the model derives");
    let kind = FormulationKind::Kane;
    // A and B at the upright pole, in Kane's state [x, th, x', th'].
    let upright = Operating { q: vec![0.0, 0.0], qdot: vec![0.0, 0.0], params: model.default_params.clone(), held: vec![] };
    let a = linearize(&model, kind, &upright).expect("A").a;
    let (b, _) = input_matrix(&model, kind, &upright, &model.inputs).expect("B");
    let q = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![10.0, 100.0, 1.0, 1.0]));
    let r = DMatrix::from_element(1, 1, 0.1);
    let k = lqr(&a, &b, &q, &r, 1e-3);
    let closed_loop = (&a - &b * &k).complex_eigenvalues().iter().copied().collect();
    let gain: Vec<f64> = k.iter().copied().collect();
    let law = gain.clone();
    let controller = Controller::new(move |_t, q, qd, u| u[0] = -(law[0] * q[0] + law[1] * q[1] + law[2] * qd[0] + law[3] * qd[1]));
    let (sys, y0) = System::start(&model, kind, model.default_params.clone(), &[0.0, tilt], &[0.0, 0.0]).expect("the start is admissible");
    let sys = sys.with_controller(controller);
    let times: Vec<f64> = (0..=1000).map(|i| i as f64 * 0.01).collect();
    let run = runtime::events::run(&sys, &y0, &times, &Settings::tight(10.0), &mut |_| {}).expect("the run succeeds");
    let (mut x, mut th, mut force) = (Vec::new(), Vec::new(), Vec::new());
    for (t, y) in run.solution.times.iter().zip(&run.solution.states) {
        let (q, _) = sys.velocities(*t, y).expect("a state");
        x.push(q[0]);
        th.push(q[1]);
        force.push(sys.params_at(*t, y).expect("the inputs")[model.inputs[0]]);
    }
    Balanced { gain, closed_loop, times: run.solution.times, x, th, force }
}

#[allow(dead_code)] // the tests include this file for `balance`
fn main() {
    let b = balance(0.3);
    println!("LQR gain K = {:?}", b.gain);
    println!("closed-loop eigenvalues: {:?}", b.closed_loop);
    for k in (0..b.times.len()).step_by(100) {
        println!("t = {:5.2}  x = {:+.6}  th = {:+.6}  F = {:+.4}", b.times[k], b.x[k], b.th[k], b.force[k]);
    }
}
