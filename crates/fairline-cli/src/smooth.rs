//! `fairline smooth` (the classic smoothing family, Grüner thesis ch. 3) and
//! `fairline fair-quad` (structure-line fairing of quad meshes, ch. 4).

use crate::args::{ZebraArgs, choice};
use crate::common::{print_warnings, write_report};
use crate::error::bad_input;
use crate::output::spinner;
use anyhow::Result;
use fairline::Control;
use fairline::mesh::{SurfaceMesh, VertexId};
use fairline::picture::{Picture, mesh_picture};
use fairline::render::{ReflectionZebra, RenderOptions, side_by_side};
use fairline::smooth::SmoothMethod;
use fairline_commands::Weights;
use fairline_commands::fair_quad::{self, QuadMethod, QuadSettings};
use fairline_commands::smooth::{self, SmoothSettings};
use std::path::{Path, PathBuf};

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
    #[arg(long, value_parser = choice::<SmoothMethod>(), default_value = "taubin")]
    pub method: SmoothMethod,
    /// Laplacian weights (laplace, taubin).
    #[arg(long, value_parser = choice::<Weights>(), default_value = "uniform")]
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
    /// Most work of schneider-kobbelt, in evaluations of Δ_B H at a vertex
    /// (default 10000000, about ten seconds): an iteration that would go
    /// beyond it is not started, and the run ends unconverged (exit 1).
    /// Schneider-kobbelt also stops (exit 1, the reason in the report's
    /// stop_reason) when its residual stagnates or diverges.
    #[arg(long, value_name = "N")]
    pub max_work: Option<u64>,
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
    #[command(flatten)]
    pub zebra: ZebraArgs,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

/// Reads the fixed-vertices file `{"vertices":[...]}` (the one reader,
/// [`fairline::io::read_fixed_vertices`]); errors name the file and exit 2.
pub fn read_fixed(path: &Path, count: usize) -> Result<Vec<VertexId>> {
    fairline::io::read_fixed_vertices(path, count).map_err(|e| bad_input(e.to_string()))
}

/// Two meshes side by side under one camera framing the input; with
/// --zebra both with the reflection zebra of the input's panel (titled
/// with its period), which is returned.
pub fn before_after(
    before: &SurfaceMesh,
    after: &SurfaceMesh,
    labels: [&str; 2],
    wireframe: bool,
    zebra: &ZebraArgs,
    path: &Path,
) -> Result<Option<ReflectionZebra>> {
    let mut opts = RenderOptions::with_size(700, 560);
    (opts.view_dir, opts.up) = crate::render::camera(before, None);
    let zebra = zebra.reflection_zebra(before, None, &opts)?;
    let pic = Picture {
        wireframe,
        zebra,
        title: zebra.as_ref().map(crate::args::zebra_title),
        ..Default::default()
    };
    let a = mesh_picture(before, &pic, &opts)?;
    let b = mesh_picture(after, &pic, &opts)?;
    side_by_side(&[a, b], &labels).write_png(path)?;
    Ok(zebra)
}

impl Args {
    /// The command layer's settings of these arguments (`fixed`: the
    /// vertices of the --fixed file).
    fn settings(&self, fixed: Vec<VertexId>) -> SmoothSettings {
        SmoothSettings {
            method: self.method,
            weights: self.weights,
            exponent: self.exponent,
            iterations: self.iterations,
            lambda: self.lambda,
            mu: self.mu,
            pass_band: self.pass_band,
            time_step: self.time_step,
            epsilon: self.epsilon,
            max_work: self.max_work,
            fix_boundary: self.fix_boundary,
            hierarchical_boundary: self.hierarchical_boundary,
            fixed,
            preserve_volume: self.preserve_volume,
            tangential: self.tangential,
        }
    }
}

