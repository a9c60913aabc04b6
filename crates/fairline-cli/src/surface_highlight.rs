//! `fairline highlight SURFACE.json|.igs`: highlight lines of B-spline
//! surfaces (Nishiyama et al. §2) traced in the parameter domain, written
//! with their (u, v) pre-images and 3D points; PNG of the shaded surface
//! with the lines, SVG of the pre-images.

use crate::args::{HighlightArgs, Radii, ZebraArgs};
use crate::common::{print_warnings, write_json, write_report};
use crate::error::bad_input;
use crate::output::require_extension;
use anyhow::Result;
use fairline::bspline::BSplineSurface;
use fairline::highlight::{
    CircularLights, LightArray, PatchHighlights, Readability, SurfaceHighlightLine, SurfaceLight,
    readable_surface_lines, readable_surface_lines_in_view,
};
use fairline::picture::{Picture, labelled_mesh_picture, mesh_picture};
use fairline::render::{PolylineLayer, ReflectionZebra, RegionLabels, RenderOptions, SvgPlot};
use fairline::{Control, Vec3};
use fairline_commands::Subject;
use fairline_commands::highlight::HighlightLights;
use fairline_commands::surface_highlight::{self, SurfaceHighlightSettings};
use serde_json::{Value, json};

/// Colours of successive lights (linear light, sRGB-ish) for pictures.
pub const PALETTE: [[f32; 3]; 6] = [
    [0.75, 0.05, 0.05],
    [0.05, 0.15, 0.70],
    [0.05, 0.45, 0.10],
    [0.60, 0.25, 0.00],
    [0.45, 0.05, 0.55],
    [0.00, 0.40, 0.45],
];

/// sRGB bytes of a palette colour (for SVG).
pub fn palette_srgb(k: usize) -> [u8; 3] {
    let c = PALETTE[k % PALETTE.len()];
    let px = fairline::render::linear_to_srgb8(c);
    [px[0], px[1], px[2]]
}

/// Polylines of surface highlight lines for a picture, coloured by light.
pub fn polylines(lines: &[&SurfaceHighlightLine], width: f32) -> Vec<PolylineLayer> {
    lines
        .iter()
        .map(|l| PolylineLayer {
            points: l.points.clone(),
            closed: l.closed,
            color: PALETTE[l.light % PALETTE.len()],
            width_px: width,
        })
        .collect()
}

/// Tessellation samples along the diagonal of a part in
/// [`surface_picture`].
const PICTURE_SAMPLES: usize = 96;

/// The --zebra of a picture of `surfaces` drawn with `opts` (on the
/// tessellation [`surface_picture`] draws; tubes along `light`, else the
/// part's default lights); `None` without --zebra.
pub fn surface_zebra(
    surfaces: &[BSplineSurface],
    zebra: &ZebraArgs,
    light: Option<&LightArray>,
    opts: &RenderOptions,
) -> Result<Option<ReflectionZebra>> {
    if !zebra.zebra {
        return Ok(None);
    }
    let (mesh, _) = crate::surface::tessellated_part_with_patches(surfaces, PICTURE_SAMPLES)?;
    zebra.reflection_zebra(&mesh, light, opts)
}

/// A picture of tessellated surfaces with polylines over them and a
/// reflection `zebra` under them (its period added to the title); a part of
/// several patches gets each patch's index (its position in `surfaces`)
/// written at the patch's visible centre.
pub fn surface_picture(
    surfaces: &[BSplineSurface],
    polylines: Vec<PolylineLayer>,
    title: &str,
    zebra: Option<ReflectionZebra>,
    opts: &RenderOptions,
) -> Result<fairline::render::Image> {
    let (mesh, patch) = crate::surface::tessellated_part_with_patches(surfaces, PICTURE_SAMPLES)?;
    let title = match &zebra {
        Some(z) => format!("{title}; {}", crate::args::zebra_title(z)),
        None => title.to_string(),
    };
    let picture = Picture {
        polylines,
        title: Some(title),
        zebra,
        ..Default::default()
    };
    if surfaces.len() > 1 && patch.len() == mesh.face_count() {
        let labels = RegionLabels {
            triangle_region: patch,
            texts: (0..surfaces.len()).map(|k| k.to_string()).collect(),
        };
        return Ok(labelled_mesh_picture(&mesh, &picture, &labels, opts)?.0);
    }
    Ok(mesh_picture(&mesh, &picture, opts)?)
}

