//! `fairline render`: pictures of meshes and surfaces.

use crate::args::{LightArgs, ZebraArgs, parse_size, parse_vec3, to_input_error};
use crate::common::Report;
use crate::error::bad_input;
use anyhow::{Context, Result};
use fairline::geom::{CurvatureMethod, principal_curvatures};
use fairline::highlight::{HighlightModel, LightArray};
use fairline::picture::{Picture, ScalarField, mesh_picture};
use fairline::render::{Colormap, PartView, PolylineLayer, RegionLabels, RenderOptions};
use fairline::{Control, SurfaceMesh, Vec3};
use fairline_commands::detect::{self, DetectInput, DetectSettings};
use std::path::PathBuf;

/// Tessellation samples along the diagonal of a multi-patch part
/// ([`crate::surface::tessellated_part`]); one surface gets 64 × 64.
const PART_SAMPLES: usize = 200;

/// Per-vertex scalar to colour the surface with.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scalar {
    /// Larger principal curvature.
    K1,
    /// Smaller principal curvature.
    K2,
    /// Mean curvature (k1 + k2) / 2.
    Mean,
    /// Gaussian curvature k1 k2.
    Gauss,
}

/// Renders a mesh (or a B-spline surface, tessellated) to PNG with a
/// software rasteriser: smooth shading, optional curvature colouring with a
/// legend, optional wireframe, optional highlight lines of a linear light
/// array (Yong et al. Algorithm 1; light options as for `highlight`, defaults
/// from the bounding box) with the stretches `detect` finds irregular drawn
/// in red over them, optional reflection zebra (the eye's ray reflected
/// into parallel tube lights along the light array's direction, as Rhino's
/// Zebra; stripes denser than about three pixels fade to grey).
/// Deterministic output.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline render fairline-demo/sphere.ply --png sphere.png\n  fairline render fairline-demo/rounded-cube.obj --png cube-mean.png --scalar mean --view 1,0.3,-0.5 --size 1600x1200\n  fairline render fairline-demo/dented-panel.obj --png panel-lines.png --highlight --plane-normal 0,0,1 --direction 0,1,0 --spacing 0.05\n  fairline render fairline-demo/dented-panel.obj --png panel-zebra.png --zebra"
)]
pub struct Args {
    /// Mesh (.obj .ply .off .stl) or surface (.json .igs .step).
    pub input: PathBuf,
    /// Output PNG.
    #[arg(long, value_name = "IMG.png")]
    pub png: PathBuf,
    /// Colour by a curvature field (Rusinkiewicz estimate).
    #[arg(long, value_enum)]
    pub scalar: Option<Scalar>,
    /// Colour range LO,HI of --scalar (default: the 2nd-98th percentile,
    /// symmetric about 0, so a few extreme vertices do not wash the map out).
    #[arg(long, value_name = "LO,HI", value_parser = crate::args::parse_range, allow_hyphen_values = true)]
    pub range: Option<(f64, f64)>,
    /// Viewing direction X,Y,Z (from the eye towards the object).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub view: Option<Vec3>,
    /// Image size WxH.
    #[arg(long, value_parser = parse_size, default_value = "1200x900")]
    pub size: (u32, u32),
    /// Draw the mesh edges.
    #[arg(long)]
    pub wireframe: bool,
    /// Draw highlight lines on the shaded mesh; irregular stretches (as
    /// `detect` finds them) in red.
    #[arg(long)]
    pub highlight: bool,
    #[command(flatten)]
    pub zebra: ZebraArgs,
    #[command(flatten)]
    pub light: LightArgs,
    /// With --highlight: flag where |κ − κ̄|·s exceeds this (see `detect`).
    #[arg(long, default_value_t = DetectSettings::default().threshold, requires = "highlight")]
    pub threshold: f64,
    /// Surface index in a multi-surface file (default: all surfaces).
    #[arg(long)]
    pub surface: Option<usize>,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

/// Render options of a picture of `mesh` at `size`: the camera rule's
/// view of the part ([`fairline::picture::part_view`]), or the command
/// line's `view` with the part's up; and the rule's view for the report.
pub fn options(
    mesh: &SurfaceMesh,
    view: Option<Vec3>,
    size: (u32, u32),
) -> Result<(RenderOptions, PartView)> {
    crate::args::check_view(view)?;
    let pv = fairline::picture::part_view(mesh);
    let mut opts = RenderOptions::with_size(size.0, size.1);
    opts.view_dir = view.unwrap_or(pv.view_dir);
    opts.up = pv.up;
    Ok((opts, pv))
}

/// The view direction and up of a picture of `mesh`: the camera rule's
/// ([`fairline::picture::part_view`]), the direction replaced by `view`
/// when given.
pub fn camera(mesh: &SurfaceMesh, view: Option<Vec3>) -> (Vec3, Vec3) {
    let pv = fairline::picture::part_view(mesh);
    (view.unwrap_or(pv.view_dir), pv.up)
}

/// The report's account of a picture's camera: the direction and up used
/// and the rule's view of the part with why its up is up.
pub fn view_json(opts: &RenderOptions, pv: &PartView) -> serde_json::Value {
    serde_json::json!({
        "dir": opts.view_dir.to_array(),
        "up": opts.up.to_array(),
        "part": pv,
    })
}

pub fn run(args: Args) -> Result<()> {
    crate::output::require_extension("--png", &args.png, &["png"])?;
    if args.range.is_some() && args.scalar.is_none() {
        return Err(bad_input(
            "--range sets the colour range of --scalar; give --scalar too (e.g. --scalar mean --range -2,2)",
        ));
    }
    let job = crate::output::Job::new("render")
        .input(&args.input)
        .input_opt(args.light.lights.as_deref())
        .output("--png", &args.png)
        .output_opt("--report", args.report.as_deref())
        .check()?;
    check_light_options_need_highlight(&args)?;
    let (mesh, patch_labels) = load_mesh(&args)?;
    let (opts, part_view) = options(&mesh, args.view, args.size)?;
    let tri;
    let tri_mesh = if mesh.is_triangle_mesh() {
        &mesh
    } else {
        tri = fairline::mesh::triangulate(&mesh)
            .with_context(|| format!("{}: triangulating its polygons", args.input.display()))?
            .mesh;
        &tri
    };
    let light = if args.highlight {
        Some(args.light.light_array(tri_mesh)?)
    } else {
        None
    };
    let zebra = if args.zebra.zebra {
        let array = args.light.light_array(tri_mesh)?;
        args.zebra.reflection_zebra(tri_mesh, Some(&array), &opts)?
    } else {
        None
    };
    let mut report = Report::new("render");
    let mut summary = None;
    let bar = crate::output::spinner("rendering");
    let image = report.time(|| -> Result<_> {
        let values;
        let mut picture = Picture {
            wireframe: args.wireframe,
            title: Some(
                args.input
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default(),
            ),
            ..Default::default()
        };
        picture.zebra = zebra;
        if let (Some(z), Some(t)) = (&zebra, &mut picture.title) {
            t.push_str(&format!(": {}", crate::args::zebra_title(z)));
        }
        let mut key = Vec::new();
        if let Some(light) = light {
            let drawn = highlight_overlay(&args, tri_mesh, light, &opts)?;
            picture.polylines = drawn.polylines;
            key = drawn.key;
            summary = Some(drawn.summary);
        }
        if let Some(s) = args.scalar {
            let name;
            (values, name) = curvature_field(tri_mesh, s);
            picture.scalar = Some(ScalarField {
                name: name.into(),
                values: &values,
                colormap: Colormap::Coolwarm,
                range: args.range,
            });
        }
        let mut img = match &patch_labels {
            Some(l) if l.triangle_region.len() == mesh.face_count() => {
                fairline::picture::labelled_mesh_picture(&mesh, &picture, l, &opts)?.0
            }
            _ => mesh_picture(&mesh, &picture, &opts)?,
        };
        crate::highlight_png::draw_key(&mut img, &key);
        Ok(img)
    })?;
    bar.finish_and_clear();
    image.write_png(&args.png)?;
    report.set("vertices", mesh.vertex_count());
    report.set("faces", mesh.face_count());
    report.set("width", args.size.0);
    report.set("height", args.size.1);
    report.set("view", view_json(&opts, &part_view));
    if let Some(z) = &zebra {
        report.set("zebra", crate::args::zebra_json(z));
    }
    let mut what = format!(
        "{}x{} picture of {} vertices",
        args.size.0,
        args.size.1,
        mesh.vertex_count()
    );
    if let Some(h) = summary {
        if h["lines"] == 0 {
            report.warn("no highlight line crosses the mesh; try other light options (--plane-normal, --direction, --spacing)");
        }
        what.push_str(&format!(
            " with {} highlight line(s), {} flagged region(s)",
            h["lines"], h["regions"]
        ));
        report.set("highlight", h);
    }
    report.write(args.report.as_deref())?;
    job.finish(what)?;
    Ok(())
}

/// Light options mean nothing without `--highlight` or `--zebra`: refused
/// (exit 2).
fn check_light_options_need_highlight(args: &Args) -> Result<()> {
    let l = &args.light;
    let lights_used = args.highlight || args.zebra.zebra;
    if !lights_used
        && (l.direction.is_some()
            || l.plane_normal.is_some()
            || l.plane_point.is_some()
            || l.spacing.is_some()
            || l.lights.is_some()
            || l.min_normal_cos != fairline::highlight::HighlightOptions::default().min_normal_cos)
    {
        return Err(bad_input(
            "light options (--direction, --plane-normal, --plane-point, --spacing, --lights, --min-normal-cos) need --highlight or --zebra",
        ));
    }
    Ok(())
}

/// The mesh to draw: a mesh file as read, or a surface file tessellated
/// (one surface, or `--surface K`: 64 × 64 samples; a part of several
/// patches: [`PART_SAMPLES`] along its diagonal, with each patch's index to
/// label at its visible centre).
fn load_mesh(args: &Args) -> Result<(SurfaceMesh, Option<RegionLabels>)> {
    if !crate::surface::is_surface_path(&args.input) {
        return Ok((crate::input::read_mesh(&args.input)?, None));
    }
    if args.surface.is_some() {
        let mesh = crate::surface::load_tessellated(&args.input, args.surface, 64)?;
        return Ok((mesh, None));
    }
    let surfaces = crate::surface::load_surfaces(&args.input)?;
    if surfaces.len() == 1 {
        return Ok((crate::surface::tessellated_part(&surfaces, 64)?, None));
    }
    let (mesh, patch) = crate::surface::tessellated_part_with_patches(&surfaces, PART_SAMPLES)?;
    let labels = RegionLabels {
        triangle_region: patch,
        texts: (0..surfaces.len()).map(|k| k.to_string()).collect(),
    };
    Ok((mesh, Some(labels)))
}

/// What `--highlight` adds to the picture: the readable lines with the
/// irregular stretches `detect` finds drawn over them, the key's entries,
/// and the report's `highlight` summary.
struct HighlightOverlay {
    polylines: Vec<PolylineLayer>,
    key: Vec<([f32; 3], String)>,
    summary: serde_json::Value,
}

/// The readable highlight lines of `light` on `tri_mesh` (triangles) and
/// the stretches the command layer's `detect` flags on them
/// (`--threshold`), seen from the camera of `opts`.
fn highlight_overlay(
    args: &Args,
    tri_mesh: &SurfaceMesh,
    light: LightArray,
    opts: &RenderOptions,
) -> Result<HighlightOverlay> {
    let shown_light = args.light.readable(tri_mesh, light)?;
    let model =
        HighlightModel::new(tri_mesh, shown_light, args.light.options()).map_err(to_input_error)?;
    // the detection of `fairline detect` (the whole part, what one array
    // leaves unjudged judged again with finer arrays) on the readable lines
    let settings = DetectSettings {
        threshold: args.threshold,
        ..DetectSettings::default()
    };
    let input = DetectInput {
        mesh: tri_mesh,
        source: None,
        name: None,
    };
    let out = detect::run_with_model(
        input,
        &settings,
        light,
        &model,
        fairline_commands::Report::new("detect"),
        &Control::new(),
    )?;
    let (all, lines, det) = (&out.lines, &out.shown, &out.detection);
    let stretches: Vec<Vec<Vec3>> = det
        .lines
        .iter()
        .flat_map(|l| l.stretches.iter().cloned())
        .collect();
    let key = crate::highlight_png::key_entries(&crate::highlight_png::Overlay {
        lines,
        bands: None,
        flagged: &stretches,
        region: None,
        unjudged: None,
        view: (opts.view_dir, opts.up),
        title: String::new(),
        spacing: Some(shown_light.spacing()),
        zebra: None,
    });
    let summary = serde_json::json!({
        "light": shown_light,
        "detect_light": light,
        "lines": all.lines.len(),
        "drawn": fairline::highlight::DrawnLineStats::of(tri_mesh, &shown_light, lines),
        "nodes": lines.node_count(),
        "irregular_stretches": stretches.len(),
        "regions": det.regions.len(),
    });
    Ok(HighlightOverlay {
        polylines: crate::highlight_png::line_layers(lines, &stretches),
        key,
        summary,
    })
}

/// The `--scalar` curvature field of `tri_mesh` (Rusinkiewicz estimate),
/// one value per vertex, and its name for the legend.
fn curvature_field(tri_mesh: &SurfaceMesh, s: Scalar) -> (Vec<f64>, &'static str) {
    let c = principal_curvatures(tri_mesh, CurvatureMethod::Rusinkiewicz);
    let values = match s {
        Scalar::K1 => c.k1.clone(),
        Scalar::K2 => c.k2.clone(),
        Scalar::Mean => c.mean(),
        Scalar::Gauss => c.gauss(),
    };
    let name = match s {
        Scalar::K1 => "k1",
        Scalar::K2 => "k2",
        Scalar::Mean => "mean curvature",
        Scalar::Gauss => "Gaussian curvature",
    };
    (values, name)
}
