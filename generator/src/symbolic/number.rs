//! Rational numbers for coefficients and exponents: exact while they fit machine integers, and
//! integers exact at any size; a non-integer that outgrows them is rounded to a float
//! ([`Rat::inexact`]).
//!
//! A [`Rat`] is kept in machine integers (`i64` numerator and denominator, in lowest terms)
//! while it fits, and moves to a big-integer rational only on overflow. Multibody models
//! have small coefficients (`1/2`, `1/12`, `981/100`), so nearly every operation is a few
//! integer instructions; `perf` on a 12-link chain showed 50-60 % of the time in big-integer
//! gcd and division when every coefficient was a `BigRational`. `num-rational` has no such
//! hybrid, so this one is ours; it is checked against `BigRational` by property tests.
//!
//! ```
//! use generator::symbolic::{Rat, rat_from_decimal, rat_to_f64};
//! let g = rat_from_decimal("9.81").unwrap();
//! assert_eq!(g.to_string(), "981/100");
//! assert_eq!(rat_to_f64(&g), 9.81);
//! assert_eq!(Rat::frac(1, 2) + Rat::frac(1, 3), Rat::frac(5, 6));
//! ```

use num_bigint::BigInt;

use num_rational::BigRational;
use num_traits::{Signed, ToPrimitive};
use std::cmp::Ordering;
use std::fmt;

/// An exact rational number (see the module docs).
#[derive(Clone, PartialEq, Eq, Hash)]
pub struct Rat(Repr);

/// `Small(n, d)`: `d > 0`, `gcd(|n|, d) = 1`, `n != i64::MIN`. `Big` only for values that do
/// not fit `Small`, in lowest terms with a positive denominator, so equal values have equal
/// representations: equality and the hash compare the numerator and the denominator as they are.
/// (`BigRational`'s own `Eq` and `Hash` accept unreduced values, so they compare and hash through
/// a continued-fraction expansion, a big-integer division per step: on a humanoid's URDF, whose
/// 15-digit decimals make big rationals, that was a tenth of the derivation.)
#[derive(Clone)]
enum Repr {
    Small(i64, i64),
    Big(Box<BigRational>),
    /// An inexact number: a non-integer whose exact numerator or denominator outgrew `i64`,
    /// rounded to the nearest float (see [`Rat::inexact`]); never a value `Small` or `Big` can
    /// hold, so equal values still have equal representations.
    Float(f64),
}

impl PartialEq for Repr {
    fn eq(&self, other: &Repr) -> bool {
        match (self, other) {
            (Repr::Small(n1, d1), Repr::Small(n2, d2)) => n1 == n2 && d1 == d2,
            (Repr::Big(a), Repr::Big(b)) => a.numer() == b.numer() && a.denom() == b.denom(),
            (Repr::Float(a), Repr::Float(b)) => a.to_bits() == b.to_bits(),
            _ => false,
        }
    }
}

impl Eq for Repr {}

impl std::hash::Hash for Repr {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        match self {
            Repr::Small(n, d) => {
                state.write_u8(0);
                n.hash(state);
                d.hash(state);
            }
            Repr::Big(b) => {
                state.write_u8(1);
                b.numer().hash(state);
                b.denom().hash(state);
            }
            Repr::Float(x) => {
                state.write_u8(2);
                x.to_bits().hash(state);
            }
        }
    }
}

/// Binary gcd (no division: several times faster than Euclid's, whose steps on 128-bit words
/// were a 128-bit division each: `__umodti3`, a sixth of deriving a floating tree whose URDF has
/// long decimals, `perf`).
fn binary_gcd<T: num_traits::PrimInt>(a: T, b: T) -> T {
    if a.is_zero() {
        return b;
    }
    if b.is_zero() {
        return a;
    }
    let shift = (a | b).trailing_zeros() as usize;
    let (mut a, mut b) = (a >> a.trailing_zeros() as usize, b >> b.trailing_zeros() as usize);
    // A power of two against anything (the halves of product-to-sum coefficients): no loop.
    if a.is_one() || b.is_one() {
        return T::one() << shift;
    }
    loop {
        if a > b {
            std::mem::swap(&mut a, &mut b);
        }
        b = b - a;
        if b.is_zero() {
            return a << shift;
        }
        b = b >> b.trailing_zeros() as usize;
    }
}

