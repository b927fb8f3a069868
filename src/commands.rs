//! `compare`, `sweep` and `linearize`: the runtime's functions on a model evaluated in-process,
//! with their tables, files and plots.

use crate::args::{FormulationArg, MethodArg, RunArgs, ValueArgs, describe, formulations, index_of};
use crate::{CliError, plot, print};
use clap::Args;
use files::write_creating_folder as write_file;
use runtime::compare::{Options, compare as compare_runs, table};
use runtime::linearize::{Motion, Operating, Swept, crossings, grows, growth, linearize as linearize_at};
use runtime::sweep::{SweepOptions, csv as sweep_csv, sweep as sweep_runs};
use runtime::system::Drift;
use seam::FormulationKind;
use std::io::Write;
use std::path::PathBuf;

#[derive(Args, Debug, Clone, PartialEq)]
pub struct CompareArgs {
    /// A model file (`path/to/my_model.ron`) or the name of a built-in model (cart_pendulum,
    /// three_body, satellite_boom, ...).
    pub model: PathBuf,
    #[command(flatten)]
    pub run: RunArgs,
    /// The time of a run is the median of N runs (wall clock, one thread).
    #[arg(long, value_name = "N", default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub repeats: u32,
    /// A comma-separated subset of the formulations (default: all the model has).
    #[arg(long, value_enum, value_delimiter = ',', value_name = "LIST")]
    pub formulations: Vec<FormulationArg>,
    /// Baumgarte stabilization of Lagrange.
    #[arg(long, value_name = "ALPHA,BETA", value_parser = pair, allow_hyphen_values = true, conflicts_with = "projection")]
    pub baumgarte: Option<(f64, f64)>,
    /// Project Lagrange and Maggi onto the constraints after every step.
    #[arg(long)]
    pub projection: bool,
    /// Also write the records as JSON, atomically; `-` writes them to stdout, alone (the table
    /// then goes to stderr).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Also write SVG plots of the coordinates and errors into DIR.
    #[arg(long, value_name = "DIR")]
    pub plots: Option<PathBuf>,
    /// Also write the self-contained page of the motion with every formulation's run over the
    /// default one's (each in a colour of its own, dashed): at loose tolerances, see them part.
    #[arg(long, value_name = "OUT.html")]
    pub animate: Option<PathBuf>,
}

#[derive(Args, Debug, Clone, PartialEq)]
pub struct SweepArgs {
    /// A model file or the name of a built-in model.
    pub model: PathBuf,
    #[command(flatten)]
    pub run: RunArgs,
    /// The directory the results are written to.
    #[arg(long, value_name = "DIR", default_value = ".")]
    pub out: PathBuf,
    /// The time of a run is the median of N runs (wall clock, one thread).
    #[arg(long, value_name = "N", default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub repeats: u32,
    /// Three tolerances and three RK4 steps instead of ten and seven.
    #[arg(long)]
    pub quick: bool,
    /// A comma-separated subset of the formulations (default: all the model has).
    #[arg(long, value_enum, value_delimiter = ',', value_name = "LIST")]
    pub formulations: Vec<FormulationArg>,
    /// The integrators to sweep (add ros23 for a stiff model).
    #[arg(long, value_enum, value_delimiter = ',', value_name = "LIST", default_value = "dopri5,dop853,rk4")]
    pub methods: Vec<MethodArg>,
}

#[derive(Args, Debug, Clone, PartialEq)]
pub struct LinearizeArgs {
    /// A model file or the name of a built-in model.
    pub model: PathBuf,
    /// The formulation whose state is linearized.
    #[arg(long, value_enum, default_value = "kane")]
    pub formulation: FormulationArg,
    /// The operating point: the model's initial state with these values. With velocity
    /// constraints, the rates not given (nor swept) are solved from them.
    #[command(flatten)]
    pub values: ValueArgs,
    /// A parameter to treat as an input `u` (repeatable): prints `B` of `x' = A x + B u`.
    #[arg(long = "input", value_name = "NAME")]
    pub input: Vec<String>,
    /// Sweep a parameter (`k`) or a coordinate's rate (`x'`) from `--from` to `--to`.
    #[arg(long, value_name = "NAME", requires_all = ["from", "to"])]
    pub sweep: Option<String>,
    #[arg(long, allow_hyphen_values = true, requires = "sweep")]
    pub from: Option<f64>,
    #[arg(long, allow_hyphen_values = true, requires = "sweep")]
    pub to: Option<f64>,
    /// Number of values in the sweep.
    #[arg(long, default_value_t = 101, value_parser = clap::value_parser!(u32).range(2..=100_000))]
    pub steps: u32,
    /// The directory a sweep's results are written to.
    #[arg(long, value_name = "DIR", default_value = ".")]
    pub out: PathBuf,
}

