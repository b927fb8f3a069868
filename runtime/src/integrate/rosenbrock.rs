//! The Rosenbrock method of Shampine and Reichelt's `ode23s` (SIAM J. Sci. Comput. 18 (1997)
//! 1-22): order 2 with an order-3 error estimate, L-stable, one Jacobian and one LU
//! factorization of `W = I - h d J` per step, three right-hand sides (the last one is the next
//! step's first), and its own second-order dense output.
//!
//! For stiff systems (a stiff spring, a large mass ratio): its step is set by the accuracy
//! asked for, not by the fastest eigenvalue, where an explicit method's stability limit
//! forces steps of order `1/|lambda_max|`. The Jacobian is the model's exact one when given,
//! otherwise forward differences of the right-hand side (`n` extra calls per step).

use super::{Jacobian, Project, Reason, Rhs, RunError, Settings, Solution, States, Stats, error_norm, finish_step, initial_step, next_step_size};
use nalgebra::{DMatrix, DVector};

/// `d = 1 / (2 + sqrt 2)`.
const D: f64 = 0.292_893_218_813_452_5;
/// `e32 = 6 + sqrt 2`.
const E32: f64 = 7.414_213_562_373_095;

pub(super) fn run(f: &mut Rhs, jac: &mut Jacobian, project: &mut Project, y0: &[f64], outputs: &[f64], s: &Settings) -> Result<Solution, RunError> {
    let n = y0.len();
    let mut stats = Stats::default();
    let t_end = *outputs.last().expect("checked");
    let mut t = outputs[0];
    let mut y = y0.to_vec();
    let mut states = States::new(n, outputs.len());
    states.push(&y);
    let mut next = 1;
    let stop = |t: f64, y: &[f64], reason: Reason| RunError { t, state: y.to_vec(), reason };
    let mut f0 = vec![0.0; n];
    f(t, &y, &mut f0, &mut stats).map_err(|r| stop(t, &y, r))?;
    let mut h = initial_step(f, t, &y, &f0, 3, s, &mut stats).map_err(|r| stop(t, &y, r))?;
    let (mut f1, mut f2, mut tmp, mut y_new, mut err) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut j = DMatrix::<f64>::zeros(n, n);
    let mut dfdt = vec![0.0; n];
    // The stages, reused from step to step.
    let (mut k1, mut k2, mut k3) = (DVector::<f64>::zeros(n), DVector::<f64>::zeros(n), DVector::<f64>::zeros(n));
    let mut fresh_jacobian = false;
    // The iteration matrix and its pivots, factored in place every step (no allocation).
    let (mut w, mut pivots) = (DMatrix::<f64>::zeros(n, n), vec![0usize; n]);
    while next < outputs.len() {
        h = next_step_size(&stats, s, t, h, t_end, &y, &f0).map_err(|r| stop(t, &y, r))?;
        if !fresh_jacobian {
            if !jac(t, &y, &mut j).map_err(|r| stop(t, &y, r))? {
                // Forward differences, one right-hand side per column.
                tmp.copy_from_slice(&y);
                for k in 0..n {
                    let d = f64::EPSILON.sqrt() * y[k].abs().max(1.0);
                    tmp[k] = y[k] + d;
                    f(t, &tmp, &mut f1, &mut stats).map_err(|r| stop(t, &y, r))?;
                    for i in 0..n {
                        j[(i, k)] = (f1[i] - f0[i]) / d;
                    }
                    tmp[k] = y[k];
                }
            }
            // df/dt by a forward difference, unless the model does not read t (then it is 0).
            if !s.time_independent {
                let dt = f64::EPSILON.sqrt() * t.abs().max(1.0);
                f(t + dt, &y, &mut tmp, &mut stats).map_err(|r| stop(t, &y, r))?;
                for i in 0..n {
                    dfdt[i] = (tmp[i] - f0[i]) / dt;
                }
            }
            stats.jacobians += 1;
            fresh_jacobian = true;
        }
        stats.factorizations += 1;
        if !factor(&mut w, &j, h * D, &mut pivots) {
            stats.rejected += 1;
            h *= 0.5;
            continue;
        }
        for i in 0..n {
            k1[i] = f0[i] + h * D * dfdt[i];
        }
        solve(&w, &pivots, &mut k1);
        for i in 0..n {
            tmp[i] = y[i] + 0.5 * h * k1[i];
        }
        f(t + 0.5 * h, &tmp, &mut f1, &mut stats).map_err(|r| stop(t, &y, r))?;
        for i in 0..n {
            k2[i] = f1[i] - k1[i];
        }
        solve(&w, &pivots, &mut k2);
        k2 += &k1;
        for i in 0..n {
            y_new[i] = y[i] + h * k2[i];
        }
        f(t + h, &y_new, &mut f2, &mut stats).map_err(|r| stop(t, &y, r))?;
        for i in 0..n {
            k3[i] = f2[i] - E32 * (k2[i] - f1[i]) - 2.0 * (k1[i] - f0[i]) + h * D * dfdt[i];
        }
        solve(&w, &pivots, &mut k3);
        for i in 0..n {
            err[i] = h / 6.0 * (k1[i] - 2.0 * k2[i] + k3[i]);
        }
        let e = error_norm(&err, &y, &y_new, s.rtol, s.atol);
        if !e.is_finite() || !y_new.iter().all(|v| v.is_finite()) {
            stats.rejected += 1;
            h *= 0.1;
            continue;
        }
        if e <= 1.0 {
            stats.steps += 1;
            let t_new = if h == t_end - t { t_end } else { t + h };
            // ode23s's interpolant: y + h (s (1 - s) k1 + s (s - 2d) k2) / (1 - 2d).
            while next < outputs.len() && outputs[next] <= t_new {
                let th = (outputs[next] - t) / h;
                let (a, b) = (th * (1.0 - th) / (1.0 - 2.0 * D), th * (th - 2.0 * D) / (1.0 - 2.0 * D));
                for i in 0..n {
                    tmp[i] = y[i] + h * (a * k1[i] + b * k2[i]);
                }
                states.push(&tmp);
                next += 1;
            }
            t = t_new;
            std::mem::swap(&mut y, &mut y_new);
            finish_step(f, project, t, &mut y, &f2, &mut f0, &mut states, outputs[next - 1], &mut stats).map_err(|r| stop(t, &y, r))?;
            fresh_jacobian = false;
            let grow = if e == 0.0 { 5.0 } else { (0.8 * e.powf(-1.0 / 3.0)).min(5.0) };
            h = (h * grow).min(s.h_max);
        } else {
            stats.rejected += 1;
            h *= (0.8 * e.powf(-1.0 / 3.0)).max(0.1);
        }
    }
    Ok(Solution { times: outputs.to_vec(), states, stats })
}

