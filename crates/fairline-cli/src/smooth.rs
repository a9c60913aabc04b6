//! `fairline smooth` (the classic smoothing family, Grüner thesis ch. 3) and
//! `fairline fair-quad` (structure-line fairing of quad meshes, ch. 4).

use crate::common::Report;
use crate::error::bad_input;
use crate::output::spinner;
use anyhow::Result;
use fairline::fair::{QuadFairOptions, fair_structure_lines};
use fairline::geom::LaplaceWeights;
use fairline::mesh::{SurfaceMesh, VertexId};
use fairline::picture::{Picture, mesh_picture};
use fairline::render::{RenderOptions, side_by_side};
use fairline::smooth::{SmoothError, SmoothMethod, SmoothOptions, smooth, smooth_warnings};
use std::path::{Path, PathBuf};

/// Smoothing method.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Laplace smoothing x' = x + λΔx (Grüner §3.2.2).
    Laplace,
    /// Taubin λ|μ: a λ step then a μ step per iteration (§3.2.3).
    Taubin,
    /// Backward Euler (M − tL)x' = Mx, cotangent L (Desbrun et al.); triangles.
    Implicit,
    /// Spring model of Yamada et al. (§3.3); boundary fixed.
    Spring,
    /// Δ_B H = 0 with G¹ boundary (Schneider and Kobbelt, §3.4); triangles.
    SchneiderKobbelt,
}

impl From<Method> for SmoothMethod {
    fn from(m: Method) -> SmoothMethod {
        match m {
            Method::Laplace => SmoothMethod::Laplace,
            Method::Taubin => SmoothMethod::Taubin,
            Method::Implicit => SmoothMethod::Implicit,
            Method::Spring => SmoothMethod::Spring,
            Method::SchneiderKobbelt => SmoothMethod::SchneiderKobbelt,
        }
    }
}

/// Laplacian edge weights.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weights {
    /// w = 1 (umbrella).
    Uniform,
    /// w = |e|^exponent (exponent −1 by default, Fujiwara).
    Edge,
    /// Cotangent weights (Desbrun); triangle meshes.
    Cotan,
}

