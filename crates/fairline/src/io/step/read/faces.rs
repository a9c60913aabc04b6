//! Faces on B-spline surfaces (and offsets of them): the surface, its trimming
//! loops from parameter-space curves or the 3-D edges, and the choice between
//! the two curves of a seam.

use super::edges::EdgeUse;
use super::pcurve::{PcurveMap, PcurveUse};
use super::{R, Reader, StepSurface, invert_point, polyline};
use crate::bspline::{BSplineSurface, TrimCurve, TrimLoop};
use crate::io::step::p21::{Instance, Value};

impl<'a> Reader<'a> {
    /// B_SPLINE_SURFACE_WITH_KNOTS, simple or complex (with
    /// RATIONAL_B_SPLINE_SURFACE).
    pub(super) fn bspline_surface(&self, i: &'a Instance) -> R<BSplineSurface> {
        let (head, tail): (&[Value], &[Value]) = match i.part("B_SPLINE_SURFACE") {
            Some(h) => (h, i.part("B_SPLINE_SURFACE_WITH_KNOTS").unwrap_or(&[])),
            None => {
                let p = self.params(i, &["B_SPLINE_SURFACE_WITH_KNOTS"])?;
                (p.get(1..8).unwrap_or(&[]), p.get(8..).unwrap_or(&[]))
            }
        };
        let (du, dv) = (self.int(i, head, 0)?, self.int(i, head, 1)?);
        let rows = self.list(i, head, 2)?;
        let mut points = Vec::new();
        let mut count_v = None;
        for row in rows {
            let Value::List(r) = row else {
                return Err(self.err(i, "control points are not a list of lists".into()));
            };
            if *count_v.get_or_insert(r.len()) != r.len() {
                return Err(self.err(i, "control point rows differ in length".into()));
            }
            for p in self.refs(i, r)? {
                points.push(self.point(p)?);
            }
        }
        let ku = self.knots(i, self.list(i, tail, 0)?, self.list(i, tail, 2)?)?;
        let kv = self.knots(i, self.list(i, tail, 1)?, self.list(i, tail, 3)?)?;
        let weights = match i.part("RATIONAL_B_SPLINE_SURFACE") {
            Some(w) => {
                let mut out = Vec::new();
                for row in self.list(i, w, 0)? {
                    let Value::List(r) = row else {
                        return Err(self.err(i, "weights are not a list of lists".into()));
                    };
                    out.extend(self.numbers(i, r)?);
                }
                Some(out)
            }
            None => None,
        };
        BSplineSurface::from_flat(
            du,
            dv,
            ku,
            kv,
            [rows.len(), count_v.unwrap_or(0)],
            points,
            weights,
        )
        .map_err(|e| self.err(i, e.to_string()))
    }
}

impl<'a> Reader<'a> {
    /// An `OFFSET_SURFACE` (ISO 10303-42 §4.4.14) whose basis, through
    /// nested offsets, is a B-spline surface: the exact offset S + d·N on
    /// the basis's parameters, as a plane moved exactly or a bicubic
    /// B-spline fitted within 1e-7 of the basis's size
    /// ([`crate::bspline::offset::offset_surface`]), the fit named in the
    /// warnings. `None` for any other surface.
    fn offset_of_bspline(&self, si: &'a Instance) -> R<Option<BSplineSurface>> {
        if !si.is("OFFSET_SURFACE") {
            return Ok(None);
        }
        let (basis, d) = self.offset_basis(si)?;
        if !basis.is("B_SPLINE_SURFACE_WITH_KNOTS") {
            return Ok(None);
        }
        let s = self.bspline_surface(basis)?;
        let o = self
            .offset_on_parameters(&s, d, si.id)
            .map_err(|m| self.err(si, format!("the offset surface: {m}")))?;
        Ok(Some(o))
    }

