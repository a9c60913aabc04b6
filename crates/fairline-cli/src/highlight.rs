//! `fairline highlight`: highlight lines of a linear light array (Yong et
//! al. §2) or of concentric circular lights (Nishiyama et al. §2) on a
//! triangle mesh, written as JSON or OBJ polylines.

use crate::args::{HighlightArgs, Radii, circular_file};
use crate::common::{print_warnings, write_report};
use crate::error::bad_input;
use crate::input::read_triangles;
use crate::lines_file::{
    LinesFormat, check_curve_tolerance, lines_format, write_curves, write_lines,
};
use crate::output::spinner;
use anyhow::Result;
use fairline::highlight::{CircularLights, HighlightBands, HighlightLines, LightArray};
use fairline::render::ReflectionZebra;
use fairline::{Control, Vec3};
use fairline_commands::Subject;
use fairline_commands::highlight::{self, HighlightLights, HighlightOutcome, HighlightSettings};
use std::path::Path;

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
        let zebra = write_picture(&args, png, &mesh, &MeshLines::of(&out), view)?;
        if let Some(z) = &zebra {
            out.report.set("zebra", crate::args::zebra_json(z));
        }
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
    light: Option<&'a LightArray>,
}

impl<'a> MeshLines<'a> {
    fn of(out: &'a HighlightOutcome) -> Self {
        MeshLines {
            lines: &out.lines,
            bands: out.bands.as_ref(),
            drawn: out.drawn.as_ref(),
            spacing: out.light.map(|l| l.spacing()),
            light: out.light.as_ref(),
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
/// mesh, titled with the file name and the number of lines; with --zebra
/// the reflection zebra (tubes along the linear lights, else the part's
/// default lights) under them, which is returned.
fn write_picture(
    args: &HighlightArgs,
    png: &Path,
    mesh: &fairline::SurfaceMesh,
    drawn: &MeshLines<'_>,
    view: (Vec3, Vec3),
) -> Result<Option<ReflectionZebra>> {
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
    let mut title = match drawn.drawn {
        Some(d) if d.lines.len() != lines.lines.len() => format!(
            "{name}: {} of {} line pieces drawn",
            d.lines.len(),
            lines.lines.len()
        ),
        _ => format!("{name}: {} highlight lines", lines.lines.len()),
    };
    let opts = crate::highlight_png::render_options(args.size, view);
    let zebra = args.zebra.reflection_zebra(mesh, drawn.light, &opts)?;
    if let Some(z) = &zebra {
        title.push_str(&format!("; {}", crate::args::zebra_title(z)));
    }
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
            zebra,
        },
    )?;
    Ok(zebra)
}
