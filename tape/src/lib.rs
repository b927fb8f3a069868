//! Register tapes: the straight-line arithmetic of one emitted function body, as a list of
//! IEEE operations in the emitted code's order (no reassociation, no fused multiply-add: Rust
//! does neither), so that running it gives the compiled module's numbers. The generator
//! compiles its bodies' syntax trees into tapes (`generator::emit::tape::compile`); a
//! [`Backend`] makes each a [`Kernel`]: the [`Interpreter`] runs the tape as it is, the `jit`
//! crate compiles it to machine code.
//!
//! The registers are the inputs, then the constants, then one per instruction; the outputs
//! name registers.
//!
//! ```
//! use tape::{Instr, Tape, Unary};
//! // out = 2 sin(x) - x
//! let tape = Tape::write(|w| {
//!     let x = w.input(0);
//!     let s = w.instr(Instr::Call(Unary::Sin, x));
//!     let two = w.constant(2.0);
//!     let twice = w.instr(Instr::Mul(two, s));
//!     vec![w.instr(Instr::Sub(twice, x))]
//! });
//! let mut out = [0.0];
//! tape.eval(&[0.5], &mut out);
//! assert_eq!(out[0], 2.0 * f64::sin(0.5) - 0.5);
//! ```

mod kernel;

pub use kernel::{Backend, Interpreter, Kernel, kernels};

use std::cell::RefCell;
use std::collections::HashMap;

/// One instruction: the operation and its operands (registers), writing the next register.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Instr {
    Add(u32, u32),
    Sub(u32, u32),
    Mul(u32, u32),
    Div(u32, u32),
    Neg(u32),
    Call(Unary, u32),
    Powi(u32, i32),
    Powf(u32, u32),
}

impl Instr {
    /// The same instruction reading `f(r)` for each operand register `r`.
    fn map_operands(self, f: impl Fn(u32) -> u32) -> Instr {
        match self {
            Instr::Add(a, b) => Instr::Add(f(a), f(b)),
            Instr::Sub(a, b) => Instr::Sub(f(a), f(b)),
            Instr::Mul(a, b) => Instr::Mul(f(a), f(b)),
            Instr::Div(a, b) => Instr::Div(f(a), f(b)),
            Instr::Neg(a) => Instr::Neg(f(a)),
            Instr::Call(u, a) => Instr::Call(u, f(a)),
            Instr::Powi(a, n) => Instr::Powi(f(a), n),
            Instr::Powf(a, b) => Instr::Powf(f(a), f(b)),
        }
    }
}

/// The `f64` methods emitted code calls with one argument.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Unary {
    Sin,
    Cos,
    Tan,
    Exp,
    Ln,
    Abs,
    Sqrt,
}

impl Unary {
    /// The method of that name (`sin`, `cos`, `tan`, `exp`, `ln`, `abs`, `sqrt`).
    pub fn named(name: &str) -> Option<Unary> {
        Some(match name {
            "sin" => Unary::Sin,
            "cos" => Unary::Cos,
            "tan" => Unary::Tan,
            "exp" => Unary::Exp,
            "ln" => Unary::Ln,
            "abs" => Unary::Abs,
            "sqrt" => Unary::Sqrt,
            _ => return None,
        })
    }

    /// The method applied to `x`, as emitted code calls it.
    #[inline(always)]
    pub fn apply(self, x: f64) -> f64 {
        match self {
            Unary::Sin => x.sin(),
            Unary::Cos => x.cos(),
            Unary::Tan => x.tan(),
            Unary::Exp => x.exp(),
            Unary::Ln => x.ln(),
            Unary::Abs => x.abs(),
            Unary::Sqrt => x.sqrt(),
        }
    }
}

/// A compiled body (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct Tape {
    inputs: usize,
    constants: Vec<f64>,
    instrs: Vec<Instr>,
    outputs: Vec<u32>,
}

thread_local! {
    /// Each thread's registers, reused from call to call (no allocation per call).
    static REGISTERS: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
}

impl Tape {
    /// The tape `write` writes: it returns the registers of the outputs.
    pub fn write(write: impl FnOnce(&mut Writer) -> Vec<u32>) -> Tape {
        let mut w = Writer::new();
        let outs = write(&mut w);
        w.finish(outs)
    }

