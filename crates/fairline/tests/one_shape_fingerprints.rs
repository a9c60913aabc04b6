//! Fingerprints of results recorded from reference implementations of
//! highlight lines, curvature, polyline networks and the implicit
//! smoothing step (written outside the crate's one shape, with their own
//! assembly): the same inputs must give the same bits. A fingerprint is the FNV-1a hash of the bits of every coordinate
//! (and every count) of a result, so any change of any value shows.

use fairline::Vec3;
use fairline::geom::CurvatureMethod;
use fairline::highlight::{CircularLight, HighlightLines, HighlightOptions, LightArray};
use fairline::mesh::{SurfaceMesh, VertexId};
use fairline::shapes;
use fairline::smooth::{ImplicitOptions, implicit_smooth};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// FNV-1a over 64-bit words.
#[derive(Clone, Copy)]
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf29ce484222325)
    }
    fn word(mut self, w: u64) -> Self {
        for b in w.to_le_bytes() {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x100000001b3);
        }
        self
    }
    fn f(self, x: f64) -> Self {
        self.word(x.to_bits())
    }
    fn v(self, p: Vec3) -> Self {
        self.f(p.x).f(p.y).f(p.z)
    }
    fn all_f(self, xs: &[f64]) -> Self {
        xs.iter().fold(self.word(xs.len() as u64), |h, &x| h.f(x))
    }
    fn all_v(self, ps: &[Vec3]) -> Self {
        ps.iter().fold(self.word(ps.len() as u64), |h, &p| h.v(p))
    }
    fn lines(self, l: &HighlightLines) -> Self {
        l.lines
            .iter()
            .fold(self.word(l.lines.len() as u64), |h, l| {
                h.word(l.index as u64)
                    .word(u64::from(l.closed))
                    .all_v(&l.points)
            })
    }
}

