//! Readable linear lights on parts of B-spline surfaces: the
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
///   ([`LightChoice::light_array_in_box`]); with an `up` axis given, the
///   mesh side's default lights of the part for it
///   ([`LightChoice::light_array`]: light direction along the part); with
///   neither, the side of the part whose picture shows the most of it with
///   readable lines ([`best_covered_lights`]) — all with the spacing made
///   readable unless `choice.spacing` is given ([`LightChoice::readable`]:
///   every k-th light, k = round(ĝ/3) with ĝ the area-weighted median of
///   |∇d_P|).
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
    let (mesh, patch) = tessellate_part(surfaces, LIGHT_CHOICE_SAMPLES)?;
    let array = match given {
        Some(a) => a,
        None if choice.plane_normal.is_some() => {
            let (mut lo, mut hi) = (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY));
            for s in surfaces {
                let (a, b) = s.control_bounding_box();
                lo = lo.min(a);
                hi = hi.max(b);
            }
            choice.readable(&mesh, choice.light_array_in_box(lo, hi)?)?
        }
        None if choice.up == UpAxis::Auto => best_covered_lights(&mesh, &patch, choice)?.0,
        None => choice.readable(&mesh, choice.light_array(&mesh)?)?,
    };
    let readability = Readability::for_part(&mesh, &array);
    Ok((array, readability))
}

/// The view of a part's picture under the linear lights `light`: the
/// direction from the eye and the screen's up. With +z up on the screen
/// whenever the lights face sideways (their plane normal Z more than 45°
/// from the z axis), seen from a little above (CAD parts are modelled
/// z-up): `−Z − 0.35·up`. Otherwise from the lights' side, tilted about 40°
/// toward the screen's up (+y made orthogonal to Z; Z × H when Z lies
/// within 45° of y), so that what stands on a flat face shows beside it:
/// `−Z + 0.85·up`. The mesh pictures look along the lights tilted by 19°.
pub fn part_view(light: &LightArray) -> (Vec3, Vec3) {
    let z = light.plane_normal();
    let half = std::f64::consts::FRAC_1_SQRT_2;
    let up_z = (Vec3::Z - Vec3::Z.dot(z) * z).normalize_or_zero();
    if z.dot(Vec3::Z).abs() < half && up_z != Vec3::ZERO {
        return (-z - 0.35 * up_z, up_z);
    }
    let up_y = (Vec3::Y - Vec3::Y.dot(z) * z).normalize_or_zero();
    let up = if z.dot(Vec3::Y).abs() >= half || up_y == Vec3::ZERO {
        light.across()
    } else {
        up_y
    };
    (-z + 0.85 * up, up)
}

/// Size (pixels) of the pictures [`best_covered_lights`] judges the views
/// by: enough for the fraction of each patch that is seen, cheap next to
/// the tracing of the lines.
const COVERAGE_VIEW: (u32, u32) = (240, 180);