    /// This tape, then `next` reading its input `k` from this tape's output `wiring[k]`: one
    /// tape with the same inputs, whose outputs are this one's and then `next`'s. The same
    /// instructions in the same order, so the same numbers as running the two one after the
    /// other; one call instead of two (a right-hand side and its `L D L^T` solve).
    ///
    /// ```
    /// use tape::{Instr, Tape};
    /// let sum = Tape::write(|w| vec![w.instr(Instr::Add(w.input(0), w.input(1))), w.input(1)]);
    /// let half = Tape::write(|w| {
    ///     let two = w.constant(2.0);
    ///     vec![w.instr(Instr::Div(w.input(0), two))]
    /// });
    /// let both = sum.followed_by(&half, &[0]);
    /// let mut out = [0.0; 3];
    /// both.eval(&[3.0, 4.0], &mut out);
    /// assert_eq!(out, [7.0, 4.0, 3.5]);
    /// ```
    ///
    /// # Panics
    ///
    /// Where `wiring` does not give each of `next`'s inputs one of this tape's outputs.
    pub fn followed_by(&self, next: &Tape, wiring: &[usize]) -> Tape {
        assert!(wiring.len() >= next.inputs && wiring.iter().all(|&k| k < self.outputs.len()), "each input of the next tape is an output of this one");
        let mut w = Writer::new();
        // Each finished register of `tape` as a register of the writer (tagged until
        // `finish`), given what its inputs are.
        let append = |w: &mut Writer, tape: &Tape, input: &dyn Fn(usize) -> u32| -> Vec<u32> {
            let mut regs: Vec<u32> = (0..tape.inputs).map(input).collect();
            regs.extend(tape.constants.iter().map(|&v| w.constant(v)));
            for ins in &tape.instrs {
                let r = w.instr(ins.map_operands(|r| regs[r as usize]));
                regs.push(r);
            }
            tape.outputs.iter().map(|&o| regs[o as usize]).collect()
        };
        let first = append(&mut w, self, &|k| k as u32);
        let second = append(&mut w, next, &|k| first[wiring[k]]);
        w.finish([first, second].concat())
    }

    /// Number of input registers the tape reads.
    pub fn inputs(&self) -> usize {
        self.inputs
    }

    /// Number of outputs.
    pub fn outputs(&self) -> usize {
        self.outputs.len()
    }

    /// Number of arithmetic instructions.
    pub fn instructions(&self) -> usize {
        self.instrs.len()
    }

    /// The program, for a backend that compiles it (a JIT): the number of input registers,
    /// the constants (the registers after them), the instructions (one register each, after
    /// the constants) and the registers the outputs read.
    pub fn parts(&self) -> (usize, &[f64], &[Instr], &[u32]) {
        (self.inputs, &self.constants, &self.instrs, &self.outputs)
    }

    /// Evaluates the tape at `inputs` (laid out as the tape's writer numbered them), writing
    /// every output. Inputs past the end of `inputs` read zero.
    pub fn eval(&self, inputs: &[f64], out: &mut [f64]) {
        REGISTERS.with(|cell| {
            let mut regs = cell.borrow_mut();
            self.eval_with(inputs, &mut regs, out);
        })
    }

    fn eval_with(&self, inputs: &[f64], regs: &mut Vec<f64>, out: &mut [f64]) {
        let base = self.inputs + self.constants.len();
        // Every instruction writes its register before any later one reads it: the buffer only
        // grows, and is never cleared.
        if regs.len() < base + self.instrs.len() {
            regs.resize(base + self.instrs.len(), 0.0);
        }
        let given = self.inputs.min(inputs.len());
        regs[..given].copy_from_slice(&inputs[..given]);
        regs[given..self.inputs].fill(0.0);
        regs[self.inputs..base].copy_from_slice(&self.constants);
        let r = regs.as_mut_slice();
        for (k, ins) in self.instrs.iter().enumerate() {
            // Operands always precede their instruction (checked by the slice's bounds).
            let v = match *ins {
                Instr::Add(a, b) => r[a as usize] + r[b as usize],
                Instr::Sub(a, b) => r[a as usize] - r[b as usize],
                Instr::Mul(a, b) => r[a as usize] * r[b as usize],
                Instr::Div(a, b) => r[a as usize] / r[b as usize],
                Instr::Neg(a) => -r[a as usize],
                Instr::Call(f, a) => f.apply(r[a as usize]),
                Instr::Powi(a, n) => r[a as usize].powi(n),
                Instr::Powf(a, b) => r[a as usize].powf(r[b as usize]),
            };
            r[base + k] = v;
        }
        for (o, &reg) in out.iter_mut().zip(&self.outputs) {
            *o = r[reg as usize];
        }
    }
}

/// Writes a tape instruction by instruction: the generator's compiler of emitted bodies, and
/// straight-line code that is not an emitted body (an `L D L^T` solve). Registers it returns are
/// tagged until [`Writer::finish`] numbers them, since how many constants sit between the inputs
/// and the instructions is known only at the end.
///
/// ```
/// use tape::{Instr, Writer};
/// // out = (x0 + x1) * 2
/// let mut w = Writer::new();
/// let sum = w.instr(Instr::Add(w.input(0), w.input(1)));
/// let two = w.constant(2.0);
/// let out = w.instr(Instr::Mul(sum, two));
/// let tape = w.finish(vec![out]);
/// let mut y = [0.0];
/// tape.eval(&[1.5, 2.0], &mut y);
/// assert_eq!((tape.inputs(), y[0]), (2, 7.0));
/// ```
#[derive(Debug, Default)]
pub struct Writer {
    tape: Tape,
    constants: HashMap<u64, u32>,
}

/// Marks an operand as a constant's index, or an instruction's, until [`Writer::finish`].
const CONST_TAG: u32 = 1 << 31;
const INSTR_TAG: u32 = 1 << 30;

