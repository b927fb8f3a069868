//! Events: zero crossings of functions of the state, watched after every accepted step and
//! located inside it on the method's dense output by a bracketing root finder (the Illinois
//! variant of regula falsi, with bisection as its fallback), to 1e-12 in time. What happens
//! there is the event's [`EventAction`]: the run stops, the crossing is recorded, or a reset map
//! gives the state the run goes on from (an impact).

use super::{Reason, Stats};
use seam::Failure;
pub use seam::{Direction, EventAction};

/// The event functions of a run and what happens at each.
///
/// ```
/// use runtime::integrate::{Direction, EventAction, Events, Method, Settings, integrate_with_events};
/// // A ball dropped from 1 m onto a floor that returns 0.9 of its speed.
/// let mut f = |_t: f64, y: &[f64], dy: &mut [f64]| -> Result<(), seam::Failure> {
///     dy[0] = y[1];
///     dy[1] = -9.81;
///     Ok(())
/// };
/// let mut height = |_t: f64, y: &[f64], g: &mut [f64]| -> Result<(), seam::Failure> {
///     g[0] = y[0];
///     Ok(())
/// };
/// let mut bounce = |_k: usize, _t: f64, y: &[f64], after: &mut [f64]| -> Result<(), seam::Failure> {
///     after[0] = y[0];
///     after[1] = -0.9 * y[1];
///     Ok(())
/// };
/// let mut events = Events::new(vec![(Direction::Falling, EventAction::Reset)], &mut height, &mut bounce);
/// let s = Settings { method: Method::Dop853, rtol: 1e-12, atol: 1e-12, ..Settings::default() };
/// let sol = integrate_with_events(&mut f, None, None, &mut events, &[1.0, 0.0], &[0.0, 1.0], &s).unwrap();
/// // The first impact is at sqrt(2 h / g).
/// assert!((sol.events[0].t - (2.0f64 / 9.81).sqrt()).abs() < 1e-12);
/// ```
pub struct Events<'a> {
    /// Per event: the crossing that counts, and the action.
    pub kinds: Vec<(Direction, EventAction)>,
    /// `values(t, y, g)`: every event function at a state.
    pub values: &'a mut dyn FnMut(f64, &[f64], &mut [f64]) -> Result<(), Failure>,
    /// `reset(k, t, y, after)`: the state after event `k` (events whose action is `Reset`).
    pub reset: &'a mut dyn FnMut(usize, f64, &[f64], &mut [f64]) -> Result<(), Failure>,
    /// The most events a run may have: beyond it the run stops with
    /// [`Reason::TooManyEvents`], as at a Zeno point where events accumulate.
    pub max_events: usize,
}

impl<'a> Events<'a> {
    /// The events `kinds`, their functions and reset map, at most 10,000 of them in a run.
    pub fn new(
        kinds: Vec<(Direction, EventAction)>,
        values: &'a mut dyn FnMut(f64, &[f64], &mut [f64]) -> Result<(), Failure>,
        reset: &'a mut dyn FnMut(usize, f64, &[f64], &mut [f64]) -> Result<(), Failure>,
    ) -> Events<'a> {
        Events { kinds, values, reset, max_events: 10_000 }
    }
}

/// An event that happened: which, when, the state there, and (for a reset) the state after.
#[derive(Clone, Debug, PartialEq)]
pub struct Occurrence {
    pub event: usize,
    pub t: f64,
    pub state: Vec<f64>,
    pub after: Option<Vec<f64>>,
}

/// The points of a step at which every event function is sampled (on the method's dense
/// output, the step's end the last of them): a step in which one event's samples change sign
/// more than once is done again, shorter, so that each crossing gets a step of its own. A
/// crossing is found when its function changes sign once between two neighbouring samples;
/// one that changes sign and back between them (an event faster than an eighth of a step) can
/// be missed: `h_max` below its time scale finds it.
pub const SAMPLES_PER_STEP: usize = 8;

