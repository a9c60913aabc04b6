//! The statistics of the drawn (readable) highlight lines as every front
//! end reports them (the `drawn` key of `fairline highlight`, `detect` and
//! `render --highlight`, and of the Python functions): written once.

use super::{HighlightLines, LightArray, LineStats, readable::part_width};
use crate::mesh::SurfaceMesh;
use serde::Serialize;

/// [`LineStats`] of the drawn lines, with the median and N50 piece
/// lengths also relative to the part's width across the lights
/// ([`part_width`]): a readable drawing has long pieces relative to the
/// part.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DrawnLineStats {
    /// Number of polylines.
    pub pieces: usize,
    /// Number of distinct lights among them.
    pub lights: usize,
    /// `pieces / lights` (0 without lines).
    pub pieces_per_light: f64,
    /// Median polyline length (mesh units).
    pub median_length: f64,
    /// `median_length` over the part's width across the lights.
    pub median_length_over_width: f64,
    /// Length-weighted median piece length (mesh units).
    pub n50_length: f64,
    /// `n50_length` over the part's width across the lights.
    pub n50_length_over_width: f64,
    /// Total length of all polylines (mesh units).
    pub total_length: f64,
}

impl DrawnLineStats {
    /// The statistics of `lines` drawn with `light` on `mesh`.
    pub fn of(mesh: &SurfaceMesh, light: &LightArray, lines: &HighlightLines) -> Self {
        let st = LineStats::of(lines);
        let width = part_width(mesh.positions(), light.across());
        DrawnLineStats {
            pieces: st.pieces,
            lights: st.lights,
            pieces_per_light: st.pieces_per_light,
            median_length: st.median_length,
            median_length_over_width: st.median_length / width,
            n50_length: st.n50_length,
            n50_length_over_width: st.n50_length / width,
            total_length: st.total_length,
        }
    }
}
