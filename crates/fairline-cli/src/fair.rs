//! `fairline fair`: highlight-line fairing of a triangle mesh (Yong et al.
//! §3, Algorithm 2) inside a region, with the surface-diffusion-flow
//! baseline for comparison.

use crate::common::{Report, bad_input, progress};
use crate::highlight::{LightArgs, to_input_error};
use anyhow::Result;
use fairline::SurfaceMesh;
use fairline::fair::{
    FairError, FairMethod, FairOptions, FairResult, RegionSpec, fair_highlight_lines_with,
    fairing_picture, grow_region,
};
use fairline::highlight::{DetectOptions, HighlightModel, detect_irregularities};
use fairline::mesh::FaceId;
use fairline::render::RenderOptions;
use serde_json::{Value, json};
use std::path::PathBuf;

/// The energy to minimise.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Yong et al.: Willmore energy + distance of the highlight lines to
    /// their desired curves.
    Highlight,
    /// Baseline: surface diffusion flow ∂V/∂t = N Δ_B H (Xu et al.).
    DiffusionFlow,
}

/// Removes a local irregularity so that the highlight lines inside a region
/// follow smooth desired curves (optimized geometric Hermite curves between
/// the nodes just outside the region), moving only vertices whose motion
/// changes nothing outside the region: every vertex, normal and highlight
/// node outside stays bit-identical. The region is region JSON
/// ({"faces":[..]}, {"vertices":[..]} or {"sphere":{"center":[x,y,z],"radius":r}}),
/// e.g. the output of `fairline detect`; with --auto the irregular regions
/// are detected (and grown by four rings of faces) and faired in turn. Use
/// the same light options as for `highlight`/`detect`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  fairline fair panel.obj --region region.json -o panel-faired.obj --png fair.png --report fair.json\n  fairline detect panel.obj -o region.json && fairline fair panel.obj --region region.json -o faired.obj\n  fairline fair panel.obj --auto -o faired.obj\n  fairline fair panel.obj --region region.json --method diffusion-flow -o flow.obj"
)]
pub struct Args {
    /// Input triangle mesh.
    pub mesh: PathBuf,
    /// Region JSON.
    #[arg(
        long,
        value_name = "REGION.json",
        required_unless_present = "auto",
        conflicts_with = "auto"
    )]
    pub region: Option<PathBuf>,
    /// Detect irregular regions and fair each in turn.
    #[arg(long)]
    pub auto: bool,
    #[command(flatten)]
    pub light: LightArgs,
    /// Output mesh (.obj .ply .off .stl).
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// Most iterations N_max.
    #[arg(long, default_value_t = FairOptions::default().max_iterations)]
    pub max_iterations: usize,
    /// Stop when max|x_i| / mean edge length < epsilon (Eq. (17)).
    #[arg(long, default_value_t = FairOptions::default().epsilon)]
    pub epsilon: f64,
    /// Energy to minimise.
    #[arg(long, value_enum, default_value_t = Method::Highlight)]
    pub method: Method,
    /// Weight ω1 of the Willmore (fairness) energy.
    #[arg(long, default_value_t = FairOptions::default().fair_weight)]
    pub fair_weight: f64,
    /// Weight ω2 of the highlight-line difference energy.
    #[arg(long, default_value_t = FairOptions::default().diff_weight)]
    pub diff_weight: f64,
    /// Before/after picture with highlight lines, region outline and
    /// desired curves.
    #[arg(long, value_name = "IMG.png")]
    pub png: Option<PathBuf>,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

/// `e` with the region file's name in front, when there is one.
fn name_region(e: anyhow::Error, region: Option<&std::path::Path>) -> anyhow::Error {
    match region {
        Some(p) => e.context(p.display().to_string()),
        None => e,
    }
}

