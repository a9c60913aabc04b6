//! Surface files by extension: the one place that maps `.json`,
//! `.igs`/`.iges`, `.step`/`.stp` and `.g2` to their readers and writers.
//!
//! Reading keeps the file's length unit ([`SurfaceFile::unit`]; JSON and
//! GoTools have none) and writing puts it back, so converting between
//! formats changes no coordinate. Every writer keeps control points, knots,
//! weights and trimming curves bit-identical on a read → write → read round
//! trip. GoTools `.g2` is read only ([`SurfaceFormat::is_writable`]).

use std::path::{Path, PathBuf};

use thiserror::Error;

use super::IoError;
use super::gotools::{GoToolsError, read_gotools};
use super::iges_read::{IgesError, read_iges};
use super::iges_write::{IgesWriteOptions, write_iges};
use super::step::{StepError, StepWriteOptions, read_step_with, write_step};
use super::surface_json::{SurfaceJsonError, read_surface_json_file, write_surfaces_json};
use super::units::LengthUnit;
pub use super::unreadable::Unreadable;
use crate::bspline::BSplineSurface;

/// A surface file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SurfaceFormat {
    /// fairline's surface JSON (DESIGN.md §5); reading also takes geomdl's
    /// JSON (NURBS-Python, [`super::geomdl`]), told apart by its content.
    Json,
    /// IGES 5.3 (entity 128, trims as 144/142).
    Iges,
    /// STEP ISO 10303-21 (AP203/AP214/AP242 geometry).
    Step,
    /// SINTEF GoTools text format (`.g2`; spline and bounded spline
    /// surfaces), read only: see [`super::gotools`].
    GoTools,
}

impl SurfaceFormat {
    /// The format named by the extension (case-insensitive): `.json`,
    /// `.igs`/`.iges`, `.step`/`.stp`, `.g2`; `None` otherwise.
    pub fn from_path(path: impl AsRef<Path>) -> Option<Self> {
        let ext = path
            .as_ref()
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("json") => Some(Self::Json),
            Some("igs" | "iges") => Some(Self::Iges),
            Some("step" | "stp") => Some(Self::Step),
            Some("g2") => Some(Self::GoTools),
            _ => None,
        }
    }

    /// Whether fairline writes this format (GoTools is read only).
    pub fn is_writable(self) -> bool {
        !matches!(self, Self::GoTools)
    }
}

/// The surfaces of a file and its length unit.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceFile {
    /// Every surface, in file order (trimmed where the file trims them).
    pub surfaces: Vec<BSplineSurface>,
    /// The length unit the file declares (none for JSON, or when the file
    /// names no unit fairline knows).
    pub unit: Option<LengthUnit>,
    /// What the reader did not take as the file says (STEP: p-curves that
    /// disagree with their 3-D edges); one line each.
    pub warnings: Vec<String>,
    /// Every face (IGES: trimmed, bounded or free surface entity, B-rep
    /// face; STEP: face; GoTools: any object that is not a readable spline
    /// surface) the reader could not read: it is in none of
    /// [`Self::surfaces`]. A front end must not treat the part as complete
    /// while this is not empty.
    pub unreadable: Vec<Unreadable>,
}

impl SurfaceFile {
    /// One line naming the unreadable faces: the count and the first
    /// `first` of them; `None` when every face was read. `area` is the
    /// total area of the faces read, for the estimated share of the
    /// unreadable ones.
    pub fn unreadable_summary(&self, first: usize, area: Option<f64>) -> Option<String> {
        if self.unreadable.is_empty() {
            return None;
        }
        let n = self.unreadable.len();
        let named: Vec<String> = self
            .unreadable
            .iter()
            .take(first)
            .map(|u| u.to_string())
            .collect();
        let est: f64 = self
            .unreadable
            .iter()
            .filter_map(|u| u.estimated_area)
            .sum();
        let share = match area {
            Some(a) if est > 0.0 && (a + est) > 0.0 => format!(
                " (at most {:.1} % of the part's area, from the faces whose surface was read)",
                100.0 * est / (a + est)
            ),
            _ => String::new(),
        };
        Some(format!(
            "could not read {n} face(s){share}: {}{}",
            named.join("; "),
            if n > named.len() {
                format!("; … and {} more", n - named.len())
            } else {
                String::new()
            }
        ))
    }
}

