//! Readable linear lights on parts of B-spline surfaces (issue #20): the
//! mesh side's default lights and readable drawing
//! ([`LightArray::default_for_mesh`], [`LightArray::readable_multiple`],
//! [`Readability`], see [`crate::highlight::readable`]) applied to a part,
//! so that `fairline highlight PART.json` with no light options draws the
//! lines a readable number of pixels apart, as `fairline highlight
//! MESH.ply` does (beyond Yong et al., who draw every line).
//!
//! The distance gradient |∇d_P| is evaluated exactly on the surface (from
//! the first and second derivatives), not on triangles.

use super::{SurfaceHighlightLine, SurfaceLight};
use crate::Vec3;
use crate::bspline::{BSplineSurface, SurfaceDerivatives, tessellate_part};
use crate::highlight::readable::polyline_length;
use crate::highlight::{HighlightError, LightArray, LightChoice, Readability, UpAxis};
use rayon::prelude::*;

/// Samples along the part's diagonal of the tessellation the default
/// linear lights are chosen on ([`part_light_array`]).
pub const LIGHT_CHOICE_SAMPLES: usize = 48;

/// The linear light array of a part and what its picture can show:
///
/// - `given` (e.g. read from a lights file) is used as it is;
/// - otherwise the array of `choice`: with a plane normal given, the
///   defaults of the control points' bounding box
///   ([`LightChoice::light_array_in_box`]); without, the mesh side's default
///   lights of the part ([`LightChoice::light_array`]: plane normal from the
///   principal axes and the surface's facing, light direction along the
///   part) — both with the spacing made readable unless `choice.spacing` is
///   given ([`LightChoice::readable`]: every k-th light, k = round(ĝ/3)
///   with ĝ the area-weighted median of |∇d_P|).
///
/// The mesh functions see the part tessellated with
/// [`LIGHT_CHOICE_SAMPLES`] samples along its diagonal
/// ([`tessellate_part`]). The [`Readability`] is that of the part's width
/// across the lights ([`Readability::for_part`]).
pub fn part_light_array(
    surfaces: &[BSplineSurface],
    choice: &LightChoice,
    given: Option<LightArray>,
) -> Result<(LightArray, Readability), HighlightError> {
    let (mesh, _) = tessellate_part(surfaces, LIGHT_CHOICE_SAMPLES)?;
    let array = match given {
        Some(a) => a,
        None => {
            let base = if choice.plane_normal.is_some() {
                let (mut lo, mut hi) = (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY));
                for s in surfaces {
                    let (a, b) = s.control_bounding_box();
                    lo = lo.min(a);
                    hi = hi.max(b);
                }
                choice.light_array_in_box(lo, hi)?
            } else if choice.up == UpAxis::Auto {
                most_readable_axis(&mesh, choice)?
            } else {
                choice.light_array(&mesh)?
            };
            choice.readable(&mesh, base)?
        }
    };
    let readability = Readability::for_part(&mesh, &array);
    Ok((array, readability))
}

/// The lights of `choice` (no plane normal given, `up` automatic) facing
/// the part from the side where its lines are most readable: of the mesh
/// side's defaults with the lights along +z, +y and +x
/// ([`LightChoice::light_array`] with [`UpAxis::Z`], …: light direction
/// along the part's longest extent), the one with the smallest
/// area-weighted median ĝ of |∇d_P| (the first on ties): the lines lie
/// farthest apart over most of the part. The mesh side's automatic axis
/// (least extent, turned to the side the surface faces) is not used: on a
/// part of patches the facing depends on how each patch happens to be
/// parametrised (it put the teapot's lights below it).
fn most_readable_axis(
    mesh: &crate::SurfaceMesh,
    choice: &LightChoice,
) -> Result<LightArray, HighlightError> {
    let mut best: Option<(f64, LightArray)> = None;
    for up in [UpAxis::Z, UpAxis::Y, UpAxis::X] {
        let array = choice.up(up).light_array(mesh)?;
        let g = crate::highlight::readable::sampled_median_distance_gradient(
            mesh,
            &array,
            crate::highlight::readable::GRADIENT_SAMPLE_FACES,
        )
        .unwrap_or(f64::INFINITY);
        if best.as_ref().is_none_or(|b| g < b.0) {
            best = Some((g, array));
        }
    }
    match best {
        Some((_, a)) => Ok(a),
        None => choice.light_array(mesh),
    }
}

