//! `fairline fair-surface`: circular-highlight fairing of a B-spline surface
//! (Nishiyama et al. §3).

use crate::common::{print_warnings, read_json, write_report};
use crate::error::bad_input;
use crate::surface_highlight::{
    palette_srgb, plot_lines, polylines, surface_picture, surface_zebra, uv_plot,
};
use anyhow::Result;
use fairline::Control;
use fairline::bspline::BSplineSurface;
use fairline::fair::{
    BoundaryControl, EndpointPair, PaperDamping, SurfaceFairMethod, SurfaceFairOptions,
    SurfaceFairReport,
};
use fairline::highlight::{
    CircularLight, CircularLights, SurfaceHighlightOptions, SurfaceHighlights, SurfaceLight,
    surface_highlight_lines,
};
use fairline::render::{ReflectionZebra, RenderOptions, SvgPlot, side_by_side};
use fairline_commands::fair_surface::{self, FairSurfaceInput, FairSurfaceSettings};
use fairline_commands::{CommandError, Subject};
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
/// LIGHTS.json: {"center":[x,y,z],"axis":[x,y,z],"radii":[r1,...]}; without
/// --lights, the circular lights of `fairline highlight FILE --circular`
/// (derived from all surfaces of the file) are used and printed.
///
/// The stretches to fair are given in one of two ways (both may be mixed):
///
/// - by (u, v) read off a picture, ENDPOINTS.json
///   {"endpoints":[{"radius":r,"start":[u,v],"end":[u,v]},...]}: each point
///   is snapped to the nearest point of that radius' pre-image; a point that
///   lies more than 2 % of the parameter domain's diagonal from it gets a
///   warning (it was probably read off another line);
/// - by line id and a parameter along the line: `--lines LINES.json` (the
///   output of `fairline highlight` on the same file and lights; its SVG
///   writes each line's id as #ID) with `--from ID:T --to ID:T` (repeat the
///   pair for more stretches), or the entry {"line":ID,"from":T,"to":T} in
///   ENDPOINTS.json. T is the fraction of the line's length from its first
///   point (0 = first point, 1 = last point, or back at the first one for a
///   closed line).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline fair-surface fairline-demo/bspline-panel-dented.json --lights fairline-demo/bspline-panel-lights.json --endpoints fairline-demo/bspline-panel-endpoints.json -o panel-faired.json --report fair.json --png fair.png --svg uv.svg\n  fairline highlight fairline-demo/bspline-panel-dented.json --lights fairline-demo/bspline-panel-lights.json -o panel-lines.json --svg panel-lines.svg\n  fairline fair-surface fairline-demo/bspline-panel-dented.json --lights fairline-demo/bspline-panel-lights.json --lines panel-lines.json --from 5:0.35 --to 5:0.65 -o panel-faired.json"
)]
pub struct Args {
    /// Input surface (.json, .igs/.iges, .step/.stp or .g2).
    pub surface_file: PathBuf,
    /// Circular lights JSON (default: derived from the part and printed).
    #[arg(long, value_name = "LIGHTS.json")]
    pub lights: Option<PathBuf>,
    /// Endpoints JSON: (u, v) pairs per radius, or line id + parameters.
    #[arg(long, value_name = "ENDPOINTS.json", required_unless_present = "from")]
    pub endpoints: Option<PathBuf>,
    /// Highlight lines JSON (`fairline highlight -o`) whose line ids --from,
    /// --to and {"line":ID,...} endpoints name.
    #[arg(long, value_name = "LINES.json")]
    pub lines: Option<PathBuf>,
    /// Start of a stretch: line id (the "id" in LINES.json, #ID in its SVG)
    /// and the fraction T (0..1) of the line's length from its first point.
    #[arg(long, value_name = "ID:T", value_parser = parse_line_point, requires_all = ["to", "lines"])]
    pub from: Vec<LinePoint>,
    /// End of the stretch (same line as the --from of the same position).
    #[arg(long, value_name = "ID:T", value_parser = parse_line_point, requires = "from")]
    pub to: Vec<LinePoint>,
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
    /// Step factor μ of the damped step R + μΔr, Nishiyama et al.
    /// Eq. (3.13) (paper; the paper's 0.1 by default, 1 turns the damping
    /// off).
    #[arg(long, default_value_t = SurfaceFairOptions::default().damped_step, value_name = "MU")]
    pub damped_step: f64,
    /// When the paper's solver damps a step (paper): `residual` when the
    /// full step raises Σ d_s², the sum of squares the least-squares step
    /// minimises (default); `max-mean` when it raises the largest or the
    /// mean |d_s| (Eq. (3.12) as printed: near the least-squares floor it
    /// damps nearly every step and the iteration creeps); `off` never
    /// (Eq. (3.11)).
    #[arg(long, value_enum, default_value = "residual")]
    pub damping: DampingArg,
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
    #[command(flatten)]
    pub zebra: crate::args::ZebraArgs,
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

/// `--damping`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum DampingArg {
    Residual,
    MaxMean,
    Off,
}

