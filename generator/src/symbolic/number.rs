//! Exact rational numbers for coefficients and exponents.
//!
//! ```
//! use generator::symbolic::number::{rat_from_decimal, rat_to_f64};
//! let g = rat_from_decimal("9.81").unwrap();
//! assert_eq!(g.to_string(), "981/100");
//! assert_eq!(rat_to_f64(&g), 9.81);
//! ```

use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, ToPrimitive, Zero};

/// The exact rational type used for every coefficient and exponent.
pub type Rat = BigRational;

/// An integer as a rational.
pub fn rat_from_i64(i: i64) -> Rat {
    Rat::from_integer(BigInt::from(i))
}

/// Parses a decimal literal (`12`, `9.81`, `1e-3`, `2.5E+2`) exactly.
pub fn rat_from_decimal(s: &str) -> Option<Rat> {
    let s = s.trim();
    let (mantissa, exponent) = match s.find(['e', 'E']) {
        Some(i) => (&s[..i], s[i + 1..].parse::<i32>().ok()?),
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
    let n: BigInt = if digits.is_empty() { BigInt::zero() } else { digits.parse().ok()? };
    let scale = exponent - frac_part.len() as i32;
    let ten = BigInt::from(10);
    let mut r = Rat::from_integer(n);
    if scale >= 0 {
        r *= Rat::from_integer(num_traits::pow::Pow::pow(&ten, scale as u32));
    } else {
        r /= Rat::from_integer(num_traits::pow::Pow::pow(&ten, (-scale) as u32));
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
    if r.denom().is_one() {
        return r.numer().to_f64().unwrap_or(f64::NAN);
    }
    match (r.numer().to_f64(), r.denom().to_f64()) {
        (Some(n), Some(d)) if n.is_finite() && d.is_finite() && n.abs() < 9.0e15 && d < 9.0e15 => n / d,
        _ => r.to_f64().unwrap_or(f64::NAN),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimals_are_exact() {
        assert_eq!(rat_from_decimal("0.5").unwrap(), Rat::new(1.into(), 2.into()));
        assert_eq!(rat_from_decimal("-1e-3").unwrap(), Rat::new((-1).into(), 1000.into()));
        assert_eq!(rat_from_decimal("2.5E+2").unwrap(), rat_from_i64(250));
        assert!(rat_from_decimal("1.2.3").is_none());
        assert!(rat_from_decimal("").is_none());
        assert_eq!(rat_to_f64(&rat_from_f64(0.1).unwrap()), 0.1);
        assert_eq!(rat_to_f64(&rat_from_f64(-0.018).unwrap()), -0.018);
    }
}
