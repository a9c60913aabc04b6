//! The two height-field fits of the measure: the fine fit that says what
//! the surface is at a site, and the robust coarse fit that says what it
//! should be.

use crate::Vec3;
use crate::solve::{height_monomials, solve_spd};

/// Orthonormal tangent frame (bx, by) of a unit normal.
pub(super) fn frame(n: Vec3) -> (Vec3, Vec3) {
    let bx = n.any_orthonormal_vector();
    (bx, n.cross(bx))
}

/// Fine fit: weighted least-squares height field (N = 10: cubic, N = 6:
/// quadric) over the neighbours in the frame of `n0`, coordinates scaled by
/// r, weights (1 − ρ²)². Returns the denoised position, normal and
/// weighted RMS residual (mesh units); `None` with fewer than N + 4 points.
pub(super) fn fine_fit<const N: usize>(
    p0: Vec3,
    n0: Vec3,
    pts: &[Vec3],
    r: f64,
) -> Option<(Vec3, Vec3, f64)> {
    let (bx, by) = frame(n0);
    let mut ata = [[0.0f64; N]; N];
    let mut atb = [0.0f64; N];
    let mut wsum = 0.0;
    let mut rows: Vec<([f64; N], f64, f64)> = Vec::with_capacity(pts.len());
    for &q in pts {
        let d = (q - p0) / r;
        let (x, y, z) = (d.dot(bx), d.dot(by), d.dot(n0));
        let w = (1.0 - x * x - y * y).max(0.0).powi(2);
        if w <= 0.0 {
            continue;
        }
        let row = height_monomials::<N>(x, y);
        for i in 0..N {
            for j in i..N {
                ata[i][j] += w * row[i] * row[j];
            }
            atb[i] += w * row[i] * z;
        }
        wsum += w;
        rows.push((row, z, w));
    }
    if rows.len() < N + 4 {
        return None;
    }
    let c = solve_spd(&ata, &atb)?;
    let mut res = 0.0;
    for (row, z, w) in &rows {
        let f: f64 = row.iter().zip(&c).map(|(a, b)| a * b).sum();
        res += w * (z - f) * (z - f);
    }
    let rms = if wsum > 0.0 {
        (res / wsum).sqrt() * r
    } else {
        0.0
    };
    let n = (n0 - c[1] * bx - c[2] * by).normalize_or_zero();
    if n == Vec3::ZERO {
        return None;
    }
    Some((p0 + c[0] * r * n0, n, rms))
}

/// Coarse fit: IRLS cubic height field through the neighbour sites'
/// positions and normals (frame of `n0` at `p0`, scaled by `r`); returns
/// the fit's unit normal at the origin. `floor` is the smallest robust
/// scale of the slope residuals (radians).
pub(super) fn smooth_normal(
    p0: Vec3,
    n0: Vec3,
    nb: &[(Vec3, Vec3)],
    r: f64,
    floor: f64,
) -> Option<Vec3> {
    smooth_normal_with_hole(p0, n0, nb, r, floor, HOLE)
}

