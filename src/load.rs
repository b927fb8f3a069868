//! From a MODEL argument to a model that runs: a model file anywhere, or the name of one of the
//! project's own models (built into the tool, so that `multibody compare three_body` works in
//! any folder), evaluated in-process ([`generator::eval`]): no cargo, no rustc, no checkout.

use crate::CliError;
use std::path::Path;

/// The project's models, built into the tool: `(name, RON text)`.
const BUILT_IN: [(&str, &str); 9] = [
    ("bicycle", include_str!("../models/bicycle.ron")),
    ("cart_pendulum", include_str!("../models/cart_pendulum.ron")),
    ("cartesian_pendulum", include_str!("../models/cartesian_pendulum.ron")),
    ("pendulum_on_cart_5", include_str!("../models/pendulum_on_cart_5.ron")),
    ("rolling_disk", include_str!("../models/rolling_disk.ron")),
    ("satellite_boom", include_str!("../models/satellite_boom.ron")),
    ("spring_cart", include_str!("../models/spring_cart.ron")),
    ("stiff_pendulum", include_str!("../models/stiff_pendulum.ron")),
    ("three_body", include_str!("../models/three_body.ron")),
];

/// The names of the built-in models.
pub fn built_in() -> impl Iterator<Item = &'static str> {
    BUILT_IN.iter().map(|(n, _)| *n)
}

/// The model MODEL names, loaded and validated: a path (anything with a `/`, an extension, or
/// an existing file) is read from disk; a bare name is a built-in model.
pub fn model(argument: &str) -> Result<generator::model::Model, CliError> {
    let path = Path::new(argument);
    let looks_like_a_path = path.extension().is_some() || argument.contains(['/', '\\']) || path.is_file();
    if looks_like_a_path {
        return Ok(generator::model::load(path)?);
    }
    match BUILT_IN.iter().find(|(n, _)| *n == argument) {
        Some((name, text)) => Ok(generator::model::from_source(&format!("models/{name}.ron"), text)?),
        None => Err(CliError::UnknownModel { name: argument.to_string(), known: built_in().collect::<Vec<_>>().join(", ") }),
    }
}

/// The model MODEL names with the parameters `params` set (`--param`), validated as the file's
/// own values are (a negative mass is refused), evaluated in-process.
pub fn evaluated(argument: &str, params: &[(String, f64)]) -> Result<seam::Model, CliError> {
    let model = model(argument)?.with_parameters(params)?;
    let (evaluated, summary) = generator::eval::evaluate_reporting(&model, &generator::emit::Options::from_model(&model))?;
    for line in summary.warnings() {
        eprintln!("warning: {line}");
    }
    Ok(evaluated)
}

#[cfg(test)]
mod tests {
    /// The built-in list is the `models/` folder.
    #[test]
    fn every_model_file_is_built_in() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
        let mut files: Vec<String> =
            std::fs::read_dir(dir).unwrap().filter_map(|e| e.ok()?.file_name().to_str()?.strip_suffix(".ron").map(str::to_string)).collect();
        files.sort();
        assert_eq!(files, super::built_in().collect::<Vec<_>>());
    }
}
