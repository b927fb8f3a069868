//! Where built libraries live: a folder of the user's own (`MULTIBODY_CACHE_DIR`, or
//! `multibody` in the platform's cache folder: `~/.cache/multibody` on Linux), never inside a
//! checkout. A library is named by its key, the SHA-256 of what it is built from, and kept with
//! the SHA-256 of its own bytes; it is built under an exclusive lock on its key, in a private
//! temporary folder, and renamed into place, so two processes never see half a library and
//! never get each other's.
//!
//! Whoever can write to the folder chooses the code this process runs, so the folder is
//! trusted only as ssh trusts its own: [`Cache::open`] opens it once (`O_DIRECTORY |
//! O_NOFOLLOW`, so a symlink in its place is refused, trailing slash or not), checks the open
//! handle (the user's own, written by no one else) and every folder above it (the user's or
//! root's, written by no one else unless sticky, as `/tmp` is), and every later step goes
//! through that handle (`/proc/self/fd/N` on Linux): a folder swapped for another after the
//! check is never used. A library is opened, its bytes hashed and compared with the digest kept
//! beside it, and only then loaded, from that same open file: a truncated or foreign library
//! is never loaded, and is built again.

use crate::Error;
use sha2::{Digest, Sha256};
use std::fs::{self, File};
use std::io::Read;
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
    hex(&hash.finalize())
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// The file name of the library of `key`.
pub fn library_name(key: &str) -> String {
    format!("{}model-{key}{}", std::env::consts::DLL_PREFIX, std::env::consts::DLL_SUFFIX)
}

/// The file name of the digest of the library of `key`.
fn digest_name(key: &str) -> String {
    format!("model-{key}.sha256")
}

/// The prefix of the temporary folders in which the library of `key` is built.
pub fn build_prefix(key: &str) -> String {
    format!(".build-{key}-")
}

/// The cache folder, open and checked ([`Cache::open`]).
#[derive(Debug)]
pub struct Cache {
    /// The folder as the user named it, for messages.
    shown: PathBuf,
    /// The open folder: every step goes through it.
    dir: File,
}

impl Cache {
    /// Opens the cache folder `folder`, creating it (private to the user) if it is missing, and
    /// refuses one that another user could change, or that lies under a folder another user
    /// could change (see the module docs).
    pub fn open(folder: &Path) -> Result<Cache, Error> {
        let refuse = |problem: String| Error::Cache { folder: folder.to_path_buf(), problem };
        let name = folder.file_name().ok_or_else(|| refuse("it names no folder".into()))?;
        let parent = match folder.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if fs::symlink_metadata(folder).is_err() {
            let mut builder = fs::DirBuilder::new();
            builder.recursive(true);
            #[cfg(unix)]
            std::os::unix::fs::DirBuilderExt::mode(&mut builder, 0o700);
            builder.create(folder).map_err(|e| Error::Io { path: folder.to_path_buf(), source: e })?;
        }
        // The folders above, as they really are (a symlinked home is fine: its target is
        // checked), each opened below the one before without following a link.
        let above = fs::canonicalize(&parent).map_err(|e| Error::Io { path: parent.clone(), source: e })?;
        let mut at = secure::open_root().map_err(|e| Error::Io { path: "/".into(), source: e })?;
        secure::check_above(&at).map_err(|p| refuse(format!("the folder `/` {p}")))?;
        let mut walked = PathBuf::from("/");
        for part in above.components().skip(1) {
            walked.push(part);
            at = secure::open_below(&at, part.as_os_str()).map_err(|e| Error::Io { path: walked.clone(), source: e })?;
            secure::check_above(&at).map_err(|p| refuse(format!("the folder above it, `{}`, {p}", walked.display())))?;
        }
        let dir = secure::open_below(&at, name).map_err(|e| match e.raw_os_error() {
            Some(code) if secure::is_link_error(code) => refuse("it is a symbolic link; name the real folder".into()),
            _ => Error::Io { path: folder.to_path_buf(), source: e },
        })?;
        secure::check_own(&dir).map_err(refuse)?;
        Ok(Cache { shown: folder.to_path_buf(), dir })
    }

    /// The path of `name` in the folder, through the open handle.
    pub fn path_of(&self, name: &str) -> PathBuf {
        secure::through(&self.dir, &self.shown).join(name)
    }

