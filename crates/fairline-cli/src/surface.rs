//! Loading B-spline surfaces from the command line (.json, .igs/.iges,
//! .step/.stp or .g2, by extension through `fairline::io::surface_file`) and
//! turning them into meshes for drawing.

use crate::error::bad_input;
use anyhow::Result;
use fairline::SurfaceMesh;
use fairline::bspline::BSplineSurface;
use fairline::io::surface_file::{SurfaceFile, SurfaceFormat, read_surface_file};
use std::path::Path;

/// True when the path names a surface file (.json, .igs/.iges, .step/.stp,
/// .g2).
pub fn is_surface_path(path: &Path) -> bool {
    SurfaceFormat::from_path(path).is_some()
}

/// True when the path names a surface file fairline writes (.json,
/// .igs/.iges, .step/.stp).
pub fn is_writable_surface_path(path: &Path) -> bool {
    SurfaceFormat::from_path(path).is_some_and(SurfaceFormat::is_writable)
}

static SKIP_UNREADABLE: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// `--skip-unreadable`: faces a surface file holds but fairline cannot read
/// are warned about instead of failing the command.
pub fn set_skip_unreadable(on: bool) {
    SKIP_UNREADABLE.store(on, std::sync::atomic::Ordering::Relaxed);
}

/// Whether `--skip-unreadable` was given.
pub fn skip_unreadable() -> bool {
    SKIP_UNREADABLE.load(std::sync::atomic::Ordering::Relaxed)
}

/// How many unreadable faces a message names.
pub const UNREADABLE_NAMED: usize = 5;

/// The error (exit status 1) for a file with faces that could not be read:
/// names the first few and the count, and the way on.
pub fn unreadable_error(path: &Path, summary: &str) -> anyhow::Error {
    anyhow::anyhow!(
        "{}: {summary}; the part is incomplete (pass --skip-unreadable to go on without them)",
        path.display()
    )
}

/// The surfaces of a file as read, unreadable faces listed but not
/// refused (for `info`); the file's warnings are printed.
pub fn load_surface_file_listing(path: &Path) -> Result<SurfaceFile> {
    let file = read_surface_file(path).map_err(|e| crate::output::name_file(path, e))?;
    if file.surfaces.is_empty() && file.unreadable.is_empty() {
        return Err(bad_input(format!(
            "{}: the file holds no B-spline surface",
            path.display()
        )));
    }
    for w in &file.warnings {
        crate::output::warn(format!("{}: {w}", path.display()));
    }
    Ok(file)
}

/// All surfaces of a JSON, IGES or STEP file, with the file's length unit.
/// Faces the file holds that cannot be read fail it (exit status 1, naming
/// them) unless `--skip-unreadable` was given, which warns about them; a
/// file none of whose faces can be read is bad input (exit status 2).
pub fn load_surface_file(path: &Path) -> Result<SurfaceFile> {
    let file = read_surface_file(path).map_err(|e| crate::output::name_file(path, e))?;
    if let Some(summary) = file.unreadable_summary(UNREADABLE_NAMED, None) {
        if file.surfaces.is_empty() {
            // nothing left to go on with: the file is unusable as it is
            return Err(bad_input(format!(
                "{}: no face could be read: {summary}",
                path.display()
            )));
        }
        if !skip_unreadable() {
            return Err(unreadable_error(path, &summary));
        }
        crate::output::warn(format!(
            "{}: {summary} (left out: --skip-unreadable)",
            path.display()
        ));
    }
    if file.surfaces.is_empty() {
        return Err(bad_input(format!(
            "{}: the file holds no B-spline surface",
            path.display()
        )));
    }
    for w in &file.warnings {
        crate::output::warn(format!("{}: {w}", path.display()));
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
/// faces renders as fast as one surface of its size.
pub fn tessellated_part(surfaces: &[BSplineSurface], n: usize) -> Result<SurfaceMesh> {
    Ok(tessellated_part_with_patches(surfaces, n)?.0)
}

/// The view direction and up of a picture of a part of `surfaces`: the
/// camera rule's ([`fairline::picture::part_view`] of the part tessellated
/// with 64 samples along its diagonal), the direction replaced by `view`
/// when given.
pub fn camera(
    surfaces: &[BSplineSurface],
    view: Option<fairline::Vec3>,
) -> Result<(fairline::Vec3, fairline::Vec3)> {
    let pv = fairline::picture::part_view(&tessellated_part(surfaces, 64)?);
    Ok((view.unwrap_or(pv.view_dir), pv.up))
}

/// [`tessellated_part`] and the patch (index into `surfaces`) of every face
/// ([`fairline::bspline::tessellate_part`]).
pub fn tessellated_part_with_patches(
    surfaces: &[BSplineSurface],
    n: usize,
) -> Result<(SurfaceMesh, Vec<u32>)> {
    Ok(fairline::bspline::tessellate_part(surfaces, n)?)
}

/// Tessellates every surface on the grid `grid(s)` into one triangle mesh;
/// also the surface of every face ([`fairline::bspline::tessellate_part_with`]).
fn tessellated_with(
    surfaces: &[BSplineSurface],
    grid: impl Fn(&BSplineSurface) -> [usize; 2] + Sync,
) -> Result<(SurfaceMesh, Vec<u32>)> {
    Ok(fairline::bspline::tessellate_part_with(surfaces, grid)?)
}