fn pair(s: &str) -> Result<(f64, f64), String> {
    let parts: Vec<f64> = s.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|_| format!("needs `alpha,beta`, not `{s}`"))?;
    match parts[..] {
        [a, b] if a.is_finite() && b.is_finite() && a >= 0.0 && b >= 0.0 => Ok((a, b)),
        _ => Err(format!("needs two non-negative numbers `alpha,beta`, not `{s}`")),
    }
}

/// `compare`: runs the formulations, prints the table, writes the JSON and plots asked for.
pub fn compare(args: &CompareArgs) -> Result<(), CliError> {
    let route = load::Route::of(args.run.values.compiled);
    let (model, source) = crate::evaluated(&args.model, &args.run.values, &Default::default(), Some(&args.run), args.run.jacobians(), route, &|_| None)?;
    let reference = args.run.reference(&model, &source)?;
    let settings = args.run.settings(&model, reference.t_end - reference.t_start);
    let mut options = Options { settings, repeats: args.repeats as usize, reference: Some(reference), ..Options::paper(&model) };
    options.formulations = formulations(&model, &args.formulations)?;
    if let Some((alpha, beta)) = args.baumgarte {
        options.drift = Drift::Baumgarte { alpha, beta };
    }
    if args.projection {
        options.drift = Drift::Projection;
    }
    let runs = compare_runs(&model, &options)?;
    let header = format!(
        "{}: {}, {} outputs, time the median of {} runs (wall clock, {})\n\n",
        model.module,
        describe(&options.settings),
        runs.first().map_or(0, |r| r.solution.times.len()),
        options.repeats,
        route.describe()
    );
    let json_to_stdout = args.json.as_deref().is_some_and(|p| p.as_os_str() == "-");
    // Before anything is written: no output may go over a file the run reads.
    for path in args.json.as_deref().filter(|_| !json_to_stdout).into_iter().chain(args.animate.as_deref()) {
        files::check_output(path)?;
    }
    if json_to_stdout {
        // stdout carries the JSON alone, so that it can be piped; the table goes to stderr.
        eprint!("{header}{}", table(&runs));
    } else {
        print(&(header + &table(&runs)))?;
    }
    for r in runs.iter().filter_map(|r| r.record.stiff_at.map(|t| (r, t))) {
        eprintln!("{}", crate::report::stiff_warning(&r.0.record.method, r.1));
    }
    if let Some(path) = &args.json {
        let records: Vec<_> = runs.iter().map(|r| &r.record).collect();
        let text = serde_json::to_string_pretty(&records).expect("records serialize");
        if json_to_stdout {
            print(&(text + "\n"))?;
        } else {
            write_file(path, text.as_bytes())?;
        }
    }
    if let Some(dir) = &args.plots {
        for p in plot::write_plots(&model, &source, &runs, dir)? {
            eprintln!("wrote {}", files::printable_path(&p));
        }
    }
    if let Some(page) = &args.animate {
        // The default formulation's run drawn as the bodies, the others over it.
        let mut ordered: Vec<&runtime::compare::Run> = runs.iter().collect();
        ordered.sort_by_key(|r| r.kind != model.default_kind());
        let q: Vec<Vec<f64>> = ordered.iter().map(|r| r.invariants.coordinates.concat()).collect();
        let motions: Vec<animate::Motion> =
            ordered.iter().zip(&q).map(|(r, q)| animate::Motion { formulation: r.kind.name(), times: &r.solution.times, q }).collect();
        let params = options.reference.as_ref().map_or_else(|| model.default_params.clone(), |r| r.params.clone());
        animate::write_overlaid(page, &source, &params, &motions)?;
        eprintln!("wrote {}", files::printable_path(page));
    }
    Ok(())
}

