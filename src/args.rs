//! What the commands share on the command line: the formulation and integrator names, and the
//! run (`--param`, `--q`, `--qdot`, `--t-end`, `--dt-out`, `--method`, `--rtol`, `--atol`,
//! `--paper`), turned into the runtime's [`Reference`] and [`Settings`].

use crate::CliError;
use clap::{Args, ValueEnum};
use runtime::compare::Reference;
use runtime::integrate::{Method, Settings};
use seam::{FormulationKind, Model};

pub use generator::command::FormulationArg;

/// An integrator, as named on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// Dormand-Prince 5(4) (MATLAB's ode45, the paper's).
    Dopri5,
    /// Dormand-Prince 8(5,3).
    Dop853,
    /// Classical Runge-Kutta with a fixed step (`--h`).
    Rk4,
    /// Rosenbrock 2(3) (`ode23s`) for stiff models.
    Ros23,
}

impl MethodArg {
    /// The adaptive integrator it names (`None` for RK4, which needs its step), by the
    /// runtime's own names ([`Method::from_name`]).
    pub fn adaptive(self) -> Option<Method> {
        Method::from_name(self.to_possible_value().expect("no variant is skipped").get_name(), None)
    }
}

impl ValueArgs {
    /// An initial state the model refuses: located in the model file's `initial` section when
    /// its own values are at fault, or naming the values given on the command line.
    pub fn locate(&self, e: runtime::system::SetupError, source: &generator::model::Model) -> CliError {
        use runtime::system::SetupError;
        let given: Vec<String> = self.q.iter().map(|(n, v)| format!("--q {n}={v}")).chain(self.qdot.iter().map(|(n, v)| format!("--qdot {n}={v}"))).collect();
        let place = match &e {
            SetupError::Violated { position: true, .. } => "initial.q",
            SetupError::Violated { position: false, .. } | SetupError::NotFinite { .. } => "initial.qdot",
            _ => return CliError::Setup(e),
        };
        if !given.is_empty() {
            return CliError::Given { given: given.join(" "), source: e };
        }
        let message = e.to_string();
        let (what, fix) = message.split_once("): ").map(|(a, b)| (format!("{a})"), b.to_string())).unwrap_or((message, String::new()));
        CliError::Model(source.error(generator::model::ErrorKind::InitialState, place, place.rsplit('.').next().unwrap_or(place), what, fix))
    }
}

/// Values that change the model's own (its parameters, its coordinates and rates), and how it
/// is run.
#[derive(Args, Debug, Clone, PartialEq, Default)]
pub struct ValueArgs {
    /// Runs the model's arithmetic as code built by rustc (needs rustc on PATH the first time;
    /// cached by content in the user's cache folder, `MULTIBODY_CACHE_DIR` to choose another)
    /// instead of the built-in JIT: the same numbers, faster per call on large models.
    #[arg(long)]
    pub compiled: bool,
    /// A parameter's value, `NAME=VALUE` (repeatable); checked as the model file's values are.
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = assignment, allow_hyphen_values = true)]
    pub param: Vec<(String, f64)>,
    /// A coordinate's value, `NAME=VALUE` (repeatable).
    #[arg(long = "q", value_name = "NAME=VALUE", value_parser = assignment, allow_hyphen_values = true)]
    pub q: Vec<(String, f64)>,
    /// A coordinate's rate, `NAME=VALUE` (repeatable).
    #[arg(long = "qdot", value_name = "NAME=VALUE", value_parser = assignment, allow_hyphen_values = true)]
    pub qdot: Vec<(String, f64)>,
    #[command(flatten)]
    pub robot: generator::command::RobotArgs,
}

/// The run: its initial state, parameters, times and integrator.
#[derive(Args, Debug, Clone, PartialEq, Default)]
pub struct RunArgs {
    #[command(flatten)]
    pub values: ValueArgs,
    /// The end of the run (default: the model file's `simulation.t_end`).
    #[arg(long, value_parser = finite, allow_hyphen_values = true)]
    pub t_end: Option<f64>,
    /// The output interval (default: the model file's `simulation.dt_out`).
    #[arg(long, value_parser = positive, allow_hyphen_values = true)]
    pub dt_out: Option<f64>,
    /// The integrator (default: DOP853 at rtol = atol = 1e-10; the paper's DOPRI5 at rtol
    /// 1e-3, atol 1e-6 with `--paper` or for a model whose file asks for it).
    #[arg(long, value_enum)]
    pub method: Option<MethodArg>,
    /// Relative tolerance (adaptive methods): below 1.
    #[arg(long, value_parser = rtol, allow_hyphen_values = true)]
    pub rtol: Option<f64>,
    /// Absolute tolerance (adaptive methods): at most 1e10.
    #[arg(long, value_parser = atol, allow_hyphen_values = true)]
    pub atol: Option<f64>,
    /// The step of `--method rk4`.
    #[arg(long, value_parser = positive, allow_hyphen_values = true, required_if_eq("method", "rk4"))]
    pub h: Option<f64>,
    /// The largest step (default: a tenth of the run).
    #[arg(long, value_parser = positive, allow_hyphen_values = true)]
    pub h_max: Option<f64>,
    /// The paper's settings: DOPRI5, rtol 1e-3, atol 1e-6, h_max a tenth of the run.
    #[arg(long)]
    pub paper: bool,
}

