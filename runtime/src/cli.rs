//! The `compare` and `sweep` commands, run on a model compiled into the calling program.
//!
//! The binaries `compare` and `sweep` are drivers ([`crate::driver`]): they turn their MODEL
//! argument into a small program with that model's module compiled in, optimized, and run it;
//! [`run_compiled`] is that program's `main`. A crate with a generated module of its own calls
//! [`compare_command`] or [`sweep_command`] directly.
//!
//! ```
//! use clap::Parser;
//! let args = runtime::cli::CompareArgs::try_parse_from(["compare", "my_model.ron", "--rtol", "1e-8"]).unwrap();
//! assert_eq!((args.model.as_str(), args.rtol), ("my_model.ron", Some(1e-8)));
//! assert!(runtime::cli::CompareArgs::try_parse_from(["compare", "m.ron", "--rtol", "-1"]).is_err());
//! ```

use crate::compare::{CompareError, Options, compare, table};
use crate::integrate::Method;
use crate::linearize::{LinearizeError, Operating, Swept, crossings, growth, linearize};
use crate::plot::PlotError;
use crate::sweep::{SweepOptions, csv, sweep};
use crate::system::Drift;
use clap::{Parser, ValueEnum};
use files::{FileError, write_creating_folder as write_atomic};
use seam::Model;
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

/// Every formulation of a model under the same integrator settings, as a table shaped like the
/// paper's Tables 2, 3 and 6 (default: the paper's settings, Dormand-Prince 5(4), rtol 1e-3,
/// atol 1e-6, h_max = span / 10).
#[derive(Parser, Debug, Clone, PartialEq)]
#[command(name = "compare", version)]
pub struct CompareArgs {
    /// A model file (`path/to/my_model.ron`) or the name of one in `models/` (cart_pendulum,
    /// three_body, satellite_boom, ...).
    pub model: String,
    /// The integrator.
    #[arg(long, value_enum, default_value_t = MethodArg::Dopri5)]
    pub method: MethodArg,
    /// Relative tolerance (adaptive methods).
    #[arg(long, value_parser = positive, allow_hyphen_values = true)]
    pub rtol: Option<f64>,
    /// Absolute tolerance (adaptive methods).
    #[arg(long, value_parser = positive, allow_hyphen_values = true)]
    pub atol: Option<f64>,
    /// The step of `--method rk4`.
    #[arg(long, value_parser = positive, allow_hyphen_values = true, required_if_eq("method", "rk4"))]
    pub h: Option<f64>,
    /// The largest step.
    #[arg(long, value_parser = positive, allow_hyphen_values = true)]
    pub h_max: Option<f64>,
    /// CPU time is the median of N runs.
    #[arg(long, value_name = "N", default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub repeats: u32,
    /// A comma-separated subset of the formulations (default: all the module has).
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
}

/// The work-precision sweep of a model: every formulation under DOPRI5 and DOP853 over a range
/// of tolerances and RK4 over a range of steps, written as CSV, JSON and an SVG diagram
/// (`DIR/<model>_work_precision.{csv,json,svg}`); progress on stderr.
#[derive(Parser, Debug, Clone, PartialEq)]
#[command(name = "sweep", version)]
pub struct SweepArgs {
    /// A model file (`path/to/my_model.ron`) or the name of one in `models/`.
    pub model: String,
    /// The directory the results are written to.
    #[arg(long, value_name = "DIR", default_value = ".")]
    pub out: PathBuf,
    /// CPU time is the median of N runs.
    #[arg(long, value_name = "N", default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub repeats: u32,
    /// Three tolerances and three RK4 steps instead of ten and seven.
    #[arg(long)]
    pub quick: bool,
    /// A comma-separated subset of the formulations (default: all the module has).
    #[arg(long, value_enum, value_delimiter = ',', value_name = "LIST")]
    pub formulations: Vec<FormulationArg>,
    /// The integrators to sweep (default: dopri5,dop853,rk4; add ros23 for a stiff model).
    #[arg(long, value_enum, value_delimiter = ',', value_name = "LIST", default_value = "dopri5,dop853,rk4")]
    pub methods: Vec<MethodArg>,
}

