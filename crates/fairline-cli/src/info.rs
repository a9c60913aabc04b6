//! `fairline info`: counts and defects of a mesh file, or the contents of a
//! surface file (.json, .igs/.iges, .step/.stp, .g2).

use crate::common::{print_warnings, write_report};
use crate::output::{Job, print_stdout};
use anyhow::Result;
use fairline::Control;
use fairline_commands::info;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Counts and defects of a mesh: vertices, faces, edges, boundary loops,
/// non-manifold edges and vertices, components, genus, degenerate faces,
/// bounding box, edge lengths. Works on broken (non-manifold, invalid) files
/// too: it reports the defects instead of refusing. For a surface file
/// (.json, .igs/.iges, .step/.stp, .g2): surfaces, trimmed and rational ones,
/// degrees, control points, length unit, bounding box and (`--area`) the
/// total trimmed area.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example:\n  fairline demo --out fairline-demo\n  fairline info fairline-demo/sphere.ply --json\n  fairline info fairline-demo/bspline-panel-dented.json --area"
)]
pub struct Args {
    /// Mesh file (.obj .ply .off .stl) or surface file (.json .igs .step).
    pub mesh: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Surface files: also compute the total trimmed area (Gauss quadrature
    /// on a 64 × 64 grid per surface: 3 × 3 Gauss–Legendre in the cells
    /// inside the face, the 6-point triangle rule in the cells the trims
    /// cut; faces in parallel).
    #[arg(long)]
    pub area: bool,
    /// Also write the JSON to this file.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    let job = Job::new("info")
        .input(&args.mesh)
        .output_opt("--report", args.report.as_deref())
        .check()?;
    if crate::surface::is_surface_path(&args.mesh) {
        return surface_info(&args, &job);
    }
    let soup = fairline::io::read_soup(&args.mesh)?;
    let bar = crate::output::spinner("inspecting");
    let name = args.mesh.display().to_string();
    let out = info::mesh(&soup, Some(&name), &Control::new());
    bar.finish_and_clear();
    let (info, value) = (&out.info, &out.value);
    let has_bbox = info.vertices > info.non_finite_vertices;
    print_warnings(&out.report);
    write_report(args.report.as_deref(), &out.report)?;
    let summary = format!(
        "{}: {} vertices, {} faces, {}",
        args.mesh.display(),
        info.vertices,
        info.faces,
        if info.faces == 0 {
            "no surface"
        } else if info.manifold_error.is_none() {
            "manifold"
        } else {
            "not a manifold"
        }
    );
    if args.json {
        print_stdout(&format!("{}\n", serde_json::to_string_pretty(value)?))?;
        job.finish(summary)?;
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
        None if info.faces == 0 => writeln!(out, "genus               undefined (no faces)"),
        None => writeln!(out, "genus               undefined (not a manifold)"),
    };
    let _ = writeln!(out, "euler               {}", info.euler_characteristic);
    let _ = if has_bbox {
        writeln!(
            out,
            "bbox                [{:.6}, {:.6}, {:.6}] – [{:.6}, {:.6}, {:.6}]",
            info.bbox.min[0],
            info.bbox.min[1],
            info.bbox.min[2],
            info.bbox.max[0],
            info.bbox.max[1],
            info.bbox.max[2]
        )
    } else {
        writeln!(out, "bbox                none (no finite vertex)")
    };
    let _ = if info.edges > 0 {
        writeln!(
            out,
            "edge length         min {:.6}  mean {:.6}  max {:.6}",
            info.edge_length.min, info.edge_length.mean, info.edge_length.max
        )
    } else {
        writeln!(out, "edge length         none (no edges)")
    };
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
        None if info.faces == 0 => writeln!(out, "manifold            no surface (no faces)"),
        None => writeln!(out, "manifold            yes"),
        Some(e) => writeln!(
            out,
            "manifold            no: {e}
hint                run `fairline repair {} OUT` to repair it",
            args.mesh.display()
        ),
    };
    print_stdout(&out)?;
    job.finish(summary)?;
    Ok(())
}

