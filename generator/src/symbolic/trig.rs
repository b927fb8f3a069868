//! The polynomial trigonometric normal form: an expression as a polynomial in `sin(x)`,
//! `cos(x)` of atomic angles and in other atoms. Angle sums and integer multiples are expanded,
//! tangents become `sin/cos`, everything is multiplied out, and `sin(x)^k` with `k >= 2` is
//! replaced by `sin(x)^(k mod 2) (1 - cos(x)^2)^(k/2)`.
//!
//! Expanding angle sums is exponential in the number of angles, so this form is only for
//! small expressions, under a term budget: the symbolic solver uses it because single-angle
//! factors stay visible in it (`cos(theta)` divides every term of a row, and denominators
//! `cos(theta)^-1` merge with numerators), which is what cancels spurious pivots. Everything
//! else uses the Fourier form of [`super::fourier`], which never expands, and the exact zero
//! test of [`super::zero`].
//!
//! ```
//! use generator::symbolic::{Expr, Limits};
//! let (a, b) = (Expr::sym("a"), Expr::sym("b"));
//! let e = (a - b).cos() - a.cos() * b.cos() - a.sin() * b.sin();
//! assert!(e.trig_normal(Limits::default()).unwrap().is_zero());
//! ```

use super::expand::expand_rec;
use super::expr::{Expr, Func, Node};
use super::limits::{Budget, Limits, StopReason};
use super::number::{Rat, rat_from_i64};
use rustc_hash::FxHashMap;

impl Expr {
    /// The trigonometric normal form (see the module docs), under `limits`.
    pub fn trig_normal(self, limits: Limits) -> Result<Expr, StopReason> {
        let budget = Budget::start(limits, "trigonometric normal form");
        let mut cx = Normalizer { budget, memo: Default::default(), expand_memo: Default::default() };
        cx.normal(self)
    }
}

struct Normalizer {
    budget: Budget,
    memo: rustc_hash::FxHashMap<Expr, Expr>,
    expand_memo: rustc_hash::FxHashMap<Expr, Expr>,
}

impl Normalizer {
    fn normal(&mut self, e: Expr) -> Result<Expr, StopReason> {
        if let Some(&r) = self.memo.get(&e) {
            return Ok(r);
        }
        let rewritten = self.rewrite(e)?;
        let expanded = expand_rec(rewritten, &self.budget, &mut self.expand_memo)?;
        let reduced = self.reduce_sin_powers(expanded)?;
        self.memo.insert(e, reduced);
        Ok(reduced)
    }

    /// Rewrites trig functions of sums and multiples into products of trig functions of atoms;
    /// normalizes function arguments and bases of non-polynomial powers recursively.
    fn rewrite(&mut self, e: Expr) -> Result<Expr, StopReason> {
        self.budget.check(0)?;
        Ok(match &*e.node() {
            Node::Num(_) | Node::Sym(_) => e,
            Node::Add { constant, terms } => {
                let mut out = Vec::with_capacity(terms.len());
                for (t, c) in terms {
                    out.push((self.rewrite(*t)?, c.clone()));
                }
                Expr::make_add(constant.clone(), out)
            }
            Node::Mul { coefficient, factors } => {
                let mut out = Vec::with_capacity(factors.len());
                for (b, x) in factors {
                    let nb = if x.is_integer() && x.is_positive() { self.rewrite(*b)? } else { self.normal(*b)? };
                    out.push((nb, x.clone()));
                }
                Expr::make_mul(coefficient.clone(), out)
            }
            Node::Fun(f @ (Func::Sin | Func::Cos | Func::Tan), a) => {
                let arg = self.normal(*a)?;
                let (s, c) = self.sin_cos(arg)?;
                match f {
                    Func::Sin => s,
                    Func::Cos => c,
                    _ => s / c,
                }
            }
            Node::Fun(f, a) => Expr::apply(*f, self.normal(*a)?),
            Node::Apply(n, a) => Expr::apply_named(*n, self.normal(*a)?),
        })
    }

