//! `multibody`: equations of motion of multibody systems, derived symbolically, run at once.
//!
//! One tool, installed with `cargo install --path .`: `generate` (a model's Rust module),
//! `inspect` (what is derived), and, on any model file, in any folder, with no cargo or rustc
//! at run time (the model is evaluated in-process): `simulate` (a trajectory), `compare` (the
//! four formulations side by side), `sweep` (work against precision), `linearize` (A, B,
//! eigenvalues). The libraries do the work: `generator` derives and evaluates, `runtime`
//! integrates and measures; this crate is their command line.

mod args;
mod commands;
mod plot;
mod report;
mod simulate;
mod watch;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// The symbolic core allocates many small nodes and maps (see the generator's binary).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Derives the equations of motion of a multibody model (a RON file) symbolically and runs
/// them: in-process, in any folder, with no Rust toolchain needed at run time.
#[derive(Parser, Debug)]
#[command(name = "multibody", version)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// The most expression nodes a derivation may build (default 1000000, about 1 KB of memory
    /// each): a larger model stops with an error naming the budget, never by running out of
    /// memory.
    #[arg(long, global = true, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    max_nodes: Option<u64>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Writes a model's equations of motion as a Rust module (to stdout, or to -o PATH).
    Generate(generator::command::GenerateArgs),
    /// Shows what is derived: T, M, N, Q, the constraints, Definition 1 per coordinate, and
    /// the reduced method's W_NI, X_NI, M_NI, L_NI.
    Inspect {
        /// A model file (RON or URDF) or the name of a built-in model.
        model: std::path::PathBuf,
        /// Print LaTeX instead of text.
        #[arg(long)]
        latex: bool,
        #[command(flatten)]
        robot: generator::command::RobotArgs,
    },
    /// Integrates one formulation and writes the trajectory (CSV and JSON) and its plots.
    Simulate(simulate::SimulateArgs),
    /// Every formulation under the same integrator settings, as a table shaped like the
    /// paper's Tables 2, 3 and 6.
    Compare(commands::CompareArgs),
    /// The work-precision sweep: every formulation under DOPRI5 and DOP853 over a range of
    /// tolerances and RK4 over a range of steps (CSV, JSON, SVG).
    Sweep(commands::SweepArgs),
    /// The linear model x' = A x (+ B u) of a formulation about an operating point, its
    /// eigenvalues, or their sweep over a parameter or a rate.
    Linearize(commands::LinearizeArgs),
    /// The live loop: runs the model as `simulate` does on every save of its file, and serves
    /// the motion on 127.0.0.1 to a page that refreshes in place (errors shown, located).
    Watch(watch::WatchArgs),
}

