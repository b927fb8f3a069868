//! Work-precision sweeps: every formulation x every integrator x a range of settings, each run
//! measured for wall-clock time (median of repeats), right-hand-side calls, error against a reference
//! solution, and the invariants, like the work-precision diagrams of ODE benchmark suites.
//!
//! ```no_run
//! use runtime::sweep::{SweepOptions, sweep};
//! let model = generated::find("satellite_boom").unwrap();
//! let points = sweep(&model, &SweepOptions::default(), &mut |_done, _total, _label| {}).unwrap();
//! assert!(points.iter().any(|p| p.method == "reduced_volterra"));
//! ```

use crate::compare::{CompareError, Reference, run_with};
use crate::integrate::{Method, Settings};
use crate::system::Drift;
use seam::{FormulationKind, Model};

/// What to sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepOptions {
    /// The adaptive integrators (default DOPRI5 and DOP853).
    pub adaptive: Vec<Method>,
    /// Tolerances (rtol = atol) for the adaptive integrators.
    pub tolerances: Vec<f64>,
    /// RK4 steps, as fractions of the output interval.
    pub rk4_steps: Vec<f64>,
    pub repeats: usize,
    /// Tolerance of the reference run (DOP853, reduced Volterra).
    pub reference_tolerance: f64,
    /// Formulations (empty: all).
    pub formulations: Vec<FormulationKind>,
    /// The run (`None`: the model file's reference run).
    pub reference: Option<Reference>,
}

impl Default for SweepOptions {
    fn default() -> Self {
        SweepOptions {
            adaptive: vec![Method::Dopri5, Method::Dop853],
            tolerances: (3..=12).map(|k| 10f64.powi(-k)).collect(),
            // Two decades of steps.
            rk4_steps: vec![1.0, 0.5, 0.2, 0.1, 0.05, 0.02, 0.01],
            repeats: 3,
            reference_tolerance: 1e-13,
            formulations: vec![],
            reference: None,
        }
    }
}

/// One measured run.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Point {
    pub scene: String,
    pub method: String,
    pub integrator: String,
    /// rtol (= atol) for the adaptive methods, the step for RK4.
    pub setting: f64,
    pub seconds: f64,
    pub rhs_calls: usize,
    pub steps: usize,
    /// Largest |q - q_ref| over the samples and coordinates.
    pub error: f64,
    pub energy_error_norm: f64,
    pub momentum_error_norm: f64,
    pub constraint_error_norm: f64,
    /// Why the run stopped, when it did not finish.
    pub failure: Option<String>,
}

fn max_error(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter().zip(b).flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs())).fold(0.0, f64::max)
}

/// The settings a sweep runs, with labels.
pub fn plan(model: &Model, options: &SweepOptions) -> Result<Vec<Settings>, CompareError> {
    let r = match &options.reference {
        Some(r) => r.clone(),
        None => Reference::of(model)?,
    };
    let (h_max, dt) = (0.1 * (r.t_end - r.t_start), r.dt_out);
    let mut out = Vec::new();
    for &method in &options.adaptive {
        for &tol in &options.tolerances {
            out.push(Settings { method, rtol: tol, atol: tol, h_max, ..Settings::default() });
        }
    }
    for &f in &options.rk4_steps {
        out.push(Settings { method: Method::Rk4 { h: f * dt }, h_max, ..Settings::default() });
    }
    Ok(out)
}

/// Runs the sweep; `progress(done, total, label)` is called before each run.
pub fn sweep(model: &Model, options: &SweepOptions, progress: &mut dyn FnMut(usize, usize, &str)) -> Result<Vec<Point>, CompareError> {
    let r = match &options.reference {
        Some(r) => r.clone(),
        None => Reference::of(model)?,
    };
    r.check()?;
    let reference_settings = Settings {
        method: Method::Dop853,
        rtol: options.reference_tolerance,
        atol: options.reference_tolerance,
        h_max: 0.1 * (r.t_end - r.t_start),
        ..Settings::default()
    };
    // The reference solution: the reduced method when the module has it, else the first.
    let reference_form =
        model.formulation(FormulationKind::ReducedVolterra).or(model.formulations.first()).map_or(FormulationKind::ReducedVolterra, |f| f.kind);
    let reference = run_with(model, &r, reference_form, &reference_settings, 1, Drift::None)?.invariants.coordinates;
    let forms: Vec<FormulationKind> = model.kinds().into_iter().filter(|k| options.formulations.is_empty() || options.formulations.contains(k)).collect();
    let settings = plan(model, options)?;
    let total = forms.len() * settings.len();
    let mut points = Vec::new();
    for form in &forms {
        for s in &settings {
            let setting = match s.method {
                Method::Rk4 { h } => h,
                _ => s.rtol,
            };
            let integrator = match s.method {
                Method::Rk4 { .. } => "RK4".to_string(),
                m => m.to_string(),
            };
            progress(points.len(), total, &format!("{form} {integrator} {setting:.2e}"));
            let point = match run_with(model, &r, *form, s, options.repeats, Drift::None) {
                Ok(r) => Point {
                    scene: model.module.to_string(),
                    method: form.to_string(),
                    integrator,
                    setting,
                    seconds: r.record.seconds,
                    rhs_calls: r.record.rhs_calls,
                    steps: r.record.steps,
                    error: max_error(&r.invariants.coordinates, &reference),
                    energy_error_norm: r.record.energy_error_norm,
                    momentum_error_norm: r.record.momentum_error_norm,
                    constraint_error_norm: r.record.constraint_error_norm,
                    failure: None,
                },
                // A failed run is a result too: recorded with its reason.
                Err(e) => Point {
                    scene: model.module.to_string(),
                    method: form.to_string(),
                    integrator,
                    setting,
                    seconds: f64::NAN,
                    rhs_calls: 0,
                    steps: 0,
                    error: f64::NAN,
                    energy_error_norm: f64::NAN,
                    momentum_error_norm: f64::NAN,
                    constraint_error_norm: f64::NAN,
                    failure: Some(e.to_string()),
                },
            };
            points.push(point);
        }
    }
    progress(total, total, "done");
    Ok(points)
}

/// The points as CSV.
pub fn csv(points: &[Point]) -> String {
    let mut out =
        String::from("scene,method,integrator,setting,seconds,rhs_calls,steps,error,energy_error_norm,momentum_error_norm,constraint_error_norm,failure\n");
    for p in points {
        out += &format!(
            "{},{},{},{:e},{:e},{},{},{:e},{:e},{:e},{:e},{}\n",
            p.scene,
            p.method,
            p.integrator,
            p.setting,
            p.seconds,
            p.rhs_calls,
            p.steps,
            p.error,
            p.energy_error_norm,
            p.momentum_error_norm,
            p.constraint_error_norm,
            p.failure.as_deref().unwrap_or("").replace(',', ";")
        );
    }
    out
}