/// Deterministic value in [−1, 1] for index i.
fn noise(i: usize) -> f64 {
    let mut x = (i as u64).wrapping_mul(0x9e3779b97f4a7c15);
    x ^= x >> 31;
    x = x.wrapping_mul(0x94d049bb133111eb);
    x ^= x >> 29;
    (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}

/// A noisy sphere (closed) and a wavy height field (with a boundary).
fn meshes() -> (SurfaceMesh, SurfaceMesh) {
    let mut sphere = shapes::icosphere(1.0, 3);
    for (i, p) in sphere.positions_mut().iter_mut().enumerate() {
        *p *= 1.0 + 0.01 * noise(i);
    }
    let mut field = shapes::height_field(31, 27, (-1.0, 1.0), (-0.8, 0.9), |x, y| {
        0.2 * (2.0 * x).sin() * (1.5 * y).cos() + 0.05 * x * y
    });
    for (i, p) in field.positions_mut().iter_mut().enumerate() {
        p.z += 0.002 * noise(i + 7);
    }
    (sphere, field)
}

fn hex(h: Fnv) -> String {
    format!("{:016x}", h.0)
}

/// (name, fingerprint) of every recorded case.
fn cases() -> Vec<(&'static str, String)> {
    let (sphere, field) = meshes();
    let mut out = Vec::new();
    // highlight lines: linear array, bands, circular lights and bands
    let light = LightArray::new(
        Vec3::new(0.0, 0.0, 3.0),
        Vec3::new(0.1, 0.2, 1.0),
        Vec3::new(1.0, 0.3, 0.0),
        0.11,
    )
    .unwrap();
    for (name, mesh) in [("sphere", &sphere), ("field", &field)] {
        let opts = HighlightOptions::default();
        let lines = fairline::highlight::highlight_lines(mesh, &light, &opts).unwrap();
        let model = fairline::highlight::HighlightModel::new(mesh, light, opts.clone()).unwrap();
        let bands = model.bands(mesh, 0.02).unwrap();
        out.push((
            if name == "sphere" {
                "linear lines sphere"
            } else {
                "linear lines field"
            },
            hex(Fnv::new()
                .lines(&lines)
                .lines(&bands.lower)
                .lines(&bands.upper)),
        ));
    }
    let circles: Vec<CircularLight> = [0.6, 0.9, 1.3]
        .iter()
        .map(|&r| {
            CircularLight::new(Vec3::new(0.1, -0.2, 2.5), Vec3::new(0.0, 0.1, 1.0), r).unwrap()
        })
        .collect();
    for (name, mesh) in [("circular sphere", &sphere), ("circular field", &field)] {
        let lines = fairline::highlight::circular_highlight_lines(
            mesh,
            &circles,
            &HighlightOptions::default(),
        )
        .unwrap();
        let bands = fairline::highlight::circular_highlight_bands(
            mesh,
            &circles,
            0.05,
            &HighlightOptions::default(),
        )
        .unwrap();
        out.push((
            name,
            hex(Fnv::new()
                .lines(&lines)
                .lines(&bands.lower)
                .lines(&bands.upper)),
        ));
    }
    // curvature, both estimators
    for (name, method) in [
        ("curvature rusinkiewicz", CurvatureMethod::Rusinkiewicz),
        ("curvature meyer", CurvatureMethod::Meyer),
    ] {
        let mut h = Fnv::new();
        for mesh in [&sphere, &field] {
            let c = fairline::geom::principal_curvatures(mesh, method);
            h = h
                .all_f(&c.k1)
                .all_f(&c.k2)
                .all_v(&c.d1)
                .all_v(&c.d2)
                .all_v(&c.normals)
                .all_f(&c.mean())
                .all_f(&c.gauss());
        }
        out.push((name, hex(h)));
    }
    // polyline network with tolerance cylinders on a wavy quad grid
    {
        let mut grid = shapes::quad_grid(15, 13, (-1.0, 1.0), (-1.0, 1.0), |x, y| 0.1 * x * y);
        for (i, p) in grid.positions_mut().iter_mut().enumerate() {
            p.z += 0.03 * noise(i + 3);
        }
        let network = fairline::fair::fair_polyline_network(&grid, &Default::default()).unwrap();
        let r = network.report;
        let h = Fnv::new()
            .all_v(&network.positions)
            .f(r.energy_before)
            .f(r.energy_after)
            .word(r.at_bound as u64)
            .word(r.iterations as u64);
        out.push(("polyline network", hex(h)));
    }
    // implicit smoothing: closed, fixed vertices with volume, a boundary
    // smoothed as curves, several steps
    let implicit = |mesh: &SurfaceMesh, o: &ImplicitOptions| {
        let r = implicit_smooth(mesh, o).unwrap();
        hex(Fnv::new()
            .all_v(&r.positions)
            .f(r.report.volume_after)
            .f(r.report.max_displacement))
    };
    out.push((
        "implicit sphere",
        implicit(&sphere, &ImplicitOptions::default().iterations(3)),
    ));
    out.push((
        "implicit sphere fixed volume",
        implicit(
            &sphere,
            &ImplicitOptions::default()
                .time_step(2.0)
                .iterations(2)
                .preserve_volume(true)
                .fixed(
                    (0..sphere.vertex_count() as u32)
                        .step_by(17)
                        .map(VertexId)
                        .collect(),
                ),
        ),
    ));
    out.push((
        "implicit field hierarchical",
        implicit(
            &field,
            &ImplicitOptions::default()
                .iterations(2)
                .hierarchical_boundary(true),
        ),
    ));
    out.push((
        "implicit field fixed boundary tangential",
        implicit(
            &field,
            &ImplicitOptions::default()
                .time_step(0.5)
                .iterations(4)
                .fix_boundary(true)
                .tangential_only(true),
        ),
    ));
    // repair of a dirty soup: every kind of change the repair makes
    {
        let soup = dirty_soup();
        let r = fairline::mesh::repair(&soup, &Default::default()).unwrap();
        // the fixture holds what its doc says
        use fairline::mesh::RemovalReason as Why;
        let rep = &r.report;
        for why in [
            Why::Duplicate,
            Why::ZeroArea,
            Why::InvalidIndex,
            Why::TooFewVertices,
        ] {
            assert!(rep.removed_faces.iter().any(|f| f.reason == why), "{why:?}");
        }
        assert!(!rep.flipped_faces.is_empty() && !rep.collapsed_faces.is_empty());
        assert!(!rep.split_edges.is_empty() && !rep.split_vertices.is_empty());
        assert!(!rep.removed_vertices.is_empty() && !rep.orientation_conflicts.is_empty());
        assert!(!rep.manifold && rep.remaining_problem.is_some());
        let json = serde_json::to_string(&r.report).unwrap();
        let h = json
            .bytes()
            .fold(Fnv::new().all_v(&r.soup.positions), |h, b| {
                h.word(u64::from(b))
            });
        let h = r.soup.indices.iter().fold(h, |h, &i| h.word(u64::from(i)));
        let h = r.soup.offsets.iter().fold(h, |h, &o| h.word(u64::from(o)));
        out.push(("repair", hex(h)));
    }
    out
}

/// A dirty face list with every defect [`fairline::mesh::repair`]
/// repairs or reports: a noisy sphere with two reversed faces, a
/// duplicate, a fin on an edge (non-manifold edge), a cone touching the
/// sphere at one vertex (non-manifold vertex), a zero-area face, a face
/// with an index out of range, a face of two vertices, a face with a
/// repeated corner, an unreferenced vertex, and a Möbius strip (cannot be
/// oriented: the output is reported as still not a manifold).
fn dirty_soup() -> fairline::Soup {
    let mut sphere = shapes::icosphere(1.0, 2);
    for (i, p) in sphere.positions_mut().iter_mut().enumerate() {
        *p *= 1.0 + 0.01 * noise(i + 11);
    }
    let soup = sphere.to_soup();
    let mut positions = soup.positions.clone();
    let mut faces: Vec<Vec<u32>> = soup.faces().map(<[u32]>::to_vec).collect();
    faces[5].reverse();
    faces[17].reverse();
    let mut dup = faces[3].clone();
    dup.rotate_left(1);
    faces.push(dup);
    // a fin standing on the first edge of face 0
    let (a, b) = (faces[0][0], faces[0][1]);
    let tip = positions.len() as u32;
    positions
        .push((positions[a as usize] + positions[b as usize]) * 0.5 + Vec3::new(0.0, 0.0, 2.0));
    faces.push(vec![a, b, tip]);
    // a cone of 5 faces whose apex is the sphere's vertex 0
    let apex = 0u32;
    let base = positions.len() as u32;
    for k in 0..5 {
        let t = k as f64 / 5.0 * std::f64::consts::TAU;
        positions
            .push(positions[0] * 1.5 + Vec3::new(0.2 * t.cos(), 0.2 * t.sin(), 0.1 * noise(k)));
    }
    for k in 0..5 {
        faces.push(vec![apex, base + k, base + (k + 1) % 5]);
    }
    // zero area: a vertex exactly between two others
    let mid = positions.len() as u32;
    positions.push(Vec3::new(3.0, 0.0, 0.0));
    positions.push(Vec3::new(5.0, 0.0, 0.0));
    positions.push(Vec3::new(4.0, 0.0, 0.0));
    faces.push(vec![mid, mid + 1, mid + 2]);
    faces.push(vec![1, 2, 99_999]);
    faces.push(vec![1, 2]);
    let (c, d, e) = (faces[8][0], faces[8][1], faces[8][2]);
    faces.push(vec![c, c, d, e, 2]);
    positions.push(Vec3::new(9.0, 9.0, 9.0)); // unreferenced
    // a Möbius strip of 10 quads
    let n = 10u32;
    let start = positions.len() as u32;
    for i in 0..n {
        let t = std::f64::consts::TAU * i as f64 / n as f64;
        for s in [-0.3, 0.3] {
            let w = s * (t / 2.0).cos();
            positions.push(Vec3::new(
                4.0 + (1.0 + w) * t.cos(),
                (1.0 + w) * t.sin(),
                s * (t / 2.0).sin(),
            ));
        }
    }
    for i in 0..n {
        let (c, d) = if i + 1 < n {
            (2 * i + 2, 2 * i + 3)
        } else {
            (1, 0)
        };
        faces.push(
            [2 * i, c, d, 2 * i + 1]
                .iter()
                .map(|&v| start + v)
                .collect(),
        );
    }
    fairline::Soup::from_polygons(positions, &faces)
}

/// Recorded from the reference implementations (see the module doc).
const RECORDED: &[(&str, &str)] = &[
    ("linear lines sphere", "4fd5d9c2b074a01f"),
    ("linear lines field", "78c4fe83d52bdcab"),
    ("circular sphere", "e204a1fc4027126c"),
    ("circular field", "a5fadcb986f4a584"),
    ("curvature rusinkiewicz", "74a48e914499e1c1"),
    ("curvature meyer", "5501b06bfdeff3ee"),
    ("polyline network", "9793a987758b777e"),
    ("implicit sphere", "c82c0c245a43e45e"),
    ("implicit sphere fixed volume", "1850a1a9462de3b9"),
    ("implicit field hierarchical", "312714f80a6fcdbf"),
    (
        "implicit field fixed boundary tangential",
        "bd5a13c5c0b25839",
    ),
    ("repair", "0f93fef538ca9717"),
];

#[test]
fn results_equal_the_recorded_fingerprints() {
    let got = cases();
    assert_eq!(got.len(), RECORDED.len(), "cases and records");
    for ((name, h), (want_name, want)) in got.iter().zip(RECORDED) {
        assert_eq!(name, want_name);
        assert_eq!(h, want, "{name}");
    }
}

/// A control whose flag is raised once `after` progress steps were seen;
/// also counts the steps.
fn stopping_control(after: usize) -> (fairline::Control, Arc<AtomicUsize>) {
    let steps = Arc::new(AtomicUsize::new(0));
    let seen = Arc::clone(&steps);
    let flag = Arc::new(AtomicBool::new(false));
    let raise = Arc::clone(&flag);
    let control = fairline::Control::new()
        .cancel_flag(flag)
        .on_progress(move |_| {
            if seen.fetch_add(1, Ordering::Relaxed) + 1 >= after {
                raise.store(true, Ordering::Relaxed);
            }
        });
    (control, steps)
}

/// Every entry point put into the one shape stops with its `Cancelled`
/// error once the caller's flag is up, reports progress on the way (one
/// step per light for circular lights), and returns the same result with a
/// control that never stops as without one.
#[test]
fn the_entry_points_report_progress_and_can_be_cancelled() {
    use fairline::fair::{PolylineNetworkOptions, QuadFairError, fair_polyline_network};
    use fairline::geom::{CurvatureError, CurvatureOptions, curvature};
    use fairline::highlight::{
        HighlightError, circular_highlight_bands, circular_highlight_lines, highlight_lines,
    };
    let (sphere, field) = meshes();
    let light = LightArray::new(Vec3::new(0.0, 0.0, 3.0), Vec3::Z, Vec3::X, 0.1).unwrap();
    let circles: Vec<CircularLight> = [0.5, 0.8, 1.1, 1.4]
        .iter()
        .map(|&r| CircularLight::new(Vec3::new(0.0, 0.0, 2.0), Vec3::Z, r).unwrap())
        .collect();
    let plain = HighlightOptions::default();

    // linear lights: three phases; stopped after the first
    let (c, steps) = stopping_control(usize::MAX);
    let watched = highlight_lines(&field, &light, &plain.clone().control(c)).unwrap();
    assert_eq!(watched, highlight_lines(&field, &light, &plain).unwrap());
    assert_eq!(steps.load(Ordering::Relaxed), 4, "3 phases + done");
    let (c, _) = stopping_control(1);
    assert!(matches!(
        highlight_lines(&field, &light, &plain.clone().control(c)),
        Err(HighlightError::Cancelled(_))
    ));

    // circular lights: one step per light, bands two per light
    let (c, steps) = stopping_control(usize::MAX);
    let watched = circular_highlight_lines(&sphere, &circles, &plain.clone().control(c)).unwrap();
    assert_eq!(
        watched,
        circular_highlight_lines(&sphere, &circles, &plain).unwrap()
    );
    assert_eq!(steps.load(Ordering::Relaxed), circles.len() + 1);
    let (c, steps) = stopping_control(2);
    assert!(matches!(
        circular_highlight_lines(&sphere, &circles, &plain.clone().control(c)),
        Err(HighlightError::Cancelled(_))
    ));
    assert_eq!(
        steps.load(Ordering::Relaxed),
        2,
        "stopped at the second light"
    );
    let (c, steps) = stopping_control(usize::MAX);
    circular_highlight_bands(&sphere, &circles, 0.02, &plain.clone().control(c)).unwrap();
    assert_eq!(steps.load(Ordering::Relaxed), 2 * circles.len() + 2);
    let (c, _) = stopping_control(circles.len() + 1);
    assert!(matches!(
        circular_highlight_bands(&sphere, &circles, 0.02, &plain.clone().control(c)),
        Err(HighlightError::Cancelled(_))
    ));

    // curvature: on the (clean) unit sphere k1, k2, H and K are about 1
    let unit = shapes::icosphere(1.0, 3);
    let (c, steps) = stopping_control(usize::MAX);
    let out = curvature(&unit, &CurvatureOptions::default().control(c)).unwrap();
    assert_eq!(steps.load(Ordering::Relaxed), 2);
    assert_eq!(out.fields.k1.len(), unit.vertex_count());
    assert_eq!(out.mean, out.fields.mean());
    assert_eq!(out.gauss, out.fields.gauss());
    assert_eq!(out.report.vertices, unit.vertex_count());
    assert!(!out.report.triangulated);
    for s in [
        out.report.k1,
        out.report.k2,
        out.report.mean,
        out.report.gauss,
    ] {
        assert!(
            s.min > 0.85 && s.max < 1.15 && s.min <= s.mean && s.mean <= s.max,
            "{s:?}"
        );
    }
    let json = serde_json::to_value(&out.report).unwrap();
    assert_eq!(json["method"], "rusinkiewicz");
    let (c, _) = stopping_control(1);
    assert!(matches!(
        curvature(&sphere, &CurvatureOptions::default().control(c)),
        Err(CurvatureError::Cancelled(_))
    ));
    // polygons are triangulated, one value per input vertex
    let quads = shapes::quad_grid(6, 5, (-1.0, 1.0), (-1.0, 1.0), |x, y| {
        0.3 * x * x - 0.2 * y * y
    });
    let q = curvature(&quads, &CurvatureOptions::default()).unwrap();
    assert!(q.report.triangulated);
    assert_eq!(q.fields.k1.len(), quads.vertex_count());

    // polyline network
    let grid = shapes::quad_grid(9, 8, (-1.0, 1.0), (-1.0, 1.0), |x, y| {
        0.05 * noise((x * 100.0 + y * 7.0) as usize)
    });
    let (c, steps) = stopping_control(usize::MAX);
    let out = fair_polyline_network(&grid, &PolylineNetworkOptions::default().control(c)).unwrap();
    assert_eq!(steps.load(Ordering::Relaxed), 2);
    assert!(out.report.energy_after <= out.report.energy_before);
    assert_eq!(
        out,
        fair_polyline_network(&grid, &PolylineNetworkOptions::default()).unwrap()
    );
    let (c, _) = stopping_control(1);
    assert!(matches!(
        fair_polyline_network(&grid, &PolylineNetworkOptions::default().control(c)),
        Err(QuadFairError::Cancelled(_))
    ));

    // repair: one step per stage, the same result watched or not
    use fairline::mesh::{RepairError, RepairOptions, repair};
    let soup = dirty_soup();
    let (c, steps) = stopping_control(usize::MAX);
    let watched = repair(&soup, &RepairOptions::default().control(c)).unwrap();
    assert_eq!(steps.load(Ordering::Relaxed), 4);
    assert_eq!(watched, repair(&soup, &RepairOptions::default()).unwrap());
    for after in 1..4 {
        let (c, steps) = stopping_control(after);
        assert!(matches!(
            repair(&soup, &RepairOptions::default().control(c)),
            Err(RepairError::Cancelled(_))
        ));
        assert_eq!(steps.load(Ordering::Relaxed), after);
    }
}
