//! Reading and writing the project's files without destroying anything: one helper for every
//! file the generator, the runtime and the command line write or read.
//!
//! - [`write_atomic`] writes a regular file through an exclusive temporary file in the target's
//!   directory (`tempfile`: created with `O_EXCL` under a random name, so a planted symlink is
//!   never followed), renamed over the target: a failure midway leaves the old file as it was.
//! - A path that is not a regular file is never replaced: a character device or a pipe
//!   (`/dev/null`, `/dev/stdout`, a FIFO) is written through, as the shell's `>` would; a
//!   directory, a block device, a socket or a dangling symlink is refused with [`FileError`].
//!   A symlink to a regular file replaces the file it points to and keeps the link.
//! - [`write_if_changed`] leaves a regular file alone when it already holds the bytes (builds
//!   that depend on it stay fresh); it reads at most as many bytes as it would write.
//! - [`read_bounded`] reads at most `limit` bytes and says so when a file holds more
//!   (`/dev/zero` as a model file ends with [`FileError::TooLarge`], not with the memory).
//! - Nothing this process read is ever written over: every regular file [`read_bounded`]
//!   opens is remembered by device and inode, and a write whose target is one of them (by any
//!   path: a symlink, a hard link, `./m.ron` for `m.ron`) is refused with
//!   [`FileError::IsAnInput`], whatever flags the caller was given. [`check_output`] asks the
//!   same question before any work is done.
//! - A symlink in a shared sticky folder (`/tmp`) that belongs to another user is not followed,
//!   as the kernel's `protected_symlinks` rule would not follow it ([`FileError::ForeignLink`]):
//!   another user cannot point a run's output at a file of this one's.
//!
//! ```
//! let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("module.rs");
//! files::write_atomic(&path, b"pub fn f() {}\n").unwrap();
//! assert_eq!(files::write_if_changed(&path, b"pub fn f() {}\n").unwrap(), files::Written::Unchanged);
//! assert_eq!(files::read_bounded(&path, 1024).unwrap(), b"pub fn f() {}\n");
//! assert!(matches!(files::read_bounded(&path, 4), Err(files::FileError::TooLarge { limit: 4, .. })));
//! // Read now, it is an input of this process: never written over.
//! assert!(matches!(files::write_atomic(&path, b"{}"), Err(files::FileError::IsAnInput { .. })));
//! ```

use std::fs::{File, OpenOptions};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// `text` with its control characters escaped (`\n`, `\t`, `\u{1b}`): a name or path a user
/// gave, fit to print on a terminal or into one line of a file. Everything else is kept as it
/// is, so an ordinary name prints unchanged.
///
/// ```
/// assert_eq!(files::printable("models/x.ron"), "models/x.ron");
/// assert_eq!(files::printable("a\nb\u{1b}[31m"), "a\\nb\\u{1b}[31m");
/// ```
pub fn printable(text: &str) -> String {
    text.chars().map(|c| if c.is_control() { c.escape_debug().to_string() } else { c.to_string() }).collect()
}

/// [`printable`] of a path (lossy where it is not UTF-8).
pub fn printable_path(path: &Path) -> String {
    printable(&path.to_string_lossy())
}

/// Why a file could not be read or written. A failed write leaves the target as it was.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// The system refused (no such folder, no permission, a full disk...).
    #[error("cannot {action} `{}`: {source}", printable_path(path))]
    Io {
        path: PathBuf,
        action: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// The path is something a file must not replace.
    #[error("cannot write `{}`: it is {kind}, not a regular file; nothing was written (give the path of a file)", printable_path(path))]
    NotRegular { path: PathBuf, kind: &'static str },
    /// A read found more than `limit` bytes.
    #[error("`{}` holds more than {limit} bytes, the most this reads (is it the right file?)", printable_path(path))]
    TooLarge { path: PathBuf, limit: u64 },
    /// The target is a file this process read (its model, an input series): it is never
    /// written over, whatever the flags.
    #[error(
        "cannot write `{}`: it is `{}`, which this run reads; nothing was written (give the output another path)",
        printable_path(path),
        printable_path(input)
    )]
    IsAnInput { path: PathBuf, input: PathBuf },
    /// A symlink another user owns, in a folder every user may write to but only owners may
    /// delete from (sticky, like `/tmp`): not followed.
    #[error(
        "cannot write `{}`: `{}` is a symbolic link of another user (uid {owner}) in a shared sticky folder, and is not followed (as the kernel's protected_symlinks would not); nothing was written",
        printable_path(path),
        printable_path(link)
    )]
    ForeignLink { path: PathBuf, link: PathBuf, owner: u32 },
}