/// |∇d_P|, the gradient on the surface of the highlight distance d_P of
/// Yong et al. Eq. (1) (sign of DESIGN.md §3), at the point with
/// derivatives `d`: neighbouring highlight lines lie s/|∇d_P| apart there
/// ([`crate::highlight::readable`]). With n = S_u × S_v, N = n/|n|,
/// f = ((P − A0) × N)·H and g = Z·N (d_P = f/g):
///
/// - N_u = (n_u − N (N·n_u))/|n| with n_u = S_uu × S_v + S_u × S_uv (and
///   likewise in v), the derivative of the unit normal of Nishiyama et al.
///   Eq. (2.4);
/// - d_u = (f_u g − f g_u)/g² with f_u = (S_u × N + (P − A0) × N_u)·H and
///   g_u = Z·N_u;
/// - |∇d|² = (G d_u² − 2F d_u d_v + E d_v²)/(EG − F²) with the first
///   fundamental form E, F, G.
///
/// `None` where |Z·N| < `min_cos` (d_P undefined), the normal or the first
/// fundamental form is degenerate, or the result is not finite.
pub fn linear_distance_gradient(
    array: &LightArray,
    d: &SurfaceDerivatives,
    min_cos: f64,
) -> Option<f64> {
    let n = d.su.cross(d.sv);
    let len = n.length();
    if !(len > 0.0 && len.is_finite()) {
        return None;
    }
    let unit = n / len;
    let (z, h) = (array.plane_normal(), array.direction());
    let g = z.dot(unit);
    if !(g.abs() >= min_cos) || g == 0.0 {
        return None;
    }
    let normal_derivative = |m: Vec3| (m - unit * unit.dot(m)) / len;
    let n_u = normal_derivative(d.suu.cross(d.sv) + d.su.cross(d.suv));
    let n_v = normal_derivative(d.suv.cross(d.sv) + d.su.cross(d.svv));
    let r = d.point - array.plane_point();
    let f = r.cross(unit).dot(h);
    let derivative = |s: Vec3, n_s: Vec3| {
        let f_s = (s.cross(unit) + r.cross(n_s)).dot(h);
        let g_s = z.dot(n_s);
        (f_s * g - f * g_s) / (g * g)
    };
    let (du, dv) = (derivative(d.su, n_u), derivative(d.sv, n_v));
    let (e, ff, gg) = (d.su.dot(d.su), d.su.dot(d.sv), d.sv.dot(d.sv));
    let det = e * gg - ff * ff;
    if !(det > 0.0 && det.is_finite()) {
        return None;
    }
    let q = (gg * du * du - 2.0 * ff * du * dv + e * dv * dv) / det;
    let grad = q.max(0.0).sqrt();
    grad.is_finite().then_some(grad)
}

/// The readable drawing of the linear highlight lines of one surface (the
/// rule of [`crate::highlight::readable`] for meshes): each line is cut at
/// the points where the separation s/|∇d_P| from its neighbours
/// ([`linear_distance_gradient`], s the spacing of its array) is below
/// `r.min_separation`, and the pieces shorter than `r.min_length` that
/// such a cut made are left out (a short piece that the cut did not make —
/// a whole line on a small patch, or a piece ending on the patch border —
/// may continue on the neighbouring patch and is kept). Lines of circular
/// lights are kept as they are. Pieces keep their light, level and radius;
/// deterministic.
pub fn readable_surface_lines(
    surface: &BSplineSurface,
    lights: &[SurfaceLight],
    lines: &[SurfaceHighlightLine],
    r: &Readability,
) -> Vec<SurfaceHighlightLine> {
    lines
        .par_iter()
        .flat_map_iter(|line| {
            let Some(SurfaceLight::Linear { array, min_cos, .. }) = lights.get(line.light) else {
                return vec![line.clone()];
            };
            let max_gradient = if r.min_separation > 0.0 {
                array.spacing() / r.min_separation
            } else {
                f64::INFINITY
            };
            let keep: Vec<bool> = line
                .uv
                .iter()
                .map(|&[u, v]| {
                    linear_distance_gradient(array, &surface.derivatives(u, v), *min_cos)
                        .is_some_and(|g| g <= max_gradient)
                })
                .collect();
            readable_pieces(line, &keep, r.min_length)
        })
        .collect()
}

/// The pieces of `line` made of the points marked `keep`; a piece that
/// ends next to a dropped point and is shorter than `min_length` is left
/// out.
fn readable_pieces(
    line: &SurfaceHighlightLine,
    keep: &[bool],
    min_length: f64,
) -> Vec<SurfaceHighlightLine> {
    let n = line.uv.len();
    if keep.iter().all(|&k| k) {
        return vec![line.clone()];
    }
    // Runs of kept points (start, length); a loop is walked from a dropped
    // point so that no run wraps.
    let start = if line.closed {
        keep.iter().position(|&k| !k).unwrap_or(0)
    } else {
        0
    };
    let steps = if line.closed { n + 1 } else { n };
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut run: Option<(usize, usize)> = None;
    for k in 0..steps {
        let i = (start + k) % n;
        if keep[i] {
            run = Some(run.map_or((k, 1), |(s, len)| (s, len + 1)));
        } else if let Some(r) = run.take() {
            runs.push(r);
        }
    }
    runs.extend(run);
    runs.into_iter()
        .filter_map(|(first, len)| {
            let idx: Vec<usize> = (first..first + len).map(|k| (start + k) % n).collect();
            if idx.len() < 2 {
                return None;
            }
            let points: Vec<Vec3> = idx.iter().map(|&i| line.points[i]).collect();
            let cut_at_start = line.closed || first > 0;
            let cut_at_end = line.closed || first + len < steps;
            if (cut_at_start || cut_at_end) && polyline_length(&points, false) < min_length {
                return None;
            }
            Some(SurfaceHighlightLine {
                light: line.light,
                radius: line.radius,
                level: line.level,
                closed: false,
                uv: idx.iter().map(|&i| line.uv[i]).collect(),
                points,
            })
        })
        .collect()
}
