//! The compiled route (`multibody --compiled`): a model's emitted module, exactly as
//! `multibody generate` writes it, built by rustc into a shared library once per content
//! ([`cache`]: keyed by SHA-256, in the user's cache folder, under a lock), loaded, and put
//! behind the seam's traits, so that a run gets the compiled module's speed with no cargo, no
//! project and no checkout. Only C types cross between the two compilers ([`abi`]: one
//! function, `multibody_call`, and flat slices and faults); the library builds its own copy of
//! the `seam` crate from the sources this crate carries. No path, name or text of the user's
//! reaches the library's sources but the module the generator emitted, where every user text is
//! an escaped string literal.
//!
//! ```no_run
//! let model = generator::model::load("models/three_body.ron").unwrap();
//! let options = generator::emit::Options { tapes: true, ..generator::emit::Options::from_model(&model) };
//! let generated = generator::generate(&model, &options).unwrap();
//! let description = generator::eval::model::Evaluated::model(generated.program.unwrap());
//! let folder = native::cache::default_folder().unwrap();
//! let library = native::build(&generated.code, &folder, &mut |_| eprintln!("compiling once...")).unwrap();
//! let compiled: seam::Model = library.model(description).unwrap();
//! ```

pub mod abi;
pub mod cache;

use seam::{Failure, FormulationFunctions, ModelFunctions};
use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Arc, Mutex};

/// Why the compiled route could not give a model. None of these is a fault in the model.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(
        "the compiled route needs rustc, and `{program}` could not be started ({source}): install Rust (https://rustup.rs) or set RUSTC, or leave out --compiled to run the model in-process"
    )]
    NoRustc { program: String, source: std::io::Error },
    #[error("rustc failed to build the model's library ({status}); this is a fault of multibody, please report it with this output:\n{output}")]
    Rustc { status: String, output: String },
    #[error("rustc was killed (signal {signal}) while it built the model's library: out of memory, or stopped by hand? Run again to build it")]
    RustcKilled { signal: i32 },
    #[error(
        "the disk of the cache folder is full: the model's library could not be built there (free some space, or set MULTIBODY_CACHE_DIR to a folder on another disk):\n{output}"
    )]
    DiskFull { output: String },
    #[error("the cache folder {} cannot be used: {problem} (or set {} to another folder)", folder.display(), cache::CACHE_VARIABLE)]
    Cache { folder: PathBuf, problem: String },
    #[error("no cache folder is known on this system: set {}", cache::CACHE_VARIABLE)]
    NoCacheFolder,
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error("the cached library {} cannot be used ({reason}); delete it to build it again", path.display())]
    Load { path: PathBuf, reason: String },
}

/// The `seam` crate's sources, built into every library (`lib.rs` first).
pub const SEAM_SOURCES: [(&str, &str); 10] = [
    ("lib.rs", include_str!("../../runtime/seam/src/lib.rs")),
    ("check.rs", include_str!("../../runtime/seam/src/check.rs")),
    ("compiled.rs", include_str!("../../runtime/seam/src/compiled.rs")),
    ("event.rs", include_str!("../../runtime/seam/src/event.rs")),
    ("failure.rs", include_str!("../../runtime/seam/src/failure.rs")),
    ("grid.rs", include_str!("../../runtime/seam/src/grid.rs")),
    ("kind.rs", include_str!("../../runtime/seam/src/kind.rs")),
    ("model.rs", include_str!("../../runtime/seam/src/model.rs")),
    ("rates.rs", include_str!("../../runtime/seam/src/rates.rs")),
    ("solve.rs", include_str!("../../runtime/seam/src/solve.rs")),
];

/// The library's fixed crate root, and the ABI it shares with this crate.
const LIBRARY_ROOT: &str = include_str!("../library/lib.rs");
const ABI: &str = include_str!("abi.rs");

/// rustc's flags for the `seam` rlib and for the library.
const SEAM_FLAGS: [&str; 10] = ["--crate-type", "rlib", "--crate-name", "seam", "--edition", "2024", "-C", "opt-level=3", "-C", "panic=abort"];
const LIBRARY_FLAGS: [&str; 12] =
    ["--crate-type", "cdylib", "--crate-name", "multibody_model", "--edition", "2024", "-C", "opt-level=3", "-C", "panic=abort", "-C", "strip=symbols"];

