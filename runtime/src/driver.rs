//! From a MODEL argument to a program with that model compiled in, optimized: what the
//! `compare` and `sweep` binaries do before they run anything.
//!
//! MODEL is a model file (`path/to/my_model.ron`) or the name of a file in the workspace's
//! `models/`. The driver
//! 1. runs the generator on the file (its located error, and a non-zero exit, when the model is
//!    wrong), writing the module into a small Cargo project of its own under
//!    `target/models/<name>-<hash of the path>/`; the module is rewritten only when its bytes
//!    change, so the build is cached by the model's content;
//! 2. builds that project in release mode (`target/models` is its target directory, shared by
//!    every model, so the runtime and its dependencies compile once);
//! 3. runs it with the command and the arguments it was given ([`crate::cli::run_compiled`]).
//!
//! The first run builds the generator and the runtime (minutes); a later run of an unchanged
//! model only checks that both are up to date. Nested cargo commands use their own target
//! directory: `cargo test` holds the lock of the workspace's while tests run.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

/// The workspace this binary was built from: the generator, the runtime and `models/`.
const WORKSPACE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

/// Which command the driver serves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tool {
    Compare,
    Sweep,
    Linearize,
}

impl Tool {
    fn name(self) -> &'static str {
        match self {
            Tool::Compare => "compare",
            Tool::Sweep => "sweep",
            Tool::Linearize => "linearize",
        }
    }
}

/// Why a model could not be turned into a program.
#[derive(Debug, thiserror::Error)]
pub enum DriverError {
    #[error("no model `{name}`: it is not a file, and `models/` has no `{name}.ron` (it has: {known})")]
    UnknownModel { name: String, known: String },
    #[error("cannot read model file `{path}`: {source}")]
    Unreadable { path: PathBuf, source: std::io::Error },
    /// The generator refused the model; it has printed the located error itself.
    #[error("the generator refused `{path}` (see above)")]
    Refused { path: PathBuf, code: i32 },
    #[error("cannot run `{program}`: {source}")]
    Spawn { program: String, source: std::io::Error },
    #[error(transparent)]
    Write(files::FileError),
    #[error("building the program for `{path}` failed (a bug: the emitted module should always compile; the build log is above)")]
    Build { path: PathBuf },
}

impl DriverError {
    /// The generator's own exit code when it refused the model, 1 otherwise.
    pub fn exit_code(&self) -> u8 {
        match self {
            DriverError::Refused { code, .. } => u8::try_from(*code).unwrap_or(1).max(1),
            _ => 1,
        }
    }
}

/// The model file MODEL names: a path to a file, or a name in `models/`.
///
/// ```
/// let path = runtime::driver::resolve("cart_pendulum").unwrap();
/// assert!(path.ends_with("models/cart_pendulum.ron"));
/// let err = runtime::driver::resolve("no_such_model").unwrap_err().to_string();
/// assert!(err.contains("no model `no_such_model`") && err.contains("three_body"), "{err}");
/// ```
pub fn resolve(model: &str) -> Result<PathBuf, DriverError> {
    let as_path = Path::new(model);
    let looks_like_a_path = as_path.extension().is_some() || model.contains(['/', '\\']) || as_path.is_file();
    let path = if looks_like_a_path { as_path.to_path_buf() } else { Path::new(WORKSPACE).join("models").join(format!("{model}.ron")) };
    if !looks_like_a_path && !path.is_file() {
        return Err(DriverError::UnknownModel { name: model.to_string(), known: known_models().join(", ") });
    }
    std::fs::canonicalize(&path).map_err(|source| DriverError::Unreadable { path: as_path.to_path_buf(), source })
}

/// The names of the files in `models/`, sorted.
pub fn known_models() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(Path::new(WORKSPACE).join("models"))
        .into_iter()
        .flatten()
        .filter_map(|e| e.ok())
        .filter_map(|e| e.file_name().to_str().and_then(|n| n.strip_suffix(".ron")).map(str::to_string))
        .collect();
    names.sort();
    names
}

/// 64-bit FNV-1a: a stable name for a path (the standard hasher may change between releases).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3))
}

/// The cache project's name for a model file: its stem, cleaned, and a hash of its path.
fn project_name(file: &Path) -> String {
    let stem = file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let clean: String = stem.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c.to_ascii_lowercase() } else { '_' }).take(40).collect();
    format!("model-{clean}-{:08x}", fnv1a(file.as_os_str().as_encoded_bytes()) as u32)
}

