//! A crate with a model of its own (`models/gantry_crane.ron`, not one of the project's):
//! `build.rs` generates its module into `OUT_DIR` and it is included here; the runtime's
//! integrators, monitors and comparison run it through the seam (`gantry_crane::model()`).
//!
//! ```
//! let table = downstream::comparison(1).unwrap();
//! assert!(table.contains("| reduced_volterra | 5 | 2 |"), "{table}");
//! ```

#![forbid(unsafe_code)]
#![deny(warnings)]

/// The gantry crane, generated at build time.
#[allow(clippy::all)]
pub mod gantry_crane {
    include!(concat!(env!("OUT_DIR"), "/gantry_crane.rs"));
}

use runtime::compare::{CompareError, Options, compare, table};

/// Every formulation of the crane at the paper's integrator settings, as the comparison table
/// (CPU time the median of `repeats` runs).
pub fn comparison(repeats: usize) -> Result<String, CompareError> {
    let model = gantry_crane::model();
    let runs = compare(&model, &Options { repeats, ..Options::paper(&model) })?;
    Ok(table(&runs))
}

#[cfg(test)]
mod tests {
    use super::gantry_crane as crane;
    use runtime::compare::{Options, Reference, compare};
    use runtime::integrate::{Settings, integrate};
    use runtime::monitor::{monitor, norm};
    use runtime::system::System;

    #[test]
    fn the_runtime_integrates_the_crate_s_own_model_and_its_invariants_hold() {
        let model = crane::model();
        let r = Reference::of(&model).unwrap();
        let settings = Settings { rtol: 1e-10, atol: 1e-10, ..Settings::paper(r.t_end - r.t_start) };
        let (sys, y0) = System::start(&model, runtime::seam::FormulationKind::ReducedVolterra, r.params.clone(), &r.q0, &r.qd0).unwrap();
        let sol = integrate(&mut |t, y, dy| sys.rhs(t, y, dy), &y0, &r.times().unwrap(), &settings).unwrap();
        let inv = monitor(&sys, &sol).unwrap();
        assert!(norm(&inv.energy_error) < 1e-6 * inv.energy0.abs().max(1.0), "energy drift {}", norm(&inv.energy_error));
        // The trolley's momentum is what the reduced method holds fixed; Lagrange integrates it.
        assert!(inv.momentum_error[0].iter().all(|e| e.abs() < 1e-12));
        let swing = inv.coordinates.iter().map(|q| q[1]).fold(f64::NEG_INFINITY, f64::max);
        assert!(swing > 0.59, "the cable swings: max phi {swing}");
    }

    #[test]
    fn the_four_formulations_agree_on_the_crane() {
        let model = crane::model();
        let tight = Options { settings: Settings { rtol: 1e-11, atol: 1e-11, ..Options::paper(&model).settings }, repeats: 1, ..Options::paper(&model) };
        let runs = compare(&model, &tight).unwrap();
        assert_eq!(runs.len(), 4);
        let last = |i: usize| runs[i].invariants.coordinates.last().unwrap().clone();
        let reduced = last(3);
        for i in 0..3 {
            let other = last(i);
            // Coordinates the reduced method keeps (phi, psi) and the reconstructed x.
            for j in 0..3 {
                assert!((other[j] - reduced[j]).abs() < 1e-6, "{} q{j}: {} against {}", runs[i].record.method, other[j], reduced[j]);
            }
        }
    }

    #[test]
    fn a_wrong_slice_length_and_an_inadmissible_state_are_typed_errors() {
        let model = crane::model();
        let lagrange = model.formulation(runtime::seam::FormulationKind::Lagrange).unwrap();
        let mut dy = [0.0; 6];
        let e = lagrange.rhs(0.0, &[0.0; 5], &model.default_params, &[0.0], &mut dy).unwrap_err();
        assert_eq!(e, runtime::seam::Failure::Dimension { argument: "state", expected: 6, got: 5 });
        let e = System::start(&model, runtime::seam::FormulationKind::Kane, vec![1.0; 2], &[0.0; 3], &[0.0; 3]).unwrap_err();
        assert!(e.to_string().contains("`params` has 2 entries, 6 expected"), "{e}");
    }
}