/// Why a command failed: the user's model (rendered with its excerpt), the run, or a file.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    #[error(transparent)]
    Model(#[from] generator::model::ModelError),
    #[error(transparent)]
    Load(load::LoadError),
    #[error("model `{model}` has no `simulation` section: give the run with --t-end and --dt-out")]
    NoRun { model: String },
    #[error("run settings: {0}")]
    Grid(seam::GridError),
    #[error(transparent)]
    Compare(#[from] runtime::compare::CompareError),
    #[error(transparent)]
    Setup(#[from] runtime::system::SetupError),
    #[error(transparent)]
    Run(#[from] runtime::integrate::RunError),
    #[error("monitoring the run failed: {0}")]
    Monitor(seam::Failure),
    #[error(transparent)]
    Linearize(#[from] runtime::linearize::LinearizeError),
    #[error(transparent)]
    File(#[from] files::FileError),
    #[error(transparent)]
    Plot(#[from] plot::PlotError),
    #[error("the animation: {0}")]
    Animate(#[from] animate::AnimateError),
    #[error("no {what} `{name}` ({})", known_or_none(.known))]
    UnknownName { what: &'static str, name: String, known: String },
    #[error("model `{model}` has no formulation `{kind}` (it has: {available})")]
    UnknownFormulation { model: String, kind: seam::FormulationKind, available: String },
    #[error("cannot write to stdout: {0}")]
    Stdout(std::io::Error),
    #[error("cannot write the CSV: {0}")]
    Csv(#[from] csv::Error),
    #[error("with {given} (given on the command line): {source}")]
    Given { given: String, source: runtime::system::SetupError },
    #[error("{file}:{line}: {message} (an input's time series is two columns `t,value` with increasing times)")]
    Series { file: String, line: usize, message: String },
    #[error(
        "`watch` follows a model file, and `{given}` is none: give the path of a RON or URDF file (the built-in models are the files of the repository's `models/` folder)"
    )]
    WatchNeedsFile { given: String },
    #[error(transparent)]
    RobotOptions(#[from] generator::model::OptionsNotRead),
    #[error("cannot serve the page on 127.0.0.1:{port}: {reason} (give another --port, or none for one the system picks)")]
    Serve { port: u16, reason: String },
}

/// The names a model knows, for an unknown one: "known: a, b", or that it has none (a model
/// with no inputs, asked for one).
fn known_or_none(known: &str) -> String {
    if known.is_empty() { "the model has none".to_string() } else { format!("known: {known}") }
}

fn main() -> ExitCode {
    use std::io::IsTerminal;
    let cli = Cli::parse();
    generator::symbolic::budget_for_command_line(cli.max_nodes);
    let result = match cli.command {
        Command::Generate(args) => return generator::command::exit(generator::command::generate(args)),
        Command::Inspect { model, latex, robot } => {
            match robot.options_for(std::path::Path::new(&model)).map_err(CliError::from).and_then(|o| Ok(load::model_with(&model, &o)?)) {
                Ok(model) => return generator::command::exit(generator::command::print_inspection(&model, latex)),
                Err(e) => Err(e),
            }
        }
        Command::Simulate(args) => simulate::simulate(&args),
        Command::Compare(args) => commands::compare(&args),
        Command::Sweep(args) => commands::sweep(&args),
        Command::Linearize(args) => commands::linearize(&args),
        Command::Watch(args) => watch::watch(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{}", describe(&e, std::io::stderr().is_terminal()));
            ExitCode::FAILURE
        }
    }
}

/// The error as the user reads it: a model's with its located excerpt (in colour on a
/// terminal), any other as one line.
pub fn describe(e: &CliError, color: bool) -> String {
    match e {
        CliError::Model(e) | CliError::Load(load::LoadError::Model(e)) => e.render(color),
        CliError::Animate(animate::AnimateError::Mesh(e)) => e.render(color),
        e => format!("error: {e}"),
    }
}

impl From<load::LoadError> for CliError {
    fn from(e: load::LoadError) -> CliError {
        CliError::Load(e)
    }
}

/// The model MODEL names with `--param` applied, its names on the command line checked
/// (`--q`, `--qdot`, and the `more` a command takes) and the span of the `run` a command makes
/// (none for `linearize`) before anything is derived, then
/// evaluated by [`load::evaluate`] on `route`; its warnings and the compiled route's one-time
/// build are told on stderr.
pub fn evaluated(
    argument: &std::path::Path,
    values: &args::ValueArgs,
    more: &args::Names,
    run: Option<&args::RunArgs>,
    exact: load::Jacobians,
    route: load::Route,
    only: &dyn Fn(&generator::model::Model) -> Option<seam::FormulationKind>,
) -> Result<(seam::Model, generator::model::Model), CliError> {
    let model = load::model_with(argument, &values.robot.options_for(std::path::Path::new(argument))?)?.with_parameters(&values.param)?;
    args::check_names(&model, values, more)?;
    if let Some(run) = run {
        run.check_span(&model)?;
    }
    let loaded = load::evaluate_only(&model, only(&model), exact, route, &mut |path| {
        eprintln!("compiling the model with rustc into {} (once per model and version)...", files::printable_path(path));
    })?;
    for line in &loaded.warnings {
        eprintln!("warning: {line}");
    }
    Ok((loaded.model, model))
}

/// Writes to stdout; a closed pipe (`multibody compare m | head`) ends the program quietly.
pub fn print(text: &str) -> Result<(), CliError> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => std::process::exit(0),
        other => other.map_err(CliError::Stdout),
    }
}
