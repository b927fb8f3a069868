//! Rewrites that make emitted code cheaper without changing its value (beyond rounding):
//!
//! - [`factor_sums`]: multivariate Horner form. In a sum, the factor shared by the most
//!   terms is pulled out, recursively: `a*x*y + b*x*y + x` becomes `x*(y*(a + b) + 1)`. The
//!   pieces it creates are hash-consed like everything else, so a factor sum such as
//!   `M + m1 + m2` found in several places is computed once.
//! - [`share_reciprocals`]: a denominator used by two or more products is inverted once,
//!   `1/d`, and multiplied in (one division instead of many).
//! - [`expand_angle_sums`]: `cos(theta1 - theta2)` becomes
//!   `cos(theta1) cos(theta2) + sin(theta1) sin(theta2)` when the sines and cosines of the single
//!   angles are computed anyway: two products instead of a call.

use super::cse::post_order;
use crate::symbolic::number::Rat;
use crate::symbolic::{Expr, Func, Node, Symbol};
use rustc_hash::{FxHashMap as HashMap, FxHashSet};

/// The named function that emission lowers as `1.0 / x`.
pub fn reciprocal_symbol() -> Symbol {
    Symbol::new("1/")
}

/// A term of a sum as coefficient times factors.
type Term = (Rat, Vec<(Expr, Rat)>);

fn as_term(e: Expr, c: &Rat) -> Term {
    match &*e.node() {
        Node::Mul { coefficient, factors } => (coefficient * c, factors.clone()),
        _ => (c.clone(), vec![(e, Rat::one())]),
    }
}

fn from_term(t: &Term) -> Expr {
    Expr::make_mul(t.0.clone(), t.1.clone())
}

/// Most tied factors [`horner`] compares by how many factors their terms share.
const HORNER_CANDIDATES: usize = 8;

/// Horner form of a sum of terms (constant kept apart).
fn horner(constant: Rat, terms: Vec<Term>) -> Expr {
    // Count, for each (base, sign of exponent), the terms holding it with an integer exponent.
    let mut count: HashMap<(Expr, bool), usize> = HashMap::default();
    for (_, factors) in &terms {
        for (b, e) in factors {
            if e.is_integer() && !e.is_zero() {
                *count.entry((*b, e.is_negative())).or_default() += 1;
            }
        }
    }
    // The factor held by the most terms; among ties (and near-ties), the one whose terms share
    // the most factors besides it, so that they come out together: x l m1 u^2 + x l m2 u^2
    // + y m2 becomes x l u^2 (m1 + m2) + y m2, not m2 (x l u^2 + y) + x l m1 u^2.
    let mut ranked: Vec<((Expr, bool), usize)> = count.iter().filter(|(_, n)| **n >= 2).map(|(k, n)| (*k, *n)).collect();
    ranked.sort_by(|(ka, na), (kb, nb)| nb.cmp(na).then_with(|| ka.0.key().cmp(&kb.0.key())).then_with(|| ka.1.cmp(&kb.1)));
    let top = ranked.first().map_or(0, |(_, n)| *n);
    let shared_with = |base: Expr, negative: bool| -> usize {
        let mut common: Option<HashMap<(Expr, bool), i64>> = None;
        for (_, factors) in &terms {
            if !factors.iter().any(|(b, e)| *b == base && e.is_integer() && e.is_negative() == negative && !e.is_zero()) {
                continue;
            }
            let here: HashMap<(Expr, bool), i64> = factors.iter().filter_map(|(b, e)| e.to_i64().filter(|n| *n != 0).map(|n| ((*b, n < 0), n.abs()))).collect();
            common = Some(match common {
                None => here,
                Some(c) => c.into_iter().filter_map(|(k, n)| here.get(&k).map(|m| (k, n.min(*m)))).collect(),
            });
        }
        common.map_or(0, |c| c.values().map(|n| *n as usize).sum())
    };
    let best = ranked
        .iter()
        .take_while(|(_, n)| *n == top)
        .take(HORNER_CANDIDATES)
        .map(|(k, _)| (*k, shared_with(k.0, k.1)))
        .fold(None::<((Expr, bool), usize)>, |acc, (k, score)| match acc {
            Some((_, best)) if best >= score => acc,
            _ => Some((k, score)),
        })
        .map(|(k, _)| k);
    let Some((base, negative)) = best else {
        return Expr::make_add(constant, terms.iter().map(|t| (from_term(t), Rat::one())).collect());
    };
    let step = if negative { -Rat::one() } else { Rat::one() };
    let mut with = Vec::new();
    let mut without = Vec::new();
    for (c, factors) in terms {
        let hit = factors.iter().any(|(b, e)| *b == base && e.is_integer() && e.is_negative() == negative && !e.is_zero());
        if hit {
            let reduced: Vec<(Expr, Rat)> = factors
                .into_iter()
                .filter_map(|(b, e)| {
                    if b == base {
                        let r = e - &step;
                        (!r.is_zero()).then_some((b, r))
                    } else {
                        Some((b, e))
                    }
                })
                .collect();
            with.push((c, reduced));
        } else {
            without.push((c, factors));
        }
    }
    let inner = horner(Rat::zero(), with);
    let pulled = Expr::make_mul(Rat::one(), vec![(base, step), (inner, Rat::one())]);
    let rest = horner(constant, without);
    rest + pulled
}