/// Smooths a mesh with one of the classic methods, all sharing the
/// constraints of Grüner §3.2.4: fixed vertices, fixed boundary,
/// hierarchical boundary (boundary faired as curves first), volume
/// preservation (closed meshes) and tangential-only motion.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline smooth fairline-demo/wavy.obj --method taubin --iterations 10 --pass-band 0.1 -o smooth.obj\n  fairline smooth fairline-demo/sphere.ply --method implicit --time-step 2 --preserve-volume -o out.ply --report r.json\n  fairline smooth fairline-demo/quad-saddle.obj --method laplace --weights edge --fix-boundary -o out.obj --png cmp.png"
)]
pub struct Args {
    /// Input mesh (.obj .ply .off .stl).
    pub mesh: PathBuf,
    /// Output mesh.
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// Method.
    #[arg(long, value_enum, default_value = "taubin")]
    pub method: Method,
    /// Laplacian weights (laplace, taubin).
    #[arg(long, value_enum, default_value = "uniform")]
    pub weights: Weights,
    /// Exponent of the edge-length weights.
    #[arg(long, default_value_t = -1.0, allow_hyphen_values = true)]
    pub exponent: f64,
    /// Iterations (laplace, taubin: steps / λ|μ pairs; implicit: time steps;
    /// spring, schneider-kobbelt: the most sweeps). Default 10, 1 for
    /// implicit, 200 for spring (which stops earlier, once its sweeps stop
    /// shrinking by 20 % each: the noise is gone), 50 for schneider-kobbelt.
    #[arg(long)]
    pub iterations: Option<usize>,
    /// λ (laplace: default 0.5; taubin: default from the pass band).
    #[arg(long)]
    pub lambda: Option<f64>,
    /// μ < −λ (taubin; default from the pass band).
    #[arg(long, allow_hyphen_values = true)]
    pub mu: Option<f64>,
    /// Taubin pass band k_PB, 1/λ + 1/μ = k_PB.
    #[arg(long, default_value_t = 0.1)]
    pub pass_band: f64,
    /// Implicit time step in units of the squared mean edge length.
    #[arg(long, default_value_t = 1.0)]
    pub time_step: f64,
    /// Convergence threshold (spring, schneider-kobbelt).
    #[arg(long)]
    pub epsilon: Option<f64>,
    /// Keep every boundary vertex fixed.
    #[arg(long)]
    pub fix_boundary: bool,
    /// Smooth the boundary as curves first (hierarchical labels).
    #[arg(long)]
    pub hierarchical_boundary: bool,
    /// JSON file `{"vertices":[...]}` of vertices that never move.
    #[arg(long, value_name = "FILE.json")]
    pub fixed: Option<PathBuf>,
    /// Rescale so the enclosed volume stays that of the input (closed meshes).
    #[arg(long)]
    pub preserve_volume: bool,
    /// Move vertices only in their tangent planes.
    #[arg(long)]
    pub tangential: bool,
    /// Write a before/after picture.
    #[arg(long, value_name = "IMG.png")]
    pub png: Option<PathBuf>,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

/// Reads the fixed-vertices file `{"vertices":[...]}` (the one reader,
/// [`fairline::io::read_fixed_vertices`]); errors name the file and exit 2.
pub fn read_fixed(path: &Path, count: usize) -> Result<Vec<VertexId>> {
    fairline::io::read_fixed_vertices(path, count).map_err(|e| bad_input(e.to_string()))
}

fn finite(name: &str, v: Option<f64>) -> Result<()> {
    match v {
        Some(x) if !x.is_finite() => Err(bad_input(format!("--{name} must be finite"))),
        _ => Ok(()),
    }
}

/// A library error caused by the options or the mesh is bad input (exit 2);
/// a failed solve or a diverged result is a computation failure (exit 1).
fn smooth_error(e: SmoothError) -> anyhow::Error {
    match e {
        SmoothError::Solve(_) | SmoothError::Diverged(_) => anyhow::Error::new(e),
        other => bad_input(other.to_string()),
    }
}

/// Two meshes side by side under one camera framing the input.
pub fn before_after(
    before: &SurfaceMesh,
    after: &SurfaceMesh,
    labels: [&str; 2],
    wireframe: bool,
    path: &Path,
) -> Result<()> {
    let opts = RenderOptions::with_size(700, 560);
    let pic = Picture {
        wireframe,
        ..Default::default()
    };
    let a = mesh_picture(before, &pic, &opts)?;
    let b = mesh_picture(after, &pic, &opts)?;
    side_by_side(&[a, b], &labels).write_png(path)?;
    Ok(())
}

pub fn run(args: Args) -> Result<()> {
    let job = crate::output::Job::new("smooth")
        .input(&args.mesh)
        .input_opt(args.fixed.as_deref())
        .output("-o", &args.output)
        .output_opt("--png", args.png.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    for (n, v) in [
        ("lambda", args.lambda),
        ("mu", args.mu),
        ("pass-band", Some(args.pass_band)),
        ("time-step", Some(args.time_step)),
        ("epsilon", args.epsilon),
        ("exponent", Some(args.exponent)),
    ] {
        finite(n, v)?;
    }
    if args.iterations == Some(0) {
        return Err(bad_input("--iterations must be at least 1"));
    }
    let mut mesh = fairline::io::read_mesh(&args.mesh)?;
    crate::input::note_split_vertices(&args.mesh, &mesh);
    let fixed = match &args.fixed {
        Some(p) => read_fixed(p, mesh.vertex_count())?,
        None => Vec::new(),
    };
    let weights = match args.weights {
        Weights::Uniform => LaplaceWeights::Uniform,
        Weights::Edge => LaplaceWeights::EdgeLength {
            exponent: args.exponent,
        },
        Weights::Cotan => LaplaceWeights::Cotangent,
    };
    let options = SmoothOptions::default()
        .method(args.method.into())
        .weights(weights)
        .lambda(args.lambda)
        .mu(args.mu)
        .pass_band(args.pass_band)
        .time_step(args.time_step)
        .epsilon(args.epsilon)
        .iterations(args.iterations)
        .fixed(fixed)
        .fix_boundary(args.fix_boundary)
        .hierarchical_boundary(args.hierarchical_boundary)
        .preserve_volume(args.preserve_volume)
        .tangential_only(args.tangential);
    let mut report = Report::new("smooth");
    let bar = spinner("smoothing");
    let result = report.time(|| smooth(&mesh, &options));
    bar.finish_and_clear();
    let out = result.map_err(smooth_error)?;
    let r = &out.report;
    let name = options.method.name();
    report.set("method", name);
    report.set("vertices", mesh.vertex_count());
    report.set_fields(r);
    let warnings = smooth_warnings(&mesh, &options, r);
    // the input is kept only for the before/after picture
    let input = args.png.is_some().then(|| mesh.clone());
    mesh.set_positions(out.positions)?;
    fairline::io::write_mesh(&args.output, &mesh)?;
    if let (Some(png), Some(input)) = (&args.png, &input) {
        before_after(input, &mesh, ["input", name], false, png)?;
    }
    for w in warnings {
        report.warn(w);
    }
    report.write(args.report.as_deref())?;
    job.finish(format_args!(
        "{name}, {} iteration(s){} on {} vertices, largest move {:.3e}",
        r.iterations,
        if r.converged { "" } else { ", not converged" },
        mesh.vertex_count(),
        r.max_displacement
    ));
    Ok(())
}

/// Structure-line fairing of a quad mesh (Grüner thesis ch. 4, Eq. (30)–(34)):
/// zigzagging structure lines are straightened by a sparse least-squares
/// fit of the linearised direction residual of every run of four points,
/// with a penalty ω‖p − p⁰‖² that keeps the shape. Corners never move.
/// The points slide along a smooth fit of the input surface, so the surface
/// keeps its shape (`--off-surface`: the thesis' method as printed).
/// The weight is scale-invariant: ω is divided by the squared mean edge
/// length, so the same value behaves the same on a mesh of any size.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline fair-quad fairline-demo/quad-saddle.obj -o faired.obj\n  fairline fair-quad fairline-demo/quad-saddle.obj --weight 0.005 --deviation 0.05 --deviation-factor 0.5 --iterations 4 --fix-boundary -o faired.obj --png cmp.png --report r.json"
)]
pub struct QuadArgs {
    /// Input quad mesh (.obj .ply .off).
    pub mesh: PathBuf,
    /// Output mesh.
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// Penalty weight ω (scale-invariant, see above).
    #[arg(long, default_value_t = 0.01)]
    pub weight: f64,
    /// Deviation parameter: runs whose Eq. (30) deviation exceeds it free
    /// their two middle points.
    #[arg(long, default_value_t = 0.1)]
    pub deviation: f64,
    /// Factor applied to the deviation after every iteration (the thesis
    /// halves it; 0.1 leaves less of a wave in three iterations).
    #[arg(long, default_value_t = 0.1)]
    pub deviation_factor: f64,
    /// Iterations.
    #[arg(long, default_value_t = 3)]
    pub iterations: usize,
    /// Keep every boundary vertex fixed (corners are always fixed).
    #[arg(long)]
    pub fix_boundary: bool,
    /// Let the points leave the input surface (the thesis' Eq. (34) as
    /// printed). By default they slide along a smooth fit of the input
    /// surface, so straightening the lines does not deform the surface.
    #[arg(long)]
    pub off_surface: bool,
    /// JSON file `{"vertices":[...]}` of vertices that never move.
    #[arg(long, value_name = "FILE.json")]
    pub fixed: Option<PathBuf>,
    /// Write a before/after picture with the structure lines.
    #[arg(long, value_name = "IMG.png")]
    pub png: Option<PathBuf>,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

pub fn run_quad(args: QuadArgs) -> Result<()> {
    let job = crate::output::Job::new("fair-quad")
        .input(&args.mesh)
        .input_opt(args.fixed.as_deref())
        .output("-o", &args.output)
        .output_opt("--png", args.png.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    if !args.weight.is_finite() || args.weight <= 0.0 {
        return Err(bad_input("--weight must be a positive number"));
    }
    if !args.deviation.is_finite() || args.deviation < 0.0 {
        return Err(bad_input("--deviation must be ≥ 0"));
    }
    if !args.deviation_factor.is_finite() || args.deviation_factor <= 0.0 {
        return Err(bad_input("--deviation-factor must be positive"));
    }
    let mut mesh = fairline::io::read_mesh(&args.mesh)?;
    crate::input::note_split_vertices(&args.mesh, &mesh);
    if !mesh.faces().any(|f| mesh.face_size(f) == 4) {
        return Err(bad_input(format!(
            "{}: fair-quad needs a quad mesh (no quadrilateral found)",
            args.mesh.display()
        )));
    }
    let fixed = match &args.fixed {
        Some(p) => read_fixed(p, mesh.vertex_count())?,
        None => Vec::new(),
    };
    let input = mesh.clone();
    let opts = QuadFairOptions::default()
        .weight(args.weight)
        .deviation(args.deviation)
        .deviation_factor(args.deviation_factor)
        .iterations(args.iterations)
        .fix_boundary(args.fix_boundary)
        .fixed(fixed)
        .on_surface(!args.off_surface);
    let mut report = Report::new("fair-quad");
    let bar = spinner("fairing structure lines");
    let out = report.time(|| fair_structure_lines(&mesh, &opts));
    bar.finish_and_clear();
    let out = out.map_err(|e| match e {
        fairline::fair::QuadFairError::Solve(_) => anyhow::Error::new(e),
        other => bad_input(other.to_string()),
    })?;
    mesh.set_positions(out.positions)?;
    let r = out.report;
    report.set_fields(&r);
    fairline::io::write_mesh(&args.output, &mesh)?;
    if let Some(png) = &args.png {
        before_after(
            &input,
            &mesh,
            ["input", "structure-line fairing"],
            true,
            png,
        )?;
    }
    for w in r.warnings() {
        report.warn(w);
    }
    report.write(args.report.as_deref())?;
    job.finish(format_args!(
        "{} iteration(s) on {} structure line(s), {} free vertices, structure energy {:.3e} → {:.3e}",
        r.iterations,
        r.structure_lines,
        r.free_vertices,
        r.structure_energy_before,
        r.structure_energy_after
    ));
    Ok(())
}
