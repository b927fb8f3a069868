//! Every formulation of a model under the same integrator settings, measured like the paper's
//! Tables 2, 3 and 6: states, equations, wall-clock time of a run (median of repeated runs), and the norms of
//! the energy, constraint and momentum errors.
//!
//! ```
//! use runtime::compare::{Options, compare};
//! let model = generated::find("cart_pendulum").unwrap();
//! let runs = compare(&model, &Options { repeats: 1, ..Options::paper(&model) }).unwrap();
//! let reduced = runs.iter().find(|r| r.record.method == "reduced_volterra").unwrap();
//! assert_eq!(reduced.kind, seam::FormulationKind::ReducedVolterra);
//! assert!(reduced.record.constraint_error_norm < 1e-12);
//! ```

use crate::integrate::{RunError, Settings, Solution};
use crate::monitor::{Invariants, monitor_with_jumps, norm};
use crate::system::{Drift, SetupError, System};
use seam::{Failure, FormulationKind, Model};
use std::time::Instant;

/// What to run.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    pub settings: Settings,
    /// The time of a run is the median of this many runs.
    pub repeats: usize,
    /// Formulations to run (empty: all the model has).
    pub formulations: Vec<FormulationKind>,
    /// Drift control applied to the classical formulations that support it.
    pub drift: Drift,
    /// The run: initial state, parameters and times (`None`: the model file's reference run).
    pub reference: Option<Reference>,
}

impl Options {
    /// The paper's settings for the model's reference run, 5 repeats.
    pub fn paper(model: &Model) -> Options {
        // Without a reference run there is nothing to run; `run` says so.
        let span = model.run.map_or(1.0, |(t0, t1, _)| t1 - t0);
        Options { settings: Settings::paper(span), repeats: 5, formulations: vec![], drift: Drift::None, reference: None }
    }
}

/// JSON writes a non-finite number as `null`: read back as NaN (the table prints it as `-`, or as
/// `NaN`/`inf` where the number was infinite, which a record read back cannot tell apart).
fn null_as_nan<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(<Option<f64> as serde::Deserialize>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// One row of the comparison table (also the JSON record, written by `compare --json` and read
/// back to check the tables quoted from it).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Record {
    pub scene: String,
    pub method: String,
    pub integrator: String,
    pub states: usize,
    pub equations: usize,
    #[serde(deserialize_with = "null_as_nan")]
    pub seconds: f64,
    /// The column the energy error is reported in (`energy err`, `jacobi err`, `h - W err`:
    /// [`seam::EnergyBalance::column`]) and what it measures.
    pub energy_column: String,
    pub energy_balance: String,
    #[serde(deserialize_with = "null_as_nan")]
    pub energy_error_norm: f64,
    /// Relative to the initial energy; NaN where that is zero (the table shows `-`).
    #[serde(deserialize_with = "null_as_nan")]
    pub energy_error_rel: f64,
    #[serde(deserialize_with = "null_as_nan")]
    pub constraint_error_norm: f64,
    #[serde(deserialize_with = "null_as_nan")]
    pub position_constraint_error_norm: f64,
    /// All ignorable momenta together.
    #[serde(deserialize_with = "null_as_nan")]
    pub momentum_error_norm: f64,
    #[serde(deserialize_with = "null_as_nan")]
    pub momentum_error_rel: f64,
    /// Each ignorable momentum on its own.
    pub momenta: Vec<MomentumError>,
    pub steps: usize,
    pub rejected: usize,
    pub rhs_calls: usize,
    /// Largest condition number of the matrix solved at run time, over the samples.
    #[serde(deserialize_with = "null_as_nan")]
    pub max_condition: f64,
    /// Smallest distance to the singular set of `[Y; M'; a]` over the samples (`null`: none).
    #[serde(deserialize_with = "null_as_nan")]
    pub min_singular_margin: f64,
    /// DOPRI5: the time from which the run looks stiff by Hairer's test (`null`: it does not).
    pub stiff_at: Option<f64>,
}

/// The drift of one ignorable coordinate's momentum over a run.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MomentumError {
    pub coordinate: String,
    /// Norm of `G(t) - G(0)` over the samples.
    #[serde(deserialize_with = "null_as_nan")]
    pub norm: f64,
    /// The same divided by `|G(0)|` (NaN, `null` in JSON, when `G(0) = 0`).
    #[serde(deserialize_with = "null_as_nan")]
    pub rel: f64,
}

/// A formulation's run: its record, samples and monitors.
#[derive(Clone, Debug)]
pub struct Run {
    pub kind: FormulationKind,
    pub record: Record,
    pub solution: Solution,
    pub invariants: Invariants,
}

