//! [`Builder`]: generating modules from model files in a `build.rs`, in the manner of
//! prost-build or bindgen. It writes each module into `OUT_DIR` (atomically, and only when its
//! bytes change), prints `cargo:rerun-if-changed` for every model file itself, and warns when
//! the build script runs the generator unoptimized (cargo builds build dependencies at
//! `opt-level = 0` unless the crate says otherwise; derivation is then about ten times slower).
//! The generator alone needs optimizing: `build-override` would optimize every build
//! dependency and proc macro too (syn, serde's derive...), which only lengthens the first build.
//!
//! ```toml
//! # Cargo.toml of the crate whose build.rs runs the generator
//! [profile.dev.package.generator]
//! opt-level = 3
//! [profile.release.package.generator]
//! opt-level = 3
//! ```

use crate::emit::{Formulation, Generated, Options, Parameters, Summary};
use crate::model::ModelError;
use crate::pipeline::generate;
use std::path::{Path, PathBuf};

/// Generates the modules of model files, for a build script.
///
/// ```no_run
/// // build.rs, inside `fn main()`:
/// generator::Builder::new()
///     .model("models/my_model.ron")
///     .seam_path("runtime::seam") // the crate depends on `runtime`, which re-exports the seam
///     .generate()
///     .unwrap_or_else(|e| panic!("{e}"));
/// // src/lib.rs:
/// // pub mod my_model { include!(concat!(env!("OUT_DIR"), "/my_model.rs")); }
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Builder {
    models: Vec<PathBuf>,
    out_dir: Option<PathBuf>,
    formulations: Option<Vec<Formulation>>,
    parameters: Option<Parameters>,
    integrate_ignorable: Option<bool>,
    max_lets_per_function: Option<usize>,
    jacobian: Option<bool>,
    parameter_jacobian: Option<bool>,
    fma: bool,
    seam_path: String,
    cargo_metadata: bool,
}

impl Default for Builder {
    fn default() -> Self {
        Builder::new()
    }
}

/// One module written by [`Builder::generate`].
#[derive(Clone, Debug)]
pub struct Built {
    /// The model file.
    pub model: PathBuf,
    /// The module file (`<out_dir>/<model name>.rs`).
    pub path: PathBuf,
    /// False when the file already held these bytes and was left alone.
    pub written: bool,
    pub summary: Summary,
}

