//! Integrators: fixed-step RK4, adaptive Dormand-Prince 5(4) with PI step control and dense
//! output (what MATLAB's `ode45` does with a vector of output times), DOP853 with its
//! seventh-order dense output, and the stiff Rosenbrock 2(3) of `ode23s`.
//!
//! The three adaptive methods run in one driver (`driver.rs`, as Hairer's codes share one
//! loop): one step-size controller configured per method, one dense-output loop, one step end
//! (divergence check, projection); each method only attempts steps and interpolates in the last
//! accepted one. Each is checked on Hairer's reference problems (the Arenstorf orbit, Van der Pol
//! at mu = 1e3) and by an order test of the method and of its dense output.
//!
//! All three are ours: the systems are small (4 to 16 states), a right-hand side costs 0.1 to
//! 1 µs, and the candidate crates either allocate per step, pull a second nalgebra, or gave a
//! wrong dense output (measured when the crates were chosen). The measurement is in `docs/benchmarks.md`.
//!
//! ```
//! use runtime::integrate::{Method, Settings, integrate};
//! // y'' = -y from (1, 0): y(t) = cos t.
//! let mut f = |_t: f64, y: &[f64], dy: &mut [f64]| -> Result<(), seam::Failure> {
//!     dy[0] = y[1];
//!     dy[1] = -y[0];
//!     Ok(())
//! };
//! let out: Vec<f64> = (0..=10).map(|i| i as f64).collect();
//! let s = Settings { method: Method::Dopri5, rtol: 1e-8, atol: 1e-10, ..Settings::default() };
//! let sol = integrate(&mut f, &[1.0, 0.0], &out, &s).unwrap();
//! assert!((sol.states[10][0] - 10f64.cos()).abs() < 1e-6);
//! ```

mod dop853;
mod dopri5;
mod driver;
mod events;
mod rk4;
mod rosenbrock;

pub use events::{Direction, EventAction, Events, Occurrence, time_tolerance};
use seam::Failure;
use std::fmt;

/// The integration method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// Classical Runge-Kutta, fixed step `h` (shortened to land on output times).
    Rk4 { h: f64 },
    /// Dormand-Prince 5(4), PI step control, dense output (Shampine's 4th-order interpolant).
    Dopri5,
    /// Dormand-Prince 8(5,3) with its seventh-order dense output.
    Dop853,
    /// Shampine and Reichelt's `ode23s` Rosenbrock 2(3), L-stable, for stiff systems: the
    /// model's exact Jacobian when given, else finite differences.
    Rosenbrock23,
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Method::Rk4 { h } => write!(f, "RK4 h={}", seam::short(*h)),
            Method::Dopri5 => write!(f, "DOPRI5"),
            Method::Dop853 => write!(f, "DOP853"),
            Method::Rosenbrock23 => write!(f, "ROS23"),
        }
    }
}

impl Method {
    /// The names the front ends take: `dopri5`, `dop853`, `ros23` and `rk4` (which needs its
    /// fixed step `h`).
    pub const NAMES: [&'static str; 4] = ["dopri5", "dop853", "rk4", "ros23"];

    /// The method a front end names (see [`Method::NAMES`]); `rk4` takes the step `h`.
    ///
    /// ```
    /// use runtime::integrate::Method;
    /// assert_eq!(Method::from_name("dop853", None), Some(Method::Dop853));
    /// assert_eq!(Method::from_name("rk4", Some(0.01)), Some(Method::Rk4 { h: 0.01 }));
    /// assert_eq!(Method::from_name("rk4", None), None);
    /// ```
    pub fn from_name(name: &str, h: Option<f64>) -> Option<Method> {
        match name {
            "dopri5" => Some(Method::Dopri5),
            "dop853" => Some(Method::Dop853),
            "ros23" => Some(Method::Rosenbrock23),
            "rk4" => h.filter(|h| h.is_finite() && *h > 0.0).map(|h| Method::Rk4 { h }),
            _ => None,
        }
    }
}

/// The largest absolute tolerance [`Settings::check_tolerances`] takes: an error allowed to be
/// larger than this in any unit controls nothing.
pub const MAX_ATOL: f64 = 1e10;

/// Integrator settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    pub method: Method,
    pub rtol: f64,
    pub atol: f64,
    /// Largest step (adaptive methods).
    pub h_max: f64,
    /// Give up after this many steps.
    pub max_steps: usize,
    /// The right-hand side does not read `t` (the seam's `Formulation::depends_on_time` is
    /// false): the Rosenbrock method then skips its `df/dt` difference, one call a step.
    pub time_independent: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings { method: Method::Dopri5, rtol: 1e-3, atol: 1e-6, h_max: f64::INFINITY, max_steps: 10_000_000, time_independent: false }
    }
}

impl Settings {
    /// "The paper's settings" (`docs/scenes.md`): MATLAB `ode45` defaults, Dormand-Prince
    /// 5(4) with rtol 1e-3, atol 1e-6, maximum step a tenth of the span.
    pub fn paper(span: f64) -> Settings {
        Settings { method: Method::Dopri5, rtol: 1e-3, atol: 1e-6, h_max: 0.1 * span, ..Settings::default() }
    }

    /// Whether `rtol` and `atol` control an error at all: each a finite positive number, a
    /// relative tolerance below 1 (at 1 or above every step passes) and an absolute one at most
    /// [`MAX_ATOL`].
    ///
    /// ```
    /// use runtime::integrate::Settings;
    /// assert!(Settings::check_tolerances(1e-10, 1e-10).is_ok());
    /// assert!(Settings::check_tolerances(1e300, 1e-10).unwrap_err().contains("rtol"));
    /// assert!(Settings::check_tolerances(1e-3, 1e300).unwrap_err().contains("atol"));
    /// ```
    pub fn check_tolerances(rtol: f64, atol: f64) -> Result<(), String> {
        if !(rtol > 0.0 && rtol < 1.0) {
            return Err(format!("rtol = {rtol:e}: a relative tolerance is a positive number below 1 (1e-3 is loose, 1e-12 tight)"));
        }
        if !(atol > 0.0 && atol <= MAX_ATOL) {
            return Err(format!("atol = {atol:e}: an absolute tolerance is a positive number at most {MAX_ATOL:e} (beyond it nothing is controlled)"));
        }
        Ok(())
    }

