//! Closest points on a triangle set: a uniform grid of triangle buckets
//! searched ring by ring around the query (Ericson, Real-Time Collision
//! Detection, §7.1), with the exact point-triangle distance of
//! [`closest_point_on_triangle`] inside each bucket.
//!
//! Building costs O(T) for T triangles of similar size (each triangle is
//! entered into the cells its bounding box overlaps; the grid has about
//! one cell per triangle); a query near the surface visits a few cells.
//! Triangles with a non-finite corner are left out; degenerate triangles
//! (zero area) are kept, their closest point being that of a segment or a
//! point.

use super::measures::closest_point_on_triangle;
use crate::Vec3;

/// Most cells of a [`TriangleGrid`] (bounds memory for huge meshes).
const MAX_CELLS: usize = 1 << 22;

/// The point of a triangle set closest to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosestPoint {
    /// Index of the triangle (into the list the grid was built from).
    pub triangle: usize,
    /// Barycentric coordinates of the point in that triangle (sum 1, ≥ 0).
    pub barycentric: [f64; 3],
    /// The closest point.
    pub point: Vec3,
    /// Its distance to the query point.
    pub distance: f64,
}

/// A uniform grid over a triangle set for closest-point queries.
#[derive(Clone, Debug)]
pub struct TriangleGrid {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    lo: Vec3,
    cell: f64,
    dims: [usize; 3],
    /// Bucket `c` holds `items[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    items: Vec<u32>,
}

impl TriangleGrid {
    /// The grid of `triangles` (vertex indices into `positions`; an index
    /// out of range or a non-finite corner leaves the triangle out).
    pub fn new(positions: &[Vec3], triangles: &[[u32; 3]]) -> TriangleGrid {
        let usable = |t: &[u32; 3]| {
            t.iter()
                .all(|&i| positions.get(i as usize).is_some_and(|p| p.is_finite()))
        };
        let kept: Vec<u32> = (0..triangles.len() as u32)
            .filter(|&k| usable(&triangles[k as usize]))
            .collect();
        let mut lo = Vec3::splat(f64::INFINITY);
        let mut hi = Vec3::splat(f64::NEG_INFINITY);
        for &k in &kept {
            for &i in &triangles[k as usize] {
                lo = lo.min(positions[i as usize]);
                hi = hi.max(positions[i as usize]);
            }
        }
        let mut grid = TriangleGrid {
            positions: positions.to_vec(),
            triangles: triangles.to_vec(),
            lo,
            cell: 1.0,
            dims: [0; 3],
            start: vec![0],
            items: Vec::new(),
        };
        if kept.is_empty() {
            return grid;
        }
        let size = hi - lo;
        let extent = size.max_element();
        // about one cell per triangle, cubic cells, no side thinner than
        // a millionth of the largest (flat parts)
        let target = kept.len().clamp(1, MAX_CELLS) as f64;
        let thick = size.max(Vec3::splat(extent * 1e-6 + f64::MIN_POSITIVE));
        let mut cell = (thick.x * thick.y * thick.z / target).cbrt();
        if !(cell.is_finite() && cell > 0.0) {
            cell = extent.max(1.0);
        }
        let dim = |s: f64, cell: f64| ((s / cell).floor() as usize + 1).max(1);
        while dim(size.x, cell) * dim(size.y, cell) * dim(size.z, cell) > MAX_CELLS {
            cell *= 1.26;
        }
        grid.cell = cell;
        grid.dims = [dim(size.x, cell), dim(size.y, cell), dim(size.z, cell)];
        let n_cells = grid.dims.iter().product::<usize>();
        // two passes: count, then fill (compressed rows)
        let mut count = vec![0u32; n_cells + 1];
        for &k in &kept {
            grid.for_cells_of(k as usize, |c| count[c + 1] += 1);
        }
        for c in 0..n_cells {
            count[c + 1] += count[c];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; count[n_cells] as usize];
        for &k in &kept {
            grid.for_cells_of(k as usize, |c| {
                items[fill[c] as usize] = k;
                fill[c] += 1;
            });
        }
        grid.start = count;
        grid.items = items;
        grid
    }

    /// Whether the grid holds no triangle (every query answers `None`).
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// The cell of a coordinate along `axis`, clamped into the grid.
    fn cell_of(&self, x: f64, axis: usize) -> usize {
        let t = ((x - self.lo[axis]) / self.cell).floor();
        if t.is_nan() || t < 0.0 {
            0
        } else {
            (t as usize).min(self.dims[axis] - 1)
        }
    }

