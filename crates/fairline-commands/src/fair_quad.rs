//! `fair-quad`: structure-line fairing of a quad mesh (Grüner thesis ch. 4,
//! Eq. (30)–(34)), as every front end runs it.

use crate::error::{CommandError, Subject};
use crate::report::Report;
use crate::warning::Warning;
use crate::words::{push_changed, push_switch};
use fairline::fair::{QuadFairOptions, QuadFairReport, fair_structure_lines};
use fairline::mesh::VertexId;
use fairline::{Control, SurfaceMesh, Vec3};

/// The options of `fair-quad` (defaults: the CLI's).
#[derive(Clone, Debug, PartialEq)]
pub struct QuadSettings {
    /// Penalty weight ω (scale-invariant).
    pub weight: f64,
    /// Runs whose Eq. (30) deviation exceeds it free their middle points.
    pub deviation: f64,
    /// Factor applied to the deviation after every iteration.
    pub deviation_factor: f64,
    /// Iterations.
    pub iterations: usize,
    /// Keep every boundary vertex fixed.
    pub fix_boundary: bool,
    /// Vertices that never move.
    pub fixed: Vec<VertexId>,
    /// Let the points leave the input surface (Eq. (34) as printed).
    pub off_surface: bool,
}

impl Default for QuadSettings {
    fn default() -> Self {
        QuadSettings {
            weight: 0.01,
            deviation: 0.1,
            deviation_factor: 0.1,
            iterations: 3,
            fix_boundary: false,
            fixed: Vec::new(),
            off_surface: false,
        }
    }
}

impl QuadSettings {
    /// Refuses a weight that is not positive, a negative deviation and a
    /// factor that is not positive (naming the option).
    pub fn check(&self) -> Result<(), CommandError> {
        if !self.weight.is_finite() || self.weight <= 0.0 {
            return Err(CommandError::invalid("weight", "must be a positive number"));
        }
        if !self.deviation.is_finite() || self.deviation < 0.0 {
            return Err(CommandError::invalid("deviation", "must be ≥ 0"));
        }
        if !self.deviation_factor.is_finite() || self.deviation_factor <= 0.0 {
            return Err(CommandError::invalid(
                "deviation-factor",
                "must be positive",
            ));
        }
        Ok(())
    }

    /// The `fairline fair-quad` command line of these settings on `input`,
    /// writing `output` (shell words); fixed vertices from `fixed.json`.
    pub fn command_line(&self, input: &str, output: &str) -> String {
        let d = QuadSettings::default();
        let mut c = format!(
            "fairline fair-quad {input} --weight {} --iterations {}",
            self.weight, self.iterations
        );
        push_changed(&mut c, "deviation", self.deviation, d.deviation);
        push_changed(
            &mut c,
            "deviation-factor",
            self.deviation_factor,
            d.deviation_factor,
        );
        push_switch(&mut c, "fix-boundary", self.fix_boundary);
        push_switch(&mut c, "off-surface", self.off_surface);
        if !self.fixed.is_empty() {
            c.push_str(" --fixed fixed.json");
        }
        c.push_str(&format!(" -o {output}"));
        c
    }
}

/// What `fair-quad` gives.
#[derive(Clone, Debug)]
pub struct QuadOutcome {
    /// The new positions of the input's vertices.
    pub positions: Vec<Vec3>,
    /// What the fairing did.
    pub result: QuadFairReport,
    /// The JSON report.
    pub report: Report,
}

/// Fairs the structure lines of the quad mesh `mesh`.
pub fn run(
    mesh: &SurfaceMesh,
    settings: &QuadSettings,
    control: &Control,
) -> Result<QuadOutcome, CommandError> {
    settings.check()?;
    crate::require_faces(mesh.face_count(), mesh.original_vertex_count())?;
    if !mesh.faces().any(|f| mesh.face_size(f) == 4) {
        return Err(CommandError::bad_input(
            "fair-quad needs a quad mesh (no quadrilateral found)",
        )
        .about(Subject::Input));
    }
    let options = QuadFairOptions::default()
        .weight(settings.weight)
        .deviation(settings.deviation)
        .deviation_factor(settings.deviation_factor)
        .iterations(settings.iterations)
        .fix_boundary(settings.fix_boundary)
        .fixed(settings.fixed.clone())
        .on_surface(!settings.off_surface)
        .control(control.clone());
    let mut report = Report::new("fair-quad");
    let out = report.time(|| fair_structure_lines(mesh, &options))?;
    let r = out.report;
    report.set_fields(&r);
    if r.structure_energy_after > r.structure_energy_before {
        report.warn(Warning::QuadEnergyWorse {
            before: r.structure_energy_before,
            after: r.structure_energy_after,
        });
    }
    Ok(QuadOutcome {
        positions: out.positions,
        result: r,
        report,
    })
}
