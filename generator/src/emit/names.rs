//! Identifiers for model symbols in emitted code: unique, never a Rust keyword, and never one
//! of the module's own item or argument names.

use std::collections::HashSet;

const RUST_WORDS: &[&str] = &[
    "as", "async", "await", "break", "const", "continue", "crate", "dyn", "else", "enum", "extern", "false", "fn", "for", "gen", "if", "impl", "in", "let",
    "loop", "match", "mod", "move", "mut", "pub", "ref", "return", "self", "Self", "static", "struct", "super", "trait", "true", "type", "unsafe", "use",
    "where", "while", "abstract", "become", "box", "do", "final", "macro", "override", "priv", "typeof", "unsized", "virtual", "yield", "try", "union", "Ok",
    "Err", "Some", "None", "f64", "usize", "core", "std",
];

/// Names of the module's own items and of function arguments and locals.
const ITEM_NAMES: &[&str] = &[
    "MODEL",
    "NUM_COORDINATES",
    "NUM_CONSTRAINTS",
    "NUM_QUASI",
    "NUM_IGNORABLE",
    "NUM_HOLONOMIC",
    "COORDINATES",
    "CONSTRAINTS",
    "IGNORABLE",
    "INITIAL_Q",
    "INITIAL_QDOT",
    "T_START",
    "T_END",
    "DT_OUT",
    "PARAMETERS_BAKED",
    "SINGULAR_TOLERANCE",
    "PIVOT_TOLERANCE",
    "CONSTRAINT_TOLERANCE",
    "Params",
    "solve_dense",
    "solve_spd",
    "energy",
    "work_rate",
    "momenta",
    "constraint_residuals",
    "position_residuals",
    "reduced_volterra",
    "kane",
    "STATES",
    "EQUATIONS",
    "STATE_NAMES",
    "INTEGRATES_IGNORABLE",
    "HAS_WORK_STATE",
    "rhs",
    "initial_state",
    "velocities",
    "t",
    "state",
    "params",
    "g_i",
    "dstate",
    "q",
    "qdot",
    "v",
    "mass",
    "force",
    "value",
    "residual",
    "tolerance",
    "column",
    "index",
    "constraint",
    "bound",
    "residuals",
    "positions",
    "alpha",
    "beta",
    "rhs_baumgarte",
    "lagrange",
    "maggi",
    "matrix",
    "singular_margin",
    "MATRIX_SIZE",
    "Assembly",
    "assemble",
    "finish",
    "a",
    "w",
    "c",
    "power",
    "checks",
    "CONDITIONS",
    "condition",
    "Failure",
    "FORMULATION",
    "FORMULATIONS",
    "DEFAULT_PARAMS",
    "DEFAULT",
    "model",
    "seam",
];

/// A set of identifiers handed out so far.
pub struct Names {
    taken: HashSet<String>,
}

impl Default for Names {
    fn default() -> Self {
        Names::new()
    }
}

impl Names {
    /// Keywords and the module's own names are taken from the start.
    pub fn new() -> Names {
        Names { taken: RUST_WORDS.iter().chain(ITEM_NAMES).map(|s| s.to_string()).collect() }
    }

    /// An identifier for `base`: its characters that are not letters, digits or `_` become `_`,
    /// a leading digit gets a `_` before it, and `_` is appended until it is unused.
    pub fn fresh(&mut self, base: &str) -> String {
        let mut name: String = base.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
        if name.is_empty() || name.starts_with(|c: char| c.is_ascii_digit()) || name == "_" {
            name.insert(0, '_');
        }
        while self.taken.contains(&name) {
            name.push('_');
        }
        self.taken.insert(name.clone());
        name
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::emit::names::Names;
        let mut names = Names::new();
        assert_eq!(names.fresh("theta1'"), "theta1_");
        assert_eq!(names.fresh("fn"), "fn_");
        assert_eq!(names.fresh("theta1'"), "theta1__");
    }
}
