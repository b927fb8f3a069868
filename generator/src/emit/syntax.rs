//! Small constructors of Rust syntax trees (`syn::Expr`, `syn::Stmt`) for the emitted bodies,
//! which are built as trees rather than as tokens to parse: syn parsing the bodies of scene 2
//! was a third of its emission time.

use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::quote;
use syn::punctuated::Punctuated;

/// The path `a::b::c` as an expression.
pub fn path(segments: &[&str]) -> syn::Expr {
    let mut p = Punctuated::new();
    for s in segments {
        p.push(syn::PathSegment::from(Ident::new(s, Span::call_site())));
    }
    syn::Expr::Path(syn::ExprPath { attrs: vec![], qself: None, path: syn::Path { leading_colon: None, segments: p } })
}

/// The variable `name`.
pub fn ident(name: &str) -> syn::Expr {
    path(&[name])
}

/// `base[k]`.
pub fn index(base: &str, k: usize) -> syn::Expr {
    syn::Expr::Index(syn::ExprIndex {
        attrs: vec![],
        expr: Box::new(ident(base)),
        bracket_token: Default::default(),
        index: Box::new(literal(Literal::usize_unsuffixed(k))),
    })
}

/// A literal.
pub fn literal(lit: Literal) -> syn::Expr {
    syn::Expr::Lit(syn::ExprLit { attrs: vec![], lit: syn::Lit::new(lit) })
}

/// A float literal written as `text` (`"1.0"`).
pub fn float(text: &str) -> syn::Expr {
    literal(text.parse().expect("a float literal"))
}

/// `f(args...)` for the function at `path`.
pub fn call(function: &[&str], args: Vec<syn::Expr>) -> syn::Expr {
    syn::Expr::Call(syn::ExprCall { attrs: vec![], func: Box::new(path(function)), paren_token: Default::default(), args: args.into_iter().collect() })
}

/// `left op right`.
pub fn binary(left: syn::Expr, op: syn::BinOp, right: syn::Expr) -> syn::Expr {
    syn::Expr::Binary(syn::ExprBinary { attrs: vec![], left: Box::new(left), op, right: Box::new(right) })
}

/// `(e)`.
pub fn paren(e: syn::Expr) -> syn::Expr {
    syn::Expr::Paren(syn::ExprParen { attrs: vec![], paren_token: Default::default(), expr: Box::new(e) })
}

/// `-` written before `e`'s text, as the parser reads it: unary minus binds tighter than any
/// binary operator, so it lands on the leftmost operand (`-a * b` is `(-a) * b`).
pub fn neg(e: syn::Expr) -> syn::Expr {
    match e {
        syn::Expr::Binary(mut b) => {
            let left = std::mem::replace(&mut *b.left, syn::Expr::Verbatim(Default::default()));
            *b.left = neg(left);
            syn::Expr::Binary(b)
        }
        other => syn::Expr::Unary(syn::ExprUnary { attrs: vec![], op: syn::UnOp::Neg(Default::default()), expr: Box::new(other) }),
    }
}

/// `let name = value;`
pub fn let_stmt(name: &str, value: syn::Expr) -> syn::Stmt {
    syn::Stmt::Local(syn::Local {
        attrs: vec![],
        let_token: Default::default(),
        modifiers: Default::default(),
        pat: syn::Pat::Ident(syn::PatIdent { attrs: vec![], by_ref: None, mutability: None, ident: Ident::new(name, Span::call_site()), subpat: None }),
        init: Some(syn::LocalInit { eq_token: Default::default(), expr: Box::new(value), diverge: None }),
        semi_token: Default::default(),
    })
}

/// `target = value;`
pub fn assign_stmt(target: syn::Expr, value: syn::Expr) -> syn::Stmt {
    let e = syn::Expr::Assign(syn::ExprAssign { attrs: vec![], left: Box::new(target), eq_token: Default::default(), right: Box::new(value) });
    syn::Stmt::Expr(e, Some(Default::default()))
}

/// An unsuffixed `usize` literal (an array length, an index).
pub fn usize_lit(n: usize) -> Literal {
    Literal::usize_unsuffixed(n)
}

/// A doc attribute. prettyplease prints it as `///` lines, so a line break in the text would end
/// the comment and let the rest through as code: every control character (model names and
/// descriptions come from the user) becomes a space.
pub fn doc(text: &str) -> TokenStream {
    let text: String = text.chars().map(|c| if c.is_control() { ' ' } else { c }).collect();
    quote!(#[doc = #text])
}

#[cfg(test)]
mod tests {
    use super::*;
    use quote::ToTokens;

    /// What syn parses from `text`, and the tree built, print the same.
    fn same(built: syn::Expr, text: &str) {
        let parsed: syn::Expr = syn::parse_str(text).unwrap();
        assert_eq!(built, parsed, "{text}");
        assert_eq!(built.to_token_stream().to_string(), parsed.to_token_stream().to_string());
    }

    #[test]
    fn trees_are_what_the_parser_reads() {
        let mul = || syn::BinOp::Mul(Default::default());
        let sub = || syn::BinOp::Sub(Default::default());
        same(neg(binary(ident("a"), mul(), ident("b"))), "-a * b");
        same(binary(binary(ident("a"), sub(), ident("b")), sub(), neg(ident("c"))), "a - b - -c");
        same(call(&["f64", "sin"], vec![index("v", 3)]), "f64::sin(v[3])");
        same(neg(float("2.5")), "-2.5");
        let s = let_stmt("x0", ident("y"));
        assert_eq!(s, syn::parse_str::<syn::Stmt>("let x0 = y;").unwrap());
        let s = assign_stmt(index("v", 0), ident("y"));
        assert_eq!(s, syn::parse_str::<syn::Stmt>("v[0] = y;").unwrap());
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::emit::syntax::{binary, ident, neg, paren};
        let (a, b) = (ident("a"), ident("b"));
        let e = neg(binary(a, syn::BinOp::Mul(Default::default()), paren(b)));
        assert_eq!(quote::ToTokens::to_token_stream(&e).to_string(), "- a * (b)");
    }
}

/// `values` (row-major) as `rows` array literals of `cols` entries each: `[[a, b], [c, d]]`'s
/// rows. Every row is written, empty ones too (`[f64; 0]` rows where `cols` is 0).
pub fn matrix_rows<T: quote::ToTokens>(values: &[T], rows: usize, cols: usize) -> Vec<TokenStream> {
    (0..rows)
        .map(|i| {
            let row = &values[i * cols..(i + 1) * cols];
            quote!([#(#row),*])
        })
        .collect()
}
