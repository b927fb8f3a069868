//! Memoized symbolic differentiation.
//!
//! ```
//! use generator::symbolic::{Expr, Symbol};
//! let x = Symbol::new("x");
//! let e = x.expr().sin() * x.expr();
//! assert_eq!(e.diff(x), x.expr().cos() * x.expr() + x.expr().sin());
//! ```

use super::expr::{Expr, Func, Node, Symbol, memo_diff_get, memo_diff_put};
use super::number::Rat;

impl Expr {
    /// The partial derivative with respect to `x`; memoized across calls.
    pub fn diff(self, x: Symbol) -> Expr {
        if !self.may_contain(x) {
            return Expr::zero();
        }
        if let Some(d) = memo_diff_get(self, x) {
            return d;
        }
        let d = match &*self.node() {
            Node::Num(_) => Expr::zero(),
            Node::Sym(s) => {
                if *s == x {
                    Expr::one()
                } else {
                    Expr::zero()
                }
            }
            Node::Add { terms, .. } => Expr::make_add(Rat::zero(), terms.iter().map(|(t, c)| (t.diff(x), c.clone())).collect()),
            Node::Mul { coefficient, factors } => {
                let mut terms = Vec::new();
                for (i, (b, e)) in factors.iter().enumerate() {
                    let db = b.diff(x);
                    if db.is_zero() {
                        continue;
                    }
                    let mut fs: Vec<(Expr, Rat)> =
                        factors.iter().enumerate().map(|(j, (bj, ej))| if j == i { (*bj, ej - Rat::one()) } else { (*bj, ej.clone()) }).collect();
                    fs.push((db, Rat::one()));
                    terms.push((Expr::make_mul(coefficient * e, fs), Rat::one()));
                }
                Expr::make_add(Rat::zero(), terms)
            }
            Node::Fun(f, a) => {
                let da = a.diff(x);
                let outer = match f {
                    Func::Sin => a.cos(),
                    Func::Cos => -a.sin(),
                    Func::Tan => a.tan().powi(2) + 1,
                    Func::Exp => self,
                    Func::Ln => a.recip(),
                    Func::Abs => *a / self,
                };
                outer * da
            }
            Node::Apply(name, a) => {
                let da = a.diff(x);
                let derived = Symbol::new(&format!("{}'", name.name()));
                Expr::apply_named(derived, *a) * da
            }
        };
        memo_diff_put(self, x, d);
        d
    }

    /// Total time derivative: `∂e/∂t + Σ ∂e/∂x_i · dx_i` over the `(x_i, dx_i)` pairs given
    /// (coordinates with their velocities, velocities with their accelerations).
    pub fn time_derivative(self, t: Symbol, chain: &[(Symbol, Expr)]) -> Expr {
        let mut terms = vec![self.diff(t)];
        for (s, ds) in chain {
            let d = self.diff(*s);
            if !d.is_zero() {
                terms.push(d * *ds);
            }
        }
        Expr::sum(terms)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chain_and_product_rules() {
        let x = Symbol::new("x");
        let y = Symbol::new("y");
        let (xe, ye) = (x.expr(), y.expr());
        assert_eq!((xe * ye).diff(x), ye);
        assert_eq!(xe.powi(3).diff(x), xe.powi(2) * 3);
        assert_eq!((xe * 2).cos().diff(x), -((xe * 2).sin()) * 2);
        assert_eq!(ye.exp().diff(x), Expr::zero());
        assert_eq!(xe.ln().diff(x), xe.recip());
    }

    #[test]
    fn named_functions_get_a_derived_name() {
        let t = Symbol::new("t");
        let f = Expr::apply_named(Symbol::new("F"), t.expr());
        let d = f.diff(t);
        assert_eq!(d, Expr::apply_named(Symbol::new("F'"), t.expr()));
    }
}

/// Memoized total time derivative in one pass over the DAG (forward mode):
/// `d/dt e = ∂e/∂t + Σ ∂e/∂x_i · rate_i` for the `(x_i, rate_i)` pairs given. The cost is
/// linear in the number of distinct nodes, where summing partial derivatives costs one pass
/// per symbol.
#[derive(Clone, Debug)]
pub struct TimeDerivative {
    t: Symbol,
    rates: rustc_hash::FxHashMap<Symbol, Expr>,
    mask: u128,
    memo: rustc_hash::FxHashMap<Expr, Expr>,
}

impl TimeDerivative {
    /// The derivative along `pairs` (symbols absent from them are constants), time `t`.
    pub fn new(t: Symbol, pairs: &[(Symbol, Expr)]) -> TimeDerivative {
        let rates: rustc_hash::FxHashMap<Symbol, Expr> = pairs.iter().copied().collect();
        let mask = pairs.iter().fold(1u128 << (t.id % 128), |m, (s, _)| m | (1u128 << (s.id % 128)));
        TimeDerivative { t, rates, mask, memo: rustc_hash::FxHashMap::default() }
    }

