//! `fairline convert`: mesh format conversion.

use crate::common::{Report, check_output};
use anyhow::Result;
use std::path::PathBuf;

/// Converts between mesh formats by extension (.obj .ply .off .stl). Polygons
/// are kept where the format allows (STL is triangulated). Coordinates are
/// written exactly (shortest round-trip decimal, or binary doubles in PLY).
#[derive(clap::Args, Debug)]
#[command(after_help = "Example:\n  fairline convert bunny.obj bunny.ply")]
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
    check_output(&args.input, &args.output)?;
    let soup = fairline::io::read_soup(&args.input)?;
    let mut report = Report::new("convert");
    report.set("vertices", soup.vertex_count());
    report.set("faces", soup.face_count());
    fairline::io::write_soup(&args.output, &soup)?;
    report.write(args.report.as_deref())?;
    Ok(())
}