impl FileError {
    /// The message without the path (for callers that name the file themselves).
    pub fn source_message(&self) -> String {
        match self {
            FileError::Io { source, .. } => source.to_string(),
            FileError::NotRegular { kind, .. } => format!("it is {kind}, not a regular file"),
            FileError::TooLarge { limit, .. } => format!("it holds more than {limit} bytes"),
            FileError::IsAnInput { input, .. } => format!("it is `{}`, which this run reads", printable_path(input)),
            FileError::ForeignLink { link, owner, .. } => {
                format!("`{}` is a symbolic link of another user (uid {owner}) in a shared sticky folder", printable_path(link))
            }
        }
    }

    /// The path the error is about.
    pub fn path(&self) -> &Path {
        match self {
            FileError::Io { path, .. }
            | FileError::NotRegular { path, .. }
            | FileError::TooLarge { path, .. }
            | FileError::IsAnInput { path, .. }
            | FileError::ForeignLink { path, .. } => path,
        }
    }
}

/// What a write did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Written {
    /// A regular file was created or replaced atomically.
    Replaced,
    /// The regular file already held these bytes and was left alone.
    Unchanged,
    /// The bytes went through a character device or a pipe, which is still there.
    Through,
}

/// What a path is, for deciding how to write it.
#[derive(Debug)]
enum Target {
    /// Nothing there yet: create it.
    Missing(PathBuf),
    /// A regular file (the resolved path when reached through symlinks).
    Regular(PathBuf, std::fs::Metadata),
    /// A character device or a FIFO: write through it.
    Stream(PathBuf),
}

fn io<'a>(path: &'a Path, action: &'static str) -> impl FnOnce(std::io::Error) -> FileError + 'a {
    move |source| FileError::Io { path: path.to_path_buf(), action, source }
}

/// The files this process read ([`read_bounded`]), by device and inode, with the path each was
/// read by.
static INPUTS: std::sync::Mutex<Vec<(u64, u64, PathBuf)>> = std::sync::Mutex::new(Vec::new());

/// A file's identity: its device and inode (on other systems, its canonical path's hash).
fn identity(meta: &std::fs::Metadata, path: &Path) -> (u64, u64) {
    #[cfg(unix)]
    {
        let _ = path;
        use std::os::unix::fs::MetadataExt;
        (meta.dev(), meta.ino())
    }
    #[cfg(not(unix))]
    {
        let _ = meta;
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf()).hash(&mut h);
        (0, h.finish())
    }
}

/// Remembers the regular file `meta` describes as one this process reads.
fn remember_input(meta: &std::fs::Metadata, path: &Path) {
    if !meta.is_file() {
        return;
    }
    let id = identity(meta, path);
    let mut inputs = INPUTS.lock().unwrap_or_else(|e| e.into_inner());
    if !inputs.iter().any(|(d, i, _)| (*d, *i) == id) {
        inputs.push((id.0, id.1, path.to_path_buf()));
    }
}

/// The input (its path as read) that `meta` is, if any. An input whose path no longer leads to
/// the file read (deleted, or replaced) is forgotten: its inode may now be another file's.
fn input_at(meta: &std::fs::Metadata, path: &Path) -> Option<PathBuf> {
    if !meta.is_file() {
        return None;
    }
    let id = identity(meta, path);
    still_inputs().iter().find(|(d, i, _)| (*d, *i) == id).map(|(_, _, p)| p.clone())
}

