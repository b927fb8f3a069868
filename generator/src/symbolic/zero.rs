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
//! 50-body chain where any normal form would be exponential.
//!
//! Beyond rational functions of sines and cosines:
//!
//! - a square root `sqrt(f)` (any power `f^(n/2)`) is a value `y` with `y^2 = f`, and `abs(g)`
//!   is `g` or `-g`: the test tries every sign of each (at most [`MAX_BRANCHES`]), so a zero holds
//!   on every branch, the real one included; a point where a radicand has no square root in the
//!   field is skipped;
//! - `exp` of a linear combination of symbols is a homomorphism (a random base per atom, as the
//!   angles have), so `exp(a) exp(b) = exp(a + b)` is decided exactly;
//! - any other `exp`, every `ln`, and the model's named functions are random functions of their
//!   argument's value: a zero then holds for every function, these included.
//!
//! A nonzero value that the branches or the stand-in functions could have produced (and
//! anything the arithmetic cannot represent: other fractional powers, `pi` times a rational
//! that is not a multiple of 1/2) is checked in floating point at random real points: a value
//! clearly beyond rounding is a witness of "not zero"; otherwise the answer is
//! [`ZeroVerdict::Undecided`], which no caller takes as zero and every derivation reports. A
//! floating-point test never says "zero".
//!
//! ```
//! use generator::symbolic::{Expr, ZeroProof, ZeroVerdict, zero_test};
//! let (a, b) = (Expr::sym("a"), Expr::sym("b"));
//! let e = (a - b).cos() - a.cos() * b.cos() - a.sin() * b.sin();
//! assert!(matches!(zero_test(e), ZeroVerdict::Zero { proof: ZeroProof::Modular { .. } }));
//! assert!(!zero_test((a + b).cos() - a.cos() * b.cos()).is_zero());
//! ```

use super::eval::Env;
use super::expr::{Expr, Func, Node, Symbol};
use super::number::{Rat, rat_from_f64};
use rustc_hash::{FxHashMap, FxHashSet};

/// How a zero verdict was reached.
#[derive(Clone, Debug, PartialEq)]
pub enum ZeroProof {
    /// The expression is the number zero as built.
    Structural,
    /// Exact evaluation modulo a prime vanished at `points` independent random points, on
    /// every sign of each of its `branches` (square roots and absolute values).
    Modular { points: usize, branches: usize },
}

