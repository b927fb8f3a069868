//! The crates of a user's own beside the workspace (`examples/outside` and
//! `examples/downstream`, each its own Cargo project that depends on the generator in build.rs
//! and the runtime by path): they build, their tests pass, they print their model's comparison
//! table, and they compile none of the project's committed modules, and neither clap nor
//! mimalloc (the generator binary's).
//!
//! The nested cargo commands share the workspace's target directory (cargo releases its lock
//! before the tests run), and the two crates lock the same versions with the same features: the
//! generator for their build scripts is built once for both.

use std::path::Path;
use std::process::Command;

/// `cargo ARGS` on the crate `examples/<name>`.
fn cargo(name: &str, args: &[&str]) -> std::process::Output {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
        .args(args)
        .arg("--manifest-path")
        .arg(root.join(format!("examples/{name}/Cargo.toml")))
        .env("CARGO_TARGET_DIR", root.join("target"))
        .output()
        .expect("cargo runs")
}

/// The crate `name` builds with the generator in its build script and nothing of the project's
/// committed modules or the generator binary; its tests (each of `tests` passing) and its
/// comparison table (each of `rows` in it).
fn builds_tests_and_runs(name: &str, tests: &[&str], rows: &[&str]) {
    let tree = cargo(name, &["tree", "--edges", "normal,build", "--prefix", "none"]);
    assert!(tree.status.success(), "{name}: {}", String::from_utf8_lossy(&tree.stderr));
    let tree = String::from_utf8_lossy(&tree.stdout);
    assert!(tree.lines().any(|l| l.starts_with("runtime v")) && tree.lines().any(|l| l.starts_with("generator v")), "{tree}");
    assert!(tree.lines().any(|l| l.starts_with("seam v")), "{tree}");
    assert!(!tree.lines().any(|l| l.starts_with("generated v")), "{name}: the committed modules are not a dependency:\n{tree}");
    // A build script compiles the library only: the generator binary's command line and
    // allocator stay with the binary.
    for binary_only in ["clap v", "mimalloc v"] {
        assert!(!tree.lines().any(|l| l.starts_with(binary_only)), "{name}: a build.rs user compiles {binary_only}:\n{tree}");
    }

    let test = cargo(name, &["test", "--release"]);
    let log = String::from_utf8_lossy(&test.stdout);
    let errors = String::from_utf8_lossy(&test.stderr);
    assert!(test.status.success(), "{name}: {log}\n{errors}");
    // Its Cargo.toml optimizes the generator (the builder's warning, where its build script ran).
    assert!(!errors.contains("runs unoptimized"), "{name}: {errors}");
    for t in tests {
        assert!(log.contains(&format!("{t} ... ok")), "{name}: {t} in\n{log}");
    }

    let run = cargo(name, &["run", "--release", "-q"]);
    assert!(run.status.success(), "{name}: {}", String::from_utf8_lossy(&run.stderr));
    let table = String::from_utf8_lossy(&run.stdout);
    for row in rows {
        assert!(table.contains(row), "{name}: {row} in\n{table}");
    }
}

#[test]
fn the_crates_of_a_user_s_own_build_test_run_and_use_no_committed_module() {
    builds_tests_and_runs(
        "outside",
        &["the_damper_s_work_balances_the_energy", "the_typed_functions_and_the_seam_agree"],
        &["| lagrange | 5 | 2 |", "| kane | 5 | 2 |", "| reduced_volterra | 5 | 2 |"],
    );
    builds_tests_and_runs(
        "downstream",
        &[
            "the_runtime_integrates_the_crate_s_own_model_and_its_invariants_hold",
            "the_four_formulations_agree_on_the_crane",
            "a_wrong_slice_length_and_an_inadmissible_state_are_typed_errors",
        ],
        &["| lagrange |", "| reduced_volterra | 5 | 2 |"],
    );
}

/// The crates beside the workspace resolve every package to a version the workspace's lock
/// holds, so that their nested builds share the workspace's artifacts: a newer `textwrap` in its lock (0.16.4,
/// through miette) once pulled in twenty ICU crates and built the generator again, two minutes
/// of the test command.
#[test]
fn the_crates_beside_the_workspace_lock_the_workspace_s_versions() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // (name, version) of every package of a Cargo.lock.
    let packages = |path: &str| -> std::collections::BTreeSet<(String, String)> {
        let text = std::fs::read_to_string(root.join(path)).unwrap();
        let value = |line: &str, key: &str| line.strip_prefix(key).map(|v| v.trim_matches('"').to_string());
        let lines: Vec<&str> = text.lines().collect();
        lines.windows(2).filter_map(|w| Some((value(w[0], "name = ")?, value(w[1], "version = ")?))).collect()
    };
    let workspace = packages("Cargo.lock");
    for name in ["outside", "downstream"] {
        let own = packages(&format!("examples/{name}/Cargo.lock"));
        let foreign: Vec<_> = own.iter().filter(|(n, _)| n != name).filter(|p| !workspace.contains(*p)).collect();
        assert!(own.len() > 50 && foreign.is_empty(), "{name}: versions the workspace does not lock (`cargo update --precise` them): {foreign:?}");
    }
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
