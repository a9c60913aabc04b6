//! Desired highlight lines, Yong et al. §3.2 and §3.5: for every highlight
//! line that crosses the region R, the nodes Q0 and Q1 just outside R, the
//! tangents there estimated from the line's outside part, the optimized
//! geometric Hermite (OGH) curve of Eq. (5) between them, and the target
//! Q̃_i of every inside node by Eq. (12) with its segment length l_i of
//! Eq. (14).
//!
//! Tangents: the outside nodes beyond Q0 (resp. Q1), up to an arc length of
//! half the chord |Q1 − Q0| (at least three nodes when the line has them),
//! are fitted in the least-squares sense by a parabola P(s) = Q + a·s + b·s²
//! through Q in the arc-length parameter s; the tangent is a. A contour line
//! of a triangle mesh kinks at every edge, so a one-segment difference would
//! be noisy; the parabola also follows a line that is curved outside R. With
//! a single outside neighbour the fit is linear; with none the tangent is
//! zero and [`crate::curves::ogh_curve`] falls back to the straight segment
//! (its documented [`crate::curves::OghKind::Straight`] case; the
//! `Constrained` case covers a failed tangent-preserving condition).
//!
//! Refitted tangents (beyond the paper; Yong et al. §3.7 rebuild the
//! target function from the current mesh in every iteration): on the input
//! the tangents T0, T1 can only be fitted to the line's outside part, an
//! extrapolation that is poor where that part is short or curved (wide
//! regions). Once the defect is gone, [`across_tangents`] fits the same
//! parabola to nodes on both sides of Q0 (resp. Q1) — the outside part and
//! the nearest quarter chord of the faired inside line — a central estimate
//! of the line's direction at Q0 that is still anchored outside;
//! [`desired_lines_with`] builds the OGH curves with them.
//!
//! A run of inside nodes that reaches the end of an open line (the line
//! stops inside R) has no second delimiting node and gets no desired curve;
//! neither does a closed line lying entirely inside R. They are counted in
//! [`DesiredLines::skipped`].

use crate::Vec3;
use crate::curves::{ArcLengthTable, OghCurve, chord_parameters, ogh_curve};
use crate::highlight::{HighlightLines, NodeId};
use std::collections::BTreeMap;

/// Refitted tangents (T0, T1) of desired lines, by the delimiting nodes
/// (Q0, Q1) of their run (outside R, so they do not change while R is
/// faired).
pub type Tangents = BTreeMap<(NodeId, NodeId), (Vec3, Vec3)>;

/// Samples of the arc-length table of an OGH curve.
const ARC_SAMPLES: usize = 256;

/// One desired highlight line between two delimiting outside nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct DesiredLine {
    /// Light index m of the line.
    pub index: i64,
    /// The delimiting outside nodes Q0 and Q1 (Q_0 and Q_{n+1}).
    pub ends: (NodeId, NodeId),
    /// Positions of Q0 and Q1.
    pub end_points: (Vec3, Vec3),
    /// Tangents T0 and T1 estimated from the outside part of the line
    /// (zero when the line has no outside node beyond Q0 or Q1).
    pub tangents: (Vec3, Vec3),
    /// The OGH curve of Eq. (5) (or its documented fallback).
    pub curve: OghCurve,
    /// The inside nodes Q_1..Q_n in line order.
    pub nodes: Vec<NodeId>,
    /// Their current positions.
    pub points: Vec<Vec3>,
    /// Target positions Q̃_i = H̃(c(Q_i)), Eq. (12).
    pub targets: Vec<Vec3>,
    /// Segment lengths l_i, Eq. (14).
    pub lengths: Vec<f64>,
    /// The OGH curve sampled densely (for distances and drawing).
    pub samples: Vec<Vec3>,
}

/// The desired lines of one region.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DesiredLines {
    /// Lines with both delimiting nodes.
    pub lines: Vec<DesiredLine>,
    /// Runs of inside nodes without two delimiting outside nodes.
    pub skipped: usize,
}

/// How far the highlight lines inside R are from their desired curves.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HighlightDeviation {
    /// Length-weighted RMS distance of the inside nodes to their desired
    /// OGH curves, sqrt(Σ l_i dist_i² / Σ l_i) (mesh units).
    pub rms: f64,
    /// Largest such distance (mesh units).
    pub max: f64,
    /// Inside nodes measured.
    pub nodes: usize,
}

