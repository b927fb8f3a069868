//! The one adaptive driver behind DOPRI5, DOP853 and Rosenbrock 2(3), as Hairer's codes share
//! one loop: the step budget and underflow check, the attempt, one step-size controller, the
//! dense-output loop over the output times inside an accepted step, and the step's end (the
//! divergence check, projection, the next step's first rate). A method only attempts steps and
//! interpolates inside the last accepted one ([`Stepper`]).

use super::events::Watch;
use super::{Project, REFUSALS, Reason, Rhs, RunError, Settings, Solution, States, Stats, finish_step, grown_step, initial_step, next_step_size, of_the_state};

/// A method's step-size controller, Hairer's: after a step with error norm `e`, the next step
/// is `h / fac` with `fac = e^expo / facold^beta / safe`, clamped to `[fac_min, fac_max]` on
/// acceptance (`facold` the last accepted error, for the PI part) and to at most `fac_max` on
/// rejection.
#[derive(Clone, Copy, Debug)]
pub(super) struct Control {
    pub expo: f64,
    pub beta: f64,
    pub safe: f64,
    /// Smallest `fac`: the largest growth is `1 / fac_min`.
    pub fac_min: f64,
    /// Largest `fac`: the largest shrink.
    pub fac_max: f64,
    /// The factor a step shrinks by when its error is not finite.
    pub non_finite: f64,
    /// The factor a step shrinks by when the method could not form it (a singular iteration
    /// matrix).
    pub unformed: f64,
    /// Whether a step after a rejection may grow beyond the one just taken (Hairer's rule for
    /// the explicit pairs).
    pub hold_after_reject: bool,
}

/// One adaptive method, as the driver sees it.
pub(super) trait Stepper {
    /// The order the initial step is chosen for.
    const ORDER: i32;
    /// The controller's constants.
    const CONTROL: Control;

    /// Attempts the step `h` from `(t, y)`, whose rate is `f0`: writes the new state into
    /// `y_new` and returns the error norm, or `None` when the step cannot be formed at this `h`.
    #[allow(clippy::too_many_arguments)]
    fn attempt(
        &mut self,
        f: &mut Rhs,
        t: f64,
        y: &[f64],
        f0: &[f64],
        h: f64,
        y_new: &mut [f64],
        s: &Settings,
        stats: &mut Stats,
    ) -> Result<Option<f64>, Reason>;

    /// After an accepted step from `t` to `(t_new, y_new)`: the rate there (the method's last
    /// stage, or a new evaluation), written into `f1`, and whatever the method checks on
    /// accepted steps (DOPRI5's stiffness test).
    #[allow(clippy::too_many_arguments)]
    fn accepted(&mut self, f: &mut Rhs, t: f64, t_new: f64, h: f64, y_new: &[f64], f1: &mut [f64], stats: &mut Stats) -> Result<(), Reason>;

    /// Prepares the interpolant over the accepted step `[t, t + h]` from `y` (rate `f0`) to
    /// `y_new` (rate `f1`); called only when an output time falls inside it.
    #[allow(clippy::too_many_arguments)]
    fn prepare_dense(&mut self, f: &mut Rhs, t: f64, y: &[f64], f0: &[f64], y_new: &[f64], f1: &[f64], h: f64, stats: &mut Stats) -> Result<(), Reason>;

    /// The interpolant at `t + theta h`, into `out`.
    fn dense(&self, theta: f64, out: &mut [f64]);
}

