//! The JSON files that select parts of a mesh (DESIGN.md §5): the region
//! file `{"faces":[...]}` / `{"vertices":[...]}` /
//! `{"sphere":{"center":[x,y,z],"radius":r}}` of fairing and detection, and
//! the fixed-vertices file `{"vertices":[...]}` of smoothing, structure-line
//! fairing and vertex flow. One reader per format; both name the file in
//! their errors ([`IoError`]).

use super::IoError;
use super::Location;
use crate::Vec3;
use crate::mesh::{FaceId, SurfaceMesh, VertexId};
use serde::{Deserialize, Serialize};
use std::path::Path;
use thiserror::Error;

/// Why a region description is unusable (bad JSON, an index out of range,
/// no face selected). Displayed as `invalid region: …`.
#[derive(Debug, Error, Clone, PartialEq)]
#[error("invalid region: {0}")]
pub struct RegionError(pub String);

/// A region description (DESIGN.md §5): `{"faces":[...]}`,
/// `{"vertices":[...]}` (the faces all of whose vertices are listed) or
/// `{"sphere":{"center":[x,y,z],"radius":r}}` (faces with all vertices in
/// the closed ball). [`RegionSpec::faces`] turns it into the faces of a
/// mesh, the `region: Vec<FaceId>` every algorithm takes.
#[derive(Clone, Debug, PartialEq)]
pub enum RegionSpec {
    /// Face indices.
    Faces(Vec<u32>),
    /// Vertex indices (as in the input file: a split copy of a vertex
    /// counts as that vertex).
    Vertices(Vec<u32>),
    /// A ball.
    Sphere {
        /// Centre (mesh units).
        center: Vec3,
        /// Radius (mesh units).
        radius: f64,
    },
}

#[derive(Serialize, Deserialize)]
struct SphereJson {
    center: [f64; 3],
    radius: f64,
}

#[derive(Serialize, Deserialize, Default)]
struct RegionJson {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    faces: Option<Vec<u32>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    vertices: Option<Vec<u32>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sphere: Option<SphereJson>,
}

impl RegionSpec {
    /// Parses the region JSON of DESIGN.md §5. Other keys (e.g. the
    /// `"regions"` a detection adds) are ignored; exactly one of `faces`,
    /// `vertices`, `sphere` must be present.
    pub fn from_json(text: &str) -> Result<Self, RegionError> {
        let r: RegionJson = serde_json::from_str(text)
            .map_err(|e| RegionError(format!("cannot parse region JSON: {e}")))?;
        match (r.faces, r.vertices, r.sphere) {
            (Some(f), None, None) => Ok(RegionSpec::Faces(f)),
            (None, Some(v), None) => Ok(RegionSpec::Vertices(v)),
            (None, None, Some(s)) => {
                let center = Vec3::from_array(s.center);
                if !center.is_finite() || !(s.radius > 0.0) || !s.radius.is_finite() {
                    return Err(RegionError(format!(
                        "sphere needs a finite centre and a positive radius, got {:?} and {}",
                        s.center, s.radius
                    )));
                }
                Ok(RegionSpec::Sphere {
                    center,
                    radius: s.radius,
                })
            }
            _ => Err(RegionError(
                "the region JSON needs exactly one of \"faces\", \"vertices\", \"sphere\"".into(),
            )),
        }
    }

    /// The JSON text of DESIGN.md §5.
    pub fn to_json(&self) -> String {
        let mut r = RegionJson::default();
        match self {
            RegionSpec::Faces(f) => r.faces = Some(f.clone()),
            RegionSpec::Vertices(v) => r.vertices = Some(v.clone()),
            RegionSpec::Sphere { center, radius } => {
                r.sphere = Some(SphereJson {
                    center: center.to_array(),
                    radius: *radius,
                })
            }
        }
        serde_json::to_string(&r).unwrap_or_default()
    }

    /// The faces of the region on `mesh`, sorted. Errors on out-of-range
    /// indices and on an empty result.
    pub fn faces(&self, mesh: &SurfaceMesh) -> Result<Vec<FaceId>, RegionError> {
        let nf = mesh.face_count();
        let mut faces: Vec<FaceId> = match self {
            RegionSpec::Faces(f) => {
                if let Some(&bad) = f.iter().find(|&&i| i as usize >= nf) {
                    return Err(RegionError(format!(
                        "face {bad} out of range (the mesh has {nf} faces)"
                    )));
                }
                f.iter().map(|&i| FaceId(i)).collect()
            }
            RegionSpec::Vertices(v) => {
                // listed by input index: a split copy counts as its vertex
                let nv = mesh.original_vertex_count();
                if let Some(&bad) = v.iter().find(|&&i| i as usize >= nv) {
                    return Err(RegionError(format!(
                        "vertex {bad} out of range (the mesh has {nv} vertices)"
                    )));
                }
                let mut listed = vec![false; nv];
                for &i in v {
                    listed[i as usize] = true;
                }
                mesh.faces()
                    .filter(|&f| {
                        mesh.face_vertices(f)
                            .all(|w| listed[mesh.original_vertex(w).idx()])
                    })
                    .collect()
            }
            RegionSpec::Sphere { center, radius } => {
                let p = mesh.positions();
                mesh.faces()
                    .filter(|&f| {
                        mesh.face_vertices(f)
                            .all(|w| (p[w.idx()] - *center).length() <= *radius)
                    })
                    .collect()
            }
        };
        faces.sort_unstable();
        faces.dedup();
        if faces.is_empty() {
            return Err(RegionError(
                "the region contains no face of the mesh".into(),
            ));
        }
        Ok(faces)
    }
}

