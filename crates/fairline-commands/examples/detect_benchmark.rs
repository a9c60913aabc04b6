//! Detection measured as a detector, and fairing measured against the
//! defect-free truth (docs/bench/detection.md).
//!
//! Plants defects — bump, dent, flat spot, ripple, kink — at seeded random
//! places on the real meshes of `../shared/data/meshes` (spot, bunny_npm,
//! bob_small, bunny_zipper; the closed meshes below 5k vertices are refined
//! by Loop subdivision until they have 5k, and the clean refined mesh is the
//! truth) and on generated surfaces (a crowned panel, a surface of
//! revolution, a torus, an organic blob), runs detection as `fairline
//! detect` does (default options and lights, the library's public API only)
//! and reports:
//!
//! - recall (a region shares a face with the defect's footprint) and the
//!   rank-first rate (the best region does), for all cases and for the
//!   target class (depth ≥ 0.3 % of the bounding-box diagonal, radius ≥ 3 %);
//! - false regions: regions that miss the footprint, per defective part, and
//!   the regions on each clean part;
//! - region size against footprint (area of the best matching region over
//!   the area of the faces the defect moved);
//! - the share of the part not judged;
//! - fairing: each found defect is faired (its region grown by
//!   `AUTO_RINGS`, as `fairline fair --auto`) with every method, and the
//!   max / rms distance of the result to the truth is compared with the
//!   defect's own.
//!
//! Depths are drawn log-uniform in 0.1–1 % of the bounding-box diagonal,
//! radii uniform in 1–8 %. Two seed sets are fixed here: the **tuning**
//! set, the only one any default of detection or fairing may be tuned on,
//! and the **held-out** set, which is only reported
//! (`--set held-out`, the default). Tables in docs/bench/detection.md are
//! from the held-out set.
//!
//! ```text
//! cargo run --release -p fairline-commands --example detect_benchmark -- [--set tuning|held-out] [--large] [--no-fair] [--parts a,b] [--dump DIR]
//! ```
//!
//! Default sizes are 5k–36k vertices (a few minutes on two cores);
//! `--large` generates the surfaces at about 500k vertices and refines the
//! real meshes to at least 100k. `--dump DIR` writes each clean part (PLY)
//! and each planted case (defective positions, footprint, the detection's
//! site scores) for analysis elsewhere, without judging the cases.

use fairline::fair::{FairMethod, FairOptions, fair_highlight_lines, grow_region};
use fairline::highlight::{
    DetectOptions, Detection, HighlightModel, HighlightOptions, LightArray, LightChoice, UpAxis,
};
use fairline::mesh::bounding_box;
use fairline::{FaceId, SurfaceMesh, Vec3, VertexId, geom, shapes};
use fairline_commands::regions::AUTO_RINGS;
use std::collections::{HashMap, VecDeque};
use std::time::Instant;

/// Seeds the defaults may be tuned on (the least-change rule of fairing was
/// chosen with all six in view).
const TUNING_SEEDS: [u64; 6] = [11, 12, 13, 9001, 9002, 9003];
/// Seeds that are only reported.
const HELD_OUT_SEEDS: [u64; 3] = [5501, 5502, 5503];

const KINDS: [Kind; 5] = [
    Kind::Bump,
    Kind::Dent,
    Kind::FlatSpot,
    Kind::Ripple,
    Kind::Kink,
];

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Bump,
    Dent,
    FlatSpot,
    Ripple,
    Kink,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Bump => "bump",
            Kind::Dent => "dent",
            Kind::FlatSpot => "flat spot",
            Kind::Ripple => "ripple",
            Kind::Kink => "kink",
        }
    }
}

