//! Emitted modules (filled by the generator).
