//! The stated minimum Rust version is true: the workspace's `rust-version` is at least the
//! largest `rust-version` among the locked dependencies, and the README states the same.

/// `1.89` as `[1, 89, 0]`: three components, so that `1.89` and `1.89.0` compare equal.
fn version(text: &str) -> [u32; 3] {
    let mut out = [0; 3];
    for (slot, part) in out.iter_mut().zip(text.split('.')) {
        *slot = part.parse().unwrap_or(0);
    }
    out
}

#[test]
fn the_stated_rust_version_covers_every_locked_dependency() {
    let root = env!("CARGO_MANIFEST_DIR");
    let out = std::process::Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
        .args(["metadata", "--format-version", "1", "--locked"])
        .current_dir(root)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let packages = meta["packages"].as_array().unwrap();
    let ours = packages.iter().find(|p| p["name"] == "multibody").unwrap()["rust_version"].as_str().unwrap().to_string();
    let (needed, by) = packages.iter().filter_map(|p| Some((version(p["rust_version"].as_str()?), p["name"].as_str()?.to_string()))).max().unwrap();
    assert!(version(&ours) >= needed, "rust-version {ours} is below {needed:?}, which {by} needs");
    let readme = std::fs::read_to_string(format!("{root}/README.md")).unwrap();
    assert!(readme.contains(&format!("(Rust {ours} or later)")), "the README states another version than {ours}");
}
