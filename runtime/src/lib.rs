//! The runtime: integrators, the emitted models as systems to integrate, invariant monitors,
//! and the comparison of formulations (the paper's section 3).
//!
//! Every model reaches it as a `seam::Model` (the emitted module's `model()`), never as a
//! particular module: the runtime depends on the seam crate only.
//!
//! Layout: [`integrate`] (RK4, DOPRI5, DOP853) → [`system`] (a formulation of an emitted model
//! as `y' = f(t, y)`) → [`monitor`] (energy with the work integral, momenta, constraints) →
//! [`compare`] and [`sweep`] (tables, JSON, [`plot`]s) → [`cli`] (the commands) and [`driver`]
//! (a model file to a compiled program that runs them).

#![forbid(unsafe_code)]

pub mod integrate;
pub mod system;
pub mod monitor;
pub mod compare;
pub mod sweep;
pub mod linearize;
pub mod plot;
pub mod cli;
pub mod driver;

/// The seam crate, for generated modules emitted with `seam_path = "runtime::seam"`.
pub use seam;