/// The tolerance in time of a located event at time `t`: 1e-12, or the resolution of `t`
/// where that is coarser.
pub fn time_tolerance(t: f64) -> f64 {
    1e-12f64.max(4.0 * f64::EPSILON * t.abs())
}

/// The events as the driver watches them during one stretch of a run.
pub(super) struct Watch<'w, 'a> {
    events: &'w mut Events<'a>,
    /// The event just reset, and the side of zero it is taken to leave to (the side it came
    /// from: a reset sends it back, as an impact does): it sits on its zero, so for its first
    /// step it is searched from a short time after the reset, where it must have left.
    rearmed: Option<(usize, f64)>,
    before: Vec<f64>,
    after: Vec<f64>,
    probe: Vec<f64>,
    /// The recorded events of the stretch, in time order.
    pub recorded: Vec<Occurrence>,
    /// The event that ended the stretch (a stop or a reset), when one did.
    pub hit: Option<Occurrence>,
    /// The sign of the hit event's function before its crossing.
    pub hit_side: f64,
    /// The events whose function is zero at the run's start: each is taken to come from the
    /// side opposite to the one it moves to, so that a run starting on an event's surface and
    /// moving through it in its direction (a ball released on its floor) has the event at once.
    at_zero: Vec<bool>,
}

impl<'w, 'a> Watch<'w, 'a> {
    pub fn new(events: &'w mut Events<'a>, rearmed: Option<(usize, f64)>) -> Self {
        let k = events.kinds.len();
        Watch {
            events,
            rearmed,
            before: vec![0.0; k],
            after: vec![0.0; k],
            probe: vec![0.0; k],
            recorded: Vec::new(),
            hit: None,
            hit_side: 0.0,
            at_zero: vec![false; k],
        }
    }

    /// The event functions at the stretch's first state.
    pub fn start(&mut self, t: f64, y: &[f64]) -> Result<(), Reason> {
        (self.events.values)(t, y, &mut self.before).map_err(Reason::Rhs)?;
        for (k, v) in self.before.iter().enumerate() {
            self.at_zero[k] = *v == 0.0 && self.rearmed.is_none_or(|(j, _)| j != k);
        }
        if let Some((k, side)) = self.rearmed {
            self.before[k] = side * f64::MIN_POSITIVE;
        }
        Ok(())
    }

    /// After the accepted step to `(t_new, y_new)`: the event functions there.
    pub fn ended(&mut self, t_new: f64, y_new: &[f64], stats: &mut Stats) -> Result<(), Reason> {
        stats.event_evaluations += 1;
        (self.events.values)(t_new, y_new, &mut self.after).map_err(Reason::Rhs)?;
        Ok(())
    }

    /// Whether an event function crossed zero in its direction between the step's ends (the
    /// caller then calls [`Watch::locate`]).
    pub fn crossed(&self) -> bool {
        self.crossings().next().is_some()
    }

