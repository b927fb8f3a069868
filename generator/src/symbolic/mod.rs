//! Our own symbolic engine: a hash-consed expression DAG with exact rational coefficients,
//! differentiation, substitution, expansion, a trigonometric normal form with a zero test,
//! numeric evaluation, a parser for model files, text and LaTeX printing, and small symbolic
//! matrices with a fraction-free solver. Expensive passes run under [`Limits`].
//!
//! The modules are the generator's own; this face is what other crates use: expressions and
//! their context, numbers, evaluation, the simplifier and the zero test, the parser, and the
//! node budget. Most operations are methods of [`Expr`].
//!
//! ```
//! use generator::symbolic::{Env, Expr, Symbol};
//! let x = Symbol::new("x");
//! let e = (x.expr().sin() * x.expr()).diff(x);
//! let mut env = Env::default();
//! env.set(x, 0.5);
//! assert!((e.eval(&env).unwrap() - (0.5f64.cos() * 0.5 + 0.5f64.sin())).abs() < 1e-15);
//! ```

pub(crate) mod diff;
pub(crate) mod eval;
pub(crate) mod expand;
pub(crate) mod expr;
pub(crate) mod fourier;
pub(crate) mod limits;
pub(crate) mod matrix;
pub(crate) mod number;
pub(crate) mod parse;
pub(crate) mod print;
pub(crate) mod report;
pub(crate) mod subs;
pub(crate) mod transfer;
pub(crate) mod trig;
pub(crate) mod zero;

pub use eval::{Env, EvalError};
pub use expr::{Context, DEFAULT_MAX_NODES, Expr, Func, Node, Symbol, budget_for_command_line, set_max_nodes};
pub use fourier::{FourierLimits, Simplifier, SimplifyReport};
pub use limits::{Budget, Limits, StopReason};
pub use matrix::Matrix;
pub use number::{Rat, rat_from_decimal, rat_to_f64};
pub use parse::{Ast, LowerError, ParseError, Resolver, lower, parse};
pub use zero::{SplitMix, ZeroProof, ZeroVerdict, zero_test};