/// The remembered inputs, those no longer at their path (deleted, or replaced: the inode may now
/// be another file's) forgotten.
fn still_inputs() -> std::sync::MutexGuard<'static, Vec<(u64, u64, PathBuf)>> {
    let mut inputs = INPUTS.lock().unwrap_or_else(|e| e.into_inner());
    inputs.retain(|(d, i, p)| std::fs::metadata(p).is_ok_and(|m| identity(&m, p) == (*d, *i)));
    inputs
}

/// The files this process has read as its inputs ([`read_bounded`], [`note_input`]), by their
/// paths as read, in the order first read; those no longer at their path are forgotten.
/// `multibody watch` follows them all: a model file, a URDF it includes, an input's series.
///
/// ```
/// let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("model.ron");
/// std::fs::write(&path, "Model()").unwrap();
/// files::read_bounded(&path, 100).unwrap();
/// assert!(files::inputs().contains(&path));
/// std::fs::remove_file(&path).unwrap();
/// assert!(!files::inputs().contains(&path));
/// ```
pub fn inputs() -> Vec<PathBuf> {
    still_inputs().iter().map(|(_, _, p)| p.clone()).collect()
}

/// Remembers `path`, read by other means than [`read_bounded`], as an input of this process:
/// no write replaces it afterwards.
pub fn note_input(path: &Path) {
    if let Ok(meta) = std::fs::metadata(path) {
        remember_input(&meta, path);
    }
}

/// Whether a write to `path` would be refused ([`FileError::IsAnInput`], a path that is not a
/// regular file, a foreign link): asked before a run's work, so that a wrong output path costs
/// nothing. Nothing is created.
///
/// ```
/// let dir = tempfile::tempdir().unwrap();
/// let model = dir.path().join("m.ron");
/// std::fs::write(&model, "Model()").unwrap();
/// files::read_bounded(&model, 1024).unwrap();
/// let e = files::check_output(&dir.path().join("./m.ron")).unwrap_err();
/// assert!(matches!(e, files::FileError::IsAnInput { .. }), "{e}");
/// assert!(files::write_atomic(&model, b"{}").is_err());
/// assert_eq!(std::fs::read(&model).unwrap(), b"Model()");
/// files::check_output(&dir.path().join("out.json")).unwrap();
/// ```
pub fn check_output(path: &Path) -> Result<(), FileError> {
    target(path).map(|_| ())
}

/// The kernel's `protected_symlinks` rule for the symlink `link` (its own metadata `meta`): in
/// a sticky folder every user may write to, it is followed only if this user or the folder's
/// owner owns it.
#[cfg(unix)]
fn trusted_link(shown: &Path, link: &Path, meta: &std::fs::Metadata) -> Result<(), FileError> {
    use std::os::unix::fs::MetadataExt;
    let folder = match link.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let Ok(dir) = std::fs::metadata(folder) else { return Ok(()) };
    let shared_sticky = dir.mode() & 0o1002 == 0o1002;
    // SAFETY: `geteuid` has no preconditions and cannot fail.
    let me = unsafe { libc::geteuid() };
    if shared_sticky && meta.uid() != me && meta.uid() != dir.uid() {
        return Err(FileError::ForeignLink { path: shown.to_path_buf(), link: link.to_path_buf(), owner: meta.uid() });
    }
    Ok(())
}

#[cfg(not(unix))]
fn trusted_link(_: &Path, _: &Path, _: &std::fs::Metadata) -> Result<(), FileError> {
    Ok(())
}

