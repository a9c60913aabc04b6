//! `fairline highlight`: highlight lines of a linear light array (Yong et
//! al. §2) or of concentric circular lights (Nishiyama et al. §2) on a
//! triangle mesh, written as JSON or OBJ polylines.

use crate::args::{HighlightArgs, Radii, circular_file, derived_circular_lights, to_input_error};
use crate::common::Report;
use crate::error::bad_input;
use crate::input::read_triangles;
use crate::output::spinner;
use anyhow::Result;
use fairline::Vec3;
use fairline::highlight::{
    CircularLight, CircularLights, HighlightBands, HighlightError, HighlightLines, HighlightModel,
    HighlightOptions, Readability, circular_highlight_bands, circular_highlight_lines,
};
use serde_json::json;
use std::path::Path;

/// Output format of polylines.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum LinesFormat {
    /// JSON of DESIGN.md §4.
    Json,
    /// Wavefront OBJ `l` elements.
    Obj,
}

/// The format of `path` from its extension.
pub fn lines_format(path: &Path) -> Result<LinesFormat> {
    crate::output::require_extension("-o", path, &["json", "obj"])?;
    let obj = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    Ok(if obj {
        LinesFormat::Obj
    } else {
        LinesFormat::Json
    })
}

/// Writes lines (and bands) atomically in the format of `path`'s
/// extension ([`fairline::highlight::highlight_lines_json`],
/// [`fairline::highlight::highlight_lines_obj`]).
pub fn write_lines(
    path: &Path,
    lines: &HighlightLines,
    bands: Option<&HighlightBands>,
    radii: Option<&[f64]>,
) -> Result<()> {
    match lines_format(path)? {
        LinesFormat::Json => crate::common::write_json(
            path,
            &fairline::highlight::highlight_lines_json(lines, bands, radii),
        ),
        LinesFormat::Obj => {
            let text = fairline::highlight::highlight_lines_obj(lines, bands);
            fairline::io::atomic_write(path, |w| {
                use std::io::Write;
                w.write_all(text.as_bytes())
            })?;
            Ok(())
        }
    }
}