    /// Tight settings, for a user's model: DOP853 at rtol = atol = 1e-10, maximum step a tenth
    /// of the span (the paper's loose settings can show a false nutation of a fast top).
    pub fn tight(span: f64) -> Settings {
        Settings { method: Method::Dop853, rtol: 1e-10, atol: 1e-10, h_max: 0.1 * span, ..Settings::default() }
    }
}

/// Work done by the integrator.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    pub steps: usize,
    pub rejected: usize,
    pub rhs_calls: usize,
    /// Jacobian evaluations (stiff method; finite differences count their calls as rhs calls).
    pub jacobians: usize,
    /// LU factorizations of the iteration matrix (stiff method).
    pub factorizations: usize,
    /// DOPRI5 and DOP853: the time from which the problem looks stiff by Hairer's test (the
    /// step size held by stability: `h |lambda|` beyond the method's stability boundary, 3.25
    /// or 6.1, on 15 accepted steps in a row, without six in-bounds ones between), where a
    /// stiff method (`ros23`) does better.
    pub stiff_at: Option<f64>,
    /// Evaluations of the event functions (after each accepted step, and while locating).
    pub event_evaluations: usize,
}

impl Stats {
    /// Adds the work of another stretch of the same run.
    pub(crate) fn add(&mut self, other: &Stats) {
        self.steps += other.steps;
        self.rejected += other.rejected;
        self.rhs_calls += other.rhs_calls;
        self.jacobians += other.jacobians;
        self.factorizations += other.factorizations;
        self.event_evaluations += other.event_evaluations;
        self.stiff_at = self.stiff_at.or(other.stiff_at);
    }
}

/// The states at the requested output times, and the events of the run.
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    /// The output times reached: all of them, or those before a stop event.
    pub times: Vec<f64>,
    pub states: States,
    pub stats: Stats,
    /// The events that happened, in time order ([`integrate_with_events`]).
    pub events: Vec<Occurrence>,
    /// A stop event ended the run (the last of `events`).
    pub stopped: bool,
}

/// Equal-length states stored in one flat buffer (no allocation per sample).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct States {
    dim: usize,
    data: Vec<f64>,
}

impl States {
    /// Room for `capacity` states of `dim` entries.
    pub fn new(dim: usize, capacity: usize) -> States {
        States { dim, data: Vec::with_capacity(dim * capacity) }
    }
    /// Appends a state.
    pub fn push(&mut self, y: &[f64]) {
        debug_assert_eq!(y.len(), self.dim);
        self.data.extend_from_slice(y);
    }
    /// Number of states.
    pub fn len(&self) -> usize {
        self.data.len().checked_div(self.dim).unwrap_or(0)
    }
    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }
    /// The states in order.
    pub fn iter(&self) -> std::slice::ChunksExact<'_, f64> {
        self.data.chunks_exact(self.dim.max(1))
    }
    /// The last state.
    pub fn last(&self) -> Option<&[f64]> {
        self.iter().last()
    }
    /// The last state, mutable.
    pub fn last_mut(&mut self) -> Option<&mut [f64]> {
        let dim = self.dim.max(1);
        self.data.chunks_exact_mut(dim).last()
    }
}

impl std::ops::Index<usize> for States {
    type Output = [f64];
    fn index(&self, i: usize) -> &[f64] {
        &self.data[i * self.dim..(i + 1) * self.dim]
    }
}

impl<'a> IntoIterator for &'a States {
    type Item = &'a [f64];
    type IntoIter = std::slice::ChunksExact<'a, f64>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

/// Why a run stopped early: the time, the last accepted state, and the reason.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("integration stopped after t = {t}, its last accepted step: {reason}")]
pub struct RunError {
    pub t: f64,
    pub state: Vec<f64>,
    pub reason: Reason,
}

/// The reason a run stopped.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Reason {
    /// The right-hand side (or the projection) refused: a singular configuration, a
    /// non-finite value, a wrong slice length, typed as the model reported it.
    #[error("{0}")]
    Rhs(Failure),
    /// The step size fell below what the time's resolution allows.
    #[error("step size {h:e} underflows at this time (tolerance too tight?)")]
    StepSizeTooSmall { h: f64 },
    /// The step size fell to nothing because the numbers overflow: entry `index` of the state
    /// or of its rate is at the edge of f64 (or beyond it).
    #[error(
        "the {what} entry {index} is {value:e}, at the edge of f64: the steps that follow overflow (scale the model: other units, smaller parameters or initial values)"
    )]
    Overflow { what: &'static str, index: usize, value: f64 },
    /// More steps than `max_steps`.
    #[error("more than {0} steps")]
    TooManySteps(usize),
    /// A state that is not finite (a fixed step too large for the dynamics).
    #[error("the state is not finite (diverged)")]
    Diverged,
    /// Output times that are not increasing.
    #[error("output times must start at the initial time and increase")]
    BadOutputTimes,
    /// More events than the run's budget ([`Events::max_events`]).
    #[error("more than {0} events: they accumulate here (a Zeno point, as a bouncing ball's impacts do); end the run before it, or raise the budget")]
    TooManyEvents(usize),
    /// The steps after a reset shrank to nothing: the events accumulate (a Zeno point).
    #[error(
        "the events accumulate here, {count} of them so far, ever closer (a Zeno point, as a bouncing ball's impacts do): the steps between them shrink to nothing; end the run before it"
    )]
    EventsAccumulate { count: usize },
    /// The caller asked the run to stop (a Ctrl-C, checked between right-hand sides:
    /// [`crate::events::run_interruptible`]); the state is the last accepted step's.
    #[error("interrupted: the caller asked the run to stop")]
    Interrupted,
    /// A reset map put the state past its event's surface (the event function on the side
    /// the crossing went to, `value`), where it would cross again at once, without end.
    #[error(
        "the reset of the model's event #{} puts the state past the event's surface (its function is {value:e} after the reset, on the side the crossing went to): it would happen again at once, without end; the reset must send the state back to the side it came from, or onto the surface",
        event + 1
    )]
    ResetPastSurface { event: usize, value: f64 },
    /// Events are located on a method's dense output, which RK4 does not have.
    #[error("events need an adaptive method (DOPRI5, DOP853 or ROS23), which interpolates inside its steps; RK4 does not")]
    EventsNeedDenseOutput,
}

