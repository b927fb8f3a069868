//! Output files written atomically: the bytes go to a temporary file in the target's
//! directory (`tempfile`), which is then renamed over the target, so a failure midway leaves the
//! old file as it was and never a half-written one.
//!
//! ```
//! let dir = std::env::temp_dir().join(format!("runtime-output-doc-{}", std::process::id()));
//! let path = dir.join("records.json");
//! runtime::output::write_atomic(&path, b"[]").unwrap();
//! assert_eq!(std::fs::read_to_string(&path).unwrap(), "[]");
//! std::fs::remove_dir_all(&dir).unwrap();
//! ```

use std::io::Write;
use std::path::{Path, PathBuf};

/// Why an output file could not be written (the target is unchanged).
#[derive(Debug, thiserror::Error)]
#[error("cannot write `{path}`: {source}")]
pub struct OutputError {
    pub path: PathBuf,
    #[source]
    pub source: std::io::Error,
}

/// Writes `bytes` to `path` atomically, creating its directory when missing.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let err = |source| OutputError { path: path.to_path_buf(), source };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(err)?;
    let mut tmp = tempfile::NamedTempFile::new_in(&dir).map_err(err)?;
    tmp.write_all(bytes).and_then(|()| tmp.as_file().sync_all()).map_err(err)?;
    // The temporary file is private (0600); the result gets the target's permissions, or a
    // new file's usual ones.
    let permissions = match std::fs::metadata(path) {
        Ok(m) => m.permissions(),
        Err(_) => new_file_permissions(tmp.as_file()).map_err(err)?,
    };
    tmp.as_file().set_permissions(permissions).map_err(err)?;
    tmp.persist(path).map_err(|e| err(e.error))?;
    Ok(())
}

/// Read and write for everyone the process's umask allows (what `File::create` gives).
#[cfg(unix)]
fn new_file_permissions(_file: &std::fs::File) -> std::io::Result<std::fs::Permissions> {
    use std::os::unix::fs::PermissionsExt;
    // The umask is only readable by setting it; a file created the usual way shows it.
    let dir = tempfile::tempdir()?;
    let p = dir.path().join("probe");
    std::fs::File::create(&p)?;
    let mode = std::fs::metadata(&p)?.permissions().mode();
    Ok(std::fs::Permissions::from_mode(mode & 0o777))
}

#[cfg(not(unix))]
fn new_file_permissions(file: &std::fs::File) -> std::io::Result<std::fs::Permissions> {
    Ok(file.metadata()?.permissions())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_leaves_the_old_file() {
        let dir = std::env::temp_dir().join(format!("runtime-output-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("table.csv");
        write_atomic(&path, b"old").unwrap();
        // A directory where the file should be: the rename fails, nothing else changes.
        let blocked = dir.join("blocked");
        std::fs::create_dir_all(blocked.join("inner")).unwrap();
        assert!(write_atomic(&blocked, b"new").is_err());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        let leftovers: Vec<_> =
            std::fs::read_dir(&dir).unwrap().filter_map(|e| e.ok()).filter(|e| e.file_name().to_string_lossy().starts_with(".tmp")).collect();
        assert!(leftovers.is_empty(), "temporary files left behind: {leftovers:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Results are readable like any file the user makes, not private like a temporary one.
    #[cfg(unix)]
    #[test]
    fn a_new_file_gets_the_usual_permissions_and_an_old_one_keeps_its_own() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let usual = dir.path().join("usual");
        std::fs::File::create(&usual).unwrap();
        let path = dir.path().join("out.csv");
        write_atomic(&path, b"a").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&path), mode(&usual));
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o640)).unwrap();
        write_atomic(&path, b"b").unwrap();
        assert_eq!(mode(&path), 0o640);
    }
}
