//! The checks every model's functions make on what they computed, written once: emitted modules
//! and the in-process evaluator call them, so both report the same failure at the same place.
//!
//! ```
//! use seam::{Failure, check};
//! assert!(check::finite(0.5, &[1.0, 2.0]).is_ok());
//! assert!(matches!(check::finite(0.5, &[1.0, f64::NAN]), Err(Failure::NonFinite { index: 1, .. })));
//! // A factor of a symbolically solved matrix too close to zero: singular.
//! let conditions = ["cos(theta)", "l"];
//! let err = check::nonsingular(0.5, &conditions, &[0.3, 1e-15], 1e-12).unwrap_err();
//! assert!(matches!(err, Failure::Singular { ref condition, .. } if condition == "l"));
//! ```

use crate::Failure;
use std::borrow::Cow;

/// `Err(Failure::NonFinite)` naming the first entry of `values` that is not finite.
#[inline]
pub fn finite(t: f64, values: &[f64]) -> Result<(), Failure> {
    finite_after(t, 0, values)
}

/// [`finite`] for entries numbered from `offset` (a second output after a first of that length).
#[inline]
pub fn finite_after(t: f64, offset: usize, values: &[f64]) -> Result<(), Failure> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(k) => Err(Failure::NonFinite { t, index: offset + k }),
    }
}

/// `Err(Failure::Singular)` naming the first of the `conditions` whose value's magnitude is not
/// above `tolerance` (a NaN included): the factors whose vanishing makes a symbolically solved
/// matrix singular.
#[inline]
pub fn nonsingular<S: Clone + Into<Cow<'static, str>>>(t: f64, conditions: &[S], values: &[f64], tolerance: f64) -> Result<(), Failure> {
    for (condition, &value) in conditions.iter().zip(values) {
        if !(value.abs() > tolerance) {
            return Err(Failure::Singular { t, condition: condition.clone().into(), value });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_failure_is_named_with_its_place() {
        assert!(matches!(finite_after(1.0, 4, &[0.0, f64::INFINITY, f64::NAN]), Err(Failure::NonFinite { index: 5, .. })));
        let names = vec!["a".to_string(), "b".to_string()];
        assert!(nonsingular(2.0, &names, &[1.0, 2.0], 1e-12).is_ok());
        let err = nonsingular(2.0, &names, &[f64::NAN, 0.0], 1e-12).unwrap_err();
        assert!(matches!(err, Failure::Singular { ref condition, t, .. } if condition == "a" && t == 2.0));
    }
}
