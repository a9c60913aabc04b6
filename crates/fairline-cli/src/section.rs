//! `fairline section`: plane sections of a mesh (or of surfaces,
//! tessellated) as polylines with their curvature combs; with `--iso`,
//! isoparametric curves of B-spline surfaces with their exact combs.

use crate::args::{parse_size, parse_vec3};
use crate::common::{print_warnings, write_report};
use crate::error::bad_input;
use anyhow::Result;
use fairline::bspline::IsoCurve;
use fairline::geom::SectionCurve;
use fairline::{Control, Vec3};
use fairline_commands::section::{self, IsoSettings, SectionSettings};
use std::path::{Path, PathBuf};

/// Cuts the surface with `--count` parallel planes `--spacing` apart (the
/// first through `--plane-point`, normal `--plane-normal`) and writes the
/// section polylines with the curvature of each point (the circle through
/// it and its neighbours) and its comb vector −scale·κ·m (m towards the
/// centre of curvature: the comb stands on the convex side). Polygons are
/// triangulated, surface files (.json .igs .step) tessellated (--grid).
/// With --iso N on a surface file: N isoparametric curves per direction
/// of each surface, with the exact curvature of the surface's derivatives.
/// --png draws the part with the curves and their combs (teeth and the
/// line through their tips; without --comb-scale the median curvature's
/// tooth is 4 % of the part's diagonal, teeth longer than 4× it are cut
/// and counted in the title).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline section fairline-demo/sphere.ply --plane-point 0,0,0 --plane-normal 0,0,1 --csv sections.csv\n  fairline section fairline-demo/dented-panel.obj --plane-point 0,-1.5,0 --plane-normal 0,1,0 --count 7 --spacing 0.5 --comb-scale 0.2 --obj sections.obj --report sections.json\n  fairline section fairline-demo/bspline-panel-dented.json --iso 7 --comb-scale 0.5 --obj combs.obj --csv combs.csv\n  fairline section fairline-demo/bspline-panel-dented.json --iso 9 --png combs.png"
)]
pub struct Args {
    /// Mesh (.obj .ply .off .stl) or surfaces (.json .igs .step).
    pub input: PathBuf,
    /// A point of the first plane X,Y,Z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, required_unless_present = "iso", conflicts_with = "iso")]
    pub plane_point: Option<Vec3>,
    /// The planes' normal X,Y,Z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, required_unless_present = "iso", conflicts_with = "iso")]
    pub plane_normal: Option<Vec3>,
    /// B-spline surfaces: instead of plane sections, N isoparametric curves
    /// per direction and surface (the domain's ends, the patch edges,
    /// included) with their exact curvature combs, cut to trimmed faces,
    /// whose edges (trimming curves on the surface) are combed as well.
    #[arg(long, value_name = "N")]
    pub iso: Option<usize>,
    /// With --iso: samples along each iso-curve (the interior knots added).
    #[arg(long, default_value_t = 200, value_name = "N", requires = "iso")]
    pub samples: usize,
    /// With --iso: only this surface of the file (default: all).
    #[arg(long, value_name = "K", requires = "iso")]
    pub surface: Option<usize>,
    /// Number of parallel planes.
    #[arg(long, default_value_t = 1)]
    pub count: usize,
    /// Distance between the planes (along the normal).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub spacing: f64,
    /// Length of the comb per unit curvature (default 1 in the files;
    /// in the picture, the median curvature's tooth 4 % of the diagonal).
    #[arg(long)]
    pub comb_scale: Option<f64>,
    /// Points as CSV: `section,curve,point,x,y,z,curvature,comb_x,comb_y,comb_z`
    /// (with --iso: `surface,kind,value,curve,point,t,x,y,z,curvature,comb_x,comb_y,comb_z`).
    #[arg(long, value_name = "OUT.csv")]
    pub csv: Option<PathBuf>,
    /// Polylines as OBJ lines (`l`): the sections, then the comb teeth.
    #[arg(long, value_name = "OUT.obj")]
    pub obj: Option<PathBuf>,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
    /// Picture of the part with the curves and their curvature combs.
    #[arg(long, value_name = "IMG.png")]
    pub png: Option<PathBuf>,
    /// Viewing direction X,Y,Z of the picture.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub view: Option<Vec3>,
    /// Picture size WxH.
    #[arg(long, value_parser = parse_size, default_value = "1200x900")]
    pub size: (u32, u32),
    #[command(flatten)]
    pub zebra: crate::args::ZebraArgs,
    /// Tessellation grid per patch and direction for plane sections of
    /// surface files.
    #[arg(long, default_value_t = 64, value_name = "N")]
    pub grid: usize,
}