    /// `basis` offset by `distance` along its normal on its parameters
    /// ([`crate::bspline::offset::offset_surface`]): exact for a plane,
    /// otherwise a bicubic fitted within 1e-7 of the size of the basis's
    /// control net (plus twice the distance), the fit named in the
    /// warnings as the `OFFSET_SURFACE` `#entity`. Errors say why no fit
    /// was found.
    pub(super) fn offset_on_parameters(
        &self,
        basis: &BSplineSurface,
        distance: f64,
        entity: u64,
    ) -> Result<BSplineSurface, String> {
        let (lo, hi) = basis.control_bounding_box();
        let tolerance = 1e-7 * ((hi - lo).length() + 2.0 * distance.abs());
        let o = crate::bspline::offset::offset_surface(basis, distance, tolerance)?;
        if let Some(e) = o.deviation {
            self.fitted.borrow_mut().push(format!(
                "#{entity} OFFSET_SURFACE: the offset surface is approximated by a bicubic B-spline within {tolerance:.1e} (largest deviation found {e:.1e})"
            ));
        }
        Ok(o.surface)
    }
}

/// For each edge of a loop with several agreeing p-curves (a seam), the
/// index of the one to use (0: the first); `None` for the others. Every
/// edge takes the candidate whose start lies nearest to the previous
/// edge's end, starting from each candidate of the first such edge in
/// turn; the start with the smallest total gap around the loop wins.
fn seam_choice(found: &[(PcurveUse, Vec<TrimCurve>)]) -> Vec<Option<usize>> {
    let n = found.len();
    let cands: Vec<Vec<&TrimCurve>> = found
        .iter()
        .map(|(u, o)| match u {
            PcurveUse::Used(c) => std::iter::once(c).chain(o.iter()).collect(),
            _ => Vec::new(),
        })
        .collect();
    let Some(first) = cands.iter().position(|c| c.len() > 1) else {
        return cands.iter().map(|c| (!c.is_empty()).then_some(0)).collect();
    };
    let ends = |c: &TrimCurve| {
        let [a, b] = c.domain();
        (c.eval(a), c.eval(b))
    };
    let gap = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
    let mut best: Option<(f64, Vec<Option<usize>>)> = None;
    for start in 0..cands[first].len() {
        let mut pick: Vec<Option<usize>> = vec![None; n];
        pick[first] = Some(start);
        let mut prev_end = Some(ends(cands[first][start]).1);
        for step in 1..n {
            let k = (first + step) % n;
            let c = &cands[k];
            if c.is_empty() {
                prev_end = None;
                continue;
            }
            let j = match prev_end {
                Some(p) if c.len() > 1 => (0..c.len())
                    .min_by(|&x, &y| gap(p, ends(c[x]).0).total_cmp(&gap(p, ends(c[y]).0)))
                    .unwrap_or(0),
                _ => 0,
            };
            pick[k] = Some(j);
            prev_end = Some(ends(c[j]).1);
        }
        let mut total = 0.0;
        for k in 0..n {
            let next = (k + 1) % n;
            if let (Some(a), Some(b)) = (pick[k], pick[next]) {
                total += gap(ends(cands[k][a]).1, ends(cands[next][b]).0);
            }
        }
        if best.as_ref().is_none_or(|b| total < b.0) {
            best = Some((total, pick));
        }
    }
    best.map(|b| b.1).unwrap_or_else(|| vec![None; n])
}

impl<'a> Reader<'a> {
    pub(super) fn face(&self, f: &'a Instance) -> R<StepSurface> {
        let p = self.params(f, &["ADVANCED_FACE", "FACE_SURFACE"])?;
        let bounds = self.refs(f, self.list(f, p, 1)?)?;
        let si = self.refer(f, p, 2)?;
        let same_sense = self.flag(f, p, 3)?;
        let mut loops: Vec<(bool, Vec<EdgeUse>)> = Vec::new();
        for b in bounds {
            if let Some(l) = self.bound_edges(b)? {
                loops.push(l);
            }
        }
        // The outer bound first (FACE_OUTER_BOUND, else decided later by area).
        loops.sort_by_key(|l| !l.0);
        let surface = if si.is("B_SPLINE_SURFACE_WITH_KNOTS") {
            let s = self.bspline_surface(si)?;
            let trims = loops
                .iter()
                .map(|(_, edges)| self.bspline_loop(&s, si.id, edges))
                .collect::<R<Vec<_>>>()?;
            self.attach(f, s, trims, loops.first().is_some_and(|l| l.0))?
        } else if let Some(s) = self.offset_of_bspline(si)? {
            // on the basis's parameters: its p-curves trim the offset
            let trims = loops
                .iter()
                .map(|(_, edges)| self.bspline_loop(&s, si.id, edges))
                .collect::<R<Vec<_>>>()?;
            self.attach(f, s, trims, loops.first().is_some_and(|l| l.0))?
        } else {
            self.analytic_face(f, si, &loops, same_sense)?
        };
        Ok(StepSurface {
            surface,
            entity: f.id,
            surface_entity: si.id,
            surface_type: si.type_name().to_string(),
            same_sense,
        })
    }

