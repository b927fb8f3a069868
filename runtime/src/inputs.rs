//! Inputs: the model's input parameters (`inputs` in a model file, `seam::Model::inputs`), set
//! at every call of its functions by a control law `u = k(t, q, q')`: a closure in Rust (a
//! controller), or time series read from CSV and interpolated linearly.

use std::fmt;
use std::sync::Arc;

/// A control law: `law(t, q, q', u)` writes the inputs `u`, in the order of the model's inputs.
pub type Law = dyn Fn(f64, &[f64], &[f64], &mut [f64]) + Send + Sync;

/// A control law a [`crate::system::System`] calls at every right-hand side.
///
/// ```
/// use runtime::inputs::Controller;
/// // A PD law on the first coordinate.
/// let pd = Controller::new(|_t, q, qd, u| u[0] = -10.0 * q[0] - 2.0 * qd[0]);
/// let mut u = [0.0];
/// pd.apply(0.0, &[0.1], &[0.0], &mut u);
/// assert_eq!(u, [-1.0]);
/// ```
#[derive(Clone)]
pub struct Controller {
    law: Arc<Law>,
    /// Times where the law has a kink (a time series' samples): a run stops there and starts
    /// again, rather than stepping across them.
    breaks: Arc<[f64]>,
}

impl Controller {
    pub fn new(law: impl Fn(f64, &[f64], &[f64], &mut [f64]) + Send + Sync + 'static) -> Controller {
        Controller { law: Arc::new(law), breaks: Arc::new([]) }
    }

    /// The inputs at `(t, q, q')`.
    pub fn apply(&self, t: f64, q: &[f64], qdot: &[f64], u: &mut [f64]) {
        (self.law)(t, q, qdot, u)
    }

    /// Inputs that follow time series, one per input in order; their samples' times are the
    /// law's breaks.
    ///
    /// ```
    /// use runtime::inputs::{Controller, TimeSeries};
    /// let c = Controller::series(vec![TimeSeries::parse("0,0\n1,2\n3,0\n").unwrap(), TimeSeries::parse("0,1\n1,1\n").unwrap()]);
    /// assert_eq!(c.breaks(), [0.0, 1.0, 3.0]);
    /// ```
    pub fn series(series: Vec<TimeSeries>) -> Controller {
        let mut breaks: Vec<f64> = series.iter().flat_map(|s| s.times.iter().copied()).collect();
        breaks.sort_by(f64::total_cmp);
        breaks.dedup();
        let law = move |t: f64, _: &[f64], _: &[f64], u: &mut [f64]| {
            for (u, s) in u.iter_mut().zip(&series) {
                *u = s.at(t);
            }
        };
        Controller { law: Arc::new(law), breaks: breaks.into() }
    }

    /// The times where the law has a kink, in order: an integrator's error estimate does not
    /// hold across them, so a run stops and starts again at each.
    pub fn breaks(&self) -> &[f64] {
        &self.breaks
    }
}

impl fmt::Debug for Controller {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Controller(..)")
    }
}

/// A time series `(t_k, v_k)`, interpolated linearly between its samples and held at its ends.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeSeries {
    times: Vec<f64>,
    values: Vec<f64>,
}

/// Why a time series was refused: the line (1-based) and what is wrong there.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("line {line}: {message}")]
pub struct SeriesError {
    pub line: usize,
    pub message: String,
}

/// A header's field: a name (`t`, `force (N)`), starting with a letter, not a number.
fn is_a_name(field: &str) -> bool {
    field.chars().next().is_some_and(|c| c.is_alphabetic() || c == '_') && field.parse::<f64>().is_err()
}

impl TimeSeries {
    /// Samples at increasing, finite times with finite values (at least one).
    pub fn new(times: Vec<f64>, values: Vec<f64>) -> Result<TimeSeries, SeriesError> {
        let bad = |line: usize, message: String| SeriesError { line, message };
        if times.is_empty() || times.len() != values.len() {
            return Err(bad(1, "a time series needs at least one sample `t,value`".into()));
        }
        for k in 0..times.len() {
            if !times[k].is_finite() || !values[k].is_finite() {
                return Err(bad(k + 1, format!("`{}, {}` is not a finite sample", times[k], values[k])));
            }
            if k > 0 && !(times[k] > times[k - 1]) {
                return Err(bad(k + 1, format!("time {} does not follow {}: the times must increase", times[k], times[k - 1])));
            }
        }
        Ok(TimeSeries { times, values })
    }

    /// Two columns `t,value` of CSV (a first line of names, `t,value`, is a header).
    ///
    /// ```
    /// let s = runtime::inputs::TimeSeries::parse("t,F\n0,0\n1,2\n").unwrap();
    /// assert_eq!((s.at(-1.0), s.at(0.25), s.at(5.0)), (0.0, 0.5, 2.0));
    /// assert!(runtime::inputs::TimeSeries::parse("0,1\n0,2\n").unwrap_err().to_string().contains("line 2"));
    /// // A first row with a typo is an error on line 1, not a header dropped silently.
    /// let e = runtime::inputs::TimeSeries::parse("0,O.5\n1,2\n").unwrap_err().to_string();
    /// assert!(e.contains("line 1") && e.contains("`O.5` is not a number"), "{e}");
    /// ```
    pub fn parse(text: &str) -> Result<TimeSeries, SeriesError> {
        let mut reader = csv::ReaderBuilder::new().has_headers(false).trim(csv::Trim::All).from_reader(text.as_bytes());
        let (mut times, mut values, mut lines) = (Vec::new(), Vec::new(), Vec::new());
        for (k, record) in reader.records().enumerate() {
            let record = record.map_err(|e| SeriesError { line: k + 1, message: e.to_string() })?;
            let number = |i: usize| record.get(i).and_then(|x| x.parse::<f64>().ok());
            match (number(0), number(1), record.len()) {
                (Some(t), Some(v), 2) => {
                    times.push(t);
                    values.push(v);
                    lines.push(k + 1);
                }
                // A header is recognised by its names (`t,value`), not by failing to parse: a
                // first row with a typo in a number is an error, not a header dropped silently.
                _ if k == 0 && record.iter().all(is_a_name) => {}
                _ => {
                    let bad: Vec<&str> = record.iter().filter(|x| x.parse::<f64>().is_err()).collect();
                    let message = match (record.len(), bad.first()) {
                        (2, Some(x)) => format!("`{}` is not a number: expected two numbers `t,value`", x.escape_debug()),
                        (n, _) => format!("{n} fields: expected two numbers `t,value`"),
                    };
                    return Err(SeriesError { line: k + 1, message });
                }
            }
        }
        TimeSeries::new(times, values).map_err(|mut e| {
            e.line = lines.get(e.line - 1).copied().unwrap_or(e.line);
            e
        })
    }

    /// The value at `t`.
    pub fn at(&self, t: f64) -> f64 {
        let k = self.times.partition_point(|x| *x <= t);
        if k == 0 {
            return self.values[0];
        }
        if k == self.times.len() {
            return self.values[k - 1];
        }
        let (t0, t1, v0, v1) = (self.times[k - 1], self.times[k], self.values[k - 1], self.values[k]);
        v0 + (v1 - v0) * (t - t0) / (t1 - t0)
    }
}