/// `--boundary`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum BoundaryArg {
    Fixed,
    Tangent,
    Free,
}

/// A point named by a line id and the fraction of the line's length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinePoint {
    /// The line's "id" in LINES.json.
    pub line: usize,
    /// Fraction 0..1 of the line's length from its first point.
    pub t: f64,
}

fn parse_line_point(s: &str) -> Result<LinePoint, String> {
    let (a, b) = s.split_once(':').ok_or_else(|| {
        format!("expected ID:T (a line id and a fraction 0..1 of its length), got {s:?}")
    })?;
    let line = a
        .trim()
        .parse::<usize>()
        .map_err(|_| format!("the line id {a:?} is not a non-negative integer"))?;
    let t = b
        .trim()
        .parse::<f64>()
        .map_err(|_| format!("the parameter {b:?} is not a number"))?;
    if !(0.0..=1.0).contains(&t) {
        return Err(format!(
            "the parameter must lie in 0..1 (a fraction of the line's length), got {t}"
        ));
    }
    Ok(LinePoint { line, t })
}

/// One entry of ENDPOINTS.json: (u, v) endpoints of DESIGN.md §5, or a line
/// id with the parameters of both ends.
#[derive(serde::Deserialize)]
#[serde(untagged)]
enum EndpointSpec {
    Uv(EndpointPair),
    Line(LineStretch),
}

/// `{"line":ID,"from":T,"to":T}`.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct LineStretch {
    line: usize,
    from: f64,
    to: f64,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct EndpointsFile {
    endpoints: Vec<EndpointSpec>,
}

