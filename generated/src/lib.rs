//! The emitted module of every model in `models/`, committed: the list of built-in models.
//! Each module describes itself as a `seam::Model` (`model()`), so that code which does not
//! know a model at compile time (the runtime, the workspace tests) calls it through slices.
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

#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod bicycle;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod bicycle_lagrange;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod bouncing_ball;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod cart_pendulum;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod cart_pendulum_baked;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod cartesian_pendulum;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod inverted_pendulum;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod pendulum_on_cart_5;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod rolling_disk;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod satellite_boom;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod satellite_boom_quaternion;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod spring_cart;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod stiff_pendulum;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod three_body;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod three_body_quaternion;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod three_body_drop;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod three_body_split;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod tumbling_body;
#[allow(clippy::all)] // machine-written: clippy's style lints do not apply
#[rustfmt::skip] // machine-written: prettyplease's layout, checked byte for byte by tests/regenerate.rs
pub mod winch;

mod registry;
pub use registry::{find, models};
pub use seam::{Failure, Formulation, FormulationKind, Model};
