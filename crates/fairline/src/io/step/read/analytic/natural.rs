//! Natural coordinates of a face on a periodic surface: angles wrapped and
//! unwrapped along a loop, the box the loops span, and loops recut between
//! holes.

use super::{NaturalBox, NaturalLoop, Periods};
use crate::bspline::{TrimCurve, polygon_signed_area2};
use crate::io::step::read::curves::ToUv;
use crate::io::step::read::polyline;

/// `x` shifted by whole periods to within half a period of `near`.
fn wrap(x: f64, near: f64, period: Option<f64>) -> f64 {
    match period {
        Some(p) if p > 0.0 => x + p * ((near - x) / p).round(),
        _ => x,
    }
}

/// Points on the axis (angle undefined) take the angle of the point before
/// them, going round the loop from the first point off the axis.
pub(super) fn take_neighbour_angles_on_axis(pts: &mut [(f64, f64, bool)]) {
    if let Some(k) = pts.iter().position(|p| !p.2) {
        let n = pts.len();
        for s in 1..n {
            let (prev, cur) = ((k + s - 1) % n, (k + s) % n);
            if pts[cur].2 {
                pts[cur].0 = pts[prev].0;
            }
        }
    }
}

/// The loop with each coordinate shifted by whole periods to within half a
/// period of the point before it.
pub(super) fn unwrap_loop(pts: &[(f64, f64, bool)], periods: Periods) -> NaturalLoop {
    let mut out: NaturalLoop = Vec::with_capacity(pts.len());
    for &(a, b, _) in pts {
        let (mut a, mut b) = (a, b);
        if let Some(&(pa, pb)) = out.last() {
            a = wrap(a, pa, periods[0]);
            b = wrap(b, pb, periods[1]);
        }
        out.push((a, b));
    }
    out
}

/// Holes shifted by whole periods next to the outer loop (their mean
/// within half a period of the outer loop's).
pub(super) fn shift_holes_next_to_outer(nat: &mut [NaturalLoop], periods: Periods) {
    let mean = |l: &[(f64, f64)]| {
        let n = l.len().max(1) as f64;
        (
            l.iter().map(|p| p.0).sum::<f64>() / n,
            l.iter().map(|p| p.1).sum::<f64>() / n,
        )
    };
    let Some(outer) = nat.first() else { return };
    let (ma, mb) = mean(outer);
    for l in nat.iter_mut().skip(1) {
        let (la, lb) = mean(l);
        let (sa, sb) = (wrap(la, ma, periods[0]) - la, wrap(lb, mb, periods[1]) - lb);
        for p in l.iter_mut() {
            p.0 += sa;
            p.1 += sb;
        }
    }
}