/// Integrates `y' = f(t, y)` from `y0` at `outputs[0]` and returns the state at each output
/// time.
pub fn integrate(
    f: &mut dyn FnMut(f64, &[f64], &mut [f64]) -> Result<(), Failure>,
    y0: &[f64],
    outputs: &[f64],
    settings: &Settings,
) -> Result<Solution, RunError> {
    integrate_projected(f, None, y0, outputs, settings)
}

/// A map applied to the state after every accepted step (drift control by projection onto
/// the constraints). It returns `true` when it changed the state.
pub type Projector<'a> = &'a mut dyn FnMut(f64, &mut [f64]) -> Result<bool, Failure>;

/// The exact Jacobian of the right-hand side: `(t, y, dy, jac)` writes `dy = f(t, y)` and
/// `jac[i * n + k] = d f_i / d y_k` (the emitted `jacobian` through the seam).
pub type JacobianFn<'a> = &'a mut dyn FnMut(f64, &[f64], &mut [f64], &mut [f64]) -> Result<(), Failure>;

/// [`integrate`], with `project` applied after every accepted step.
pub fn integrate_projected(
    f: &mut dyn FnMut(f64, &[f64], &mut [f64]) -> Result<(), Failure>,
    project: Option<Projector>,
    y0: &[f64],
    outputs: &[f64],
    settings: &Settings,
) -> Result<Solution, RunError> {
    integrate_with_jacobian(f, None, project, y0, outputs, settings)
}

/// [`integrate_projected`] with the right-hand side's exact Jacobian for the stiff method
/// (without it, [`Method::Rosenbrock23`] uses forward differences; the explicit methods
/// ignore it).
///
/// ```
/// use runtime::integrate::{Method, Settings, integrate_with_jacobian};
/// // A stiff decay towards cos t: y' = -1e6 (y - cos t).
/// let mut f = |t: f64, y: &[f64], dy: &mut [f64]| -> Result<(), seam::Failure> {
///     dy[0] = -1e6 * (y[0] - t.cos());
///     Ok(())
/// };
/// let mut jac = |t: f64, y: &[f64], dy: &mut [f64], j: &mut [f64]| -> Result<(), seam::Failure> {
///     dy[0] = -1e6 * (y[0] - t.cos());
///     j[0] = -1e6;
///     Ok(())
/// };
/// let s = Settings { method: Method::Rosenbrock23, rtol: 1e-5, atol: 1e-8, ..Settings::default() };
/// let sol = integrate_with_jacobian(&mut f, Some(&mut jac), None, &[1.0], &[0.0, 10.0], &s).unwrap();
/// assert!((sol.states[1][0] - 10f64.cos()).abs() < 1e-5);
/// // An explicit method is held to steps of about 3e-6 by stability: millions of them.
/// assert!(sol.stats.steps < 5000, "{:?}", sol.stats);
/// ```
pub fn integrate_with_jacobian(
    f: &mut dyn FnMut(f64, &[f64], &mut [f64]) -> Result<(), Failure>,
    jacobian: Option<JacobianFn>,
    project: Option<Projector>,
    y0: &[f64],
    outputs: &[f64],
    settings: &Settings,
) -> Result<Solution, RunError> {
    let mut run = Runner { f, jacobian, project };
    run.stretch(y0, outputs, settings, None)
}

/// [`integrate_with_jacobian`] watching `events`: each is located in the step where its function
/// crosses zero in its direction, to [`time_tolerance`], and recorded in
/// [`Solution::events`]; a stop ends the run there, a reset goes on from the state its map
/// gives (the run restarts from it: a new first step).
pub fn integrate_with_events(
    f: &mut dyn FnMut(f64, &[f64], &mut [f64]) -> Result<(), Failure>,
    jacobian: Option<JacobianFn>,
    project: Option<Projector>,
    events: &mut Events,
    y0: &[f64],
    outputs: &[f64],
    settings: &Settings,
) -> Result<Solution, RunError> {
    let mut run = Runner { f, jacobian, project };
    if events.kinds.is_empty() {
        return run.stretch(y0, outputs, settings, None);
    }
    if matches!(settings.method, Method::Rk4 { .. }) {
        return Err(RunError { t: outputs.first().copied().unwrap_or(0.0), state: y0.to_vec(), reason: Reason::EventsNeedDenseOutput });
    }
    let mut all = Solution { times: Vec::new(), states: States::new(y0.len(), outputs.len()), stats: Stats::default(), events: Vec::new(), stopped: false };
    let (mut start, mut stretch_outputs, mut skip_first, mut rearmed) = (y0.to_vec(), outputs.to_vec(), false, None);
    loop {
        let mut watch = events::Watch::new(events, rearmed);
        let part = run.stretch(&start, &stretch_outputs, settings, Some(&mut watch)).map_err(|mut e| {
            // Steps that vanish right after a reset: the resets come ever closer.
            if rearmed.is_some() && matches!(e.reason, Reason::StepSizeTooSmall { .. }) {
                e.reason = Reason::EventsAccumulate { count: all.events.len() };
            }
            e
        })?;
        all.stats.add(&part.stats);
        for (k, (t, y)) in part.times.iter().zip(&part.states).enumerate() {
            if !(k == 0 && skip_first) {
                all.times.push(*t);
                all.states.push(y);
            }
        }
        let (recorded, hit, side, budget) = (std::mem::take(&mut watch.recorded), watch.hit.take(), watch.hit_side, watch.max_events());
        all.events.extend(recorded);
        let Some(mut hit) = hit else { break };
        if all.events.len() >= budget {
            return Err(RunError { t: hit.t, state: hit.state, reason: Reason::TooManyEvents(budget) });
        }
        if events.kinds[hit.event].1 == EventAction::Stop {
            all.events.push(hit);
            all.stopped = true;
            break;
        }
        let mut after = vec![0.0; y0.len()];
        (events.reset)(hit.event, hit.t, &hit.state, &mut after).map_err(|e| RunError { t: hit.t, state: hit.state.clone(), reason: Reason::Rhs(e) })?;
        // A reset sends the state back to the side it came from (or onto the surface): one
        // that lands past it would cross again at once, without end.
        // (Past by more than the located crossing's own distance from it, and round-off.)
        let (mut values, mut at_hit) = (vec![0.0; events.kinds.len()], vec![0.0; events.kinds.len()]);
        (events.values)(hit.t, &after, &mut values).map_err(|e| RunError { t: hit.t, state: after.clone(), reason: Reason::Rhs(e) })?;
        (events.values)(hit.t, &hit.state, &mut at_hit).map_err(|e| RunError { t: hit.t, state: hit.state.clone(), reason: Reason::Rhs(e) })?;
        let near = 1e-9f64.max(100.0 * at_hit[hit.event].abs());
        if values[hit.event] * side < -near {
            return Err(RunError { t: hit.t, state: after, reason: Reason::ResetPastSurface { event: hit.event, value: values[hit.event] } });
        }
        // Go on from the reset state; an output at the event's very time is the state after it.
        let rest: Vec<f64> = outputs.iter().copied().filter(|o| *o >= hit.t).collect();
        skip_first = rest.first() != Some(&hit.t);
        stretch_outputs = std::iter::once(hit.t).chain(rest.into_iter().filter(|o| *o > hit.t)).collect();
        start = after.clone();
        rearmed = Some((hit.event, side));
        hit.after = Some(after);
        all.events.push(hit);
        if stretch_outputs.len() == 1 && skip_first {
            break;
        }
    }
    Ok(all)
}

