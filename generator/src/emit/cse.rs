//! Common-subexpression elimination over all outputs of one function.
//!
//! The expression pool is hash-consed, so a common subexpression is simply a node reached
//! from more than one place. [`plan`] lists, in evaluation order, the nodes that get their own
//! `let`: those used at least twice, and the compound bases of small integer powers (so
//! `x^2` becomes `x * x`). The order comes from a depth-first walk in the outputs' order and
//! the canonical child order, so it never depends on how the expressions were built.

use crate::symbolic::{Expr, Node};
use rustc_hash::{FxHashMap as HashMap, FxHashSet};

fn is_leaf(e: Expr) -> bool {
    matches!(&*e.node(), Node::Num(_) | Node::Sym(_))
}

/// The subexpressions to bind, in an order where each comes after everything it uses.
#[cfg(test)]
pub fn plan(outputs: &[Expr]) -> Vec<Expr> {
    plan_with(outputs, &FxHashSet::default())
}

/// [`plan`], binding every node of `forced` too (the named intermediates of a recursion,
/// which later outputs read by name).
pub fn plan_with(outputs: &[Expr], forced: &FxHashSet<Expr>) -> Vec<Expr> {
    let order = post_order(outputs);
    let mut uses: HashMap<Expr, usize> = HashMap::default();
    let mut force = forced.clone();
    for e in outputs {
        *uses.entry(*e).or_default() += 1;
    }
    for &e in &order {
        for c in e.children() {
            *uses.entry(c).or_default() += 1;
        }
        if let Node::Mul { factors, .. } = &*e.node() {
            for (b, ex) in factors {
                let small = ex.is_integer() && ex.abs().to_i64().is_some_and(|n| n == 2 || n == 3);
                if small {
                    force.insert(*b);
                }
            }
        }
    }
    order.into_iter().filter(|e| !is_leaf(*e) && (uses[e] >= 2 || force.contains(e))).collect()
}

pub use crate::symbolic::expr::post_order;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn children_come_before_parents_and_squares_bind_their_base() {
        let (x, y) = (Expr::sym("x"), Expr::sym("y"));
        let base = x + y;
        let e = base.powi(2) + x.cos();
        let bound = plan(&[e]);
        assert_eq!(bound, vec![base]);
        let order = post_order(&[e]);
        let pos = |n: Expr| order.iter().position(|o| *o == n).unwrap();
        assert!(pos(base) < pos(base.powi(2)) && pos(base.powi(2)) < pos(e));
    }

    #[test]
    fn order_does_not_depend_on_construction_order() {
        let (a, b) = (Expr::sym("a"), Expr::sym("b"));
        let first = (a.sin() * b.cos() + b.cos() * a.sin().powi(3)).to_string();
        let e = b.cos() * a.sin().powi(3) + a.sin() * b.cos();
        assert_eq!(e.to_string(), first);
        let names: Vec<String> = plan(&[e]).iter().map(|n| n.to_string()).collect();
        assert_eq!(names, vec!["sin(a)", "cos(b)"]);
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::emit::cse::plan;
        use crate::symbolic::Expr;
        let (x, y) = (Expr::sym("x"), Expr::sym("y"));
        let s = x.sin();
        let bound = plan(&[s * y, s + y]);
        assert_eq!(bound, vec![s]);
    }
}
