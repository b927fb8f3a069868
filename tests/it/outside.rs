//! The example crate outside the workspace (`examples/outside`, its own Cargo project that
//! depends on the generator and the runtime by path): it builds, its tests pass, it prints its
//! model's comparison table, and it compiles none of the project's committed modules, and
//! neither clap nor mimalloc (the generator binary's).
//!
//! The nested cargo commands share the workspace's target directory (cargo releases its lock
//! before the tests run), so the generator, the runtime and their dependencies, already built
//! for the workspace's tests, are not built again.

use std::path::Path;
use std::process::Command;

fn cargo(args: &[&str]) -> std::process::Output {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
        .args(args)
        .arg("--manifest-path")
        .arg(root.join("examples/outside/Cargo.toml"))
        .env("CARGO_TARGET_DIR", root.join("target"))
        .output()
        .expect("cargo runs")
}

#[test]
fn the_example_outside_the_workspace_builds_tests_runs_and_uses_no_committed_module() {
    let tree = cargo(&["tree", "--edges", "normal,build", "--prefix", "none"]);
    assert!(tree.status.success(), "{}", String::from_utf8_lossy(&tree.stderr));
    let tree = String::from_utf8_lossy(&tree.stdout);
    assert!(tree.lines().any(|l| l.starts_with("runtime v")) && tree.lines().any(|l| l.starts_with("generator v")), "{tree}");
    assert!(tree.lines().any(|l| l.starts_with("seam v")), "{tree}");
    assert!(!tree.lines().any(|l| l.starts_with("generated v")), "the committed modules are not a dependency:\n{tree}");
    // A build script compiles the library only: the generator binary's command line and
    // allocator stay with the binary.
    for binary_only in ["clap v", "mimalloc v"] {
        assert!(!tree.lines().any(|l| l.starts_with(binary_only)), "a build.rs user compiles {binary_only}:\n{tree}");
    }

    let test = cargo(&["test", "--release"]);
    let log = String::from_utf8_lossy(&test.stdout);
    assert!(test.status.success(), "{log}\n{}", String::from_utf8_lossy(&test.stderr));
    assert!(log.contains("the_damper_s_work_balances_the_energy ... ok") && log.contains("the_typed_functions_and_the_seam_agree ... ok"), "{log}");

    let run = cargo(&["run", "--release", "-q"]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let table = String::from_utf8_lossy(&run.stdout);
    for row in ["| lagrange | 5 | 2 |", "| kane | 5 | 2 |", "| reduced_volterra | 5 | 2 |"] {
        assert!(table.contains(row), "{row} in\n{table}");
    }
}

/// The crate outside resolves every package to a version the workspace's lock holds, so that
/// its nested build shares the workspace's artifacts: a newer `textwrap` in its lock (0.16.4,
/// through miette) once pulled in twenty ICU crates and built the generator again, two minutes
/// of the test command.
#[test]
fn the_crate_outside_locks_the_workspace_s_versions() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // (name, version) of every package of a Cargo.lock.
    let packages = |path: &str| -> std::collections::BTreeSet<(String, String)> {
        let text = std::fs::read_to_string(root.join(path)).unwrap();
        let value = |line: &str, key: &str| line.strip_prefix(key).map(|v| v.trim_matches('"').to_string());
        let lines: Vec<&str> = text.lines().collect();
        lines.windows(2).filter_map(|w| Some((value(w[0], "name = ")?, value(w[1], "version = ")?))).collect()
    };
    let workspace = packages("Cargo.lock");
    let outside = packages("examples/outside/Cargo.lock");
    let foreign: Vec<_> = outside.iter().filter(|(name, _)| name != "outside").filter(|p| !workspace.contains(*p)).collect();
    assert!(outside.len() > 50 && foreign.is_empty(), "versions the workspace does not lock (`cargo update --precise` them): {foreign:?}");
}

/// The JIT depends on the tapes and cranelift only: not on the generator (the symbolic core,
/// syn, miette, the URDF reader), whose tapes it compiles. `cargo tree` of the package, normal
/// edges, counts the crates it builds.
#[test]
fn the_jit_depends_on_the_tapes_and_cranelift_only() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
        .args(["tree", "-p", "jit", "--edges", "normal", "--prefix", "none"])
        .current_dir(root)
        .output()
        .expect("cargo runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let tree = String::from_utf8_lossy(&out.stdout);
    let crates: std::collections::BTreeSet<&str> = tree.lines().map(|l| l.trim_end_matches(" (*)")).filter(|l| !l.is_empty()).collect();
    let ours: Vec<&&str> = crates.iter().filter(|l| l.contains(" (/")).collect();
    assert_eq!(ours.len(), 2, "jit and tape only of this workspace: {ours:?}");
    assert!(ours.iter().any(|l| l.starts_with("tape v")), "{ours:?}");
    assert!(crates.len() <= 40, "jit builds {} crates:\n{tree}", crates.len());
}
