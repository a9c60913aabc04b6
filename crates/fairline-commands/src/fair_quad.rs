//! `fair-quad`: structure-line fairing of a quad mesh (Grüner thesis ch. 4,
//! Eq. (30)–(34)), or the fair polyline network with tolerance cylinders
//! (§3.1.1), as every front end runs it.

use crate::error::{CommandError, Subject};
use crate::report::Report;
use crate::warning::Warning;
use crate::words::{push_changed, push_switch};
use fairline::fair::{
    PolylineNetworkOptions, QuadFairOptions, QuadFairReport, fair_polyline_network,
    fair_structure_lines, structure_energy,
};
use fairline::mesh::VertexId;
use fairline::{Control, SurfaceMesh, Vec3};

/// What `fair-quad` minimises.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum QuadMethod {
    /// The straightness of the structure lines, Eq. (30)–(34) (ch. 4).
    #[default]
    StructureLines,
    /// The height-only bending energy of the polyline network, every vertex
    /// inside its tolerance cylinder (§3.1.1, Eq. (11) after Hofer et al.).
    Network,
}

/// The options of `fair-quad` (defaults: the CLI's).
#[derive(Clone, Debug, PartialEq)]
pub struct QuadSettings {
    /// What is minimised.
    pub method: QuadMethod,
    /// Half height h of the tolerance cylinders of
    /// [`QuadMethod::Network`], in mean edge lengths (|z − z⁰| ≤ h·ē).
    pub tolerance: f64,
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
    /// Per-vertex penalty weights by deviation
    /// ([`fairline::fair::QuadFairOptions::deviation_weights`]).
    pub deviation_weights: bool,
}

impl Default for QuadSettings {
    fn default() -> Self {
        QuadSettings {
            method: QuadMethod::StructureLines,
            tolerance: 0.1,
            weight: 0.01,
            deviation: 0.1,
            deviation_factor: 0.1,
            iterations: 3,
            fix_boundary: false,
            fixed: Vec::new(),
            off_surface: false,
            deviation_weights: false,
        }
    }
}

impl QuadSettings {
    /// Refuses a weight that is not positive, a negative deviation and a
    /// factor that is not positive (naming the option).
    pub fn check(&self) -> Result<(), CommandError> {
        if !self.tolerance.is_finite() || self.tolerance < 0.0 {
            return Err(CommandError::invalid("tolerance", "must be ≥ 0"));
        }
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
        if self.method == QuadMethod::Network {
            let mut c = format!(
                "fairline fair-quad {input} --method network --tolerance {}",
                self.tolerance
            );
            push_switch(&mut c, "fix-boundary", self.fix_boundary);
            if !self.fixed.is_empty() {
                c.push_str(" --fixed fixed.json");
            }
            c.push_str(&format!(" -o {output}"));
            return c;
        }
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
        push_switch(&mut c, "deviation-weights", self.deviation_weights);
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

/// Fairs the structure lines of the quad mesh `mesh` (or its polyline
/// network, [`QuadMethod::Network`]).
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
    if settings.method == QuadMethod::Network {
        return run_network(mesh, settings, control);
    }
    let options = QuadFairOptions::default()
        .weight(settings.weight)
        .deviation(settings.deviation)
        .deviation_factor(settings.deviation_factor)
        .iterations(settings.iterations)
        .fix_boundary(settings.fix_boundary)
        .fixed(settings.fixed.clone())
        .on_surface(!settings.off_surface)
        .deviation_weights(settings.deviation_weights)
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

/// The fair polyline network with tolerance cylinders (Grüner thesis
/// §3.1.1): only the heights move, each within ±h·ē of its input (h =
/// `settings.tolerance`, ē the mean edge length); fixed vertices and, with
/// `fix_boundary`, the boundary get no tolerance. The report carries the
/// structure-line keys (Eq. (30) energy before and after, vertices free to
/// move, QP iterations) and the network's own: `network_energy_before`,
/// `network_energy_after`, `at_bound` (vertices on the top or bottom of
/// their cylinder), `tolerance`.
fn run_network(
    mesh: &SurfaceMesh,
    settings: &QuadSettings,
    control: &Control,
) -> Result<QuadOutcome, CommandError> {
    let ebar = fairline::geom::mean_edge_length(mesh);
    let mut h = vec![settings.tolerance * ebar; mesh.vertex_count()];
    for v in &settings.fixed {
        if let Some(x) = h.get_mut(v.idx()) {
            *x = 0.0;
        }
    }
    if settings.fix_boundary {
        for v in mesh.vertices() {
            if mesh.is_boundary_vertex(v) {
                h[v.idx()] = 0.0;
            }
        }
    }
    let free_vertices = h.iter().filter(|x| **x > 0.0).count();
    let options = PolylineNetworkOptions::default()
        .tolerance(settings.tolerance)
        .per_vertex(Some(h))
        .control(control.clone());
    let mut report = Report::new("fair-quad");
    let out = report.time(|| fair_polyline_network(mesh, &options))?;
    let n = out.report;
    let mut after = mesh.clone();
    after.set_positions(out.positions.clone())?;
    let max_displacement = out
        .positions
        .iter()
        .zip(mesh.positions())
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    let r = QuadFairReport {
        vertices: mesh.vertex_count(),
        structure_lines: fairline::mesh::structure_lines(mesh).len(),
        free_vertices,
        structure_energy_before: structure_energy(mesh),
        structure_energy_after: structure_energy(&after),
        max_displacement,
        iterations: n.iterations,
    };
    report.set_fields(&r);
    if r.structure_energy_after > r.structure_energy_before {
        report.warn(Warning::NetworkStructureWorse {
            before: r.structure_energy_before,
            after: r.structure_energy_after,
        });
    }
    report.set("method", "network");
    report.set("tolerance", settings.tolerance);
    report.set("network_energy_before", n.energy_before);
    report.set("network_energy_after", n.energy_after);
    report.set("at_bound", n.at_bound);
    Ok(QuadOutcome {
        positions: out.positions,
        result: r,
        report,
    })
}
