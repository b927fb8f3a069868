//! Common-subexpression elimination over all outputs of one function.
//!
//! The expression pool is hash-consed, so a common subexpression is simply a node reached
//! from more than one place. [`plan`] lists, in evaluation order, the nodes that get their own
//! `let`: those used at least twice, and the compound bases of small integer powers (so
//! `x^2` becomes `x * x`). The order comes from a depth-first walk in the outputs' order and
//! the canonical child order, so it never depends on how the expressions were built.
//!
//! A root or fractional power inside a product (`a * sqrt(b)`, `c / sqrt(b)`) is a factor of
//! that product, not a node of its own: the plan counts it as the node `b^(1/2)` (its
//! [`root_of`]), so that a root read by many products is computed once (the bicycle's Kane
//! form reads its contact geometry's few roots in most of its products: docs/bicycle.md).

use crate::symbolic::number::Rat;
use crate::symbolic::{Expr, Node};
use rustc_hash::{FxHashMap as HashMap, FxHashSet};

/// The power `b^|e|` a product's factor `(b, e)` with a fractional exponent stands for, as a
/// node of its own; `None` for an integer exponent, or where the product is that power itself.
pub(super) fn root_of(product: Expr, base: Expr, exponent: &Rat) -> Option<Expr> {
    if exponent.is_integer() {
        return None;
    }
    let root = Expr::make_mul(Rat::one(), vec![(base, exponent.abs())]);
    (root != product).then_some(root)
}

/// The roots a node's factors stand for ([`root_of`]), with their bases.
fn roots(e: Expr) -> Vec<(Expr, Expr)> {
    match &*e.node() {
        Node::Mul { factors, .. } => factors.iter().filter_map(|(b, ex)| root_of(e, *b, ex).map(|r| (*b, r))).collect(),
        _ => Vec::new(),
    }
}

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
    let mut uses: HashMap<Expr, usize> = HashMap::default();
    let mut force = forced.clone();
    for e in outputs {
        *uses.entry(*e).or_default() += 1;
    }
    // The post-order, each root placed just before the first product that reads it (after its
    // base, which that product's children precede).
    let mut order = Vec::new();
    let mut placed: FxHashSet<Expr> = FxHashSet::default();
    // `roots` are `e`'s ([`roots`]), found once by the caller: a root has none of its own.
    let mut place = |e: Expr, roots: &[(Expr, Expr)], order: &mut Vec<Expr>, uses: &mut HashMap<Expr, usize>| {
        if !placed.insert(e) {
            return;
        }
        order.push(e);
        for c in e.children() {
            // A base read through its root is counted once, as the root's child.
            if !roots.iter().any(|(b, _)| *b == c) {
                *uses.entry(c).or_default() += 1;
            }
        }
        for (_, r) in roots {
            *uses.entry(*r).or_default() += 1;
        }
        if let Node::Mul { factors, .. } = &*e.node() {
            for (b, ex) in factors {
                let small = ex.is_integer() && ex.abs().to_i64().is_some_and(|n| n == 2 || n == 3);
                if small {
                    force.insert(*b);
                }
            }
        }
    };
    for e in post_order(outputs) {
        let roots = roots(e);
        for (_, r) in &roots {
            place(*r, &[], &mut order, &mut uses);
        }
        place(e, &roots, &mut order, &mut uses);
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

    /// A square root and a fractional power, each read by two products (one dividing by it):
    /// each is bound once, before its first reader, and its base (read by the root only) is not;
    /// a root read once stays inline.
    #[test]
    fn a_root_read_by_several_products_is_bound_once() {
        let (x, y, a, c) = (Expr::sym("x"), Expr::sym("y"), Expr::sym("a"), Expr::sym("c"));
        let b = x + y;
        let root = b.sqrt();
        let power = (x - y).pow_rat(&Rat::frac(3, 2));
        let once = (x * y + 1).sqrt();
        let outputs = [a * root, c / root, a * power, c * power, a * once];
        let bound = plan(&outputs);
        assert_eq!(bound, vec![root, power], "{bound:?}");
        let order = post_order(&outputs);
        assert!(!order.contains(&root) && !order.contains(&power), "the roots are factors of the products, not nodes of the outputs");
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
