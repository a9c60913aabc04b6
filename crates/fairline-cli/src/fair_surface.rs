//! `fairline fair-surface`: circular-highlight fairing of a B-spline surface
//! (Nishiyama et al. §3).

use crate::common::{Report, read_json};
use crate::error::bad_input;
use crate::surface_highlight::{palette_srgb, plot_lines, polylines, surface_picture, uv_plot};
use anyhow::Result;
use fairline::bspline::BSplineSurface;
use fairline::fair::{
    BoundaryControl, Endpoints, SurfaceFairError, SurfaceFairMethod, SurfaceFairOptions,
    fair_surface,
};
use fairline::highlight::{
    CircularLight, CircularLights, SurfaceHighlightOptions, SurfaceLight, surface_highlight_lines,
};
use fairline::render::{RenderOptions, side_by_side};
use std::path::PathBuf;

/// Fairs a B-spline surface so that chosen stretches of its circular
/// highlight lines follow smooth targets (Nishiyama et al. §3): each
/// endpoint pair of ENDPOINTS.json is snapped onto the pre-image of its
/// light, joined by a cubic Hermite target in (u, v), sampled, and the
/// control points whose support meets the knot-span box of the endpoints are
/// moved — by default (`--method regularised`) by Levenberg–Marquardt on the
/// targets plus weak targets holding every other line crossing the moved
/// region plus a thin-plate energy of the displacement, so no other line gets
/// wavier; `--method paper` is the paper's Gauss–Newton with a truncated
/// SVD. Control points on the patch boundary stay fixed unless `--boundary
/// free`. All other control points are written back bit-identical. Output: the surface file (all
/// surfaces of the input, surface --surface replaced, trims kept) as JSON,
/// IGES (.igs/.iges) or STEP (.step/.stp) by the extension of -o; IGES and
/// STEP keep the input's length unit.
///
/// LIGHTS.json: {"center":[x,y,z],"axis":[x,y,z],"radii":[r1,...]};
/// ENDPOINTS.json: {"endpoints":[{"radius":r,"start":[u,v],"end":[u,v]},...]}.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline fair-surface fairline-demo/bspline-panel-dented.json --lights fairline-demo/bspline-panel-lights.json --endpoints fairline-demo/bspline-panel-endpoints.json -o panel-faired.json --report fair.json --png fair.png --svg uv.svg"
)]
pub struct Args {
    /// Input surface (.json, .igs/.iges or .step/.stp).
    pub surface_file: PathBuf,
    /// Circular lights JSON.
    #[arg(long, value_name = "LIGHTS.json")]
    pub lights: PathBuf,
    /// Endpoints JSON.
    #[arg(long, value_name = "ENDPOINTS.json")]
    pub endpoints: PathBuf,
    /// Output surfaces: .json, .igs/.iges or .step/.stp.
    #[arg(short, long, value_name = "OUT.json|igs|step")]
    pub output: PathBuf,
    /// Which surface of the file to fair.
    #[arg(long, default_value_t = 0, value_name = "K")]
    pub surface: usize,
    /// Most Gauss–Newton iterations.
    #[arg(long, default_value_t = SurfaceFairOptions::default().max_iterations)]
    pub max_iterations: usize,
    /// ε of the stopping rule (relative change of mean |d_s|), Eq. (3.14).
    #[arg(long, default_value_t = SurfaceFairOptions::default().epsilon)]
    pub epsilon: f64,
    /// Singular values below this fraction of the largest are dropped.
    #[arg(long, default_value_t = SurfaceFairOptions::default().truncation)]
    pub truncation: f64,
    /// Floor the truncation is lowered to (tenfold) when a step is rejected or
    /// mean |d_s| falls by less than half; equal to --truncation for the
    /// paper's fixed rule (a larger value is taken as --truncation).
    #[arg(long, default_value_t = SurfaceFairOptions::default().min_truncation)]
    pub min_truncation: f64,
    /// Target sample spacing s as a fraction of the domain diagonal, Eq. (3.5).
    #[arg(long, default_value_t = SurfaceFairOptions::default().sample_spacing)]
    pub sample_spacing: f64,
    /// Grid points per direction for the pre-images.
    #[arg(long, default_value_t = SurfaceFairOptions::default().grid, value_name = "N")]
    pub grid: usize,
    /// Solver: `regularised` (Levenberg–Marquardt with weak targets on every
    /// other line and a thin-plate energy on the displacement: keeps the
    /// other lines fair) or `paper` (Nishiyama et al.'s truncated SVD).
    #[arg(long, value_enum, default_value = "regularised")]
    pub method: MethodArg,
    /// Which boundary control points may move: `fixed` (the outermost row:
    /// boundary curves and seams stay closed), `tangent` (two rows: seams
    /// also keep G1) or `free`.
    #[arg(long, value_enum, default_value = "fixed")]
    pub boundary: BoundaryArg,
    /// Weight of the weak targets holding the other lines (regularised).
    #[arg(long, default_value_t = SurfaceFairOptions::default().keep_weight)]
    pub keep_weight: f64,
    /// Weight of the thin-plate energy of the displacement (regularised).
    #[arg(long, default_value_t = SurfaceFairOptions::default().fairness_weight)]
    pub fairness_weight: f64,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
    /// Picture: highlight lines before | after.
    #[arg(long, value_name = "IMG.png")]
    pub png: Option<PathBuf>,
    /// SVG of the pre-images before (grey) and after (colour), endpoints and targets.
    #[arg(long, value_name = "UV.svg")]
    pub svg: Option<PathBuf>,
}