pub fn run(args: Args) -> Result<()> {
    let job = crate::output::Job::new("smooth")
        .input(&args.mesh)
        .input_opt(args.fixed.as_deref())
        .output("-o", &args.output)
        .output_opt("--png", args.png.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    args.settings(Vec::new()).check()?;
    let mut mesh = crate::input::read_mesh(&args.mesh)?;
    crate::input::note_split_vertices(&args.mesh, &mesh);
    let fixed = match &args.fixed {
        Some(p) => read_fixed(p, mesh.vertex_count())?,
        None => Vec::new(),
    };
    let settings = args.settings(fixed);
    let bar = spinner("smoothing");
    let result = smooth::run(&mesh, &settings, &Control::new());
    bar.finish_and_clear();
    let mut out = result?;
    let stopped = out.stopped_error(fairline_commands::FrontEnd::Cli);
    let r = &out.result;
    let name = settings.method.name();
    // the input is kept only for the before/after picture
    let input = args.png.is_some().then(|| mesh.clone());
    mesh.set_positions(out.positions)?;
    fairline::io::write_mesh(&args.output, &mesh)?;
    if let (Some(png), Some(input)) = (&args.png, &input)
        && let Some(z) = before_after(input, &mesh, ["input", name], false, &args.zebra, png)?
    {
        out.report.set("zebra", crate::args::zebra_json(&z));
    }
    print_warnings(&out.report);
    write_report(args.report.as_deref(), &out.report)?;
    job.finish(format_args!(
        "{name}, {} iteration(s){} on {} vertices, largest move {:.3e}",
        r.iterations,
        if r.converged { "" } else { ", not converged" },
        mesh.vertex_count(),
        r.max_displacement
    ))?;
    if let Some(e) = stopped {
        // the output is written so that it can be looked at, but it is not
        // what was asked for: exit 1 with the command layer's sentence
        anyhow::bail!(
            "{}: {}; {} was written for inspection only",
            args.mesh.display(),
            e.message(fairline_commands::FrontEnd::Cli),
            args.output.display()
        );
    }
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
///
/// `--method network` fairs the polyline network instead (Grüner §3.1.1,
/// after Hofer et al.): only the heights z move, minimising the bending
/// energy Σ (z_{k−1} − 2z_k + z_{k+1})² of every structure line with each
/// vertex inside its tolerance cylinder |z − z⁰| ≤ h·ē (`--tolerance h`,
/// ē the mean edge length); `--fixed` and `--fix-boundary` give zero
/// tolerance.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline fair-quad fairline-demo/quad-saddle.obj -o faired.obj\n  fairline fair-quad fairline-demo/quad-saddle.obj --weight 0.005 --deviation 0.05 --deviation-factor 0.5 --iterations 4 --fix-boundary -o faired.obj --png cmp.png --report r.json\n  fairline fair-quad fairline-demo/quad-saddle.obj --method network --tolerance 0.05 -o network.obj --report r.json"
)]
pub struct QuadArgs {
    /// Input quad mesh (.obj .ply .off).
    pub mesh: PathBuf,
    /// Output mesh.
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// What to minimise.
    #[arg(long, value_parser = crate::args::choice::<QuadMethod>(), default_value = "structure-lines")]
    pub method: QuadMethod,
    /// Half height h of the tolerance cylinders of `--method network`, in
    /// mean edge lengths (|z − z⁰| ≤ h·ē).
    #[arg(long, default_value_t = 0.1)]
    pub tolerance: f64,
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
    /// Give every freed point its own penalty weight ω·δ/d by its
    /// deviation d (δ the iteration's --deviation): the worse the zigzag,
    /// the less the point is held (the thesis' suggested extension;
    /// measured no better than one weight on generated zigzag grids).
    #[arg(long)]
    pub deviation_weights: bool,
    /// JSON file `{"vertices":[...]}` of vertices that never move.
    #[arg(long, value_name = "FILE.json")]
    pub fixed: Option<PathBuf>,
    /// Write a before/after picture with the structure lines.
    #[arg(long, value_name = "IMG.png")]
    pub png: Option<PathBuf>,
    #[command(flatten)]
    pub zebra: ZebraArgs,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

impl QuadArgs {
    /// The command layer's settings of these arguments.
    fn settings(&self, fixed: Vec<VertexId>) -> QuadSettings {
        QuadSettings {
            method: self.method,
            tolerance: self.tolerance,
            weight: self.weight,
            deviation: self.deviation,
            deviation_factor: self.deviation_factor,
            iterations: self.iterations,
            fix_boundary: self.fix_boundary,
            fixed,
            off_surface: self.off_surface,
            deviation_weights: self.deviation_weights,
        }
    }
}

pub fn run_quad(args: QuadArgs) -> Result<()> {
    let job = crate::output::Job::new("fair-quad")
        .input(&args.mesh)
        .input_opt(args.fixed.as_deref())
        .output("-o", &args.output)
        .output_opt("--png", args.png.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    args.settings(Vec::new()).check()?;
    let mut mesh = crate::input::read_mesh(&args.mesh)?;
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
    let bar = spinner("fairing structure lines");
    let out = fair_quad::run(&mesh, &args.settings(fixed), &Control::new());
    bar.finish_and_clear();
    let mut out = out?;
    mesh.set_positions(out.positions)?;
    let r = out.result;
    fairline::io::write_mesh(&args.output, &mesh)?;
    if let Some(png) = &args.png
        && let Some(z) = before_after(
            &input,
            &mesh,
            [
                "input",
                match args.method {
                    QuadMethod::StructureLines => "structure-line fairing",
                    QuadMethod::Network => "polyline network",
                },
            ],
            true,
            &args.zebra,
            png,
        )?
    {
        out.report.set("zebra", crate::args::zebra_json(&z));
    }
    print_warnings(&out.report);
    write_report(args.report.as_deref(), &out.report)?;
    job.finish(format_args!(
        "{} iteration(s) on {} structure line(s), {} free vertices, structure energy {:.3e} → {:.3e}",
        r.iterations,
        r.structure_lines,
        r.free_vertices,
        r.structure_energy_before,
        r.structure_energy_after
    ))?;
    Ok(())
}
