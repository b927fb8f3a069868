//! Invariant monitors along a run, from the sampled states:
//!
//! - energy error `E(t) - E(0)` with `E = T + V - W`, `W` the work of the applied
//!   non-potential forces, integrated as a state `W' = Q . q'` with the dynamics (Eq. 80);
//! - the drift `G(t) - G(0)` of each ignorable coordinate's momentum `M' q' + N2`;
//! - constraint residuals: velocity level `|a q' + b|` and, for holonomic constraints, position
//!   level `|h(q, t)|` (Euclidean norms over the constraints at each sample).

use crate::integrate::Solution;
use crate::system::System;
use seam::Failure;

/// Error series at the output times.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Invariants {
    /// `E(t) - E(0)`.
    pub energy_error: Vec<f64>,
    /// `E(0)`, for relative errors.
    pub energy0: f64,
    /// Per ignorable coordinate: `G(t) - G(0)`.
    pub momentum_error: Vec<Vec<f64>>,
    /// `G(0)`.
    pub momentum0: Vec<f64>,
    /// Velocity-level constraint residual norm.
    pub velocity_constraint: Vec<f64>,
    /// Position-level (holonomic) residual norm.
    pub position_constraint: Vec<f64>,
    /// `q(t)` at the samples.
    pub coordinates: Vec<Vec<f64>>,
    /// `q'(t)` at the samples.
    pub rates: Vec<Vec<f64>>,
    /// `E(t) = T + V - W` at the samples.
    pub energy: Vec<f64>,
    /// 2-norm condition number of the matrix `rhs` solves (Lagrange: `[M a^T; a 0]`, Maggi:
    /// `W^T M W`, Kane and reduced Volterra: `M_NI`).
    pub condition: Vec<f64>,
    /// Distance to the singular set of what was solved symbolically (smallest singular factor
    /// of `[Y; M'; a]`; infinite when there is none).
    pub singular_margin: Vec<f64>,
}

/// 2-norm condition number of a square matrix given row-major.
pub fn condition_number(n: usize, a: &[f64]) -> f64 {
    // No equations (every coordinate ignorable, the reduced form of a free rotor): nothing to
    // solve, nothing ill-conditioned (nalgebra's SVD refuses an empty matrix).
    if n == 0 {
        return 1.0;
    }
    let m = nalgebra::DMatrix::from_row_slice(n, n, a);
    let sv = m.singular_values();
    let (lo, hi) = sv.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), s| (lo.min(*s), hi.max(*s)));
    if lo > 0.0 { hi / lo } else { f64::INFINITY }
}

/// Euclidean norm of a sampled series, as in the paper's tables.
pub fn norm(series: &[f64]) -> f64 {
    series.iter().map(|x| x * x).fold(0.0, |a, b| a + b).sqrt()
}

/// The momentum conjugate to a symmetry of the kinetic energy: `(dT/dq') . xi`, with `xi` the
/// rates of the coordinates that the symmetry's motion gives at `q` (for a rotation of the
/// whole system about a world axis, the angular momentum about that axis: Noether's charge,
/// conserved where the forces do no work along `xi`). `T` is quadratic in `q'`, so the central
/// difference along `xi` is exact but for round-off.
///
/// ```
/// # use seam::*;
/// # fn demo(model: &Model, q: &[f64], qdot: &[f64], xi: &[f64]) -> Result<f64, Failure> {
/// // A free particle's x momentum: `xi` moves x alone.
/// let p_x = runtime::monitor::momentum_along(model, 0.0, &model.default_params, q, qdot, xi)?;
/// # Ok(p_x) }
/// ```
pub fn momentum_along(model: &seam::Model, t: f64, params: &[f64], q: &[f64], qdot: &[f64], xi: &[f64]) -> Result<f64, Failure> {
    // The step's size does not matter to a quadratic; one of the rates' scale keeps the two
    // energies of the velocities' size, so the difference loses no more than it must.
    let scale = qdot.iter().chain(xi).fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
    let h = scale / xi.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
    let energy = |sign: f64| -> Result<f64, Failure> {
        let moved: Vec<f64> = qdot.iter().zip(xi).map(|(v, x)| v + sign * h * x).collect();
        let mut e = [0.0];
        model.energy(t, q, &moved, params, &mut e)?;
        Ok(e[0])
    };
    Ok((energy(1.0)? - energy(-1.0)?) / (2.0 * h))
}

/// Evaluates the monitors at every sample of `sol`.
pub fn monitor(sys: &System, sol: &Solution) -> Result<Invariants, Failure> {
    monitor_with_jumps(sys, sol, &[])
}

/// [`monitor`] of a run with resets ([`crate::events::run`]): after each, the states are read
/// with the momenta `G_I` it left, and its jumps of energy and momenta are taken out of the
/// balances (they are the impact's, not the integration's).
pub fn monitor_with_jumps(sys: &System, sol: &Solution, jumps: &[crate::events::Jump]) -> Result<Invariants, Failure> {
    let mut current = sys.clone();
    let mut passed = 0;
    let (mut energy_jumps, mut momentum_jumps) = (0.0, vec![0.0; sys.model.ignorable.len()]);
    let sys = &mut current;
    let model = &sys.model.clone();
    let s = model.ignorable.len();
    let mut inv = Invariants { momentum_error: vec![Vec::new(); s], ..Invariants::default() };
    let mut e_buf = [0.0];
    let mut g_buf = vec![0.0; s];
    let mut c_buf = vec![0.0; model.constraints.len()];
    let mut h_buf = vec![0.0; model.holonomic];
    let n = sys.form.matrix_size;
    let mut a_buf = vec![0.0; n * n];
    let mut e0 = None;
    let mut g0: Vec<f64> = Vec::new();
    for (t, y) in sol.times.iter().zip(&sol.states) {
        // The resets up to this time (an output at a reset's time is the state after it).
        while passed < jumps.len() && jumps[passed].t <= *t {
            let jump = &jumps[passed];
            sys.g_i.clone_from(&jump.g_i);
            energy_jumps += jump.energy;
            momentum_jumps.iter_mut().zip(&jump.momenta).for_each(|(a, b)| *a += b);
            passed += 1;
        }
        let (q, qd) = sys.velocities(*t, y)?;
        model.energy(*t, &q, &qd, &sys.params, &mut e_buf)?;
        let e = e_buf[0] - sys.work(y) - energy_jumps;
        let e_start = *e0.get_or_insert(e);
        inv.energy.push(e);
        inv.energy_error.push(e - e_start);
        model.momenta(*t, &q, &qd, &sys.params, &mut g_buf)?;
        if g0.is_empty() {
            g0 = g_buf.clone();
        }
        for k in 0..s {
            inv.momentum_error[k].push(g_buf[k] - momentum_jumps[k] - g0[k]);
        }
        model.constraint_residuals(*t, &q, &qd, &sys.params, &mut c_buf)?;
        inv.velocity_constraint.push(norm(&c_buf));
        model.position_residuals(*t, &q, &qd, &sys.params, &mut h_buf)?;
        inv.position_constraint.push(norm(&h_buf));
        inv.coordinates.push(q);
        inv.rates.push(qd);
        sys.form.matrix(*t, y, &sys.params, &sys.g_i, &mut a_buf)?;
        inv.condition.push(condition_number(n, &a_buf));
        inv.singular_margin.push(sys.form.singular_margin(*t, y, &sys.params, &sys.g_i)?);
    }
    inv.energy0 = e0.unwrap_or(0.0);
    inv.momentum0 = g0;
    Ok(inv)
}
