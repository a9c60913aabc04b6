//! `fairline info`: counts and defects of a mesh file.

use crate::common::Report;
use anyhow::Result;
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
    let soup = fairline::io::read_soup(&args.mesh)?;
    let mut report = Report::new("info");
    let info = report.time(|| fairline::mesh::inspect(&soup));
    let value = serde_json::to_value(&info)?;
    if let serde_json::Value::Object(m) = &value {
        for (k, v) in m {
            report.set(k, v);
        }
    }
    report.write(args.report.as_deref())?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&value)?);
        return Ok(());
    }
    let sizes: Vec<String> = info
        .face_sizes
        .iter()
        .map(|(k, v)| format!("{v} with {k} vertices"))
        .collect();
    println!("file                {}", args.mesh.display());
    println!("vertices            {}", info.vertices);
    println!("faces               {} ({})", info.faces, sizes.join(", "));
    println!("edges               {}", info.edges);
    println!(
        "boundary edges      {} in {} loops",
        info.boundary_edges, info.boundary_loops
    );
    println!("components          {}", info.components);
    match info.genus {
        Some(g) => println!("genus               {g}"),
        None => println!("genus               undefined (not a manifold)"),
    }
    println!("euler               {}", info.euler_characteristic);
    println!(
        "bbox                [{:.6}, {:.6}, {:.6}] – [{:.6}, {:.6}, {:.6}]",
        info.bbox.min[0],
        info.bbox.min[1],
        info.bbox.min[2],
        info.bbox.max[0],
        info.bbox.max[1],
        info.bbox.max[2]
    );
    println!(
        "edge length         min {:.6}  mean {:.6}  max {:.6}",
        info.edge_length.min, info.edge_length.mean, info.edge_length.max
    );
    println!("area                {:.6}", info.area);
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
            println!("DEFECT              {n} {name}");
        }
    }
    match &info.manifold_error {
        None => println!("manifold            yes"),
        Some(e) => println!("manifold            no: {e}"),
    }
    Ok(())
}
