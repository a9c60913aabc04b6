//! The options of highlight-line fairing: the method, the region, the
//! lights, the weights and the stopping rule, with their defaults.

use crate::Control;
use crate::fair::FairError;
use crate::highlight::{HighlightOptions, LightArray};
use crate::mesh::FaceId;

/// Which energy the fairing minimises.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum FairMethod {
    /// Yong et al. Eq. (15) with desired lines whose end tangents come from
    /// a smooth fit beyond the defect's footprint (module `end_tangents`),
    /// a share of the diffusion-flow state ([`FairOptions::flow_share`]),
    /// the optional refits of the desired lines ([`FairOptions::refits`])
    /// and the optional curvature-Laplacian term ω3 f_lap
    /// ([`FairOptions::laplacian_weight`]); see the module documentation.
    #[default]
    Highlight,
    /// Yong et al. Eq. (15) exactly: ω1 f_fair + ω2 f_diff, whatever
    /// [`FairOptions::laplacian_weight`] says.
    Paper,
    /// Baseline: surface diffusion flow ∂V/∂t = N Δ_B H (Xu et al.) on the
    /// same movable vertices.
    DiffusionFlow,
    /// Membrane energy (Grüner thesis §3.1.2, Eq. (14)): ΔX = 0 on the
    /// movable vertices, the others held ([`crate::fair::energy_fairing`]); no
    /// lights are used and the vertices move freely (not along normals).
    Membrane,
    /// Thin-plate energy (Grüner §3.1.2, Eq. (13)): Δ²X = 0 on the movable
    /// vertices ([`crate::fair::energy_fairing`]).
    ThinPlate,
    /// Linearised variation of curvature, minimum variation surfaces
    /// (Grüner §3.1.3, Eq. (15)): Δ³X = 0 on the movable vertices
    /// ([`crate::fair::energy_fairing`]).
    Mvs,
}

impl FairMethod {
    /// The energy of an energy-functional method, `None` for the
    /// highlight-line methods.
    pub fn energy(self) -> Option<crate::fair::FairEnergy> {
        match self {
            FairMethod::Membrane => Some(crate::fair::FairEnergy::Membrane),
            FairMethod::ThinPlate => Some(crate::fair::FairEnergy::ThinPlate),
            FairMethod::Mvs => Some(crate::fair::FairEnergy::VariationOfCurvature),
            FairMethod::Highlight | FairMethod::Paper | FairMethod::DiffusionFlow => None,
        }
    }
}

/// Options of [`fair_highlight_lines`](super::fair_highlight_lines): the region, the lights, the energy
/// and the stopping rule of Yong et al. Algorithm 2.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct FairOptions {
    /// The region R to fair, as its faces (Yong et al. §3.1); must not be
    /// empty. Read a region file with [`crate::io::read_region`] and
    /// [`crate::io::RegionSpec::faces`].
    pub region: Vec<FaceId>,
    /// The linear light array whose highlight lines are faired; `None`: the
    /// default lights of `fairline highlight` for the mesh
    /// ([`LightArray::default_for_mesh`], up axis found from the part).
    pub light: Option<LightArray>,
    /// The energy to minimise (default [`FairMethod::Highlight`]).
    pub method: FairMethod,
    /// ω1, weight of f_fair (default 1, as in Yong et al. §4).
    pub fair_weight: f64,
    /// ω2, weight of f_diff (default 1, as in Yong et al. §4); f_diff is
    /// measured in light spacings per region diameter (module `system`).
    pub diff_weight: f64,
    /// ω3, weight of the curvature-Laplacian fairness term
    /// f_lap = D⁴ ∫(Δ_B H)² dA of [`FairMethod::Highlight`] (D the
    /// region's diameter): the energy whose zero is the stationary state of
    /// surface diffusion flow (Xu et al.). Default 0 (see the module
    /// documentation for the measured trade-off).
    pub laplacian_weight: f64,
    /// N_max, most iterations (default 50).
    pub max_iterations: usize,
    /// ε of Eq. (17) (default 1e-3).
    pub epsilon: f64,
    /// Refits of the desired lines ([`FairMethod::Highlight`] only,
    /// default 0): each time Eq. (17) is met, the tangents T0, T1 of the
    /// desired lines are refitted across their end nodes to the faired
    /// lines ([`crate::fair::desired::across_tangents`]) and the iteration goes
    /// on, this many times; 0 keeps the tangents of the smooth fit beyond
    /// the footprint ([`super::fitted_surface_tangents`]), which are closer
    /// to the truth's on the generated family (BENCHMARKS.md).
    pub refits: usize,
    /// Share of the surface-diffusion-flow state in the result of
    /// [`FairMethod::Highlight`] (default 0.25; 0 switches it off): the
    /// movable vertices end at (1 − s)·(highlight result) + s·(diffusion-flow
    /// result on the same region), see the module documentation.
    pub flow_share: f64,
    /// Least change ([`FairMethod::Highlight`] with a flow share only,
    /// default on): of the blended result and the diffusion-flow state,
    /// keep the one that moves the movable vertices less (RMS
    /// displacement); see the module documentation.
    pub least_change: bool,
    /// Options of the highlight line model.
    pub highlight: HighlightOptions,
    /// Progress (stage "iterations", once per iteration) and cancellation.
    pub control: Control,
}

