//! Dormand-Prince 5(4) (Hairer's DOPRI5): PI step-size control, and Shampine's dense output
//! for the output times between steps, as MATLAB's `ode45` does with a vector of times.

use super::{
    Project, Reason, Rhs, RunError, Settings, Solution, States, Stats, axpy_stages, combine, error_norm, finish_step, grown_step, initial_step, next_step_size,
};

const C: [f64; 7] = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0],
    [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0],
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0],
];
/// Fifth minus fourth order weights.
const E: [f64; 7] = [71.0 / 57600.0, 0.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0];
/// Shampine's dense output.
const D: [f64; 7] = [
    -12715105075.0 / 11282082432.0,
    0.0,
    87487479700.0 / 32700410799.0,
    -10690763975.0 / 1880347072.0,
    701980252875.0 / 199316789632.0,
    -1453857185.0 / 822651844.0,
    69997945.0 / 29380423.0,
];

pub(super) fn run(f: &mut Rhs, project: &mut Project, y0: &[f64], outputs: &[f64], s: &Settings) -> Result<Solution, RunError> {
    let n = y0.len();
    let mut stats = Stats::default();
    let t_end = *outputs.last().expect("checked");
    let mut t = outputs[0];
    let mut y = y0.to_vec();
    let mut states = States::new(n, outputs.len());
    states.push(&y);
    let mut next = 1;
    let stop = |t: f64, y: &[f64], reason: Reason| RunError { t, state: y.to_vec(), reason };
    let mut k: Vec<Vec<f64>> = vec![vec![0.0; n]; 7];
    f(t, &y, &mut k[0], &mut stats).map_err(|r| stop(t, &y, r))?;
    let mut h = initial_step(f, t, &y, &k[0].clone(), 5, s, &mut stats).map_err(|r| stop(t, &y, r))?;
    let (beta, safe, facc1, facc2) = (0.04, 0.9, 5.0, 0.1);
    let expo1 = 0.2 - beta * 0.75;
    let mut facold: f64 = 1e-4;
    let mut rejected_last = false;
    let (mut tmp, mut y_new, mut err) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut rcont = vec![vec![0.0; n]; 5];
    // Hairer's stiffness test: the dominant eigenvalue times h from the last two stages.
    let (mut stiff_steps, mut non_stiff_steps) = (0usize, 0usize);
    while next < outputs.len() {
        h = next_step_size(&stats, s, t, h, t_end, &y, &k[0]).map_err(|r| stop(t, &y, r))?;
        for st in 1..6 {
            combine(&mut tmp, &y, h, &A[st][..st], &k);
            let (_, tail) = k.split_at_mut(st);
            f(t + C[st] * h, &tmp, &mut tail[0], &mut stats).map_err(|r| stop(t, &y, r))?;
        }
        combine(&mut y_new, &y, h, &A[6], &k);
        f(t + h, &y_new, &mut k[6], &mut stats).map_err(|r| stop(t, &y, r))?;
        err.fill(0.0);
        axpy_stages(&mut err, h, &E, &k);
        let e = error_norm(&err, &y, &y_new, s.rtol, s.atol);
        if !e.is_finite() {
            stats.rejected += 1;
            rejected_last = true;
            h *= 0.2;
            continue;
        }
        let fac11 = e.powf(expo1);
        if e <= 1.0 {
            let fac = (fac11 / facold.powf(beta) / safe).clamp(facc2, facc1);
            let h_new = h / fac;
            facold = e.max(1e-4);
            stats.steps += 1;
            // Stages 6 and 7 are evaluated at t + h, at `tmp` (stage 6's argument, still in
            // `tmp`) and at `y_new`: their difference estimates h lambda.
            if stats.stiff_at.is_none() {
                let (num, den) = (0..n).fold((0.0, 0.0), |(a, b), i| (a + (k[6][i] - k[5][i]).powi(2), b + (y_new[i] - tmp[i]).powi(2)));
                if den > 0.0 && h * (num / den).sqrt() > 3.25 {
                    non_stiff_steps = 0;
                    stiff_steps += 1;
                    if stiff_steps == 15 {
                        stats.stiff_at = Some(t);
                    }
                } else {
                    non_stiff_steps += 1;
                    if non_stiff_steps == 6 {
                        stiff_steps = 0;
                    }
                }
            }
            // Dense output over [t, t + h].
            for i in 0..n {
                let ydiff = y_new[i] - y[i];
                let bspl = h * k[0][i] - ydiff;
                rcont[0][i] = y[i];
                rcont[1][i] = ydiff;
                rcont[2][i] = bspl;
                rcont[3][i] = ydiff - h * k[6][i] - bspl;
            }
            rcont[4].fill(0.0);
            axpy_stages(&mut rcont[4], h, &D, &k);
            let t_new = if h == t_end - t { t_end } else { t + h };
            while next < outputs.len() && outputs[next] <= t_new {
                let theta = (outputs[next] - t) / h;
                let theta1 = 1.0 - theta;
                for i in 0..n {
                    tmp[i] = rcont[0][i] + theta * (rcont[1][i] + theta1 * (rcont[2][i] + theta * (rcont[3][i] + theta1 * rcont[4][i])));
                }
                states.push(&tmp);
                next += 1;
            }
            t = t_new;
            std::mem::swap(&mut y, &mut y_new);
            let (first, rest) = k.split_at_mut(1);
            finish_step(f, project, t, &mut y, &rest[5], &mut first[0], &mut states, outputs[next - 1], &mut stats).map_err(|r| stop(t, &y, r))?;
            h = grown_step(h_new, h, s, rejected_last);
            rejected_last = false;
        } else {
            stats.rejected += 1;
            rejected_last = true;
            h /= (fac11 / safe).min(facc1);
        }
    }
    Ok(Solution { times: outputs.to_vec(), states, stats })
}