    /// The path of the library of `key`, as the user would name it (for messages).
    pub fn shown_library(&self, key: &str) -> PathBuf {
        self.shown.join(library_name(key))
    }

    /// Waits for the exclusive lock on `key` (released when the lock is dropped).
    pub fn lock(&self, key: &str) -> Result<KeyLock, Error> {
        let path = self.path_of(&format!("model-{key}.lock"));
        let file = secure::create_private(&path).map_err(|e| Error::Io { path: self.shown.join(format!("model-{key}.lock")), source: e })?;
        file.lock().map_err(|e| Error::Io { path: path.clone(), source: e })?;
        Ok(KeyLock { _file: file })
    }

    /// The library of `key`, opened and verified: its bytes hash to the digest kept beside it.
    /// `None` when there is none, or when it does not verify (truncated, swapped): it is to
    /// be built again.
    pub fn verified(&self, key: &str) -> Option<File> {
        let mut library = secure::open_file(&self.path_of(&library_name(key))).ok()?;
        let mut digest = String::new();
        secure::open_file(&self.path_of(&digest_name(key))).ok()?.take(128).read_to_string(&mut digest).ok()?;
        let mut hash = Sha256::new();
        std::io::copy(&mut library, &mut hash).ok()?;
        (hex(&hash.finalize()) == digest.trim()).then_some(library)
    }

    /// A private temporary folder to build the library of `key` in, after removing the ones
    /// a build killed midway left behind (the caller holds the key's lock: no other build of
    /// this key runs).
    pub fn build_folder(&self, key: &str) -> Result<tempfile::TempDir, Error> {
        let here = secure::through(&self.dir, &self.shown);
        if let Ok(entries) = fs::read_dir(&here) {
            for entry in entries.flatten() {
                if entry.file_name().to_string_lossy().starts_with(&build_prefix(key)) {
                    let _ = fs::remove_dir_all(entry.path());
                }
            }
        }
        tempfile::Builder::new().prefix(&build_prefix(key)).tempdir_in(&here).map_err(|e| Error::Io { path: self.shown.clone(), source: e })
    }

    /// Puts the library built at `built` into place as the library of `key`, its digest first:
    /// a reader sees the new library with its digest, or the old state.
    pub fn store(&self, key: &str, built: &Path) -> Result<(), Error> {
        let io = |e: std::io::Error| Error::Io { path: self.shown_library(key), source: e };
        let mut hash = Sha256::new();
        std::io::copy(&mut File::open(built).map_err(io)?, &mut hash).map_err(io)?;
        let digest = built.with_file_name(digest_name(key));
        fs::write(&digest, hex(&hash.finalize())).map_err(io)?;
        fs::rename(&digest, self.path_of(&digest_name(key))).map_err(io)?;
        fs::rename(built, self.path_of(&library_name(key))).map_err(io)
    }
}

/// Holds the exclusive lock on a key while it lives (released when dropped).
pub struct KeyLock {
    _file: File,
}

/// The checks and opens that keep to one open folder.
#[cfg(unix)]
mod secure {
    use std::ffi::{CString, OsStr};
    use std::fs::File;
    use std::os::fd::{AsRawFd, FromRawFd};
    use std::os::unix::ffi::OsStrExt;
    use std::os::unix::fs::MetadataExt;
    use std::path::{Path, PathBuf};

    fn euid() -> u32 {
        // SAFETY: `geteuid` has no preconditions and cannot fail.
        unsafe { libc::geteuid() }
    }

    /// `/`, opened as a folder.
    pub fn open_root() -> std::io::Result<File> {
        open_flags(libc::AT_FDCWD, OsStr::new("/"), libc::O_DIRECTORY)
    }

    /// The folder `name` in the open folder `at`, not following a link.
    pub fn open_below(at: &File, name: &OsStr) -> std::io::Result<File> {
        open_flags(at.as_raw_fd(), name, libc::O_DIRECTORY | libc::O_NOFOLLOW)
    }

    fn open_flags(at: i32, name: &OsStr, flags: i32) -> std::io::Result<File> {
        let name = CString::new(name.as_bytes()).map_err(|_| std::io::Error::other("a NUL byte in the path"))?;
        // SAFETY: `name` is a NUL-terminated string; `at` is an open folder or AT_FDCWD.
        let fd = unsafe { libc::openat(at, name.as_ptr(), flags | libc::O_RDONLY | libc::O_CLOEXEC) };
        if fd < 0 {
            return Err(std::io::Error::last_os_error());
        }
        // SAFETY: `fd` was just opened and is owned by nothing else.
        Ok(unsafe { File::from_raw_fd(fd) })
    }

