//! From a MODEL argument to a model that runs: a model file anywhere, or the name of one of the
//! project's own models (built into the tool, so that `multibody compare three_body` works in
//! any folder), evaluated in-process ([`generator::eval`]: no cargo, no rustc, no checkout), or
//! with `--compiled` as its emitted module built by rustc into a library cached by content in
//! the user's cache folder (the `native` crate).

use std::path::Path;

/// The project's models, built into the tool: `(name, RON text)`.
const BUILT_IN: [(&str, &str); 15] = [
    ("bicycle", include_str!("../../models/bicycle.ron")),
    ("bouncing_ball", include_str!("../../models/bouncing_ball.ron")),
    ("cart_pendulum", include_str!("../../models/cart_pendulum.ron")),
    ("cartesian_pendulum", include_str!("../../models/cartesian_pendulum.ron")),
    ("inverted_pendulum", include_str!("../../models/inverted_pendulum.ron")),
    ("pendulum_on_cart_5", include_str!("../../models/pendulum_on_cart_5.ron")),
    ("rolling_disk", include_str!("../../models/rolling_disk.ron")),
    ("satellite_boom", include_str!("../../models/satellite_boom.ron")),
    ("satellite_boom_quaternion", include_str!("../../models/satellite_boom_quaternion.ron")),
    ("spring_cart", include_str!("../../models/spring_cart.ron")),
    ("stiff_pendulum", include_str!("../../models/stiff_pendulum.ron")),
    ("three_body", include_str!("../../models/three_body.ron")),
    ("three_body_quaternion", include_str!("../../models/three_body_quaternion.ron")),
    ("tumbling_body", include_str!("../../models/tumbling_body.ron")),
    ("winch", include_str!("../../models/winch.ron")),
];

/// The names of the built-in models.
pub fn built_in() -> impl Iterator<Item = &'static str> {
    BUILT_IN.iter().map(|(n, _)| *n)
}

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

/// A model's text and the file name its errors print.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Source {
    /// The file as errors name it (`models/<name>.ron` for a built-in model).
    pub file: String,
    pub text: String,
}

impl Source {
    /// The model, parsed and validated.
    pub fn model(&self) -> Result<generator::model::Model, LoadError> {
        Ok(generator::model::from_source(&self.file, &self.text)?)
    }
}

/// The text of the model MODEL names: a path (anything with a `/`, an extension, or an existing
/// file) is read from disk; a bare name is a built-in model.
///
/// ```
/// let source = load::source("three_body").unwrap();
/// assert_eq!(source.file, "models/three_body.ron");
/// assert!(load::source("no_such_model").is_err());
/// ```
pub fn source(argument: &str) -> Result<Source, LoadError> {
    let path = Path::new(argument);
    let looks_like_a_path = path.extension().is_some() || argument.contains(['/', '\\']) || path.is_file();
    if looks_like_a_path {
        let (file, text) = generator::model::read_source(path)?;
        return Ok(Source { file, text });
    }
    match BUILT_IN.iter().find(|(n, _)| *n == argument) {
        Some((name, text)) => Ok(Source { file: format!("models/{name}.ron"), text: text.to_string() }),
        None => Err(LoadError::UnknownModel { name: argument.to_string(), known: built_in().collect::<Vec<_>>().join(", ") }),
    }
}

/// The model MODEL names ([`source`]), loaded and validated.
pub fn model(argument: &str) -> Result<generator::model::Model, LoadError> {
    source(argument)?.model()
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
    let plain = generator::emit::Options::from_model(model);
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
            let (evaluated, summary) = match generator::eval::evaluate_with_backend(model, &options, &jit) {
                Err(e) if fallback(&e) => generator::eval::evaluate_with_backend(model, &plain, &jit)?,
                other => other?,
            };
            (evaluated, summary, jit.interpreted())
        }
        Route::Compiled => {
            // The module as `generate` writes it, and its tapes for the description.
            let generated = match generator::emit::generate(model, &generator::emit::Options { tapes: true, ..options }) {
                Err(e) if fallback(&e) => generator::emit::generate(model, &generator::emit::Options { tapes: true, ..plain })?,
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
pub fn evaluated(argument: &str, params: &[(String, f64)], exact: Jacobians, route: Route, on_compile: &mut dyn FnMut(&Path)) -> Result<Loaded, LoadError> {
    evaluate(&model(argument)?.with_parameters(params)?, exact, route, on_compile)
}

/// Why a model could not be loaded: the user's model (its located error), an unknown name, or
/// the compiled route's build.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error(transparent)]
    Model(#[from] generator::model::ModelError),
    #[error("no model `{name}`: it is not a file, and no built-in model has that name (built in: {known})")]
    UnknownModel { name: String, known: String },
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

#[cfg(test)]
mod tests {
    /// The built-in list is the `models/` folder.
    #[test]
    fn every_model_file_is_built_in() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../models");
        let mut files: Vec<String> =
            std::fs::read_dir(dir).unwrap().filter_map(|e| e.ok()?.file_name().to_str()?.strip_suffix(".ron").map(str::to_string)).collect();
        files.sort();
        assert_eq!(files, super::built_in().collect::<Vec<_>>());
    }
}
