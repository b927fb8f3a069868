//! From a MODEL argument to a model that runs: a model file anywhere, or the name of one of the
//! project's own models (built into the tool, so that `multibody compare three_body` works in
//! any folder), evaluated in-process ([`generator::eval`]: no cargo, no rustc, no checkout), or
//! with `--compiled` as its emitted module built by rustc into a library cached by content in
//! the user's cache folder (the `native` crate).

use std::path::Path;

pub use generator::model::{Source, built_in};

/// Whether an evaluated model carries its exact Jacobians (derived and differentiated once more:
/// worth it for the stiff method and `linearize` only).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Jacobians {
    /// None: the runtime differences the right-hand side where it needs one.
    Differenced,
    /// Exact, of one formulation (`Some`) or of every formulation the run uses: by the state
    /// (the stiff method, `linearize`'s `A`) and, with `by_parameters`, by the runtime
    /// parameters too (`linearize`'s input matrix `B`: nothing else reads it, and on the
    /// bicycle it alone passes the node budget).
    Exact { only: Option<seam::FormulationKind>, by_parameters: bool },
}

/// The text of the model MODEL names: a path, or the name of a built-in model
/// ([`generator::model::source`]).
///
/// ```
/// let source = load::source("three_body").unwrap();
/// assert_eq!(source.file, "models/three_body.ron");
/// assert!(load::source("no_such_model").is_err());
/// ```
pub fn source(argument: impl AsRef<std::ffi::OsStr>) -> Result<Source, LoadError> {
    Ok(generator::model::source(Path::new(argument.as_ref()))?)
}

/// [`source`], a URDF robot read with `robot`'s options ([`generator::model::source_with`]).
pub fn source_with(argument: impl AsRef<std::ffi::OsStr>, robot: &generator::model::UrdfOptions) -> Result<Source, LoadError> {
    Ok(generator::model::source_with(Path::new(argument.as_ref()), robot)?)
}

/// [`model`], a URDF robot read with `robot`'s options.
pub fn model_with(argument: impl AsRef<std::ffi::OsStr>, robot: &generator::model::UrdfOptions) -> Result<generator::model::Model, LoadError> {
    Ok(source_with(argument, robot)?.model()?)
}

/// The model MODEL names ([`source`]), loaded and validated.
pub fn model(argument: impl AsRef<std::ffi::OsStr>) -> Result<generator::model::Model, LoadError> {
    Ok(source(argument)?.model()?)
}

/// A model that runs, and what its user should be told about it.
pub struct Loaded {
    /// The model behind the seam's traits.
    pub model: seam::Model,
    /// Warnings for the user: exact Jacobians over the node budget replaced by differences,
    /// functions the JIT could not compile, the derivation's own warnings.
    pub warnings: Vec<String>,
}

/// `model` evaluated in-process (its tapes compiled to machine code by the `jit` crate) or, on
/// the compiled `route`, as its module built by rustc (`on_compile` is told the library's path
/// before a build, which happens once per model and version); `exact` asks for the exact
/// Jacobians too (by the state, and by the parameters where asked), for the stiff method and
/// `linearize`.
/// Exact Jacobians that exceed the node budget (the bicycle's Kane form) fall back to
/// differences, with a warning that says so.
///
/// ```
/// let model = load::model("cart_pendulum").unwrap();
/// let loaded = load::evaluate(&model, load::Jacobians::Differenced, load::Route::Jit, &mut |_| {}).unwrap();
/// assert_eq!(loaded.model.coordinates, ["theta1", "theta2", "x"]);
/// ```
pub fn evaluate(model: &generator::model::Model, exact: Jacobians, route: Route, on_compile: &mut dyn FnMut(&Path)) -> Result<Loaded, LoadError> {
    evaluate_only(model, None, exact, route, on_compile)
}

/// The formulation a run of `model` uses when none is named: the paper's reduced method where
/// the model emits it, else Kane's, else its first (as `seam::Model::default_kind` says of an
/// evaluated model).
///
/// ```
/// let model = load::model("cart_pendulum").unwrap();
/// assert_eq!(load::default_formulation(&model), seam::FormulationKind::ReducedVolterra);
/// ```
pub fn default_formulation(model: &generator::model::Model) -> seam::FormulationKind {
    let kinds: Vec<seam::FormulationKind> = generator::emit::Options::from_model(model).formulations.iter().map(|f| f.kind()).collect();
    seam::FormulationKind::default_among(&kinds)
}

