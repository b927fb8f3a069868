//! The attacks of the issue "Never, round 2", held so that they stay fixed: outputs onto the
//! files a run reads (by name, by a symlink, by a hard link, whatever the flag), and outputs
//! through a symlink another user planted in a shared sticky folder.

use crate::common::multibody;
use std::path::Path;

/// A folder holding `m.ron` (scene 1) and `u.csv` (an input series for the inverted pendulum's force `F`).
fn folder() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let models = concat!(env!("CARGO_MANIFEST_DIR"), "/models");
    std::fs::copy(format!("{models}/cart_pendulum.ron"), dir.path().join("m.ron")).unwrap();
    std::fs::copy(format!("{models}/inverted_pendulum.ron"), dir.path().join("w.ron")).unwrap();
    std::fs::write(dir.path().join("u.csv"), "t,value\n0,0\n1,0.5\n").unwrap();
    dir
}

fn refused(dir: &Path, args: &[&str], words: &str) {
    let out = multibody(dir, args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains(words), "{args:?}: exit {:?}: {err}", out.status.code());
}

/// No output of any command may be a file the run reads, by any path, whatever the flag.
#[test]
fn no_output_is_a_file_the_run_reads() {
    let dir = folder();
    let d = dir.path();
    let model = std::fs::read(d.join("m.ron")).unwrap();
    let series = std::fs::read(d.join("u.csv")).unwrap();
    std::os::unix::fs::symlink(d.join("m.ron"), d.join("link.json")).unwrap();
    std::fs::hard_link(d.join("m.ron"), d.join("hard.html")).unwrap();
    let reads = "which this run reads";
    for output in ["m.ron", "./m.ron", "link.json", "hard.html"] {
        refused(d, &["compare", "m.ron", "--t-end", "0.1", "--repeats", "1", "--json", output], reads);
        refused(d, &["simulate", "m.ron", "--t-end", "0.1", "--animate", output], reads);
    }
    refused(d, &["generate", "m.ron", "-o", "m.ron", "--force"], "model file itself");
    refused(d, &["generate", "m.ron", "-o", "hard.html", "--force"], reads);
    refused(d, &["simulate", "w.ron", "--t-end", "0.1", "--input", "F=u.csv", "--animate", "u.csv"], reads);
    assert_eq!(std::fs::read(d.join("m.ron")).unwrap(), model);
    assert_eq!(std::fs::read(d.join("u.csv")).unwrap(), series);
    assert!(std::fs::symlink_metadata(d.join("link.json")).unwrap().file_type().is_symlink());
    // Another output path is fine.
    let out = multibody(d, &["compare", "m.ron", "--t-end", "0.1", "--repeats", "1", "--json", "records.json"]);
    crate::common::ok(&out);
    assert!(d.join("records.json").is_file());
}

/// A symlink planted by another user in a sticky folder every user may write to (`/tmp`, here a
/// copy of it) is not followed: the file it points to keeps its bytes. The tests run as root,
/// as CI does: the link is given to another uid with `lchown`.
#[test]
fn a_link_planted_by_another_user_in_a_sticky_folder_is_not_followed() {
    use std::os::unix::fs::PermissionsExt;
    let dir = folder();
    let d = dir.path();
    let shared = d.join("shared");
    std::fs::create_dir(&shared).unwrap();
    std::fs::set_permissions(&shared, std::fs::Permissions::from_mode(0o1777)).unwrap();
    let victim = d.join("victim.txt");
    std::fs::write(&victim, "root's file").unwrap();
    let planted = shared.join("out.json");
    std::os::unix::fs::symlink(&victim, &planted).unwrap();
    std::os::unix::fs::lchown(&planted, Some(4242), Some(4242)).expect("lchown needs root (the tests run as root, as CI does)");
    let target = planted.to_str().unwrap();
    refused(d, &["compare", "m.ron", "--t-end", "0.1", "--repeats", "1", "--json", target], "symbolic link of another user");
    refused(d, &["simulate", "m.ron", "--t-end", "0.1", "--animate", target], "symbolic link of another user");
    refused(d, &["generate", "m.ron", "-o", shared.join("out.json").to_str().unwrap()], "symbolic link of another user");
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "root's file");
    // The user's own link there is followed, as the kernel would.
    let own = shared.join("own.json");
    std::os::unix::fs::symlink(d.join("mine.json"), &own).unwrap();
    std::fs::write(d.join("mine.json"), "").unwrap();
    crate::common::ok(&multibody(d, &["compare", "m.ron", "--t-end", "0.1", "--repeats", "1", "--json", own.to_str().unwrap()]));
    assert!(std::fs::read_to_string(d.join("mine.json")).unwrap().starts_with('['));
}