/// The readable lights of `choice` (no plane normal, `up` automatic) from
/// the side of the part whose picture shows the most of it with readable
/// lines, with that fraction of the part's area. Candidates: the mesh
/// side's default lights along +z, −z, +y, −y, +x and −x
/// ([`LightChoice::light_array`] with [`UpAxis::Z`], …, and the same lights
/// mirrored through the part's centre), each made readable
/// ([`LightChoice::readable`]); each is judged by [`covered_fraction`] seen
/// from [`part_view`]. The largest wins (the first on ties).
///
/// Before, the axis of the smallest median |∇d_P| was taken, with the
/// lights always on the + side: on the impeller (blades on one side of a
/// dish) the lights faced the dish's flat back, whose lines are the
/// sparsest, and the picture from the lights' side showed the back of the
/// dish with the blades hidden behind it.
pub fn best_covered_lights(
    mesh: &crate::SurfaceMesh,
    patch: &[u32],
    choice: &LightChoice,
) -> Result<(LightArray, f64), HighlightError> {
    let (lo, hi) =
        crate::mesh::bounding_box(mesh.positions()).ok_or(HighlightError::NoFiniteVertices)?;
    let centre = 0.5 * (lo + hi);
    let part = CoverageInput::new(mesh, patch);
    let mut best: Option<(f64, LightArray)> = None;
    for up in [UpAxis::Z, UpAxis::Y, UpAxis::X] {
        let above = choice.up(up).light_array(mesh)?;
        let below = LightArray::new(
            above.plane_point()
                - 2.0
                    * (above.plane_point() - centre).dot(above.plane_normal())
                    * above.plane_normal(),
            -above.plane_normal(),
            above.direction(),
            above.spacing(),
        )?;
        for base in [above, below] {
            let drawn = choice.readable(mesh, base)?;
            let covered = covered_fraction(&part, &drawn);
            if best.as_ref().is_none_or(|b| covered > b.0) {
                best = Some((covered, drawn));
            }
        }
    }
    match best {
        Some((c, a)) => Ok((a, c)),
        None => Ok((choice.readable(mesh, choice.light_array(mesh)?)?, 0.0)),
    }
}

/// What [`covered_fraction`] needs of a part's mesh, computed once for all
/// the candidate lights.
struct CoverageInput<'a> {
    mesh: &'a crate::SurfaceMesh,
    patch: &'a [u32],
    triangles: Vec<[u32; 3]>,
    normals: Vec<Vec3>,
    areas: Vec<f64>,
}

impl<'a> CoverageInput<'a> {
    fn new(mesh: &'a crate::SurfaceMesh, patch: &'a [u32]) -> Self {
        CoverageInput {
            mesh,
            patch,
            triangles: mesh
                .faces()
                .map(|f| mesh.triangle(f).map(|v| v.0))
                .collect(),
            normals: crate::geom::vertex_normals(mesh),
            areas: crate::geom::face_areas(mesh),
        }
    }
}