    fn for_cells_of(&self, k: usize, mut f: impl FnMut(usize)) {
        let t = self.triangles[k].map(|i| self.positions[i as usize]);
        let (a, b) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
        let (i0, i1) = (self.cell_of(a.x, 0), self.cell_of(b.x, 0));
        let (j0, j1) = (self.cell_of(a.y, 1), self.cell_of(b.y, 1));
        let (k0, k1) = (self.cell_of(a.z, 2), self.cell_of(b.z, 2));
        for kk in k0..=k1 {
            for j in j0..=j1 {
                for i in i0..=i1 {
                    f(i + self.dims[0] * (j + self.dims[1] * kk));
                }
            }
        }
    }

    /// The point of the triangle set closest to `p`, or `None` when the
    /// set is empty or `p` is not finite. Exact: rings of cells around `p`
    /// are searched until no unsearched cell can hold a closer point.
    pub fn closest(&self, p: Vec3) -> Option<ClosestPoint> {
        if self.is_empty() || !p.is_finite() {
            return None;
        }
        let c = [0, 1, 2].map(|a| self.cell_of(p[a], a) as i64);
        let dims = self.dims.map(|d| d as i64);
        let max_ring = *dims.iter().max().unwrap_or(&1);
        let mut best: Option<ClosestPoint> = None;
        for r in 0..=max_ring {
            // the cells at Chebyshev distance r from c
            for k in (c[2] - r).max(0)..=(c[2] + r).min(dims[2] - 1) {
                for j in (c[1] - r).max(0)..=(c[1] + r).min(dims[1] - 1) {
                    let on_shell = (k - c[2]).abs() == r || (j - c[1]).abs() == r;
                    let step = if on_shell { 1 } else { (2 * r).max(1) };
                    let mut i = c[0] - r;
                    while i <= c[0] + r {
                        if i >= 0 && i < dims[0] {
                            let cell = (i + dims[0] * (j + dims[1] * k)) as usize;
                            self.search_cell(cell, p, &mut best);
                        }
                        i += step;
                    }
                }
            }
            // every point within r cells of p's cell has been seen
            if let Some(b) = best
                && b.distance <= r as f64 * self.cell
            {
                break;
            }
        }
        best
    }

