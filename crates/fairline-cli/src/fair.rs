//! `fairline fair`: highlight-line fairing of a triangle mesh (Yong et al.
//! §3, Algorithm 2) inside a region, with the surface-diffusion-flow
//! baseline for comparison.

use crate::args::{LightArgs, to_input_error};
use crate::common::Report;
use crate::error::bad_input;
use crate::output::progress;
use anyhow::Result;
use fairline::fair::{
    AUTO_RINGS, FairError, FairMethod, FairOptions, FairReport, detect_regions_to_fair,
    fair_highlight_lines, fairing_made_worse, grow_region, regions_deviation, regions_report,
    regions_union, regions_warnings,
};
use fairline::highlight::detect_region;
use fairline::mesh::FaceId;
use fairline::picture::{
    FAIRING_DESIRED_COLOR, FAIRING_LINE_COLOR, FAIRING_OUTLINE_COLOR, fairing_picture,
};
use fairline::render::RenderOptions;
use fairline::{Control, SurfaceMesh};
use serde_json::{Value, json};
use std::path::PathBuf;

/// The energy to minimise.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Yong et al.'s energy with the desired curves' end tangents taken
    /// from a smooth surface fitted beyond the defect's footprint (the
    /// lines the clean surface would have), then ¾ of that result + ¼ of
    /// the diffusion-flow result on the same region (closer to the
    /// defect-free surface than diffusion flow on every generated panel;
    /// BENCHMARKS.md Session 22); --laplacian-weight adds a
    /// curvature-Laplacian term.
    Highlight,
    /// Yong et al. exactly (Algorithm 2): Willmore energy + distance of the
    /// highlight lines to their desired curves, desired curves from the
    /// input's outside parts, no refits, no diffusion-flow share.
    Paper,
    /// Baseline: surface diffusion flow ∂V/∂t = N Δ_B H (Xu et al.).
    DiffusionFlow,
}