impl Writer {
    /// An empty tape.
    pub fn new() -> Writer {
        Writer::default()
    }

    /// Input `k`'s register.
    pub fn input(&self, k: usize) -> u32 {
        k as u32
    }

    /// A constant's register (one per value, by its bits).
    pub fn constant(&mut self, v: f64) -> u32 {
        if let Some(&r) = self.constants.get(&v.to_bits()) {
            return r;
        }
        let r = CONST_TAG | self.tape.constants.len() as u32;
        self.tape.constants.push(v);
        self.constants.insert(v.to_bits(), r);
        r
    }

    /// The register `ins` writes; its operands are registers returned before.
    pub fn instr(&mut self, ins: Instr) -> u32 {
        self.tape.instrs.push(ins);
        INSTR_TAG | (self.tape.instrs.len() - 1) as u32
    }

    /// The tape, its outputs reading `outputs`: the registers numbered inputs, then constants,
    /// then instructions. The inputs are the registers below the highest input read.
    pub fn finish(self, outputs: Vec<u32>) -> Tape {
        let mut tape = self.tape;
        tape.outputs = outputs;
        let read = |r: u32| if r & (CONST_TAG | INSTR_TAG) == 0 { r + 1 } else { 0 };
        let operands = tape.instrs.iter().flat_map(|ins| match *ins {
            Instr::Add(a, b) | Instr::Sub(a, b) | Instr::Mul(a, b) | Instr::Div(a, b) | Instr::Powf(a, b) => [a, b],
            Instr::Neg(a) | Instr::Call(_, a) | Instr::Powi(a, _) => [a, a],
        });
        tape.inputs = operands.chain(tape.outputs.iter().copied()).map(read).max().unwrap_or(0) as usize;
        let (ni, nc) = (tape.inputs as u32, tape.constants.len() as u32);
        let reg = |r: u32| {
            if r & CONST_TAG != 0 {
                ni + (r & !CONST_TAG)
            } else if r & INSTR_TAG != 0 {
                ni + nc + (r & !INSTR_TAG)
            } else {
                r
            }
        };
        for ins in &mut tape.instrs {
            *ins = ins.map_operands(reg);
        }
        for o in &mut tape.outputs {
            *o = reg(*o);
        }
        tape
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tape of `length` instructions over `inputs` inputs drawn by `pick`, with constants
    /// (some shared with other tapes), and outputs that are instructions, inputs and constants.
    fn tape(inputs: usize, length: usize, pick: &mut impl FnMut(usize) -> usize) -> Tape {
        Tape::write(|w| {
            let mut regs: Vec<u32> = (0..inputs).map(|k| w.input(k)).collect();
            regs.push(w.constant(0.5));
            regs.push(w.constant(3.0 + pick(4) as f64));
            for k in 0..length {
                let (a, b) = (regs[pick(regs.len())], regs[pick(regs.len())]);
                let ins = match k % 5 {
                    0 => Instr::Add(a, b),
                    1 => Instr::Sub(a, b),
                    2 => Instr::Mul(a, b),
                    3 => Instr::Call(Unary::Sin, a),
                    _ => Instr::Div(a, b),
                };
                regs.push(w.instr(ins));
            }
            let last = regs.len() - 1;
            vec![regs[last], w.input(inputs - 1), regs[inputs], regs[last - 1], regs[last - 2]]
        })
    }

    /// One tape, then the next on its outputs: the joined tape gives the same bits as the two
    /// run one after the other, for any wiring, and keeps the first tape's inputs.
    #[test]
    fn a_joined_tape_computes_what_its_two_tapes_compute_in_turn() {
        let mut seed = 7u64;
        let mut pick = |n: usize| {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 33) as usize) % n
        };
        for round in 0..50 {
            let first = tape(3 + round % 4, 20 + round, &mut pick);
            let next = tape(2 + round % 3, 10 + round % 7, &mut pick);
            let wiring: Vec<usize> = (0..5).map(|_| pick(first.outputs())).collect();
            let joined = first.followed_by(&next, &wiring);
            assert_eq!((joined.inputs, joined.outputs()), (first.inputs, first.outputs() + next.outputs()));
            assert_eq!(joined.instructions(), first.instructions() + next.instructions());
            let inputs: Vec<f64> = (0..first.inputs).map(|k| 0.3 + k as f64 * 0.7 - round as f64 * 0.01).collect();
            let mut out = vec![0.0; first.outputs()];
            first.eval(&inputs, &mut out);
            let between: Vec<f64> = wiring.iter().map(|&k| out[k]).collect();
            let mut then = vec![0.0; next.outputs()];
            next.eval(&between, &mut then);
            let mut both = vec![0.0; joined.outputs()];
            joined.eval(&inputs, &mut both);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&both), bits(&[out, then].concat()), "round {round}");
        }
    }

    #[test]
    #[should_panic(expected = "each input of the next tape")]
    fn a_joined_tape_needs_every_input_wired() {
        let sum = Tape::write(|w| vec![w.instr(Instr::Add(w.input(0), w.input(1)))]);
        sum.followed_by(&sum, &[0]);
    }
}