/// Integrates with `stepper` from `y0` at `outputs[0]`, writing the state at every output time.
/// With `watch`, each accepted step is searched for events; at a stop or a reset the run ends
/// there, with the outputs before it (the caller goes on from the reset).
pub(super) fn drive<S: Stepper>(
    stepper: &mut S,
    f: &mut Rhs,
    project: &mut Project,
    y0: &[f64],
    outputs: &[f64],
    s: &Settings,
    mut watch: Option<&mut Watch>,
) -> Result<Solution, RunError> {
    let n = y0.len();
    let c = S::CONTROL;
    let mut stats = Stats::default();
    let t_end = *outputs.last().expect("checked");
    let mut t = outputs[0];
    let mut y = y0.to_vec();
    let mut states = States::new(n, outputs.len());
    states.push(&y);
    let mut next = 1;
    let stop = |t: f64, y: &[f64], reason: Reason| RunError { t, state: y.to_vec(), reason };
    let (mut f0, mut f1, mut y_new, mut out) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    f(t, &y, &mut f0, &mut stats).map_err(|r| stop(t, &y, r))?;
    if let Some(w) = watch.as_deref_mut() {
        w.start(t, &y).map_err(|r| stop(t, &y, r))?;
    }
    let mut h = initial_step(f, t, &y, &f0, S::ORDER, s, &mut stats).map_err(|r| stop(t, &y, r))?;
    let mut facold: f64 = 1e-4;
    let mut rejected_last = false;
    // The model's refusals of the first step's trial stages, and the last of them. The first
    // step's size is a guess, and its stages can reach states the motion does not (a floating
    // robot hand's first step, 0.009 s where its light fingers needed 0.002 s, put a finger
    // where the mass matrix is singular): the step is rejected and shrunk, as one whose error
    // is not finite, and the run stops with the refusal when it persists (REFUSALS times, or
    // until the step underflows). Once under way, steps are sized by the error they make, and a
    // refusal stops the run: shrinking there could step across a singular set (a ZYX body's
    // gimbal lock, at loose tolerances) and go on past it.
    let (mut refusals, mut refused) = (0, None);
    while next < outputs.len() {
        h = next_step_size(&stats, s, t, h, t_end, &y, &f0).map_err(|r| stop(t, &y, if refusals > 0 { refused.clone().map_or(r, Reason::Rhs) } else { r }))?;
        let attempted = match stepper.attempt(f, t, &y, &f0, h, &mut y_new, s, &mut stats) {
            Err(Reason::Rhs(failure)) if stats.steps == 0 && of_the_state(&failure) && refusals < REFUSALS => {
                refusals += 1;
                refused = Some(failure);
                stats.rejected += 1;
                rejected_last = true;
                h *= c.non_finite;
                continue;
            }
            other => other.map_err(|r| stop(t, &y, r))?,
        };
        let Some(e) = attempted else {
            stats.rejected += 1;
            rejected_last = true;
            h *= c.unformed;
            continue;
        };
        if !e.is_finite() || !y_new.iter().all(|v| v.is_finite()) {
            stats.rejected += 1;
            rejected_last = true;
            h *= c.non_finite;
            continue;
        }
        let fac11 = e.powf(c.expo);
        if e > 1.0 {
            stats.rejected += 1;
            rejected_last = true;
            h /= (fac11 / c.safe).min(c.fac_max);
            continue;
        }
        let fac = (fac11 / facold.powf(c.beta) / c.safe).clamp(c.fac_min, c.fac_max);
        let h_new = h / fac;
        facold = e.max(1e-4);
        stats.steps += 1;
        refusals = 0;
        let t_new = if h == t_end - t { t_end } else { t + h };
        stepper.accepted(f, t, t_new, h, &y_new, &mut f1, &mut stats).map_err(|r| stop(t, &y, r))?;
        let mut prepared = false;
        if let Some(w) = watch.as_deref_mut() {
            // The event functions over the step: one changing sign more than once gets
            // shorter steps, a crossing each.
            w.ended(t_new, &y_new, &mut stats).map_err(|r| stop(t, &y, r))?;
            stepper.prepare_dense(f, t, &y, &f0, &y_new, &f1, h, &mut stats).map_err(|r| stop(t, &y, r))?;
            prepared = true;
            if let Some(shorter) = w.scan(t, h, n, &mut |theta, out| stepper.dense(theta, out), &mut stats).map_err(|r| stop(t, &y, r))? {
                stats.rejected += 1;
                stats.steps -= 1;
                rejected_last = true;
                h *= shorter;
                continue;
            }
            if w.crossed() {
                let hit = w.locate(t, h, n, &mut |theta, out| stepper.dense(theta, out), &mut stats).map_err(|r| stop(t, &y, r))?;
                if let Some(at) = hit {
                    // The run ends at the event: the outputs before it are the interpolant's.
                    while next < outputs.len() && outputs[next] < at {
                        stepper.dense((outputs[next] - t) / h, &mut out);
                        states.push(&out);
                        next += 1;
                    }
                    return Ok(Solution { times: outputs[..next].to_vec(), states, stats, events: Vec::new(), stopped: false });
                }
            }
            w.advance();
        }
        if outputs[next] <= t_new {
            if !prepared {
                stepper.prepare_dense(f, t, &y, &f0, &y_new, &f1, h, &mut stats).map_err(|r| stop(t, &y, r))?;
            }
            while next < outputs.len() && outputs[next] <= t_new {
                stepper.dense((outputs[next] - t) / h, &mut out);
                states.push(&out);
                next += 1;
            }
        }
        t = t_new;
        std::mem::swap(&mut y, &mut y_new);
        finish_step(f, project, t, &mut y, &f1, &mut f0, &mut states, outputs[next - 1], &mut stats).map_err(|r| stop(t, &y, r))?;
        h = if c.hold_after_reject { grown_step(h_new, h, s, rejected_last) } else { h_new.min(s.h_max) };
        rejected_last = false;
    }
    Ok(Solution { times: outputs.to_vec(), states, stats, events: Vec::new(), stopped: false })
}