    /// `(sin(arg), cos(arg))` expanded over the terms of a normalized argument.
    fn sin_cos(&mut self, arg: Expr) -> Result<(Expr, Expr), StopReason> {
        self.budget.check(0)?;
        if let Node::Add { constant, terms } = &*arg.node() {
            let mut parts: Vec<Expr> = terms.iter().map(|(t, c)| t.scale(c)).collect();
            if !constant.is_zero() {
                parts.push(Expr::num(constant.clone()));
            }
            let first = parts[0];
            let rest = Expr::sum(parts[1..].iter().copied());
            let (s1, c1) = self.sin_cos(first)?;
            let (s2, c2) = self.sin_cos(rest)?;
            return Ok((s1 * c2 + c1 * s2, c1 * c2 - s1 * s2));
        }
        let (k, atom) = arg.split_coefficient();
        if atom.is_one() || k.is_one() || k.is_zero() {
            return Ok((arg.sin(), arg.cos()));
        }
        // k = p/q: angle = p * (atom/q), expanded as a multiple of the atomic angle atom/q.
        let q = Rat::from_big(num_rational::BigRational::from_integer(k.denom()));
        let p = k.numer().to_string().parse::<i64>().unwrap_or(1);
        let base = atom.scale(&q.recip());
        let (sb, cb) = (base.sin(), base.cos());
        let n = p.unsigned_abs();
        if n > 64 {
            return Ok((arg.sin(), arg.cos()));
        }
        let (mut s, mut c) = (sb, cb);
        for _ in 1..n {
            let ns = s * cb + c * sb;
            let nc = c * cb - s * sb;
            s = ns;
            c = nc;
        }
        if p < 0 {
            s = -s;
        }
        Ok((s, c))
    }

