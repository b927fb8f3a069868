//! What runs a tape: the `tape` crate's kernels (the interpreter by default, or code a backend
//! compiled from the tape: the `jit` crate's cranelift backend, which the `multibody` tool uses).
//! Every kernel performs the tape's operations in its order, so every backend gives the
//! compiled module's numbers.

pub use ::tape::{Backend, Interpreter, Kernel, kernels};