    /// `d/dt e`.
    pub fn dt(&mut self, e: Expr) -> Expr {
        if e.mask() & self.mask == 0 {
            return Expr::zero();
        }
        if let Some(&d) = self.memo.get(&e) {
            return d;
        }
        for node in e.post_order_nodes() {
            if self.memo.contains_key(&node) {
                continue;
            }
            let d = if node.mask() & self.mask == 0 { Expr::zero() } else { self.rule(node) };
            self.memo.insert(node, d);
        }
        self.memo[&e]
    }

    fn of(&self, e: Expr) -> Expr {
        if e.mask() & self.mask == 0 { Expr::zero() } else { self.memo[&e] }
    }

    fn rule(&self, e: Expr) -> Expr {
        match &*e.node() {
            Node::Num(_) => Expr::zero(),
            Node::Sym(s) if *s == self.t => Expr::one(),
            Node::Sym(s) => self.rates.get(s).copied().unwrap_or_else(Expr::zero),
            Node::Add { terms, .. } => Expr::make_add(Rat::zero(), terms.iter().map(|(t, c)| (self.of(*t), c.clone())).collect()),
            Node::Mul { coefficient, factors } => {
                let mut terms = Vec::new();
                for (i, (b, x)) in factors.iter().enumerate() {
                    let db = self.of(*b);
                    if db.is_zero() {
                        continue;
                    }
                    let mut fs: Vec<(Expr, Rat)> =
                        factors.iter().enumerate().map(|(j, (bj, xj))| if j == i { (*bj, xj - Rat::one()) } else { (*bj, xj.clone()) }).collect();
                    fs.push((db, Rat::one()));
                    terms.push((Expr::make_mul(coefficient * x, fs), Rat::one()));
                }
                Expr::make_add(Rat::zero(), terms)
            }
            Node::Fun(f, a) => {
                let da = self.of(*a);
                let outer = match f {
                    Func::Sin => a.cos(),
                    Func::Cos => -a.sin(),
                    Func::Tan => a.tan().powi(2) + 1,
                    Func::Exp => e,
                    Func::Ln => a.recip(),
                    Func::Abs => *a / e,
                };
                outer * da
            }
            Node::Apply(name, a) => {
                let derived = Symbol::new(&format!("{}'", name.name()));
                Expr::apply_named(derived, *a) * self.of(*a)
            }
        }
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn time_derivative() {
        use crate::symbolic::{Expr, Symbol, diff::TimeDerivative};
        let (t, q) = (Symbol::new("t"), Symbol::new("q"));
        let mut d = TimeDerivative::new(t, &[(q, Expr::sym("q'"))]);
        let e = q.expr().sin() * t.expr();
        assert_eq!(d.dt(e), q.expr().cos() * Expr::sym("q'") * t.expr() + q.expr().sin());
    }
}