/// The run's functions, for each stretch between events.
struct Runner<'f, 'j, 'p> {
    f: &'f mut dyn FnMut(f64, &[f64], &mut [f64]) -> Result<(), Failure>,
    jacobian: Option<JacobianFn<'j>>,
    project: Option<Projector<'p>>,
}

impl Runner<'_, '_, '_> {
    /// Integrates from `y0` at `outputs[0]` over `outputs`, watching events when `watch` is given.
    fn stretch(&mut self, y0: &[f64], outputs: &[f64], settings: &Settings, watch: Option<&mut events::Watch>) -> Result<Solution, RunError> {
        if outputs.is_empty() || outputs.windows(2).any(|w| !(w[1] > w[0])) {
            return Err(RunError { t: outputs.first().copied().unwrap_or(0.0), state: y0.to_vec(), reason: Reason::BadOutputTimes });
        }
        let f = &mut self.f;
        let mut counted = |t: f64, y: &[f64], dy: &mut [f64], stats: &mut Stats| -> Result<(), Reason> {
            stats.rhs_calls += 1;
            f(t, y, dy).map_err(Reason::Rhs)
        };
        let project = &mut self.project;
        let mut projector = |t: f64, y: &mut [f64]| -> Result<bool, Reason> {
            match project.as_mut() {
                Some(p) => p(t, y).map_err(Reason::Rhs),
                None => Ok(false),
            }
        };
        match settings.method {
            Method::Rk4 { h } => rk4::run(&mut counted, &mut projector, y0, outputs, h, settings.max_steps),
            Method::Dopri5 => driver::drive(&mut dopri5::Dopri5::new(y0.len()), &mut counted, &mut projector, y0, outputs, settings, watch),
            Method::Dop853 => driver::drive(&mut dop853::Dop853::new(y0.len()), &mut counted, &mut projector, y0, outputs, settings, watch),
            Method::Rosenbrock23 => {
                let n = y0.len();
                let (mut dy, mut flat) = (vec![0.0; n], vec![0.0; n * n]);
                let jacobian = &mut self.jacobian;
                let mut jac = |t: f64, y: &[f64], j: &mut nalgebra::DMatrix<f64>| -> Result<bool, Reason> {
                    let Some(exact) = jacobian.as_mut() else { return Ok(false) };
                    exact(t, y, &mut dy, &mut flat).map_err(Reason::Rhs)?;
                    for i in 0..n {
                        for k in 0..n {
                            j[(i, k)] = flat[i * n + k];
                        }
                    }
                    Ok(true)
                };
                driver::drive(&mut rosenbrock::Rosenbrock::new(n, &mut jac), &mut counted, &mut projector, y0, outputs, settings, watch)
            }
        }
    }
}

/// The exact Jacobian as the stiff stepper sees it: fills `J` and returns true, or returns
/// false when there is none (the stepper then differences the right-hand side).
type Jacobian<'a> = dyn FnMut(f64, &[f64], &mut nalgebra::DMatrix<f64>) -> Result<bool, Reason> + 'a;

/// The projection hook as the steppers see it.
type Project<'a> = dyn FnMut(f64, &mut [f64]) -> Result<bool, Reason> + 'a;

/// The right-hand side as the steppers see it, counting calls.
type Rhs<'a> = dyn FnMut(f64, &[f64], &mut [f64], &mut Stats) -> Result<(), Reason> + 'a;

/// Weighted RMS norm of an error estimate (Hairer's `sk = atol + rtol * max(|y0|, |y1|)`).
fn error_norm(err: &[f64], y0: &[f64], y1: &[f64], rtol: f64, atol: f64) -> f64 {
    let n = err.len().max(1) as f64;
    let sum: f64 = err
        .iter()
        .zip(y0.iter().zip(y1))
        .map(|(e, (a, b))| {
            let sk = atol + rtol * a.abs().max(b.abs());
            (e / sk) * (e / sk)
        })
        .sum();
    (sum / n).sqrt()
}

