//! One formulation of an emitted model as a system `y' = f(t, y)`, with the conserved momenta
//! `G_I` it was started with.
//!
//! ```
//! use seam::FormulationKind;
//! let model = generated::find("cart_pendulum").unwrap();
//! let (q0, qd0) = model.initial.clone().unwrap();
//! let (sys, y0) = runtime::system::System::start(&model, FormulationKind::ReducedVolterra, model.default_params.clone(), &q0, &qd0).unwrap();
//! let mut dy = vec![0.0; y0.len()];
//! sys.rhs(0.0, &y0, &mut dy).unwrap();
//! assert_eq!(y0.len(), sys.form.states());
//! ```

use seam::{Failure, Formulation, FormulationKind, Model};

/// Drift control for the classical methods (Lagrange, Maggi), off by default so the paper's
/// comparison stays honest.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Drift {
    #[default]
    None,
    /// Lagrange only: `a q'' = gamma - 2 alpha (a q' + b) - beta^2 h`.
    Baumgarte { alpha: f64, beta: f64 },
    /// After every step, `q` is moved onto the holonomic constraints (Gauss-Newton, minimal
    /// norm) and `q'` onto `a q' + b = 0` (minimal-norm correction).
    Projection,
}

/// How near a frame's ZYX Euler angles may come to their singular attitude: a state with
/// `|cos(theta)|` at most this is refused by [`System::rhs`] (every formulation, every method),
/// so a run stops at its last step before it, naming the condition. Measured on a torque-free
/// body whose pitch reaches pi/2 at t = 5 (`tests/it/quaternion.rs`), at rtol 1e-12: Lagrange's
/// and Maggi's forms take 60 and 763 steps to come within 1e-4, 162862 and 5179147 steps to
/// come within 1e-6 (their rates grow as 1/cos(theta), their accelerations faster), where
/// Kane's form takes 43 and 52.
pub const GIMBAL_MARGIN: f64 = 1e-4;

/// What a state at a frame's singular ZYX attitude is refused with.
fn gimbal_failure(model: &Model, g: &seam::Gimbal, t: f64, value: f64) -> Failure {
    let condition = format!(
        "cos({}) = 0: frame `{}`'s ZYX Euler angles reach their singular attitude (gimbal lock, where their rates grow without bound; a run stops within {GIMBAL_MARGIN:e} of it): turn the frame by Quaternion(e0, e1, e2, e3) instead, which has no singular attitude",
        model.coordinates[g.pitch], g.frame
    );
    Failure::Singular { t, condition: condition.into(), value }
}

/// A formulation ready to integrate.
#[derive(Clone, Debug)]
pub struct System {
    pub model: Model,
    pub form: Formulation,
    pub params: Vec<f64>,
    /// `G_I` from the initial state (Eq. 26).
    pub g_i: Vec<f64>,
    /// Drift control (classical formulations only).
    pub drift: Drift,
    /// The control law that sets the model's inputs at every call (none: their nominal values).
    pub controller: Option<crate::inputs::Controller>,
    /// For each of the model's gimbals, the sign of `cos(theta)` where the run started: the
    /// side of the singular attitude it must stay on (a step across it, at loose tolerances,
    /// would pass it unseen). Empty for a system not started by [`System::start`].
    pub gimbal_sides: Vec<f64>,
}