/// The outcome of [`zero_test`].
#[derive(Clone, Debug, PartialEq)]
pub enum ZeroVerdict {
    /// Identically zero.
    Zero { proof: ZeroProof },
    /// Not zero: a real point where it is not, with the value there.
    NonZero { value: f64, at: Vec<(String, f64)> },
    /// Neither proven zero nor shown nonzero: the exact test could not decide (`reason`), and
    /// the expression vanished, to rounding, at every real point tried. Never taken as zero:
    /// callers keep the term (or the safe side of a decision), and the derivation reports it
    /// (the thread's report of cuts).
    Undecided { reason: &'static str },
}

impl ZeroVerdict {
    /// True for [`ZeroVerdict::Zero`] only: an undecided expression is not known to be zero.
    pub fn is_zero(&self) -> bool {
        matches!(self, ZeroVerdict::Zero { .. })
    }
    /// True for [`ZeroVerdict::NonZero`] only: an undecided expression is not known to be
    /// nonzero either.
    pub fn is_nonzero(&self) -> bool {
        matches!(self, ZeroVerdict::NonZero { .. })
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

/// Decides whether `e` is identically zero (see the module docs). An undecided answer is
/// recorded in this thread's report of cuts.
pub fn zero_test(e: Expr) -> ZeroVerdict {
    if e.is_zero() {
        return ZeroVerdict::Zero { proof: ZeroProof::Structural };
    }
    if e.as_num().is_some() {
        return numeric_witness(e);
    }
    let verdict = match modular_zero(e) {
        Ok(Modular::Zero { branches }) => ZeroVerdict::Zero { proof: ZeroProof::Modular { points: MODULAR_POINTS, branches } },
        Ok(Modular::NonZero { proof: Ok(()) }) => numeric_witness(e),
        Ok(Modular::NonZero { proof: Err(reason) }) | Err(reason) => numeric_check(e, reason),
    };
    if let ZeroVerdict::Undecided { reason } = verdict {
        super::report::record(|c| *c.undecided.entry(reason.to_string()).or_default() += 1);
    }
    verdict
}

/// `e` with each symbol of `symbols` it does not depend on set to zero, where `e` equals
/// itself so (`e - e|s=0` identically zero, decided as [`zero_test`] decides): a coordinate
/// that only cancels through identities (the absolute orientation of a free system in its
/// shape's equations) leaves, and its sines and cosines with it. A symbol whose zero is
/// outside `e`'s domain (a division by `sin s`) fails the test and stays.
pub fn settle_absent(e: Expr, symbols: &[Symbol]) -> Expr {
    let mut out = e;
    for s in symbols {
        if !out.contains(*s) {
            continue;
        }
        let settled = out.subs(&std::collections::HashMap::from([(*s, Expr::zero())]));
        if zero_test(out - settled).is_zero() {
            out = settled;
        }
    }
    out
}

/// `zero_test(e).is_zero()`.
pub fn is_identically_zero(e: Expr) -> bool {
    zero_test(e).is_zero()
}

/// Independent points at which the modular value must vanish.
pub const MODULAR_POINTS: usize = 2;

/// Random real points the floating-point check of an undecided expression tries.
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
    /// A denominator vanished at this point, or a square root has no value in the field there:
    /// try another.
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
    // Most coefficients are integers: no inverse to take (it costs about 120 products).
    if d == 1 {
        return Ok(n);
    }
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
    /// Per angle atom: its base point (for `atom / L`).
    bases: FxHashMap<Expr, Phase>,
    /// Per exponent atom: `exp(atom / L)`.
    exp_bases: FxHashMap<Expr, u64>,
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

    /// A point with no values yet, for drawing one base from `seed`.
    fn seeded(seed: u64) -> Point {
        Point { values: FxHashMap::default(), bases: FxHashMap::default(), exp_bases: FxHashMap::default(), rng: SplitMix(seed), seed }
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

/// What the modular evaluation of one expression needs to know before its points: the common
/// denominator of each angle atom's and each exponent atom's coefficients, and the branches
/// (square roots and absolute values) whose signs every point tries.
#[derive(Default)]
struct Shape {
    angle_denominators: FxHashMap<Expr, i64>,
    exp_denominators: FxHashMap<Expr, i64>,
    /// Distinct square-root nodes: each has a value in the field at half the points.
    square_roots: usize,
    /// True when an `exp` or `ln` stands in as an unknown function: a zero then holds for any
    /// function (so for these), but a nonzero proves nothing.
    stand_ins: bool,
}

/// The two kinds of values with a sign to choose.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
enum Branch {
    SquareRoot,
    Abs,
}

/// Most square roots and absolute values of distinct values in one expression the test tries
/// every sign of (`2^8` evaluations per point); more, and the test answers "undecided".
pub const MAX_BRANCHES: usize = 8;

/// The branches of one point: a square root or an absolute value is a function of its
/// argument's value, so each distinct (kind, value) is one sign to choose, numbered in the
/// order met.
type Branches = FxHashMap<(Branch, u64), usize>;

/// Adds the denominators of `arg`'s atoms to `map`; true when an atom is not canonical (its
/// base is then a random function of its value: a zero still holds, a nonzero proves nothing).
fn add_denominator(map: &mut FxHashMap<Expr, i64>, arg: Expr) -> Result<bool, Failure> {
    let mut stand_in = false;
    for (atom, k) in angle_terms(arg) {
        stand_in |= !is_canonical_angle(atom);
        let d = k.as_i64_pair().map(|(_, d)| d).ok_or(Failure::Unsupported("an angle coefficient too large"))?;
        let l = map.entry(atom).or_insert(1);
        let g = gcd(*l, d);
        *l = (*l / g).checked_mul(d).filter(|x| *x <= MAX_ANGLE_DENOMINATOR).ok_or(Failure::Unsupported("angles with huge denominators"))?;
    }
    Ok(stand_in)
}

impl Shape {
    fn of(order: &[Expr]) -> Result<Shape, Failure> {
        let mut shape = Shape::default();
        for e in order {
            match &*e.node() {
                Node::Fun(Func::Sin | Func::Cos | Func::Tan, a) => shape.stand_ins |= add_denominator(&mut shape.angle_denominators, *a)?,
                Node::Fun(Func::Exp, a) => shape.stand_ins |= add_denominator(&mut shape.exp_denominators, *a)?,
                Node::Fun(Func::Ln, _) => shape.stand_ins = true,
                Node::Mul { factors, .. } => {
                    for (_, x) in factors.iter().filter(|(_, x)| !x.is_integer()) {
                        match x.as_i64_pair() {
                            Some((_, 2)) => shape.square_roots += 1,
                            _ => return Err(Failure::Unsupported("a fractional power other than a square root")),
                        }
                    }
                }
                _ => {}
            }
        }
        Ok(shape)
    }
}

/// The square root of `v` in the field, when it has one (`p = 3 mod 4`: `v^((p+1)/4)`).
fn sqrtm(v: u64) -> Option<u64> {
    let r = powm(v, (P + 1) / 4);
    (mulm(r, r) == v).then_some(r)
}

/// A random function's value: a hash of its tag, the point's seed and the argument's residue.
fn stand_in(seed: u64, tag: u64, argument: u64) -> u64 {
    SplitMix(seed ^ tag.wrapping_mul(0x9E37_79B9) ^ argument.rotate_left(17)).next_u64() & P
}

/// The value of `order`'s last node at `point`, each branch `b` (numbered in `branches`, at
/// most [`MAX_BRANCHES`]) taking the negative sign where bit `b` of `signs` is set.
fn eval_at(order: &[Expr], shape: &Shape, point: &mut Point, branches: &mut Branches, signs: u64) -> Result<u64, Failure> {
    let mut value: FxHashMap<Expr, u64> = FxHashMap::default();
    value.reserve(order.len());
    let pi = Symbol::new("pi");
    let mut sign = |kind: Branch, key: u64, v: u64| -> Result<u64, Failure> {
        let n = branches.len();
        let b = *branches.entry((kind, key)).or_insert(n);
        if b >= MAX_BRANCHES {
            return Err(Failure::Unsupported("more square roots and absolute values than the test tries every sign of"));
        }
        Ok(if signs >> b & 1 == 1 { subm(0, v) } else { v })
    };
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
                    let (bv, n) = match x.to_i64() {
                        Some(n) => (value[b], n),
                        None => {
                            let (n, _) = x.as_i64_pair().ok_or(Failure::Unsupported("a fractional power other than a square root"))?;
                            (sign(Branch::SquareRoot, value[b], sqrtm(value[b]).ok_or(Failure::Pole)?)?, n)
                        }
                    };
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
                    let l = shape.angle_denominators[&atom];
                    let power = atom_power(&k, l)?;
                    if is_canonical_angle(atom) {
                        let base = match point.bases.get(&atom) {
                            Some(b) => *b,
                            None => {
                                let b = point.random_phase();
                                point.bases.insert(atom, b);
                                b
                            }
                        };
                        phase = phase.mul(base.pow(power));
                    } else {
                        let (key, sign) = value_key(atom_value(atom, &k, *a, &value)?, l);
                        let base = Point::seeded(point.seed ^ 0x0A_4613 ^ key).random_phase();
                        phase = phase.mul(base.pow(sign * power));
                    }
                }
                match f {
                    Func::Cos => phase.0,
                    Func::Sin => phase.1,
                    _ => mulm(phase.1, invm(phase.0).ok_or(Failure::Pole)?),
                }
            }
            Node::Fun(Func::Exp, a) => {
                // exp(k . atoms) as the product of each atom's random base (for atom / L) to the
                // power k L: exp of independent symbols are algebraically independent of them.
                let mut acc = 1;
                for (atom, k) in angle_terms(*a) {
                    let l = shape.exp_denominators[&atom];
                    let mut n = atom_power(&k, l)?;
                    let base = if is_canonical_angle(atom) {
                        match point.exp_bases.get(&atom) {
                            Some(b) => *b,
                            None => {
                                let b = point.residue();
                                point.exp_bases.insert(atom, b);
                                b
                            }
                        }
                    } else {
                        let (key, sign) = value_key(atom_value(atom, &k, *a, &value)?, l);
                        n *= sign;
                        Point::seeded(point.seed ^ 0xE4_E4E4 ^ key).residue()
                    };
                    let p = powm(base, n.unsigned_abs());
                    acc = mulm(acc, if n >= 0 { p } else { invm(p).ok_or(Failure::Pole)? });
                }
                acc
            }
            Node::Fun(Func::Ln, a) => stand_in(point.seed, 0x1E, value[a]),
            // |g| = |-g|: one branch for both.
            Node::Fun(Func::Abs, a) => {
                let v = value[a];
                let key = v.min(subm(0, v));
                sign(Branch::Abs, key, key)?
            }
            // A named function: a random function (the same argument gives the same value).
            Node::Apply(name, a) => stand_in(point.seed, name.id as u64, value[a]),
        };
        value.insert(e, v);
    }
    Ok(value[order.last().expect("the expression itself")])
}

