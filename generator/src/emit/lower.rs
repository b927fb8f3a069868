//! Lowering one expression node to Rust tokens, with its operation count.
//!
//! Children that are bound to `let`s (or are inputs) appear as identifiers; everything else is
//! inlined. Parentheses are written only where Rust's precedence needs them, so the output
//! passes `#![deny(warnings)]` (no `unused_parens`).
//!
//! ```
//! use generator::emit::lower::lower;
//! use generator::symbolic::Expr;
//! let x = Expr::sym("x");
//! let e = x.sin() * 3 - x;
//! let name = |s: generator::symbolic::Symbol| {
//!     let i = proc_macro2::Ident::new(&s.name(), proc_macro2::Span::call_site());
//!     Some(quote::quote!(#i))
//! };
//! let (tokens, ops) = lower(e, &name, &|_| None).unwrap();
//! assert_eq!(tokens.to_string(), "3.0 * f64 :: sin (x) - x");
//! assert_eq!(ops.total(), 3);
//! ```

use super::ops::OpCount;
use crate::symbolic::number::{Rat, rat_to_f64};
use crate::symbolic::{Expr, Node, Symbol};
use proc_macro2::{Literal, TokenStream};
use quote::quote;

/// Why an expression could not be lowered.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LowerError {
    /// A symbol with no binding in the emitted function.
    #[error("symbol `{0}` has no value in this function")]
    Unbound(String),
    /// A named function left after inlining the time functions.
    #[error("function `{0}` has no definition")]
    UndefinedFunction(String),
    /// A number that is not a finite float (its order of magnitude, `10^600`).
    #[error("a constant of about {0} is not a finite f64 (the model's numbers multiply beyond the range of f64)")]
    NotFinite(String),
}

/// `10^k` for a rational far outside the range of `f64`, from the digit counts of its
/// numerator and denominator (the number itself can have thousands of digits).
fn order_of_magnitude(r: &Rat) -> String {
    let text = r.to_string();
    let text = text.trim_start_matches('-');
    let (num, den) = text.split_once('/').unwrap_or((text, "1"));
    let k = num.len() as i64 - den.len() as i64;
    format!("10^{k}")
}

/// Rust expression tree, before printing: just enough structure for precedence.
enum Code {
    Atom(TokenStream),
    /// Terms with their signs (true = subtract).
    Sum(Vec<(bool, Code)>),
    /// Numerator and denominator factors (all atoms or calls or parenthesized sums).
    Product(Vec<Code>, Vec<Code>),
    Neg(Box<Code>),
}

/// Binding precedence: sums < products < unary minus < atoms.
#[derive(PartialEq, PartialOrd, Clone, Copy)]
enum Prec {
    Sum,
    Product,
    Unary,
    Atom,
}

impl Code {
    fn prec(&self) -> Prec {
        match self {
            Code::Atom(_) => Prec::Atom,
            Code::Sum(t) if t.len() == 1 && !t[0].0 => t[0].1.prec(),
            Code::Sum(_) => Prec::Sum,
            Code::Product(n, d) if n.len() == 1 && d.is_empty() => n[0].prec(),
            Code::Product(..) => Prec::Product,
            Code::Neg(_) => Prec::Unary,
        }
    }

