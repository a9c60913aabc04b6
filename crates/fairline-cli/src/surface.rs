//! Loading B-spline surfaces from the command line (.json, .igs/.iges or
//! .step/.stp, by extension through `fairline::io::surface_file`) and
//! turning them into meshes for drawing.

use crate::error::bad_input;
use anyhow::Result;
use fairline::SurfaceMesh;
use fairline::bspline::{BSplineSurface, tessellate};
use fairline::io::surface_file::{SurfaceFile, SurfaceFormat, read_surface_file};
use std::path::Path;

/// True when the path names a surface file (.json, .igs/.iges, .step/.stp).
pub fn is_surface_path(path: &Path) -> bool {
    SurfaceFormat::from_path(path).is_some()
}

/// All surfaces of a JSON, IGES or STEP file, with the file's length unit.
pub fn load_surface_file(path: &Path) -> Result<SurfaceFile> {
    let file = read_surface_file(path).map_err(|e| crate::output::name_file(path, e))?;
    if file.surfaces.is_empty() {
        return Err(bad_input(format!(
            "{}: the file holds no B-spline surface",
            path.display()
        )));
    }
    Ok(file)
}

/// All surfaces of a JSON, IGES or STEP file.
pub fn load_surfaces(path: &Path) -> Result<Vec<BSplineSurface>> {
    Ok(load_surface_file(path)?.surfaces)
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
    Ok(tessellated_with(surfaces, |_| [n, n])?.0)
}

/// Tessellates a part for a picture: one surface `n` × `n`; several, each on
/// its [`fairline::highlight::patch_grid`] (about `n` samples along the
/// part's diagonal, small faces get few), so that a part of hundreds of
/// faces renders as fast as one surface of its size (issue #20 item 4).
pub fn tessellated_part(surfaces: &[BSplineSurface], n: usize) -> Result<SurfaceMesh> {
    Ok(tessellated_part_with_patches(surfaces, n)?.0)
}

/// [`tessellated_part`] and the patch (index into `surfaces`) of every face.
pub fn tessellated_part_with_patches(
    surfaces: &[BSplineSurface],
    n: usize,
) -> Result<(SurfaceMesh, Vec<u32>)> {
    if surfaces.len() <= 1 {
        return tessellated_with(surfaces, |_| [n, n]);
    }
    let (mut lo, mut hi) = (
        fairline::Vec3::splat(f64::INFINITY),
        fairline::Vec3::splat(f64::NEG_INFINITY),
    );
    for s in surfaces {
        let (a, b) = s.control_bounding_box();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    let diagonal = (hi - lo).length();
    tessellated_with(surfaces, |s| {
        fairline::highlight::patch_grid(s, diagonal, n)
    })
}

/// Tessellates every surface on the grid `grid(s)` (in parallel, merged in
/// input order) into one triangle mesh; also the surface of every face.
fn tessellated_with(
    surfaces: &[BSplineSurface],
    grid: impl Fn(&BSplineSurface) -> [usize; 2] + Sync,
) -> Result<(SurfaceMesh, Vec<u32>)> {
    use rayon::prelude::*;
    let pieces: Vec<_> = surfaces
        .par_iter()
        .map(|s| {
            let [nu, nv] = grid(s);
            tessellate(s, nu, nv)
        })
        .collect();
    let mut positions = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut patch: Vec<u32> = Vec::new();
    for (k, t) in pieces.into_iter().enumerate() {
        let base = positions.len() as u32;
        positions.extend(t.positions);
        triangles.extend(t.triangles.iter().map(|tri| tri.map(|i| i + base)));
        patch.resize(triangles.len(), k as u32);
    }
    // Degenerate points (poles of a patch) can make a tessellation
    // non-manifold; keep only the triangles a manifold mesh accepts.
    match SurfaceMesh::new(positions.clone(), &triangles) {
        Ok(m) => Ok((m, patch)),
        Err(_) => {
            let keep = |t: &[u32; 3]| t[0] != t[1] && t[1] != t[2] && t[0] != t[2];
            let kept_patch: Vec<u32> = triangles
                .iter()
                .zip(&patch)
                .filter(|(t, _)| keep(t))
                .map(|(_, &p)| p)
                .collect();
            let kept: Vec<[u32; 3]> = triangles.into_iter().filter(keep).collect();
            Ok((SurfaceMesh::new(positions, &kept)?, kept_patch))
        }
    }
}