    /// Calls `f` with the closest point of every triangle that comes
    /// within `radius` of `p` (a triangle may be visited more than once,
    /// from each cell it spans). Does nothing, and returns `false`, when
    /// the cells within `radius` are more than `max_cells` (the cost of a
    /// query stays bounded); `true` otherwise.
    pub fn for_each_within(
        &self,
        p: Vec3,
        radius: f64,
        max_cells: usize,
        mut f: impl FnMut(ClosestPoint),
    ) -> bool {
        if self.is_empty() || !p.is_finite() || !(radius >= 0.0 && radius.is_finite()) {
            return false;
        }
        let range = |a: usize| {
            (
                self.cell_of(p[a] - radius, a),
                self.cell_of(p[a] + radius, a),
            )
        };
        let ((i0, i1), (j0, j1), (k0, k1)) = (range(0), range(1), range(2));
        let cells = (i1 - i0 + 1) as f64 * (j1 - j0 + 1) as f64 * (k1 - k0 + 1) as f64;
        if cells > max_cells as f64 {
            return false;
        }
        for k in k0..=k1 {
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let cell = i + self.dims[0] * (j + self.dims[1] * k);
                    let (s, e) = (self.start[cell] as usize, self.start[cell + 1] as usize);
                    for &t in &self.items[s..e] {
                        let c = self.triangles[t as usize].map(|i| self.positions[i as usize]);
                        // the triangle's box beyond the radius: skip it
                        let (a, b) = (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]));
                        let gap = (a - p).max(p - b).max(Vec3::ZERO);
                        if gap.length_squared() > radius * radius {
                            continue;
                        }
                        let w = closest_point_on_triangle(p, c[0], c[1], c[2]);
                        let q = w[0] * c[0] + w[1] * c[1] + w[2] * c[2];
                        let d = p.distance(q);
                        if d <= radius {
                            f(ClosestPoint {
                                triangle: t as usize,
                                barycentric: w,
                                point: q,
                                distance: d,
                            });
                        }
                    }
                }
            }
        }
        true
    }

    fn search_cell(&self, cell: usize, p: Vec3, best: &mut Option<ClosestPoint>) {
        let (s, e) = (self.start[cell] as usize, self.start[cell + 1] as usize);
        for &k in &self.items[s..e] {
            let t = self.triangles[k as usize].map(|i| self.positions[i as usize]);
            let w = closest_point_on_triangle(p, t[0], t[1], t[2]);
            let q = w[0] * t[0] + w[1] * t[1] + w[2] * t[2];
            let d = p.distance(q);
            if best.is_none_or(|b| d < b.distance) {
                *best = Some(ClosestPoint {
                    triangle: k as usize,
                    barycentric: w,
                    point: q,
                    distance: d,
                });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    /// The grid answers what a scan of every triangle answers.
    #[test]
    fn grid_matches_brute_force() {
        let m = shapes::torus(2.0, 0.5, 24, 12);
        let tris: Vec<[u32; 3]> = m.faces().map(|f| m.triangle(f).map(|v| v.0)).collect();
        let grid = TriangleGrid::new(m.positions(), &tris);
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..300 {
            let p = Vec3::new(rnd() * 8.0 - 4.0, rnd() * 8.0 - 4.0, rnd() * 3.0 - 1.5);
            let g = grid.closest(p).unwrap();
            let brute = tris
                .iter()
                .map(|t| {
                    let c = t.map(|i| m.positions()[i as usize]);
                    let w = closest_point_on_triangle(p, c[0], c[1], c[2]);
                    p.distance(w[0] * c[0] + w[1] * c[1] + w[2] * c[2])
                })
                .fold(f64::INFINITY, f64::min);
            assert!(
                (g.distance - brute).abs() < 1e-12,
                "{p}: {} vs {brute}",
                g.distance
            );
        }
        // far outside the grid too
        let far = grid.closest(Vec3::new(100.0, 0.0, 0.0)).unwrap();
        assert!((far.distance - 97.5).abs() < 0.05, "{}", far.distance);
    }

    /// Every triangle within the radius is visited, none beyond it, and a
    /// radius spanning too many cells visits nothing.
    #[test]
    fn triangles_within_a_radius_are_those_a_scan_finds() {
        let m = shapes::torus(2.0, 0.5, 24, 12);
        let tris: Vec<[u32; 3]> = m.faces().map(|f| m.triangle(f).map(|v| v.0)).collect();
        let grid = TriangleGrid::new(m.positions(), &tris);
        for (p, r) in [
            (Vec3::new(2.5, 0.0, 0.0), 0.3),
            (Vec3::new(0.0, 1.9, 0.4), 0.6),
            (Vec3::new(0.1, 0.1, 0.0), 1.6),
        ] {
            let mut seen = vec![false; tris.len()];
            assert!(grid.for_each_within(p, r, usize::MAX, |c| {
                assert!(c.distance <= r);
                seen[c.triangle] = true;
            }));
            for (k, t) in tris.iter().enumerate() {
                let c = t.map(|i| m.positions()[i as usize]);
                let w = closest_point_on_triangle(p, c[0], c[1], c[2]);
                let d = p.distance(w[0] * c[0] + w[1] * c[1] + w[2] * c[2]);
                assert_eq!(seen[k], d <= r, "triangle {k} at {d}, radius {r}");
            }
            assert!(seen.iter().any(|&x| x));
        }
        let mut any = false;
        assert!(!grid.for_each_within(Vec3::ZERO, 10.0, 8, |_| any = true));
        assert!(!any);
    }

    #[test]
    fn empty_and_degenerate_sets_are_answered() {
        let g = TriangleGrid::new(&[], &[]);
        assert!(g.closest(Vec3::ZERO).is_none());
        // a triangle collapsed to a segment: the distance to the segment
        let p = [Vec3::ZERO, Vec3::X, Vec3::X];
        let g = TriangleGrid::new(&p, &[[0, 1, 2]]);
        let c = g.closest(Vec3::new(0.5, 2.0, 0.0)).unwrap();
        assert!((c.distance - 2.0).abs() < 1e-12);
        // non-finite corners are left out
        let p = [Vec3::ZERO, Vec3::X, Vec3::new(f64::NAN, 0.0, 0.0)];
        assert!(TriangleGrid::new(&p, &[[0, 1, 2]]).is_empty());
        assert!(g.closest(Vec3::new(f64::NAN, 0.0, 0.0)).is_none());
    }
}
