//! The workspace tests, one binary (each file of this folder a module): every crate linked
//! once instead of once per file.

mod common;

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
mod outside;
mod quaternion;
mod readme;
mod robots;
mod rolling;
mod rust_version;
mod stiff;
mod trajectories;
mod volterra;
mod watch;
