//! Whether an output path would replace a model: every front end that writes a module (`generate
//! -o`, the wheel's `generate_rust`) asks before it writes, and words the refusal its own way.

use std::path::Path;

/// Why writing Rust to a path would replace a model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Overwrite {
    /// The output is the model file itself.
    ModelItself,
    /// The output is a `.ron` file (another model, most likely).
    RonFile,
}

/// Whether writing Rust from the model file `input` to `output` would replace a model: every
/// front end that writes a module (`generate -o`, the wheel's `generate_rust`) asks, and words
/// the refusal its own way.
///
/// ```
/// use generator::overwrite::{Overwrite, overwrites_a_model};
/// use std::path::Path;
/// assert_eq!(overwrites_a_model(Path::new("m.ron"), Path::new("m.ron")), Some(Overwrite::ModelItself));
/// assert_eq!(overwrites_a_model(Path::new("m.ron"), Path::new("other.RON")), Some(Overwrite::RonFile));
/// assert_eq!(overwrites_a_model(Path::new("m.ron"), Path::new("m.rs")), None);
/// ```
pub fn overwrites_a_model(input: &Path, output: &Path) -> Option<Overwrite> {
    let same = match (std::fs::canonicalize(input), std::fs::canonicalize(output)) {
        (Ok(a), Ok(b)) => a == b,
        _ => input == output,
    };
    if same {
        return Some(Overwrite::ModelItself);
    }
    output.extension().is_some_and(|e| e.eq_ignore_ascii_case("ron")).then_some(Overwrite::RonFile)
}
