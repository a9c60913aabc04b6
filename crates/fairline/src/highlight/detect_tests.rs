//! Evidence for the defect detection: generated surfaces
//! with a known smooth truth stay quiet at every resolution; small planted
//! bumps, dents, flat spots and ripples are found and ranked first, with a
//! region of about their footprint.

use super::*;
use crate::Vec3;
use crate::mesh::{FaceId, SurfaceMesh};
use crate::shapes;

/// A deterministic pseudo-random number in [0, 1) (SplitMix64).
fn rand01(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

/// Height field z = f(x, y) over [−1, 1]² on an n × n grid whose interior
/// vertices are jittered by up to ±0.3 cells (irregular sampling: vertex
/// normals carry their O(h) error), heights exact.
pub(super) fn field(n: u32, f: impl Fn(f64, f64) -> f64) -> SurfaceMesh {
    let mut state = 7u64 + n as u64;
    let h = 2.0 / (n - 1) as f64;
    let mut pos = Vec::with_capacity((n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let mut x = -1.0 + i as f64 * h;
            let mut y = -1.0 + j as f64 * h;
            let (jx, jy) = (rand01(&mut state) - 0.5, rand01(&mut state) - 0.5);
            if i > 0 && i + 1 < n {
                x += 0.6 * jx * h;
            }
            if j > 0 && j + 1 < n {
                y += 0.6 * jy * h;
            }
            pos.push(Vec3::new(x, y, f(x, y)));
        }
    }
    let id = |i: u32, j: u32| i + n * j;
    let mut faces = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            if (i + j) % 2 == 0 {
                faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            } else {
                faces.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                faces.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
    }
    SurfaceMesh::new(pos, &faces).unwrap()
}

/// Detection with the default lights chosen from the part.
fn detect(mesh: &SurfaceMesh) -> Detection {
    let light = LightArray::default_for_mesh(mesh, UpAxis::Auto).unwrap();
    let lines = highlight_lines(mesh, &light, &HighlightOptions::default()).unwrap();
    detect_irregularities(mesh, &light, &lines, &DetectOptions::default()).unwrap()
}

pub(super) fn saddle(x: f64, y: f64) -> f64 {
    0.3 * (x * x - y * y)
}
pub(super) fn hills(x: f64, y: f64) -> f64 {
    0.12 * (1.5 * std::f64::consts::PI * x).sin() * (1.5 * std::f64::consts::PI * y).sin()
}
/// A crowned, slightly asymmetric car-roof-like panel.
pub(super) fn panel(x: f64, y: f64) -> f64 {
    0.3 * (1.0 - 0.45 * x * x - 0.25 * y * y) + 0.05 * x * x * x - 0.03 * x * y * y
}
/// A dome of revolution about the z axis.
pub(super) fn dome(x: f64, y: f64) -> f64 {
    0.4 * (-1.5 * (x * x + y * y)).exp()
}

fn summary(d: &Detection) -> String {
    format!(
        "fraction {:.4}, regions {}, max score {:.2} (site {:.2}), median {:.3}, threshold {:.2}, sites {}/{}",
        d.flagged_area_fraction,
        d.regions.len(),
        d.max_score(),
        d.sites.iter().filter_map(|s| s.score).fold(0.0, f64::max),
        d.median_score,
        d.threshold,
        d.judged_sites,
        d.sites.len()
    )
}

#[test]
fn clean_smooth_surfaces_stay_quiet_at_every_resolution() {
    type Shape = (&'static str, fn(u32) -> SurfaceMesh);
    let shapes_list: [Shape; 6] = [
        ("saddle", |n| field(n, saddle)),
        ("sin-sin hills", |n| field(n, hills)),
        ("car panel", |n| field(n, panel)),
        ("dome of revolution", |n| field(n, dome)),
        ("cylinder", |n| shapes::cylinder(1.0, 3.0, 2 * n, n / 2)),
        ("torus", |n| shapes::torus(1.0, 0.4, 2 * n, n / 2)),
    ];
    for (name, make) in shapes_list {
        let mut fractions = Vec::new();
        // about 5k and 50k vertices
        for n in [71u32, 224] {
            let mesh = make(n);
            let d = detect(&mesh);
            println!("{name} {} vertices: {}", mesh.vertex_count(), summary(&d));
            for r in d.regions.iter().take(6) {
                println!(
                    "  score {:.2} at {:.3?}, area {:.4}",
                    r.score, r.center, r.area
                );
            }
            assert!(
                d.flagged_area_fraction <= 0.01,
                "{name} at {} vertices: {}",
                mesh.vertex_count(),
                summary(&d)
            );
            assert!(
                d.judged_sites * 10 >= d.sites.len() * 9,
                "{name}: {}",
                summary(&d)
            );
            // the flat-spot measure stays far below its floor (measured:
            // at most 0.05 against 0.5)
            assert_eq!(d.flat_spot_sites, 0, "{name}: {}", summary(&d));
            fractions.push(d.flagged_area_fraction);
        }
        assert!(
            fractions[1] <= fractions[0] + 0.002,
            "{name}: flagged fraction grows with resolution: {fractions:?}"
        );
    }
}

#[test]
fn clean_surfaces_at_half_a_million_vertices_stay_quiet() {
    for (name, mesh) in [
        ("sin-sin hills", field(708, hills)),
        ("torus", shapes::torus(1.0, 0.4, 1000, 500)),
    ] {
        let t = std::time::Instant::now();
        let d = detect(&mesh);
        println!(
            "{name} {} vertices: {} ({:.2} s)",
            mesh.vertex_count(),
            summary(&d),
            t.elapsed().as_secs_f64()
        );
        assert!(mesh.vertex_count() >= 490_000);
        assert!(d.flagged_area_fraction <= 0.01, "{name}: {}", summary(&d));
    }
}

/// A planted defect: its centre, an estimate of its footprint radius
/// (where the deviation exceeds a tenth of its peak; the test measures it)
/// and the deviation δ(x, y).
struct Defect {
    name: &'static str,
    center: (f64, f64),
    footprint: f64,
    delta: Box<dyn Fn(f64, f64) -> f64 + Sync>,
}

fn defects(amplitude: f64) -> Vec<Defect> {
    let c = (0.3, -0.2);
    let r2 = move |x: f64, y: f64| (x - c.0).powi(2) + (y - c.1).powi(2);
    let sigma = 0.1;
    let gauss_footprint = sigma * 10f64.ln().sqrt();
    vec![
        Defect {
            name: "bump",
            center: c,
            footprint: gauss_footprint,
            delta: Box::new(move |x, y| amplitude * (-r2(x, y) / (sigma * sigma)).exp()),
        },
        Defect {
            name: "dent",
            center: c,
            footprint: gauss_footprint,
            delta: Box::new(move |x, y| -amplitude * (-r2(x, y) / (sigma * sigma)).exp()),
        },
        Defect {
            // the crown flattened toward its tangent plane at c inside a
            // flat-topped window of radius ρ (deviation ≈ κρ²/2 there)
            name: "flat spot",
            center: c,
            footprint: 0.14,
            delta: Box::new(move |x, y| {
                let (dx, dy) = (x - c.0, y - c.1);
                let gx = 0.3 * (-0.9 * c.0) + 0.15 * c.0 * c.0 - 0.03 * c.1 * c.1;
                let gy = 0.3 * (-0.5 * c.1) - 0.06 * c.0 * c.1;
                let tangent = panel(c.0, c.1) + gx * dx + gy * dy;
                let w = (-(r2(x, y) / (0.1f64 * 0.1)).powi(2)).exp();
                w * (tangent - panel(x, y))
            }),
        },
        Defect {
            name: "ripple",
            center: c,
            footprint: 0.15 * 10f64.ln().sqrt(),
            delta: Box::new(move |x, y| {
                amplitude
                    * (2.0 * std::f64::consts::PI * (x - c.0) / 0.12).cos()
                    * (-r2(x, y) / (0.15f64 * 0.15)).exp()
            }),
        },
    ]
}

#[test]
fn planted_defects_are_found_ranked_first_with_a_tight_region() {
    // car panel over [−1, 1]²: bounding-box diagonal ≈ 2.85; amplitude
    // 0.1 % of it
    let clean = field(224, panel);
    let (lo, hi) = crate::mesh::bounding_box(clean.positions()).unwrap();
    let amplitude = 1e-3 * (hi - lo).length();
    for defect in defects(amplitude) {
        let mesh = field(224, |x, y| panel(x, y) + (defect.delta)(x, y));
        let d = detect(&mesh);
        println!("{}: {}", defect.name, summary(&d));
        for r in d.regions.iter().take(3) {
            println!(
                "  score {:.2} at {:.3?}, area {:.4}",
                r.score, r.center, r.area
            );
        }
        assert!(!d.regions.is_empty(), "{}: not found", defect.name);
        let top = &d.regions[0];
        let c = Vec3::new(defect.center.0, defect.center.1, 0.0);
        let off = (top.center - c).truncate().length();
        assert!(
            off < defect.footprint,
            "{}: top region centred {off:.3} from the defect",
            defect.name
        );
        // the footprint measured: farthest point from the centre (16
        // directions) where |δ| reaches a tenth of its peak
        let mut peak: f64 = 0.0;
        let mut samples = Vec::new();
        for k in 0..16 {
            let a = k as f64 * std::f64::consts::PI / 8.0;
            for i in 0..=500 {
                let r = i as f64 * 0.001;
                let v = (defect.delta)(c.x + r * a.cos(), c.y + r * a.sin()).abs();
                peak = peak.max(v);
                samples.push((r, v));
            }
        }
        let footprint = samples
            .iter()
            .filter(|(_, v)| *v >= 0.1 * peak)
            .map(|(r, _)| *r)
            .fold(0.0, f64::max);
        assert!(
            footprint <= 1.2 * defect.footprint,
            "{}: {footprint}",
            defect.name
        );
        let footprint_area = std::f64::consts::PI * footprint.powi(2);
        // "no larger than about three times the footprint";
        // measured: bump and dent 1.5×, flat spot 2.7×, ripple 3.06× (a
        // ripple of one spacing stays visible beyond its 10 % footprint)
        println!("  area / footprint {:.2}", top.area / footprint_area);
        assert!(
            top.area <= 3.1 * footprint_area,
            "{}: region area {:.4} vs footprint {:.4}",
            defect.name,
            top.area,
            footprint_area
        );
        // anything else flagged is far weaker
        for r in &d.regions[1..] {
            assert!(
                r.score < 0.5 * top.score,
                "{}: second region {:.2} at {:?} vs top {:.2}",
                defect.name,
                r.score,
                r.center,
                top.score
            );
        }
    }
}

/// Cancelling through the control's flag stops detection with the
/// `Cancelled` error; progress reaches the callback stage by stage, and a
/// control that is never raised changes nothing.
/// The flat-spot measure (detect's module documentation, step 8) on
/// clean panels as coarse as Spot (R raised to five mean edges, 31² and
/// 41² vertices, where it is meant to work): no flat-spot site and no
/// region. With the measure off (`flat_spot_factor` 0) no site has a
/// flat-spot value and the floor is 0. (Its finds are tested on the
/// dented Spot: real_inspect_cli; the generated families at 5k and 50k
/// vertices have none: clean_smooth_surfaces_stay_quiet_at_every_resolution.)
#[test]
fn the_flat_spot_measure_is_quiet_on_clean_coarse_panels_and_can_be_off() {
    for n in [31u32, 41] {
        let clean = detect(&field(n, panel));
        assert!(
            clean.smooth_radius > 0.25,
            "{n}: coarse: {}",
            clean.smooth_radius
        );
        assert!(clean.flat_spot_floor >= 0.5, "{n}: the measure ran");
        assert_eq!(clean.flat_spot_sites, 0, "{n}: {}", summary(&clean));
        assert!(clean.regions.is_empty(), "{n}: {}", summary(&clean));
    }
    let mesh = field(31, panel);
    let light = LightArray::default_for_mesh(&mesh, UpAxis::Auto).unwrap();
    let off = detect_irregularities(
        &mesh,
        &light,
        &HighlightLines::default(),
        &DetectOptions::default().flat_spot_factor(0.0),
    )
    .unwrap();
    assert!(off.sites.iter().all(|s| s.flat_spot.is_none()));
    assert_eq!((off.flat_spot_sites, off.flat_spot_floor), (0, 0.0));
}

#[test]
fn detection_reports_progress_and_stops_when_cancelled() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
    let mesh = field(71, |x, y| {
        panel(x, y) + 0.003 * (-(x * x + y * y) / 0.01).exp()
    });
    let light = LightArray::default_for_mesh(&mesh, UpAxis::Auto).unwrap();
    let lines = highlight_lines(&mesh, &light, &HighlightOptions::default()).unwrap();
    let plain = detect_irregularities(&mesh, &light, &lines, &DetectOptions::default()).unwrap();
    let steps = Arc::new(AtomicU64::new(0));
    let seen = Arc::clone(&steps);
    let flag = Arc::new(AtomicBool::new(false));
    let watched = DetectOptions::default().control(
        crate::Control::new()
            .on_progress(move |p| {
                assert_eq!(p.stage, "detect");
                seen.store(p.done, Ordering::Relaxed);
            })
            .cancel_flag(Arc::clone(&flag)),
    );
    let d = detect_irregularities(&mesh, &light, &lines, &watched).unwrap();
    assert_eq!(d, plain, "a control never raised changes nothing");
    assert_eq!(steps.load(Ordering::Relaxed), 5);
    flag.store(true, Ordering::Relaxed);
    assert!(matches!(
        detect_irregularities(&mesh, &light, &lines, &watched),
        Err(HighlightError::Cancelled(_))
    ));
    assert_eq!(
        steps.load(Ordering::Relaxed),
        1,
        "stopped after the first stage"
    );
}

/// The faces shown as "not judged" are where the shape is finer than the
/// measure's scale: on a panel with a narrow, steep ridge along y (its
/// normal turns by ±74° within 0.1, finer than R = 1.5 spacings) they
/// cover the ridge's crest and lie near the ridge only; the mesh border,
/// never judged, is not among them; on the clean panel there are none.
#[test]
fn faces_not_judged_are_the_shape_finer_than_the_scale() {
    let ridge = field(161, |x, y| panel(x, y) + 0.25 * (-(x / 0.06).powi(2)).exp());
    let d = detect(&ridge);
    let faces = d.shape_faces(&ridge);
    assert!(
        faces.windows(2).all(|w| w[0] < w[1]),
        "ascending, no repeats"
    );
    let p = ridge.positions();
    let centroid = |f: FaceId| {
        let [a, b, c] = ridge.triangle(f);
        (p[a.idx()] + p[b.idx()] + p[c.idx()]) / 3.0
    };
    let shape: std::collections::HashSet<FaceId> = faces.iter().copied().collect();
    // every face on the crest, away from the border, is shape
    let crest: Vec<FaceId> = (0..ridge.face_count() as u32)
        .map(FaceId)
        .filter(|&f| {
            let c = centroid(f);
            c.x.abs() < 0.02 && c.y.abs() < 0.9
        })
        .collect();
    assert!(!crest.is_empty());
    let missed = crest.iter().filter(|f| !shape.contains(f)).count();
    assert_eq!(missed, 0, "{missed} of {} crest faces judged", crest.len());
    // and nothing far from the ridge: a site is shape when a normal within
    // R turns from its own by more than 57°, so (the sides being nearly
    // flat) by more than about 28° from the vertical; the ridge is that
    // steep for |x| < 0.11 (slope 0.53 there), so shape faces lie within
    // R and two site cells of that band
    let reach = 0.11 + d.smooth_radius + 2.0 * d.site_cell;
    for &f in &faces {
        assert!(centroid(f).x.abs() < reach, "{:?} at {}", f, centroid(f));
    }
    // the flat sides are judged
    let judged_far = (0..ridge.face_count() as u32)
        .map(FaceId)
        .filter(|&f| centroid(f).x.abs() > 0.5 && !shape.contains(&f))
        .count();
    assert!(judged_far > 0);
    let clean = field(161, panel);
    assert!(detect(&clean).shape_faces(&clean).is_empty());
}

/// On a mesh whose faces are larger than the site spacing (a coarse
/// icosphere: every site turns by more than the measure allows, so none is
/// judged), the faces far from every site are counted by their corner
/// sites: the whole part is reported not judged, not < 1 % of it.
#[test]
fn a_coarse_part_with_no_site_judged_is_reported_wholly_not_judged() {
    let ball = shapes::icosphere(1.0, 1);
    let d = detect(&ball);
    assert!(d.sites.iter().all(|s| s.score.is_none()), "{}", summary(&d));
    assert!(
        d.not_judged_fraction > 0.99,
        "not judged {} of the part: {}",
        d.not_judged_fraction,
        summary(&d)
    );
}
