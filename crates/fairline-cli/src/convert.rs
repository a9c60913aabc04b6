//! `fairline convert`: mesh format conversion.

use crate::common::Report;
use crate::output::Job;
use anyhow::Result;
use std::path::PathBuf;

/// Converts between mesh formats by extension (.obj .ply .off .stl). Polygons
/// are kept where the format allows (STL is triangulated). Coordinates are
/// written exactly (shortest round-trip decimal, or binary doubles in PLY).
/// B-spline surfaces (.igs/.iges, .json) convert to surface JSON (all
/// entity-128 surfaces, exact), or to a mesh (tessellated, 64 × 64 per surface).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline convert fairline-demo/wavy.obj wavy.ply\n  fairline convert fairline-demo/bspline-panel-dented.json panel-mesh.obj"
)]
pub struct Args {
    /// Input mesh.
    pub input: PathBuf,
    /// Output mesh; never the input file.
    pub output: PathBuf,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    let job = Job::new("convert")
        .input(&args.input)
        .output("OUT", &args.output)
        .output_opt("--report", args.report.as_deref())
        .check()?;
    if crate::surface::is_surface_path(&args.input) {
        let surfaces = crate::surface::load_surfaces(&args.input)?;
        let mut report = Report::new("convert");
        report.set("surfaces", surfaces.len());
        if crate::surface::is_surface_path(&args.output) {
            let ext = args
                .output
                .extension()
                .and_then(|e| e.to_str())
                .unwrap_or("");
            if !ext.eq_ignore_ascii_case("json") {
                return Err(crate::common::bad_input(format!(
                    "{}: surfaces are written as .json (IGES output is not supported)",
                    args.output.display()
                )));
            }
            fairline::bspline::write_surfaces_json(&args.output, &surfaces)?;
            report.write(args.report.as_deref())?;
            job.finish(format_args!("{} surface(s) converted", surfaces.len()));
            return Ok(());
        } else {
            let mesh = crate::surface::tessellated_mesh(&surfaces, 64)?;
            report.set("vertices", mesh.vertex_count());
            report.set("faces", mesh.face_count());
            fairline::io::write_mesh(&args.output, &mesh)?;
            report.write(args.report.as_deref())?;
            job.finish(format_args!(
                "{} surface(s) tessellated to {} vertices, {} faces",
                surfaces.len(),
                mesh.vertex_count(),
                mesh.face_count()
            ));
        }
        return Ok(());
    }
    let soup = fairline::io::read_soup(&args.input)?;
    let mut report = Report::new("convert");
    report.set("vertices", soup.vertex_count());
    report.set("faces", soup.face_count());
    fairline::io::write_soup(&args.output, &soup)?;
    report.write(args.report.as_deref())?;
    job.finish(format_args!(
        "{} vertices, {} faces converted",
        soup.vertex_count(),
        soup.face_count()
    ));
    Ok(())
}