/// The value of `atom`, with coefficient `k` in the angle or exponent `arg`.
fn atom_value(atom: Expr, k: &Rat, arg: Expr, value: &FxHashMap<Expr, u64>) -> Result<u64, Failure> {
    match value.get(&atom) {
        Some(v) => Ok(*v),
        // An atom split off a product (`2 f g` gives `f g`) is no node of its own: its value is
        // the argument's over the coefficient.
        None => Ok(mulm(value[&arg], invm(rat_mod(k)?).ok_or(Failure::Pole)?)),
    }
}

/// The key [`value_key`] gives an atom whose value is zero; its power is 0, so its base is 1.
const ZERO_KEY: u64 = 0;

/// The key of the random base of an atom that is no product of symbols, from its value `v`
/// and the denominator `l` its base is for: `v` and `-v` share one base, the second with the
/// opposite power (`sign`), so the base is odd as `e^(i v)` is. A zero found with such bases
/// holds for every function of the atom's value, the true one among them; a nonzero proves
/// nothing (relations between different atoms are not modelled).
fn value_key(v: u64, l: i64) -> (u64, i64) {
    if v == 0 {
        // e^0 = 1: the key of a base that is 1 (see `unit_at_zero`).
        return (ZERO_KEY, 0);
    }
    let c = v.min(subm(0, v));
    (c.rotate_left(23) ^ (l as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15), if c == v { 1 } else { -1 })
}

