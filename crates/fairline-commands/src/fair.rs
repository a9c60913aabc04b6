//! `fair`: highlight-line fairing of a triangle mesh inside regions (Yong
//! et al. §3, Algorithm 2) — the region given, or with `auto` the regions
//! detection finds — with the detection score measured before and after,
//! as the CLI, the Python package and the workbench all run it.

use crate::error::{CommandError, Subject};
use crate::lights::Lights;
use crate::names::Choice;
use crate::regions::{
    AUTO_RINGS, detect_regions_to_fair, fairing_made_worse, regions_deviation, regions_report,
    regions_union, regions_warnings,
};
use crate::report::Report;
use crate::warning::{RemainingDefect, Warning};
use crate::{Note, words};
use fairline::fair::{
    FairError, FairMethod, FairOptions, FairReport, fair_highlight_lines, grow_region,
};
use fairline::highlight::{LightArray, RegionDetection, detect_region};
use fairline::mesh::FaceId;
use fairline::{Control, Progress, SurfaceMesh, Vec3};
use serde_json::{Value, json};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// The options of `fair` (defaults: the CLI's).
#[derive(Clone, Debug, PartialEq)]
pub struct FairSettings {
    /// Detect the irregular regions and fair each in turn (no region is
    /// given then).
    pub auto: bool,
    /// Rings of faces added to every region before fairing.
    pub grow: usize,
    /// The lights (detection at these, fairing at their readable lights).
    pub lights: Lights,
    /// Most iterations N_max per region.
    pub max_iterations: usize,
    /// Stop when max|x_i| / mean edge length < epsilon (Eq. (17)).
    pub epsilon: f64,
    /// The energy to minimise.
    pub method: FairMethod,
    /// Weight ω1 of the Willmore energy.
    pub fair_weight: f64,
    /// Weight ω2 of the highlight-line difference energy.
    pub diff_weight: f64,
    /// Weight ω3 of the curvature-Laplacian term.
    pub laplacian_weight: f64,
    /// Least change ([`FairOptions::least_change`]): the highlight result
    /// only where it dominates the diffusion-flow state (default true).
    pub least_change: bool,
}

impl Default for FairSettings {
    fn default() -> Self {
        let d = FairOptions::default();
        FairSettings {
            auto: false,
            grow: 0,
            lights: Lights::default(),
            max_iterations: d.max_iterations,
            epsilon: d.epsilon,
            method: FairMethod::Highlight,
            fair_weight: d.fair_weight,
            diff_weight: d.diff_weight,
            laplacian_weight: d.laplacian_weight,
            least_change: d.least_change,
        }
    }
}

impl FairSettings {
    /// The `fairline fair` command line that runs these settings on the
    /// file `input` with the region file `region.json` (or `--auto`) and
    /// the lights file `lights.json`, writing `output` (both shell words).
    pub fn command_line(&self, input: &str, output: &str) -> String {
        let d = FairSettings::default();
        let mut c = format!("fairline fair {input}");
        c.push_str(if self.auto {
            " --auto"
        } else {
            " --region region.json"
        });
        if self.grow != d.grow {
            c.push_str(&format!(" --grow {}", self.grow));
        }
        c.push_str(&self.lights.args("lights.json"));
        c.push_str(&format!(" --method {}", self.method.name()));
        words::push_changed(
            &mut c,
            "max-iterations",
            self.max_iterations,
            d.max_iterations,
        );
        words::push_changed(&mut c, "epsilon", self.epsilon, d.epsilon);
        words::push_changed(&mut c, "fair-weight", self.fair_weight, d.fair_weight);
        words::push_changed(&mut c, "diff-weight", self.diff_weight, d.diff_weight);
        words::push_changed(
            &mut c,
            "laplacian-weight",
            self.laplacian_weight,
            d.laplacian_weight,
        );
        if !self.least_change {
            c.push_str(" --no-least-change");
        }
        c.push_str(&format!(" -o {output}"));
        c
    }