/// On 64-bit words where both fit.
fn gcd_u128(a: u128, b: u128) -> u128 {
    if a <= u64::MAX as u128 && b <= u64::MAX as u128 { binary_gcd(a as u64, b as u64) as u128 } else { binary_gcd(a, b) }
}

/// `n / d` (`n, d > 0`, both below `2^127`) rounded to the nearest float, ties to even: the
/// quotient's bits by 128-bit division, up to 64 at a time, until more than 65 are known (the last ones and
/// whether the remainder is zero decide the rounding). `None` where the result would not be a
/// normal float (the caller's big-integer route handles those).
fn quotient_to_f64(n: u128, d: u128) -> Option<f64> {
    let (mut q, mut r, mut exp) = (n / d, n % d, 0i32);
    while q < (1u128 << 65) && r != 0 {
        // r < d < 2^127: r << k fits for k below r's leading zeros, and q << k below q's.
        let k = (r.leading_zeros().min(q.leading_zeros()) - 1).min(64);
        if k == 0 {
            return None;
        }
        let wide = r << k;
        q = (q << k) | (wide / d);
        r = wide % d;
        exp -= k as i32;
    }
    if q == 0 {
        return None;
    }
    let drop = (128 - q.leading_zeros()).saturating_sub(53);
    let mut mantissa = (q >> drop) as u64;
    if drop > 0 {
        let (dropped, half) = (q & ((1u128 << drop) - 1), 1u128 << (drop - 1));
        if dropped > half || (dropped == half && (r != 0 || mantissa & 1 == 1)) {
            mantissa += 1;
        }
    } else if r != 0 {
        // Not reached: the loop leaves a remainder only past 65 bits.
        return None;
    }
    let scale = exp + drop as i32;
    // mantissa <= 2^53: exact in a float; times a power of two within the normal range.
    (-1000..=1000).contains(&scale).then(|| mantissa as f64 * 2f64.powi(scale))
}

fn gcd_i64(a: i64, b: i64) -> i64 {
    binary_gcd(a.unsigned_abs(), b.unsigned_abs()) as i64
}

impl Rat {
    /// Zero.
    pub const ZERO: Rat = Rat(Repr::Small(0, 1));
    /// One.
    pub const ONE: Rat = Rat(Repr::Small(1, 1));

    /// Zero.
    pub fn zero() -> Rat {
        Rat::ZERO
    }

    /// One.
    pub fn one() -> Rat {
        Rat::ONE
    }

    /// An integer.
    pub fn int(n: i64) -> Rat {
        Rat::from_i128(n as i128, 1)
    }

    /// `n / d` in lowest terms. Panics when `d == 0` (a caller's bug, never input).
    pub fn frac(n: i64, d: i64) -> Rat {
        assert!(d != 0, "rational with zero denominator");
        Rat::from_i128(n as i128, d as i128)
    }

    /// `n / d` from 128-bit parts (`d != 0`).
    fn from_i128(n: i128, d: i128) -> Rat {
        if d == 1 && n > i64::MIN as i128 && n <= i64::MAX as i128 {
            return Rat(Repr::Small(n as i64, 1));
        }
        let (mut n, mut d) = if d < 0 { (-n, -d) } else { (n, d) };
        let g = gcd_u128(n.unsigned_abs(), d as u128) as i128;
        if g > 1 {
            n /= g;
            d /= g;
        }
        Rat::from_lowest_terms(n, d)
    }

    /// `n / d` in lowest terms (`d > 0`): machine integers where they fit; else an integer
    /// stays exact and any other rational becomes the nearest float, as [`Rat::from_big`] makes
    /// it, without big integers ([`quotient_to_f64`]): their conversion was a quarter of
    /// deriving a floating chain whose origins turn by 0.1 rad.
    fn from_lowest_terms(n: i128, d: i128) -> Rat {
        if n > i64::MIN as i128 && n <= i64::MAX as i128 && d <= i64::MAX as i128 {
            return Rat(Repr::Small(n as i64, d as i64));
        }
        match quotient_to_f64(n.unsigned_abs(), d as u128) {
            Some(x) if d != 1 => Rat::inexact(if n < 0 { -x } else { x }),
            _ => Rat::from_big(BigRational::new_raw(BigInt::from(n), BigInt::from(d))),
        }
    }