fn assignment(s: &str) -> Result<(String, f64), String> {
    let (name, value) = s.split_once('=').ok_or_else(|| format!("needs `NAME=VALUE`, not `{s}`"))?;
    let v: f64 = value.trim().parse().map_err(|_| format!("`{value}` is not a number (in `{s}`)"))?;
    if !v.is_finite() {
        return Err(format!("`{value}` is not finite (in `{s}`)"));
    }
    Ok((name.trim().to_string(), v))
}

pub fn positive(s: &str) -> Result<f64, String> {
    s.parse::<f64>().ok().filter(|x| x.is_finite() && *x > 0.0).ok_or_else(|| format!("needs a positive number, not `{s}`"))
}

fn rtol(s: &str) -> Result<f64, String> {
    let x: f64 = s.parse().map_err(|_| format!("needs a number, not `{s}`"))?;
    Settings::check_tolerances(x, 1e-10).map(|()| x)
}

fn atol(s: &str) -> Result<f64, String> {
    let x: f64 = s.parse().map_err(|_| format!("needs a number, not `{s}`"))?;
    Settings::check_tolerances(1e-10, x).map(|()| x)
}

fn finite(s: &str) -> Result<f64, String> {
    s.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| format!("needs a finite number, not `{s}`"))
}

/// The position of `name` among `names` (a model's coordinates or parameters).
pub fn index_of(names: &[String], name: &str, what: &'static str) -> Result<usize, CliError> {
    names.iter().position(|n| n == name).ok_or_else(|| CliError::UnknownName { what, name: name.to_string(), known: names.join(", ") })
}

/// Names a command takes beyond `--param`, `--q` and `--qdot`: parameters as inputs, a swept
/// parameter or rate.
#[derive(Clone, Copy, Debug, Default)]
pub struct Names<'a> {
    pub inputs: &'a [String],
    pub sweep: Option<&'a str>,
}

/// Every name given on the command line is the model's: coordinates for `--q` and `--qdot`,
/// parameters for `--input`, a parameter or a coordinate's rate (`x'`) for `--sweep`. Checked
/// on the parsed model, before anything is derived (a misspelling costs nothing).
pub fn check_names(model: &generator::model::Model, values: &ValueArgs, more: &Names) -> Result<(), CliError> {
    let coordinates: Vec<String> = model.coordinates.iter().map(|c| c.name().to_string()).collect();
    let parameters: Vec<String> = model.parameters.iter().map(|(p, _)| p.name().to_string()).collect();
    for (name, _) in values.q.iter().chain(&values.qdot) {
        index_of(&coordinates, name, "coordinate")?;
    }
    for name in more.inputs {
        index_of(&parameters, name, "parameter")?;
    }
    if let Some(name) = more.sweep {
        let rate = name.strip_suffix('\'').filter(|c| coordinates.iter().any(|k| k == c));
        if rate.is_none() && !parameters.iter().any(|p| p == name) {
            let known = parameters.iter().cloned().chain(coordinates.iter().map(|c| format!("{c}'"))).collect::<Vec<_>>().join(", ");
            return Err(CliError::UnknownName { what: "parameter or rate to sweep", name: name.to_string(), known });
        }
    }
    Ok(())
}

impl RunArgs {
    /// The model's reference run with `--q`, `--qdot`, `--t-end` and `--dt-out` applied (the
    /// model was loaded with `--param`); a model without an `initial`
    /// section starts at rest at zero, one without `simulation` needs `--t-end` and `--dt-out`.
    ///
    /// The initial state is checked against the constraints here, before any run: a violation
    /// of the model file's own values is located in its `initial` section; one of values given
    /// with `--q`/`--qdot` names them.
    pub fn reference(&self, model: &Model, source: &generator::model::Model) -> Result<Reference, CliError> {
        let m = model.coordinates.len();
        let (mut q0, mut qd0) = model.initial.clone().unwrap_or((vec![0.0; m], vec![0.0; m]));
        // `--param` is applied to the model itself (`load::evaluated`), validated as its file's
        // values are: here the model's values are the run's.
        let params = model.default_params.clone();
        for (name, v) in &self.values.q {
            q0[index_of(&model.coordinates, name, "coordinate")?] = *v;
        }
        for (name, v) in &self.values.qdot {
            qd0[index_of(&model.coordinates, name, "coordinate")?] = *v;
        }
        let (t_start, t_end, dt_out) = self.span(&model.module, model.run)?;
        let reference = Reference { q0, qd0, params, t_start, t_end, dt_out };
        if let Err(e) = runtime::system::System::start(model, model.default_kind(), reference.params.clone(), &reference.q0, &reference.qd0) {
            return Err(self.values.locate(e, source));
        }
        Ok(reference)
    }