    /// The library's options at the fairing lights `light` (the region and
    /// the control are set per region).
    fn options(&self, light: LightArray) -> FairOptions {
        FairOptions::default()
            .light(light)
            .method(self.method)
            .fair_weight(self.fair_weight)
            .diff_weight(self.diff_weight)
            .laplacian_weight(self.laplacian_weight)
            .least_change(self.least_change)
            .max_iterations(self.max_iterations)
            .epsilon(self.epsilon)
            .highlight(self.lights.options())
    }
}

/// What `fair` works on: the mesh, the region (its faces; `None` with
/// `auto`) and the name of the input in messages (the CLI's path).
#[derive(Clone, Copy, Debug)]
pub struct FairInput<'a> {
    /// The triangle mesh.
    pub mesh: &'a SurfaceMesh,
    /// The faces of the region to fair.
    pub region: Option<&'a [FaceId]>,
    /// The input's name in warnings (`None`: not named).
    pub name: Option<&'a str>,
}

/// What `fair` gives.
#[derive(Clone, Debug)]
pub struct FairOutcome {
    /// The mesh after the last region.
    pub mesh: SurfaceMesh,
    /// The first faired region's positions and report (for a picture).
    pub first: Option<(Vec<Vec3>, FairReport)>,
    /// The detection lights and the fairing (readable) lights.
    pub light: LightArray,
    /// The lights the fairing worked on.
    pub fairing_light: LightArray,
    /// Each faired region's report.
    pub results: Vec<FairReport>,
    /// Detection inside the regions before and after (same lights).
    pub before: RegionDetection,
    /// After fairing.
    pub after: RegionDetection,
    /// Largest move of a vertex over the run.
    pub largest_move: f64,
    /// The JSON report.
    pub report: Report,
    /// What the run says on the way (regions detected and grown).
    pub notes: Vec<Note>,
    /// Regions there were to fair: the region given, or those detection
    /// found (`auto`; none when it found no defect).
    pub regions: usize,
}

/// Fairs the regions of `input` with `settings`, reporting progress (one
/// step per iteration over all regions) and stopping when cancelled through
/// `control`.
pub fn run(
    input: FairInput<'_>,
    settings: &FairSettings,
    control: &Control,
) -> Result<FairOutcome, CommandError> {
    let mesh = input.mesh;
    if input.region.is_some() == settings.auto {
        return Err(CommandError::bad_input(
            "give a region, or auto to detect the regions (not both)",
        ));
    }
    crate::require_faces(mesh.face_count(), mesh.original_vertex_count())?;
    if !mesh.is_triangle_mesh() {
        return Err(CommandError::bad_input(
            "highlight-line fairing needs a triangle mesh (this one has polygons; triangulate it first, e.g. with `fairline convert`)",
        )
        .about(Subject::Input));
    }
    // detection at the detail lights, as `detect`; fairing on the lines
    // the mesh resolves (the readable lights)
    let lights = &settings.lights;
    let light = lights.light_array(mesh)?;
    let fairing_light = lights.readable(mesh, light)?;
    let mut report = Report::new("fair");
    let mut notes = Vec::new();
    let regions = match input.region {
        Some(faces) => vec![faces.to_vec()],
        None => detected_regions(mesh, light, lights, &mut report, &mut notes)?,
    };
    let regions = grow_regions(mesh, regions, settings.grow, &mut notes);
    let region_faces = regions_union(&regions);
    let before = detect_region(mesh, &light, lights.options(), &region_faces)?;
    let options = settings.options(fairing_light);
    let faired = fair_each_region(
        mesh,
        &regions,
        &options,
        settings.auto,
        control,
        &mut report,
    )
    .map_err(|e| match input.region {
        Some(_) => e.about(Subject::Region),
        None => e,
    })?;
    let current = &faired.mesh;
    let after = detect_region(current, &light, lights.options(), &region_faces)?;
    let (score_before, score_after) = (before.score, after.score);
    let on_output = Detected {
        mesh: current,
        light,
        region: &region_faces,
        before: &before,
        after: &after,
    };
    report_detection(&on_output, lights, input.name, &mut report)?;
    report.set("method", settings.method.name());
    report.set("light", light);
    report.set("fairing_light", fairing_light);
    report.set("regions", faired.results.len());
    if settings.auto {
        report.set("skipped_regions", &faired.skipped);
    }
    let largest_move = current
        .positions()
        .iter()
        .zip(mesh.positions())
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    report.set_fields(regions_report(&faired.results, largest_move));
    if settings.auto {
        report.set("nothing_to_fair", regions.is_empty());
    }
    let scores = (score_before, score_after);
    let attempted = regions.len();
    for w in regions_warnings(&faired.results, attempted, settings.max_iterations, scores) {
        report.warn(w);
    }
    Ok(FairOutcome {
        mesh: faired.mesh,
        first: faired.first,
        light,
        fairing_light,
        results: faired.results,
        before,
        after,
        largest_move,
        report,
        notes,
        regions: attempted,
    })
}