/// Why [`Builder::generate`] failed.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// A model is invalid or cannot be emitted (the error names the file, the place and the fix).
    #[error("{0}")]
    Model(#[from] ModelError),
    /// A module could not be written (the old file is unchanged).
    #[error("{0}")]
    Io(#[from] files::FileError),
    #[error("no output directory: call `out_dir(..)`, or run from a build script (cargo sets `OUT_DIR`)")]
    NoOutDir,
    #[error("`{first}` and `{second}` both define a model named `{name}`: their modules would be the same file; rename one model")]
    DuplicateName { name: String, first: PathBuf, second: PathBuf },
    /// The path given to [`Builder::seam_path`] is not a Rust path.
    #[error("Builder::seam_path: {message}; {}", crate::emit::SEAM_PATH_HELP)]
    SeamPath { message: String },
}

impl Builder {
    /// No models yet; the output directory is `OUT_DIR`; every option from the model files.
    pub fn new() -> Builder {
        Builder {
            models: Vec::new(),
            out_dir: None,
            formulations: None,
            parameters: None,
            integrate_ignorable: None,
            max_lets_per_function: None,
            jacobian: None,
            parameter_jacobian: None,
            fma: false,
            seam_path: crate::emit::DEFAULT_SEAM_PATH.to_string(),
            cargo_metadata: true,
        }
    }

    /// Adds a model file; its module is written as `<out_dir>/<model name>.rs`.
    pub fn model(mut self, path: impl AsRef<Path>) -> Builder {
        self.models.push(path.as_ref().to_path_buf());
        self
    }

    /// Where the modules go (default: `OUT_DIR`).
    pub fn out_dir(mut self, dir: impl AsRef<Path>) -> Builder {
        self.out_dir = Some(dir.as_ref().to_path_buf());
        self
    }

    /// The formulations to emit, instead of each model file's `emit.formulations`.
    pub fn formulations(mut self, list: &[Formulation]) -> Builder {
        let mut list = list.to_vec();
        list.sort();
        list.dedup();
        self.formulations = Some(list);
        self
    }

    /// Fold the parameters into the code as constants (`true`) or keep them as fields of
    /// `Params` (`false`), instead of each model file's choice.
    pub fn baked_parameters(mut self, baked: bool) -> Builder {
        self.parameters = Some(if baked { Parameters::Baked } else { Parameters::Runtime });
        self
    }

    /// Keep the ignorable coordinates in the reduced method's state (`true`) or drop them.
    pub fn integrate_ignorable(mut self, keep: bool) -> Builder {
        self.integrate_ignorable = Some(keep);
        self
    }

    /// Split functions with more than `n` common subexpressions into helpers.
    pub fn max_lets_per_function(mut self, n: usize) -> Builder {
        self.max_lets_per_function = Some(n.max(1));
        self
    }

    /// Emit each formulation's exact `jacobian` (`true`) or leave it out, instead of each
    /// model file's choice.
    pub fn jacobian(mut self, emit: bool) -> Builder {
        self.jacobian = Some(emit);
        self
    }

    /// Emit each formulation's `parameter_jacobian` (`true`) or not, instead of each model
    /// file's choice.
    pub fn parameter_jacobian(mut self, emit: bool) -> Builder {
        self.parameter_jacobian = Some(emit);
        self
    }

    /// Emit fused multiply-adds (default off). Build the crate with
    /// `-C target-cpu=native` or `-C target-feature=+fma` where the CPU has them.
    pub fn fma(mut self, on: bool) -> Builder {
        self.fma = on;
        self
    }

    /// The seam crate's path in the emitted code (default `::seam`; `runtime::seam` for a crate
    /// that depends on the runtime only).
    pub fn seam_path(mut self, path: impl Into<String>) -> Builder {
        self.seam_path = path.into();
        self
    }

    /// Print `cargo:rerun-if-changed` and the unoptimized-build warning (default: on).
    pub fn cargo_metadata(mut self, on: bool) -> Builder {
        self.cargo_metadata = on;
        self
    }

    /// The options for one model file.
    fn options(&self, model: &crate::model::Model) -> Options {
        let mut o = Options::from_model(model);
        if let Some(f) = &self.formulations {
            o.formulations = f.clone();
        }
        if let Some(p) = self.parameters {
            o.parameters = p;
        }
        if let Some(k) = self.integrate_ignorable {
            o.integrate_ignorable = k;
        }
        if let Some(n) = self.max_lets_per_function {
            o.max_lets_per_function = n;
        }
        if let Some(j) = self.jacobian {
            o.jacobian = j;
        }
        if let Some(j) = self.parameter_jacobian {
            o.parameter_jacobian = j;
        }
        o.fma = self.fma;
        o.seam_path = self.seam_path.clone();
        o
    }

    /// Generates and writes every module; see the module docs.
    pub fn generate(&self) -> Result<Vec<Built>, BuildError> {
        if self.cargo_metadata {
            for m in &self.models {
                println!("cargo:rerun-if-changed={}", m.display());
            }
            if unoptimized() {
                println!(
                    "cargo:warning=the generator runs unoptimized in this build script (about ten times slower); add `[profile.dev.package.generator] opt-level = 3` and `[profile.release.package.generator] opt-level = 3` to Cargo.toml"
                );
            }
        }
        crate::emit::parse_seam_path(&self.seam_path).map_err(|message| BuildError::SeamPath { message })?;
        let out_dir = match &self.out_dir {
            Some(d) => d.clone(),
            None => std::env::var_os("OUT_DIR").map(PathBuf::from).ok_or(BuildError::NoOutDir)?,
        };
        // Every model is read and checked before anything is written.
        let mut models: Vec<(&PathBuf, crate::model::Model)> = Vec::new();
        for file in &self.models {
            let model = crate::model::load(file)?;
            if let Some((first, _)) = models.iter().find(|(_, m)| m.name == model.name) {
                return Err(BuildError::DuplicateName { name: model.name.clone(), first: first.to_path_buf(), second: file.clone() });
            }
            models.push((file, model));
        }
        std::fs::create_dir_all(&out_dir).map_err(|source| files::FileError::Io { path: out_dir.clone(), action: "create the folder", source })?;
        let mut built: Vec<Built> = Vec::new();
        for (file, model) in models {
            let Generated { code, summary, .. } = generate(&model, &self.options(&model))?;
            let path = out_dir.join(format!("{}.rs", model.name));
            let written = write_if_changed(&path, &code)?;
            built.push(Built { model: file.clone(), path, written, summary });
        }
        Ok(built)
    }
}

/// True when this library was compiled at `opt-level = 0`.
fn unoptimized() -> bool {
    env!("GENERATOR_OPT_LEVEL") == "0"
}

/// Writes `code` to `path` atomically unless the file already holds it; returns whether it
/// wrote.
pub(super) fn write_if_changed(path: &Path, code: &str) -> Result<bool, files::FileError> {
    Ok(files::write_if_changed(path, code.as_bytes())? != files::Written::Unchanged)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn models() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../models")
    }

    #[test]
    fn writes_each_module_once_and_applies_the_options() {
        let dir = std::env::temp_dir().join(format!("builder-{}", std::process::id()));
        let builder = Builder::new()
            .model(models().join("cart_pendulum.ron"))
            .out_dir(&dir)
            .formulations(&[Formulation::ReducedVolterra, Formulation::Kane])
            .baked_parameters(true)
            .seam_path("runtime::seam")
            .cargo_metadata(false);
        let first = builder.generate().unwrap();
        assert_eq!(first.len(), 1);
        assert!(first[0].written && first[0].path.ends_with("cart_pendulum.rs"));
        let code = std::fs::read_to_string(&first[0].path).unwrap();
        assert!(code.contains("pub use runtime::seam::Failure;"), "seam path");
        assert!(code.contains("pub mod kane") && code.contains("pub mod reduced_volterra") && !code.contains("pub mod lagrange"));
        assert!(code.contains("pub const PARAMETERS_BAKED: bool = true;"));
        // Unchanged bytes are not rewritten, so cargo sees nothing new.
        assert!(!builder.generate().unwrap()[0].written);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn two_models_of_one_name_are_refused_and_a_bad_model_is_located() {
        let dir = std::env::temp_dir().join(format!("builder-dup-{}", std::process::id()));
        let m = models().join("satellite_boom.ron");
        let e = Builder::new().model(&m).model(&m).out_dir(&dir).cargo_metadata(false).generate().unwrap_err();
        assert!(matches!(e, BuildError::DuplicateName { .. }), "{e}");
        let bad = dir.join("bad.ron");
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(&bad, "Model(name: \"bad\", coordinates: [").unwrap();
        let e = Builder::new().model(&bad).out_dir(&dir).cargo_metadata(false).generate().unwrap_err();
        assert!(matches!(e, BuildError::Model(_)) && e.to_string().contains("bad.ron"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_seam_path_that_is_not_a_path_is_refused_before_anything_is_read() {
        let dir = std::env::temp_dir().join(format!("builder-seam-{}", std::process::id()));
        let e = Builder::new().model(models().join("no_such.ron")).seam_path("not a path").out_dir(&dir).cargo_metadata(false).generate().unwrap_err();
        assert!(matches!(e, BuildError::SeamPath { .. }), "{e}");
        assert!(e.to_string().starts_with("Builder::seam_path: `not a path` is not a Rust path") && e.to_string().contains("runtime::seam"), "{e}");
        assert!(!dir.exists());
    }
}
