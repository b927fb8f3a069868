//! What an emitted module builds: its description and functions as `'static` data and function
//! pointers ([`StaticModel`], [`StaticFormulation`]), turned into a [`Model`] by `From`.

use crate::{Failure, Formulation, FormulationFunctions, FormulationKind, Model, ModelFunctions, StateLayout};
use std::sync::Arc;

/// `rhs(t, state, params, g_i, dstate)`: `dstate = f(t, state)`.
pub type RhsFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64]) -> Result<(), Failure>;
/// `rhs_baumgarte(t, state, params, g_i, dstate, alpha, beta)`.
pub type StabilizedFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64], f64, f64) -> Result<(), Failure>;
/// `matrix(t, state, params, g_i, out)`: the matrix `rhs` solves, row-major.
pub type MatrixFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64]) -> Result<(), Failure>;
/// `singular_margin(t, state, params, g_i)`.
pub type MarginFn = fn(f64, &[f64], &[f64], &[f64]) -> Result<f64, Failure>;
/// `initial_state(t, q, qdot, params, state, g_i)`.
pub type InitialFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64], &mut [f64]) -> Result<(), Failure>;
/// `velocities(t, state, params, g_i, q, qdot)`.
pub type VelocitiesFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64], &mut [f64]) -> Result<(), Failure>;
/// `(t, state, params, g_i, dstate, jac)`: the right-hand side and a Jacobian, row-major.
pub type JacobianFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64], &mut [f64]) -> Result<(), Failure>;
/// A function of `(t, q, qdot, params)` writing its outputs.
pub type PointFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64]) -> Result<(), Failure>;

/// One formulation of an emitted module.
#[derive(Clone, Copy, Debug)]
pub struct StaticFormulation {
    pub kind: FormulationKind,
    /// The coordinates the state holds (indices into the model's coordinates).
    pub coordinates: &'static [usize],
    /// How many speeds follow them.
    pub speeds: usize,
    /// The last state entry is the work integral `W` (Eq. 80).
    pub work: bool,
    /// Number of second-order equations solved.
    pub equations: usize,
    /// `rhs` reads `t`.
    pub depends_on_time: bool,
    pub state_names: &'static [&'static str],
    pub rhs: RhsFn,
    pub rhs_baumgarte: Option<StabilizedFn>,
    pub initial_state: InitialFn,
    pub velocities: VelocitiesFn,
    pub matrix_size: usize,
    pub matrix: MatrixFn,
    pub singular_margin: MarginFn,
    pub jacobian: Option<JacobianFn>,
    pub parameter_jacobian: Option<JacobianFn>,
}

