//! The smoothed-mesh comparison for the wide flank dent on Spot (issue
//! #18, session 23): the isolated extrema of the highlight distance d under
//! the detection lights rotated about their plane normal (as
//! [`super::loops_table`]) are compared with the extrema of d on the mesh
//! smoothed by Taubin's λ|μ filter with its pass band at the wavelength
//! `c`·R (k_PB = (π h / (c R))², h the mean edge: the uniform Laplacian's
//! eigenvalue of a wave of length ℓ on a regular mesh is about (π h / ℓ)²).
//! An extremum that the smoothed mesh does not have at the same place
//! (same kind within R, in the input's coordinates) is one the smooth model
//! does not explain; its excess depth is its persistence minus that of the
//! best smoothed match, in score units (tenths of the spacing s).
//!
//! `cargo test --release -p fairline --lib smoothed_table -- --ignored --nocapture`
//! (`MESHES`, `SCALES` (c), `ITER` override the lists).

use super::loops_table::{
    cases, default_detection, distances, extrema, persistent_extrema, split_at_dent,
};
use super::*;

fn list(var: &str, default: &[f64]) -> Vec<f64> {
    std::env::var(var)
        .ok()
        .map(|s| s.split(',').filter_map(|x| x.parse().ok()).collect())
        .unwrap_or_else(|| default.to_vec())
}

/// The mesh smoothed by Taubin's filter with its pass band at wavelength
/// `wavelength` (mesh units).
fn smoothed(mesh: &SurfaceMesh, wavelength: f64, iterations: usize) -> SurfaceMesh {
    let h = geom::mean_edge_length(mesh);
    let k_pb = (std::f64::consts::PI * h / wavelength)
        .powi(2)
        .clamp(1e-4, 0.5);
    let out = crate::smooth::taubin_smooth(
        mesh,
        &crate::smooth::TaubinOptions::default()
            .pass_band(k_pb)
            .iterations(iterations)
            .fix_boundary(std::env::var("FREE_BOUNDARY").is_err()),
    )
    .expect("taubin");
    let mut m = mesh.clone();
    m.positions_mut().copy_from_slice(&out.positions);
    m
}

/// One extremum of the input: position, persistence (score units), excess
/// over the best smoothed match (score units), judged.
struct Unexplained {
    at: Vec3,
    depth: f64,
    excess: f64,
    judged: bool,
}

fn unexplained_extrema(
    mesh: &SurfaceMesh,
    smooth: &SurfaceMesh,
    det: &Detection,
    light: &LightArray,
) -> Vec<Unexplained> {
    let p = mesh.positions();
    let h = geom::mean_edge_length(mesh);
    let unit = 0.1 * light.spacing();
    let normals = geom::vertex_normals(mesh);
    let (d, branch) = distances(mesh, &normals, light);
    // head-on: a normal error δ moves the line by L·δ/(Z·N)² in d, by L·δ
    // seen head on (the score's unit)
    let head_on = std::env::var("HEADON").is_ok();
    let (ds, branch_s) = distances(smooth, &geom::vertex_normals(smooth), light);
    let depth: HashMap<usize, f64> = persistent_extrema(mesh, &d, &branch)
        .into_iter()
        .map(|(v, _, x)| (v, x / unit))
        .collect();
    let smooth_ex = persistent_extrema(smooth, &ds, &branch_s);
    let nearest_site = |q: Vec3| {
        det.sites.iter().min_by(|a, b| {
            (a.position - q)
                .length_squared()
                .total_cmp(&(b.position - q).length_squared())
        })
    };
    let r = det.smooth_radius;
    let mut out = Vec::new();
    for (v, is_max, isolation) in extrema(mesh, &d, 2) {
        if isolation < 3.0 * h {
            continue;
        }
        let k = if head_on {
            normals[v].dot(light.plane_normal()).powi(2)
        } else {
            1.0
        };
        let x = k * depth.get(&v).copied().unwrap_or(0.0);
        let matched = smooth_ex
            .iter()
            .filter(|(u, m, _)| *m == is_max && (p[*u] - p[v]).length() < r)
            .map(|e| k * e.2 / unit)
            .fold(0.0f64, f64::max);
        out.push(Unexplained {
            at: p[v],
            depth: x,
            excess: x - matched,
            judged: nearest_site(p[v]).is_some_and(|s| s.score.is_some()),
        });
    }
    out.sort_by(|a, b| b.excess.total_cmp(&a.excess));
    out
}