/// The linear model `x' = A x` of a formulation about an operating point (the model's initial
/// state, with `--q`, `--qdot` and `--param` overrides), and its eigenvalues; with `--sweep`,
/// the eigenvalues over a range of one parameter or one initial rate, written as CSV, JSON
/// and an SVG plot (`DIR/<model>_eigenvalues.{csv,json,svg}`), with the values where a real
/// part crosses zero.
#[derive(Parser, Debug, Clone, PartialEq)]
#[command(name = "linearize", version)]
pub struct LinearizeArgs {
    /// A model file (`path/to/my_model.ron`) or the name of one in `models/`.
    pub model: String,
    /// The formulation whose state is linearized.
    #[arg(long, value_enum, default_value_t = FormulationArg::Kane)]
    pub formulation: FormulationArg,
    /// A coordinate's value at the operating point, `NAME=VALUE` (repeatable).
    #[arg(long = "q", value_name = "NAME=VALUE", value_parser = assignment, allow_hyphen_values = true)]
    pub q: Vec<(String, f64)>,
    /// A coordinate's rate at the operating point, `NAME=VALUE` (repeatable). With velocity
    /// constraints, the rates not given (nor swept) are solved from them.
    #[arg(long = "qdot", value_name = "NAME=VALUE", value_parser = assignment, allow_hyphen_values = true)]
    pub qdot: Vec<(String, f64)>,
    /// A parameter's value, `NAME=VALUE` (repeatable).
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = assignment, allow_hyphen_values = true)]
    pub param: Vec<(String, f64)>,
    /// A parameter to treat as an input `u` (repeatable): prints the input matrix `B` of
    /// `x' = A x + B u` beside the eigenvalues.
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

fn assignment(s: &str) -> Result<(String, f64), String> {
    let (name, value) = s.split_once('=').ok_or_else(|| format!("needs `NAME=VALUE`, not `{s}`"))?;
    let v: f64 = value.trim().parse().map_err(|_| format!("`{value}` is not a number (in `{s}`)"))?;
    if !v.is_finite() {
        return Err(format!("`{value}` is not finite (in `{s}`)"));
    }
    Ok((name.trim().to_string(), v))
}

/// The operating point `args` describe: the model's initial state and parameters with the
/// overrides applied.
pub fn operating_point(model: &Model, args: &LinearizeArgs) -> Result<Operating, CliError> {
    let m = model.coordinates.len();
    let (mut q, mut qdot) = match model.initial {
        Some((q, qd)) => (q.to_vec(), qd.to_vec()),
        None => (vec![0.0; m], vec![0.0; m]),
    };
    let mut params = model.default_params.to_vec();
    let find = index_of;
    for (name, v) in &args.q {
        q[find(model.coordinates, name, "coordinate")?] = *v;
    }
    let mut held = Vec::new();
    for (name, v) in &args.qdot {
        let j = find(model.coordinates, name, "coordinate")?;
        qdot[j] = *v;
        held.push(j);
    }
    for (name, v) in &args.param {
        params[find(model.parameter_names, name, "parameter")?] = *v;
    }
    Ok(Operating { q, qdot, params, held })
}

/// The position of `name` among `names` (a model's coordinates or parameters).
fn index_of(names: &[&str], name: &str, what: &'static str) -> Result<usize, CliError> {
    names.iter().position(|n| *n == name).ok_or_else(|| CliError::UnknownName { what, name: name.to_string(), known: names.join(", ") })
}

/// `linearize`: the eigenvalues at the operating point, or the sweep's files.
pub fn linearize_command(model: &Model, args: &LinearizeArgs) -> Result<(), CliError> {
    let form = formulations(model, &[args.formulation])?.remove(0);
    let at = operating_point(model, args)?;
    let Some(name) = &args.sweep else {
        let lin = linearize(model, &form, &at)?;
        let mut text = format!(
            "{} {form}: A is {n} x {n} ({}), largest nonzero real part {:e}\n",
            model.module,
            if lin.exact { "exact Jacobian" } else { "finite differences" },
            growth(&lin.eigenvalues.iter().map(|l| (l.re, l.im)).collect::<Vec<_>>()),
            n = lin.a.nrows()
        );
        for l in &lin.eigenvalues {
            text += &format!("  {:+.12e} {:+.12e}i\n", l.re, l.im);
        }
        if !args.input.is_empty() {
            let inputs: Vec<usize> = args.input.iter().map(|n| index_of(model.parameter_names, n, "parameter")).collect::<Result<_, _>>()?;
            let (b, exact) = crate::linearize::input_matrix(model, &form, &at, &inputs)?;
            text += &format!("B ({}), columns {}:\n", if exact { "exact" } else { "finite differences" }, args.input.join(", "));
            for (r, name) in (0..b.nrows()).zip(model.formulation(&form).map_or(&[][..], |f| f.state_names)) {
                let row: Vec<String> = b.row(r).iter().map(|x| format!("{x:+.9e}")).collect();
                text += &format!("  {name:>12}: {}\n", row.join(" "));
            }
        }
        return print(&text);
    };
    let swept = Swept::find(model, name)?;
    let (a, b) = (args.from.expect("clap requires --from"), args.to.expect("clap requires --to"));
    let k = args.steps as usize;
    let values: Vec<f64> = (0..k).map(|i| a + (b - a) * i as f64 / (k - 1) as f64).collect();
    let rows = crate::linearize::sweep(model, &form, &at, swept, &values)?;
    let cross = crossings(model, &form, &at, swept, &rows)?;
    let base = args.out.join(format!("{}_eigenvalues", model.module));
    write_atomic(&base.with_extension("csv"), crate::linearize::csv(name, &rows).as_bytes())?;
    let json = serde_json::json!({ "model": model.module, "formulation": form, "swept": name, "crossings": cross, "rows": rows });
    write_atomic(&base.with_extension("json"), serde_json::to_string_pretty(&json).expect("plain data").as_bytes())?;
    crate::plot::write_eigenvalues(&format!("{} ({form})", model.module), name, &rows, &base.with_extension("svg"))?;
    let mut text = format!("{} {form}: {} values of {name} from {a} to {b}; written {}.{{csv,json,svg}}\n", model.module, k, base.display());
    for c in &cross {
        text += &format!("  the largest nonzero real part crosses zero at {name} = {c:.12}\n");
    }
    print(&text)
}

