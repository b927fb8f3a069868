//! Explicit limits for expensive passes, and the reason a pass stopped early.
//!
//! Every pass that can grow (expansion, the normal forms, elimination) takes a [`Limits`]
//! and, when it stops early, returns a [`StopReason`] naming the limit and where, like egg's
//! `Runner` and `StopReason`. Limits count work (terms, term products), never time, so the
//! same model gives the same output on any machine, however loaded.
//!
//! ```
//! use generator::symbolic::{Budget, Limits, StopReason};
//! let budget = Budget::start(Limits { max_terms: 10, max_work: 100 }, "expand");
//! assert!(budget.check(5).is_ok());
//! let stop = budget.check(12).unwrap_err();
//! assert_eq!(stop, StopReason::TermLimit { limit: 10, reached: 12, pass: "expand" });
//! assert!(stop.to_string().contains("expand"));
//! ```

use std::cell::Cell;

/// Limits for one expensive pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Most terms a sum may reach.
    pub max_terms: usize,
    /// Most units of work (terms created) the pass may spend in all.
    pub max_work: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits { max_terms: 20_000, max_work: 2_000_000 }
    }
}

/// Why a pass stopped before finishing.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum StopReason {
    /// A sum grew past `limit` terms.
    #[error("{pass} stopped: a sum reached {reached} terms (limit {limit})")]
    TermLimit { limit: usize, reached: usize, pass: &'static str },
    /// The pass spent its work budget.
    #[error("{pass} stopped: its work budget of {limit} term products is spent")]
    WorkLimit { limit: u64, pass: &'static str },
}

/// A started budget: checks the limits as a pass goes.
#[derive(Clone, Debug)]
pub struct Budget {
    limits: Limits,
    work: Cell<u64>,
    pass: &'static str,
}

impl Budget {
    /// A fresh budget for `pass`.
    pub fn start(limits: Limits, pass: &'static str) -> Budget {
        Budget { limits, work: Cell::new(0), pass }
    }

    /// Counts `terms` units of work; fails when a sum of `terms` is past the term limit or
    /// the work budget is spent.
    pub fn check(&self, terms: usize) -> Result<(), StopReason> {
        if terms > self.limits.max_terms {
            return Err(StopReason::TermLimit { limit: self.limits.max_terms, reached: terms, pass: self.pass });
        }
        let w = self.work.get() + terms as u64;
        self.work.set(w);
        if w > self.limits.max_work {
            return Err(StopReason::WorkLimit { limit: self.limits.max_work, pass: self.pass });
        }
        Ok(())
    }
}
