//! STEP (ISO 10303-21 exchange files of AP203/AP214/AP242 geometry):
//! reading faces as trimmed B-spline surfaces ([`read_step`], see
//! [`read`](self) for what is supported) and writing surfaces back
//! ([`write_step`]).
//!
//! - [`p21`]: the Part 21 parser (instances, complex instances, every
//!   parameter kind);
//! - `read`: geometry and topology to
//!   [`BSplineSurface`](crate::bspline::BSplineSurface)s with trims;
//! - `nurbs`: exact NURBS forms of conics and swept surfaces;
//! - `edge_curve`: the 3-D curves of trim curves on their surfaces, exact
//!   or fitted within a stated tolerance;
//! - `write`: B-spline surfaces and faces with p-curves and 3-D edge curves.

mod edge_curve;
pub(crate) mod nurbs;
pub mod p21;
mod read;
mod write;

use std::path::{Path, PathBuf};

use thiserror::Error;

pub use read::{StepImport, StepSurface, TrimSources};
pub(crate) use read::{invert_point, polyline};
pub use write::{StepWriteOptions, surfaces_to_step, write_step};

#[cfg(test)]
mod tests;

/// Why a STEP file could not be read; names the file, line and entity.
#[derive(Debug, Error)]
pub enum StepError {
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The text does not follow ISO 10303-21.
    #[error("line {line}: {message}")]
    Syntax {
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// An entity instance is malformed or not supported.
    #[error("line {line}: #{id} {message}")]
    Entity {
        /// The instance name `#id`.
        id: u64,
        /// 1-based line where it starts.
        line: usize,
        /// Its type and what is wrong.
        message: String,
    },
    /// An error of the content of a file, with the file's name.
    #[error("{}: {error}", path.display())]
    InFile {
        /// The file.
        path: PathBuf,
        /// What is wrong in it.
        error: Box<StepError>,
    },
}

/// Reads every face (and free bounded B-spline surface) of a STEP file as
/// a trimmed B-spline surface. Errors name the file, line and `#id`; the
/// first face that cannot be read is an error.
pub fn read_step(path: impl AsRef<Path>) -> Result<StepImport, StepError> {
    read_step_with(path, false)
}

/// [`read_step`]; with `collect`, a face that cannot be read is not an
/// error but listed in [`StepImport::unreadable`] (errors of the file's
/// syntax still are).
pub fn read_step_with(path: impl AsRef<Path>, collect: bool) -> Result<StepImport, StepError> {
    let path = path.as_ref();
    let bytes = super::read_input_file(path, super::MAX_INPUT_FILE_BYTES).map_err(|source| {
        StepError::Read {
            path: path.to_path_buf(),
            source,
        }
    })?;
    parse_step_bytes_with(&bytes, collect).map_err(|error| StepError::InFile {
        path: path.to_path_buf(),
        error: Box::new(error),
    })
}

/// Reads the faces of an exchange built in memory (by another format's
/// reader, see [`crate::io::iges_read`]'s B-rep faces), collecting the faces
/// that cannot be read (see [`read_step_with`]).
pub(crate) fn read_exchange(ex: &p21::Exchange) -> Result<StepImport, StepError> {
    read::read(ex, true)
}

/// Parses STEP text; see [`read_step`].
pub fn parse_step(text: &str) -> Result<StepImport, StepError> {
    parse_step_bytes(text.as_bytes())
}

/// Parses STEP bytes; see [`read_step`].
pub fn parse_step_bytes(bytes: &[u8]) -> Result<StepImport, StepError> {
    parse_step_bytes_with(bytes, false)
}

/// Parses STEP bytes; see [`read_step_with`].
pub fn parse_step_bytes_with(bytes: &[u8], collect: bool) -> Result<StepImport, StepError> {
    let ex = p21::parse(bytes).map_err(|e| StepError::Syntax {
        line: e.line,
        message: e.message,
    })?;
    read::read(&ex, collect)
}
