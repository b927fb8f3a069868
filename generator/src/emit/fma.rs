//! Fused multiply-adds in emitted code ([`super::Options::fma`]): every `a * b + c`,
//! `c + a * b`, `a * b - c` and `c - a * b` of a function body becomes one
//! `f64::mul_add(a, b, c)` (with `c` or `a` negated, which is exact), rounded once instead of
//! twice. On a target with the instruction (`-C target-cpu=native` on x86-64 since Haswell,
//! or `-C target-feature=+fma`) each is one instruction; elsewhere `mul_add` is the C
//! library's `fma`, correct but slow. The values differ from the plain code's by round-off.
//!
//! The straight-line code is rewritten (its values are all `f64`): the bodies, and the
//! unrolled `L D L^T` solves (`solve_ldl`, whose eliminations subtract products); the generic
//! solvers with loops and the code around them are left as they are.

use syn::visit_mut::VisitMut;
use syn::{BinOp, Expr, parse_quote};

/// Rewrites the additions and subtractions of products in `e` (children first, so a chain of
/// terms becomes a chain of `mul_add`s).
pub fn fuse(e: &mut Expr) {
    Fuse.visit_expr_mut(e);
}

/// Rewrites every expression of `stmts` (the `let`s of a body, a helper's assignments).
pub fn fuse_stmts(stmts: &mut [syn::Stmt]) {
    for s in stmts {
        Fuse.visit_stmt_mut(s);
    }
}

/// Rewrites every expression in the body of `item` (a helper function of a split body).
pub fn fuse_item(item: &mut syn::Item) {
    Fuse.visit_item_mut(item);
}

struct Fuse;

impl VisitMut for Fuse {
    fn visit_expr_mut(&mut self, e: &mut Expr) {
        syn::visit_mut::visit_expr_mut(self, e);
        // A call fused inside parentheses needs them no more (rustc warns `unused_parens`).
        if let Expr::Paren(p) = e
            && is_operand(&p.expr)
            && !matches!(*p.expr, Expr::Lit(_))
        {
            *e = (*p.expr).clone();
            return;
        }
        let Expr::Binary(b) = e else { return };
        let minus = match b.op {
            BinOp::Add(_) => false,
            BinOp::Sub(_) => true,
            _ => return,
        };
        let (left, right) = (&*b.left, &*b.right);
        // The arguments of a call need no parentheses.
        let fused: Expr = if let Some((x, y)) = product(left) {
            let c = if minus { negated(right) } else { strip(right) };
            let (x, y) = (strip(&x), strip(&y));
            parse_quote!(f64::mul_add(#x, #y, #c))
        } else if let Some((x, y)) = product(right) {
            let x = if minus { negated(&x) } else { strip(&x) };
            let (y, left) = (strip(&y), strip(left));
            parse_quote!(f64::mul_add(#x, #y, #left))
        } else {
            return;
        };
        *e = fused;
    }
}

/// `(a, b)` of a product `a * b` (through parentheses).
fn product(e: &Expr) -> Option<(Expr, Expr)> {
    match e {
        Expr::Paren(p) => product(&p.expr),
        Expr::Binary(b) if matches!(b.op, BinOp::Mul(_)) => Some(((*b.left).clone(), (*b.right).clone())),
        _ => None,
    }
}

/// Whether `e` is a single operand: never needs parentheses around it.
fn is_operand(e: &Expr) -> bool {
    matches!(e, Expr::Path(_) | Expr::Lit(_) | Expr::Call(_) | Expr::MethodCall(_) | Expr::Index(_) | Expr::Paren(_) | Expr::Field(_))
}

/// `-e`, parenthesized only where `e` is not a single operand.
fn negated(e: &Expr) -> Expr {
    match e {
        Expr::Unary(u) if matches!(u.op, syn::UnOp::Neg(_)) => strip(&u.expr),
        e if is_operand(e) => parse_quote!(-#e),
        _ => parse_quote!(-(#e)),
    }
}

/// `e` without its outer parentheses.
fn strip(e: &Expr) -> Expr {
    match e {
        Expr::Paren(p) => strip(&p.expr),
        _ => e.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn show(mut e: Expr) -> String {
        fuse(&mut e);
        quote::ToTokens::to_token_stream(&e).to_string()
    }

    #[test]
    fn each_sign_of_a_product_and_an_addend_fuses() {
        assert_eq!(show(parse_quote!(a * b + c)), "f64 :: mul_add (a , b , c)");
        assert_eq!(show(parse_quote!(c + a * b)), "f64 :: mul_add (a , b , c)");
        assert_eq!(show(parse_quote!(a * b - c)), "f64 :: mul_add (a , b , - c)");
        assert_eq!(show(parse_quote!(c - a * b)), "f64 :: mul_add (- a , b , c)");
        assert_eq!(show(parse_quote!(a * b - (c + d))), "f64 :: mul_add (a , b , - (c + d))");
        assert_eq!(show(parse_quote!(a * b - -c)), "f64 :: mul_add (a , b , c)");
        // Nothing to fuse.
        assert_eq!(show(parse_quote!(a / b + c)), "a / b + c");
        assert_eq!(show(parse_quote!(a * b)), "a * b");
    }

    #[test]
    fn nested_products_fuse_inside_calls_and_parentheses() {
        assert_eq!(show(parse_quote!(f64::sin(x * y + z))), "f64 :: sin (f64 :: mul_add (x , y , z))");
        assert_eq!(show(parse_quote!((a * b + c) * d + e)), "f64 :: mul_add (f64 :: mul_add (a , b , c) , d , e)");
        // Parentheses around an argument go; those a sum needs stay.
        assert_eq!(show(parse_quote!((a + b) * c + (d + e))), "f64 :: mul_add (a + b , c , d + e)");
        assert_eq!(show(parse_quote!((a / b) * c - (d + e))), "f64 :: mul_add (a / b , c , - (d + e))");
        assert_eq!(show(parse_quote!(x * (a * b + c))), "x * f64 :: mul_add (a , b , c)");
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::emit::fma::fuse;
        let mut e: syn::Expr = syn::parse_quote!(x * y + z - 2.0 * w);
        fuse(&mut e);
        assert_eq!(quote::ToTokens::to_token_stream(&e).to_string(), "f64 :: mul_add (- 2.0 , w , f64 :: mul_add (x , y , z))");
    }
}
