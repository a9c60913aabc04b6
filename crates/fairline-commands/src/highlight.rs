//! `highlight` on a triangle mesh: the highlight lines (and bands) of a
//! linear light array (Yong et al. §2), read at its readable lights, or of
//! concentric circular lights (Nishiyama et al. §2) — the light policy, the
//! lines, the JSON report and its warnings — as the CLI, the Python package
//! and the workbench all run it. Writing the lines and drawing pictures
//! stay in the front ends.

use crate::error::{CommandError, Subject};
use crate::lights::Lights;
use crate::report::Report;
use crate::warning::Warning;
use fairline::highlight::{
    CircularLight, CircularLights, DEFAULT_CIRCULAR_RADII, DrawnLineStats, HighlightBands,
    HighlightLines, HighlightModel, HighlightOptions, LightArray, Readability,
    circular_highlight_bands, circular_highlight_lines, default_circular_lights_for_mesh,
};
use fairline::{Control, SurfaceMesh, Vec3};
use serde_json::json;

/// The lights of a `highlight` run (on a mesh or on B-spline surfaces).
#[derive(Clone, Debug, PartialEq)]
pub enum HighlightLights {
    /// A linear light array ([`Lights`]: its readable lights are drawn).
    Linear(Lights),
    /// Circular lights given; `from_lights` when they came from the lights
    /// file (errors about them are then about [`Subject::Lights`]).
    Circular {
        /// The lights.
        spec: CircularLights,
        /// Whether they came from the lights file.
        from_lights: bool,
    },
    /// Circular lights derived from the part (the CLI's `--circular`),
    /// the lights on the side of `up` when given.
    DerivedCircular {
        /// The side the lights are on (`None`: the part's own).
        up: Option<Vec3>,
    },
}

/// The options of `highlight` on a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct HighlightSettings {
    /// The lights.
    pub lights: HighlightLights,
    /// Half-width of the highlight bands (`None`: no bands).
    pub band: Option<f64>,
}

impl HighlightSettings {
    /// Refuses a band that is not a positive number (naming the option).
    pub fn check(&self) -> Result<(), CommandError> {
        if let Some(b) = self.band
            && !(b > 0.0 && b.is_finite())
        {
            return Err(CommandError::invalid(
                "band",
                format!("must be a positive number, got {b}"),
            ));
        }
        Ok(())
    }
}

/// What `highlight` gives on a mesh.
#[derive(Clone, Debug)]
pub struct HighlightOutcome {
    /// Every line.
    pub lines: HighlightLines,
    /// The bands, when asked for.
    pub bands: Option<HighlightBands>,
    /// The radii of circular lights (`None`: linear lights).
    pub radii: Option<Vec<f64>>,
    /// The circular lights (empty for linear lights).
    pub circular: Vec<CircularLight>,
    /// The circular lights derived from the part (front ends show them so
    /// that they can be saved and reused).
    pub derived: Option<CircularLights>,
    /// The readable linear lights the lines were computed at (`None`:
    /// circular lights).
    pub light: Option<LightArray>,
    /// The readable subset of the lines to draw (linear lights).
    pub drawn: Option<HighlightLines>,
    /// The JSON report.
    pub report: Report,
}

/// The lines document of an outcome (DESIGN.md §4), as every front end
/// writes it.
pub fn lines_document(out: &HighlightOutcome) -> serde_json::Value {
    fairline::highlight::highlight_lines_json(&out.lines, out.bands.as_ref(), out.radii.as_deref())
}

