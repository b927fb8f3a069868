//! The Rosenbrock method of Shampine and Reichelt's `ode23s` (SIAM J. Sci. Comput. 18 (1997)
//! 1-22): order 2 with an order-3 error estimate, L-stable, one Jacobian and one LU
//! factorization of `W = I - h d J` per step, three right-hand sides (the last one is the next
//! step's first), and its own second-order dense output.
//!
//! For stiff systems (a stiff spring, a large mass ratio): its step is set by the accuracy
//! asked for, not by the fastest eigenvalue, where an explicit method's stability limit
//! forces steps of order `1/|lambda_max|`. The Jacobian is the model's exact one when given,
//! otherwise forward differences of the right-hand side (`n` extra calls per step).

use super::driver::{Control, Stepper};
use super::{Jacobian, Reason, Rhs, Settings, Stats, error_norm};
use nalgebra::{DMatrix, DVector};

/// `d = 1 / (2 + sqrt 2)`.
const D: f64 = 0.292_893_218_813_452_5;
/// `e32 = 6 + sqrt 2`.
const E32: f64 = 7.414_213_562_373_095;

/// The stiff method's Jacobian, iteration matrix, stages and dense-output data, reused from
/// step to step (no allocation per step).
pub(super) struct Rosenbrock<'a, 'j> {
    jac: &'a mut Jacobian<'j>,
    j: DMatrix<f64>,
    dfdt: Vec<f64>,
    /// True while the Jacobian is the one at the current step's start (a rejected step keeps it).
    fresh: bool,
    w: DMatrix<f64>,
    pivots: Vec<usize>,
    k1: DVector<f64>,
    k2: DVector<f64>,
    k3: DVector<f64>,
    f1: Vec<f64>,
    f2: Vec<f64>,
    tmp: Vec<f64>,
    err: Vec<f64>,
    /// The accepted step's start and size, for the interpolant.
    y0: Vec<f64>,
    h: f64,
}

impl<'a, 'j> Rosenbrock<'a, 'j> {
    pub(super) fn new(n: usize, jac: &'a mut Jacobian<'j>) -> Rosenbrock<'a, 'j> {
        Rosenbrock {
            jac,
            j: DMatrix::zeros(n, n),
            dfdt: vec![0.0; n],
            fresh: false,
            w: DMatrix::zeros(n, n),
            pivots: vec![0; n],
            k1: DVector::zeros(n),
            k2: DVector::zeros(n),
            k3: DVector::zeros(n),
            f1: vec![0.0; n],
            f2: vec![0.0; n],
            tmp: vec![0.0; n],
            err: vec![0.0; n],
            y0: vec![0.0; n],
            h: 0.0,
        }
    }
}

impl Stepper for Rosenbrock<'_, '_> {
    const ORDER: i32 = 3;
    // ode23s's controller: 0.8 e^(-1/3), growth at most 5, shrink at most 10.
    const CONTROL: Control =
        Control { expo: 1.0 / 3.0, beta: 0.0, safe: 0.8, fac_min: 0.2, fac_max: 10.0, non_finite: 0.1, unformed: 0.5, hold_after_reject: false };

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
    ) -> Result<Option<f64>, Reason> {
        let n = y.len();
        if !self.fresh {
            if !(self.jac)(t, y, &mut self.j)? {
                // Forward differences, one right-hand side per column.
                self.tmp.copy_from_slice(y);
                for k in 0..n {
                    let d = f64::EPSILON.sqrt() * y[k].abs().max(1.0);
                    self.tmp[k] = y[k] + d;
                    f(t, &self.tmp, &mut self.f1, stats)?;
                    for i in 0..n {
                        self.j[(i, k)] = (self.f1[i] - f0[i]) / d;
                    }
                    self.tmp[k] = y[k];
                }
            }
            // df/dt by a forward difference, unless the model does not read t (then it is 0).
            if !s.time_independent {
                let dt = f64::EPSILON.sqrt() * t.abs().max(1.0);
                f(t + dt, y, &mut self.tmp, stats)?;
                for i in 0..n {
                    self.dfdt[i] = (self.tmp[i] - f0[i]) / dt;
                }
            }
            stats.jacobians += 1;
            self.fresh = true;
        }
        stats.factorizations += 1;
        if !factor(&mut self.w, &self.j, h * D, &mut self.pivots) {
            return Ok(None);
        }
        let (k1, k2, k3) = (&mut self.k1, &mut self.k2, &mut self.k3);
        for i in 0..n {
            k1[i] = f0[i] + h * D * self.dfdt[i];
        }
        solve(&self.w, &self.pivots, k1);
        for i in 0..n {
            self.tmp[i] = y[i] + 0.5 * h * k1[i];
        }
        f(t + 0.5 * h, &self.tmp, &mut self.f1, stats)?;
        for i in 0..n {
            k2[i] = self.f1[i] - k1[i];
        }
        solve(&self.w, &self.pivots, k2);
        *k2 += &*k1;
        for i in 0..n {
            y_new[i] = y[i] + h * k2[i];
        }
        f(t + h, y_new, &mut self.f2, stats)?;
        for i in 0..n {
            k3[i] = self.f2[i] - E32 * (k2[i] - self.f1[i]) - 2.0 * (k1[i] - f0[i]) + h * D * self.dfdt[i];
        }
        solve(&self.w, &self.pivots, k3);
        for i in 0..n {
            self.err[i] = h / 6.0 * (k1[i] - 2.0 * k2[i] + k3[i]);
        }
        Ok(Some(error_norm(&self.err, y, y_new, s.rtol, s.atol)))
    }

    fn accepted(&mut self, _f: &mut Rhs, _t: f64, _t_new: f64, _h: f64, _y_new: &[f64], f1: &mut [f64], _stats: &mut Stats) -> Result<(), Reason> {
        // The last stage is the next step's first; the next step needs a new Jacobian.
        f1.copy_from_slice(&self.f2);
        self.fresh = false;
        Ok(())
    }

    fn prepare_dense(&mut self, _f: &mut Rhs, _t: f64, y: &[f64], _f0: &[f64], _y_new: &[f64], _f1: &[f64], h: f64, _stats: &mut Stats) -> Result<(), Reason> {
        self.y0.copy_from_slice(y);
        self.h = h;
        Ok(())
    }

    /// ode23s's interpolant: `y + h (s (1 - s) k1 + s (s - 2d) k2) / (1 - 2d)`.
    fn dense(&self, theta: f64, out: &mut [f64]) {
        let (a, b) = (theta * (1.0 - theta) / (1.0 - 2.0 * D), theta * (theta - 2.0 * D) / (1.0 - 2.0 * D));
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.y0[i] + self.h * (a * self.k1[i] + b * self.k2[i]);
        }
    }
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
