//! Explicit limits for expensive passes, and the reason a pass stopped early.
//!
//! Every pass that can grow (expansion, trigonometric normal form, elimination) takes a
//! [`Limits`] and, when it stops early, returns a [`StopReason`] naming the limit and where,
//! like egg's `Runner` and `StopReason`.
//!
//! ```
//! use generator::symbolic::limits::{Limits, StopReason};
//! let limits = Limits { max_terms: 10, ..Limits::default() };
//! let stop = StopReason::TermLimit { limit: limits.max_terms, reached: 12, pass: "expand" };
//! assert!(stop.to_string().contains("expand"));
//! ```

use std::time::{Duration, Instant};

/// Limits for one expensive pass.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// Most terms a sum may reach while expanding.
    pub max_terms: usize,
    /// Wall-clock budget for the pass.
    pub max_time: Duration,
}

impl Default for Limits {
    fn default() -> Self {
        Limits { max_terms: 20_000, max_time: Duration::from_secs(10) }
    }
}

/// Why a pass stopped before finishing.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum StopReason {
    /// A sum grew past `limit` terms.
    #[error("{pass} stopped: a sum reached {reached} terms (limit {limit})")]
    TermLimit { limit: usize, reached: usize, pass: &'static str },
    /// The pass ran out of time.
    #[error("{pass} stopped: time limit of {limit_ms} ms reached")]
    TimeLimit { limit_ms: u128, pass: &'static str },
}

/// A started budget: checks the limits as a pass goes.
#[derive(Clone, Copy, Debug)]
pub struct Budget {
    limits: Limits,
    start: Instant,
    pass: &'static str,
}

impl Budget {
    /// Starts the clock for `pass`.
    pub fn start(limits: Limits, pass: &'static str) -> Budget {
        Budget { limits, start: Instant::now(), pass }
    }

    /// Fails when `terms` is past the term limit or the time is up.
    pub fn check(&self, terms: usize) -> Result<(), StopReason> {
        if terms > self.limits.max_terms {
            return Err(StopReason::TermLimit { limit: self.limits.max_terms, reached: terms, pass: self.pass });
        }
        if self.start.elapsed() > self.limits.max_time {
            return Err(StopReason::TimeLimit { limit_ms: self.limits.max_time.as_millis(), pass: self.pass });
        }
        Ok(())
    }
}