/// The integer power `k L` of an atom's base point (for `atom / L`).
fn atom_power(k: &Rat, l: i64) -> Result<i64, Failure> {
    let (n, d) = k.as_i64_pair().ok_or(Failure::Unsupported("an angle coefficient too large"))?;
    n.checked_mul(l / d).ok_or(Failure::Unsupported("an angle coefficient too large"))
}

/// The modular test's answer.
enum Modular {
    /// Zero at [`MODULAR_POINTS`] points, on every sign of every branch.
    Zero { branches: usize },
    /// Nonzero at a point; `proof` says whether that shows the expression is not identically
    /// zero, and if not, why. It does when no stand-in function was involved and the value is
    /// nonzero on every sign of every branch: the real branch lies on one of them.
    NonZero { proof: Result<(), &'static str> },
}

/// Points tried before the test gives up on poles and square roots outside the field.
fn attempts(shape: &Shape) -> usize {
    16 << shape.square_roots.min(MAX_BRANCHES)
}

fn modular_zero(e: Expr) -> Result<Modular, &'static str> {
    let order = e.post_order_nodes();
    let shape = match Shape::of(&order) {
        Ok(s) => s,
        Err(Failure::Unsupported(r)) => return Err(r),
        Err(Failure::Pole) => unreachable!("no evaluation yet"),
    };
    let mut rng = SplitMix(0x5E_ED0F_2E40 ^ e.key());
    let mut zeros = 0;
    'points: for _ in 0..attempts(&shape) {
        let seed = rng.next_u64();
        let mut branches = Branches::default();
        let (mut zero_somewhere, mut nonzero_somewhere) = (false, false);
        let mut signs = 0u64;
        // Branches are met as the evaluation goes: the loop runs over every sign pattern of
        // the branches known so far, which grows when a pattern meets a new one.
        while signs < 1 << branches.len() {
            // The same seed draws the same values in the same order: one point, every sign.
            let mut point = Point::seeded(seed);
            match eval_at(&order, &shape, &mut point, &mut branches, signs) {
                Ok(0) => zero_somewhere = true,
                Ok(_) => nonzero_somewhere = true,
                Err(Failure::Pole) => continue 'points,
                Err(Failure::Unsupported(r)) => return Err(r),
            }
            signs += 1;
        }
        if nonzero_somewhere {
            let proof = if shape.stand_ins {
                Err("a function of an expression the exact test can only treat as an unknown function (ln, or sin, cos or exp of a non-polynomial argument)")
            } else if zero_somewhere {
                Err("a square root or absolute value that vanishes on some of its signs only")
            } else {
                Ok(())
            };
            return Ok(Modular::NonZero { proof });
        }
        zeros += 1;
        if zeros == MODULAR_POINTS {
            return Ok(Modular::Zero { branches: branches.len() });
        }
    }
    // Poles at every point tried: the expression divides by something identically zero.
    Err("a denominator vanishes, or a square root has no value, at every point tried")
}

