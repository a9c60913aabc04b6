//! `fairline section`: plane sections of a mesh (or of surfaces,
//! tessellated) as polylines with their curvature combs.

use crate::args::parse_vec3;
use crate::common::{print_warnings, write_report};
use crate::error::bad_input;
use anyhow::Result;
use fairline::geom::SectionCurve;
use fairline::{Control, Vec3};
use fairline_commands::section::{self, SectionSettings};
use std::path::{Path, PathBuf};

/// Cuts the surface with `--count` parallel planes `--spacing` apart (the
/// first through `--plane-point`, normal `--plane-normal`) and writes the
/// section polylines with the curvature of each point (the circle through
/// it and its neighbours) and its comb vector −scale·κ·m (m towards the
/// centre of curvature: the comb stands on the convex side). Polygons are
/// triangulated, surface files (.json .igs .step) tessellated (--grid).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline section fairline-demo/sphere.ply --plane-point 0,0,0 --plane-normal 0,0,1 --csv sections.csv\n  fairline section fairline-demo/dented-panel.obj --plane-point 0,-1.5,0 --plane-normal 0,1,0 --count 7 --spacing 0.5 --comb-scale 0.2 --obj sections.obj --report sections.json"
)]
pub struct Args {
    /// Mesh (.obj .ply .off .stl) or surfaces (.json .igs .step).
    pub input: PathBuf,
    /// A point of the first plane X,Y,Z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub plane_point: Vec3,
    /// The planes' normal X,Y,Z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub plane_normal: Vec3,
    /// Number of parallel planes.
    #[arg(long, default_value_t = 1)]
    pub count: usize,
    /// Distance between the planes (along the normal).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub spacing: f64,
    /// Length of the comb per unit curvature.
    #[arg(long, default_value_t = 1.0)]
    pub comb_scale: f64,
    /// Points as CSV: `section,curve,point,x,y,z,curvature,comb_x,comb_y,comb_z`.
    #[arg(long, value_name = "OUT.csv")]
    pub csv: Option<PathBuf>,
    /// Polylines as OBJ lines (`l`): the sections, then the comb teeth.
    #[arg(long, value_name = "OUT.obj")]
    pub obj: Option<PathBuf>,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
    /// Tessellation grid per patch and direction for surface files.
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
    let settings = SectionSettings {
        point: args.plane_point,
        normal: args.plane_normal,
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
