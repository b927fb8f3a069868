//! The generator's commands, shared by the `generator` binary and the `multibody` tool:
//! `generate` (a model's Rust module) and `inspect` (what is derived).
//!
//! ```
//! use clap::Parser;
//! #[derive(Parser)]
//! struct Cli {
//!     #[command(flatten)]
//!     generate: generator::command::GenerateArgs,
//! }
//! let cli = Cli::try_parse_from(["generator", "m.ron", "--formulations", "kane,reduced"]).unwrap();
//! assert_eq!(cli.generate.formulations.unwrap().len(), 2);
//! ```

use crate::emit::{self, Formulation, Options, Parameters};
use crate::overwrite::{Overwrite, overwrites_a_model};
use clap::{Args, ValueEnum};
use std::io::Write;
use std::path::{Path, PathBuf};

/// A formulation on the command line: the seam's [`seam::FormulationKind`], whose names and
/// aliases are the only spelling of them (every command of both tools takes this one type).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FormulationArg(pub seam::FormulationKind);

impl ValueEnum for FormulationArg {
    fn value_variants<'a>() -> &'a [Self] {
        use seam::FormulationKind as K;
        &[FormulationArg(K::Lagrange), FormulationArg(K::Maggi), FormulationArg(K::Kane), FormulationArg(K::ReducedVolterra)]
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.0.name()).aliases(self.0.aliases()))
    }
}

impl From<FormulationArg> for Formulation {
    fn from(f: FormulationArg) -> Formulation {
        Formulation::of(f.0)
    }
}

/// How a URDF robot is read: `--base`, `--gravity`, `--limits` (refused for a model that is
/// not a URDF file, which would not read them: [`RobotArgs::options_for`]).
#[derive(Args, Debug, Clone, PartialEq, Default)]
pub struct RobotArgs {
    /// A URDF robot's base: fixed to the world (default), or floating (three translations and a
    /// unit quaternion).
    #[arg(long, value_enum, value_name = "BASE")]
    pub base: Option<BaseArg>,
    /// A URDF robot's gravity, `X,Y,Z` in world components (default `0,0,-9.81`; `0,0,0` for a
    /// robot in space).
    #[arg(long, value_name = "X,Y,Z", value_parser = gravity, allow_hyphen_values = true)]
    pub gravity: Option<[f64; 3]>,
    /// What a URDF robot's joint limits become: reported only (default), recorded events, or
    /// events that stop the run.
    #[arg(long, value_enum, value_name = "WHAT")]
    pub limits: Option<LimitsArg>,
}

/// A URDF robot's base on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BaseArg {
    Fixed,
    Floating,
}

/// What a URDF robot's limits become, on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum LimitsArg {
    Report,
    Record,
    Stop,
}

fn gravity(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<f64> = s.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|_| format!("needs `X,Y,Z`, not `{s}`"))?;
    match parts[..] {
        [x, y, z] if parts.iter().all(|v| v.is_finite()) => Ok([x, y, z]),
        _ => Err(format!("needs three finite numbers `X,Y,Z`, not `{s}`")),
    }
}

impl RobotArgs {
    /// [`RobotArgs::options`] for the model `argument` (a path or a built-in name): refused
    /// where they were given for a model that is not a URDF file (they were silently ignored).
    pub fn options_for(&self, argument: &Path) -> Result<crate::model::urdf::UrdfOptions, crate::model::OptionsNotRead> {
        let given = [(self.base.is_some(), "--base"), (self.gravity.is_some(), "--gravity"), (self.limits.is_some(), "--limits")];
        crate::model::refuse_options_unless_urdf(argument, given.into_iter().filter(|(on, _)| *on).map(|(_, name)| name).collect())?;
        Ok(self.options())
    }

    /// The URDF options these arguments ask for.
    pub fn options(&self) -> crate::model::urdf::UrdfOptions {
        use crate::model::urdf::{Base, LimitAction, UrdfOptions};
        let d = UrdfOptions::default();
        UrdfOptions {
            base: match self.base {
                Some(BaseArg::Floating) => Base::Floating,
                Some(BaseArg::Fixed) => Base::Fixed,
                None => d.base,
            },
            gravity: self.gravity.unwrap_or(d.gravity),
            limits: match self.limits {
                Some(LimitsArg::Record) => LimitAction::Record,
                Some(LimitsArg::Stop) => LimitAction::Stop,
                Some(LimitsArg::Report) => LimitAction::Report,
                None => d.limits,
            },
        }
    }
}