fn read_text(path: &Path) -> Result<String, IoError> {
    let io_err = |source| IoError::Io {
        path: path.to_path_buf(),
        source,
    };
    let bytes = super::read_input_file(path, super::MAX_INPUT_FILE_BYTES).map_err(io_err)?;
    String::from_utf8(bytes).map_err(|e| {
        io_err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
        ))
    })
}

fn format_error(path: &Path, message: String) -> IoError {
    IoError::Format {
        path: path.to_path_buf(),
        location: Location::File,
        message,
    }
}

/// Reads a region file (DESIGN.md §5; see [`RegionSpec::from_json`]);
/// errors name the file: `region.json: invalid region: …`.
pub fn read_region(path: impl AsRef<Path>) -> Result<RegionSpec, IoError> {
    let path = path.as_ref();
    let text = read_text(path)?;
    RegionSpec::from_json(&text).map_err(|e| format_error(path, e.to_string()))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FixedJson {
    vertices: Vec<i64>,
}

/// Parses the fixed-vertices JSON `{"vertices":[...]}` (DESIGN.md §5; no
/// other key) and checks every index against `vertex_count`; the error
/// message names the entry: `vertices[3] = 12 is not a vertex (the mesh has
/// 10)`.
pub fn fixed_vertices_from_json(text: &str, vertex_count: usize) -> Result<Vec<VertexId>, String> {
    let f: FixedJson = serde_json::from_str(text).map_err(|e| e.to_string())?;
    f.vertices
        .iter()
        .enumerate()
        .map(|(k, &v)| {
            if v < 0 || v as u64 >= vertex_count as u64 {
                Err(format!(
                    "vertices[{k}] = {v} is not a vertex (the mesh has {vertex_count})"
                ))
            } else {
                Ok(VertexId(v as u32))
            }
        })
        .collect()
}

/// Reads a fixed-vertices file (see [`fixed_vertices_from_json`]); errors
/// name the file.
pub fn read_fixed_vertices(
    path: impl AsRef<Path>,
    vertex_count: usize,
) -> Result<Vec<VertexId>, IoError> {
    let path = path.as_ref();
    let text = read_text(path)?;
    fixed_vertices_from_json(&text, vertex_count).map_err(|m| format_error(path, m))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    #[test]
    fn region_json_forms() {
        let mesh = shapes::plane(9);
        let f = RegionSpec::from_json(r#"{"faces":[0,1,2,2]}"#).unwrap();
        assert_eq!(
            f.faces(&mesh).unwrap(),
            vec![FaceId(0), FaceId(1), FaceId(2)]
        );
        // vertices: exactly the faces all of whose vertices are listed
        let v = RegionSpec::from_json(r#"{"vertices":[0,1,9,10]}"#).unwrap();
        let fv = v.faces(&mesh).unwrap();
        assert_eq!(fv.len(), 2);
        let s = RegionSpec::from_json(r#"{"sphere":{"center":[0,0,0],"radius":0.6},"regions":[]}"#)
            .unwrap();
        let p = mesh.positions();
        for f in s.faces(&mesh).unwrap() {
            assert!(mesh.face_vertices(f).all(|w| p[w.idx()].length() <= 0.6));
        }
        assert_eq!(RegionSpec::from_json(&s.to_json()).unwrap(), s);
        assert_eq!(
            RegionSpec::Faces(vec![3, 1]).to_json(),
            r#"{"faces":[3,1]}"#
        );
        for bad in [
            "{}",
            r#"{"faces":[1],"vertices":[2]}"#,
            r#"{"sphere":{"center":[0,0,0],"radius":-1}}"#,
            "not json",
        ] {
            let e = RegionSpec::from_json(bad).unwrap_err();
            assert!(e.to_string().starts_with("invalid region: "), "{bad}: {e}");
        }
        assert!(RegionSpec::Faces(vec![9999]).faces(&mesh).is_err());
        assert!(RegionSpec::Vertices(vec![9999]).faces(&mesh).is_err());
        let far = RegionSpec::Sphere {
            center: Vec3::splat(10.0),
            radius: 0.1,
        };
        assert!(far.faces(&mesh).is_err());
    }

    #[test]
    fn files_are_read_and_errors_name_them() {
        let dir = std::env::temp_dir().join(format!("fairline-selection-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let region = dir.join("region.json");
        std::fs::write(&region, r#"{"faces":[4,2]}"#).unwrap();
        assert_eq!(read_region(&region).unwrap(), RegionSpec::Faces(vec![4, 2]));
        std::fs::write(&region, r#"{"faces":"x"}"#).unwrap();
        let e = read_region(&region).unwrap_err().to_string();
        assert!(
            e.contains("region.json: invalid region: cannot parse region JSON"),
            "{e}"
        );
        let fixed = dir.join("fixed.json");
        std::fs::write(&fixed, r#"{"vertices":[0,7]}"#).unwrap();
        assert_eq!(
            read_fixed_vertices(&fixed, 8).unwrap(),
            vec![VertexId(0), VertexId(7)]
        );
        let e = read_fixed_vertices(&fixed, 7).unwrap_err().to_string();
        assert!(
            e.ends_with("fixed.json: vertices[1] = 7 is not a vertex (the mesh has 7)"),
            "{e}"
        );
        for bad in [
            r#"{"vertices":[-1]}"#,
            r#"{"vertex":[1]}"#,
            r#"{"vertices":[1],"faces":[]}"#,
            "[",
        ] {
            std::fs::write(&fixed, bad).unwrap();
            let e = read_fixed_vertices(&fixed, 7).unwrap_err().to_string();
            assert!(e.contains("fixed.json: "), "{bad}: {e}");
        }
        let missing = dir.join("none.json");
        assert!(
            read_fixed_vertices(&missing, 7)
                .unwrap_err()
                .to_string()
                .contains("none.json")
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
