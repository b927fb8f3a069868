//! Deciding "identically zero" without expanding anything.
//!
//! An expression is evaluated exactly, over the integers modulo the prime `p = 2^61 - 1`, at
//! seeded random points: every symbol gets a random residue, and the sine and cosine of an
//! angle come from the rational parametrization `t = tan(x/2)`, `cos x = (1 - t^2)/(1 + t^2)`,
//! `sin x = 2t/(1 + t^2)`, with `t` random. A linear combination of angles `k . q` is the
//! product of the angles' points on the circle `c^2 + s^2 = 1` raised to the integer powers
//! `k` (rational `k` use a base point for `x / L`, `L` the common denominator). Time functions
//! are random functions (the same argument gives the same value). Every step is an identity
//! of rational functions in `(q, t_q)`, so:
//!
//! - a nonzero value at one point proves the expression is not identically zero (a float
//!   evaluation at a real point is attached as a witness);
//! - zero at two independent random points means it is zero with probability of error below
//!   `(d / p)^2`, `d` its degree: about `1e-30` for the expressions of multibody models.
//!
//! The cost is linear in the number of distinct nodes, so the test runs on the raw DAG of a
//! 50-body chain where any normal form would be exponential. Expressions the modular
//! arithmetic cannot represent (`exp`, `ln`, `abs`, fractional powers, `pi` times a rational
//! that is not a multiple of 1/2) fall back to a seeded floating-point test.
//!
//! ```
//! use generator::symbolic::{Expr, zero::{zero_test, ZeroProof, ZeroVerdict}};
//! let (a, b) = (Expr::sym("a"), Expr::sym("b"));
//! let e = (a - b).cos() - a.cos() * b.cos() - a.sin() * b.sin();
//! assert!(matches!(zero_test(e), ZeroVerdict::Zero { proof: ZeroProof::Modular { .. } }));
//! assert!(!zero_test((a + b).cos() - a.cos() * b.cos()).is_zero());
//! ```

use super::eval::Env;
use super::expr::{Expr, Func, Node, Symbol};
use super::number::{Rat, rat_from_f64};
use rustc_hash::FxHashMap;

