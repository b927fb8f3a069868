//! Prebuilt syntax trees placed into a module skeleton.
//!
//! The skeleton (signatures, docs, the fixed logic around the computed values) is written with
//! `quote!` and parsed; the large computed parts (a body's `let`s, its output expressions, its
//! helper functions) are built as trees by [`super::lower`] and [`super::function`]. Each
//! stands in the skeleton as a placeholder macro `__splice!(k)` that [`Splices::apply`]
//! replaces after parsing, so syn never parses what the generator built itself.

use proc_macro2::{Literal, TokenStream};
use quote::quote;
use syn::visit_mut::VisitMut;

const MACRO: &str = "__splice";

/// The trees waiting for their place, by placeholder number.
#[derive(Default)]
pub struct Splices {
    parts: Vec<Option<Part>>,
}

enum Part {
    Stmts(Vec<syn::Stmt>),
    Expr(syn::Expr),
    Items(Vec<syn::Item>),
}

/// A placeholder left in the tree (a splice put where its kind does not fit), or one never used.
#[derive(Debug, thiserror::Error)]
#[error("internal: splice {0} was not placed")]
pub struct Unplaced(pub usize);

impl Splices {
    fn push(&mut self, part: Part) -> TokenStream {
        let k = Literal::usize_unsuffixed(self.parts.len());
        self.parts.push(Some(part));
        let name = proc_macro2::Ident::new(MACRO, proc_macro2::Span::call_site());
        quote!(#name!(#k))
    }

    /// A placeholder, in statement position, for `stmts`.
    pub fn stmts(&mut self, stmts: Vec<syn::Stmt>) -> TokenStream {
        let mac = self.push(Part::Stmts(stmts));
        quote!(#mac;)
    }

    /// A placeholder, in expression position, for `e`.
    pub fn expr(&mut self, e: syn::Expr) -> TokenStream {
        self.push(Part::Expr(e))
    }

    /// A placeholder, in item position, for `items`.
    pub fn items(&mut self, items: Vec<syn::Item>) -> TokenStream {
        let mac = self.push(Part::Items(items));
        quote!(#mac;)
    }

    /// Replaces every placeholder in `file` by its tree.
    pub fn apply(mut self, file: &mut syn::File) -> Result<(), Unplaced> {
        let mut v = Visitor { parts: &mut self.parts };
        v.visit_file_mut(file);
        match self.parts.iter().position(Option::is_some) {
            Some(k) => Err(Unplaced(k)),
            None => Ok(()),
        }
    }
}

struct Visitor<'a> {
    parts: &'a mut Vec<Option<Part>>,
}

/// The placeholder number of `mac`, if it is one.
fn number(mac: &syn::Macro) -> Option<usize> {
    if !mac.path.is_ident(MACRO) {
        return None;
    }
    mac.tokens.to_string().parse().ok()
}

impl Visitor<'_> {
    fn take(&mut self, mac: &syn::Macro) -> Option<Part> {
        number(mac).and_then(|k| self.parts.get_mut(k)).and_then(Option::take)
    }

    fn items(&mut self, items: &mut Vec<syn::Item>) {
        let old = std::mem::take(items);
        for item in old {
            if let syn::Item::Macro(m) = &item {
                match self.take(&m.mac) {
                    Some(Part::Items(v)) => {
                        items.extend(v);
                        continue;
                    }
                    Some(other) => self.put_back(&m.mac, other),
                    None => {}
                }
            }
            items.push(item);
        }
    }

    fn put_back(&mut self, mac: &syn::Macro, part: Part) {
        if let Some(k) = number(mac) {
            self.parts[k] = Some(part);
        }
    }
}

impl VisitMut for Visitor<'_> {
    fn visit_file_mut(&mut self, f: &mut syn::File) {
        self.items(&mut f.items);
        syn::visit_mut::visit_file_mut(self, f);
    }

    fn visit_item_mod_mut(&mut self, m: &mut syn::ItemMod) {
        if let Some((_, items)) = &mut m.content {
            self.items(items);
        }
        syn::visit_mut::visit_item_mod_mut(self, m);
    }

    fn visit_block_mut(&mut self, b: &mut syn::Block) {
        let old = std::mem::take(&mut b.stmts);
        for stmt in old {
            if let syn::Stmt::Macro(m) = &stmt {
                match self.take(&m.mac) {
                    Some(Part::Stmts(v)) => {
                        b.stmts.extend(v);
                        continue;
                    }
                    Some(other) => self.put_back(&m.mac, other),
                    None => {}
                }
            }
            b.stmts.push(stmt);
        }
        syn::visit_mut::visit_block_mut(self, b);
    }

    fn visit_expr_mut(&mut self, e: &mut syn::Expr) {
        if let syn::Expr::Macro(m) = e {
            match self.take(&m.mac) {
                Some(Part::Expr(tree)) => {
                    *e = tree;
                    return;
                }
                Some(other) => {
                    let mac = m.mac.clone();
                    self.put_back(&mac, other);
                }
                None => {}
            }
        }
        syn::visit_mut::visit_expr_mut(self, e);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emit::syntax::{ident, let_stmt};

    #[test]
    fn items_and_nested_expressions_are_placed() {
        let mut s = Splices::default();
        let helper: syn::Item = syn::parse_quote!(
            fn helper() {}
        );
        let items = s.items(vec![helper]);
        let e = s.expr(ident("a"));
        let st = s.stmts(vec![let_stmt("a", ident("b")), let_stmt("c", ident("a"))]);
        let mut file: syn::File = syn::parse2(quote!(mod m { #items fn f(b: f64) -> [f64; 1] { #st [f64::sin(#e)] } })).unwrap();
        s.apply(&mut file).unwrap();
        let text = prettyplease::unparse(&file);
        assert!(text.contains("fn helper() {}"), "{text}");
        assert!(text.contains("let c = a;\n        [f64::sin(a)]"), "{text}");
        assert!(!text.contains(MACRO), "{text}");
    }

    #[test]
    fn an_unplaced_splice_is_an_error() {
        let mut s = Splices::default();
        let _forgotten = s.expr(ident("a"));
        let e = s.expr(ident("b"));
        let mut file: syn::File = syn::parse2(quote!(fn f(b: f64) -> f64 { #e })).unwrap();
        assert_eq!(s.apply(&mut file).unwrap_err().0, 0);
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::emit::splice::Splices;
        use crate::emit::syntax::{ident, let_stmt};
        let mut s = Splices::default();
        let stmts = s.stmts(vec![let_stmt("x", ident("y"))]);
        let value = s.expr(ident("x"));
        let mut file: syn::File = syn::parse2(quote::quote!(fn f(y: f64) -> f64 { #stmts #value })).unwrap();
        s.apply(&mut file).unwrap();
        assert_eq!(prettyplease::unparse(&file), "fn f(y: f64) -> f64 {\n    let x = y;\n    x\n}\n");
    }
}
