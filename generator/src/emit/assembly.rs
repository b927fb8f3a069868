//! How a right-hand side assembles its matrix and forcing: the dense form's entries, or the
//! recursion over the tree of frames (`formulation::composite`), whichever the emitted
//! code computes in fewer operations (both bodies are built: a count before the emitter's
//! sharing, [`crate::symbolic::expr::dag_ops`], picks wrongly on the 20-link pendulum and on
//! scene 2's reduced form). One rule, for emission, the summary and `inspect`.

/// True when the recursion's `by_tree` operations are fewer than the dense entries'
/// `by_entries`.
pub fn prefers_recursion(by_tree: usize, by_entries: usize) -> bool {
    by_tree < by_entries
}

/// True when the articulated-body recursion's `by_recursion` operations are fewer than those
/// of the matrix's assembly and its solve together, `by_matrix`.
pub fn prefers_articulated(by_recursion: usize, by_matrix: usize) -> bool {
    by_recursion < by_matrix
}

/// True when the articulated-body recursion's `by_recursion` operations are already fewer than
/// the matrix's solve alone, `solve`: it then wins whatever the matrix's assembly costs
/// ([`prefers_articulated`] with an assembly of zero operations), and the matrix's bodies need
/// not be built to decide (the 60-link pendulum's Kane: 7923 against a solve of 84912).
pub fn beats_solve_alone(by_recursion: usize, solve: usize) -> bool {
    prefers_articulated(by_recursion, solve)
}

/// True where the articulated-body recursion may win and its body is worth building: its
/// program's operations before the emitter's sharing, `articulated`, are at most the
/// composite-body recursion's, `composite` (counted the same way), and the solve it saves
/// together (a tie is built: the emitted counts decide). Where it is more, it only adds to the composite recursion what the solve would
/// cost (scene 2's Kane: 1028 against 746 + 241 before sharing; 846 against 454 + 241 once emitted).
/// Without a composite recursion to compare with, it is built.
pub fn worth_building_articulated(articulated: usize, composite: Option<usize>, solve: usize) -> bool {
    composite.is_none_or(|c| articulated <= c + solve)
}

/// The summary's and `inspect`'s line for a right-hand side: how it solves, then how it
/// assembles.
pub(super) fn summary_line(solve: &super::ldl::Solve, assembly: &str) -> String {
    format!("{}; {assembly}", solve.describe())
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::emit::assembly::prefers_recursion;
        assert!(prefers_recursion(900, 1000));
        assert!(!prefers_recursion(1000, 1000)); // a tie keeps the dense entries
    }
    #[test]
    fn prefers_articulated_example() {
        use crate::emit::assembly::prefers_articulated;
        assert!(prefers_articulated(2000, 6000));
        assert!(!prefers_articulated(6000, 6000)); // a tie keeps the matrix
    }
    #[test]
    fn beats_solve_alone_example() {
        use crate::emit::assembly::{beats_solve_alone, prefers_articulated};
        assert!(beats_solve_alone(7923, 84912));
        assert!(!beats_solve_alone(2550, 2550)); // a tie builds the matrix's bodies to compare
        assert!(prefers_articulated(7923, 84912 + 28026));
    }
    #[test]
    fn worth_building_articulated_example() {
        use crate::emit::assembly::worth_building_articulated;
        assert!(worth_building_articulated(3629, Some(2562), 1362));
        assert!(!worth_building_articulated(1028, Some(746), 241));
        assert!(worth_building_articulated(2801, Some(1902), 899)); // the spatial 6-link chain
        assert!(worth_building_articulated(1028, None, 241));
    }
}