/// Every symlink on the way to `path` (each prefix of it) passes [`trusted_link`].
fn trusted_links(path: &Path) -> Result<(), FileError> {
    let mut prefix = PathBuf::new();
    for part in path.components() {
        prefix.push(part);
        if let Ok(meta) = std::fs::symlink_metadata(&prefix)
            && meta.file_type().is_symlink()
        {
            trusted_link(path, &prefix, &meta)?;
        }
    }
    Ok(())
}

/// Classifies `path` without opening it: what a write would do there, and refuses what it must
/// not touch (an input of this run, a foreign link, what is not a file).
fn target(path: &Path) -> Result<Target, FileError> {
    trusted_links(path)?;
    let found = classify(path)?;
    let meta = match &found {
        Target::Regular(_, meta) => Some(meta.clone()),
        Target::Stream(resolved) => std::fs::metadata(resolved).ok(),
        Target::Missing(_) => None,
    };
    if let Some(input) = meta.and_then(|m| input_at(&m, path)) {
        return Err(FileError::IsAnInput { path: path.to_path_buf(), input });
    }
    Ok(found)
}

/// What is at `path`, following symlinks.
fn classify(path: &Path) -> Result<Target, FileError> {
    let link = match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Target::Missing(path.to_path_buf())),
        other => other.map_err(io(path, "inspect"))?,
    };
    let (resolved, meta) = if link.file_type().is_symlink() {
        match std::fs::canonicalize(path) {
            Ok(p) => {
                let meta = std::fs::metadata(&p).map_err(io(path, "inspect"))?;
                (p, meta)
            }
            Err(_) => return Err(FileError::NotRegular { path: path.to_path_buf(), kind: "a symlink to nothing" }),
        }
    } else {
        (path.to_path_buf(), link)
    };
    let ft = meta.file_type();
    if ft.is_file() {
        return Ok(Target::Regular(resolved, meta));
    }
    if ft.is_dir() {
        return Err(FileError::NotRegular { path: path.to_path_buf(), kind: "a directory" });
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ft.is_char_device() || ft.is_fifo() {
            return Ok(Target::Stream(resolved));
        }
        if ft.is_block_device() {
            return Err(FileError::NotRegular { path: path.to_path_buf(), kind: "a block device" });
        }
        if ft.is_socket() {
            return Err(FileError::NotRegular { path: path.to_path_buf(), kind: "a socket" });
        }
    }
    Err(FileError::NotRegular { path: path.to_path_buf(), kind: "a special file" })
}

/// Writes `bytes` to `path` (see the crate docs): a regular or new file atomically, a device or
/// a pipe through it; anything else is refused.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<Written, FileError> {
    write(path, bytes, false)
}

/// [`write_atomic`] into a folder that is created first when missing (`--out DIR`, `--plots
/// DIR`).
pub fn write_creating_folder(path: &Path, bytes: &[u8]) -> Result<Written, FileError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(io(dir, "create the folder"))?;
    }
    write_atomic(path, bytes)
}

/// [`write_atomic`], except that a regular file already holding `bytes` is left alone.
pub fn write_if_changed(path: &Path, bytes: &[u8]) -> Result<Written, FileError> {
    write(path, bytes, true)
}

fn write(path: &Path, bytes: &[u8], skip_unchanged: bool) -> Result<Written, FileError> {
    match target(path)? {
        Target::Stream(resolved) => {
            // No `create`, no `truncate`: a device or pipe is used as it is, never made anew.
            let mut f = OpenOptions::new().write(true).open(&resolved).map_err(io(path, "open"))?;
            f.write_all(bytes).and_then(|()| f.flush()).map_err(io(path, "write"))?;
            Ok(Written::Through)
        }
        Target::Regular(resolved, meta) => {
            if skip_unchanged && meta.len() == bytes.len() as u64 && holds(&resolved, bytes) {
                return Ok(Written::Unchanged);
            }
            replace(path, &resolved, bytes, Some(meta.permissions()))
        }
        Target::Missing(p) => replace(path, &p, bytes, None),
    }
}

