//! The measured account of the wide flank dent on Spot (README, Default
//! lights on real meshes): two table printers, not checks.
//!
//! - [`loop_extrema_table`]: the closed loop the default picture draws in
//!   the dent bounds a disk that holds an extremum of the highlight
//!   distance d. The printer finds the extrema of d under the detection
//!   lights rotated about their plane normal (6 arrays, 30° apart): strict
//!   over two rings of neighbours with every neighbour lit, isolated (no
//!   vertex with a larger (max) / smaller (min) d nearer than 3 mean edge
//!   lengths), with their 0-dimensional persistence (how far d falls from
//!   the extremum before its basin joins a deeper one) in score units,
//!   tenths of the spacing s — the depth of the loop in the unit of the
//!   measure's score — and per judged site the number of arrays with such
//!   an extremum within R.
//! - [`flat_spot_table`]: the flat-spot measure of the brief — the
//!   curvature tensor (Rusinkiewicz) averaged over a footprint of
//!   max(2 h, r_f) and over an annulus [A1, A2]·R around each judged site;
//!   in the annulus' principal direction of largest |κ|, the relative drop
//!   (κ_annulus − κ_footprint)/κ_annulus (1: the footprint is flat in the
//!   direction its surroundings curve most; above 1: it curves the other
//!   way) and the absolute drop times R.
//!
//! `cargo test --release -p fairline --lib loops_table -- --ignored --nocapture`
//! (`MESHES`, `A1`, `A2` override the lists and the annulus).

use super::flat_spot::most_curved_direction;
use super::wide_table::dented;
use super::*;
use crate::highlight::UpAxis;

/// Spot clean and with the flank dents of radius 0.15 and 0.3 (their
/// centres), then the meshes of `MESHES` (or `default`) from
/// ../shared/data; empty when the data are missing.
pub(super) fn cases(default: &str) -> Vec<(String, SurfaceMesh, Option<Vec3>)> {
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/meshes");
    let Ok(spot) = crate::io::read_mesh(data.join("spot.ply")) else {
        eprintln!("SKIPPED: ../shared/data missing");
        return Vec::new();
    };
    let mut cases: Vec<(String, SurfaceMesh, Option<Vec3>)> = Vec::new();
    for r in [0.15, 0.3] {
        let (m, c) = dented(&spot, r);
        cases.push((format!("spot, dent radius {r}"), m, Some(c)));
    }
    cases.push(("spot".into(), spot, None));
    let names = std::env::var("MESHES").unwrap_or_else(|_| default.into());
    for name in names.split(',').filter(|s| !s.is_empty()) {
        if let Ok(m) = crate::io::read_mesh(data.join(name)) {
            cases.push((name.into(), m, None));
        }
    }
    cases
}

