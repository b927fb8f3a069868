//! The committed modules: each with its model file and how its options differ from the file's
//! own. One list, for the regeneration test and for the in-process evaluation test
//! (`tests/it/evaluated.rs` at the root includes this file).

use generator::emit::{Formulation, Options, Parameters};

/// (module, model, how its options differ from the model's own).
pub fn variants() -> Vec<(&'static str, &'static str, fn(&mut Options))> {
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
        // Events: an impact's reset map, a recorded crossing, a stop.
        ("bouncing_ball", "bouncing_ball", |o| o.parameter_jacobian = true),
        // An input (`F`), read from the parameters at every call.
        ("inverted_pendulum", "inverted_pendulum", |o| o.parameter_jacobian = true),
        // Unit quaternions: the attitude without a singular configuration.
        ("tumbling_body", "tumbling_body", |_| {}),
        // Scenes 2 and 3 with their attitudes in unit quaternions.
        ("three_body_quaternion", "three_body_quaternion", |_| {}),
        ("satellite_boom_quaternion", "satellite_boom_quaternion", |_| {}),
        // A moving constraint (a rope reeled by a winch): its power joins the work integral.
        ("winch", "winch", |o| o.parameter_jacobian = true),
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
