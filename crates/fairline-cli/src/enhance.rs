//! `fairline enhance`: feature enhancement by vertex flow (Ji et al. 2011).

use crate::args::{ZebraArgs, choice};
use crate::common::{print_warnings, write_report};
use crate::error::bad_input;
use crate::output::spinner;
use anyhow::{Context, Result};
use fairline::Control;
use fairline::enhance::{EnhanceSolver, Projection};
use fairline::geom::{CurvatureMethod, principal_curvatures, vertex_normals};
use fairline::mesh::SurfaceMesh;
use fairline::render::{
    Colormap, Image, Legend, MeshLayer, ReflectionZebra, RenderOptions, Scene, clipped, render,
    scalar_colors, side_by_side,
};
use fairline_commands::enhance::{self, EnhanceSettings};
use std::path::PathBuf;

/// Moves the vertices of a triangle mesh from flat regions toward ridges
/// and valleys (vertex flow, Ji et al. 2011) without changing the
/// connectivity: minimises F_em + λ F_sd + μ F_smo by sparse least squares,
/// then puts every moved vertex back onto a smooth fit of the input surface
/// (--projection), so that the mesh approximates the shape better, not only
/// differently. The vertices of --fixed and the corners of the boundary stay
/// bit-identical; the other boundary vertices slide along the input's
/// boundary polyline and stay on it (with --projection none the whole
/// boundary stays); flipped triangles are repaired. The result does not depend on the scale or
/// position of the input (internally normalised by the mean edge length).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline enhance fairline-demo/rounded-cube.obj --lambda 0.5 --mu 0.5 -o cube-enhanced.obj --report r.json --png cube-enhanced.png\n  fairline enhance fairline-demo/sphere.ply --solver cg -o sphere-enhanced.ply\n  fairline enhance fairline-demo/rounded-cube.obj --projection none -o cube-paper.obj\n\nReport keys: projection flipped_triangles degraded_triangles backtracked_vertices quality_resolves quality_before quality_after histogram_before histogram_after max_displacement max_distance_to_input solver cg_iterations cg_relative_residual direct_fallbacks timings."
)]
pub struct Args {
    /// Input triangle mesh (.obj .ply .off .stl).
    pub mesh: PathBuf,
    /// λ, weight of the squared-distance term (smaller: stronger features). > 0.
    #[arg(long, default_value_t = 1.0)]
    pub lambda: f64,
    /// μ, weight of the fairness term (larger: better triangles). ≥ 0.
    #[arg(long, default_value_t = 0.5)]
    pub mu: f64,
    /// Solves; curvature is recomputed on the current mesh before each one
    /// after the first.
    #[arg(long, default_value_t = 1)]
    pub iterations: usize,
    /// Solver of the least-squares system: `cg` (block-Jacobi conjugate
    /// gradients, fast on curved meshes), `amg` (conjugate gradients
    /// preconditioned by a multigrid bi-Laplacian model: few iterations
    /// also on large flat or cylindrical parts, at a higher cost per
    /// iteration), `direct` (sparse Cholesky, memory-hungry), or `auto`
    /// (`amg` on meshes with large flat or cylindrical parts; elsewhere
    /// `cg` for up to 40 iterations, fewer when its progress shows it
    /// would need more, then `amg` from there; `direct` only should that
    /// fail). All give the same result to 1e-8 of the size of the mesh.
    #[arg(long, value_parser = choice::<EnhanceSolver>(), default_value = "auto")]
    pub solver: EnhanceSolver,
    /// Where the vertices go after each solve: `smooth` (onto the Phong
    /// patch, α = ½, of the nearest input triangle: between the input's
    /// vertices they land on a smooth fit of the surface, not on its chords),
    /// `mesh` (onto the nearest point of the input mesh) or `none` (the
    /// paper's method: they slide along tangent planes and leave curved
    /// parts).
    #[arg(long, value_parser = choice::<Projection>(), default_value = "smooth")]
    pub projection: Projection,
    /// JSON file `{"vertices":[...]}` of vertices that must not move (list
    /// the boundary vertices here to keep the whole boundary in place).
    #[arg(long, value_name = "FILE.json")]
    pub fixed: Option<PathBuf>,
    /// Output mesh.
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
    /// Picture of input and output side by side, coloured by mean curvature,
    /// with the mesh edges; with --zebra shaded grey with the reflection
    /// zebra instead of the colour map.
    #[arg(long, value_name = "IMG.png")]
    pub png: Option<PathBuf>,
    #[command(flatten)]
    pub zebra: ZebraArgs,
}