/// Every region detection finds on `mesh` under `light`, grown by
/// [`AUTO_RINGS`] (noted), with the detection's report keys.
fn detected_regions(
    mesh: &SurfaceMesh,
    light: LightArray,
    lights: &Lights,
    report: &mut Report,
    notes: &mut Vec<Note>,
) -> Result<Vec<Vec<FaceId>>, CommandError> {
    let (det, grown) = report.time(|| detect_regions_to_fair(mesh, light, lights.options()))?;
    report.set("detected_regions", det.regions.len());
    if det.regions.is_empty() {
        notes.push(Note::NothingDetected);
    }
    for (k, (r, g)) in det.regions.iter().zip(&grown).enumerate() {
        notes.push(Note::AutoRegionGrown {
            region: k + 1,
            score: r.score,
            rings: AUTO_RINGS,
            from: r.faces.len(),
            to: g.len(),
        });
    }
    Ok(grown)
}

/// The faired mesh with the detection inside the faired faces before and
/// after (same lights).
struct Detected<'a> {
    mesh: &'a SurfaceMesh,
    light: LightArray,
    region: &'a [FaceId],
    before: &'a RegionDetection,
    after: &'a RegionDetection,
}

/// The detection keys of the report, and the warning when `detect` on the
/// output (with the lights it chooses there: the default lights follow the
/// part, which fairing changed a little) still flags a defect.
fn report_detection(
    d: &Detected<'_>,
    lights: &Lights,
    name: Option<&str>,
    report: &mut Report,
) -> Result<(), CommandError> {
    let (before, after) = (d.before, d.after);
    report.set("detect_score_before", before.score);
    report.set("detect_score_after", after.score);
    report.set("detect_threshold", before.threshold);
    report.set("detect_flat_spot_before", before.flat_spot);
    report.set("detect_flat_spot_after", after.flat_spot);
    report.set("detect_flat_spot_floor", before.detection.flat_spot_floor);
    let output_light = lights.light_array(d.mesh)?;
    let as_detect = if output_light == d.light {
        None
    } else {
        Some(detect_region(
            d.mesh,
            &output_light,
            lights.options(),
            d.region,
        )?)
    };
    let as_detect = as_detect.as_ref().unwrap_or(after);
    report.set("detect_regions_after", as_detect.detection.regions.len());
    if let Some(defect) = remaining_defect(as_detect, before.score, after.score) {
        report.warn(Warning::RemainingDefect {
            input: name.map(str::to_string),
            defect,
        });
    }
    Ok(())
}

