//! Mesh files: OBJ, PLY (ascii and binary), OFF and STL; CAD surface files:
//! fairline's surface JSON ([`surface_json`]), IGES reading ([`iges_read`])
//! and writing ([`iges_write`]), STEP reading and writing ([`step`]) and
//! the choice of surface format by extension ([`surface_file`]); the JSON
//! files that select parts of a mesh, regions and fixed vertices
//! ([`selection`]).
//!
//! Every reader produces a [`Soup`] (positions plus polygons, no
//! connectivity); [`read_mesh`] then builds a [`SurfaceMesh`]. Readers never
//! panic and never trust a count from a header: binary counts are checked
//! against the bytes that remain, text readers grow their vectors as they
//! parse. Malformed input gives an [`IoError`] that names the file, the line
//! (text) or byte offset (binary), and the element (`vertex 3`, `face 7`,
//! 0-based like every index in fairline).
//!
//! Writers keep f64 exact (DESIGN §2): text formats print Rust's shortest
//! round-trip representation (`{}`), binary PLY stores doubles, so a vertex
//! that was not moved is written bit-identical. STL stores f32 by definition.
//! Every file is written atomically ([`atomic_write`]).
//!
//! The format is chosen by the file extension ([`MeshFormat::from_path`]).

pub mod curve_fit;
pub mod geomdl;
pub mod gotools;
pub mod iges_read;
pub mod iges_write;
pub mod model_curve;
mod obj;
mod off;
mod ply;
pub mod selection;
pub mod step;
mod stl;
pub mod surface_file;
pub mod surface_json;
pub mod units;
pub mod unreadable;

use std::fmt;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use thiserror::Error;

pub use gotools::{GoToolsError, GoToolsImport, parse_gotools, read_gotools};
pub use iges_read::{IgesError, IgesImport, IgesSurface, parse_iges, read_iges};
pub use surface_json::{
    MAX_SURFACE_JSON_BYTES, SurfaceJsonError, parse_surface_json_any, parse_surfaces_json,
    read_surface_json_file, read_surfaces_json, surface_to_json, surfaces_to_json,
    write_surface_json, write_surfaces_json,
};

use crate::mesh::{MeshError, Soup, SurfaceMesh};

pub use selection::{
    RegionError, RegionSpec, fixed_vertices_from_json, read_fixed_vertices, read_region,
};

/// Where in a file an error was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// The file as a whole (for example: it is empty).
    File,
    /// A 1-based line number of a text file (or of a PLY header).
    Line(usize),
    /// A 0-based byte offset into a binary file.
    Byte(usize),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::File => Ok(()),
            Location::Line(l) => write!(f, ":{l}"),
            Location::Byte(b) => write!(f, ": byte {b}"),
        }
    }
}

/// Why a mesh file could not be read or written.
///
/// Displayed as `path:line: element: message`, for example
/// `bunny.ply:12: vertex 3: expected 3 coordinates, found 2`.
#[derive(Debug, Error)]
pub enum IoError {
    /// The operating system refused to read or write the file.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The file's content does not follow its format.
    #[error("{}{location}: {message}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// Line or byte offset of the problem.
        location: Location,
        /// What is wrong, starting with the element (`vertex 3: ...`).
        message: String,
    },
    /// The file was read, but its faces do not form a [`SurfaceMesh`].
    #[error("{}: {source}", path.display())]
    Mesh {
        /// The file.
        path: PathBuf,
        /// Why the mesh could not be built.
        #[source]
        source: MeshError,
    },
    /// The file name has no extension fairline knows.
    #[error(
        "{}: unknown mesh format (expected extension .obj, .ply, .off or .stl); surface formats: .json (fairline's surface JSON), .igs/.iges (IGES 5.3), .step/.stp (STEP AP203/AP214/AP242), .g2 (GoTools){}",
        path.display(),
        foreign_surface_hint(path)
    )]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// The data handed to a writer cannot be written (non-finite
    /// coordinates, indices out of range, mismatched property lengths, ...).
    #[error("{}: {message}", path.display())]
    InvalidData {
        /// The file that was to be written.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The output path names the input file.
    #[error(
        "refusing to write {}: it is the input file {}",
        output.display(),
        input.display()
    )]
    SameFile {
        /// The input file.
        input: PathBuf,
        /// The output file.
        output: PathBuf,
    },
}

