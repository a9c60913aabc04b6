//! Placeholder: filled in by its issue.

pub mod quad;

pub use quad::{
    PolylineNetworkOptions, PolylineNetworkReport, QuadFairError, QuadFairOptions, QuadFairReport,
    fair_polyline_network, fair_structure_lines, structure_energy,
};
