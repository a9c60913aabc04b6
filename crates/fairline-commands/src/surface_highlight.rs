//! `highlight` on B-spline surfaces: the highlight lines of every chosen
//! surface traced in its parameter domain (Nishiyama et al. §2) — the
//! light policy (circular lights given or derived from the whole part, or
//! the part's readable linear lights), the lines document, the JSON report
//! and its warnings — as the CLI and the Python package run it. Writing
//! the lines and drawing pictures stay in the front ends.

use crate::error::{CommandError, Subject};
use crate::highlight::HighlightLights;
use crate::report::Report;
use crate::warning::Warning;
use fairline::Control;
use fairline::bspline::BSplineSurface;
use fairline::highlight::surface::DEFAULT_MAX_LIGHTS;
use fairline::highlight::{
    CircularLights, DEFAULT_CIRCULAR_RADII, LightArray, PartLights, PatchHighlights, Readability,
    SurfaceHighlightOptions, default_circular_lights, part_highlight_lines,
    surface_highlight_lines_json,
};
use serde_json::{Value, json};

/// The options of `highlight` on surfaces (defaults: the CLI's).
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceHighlightSettings {
    /// The lights (`DerivedCircular` derives them from every surface of
    /// the part, the chosen one or not).
    pub lights: HighlightLights,
    /// Grid points per direction for the pre-images.
    pub grid: usize,
    /// Half-width of the highlight bands (`None`: no bands).
    pub band: Option<f64>,
    /// The one surface to draw (`None`: all).
    pub surface: Option<usize>,
}

impl Default for SurfaceHighlightSettings {
    fn default() -> Self {
        SurfaceHighlightSettings {
            lights: HighlightLights::Linear(crate::Lights::default()),
            grid: 200,
            band: None,
            surface: None,
        }
    }
}

