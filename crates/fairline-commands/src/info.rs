//! `info`: what a mesh file or a surface file holds — counts, topology,
//! sizes, units, faces that could not be read — as its JSON report, as
//! every front end gives it. Reading the file and printing the table stay
//! in the front ends.

use crate::report::Report;
use crate::warning::Warning;
use fairline::bspline::BSplineSurface;
use fairline::io::surface_file::SurfaceFile;
use fairline::mesh::{MeshInfo, Soup, inspect};
use fairline::{Control, Vec3};
use serde_json::Value;

/// What `info` gives on a mesh.
#[derive(Clone, Debug)]
pub struct MeshInfoOutcome {
    /// The library's description of the mesh.
    pub info: MeshInfo,
    /// Its values as JSON (what `--json` prints): absent values, the edge
    /// lengths of a mesh without edges and the box of one without a finite
    /// vertex left out, non-finite numbers left out.
    pub value: Value,
    /// The JSON report.
    pub report: Report,
}

/// Describes the mesh `soup` (every mesh is accepted, an empty one too,
/// with a warning); `name` names the input in warnings. The computation
/// takes no control.
pub fn mesh(soup: &Soup, name: Option<&str>, control: &Control) -> MeshInfoOutcome {
    let _ = control;
    let mut report = Report::new("info");
    let info = report.time(|| inspect(soup));
    let mut value = serde_json::to_value(&info).unwrap_or_default();
    // Absent values (no genus for a non-manifold mesh, no manifold error for
    // a manifold one) are left out rather than written as null.
    // A file without edges has no edge lengths, one without a finite vertex
    // no bounding box: left out too, rather than written as zeros.
    let has_bbox = info.vertices > info.non_finite_vertices;
    if let Value::Object(m) = &mut value {
        m.retain(|_, v| !v.is_null());
        if info.edges == 0 {
            m.remove("edge_length");
        }
        if !has_bbox {
            m.remove("bbox");
        }
        for (k, v) in m.iter() {
            report.set(k, v);
        }
    }
    if info.faces == 0 {
        let what = match info.vertices {
            0 => "the file holds no vertex and no face: an empty mesh".to_string(),
            n => format!(
                "the file has no faces, so it holds no surface; only its {n} vertices are counted"
            ),
        };
        report.warn(Warning::Text(named(name, what)));
    }
    // the same values without non-finite numbers (report.set warned)
    let value = crate::finite_only("", value, &mut Vec::new()).unwrap_or_default();
    MeshInfoOutcome {
        info,
        value,
        report,
    }
}

/// `text` with the input's name in front.
fn named(name: Option<&str>, text: String) -> String {
    match name {
        Some(n) => format!("{n}: {text}"),
        None => text,
    }
}

/// What `info` gives on a surface file.
#[derive(Clone, Debug)]
pub struct SurfaceInfoOutcome {
    /// Trimmed surfaces.
    pub trimmed: usize,
    /// Rational surfaces.
    pub rational: usize,
    /// Largest degree in either direction.
    pub max_degree: usize,
    /// Control points of all surfaces.
    pub control_points: usize,
    /// Area of the trimmed faces, when asked for.
    pub area: Option<f64>,
    /// Box of the faces themselves (`None`: no face was read).
    pub bounding_box: Option<(Vec3, Vec3)>,
    /// The file's length unit.
    pub unit: Option<String>,
    /// The faces that could not be read, summed up (the first
    /// `unreadable_named` named).
    pub unreadable: Option<String>,
    /// The JSON report.
    pub report: Report,
}

/// Describes the surfaces of `file` (with the area of the trimmed faces
/// when `area`); `name` names the input in warnings; the summary of the
/// faces not read names the first `unreadable_named`. The computation takes
/// no control.
pub fn surfaces(
    file: &SurfaceFile,
    area: bool,
    name: Option<&str>,
    unreadable_named: usize,
    control: &Control,
) -> SurfaceInfoOutcome {
    let _ = control;
    let surfaces = &file.surfaces;
    let mut report = Report::new("info");
    let area: Option<f64> = report.time(|| area.then(|| part_area(surfaces)));
    let (mut lo, mut hi) = (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY));
    // the box of the faces themselves (sampled on the trimmed geometry), not
    // of their control nets
    for s in surfaces {
        let (a, b) =
            fairline::bspline::face_bounding_box(s).unwrap_or_else(|| s.control_bounding_box());
        lo = lo.min(a);
        hi = hi.max(b);
    }
    let trimmed = surfaces.iter().filter(|s| s.is_trimmed()).count();
    let rational = surfaces.iter().filter(|s| s.is_rational()).count();
    let max_degree = surfaces
        .iter()
        .map(|s| s.degree_u().max(s.degree_v()))
        .max()
        .unwrap_or(0);
    let control_points: usize = surfaces.iter().map(|s| s.control_points().len()).sum();
    let unit = file.unit.as_ref().map(|u| u.name.clone());
    report.set("surfaces", surfaces.len());
    // what the reader did not take as the file says (an offset surface
    // fitted within a tolerance, p-curves that disagree with their edges)
    if !file.warnings.is_empty() {
        report.set("reader_warnings", &file.warnings);
    }
    report.set("trimmed", trimmed);
    report.set("rational", rational);
    report.set("max_degree", max_degree);
    report.set("control_points", control_points);
    if let Some(a) = area {
        report.set("area", a);
    }
    // no face read: no bounding box (an empty box is not a number)
    let bounding_box =
        (!surfaces.is_empty() && lo.is_finite() && hi.is_finite()).then_some((lo, hi));
    if let Some((lo, hi)) = bounding_box {
        report.set("bounding_box", [lo.to_array(), hi.to_array()]);
    }
    if let Some(u) = &unit {
        report.set("unit", u);
    }
    report.set("unreadable_faces", file.unreadable.len());
    report.set("unreadable", &file.unreadable);
    let unreadable = file.unreadable_summary(unreadable_named, area);
    if let Some(msg) = &unreadable {
        report.warn(Warning::Text(named(name, msg.clone())));
    }
    SurfaceInfoOutcome {
        trimmed,
        rational,
        max_degree,
        control_points,
        area,
        bounding_box,
        unit,
        unreadable,
        report,
    }
}

/// The area of the trimmed faces, in parallel over the faces, summed in
/// file order.
fn part_area(surfaces: &[BSplineSurface]) -> f64 {
    use rayon::prelude::*;
    let areas: Vec<f64> = surfaces
        .par_iter()
        .map(|s| fairline::bspline::trimmed_area(s, 64, 64))
        .collect();
    areas.iter().sum()
}