/// Least-squares parabola through `q` fitted to `pts` at arc lengths `s`
/// (signed); returns the derivative at `q`.
pub(super) fn fitted_tangent(q: Vec3, pts: &[Vec3], s: &[f64]) -> Vec3 {
    if pts.is_empty() {
        return Vec3::ZERO;
    }
    let (mut s2, mut s3, mut s4) = (0.0, 0.0, 0.0);
    let (mut r1, mut r2) = (Vec3::ZERO, Vec3::ZERO);
    for (&p, &t) in pts.iter().zip(s) {
        let d = p - q;
        s2 += t * t;
        s3 += t * t * t;
        s4 += t * t * t * t;
        r1 += t * d;
        r2 += t * t * d;
    }
    let det = s2 * s4 - s3 * s3;
    if pts.len() >= 2 && det > 1e-12 * s2 * s4 && det.is_finite() {
        let a = (s4 * r1 - s3 * r2) / det;
        if a.is_finite() {
            return a;
        }
    }
    if s2 > 0.0 {
        let a = r1 / s2;
        if a.is_finite() {
            return a;
        }
    }
    Vec3::ZERO
}

/// Nodes of one side (`inside[i] == side`) walking away from position
/// `start` of `seq` in direction `step` (±1), up to arc length `reach` (at
/// least `min_nodes` nodes when available); returns points and signed arc
/// lengths (negative backwards).
pub(super) fn part(
    seq: &[(NodeId, Vec3)],
    inside: &[bool],
    side: bool,
    start: usize,
    step: isize,
    reach: f64,
    min_nodes: usize,
) -> (Vec<Vec3>, Vec<f64>) {
    let mut pts = Vec::new();
    let mut s = Vec::new();
    let mut acc = 0.0;
    let mut prev = seq[start].1;
    let mut i = start as isize + step;
    while i >= 0 && (i as usize) < seq.len() && inside[i as usize] == side {
        let p = seq[i as usize].1;
        acc += (p - prev).length();
        pts.push(p);
        s.push(acc * step as f64);
        prev = p;
        if acc >= reach && pts.len() >= min_nodes {
            break;
        }
        i += step;
    }
    (pts, s)
}

/// One run of inside nodes of a line with its delimiting outside nodes:
/// the line's node sequence (closed lines opened at an outside node),
/// the inside flags, and the run `a..b` (Q0 at a − 1, Q1 at b).
pub(super) struct Run<'a> {
    pub(super) index: i64,
    pub(super) seq: &'a [(NodeId, Vec3)],
    pub(super) ins: &'a [bool],
    pub(super) a: usize,
    pub(super) b: usize,
}