/// `sweep`: runs the sweep with progress on stderr and writes its CSV, JSON and diagram.
pub fn sweep(args: &SweepArgs) -> Result<(), CliError> {
    let stiff = args.methods.contains(&MethodArg::Ros23) || args.run.method == Some(MethodArg::Ros23);
    let jacobians = if stiff { load::Jacobians::Exact { only: None, by_parameters: false } } else { load::Jacobians::Differenced };
    let (model, source) =
        crate::evaluated(&args.model, &args.run.values, &Default::default(), Some(&args.run), jacobians, load::Route::of(args.run.values.compiled), &|_| None)?;
    let reference = args.run.reference(&model, &source)?;
    let mut options = SweepOptions {
        repeats: args.repeats as usize,
        formulations: formulations(&model, &args.formulations)?,
        reference: Some(reference),
        ..SweepOptions::default()
    };
    options.adaptive =
        [MethodArg::Dopri5, MethodArg::Dop853, MethodArg::Ros23].into_iter().filter(|a| args.methods.contains(a)).filter_map(MethodArg::adaptive).collect();
    // Events are located on a method's dense output, which RK4 has not: RK4 is left out of a
    // model with events, and the note says so (its runs would all be refused at the start).
    let mut notes = Vec::new();
    if !model.events.is_empty() && args.methods.contains(&MethodArg::Rk4) {
        notes.push("RK4 left out: the model has events, which are located on the integrator's dense output, and RK4 has none".to_string());
    }
    if !args.methods.contains(&MethodArg::Rk4) || !model.events.is_empty() {
        options.rk4_steps.clear();
    }
    if args.quick {
        options.tolerances = vec![1e-3, 1e-6, 1e-9];
        if !options.rk4_steps.is_empty() {
            options.rk4_steps = vec![1.0, 0.1, 0.01];
        }
    }
    let bar = crate::report::progress_bar(0);
    let points = sweep_runs(&model, &options, &mut |done, total, label| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
        bar.set_message(label.to_string());
    })?;
    bar.finish_and_clear();
    let base = args.out.join(format!("{}_work_precision", model.module));
    write_file(&base.with_extension("csv"), sweep_csv(&points).as_bytes())?;
    write_file(&base.with_extension("json"), serde_json::to_string_pretty(&points).expect("points serialize").as_bytes())?;
    plot::write_work_precision(&points, &base.with_extension("svg"))?;
    let failed = points.iter().filter(|p| p.failure.is_some()).count();
    let mut text = format!("{} runs ({failed} stopped early), written to {}.{{csv,json,svg}}\n", points.len(), files::printable_path(&base));
    for note in notes {
        text += &format!("  note: {note}\n");
    }
    print(&text)
}

/// The operating point `args` describe: the model's initial state and parameters with the
/// overrides applied.
fn operating_point(model: &seam::Model, args: &LinearizeArgs) -> Result<Operating, CliError> {
    let m = model.coordinates.len();
    let (mut q, mut qdot) = model.initial.clone().unwrap_or((vec![0.0; m], vec![0.0; m]));
    let mut params = model.default_params.clone();
    for (name, v) in &args.values.q {
        q[index_of(&model.coordinates, name, "coordinate")?] = *v;
    }
    let mut held = Vec::new();
    for (name, v) in &args.values.qdot {
        let j = index_of(&model.coordinates, name, "coordinate")?;
        qdot[j] = *v;
        held.push(j);
    }
    for (name, v) in &args.values.param {
        params[index_of(&model.parameter_names, name, "parameter")?] = *v;
    }
    Ok(Operating { q, qdot, params, held })
}

/// What the eigenvalues at the operating point mean: an equilibrium's say nothing more; at a
/// steady motion only cyclic entries move; elsewhere `A` holds for an instant.
fn describe_motion(lin: &runtime::linearize::Linear, states: &[String]) -> String {
    let name = |i: usize| states.get(i).cloned().unwrap_or_else(|| format!("state {i}"));
    match lin.motion() {
        Motion::Equilibrium => "  an equilibrium: x' = 0 there\n".to_string(),
        Motion::Steady { moving } => format!(
            "  a steady motion: only cyclic entries move ({}), and nothing depends on them, so these are the eigenvalues of the motion\n",
            moving.iter().map(|&i| format!("{}' = {:e}", name(i), lin.rates[i])).collect::<Vec<_>>().join(", ")
        ),
        Motion::Transient { entry, rate } => format!(
            "  note: not an equilibrium nor a steady motion: {}' = {rate:e} there (|x'| = {:e}){}. A is the Jacobian of the flow at this instant: its eigenvalues are how fast neighbouring motions separate from this one now, not the stability of the motion (linearize at an equilibrium, or in a formulation whose state holds the motion steady: only cyclic entries moving)\n",
            name(entry),
            lin.rates.iter().map(|r| r * r).sum::<f64>().sqrt(),
            if lin.drifting.contains(&entry) { format!(", and A changes with {} near the point", name(entry)) } else { String::new() }
        ),
    }
}

