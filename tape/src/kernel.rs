//! What runs a tape: the interpreter by default, or code a backend compiled from it (the
//! `jit` crate's cranelift backend, which the `multibody` tool uses). Every kernel performs the
//! tape's operations in its order, so every backend gives the compiled module's numbers.
//!
//! ```
//! use tape::{Backend, Instr, Interpreter, Kernel, Tape};
//! // x * x + 1
//! let tape = Tape::write(|w| {
//!     let square = w.instr(Instr::Mul(w.input(0), w.input(0)));
//!     let one = w.constant(1.0);
//!     vec![w.instr(Instr::Add(square, one))]
//! });
//! let kernel = Interpreter.kernel(tape);
//! let mut out = [0.0];
//! kernel.run(&[3.0], &mut out);
//! assert_eq!((kernel.inputs(), kernel.outputs(), out[0]), (1, 1, 10.0));
//! ```

use crate::Tape;

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
        Tape::inputs(self)
    }
    fn outputs(&self) -> usize {
        Tape::outputs(self)
    }
    fn run(&self, inputs: &[f64], out: &mut [f64]) {
        self.eval(inputs, out);
    }
}

/// How the tapes of an evaluated model become kernels (shared by the threads that compile a
/// model's tapes side by side, [`kernels`]).
pub trait Backend: Sync {
    /// The kernel of `tape` (a backend that cannot compile it returns the tape itself).
    fn kernel(&self, tape: Tape) -> Box<dyn Kernel>;
}

/// The kernels of `tapes`, in their order, made by `backend` on up to `threads` threads, the
/// longest tapes first (a JIT's time grows with a tape's length). Each kernel depends only on
/// its tape, so the result is the same for any number of threads. Measured with `perf stat -r
/// 15 multibody compare three_body` on this project's 2-core machine, against one thread: 72.6
/// and 71.9 ms of wall time, 67.1 and 66.1 ms side by side (a few percent more CPU).
///
/// ```
/// use tape::{Instr, Interpreter, Kernel, Tape, kernels};
/// let tape = |k: f64| {
///     Tape::write(|w| {
///         let k = w.constant(k);
///         vec![w.instr(Instr::Mul(w.input(0), k))]
///     })
/// };
/// let made = kernels(vec![tape(2.0), tape(3.0), tape(5.0)], &Interpreter, 2);
/// let mut out = [0.0];
/// made[2].run(&[1.5], &mut out);
/// assert_eq!(out[0], 7.5);
/// ```
pub fn kernels(tapes: Vec<Tape>, backend: &dyn Backend, threads: usize) -> Vec<Box<dyn Kernel>> {
    let mut order: Vec<usize> = (0..tapes.len()).collect();
    order.sort_by_key(|&k| std::cmp::Reverse(tapes[k].parts().2.len()));
    let slots: Vec<std::sync::Mutex<Option<Tape>>> = tapes.into_iter().map(|t| std::sync::Mutex::new(Some(t))).collect();
    let next = std::sync::atomic::AtomicUsize::new(0);
    let work = || {
        let mut made = Vec::new();
        loop {
            let at = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let Some(&k) = order.get(at) else { break made };
            let tape = slots[k].lock().unwrap_or_else(std::sync::PoisonError::into_inner).take().expect("each tape is taken once");
            made.push((k, backend.kernel(tape)));
        }
    };
    let threads = threads.clamp(1, slots.len().max(1));
    let mut made: Vec<(usize, Box<dyn Kernel>)> = std::thread::scope(|s| {
        (1..threads).map(|_| s.spawn(work)).collect::<Vec<_>>().into_iter().fold(work(), |mut all, h| {
            all.extend(h.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)));
            all
        })
    });
    made.sort_by_key(|(k, _)| *k);
    made.into_iter().map(|(_, kernel)| kernel).collect()
}

/// Runs the tapes as they are.
pub struct Interpreter;

impl Backend for Interpreter {
    fn kernel(&self, tape: Tape) -> Box<dyn Kernel> {
        Box::new(tape)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Instr;

    /// A tape of `links` dependent operations ending in `k * x`: tapes of different lengths, so
    /// that the longest-first order differs from the given one.
    fn tape(k: usize, links: usize) -> Tape {
        Tape::write(|w| {
            let mut v = w.input(0);
            let (half, quarter) = (w.constant(0.5), w.constant(0.25));
            for _ in 0..links {
                let scaled = w.instr(Instr::Mul(v, half));
                v = w.instr(Instr::Add(scaled, quarter));
            }
            let k = w.constant(k as f64);
            vec![w.instr(Instr::Mul(v, k))]
        })
    }

    /// The kernels come back in the tapes' order and give the same numbers for any number of
    /// threads (each tape taken exactly once).
    #[test]
    fn kernels_keep_the_tapes_order_on_any_number_of_threads() {
        let lengths = [3, 40, 1, 17, 40, 8, 25];
        let run = |threads: usize| -> Vec<u64> {
            let made = kernels(lengths.iter().enumerate().map(|(k, &n)| tape(k + 1, n)).collect(), &Interpreter, threads);
            assert_eq!(made.len(), lengths.len());
            made.iter()
                .map(|kernel| {
                    let mut out = [0.0];
                    kernel.run(&[0.75], &mut out);
                    out[0].to_bits()
                })
                .collect()
        };
        let alone = run(1);
        for (k, &n) in lengths.iter().enumerate() {
            let mut x = 0.75f64;
            for _ in 0..n {
                x = x * 0.5 + 0.25;
            }
            assert_eq!(alone[k], (x * (k + 1) as f64).to_bits(), "tape {k}");
        }
        for threads in [2, 3, 16] {
            assert_eq!(run(threads), alone, "{threads} threads");
        }
        assert!(kernels(Vec::new(), &Interpreter, 4).is_empty());
    }
}