    /// `O_NOFOLLOW` on a symlink fails with `ELOOP` (or `ENOTDIR` with `O_DIRECTORY`).
    pub fn is_link_error(code: i32) -> bool {
        code == libc::ELOOP || code == libc::ENOTDIR
    }

    /// A folder above the cache: the user's or root's, and written by no one else unless
    /// sticky (only owners may then remove or rename what is in it).
    pub fn check_above(dir: &File) -> Result<(), String> {
        let meta = dir.metadata().map_err(|e| e.to_string())?;
        let (uid, mode) = (meta.uid(), meta.mode());
        if uid != euid() && uid != 0 {
            return Err(format!("belongs to user {uid}, who could swap the cache for a folder of theirs"));
        }
        if mode & 0o022 != 0 && mode & 0o1000 == 0 {
            return Err(format!("may be written by other users (mode {:o}, not sticky), who could swap the cache for a folder of theirs", mode & 0o7777));
        }
        Ok(())
    }

    /// The cache folder itself: the user's, written by no one else.
    pub fn check_own(dir: &File) -> Result<(), String> {
        let meta = dir.metadata().map_err(|e| e.to_string())?;
        if meta.uid() != euid() {
            return Err(format!("it belongs to user {}, not to this user ({})", meta.uid(), euid()));
        }
        if meta.mode() & 0o022 != 0 {
            return Err(format!("other users can write to it (mode {:o}); `chmod go-w` it", meta.mode() & 0o777));
        }
        Ok(())
    }

    /// The path of the open folder `dir`: its handle on Linux (`/proc/self/fd/N`, which
    /// resolves to that folder whatever is at its name now), its name elsewhere.
    pub fn through(dir: &File, shown: &Path) -> PathBuf {
        if cfg!(target_os = "linux") { PathBuf::from(format!("/proc/self/fd/{}", dir.as_raw_fd())) } else { shown.to_path_buf() }
    }

    /// A regular file of the user's, opened for reading without following a link.
    pub fn open_file(path: &Path) -> std::io::Result<File> {
        let file = std::fs::OpenOptions::new().read(true).custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC).open(path)?;
        let meta = file.metadata()?;
        if !meta.is_file() || meta.uid() != euid() || meta.mode() & 0o022 != 0 {
            return Err(std::io::Error::other("not a regular file of this user's, written by no one else"));
        }
        Ok(file)
    }

    /// A file private to the user, created if missing, never through a link.
    pub fn create_private(path: &Path) -> std::io::Result<File> {
        use std::os::unix::fs::OpenOptionsExt as _;
        std::fs::OpenOptions::new().create(true).truncate(false).write(true).mode(0o600).custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC).open(path)
    }

    use std::os::unix::fs::OpenOptionsExt;
}

/// Elsewhere the folder is used by its name, with the checks `std` can make.
#[cfg(not(unix))]
mod secure {
    use std::ffi::OsStr;
    use std::fs::File;
    use std::path::{Path, PathBuf};