/// [`evaluate`], deriving only the formulation `only` where given: a run of one formulation
/// (`simulate`) derives, emits and compiles a quarter of the work or less (the mechanics, which
/// every formulation shares, are derived once either way).
///
/// ```
/// let model = load::model("three_body").unwrap();
/// let one = load::evaluate_only(&model, Some(seam::FormulationKind::Kane), load::Jacobians::Differenced, load::Route::Jit, &mut |_| {}).unwrap();
/// assert_eq!(one.model.kinds(), [seam::FormulationKind::Kane]);
/// ```
pub fn evaluate_only(
    model: &generator::model::Model,
    only: Option<seam::FormulationKind>,
    exact: Jacobians,
    route: Route,
    on_compile: &mut dyn FnMut(&Path),
) -> Result<Loaded, LoadError> {
    let mut plain = generator::emit::Options::from_model(model);
    if let Some(kind) = only {
        plain.formulations = vec![generator::emit::Formulation::of(kind)];
    }
    let mut options = plain.clone();
    if let Jacobians::Exact { only, by_parameters } = exact {
        options.jacobian = true;
        options.parameter_jacobian = by_parameters;
        if let Some(kind) = only {
            options.formulations = vec![generator::emit::Formulation::of(kind)];
        }
    }
    let mut warnings = Vec::new();
    // Exact Jacobians over the node budget fall back to differences.
    let mut fallback = |e: &generator::model::ModelError| {
        let over = e.kind == generator::model::ErrorKind::Budget && exact != Jacobians::Differenced;
        if over {
            warnings.push(
                "the exact Jacobians need more expression nodes than the budget allows (`--max-nodes` raises it): the runtime differences the right-hand side instead"
                    .to_string(),
            );
        }
        over
    };
    let (evaluated, summary, interpreted) = match route {
        Route::Jit => {
            let jit = jit::Jit::default();
            let (evaluated, summary) = match generator::evaluate_with_backend(model, &options, &jit) {
                Err(e) if fallback(&e) => generator::evaluate_with_backend(model, &plain, &jit)?,
                other => other?,
            };
            (evaluated, summary, jit.interpreted())
        }
        Route::Compiled => {
            // The module as `generate` writes it, and its tapes for the description.
            let generated = match generator::generate(model, &generator::emit::Options { tapes: true, ..options }) {
                Err(e) if fallback(&e) => generator::generate(model, &generator::emit::Options { tapes: true, ..plain })?,
                other => other?,
            };
            let folder = native::cache::default_folder()?;
            let library = native::build(&generated.code, &folder, on_compile)?;
            let description = generator::eval::model::Evaluated::model(generated.program.expect("tapes were asked for"));
            (library.model(description)?, generated.summary, 0)
        }
    };
    warnings.extend(summary.warnings());
    if interpreted > 0 {
        warnings.push(format!(
            "{interpreted} of the model's functions could not be compiled to this machine's code and are interpreted (the same numbers, 2 to 5 times slower)"
        ));
    }
    Ok(Loaded { model: evaluated, warnings })
}

/// The model MODEL names ([`model`]) with the parameters `params` set, validated as the
/// file's own values are (a negative mass is refused), then [`evaluate`]d.
pub fn evaluated(
    argument: impl AsRef<std::ffi::OsStr>,
    params: &[(String, f64)],
    exact: Jacobians,
    route: Route,
    on_compile: &mut dyn FnMut(&Path),
) -> Result<Loaded, LoadError> {
    evaluate(&model(argument)?.with_parameters(params)?, exact, route, on_compile)
}

/// Why a model could not be loaded: the user's model (its located error), an unknown name, or
/// the compiled route's build.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error(transparent)]
    Model(#[from] generator::model::ModelError),
    #[error(transparent)]
    Compiled(#[from] native::Error),
}

/// How the model's arithmetic runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Route {
    /// Compiled in-process by the `jit` crate (cranelift): no toolchain needed.
    Jit,
    /// Built by rustc into a shared library cached by content (`--compiled`, the `native` crate).
    Compiled,
}

impl Route {
    /// The route `--compiled` asks for.
    pub fn of(compiled: bool) -> Route {
        if compiled { Route::Compiled } else { Route::Jit }
    }

    /// How the model ran, for a table's header.
    pub fn describe(self) -> &'static str {
        match self {
            Route::Jit => "evaluated in-process",
            Route::Compiled => "built by rustc, --compiled",
        }
    }
}