    /// The run's `(t_start, t_end, dt_out)`: the model's `simulation` (`run`) with `--t-end` and
    /// `--dt-out` over it, refused when there is none or it makes no output times. The
    /// commands that run check it on the model as loaded, before anything is derived.
    pub fn span(&self, model: &str, run: Option<(f64, f64, f64)>) -> Result<(f64, f64, f64), CliError> {
        let span = match (run, self.t_end, self.dt_out) {
            (Some((a, b, c)), t_end, dt_out) => (a, t_end.unwrap_or(b), dt_out.unwrap_or(c)),
            (None, Some(b), Some(c)) => (0.0, b, c),
            (None, _, _) => return Err(CliError::NoRun { model: model.to_string() }),
        };
        seam::output_steps(span.0, span.1, span.2).map_err(CliError::Grid)?;
        Ok(span)
    }

    /// [`RunArgs::span`] of a model as loaded, before it is derived.
    pub fn check_span(&self, source: &generator::model::Model) -> Result<(), CliError> {
        self.span(&source.name, source.simulation.as_ref().map(|s| (s.t_start, s.t_end, s.dt_out))).map(|_| ())
    }

    /// The Jacobians a run with these settings wants: exact ones for the stiff method.
    pub fn jacobians(&self) -> load::Jacobians {
        if self.method == Some(MethodArg::Ros23) { load::Jacobians::Exact { only: None, by_parameters: false } } else { load::Jacobians::Differenced }
    }

    /// True when the run uses the paper's settings (`--paper`, or the model file asks).
    pub fn paper(&self, model: &Model) -> bool {
        self.paper || model.paper_settings
    }

    /// The integrator settings for a run of `span` seconds.
    pub fn settings(&self, model: &Model, span: f64) -> Settings {
        let mut s = if self.paper(model) { Settings::paper(span) } else { Settings::tight(span) };
        if let Some(m) = self.method {
            s.method = m.adaptive().unwrap_or(Method::Rk4 { h: self.h.unwrap_or(0.01 * span) });
        }
        if let Some(x) = self.rtol {
            s.rtol = x;
        }
        if let Some(x) = self.atol {
            s.atol = x;
        }
        if let Some(x) = self.h_max {
            s.h_max = x;
        }
        s
    }
}

/// The settings in one line, for every table and file header.
pub fn describe(s: &Settings) -> String {
    match s.method {
        Method::Rk4 { h } => format!("RK4, h {}", step(h)),
        m => format!("{m}, rtol {:e}, atol {:e}, h_max {}", s.rtol, s.atol, step(s.h_max)),
    }
}

/// A step size as a person reads it: to 12 significant digits, so that one derived by a
/// product (a tenth of a 0.1-s run, 0.010000000000000002) reads as the setting it is (0.01).
fn step(h: f64) -> String {
    seam::short(format!("{h:.11e}").parse().unwrap_or(h))
}

/// The requested formulations, checked against what the model has.
pub fn formulations(model: &Model, list: &[FormulationArg]) -> Result<Vec<FormulationKind>, CliError> {
    list.iter()
        .map(|f| {
            model.formulation(f.0).map(|_| f.0).ok_or_else(|| CliError::UnknownFormulation {
                model: model.module.clone(),
                kind: f.0,
                available: model.kinds().iter().map(|k| k.name()).collect::<Vec<_>>().join(", "),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The command line's method names are the runtime's, and each names its method.
    #[test]
    fn method_names_are_the_runtimes() {
        let names: Vec<String> = MethodArg::value_variants().iter().map(|m| m.to_possible_value().unwrap().get_name().to_string()).collect();
        let mut sorted = names.clone();
        sorted.sort();
        let mut runtime_names = Method::NAMES.to_vec();
        runtime_names.sort();
        assert_eq!(sorted, runtime_names);
        assert_eq!(MethodArg::Dopri5.adaptive(), Some(Method::Dopri5));
        assert_eq!(MethodArg::Dop853.adaptive(), Some(Method::Dop853));
        assert_eq!(MethodArg::Ros23.adaptive(), Some(Method::Rosenbrock23));
        assert_eq!(MethodArg::Rk4.adaptive(), None);
    }

    /// A step derived by a product reads as its setting; one with more digits keeps twelve.
    #[test]
    fn steps_read_as_their_settings() {
        // A tenth of a 0.1-s run, as the paper's settings take it.
        let tenth = Settings { h_max: 0.1 * 0.1, ..Settings::default() };
        assert_ne!(0.1 * 0.1, 0.01);
        assert!(describe(&tenth).ends_with("h_max 0.01"), "{}", describe(&tenth));
        assert_eq!(step(0.4), "0.4");
        assert_eq!(step(1.0 / 3.0), "3.33333333333e-1");
        assert_eq!(step(1e-300), "1e-300");
    }
}
