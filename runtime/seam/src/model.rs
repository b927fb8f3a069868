//! What a model is to the code that runs it: its description (sizes, names, parameter values,
//! each formulation's kind and state layout) and its functions over slices, behind two traits
//! that a compiled module ([`crate::StaticModel`]) and a model evaluated in-process both
//! implement.

use crate::{Failure, FormulationKind, StateLayout};
use std::fmt;
use std::sync::Arc;

/// The functions of a model's coordinates and rates: `(t, q, q', params, out)`.
pub trait ModelFunctions: Send + Sync {
    /// `T + V`: one output.
    fn energy(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure>;
    /// `Q . q'`: one output.
    fn work_rate(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure>;
    /// `M' q' + N2` (Eq. 26): one output per ignorable coordinate.
    fn momenta(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure>;
    /// `a q' + b`: one output per constraint.
    fn constraint_residuals(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure>;
    /// The holonomic constraints' residuals (`qdot` is ignored): one output each.
    fn position_residuals(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure>;
    /// The event functions `g(t, q, q')`: one output per event ([`Model::events`]).
    fn event_values(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        let _ = (t, q, qdot, params, out);
        Err(Failure::Missing { function: "event_values" })
    }
    /// Every event's reset map at `(t, q, q')`: for event `k`, `out[2 m k..2 m (k + 1)]` holds
    /// the new `q` and `q'` (an event without one leaves them as they are).
    fn event_resets(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        let _ = (t, q, qdot, params, out);
        Err(Failure::Missing { function: "event_resets" })
    }
}

/// The functions of one formulation's state: `(t, state, params, g_i, ...)`.
pub trait FormulationFunctions: Send + Sync {
    /// `dstate = f(t, state)`.
    fn rhs(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64]) -> Result<(), Failure>;
    /// Lagrange only: the Baumgarte-stabilized right-hand side.
    fn rhs_baumgarte(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64], alpha: f64, beta: f64) -> Result<(), Failure> {
        let _ = (t, state, params, g_i, dstate, alpha, beta);
        Err(Failure::Missing { function: "rhs_baumgarte" })
    }
    /// The state and the conserved momenta `G_I` of `q(t), q'(t)`;
    /// [`Failure::ConstraintViolated`] when `q'` is not admissible.
    fn initial_state(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], state: &mut [f64], g_i: &mut [f64]) -> Result<(), Failure>;
    /// `q` and `q'` at a state.
    fn velocities(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], q: &mut [f64], qdot: &mut [f64]) -> Result<(), Failure>;
    /// The matrix `rhs` solves, row-major.
    fn matrix(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], out: &mut [f64]) -> Result<(), Failure>;
    /// Distance to the singular set of what was solved symbolically (infinite when nothing was).
    fn singular_margin(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64]) -> Result<f64, Failure>;
    /// The right-hand side and its Jacobian by the state, row-major
    /// (`jac[i * states + k] = d dstate[i] / d state[k]`).
    fn jacobian(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64], jac: &mut [f64]) -> Result<(), Failure> {
        let _ = (t, state, params, g_i, dstate, jac);
        Err(Failure::Missing { function: "jacobian" })
    }
    /// The derivative by the parameters (`jac[i * parameters + k]`).
    fn parameter_jacobian(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64], jac: &mut [f64]) -> Result<(), Failure> {
        let _ = (t, state, params, g_i, dstate, jac);
        Err(Failure::Missing { function: "parameter_jacobian" })
    }
}

