//! Unit quaternions (`Quaternion(e0, e1, e2, e3)`): `models/tumbling_body.ron`, a torque-free
//! body spun near its intermediate axis, flips with the period of Euler's equations' closed
//! form (Jacobi elliptic functions), keeps its energy and world-frame angular momentum, keeps
//! its unit norm (to round-off with the projection), agrees with the same body in ZYX Euler
//! angles away from their singularity, and starts where those angles are singular.

mod common;
use runtime::integrate::{Method, Settings};
use runtime::system::{Drift, System};
use seam::{FormulationKind, Model};

const I: [f64; 3] = [1.0, 2.0, 3.0];
const OMEGA0: [f64; 3] = [0.1, 5.0, 0.1];

fn tight() -> Settings {
    Settings { method: Method::Dop853, rtol: 1e-12, atol: 1e-12, h_max: 2.0, ..Settings::default() }
}

fn evaluated(file: &str, text: Option<&str>) -> Model {
    let path = format!("{}/{file}", env!("CARGO_MANIFEST_DIR"));
    let m = match text {
        Some(t) => generator::model::from_source(&path, t).unwrap(),
        None => generator::model::load(&path).unwrap(),
    };
    generator::eval::evaluate(&m).unwrap()
}

/// `R(e)`, body to world, and the world-frame angular momentum `R I omega`.
fn rotation(e: &[f64]) -> [[f64; 3]; 3] {
    let [e0, e1, e2, e3] = [e[0], e[1], e[2], e[3]];
    [
        [e0 * e0 + e1 * e1 - e2 * e2 - e3 * e3, 2.0 * (e1 * e2 - e0 * e3), 2.0 * (e1 * e3 + e0 * e2)],
        [2.0 * (e1 * e2 + e0 * e3), e0 * e0 - e1 * e1 + e2 * e2 - e3 * e3, 2.0 * (e2 * e3 - e0 * e1)],
        [2.0 * (e1 * e3 - e0 * e2), 2.0 * (e2 * e3 + e0 * e1), e0 * e0 - e1 * e1 - e2 * e2 + e3 * e3],
    ]
}

fn world_momentum(e: &[f64], omega: &[f64]) -> [f64; 3] {
    let r = rotation(e);
    let body: Vec<f64> = (0..3).map(|k| I[k] * omega[k]).collect();
    [0, 1, 2].map(|i| (0..3).map(|k| r[i][k] * body[k]).sum())
}

/// Half the period of `omega_2(t)` (the time between flips) from Euler's equations' closed
/// form (Landau and Lifshitz, Mechanics, section 37), for `L^2 > 2 E I2`: `T = 4 K(k) / lambda`,
/// `lambda = sqrt((I3 - I2)(L^2 - 2 E I1) / (I1 I2 I3))`,
/// `k^2 = (I2 - I1)(2 E I3 - L^2) / ((I3 - I2)(L^2 - 2 E I1))`.
fn half_period() -> f64 {
    let two_e: f64 = (0..3).map(|k| I[k] * OMEGA0[k] * OMEGA0[k]).sum();
    let l2: f64 = (0..3).map(|k| (I[k] * OMEGA0[k]).powi(2)).sum();
    assert!(l2 > two_e * I[1]);
    let lambda = ((I[2] - I[1]) * (l2 - two_e * I[0]) / (I[0] * I[1] * I[2])).sqrt();
    let m = (I[1] - I[0]) * (two_e * I[2] - l2) / ((I[2] - I[1]) * (l2 - two_e * I[0]));
    2.0 * common::elliptic_k(m) / lambda
}

/// Every formulation, in-process and compiled, with the unit norm projected after every step:
/// the flips come every half period of the closed form, and the energy and the world-frame
/// angular momentum stay put.
#[test]
fn the_tennis_racket_flips_with_the_closed_form_period() {
    let expected = half_period();
    for (label, model) in [("in-process", evaluated("models/tumbling_body.ron", None)), ("compiled", generated::tumbling_body::model())] {
        for form in &model.formulations {
            let what = format!("{label} {}", form.kind);
            let r = runtime::compare::Reference::of(&model).unwrap();
            let (sys, y0) = System::start(&model, form.kind, r.params.clone(), &r.q0, &r.qd0).unwrap();
            // The unit norm held by the projection: the period is sensitive to the invariants
            // (L^2 - 2 E I2 is 0.18 of L^2 = 100).
            let sys = sys.with_drift(Drift::Projection).unwrap();
            let run = runtime::events::run(&sys, &y0, &r.times().unwrap(), &tight(), &mut |_| {}).unwrap();
            let flips: Vec<f64> = run.solution.events.iter().map(|o| o.t).collect();
            assert!(flips.len() >= 5, "{what}: {flips:?}");
            for w in flips.windows(2) {
                // Kane's form and the reduced method integrate the body rates themselves: 1e-12
                // here; Lagrange and Maggi integrate the four rates of e under the constraint,
                // and their flips come earlier by 2e-10 more each time (1e-9 by the fifth).
                let tol = if form.kind.speeds() == seam::Speeds::QuasiVelocities { 1e-11 } else { 1e-8 };
                assert!(((w[1] - w[0]) / expected - 1.0).abs() < tol, "{what}: flips {} apart, the closed form {expected}", w[1] - w[0]);
            }
            let inv = runtime::monitor::monitor(&sys, &run.solution).unwrap();
            let worst = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            assert!(worst(&inv.energy_error) < 1e-10 * inv.energy0, "{what}: energy drift {}", worst(&inv.energy_error));
            let l0 = world_momentum(&r.q0, &OMEGA0);
            let norm0 = l0.iter().map(|x| x * x).sum::<f64>().sqrt();
            for (q, qd) in inv.coordinates.iter().zip(&inv.rates) {
                // omega = 2 G(e) e'.
                let g = [[-q[1], q[0], q[3], -q[2]], [-q[2], -q[3], q[0], q[1]], [-q[3], q[2], -q[1], q[0]]];
                let omega: Vec<f64> = g.iter().map(|row| 2.0 * (0..4).map(|k| row[k] * qd[k]).sum::<f64>()).collect();
                let l = world_momentum(q, &omega);
                let drift = (0..3).map(|k| (l[k] - l0[k]).powi(2)).sum::<f64>().sqrt();
                assert!(drift < 1e-9 * norm0, "{what}: angular momentum drift {drift}");
            }
        }
    }
}

