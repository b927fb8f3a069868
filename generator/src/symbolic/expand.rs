//! Expansion: products of sums multiplied out, positive integer powers of sums expanded.
//!
//! ```
//! use generator::symbolic::{Expr, Limits};
//! let (x, y) = (Expr::sym("x"), Expr::sym("y"));
//! let e = (x + y).powi(2);
//! assert_eq!(e.expand(Limits::default()).unwrap(), x * x + x * y * 2 + y * y);
//! ```

use super::expr::{Expr, Node};
use super::limits::{Budget, Limits, StopReason};
use super::number::Rat;

/// A sum as `(term, coefficient)` pairs; the constant is the term `1`.
type Terms = Vec<(Expr, Rat)>;

fn as_terms(e: Expr) -> Terms {
    match &*e.node() {
        Node::Add { constant, terms } => {
            let mut v = terms.clone();
            if !constant.is_zero() {
                v.push((Expr::one(), constant.clone()));
            }
            v
        }
        Node::Num(r) => vec![(Expr::one(), r.clone())],
        _ => {
            let (c, rest) = e.split_coefficient();
            vec![(rest, c)]
        }
    }
}

fn from_terms(t: Terms) -> Expr {
    Expr::make_add(Rat::zero(), t)
}

fn multiply(a: &Terms, b: &Terms, budget: &Budget) -> Result<Expr, StopReason> {
    budget.check(a.len() * b.len())?;
    let mut out = Vec::with_capacity(a.len() * b.len());
    for (ta, ca) in a {
        for (tb, cb) in b {
            out.push((*ta * *tb, ca * cb));
        }
    }
    let r = from_terms(out);
    Ok(r)
}

impl Expr {
    /// Expands products of sums (recursively, including inside function arguments).
    pub fn expand(self, limits: Limits) -> Result<Expr, StopReason> {
        let budget = Budget::start(limits, "expand");
        let mut memo = rustc_hash::FxHashMap::default();
        expand_rec(self, &budget, &mut memo)
    }
}

pub(crate) fn expand_rec(e: Expr, budget: &Budget, memo: &mut rustc_hash::FxHashMap<Expr, Expr>) -> Result<Expr, StopReason> {
    if let Some(&r) = memo.get(&e) {
        return Ok(r);
    }
    let r = match &*e.node() {
        Node::Num(_) | Node::Sym(_) => e,
        Node::Add { constant, terms } => {
            let mut out = Vec::with_capacity(terms.len());
            for (t, c) in terms {
                out.push((expand_rec(*t, budget, memo)?, c.clone()));
            }
            let r = Expr::make_add(constant.clone(), out);
            budget.check(term_count(r))?;
            r
        }
        Node::Mul { coefficient, factors } => {
            let mut acc: Terms = vec![(Expr::one(), coefficient.clone())];
            let mut opaque: Vec<(Expr, Rat)> = Vec::new();
            for (b, ex) in factors {
                let bx = expand_rec(*b, budget, memo)?;
                let is_sum = matches!(&*bx.node(), Node::Add { .. });
                if is_sum && ex.is_integer() && ex.is_positive() {
                    let n = ex.to_i64().and_then(|n| u32::try_from(n).ok()).unwrap_or(u32::MAX);
                    let bt = as_terms(bx);
                    for _ in 0..n {
                        acc = as_terms(multiply(&acc, &bt, budget)?);
                    }
                } else {
                    opaque.push((bx, ex.clone()));
                }
            }
            let rest = Expr::make_mul(Rat::one(), opaque);
            let r = multiply(&acc, &[(rest, Rat::one())].to_vec(), budget)?;
            budget.check(term_count(r))?;
            r
        }
        Node::Fun(f, a) => Expr::apply(*f, expand_rec(*a, budget, memo)?),
        Node::Apply(n, a) => Expr::apply_named(*n, expand_rec(*a, budget, memo)?),
    };
    memo.insert(e, r);
    Ok(r)
}

/// Number of top-level terms of a sum (1 for anything else).
pub fn term_count(e: Expr) -> usize {
    match &*e.node() {
        Node::Add { terms, .. } => terms.len() + 1,
        _ => 1,
    }
}
