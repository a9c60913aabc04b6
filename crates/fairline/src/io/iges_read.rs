//! IGES import of rational B-spline surfaces (entity 128).
//!
//! Reads the fixed-format ASCII IGES file (IGES 5.3 §2): 80-column records
//! with the section letter (`S`, `G`, `D`, `P`, `T`) in column 73. The Global
//! section's first two fields set the parameter and record delimiters
//! (default `,` and `;`); Hollerith strings `nH…` may contain delimiters and
//! span records; parameter data occupy columns 1–64 of the `P` records and may
//! continue over several of them; directory entries come in pairs of `D`
//! records of ten 8-column fields. Reals may use `D` exponents (`1.0D+01`) or
//! omit digits (`1.`, `1.E-3`).
//!
//! Every entity 128 becomes a [`BSplineSurface`] (Piegl & Tiller's NURBS
//! form; IGES 5.3 §4.24): `K1, K2, M1, M2, PROP1..5`, knots S and T, weights,
//! control points and the parameter range `U0 U1 V0 V1`. A polynomial surface
//! (`PROP3 = 1`) is built without weights (they are still read and checked to
//! be numbers). A transformation matrix (entity 124, chained through its own
//! directory entry) referenced by directory field 7 is applied to the control
//! points.
//!
//! Trimmed surfaces (entity 144, IGES 5.3 §4.34) on an entity 128 attach
//! their outer and inner boundaries (entities 142) to the surface as
//! trimming loops ([`BSplineSurface::set_trims`]). Each boundary is read from
//! its parameter-space curve (142's `BPTR`), made of entities 126 (rational
//! B-spline curve), 110 (line), 100 (circular arc, with its 124
//! transformation) and 102 (composite curve). A boundary given only in
//! model space (`BPTR = 0`) gets its parameter-space curve by projecting the
//! model-space curve onto the surface ([`project_boundary`](boundary::project_boundary)); a boundary
//! whose model-space curve is missing (`CPTR = 0`) is read from its
//! parameter-space curve alone.
//!
//! Surfaces of revolution (entity 120, IGES 5.3 §4.18: axis line `L`,
//! generatrix `C(t)` — a line 110, a circular arc 100, an elliptic arc 104
//! or a B-spline curve 126 — and the angles
//! `SA`, `TA`) are converted exactly to NURBS (Piegl & Tiller A8.1, through
//! [`crate::io::step`]'s `revolve`, as the STEP reader does for its
//! analytic surfaces): `u` is the generatrix parameter `t` as in the file,
//! `v` the rational quadratic arcs' parameter, equal to the angle at the arc
//! joints and ends ([`IgesSurface::entity_type`] = 120). Their 142 curves
//! are given in `(t, θ)`; `θ` is mapped to the arcs' parameter exactly
//! where a boundary segment is parallel to an axis of `(t, θ)` (a line
//! stays a line under the monotone map of one coordinate) and by dense
//! sampling otherwise. Planes (entity 108) trimmed by a 144 become bilinear
//! patches with their boundaries from the 142s' model-space curves. A 144
//! on any other surface the B-rep reading converts (122, 190–198, a 120
//! of a hyperbola or parabola) is read as a face bounded by its 142s'
//! model-space curves, through the STEP reader ([`brep`]); one on a surface
//! of another type is counted in [`IgesImport::skipped_trimmed`]
//! and listed, with bounded surfaces (143) and surface entities of a type
//! not read, in [`IgesImport::unreadable`].
//!
//! B-rep solids, shells and faces (186, 514, 510 with loops 508, edges 504
//! and vertices 502) are read face by face ([`brep`]).
//!
//! Tabulated cylinders (122), ruled surfaces (118), parametric spline
//! surfaces (114, and curves 112) and offset surfaces (140) are converted
//! to B-splines ([`surfaces`]; exact except an offset of a surface that is
//! not a plane, cylinder, cone, sphere or torus, fitted within a stated
//! tolerance and named in [`IgesImport::warnings`]); bounded surfaces (143
//! with boundaries 141) are read as trimmed surfaces ([`bounded`]).

