//! What an emitted model is, for code that picks one at run time.
//!
//! Every module the generator emits ends with `pub fn model() -> seam::Model`: its sizes and
//! names, its parameters as values, each formulation's functions over slices, and the shared
//! functions (energy, work rate, momenta, constraint residuals). Every function returns the one
//! error type of this crate, [`Failure`], both through the slices and through the module's own
//! fixed-size functions. The runtime (integrators, monitors, the comparison of formulations)
//! depends on this crate only, never on a particular model.
//!
//! The crate has no dependencies, so that a crate holding one generated module compiles it and
//! this file, nothing more.
//!
//! ```
//! // A hand-written one-coordinate model (x'' = -x), as an emitted module would describe it.
//! use seam::{Failure, Formulation, Model, array, array_mut};
//!
//! fn rhs(_t: f64, state: &[f64], _params: &[f64], _g_i: &[f64], dstate: &mut [f64]) -> Result<(), Failure> {
//!     let [x, v] = *array::<2>("state", state)?;
//!     *array_mut::<2>("dstate", dstate)? = [v, -x];
//!     Ok(())
//! }
//! static FORMULATIONS: [Formulation; 1] =
//!     [Formulation { name: "lagrange", states: 2, equations: 1, rhs, ..Formulation::EMPTY }];
//! let model = Model { name: "oscillator", coordinates: &["x"], formulations: &FORMULATIONS, ..Model::EMPTY };
//!
//! let lagrange = model.formulation("lagrange").unwrap();
//! let mut dy = [0.0; 2];
//! (lagrange.rhs)(0.0, &[1.0, 0.0], &[], &[], &mut dy).unwrap();
//! assert_eq!(dy, [0.0, -1.0]);
//! let short = (lagrange.rhs)(0.0, &[1.0], &[], &[], &mut dy);
//! assert_eq!(short, Err(Failure::Dimension { argument: "state", expected: 2, got: 1 }));
//! assert!((model.energy)(0.0, &[1.0], &[0.0], &[], &mut [0.0]).is_err());
//! ```

#![forbid(unsafe_code)]

use std::fmt;

/// Why an emitted function could not produce a value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Failure {
    /// The equations are singular at time `t`: `condition` vanishes (its value, or the pivot
    /// column for the mass matrix).
    Singular { t: f64, condition: &'static str, value: f64 },
    /// Output `index` is not a finite number at time `t`.
    NonFinite { t: f64, index: usize },
    /// A state violates `constraint`: its residual exceeds the tolerance.
    ConstraintViolated { constraint: &'static str, residual: f64, tolerance: f64 },
    /// A slice argument has the wrong length.
    Dimension { argument: &'static str, expected: usize, got: usize },
    /// The module was emitted without this function (the model file's `emit.functions`).
    Missing { function: &'static str },
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Failure::Singular { t, condition, value } => {
                write!(f, "singular configuration at t = {t}: {condition} (value {value:e})")
            }
            Failure::NonFinite { t, index } => write!(f, "non-finite value in output {index} at t = {t}"),
            Failure::ConstraintViolated { constraint, residual, tolerance } => {
                write!(f, "constraint `{constraint}` is violated: residual {residual:e} exceeds {tolerance:e}")
            }
            Failure::Dimension { argument, expected, got } => {
                write!(f, "`{argument}` has {got} entries, {expected} expected")
            }
            Failure::Missing { function } => {
                write!(f, "the module was emitted without `{function}`: add it to `emit.functions` in the model file")
            }
        }
    }
}

impl std::error::Error for Failure {}

/// `rhs(t, state, params, g_i, dstate)`: `dstate = f(t, state)`.
pub type RhsFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64]) -> Result<(), Failure>;
/// `rhs_baumgarte(t, state, params, g_i, dstate, alpha, beta)`.
pub type StabilizedFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64], f64, f64) -> Result<(), Failure>;
/// `matrix(t, state, params, g_i, out)`: the matrix `rhs` solves, row-major.
pub type MatrixFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64]) -> Result<(), Failure>;
/// `singular_margin(t, state, params, g_i)`: distance to the singular set of what was solved
/// symbolically (infinite when nothing was).
pub type MarginFn = fn(f64, &[f64], &[f64], &[f64]) -> Result<f64, Failure>;
/// `initial_state(t, q, qdot, params, state, g_i)`: the state and the conserved momenta `G_I`
/// of `q(t), q'(t)`; [`Failure::ConstraintViolated`] when `q'` is not admissible.
pub type InitialFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64], &mut [f64]) -> Result<(), Failure>;
/// `velocities(t, state, params, g_i, q, qdot)`: `q` and `q'` at a state.
pub type VelocitiesFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64], &mut [f64]) -> Result<(), Failure>;
/// A function of `(t, q, qdot, params)` writing its outputs.
/// `(t, state, params, g_i, dstate, jac)`: the right-hand side and its Jacobian by the state,
/// row-major (`jac[i * states + k] = d dstate[i] / d state[k]`).
pub type JacobianFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64], &mut [f64]) -> Result<(), Failure>;
pub type PointFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64]) -> Result<(), Failure>;