    /// From a big rational, moving back to machine integers when it fits; an integer stays
    /// exact, any other rational that does not fit becomes the nearest float ([`Rat::inexact`]).
    pub fn from_big(r: BigRational) -> Rat {
        match (r.numer().to_i64(), r.denom().to_i64()) {
            (Some(n), Some(d)) if n != i64::MIN => Rat(Repr::Small(n, d)),
            _ if r.is_integer() => Rat(Repr::Big(Box::new(r))),
            _ => Rat::inexact(r.to_f64().unwrap_or(f64::NAN)),
        }
    }

    /// The float `x` as a number: exact (`Small`, or `Big` for an integer beyond `i64`) where
    /// its value fits, else inexact. A rational whose numerator or denominator outgrows `i64`
    /// is rounded so: a URDF's 15-digit decimals (0.866025403783692, 0.500000000001294) made
    /// products of hundreds of digits whose gcds took 85 % of a floating anymal C's derivation,
    /// and every number the emitted code uses is a float anyway. Models written with small
    /// rationals (`1/2`, `981/100`) never overflow and stay exact.
    ///
    /// ```
    /// use generator::symbolic::Rat;
    /// assert_eq!(Rat::inexact(0.375), Rat::frac(3, 8));
    /// let tiny = Rat::frac(1, 1 << 40) * Rat::frac(1, 1 << 40);
    /// assert!(!tiny.is_exact() && tiny.to_f64() == 2f64.powi(-80));
    /// assert!((&tiny * &Rat::int(1 << 40) * Rat::int(1 << 40)).is_one());
    /// ```
    pub fn inexact(x: f64) -> Rat {
        if x == 0.0 {
            return Rat::ZERO;
        }
        if !x.is_finite() {
            return Rat(Repr::Float(x));
        }
        // x = m 2^e, m odd.
        let bits = x.to_bits();
        let exponent = ((bits >> 52) & 0x7ff) as i64;
        let fraction = bits & ((1u64 << 52) - 1);
        let (mut m, mut e) = if exponent == 0 { (fraction, -1074) } else { (fraction | (1u64 << 52), exponent - 1075) };
        let tz = m.trailing_zeros() as i64;
        m >>= tz;
        e += tz;
        let sign = if x < 0.0 { -1i64 } else { 1 };
        let width = 64 - m.leading_zeros() as i64;
        if e >= 0 {
            if width + e <= 126 {
                return Rat::from_i128(sign as i128 * ((m as i128) << e), 1);
            }
            return Rat(Repr::Big(Box::new(BigRational::from_integer(BigInt::from(sign) * (BigInt::from(m) << e as usize)))));
        }
        if -e <= 62 {
            return Rat(Repr::Small(sign * m as i64, 1i64 << -e));
        }
        Rat(Repr::Float(x))
    }

    /// False for a number held as a float: a value rounded by [`Rat::inexact`] that no machine
    /// fraction holds (a rounded value that one holds, `m / 2^k`, is held as that fraction).
    pub fn is_exact(&self) -> bool {
        !matches!(self.0, Repr::Float(_))
    }

    /// As a big rational.
    pub fn to_big(&self) -> BigRational {
        match &self.0 {
            Repr::Small(n, d) => BigRational::new_raw(BigInt::from(*n), BigInt::from(*d)),
            Repr::Big(b) => (**b).clone(),
            Repr::Float(x) => BigRational::from_float(*x).unwrap_or_default(),
        }
    }

    /// Numerator and denominator when both fit `i64` (the denominator is positive).
    pub fn as_i64_pair(&self) -> Option<(i64, i64)> {
        match self.0 {
            Repr::Small(n, d) => Some((n, d)),
            Repr::Big(_) | Repr::Float(_) => None,
        }
    }

    /// The numerator as a big integer.
    pub fn numer(&self) -> BigInt {
        match &self.0 {
            Repr::Small(n, _) => BigInt::from(*n),
            Repr::Big(b) => b.numer().clone(),
            Repr::Float(_) => self.to_big().numer().clone(),
        }
    }

    /// The (positive) denominator as a big integer.
    pub fn denom(&self) -> BigInt {
        match &self.0 {
            Repr::Small(_, d) => BigInt::from(*d),
            Repr::Big(b) => b.denom().clone(),
            Repr::Float(_) => self.to_big().denom().clone(),
        }
    }

    /// True for zero.
    pub fn is_zero(&self) -> bool {
        matches!(self.0, Repr::Small(0, _))
    }