/// True when the regular file at `path` holds exactly `bytes` (reads at most one byte more).
fn holds(path: &Path, bytes: &[u8]) -> bool {
    let Ok(f) = File::open(path) else { return false };
    let mut have = Vec::with_capacity(bytes.len());
    f.take(bytes.len() as u64 + 1).read_to_end(&mut have).is_ok() && have == bytes
}

/// The temporary file, written, renamed over `target`. `shown` is the path the user gave.
fn replace(shown: &Path, target: &Path, bytes: &[u8], keep: Option<std::fs::Permissions>) -> Result<Written, FileError> {
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = target.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    // `.NAME.PID.`: a writer killed before its rename (kill -9) leaves its temporary file, which
    // the next write of the same output removes once no process has that id.
    let stem: String = format!(".{name}.").chars().filter(|c| !c.is_control()).take(56).collect();
    remove_stale_temporaries(&dir, &stem);
    let prefix = format!("{stem}{}.", std::process::id());
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    // The result keeps the target's permissions; a new file gets what `File::create` gives
    // (0666 less the umask), where a temporary file would be private (0600).
    if let Some(p) = keep.clone().or_else(new_file_permissions) {
        builder.permissions(p);
    }
    let mut tmp = builder.tempfile_in(&dir).map_err(io(shown, "create a temporary file beside"))?;
    if let Some(p) = keep {
        tmp.as_file().set_permissions(p).map_err(io(shown, "set the permissions of"))?;
    }
    tmp.write_all(bytes).and_then(|()| tmp.as_file().sync_all()).map_err(io(shown, "write"))?;
    tmp.persist(target).map_err(|e| FileError::Io { path: shown.to_path_buf(), action: "replace", source: e.error })?;
    Ok(Written::Replaced)
}

