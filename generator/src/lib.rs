//! Derives the equations of motion of multibody systems symbolically and emits Rust.
//!
//! The pipeline: [`model`] (parse and validate a RON model) → [`kinematics`] (frames, body
//! velocities) → [`formulation`] (T, M, N, Q, constraints, ignorable coordinates, and the
//! formulations) → [`emit`] (flat Rust) or [`eval`] (in-process tapes), the run owned by one place
//! ([`generate`], [`evaluate`]); [`Builder`] for build scripts. [`symbolic`] is the engine
//! underneath.

pub mod symbolic;
pub mod kinematics;
pub mod model;
pub mod formulation;
mod inspect;
/// The `generate` and `inspect` command lines (clap), shared by the `generator` binary and the
/// `multibody` tool: only with the `cli` feature, so that a build script compiles no clap.
#[cfg(feature = "cli")]
pub mod command;
pub mod overwrite;
pub mod emit;
pub mod eval;
mod pipeline;
mod build_script;
pub mod pose;

pub use build_script::{BuildError, Builder, Built};
pub use pipeline::{evaluate, evaluate_reporting, evaluate_with, evaluate_with_backend, generate, inspect};