/// A polyline in (u, v) with its colour (linear light) and width (pixels).
pub type UvLine = (Vec<[f64; 2]>, [f32; 3], f32);

/// A PNG picture of the parameter domain of `surface` seen from above with
/// polylines in (u, v): each entry is (points, colour, width); the domain is
/// drawn as a flat light-grey rectangle.
pub fn uv_picture(
    surface: &BSplineSurface,
    lines: &[UvLine],
    title: &str,
    size: (u32, u32),
) -> Result<fairline::render::Image> {
    let (du, dv) = (surface.domain_u(), surface.domain_v());
    let mesh = fairline::shapes::quad_grid(2, 2, (du[0], du[1]), (dv[0], dv[1]), |_, _| 0.0);
    let polylines = lines
        .iter()
        .map(|(pts, color, w)| PolylineLayer {
            points: pts.iter().map(|p| Vec3::new(p[0], p[1], 0.0)).collect(),
            closed: false,
            color: *color,
            width_px: *w,
        })
        .collect();
    let picture = Picture {
        polylines,
        title: Some(title.to_string()),
        ..Default::default()
    };
    let mut opts = RenderOptions::with_size(size.0, size.1);
    opts.view_dir = Vec3::new(0.0, 0.0, -1.0);
    opts.up = Vec3::Y;
    opts.orthographic = true;
    Ok(mesh_picture(&mesh, &picture, &opts)?)
}

/// An SVG plot of pre-images in the domain of `surface`.
pub fn uv_plot(surface: &BSplineSurface, title: &str) -> SvgPlot {
    let (du, dv) = (surface.domain_u(), surface.domain_v());
    let mut plot = SvgPlot::new(800, 800, (du[0], du[1]), (dv[0], dv[1]));
    plot.title(title);
    plot.axes("u", "v");
    plot
}

/// Adds pre-image polylines to a plot (closed lines repeat their start).
pub fn plot_lines(plot: &mut SvgPlot, lines: &[&SurfaceHighlightLine], width: f64) {
    for l in lines {
        let mut uv = l.uv.clone();
        if l.closed && !uv.is_empty() {
            uv.push(uv[0]);
        }
        plot.polyline(&uv, palette_srgb(l.light), width);
    }
}

/// Writes each line's id (`#id`, the `"id"` of the lines JSON, counted from
/// `first_id`) beside the line's middle point, in the line's colour, so
/// that a stretch can be named as `--from ID:T` in `fair-surface`.
pub fn plot_line_ids(plot: &mut SvgPlot, lines: &[SurfaceHighlightLine], first_id: usize) {
    for (k, l) in lines.iter().enumerate() {
        if let Some(&p) = l.uv.get(l.uv.len() / 2) {
            plot.text(p, palette_srgb(l.light), &format!("#{}", first_id + k));
        }
    }
}

/// The SVG legend of the lights drawn: one entry per light that has a
/// line, "R = r" for circular lights, "light m" for linear ones.
pub fn legend_entries(
    lights: &[SurfaceLight],
    lines: &[SurfaceHighlightLine],
) -> Vec<([u8; 3], String)> {
    let mut used: Vec<usize> = lines.iter().map(|l| l.light).collect();
    used.sort_unstable();
    used.dedup();
    used.into_iter()
        .filter_map(|k| {
            let text = match lights.get(k)? {
                SurfaceLight::Circular(c) => format!("R = {}", c.radius()),
                SurfaceLight::Linear { index, .. } => format!("light {index}"),
            };
            Some((palette_srgb(k), text))
        })
        .collect()
}

