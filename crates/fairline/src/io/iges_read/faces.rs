//! Faces of an IGES file beyond the B-spline surface: trimmed planes
//! (entity 108 under a 144) and the census of faces that cannot be read.

use super::{
    Faces, INT, Iges, IgesError, IgesSurface, Param, REAL, Revolved, TrimCurve, TrimLoop,
    Unreadable, Vec3, param,
};
use crate::bspline::BSplineSurface;

/// Surface entity types that make a face when they are independent
/// (subordinate switch 0) and not the base of a trimmed or bounded surface.
const SURFACE_TYPES: [i64; 12] = [108, 114, 118, 120, 122, 128, 140, 190, 192, 194, 196, 198];

impl Iges<'_> {
    /// `entity T (DE n, line l)` for messages.
    pub(super) fn describe_entity(&self, k: usize) -> String {
        format!(
            "entity {} (DE {}, line {})",
            self.dir[k].entity_type,
            2 * k + 1,
            self.dir[k].line
        )
    }

    /// Why the base surface `b` of a trimmed surface was not read.
    pub(super) fn why_not_read(&self, b: usize) -> String {
        match self.dir[b].entity_type {
            120 => format!(
                "its surface of revolution ({}) has a generatrix fairline does not read (it reads a line 110, a circular arc 100 or a B-spline curve 126)",
                self.describe_entity(b)
            ),
            t => format!(
                "its base surface is {}; fairline reads trimmed surfaces on 128, 120 and 108, not on entity {t}",
                self.describe_entity(b)
            ),
        }
    }

    /// Lists the faces no trimmed surface (144) covers that cannot be
    /// read: bounded surfaces (143, their base left out), B-rep faces
    /// (510), independent surface entities of a type fairline does not read
    /// and surfaces of revolution whose generatrix it does not read.
    pub(super) fn untrimmed_faces(
        &self,
        bsplines: &[Option<IgesSurface>],
        revolved: &[Option<Revolved>],
        trimmed: &[bool],
        faces: &mut Faces,
    ) {
        for k in 0..self.dir.len() {
            let e = &self.dir[k];
            let independent = (e.status / 10_000) % 100 == 0;
            let reason = match e.entity_type {
                143 => {
                    let base = self
                        .parameters(k)
                        .ok()
                        .and_then(|p| super::text_of(&p, 2).and_then(super::parse_int))
                        .and_then(|de| self.entry(de));
                    let mut area = None;
                    if let Some(b) = base {
                        faces.dropped[b] = true;
                        area = bsplines[b]
                            .as_ref()
                            .map(|s| &s.surface)
                            .or(revolved[b].as_ref().map(|r| &r.surface))
                            .map(|s| crate::bspline::trimmed_area(s, 16, 16));
                    }
                    faces.unreadable.push(Unreadable {
                        entity: self.describe_entity(k),
                        reason: "a bounded surface (143): its model-space boundaries (141) are not read".into(),
                        estimated_area: area,
                    });
                    continue;
                }
                510 => "a B-rep face (510): the B-rep entities (186, 514, 510, 508, 504, 502) are not read; write the file with trimmed surfaces (144), e.g. OpenCASCADE's write.iges.brep.mode = Faces".to_string(),
                120 if independent && !trimmed[k] && revolved[k].is_none() => {
                    "a surface of revolution whose generatrix fairline does not read (it reads a line 110, a circular arc 100 or a B-spline curve 126)".into()
                }
                t if independent
                    && !trimmed[k]
                    && SURFACE_TYPES.contains(&t)
                    && !matches!(t, 120 | 128)
                    && !(t == 108 && e.form == 0) =>
                {
                    format!("surface entity {t} is not read on its own (only under a trimmed surface 144, for 108)")
                }
                _ => continue,
            };
            faces.unreadable.push(Unreadable {
                entity: self.describe_entity(k),
                reason,
                estimated_area: None,
            });
        }
    }

    /// A plane (entity 108, IGES 5.3 §4.12: `A B C D`, the plane `Ax + By +
    /// Cz = D`) trimmed by the 144 `k`: a bilinear NURBS patch whose
    /// parameters are Cartesian coordinates in the plane (origin the foot
    /// of the perpendicular from the model origin, axes `x̂ × n`-based
    /// right-handed with the plane's normal `(A, B, C)`), spanning the
    /// control points of the boundaries. The boundaries are the 142s'
    /// model-space curves (`CPTR`; a plane has no parameter space in IGES),
    /// mapped into the plane's coordinates by its affine frame: exact, as
    /// rational B-splines are invariant under affine maps.
    pub(super) fn plane_face(
        &self,
        k: usize,
        b: usize,
        p: &[(Param, usize)],
        line: usize,
    ) -> Result<IgesSurface, IgesError> {
        let pb = self.parameters(b)?;
        let lb = pb.first().map_or(self.dir[b].line, |t| t.1);
        let mut c = [0.0; 4];
        for (i, v) in c.iter_mut().enumerate() {
            *v = param(self, b, &pb, i + 1, lb, &REAL)?;
        }
        let n = Vec3::new(c[0], c[1], c[2]);
        let len = n.length();
        if !(len > 0.0 && len.is_finite()) {
            return Err(self.entity_error(b, lb, "the plane's normal (A, B, C) is zero".into()));
        }
        let mut normal = n / len;
        let mut origin = normal * (c[3] / len);
        let helper = if normal.x.abs() < 0.9 {
            Vec3::X
        } else {
            Vec3::Y
        };
        let mut ex = helper.cross(normal).normalize();
        if self.dir[b].transform != 0 {
            let t = self.entry(self.dir[b].transform).ok_or_else(|| {
                self.entity_error(
                    b,
                    lb,
                    "the transformation pointer is not a directory entry".into(),
                )
            })?;
            let m = self.transform(t, 0)?;
            origin = m.transform_point3(origin);
            normal = m.transform_vector3(normal).normalize();
            ex = m.transform_vector3(ex);
            ex = (ex - normal * ex.dot(normal)).normalize();
        }
        let ey = normal.cross(ex);
        let n1 = param(self, k, p, 2, line, &INT)?;
        let n2 = param(self, k, p, 3, line, &INT)?;
        if n1 == 0 {
            return Err(self.entity_error(
                k,
                line,
                "a plane (108) trimmed without an outer boundary (N1 = 0) has no extent".into(),
            ));
        }
        let holes = usize::try_from(n2)
            .ok()
            .filter(|&h| h < p.len())
            .ok_or_else(|| self.entity_error(k, line, format!("N2 = {n2} inner boundaries")))?;
        let mut loops = Vec::with_capacity(holes + 1);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for slot in 4..5 + holes {
            let de = param(self, k, p, slot, line, &INT)?;
            let b142 = self.entry(de).filter(|&j| self.dir[j].entity_type == 142);
            let Some(j) = b142 else {
                return Err(self.entity_error(
                    k,
                    line,
                    format!("boundary {de} is not an entity 142"),
                ));
            };
            let pj = self.parameters(j)?;
            let lj = pj.first().map_or(self.dir[j].line, |t| t.1);
            let cptr = param(self, j, &pj, 4, lj, &INT)?;
            let curve = self.entry(cptr).ok_or_else(|| {
                self.entity_error(
                    j,
                    lj,
                    format!("a boundary of a plane needs its model-space curve (CPTR = {cptr})"),
                )
            })?;
            let mut pieces = Vec::new();
            self.curve_pieces(curve, 0, &mut pieces)?;
            let size = pieces
                .iter()
                .flat_map(|q| q.points.iter())
                .map(|q| (*q - origin).length())
                .fold(1.0_f64, f64::max);
            let mut curves = Vec::with_capacity(pieces.len());
            for piece in &pieces {
                let mut uv = Vec::with_capacity(piece.points.len());
                for q in &piece.points {
                    let d = *q - origin;
                    let off = d.dot(normal);
                    if off.abs() > 1e-7 * size {
                        return Err(self.entity_error(
                            j,
                            lj,
                            format!("the boundary curve leaves the plane by {off:.3e}"),
                        ));
                    }
                    let (u, v) = (d.dot(ex), d.dot(ey));
                    lo = [lo[0].min(u), lo[1].min(v)];
                    hi = [hi[0].max(u), hi[1].max(v)];
                    uv.push([u, v]);
                }
                curves.push(
                    TrimCurve::new(piece.degree, piece.knots.clone(), uv, piece.weights.clone())
                        .map_err(|m| self.entity_error(j, lj, m))?,
                );
            }
            if curves.is_empty() {
                return Err(self.entity_error(j, lj, "the boundary curve is empty".into()));
            }
            loops.push(TrimLoop { curves });
        }
        // a margin so that no boundary runs along the patch's own edge
        let pad = 1e-3 * (hi[0] - lo[0]).max(hi[1] - lo[1]).max(f64::MIN_POSITIVE);
        let (u0, u1, v0, v1) = (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad);
        if !(u1 > u0 && v1 > v0 && (u1 - u0).is_finite() && (v1 - v0).is_finite()) {
            return Err(self.entity_error(k, line, "the plane's boundary has no area".into()));
        }
        let at = |u: f64, v: f64| origin + u * ex + v * ey;
        let mut surface = BSplineSurface::from_flat(
            1,
            1,
            vec![u0, u0, u1, u1],
            vec![v0, v0, v1, v1],
            [2, 2],
            vec![at(u0, v0), at(u0, v1), at(u1, v0), at(u1, v1)],
            None,
        )
        .map_err(|source| IgesError::Surface {
            entity: 2 * b + 1,
            line: lb,
            source,
        })?;
        surface
            .set_trims(loops)
            .map_err(|e| self.entity_error(k, line, e.to_string()))?;
        Ok(IgesSurface {
            surface,
            directory_entry: 2 * b + 1,
            entity_type: 108,
            form: self.dir[b].form,
            rational: false,
            closed: [false, false],
            periodic: [false, false],
            parameter_range: [u0, u1, v0, v1],
            transformed: self.dir[b].transform != 0,
            trimmed: true,
            trim_entity: Some(2 * k + 1),
        })
    }
}