/// A real point where `e` is not zero (for a verdict already known to be "not zero"); the value
/// may be NaN where the expression has no real value there.
fn numeric_witness(e: Expr) -> ZeroVerdict {
    let (syms, applied) = e.symbols_and_applied();
    let mut rng = SplitMix(0x317_7E55 ^ e.key());
    let mut last = (f64::NAN, vec![]);
    for _ in 0..NUMERIC_POINTS {
        let (env, values) = random_env(&syms, &applied, &mut rng);
        if let Ok(v) = e.eval(&env) {
            if v.is_finite() && v != 0.0 {
                return ZeroVerdict::NonZero { value: v, at: named(&syms, &values) };
            }
            last = (v, values);
        }
    }
    ZeroVerdict::NonZero { value: last.0, at: named(&syms, &last.1) }
}

/// Values in `[0.1, 2)` for the symbols, and random smooth definitions for those `applied` as
/// named functions (every symbol draws its definition's numbers, so a point does not depend
/// on which are applied).
fn random_env(syms: &[Symbol], applied: &FxHashSet<Symbol>, rng: &mut SplitMix) -> (Env, Vec<f64>) {
    let mut env = Env::default();
    let mut values = Vec::with_capacity(syms.len());
    let arg = Symbol::internal("arg");
    for s in syms {
        let v = rng.uniform(0.1, 2.0);
        env.set(*s, v);
        let (a, b) = (rng.uniform(0.5, 1.5), rng.uniform(0.0, 1.0));
        if applied.contains(s) {
            let num = |x: f64| Expr::num(rat_from_f64(x).unwrap_or_else(Rat::one));
            env.define(*s, arg, (arg.expr() * num(a) + num(b)).sin());
        }
        values.push(v);
    }
    (env, values)
}

/// The point a witness was found at, by the symbols' names.
fn named(syms: &[Symbol], values: &[f64]) -> Vec<(String, f64)> {
    syms.iter().zip(values).map(|(s, v)| (s.name(), *v)).collect()
}

/// For what the exact test could not decide: a real point where `e` is clearly not zero (its
/// value beyond the rounding of its terms) makes it [`ZeroVerdict::NonZero`]; otherwise it is
/// [`ZeroVerdict::Undecided`], never zero.
fn numeric_check(e: Expr, reason: &'static str) -> ZeroVerdict {
    let (syms, applied) = e.symbols_and_applied();
    let mut rng = SplitMix(0x5EED_0F2E_4055 ^ e.key());
    for _ in 0..NUMERIC_POINTS {
        let (env, values) = random_env(&syms, &applied, &mut rng);
        let (Ok(value), Ok(scale)) = (e.eval(&env), magnitude(e, &env, 3)) else { continue };
        if !value.is_finite() || !scale.is_finite() {
            continue;
        }
        if value.abs() > 1e-10 * scale.max(1e-300) || (scale == 0.0 && value != 0.0) {
            return ZeroVerdict::NonZero { value, at: named(&syms, &values) };
        }
    }
    ZeroVerdict::Undecided { reason }
}

