//! Surface entities converted to B-spline surfaces: tabulated cylinder
//! (122), ruled surface (118, in [`super::ruled`]), parametric spline
//! surface (114) and offset surface (140), and the parametric spline curve
//! (112) as a curve.
//!
//! Each conversion keeps, where it can, the map from the file's surface
//! parameters to the B-spline's ([`Axis`]), so that the parameter-space
//! boundaries of a trimmed surface (144) on it are read exactly
//! ([`map_loop`]); where there is none the face is bounded by its
//! model-space curves ([`super::brep`]).

use super::curve_ops::{joined, power_to_bezier, reparametrised};
use super::{
    ArcMap, Iges, IgesError, IgesSurface, Nurbs3, Param, TrimLoop, Vec3, boundary::Piece, faces,
    params::INT, params::REAL, params::param, parse_int, read_entity_128, records::DirEntry,
    text_of,
};
use crate::bspline::BSplineSurface;
use crate::bspline::basis::MAX_DEGREE;
use crate::bspline::offset::offset_surface;

/// Deepest chain of offset surfaces (140 of a 140 …) read.
const MAX_OFFSET_DEPTH: usize = 8;

/// The map of one file surface parameter to the B-spline's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Axis {
    /// The same parameter.
    Identity,
    /// The file's parameter `x ∈ [0, 1]` runs linearly over the angles of
    /// the arcs of `map` (scale 1); the B-spline's parameter is the arcs'
    /// parameter mapped linearly onto `[0, 1]`.
    Normalized(ArcMap),
    /// The file's parameter is the angle; the B-spline's the arcs'.
    Angle(ArcMap),
}

impl Axis {
    pub(super) fn apply(&self, x: f64) -> f64 {
        match self {
            Axis::Identity => x,
            Axis::Normalized(m) => {
                if m.sweep == 0.0 {
                    return x;
                }
                (m.param(m.start + x * m.sweep) - m.start) / m.sweep
            }
            Axis::Angle(m) => m.param(x),
        }
    }

    /// The file's parameter range for the B-spline's `domain`.
    fn file_range(&self, domain: [f64; 2]) -> [f64; 2] {
        match self {
            Axis::Identity => domain,
            Axis::Normalized(_) => [0.0, 1.0],
            Axis::Angle(m) => [m.start, m.start + m.sweep],
        }
    }

    /// The arc joints of the map, in the file's parameter.
    fn joints(&self) -> Vec<f64> {
        match self {
            Axis::Identity => Vec::new(),
            Axis::Normalized(m) => (1..m.arcs).map(|k| k as f64 / m.arcs as f64).collect(),
            Axis::Angle(m) => (1..m.arcs)
                .map(|k| m.start + k as f64 * m.sweep / m.arcs as f64)
                .collect(),
        }
    }
}

/// A surface entity converted to a B-spline surface.
#[derive(Clone, Debug)]
pub(super) struct Converted {
    /// The surface, the entity's transformation applied.
    pub surface: BSplineSurface,
    /// File parameters to the surface's, per direction; `None` when the
    /// file's parametrisation is not one [`Axis`] per direction.
    pub axes: Option<[Axis; 2]>,
    /// A fitted surface (140 that is not a plane): the tolerance it meets
    /// and the largest deviation found.
    pub fit: Option<(f64, f64)>,
    /// The entity's transformation matrix (124) was applied.
    pub transformed: bool,
}

impl Converted {
    /// The import record of entity `k` (directory entry `e`).
    pub fn into_iges_surface(self, k: usize, e: &DirEntry, trimmed: bool) -> IgesSurface {
        let range = self.file_range();
        IgesSurface {
            rational: self.surface.is_rational(),
            surface: self.surface,
            directory_entry: 2 * k + 1,
            entity_type: e.entity_type,
            form: e.form,
            closed: [false, false],
            periodic: [false, false],
            parameter_range: range,
            transformed: self.transformed,
            trimmed,
            trim_entity: None,
        }
    }

    /// The file's parameter range `[u0, u1, v0, v1]`.
    pub fn file_range(&self) -> [f64; 4] {
        let (du, dv) = (self.surface.domain_u(), self.surface.domain_v());
        match &self.axes {
            Some([a, b]) => {
                let (u, v) = (a.file_range(du), b.file_range(dv));
                [u[0], u[1], v[0], v[1]]
            }
            None => [du[0], du[1], dv[0], dv[1]],
        }
    }
}

