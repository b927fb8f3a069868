//! The README's commands leave the checkout as it was (`git status` clean): every output path
//! they name (`-o PATH`, `--out DIR`, `--animate PAGE`) in a shell block is outside it or
//! ignored by git, and neither a tracked file nor a directory holding tracked files. (The text
//! names the commands that regenerate `docs/` on purpose, outside the blocks.)

use std::process::Command;

/// The output paths named in the README's ```sh blocks.
fn output_paths(readme: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut in_block = false;
    for line in readme.lines() {
        if line.trim_start().starts_with("```") {
            in_block = line.trim() == "```sh" && !in_block;
            continue;
        }
        if !in_block {
            continue;
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        for w in words.windows(2) {
            if w[0] == "-o" || w[0] == "--out" || w[0] == "--animate" {
                out.push(w[1].to_string());
            }
        }
    }
    out
}

#[test]
fn readme_commands_write_only_untracked_paths() {
    let root = env!("CARGO_MANIFEST_DIR");
    let readme = std::fs::read_to_string(format!("{root}/README.md")).unwrap();
    let paths = output_paths(&readme);
    assert!(paths.len() >= 3, "the README's commands name their outputs: {paths:?}");
    for path in paths {
        // Outside the checkout nothing is tracked.
        if std::path::Path::new(&path).is_absolute() && !path.starts_with(root) {
            continue;
        }
        let listed = Command::new("git").args(["ls-files", "--", &path]).current_dir(root).output().expect("git runs in a checkout");
        assert!(listed.status.success());
        let tracked = String::from_utf8_lossy(&listed.stdout);
        assert!(tracked.trim().is_empty(), "the README's command writes `{path}`, which holds tracked files:\n{tracked}");
        // And `git status` does not list it: it is ignored.
        let ignored = Command::new("git").args(["check-ignore", "-q", "--no-index", "--", &path]).current_dir(root).status().expect("git runs in a checkout");
        assert!(ignored.success(), "the README's command writes `{path}`, which `git status` would then list: write under `target/` or outside the checkout");
    }
}

/// The scan itself finds a tracked target when there is one.
#[test]
fn a_tracked_target_would_be_found() {
    let paths = output_paths("text\n```sh\ncargo run -p runtime --bin sweep -- m --out docs/plots\n```\n--out ignored\n");
    assert_eq!(paths, ["docs/plots"]);
    let listed = Command::new("git").args(["ls-files", "--", "docs/plots"]).current_dir(env!("CARGO_MANIFEST_DIR")).output().unwrap();
    assert!(!String::from_utf8_lossy(&listed.stdout).trim().is_empty());
    // A new file at the root is not ignored: `git status` would list it.
    let ignored =
        Command::new("git").args(["check-ignore", "-q", "--no-index", "--", "cart_pendulum.rs"]).current_dir(env!("CARGO_MANIFEST_DIR")).status().unwrap();
    assert!(!ignored.success());
}

/// The relative links of a markdown page: `[text](target)`, without `http` and without the
/// `#anchor` part.
fn relative_links(page: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = page;
    while let Some(i) = rest.find("](") {
        rest = &rest[i + 2..];
        let Some(end) = rest.find(')') else { break };
        let target = &rest[..end];
        if !target.starts_with("http") && !target.starts_with('#') && !target.contains(' ') {
            out.push(target.split('#').next().unwrap().to_string());
        }
    }
    out
}

/// Every page a reader reaches from the README (the README, ARCHITECTURE.md and `docs/*.md`)
/// links only to files the checkout holds: the pages were split out of the README, and a link
/// left pointing at the old place is a dead end for a reader.
#[test]
fn the_pages_link_to_files_that_exist() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut pages = vec![root.join("README.md"), root.join("ARCHITECTURE.md")];
    for entry in std::fs::read_dir(root.join("docs")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "md") {
            pages.push(path);
        }
    }
    let mut checked = 0;
    for page in &pages {
        let text = std::fs::read_to_string(page).unwrap();
        for link in relative_links(&text) {
            let target = page.parent().unwrap().join(&link);
            assert!(target.exists(), "{} links to `{link}`, which does not exist", page.strip_prefix(root).unwrap().display());
            checked += 1;
        }
    }
    assert!(checked >= 30, "{checked} links checked");
}

#[test]
fn links_are_read_from_markdown() {
    let links = relative_links("see [a](docs/a.md#x), [b](https://x.y), ![c](plots/c.svg) and [d](#here)");
    assert_eq!(links, ["docs/a.md", "plots/c.svg"]);
}

/// The README's first command builds the generator and its dependencies with the features the
/// test command's build turns on, so that the tests reuse its build (the feature pins of
/// `generator/Cargo.toml`): every package and feature set `cargo tree` shows for the generator
/// alone is one the workspace's build has. (Cargo unifies features over what a command builds:
/// without the pins, six packages differed, the generator was compiled again.)
#[test]
fn the_test_command_reuses_the_first_command_s_build() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    assert!(readme.contains("cargo run --release -p generator -- ") && readme.contains("cargo test --workspace --release"), "the README's two commands");
    let tree = |args: &[&str]| -> std::collections::BTreeSet<String> {
        let out = std::process::Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
            .arg("tree")
            .args(args)
            .args(["--format", "{p} [{f}]", "--prefix", "none"])
            .current_dir(root)
            .output()
            .expect("cargo runs");
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8_lossy(&out.stdout).lines().map(|l| l.replace(" (*)", "").replace(" (proc-macro)", "")).filter(|l| !l.is_empty()).collect()
    };
    let alone = tree(&["-p", "generator", "--edges", "normal,build"]);
    let workspace = tree(&["--workspace", "--edges", "normal,build,dev"]);
    let apart: Vec<&String> = alone.difference(&workspace).collect();
    assert!(alone.len() > 50, "{alone:?}");
    assert!(
        apart.is_empty(),
        "built by the first command with features the tests' build changes (pin the workspace's features in generator/Cargo.toml): {apart:?}"
    );
}
