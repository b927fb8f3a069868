//! Numeric evaluation of expressions.
//!
//! ```
//! use generator::symbolic::{Expr, Env, Symbol};
//! let x = Symbol::new("x");
//! let mut env = Env::default();
//! env.set(x, 0.5);
//! let v = (x.expr().sin().powi(2) + x.expr().cos().powi(2)).eval(&env).unwrap();
//! assert!((v - 1.0).abs() < 1e-15);
//! ```

use super::expr::{Expr, Node, Symbol};
use super::number::rat_to_f64;
use std::collections::HashMap;

/// Values of symbols and definitions of named functions for evaluation.
#[derive(Clone, Default, Debug)]
pub struct Env {
    values: HashMap<Symbol, f64>,
    functions: HashMap<Symbol, (Symbol, Expr)>,
}

/// Why an evaluation failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EvalError {
    /// A symbol had no value.
    #[error("no value for symbol `{0}`")]
    Unbound(String),
    /// A named function had no definition.
    #[error("no definition for function `{0}`")]
    UndefinedFunction(String),
}

impl Env {
    /// Sets a symbol's value.
    pub fn set(&mut self, s: Symbol, v: f64) {
        self.values.insert(s, v);
    }
    /// A symbol's value.
    pub fn get(&self, s: Symbol) -> Option<f64> {
        self.values.get(&s).copied()
    }
    /// Defines a named function `name(param) = body`.
    pub fn define(&mut self, name: Symbol, param: Symbol, body: Expr) {
        self.functions.insert(name, (param, body));
    }
}

impl Expr {
    /// Evaluates to a float; every symbol must have a value.
    pub fn eval(self, env: &Env) -> Result<f64, EvalError> {
        let mut memo = rustc_hash::FxHashMap::default();
        eval_rec(self, env, &mut memo)
    }

    /// Evaluates many expressions sharing one memo.
    pub fn eval_all(items: &[Expr], env: &Env) -> Result<Vec<f64>, EvalError> {
        let mut memo = rustc_hash::FxHashMap::default();
        items.iter().map(|e| eval_rec(*e, env, &mut memo)).collect()
    }
}

fn eval_rec(e: Expr, env: &Env, memo: &mut rustc_hash::FxHashMap<Expr, f64>) -> Result<f64, EvalError> {
    if let Some(&v) = memo.get(&e) {
        return Ok(v);
    }
    let v = match &*e.node() {
        Node::Num(r) => rat_to_f64(r),
        Node::Sym(s) => env.get(*s).ok_or_else(|| EvalError::Unbound(s.name()))?,
        Node::Add { constant, terms } => {
            let mut acc = rat_to_f64(constant);
            for (t, c) in terms {
                acc += rat_to_f64(c) * eval_rec(*t, env, memo)?;
            }
            acc
        }
        Node::Mul { coefficient, factors } => {
            let mut acc = rat_to_f64(coefficient);
            for (b, ex) in factors {
                let bv = eval_rec(*b, env, memo)?;
                acc *= pow_f64(bv, rat_to_f64(ex), ex.is_integer());
            }
            acc
        }
        Node::Fun(f, a) => f.apply(eval_rec(*a, env, memo)?),
        Node::Apply(name, a) => {
            let av = eval_rec(*a, env, memo)?;
            let (param, body) = env.functions.get(name).ok_or_else(|| EvalError::UndefinedFunction(name.name()))?;
            let mut inner = env.clone();
            inner.set(*param, av);
            body.eval(&inner)?
        }
    };
    memo.insert(e, v);
    Ok(v)
}

/// `b^e` with integer exponents done by `powi` (exact sign for negative bases).
pub fn pow_f64(b: f64, e: f64, integer: bool) -> f64 {
    if integer && e.abs() < 64.0 {
        b.powi(e as i32)
    } else if e == 0.5 {
        b.sqrt()
    } else {
        b.powf(e)
    }
}

/// An upper bound of `|e|` by the triangle inequality: sums become sums of magnitudes and
/// products products of magnitudes. A residual is negligible against it when it is a few
/// rounding errors of this size.
pub fn magnitude(e: Expr) -> Expr {
    magnitude_memo(e, &mut rustc_hash::FxHashMap::default())
}

/// [`magnitude`] over the DAG, each shared node once: walked as a tree, a long chain's
/// expressions (a node reached along every path through the shared ones above it) took
/// minutes, and built a node per path (a 20-joint floating chain's pivot checks).
fn magnitude_memo(e: Expr, memo: &mut rustc_hash::FxHashMap<Expr, Expr>) -> Expr {
    if let Some(m) = memo.get(&e) {
        return *m;
    }
    let m = match &*e.node() {
        Node::Num(r) => Expr::num(r.abs()),
        Node::Add { constant, terms } => {
            let mut out = Expr::num(constant.abs());
            for (t, c) in terms {
                out += magnitude_memo(*t, memo).scale(&c.abs());
            }
            out
        }
        Node::Mul { coefficient, factors } => {
            let mut out = Expr::num(coefficient.abs());
            for (b, ex) in factors {
                let positive_integer = ex.is_integer() && !ex.is_negative() && !ex.is_zero();
                out = out * if positive_integer { magnitude_memo(*b, memo).pow_rat(ex) } else { b.abs().pow_rat(ex) };
            }
            out
        }
        _ => e.abs(),
    };
    memo.insert(e, m);
    m
}

#[cfg(test)]
mod tests {
    use crate::symbolic::{Expr, eval::magnitude};

    /// A DAG whose every level holds the one below twice: walked as a tree, its magnitude
    /// would visit 2^60 paths (a long chain's pivots did so, for minutes); over the DAG, a node
    /// per node, and the same bound as the sum of its terms' bounds.
    #[test]
    fn the_magnitude_of_a_deep_dag_is_built_once_per_node() {
        let (x, y) = (Expr::sym("x"), Expr::sym("y"));
        let mut e = x;
        for _ in 0..60 {
            e = e * e * y - e;
        }
        let m = magnitude(e);
        assert!(m.dag_size() < 20 * 60, "{}", m.dag_size());
        let small = x * x * y - x;
        assert_eq!(magnitude(small), x.abs() * x.abs() * y.abs() + x.abs());
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn magnitude_bounds_a_sum() {
        use crate::symbolic::{Expr, eval::magnitude};
        let (a, b) = (Expr::sym("a"), Expr::sym("b"));
        assert_eq!(magnitude(a - b * 2), a.abs() + b.abs() * 2);
    }
}
