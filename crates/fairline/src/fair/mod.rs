//! Fairing: highlight-line fairing of triangle meshes (Yong et al. §3,
//! Algorithm 2) with its regions and movable vertices (§3.1), desired
//! highlight lines (§3.2, §3.5) and the surface-diffusion-flow baseline;
//! structure-line fairing of quad meshes (Grüner) in [`quad`];
//! circular-highlight fairing of B-spline surfaces (Nishiyama et al. §3) in
//! [`surface`]; membrane, thin-plate and minimum-variation energy fairing
//! of a region (Grüner §3.1.2–3.1.3) in [`energy`].

mod desired;
mod end_tangents;
pub mod energy;
mod error;
#[cfg(test)]
pub(crate) mod family;
pub mod highlight;
pub mod quad;
pub mod region;
pub mod surface;
mod system;

pub use desired::{
    DesiredLine, DesiredLines, HighlightDeviation, Tangents, across_tangents, desired_lines,
    desired_lines_with,
};
pub use end_tangents::fitted_surface_tangents;
pub use energy::{FairEnergy, energy_fairing};
pub use error::FairError;
pub use highlight::{
    FairMethod, FairOptions, FairReport, IterationReport, LEAST_CHANGE_MARGIN, LeastChange,
    fair_highlight_lines, grow_region,
};
pub use quad::{
    PolylineNetworkOptions, PolylineNetworkReport, QuadFairError, QuadFairOptions, QuadFairReport,
    fair_polyline_network, fair_structure_lines, structure_energy,
};
pub use region::{MovableSet, movable_vertices};
pub use surface::{
    BoundaryControl, EndpointPair, Endpoints, FairIteration, FairStop, PaperDamping,
    SurfaceFairError, SurfaceFairMethod, SurfaceFairOptions, SurfaceFairReport, TargetCurve,
    Waviness, endpoints_around, fair_surface, polyline_waviness, target_curves,
};

#[cfg(test)]
pub(crate) mod tests;
