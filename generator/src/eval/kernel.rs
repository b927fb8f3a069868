//! What runs a tape: the interpreter by default, or code a backend compiled from it (the
//! `jit` crate's cranelift backend, which the `multibody` tool uses). Every kernel performs the
//! tape's operations in its order, so every backend gives the compiled module's numbers.
//!
//! ```
//! use generator::emit::tape::{Slots, Tape};
//! use generator::eval::kernel::{Backend, Interpreter, Kernel};
//! let stmts: Vec<syn::Stmt> = vec![syn::parse_quote!(let x = state[0];)];
//! let tape = Tape::compile(&stmts, &[syn::parse_quote!(x * x + 1.0)], &Slots::new(&[("state", 1)])).unwrap();
//! let kernel = Interpreter.kernel(tape);
//! let mut out = [0.0];
//! kernel.run(&[3.0], &mut out);
//! assert_eq!((kernel.inputs(), kernel.outputs(), out[0]), (1, 1, 10.0));
//! ```

use crate::emit::tape::Tape;

/// One emitted function's arithmetic, ready to run.
pub trait Kernel: Send + Sync {
    /// Number of input registers it reads (`inputs` must hold at least these).
    fn inputs(&self) -> usize;
    /// Number of outputs it writes.
    fn outputs(&self) -> usize;
    /// Writes the outputs for `inputs`.
    fn run(&self, inputs: &[f64], out: &mut [f64]);
}

impl Kernel for Tape {
    fn inputs(&self) -> usize {
        self.parts().0
    }
    fn outputs(&self) -> usize {
        Tape::outputs(self)
    }
    fn run(&self, inputs: &[f64], out: &mut [f64]) {
        self.eval(inputs, out);
    }
}

/// How the tapes of an evaluated model become kernels.
pub trait Backend {
    /// The kernel of `tape` (a backend that cannot compile it returns the tape itself).
    fn kernel(&self, tape: Tape) -> Box<dyn Kernel>;
}

/// Runs the tapes as they are.
pub struct Interpreter;

impl Backend for Interpreter {
    fn kernel(&self, tape: Tape) -> Box<dyn Kernel> {
        Box::new(tape)
    }
}
