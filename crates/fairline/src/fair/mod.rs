//! Fairing: highlight-line fairing of triangle meshes (Yong et al. §3,
//! Algorithm 2) with its regions and movable vertices (§3.1).

mod error;
pub mod highlight;
pub mod region;

pub use error::FairError;