/// One formulation of a model: its sizes and its functions over slices.
#[derive(Clone, Copy, Debug)]
pub struct Formulation {
    /// `lagrange`, `maggi`, `kane` or `reduced_volterra`.
    pub name: &'static str,
    /// Length of the state.
    pub states: usize,
    /// Number of second-order equations solved.
    pub equations: usize,
    /// The ignorable coordinates are integrated (otherwise they left the state).
    pub integrates_ignorable: bool,
    /// The last state entry is the work integral `W` (Eq. 80).
    pub has_work_state: bool,
    pub state_names: &'static [&'static str],
    pub rhs: RhsFn,
    /// Lagrange only: the Baumgarte-stabilized right-hand side.
    pub rhs_baumgarte: Option<StabilizedFn>,
    pub initial_state: InitialFn,
    pub velocities: VelocitiesFn,
    /// Size of the matrix `rhs` solves numerically.
    pub matrix_size: usize,
    pub matrix: MatrixFn,
    pub singular_margin: MarginFn,
    /// The exact Jacobian, when the module was emitted with it.
    pub jacobian: Option<JacobianFn>,
    /// The exact derivative by the parameters (`jac[i * parameters + k]`), when emitted.
    pub parameter_jacobian: Option<JacobianFn>,
}

/// One emitted model.
#[derive(Clone, Copy, Debug)]
pub struct Model {
    /// The module's name: the model's name, or the name it was emitted under (a variant such as
    /// `cart_pendulum_baked`).
    pub module: &'static str,
    /// The model's own name.
    pub name: &'static str,
    pub coordinates: &'static [&'static str],
    pub constraints: &'static [&'static str],
    /// Indices of the ignorable coordinates in `coordinates`.
    pub ignorable: &'static [usize],
    /// Number of holonomic (position-level) constraints, the first of `constraints`.
    pub holonomic: usize,
    pub parameter_names: &'static [&'static str],
    /// The model file's parameter values (empty when they were baked into the code).
    pub default_params: &'static [f64],
    /// `(q(0), q'(0))` of the reference run, when the model file gives one.
    pub initial: Option<(&'static [f64], &'static [f64])>,
    /// `(t_start, t_end, dt_out)` of the reference run, when the model file gives one.
    pub run: Option<(f64, f64, f64)>,
    /// `T + V`: one output.
    pub energy: PointFn,
    /// `Q . q'`: one output.
    pub work_rate: PointFn,
    /// One output per ignorable coordinate.
    pub momenta: PointFn,
    /// One output per constraint.
    pub constraint_residuals: PointFn,
    /// One output per holonomic constraint (`qdot` is ignored).
    pub position_residuals: PointFn,
    pub formulations: &'static [Formulation],
}

impl Model {
    /// A model with no coordinates and no formulations, whose functions all fail with
    /// [`Failure::Missing`]: the base to fill in with struct update syntax.
    pub const EMPTY: Model = Model {
        module: "",
        name: "",
        coordinates: &[],
        constraints: &[],
        ignorable: &[],
        holonomic: 0,
        parameter_names: &[],
        default_params: &[],
        initial: None,
        run: None,
        energy: missing_energy,
        work_rate: missing_work_rate,
        momenta: missing_momenta,
        constraint_residuals: missing_constraint_residuals,
        position_residuals: missing_position_residuals,
        formulations: &[],
    };

    /// The formulation called `name`.
    pub fn formulation(&self, name: &str) -> Option<&'static Formulation> {
        self.formulations.iter().find(|f| f.name == name)
    }
}

impl Formulation {
    /// A formulation of no states whose functions all fail with [`Failure::Missing`].
    pub const EMPTY: Formulation = Formulation {
        name: "",
        states: 0,
        equations: 0,
        integrates_ignorable: true,
        has_work_state: false,
        state_names: &[],
        rhs: |_, _, _, _, _| Err(Failure::Missing { function: "rhs" }),
        rhs_baumgarte: None,
        initial_state: |_, _, _, _, _, _| Err(Failure::Missing { function: "initial_state" }),
        velocities: |_, _, _, _, _, _| Err(Failure::Missing { function: "velocities" }),
        matrix_size: 0,
        matrix: |_, _, _, _, _| Err(Failure::Missing { function: "matrix" }),
        singular_margin: |_, _, _, _| Err(Failure::Missing { function: "singular_margin" }),
        jacobian: None,
        parameter_jacobian: None,
    };
}

