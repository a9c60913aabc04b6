//! Detection of irregular stretches of highlight lines and their conversion
//! into suggested fairing regions (beyond Yong et al.: §3.1 leaves the
//! choice of the irregular region R to the user; this module proposes one).
//!
//! Fairness measure, per highlight line:
//! 1. the polyline is resampled at a uniform arc-length step h (default
//!    max(1.5 × mean edge length, s/25), s the light spacing), which removes
//!    the kinks every mesh edge puts into a contour line;
//! 2. the discrete curvature vector at each sample is κ_j = (u_j − u_{j−1})/h
//!    with u the unit chord directions (|κ_j| ≈ turning angle / local
//!    length), lightly smoothed over three samples;
//! 3. its slow part κ̄_j is the mean over a window of length w·s (default
//!    w = 2); the *wiggle* W_j = |κ_j − κ̄_j|·s is the curvature variation
//!    normalised by the spacing (dimensionless; 0 for circles and straight
//!    lines, and slowly varying for smooth surfaces);
//! 4. a sample is flagged when W_j exceeds `wiggle_threshold` (default 0.3),
//!    when its turning angle exceeds `kink_angle` (default 0.35 rad, 20°),
//!    or when it lies between two inflections (the curvature vector reverses
//!    with |κ|·s > `inflection_curvature`, default 0.5) closer than the
//!    window: an inflection cluster.
//!
//! When the light plane normal Z is given, samples where |Z·N| < 0.3 are
//! not judged (near silhouettes lines crowd and bend for reasons that have
//! nothing to do with fairness).
//!
//! Flagged samples closer than the window form stretches; a stretch's score
//! is Σ W_j·h/s (its integrated wiggle measured in spacings; a kink counts
//! as W = `wiggle_threshold` × turning angle / `kink_angle`). The faces whose
//! centroid lies within `region_radius` (default 0.75 s) of a flagged sample,
//! grown from the faces at the flagged nodes through face adjacency (hence
//! connected), are united over all lines; each connected component is a
//! suggested region whose score is the sum of its stretches' scores.

use super::{HighlightError, HighlightLine, HighlightLines, NodeId};
use crate::Vec3;
use crate::geom;
use crate::mesh::{FaceId, SurfaceMesh};
use rayon::prelude::*;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A small multiplicative hasher for integer cell keys (the default SipHash
/// dominated region growing); not for untrusted keys, which these are not.
#[derive(Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_i64(&mut self, i: i64) {
        self.write_u64(i as u64);
    }
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x517c_c1b7_2722_0a95);
    }
}

/// Flagged sample points per grid cell.
type CellMap = HashMap<(i64, i64, i64), Vec<Vec3>, BuildHasherDefault<CellHasher>>;

/// The 26 cells around a cell.
const NEIGHBOUR_CELLS: [(i64, i64, i64); 26] = {
    let mut out = [(0, 0, 0); 26];
    let mut n = 0;
    let mut d = 0;
    while d < 27 {
        let c = (d / 9 - 1, (d / 3) % 3 - 1, d % 3 - 1);
        if !(c.0 == 0 && c.1 == 0 && c.2 == 0) {
            out[n] = c;
            n += 1;
        }
        d += 1;
    }
    out
};

/// Options of [`detect_irregularities`]; lengths relative to the spacing s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DetectOptions {
    /// Resampling step h in mesh units; `None` = max(1.5 × mean edge
    /// length, s/25).
    pub sample_step: Option<f64>,
    /// Window length for the slow curvature part, in spacings (default 2).
    pub window: f64,
    /// Flag where |κ − κ̄|·s exceeds this (default 0.3).
    pub wiggle_threshold: f64,
    /// Flag where one sample turns by more than this many radians (0.35).
    pub kink_angle: f64,
    /// |κ|·s above which a reversal of the curvature vector counts as an
    /// inflection (default 0.5).
    pub inflection_curvature: f64,
    /// Radius around flagged samples that goes into a region, in spacings
    /// (default 0.75).
    pub region_radius: f64,
    /// Stretches scoring below this are ignored (default 0.05).
    pub min_score: f64,
    /// The light plane normal Z; when given, line samples where the surface
    /// normal N has |Z·N| < `min_normal_cos` are not judged (near
    /// silhouettes highlight lines crowd and bend for reasons unrelated to
    /// fairness). Default `None`.
    pub plane_normal: Option<Vec3>,
    /// See `plane_normal` (default 0.3).
    pub min_normal_cos: f64,
}

