//! One formulation of an emitted model as a system `y' = f(t, y)`, with the conserved momenta
//! `G_I` it was started with.
//!
//! ```
//! let model = generated::find("cart_pendulum").unwrap();
//! let (q0, qd0) = model.initial;
//! let (sys, y0) = runtime::system::System::start(model, "reduced_volterra", (model.default_params)(), q0, qd0).unwrap();
//! let mut dy = vec![0.0; y0.len()];
//! sys.rhs(0.0, &y0, &mut dy).unwrap();
//! assert_eq!(y0.len(), sys.form.states);
//! ```

use generated::{Failure, Formulation, Model};

/// A formulation ready to integrate.
#[derive(Clone, Debug)]
pub struct System {
    pub model: Model,
    pub form: &'static Formulation,
    pub params: Vec<f64>,
    /// `G_I` from the initial state (Eq. 26).
    pub g_i: Vec<f64>,
}

/// Why a system could not be set up.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SetupError {
    #[error("model `{model}` has no formulation `{name}` (it has: {available})")]
    UnknownFormulation { model: String, name: String, available: String },
    #[error("initial state rejected: {0}")]
    Initial(Failure),
}

impl System {
    /// The system of formulation `name` and its initial state from `q(0), q'(0)`.
    pub fn start(model: Model, name: &str, params: Vec<f64>, q0: &[f64], qd0: &[f64]) -> Result<(System, Vec<f64>), SetupError> {
        let form = model.formulation(name).ok_or_else(|| SetupError::UnknownFormulation {
            model: model.module.to_string(),
            name: name.to_string(),
            available: model.formulations.iter().map(|f| f.name).collect::<Vec<_>>().join(", "),
        })?;
        let mut y0 = vec![0.0; form.states];
        let mut g_i = vec![0.0; model.ignorable.len()];
        (form.initial_state)(0.0, q0, qd0, &params, &mut y0, &mut g_i).map_err(SetupError::Initial)?;
        Ok((System { model, form, params, g_i }, y0))
    }

    /// `dy = f(t, y)`.
    pub fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Failure> {
        (self.form.rhs)(t, y, &self.params, &self.g_i, dy)
    }

    /// `(q, q')` at a state.
    pub fn velocities(&self, t: f64, y: &[f64]) -> Result<(Vec<f64>, Vec<f64>), Failure> {
        let m = self.model.coordinates.len();
        let (mut q, mut qd) = (vec![0.0; m], vec![0.0; m]);
        (self.form.velocities)(t, y, &self.params, &self.g_i, &mut q, &mut qd)?;
        Ok((q, qd))
    }

    /// The work integral `W` carried in the state (0 when no force can do work).
    pub fn work(&self, y: &[f64]) -> f64 {
        if self.form.has_work_state { y[self.form.states - 1] } else { 0.0 }
    }
}