/// `info` of a surface file: what it holds, in its own unit.
fn surface_info(args: &Args, job: &Job) -> Result<()> {
    let file = crate::surface::load_surface_file_listing(&args.mesh)?;
    let surfaces = &file.surfaces;
    let name = args.mesh.display().to_string();
    let out = info::surfaces(
        &file,
        args.area,
        Some(&name),
        crate::surface::UNREADABLE_NAMED,
        &Control::new(),
    );
    let (trimmed, rational, max_degree) = (out.trimmed, out.rational, out.max_degree);
    let (control_points, area, unit) = (out.control_points, out.area, &out.unit);
    let (unreadable, bounding_box) = (out.unreadable.clone(), out.bounding_box);
    print_warnings(&out.report);
    write_report(args.report.as_deref(), &out.report)?;
    let summary = format!(
        "{}: {} surface(s), {trimmed} trimmed, {rational} rational",
        args.mesh.display(),
        surfaces.len()
    );
    if args.json {
        print_stdout(&format!(
            "{}\n",
            serde_json::to_string_pretty(&out.report.to_json())?
        ))?;
    } else {
        let mut text = String::new();
        let _ = writeln!(text, "file                {}", args.mesh.display());
        let _ = writeln!(
            text,
            "surfaces            {} ({trimmed} trimmed, {rational} rational, degree <= {max_degree})",
            surfaces.len()
        );
        let _ = writeln!(text, "control points      {control_points}");
        let _ = writeln!(
            text,
            "unit                {}",
            unit.as_deref().unwrap_or("(none)")
        );
        if let Some((lo, hi)) = bounding_box {
            let _ = writeln!(
                text,
                "bounding box        ({}, {}, {}) .. ({}, {}, {}) (of the faces)",
                human(lo.x),
                human(lo.y),
                human(lo.z),
                human(hi.x),
                human(hi.y),
                human(hi.z)
            );
        } else {
            let _ = writeln!(text, "bounding box        (none: no face was read)");
        }
        if let Some(a) = area {
            let _ = writeln!(text, "area                {} (trimmed faces)", human(a));
        }
        for u in &file.unreadable {
            let _ = writeln!(text, "NOT READ            {u}");
        }
        print_stdout(&text)?;
    }
    if let Some(msg) = unreadable
        && !crate::surface::skip_unreadable()
    {
        return Err(crate::surface::unreadable_error(&args.mesh, &msg));
    }
    job.finish(summary)?;
    Ok(())
}

/// A number as a person writes it: 7 significant digits, no trailing
/// zeros, no exponent between 1e-4 and 1e12 (`28617.1`, `-0.5`, `12`).
fn human(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{}", if x == 0.0 { 0.0 } else { x });
    }
    let mag = x.abs().log10().floor() as i32;
    if !(-4..12).contains(&mag) {
        let t = format!("{x:.6e}");
        let (m, e) = t.split_once('e').unwrap_or((&t, "0"));
        let m = m.trim_end_matches('0').trim_end_matches('.');
        return format!("{m}e{e}");
    }
    let decimals = (6 - mag).max(0) as usize;
    let t = format!("{x:.decimals$}");
    let t = if t.contains('.') {
        t.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        t
    };
    if t == "-0" { "0".into() } else { t }
}

#[cfg(test)]
mod tests {
    #[test]
    fn numbers_print_as_a_person_writes_them() {
        use super::human;
        assert_eq!(human(28617.096341), "28617.1");
        assert_eq!(human(-15.000000001346898), "-15");
        assert_eq!(human(0.5), "0.5");
        assert_eq!(human(2.0e-7), "2e-7");
        assert_eq!(human(-1.25e-16), "-1.25e-16");
        assert_eq!(human(0.0), "0");
        assert_eq!(human(123456789.0), "123456789");
    }
}