impl Default for DetectOptions {
    fn default() -> Self {
        DetectOptions {
            sample_step: None,
            window: 2.0,
            wiggle_threshold: 0.3,
            kink_angle: 0.35,
            inflection_curvature: 0.5,
            region_radius: 0.75,
            min_score: 0.05,
            plane_normal: None,
            min_normal_cos: 0.3,
        }
    }
}

/// A flagged stretch of one highlight line.
#[derive(Clone, Debug, PartialEq)]
pub struct Stretch {
    /// Arc length (mesh units) where the stretch starts and ends.
    pub arc: (f64, f64),
    /// Integrated normalised wiggle Σ W_j·h/s.
    pub score: f64,
    /// The flagged sample points.
    pub points: Vec<Vec3>,
}

/// Fairness of one highlight line.
#[derive(Clone, Debug, PartialEq)]
pub struct LineFairness {
    /// Position of the line in the [`HighlightLines`] it came from.
    pub line: usize,
    /// Its light index m.
    pub index: i64,
    /// Its length (mesh units).
    pub length: f64,
    /// Largest normalised wiggle |κ − κ̄|·s along the line.
    pub max_wiggle: f64,
    /// Root-mean-square normalised wiggle along the line.
    pub rms_wiggle: f64,
    /// Number of inflections (reversals of the curvature vector).
    pub inflections: usize,
    /// Sum of the scores of its stretches (for ranking lines).
    pub score: f64,
    /// Flagged stretches.
    pub stretches: Vec<Stretch>,
}

/// A suggested fairing region: a connected face set (DESIGN.md §5 region).
#[derive(Clone, Debug, PartialEq)]
pub struct IrregularRegion {
    /// Faces, ascending.
    pub faces: Vec<FaceId>,
    /// Sum of the scores of the stretches inside (for ranking).
    pub score: f64,
    /// Area-free centre: mean of the flagged sample points inside.
    pub center: Vec3,
    /// Lines (positions in the input) with stretches inside.
    pub lines: Vec<usize>,
}

/// Result of [`detect_irregularities`].
#[derive(Clone, Debug, PartialEq)]
pub struct Detection {
    /// Per-line fairness, in line order.
    pub lines: Vec<LineFairness>,
    /// Regions by decreasing score.
    pub regions: Vec<IrregularRegion>,
}

impl Detection {
    /// All region faces (union, ascending): the region JSON `{"faces":[..]}`.
    pub fn all_faces(&self) -> Vec<FaceId> {
        let mut f: Vec<FaceId> = self
            .regions
            .iter()
            .flat_map(|r| r.faces.iter().copied())
            .collect();
        f.sort_unstable();
        f.dedup();
        f
    }
}

struct Sample {
    p: Vec3,
    /// index of the polyline segment the sample lies on
    seg: usize,
}

