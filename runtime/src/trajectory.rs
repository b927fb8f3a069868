//! One formulation run from its initial state with the model's events, monitored, and laid
//! out as the table every front end shows: `t`, `q`, `q'`, the formulation's state, the energy
//! (or its work balance) and its error, the momenta of the ignorable coordinates, the
//! constraint residuals and the inputs. The command line writes it as CSV and JSON, the Python
//! wheel returns it as arrays: one layout, named here.
//!
//! ```
//! use runtime::{integrate::Settings, system::System, trajectory::simulate};
//! let model = generated::cart_pendulum::model();
//! let (sys, y0) = System::start(&model, seam::FormulationKind::Kane, model.default_params.clone(), &[0.3, 0.0, 0.0], &[0.0; 3]).unwrap();
//! let run = simulate(&sys, &y0, &[0.0, 0.5, 1.0], &Settings::tight(1.0), &mut |_| {}).unwrap();
//! assert_eq!(run.columns[..4], ["t", "theta1", "theta2", "x"]);
//! assert_eq!(run.rows.len(), 3);
//! let energy_error = run.column("energy_error").unwrap();
//! assert!(energy_error.iter().all(|e| e.abs() < 1e-9));
//! ```

use crate::events::{Jump, run_interruptible, system_before};
use crate::integrate::{RunError, Settings, Solution};
use crate::monitor::{Invariants, monitor_with_jumps};
use crate::system::System;
use seam::{EventAction, Failure};
use std::ops::ControlFlow;

/// A monitored run and its table.
pub struct Trajectory {
    /// The column names: `t`, each coordinate, each coordinate with `'`, `state:NAME` for each
    /// state, the energy quantity and `<quantity>_error`, `momentum:COORDINATE` for each
    /// ignorable coordinate, `constraint_residual`, `position_residual`, `input:NAME` for each
    /// input.
    pub columns: Vec<String>,
    /// One row per output time reached.
    pub rows: Vec<Vec<f64>>,
    pub solution: Solution,
    pub jumps: Vec<Jump>,
    pub invariants: Invariants,
    /// The events that happened, in order.
    pub events: Vec<Crossing>,
}

/// An event that happened: its name, what it did, its time, and the coordinates and rates just
/// before it.
#[derive(Clone, Debug, PartialEq)]
pub struct Crossing {
    pub name: String,
    pub action: EventAction,
    pub t: f64,
    pub q: Vec<f64>,
    pub qdot: Vec<f64>,
}

impl Trajectory {
    /// The values of the column `name` at every row.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let k = self.columns.iter().position(|c| c == name)?;
        Some(self.rows.iter().map(|r| r[k]).collect())
    }
}