impl IoError {
    /// The file the error is about (the output file for
    /// [`IoError::SameFile`]).
    pub fn path(&self) -> &Path {
        match self {
            IoError::Io { path, .. }
            | IoError::Format { path, .. }
            | IoError::Mesh { path, .. }
            | IoError::UnknownFormat { path }
            | IoError::InvalidData { path, .. } => path,
            IoError::SameFile { output, .. } => output,
        }
    }

    /// The 1-based line number, for format errors in text files.
    pub fn line(&self) -> Option<usize> {
        match self {
            IoError::Format {
                location: Location::Line(l),
                ..
            } => Some(*l),
            _ => None,
        }
    }
}

/// A mesh file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshFormat {
    /// Wavefront OBJ (text; polygons kept).
    Obj,
    /// Stanford PLY (ascii or binary; polygons kept; written as binary
    /// little-endian with double coordinates).
    Ply,
    /// Geomview OFF (text; polygons kept).
    Off,
    /// STL (ascii or binary; triangles only, f32 coordinates; written as
    /// binary).
    Stl,
}

impl MeshFormat {
    /// The format named by the file extension (case-insensitive: `.obj`,
    /// `.ply`, `.off`, `.stl`); [`IoError::UnknownFormat`] otherwise.
    pub fn from_path(path: impl AsRef<Path>) -> Result<MeshFormat, IoError> {
        let path = path.as_ref();
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("obj") => Ok(MeshFormat::Obj),
            Some("ply") => Ok(MeshFormat::Ply),
            Some("off") => Ok(MeshFormat::Off),
            Some("stl") => Ok(MeshFormat::Stl),
            _ => Err(IoError::UnknownFormat {
                path: path.to_path_buf(),
            }),
        }
    }

    /// The usual lower-case file extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            MeshFormat::Obj => "obj",
            MeshFormat::Ply => "ply",
            MeshFormat::Off => "off",
            MeshFormat::Stl => "stl",
        }
    }
}

/// Reads a mesh file as a [`Soup`], choosing the format by extension.
///
/// STL vertices are welded by exact position. No connectivity checks are
/// made beyond index range and face size (at least 3); coordinates must be
/// finite.
pub fn read_soup(path: impl AsRef<Path>) -> Result<Soup, IoError> {
    let path = path.as_ref();
    let format = MeshFormat::from_path(path)?;
    let bytes = read_bytes(path)?;
    read_with(&bytes, format, path)
}

/// Parses the bytes of a mesh file in the given format; `name_for_errors`
/// is the file name used in error messages.
pub fn read_soup_bytes(
    bytes: &[u8],
    format: MeshFormat,
    name_for_errors: &str,
) -> Result<Soup, IoError> {
    read_with(bytes, format, Path::new(name_for_errors))
}