impl SurfaceHighlightSettings {
    /// Refuses a grid out of 2..=4000 and a band that is not a positive
    /// number (naming the option).
    pub fn check(&self) -> Result<(), CommandError> {
        if !(2..=4000).contains(&self.grid) {
            return Err(CommandError::invalid(
                "grid",
                format!("must be between 2 and 4000, got {}", self.grid),
            ));
        }
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

/// What `highlight` gives on surfaces.
#[derive(Clone, Debug)]
pub struct SurfaceHighlightOutcome {
    /// The chosen surfaces.
    pub surfaces: Vec<BSplineSurface>,
    /// Each chosen surface's index in the part and its lines.
    pub results: Vec<(usize, PatchHighlights)>,
    /// The linear lights and what their picture can show (`None`: circular
    /// lights).
    pub readable: Option<(LightArray, Readability)>,
    /// The circular lights derived from the part (front ends show them so
    /// that they can be saved and reused).
    pub derived: Option<CircularLights>,
    /// The lines document (DESIGN.md §4), as every front end writes it.
    pub document: Value,
    /// The number of lines in it.
    pub lines: usize,
    /// The JSON report.
    pub report: Report,
}

/// Refuses a surface index beyond the part (about the input, naming the
/// option `surface`).
fn check_surface(surface: Option<usize>, count: usize) -> Result<(), CommandError> {
    match surface {
        Some(k) if k >= count => Err(CommandError::invalid(
            "surface",
            format!("{k} is out of range (the file holds {count} surfaces)"),
        )
        .about(Subject::Input)),
        _ => Ok(()),
    }
}

/// Draws the highlight lines of `settings` on the surfaces of `all`;
/// `progress` is called once per surface done. The computation takes no
/// control: it is not cancelled.
pub fn run(
    all: &[BSplineSurface],
    settings: &SurfaceHighlightSettings,
    control: &Control,
    progress: &(dyn Fn() + Sync),
) -> Result<SurfaceHighlightOutcome, CommandError> {
    let _ = control;
    settings.check()?;
    if all.is_empty() {
        return Err(CommandError::bad_input("no B-spline surface given").about(Subject::Input));
    }
    check_surface(settings.surface, all.len())?;
    let circular = circular_spec(&settings.lights, all)?;
    let chosen: Vec<(usize, BSplineSurface)> = match settings.surface {
        Some(k) => vec![(k, all[k].clone())],
        None => all.iter().cloned().enumerate().collect(),
    };
    let surfaces: Vec<BSplineSurface> = chosen.iter().map(|(_, s)| s.clone()).collect();
    let mut report = Report::new("highlight");
    report.set("surfaces", chosen.len());
    report.set("grid", settings.grid);
    let opts = SurfaceHighlightOptions::default()
        .grid(settings.grid)
        .band(settings.band);
    let derived = circular.as_ref().and_then(|(s, d, _)| d.then(|| s.clone()));
    let (part_lights, readable) = part_lights(&settings.lights, circular, &surfaces, &mut report)?;
    let patches = report.time(|| part_highlight_lines(&surfaces, &part_lights, &opts, progress));
    let results: Vec<(usize, PatchHighlights)> = chosen
        .iter()
        .zip(patches)
        .map(|((k, _), p)| (*k, p))
        .collect();
    let (document, counts) = surface_highlight_lines_json(
        &results.iter().map(|(k, p)| (*k, p)).collect::<Vec<_>>(),
        settings.band,
    );
    report.set("lines", counts.lines);
    report.set("closed_lines", counts.closed_lines);
    report.set("points", counts.points);
    if counts.lines == 0 {
        report.warn(Warning::NoPreImage);
    }
    Ok(SurfaceHighlightOutcome {
        surfaces,
        results,
        readable,
        derived,
        document,
        lines: counts.lines,
        report,
    })
}

/// The circular lights asked for: given, or derived from the whole part
/// `all` (so that `fair-surface` on the same file derives the same ones);
/// with whether they were derived and whether they came from the lights
/// file. `None` for linear lights.
fn circular_spec(
    lights: &HighlightLights,
    all: &[BSplineSurface],
) -> Result<Option<(CircularLights, bool, bool)>, CommandError> {
    Ok(match lights {
        HighlightLights::Linear(_) => None,
        HighlightLights::Circular { spec, from_lights } => {
            Some((spec.clone(), false, *from_lights))
        }
        HighlightLights::DerivedCircular { up } => {
            let spec =
                default_circular_lights(all, *up, DEFAULT_CIRCULAR_RADII).ok_or_else(|| {
                    CommandError::bad_input(
                        "cannot derive circular lights: the part has no area with a defined normal",
                    )
                })?;
            Some((spec, true, false))
        }
    })
}

/// The lights of the run over the chosen `surfaces`: the circular ones,
/// else the given linear array or the part's readable default lights with
/// the options given in place ([`crate::Lights::part_light_array`]) with
/// what its picture can show; recorded in the report.
fn part_lights(
    lights: &HighlightLights,
    circular: Option<(CircularLights, bool, bool)>,
    surfaces: &[BSplineSurface],
    report: &mut Report,
) -> Result<(PartLights, Option<(LightArray, Readability)>), CommandError> {
    if let Some((spec, derived, from_lights)) = circular {
        let lights = spec.lights().map_err(|e| {
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
        let mut light = json!({"kind": "circular", "center": spec.center, "axis": spec.axis, "radii": spec.radii});
        if derived {
            light["derived"] = json!(true);
        }
        report.set("light", light);
        return Ok((PartLights::Circular(lights), None));
    }
    let HighlightLights::Linear(linear) = lights else {
        return Ok((PartLights::Circular(Vec::new()), None));
    };
    let (array, readability) = linear.part_light_array(surfaces)?;
    report.set("light", json!({"kind": "linear", "array": array}));
    Ok((
        PartLights::Linear {
            array,
            min_cos: linear.min_normal_cos,
            max_lights: DEFAULT_MAX_LIGHTS,
        },
        Some((array, readability)),
    ))
}
