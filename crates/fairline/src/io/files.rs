//! Input files read safely (regular files only, bounded size) and the checks
//! that an output is not the input under another name.

use std::fs::File;
use std::path::{Path, PathBuf};

use super::IoError;

/// The largest input file fairline reads whole (8 GiB): a binary STL of
/// 160 million triangles, far beyond any mesh the algorithms can hold.
pub const MAX_INPUT_FILE_BYTES: u64 = 8 << 30;

/// Refuses a `path` that is not a regular file, before opening it: a
/// directory, a FIFO (opening one would wait for a writer), a device such
/// as `/dev/zero` or `/dev/urandom` (it never ends), a socket. Symbolic
/// links are followed. The error is [`std::io::ErrorKind::InvalidInput`]
/// with a message that says what the path is; a path that cannot be looked
/// at gives the operating system's error.
pub fn require_regular_file(path: impl AsRef<Path>) -> std::io::Result<()> {
    let meta = std::fs::metadata(path)?;
    if meta.is_file() {
        return Ok(());
    }
    Err(std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        format!(
            "is {}, not a regular file; give a file",
            file_kind(&meta.file_type())
        ),
    ))
}

/// What a file that is not a regular file is, for messages.
fn file_kind(t: &std::fs::FileType) -> &'static str {
    if t.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    "a special file"
}

/// Reads a whole input file: refused unless it is a regular file
/// ([`require_regular_file`], checked before opening and again on the
/// opened file), and refused (nothing more read) once it holds more than
/// `max_bytes` bytes, so a file that grows while it is read is bounded too.
/// Errors are [`std::io::Error`]s; callers add the path.
pub fn read_input_file(path: impl AsRef<Path>, max_bytes: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let path = path.as_ref();
    require_regular_file(path)?;
    let file = File::open(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() {
        // replaced between the look and the opening
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "is {}, not a regular file; give a file",
                file_kind(&meta.file_type())
            ),
        ));
    }
    let too_large = |size: u64| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("is {size} bytes, more than the {max_bytes} bytes fairline reads"),
        )
    };
    if meta.len() > max_bytes {
        return Err(too_large(meta.len()));
    }
    let mut bytes = Vec::with_capacity(usize::try_from(meta.len()).unwrap_or(0));
    file.take(max_bytes.saturating_add(1))
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_large(bytes.len() as u64));
    }
    Ok(bytes)
}

/// Whether `a` and `b` name the same file: the same canonical path (a path
/// that does not exist yet is its canonical parent folder plus its name),
/// or, on Unix, the same device and inode (hard links). Paths that cannot
/// be resolved at all are compared as given.
pub fn same_file(a: impl AsRef<Path>, b: impl AsRef<Path>) -> bool {
    let (a, b) = (a.as_ref(), b.as_ref());
    if a == b {
        return true;
    }
    let (ca, cb) = (canonical_or_planned(a), canonical_or_planned(b));
    if let (Some(x), Some(y)) = (&ca, &cb)
        && x == y
    {
        return true;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b))
            && x.dev() == y.dev()
            && x.ino() == y.ino()
        {
            return true;
        }
    }
    false
}

/// The canonical path of `path`, or for a path that does not exist the
/// canonical path of its folder joined with its file name.
fn canonical_or_planned(path: &Path) -> Option<PathBuf> {
    if let Ok(c) = std::fs::canonicalize(path) {
        return Some(c);
    }
    let name = path.file_name()?;
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    std::fs::canonicalize(parent).ok().map(|p| p.join(name))
}

/// Refuses an `output` path that names the same file as `input` (see
/// [`same_file`]: canonical path, device and inode). The input must exist.
pub fn ensure_distinct(input: impl AsRef<Path>, output: impl AsRef<Path>) -> Result<(), IoError> {
    let (input, output) = (input.as_ref(), output.as_ref());
    std::fs::canonicalize(input).map_err(|source| IoError::Io {
        path: input.to_path_buf(),
        source,
    })?;
    if same_file(input, output) {
        return Err(IoError::SameFile {
            input: input.to_path_buf(),
            output: output.to_path_buf(),
        });
    }
    Ok(())
}
