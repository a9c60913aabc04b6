//! `fairline deviation`: the signed distance of one state of a surface
//! from another, as a picture with legend and histogram, per-vertex CSV
//! and a JSON report.

use crate::args::{parse_size, parse_vec3};
use crate::common::write_report;
use crate::error::bad_input;
use anyhow::Result;
use fairline::bspline::BSplineSurface;
use fairline::geom::Histogram;
use fairline::picture::{Picture, ScalarField, mesh_picture};
use fairline::render::{Colormap, Image, linear_to_srgb8};
use fairline::{Control, SurfaceMesh, Vec3};
use fairline_commands::Subject;
use fairline_commands::deviation::{self, DEFAULT_BINS, DeviationSettings, summary};
use std::path::{Path, PathBuf};

/// The signed deviation of AFTER from BEFORE, per vertex of AFTER: for
/// meshes of the same connectivity the vertex motion along BEFORE's normal,
/// otherwise the distance to the closest point of BEFORE, positive on the
/// side BEFORE's normals point to. When BEFORE is a B-spline surface file
/// (.json .igs .step) the distance is to its surfaces themselves (the
/// closest point by point inversion, started on a --grid tessellation),
/// exact to rounding; an AFTER surface file is measured at the vertices of
/// its tessellation (--grid per patch and direction), and when both are
/// surface files the largest deviation is also searched between those
/// vertices, on the surfaces themselves (report key "peak").
/// The report gives max/mean/rms/percentiles and a histogram; with
/// --region, separately inside the region (the intended motion) and
/// outside it (side effects: 0 for highlight-line fairing); and the
/// deviation split by wavelength into its broad part (whole
/// neighbourhoods moved: offset, drift, the shrinkage of a smoothing) and
/// its local part (a few vertices moved against their neighbours: the
/// noise or the defect a repair removes). Lengths are in the files' units.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline fair fairline-demo/dented-panel.obj --region fairline-demo/dented-panel-region.json -o faired.obj\n  fairline deviation fairline-demo/dented-panel.obj faired.obj --region fairline-demo/dented-panel-region.json --png deviation.png --report deviation.json\n  fairline deviation fairline-demo/sphere.ply fairline-demo/sphere.ply --csv d.csv\n  fairline smooth fairline-demo/wavy.obj --method laplace -o laplace.obj\n  fairline deviation fairline-demo/wavy.obj laplace.obj --show broad --png shrinkage.png"
)]
pub struct Args {
    /// The reference: mesh (.obj .ply .off .stl) or surfaces (.json .igs .step).
    pub before: PathBuf,
    /// The measured state, one value per vertex of it.
    pub after: PathBuf,
    /// Region JSON (faces of AFTER): statistics inside and outside it.
    #[arg(long, value_name = "REGION.json")]
    pub region: Option<PathBuf>,
    /// Picture of AFTER coloured by the signed deviation, with legend and
    /// histogram.
    #[arg(long, value_name = "IMG.png")]
    pub png: Option<PathBuf>,
    /// Per-vertex values: `vertex,x,y,z,signed,distance,in_region,broad,local`.
    #[arg(long, value_name = "OUT.csv")]
    pub csv: Option<PathBuf>,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
    /// Colour range ±MAX of the picture (default: the 98th percentile of
    /// the non-zero |d|, values beyond drawn in the end colours).
    #[arg(long, value_name = "MAX", conflicts_with = "range")]
    pub max: Option<f64>,
    /// Colour range LO,HI of the picture (instead of ±MAX).
    #[arg(long, value_name = "LO,HI", value_parser = crate::args::parse_range, allow_hyphen_values = true)]
    pub range: Option<(f64, f64)>,
    /// Histogram bins.
    #[arg(long, default_value_t = DEFAULT_BINS)]
    pub bins: usize,
    /// The wavelength (model units) that splits the deviation into its
    /// broad part (longer waves) and its local part (default: ten mean
    /// edge lengths of AFTER, so noise is local and the shape broad).
    #[arg(long, value_name = "LENGTH")]
    pub broad_wavelength: Option<f64>,
    /// What the picture colours: the signed deviation, its broad part or
    /// its local part.
    #[arg(long, value_enum, default_value_t = Show::Signed)]
    pub show: Show,
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

/// The part of the deviation a picture shows.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Show {
    /// The signed deviation.
    Signed,
    /// Its broad part (waves longer than --broad-wavelength).
    Broad,
    /// Its local part.
    Local,
}