/// Hairer's initial step guess for an order-`order` method.
fn initial_step(f: &mut Rhs, t: f64, y: &[f64], f0: &[f64], order: i32, s: &Settings, stats: &mut Stats) -> Result<f64, Reason> {
    let n = y.len();
    let sk: Vec<f64> = y.iter().map(|v| s.atol + s.rtol * v.abs()).collect();
    let dnf: f64 = f0.iter().zip(&sk).map(|(a, b)| (a / b) * (a / b)).sum::<f64>() / n as f64;
    let dny: f64 = y.iter().zip(&sk).map(|(a, b)| (a / b) * (a / b)).sum::<f64>() / n as f64;
    let mut h = if dnf <= 1e-10 || dny <= 1e-10 { 1e-6 } else { (dny / dnf).sqrt() * 0.01 };
    h = h.min(s.h_max);
    // The trial Euler step, ten times shorter where the model refuses the state it reaches.
    let mut f1 = vec![0.0; n];
    let mut refusals = 0;
    loop {
        let y1: Vec<f64> = y.iter().zip(f0).map(|(a, b)| a + h * b).collect();
        match f(t + h, &y1, &mut f1, stats) {
            Ok(()) => break,
            Err(Reason::Rhs(failure)) if of_the_state(&failure) && refusals < REFUSALS => {
                refusals += 1;
                h *= 0.1;
            }
            Err(r) => return Err(r),
        }
    }
    let der2: f64 = (f1.iter().zip(f0).zip(&sk).map(|((a, b), c)| ((a - b) / c).powi(2)).sum::<f64>() / n as f64).sqrt() / h;
    let der12 = der2.max(dnf.sqrt());
    let h1 = if der12 <= 1e-15 { (h * 1e-3).max(1e-6) } else { (0.01 / der12).powf(1.0 / order as f64) };
    Ok((100.0 * h).min(h1).min(s.h_max))
}

/// How many times in a row the model may refuse the states the first step only tries (the
/// initial step's trial Euler step, the first step's stages), each time with the step
/// shortened, before the run stops with the refusal.
const REFUSALS: usize = 6;

/// Whether the model's refusal is of the state it was given (a singular configuration, a value
/// that is not finite), which a shorter step may not reach; a wrong length or a missing
/// function is not.
fn of_the_state(failure: &Failure) -> bool {
    matches!(failure, Failure::Singular { .. } | Failure::SingularMatrix { .. } | Failure::NonFinite { .. })
}

/// `out = y + h * sum_j a_j k_j` (zero weights skipped).
fn combine(out: &mut [f64], y: &[f64], h: f64, a: &[f64], k: &[Vec<f64>]) {
    out.copy_from_slice(y);
    axpy_stages(out, h, a, k);
}

/// `out += h * sum_j a_j k_j`.
fn axpy_stages(out: &mut [f64], h: f64, a: &[f64], k: &[Vec<f64>]) {
    for (aj, kj) in a.iter().zip(k) {
        if *aj != 0.0 {
            let w = h * aj;
            for (o, x) in out.iter_mut().zip(kj) {
                *o += w * x;
            }
        }
    }
}

/// Before an adaptive step: the step budget, step-size underflow, and the last step shortened
/// to end on `t_end`. Returns the step to try.
/// The next step, or why there is none. `y` and its rate `f0` tell an underflowing step whose
/// cause is numbers at the edge of f64 (a parameter or a rate of 1e200) from a tolerance too
/// tight for the problem.
fn next_step_size(stats: &Stats, s: &Settings, t: f64, h: f64, t_end: f64, y: &[f64], f0: &[f64]) -> Result<f64, Reason> {
    if stats.steps + stats.rejected >= s.max_steps {
        return Err(Reason::TooManySteps(s.max_steps));
    }
    if 0.1 * h.abs() <= t.abs().max(1.0) * f64::EPSILON {
        // Beyond 1e150 the products in a step overflow: that, not the tolerance, stops it.
        let huge = |v: &f64| !(v.abs() <= 1e150);
        if let Some(index) = f0.iter().position(huge) {
            return Err(Reason::Overflow { what: "rate", index, value: f0[index] });
        }
        if let Some(index) = y.iter().position(huge) {
            return Err(Reason::Overflow { what: "state", index, value: y[index] });
        }
        return Err(Reason::StepSizeTooSmall { h });
    }
    Ok(if t + 1.01 * h >= t_end { t_end - t } else { h })
}

/// After an accepted step ending at `t` with state `y`, whose right-hand side `fsal` the
/// method already has: the divergence check, the first stage `k0` of the next step, and the
/// projection (which re-evaluates `k0` and rewrites an output written at `t`).
#[allow(clippy::too_many_arguments)]
fn finish_step(
    f: &mut Rhs,
    project: &mut Project,
    t: f64,
    y: &mut [f64],
    fsal: &[f64],
    k0: &mut [f64],
    states: &mut States,
    last_output: f64,
    stats: &mut Stats,
) -> Result<(), Reason> {
    if !finite(y) {
        return Err(Reason::Diverged);
    }
    k0.copy_from_slice(fsal);
    if project(t, y)? {
        f(t, y, k0, stats)?;
        if last_output == t {
            states.last_mut().expect("an output was written").copy_from_slice(y);
        }
    }
    Ok(())
}

/// The step after an accepted one: the controller's proposal, capped by `h_max`, and not
/// larger than the step just taken when that one followed a rejection.
fn grown_step(proposal: f64, taken: f64, s: &Settings, rejected_last: bool) -> f64 {
    let h = proposal.min(s.h_max);
    if rejected_last { h.min(taken) } else { h }
}

/// What [`Stats::stiff_at`] tells the user, without the way to ask for the stiff method (each
/// front end names its own: `--method ros23`, `method="ros23"`).
///
/// ```
/// let note = runtime::integrate::stiffness_note(0.25);
/// assert_eq!(note, "looks stiff from t = 0.250000 (Hairer's test: the step size is held by stability, not accuracy)");
/// ```
pub fn stiffness_note(t: f64) -> String {
    format!("looks stiff from t = {t:.6} (Hairer's test: the step size is held by stability, not accuracy)")
}

/// Hairer's stiffness test, as DOPRI5 and DOP853 carry it (`dopri5.f`, `dop853.f`): after each
/// accepted step, `h |lambda|` estimated from two stages evaluated at the same time (the
/// difference of their rates over the difference of their arguments); beyond the method's
/// stability boundary on 15 steps in a row (six in-bounds steps between reset the count), the
/// step size is held by stability, not accuracy, and the time is recorded in
/// [`Stats::stiff_at`]. Hairer tests every thousandth step until one is beyond; this tests every
/// step (one pass over the state, against a step's seven or twelve right-hand sides).
struct StiffnessTest {
    /// The method's stability boundary on the negative real axis: 3.25 for DOPRI5, 6.1 for
    /// DOP853 (Hairer's values).
    boundary: f64,
    beyond: usize,
    within: usize,
}