#[test]
#[ignore = "table printer (needs ../shared/data), not a check"]
fn smoothed_extrema_table() {
    const ROTATIONS: usize = 6;
    let scales = list("SCALES", &[2.0, 3.0, 4.0]);
    let iterations = list("ITER", &[60.0])[0] as usize;
    for (name, mesh, centre) in cases("bunny_npm.obj,bob_small.ply,lego_open.ply,bunny_zipper.ply")
    {
        let (light, det) = default_detection(&mesh);
        let s = light.spacing();
        println!(
            "{name}: s {s:.4}, R {:.4}, h {:.4}, threshold {:.1}",
            det.smooth_radius,
            geom::mean_edge_length(&mesh),
            det.threshold
        );
        let z = light.plane_normal();
        for &c in &scales {
            let smooth = smoothed(&mesh, c * det.smooth_radius, iterations);
            let moved: Vec<f64> = mesh
                .positions()
                .iter()
                .zip(smooth.positions())
                .map(|(a, b)| (*a - *b).length())
                .collect();
            let at_dent = centre.map_or(0.0, |cc| {
                mesh.positions()
                    .iter()
                    .zip(&moved)
                    .filter(|(q, _)| (**q - cc).length() < 0.1)
                    .map(|x| *x.1)
                    .fold(0.0, f64::max)
            });
            println!(
                "  wavelength {c} R: moved median {:.4}, at the dent {at_dent:.4}",
                median(moved.clone())
            );
            let (mut far_j, mut far_all, mut near) = (Vec::new(), Vec::new(), Vec::new());
            let mut per_array: Vec<Vec<Unexplained>> = Vec::new();
            for step in 0..ROTATIONS {
                let phi = step as f64 * std::f64::consts::PI / ROTATIONS as f64;
                let dir = phi.cos() * light.direction() + phi.sin() * z.cross(light.direction());
                let rotated = LightArray::new(light.plane_point(), z, dir, s).expect("light");
                let ex = unexplained_extrema(&mesh, &smooth, &det, &rotated);
                let mut dent = (f64::NEG_INFINITY, 0.0, false);
                for e in &ex {
                    if std::env::var("LIST").is_ok() && e.judged && e.excess > 5.0 {
                        println!(
                            "      array {step}: judged extremum depth {:.1} excess {:.1} at {:.3?}",
                            e.depth,
                            e.excess,
                            e.at.to_array()
                        );
                    }
                    match centre.map(|cc| (e.at - cc).length()) {
                        Some(dd) if dd < 0.3 => {
                            if e.excess > dent.0 {
                                dent = (e.excess, e.depth, e.judged);
                            }
                        }
                        Some(dd) if dd < 0.6 => {}
                        _ => {
                            far_all.push(e.excess);
                            if e.judged {
                                far_j.push(e.excess);
                            }
                        }
                    }
                }
                per_array.push(ex);
                if centre.is_some() {
                    near.push(format!(
                        "{:.1}/{:.1}{}",
                        dent.0,
                        dent.1,
                        if dent.2 { "" } else { "*" }
                    ));
                }
            }
            far_j.sort_by(|a, b| b.total_cmp(a));
            far_all.sort_by(|a, b| b.total_cmp(a));
            let top = |v: &[f64]| -> String {
                v.iter()
                    .take(8)
                    .map(|x| format!("{x:.1}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            println!("    elsewhere, judged: {}", top(&far_j));
            println!("    elsewhere, all:    {}", top(&far_all));
            print_consistency(&det, &per_array, centre);
            print_gated_normal_scores(&mesh, &smooth, &det, &light, &per_array, centre);
            if centre.is_some() {
                println!(
                    "    at the dent per array (excess/depth, * not judged): {}",
                    near.join(" ")
                );
            }
        }
    }
}

/// Per judged site, the arrays with an unexplained extremum (excess above
/// half its depth and above 1) within R: histogram of the counts, and the
/// largest over the sites of the least excess among the arrays, for sites
/// with 5 or 6 arrays, elsewhere and at the dent.
fn print_consistency(det: &Detection, per_array: &[Vec<Unexplained>], centre: Option<Vec3>) {
    let mut counts = vec![0usize; per_array.len() + 1];
    let (mut far, mut near) = (Vec::new(), Vec::new());
    for site in det.sites.iter().filter(|s| s.score.is_some()) {
        let best: Vec<f64> = per_array
            .iter()
            .filter_map(|ex| {
                ex.iter()
                    .filter(|e| {
                        e.excess > 1.0
                            && e.excess > 0.5 * e.depth
                            && (e.at - site.position).length() < det.smooth_radius
                    })
                    .map(|e| e.excess)
                    .reduce(f64::max)
            })
            .collect();
        counts[best.len()] += 1;
        if best.len() >= 5 && std::env::var("PLACES").is_ok() {
            println!(
                "      site {:?} at {:.3?}: arrays {}, excess {:.1?}, score {:.1?} (threshold {:.1})",
                site.vertex,
                site.position.to_array(),
                best.len(),
                best,
                site.score,
                site.threshold
            );
        }
        if best.len() >= 5 {
            let least = best.iter().copied().fold(f64::INFINITY, f64::min);
            let sorted = {
                let mut b = best.clone();
                b.sort_by(f64::total_cmp);
                b
            };
            let second = sorted.get(1).copied().unwrap_or(least);
            match centre.map(|c| (site.position - c).length()) {
                Some(dd) if dd < 0.3 => near.push((least, second, best.len())),
                Some(dd) if dd < 0.6 => {}
                _ => far.push((least, second, best.len())),
            }
        }
    }
    far.sort_by(|a, b| b.1.total_cmp(&a.1));
    near.sort_by(|a, b| b.1.total_cmp(&a.1));
    let fmt = |v: &[(f64, f64, usize)]| -> String {
        v.iter()
            .take(5)
            .map(|x| format!("{:.1}/{:.1}({})", x.0, x.1, x.2))
            .collect::<Vec<_>>()
            .join(" ")
    };
    println!(
        "    judged sites by arrays with an unexplained extremum within R: {counts:?}; with >= 5 (least/second-least excess): elsewhere {} ({} sites); at the dent {}",
        fmt(&far),
        far.len(),
        fmt(&near)
    );
}

/// Per judged site: the angle between the input's and the smoothed mesh's
/// vertex normals in score units (θ·L/(0.1 s), L the distance from the
/// light plane, at least s), its place and the site's threshold.
fn smoothed_normal_scores(
    mesh: &SurfaceMesh,
    smooth: &SurfaceMesh,
    det: &Detection,
    light: &LightArray,
) -> Vec<(Vec3, f64, f64)> {
    let s = light.spacing();
    let (n0, n1) = (geom::vertex_normals(mesh), geom::vertex_normals(smooth));
    det.sites
        .iter()
        .filter(|site| site.score.is_some())
        .map(|site| {
            let v = site.vertex.idx();
            let dist = (light.plane_point() - site.position)
                .dot(light.plane_normal())
                .abs()
                .max(s);
            let theta = n0[v].dot(n1[v]).clamp(-1.0, 1.0).acos();
            (site.position, theta * dist / (0.1 * s), site.threshold)
        })
        .collect()
}

#[test]
#[ignore = "table printer (needs ../shared/data), not a check"]
fn smoothed_normal_table() {
    let scales = list("SCALES", &[2.0, 3.0, 4.0]);
    let iterations = list("ITER", &[60.0])[0] as usize;
    for (name, mesh, centre) in cases("bunny_npm.obj,lego_open.ply,bunny_zipper.ply") {
        let (light, det) = default_detection(&mesh);
        println!(
            "{name}: R {:.4}, threshold {:.1}, median score {:.2}",
            det.smooth_radius, det.threshold, det.median_score
        );
        for &c in &scales {
            let smooth = smoothed(&mesh, c * det.smooth_radius, iterations);
            let rows = smoothed_normal_scores(&mesh, &smooth, &det, &light);
            let med = median(rows.iter().map(|r| r.1).collect());
            let (mut far, mut near) = (Vec::new(), (0.0f64, 0.0f64));
            for (q, sc, t) in &rows {
                match centre.map(|cc| (*q - cc).length()) {
                    Some(dd) if dd < 0.3 => {
                        near = (near.0.max(*sc), near.1.max(sc / med.max(1e-12)))
                    }
                    Some(dd) if dd < 0.6 => {}
                    _ => far.push((*sc, sc / med.max(1e-12), sc / t)),
                }
            }
            far.sort_by(|a, b| b.1.total_cmp(&a.1));
            let top: Vec<String> = far
                .iter()
                .take(6)
                .map(|x| format!("{:.1}({:.1}×med, {:.2}×thr)", x.0, x.1, x.2))
                .collect();
            println!(
                "  wavelength {c} R: median {med:.2}; elsewhere {}; at the dent {:.1} ({:.1}×med)",
                top.join(" "),
                near.0,
                near.1
            );
        }
    }
}

/// The smoothed-normal scores ([`smoothed_normal_scores`]) of the judged
/// sites with an unexplained extremum within R in at least 5 arrays, as
/// multiples of the median over all judged sites: the largest elsewhere
/// and at the dent.
fn print_gated_normal_scores(
    mesh: &SurfaceMesh,
    smooth: &SurfaceMesh,
    det: &Detection,
    light: &LightArray,
    per_array: &[Vec<Unexplained>],
    centre: Option<Vec3>,
) {
    let rows = smoothed_normal_scores(mesh, smooth, det, light);
    let med = median(rows.iter().map(|r| r.1).collect()).max(1e-12);
    let (mut far, mut near) = (Vec::new(), 0.0f64);
    for (q, sc, _) in &rows {
        let arrays = per_array
            .iter()
            .filter(|ex| {
                ex.iter().any(|e| {
                    e.excess > 1.0
                        && e.excess > 0.5 * e.depth
                        && (e.at - *q).length() < det.smooth_radius
                })
            })
            .count();
        if arrays < 5 {
            continue;
        }
        match centre.map(|c| (*q - c).length()) {
            Some(dd) if dd < 0.3 => near = near.max(sc / med),
            Some(dd) if dd < 0.6 => {}
            _ => far.push(sc / med),
        }
    }
    far.sort_by(|a, b| b.total_cmp(a));
    let top: Vec<String> = far.iter().take(6).map(|x| format!("{x:.2}")).collect();
    println!(
        "    gated smoothed-normal scores (× median {med:.1}): elsewhere {} ({} sites); at the dent {near:.2}",
        top.join(" "),
        far.len()
    );
}

/// Per judged site: the curvature tensor (Rusinkiewicz) averaged over a
/// footprint of max(2 h, r_f) on the input and on the smoothed mesh; in the
/// smoothed footprint's principal direction of largest |κ|, the relative
/// drop (κ_smooth − κ_input)/κ_smooth and the drop times R, with the place.
fn smoothed_curvature_drops(
    mesh: &SurfaceMesh,
    smooth: &SurfaceMesh,
    det: &Detection,
) -> Vec<(f64, f64, Vec3, f64)> {
    let foot = match std::env::var("FOOT")
        .ok()
        .and_then(|x| x.parse::<f64>().ok())
    {
        Some(f) => f * det.smooth_radius,
        None => (2.0 * geom::mean_edge_length(mesh)).max(det.fine_radius),
    };
    let judged: Vec<usize> = (0..det.sites.len())
        .filter(|&i| det.sites[i].score.is_some())
        .collect();
    let drops = super::flat_spot::curvature_drops(mesh, smooth, &det.sites, &judged, foot);
    let r = det.smooth_radius;
    judged
        .iter()
        .filter_map(|&i| {
            let d = drops[i]?;
            Some((
                d.relative(),
                (d.smooth - d.input) * r,
                mesh.positions()[det.sites[i].vertex.idx()],
                d.smooth * r,
            ))
        })
        .collect()
}

/// The generated families at about 5k and 50k vertices (no dent).
fn families() -> Vec<(String, SurfaceMesh, Option<Vec3>)> {
    use crate::highlight::detect_tests::{dome, field, hills, panel, saddle};
    let mut all = Vec::new();
    for n in [71u32, 224] {
        all.push((format!("saddle {n}"), field(n, saddle), None));
        all.push((format!("hills {n}"), field(n, hills), None));
        all.push((format!("panel {n}"), field(n, panel), None));
        all.push((format!("dome {n}"), field(n, dome), None));
        all.push((
            format!("cylinder {n}"),
            crate::shapes::cylinder(1.0, 3.0, 2 * n, n / 2),
            None,
        ));
        all.push((
            format!("torus {n}"),
            crate::shapes::torus(1.0, 0.4, 2 * n, n / 2),
            None,
        ));
    }
    all
}

#[test]
#[ignore = "table printer (needs ../shared/data), not a check"]
fn smoothed_flat_spot_table() {
    let scales = list("SCALES", &[2.0, 3.0, 4.0]);
    let iterations = list("ITER", &[60.0])[0] as usize;
    let mut all = cases("bunny_npm.obj,lego_open.ply,bunny_zipper.ply");
    if std::env::var("FAMILIES").is_ok() {
        all.extend(families());
    }
    for (name, mesh, centre) in all {
        let (_, det) = default_detection(&mesh);
        println!(
            "{name}: R {:.4}, {} vertices",
            det.smooth_radius,
            mesh.vertex_count()
        );
        for &c in &scales {
            let smooth = smoothed(&mesh, c * det.smooth_radius, iterations);
            let drops = smoothed_curvature_drops(&mesh, &smooth, &det);
            let mut abs_rel: Vec<f64> = drops.iter().map(|r| r.0.abs()).collect();
            abs_rel.sort_by(f64::total_cmp);
            let q = |f: f64| {
                abs_rel
                    .get(((abs_rel.len() as f64 * f) as usize).min(abs_rel.len().saturating_sub(1)))
                    .copied()
                    .unwrap_or(0.0)
            };
            let floor = (4.0 * q(0.9)).max(0.5);
            let mut abs_drop: Vec<f64> = drops.iter().map(|r| r.1.abs()).collect();
            abs_drop.sort_by(f64::total_cmp);
            let p90_drop = abs_drop
                .get(abs_drop.len() * 9 / 10)
                .copied()
                .unwrap_or(0.0);
            let both = drops
                .iter()
                .filter(|r| r.0 > 0.5 && r.1 > 4.0 * p90_drop)
                .count();
            println!(
                "  wavelength {c} R: |drop × R| p90 {p90_drop:.3}; sites with relative drop > 0.5 and drop × R > 4 p90: {both}"
            );
            let mut top: Vec<&(f64, f64, Vec3, f64)> = drops.iter().collect();
            top.sort_by(|a, b| b.0.total_cmp(&a.0));
            println!(
                "  wavelength {c} R: |relative drop| p50 {:.3} p90 {:.3} p99 {:.3}; floor max(0.5, 4 p90) {floor:.2}: {} sites above; top (rel, κ_s·R): {}",
                q(0.5),
                q(0.9),
                q(0.99),
                drops.iter().filter(|r| r.0 > floor).count(),
                top.iter()
                    .take(5)
                    .map(|r| format!("({:.2}, {:.2})", r.0, r.3))
                    .collect::<Vec<_>>()
                    .join(" ")
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
                    "  wavelength {c} R, {label}: largest elsewhere {}; at the dent {near:.2}; elsewhere above 0.5: {} of {}, median {:.3}",
                    top.join(" "),
                    far.iter().filter(|&&x| x > 0.5).count(),
                    far.len(),
                    far.get(far.len() / 2).copied().unwrap_or(0.0)
                );
            }
        }
    }
}

#[test]
#[ignore = "data dump (needs ../shared/data), not a check"]
fn smoothed_flat_spot_dump() {
    use std::io::Write;
    let scales = list("SCALES", &[3.0, 4.0]);
    let mut all = cases(
        "bunny_npm.obj,lego_open.ply,bunny_zipper.ply,bob_small.ply,bunny_res4.ply,elephant_nonmanifold.obj",
    );
    all.extend(families());
    let mut f = std::fs::File::create(std::env::var("DUMP").unwrap_or("/tmp/flat_dump.csv".into()))
        .expect("dump");
    writeln!(
        f,
        "mesh,c,R,noise,h,rel,ksR,dropR,dist,facet,score,thr,x,y,z,cell"
    )
    .unwrap();
    for (name, mesh, centre) in all {
        let (_, det) = default_detection(&mesh);
        let h = geom::mean_edge_length(&mesh);
        for &c in &scales {
            let smooth = smoothed(&mesh, c * det.smooth_radius, 60);
            let drops = smoothed_curvature_drops(&mesh, &smooth, &det);
            for r in &drops {
                let site = det
                    .sites
                    .iter()
                    .find(|s| mesh.positions()[s.vertex.idx()] == r.2);
                let dist = centre.map_or(-1.0, |cc| (r.2 - cc).length());
                writeln!(
                    f,
                    "{name},{c},{},{},{h},{},{},{},{dist},{},{},{},{},{},{},{}",
                    det.smooth_radius,
                    det.noise_level,
                    r.0,
                    r.3,
                    r.1,
                    site.map_or(0.0, |s| s.facet_angle),
                    site.and_then(|s| s.score).unwrap_or(-1.0),
                    site.map_or(0.0, |s| s.threshold),
                    r.2.x,
                    r.2.y,
                    r.2.z,
                    det.site_cell,
                )
                .unwrap();
            }
            eprintln!("{name} c {c}: {} rows", drops.len());
        }
    }
}
