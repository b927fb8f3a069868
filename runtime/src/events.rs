//! A system run with its model's events (`seam::Model::events`): the event functions
//! `g(t, q, q')` watched on the integrator's dense output ([`crate::integrate::integrate_with_events`]),
//! and a reset applied through the model's reset map: the new `q` and `q'` give the new state by
//! the formulation's own `initial_state` (so the constraints are checked, and the reduced method's
//! conserved momenta `G_I` are those after the impact), the work integral carried across. What a
//! reset changes is kept as a [`Jump`]: the monitors take the impact's energy and momentum out of
//! the balances, which then hold across it.

use crate::integrate::{Events, JacobianFn, Projector, Reason, RunError, Settings, Solution, States, Stats, integrate_with_events};
use crate::system::{Drift, System};
use seam::Failure;
use std::cell::{Cell, RefCell};
use std::ops::ControlFlow;

/// How many right-hand sides a front end lets pass between two checks for Ctrl-C (a check takes
/// the Python interpreter's lock; a call of the largest committed model takes a few
/// microseconds, so a check comes every few milliseconds).
pub const INTERRUPT_CHECK_CALLS: u32 = 1024;

/// What one reset changed: when, which event, the conserved momenta `G_I` after it, and the
/// jumps of the energy function and of the ignorable momenta across it.
#[derive(Clone, Debug, PartialEq)]
pub struct Jump {
    pub t: f64,
    pub event: usize,
    pub g_i: Vec<f64>,
    pub energy: f64,
    pub momenta: Vec<f64>,
}

/// A run with events: the solution (its events in [`Solution::events`]) and the resets' jumps.
#[derive(Clone, Debug)]
pub struct EventRun {
    pub solution: Solution,
    pub jumps: Vec<Jump>,
}

/// `sys` as it stands just before `t` in a run with these `jumps`: with the momenta `G_I` of
/// the last reset before `t` (a state the run reports at an event, before its reset, reads so).
pub fn system_before(sys: &System, jumps: &[Jump], t: f64) -> System {
    let mut before = sys.clone();
    if let Some(j) = jumps.iter().rev().find(|j| j.t < t) {
        before.g_i.clone_from(&j.g_i);
    }
    before
}

/// Integrates `sys` from `y0` over `times` watching its model's events (a model without any is
/// a plain run); `on_rhs(t)` is told of every right-hand side (for progress). The exact
/// Jacobian is used when the system has one, and the projection after every step when its drift
/// control is [`Drift::Projection`].
pub fn run(sys: &System, y0: &[f64], times: &[f64], settings: &Settings, on_rhs: &mut dyn FnMut(f64)) -> Result<EventRun, RunError> {
    run_interruptible(sys, y0, times, settings, &mut |t| {
        on_rhs(t);
        ControlFlow::Continue(())
    })
}