/// Horner-factors every sum in `outputs` (bottom-up, shared across outputs).
#[cfg(test)]
pub fn factor_sums(outputs: &[Expr]) -> Vec<Expr> {
    factor_sums_with(outputs, &mut HashMap::default())
}

/// [`factor_sums`] with a memo kept by the caller: the Horner form of a node does not depend on
/// where it occurs, so the functions of one module share it.
pub fn factor_sums_with(outputs: &[Expr], memo: &mut HashMap<Expr, Expr>) -> Vec<Expr> {
    for e in post_order(outputs) {
        if memo.contains_key(&e) {
            continue;
        }
        let rebuilt = e.map_children(|c| memo[&c]);
        let r = match &*rebuilt.node() {
            Node::Add { constant, terms } if terms.len() >= 2 => horner(constant.clone(), terms.iter().map(|(t, c)| as_term(*t, c)).collect()),
            _ => rebuilt,
        };
        memo.insert(e, r);
    }
    outputs.iter().map(|e| memo[e]).collect()
}

/// Replaces denominators used by two or more products with a shared reciprocal.
pub fn share_reciprocals(outputs: &[Expr]) -> Vec<Expr> {
    let order = post_order(outputs);
    let mut uses: HashMap<Expr, usize> = HashMap::default();
    for e in &order {
        if let Node::Mul { factors, .. } = &*e.node() {
            for (b, ex) in factors {
                if ex.is_negative() && ex.is_integer() {
                    *uses.entry(*b).or_default() += 1;
                }
            }
        }
    }
    let recip = reciprocal_symbol();
    let mut memo: HashMap<Expr, Expr> = HashMap::default();
    for e in order {
        let r = match &*e.node() {
            Node::Mul { coefficient, factors } => {
                let f = factors
                    .iter()
                    .map(|(b, ex)| {
                        let nb = memo[b];
                        if ex.is_negative() && ex.is_integer() && uses[b] >= 2 { (Expr::apply_named(recip, nb), -ex) } else { (nb, ex.clone()) }
                    })
                    .collect();
                Expr::make_mul(coefficient.clone(), f)
            }
            _ => e.map_children(|c| memo[&c]),
        };
        memo.insert(e, r);
    }
    outputs.iter().map(|e| memo[e]).collect()
}

