//! `simulate`: one formulation of a model, integrated, and its trajectory written: `t`, `q`,
//! `q'`, the formulation's state, the energy and its error, the momenta of the ignorable
//! coordinates and the constraint residuals, as CSV (the `csv` crate) and JSON (with the
//! settings used), and plots of `q(t)` and of the invariants' errors.

use crate::args::{FormulationArg, RunArgs, describe, formulations};
use crate::{CliError, plot, print};
use clap::Args;
use files::write_creating_folder as write_file;
use runtime::system::System;
use runtime::trajectory;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args, Debug, Clone, PartialEq)]
pub struct SimulateArgs {
    /// A model file (`path/to/my_model.ron`) or the name of a built-in model.
    pub model: std::path::PathBuf,
    /// The formulation (default: the reduced Volterra method where the model has it).
    #[arg(long, value_enum)]
    pub formulation: Option<FormulationArg>,
    #[command(flatten)]
    pub run: RunArgs,
    /// An input's time series, `NAME=FILE.csv` (repeatable): two columns `t,value`, interpolated
    /// linearly and held at the ends; an input without one keeps its nominal value.
    #[arg(long = "input", value_name = "NAME=FILE.csv", value_parser = input_file)]
    pub input: Vec<(String, PathBuf)>,
    /// The directory the trajectory and plots are written to:
    /// `<model>_<formulation>.{csv,json}`, `<model>_<formulation>_{coordinates,invariants}.svg`.
    #[arg(long, value_name = "DIR", default_value = ".")]
    pub out: PathBuf,
    /// Also writes a self-contained HTML page that plays the motion in 3-D (each body as its
    /// equivalent inertia box, frames as axes, a time slider; no network needed to view it).
    #[arg(long, value_name = "OUT.html")]
    pub animate: Option<PathBuf>,
}

fn input_file(s: &str) -> Result<(String, PathBuf), String> {
    let (name, file) = s.split_once('=').ok_or_else(|| format!("needs `NAME=FILE.csv`, not `{s}`"))?;
    Ok((name.trim().to_string(), PathBuf::from(file)))
}

/// The control law of `--input`: each named input follows its file's time series, the others
/// keep their nominal values; `None` without `--input`.
fn series_controller(model: &seam::Model, given: &[(String, PathBuf)]) -> Result<Option<runtime::inputs::Controller>, CliError> {
    use runtime::inputs::TimeSeries;
    if given.is_empty() {
        return Ok(None);
    }
    let names: Vec<String> = model.inputs.iter().map(|&i| model.parameter_names[i].clone()).collect();
    let mut series: Vec<TimeSeries> =
        model.inputs.iter().map(|&i| TimeSeries::new(vec![0.0], vec![model.default_params[i]]).expect("a finite nominal value")).collect();
    for (name, file) in given {
        let k = crate::args::index_of(&names, name, "input")?;
        let bytes = files::read_bounded(file, 64 << 20)?;
        let text = String::from_utf8_lossy(&bytes);
        series[k] = TimeSeries::parse(&text).map_err(|e| CliError::Series { file: files::printable_path(file), line: e.line, message: e.message })?;
    }
    Ok(Some(runtime::inputs::Controller::series(series)))
}

pub fn simulate(args: &SimulateArgs) -> Result<(), CliError> {
    match run(args)? {
        Some(e) => Err(CliError::Run(e)),
        None => Ok(()),
    }
}

