//! `fairline draft`: the draft-angle map of a part against a pull
//! direction, as a picture with legend and the outline of the area below
//! the minimum draft, per-face CSV and a JSON report.

use crate::args::{parse_size, parse_vec3};
use crate::common::{print_warnings, write_report};
use crate::error::bad_input;
use anyhow::Result;
use fairline::picture::{Picture, ScalarField, mesh_picture};
use fairline::render::{Colormap, PolylineLayer};
use fairline::{Control, SurfaceMesh, Vec3};
use fairline_commands::draft::{self, DEFAULT_MIN_ANGLE, DraftSettings, below_outline, summary};
use std::path::{Path, PathBuf};

/// The draft angle of every face against the pull (demoulding) direction:
/// δ = asin(n · pull), 90° minus the angle between the face normal and the
/// pull; positive where the face looks along the pull, negative where it
/// looks away (the other mould half, or an undercut). Faces with |δ| below
/// --min-angle have insufficient draft for either half: the report gives
/// the share of the area below it (`below_share`), and the picture
/// outlines it. B-spline surfaces (.json .igs .step) are tessellated
/// (--grid per patch and direction).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline draft fairline-demo/dented-panel.obj --pull 0,0,1 --min-angle 3 --png draft.png --report draft.json\n  fairline draft fairline-demo/bspline-panel-dented.json --pull 0,0,1 --min-angle 5 --csv draft.csv"
)]
pub struct Args {
    /// Mesh (.obj .ply .off .stl) or surfaces (.json .igs .step).
    pub input: PathBuf,
    /// The pull direction X,Y,Z (need not be unit).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, default_value = "0,0,1")]
    pub pull: Vec3,
    /// The minimum draft angle, degrees.
    #[arg(long, default_value_t = DEFAULT_MIN_ANGLE, value_name = "DEG")]
    pub min_angle: f64,
    /// Picture coloured by the draft angle (legend in degrees), the area
    /// below the minimum outlined.
    #[arg(long, value_name = "IMG.png")]
    pub png: Option<PathBuf>,
    /// Per-face values: `face,draft_deg,area,below`.
    #[arg(long, value_name = "OUT.csv")]
    pub csv: Option<PathBuf>,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
    /// Viewing direction X,Y,Z of the picture.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub view: Option<Vec3>,
    /// Picture size WxH.
    #[arg(long, value_parser = parse_size, default_value = "1200x900")]
    pub size: (u32, u32),
    /// Tessellation grid per patch and direction for surface files.
    #[arg(long, default_value_t = 64, value_name = "N")]
    pub grid: usize,
}

pub fn run(args: Args) -> Result<()> {
    if args.png.is_none() && args.csv.is_none() && args.report.is_none() {
        return Err(bad_input("nothing to write: give --png, --csv or --report"));
    }
    crate::output::require_extension(
        "--png",
        args.png.as_deref().unwrap_or(Path::new("a.png")),
        &["png"],
    )?;
    crate::output::require_extension(
        "--csv",
        args.csv.as_deref().unwrap_or(Path::new("a.csv")),
        &["csv"],
    )?;
    if !(2..=1024).contains(&args.grid) {
        return Err(bad_input("--grid must be between 2 and 1024"));
    }
    let settings = DraftSettings {
        pull: args.pull,
        min_angle: args.min_angle,
    };
    // the settings are checked before any file is read
    draft::run(&fairline::shapes::plane(2), &settings, &Control::new())?;
    let job = crate::output::Job::new("draft")
        .input(&args.input)
        .output_opt("--png", args.png.as_deref())
        .output_opt("--csv", args.csv.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    let mesh = if crate::surface::is_surface_path(&args.input) {
        let s = crate::surface::load_surfaces(&args.input)?;
        crate::surface::tessellated_mesh(&s, args.grid)?
    } else {
        crate::input::read_mesh(&args.input)?
    };
    let out = draft::run(&mesh, &settings, &Control::new())
        .map_err(|e| crate::output::name_file(&args.input, e))?;
    if let Some(png) = &args.png {
        picture(&mesh, &out, args.min_angle, args.view, args.size)?.write_png(png)?;
    }
    if let Some(csv) = &args.csv {
        write_csv(csv, &out)?;
    }
    print_warnings(&out.report);
    write_report(args.report.as_deref(), &out.report)?;
    job.finish(summary(&out, args.min_angle))?;
    Ok(())
}

/// `face,draft_deg,area,below` per face.
fn write_csv(path: &Path, out: &draft::DraftOutcome) -> Result<()> {
    use std::io::Write;
    fairline::io::atomic_write(path, |w| {
        let mut w = std::io::BufWriter::new(w);
        writeln!(w, "face,draft_deg,area,below")?;
        for (f, ((d, a), b)) in out
            .angles
            .face_deg
            .iter()
            .zip(&out.angles.face_area)
            .zip(&out.below)
            .enumerate()
        {
            writeln!(w, "{f},{d},{a},{}", *b as u8)?;
        }
        w.flush()
    })
    .map_err(|e| anyhow::anyhow!("writing {}: {e}", path.display()))
}

/// The part coloured by the vertex draft angle on [−90°, 90°] (blue: the
/// part looks away from the pull, red: along it, grey: walls), the area
/// below the minimum outlined in black, legend and summary in the title.
fn picture(
    mesh: &SurfaceMesh,
    out: &draft::DraftOutcome,
    min_angle: f64,
    view: Option<Vec3>,
    size: (u32, u32),
) -> Result<fairline::render::Image> {
    let (opts, _) = crate::render::options(mesh, view, size)?;
    // the outline as one polyline layer: a non-finite point breaks it
    let mut points = Vec::new();
    for [a, b] in below_outline(mesh, &out.below) {
        points.extend([a, b, Vec3::splat(f64::NAN)]);
    }
    let polylines = if points.is_empty() {
        Vec::new()
    } else {
        vec![PolylineLayer {
            points,
            closed: false,
            color: [0.0, 0.0, 0.0],
            width_px: 2.5,
        }]
    };
    Ok(mesh_picture(
        mesh,
        &Picture {
            scalar: Some(ScalarField {
                name: "draft angle (degrees)".into(),
                values: &out.angles.vertex_deg,
                colormap: Colormap::Coolwarm,
                range: Some((-90.0, 90.0)),
            }),
            polylines,
            title: Some(format!(
                "draft: {:.1} % of the area below {min_angle} deg (outlined)",
                100.0 * out.shares.below
            )),
            ..Default::default()
        },
        &opts,
    )?)
}