/// Removes a local irregularity so that the highlight lines inside a region
/// follow smooth desired curves (optimized geometric Hermite curves between
/// the nodes just outside the region), moving only vertices whose motion
/// changes nothing outside the region: every vertex, normal and highlight
/// node outside stays bit-identical. The region is region JSON
/// ({"faces":[..]}, {"vertices":[..]} or {"sphere":{"center":[x,y,z],"radius":r}}),
/// e.g. the output of `fairline detect` (which already holds the two rings
/// of support faces fairing needs: a vertex can move only when all faces
/// around it and around its neighbours are in the region); --grow N adds N
/// rings of faces to any region. With --auto the irregular regions are
/// detected, grown by four rings and faired in turn. The report measures
/// the detection score (`fairline detect`) inside the region before and
/// after with the same lights, and runs detection on the result: when it
/// still flags a region (inside or outside the faired one, each site
/// against its own threshold, exactly as `detect` on the output would), a
/// warning names it and says what to do. Use the same light options as for
/// `highlight`/`detect`: the detection scores are measured with those
/// lights (report key "light"), the fairing works on the lines `highlight`
/// and `detect` draw ("fairing_light": every k-th line on round parts,
/// whose detail lines lie a fraction of an edge apart; the same lights on
/// panels and whenever --spacing or --lights is given).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline fair fairline-demo/dented-panel.obj --region fairline-demo/dented-panel-region.json -o panel-faired.obj --png fair.png --report fair.json\n  fairline detect fairline-demo/dented-panel.obj -o region.json && fairline fair fairline-demo/dented-panel.obj --region region.json -o faired.obj\n  fairline fair fairline-demo/dented-panel.obj --auto -o faired-auto.obj\n  fairline fair fairline-demo/dented-panel.obj --region fairline-demo/dented-panel-region.json --method diffusion-flow -o flow.obj\n  fairline fair fairline-demo/dented-panel.obj --region fairline-demo/dented-panel-region.json --method paper -o paper.obj"
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
    /// Grow the region by N rings of faces (faces sharing a vertex with it)
    /// before fairing.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub grow: usize,
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
    /// Weight ω3 of the curvature-Laplacian fairness term
    /// D⁴ ∫(Δ_B H)² dA (D the region's diameter); --method highlight only.
    #[arg(long, default_value_t = FairOptions::default().laplacian_weight)]
    pub laplacian_weight: f64,
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
        FairError::NoMovableVertex(_)
        | FairError::Region(_)
        | FairError::InvalidOption(_)
        | FairError::Mesh(_)
        | FairError::Highlight(_) => bad_input(e.user_message()),
        FairError::Solve(_) | FairError::Cancelled(_) => anyhow::Error::new(e),
    }
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
    crate::input::note_split_vertices(&args.mesh, &mesh);
    if !mesh.is_triangle_mesh() {
        return Err(bad_input(format!(
            "{}: highlight-line fairing needs a triangle mesh (this one has polygons; triangulate it first, e.g. with `fairline convert`)",
            args.mesh.display()
        )));
    }
    // detection (the report's scores, --auto, the warning) measures at the
    // detail lights, as `detect`; fairing works on the lines the mesh
    // resolves: the readable lights (every k-th line on round parts, where
    // the detail lines lie a fraction of an edge apart; the same lights on
    // panels and whenever the spacing or a lights file is given)
    let light = args.light.light_array(&mesh)?;
    let fairing_light = args.light.readable(&mesh, light)?;
    let options = fair_options(&args, fairing_light);
    let mut report = Report::new("fair");
    let regions = regions_to_fair(&args, &mesh, light, &mut report)?;
    let regions = grow_regions(&mesh, regions, args.grow);
    // the detection score inside the regions, before (same lights as after)
    let region_faces = regions_union(&regions);
    let before = detect_region(&mesh, &light, args.light.options(), &region_faces)
        .map_err(to_input_error)?;
    let faired = fair_each_region(&args, &mesh, &regions, &options, &mut report)?;
    let current = &faired.mesh;
    fairline::io::write_mesh(&args.output, current)?;
    // the detection score inside the region after fairing, with the same
    // lights as before
    let after = detect_region(current, &light, args.light.options(), &region_faces)
        .map_err(to_input_error)?;
    let (score_before, score_after, threshold) = (before.score, after.score, before.threshold);
    report.set("detect_score_before", score_before);
    report.set("detect_score_after", score_after);
    report.set("detect_threshold", threshold);
    // the flat-spot measure inside the region (detect's second measure)
    let flat_floor = before.detection.flat_spot_floor;
    let (flat_before, flat_after) = (before.flat_spot, after.flat_spot);
    report.set("detect_flat_spot_before", flat_before);
    report.set("detect_flat_spot_after", flat_after);
    report.set("detect_flat_spot_floor", flat_floor);
    let flat_spot = if flat_floor > 0.0 && flat_before > flat_floor {
        format!(", flat spot {flat_before:.2} → {flat_after:.2} (floor {flat_floor:.2})")
    } else {
        String::new()
    };
    // and `detect` on the output, with the lights it chooses there (the
    // default lights follow the part, which fairing changed a little)
    let output_light = args.light.light_array(current)?;
    let as_detect = if output_light == light {
        after
    } else {
        detect_region(current, &output_light, args.light.options(), &region_faces)
            .map_err(to_input_error)?
    };
    report.set("detect_regions_after", as_detect.detection.regions.len());
    if let Some(w) = as_detect.remaining_defect_warning(score_before, score_after) {
        report.warn(format!("{}: {w}", args.mesh.display()));
    }
    if let (Some(png), Some(r), Some(faired_mesh)) =
        (&args.png, faired.results.first(), &faired.first)
    {
        write_picture(png, &mesh, fairing_light, r, faired_mesh)?;
    }
    if faired.first.is_none()
        && let Some(png) = &args.png
    {
        crate::output::say("note: no region was faired, so no picture was written");
        job.skip(png);
    }
    report.set("method", crate::output::option_value(&args.method));
    report.set("light", light);
    report.set("fairing_light", fairing_light);
    report.set("regions", faired.results.len());
    if args.auto {
        report.set("skipped_regions", &faired.skipped);
    }
    let total_moved = current
        .positions()
        .iter()
        .zip(mesh.positions())
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    let results = &faired.results;
    report.set_fields(regions_report(results, total_moved));
    let converged = results.iter().all(|r| r.converged);
    let (before, after) = regions_deviation(results);
    for w in regions_warnings(results, args.max_iterations, (score_before, score_after)) {
        report.warn(w);
    }
    report.write(args.report.as_deref())?;
    job.finish(format_args!(
        "{} region(s) faired, {}, detection score {score_before:.2} → {score_after:.2} (threshold {threshold:.2}){flat_spot}, highlight deviation {before:.3e} → {after:.3e}, largest move {total_moved:.3e}",
        results.len(),
        if converged { "converged" } else { "not converged" }
    ));
    if fairing_made_worse(results, (score_after, threshold), (flat_after, flat_floor)) {
        // the output is written so that it can be looked at, but it is not
        // what was asked for: exit 1 (the warning above says what got worse)
        anyhow::bail!(
            "{}: fairing made the highlight lines worse (deviation {before:.4e} -> {after:.4e}) and detection still flags the region (score {score_after:.2}, threshold {threshold:.2}); {} was written for inspection only",
            args.mesh.display(),
            args.output.display()
        );
    }
    Ok(())
}

/// The library's fairing options from the command line (the region and
/// the progress are set per region).
fn fair_options(args: &Args, light: fairline::highlight::LightArray) -> FairOptions {
    FairOptions::default()
        .light(light)
        .method(match args.method {
            Method::Highlight => FairMethod::Highlight,
            Method::Paper => FairMethod::Paper,
            Method::DiffusionFlow => FairMethod::DiffusionFlow,
        })
        .fair_weight(args.fair_weight)
        .diff_weight(args.diff_weight)
        .laplacian_weight(args.laplacian_weight)
        .max_iterations(args.max_iterations)
        .epsilon(args.epsilon)
        .highlight(args.light.options())
}