/// The (u, v) at fraction `t` of the length (in space) of line `id` of a
/// highlight lines document, and the line's radius. Input errors name the
/// file and the line.
fn point_on_line(
    doc: &serde_json::Value,
    path: &std::path::Path,
    surface: usize,
    id: usize,
    t: f64,
) -> Result<(f64, [f64; 2])> {
    let here = || format!("{}: line #{id}", path.display());
    if !(0.0..=1.0).contains(&t) {
        return Err(bad_input(format!(
            "{}: the parameter must lie in 0..1, got {t}",
            here()
        )));
    }
    let lines = doc
        .get("lines")
        .and_then(|l| l.as_array())
        .ok_or_else(|| bad_input(format!("{}: no \"lines\" list", path.display())))?;
    let line = lines
        .iter()
        .find(|l| l.get("id").and_then(|x| x.as_u64()) == Some(id as u64))
        .ok_or_else(|| {
            bad_input(format!(
                "{}: no line has id {id} (the file holds {} lines)",
                path.display(),
                lines.len()
            ))
        })?;
    if let Some(s) = line.get("surface").and_then(|x| x.as_u64())
        && s != surface as u64
    {
        return Err(bad_input(format!(
            "{} lies on surface {s}; give --surface {s}",
            here()
        )));
    }
    let radius = line.get("radius").and_then(|x| x.as_f64()).ok_or_else(|| {
        bad_input(format!(
            "{} has no radius: fair-surface fairs circular highlight lines",
            here()
        ))
    })?;
    let pairs = |key: &str| -> Option<Vec<Vec<f64>>> {
        serde_json::from_value(line.get(key)?.clone()).ok()
    };
    let (Some(uv), Some(points)) = (pairs("uv"), pairs("points")) else {
        return Err(bad_input(format!("{} needs \"uv\" and \"points\"", here())));
    };
    let ok = uv.len() == points.len()
        && !uv.is_empty()
        && uv
            .iter()
            .all(|p| p.len() == 2 && p.iter().all(|x| x.is_finite()))
        && points
            .iter()
            .all(|p| p.len() == 3 && p.iter().all(|x| x.is_finite()));
    if !ok {
        return Err(bad_input(format!(
            "{}: \"uv\" and \"points\" must be equally long lists of finite [u,v] and [x,y,z]",
            here()
        )));
    }
    let closed = line.get("closed").and_then(|x| x.as_bool()) == Some(true);
    let n = points.len();
    let segments = if closed { n } else { n - 1 };
    let p3 = |k: usize| fairline::Vec3::new(points[k][0], points[k][1], points[k][2]);
    let lengths: Vec<f64> = (0..segments)
        .map(|k| (p3((k + 1) % n) - p3(k)).length())
        .collect();
    let total: f64 = lengths.iter().sum();
    let first = [uv[0][0], uv[0][1]];
    if total.is_nan() || total <= 0.0 {
        return Ok((radius, first));
    }
    let mut left = t * total;
    for (k, &len) in lengths.iter().enumerate() {
        if left <= len || k + 1 == segments {
            let f = if len > 0.0 {
                (left / len).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (a, b) = (&uv[k], &uv[(k + 1) % n]);
            return Ok((radius, [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]));
        }
        left -= len;
    }
    Ok((radius, first))
}

/// The endpoint pairs of the run: those of ENDPOINTS.json (line entries
/// resolved on LINES.json) followed by the --from/--to pairs.
fn endpoint_pairs(args: &Args) -> Result<Vec<EndpointPair>> {
    let lines_doc: Option<serde_json::Value> = match &args.lines {
        Some(p) => Some(read_json(p)?),
        None => None,
    };
    let on_line = |id: usize, t: f64| -> Result<(f64, [f64; 2])> {
        match (&lines_doc, &args.lines) {
            (Some(doc), Some(path)) => point_on_line(doc, path, args.surface, id, t),
            _ => Err(bad_input(
                "endpoints given by line id need --lines LINES.json (the output of `fairline highlight`)",
            )),
        }
    };
    let stretch = |id: usize, from: f64, to: f64| -> Result<EndpointPair> {
        let (radius, start) = on_line(id, from)?;
        let (_, end) = on_line(id, to)?;
        Ok(EndpointPair { radius, start, end })
    };
    let mut pairs = Vec::new();
    if let Some(path) = &args.endpoints {
        let file: EndpointsFile = read_json(path).map_err(|e| {
            bad_input(format!(
                "{e:#} (each endpoint is {{\"radius\":r,\"start\":[u,v],\"end\":[u,v]}} or {{\"line\":ID,\"from\":T,\"to\":T}})"
            ))
        })?;
        for e in file.endpoints {
            pairs.push(match e {
                EndpointSpec::Uv(p) => p,
                EndpointSpec::Line(l) => stretch(l.line, l.from, l.to)?,
            });
        }
    }
    if args.from.len() != args.to.len() {
        return Err(bad_input(format!(
            "--from and --to come in pairs: {} --from, {} --to",
            args.from.len(),
            args.to.len()
        )));
    }
    for (a, b) in args.from.iter().zip(&args.to) {
        if a.line != b.line {
            return Err(bad_input(format!(
                "--from {}:{} and --to {}:{} name different lines; a stretch lies on one line",
                a.line, a.t, b.line, b.t
            )));
        }
        pairs.push(stretch(a.line, a.t, b.t)?);
    }
    if pairs.is_empty() {
        return Err(bad_input(
            "no stretch to fair: give --endpoints ENDPOINTS.json or --from ID:T --to ID:T",
        ));
    }
    Ok(pairs)
}

/// The file the endpoints come from: --endpoints, or --lines with
/// --from/--to.
fn endpoints_file(args: &Args) -> String {
    args.endpoints
        .as_deref()
        .or(args.lines.as_deref())
        .map_or("the endpoints".to_string(), |p| p.display().to_string())
}

impl Args {
    /// The command layer's settings of these arguments.
    fn settings(&self) -> FairSurfaceSettings {
        FairSurfaceSettings {
            surface: self.surface,
            max_iterations: self.max_iterations,
            epsilon: self.epsilon,
            truncation: self.truncation,
            min_truncation: self.min_truncation,
            damped_step: self.damped_step,
            damping: match self.damping {
                DampingArg::Residual => PaperDamping::Residual,
                DampingArg::MaxMean => PaperDamping::MaxMean,
                DampingArg::Off => PaperDamping::Off,
            },
            sample_spacing: self.sample_spacing,
            grid: self.grid,
            method: match self.method {
                MethodArg::Regularised => SurfaceFairMethod::Regularised,
                MethodArg::Paper => SurfaceFairMethod::Paper,
            },
            boundary: match self.boundary {
                BoundaryArg::Fixed => BoundaryControl::Fixed,
                BoundaryArg::Tangent => BoundaryControl::FixedWithTangents,
                BoundaryArg::Free => BoundaryControl::Free,
            },
            keep_weight: self.keep_weight,
            fairness_weight: self.fairness_weight,
        }
    }

    /// A failure of the command layer with the file it is about named: the
    /// surface file or the lights file.
    fn name_subject(&self, e: CommandError) -> anyhow::Error {
        if e.subject() == Some(Subject::Endpoints) {
            // an endpoint's light is in the endpoints (or lines) file and
            // the lights file, drawn on the surface file
            let lights = self
                .lights
                .as_deref()
                .map_or("the lights derived from the part".to_string(), |p| {
                    format!("the lights of {}", p.display())
                });
            return anyhow::Error::new(e).context(format!(
                "{} ({lights} on {})",
                endpoints_file(self),
                self.surface_file.display()
            ));
        }
        let path = match e.subject() {
            Some(Subject::Input) => Some(self.surface_file.as_path()),
            Some(Subject::Lights) => self.lights.as_deref(),
            _ => None,
        };
        match path {
            Some(p) => anyhow::Error::new(e).context(p.display().to_string()),
            None => anyhow::Error::new(e),
        }
    }
}

pub fn run(args: Args) -> Result<()> {
    let job = output_job(&args)?;
    let input = crate::surface::load_surface_file(&args.surface_file)?;
    let unit = input.unit;
    let surfaces = input.surfaces;
    let settings = args.settings();
    fair_surface::check_surface(settings.surface, surfaces.len())
        .map_err(|e| args.name_subject(e))?;
    let given: Option<CircularLights> = match &args.lights {
        Some(path) => Some(read_json(path)?),
        None => None,
    };
    let endpoints = endpoint_pairs(&args)?;
    let bar = crate::output::spinner("fairing");
    let out = fair_surface::run(
        FairSurfaceInput {
            surfaces: &surfaces,
            lights: given.as_ref(),
            endpoints: &endpoints,
        },
        &settings,
        &Control::new(),
    );
    bar.finish_and_clear();
    let mut out = out.map_err(|e| args.name_subject(e))?;
    if let Some(spec) = &out.derived {
        eprintln!(
            "default circular lights (save as LIGHTS.json to reuse): {}",
            serde_json::to_string(spec)?
        );
    }
    let rep = &out.result;
    print_summary(rep, settings.boundary);
    // Pictures before the output file, so a failure leaves no output.
    let faired = &out.surfaces[settings.surface];
    let zebra = write_pictures(&args, &surfaces[settings.surface], faired, &out.lights, rep)?;
    if let Some(z) = &zebra {
        out.report.set("zebra", crate::args::zebra_json(z));
    }
    fairline::io::surface_file::write_surface_file(&args.output, &out.surfaces, unit.as_ref())?;
    print_warnings(&out.report);
    write_report(args.report.as_deref(), &out.report)?;
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
    ))?;
    if out.paper_unconverged() {
        // the paper's method promises the targets: written for inspection,
        // but not what was asked for (the warning above says why)
        anyhow::bail!(
            "{}: the paper's method did not converge ({:?}); {} was written for inspection only",
            args.surface_file.display(),
            rep.stop,
            args.output.display()
        );
    }
    Ok(())
}

