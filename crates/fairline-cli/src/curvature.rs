//! `fairline curvature`: per-vertex principal curvatures written as PLY.

use crate::args::choice;
use crate::common::write_report;
use crate::output::spinner;
use anyhow::Result;
use fairline::Control;
use fairline::geom::CurvatureMethod;
use fairline_commands::curvature::{self, CurvatureSettings};
use fairline_commands::{Choice, Subject};
use std::path::PathBuf;

/// Per-vertex curvature as a binary PLY with double vertex properties
/// `x y z nx ny nz k1 k2 mean gauss d1x d1y d1z d2x d2y d2z`.
/// k1 ≥ k2, signed: a sphere of radius r with outward normals gives +1/r.
/// Polygon meshes are triangulated first (vertices unchanged).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline curvature fairline-demo/sphere.ply -o sphere-curvature.ply --method rusinkiewicz --report r.json"
)]
pub struct Args {
    /// Input mesh.
    pub mesh: PathBuf,
    /// Output PLY file.
    #[arg(short, long, value_name = "OUT.ply")]
    pub output: PathBuf,
    /// Estimator.
    #[arg(long, value_parser = choice::<CurvatureMethod>(), default_value = "rusinkiewicz")]
    pub method: CurvatureMethod,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    crate::output::require_extension("-o", &args.output, &["ply"])?;
    let job = crate::output::Job::new("curvature")
        .input(&args.mesh)
        .output("-o", &args.output)
        .output_opt("--report", args.report.as_deref())
        .check()?;
    let mesh = crate::input::read_mesh(&args.mesh)?;
    crate::input::note_split_vertices(&args.mesh, &mesh);
    let settings = CurvatureSettings {
        method: args.method,
    };
    let bar = spinner("curvature");
    let result = curvature::run(&mesh, &settings, &Control::new());
    bar.finish_and_clear();
    let result = result.map_err(|e| {
        let about_input = e.subject() == Some(Subject::Input);
        let e = anyhow::Error::new(e);
        if about_input {
            e.context(args.mesh.display().to_string())
        } else {
            e
        }
    })?;
    let out = &result.output;
    let (c, mean, gauss) = (&out.fields, &out.mean, &out.gauss);
    let triangulated = out.report.triangulated;
    let comp =
        |f: fn(&fairline::Vec3) -> f64, v: &[fairline::Vec3]| v.iter().map(f).collect::<Vec<f64>>();
    let n = [
        comp(|v| v.x, &c.normals),
        comp(|v| v.y, &c.normals),
        comp(|v| v.z, &c.normals),
    ];
    let d1 = [
        comp(|v| v.x, &c.d1),
        comp(|v| v.y, &c.d1),
        comp(|v| v.z, &c.d1),
    ];
    let d2 = [
        comp(|v| v.x, &c.d2),
        comp(|v| v.y, &c.d2),
        comp(|v| v.z, &c.d2),
    ];
    let cols: [(&str, &[f64]); 13] = [
        ("nx", &n[0]),
        ("ny", &n[1]),
        ("nz", &n[2]),
        ("k1", &c.k1),
        ("k2", &c.k2),
        ("mean", mean),
        ("gauss", gauss),
        ("d1x", &d1[0]),
        ("d1y", &d1[1]),
        ("d1z", &d1[2]),
        ("d2x", &d2[0]),
        ("d2y", &d2[1]),
        ("d2z", &d2[2]),
    ];
    // one row per input vertex: a split non-manifold vertex takes the values
    // of the fan that kept its index
    let props: Vec<(&str, &[f64])> = cols
        .iter()
        .map(|&(name, v)| (name, mesh.original_values(v)))
        .collect();
    fairline::io::write_ply_with_vertex_properties(&args.output, &mesh.to_soup(), &props)?;
    write_report(args.report.as_deref(), &result.report)?;
    job.finish(format_args!(
        "{} curvature of {} vertices{}",
        args.method.name(),
        mesh.vertex_count(),
        if triangulated {
            " (polygons triangulated)"
        } else {
            ""
        }
    ))?;
    Ok(())
}
