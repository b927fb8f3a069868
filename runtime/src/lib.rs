//! The runtime: integrators, the emitted models as systems to integrate, invariant monitors,
//! and the comparison of formulations (the paper's section 3).
//!
//! Layout: [`integrate`] (RK4, DOPRI5, DOP853) → [`system`] (a formulation of an emitted model
//! as `y' = f(t, y)`) → [`monitor`] (energy with the work integral, momenta, constraints) →
//! [`compare`] (tables, JSON, plots).

#![forbid(unsafe_code)]

pub mod integrate;
pub mod system;
pub mod monitor;
pub mod compare;
pub mod plot;
pub mod sweep;
