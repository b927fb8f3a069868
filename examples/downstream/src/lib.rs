//! A crate that uses a generated module: `build.rs` writes it to `OUT_DIR`, and it is
//! included here. [`step`] advances the reduced Volterra equations of scene 1 by one
//! classical Runge-Kutta step.
//!
//! ```
//! use downstream::cart_pendulum as model;
//! let params = model::Params::default();
//! let (mut state, g_i) = model::reduced_volterra::initial_state(0.0, &model::INITIAL_Q, &model::INITIAL_QDOT, &params).unwrap();
//! downstream::step(0.0, 1e-3, &mut state, &params, &g_i).unwrap();
//! ```

#![forbid(unsafe_code)]
#![deny(warnings)]

/// Scene 1, generated at build time.
#[allow(clippy::all)]
pub mod cart_pendulum {
    include!(concat!(env!("OUT_DIR"), "/cart_pendulum.rs"));
}

use cart_pendulum::reduced_volterra::{STATES, rhs};
use cart_pendulum::{EvalError, NUM_IGNORABLE, Params};

/// One RK4 step of size `h` from time `t`, in place.
pub fn step(t: f64, h: f64, state: &mut [f64; STATES], params: &Params, g_i: &[f64; NUM_IGNORABLE]) -> Result<(), EvalError> {
    let mut k = [[0.0; STATES]; 4];
    let mut y = *state;
    rhs(t, &y, params, g_i, &mut k[0])?;
    for (i, c) in [0.5, 0.5, 1.0].into_iter().enumerate() {
        for j in 0..STATES {
            y[j] = state[j] + c * h * k[i][j];
        }
        let mut next = [0.0; STATES];
        rhs(t + c * h, &y, params, g_i, &mut next)?;
        k[i + 1] = next;
    }
    for j in 0..STATES {
        state[j] += h / 6.0 * (k[0][j] + 2.0 * k[1][j] + 2.0 * k[2][j] + k[3][j]);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use cart_pendulum as model;

    #[test]
    fn a_short_simulation_keeps_energy_momentum_and_the_constraint() {
        let params = Params::default();
        let (mut state, g_i) =
            model::reduced_volterra::initial_state(0.0, &model::INITIAL_Q, &model::INITIAL_QDOT, &params).unwrap();
        let energy = |s: &[f64; STATES]| {
            let (q, qd) = model::reduced_volterra::velocities(0.0, s, &params, &g_i).unwrap();
            (model::energy(0.0, &q, &qd, &params), model::momenta(0.0, &q, &qd, &params)[0], model::constraint_residuals(0.0, &q, &qd, &params)[0])
        };
        let (e0, _, _) = energy(&state);
        let h = 1e-3;
        for n in 0..1000 {
            step(n as f64 * h, h, &mut state, &params, &g_i).unwrap();
        }
        let (e1, g1, c1) = energy(&state);
        assert!((e1 - e0).abs() < 1e-9 * e0.abs(), "energy {e0} -> {e1}");
        assert!((g1 - g_i[0]).abs() < 1e-13, "momentum {} -> {g1}", g_i[0]);
        assert!(c1.abs() < 1e-13, "constraint residual {c1}");
        assert!((state[0] - model::INITIAL_Q[0]).abs() > 1e-3, "the pendulum moved");
    }
}