/// An integrator, as named on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    Dopri5,
    Dop853,
    Rk4,
    /// Rosenbrock 2(3) (`ode23s`) for stiff models, with the exact Jacobian when the module
    /// has one (`generator --jacobian`), else finite differences.
    Ros23,
}

impl MethodArg {
    /// The adaptive integrator it names (`None` for RK4, which needs its step).
    pub fn adaptive(self) -> Option<Method> {
        match self {
            MethodArg::Dopri5 => Some(Method::Dopri5),
            MethodArg::Dop853 => Some(Method::Dop853),
            MethodArg::Ros23 => Some(Method::Rosenbrock23),
            MethodArg::Rk4 => None,
        }
    }
}

/// A formulation, as named on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum FormulationArg {
    Lagrange,
    Maggi,
    Kane,
    #[value(name = "reduced_volterra", alias = "reduced", alias = "reduced-volterra")]
    ReducedVolterra,
}

impl FormulationArg {
    /// The formulation's name in emitted modules.
    pub fn name(self) -> &'static str {
        match self {
            FormulationArg::Lagrange => "lagrange",
            FormulationArg::Maggi => "maggi",
            FormulationArg::Kane => "kane",
            FormulationArg::ReducedVolterra => "reduced_volterra",
        }
    }
}

fn positive(s: &str) -> Result<f64, String> {
    s.parse::<f64>().ok().filter(|x| x.is_finite() && *x > 0.0).ok_or_else(|| format!("needs a positive number, not `{s}`"))
}

fn pair(s: &str) -> Result<(f64, f64), String> {
    let parts: Vec<f64> = s.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|_| format!("needs `alpha,beta`, not `{s}`"))?;
    match parts[..] {
        [a, b] if a.is_finite() && b.is_finite() && a >= 0.0 && b >= 0.0 => Ok((a, b)),
        _ => Err(format!("needs two non-negative numbers `alpha,beta`, not `{s}`")),
    }
}