/// The key of the library of `module`: everything it is built from.
pub fn key(module: &str) -> String {
    let mut parts: Vec<&[u8]> = vec![env!("CARGO_PKG_VERSION").as_bytes(), std::env::consts::ARCH.as_bytes(), std::env::consts::OS.as_bytes()];
    parts.extend(SEAM_FLAGS.iter().chain(&LIBRARY_FLAGS).map(|f| f.as_bytes()));
    parts.extend(SEAM_SOURCES.iter().flat_map(|(name, text)| [name.as_bytes(), text.as_bytes()]));
    parts.extend([LIBRARY_ROOT.as_bytes(), ABI.as_bytes(), module.as_bytes()]);
    cache::key(&parts)
}

/// A model's library, loaded.
pub struct Library {
    loaded: Arc<Loaded>,
    path: PathBuf,
    built: bool,
}

struct Loaded {
    call: abi::CallFn,
    formulation: abi::FormulationFn,
    // Declared last: dropped after the function pointers above, which point into it.
    _library: libloading::Library,
}

impl Library {
    /// Where the library is.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Whether this call built it (false: it was in the cache).
    pub fn built(&self) -> bool {
        self.built
    }

    /// The names of the library's formulations, in order.
    pub fn formulations(&self) -> Vec<String> {
        (0..)
            .map_while(|k| {
                let mut len = 0;
                // SAFETY: `multibody_formulation` returns null or a pointer to `len` bytes of a
                // `'static` name in the library, which outlives this call.
                unsafe {
                    let p = (self.loaded.formulation)(k, &mut len);
                    (!p.is_null()).then(|| String::from_utf8_lossy(std::slice::from_raw_parts(p, len)).into_owned())
                }
            })
            .collect()
    }

    /// `description` (the same module's description, from its in-process evaluation) with every
    /// function the library's: the numbers are the compiled module's.
    pub fn model(&self, mut description: seam::Model) -> Result<seam::Model, Error> {
        let ours: Vec<String> = description.formulations.iter().map(|f| f.kind.name().to_string()).collect();
        let theirs = self.formulations();
        if ours != theirs {
            return Err(Error::Load { path: self.path.clone(), reason: format!("its formulations are {theirs:?}, the model's {ours:?}") });
        }
        for (k, f) in description.formulations.iter_mut().enumerate() {
            f.functions = Arc::new(NativeFormulation { loaded: self.loaded.clone(), index: k });
        }
        description.functions = Arc::new(NativeModel { loaded: self.loaded.clone() });
        Ok(description)
    }
}

/// The library of `module` (an emitted module's source), from the cache in `folder` or built
/// into it (`on_build` is told first, with the library's path: building takes seconds).
pub fn build(module: &str, folder: &Path, on_build: &mut dyn FnMut(&Path)) -> Result<Library, Error> {
    build_with(module, folder, &rustc_program(), on_build)
}

/// The rustc to build with: `RUSTC` when set, else `rustc` on `PATH`.
pub fn rustc_program() -> PathBuf {
    std::env::var_os("RUSTC").filter(|r| !r.is_empty()).unwrap_or_else(|| "rustc".into()).into()
}