impl FairOutcome {
    /// Whether there was nothing to fair: `auto` and detection found no
    /// defect above its threshold. The output is the input, as asked.
    pub fn nothing_to_fair(&self) -> bool {
        self.regions == 0
    }
    /// Whether there were regions to fair but none was faired (`auto`
    /// skips a detected region without a vertex free to move): the output
    /// is the input unchanged, which is not what was asked for; front
    /// ends exit 1 (the CLI), raise or mark the result.
    pub fn nothing_faired(&self) -> bool {
        self.regions > 0 && self.results.is_empty()
    }
    /// Whether every faired region converged.
    pub fn converged(&self) -> bool {
        self.results.iter().all(|r| r.converged)
    }
    /// The highlight-line deviation before and after (largest over the
    /// regions).
    pub fn deviation(&self) -> (f64, f64) {
        regions_deviation(&self.results)
    }
    /// Whether the result is not what was asked for: fairing made the
    /// highlight lines worse and detection does not confirm the defect
    /// gone ([`crate::regions::fairing_made_worse`]); front ends then exit
    /// 1 (the CLI), raise or mark the result.
    pub fn made_worse(&self) -> bool {
        fairing_made_worse(
            &self.results,
            (self.after.score, self.before.threshold),
            (self.after.flat_spot, self.before.detection.flat_spot_floor),
        )
    }
}

/// What detection still flags on the result (`detection`: `detect` on the
/// output, with the lights it would choose there), with the scores inside
/// the faired region; `None` when it flags nothing.
fn remaining_defect(
    detection: &RegionDetection,
    score_before: f64,
    score_after: f64,
) -> Option<RemainingDefect> {
    let best = detection.detection.regions.first()?;
    Some(RemainingDefect {
        regions: detection.detection.regions.len(),
        overlapping: detection.overlaps.iter().filter(|&&o| o).count(),
        best_inside: detection.overlaps.first().copied().unwrap_or(false),
        score: best.score,
        threshold: best.threshold,
        flat_spot: best.flat_spot,
        flat_spot_floor: detection.detection.flat_spot_floor,
        center: best.center.to_array(),
        score_before,
        score_after,
    })
}

/// Each region grown by `rings` rings of faces (noted), or the regions as
/// they are.
fn grow_regions(
    mesh: &SurfaceMesh,
    regions: Vec<Vec<FaceId>>,
    rings: usize,
    notes: &mut Vec<Note>,
) -> Vec<Vec<FaceId>> {
    if rings == 0 {
        return regions;
    }
    regions
        .iter()
        .map(|f| {
            let grown = grow_region(mesh, f, rings);
            notes.push(Note::RegionGrown {
                rings,
                from: f.len(),
                to: grown.len(),
            });
            grown
        })
        .collect()
}

/// What fairing the regions in turn gave.
struct Faired {
    mesh: SurfaceMesh,
    results: Vec<FairReport>,
    first: Option<(Vec<Vec3>, FairReport)>,
    /// Regions `auto` skipped (no movable vertex), with the reason.
    skipped: Vec<Value>,
}

/// Fairs the regions in turn, each on the result of the one before, with
/// the progress of all of them as one run of `control`.
fn fair_each_region(
    mesh: &SurfaceMesh,
    regions: &[Vec<FaceId>],
    options: &FairOptions,
    auto: bool,
    control: &Control,
    report: &mut Report,
) -> Result<Faired, CommandError> {
    let mut faired = Faired {
        mesh: mesh.clone(),
        results: Vec::new(),
        first: None,
        skipped: Vec::new(),
    };
    let total = (regions.len() * options.max_iterations) as u64;
    let done = Arc::new(AtomicU64::new(0));
    for (k, faces) in regions.iter().enumerate() {
        let start = done.load(Ordering::Relaxed);
        let seen = Arc::clone(&done);
        let region_control = control.mapped(move |p| {
            seen.store(start + p.done, Ordering::Relaxed);
            Progress {
                stage: p.stage,
                done: start + p.done,
                total,
            }
        });
        let region_options = options
            .clone()
            .region(faces.clone())
            .control(region_control);
        match report.time(|| fair_highlight_lines(&faired.mesh, &region_options)) {
            Ok(out) => {
                faired.mesh.set_positions(out.positions)?;
                if faired.first.is_none() {
                    faired.first = Some((faired.mesh.positions().to_vec(), out.report.clone()));
                }
                faired.results.push(out.report);
            }
            Err(FairError::NoMovableVertex(msg)) if auto => {
                faired.skipped.push(json!({"region": k, "reason": msg}));
            }
            Err(e) => return Err(e.into()),
        }
    }
    Ok(faired)
}
