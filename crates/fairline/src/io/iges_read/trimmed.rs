//! Trimmed surfaces (entity 144): which surfaces are trimmed, and the
//! trimming loops of each, by the base surface's directory entry.

use super::params::{INT, Param, param, parse_int, text_of};
use super::records::Iges;
use super::revolution::Revolved;
use super::{Conversions, IgesError, IgesSurface, brep, faces, surfaces};
use crate::bspline::{BSplineSurface, TrimLoop};
use crate::io::unreadable::Unreadable;

/// The trimming loops of a base surface and the DE of their 144.
type LoopsOf = Vec<Option<(usize, Vec<TrimLoop>)>>;

impl Iges<'_> {
    /// Which directory entries are the base surface of a trimmed (144) or
    /// bounded (143) surface.
    pub(super) fn trimmed_bases(&self) -> Vec<bool> {
        let mut trimmed = vec![false; self.dir.len()];
        for k in 0..self.dir.len() {
            let slot = match self.dir[k].entity_type {
                144 => 1,
                143 => 2,
                _ => continue,
            };
            let Ok(p) = self.parameters(k) else { continue };
            if let Some(t) = text_of(&p, slot)
                .and_then(parse_int)
                .and_then(|de| self.entry(de))
            {
                trimmed[t] = true;
            }
        }
        trimmed
    }

    /// The trimming loops of every 144, by the directory entry of its base
    /// surface (loops of a surface of revolution mapped into its NURBS
    /// parameters); planes (108) trimmed by a 144 become bounded NURBS
    /// planes with their loops ([`Iges::plane_face`]). A 144 whose base
    /// surface was not read, or whose boundaries cannot be read, is counted
    /// in `skipped` and listed in [`Faces::unreadable`] when that is for
    /// something fairline does not read; errors of the file's data fail.
    pub(super) fn trimming_loops(
        &self,
        bsplines: &[Option<IgesSurface>],
        revolved: &[Option<Revolved>],
        conv: &Conversions,
        skipped: &mut usize,
    ) -> Result<Faces, IgesError> {
        let n = self.dir.len();
        let mut f = Faces {
            loops: vec![None; n],
            planes: vec![None; n],
            unreadable: Vec::new(),
            translated: Vec::new(),
            bounded_failed: vec![None; n],
        };
        for k in 0..n {
            if self.dir[k].entity_type != 144 {
                continue;
            }
            let p = self.parameters(k)?;
            let line = p.first().map_or(self.dir[k].line, |t| t.1);
            let base = param(self, k, &p, 1, line, &INT)?;
            let Some(b) = self.entry(base) else {
                return Err(self.entity_error(
                    k,
                    line,
                    format!("surface pointer {base} is not a directory entry"),
                ));
            };
            // a converted surface whose boundaries are all given in its
            // parameters, mapped exactly
            let mapped = conv.surfaces[b]
                .as_ref()
                .and_then(|c| c.axes.map(|a| (c, a)))
                .filter(|_| self.boundaries_in_parameter_space(&p, line));
            let loops: Result<Option<Vec<TrimLoop>>, IgesError> =
                match (&bsplines[b], &revolved[b], mapped) {
                    (Some(s), _, _) => {
                        let s = &s.surface;
                        read_entity_144(self, k, s, (s.domain_u(), s.domain_v()), &p, line)
                    }
                    (_, _, Some((c, axes))) => {
                        let r = c.file_range();
                        let domain = ([r[0], r[1]], [r[2], r[3]]);
                        read_entity_144(self, k, &c.surface, domain, &p, line).and_then(|loops| {
                            loops
                                .map(|loops| {
                                    loops
                                        .into_iter()
                                        .map(|l| surfaces::map_loop(l, &axes, &c.surface))
                                        .collect::<Result<Vec<_>, String>>()
                                        .map_err(|m| self.entity_error(k, line, m))
                                })
                                .transpose()
                        })
                    }
                    (_, Some(r), _) => {
                        let domain = (r.surface.domain_u(), r.angles);
                        read_entity_144(self, k, &r.surface, domain, &p, line).and_then(|loops| {
                            loops
                                .map(|loops| {
                                    loops
                                        .iter()
                                        .map(|l| r.map_loop(l))
                                        .collect::<Result<Vec<_>, String>>()
                                        .map_err(|m| self.entity_error(k, line, m))
                                })
                                .transpose()
                        })
                    }
                    _ if self.dir[b].entity_type == 108 => match self.plane_face(k, b, &p, line) {
                        Ok(s) => {
                            f.planes[b] = Some(s);
                            continue;
                        }
                        Err(e) => Err(e),
                    },
                    // read with its base surface through the STEP reader's
                    // topology ([`brep`]): any surface that converts exactly
                    _ if brep::TRANSLATED_SURFACES.contains(&self.dir[b].entity_type) => {
                        f.translated.push(k);
                        continue;
                    }
                    _ => Ok(None),
                };
            match loops {
                Ok(Some(loops)) => {
                    let loops = loops.into_iter().map(faces::chained).collect();
                    f.loops[b] = Some((2 * k + 1, loops));
                }
                Err(e) if !matches!(e, IgesError::Unsupported { .. }) => return Err(e),
                other => {
                    *skipped += 1;
                    let reason = match other {
                        Err(e) => e.to_string(),
                        _ if bsplines[b].is_some() || revolved[b].is_some() => {
                            "a boundary (142) has neither a parameter-space nor a model-space curve"
                                .into()
                        }
                        _ => match &conv.failed[b] {
                            Some(m) => {
                                format!("its base surface, {}: {m}", self.describe_entity(b))
                            }
                            None => self.why_not_read(b),
                        },
                    };
                    let estimated_area = bsplines[b]
                        .as_ref()
                        .map(|s| &s.surface)
                        .or(revolved[b].as_ref().map(|r| &r.surface))
                        .or(conv.surfaces[b].as_ref().map(|c| &c.surface))
                        .map(|s| crate::bspline::trimmed_area(s, 16, 16));
                    f.unreadable.push(Unreadable {
                        entity: self.describe_entity(k),
                        reason,
                        estimated_area,
                    });
                }
            }
        }
        Ok(f)
    }
}

