//! Random states for the formulations' tests: parameters near their own values, `t`, the
//! coordinates and the given speeds, drawn from one deterministic sequence.

use crate::model::Model;
use crate::symbolic::Symbol;
use crate::symbolic::eval::Env;

/// A deterministic generator of test values (SplitMix64).
pub(super) fn next(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}

/// Random values of the parameters (near their own), `t`, the coordinates (Euler
/// parameters on the unit sphere, where their kinematics hold) and `speeds`.
pub(super) fn random_state(model: &Model, speeds: &[Symbol], seed: &mut u64) -> Env {
    let mut env = Env::default();
    for (s, v) in &model.parameters {
        env.set(*s, *v * (1.0 + 0.2 * next(seed)));
    }
    env.set(crate::symbolic::Symbol::new("pi"), std::f64::consts::PI);
    for (f, body) in &model.time_functions {
        env.define(*f, model.t, *body);
    }
    env.set(model.t, next(seed));
    for q in model.coordinates.iter().chain(speeds) {
        env.set(*q, next(seed));
    }
    let unit: Vec<Symbol> = ["e0", "e1", "e2", "e3"].iter().filter_map(|n| model.coordinates.iter().copied().find(|q| q.name() == *n)).collect();
    let norm = unit.iter().map(|q| env.get(*q).unwrap().powi(2)).sum::<f64>().sqrt();
    for q in &unit {
        env.set(*q, env.get(*q).unwrap() / norm);
    }
    env
}
