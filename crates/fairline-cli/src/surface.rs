//! Loading B-spline surfaces from the command line (.json or .igs/.iges)
//! and turning them into meshes for drawing.

use crate::common::bad_input;
use anyhow::Result;
use fairline::SurfaceMesh;
use fairline::bspline::{BSplineSurface, read_iges, read_surfaces_json, tessellate};
use std::path::Path;

/// True when the path names a surface file (.json, .igs, .iges).
pub fn is_surface_path(path: &Path) -> bool {
    matches!(
        path.extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref(),
        Some("json" | "igs" | "iges")
    )
}

/// All surfaces of a JSON or IGES file.
pub fn load_surfaces(path: &Path) -> Result<Vec<BSplineSurface>> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    let surfaces = if ext == "json" {
        read_surfaces_json(path).map_err(|e| crate::output::name_file(path, e))?
    } else {
        read_iges(path)
            .map_err(|e| crate::output::name_file(path, e))?
            .surfaces
            .into_iter()
            .map(|s| s.surface)
            .collect()
    };
    if surfaces.is_empty() {
        return Err(bad_input(format!(
            "{}: the file holds no B-spline surface",
            path.display()
        )));
    }
    Ok(surfaces)
}

/// One surface by index (`--surface K`).
pub fn load_surface(path: &Path, index: usize) -> Result<BSplineSurface> {
    let mut all = load_surfaces(path)?;
    if index >= all.len() {
        return Err(bad_input(format!(
            "{}: --surface {index} is out of range (the file holds {} surfaces)",
            path.display(),
            all.len()
        )));
    }
    Ok(all.swap_remove(index))
}

/// Tessellates the chosen surface (or every surface when `index` is `None`)
/// into one triangle mesh, `n` × `n` samples per surface.
pub fn load_tessellated(path: &Path, index: Option<usize>, n: usize) -> Result<SurfaceMesh> {
    let surfaces = match index {
        Some(k) => vec![load_surface(path, k)?],
        None => load_surfaces(path)?,
    };
    tessellated_mesh(&surfaces, n)
}

/// Tessellates surfaces into one triangle mesh, `n` × `n` samples each.
pub fn tessellated_mesh(surfaces: &[BSplineSurface], n: usize) -> Result<SurfaceMesh> {
    let mut positions = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    for s in surfaces {
        let t = tessellate(s, n, n);
        let base = positions.len() as u32;
        positions.extend(t.positions);
        triangles.extend(t.triangles.iter().map(|tri| tri.map(|i| i + base)));
    }
    // Degenerate points (poles of a patch) can make a tessellation
    // non-manifold; keep only the triangles a manifold mesh accepts.
    match SurfaceMesh::new(positions.clone(), &triangles) {
        Ok(m) => Ok(m),
        Err(_) => {
            let kept: Vec<[u32; 3]> = triangles
                .into_iter()
                .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
                .collect();
            Ok(SurfaceMesh::new(positions, &kept)?)
        }
    }
}