/// One formulation of a model: what it is, its state's layout, and its functions.
#[derive(Clone)]
pub struct Formulation {
    pub kind: FormulationKind,
    pub layout: StateLayout,
    /// Number of second-order equations solved (the paper's Table 1).
    pub equations: usize,
    pub state_names: Vec<String>,
    /// Size of the matrix `rhs` solves numerically.
    pub matrix_size: usize,
    /// `rhs_baumgarte` is there (Lagrange).
    pub has_baumgarte: bool,
    /// The exact `jacobian` is there.
    pub has_jacobian: bool,
    /// The exact `parameter_jacobian` is there.
    pub has_parameter_jacobian: bool,
    /// `rhs` reads `t` (a time function, a prescribed motion): false lets a stiff method skip
    /// its `df/dt`.
    pub depends_on_time: bool,
    pub functions: Arc<dyn FormulationFunctions>,
}

impl fmt::Debug for Formulation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Formulation").field("kind", &self.kind).field("layout", &self.layout).field("equations", &self.equations).finish_non_exhaustive()
    }
}

impl Formulation {
    /// The formulation's name ([`FormulationKind::name`]).
    pub fn name(&self) -> &'static str {
        self.kind.name()
    }

    /// Length of the state.
    pub fn states(&self) -> usize {
        self.layout.len()
    }

    /// True when the last state entry is the work integral `W` (Eq. 80).
    pub fn has_work_state(&self) -> bool {
        self.layout.work
    }

    /// See [`FormulationFunctions::rhs`].
    pub fn rhs(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64]) -> Result<(), Failure> {
        self.functions.rhs(t, state, params, g_i, dstate)
    }

    /// See [`FormulationFunctions::rhs_baumgarte`].
    #[allow(clippy::too_many_arguments)]
    pub fn rhs_baumgarte(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64], alpha: f64, beta: f64) -> Result<(), Failure> {
        self.functions.rhs_baumgarte(t, state, params, g_i, dstate, alpha, beta)
    }

    /// See [`FormulationFunctions::initial_state`].
    pub fn initial_state(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], state: &mut [f64], g_i: &mut [f64]) -> Result<(), Failure> {
        self.functions.initial_state(t, q, qdot, params, state, g_i)
    }

    /// See [`FormulationFunctions::velocities`].
    pub fn velocities(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], q: &mut [f64], qdot: &mut [f64]) -> Result<(), Failure> {
        self.functions.velocities(t, state, params, g_i, q, qdot)
    }

    /// See [`FormulationFunctions::matrix`].
    pub fn matrix(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.functions.matrix(t, state, params, g_i, out)
    }

    /// See [`FormulationFunctions::singular_margin`].
    pub fn singular_margin(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64]) -> Result<f64, Failure> {
        self.functions.singular_margin(t, state, params, g_i)
    }

    /// See [`FormulationFunctions::jacobian`].
    pub fn jacobian(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64], jac: &mut [f64]) -> Result<(), Failure> {
        self.functions.jacobian(t, state, params, g_i, dstate, jac)
    }

    /// See [`FormulationFunctions::parameter_jacobian`].
    pub fn parameter_jacobian(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64], jac: &mut [f64]) -> Result<(), Failure> {
        self.functions.parameter_jacobian(t, state, params, g_i, dstate, jac)
    }
}

/// A frame turned by ZYX Euler angles `(psi, theta, phi)`, all three coordinates: singular
/// where `cos(theta)` vanishes.
///
/// ```
/// let g = seam::Gimbal { frame: "body".into(), pitch: 1 };
/// assert_eq!(g.margin(&[0.3, std::f64::consts::FRAC_PI_2, 0.0]).abs() < 1e-15, true);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Gimbal {
    /// The frame's name.
    pub frame: String,
    /// The index of the pitch `theta` among the model's coordinates.
    pub pitch: usize,
}

impl Gimbal {
    /// `cos(theta)` at the coordinates `q`: zero at the singular attitude.
    pub fn margin(&self, q: &[f64]) -> f64 {
        q[self.pitch].cos()
    }
}