pub fn run(args: Args) -> Result<()> {
    if args.csv.is_none() && args.obj.is_none() && args.report.is_none() && args.png.is_none() {
        return Err(bad_input(
            "nothing to write: give --csv, --obj, --png or --report",
        ));
    }
    crate::output::require_extension(
        "--png",
        args.png.as_deref().unwrap_or(Path::new("a.png")),
        &["png"],
    )?;
    crate::args::check_view(args.view)?;
    if let Some(c) = args.comb_scale
        && !c.is_finite()
    {
        return Err(bad_input(format!("--comb-scale {c}: give a finite number")));
    }
    crate::output::require_extension(
        "--csv",
        args.csv.as_deref().unwrap_or(Path::new("a.csv")),
        &["csv"],
    )?;
    crate::output::require_extension(
        "--obj",
        args.obj.as_deref().unwrap_or(Path::new("a.obj")),
        &["obj"],
    )?;
    if !(2..=1024).contains(&args.grid) {
        return Err(bad_input("--grid must be between 2 and 1024"));
    }
    if let Some(count) = args.iso {
        return run_iso(&args, count);
    }
    let (Some(point), Some(normal)) = (args.plane_point, args.plane_normal) else {
        return Err(bad_input(
            "give --plane-point and --plane-normal, or --iso N",
        ));
    };
    let settings = SectionSettings {
        point,
        normal,
        count: args.count,
        spacing: args.spacing,
        comb_scale: args.comb_scale.unwrap_or(1.0),
    };
    // the settings are checked before any file is read
    let probe = fairline::shapes::plane(2);
    if let Err(e) = section::run(&probe, &settings, &Control::new()) {
        return Err(e.into());
    }
    let job = crate::output::Job::new("section")
        .input(&args.input)
        .output_opt("--csv", args.csv.as_deref())
        .output_opt("--obj", args.obj.as_deref())
        .output_opt("--png", args.png.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    let mesh = if crate::surface::is_surface_path(&args.input) {
        let s = crate::surface::load_surfaces(&args.input)?;
        crate::surface::tessellated_mesh(&s, args.grid)?
    } else {
        crate::input::read_triangles(&args.input)?.0
    };
    let mut out = section::run(&mesh, &settings, &Control::new())
        .map_err(|e| crate::output::name_file(&args.input, e))?;
    let scale = args.comb_scale.unwrap_or(1.0);
    if let Some(p) = &args.csv {
        write_csv(p, &out.sections, scale)?;
    }
    if let Some(p) = &args.obj {
        write_obj(p, &out.sections, scale)?;
    }
    if let Some(p) = &args.png {
        let curves: Vec<&SectionCurve> = out.sections.iter().flatten().collect();
        let what = format!("{} plane sections", args.count);
        if let Some(z) = comb_picture(&mesh, &curves, &what, &args, p)? {
            out.report.set("zebra", crate::args::zebra_json(&z));
        }
    }
    print_warnings(&out.report);
    write_report(args.report.as_deref(), &out.report)?;
    job.finish(section::summary(&out, mesh.vertex_count()))?;
    Ok(())
}

/// `--iso N`: the isoparametric curves of a surface file with their combs.
fn run_iso(args: &Args, count: usize) -> Result<()> {
    let settings = IsoSettings {
        count,
        samples: args.samples,
        surface: args.surface,
        comb_scale: args.comb_scale.unwrap_or(1.0),
    };
    // the settings are checked before any file is read (but the index)
    let probe = IsoSettings {
        surface: None,
        ..settings
    };
    section::iso(&[], &probe, &Control::new())?;
    if !crate::surface::is_surface_path(&args.input) {
        return Err(bad_input(format!(
            "{}: --iso is for B-spline surfaces (.json .igs .step); a mesh has no parameter lines",
            args.input.display()
        )));
    }
    let job = crate::output::Job::new("section")
        .input(&args.input)
        .output_opt("--csv", args.csv.as_deref())
        .output_opt("--obj", args.obj.as_deref())
        .output_opt("--png", args.png.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    let surfaces = crate::surface::load_surfaces(&args.input)?;
    let mut out = section::iso(&surfaces, &settings, &Control::new())?;
    let scale = args.comb_scale.unwrap_or(1.0);
    if let Some(p) = &args.csv {
        write_iso_csv(p, &out.curves, scale)?;
    }
    if let Some(p) = &args.obj {
        let curves: Vec<SectionCurve> = out.curves.iter().map(|(_, c)| c.curve.clone()).collect();
        write_obj(p, &[curves], scale)?;
    }
    if let Some(p) = &args.png {
        let part = crate::surface::tessellated_part(&surfaces, 256)?;
        let curves: Vec<&SectionCurve> = out.curves.iter().map(|(_, c)| &c.curve).collect();
        let what = format!("{} iso-curves", curves.len());
        if let Some(z) = comb_picture(&part, &curves, &what, args, p)? {
            out.report.set("zebra", crate::args::zebra_json(&z));
        }
    }
    print_warnings(&out.report);
    write_report(args.report.as_deref(), &out.report)?;
    job.finish(section::iso_summary(&out))?;
    Ok(())
}

/// Longest tooth of a picture with the automatic comb scale, in teeth of
/// the median curvature.
const TOOTH_CAP: f64 = 4.0;

/// The part with `curves` (dark) and their combs: the teeth (every other
/// sample of long curves, at most about 80 per curve) and the line through
/// their tips. The comb scale is `--comb-scale`, else the one that makes
/// the median curvature's tooth 4 % of the part's diagonal, with teeth
/// longer than [`TOOTH_CAP`] of it cut (their count is in the title);
/// with --zebra the reflection zebra under them, which is returned. Written
/// to `png`.
fn comb_picture(
    mesh: &fairline::SurfaceMesh,
    curves: &[&SectionCurve],
    what: &str,
    args: &Args,
    png: &Path,
) -> Result<Option<fairline::render::ReflectionZebra>> {
    use fairline::picture::{Picture, mesh_picture};
    use fairline::render::PolylineLayer;
    let (opts, _) = crate::render::options(mesh, args.view, args.size)?;
    let diagonal = fairline::mesh::bounding_box(mesh.positions())
        .map_or(1.0, |(lo, hi)| (hi - lo).length())
        .max(f64::MIN_POSITIVE);
    let mut kappa: Vec<f64> = curves
        .iter()
        .flat_map(|c| c.curvature.iter().map(|k| k.abs()))
        .filter(|k| k.is_finite() && *k > 1e-12)
        .collect();
    kappa.sort_by(f64::total_cmp);
    let median = kappa.get(kappa.len() / 2).copied().unwrap_or(0.0);
    let (scale, cap) = match args.comb_scale {
        Some(c) => (c, f64::INFINITY),
        None if median > 0.0 => {
            let tooth = 0.04 * diagonal;
            (tooth / median, TOOTH_CAP * tooth)
        }
        None => (0.0, f64::INFINITY),
    };
    let gap = Vec3::splat(f64::NAN);
    let (mut lines, mut teeth, mut tips) = (Vec::new(), Vec::new(), Vec::new());
    let mut cut = 0usize;
    for c in curves {
        lines.extend_from_slice(&c.points);
        if c.closed
            && let Some(&first) = c.points.first()
        {
            lines.push(first);
        }
        lines.push(gap);
        let comb = c.comb(scale);
        let step = c.points.len().div_ceil(80).max(1);
        for (i, (p, t)) in c.points.iter().zip(&comb).enumerate() {
            let len = t.length();
            let t = if len > cap {
                cut += 1;
                *t * (cap / len)
            } else {
                *t
            };
            let tip = *p + t;
            tips.push(if tip.is_finite() { tip } else { gap });
            if i % step == 0 && tip.is_finite() {
                teeth.extend_from_slice(&[*p, tip, gap]);
            }
        }
        tips.push(gap);
    }
    let layer = |points: Vec<Vec3>, color: [f32; 3], width_px: f32| PolylineLayer {
        points,
        closed: false,
        color,
        width_px,
    };
    let mut title = format!("{what}, combs {scale:.2e} per unit curvature (median {median:.2e})");
    if cut > 0 {
        title.push_str(&format!("; {cut} teeth cut at {TOOTH_CAP}x"));
    }
    let zebra = args.zebra.reflection_zebra(mesh, None, &opts)?;
    if let Some(z) = &zebra {
        title.push_str(&format!("; {}", crate::args::zebra_title(z)));
    }
    let picture = Picture {
        polylines: vec![
            layer(teeth, [0.75, 0.2, 0.55], 1.0),
            layer(tips, [0.55, 0.05, 0.4], 1.5),
            layer(lines, [0.02, 0.02, 0.08], 2.0),
        ],
        title: Some(title),
        zebra,
        ..Default::default()
    };
    mesh_picture(mesh, &picture, &opts)?.write_png(png)?;
    Ok(zebra)
}

fn write_iso_csv(path: &Path, curves: &[(usize, IsoCurve)], scale: f64) -> Result<()> {
    use std::io::Write;
    fairline::io::atomic_write(path, |w| {
        let mut w = std::io::BufWriter::new(w);
        writeln!(
            w,
            "surface,kind,value,curve,point,t,x,y,z,curvature,comb_x,comb_y,comb_z"
        )?;
        for (j, (k, c)) in curves.iter().enumerate() {
            let comb = c.curve.comb(scale);
            for (i, p) in c.curve.points.iter().enumerate() {
                let t = comb[i];
                writeln!(
                    w,
                    "{k},{},{},{j},{i},{},{},{},{},{},{},{},{}",
                    c.kind_name(),
                    c.kind_value(),
                    c.params[i],
                    p.x,
                    p.y,
                    p.z,
                    c.curve.curvature[i],
                    t.x,
                    t.y,
                    t.z
                )?;
            }
        }
        w.flush()
    })
    .map_err(|e| anyhow::anyhow!("writing {}: {e}", path.display()))
}

fn write_csv(path: &Path, sections: &[Vec<SectionCurve>], scale: f64) -> Result<()> {
    use std::io::Write;
    fairline::io::atomic_write(path, |w| {
        let mut w = std::io::BufWriter::new(w);
        writeln!(
            w,
            "section,curve,point,x,y,z,curvature,comb_x,comb_y,comb_z"
        )?;
        for (k, s) in sections.iter().enumerate() {
            for (j, c) in s.iter().enumerate() {
                for (i, ((p, kappa), t)) in c
                    .points
                    .iter()
                    .zip(&c.curvature)
                    .zip(c.comb(scale))
                    .enumerate()
                {
                    writeln!(
                        w,
                        "{k},{j},{i},{},{},{},{kappa},{},{},{}",
                        p.x, p.y, p.z, t.x, t.y, t.z
                    )?;
                }
            }
        }
        w.flush()
    })
    .map_err(|e| anyhow::anyhow!("writing {}: {e}", path.display()))
}

/// The sections as OBJ polylines (closed ones repeat their first point),
/// then one two-point line per comb tooth.
fn write_obj(path: &Path, sections: &[Vec<SectionCurve>], scale: f64) -> Result<()> {
    use std::io::Write;
    fairline::io::atomic_write(path, |w| {
        let mut w = std::io::BufWriter::new(w);
        writeln!(w, "# fairline section: section polylines, then comb teeth")?;
        let mut next = 1usize;
        let mut teeth = Vec::new();
        for c in sections.iter().flatten() {
            let first = next;
            for p in &c.points {
                writeln!(w, "v {} {} {}", p.x, p.y, p.z)?;
            }
            next += c.points.len();
            let mut line: Vec<String> = (first..next).map(|i| i.to_string()).collect();
            if c.closed {
                line.push(first.to_string());
            }
            if line.len() >= 2 {
                writeln!(w, "l {}", line.join(" "))?;
            }
            for (p, t) in c.points.iter().zip(c.comb(scale)) {
                teeth.push((*p, *p + t));
            }
        }
        for (a, b) in teeth {
            writeln!(w, "v {} {} {}\nv {} {} {}", a.x, a.y, a.z, b.x, b.y, b.z)?;
            writeln!(w, "l {} {}", next, next + 1)?;
            next += 2;
        }
        w.flush()
    })
    .map_err(|e| anyhow::anyhow!("writing {}: {e}", path.display()))
}