    /// True for one.
    pub fn is_one(&self) -> bool {
        matches!(self.0, Repr::Small(1, 1))
    }

    /// True for an integer.
    pub fn is_integer(&self) -> bool {
        match &self.0 {
            Repr::Small(_, d) => *d == 1,
            Repr::Big(b) => b.is_integer(),
            Repr::Float(_) => false,
        }
    }

    /// The value as an `i64` when it is an integer that fits.
    pub fn to_i64(&self) -> Option<i64> {
        match self.0 {
            Repr::Small(n, 1) => Some(n),
            _ => None,
        }
    }

    /// The value as an `i32` when it is an integer that fits.
    pub fn to_i32(&self) -> Option<i32> {
        self.to_i64().and_then(|n| i32::try_from(n).ok())
    }

    /// True when negative.
    pub fn is_negative(&self) -> bool {
        match &self.0 {
            Repr::Small(n, _) => *n < 0,
            Repr::Big(b) => b.is_negative(),
            Repr::Float(x) => *x < 0.0,
        }
    }

    /// True when positive.
    pub fn is_positive(&self) -> bool {
        match &self.0 {
            Repr::Small(n, _) => *n > 0,
            Repr::Big(b) => b.is_positive(),
            Repr::Float(x) => *x > 0.0,
        }
    }

    /// The absolute value.
    pub fn abs(&self) -> Rat {
        if self.is_negative() { -self } else { self.clone() }
    }

    /// `1 / self`. Panics on zero (a caller's bug).
    pub fn recip(&self) -> Rat {
        match &self.0 {
            Repr::Small(n, d) => Rat::frac(*d, *n),
            Repr::Big(b) => Rat::from_big(b.recip()),
            Repr::Float(x) => Rat::inexact(1.0 / x),
        }
    }

    /// `self ^ p` for an integer power (`0 ^ negative` panics: callers check first).
    pub fn pow(&self, p: i32) -> Rat {
        if p < 0 {
            return self.recip().pow(-p);
        }
        let mut base = self.clone();
        let mut acc = Rat::one();
        let mut e = p as u32;
        while e > 0 {
            if e & 1 == 1 {
                acc = &acc * &base;
            }
            e >>= 1;
            if e > 0 {
                base = &base * &base;
            }
        }
        acc
    }

    /// The exact `q`-th root of a non-negative rational when it is one (`(8/27)^(1/3) = 2/3`).
    pub fn exact_root(&self, q: u32) -> Option<Rat> {
        if q == 0 || self.is_negative() || !self.is_exact() {
            return None;
        }
        let (n, d) = (self.numer(), self.denom());
        let (rn, rd) = (n.nth_root(q), d.nth_root(q));
        (num_traits::pow(rn.clone(), q as usize) == n && num_traits::pow(rd.clone(), q as usize) == d).then(|| Rat::from_big(BigRational::new(rn, rd)))
    }

    /// The nearest float (infinite when out of range).
    pub fn to_f64(&self) -> f64 {
        match &self.0 {
            Repr::Small(n, d) => {
                if *d == 1 {
                    *n as f64
                } else if n.unsigned_abs() < (1 << 53) && *d < (1 << 53) {
                    *n as f64 / *d as f64
                } else {
                    self.to_big().to_f64().unwrap_or(f64::NAN)
                }
            }
            Repr::Big(b) => b.to_f64().unwrap_or(f64::NAN),
            Repr::Float(x) => *x,
        }
    }

    /// Hash words of the value that do not depend on the platform: for structural keys.
    pub fn stable_words(&self) -> (u64, u64) {
        match &self.0 {
            Repr::Small(n, d) => (*n as u64, *d as u64),
            Repr::Big(b) => {
                let fold = |x: &BigInt| {
                    let (sign, digits) = x.to_u64_digits();
                    digits.iter().fold(sign as u64, |h, w| h.rotate_left(7) ^ w.wrapping_mul(0x9E37_79B9_7F4A_7C15))
                };
                (fold(b.numer()), fold(b.denom()) ^ 0xB16)
            }
            Repr::Float(x) => (x.to_bits(), 0xF10A7),
        }
    }
}

impl Default for Rat {
    fn default() -> Self {
        Rat::ZERO
    }
}

impl From<i64> for Rat {
    fn from(n: i64) -> Rat {
        Rat::int(n)
    }
}