/// `linearize`: the eigenvalues at the operating point, or the sweep's files.
pub fn linearize(args: &LinearizeArgs) -> Result<(), CliError> {
    // The exact Jacobians of the formulation linearized: A, and B with `--input`, to round-off.
    let names = crate::args::Names { inputs: &args.input, sweep: args.sweep.as_deref() };
    if let (Some(name), Some(from), Some(to)) = (&args.sweep, args.from, args.to) {
        // A swept parameter takes the values its file may hold (a mass stays positive): checked
        // at the ends of the range before anything is derived (the checks are on convex sets
        // of the values, so the ends decide).
        let source = load::model_with(&args.model, &args.values.robot.options_for(std::path::Path::new(&args.model))?)?.with_parameters(&args.values.param)?;
        if source.parameters.iter().any(|(p, _)| p.name() == *name) {
            for v in [from, to] {
                source.with_parameters(&[(name.clone(), v)]).map_err(|mut e| {
                    e.message = format!("the sweep of `{name}` from {from} to {to} reaches {name} = {v}, which the model refuses: {}", e.message);
                    e
                })?;
            }
        }
    }
    let (model, _) = crate::evaluated(
        &args.model,
        &args.values,
        &names,
        None,
        load::Jacobians::Exact { only: Some(args.formulation.0), by_parameters: !args.input.is_empty() },
        load::Route::of(args.values.compiled),
        // Only the formulation linearized is derived, where the model emits it.
        &|m| generator::emit::Options::from_model(m).formulations.iter().any(|f| f.kind() == args.formulation.0).then_some(args.formulation.0),
    )?;
    let kind: FormulationKind = formulations(&model, &[args.formulation])?[0];
    let at = operating_point(&model, args)?;
    let Some(name) = &args.sweep else {
        let lin = linearize_at(&model, kind, &at)?;
        let pairs: Vec<(f64, f64)> = lin.eigenvalues.iter().map(|l| (l.re, l.im)).collect();
        let states = model.formulation(kind).map(|f| f.state_names.clone()).unwrap_or_default();
        let mut text = format!(
            "{} {kind}: A is {n} x {n} ({}), {}\n",
            model.module,
            if lin.exact { "exact Jacobian" } else { "finite differences" },
            match lin.eigenvalues.len() {
                0 => "no eigenvalues but the zeros of its cyclic entries".to_string(),
                _ => format!("largest nonzero real part {:e}{}", growth(&pairs), if grows(&pairs) { "" } else { " (none above round-off)" }),
            },
            n = lin.a.nrows()
        );
        text += &describe_motion(&lin, &states);
        for l in &lin.eigenvalues {
            text += &format!("  {:+.12e} {:+.12e}i\n", l.re, l.im);
        }
        if !args.input.is_empty() {
            let inputs: Vec<usize> = args.input.iter().map(|n| index_of(&model.parameter_names, n, "parameter")).collect::<Result<_, _>>()?;
            let (b, exact) = runtime::linearize::input_matrix(&model, kind, &at, &inputs)?;
            text += &format!("B ({}), columns {}:\n", if exact { "exact" } else { "finite differences" }, args.input.join(", "));
            let names = model.formulation(kind).map(|f| f.state_names.clone()).unwrap_or_default();
            // Right-aligned to the longest name (a robot's joints' rates run long).
            let width = names.iter().map(|n| n.chars().count()).max().unwrap_or(0);
            for (r, name) in (0..b.nrows()).zip(names) {
                let row: Vec<String> = b.row(r).iter().map(|x| format!("{x:+.9e}")).collect();
                text += &format!("  {name:>width$}: {}\n", row.join(" "));
            }
        }
        return print(&text);
    };
    let swept = Swept::find(&model, name)?;
    let (a, b) = (args.from.expect("clap requires --from"), args.to.expect("clap requires --to"));
    let k = args.steps as usize;
    let values: Vec<f64> = (0..k).map(|i| a + (b - a) * i as f64 / (k - 1) as f64).collect();
    let rows = runtime::linearize::sweep(&model, kind, &at, swept, &values)?;
    let transient: Vec<f64> = rows.iter().filter(|r| r.transient).map(|r| r.value).collect();
    let cross = crossings(&model, kind, &at, swept, &rows)?;
    let base = args.out.join(format!("{}_eigenvalues", model.module));
    write_file(&base.with_extension("csv"), runtime::linearize::csv(name, &rows).as_bytes())?;
    let json = serde_json::json!({ "model": model.module, "formulation": kind.name(), "swept": name, "crossings": cross, "rows": rows });
    write_file(&base.with_extension("json"), serde_json::to_string_pretty(&json).expect("plain data").as_bytes())?;
    plot::write_eigenvalues(&format!("{} ({kind})", model.module), name, &rows, &base.with_extension("svg"))?;
    let mut text = format!("{} {kind}: {} values of {name} from {a} to {b}; written {}.{{csv,json,svg}}\n", model.module, k, files::printable_path(&base));
    for c in &cross {
        text += &format!("  the largest nonzero real part crosses zero at {name} = {c:.12}\n");
    }
    if !transient.is_empty() {
        text += &format!(
            "  note: at {} of the {k} values ({name} = {:e} to {:e}) the point is neither an equilibrium nor a steady motion in {kind}'s state: their eigenvalues hold for an instant only, and their crossings say nothing of stability (`linearize` at one of them says which entry moves)\n",
            transient.len(),
            transient[0],
            transient[transient.len() - 1]
        );
    }
    let _ = std::io::stderr().flush();
    print(&text)
}