/// Most radii a picture key lists one by one; the rest are counted.
const KEY_RADII: usize = 10;

/// The key of the PNG picture: for circular lights one entry per radius
/// that has a line, in its colour (the SVG's legend); for linear lights one
/// entry with the light spacing (the colours cycle through the lights, as
/// in the SVG, so they are not listed one by one).
fn picture_key(results: &[(usize, PatchHighlights)]) -> Vec<([f32; 3], String)> {
    let mut radii: Vec<(usize, f64)> = Vec::new();
    let mut spacing = None;
    for (_, p) in results {
        let (lights, h) = (&p.lights, &p.highlights);
        for l in h.lines.iter().chain(&h.band_lower).chain(&h.band_upper) {
            match lights.get(l.light) {
                Some(SurfaceLight::Circular(c)) => radii.push((l.light, c.radius())),
                Some(SurfaceLight::Linear { array, .. }) => spacing = Some(array.spacing()),
                None => {}
            }
        }
    }
    radii.sort_by_key(|r| r.0);
    radii.dedup_by_key(|r| r.0);
    let mut key: Vec<([f32; 3], String)> = radii
        .iter()
        .take(KEY_RADII)
        .map(|&(k, r)| {
            (
                PALETTE[k % PALETTE.len()],
                format!("circular light R = {}", crate::highlight_png::fmt_len(r)),
            )
        })
        .collect();
    if radii.len() > KEY_RADII {
        key.push((
            PALETTE[radii[KEY_RADII].0 % PALETTE.len()],
            format!("… {} more radii", radii.len() - KEY_RADII),
        ));
    }
    if let Some(s) = spacing {
        key.push((
            PALETTE[0],
            format!(
                "highlight lines (colour per light), light spacing {}",
                crate::highlight_png::fmt_len(s)
            ),
        ));
    }
    key
}

pub fn run(args: HighlightArgs) -> Result<()> {
    let job = output_job(&args)?;
    check_options(&args)?;
    let file = crate::surface::load_surface_file(&args.mesh)?;
    let (all, unit) = (file.surfaces, file.unit);
    let settings = SurfaceHighlightSettings {
        lights: highlight_lights(&args)?,
        grid: args.grid,
        band: args.band,
        surface: args.surface,
    };
    let count = settings.surface.map_or(all.len(), |_| 1);
    let bar = crate::output::progress(count as u64, "highlight lines");
    let out = surface_highlight::run(&all, &settings, &Control::new(), &|| bar.inc(1));
    bar.finish_and_clear();
    let mut out = out.map_err(|e| match e.subject() {
        Some(Subject::Input) => crate::output::name_file(&args.mesh, e),
        Some(Subject::Lights) => match &args.light.lights {
            Some(path) => crate::output::name_file(path, e),
            None => anyhow::Error::new(e),
        },
        _ => anyhow::Error::new(e),
    })?;
    if let Some(spec) = &out.derived {
        eprintln!(
            "default circular lights (save as LIGHTS.json to reuse): {}",
            serde_json::to_string(spec)?
        );
    }
    let (surfaces, results) = (&out.surfaces, &out.results);
    // Pictures first (they can fail on bad options); the lines file last.
    if let Some(p) = &args.png {
        let view = match (&out.readable, args.view) {
            (Some((array, _)), None) => {
                let (dir, up) = crate::surface::camera(surfaces, None)?;
                Some(facing_the_lights(dir, up, array))
            }
            _ => Some(crate::surface::camera(surfaces, args.view)?),
        };
        let drawn = drawn_lines(
            surfaces,
            results,
            out.readable.as_ref().map(|r| &r.1),
            view.map(|(dir, _)| dir),
        );
        if let Some((dir, up)) = view {
            out.report
                .set("view", json!({"dir": dir.to_array(), "up": up.to_array()}));
        }
        out.report.set("drawn", drawn_json(&drawn));
        let light = out.readable.as_ref().map(|(array, _)| array);
        let zebra = write_picture(&args, surfaces, results, &drawn, (view, light), p)?;
        if let Some(z) = &zebra {
            out.report.set("zebra", crate::args::zebra_json(z));
        }
    }
    if let Some(p) = &args.svg {
        write_svg(&args, surfaces, results, p)?;
    }
    if crate::lines_file::lines_format(&args.output)? == crate::lines_file::LinesFormat::Iges {
        let tol = fairline_commands::curves::surface_tolerance(args.curve_tolerance, surfaces);
        let summary = crate::lines_file::write_curves(
            &args.output,
            &fairline_commands::curves::surface_lines(results),
            tol,
            unit.as_ref(),
        )?;
        out.report.set("curves", summary);
    } else {
        write_json(&args.output, &out.document)?;
    }
    print_warnings(&out.report);
    write_report(args.report.as_deref(), &out.report)?;
    job.finish(format_args!(
        "{} highlight line pre-image(s) on {} surface(s)",
        out.lines,
        results.len()
    ))?;
    Ok(())
}

