//! The whole smoothing family behind one entry point, chosen by method:
//! what `fairline smooth --method …`, the workbench and the Python `smooth`
//! call, so that the choice of method and the per-method defaults live in
//! one place. Each method is the function of its own module (Grüner thesis
//! ch. 3); this only routes the shared options to it.

use super::{
    ImplicitOptions, LaplaceOptions, SchneiderKobbeltOptions, SmoothError, SmoothReport,
    SpringOptions, TaubinOptions, implicit_smooth, laplace_smooth, schneider_kobbelt,
    spring_smooth, taubin_smooth,
};
use crate::control::{Control, Output};
use crate::geom::LaplaceWeights;
use crate::mesh::{SurfaceMesh, VertexId};
use serde::Serialize;

/// A method of the smoothing family; its [`SmoothMethod::name`] is the
/// CLI's `--method` value.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SmoothMethod {
    /// Laplace smoothing x' = x + λΔx (Grüner §3.2.2; [`laplace_smooth`]).
    Laplace,
    /// Taubin λ|μ smoothing (§3.2.3; [`taubin_smooth`]).
    #[default]
    Taubin,
    /// Backward Euler (M − tL)x' = Mx with the cotangent Laplacian (Desbrun
    /// et al.; [`implicit_smooth`]).
    Implicit,
    /// The spring model of Yamada et al. (§3.3; [`spring_smooth`]).
    Spring,
    /// Δ_B H = 0 with a G¹ boundary (Schneider and Kobbelt, §3.4;
    /// [`schneider_kobbelt`]).
    SchneiderKobbelt,
}

impl SmoothMethod {
    /// Every method, in the order of the CLI's `--method` list.
    pub const ALL: [SmoothMethod; 5] = [
        SmoothMethod::Laplace,
        SmoothMethod::Taubin,
        SmoothMethod::Implicit,
        SmoothMethod::Spring,
        SmoothMethod::SchneiderKobbelt,
    ];

    /// The method's name: the CLI's `--method` value.
    pub fn name(self) -> &'static str {
        match self {
            SmoothMethod::Laplace => "laplace",
            SmoothMethod::Taubin => "taubin",
            SmoothMethod::Implicit => "implicit",
            SmoothMethod::Spring => "spring",
            SmoothMethod::SchneiderKobbelt => "schneider-kobbelt",
        }
    }

    /// The method named `name` ([`SmoothMethod::name`]), if there is one.
    pub fn from_name(name: &str) -> Option<SmoothMethod> {
        SmoothMethod::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// Options of [`smooth`]: the method and the options of every method, each
/// used by the methods it applies to (the others ignore it, as the CLI's
/// `fairline smooth` does). `None` takes the method's own default.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct SmoothOptions {
    /// The method.
    pub method: SmoothMethod,
    /// Laplacian edge weights (laplace, taubin).
    pub weights: LaplaceWeights,
    /// λ (laplace: default 0.5; taubin: default from the pass band).
    pub lambda: Option<f64>,
    /// μ < −λ (taubin; default from the pass band).
    pub mu: Option<f64>,
    /// Taubin's pass band k_PB, 1/λ + 1/μ = k_PB (taubin).
    pub pass_band: f64,
    /// Time step of implicit smoothing in units of the squared mean edge
    /// length (implicit).
    pub time_step: f64,
    /// Convergence threshold (spring, schneider-kobbelt).
    pub epsilon: Option<f64>,
    /// Iterations (laplace, taubin: steps / λ|μ pairs; implicit: time
    /// steps; spring, schneider-kobbelt: the most sweeps). `None`: the
    /// method's default (10, 10, 1, 200, 50).
    pub iterations: Option<usize>,
    /// Most work in evaluations of Δ_B H at a vertex (schneider-kobbelt;
    /// `None`: [`super::DEFAULT_MAX_WORK`]).
    pub max_work: Option<u64>,
    /// Vertices that never move (bit-identical in the output).
    pub fixed: Vec<VertexId>,
    /// Keep every boundary vertex fixed (laplace, taubin, implicit).
    pub fix_boundary: bool,
    /// Smooth the boundary as curves first (laplace, taubin, implicit).
    pub hierarchical_boundary: bool,
    /// Keep the enclosed volume of a closed mesh (laplace, taubin,
    /// implicit).
    pub preserve_volume: bool,
    /// Move vertices only in their tangent planes (laplace, taubin,
    /// implicit).
    pub tangential_only: bool,
    /// Progress callback and cancel flag, handed to the method.
    pub control: Control,
}

impl Default for SmoothOptions {
    fn default() -> Self {
        let taubin = TaubinOptions::default();
        SmoothOptions {
            method: SmoothMethod::default(),
            weights: taubin.weights,
            lambda: None,
            mu: None,
            pass_band: taubin.pass_band,
            time_step: ImplicitOptions::default().time_step,
            epsilon: None,
            iterations: None,
            max_work: None,
            fixed: Vec::new(),
            fix_boundary: false,
            hierarchical_boundary: false,
            preserve_volume: false,
            tangential_only: false,
            control: Control::default(),
        }
    }
}

super::setters!(SmoothOptions {
    method: SmoothMethod,
    weights: LaplaceWeights,
    lambda: Option<f64>,
    mu: Option<f64>,
    pass_band: f64,
    time_step: f64,
    epsilon: Option<f64>,
    iterations: Option<usize>,
    max_work: Option<u64>,
    fixed: Vec<VertexId>,
    fix_boundary: bool,
    hierarchical_boundary: bool,
    preserve_volume: bool,
    tangential_only: bool,
    control: Control,
});

