//! How a right-hand side assembles its matrix and forcing: the dense form's entries, or the
//! recursion over the tree of frames ([`crate::formulation::recursive`]), whichever the emitted
//! code computes in fewer operations (both bodies are built: a count before the emitter's
//! sharing, [`crate::symbolic::expr::dag_ops`], picks wrongly on the 20-link pendulum and on
//! scene 2's reduced form). One rule, for emission, the summary and `inspect`.
//!
//! ```
//! use generator::emit::assembly::prefers_recursion;
//! assert!(prefers_recursion(900, 1000));
//! assert!(!prefers_recursion(1000, 1000)); // a tie keeps the dense entries
//! ```

use crate::formulation::Derivation;
use crate::model::{Model, ModelError};

/// True when the recursion's `by_tree` operations are fewer than the dense entries'
/// `by_entries`.
pub fn prefers_recursion(by_tree: usize, by_entries: usize) -> bool {
    by_tree < by_entries
}

/// True when the articulated-body recursion's `by_recursion` operations are fewer than those
/// of the matrix's assembly and its solve together, `by_matrix`.
///
/// ```
/// use generator::emit::assembly::prefers_articulated;
/// assert!(prefers_articulated(2000, 6000));
/// assert!(!prefers_articulated(6000, 6000)); // a tie keeps the matrix
/// ```
pub fn prefers_articulated(by_recursion: usize, by_matrix: usize) -> bool {
    by_recursion < by_matrix
}

/// Each formulation's solve and assembly, `(name, description)`, as the generator chooses them
/// from the derivation `d` under `options` (the summary's text).
///
/// ```
/// use generator::{emit, formulation};
/// let model = generator::model::load("../models/three_body.ron").unwrap();
/// let d = formulation::derive(&model, &formulation::Request::all()).unwrap();
/// let chosen = emit::assembly::describe(&model, &d, &emit::Options::from_model(&model)).unwrap();
/// assert_eq!(chosen.len(), 4);
/// assert!(chosen.iter().all(|(_, how)| how.contains("; assembly: ")));
/// ```
pub fn describe(model: &Model, d: &Derivation, options: &super::Options) -> Result<Vec<(String, String)>, ModelError> {
    super::module::assemblies(model, d, options)
}