/// [`smooth_normal`] leaving out the sites within `hole` smooth radii.
fn smooth_normal_with_hole(
    p0: Vec3,
    n0: Vec3,
    nb: &[(Vec3, Vec3)],
    r: f64,
    floor: f64,
    hole: f64,
) -> Option<Vec3> {
    let (bx, by) = frame(n0);
    struct Row {
        x: f64,
        y: f64,
        z: f64,
        gx: f64,
        gy: f64,
        w: f64,
    }
    let mut all_rows: Vec<Row> = Vec::with_capacity(nb.len());
    for &(q, nq) in nb {
        let d = (q - p0) / r;
        let (x, y, z) = (d.dot(bx), d.dot(by), d.dot(n0));
        let rr = x * x + y * y;
        let w = (1.0 - rr).max(0.0).powi(2);
        let nz = nq.dot(n0);
        if w <= 0.0 || nz < 0.3 {
            continue;
        }
        all_rows.push(Row {
            x,
            y,
            z,
            gx: -nq.dot(bx) / nz,
            gy: -nq.dot(by) / nz,
            w,
        });
    }
    // one-sided neighbourhood (mesh boundary): a cubic fitted on one side
    // of the site errs more at the site, so the fit shrinks to 0.6 R there
    // and keeps the sites near the judged one; elsewhere it leaves them out
    let mut rows: Vec<Row> = Vec::with_capacity(all_rows.len());
    let wsum: f64 = all_rows.iter().map(|r| r.w).sum();
    if wsum > 0.0 {
        let cx = all_rows.iter().map(|r| r.w * r.x).sum::<f64>() / wsum;
        let cy = all_rows.iter().map(|r| r.w * r.y).sum::<f64>() / wsum;
        if cx.hypot(cy) > BOUNDARY_OFFSET {
            let k = BOUNDARY_SHRINK;
            rows = all_rows;
            rows.retain(|r| r.x * r.x + r.y * r.y < k * k);
            for r in &mut rows {
                (r.x, r.y, r.z) = (r.x / k, r.y / k, r.z / k);
                r.w = (1.0 - r.x * r.x - r.y * r.y).max(0.0).powi(2);
            }
        } else {
            rows = all_rows;
            rows.retain(|r| r.x * r.x + r.y * r.y >= hole * hole);
        }
    }
    if rows.len() < 12 {
        return None;
    }
    let basis = |x: f64, y: f64| -> ([f64; 10], [f64; 10], [f64; 10]) {
        (
            height_monomials(x, y),
            [
                0.0,
                1.0,
                0.0,
                2.0 * x,
                y,
                0.0,
                3.0 * x * x,
                2.0 * x * y,
                y * y,
                0.0,
            ],
            [
                0.0,
                0.0,
                1.0,
                0.0,
                x,
                2.0 * y,
                0.0,
                x * x,
                2.0 * x * y,
                3.0 * y * y,
            ],
        )
    };
    let mut robust = vec![1.0f64; rows.len()];
    let mut coef = [0.0f64; 10];
    for pass in 0..3 {
        let mut ata = [[0.0f64; 10]; 10];
        let mut atb = [0.0f64; 10];
        for (row, &rw) in rows.iter().zip(&robust) {
            let w = row.w * rw;
            if w <= 0.0 {
                continue;
            }
            let (v, dx, dy) = basis(row.x, row.y);
            for i in 0..10 {
                for j in i..10 {
                    ata[i][j] += w * (v[i] * v[j] + dx[i] * dx[j] + dy[i] * dy[j]);
                }
                atb[i] += w * (v[i] * row.z + dx[i] * row.gx + dy[i] * row.gy);
            }
        }
        coef = solve_spd(&ata, &atb)?;
        if pass == 2 {
            break;
        }
        // slope residuals and their robust scale
        let res: Vec<f64> = rows
            .iter()
            .map(|row| {
                let (_, dx, dy) = basis(row.x, row.y);
                let fx: f64 = dx.iter().zip(&coef).map(|(a, b)| a * b).sum();
                let fy: f64 = dy.iter().zip(&coef).map(|(a, b)| a * b).sum();
                ((fx - row.gx).powi(2) + (fy - row.gy).powi(2)).sqrt()
            })
            .collect();
        let mut sorted = res.clone();
        sorted.sort_by(f64::total_cmp);
        let med = sorted[sorted.len() / 2];
        let scale = (1.4826 * med).max(floor);
        let c = 4.685 * scale;
        for (rw, e) in robust.iter_mut().zip(&res) {
            let u = e / c;
            *rw = if u < 1.0 { (1.0 - u * u).powi(2) } else { 0.0 };
        }
    }
    let n = (n0 - coef[1] * bx - coef[2] * by).normalize_or_zero();
    (n != Vec3::ZERO).then_some(n)
}

/// Weighted centroid offset of a neighbourhood (in smooth radii) above
/// which the site counts as near a boundary.
const BOUNDARY_OFFSET: f64 = 0.05;
/// The smooth fit leaves out the sites within this many smooth radii of
/// the site it judges, so a defect there does not bend the fit toward
/// itself (the fit interpolates across the hole).
const HOLE: f64 = 0.35;
/// Radius of the smooth fit near a boundary, in smooth radii.
const BOUNDARY_SHRINK: f64 = 0.6;