/// The regions to fair, in turn: the region file's one region, or with
/// --auto every detected region grown by [`AUTO_RINGS`] (said on the
/// terminal).
fn regions_to_fair(
    args: &Args,
    mesh: &SurfaceMesh,
    light: fairline::highlight::LightArray,
    report: &mut Report,
) -> Result<Vec<Vec<FaceId>>> {
    if let Some(path) = &args.region {
        let spec = fairline::io::read_region(path).map_err(|e| bad_input(e.to_string()))?;
        return Ok(vec![
            spec.faces(mesh)
                .map_err(|e| bad_input(format!("{}: {e}", path.display())))?,
        ]);
    }
    let (det, grown) = report
        .time(|| detect_regions_to_fair(mesh, light, args.light.options()))
        .map_err(to_input_error)?;
    report.set("detected_regions", det.regions.len());
    if det.regions.is_empty() {
        eprintln!(
            "note: {}: --auto found no defect above the detection threshold; nothing to fair",
            args.mesh.display()
        );
    }
    for (k, (r, g)) in det.regions.iter().zip(&grown).enumerate() {
        eprintln!(
            "note: --auto: region {} (score {:.1}) grown by {AUTO_RINGS} rings of faces: {} -> {} faces",
            k + 1,
            r.score,
            r.faces.len(),
            g.len()
        );
    }
    Ok(grown)
}

/// Each region grown by `rings` rings of faces (--grow; said on the
/// terminal), or the regions as they are.
fn grow_regions(mesh: &SurfaceMesh, regions: Vec<Vec<FaceId>>, rings: usize) -> Vec<Vec<FaceId>> {
    if rings == 0 {
        return regions;
    }
    regions
        .iter()
        .map(|f| {
            let grown = grow_region(mesh, f, rings);
            eprintln!(
                "note: region grown by {} rings of faces: {} -> {} faces",
                rings,
                f.len(),
                grown.len()
            );
            grown
        })
        .collect()
}

/// What fairing the regions in turn gave.
struct Faired {
    /// The mesh after the last region.
    mesh: SurfaceMesh,
    /// Each faired region's report.
    results: Vec<FairReport>,
    /// The first region's faired mesh, for the picture.
    first: Option<SurfaceMesh>,
    /// Regions --auto skipped (no movable vertex), with the reason.
    skipped: Vec<Value>,
}

/// Fairs the regions in turn, each on the result of the one before, with
/// one progress bar over all of them.
fn fair_each_region(
    args: &Args,
    mesh: &SurfaceMesh,
    regions: &[Vec<FaceId>],
    options: &FairOptions,
    report: &mut Report,
) -> Result<Faired> {
    let mut faired = Faired {
        mesh: mesh.clone(),
        results: Vec::new(),
        first: None,
        skipped: Vec::new(),
    };
    let bar = progress((regions.len() * options.max_iterations) as u64, "fairing");
    for (k, faces) in regions.iter().enumerate() {
        let start = bar.position();
        let shown = bar.clone();
        let control = Control::new().on_progress(move |p| shown.set_position(start + p.done));
        let region_options = options.clone().region(faces.clone()).control(control);
        let outcome = report.time(|| fair_highlight_lines(&faired.mesh, &region_options));
        match outcome {
            Ok(out) => {
                faired.results.push(out.report);
                faired.mesh.set_positions(out.positions)?;
                if faired.first.is_none() {
                    faired.first = Some(faired.mesh.clone());
                }
            }
            Err(FairError::NoMovableVertex(msg)) if args.auto => {
                faired.skipped.push(json!({"region": k, "reason": msg}));
            }
            // a region that cannot be faired is the region file's fault: name it
            Err(e) => return Err(name_region(to_error(e), args.region.as_deref())),
        }
    }
    bar.finish_and_clear();
    Ok(faired)
}

/// The --png before/after picture of the first region with the lines of
/// the lights it was faired with, `light` (the readable lights: the lines
/// `highlight` and `detect` show with the same options) and their desired
/// curves.
fn write_picture(
    png: &std::path::Path,
    mesh: &SurfaceMesh,
    light: fairline::highlight::LightArray,
    r: &FairReport,
    faired: &SurfaceMesh,
) -> Result<()> {
    let mut opts = RenderOptions::with_size(900, 700);
    (opts.view_dir, opts.up) = crate::highlight_png::default_camera(&light);
    let mut img = fairing_picture(mesh, faired, r, &opts)?;
    crate::highlight_png::draw_key(
        &mut img,
        &[
            (
                FAIRING_LINE_COLOR,
                format!(
                    "highlight lines, light spacing {}",
                    crate::highlight_png::fmt_len(light.spacing())
                ),
            ),
            (FAIRING_OUTLINE_COLOR, "region outline".into()),
            (FAIRING_DESIRED_COLOR, "desired lines (before)".into()),
        ],
    );
    img.write_png(png)?;
    Ok(())
}