/// Removes the temporary files `STEM PID . RANDOM .tmp` in `dir` that writers killed before
/// their rename left: regular files owned by this user whose process is gone. (Linux: a
/// process is known by `/proc/PID`; elsewhere nothing is removed.)
fn remove_stale_temporaries(dir: &Path, stem: &str) {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::MetadataExt;
        let Ok(entries) = std::fs::read_dir(dir) else { return };
        let me = own_uid();
        for entry in entries.flatten() {
            let file = entry.file_name();
            let Some(rest) = file.to_str().and_then(|f| f.strip_prefix(stem)).and_then(|r| r.strip_suffix(".tmp")) else { continue };
            let Some(pid) = rest.split_once('.').and_then(|(pid, _)| pid.parse::<u32>().ok()) else { continue };
            let gone = !Path::new(&format!("/proc/{pid}")).exists();
            let ours = std::fs::symlink_metadata(entry.path()).is_ok_and(|m| m.file_type().is_file() && Some(m.uid()) == me);
            if gone && ours {
                let _ = std::fs::remove_file(entry.path());
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (dir, stem);
}

/// This process's user id, from `/proc/self` (the owner of a process's own entry).
#[cfg(target_os = "linux")]
fn own_uid() -> Option<u32> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata("/proc/self").ok().map(|m| m.uid())
}

/// The mode `File::create` asks for; the kernel applies the umask when the file is created.
#[cfg(unix)]
fn new_file_permissions() -> Option<std::fs::Permissions> {
    use std::os::unix::fs::PermissionsExt;
    Some(std::fs::Permissions::from_mode(0o666))
}

/// Elsewhere a temporary file is not made private: nothing to widen.
#[cfg(not(unix))]
fn new_file_permissions() -> Option<std::fs::Permissions> {
    None
}

/// Reads at most `limit` bytes of `path`: [`FileError::TooLarge`] when it holds more, whatever
/// it is (a regular file, a device that never ends, a pipe).
pub fn read_bounded(path: &Path, limit: u64) -> Result<Vec<u8>, FileError> {
    let f = File::open(path).map_err(io(path, "read"))?;
    if f.metadata().is_ok_and(|m| m.is_dir()) {
        return Err(FileError::Io { path: path.to_path_buf(), action: "read", source: std::io::Error::other("it is a directory") });
    }
    if let Ok(meta) = f.metadata() {
        remember_input(&meta, path);
    }
    let mut out = Vec::new();
    f.take(limit.saturating_add(1)).read_to_end(&mut out).map_err(io(path, "read"))?;
    if out.len() as u64 > limit {
        return Err(FileError::TooLarge { path: path.to_path_buf(), limit });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn leftovers(dir: &Path) -> Vec<String> {
        std::fs::read_dir(dir).unwrap().filter_map(|e| e.ok()).map(|e| e.file_name().to_string_lossy().into_owned()).filter(|n| n.ends_with(".tmp")).collect()
    }

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("table.csv");
        assert_eq!(write_atomic(&path, b"old").unwrap(), Written::Replaced);
        let blocked = dir.path().join("blocked");
        std::fs::create_dir_all(blocked.join("inner")).unwrap();
        let e = write_atomic(&blocked, b"new").unwrap_err();
        assert!(matches!(e, FileError::NotRegular { kind: "a directory", .. }), "{e}");
        assert!(blocked.join("inner").is_dir());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        assert!(leftovers(dir.path()).is_empty(), "{:?}", leftovers(dir.path()));
    }

    /// A writer killed between its temporary file and the rename (kill -9) left `.NAME.PID.*.tmp`
    /// behind: the next write of NAME removes it once that process is gone, and leaves a live
    /// writer's, another output's and a file not of this pattern alone.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_killed_writer_s_temporary_file_is_removed_by_the_next_write() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("run.csv");
        // A process id no process has: above the kernel's largest (`pid_max` is at most 2^22).
        let dead = 4_194_305u32;
        let stale = dir.path().join(format!(".run.csv.{dead}.a1b2c3.tmp"));
        let live = dir.path().join(format!(".run.csv.{}.d4e5f6.tmp", std::process::id()));
        let other = dir.path().join(format!(".plot.svg.{dead}.a1b2c3.tmp"));
        let unrelated = dir.path().join(".run.csv.notapid.tmp");
        for f in [&stale, &live, &other, &unrelated] {
            std::fs::write(f, b"partial").unwrap();
        }
        write_atomic(&path, b"rows").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "rows");
        assert!(!stale.exists(), "the dead writer's temporary file is gone");
        assert!(live.exists() && other.exists() && unrelated.exists(), "{:?}", leftovers(dir.path()));
    }

    #[cfg(unix)]
    #[test]
    fn a_new_file_gets_the_usual_permissions_and_an_old_one_keeps_its_own() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let usual = dir.path().join("usual");
        File::create(&usual).unwrap();
        let path = dir.path().join("out.csv");
        write_atomic(&path, b"a").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&path), mode(&usual));
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o640)).unwrap();
        write_atomic(&path, b"b").unwrap();
        assert_eq!(mode(&path), 0o640);
    }

    /// A symlink planted where an old version named its temporary file (`.NAME.PID.tmp`) is
    /// never followed: its target keeps its bytes.
    #[cfg(unix)]
    #[test]
    fn a_planted_symlink_at_the_old_temporary_name_is_not_followed() {
        let dir = tempfile::tempdir().unwrap();
        let victim = dir.path().join("victim");
        std::fs::write(&victim, b"precious").unwrap();
        let planted = dir.path().join(format!(".x.rs.{}.tmp", std::process::id()));
        std::os::unix::fs::symlink(&victim, &planted).unwrap();
        write_atomic(&dir.path().join("x.rs"), b"module").unwrap();
        assert_eq!(std::fs::read(&victim).unwrap(), b"precious");
        assert_eq!(std::fs::read(dir.path().join("x.rs")).unwrap(), b"module");
    }

    #[cfg(unix)]
    #[test]
    fn a_symlink_to_a_file_keeps_the_link_and_replaces_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real.rs");
        std::fs::write(&real, b"old").unwrap();
        let link = dir.path().join("link.rs");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        write_atomic(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
        let dangling = dir.path().join("dangling.rs");
        std::os::unix::fs::symlink(dir.path().join("nowhere/x"), &dangling).unwrap();
        assert!(matches!(write_atomic(&dangling, b"x"), Err(FileError::NotRegular { .. })));
        assert!(std::fs::symlink_metadata(&dangling).unwrap().file_type().is_symlink());
    }

    /// A FIFO (as a pipe on stdout would be) is written through and stays a FIFO; a read of
    /// it with a bound ends.
    #[cfg(unix)]
    #[test]
    fn a_fifo_is_written_through_not_replaced() {
        use std::os::unix::fs::FileTypeExt;
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("pipe");
        let st = std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
        assert!(st.success());
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::read(&fifo).unwrap())
        };
        assert_eq!(write_atomic(&fifo, b"through").unwrap(), Written::Through);
        assert_eq!(reader.join().unwrap(), b"through");
        assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
    }

    /// Copies of `/dev/null`, `/dev/full` and `/dev/zero` made with `mknod` in a temporary
    /// folder (never the real `/dev`; the tests run as root, as CI does): written through or
    /// refused with the device's own error, never replaced; a read of the endless one is bounded.
    #[cfg(unix)]
    #[test]
    fn device_nodes_are_written_through_never_replaced_and_reads_of_them_are_bounded() {
        use std::os::unix::fs::FileTypeExt;
        let dir = tempfile::tempdir().unwrap();
        let node = |name: &str, minor: &str| {
            let p = dir.path().join(name);
            let st = std::process::Command::new("mknod").arg(&p).args(["c", "1", minor]).status().unwrap();
            assert!(st.success(), "mknod needs root (the tests run as root, as CI does)");
            p
        };
        let (null, zero, full) = (node("null", "3"), node("zero", "5"), node("full", "7"));
        let is_char = |p: &Path| std::fs::symlink_metadata(p).unwrap().file_type().is_char_device();
        assert_eq!(write_atomic(&null, b"module").unwrap(), Written::Through);
        assert_eq!(write_if_changed(&null, b"module").unwrap(), Written::Through);
        let e = write_atomic(&full, b"module").unwrap_err();
        assert!(e.to_string().contains("cannot write"), "{e}");
        let e = write_if_changed(&zero, &vec![0u8; 1 << 20]).unwrap();
        assert_eq!(e, Written::Through);
        assert!(is_char(&null) && is_char(&zero) && is_char(&full));
        assert!(matches!(read_bounded(&zero, 1 << 16), Err(FileError::TooLarge { limit: 65536, .. })));
        // A symlink to a device (as `/dev/stdout` is) goes through to the device, and stays.
        let link = dir.path().join("stdout");
        std::os::unix::fs::symlink(&null, &link).unwrap();
        assert_eq!(write_atomic(&link, b"x").unwrap(), Written::Through);
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink() && is_char(&null));
    }

    #[test]
    fn an_unchanged_file_is_not_rewritten_and_a_changed_one_is() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.rs");
        assert_eq!(write_if_changed(&path, b"abc").unwrap(), Written::Replaced);
        assert_eq!(write_if_changed(&path, b"abc").unwrap(), Written::Unchanged);
        assert_eq!(write_if_changed(&path, b"abd").unwrap(), Written::Replaced);
        assert_eq!(std::fs::read(&path).unwrap(), b"abd");
    }

    #[test]
    fn reads_are_bounded() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.ron");
        std::fs::write(&path, vec![b'x'; 100]).unwrap();
        assert_eq!(read_bounded(&path, 100).unwrap().len(), 100);
        let e = read_bounded(&path, 99).unwrap_err();
        assert!(e.to_string().contains("more than 99 bytes"), "{e}");
        assert!(read_bounded(dir.path(), 10).unwrap_err().to_string().contains("directory"));
    }
}