/// Rewrites sin/cos of sums of angles `±x ± y ...` into products of the sines and cosines
/// of the single angles, for angles whose sine and cosine both occur in `outputs`.
pub fn expand_angle_sums(outputs: &[Expr]) -> Vec<Expr> {
    let order = post_order(outputs);
    let mut sines = FxHashSet::default();
    let mut cosines = FxHashSet::default();
    for e in &order {
        match &*e.node() {
            Node::Fun(Func::Sin, a) => {
                sines.insert(*a);
            }
            Node::Fun(Func::Cos, a) => {
                cosines.insert(*a);
            }
            _ => {}
        }
    }
    let expandable = |a: Expr| -> Option<Vec<(Expr, bool)>> {
        match &*a.node() {
            Node::Add { constant, terms } if constant.is_zero() && terms.len() >= 2 => terms
                .iter()
                .map(|(x, c)| {
                    let unit = c.is_one() || (-c).is_one();
                    (unit && sines.contains(x) && cosines.contains(x)).then_some((*x, c.is_negative()))
                })
                .collect(),
            _ => None,
        }
    };
    let mut memo: HashMap<Expr, Expr> = HashMap::default();
    for e in order {
        let r = match &*e.node() {
            Node::Fun(f @ (Func::Sin | Func::Cos), a) => match expandable(*a) {
                Some(angles) => {
                    let (s, c) = sin_cos_of_sum(&angles);
                    if *f == Func::Sin { s } else { c }
                }
                None => e.map_children(|c| memo[&c]),
            },
            _ => e.map_children(|c| memo[&c]),
        };
        memo.insert(e, r);
    }
    outputs.iter().map(|e| memo[e]).collect()
}

/// `(sin, cos)` of `sum(±x_i)` by the angle-sum formulas.
fn sin_cos_of_sum(angles: &[(Expr, bool)]) -> (Expr, Expr) {
    let (x, negative) = angles[0];
    let (sx, cx) = (if negative { -x.sin() } else { x.sin() }, x.cos());
    if angles.len() == 1 {
        return (sx, cx);
    }
    let (sr, cr) = sin_cos_of_sum(&angles[1..]);
    (sx * cr + cx * sr, cx * cr - sx * sr)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::symbolic::eval::Env;

    #[test]
    fn rewrites_keep_the_value() {
        let (a, b, x, y) = (Expr::sym("a"), Expr::sym("b"), Expr::sym("x"), Expr::sym("y"));
        let e = (a * x * y + b * x * y + x * 3 - y.powi(2) * a) / (x + y) + b / (x + y) + 2;
        let mut env = Env::default();
        for (s, v) in [("a", 0.3), ("b", -1.7), ("x", 2.5), ("y", 0.9)] {
            env.set(Symbol::new(s), v);
        }
        env.define(reciprocal_symbol(), Symbol::internal("arg"), Symbol::internal("arg").expr().recip());
        let want = e.eval(&env).unwrap();
        let f = factor_sums(&[e]);
        let g = share_reciprocals(&f);
        let (sa, ca) = (a.sin(), a.cos());
        let h = expand_angle_sums(&[(a - b).cos() + (a + b - x).sin() * sa * ca * b.sin() * b.cos() * x.sin() * x.cos()])[0];
        assert!(!h.to_string().contains("a - b") && !h.to_string().contains("a + b"), "{h}");
        let want_h = ((a - b).cos() + (a + b - x).sin() * sa * ca * b.sin() * b.cos() * x.sin() * x.cos()).eval(&env).unwrap();
        assert!((h.eval(&env).unwrap() - want_h).abs() < 1e-14);
        for out in [f[0], g[0]] {
            assert!((out.eval(&env).unwrap() - want).abs() < 1e-12 * want.abs());
        }
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::emit::optimize::factor_sums;
        use crate::symbolic::Expr;
        let (a, b, x, y) = (Expr::sym("a"), Expr::sym("b"), Expr::sym("x"), Expr::sym("y"));
        let e = a * x * y + b * x * y + x;
        assert_eq!(factor_sums(&[e])[0], x * (y * (a + b) + 1));
    }
}
