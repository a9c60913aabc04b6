//! Helpers shared by the command-line tests: run the `fairline` binary, a
//! fresh temporary directory per test, the shared real data, JSON reports.
#![allow(dead_code)] // each test binary uses its own subset

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `fairline` binary built for these tests.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fairline"))
}

/// Runs `fairline` with `args` and returns its status and output.
pub fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("run fairline")
}

/// A fresh, empty temporary directory unique to this test process and
/// `name`.
pub fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("fairline-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[path = "../../../fairline/tests/support/shared_data.rs"]
mod shared_data;

/// A file of the shared real data (`../shared/data/` beside the checkout);
/// when it is missing the test fails under CI and says loudly that it
/// checked nothing otherwise (see `shared_data.rs`).
pub fn data(rel: &str) -> Option<PathBuf> {
    shared_data::shared_data(rel)
}

/// The JSON document in `path`.
pub fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Asserts that the command succeeded, showing its standard error if not.
pub fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "status {:?}: {}",
        o.status,
        String::from_utf8_lossy(&o.stderr)
    );
}

/// `p` as a command-line argument.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Spot (`mesh`, from ../shared/data) with a dent planted on its flank,
/// written as OBJ into `dir`: centred at mid-length (the middle of the z
/// range, the body's long axis) on the vertex farthest along +x, 2 % of the
/// bounding-box diagonal deep, of the given `radius` ρ, profile
/// (1 − r²/ρ²)² along the inward vertex normal. Returns the path and the
/// dent's centre.
///
/// Radius 0.15 is about three mean edges (0.3 across, less than one drawn
/// light spacing, 0.44); radius 0.3 is as wide as the body is round
/// (radius ≈ 0.38). Not at the +x extreme of the whole mesh: that is the
/// tip of an ear, shape finer than the measure's scale (its sites are
/// never judged), where a "dent" only bends the ear.
pub fn dented_spot(mesh: &Path, dir: &Path, radius: f64) -> (PathBuf, fairline::Vec3) {
    let mut m = fairline::io::read_mesh(mesh).unwrap();
    let normals = fairline::geom::vertex_normals(&m);
    let p = m.positions().to_vec();
    let (lo, hi) = fairline::mesh::bounding_box(&p).unwrap();
    let mid = 0.5 * (lo.z + hi.z);
    let c = p
        .iter()
        .copied()
        .filter(|q| (q.z - mid).abs() < 0.05 * (hi.z - lo.z))
        .max_by(|a, b| a.x.total_cmp(&b.x))
        .unwrap();
    let depth = 0.02 * (hi - lo).length();
    for (q, n) in m.positions_mut().iter_mut().zip(&normals) {
        let r = (*q - c).length() / radius;
        if r < 1.0 {
            *q -= depth * (1.0 - r * r).powi(2) * *n;
        }
    }
    let out = dir.join(format!("spot-dented-{radius}.obj"));
    fairline::io::write_mesh(&out, &m).unwrap();
    (out, c)
}

/// Dome-like bicubic 15 × 15 surface (Nishiyama et al. Fig. 5), with
/// control point (11, 7) raised by 0.03 when `bump`.
pub fn dome_surface(bump: bool) -> fairline::bspline::BSplineSurface {
    use fairline::Vec3;
    use fairline::bspline::{BSplineSurface, clamped_uniform_knots};
    let n = 15;
    let net = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    let x = -1.0 + 2.0 * i as f64 / (n - 1) as f64;
                    let y = -1.0 + 2.0 * j as f64 / (n - 1) as f64;
                    let dz = if bump && (i, j) == (11, 7) { 0.03 } else { 0.0 };
                    Vec3::new(x, y, 0.8 - 0.4 * (x * x + y * y) + dz)
                })
                .collect()
        })
        .collect();
    let k = clamped_uniform_knots(n, 3);
    BSplineSurface::new(3, 3, k.clone(), k, net, None).unwrap()
}

/// (u, v) of the dome's bump: the Greville abscissae of control point
/// (11, 7).
pub const DOME_BUMP_UV: [f64; 2] = [(9.0 + 10.0 + 11.0) / 36.0, (5.0 + 6.0 + 7.0) / 36.0];