/// A boundary whose curves do not follow each other end to start (a
/// composite curve listing a seam's two sides in the order of the edges'
/// uses rather than along the loop) reordered into a chain: from the first
/// curve, each next curve is the unused one starting nearest the current
/// end. The order is kept unless the chain's total gap between ends and
/// starts is less than half the given order's (gaps that the file means,
/// such as degenerate edges at a pole it leaves out, stay).
pub(super) fn chained(l: TrimLoop) -> TrimLoop {
    let n = l.curves.len();
    if n < 3 {
        return l;
    }
    let ends: Vec<([f64; 2], [f64; 2])> = l
        .curves
        .iter()
        .map(|c| {
            let [a, b] = c.domain();
            (c.eval(a), c.eval(b))
        })
        .collect();
    let gap = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
    let total = |order: &[usize]| -> f64 {
        (0..n)
            .map(|k| gap(ends[order[k]].1, ends[order[(k + 1) % n]].0))
            .sum()
    };
    let given: Vec<usize> = (0..n).collect();
    let mut order = vec![0];
    let mut used = vec![false; n];
    used[0] = true;
    for _ in 1..n {
        let end = ends[*order.last().unwrap_or(&0)].1;
        let next = (0..n)
            .filter(|&j| !used[j])
            .min_by(|&a, &b| gap(end, ends[a].0).total_cmp(&gap(end, ends[b].0)));
        let Some(j) = next else { break };
        used[j] = true;
        order.push(j);
    }
    if order.len() == n && total(&order) < 0.5 * total(&given) {
        let mut curves: Vec<Option<TrimCurve>> = l.curves.into_iter().map(Some).collect();
        TrimLoop {
            curves: order.iter().filter_map(|&k| curves[k].take()).collect(),
        }
    } else {
        l
    }
}

