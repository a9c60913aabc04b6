//! `fairline info`: counts and defects of a mesh file.

use crate::common::Report;
use crate::output::{Job, print_stdout};
use anyhow::Result;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Counts and defects of a mesh: vertices, faces, edges, boundary loops,
/// non-manifold edges and vertices, components, genus, degenerate faces,
/// bounding box, edge lengths. Works on broken (non-manifold, invalid) files
/// too: it reports the defects instead of refusing.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example:\n  fairline demo --out fairline-demo\n  fairline info fairline-demo/sphere.ply --json"
)]
pub struct Args {
    /// Mesh file (.obj .ply .off .stl).
    pub mesh: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Also write the JSON to this file.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    let job = Job::new("info")
        .input(&args.mesh)
        .output_opt("--report", args.report.as_deref())
        .check()?;
    let soup = fairline::io::read_soup(&args.mesh)?;
    let mut report = Report::new("info");
    let info = report.time(|| fairline::mesh::inspect(&soup));
    let mut value = serde_json::to_value(&info)?;
    // Absent values (no genus for a non-manifold mesh, no manifold error for
    // a manifold one) are left out rather than written as null.
    if let serde_json::Value::Object(m) = &mut value {
        m.retain(|_, v| !v.is_null());
        for (k, v) in m.iter() {
            report.set(k, v);
        }
    }
    // the same values without non-finite numbers (report.set warned)
    let value = crate::common::finite_only("", value, &mut Vec::new()).unwrap_or_default();
    report.write(args.report.as_deref())?;
    let summary = format!(
        "{}: {} vertices, {} faces, {}",
        args.mesh.display(),
        info.vertices,
        info.faces,
        if info.manifold_error.is_none() {
            "manifold"
        } else {
            "not a manifold"
        }
    );
    if args.json {
        print_stdout(&format!("{}\n", serde_json::to_string_pretty(&value)?))?;
        job.finish(summary);
        return Ok(());
    }
    let mut out = String::new();
    let sizes: Vec<String> = info
        .face_sizes
        .iter()
        .map(|(k, v)| format!("{v} with {k} vertices"))
        .collect();
    let _ = writeln!(out, "file                {}", args.mesh.display());
    let _ = writeln!(out, "vertices            {}", info.vertices);
    let _ = writeln!(
        out,
        "faces               {} ({})",
        info.faces,
        sizes.join(", ")
    );
    let _ = writeln!(out, "edges               {}", info.edges);
    let _ = writeln!(
        out,
        "boundary edges      {} in {} loops",
        info.boundary_edges, info.boundary_loops
    );
    let _ = writeln!(out, "components          {}", info.components);
    let _ = match info.genus {
        Some(g) => writeln!(out, "genus               {g}"),
        None => writeln!(out, "genus               undefined (not a manifold)"),
    };
    let _ = writeln!(out, "euler               {}", info.euler_characteristic);
    let _ = writeln!(
        out,
        "bbox                [{:.6}, {:.6}, {:.6}] – [{:.6}, {:.6}, {:.6}]",
        info.bbox.min[0],
        info.bbox.min[1],
        info.bbox.min[2],
        info.bbox.max[0],
        info.bbox.max[1],
        info.bbox.max[2]
    );
    let _ = writeln!(
        out,
        "edge length         min {:.6}  mean {:.6}  max {:.6}",
        info.edge_length.min, info.edge_length.mean, info.edge_length.max
    );
    let _ = writeln!(out, "area                {:.6}", info.area);
    let defects = [
        ("non-manifold edges", info.non_manifold_edges),
        (
            "face incidences on non-manifold edges",
            info.non_manifold_edge_incidences,
        ),
        ("duplicate faces", info.duplicate_faces),
        ("non-manifold vertices", info.non_manifold_vertices),
        (
            "inconsistently oriented edges",
            info.inconsistently_oriented_edges,
        ),
        ("invalid faces", info.invalid_faces),
        ("degenerate faces", info.degenerate_faces),
        ("isolated vertices", info.isolated_vertices),
        ("non-finite vertices", info.non_finite_vertices),
    ];
    for (name, n) in defects {
        if n > 0 {
            let _ = writeln!(out, "DEFECT              {n} {name}");
        }
    }
    let _ = match &info.manifold_error {
        None if info.non_manifold_vertices > 0 => writeln!(
            out,
            "manifold            yes, once its {} non-manifold vertices are split per fan (every command does this)",
            info.non_manifold_vertices
        ),
        None => writeln!(out, "manifold            yes"),
        Some(e) => writeln!(
            out,
            "manifold            no: {e}
hint                run `fairline repair {} OUT` to repair it",
            args.mesh.display()
        ),
    };
    print_stdout(&out)?;
    job.finish(summary);
    Ok(())
}
