//! The `multibody` tool is this package's binary (`src/main.rs`); the workspace-level tests
//! live in `tests/`.