pub fn run(args: Args) -> Result<()> {
    // every check that can refuse the input runs before anything is written
    let job = crate::output::Job::new("enhance")
        .input(&args.mesh)
        .input_opt(args.fixed.as_deref())
        .output("-o", &args.output)
        .output_opt("--png", args.png.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    if let Some(png) = &args.png {
        crate::output::require_extension("--png", png, &["png"])?;
    }
    let mesh = crate::input::read_mesh(&args.mesh)?;
    crate::input::note_split_vertices(&args.mesh, &mesh);
    if !mesh.is_triangle_mesh() {
        return Err(bad_input(format!(
            "{}: enhance needs a triangle mesh (triangulate it first, e.g. with `fairline convert`)",
            args.mesh.display()
        )));
    }
    let fixed = match &args.fixed {
        Some(p) => fairline::io::read_fixed_vertices(p, mesh.vertex_count())
            .map_err(|e| bad_input(e.to_string()))?,
        None => Vec::new(),
    };
    let settings = EnhanceSettings {
        lambda: args.lambda,
        mu: args.mu,
        iterations: args.iterations,
        solver: args.solver,
        projection: args.projection,
        fixed,
    };
    let bar = spinner("vertex flow");
    let result = enhance::run(&mesh, &settings, &Control::new());
    bar.finish_and_clear();
    let mut result = result?;
    let mut out = mesh.clone();
    out.set_positions(result.positions)?;
    // the picture is made before anything is written
    let image = match &args.png {
        Some(_) => {
            let (image, zebra) = picture(&mesh, &out, (900, 800), &args.zebra)?;
            if let Some(z) = &zebra {
                result.report.set("zebra", crate::args::zebra_json(z));
            }
            Some(image)
        }
        None => None,
    };
    fairline::io::write_mesh(&args.output, &out)?;
    if let (Some(png), Some(image)) = (&args.png, image) {
        image
            .write_png(png)
            .with_context(|| format!("writing {}", png.display()))?;
    }
    let r = &result.result;
    print_warnings(&result.report);
    write_report(args.report.as_deref(), &result.report)?;
    job.finish(format_args!(
        "vertex flow, {} iteration(s) on {} vertices ({} free), minimum triangle quality {:.3} → {:.3}",
        r.iterations, r.vertices, r.free_vertices, r.quality_before.min, r.quality_after.min
    ))?;
    Ok(())
}

/// Input and output side by side, `size` pixels each, smooth shaded,
/// coloured by mean curvature on a common scale (the input's range), with
/// wireframe, so that the migration of vertices toward features shows.
/// With --zebra the panels are grey with the reflection zebra of the
/// input's panel (titled with its period) instead of the colour map; the
/// zebra is returned.
pub fn picture(
    input: &SurfaceMesh,
    output: &SurfaceMesh,
    size: (u32, u32),
    zebra: &ZebraArgs,
) -> Result<(Image, Option<ReflectionZebra>)> {
    let mut opts = RenderOptions::with_size(size.0, size.1);
    (opts.view_dir, opts.up) = crate::render::camera(input, None);
    let zebra = zebra.reflection_zebra(input, None, &opts)?;
    let h_in = principal_curvatures(input, CurvatureMethod::Rusinkiewicz).mean();
    let h_out = principal_curvatures(output, CurvatureMethod::Rusinkiewicz).mean();
    let (c_in, range) = scalar_colors(&h_in, Colormap::Coolwarm, None);
    let (c_out, _) = scalar_colors(&h_out, Colormap::Coolwarm, Some(range));
    let panel = |mesh: &SurfaceMesh, colors: &[[f32; 3]]| -> Result<Image> {
        let triangles: Vec<[u32; 3]> = mesh
            .faces()
            .map(|f| mesh.triangle(f).map(|v| v.0))
            .collect();
        let normals = vertex_normals(mesh);
        let layer = MeshLayer::new(mesh.positions(), &triangles)
            .with_normals(&normals)
            .with_wireframe([0.08, 0.08, 0.1])
            .with_two_sided(false);
        let scene = match &zebra {
            Some(z) => Scene {
                meshes: vec![layer.with_zebra(Some(*z))],
                title: Some(crate::args::zebra_title(z)),
                ..Default::default()
            },
            None => Scene {
                meshes: vec![layer.with_colors(colors)],
                legend: Some(Legend {
                    title: "mean curvature".into(),
                    colormap: Colormap::Coolwarm,
                    min: range.0,
                    max: range.1,
                    clipped: clipped(&h_in, range) || clipped(&h_out, range),
                }),
                ..Default::default()
            },
        };
        Ok(render(&scene, &opts)?)
    };
    let a = panel(input, &c_in)?;
    let b = panel(output, &c_out)?;
    Ok((side_by_side(&[a, b], &["input", "vertex flow"]), zebra))
}