/// The faces [`Iges::trimming_loops`] found, by directory entry of the
/// base surface.
pub(super) struct Faces {
    /// Loops of 144s on 128 and 120 bases, and the 144's DE.
    pub(super) loops: LoopsOf,
    /// Trimmed planes (144 on 108), complete.
    pub(super) planes: Vec<Option<IgesSurface>>,
    /// The faces that could not be read.
    pub(super) unreadable: Vec<Unreadable>,
    /// 144s on other surfaces, read with the B-rep faces ([`brep`]).
    pub(super) translated: Vec<usize>,
    /// Why a bounded surface (143) was not read, by its directory entry.
    pub(super) bounded_failed: Vec<Option<String>>,
}

/// Entity 144, trimmed parametric surface (IGES 5.3 §4.34): `PTS N1 N2 PTO
/// PTI1..PTIN2`. `N1 = 0` means the outer boundary is the boundary of the
/// surface's domain. Each boundary is an entity 142 read by
/// [`Iges::boundary_loop`].
///
/// `surface` is the base surface (for boundaries given only in model space,
/// or whose parameter-space curves leave `domain`, which are projected onto
/// it) and `domain` its parameter range as the file's parameter-space
/// curves see it.
fn read_entity_144(
    g: &Iges<'_>,
    k: usize,
    surface: &BSplineSurface,
    domain: ([f64; 2], [f64; 2]),
    p: &[(Param, usize)],
    line: usize,
) -> Result<Option<Vec<TrimLoop>>, IgesError> {
    let n1 = param(g, k, p, 2, line, &INT)?;
    let n2 = param(g, k, p, 3, line, &INT)?;
    let holes = usize::try_from(n2)
        .ok()
        .filter(|&n| n < p.len())
        .ok_or_else(|| g.entity_error(k, line, format!("N2 = {n2} inner boundaries")))?;
    let mut loops = Vec::with_capacity(holes + 1);
    if n1 == 0 {
        let (u, v) = domain;
        loops.push(
            TrimLoop::polygon(&[[u[0], v[0]], [u[1], v[0]], [u[1], v[1]], [u[0], v[1]]])
                .map_err(|m| g.entity_error(k, line, m))?,
        );
    } else {
        let Some(outer) =
            g.boundary_loop(k, param(g, k, p, 4, line, &INT)?, line, surface, domain)?
        else {
            return Ok(None);
        };
        loops.push(outer);
    }
    for h in 0..holes {
        let Some(hole) =
            g.boundary_loop(k, param(g, k, p, 5 + h, line, &INT)?, line, surface, domain)?
        else {
            return Ok(None);
        };
        loops.push(hole);
    }
    Ok(Some(loops))
}