impl fmt::Display for Rat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.0 {
            Repr::Small(n, 1) => write!(f, "{n}"),
            Repr::Small(n, d) => write!(f, "{n}/{d}"),
            Repr::Big(b) => write!(f, "{b}"),
            // The shortest decimal that reads back to the float.
            Repr::Float(x) => write!(f, "{x:?}"),
        }
    }
}

impl fmt::Debug for Rat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{self}")
    }
}

impl Ord for Rat {
    fn cmp(&self, other: &Rat) -> Ordering {
        match (&self.0, &other.0) {
            (Repr::Small(a, b), Repr::Small(c, d)) => ((*a as i128) * (*d as i128)).cmp(&((*c as i128) * (*b as i128))),
            (Repr::Float(a), Repr::Float(b)) => a.total_cmp(b),
            _ => self.to_big().cmp(&other.to_big()),
        }
    }
}

impl PartialOrd for Rat {
    fn partial_cmp(&self, other: &Rat) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

fn add(a: &Rat, b: &Rat) -> Rat {
    match (&a.0, &b.0) {
        (Repr::Small(0, _), _) => b.clone(),
        (_, Repr::Small(0, _)) => a.clone(),
        (Repr::Small(n1, 1), Repr::Small(n2, 1)) => match n1.checked_add(*n2) {
            Some(n) if n != i64::MIN => Rat(Repr::Small(n, 1)),
            _ => Rat::from_i128(*n1 as i128 + *n2 as i128, 1),
        },
        (Repr::Small(n1, d1), Repr::Small(n2, d2)) => {
            if d1 == d2 {
                return Rat::from_i128(*n1 as i128 + *n2 as i128, *d1 as i128);
            }
            Rat::from_i128(*n1 as i128 * *d2 as i128 + *n2 as i128 * *d1 as i128, *d1 as i128 * *d2 as i128)
        }
        (Repr::Float(_), _) | (_, Repr::Float(_)) => Rat::inexact(a.to_f64() + b.to_f64()),
        _ => Rat::from_big(a.to_big() + b.to_big()),
    }
}

fn mul(a: &Rat, b: &Rat) -> Rat {
    match (&a.0, &b.0) {
        (Repr::Small(0, _), _) | (_, Repr::Small(0, _)) => Rat::ZERO,
        (Repr::Small(1, 1), _) => b.clone(),
        (_, Repr::Small(1, 1)) => a.clone(),
        (Repr::Small(n1, 1), Repr::Small(n2, 1)) => match n1.checked_mul(*n2) {
            Some(n) if n != i64::MIN => Rat(Repr::Small(n, 1)),
            _ => Rat::from_i128(*n1 as i128 * *n2 as i128, 1),
        },
        (Repr::Small(n1, d1), Repr::Small(n2, d2)) => {
            let g1 = if *d2 == 1 { 1 } else { gcd_i64(*n1, *d2).max(1) };
            let g2 = if *d1 == 1 { 1 } else { gcd_i64(*n2, *d1).max(1) };
            // Integer division is slow: skipped where the gcd is one (coprime, the common case).
            let (n1, d2) = if g1 == 1 { (*n1, *d2) } else { (*n1 / g1, *d2 / g1) };
            let (n2, d1) = if g2 == 1 { (*n2, *d1) } else { (*n2 / g2, *d1 / g2) };
            let n = n1 as i128 * n2 as i128;
            let d = d1 as i128 * d2 as i128;
            // Cross-cancelled factors of coprime pairs: already in lowest terms.
            Rat::from_lowest_terms(n, d)
        }
        (Repr::Float(_), _) | (_, Repr::Float(_)) => Rat::inexact(a.to_f64() * b.to_f64()),
        _ => Rat::from_big(a.to_big() * b.to_big()),
    }
}

fn neg(a: &Rat) -> Rat {
    match &a.0 {
        Repr::Small(n, d) => Rat(Repr::Small(-n, *d)),
        Repr::Big(b) => Rat::from_big(-(**b).clone()),
        Repr::Float(x) => Rat(Repr::Float(-x)),
    }
}

fn div(a: &Rat, b: &Rat) -> Rat {
    // One rounding at most: the quotient of the exact values, not a product with a reciprocal
    // that may have been rounded already.
    match (&a.0, &b.0) {
        (Repr::Small(n1, d1), Repr::Small(n2, d2)) if *n2 != 0 => Rat::from_i128(*n1 as i128 * *d2 as i128, *d1 as i128 * *n2 as i128),
        (Repr::Float(_), _) | (_, Repr::Float(_)) => Rat::inexact(a.to_f64() / b.to_f64()),
        _ => mul(a, &b.recip()),
    }
}

macro_rules! binary_op {
    ($trait:ident, $method:ident, $f:ident, $assign:ident, $assign_method:ident) => {
        impl std::ops::$trait<&Rat> for &Rat {
            type Output = Rat;
            fn $method(self, o: &Rat) -> Rat {
                $f(self, o)
            }
        }
        impl std::ops::$trait<Rat> for Rat {
            type Output = Rat;
            fn $method(self, o: Rat) -> Rat {
                $f(&self, &o)
            }
        }
        impl std::ops::$trait<&Rat> for Rat {
            type Output = Rat;
            fn $method(self, o: &Rat) -> Rat {
                $f(&self, o)
            }
        }
        impl std::ops::$trait<Rat> for &Rat {
            type Output = Rat;
            fn $method(self, o: Rat) -> Rat {
                $f(self, &o)
            }
        }
        impl std::ops::$assign<Rat> for Rat {
            fn $assign_method(&mut self, o: Rat) {
                *self = $f(self, &o);
            }
        }
        impl std::ops::$assign<&Rat> for Rat {
            fn $assign_method(&mut self, o: &Rat) {
                *self = $f(self, o);
            }
        }
    };
}

binary_op!(Add, add, add, AddAssign, add_assign);
binary_op!(Mul, mul, mul, MulAssign, mul_assign);
binary_op!(Div, div, div, DivAssign, div_assign);

fn sub(a: &Rat, b: &Rat) -> Rat {
    add(a, &neg(b))
}
binary_op!(Sub, sub, sub, SubAssign, sub_assign);

impl std::ops::Neg for Rat {
    type Output = Rat;
    fn neg(self) -> Rat {
        neg(&self)
    }
}

impl std::ops::Neg for &Rat {
    type Output = Rat;
    fn neg(self) -> Rat {
        neg(self)
    }
}

/// An integer as a rational.
pub fn rat_from_i64(i: i64) -> Rat {
    Rat::int(i)
}

/// Largest decimal exponent a literal may carry: beyond it the value is outside the range of
/// `f64` (about 1.8e308, smallest subnormal 4.9e-324) and would only cost time as an exact
/// number.
pub const MAX_DECIMAL_EXPONENT: i64 = 330;

/// Most digits a literal may have (17 significant digits round-trip an `f64`).
pub const MAX_DECIMAL_DIGITS: usize = 40;

/// Parses a decimal literal (`12`, `9.81`, `1e-3`, `2.5E+2`) exactly. Literals whose value lies
/// outside the range of `f64`, or with more than `MAX_DECIMAL_DIGITS` digits, are refused.
pub fn rat_from_decimal(s: &str) -> Option<Rat> {
    let s = s.trim();
    let (mantissa, exponent) = match s.find(['e', 'E']) {
        Some(i) => (&s[..i], s[i + 1..].parse::<i64>().ok()?),
        None => (s, 0),
    };
    let (neg, mantissa) = match mantissa.strip_prefix('-') {
        Some(m) => (true, m),
        None => (false, mantissa.strip_prefix('+').unwrap_or(mantissa)),
    };
    let (int_part, frac_part) = match mantissa.find('.') {
        Some(i) => (&mantissa[..i], &mantissa[i + 1..]),
        None => (mantissa, ""),
    };
    if int_part.is_empty() && frac_part.is_empty() {
        return None;
    }
    if !int_part.chars().chain(frac_part.chars()).all(|c| c.is_ascii_digit()) {
        return None;
    }
    let digits = format!("{int_part}{frac_part}");
    let digits = digits.trim_start_matches('0');
    if digits.is_empty() {
        return Some(Rat::zero());
    }
    if digits.len() > MAX_DECIMAL_DIGITS {
        return None;
    }
    // Decimal exponent of the leading digit: the value lies in [10^lead, 10^(lead+1)).
    let scale = exponent - frac_part.len() as i64;
    let lead = scale + digits.len() as i64 - 1;
    if !(-MAX_DECIMAL_EXPONENT..=MAX_DECIMAL_EXPONENT).contains(&lead) {
        return None;
    }
    let n: BigInt = digits.parse().ok()?;
    let ten = BigInt::from(10);
    let r = if scale >= 0 {
        BigRational::from_integer(n * num_traits::pow(ten, scale as usize))
    } else {
        BigRational::new(n, num_traits::pow(ten, (-scale) as usize))
    };
    let r = Rat::from_big(r);
    if !r.to_f64().is_finite() {
        return None;
    }
    Some(if neg { -r } else { r })
}

/// The shortest decimal that round-trips the float, as an exact rational. NaN and infinities
/// have no rational value.
pub fn rat_from_f64(x: f64) -> Option<Rat> {
    if !x.is_finite() {
        return None;
    }
    rat_from_decimal(&format!("{x:e}"))
}

/// The nearest float.
pub fn rat_to_f64(r: &Rat) -> f64 {
    r.to_f64()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The binary gcd on 128-bit words is Euclid's, on words of every size (both beyond 64 bits,
    /// one beyond, powers of two, zero).
    #[test]
    fn the_binary_gcd_of_wide_words_is_euclid_s() {
        fn euclid(mut a: u128, mut b: u128) -> u128 {
            while b != 0 {
                (a, b) = (b, a % b);
            }
            a
        }
        let mut x: u128 = 0x9E37_79B9_7F4A_7C15_F39C_C060_5CED_C834;
        let mut words = vec![0, 1, 2, 3, 1 << 64, (1 << 64) + 1, 3 << 100, u128::MAX, u64::MAX as u128, 6 * 10u128.pow(30), 4 * 10u128.pow(30)];
        for _ in 0..200 {
            // xorshift: wide words, and words sharing factors (a product with a small one).
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            words.push(x >> (x % 100) as u32);
            words.push((x >> 70) * 360);
        }
        for a in &words {
            for b in words.iter().step_by(7) {
                assert_eq!(gcd_u128(*a, *b), euclid(*a, *b), "gcd({a}, {b})");
            }
        }
    }

    /// The quotient of wide words rounds as the big rationals' conversion does (to the nearest
    /// float, ties to even), on quotients of every size, ties and exact ones among them.
    #[test]
    fn the_quotient_of_wide_words_is_the_big_rational_s_float() {
        let big = |n: u128, d: u128| BigRational::new(BigInt::from(n), BigInt::from(d)).to_f64().unwrap();
        let mut x: u128 = 0x2545_F491_4F6C_DD1D_9E37_79B9_7F4A_7C15;
        let mut pairs =
            vec![(1, 3), (2, 3), (1, 10), (7, 1 << 60), ((1 << 53) + 1, 1), ((1 << 54) + 2, 4), (3 << 100, 7), (1, (1 << 125) + 1), ((1 << 125) - 1, 3)];
        // Ties: an odd 54-bit numerator over 2 rounds to even.
        pairs.extend([((1u128 << 53) + 1, 2), ((1u128 << 53) + 3, 2), ((1u128 << 80) + (1 << 27), 1 << 20)]);
        for _ in 0..20_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let (n, d) = ((x >> 2) >> (x % 120) as u32, ((x.rotate_left(64) >> 2) >> ((x >> 8) % 120) as u32).max(1));
            pairs.push((n.max(1), d));
        }
        let mut checked = 0;
        for (n, d) in pairs {
            if let Some(q) = quotient_to_f64(n, d) {
                assert_eq!(q.to_bits(), big(n, d).to_bits(), "{n} / {d}");
                checked += 1;
            }
        }
        assert!(checked > 19_000, "{checked}");
        // In the arithmetic: a product that outgrows machine integers, as the big route made it.
        let (a, b) = (Rat::frac(994_996_671_102_073_589, 999_999_999_999_999_999), Rat::frac(99_833_416_646_828_153, 1_000_000_000_000_000_007));
        let wide = BigRational::new(BigInt::from(994_996_671_102_073_589i64), BigInt::from(999_999_999_999_999_999i64))
            * BigRational::new(BigInt::from(99_833_416_646_828_153i64), BigInt::from(1_000_000_000_000_000_007i64));
        assert_eq!((&a * &b).to_f64().to_bits(), wide.to_f64().unwrap().to_bits());
    }