    /// The event functions at [`SAMPLES_PER_STEP`] points of the step `[t, t + h]` on its
    /// dense output: `None` when no event's samples change sign more than once, else the
    /// factor to shorten the step by (it is done again).
    pub fn scan(&mut self, t: f64, h: f64, n: usize, dense: &mut dyn FnMut(f64, &mut [f64]), stats: &mut Stats) -> Result<Option<f64>, Reason> {
        let mut y = vec![0.0; n];
        let samples: Vec<Vec<f64>> = (1..=SAMPLES_PER_STEP)
            .map(|j| {
                if j == SAMPLES_PER_STEP {
                    return Ok(self.after.clone());
                }
                let theta = j as f64 / SAMPLES_PER_STEP as f64;
                dense(theta, &mut y);
                stats.event_evaluations += 1;
                (self.events.values)(t + theta * h, &y, &mut self.probe).map_err(Reason::Rhs)?;
                Ok(self.probe.clone())
            })
            .collect::<Result<_, Reason>>()?;
        // An event that started on its zero comes from the side opposite to the one it leaves
        // to (its first sample off zero in this step).
        for k in 0..self.before.len() {
            if self.at_zero[k]
                && let Some(first) = samples.iter().map(|v| v[k]).find(|v| *v != 0.0)
            {
                self.before[k] = -first.signum() * f64::MIN_POSITIVE;
            }
        }
        let mut last = self.before.clone();
        let mut changes = vec![0usize; last.len()];
        for sample in samples {
            for (k, v) in sample.iter().enumerate() {
                // A zero continues the sign before it: touching zero is not a change.
                if *v != 0.0 {
                    if last[k] != 0.0 && v.signum() != last[k].signum() {
                        changes[k] += 1;
                    }
                    last[k] = *v;
                }
            }
        }
        let most = changes.iter().copied().max().unwrap_or(0);
        Ok((most > 1).then(|| 0.5 / most as f64))
    }

