//! The noise floors of the measure: the mesh's threshold from its median
//! score, and the discretisation floor from its facet angles (steps 5 and
//! 7 of the module documentation of [`super`]).

use super::options::DetectOptions;
use super::sites::{FineFit, Judgement};

pub(super) fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The noise floors of the measure (steps 5 and 7 of the module
/// documentation).
pub(super) struct NoiseFloors {
    /// max(threshold, noise_factor × median score).
    pub(super) threshold: f64,
    /// `discretisation_factor` × discretisation level.
    pub(super) facet_factor: f64,
    pub(super) judged_sites: usize,
    pub(super) median_score: f64,
    pub(super) noise_level: f64,
    pub(super) facet_angle: f64,
    pub(super) discretisation_level: f64,
}

impl NoiseFloors {
    pub(super) fn estimate(
        judgements: &[Judgement],
        fine: &[Option<FineFit>],
        o: &DetectOptions,
    ) -> Self {
        let judged: Vec<f64> = judgements.iter().filter_map(|j| j.score).collect();
        let judged_sites = judged.len();
        let median_score = median(judged);
        let noise_level = median(
            fine.iter()
                .flatten()
                .map(|f| f.residual)
                .filter(|r| r.is_finite())
                .collect(),
        );
        // normal error over facet angle at the judged sites with facets
        let mut ratios = Vec::new();
        let mut facets = Vec::new();
        for (j, f) in judgements.iter().zip(fine) {
            if let (Some(score), Some(f)) = (j.score, f) {
                facets.push(f.facet_angle);
                if f.facet_angle > 0.0 {
                    let ratio = score * j.unit_angle / f.facet_angle;
                    if ratio.is_finite() {
                        ratios.push(ratio);
                    }
                }
            }
        }
        let discretisation_level = median(ratios);
        NoiseFloors {
            threshold: o.threshold.max(o.noise_factor * median_score),
            facet_factor: o.discretisation_factor * discretisation_level,
            judged_sites,
            median_score,
            noise_level,
            facet_angle: median(facets),
            discretisation_level,
        }
    }

    /// The threshold at one site: the mesh's, raised to the normal error
    /// the site's facets explain (in score units, δ·factor/θ₀).
    pub(super) fn at(&self, j: &Judgement, f: Option<&FineFit>) -> f64 {
        match (j.score, f) {
            (Some(_), Some(f)) if j.unit_angle > 0.0 => {
                let facet = self.facet_factor * f.facet_angle / j.unit_angle;
                if facet.is_finite() {
                    self.threshold.max(facet)
                } else {
                    self.threshold
                }
            }
            _ => self.threshold,
        }
    }
}
