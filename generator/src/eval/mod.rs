//! In-process evaluation: the same optimized functions the emitter writes as Rust, run at once
//! as register tapes, behind the seam's [`seam::Model`] — a model file reaches a result with no
//! cargo or rustc.
//!
//! Generation with [`crate::emit::Options::tapes`] compiles each emitted function body into a
//! [`tape::Tape`] from its syntax trees (the very trees prettyplease prints), and records what
//! the module's hand-written parts do around them ([`Program`]: sizes, names, each
//! formulation's layout and checks): both are emission's output, in `emit`. [`model::Evaluated`] is the module's `model()` over them:
//! the same checks, the same dense solve, the same errors.
//!
//! ```
//! let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
//! let evaluated = generator::eval::evaluate(&model).unwrap();
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

use crate::emit::{Options, generate};
use crate::model::{Model, ModelError};

/// `model` as a [`seam::Model`] evaluated in-process, with the options its file asks for (its
/// `emit` section), every formulation it requests.
pub fn evaluate(model: &Model) -> Result<seam::Model, ModelError> {
    evaluate_with(model, &Options::from_model(model))
}

/// [`evaluate`] with other options (formulations, baked parameters, dropped ignorable
/// coordinates, the exact Jacobians: `jacobian` and `parameter_jacobian` evaluate in-process as
/// the emitted ones do).
pub fn evaluate_with(model: &Model, options: &Options) -> Result<seam::Model, ModelError> {
    Ok(evaluate_reporting(model, options)?.0)
}

/// [`evaluate_with`], and the generation's summary: what the derivation's budgets cut and what it
/// could not decide ([`crate::emit::Summary::warnings`]), for the caller to report.
pub fn evaluate_reporting(model: &Model, options: &Options) -> Result<(seam::Model, crate::emit::Summary), ModelError> {
    evaluate_with_backend(model, options, &kernel::Interpreter)
}

/// [`evaluate_reporting`] with the tapes made kernels by `backend` (the `jit` crate's compiler).
pub fn evaluate_with_backend(model: &Model, options: &Options, backend: &dyn kernel::Backend) -> Result<(seam::Model, crate::emit::Summary), ModelError> {
    let options = Options { tapes: true, max_lets_per_function: usize::MAX, ..options.clone() };
    let generated = generate(model, &options)?;
    let program =
        generated.program.ok_or_else(|| model.error(crate::model::ErrorKind::Emission, "emit", "emit", "internal error: no tapes".into(), String::new()))?;
    Ok((model::Evaluated::model_with(program, backend), generated.summary))
}