/// Why a system could not be set up.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SetupError {
    #[error("model `{model}` has no formulation `{kind}` (it has: {available})")]
    UnknownFormulation { model: String, kind: FormulationKind, available: String },
    #[error("initial state rejected: {0}")]
    Initial(Failure),
    /// The initial coordinates (`position`) or rates violate constraint `constraint`.
    #[error(
        "the initial {} violate {} constraint `{constraint}` (residual {residual:e}, tolerance {tolerance:e}): {}",
        if *position { "coordinates" } else { "rates" },
        if *position { "the position" } else { "the velocity" },
        if *position {
            "give coordinates on the constraint (solve it for one of them)"
        } else {
            "give rates that satisfy it (for a position constraint, its time derivative); set the rates it determines by it, or leave them to `linearize`, which solves the rates not given from the constraints"
        }
    )]
    Violated { constraint: String, position: bool, residual: f64, tolerance: f64 },
    /// A coordinate, rate or parameter that is not a finite number.
    #[error("the initial {what} `{name}` is {value}, not a finite number")]
    NotFinite { what: &'static str, name: String, value: f64 },
    #[error("{drift:?} applies to {applies}, not to `{kind}`")]
    DriftNotApplicable { drift: Drift, kind: FormulationKind, applies: &'static str },
}

impl System {
    /// The system of formulation `kind` and its initial state from `q(0), q'(0)`.
    pub fn start(model: &Model, kind: FormulationKind, params: Vec<f64>, q0: &[f64], qd0: &[f64]) -> Result<(System, Vec<f64>), SetupError> {
        for (what, names, values) in
            [("coordinate", &model.coordinates, q0), ("rate", &model.coordinates, qd0), ("parameter", &model.parameter_names, &params[..])]
        {
            if let Some((name, value)) = names.iter().zip(values).find(|(_, v)| !v.is_finite()) {
                let name = if what == "rate" { format!("{name}'") } else { name.clone() };
                return Err(SetupError::NotFinite { what, name, value: *value });
            }
        }
        for g in &model.gimbals {
            if let Some(value) = q0.get(g.pitch).map(|theta| theta.cos())
                && !(value.abs() > GIMBAL_MARGIN)
            {
                return Err(SetupError::Initial(gimbal_failure(model, g, 0.0, value)));
            }
        }
        let mut sys = System::new(model, kind, params, vec![0.0; model.ignorable.len()])?;
        sys.gimbal_sides = model.gimbals.iter().map(|g| q0.get(g.pitch).map_or(1.0, |theta| theta.cos().signum())).collect();
        let mut y0 = vec![0.0; sys.form.states()];
        match sys.form.initial_state(0.0, q0, qd0, &sys.params, &mut y0, &mut sys.g_i) {
            Ok(()) => Ok((sys, y0)),
            Err(Failure::ConstraintViolated { constraint, residual, tolerance }) => {
                // Position level where the coordinates alone violate it.
                let holonomic = &model.constraints[..model.holonomic];
                let position = holonomic.iter().position(|c| *c == constraint).is_some_and(|k| {
                    let mut out = vec![0.0; model.holonomic];
                    sys.model.position_residuals(0.0, q0, qd0, &sys.params, &mut out).is_ok() && !(out[k].abs() <= tolerance)
                });
                Err(SetupError::Violated { constraint: constraint.into_owned(), position, residual, tolerance })
            }
            Err(e) => Err(SetupError::Initial(e)),
        }
    }

    /// The system of formulation `kind` with the conserved momenta `g_i` given (one per
    /// ignorable coordinate; only the reduced formulation reads them), for evaluating its
    /// right-hand side at states of the caller's choosing.
    pub fn new(model: &Model, kind: FormulationKind, params: Vec<f64>, g_i: Vec<f64>) -> Result<System, SetupError> {
        let form = model.formulation(kind).ok_or_else(|| SetupError::UnknownFormulation {
            model: model.module.clone(),
            kind,
            available: model.kinds().iter().map(|k| k.name()).collect::<Vec<_>>().join(", "),
        })?;
        Ok(System { model: model.clone(), form: form.clone(), params, g_i, drift: Drift::None, controller: None, gimbal_sides: Vec::new() })
    }

    /// The same system with its inputs set by `controller` at every call.
    pub fn with_controller(mut self, controller: crate::inputs::Controller) -> System {
        self.controller = Some(controller);
        self
    }

    /// The parameters at a state: the model's, with the inputs the controller gives there.
    pub fn params_at(&self, t: f64, y: &[f64]) -> Result<std::borrow::Cow<'_, [f64]>, Failure> {
        let Some(controller) = &self.controller else { return Ok(std::borrow::Cow::Borrowed(&self.params)) };
        let (q, qd) = self.velocities(t, y)?;
        let mut u = vec![0.0; self.model.inputs.len()];
        controller.apply(t, &q, &qd, &mut u);
        let mut params = self.params.clone();
        for (&i, v) in self.model.inputs.iter().zip(&u) {
            params[i] = *v;
        }
        Ok(std::borrow::Cow::Owned(params))
    }

    /// The same system with drift control.
    pub fn with_drift(mut self, drift: Drift) -> Result<System, SetupError> {
        let ok = match drift {
            Drift::None => true,
            Drift::Baumgarte { .. } => self.form.has_baumgarte,
            Drift::Projection => {
                let m = self.model.coordinates.len();
                self.form.layout.holds_every_rate(m) || self.form.layout.coordinates.iter().copied().eq(0..m)
            }
        };
        if !ok {
            let applies = if matches!(drift, Drift::Projection) {
                "states that hold every coordinate (lagrange, maggi, kane, and reduced_volterra with its ignorable coordinates integrated)"
            } else {
                "lagrange"
            };
            return Err(SetupError::DriftNotApplicable { drift, kind: self.form.kind, applies });
        }
        self.drift = drift;
        Ok(self)
    }

    /// Refuses a state within [`GIMBAL_MARGIN`] of a frame's singular ZYX attitude, or past
    /// it from where the run started.
    fn away_from_gimbal_lock(&self, t: f64, y: &[f64]) -> Result<(), Failure> {
        for (i, g) in self.model.gimbals.iter().enumerate() {
            // The pitch is in every state: the energy depends on it, so it is never ignorable.
            if let Some(k) = self.form.layout.coordinates.iter().position(|&c| c == g.pitch) {
                let value = y[k].cos();
                let side = self.gimbal_sides.get(i).copied().unwrap_or(value.signum());
                if !(value * side > GIMBAL_MARGIN) {
                    return Err(gimbal_failure(&self.model, g, t, value));
                }
            }
        }
        Ok(())
    }

    /// `dy = f(t, y)`.
    pub fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Failure> {
        self.away_from_gimbal_lock(t, y)?;
        let params = self.params_at(t, y)?;
        match self.drift {
            Drift::Baumgarte { alpha, beta } => self.form.rhs_baumgarte(t, y, &params, &self.g_i, dy, alpha, beta),
            _ => self.form.rhs(t, y, &params, &self.g_i, dy),
        }
    }

    /// True when `jacobian` is the model's exact one (emitted with `--jacobian`, and no
    /// Baumgarte terms, which it does not include).
    pub fn has_exact_jacobian(&self) -> bool {
        // A controller's feedback is not in the emitted Jacobian either.
        self.form.has_jacobian && !matches!(self.drift, Drift::Baumgarte { .. }) && self.controller.is_none()
    }

    /// `dy = f(t, y)` and `jac = df/dy` (row-major) from the emitted `jacobian`;
    /// `Failure::Missing` when the module has none (see [`System::has_exact_jacobian`]).
    pub fn jacobian(&self, t: f64, y: &[f64], dy: &mut [f64], jac: &mut [f64]) -> Result<(), Failure> {
        self.away_from_gimbal_lock(t, y)?;
        if self.has_exact_jacobian() { self.form.jacobian(t, y, &self.params, &self.g_i, dy, jac) } else { Err(Failure::Missing { function: "jacobian" }) }
    }

    /// Projection onto the constraints for [`Drift::Projection`] (a state `[q; q'; W?]`, which
    /// [`System::with_drift`] checked from the layout); returns
    /// whether the state changed.
    pub fn project(&self, t: f64, y: &mut [f64]) -> Result<bool, Failure> {
        if self.drift != Drift::Projection {
            return Ok(false);
        }
        let m = self.model.coordinates.len();
        let (r, h) = (self.model.constraints.len(), self.model.holonomic);
        let mut changed = false;
        // Positions: Gauss-Newton on h(q) = 0 with a central-difference Jacobian.
        if h > 0 {
            for _ in 0..3 {
                let res = self.position_residuals(t, &y[..m])?;
                if res.iter().all(|v| v.abs() < 1e-15) {
                    break;
                }
                let mut jac = nalgebra::DMatrix::zeros(h, m);
                for j in 0..m {
                    let step = 1e-7 * (1.0 + y[j].abs());
                    let mut qp = y[..m].to_vec();
                    qp[j] += step;
                    let hp = self.position_residuals(t, &qp)?;
                    qp[j] -= 2.0 * step;
                    let hm = self.position_residuals(t, &qp)?;
                    for i in 0..h {
                        jac[(i, j)] = (hp[i] - hm[i]) / (2.0 * step);
                    }
                }
                let dq = minimal_norm(&jac, &res);
                for j in 0..m {
                    y[j] -= dq[j];
                }
                changed = true;
            }
        }
        // Velocities: a q' + b is linear in q', so a and b come out exactly. Quasi-velocities
        // describe admissible motions only: nothing to project.
        if r > 0 && self.form.layout.holds_every_rate(m) {
            let q = y[..m].to_vec();
            let (a, _) = constraint_matrix(&self.model, t, &q, &self.params)?;
            let res = self.velocity_residuals(t, &q, &y[m..2 * m])?;
            let dv = minimal_norm(&a, &res);
            for j in 0..m {
                y[m + j] -= dv[j];
            }
            changed = true;
        }
        Ok(changed)
    }

    fn position_residuals(&self, t: f64, q: &[f64]) -> Result<Vec<f64>, Failure> {
        let mut out = vec![0.0; self.model.holonomic];
        self.model.position_residuals(t, q, &vec![0.0; q.len()], &self.params, &mut out)?;
        Ok(out)
    }

    fn velocity_residuals(&self, t: f64, q: &[f64], qd: &[f64]) -> Result<Vec<f64>, Failure> {
        velocity_residuals(&self.model, t, q, qd, &self.params)
    }

    /// `(q, q')` at a state.
    pub fn velocities(&self, t: f64, y: &[f64]) -> Result<(Vec<f64>, Vec<f64>), Failure> {
        let m = self.model.coordinates.len();
        let (mut q, mut qd) = (vec![0.0; m], vec![0.0; m]);
        self.form.velocities(t, y, &self.params, &self.g_i, &mut q, &mut qd)?;
        Ok((q, qd))
    }

    /// The work integral `W` carried in the state (0 when no force can do work).
    pub fn work(&self, y: &[f64]) -> f64 {
        self.form.layout.work_index().map_or(0.0, |k| y[k])
    }
}

