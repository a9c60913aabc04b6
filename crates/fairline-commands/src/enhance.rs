//! `enhance`: feature enhancement by vertex flow (Ji et al. 2011), as every
//! front end runs it.

use crate::error::{CommandError, Subject};
use crate::names::Choice;
use crate::report::Report;
use crate::warning::Warning;
use fairline::enhance::{
    EnhanceOptions, EnhanceReport, EnhanceSolver, Projection, enhance_features,
};
use fairline::mesh::VertexId;
use fairline::{Control, SurfaceMesh, Vec3};

/// The options of `enhance` (defaults: the CLI's).
#[derive(Clone, Debug, PartialEq)]
pub struct EnhanceSettings {
    /// λ, weight of the squared-distance term.
    pub lambda: f64,
    /// μ, weight of the fairness term.
    pub mu: f64,
    /// Solves.
    pub iterations: usize,
    /// Solver of the least-squares system.
    pub solver: EnhanceSolver,
    /// Where the vertices go after each solve.
    pub projection: Projection,
    /// Vertices that must not move.
    pub fixed: Vec<VertexId>,
}

impl Default for EnhanceSettings {
    fn default() -> Self {
        EnhanceSettings {
            lambda: 1.0,
            mu: 0.5,
            iterations: 1,
            solver: EnhanceSolver::Auto,
            projection: Projection::Smooth,
            fixed: Vec::new(),
        }
    }
}

impl EnhanceSettings {
    /// The `fairline enhance` command line of these settings on `input`,
    /// writing `output` (shell words); fixed vertices from `fixed.json`.
    pub fn command_line(&self, input: &str, output: &str) -> String {
        let d = EnhanceSettings::default();
        let mut c = format!(
            "fairline enhance {input} --lambda {} --mu {} --iterations {}",
            self.lambda, self.mu, self.iterations
        );
        if self.solver != d.solver {
            c.push_str(&format!(" --solver {}", self.solver.name()));
        }
        if self.projection != d.projection {
            c.push_str(&format!(" --projection {}", self.projection.name()));
        }
        if !self.fixed.is_empty() {
            c.push_str(" --fixed fixed.json");
        }
        c.push_str(&format!(" -o {output}"));
        c
    }
}

/// What `enhance` gives.
#[derive(Clone, Debug)]
pub struct EnhanceOutcome {
    /// The new positions of the input's vertices.
    pub positions: Vec<Vec3>,
    /// What the vertex flow did.
    pub result: EnhanceReport,
    /// The JSON report.
    pub report: Report,
}

/// Enhances the features of the triangle mesh `mesh`.
pub fn run(
    mesh: &SurfaceMesh,
    settings: &EnhanceSettings,
    control: &Control,
) -> Result<EnhanceOutcome, CommandError> {
    crate::require_faces(mesh.face_count(), mesh.original_vertex_count())?;
    if !mesh.is_triangle_mesh() {
        return Err(CommandError::bad_input(
            "enhance needs a triangle mesh (triangulate it first, e.g. with `fairline convert`)",
        )
        .about(Subject::Input));
    }
    let options = EnhanceOptions::default()
        .lambda(settings.lambda)
        .mu(settings.mu)
        .iterations(settings.iterations)
        .solver(settings.solver)
        .projection(settings.projection)
        .fixed(settings.fixed.clone())
        .control(control.clone());
    let mut report = Report::new("enhance");
    let out = report.time(|| enhance_features(mesh, &options))?;
    let r = out.report;
    report.set_fields(&r);
    report.set("histogram_before", &r.quality_before.histogram);
    report.set("histogram_after", &r.quality_after.histogram);
    if r.flipped_triangles > 0 {
        report.warn(Warning::TrianglesFlipped {
            count: r.flipped_triangles,
        });
    }
    Ok(EnhanceOutcome {
        positions: out.positions,
        result: r,
        report,
    })
}
