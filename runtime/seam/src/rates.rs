//! The state's rates from a right-hand side's solution, written once: every emitted module's
//! `rhs` and `jacobian` and the in-process evaluator call these, so that the rates are summed in
//! one order everywhere. What stays per model is the assembly (the matrix, the forcing and the
//! parts below, evaluated by the model's own code) and the solve.
//!
//! A state is `[kept coordinates; speeds; work]`: the kept coordinates' rates are the
//! assembly's `qdot`; the speeds' rates are the solution `x`'s first entries, or `W x + c` where
//! the formulation maps the solution to the speeds (the Volterra forms); the work integral's rate
//! is the power, plus its weights on `x` with moving constraints.
//!
//! ```
//! use seam::rates::{Block, Layout, write};
//! // Two kept coordinates, two speeds read from a solution of three (one multiplier), the power.
//! let layout = Layout { speeds: 2, post: None, work: true };
//! let block = Block { qdot: &[0.1, 0.2], power: 4.0, ..Block::EMPTY };
//! let mut dstate = [0.0; 5];
//! write(0.0, layout, &block, &[1.0, 2.0, 9.0], &mut dstate).unwrap();
//! assert_eq!(dstate, [0.1, 0.2, 1.0, 2.0, 4.0]);
//! ```

use crate::Failure;
use crate::check;
use crate::solve::{Square, lu_solve};

/// How a formulation's solution becomes the state's rates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// The number of speeds in the state.
    pub speeds: usize,
    /// `Some((rows, columns))` of `W` where the speeds' rates are `W x + c`; `None` where they
    /// are the solution's first `speeds` entries.
    pub post: Option<(usize, usize)>,
    /// Whether the state ends with the work integral.
    pub work: bool,
}

/// One block of an assembly as slices: its values, or their derivatives by one variable. Parts
/// a formulation does not have are empty (a power of zero).
#[derive(Clone, Copy, Debug)]
pub struct Block<'a> {
    /// The kept coordinates' rates.
    pub qdot: &'a [f64],
    /// The solved matrix, row-major (read in derivative blocks only).
    pub matrix: &'a [f64],
    /// The forcing (read in derivative blocks only: the values' forcing is solved into `x`).
    pub force: &'a [f64],
    /// `W`, row-major `Layout::post`.
    pub w: &'a [f64],
    /// `c`.
    pub c: &'a [f64],
    /// The power `W'` (without moving constraints' share).
    pub power: f64,
    /// The power's weights on the solution (moving constraints), or empty.
    pub power_weights: &'a [f64],
}

impl Block<'static> {
    /// A block with every part empty, for struct update syntax.
    pub const EMPTY: Block<'static> = Block { qdot: &[], matrix: &[], force: &[], w: &[], c: &[], power: 0.0, power_weights: &[] };
}

/// Writes `rhs`'s `dstate` from the assembly `a` and the solution `x`, then checks it finite.
///
/// The speeds' rates under `W x + c` are summed `W[j][0] x[0] + ... + W[j][k] x[k] + c[j]`, left
/// to right; the power as `power + weights[0] x[0] + ...`.
// Always inlined: in a module's `rhs` every length is a constant, and the copies and sums
// unroll as the module's own statements did (inlined by choice, a tiny model's call took up to
// half as long again).
#[inline(always)]
#[allow(clippy::manual_memcpy)]
pub fn write(t: f64, layout: Layout, a: &Block, x: &[f64], dstate: &mut [f64]) -> Result<(), Failure> {
    let nq = a.qdot.len();
    // Entry by entry, not `copy_from_slice`: a block copy reads the solution's entries back
    // from memory as one vector just after the solve stored them one by one, a stall that
    // took a tiny model's call from 16 to 24 ns (Kane's, the Cartesian pendulum); entries the
    // compiler keeps in registers.
    for j in 0..nq {
        dstate[j] = a.qdot[j];
    }
    match layout.post {
        None => {
            for j in 0..layout.speeds {
                dstate[nq + j] = x[j];
            }
        }
        Some((rows, columns)) => {
            for j in 0..rows {
                dstate[nq + j] = match columns {
                    0 => a.c[j],
                    _ => (1..columns).fold(a.w[j * columns] * x[0], |sum, k| sum + a.w[j * columns + k] * x[k]) + a.c[j],
                };
            }
        }
    }
    if layout.work {
        let last = dstate.len() - 1;
        dstate[last] = a.power_weights.iter().zip(x).fold(a.power, |sum, (w, x)| sum + w * x);
    }
    check::finite(t, dstate)
}