    /// Tokens, parenthesized if this binds looser than `min`.
    fn tokens_at(&self, min: Prec) -> TokenStream {
        let t = self.tokens();
        if self.prec() < min { quote!((#t)) } else { t }
    }

    fn tokens(&self) -> TokenStream {
        match self {
            Code::Atom(t) => t.clone(),
            Code::Sum(terms) => {
                let mut out = TokenStream::new();
                for (i, (minus, c)) in terms.iter().enumerate() {
                    let t = c.tokens_at(Prec::Product);
                    out.extend(match (i, minus) {
                        (0, false) => t,
                        (0, true) => quote!(-#t),
                        (_, false) => quote!(+ #t),
                        (_, true) => quote!(- #t),
                    });
                }
                out
            }
            Code::Product(num, den) => {
                let mut out = TokenStream::new();
                if num.is_empty() {
                    out.extend(quote!(1.0));
                }
                for (i, c) in num.iter().enumerate() {
                    // `a * b / c`: later factors must bind tighter than `*` (left associative).
                    let t = c.tokens_at(if i == 0 { Prec::Product } else { Prec::Unary });
                    out.extend(if i == 0 { t } else { quote!(* #t) });
                }
                if !den.is_empty() {
                    let d = if den.len() == 1 { den[0].tokens_at(Prec::Atom) } else { join_mul(den) };
                    out.extend(quote!(/ #d));
                }
                out
            }
            Code::Neg(c) => {
                let t = c.tokens_at(Prec::Unary);
                quote!(-#t)
            }
        }
    }
}

fn join_mul(den: &[Code]) -> TokenStream {
    let mut inner = TokenStream::new();
    for (i, c) in den.iter().enumerate() {
        let t = c.tokens_at(Prec::Unary);
        inner.extend(if i == 0 { t } else { quote!(* #t) });
    }
    quote!((#inner))
}

/// A float literal for a rational number.
pub fn literal(r: &Rat) -> Result<TokenStream, LowerError> {
    let v = rat_to_f64(r);
    let lit = magnitude_literal(v).ok_or_else(|| LowerError::NotFinite(order_of_magnitude(r)))?;
    Ok(if v < 0.0 { quote!(-#lit) } else { quote!(#lit) })
}

/// `|v|` as the shortest literal that reads back to it (`0.5`, `1e-12`, `1.0`).
fn magnitude_literal(v: f64) -> Option<Literal> {
    if !v.is_finite() {
        return None;
    }
    // Debug formatting is the shortest round-trip form, with an exponent when that is shorter.
    let text = format!("{:?}", v.abs());
    Some(text.parse().unwrap_or_else(|_| Literal::f64_unsuffixed(v.abs())))
}

fn num_code(r: &Rat) -> Result<Code, LowerError> {
    let v = rat_to_f64(r);
    let lit = magnitude_literal(v).ok_or_else(|| LowerError::NotFinite(order_of_magnitude(r)))?;
    Ok(if v < 0.0 { Code::Neg(Box::new(Code::Atom(quote!(#lit)))) } else { Code::Atom(quote!(#lit)) })
}

fn call(name: &'static str, args: TokenStream, ops: &mut OpCount) -> Code {
    ops.call(name);
    let f = proc_macro2::Ident::new(name, proc_macro2::Span::call_site());
    Code::Atom(quote!(f64::#f(#args)))
}

/// Lowers the top node of `e`; children go through `child`.
fn lower_node(
    e: Expr,
    ops: &mut OpCount,
    symbol: &dyn Fn(Symbol) -> Option<TokenStream>,
    child: &mut dyn FnMut(Expr, &mut OpCount) -> Result<Code, LowerError>,
) -> Result<Code, LowerError> {
    Ok(match &*e.node() {
        Node::Num(r) => num_code(r)?,
        Node::Sym(s) => Code::Atom(symbol(*s).ok_or_else(|| LowerError::Unbound(s.name()))?),
        Node::Add { constant, terms } => {
            let mut out = Vec::new();
            for (t, c) in terms {
                let inner = child(*t, ops)?;
                let mag = c.abs();
                let code = if mag.is_one() {
                    inner
                } else {
                    ops.mul += 1;
                    Code::Product(vec![num_code(&mag)?, inner], vec![])
                };
                out.push((c.is_negative(), code));
            }
            if !constant.is_zero() {
                out.push((constant.is_negative(), num_code(&constant.abs())?));
            }
            ops.add += out.len().saturating_sub(1);
            if out.first().is_some_and(|(minus, _)| *minus) {
                // Lead with a positive term where there is one: `b - a`, not `-a + b`.
                if let Some(i) = out.iter().position(|(minus, _)| !*minus) {
                    let first = out.remove(i);
                    out.insert(0, first);
                } else {
                    ops.neg += 1;
                }
            }
            Code::Sum(out)
        }
        Node::Mul { coefficient, factors } => {
            let mut num = Vec::new();
            let mut den = Vec::new();
            let mag = coefficient.abs();
            if !mag.is_one() {
                num.push(num_code(&mag)?);
            }
            for (b, ex) in factors {
                let target = if ex.is_negative() { &mut den } else { &mut num };
                let ex = ex.abs();
                if ex.is_integer() {
                    let n = ex.to_i32().unwrap_or(i32::MAX);
                    let base = child(*b, ops)?;
                    if n == 1 {
                        target.push(base);
                    } else if (n == 2 || n == 3) && matches!(base, Code::Atom(_)) {
                        for _ in 0..n {
                            target.push(Code::Atom(base.tokens()));
                        }
                    } else {
                        let bt = base.tokens();
                        let nl = Literal::i32_unsuffixed(n);
                        ops.call("powi");
                        target.push(Code::Atom(quote!(f64::powi(#bt, #nl))));
                    }
                } else if ex == Rat::frac(1, 2) {
                    let bt = child(*b, ops)?.tokens();
                    target.push(call("sqrt", bt, ops));
                } else {
                    let bt = child(*b, ops)?.tokens();
                    let et = literal(&ex)?;
                    ops.call("powf");
                    target.push(Code::Atom(quote!(f64::powf(#bt, #et))));
                }
            }
            ops.mul += num.len().saturating_sub(1) + den.len().saturating_sub(1);
            if !den.is_empty() {
                ops.div += 1;
            }
            let product = if num.len() == 1 && den.is_empty() { num.pop().unwrap() } else { Code::Product(num, den) };
            if coefficient.is_negative() {
                ops.neg += 1;
                Code::Neg(Box::new(product))
            } else {
                product
            }
        }
        Node::Fun(f, a) => {
            let at = child(*a, ops)?.tokens();
            call(f.name(), at, ops)
        }
        Node::Apply(name, a) if *name == super::optimize::reciprocal_symbol() => {
            ops.div += 1;
            Code::Product(vec![], vec![child(*a, ops)?])
        }
        Node::Apply(name, _) => return Err(LowerError::UndefinedFunction(name.name())),
    })
}

/// Lowers `e` to tokens: `symbol` names inputs, `bound` names subexpressions already held in
/// a `let` (returns `None` for those to inline). The root itself is never looked up in
/// `bound`, so a `let`'s own right-hand side can be lowered with the same closure.
pub fn lower(
    e: Expr,
    symbol: &dyn Fn(Symbol) -> Option<TokenStream>,
    bound: &dyn Fn(Expr) -> Option<TokenStream>,
) -> Result<(TokenStream, OpCount), LowerError> {
    let mut ops = OpCount::default();
    let code = lower_rec(e, true, symbol, bound, &mut ops)?;
    Ok((code.tokens(), ops))
}

fn lower_rec(
    e: Expr,
    root: bool,
    symbol: &dyn Fn(Symbol) -> Option<TokenStream>,
    bound: &dyn Fn(Expr) -> Option<TokenStream>,
    ops: &mut OpCount,
) -> Result<Code, LowerError> {
    if !root && let Some(t) = bound(e) {
        return Ok(Code::Atom(t));
    }
    lower_node(e, ops, symbol, &mut |c, ops| lower_rec(c, false, symbol, bound, ops))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lowered expression as prettyplease prints it.
    fn show(e: Expr) -> String {
        let name = |s: Symbol| {
            let i = proc_macro2::Ident::new(&s.name(), proc_macro2::Span::call_site());
            Some(quote!(#i))
        };
        let (t, _) = lower(e, &name, &|_| None).unwrap();
        let file: syn::File = syn::parse2(quote!(fn f() { let _ = #t; })).unwrap();
        let text = prettyplease::unparse(&file);
        text.lines().nth(1).unwrap().trim().trim_start_matches("let _ = ").trim_end_matches(';').to_string()
    }

    #[test]
    fn precedence_needs_no_extra_parentheses() {
        let (a, b, c) = (Expr::sym("a"), Expr::sym("b"), Expr::sym("c"));
        assert_eq!(show((a + b) * c), "(a + b) * c");
        assert!(["a / (b * c)", "a / (c * b)"].contains(&show(a / (b * c)).as_str()));
        assert_eq!(show(a - b), "a - b");
        assert!(["-(a * b)", "-(b * a)"].contains(&show(-a * b).as_str()));
        assert_eq!(show(a * a), "a * a");
        assert_eq!(show(a.powi(5)), "f64::powi(a, 5)");
        assert_eq!(show((a + b).recip()), "1.0 / (a + b)");
        assert_eq!(show(a.sqrt()), "f64::sqrt(a)");
        let tiny = Expr::num(crate::symbolic::number::rat_from_f64(1e-12).unwrap());
        assert_eq!(show(a * tiny), "1e-12 * a");
        assert_eq!(show(a * 2), "2.0 * a");
    }
}
