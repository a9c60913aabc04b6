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

mod atomic;
pub mod curve_fit;
mod files;
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
#[cfg(test)]
mod tests;
mod text;
pub mod units;
pub mod unreadable;

use std::fmt;
use std::path::{Path, PathBuf};

use thiserror::Error;

pub use gotools::{GoToolsError, GoToolsImport, parse_gotools, read_gotools};
pub use iges_read::{IgesError, IgesImport, IgesSurface, parse_iges, read_iges};
pub use surface_json::{
    MAX_SURFACE_JSON_BYTES, SurfaceJsonError, parse_surface_json_any, parse_surfaces_json,
    read_surface_json_file, read_surfaces_json, surface_to_json, surfaces_to_json,
    write_surface_json, write_surfaces_json,
};

use crate::mesh::{MeshError, Soup, SurfaceMesh};

pub use atomic::{
    atomic_write, atomic_write_here, commit_staged_writes, discard_staged_writes,
    hard_link_refusal, hard_links, remove_temporary_files, stage_writes, write_failures,
};
pub use files::{
    MAX_INPUT_FILE_BYTES, ensure_distinct, read_input_file, require_regular_file, same_file,
};

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