/// Stand-ins for shared functions a module was emitted without.
fn missing_energy(_: f64, _: &[f64], _: &[f64], _: &[f64], _: &mut [f64]) -> Result<(), Failure> {
    Err(Failure::Missing { function: "energy" })
}
fn missing_work_rate(_: f64, _: &[f64], _: &[f64], _: &[f64], _: &mut [f64]) -> Result<(), Failure> {
    Err(Failure::Missing { function: "work_rate" })
}
fn missing_momenta(_: f64, _: &[f64], _: &[f64], _: &[f64], _: &mut [f64]) -> Result<(), Failure> {
    Err(Failure::Missing { function: "momenta" })
}
fn missing_constraint_residuals(_: f64, _: &[f64], _: &[f64], _: &[f64], _: &mut [f64]) -> Result<(), Failure> {
    Err(Failure::Missing { function: "constraint_residuals" })
}
fn missing_position_residuals(_: f64, _: &[f64], _: &[f64], _: &[f64], _: &mut [f64]) -> Result<(), Failure> {
    Err(Failure::Missing { function: "position_residuals" })
}

/// The most output intervals one run may have (its output times are one more): a run holds every sample in memory (the states and
/// the monitored invariants), so a million samples of a few dozen numbers stay under a gigabyte.
pub const MAX_OUTPUTS: usize = 1_000_000;

/// Why `(t_start, t_end, dt_out)` is not a run that can be sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GridError {
    /// Not finite, `t_end <= t_start`, or `dt_out <= 0`.
    NotARun { t_start: f64, t_end: f64, dt_out: f64 },
    /// `dt_out` is longer than the run: there would be no output inside it.
    StepLongerThanRun { span: f64, dt_out: f64 },
    /// More output times than [`MAX_OUTPUTS`].
    TooManyOutputs { count: f64 },
}

impl fmt::Display for GridError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            GridError::NotARun { t_start, t_end, dt_out } => {
                write!(
                    f,
                    "a run from t = {t_start} to t_end = {t_end} every dt_out = {dt_out} is not a run: use finite numbers with t_end > t_start and dt_out > 0"
                )
            }
            GridError::StepLongerThanRun { span, dt_out } => {
                write!(f, "dt_out = {dt_out} is longer than the run ({span}): no output would fall inside it; use dt_out <= t_end - t_start")
            }
            GridError::TooManyOutputs { count } => write!(
                f,
                "the run would have {count:.3e} output times, more than the {} a run may hold: use a larger dt_out or a shorter t_end",
                MAX_OUTPUTS + 1
            ),
        }
    }
}

impl std::error::Error for GridError {}

/// The output times of a run: `t_start, t_start + dt_out, ...`, and `t_end` exactly as the last
/// one (the step before it may be shorter), or why there are none.
///
/// ```
/// assert_eq!(seam::output_times(0.0, 1.0, 0.25), Ok(vec![0.0, 0.25, 0.5, 0.75, 1.0]));
/// assert_eq!(seam::output_times(0.0, 1.0, 0.6), Ok(vec![0.0, 0.6, 1.0]));
/// assert!(seam::output_times(0.0, 1.0, 100.0).is_err());
/// assert!(seam::output_times(0.0, 1e300, 0.01).unwrap_err().to_string().contains("dt_out"));
/// ```
pub fn output_times(t_start: f64, t_end: f64, dt_out: f64) -> Result<Vec<f64>, GridError> {
    let n = output_steps(t_start, t_end, dt_out)?;
    Ok((0..n).map(|i| t_start + i as f64 * dt_out).chain([t_end]).collect())
}

/// The number of output intervals of a run (one less than its output times): `(t_end -
/// t_start) / dt_out` rounded up, or rounded to the nearest where it is within `1e-9` of it
/// (`50 / 0.01` is 5000, not 5001).
pub fn output_steps(t_start: f64, t_end: f64, dt_out: f64) -> Result<usize, GridError> {
    if !(t_start.is_finite() && t_end.is_finite() && dt_out.is_finite() && t_end > t_start && dt_out > 0.0) {
        return Err(GridError::NotARun { t_start, t_end, dt_out });
    }
    let span = t_end - t_start;
    if !span.is_finite() {
        return Err(GridError::TooManyOutputs { count: f64::INFINITY });
    }
    if dt_out > span * (1.0 + 1e-12) {
        return Err(GridError::StepLongerThanRun { span, dt_out });
    }
    let ratio = span / dt_out;
    if !(ratio <= MAX_OUTPUTS as f64 + 0.5) {
        return Err(GridError::TooManyOutputs { count: ratio + 1.0 });
    }
    let nearest = ratio.round();
    let n = if (ratio - nearest).abs() <= 1e-9 * ratio.max(1.0) { nearest } else { ratio.ceil() };
    Ok((n as usize).max(1))
}