    /// Replaces `sin(x)^k`, `k >= 2`, by `sin(x)^(k mod 2) (1 - cos(x)^2)^(k/2)` in every term.
    fn reduce_sin_powers(&mut self, e: Expr) -> Result<Expr, StopReason> {
        let (constant, terms) = match &*e.node() {
            Node::Add { constant, terms } => (constant.clone(), terms.clone()),
            _ => (Rat::zero(), vec![(e, Rat::one())]),
        };
        let mut out: Vec<(Expr, Rat)> = Vec::with_capacity(terms.len());
        for (t, c) in terms {
            let (k, mono) = t.split_coefficient();
            let factors = match &*mono.node() {
                Node::Mul { factors, .. } => factors.clone(),
                _ => vec![(mono, Rat::one())],
            };
            let mut changed = false;
            let mut kept = Vec::with_capacity(factors.len());
            for (b, x) in factors {
                let is_sin = matches!(&*b.node(), Node::Fun(Func::Sin, _));
                if is_sin && x.is_integer() && x >= rat_from_i64(2) {
                    let n = x.to_i64().and_then(|n| u32::try_from(n).ok()).unwrap_or(0);
                    let Node::Fun(_, a) = &*b.node() else { unreachable!("checked above") };
                    let one_minus_cos2 = Expr::one() - a.cos().powi(2);
                    kept.push((one_minus_cos2, rat_from_i64((n / 2) as i64)));
                    if n % 2 == 1 {
                        kept.push((b, Rat::one()));
                    }
                    changed = true;
                } else {
                    kept.push((b, x));
                }
            }
            let term = Expr::make_mul(k * c, kept);
            if changed {
                out.push((expand_rec(term, &self.budget, &mut self.expand_memo)?, Rat::one()));
            } else {
                out.push((term, Rat::one()));
            }
            self.budget.check(out.len())?;
        }
        Ok(Expr::make_add(constant, out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pythagoras_and_angle_sums_vanish() {
        let (a, b, x) = (Expr::sym("a"), Expr::sym("b"), Expr::sym("x"));
        let lim = Limits::default();
        assert_eq!((x.sin().powi(2) + x.cos().powi(2) - 1).trig_normal(lim).unwrap(), Expr::zero());
        assert_eq!(((a - b).cos() - a.cos() * b.cos() - a.sin() * b.sin()).trig_normal(lim).unwrap(), Expr::zero());
        assert_eq!(((a * 2).sin() - a.sin() * a.cos() * 2).trig_normal(lim).unwrap(), Expr::zero());
        assert!((x.tan() * x.cos() - x.sin()).trig_normal(lim).unwrap().is_zero());
        // Denominators are atoms: cos(x) * cos(x)^-1 merges to 1.
        assert!((x.cos() * (x.sin() / x.cos()) - x.sin()).trig_normal(lim).unwrap().is_zero());
    }

    #[test]
    fn limits_stop_the_normal_form_and_say_why() {
        let xs: Vec<Expr> = (0..8).map(|i| Expr::sym(&format!("v{i}"))).collect();
        let e = Expr::sum(xs.iter().copied()).powi(6);
        let err = e.trig_normal(Limits { max_terms: 100, ..Limits::default() }).unwrap_err();
        assert!(matches!(err, StopReason::TermLimit { limit: 100, .. }), "{err}");
    }
}

/// Most terms a sum may have for [`Expr::simplify_trig`] to try contracting it.
const CONTRACT_MAX_TERMS: usize = 400;

impl Expr {
    /// A compact equivalent form: the trigonometric normal form with products of sines and
    /// cosines contracted back into angle sums and differences
    /// (`cos a cos b + sin a sin b -> cos(a - b)`), kept only when it is no larger than the
    /// input. Never runs past `limits`: on a stop, the input comes back unchanged.
    pub fn simplify_trig(self, limits: Limits) -> Expr {
        match self.trig_normal(limits) {
            Ok(n) => {
                let c = contract(n);
                if c.tree_size() <= self.tree_size() { c } else { self }
            }
            Err(_) => self,
        }
    }
}

/// The factors of a monomial as a sorted list.
fn factors_of(mono: Expr) -> Vec<(Expr, Rat)> {
    match &*mono.node() {
        Node::Mul { factors, .. } => factors.clone(),
        Node::Num(_) => vec![],
        _ => vec![(mono, Rat::one())],
    }
}

/// Splits off one `f(a)^1` factor with `f` sin or cos: returns (func, arg, rest factors).
fn trig_factors(fs: &[(Expr, Rat)]) -> Vec<(usize, Func, Expr)> {
    fs.iter()
        .enumerate()
        .filter_map(|(i, (b, x))| match &*b.node() {
            Node::Fun(f @ (Func::Sin | Func::Cos), a) if x.is_one() => Some((i, *f, *a)),
            _ => None,
        })
        .collect()
}

fn contract(e: Expr) -> Expr {
    let Node::Add { constant, terms } = &*e.node() else { return e };
    if terms.len() > CONTRACT_MAX_TERMS {
        return e;
    }
    let mut terms: Vec<(Vec<(Expr, Rat)>, Rat)> = terms
        .iter()
        .map(|(t, c)| {
            let (k, mono) = t.split_coefficient();
            (factors_of(mono), c * k)
        })
        .collect();
    'outer: loop {
        // Each term's monomial once, and where each one is: the partner search below looks a
        // target up instead of building every term's monomial again for every pair of every
        // term (that was nine tenths of loading the bicycle, whose contact it contracts).
        let monos: Vec<Expr> = terms.iter().map(|(fs, _)| Expr::make_mul(Rat::one(), fs.clone())).collect();
        let mut at: FxHashMap<Expr, Vec<usize>> = FxHashMap::default();
        for (j, m) in monos.iter().enumerate() {
            at.entry(*m).or_default().push(j);
        }
        for i in 0..terms.len() {
            let ti = trig_factors(&terms[i].0);
            for (x, fx, ax) in &ti {
                for (y, fy, ay) in &ti {
                    if x >= y || ax == ay {
                        continue;
                    }
                    // Term i has fx(ax) fy(ay) K. Look for the partner with the other functions.
                    let rest: Vec<(Expr, Rat)> = terms[i].0.iter().enumerate().filter(|(k, _)| k != x && k != y).map(|(_, f)| f.clone()).collect();
                    let other = |f: Func| if f == Func::Sin { Func::Cos } else { Func::Sin };
                    let (gx, gy) = (other(*fx), other(*fy));
                    let want_x = Expr::apply(gx, *ax);
                    let want_y = Expr::apply(gy, *ay);
                    let mut target = rest.clone();
                    target.push((want_x, Rat::one()));
                    target.push((want_y, Rat::one()));
                    let target_mono = Expr::make_mul(Rat::one(), target);
                    for &j in at.get(&target_mono).map_or(&[][..], Vec::as_slice) {
                        if j == i {
                            continue;
                        }
                        let (ci, cj) = (terms[i].1.clone(), terms[j].1.clone());
                        let same = ci == cj;
                        if !same && ci != -cj.clone() {
                            continue;
                        }
                        // cos cos + sin sin = cos(a-b); cos cos - sin sin = cos(a+b);
                        // sin a cos b + cos a sin b = sin(a+b); sin a cos b - cos a sin b = sin(a-b).
                        let (new_f, arg) = match (fx, fy) {
                            (Func::Cos, Func::Cos) => (Func::Cos, if same { *ax - *ay } else { *ax + *ay }),
                            (Func::Sin, Func::Sin) => (Func::Cos, if same { *ax - *ay } else { *ax + *ay }),
                            (Func::Sin, Func::Cos) => (Func::Sin, if same { *ax + *ay } else { *ax - *ay }),
                            _ => (Func::Sin, if same { *ay + *ax } else { *ay - *ax }),
                        };
                        // For (sin, sin) first with minus: -sin sin + cos cos: coefficient of the
                        // cos-cos partner leads, handled by using cj.
                        let coef = match (fx, fy) {
                            (Func::Sin, Func::Sin) => cj,
                            _ => ci,
                        };
                        let mut nf = rest;
                        nf.push((Expr::apply(new_f, arg), Rat::one()));
                        let (hi, lo) = if i > j { (i, j) } else { (j, i) };
                        terms.remove(hi);
                        terms.remove(lo);
                        terms.push((nf, coef));
                        continue 'outer;
                    }
                }
            }
        }
        break;
    }
    Expr::make_add(constant.clone(), terms.into_iter().map(|(fs, c)| (Expr::make_mul(Rat::one(), fs), c)).collect())
}

#[cfg(test)]
mod contract_tests {
    use super::*;
    use crate::symbolic::Symbol;

    #[test]
    fn products_contract_to_angle_differences() {
        let (a, b, k) = (Expr::sym("a"), Expr::sym("b"), Expr::sym("k"));
        let lim = Limits::default();
        assert_eq!((k * a.cos() * b.cos() + k * a.sin() * b.sin()).simplify_trig(lim), k * (a - b).cos());
        assert_eq!((a.cos() * b.cos() - a.sin() * b.sin()).simplify_trig(lim), (a + b).cos());
        assert_eq!((a.sin() * b.cos() - a.cos() * b.sin()).simplify_trig(lim), (a - b).sin());
        assert_eq!((k * a.sin().powi(2) + k * a.cos().powi(2)).simplify_trig(lim), k);
        // Values are preserved for something that does not contract.
        let e = a.sin() * b.cos() * 2 + a.cos() * b.sin() * 3;
        let s = e.simplify_trig(lim);
        let mut env = crate::symbolic::eval::Env::default();
        env.set(Symbol::new("a"), 0.3);
        env.set(Symbol::new("b"), 1.1);
        assert!((s.eval(&env).unwrap() - e.eval(&env).unwrap()).abs() < 1e-14);
    }
}
