//! Least change: the blend of the highlight result with the
//! diffusion-flow state, and the comparison that keeps it only where it
//! dominates that state.

use crate::Vec3;
use crate::fair::FairError;
use crate::fair::region::MovableSet;
use crate::highlight::{HighlightLines, HighlightModel};
use crate::mesh::{SurfaceMesh, VertexId};

/// What least change ([`FairOptions::least_change`](super::FairOptions::least_change)) compares: the
/// blended highlight result H' = (1 − s)·H + s·F and the diffusion-flow
/// state F, each by the RMS displacement of the movable vertices from the
/// input (mesh units) and by the RMS distance of its highlight lines from
/// the desired lines of the highlight method (light spacings, as
/// [`FairReport::highlight_deviation_after`](super::FairReport::highlight_deviation_after)).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct LeastChange {
    /// RMS displacement of H'.
    pub displacement_highlight: f64,
    /// RMS displacement of F.
    pub displacement_flow: f64,
    /// Deviation of H' from the desired lines.
    pub deviation_highlight: f64,
    /// Deviation of F from the same desired lines.
    pub deviation_flow: f64,
}

impl LeastChange {
    /// H' is kept when it dominates F: nearer the desired lines, and a
    /// change of the part at least [`LEAST_CHANGE_MARGIN`] smaller (RMS
    /// displacement). Otherwise F, which has no desired lines to be wrong
    /// about, is kept.
    pub fn keeps_highlight(&self) -> bool {
        self.deviation_highlight < self.deviation_flow
            && self.displacement_highlight < (1.0 - LEAST_CHANGE_MARGIN) * self.displacement_flow
    }
}

/// The share by which the highlight result must move the movable vertices
/// less than the diffusion-flow state to be kept (RMS displacement): closer
/// than 1 % the two are the same change of the part.
pub const LEAST_CHANGE_MARGIN: f64 = 0.01;

/// RMS over `movable` of |p − start| (non-finite differences count 0).
pub(super) fn rms_displacement(positions: &[Vec3], start: &[Vec3], movable: &[VertexId]) -> f64 {
    if movable.is_empty() {
        return 0.0;
    }
    let sum: f64 = movable
        .iter()
        .map(|v| {
            let d = positions[v.idx()] - start[v.idx()];
            if d.is_finite() {
                d.length_squared()
            } else {
                0.0
            }
        })
        .sum();
    (sum / movable.len() as f64).sqrt()
}

/// (1 − s)·highlight + s·flow on the movable vertices
/// ([`FairOptions::flow_share`]); the others are the input in both, so they
/// stay bit-identical. Returns the lines of the blended mesh.
pub(super) fn blend_flow(
    mesh: &mut SurfaceMesh,
    model: &mut HighlightModel,
    set: &MovableSet,
    flow: &[Vec3],
    s: f64,
) -> Result<HighlightLines, FairError> {
    let positions = mesh.positions_mut();
    for v in &set.movable {
        let (h, f) = (positions[v.idx()], flow[v.idx()]);
        let np = if s >= 1.0 { f } else { h + s * (f - h) };
        if np.is_finite() {
            positions[v.idx()] = np;
        }
    }
    model.update(mesh, &set.movable)?;
    Ok(model.lines(mesh))
}