/// `--method`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum MethodArg {
    Regularised,
    Paper,
}

/// `--boundary`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum BoundaryArg {
    Fixed,
    Tangent,
    Free,
}

fn to_cli(e: SurfaceFairError) -> anyhow::Error {
    match e {
        SurfaceFairError::Svd | SurfaceFairError::Surface(_) => anyhow::Error::new(e),
        SurfaceFairError::NothingToMove(_) => bad_input(format!("{e} (--boundary free)")),
        other => bad_input(other.to_string()),
    }
}

pub fn run(args: Args) -> Result<()> {
    if !crate::surface::is_surface_path(&args.output) {
        return Err(bad_input(format!(
            "{}: -o must name a surface file (.json, .igs/.iges or .step/.stp)",
            args.output.display()
        )));
    }
    if let Some(p) = &args.png {
        crate::output::require_extension("--png", p, &["png"])?;
    }
    if let Some(p) = &args.svg {
        crate::output::require_extension("--svg", p, &["svg"])?;
    }
    let job = crate::output::Job::new("fair-surface")
        .input(&args.surface_file)
        .input(&args.lights)
        .input(&args.endpoints)
        .output("-o", &args.output)
        .output_opt("--png", args.png.as_deref())
        .output_opt("--svg", args.svg.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    let input = crate::surface::load_surface_file(&args.surface_file)?;
    let unit = input.unit;
    let mut surfaces = input.surfaces;
    if args.surface >= surfaces.len() {
        return Err(bad_input(format!(
            "{}: --surface {} is out of range (the file holds {} surfaces)",
            args.surface_file.display(),
            args.surface,
            surfaces.len()
        )));
    }
    let spec: CircularLights = read_json(&args.lights)?;
    let lights: Vec<CircularLight> = spec
        .lights()
        .map_err(|e| bad_input(format!("{}: {e}", args.lights.display())))?;
    let ends: Endpoints = read_json(&args.endpoints)?;
    let opts = SurfaceFairOptions::default()
        .lights(lights.clone())
        .endpoints(ends.endpoints.clone())
        .grid(args.grid)
        .sample_spacing(args.sample_spacing)
        .truncation(args.truncation)
        // a larger floor is taken as --truncation; NaN is left for the
        // library's option check to refuse (f64::min would hide it)
        .min_truncation(if args.min_truncation > args.truncation {
            args.truncation
        } else {
            args.min_truncation
        })
        .epsilon(args.epsilon)
        .max_iterations(args.max_iterations)
        .method(match args.method {
            MethodArg::Regularised => SurfaceFairMethod::Regularised,
            MethodArg::Paper => SurfaceFairMethod::Paper,
        })
        .boundary(match args.boundary {
            BoundaryArg::Fixed => BoundaryControl::Fixed,
            BoundaryArg::Tangent => BoundaryControl::FixedWithTangents,
            BoundaryArg::Free => BoundaryControl::Free,
        })
        .keep_weight(args.keep_weight)
        .fairness_weight(args.fairness_weight);
    let input = surfaces[args.surface].clone();
    let mut report = Report::new("fair-surface");
    let bar = crate::output::spinner("fairing");
    let out = report
        .time(|| fair_surface(&input, &opts))
        .map_err(to_cli)?;
    bar.finish_and_clear();
    let (faired, rep) = (out.surfaces, out.report);
    // Endpoints that snapped far from where they were given (more than 2 %
    // of the parameter domain's diagonal) were probably read off the wrong
    // line.
    let (du, dv) = (input.domain_u(), input.domain_v());
    let diag = (du[1] - du[0]).hypot(dv[1] - dv[0]);
    for t in &rep.targets {
        for (k, d) in t.snap_distance.iter().enumerate() {
            if *d > 0.02 * diag {
                let given = ends.endpoints[t.index];
                let p = if k == 0 { given.start } else { given.end };
                let q = if k == 0 { t.start } else { t.end };
                eprintln!(
                    "warning: {}: endpoint {} {}: ({:.4}, {:.4}) is {:.4} away from the nearest line of radius {} and was moved to ({:.4}, {:.4})",
                    args.endpoints.display(),
                    t.index,
                    if k == 0 { "start" } else { "end" },
                    p[0],
                    p[1],
                    d,
                    t.radius,
                    q[0],
                    q[1]
                );
            }
        }
    }
    eprintln!(
        "fair-surface: {} stretches, {} control points moved, {} held on the patch boundary ({}); {} iterations, {} ({:?}); mean |d_s| {:.3e} -> {:.3e}",
        rep.targets.len(),
        rep.modified_control_points,
        rep.held_boundary_points.len(),
        match opts.boundary {
            BoundaryControl::Free => "boundary free",
            BoundaryControl::Fixed => "boundary rows fixed: seams stay closed",
            BoundaryControl::FixedWithTangents => "two boundary rows fixed: seams keep G1",
        },
        rep.iterations,
        if rep.converged {
            "converged"
        } else {
            "NOT converged"
        },
        rep.stop,
        rep.residual_before.mean,
        rep.residual_after.mean
    );
    // The library's report carries the command's keys.
    if let serde_json::Value::Object(fields) = serde_json::to_value(&rep)? {
        for (key, value) in fields {
            report.set(&key, value);
        }
    }
    // Pictures before the output file, so a failure leaves no output.
    let slights: Vec<SurfaceLight> = lights.iter().map(|l| SurfaceLight::Circular(*l)).collect();
    let hopts = SurfaceHighlightOptions::default().grid(args.grid);
    if args.png.is_some() || args.svg.is_some() {
        let before = surface_highlight_lines(&input, &slights, &hopts);
        let after = surface_highlight_lines(&faired, &slights, &hopts);
        if let Some(p) = &args.png {
            let opts = RenderOptions::with_size(900, 700);
            let pic = |s: &BSplineSurface, h: &fairline::highlight::SurfaceHighlights, t: &str| {
                surface_picture(
                    std::slice::from_ref(s),
                    polylines(&h.lines.iter().collect::<Vec<_>>(), 2.0),
                    t,
                    &opts,
                )
            };
            let img = side_by_side(
                &[
                    pic(&input, &before, "input")?,
                    pic(&faired, &after, "faired")?,
                ],
                &["before", "after"],
            );
            img.write_png(p)?;
        }
        if let Some(p) = &args.svg {
            let mut plot = uv_plot(
                &input,
                "pre-images: before (grey), after (colour), targets (black)",
            );
            for l in &before.lines {
                let mut uv = l.uv.clone();
                if l.closed && !uv.is_empty() {
                    uv.push(uv[0]);
                }
                plot.polyline(&uv, [170, 170, 170], 2.5);
            }
            plot_lines(&mut plot, &after.lines.iter().collect::<Vec<_>>(), 1.2);
            for t in &rep.targets {
                plot.polyline(&t.samples, [0, 0, 0], 0.8);
                plot.marker(t.start, palette_srgb(t.light), "");
                plot.marker(t.end, palette_srgb(t.light), "");
            }
            let kb = rep.knot_box;
            plot.polyline(
                &[
                    [kb[0], kb[2]],
                    [kb[1], kb[2]],
                    [kb[1], kb[3]],
                    [kb[0], kb[3]],
                    [kb[0], kb[2]],
                ],
                [220, 120, 0],
                1.0,
            );
            plot.write(p)?;
        }
    }
    surfaces[args.surface] = faired;
    fairline::io::surface_file::write_surface_file(&args.output, &surfaces, unit.as_ref())?;
    if !rep.converged {
        report.warn(format!(
            "fairing did not converge ({:?} after {} iteration(s)); try --max-iterations or other endpoints",
            rep.stop,
            rep.iterations
        ));
    }
    if rep.residual_after.max > rep.residual_before.max {
        report.warn(format!(
            "the largest highlight residual got worse: {:.4e} before, {:.4e} after",
            rep.residual_before.max, rep.residual_after.max
        ));
    }
    report.write(args.report.as_deref())?;
    job.finish(format_args!(
        "{} iteration(s), {}, {} control point(s) moved, largest residual {:.3e} → {:.3e}",
        rep.iterations,
        if rep.converged {
            "converged"
        } else {
            "not converged"
        },
        rep.modified_control_points,
        rep.residual_before.max,
        rep.residual_after.max
    ));
    Ok(())
}
