//! The names of the choices a user makes (methods, weights, solvers,
//! projections, axes), parsed in one place: every front end lists and
//! parses them with [`Choice`] (the CLI gives the list to its argument
//! parser, Python and the workbench parse the strings they get).

use crate::error::CommandError;
use fairline::enhance::{EnhanceSolver, Projection};
use fairline::fair::FairMethod;
use fairline::geom::{CurvatureMethod, LaplaceWeights};
use fairline::highlight::UpAxis;
use fairline::smooth::SmoothMethod;

/// One value of a choice: its name, the value and a one-line help.
#[derive(Clone, Copy, Debug)]
pub struct Named<T: 'static> {
    /// The name users type.
    pub name: &'static str,
    /// The value.
    pub value: T,
    /// What it means, in one sentence.
    pub help: &'static str,
}

/// A choice between named values.
pub trait Choice: Copy + PartialEq + 'static {
    /// The option that takes the choice (the CLI's long name without `--`).
    const OPTION: &'static str;
    /// Every value, in the order of the help.
    const ALL: &'static [Named<Self>];

    /// The names, in order.
    fn names() -> Vec<&'static str> {
        Self::ALL.iter().map(|n| n.name).collect()
    }

    /// The value named `name`; a bad-input error naming the option and
    /// listing the names otherwise.
    fn parse(name: &str) -> Result<Self, CommandError> {
        Self::ALL
            .iter()
            .find(|n| n.name == name)
            .map(|n| n.value)
            .ok_or_else(|| {
                CommandError::invalid(
                    Self::OPTION,
                    format!("must be one of {}; got {name:?}", Self::names().join(", ")),
                )
            })
    }

    /// The name of `self`.
    fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|n| n.value == self)
            .map_or("", |n| n.name)
    }
}

impl Choice for FairMethod {
    const OPTION: &'static str = "method";
    const ALL: &'static [Named<Self>] = &[
        Named {
            name: "highlight",
            value: FairMethod::Highlight,
            help: "Yong et al.'s energy with end tangents from a smooth fit beyond the defect, then ¾ of that result + ¼ of the diffusion-flow result",
        },
        Named {
            name: "paper",
            value: FairMethod::Paper,
            help: "Yong et al. exactly (Algorithm 2): Willmore energy + distance of the highlight lines to their desired curves",
        },
        Named {
            name: "diffusion-flow",
            value: FairMethod::DiffusionFlow,
            help: "Baseline: surface diffusion flow ∂V/∂t = N Δ_B H (Xu et al.)",
        },
        Named {
            name: "membrane",
            value: FairMethod::Membrane,
            help: "Membrane energy, ΔX = 0 on the movable vertices (Grüner §3.1.2, Eq. (14)); no lights",
        },
        Named {
            name: "thin-plate",
            value: FairMethod::ThinPlate,
            help: "Thin-plate energy, Δ²X = 0 on the movable vertices (Grüner §3.1.2, Eq. (13)); no lights",
        },
        Named {
            name: "mvs",
            value: FairMethod::Mvs,
            help: "Minimum variation of curvature, Δ³X = 0 on the movable vertices (Grüner §3.1.3); no lights",
        },
    ];
}

impl Choice for crate::fair_quad::QuadMethod {
    const OPTION: &'static str = "method";
    const ALL: &'static [Named<Self>] = &[
        Named {
            name: "structure-lines",
            value: crate::fair_quad::QuadMethod::StructureLines,
            help: "Straighten the structure lines (Grüner ch. 4, Eq. (30)–(34))",
        },
        Named {
            name: "network",
            value: crate::fair_quad::QuadMethod::Network,
            help: "Fair polyline network: least bending of the heights, each inside its tolerance cylinder (Grüner §3.1.1)",
        },
    ];
}

impl Choice for SmoothMethod {
    const OPTION: &'static str = "method";
    const ALL: &'static [Named<Self>] = &[
        Named {
            name: "laplace",
            value: SmoothMethod::Laplace,
            help: "Laplace smoothing x' = x + λΔx (Grüner §3.2.2)",
        },
        Named {
            name: "taubin",
            value: SmoothMethod::Taubin,
            help: "Taubin λ|μ: a λ step then a μ step per iteration (§3.2.3)",
        },
        Named {
            name: "implicit",
            value: SmoothMethod::Implicit,
            help: "Backward Euler (M − tL)x' = Mx, cotangent L (Desbrun et al.); triangles",
        },
        Named {
            name: "spring",
            value: SmoothMethod::Spring,
            help: "Spring model of Yamada et al. (§3.3); boundary fixed",
        },
        Named {
            name: "schneider-kobbelt",
            value: SmoothMethod::SchneiderKobbelt,
            help: "Δ_B H = 0 with G¹ boundary (Schneider and Kobbelt, §3.4); triangles",
        },
    ];
}

