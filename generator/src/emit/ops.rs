//! Operation counts of emitted code: arithmetic operations and calls, per function.

use std::collections::BTreeMap;
use std::fmt;

/// Counts of the floating-point operations a function performs (straight-line code; a dense
/// solve is counted for its worst case).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct OpCount {
    /// Additions and subtractions.
    pub add: usize,
    /// Multiplications.
    pub mul: usize,
    /// Divisions.
    pub div: usize,
    /// Negations.
    pub neg: usize,
    /// Calls of `f64` functions by name (`sin`, `cos`, `sqrt`, `powi`, ...).
    pub calls: BTreeMap<&'static str, usize>,
}

impl OpCount {
    /// Records one call of `name`.
    pub fn call(&mut self, name: &'static str) {
        *self.calls.entry(name).or_default() += 1;
    }

    /// Number of calls of all functions.
    pub fn call_count(&self) -> usize {
        self.calls.values().sum()
    }

    /// All operations, each counted once.
    pub fn total(&self) -> usize {
        self.add + self.mul + self.div + self.neg + self.call_count()
    }

    /// Adds another count to this one.
    pub fn merge(&mut self, other: &OpCount) {
        self.add += other.add;
        self.mul += other.mul;
        self.div += other.div;
        self.neg += other.neg;
        for (k, v) in &other.calls {
            *self.calls.entry(k).or_default() += v;
        }
    }
}

impl fmt::Display for OpCount {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ops ({} add, {} mul, {} div, {} neg", self.total(), self.add, self.mul, self.div, self.neg)?;
        for (k, v) in &self.calls {
            write!(f, ", {v} {k}")?;
        }
        write!(f, ")")
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::emit::ops::OpCount;
        let mut a = OpCount::default();
        a.add += 2;
        a.call("sin");
        assert_eq!(a.total(), 3);
    }
}
