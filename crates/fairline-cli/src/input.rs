//! Reading a command's input mesh: the refusal of a mesh without faces, the
//! note on non-manifold vertices that were split, and triangulation for the
//! commands that need triangles.

use crate::error::bad_input;
use anyhow::{Context, Result};
use fairline::SurfaceMesh;
use fairline::mesh::FaceId;
use std::path::Path;

/// Says on stderr how many non-manifold vertices of `path` were split into
/// separate fans (kept fixed, merged back on output); nothing when none.
pub fn note_split_vertices(path: &Path, mesh: &fairline::SurfaceMesh) {
    let n = mesh.split_vertex_count();
    if n > 0 {
        eprintln!(
            "note: {}: {n} non-manifold vertices split into {} fans; they stay fixed and are merged back on output",
            path.display(),
            n + mesh.vertex_count() - mesh.original_vertex_count()
        );
    }
}

/// Refuses (exit status 2, nothing written) the mesh file `path` of
/// `faces` faces and `vertices` vertices when it has no face: no command
/// but `info` has a surface to work on then.
pub fn require_faces(path: &Path, faces: usize, vertices: usize) -> Result<()> {
    fairline_commands::require_faces(faces, vertices)
        .map_err(|e| bad_input(format!("{}: {e}; nothing written", path.display())))
}

/// Reads a mesh file that has at least one face ([`require_faces`]).
pub fn read_mesh(path: &Path) -> Result<SurfaceMesh> {
    let mesh = fairline::io::read_mesh(path)?;
    require_faces(path, mesh.face_count(), mesh.original_vertex_count())?;
    Ok(mesh)
}

/// Reads a mesh that has at least one face and triangulates polygons; also returns, for each
/// triangle, the input face it came from (None when nothing changed).
pub fn read_triangles(path: &Path) -> Result<(SurfaceMesh, Option<Vec<FaceId>>)> {
    if crate::surface::is_surface_path(path) {
        return Err(bad_input(format!(
            "{}: B-spline surfaces are not handled by this command yet; give a mesh (.obj .ply .off .stl)",
            path.display()
        )));
    }
    let mesh = read_mesh(path)?;
    note_split_vertices(path, &mesh);
    if mesh.is_triangle_mesh() {
        Ok((mesh, None))
    } else {
        let t = fairline::mesh::triangulate(&mesh)
            .with_context(|| format!("{}: triangulating its polygons", path.display()))?;
        Ok((t.mesh, Some(t.source_face)))
    }
}
