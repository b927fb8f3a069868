//! Where built libraries live: a folder of the user's own (`MULTIBODY_CACHE_DIR`, or
//! `multibody` in the platform's cache folder: `~/.cache/multibody` on Linux), never inside a
//! checkout. A library is named by its key, the SHA-256 of what it is built from; it is built
//! under an exclusive lock on its key, in a private temporary folder, and renamed into place, so
//! two processes never see half a library and never get each other's.

use crate::Error;
use sha2::{Digest, Sha256};
use std::fs::{self, File};
use std::path::{Path, PathBuf};

/// The environment variable that names the cache folder.
pub const CACHE_VARIABLE: &str = "MULTIBODY_CACHE_DIR";

/// The cache folder: `MULTIBODY_CACHE_DIR` when set, else `multibody` in the platform's cache
/// folder.
pub fn default_folder() -> Result<PathBuf, Error> {
    if let Some(dir) = std::env::var_os(CACHE_VARIABLE).filter(|d| !d.is_empty()) {
        return Ok(PathBuf::from(dir));
    }
    dirs::cache_dir().map(|d| d.join("multibody")).ok_or(Error::NoCacheFolder)
}

/// The SHA-256 of `parts` (each length-prefixed, so no two lists of parts share a key), as 64
/// hex digits: the key of a library built from them.
///
/// ```
/// let a = native::cache::key(&[b"fn a() {}"]);
/// assert_eq!(a.len(), 64);
/// assert_ne!(a, native::cache::key(&[b"fn b() {}"]));
/// assert_ne!(native::cache::key(&[b"ab", b"c"]), native::cache::key(&[b"a", b"bc"]));
/// assert_eq!(a, native::cache::key(&[b"fn a() {}"]));
/// ```
pub fn key(parts: &[&[u8]]) -> String {
    let mut hash = Sha256::new();
    for part in parts {
        hash.update((part.len() as u64).to_le_bytes());
        hash.update(part);
    }
    hash.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// The path of the library of `key` in `folder`.
pub fn library_path(folder: &Path, key: &str) -> PathBuf {
    folder.join(format!("{}model-{key}{}", std::env::consts::DLL_PREFIX, std::env::consts::DLL_SUFFIX))
}

/// Creates the cache folder (private to the user) if it is missing, and refuses one that another
/// user could write to: whoever can write there chooses the code this process runs.
pub fn prepare(folder: &Path) -> Result<(), Error> {
    let refuse = |problem: &str| Error::Cache { folder: folder.to_path_buf(), problem: problem.to_string() };
    if fs::symlink_metadata(folder).is_err() {
        let mut builder = fs::DirBuilder::new();
        builder.recursive(true);
        #[cfg(unix)]
        std::os::unix::fs::DirBuilderExt::mode(&mut builder, 0o700);
        builder.create(folder).map_err(|e| Error::Io { path: folder.to_path_buf(), source: e })?;
    }
    let meta = fs::symlink_metadata(folder).map_err(|e| Error::Io { path: folder.to_path_buf(), source: e })?;
    if meta.file_type().is_symlink() {
        return Err(refuse("it is a symbolic link; name the real folder"));
    }
    if !meta.is_dir() {
        return Err(refuse("it is not a folder"));
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        // SAFETY: `geteuid` has no preconditions and cannot fail.
        let me = unsafe { libc::geteuid() };
        if meta.uid() != me {
            return Err(refuse(&format!("it belongs to user {}, not to this user ({me})", meta.uid())));
        }
        if meta.mode() & 0o022 != 0 {
            return Err(refuse(&format!("other users can write to it (mode {:o}); `chmod go-w` it", meta.mode() & 0o777)));
        }
    }
    Ok(())
}

/// Holds the exclusive lock on `key` in `folder` while it lives (released when dropped).
pub struct KeyLock {
    _file: File,
}

/// Waits for the exclusive lock on `key` in `folder`.
pub fn lock(folder: &Path, key: &str) -> Result<KeyLock, Error> {
    let path = folder.join(format!("model-{key}.lock"));
    let file = fs::OpenOptions::new().create(true).truncate(false).write(true).open(&path).map_err(|e| Error::Io { path: path.clone(), source: e })?;
    file.lock().map_err(|e| Error::Io { path, source: e })?;
    Ok(KeyLock { _file: file })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A folder other users can write to, or a symbolic link, is refused with what to do.
    #[cfg(unix)]
    #[test]
    fn shared_or_linked_folders_are_refused() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let open = dir.path().join("open");
        fs::create_dir(&open).unwrap();
        fs::set_permissions(&open, fs::Permissions::from_mode(0o777)).unwrap();
        let e = prepare(&open).unwrap_err().to_string();
        assert!(e.contains("other users can write to it") && e.contains("chmod go-w"), "{e}");
        let link = dir.path().join("link");
        std::os::unix::fs::symlink(dir.path(), &link).unwrap();
        let e = prepare(&link).unwrap_err().to_string();
        assert!(e.contains("symbolic link"), "{e}");
        let made = dir.path().join("a/b/cache");
        prepare(&made).unwrap();
        assert_eq!(fs::metadata(&made).unwrap().permissions().mode() & 0o777, 0o700);
    }

    /// The key covers the source byte for byte.
    #[test]
    fn keys_differ_by_one_byte() {
        assert_ne!(key(&[b"let a = 1;"]), key(&[b"let a = 2;"]));
        assert!(key(&[b"x"]).bytes().all(|b| b.is_ascii_hexdigit()));
    }
}