/// Calls `f` for every run of inside nodes with two delimiting outside
/// nodes (§3.2); returns the runs without them (skipped).
pub(super) fn for_each_run(
    lines: &HighlightLines,
    inside: impl Fn(NodeId) -> bool,
    mut f: impl FnMut(&Run<'_>),
) -> usize {
    let mut skipped = 0;
    for line in &lines.lines {
        let n = line.nodes.len().min(line.points.len());
        if n == 0 {
            continue;
        }
        let flags: Vec<bool> = line.nodes[..n].iter().map(|&nd| inside(nd)).collect();
        if !flags.iter().any(|&f| f) {
            continue;
        }
        // the node sequence as an open polyline; closed lines start at an
        // outside node and repeat it at the end
        let mut seq: Vec<(NodeId, Vec3)> = Vec::with_capacity(n + 1);
        let mut ins: Vec<bool> = Vec::with_capacity(n + 1);
        if line.closed {
            let Some(first) = flags.iter().position(|&f| !f) else {
                skipped += 1;
                continue;
            };
            for k in 0..=n {
                let j = (first + k) % n;
                seq.push((line.nodes[j], line.points[j]));
                ins.push(flags[j]);
            }
        } else {
            for j in 0..n {
                seq.push((line.nodes[j], line.points[j]));
                ins.push(flags[j]);
            }
        }
        let len = seq.len();
        let mut i = 0;
        while i < len {
            if !ins[i] {
                i += 1;
                continue;
            }
            let a = i;
            while i < len && ins[i] {
                i += 1;
            }
            let b = i; // one past the run
            if a == 0 || b >= len {
                skipped += 1;
                continue;
            }
            f(&Run {
                index: line.index,
                seq: &seq,
                ins: &ins,
                a,
                b,
            });
        }
    }
    skipped
}

/// Builds the desired highlight lines (Yong et al. §3.2, §3.5) of the lines
/// `lines` for the region whose inside nodes are those for which `inside`
/// returns true; see the module documentation for tangents and skipped
/// runs. Node positions are those stored in `lines`.
pub fn desired_lines(lines: &HighlightLines, inside: impl Fn(NodeId) -> bool) -> DesiredLines {
    desired_lines_with(lines, inside, &Tangents::new())
}

/// [`desired_lines`] with the tangents of `tangents` (from
/// [`across_tangents`]) for the runs it lists; the other runs get tangents
/// fitted to the outside part.
pub fn desired_lines_with(
    lines: &HighlightLines,
    inside: impl Fn(NodeId) -> bool,
    tangents: &Tangents,
) -> DesiredLines {
    let mut out = DesiredLines::default();
    out.skipped = for_each_run(lines, inside, |run| {
        let Run {
            index,
            seq,
            ins,
            a,
            b,
        } = *run;
        let (q0, q1) = (seq[a - 1], seq[b]);
        let (t0, t1) = match tangents.get(&(q0.0, q1.0)) {
            Some(&t) => t,
            None => {
                let reach = 0.5 * (q1.1 - q0.1).length();
                let (p0, s0) = part(seq, ins, false, a - 1, -1, reach, 3);
                let (p1, s1) = part(seq, ins, false, b, 1, reach, 3);
                (
                    fitted_tangent(q0.1, &p0, &s0),
                    fitted_tangent(q1.1, &p1, &s1),
                )
            }
        };
        let curve = ogh_curve(q0.1, t0, q1.1, t1);
        let table = ArcLengthTable::new(|t| curve.hermite.point(t), ARC_SAMPLES);
        let run_pts: Vec<Vec3> = seq[a - 1..=b].iter().map(|x| x.1).collect();
        let c = chord_parameters(&run_pts);
        let nodes: Vec<NodeId> = seq[a..b].iter().map(|x| x.0).collect();
        let points: Vec<Vec3> = run_pts[1..run_pts.len() - 1].to_vec();
        let targets: Vec<Vec3> = c[1..c.len() - 1].iter().map(|&s| table.point(s)).collect();
        let lengths: Vec<f64> = (1..run_pts.len() - 1)
            .map(|k| {
                0.5 * ((run_pts[k] - run_pts[k - 1]).length()
                    + (run_pts[k] - run_pts[k + 1]).length())
            })
            .collect();
        let samples: Vec<Vec3> = (0..=ARC_SAMPLES)
            .map(|k| curve.hermite.point(k as f64 / ARC_SAMPLES as f64))
            .collect();
        out.lines.push(DesiredLine {
            index,
            ends: (q0.0, q1.0),
            end_points: (q0.1, q1.1),
            tangents: (t0, t1),
            curve,
            nodes,
            points,
            targets,
            lengths,
            samples,
        });
    });
    out
}

/// Share of the chord |Q1 − Q0| of the inside line that
/// [`across_tangents`] adds to the outside part.
const ACROSS_REACH: f64 = 0.25;

/// Tangents T0, T1 of every run fitted across its delimiting nodes (module
/// documentation): the parabola of [`desired_lines`] through Q0 fitted to
/// the outside nodes beyond Q0 (up to half the chord) and the inside nodes
/// after it (up to a quarter of the chord, at least two), likewise at Q1.
/// Meant for a mesh whose region has already been faired.
pub fn across_tangents(lines: &HighlightLines, inside: impl Fn(NodeId) -> bool) -> Tangents {
    let mut out = Tangents::new();
    for_each_run(lines, inside, |run| {
        let Run { seq, ins, a, b, .. } = *run;
        let (q0, q1) = (seq[a - 1], seq[b]);
        let chord = (q1.1 - q0.1).length();
        let across = |q: usize, outward: isize| {
            let (mut p, mut s) = part(seq, ins, false, q, outward, 0.5 * chord, 3);
            let (pi, si) = part(seq, ins, true, q, -outward, ACROSS_REACH * chord, 2);
            p.extend(pi);
            s.extend(si);
            fitted_tangent(seq[q].1, &p, &s)
        };
        let (t0, t1) = (across(a - 1, -1), across(b, 1));
        if t0.is_finite() && t1.is_finite() && t0 != Vec3::ZERO && t1 != Vec3::ZERO {
            out.insert((q0.0, q1.0), (t0, t1));
        }
    });
    out
}

/// Distance from `p` to the polyline `pts`.
pub fn distance_to_polyline(p: Vec3, pts: &[Vec3]) -> f64 {
    match pts.len() {
        0 => f64::INFINITY,
        1 => (p - pts[0]).length(),
        _ => pts
            .windows(2)
            .map(|w| {
                let d = w[1] - w[0];
                let l2 = d.length_squared();
                let t = if l2 > 0.0 {
                    ((p - w[0]).dot(d) / l2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (p - (w[0] + t * d)).length()
            })
            .fold(f64::INFINITY, f64::min),
    }
}

impl DesiredLines {
    /// Highlight deviation of the current inside nodes from the desired
    /// curves: each node's distance to its OGH curve, weighted by l_i.
    pub fn deviation(&self) -> HighlightDeviation {
        let (mut num, mut den, mut max, mut count) = (0.0, 0.0, 0.0f64, 0);
        for l in &self.lines {
            for (p, &w) in l.points.iter().zip(&l.lengths) {
                let d = distance_to_polyline(*p, &l.samples);
                if d.is_finite() {
                    num += w * d * d;
                    den += w;
                    max = max.max(d);
                    count += 1;
                }
            }
        }
        HighlightDeviation {
            rms: if den > 0.0 { (num / den).sqrt() } else { 0.0 },
            max,
            nodes: count,
        }
    }
}