    fn crossings(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.after.len()).filter(|&k| self.events.kinds[k].0.crossed(self.before[k], self.after[k]))
    }

    /// Locates every crossing in the step `[t, t + h]` on the interpolant `dense(theta, out)`:
    /// records the recorded events up to the first stop or reset, and returns the time of that
    /// one (the step is cut there), or `None`.
    pub fn locate(&mut self, t: f64, h: f64, n: usize, dense: &mut dyn FnMut(f64, &mut [f64]), stats: &mut Stats) -> Result<Option<f64>, Reason> {
        let mut found: Vec<(f64, usize)> = Vec::new();
        let crossing: Vec<usize> = self.crossings().collect();
        let mut y = vec![0.0; n];
        for k in crossing {
            let theta = self.root(k, t, h, &mut y, dense, stats)?;
            found.push((theta, k));
        }
        found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for (theta, k) in found {
            let at = if theta >= 1.0 { t + h } else { t + theta * h };
            dense(theta, &mut y);
            let occurrence = Occurrence { event: k, t: at, state: y.clone(), after: None };
            match self.events.kinds[k].1 {
                EventAction::Record => self.recorded.push(occurrence),
                EventAction::Stop | EventAction::Reset => {
                    self.hit_side = self.before[k].signum();
                    self.hit = Some(occurrence);
                    return Ok(Some(at));
                }
            }
        }
        Ok(None)
    }

    /// The step is over: its end is the next step's start, and every event is watched again.
    pub fn advance(&mut self) {
        std::mem::swap(&mut self.before, &mut self.after);
        self.rearmed = None;
        self.at_zero.fill(false);
    }

    /// The fraction of the step `[t, t + h]` where event `k` crosses, on the side past its zero.
    fn root(&mut self, k: usize, t: f64, h: f64, y: &mut [f64], dense: &mut dyn FnMut(f64, &mut [f64]), stats: &mut Stats) -> Result<f64, Reason> {
        let (mut a, mut fa, mut b, mut fb) = (0.0f64, self.before[k], 1.0f64, self.after[k]);
        if fb == 0.0 {
            return Ok(1.0);
        }
        if self.at_zero[k] {
            // On its zero at the start, and leaving it in its direction: it happens there.
            return Ok(0.0);
        }
        let tol = time_tolerance(t + h) / h.abs();
        if self.rearmed.is_some_and(|(j, _)| j == k) {
            // Just reset: searched from ten time tolerances on. Still on the crossed side there,
            // it did not leave its zero (a ball at rest on its floor): it happens again at once.
            a = (10.0 * tol).min(0.5);
            dense(a, y);
            stats.event_evaluations += 1;
            (self.events.values)(t + a * h, y, &mut self.probe).map_err(Reason::Rhs)?;
            fa = self.probe[k];
            if fa.signum() != self.before[k].signum() || fa == 0.0 {
                return Ok(a);
            }
        }
        let mut side = 0;
        for iteration in 0..200 {
            if b - a <= tol {
                break;
            }
            // Illinois' secant point, or a bisection when it stalls.
            let mut c = (a * fb - b * fa) / (fb - fa);
            if iteration >= 60 || !(c > a && c < b) {
                c = 0.5 * (a + b);
            }
            dense(c, y);
            stats.event_evaluations += 1;
            (self.events.values)(t + c * h, y, &mut self.probe).map_err(Reason::Rhs)?;
            let fc = self.probe[k];
            if fc == 0.0 {
                return Ok(c);
            }
            if (fc > 0.0) == (fb > 0.0) {
                (b, fb) = (c, fc);
                if side == -1 {
                    fa *= 0.5;
                }
                side = -1;
            } else {
                (a, fa) = (c, fc);
                if side == 1 {
                    fb *= 0.5;
                }
                side = 1;
            }
        }
        Ok(b)
    }

    /// The events' list and counts, for errors and reports.
    pub fn max_events(&self) -> usize {
        self.events.max_events
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Method, Settings, integrate_with_events};
    use super::*;

    /// `y'' = -y` from `(1, 0)`: `y = cos t` crosses zero falling at pi/2, rising at 3 pi/2.
    fn oscillator(_t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Failure> {
        dy[0] = y[1];
        dy[1] = -y[0];
        Ok(())
    }

    fn settings(method: Method) -> Settings {
        Settings { method, rtol: 1e-12, atol: 1e-12, ..Settings::default() }
    }

    /// Recorded crossings of `cos t` are at the odd multiples of pi/2, each in its direction,
    /// to 1e-12 in time with DOP853 and to the interpolant's accuracy with DOPRI5.
    #[test]
    fn recorded_crossings_are_located_to_the_tolerance() {
        for (method, tol) in [(Method::Dop853, 1e-11), (Method::Dopri5, 1e-8), (Method::Rosenbrock23, 1e-5)] {
            for (direction, first) in [(Direction::Falling, 0.5), (Direction::Rising, 1.5), (Direction::Either, 0.5)] {
                let mut values = |_t: f64, y: &[f64], g: &mut [f64]| -> Result<(), Failure> {
                    g[0] = y[0];
                    Ok(())
                };
                let mut reset = |_: usize, _: f64, _: &[f64], _: &mut [f64]| -> Result<(), Failure> { unreachable!("recorded events reset nothing") };
                let mut events = Events::new(vec![(direction, EventAction::Record)], &mut values, &mut reset);
                let sol = integrate_with_events(&mut oscillator, None, None, &mut events, &[1.0, 0.0], &[0.0, 5.0, 10.0], &settings(method)).unwrap();
                let step = if direction == Direction::Either { 1.0 } else { 2.0 };
                let expected: Vec<f64> = (0..).map(|j| (first + step * j as f64) * std::f64::consts::PI).take_while(|t| *t < 10.0).collect();
                let got: Vec<f64> = sol.events.iter().map(|e| e.t).collect();
                assert_eq!(got.len(), expected.len(), "{method} {direction:?}: {got:?}");
                for (g, e) in got.iter().zip(&expected) {
                    assert!((g - e).abs() < tol, "{method} {direction:?}: {g} against {e}");
                }
                assert!(sol.events.iter().all(|e| e.state[0].abs() < 10.0 * tol && e.after.is_none()));
                // Recording does not change the run: the outputs are the plain run's.
                let plain = super::super::integrate(&mut oscillator, &[1.0, 0.0], &[0.0, 5.0, 10.0], &settings(method)).unwrap();
                assert_eq!(sol.states, plain.states);
                assert!(!sol.stopped);
            }
        }
    }

    /// A stop ends the run at the event: the outputs before it, none after.
    #[test]
    fn a_stop_ends_the_run_at_the_event() {
        let mut values = |_t: f64, y: &[f64], g: &mut [f64]| -> Result<(), Failure> {
            g[0] = y[0] + 0.5;
            Ok(())
        };
        let mut reset = |_: usize, _: f64, _: &[f64], _: &mut [f64]| -> Result<(), Failure> { unreachable!() };
        let mut events = Events::new(vec![(Direction::Falling, EventAction::Stop)], &mut values, &mut reset);
        let outputs: Vec<f64> = (0..=10).map(|k| k as f64 * 0.5).collect();
        let sol = integrate_with_events(&mut oscillator, None, None, &mut events, &[1.0, 0.0], &outputs, &settings(Method::Dop853)).unwrap();
        // cos t = -1/2 at t = 2 pi / 3.
        let at = 2.0 * std::f64::consts::PI / 3.0;
        assert!(sol.stopped);
        assert_eq!(sol.events.len(), 1);
        assert!((sol.events[0].t - at).abs() < 1e-11);
        assert!(sol.times.iter().all(|t| *t < at) && sol.times.len() == 5, "{:?}", sol.times);
    }

    /// A ball bouncing with restitution e: the impact times from the closed form
    /// `t_k = t_1 (1 + 2 (e + ... + e^(k-1)))`, `t_1 = sqrt(2 h / g)`, and the speed after each
    /// impact `e^k sqrt(2 g h)`; the output times between impacts hold the parabola.
    #[test]
    fn a_bouncing_ball_meets_the_closed_form() {
        let (g, e, h0) = (9.81, 0.8, 1.0);
        let mut f = |_t: f64, y: &[f64], dy: &mut [f64]| -> Result<(), Failure> {
            dy[0] = y[1];
            dy[1] = -g;
            Ok(())
        };
        let mut values = |_t: f64, y: &[f64], out: &mut [f64]| -> Result<(), Failure> {
            out[0] = y[0];
            Ok(())
        };
        let mut reset = |_: usize, _: f64, y: &[f64], after: &mut [f64]| -> Result<(), Failure> {
            after[0] = y[0];
            after[1] = -e * y[1];
            Ok(())
        };
        let mut events = Events::new(vec![(Direction::Falling, EventAction::Reset)], &mut values, &mut reset);
        let outputs: Vec<f64> = (0..=40).map(|k| k as f64 * 0.1).collect();
        let sol = integrate_with_events(&mut f, None, None, &mut events, &[h0, 0.0], &outputs, &settings(Method::Dop853)).unwrap();
        let t1 = (2.0 * h0 / g).sqrt();
        let v1 = (2.0 * g * h0).sqrt();
        let mut expected = vec![t1];
        for k in 1..sol.events.len() {
            expected.push(expected[k - 1] + 2.0 * t1 * e.powi(k as i32));
        }
        assert!(sol.events.len() >= 8, "{}", sol.events.len());
        for (k, (o, t)) in sol.events.iter().zip(&expected).enumerate() {
            assert!((o.t - t).abs() < 1e-10 * (k + 1) as f64, "impact {k}: {} against {t}", o.t);
            let speed = o.after.as_ref().unwrap()[1];
            assert!((speed - v1 * e.powi(k as i32 + 1)).abs() < 1e-9, "impact {k}: {speed}");
        }
        // Between impacts the height is the parabola from the last impact.
        assert_eq!(sol.times, outputs);
        for (t, y) in sol.times.iter().zip(&sol.states) {
            let last = sol.events.iter().rev().find(|o| o.t <= *t);
            let height = match last {
                None => h0 - 0.5 * g * t * t,
                Some(o) => {
                    let (dt, v) = (t - o.t, o.after.as_ref().unwrap()[1]);
                    v * dt - 0.5 * g * dt * dt
                }
            };
            assert!((y[0] - height).abs() < 1e-9, "t = {t}: {} against {height}", y[0]);
        }
    }

    /// Events that accumulate (a ball that loses half its speed at every impact comes to rest
    /// at `3 t_1` after infinitely many) end the run with a clear reason instead of looping or
    /// falling through the floor: the event budget, or, within it, the steps vanishing between
    /// ever closer resets.
    #[test]
    fn accumulating_events_end_the_run_with_their_reason() {
        let rest = 3.0 * (2.0f64 / 9.81).sqrt();
        for (budget, expected) in [(20, Reason::TooManyEvents(20)), (10_000, Reason::EventsAccumulate { count: 0 })] {
            let mut f = |_t: f64, y: &[f64], dy: &mut [f64]| -> Result<(), Failure> {
                dy[0] = y[1];
                dy[1] = -9.81;
                Ok(())
            };
            let mut values = |_t: f64, y: &[f64], out: &mut [f64]| -> Result<(), Failure> {
                out[0] = y[0];
                Ok(())
            };
            let mut reset = |_: usize, _: f64, y: &[f64], after: &mut [f64]| -> Result<(), Failure> {
                after[0] = y[0];
                after[1] = -0.5 * y[1];
                Ok(())
            };
            let mut events = Events::new(vec![(Direction::Falling, EventAction::Reset)], &mut values, &mut reset);
            events.max_events = budget;
            let e = integrate_with_events(&mut f, None, None, &mut events, &[1.0, 0.0], &[0.0, 10.0], &settings(Method::Dop853)).unwrap_err();
            match (&e.reason, &expected) {
                (Reason::EventsAccumulate { count }, Reason::EventsAccumulate { .. }) => {
                    assert!(*count > 20 && *count < budget, "{e}");
                    assert!((e.t - rest).abs() < 1e-9, "{e}");
                    assert!(e.to_string().contains("Zeno point"), "{e}");
                }
                _ => {
                    assert_eq!(e.reason, expected);
                    assert!(e.t < rest && e.to_string().contains("more than 20 events"), "{e}");
                }
            }
            // Never below the floor.
            assert!(e.state[0] > -1e-9, "{e}");
        }
    }

    /// A ball starting on its floor and moving down (the event function zero at the start,
    /// moving in the event's direction) bounces at once; it used to fall through the floor to
    /// y = -122. Starting on the floor moving up, it has no event there.
    #[test]
    fn an_event_at_the_start_happens_at_the_start() {
        for (speed, first) in [(-2.0, 0.0), (2.0, 2.0 * 2.0 / 9.81)] {
            let mut f = |_t: f64, y: &[f64], dy: &mut [f64]| -> Result<(), Failure> {
                dy[0] = y[1];
                dy[1] = -9.81;
                Ok(())
            };
            let mut values = |_t: f64, y: &[f64], out: &mut [f64]| -> Result<(), Failure> {
                out[0] = y[0];
                Ok(())
            };
            let mut reset = |_: usize, _: f64, y: &[f64], after: &mut [f64]| -> Result<(), Failure> {
                after[0] = y[0];
                after[1] = -y[1];
                Ok(())
            };
            let mut events = Events::new(vec![(Direction::Falling, EventAction::Reset)], &mut values, &mut reset);
            let times: Vec<f64> = (0..=50).map(|i| 0.1 * i as f64).collect();
            let sol = integrate_with_events(&mut f, None, None, &mut events, &[0.0, speed], &times, &settings(Method::Dop853)).unwrap();
            assert!((sol.events[0].t - first).abs() < 1e-9, "{speed}: {:?}", sol.events[0]);
            assert!(sol.states.iter().all(|y| y[0] > -1e-9), "{speed}: never below the floor");
            // Elastic: the bounces reach 2^2 / (2 g) again and again.
            let top = sol.states.iter().map(|y| y[0]).fold(0.0f64, f64::max);
            assert!((top - 4.0 / (2.0 * 9.81)).abs() < 1e-3, "{speed}: {top}");
        }
    }

    /// `sin(1000 t)` changes sign 3183 times in 10 s, while the dynamics (none) would take a few
    /// long steps: every crossing is found (10 were), each to its time, in every method with a
    /// dense output; and its zero at the start, rising, is one too.
    #[test]
    fn a_fast_event_function_loses_no_crossing() {
        for method in [Method::Dop853, Method::Dopri5, Method::Rosenbrock23] {
            let mut f = |_t: f64, y: &[f64], dy: &mut [f64]| -> Result<(), Failure> {
                dy[0] = -0.1 * y[0];
                Ok(())
            };
            let mut values = |t: f64, _y: &[f64], out: &mut [f64]| -> Result<(), Failure> {
                out[0] = (1000.0 * t).sin();
                Ok(())
            };
            let mut reset = |_: usize, _: f64, _: &[f64], _: &mut [f64]| -> Result<(), Failure> { unreachable!() };
            let mut events = Events::new(vec![(Direction::Either, EventAction::Record)], &mut values, &mut reset);
            let s = Settings { method, rtol: 1e-8, atol: 1e-8, ..Settings::default() };
            let sol = integrate_with_events(&mut f, None, None, &mut events, &[1.0], &[0.0, 10.0], &s).unwrap();
            let expected = (10_000.0 / std::f64::consts::PI).floor() as usize + 1;
            assert_eq!(sol.events.len(), expected, "{method}");
            for (k, e) in sol.events.iter().enumerate() {
                let exact = k as f64 * std::f64::consts::PI / 1000.0;
                assert!((e.t - exact).abs() < 1e-9, "{method}: crossing {k} at {} against {exact}", e.t);
            }
        }
    }

    /// A reset that puts the state past its event's surface (a floor that throws the ball
    /// below itself) is named as such; it was reported as more than 10000 events at a Zeno
    /// point.
    #[test]
    fn a_reset_past_the_surface_is_named() {
        let mut f = |_t: f64, y: &[f64], dy: &mut [f64]| -> Result<(), Failure> {
            dy[0] = y[1];
            dy[1] = -9.81;
            Ok(())
        };
        let mut values = |_t: f64, y: &[f64], out: &mut [f64]| -> Result<(), Failure> {
            out[0] = y[0];
            Ok(())
        };
        let mut reset = |_: usize, _: f64, y: &[f64], after: &mut [f64]| -> Result<(), Failure> {
            after[0] = y[0] - 0.1;
            after[1] = -y[1];
            Ok(())
        };
        let mut events = Events::new(vec![(Direction::Falling, EventAction::Reset)], &mut values, &mut reset);
        let e = integrate_with_events(&mut f, None, None, &mut events, &[1.0, 0.0], &[0.0, 10.0], &settings(Method::Dop853)).unwrap_err();
        assert!(matches!(e.reason, Reason::ResetPastSurface { event: 0, value } if (value + 0.1).abs() < 1e-9), "{e}");
        assert!(e.to_string().contains("past the event's surface") && e.to_string().contains("event #1"), "{e}");
        assert!((e.t - (2.0f64 / 9.81).sqrt()).abs() < 1e-9);
    }

    /// RK4 has no dense output: a run with events and RK4 is refused.
    #[test]
    fn events_need_an_adaptive_method() {
        let mut values = |_t: f64, y: &[f64], g: &mut [f64]| -> Result<(), Failure> {
            g[0] = y[0];
            Ok(())
        };
        let mut reset = |_: usize, _: f64, _: &[f64], _: &mut [f64]| -> Result<(), Failure> { Ok(()) };
        let mut events = Events::new(vec![(Direction::Either, EventAction::Record)], &mut values, &mut reset);
        let e = integrate_with_events(&mut oscillator, None, None, &mut events, &[1.0, 0.0], &[0.0, 1.0], &settings(Method::Rk4 { h: 0.1 })).unwrap_err();
        assert_eq!(e.reason, Reason::EventsNeedDenseOutput);
    }
}
