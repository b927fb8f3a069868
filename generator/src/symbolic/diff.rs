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
            Node::Add { terms, .. } => {
                Expr::make_add(Rat::zero(), terms.iter().map(|(t, c)| (t.diff(x), c.clone())).collect())
            }
            Node::Mul { coefficient, factors } => {
                let mut terms = Vec::new();
                for (i, (b, e)) in factors.iter().enumerate() {
                    let db = b.diff(x);
                    if db.is_zero() {
                        continue;
                    }
                    let mut fs: Vec<(Expr, Rat)> = factors
                        .iter()
                        .enumerate()
                        .map(|(j, (bj, ej))| if j == i { (*bj, ej - Rat::one()) } else { (*bj, ej.clone()) })
                        .collect();
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