/// Library errors that are the user's input (region, options) exit with 2.
fn to_error(e: FairError) -> anyhow::Error {
    match e {
        FairError::Region(_)
        | FairError::NoMovableVertex(_)
        | FairError::InvalidOption(_)
        | FairError::Mesh(_)
        | FairError::Highlight(_) => bad_input(e.to_string()),
        FairError::Solve(_) => anyhow::Error::new(e),
    }
}

pub(crate) fn result_json(r: &FairResult) -> Value {
    json!({
        "iterations": r.iterations,
        "converged": r.converged,
        "movable_vertices": r.region.movable.len(),
        "inside_vertices": r.region.inside_vertices.len(),
        "region_faces": r.region.in_region.iter().filter(|&&b| b).count(),
        "willmore_before": r.willmore_before,
        "willmore_after": r.willmore_after,
        "highlight_deviation_before": r.deviation_before.rms,
        "highlight_deviation_after": r.deviation_after.rms,
        "highlight_deviation_max_before": r.deviation_before.max,
        "highlight_deviation_max_after": r.deviation_after.max,
        "desired_lines": r.desired_before.lines.len(),
        "max_displacement": r.max_displacement,
        "mean_edge_length": r.mean_edge_length,
        "history": r.history.iter().map(|h| json!({
            "iteration": h.iteration,
            "f_fair": h.f_fair,
            "f_diff": h.f_diff,
            "objective": h.objective,
            "predicted": h.predicted,
            "achieved": h.achieved,
            "accepted": h.accepted,
            "max_step": h.max_step,
            "step_ratio": h.step_ratio,
            "active_bounds": h.active_bounds,
            "target_nodes": h.target_nodes,
        })).collect::<Vec<_>>(),
    })
}

