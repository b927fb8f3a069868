//! The emitted module of every model in `models/`, committed, and a registry that lets code
//! that does not know a model at compile time (the runtime, the workspace tests) call them
//! through slices.
//!
//! Each module is the generator's output, byte for byte (`tests/regenerate.rs` checks it;
//! `REGENERATE=1 cargo test -p generated --test regenerate` rewrites them). Use a module
//! directly for speed:
//!
//! ```
//! use generated::cart_pendulum as model;
//! let params = model::Params::default();
//! let (state, g_i) = model::reduced_volterra::initial_state(0.0, &model::INITIAL_Q, &model::INITIAL_QDOT, &params).unwrap();
//! let mut dstate = [0.0; model::reduced_volterra::STATES];
//! model::reduced_volterra::rhs(0.0, &state, &params, &g_i, &mut dstate).unwrap();
//! assert!((dstate[0] - model::INITIAL_QDOT[0]).abs() < 1e-12);
//! ```

#![forbid(unsafe_code)]
#![deny(warnings)]

pub mod cart_pendulum;
pub mod cart_pendulum_baked;
pub mod cartesian_pendulum;
pub mod rolling_disk;
pub mod satellite_boom;
pub mod spring_cart;
pub mod three_body;
pub mod three_body_drop;
pub mod three_body_split;

mod registry;
pub use registry::{Failure, Formulation, Model, find, models};
