//! The generator's command line: generate a model's Rust module, or `inspect` what is derived.

use clap::{Args, Parser, Subcommand, ValueEnum};
use generator::emit::{self, Formulation, Options, Parameters};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The symbolic core allocates many small nodes and maps: mimalloc cut scene 2's load, derive
/// and emit by 15 % against the system allocator (`cargo bench -p generator --bench scaling`).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Derives a multibody model's equations of motion symbolically and writes them as a Rust module
/// (to stdout, or to the file given with -o); a summary of sizes, operation counts and timings
/// goes to stderr.
#[derive(Parser, Debug)]
#[command(name = "generator", version, args_conflicts_with_subcommands = true)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    generate: GenerateArgs,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Shows what is derived from a model: T, M, N, Q, the constraints, Definition 1 per
    /// coordinate, and the reduced method's W_NI, X_NI, M_NI, L_NI.
    Inspect {
        /// The model file (RON).
        model: PathBuf,
        /// Print LaTeX instead of text.
        #[arg(long)]
        latex: bool,
    },
}

/// A formulation, as named on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum FormulationArg {
    Lagrange,
    Maggi,
    Kane,
    #[value(alias = "reduced", alias = "reduced_volterra")]
    ReducedVolterra,
}

impl From<FormulationArg> for Formulation {
    fn from(f: FormulationArg) -> Formulation {
        match f {
            FormulationArg::Lagrange => Formulation::Lagrange,
            FormulationArg::Maggi => Formulation::Maggi,
            FormulationArg::Kane => Formulation::Kane,
            FormulationArg::ReducedVolterra => Formulation::ReducedVolterra,
        }
    }
}

#[derive(Args, Debug)]
struct GenerateArgs {
    /// The model file (RON).
    model: Option<PathBuf>,
    /// Write the module to this file (atomically: a temporary file renamed over it) instead of
    /// stdout.
    #[arg(short, long, value_name = "PATH")]
    output: Option<PathBuf>,
    /// Allow an output path that ends in `.ron` or is the model itself.
    #[arg(long)]
    force: bool,
    /// The formulations to emit (overrides the model's `emit` section).
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    formulations: Option<Vec<FormulationArg>>,
    /// Fold the parameters into the code as constants.
    #[arg(long, conflicts_with = "runtime_params")]
    baked: bool,
    /// Keep the parameters as fields of `Params`.
    #[arg(long)]
    runtime_params: bool,
    /// Leave the ignorable coordinates out of the reduced method's state.
    #[arg(long)]
    drop_ignorable: bool,
    /// Emit each formulation's exact `jacobian` (the right-hand side and its derivative by the
    /// state) for the stiff integrator and linearization.
    #[arg(long)]
    jacobian: bool,
    /// Emit each formulation's `parameter_jacobian`, the right-hand side's derivative by the
    /// runtime parameters.
    #[arg(long)]
    parameter_jacobian: bool,
    /// Split functions with more than N common subexpressions into helpers.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    max_lets: Option<u64>,
    /// The seam crate's path in the emitted code: `::seam`, or a re-export such as
    /// `runtime::seam` for a crate that depends on the runtime only.
    #[arg(long, value_name = "PATH", default_value = emit::DEFAULT_SEAM_PATH)]
    seam_path: String,
    /// The name the module reports as `model().module` (default: the model's name).
    #[arg(long, value_name = "NAME")]
    module_name: Option<String>,
    /// Print no summary to stderr.
    #[arg(short, long)]
    quiet: bool,
}

/// Why the command failed: a model error (rendered with its excerpt) or another message.
enum Failure {
    Model(generator::model::ModelError),
    Message(String),
}

impl From<String> for Failure {
    fn from(m: String) -> Failure {
        Failure::Message(m)
    }
}

impl From<generator::model::ModelError> for Failure {
    fn from(e: generator::model::ModelError) -> Failure {
        Failure::Model(e)
    }
}

fn main() -> ExitCode {
    use std::io::IsTerminal;
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Model(e)) => {
            // Colour only on a terminal; a labelled excerpt of the file either way.
            eprintln!("{}", e.render(std::io::stderr().is_terminal()));
            ExitCode::FAILURE
        }
        Err(Failure::Message(msg)) => {
            eprintln!("{msg}");
            ExitCode::FAILURE
        }
    }
}

/// Writes to stdout; a closed pipe (`generator m.ron | head -1`) ends the program quietly.
fn print_stdout(text: &str) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => std::process::exit(0),
        other => other.map_err(|e| Failure::Message(format!("error: cannot write to stdout: {e}"))),
    }
}

fn run(cli: Cli) -> Result<(), Failure> {
    if let Some(Command::Inspect { model, latex }) = cli.command {
        let model = generator::model::load(&model)?;
        let text = generator::inspect::inspect(&model, latex)?;
        return print_stdout(&text);
    }
    let args = cli.generate;
    let Some(file) = args.model else {
        return Err(Failure::Message("error: a model file is needed: `generator MODEL.ron [-o PATH]` (see --help)".into()));
    };
    if let Some(out) = &args.output {
        refuse_overwriting_a_model(&file, out, args.force)?;
    }
    let model = generator::model::load(&file)?;
    let mut options = Options::from_model(&model);
    if let Some(list) = &args.formulations {
        let mut f: Vec<Formulation> = list.iter().map(|x| (*x).into()).collect();
        f.sort();
        f.dedup();
        options.formulations = f;
    }
    if args.baked {
        options.parameters = Parameters::Baked;
    }
    if args.runtime_params {
        options.parameters = Parameters::Runtime;
    }
    if args.drop_ignorable {
        options.integrate_ignorable = false;
    }
    if args.jacobian {
        options.jacobian = true;
    }
    if args.parameter_jacobian {
        options.parameter_jacobian = true;
    }
    if let Some(n) = args.max_lets {
        options.max_lets_per_function = n as usize;
    }
    options.seam_path = args.seam_path.clone();
    options.module_name = args.module_name.clone();
    let out = emit::generate(&model, &options)?;
    match &args.output {
        // An unchanged file is left alone, so builds that depend on it stay fresh.
        Some(path) => {
            let written = files::write_if_changed(path, out.code.as_bytes()).map_err(|e| Failure::Message(format!("error: {e}")))?;
            if !args.quiet {
                let verb = match written {
                    files::Written::Unchanged => "unchanged",
                    files::Written::Replaced => "wrote",
                    files::Written::Through => "wrote through",
                };
                eprintln!("{verb} {}", path.display());
            }
        }
        None => print_stdout(&out.code)?,
    }
    if !args.quiet {
        eprintln!("{}", out.summary);
    }
    Ok(())
}

/// Refuses to write Rust over the model itself, or over any `.ron` file, unless `force`.
fn refuse_overwriting_a_model(input: &Path, output: &Path, force: bool) -> Result<(), String> {
    if force {
        return Ok(());
    }
    let same = match (std::fs::canonicalize(input), std::fs::canonicalize(output)) {
        (Ok(a), Ok(b)) => a == b,
        _ => input == output,
    };
    if same {
        return Err(format!(
            "error: the output `{}` is the model file itself: writing Rust there would destroy the model\n  help: give another path with -o (or --force if you mean it)",
            output.display()
        ));
    }
    if output.extension().is_some_and(|e| e.eq_ignore_ascii_case("ron")) {
        return Err(format!(
            "error: the output `{}` is a `.ron` file: the generator writes Rust, and this would replace a model\n  help: write to a `.rs` path (or pass --force if you mean it)",
            output.display()
        ));
    }
    Ok(())
}
