//! The output times of a run, and why some settings are not a run.

use std::fmt;

/// The most output intervals one run may have (its output times are one more): a run holds every sample in memory (the states and
/// the monitored invariants), so a million samples of a few dozen numbers stay under a gigabyte.
pub const MAX_OUTPUTS: usize = 1_000_000;

/// `x` as a person reads it: plain where that is short (`0.25`, `1500`), in exponent form where
/// the plain form would be long (`1e300`, not three hundred digits).
///
/// ```
/// assert_eq!(seam::short(0.25), "0.25");
/// assert_eq!(seam::short(1e300), "1e300");
/// assert_eq!(seam::short(-1e-300), "-1e-300");
/// ```
pub fn short(x: f64) -> String {
    let plain = format!("{x}");
    if plain.len() <= 12 { plain } else { format!("{x:e}") }
}

/// Why `(t_start, t_end, dt_out)` is not a run that can be sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GridError {
    /// Not finite, `t_end <= t_start`, or `dt_out <= 0`.
    NotARun { t_start: f64, t_end: f64, dt_out: f64 },
    /// `dt_out` is longer than the run: there would be no output inside it.
    StepLongerThanRun { span: f64, dt_out: f64 },
    /// More output times than [`MAX_OUTPUTS`].
    TooManyOutputs { count: f64 },
}

impl fmt::Display for GridError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            GridError::NotARun { t_start, t_end, dt_out } => {
                write!(
                    f,
                    "a run from t = {} to t_end = {} every dt_out = {} is not a run: use finite numbers with t_end > t_start and dt_out > 0",
                    short(t_start),
                    short(t_end),
                    short(dt_out)
                )
            }
            GridError::StepLongerThanRun { span, dt_out } => {
                write!(f, "dt_out = {} is longer than the run ({}): no output would fall inside it; use dt_out <= t_end - t_start", short(dt_out), short(span))
            }
            GridError::TooManyOutputs { count } => write!(
                f,
                "the run would have {count:.3e} output times, more than the {} a run may hold: use a larger dt_out or a shorter t_end",
                MAX_OUTPUTS + 1
            ),
        }
    }
}

impl std::error::Error for GridError {}

/// The output times of a run: `t_start, t_start + dt_out, ...`, and `t_end` exactly as the last
/// one (the step before it may be shorter), or why there are none.
///
/// ```
/// assert_eq!(seam::output_times(0.0, 1.0, 0.25), Ok(vec![0.0, 0.25, 0.5, 0.75, 1.0]));
/// assert_eq!(seam::output_times(0.0, 1.0, 0.6), Ok(vec![0.0, 0.6, 1.0]));
/// assert!(seam::output_times(0.0, 1.0, 100.0).is_err());
/// assert!(seam::output_times(0.0, 1e300, 0.01).unwrap_err().to_string().contains("dt_out"));
/// ```
pub fn output_times(t_start: f64, t_end: f64, dt_out: f64) -> Result<Vec<f64>, GridError> {
    let n = output_steps(t_start, t_end, dt_out)?;
    Ok((0..n).map(|i| t_start + i as f64 * dt_out).chain([t_end]).collect())
}

/// The number of output intervals of a run (one less than its output times): `(t_end -
/// t_start) / dt_out` rounded up, or rounded to the nearest where it is within `1e-9` of it
/// (`50 / 0.01` is 5000, not 5001).
pub fn output_steps(t_start: f64, t_end: f64, dt_out: f64) -> Result<usize, GridError> {
    if !(t_start.is_finite() && t_end.is_finite() && dt_out.is_finite() && t_end > t_start && dt_out > 0.0) {
        return Err(GridError::NotARun { t_start, t_end, dt_out });
    }
    let span = t_end - t_start;
    if !span.is_finite() {
        return Err(GridError::TooManyOutputs { count: f64::INFINITY });
    }
    if dt_out > span * (1.0 + 1e-12) {
        return Err(GridError::StepLongerThanRun { span, dt_out });
    }
    let ratio = span / dt_out;
    if !(ratio <= MAX_OUTPUTS as f64 + 0.5) {
        return Err(GridError::TooManyOutputs { count: ratio + 1.0 });
    }
    let nearest = ratio.round();
    let n = if (ratio - nearest).abs() <= 1e-9 * ratio.max(1.0) { nearest } else { ratio.ceil() };
    Ok((n as usize).max(1))
}
