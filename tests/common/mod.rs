//! Helpers shared by the workspace tests.

#![allow(dead_code)] // each test file uses its own subset

use generator::formulation::volterra::Volterra;
use generator::model::{self, Model};
use generator::symbolic::eval::Env;
use generator::symbolic::{Expr, Symbol};

/// A model of `models/`.
pub fn load(name: &str) -> Model {
    model::load(format!("{}/models/{name}.ron", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

/// `q''` implied by a Volterra form with `q' = W u + X` and the rates `u'`, at the state in `env`
/// (`q`, `u`, `G`, `t` set): `d/dt(W u + X)` along the motion plus `W u'`.
pub fn accelerations_from(v: &Volterra, env: &Env, model: &Model, udot: &[f64]) -> Vec<f64> {
    let chain: Vec<(Symbol, Expr)> = model.coordinates.iter().copied().zip(v.qdot.iter().copied()).collect();
    v.qdot
        .iter()
        .map(|e| {
            let explicit = e.time_derivative(model.t, &chain).eval(env).unwrap();
            explicit + v.u.iter().zip(udot).map(|(u, ud)| e.diff(*u).eval(env).unwrap() * ud).sum::<f64>()
        })
        .collect()
}