/// Why a comparison failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CompareError {
    #[error("{method}: {source}")]
    Setup { method: String, source: SetupError },
    #[error("{method}: {source}")]
    Run { method: String, source: RunError },
    #[error("{method}: monitor failed: {source}")]
    Monitor { method: String, source: Failure },
    #[error("run settings: {0}")]
    Grid(#[from] seam::GridError),
    #[error("model `{model}` has no reference run: its file has no `{section}` section (add `{section}: {example}` to run it)")]
    NoReference { model: String, section: &'static str, example: &'static str },
}

/// A run: the initial state, the parameters and the output times. [`Reference::of`] reads the
/// model file's `initial` and `simulation` sections and its parameter values; the command line
/// changes them (`--q`, `--qdot`, `--param`, `--t-end`, `--dt-out`).
#[derive(Clone, Debug, PartialEq)]
pub struct Reference {
    pub q0: Vec<f64>,
    pub qd0: Vec<f64>,
    pub params: Vec<f64>,
    pub t_start: f64,
    pub t_end: f64,
    pub dt_out: f64,
}

impl Reference {
    /// The reference run of `model`, or [`CompareError::NoReference`] naming the missing section.
    ///
    /// ```
    /// let model = generated::find("cart_pendulum").unwrap();
    /// let r = runtime::compare::Reference::of(&model).unwrap();
    /// assert_eq!((r.t_end, r.dt_out), (50.0, 0.01));
    /// let bare = seam::Model { initial: None, ..model };
    /// assert!(runtime::compare::Reference::of(&bare).unwrap_err().to_string().contains("`initial`"));
    /// ```
    pub fn of(model: &Model) -> Result<Reference, CompareError> {
        let missing = |section, example| CompareError::NoReference { model: model.module.to_string(), section, example };
        let (q0, qd0) = model.initial.clone().ok_or_else(|| missing("initial", "Initial(q: [...], qdot: [...])"))?;
        let (t_start, t_end, dt_out) = model.run.ok_or_else(|| missing("simulation", "Simulation(t_end: 10.0, dt_out: 0.01)"))?;
        let reference = Reference { q0, qd0, params: model.default_params.clone(), t_start, t_end, dt_out };
        reference.check()?;
        Ok(reference)
    }

    /// Why the settings are not a run, if they are not (without building the output times).
    pub fn check(&self) -> Result<(), seam::GridError> {
        seam::output_steps(self.t_start, self.t_end, self.dt_out).map(|_| ())
    }

    /// The output times `t_start, t_start + dt_out, ..., t_end` ([`seam::output_times`]), or
    /// why the settings are not a run.
    pub fn times(&self) -> Result<Vec<f64>, seam::GridError> {
        seam::output_times(self.t_start, self.t_end, self.dt_out)
    }
}

/// Runs one formulation of the model's reference run.
pub fn run(model: &Model, kind: FormulationKind, settings: &Settings, repeats: usize) -> Result<Run, CompareError> {
    run_with(model, &Reference::of(model)?, kind, settings, repeats, Drift::None)
}