/// SplitMix64: a small, well-mixed seeded generator.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn uniform(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// One Loop subdivision step (boundary edges split at their midpoints,
/// boundary vertices kept).
fn loop_subdivide(mesh: &SurfaceMesh) -> SurfaceMesh {
    let p = mesh.positions();
    let tris: Vec<[u32; 3]> = mesh
        .faces()
        .map(|f| {
            let v: Vec<u32> = mesh.face_vertices(f).map(|v| v.0).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    let mut opposite: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for t in &tris {
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            opposite.entry((a.min(b), a.max(b))).or_default().push(c);
        }
    }
    let n = p.len();
    let mut nbrs: Vec<Vec<u32>> = vec![Vec::new(); n];
    let mut boundary = vec![false; n];
    for (&(a, b), opp) in &opposite {
        nbrs[a as usize].push(b);
        nbrs[b as usize].push(a);
        if opp.len() != 2 {
            boundary[a as usize] = true;
            boundary[b as usize] = true;
        }
    }
    let mut pos: Vec<Vec3> = (0..n)
        .map(|i| {
            let k = nbrs[i].len();
            if boundary[i] || k < 3 {
                return p[i];
            }
            let beta = if k == 3 {
                3.0 / 16.0
            } else {
                3.0 / (8.0 * k as f64)
            };
            let sum: Vec3 = nbrs[i].iter().map(|&j| p[j as usize]).sum();
            (1.0 - k as f64 * beta) * p[i] + beta * sum
        })
        .collect();
    let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
    let mut keys: Vec<(u32, u32)> = opposite.keys().copied().collect();
    keys.sort_unstable();
    for (a, b) in keys {
        let opp = &opposite[&(a, b)];
        let (pa, pb) = (p[a as usize], p[b as usize]);
        let q = if opp.len() == 2 {
            0.375 * (pa + pb) + 0.125 * (p[opp[0] as usize] + p[opp[1] as usize])
        } else {
            0.5 * (pa + pb)
        };
        mid.insert((a, b), pos.len() as u32);
        pos.push(q);
    }
    let m = |a: u32, b: u32| mid[&(a.min(b), a.max(b))];
    let mut faces = Vec::with_capacity(4 * tris.len());
    for t in &tris {
        let (a, b, c) = (t[0], t[1], t[2]);
        let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
        faces.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    SurfaceMesh::new(pos, &faces).expect("subdivided mesh")
}

/// The vertices moved to their positions on the Loop limit surface (so the
/// refined mesh samples one smooth surface).
fn loop_limit(mesh: &SurfaceMesh) -> SurfaceMesh {
    let p = mesh.positions();
    let pos: Vec<Vec3> = mesh
        .vertices()
        .map(|v| {
            let nb: Vec<VertexId> = mesh.one_ring(v).collect();
            let k = nb.len();
            if mesh.is_boundary_vertex(v) || k < 3 {
                return p[v.idx()];
            }
            let beta = if k == 3 {
                3.0 / 16.0
            } else {
                3.0 / (8.0 * k as f64)
            };
            let chi = 1.0 / (3.0 / (8.0 * beta) + k as f64);
            let sum: Vec3 = nb.iter().map(|w| p[w.idx()]).sum();
            (1.0 - k as f64 * chi) * p[v.idx()] + chi * sum
        })
        .collect();
    let mut m = mesh.clone();
    m.set_positions(pos).expect("limit positions");
    m
}

/// The parts: (name, clean mesh, real).
fn parts(large: bool, only: &Option<Vec<String>>) -> Vec<(String, SurfaceMesh, bool)> {
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/meshes");
    let min_real = if large { 100_000 } else { 5_000 };
    let mut out = Vec::new();
    let wanted = |name: &str| only.as_ref().is_none_or(|o| o.iter().any(|w| w == name));
    for file in [
        "spot.ply",
        "bunny_npm.obj",
        "bob_small.ply",
        "bunny_zipper.ply",
    ] {
        let name = file.split('.').next().unwrap_or(file).to_string();
        if !wanted(&name) {
            continue;
        }
        match fairline::io::read_mesh(data.join(file)) {
            Ok(mut m) => {
                let closed = m.vertices().all(|v| !m.is_boundary_vertex(v));
                let refined = closed && m.vertex_count() < min_real;
                while closed && m.vertex_count() < min_real {
                    m = loop_subdivide(&m);
                }
                if refined {
                    m = loop_limit(&m);
                }
                out.push((name, m, true));
            }
            Err(e) => eprintln!("warning: {file} not read ({e}); left out"),
        }
    }
    // generated surfaces, about 10-15k vertices (500k with --large)
    let k = if large { 6.0 } else { 1.0 };
    let n = |base: f64| (base * k).round() as u32;
    if wanted("panel") {
        out.push((
            "panel".into(),
            shapes::height_field(n(140.0), n(105.0), (-1.0, 1.0), (-0.75, 0.75), |x, y| {
                0.3 * (1.0 - 0.45 * x * x - 0.25 * y * y) + 0.04 * (1.3 * x).sin() * y
            }),
            false,
        ));
    }
    if wanted("revolution") {
        let mut m = shapes::cylinder(1.0, 3.0, n(128.0), n(96.0));
        for q in m.positions_mut() {
            let r = 0.6 + 0.25 * (2.2 * q.z).sin() + 0.05 * q.z;
            q.x *= r;
            q.y *= r;
        }
        out.push(("revolution".into(), m, false));
    }
    if wanted("torus") {
        out.push((
            "torus".into(),
            shapes::torus(3.0, 1.0, n(200.0), n(64.0)),
            false,
        ));
    }
    if wanted("blob") {
        let mut m = shapes::icosphere(1.0, if large { 8 } else { 5 });
        for q in m.positions_mut() {
            let d = q.normalize();
            let r = 1.0
                + 0.18 * (2.0 * d.x + 0.5).sin() * (1.5 * d.y).cos()
                + 0.12 * (2.5 * d.z - 0.3).sin()
                + 0.25 * d.x * d.x;
            *q = d * r;
        }
        out.push(("blob".into(), m, false));
    }
    out
}

/// A planted defect: displaced positions and what it is.
struct Defect {
    kind: Kind,
    /// Largest displacement over the diagonal.
    depth: f64,
    /// Radius over the diagonal.
    radius: f64,
    positions: Vec<Vec3>,
    /// Faces with a vertex the defect moved.
    footprint: Vec<bool>,
    footprint_area: f64,
}

/// Smooth compact profile (1 − t²)³.
fn bump_profile(t: f64) -> f64 {
    if t >= 1.0 { 0.0 } else { (1.0 - t * t).powi(3) }
}

/// A flat-topped profile: 1 up to 0.4, then a smoothstep to 0 at 1.
fn plateau_profile(t: f64) -> f64 {
    if t <= 0.4 {
        1.0
    } else if t >= 1.0 {
        0.0
    } else {
        let u = (1.0 - t) / 0.6;
        u * u * (3.0 - 2.0 * u)
    }
}

fn plant(mesh: &SurfaceMesh, kind: Kind, rng: &mut Rng, diag: f64) -> Option<Defect> {
    let depth = diag * 0.001 * 10f64.powf(rng.uniform());
    let radius = diag * (0.01 + 0.07 * rng.uniform());
    let p = mesh.positions();
    let normals = geom::vertex_normals(mesh);
    let boundary: Vec<Vec3> = mesh
        .vertices()
        .filter(|&v| mesh.is_boundary_vertex(v))
        .map(|v| p[v.idx()])
        .collect();
    // a centre away from the border
    let mut centre = None;
    for _ in 0..2000 {
        let c = rng.below(p.len());
        let far = boundary.iter().all(|b| (*b - p[c]).length() > 1.1 * radius);
        if far && normals[c].length() > 0.5 {
            centre = Some(c);
            break;
        }
    }
    let c = centre?;
    let pc = p[c];
    // the vertices within the radius reachable from the centre (not the
    // other side of a thin part)
    let mut inside = vec![false; p.len()];
    let mut queue = VecDeque::from([VertexId(c as u32)]);
    inside[c] = true;
    let mut ball = Vec::new();
    while let Some(v) = queue.pop_front() {
        ball.push(v.idx());
        for w in mesh.one_ring(v) {
            if !inside[w.idx()] && (p[w.idx()] - pc).length() < radius {
                inside[w.idx()] = true;
                queue.push_back(w);
            }
        }
    }
    let mut n: Vec3 = ball
        .iter()
        .filter(|&&i| (p[i] - pc).length() < 0.3 * radius)
        .map(|&i| normals[i])
        .sum();
    if n.length().is_nan() || n.length() <= 0.0 {
        n = normals[c];
    }
    let n = n.normalize();
    let t = n.any_orthonormal_vector();
    let angle = 2.0 * std::f64::consts::PI * rng.uniform();
    let t = (t * angle.cos() + n.cross(t) * angle.sin()).normalize();
    let mut disp = vec![0.0f64; p.len()];
    let lambda = if kind == Kind::FlatSpot {
        let most = ball
            .iter()
            .map(|&i| {
                let d = p[i] - pc;
                plateau_profile(d.length() / radius) * d.dot(n).abs()
            })
            .fold(0.0, f64::max);
        if most > 0.0 {
            (depth / most).min(1.0)
        } else {
            0.0
        }
    } else {
        0.0
    };
    for &i in &ball {
        let d = p[i] - pc;
        let rho = d.length() / radius;
        disp[i] = match kind {
            Kind::Bump => depth * bump_profile(rho),
            Kind::Dent => -depth * bump_profile(rho),
            Kind::FlatSpot => -lambda * plateau_profile(rho) * d.dot(n),
            Kind::Ripple => depth * bump_profile(rho) * (3.0 * std::f64::consts::PI * rho).cos(),
            Kind::Kink => {
                let u = d.dot(t).abs() / radius;
                -depth * (1.0 - u.min(1.0)) * bump_profile(rho)
            }
        };
    }
    let actual = disp.iter().fold(0.0f64, |a, d| a.max(d.abs()));
    let positions: Vec<Vec3> = p.iter().zip(&disp).map(|(q, d)| *q + *d * n).collect();
    let moved: Vec<bool> = disp.iter().map(|d| d.abs() > 0.01 * actual).collect();
    let areas = geom::face_areas(mesh);
    let footprint: Vec<bool> = mesh
        .faces()
        .map(|f| mesh.face_vertices(f).any(|v| moved[v.idx()]))
        .collect();
    let footprint_area = footprint
        .iter()
        .zip(&areas)
        .filter(|(f, _)| **f)
        .map(|(_, a)| *a)
        .sum();
    Some(Defect {
        kind,
        depth: actual / diag,
        radius: radius / diag,
        positions,
        footprint,
        footprint_area,
    })
}

/// Detection options: the defaults, or for tuning runs (tuning seeds
/// only) `--margin M`, `--noise-factor K`, `--smooth-radius R`,
/// `--threshold T`, `--discretisation-factor K`, `--fine-radius F`.
fn detect_options() -> DetectOptions {
    let args: Vec<String> = std::env::args().collect();
    let value = |f: &str| {
        args.iter()
            .position(|a| a == f)
            .and_then(|i| args.get(i + 1))
            .and_then(|v| v.parse::<f64>().ok())
    };
    let mut o = DetectOptions::default();
    if let Some(v) = value("--margin") {
        o = o.region_margin(v);
    }
    if let Some(v) = value("--noise-factor") {
        o = o.noise_factor(v);
    }
    if let Some(v) = value("--smooth-radius") {
        o = o.smooth_radius(v);
    }
    if let Some(v) = value("--threshold") {
        o = o.threshold(v);
    }
    if let Some(v) = value("--discretisation-factor") {
        o = o.discretisation_factor(v);
    }
    if let Some(v) = value("--fine-radius") {
        o = o.fine_radius(v);
    }
    o
}

/// Detection as `fairline detect` runs it: default lights of the part,
/// default options.
fn detect(mesh: &SurfaceMesh) -> (Detection, LightArray) {
    let light = LightChoice::default()
        .up(UpAxis::Auto)
        .light_array(mesh)
        .expect("lights");
    let model = HighlightModel::new(mesh, light, HighlightOptions::default()).expect("model");
    let lines = model.lines(mesh);
    let det = fairline::highlight::detect_whole_part(mesh, &light, &lines, &detect_options())
        .expect("detect");
    (det, light)
}

/// Distances of `positions` to the truth: (max, rms over the vertices that
/// differ from the truth or from the defective state).
fn distance(positions: &[Vec3], truth: &[Vec3], defective: &[Vec3]) -> (f64, f64) {
    let (mut max, mut sum, mut n) = (0.0f64, 0.0, 0usize);
    for ((q, t), d) in positions.iter().zip(truth).zip(defective) {
        if q != t || d != t {
            let e = (*q - *t).length();
            max = max.max(e);
            sum += e * e;
            n += 1;
        }
    }
    (max, if n > 0 { (sum / n as f64).sqrt() } else { 0.0 })
}

struct CaseResult {
    part: String,
    real: bool,
    kind: Kind,
    depth: f64,
    radius: f64,
    found: bool,
    first: bool,
    false_regions: usize,
    size_ratio: Option<f64>,
    not_judged: f64,
    /// (fairing, max, rms, deviation got worse) and the defect's own (max, rms).
    fair: Vec<(&'static str, f64, f64, bool)>,
    before: (f64, f64),
}

impl CaseResult {
    fn target(&self) -> bool {
        self.depth >= 0.003 && self.radius >= 0.03
    }
}

/// One way of fairing a found defect.
#[derive(Clone, Copy)]
struct Fairing {
    label: &'static str,
    method: FairMethod,
    least_change: bool,
}

/// The default first, diffusion flow last.
const METHODS: [Fairing; 4] = [
    Fairing {
        label: "highlight (default)",
        method: FairMethod::Highlight,
        least_change: true,
    },
    Fairing {
        label: "highlight without least change",
        method: FairMethod::Highlight,
        least_change: false,
    },
    Fairing {
        label: "paper",
        method: FairMethod::Paper,
        least_change: true,
    },
    Fairing {
        label: "diffusion-flow",
        method: FairMethod::DiffusionFlow,
        least_change: true,
    },
];

#[allow(clippy::too_many_arguments)]
fn run_case(
    part: &str,
    real: bool,
    clean: &SurfaceMesh,
    defect: Defect,
    diag: f64,
    fair: bool,
) -> CaseResult {
    let mut mesh = clean.clone();
    mesh.set_positions(defect.positions.clone())
        .expect("positions");
    let (det, light) = detect(&mesh);
    let areas = geom::face_areas(&mesh);
    let hits: Vec<bool> = det
        .regions
        .iter()
        .map(|r| r.faces.iter().any(|f| defect.footprint[f.idx()]))
        .collect();
    let found = hits.iter().any(|&h| h);
    let first = hits.first().copied().unwrap_or(false);
    let false_regions = hits.iter().filter(|&&h| !h).count();
    let matched = det
        .regions
        .iter()
        .zip(&hits)
        .find(|(_, h)| **h)
        .map(|(r, _)| r);
    let size_ratio = matched.map(|r| {
        let a: f64 = r.faces.iter().map(|f| areas[f.idx()]).sum();
        a / defect.footprint_area.max(f64::MIN_POSITIVE)
    });
    let before = distance(&defect.positions, clean.positions(), &defect.positions);
    let mut fair_out = Vec::new();
    if fair && let Some(r) = matched {
        let faces: Vec<FaceId> = grow_region(&mesh, &r.faces, AUTO_RINGS);
        let fair_light = LightChoice::default()
            .readable(&mesh, light)
            .unwrap_or(light);
        for m in METHODS {
            let o = FairOptions::default()
                .region(faces.clone())
                .light(fair_light)
                .method(m.method)
                .least_change(m.least_change);
            match fair_highlight_lines(&mesh, &o) {
                Ok(out) => {
                    let (mx, rms) = distance(&out.positions, clean.positions(), &defect.positions);
                    let worse = out.report.highlight_deviation_after
                        > out.report.highlight_deviation_before;
                    fair_out.push((m.label, mx / diag, rms / diag, worse));
                }
                Err(e) => eprintln!("  {part}: fairing with {} failed: {e}", m.label),
            }
        }
    }
    CaseResult {
        part: part.into(),
        real,
        kind: defect.kind,
        depth: defect.depth,
        radius: defect.radius,
        found,
        first,
        false_regions,
        size_ratio,
        not_judged: det.not_judged_fraction,
        fair: fair_out,
        before: (before.0 / diag, before.1 / diag),
    }
}

fn pct(a: usize, b: usize) -> String {
    if b == 0 {
        "–".into()
    } else {
        format!("{:.0} % ({a}/{b})", 100.0 * a as f64 / b as f64)
    }
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    Some(v[v.len() / 2])
}

fn fmt_opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("–".into(), |x| format!("{x:.digits$}"))
}

/// One row of the detection table over `cases`.
fn detection_row(label: &str, cases: &[&CaseResult]) -> String {
    let target: Vec<&&CaseResult> = cases.iter().filter(|c| c.target()).collect();
    let ratios: Vec<f64> = cases.iter().filter_map(|c| c.size_ratio).collect();
    let within3 = ratios.iter().filter(|&&r| r <= 3.0).count();
    format!(
        "| {label} | {} | {} | {} | {} | {} | {} | {} | {:.2} | {} | {} |",
        cases.len(),
        pct(cases.iter().filter(|c| c.found).count(), cases.len()),
        pct(cases.iter().filter(|c| c.first).count(), cases.len()),
        target.len(),
        pct(target.iter().filter(|c| c.found).count(), target.len()),
        pct(target.iter().filter(|c| c.first).count(), target.len()),
        fmt_opt(median(ratios.clone()), 1),
        cases.iter().map(|c| c.false_regions).sum::<usize>() as f64 / cases.len().max(1) as f64,
        pct(within3, ratios.len()),
        fmt_opt(
            median(cases.iter().map(|c| 100.0 * c.not_judged).collect()),
            1
        ),
    )
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let flag = |f: &str| args.iter().any(|a| a == f);
    let value = |f: &str| {
        args.iter()
            .position(|a| a == f)
            .and_then(|i| args.get(i + 1).cloned())
    };
    let set = value("--set").unwrap_or_else(|| "held-out".into());
    if detect_options() != DetectOptions::default() && set != "tuning" {
        eprintln!("options other than the defaults are for the tuning seeds only (--set tuning)");
        std::process::exit(2);
    }
    let seeds: &[u64] = match set.as_str() {
        "tuning" => &TUNING_SEEDS,
        "held-out" => &HELD_OUT_SEEDS,
        other => {
            eprintln!("--set must be tuning or held-out, got {other}");
            std::process::exit(2);
        }
    };
    let large = flag("--large");
    let fair = !flag("--no-fair");
    let only = value("--parts").map(|s| s.split(',').map(String::from).collect());
    let start = Instant::now();
    let mut cases = Vec::new();
    let mut clean_rows = Vec::new();
    for (name, clean, real) in parts(large, &only) {
        let (lo, hi) = bounding_box(clean.positions()).expect("finite part");
        let diag = (hi - lo).length();
        let t0 = Instant::now();
        let (det, light) = detect(&clean);
        clean_rows.push(format!(
            "| {name} | {} | {} | {:.4} | {:.4} | {} | {} | {:.1} % | {:.2} | {:.2} | {:.2} s |",
            if real { "real" } else { "generated" },
            clean.vertex_count(),
            light.spacing() / diag,
            det.smooth_radius / diag,
            det.spacings.len(),
            det.regions.len(),
            100.0 * det.not_judged_fraction,
            det.threshold,
            det.discretisation_level,
            t0.elapsed().as_secs_f64()
        ));
        eprintln!("{}", clean_rows.last().map_or("", String::as_str));
        if let Some(dir) = value("--dump") {
            std::fs::create_dir_all(&dir).expect("dump folder");
            fairline::io::write_mesh(format!("{dir}/{name}.ply"), &clean).expect("dump mesh");
        }
        if flag("--clean-only") {
            continue;
        }
        for &seed in seeds {
            for (k, kind) in KINDS.iter().enumerate() {
                let mut rng = Rng(seed.wrapping_mul(1000).wrapping_add(k as u64) ^ hash(&name));
                let Some(defect) = plant(&clean, *kind, &mut rng, diag) else {
                    eprintln!("  {name}: no place for a {}", kind.name());
                    continue;
                };
                if let Some(dir) = value("--dump") {
                    dump_case(&dir, &name, seed, k, &clean, &defect);
                    continue;
                }
                let c = run_case(&name, real, &clean, defect, diag, fair);
                eprintln!(
                    "  {name} seed {seed} {:9} depth {:.2} % radius {:.1} %: found {} first {} false {} size {} not judged {:.0} %{}",
                    c.kind.name(),
                    100.0 * c.depth,
                    100.0 * c.radius,
                    c.found,
                    c.first,
                    c.false_regions,
                    fmt_opt(c.size_ratio, 1),
                    100.0 * c.not_judged,
                    c.fair
                        .iter()
                        .map(|(m, mx, rms, w)| format!(
                            "; {} max {:.2e} rms {:.2e}{}",
                            m,
                            mx,
                            rms,
                            if *w { " (deviation worse)" } else { "" }
                        ))
                        .collect::<String>()
                );
                cases.push(c);
            }
        }
    }
    print_tables(
        &set,
        seeds,
        &cases,
        &clean_rows,
        start.elapsed().as_secs_f64(),
    );
}

fn hash(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    })
}