fn resample(points: &[Vec3], closed: bool, h: f64) -> (Vec<Sample>, f64, f64) {
    let mut pts: Vec<Vec3> = points.to_vec();
    if closed && pts.len() > 2 {
        pts.push(pts[0]);
    }
    let mut cum = Vec::with_capacity(pts.len());
    let mut l = 0.0;
    cum.push(0.0);
    for w in pts.windows(2) {
        l += (w[1] - w[0]).length();
        cum.push(l);
    }
    if !(l > 0.0) || pts.len() < 2 {
        return (Vec::new(), 0.0, l);
    }
    let n = ((l / h).round() as usize).max(1);
    let step = l / n as f64;
    let count = if closed { n } else { n + 1 };
    let mut out = Vec::with_capacity(count);
    let mut k = 0;
    for j in 0..count {
        let t = (j as f64 * step).min(l);
        while k + 2 < cum.len() && cum[k + 1] < t {
            k += 1;
        }
        let len = cum[k + 1] - cum[k];
        let a = if len > 0.0 {
            ((t - cum[k]) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push(Sample {
            p: pts[k].lerp(pts[k + 1], a),
            seg: k,
        });
    }
    (out, step, l)
}

/// Fairness analysis of one line; returns the fairness and the source
/// segment (node index) of each flagged sample.
fn analyse(
    line_no: usize,
    line: &HighlightLine,
    judged: &[bool],
    s: f64,
    h: f64,
    o: &DetectOptions,
) -> (LineFairness, Vec<Vec<usize>>) {
    let (index, closed) = (line.index, line.closed);
    let (smp, step, length) = resample(&line.points, closed, h);
    let n = smp.len();
    let mut fair = LineFairness {
        line: line_no,
        index,
        length,
        max_wiggle: 0.0,
        rms_wiggle: 0.0,
        inflections: 0,
        score: 0.0,
        stretches: Vec::new(),
    };
    if n < 5 || !(step > 0.0) {
        return (fair, Vec::new());
    }
    let at = |j: isize| -> Option<usize> {
        if closed {
            Some(j.rem_euclid(n as isize) as usize)
        } else if j >= 0 && (j as usize) < n {
            Some(j as usize)
        } else {
            None
        }
    };
    // curvature vectors and turning angles
    let mut kappa = vec![Vec3::ZERO; n];
    let mut turn = vec![0.0; n];
    let mut has = vec![false; n];
    for j in 0..n {
        let (Some(a), Some(c)) = (at(j as isize - 1), at(j as isize + 1)) else {
            continue;
        };
        let seg = smp[j].seg;
        if !judged.get(seg).copied().unwrap_or(true)
            || !judged.get(seg + 1).copied().unwrap_or(true)
        {
            continue;
        }
        let u0 = (smp[j].p - smp[a].p).normalize_or_zero();
        let u1 = (smp[c].p - smp[j].p).normalize_or_zero();
        if u0 == Vec3::ZERO || u1 == Vec3::ZERO {
            continue;
        }
        kappa[j] = (u1 - u0) / step;
        turn[j] = u0.dot(u1).clamp(-1.0, 1.0).acos();
        has[j] = true;
    }
    // light smoothing (3 taps)
    let mut ks = vec![Vec3::ZERO; n];
    for j in 0..n {
        if !has[j] {
            continue;
        }
        let mut sum = Vec3::ZERO;
        let mut cnt = 0.0;
        for dj in -1..=1 {
            if let Some(i) = at(j as isize + dj)
                && has[i]
            {
                sum += kappa[i];
                cnt += 1.0;
            }
        }
        ks[j] = sum / cnt;
    }
    // slow part over the window (prefix sums; clipped at open ends)
    let half = ((o.window * s / step) * 0.5).round().max(1.0) as isize;
    let mut wig = vec![0.0; n];
    for j in 0..n {
        if !has[j] {
            continue;
        }
        let mut sum = Vec3::ZERO;
        let mut cnt = 0.0;
        for dj in -half..=half {
            if let Some(i) = at(j as isize + dj)
                && has[i]
                && (closed || (i as isize - j as isize).abs() <= half)
            {
                sum += ks[i];
                cnt += 1.0;
            }
        }
        let slow = sum / cnt;
        wig[j] = (ks[j] - slow).length() * s;
    }
    let mut flagged: Vec<bool> = (0..n)
        .map(|j| has[j] && (wig[j] > o.wiggle_threshold || turn[j] > o.kink_angle))
        .collect();
    // inflections: reversals of the smoothed curvature vector
    let mut infl: Vec<usize> = Vec::new();
    for j in 0..n {
        let Some(i) = at(j as isize + 1) else {
            continue;
        };
        if has[j]
            && has[i]
            && ks[j].length() * s > o.inflection_curvature
            && ks[i].length() * s > o.inflection_curvature
            && ks[j].dot(ks[i]) < 0.0
        {
            infl.push(j);
        }
    }
    fair.inflections = infl.len();
    let win = (o.window * s / step).round().max(1.0) as usize;
    for w in infl.windows(2) {
        if w[1] - w[0] <= win {
            for f in flagged.iter_mut().take(w[1] + 1).skip(w[0]) {
                *f = true;
            }
        }
    }
    fair.max_wiggle = wig.iter().copied().fold(0.0, f64::max);
    let cnt = has.iter().filter(|&&x| x).count().max(1) as f64;
    fair.rms_wiggle = (wig.iter().map(|w| w * w).sum::<f64>() / cnt).sqrt();
    // stretches: flagged samples with gaps below the window merged
    let mut stretches: Vec<(usize, usize)> = Vec::new();
    for j in 0..n {
        if !flagged[j] {
            continue;
        }
        match stretches.last_mut() {
            Some(last) if j - last.1 <= win => last.1 = j,
            _ => stretches.push((j, j)),
        }
    }
    let mut segs = Vec::new();
    for (a, b) in stretches {
        let score: f64 = (a..=b)
            .map(|j| wig[j].max(o.wiggle_threshold * turn[j] / o.kink_angle))
            .sum::<f64>()
            * step
            / s;
        if !(score >= o.min_score) {
            continue;
        }
        fair.stretches.push(Stretch {
            arc: (a as f64 * step, b as f64 * step),
            score,
            points: (a..=b).map(|j| smp[j].p).collect(),
        });
        segs.push((a..=b).map(|j| smp[j].seg).collect());
        fair.score += score;
    }
    (fair, segs)
}

/// Detects irregular stretches of highlight lines and turns them into
/// suggested fairing regions (see the module documentation for the measure,
/// defaults and region construction). `spacing` is the light spacing s
/// (mesh units) the wiggle is normalised by. Errors on non-triangle meshes
/// and invalid options; lines with fewer than five samples are scored 0.
pub fn detect_irregularities(
    mesh: &SurfaceMesh,
    lines: &HighlightLines,
    spacing: f64,
    options: &DetectOptions,
) -> Result<Detection, HighlightError> {
    mesh.require_triangles()?;
    let o = options;
    if !(spacing > 0.0) || !spacing.is_finite() {
        return Err(HighlightError::InvalidOption(format!(
            "spacing must be positive, got {spacing}"
        )));
    }
    for (name, v) in [
        ("window", o.window),
        ("wiggle_threshold", o.wiggle_threshold),
        ("kink_angle", o.kink_angle),
        ("region_radius", o.region_radius),
    ] {
        if !(v > 0.0) || !v.is_finite() {
            return Err(HighlightError::InvalidOption(format!(
                "{name} must be positive, got {v}"
            )));
        }
    }
    let h = match o.sample_step {
        Some(h) if h > 0.0 && h.is_finite() => h,
        Some(h) => {
            return Err(HighlightError::InvalidOption(format!(
                "sample_step must be positive, got {h}"
            )));
        }
        None => {
            let e = geom::mean_edge_length(mesh);
            let h = (1.5 * e).max(spacing / 25.0);
            if h > 0.0 && h.is_finite() {
                h
            } else {
                spacing / 25.0
            }
        }
    };
    // which nodes are judged: |Z·N| >= min_normal_cos at the node
    let normals = o.plane_normal.map(|_| geom::vertex_normals(mesh));
    let z = o.plane_normal.and_then(|z| z.try_normalize());
    let judged_node = |nd: NodeId| -> bool {
        let (Some(z), Some(nrm)) = (z, normals.as_ref()) else {
            return true;
        };
        let n = match nd {
            NodeId::Vertex(v, _) => nrm[v.idx()],
            NodeId::Edge(e, _) => {
                let (a, b) = mesh.edge_vertices(e);
                nrm[a.idx()] + nrm[b.idx()]
            }
        };
        n.normalize_or_zero().dot(z).abs() >= o.min_normal_cos
    };
    let analysed: Vec<(LineFairness, Vec<Vec<usize>>)> = lines
        .lines
        .par_iter()
        .enumerate()
        .map(|(i, l)| {
            let mut judged: Vec<bool> = l.nodes.iter().map(|&nd| judged_node(nd)).collect();
            if l.closed && !judged.is_empty() {
                judged.push(judged[0]);
            }
            analyse(i, l, &judged, spacing, h, o)
        })
        .collect();
    let radius = o.region_radius * spacing;
    let p = mesh.positions();
    let centroid = |f: FaceId| {
        let [a, b, c] = mesh.triangle(f);
        (p[a.idx()] + p[b.idx()] + p[c.idx()]) / 3.0
    };
    let node_faces = |nd: NodeId| -> Vec<FaceId> {
        match nd {
            NodeId::Edge(e, _) => [0, 1]
                .iter()
                .filter_map(|&i| mesh.face(mesh.edge_halfedge(e, i)))
                .collect(),
            NodeId::Vertex(v, _) => mesh.vertex_faces(v).collect(),
        }
    };
    // per stretch: grown face sets
    let mut in_region = vec![false; mesh.face_count()];
    let mut stretch_faces: Vec<(usize, f64, Vec3, Vec<FaceId>)> = Vec::new();
    let mut mark = vec![u32::MAX; mesh.face_count()];
    let mut stamp = 0u32;
    for (li, (fair, segs)) in analysed.iter().enumerate() {
        let line = &lines.lines[li];
        for (st, seg_ids) in fair.stretches.iter().zip(segs) {
            stamp += 1;
            let mut queue: Vec<FaceId> = Vec::new();
            for &k in seg_ids {
                let nodes = &line.nodes;
                for nd in [nodes.get(k), nodes.get((k + 1) % nodes.len().max(1))]
                    .into_iter()
                    .flatten()
                {
                    for f in node_faces(*nd) {
                        if mark[f.idx()] != stamp {
                            mark[f.idx()] = stamp;
                            queue.push(f);
                        }
                    }
                }
            }
            // flagged samples bucketed in cubes of side `radius`: a face is
            // near when a sample in its own cube or one of the 26 around it
            // is close (own cube first: the usual hit inside a region)
            let cell = |x: Vec3| {
                let c = (x / radius).floor();
                (c.x as i64, c.y as i64, c.z as i64)
            };
            let mut grid: CellMap = HashMap::default();
            for &q in &st.points {
                grid.entry(cell(q)).or_default().push(q);
            }
            let near = |x: Vec3| {
                let (i, j, k) = cell(x);
                let hit = |c: (i64, i64, i64)| {
                    grid.get(&c)
                        .is_some_and(|pts| pts.iter().any(|q| (x - *q).length() <= radius))
                };
                hit((i, j, k))
                    || NEIGHBOUR_CELLS.iter().any(|&(di, dj, dk)| {
                        hit((
                            i.saturating_add(di),
                            j.saturating_add(dj),
                            k.saturating_add(dk),
                        ))
                    })
            };
            let mut faces = Vec::new();
            while let Some(f) = queue.pop() {
                faces.push(f);
                for hh in mesh.face_halfedges(f) {
                    if let Some(g) = mesh.face(mesh.opposite(hh))
                        && mark[g.idx()] != stamp
                    {
                        mark[g.idx()] = stamp;
                        if near(centroid(g)) {
                            queue.push(g);
                        }
                    }
                }
            }
            for f in &faces {
                in_region[f.idx()] = true;
            }
            let c = st.points.iter().copied().sum::<Vec3>() / st.points.len().max(1) as f64;
            stretch_faces.push((li, st.score, c, faces));
        }
    }
    // connected components of the union
    let mut comp = vec![u32::MAX; mesh.face_count()];
    let mut regions: Vec<IrregularRegion> = Vec::new();
    for f0 in 0..mesh.face_count() {
        if !in_region[f0] || comp[f0] != u32::MAX {
            continue;
        }
        let id = regions.len() as u32;
        let mut faces = Vec::new();
        let mut stack = vec![FaceId(f0 as u32)];
        comp[f0] = id;
        while let Some(f) = stack.pop() {
            faces.push(f);
            for hh in mesh.face_halfedges(f) {
                if let Some(g) = mesh.face(mesh.opposite(hh))
                    && in_region[g.idx()]
                    && comp[g.idx()] == u32::MAX
                {
                    comp[g.idx()] = id;
                    stack.push(g);
                }
            }
        }
        faces.sort_unstable();
        regions.push(IrregularRegion {
            faces,
            score: 0.0,
            center: Vec3::ZERO,
            lines: Vec::new(),
        });
    }
    let mut weight = vec![0.0; regions.len()];
    for (li, score, c, faces) in &stretch_faces {
        // a stretch may touch several components: share its score by faces
        let mut ids: Vec<usize> = faces.iter().map(|f| comp[f.idx()] as usize).collect();
        ids.sort_unstable();
        let total = ids.len() as f64;
        for chunk in ids.chunk_by(|a, b| a == b) {
            let r = chunk[0];
            let share = score * chunk.len() as f64 / total;
            regions[r].score += share;
            regions[r].center += share * *c;
            weight[r] += share;
            regions[r].lines.push(*li);
        }
    }
    for (r, w) in regions.iter_mut().zip(&weight) {
        if *w > 0.0 {
            r.center /= *w;
        }
        r.lines.sort_unstable();
        r.lines.dedup();
    }
    regions.retain(|r| r.score > 0.0);
    regions.sort_by(|a, b| b.score.total_cmp(&a.score).then(a.faces.cmp(&b.faces)));
    Ok(Detection {
        lines: analysed.into_iter().map(|(f, _)| f).collect(),
        regions,
    })
}
