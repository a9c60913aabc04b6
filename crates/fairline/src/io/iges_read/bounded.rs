//! Bounded surfaces (entity 143) read as trimmed surfaces.

use super::{
    Conversions, Iges, IgesError, IgesSurface, Param, Revolved, TrimLoop, boundary::Piece,
    boundary::project_boundary, faces, faces::PlaneLoop, params::INT, params::param, surfaces,
    trimmed::Faces,
};
use crate::bspline::BSplineSurface;

impl Iges<'_> {
    /// Every bounded surface (143, IGES 5.3 §4.33: `TYPE SPTR N BDPT1..N`)
    /// on a surface that was read (128, 120, or one converted) becomes the
    /// trimming loops of that surface: the first boundary (141) is the
    /// outer one, the others holes. A boundary entity (141, IGES 5.3 §4.31:
    /// `TYPE PREF SPTR N`, then per curve `CRVPT SENSE K PSCPT1..K`) is read
    /// from its parameter-space curves where the 143 and 141 have them
    /// (`TYPE = 1`, every curve with `K ≥ 1`) and the surface's file
    /// parameters map exactly to the B-spline's; otherwise its model-space
    /// curves (`CRVPT`) are projected onto the surface ([`project_boundary`]).
    /// A curve with `SENSE = 2` is used reversed. A bounded surface that
    /// cannot be read is given a reason in [`Faces::bounded_failed`].
    pub(super) fn bounded_surfaces(
        &self,
        bsplines: &[Option<IgesSurface>],
        revolved: &[Option<Revolved>],
        conv: &Conversions,
        f: &mut Faces,
    ) -> Result<(), IgesError> {
        for k in 0..self.dir.len() {
            if self.dir[k].entity_type != 143 {
                continue;
            }
            let p = self.parameters(k)?;
            let line = p.first().map_or(self.dir[k].line, |t| t.1);
            let base = param(self, k, &p, 2, line, &INT)?;
            let Some(b) = self.entry(base) else {
                return Err(self.entity_error(
                    k,
                    line,
                    format!("surface pointer {base} is not a directory entry"),
                ));
            };
            if self.dir[b].entity_type == 108 {
                if f.planes[b].is_some() || f.loops[b].is_some() {
                    f.bounded_failed[k] = Some(format!(
                        "its base surface {} is trimmed by another entity",
                        self.describe_entity(b)
                    ));
                    continue;
                }
                match self.bounded_plane(k, b, &p, line) {
                    Ok(s) => f.planes[b] = Some(s),
                    Err(e @ IgesError::Unsupported { .. }) => {
                        f.bounded_failed[k] = Some(e.to_string())
                    }
                    Err(e) => return Err(e),
                }
                continue;
            }
            // on an analytic surface (190–198): read with its base surface
            // through the STEP reader's topology, as a 144 there
            if (190..=198).contains(&self.dir[b].entity_type) {
                f.translated.push(k);
                continue;
            }
            type Map<'a> = Box<dyn Fn(TrimLoop) -> Result<TrimLoop, String> + 'a>;
            let (surface, map): (&BSplineSurface, Option<Map<'_>>) = match (
                &bsplines[b],
                &revolved[b],
                &conv.surfaces[b],
            ) {
                (Some(s), _, _) => (&s.surface, Some(Box::new(Ok))),
                (_, Some(r), _) => (&r.surface, Some(Box::new(|l| r.map_loop(&l)))),
                (_, _, Some(c)) => (
                    &c.surface,
                    c.axes.map(|axes| -> Map<'_> {
                        Box::new(move |l| surfaces::map_loop(l, &axes, &c.surface))
                    }),
                ),
                _ => {
                    f.bounded_failed[k] = Some(match &conv.failed[b] {
                        Some(m) => format!("its base surface, {}: {m}", self.describe_entity(b)),
                        None => format!(
                            "a bounded surface (143) on {}: fairline reads them on 108, 114, 118, 120, 122, 128, 140 and 190–198",
                            self.describe_entity(b)
                        ),
                    });
                    continue;
                }
            };
            if f.loops[b].is_some() {
                f.bounded_failed[k] = Some(format!(
                    "its base surface {} is trimmed by another entity",
                    self.describe_entity(b)
                ));
                continue;
            }
            let with_pcurves = param(self, k, &p, 1, line, &INT)? == 1;
            let boundaries = self.boundaries_143(k, &p, line)?;
            let mut loops = Vec::with_capacity(boundaries.len());
            let mut failed = None;
            for bk in boundaries {
                match self.boundary_141(bk, surface, with_pcurves, map.as_deref()) {
                    Ok(l) => loops.push(faces::chained(l)),
                    Err(e @ IgesError::Unsupported { .. }) => {
                        failed = Some(e.to_string());
                        break;
                    }
                    Err(e) => return Err(e),
                }
            }
            match failed {
                Some(reason) => f.bounded_failed[k] = Some(reason),
                None => f.loops[b] = Some((2 * k + 1, loops)),
            }
        }
        Ok(())
    }

    /// One boundary entity (141) as a loop in the B-spline's parameters.
    fn boundary_141(
        &self,
        k: usize,
        surface: &BSplineSurface,
        with_pcurves: bool,
        map: Option<&dyn Fn(TrimLoop) -> Result<TrimLoop, String>>,
    ) -> Result<TrimLoop, IgesError> {
        let curves = self.curves_141(k, with_pcurves && map.is_some())?;
        if let (Some(pieces), Some(map)) = (curves.parameter, map) {
            let trims = pieces
                .iter()
                .map(Piece::to_trim)
                .collect::<Result<Vec<_>, _>>()
                .map_err(|m| self.entity_error(k, curves.line, m))?;
            return map(TrimLoop { curves: trims })
                .map_err(|m| self.entity_error(k, curves.line, m));
        }
        project_boundary(surface, &curves.model).map_err(|m| self.entity_error(k, curves.line, m))
    }

    /// The curves of the boundary entity (141) `k` (IGES 5.3 §4.31: `TYPE
    /// PREF SPTR N`, then per curve `CRVPT SENSE K PSCPT1..K`), each
    /// reversed where `SENSE = 2`: the model-space ones, and the
    /// parameter-space ones when `want_parameter` and the entity has them
    /// for every curve (`TYPE = 1`, `K ≥ 1`).
    pub(super) fn curves_141(
        &self,
        k: usize,
        want_parameter: bool,
    ) -> Result<Curves141, IgesError> {
        let p = self.parameters(k)?;
        let line = p.first().map_or(self.dir[k].line, |t| t.1);
        let pcurves = want_parameter && param(self, k, &p, 1, line, &INT)? == 1;
        let n = param(self, k, &p, 4, line, &INT)?;
        let n = usize::try_from(n)
            .ok()
            .filter(|&n| n >= 1 && n < p.len())
            .ok_or_else(|| self.entity_error(k, line, format!("{n} curves")))?;
        let mut model = Vec::new();
        let mut params: Option<Vec<Piece>> = pcurves.then(Vec::new);
        let mut at = 5;
        for _ in 0..n {
            let crv = param(self, k, &p, at, line, &INT)?;
            let reversed = param(self, k, &p, at + 1, line, &INT)? == 2;
            let count = param(self, k, &p, at + 2, line, &INT)?;
            let count = usize::try_from(count)
                .ok()
                .filter(|&c| c < p.len())
                .ok_or_else(|| {
                    self.entity_error(k, line, format!("{count} parameter-space curves"))
                })?;
            let c = self.entry(crv).ok_or_else(|| {
                self.entity_error(
                    k,
                    line,
                    format!("curve pointer {crv} is not a directory entry"),
                )
            })?;
            let mut pieces = Vec::new();
            self.curve_pieces(c, 0, &mut pieces)?;
            push_oriented(&mut model, pieces, reversed);
            if count == 0 {
                params = None;
            }
            for j in 0..count {
                let pc = param(self, k, &p, at + 3 + j, line, &INT)?;
                if let Some(out) = params.as_mut() {
                    let c = self.entry(pc).ok_or_else(|| {
                        self.entity_error(
                            k,
                            line,
                            format!("curve pointer {pc} is not a directory entry"),
                        )
                    })?;
                    let mut pieces = Vec::new();
                    self.curve_pieces(c, 0, &mut pieces)?;
                    push_oriented(out, pieces, reversed);
                }
            }
            at += 3 + count;
        }
        Ok(Curves141 {
            line,
            model,
            parameter: params,
        })
    }

    /// The boundary entities (141) of the bounded surface (143) `k`
    /// (parameters `p`: `TYPE SPTR N BDPT1..N`), by directory index, the
    /// outer one first.
    pub(super) fn boundaries_143(
        &self,
        k: usize,
        p: &[(Param, usize)],
        line: usize,
    ) -> Result<Vec<usize>, IgesError> {
        let n = param(self, k, p, 3, line, &INT)?;
        let n = usize::try_from(n)
            .ok()
            .filter(|&n| n >= 1 && n < p.len())
            .ok_or_else(|| self.entity_error(k, line, format!("{n} boundaries")))?;
        (0..n)
            .map(|i| {
                let de = param(self, k, p, 4 + i, line, &INT)?;
                self.entry(de)
                    .filter(|&j| self.dir[j].entity_type == 141)
                    .ok_or_else(|| {
                        self.entity_error(k, line, format!("boundary {de} is not an entity 141"))
                    })
            })
            .collect()
    }

    /// A plane (108) bounded by the 143 `k` (parameters `p`): its
    /// boundaries' model-space curves are its loops ([`Iges::plane_patch`]).
    fn bounded_plane(
        &self,
        k: usize,
        b: usize,
        p: &[(Param, usize)],
        line: usize,
    ) -> Result<IgesSurface, IgesError> {
        let boundaries = self.boundaries_143(k, p, line)?;
        let mut loops = Vec::with_capacity(boundaries.len());
        for bk in boundaries {
            let curves = self.curves_141(bk, false)?;
            loops.push(PlaneLoop {
                entity: bk,
                line: curves.line,
                pieces: curves.model,
            });
        }
        self.plane_patch(k, line, b, &loops)
    }
}

/// The curves of a boundary entity (141) along its loop.
pub(super) struct Curves141 {
    /// The entity's line, for messages.
    pub(super) line: usize,
    /// Model-space curves.
    pub(super) model: Vec<Piece>,
    /// Parameter-space curves, where asked for and given for every curve.
    pub(super) parameter: Option<Vec<Piece>>,
}

/// Appends a curve's pieces, in reverse order and each reversed when
/// `reversed`.
fn push_oriented(out: &mut Vec<Piece>, pieces: Vec<Piece>, reversed: bool) {
    if !reversed {
        out.extend(pieces);
        return;
    }
    for piece in pieces.into_iter().rev() {
        let r = piece.nurbs().reversed();
        out.push(Piece {
            degree: r.degree,
            knots: r.knots,
            points: r.points,
            weights: r.weights,
        });
    }
}