/// How a zero verdict was reached.
#[derive(Clone, Debug, PartialEq)]
pub enum ZeroProof {
    /// The expression is the number zero as built.
    Structural,
    /// Exact evaluation modulo a prime vanished at `points` independent random points.
    Modular { points: usize },
    /// The modular test could not represent the expression (`reason`); it vanished, to
    /// rounding, at every random real point tried.
    Numeric { points: usize, reason: &'static str },
}

/// The outcome of [`zero_test`].
#[derive(Clone, Debug, PartialEq)]
pub enum ZeroVerdict {
    /// Identically zero.
    Zero { proof: ZeroProof },
    /// Not zero: a real point where it is not, with the value there.
    NonZero { value: f64, at: Vec<(String, f64)> },
}

impl ZeroVerdict {
    /// True for [`ZeroVerdict::Zero`].
    pub fn is_zero(&self) -> bool {
        matches!(self, ZeroVerdict::Zero { .. })
    }
}

/// A small deterministic random source (splitmix64) for seeded tests.
#[derive(Clone, Debug)]
pub struct SplitMix(pub u64);

impl SplitMix {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// A uniform float in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// Decides whether `e` is identically zero (see the module docs).
pub fn zero_test(e: Expr) -> ZeroVerdict {
    if e.is_zero() {
        return ZeroVerdict::Zero { proof: ZeroProof::Structural };
    }
    if e.as_num().is_some() {
        return numeric_witness(e);
    }
    match modular_zero(e) {
        Ok(true) => ZeroVerdict::Zero { proof: ZeroProof::Modular { points: MODULAR_POINTS } },
        Ok(false) => numeric_witness(e),
        Err(reason) => numeric_zero_test(e, reason),
    }
}

/// `e` with each symbol of `symbols` it only depends on formally (its partial derivative is
/// identically zero) set to zero: exact, and it removes terms that cancel only through
/// identities a simplifier missed.
///
/// ```
/// use generator::symbolic::{Expr, Symbol, zero::prune_absent};
/// let (a, v) = (Expr::sym("a"), Symbol::new("v"));
/// let e = v.expr() * (a.sin().powi(2) + a.cos().powi(2)) - v.expr() + a;
/// assert_eq!(prune_absent(e, &[v]), a);
/// ```
pub fn prune_absent(e: Expr, symbols: &[Symbol]) -> Expr {
    let mut out = e;
    let mut zero = std::collections::HashMap::new();
    for s in symbols {
        if out.contains(*s) && zero_test(out.diff(*s)).is_zero() {
            zero.insert(*s, Expr::zero());
        }
    }
    if !zero.is_empty() {
        out = out.subs(&zero);
    }
    out
}

/// `zero_test(e).is_zero()`.
pub fn is_identically_zero(e: Expr) -> bool {
    zero_test(e).is_zero()
}

/// Independent points at which the modular value must vanish.
pub const MODULAR_POINTS: usize = 2;

/// Number of random points the floating-point fallback uses.
pub const NUMERIC_POINTS: usize = 8;

/// The prime `2^61 - 1`.
const P: u64 = (1u64 << 61) - 1;

fn reduce(x: u128) -> u64 {
    let lo = (x as u64) & P;
    let hi = (x >> 61) as u64;
    let s = lo + (hi & P) + ((x >> 122) as u64);
    let s = (s & P) + (s >> 61);
    if s >= P { s - P } else { s }
}

fn addm(a: u64, b: u64) -> u64 {
    let s = a + b;
    if s >= P { s - P } else { s }
}

fn subm(a: u64, b: u64) -> u64 {
    if a >= b { a - b } else { a + P - b }
}

fn mulm(a: u64, b: u64) -> u64 {
    reduce(a as u128 * b as u128)
}

fn powm(mut a: u64, mut e: u64) -> u64 {
    let mut acc = 1;
    while e > 0 {
        if e & 1 == 1 {
            acc = mulm(acc, a);
        }
        a = mulm(a, a);
        e >>= 1;
    }
    acc
}

/// The inverse, `None` for zero (a pole at this point).
fn invm(a: u64) -> Option<u64> {
    (a != 0).then(|| powm(a, P - 2))
}

/// Why a point gave no value.
enum Failure {
    /// The expression has a node the modular arithmetic cannot represent.
    Unsupported(&'static str),
    /// A denominator vanished at this point: try another.
    Pole,
}

fn rat_mod(r: &Rat) -> Result<u64, Failure> {
    let (n, d) = match r.as_i64_pair() {
        Some((n, d)) => (if n < 0 { subm(0, n.unsigned_abs() % P) } else { n as u64 % P }, d as u64 % P),
        None => {
            let m = num_bigint::BigInt::from(P);
            let to = |x: num_bigint::BigInt| -> u64 {
                let r = ((x % &m) + &m) % &m;
                r.to_u64_digits().1.first().copied().unwrap_or(0)
            };
            (to(r.numer()), to(r.denom()))
        }
    };
    // A denominator divisible by p (a number with over 18 digits of a special form): no value.
    let inv = invm(d).ok_or(Failure::Unsupported("a coefficient's denominator is a multiple of the prime"))?;
    Ok(mulm(n, inv))
}

/// A point on the circle, `(cos, sin)`.
#[derive(Clone, Copy)]
struct Phase(u64, u64);

impl Phase {
    const ONE: Phase = Phase(1, 0);
    fn mul(self, o: Phase) -> Phase {
        Phase(subm(mulm(self.0, o.0), mulm(self.1, o.1)), addm(mulm(self.1, o.0), mulm(self.0, o.1)))
    }
    fn pow(self, n: i64) -> Phase {
        let mut base = if n < 0 { Phase(self.0, subm(0, self.1)) } else { self };
        let mut e = n.unsigned_abs();
        let mut acc = Phase::ONE;
        while e > 0 {
            if e & 1 == 1 {
                acc = acc.mul(base);
            }
            base = base.mul(base);
            e >>= 1;
        }
        acc
    }
}

/// The angle `arg` as `constant + sum k_i atom_i`: atoms with rational coefficients.
fn angle_terms(arg: Expr) -> Vec<(Expr, Rat)> {
    match &*arg.node() {
        Node::Add { constant, terms } => {
            let mut out: Vec<(Expr, Rat)> = terms.clone();
            if !constant.is_zero() {
                out.push((Expr::one(), constant.clone()));
            }
            out
        }
        Node::Num(r) => vec![(Expr::one(), r.clone())],
        _ => {
            let (k, atom) = arg.split_coefficient();
            vec![(atom, k)]
        }
    }
}

/// True for the atoms of an angle whose phase may be drawn independently: `1` (a constant
/// phase), a symbol, or a product of symbols. Equal values of these are equal expressions (the
/// sums and products are canonical); an atom such as `sin(2x)` is not, since `2 sin(x) cos(x)`
/// is the same function, so its phase is not independent of the other atoms'.
fn is_canonical_angle(atom: Expr) -> bool {
    match &*atom.node() {
        Node::Num(_) | Node::Sym(_) => true,
        Node::Mul { factors, .. } => factors.iter().all(|(b, x)| b.as_sym().is_some() && x.is_integer() && x.is_positive()),
        _ => false,
    }
}

/// Largest common denominator of an angle's coefficients the test handles.
const MAX_ANGLE_DENOMINATOR: i64 = 1 << 20;

fn gcd(a: i64, b: i64) -> i64 {
    if b == 0 { a.abs() } else { gcd(b, a % b) }
}

struct Point {
    values: FxHashMap<Symbol, u64>,
    /// Per angle atom: its base point (for `atom / L`) and `L`.
    bases: FxHashMap<Expr, (Phase, i64)>,
    rng: SplitMix,
    /// Seed of this point's random functions (fixed: equal arguments, equal values).
    seed: u64,
}

impl Point {
    fn residue(&mut self) -> u64 {
        loop {
            let r = self.rng.next_u64() & P;
            if r != 0 && r != P {
                return r;
            }
        }
    }

