//! A register tape: the straight-line arithmetic of one emitted function body, compiled from
//! the very syntax trees the emitter prints, so that it performs the same IEEE operations in
//! the same order as the compiled module (no reassociation, no fused multiply-add: Rust does
//! neither) and gives the same numbers.
//!
//! The registers are the inputs (`t`, the state, the parameters...), then the constants, then one
//! per instruction; the outputs name registers.
//!
//! ```
//! use generator::emit::tape::{Slots, Tape};
//! let stmts: Vec<syn::Stmt> = vec![syn::parse_quote!(let x = state[0];), syn::parse_quote!(let x0 = f64::sin(x);)];
//! let outputs: Vec<syn::Expr> = vec![syn::parse_quote!(2.0 * x0 - x)];
//! let slots = Slots::new(&[("t", 1), ("state", 1)]);
//! let tape = Tape::compile(&stmts, &outputs, &slots).unwrap();
//! let mut out = [0.0];
//! tape.eval(&[0.0, 0.5], &mut out);
//! assert_eq!(out[0], 2.0 * f64::sin(0.5) - 0.5);
//! ```

use std::cell::RefCell;
use std::collections::HashMap;

/// Why a body could not be compiled to a tape: it holds syntax the emitter does not write (a
/// bug in the emitter or here, never the user's model).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("internal error: cannot evaluate `{0}` in-process")]
pub struct TapeError(pub String);

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
    fn of(name: &str) -> Option<Unary> {
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

/// Where a function's arguments sit in the input registers: each argument name with its
/// length, in order (`t` is one entry), and the parameters' field names when `params` is a
/// struct.
#[derive(Clone, Debug, Default)]
pub struct Slots {
    offsets: HashMap<String, (usize, usize)>,
    fields: HashMap<String, usize>,
    len: usize,
}

impl Slots {
    /// The layout of arguments `(name, length)`, in order.
    pub fn new(args: &[(&str, usize)]) -> Slots {
        let mut s = Slots::default();
        for (name, n) in args {
            s.offsets.insert(name.to_string(), (s.len, *n));
            s.len += n;
        }
        s
    }

    /// `params.NAME` reads entry `k` of the `params` argument, for each name in order.
    pub fn with_fields(mut self, names: &[String]) -> Slots {
        self.fields = names.iter().enumerate().map(|(k, n)| (n.clone(), k)).collect();
        self
    }

    /// Number of input registers the arguments span.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when the function reads nothing.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn element(&self, arg: &str, k: usize) -> Option<u32> {
        let &(at, n) = self.offsets.get(arg)?;
        (k < n).then_some((at + k) as u32)
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
    /// Compiles `stmts` (`let NAME = EXPR;`, and the split form's `v[k] = EXPR;`) and the
    /// `outputs` over the arguments laid out by `slots`.
    pub fn compile(stmts: &[syn::Stmt], outputs: &[syn::Expr], slots: &Slots) -> Result<Tape, TapeError> {
        let mut c = Compiler { slots, tape: Tape::default(), names: HashMap::new(), constants: HashMap::new() };
        for s in stmts {
            c.stmt(s)?;
        }
        let outs = outputs.iter().map(|e| c.expr(e)).collect::<Result<Vec<_>, _>>()?;
        c.tape.outputs = outs;
        Ok(c.finish())
    }

    /// The tape `write` writes: it returns the registers of the outputs.
    pub fn write(write: impl FnOnce(&mut TapeWriter) -> Vec<u32>) -> Tape {
        let slots = Slots::new(&[]);
        let mut c = Compiler { slots: &slots, tape: Tape::default(), names: HashMap::new(), constants: HashMap::new() };
        let outs = write(&mut TapeWriter(&mut c));
        c.tape.outputs = outs;
        c.finish()
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

    /// Evaluates the tape at `inputs` (as laid out by the [`Slots`] it was compiled with),
    /// writing every output.
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

/// Writes a tape instruction by instruction, for straight-line code that is not an emitted body
/// (an `L D L^T` solve: [`super::ldl::LdlPlan::tape`]).
///
/// ```
/// use generator::emit::tape::{Instr, Tape};
/// // out = (x0 + x1) * 2
/// let tape = Tape::write(|w| {
///     let sum = w.instr(Instr::Add(w.input(0), w.input(1)));
///     let two = w.constant(2.0);
///     vec![w.instr(Instr::Mul(sum, two))]
/// });
/// let mut out = [0.0];
/// tape.eval(&[1.5, 2.0], &mut out);
/// assert_eq!(out, [7.0]);
/// ```
pub struct TapeWriter<'c, 'a>(&'c mut Compiler<'a>);

impl TapeWriter<'_, '_> {
    /// Input `k`'s register.
    pub fn input(&self, k: usize) -> u32 {
        k as u32
    }

    /// A constant's register (one per value).
    pub fn constant(&mut self, v: f64) -> u32 {
        self.0.constant(v)
    }

    /// The register `ins` writes; its operands are registers returned before.
    pub fn instr(&mut self, ins: Instr) -> u32 {
        self.0.push(ins)
    }
}

struct Compiler<'a> {
    slots: &'a Slots,
    tape: Tape,
    names: HashMap<String, u32>,
    constants: HashMap<u64, u32>,
}

fn text(t: &impl quote::ToTokens) -> String {
    t.to_token_stream().to_string()
}

impl Compiler<'_> {
    /// The instruction's result, tagged until [`Compiler::finish`] numbers the registers.
    fn push(&mut self, ins: Instr) -> u32 {
        self.tape.instrs.push(ins);
        INSTR_TAG | (self.tape.instrs.len() - 1) as u32
    }

    /// A constant's register, tagged until [`Compiler::finish`]: the constants sit between the
    /// inputs and the instructions, and how many there are is known only at the end.
    fn constant(&mut self, v: f64) -> u32 {
        if let Some(&r) = self.constants.get(&v.to_bits()) {
            return r;
        }
        let r = CONST_TAG | self.tape.constants.len() as u32;
        self.tape.constants.push(v);
        self.constants.insert(v.to_bits(), r);
        r
    }

    fn stmt(&mut self, s: &syn::Stmt) -> Result<(), TapeError> {
        match s {
            syn::Stmt::Local(local) => {
                let syn::Pat::Ident(p) = &local.pat else { return Err(TapeError(text(s))) };
                let init = local.init.as_ref().ok_or_else(|| TapeError(text(s)))?;
                let r = self.expr(&init.expr)?;
                self.names.insert(p.ident.to_string(), r);
                Ok(())
            }
            syn::Stmt::Expr(syn::Expr::Assign(a), _) => {
                let r = self.expr(&a.right)?;
                self.names.insert(text(&a.left), r);
                Ok(())
            }
            _ => Err(TapeError(text(s))),
        }
    }

    fn expr(&mut self, e: &syn::Expr) -> Result<u32, TapeError> {
        let r = match e {
            syn::Expr::Paren(p) => return self.expr(&p.expr),
            syn::Expr::Group(g) => return self.expr(&g.expr),
            syn::Expr::Lit(l) => {
                let v = match &l.lit {
                    syn::Lit::Float(f) => f.base10_parse::<f64>(),
                    syn::Lit::Int(i) => i.base10_parse::<f64>(),
                    _ => return Err(TapeError(text(e))),
                }
                .map_err(|_| TapeError(text(e)))?;
                self.constant(v)
            }
            syn::Expr::Path(p) => {
                let name = text(p).replace(' ', "");
                match name.as_str() {
                    "f64::NAN" => self.constant(f64::NAN),
                    "f64::INFINITY" => self.constant(f64::INFINITY),
                    _ => match self.names.get(&name) {
                        Some(&r) => r,
                        None => self.slots.element(&name, 0).ok_or_else(|| TapeError(text(e)))?,
                    },
                }
            }
            syn::Expr::Index(ix) => {
                let base = text(&ix.expr);
                let k: usize = match &*ix.index {
                    syn::Expr::Lit(syn::ExprLit { lit: syn::Lit::Int(i), .. }) => i.base10_parse().map_err(|_| TapeError(text(e)))?,
                    _ => return Err(TapeError(text(e))),
                };
                match self.names.get(&text(e)) {
                    Some(&r) => r,
                    None => self.slots.element(&base, k).ok_or_else(|| TapeError(text(e)))?,
                }
            }
            syn::Expr::Field(f) => {
                let syn::Member::Named(field) = &f.member else { return Err(TapeError(text(e))) };
                let k = *self.slots.fields.get(&field.to_string()).ok_or_else(|| TapeError(text(e)))?;
                self.slots.element(&text(&f.base), k).ok_or_else(|| TapeError(text(e)))?
            }
            syn::Expr::Unary(u) if matches!(u.op, syn::UnOp::Neg(_)) => {
                let a = self.expr(&u.expr)?;
                self.push(Instr::Neg(a))
            }
            syn::Expr::Binary(b) => {
                let (l, r) = (self.expr(&b.left)?, self.expr(&b.right)?);
                let ins = match b.op {
                    syn::BinOp::Add(_) => Instr::Add(l, r),
                    syn::BinOp::Sub(_) => Instr::Sub(l, r),
                    syn::BinOp::Mul(_) => Instr::Mul(l, r),
                    syn::BinOp::Div(_) => Instr::Div(l, r),
                    _ => return Err(TapeError(text(e))),
                };
                self.push(ins)
            }
            syn::Expr::Call(call) => {
                let f = text(&call.func).replace(' ', "");
                let name = f.strip_prefix("f64::").ok_or_else(|| TapeError(text(e)))?;
                let args: Vec<&syn::Expr> = call.args.iter().collect();
                match (name, &args[..]) {
                    ("powi", [x, n]) => {
                        let x = self.expr(x)?;
                        let n: i32 = text(*n).replace(' ', "").parse().map_err(|_| TapeError(text(e)))?;
                        self.push(Instr::Powi(x, n))
                    }
                    ("powf", [x, y]) => {
                        let (x, y) = (self.expr(x)?, self.expr(y)?);
                        self.push(Instr::Powf(x, y))
                    }
                    (name, [x]) => {
                        let f = Unary::of(name).ok_or_else(|| TapeError(text(e)))?;
                        let x = self.expr(x)?;
                        self.push(Instr::Call(f, x))
                    }
                    _ => return Err(TapeError(text(e))),
                }
            }
            _ => return Err(TapeError(text(e))),
        };
        Ok(r)
    }
}

/// Marks an operand as a constant's index, or an instruction's, until [`Compiler::finish`].
const CONST_TAG: u32 = 1 << 31;
const INSTR_TAG: u32 = 1 << 30;

impl Compiler<'_> {
    /// Numbers the registers: inputs, then constants, then instructions.
    fn finish(self) -> Tape {
        let mut tape = self.tape;
        // The inputs are the registers below the highest one read.
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
            *ins = match *ins {
                Instr::Add(a, b) => Instr::Add(reg(a), reg(b)),
                Instr::Sub(a, b) => Instr::Sub(reg(a), reg(b)),
                Instr::Mul(a, b) => Instr::Mul(reg(a), reg(b)),
                Instr::Div(a, b) => Instr::Div(reg(a), reg(b)),
                Instr::Neg(a) => Instr::Neg(reg(a)),
                Instr::Call(f, a) => Instr::Call(f, reg(a)),
                Instr::Powi(a, n) => Instr::Powi(reg(a), n),
                Instr::Powf(a, b) => Instr::Powf(reg(a), reg(b)),
            };
        }
        for o in &mut tape.outputs {
            *o = reg(*o);
        }
        tape
    }
}