#[derive(Args, Debug)]
pub struct GenerateArgs {
    /// The model: a RON file, a URDF robot, or the name of a built-in model (`three_body`, ...).
    pub model: Option<PathBuf>,
    #[command(flatten)]
    pub robot: RobotArgs,
    /// Write the module to this file (atomically: a temporary file renamed over it) instead of
    /// stdout.
    #[arg(short, long, value_name = "PATH")]
    pub output: Option<PathBuf>,
    /// Allow an output path that ends in `.ron` or is the model itself.
    #[arg(long)]
    pub force: bool,
    /// The formulations to emit (overrides the model's `emit` section).
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub formulations: Option<Vec<FormulationArg>>,
    /// Fold the parameters into the code as constants.
    #[arg(long, conflicts_with = "runtime_params")]
    pub baked: bool,
    /// Keep the parameters as fields of `Params`.
    #[arg(long)]
    pub runtime_params: bool,
    /// Leave the ignorable coordinates out of the reduced method's state.
    #[arg(long)]
    pub drop_ignorable: bool,
    /// Emit each formulation's exact `jacobian` (the right-hand side and its derivative by the
    /// state) for the stiff integrator and linearization.
    #[arg(long)]
    pub jacobian: bool,
    /// Emit each formulation's `parameter_jacobian`, the right-hand side's derivative by the
    /// runtime parameters.
    #[arg(long)]
    pub parameter_jacobian: bool,
    /// Emit fused multiply-adds (`f64::mul_add`) in the function bodies and the unrolled solves: build the module with
    /// `-C target-cpu=native` or `-C target-feature=+fma` where the CPU has them.
    #[arg(long)]
    pub fma: bool,
    /// Split functions with more than N common subexpressions into helpers.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub max_lets: Option<u64>,
    /// The seam crate's path in the emitted code: `::seam`, or a re-export such as
    /// `runtime::seam` for a crate that depends on the runtime only.
    #[arg(long, value_name = "PATH", default_value = emit::DEFAULT_SEAM_PATH)]
    pub seam_path: String,
    /// The name the module reports as `model().module` (default: the model's name).
    #[arg(long, value_name = "NAME")]
    pub module_name: Option<String>,
    /// Print no summary to stderr.
    #[arg(short, long)]
    pub quiet: bool,
}

/// The exit of a command: its error on stderr (a model error with its labelled excerpt, in
/// colour only on a terminal) and a non-zero code, or success.
pub fn exit(result: Result<(), Failure>) -> std::process::ExitCode {
    use std::io::IsTerminal;
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(Failure::Model(e)) => {
            eprintln!("{}", e.render(std::io::stderr().is_terminal()));
            std::process::ExitCode::FAILURE
        }
        Err(Failure::Message(m)) => {
            eprintln!("{m}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// Why the command failed: a model error (rendered with its excerpt) or another message.
pub enum Failure {
    Model(crate::model::ModelError),
    Message(String),
}

impl From<String> for Failure {
    fn from(m: String) -> Failure {
        Failure::Message(m)
    }
}

impl From<crate::model::ModelError> for Failure {
    fn from(e: crate::model::ModelError) -> Failure {
        Failure::Model(e)
    }
}

/// Writes to stdout; a closed pipe (`generator m.ron | head -1`) ends the program quietly.
pub fn print_stdout(text: &str) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => std::process::exit(0),
        other => other.map_err(|e| Failure::Message(format!("error: cannot write to stdout: {e}"))),
    }
}

/// `inspect MODEL [--latex]`: what is derived, printed.
pub fn inspect(model: &Path, latex: bool) -> Result<(), Failure> {
    print_inspection(&crate::model::source(model)?.model()?, latex)
}

/// What is derived from a loaded model, printed (text, or LaTeX with `latex`).
pub fn print_inspection(model: &crate::model::Model, latex: bool) -> Result<(), Failure> {
    let text = crate::pipeline::inspect(model, latex)?;
    print_stdout(&text)
}

/// Generates the module `args` ask for: to the output file (atomically, left alone when it
/// already holds the bytes) or to stdout, with the summary on stderr.
pub fn generate(args: GenerateArgs) -> Result<(), Failure> {
    let Some(file) = args.model else {
        return Err(Failure::Message("error: a model file is needed: `generator MODEL.ron [-o PATH]` (see --help)".into()));
    };
    if let Some(out) = &args.output {
        refuse_overwriting_a_model(&file, out, args.force)?;
    }
    // An option of the command line: said before the model is read, and named as given.
    crate::emit::parse_seam_path(&args.seam_path)
        .map_err(|message| Failure::Message(format!("error: --seam-path: {message}\n  help: {}", crate::emit::SEAM_PATH_HELP)))?;
    let robot = args.robot.options_for(&file).map_err(|e| Failure::Message(format!("error: {e}")))?;
    let model = crate::model::source_with(&file, &robot)?.model()?;
    if let Some(out) = &args.output {
        // The model read, the output may not be it (by any path), whatever `--force` says.
        files::check_output(out).map_err(|e| Failure::Message(format!("error: {e}")))?;
    }
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
    options.fma = args.fma;
    if let Some(n) = args.max_lets {
        options.max_lets_per_function = n as usize;
    }
    options.seam_path = args.seam_path.clone();
    options.module_name = args.module_name.clone();
    let out = crate::pipeline::generate(&model, &options)?;
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
                eprintln!("{verb} {}", files::printable_path(path));
            }
        }
        None => print_stdout(&out.code)?,
    }
    if !args.quiet {
        eprintln!("{}", out.summary);
    } else {
        for line in out.summary.warnings() {
            eprintln!("warning: {line}");
        }
    }
    Ok(())
}

/// Refuses to write Rust over the model itself (whatever `force` says), or over any `.ron`
/// file unless `force`.
fn refuse_overwriting_a_model(input: &Path, output: &Path, force: bool) -> Result<(), String> {
    match overwrites_a_model(input, output).filter(|o| !force || *o == Overwrite::ModelItself) {
        None => Ok(()),
        Some(Overwrite::ModelItself) => Err(format!(
            "error: the output `{}` is the model file itself: writing Rust there would destroy the model\n  help: give another path with -o",
            files::printable_path(output)
        )),
        Some(Overwrite::RonFile) => Err(format!(
            "error: the output `{}` is a `.ron` file: the generator writes Rust, and this would replace a model\n  help: write to a `.rs` path (or pass --force if you mean it)",
            files::printable_path(output)
        )),
    }
}
