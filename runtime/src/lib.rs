//! The runtime, a library: integrators, a model's formulations as systems to integrate,
//! invariant monitors, and the comparison of formulations (the paper's section 3), the
//! work-precision sweep and linearization, as functions. No command line, plotting or build
//! machinery: the `multibody` tool (the repository's root crate) holds those.
//!
//! Every model reaches it as a `seam::Model`, compiled (an emitted module's `model()`) or
//! evaluated in-process (`generator::eval`): the runtime depends on the seam crate only.
//!
//! Layout: [`integrate`] (RK4, DOPRI5, DOP853, Rosenbrock 2(3)) → [`system`] (a formulation as
//! `y' = f(t, y)`; [`events`]: a run with the model's events) → [`monitor`] (energy with the
//! work integral, momenta, constraints; [`trajectory`]: a monitored run as a table) →
//! [`compare`], [`sweep`], [`linearize`], [`ensemble`] (many runs on every core).

#![forbid(unsafe_code)]

pub mod integrate;
pub mod inputs;
pub mod system;
pub mod events;
pub mod monitor;
pub mod compare;
pub mod sweep;
pub mod linearize;
pub mod ensemble;
pub mod trajectory;

/// The seam crate, for generated modules emitted with `seam_path = "runtime::seam"`.
pub use seam;
