//! `detect`: irregular stretches of highlight lines turned into suggested
//! fairing regions — the light policy (the measure at the lights asked
//! for, the lines read at their readable lights), detection of the whole
//! part ([`detect_whole_part`]: what one array leaves unjudged is judged
//! again with finer arrays), the suggested region and the JSON report —
//! as the CLI, the Python package and the workbench all run it.

use crate::error::CommandError;
use crate::lights::Lights;
use crate::regions::{detected_region_entries, suggested_region};
use crate::report::Report;
use crate::warning::Warning;
use crate::words::{push_changed, push_given};
use fairline::highlight::{
    DetectOptions, Detection, DrawnLineStats, HighlightLines, HighlightModel, LightArray,
    Readability, detect_whole_part,
};
use fairline::mesh::FaceId;
use fairline::{Control, SurfaceMesh};

/// The options of `detect` (defaults: the CLI's, which are the library's
/// [`DetectOptions`] defaults).
#[derive(Clone, Debug, PartialEq)]
pub struct DetectSettings {
    /// The lights (the measure at these, the lines at their readable
    /// lights).
    pub lights: Lights,
    /// Score above which a site is flagged (raised above a scan's noise).
    pub threshold: f64,
    /// Radius of the smooth comparison surface, in light spacings.
    pub smooth_radius: f64,
    /// Faces within this distance of a flagged point go into a region, in
    /// light spacings.
    pub region_margin: f64,
    /// Keep only the best this many regions (`None`: all).
    pub max_regions: Option<usize>,
}

impl Default for DetectSettings {
    fn default() -> Self {
        let d = DetectOptions::default();
        DetectSettings {
            lights: Lights::default(),
            threshold: d.threshold,
            smooth_radius: d.smooth_radius,
            region_margin: d.region_margin,
            max_regions: None,
        }
    }
}

impl DetectSettings {
    /// The `fairline detect` command line of these settings on the file
    /// `input` (a given light array read from `lights.json`), writing
    /// `output` (shell words); only what differs from the defaults.
    pub fn command_line(&self, input: &str, output: &str) -> String {
        let d = DetectSettings::default();
        let mut c = format!("fairline detect {input}{}", self.lights.args("lights.json"));
        c.push_str(&format!(" -o {output}"));
        push_changed(&mut c, "threshold", self.threshold, d.threshold);
        push_changed(&mut c, "smooth-radius", self.smooth_radius, d.smooth_radius);
        push_changed(&mut c, "region-margin", self.region_margin, d.region_margin);
        push_given(&mut c, "max-regions", self.max_regions);
        c
    }

    /// The library's options.
    pub fn options(&self) -> DetectOptions {
        DetectOptions::default()
            .threshold(self.threshold)
            .smooth_radius(self.smooth_radius)
            .region_margin(self.region_margin)
    }
}

/// What `detect` works on: the triangle mesh, the input face of each of
/// its faces when it was triangulated from polygons (`None`: the mesh is
/// the input) and the input's name in warnings (the CLI's path).
#[derive(Clone, Copy, Debug)]
pub struct DetectInput<'a> {
    /// The triangle mesh.
    pub mesh: &'a SurfaceMesh,
    /// Input face of each face.
    pub source: Option<&'a [FaceId]>,
    /// The input's name in warnings (`None`: not named).
    pub name: Option<&'a str>,
}

/// What `detect` gives.
#[derive(Clone, Debug)]
pub struct DetectOutcome {
    /// The lights of the measure.
    pub light: LightArray,
    /// The readable lights the lines were read at (`light` or a subset of
    /// its lines).
    pub shown_light: LightArray,
    /// Every line of `shown_light`.
    pub lines: HighlightLines,
    /// Their readable drawing, on which the flagged stretches lie.
    pub shown: HighlightLines,
    /// The detection, its regions cut to `max_regions`.
    pub detection: Detection,
    /// The suggested region: the union of the regions with two rings of
    /// support faces, as sorted input faces.
    pub region: Vec<u32>,
    /// The JSON report.
    pub report: Report,
}