/// [`simulate`], its outputs written, with the error that stopped the run early if one did
/// (what came before it is written).
pub fn run(args: &SimulateArgs) -> Result<Option<runtime::integrate::RunError>, CliError> {
    // One formulation runs: only it is derived, emitted and compiled (where the model emits it;
    // one it leaves out is refused below, naming those it has).
    let asked = args.formulation.map(|f| f.0);
    let only = |m: &generator::model::Model| match asked {
        None => Some(load::default_formulation(m)),
        Some(kind) => generator::emit::Options::from_model(m).formulations.iter().any(|f| f.kind() == kind).then_some(kind),
    };
    let (model, source) = crate::evaluated(
        &args.model,
        &args.run.values,
        &Default::default(),
        Some(&args.run),
        args.run.jacobians(),
        load::Route::of(args.run.values.compiled),
        &only,
    )?;
    let kind = match args.formulation {
        Some(f) => formulations(&model, &[f])?[0],
        None => model.default_kind(),
    };
    let reference = args.run.reference(&model, &source)?;
    let settings = args.run.settings(&model, reference.t_end - reference.t_start);
    let (mut sys, y0) = System::start(&model, kind, reference.params.clone(), &reference.q0, &reference.qd0)?;
    if let Some(controller) = series_controller(&model, &args.input)? {
        sys = sys.with_controller(controller);
    }
    // Every output is checked before the run: none may be a file the run reads (the model,
    // an input series), whatever its name says.
    let base = args.out.join(format!("{}_{}", model.module, kind.name()));
    for path in [base.with_extension("csv"), base.with_extension("json")].iter().chain(&args.animate) {
        files::check_output(path)?;
    }
    // A page that cannot be drawn (a mesh file missing) is refused before the run, not after.
    if let Some(e) = args.animate.as_ref().and(source.undrawable()) {
        return Err(animate::AnimateError::Mesh(Box::new(e.clone())).into());
    }
    let times = reference.times().map_err(CliError::Grid)?;
    let span = reference.t_end - reference.t_start;
    let bar = crate::report::progress_bar(1000);
    bar.set_message(format!("{} {kind}", model.module));
    let start = Instant::now();
    let mut calls = 0u64;
    let mut progress = |t: f64| {
        calls += 1;
        if calls.is_multiple_of(1024) {
            bar.set_position((1000.0 * (t - reference.t_start) / span) as u64);
        }
    };
    let run = trajectory::simulate(&sys, &y0, &times, &settings, &mut progress);
    bar.finish_and_clear();
    // A run that stops early keeps its trajectory up to the stop: it is written, then the
    // error is reported.
    let (run, failed) = match run {
        Ok(run) => (run, None),
        Err(trajectory::TrajectoryError::Run(e)) => match trajectory::up_to(&sys, &y0, &times, &settings, &e) {
            Some(kept) => (kept, Some(e)),
            None => return Err(CliError::Run(e)),
        },
        Err(trajectory::TrajectoryError::Monitor(e)) => return Err(CliError::Monitor(e)),
    };
    let elapsed = start.elapsed();
    let (solution, inv, header, rows) = (&run.solution, &run.invariants, &run.columns, &run.rows);
    if let Some(t) = solution.stats.stiff_at {
        eprintln!("{}", crate::report::stiff_warning(kind.name(), t));
    }
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(header)?;
    for row in rows {
        w.write_record(row.iter().map(|x| format!("{x:e}")))?;
    }
    let text = w.into_inner().map_err(|e| CliError::Csv(e.into_error().into()))?;
    write_file(&base.with_extension("csv"), &text)?;
    let json = serde_json::json!({
        "model": model.module,
        "formulation": kind.name(),
        "settings": describe(&settings),
        "evaluation": "in-process",
        "t_start": reference.t_start,
        "t_end": reference.t_end,
        "dt_out": reference.dt_out,
        "params": model.parameter_names.iter().zip(&reference.params).map(|(n, v)| (n.clone(), serde_json::Value::from(*v))).collect::<serde_json::Map<String, serde_json::Value>>(),
        "steps": solution.stats.steps,
        "rejected": solution.stats.rejected,
        "rhs_calls": solution.stats.rhs_calls,
        // DOPRI5's or DOP853's stiffness test (the warning on stderr): when, or null.
        "stiff_at": solution.stats.stiff_at,
        "stopped_by_event": solution.stopped,
        "stopped_by_error": failed.as_ref().map(|e| e.to_string()),
        "events": run.events.iter().map(|e| serde_json::json!({ "event": e.name, "action": e.action.name(), "t": e.t, "q": e.q, "qdot": e.qdot })).collect::<Vec<_>>(),
        // The model file's units of its coordinates and parameters (`units`), for what reads the file.
        "units": source.def.units,
        "columns": header,
        "rows": rows,
    });
    write_file(&base.with_extension("json"), serde_json::to_string(&json).expect("plain data").as_bytes())?;
    let plots = plot::write_trajectory(&model, &source, &sys.form, &solution.times, inv, &base)?;
    let end = match (solution.stopped, solution.events.last(), &failed) {
        (_, _, Some(e)) => format!(
            "{} (the last output before the run stopped at t = {}: see the error below)",
            seam::short(*solution.times.last().expect("kept outputs")),
            seam::short(e.t)
        ),
        (true, Some(o), None) => format!("{} (stopped there by event `{}`)", seam::short(o.t), model.events[o.event].name),
        _ => seam::short(reference.t_end),
    };
    let mut text = format!(
        "{} {kind}: {} outputs from t = {} to {} ({}), {} steps, {} right-hand sides, {:.3} s\n",
        model.module,
        solution.times.len(),
        seam::short(reference.t_start),
        end,
        describe(&settings),
        solution.stats.steps,
        solution.stats.rhs_calls,
        elapsed.as_secs_f64()
    );
    let worst = |s: &[f64]| s.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    text += &format!(
        "  max |{} error| {:.3e} ({}(0) = {:.6e})\n",
        model.energy_balance.quantity(),
        worst(&inv.energy_error),
        model.energy_balance.quantity(),
        inv.energy0
    );
    for (k, &j) in model.ignorable.iter().enumerate() {
        text += &format!("  max |momentum error ({})| {:.3e}\n", model.coordinates[j], worst(&inv.momentum_error[k]));
    }
    if !model.constraints.is_empty() {
        text += &format!("  max constraint residual {:.3e}\n", worst(&inv.velocity_constraint));
    }
    if !model.events.is_empty() {
        text += &format!("  {} events{}\n", run.events.len(), if solution.stopped { " (the last stopped the run)" } else { "" });
        for e in run.events.iter().take(20) {
            let coords: Vec<String> = model.coordinates.iter().zip(&e.q).map(|(c, v)| format!("{c} = {v:.6e}")).collect();
            text += &format!("    t = {:.12e}  {} ({})  {}\n", e.t, e.name, e.action.name(), coords.join(", "));
        }
        if run.events.len() > 20 {
            text += &format!("    ... {} more in the JSON file\n", run.events.len() - 20);
        }
    }
    text += &format!("  wrote {0}.csv, {0}.json", files::printable_path(&base));
    if let Some(page) = &args.animate {
        let source =
            load::model_with(&args.model, &args.run.values.robot.options_for(std::path::Path::new(&args.model))?)?.with_parameters(&args.run.values.param)?;
        let q: Vec<f64> = inv.coordinates.concat();
        animate::write(page, &source, &reference.params, &animate::Motion { formulation: kind.name(), times: &solution.times, q: &q })?;
        text += &format!(", {}", files::printable_path(page));
    }
    for p in &plots {
        text += &format!(", {}", files::printable_path(p));
    }
    print(&(text + "\n"))?;
    Ok(failed)
}