impl StiffnessTest {
    fn new(boundary: f64) -> StiffnessTest {
        StiffnessTest { boundary, beyond: 0, within: 0 }
    }

    /// One accepted step of size `h` from `t`: the rates `f_a`, `f_b` at the arguments `y_a`,
    /// `y_b`, both at the same time.
    fn observe(&mut self, t: f64, h: f64, (f_a, y_a): (&[f64], &[f64]), (f_b, y_b): (&[f64], &[f64]), stats: &mut Stats) {
        if stats.stiff_at.is_some() {
            return;
        }
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..y_a.len() {
            num += (f_a[i] - f_b[i]).powi(2);
            den += (y_a[i] - y_b[i]).powi(2);
        }
        if den > 0.0 && h.abs() * (num / den).sqrt() > self.boundary {
            self.within = 0;
            self.beyond += 1;
            if self.beyond == 15 {
                stats.stiff_at = Some(t);
            }
        } else {
            self.within += 1;
            if self.within == 6 {
                self.beyond = 0;
            }
        }
    }
}

fn finite(y: &[f64]) -> bool {
    y.iter().all(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `y'' = -y`, `y(0) = 1`: `y = cos t`.
    fn oscillator(_t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Failure> {
        dy[0] = y[1];
        dy[1] = -y[0];
        Ok(())
    }

    /// A run refused on its first trial stage says both times: the last step accepted (the
    /// start) and the stage's own, where the model refused (it read "stopped at t = 0:
    /// singular at t = 0.006", two times for one stop).
    #[test]
    fn a_stop_names_the_last_accepted_step_and_the_refusal_apart() {
        let mut refuse =
            |t: f64, _: &[f64], _: &mut [f64]| if t > 0.0 { Err(Failure::Singular { t, condition: "mass matrix M".into(), value: 1.0 }) } else { Ok(()) };
        let err = integrate(&mut refuse, &[1.0, 0.0], &[0.0, 1.0], &Settings { h_max: 0.1, ..Settings::default() }).unwrap_err();
        assert_eq!(err.t, 0.0);
        let said = err.to_string();
        assert!(said.starts_with("integration stopped after t = 0, its last accepted step: singular configuration at t = 0."), "{said}");
    }

    /// A model that refuses the states only a too large first step reaches (the first step's
    /// size is a guess, made for the slow part of a stiff system: an explicit method's stages
    /// then grow without bound, as a floating robot hand's light fingers did) is integrated from
    /// a shorter first step, to the closed form; its refusals were met. Here `x' = -x` beside
    /// `z' = -1e6 z` from `z = 1e-8`, refusing `|z| > 1`, which the motion never reaches. A run
    /// refused once under way still stops there (the test above).
    #[test]
    fn a_first_step_refused_by_the_model_is_shortened() {
        for method in [Method::Dopri5, Method::Dop853] {
            let refusals = std::cell::Cell::new(0);
            let mut stiff = |t: f64, y: &[f64], dy: &mut [f64]| {
                if y[1].abs() > 1.0 {
                    refusals.set(refusals.get() + 1);
                    return Err(Failure::Singular { t, condition: "|z| > 1".into(), value: y[1] });
                }
                dy[0] = -y[0];
                dy[1] = -1e6 * y[1];
                Ok(())
            };
            let s = Settings { method, rtol: 1e-9, atol: 1e-9, h_max: 1.0, ..Settings::default() };
            let sol = integrate(&mut stiff, &[1.0, 1e-8], &[0.0, 0.01], &s).unwrap_or_else(|e| panic!("{method:?}: {e}"));
            assert!(refusals.get() > 0 && sol.stats.rejected > 0, "{method:?}: {} refusals, {:?}", refusals.get(), sol.stats);
            let y = &sol.states[1];
            assert!((y[0] - (-0.01f64).exp()).abs() < 1e-8 && y[1].abs() < 1e-8, "{method:?}: {y:?}");
        }
    }

    /// Hairer's reference problem for the explicit pairs (Hairer, Norsett & Wanner, "Solving
    /// ODEs I", section II.0): the Arenstorf orbit of the restricted three-body problem, periodic
    /// with period `T = 17.0652165601579625588917206249`.
    fn arenstorf(_t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Failure> {
        const MU: f64 = 0.012277471;
        let mu1 = 1.0 - MU;
        let d1 = ((y[0] + MU).powi(2) + y[1] * y[1]).powf(1.5);
        let d2 = ((y[0] - mu1).powi(2) + y[1] * y[1]).powf(1.5);
        dy[0] = y[2];
        dy[1] = y[3];
        dy[2] = y[0] + 2.0 * y[3] - mu1 * (y[0] + MU) / d1 - MU * (y[0] - mu1) / d2;
        dy[3] = y[1] - 2.0 * y[2] - mu1 * y[1] / d1 - MU * y[1] / d2;
        Ok(())
    }

    /// After one period the orbit closes: each explicit pair returns to the start, its error
    /// shrinking with the tolerance, DOP853 with fewer steps than DOPRI5 at tight tolerances.
    #[test]
    fn the_arenstorf_orbit_closes_after_one_period() {
        const PERIOD: f64 = 17.065_216_560_157_963;
        let y0 = [0.994, 0.0, 0.0, -2.001_585_106_379_082_5];
        let closing = |method: Method, tol: f64| {
            let s = Settings { method, rtol: tol, atol: tol, ..Settings::default() };
            let sol = integrate(&mut arenstorf, &y0, &[0.0, PERIOD / 2.0, PERIOD], &s).unwrap();
            // Not stiff: the close approaches shorten the steps for accuracy, not stability.
            assert_eq!(sol.stats.stiff_at, None, "{method} at {tol:e}");
            let end = &sol.states[2];
            (end.iter().zip(&y0).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max), sol.stats.steps)
        };
        for method in [Method::Dopri5, Method::Dop853] {
            let (loose, _) = closing(method, 1e-6);
            let (tight, steps) = closing(method, 1e-10);
            assert!(tight < 1e-5, "{method}: closes to {tight:e} at 1e-10");
            assert!(tight < 1e-2 * loose, "{method}: {tight:e} at 1e-10 against {loose:e} at 1e-6");
            assert!(steps > 50, "{method}: {steps} steps");
        }
        assert!(closing(Method::Dop853, 1e-10).1 < closing(Method::Dopri5, 1e-10).1);
    }

    /// Van der Pol's oscillator with mu = 1e3, the stiff reference problem: the Rosenbrock
    /// method crosses the slow manifold in a few hundred steps, where DOPRI5 and DOP853 need
    /// tens of thousands and find the problem stiff (Hairer's test, each at its own stability
    /// boundary); all reach the same state.
    #[test]
    fn van_der_pol_at_mu_1e3_is_stiff_for_the_explicit_pairs_and_not_for_rosenbrock() {
        let mut vdp = |_t: f64, y: &[f64], dy: &mut [f64]| -> Result<(), Failure> {
            dy[0] = y[1];
            dy[1] = 1e3 * (1.0 - y[0] * y[0]) * y[1] - y[0];
            Ok(())
        };
        let outputs = [0.0, 300.0];
        let run = |method: Method, vdp: &mut dyn FnMut(f64, &[f64], &mut [f64]) -> Result<(), Failure>| {
            integrate(vdp, &[2.0, 0.0], &outputs, &Settings { method, rtol: 1e-6, atol: 1e-6, ..Settings::default() }).unwrap()
        };
        let ros = run(Method::Rosenbrock23, &mut vdp);
        assert_eq!(ros.stats.stiff_at, None, "the stiff method runs no stiffness test");
        for method in [Method::Dopri5, Method::Dop853] {
            let explicit = run(method, &mut vdp);
            assert!(
                ros.stats.steps < 2_000 && explicit.stats.steps > 20 * ros.stats.steps,
                "ROS23 {} steps, {method} {}",
                ros.stats.steps,
                explicit.stats.steps
            );
            assert!(explicit.stats.stiff_at.is_some_and(|t| t < 10.0), "{method}: {:?}", explicit.stats.stiff_at);
            assert!((ros.states[1][0] - explicit.states[1][0]).abs() < 1e-3, "{} against {method}'s {}", ros.states[1][0], explicit.states[1][0]);
        }
    }

    /// RK4's order: halving the step divides the error by 2^4.
    #[test]
    fn rk4_converges_at_order_four() {
        let outputs: Vec<f64> = (0..=10).map(|i| i as f64).collect();
        let (coarse, _) = max_error(&Settings { method: Method::Rk4 { h: 0.1 }, ..Settings::default() }, &outputs);
        let (fine, _) = max_error(&Settings { method: Method::Rk4 { h: 0.05 }, ..Settings::default() }, &outputs);
        let order = (coarse / fine).log2();
        assert!((order - 4.0).abs() < 0.1, "observed order {order}");
    }

    fn max_error(settings: &Settings, outputs: &[f64]) -> (f64, Stats) {
        let sol = integrate(&mut oscillator, &[1.0, 0.0], outputs, settings).unwrap();
        let e = sol.times.iter().zip(&sol.states).map(|(t, y)| (y[0] - t.cos()).abs().max((y[1] + t.sin()).abs())).fold(0.0, f64::max);
        (e, sol.stats)
    }

    fn grid(end: f64, dt: f64) -> Vec<f64> {
        (0..=((end / dt).round() as usize)).map(|i| i as f64 * dt).collect()
    }

    #[test]
    fn rk4_is_fourth_order() {
        let out = grid(10.0, 0.5);
        let (e1, _) = max_error(&Settings { method: Method::Rk4 { h: 0.1 }, ..Settings::default() }, &out);
        let (e2, s2) = max_error(&Settings { method: Method::Rk4 { h: 0.05 }, ..Settings::default() }, &out);
        let ratio = e1 / e2;
        assert!((14.0..18.0).contains(&ratio), "error ratio {ratio} for halved steps");
        assert_eq!((s2.steps, s2.rhs_calls), (200, 800));
    }

    /// Each adaptive method's order, and its dense output's: with a tolerance so loose that
    /// every step is accepted at `h_max`, halving `h_max` divides the error at the steps' ends by
    /// `2^p` (DOPRI5 5, DOP853 8, Rosenbrock 2(3) 2), and the error over a fine grid of dense
    /// outputs between them by the same (an interpolant of order q adds a local error of order
    /// `q + 1`, at most the method's own here).
    #[test]
    fn each_method_and_its_dense_output_converge_at_their_order() {
        for (method, order, h) in [(Method::Dopri5, 5.0, 0.2), (Method::Dop853, 8.0, 0.5), (Method::Rosenbrock23, 2.0, 0.05)] {
            let observed = |outputs: &[f64]| {
                let errors: Vec<f64> = [h, h / 2.0]
                    .iter()
                    .map(|&h_max| {
                        let s = Settings { method, rtol: 1e3, atol: 1e3, h_max, ..Settings::default() };
                        max_error(&s, outputs).0
                    })
                    .collect();
                (errors[0] / errors[1]).log2()
            };
            // The end of the run only (a step lands on it), then outputs between the steps.
            let at_end = observed(&[0.0, 10.0]);
            let dense = observed(&grid(10.0, 0.01));
            assert!((at_end - order).abs() < 0.35, "{method}: order {at_end} at the end, expected {order}");
            assert!((dense - order).abs() < 0.35, "{method}: order {dense} over the dense outputs, expected {order}");
        }
    }

    #[test]
    fn adaptive_methods_meet_their_tolerance_and_tighten_with_it() {
        // Many outputs per step: the dense outputs are checked too.
        for (method, out) in [(Method::Dopri5, grid(20.0, 0.01)), (Method::Dop853, grid(20.0, 0.01))] {
            let mut last = f64::INFINITY;
            for rtol in [1e-4, 1e-7, 1e-10] {
                let (e, stats) = max_error(&Settings { method, rtol, atol: rtol, ..Settings::default() }, &out);
                eprintln!("{method} rtol {rtol:e}: error {e:e}, {stats:?}");
                assert!(e < 200.0 * rtol, "{method} rtol {rtol}: error {e:e}");
                assert!(e < last, "{method}: error must fall with rtol");
                assert!(stats.rejected <= stats.steps);
                last = e;
            }
        }
        let (e, _) = max_error(&Settings { method: Method::Dop853, rtol: 1e-13, atol: 1e-13, ..Settings::default() }, &grid(20.0, 0.01));
        assert!(e < 1e-11, "DOP853 at 1e-13: {e:e}");
    }

    #[test]
    fn rosenbrock_meets_its_tolerance_with_exact_or_differenced_jacobians() {
        let out = grid(10.0, 0.05);
        let mut last = f64::INFINITY;
        for rtol in [1e-3, 1e-5, 1e-7] {
            let s = Settings { method: Method::Rosenbrock23, rtol, atol: rtol, ..Settings::default() };
            let (e, stats) = max_error(&s, &out);
            // Second order with local error control: the global error over 1.6 periods is a few
            // hundred tolerances.
            assert!(e < 1000.0 * rtol, "rtol {rtol}: error {e:e}");
            assert!(e < last);
            assert_eq!(stats.jacobians, stats.steps, "one Jacobian per accepted step: {stats:?}");
            last = e;
            // The exact Jacobian of the oscillator: the same steps, fewer right-hand sides.
            let mut jac = |_t: f64, y: &[f64], dy: &mut [f64], j: &mut [f64]| -> Result<(), Failure> {
                oscillator(0.0, y, dy)?;
                j.copy_from_slice(&[0.0, 1.0, -1.0, 0.0]);
                Ok(())
            };
            let exact = integrate_with_jacobian(&mut oscillator, Some(&mut jac), None, &[1.0, 0.0], &out, &s).unwrap();
            assert_eq!(exact.stats.steps, stats.steps);
            assert_eq!(exact.stats.rhs_calls + 2 * stats.jacobians, stats.rhs_calls);
        }
    }

    /// A stiff linear system with a slow mode: `y1' = -k (y1 - y2)`, `y2' = -y2`, `k = 1e6`.
    /// DOPRI5's steps are bounded by stability (about `3.3 / k`); the Rosenbrock method's by
    /// the slow mode's accuracy.
    #[test]
    fn the_stiff_method_takes_accuracy_bound_steps_where_explicit_ones_cannot() {
        let k = 1e6;
        let mut f = |_t: f64, y: &[f64], dy: &mut [f64]| -> Result<(), Failure> {
            dy[0] = -k * (y[0] - y[1]);
            dy[1] = -y[1];
            Ok(())
        };
        let out = [0.0, 0.5, 1.0];
        let stiff = integrate(&mut f, &[2.0, 1.0], &out, &Settings { method: Method::Rosenbrock23, rtol: 1e-6, atol: 1e-9, ..Settings::default() }).unwrap();
        // y2 = exp(-t); y1 follows it: y1 = y2 k / (k - 1) + transient.
        let exact = (-1.0f64).exp();
        assert!((stiff.states[2][1] - exact).abs() < 1e-5, "{:?}", &stiff.states[2]);
        assert!((stiff.states[2][0] - exact * k / (k - 1.0)).abs() < 1e-5);
        assert!(stiff.stats.steps < 500, "{:?}", stiff.stats);
        let explicit = integrate(&mut f, &[2.0, 1.0], &out, &Settings { method: Method::Dopri5, rtol: 1e-6, atol: 1e-9, ..Settings::default() }).unwrap();
        assert!(explicit.stats.steps > 100 * stiff.stats.steps, "DOPRI5 {:?} against {:?}", explicit.stats, stiff.stats);
    }

    #[test]
    fn dense_output_takes_fewer_steps_than_outputs() {
        let out = grid(20.0, 0.01);
        let sol = integrate(&mut oscillator, &[1.0, 0.0], &out, &Settings::paper(20.0)).unwrap();
        assert_eq!(sol.states.len(), out.len());
        assert!(sol.stats.steps < 200, "{} steps for 2001 outputs", sol.stats.steps);
        // The paper's cap: no step longer than a tenth of the span.
        assert!(sol.stats.steps >= 10);
    }

    #[test]
    fn failures_stop_the_run_with_time_state_and_reason() {
        let out = grid(1.0, 0.1);
        // A tolerance below what doubles can resolve: the step size underflows.
        let tight = Settings { method: Method::Dopri5, rtol: 1e-30, atol: 1e-30, max_steps: 200_000, ..Settings::default() };
        let err = integrate(&mut oscillator, &[1.0, 0.0], &out, &tight).unwrap_err();
        assert!(matches!(err.reason, Reason::StepSizeTooSmall { .. } | Reason::TooManySteps(_)), "{err}");
        // A fixed step far too large for a stiff decay diverges and says so.
        let mut stiff = |_t: f64, y: &[f64], dy: &mut [f64]| -> Result<(), Failure> {
            dy[0] = -1000.0 * y[0];
            Ok(())
        };
        let err = integrate(&mut stiff, &[1.0], &grid(100.0, 1.0), &Settings { method: Method::Rk4 { h: 0.5 }, ..Settings::default() }).unwrap_err();
        assert_eq!(err.reason, Reason::Diverged);
        assert!(err.t > 0.0);
        // A right-hand side that refuses: its message, the time, the last good state.
        let mut refuses = |t: f64, y: &[f64], dy: &mut [f64]| -> Result<(), Failure> {
            if t > 0.5 {
                return Err(Failure::Singular { t, condition: "t - 1/2".into(), value: 0.5 - t });
            }
            dy[0] = y[0];
            Ok(())
        };
        let err = integrate(&mut refuses, &[1.0], &out, &Settings::default()).unwrap_err();
        assert!(matches!(&err.reason, Reason::Rhs(Failure::Singular { condition, .. }) if condition == "t - 1/2"), "{err}");
        assert!(err.t <= 0.5 + 1e-12 && err.state[0] > 1.0);
        // Output times that go backwards.
        assert_eq!(integrate(&mut oscillator, &[1.0, 0.0], &[0.0, 1.0, 0.5], &Settings::default()).unwrap_err().reason, Reason::BadOutputTimes);
    }
}
