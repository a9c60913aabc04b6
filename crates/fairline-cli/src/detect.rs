//! `fairline detect`: irregular stretches of highlight lines turned into
//! suggested fairing regions.

use crate::args::{LightArgs, parse_size, parse_vec3};
use crate::common::{print_warnings, write_json, write_report};
use crate::input::read_triangles;
use crate::output::spinner;
use anyhow::Result;
use fairline::Control;
use fairline::highlight::{DetectOptions, Detection};
use fairline_commands::detect::{self, DetectInput, DetectSettings};
use serde_json::json;
use std::path::PathBuf;

/// Finds surface defects that disturb the highlight lines — bumps, dents,
/// flat spots, ripples, kinks up to about two light spacings across — and
/// turns them into connected face regions. The surface's
/// normals (from a fine local quadric fit) are compared with a smooth cubic
/// fit over 1.5 light spacings (--smooth-radius) around each point; the
/// score is the highlight-line displacement that difference causes, in
/// tenths of a spacing (score 1 = the line is displaced by 0.1 spacing
/// against the smooth surface's line).
/// Smooth shape (strong curvature, saddles, cylinders) scores near 0;
/// shape finer than the smooth radius (ears, horns, legs, creases: the
/// surface turns by more than 1 rad within it) is judged again with light
/// arrays of half the spacing, a quarter, … where the mesh resolves them,
/// and what stays unjudged is reported first; on noisy scans the threshold
/// rises above the noise (reported). A second measure flags flat spots wider than the fit: where
/// the curvature falls, over an area, against the surface smoothed at four
/// smooth radii (report keys flat_spot_floor, flat_spot_sites; regions are
/// ranked by severity, how far their strongest site exceeds its measure's
/// threshold). The picture draws the readable lines (round parts: every
/// k-th line, see `highlight`) with a key. Writes the
/// union of all regions as region JSON {"faces":[...]} (faces of the input
/// mesh) with two rings of support faces added around each region (what
/// fairing needs to move every vertex of it), ready for `fairline fair
/// --region`; the report lists each region
/// with its score, flat spot, severity, area, centre and the lines
/// crossing it.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline detect fairline-demo/dented-panel.obj -o region.json --png detect.png --report detect.json\n  fairline detect fairline-demo/dented-panel.obj -o region.json && fairline fair fairline-demo/dented-panel.obj --region region.json -o faired.obj\n  fairline detect fairline-demo/wavy.obj --up y -o region-y.json"
)]
pub struct Args {
    /// Input triangle (or polygon) mesh.
    pub mesh: PathBuf,
    #[command(flatten)]
    pub light: LightArgs,
    /// Flag where the score (highlight displacement in tenths of a spacing)
    /// exceeds this; raised automatically above the noise of a scan.
    #[arg(long, default_value_t = DetectOptions::default().threshold)]
    pub threshold: f64,
    /// Radius of the smooth comparison surface, in light spacings: defects
    /// up to about this size are found, larger shape is taken as intended.
    #[arg(long, default_value_t = DetectOptions::default().smooth_radius)]
    pub smooth_radius: f64,
    /// Faces within this distance of a flagged point go into a region, in
    /// light spacings.
    #[arg(long, alias = "region-radius", default_value_t = DetectOptions::default().region_margin)]
    pub region_margin: f64,
    /// Keep only the best N regions in the output (default: all).
    #[arg(long)]
    pub max_regions: Option<usize>,
    /// Output region JSON.
    #[arg(short, long, value_name = "REGION.json")]
    pub output: PathBuf,
    /// Picture: highlight lines on the shaded mesh, irregular stretches in
    /// red, suggested regions tinted orange.
    #[arg(long, value_name = "IMG.png")]
    pub png: Option<PathBuf>,
    /// Viewing direction of the picture X,Y,Z (from the eye towards the
    /// object; default: down the light-plane normal, slightly tilted).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, value_name = "X,Y,Z")]
    pub view: Option<fairline::Vec3>,
    /// Size of the --png picture, WxH.
    #[arg(long, value_parser = parse_size, default_value = "1200x900", requires = "png")]
    pub size: (u32, u32),
    #[command(flatten)]
    pub zebra: crate::args::ZebraArgs,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    crate::output::require_extension("-o", &args.output, &["json"])?;
    if let Some(p) = &args.png {
        crate::output::require_extension("--png", p, &["png"])?;
    }
    let job = crate::output::Job::new("detect")
        .input(&args.mesh)
        .input_opt(args.light.lights.as_deref())
        .output("-o", &args.output)
        .output_opt("--png", args.png.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    crate::args::check_view(args.view)?;
    let (mesh, source) = read_triangles(&args.mesh)?;
    let settings = DetectSettings {
        lights: args.light.lights()?,
        threshold: args.threshold,
        smooth_radius: args.smooth_radius,
        region_margin: args.region_margin,
        max_regions: args.max_regions,
    };
    let name = args.mesh.display().to_string();
    let input = DetectInput {
        mesh: &mesh,
        source: source.as_deref(),
        name: Some(&name),
    };
    let bar = spinner("detecting irregularities");
    let out = detect::run(input, &settings, &Control::new());
    bar.finish_and_clear();
    let mut out = out?;
    let (light, det) = (&out.light, &out.detection);
    if let Some(w) = crate::highlight_png::line_warning(
        &args.mesh,
        &out.lines,
        &out.shown,
        &out.shown_light,
        fairline::highlight::readable::part_width(mesh.positions(), light.across()),
    ) {
        eprintln!("{w}");
    }
    print_measure_notes(&args, det, light.spacing());
    write_json(&args.output, &json!({"faces": out.region}))?;
    if let Some(png) = &args.png {
        let zebra = write_picture(&args, png, &mesh, &out.shown_light, &out.shown, det)?;
        if let Some(z) = &zebra {
            out.report.set("zebra", crate::args::zebra_json(z));
        }
    }
    print_warnings(&out.report);
    write_report(args.report.as_deref(), &out.report)?;
    job.finish(format_args!(
        "{} ({} faces) from {} highlight line(s) on {} vertices",
        det.summary(),
        out.region.len(),
        out.lines.lines.len(),
        mesh.vertex_count()
    ))?;
    Ok(())
}

/// The terminal notes on what the measure did not judge or flag: shape
/// finer than its scale, a noisy surface, sites within their
/// discretisation floor.
fn print_measure_notes(args: &Args, det: &Detection, spacing: f64) {
    if det.spacings.len() > 1 {
        eprintln!(
            "note: {}: the lights (spacing {spacing:.4}) left part of the surface unjudged (shape finer than their scale); finer arrays judged it too (spacings {})",
            args.mesh.display(),
            det.spacings[1..]
                .iter()
                .map(|s| format!("{s:.4}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if det.shape_sites > 0 && !det.unjudged_faces.is_empty() {
        // R is raised above --smooth-radius spacings on meshes too coarse
        // for the spacing (five mean edges at least): then only a finer
        // mesh is judged at a finer scale
        let hint = if det.smooth_radius > 1.001 * args.smooth_radius * spacing {
            "the mesh is too coarse for a finer scale (the radius is five mean edges at least); a finer mesh is judged at its own scale".to_string()
        } else {
            format!(
                "a smaller --smooth-radius (now {}) judges finer shape",
                args.smooth_radius
            )
        };
        eprintln!(
            "note: {}: {} of {} sites ({:.0} %) are shape finer than the measure's scale (the surface turns by more than {:.0}° within {:.3} of them: ears, horns, creases, tight fillets) and were not judged{}; {hint}",
            args.mesh.display(),
            det.shape_sites,
            det.sites.len(),
            100.0 * det.shape_sites as f64 / det.sites.len().max(1) as f64,
            DetectOptions::default().max_turn.to_degrees(),
            det.smooth_radius,
            if args.png.is_some() {
                " (tinted blue in the picture)"
            } else {
                ""
            },
        );
    }
    if det.threshold > args.threshold {
        eprintln!(
            "note: {}: the surface is noisy (median score {:.2}, fine-fit residual {:.3e}); only scores above {:.2} are flagged",
            args.mesh.display(),
            det.median_score,
            det.noise_level,
            det.threshold
        );
    }
    if det.flat_spot_sites > 0 {
        eprintln!(
            "note: {}: {} site(s) flagged as a flat spot: over an area, the surface's curvature falls against the surface smoothed at the wavelength {:.3} by more than {:.2} of it (the floor; 1 = flat); wider than the normal measure's radius {:.3}",
            args.mesh.display(),
            det.flat_spot_sites,
            fairline::highlight::detect::FLAT_SPOT_WAVELENGTH * det.smooth_radius,
            det.flat_spot_floor,
            det.smooth_radius,
        );
    }
    if det.discretisation_sites > 0 {
        eprintln!(
            "note: {}: {} site(s) score above {:.2} but within what the mesh's own facets explain (facets turn the normal by {:.1}° per edge there and more; discretisation level {:.2}); not flagged: shape modelled with few edges, not a defect at this resolution",
            args.mesh.display(),
            det.discretisation_sites,
            det.threshold,
            det.facet_angle.to_degrees(),
            det.discretisation_level
        );
    }
}

/// The --png picture: the readable lines, the flagged stretches and the
/// regions, titled with the number of regions and the best score; with
/// --zebra the reflection zebra under them, which is returned.
fn write_picture(
    args: &Args,
    png: &std::path::Path,
    mesh: &fairline::SurfaceMesh,
    shown_light: &fairline::highlight::LightArray,
    shown: &fairline::highlight::HighlightLines,
    det: &Detection,
) -> Result<Option<fairline::render::ReflectionZebra>> {
    let stretches = crate::highlight_png::stretches(det);
    let (view, up) = crate::render::camera(mesh, args.view);
    let mut title = format!(
        "{}: {}{}",
        args.mesh
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        det.summary(),
        det.best_summary()
            .map(|b| format!(", best {b}"))
            .unwrap_or_default()
    );
    let opts = crate::highlight_png::render_options(args.size, (view, up));
    let zebra = args
        .zebra
        .reflection_zebra(mesh, Some(shown_light), &opts)?;
    if let Some(z) = &zebra {
        title.push_str(&format!("; {}", crate::args::zebra_title(z)));
    }
    let faces = det.all_faces();
    let unjudged = det.shape_faces(mesh);
    crate::highlight_png::write(
        args.size,
        png,
        mesh,
        crate::highlight_png::Overlay {
            lines: shown,
            bands: None,
            flagged: &stretches,
            region: Some(&faces),
            unjudged: Some(&unjudged),
            view: (view, up),
            title,
            spacing: Some(shown_light.spacing()),
            zebra,
        },
    )?;
    Ok(zebra)
}
