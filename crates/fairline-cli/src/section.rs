//! `fairline section`: plane sections of a mesh (or of surfaces,
//! tessellated) as polylines with their curvature combs; with `--iso`,
//! isoparametric curves of B-spline surfaces with their exact combs.

use crate::args::parse_vec3;
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
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline section fairline-demo/sphere.ply --plane-point 0,0,0 --plane-normal 0,0,1 --csv sections.csv\n  fairline section fairline-demo/dented-panel.obj --plane-point 0,-1.5,0 --plane-normal 0,1,0 --count 7 --spacing 0.5 --comb-scale 0.2 --obj sections.obj --report sections.json\n  fairline section fairline-demo/bspline-panel-dented.json --iso 7 --comb-scale 0.5 --obj combs.obj --csv combs.csv"
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
    /// Length of the comb per unit curvature.
    #[arg(long, default_value_t = 1.0)]
    pub comb_scale: f64,
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
    /// Tessellation grid per patch and direction for plane sections of
    /// surface files.
    #[arg(long, default_value_t = 64, value_name = "N")]
    pub grid: usize,
}

pub fn run(args: Args) -> Result<()> {
    if args.csv.is_none() && args.obj.is_none() && args.report.is_none() {
        return Err(bad_input("nothing to write: give --csv, --obj or --report"));
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
        comb_scale: args.comb_scale,
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
        .output_opt("--report", args.report.as_deref())
        .check()?;
    let mesh = if crate::surface::is_surface_path(&args.input) {
        let s = crate::surface::load_surfaces(&args.input)?;
        crate::surface::tessellated_mesh(&s, args.grid)?
    } else {
        crate::input::read_triangles(&args.input)?.0
    };
    let out = section::run(&mesh, &settings, &Control::new())
        .map_err(|e| crate::output::name_file(&args.input, e))?;
    if let Some(p) = &args.csv {
        write_csv(p, &out.sections, args.comb_scale)?;
    }
    if let Some(p) = &args.obj {
        write_obj(p, &out.sections, args.comb_scale)?;
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
        comb_scale: args.comb_scale,
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
        .output_opt("--report", args.report.as_deref())
        .check()?;
    let surfaces = crate::surface::load_surfaces(&args.input)?;
    let out = section::iso(&surfaces, &settings, &Control::new())?;
    if let Some(p) = &args.csv {
        write_iso_csv(p, &out.curves, args.comb_scale)?;
    }
    if let Some(p) = &args.obj {
        let curves: Vec<SectionCurve> = out.curves.iter().map(|(_, c)| c.curve.clone()).collect();
        write_obj(p, &[curves], args.comb_scale)?;
    }
    print_warnings(&out.report);
    write_report(args.report.as_deref(), &out.report)?;
    job.finish(section::iso_summary(&out))?;
    Ok(())
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