#[cfg(test)]
mod tests {
    use super::super::parse_iges;
    use super::super::tests::{GLOBAL, iges_file};
    use crate::bspline::trimmed_area;
    use std::f64::consts::{FRAC_PI_2, PI, TAU};

    #[test]
    fn iges_trimmed_plane_with_a_hole_is_exact_and_unread_faces_are_listed() {
        let entities = [
            (108, 0, 0, "108,0.,0.,1.,0.,0,0.,0.,0.,0.;"),
            (110, 0, 0, "110,0.,0.,0.,10.,0.,0.;"),
            (110, 0, 0, "110,10.,0.,0.,10.,5.,0.;"),
            (110, 0, 0, "110,10.,5.,0.,0.,5.,0.;"),
            (110, 0, 0, "110,0.,5.,0.,0.,0.,0.;"),
            (102, 0, 0, "102,4,3,5,7,9;"),
            (142, 0, 0, "142,0,1,0,11,2;"),
            (100, 0, 0, "100,0.,5.,2.5,6.,2.5,6.,2.5;"),
            (142, 0, 0, "142,0,1,0,15,2;"),
            (144, 0, 0, "144,1,1,1,13,17;"),
            // a trimmed tabulated cylinder (122) and a B-rep face (510):
            // not read, listed
            (122, 0, 0, "122,3,0.,0.,1.;"),
            (144, 0, 0, "144,21,1,0,13;"),
            (510, 0, 1, "510,1,1,0;"),
        ];
        let imp = parse_iges(&iges_file(GLOBAL, &entities)).unwrap();
        assert_eq!(imp.surfaces.len(), 1);
        let plane = &imp.surfaces[0];
        assert_eq!((plane.entity_type, plane.trim_entity), (108, Some(19)));
        let area = trimmed_area(&plane.surface, 64, 64);
        let want = 50.0 - PI;
        assert!((area - want).abs() <= 1e-6 * want, "{area} vs {want}");
        let names: Vec<&str> = imp.unreadable.iter().map(|u| u.entity.as_str()).collect();
        assert_eq!(names.len(), 2, "{names:?}");
        assert!(names[0].starts_with("entity 144 (DE 23"), "{names:?}");
        assert!(
            imp.unreadable[0].reason.contains("entity 122"),
            "{:?}",
            imp.unreadable[0]
        );
        assert!(names[1].starts_with("entity 510 (DE 25"), "{names:?}");
    }

