//! An open document of the workbench: a mesh or a set of B-spline surfaces,
//! the triangle mesh drawn for it, and its history of steps (undo/redo).

use crate::error::bad_input;
use anyhow::Result;
use fairline::bspline::{BSplineSurface, tessellate};
use fairline::mesh::FaceId;
use fairline::{SurfaceMesh, Vec3};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};
use std::time::Instant;

/// One state of a document: its positions (and surfaces) after an action.
pub struct Step {
    /// What was done ("open", "fair (highlight)", ...).
    pub label: String,
    /// The equivalent `fairline` command.
    pub command: String,
    /// The report of the action.
    pub report: Value,
    /// Vertex positions of the drawn triangle mesh.
    pub positions: Arc<Vec<Vec3>>,
    /// The surfaces (surface documents only).
    pub surfaces: Option<Arc<Vec<BSplineSurface>>>,
    /// The vertex normals of these positions as the page gets them (f32
    /// triples), computed once, on first request (the open step: while the
    /// file is loaded).
    pub normal_bytes: OnceLock<Vec<u8>>,
}

impl Step {
    /// A step with its normals not computed yet.
    pub fn new(
        label: String,
        command: String,
        report: Value,
        positions: Arc<Vec<Vec3>>,
        surfaces: Option<Arc<Vec<BSplineSurface>>>,
    ) -> Step {
        Step {
            label,
            command,
            report,
            positions,
            surfaces,
            normal_bytes: OnceLock::new(),
        }
    }
}

/// A mesh or surface file opened in the workbench.
pub struct Doc {
    /// File name shown on the page.
    pub name: String,
    /// The path given on the command line.
    pub path: PathBuf,
    /// The mesh as read when it has polygons (else `tri` is the mesh as
    /// read; see [`Doc::input_mesh`]).
    pub polygons: Option<SurfaceMesh>,
    /// The triangle mesh drawn and given to triangle algorithms (for
    /// surfaces, the tessellation); the same vertices as the input mesh.
    pub tri: Arc<SurfaceMesh>,
    /// Input face of each triangle when `mesh` has polygons.
    pub tri_source: Option<Vec<FaceId>>,
    /// Patch index of each triangle (surfaces), else empty.
    pub patch_of_triangle: Vec<u32>,
    /// Tessellation grid per patch direction (surfaces).
    pub grid: usize,
    /// The length unit a surface file declares (IGES, STEP), written
    /// into the files made from it.
    pub unit: Option<fairline::io::units::LengthUnit>,
    /// Scalar vertex properties read from a PLY file.
    pub ply_scalars: Vec<(String, Vec<f64>)>,
    /// Bounding-box centre of the input (binary positions are relative to it).
    pub center: Vec3,
    /// Half the bounding-box diagonal.
    pub radius: f64,
    /// Bounding box of the input.
    pub bbox: (Vec3, Vec3),
    /// The camera rule's view of the input ([`fairline::picture::part_view`]):
    /// the workbench's first view, the same as the command line's pictures.
    pub view: fairline::render::PartView,
    /// Steps; `history[cursor]` is the current state.
    pub history: Vec<Step>,
    /// Index of the current step.
    pub cursor: usize,
    /// `tri` with the current step's positions when that is not step 0
    /// (kept in step with `cursor`, so requests on the current state need no
    /// copy of the mesh; see [`Doc::now`]).
    now_moved: Option<Arc<SurfaceMesh>>,
    /// The triangles of `tri` as the page gets them (u32 triples).
    pub index_bytes: Vec<u8>,
    /// Where opening the file took its time (seconds): `read` (reading and
    /// building the mesh, or reading and tessellating the surfaces),
    /// `prepare` (triangulation, normals and the binary buffers), `total`.
    pub load_s: Value,
}

/// The triangle mesh of surfaces tessellated `n` × `n` per patch, and the
/// patch index of each triangle.
pub fn tessellate_all(surfaces: &[BSplineSurface], n: usize) -> Result<(SurfaceMesh, Vec<u32>)> {
    let mut positions = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut patch = Vec::new();
    for (k, s) in surfaces.iter().enumerate() {
        let t = tessellate(s, n, n);
        let base = positions.len() as u32;
        positions.extend(t.positions);
        for tri in &t.triangles {
            // degenerate corners (poles) would make the mesh non-manifold
            if tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2] {
                triangles.push(tri.map(|i| i + base));
                patch.push(k as u32);
            }
        }
    }
    let mesh = SurfaceMesh::new(positions, &triangles)?;
    Ok((mesh, patch))
}

