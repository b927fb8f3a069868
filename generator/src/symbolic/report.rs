//! What a derivation could not decide exactly or cut for a budget: collected where it happens,
//! reported with the result (the generation summary, `inspect`, a warning on stderr), never
//! silent.
//!
//! Each thread collects its own [`Cuts`] (a derivation runs on one thread, its emission partly
//! on a second); an entry point [`take`]s them before it starts and after it ends, and merges
//! the threads' ([`Cuts::merge`]).

use std::cell::RefCell;
use std::collections::BTreeMap;

/// What budgets cut and which questions stayed undecided, with the safe side each took.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Cuts {
    /// Zero tests that could not decide, by the reason the exact test gave: each answered
    /// "not known to be zero", so the term was kept.
    pub undecided: BTreeMap<String, usize>,
    /// Normal forms inside the symbolic solver that a term or work limit stopped (the entry was
    /// kept as built: exact, only larger).
    pub solver_stops: usize,
    /// Decisions taken on the safe side for want of an answer, and routes that fell back to
    /// another, in words: the equations are exact.
    pub notes: Vec<String>,
    /// What the user should act on: a decision that changes what the model does (a run that
    /// stops where an undecided pivot vanishes; an automatic choice that left a coordinate out).
    pub warnings: Vec<String>,
}

impl Cuts {
    /// True when nothing was cut and every question was decided.
    pub fn is_empty(&self) -> bool {
        self.undecided.is_empty() && self.solver_stops == 0 && self.notes.is_empty() && self.warnings.is_empty()
    }

    /// Adds `other`'s entries (another thread's) to these.
    pub fn merge(&mut self, other: Cuts) {
        for (reason, n) in other.undecided {
            *self.undecided.entry(reason).or_default() += n;
        }
        self.solver_stops += other.solver_stops;
        for note in other.notes {
            self.note(note);
        }
        for warning in other.warnings {
            self.warn(warning);
        }
    }

    /// Adds a warning, once.
    pub fn warn(&mut self, warning: String) {
        if !self.warnings.contains(&warning) {
            self.warnings.push(warning);
        }
    }

    /// Adds a note in words, once.
    pub fn note(&mut self, note: String) {
        if !self.notes.contains(&note) {
            self.notes.push(note);
        }
    }

    /// One line per kind of cut, for a summary: the quiet ones (exact equations) first, then
    /// the [`Cuts::warnings`].
    pub fn lines(&self) -> Vec<String> {
        let mut out = self.quiet_lines();
        out.extend(self.warnings.iter().cloned());
        out
    }

    /// The cuts that leave the equations exact (undecided terms kept, solver entries kept as
    /// built, notes): for a summary and `inspect`, not a warning at every load.
    pub fn quiet_lines(&self) -> Vec<String> {
        let mut out = Vec::new();
        for (reason, n) in &self.undecided {
            out.push(format!("{n} zero test(s) could not be decided exactly ({reason}): the terms were kept"));
        }
        if self.solver_stops > 0 {
            out.push(format!("{} entries of a symbolic solve hit the solver's term or work limit (kept as built)", self.solver_stops));
        }
        out.extend(self.notes.iter().cloned());
        out
    }
}

thread_local! {
    static CUTS: RefCell<Cuts> = RefCell::new(Cuts::default());
}

/// Records a cut on this thread.
pub fn record(f: impl FnOnce(&mut Cuts)) {
    CUTS.with(|c| f(&mut c.borrow_mut()));
}

/// This thread's cuts since the last `take`, leaving none.
pub fn take() -> Cuts {
    CUTS.with(|c| std::mem::take(&mut *c.borrow_mut()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merging_adds_counts_and_keeps_notes_once() {
        let mut a = Cuts { undecided: [("sqrt".to_string(), 2)].into(), solver_stops: 1, notes: vec!["n".into()], warnings: vec!["w".into()] };
        a.merge(Cuts {
            undecided: [("sqrt".to_string(), 3), ("ln".to_string(), 1)].into(),
            solver_stops: 2,
            notes: vec!["n".into(), "m".into()],
            warnings: vec!["w".into()],
        });
        assert_eq!(a.undecided["sqrt"], 5);
        assert_eq!(a.undecided["ln"], 1);
        assert_eq!(a.solver_stops, 3);
        assert_eq!(a.notes, ["n", "m"]);
        assert_eq!(a.warnings, ["w"]);
        assert_eq!((a.lines().len(), a.quiet_lines().len()), (6, 5));
        assert!(Cuts::default().is_empty() && !a.is_empty());
    }

    #[test]
    fn each_thread_collects_its_own() {
        take();
        record(|c| c.solver_stops += 1);
        let other = std::thread::spawn(|| {
            record(|c| c.solver_stops += 5);
            take()
        })
        .join()
        .unwrap();
        assert_eq!(other.solver_stops, 5);
        assert_eq!(take().solver_stops, 1);
        assert!(take().is_empty());
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::symbolic::{Expr, report, zero::zero_test};
        report::take();
        let x = Expr::sym("x");
        // ln(x^2) = 2 ln(x) for x > 0 only: the exact test cannot prove it, the floats cannot refute it.
        assert!(!zero_test((x * x).ln() - x.ln() * 2).is_zero());
        let cuts = report::take();
        assert_eq!(cuts.undecided.values().sum::<usize>(), 1);
        assert!(cuts.lines()[0].contains("could not be decided"), "{:?}", cuts.lines());
    }
}