impl Default for FairOptions {
    fn default() -> Self {
        FairOptions {
            region: Vec::new(),
            light: None,
            method: FairMethod::Highlight,
            fair_weight: 1.0,
            diff_weight: 1.0,
            laplacian_weight: 0.0,
            max_iterations: 50,
            epsilon: 1e-3,
            refits: DEFAULT_REFITS,
            flow_share: DEFAULT_FLOW_SHARE,
            least_change: true,
            highlight: HighlightOptions::default(),
            control: Control::default(),
        }
    }
}

impl FairOptions {
    /// Sets [`FairOptions::region`].
    pub fn region(mut self, faces: Vec<FaceId>) -> Self {
        self.region = faces;
        self
    }
    /// Sets [`FairOptions::light`].
    pub fn light(mut self, light: LightArray) -> Self {
        self.light = Some(light);
        self
    }
    /// Sets [`FairOptions::method`].
    pub fn method(mut self, m: FairMethod) -> Self {
        self.method = m;
        self
    }
    /// Sets ω1 and ω2.
    pub fn weights(mut self, fair: f64, diff: f64) -> Self {
        self.fair_weight = fair;
        self.diff_weight = diff;
        self
    }
    /// Sets [`FairOptions::fair_weight`] (ω1).
    pub fn fair_weight(mut self, w1: f64) -> Self {
        self.fair_weight = w1;
        self
    }
    /// Sets [`FairOptions::diff_weight`] (ω2).
    pub fn diff_weight(mut self, w2: f64) -> Self {
        self.diff_weight = w2;
        self
    }
    /// Sets [`FairOptions::laplacian_weight`] (ω3).
    pub fn laplacian_weight(mut self, w3: f64) -> Self {
        self.laplacian_weight = w3;
        self
    }
    /// Sets [`FairOptions::max_iterations`].
    pub fn max_iterations(mut self, n: usize) -> Self {
        self.max_iterations = n;
        self
    }
    /// Sets [`FairOptions::epsilon`].
    pub fn epsilon(mut self, e: f64) -> Self {
        self.epsilon = e;
        self
    }
    /// Sets [`FairOptions::refits`].
    pub fn refits(mut self, n: usize) -> Self {
        self.refits = n;
        self
    }
    /// Sets [`FairOptions::flow_share`].
    pub fn flow_share(mut self, s: f64) -> Self {
        self.flow_share = s;
        self
    }
    /// Sets [`FairOptions::least_change`](super::FairOptions::least_change).
    pub fn least_change(mut self, on: bool) -> Self {
        self.least_change = on;
        self
    }
    /// Sets [`FairOptions::highlight`].
    pub fn highlight(mut self, h: HighlightOptions) -> Self {
        self.highlight = h;
        self
    }
    /// Sets [`FairOptions::control`].
    pub fn control(mut self, c: Control) -> Self {
        self.control = c;
        self
    }
    pub(super) fn check(&self) -> Result<(), FairError> {
        for (name, v) in [
            ("fair weight ω1", self.fair_weight),
            ("difference weight ω2", self.diff_weight),
            ("curvature-Laplacian weight ω3", self.laplacian_weight),
        ] {
            if !(v >= 0.0) || !v.is_finite() {
                return Err(FairError::InvalidOption(format!(
                    "{name} must be a finite number ≥ 0, got {v}"
                )));
            }
        }
        if self.method != FairMethod::DiffusionFlow && self.fair_weight + self.diff_weight == 0.0 {
            return Err(FairError::InvalidOption(
                "at least one of the weights ω1, ω2 must be positive".into(),
            ));
        }
        if !(0.0..=1.0).contains(&self.flow_share) {
            return Err(FairError::InvalidOption(format!(
                "the diffusion-flow share must be a number in [0, 1], got {}",
                self.flow_share
            )));
        }
        if !(self.epsilon > 0.0) || !self.epsilon.is_finite() {
            return Err(FairError::InvalidOption(format!(
                "epsilon must be a positive number, got {}",
                self.epsilon
            )));
        }
        Ok(())
    }
}

/// Default [`FairOptions::refits`] (measured on the generated family: with
/// the fitted end tangents, refits lose
/// the widest saddle dent and cubic bump to diffusion flow).
pub const DEFAULT_REFITS: usize = 0;
/// Default [`FairOptions::flow_share`] (measured on the generated family:
/// without it the fitted end tangents
/// lose the widest cubic bump by 4 % in surface RMS).
pub const DEFAULT_FLOW_SHARE: f64 = 0.25;