pub fn run(args: HighlightArgs) -> Result<()> {
    if crate::surface::is_surface_path(&args.mesh) {
        return crate::surface_highlight::run(args);
    }
    lines_format(&args.output)?;
    if let Some(p) = &args.png {
        crate::output::require_extension("--png", p, &["png"])?;
    }
    let job = crate::output::Job::new("highlight")
        .input(&args.mesh)
        .input_opt(args.light.lights.as_deref())
        .output("-o", &args.output)
        .output_opt("--png", args.png.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    check_view_and_band(&args)?;
    let (mesh, _) = read_triangles(&args.mesh)?;
    let mut report = Report::new("highlight");
    report.set("vertices", mesh.vertex_count());
    report.set("faces", mesh.face_count());
    let bar = spinner("highlight lines");
    let drawn = match circular_lights(&args, &mesh)? {
        Some(spec) => circular_lines(&args, &mesh, spec, &mut report)?,
        None => linear_lines(&args, &mesh, &mut report)?,
    };
    bar.finish_and_clear();
    let lines = &drawn.lines;
    write_lines(
        &args.output,
        lines,
        drawn.bands.as_ref(),
        drawn.radii.as_deref(),
    )?;
    let counts = lines.counts();
    report.set("summary", counts);
    report.set_fields(counts);
    if let Some(b) = &drawn.bands {
        report.set("band", json!({"radius": b.radius, "lower_lines": b.lower.lines.len(), "upper_lines": b.upper.lines.len()}));
    }
    if let Some(png) = &args.png {
        write_picture(&args, png, &mesh, &drawn)?;
    }
    if lines.lines.is_empty() {
        report.warn("no highlight line crosses the mesh; try other light options (--plane-normal, --direction, --spacing)");
    }
    report.write(args.report.as_deref())?;
    job.finish(format_args!(
        "{} highlight line(s) ({} closed, {} nodes) on {} vertices",
        counts.lines,
        counts.closed_lines,
        counts.nodes,
        mesh.vertex_count()
    ))?;
    Ok(())
}

/// Refuses a zero `--view` and a `--band` that is not a positive number.
fn check_view_and_band(args: &HighlightArgs) -> Result<()> {
    crate::args::check_view(args.view)?;
    if let Some(b) = args.band
        && !(b > 0.0 && b.is_finite())
    {
        return Err(bad_input(format!(
            "--band must be a positive number, got {b}"
        )));
    }
    Ok(())
}

/// What [`run`] computed on a mesh: the lines (and bands), the radii of
/// circular lights, the readable subset drawn of linear lights (`None`:
/// draw all lines), the picture's default view and up, and the light
/// spacing for the picture's key (linear lights).
struct MeshLines {
    lines: HighlightLines,
    bands: Option<HighlightBands>,
    radii: Option<Vec<f64>>,
    drawn: Option<HighlightLines>,
    view_up: (Vec3, Vec3),
    spacing: Option<f64>,
}

/// The circular lights asked for: given on the command line, in the
/// `--lights` file, or derived from the part (`--circular`); `None` for a
/// linear light array.
fn circular_lights(
    args: &HighlightArgs,
    mesh: &fairline::SurfaceMesh,
) -> Result<Option<CircularLights>> {
    Ok(
        match (args.circle_center, args.circle_axis, args.radii.clone()) {
            (Some(c), Some(t), Some(Radii(radii))) => Some(CircularLights {
                center: c.to_array(),
                axis: t.to_array(),
                radii,
            }),
            _ => match &args.light.lights {
                Some(path) => circular_file(path)?,
                None if args.circular => Some(derived_circular_lights(
                    fairline::highlight::default_circular_lights_for_mesh(
                        mesh,
                        args.light.up.vector(),
                        fairline::highlight::DEFAULT_CIRCULAR_RADII,
                    ),
                )?),
                None => None,
            },
        },
    )
}

/// Lines (and bands) of the circular lights `spec` (Nishiyama et al. §2);
/// records the lights in the report.
fn circular_lines(
    args: &HighlightArgs,
    mesh: &fairline::SurfaceMesh,
    spec: CircularLights,
    report: &mut Report,
) -> Result<MeshLines> {
    let radii = spec.radii.clone();
    let from_file = args.circle_center.is_none() || args.circle_axis.is_none();
    let lights: Vec<CircularLight> =
        spec.lights()
            .map_err(|e| match (&args.light.lights, from_file) {
                (Some(path), true) => crate::output::name_file(path, to_input_error(e)),
                _ => to_input_error(e),
            })?;
    if lights.is_empty() {
        return Err(bad_input("circular lights need at least one radius"));
    }
    let (lines, bands) = report
        .time(|| -> Result<_, HighlightError> {
            let opts = HighlightOptions::default();
            let lines = circular_highlight_lines(mesh, &lights, &opts)?;
            let bands = match args.band {
                Some(rho) => Some(circular_highlight_bands(mesh, &lights, rho, &opts)?),
                None => None,
            };
            Ok((lines, bands))
        })
        .map_err(to_input_error)?;
    let axis = lights[0].axis();
    let view_up = (
        -axis + 0.35 * axis.any_orthonormal_vector(),
        axis.any_orthonormal_vector(),
    );
    let mut light =
        json!({"kind": "circular", "center": spec.center, "axis": spec.axis, "radii": spec.radii});
    if args.circular {
        light["derived"] = json!(true);
    }
    report.set("light", light);
    Ok(MeshLines {
        lines,
        bands,
        radii: Some(radii),
        drawn: None,
        view_up,
        spacing: None,
    })
}

/// Lines (and bands) of the readable linear light array (Yong et al. §2)
/// and the readable subset to draw; records the lights and the drawn
/// lines' statistics in the report, warns when the lines are hard to read.
fn linear_lines(
    args: &HighlightArgs,
    mesh: &fairline::SurfaceMesh,
    report: &mut Report,
) -> Result<MeshLines> {
    let light = args.light.light_array(mesh)?;
    let light = args.light.readable(mesh, light)?;
    let opts = args.light.options();
    let (lines, bands, shown) = report
        .time(|| -> Result<_, HighlightError> {
            let model = HighlightModel::new(mesh, light, opts)?;
            let lines = model.lines(mesh);
            let bands = match args.band {
                Some(rho) => Some(model.bands(mesh, rho)?),
                None => None,
            };
            let shown = model.readable_lines(mesh, &lines, &Readability::for_part(mesh, &light));
            Ok((lines, bands, shown))
        })
        .map_err(to_input_error)?;
    report.set("light", json!({"kind": "linear", "array": light}));
    report.set(
        "drawn",
        fairline::highlight::DrawnLineStats::of(mesh, &light, &shown),
    );
    if let Some(w) = crate::highlight_png::line_warning(
        &args.mesh,
        &lines,
        &shown,
        &light,
        fairline::highlight::readable::part_width(mesh.positions(), light.across()),
    ) {
        eprintln!("{w}");
    }
    Ok(MeshLines {
        lines,
        bands,
        radii: None,
        drawn: Some(shown),
        view_up: crate::highlight_png::default_camera(&light),
        spacing: Some(light.spacing()),
    })
}

/// The `--png` picture: the drawn lines (and both bands) on the shaded
/// mesh, titled with the file name and the number of lines.
fn write_picture(
    args: &HighlightArgs,
    png: &Path,
    mesh: &fairline::SurfaceMesh,
    drawn: &MeshLines,
) -> Result<()> {
    let lines = &drawn.lines;
    let band_lines = drawn.bands.as_ref().map(|b| {
        let mut all = b.lower.clone();
        all.lines.extend(b.upper.lines.iter().cloned());
        all
    });
    let view = args.view.unwrap_or(drawn.view_up.0);
    let name = args
        .mesh
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let title = match &drawn.drawn {
        Some(d) if d.lines.len() != lines.lines.len() => format!(
            "{name}: {} of {} line pieces drawn",
            d.lines.len(),
            lines.lines.len()
        ),
        _ => format!("{name}: {} highlight lines", lines.lines.len()),
    };
    crate::highlight_png::write(
        args.size,
        png,
        mesh,
        crate::highlight_png::Overlay {
            lines: drawn.drawn.as_ref().unwrap_or(lines),
            bands: band_lines.as_ref(),
            flagged: &[],
            region: None,
            unjudged: None,
            view: (view, drawn.view_up.1),
            title,
            spacing: drawn.spacing,
        },
    )
}