    fn symbol(&mut self, s: Symbol) -> u64 {
        if let Some(&v) = self.values.get(&s) {
            return v;
        }
        let v = self.residue();
        self.values.insert(s, v);
        v
    }

    fn random_phase(&mut self) -> Phase {
        loop {
            let t = self.residue();
            let t2 = mulm(t, t);
            if let Some(inv) = invm(addm(1, t2)) {
                return Phase(mulm(subm(1, t2), inv), mulm(addm(t, t), inv));
            }
        }
    }
}

fn pi_phase(k: &Rat) -> Result<Phase, Failure> {
    // e^{i pi k} for k a multiple of 1/2; anything else is an algebraic number we do not model.
    let twice = k * Rat::int(2);
    let n = twice.to_i64().ok_or(Failure::Unsupported("pi times a rational that is not a multiple of 1/2 in an angle"))?;
    Ok(match n.rem_euclid(4) {
        0 => Phase(1, 0),
        1 => Phase(0, 1),
        2 => Phase(P - 1, 0),
        _ => Phase(0, P - 1),
    })
}

/// The common denominators of every angle atom's coefficients.
fn angle_denominators(order: &[Expr]) -> Result<FxHashMap<Expr, i64>, Failure> {
    let mut lcm: FxHashMap<Expr, i64> = FxHashMap::default();
    for e in order {
        if let Node::Fun(Func::Sin | Func::Cos | Func::Tan, a) = &*e.node() {
            for (atom, k) in angle_terms(*a) {
                if !is_canonical_angle(atom) {
                    return Err(Failure::Unsupported("an angle that is not a linear combination of symbols and their products"));
                }
                let d = k.as_i64_pair().map(|(_, d)| d).ok_or(Failure::Unsupported("an angle coefficient too large"))?;
                let l = lcm.entry(atom).or_insert(1);
                let g = gcd(*l, d);
                *l = (*l / g).checked_mul(d).filter(|x| *x <= MAX_ANGLE_DENOMINATOR).ok_or(Failure::Unsupported("angles with huge denominators"))?;
            }
        }
    }
    Ok(lcm)
}

fn eval_at(order: &[Expr], denominators: &FxHashMap<Expr, i64>, point: &mut Point) -> Result<u64, Failure> {
    let mut value: FxHashMap<Expr, u64> = FxHashMap::default();
    value.reserve(order.len());
    let pi = Symbol::new("pi");
    for &e in order {
        let v = match &*e.node() {
            Node::Num(r) => rat_mod(r)?,
            Node::Sym(s) => point.symbol(*s),
            Node::Add { constant, terms } => {
                let mut acc = rat_mod(constant)?;
                for (t, c) in terms {
                    acc = addm(acc, mulm(rat_mod(c)?, value[t]));
                }
                acc
            }
            Node::Mul { coefficient, factors } => {
                let mut acc = rat_mod(coefficient)?;
                for (b, x) in factors {
                    let n = x.to_i64().ok_or(Failure::Unsupported("a fractional power"))?;
                    let bv = value[b];
                    let p = if n >= 0 { powm(bv, n as u64) } else { invm(powm(bv, n.unsigned_abs())).ok_or(Failure::Pole)? };
                    acc = mulm(acc, p);
                }
                acc
            }
            Node::Fun(f @ (Func::Sin | Func::Cos | Func::Tan), a) => {
                let mut phase = Phase::ONE;
                for (atom, k) in angle_terms(*a) {
                    if atom.as_sym() == Some(pi) {
                        phase = phase.mul(pi_phase(&k)?);
                        continue;
                    }
                    let l = denominators[&atom];
                    let (base, _) = match point.bases.get(&atom) {
                        Some(b) => *b,
                        None => {
                            let b = (point.random_phase(), l);
                            point.bases.insert(atom, b);
                            b
                        }
                    };
                    let (n, d) = k.as_i64_pair().ok_or(Failure::Unsupported("an angle coefficient too large"))?;
                    let power = n.checked_mul(l / d).ok_or(Failure::Unsupported("an angle coefficient too large"))?;
                    phase = phase.mul(base.pow(power));
                }
                match f {
                    Func::Cos => phase.0,
                    Func::Sin => phase.1,
                    _ => mulm(phase.1, invm(phase.0).ok_or(Failure::Pole)?),
                }
            }
            Node::Fun(Func::Exp, _) => return Err(Failure::Unsupported("exp")),
            Node::Fun(Func::Ln, _) => return Err(Failure::Unsupported("ln")),
            Node::Fun(Func::Abs, _) => return Err(Failure::Unsupported("abs")),
            Node::Apply(name, a) => {
                // A random function: a hash of the name and the argument's residue.
                let mut h = SplitMix(point.seed ^ (name.0 as u64).wrapping_mul(0x9E37_79B9) ^ value[a].rotate_left(17));
                h.next_u64() & P
            }
        };
        value.insert(e, v);
    }
    Ok(value[order.last().expect("the expression itself")])
}

/// `Ok(true)`: zero at every point; `Ok(false)`: nonzero somewhere; `Err`: not representable.
fn modular_zero(e: Expr) -> Result<bool, &'static str> {
    let order = e.post_order_nodes();
    let denominators = match angle_denominators(&order) {
        Ok(d) => d,
        Err(Failure::Unsupported(r)) => return Err(r),
        Err(Failure::Pole) => unreachable!("no evaluation yet"),
    };
    let mut rng = SplitMix(0x5E_ED0F_2E40 ^ e.key());
    let mut zeros = 0;
    for _ in 0..16 {
        let seed = rng.next_u64();
        let mut point = Point { values: FxHashMap::default(), bases: FxHashMap::default(), rng: SplitMix(seed), seed };
        match eval_at(&order, &denominators, &mut point) {
            Ok(0) => {
                zeros += 1;
                if zeros == MODULAR_POINTS {
                    return Ok(true);
                }
            }
            Ok(_) => return Ok(false),
            Err(Failure::Pole) => continue,
            Err(Failure::Unsupported(r)) => return Err(r),
        }
    }
    // Poles at every point tried: the expression divides by something identically zero.
    Err("a denominator vanishes at every point tried")
}

/// A real point where `e` is not zero (for a verdict already known to be "not zero"); the value
/// may be NaN where the expression has no real value there.
fn numeric_witness(e: Expr) -> ZeroVerdict {
    let syms = e.free_symbols();
    let mut rng = SplitMix(0x317_7E55 ^ e.key());
    let mut last = (f64::NAN, vec![]);
    for _ in 0..NUMERIC_POINTS {
        let (env, at) = random_env(&syms, &mut rng);
        if let Ok(v) = e.eval(&env) {
            if v.is_finite() && v != 0.0 {
                return ZeroVerdict::NonZero { value: v, at };
            }
            last = (v, at);
        }
    }
    ZeroVerdict::NonZero { value: last.0, at: last.1 }
}

/// Values in `[0.1, 2)` for the symbols, and random smooth definitions for named functions.
fn random_env(syms: &[Symbol], rng: &mut SplitMix) -> (Env, Vec<(String, f64)>) {
    let mut env = Env::default();
    let mut at = Vec::new();
    let arg = Symbol::internal("arg");
    for s in syms {
        let v = rng.uniform(0.1, 2.0);
        env.set(*s, v);
        let (a, b) = (rng.uniform(0.5, 1.5), rng.uniform(0.0, 1.0));
        let num = |x: f64| Expr::num(rat_from_f64(x).unwrap_or_else(Rat::one));
        env.define(*s, arg, (arg.expr() * num(a) + num(b)).sin());
        at.push((s.name(), v));
    }
    (env, at)
}

/// The floating-point fallback: the value must vanish against the size of its terms.
fn numeric_zero_test(e: Expr, reason: &'static str) -> ZeroVerdict {
    let syms = e.free_symbols();
    let mut rng = SplitMix(0x5EED_0F2E_4055 ^ e.key());
    let terms: Vec<Expr> = match &*e.node() {
        Node::Add { terms, .. } => terms.iter().map(|(t, c)| t.scale(c)).collect(),
        _ => vec![e],
    };
    let constant = match &*e.node() {
        Node::Add { constant, .. } => constant.to_f64().abs(),
        _ => 0.0,
    };
    let mut evaluated = 0;
    for _ in 0..NUMERIC_POINTS {
        let (env, at) = random_env(&syms, &mut rng);
        let (Ok(value), Ok(parts)) = (e.eval(&env), Expr::eval_all(&terms, &env)) else { continue };
        if !value.is_finite() {
            continue;
        }
        evaluated += 1;
        let scale: f64 = parts.iter().map(|v| v.abs()).sum::<f64>() + constant;
        if value.abs() > 1e-10 * scale.max(1e-300) || (scale == 0.0 && value != 0.0) {
            return ZeroVerdict::NonZero { value, at };
        }
    }
    if evaluated == 0 {
        return ZeroVerdict::NonZero { value: f64::NAN, at: vec![] };
    }
    ZeroVerdict::Zero { proof: ZeroProof::Numeric { points: evaluated, reason } }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn zero(e: Expr) -> bool {
        zero_test(e).is_zero()
    }

    #[test]
    fn trigonometric_identities_are_zero_exactly() {
        let (a, x) = (Expr::sym("a"), Expr::sym("x"));
        assert_eq!(zero_test(x.sin().powi(2) + x.cos().powi(2) - 1), ZeroVerdict::Zero { proof: ZeroProof::Modular { points: 2 } });
        assert!(zero((a * 2).sin() - a.sin() * a.cos() * 2));
        assert!(zero((a / 2).cos().powi(2) * 2 - 1 - a.cos()));
        assert!(zero(x.tan() * x.cos() - x.sin()));
        assert!(zero((x.sin().powi(2) + x.cos().powi(2)) / x.cos() - x.cos().recip()));
        // A 12-angle chain: cos(q1 + ... + q12) against its recursive expansion.
        let qs: Vec<Expr> = (0..12).map(|i| Expr::sym(&format!("zq{i}"))).collect();
        let (mut s, mut c) = (qs[0].sin(), qs[0].cos());
        for q in &qs[1..] {
            let ns = s * q.cos() + c * q.sin();
            c = c * q.cos() - s * q.sin();
            s = ns;
        }
        assert!(zero(c - Expr::sum(qs.iter().copied()).cos()));
        assert!(!zero(c - Expr::sum(qs.iter().copied()).sin()));
        // Angles with a constant and with pi.
        let pi = Expr::sym("pi");
        assert!(zero((x + pi / 2).sin() - x.cos()));
        assert!(zero((x + 1).cos() - x.cos() * Expr::one().cos() + x.sin() * Expr::one().sin()));
        // Named functions are the same function at equal arguments.
        let f = Symbol::new("F");
        let t = Expr::sym("t");
        assert!(zero(Expr::apply_named(f, t * 2) - Expr::apply_named(f, t + t)));
        assert!(!zero(Expr::apply_named(f, t * 2) - Expr::apply_named(f, t)));
    }

    #[test]
    fn near_misses_are_rejected_with_a_witness() {
        let (a, b) = (Expr::sym("a"), Expr::sym("b"));
        let eps = Expr::num(Rat::frac(1, 10_000_000));
        assert!(!zero(a.sin().powi(2) + a.cos().powi(2) - 1 - eps));
        assert!(!zero((a - b).cos() - a.cos() * b.cos() + a.sin() * b.sin()));
        match zero_test(a.sin() - a.cos()) {
            ZeroVerdict::NonZero { value, at } => assert!(value.abs() > 0.0 && at.len() == 1),
            z => panic!("{z:?}"),
        }
    }

    #[test]
    fn unsupported_functions_fall_back_to_floats() {
        let x = Expr::sym("x");
        match zero_test(x.exp() * (-x).exp() - 1) {
            ZeroVerdict::Zero { proof: ZeroProof::Numeric { reason, .. } } => assert_eq!(reason, "exp"),
            z => panic!("{z:?}"),
        }
        assert!(!zero(x.sqrt() - x));
    }
}
