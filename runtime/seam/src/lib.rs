//! What a model is, for the code that runs it: the contract between the generator's output
//! (a compiled module, or a model evaluated in-process) and the runtime.
//!
//! - [`FormulationKind`] and [`StateLayout`]: which formulation a set of functions is and how
//!   its state is laid out, as types (the runtime never matches names).
//! - [`Model`] and [`Formulation`]: a model's description and its functions over slices,
//!   behind [`ModelFunctions`] and [`FormulationFunctions`]. An emitted module implements them
//!   with function pointers ([`StaticModel`], its `model()`); a model evaluated in-process
//!   implements them on its own.
//! - [`Event`]: a named zero crossing a run locates, and what happens there.
//! - [`Failure`]: the one error every function returns.
//! - [`output_times`]: the output grid of a run, and why some settings are not one.
//! - [`check`], [`solve`] and [`rates`]: what every model's right-hand side does after its
//!   assembly (the checks, the dense solves, the state's rates from the solution), written once.
//!
//! The crate has no dependencies, so that a crate holding one generated module compiles it and
//! this crate, nothing more.

#![forbid(unsafe_code)]

mod compiled;
mod event;
mod failure;
mod grid;
mod kind;
mod model;
pub mod check;
pub mod rates;
pub mod solve;

pub use compiled::{InitialFn, JacobianFn, MarginFn, MatrixFn, PointFn, RhsFn, StabilizedFn, StaticFormulation, StaticModel, VelocitiesFn};
pub use event::{Direction, Event, EventAction};
pub use failure::Failure;
pub use grid::{GridError, MAX_OUTPUTS, output_steps, output_times, short};
pub use kind::{EnergyBalance, FormulationKind, Speeds, StateLayout};
pub use model::{Formulation, FormulationFunctions, Gimbal, Model, ModelFunctions};

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
        let model = Model::from(StaticModel::EMPTY);
        let e = model.energy(0.0, &[], &[], &[], &mut out).unwrap_err();
        assert_eq!(e, Failure::Missing { function: "energy" });
        assert!(e.to_string().contains("emit.functions"), "{e}");
        let form = Formulation::from(StaticFormulation::EMPTY);
        assert!(form.rhs(0.0, &[], &[], &[], &mut []).is_err());
        assert_eq!(form.jacobian(0.0, &[], &[], &[], &mut [], &mut []), Err(Failure::Missing { function: "jacobian" }));
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