/// The size of the terms that make up `e`'s value at `env`, down to `depth` levels of sums and
/// products: a sum's is the sum of its terms' sizes, a product's the product of its factors'
/// (to their powers). Cancellation to rounding leaves the value near 1e-16 of it.
fn magnitude(e: Expr, env: &super::eval::Env, depth: u32) -> Result<f64, super::eval::EvalError> {
    if depth == 0 {
        return Ok(e.eval(env)?.abs());
    }
    match &*e.node() {
        Node::Add { constant, terms } => {
            let mut total = constant.to_f64().abs();
            for (t, c) in terms {
                total += c.to_f64().abs() * magnitude(*t, env, depth - 1)?;
            }
            Ok(total)
        }
        Node::Mul { coefficient, factors } => {
            let mut total = coefficient.to_f64().abs();
            for (b, x) in factors {
                let x = x.to_f64();
                // A divisor's own cancellation makes the quotient larger, not its terms.
                let size = if x > 0.0 { magnitude(*b, env, depth - 1)? } else { b.eval(env)?.abs() };
                total *= size.powf(x);
            }
            Ok(total)
        }
        _ => Ok(e.eval(env)?.abs()),
    }
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
        assert_eq!(zero_test(x.sin().powi(2) + x.cos().powi(2) - 1), ZeroVerdict::Zero { proof: ZeroProof::Modular { points: 2, branches: 0 } });
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
    fn rationals_map_to_the_field() {
        let value = |r: Rat| rat_mod(&r).ok().unwrap();
        assert_eq!(value(Rat::int(5)), 5);
        assert_eq!(value(Rat::int(-1)), P - 1);
        // A fraction is its numerator times its denominator's inverse: 2 * (1/2) = 1.
        assert_eq!(mulm(value(Rat::frac(1, 2)), 2), 1);
        assert_eq!(mulm(value(Rat::frac(-7, 3)), 3), P - 7);
    }

    #[test]
    fn a_witness_defines_the_functions_it_applies() {
        // The witness evaluates `F` by a random smooth stand-in: a finite, nonzero value at a
        // point that names every symbol, with `t` drawn from [0.1, 2).
        let (f, t, a) = (Symbol::new("F"), Expr::sym("t"), Expr::sym("a"));
        let e = Expr::apply_named(f, t * 2) * a - Expr::apply_named(f, t) * a;
        let ZeroVerdict::NonZero { value, at } = zero_test(e) else { panic!("F(2t) a - F(t) a is not zero") };
        assert!(value.is_finite() && value != 0.0, "{value}");
        let names: Vec<&str> = at.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["F", "a", "t"]);
        let t_value = at.iter().find(|(n, _)| n == "t").unwrap().1;
        assert!((0.1..2.0).contains(&t_value), "{t_value}");
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

    /// The issue's example: a floating-point test called this zero.
    #[test]
    fn a_near_miss_under_a_square_root_is_not_zero() {
        let x = Expr::sym("x");
        let tiny = Expr::num(Rat::frac(1, 1_000_000_000_000));
        assert!(zero_test((x + tiny).sqrt() - x.sqrt()).is_nonzero());
        assert!(zero_test((x + tiny).abs() - x.abs()).is_nonzero());
        assert!(zero_test((x + tiny).exp() - x.exp() * 2).is_nonzero());
        assert!(!zero((x + tiny).exp() - x.exp()));
        assert!(!zero((x + tiny).ln() - x.ln()));
    }

    #[test]
    fn square_roots_and_absolute_values_are_decided_on_every_branch() {
        let (x, y) = (Expr::sym("x"), Expr::sym("y"));
        let proof = |e: Expr| match zero_test(e) {
            ZeroVerdict::Zero { proof: ZeroProof::Modular { branches, .. } } => branches,
            z => panic!("{z:?}"),
        };
        assert_eq!(proof(((x + 1).sqrt() + 1) * ((x + 1).sqrt() - 1) - x), 1);
        assert_eq!(proof(((x * x + y).sqrt() + x) * ((x * x + y).sqrt() - x) - y), 1);
        assert_eq!(proof((x.abs() + 1) * (x.abs() - 1) - x * x + 1), 1);
        // A square root is a function of its radicand's value.
        assert_eq!(proof((x.sin().powi(2) + x.cos().powi(2) + y).sqrt() - (y + 1).sqrt()), 1);
        assert_eq!(proof(((x + 1).sqrt() + y.sqrt()) * ((x + 1).sqrt() - y.sqrt()) - x - 1 + y), 2);
        // True for x > 0 only: never "zero", never a false witness.
        assert_eq!(zero_test((x * x).sqrt() - x), ZeroVerdict::Undecided { reason: "a square root or absolute value that vanishes on some of its signs only" });
        assert!(matches!(zero_test(x.abs() - x), ZeroVerdict::Undecided { .. }));
        // The rounding of a sum inside a product is judged against the sum's terms.
        let k = Expr::sym("k");
        assert!(matches!(zero_test(-k * (x / (x * x).sqrt() - 1)), ZeroVerdict::Undecided { .. }));
        // Refuted with a real witness.
        assert!(zero_test(x.sqrt() - x).is_nonzero());
        assert!(zero_test((x * x).sqrt() + x).is_nonzero());
    }

    #[test]
    fn exponentials_of_sums_are_decided_exactly() {
        let (x, y) = (Expr::sym("x"), Expr::sym("y"));
        let exact = |e: Expr| matches!(zero_test(e), ZeroVerdict::Zero { proof: ZeroProof::Modular { .. } });
        assert!(exact(x.exp() * (-x).exp() - 1));
        assert!(exact((x + y).exp() - x.exp() * y.exp()));
        assert!(exact((x / 2).exp().powi(2) - x.exp()));
        assert!(exact((x + 2).exp() - x.exp() * Expr::int(2).exp()));
        // Atoms that are not symbols get a random base of their value: the homomorphism still
        // holds over them.
        assert!(exact(x.sin().exp().powi(2) - (x.sin() * 2).exp()));
        assert!(exact((x.sin() * 2).sin() - x.sin().sin() * x.sin().cos() * 2));
        assert!(exact((x.cos() + y.sin()).cos() - x.cos().cos() * y.sin().cos() + x.cos().sin() * y.sin().sin()));
        assert!(zero_test((x + y).exp() - x.exp() - y.exp()).is_nonzero());
    }

    /// Identities the exact test cannot prove are undecided and recorded, never zero.
    #[test]
    fn what_cannot_be_decided_is_undecided_and_recorded() {
        let x = Expr::sym("x");
        super::super::report::take();
        let cube_root = x.pow_rat(&Rat::frac(1, 3));
        for e in [(x * x).ln() - x.ln() * 2, (cube_root + 1) * (cube_root * cube_root - cube_root + 1) - x - 1, (x + 1).ln().exp() - x - 1] {
            assert!(matches!(zero_test(e), ZeroVerdict::Undecided { .. }), "{e}");
        }
        let cuts = super::super::report::take();
        assert_eq!(cuts.undecided.values().sum::<usize>(), 3, "{cuts:?}");
        assert!(cuts.undecided.contains_key("a fractional power other than a square root"), "{cuts:?}");
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn settle_absent_example() {
        use crate::symbolic::{
            Symbol,
            zero::{is_identically_zero, settle_absent},
        };
        let (a, b) = (Symbol::new("a"), Symbol::new("b"));
        // (cos a cos b + sin a sin b)^2 + (sin a cos b - cos a sin b)^2 = 1, for every a.
        let (ca, sa, cb, sb) = (a.expr().cos(), a.expr().sin(), b.expr().cos(), b.expr().sin());
        let e = (ca * cb + sa * sb).powi(2) + (sa * cb - ca * sb).powi(2) + b.expr();
        let settled = settle_absent(e, &[a]);
        assert!(!settled.contains(a) && is_identically_zero(settled - 1 - b.expr()));
        // 1 / sin(a) does depend on a.
        let f = b.expr() / a.expr().sin();
        assert_eq!(settle_absent(f, &[a]), f);
    }
}