/// A TOML basic string.
fn toml_string(s: &str) -> String {
    let mut out = String::from('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

fn cargo() -> OsString {
    std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into())
}

fn write_if_changed(path: &Path, text: &str) -> Result<(), DriverError> {
    files::write_if_changed(path, text.as_bytes()).map(|_| ()).map_err(DriverError::Write)
}

fn status(mut cmd: Command, program: &str) -> Result<std::process::ExitStatus, DriverError> {
    cmd.status().map_err(|source| DriverError::Spawn { program: program.to_string(), source })
}

/// Generates, builds and returns the program for the model file `file` (see the module docs).
pub fn program_for(file: &Path) -> Result<PathBuf, DriverError> {
    let workspace = std::fs::canonicalize(WORKSPACE).map_err(|source| DriverError::Unreadable { path: WORKSPACE.into(), source })?;
    let target = workspace.join("target").join("models");
    let name = project_name(file);
    let project = target.join(&name);
    let src = project.join("src");
    std::fs::create_dir_all(&src).map_err(|source| DriverError::Write(files::FileError::Io { path: src.clone(), action: "create the folder", source }))?;
    let binary = target.join("release").join(format!("{name}{}", std::env::consts::EXE_SUFFIX));

    // 1. The module, from the generator (built optimized, in the driver's own target directory).
    let module = src.join("model.rs");
    let before = std::fs::read(&module).ok();
    let generator_built = target.join("release").join(format!("generator{}", std::env::consts::EXE_SUFFIX)).is_file();
    if !generator_built {
        eprintln!("building the generator (first run only)...");
    }
    let mut cmd = Command::new(cargo());
    cmd.args(["run", "--release", "-p", "generator"]);
    if generator_built {
        cmd.arg("-q");
    }
    cmd.arg("--manifest-path").arg(workspace.join("Cargo.toml")).arg("--target-dir").arg(&target);
    cmd.arg("--").arg(file).arg("-o").arg(&module).args(["--seam-path", "runtime::seam", "--quiet"]);
    let st = status(cmd, "cargo run -p generator")?;
    if !st.success() {
        return Err(DriverError::Refused { path: file.to_path_buf(), code: st.code().unwrap_or(1) });
    }

    // 2. The project around it, and its build.
    let runtime = workspace.join("runtime");
    let manifest = format!(
        "# Written by the runtime's `compare`/`sweep` for {file}: do not edit.\n[package]\nname = {name}\nversion = \"0.0.0\"\nedition = \"2024\"\npublish = false\n\n[dependencies]\nruntime = {{ path = {runtime} }}\n\n# Not a member of the project's workspace.\n[workspace]\n",
        file = file.display(),
        name = toml_string(&name),
        runtime = toml_string(&runtime.to_string_lossy()),
    );
    write_if_changed(&project.join("Cargo.toml"), &manifest)?;
    let lock = project.join("Cargo.lock");
    if !lock.is_file() {
        // The workspace's resolution: the same dependency versions, no registry lookup.
        if let Ok(text) = std::fs::read_to_string(workspace.join("Cargo.lock")) {
            write_if_changed(&lock, &text)?;
        }
    }
    let main = format!(
        "//! Written by the runtime's `compare`/`sweep` for {}: the model's module, run by the runtime's commands.\n\n#[allow(clippy::all, dead_code, non_snake_case)]\nmod model;\n\nfn main() -> std::process::ExitCode {{\n    runtime::cli::run_compiled(model::model())\n}}\n",
        file.display()
    );
    write_if_changed(&src.join("main.rs"), &main)?;
    let changed = before != std::fs::read(&module).ok() || !binary.is_file();
    if changed {
        eprintln!("compiling {} (optimized; cached until the model changes)...", file.display());
    }
    let mut cmd = Command::new(cargo());
    cmd.args(["build", "--release"]);
    if !changed {
        cmd.arg("-q");
    }
    cmd.arg("--manifest-path").arg(project.join("Cargo.toml")).arg("--target-dir").arg(&target);
    if !status(cmd, "cargo build")?.success() {
        return Err(DriverError::Build { path: file.to_path_buf() });
    }
    Ok(binary)
}

/// The `main` of the `compare` and `sweep` binaries.
pub fn main(tool: Tool) -> ExitCode {
    use clap::Parser;
    let args: Vec<OsString> = std::env::args_os().collect();
    // Parse first: `--help`, `--version` and bad arguments are answered before any build.
    let model = match tool {
        Tool::Compare => crate::cli::CompareArgs::parse_from(&args).model,
        Tool::Sweep => crate::cli::SweepArgs::parse_from(&args).model,
        Tool::Linearize => crate::cli::LinearizeArgs::parse_from(&args).model,
    };
    let program = match resolve(&model).and_then(|file| program_for(&file)) {
        Ok(p) => p,
        Err(e) => {
            if !matches!(e, DriverError::Refused { .. }) {
                eprintln!("error: {e}");
            }
            return ExitCode::from(e.exit_code());
        }
    };
    match Command::new(&program).arg(tool.name()).args(&args[1..]).status() {
        Ok(st) => ExitCode::from(st.code().map_or(1, |c| u8::try_from(c).unwrap_or(1))),
        Err(e) => {
            eprintln!("error: cannot run `{}`: {e}", program.display());
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn project_names_are_stable_and_distinct() {
        let a = project_name(Path::new("/tmp/x/my model.ron"));
        assert_eq!(a, project_name(Path::new("/tmp/x/my model.ron")));
        assert!(a.starts_with("model-my_model-"), "{a}");
        assert_ne!(a, project_name(Path::new("/tmp/y/my model.ron")));
    }

    #[test]
    fn toml_strings_escape_quotes_and_backslashes() {
        assert_eq!(toml_string(r#"C:\a "b""#), r#""C:\\a \"b\"""#);
    }
}
