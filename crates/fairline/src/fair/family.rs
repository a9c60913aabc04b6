//! A generated family of fairing problems with a known defect-free truth:
//! car-panel-like height fields (quadratic, cubic,
//! wavy, saddle-like) with a planted Gaussian bump or dent of several
//! sizes, the region around it, the lights, and the two measures the
//! comparison of highlight-line fairing with surface diffusion flow uses:
//! surface distance to the truth inside the region and distance of the
//! result's highlight lines to the truth's lines under the same lights.

use super::FairReport;
use super::desired::distance_to_polyline;
use crate::Vec3;
use crate::highlight::{HighlightLines, HighlightModel, HighlightOptions, LightArray};
use crate::io::RegionSpec;
use crate::mesh::{FaceId, SurfaceMesh};
use crate::shapes;

/// A smooth panel z = f(x, y) over [−1, 1]².
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Panel {
    /// Crowned roof 0.25 (1 − 0.4 x² − 0.3 y²).
    Quadratic,
    /// The roof with cubic terms 0.04 x³ − 0.03 x y².
    Cubic,
    /// The roof with a wave 0.02 sin(3x + 1) cos(2y).
    Wavy,
    /// Saddle-like 0.12 x² − 0.08 y² + 0.02 x y.
    Saddle,
}

impl Panel {
    pub(crate) const ALL: [Panel; 4] = [Panel::Quadratic, Panel::Cubic, Panel::Wavy, Panel::Saddle];

    pub(crate) fn height(self, x: f64, y: f64) -> f64 {
        let roof = 0.25 * (1.0 - 0.4 * x * x - 0.3 * y * y);
        match self {
            Panel::Quadratic => roof,
            Panel::Cubic => roof + 0.04 * x * x * x - 0.03 * x * y * y,
            Panel::Wavy => roof + 0.02 * (3.0 * x + 1.0).sin() * (2.0 * y).cos(),
            Panel::Saddle => 0.12 * x * x - 0.08 * y * y + 0.02 * x * y,
        }
    }

    pub(crate) fn name(self) -> &'static str {
        match self {
            Panel::Quadratic => "quadratic",
            Panel::Cubic => "cubic",
            Panel::Wavy => "wavy",
            Panel::Saddle => "saddle",
        }
    }
}

/// One case: a panel, a Gaussian defect of width `sigma` and signed
/// amplitude `amplitude` (positive: bump) at [`DEFECT_CENTER`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct Case {
    pub panel: Panel,
    pub sigma: f64,
    pub amplitude: f64,
    /// Where the defect sits (x, y); [`DEFECT_CENTER`] in the family.
    pub center: (f64, f64),
}

/// Where the defect sits (x, y).
pub(crate) const DEFECT_CENTER: (f64, f64) = (0.1, -0.05);
/// Grid vertices per side.
pub(crate) const GRID: u32 = 41;

impl Case {
    /// Every panel × {bump, dent} × σ ∈ {0.08, 0.11, 0.15}, amplitude
    /// ±0.2 σ.
    pub(crate) fn family() -> Vec<Case> {
        let mut out = Vec::new();
        for panel in Panel::ALL {
            for sigma in [0.08, 0.11, 0.15] {
                for sign in [1.0, -1.0] {
                    out.push(Case {
                        panel,
                        sigma,
                        amplitude: sign * 0.2 * sigma,
                        center: DEFECT_CENTER,
                    });
                }
            }
        }
        out
    }

    /// Cases held out of the tuning: the same panels with the defect at
    /// two other places and of two other widths (σ 0.09, 0.13).
    pub(crate) fn held_out() -> Vec<Case> {
        let mut out = Vec::new();
        for center in [(-0.15, 0.2), (0.25, 0.1)] {
            for panel in Panel::ALL {
                for sigma in [0.09, 0.13] {
                    for sign in [1.0, -1.0] {
                        out.push(Case {
                            panel,
                            sigma,
                            amplitude: sign * 0.2 * sigma,
                            center,
                        });
                    }
                }
            }
        }
        out
    }