/// The output checks of the command (file kinds by extension, nothing
/// written over an input) and its job.
fn output_job(args: &HighlightArgs) -> Result<crate::output::Job> {
    require_extension("-o", &args.output, &["json", "igs", "iges"])?;
    crate::lines_file::check_curve_tolerance(args.curve_tolerance)?;
    if args.curve_tolerance.is_some()
        && crate::lines_file::lines_format(&args.output)? != crate::lines_file::LinesFormat::Iges
    {
        return Err(crate::error::bad_input(
            "--curve-tolerance is for curves: give -o LINES.igs".to_string(),
        ));
    }
    if let Some(p) = &args.png {
        require_extension("--png", p, &["png"])?;
    }
    if let Some(p) = &args.svg {
        require_extension("--svg", p, &["svg"])?;
    }
    crate::output::Job::new("highlight")
        .input(&args.mesh)
        .input_opt(args.light.lights.as_deref())
        .output("-o", &args.output)
        .output_opt("--png", args.png.as_deref())
        .output_opt("--svg", args.svg.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()
}

/// Input errors for --view, --grid and --band out of range.
fn check_options(args: &HighlightArgs) -> Result<()> {
    if args.view.is_some_and(|v| v.length() == 0.0) {
        return Err(bad_input("--view must not be the zero vector"));
    }
    if !(2..=4000).contains(&args.grid) {
        return Err(bad_input(format!(
            "--grid must be between 2 and 4000, got {}",
            args.grid
        )));
    }
    if let Some(b) = args.band
        && !(b > 0.0 && b.is_finite())
    {
        return Err(bad_input(format!(
            "--band must be a positive number, got {b}"
        )));
    }
    Ok(())
}

/// The lights asked for: circular lights given on the command line, in the
/// `--lights` file, or derived from the whole part (`--circular`); else the
/// linear light array.
fn highlight_lights(args: &HighlightArgs) -> Result<HighlightLights> {
    if let (Some(c), Some(t), Some(Radii(radii))) =
        (args.circle_center, args.circle_axis, args.radii.clone())
    {
        return Ok(HighlightLights::Circular {
            spec: CircularLights {
                center: c.to_array(),
                axis: t.to_array(),
                radii,
            },
            from_lights: false,
        });
    }
    if let Some(path) = &args.light.lights
        && let Some(spec) = crate::args::circular_file(path)?
    {
        return Ok(HighlightLights::Circular {
            spec,
            from_lights: true,
        });
    }
    if args.circular {
        return Ok(HighlightLights::DerivedCircular {
            up: args.light.up.vector(),
        });
    }
    Ok(HighlightLights::Linear(args.light.lights()?))
}

/// The lines the picture draws: with linear lights the readable drawing of
/// every surface's lines (band boundaries too) as the picture seen along
/// `view` shows them ([`readable_surface_lines_in_view`]: lines closer on
/// the screen than the readable gap are cut; [`readable_surface_lines`]
/// without a view), else all lines.
fn drawn_lines(
    surfaces: &[BSplineSurface],
    results: &[(usize, PatchHighlights)],
    readability: Option<&Readability>,
    view: Option<Vec3>,
) -> Vec<SurfaceHighlightLine> {
    results
        .iter()
        .zip(surfaces)
        .flat_map(|((_, p), s)| {
            let h = &p.highlights;
            let all: Vec<SurfaceHighlightLine> = h
                .lines
                .iter()
                .chain(&h.band_lower)
                .chain(&h.band_upper)
                .cloned()
                .collect();
            match (readability, view) {
                (Some(r), Some(v)) => readable_surface_lines_in_view(s, &p.lights, &all, r, v),
                (Some(r), None) => readable_surface_lines(s, &p.lights, &all, r),
                (None, _) => all,
            }
        })
        .collect()
}

/// Report entry of the drawn lines: pieces and points.
fn drawn_json(drawn: &[SurfaceHighlightLine]) -> Value {
    json!({
        "pieces": drawn.len(),
        "points": drawn.iter().map(|l| l.points.len()).sum::<usize>(),
    })
}

/// The --png picture: the shaded part with the drawn lines, patch indices
/// and the key, seen from `view` (direction, up) when given; with --zebra
/// the reflection zebra (tubes along the linear `light`, else the part's
/// default lights) under the lines, which is returned.
fn write_picture(
    args: &HighlightArgs,
    surfaces: &[BSplineSurface],
    results: &[(usize, PatchHighlights)],
    drawn: &[SurfaceHighlightLine],
    (view, light): (Option<(Vec3, Vec3)>, Option<&LightArray>),
    path: &std::path::Path,
) -> Result<Option<ReflectionZebra>> {
    let title = format!(
        "{}: highlight lines",
        args.mesh
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    let mut ropts = RenderOptions::with_size(1200, 900);
    if let Some((dir, up)) = view {
        ropts.view_dir = dir;
        ropts.up = up;
    }
    let drawn: Vec<&SurfaceHighlightLine> = drawn.iter().collect();
    let zebra = surface_zebra(surfaces, &args.zebra, light, &ropts)?;
    let mut img = surface_picture(surfaces, polylines(&drawn, 2.0), &title, zebra, &ropts)?;
    crate::highlight_png::draw_key(&mut img, &picture_key(results));
    img.write_png(path)?;
    Ok(zebra)
}

/// The --svg plot of one surface's pre-images (--surface, else the first)
/// with line ids and the legend.
fn write_svg(
    args: &HighlightArgs,
    surfaces: &[BSplineSurface],
    results: &[(usize, PatchHighlights)],
    path: &std::path::Path,
) -> Result<()> {
    let multi = results.len() > 1;
    let want = args.surface.unwrap_or(0);
    let at = results.iter().position(|(k, _)| *k == want).unwrap_or(0);
    let s = &surfaces[at];
    let (k, p) = &results[at];
    let (lights, h) = (&p.lights, &p.highlights);
    // ids of this surface's lines: after those of the surfaces before it
    let first_id: usize = results[..at]
        .iter()
        .map(|r| r.1.highlights.lines.len())
        .sum();
    let title = if multi {
        format!("surface {k}: highlight line pre-images (u, v), #line ids")
    } else {
        "highlight line pre-images (u, v), #line ids".to_string()
    };
    let mut plot = uv_plot(s, &title);
    plot_trim_loops(&mut plot, s);
    plot_lines(&mut plot, &h.lines.iter().collect::<Vec<_>>(), 1.5);
    plot_lines(
        &mut plot,
        &h.band_lower.iter().chain(&h.band_upper).collect::<Vec<_>>(),
        0.6,
    );
    plot_line_ids(&mut plot, &h.lines, first_id);
    // the patch index, as the PNG writes it on every patch of a part
    if multi && let Some(p) = label_point(s) {
        plot.label(p, &k.to_string());
    }
    let mut legend = legend_entries(lights, &h.lines);
    if !h.lines.is_empty() {
        legend.push((
            [60, 60, 60],
            format!("lines #{first_id}..#{}", first_id + h.lines.len() - 1),
        ));
    }
    plot.legend(&legend);
    plot.write(path)?;
    Ok(())
}

/// Draws the trimming loops of a trimmed surface (grey): the face the
/// lines lie in.
pub fn plot_trim_loops(plot: &mut SvgPlot, surface: &BSplineSurface) {
    if let Some(trim) = surface.trim() {
        for poly in trim.polylines() {
            let mut closed = poly.clone();
            if let Some(&first) = poly.first() {
                closed.push(first);
            }
            plot.polyline(&closed, [120, 120, 120], 1.0);
        }
    }
}

/// Where a label on the (u, v) domain of `surface` goes: of a 24 × 24 grid
/// of points over the domain, the one inside the (trimmed) face farthest
/// from the points outside it and from the domain's border (distances in
/// fractions of the domain's sides), as the PNG labels sit at the deepest
/// visible point of each patch. `None` when no grid point is inside.
pub fn label_point(surface: &BSplineSurface) -> Option<[f64; 2]> {
    const N: usize = 24;
    let ([u0, u1], [v0, v1]) = (surface.domain_u(), surface.domain_v());
    let at = |a: usize, b: usize| {
        let (x, y) = ((a as f64 + 0.5) / N as f64, (b as f64 + 0.5) / N as f64);
        ([x, y], [u0 + x * (u1 - u0), v0 + y * (v1 - v0)])
    };
    let inside: Vec<([f64; 2], [f64; 2], bool)> = (0..N)
        .flat_map(|a| (0..N).map(move |b| (a, b)))
        .map(|(a, b)| {
            let (unit, uv) = at(a, b);
            (unit, uv, surface.contains_uv(uv[0], uv[1]))
        })
        .collect();
    let outside: Vec<[f64; 2]> = inside.iter().filter(|p| !p.2).map(|p| p.0).collect();
    inside
        .iter()
        .filter(|p| p.2)
        .map(|&(x, uv, _)| {
            let border = x[0].min(1.0 - x[0]).min(x[1]).min(1.0 - x[1]);
            let depth = outside
                .iter()
                .map(|o| (o[0] - x[0]).hypot(o[1] - x[1]))
                .fold(border, f64::min);
            (depth, uv)
        })
        .fold(None, |best: Option<(f64, [f64; 2])>, c| match best {
            Some(b) if b.0 >= c.0 => Some(b),
            _ => Some(c),
        })
        .map(|b| b.1)
}

/// The camera rule's view `dir` (with `up`) seen from the side of the
/// lights `array` was chosen for (the side whose picture shows the most of
/// the part with readable lines): when the rule would look at the part
/// from behind the light plane, its direction is mirrored through that
/// plane, so that a dish's blades, not its flat back, face the camera. The
/// up stays the rule's unless the mirrored direction lies along it.
fn facing_the_lights(
    dir: fairline::Vec3,
    up: fairline::Vec3,
    array: &fairline::highlight::LightArray,
) -> (fairline::Vec3, fairline::Vec3) {
    let z = array.plane_normal();
    let along = dir.dot(z);
    if along <= 0.0 {
        return (dir, up);
    }
    let mirrored = dir - 2.0 * along * z;
    if mirrored.normalize_or_zero().cross(up).length() > 1e-3 {
        (mirrored, up)
    } else {
        (mirrored, mirrored.any_orthonormal_vector())
    }
}
