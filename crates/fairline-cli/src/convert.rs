//! `fairline convert`: mesh format conversion.

use crate::common::Report;
use crate::output::Job;
use anyhow::Result;
use std::path::PathBuf;

/// Converts between mesh formats by extension (.obj .ply .off .stl). Polygons
/// are kept where the format allows (STL is triangulated). Coordinates are
/// written exactly (shortest round-trip decimal, or binary doubles in PLY).
/// B-spline surfaces (.json, .igs/.iges, .step/.stp) convert between these
/// three formats by extension, exactly (control points, knots, weights and
/// trimming curves bit-identical; the length unit kept), or to a mesh
/// (tessellated, 64 × 64 per surface); GoTools (.g2) and geomdl JSON are
/// read and convert to any of them.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline convert fairline-demo/wavy.obj wavy.ply\n  fairline convert fairline-demo/bspline-panel-dented.json panel-mesh.obj\n  fairline convert fairline-demo/bspline-panel-dented.json panel.igs\n  fairline convert fairline-demo/bspline-panel-dented.json panel.step"
)]
pub struct Args {
    /// Input mesh or surface file.
    pub input: PathBuf,
    /// Output mesh or surface file; never the input file.
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
    if crate::surface::is_surface_path(&args.output)
        && !crate::surface::is_writable_surface_path(&args.output)
    {
        return Err(crate::error::bad_input(format!(
            "{}: fairline reads this surface format but does not write it (write .json, .igs/.iges or .step/.stp)",
            args.output.display()
        )));
    }
    if crate::surface::is_surface_path(&args.input) {
        let input = crate::surface::load_surface_file(&args.input)?;
        let mut report = Report::new("convert");
        // reached only with --skip-unreadable (load_surface_file fails
        // otherwise): the faces left out go into the report too
        if let Some(msg) = input.unreadable_summary(crate::surface::UNREADABLE_NAMED, None) {
            report.warn(format!(
                "{}: {msg}; written without them",
                args.input.display()
            ));
        }
        let surfaces = input.surfaces;
        report.set("surfaces", surfaces.len());
        report.set(
            "trimmed",
            surfaces.iter().filter(|s| s.is_trimmed()).count(),
        );
        if crate::surface::is_surface_path(&args.output) {
            fairline::io::surface_file::write_surface_file(
                &args.output,
                &surfaces,
                input.unit.as_ref(),
            )?;
            report.write(args.report.as_deref())?;
            job.finish(format_args!(
                "{} surface(s) converted ({} trimmed)",
                surfaces.len(),
                surfaces.iter().filter(|s| s.is_trimmed()).count()
            ))?;
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
            ))?;
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
    ))?;
    Ok(())
}