use std::path::{Path, PathBuf};

use thiserror::Error;

use super::step::nurbs::{ArcMap, Nurbs3};
use crate::Vec3;
use crate::bspline::{BSplineError, BSplineSurface, TrimCurve, TrimLoop};
use crate::io::unreadable::Unreadable;
use bspline_surface::read_entity_128;
use params::{Param, global_delimiters, parse_int, text_of, tokenize};
use records::{Iges, directory, sections};
use revolution::Revolved;
use surfaces::Converted;

mod boundary;
mod bounded;
mod brep;
mod bspline_surface;
mod curve_ops;
mod faces;
mod params;
mod records;
mod revolution;
mod ruled;
#[cfg(test)]
mod surface_tests;
mod surfaces;
#[cfg(test)]
mod tests;
mod trimmed;

/// Why an IGES file could not be imported; names the file line and entity.
#[derive(Debug, Error)]
pub enum IgesError {
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The record structure is broken.
    #[error("line {line}: {message}")]
    Format {
        /// 1-based line number in the file.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// An entity's directory entry or parameter data is malformed.
    #[error("line {line}: entity {entity_type} (directory entry {entity}): {message}")]
    Entity {
        /// Directory entry sequence number (odd, 1-based).
        entity: usize,
        /// Entity type number.
        entity_type: i64,
        /// 1-based line number in the file.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// An error of the content of a file, with the file's name.
    #[error("{}: {error}", path.display())]
    InFile {
        /// The file.
        path: PathBuf,
        /// What is wrong in it (line, entity).
        error: Box<IgesError>,
    },
    /// An entity fairline does not read where it stands (a curve type in a
    /// boundary, a conic not in standard position, a plane without an
    /// outer boundary): the face it belongs to is listed in
    /// [`IgesImport::unreadable`] rather than failing the file.
    #[error("line {line}: entity {entity_type} (directory entry {entity}): {message}")]
    Unsupported {
        /// Directory entry sequence number (odd, 1-based).
        entity: usize,
        /// Entity type number.
        entity_type: i64,
        /// 1-based line number in the file.
        line: usize,
        /// What is not supported.
        message: String,
    },
    /// An entity 128 does not make a valid B-spline surface.
    #[error("line {line}: entity 128 (directory entry {entity}): {source}")]
    Surface {
        /// Directory entry sequence number.
        entity: usize,
        /// 1-based line number of its parameter data.
        line: usize,
        /// The validation error.
        source: BSplineError,
    },
}

/// One imported entity 128.
#[derive(Clone, Debug, PartialEq)]
pub struct IgesSurface {
    /// The surface (transformation already applied).
    pub surface: BSplineSurface,
    /// Directory entry sequence number of the entity (odd, 1-based).
    pub directory_entry: usize,
    /// The entity it was read from: 128 (rational B-spline surface), 120
    /// (surface of revolution, converted exactly), 114, 118, 122, 140
    /// (converted, [`surfaces`]), 108 (trimmed plane), 510
    /// (B-rep face) or 144 (trimmed surface read through its topology;
    /// for these two, [`Self::form`] is the surface's entity type).
    pub entity_type: i64,
    /// Form number (0 = free form, 1 plane, 2 cylinder, …).
    pub form: i64,
    /// `PROP3 == 0`: declared rational (weights kept).
    pub rational: bool,
    /// `PROP1, PROP2`: closed in u, closed in v.
    pub closed: [bool; 2],
    /// `PROP4, PROP5`: periodic in u, periodic in v.
    pub periodic: [bool; 2],
    /// `U0, U1, V0, V1`: the parameter range the file declares.
    pub parameter_range: [f64; 4],
    /// A transformation matrix (entity 124) was applied.
    pub transformed: bool,
    /// Referenced by a trimmed (144) or bounded (143) surface entity.
    pub trimmed: bool,
    /// Directory entry of the entity 144 whose loops were attached to
    /// [`Self::surface`], if any.
    pub trim_entity: Option<usize>,
}

/// The result of [`read_iges`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IgesImport {
    /// Every entity 128 and every surface of revolution (120), tabulated
    /// cylinder (122), ruled (118), parametric spline (114) and offset
    /// (140) surface that could be converted, in directory order (an offset
    /// surface's base is not a face of its own), then the B-rep faces.
    pub surfaces: Vec<IgesSurface>,
    /// How many of them are referenced by a trimmed (144) or bounded (143)
    /// surface.
    pub trimmed: usize,
    /// Entities 144 not applied: their base surface is neither an entity
    /// 128, a converted 120 nor a plane 108, or a boundary (142) has neither a
    /// parameter-space nor a model-space curve (that face stays untrimmed).
    pub skipped_trimmed: usize,
    /// Surface entities not converted: 120 whose generatrix is not a single
    /// line (110), circular arc (100), elliptic arc (104) or B-spline curve
    /// (126), and 114, 118, 122, 140 that cannot be (outside B-rep faces).
    pub skipped_surfaces: usize,
    /// Unit name from the Global section (field 15), if given.
    pub units: Option<String>,
    /// Every face the file holds that could not be read: trimmed (144)
    /// and bounded (143) surfaces whose base surface or boundaries could
    /// not be read (a base surface that was read is still in
    /// [`Self::surfaces`], untrimmed: `trimmed` set, no `trim_entity`;
    /// [`crate::io::surface_file::read_surface_file`] leaves it out),
    /// independent surface entities of a type not read, B-rep faces (510)
    /// and trimmed surfaces read through their topology whose surface or
    /// edges are of a type not read.
    pub unreadable: Vec<Unreadable>,
    /// Faces read with a caveat: an offset surface (140) that is not a
    /// plane is a fitted B-spline (the tolerance and the largest deviation
    /// found are named).
    pub warnings: Vec<String>,
}

/// Reads every rational B-spline surface (entity 128) of an ASCII IGES file.
/// Errors name the file, and the line and entity where known.
pub fn read_iges(path: impl AsRef<Path>) -> Result<IgesImport, IgesError> {
    let path = path.as_ref();
    let bytes = super::read_input_file(path, super::MAX_INPUT_FILE_BYTES).map_err(|source| {
        IgesError::Read {
            path: path.to_path_buf(),
            source,
        }
    })?;
    parse_iges_bytes(&bytes).map_err(|error| IgesError::InFile {
        path: path.to_path_buf(),
        error: Box::new(error),
    })
}

/// Parses IGES text; see [`read_iges`].
pub fn parse_iges(text: &str) -> Result<IgesImport, IgesError> {
    parse_iges_bytes(text.as_bytes())
}

fn parse_iges_bytes(bytes: &[u8]) -> Result<IgesImport, IgesError> {
    let sections = sections(bytes)?;
    let global = &sections.global;
    let (pd, rd) =
        global_delimiters(global).map_err(|message| IgesError::Format { line: 1, message })?;
    let units =
        tokenize(global, pd, rd)
            .ok()
            .and_then(|(t, _)| match t.get(14).map(|t| &t.param) {
                Some(Param::Hollerith(h)) => Some(String::from_utf8_lossy(h).into_owned()),
                _ => None,
            });
    let g = Iges {
        dir: directory(&sections.directory)?,
        params: sections.parameters,
        pd,
        rd,
    };
    let trimmed = g.trimmed_bases();
    let mut out = IgesImport {
        units,
        ..IgesImport::default()
    };
    // The surfaces (128, and 120 converted to NURBS), by directory entry.
    let mut bsplines: Vec<Option<IgesSurface>> = vec![None; g.dir.len()];
    let mut revolved: Vec<Option<Revolved>> = vec![None; g.dir.len()];
    // 114, 118, 122 and 140 converted, or why not
    let mut conv = Conversions {
        surfaces: vec![None; g.dir.len()],
        failed: vec![None; g.dir.len()],
    };
    let mut offset_bases = vec![false; g.dir.len()];
    for k in 0..g.dir.len() {
        match g.dir[k].entity_type {
            128 => bsplines[k] = Some(read_entity_128(&g, k, trimmed[k])?),
            120 => {
                revolved[k] = g.read_entity_120(k)?;
                out.skipped_surfaces += usize::from(revolved[k].is_none());
            }
            t @ (114 | 118 | 122 | 140) => {
                if t == 140
                    && let Some(b) = g
                        .parameters(k)
                        .ok()
                        .and_then(|p| text_of(&p, 5).and_then(parse_int))
                        .and_then(|de| g.entry(de))
                {
                    offset_bases[b] = true;
                }
                match g.convert_surface(k, 0) {
                    Ok(c) => {
                        if let Some((tolerance, deviation)) = c.fit {
                            let what = match (t, g.dir[k].form) {
                                (118, 0) => "the ruled surface of equal arc length",
                                (118, _) => "the ruled surface of equal parameter",
                                _ => "the offset surface",
                            };
                            out.warnings.push(format!(
                                "{}: {what} is approximated by a bicubic B-spline within {tolerance:.1e} (largest deviation found {deviation:.1e})",
                                g.describe_entity(k)
                            ));
                        }
                        conv.surfaces[k] = Some(c);
                    }
                    Err(IgesError::Unsupported { message, .. }) => conv.failed[k] = Some(message),
                    Err(e) => return Err(e),
                }
            }
            _ => {}
        }
    }
    let mut faces = g.trimming_loops(&bsplines, &revolved, &conv, &mut out.skipped_trimmed)?;
    g.bounded_surfaces(&bsplines, &revolved, &conv, &mut faces)?;

    let (mut loops_of, mut planes) = (
        std::mem::take(&mut faces.loops),
        std::mem::take(&mut faces.planes),
    );
    let brep = g.brep_faces(&faces.translated)?;
    g.untrimmed_faces(
        &bsplines,
        &revolved,
        &conv,
        &trimmed,
        &brep.bases,
        &mut faces,
    );
    // not converted on their own; those under a B-rep face are that face's
    out.skipped_surfaces += (0..g.dir.len())
        .filter(|&k| conv.failed[k].is_some() && !brep.bases[k])
        .count();
    out.unreadable = std::mem::take(&mut faces.unreadable);
    out.unreadable.extend(brep.unreadable);
    for (k, &is_trimmed) in trimmed.iter().enumerate() {
        if (brep.bases[k] || offset_bases[k]) && !is_trimmed {
            // the surface of a B-rep face (read with the face) or the base
            // of an offset surface (read as the offset)
            continue;
        }
        let mut s = match (bsplines[k].take(), revolved[k].take(), planes[k].take()) {
            (Some(s), _, _) => s,
            (None, Some(r), _) => r.into_iges_surface(k, is_trimmed),
            (None, None, Some(p)) => {
                out.trimmed += 1;
                out.surfaces.push(p);
                continue;
            }
            // a converted base of a 144 read through the B-rep translation
            // is that face's
            (None, None, None) if brep.bases[k] => continue,
            (None, None, None) => match conv.surfaces[k].take() {
                Some(c) => c.into_iges_surface(k, &g.dir[k], is_trimmed),
                None => continue,
            },
        };
        if let Some((de, loops)) = loops_of[k].take() {
            s.surface.set_trims(loops).map_err(|e| IgesError::Entity {
                entity: de,
                entity_type: 144,
                line: g.dir[(de - 1) / 2].line,
                message: e.to_string(),
            })?;
            s.trim_entity = Some(de);
        }
        out.trimmed += usize::from(s.trimmed);
        out.surfaces.push(s);
    }
    out.trimmed += brep.surfaces.len();
    out.surfaces.extend(brep.surfaces);
    Ok(out)
}

/// The surface entities converted to B-spline surfaces ([`surfaces`]), by
/// directory entry, and why the others of their types were not.
struct Conversions {
    surfaces: Vec<Option<Converted>>,
    failed: Vec<Option<String>>,
}