    /// Unit direction of the truth's highlight line (level line of the
    /// highlight distance of Eq. (1) on the exact panel) through the panel
    /// point above (x, y), oriented along `reference`.
    pub(crate) fn truth_line_direction(
        &self,
        light: &LightArray,
        x: f64,
        y: f64,
        reference: Vec3,
    ) -> Option<Vec3> {
        let f = |x: f64, y: f64| self.panel.height(x, y);
        let e = 1e-5;
        let grad = |x: f64, y: f64| {
            (
                (f(x + e, y) - f(x - e, y)) / (2.0 * e),
                (f(x, y + e) - f(x, y - e)) / (2.0 * e),
            )
        };
        let d = |x: f64, y: f64| {
            let (fx, fy) = grad(x, y);
            let n = Vec3::new(-fx, -fy, 1.0).normalize();
            light.highlight_distance(Vec3::new(x, y, f(x, y)), n, 0.1)
        };
        let h = 1e-4;
        let dx = (d(x + h, y)? - d(x - h, y)?) / (2.0 * h);
        let dy = (d(x, y + h)? - d(x, y - h)?) / (2.0 * h);
        let (fx, fy) = grad(x, y);
        let t = (-dy * Vec3::new(1.0, 0.0, fx) + dx * Vec3::new(0.0, 1.0, fy)).normalize_or_zero();
        if t == Vec3::ZERO {
            return None;
        }
        Some(if t.dot(reference) < 0.0 { -t } else { t })
    }

    pub(crate) fn label(&self) -> String {
        format!(
            "{} {} σ={}",
            self.panel.name(),
            if self.amplitude > 0.0 { "bump" } else { "dent" },
            self.sigma
        )
    }

    fn defect(&self, x: f64, y: f64) -> f64 {
        let (dx, dy) = (x - self.center.0, y - self.center.1);
        self.amplitude * (-(dx * dx + dy * dy) / (2.0 * self.sigma * self.sigma)).exp()
    }

    /// The defect-free truth sampled on the grid.
    pub(crate) fn truth_mesh(&self) -> SurfaceMesh {
        let p = self.panel;
        shapes::height_field(GRID, GRID, (-1.0, 1.0), (-1.0, 1.0), move |x, y| {
            p.height(x, y)
        })
    }

    /// The truth plus the planted defect.
    pub(crate) fn input_mesh(&self) -> SurfaceMesh {
        let c = *self;
        shapes::height_field(GRID, GRID, (-1.0, 1.0), (-1.0, 1.0), move |x, y| {
            c.panel.height(x, y) + c.defect(x, y)
        })
    }

    /// The region: the ball of radius 3.5 σ + 3 grid spacings around the
    /// defect (two rings of the margin are the support of §3.1).
    pub(crate) fn region(&self, mesh: &SurfaceMesh) -> Vec<FaceId> {
        let h = 2.0 / (GRID - 1) as f64;
        let (x, y) = self.center;
        RegionSpec::Sphere {
            center: Vec3::new(x, y, self.panel.height(x, y)),
            radius: 3.5 * self.sigma + 3.0 * h,
        }
        .faces(mesh)
        .unwrap_or_default()
    }

    /// Parallel lights along x in the plane through (0, 0, 3), tilted
    /// toward y, spacing 0.06.
    pub(crate) fn light(&self) -> LightArray {
        LightArray::new(
            Vec3::new(0.0, 0.0, 3.0),
            Vec3::new(0.0, 0.15, 1.0),
            Vec3::X,
            0.06,
        )
        .expect("valid light array")
    }

    /// Distance of `p` to the truth surface, to first order:
    /// |z − f(x, y)| / √(1 + |∇f|²).
    pub(crate) fn truth_distance(&self, p: Vec3) -> f64 {
        let f = |x: f64, y: f64| self.panel.height(x, y);
        let e = 1e-6;
        let fx = (f(p.x + e, p.y) - f(p.x - e, p.y)) / (2.0 * e);
        let fy = (f(p.x, p.y + e) - f(p.x, p.y - e)) / (2.0 * e);
        (p.z - f(p.x, p.y)).abs() / (1.0 + fx * fx + fy * fy).sqrt()
    }
}

/// Max and RMS of a list of distances.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct MaxRms {
    pub max: f64,
    pub rms: f64,
}