/// An emitted module: what its `model()` turns into a [`Model`].
///
/// ```
/// // A hand-written one-coordinate model (x'' = -x), as an emitted module would describe it.
/// use seam::{Failure, FormulationKind, Model, StaticFormulation, StaticModel, array, array_mut};
///
/// fn rhs(_t: f64, state: &[f64], _params: &[f64], _g_i: &[f64], dstate: &mut [f64]) -> Result<(), Failure> {
///     let [x, v] = *array::<2>("state", state)?;
///     *array_mut::<2>("dstate", dstate)? = [v, -x];
///     Ok(())
/// }
/// static FORMULATIONS: [StaticFormulation; 1] =
///     [StaticFormulation { kind: FormulationKind::Lagrange, coordinates: &[0], speeds: 1, rhs, ..StaticFormulation::EMPTY }];
/// let model = Model::from(StaticModel { name: "oscillator", coordinates: &["x"], formulations: &FORMULATIONS, ..StaticModel::EMPTY });
///
/// let lagrange = model.formulation(FormulationKind::Lagrange).unwrap();
/// let mut dy = [0.0; 2];
/// lagrange.rhs(0.0, &[1.0, 0.0], &[], &[], &mut dy).unwrap();
/// assert_eq!(dy, [0.0, -1.0]);
/// let short = lagrange.rhs(0.0, &[1.0], &[], &[], &mut dy);
/// assert_eq!(short, Err(Failure::Dimension { argument: "state", expected: 2, got: 1 }));
/// assert!(model.energy(0.0, &[1.0], &[0.0], &[], &mut [0.0]).is_err());
/// ```
#[derive(Clone, Copy, Debug)]
pub struct StaticModel {
    pub module: &'static str,
    pub name: &'static str,
    pub coordinates: &'static [&'static str],
    pub constraints: &'static [&'static str],
    pub ignorable: &'static [usize],
    pub holonomic: usize,
    pub parameter_names: &'static [&'static str],
    /// Indices into `parameter_names` of the inputs.
    pub inputs: &'static [usize],
    pub default_params: &'static [f64],
    pub initial: Option<(&'static [f64], &'static [f64])>,
    pub run: Option<(f64, f64, f64)>,
    /// The model file asks for the paper's integrator settings.
    pub paper_settings: bool,
    /// What `energy` computes.
    pub energy_balance: crate::EnergyBalance,
    /// The events: `(name, direction, action)`, in the order of `event_values`' outputs.
    pub events: &'static [(&'static str, crate::Direction, crate::EventAction)],
    /// The frames turned by ZYX Euler angles: `(frame, index of the pitch coordinate)`.
    pub gimbals: &'static [(&'static str, usize)],
    pub event_values: PointFn,
    pub event_resets: PointFn,
    pub energy: PointFn,
    pub work_rate: PointFn,
    pub momenta: PointFn,
    pub constraint_residuals: PointFn,
    pub position_residuals: PointFn,
    pub formulations: &'static [StaticFormulation],
}

impl StaticModel {
    /// A model with no coordinates and no formulations, whose functions all fail with
    /// [`Failure::Missing`]: the base to fill in with struct update syntax.
    pub const EMPTY: StaticModel = StaticModel {
        module: "",
        name: "",
        coordinates: &[],
        constraints: &[],
        ignorable: &[],
        holonomic: 0,
        parameter_names: &[],
        inputs: &[],
        default_params: &[],
        initial: None,
        run: None,
        paper_settings: false,
        energy_balance: crate::EnergyBalance::Energy,
        events: &[],
        gimbals: &[],
        event_values: |_, _, _, _, _| Err(Failure::Missing { function: "event_values" }),
        event_resets: |_, _, _, _, _| Err(Failure::Missing { function: "event_resets" }),
        energy: |_, _, _, _, _| Err(Failure::Missing { function: "energy" }),
        work_rate: |_, _, _, _, _| Err(Failure::Missing { function: "work_rate" }),
        momenta: |_, _, _, _, _| Err(Failure::Missing { function: "momenta" }),
        constraint_residuals: |_, _, _, _, _| Err(Failure::Missing { function: "constraint_residuals" }),
        position_residuals: |_, _, _, _, _| Err(Failure::Missing { function: "position_residuals" }),
        formulations: &[],
    };
}

impl StaticFormulation {
    /// A formulation of no states whose functions all fail with [`Failure::Missing`].
    pub const EMPTY: StaticFormulation = StaticFormulation {
        kind: FormulationKind::Lagrange,
        coordinates: &[],
        speeds: 0,
        work: false,
        equations: 0,
        depends_on_time: true,
        state_names: &[],
        rhs: |_, _, _, _, _| Err(Failure::Missing { function: "rhs" }),
        rhs_baumgarte: None,
        initial_state: |_, _, _, _, _, _| Err(Failure::Missing { function: "initial_state" }),
        velocities: |_, _, _, _, _, _| Err(Failure::Missing { function: "velocities" }),
        matrix_size: 0,
        matrix: |_, _, _, _, _| Err(Failure::Missing { function: "matrix" }),
        singular_margin: |_, _, _, _| Err(Failure::Missing { function: "singular_margin" }),
        jacobian: None,
        parameter_jacobian: None,
    };
}