/// [`run`], stopped where `on_rhs(t)` breaks (asked before every right-hand side): the run then
/// ends with [`Reason::Interrupted`] at its last accepted step. A front end checks for Ctrl-C
/// there (the Python wheel does, every [`crate::events::INTERRUPT_CHECK_CALLS`] calls).
///
/// ```
/// use runtime::{events::run_interruptible, integrate::{Reason, Settings}, system::System};
/// use std::ops::ControlFlow;
/// let model = generated::cart_pendulum::model();
/// let (sys, y0) = System::start(&model, seam::FormulationKind::Kane, model.default_params.clone(), &[0.3, 0.0, 0.0], &[0.0; 3]).unwrap();
/// let mut calls = 0;
/// let stop_after_100 = &mut |_t: f64| {
///     calls += 1;
///     if calls > 100 { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
/// };
/// let err = run_interruptible(&sys, &y0, &[0.0, 100.0], &Settings::tight(100.0), stop_after_100).unwrap_err();
/// assert_eq!(err.reason, Reason::Interrupted);
/// assert!(err.t > 0.0 && err.t < 100.0);
/// ```
pub fn run_interruptible(
    sys: &System,
    y0: &[f64],
    times: &[f64],
    settings: &Settings,
    on_rhs: &mut dyn FnMut(f64) -> ControlFlow<()>,
) -> Result<EventRun, RunError> {
    let interrupted = Cell::new(false);
    let current = RefCell::new(sys.clone());
    let jumps = RefCell::new(Vec::new());
    let model = &sys.model;
    let m = model.coordinates.len();
    let mut rhs = |t: f64, y: &[f64], dy: &mut [f64]| {
        if on_rhs(t).is_break() {
            interrupted.set(true);
            // Any failure stops the integrator at its last accepted step; the reason is
            // replaced by `Interrupted` below, so this one is never seen.
            return Err(Failure::Missing { function: "rhs" });
        }
        current.borrow().rhs(t, y, dy)
    };
    let mut exact = |t: f64, y: &[f64], dy: &mut [f64], j: &mut [f64]| current.borrow().jacobian(t, y, dy, j);
    let mut jacobian: Option<JacobianFn> = if sys.has_exact_jacobian() { Some(&mut exact) } else { None };
    let mut project = |t: f64, y: &mut [f64]| current.borrow().project(t, y);
    let mut projector: Option<Projector> = if sys.drift == Drift::Projection { Some(&mut project) } else { None };
    let mut values = |t: f64, y: &[f64], g: &mut [f64]| -> Result<(), Failure> {
        let s = current.borrow();
        let (q, qd) = s.velocities(t, y)?;
        model.event_values(t, &q, &qd, &s.params, g)
    };
    let mut reset = |event: usize, t: f64, y: &[f64], after: &mut [f64]| -> Result<(), Failure> {
        let mut s = current.borrow_mut();
        let (q, qd) = s.velocities(t, y)?;
        let mut maps = vec![0.0; 2 * m * model.events.len()];
        model.event_resets(t, &q, &qd, &s.params, &mut maps)?;
        let (q1, qd1) = maps[2 * m * event..2 * m * (event + 1)].split_at(m);
        let mut g_i = vec![0.0; model.ignorable.len()];
        s.form.initial_state(t, q1, qd1, &s.params, after, &mut g_i)?;
        if let Some(w) = s.form.layout.work_index() {
            after[w] = y[w];
        }
        let (mut e0, mut e1) = ([0.0], [0.0]);
        model.energy(t, &q, &qd, &s.params, &mut e0)?;
        model.energy(t, q1, qd1, &s.params, &mut e1)?;
        let (mut p0, mut p1) = (vec![0.0; g_i.len()], vec![0.0; g_i.len()]);
        model.momenta(t, &q, &qd, &s.params, &mut p0)?;
        model.momenta(t, q1, qd1, &s.params, &mut p1)?;
        let momenta = p1.iter().zip(&p0).map(|(a, b)| a - b).collect();
        jumps.borrow_mut().push(Jump { t, event, g_i: g_i.clone(), energy: e1[0] - e0[0], momenta });
        s.g_i = g_i;
        Ok(())
    };
    let kinds = model.events.iter().map(|e| (e.direction, e.action)).collect();
    let mut events = Events::new(kinds, &mut values, &mut reset);
    // The control law's kinks inside the run: it stops and starts again at each (stepping
    // across one costs steps and accuracy: the error estimate assumes a smooth right-hand side).
    let (first, last) = (times.first().copied().unwrap_or(0.0), times.last().copied().unwrap_or(0.0));
    let breaks: Vec<f64> = sys.controller.as_ref().map_or(Vec::new(), |c| c.breaks().iter().copied().filter(|b| *b > first && *b < last).collect());
    let mut stretch = |y: &[f64], outputs: &[f64]| {
        integrate_with_events(
            &mut rhs,
            jacobian.as_deref_mut().map(|j| j as JacobianFn),
            projector.as_deref_mut().map(|p| p as Projector),
            &mut events,
            y,
            outputs,
            settings,
        )
        .map_err(|e| if interrupted.get() { RunError { reason: Reason::Interrupted, ..e } } else { e })
    };
    if breaks.is_empty() {
        let solution = stretch(y0, times)?;
        return Ok(EventRun { solution, jumps: jumps.into_inner() });
    }
    let mut solution = Solution { times: Vec::new(), states: States::new(y0.len(), times.len()), stats: Stats::default(), events: Vec::new(), stopped: false };
    let (mut start, mut y) = (first, y0.to_vec());
    solution.times.push(first);
    solution.states.push(y0);
    for end in breaks.into_iter().chain([last]) {
        let asked: Vec<f64> = times.iter().copied().filter(|t| *t > start && *t <= end).collect();
        let outputs: Vec<f64> = std::iter::once(start).chain(asked.iter().copied()).chain((asked.last() != Some(&end)).then_some(end)).collect();
        let part = stretch(&y, &outputs)?;
        solution.stats.add(&part.stats);
        solution.events.extend(part.events);
        for (t, state) in part.times.iter().zip(part.states.iter()).skip(1) {
            if asked.contains(t) {
                solution.times.push(*t);
                solution.states.push(state);
            }
        }
        if part.stopped {
            solution.stopped = true;
            break;
        }
        y = part.states.last().expect("a stretch has its start").to_vec();
        start = end;
    }
    Ok(EventRun { solution, jumps: jumps.into_inner() })
}
