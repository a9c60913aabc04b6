//! `fairline highlight SURFACE.json|.igs`: highlight lines of B-spline
//! surfaces (Nishiyama et al. §2) traced in the parameter domain, written
//! with their (u, v) pre-images and 3D points; PNG of the shaded surface
//! with the lines, SVG of the pre-images.

use crate::args::{HighlightArgs, Radii, to_input_error};
use crate::common::{Report, write_json};
use crate::error::bad_input;
use crate::output::require_extension;
use anyhow::Result;
use fairline::Vec3;
use fairline::bspline::BSplineSurface;
use fairline::highlight::{
    CircularLights, PartLights, SurfaceHighlightLine, SurfaceHighlightOptions, SurfaceHighlights,
    SurfaceLight, part_highlight_lines,
};
use fairline::picture::{Picture, labelled_mesh_picture, mesh_picture};
use fairline::render::{PolylineLayer, RegionLabels, RenderOptions, SvgPlot};
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

/// One line as JSON (DESIGN.md §4): radius (circular) or index (linear),
/// closed, uv, points; `surface` when the file holds several.
pub fn line_json(
    l: &SurfaceHighlightLine,
    lights: &[SurfaceLight],
    surface: Option<usize>,
) -> Value {
    let uv: Vec<[f64; 2]> = l.uv.clone();
    let pts: Vec<[f64; 3]> = l.points.iter().map(|p| p.to_array()).collect();
    let mut v =
        json!({"light": l.light, "level": l.level, "closed": l.closed, "uv": uv, "points": pts});
    if let Some(r) = l.radius {
        v["radius"] = json!(r);
    }
    if let Some(SurfaceLight::Linear { index, .. }) = lights.get(l.light) {
        v["index"] = json!(index);
    }
    if let Some(s) = surface {
        v["surface"] = json!(s);
    }
    v
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

/// A picture of tessellated surfaces with polylines over them; a part of
/// several patches gets each patch's index (its position in `surfaces`)
/// written at the patch's visible centre (issue #20 item 7).
pub fn surface_picture(
    surfaces: &[BSplineSurface],
    polylines: Vec<PolylineLayer>,
    title: &str,
    opts: &RenderOptions,
) -> Result<fairline::render::Image> {
    let (mesh, patch) = crate::surface::tessellated_part_with_patches(surfaces, 96)?;
    let picture = Picture {
        polylines,
        title: Some(title.to_string()),
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
fn picture_key(
    results: &[(usize, Vec<SurfaceLight>, SurfaceHighlights)],
) -> Vec<([f32; 3], String)> {
    let mut radii: Vec<(usize, f64)> = Vec::new();
    let mut spacing = None;
    for (_, lights, h) in results {
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
    let all = crate::surface::load_surfaces(&args.mesh)?;
    if let Some(k) = args.surface
        && k >= all.len()
    {
        return Err(bad_input(format!(
            "{}: --surface {k} is out of range (the file holds {} surfaces)",
            args.mesh.display(),
            all.len()
        )));
    }
    let circular_spec = circular_spec(&args, &all)?;
    let chosen: Vec<(usize, BSplineSurface)> = match args.surface {
        Some(k) => vec![(k, all[k].clone())],
        None => all.into_iter().enumerate().collect(),
    };
    let mut report = Report::new("highlight");
    report.set("surfaces", chosen.len());
    report.set("grid", args.grid);
    let opts = SurfaceHighlightOptions::default()
        .grid(args.grid)
        .band(args.band);
    let part_lights = part_lights(&args, circular_spec, &chosen, &mut report)?;
    let bar = crate::output::progress(chosen.len() as u64, "highlight lines");
    let surfaces: Vec<BSplineSurface> = chosen.iter().map(|(_, s)| s.clone()).collect();
    let patches =
        report.time(|| part_highlight_lines(&surfaces, &part_lights, &opts, &|| bar.inc(1)));
    let results: Vec<(usize, Vec<SurfaceLight>, SurfaceHighlights)> = chosen
        .iter()
        .zip(patches)
        .map(|((k, _), p)| (*k, p.lights, p.highlights))
        .collect();
    bar.finish_and_clear();
    let (out, line_count) = lines_document(&results, args.band);
    // Pictures first (they can fail on bad options); the lines file last.
    if let Some(p) = &args.png {
        write_picture(&args, &surfaces, &results, p)?;
    }
    if let Some(p) = &args.svg {
        write_svg(&args, &chosen, &results, p)?;
    }
    write_json(&args.output, &out)?;
    report.set("lines", line_count);
    report.set(
        "closed_lines",
        results
            .iter()
            .map(|(_, _, h)| h.lines.iter().filter(|l| l.closed).count())
            .sum::<usize>(),
    );
    report.set(
        "points",
        results
            .iter()
            .map(|(_, _, h)| h.lines.iter().map(|l| l.uv.len()).sum::<usize>())
            .sum::<usize>(),
    );
    if line_count == 0 {
        report.warn("no highlight line pre-image was found on the surface; try other radii, --circle-center or --circle-axis");
    }
    report.write(args.report.as_deref())?;
    job.finish(format_args!(
        "{line_count} highlight line pre-image(s) on {} surface(s)",
        results.len()
    ));
    Ok(())
}

/// The output checks of the command (file kinds by extension, nothing
/// written over an input) and its job.
fn output_job(args: &HighlightArgs) -> Result<crate::output::Job> {
    require_extension("-o", &args.output, &["json"])?;
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

/// Circular lights: given, from a --lights file in the circular form, or
/// (--circular) derived from the whole part `all`, so that `fair-surface`
/// on the same file derives the same ones; with whether they were derived.
/// `None` for linear lights.
fn circular_spec(
    args: &HighlightArgs,
    all: &[BSplineSurface],
) -> Result<Option<(CircularLights, bool)>> {
    Ok(
        if let (Some(c), Some(t), Some(Radii(radii))) =
            (args.circle_center, args.circle_axis, args.radii.clone())
        {
            Some((
                CircularLights {
                    center: c.to_array(),
                    axis: t.to_array(),
                    radii,
                },
                false,
            ))
        } else if let Some(path) = &args.light.lights {
            crate::args::circular_file(path)?.map(|c| (c, false))
        } else if args.circular {
            Some((
                crate::args::derived_circular_lights(
                    fairline::highlight::default_circular_lights(
                        all,
                        args.light.up.vector(),
                        fairline::highlight::DEFAULT_CIRCULAR_RADII,
                    ),
                )?,
                true,
            ))
        } else {
            None
        },
    )
}

/// The lights of the run over the `chosen` surfaces (the circular ones of
/// `circular_spec`, else the linear array of the options in the chosen
/// surfaces' box), recorded in the report.
fn part_lights(
    args: &HighlightArgs,
    circular_spec: Option<(CircularLights, bool)>,
    chosen: &[(usize, BSplineSurface)],
    report: &mut Report,
) -> Result<PartLights> {
    if let Some((spec, derived)) = circular_spec {
        let lights = spec.lights().map_err(|e| match &args.light.lights {
            Some(path) if args.circle_center.is_none() => {
                crate::output::name_file(path, to_input_error(e))
            }
            _ => to_input_error(e),
        })?;
        if lights.is_empty() {
            return Err(bad_input("circular lights need at least one radius"));
        }
        let mut light = json!({"kind": "circular", "center": spec.center, "axis": spec.axis, "radii": spec.radii});
        if derived {
            light["derived"] = json!(true);
        }
        report.set("light", light);
        return Ok(PartLights::Circular(lights));
    }
    let (mut lo, mut hi) = (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY));
    for (_, s) in chosen {
        let (a, b) = s.control_bounding_box();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    let array = args.light.light_array_in_box(lo, hi)?;
    report.set("light", json!({"kind": "linear", "array": array}));
    Ok(PartLights::Linear {
        array,
        min_cos: args.light.min_normal_cos,
        max_lights: fairline::highlight::surface::DEFAULT_MAX_LIGHTS,
    })
}

/// The lines document (DESIGN.md §4) of every surface's lines, with their
/// ids (the position in "lines", named by `fair-surface --from ID:T`) and
/// the bands; with the number of lines.
fn lines_document(
    results: &[(usize, Vec<SurfaceLight>, SurfaceHighlights)],
    band: Option<f64>,
) -> (Value, usize) {
    let multi = results.len() > 1;
    let tag = |k: usize| multi.then_some(k);
    let mut lines = Vec::new();
    let (mut lower, mut upper) = (Vec::new(), Vec::new());
    for (k, lights, h) in results {
        lines.extend(h.lines.iter().map(|l| line_json(l, lights, tag(*k))));
        lower.extend(h.band_lower.iter().map(|l| line_json(l, lights, tag(*k))));
        upper.extend(h.band_upper.iter().map(|l| line_json(l, lights, tag(*k))));
    }
    for (id, l) in lines.iter_mut().enumerate() {
        l["id"] = json!(id);
    }
    let line_count = lines.len();
    let mut out = json!({"lines": lines});
    if let Some(rho) = band {
        out["bands"] = json!({"radius": rho, "lower": lower, "upper": upper});
    }
    (out, line_count)
}

/// The --png picture: the shaded part with every line, patch indices and
/// the key.
fn write_picture(
    args: &HighlightArgs,
    surfaces: &[BSplineSurface],
    results: &[(usize, Vec<SurfaceLight>, SurfaceHighlights)],
    path: &std::path::Path,
) -> Result<()> {
    let all_lines: Vec<&SurfaceHighlightLine> = results
        .iter()
        .flat_map(|(_, _, h)| h.lines.iter().chain(&h.band_lower).chain(&h.band_upper))
        .collect();
    let title = format!(
        "{}: highlight lines",
        args.mesh
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    let mut ropts = RenderOptions::with_size(1200, 900);
    if let Some(v) = args.view {
        ropts.view_dir = v;
    }
    let mut img = surface_picture(surfaces, polylines(&all_lines, 2.0), &title, &ropts)?;
    crate::highlight_png::draw_key(&mut img, &picture_key(results));
    img.write_png(path)?;
    Ok(())
}

/// The --svg plot of one surface's pre-images (--surface, else the first)
/// with line ids and the legend.
fn write_svg(
    args: &HighlightArgs,
    chosen: &[(usize, BSplineSurface)],
    results: &[(usize, Vec<SurfaceLight>, SurfaceHighlights)],
    path: &std::path::Path,
) -> Result<()> {
    let multi = chosen.len() > 1;
    let want = args.surface.unwrap_or(0);
    let (_, s) = chosen
        .iter()
        .find(|(k, _)| *k == want)
        .unwrap_or(&chosen[0]);
    let at = results.iter().position(|(k, _, _)| *k == want).unwrap_or(0);
    let (k, lights, h) = &results[at];
    // ids of this surface's lines: after those of the surfaces before it
    let first_id: usize = results[..at].iter().map(|r| r.2.lines.len()).sum();
    let title = if multi {
        format!("surface {k}: highlight line pre-images (u, v), #line ids")
    } else {
        "highlight line pre-images (u, v), #line ids".to_string()
    };
    let mut plot = uv_plot(s, &title);
    plot_lines(&mut plot, &h.lines.iter().collect::<Vec<_>>(), 1.5);
    plot_lines(
        &mut plot,
        &h.band_lower.iter().chain(&h.band_upper).collect::<Vec<_>>(),
        0.6,
    );
    plot_line_ids(&mut plot, &h.lines, first_id);
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