/// Why a run gave no trajectory: the integration, or the monitors reading its states.
#[derive(Debug, thiserror::Error)]
pub enum TrajectoryError {
    #[error(transparent)]
    Run(#[from] RunError),
    #[error("monitoring the run failed: {0}")]
    Monitor(Failure),
}

/// The columns of a trajectory of `sys` (see [`Trajectory::columns`]).
pub fn columns(sys: &System) -> Vec<String> {
    let model = &sys.model;
    let mut header: Vec<String> = vec!["t".into()];
    header.extend(model.coordinates.iter().cloned());
    header.extend(model.coordinates.iter().map(|c| format!("{c}'")));
    header.extend(sys.form.state_names.iter().map(|n| format!("state:{n}")));
    let quantity = model.energy_balance.quantity();
    header.extend([quantity.to_string(), format!("{quantity}_error")]);
    header.extend(model.ignorable.iter().map(|&j| format!("momentum:{}", model.coordinates[j])));
    header.extend(["constraint_residual".to_string(), "position_residual".to_string()]);
    header.extend(model.inputs.iter().map(|&i| format!("input:{}", model.parameter_names[i])));
    header
}

/// `sys` integrated from `y0` over the output `times` (the first is the start) with its model's
/// events, monitored; `on_rhs(t)` is told of every right-hand side (for progress).
pub fn simulate(sys: &System, y0: &[f64], times: &[f64], settings: &Settings, on_rhs: &mut dyn FnMut(f64)) -> Result<Trajectory, TrajectoryError> {
    simulate_interruptible(sys, y0, times, settings, &mut |t| {
        on_rhs(t);
        ControlFlow::Continue(())
    })
}

/// The trajectory of a run that stopped early with `error` (a singular configuration, steps
/// that vanish), up to the last output time before it stopped: the same run over those
/// outputs. The integrator is deterministic and its steps do not depend on the output times
/// before the last, so they are the failed run's up to there. `None` when no output after the
/// first comes before the stop, or when the shorter run fails too.
///
/// ```
/// use runtime::{integrate::Settings, system::System, trajectory};
/// use seam::FormulationKind;
/// let model = generated::find("three_body").unwrap();
/// let (q0, qd0) = model.initial.clone().unwrap();
/// let (sys, y0) = System::start(&model, FormulationKind::Kane, model.default_params.clone(), &q0, &qd0).unwrap();
/// let times: Vec<f64> = (0..=10).map(|k| k as f64 * 0.1).collect();
/// // A run that failed at t = 0.55 (say) kept the outputs up to 0.5.
/// let failed = runtime::integrate::RunError { t: 0.55, state: y0.clone(), reason: runtime::integrate::Reason::TooManySteps(0) };
/// let kept = trajectory::up_to(&sys, &y0, &times, &Settings::tight(1.0), &failed).unwrap();
/// assert_eq!(kept.solution.times.len(), 6);
/// ```
pub fn up_to(sys: &System, y0: &[f64], times: &[f64], settings: &Settings, error: &RunError) -> Option<Trajectory> {
    let before: Vec<f64> = times.iter().copied().take_while(|t| *t <= error.t).collect();
    if before.len() < 2 {
        return None;
    }
    simulate(sys, y0, &before, settings, &mut |_| {}).ok()
}

/// [`simulate`], stopped with [`crate::integrate::Reason::Interrupted`] where `on_rhs(t)`
/// breaks ([`crate::events::run_interruptible`]).
pub fn simulate_interruptible(
    sys: &System,
    y0: &[f64],
    times: &[f64],
    settings: &Settings,
    on_rhs: &mut dyn FnMut(f64) -> ControlFlow<()>,
) -> Result<Trajectory, TrajectoryError> {
    let model = &sys.model;
    let settings = Settings { time_independent: !sys.form.depends_on_time, ..*settings };
    let done = run_interruptible(sys, y0, times, &settings, on_rhs)?;
    let (solution, jumps) = (done.solution, done.jumps);
    let inv = monitor_with_jumps(sys, &solution, &jumps).map_err(TrajectoryError::Monitor)?;
    let mut events = Vec::new();
    for o in &solution.events {
        // The state just before the event, read with the momenta of the resets before it.
        let before = system_before(sys, &jumps, o.t);
        let (q, qdot) = before.velocities(o.t, &o.state).map_err(TrajectoryError::Monitor)?;
        let event = &model.events[o.event];
        events.push(Crossing { name: event.name.clone(), action: event.action, t: o.t, q, qdot });
    }
    let rows = (0..solution.times.len())
        .map(|i| {
            let mut row = vec![solution.times[i]];
            row.extend(&inv.coordinates[i]);
            row.extend(&inv.rates[i]);
            row.extend(&solution.states[i]);
            row.extend([inv.energy[i], inv.energy_error[i]]);
            row.extend((0..model.ignorable.len()).map(|k| inv.momentum0[k] + inv.momentum_error[k][i]));
            row.extend([inv.velocity_constraint[i], inv.position_constraint[i]]);
            let params = sys.params_at(solution.times[i], &solution.states[i]).map_err(TrajectoryError::Monitor)?;
            row.extend(model.inputs.iter().map(|&k| params[k]));
            Ok(row)
        })
        .collect::<Result<_, TrajectoryError>>()?;
    Ok(Trajectory { columns: columns(sys), rows, solution, jumps, invariants: inv, events })
}
