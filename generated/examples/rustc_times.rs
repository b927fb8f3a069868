//! rustc time per committed module, each compiled alone as a library at opt-level 3 with
//! `-D warnings` (against the seam crate, its one dependency, built first), best of 3.
//!
//! `cargo run --release -p generated --example rustc_times` writes `docs/benchmarks/rustc.json`
//! (the table of `docs/benchmarks.md`, checked by `tests/it/figures.rs`) and prints it.

use std::time::Instant;

#[path = "../../generator/tests/support/rustc.rs"]
mod rustc_support;

const COMMAND: &str = "cargo run --release -p generated --example rustc_times";

fn main() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let mut files: Vec<std::path::PathBuf> = std::fs::read_dir(format!("{root}/generated/src"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| !matches!(p.file_name().and_then(|n| n.to_str()), Some("lib.rs" | "registry.rs")))
        .collect();
    files.sort();
    let out = tempfile::tempdir().unwrap();
    rustc_support::seam_rlib();
    let mut rows = Vec::new();
    for file in &files {
        let mut best = f64::INFINITY;
        for _ in 0..3 {
            let start = Instant::now();
            let status = rustc_support::rustc()
                .args(["--crate-type", "lib", "-C", "opt-level=3", "-D", "warnings", "--out-dir"])
                .arg(out.path())
                .arg(file)
                .status()
                .unwrap();
            assert!(status.success(), "{} compiles", file.display());
            best = best.min(start.elapsed().as_secs_f64());
        }
        let lines = std::fs::read_to_string(file).unwrap().lines().count();
        let module = file.file_stem().unwrap().to_string_lossy().into_owned();
        eprintln!("{module}: {best:.2} s");
        rows.push(vec![module, lines.to_string(), format!("{best:.2} s")]);
    }
    let columns = ["module", "lines", "rustc (best of 3)"];
    let json = serde_json::json!({ "command": COMMAND, "columns": columns, "rows": rows });
    std::fs::write(format!("{root}/docs/benchmarks/rustc.json"), serde_json::to_string_pretty(&json).unwrap() + "\n").unwrap();
    println!("{}", std::iter::once(columns.join(" | ")).chain(rows.iter().map(|r| r.join(" | "))).collect::<Vec<_>>().join("\n"));
}
