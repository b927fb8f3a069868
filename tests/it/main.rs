//! The workspace tests, one binary (each file of this folder a module): every crate linked
//! once instead of once per file.

mod common;

// libtest runs the tests in the order of their names, on as many threads as there are cores.
// `beside` (the crates beside the workspace: a nested cargo build of a minute) is named to come
// first, so that it runs beside the others; as `outside`, after two thirds of the rest, it ran
// alone for most of its minute at the end.
mod beside;
mod bicycle;
mod chains;
mod cli;
mod commands;
mod defects;
mod controller;
mod derivation;
mod driven;
mod emitted;
mod evaluated;
mod events;
mod extremes;
mod figures;
mod jacobian;
mod matrix;
mod never;
mod ops_against_sympy;
mod quaternion;
mod readme;
mod robots;
mod rolling;
mod rust_version;
mod stiff;
mod trajectories;
mod volterra;
mod watch;