/// Why a command failed.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    #[error(transparent)]
    Compare(#[from] CompareError),
    #[error(transparent)]
    Output(#[from] FileError),
    #[error(transparent)]
    Plot(#[from] PlotError),
    #[error(transparent)]
    Linearize(#[from] LinearizeError),
    #[error("no {what} `{name}` (known: {known})")]
    UnknownName { what: &'static str, name: String, known: String },
    #[error("model `{model}` has no formulation `{name}` (it has: {available})")]
    UnknownFormulation { model: String, name: String, available: String },
    #[error("cannot write to stdout: {0}")]
    Stdout(std::io::Error),
}

/// The requested formulations, checked against what the module has.
fn formulations(model: &Model, list: &[FormulationArg]) -> Result<Vec<String>, CliError> {
    list.iter()
        .map(|f| {
            model.formulation(f.name()).map(|_| f.name().to_string()).ok_or_else(|| CliError::UnknownFormulation {
                model: model.module.to_string(),
                name: f.name().to_string(),
                available: model.formulations.iter().map(|f| f.name).collect::<Vec<_>>().join(", "),
            })
        })
        .collect()
}

/// The options `args` ask for.
pub fn compare_options(model: &Model, args: &CompareArgs) -> Result<Options, CliError> {
    let mut options = Options::paper(model);
    let s = &mut options.settings;
    // clap requires `--h` with `rk4`.
    s.method = args.method.adaptive().unwrap_or(Method::Rk4 { h: args.h.unwrap_or(s.h_max) });
    if let Some(x) = args.rtol {
        s.rtol = x;
    }
    if let Some(x) = args.atol {
        s.atol = x;
    }
    if let Some(x) = args.h_max {
        s.h_max = x;
    }
    options.repeats = args.repeats as usize;
    options.formulations = formulations(model, &args.formulations)?;
    if let Some((alpha, beta)) = args.baumgarte {
        options.drift = Drift::Baumgarte { alpha, beta };
    }
    if args.projection {
        options.drift = Drift::Projection;
    }
    Ok(options)
}

fn print(text: &str) -> Result<(), CliError> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        // A closed pipe (`compare m | head`) ends the program quietly.
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => std::process::exit(0),
        other => other.map_err(CliError::Stdout),
    }
}

/// `compare`: runs the formulations, prints the table, writes the JSON and plots asked for.
pub fn compare_command(model: &Model, args: &CompareArgs) -> Result<(), CliError> {
    let options = compare_options(model, args)?;
    let runs = compare(model, &options)?;
    let s = &options.settings;
    let header = format!(
        "{}: {}, rtol {:e}, atol {:e}, h_max {}, {} outputs, CPU time median of {}\n\n",
        model.module,
        s.method,
        s.rtol,
        s.atol,
        s.h_max,
        runs.first().map_or(0, |r| r.solution.times.len()),
        options.repeats
    );
    let json_to_stdout = args.json.as_deref().is_some_and(|p| p.as_os_str() == "-");
    if json_to_stdout {
        // stdout carries the JSON alone, so that it can be piped; the table goes to stderr.
        eprint!("{header}{}", table(&runs));
    } else {
        print(&(header + &table(&runs)))?;
    }
    if let Some(path) = &args.json {
        let records: Vec<_> = runs.iter().map(|r| &r.record).collect();
        let text = serde_json::to_string_pretty(&records).expect("records serialize");
        if json_to_stdout {
            print(&(text + "\n"))?;
        } else {
            write_atomic(path, text.as_bytes())?;
        }
    }
    if let Some(dir) = &args.plots {
        for p in crate::plot::write_plots(model, &runs, dir)? {
            eprintln!("wrote {}", p.display());
        }
    }
    Ok(())
}

/// `sweep`: runs the sweep with progress on stderr and writes its CSV, JSON and diagram.
pub fn sweep_command(model: &Model, args: &SweepArgs) -> Result<(), CliError> {
    let mut options = SweepOptions { repeats: args.repeats as usize, formulations: formulations(model, &args.formulations)?, ..SweepOptions::default() };
    options.adaptive =
        [MethodArg::Dopri5, MethodArg::Dop853, MethodArg::Ros23].into_iter().filter(|a| args.methods.contains(a)).filter_map(MethodArg::adaptive).collect();
    if !args.methods.contains(&MethodArg::Rk4) {
        options.rk4_steps.clear();
    }
    if args.quick {
        options.tolerances = vec![1e-3, 1e-6, 1e-9];
        if !options.rk4_steps.is_empty() {
            options.rk4_steps = vec![1.0, 0.1, 0.01];
        }
    }
    let mut stderr = std::io::stderr();
    let points = sweep(model, &options, &mut |done, total, label| {
        let _ = write!(stderr, "\r[{done:>3}/{total}] {label:<48}");
        let _ = stderr.flush();
    })?;
    eprintln!();
    let base = args.out.join(format!("{}_work_precision", model.module));
    write_atomic(&base.with_extension("csv"), csv(&points).as_bytes())?;
    write_atomic(&base.with_extension("json"), serde_json::to_string_pretty(&points).expect("points serialize").as_bytes())?;
    crate::plot::write_work_precision(&points, &base.with_extension("svg"))?;
    let failed = points.iter().filter(|p| p.failure.is_some()).count();
    print(&format!("{} runs ({failed} stopped early), written to {}.{{csv,json,svg}}\n", points.len(), base.display()))
}

/// The `main` of a program with `model` compiled in: its first argument names the command
/// (`compare` or `sweep`), the rest are that command's arguments.
pub fn run_compiled(model: Model) -> ExitCode {
    let mut args = std::env::args_os().skip(1);
    let command = args.next().map(|a| a.to_string_lossy().into_owned()).unwrap_or_default();
    let result = match command.as_str() {
        "compare" => compare_command(&model, &CompareArgs::parse_from(std::iter::once("compare".into()).chain(args))),
        "sweep" => sweep_command(&model, &SweepArgs::parse_from(std::iter::once("sweep".into()).chain(args))),
        "linearize" => linearize_command(&model, &LinearizeArgs::parse_from(std::iter::once("linearize".into()).chain(args))),
        other => {
            eprintln!("error: unknown command `{other}`: use `compare`, `sweep` or `linearize`");
            return ExitCode::from(2);
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