/// Detects on `input` with `settings`; progress and cancellation through
/// `control`.
pub fn run(
    input: DetectInput<'_>,
    settings: &DetectSettings,
    control: &Control,
) -> Result<DetectOutcome, CommandError> {
    let mesh = input.mesh;
    let light = settings.lights.light_array(mesh)?;
    // the measure works at the scale of `light`; the lines shown and
    // listed are those of the readable lights (a subset of the lines of
    // `light` on round parts, the same lines on panels)
    let shown_light = settings.lights.readable(mesh, light)?;
    let mut report = Report::new("detect");
    let model =
        report.time(|| HighlightModel::new(mesh, shown_light, settings.lights.options()))?;
    run_with_model(input, settings, light, &model, report, control)
}

/// [`run`] with the highlight model of the readable lights already built
/// (`model`, at the readable lights of `light`; the workbench keeps one per
/// document), adding to `report`.
pub fn run_with_model(
    input: DetectInput<'_>,
    settings: &DetectSettings,
    light: LightArray,
    model: &HighlightModel,
    mut report: Report,
    control: &Control,
) -> Result<DetectOutcome, CommandError> {
    let mesh = input.mesh;
    let shown_light = *model.light();
    let options = settings.options().control(control.clone());
    let (lines, shown, mut detection) = report.time(|| {
        let lines = model.lines(mesh);
        let shown = model.readable_lines(mesh, &lines, &Readability::for_part(mesh, &shown_light));
        let detection = detect_whole_part(mesh, &light, &shown, &options)?;
        Ok::<_, CommandError>((lines, shown, detection))
    })?;
    if let Some(n) = settings.max_regions {
        detection.regions.truncate(n);
    }
    // faces of the input mesh (triangulated polygons map back to their
    // polygon); the region holds two more rings of faces: the support that
    // fairing needs to move every vertex of the suggested region
    let region = suggested_region(mesh, &detection, input.source);
    report.set("vertices", mesh.vertex_count());
    report.set("lines", lines.lines.len());
    report.set("spacing", light.spacing());
    report.set("drawn_spacing", shown_light.spacing());
    report.set("drawn", DrawnLineStats::of(mesh, &shown_light, &shown));
    // the library's numbers of the measure, under its own names
    report.set_fields(&detection);
    report.set("light", light);
    report.set("region_faces", region.len());
    report.set("regions", detected_region_entries(&detection, input.source));
    if lines.lines.is_empty() {
        report.warn(Warning::NoLineToDetectOn);
    }
    if let Some(w) = detection.not_judged_warning() {
        report.warn(Warning::Text(match input.name {
            Some(name) => format!("{name}: {w}"),
            None => w,
        }));
    }
    Ok(DetectOutcome {
        light,
        shown_light,
        lines,
        shown,
        detection,
        region,
        report,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_command_line_names_what_differs_from_the_defaults() {
        let s = DetectSettings {
            threshold: 2.5,
            max_regions: Some(1),
            ..DetectSettings::default()
        };
        assert_eq!(
            s.command_line("in.obj", "region.json"),
            "fairline detect in.obj -o region.json --threshold 2.5 --max-regions 1"
        );
    }

    /// The dented panel's dent is found, and the report holds the keys of
    /// the measure and the suggested region.
    #[test]
    fn a_dent_is_found_and_reported() {
        let mesh = fairline::shapes::height_field(41, 41, (-2.0, 2.0), (-2.0, 2.0), |x, y| {
            0.15 * (1.3 * x).sin() * (0.9 * y).cos()
                - 0.01 * (-((x - 0.5).powi(2) + (y + 0.4).powi(2)) / (0.16f64 * 0.16)).exp()
        });
        let input = DetectInput {
            mesh: &mesh,
            source: None,
            name: None,
        };
        let out = run(input, &DetectSettings::default(), &Control::new()).unwrap();
        assert!(!out.detection.regions.is_empty());
        let r = out.report.to_json();
        for key in [
            "vertices",
            "lines",
            "spacing",
            "drawn",
            "light",
            "region_faces",
            "regions",
        ] {
            assert!(r.get(key).is_some(), "{key}: {r}");
        }
        assert_eq!(r["region_faces"], out.region.len());
    }
}