fn print_tables(set: &str, seeds: &[u64], cases: &[CaseResult], clean_rows: &[String], secs: f64) {
    println!(
        "### Detection ({set} seeds {seeds:?}; {} cases, {secs:.0} s)\n",
        cases.len()
    );
    println!(
        "| cases | n | found | ranked first | n target | target found | target first | region / footprint (median) | false regions per part | region ≤ 3× footprint | not judged (median) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    let all: Vec<&CaseResult> = cases.iter().collect();
    let real: Vec<&CaseResult> = cases.iter().filter(|c| c.real).collect();
    let gen_: Vec<&CaseResult> = cases.iter().filter(|c| !c.real).collect();
    println!("{}", detection_row("all", &all));
    println!("{}", detection_row("real meshes", &real));
    println!("{}", detection_row("generated", &gen_));
    let mut names: Vec<&str> = cases.iter().map(|c| c.part.as_str()).collect();
    names.dedup();
    for n in &names {
        let v: Vec<&CaseResult> = cases.iter().filter(|c| c.part == *n).collect();
        println!("{}", detection_row(n, &v));
    }
    for k in KINDS {
        let v: Vec<&CaseResult> = cases.iter().filter(|c| c.kind == k).collect();
        println!("{}", detection_row(k.name(), &v));
    }
    println!("\n### Clean parts\n");
    println!(
        "| part | kind | vertices | spacing / diagonal | R / diagonal | light arrays | regions | not judged | threshold | discretisation level | detect time |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for r in clean_rows {
        println!("{r}");
    }
    let faired: Vec<&CaseResult> = cases
        .iter()
        .filter(|c| c.fair.len() == METHODS.len())
        .collect();
    if faired.is_empty() {
        return;
    }
    println!(
        "\n### Fairing the found defects ({} cases; distances to the truth over the diagonal, medians)\n",
        faired.len()
    );
    println!(
        "| method | max before | max after | rms before | rms after | closer than the defect (rms) | highlight deviation worse |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (i, m) in METHODS.iter().enumerate() {
        let after_max: Vec<f64> = faired.iter().map(|c| c.fair[i].1).collect();
        let after_rms: Vec<f64> = faired.iter().map(|c| c.fair[i].2).collect();
        let closer = faired.iter().filter(|c| c.fair[i].2 < c.before.1).count();
        let worse = faired.iter().filter(|c| c.fair[i].3).count();
        println!(
            "| {} | {} | {} | {} | {} | {} | {} |",
            m.label,
            fmt_opt(median(faired.iter().map(|c| c.before.0).collect()), 5),
            fmt_opt(median(after_max), 5),
            fmt_opt(median(faired.iter().map(|c| c.before.1).collect()), 5),
            fmt_opt(median(after_rms), 5),
            pct(closer, faired.len()),
            pct(worse, faired.len()),
        );
    }
    // the default and the highlight blend without least change against
    // diffusion flow, case by case
    let flow = METHODS.len() - 1;
    let ratio = |c: &&CaseResult, i: usize, k: usize| {
        let (d, f) = if k == 0 {
            (c.fair[i].1, c.fair[flow].1)
        } else {
            (c.fair[i].2, c.fair[flow].2)
        };
        if f > 0.0 {
            d / f
        } else if d > 0.0 {
            f64::INFINITY
        } else {
            1.0
        }
    };
    println!(
        "\n| against diffusion-flow | measure | at least as close | worst ratio | median ratio |"
    );
    println!("|---|---|---|---|---|");
    for i in [0, 1] {
        for (k, what) in ["max", "rms"].iter().enumerate() {
            let r: Vec<f64> = faired.iter().map(|c| ratio(c, i, k)).collect();
            println!(
                "| {} | {what} | {} | {:.2} | {} |",
                METHODS[i].label,
                pct(r.iter().filter(|&&x| x <= 1.0).count(), r.len()),
                r.iter().copied().fold(0.0, f64::max),
                fmt_opt(median(r.clone()), 2),
            );
        }
    }
}

/// Writes a planted case for analysis outside the benchmark: the defective
/// positions (little-endian f64, n × 3), the footprint (one byte per face)
/// and a line of metadata.
fn dump_case(dir: &str, part: &str, seed: u64, k: usize, clean: &SurfaceMesh, d: &Defect) {
    use std::io::Write;
    let stem = format!("{dir}/{part}-{seed}-{k}");
    let mut bytes = Vec::with_capacity(24 * d.positions.len());
    for q in &d.positions {
        for c in [q.x, q.y, q.z] {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    std::fs::write(format!("{stem}.pos"), bytes).expect("dump positions");
    let foot: Vec<u8> = d.footprint.iter().map(|&f| f as u8).collect();
    std::fs::write(format!("{stem}.foot"), foot).expect("dump footprint");
    let mut mesh = clean.clone();
    mesh.set_positions(d.positions.clone()).expect("positions");
    let (det, _) = detect(&mesh);
    let mut sites = String::new();
    for s in &det.sites {
        sites += &format!(
            "{} {} {} {} {}\n",
            s.vertex.0,
            s.score.unwrap_or(f64::NAN),
            s.threshold,
            s.flat_spot.unwrap_or(f64::NAN),
            det.regions
                .iter()
                .position(|r| r.faces.iter().any(|f| d.footprint[f.idx()]))
                .map_or(-1, |i| i as i64)
        );
    }
    std::fs::write(format!("{stem}.sites"), sites).expect("dump sites");
    let mut meta = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(format!("{dir}/cases.txt"))
        .expect("dump metadata");
    writeln!(
        meta,
        "{part} {seed} {k} {} {} {} {}",
        d.kind.name().replace(' ', "_"),
        d.depth,
        d.radius,
        clean.vertex_count()
    )
    .expect("dump metadata");
}