pub fn run(args: Args) -> Result<()> {
    let mut job = crate::output::Job::new("fair")
        .input(&args.mesh)
        .input_opt(args.region.as_deref())
        .input_opt(args.light.lights.as_deref())
        .output("-o", &args.output)
        .output_opt("--png", args.png.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    let mesh = fairline::io::read_mesh(&args.mesh)?;
    crate::repair::note_split_vertices(&args.mesh, &mesh);
    if !mesh.is_triangle_mesh() {
        return Err(bad_input(format!(
            "{}: highlight-line fairing needs a triangle mesh (this one has polygons; triangulate it first, e.g. with `fairline convert`)",
            args.mesh.display()
        )));
    }
    let light = args.light.light_array(&mesh)?;
    let options = FairOptions {
        method: match args.method {
            Method::Highlight => FairMethod::Highlight,
            Method::DiffusionFlow => FairMethod::DiffusionFlow,
        },
        fair_weight: args.fair_weight,
        diff_weight: args.diff_weight,
        max_iterations: args.max_iterations,
        epsilon: args.epsilon,
        highlight: args.light.options(),
    };
    let mut report = Report::new("fair");
    // the regions to fair, in turn
    let regions: Vec<Vec<FaceId>> = if let Some(path) = &args.region {
        let text = std::fs::read_to_string(path)
            .map_err(|e| bad_input(format!("{}: {e}", path.display())))?;
        let spec = RegionSpec::from_json(&text)
            .map_err(|e| bad_input(format!("{}: {e}", path.display())))?;
        vec![
            spec.faces(&mesh)
                .map_err(|e| bad_input(format!("{}: {e}", path.display())))?,
        ]
    } else {
        let det = report
            .time(|| -> Result<_, fairline::highlight::HighlightError> {
                let model = HighlightModel::new(&mesh, light, args.light.options())?;
                let lines = model.lines(&mesh);
                let opts = DetectOptions {
                    plane_normal: Some(light.plane_normal()),
                    ..DetectOptions::default()
                };
                detect_irregularities(&mesh, &lines, light.spacing(), &opts)
            })
            .map_err(to_input_error)?;
        report.set("detected_regions", det.regions.len());
        det.regions
            .iter()
            .map(|r| grow_region(&mesh, &r.faces, 4))
            .collect()
    };
    let mut current: SurfaceMesh = mesh.clone();
    let mut results: Vec<Value> = Vec::new();
    let mut first: Option<FairResult> = None;
    let mut skipped: Vec<Value> = Vec::new();
    let bar = progress((regions.len() * options.max_iterations) as u64, "fairing");
    for (k, faces) in regions.iter().enumerate() {
        let outcome = report.time(|| {
            fair_highlight_lines_with(&current, &light, faces, &options, &mut |_| bar.inc(1))
        });
        match outcome {
            Ok(r) => {
                results.push(result_json(&r));
                current = r.mesh.clone();
                if first.is_none() {
                    first = Some(r);
                }
            }
            Err(FairError::NoMovableVertex(msg)) if args.auto => {
                skipped.push(json!({"region": k, "reason": msg}));
            }
            // a region that cannot be faired is the region file's fault: name it
            Err(e) => return Err(name_region(to_error(e), args.region.as_deref())),
        }
    }
    bar.finish_and_clear();
    fairline::io::write_mesh(&args.output, &current)?;
    if first.is_none() {
        report.warn("no region was faired (nothing detected): the output is the input unchanged");
        if let Some(png) = &args.png {
            crate::output::say("note: no region was faired, so no picture was written");
            job.skip(png);
        }
    }
    if let (Some(png), Some(r)) = (&args.png, &first) {
        let mut opts = RenderOptions::with_size(900, 700);
        opts.view_dir = -light.plane_normal() + 0.35 * light.across();
        opts.up = light.direction();
        let img = fairing_picture(&mesh, r, &opts)?;
        img.write_png(png)?;
    }
    report.set("method", crate::output::option_value(&args.method));
    report.set("light", light);
    report.set("regions", results.len());
    if args.auto {
        report.set("skipped_regions", skipped);
    }
    let total_moved = current
        .positions()
        .iter()
        .zip(mesh.positions())
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    match results.as_slice() {
        [one] => {
            if let Value::Object(m) = one {
                for (key, v) in m {
                    report.set(key, v.clone());
                }
            }
        }
        _ => {
            let sum = |key: &str| -> f64 { results.iter().filter_map(|r| r[key].as_f64()).sum() };
            report.set("iterations", sum("iterations") as u64);
            report.set(
                "converged",
                results.iter().all(|r| r["converged"] == json!(true)),
            );
            report.set("movable_vertices", sum("movable_vertices") as u64);
            report.set("willmore_before", sum("willmore_before"));
            report.set("willmore_after", sum("willmore_after"));
            report.set(
                "highlight_deviation_before",
                results
                    .iter()
                    .filter_map(|r| r["highlight_deviation_before"].as_f64())
                    .fold(0.0, f64::max),
            );
            report.set(
                "highlight_deviation_after",
                results
                    .iter()
                    .filter_map(|r| r["highlight_deviation_after"].as_f64())
                    .fold(0.0, f64::max),
            );
            report.set("max_displacement", total_moved);
            report.set("per_region", results.clone());
        }
    }
    let converged = results.iter().all(|r| r["converged"] == json!(true));
    let deviation = |key: &str| {
        results
            .iter()
            .filter_map(|r| r[key].as_f64())
            .fold(0.0, f64::max)
    };
    let (before, after) = (
        deviation("highlight_deviation_before"),
        deviation("highlight_deviation_after"),
    );
    if !converged {
        report.warn(format!(
            "fairing did not converge within --max-iterations {}; try more iterations or a larger region (--grow, --auto)",
            args.max_iterations
        ));
    }
    if after > before {
        report.warn(format!(
            "the highlight-line deviation got worse: {before:.4e} before, {after:.4e} after"
        ));
    }
    report.write(args.report.as_deref())?;
    job.finish(format_args!(
        "{} region(s) faired, {}, highlight deviation {before:.3e} → {after:.3e}, largest move {total_moved:.3e}",
        results.len(),
        if converged { "converged" } else { "not converged" }
    ));
    Ok(())
}