/// The output checks of the command (file kinds by extension, nothing
/// written over an input) and its job.
fn output_job(args: &Args) -> Result<crate::output::Job> {
    if !crate::surface::is_writable_surface_path(&args.output) {
        return Err(bad_input(format!(
            "{}: -o must name a surface file fairline writes (.json, .igs/.iges or .step/.stp)",
            args.output.display()
        )));
    }
    if let Some(p) = &args.png {
        crate::output::require_extension("--png", p, &["png"])?;
    }
    if let Some(p) = &args.svg {
        crate::output::require_extension("--svg", p, &["svg"])?;
    }
    crate::output::Job::new("fair-surface")
        .input(&args.surface_file)
        .input_opt(args.lights.as_deref())
        .input_opt(args.endpoints.as_deref())
        .input_opt(args.lines.as_deref())
        .output("-o", &args.output)
        .output_opt("--png", args.png.as_deref())
        .output_opt("--svg", args.svg.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()
}

/// The terminal line saying what was moved, what was held and how the
/// iteration ended.
fn print_summary(rep: &SurfaceFairReport, boundary: BoundaryControl) {
    eprintln!(
        "fair-surface: {} stretches, {} control points moved, {} held on the patch boundary ({}); {} iterations, {} ({:?}); mean |d_s| {:.3e} -> {:.3e}",
        rep.targets.len(),
        rep.modified_control_points,
        rep.held_boundary_points.len(),
        match boundary {
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
}

/// The --png (highlight lines before | after; with --zebra on the
/// reflection zebra of the input's panel, which is returned) and --svg
/// (pre-images before and after, targets, endpoints and the knot box)
/// pictures.
fn write_pictures(
    args: &Args,
    input: &BSplineSurface,
    faired: &BSplineSurface,
    lights: &[CircularLight],
    rep: &SurfaceFairReport,
) -> Result<Option<ReflectionZebra>> {
    if args.png.is_none() && args.svg.is_none() {
        return Ok(None);
    }
    let slights: Vec<SurfaceLight> = lights.iter().map(|l| SurfaceLight::Circular(*l)).collect();
    let hopts = SurfaceHighlightOptions::default().grid(args.grid);
    let before = surface_highlight_lines(input, &slights, &hopts);
    let after = surface_highlight_lines(faired, &slights, &hopts);
    let mut zebra = None;
    if let Some(p) = &args.png {
        let img;
        (img, zebra) = before_after_png(input, faired, &before, &after, &args.zebra)?;
        img.write_png(p)?;
    }
    if let Some(p) = &args.svg {
        before_after_svg(input, &before, &after, rep).write(p)?;
    }
    Ok(zebra)
}

/// The shaded surfaces with their highlight lines, before | after; with
/// --zebra both on the reflection zebra of the input's panel (the part's
/// default linear lights), which is returned.
fn before_after_png(
    input: &BSplineSurface,
    faired: &BSplineSurface,
    before: &SurfaceHighlights,
    after: &SurfaceHighlights,
    zebra: &crate::args::ZebraArgs,
) -> Result<(fairline::render::Image, Option<ReflectionZebra>)> {
    let mut opts = RenderOptions::with_size(900, 700);
    (opts.view_dir, opts.up) = crate::surface::camera(std::slice::from_ref(input), None)?;
    let zebra = surface_zebra(std::slice::from_ref(input), zebra, None, &opts)?;
    let pic = |s: &BSplineSurface, h: &SurfaceHighlights, t: &str| {
        surface_picture(
            std::slice::from_ref(s),
            polylines(&h.lines.iter().collect::<Vec<_>>(), 2.0),
            t,
            zebra,
            &opts,
        )
    };
    let img = side_by_side(
        &[pic(input, before, "input")?, pic(faired, after, "faired")?],
        &["before", "after"],
    );
    Ok((img, zebra))
}

/// The pre-images before (grey) and after (colour), the targets (black),
/// the endpoints and the knot-span box of the moved control points.
fn before_after_svg(
    input: &BSplineSurface,
    before: &SurfaceHighlights,
    after: &SurfaceHighlights,
    rep: &SurfaceFairReport,
) -> SvgPlot {
    let mut plot = uv_plot(
        input,
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
    plot
}
