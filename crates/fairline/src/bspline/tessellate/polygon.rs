//! Polygons of one grid cell: the cell clipped by the chains that cross it,
//! holes bridged to the outer polygon, and ear clipping.

use super::trimmed::{Chain, Vert, perimeter};
use crate::bspline::trim::winding_number;

/// The triangles of the trimmed region inside one grid cell `rect =
/// [u_lo, u_hi, v_lo, v_hi]`, from the pieces of the loops that cross it.
/// Open chains enter and leave through the cell boundary with the region on
/// their left: after a chain leaves, the boundary is walked counter-clockwise
/// (taking the corners passed) to the next entering chain, until the polygon
/// closes. Closed chains are whole loops: an outer loop is a polygon of its
/// own, a hole is bridged into the polygon that holds it.
pub(super) fn clip_cell(
    chains: &[Chain],
    rect: [f64; 4],
    corners: &[(Vert, [f64; 2]); 4],
    inside: impl Fn([f64; 2]) -> bool,
) -> Vec<[Vert; 3]> {
    type Poly = Vec<(Vert, [f64; 2])>;
    let open: Vec<&Chain> = chains.iter().filter(|c| !c.closed).collect();
    let mut polys: Vec<Poly> = Vec::new();
    let mut holes: Vec<Poly> = Vec::new();
    for c in chains.iter().filter(|c| c.closed) {
        let pts: Vec<[f64; 2]> = c.points.iter().map(|p| p.1).collect();
        if super::super::trim::polygon_signed_area2(&pts) > 0.0 {
            polys.push(c.points.clone());
        } else {
            holes.push(c.points.clone());
        }
    }
    if open.is_empty() {
        // Only whole loops inside the cell: the cell itself is a polygon
        // when its corner lies in the face (then the loops are holes).
        if inside(corners[0].1) {
            polys.push(corners.to_vec());
        }
    } else {
        let entry: Vec<f64> = open
            .iter()
            .map(|c| perimeter(c.points[0].1, rect))
            .collect();
        let exit: Vec<f64> = open
            .iter()
            .map(|c| perimeter(c.points[c.points.len() - 1].1, rect))
            .collect();
        let mut used = vec![false; open.len()];
        for first in 0..open.len() {
            if used[first] {
                continue;
            }
            let mut poly: Poly = Vec::new();
            let mut cur = first;
            for _ in 0..=open.len() {
                used[cur] = true;
                let pts = &open[cur].points;
                poly.extend_from_slice(pts);
                let s = exit[cur];
                // The next chain entering counter-clockwise from here.
                let dist = |e: f64| {
                    let d = (e - s).rem_euclid(4.0);
                    if d.is_finite() { d } else { 0.0 }
                };
                let next = (0..open.len())
                    .filter(|&k| !used[k] || k == first)
                    .min_by(|&i, &j| dist(entry[i]).total_cmp(&dist(entry[j])));
                let Some(next) = next else { break };
                let d = dist(entry[next]);
                let mut cs: Vec<(f64, usize)> = (0..4)
                    .map(|k| (dist(k as f64), k))
                    .filter(|&(dc, _)| dc > 0.0 && dc < d)
                    .collect();
                cs.sort_by(|x, y| x.0.total_cmp(&y.0));
                for (_, k) in cs {
                    poly.push(corners[k]);
                }
                if next == first {
                    break;
                }
                cur = next;
            }
            // Drop repeated consecutive vertices (chain ends meet).
            poly.dedup_by(|a, b| a.0 == b.0);
            while poly.len() > 1 && poly.first().map(|p| p.0) == poly.last().map(|p| p.0) {
                poly.pop();
            }
            if poly.len() >= 3 {
                polys.push(poly);
            }
        }
    }
    for hole in holes {
        let probe = hole[0].1;
        let holder = polys.iter().position(|p| {
            let pts: Vec<[f64; 2]> = p.iter().map(|q| q.1).collect();
            winding_number(&pts, probe) != 0
        });
        if let Some(k) = holder {
            let merged = bridge_hole(&polys[k], &hole);
            polys[k] = merged;
        }
    }
    let mut out = Vec::new();
    for p in &polys {
        ear_clip(p, &mut out);
    }
    out
}

