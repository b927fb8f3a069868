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
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../runtime/seam/src/lib.rs");
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
