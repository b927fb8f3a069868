//! Substitution of symbols by expressions.
//!
//! ```
//! use generator::symbolic::{Expr, Symbol};
//! use std::collections::HashMap;
//! let x = Symbol::new("x");
//! let map = HashMap::from([(x, Expr::int(2))]);
//! assert_eq!((x.expr() * x.expr() + 1).subs(&map), Expr::int(5));
//! ```

use super::expr::{Expr, Node, Symbol};
use std::collections::HashMap;

impl Expr {
    /// Replaces every symbol in `map` by its expression (simultaneously), re-canonicalizing.
    pub fn subs(self, map: &HashMap<Symbol, Expr>) -> Expr {
        let mask = map.keys().fold(0u128, |m, s| m | (1u128 << (s.id % 128)));
        let mut memo = rustc_hash::FxHashMap::default();
        subs_rec(self, map, mask, &mut memo)
    }

    /// Substitutes many expressions with one shared memo (shared subexpressions once).
    pub fn subs_all(items: &[Expr], map: &HashMap<Symbol, Expr>) -> Vec<Expr> {
        let mask = map.keys().fold(0u128, |m, s| m | (1u128 << (s.id % 128)));
        let mut memo = rustc_hash::FxHashMap::default();
        items.iter().map(|e| subs_rec(*e, map, mask, &mut memo)).collect()
    }
}

fn subs_rec(e: Expr, map: &HashMap<Symbol, Expr>, mask: u128, memo: &mut rustc_hash::FxHashMap<Expr, Expr>) -> Expr {
    if e.mask() & mask == 0 {
        return e;
    }
    if let Some(&r) = memo.get(&e) {
        return r;
    }
    let r = match &*e.node() {
        Node::Sym(s) => map.get(s).copied().unwrap_or(e),
        _ => e.map_children(|c| subs_rec(c, map, mask, memo)),
    };
    memo.insert(e, r);
    r
}