/// Reads a mesh file and builds a [`SurfaceMesh`] from it; a face list that
/// is not an orientable manifold gives [`IoError::Mesh`].
pub fn read_mesh(path: impl AsRef<Path>) -> Result<SurfaceMesh, IoError> {
    let path = path.as_ref();
    let soup = read_soup(path)?;
    SurfaceMesh::from_owned_soup(soup).map_err(|source| IoError::Mesh {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes a [`Soup`] atomically in the format named by the extension.
///
/// OBJ and OFF print coordinates with `{}` (bit-exact round trip), PLY is
/// binary little-endian with double coordinates, STL is binary (f32; polygons
/// are split into triangle fans and facet normals computed). Refuses
/// non-finite coordinates, out-of-range indices, faces with fewer than
/// three vertices, and for STL coordinates that f32 cannot hold (they would
/// be written as infinity); nothing is written then.
pub fn write_soup(path: impl AsRef<Path>, soup: &Soup) -> Result<(), IoError> {
    let path = path.as_ref();
    let format = MeshFormat::from_path(path)?;
    validate_for_write(soup, path)?;
    match format {
        MeshFormat::Obj => atomic_write(path, |w| obj::write(w, soup)),
        MeshFormat::Off => atomic_write(path, |w| off::write(w, soup)),
        MeshFormat::Ply => atomic_write(path, |w| ply::write(w, soup, &[])),
        MeshFormat::Stl => {
            if stl::triangle_count(soup) > u32::MAX as usize {
                return Err(invalid(path, "too many triangles for STL"));
            }
            // STL stores f32: a coordinate beyond ±f32::MAX would become inf
            let beyond_f32 = |c: f64| !(c as f32).is_finite();
            if let Some((v, p)) = soup
                .positions
                .iter()
                .enumerate()
                .find(|(_, p)| p.to_array().into_iter().any(beyond_f32))
            {
                return Err(invalid(
                    path,
                    format!(
                        "vertex {v}: coordinate beyond the range of STL's 32-bit floats (±{:e}) ({p}); write .ply, .obj or .off instead",
                        f32::MAX
                    ),
                ));
            }
            atomic_write(path, |w| stl::write(w, soup))
        }
    }
}

/// Writes a [`SurfaceMesh`] atomically in the format named by the extension
/// (see [`write_soup`]).
pub fn write_mesh(path: impl AsRef<Path>, mesh: &SurfaceMesh) -> Result<(), IoError> {
    write_soup(path, &mesh.to_soup())
}

/// Writes a binary little-endian PLY with `double x y z`, then one `double`
/// vertex property per entry of `props` (in order), then the faces as
/// `property list uchar int vertex_indices` (`uint` count when a face has
/// more than 255 vertices). Written atomically.
///
/// Each property must have one value per vertex and a name that is a single
/// word different from `x`, `y`, `z` and from the other names; every value
/// must be finite (nothing is written otherwise).
pub fn write_ply_with_vertex_properties(
    path: impl AsRef<Path>,
    soup: &Soup,
    props: &[(&str, &[f64])],
) -> Result<(), IoError> {
    let path = path.as_ref();
    validate_for_write(soup, path)?;
    for (i, (name, values)) in props.iter().enumerate() {
        if name.is_empty() || !name.bytes().all(|b| b.is_ascii_graphic()) {
            return Err(invalid(
                path,
                format!("vertex property name {name:?} is not a single word"),
            ));
        }
        if ["x", "y", "z"].contains(name) || props[..i].iter().any(|(n, _)| n == name) {
            return Err(invalid(
                path,
                format!("vertex property name {name:?} is used twice"),
            ));
        }
        if let Some((v, x)) = values.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(invalid(
                path,
                format!("vertex {v}: property {name:?} is {x} (NaN or infinite)"),
            ));
        }
        if values.len() != soup.vertex_count() {
            return Err(invalid(
                path,
                format!(
                    "vertex property {name:?} has {} values for {} vertices",
                    values.len(),
                    soup.vertex_count()
                ),
            ));
        }
    }
    atomic_write(path, |w| ply::write(w, soup, props))
}

/// Reads a PLY file and every scalar vertex property other than `x`, `y`,
/// `z` (which are in the soup), by name and in file order, converted to f64.
/// Such values may be NaN or infinite; coordinates may not.
pub fn read_ply_vertex_properties(
    path: impl AsRef<Path>,
) -> Result<(Soup, VertexProperties), IoError> {
    let path = path.as_ref();
    let bytes = read_bytes(path)?;
    ply::read(&bytes, path, true)
}

/// Named per-vertex scalar values, in file order: `(name, one value per vertex)`.
pub type VertexProperties = Vec<(String, Vec<f64>)>;

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

static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Items formatted per parallel chunk before a group of chunks is written.
const FORMAT_CHUNK: usize = 4096;

/// Chunks formatted at a time (bounds the text held in memory).
const FORMAT_GROUP: usize = 64;

/// Writes items 0..count, each formatted into a byte buffer by
/// `format(i, buffer)`, in order: the same bytes as formatting them one
/// after another, formatted in parallel chunks (text output of large
/// meshes is bound by number formatting).
pub(crate) fn write_formatted(
    w: &mut impl Write,
    count: usize,
    format: impl Fn(usize, &mut Vec<u8>) -> std::io::Result<()> + Sync,
) -> std::io::Result<()> {
    use rayon::prelude::*;
    for group in (0..count).step_by(FORMAT_CHUNK * FORMAT_GROUP) {
        let end = (group + FORMAT_CHUNK * FORMAT_GROUP).min(count);
        let starts: Vec<usize> = (group..end).step_by(FORMAT_CHUNK).collect();
        let parts = starts
            .into_par_iter()
            .map(|start| {
                let mut buffer = Vec::new();
                for i in start..(start + FORMAT_CHUNK).min(end) {
                    format(i, &mut buffer)?;
                }
                Ok(buffer)
            })
            .collect::<std::io::Result<Vec<Vec<u8>>>>()?;
        for part in parts {
            w.write_all(&part)?;
        }
    }
    Ok(())
}

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

// ---------------------------------------------------------------------------
// shared helpers of the format modules

fn read_bytes(path: &Path) -> Result<Vec<u8>, IoError> {
    read_input_file(path, MAX_INPUT_FILE_BYTES).map_err(|source| IoError::Io {
        path: path.to_path_buf(),
        source,
    })
}

fn read_with(bytes: &[u8], format: MeshFormat, path: &Path) -> Result<Soup, IoError> {
    if bytes.iter().all(|b| b.is_ascii_whitespace()) {
        return Err(format_err(path, Location::File, "empty file"));
    }
    match format {
        MeshFormat::Obj => obj::read(bytes, path),
        MeshFormat::Off => off::read(bytes, path),
        MeshFormat::Ply => ply::read(bytes, path, false).map(|(soup, _)| soup),
        MeshFormat::Stl => stl::read(bytes, path),
    }
}

fn format_err(path: &Path, location: Location, message: impl Into<String>) -> IoError {
    IoError::Format {
        path: path.to_path_buf(),
        location,
        message: message.into(),
    }
}

fn invalid(path: &Path, message: impl Into<String>) -> IoError {
    IoError::InvalidData {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Checks what every writer needs: finite coordinates, faces of at least
/// three in-range indices, a well-formed offset array.
fn validate_for_write(soup: &Soup, path: &Path) -> Result<(), IoError> {
    for (v, p) in soup.positions.iter().enumerate() {
        if !p.is_finite() {
            return Err(invalid(
                path,
                format!("vertex {v}: coordinate is NaN or infinite ({p})"),
            ));
        }
    }
    if soup.offsets.first().is_some_and(|&o| o != 0)
        || soup.offsets.windows(2).any(|w| w[1] < w[0])
        || soup
            .offsets
            .last()
            .is_some_and(|&o| o as usize != soup.indices.len())
    {
        return Err(invalid(path, "malformed face offsets"));
    }
    let nv = soup.vertex_count();
    for (f, face) in soup.faces().enumerate() {
        if face.len() < 3 {
            return Err(invalid(
                path,
                format!(
                    "face {f}: has {} vertices; a face needs at least 3",
                    face.len()
                ),
            ));
        }
        if let Some(&i) = face.iter().find(|&&i| i as usize >= nv) {
            return Err(invalid(
                path,
                format!("face {f}: vertex index {i} out of range ({nv} vertices)"),
            ));
        }
    }
    Ok(())
}

/// Lines of a text file: yields `(1-based line number, line)` without the
/// line ending: `\n`, `\r\n`, or (old Mac files) a lone `\r`.
struct Lines<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
    /// Whether a `\r` not followed by `\n` ends a line.
    lone_cr: bool,
}

impl<'a> Lines<'a> {
    /// Lines ended by `\n`, `\r\n` or a lone `\r`.
    fn new(data: &'a [u8], first_line: usize) -> Self {
        Lines {
            data,
            pos: 0,
            line: first_line,
            lone_cr: true,
        }
    }

    /// Lines ended by `\n` or `\r\n` only: for a header followed by binary
    /// data, where the byte after a `\r` may be data.
    fn lf_only(data: &'a [u8], first_line: usize) -> Self {
        Lines {
            lone_cr: false,
            ..Lines::new(data, first_line)
        }
    }

    /// Bytes not yet returned.
    fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a [u8]);

    fn next(&mut self) -> Option<Self::Item> {
        if self.pos >= self.data.len() {
            return None;
        }
        let rest = &self.data[self.pos..];
        let end = if self.lone_cr {
            rest.iter().position(|&b| b == b'\n' || b == b'\r')
        } else {
            rest.iter().position(|&b| b == b'\n')
        };
        let (line, advance) = match end {
            Some(i) if rest[i] == b'\r' && rest.get(i + 1) == Some(&b'\n') => (&rest[..i], i + 2),
            Some(i) if rest[i] == b'\n' && i > 0 && rest[i - 1] == b'\r' => (&rest[..i - 1], i + 1),
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        self.pos += advance;
        let n = self.line;
        self.line += 1;
        Some((n, line))
    }
}

/// Splits a line into whitespace-separated tokens.
fn tokens(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|b| b.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
}

/// Parses a decimal floating-point token (Rust's `f64` grammar, which
/// also accepts `inf` and `nan`; callers check finiteness).
fn parse_f64(tok: &[u8]) -> Option<f64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

/// Parses a decimal integer token: an optional `+` or `-`, then one or more
/// ASCII digits (Rust's `i64` grammar); `None` on anything else or beyond
/// the range of `i64`. Read straight from the bytes (face indices are most of
/// the tokens of a mesh file).
fn parse_i64(tok: &[u8]) -> Option<i64> {
    let (negative, digits) = match tok {
        [b'-', rest @ ..] => (true, rest),
        [b'+', rest @ ..] => (false, rest),
        _ => (false, tok),
    };
    if digits.is_empty() {
        return None;
    }
    // accumulated as a negative number, so that i64::MIN fits
    let mut v: i64 = 0;
    for &b in digits {
        let d = b.wrapping_sub(b'0');
        if d > 9 {
            return None;
        }
        v = v.checked_mul(10)?.checked_sub(i64::from(d))?;
    }
    if negative { Some(v) } else { v.checked_neg() }
}

/// A token for an error message: lossy UTF-8, at most 40 characters.
fn show(tok: &[u8]) -> String {
    let s = String::from_utf8_lossy(tok);
    if s.chars().count() > 40 {
        let cut: String = s.chars().take(40).collect();
        format!("{cut}...")
    } else {
        s.into_owned()
    }
}

/// A capacity to reserve for `count` items announced by a header when
/// `bytes` bytes remain and every item takes at least `min_item_bytes` of
/// them: never more than the file can hold.
fn capped_capacity(count: usize, bytes: usize, min_item_bytes: usize) -> usize {
    count.min(bytes / min_item_bytes.max(1))
}

/// Refuses bytes after the end of binary data (`end`): they mean the header's
/// counts do not describe the file, and whatever they hold would be lost
/// silently. A final line ending (`\n` or `\r\n`, which some writers add) is
/// tolerated. Shared by binary PLY and binary STL.
fn trailing_bytes(bytes: &[u8], end: usize, path: &Path) -> Result<(), IoError> {
    let tail = bytes.get(end..).unwrap_or_default();
    if tail.is_empty() || tail == b"\n" || tail == b"\r\n" {
        return Ok(());
    }
    Err(format_err(
        path,
        Location::Byte(end),
        format!(
            "{} bytes after the end of the data the header announces (wrong counts or a damaged file?)",
            tail.len()
        ),
    ))
}

/// Appends a face to a soup, failing when the index array would outgrow
/// 32-bit offsets.
fn push_face(soup: &mut Soup, face: &[u32]) -> Result<(), &'static str> {
    if soup.indices.len() + face.len() > u32::MAX as usize {
        return Err("too many face indices for 32-bit offsets");
    }
    soup.push_face(face);
    Ok(())
}

/// A hint for surface formats fairline does not read (Rhino .3dm, ACIS
/// .sat, Parasolid .x_t, OpenCASCADE .brep): export IGES or STEP.
fn foreign_surface_hint(path: &Path) -> &'static str {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some(
            "3dm" | "sat" | "sab" | "x_t" | "x_b" | "brep" | "igs.gz" | "jt" | "catpart" | "prt"
            | "sldprt",
        ) => {
            "; this surface format is not read: export IGES or STEP from the program that wrote it"
        }
        _ => "",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Vec3;

    #[test]
    fn integer_tokens_read_as_rust_reads_them() {
        let cases: &[&[u8]] = &[
            b"0",
            b"7",
            b"-7",
            b"+7",
            b"0042",
            b"-0",
            b"9223372036854775807",
            b"-9223372036854775808",
            b"9223372036854775808",
            b"-9223372036854775809",
            b"99999999999999999999",
            b"",
            b"-",
            b"+",
            b"1.0",
            b"1e3",
            b"12a",
            b" 1",
            b"--1",
            b"+-1",
            b"\xd9\xa3",
            b"\xff",
        ];
        for &tok in cases {
            let std = std::str::from_utf8(tok)
                .ok()
                .and_then(|s| s.parse::<i64>().ok());
            assert_eq!(parse_i64(tok), std, "{:?}", String::from_utf8_lossy(tok));
        }
        assert_eq!(parse_i64(b"-9223372036854775808"), Some(i64::MIN));
        assert_eq!(parse_i64(b"123456"), Some(123_456));
    }

    fn temp_dir(tag: &str) -> PathBuf {
        let n = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
        let dir =
            std::env::temp_dir().join(format!("fairline-io-{tag}-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn quad_soup() -> Soup {
        Soup::from_polygons(
            vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.1),
                Vec3::new(0.0, 1.0, 0.0),
            ],
            &[[0u32, 1, 2, 3]],
        )
    }

    #[cfg(unix)]
    #[test]
    fn special_files_are_refused_before_they_are_read() {
        let dir = temp_dir("special-input");
        // a device that never ends, under a mesh file name
        let zero = dir.join("zero.stl");
        std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
        let e = read_soup(&zero).unwrap_err();
        assert!(matches!(e, IoError::Io { .. }), "{e}");
        assert_eq!(
            e.to_string(),
            format!(
                "{}: is a device, not a regular file; give a file",
                zero.display()
            )
        );
        // a directory
        let sub = dir.join("sub.obj");
        std::fs::create_dir(&sub).unwrap();
        let e = read_mesh(&sub).unwrap_err().to_string();
        assert!(
            e.contains("sub.obj: is a directory, not a regular file"),
            "{e}"
        );
        // a FIFO: opening it would wait for a writer, so it must be refused
        // without being opened; a writer unblocks a reader that hangs
        let fifo = dir.join("pipe.obj");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        assert!(made.unwrap().success(), "mkfifo");
        let (tx, rx) = std::sync::mpsc::channel();
        let reading = fifo.clone();
        std::thread::spawn(move || tx.send(read_soup(&reading).map(|_| ())));
        let got = rx.recv_timeout(std::time::Duration::from_secs(10));
        if got.is_err() {
            drop(std::fs::OpenOptions::new().write(true).open(&fifo));
            panic!("reading a FIFO waited for a writer");
        }
        let e = got.unwrap().unwrap_err().to_string();
        assert!(
            e.contains("pipe.obj: is a FIFO (named pipe), not a regular file"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn input_files_are_read_up_to_a_cap() {
        let dir = temp_dir("cap");
        let path = dir.join("ten.bin");
        std::fs::write(&path, [7u8; 10]).unwrap();
        assert_eq!(read_input_file(&path, 10).unwrap(), vec![7u8; 10]);
        let e = read_input_file(&path, 9).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
        assert_eq!(
            e.to_string(),
            "is 10 bytes, more than the 9 bytes fairline reads"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn format_from_extension_is_case_insensitive() {
        assert_eq!(MeshFormat::from_path("a/B.OBJ").unwrap(), MeshFormat::Obj);
        assert_eq!(MeshFormat::from_path("x.Ply").unwrap(), MeshFormat::Ply);
        assert_eq!(MeshFormat::from_path("x.off").unwrap(), MeshFormat::Off);
        assert_eq!(MeshFormat::from_path("x.sTl").unwrap(), MeshFormat::Stl);
        let e = MeshFormat::from_path("dir/mesh.xyz").unwrap_err();
        assert!(e.to_string().contains("mesh.xyz"), "{e}");
        assert!(MeshFormat::from_path("noext").is_err());
    }

    #[test]
    fn error_display_names_file_line_and_element() {
        let e = format_err(
            Path::new("bunny.ply"),
            Location::Line(12),
            "vertex 3: expected 3 coordinates, found 2",
        );
        assert_eq!(
            e.to_string(),
            "bunny.ply:12: vertex 3: expected 3 coordinates, found 2"
        );
        assert_eq!(e.line(), Some(12));
        let e = format_err(Path::new("b.stl"), Location::Byte(84), "triangle 0: x");
        assert_eq!(e.to_string(), "b.stl: byte 84: triangle 0: x");
    }

    #[test]
    fn empty_file_is_an_error_in_every_format() {
        for f in [
            MeshFormat::Obj,
            MeshFormat::Ply,
            MeshFormat::Off,
            MeshFormat::Stl,
        ] {
            let e = read_soup_bytes(b"", f, "empty").unwrap_err();
            assert!(e.to_string().contains("empty file"), "{e}");
            assert!(read_soup_bytes(b" \n\r\n", f, "empty").is_err());
        }
    }

    /// Parallel formatting writes the same bytes as formatting one item
    /// after another, across chunk and group boundaries, and passes on a
    /// formatting error.
    #[test]
    fn formatted_writing_keeps_the_order() {
        let count = FORMAT_CHUNK * FORMAT_GROUP + FORMAT_CHUNK + 7;
        let line = |i: usize| format!("{i} {}\n", (i as f64).sqrt());
        let mut written = Vec::new();
        write_formatted(&mut written, count, |i, out| {
            out.write_all(line(i).as_bytes())
        })
        .unwrap();
        let expected: String = (0..count).map(line).collect();
        assert!(written == expected.as_bytes());
        let failing = write_formatted(&mut Vec::new(), count, |i, out| {
            if i == count - 3 {
                Err(std::io::Error::other("bad item"))
            } else {
                out.write_all(b"x")
            }
        });
        assert_eq!(failing.unwrap_err().to_string(), "bad item");
    }

    #[test]
    fn atomic_write_failure_leaves_nothing() {
        let dir = temp_dir("atomic");
        let path = dir.join("out.obj");
        let failures = write_failures();
        let r = atomic_write(&path, |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("boom"))
        });
        assert!(r.is_err());
        // counted as a write that failed (other tests may add theirs)
        assert!(write_failures() > failures);
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        // success replaces the file, failure keeps the old content
        atomic_write(&path, |w| w.write_all(b"one")).unwrap();
        assert!(atomic_write(&path, |_| Err(std::io::Error::other("no"))).is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"one");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        // an unwritable directory is an error naming the path
        let e = atomic_write(dir.join("missing/x.obj"), |w| w.write_all(b"x")).unwrap_err();
        assert!(e.to_string().contains("missing"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn ensure_distinct_catches_same_file() {
        let dir = temp_dir("distinct");
        let input = dir.join("in.obj");
        write_soup(&input, &quad_soup()).unwrap();
        assert!(matches!(
            ensure_distinct(&input, &input),
            Err(IoError::SameFile { .. })
        ));
        let dotted = dir.join(".").join("in.obj");
        assert!(ensure_distinct(&input, &dotted).is_err());
        assert!(ensure_distinct(&input, dir.join("out.obj")).is_ok());
        std::fs::create_dir(dir.join("sub")).unwrap();
        assert!(ensure_distinct(&input, dir.join("sub/../in.obj")).is_err());
        #[cfg(unix)]
        {
            let link = dir.join("link.obj");
            std::fs::hard_link(&input, &link).unwrap();
            assert!(ensure_distinct(&input, &link).is_err());
        }
        // a missing input is an I/O error
        assert!(matches!(
            ensure_distinct(dir.join("nope.obj"), &input),
            Err(IoError::Io { .. })
        ));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn same_file_sees_symlinks_and_planned_paths() {
        let dir = temp_dir("samefile");
        let input = dir.join("in.obj");
        write_soup(&input, &quad_soup()).unwrap();
        #[cfg(unix)]
        {
            let sym = dir.join("sym.obj");
            std::os::unix::fs::symlink(&input, &sym).unwrap();
            assert!(same_file(&input, &sym));
        }
        // two spellings of a file that does not exist yet
        assert!(same_file(dir.join("new.obj"), dir.join("./new.obj")));
        assert!(!same_file(dir.join("new.obj"), dir.join("other.obj")));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn atomic_write_refuses_special_files_and_follows_symlinks() {
        let dir = temp_dir("special");
        // a directory is refused, not replaced
        let sub = dir.join("sub");
        std::fs::create_dir(&sub).unwrap();
        let e = atomic_write(&sub, |w| w.write_all(b"x")).unwrap_err();
        assert!(e.to_string().contains("directory"), "{e}");
        assert!(sub.is_dir());
        // a FIFO is refused and stays a FIFO
        let fifo = dir.join("fifo");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.map(|s| s.success()).unwrap_or(false) {
            let e = atomic_write(&fifo, |w| w.write_all(b"x")).unwrap_err();
            assert!(e.to_string().contains("not a regular file"), "{e}");
            use std::os::unix::fs::FileTypeExt;
            assert!(
                std::fs::symlink_metadata(&fifo)
                    .unwrap()
                    .file_type()
                    .is_fifo()
            );
        }
        // /dev/null is a character device: refused, never replaced
        assert!(atomic_write("/dev/null", |w| w.write_all(b"x")).is_err());
        // a symbolic link keeps being a link; its target gets the content
        let target = dir.join("target.txt");
        std::fs::write(&target, b"old").unwrap();
        let link = dir.join("link.txt");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        atomic_write(&link, |w| w.write_all(b"new")).unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        // a dangling link is refused
        let dangling = dir.join("dangling.txt");
        std::os::unix::fs::symlink(dir.join("nothing"), &dangling).unwrap();
        assert!(atomic_write(&dangling, |w| w.write_all(b"x")).is_err());
        // no temporary file is left anywhere
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
            .collect();
        assert!(left.is_empty(), "{left:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_panic_while_writing_leaves_no_temporary_file() {
        let dir = temp_dir("panic");
        let path = dir.join("out.obj");
        let r = std::panic::catch_unwind(|| {
            let _ = atomic_write(&path, |w| {
                w.write_all(b"partial")?;
                panic!("writer failed");
            });
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn writers_refuse_invalid_soups() {
        let dir = temp_dir("invalid");
        let mut soup = quad_soup();
        soup.positions[2].y = f64::NAN;
        let e = write_soup(dir.join("a.obj"), &soup).unwrap_err();
        assert!(e.to_string().contains("vertex 2"), "{e}");
        let soup = Soup::from_polygons(quad_soup().positions, &[[0u32, 1, 7]]);
        let e = write_soup(dir.join("a.off"), &soup).unwrap_err();
        assert!(e.to_string().contains("face 0"), "{e}");
        let soup = Soup::from_polygons(quad_soup().positions, &[[0u32, 1]]);
        assert!(write_soup(dir.join("a.ply"), &soup).is_err());
        let e = write_ply_with_vertex_properties(
            dir.join("b.ply"),
            &quad_soup(),
            &[("k", &[1.0, 2.0][..])],
        )
        .unwrap_err();
        assert!(e.to_string().contains("2 values for 4 vertices"), "{e}");
        let v = [0.0; 4];
        assert!(
            write_ply_with_vertex_properties(dir.join("b.ply"), &quad_soup(), &[("x", &v[..])])
                .is_err()
        );
        assert!(
            write_ply_with_vertex_properties(dir.join("b.ply"), &quad_soup(), &[("a b", &v[..])])
                .is_err()
        );
        assert!(write_soup(dir.join("a.xyz"), &quad_soup()).is_err());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn lines_handle_crlf_and_missing_final_newline() {
        let v: Vec<_> = Lines::new(b"a\r\nb\n\nc", 1).collect();
        assert_eq!(
            v,
            vec![
                (1, &b"a"[..]),
                (2, &b"b"[..]),
                (3, &b""[..]),
                (4, &b"c"[..])
            ]
        );
    }
}