/// How much of the part its picture under `light` (seen from
/// [`part_view`]) shows with readable lines: the fraction of the part's
/// area shown times the mean fraction of each patch shown. Shown are the
/// triangles where the lines are drawn — |∇d_P| defined and at most
/// s/min_separation ([`Readability::for_part`], the rule of the readable
/// drawing) — weighted, patch by patch, by the fraction of their projected
/// area that is in front in a [`COVERAGE_VIEW`] picture
/// ([`crate::render::visible_triangles`]: the pixels where they are seen
/// over their projected pixel area, so hidden parts count as not shown).
/// Both terms: the area alone prefers one large flat face (the flat
/// underside of featuretype.STEP, none of its features), the patches alone
/// many small faces seen at a grazing angle. 0 when nothing can be judged.
fn covered_fraction(part: &CoverageInput, light: &LightArray) -> f64 {
    let mesh = part.mesh;
    let min_cos = crate::highlight::HighlightOptions::default().min_normal_cos;
    let (d, branch): (Vec<f64>, Vec<i8>) = mesh
        .positions()
        .par_iter()
        .zip(&part.normals)
        .map(|(&p, &n)| crate::highlight::light::vertex_distance(light, p, n, min_cos))
        .unzip();
    let gradient = crate::highlight::readable::face_distance_gradients(mesh, &d, &branch);
    let r = Readability::for_part(mesh, light);
    let max_gradient = if r.min_separation > 0.0 {
        light.spacing() / r.min_separation
    } else {
        f64::INFINITY
    };
    let readable: Vec<bool> = gradient
        .iter()
        .map(|g| g.is_some_and(|g| g <= max_gradient))
        .collect();
    let (dir, up) = part_view(light);
    let scene = crate::render::Scene {
        meshes: vec![crate::render::MeshLayer::new(
            mesh.positions(),
            &part.triangles,
        )],
        ..Default::default()
    };
    let opts = crate::render::RenderOptions::with_size(COVERAGE_VIEW.0, COVERAGE_VIEW.1)
        .view_dir(dir)
        .up(up)
        .supersample(1);
    let Ok(Some((camera, ids))) = crate::render::visible_triangles(&scene, &opts) else {
        return 0.0;
    };
    let mut seen = vec![0u32; part.triangles.len()];
    for &id in &ids {
        if let Some(c) = seen.get_mut(id as usize) {
            *c += 1;
        }
    }
    let (w, h) = (f64::from(COVERAGE_VIEW.0), f64::from(COVERAGE_VIEW.1));
    let pixel = |p: Vec3| {
        camera
            .project(p)
            .map(|q| [(q.x + 1.0) * 0.5 * w, (1.0 - q.y) * 0.5 * h])
    };
    let projected_pixels = |t: &[u32; 3]| -> f64 {
        let p = mesh.positions();
        match t.map(|k| pixel(p[k as usize])) {
            [Some(a), Some(b), Some(c)] => {
                0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs()
            }
            _ => 0.0,
        }
    };
    // per patch: readable area, its projected pixels and the pixels seen
    let patches = part.patch.iter().max().map_or(1, |&m| m as usize + 1);
    let mut sums = vec![[0.0f64; 3]; patches];
    for (f, t) in part.triangles.iter().enumerate() {
        if !readable[f] {
            continue;
        }
        let k = part.patch.get(f).map_or(0, |&k| k as usize);
        let s = &mut sums[k.min(patches - 1)];
        s[0] += part.areas[f];
        s[1] += projected_pixels(t);
        s[2] += f64::from(seen[f]);
    }
    // the part's area and each patch's
    let mut patch_area = vec![0.0f64; patches];
    for (f, a) in part.areas.iter().enumerate() {
        let k = part.patch.get(f).map_or(0, |&k| k as usize);
        patch_area[k.min(patches - 1)] += a;
    }
    let total: f64 = patch_area.iter().sum();
    let (mut shown, mut patches_shown) = (0.0, 0.0);
    for (s, &a) in sums.iter().zip(&patch_area) {
        if s[1] > 0.0 && a > 0.0 {
            let seen = s[0] * (s[2] / s[1]).min(1.0);
            shown += seen;
            patches_shown += seen / a;
        }
    }
    let score = (shown / total) * (patches_shown / patches as f64);
    if total > 0.0 && score.is_finite() {
        score
    } else {
        0.0
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
    let DistanceDerivatives { du, dv, .. } = distance_derivatives(array, d, min_cos)?;
    let (e, ff, gg) = (d.su.dot(d.su), d.su.dot(d.sv), d.sv.dot(d.sv));
    let det = e * gg - ff * ff;
    if !(det > 0.0 && det.is_finite()) {
        return None;
    }
    let q = (gg * du * du - 2.0 * ff * du * dv + e * dv * dv) / det;
    let grad = q.max(0.0).sqrt();
    grad.is_finite().then_some(grad)
}

/// The partial derivatives d_u, d_v of d_P at a surface point and its unit
/// normal (see [`linear_distance_gradient`] for the formulas).
struct DistanceDerivatives {
    du: f64,
    dv: f64,
    unit: Vec3,
}

fn distance_derivatives(
    array: &LightArray,
    d: &SurfaceDerivatives,
    min_cos: f64,
) -> Option<DistanceDerivatives> {
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
    Some(DistanceDerivatives {
        du: derivative(d.su, n_u),
        dv: derivative(d.sv, n_v),
        unit,
    })
}

/// The separation of neighbouring lines of `array` at a surface point as
/// seen on a picture looking along the unit vector `view` (parallel
/// projection): the neighbour lies δ = s ∇d_P/|∇d_P|² away on the surface
/// (s the spacing; ∇d_P = ((G d_u − F d_v) S_u + (E d_v − F d_u) S_v)/(EG −
/// F²), the surface gradient of Nishiyama et al. Eq. (2.15)'s distance),
/// and the screen distance between the two projected lines is the part of
/// the projected δ across the projected line tangent t = N × ∇d/|∇d|:
/// |(δ × t)·view| / |t − (t·view) view| = (s/|∇d|) |N·view| / |t −
/// (t·view) view|. Equal to the separation on the surface s/|∇d| where
/// the surface faces the viewer, smaller toward grazing angles (never
/// larger: |t − (t·v) v| ≥ |N·v| for orthonormal t, N). A line seen end on
/// (t along the view) keeps its surface separation. `None` where d_P or
/// its gradient is undefined or zero.
pub fn linear_separation_on_screen(
    array: &LightArray,
    d: &SurfaceDerivatives,
    min_cos: f64,
    view: Vec3,
) -> Option<f64> {
    let DistanceDerivatives { du, dv, unit } = distance_derivatives(array, d, min_cos)?;
    let (e, ff, gg) = (d.su.dot(d.su), d.su.dot(d.sv), d.sv.dot(d.sv));
    let det = e * gg - ff * ff;
    if !(det > 0.0 && det.is_finite()) {
        return None;
    }
    let gradient = ((gg * du - ff * dv) * d.su + (e * dv - ff * du) * d.sv) / det;
    let length = gradient.length();
    if !(length > 0.0 && length.is_finite()) {
        return None;
    }
    let surface_separation = array.spacing() / length;
    let tangent = unit.cross(gradient / length);
    let across = (tangent - tangent.dot(view) * view).length();
    let facing = unit.dot(view).abs();
    let separation = if across > 1e-9 {
        surface_separation * (facing / across).min(1.0)
    } else {
        surface_separation
    };
    separation.is_finite().then_some(separation)
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
    readable_pieces_by(surface, lights, lines, r, None)
}

/// [`readable_surface_lines`] for a picture looking along `view` (from the
/// eye toward the part): a line is cut where it comes closer to its
/// neighbour on the screen than `r.min_separation` (the picture's pixels
/// per unit times that is the gap in pixels), the separation measured as
/// the picture shows it ([`linear_separation_on_screen`]; parallel
/// projection along `view`), so that faces seen at a grazing angle, where
/// the lines crowd on the screen, are thinned too. Equal to
/// [`readable_surface_lines`] where the surface faces the viewer; never
/// keeps a point that one drops. A zero or non-finite `view` gives
/// [`readable_surface_lines`].
pub fn readable_surface_lines_in_view(
    surface: &BSplineSurface,
    lights: &[SurfaceLight],
    lines: &[SurfaceHighlightLine],
    r: &Readability,
    view: Vec3,
) -> Vec<SurfaceHighlightLine> {
    let view = view.normalize_or_zero();
    let view = (view != Vec3::ZERO && view.is_finite()).then_some(view);
    readable_pieces_by(surface, lights, lines, r, view)
}

/// The readable pieces of every linear line: the separation on the surface
/// (`view` None) or on the screen decides which points are kept.
fn readable_pieces_by(
    surface: &BSplineSurface,
    lights: &[SurfaceLight],
    lines: &[SurfaceHighlightLine],
    r: &Readability,
    view: Option<Vec3>,
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
                    let d = surface.derivatives(u, v);
                    match view {
                        None => linear_distance_gradient(array, &d, *min_cos)
                            .is_some_and(|g| g <= max_gradient),
                        // (no screen separation where the gradient vanishes:
                        // the neighbours are far, the surface rule decides)
                        Some(w) => {
                            linear_distance_gradient(array, &d, *min_cos)
                                .is_some_and(|g| g <= max_gradient)
                                && linear_separation_on_screen(array, &d, *min_cos, w)
                                    .is_none_or(|sep| sep >= r.min_separation)
                        }
                    }
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