/// Runs one formulation of `reference` with drift control.
pub fn run_with(model: &Model, reference: &Reference, kind: FormulationKind, settings: &Settings, repeats: usize, drift: Drift) -> Result<Run, CompareError> {
    let method = kind.name();
    let setup = |source| CompareError::Setup { method: method.into(), source };
    let (sys, y0) = System::start(model, kind, reference.params.clone(), &reference.q0, &reference.qd0).map_err(setup)?;
    let sys = sys.with_drift(drift).map_err(setup)?;
    let settings = &Settings { time_independent: !sys.form.depends_on_time, ..*settings };
    let label = match drift {
        Drift::None => method.to_string(),
        Drift::Baumgarte { .. } => format!("{method}+baumgarte"),
        Drift::Projection => format!("{method}+projection"),
    };
    let times = reference.times()?;
    let mut elapsed = Vec::new();
    let mut solution = None;
    for _ in 0..repeats.max(1) {
        let start = Instant::now();
        // The model's events, when it has any: resets applied, the run stopped where one says.
        let run = crate::events::run(&sys, &y0, &times, settings, &mut |_| {}).map_err(|source| CompareError::Run { method: method.into(), source })?;
        elapsed.push(start.elapsed().as_secs_f64());
        solution = Some(run);
    }
    elapsed.sort_by(f64::total_cmp);
    let crate::events::EventRun { solution, jumps } = solution.expect("at least one run");
    let invariants = monitor_with_jumps(&sys, &solution, &jumps).map_err(|source| CompareError::Monitor { method: method.into(), source })?;
    let energy = norm(&invariants.energy_error);
    let momentum = invariants.momentum_error.iter().map(|s| norm(s).powi(2)).fold(0.0, |a, b| a + b).sqrt();
    let g0 = norm(&invariants.momentum0);
    let record = Record {
        scene: model.module.to_string(),
        method: label,
        integrator: settings.method.to_string(),
        states: sys.form.states(),
        equations: sys.form.equations,
        seconds: elapsed[elapsed.len() / 2],
        energy_column: model.energy_balance.column().to_string(),
        energy_balance: model.energy_balance.describe().to_string(),
        energy_error_norm: energy,
        // Undefined (shown `-`) for a motion whose energy is zero, such as a robot at rest.
        energy_error_rel: if invariants.energy0 != 0.0 { energy / invariants.energy0.abs() } else { f64::NAN },
        constraint_error_norm: norm(&invariants.velocity_constraint),
        position_constraint_error_norm: norm(&invariants.position_constraint),
        momentum_error_norm: momentum,
        momentum_error_rel: if g0 > 0.0 { momentum / g0 } else { f64::NAN },
        momenta: model
            .ignorable
            .iter()
            .zip(invariants.momentum_error.iter().zip(&invariants.momentum0))
            .map(|(&j, (series, g))| {
                let n = norm(series);
                MomentumError { coordinate: model.coordinates[j].to_string(), norm: n, rel: if *g != 0.0 { n / g.abs() } else { f64::NAN } }
            })
            .collect(),
        steps: solution.stats.steps,
        rejected: solution.stats.rejected,
        rhs_calls: solution.stats.rhs_calls,
        max_condition: invariants.condition.iter().fold(0.0, |a, b| a.max(*b)),
        min_singular_margin: invariants.singular_margin.iter().fold(f64::INFINITY, |a, b| a.min(*b)),
        stiff_at: solution.stats.stiff_at,
    };
    Ok(Run { kind, record, solution, invariants })
}

/// Runs every requested formulation of `model`.
pub fn compare(model: &Model, options: &Options) -> Result<Vec<Run>, CompareError> {
    let reference = match &options.reference {
        Some(r) => r.clone(),
        None => Reference::of(model)?,
    };
    reference.check()?;
    model
        .formulations
        .iter()
        .filter(|f| options.formulations.is_empty() || options.formulations.contains(&f.kind))
        .map(|f| {
            let drift = match options.drift {
                Drift::Baumgarte { .. } if f.has_baumgarte => options.drift,
                Drift::Projection if f.layout.holds_every_rate(model.coordinates.len()) => options.drift,
                _ => Drift::None,
            };
            run_with(model, &reference, f.kind, &options.settings, options.repeats, drift)
        })
        .collect()
}

/// The runs as a Markdown table shaped like the paper's ([`table_of`] their records).
pub fn table(runs: &[Run]) -> String {
    table_of(&runs.iter().map(|r| r.record.clone()).collect::<Vec<_>>())
}

/// Records as a Markdown table shaped like the paper's: one column pair (absolute, relative)
/// per ignorable momentum, as the paper's "momentum err (X)".
pub fn table_of(records: &[Record]) -> String {
    let names: Vec<&str> = records.first().map(|r| r.momenta.iter().map(|m| m.coordinate.as_str()).collect()).unwrap_or_default();
    let momentum_header: String = names.iter().map(|n| format!(" momentum err ({n}) | (rel) |")).collect();
    let momentum_rule = "---|---|".repeat(names.len());
    let energy = records.first().map_or("energy err", |r| r.energy_column.as_str());
    let mut out = format!(
        "| method | states | equations | time s | {energy} | (rel) | constraint err |{momentum_header} steps | rhs calls | max cond |\n|---|---|---|---|---|---|---|{momentum_rule}---|---|---|\n",
    );
    for r in records {
        let constraint = if r.position_constraint_error_norm > 0.0 {
            format!("{:.2e} (pos {:.2e})", r.constraint_error_norm, r.position_constraint_error_norm)
        } else {
            format!("{:.2e}", r.constraint_error_norm)
        };
        let fmt = |x: f64| if x.is_nan() { "-".to_string() } else { format!("{x:.2e}") };
        let momentum: String = r.momenta.iter().map(|m| format!(" {} | {} |", fmt(m.norm), fmt(m.rel))).collect();
        out += &format!(
            "| {} | {} | {} | {:.2e} | {:.2e} | {} | {} |{} {} | {} | {:.1e} |\n",
            r.method,
            r.states,
            r.equations,
            r.seconds,
            r.energy_error_norm,
            fmt(r.energy_error_rel),
            constraint,
            momentum,
            r.steps,
            r.rhs_calls,
            r.max_condition
        );
    }
    out
}