    #[test]
    fn decimals_are_exact() {
        assert_eq!(rat_from_decimal("0.5").unwrap(), Rat::frac(1, 2));
        assert_eq!(rat_from_decimal("-1e-3").unwrap(), Rat::frac(-1, 1000));
        assert_eq!(rat_from_decimal("2.5E+2").unwrap(), rat_from_i64(250));
        assert!(rat_from_decimal("1.2.3").is_none());
        assert!(rat_from_decimal("").is_none());
        assert_eq!(rat_to_f64(&rat_from_f64(0.1).unwrap()), 0.1);
        assert_eq!(rat_to_f64(&rat_from_f64(-0.018).unwrap()), -0.018);
        assert_eq!(rat_to_f64(&rat_from_f64(f64::MAX).unwrap()), f64::MAX);
        assert_eq!(rat_to_f64(&rat_from_f64(5e-324).unwrap()), 5e-324);
    }

    #[test]
    fn literals_outside_f64_are_refused() {
        assert!(rat_from_decimal("1e10000").is_none());
        assert!(rat_from_decimal("1e999999999").is_none());
        assert!(rat_from_decimal("1e400").is_none());
        assert!(rat_from_decimal(&"9".repeat(50_000)).is_none());
        assert!(rat_from_decimal("1e-400").is_none());
        assert_eq!(rat_from_decimal("0e999999").unwrap(), Rat::zero());
    }