/// The unit norm drifts with the integration error alone; the projection after every step
/// (Newton on the position constraint, the quasi-velocities left alone) holds it to round-off
/// at the steps' ends (the last output is one), for Kane's form as for Lagrange's.
#[test]
fn the_projection_holds_the_unit_norm() {
    let model = generated::tumbling_body::model();
    let r = runtime::compare::Reference::of(&model).unwrap();
    let loose = Settings { rtol: 1e-8, atol: 1e-8, ..tight() };
    for kind in [FormulationKind::Kane, FormulationKind::Lagrange] {
        let norm_drift = |drift: Drift| {
            let (sys, y0) = System::start(&model, kind, r.params.clone(), &r.q0, &r.qd0).unwrap();
            let sys = sys.with_drift(drift).unwrap();
            let run = runtime::events::run(&sys, &y0, &r.times().unwrap(), &loose, &mut |_| {}).unwrap();
            let inv = runtime::monitor::monitor(&sys, &run.solution).unwrap();
            *inv.position_constraint.last().unwrap()
        };
        let (free, projected) = (norm_drift(Drift::None), norm_drift(Drift::Projection));
        assert!(free > 1e-10, "{kind}: {free}");
        assert!(projected < 1e-14, "{kind}: {projected} after projection, {free} without");
    }
}

/// Away from theta = pi/2 the same body in ZYX Euler angles turns the same way, to 1e-9; at
/// theta = pi/2 those angles cannot even start, the quaternion can.
#[test]
fn quaternions_agree_with_euler_angles_and_pass_their_singularity() {
    let euler = evaluated("tests/fixtures/tumbling_euler.ron", None);
    let quaternion = generated::tumbling_body::model();
    let times: Vec<f64> = (0..=20).map(|k| k as f64 * 0.01).collect();
    let (se, ye) = System::start(&euler, FormulationKind::Kane, euler.default_params.clone(), &[0.0; 3], &[0.1, 5.0, 0.1]).unwrap();
    let (sq, yq) =
        System::start(&quaternion, FormulationKind::Kane, quaternion.default_params.clone(), &[1.0, 0.0, 0.0, 0.0], &[0.0, 0.05, 2.5, 0.05]).unwrap();
    let a = runtime::events::run(&se, &ye, &times, &tight(), &mut |_| {}).unwrap().solution;
    let b = runtime::events::run(&sq, &yq, &times, &tight(), &mut |_| {}).unwrap().solution;
    for (k, (x, y)) in a.states.iter().zip(&b.states).enumerate() {
        let (psi, theta, phi) = (x[0], x[1], x[2]);
        let (c1, s1, c2, s2, c3, s3) = (psi.cos(), psi.sin(), theta.cos(), theta.sin(), phi.cos(), phi.sin());
        let re =
            [[c1 * c2, c1 * s2 * s3 - s1 * c3, c1 * s2 * c3 + s1 * s3], [s1 * c2, s1 * s2 * s3 + c1 * c3, s1 * s2 * c3 - c1 * s3], [-s2, c2 * s3, c2 * c3]];
        let rq = rotation(&y[..4]);
        for i in 0..3 {
            for j in 0..3 {
                assert!((re[i][j] - rq[i][j]).abs() < 1e-9, "t = {}: R[{i}][{j}] {} against {}", times[k], re[i][j], rq[i][j]);
            }
            // Both states end with the body's angular velocity.
            assert!((x[3 + i] - y[4 + i]).abs() < 1e-9, "t = {}: omega[{i}]", times[k]);
        }
    }
    // At theta = pi/2 the Euler angles' velocity transformation is singular; the quaternion of
    // that attitude, (cos pi/4, 0, sin pi/4, 0), starts and runs.
    let (se, ye) =
        System::start(&euler, FormulationKind::Kane, euler.default_params.clone(), &[0.0, std::f64::consts::FRAC_PI_2, 0.0], &[0.0, 5.0, 0.0]).unwrap();
    let err = runtime::events::run(&se, &ye, &times, &tight(), &mut |_| {}).unwrap_err();
    assert!(err.t == 0.0 && err.to_string().contains("singular"), "{err}");
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let (sq, yq) =
        System::start(&quaternion, FormulationKind::Kane, quaternion.default_params.clone(), &[h, 0.0, h, 0.0], &[-2.5 * h, 0.0, 2.5 * h, 0.0]).unwrap();
    let run = runtime::events::run(&sq, &yq, &times, &tight(), &mut |_| {}).unwrap();
    assert_eq!(run.solution.times.len(), times.len());
}