/// `opts` (the options of Laplace, Taubin or implicit smoothing) with the
/// constraints of Grüner §3.2.4 and the control of the [`SmoothOptions`] `o`.
macro_rules! with_constraints {
    ($opts:expr, $o:expr) => {
        $opts
            .fixed($o.fixed)
            .fix_boundary($o.fix_boundary)
            .hierarchical_boundary($o.hierarchical_boundary)
            .preserve_volume($o.preserve_volume)
            .tangential_only($o.tangential_only)
            .control($o.control)
    };
}

/// Smooths `mesh` with `options.method`: the method's own function with
/// the options that apply to it (see [`SmoothOptions`]); the result is
/// exactly that function's, or [`SmoothError::Diverged`] when it is not a
/// surface (non-finite, or moved beyond [`super::DIVERGED_DISPLACEMENT`]
/// diagonals; see [`super::check_diverged`]).
pub fn smooth(
    mesh: &SurfaceMesh,
    options: &SmoothOptions,
) -> Result<Output<SmoothReport>, SmoothError> {
    let o = options.clone();
    let out = match o.method {
        SmoothMethod::Laplace => {
            let d = LaplaceOptions::default();
            let opts = d
                .clone()
                .weights(o.weights)
                .lambda(o.lambda.unwrap_or(d.lambda))
                .iterations(o.iterations.unwrap_or(d.iterations));
            laplace_smooth(mesh, &with_constraints!(opts, o))
        }
        SmoothMethod::Taubin => {
            let d = TaubinOptions::default();
            let opts = d
                .clone()
                .weights(o.weights)
                .lambda(o.lambda)
                .mu(o.mu)
                .pass_band(o.pass_band)
                .iterations(o.iterations.unwrap_or(d.iterations));
            taubin_smooth(mesh, &with_constraints!(opts, o))
        }
        SmoothMethod::Implicit => {
            let d = ImplicitOptions::default();
            let opts = d
                .clone()
                .time_step(o.time_step)
                .iterations(o.iterations.unwrap_or(d.iterations));
            implicit_smooth(mesh, &with_constraints!(opts, o))
        }
        SmoothMethod::Spring => {
            let d = SpringOptions::default();
            let opts = d
                .clone()
                .epsilon(o.epsilon.unwrap_or(d.epsilon))
                .max_iterations(o.iterations.unwrap_or(d.max_iterations));
            spring_smooth(mesh, &opts.fixed(o.fixed).control(o.control))
        }
        SmoothMethod::SchneiderKobbelt => {
            let d = SchneiderKobbeltOptions::default();
            let opts = d
                .clone()
                .epsilon(o.epsilon.unwrap_or(d.epsilon))
                .max_iterations(o.iterations.unwrap_or(d.max_iterations))
                .max_work(o.max_work.unwrap_or(d.max_work));
            schneider_kobbelt(mesh, &opts.fixed(o.fixed).control(o.control))
        }
    }?;
    super::check_diverged(mesh, out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    fn noisy_sphere() -> SurfaceMesh {
        let mut m = shapes::icosphere(1.0, 2);
        for (i, p) in m.positions_mut().iter_mut().enumerate() {
            *p *= 1.0 + 0.02 * ((i * 7919 % 13) as f64 / 6.0 - 1.0);
        }
        m
    }

    #[test]
    fn every_method_gives_exactly_what_its_own_function_gives() {
        let mesh = noisy_sphere();
        let fixed = vec![VertexId(3), VertexId(40)];
        let by = |method| {
            smooth(
                &mesh,
                &SmoothOptions::default()
                    .method(method)
                    .iterations(Some(4))
                    .fixed(fixed.clone()),
            )
            .unwrap()
        };
        let laplace = LaplaceOptions::default().iterations(4).fixed(fixed.clone());
        assert_eq!(
            by(SmoothMethod::Laplace),
            laplace_smooth(&mesh, &laplace).unwrap()
        );
        let taubin = TaubinOptions::default().iterations(4).fixed(fixed.clone());
        assert_eq!(
            by(SmoothMethod::Taubin),
            taubin_smooth(&mesh, &taubin).unwrap()
        );
        let implicit = ImplicitOptions::default()
            .iterations(4)
            .fixed(fixed.clone());
        assert_eq!(
            by(SmoothMethod::Implicit),
            implicit_smooth(&mesh, &implicit).unwrap()
        );
        let spring = SpringOptions::default()
            .max_iterations(4)
            .fixed(fixed.clone());
        assert_eq!(
            by(SmoothMethod::Spring),
            spring_smooth(&mesh, &spring).unwrap()
        );
        let sk = SchneiderKobbeltOptions::default()
            .max_iterations(4)
            .fixed(fixed.clone());
        assert_eq!(
            by(SmoothMethod::SchneiderKobbelt),
            schneider_kobbelt(&mesh, &sk).unwrap()
        );
        // the options that apply reach the method: λ, weights, volume
        let o = SmoothOptions::default()
            .method(SmoothMethod::Laplace)
            .lambda(Some(0.3))
            .weights(LaplaceWeights::Cotangent)
            .preserve_volume(true);
        let direct = LaplaceOptions::default()
            .lambda(0.3)
            .weights(LaplaceWeights::Cotangent)
            .preserve_volume(true);
        assert_eq!(
            smooth(&mesh, &o).unwrap(),
            laplace_smooth(&mesh, &direct).unwrap()
        );
    }

    #[test]
    fn names_round_trip_and_unknown_names_are_none() {
        for m in SmoothMethod::ALL {
            assert_eq!(SmoothMethod::from_name(m.name()), Some(m));
            assert_eq!(
                serde_json::to_value(m).unwrap(),
                serde_json::json!(m.name())
            );
        }
        assert_eq!(SmoothMethod::from_name("gauss"), None);
    }
}