/// The box of all loops' natural coordinates, each side at most one period
/// long; `None` when it encloses no area or spans more than a period.
pub(super) fn natural_box(nat: &[NaturalLoop], periods: Periods) -> Option<NaturalBox> {
    let (mut a0, mut a1, mut b0, mut b1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(a, b) in nat.iter().flatten() {
        a0 = a0.min(a);
        a1 = a1.max(a);
        b0 = b0.min(b);
        b1 = b1.max(b);
    }
    let too_wide =
        |lo: f64, hi: f64, period: Option<f64>| period.is_some_and(|p| hi - lo > p * (1.0 + 1e-9));
    if a1 <= a0 || b1 <= b0 || too_wide(a0, a1, periods[0]) || too_wide(b0, b1, periods[1]) {
        return None;
    }
    let clip = |lo: f64, hi: f64, period: Option<f64>| period.map_or(hi, |p| hi.min(lo + p));
    Some(NaturalBox {
        a: [a0, clip(a0, a1, periods[0])],
        b: [b0, clip(b0, b1, periods[1])],
    })
}

/// A stretch of natural coordinates as a polyline in the NURBS parameters.
pub(super) fn natural_polyline(l: &[(f64, f64)], to_uv: ToUv) -> Result<TrimCurve, String> {
    let pts: Vec<[f64; 2]> = l.iter().map(|&(a, b)| to_uv.at(a, b)).collect();
    polyline(&pts)
}

/// Whole periods a loop winds in each natural coordinate: its last point
/// (the end of its last edge, which closes the loop) minus its first, in
/// periods.
pub(super) fn turns(l: &[(f64, f64)], periods: Periods) -> [i64; 2] {
    let (Some(f), Some(e)) = (l.first(), l.last()) else {
        return [0, 0];
    };
    let count = |d: f64, period: Option<f64>| match period {
        Some(p) if p > 0.0 => (d / p).round() as i64,
        _ => 0,
    };
    [count(e.0 - f.0, periods[0]), count(e.1 - f.1, periods[1])]
}

/// A point `(s, t)` of a loop in the coordinates where `s` is the one the
/// loop winds in.
pub(super) type St = (f64, f64);

/// The loop `l` (winding once in `s`, first and last points one period
/// apart, `s` increasing overall) re-cut to run from `s = cut` to
/// `s = cut + period`: shifted by whole periods, rotated to start at its
/// first crossing of `cut` (the crossing point interpolated) and closed
/// one period on.
pub(super) fn recut(l: &[St], cut: f64, period: f64) -> Vec<St> {
    let n = l.len();
    if n < 2 {
        return l.to_vec();
    }
    let shift = period * ((cut - l[0].0) / period).floor();
    let pts: Vec<St> = l[..n - 1].iter().map(|&(s, t)| (s + shift, t)).collect();
    // pts[0].0 <= cut < pts[0].0 + period; the loop continues with pts[0] + period.
    let at = |k: usize| -> St {
        if k < pts.len() {
            pts[k]
        } else {
            (pts[k - pts.len()].0 + period, pts[k - pts.len()].1)
        }
    };
    let m = pts.len();
    let k = (0..m)
        .find(|&k| at(k).0 <= cut && cut < at(k + 1).0)
        .unwrap_or(0);
    let (p, q) = (at(k), at(k + 1));
    let ds = q.0 - p.0;
    let w = if ds > 0.0 { (cut - p.0) / ds } else { 0.0 };
    let start = (cut, p.1 + w * (q.1 - p.1));
    let mut out = Vec::with_capacity(m + 2);
    out.push(start);
    for j in k + 1..=k + m {
        let r = at(j);
        if r.0 > cut && r.0 < cut + period {
            out.push(r);
        }
    }
    out.push((cut + period, start.1));
    out
}

/// An `s` at which to cut the surface open: in the middle of the widest gap
/// between the `s` ranges of the holes (so that no hole straddles the cut),
/// or `default` without holes.
pub(super) fn cut_between_holes(holes: &[Vec<St>], period: f64, default: f64) -> f64 {
    let mut spans: Vec<(f64, f64)> = holes
        .iter()
        .filter_map(|h| {
            let lo = h.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
            let hi = h.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
            (lo <= hi).then(|| {
                let lo_mod = lo.rem_euclid(period);
                (lo_mod, lo_mod + (hi - lo))
            })
        })
        .collect();
    if spans.is_empty() {
        return default;
    }
    spans.sort_by(|x, y| x.0.total_cmp(&y.0));
    // Merge overlapping spans, then take the widest gap (cyclically).
    let mut merged: Vec<(f64, f64)> = Vec::new();
    for (lo, hi) in spans {
        match merged.last_mut() {
            Some(last) if lo <= last.1 => last.1 = last.1.max(hi),
            _ => merged.push((lo, hi)),
        }
    }
    let mut best = (f64::NEG_INFINITY, default);
    for (k, &(_, hi)) in merged.iter().enumerate() {
        let next_lo = if k + 1 < merged.len() {
            merged[k + 1].0
        } else {
            merged[0].0 + period
        };
        let gap = next_lo - hi;
        if gap > best.0 {
            best = (gap, 0.5 * (hi + next_lo));
        }
    }
    best.1
}

/// Whether a loop encloses its whole natural box (its area, by the shoelace
/// formula, is the box's to 1e-9): the face is then the untrimmed NURBS.
pub(super) fn covers_box(l: &[(f64, f64)], span: NaturalBox) -> bool {
    let pts: Vec<[f64; 2]> = l.iter().map(|&(a, b)| [a, b]).collect();
    let area = 0.5 * polygon_signed_area2(&pts).abs();
    let whole = (span.a[1] - span.a[0]) * (span.b[1] - span.b[0]);
    whole > 0.0 && area >= whole * (1.0 - 1e-9)
}
