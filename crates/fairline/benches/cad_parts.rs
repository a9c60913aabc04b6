//! Benchmark of reading and analysing real CAD parts: the
//! impeller (IGES, 277 trimmed faces of ../shared/data) read and its
//! continuity across patch boundaries (`fairline continuity`'s
//! computation), the impeller written as STEP and parsed back (every trim a
//! p-curve beside its exact or fitted 3-D edge, each checked against its
//! edge), and STEP
//! reading of the real part in
//! `tests/data/step/featuretype.STEP` (no p-curves: trims from the 3-D
//! edges) and of the same part written back by fairline (every trim a
//! p-curve, checked against its 3-D edge). Prints medians of the wall time
//! and of the CPU time of all threads (the machine is shared: the CPU time
//! depends less on the load).
//!
//! Run: `cargo bench -p fairline --bench cad_parts`
//! (`FAIRLINE_BENCH_RUNS=N` for the number of runs, default 5).

mod common;

use fairline::bspline::BSplineSurface;
use fairline::bspline::continuity::{ContinuityOptions, continuity};
use fairline::io::read_iges;
use fairline::io::step::{StepWriteOptions, parse_step, read_step, surfaces_to_step};
use std::path::Path;

fn row(task: &str, size: &str, (wall, cpu): (f64, f64)) {
    println!("| {task} | {size} | {:.1} | {:.1} |", wall * 1e3, cpu * 1e3);
}

fn main() {
    let runs = common::runs(5);
    println!(
        "machine: {} threads (rayon); medians of {runs} runs\n",
        rayon::current_num_threads()
    );
    println!("| task | size | wall ms | CPU ms |\n|---|---|---|---|");
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let impeller = manifest.join("../../../shared/data/surfaces/impeller.igs");
    match read_iges(&impeller) {
        Ok(imp) => {
            let surfaces: Vec<BSplineSurface> =
                imp.surfaces.into_iter().map(|s| s.surface).collect();
            let n = surfaces.len();
            row(
                "read impeller.igs",
                &format!("{n} faces"),
                common::median_wall_cpu(runs, || read_iges(&impeller).map(|i| i.surfaces.len())),
            );
            let opts = ContinuityOptions::default();
            let result = continuity(&surfaces, &opts).ok();
            let edges = result.as_ref().map_or(0, |r| r.seams.len());
            row(
                "continuity of impeller.igs (default options)",
                &format!("{n} faces, {edges} shared edges"),
                common::median_wall_cpu(runs, || {
                    continuity(&surfaces, &opts).map(|r| r.seams.len())
                }),
            );
            if let Ok(text) = surfaces_to_step(&surfaces, &StepWriteOptions::default()) {
                let t = parse_step(&text)
                    .map(|i| i.trim_sources)
                    .unwrap_or_default();
                row(
                    "parse impeller.igs written as STEP (trims from p-curves)",
                    &format!(
                        "{n} faces, {} p-curves, {} rejected",
                        t.pcurve, t.pcurve_rejected
                    ),
                    common::median_wall_cpu(runs, || parse_step(&text).map(|i| i.surfaces.len())),
                );
            }
        }
        Err(e) => println!("(impeller skipped: {e})"),
    }
    let featuretype = manifest.join("tests/data/step/featuretype.STEP");
    match read_step(&featuretype) {
        Ok(imp) => {
            let t = imp.trim_sources;
            row(
                "read featuretype.STEP (trims from 3-D edges)",
                &format!("{} faces, {} edges", imp.surfaces.len(), t.edge),
                common::median_wall_cpu(runs, || read_step(&featuretype).map(|i| i.surfaces.len())),
            );
            let surfaces: Vec<BSplineSurface> =
                imp.surfaces.into_iter().map(|s| s.surface).collect();
            let written = surfaces_to_step(&surfaces, &StepWriteOptions::default());
            if let Ok(text) = written {
                let back = parse_step(&text).map(|i| i.trim_sources);
                let pcurves = back.map_or(0, |t| t.pcurve);
                row(
                    "parse featuretype written back (trims from p-curves)",
                    &format!("{} faces, {pcurves} p-curves", surfaces.len()),
                    common::median_wall_cpu(runs, || parse_step(&text).map(|i| i.surfaces.len())),
                );
            }
        }
        Err(e) => println!("(featuretype skipped: {e})"),
    }
}
