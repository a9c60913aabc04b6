//! Atomic writes: every file is written to a temporary beside its target and
//! renamed over it; temporaries are removed on failure or interruption, writes
//! can be staged and committed together, and hard-linked targets are refused.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::IoError;

pub(super) static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// The temporary files [`atomic_write`] has created and not yet renamed or
/// removed, whether the process is shutting down (then no new temporary
/// file may be created), and whether writes are staged ([`stage_writes`])
/// with the staged files: (temporary file, path it is renamed to).
struct LiveTemps {
    paths: Vec<PathBuf>,
    closing: bool,
    staging: bool,
    staged: Vec<(PathBuf, PathBuf)>,
}

static LIVE_TEMPS: std::sync::Mutex<LiveTemps> = std::sync::Mutex::new(LiveTemps {
    paths: Vec::new(),
    closing: false,
    staging: false,
    staged: Vec::new(),
});

fn live_temps() -> std::sync::MutexGuard<'static, LiveTemps> {
    // A panic while the lock was held cannot leave the list inconsistent
    // (every change is one push or one removal), so a poisoned lock is used.
    LIVE_TEMPS.lock().unwrap_or_else(|e| e.into_inner())
}

/// Removes every temporary file that an [`atomic_write`] in progress has
/// created, and makes every later [`atomic_write`] fail before it creates
/// one. Meant for a process that is about to exit on a signal (SIGINT,
/// SIGTERM): the outputs it already renamed into place are complete, the
/// ones in progress leave nothing behind. Returns how many files were
/// removed. The library never calls it itself.
pub fn remove_temporary_files() -> usize {
    let mut live = live_temps();
    live.closing = true;
    live.staged.clear();
    let mut removed = 0;
    for p in live.paths.drain(..) {
        if std::fs::remove_file(&p).is_ok() {
            removed += 1;
        }
    }
    removed
}

/// Stages every later [`atomic_write`] of this process: each file is
/// written, flushed and synced in full under its temporary name beside its
/// path, but renamed into place only by [`commit_staged_writes`], all of
/// them together, or removed by [`discard_staged_writes`]. A program that
/// writes several files for one request (a mesh, a report, a picture) thus
/// writes all of them or none: a failure after the first file leaves no
/// new file beside the old ones. Until the commit the files are not at
/// their paths (nothing may read them back). [`remove_temporary_files`]
/// removes staged files too. Meant for a command-line program; the library
/// never calls it itself.
pub fn stage_writes() {
    live_temps().staging = true;
}

/// Renames every file staged since [`stage_writes`] over its path, in the
/// order they were written, ends staging and returns the paths written. A
/// rename is the one step that can still fail (it does not copy: the
/// temporary file is in the same folder); then the files before it stay
/// renamed, it and the rest are removed, and the error names its path.
pub fn commit_staged_writes() -> Result<Vec<PathBuf>, IoError> {
    let mut live = live_temps();
    live.staging = false;
    let staged = std::mem::take(&mut live.staged);
    let mut written = Vec::with_capacity(staged.len());
    let mut failure = None;
    for (tmp, target) in staged {
        if failure.is_none() {
            match std::fs::rename(&tmp, &target) {
                Ok(()) => written.push(target),
                Err(source) => {
                    failure = Some(count_write_failure(IoError::Io {
                        path: target,
                        source,
                    }))
                }
            }
        }
        // renamed, or abandoned after a failed rename
        let _ = std::fs::remove_file(&tmp);
        live.paths.retain(|p| p != &tmp);
    }
    match failure {
        Some(e) => Err(e),
        None => Ok(written),
    }
}

/// Removes every file staged since [`stage_writes`] without renaming it
/// (the paths keep what they held before) and ends staging; returns how
/// many files were removed.
pub fn discard_staged_writes() -> usize {
    let mut live = live_temps();
    live.staging = false;
    let staged = std::mem::take(&mut live.staged);
    let mut removed = 0;
    for (tmp, _) in staged {
        if std::fs::remove_file(&tmp).is_ok() {
            removed += 1;
        }
        live.paths.retain(|p| p != &tmp);
    }
    removed
}