    /// Products of a URDF's 15-digit decimals outgrow `i64`: they are rounded to the nearest
    /// float (and stay inexact through sums and products, each within a rounding of the exact
    /// value), never equal to an exact number, and the same operations give the same bits.
    #[test]
    fn rationals_that_outgrow_machine_integers_are_rounded() {
        let (c, s) = (rat_from_decimal("0.866025403783692").unwrap(), rat_from_decimal("0.500000000001294").unwrap());
        assert!(c.is_exact() && s.is_exact());
        let cc = &c * &c;
        let exact = c.to_big() * c.to_big();
        assert!(cc.to_big() != exact && cc.to_f64() == exact.to_f64().unwrap(), "{cc}");
        // Rounded, it is a float's value: a machine fraction over a power of two here, held
        // as a float where none holds it (2^-80).
        assert!(cc.as_i64_pair().is_some_and(|(_, d)| d.count_ones() == 1));
        assert!(!(&cc * &Rat::frac(1, 1 << 40) * Rat::frac(1, 1 << 40)).is_exact());
        let sum = &cc + &(&s * &s);
        let exact_sum = exact + s.to_big() * s.to_big();
        assert!((sum.to_f64() - exact_sum.to_f64().unwrap()).abs() <= 2.0 * f64::EPSILON, "{sum}");
        assert_ne!(cc, Rat::frac(3, 4));
        assert_eq!(&c * &c, cc);
        assert!((&cc - &cc).is_zero());
        // A float that a machine fraction holds is that fraction again.
        assert_eq!(&cc * &Rat::zero(), Rat::zero());
        assert_eq!(Rat::inexact(-0.25), Rat::frac(-1, 4));
        assert_eq!(Rat::inexact(2f64.powi(70)), Rat::int(1 << 35) * Rat::int(1 << 35));
        // Small rationals stay exact: a power of a third, and back.
        let p = Rat::frac(1, 3).pow(30);
        assert!(p.is_exact() == (p.as_i64_pair().is_some()));
        assert!(cc < Rat::one() && cc > Rat::frac(1, 2) && -&cc < Rat::zero());
    }

    #[test]
    fn overflow_moves_to_big_integers_and_back() {
        let big = Rat::int(i64::MAX);
        let twice = &big + &big;
        assert_eq!(twice.as_i64_pair(), None);
        assert_eq!(twice.to_string(), "18446744073709551614");
        let back = &twice - &big;
        assert_eq!(back, big);
        assert_eq!(back.as_i64_pair(), Some((i64::MAX, 1)));
        assert_eq!(Rat::int(i64::MIN).to_string(), i64::MIN.to_string());
        assert_eq!(-Rat::int(i64::MIN), Rat::from_big(BigRational::from_integer(BigInt::from(i64::MIN).abs())));
        let third = Rat::frac(1, 3);
        assert_eq!(third.pow(3), Rat::frac(1, 27));
        assert_eq!(Rat::frac(8, 27).exact_root(3), Some(Rat::frac(2, 3)));
        assert_eq!(Rat::int(2).exact_root(2), None);
        assert!(Rat::frac(-1, 2) < Rat::frac(1, 3));
    }
}
