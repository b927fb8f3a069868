//! Classical fourth-order Runge-Kutta with a fixed step, shortened to land on output times.

use super::{Project, Reason, Rhs, RunError, Solution, States, Stats, finite};

pub(super) fn run(f: &mut Rhs, project: &mut Project, y0: &[f64], outputs: &[f64], h: f64, max_steps: usize) -> Result<Solution, RunError> {
    let n = y0.len();
    let mut stats = Stats::default();
    let mut t = outputs[0];
    let mut y = y0.to_vec();
    let mut states = States::new(n, outputs.len());
    states.push(&y);
    let (mut k1, mut k2, mut k3, mut k4, mut tmp) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let stop = |t: f64, y: &[f64], reason: Reason| RunError { t, state: y.to_vec(), reason };
    if !(h > 0.0) {
        return Err(stop(t, &y, Reason::StepSizeTooSmall { h }));
    }
    for &target in &outputs[1..] {
        while t < target {
            if stats.steps >= max_steps {
                return Err(stop(t, &y, Reason::TooManySteps(max_steps)));
            }
            // Land exactly on the output time (within rounding of the step count).
            let step = if target - t < h * (1.0 + 1e-9) { target - t } else { h };
            f(t, &y, &mut k1, &mut stats).map_err(|r| stop(t, &y, r))?;
            for i in 0..n {
                tmp[i] = y[i] + 0.5 * step * k1[i];
            }
            f(t + 0.5 * step, &tmp, &mut k2, &mut stats).map_err(|r| stop(t, &y, r))?;
            for i in 0..n {
                tmp[i] = y[i] + 0.5 * step * k2[i];
            }
            f(t + 0.5 * step, &tmp, &mut k3, &mut stats).map_err(|r| stop(t, &y, r))?;
            for i in 0..n {
                tmp[i] = y[i] + step * k3[i];
            }
            f(t + step, &tmp, &mut k4, &mut stats).map_err(|r| stop(t, &y, r))?;
            for i in 0..n {
                y[i] += step / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
            t = if step == target - t { target } else { t + step };
            stats.steps += 1;
            if !finite(&y) {
                return Err(stop(t, &y, Reason::Diverged));
            }
            project(t, &mut y).map_err(|r| stop(t, &y, r))?;
        }
        states.push(&y);
    }
    Ok(Solution { times: outputs.to_vec(), states, stats, events: Vec::new(), stopped: false })
}