/// Where [`atomic_write`] puts a file given as `path`: a symbolic link is
/// followed to its target (so the link stays a link and its target gets the
/// new content); an existing path must be a regular file. Device nodes,
/// FIFOs, sockets and directories are refused, since a rename would replace
/// them with a regular file.
fn write_target(
    path: &Path,
    follow: bool,
) -> std::io::Result<(PathBuf, Option<std::fs::Metadata>)> {
    use std::io::{Error, ErrorKind};
    match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == ErrorKind::NotFound => Ok((path.to_path_buf(), None)),
        Err(e) => Err(e),
        Ok(m) if m.file_type().is_symlink() && !follow => Err(Error::new(
            ErrorKind::InvalidInput,
            "it is a symbolic link; refusing to write through it",
        )),
        Ok(m) => {
            let (target, meta) = if m.file_type().is_symlink() {
                let target = std::fs::canonicalize(path).map_err(|_| {
                    Error::new(
                        ErrorKind::InvalidInput,
                        "it is a symbolic link to nothing; refusing to replace it",
                    )
                })?;
                let meta = std::fs::metadata(&target)?;
                (target, meta)
            } else {
                (path.to_path_buf(), m)
            };
            if meta.is_file() {
                let links = hard_links(&meta);
                if links > 1 {
                    return Err(Error::new(
                        ErrorKind::InvalidInput,
                        hard_link_refusal(links),
                    ));
                }
                Ok((target, Some(meta)))
            } else if meta.is_dir() {
                Err(Error::new(ErrorKind::InvalidInput, "it is a directory"))
            } else {
                Err(Error::new(
                    ErrorKind::InvalidInput,
                    "it is not a regular file (a device, FIFO or socket); refusing to replace it",
                ))
            }
        }
    }
}

/// Why a file with `links` hard links is not replaced: writing goes
/// through a new file and a rename, which would leave the other names
/// with the old content.
pub fn hard_link_refusal(links: u64) -> String {
    format!(
        "it has {links} hard links, and replacing it would break them (the other names would keep the old content); remove this name first or write elsewhere; nothing written"
    )
}

/// Names a regular file has (1 where the platform does not count them).
pub fn hard_links(meta: &std::fs::Metadata) -> u64 {
    #[cfg(unix)]
    {
        std::os::unix::fs::MetadataExt::nlink(meta)
    }
    #[cfg(not(unix))]
    {
        let _ = meta;
        1
    }
}

/// [`atomic_write`] confined to `path` itself: an existing symbolic link
/// at `path` is refused instead of followed, and the final rename replaces
/// whatever name is at `path` (a rename never follows a link), so nothing
/// outside `path`'s folder is ever written (the workbench's saves).
pub fn atomic_write_here<F>(path: impl AsRef<Path>, write: F) -> Result<(), IoError>
where
    F: FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
{
    atomic_write_to(path.as_ref(), false, write)
}

/// Writes a file atomically: `write` fills a temporary file
/// `.NAME.PID.N.tmp` in the same directory, which is flushed, synced and
/// then renamed over `path`. If anything fails, the temporary file is
/// removed and `path` is untouched (no file is left behind when it did not
/// exist). A symbolic link is followed and its target replaced; an existing
/// `path` that is not a regular file (device, FIFO, socket, directory) is
/// refused, and so is a file with other hard links (a rename would leave
/// them with the old content). A replaced file keeps its permissions. The temporary file is listed while it exists, so that
/// [`remove_temporary_files`] can remove it when the process is stopped by
/// a signal. After [`stage_writes`] the rename waits for
/// [`commit_staged_writes`].
pub fn atomic_write<F>(path: impl AsRef<Path>, write: F) -> Result<(), IoError>
where
    F: FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
{
    atomic_write_to(path.as_ref(), true, write)
}

