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

/// `Err(Failure::ConstraintViolated)` naming the first constraint whose residual's magnitude
/// is not within `relative` times its bound (a NaN included): each entry is the constraint's
/// name, its residual and the bound it is measured against (the sum of its terms' magnitudes,
/// so that the tolerance scales with what the constraint adds up).
///
/// ```
/// use seam::{Failure, check};
/// assert!(check::satisfied([("wheel", 1e-15, 2.0)], 1e-9).is_ok());
/// let err = check::satisfied([("wheel", 1e-15, 2.0), ("rope", 1e-3, 1.0)], 1e-9).unwrap_err();
/// assert!(matches!(err, Failure::ConstraintViolated { ref constraint, .. } if constraint == "rope"));
/// ```
#[inline]
pub fn satisfied<S: Into<Cow<'static, str>>>(entries: impl IntoIterator<Item = (S, f64, f64)>, relative: f64) -> Result<(), Failure> {
    for (constraint, residual, bound) in entries {
        let tolerance = relative * bound;
        if !(residual.abs() <= tolerance) {
            return Err(Failure::ConstraintViolated { constraint: constraint.into(), residual, tolerance });
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
        let err = satisfied([("a".to_string(), f64::NAN, 1.0)], 1e-9).unwrap_err();
        assert!(matches!(err, Failure::ConstraintViolated { ref constraint, .. } if constraint == "a"));
        assert!(satisfied(Vec::<(&'static str, f64, f64)>::new(), 1e-9).is_ok());
    }
}