/// `slice` as an array of `N`, or [`Failure::Dimension`] naming `argument`.
///
/// ```
/// assert_eq!(seam::array::<2>("q", &[1.0, 2.0]), Ok(&[1.0, 2.0]));
/// assert!(seam::array::<2>("q", &[1.0]).is_err());
/// ```
pub fn array<'a, const N: usize>(argument: &'static str, slice: &'a [f64]) -> Result<&'a [f64; N], Failure> {
    slice.try_into().map_err(|_| Failure::Dimension { argument, expected: N, got: slice.len() })
}

/// `slice` as a mutable array of `N`, or [`Failure::Dimension`] naming `argument`.
///
/// ```
/// let mut out = [0.0; 2];
/// *seam::array_mut::<2>("out", &mut out).unwrap() = [3.0, 4.0];
/// assert_eq!(out, [3.0, 4.0]);
/// ```
pub fn array_mut<'a, const N: usize>(argument: &'static str, slice: &'a mut [f64]) -> Result<&'a mut [f64; N], Failure> {
    let got = slice.len();
    slice.try_into().map_err(|_| Failure::Dimension { argument, expected: N, got })
}

/// Copies a row-major `N x N` matrix into `out`, or [`Failure::Dimension`] when `out` does not
/// hold `N * N` entries.
///
/// ```
/// let mut out = [0.0; 4];
/// seam::copy_matrix(&[[1.0, 2.0], [3.0, 4.0]], &mut out).unwrap();
/// assert_eq!(out, [1.0, 2.0, 3.0, 4.0]);
/// ```
pub fn copy_matrix<const N: usize>(a: &[[f64; N]; N], out: &mut [f64]) -> Result<(), Failure> {
    copy_into("out", a, out)
}

/// Copies `a`, `R` rows of `C` entries, into the row-major slice `jac` (`R * C` long).
///
/// ```
/// let mut jac = [0.0; 6];
/// seam::copy_rows(&[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]], &mut jac).unwrap();
/// assert_eq!(jac, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
/// assert!(seam::copy_rows(&[[1.0, 2.0]], &mut [0.0; 3]).is_err());
/// ```
pub fn copy_rows<const R: usize, const C: usize>(a: &[[f64; C]; R], jac: &mut [f64]) -> Result<(), Failure> {
    copy_into("jac", a, jac)
}

/// `a` into the row-major slice `out`, named `argument` when its length is wrong.
fn copy_into<const R: usize, const C: usize>(argument: &'static str, a: &[[f64; C]; R], out: &mut [f64]) -> Result<(), Failure> {
    if out.len() != R * C {
        return Err(Failure::Dimension { argument, expected: R * C, got: out.len() });
    }
    for (row, chunk) in a.iter().zip(out.chunks_mut(C.max(1))) {
        chunk.copy_from_slice(row);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_model_reports_missing_functions() {
        let mut out = [0.0];
        let e = (Model::EMPTY.energy)(0.0, &[], &[], &[], &mut out).unwrap_err();
        assert_eq!(e, Failure::Missing { function: "energy" });
        assert!(e.to_string().contains("emit.functions"), "{e}");
        assert!((Formulation::EMPTY.rhs)(0.0, &[], &[], &[], &mut []).is_err());
    }

    #[test]
    fn output_grids_end_at_t_end_and_refuse_what_is_not_a_run() {
        let t = output_times(0.0, 50.0, 0.01).unwrap();
        assert_eq!((t.len(), t[5000]), (5001, 50.0));
        assert_eq!(output_times(2.0, 3.0, 1.0), Ok(vec![2.0, 3.0]));
        assert!(matches!(output_times(0.0, 1.0, 100.0), Err(GridError::StepLongerThanRun { .. })));
        assert!(matches!(output_times(0.0, 1e300, 0.01), Err(GridError::TooManyOutputs { .. })));
        assert!(matches!(output_times(0.0, 1.0, 1e-300), Err(GridError::TooManyOutputs { .. })));
        assert!(matches!(output_times(-1e308, 1e308, 1.0), Err(GridError::TooManyOutputs { .. })));
        assert!(matches!(output_times(0.0, 1e7, 0.01), Err(GridError::TooManyOutputs { .. })));
        assert!(matches!(output_times(1.0, 1.0, 0.1), Err(GridError::NotARun { .. })));
        assert!(matches!(output_times(0.0, 1.0, f64::NAN), Err(GridError::NotARun { .. })));
        assert_eq!(output_times(0.0, 1.0, 1e-6).unwrap().len(), 1_000_001);
    }

    #[test]
    fn dimension_errors_name_the_argument() {
        let e = array_mut::<3>("dstate", &mut [0.0; 2]).unwrap_err();
        assert_eq!(e.to_string(), "`dstate` has 2 entries, 3 expected");
        assert!(copy_matrix(&[[1.0]], &mut [0.0; 2]).is_err());
    }
}