fn atomic_write_to<F>(path: &Path, follow: bool, write: F) -> Result<(), IoError>
where
    F: FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
{
    let io_err = |source| IoError::Io {
        path: path.to_path_buf(),
        source,
    };
    let (target, existing) = write_target(path, follow).map_err(io_err)?;
    let file_name = target.file_name().ok_or_else(|| {
        io_err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "the output path has no file name",
        ))
    })?;
    let dir = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let (tmp, file) = {
        let mut live = live_temps();
        if live.closing {
            return Err(io_err(std::io::Error::new(
                std::io::ErrorKind::Interrupted,
                "the process is stopping; nothing written",
            )));
        }
        let mut attempt = 0;
        loop {
            let n = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
            let mut name = std::ffi::OsString::from(".");
            name.push(file_name);
            name.push(format!(".{}.{n}.tmp", std::process::id()));
            let tmp = dir.join(name);
            match File::options().write(true).create_new(true).open(&tmp) {
                Ok(f) => {
                    live.paths.push(tmp.clone());
                    break (tmp, f);
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && attempt < 100 => {
                    attempt += 1;
                }
                Err(e) => return Err(count_write_failure(io_err(e))),
            }
        }
    };
    // Removes the temporary file however this function ends: an error, a
    // panic in `write`, or success (then the name is already gone).
    let guard = LiveTemp(tmp);
    let result = (|| {
        // large enough that a 20 MB mesh takes a few dozen write calls
        // rather than thousands of 8 KiB ones
        let mut w = BufWriter::with_capacity(WRITE_BUFFER_BYTES, file);
        write(&mut w)?;
        w.flush()?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        if let Some(meta) = &existing {
            file.set_permissions(meta.permissions())?;
        }
        file.sync_all()?;
        drop(file);
        Ok(())
    })();
    if let Err(e) = result {
        drop(guard);
        return Err(count_write_failure(io_err(e)));
    }
    let mut live = live_temps();
    if live.staging && !live.closing {
        // renamed by commit_staged_writes, removed by discard_staged_writes
        let tmp = guard.keep();
        live.staged.push((tmp, target));
        return Ok(());
    }
    drop(live);
    let renamed = std::fs::rename(&guard.0, &target);
    drop(guard);
    renamed.map_err(|e| count_write_failure(io_err(e)))
}

/// How many writes of this process failed once their file was being
/// written: [`atomic_write`] after its checks of the path (the temporary
/// file could not be created, written, synced or renamed; the writer
/// failed) and renames of [`commit_staged_writes`]. A refusal of the path
/// itself (a directory, a special file, other hard links) is not counted.
static WRITE_FAILURES: AtomicU64 = AtomicU64::new(0);

/// How many writes of this process failed while their file was written
/// (see [`atomic_write`]); a front end tells an output that could not be
/// written from an input that could not be read by it.
pub fn write_failures() -> u64 {
    WRITE_FAILURES.load(Ordering::Relaxed)
}

fn count_write_failure<E>(e: E) -> E {
    WRITE_FAILURES.fetch_add(1, Ordering::Relaxed);
    e
}

/// Buffer size of [`atomic_write`]'s writer.
const WRITE_BUFFER_BYTES: usize = 1 << 20;

/// A temporary file of [`atomic_write`]: removed and unlisted when dropped.
struct LiveTemp(PathBuf);

impl LiveTemp {
    /// The path, left in place and listed (a staged file).
    fn keep(mut self) -> PathBuf {
        let path = std::mem::take(&mut self.0);
        std::mem::forget(self);
        path
    }
}

impl Drop for LiveTemp {
    fn drop(&mut self) {
        // after the rename there is no file of this name left to remove
        let _ = std::fs::remove_file(&self.0);
        live_temps().paths.retain(|p| p != &self.0);
    }
}
