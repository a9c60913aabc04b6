//! `fairline repair`: turns a dirty mesh into one every command accepts, and
//! the hint every refusal of dirty input ends with.

use crate::common::{print_warnings, write_report};
use crate::output::{Job, say};
use anyhow::Result;
use fairline::Control;
use fairline_commands::repair;
use std::path::PathBuf;

/// Repairs a dirty mesh: splits non-manifold edges and vertices, removes
/// unreferenced vertices and duplicate (same vertex set) and zero-area
/// faces, and makes the orientation consistent where it can. Every kept
/// vertex keeps its coordinates bit-identical and its order; split copies
/// are appended at the end. The report lists every change (removed faces
/// with the reason, removed vertices, split edges and vertices, reversed
/// faces, and `vertex_source`, the input vertex of each output vertex, when
/// the vertex list changed).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example:\n  fairline repair fairline-demo/sphere.ply sphere-repaired.ply --report repair.json"
)]
pub struct Args {
    /// Input mesh (.obj .ply .off .stl).
    pub input: PathBuf,
    /// Output mesh; never the input file.
    pub output: PathBuf,
    /// Write a JSON report of every change.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    let job = Job::new("repair")
        .input(&args.input)
        .output("OUT", &args.output)
        .output_opt("--report", args.report.as_deref())
        .check()?;
    let soup = fairline::io::read_soup(&args.input)?;
    crate::input::require_faces(&args.input, soup.face_count(), soup.vertex_count())?;
    let bar = crate::output::spinner("repairing");
    let out = repair::run(&soup, &Control::new())
        .map_err(|e| anyhow::Error::new(e).context(args.input.display().to_string()))?;
    bar.finish_and_clear();
    fairline::io::write_soup(&args.output, &out.repaired.soup)?;
    let r = &out.repaired.report;
    write_report(args.report.as_deref(), &out.report)?;
    let count = |reason| {
        r.removed_faces
            .iter()
            .filter(|f| f.reason == reason)
            .count()
    };
    use fairline::mesh::RemovalReason as R;
    let changes = [
        (count(R::Duplicate), "duplicate faces removed"),
        (count(R::ZeroArea), "zero-area faces removed"),
        (
            count(R::InvalidIndex) + count(R::TooFewVertices) + count(R::RepeatedVertex),
            "invalid faces removed",
        ),
        (
            count(R::NonManifoldEdge),
            "faces removed from edges that could not be split",
        ),
        (
            r.collapsed_faces.len(),
            "faces with a repeated vertex collapsed",
        ),
        (r.split_edges.len(), "non-manifold edges split"),
        (r.split_vertices.len(), "non-manifold vertices split"),
        (
            r.flipped_faces.len(),
            "faces reversed for a consistent orientation",
        ),
        (r.removed_vertices.len(), "unreferenced vertices removed"),
    ];
    for (n, what) in changes {
        if n > 0 {
            say(&format!("  {n} {what}"));
        }
    }
    print_warnings(&out.report);
    job.finish(format_args!(
        "{}: {} vertices, {} faces → {} vertices, {} faces{}",
        args.input.display(),
        r.vertices_before,
        r.faces_before,
        r.vertices_after,
        r.faces_after,
        if r.unchanged() {
            " (nothing to repair)"
        } else if r.vertex_source.is_empty() {
            ""
        } else {
            "; vertex indices changed (see vertex_source in the report)"
        }
    ))?;
    Ok(())
}

/// The hint appended to a refusal of dirty input: which file to repair and
/// how, or `None` when the error is not about a repairable mesh.
pub fn hint(err: &anyhow::Error) -> Option<String> {
    let io = err
        .chain()
        .find_map(|c| c.downcast_ref::<fairline::io::IoError>())?;
    let fairline::io::IoError::Mesh { path, source } = io else {
        return None;
    };
    fairline_commands::repair::repair_hint(source, fairline_commands::FrontEnd::Cli, Some(path))
}
