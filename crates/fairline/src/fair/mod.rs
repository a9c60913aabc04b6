//! Fairing: structure-line fairing of quad meshes (Grüner thesis ch. 4) and
//! fair polyline networks with tolerance cylinders (§3.1.1).

mod quad;

pub use quad::{
    PolylineNetworkOptions, PolylineNetworkReport, QuadFairError, QuadFairOptions,
    QuadFairReport, fair_polyline_network, fair_structure_lines, structure_energy,
};
