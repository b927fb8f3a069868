//! The one error type every model function returns, compiled or evaluated in-process.

use std::borrow::Cow;
use std::fmt;

/// Why a model function could not produce a value.
///
/// Names are `'static` in compiled modules and owned in models evaluated in-process, hence the
/// `Cow`s; nothing is allocated unless a function fails.
#[derive(Clone, Debug, PartialEq)]
pub enum Failure {
    /// The equations are singular at time `t`: `condition`, a factor of a symbolically solved
    /// matrix or a pivot of the articulated-body recursion, vanishes (`value` is its value).
    Singular { t: f64, condition: Cow<'static, str>, value: f64 },
    /// A numerical solve of `matrix` found no usable pivot in `column` (counted from 0) at time
    /// `t`: the matrix is singular there (or, for `L D L^T`, not positive definite).
    SingularMatrix { t: f64, matrix: Cow<'static, str>, column: usize },
    /// Output `index` is not a finite number at time `t`.
    NonFinite { t: f64, index: usize },
    /// A state violates `constraint`: its residual exceeds the tolerance.
    ConstraintViolated { constraint: Cow<'static, str>, residual: f64, tolerance: f64 },
    /// A slice argument has the wrong length.
    Dimension { argument: &'static str, expected: usize, got: usize },
    /// The model was emitted without this function (the model file's `emit.functions`).
    Missing { function: &'static str },
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Failure::Singular { t, condition, value } => {
                write!(f, "singular configuration at t = {t}: {condition} (value {value:e})")
            }
            Failure::SingularMatrix { t, matrix, column } => {
                write!(f, "singular configuration at t = {t}: {matrix} has no usable pivot in column {column}")
            }
            Failure::NonFinite { t, index } => write!(f, "non-finite value in output {index} at t = {t}"),
            Failure::ConstraintViolated { constraint, residual, tolerance } => {
                write!(f, "constraint `{constraint}` is violated: residual {residual:e} exceeds {tolerance:e}")
            }
            Failure::Dimension { argument, expected, got } => {
                write!(f, "`{argument}` has {got} entries, {expected} expected")
            }
            Failure::Missing { function } => {
                write!(f, "the module was emitted without `{function}`: add it to `emit.functions` in the model file")
            }
        }
    }
}

impl std::error::Error for Failure {}