/// Writes `jacobian`'s `dstate` and `jac` (row-major, `dstate.len()` rows of `columns`, zero
/// where nothing depends on a column) from the assembly's values `a`, their solution `x`, the
/// matrix's LU factors (`factors`, `pivots`) and each variable's derivative block
/// (`derivative(k)` for `k < variables`): `dx/ds_k = A^-1 (dF/ds_k - dA/ds_k x)`. `dx` is
/// scratch of the matrix's size. Checks both finite.
///
/// Here `W x + c` is summed from `c[j]` on, the order the Jacobian always had (the values can
/// differ from [`write`]'s in the last bit).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn write_jacobian<'a, M: Square>(
    t: f64,
    layout: Layout,
    a: &Block,
    x: &[f64],
    (factors, pivots): (&M, &[usize]),
    (variables, derivative): (usize, impl Fn(usize) -> Block<'a>),
    dx: &mut [f64],
    dstate: &mut [f64],
    (jac, columns): (&mut [f64], usize),
) -> Result<(), Failure> {
    let nq = a.qdot.len();
    let n = x.len();
    let last = dstate.len() - 1;
    jac.fill(0.0);
    dstate[..nq].copy_from_slice(a.qdot);
    match layout.post {
        None => dstate[nq..nq + layout.speeds].copy_from_slice(&x[..layout.speeds]),
        Some((rows, cols)) => {
            for j in 0..rows {
                let mut sum = a.c[j];
                for i in 0..cols {
                    sum += a.w[j * cols + i] * x[i];
                }
                dstate[nq + j] = sum;
            }
        }
    }
    if layout.work {
        dstate[last] = a.power_weights.iter().zip(x).fold(a.power, |sum, (w, x)| sum + w * x);
    }
    for k in 0..variables {
        let d = derivative(k);
        for j in 0..nq {
            jac[j * columns + k] = d.qdot[j];
        }
        for i in 0..n {
            let mut sum = d.force[i];
            for j in 0..n {
                sum -= d.matrix[i * n + j] * x[j];
            }
            dx[i] = sum;
        }
        lu_solve(factors, pivots, dx);
        match layout.post {
            None => {
                for j in 0..layout.speeds {
                    jac[(nq + j) * columns + k] = dx[j];
                }
            }
            Some((rows, cols)) => {
                for j in 0..rows {
                    let mut sum = d.c[j];
                    for i in 0..cols {
                        sum += d.w[j * cols + i] * x[i] + a.w[j * cols + i] * dx[i];
                    }
                    jac[(nq + j) * columns + k] = sum;
                }
            }
        }
        if layout.work {
            // `d power + d weights . x + weights . dx`, left to right.
            let mut sum = d.power;
            for i in 0..a.power_weights.len() {
                sum += d.power_weights[i] * x[i] + a.power_weights[i] * dx[i];
            }
            jac[last * columns + k] = sum;
        }
    }
    check::finite(t, dstate)?;
    check::finite_after(t, dstate.len(), jac)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::{Rows, lu_factor};

    /// `W x + c` and the power with its weights, in the documented order, and a NaN refused.
    #[test]
    fn the_rates_from_a_solution() {
        let layout = Layout { speeds: 2, post: Some((2, 3)), work: true };
        let w = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let a = Block { qdot: &[7.0], w: &w, c: &[0.5, -0.5], power: 1.0, power_weights: &[1.0, 0.0, 2.0], ..Block::EMPTY };
        let x = [1.0, 1.0, 2.0];
        let mut dstate = [0.0; 4];
        write(0.0, layout, &a, &x, &mut dstate).unwrap();
        assert_eq!(dstate, [7.0, 9.5, 20.5, 6.0]);
        let nan = [f64::NAN, 1.0, 2.0];
        assert!(matches!(write(2.0, layout, &a, &nan, &mut dstate), Err(Failure::NonFinite { index: 1, .. })));
    }

    /// The Jacobian of `x = A(s)^-1 F(s)` at one variable against a central difference.
    #[test]
    fn the_jacobian_of_a_solve_is_its_difference_quotient() {
        // A(s) = [[2 + s, 1], [1, 3]], F(s) = [1, s^2], at s = 0.5; state [x0, x1].
        let at = |s: f64| ([2.0 + s, 1.0, 1.0, 3.0], [1.0, s * s]);
        let solve = |s: f64| {
            let (mut m, mut f) = at(s);
            let mut pivots = [0; 2];
            lu_factor(&mut Rows::new(2, &mut m), &mut pivots).unwrap();
            lu_solve(&Rows::new(2, &mut m), &pivots, &mut f);
            f
        };
        let s = 0.5;
        let (mut m, f) = at(s);
        let mut pivots = [0; 2];
        lu_factor(&mut Rows::new(2, &mut m), &mut pivots).unwrap();
        let x = solve(s);
        let d_matrix = [1.0, 0.0, 0.0, 0.0];
        let d_force = [0.0, 2.0 * s];
        let layout = Layout { speeds: 2, post: None, work: false };
        let (mut dstate, mut jac, mut dx) = ([0.0; 2], [0.0; 2], [0.0; 2]);
        let factors = Rows::new(2, &mut m);
        let a = Block { force: &f, ..Block::EMPTY };
        let derivative = |_| Block { matrix: &d_matrix, force: &d_force, ..Block::EMPTY };
        write_jacobian(0.0, layout, &a, &x, (&factors, &pivots), (1, derivative), &mut dx, &mut dstate, (&mut jac, 1)).unwrap();
        assert_eq!(dstate, x);
        let h = 1e-6;
        let (up, down) = (solve(s + h), solve(s - h));
        for i in 0..2 {
            let quotient = (up[i] - down[i]) / (2.0 * h);
            assert!((jac[i] - quotient).abs() < 1e-8, "row {i}: {} against {quotient}", jac[i]);
        }
    }
}
