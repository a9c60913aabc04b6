//! The light options every front end offers for highlight lines, and the
//! readable-light policy, applied once.

use crate::error::CommandError;
use crate::names::Choice;
use fairline::highlight::{
    HighlightOptions, LightArray, LightChoice, Readability, UpAxis, part_light_array,
};
use fairline::{SurfaceMesh, Vec3};

/// The lights a user asked for: a linear light array given whole
/// (`given`, the CLI's `--lights FILE`), or the part's default lights with
/// the fields given put in their place; and the model option
/// `min_normal_cos`. Plain data: each front end fills it from its own
/// options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lights {
    /// Light direction H (made orthogonal to the plane normal).
    pub direction: Option<Vec3>,
    /// Normal Z of the light plane (default: from `up`).
    pub plane_normal: Option<Vec3>,
    /// Which side the lights are on when `plane_normal` is not given.
    pub up: UpAxis,
    /// Point A0 on light 0.
    pub plane_point: Option<Vec3>,
    /// Spacing s between lights.
    pub spacing: Option<f64>,
    /// A whole light array (a lights file); excludes the four fields above.
    pub given: Option<LightArray>,
    /// Smallest |Z·N| at which a vertex gets a highlight distance.
    pub min_normal_cos: f64,
}

impl Default for Lights {
    fn default() -> Self {
        Lights {
            direction: None,
            plane_normal: None,
            up: UpAxis::Auto,
            plane_point: None,
            spacing: None,
            given: None,
            min_normal_cos: HighlightOptions::default().min_normal_cos,
        }
    }
}

impl Lights {
    /// Exactly the light array `light`, given by its four fields (what the
    /// workbench sends; its command line spells them out).
    pub fn exactly(light: &LightArray) -> Self {
        Lights {
            direction: Some(light.direction()),
            plane_normal: Some(light.plane_normal()),
            plane_point: Some(light.plane_point()),
            spacing: Some(light.spacing()),
            ..Lights::default()
        }
    }

    /// What the user said about the lights, for the library's defaults.
    pub fn choice(&self) -> LightChoice {
        LightChoice::default()
            .direction(self.direction)
            .plane_normal(self.plane_normal)
            .up(self.up)
            .plane_point(self.plane_point)
            .spacing(self.spacing)
    }

    /// The light array on `mesh`: the given one, or the part's default
    /// lights with the given fields in place ([`LightChoice::light_array`]).
    pub fn light_array(&self, mesh: &SurfaceMesh) -> Result<LightArray, CommandError> {
        match self.given {
            Some(light) => Ok(light),
            None => Ok(self.choice().light_array(mesh)?),
        }
    }

    /// The lights to draw and read lines with (the readable-light policy):
    /// `light` itself when the lights were given whole or their spacing was
    /// given, else `light` with its spacing multiplied by a readable
    /// multiple on round parts ([`LightChoice::readable`]).
    pub fn readable(
        &self,
        mesh: &SurfaceMesh,
        light: LightArray,
    ) -> Result<LightArray, CommandError> {
        if self.given.is_some() {
            return Ok(light);
        }
        Ok(self.choice().readable(mesh, light)?)
    }

    /// The light array of a part of B-spline surfaces and what its picture
    /// can show: the given one as it is, or the part's readable default
    /// lights with the given fields in place.
    pub fn part_light_array(
        &self,
        surfaces: &[fairline::bspline::BSplineSurface],
    ) -> Result<(LightArray, Readability), CommandError> {
        Ok(part_light_array(surfaces, &self.choice(), self.given)?)
    }

    /// The highlight model's options.
    pub fn options(&self) -> HighlightOptions {
        HighlightOptions::default().min_normal_cos(self.min_normal_cos)
    }

    /// The light options on a command line (`lights_file` names the file
    /// of a given array); only what differs from the defaults.
    pub fn args(&self, lights_file: &str) -> String {
        let mut out = String::new();
        if self.given.is_some() {
            out.push_str(&format!(" --lights {lights_file}"));
        }
        let vec = |v: Vec3| format!("{},{},{}", v.x, v.y, v.z);
        for (name, v) in [
            ("plane-point", self.plane_point),
            ("plane-normal", self.plane_normal),
            ("direction", self.direction),
        ] {
            if let Some(v) = v {
                out.push_str(&format!(" --{name} {}", vec(v)));
            }
        }
        if let Some(s) = self.spacing {
            out.push_str(&format!(" --spacing {s}"));
        }
        if self.up != UpAxis::Auto {
            out.push_str(&format!(" --up {}", self.up.name()));
        }
        if self.min_normal_cos != Lights::default().min_normal_cos {
            out.push_str(&format!(" --min-normal-cos {}", self.min_normal_cos));
        }
        out
    }
}
