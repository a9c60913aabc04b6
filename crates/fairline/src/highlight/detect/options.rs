//! The options of detection: thresholds, radii and noise factors, with
//! their setters and validation.

use crate::Control;
use crate::highlight::HighlightError;

/// Options of [`detect_irregularities`](super::detect_irregularities); lengths in light spacings s.
/// Build them with `DetectOptions::default()` and the setters.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct DetectOptions {
    /// Flag sites whose score (highlight displacement in tenths of a
    /// spacing, see the [module documentation](super)) exceeds this (default 1).
    pub threshold: f64,
    /// Radius R of the smooth (cubic) fit, in spacings (default 1.5): defects
    /// up to about this lateral size are found; shape at larger scales is
    /// taken as intended.
    pub smooth_radius: f64,
    /// Radius of the fine (quadric) fit, in spacings (default 0.25; at
    /// least 2.5 mean edge lengths are used).
    pub fine_radius: f64,
    /// Distance between sites, in spacings (default 0.25).
    pub site_spacing: f64,
    /// Faces within this distance of a flagged site go into a region, in
    /// spacings (default 1); scaled up with R on meshes too coarse for the
    /// spacing ([module documentation](super), Regions).
    pub region_margin: f64,
    /// The threshold is raised to this many times the median site score,
    /// the score noise of a scan (default 4; 0 turns it off).
    pub noise_factor: f64,
    /// The threshold at each site is raised to this many times the normal
    /// error that the site's own facets explain on this mesh (default 10;
    /// 0 turns it off): the discretisation floor of the module
    /// documentation, step 7.
    pub discretisation_factor: f64,
    /// Largest angle (radians, default 1) by which the surface normals
    /// within the smooth radius R may turn away from a site's normal for
    /// the site to be judged. Where they turn by more (κ·R ≳ 1: ears, horns,
    /// creases, fillets tighter than R) no cubic over R can stand for the
    /// intended surface: the shape there is finer than the scale of the
    /// measure, so it is counted as shape
    /// ([`Detection::shape_sites`](super::Detection::shape_sites)) and
    /// not judged. A defect of the kind the measure is for turns the
    /// normal by a few degrees at most (a 0.1 %-of-diagonal bump a spacing
    /// wide: about 1°).
    pub max_turn: f64,
    /// The flat-spot measure's noise factor (default 4; 0 turns the measure
    /// off): a site's area-median relative curvature drop is judged where
    /// the smoothed surface's curvature exceeds this many times the mesh's
    /// curvature noise, and flagged above max(0.5, this many times its 90th
    /// percentile over the mesh) ([module documentation](super), step 8).
    pub flat_spot_factor: f64,
    /// Progress (stage "detect", one step per stage of the measure) and
    /// cancellation.
    pub control: Control,
}

impl Default for DetectOptions {
    fn default() -> Self {
        DetectOptions {
            threshold: 1.0,
            smooth_radius: 1.5,
            fine_radius: 0.25,
            site_spacing: 0.25,
            region_margin: 1.0,
            noise_factor: 4.0,
            discretisation_factor: 10.0,
            max_turn: 1.0,
            flat_spot_factor: 4.0,
            control: Control::default(),
        }
    }
}

impl DetectOptions {
    /// Sets the score threshold.
    pub fn threshold(mut self, t: f64) -> Self {
        self.threshold = t;
        self
    }
    /// Sets the smooth-fit radius (spacings).
    pub fn smooth_radius(mut self, r: f64) -> Self {
        self.smooth_radius = r;
        self
    }
    /// Sets the fine-fit radius (spacings).
    pub fn fine_radius(mut self, r: f64) -> Self {
        self.fine_radius = r;
        self
    }
    /// Sets the distance between sites (spacings).
    pub fn site_spacing(mut self, d: f64) -> Self {
        self.site_spacing = d;
        self
    }
    /// Sets the region margin (spacings).
    pub fn region_margin(mut self, r: f64) -> Self {
        self.region_margin = r;
        self
    }
    /// Sets the noise factor (0: no noise floor).
    pub fn noise_factor(mut self, k: f64) -> Self {
        self.noise_factor = k;
        self
    }
    /// Sets the discretisation factor (0: no discretisation floor).
    pub fn discretisation_factor(mut self, k: f64) -> Self {
        self.discretisation_factor = k;
        self
    }
    /// Sets the largest normal turn within the smooth radius at which a
    /// site is judged (radians).
    pub fn max_turn(mut self, a: f64) -> Self {
        self.max_turn = a;
        self
    }
    /// Sets the flat-spot measure's noise factor (0: no flat-spot measure).
    pub fn flat_spot_factor(mut self, k: f64) -> Self {
        self.flat_spot_factor = k;
        self
    }
    /// Sets the progress callback and cancel flag.
    pub fn control(mut self, control: Control) -> Self {
        self.control = control;
        self
    }

    /// Every length and factor must be positive and finite (the noise
    /// factor may be 0).
    pub(super) fn validate(&self) -> Result<(), HighlightError> {
        for (name, v) in [
            ("threshold", self.threshold),
            ("smooth_radius", self.smooth_radius),
            ("fine_radius", self.fine_radius),
            ("site_spacing", self.site_spacing),
            ("region_margin", self.region_margin),
            ("max_turn", self.max_turn),
        ] {
            if !(v > 0.0) || !v.is_finite() {
                return Err(HighlightError::InvalidOption(format!(
                    "{name} must be positive, got {v}"
                )));
            }
        }
        for (name, v) in [
            ("noise_factor", self.noise_factor),
            ("discretisation_factor", self.discretisation_factor),
            ("flat_spot_factor", self.flat_spot_factor),
        ] {
            if !(v >= 0.0) || !v.is_finite() {
                return Err(HighlightError::InvalidOption(format!(
                    "{name} must be non-negative, got {v}"
                )));
            }
        }
        Ok(())
    }
}