/// Factors `W = I - hd J` into `w` in place (`P W = L U` by partial pivoting, `L` unit lower
/// below the diagonal, the row taken at each step in `pivots`); false when a pivot vanishes.
fn factor(w: &mut DMatrix<f64>, j: &DMatrix<f64>, hd: f64, pivots: &mut [usize]) -> bool {
    let n = j.nrows();
    for c in 0..n {
        for r in 0..n {
            w[(r, c)] = -hd * j[(r, c)];
        }
        w[(c, c)] += 1.0;
    }
    for c in 0..n {
        let mut p = c;
        for r in c + 1..n {
            if w[(r, c)].abs() > w[(p, c)].abs() {
                p = r;
            }
        }
        if !(w[(p, c)].abs() > 0.0 && w[(p, c)].is_finite()) {
            return false;
        }
        pivots[c] = p;
        w.swap_rows(c, p);
        let d = w[(c, c)];
        for r in c + 1..n {
            let f = w[(r, c)] / d;
            w[(r, c)] = f;
            for k in c + 1..n {
                w[(r, k)] -= f * w[(c, k)];
            }
        }
    }
    true
}

/// Solves `W x = b` in place from [`factor`]'s `w` and `pivots`.
fn solve(w: &DMatrix<f64>, pivots: &[usize], b: &mut DVector<f64>) {
    let n = w.nrows();
    for (c, &p) in pivots.iter().enumerate() {
        b.swap_rows(c, p);
    }
    for r in 0..n {
        for k in 0..r {
            b[r] -= w[(r, k)] * b[k];
        }
    }
    for r in (0..n).rev() {
        for k in r + 1..n {
            b[r] -= w[(r, k)] * b[k];
        }
        b[r] /= w[(r, r)];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The in-place factorization solves what nalgebra's LU solves, pivoting included.
    #[test]
    fn the_in_place_lu_solves_the_iteration_matrix() {
        let j = DMatrix::from_row_slice(3, 3, &[0.0, 2.0, -1.0, 4.0, 0.5, 3.0, -2.0, 1.0, 7.0]);
        let b = DVector::from_vec(vec![1.0, -2.0, 0.5]);
        let (mut w, mut pivots) = (DMatrix::zeros(3, 3), vec![0; 3]);
        assert!(factor(&mut w, &j, 0.7, &mut pivots));
        let mut x = b.clone();
        solve(&w, &pivots, &mut x);
        let reference = (DMatrix::<f64>::identity(3, 3) - &j * 0.7).lu().solve(&b).unwrap();
        assert!((&x - &reference).amax() < 1e-14, "{x} against {reference}");
        // I - hd J singular: refused.
        let singular = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 1.0]);
        assert!(!factor(&mut DMatrix::zeros(2, 2), &singular, 1.0, &mut [0; 2]));
    }
}