/// [`build`] with the rustc at `rustc`.
pub fn build_with(module: &str, folder: &Path, rustc: &Path, on_build: &mut dyn FnMut(&Path)) -> Result<Library, Error> {
    let key = key(module);
    let cache = cache::Cache::open(folder)?;
    let shown = cache.shown_library(&key);
    let mut built = false;
    let file = match cache.verified(&key) {
        Some(file) => file,
        None => {
            let _lock = cache.lock(&key)?;
            // Another process may have built it while this one waited for the lock.
            match cache.verified(&key) {
                Some(file) => file,
                None => {
                    on_build(&shown);
                    let work = cache.build_folder(&key)?;
                    let library = compile(module, &key, work.path(), rustc)?;
                    cache.store(&key, &library)?;
                    built = true;
                    cache.verified(&key).ok_or_else(|| Error::Load { path: shown.clone(), reason: "the library just built does not verify".into() })?
                }
            }
        }
    };
    let loaded = load(&file, &shown, &key)?;
    Ok(Library { loaded: Arc::new(loaded), path: shown, built })
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> Error + use<> {
    let path = path.to_path_buf();
    move |source| Error::Io { path, source }
}

/// Runs rustc in `folder` (every path it is given relative to it).
fn run_rustc(program: &Path, arguments: &[&str], folder: &Path) -> Result<(), Error> {
    let result = Command::new(program)
        .args(arguments)
        .current_dir(folder)
        .output()
        .map_err(|source| Error::NoRustc { program: program.display().to_string(), source })?;
    if result.status.success() {
        return Ok(());
    }
    let text = String::from_utf8_lossy(&result.stderr);
    let tail: Vec<&str> = text.lines().rev().take(40).collect();
    let output = tail.into_iter().rev().collect::<Vec<_>>().join("\n");
    #[cfg(unix)]
    if let Some(signal) = std::os::unix::process::ExitStatusExt::signal(&result.status) {
        return Err(Error::RustcKilled { signal });
    }
    if text.contains("No space left on device") || text.contains("Disk quota exceeded") {
        return Err(Error::DiskFull { output });
    }
    Err(Error::Rustc { status: result.status.to_string(), output })
}

/// Builds the library of `module` in the private folder `dir`; the path of the library.
fn compile(module: &str, key: &str, dir: &Path, rustc: &Path) -> Result<PathBuf, Error> {
    let seam_dir = dir.join("seam");
    std::fs::create_dir(&seam_dir).map_err(io(&seam_dir))?;
    let mut files: Vec<(PathBuf, &[u8])> = SEAM_SOURCES.iter().map(|(name, text)| (seam_dir.join(name), text.as_bytes())).collect();
    files.extend([
        (dir.join("lib.rs"), LIBRARY_ROOT.as_bytes()),
        (dir.join("abi.rs"), ABI.as_bytes()),
        (dir.join("module.rs"), module.as_bytes()),
        (dir.join("key.txt"), key.as_bytes()),
    ]);
    for (path, bytes) in &files {
        std::fs::write(path, bytes).map_err(|e| match e.raw_os_error() {
            Some(28) => Error::DiskFull { output: e.to_string() },
            _ => Error::Io { path: path.clone(), source: e },
        })?;
    }
    // rustc runs in `dir` and is given paths relative to it: `dir` may be reached through this
    // process's handle on the cache, which rustc does not have.
    let mut arguments: Vec<&str> = SEAM_FLAGS.to_vec();
    arguments.extend(["-o", "libseam.rlib", "seam/lib.rs"]);
    run_rustc(rustc, &arguments, dir)?;
    let name = cache::library_name(key);
    let mut arguments: Vec<&str> = LIBRARY_FLAGS.to_vec();
    arguments.extend(["--extern", "seam=libseam.rlib", "-o", &name, "lib.rs"]);
    run_rustc(rustc, &arguments, dir)?;
    Ok(dir.join(name))
}

/// Loads the library open in `file` (verified against its digest, [`cache::Cache::verified`])
/// from that same file, and checks that it is the one of `key`. `shown` names it in errors.
fn load(file: &std::fs::File, shown: &Path, key: &str) -> Result<Loaded, Error> {
    let fail = |reason: String| Error::Load { path: shown.to_path_buf(), reason };
    // Through the open file, each time by a name never used before: glibc's `dlopen` returns
    // the library already loaded under the same name without opening anything, and the number
    // of a closed file is given to the next one (`/proc/self/./fd/N`, `/proc/self/././fd/N`,
    // ... all name this process's file N).
    #[cfg(target_os = "linux")]
    let path = {
        static LOADS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let spelling = "./".repeat(LOADS.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
        PathBuf::from(format!("/proc/self/{spelling}fd/{}", std::os::fd::AsRawFd::as_raw_fd(file)))
    };
    #[cfg(not(target_os = "linux"))]
    let path = {
        let _ = file;
        shown.to_path_buf()
    };
    // SAFETY: the library's bytes are those built by `compile` from fixed sources and an
    // emitted module (their digest was checked on this open file); its only initialization
    // is static data (its model is built on first use, in Rust).
    let library = unsafe { libloading::Library::new(&path) }.map_err(|e| fail(e.to_string()))?;
    // SAFETY: each symbol has the type `library/lib.rs` gives it.
    let (stored, call, formulation) = unsafe {
        let stored: [u8; 64] = **library.get::<*const [u8; 64]>(abi::KEY_SYMBOL.as_bytes()).map_err(|e| fail(e.to_string()))?;
        let call = *library.get::<abi::CallFn>(abi::CALL_SYMBOL.as_bytes()).map_err(|e| fail(e.to_string()))?;
        let formulation = *library.get::<abi::FormulationFn>(abi::FORMULATION_SYMBOL.as_bytes()).map_err(|e| fail(e.to_string()))?;
        (stored, call, formulation)
    };
    if stored != key.as_bytes() {
        return Err(fail(format!("it was built from other sources (key {})", String::from_utf8_lossy(&stored))));
    }
    Ok(Loaded { call, formulation, _library: library })
}

/// `name` as a `'static` string: the names a failure carries (arguments, functions) are a
/// handful per model, each kept once.
fn intern(name: &str) -> &'static str {
    static NAMES: Mutex<Vec<&'static str>> = Mutex::new(Vec::new());
    let mut names = NAMES.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(n) = names.iter().find(|n| **n == name) {
        return n;
    }
    let n: &'static str = Box::leak(name.to_string().into_boxed_str());
    names.push(n);
    n
}

/// The failure a fault stands for.
fn decode(f: &abi::Fault) -> Failure {
    let text = if f.text.is_null() {
        String::new()
    } else {
        // SAFETY: the library points `text` at `text_len` bytes that stay valid until its next
        // call on this thread; they are copied here, before any.
        String::from_utf8_lossy(unsafe { std::slice::from_raw_parts(f.text, f.text_len) }).into_owned()
    };
    match f.kind {
        abi::fault::SINGULAR => Failure::Singular { t: f.t, condition: Cow::Owned(text), value: f.value },
        abi::fault::SINGULAR_MATRIX => Failure::SingularMatrix { t: f.t, matrix: Cow::Owned(text), column: f.index },
        abi::fault::NON_FINITE => Failure::NonFinite { t: f.t, index: f.index },
        abi::fault::CONSTRAINT_VIOLATED => Failure::ConstraintViolated { constraint: Cow::Owned(text), residual: f.value, tolerance: f.bound },
        abi::fault::DIMENSION => Failure::Dimension { argument: intern(&text), expected: f.expected, got: f.got },
        _ => Failure::Missing { function: intern(&text) },
    }
}

impl Loaded {
    /// Calls `which` of formulation `index` with `inputs` and `outputs`; the margin on success.
    fn call(&self, which: u32, index: usize, t: f64, inputs: [&[f64]; 3], outputs: [&mut [f64]; 2], stabilization: (f64, f64)) -> Result<f64, Failure> {
        let inputs = inputs.map(|s| abi::Input { ptr: s.as_ptr(), len: s.len() });
        let outputs = outputs.map(|s| abi::Output { ptr: s.as_mut_ptr(), len: s.len() });
        let mut margin = 0.0;
        let mut fault = abi::Fault { kind: 0, t: 0.0, value: 0.0, bound: 0.0, index: 0, expected: 0, got: 0, text: std::ptr::null(), text_len: 0 };
        // SAFETY: three input and two output slices, from distinct Rust borrows, valid for the
        // call; `margin` and `fault` are valid. The library's code reads and writes only those.
        let code = unsafe { (self.call)(which, index, t, inputs.as_ptr(), outputs.as_ptr(), stabilization.0, stabilization.1, &mut margin, &mut fault) };
        if code == 0 { Ok(margin) } else { Err(decode(&fault)) }
    }
}

/// A formulation of the library.
struct NativeFormulation {
    loaded: Arc<Loaded>,
    index: usize,
}

/// The model-level functions of the library.
struct NativeModel {
    loaded: Arc<Loaded>,
}

use abi::function as f;

impl FormulationFunctions for NativeFormulation {
    fn rhs(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64]) -> Result<(), Failure> {
        self.loaded.call(f::RHS, self.index, t, [state, params, g_i], [dstate, &mut []], (0.0, 0.0)).map(drop)
    }
    fn rhs_baumgarte(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64], alpha: f64, beta: f64) -> Result<(), Failure> {
        self.loaded.call(f::RHS_BAUMGARTE, self.index, t, [state, params, g_i], [dstate, &mut []], (alpha, beta)).map(drop)
    }
    fn initial_state(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], state: &mut [f64], g_i: &mut [f64]) -> Result<(), Failure> {
        self.loaded.call(f::INITIAL_STATE, self.index, t, [q, qdot, params], [state, g_i], (0.0, 0.0)).map(drop)
    }
    fn velocities(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], q: &mut [f64], qdot: &mut [f64]) -> Result<(), Failure> {
        self.loaded.call(f::VELOCITIES, self.index, t, [state, params, g_i], [q, qdot], (0.0, 0.0)).map(drop)
    }
    fn matrix(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.loaded.call(f::MATRIX, self.index, t, [state, params, g_i], [out, &mut []], (0.0, 0.0)).map(drop)
    }
    fn singular_margin(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64]) -> Result<f64, Failure> {
        self.loaded.call(f::SINGULAR_MARGIN, self.index, t, [state, params, g_i], [&mut [], &mut []], (0.0, 0.0))
    }
    fn jacobian(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64], jac: &mut [f64]) -> Result<(), Failure> {
        self.loaded.call(f::JACOBIAN, self.index, t, [state, params, g_i], [dstate, jac], (0.0, 0.0)).map(drop)
    }
    fn parameter_jacobian(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64], jac: &mut [f64]) -> Result<(), Failure> {
        self.loaded.call(f::PARAMETER_JACOBIAN, self.index, t, [state, params, g_i], [dstate, jac], (0.0, 0.0)).map(drop)
    }
}