/// One model: its description and its functions, compiled or evaluated in-process.
#[derive(Clone)]
pub struct Model {
    /// The module's name: the model's name, or the name it was emitted under (a variant such as
    /// `cart_pendulum_baked`).
    pub module: String,
    /// The model's own name.
    pub name: String,
    pub coordinates: Vec<String>,
    pub constraints: Vec<String>,
    /// Indices of the ignorable coordinates in `coordinates`.
    pub ignorable: Vec<usize>,
    /// Number of holonomic (position-level) constraints, the first of `constraints`.
    pub holonomic: usize,
    pub parameter_names: Vec<String>,
    /// The inputs: indices into `parameter_names` of the parameters a run may set at every call
    /// (a controller's output, a time series).
    pub inputs: Vec<usize>,
    /// The model file's parameter values (empty when they were baked into the code).
    pub default_params: Vec<f64>,
    /// `(q(0), q'(0))` of the reference run, when the model file gives one.
    pub initial: Option<(Vec<f64>, Vec<f64>)>,
    /// `(t_start, t_end, dt_out)` of the reference run, when the model file gives one.
    pub run: Option<(f64, f64, f64)>,
    /// The model file asks for the paper's integrator settings (`simulation.paper`: the
    /// paper's scenes); other models get tight ones.
    pub paper_settings: bool,
    /// What `energy` computes and what its balance with the work state means.
    pub energy_balance: crate::EnergyBalance,
    /// The model's events, in the order of [`ModelFunctions::event_values`]' outputs.
    pub events: Vec<crate::Event>,
    /// The frames turned by ZYX Euler angles: where a pitch's cosine vanishes the three angles
    /// lose a degree of freedom (gimbal lock) and their rates grow without bound; a run stops
    /// before it (`runtime::system`).
    pub gimbals: Vec<Gimbal>,
    pub formulations: Vec<Formulation>,
    pub functions: Arc<dyn ModelFunctions>,
}

impl fmt::Debug for Model {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Model")
            .field("module", &self.module)
            .field("coordinates", &self.coordinates)
            .field("formulations", &self.formulations)
            .finish_non_exhaustive()
    }
}

impl Model {
    /// The formulation of this kind, when the model has it.
    pub fn formulation(&self, kind: FormulationKind) -> Option<&Formulation> {
        self.formulations.iter().find(|f| f.kind == kind)
    }

    /// The formulation a run uses when none is named: the paper's reduced method where the
    /// model has it, else Kane's, else its first.
    pub fn default_kind(&self) -> FormulationKind {
        FormulationKind::default_among(&self.kinds())
    }

    /// The kinds the model has, in its order.
    pub fn kinds(&self) -> Vec<FormulationKind> {
        self.formulations.iter().map(|f| f.kind).collect()
    }

    /// The index of the parameter called `name`.
    pub fn parameter_index(&self, name: &str) -> Option<usize> {
        self.parameter_names.iter().position(|n| n == name)
    }

    /// The index of the coordinate called `name`.
    pub fn coordinate_index(&self, name: &str) -> Option<usize> {
        self.coordinates.iter().position(|n| n == name)
    }

    /// See [`ModelFunctions::energy`].
    pub fn energy(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.functions.energy(t, q, qdot, params, out)
    }

    /// See [`ModelFunctions::work_rate`].
    pub fn work_rate(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.functions.work_rate(t, q, qdot, params, out)
    }

    /// See [`ModelFunctions::momenta`].
    pub fn momenta(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.functions.momenta(t, q, qdot, params, out)
    }

    /// See [`ModelFunctions::constraint_residuals`].
    pub fn constraint_residuals(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.functions.constraint_residuals(t, q, qdot, params, out)
    }

    /// See [`ModelFunctions::position_residuals`].
    pub fn position_residuals(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.functions.position_residuals(t, q, qdot, params, out)
    }

    /// See [`ModelFunctions::event_values`].
    pub fn event_values(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.functions.event_values(t, q, qdot, params, out)
    }

    /// See [`ModelFunctions::event_resets`].
    pub fn event_resets(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.functions.event_resets(t, q, qdot, params, out)
    }
}