/// Why a surface file could not be read or written.
#[derive(Debug, Error)]
pub enum SurfaceFileError {
    /// Surface JSON.
    #[error(transparent)]
    Json(#[from] SurfaceJsonError),
    /// IGES.
    #[error(transparent)]
    Iges(#[from] IgesError),
    /// STEP.
    #[error(transparent)]
    Step(#[from] StepError),
    /// GoTools.
    #[error(transparent)]
    GoTools(#[from] GoToolsError),
    /// Writing.
    #[error(transparent)]
    Io(#[from] IoError),
    /// The extension names no surface format.
    #[error(
        "{}: unknown surface format (expected extension .json, .igs/.iges, .step/.stp or .g2)",
        path.display()
    )]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// The extension names a format fairline reads but does not write.
    #[error(
        "{}: fairline does not write this surface format (write .json, .igs/.iges or .step/.stp)",
        path.display()
    )]
    ReadOnlyFormat {
        /// The file.
        path: PathBuf,
    },
}

/// Reads every surface of a file, choosing the reader by extension.
pub fn read_surface_file(path: impl AsRef<Path>) -> Result<SurfaceFile, SurfaceFileError> {
    let path = path.as_ref();
    match SurfaceFormat::from_path(path) {
        Some(SurfaceFormat::Json) => {
            let imp = read_surface_json_file(path)?;
            Ok(SurfaceFile {
                surfaces: imp.surfaces,
                unreadable: imp.unreadable,
                ..SurfaceFile::default()
            })
        }
        Some(SurfaceFormat::Iges) => {
            let imp = read_iges(path)?;
            Ok(SurfaceFile {
                unit: imp.units.as_deref().and_then(LengthUnit::from_iges_name),
                // a base surface whose trimmed or bounded surface could not
                // be read (listed in `unreadable`) is not the face: left out
                surfaces: imp
                    .surfaces
                    .into_iter()
                    .filter(|s| !(s.trimmed && s.trim_entity.is_none()))
                    .map(|s| s.surface)
                    .collect(),
                warnings: imp.warnings,
                unreadable: imp.unreadable,
            })
        }
        Some(SurfaceFormat::Step) => {
            let imp = read_step_with(path, true)?;
            Ok(SurfaceFile {
                unit: imp.unit,
                surfaces: imp.surfaces.into_iter().map(|s| s.surface).collect(),
                warnings: imp.warnings,
                unreadable: imp.unreadable,
            })
        }
        Some(SurfaceFormat::GoTools) => {
            let imp = read_gotools(path)?;
            Ok(SurfaceFile {
                surfaces: imp.surfaces,
                unreadable: imp.unreadable,
                ..SurfaceFile::default()
            })
        }
        None => Err(SurfaceFileError::UnknownFormat {
            path: path.to_path_buf(),
        }),
    }
}

/// Writes surfaces in the format the extension names (atomically), in
/// `unit` (millimetres when `None`; JSON carries no unit).
pub fn write_surface_file(
    path: impl AsRef<Path>,
    surfaces: &[BSplineSurface],
    unit: Option<&LengthUnit>,
) -> Result<(), SurfaceFileError> {
    let path = path.as_ref();
    let unit = unit.cloned().unwrap_or_else(LengthUnit::millimetre);
    match SurfaceFormat::from_path(path) {
        Some(SurfaceFormat::Json) => Ok(write_surfaces_json(path, surfaces)?),
        Some(SurfaceFormat::Iges) => Ok(write_iges(
            path,
            surfaces,
            &IgesWriteOptions {
                unit,
                ..IgesWriteOptions::default()
            },
        )?),
        Some(SurfaceFormat::Step) => Ok(write_step(
            path,
            surfaces,
            &StepWriteOptions {
                unit,
                ..StepWriteOptions::default()
            },
        )?),
        Some(SurfaceFormat::GoTools) => Err(SurfaceFileError::ReadOnlyFormat {
            path: path.to_path_buf(),
        }),
        None => Err(SurfaceFileError::UnknownFormat {
            path: path.to_path_buf(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn surface_files_round_trip_through_every_format() {
        let surfaces = crate::io::iges_write::tests::generated();
        let dir =
            std::env::temp_dir().join(format!("fairline-surface-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for name in ["a.json", "a.IGS", "a.iges", "a.step", "a.stp"] {
            let p = dir.join(name);
            write_surface_file(&p, &surfaces, Some(&LengthUnit::inch())).unwrap();
            let back = read_surface_file(&p).unwrap();
            assert_eq!(back.surfaces, surfaces, "{name}");
            let want = (!name.ends_with("json")).then(LengthUnit::inch);
            assert_eq!(back.unit, want, "{name}");
        }
        let err = read_surface_file(dir.join("a.obj"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("unknown surface format"), "{err}");
        assert!(write_surface_file(dir.join("a.txt"), &surfaces, None).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
