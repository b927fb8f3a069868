//! Emitted function bodies compiled to register tapes ([`::tape::Tape`]): from the very syntax
//! trees the emitter prints, each operation in the emitted code's order, so that the tape gives
//! the compiled module's numbers.
//!
//! ```
//! use generator::emit::tape::{Slots, compile};
//! let stmts: Vec<syn::Stmt> = vec![syn::parse_quote!(let x = state[0];), syn::parse_quote!(let x0 = f64::sin(x);)];
//! let outputs: Vec<syn::Expr> = vec![syn::parse_quote!(2.0 * x0 - x)];
//! let slots = Slots::new(&[("t", 1), ("state", 1)]);
//! let tape = compile(&stmts, &outputs, &slots).unwrap();
//! let mut out = [0.0];
//! tape.eval(&[0.0, 0.5], &mut out);
//! assert_eq!(out[0], 2.0 * f64::sin(0.5) - 0.5);
//! ```

use std::collections::HashMap;

pub use ::tape::{Instr, Tape, Unary, Writer};

/// Why a body could not be compiled to a tape: it holds syntax the emitter does not write (a
/// bug in the emitter or here, never the user's model).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("internal error: cannot evaluate `{0}` in-process")]
pub struct TapeError(pub String);

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

/// Compiles `stmts` (`let NAME = EXPR;`, and the split form's `v[k] = EXPR;`) and the
/// `outputs` over the arguments laid out by `slots`.
pub fn compile<'s>(stmts: impl IntoIterator<Item = &'s syn::Stmt>, outputs: &[syn::Expr], slots: &Slots) -> Result<Tape, TapeError> {
    let mut c = Compiler { slots, w: Writer::new(), names: HashMap::new() };
    for s in stmts {
        c.stmt(s)?;
    }
    let outs = outputs.iter().map(|e| c.expr(e)).collect::<Result<Vec<_>, _>>()?;
    Ok(c.w.finish(outs))
}

struct Compiler<'a> {
    slots: &'a Slots,
    w: Writer,
    names: HashMap<String, u32>,
}

fn text(t: &impl quote::ToTokens) -> String {
    t.to_token_stream().to_string()
}

impl Compiler<'_> {
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
                self.w.constant(v)
            }
            syn::Expr::Path(p) => {
                let name = text(p).replace(' ', "");
                match name.as_str() {
                    "f64::NAN" => self.w.constant(f64::NAN),
                    "f64::INFINITY" => self.w.constant(f64::INFINITY),
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
                self.w.instr(Instr::Neg(a))
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
                self.w.instr(ins)
            }
            syn::Expr::Call(call) => {
                let f = text(&call.func).replace(' ', "");
                let name = f.strip_prefix("f64::").ok_or_else(|| TapeError(text(e)))?;
                let args: Vec<&syn::Expr> = call.args.iter().collect();
                match (name, &args[..]) {
                    ("powi", [x, n]) => {
                        let x = self.expr(x)?;
                        let n: i32 = text(*n).replace(' ', "").parse().map_err(|_| TapeError(text(e)))?;
                        self.w.instr(Instr::Powi(x, n))
                    }
                    ("powf", [x, y]) => {
                        let (x, y) = (self.expr(x)?, self.expr(y)?);
                        self.w.instr(Instr::Powf(x, y))
                    }
                    (name, [x]) => {
                        let f = Unary::named(name).ok_or_else(|| TapeError(text(e)))?;
                        let x = self.expr(x)?;
                        self.w.instr(Instr::Call(f, x))
                    }
                    _ => return Err(TapeError(text(e))),
                }
            }
            _ => return Err(TapeError(text(e))),
        };
        Ok(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every form the emitter writes compiles, reading its arguments where `slots` puts them
    /// (a struct's fields by name, arrays by index, the split form's scratch entries), and
    /// syntax it does not write is refused, naming it.
    #[test]
    fn the_emitted_forms_compile_and_others_are_refused() {
        let stmts: Vec<syn::Stmt> = vec![
            syn::parse_quote!(let a = params.m * q[1];),
            syn::parse_quote!(v[0] = f64::powi(a, 3) - f64::powf(qdot[0], t);),
            syn::parse_quote!(let b = -(v[0] / f64::sqrt(a));),
        ];
        let slots = Slots::new(&[("t", 1), ("params", 2), ("q", 2), ("qdot", 1)]).with_fields(&["g".into(), "m".into()]);
        let tape = compile(&stmts, &[syn::parse_quote!(b + 1.5)], &slots).unwrap();
        let (t, g, m, q, qdot) = (0.5, 9.81, 2.0, [0.3, 0.7], 1.25);
        let mut out = [0.0];
        tape.eval(&[t, g, m, q[0], q[1], qdot], &mut out);
        let a = m * q[1];
        let v0 = a.powi(3) - qdot.powf(t);
        assert_eq!(out[0], -(v0 / a.sqrt()) + 1.5);
        for bad in ["let c = a % 2.0;", "let c = f64::atan2(a, a);", "let c = unknown * 2.0;", "let c = q[2];"] {
            let mut with_bad = stmts.clone();
            with_bad.push(syn::parse_str(bad).unwrap());
            let err = compile(&with_bad, &[syn::parse_quote!(c)], &slots).unwrap_err();
            assert!(err.to_string().contains("cannot evaluate"), "{bad}: {err}");
        }
    }
}