impl NativeModel {
    fn point(&self, which: u32, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.loaded.call(which, 0, t, [q, qdot, params], [out, &mut []], (0.0, 0.0)).map(drop)
    }
}

impl ModelFunctions for NativeModel {
    fn energy(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.point(f::ENERGY, t, q, qdot, params, out)
    }
    fn work_rate(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.point(f::WORK_RATE, t, q, qdot, params, out)
    }
    fn momenta(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.point(f::MOMENTA, t, q, qdot, params, out)
    }
    fn constraint_residuals(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.point(f::CONSTRAINT_RESIDUALS, t, q, qdot, params, out)
    }
    fn position_residuals(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.point(f::POSITION_RESIDUALS, t, q, qdot, params, out)
    }
    fn event_values(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.point(f::EVENT_VALUES, t, q, qdot, params, out)
    }
    fn event_resets(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.point(f::EVENT_RESETS, t, q, qdot, params, out)
    }
}

#[cfg(test)]
mod tests {
    /// The carried `seam` sources are the crate's files, every one of them.
    #[test]
    fn seam_sources_are_the_seam_crate() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../runtime/seam/src");
        let mut files: Vec<String> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        files.sort();
        let mut carried: Vec<String> = super::SEAM_SOURCES.iter().map(|(n, _)| n.to_string()).collect();
        carried.sort();
        assert_eq!(files, carried);
        for (name, text) in super::SEAM_SOURCES {
            assert_eq!(std::fs::read_to_string(dir.join(name)).unwrap(), text, "{name}");
        }
    }

    /// Failure names survive the trip, each kept once.
    #[test]
    fn interned_names_are_shared() {
        let a = super::intern("dstate");
        let b = super::intern(&String::from("dstate"));
        assert!(std::ptr::eq(a, b));
        assert_eq!(a, "dstate");
    }
}
