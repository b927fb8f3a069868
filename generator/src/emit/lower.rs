//! Lowering one expression node to a Rust syntax tree, with its operation count.
//!
//! Children that are bound to `let`s (or are inputs) appear as identifiers; everything else is
//! inlined. Parentheses are written only where Rust's precedence needs them, so the output
//! passes `#![deny(warnings)]` (no `unused_parens`).

use super::ops::OpCount;
use super::syntax;
use crate::symbolic::number::{Rat, rat_to_f64};
use crate::symbolic::{Expr, Node, Symbol};
use proc_macro2::{Literal, TokenStream};

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
    Atom(syn::Expr),
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

    /// The syntax tree, parenthesized if this binds looser than `min`.
    fn expr_at(&self, min: Prec) -> syn::Expr {
        let e = self.expr();
        if self.prec() < min { syntax::paren(e) } else { e }
    }

    /// The syntax tree `syn` would parse from this code's text (left-associative operators,
    /// unary minus binding tightest), so printing it gives the same bytes.
    fn expr(&self) -> syn::Expr {
        match self {
            Code::Atom(e) => e.clone(),
            Code::Sum(terms) => {
                let mut out: Option<syn::Expr> = None;
                for (minus, c) in terms {
                    let t = c.expr_at(Prec::Product);
                    out = Some(match (out, minus) {
                        (None, false) => t,
                        (None, true) => syntax::neg(t),
                        (Some(acc), false) => syntax::binary(acc, syn::BinOp::Add(Default::default()), t),
                        (Some(acc), true) => syntax::binary(acc, syn::BinOp::Sub(Default::default()), t),
                    });
                }
                out.unwrap_or_else(|| syntax::float("0.0"))
            }
            Code::Product(num, den) => {
                let mut out: Option<syn::Expr> = if num.is_empty() { Some(syntax::float("1.0")) } else { None };
                for (i, c) in num.iter().enumerate() {
                    // `a * b / c`: later factors must bind tighter than `*` (left associative).
                    let t = c.expr_at(if i == 0 { Prec::Product } else { Prec::Unary });
                    out = Some(match out {
                        None => t,
                        Some(acc) => syntax::binary(acc, syn::BinOp::Mul(Default::default()), t),
                    });
                }
                let mut out = out.expect("a product has a first factor");
                if !den.is_empty() {
                    let d = if den.len() == 1 { den[0].expr_at(Prec::Atom) } else { join_mul(den) };
                    out = syntax::binary(out, syn::BinOp::Div(Default::default()), d);
                }
                out
            }
            Code::Neg(c) => syntax::neg(c.expr_at(Prec::Unary)),
        }
    }
}

fn join_mul(den: &[Code]) -> syn::Expr {
    let mut inner: Option<syn::Expr> = None;
    for c in den {
        let t = c.expr_at(Prec::Unary);
        inner = Some(match inner {
            None => t,
            Some(acc) => syntax::binary(acc, syn::BinOp::Mul(Default::default()), t),
        });
    }
    syntax::paren(inner.expect("a denominator has a factor"))
}

/// A float literal for a rational number.
pub fn literal(r: &Rat) -> Result<TokenStream, LowerError> {
    Ok(quote::ToTokens::into_token_stream(num_code(r)?.expr()))
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
    let atom = Code::Atom(syntax::literal(lit));
    Ok(if v < 0.0 { Code::Neg(Box::new(atom)) } else { atom })
}

fn call(name: &'static str, args: Vec<syn::Expr>, ops: &mut OpCount) -> Code {
    ops.call(name);
    Code::Atom(syntax::call(&["f64", name], args))
}

/// Lowers the top node of `e`; children go through `child`.
fn lower_node(
    e: Expr,
    ops: &mut OpCount,
    symbol: &dyn Fn(Symbol) -> Option<syn::Expr>,
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
                            target.push(Code::Atom(base.expr()));
                        }
                    } else {
                        let bt = base.expr();
                        target.push(call("powi", vec![bt, syntax::literal(Literal::i32_unsuffixed(n))], ops));
                    }
                } else if let Some(root) = super::cse::root_of(e, *b, &ex) {
                    // The root as a node of its own: a `let` where the plan bound it.
                    target.push(child(root, ops)?);
                } else if ex == Rat::frac(1, 2) {
                    let bt = child(*b, ops)?.expr();
                    target.push(call("sqrt", vec![bt], ops));
                } else {
                    let bt = child(*b, ops)?.expr();
                    let et = num_code(&ex)?.expr();
                    target.push(call("powf", vec![bt, et], ops));
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
            let at = child(*a, ops)?.expr();
            call(f.name(), vec![at], ops)
        }
        Node::Apply(name, a) if *name == super::optimize::reciprocal_symbol() => {
            ops.div += 1;
            Code::Product(vec![], vec![child(*a, ops)?])
        }
        Node::Apply(name, a) if *name == super::pairs::group_symbol() => child(*a, ops)?,
        Node::Apply(name, _) => return Err(LowerError::UndefinedFunction(name.name())),
    })
}

/// Lowers `e` to a syntax tree: `symbol` names inputs, `bound` names subexpressions already held in
/// a `let` (returns `None` for those to inline). The root itself is never looked up in
/// `bound`, so a `let`'s own right-hand side can be lowered with the same closure.
pub fn lower(e: Expr, symbol: &dyn Fn(Symbol) -> Option<syn::Expr>, bound: &dyn Fn(Expr) -> Option<syn::Expr>) -> Result<(syn::Expr, OpCount), LowerError> {
    let mut ops = OpCount::default();
    let code = lower_rec(e, true, symbol, bound, &mut ops)?;
    Ok((code.expr(), ops))
}

fn lower_rec(
    e: Expr,
    root: bool,
    symbol: &dyn Fn(Symbol) -> Option<syn::Expr>,
    bound: &dyn Fn(Expr) -> Option<syn::Expr>,
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
    use quote::quote;

    /// The lowered expression as prettyplease prints it.
    fn show(e: Expr) -> String {
        let name = |s: Symbol| Some(syntax::ident(&s.name()));
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

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::emit::lower::lower;
        use crate::symbolic::Expr;
        let x = Expr::sym("x");
        let e = x.sin() * 3 - x;
        let name = |s: crate::symbolic::Symbol| Some(crate::emit::syntax::ident(&s.name()));
        let (tree, ops) = lower(e, &name, &|_| None).unwrap();
        assert_eq!(quote::ToTokens::to_token_stream(&tree).to_string(), "3.0 * f64 :: sin (x) - x");
        assert_eq!(ops.total(), 3);
    }
}