pub(super) fn env_f64(var: &str, default: f64) -> f64 {
    std::env::var(var)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// Detection with defaults under the default lights (no lines needed).
pub(super) fn default_detection(mesh: &SurfaceMesh) -> (LightArray, Detection) {
    let light = LightArray::default_for_mesh(mesh, UpAxis::Auto).expect("vertices");
    let det = detect_irregularities(
        mesh,
        &light,
        &HighlightLines::default(),
        &DetectOptions::default(),
    )
    .expect("detect");
    (light, det)
}

/// Highlight distance per vertex (`None` where unlit) and branch.
pub(super) fn distances(
    mesh: &SurfaceMesh,
    normals: &[Vec3],
    light: &LightArray,
) -> (Vec<Option<f64>>, Vec<i8>) {
    let min_cos = super::super::HighlightOptions::default().min_normal_cos;
    mesh.positions()
        .iter()
        .zip(normals)
        .map(|(&q, &n)| {
            let (d, b) = super::super::light::vertex_distance(light, q, n, min_cos);
            ((b != 0).then_some(d), b)
        })
        .unzip()
}

/// The isolated extrema of one rotated array: (position, persistence in
/// score units, judged); prints those within 0.3 of the dent.
fn isolated_extrema(
    mesh: &SurfaceMesh,
    det: &Detection,
    d: &[Option<f64>],
    branch: &[i8],
    spacing: f64,
    centre: Option<Vec3>,
) -> Vec<(Vec3, f64, bool)> {
    let p = mesh.positions();
    let h = geom::mean_edge_length(mesh);
    let persistence: HashMap<usize, f64> = persistent_extrema(mesh, d, branch)
        .into_iter()
        .map(|(v, _, x)| (v, x / (0.1 * spacing)))
        .collect();
    let nearest_site = |q: Vec3| {
        det.sites.iter().min_by(|a, b| {
            (a.position - q)
                .length_squared()
                .total_cmp(&(b.position - q).length_squared())
        })
    };
    let mut out = Vec::new();
    for (v, _, isolation) in extrema(mesh, d, 2) {
        if isolation < 3.0 * h {
            continue;
        }
        let score = nearest_site(p[v]).and_then(|s| s.score);
        let x = persistence.get(&v).copied().unwrap_or(0.0);
        if let Some(c) = centre
            && (p[v] - c).length() < 0.3
        {
            println!(
                "    at the dent: vertex {v}, {:.2} from its centre, isolation {isolation:.3}, persistence {x:.1}, nearest site's score {score:?}",
                (p[v] - c).length()
            );
        }
        out.push((p[v], x, score.is_some()));
    }
    out.sort_by(|a, b| b.1.total_cmp(&a.1));
    out
}

#[test]
#[ignore = "table printer (needs ../shared/data), not a check"]
fn loop_extrema_table() {
    const ROTATIONS: usize = 6;
    for (name, mesh, centre) in cases("bunny_npm.obj,bob_small.ply,lego_open.ply,bunny_zipper.ply")
    {
        let (light, det) = default_detection(&mesh);
        let s = light.spacing();
        println!(
            "{name}: s {s:.4}, R {:.4}, threshold {:.1}, median score {:.2}",
            det.smooth_radius, det.threshold, det.median_score
        );
        let normals = geom::vertex_normals(&mesh);
        let z = light.plane_normal();
        let mut per_rotation: Vec<Vec<(Vec3, f64, bool)>> = Vec::new();
        for step in 0..ROTATIONS {
            let phi = step as f64 * std::f64::consts::PI / ROTATIONS as f64;
            let dir = phi.cos() * light.direction() + phi.sin() * z.cross(light.direction());
            let rotated = LightArray::new(light.plane_point(), z, dir, s).expect("light");
            let (d, branch) = distances(&mesh, &normals, &rotated);
            let ex = isolated_extrema(&mesh, &det, &d, &branch, s, centre);
            let judged: Vec<String> = ex
                .iter()
                .filter(|e| e.2)
                .take(6)
                .map(|(q, x, _)| match centre {
                    Some(c) => format!("{x:.1}@{:.2}", (*q - c).length()),
                    None => format!("{x:.1}"),
                })
                .collect();
            println!(
                "  phi {:3.0}: {} isolated extrema, at judged sites (persistence[@distance from the dent]): {}",
                phi.to_degrees(),
                ex.len(),
                judged.join(" ")
            );
            per_rotation.push(ex);
        }
        print_rotation_counts(&det, &per_rotation, centre);
    }
}

/// Per judged site, the number of arrays with an isolated extremum at a
/// judged site within R: the histogram, the largest count away from the
/// dent and at it.
fn print_rotation_counts(
    det: &Detection,
    per_rotation: &[Vec<(Vec3, f64, bool)>],
    centre: Option<Vec3>,
) {
    let mut counts = vec![0usize; per_rotation.len() + 1];
    let (mut far, mut near) = (0usize, 0usize);
    for site in det.sites.iter().filter(|s| s.score.is_some()) {
        let n = per_rotation
            .iter()
            .filter(|ex| {
                ex.iter().any(|(q, _, judged)| {
                    *judged && (*q - site.position).length() < det.smooth_radius
                })
            })
            .count();
        counts[n] += 1;
        match centre.map(|c| (site.position - c).length()) {
            Some(dd) if dd < 0.3 => near = near.max(n),
            Some(dd) if dd < 0.6 => {}
            _ => far = far.max(n),
        }
    }
    println!(
        "  judged sites by arrays with an isolated judged extremum within R: {counts:?}; largest elsewhere {far}, at the dent {near}"
    );
}

#[test]
#[ignore = "table printer (needs ../shared/data), not a check"]
fn flat_spot_table() {
    let (a1, a2) = (env_f64("A1", 1.0), env_f64("A2", 2.0));
    for (name, mesh, centre) in cases("bunny_npm.obj,lego_open.ply,bunny_zipper.ply") {
        let (_, det) = default_detection(&mesh);
        let drops = curvature_drops(&mesh, &det, a1, a2);
        println!(
            "{name}: R {:.4}, annulus [{a1}, {a2}] R, {} judged sites",
            det.smooth_radius,
            drops.len()
        );
        for (label, key) in [("relative drop", 0usize), ("drop × R", 1)] {
            let (far, near) = split_at_dent(
                drops
                    .iter()
                    .map(|r| (r.2, if key == 0 { r.0 } else { r.1 })),
                centre,
            );
            let top: Vec<String> = far.iter().take(6).map(|x| format!("{x:.2}")).collect();
            println!(
                "  {label}: largest elsewhere {}; at the dent {near:.2}; elsewhere above 0.5: {}, above 1: {}",
                top.join(" "),
                far.iter().filter(|&&x| x > 0.5).count(),
                far.iter().filter(|&&x| x > 1.0).count()
            );
        }
    }
}

/// Per judged site: (relative drop, drop × R, position) of the curvature
/// in the annulus' principal direction (module documentation).
fn curvature_drops(mesh: &SurfaceMesh, det: &Detection, a1: f64, a2: f64) -> Vec<(f64, f64, Vec3)> {
    let pc = geom::principal_curvatures(mesh, geom::CurvatureMethod::Rusinkiewicz);
    let p = mesh.positions();
    let big_r = det.smooth_radius;
    let outer = |a: Vec3| glam::DMat3::from_cols(a * a.x, a * a.y, a * a.z);
    let tensor = |v: usize| outer(pc.d1[v]) * pc.k1[v] + outer(pc.d2[v]) * pc.k2[v];
    let grid = Grid::new(
        a2 * big_r,
        p.iter().enumerate().map(|(i, &q)| (i as u32, q)),
    );
    let foot = (2.0 * geom::mean_edge_length(mesh)).max(det.fine_radius);
    let mut rows = Vec::new();
    for site in det.sites.iter().filter(|s| s.score.is_some()) {
        let (q0, n0) = (site.position, pc.normals[site.vertex.idx()]);
        let (mut sf, mut wf, mut ss, mut ws) = (glam::DMat3::ZERO, 0.0, glam::DMat3::ZERO, 0.0);
        grid.around(q0, |u| {
            let u = u as usize;
            let r = (p[u] - q0).length();
            if pc.normals[u].dot(n0) < 0.5 || !pc.k1[u].is_finite() {
                return;
            }
            if r < foot {
                sf += tensor(u);
                wf += 1.0;
            }
            if r >= a1 * big_r && r < a2 * big_r {
                ss += tensor(u);
                ws += 1.0;
            }
        });
        if wf == 0.0 || ws < 6.0 {
            continue;
        }
        let (sf, ss) = (sf * (1.0 / wf), ss * (1.0 / ws));
        let (best_k, kf) = most_curved_direction(n0, &ss, &sf);
        let rel = if best_k.abs() > 1e-12 {
            (best_k - kf) / best_k
        } else {
            0.0
        };
        rows.push((rel, (best_k - kf) * big_r, q0));
    }
    rows
}

/// Strict local extrema of `d` over `rings` rings of neighbours, every one
/// of them lit: (vertex, is a maximum, isolation — the distance to the
/// nearest lit vertex with a larger (maximum) / smaller (minimum) d).
pub(super) fn extrema(
    mesh: &SurfaceMesh,
    d: &[Option<f64>],
    rings: usize,
) -> Vec<(usize, bool, f64)> {
    let p = mesh.positions();
    let nv = mesh.vertex_count();
    let mut out = Vec::new();
    for v in 0..nv {
        let Some(dv) = d[v] else { continue };
        if mesh.is_boundary_vertex(VertexId(v as u32)) {
            continue;
        }
        let mut seen = vec![v];
        let mut frontier = vec![v];
        let (mut is_max, mut is_min, mut ok) = (true, true, true);
        for _ in 0..rings {
            let mut next = Vec::new();
            for &u in &frontier {
                for w in mesh.one_ring(VertexId(u as u32)) {
                    let w = w.idx();
                    if seen.contains(&w) {
                        continue;
                    }
                    seen.push(w);
                    next.push(w);
                    match d[w] {
                        Some(dw) => {
                            is_max &= dw < dv;
                            is_min &= dw > dv;
                        }
                        None => ok = false,
                    }
                }
            }
            frontier = next;
        }
        if !ok || !(is_max || is_min) {
            continue;
        }
        let mut iso = f64::INFINITY;
        for u in 0..nv {
            if let Some(du) = d[u]
                && ((is_max && du > dv) || (is_min && du < dv))
            {
                iso = iso.min((p[u] - p[v]).length());
            }
        }
        out.push((v, is_max, iso));
    }
    out
}

/// 0-dimensional persistence of the local maxima (and, negated, minima) of
/// `d` over the mesh graph restricted to valid vertices of one branch:
/// (vertex, is_max, persistence in d units; the global one gets its range).
pub(super) fn persistent_extrema(
    mesh: &SurfaceMesh,
    d: &[Option<f64>],
    branch: &[i8],
) -> Vec<(usize, bool, f64)> {
    let nv = mesh.vertex_count();
    let mut out = Vec::new();
    for sign in [1.0f64, -1.0] {
        let mut order: Vec<usize> = (0..nv).filter(|&v| d[v].is_some()).collect();
        order.sort_by(|&a, &b| {
            (sign * d[b].unwrap_or(0.0)).total_cmp(&(sign * d[a].unwrap_or(0.0)))
        });
        let mut parent: Vec<usize> = (0..nv).collect();
        let mut added = vec![false; nv];
        // birth (value) and vertex of each root
        let mut birth = vec![(0.0f64, 0usize); nv];
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        let mut low = vec![f64::INFINITY; nv];
        for &v in &order {
            let dv = sign * d[v].unwrap_or(0.0);
            added[v] = true;
            parent[v] = v;
            birth[v] = (dv, v);
            low[v] = dv;
            for w in mesh.one_ring(VertexId(v as u32)) {
                let w = w.idx();
                if !added[w] || branch[w] != branch[v] {
                    continue;
                }
                let (a, b) = (find(&mut parent, v), find(&mut parent, w));
                if a == b {
                    continue;
                }
                // the younger (lower birth) dies here
                let (young, old) = if birth[a].0 < birth[b].0 {
                    (a, b)
                } else {
                    (b, a)
                };
                out.push((birth[young].1, sign > 0.0, birth[young].0 - dv));
                parent[young] = old;
                low[old] = low[old].min(low[young]);
            }
            let r = find(&mut parent, v);
            low[r] = low[r].min(dv);
        }
        for v in 0..nv {
            if added[v] && find(&mut parent, v) == v {
                out.push((birth[v].1, sign > 0.0, birth[v].0 - low[v]));
            }
        }
    }
    // drop the non-extrema (persistence 0 births are ordinary vertices)
    out.retain(|e| e.2 > 0.0);
    out
}

/// Values at places split by their distance from the dent's centre: those
/// farther than 0.6 (all of them without a dent), largest first, and the
/// largest within 0.15 (−∞ when none).
pub(super) fn split_at_dent(
    values: impl Iterator<Item = (Vec3, f64)>,
    centre: Option<Vec3>,
) -> (Vec<f64>, f64) {
    let mut far: Vec<f64> = Vec::new();
    let mut near = f64::NEG_INFINITY;
    for (q, v) in values {
        match centre.map(|c| (q - c).length()) {
            Some(dd) if dd < 0.15 => near = near.max(v),
            Some(dd) if dd < 0.6 => {}
            _ => far.push(v),
        }
    }
    far.sort_by(|a, b| b.total_cmp(a));
    (far, near)
}
