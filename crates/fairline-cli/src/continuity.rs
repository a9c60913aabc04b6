//! `fairline continuity`: G0 / G1 / G2 across the shared boundaries of a
//! set of B-spline patches.

use crate::common::{print_warnings, write_report};
use crate::output::{Job, say};
use crate::surface_highlight::{surface_picture, surface_zebra};
use anyhow::Result;
use fairline::Control;
use fairline::bspline::continuity::{ContinuityOptions, SeamClass};
use fairline::render::{PolylineLayer, RenderOptions, linear_to_srgb8};
use fairline_commands::continuity::{self, ContinuitySettings};
use std::path::PathBuf;

/// Finds the boundary curves shared by the patches of SURFACES
/// (geometrically, within a matching distance; also stretches shared over
/// part of a side; trimmed faces meet along their trimming curves) and
/// reports for each the largest position gap (G0), the
/// largest angle between the tangent planes (G1, degrees) and the largest
/// normal-curvature difference across the edge (G2), classified against the
/// tolerances as gap / G0 / G1 / G2, with the worst location.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline continuity fairline-demo/bspline-panel-dented.json --report seams.json --png seams.png\n\nReport: {\"edges\":[{\"surfaces\":[i,j],\"sides\":[..],\"g0_max\":..,\"g1_max_deg\":..,\"g2_max\":..,\"g2_max_relative\":..,\"class\":\"G0\"|\"G1\"|\"G2\"|\"gap\",\"worst\":[x,y,z],\"length\":..}],\"classes\":{..},\"tolerance\":..,...}"
)]
pub struct Args {
    /// Input surfaces (.json, .igs/.iges, .step/.stp or .g2).
    pub surface_file: PathBuf,
    /// Position tolerance for G0, model units (default 1e-4 × the diagonal
    /// of the control points' bounding box).
    #[arg(long, value_name = "DIST")]
    pub tolerance: Option<f64>,
    /// Angle tolerance for G1, degrees.
    #[arg(long, default_value_t = ContinuityOptions::default().angle_tolerance_deg, value_name = "DEG")]
    pub angle_tolerance: f64,
    /// Relative normal-curvature tolerance for G2.
    #[arg(long, default_value_t = ContinuityOptions::default().curvature_tolerance, value_name = "FRACTION")]
    pub curvature_tolerance: f64,
    /// Sides closer than this are one shared edge, model units (default
    /// 10 × tolerance).
    #[arg(long, value_name = "DIST")]
    pub match_distance: Option<f64>,
    /// Samples along each shared edge.
    #[arg(long, default_value_t = ContinuityOptions::default().samples, value_name = "N")]
    pub samples: usize,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
    /// Picture: the patches with each shared edge coloured by class.
    #[arg(long, value_name = "IMG.png")]
    pub png: Option<PathBuf>,
    #[command(flatten)]
    pub zebra: crate::args::ZebraArgs,
}

/// Linear-light colour of a class in pictures.
fn class_colour(c: SeamClass) -> [f32; 3] {
    match c {
        SeamClass::Gap => [0.85, 0.0, 0.0],
        SeamClass::G0 => [1.0, 0.45, 0.0],
        SeamClass::G1 => [0.0, 0.25, 1.0],
        SeamClass::G2 => [0.0, 0.55, 0.05],
    }
}

pub fn run(args: Args) -> Result<()> {
    if let Some(p) = &args.png {
        crate::output::require_extension("--png", p, &["png"])?;
    }
    let job = Job::new("continuity")
        .input(&args.surface_file)
        .output_opt("--png", args.png.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    let surfaces = crate::surface::load_surfaces(&args.surface_file)?;
    let settings = ContinuitySettings {
        tolerance: args.tolerance,
        angle_tolerance: args.angle_tolerance,
        curvature_tolerance: args.curvature_tolerance,
        match_distance: args.match_distance,
        samples: args.samples,
    };
    let bar = crate::output::spinner("continuity");
    let out = continuity::run(&surfaces, &settings, &Control::new());
    bar.finish_and_clear();
    let mut out = out.map_err(|e| crate::output::name_file(&args.surface_file, e))?;
    let result = &out.result;
    let classes = [SeamClass::Gap, SeamClass::G0, SeamClass::G1, SeamClass::G2];
    let summary = format!(
        "{}: {}",
        args.surface_file.display(),
        continuity::summary(&out, surfaces.len(), &settings)
    );
    for s in result
        .seams
        .iter()
        .filter(|s| s.class != SeamClass::G2)
        .take(10)
    {
        say(&format!(
            "  surfaces {} {} / {} {}: {} (gap {:.2e}, angle {:.3}°, curvature {:.1} %) worst at ({:.4}, {:.4}, {:.4})",
            s.surfaces[0],
            s.sides[0],
            s.surfaces[1],
            s.sides[1],
            s.class.name(),
            s.g0_max,
            s.g1_max_deg,
            100.0 * s.g2_max_relative,
            s.worst.x,
            s.worst.y,
            s.worst.z
        ));
    }
    if let Some(p) = &args.png {
        let lines: Vec<PolylineLayer> = result
            .seams
            .iter()
            .map(|s| PolylineLayer {
                points: s.points.clone(),
                closed: false,
                color: class_colour(s.class),
                width_px: 3.0,
            })
            .collect();
        let mut opts = RenderOptions::with_size(1000, 800);
        (opts.view_dir, opts.up) = crate::surface::camera(&surfaces, None)?;
        let zebra = surface_zebra(&surfaces, &args.zebra, None, &opts)?;
        if let Some(z) = &zebra {
            out.report.set("zebra", crate::args::zebra_json(z));
        }
        let mut img = surface_picture(
            &surfaces,
            lines,
            "continuity across patch boundaries",
            zebra,
            &opts,
        )?;
        // legend: one swatch per class with its count
        let scale = 2;
        let (x0, mut y) = (12i64, 40i64);
        for c in classes {
            let colour = linear_to_srgb8(class_colour(c));
            img.fill_rect(x0, y, 28, 8, colour);
            let label = format!("{} ({})", c.name(), result.classes.get(c));
            img.draw_text(x0 + 36, y - 4, &label, [20, 20, 20, 255], scale);
            y += 24;
        }
        img.write_png(p)?;
    }
    print_warnings(&out.report);
    write_report(args.report.as_deref(), &out.report)?;
    job.finish(summary)?;
    Ok(())
}