/// A trimming loop in a converted surface's file parameters mapped to the
/// surface's: unchanged where both axes are the identity; otherwise each
/// curve becomes a C¹ piecewise cubic within 1e-9 of the domain's diagonal
/// of the mapped curve, broken at its knots and where it crosses an arc
/// joint ([`faces::hermite_trim`]).
pub(super) fn map_loop(
    l: TrimLoop,
    axes: &[Axis; 2],
    surface: &BSplineSurface,
) -> Result<TrimLoop, String> {
    if axes.iter().all(|a| *a == Axis::Identity) {
        return Ok(l);
    }
    let (du, dv) = (surface.domain_u(), surface.domain_v());
    let tol = 1e-9 * (du[1] - du[0]).hypot(dv[1] - dv[0]);
    let curves = l
        .curves
        .iter()
        .map(|c| {
            let [t0, t1] = c.domain();
            let n = (64 * c.control_points().len() * c.degree()).clamp(64, 8000);
            let f = |x: f64| {
                let p = c.eval(x);
                [axes[0].apply(p[0]), axes[1].apply(p[1])]
            };
            let mut breaks: Vec<f64> = c.knots().to_vec();
            let at = |k: usize| t0 + (t1 - t0) * k as f64 / n as f64;
            for (coord, axis) in axes.iter().enumerate() {
                for j in axis.joints() {
                    let side = |x: f64| c.eval(x)[coord] < j;
                    for k in 0..n {
                        let (lo, hi) = (at(k), at(k + 1));
                        if side(lo) != side(hi) {
                            breaks.push(faces::crossing(&side, lo, hi));
                        }
                    }
                }
            }
            faces::hermite_trim(&f, t0, t1, &mut breaks, tol)
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(TrimLoop { curves })
}

/// The tensor product of `curve` (in `u`) with a degree-1 `v` over `[0,
/// 1]`: control rows `curve.points[i]` and `other[i]`, both with the
/// curve's weights.
fn linear_in_v(curve: &Nurbs3, other: &[Vec3]) -> Result<BSplineSurface, String> {
    let n = curve.points.len();
    let mut points = Vec::with_capacity(2 * n);
    let mut weights = Vec::with_capacity(2 * n);
    for i in 0..n {
        points.push(curve.points[i]);
        points.push(other[i]);
        let w = curve.weights.as_ref().map_or(1.0, |w| w[i]);
        weights.extend([w, w]);
    }
    BSplineSurface::from_flat(
        curve.degree,
        1,
        curve.knots.clone(),
        vec![0.0, 0.0, 1.0, 1.0],
        [n, 2],
        points,
        curve.weights.is_some().then_some(weights),
    )
    .map_err(|e| e.to_string())
}

impl Iges<'_> {
    /// Whether every boundary (142) of the trimmed surface (144) with
    /// parameters `p` has its parameter-space curve (`BPTR`).
    pub(super) fn boundaries_in_parameter_space(&self, p: &[(Param, usize)], line: usize) -> bool {
        let n1 = text_of(p, 2).and_then(parse_int).unwrap_or(0);
        let n2 = text_of(p, 3).and_then(parse_int).unwrap_or(0);
        let Ok(n2) = usize::try_from(n2) else {
            return false;
        };
        let first = if n1 == 0 { 5 } else { 4 };
        (first..5 + n2.min(p.len())).all(|slot| {
            text_of(p, slot)
                .and_then(parse_int)
                .and_then(|de| self.entry(de))
                .filter(|&b| self.dir[b].entity_type == 142)
                .and_then(|b| self.parameters(b).ok())
                .is_some_and(|q| param(self, 0, &q, 3, line, &INT).is_ok_and(|bptr| bptr != 0))
        })
    }

    /// Surface entity `k` (114, 118, 122 or 140) as a B-spline surface;
    /// an `Unsupported` error says why one cannot be read.
    pub(super) fn convert_surface(&self, k: usize, depth: usize) -> Result<Converted, IgesError> {
        let e = &self.dir[k];
        let p = self.parameters(k)?;
        let line = p.first().map_or(e.line, |t| t.1);
        let mut c = match e.entity_type {
            114 => self.spline_surface(k, &p, line)?,
            118 => self.ruled_surface(k, &p, line)?,
            122 => self.tabulated_cylinder(k, &p, line)?,
            140 => self.offset(k, &p, line, depth)?,
            t => {
                return Err(self.unsupported(
                    k,
                    line,
                    format!("surface entity {t} is not converted"),
                ));
            }
        };
        if let Some(m) = self.own_transform(k)? {
            let s = &mut c.surface;
            for i in 0..s.count_u() {
                for j in 0..s.count_v() {
                    let q = m.transform_point3(s.control_point(i, j));
                    s.set_control_point(i, j, q)
                        .map_err(|err| self.entity_error(k, line, err.to_string()))?;
                }
            }
            c.transformed = true;
        }
        Ok(c)
    }

    /// A curve entity as one NURBS on `[0, 1]` and the map from its file
    /// parameter, normalised to `[0, 1]`, to the NURBS's: the identity for
    /// a line (110), a B-spline curve (126), a parametric spline curve (112)
    /// and a composite curve (102) of these; the arcs' map for a circular
    /// arc (100) and an ellipse (104); `None` for other conics and
    /// composite curves with arcs.
    pub(super) fn normalized_curve(&self, k: usize) -> Result<(Nurbs3, Option<Axis>), IgesError> {
        let e = &self.dir[k];
        let line = e.line;
        let bad = |what: &str| self.entity_error(k, line, format!("the curve {what}"));
        let (c, axis) = match e.entity_type {
            100 => {
                let (c, m) = self.arc_generatrix(k)?;
                (c, Some(Axis::Normalized(m)))
            }
            104 => {
                let p = self.parameters(k)?;
                let l = p.first().map_or(line, |t| t.1);
                let (mut c, m) = self.conic(k, &p, l)?;
                self.transform_nurbs(k, &mut c)?;
                (c, m.map(Axis::Normalized))
            }
            110 | 112 | 126 | 102 => {
                let mut pieces = Vec::new();
                self.curve_pieces(k, 0, &mut pieces)?;
                let identity = e.entity_type != 102 || self.members_keep_parameters(k)?;
                let c = self.joined_pieces(k, pieces)?;
                (c, identity.then_some(Axis::Identity))
            }
            t => {
                return Err(self.unsupported(
                    k,
                    line,
                    format!("curve entity {t} as a directrix or rail is not read (100, 102, 104, 110, 112, 126 are)"),
                ));
            }
        };
        let c = reparametrised(&c, 0.0, 1.0).ok_or_else(|| bad("has an empty parameter range"))?;
        Ok((c, axis))
    }

    /// Whether the members of composite curve `k` (102) are all lines
    /// (110), B-spline (126) or parametric spline (112) curves, whose
    /// pieces keep their file parameter ranges.
    fn members_keep_parameters(&self, k: usize) -> Result<bool, IgesError> {
        let p = self.parameters(k)?;
        let line = p.first().map_or(self.dir[k].line, |t| t.1);
        let n = param(self, k, &p, 1, line, &INT)?.clamp(0, p.len() as i64) as usize;
        for m in 0..n {
            let de = param(self, k, &p, 2 + m, line, &INT)?;
            match self.entry(de).map(|c| self.dir[c].entity_type) {
                Some(110 | 112 | 126) => {}
                _ => return Ok(false),
            }
        }
        Ok(true)
    }

    /// The pieces of curve `k` joined into one NURBS (exact,
    /// [`joined`]); an error when they do not follow each other.
    pub(super) fn joined_pieces(&self, k: usize, pieces: Vec<Piece>) -> Result<Nurbs3, IgesError> {
        if let Some(q) = pieces
            .iter()
            .find(|q| q.degree == 0 || q.degree > MAX_DEGREE)
        {
            return Err(self.entity_error(
                k,
                self.dir[k].line,
                format!(
                    "a curve of degree {} (1 to {MAX_DEGREE} are read)",
                    q.degree
                ),
            ));
        }
        let curves: Vec<Nurbs3> = pieces.iter().map(Piece::nurbs).collect();
        if let [one] = &curves[..] {
            return Ok(one.clone());
        }
        let size = curves
            .iter()
            .flat_map(|c| c.points.iter())
            .fold(0.0_f64, |m, q| m.max(q.abs().max_element()));
        joined(&curves, 1e-9 * (1.0 + size)).ok_or_else(|| {
            self.unsupported(
                k,
                self.dir[k].line,
                format!(
                    "the {} members of the curve do not join end to start (or one cannot be made of one degree with the others)",
                    curves.len()
                ),
            )
        })
    }

    /// Entity 122, tabulated cylinder (IGES 5.3 §4.19): `DE LX LY LZ`,
    /// `S(u, v) = C(t) + v·(L − C(t₀))`, `t = t₀ + u·(t₁ − t₀)`, `u, v ∈
    /// [0, 1]`. Exact: the directrix `C` (any curve [`Self::normalized_curve`]
    /// reads, open or closed) times a degree-1 `v`; the same weights on both
    /// rows keep `v` linear.
    fn tabulated_cylinder(
        &self,
        k: usize,
        p: &[(Param, usize)],
        line: usize,
    ) -> Result<Converted, IgesError> {
        let dk = self.pointer(k, p, 1, line, &[100, 102, 104, 110, 112, 126])?;
        let (curve, axis) = self.normalized_curve(dk)?;
        let end = Vec3::new(
            param(self, k, p, 2, line, &REAL)?,
            param(self, k, p, 3, line, &REAL)?,
            param(self, k, p, 4, line, &REAL)?,
        );
        let d = end - curve.eval(0.0);
        if !(d.length() > 0.0 && d.is_finite()) {
            return Err(self.entity_error(k, line, "the generatrix has no length".into()));
        }
        let other: Vec<Vec3> = curve.points.iter().map(|q| *q + d).collect();
        let surface = linear_in_v(&curve, &other).map_err(|m| self.entity_error(k, line, m))?;
        Ok(Converted {
            surface,
            axes: axis.map(|a| [a, Axis::Identity]),
            fit: None,
            transformed: false,
        })
    }

    /// Entity 114, parametric spline surface (IGES 5.3 §4.17): `CTYPE
    /// PTYPE M N TU(0..M) TV(0..N)`, then for each patch `(i, j)` (i
    /// slowest) the 16 coefficients of `X`, of `Y` and of `Z` of `Σ
    /// a_mn·s^m·t^n` (`m` fastest, `s = u − TU(i)`, `t = v − TV(j)`), a
    /// block of 48 values after each `i`. Exact: each bicubic patch in
    /// Bézier form, the patches joined with triple knots at the breakpoints
    /// (parameters as in the file); patches that do not meet (by more than
    /// 1e-9 of the net's size) are an error.
    fn spline_surface(
        &self,
        k: usize,
        p: &[(Param, usize)],
        line: usize,
    ) -> Result<Converted, IgesError> {
        let count = |n: usize| -> Result<usize, IgesError> {
            let v = param(self, k, p, n, line, &INT)?;
            usize::try_from(v)
                .ok()
                .filter(|&c| c >= 1 && c.saturating_mul(48) < p.len())
                .ok_or_else(|| self.entity_error(k, line, format!("parameter {n}: {v} segments")))
        };
        let (m, n) = (count(3)?, count(4)?);
        let needed = 5 + m + 1 + n + 1 + m.saturating_mul(n + 1).saturating_mul(48);
        if p.len() < needed {
            return Err(self.entity_error(
                k,
                line,
                format!("{} parameters, but M = {m}, N = {n} need {needed}", p.len()),
            ));
        }
        let reals = |from: usize, count: usize| -> Result<Vec<f64>, IgesError> {
            (from..from + count)
                .map(|i| param(self, k, p, i, line, &REAL))
                .collect()
        };
        let tu = reals(5, m + 1)?;
        let tv = reals(6 + m, n + 1)?;
        for t in [&tu, &tv] {
            if !t.windows(2).all(|w| w[1] > w[0]) || !t.iter().all(|x| x.is_finite()) {
                return Err(self.entity_error(k, line, "the breakpoints do not increase".into()));
            }
        }
        let first = 7 + m + n;
        let (nu, nv) = (3 * m + 1, 3 * n + 1);
        let mut net = vec![[None::<Vec3>; 1]; nu * nv];
        let mut worst = 0.0_f64;
        for i in 0..m {
            for j in 0..n {
                let at = first + (i * (n + 1) + j) * 48;
                let c = reals(at, 48)?;
                let (hu, hv) = (tu[i + 1] - tu[i], tv[j + 1] - tv[j]);
                // per coordinate: power coefficients a[m][n] to Bézier b[r][s]
                let mut bez = [[Vec3::ZERO; 4]; 4];
                for axis in 0..3 {
                    let a = |mm: usize, nn: usize| c[16 * axis + mm + 4 * nn];
                    // along s for each power of t
                    let mut rows = [[0.0; 4]; 4];
                    for (nn, row) in rows.iter_mut().enumerate() {
                        *row = power_to_bezier([a(0, nn), a(1, nn), a(2, nn), a(3, nn)], hu);
                    }
                    for r in 0..4 {
                        let col =
                            power_to_bezier([rows[0][r], rows[1][r], rows[2][r], rows[3][r]], hv);
                        for (s, v) in col.iter().enumerate() {
                            bez[r][s][axis] = *v;
                        }
                    }
                }
                for (r, row) in bez.iter().enumerate() {
                    for (s, q) in row.iter().enumerate() {
                        let slot = &mut net[(3 * i + r) * nv + 3 * j + s][0];
                        match slot {
                            Some(old) => worst = worst.max(old.distance(*q)),
                            None => *slot = Some(*q),
                        }
                    }
                }
            }
        }
        let points: Vec<Vec3> = net.iter().map(|q| q[0].unwrap_or(Vec3::ZERO)).collect();
        let size = points
            .iter()
            .fold(0.0_f64, |s, q| s.max(q.abs().max_element()));
        if !(worst <= 1e-9 * (1.0 + size)) {
            return Err(self.unsupported(
                k,
                line,
                format!("its patches do not meet (by {worst:.3e}): not one continuous surface"),
            ));
        }
        let knots = |t: &[f64]| -> Vec<f64> {
            let mut out = vec![t[0]; 4];
            for &x in &t[1..t.len() - 1] {
                out.extend([x; 3]);
            }
            out.extend([t[t.len() - 1]; 4]);
            out
        };
        let surface =
            BSplineSurface::from_flat(3, 3, knots(&tu), knots(&tv), [nu, nv], points, None)
                .map_err(|source| IgesError::Surface {
                    entity: 2 * k + 1,
                    line,
                    source,
                })?;
        Ok(Converted {
            surface,
            axes: Some([Axis::Identity, Axis::Identity]),
            fit: None,
            transformed: false,
        })
    }

    /// Entity 112, parametric spline curve (IGES 5.3 §4.14): `CTYPE H NDIM
    /// N T(1..N+1)`, then per segment `AX BX CX DX AY … DZ` of `A + B·s +
    /// C·s² + D·s³`, `s = t − T(i)`. Exact: the cubic segments in Bézier
    /// form joined at the breakpoints (parameters as in the file).
    pub(super) fn read_entity_112(
        &self,
        k: usize,
        p: &[(Param, usize)],
        line: usize,
    ) -> Result<Piece, IgesError> {
        let n = param(self, k, p, 4, line, &INT)?;
        let n = usize::try_from(n)
            .ok()
            .filter(|&n| n >= 1 && n.saturating_mul(12) < p.len())
            .ok_or_else(|| self.entity_error(k, line, format!("N = {n} segments")))?;
        let reals = |from: usize, count: usize| -> Result<Vec<f64>, IgesError> {
            (from..from + count)
                .map(|i| param(self, k, p, i, line, &REAL))
                .collect()
        };
        let t = reals(5, n + 1)?;
        if !t.windows(2).all(|w| w[1] > w[0]) || !t.iter().all(|x| x.is_finite()) {
            return Err(self.entity_error(k, line, "the breakpoints do not increase".into()));
        }
        let mut points = Vec::with_capacity(3 * n + 1);
        let mut knots = vec![t[0]; 4];
        for i in 0..n {
            let c = reals(6 + n + 12 * i, 12)?;
            let h = t[i + 1] - t[i];
            let axes: Vec<[f64; 4]> = (0..3)
                .map(|a| power_to_bezier([c[4 * a], c[4 * a + 1], c[4 * a + 2], c[4 * a + 3]], h))
                .collect();
            let b: Vec<Vec3> = (0..4)
                .map(|r| Vec3::new(axes[0][r], axes[1][r], axes[2][r]))
                .collect();
            if let Some(last) = points.last() {
                let gap = b[0].distance(*last);
                if !(gap <= 1e-9 * (1.0 + last.abs().max_element())) {
                    return Err(self.unsupported(
                        k,
                        line,
                        format!(
                            "segment {} does not start where segment {i} ends (by {gap:.3e})",
                            i + 1
                        ),
                    ));
                }
                points.extend_from_slice(&b[1..]);
            } else {
                points.extend_from_slice(&b);
            }
            let x = t[i + 1];
            knots.extend([x; 3]);
        }
        knots.push(t[n]);
        Ok(Piece {
            degree: 3,
            knots,
            points,
            weights: None,
        })
    }

    /// Entity 140, offset surface (IGES 5.3 §4.20): `NX NY NZ D DE`, the
    /// surface `S + D·N` with `N = Su × Sv / |Su × Sv|` of the base surface
    /// `DE` (128, 120, 114, 118, 122 or 140; the offset indicator `(NX, NY,
    /// NZ)` is not needed: the side is the sign of `D`). Exact for a planar
    /// base and a surface of revolution of a line (cylinder, cone; the line
    /// moved along the normal and revolved); otherwise a bicubic fit within 1e-7 of the base's size
    /// (control net diagonal plus `2|D|`) ([`offset_surface`]), on the
    /// base's parameters.
    fn offset(
        &self,
        k: usize,
        p: &[(Param, usize)],
        line: usize,
        depth: usize,
    ) -> Result<Converted, IgesError> {
        if depth >= MAX_OFFSET_DEPTH {
            return Err(self.entity_error(
                k,
                line,
                "offset surfaces nest too deeply (or form a cycle)".into(),
            ));
        }
        let d = param(self, k, p, 4, line, &REAL)?;
        let b = self.pointer(
            k,
            p,
            5,
            line,
            &[114, 118, 120, 122, 128, 140, 108, 190, 192, 194, 196, 198],
        )?;
        let (base, axes) = match self.dir[b].entity_type {
            128 => (
                read_entity_128(self, b, false)?.surface,
                Some([Axis::Identity, Axis::Identity]),
            ),
            120 => match self.read_entity_120(b)? {
                Some(r) => {
                    let u = r.tmap.map_or(Axis::Identity, Axis::Angle);
                    let axes = Some([u, Axis::Angle(r.map)]);
                    // a cylinder or cone: the offset of the line revolved
                    if d.is_finite()
                        && let Some(o) = self.revolved_offset(b, d)?
                    {
                        return Ok(Converted {
                            surface: o.surface,
                            axes,
                            fit: None,
                            transformed: false,
                        });
                    }
                    (r.surface, axes)
                }
                None => {
                    return Err(self.unsupported(
                        k,
                        line,
                        format!("its base surface: {}", self.why_not_read(b)),
                    ));
                }
            },
            114 | 118 | 122 | 140 => {
                let c = self.convert_surface(b, depth + 1)?;
                (c.surface, c.axes)
            }
            t => {
                return Err(self.unsupported(
                    k,
                    line,
                    format!("an offset of surface entity {t} is not read (of 114, 118, 120, 122, 128, 140 it is)"),
                ));
            }
        };
        let mut base = base;
        base.clear_trims();
        let (lo, hi) = base.control_bounding_box();
        let tolerance = 1e-7 * ((hi - lo).length() + 2.0 * d.abs());
        let o = offset_surface(&base, d, tolerance)
            .map_err(|m| self.unsupported(k, line, format!("the offset surface: {m}")))?;
        Ok(Converted {
            surface: o.surface,
            axes,
            fit: o.deviation.map(|e| (tolerance, e)),
            transformed: false,
        })
    }
}