impl Doc {
    /// Reads a mesh or surface file.
    pub fn open(path: &Path, grid: usize) -> Result<Doc> {
        let t0 = Instant::now();
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| path.display().to_string());
        let mut unit = None;
        let (mesh, surfaces, patch_of_triangle, ply_scalars) =
            if crate::surface::is_surface_path(path) {
                let file = crate::surface::load_surface_file(path)?;
                unit = file.unit;
                let (mesh, patch) = tessellate_all(&file.surfaces, grid)?;
                (mesh, Some(Arc::new(file.surfaces)), patch, Vec::new())
            } else {
                let mesh = fairline::io::read_mesh(path)?;
                let is_ply = path
                    .extension()
                    .and_then(|e| e.to_str())
                    .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
                let scalars = if is_ply {
                    fairline::io::read_ply_vertex_properties(path)
                        .map(|(_, props)| props)
                        .unwrap_or_default()
                        .into_iter()
                        .filter(|(n, v)| {
                            v.len() == mesh.vertex_count()
                                && !matches!(
                                    n.as_str(),
                                    "nx" | "ny" | "nz" | "red" | "green" | "blue" | "alpha"
                                )
                        })
                        .collect()
                } else {
                    Vec::new()
                };
                (mesh, None, Vec::new(), scalars)
            };
        let read_s = t0.elapsed().as_secs_f64();
        let (lo, hi) = fairline::mesh::bounding_box(mesh.positions())
            .ok_or_else(|| bad_input(format!("{}: no vertices", path.display())))?;
        if mesh.face_count() == 0 {
            return Err(bad_input(format!("{}: no faces", path.display())));
        }
        // a triangle mesh is kept once (no copy for drawing, none for the
        // current state until a step moves it)
        let (tri, tri_source, polygons) = if mesh.is_triangle_mesh() {
            (mesh, None, None)
        } else {
            let t = fairline::mesh::triangulate(&mesh)
                .map_err(|e| bad_input(format!("{}: {e}", path.display())))?;
            (t.mesh, Some(t.source_face), Some(mesh))
        };
        // the first frame needs the normals and the triangles: computed
        // here, in parallel
        let (((positions, index_bytes), view), normals) = rayon::join(
            || {
                rayon::join(
                    || (Arc::new(tri.positions().to_vec()), triangle_bytes(&tri)),
                    || fairline::picture::part_view(&tri),
                )
            },
            || super::frame::vec3_bytes(&fairline::geom::vertex_normals(&tri), Vec3::ZERO),
        );
        let normal_bytes = OnceLock::new();
        let _ = normal_bytes.set(normals);
        let center = 0.5 * (lo + hi);
        let radius = (0.5 * (hi - lo).length()).max(f64::MIN_POSITIVE);
        let kind = if surfaces.is_some() {
            "surface"
        } else {
            "mesh"
        };
        Ok(Doc {
            name: name.clone(),
            path: path.to_path_buf(),
            polygons,
            tri: Arc::new(tri),
            tri_source,
            patch_of_triangle,
            grid,
            unit,
            ply_scalars,
            center,
            radius,
            bbox: (lo, hi),
            view,
            history: vec![Step {
                label: "open".into(),
                command: format!("fairline view {}", shell_word(&path.display().to_string())),
                report: json!({"command": "open", "kind": kind}),
                positions,
                surfaces,
                normal_bytes,
            }],
            cursor: 0,
            now_moved: None,
            index_bytes,
            load_s: json!({
                "read": read_s,
                "prepare": t0.elapsed().as_secs_f64() - read_s,
                "total": t0.elapsed().as_secs_f64(),
            }),
        })
    }

    /// True for B-spline surface documents.
    pub fn is_surface(&self) -> bool {
        self.history[0].surfaces.is_some()
    }

    /// The current step.
    pub fn current(&self) -> &Step {
        &self.history[self.cursor]
    }

    /// The step `n` (clamped to the history).
    pub fn step(&self, n: Option<usize>) -> &Step {
        &self.history[n.unwrap_or(self.cursor).min(self.history.len() - 1)]
    }

    /// The vertex normals of step `n` (default the current one) as f32
    /// triples: the library's area-weighted vertex normals (Yong et al.
    /// Eq. (3)), computed once per step.
    pub fn normal_bytes(&self, n: Option<usize>) -> &[u8] {
        let current = n.is_none_or(|n| n.min(self.history.len() - 1) == self.cursor);
        self.step(n).normal_bytes.get_or_init(|| {
            let normals = if current {
                fairline::geom::vertex_normals(self.now())
            } else {
                fairline::geom::vertex_normals(&self.tri_at(n))
            };
            super::frame::vec3_bytes(&normals, Vec3::ZERO)
        })
    }

    /// The drawn triangle mesh at step `n`.
    pub fn tri_at(&self, n: Option<usize>) -> SurfaceMesh {
        let mut m = (*self.tri).clone();
        // same vertex count by construction
        let _ = m.set_positions(self.step(n).positions.to_vec());
        m
    }

    /// The drawn triangle mesh at step `n`, shared: requests compute on it
    /// after they have let go of the workbench's lock.
    pub fn shared_tri_at(&self, n: Option<usize>) -> Arc<SurfaceMesh> {
        let current = n.is_none_or(|n| n.min(self.history.len() - 1) == self.cursor);
        if current {
            Arc::clone(self.now_moved.as_ref().unwrap_or(&self.tri))
        } else {
            Arc::new(self.tri_at(n))
        }
    }

    /// The mesh as read (polygons kept; for surfaces the tessellation).
    pub fn input_mesh(&self) -> &SurfaceMesh {
        self.polygons.as_ref().unwrap_or(&self.tri)
    }

    /// The drawn triangle mesh with the current step's positions.
    pub fn now(&self) -> &SurfaceMesh {
        self.now_moved.as_ref().unwrap_or(&self.tri)
    }

    /// The input mesh (polygons kept) at the current step.
    pub fn mesh_now(&self) -> SurfaceMesh {
        let mut m = self.input_mesh().clone();
        let _ = m.set_positions(self.current().positions.to_vec());
        m
    }

    /// Appends a step after the current one (dropping the redo tail).
    pub fn push(&mut self, step: Step) {
        self.history.truncate(self.cursor + 1);
        self.history.push(step);
        self.set_cursor(self.history.len() - 1);
    }

    /// Makes step `n` the current one.
    pub fn set_cursor(&mut self, n: usize) {
        self.cursor = n.min(self.history.len() - 1);
        if self.cursor == 0 {
            self.now_moved = None;
            return;
        }
        let positions = self.history[self.cursor].positions.to_vec();
        match &mut self.now_moved {
            // same vertex count by construction
            // (copied only while a request still computes on the old one)
            Some(m) => {
                let _ = Arc::make_mut(m).set_positions(positions);
            }
            None => {
                let mut m = (*self.tri).clone();
                let _ = m.set_positions(positions);
                self.now_moved = Some(Arc::new(m));
            }
        }
    }

    /// The file name the current state would have as a command's output.
    pub fn current_file(&self) -> String {
        if self.cursor == 0 {
            return shell_word(&self.path.display().to_string());
        }
        let stem = self
            .path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "out".into());
        shell_word(&format!("{stem}-step{}.{}", self.cursor, self.out_ext()))
    }

    /// The file name of the next step's output.
    pub fn next_file(&self) -> String {
        let stem = self
            .path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "out".into());
        shell_word(&format!(
            "{stem}-step{}.{}",
            self.cursor + 1,
            self.out_ext()
        ))
    }

    fn out_ext(&self) -> String {
        if self.is_surface() {
            return "json".into();
        }
        self.path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_else(|| "ply".into())
    }

    /// The region JSON of DESIGN.md §5 for a set of drawn triangles, in the
    /// input's face indices.
    pub fn input_faces(&self, triangles: &[u32]) -> Vec<u32> {
        let mut out: Vec<u32> = triangles
            .iter()
            .filter(|&&t| (t as usize) < self.tri.face_count())
            .map(|&t| match &self.tri_source {
                Some(src) => src[t as usize].0,
                None => t,
            })
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }
}

/// The triangles of a triangle mesh as u32 little-endian triples.
fn triangle_bytes(tri: &SurfaceMesh) -> Vec<u8> {
    let mut out = Vec::with_capacity(tri.face_count() * 12);
    for f in tri.faces() {
        for v in tri.triangle(f) {
            out.extend_from_slice(&v.0.to_le_bytes());
        }
    }
    out
}

/// `s` quoted for a POSIX shell when it holds anything but plain characters.
pub fn shell_word(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./,=:+".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}
