//! The generator's integration tests, one binary (each file of this folder a module). The
//! fuzzer (`../fuzz.rs`) stays a binary of its own: it sets the process's node budget and panic
//! hook.

#[path = "../support/rustc.rs"]
mod rustc;
mod support {
    pub(crate) use super::rustc;
}

mod articulated;
mod bad_input;
mod contexts;
mod emitted_compiles;
mod evaluated_chains;
mod fma;
mod kept_as_built;
mod symbolic_properties;
mod undecided;