/// Draws the highlight lines of `settings` on `mesh` (triangles);
/// cancellation through `control`.
pub fn run(
    mesh: &SurfaceMesh,
    settings: &HighlightSettings,
    control: &Control,
) -> Result<HighlightOutcome, CommandError> {
    settings.check()?;
    // the highlight computations take no control: they are not cancelled
    let _ = control;
    let mut report = Report::new("highlight");
    report.set("vertices", mesh.vertex_count());
    report.set("faces", mesh.face_count());
    let drawn = match &settings.lights {
        HighlightLights::Linear(lights) => linear(mesh, lights, settings.band, &mut report)?,
        HighlightLights::Circular { spec, from_lights } => {
            circular(mesh, spec, *from_lights, None, settings.band, &mut report)?
        }
        HighlightLights::DerivedCircular { up } => {
            let spec = default_circular_lights_for_mesh(mesh, *up, DEFAULT_CIRCULAR_RADII)
                .ok_or_else(|| {
                    CommandError::bad_input(
                        "cannot derive circular lights: the part has no area with a defined normal",
                    )
                })?;
            circular(mesh, &spec, false, Some(&spec), settings.band, &mut report)?
        }
    };
    let counts = drawn.lines.counts();
    report.set("summary", counts);
    report.set_fields(counts);
    if let Some(b) = &drawn.bands {
        report.set(
            "band",
            json!({"radius": b.radius, "lower_lines": b.lower.lines.len(), "upper_lines": b.upper.lines.len()}),
        );
    }
    if drawn.lines.lines.is_empty() {
        report.warn(Warning::NoLineCrossesTheMesh);
    }
    Ok(HighlightOutcome {
        lines: drawn.lines,
        bands: drawn.bands,
        radii: drawn.radii,
        circular: drawn.circular,
        derived: drawn.derived,
        light: drawn.light,
        drawn: drawn.drawn,
        report,
    })
}

/// The lines of one kind of lights, before the report is finished.
struct Drawn {
    lines: HighlightLines,
    bands: Option<HighlightBands>,
    radii: Option<Vec<f64>>,
    circular: Vec<CircularLight>,
    derived: Option<CircularLights>,
    light: Option<LightArray>,
    drawn: Option<HighlightLines>,
}

/// Lines (and bands) of circular lights `spec`; `derived` when they were
/// derived from the part. Records the lights in `report`.
fn circular(
    mesh: &SurfaceMesh,
    spec: &CircularLights,
    from_lights: bool,
    derived: Option<&CircularLights>,
    band: Option<f64>,
    report: &mut Report,
) -> Result<Drawn, CommandError> {
    let lights: Vec<CircularLight> = spec.lights().map_err(|e| {
        let e = CommandError::from(e);
        if from_lights {
            e.about(Subject::Lights)
        } else {
            e
        }
    })?;
    if lights.is_empty() {
        return Err(CommandError::bad_input(
            "circular lights need at least one radius",
        ));
    }
    let (lines, bands) = report.time(|| -> Result<_, CommandError> {
        let opts = HighlightOptions::default();
        let lines = circular_highlight_lines(mesh, &lights, &opts)?;
        let bands = match band {
            Some(rho) => Some(circular_highlight_bands(mesh, &lights, rho, &opts)?),
            None => None,
        };
        Ok((lines, bands))
    })?;
    let mut light =
        json!({"kind": "circular", "center": spec.center, "axis": spec.axis, "radii": spec.radii});
    if derived.is_some() {
        light["derived"] = json!(true);
    }
    report.set("light", light);
    Ok(Drawn {
        lines,
        bands,
        radii: Some(spec.radii.clone()),
        circular: lights,
        derived: derived.cloned(),
        light: None,
        drawn: None,
    })
}

/// Lines (and bands) of the readable linear light array of `lights` and the
/// readable subset to draw; records the lights and the drawn lines'
/// statistics in `report`.
fn linear(
    mesh: &SurfaceMesh,
    lights: &Lights,
    band: Option<f64>,
    report: &mut Report,
) -> Result<Drawn, CommandError> {
    let light = lights.light_array(mesh)?;
    let light = lights.readable(mesh, light)?;
    let opts = lights.options();
    let (lines, bands, shown) = report.time(|| -> Result<_, CommandError> {
        let model = HighlightModel::new(mesh, light, opts)?;
        let lines = model.lines(mesh);
        let bands = match band {
            Some(rho) => Some(model.bands(mesh, rho)?),
            None => None,
        };
        let shown = model.readable_lines(mesh, &lines, &Readability::for_part(mesh, &light));
        Ok((lines, bands, shown))
    })?;
    report.set("light", json!({"kind": "linear", "array": light}));
    report.set("drawn", DrawnLineStats::of(mesh, &light, &shown));
    Ok(Drawn {
        lines,
        bands,
        radii: None,
        circular: Vec::new(),
        derived: None,
        light: Some(light),
        drawn: Some(shown),
    })
}