/// The Laplacian edge weights a user picks (the exponent of the
/// edge-length weights is its own option).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Weights {
    /// w = 1 (umbrella).
    #[default]
    Uniform,
    /// w = |e|^exponent (Fujiwara).
    Edge,
    /// Cotangent weights (Desbrun); triangle meshes.
    Cotan,
}

impl Weights {
    /// The library's weights, `exponent` for [`Weights::Edge`].
    pub fn laplace(self, exponent: f64) -> LaplaceWeights {
        match self {
            Weights::Uniform => LaplaceWeights::Uniform,
            Weights::Edge => LaplaceWeights::EdgeLength { exponent },
            Weights::Cotan => LaplaceWeights::Cotangent,
        }
    }
}

impl Choice for Weights {
    const OPTION: &'static str = "weights";
    const ALL: &'static [Named<Self>] = &[
        Named {
            name: "uniform",
            value: Weights::Uniform,
            help: "w = 1 (umbrella)",
        },
        Named {
            name: "edge",
            value: Weights::Edge,
            help: "w = |e|^exponent (exponent −1 by default, Fujiwara)",
        },
        Named {
            name: "cotan",
            value: Weights::Cotan,
            help: "Cotangent weights (Desbrun); triangle meshes",
        },
    ];
}

impl Choice for EnhanceSolver {
    const OPTION: &'static str = "solver";
    const ALL: &'static [Named<Self>] = &[
        Named {
            name: "auto",
            value: EnhanceSolver::Auto,
            help: "amg on meshes with large flat or cylindrical parts, else cg, amg from where cg stalls",
        },
        Named {
            name: "direct",
            value: EnhanceSolver::Direct,
            help: "Sparse Cholesky (memory-hungry)",
        },
        Named {
            name: "cg",
            value: EnhanceSolver::Cg,
            help: "Block-Jacobi conjugate gradients",
        },
        Named {
            name: "amg",
            value: EnhanceSolver::Amg,
            help: "Conjugate gradients preconditioned by a multigrid bi-Laplacian model",
        },
    ];
}

impl Choice for Projection {
    const OPTION: &'static str = "projection";
    const ALL: &'static [Named<Self>] = &[
        Named {
            name: "smooth",
            value: Projection::Smooth,
            help: "Onto the Phong patch of the nearest input triangle",
        },
        Named {
            name: "mesh",
            value: Projection::Mesh,
            help: "Onto the nearest point of the input mesh",
        },
        Named {
            name: "none",
            value: Projection::None,
            help: "The paper's method: along tangent planes",
        },
    ];
}

impl Choice for CurvatureMethod {
    const OPTION: &'static str = "method";
    const ALL: &'static [Named<Self>] = &[
        Named {
            name: "rusinkiewicz",
            value: CurvatureMethod::Rusinkiewicz,
            help: "Per-face curvature tensors (Rusinkiewicz 2004)",
        },
        Named {
            name: "meyer",
            value: CurvatureMethod::Meyer,
            help: "Discrete operators of Meyer et al. 2003",
        },
    ];
}

impl Choice for UpAxis {
    const OPTION: &'static str = "up";
    const ALL: &'static [Named<Self>] = &[
        Named {
            name: "auto",
            value: UpAxis::Auto,
            help: "From the part's principal axes",
        },
        Named {
            name: "x",
            value: UpAxis::X,
            help: "+x",
        },
        Named {
            name: "y",
            value: UpAxis::Y,
            help: "+y",
        },
        Named {
            name: "z",
            value: UpAxis::Z,
            help: "+z",
        },
    ];
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_bad_names_list_the_choices() {
        for n in <SmoothMethod as Choice>::ALL {
            assert_eq!(<SmoothMethod as Choice>::parse(n.name), Ok(n.value));
            assert_eq!(Choice::name(n.value), n.name);
        }
        let e = <FairMethod as Choice>::parse("fast").unwrap_err();
        assert_eq!(
            e.message(crate::FrontEnd::Python),
            "method must be one of highlight, paper, diffusion-flow, membrane, thin-plate, mvs; got \"fast\""
        );
    }
}
