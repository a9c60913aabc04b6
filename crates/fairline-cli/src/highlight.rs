//! `fairline highlight`: highlight lines of a linear light array (Yong et
//! al. §2) or of concentric circular lights (Nishiyama et al. §2) on a
//! triangle mesh, written as JSON or OBJ polylines.

use crate::args::{HighlightArgs, Radii, circular_file};
use crate::common::{print_warnings, write_report};
use crate::error::bad_input;
use crate::input::read_triangles;
use crate::output::spinner;
use anyhow::Result;
use fairline::highlight::{CircularLights, HighlightBands, HighlightLines};
use fairline::{Control, Vec3};
use fairline_commands::Subject;
use fairline_commands::highlight::{self, HighlightLights, HighlightOutcome, HighlightSettings};
use std::path::Path;

/// Output format of polylines.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum LinesFormat {
    /// JSON of DESIGN.md §4.
    Json,
    /// Wavefront OBJ `l` elements.
    Obj,
    /// B-spline curves in IGES ([`fairline_commands::curves`]).
    Iges,
}

/// The format of `path` from its extension.
pub fn lines_format(path: &Path) -> Result<LinesFormat> {
    crate::output::require_extension("-o", path, &["json", "obj", "igs", "iges"])?;
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    Ok(match ext.as_str() {
        "obj" => LinesFormat::Obj,
        "igs" | "iges" => LinesFormat::Iges,
        _ => LinesFormat::Json,
    })
}

/// Refuses a `--curve-tolerance` that is not a positive number.
pub fn check_curve_tolerance(t: Option<f64>) -> Result<()> {
    match t {
        Some(t) if !(t > 0.0 && t.is_finite()) => Err(bad_input(format!(
            "--curve-tolerance must be a positive number, got {t}"
        ))),
        _ => Ok(()),
    }
}

/// Writes `lines` as B-spline curves of IGES entities 126 within `tol` in
/// `unit`; returns the report's `curves` key.
pub fn write_curves(
    path: &Path,
    lines: &[fairline_commands::curves::LinePolyline<'_>],
    tol: f64,
    unit: Option<&fairline::io::units::LengthUnit>,
) -> Result<serde_json::Value> {
    let out = fairline_commands::curves::fit(lines, tol);
    let mut options = fairline::io::iges_write::IgesWriteOptions::default();
    if let Some(u) = unit {
        options = options.unit(u.clone());
    }
    fairline::io::iges_write::write_curves_iges(path, &out.curves, &options)?;
    let left_out = out.summary["left_out"].as_u64().unwrap_or(0);
    if left_out > 0 {
        crate::output::warn(format!(
            "{left_out} line(s) of fewer than two distinct points are not written as curves"
        ));
    }
    Ok(out.summary)
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
        LinesFormat::Iges => Err(anyhow::anyhow!(
            "{}: curves are written by write_curves",
            path.display()
        )),
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
    let format = lines_format(&args.output)?;
    if format != LinesFormat::Iges && args.curve_tolerance.is_some() {
        return Err(bad_input(
            "--curve-tolerance is for curves: give -o LINES.igs".to_string(),
        ));
    }
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
    check_curve_tolerance(args.curve_tolerance)?;
    let (mesh, _) = read_triangles(&args.mesh)?;
    let settings = HighlightSettings {
        lights: mesh_lights(&args)?,
        band: args.band,
    };
    let bar = spinner("highlight lines");
    let out = highlight::run(&mesh, &settings, &Control::new());
    bar.finish_and_clear();
    let mut out = out.map_err(|e| match (e.subject(), &args.light.lights) {
        (Some(Subject::Lights), Some(path)) => crate::output::name_file(path, e),
        _ => anyhow::Error::new(e),
    })?;
    if let Some(spec) = &out.derived {
        eprintln!(
            "default circular lights (save as LIGHTS.json to reuse): {}",
            serde_json::to_string(spec)?
        );
    }
    if let (Some(light), Some(shown)) = (&out.light, &out.drawn)
        && let Some(w) = crate::highlight_png::line_warning(
            &args.mesh,
            &out.lines,
            shown,
            light,
            fairline::highlight::readable::part_width(mesh.positions(), light.across()),
        )
    {
        eprintln!("{w}");
    }
    if format == LinesFormat::Iges {
        let summary = write_curves(
            &args.output,
            &fairline_commands::curves::mesh_lines(&out.lines),
            fairline_commands::curves::mesh_tolerance(args.curve_tolerance, &mesh),
            None,
        )?;
        out.report.set("curves", summary);
    } else {
        write_lines(
            &args.output,
            &out.lines,
            out.bands.as_ref(),
            out.radii.as_deref(),
        )?;
    }
    let counts = out.lines.counts();
    if let Some(png) = &args.png {
        let pv = fairline::picture::part_view(&mesh);
        let view = (args.view.unwrap_or(pv.view_dir), pv.up);
        write_picture(&args, png, &mesh, &MeshLines::of(&out), view)?;
        out.report.set(
            "view",
            serde_json::json!({"dir": view.0.to_array(), "up": view.1.to_array(), "part": pv}),
        );
    }
    print_warnings(&out.report);
    write_report(args.report.as_deref(), &out.report)?;
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

/// What the picture of a run draws: the lines (and bands), the readable
/// subset drawn of linear lights (`None`: draw all lines), and the light
/// spacing for the picture's key (linear lights).
struct MeshLines<'a> {
    lines: &'a HighlightLines,
    bands: Option<&'a HighlightBands>,
    drawn: Option<&'a HighlightLines>,
    spacing: Option<f64>,
}

impl<'a> MeshLines<'a> {
    fn of(out: &'a HighlightOutcome) -> Self {
        MeshLines {
            lines: &out.lines,
            bands: out.bands.as_ref(),
            drawn: out.drawn.as_ref(),
            spacing: out.light.map(|l| l.spacing()),
        }
    }
}

/// The lights asked for: circular lights given on the command line, in the
/// `--lights` file, or derived from the part (`--circular`); else the
/// linear light array.
fn mesh_lights(args: &HighlightArgs) -> Result<HighlightLights> {
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
    Ok(match &args.light.lights {
        Some(path) => match circular_file(path)? {
            Some(spec) => HighlightLights::Circular {
                spec,
                from_lights: true,
            },
            None => HighlightLights::Linear(args.light.lights()?),
        },
        None if args.circular => HighlightLights::DerivedCircular {
            up: args.light.up.vector(),
        },
        None => HighlightLights::Linear(args.light.lights()?),
    })
}

/// The `--png` picture: the drawn lines (and both bands) on the shaded
/// mesh, titled with the file name and the number of lines.
fn write_picture(
    args: &HighlightArgs,
    png: &Path,
    mesh: &fairline::SurfaceMesh,
    drawn: &MeshLines<'_>,
    view: (Vec3, Vec3),
) -> Result<()> {
    let lines = drawn.lines;
    let band_lines = drawn.bands.map(|b| {
        let mut all = b.lower.clone();
        all.lines.extend(b.upper.lines.iter().cloned());
        all
    });
    let name = args
        .mesh
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let title = match drawn.drawn {
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
            lines: drawn.drawn.unwrap_or(lines),
            bands: band_lines.as_ref(),
            flagged: &[],
            region: None,
            unjudged: None,
            view,
            title,
            spacing: drawn.spacing,
        },
    )
}