impl ModelFunctions for StaticModel {
    fn energy(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        (self.energy)(t, q, qdot, params, out)
    }
    fn work_rate(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        (self.work_rate)(t, q, qdot, params, out)
    }
    fn momenta(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        (self.momenta)(t, q, qdot, params, out)
    }
    fn constraint_residuals(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        (self.constraint_residuals)(t, q, qdot, params, out)
    }
    fn position_residuals(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        (self.position_residuals)(t, q, qdot, params, out)
    }
    fn event_values(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        (self.event_values)(t, q, qdot, params, out)
    }
    fn event_resets(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        (self.event_resets)(t, q, qdot, params, out)
    }
}

impl FormulationFunctions for StaticFormulation {
    fn rhs(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64]) -> Result<(), Failure> {
        (self.rhs)(t, state, params, g_i, dstate)
    }
    fn rhs_baumgarte(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64], alpha: f64, beta: f64) -> Result<(), Failure> {
        match self.rhs_baumgarte {
            Some(f) => f(t, state, params, g_i, dstate, alpha, beta),
            None => Err(Failure::Missing { function: "rhs_baumgarte" }),
        }
    }
    fn initial_state(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], state: &mut [f64], g_i: &mut [f64]) -> Result<(), Failure> {
        (self.initial_state)(t, q, qdot, params, state, g_i)
    }
    fn velocities(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], q: &mut [f64], qdot: &mut [f64]) -> Result<(), Failure> {
        (self.velocities)(t, state, params, g_i, q, qdot)
    }
    fn matrix(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        (self.matrix)(t, state, params, g_i, out)
    }
    fn singular_margin(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64]) -> Result<f64, Failure> {
        (self.singular_margin)(t, state, params, g_i)
    }
    fn jacobian(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64], jac: &mut [f64]) -> Result<(), Failure> {
        match self.jacobian {
            Some(f) => f(t, state, params, g_i, dstate, jac),
            None => Err(Failure::Missing { function: "jacobian" }),
        }
    }
    fn parameter_jacobian(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64], jac: &mut [f64]) -> Result<(), Failure> {
        match self.parameter_jacobian {
            Some(f) => f(t, state, params, g_i, dstate, jac),
            None => Err(Failure::Missing { function: "parameter_jacobian" }),
        }
    }
}

fn strings(names: &[&str]) -> Vec<String> {
    names.iter().map(|s| s.to_string()).collect()
}

impl From<StaticFormulation> for Formulation {
    fn from(f: StaticFormulation) -> Formulation {
        Formulation {
            kind: f.kind,
            layout: StateLayout { coordinates: f.coordinates.to_vec(), speeds: f.speeds, speeds_are: f.kind.speeds(), work: f.work },
            equations: f.equations,
            state_names: strings(f.state_names),
            matrix_size: f.matrix_size,
            has_baumgarte: f.rhs_baumgarte.is_some(),
            has_jacobian: f.jacobian.is_some(),
            has_parameter_jacobian: f.parameter_jacobian.is_some(),
            depends_on_time: f.depends_on_time,
            functions: Arc::new(f),
        }
    }
}

impl From<StaticModel> for Model {
    fn from(m: StaticModel) -> Model {
        Model {
            module: m.module.to_string(),
            name: m.name.to_string(),
            coordinates: strings(m.coordinates),
            constraints: strings(m.constraints),
            ignorable: m.ignorable.to_vec(),
            holonomic: m.holonomic,
            parameter_names: strings(m.parameter_names),
            inputs: m.inputs.to_vec(),
            default_params: m.default_params.to_vec(),
            initial: m.initial.map(|(q, qd)| (q.to_vec(), qd.to_vec())),
            run: m.run,
            paper_settings: m.paper_settings,
            energy_balance: m.energy_balance,
            events: m.events.iter().map(|(name, direction, action)| crate::Event { name: name.to_string(), direction: *direction, action: *action }).collect(),
            gimbals: m.gimbals.iter().map(|(frame, pitch)| crate::Gimbal { frame: frame.to_string(), pitch: *pitch }).collect(),
            formulations: m.formulations.iter().map(|f| Formulation::from(*f)).collect(),
            functions: Arc::new(m),
        }
    }
}
