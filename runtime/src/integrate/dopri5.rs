//! Dormand-Prince 5(4) (Hairer's DOPRI5): PI step-size control, and Shampine's dense output
//! for the output times between steps, as MATLAB's `ode45` does with a vector of times.

use super::driver::{Control, Stepper};
use super::{Reason, Rhs, Settings, Stats, StiffnessTest, axpy_stages, combine, error_norm};

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

/// DOPRI5's stages, its dense-output coefficients and Hairer's stiffness counters.
pub(super) struct Dopri5 {
    k: Vec<Vec<f64>>,
    tmp: Vec<f64>,
    rcont: Vec<Vec<f64>>,
    stiffness: StiffnessTest,
}

impl Dopri5 {
    pub(super) fn new(n: usize) -> Dopri5 {
        Dopri5 { k: vec![vec![0.0; n]; 7], tmp: vec![0.0; n], rcont: vec![vec![0.0; n]; 5], stiffness: StiffnessTest::new(3.25) }
    }
}

impl Stepper for Dopri5 {
    const ORDER: i32 = 5;
    // Hairer's DOPRI5 defaults: PI control with beta 0.04.
    const CONTROL: Control =
        Control { expo: 0.2 - 0.04 * 0.75, beta: 0.04, safe: 0.9, fac_min: 0.1, fac_max: 5.0, non_finite: 0.2, unformed: 0.2, hold_after_reject: true };

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
        let k = &mut self.k;
        k[0].copy_from_slice(f0);
        for st in 1..6 {
            combine(&mut self.tmp, y, h, &A[st][..st], k);
            let (_, tail) = k.split_at_mut(st);
            f(t + C[st] * h, &self.tmp, &mut tail[0], stats)?;
        }
        combine(y_new, y, h, &A[6], k);
        f(t + h, y_new, &mut k[6], stats)?;
        // The error estimate, in the dense coefficients' first row (free until acceptance).
        let err = &mut self.rcont[0];
        err.fill(0.0);
        axpy_stages(err, h, &E, k);
        Ok(Some(error_norm(err, y, y_new, s.rtol, s.atol)))
    }

    fn accepted(&mut self, _f: &mut Rhs, t: f64, _t_new: f64, h: f64, y_new: &[f64], f1: &mut [f64], stats: &mut Stats) -> Result<(), Reason> {
        let k = &self.k;
        // Hairer's stiffness test: stages 6 and 7 are evaluated at t + h, at `tmp` (stage 6's
        // argument) and at `y_new`: their difference estimates h lambda.
        self.stiffness.observe(t, h, (&k[6], y_new), (&k[5], &self.tmp), stats);
        f1.copy_from_slice(&k[6]);
        Ok(())
    }

    fn prepare_dense(&mut self, _f: &mut Rhs, _t: f64, y: &[f64], _f0: &[f64], y_new: &[f64], _f1: &[f64], h: f64, _stats: &mut Stats) -> Result<(), Reason> {
        let (k, rcont) = (&self.k, &mut self.rcont);
        for i in 0..y.len() {
            let ydiff = y_new[i] - y[i];
            let bspl = h * k[0][i] - ydiff;
            rcont[0][i] = y[i];
            rcont[1][i] = ydiff;
            rcont[2][i] = bspl;
            rcont[3][i] = ydiff - h * k[6][i] - bspl;
        }
        rcont[4].fill(0.0);
        axpy_stages(&mut rcont[4], h, &D, k);
        Ok(())
    }

    fn dense(&self, theta: f64, out: &mut [f64]) {
        let (r, theta1) = (&self.rcont, 1.0 - theta);
        for (i, o) in out.iter_mut().enumerate() {
            *o = r[0][i] + theta * (r[1][i] + theta1 * (r[2][i] + theta * (r[3][i] + theta1 * r[4][i])));
        }
    }
}