/// `a q' + b` of the model's velocity constraints.
fn velocity_residuals(model: &Model, t: f64, q: &[f64], qd: &[f64], params: &[f64]) -> Result<Vec<f64>, Failure> {
    let mut out = vec![0.0; model.constraints.len()];
    model.constraint_residuals(t, q, qd, params, &mut out)?;
    Ok(out)
}

/// `(a, b)` of the velocity constraints `a q' + b = 0` at `q`: they are linear in `q'`, so the
/// residuals at `q' = 0` and at the unit rates give them exactly.
pub fn constraint_matrix(model: &Model, t: f64, q: &[f64], params: &[f64]) -> Result<(nalgebra::DMatrix<f64>, Vec<f64>), Failure> {
    let (m, r) = (q.len(), model.constraints.len());
    let b = velocity_residuals(model, t, q, &vec![0.0; m], params)?;
    let mut a = nalgebra::DMatrix::zeros(r, m);
    for j in 0..m {
        let mut e = vec![0.0; m];
        e[j] = 1.0;
        let col = velocity_residuals(model, t, q, &e, params)?;
        for i in 0..r {
            a[(i, j)] = col[i] - b[i];
        }
    }
    Ok((a, b))
}

/// `J^T (J J^T)^-1 r`: the smallest correction `d` with `J d = r`.
fn minimal_norm(j: &nalgebra::DMatrix<f64>, r: &[f64]) -> Vec<f64> {
    let jjt = j * j.transpose();
    let rhs = nalgebra::DVector::from_column_slice(r);
    match jjt.lu().solve(&rhs) {
        Some(x) => (j.transpose() * x).iter().copied().collect(),
        None => vec![0.0; j.ncols()],
    }
}
