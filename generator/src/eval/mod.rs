//! In-process evaluation: the same optimized functions the emitter writes as Rust, run at once
//! as register tapes, behind the seam's [`seam::Model`] — a model file reaches a result with no
//! cargo or rustc.
//!
//! [`crate::evaluate`] generates with [`crate::emit::Options::tapes`]: it compiles each emitted function body into a
//! [`tape::Tape`] from its syntax trees (the very trees prettyplease prints), and records what
//! the module's hand-written parts do around them ([`Program`]: sizes, names, each
//! formulation's layout and checks): both are emission's output, in `emit`. [`model::Evaluated`] is the module's `model()` over them:
//! the same checks, the same dense solve, the same errors.
//!
//! ```
//! let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
//! let evaluated = generator::evaluate(&model).unwrap();
//! let kane = evaluated.formulation(seam::FormulationKind::Kane).unwrap();
//! let (q0, qd0) = evaluated.initial.clone().unwrap();
//! let mut state = vec![0.0; kane.states()];
//! let mut g_i = vec![0.0; evaluated.ignorable.len()];
//! kane.initial_state(0.0, &q0, &qd0, &evaluated.default_params, &mut state, &mut g_i).unwrap();
//! let mut dstate = vec![0.0; state.len()];
//! kane.rhs(0.0, &state, &evaluated.default_params, &g_i, &mut dstate).unwrap();
//! assert!((dstate[0] - qd0[0]).abs() < 1e-12);
//! ```

pub mod kernel;
pub mod model;

pub use crate::emit::program::{Description, FormShape, Program};
pub use crate::emit::tape;