/// Reads a mesh, or tessellates a surface file `grid` × `grid` per patch
/// (refused, exit 2, when that is more than the command layer's
/// [`deviation::MAX_GRID_POINTS`]); the surfaces come with it.
fn read(path: &Path, grid: usize) -> Result<(SurfaceMesh, Option<Vec<BSplineSurface>>)> {
    if crate::surface::is_surface_path(path) {
        let s = crate::surface::load_surfaces(path)?;
        deviation::check_grid(s.len(), grid).map_err(|e| {
            bad_input(format!(
                "{}: {}",
                path.display(),
                e.message(fairline_commands::FrontEnd::Cli)
            ))
        })?;
        Ok((crate::surface::tessellated_mesh(&s, grid)?, Some(s)))
    } else {
        Ok((crate::input::read_mesh(path)?, None))
    }
}

pub fn run(args: Args) -> Result<()> {
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
    if let Some(m) = args.max
        && !(m.is_finite() && m > 0.0)
    {
        return Err(bad_input(format!("--max {m}: give a positive number")));
    }
    if !(2..=1024).contains(&args.grid) {
        return Err(bad_input("--grid must be between 2 and 1024"));
    }
    let job = crate::output::Job::new("deviation")
        .input(&args.before)
        .input(&args.after)
        .input_opt(args.region.as_deref())
        .output_opt("--png", args.png.as_deref())
        .output_opt("--csv", args.csv.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    // B-spline surfaces are measured against exactly, meshes against their
    // triangles
    enum Reference {
        Surfaces(Vec<fairline::bspline::BSplineSurface>),
        Mesh(Box<SurfaceMesh>),
    }
    let before = if crate::surface::is_surface_path(&args.before) {
        Reference::Surfaces(crate::surface::load_surfaces(&args.before)?)
    } else {
        Reference::Mesh(Box::new(read(&args.before, args.grid)?.0))
    };
    let (after, after_surfaces) = read(&args.after, args.grid)?;
    let region = match &args.region {
        Some(path) => {
            let spec = fairline::io::read_region(path).map_err(|e| bad_input(e.to_string()))?;
            Some(
                spec.faces(&after)
                    .map_err(|e| bad_input(format!("{}: {e}", path.display())))?,
            )
        }
        None => None,
    };
    let settings = DeviationSettings {
        bins: args.bins,
        broad_wavelength: args.broad_wavelength,
    };
    let out = match &before {
        Reference::Surfaces(surfaces) => match &after_surfaces {
            Some(measured) => deviation::run_between_surfaces(
                surfaces,
                args.grid,
                measured,
                &after,
                region.as_deref(),
                &settings,
                &Control::new(),
            ),
            None => deviation::run_on_surfaces(
                surfaces,
                args.grid,
                &after,
                region.as_deref(),
                &settings,
                &Control::new(),
            ),
        },
        Reference::Mesh(mesh) => {
            deviation::run(mesh, &after, region.as_deref(), &settings, &Control::new())
        }
    }
    .map_err(|e| {
        let path = match e.subject() {
            Some(Subject::Input) => Some(args.before.as_path()),
            Some(Subject::Region) => args.region.as_deref(),
            _ => None,
        };
        let bad = e.kind() == fairline_commands::ErrorKind::BadInput;
        let msg = match path {
            Some(p) => format!(
                "{}: {}",
                p.display(),
                e.message(fairline_commands::FrontEnd::Cli)
            ),
            None => e.message(fairline_commands::FrontEnd::Cli),
        };
        if bad {
            bad_input(msg)
        } else {
            anyhow::anyhow!(msg)
        }
    })?;
    if let Some(png) = &args.png {
        let img = picture(
            &after, &out, args.show, args.max, args.range, args.view, args.size,
        )?;
        img.write_png(png)?;
    }
    if let Some(csv) = &args.csv {
        write_csv(csv, &after, &out)?;
    }
    write_report(args.report.as_deref(), &out.report)?;
    job.finish(summary(&out))?;
    Ok(())
}

/// `vertex,x,y,z,signed,distance,in_region,broad,local` per vertex
/// (original vertex indices; split non-manifold fans keep the value of the
/// kept index).
fn write_csv(path: &Path, mesh: &SurfaceMesh, out: &deviation::DeviationOutcome) -> Result<()> {
    use std::io::Write;
    let signed = mesh.original_values(&out.deviation.signed);
    let dist = mesh.original_values(&out.deviation.distance);
    let broad = mesh.original_values(&out.split.broad);
    let local = mesh.original_values(&out.split.local);
    fairline::io::atomic_write(path, |w| {
        let mut w = std::io::BufWriter::new(w);
        writeln!(w, "vertex,x,y,z,signed,distance,in_region,broad,local")?;
        for (i, (s, d)) in signed.iter().zip(dist).enumerate() {
            let p = mesh.positions()[i];
            let r = out.in_region.get(i).map_or(0, |&b| b as u8);
            let (b, l) = (broad[i], local[i]);
            writeln!(w, "{i},{},{},{},{s},{d},{r},{b},{l}", p.x, p.y, p.z)?;
        }
        w.flush()
    })
    .map_err(|e| anyhow::anyhow!("writing {}: {e}", path.display()))
}

/// AFTER coloured by the signed deviation (or its broad or local part) on
/// a range centred on 0, with the colour bar (units in its title) and a
/// histogram inset of the values shown.
pub fn picture(
    mesh: &SurfaceMesh,
    out: &deviation::DeviationOutcome,
    show: Show,
    max: Option<f64>,
    range: Option<(f64, f64)>,
    view: Option<Vec3>,
    size: (u32, u32),
) -> Result<Image> {
    let (opts, _) = crate::render::options(mesh, view, size)?;
    let range = match range {
        Some(r) => Some(r),
        None => max.filter(|m| *m > 0.0 && m.is_finite()).map(|m| (-m, m)),
    };
    let (name, values, stats, title) = match show {
        Show::Signed => (
            "deviation (model units)",
            &out.deviation.signed,
            &out.all,
            summary_title(out),
        ),
        Show::Broad => (
            "broad part (model units)",
            &out.split.broad,
            &out.broad,
            part_title("broad part, waves over", out.split.wavelength, &out.broad),
        ),
        Show::Local => (
            "local part (model units)",
            &out.split.local,
            &out.local,
            part_title("local part, waves under", out.split.wavelength, &out.local),
        ),
    };
    let mut img = mesh_picture(
        mesh,
        &Picture {
            scalar: Some(ScalarField {
                name: name.into(),
                values,
                colormap: Colormap::Coolwarm,
                range,
            }),
            title: Some(title),
            ..Default::default()
        },
        &opts,
    )?;
    draw_histogram(&mut img, &stats.histogram);
    Ok(img)
}

fn summary_title(out: &deviation::DeviationOutcome) -> String {
    let mut t = format!(
        "deviation: max |d| {:.3e}, rms {:.3e}",
        out.all.max_abs, out.all.rms
    );
    if let Some(p) = &out.peak {
        t.push_str(&format!(
            "; between the vertices max {:.3e}",
            p.signed.abs()
        ));
    }
    if let (Some(i), Some(o)) = (&out.inside, &out.outside) {
        t.push_str(&format!(
            "; region max {:.2e}, outside max {:.2e}",
            i.max_abs, o.max_abs
        ));
    }
    t
}

/// The title of a picture of the broad or local part.
fn part_title(what: &str, wavelength: f64, stats: &fairline::geom::DeviationStats) -> String {
    format!(
        "{what} {wavelength:.2e}: max |d| {:.3e}, mean {:+.2e}, rms {:.3e}",
        stats.max_abs, stats.mean, stats.rms
    )
}

/// A histogram of the signed values in the lower-left corner: one bar per
/// bin, coloured as the bin's centre is on the map, bar heights on a
/// logarithmic scale, ln(1 + count) (so that a few large values still show
/// beside a bin of thousands at zero), with the range written under it.
fn draw_histogram(img: &mut Image, h: &Histogram) {
    let (w, ht) = (img.width.min(1600) / 4, img.height / 6);
    if w < 40 || ht < 30 || h.counts.is_empty() {
        return;
    }
    let (x0, y0) = (16i64, img.height as i64 - ht as i64 - 30);
    img.fill_rect(x0 - 4, y0 - 4, w + 8, ht + 26, [255, 255, 255, 230]);
    let n = h.counts.len();
    let top = (h.counts.iter().copied().max().unwrap_or(0).max(1) as f64).ln_1p();
    let bw = (w as f64 / n as f64).max(1.0);
    for (k, &c) in h.counts.iter().enumerate() {
        let t = (k as f64 + 0.5) / n as f64;
        let colour = linear_to_srgb8(Colormap::Coolwarm.map(t));
        let bh = ((c as f64).ln_1p() / top * ht as f64).round() as u32;
        let x = x0 + (k as f64 * bw) as i64;
        let bw_px = (bw.floor() as u32).max(1);
        img.fill_rect(
            x,
            y0 + (ht - bh) as i64,
            bw_px,
            bh,
            [colour[0], colour[1], colour[2], 255],
        );
    }
    img.fill_rect(x0 + (w / 2) as i64, y0, 1, ht, [0, 0, 0, 255]);
    let label = format!("{:.2e} .. 0 .. {:.2e} (log count)", h.lo, h.hi);
    img.draw_text(x0, y0 + ht as i64 + 6, &label, [0, 0, 0, 255], 1);
}
