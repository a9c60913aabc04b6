//! Fairing: circular-highlight fairing of B-spline surfaces (Nishiyama et
//! al. §3) in [`surface`].

pub mod surface;

pub use surface::{
    EndpointPair, Endpoints, FairIteration, FairStop, SurfaceFairError, SurfaceFairOptions,
    SurfaceFairReport, TargetCurve, endpoints_around, fair_surface, target_curves,
};