/// Whether the open segments `a b` and `c d` cross (touching at shared
/// endpoints does not count).
fn segments_cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let orient = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    };
    if a == c || a == d || b == c || b == d {
        return false;
    }
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    (o1 > 0.0) != (o2 > 0.0) && (o3 > 0.0) != (o4 > 0.0) && o1 != 0.0 && o2 != 0.0
}

/// Joins a clockwise hole to a counter-clockwise polygon through a bridge
/// from the hole's leftmost vertex to the nearest polygon vertex it sees.
fn bridge_hole(poly: &[(Vert, [f64; 2])], hole: &[(Vert, [f64; 2])]) -> Vec<(Vert, [f64; 2])> {
    let hi = (0..hole.len())
        .min_by(|&i, &j| hole[i].1[0].total_cmp(&hole[j].1[0]))
        .unwrap_or(0);
    let h = hole[hi].1;
    let edges_ok = |p: [f64; 2]| {
        let all = [poly, hole];
        all.iter().all(|ring| {
            (0..ring.len()).all(|k| {
                let (a, b) = (ring[k].1, ring[(k + 1) % ring.len()].1);
                !segments_cross(h, p, a, b)
            })
        })
    };
    let mut order: Vec<usize> = (0..poly.len()).collect();
    let d2 = |p: [f64; 2]| (p[0] - h[0]).powi(2) + (p[1] - h[1]).powi(2);
    order.sort_by(|&i, &j| d2(poly[i].1).total_cmp(&d2(poly[j].1)));
    let pi = order
        .iter()
        .copied()
        .find(|&i| edges_ok(poly[i].1))
        .unwrap_or(order[0]);
    let mut out = Vec::with_capacity(poly.len() + hole.len() + 2);
    out.extend_from_slice(&poly[..=pi]);
    out.extend_from_slice(&hole[hi..]);
    out.extend_from_slice(&hole[..=hi]);
    out.extend_from_slice(&poly[pi..]);
    out
}

/// Ear clipping of a simple counter-clockwise polygon (bridged holes
/// allowed) into triangles appended to `out`. Ears are strictly convex
/// corners with no other vertex inside or on them; when none is left (a
/// degenerate remainder), the flattest corner is cut off.
fn ear_clip(poly: &[(Vert, [f64; 2])], out: &mut Vec<[Vert; 3]>) {
    let mut idx: Vec<usize> = (0..poly.len()).collect();
    let p = |k: usize| poly[k].1;
    let cross = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let in_tri = |q: [f64; 2], a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        cross(a, b, q) >= 0.0 && cross(b, c, q) >= 0.0 && cross(c, a, q) >= 0.0
    };
    let mut guard = 0usize;
    while idx.len() > 3 && guard < 4 * poly.len() * poly.len() + 16 {
        guard += 1;
        let n = idx.len();
        let mut cut = None;
        for k in 0..n {
            let (ia, ib, ic) = (idx[(k + n - 1) % n], idx[k], idx[(k + 1) % n]);
            let (a, b, c) = (p(ia), p(ib), p(ic));
            if cross(a, b, c) <= 0.0 {
                continue;
            }
            let blocked = idx.iter().any(|&j| {
                j != ia
                    && j != ib
                    && j != ic
                    && poly[j].1 != a
                    && poly[j].1 != b
                    && poly[j].1 != c
                    && in_tri(poly[j].1, a, b, c)
            });
            if !blocked {
                cut = Some(k);
                break;
            }
        }
        let k = cut.unwrap_or_else(|| {
            (0..n)
                .min_by(|&i, &j| {
                    let f = |k: usize| {
                        cross(p(idx[(k + n - 1) % n]), p(idx[k]), p(idx[(k + 1) % n])).abs()
                    };
                    f(i).total_cmp(&f(j))
                })
                .unwrap_or(0)
        });
        let (ia, ib, ic) = (idx[(k + n - 1) % n], idx[k], idx[(k + 1) % n]);
        if cross(p(ia), p(ib), p(ic)) > 0.0 {
            out.push([poly[ia].0, poly[ib].0, poly[ic].0]);
        }
        idx.remove(k);
    }
    if idx.len() == 3 {
        let (a, b, c) = (idx[0], idx[1], idx[2]);
        if cross(p(a), p(b), p(c)) > 0.0 {
            out.push([poly[a].0, poly[b].0, poly[c].0]);
        }
    }
}
