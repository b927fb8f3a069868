//! Our own symbolic engine: a hash-consed expression DAG with exact rational coefficients,
//! differentiation, substitution, expansion, a trigonometric normal form with a zero test,
//! numeric evaluation, a parser for model files, text and LaTeX printing, and small symbolic
//! matrices with a fraction-free solver. Expensive passes run under [`limits::Limits`].

pub mod diff;
pub mod eval;
pub mod expand;
pub mod expr;
pub mod fourier;
pub mod limits;
pub mod matrix;
pub mod number;
pub mod parse;
pub mod print;
pub mod report;
pub mod subs;
pub mod transfer;
pub mod trig;
pub mod zero;

pub use expr::{Context, Expr, Func, Node, Symbol};
pub use matrix::Matrix;
