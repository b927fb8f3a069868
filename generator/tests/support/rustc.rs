//! Compiling emitted modules on their own with rustc, for tests and benchmarks: an emitted
//! module needs only the seam crate, built here once per process as an rlib.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// The seam crate as an rlib, built once per process into a scratch directory.
pub fn seam_rlib() -> &'static Path {
    static RLIB: OnceLock<PathBuf> = OnceLock::new();
    RLIB.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("seam-rlib-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a scratch directory");
        // From the generator's package or the workspace's.
        let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
        let src = [manifest.join("../runtime/seam/src/lib.rs"), manifest.join("runtime/seam/src/lib.rs")]
            .into_iter()
            .find(|p| p.exists())
            .expect("runtime/seam/src/lib.rs");
        let out = Command::new("rustc")
            .args(["--edition", "2024", "--crate-type", "rlib", "--crate-name", "seam", "-C", "opt-level=3", "--out-dir"])
            .arg(&dir)
            .arg(&src)
            .output()
            .expect("rustc runs");
        assert!(out.status.success(), "the seam crate compiles:\n{}", String::from_utf8_lossy(&out.stderr));
        dir.join("libseam.rlib")
    })
}

/// `rustc` with the seam crate available as `seam`.
pub fn rustc() -> Command {
    let rlib = seam_rlib();
    let mut cmd = Command::new("rustc");
    cmd.args(["--edition", "2024"]).arg("--extern").arg(format!("seam={}", rlib.display()));
    cmd
}

/// A `main` for an emitted module: every formulation's `rhs` at three fixed states (state
/// element `i` of state `k` is `0.3 sin(1.7 i + k)`, momentum `i` is `0.1 (i + k + 1)`), one
/// line per call, `name k bits...` (or `name k error`).
#[allow(dead_code)]
pub const PRINT_RHS_MAIN: &str = r#"
fn main() {
    let m = model();
    for f in &m.formulations {
        for k in 0..3usize {
            let n = f.states();
            let y: Vec<f64> = (0..n).map(|i| 0.3 * ((i as f64) * 1.7 + k as f64).sin()).collect();
            let g: Vec<f64> = (0..m.ignorable.len()).map(|i| 0.1 * (i + k + 1) as f64).collect();
            let mut d = vec![0.0; n];
            match f.rhs(0.25, &y, &m.default_params, &g, &mut d) {
                Ok(()) => println!("{} {} {}", f.name(), k, d.iter().map(|x| x.to_bits().to_string()).collect::<Vec<_>>().join(" ")),
                Err(_) => println!("{} {} error", f.name(), k),
            }
        }
    }
}
"#;

/// `code` (an emitted module) compiled with [`PRINT_RHS_MAIN`] and `flags` in `dir` and run:
/// `(formulation, k, rates)` per line it prints (`None` for a refused call).
#[allow(dead_code)]
pub fn printed_rates(dir: &Path, name: &str, code: &str, flags: &[&str]) -> Vec<(String, usize, Option<Vec<f64>>)> {
    let source = dir.join(format!("{name}.rs"));
    std::fs::write(&source, format!("{code}{PRINT_RHS_MAIN}")).expect("the source is written");
    let binary = dir.join(name);
    let out = rustc().args(["--crate-type", "bin", "-A", "warnings"]).args(flags).arg("-o").arg(&binary).arg(&source).output().expect("rustc runs");
    assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
    let printed = Command::new(&binary).output().expect("the program runs");
    assert!(printed.status.success(), "{name} runs");
    String::from_utf8(printed.stdout)
        .expect("text")
        .lines()
        .map(|line| {
            let mut words = line.split_whitespace();
            let (form, k) = (words.next().unwrap().to_string(), words.next().unwrap().parse().unwrap());
            let rest: Vec<&str> = words.collect();
            let rates = (rest != ["error"]).then(|| rest.iter().map(|b| f64::from_bits(b.parse().unwrap())).collect());
            (form, k, rates)
        })
        .collect()
}