    pub fn open_root() -> std::io::Result<File> {
        Err(std::io::Error::other("the compiled route's cache needs a Unix system"))
    }
    pub fn open_below(_: &File, _: &OsStr) -> std::io::Result<File> {
        unreachable!()
    }
    pub fn is_link_error(_: i32) -> bool {
        false
    }
    pub fn check_above(_: &File) -> Result<(), String> {
        Ok(())
    }
    pub fn check_own(_: &File) -> Result<(), String> {
        Ok(())
    }
    pub fn through(_: &File, shown: &Path) -> PathBuf {
        shown.to_path_buf()
    }
    pub fn open_file(path: &Path) -> std::io::Result<File> {
        File::open(path)
    }
    pub fn create_private(path: &Path) -> std::io::Result<File> {
        std::fs::OpenOptions::new().create(true).truncate(false).write(true).open(path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A folder other users can write to, a symbolic link (with a trailing slash too), or a
    /// folder under one others may change, is refused with what to do.
    #[cfg(unix)]
    #[test]
    fn shared_or_linked_folders_are_refused() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let open = dir.path().join("open");
        fs::create_dir(&open).unwrap();
        fs::set_permissions(&open, fs::Permissions::from_mode(0o777)).unwrap();
        let e = Cache::open(&open).unwrap_err().to_string();
        assert!(e.contains("other users can write to it") && e.contains("chmod go-w"), "{e}");
        let link = dir.path().join("link");
        std::os::unix::fs::symlink(dir.path(), &link).unwrap();
        for named in [link.clone(), PathBuf::from(format!("{}/", link.display()))] {
            let e = Cache::open(&named).unwrap_err().to_string();
            assert!(e.contains("symbolic link"), "{}: {e}", named.display());
        }
        // Under a folder every user may write to, not sticky: another user could rename the
        // cache away and put a folder of theirs in its place.
        let cache = open.join("cache");
        let e = Cache::open(&cache).unwrap_err().to_string();
        assert!(e.contains("may be written by other users") && e.contains("not sticky"), "{e}");
        // Sticky (as /tmp is), it is fine.
        fs::set_permissions(&open, fs::Permissions::from_mode(0o1777)).unwrap();
        Cache::open(&cache).unwrap();
        // Under a folder of another user's.
        let theirs = dir.path().join("theirs");
        fs::create_dir(&theirs).unwrap();
        std::os::unix::fs::chown(&theirs, Some(4242), None).expect("chown needs root (the tests run as root, as CI does)");
        let e = Cache::open(&theirs.join("cache")).unwrap_err().to_string();
        assert!(e.contains("belongs to user 4242"), "{e}");
        let made = dir.path().join("a/b/cache");
        Cache::open(&made).unwrap();
        assert_eq!(fs::metadata(&made).unwrap().permissions().mode() & 0o777, 0o700);
    }

    /// Once open, the cache is the folder that was checked: a folder swapped in at its name
    /// afterwards (here a symlink to another) is not the one written to.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_folder_swapped_after_the_check_is_not_used() {
        let dir = tempfile::tempdir().unwrap();
        let cache_path = dir.path().join("cache");
        let cache = Cache::open(&cache_path).unwrap();
        let elsewhere = dir.path().join("elsewhere");
        fs::create_dir(&elsewhere).unwrap();
        fs::rename(&cache_path, dir.path().join("moved")).unwrap();
        std::os::unix::fs::symlink(&elsewhere, &cache_path).unwrap();
        drop(cache.lock("k").unwrap());
        assert!(dir.path().join("moved/model-k.lock").is_file());
        assert!(!elsewhere.join("model-k.lock").exists());
    }

    /// A library whose bytes are not those its digest names is not verified: truncated,
    /// or another file.
    #[cfg(unix)]
    #[test]
    fn only_a_library_with_its_digest_verifies() {
        let dir = tempfile::tempdir().unwrap();
        let cache = Cache::open(&dir.path().join("cache")).unwrap();
        assert!(cache.verified("k").is_none());
        let work = cache.build_folder("k").unwrap();
        let built = work.path().join("lib.so");
        fs::write(&built, vec![7u8; 5000]).unwrap();
        cache.store("k", &built).unwrap();
        assert!(cache.verified("k").is_some());
        let library = dir.path().join("cache").join(library_name("k"));
        let file = fs::OpenOptions::new().write(true).open(&library).unwrap();
        file.set_len(100).unwrap();
        assert!(cache.verified("k").is_none(), "a truncated library");
        fs::write(&library, vec![8u8; 5000]).unwrap();
        assert!(cache.verified("k").is_none(), "another library");
    }

    /// A build killed midway leaves its folder; the next build of the key removes it.
    #[test]
    fn folders_of_killed_builds_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        let cache = Cache::open(&dir.path().join("cache")).unwrap();
        let stale = cache.build_folder("k").unwrap().keep();
        let other = cache.build_folder("j").unwrap();
        let fresh = cache.build_folder("k").unwrap();
        assert!(!stale.exists() && fresh.path().exists() && other.path().exists());
    }

    /// The key covers the source byte for byte.
    #[test]
    fn keys_differ_by_one_byte() {
        assert_ne!(key(&[b"let a = 1;"]), key(&[b"let a = 2;"]));
        assert!(key(&[b"x"]).bytes().all(|b| b.is_ascii_hexdigit()));
    }
}