    #[test]
    fn iges_sphere_of_revolution_of_an_arc_with_omitted_pole_edges_has_its_full_area() {
        // A half circle of radius 15 revolved about the y axis; the trim
        // runs down one seam and up the other, leaving out the degenerate
        // edges at the poles (as OpenCASCADE writes it).
        let (h, t) = (FRAC_PI_2, TAU);
        let top = format!("110,{h},{t},0.,{},{t},0.;", -h);
        let bottom = format!("110,{},0.,0.,{h},0.,0.;", -h);
        let entities = [
            (110, 0, 0, "110,0.,-15.,0.,0.,15.,0.;"),
            (100, 0, 0, "100,0.,0.,0.,0.,-15.,0.,15.;"),
            (120, 0, 0, "120,1,3,0.,6.283185307179586;"),
            (110, 0, 0, top.as_str()),
            (110, 0, 0, bottom.as_str()),
            (102, 0, 0, "102,2,7,9;"),
            (142, 0, 0, "142,0,5,11,0,1;"),
            (144, 0, 0, "144,5,1,0,13;"),
        ];
        let imp = parse_iges(&iges_file(GLOBAL, &entities)).unwrap();
        assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
        assert_eq!(imp.surfaces.len(), 1);
        let s = &imp.surfaces[0].surface;
        let area = trimmed_area(s, 64, 64);
        let want = 4.0 * PI * 225.0;
        assert!((area - want).abs() <= 1e-6 * want, "{area} vs {want}");
        // the surface is the sphere
        let (u, v) = s.domain_center();
        assert!((s.eval(u, v).length() - 15.0).abs() < 1e-9);
    }

    #[test]
    fn iges_torus_whose_seam_pcurves_come_out_of_order_is_chained() {
        // As OpenCASCADE writes a torus: the composite lists the p-curves
        // in the order of the edge uses (right, bottom, left, top).
        let entities = [
            (144, 0, 0, "144,3,1,0,11;"),
            (120, 0, 0, "120,5,7,0.,6.283185307;"),
            (110, 0, 0, "110,0.,0.,1.,0.,0.,0.;"),
            (100, 9, 0, "100,0.,0.,0.,6.,0.,6.,0.;"),
            (124, 0, 0, "124,1.,0.,0.,20.,0.,0.,-1.,0.,0.,1.,-0.,0.;"),
            (142, 0, 0, "142,0,3,13,0,1;"),
            (102, 0, 0, "102,4,15,17,19,21;"),
            (
                110,
                0,
                0,
                "110,6.283185307,0.,0.,6.283185307,6.283185307,0.;",
            ),
            (110, 0, 0, "110,0.,0.,0.,6.283185307,0.,0.;"),
            (110, 0, 0, "110,0.,6.283185307,0.,0.,0.,0.;"),
            (
                110,
                0,
                0,
                "110,6.283185307,6.283185307,0.,0.,6.283185307,0.;",
            ),
        ];
        let imp = parse_iges(&iges_file(GLOBAL, &entities)).unwrap();
        assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
        assert_eq!(imp.surfaces.len(), 1);
        let area = trimmed_area(&imp.surfaces[0].surface, 64, 64);
        let want = 4.0 * PI * PI * 20.0 * 6.0;
        assert!((area - want).abs() <= 1e-6 * want, "{area} vs {want}");
    }
}