impl MaxRms {
    fn of(d: &[f64]) -> MaxRms {
        if d.is_empty() {
            return MaxRms::default();
        }
        MaxRms {
            max: d.iter().copied().fold(0.0, f64::max),
            rms: (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt(),
        }
    }
}

/// Surface distance to the truth over the inside vertices of the region.
pub(crate) fn surface_error(case: &Case, r: &FairReport, mesh: &SurfaceMesh) -> MaxRms {
    let d: Vec<f64> = r
        .region
        .inside_vertices
        .iter()
        .map(|v| case.truth_distance(mesh.position(*v)))
        .collect();
    MaxRms::of(&d)
}

/// Distance between the highlight lines of `mesh` and those of the truth
/// (same lights) inside the region: every inside node of either model to
/// the nearest line of the other with the same index; max and RMS over
/// both directions. A line that exists in one model only counts with its
/// distance to nothing: infinity.
pub(crate) fn line_error(
    r: &FairReport,
    mesh: &SurfaceMesh,
    truth: &SurfaceMesh,
    truth_lines: &HighlightLines,
    light: &LightArray,
) -> MaxRms {
    let lines = HighlightModel::new(mesh, *light, HighlightOptions::default())
        .expect("highlight model")
        .lines(mesh);
    let mut d = Vec::new();
    let mut one_way = |from: &HighlightLines, from_mesh: &SurfaceMesh, to: &HighlightLines| {
        for l in &from.lines {
            for (n, p) in l.nodes.iter().zip(&l.points) {
                if !r.region.node_inside(from_mesh, *n) {
                    continue;
                }
                let dist = to
                    .lines
                    .iter()
                    .filter(|t| t.index == l.index)
                    .map(|t| {
                        let mut pts = t.points.clone();
                        if t.closed && !pts.is_empty() {
                            pts.push(pts[0]);
                        }
                        distance_to_polyline(*p, &pts)
                    })
                    .fold(f64::INFINITY, f64::min);
                d.push(dist);
            }
        }
    };
    one_way(&lines, mesh, truth_lines);
    one_way(truth_lines, truth, &lines);
    MaxRms::of(&d)
}

/// The truth's lines under the case's lights.
pub(crate) fn truth_lines(truth: &SurfaceMesh, light: &LightArray) -> HighlightLines {
    HighlightModel::new(truth, *light, HighlightOptions::default())
        .expect("highlight model")
        .lines(truth)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fair::tests::fair;
    use crate::fair::{FairMethod, FairOptions};

    /// Surface max, surface RMS, line max, line RMS of one run.
    type Measures = [f64; 4];

    /// Runs `options` and the diffusion-flow baseline on every case of
    /// `cases`; checks that every vertex that is not movable is
    /// bit-identical to the input for both (then so is every normal and
    /// highlight node outside the region, §3.1); returns (case, measures of
    /// `options`, measures of the baseline).
    fn against_flow_on(cases: &[Case], options: &FairOptions) -> Vec<(String, Measures, Measures)> {
        let flow_options = FairOptions::default().method(FairMethod::DiffusionFlow);
        cases
            .iter()
            .map(|case| {
                let (mesh, truth, light) = (case.input_mesh(), case.truth_mesh(), case.light());
                let tl = truth_lines(&truth, &light);
                let faces = case.region(&mesh);
                let run = |o: &FairOptions| -> Measures {
                    let (r, after) = fair(&mesh, &light, &faces, o).unwrap();
                    for v in mesh.vertices() {
                        if !r.region.is_movable[v.idx()] {
                            assert_eq!(
                                mesh.position(v).to_array().map(f64::to_bits),
                                after.position(v).to_array().map(f64::to_bits),
                                "{}: {:?} moved vertex {v:?} outside the movable set",
                                case.label(),
                                o.method
                            );
                        }
                    }
                    assert!(after.positions().iter().all(|p| p.is_finite()));
                    let s = surface_error(case, &r, &after);
                    let l = line_error(&r, &after, &truth, &tl, &light);
                    [s.max, s.rms, l.max, l.rms]
                };
                (
                    format!("{} at {:?}", case.label(), case.center),
                    run(options),
                    run(&flow_options),
                )
            })
            .collect()
    }

    /// [`against_flow_on`] the family.
    fn against_flow(options: &FairOptions) -> Vec<(String, Measures, Measures)> {
        against_flow_on(&Case::family(), options)
    }

    fn show(m: &Measures) -> String {
        m.map(|v| format!("{v:.2e}")).join(" ")
    }

    /// The cases where `m` is farther from the truth than the baseline in
    /// any of the four measures.
    fn losses(rows: &[(String, Measures, Measures)]) -> Vec<String> {
        rows.iter()
            .filter(|(_, m, f)| (0..4).any(|i| m[i] > f[i]))
            .map(|(c, m, f)| format!("{c}: {} vs flow {}", show(m), show(f)))
            .collect()
    }

    /// Surface-max ratio (method / flow), geometric mean over the rows.
    fn mean_ratio(rows: &[(String, Measures, Measures)], k: usize) -> f64 {
        let logs: f64 = rows.iter().map(|(_, m, f)| (m[k] / f[k]).ln()).sum();
        (logs / rows.len() as f64).exp()
    }

    /// Measured: on the generated family (quadratic,
    /// cubic, wavy, saddle-like panels × bump/dent × σ 0.08, 0.11, 0.15)
    /// the default method (the paper's energy with the desired lines' end
    /// tangents from a smooth fit beyond the defect's footprint, module
    /// `end_tangents`, + ¼ of the diffusion-flow state, then least change,
    /// module `highlight`) is never farther from the defect-free truth than
    /// surface diffusion flow in any of the four measures (surface max and
    /// RMS, line max and RMS). Least change keeps the highlight result on
    /// the three wavy bumps (whose mean curvature is not harmonic) and the
    /// narrowest quadratic and cubic bumps, each strictly closer in all four
    /// measures and the wavy bumps at least 2.5× closer in surface max; on
    /// the other 19 cases the result is the flow state. On (geometric)
    /// average 0.82× flow in surface max and 0.78× in line RMS. Nothing
    /// outside the movable set moves (checked in `against_flow_on`).
    #[test]
    fn default_fairing_against_diffusion_flow_on_the_generated_family() {
        let rows = against_flow(&FairOptions::default());
        assert_eq!(rows.len(), 24);
        let kept = kept_highlight(&rows);
        for (c, m, f) in &rows {
            for k in 0..4 {
                assert!(m[k] <= f[k], "{c}: {} vs flow {}", show(m), show(f));
                if kept.contains(c) {
                    assert!(m[k] < f[k], "{c}: {} vs flow {}", show(m), show(f));
                }
            }
            if c.starts_with("wavy bump") {
                assert!(kept.contains(c), "{c}: flow state kept");
                assert!(2.5 * m[0] < f[0], "{c}: {} vs flow {}", show(m), show(f));
            }
        }
        assert!(kept.len() >= 5, "{kept:?}");
        assert!(mean_ratio(&rows, 0) < 0.85, "{}", mean_ratio(&rows, 0));
        assert!(mean_ratio(&rows, 3) < 0.8, "{}", mean_ratio(&rows, 3));
    }

    /// The cases where the default kept its highlight result (it differs
    /// from the flow state); on every other case it is the flow state.
    fn kept_highlight(rows: &[(String, Measures, Measures)]) -> Vec<String> {
        rows.iter()
            .filter(|(_, m, f)| m != f)
            .map(|(c, _, _)| c.clone())
            .collect()
    }

    /// The same claim on 32 cases held out of the choice of the fit's
    /// footprint and radius and of the flow share (the defect at (−0.15,
    /// 0.2) and (0.25, 0.1), σ 0.09 and 0.13, every panel, bump and dent):
    /// the default is never farther from the truth than diffusion flow in
    /// any of the four measures, keeps its highlight result on the four
    /// wavy bumps (strictly closer there), and is 0.91× flow on (geometric)
    /// average in surface max (the paper's energy alone loses the four
    /// saddle dents, up to 1.46× in surface max).
    #[test]
    fn default_fairing_against_diffusion_flow_on_held_out_cases() {
        let rows = against_flow_on(&Case::held_out(), &FairOptions::default());
        assert_eq!(rows.len(), 32);
        let kept = kept_highlight(&rows);
        for (c, m, f) in &rows {
            for k in 0..4 {
                assert!(m[k] <= f[k], "{c}: {} vs flow {}", show(m), show(f));
                if kept.contains(c) {
                    assert!(m[k] < f[k], "{c}: {} vs flow {}", show(m), show(f));
                }
            }
        }
        assert!(
            kept.iter().filter(|c| c.starts_with("wavy bump")).count() == 4,
            "{kept:?}"
        );
        assert!(mean_ratio(&rows, 0) < 0.95, "{}", mean_ratio(&rows, 0));
    }

    /// The paper's method (Yong et al. Eq. (15), [`FairMethod::Paper`]) on
    /// the same family: closer than flow in all four measures on 20 of the
    /// 24 cases, 2.5× closer on average in surface max and 3× in line RMS,
    /// at least 3× closer in surface max on every wavy panel; it loses only
    /// on the widest regions or the saddle dents, by at most 1.7× (see
    /// BENCHMARKS.md, "Highlight-line fairing").
    #[test]
    fn paper_fairing_against_diffusion_flow_on_the_generated_family() {
        let rows = against_flow(&FairOptions::default().method(FairMethod::Paper));
        assert_eq!(rows.len(), 24);
        let lost = losses(&rows);
        assert!(lost.len() <= 4, "loses to flow on:\n{}", lost.join("\n"));
        for l in &lost {
            assert!(
                l.contains("σ=0.15") || l.contains("saddle dent"),
                "unexpected loss: {l}"
            );
        }
        assert!(mean_ratio(&rows, 0) < 0.4, "{}", mean_ratio(&rows, 0));
        assert!(mean_ratio(&rows, 3) < 0.33, "{}", mean_ratio(&rows, 3));
        for (c, m, f) in &rows {
            for k in 0..4 {
                assert!(m[k] < 1.7 * f[k], "{c}: {} vs flow {}", show(m), show(f));
            }
            if c.starts_with("wavy") {
                assert!(3.0 * m[0] < f[0], "{c}: {} vs flow {}", show(m), show(f));
            }
        }
    }

    /// The energy-functional methods (Grüner §3.1.2–3.1.3: membrane,
    /// thin plate, minimum variation) on the held-out cases, against
    /// diffusion flow and beside the default: geometric means of method /
    /// flow over the 32 cases in surface max, surface RMS, line max and
    /// line RMS. Measured: default 0.91 0.90 0.92 0.89 (never farther than
    /// flow: least change keeps the flow state unless the highlight result
    /// dominates it); thin plate 0.62 0.70 0.46 0.63 (closer on average,
    /// but farther than flow on 7 cases in some measure); MVS 0.95 0.94
    /// 0.64 0.88 (19 cases); membrane 49 55 42 51 — ΔX = 0 flattens the
    /// crowned panels, whose coordinates are not harmonic (every case).
    #[test]
    fn energy_fairing_against_diffusion_flow_on_held_out_cases() {
        let cases = Case::held_out();
        let mut means = Vec::new();
        for method in [
            FairMethod::Highlight,
            FairMethod::Membrane,
            FairMethod::ThinPlate,
            FairMethod::Mvs,
        ] {
            let rows = against_flow_on(&cases, &FairOptions::default().method(method));
            let m: Vec<f64> = (0..4).map(|k| mean_ratio(&rows, k)).collect();
            eprintln!(
                "{method:?}: / flow {m:.3?}, farther than flow on {} of 32 in some measure",
                losses(&rows).len()
            );
            means.push(m);
        }
        let [default, membrane, thin_plate, mvs] = [&means[0], &means[1], &means[2], &means[3]];
        for k in 0..4 {
            assert!(thin_plate[k] < 0.75, "thin plate {thin_plate:?}");
            assert!(mvs[k] < 1.0, "mvs {mvs:?}");
            assert!(membrane[k] > 10.0, "membrane {membrane:?}");
        }
        // the default is never farther than flow; thin plate is closer on
        // average but not on every case
        assert!(default.iter().all(|&r| r <= 1.0), "default {default:?}");
        assert!(thin_plate[0] < default[0] && thin_plate[1] < default[1]);
    }

    /// The highlight method without refits and flow share.
    fn highlight_only() -> FairOptions {
        FairOptions::default().refits(0).flow_share(0.0)
    }

    /// ω3 (the curvature-Laplacian term) pulls the result toward the
    /// diffusion-flow state: with ω3 = 1 no case is more than 10 % farther
    /// from the truth than flow in any measure (and the average gain
    /// shrinks).
    #[test]
    fn laplacian_weight_moves_the_result_toward_diffusion_flow() {
        let rows = against_flow(&highlight_only().laplacian_weight(1.0));
        for (c, m, f) in &rows {
            for k in 0..4 {
                assert!(m[k] < 1.1 * f[k], "{c}: {} vs flow {}", show(m), show(f));
            }
        }
        let paper = against_flow(&FairOptions::default().method(FairMethod::Paper));
        assert!(mean_ratio(&rows, 0) > mean_ratio(&paper, 0));
    }

    /// Refitting the desired lines' tangents across their end nodes once
    /// the defect is gone ([`FairOptions::refits`], four refits, no flow
    /// share): started from the
    /// fitted tangents, the result's highlight lines end closer to the
    /// truth's lines than diffusion flow's (max and RMS) on every case, and
    /// the surface closer on all but the widest cubic bump and saddle dent,
    /// by at most 1.25× there — where the fitted tangents without refits
    /// win the saddle dent: the refits pull the desired lines back toward
    /// the faired lines and throw the gain of clean tangents away
    /// (BENCHMARKS.md), which is why the default does not
    /// refit.
    #[test]
    fn refitted_tangents_bring_every_case_near_or_past_diffusion_flow() {
        let rows = against_flow(&highlight_only().refits(4));
        let lost = losses(&rows);
        assert!(lost.len() <= 2, "loses to flow on:\n{}", lost.join("\n"));
        for l in &lost {
            assert!(
                l.starts_with("cubic bump σ=0.15") || l.starts_with("saddle dent σ=0.15"),
                "unexpected loss: {l}"
            );
        }
        for (c, m, f) in &rows {
            assert!(
                m[2] <= f[2] && m[3] <= f[3],
                "{c}: {} vs flow {}",
                show(m),
                show(f)
            );
            for k in 0..2 {
                assert!(m[k] < 1.25 * f[k], "{c}: {} vs flow {}", show(m), show(f));
            }
        }
        assert!(mean_ratio(&rows, 0) < 0.55, "{}", mean_ratio(&rows, 0));
        assert!(mean_ratio(&rows, 3) < 0.45, "{}", mean_ratio(&rows, 3));
    }

    /// Mean and max angle (degrees) to the truth's line directions at the
    /// end nodes of the input's desired lines: (paper's outside estimate,
    /// fitted-surface estimate), over the ends where both exist.
    fn end_tangent_angles(case: &Case) -> ([f64; 2], [f64; 2]) {
        let (mesh, light) = (case.input_mesh(), case.light());
        let faces = case.region(&mesh);
        let model = HighlightModel::new(&mesh, light, HighlightOptions::default()).unwrap();
        let lines = model.lines(&mesh);
        let nodes: Vec<_> = lines
            .lines
            .iter()
            .flat_map(|l| l.nodes.iter().copied())
            .collect();
        let set = crate::fair::movable_vertices(&mesh, &faces, &nodes).unwrap();
        let inside_edges: Vec<f64> = mesh
            .edges()
            .filter(|&e| set.edge_inside(&mesh, e))
            .map(|e| {
                let (a, b) = mesh.edge_vertices(e);
                (mesh.position(a) - mesh.position(b)).length()
            })
            .collect();
        let ebar = inside_edges.iter().sum::<f64>() / inside_edges.len() as f64;
        let min_cos = HighlightOptions::default().min_normal_cos;
        let fitted = crate::fair::fitted_surface_tangents(
            &mesh,
            &set,
            model.normals(),
            &lines,
            &light,
            min_cos,
            ebar,
        );
        let paper = crate::fair::desired_lines(&lines, |n| set.node_inside(&mesh, n));
        let (mut pa, mut fa) = (Vec::new(), Vec::new());
        for l in &paper.lines {
            let &(f0, f1) = fitted.get(&l.ends).expect("fitted tangents of every line");
            for (q, tp, tf) in [
                (l.end_points.0, l.tangents.0, f0),
                (l.end_points.1, l.tangents.1, f1),
            ] {
                if tp == Vec3::ZERO {
                    continue;
                }
                let t = case
                    .truth_line_direction(&light, q.x, q.y, tp)
                    .expect("truth direction");
                pa.push(t.angle_between(tp).to_degrees());
                fa.push(t.angle_between(tf).to_degrees());
            }
        }
        assert!(pa.len() >= 30, "{}: {} ends", case.label(), pa.len());
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
        ([mean(&pa), max(&pa)], [mean(&fa), max(&fa)])
    }

    /// The end tangents from the smooth fit beyond the footprint (module
    /// `end_tangents`) against the direction of the truth's highlight line
    /// at each end node (level line of Eq. (1) on the exact panel): on the
    /// polynomial panels (quadratic, cubic, saddle), where the cubic fit
    /// represents the clean surface, they are at least 5× closer on average
    /// than the paper's outside-part estimate and within 0.06° everywhere
    /// (the paper's estimate: up to 0.31°, contaminated by the defect's
    /// tail and by the curvature of the line's outside part); on the wavy
    /// panels (a wave of wavelength ~2 that no cubic over 6 edges follows
    /// exactly) they are within 1.7° like the paper's (≤ 1.8°).
    #[test]
    fn fitted_end_tangents_follow_the_truths_lines() {
        for case in Case::family() {
            let (paper, fitted) = end_tangent_angles(&case);
            let what = format!("{}: paper {paper:.3?}°, fitted {fitted:.3?}°", case.label());
            if case.panel == Panel::Wavy {
                assert!(fitted[1] < 1.7, "{what}");
            } else {
                assert!(5.0 * fitted[0] < paper[0], "{what}");
                assert!(fitted[1] < 0.06, "{what}");
            }
        }
    }
}
