//! `fairline detect`: irregular stretches of highlight lines turned into
//! suggested fairing regions.

use crate::common::{Report, bad_input, spinner, write_json};
use crate::highlight::{LightArgs, read_triangles, to_input_error};
use anyhow::Result;
use fairline::highlight::{DetectOptions, HighlightModel, detect_irregularities};
use fairline::mesh::FaceId;
use serde_json::json;
use std::path::PathBuf;

/// Finds wiggles, inflection clusters and kinks in the highlight lines of a
/// linear light array (curvature of each line compared with its own running
/// mean over one spacing, normalised by the spacing) and turns them into
/// connected face regions, ranked by score. Writes the union of all regions
/// as region JSON {"faces":[...]} (faces of the input mesh); the report lists
/// each region with its score, size, centre and the lines involved.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  fairline detect panel.obj -o region.json --report detect.json\n  fairline detect spot.ply --plane-normal 0,1,1 --spacing 0.02 -o region.json --png detect.png"
)]
pub struct Args {
    /// Input triangle (or polygon) mesh.
    pub mesh: PathBuf,
    #[command(flatten)]
    pub light: LightArgs,
    /// Flag where |κ − κ̄|·s exceeds this (dimensionless).
    #[arg(long, default_value_t = DetectOptions::default().wiggle_threshold)]
    pub threshold: f64,
    /// Region radius around flagged points, in light spacings.
    #[arg(long, default_value_t = DetectOptions::default().region_radius)]
    pub region_radius: f64,
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
    #[arg(long, value_parser = crate::common::parse_vec3, allow_hyphen_values = true, value_name = "X,Y,Z")]
    pub view: Option<fairline::Vec3>,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    if !args
        .output
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
    {
        return Err(bad_input(format!(
            "{}: the region is written as .json",
            args.output.display()
        )));
    }
    if let Some(p) = &args.png {
        crate::highlight_png::check_png(p)?;
    }
    let job = crate::output::Job::new("detect")
        .input(&args.mesh)
        .input_opt(args.light.lights.as_deref())
        .output("-o", &args.output)
        .output_opt("--png", args.png.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    if args.view.is_some_and(|v| v.length() == 0.0) {
        return Err(bad_input("--view must not be the zero vector"));
    }
    let (mesh, source) = read_triangles(&args.mesh)?;
    let light = args.light.light_array(&mesh)?;
    let opts = DetectOptions {
        wiggle_threshold: args.threshold,
        region_radius: args.region_radius,
        plane_normal: Some(light.plane_normal()),
        ..DetectOptions::default()
    };
    let mut report = Report::new("detect");
    let bar = spinner("detecting irregularities");
    let (lines, mut det) = report
        .time(|| -> Result<_, fairline::highlight::HighlightError> {
            let model = HighlightModel::new(&mesh, light, args.light.options())?;
            let lines = model.lines(&mesh);
            let det = detect_irregularities(&mesh, &lines, light.spacing(), &opts)?;
            Ok((lines, det))
        })
        .map_err(to_input_error)?;
    bar.finish_and_clear();
    if let Some(n) = args.max_regions {
        det.regions.truncate(n);
    }
    // faces of the input mesh (triangulated polygons map back to their polygon)
    let to_input = |faces: &[FaceId]| -> Vec<u32> {
        let mut out: Vec<u32> = match &source {
            Some(src) => faces.iter().map(|f| src[f.idx()].0).collect(),
            None => faces.iter().map(|f| f.0).collect(),
        };
        out.sort_unstable();
        out.dedup();
        out
    };
    let all = to_input(&det.all_faces());
    write_json(&args.output, &json!({"faces": all}))?;
    let regions: Vec<_> = det
        .regions
        .iter()
        .map(|r| {
            json!({
                "score": r.score,
                "faces": to_input(&r.faces).len(),
                "center": r.center.to_array(),
                "lines": r.lines,
            })
        })
        .collect();
    let flagged: Vec<_> = det
        .lines
        .iter()
        .filter(|l| !l.stretches.is_empty())
        .map(|l| {
            json!({
                "line": l.line,
                "index": l.index,
                "score": l.score,
                "max_wiggle": l.max_wiggle,
                "inflections": l.inflections,
                "stretches": l.stretches.len(),
            })
        })
        .collect();
    report.set("vertices", mesh.vertex_count());
    report.set("lines", lines.lines.len());
    report.set("spacing", light.spacing());
    report.set("light", light);
    report.set("region_faces", all.len());
    report.set("regions", regions);
    report.set("flagged_lines", flagged);
    if let Some(png) = &args.png {
        let stretches: Vec<Vec<fairline::Vec3>> = det
            .lines
            .iter()
            .flat_map(|l| l.stretches.iter().map(|s| s.points.clone()))
            .collect();
        let view = args.view.unwrap_or(crate::highlight_png::default_view(
            light.plane_normal(),
            light.across(),
        ));
        let title = format!(
            "{}: {} region(s)",
            args.mesh
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            det.regions.len()
        );
        let faces = det.all_faces();
        crate::highlight_png::write(
            png,
            &mesh,
            crate::highlight_png::Overlay {
                lines: &lines,
                bands: None,
                flagged: &stretches,
                region: Some(&faces),
                view: (view, light.across()),
                title,
            },
        )?;
    }
    if lines.lines.is_empty() {
        report.warn("no highlight line crosses the mesh, so nothing could be detected; try other light options (--plane-normal, --direction, --spacing)");
    }
    report.write(args.report.as_deref())?;
    job.finish(format_args!(
        "{} region(s) flagged ({} faces) from {} highlight line(s) on {} vertices",
        det.regions.len(),
        all.len(),
        lines.lines.len(),
        mesh.vertex_count()
    ));
    Ok(())
}