    /// Attaches loops; when no loop was marked outer, the one enclosing the
    /// largest parameter area goes first.
    pub(super) fn attach(
        &self,
        f: &Instance,
        s: BSplineSurface,
        mut trims: Vec<TrimLoop>,
        outer_known: bool,
    ) -> R<BSplineSurface> {
        if trims.is_empty() {
            return Ok(s);
        }
        if !outer_known && trims.len() > 1 {
            let area = |l: &TrimLoop| {
                let mut pts = Vec::new();
                for c in &l.curves {
                    c.flatten_into(1e-6, &mut pts);
                }
                crate::bspline::polygon_signed_area2(&pts).abs()
            };
            let k = (0..trims.len())
                .max_by(|&a, &b| area(&trims[a]).total_cmp(&area(&trims[b])))
                .unwrap_or(0);
            trims.swap(0, k);
        }
        s.with_trims(trims).map_err(|e| self.err(f, e.to_string()))
    }

    /// A loop on a B-spline surface: p-curves on it when the edges have
    /// them, else the edge points projected onto the surface.
    ///
    /// A seam edge (a SEAM_CURVE with two p-curves that both agree with
    /// the edge, as on a surface closed in u or v) takes the p-curve that
    /// continues the loop: the choice that leaves the smallest total gap
    /// between consecutive curves' ends and starts, so that a seam used
    /// twice runs once along each side of the parameter domain.
    fn bspline_loop(&self, s: &BSplineSurface, sid: u64, edges: &[EdgeUse]) -> R<TrimLoop> {
        let mut curves = Vec::with_capacity(edges.len());
        let mut guess = None;
        let mut found = Vec::with_capacity(edges.len());
        for e in edges {
            found.push(self.pcurve_trims(s, sid, e, &PcurveMap::IDENTITY, None, true)?);
        }
        let choice = seam_choice(&found);
        for ((e, (use_, others)), pick) in edges.iter().zip(found).zip(choice) {
            let use_ = match (use_, pick) {
                // the choice indexes the alternatives (0: the first p-curve)
                (PcurveUse::Used(first), Some(k)) if k > 0 => {
                    PcurveUse::Used(others.into_iter().nth(k - 1).unwrap_or(first))
                }
                (u, _) => u,
            };
            if let Some(c) = self.count_trim(e, use_) {
                curves.push(c);
                continue;
            }
            let pts: Vec<[f64; 2]> = self
                .edge_points(e)
                .into_iter()
                .map(|q| {
                    let uv = invert_point(s, q, guess);
                    guess = Some(uv);
                    [uv.0, uv.1]
                })
                .collect();
            curves.push(polyline(&pts).map_err(|m| self.err(&self.ex.instances[&e.edge], m))?);
        }
        Ok(TrimLoop { curves })
    }

    /// Counts where an edge's trim curve came from and returns the
    /// p-curve's when it is used.
    pub(super) fn count_trim(&self, e: &EdgeUse, found: PcurveUse) -> Option<TrimCurve> {
        let mut n = self.sources.get();
        let out = match found {
            PcurveUse::Used(c) => {
                n.pcurve += 1;
                Some(c)
            }
            PcurveUse::Absent => {
                n.edge += 1;
                None
            }
            PcurveUse::Rejected {
                distance,
                tolerance,
            } => {
                n.pcurve_rejected += 1;
                self.rejected
                    .borrow_mut()
                    .push((e.edge, distance, tolerance));
                None
            }
        };
        self.sources.set(n);
        out
    }

    /// Counts edges whose trims come from the 3-D edges without looking
    /// at p-curves.
    pub(super) fn count_edges(&self, edges: usize) {
        let mut n = self.sources.get();
        n.edge += edges;
        self.sources.set(n);
    }
}
