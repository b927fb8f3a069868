//! The project's own models, built into every tool (the `generator` and `multibody` binaries,
//! the Python wheel), so that a model is named the same way everywhere: a path to a file, or
//! the name of one of these.

use super::{ErrorKind, ModelError};
use std::path::Path;

/// The project's models: `(name, RON text)`, the files of `models/`.
const BUILT_IN: [(&str, &str); 15] = [
    ("bicycle", include_str!("../../../models/bicycle.ron")),
    ("bouncing_ball", include_str!("../../../models/bouncing_ball.ron")),
    ("cart_pendulum", include_str!("../../../models/cart_pendulum.ron")),
    ("cartesian_pendulum", include_str!("../../../models/cartesian_pendulum.ron")),
    ("inverted_pendulum", include_str!("../../../models/inverted_pendulum.ron")),
    ("pendulum_on_cart_5", include_str!("../../../models/pendulum_on_cart_5.ron")),
    ("rolling_disk", include_str!("../../../models/rolling_disk.ron")),
    ("satellite_boom", include_str!("../../../models/satellite_boom.ron")),
    ("satellite_boom_quaternion", include_str!("../../../models/satellite_boom_quaternion.ron")),
    ("spring_cart", include_str!("../../../models/spring_cart.ron")),
    ("stiff_pendulum", include_str!("../../../models/stiff_pendulum.ron")),
    ("three_body", include_str!("../../../models/three_body.ron")),
    ("three_body_quaternion", include_str!("../../../models/three_body_quaternion.ron")),
    ("tumbling_body", include_str!("../../../models/tumbling_body.ron")),
    ("winch", include_str!("../../../models/winch.ron")),
];

/// The names of the built-in models.
pub fn built_in() -> impl Iterator<Item = &'static str> {
    BUILT_IN.iter().map(|(n, _)| *n)
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
    pub fn model(&self) -> Result<super::Model, ModelError> {
        super::from_source(&self.file, &self.text)
    }
}

/// The text of the model `argument` names: a path (anything with a `/`, an extension, or an
/// existing file) is read from disk; a bare name is a built-in model.
///
/// ```
/// use generator::model::source;
/// let s = source("three_body".as_ref()).unwrap();
/// assert_eq!(s.file, "models/three_body.ron");
/// let e = source("three_bdy".as_ref()).unwrap_err().to_string();
/// assert!(e.contains("no model `three_bdy`") && e.contains("three_body"), "{e}");
/// ```
pub fn source(argument: &Path) -> Result<Source, ModelError> {
    source_with(argument, &super::urdf::UrdfOptions::default())
}

/// [`source`], a URDF file (`.urdf`) read with `robot`'s options (its base, gravity, limits)
/// into the RON text of its model (see [`UrdfOptions`](super::UrdfOptions)); they are not read for a RON model.
///
/// ```
/// use generator::model::{Base, UrdfOptions, source_with};
/// let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("one.urdf");
/// std::fs::write(&path, r#"<robot name="one"><link name="a"><inertial><mass value="1"/>
///   <inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>"#).unwrap();
/// let floating = source_with(&path, &UrdfOptions { base: Base::Floating, ..UrdfOptions::default() }).unwrap();
/// assert_eq!(floating.model().unwrap().m(), 7); // three translations and a quaternion
/// ```
pub fn source_with(argument: &Path, robot: &super::urdf::UrdfOptions) -> Result<Source, ModelError> {
    let text = argument.to_string_lossy();
    let looks_like_a_path = argument.extension().is_some() || text.contains(['/', '\\']) || argument.is_file();
    if looks_like_a_path {
        let (file, text) = super::read_source(argument)?;
        if super::is_urdf(argument) {
            let def = super::urdf::model_file(&file, &text, robot)?;
            if def.coordinates.is_empty() {
                // Alone, a robot with nothing to move is a mistake (a drone's URDF, one link,
                // on the default fixed base); included by a RON model, it can be its scenery.
                let at = text.find("<robot").unwrap_or(0);
                return Err(ModelError::at(
                    ErrorKind::QuasiVelocityCount,
                    &file,
                    &text,
                    Some(at..at + "<robot".len().min(text.len() - at)),
                    "robot",
                    format!("robot `{}` has no moving joint and a fixed base: nothing in it moves", def.name),
                    "give it a floating base (`--base floating`; in Python `load(path, base=\"floating\")`), or a revolute, continuous or prismatic joint"
                        .into(),
                ));
            }
            return Ok(Source { file, text: super::to_ron(&def) });
        }
        return Ok(Source { file, text });
    }
    match BUILT_IN.iter().find(|(n, _)| *n == text) {
        Some((name, text)) => Ok(Source { file: format!("models/{name}.ron"), text: text.to_string() }),
        None => Err(ModelError::unlocated(
            ErrorKind::Io,
            &text,
            format!("no model `{text}`: it is not a file, and no built-in model has that name"),
            format!("give the path of a model file (`path/to/{text}.ron`), or a built-in model: {}", built_in().collect::<Vec<_>>().join(", ")),
        )),
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
