//! Continuity across patch boundaries: which boundary
//! curves of a set of B-spline patches are shared — found geometrically, so
//! patches need no topology, and a boundary may be shared over part of its
//! length only (T-junctions) — and how smoothly the patches join along each
//! shared stretch. The boundary of an untrimmed patch is the four sides of
//! its parameter rectangle; that of a trimmed patch (a CAD face) is the
//! curves of its trimming loops, mapped onto the surface ([`Boundary`]), so
//! faces that meet along trims are found too.
//!
//! - **G0**: the position gap |S_A − S_B| between a point of A's side and
//!   the closest point of B's side;
//! - **G1**: the angle between the tangent planes across the edge, measured
//!   as the angle between A's inward cross-boundary direction d_A and the
//!   reverse −d_B of B's (each the cross-boundary partial derivative made
//!   orthogonal to its side's tangent): 0° for a smooth join, whatever the
//!   patches' orientation;
//! - **G2**: the difference of the normal curvatures across the edge,
//!   κ_n(d) = II(d, d) / I(d, d) (fundamental forms of each patch, B's
//!   normal turned to agree with A's), absolute (1 / length) and relative to
//!   max(|κ_A|, |κ_B|, 1 / model size).
//!
//! An edge is classified `gap` when its largest gap exceeds the position
//! tolerance, else `G0` when its largest angle exceeds the angle tolerance,
//! else `G1` when its largest relative curvature difference exceeds the
//! curvature tolerance, else `G2` (the classes of Rhino's
//! GlobalEdgeContinuity / Alias surface continuity).

use crate::Vec3;
use crate::bspline::{BSplineSurface, SurfaceDerivatives, TrimCurve};
use crate::control::{Control, setters};
use rayon::prelude::*;
use serde::{Serialize, Serializer};
use thiserror::Error;

/// A side of a patch's parameter rectangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PatchSide {
    /// u = u_min, running in v.
    UMin,
    /// u = u_max, running in v.
    UMax,
    /// v = v_min, running in u.
    VMin,
    /// v = v_max, running in u.
    VMax,
}

impl PatchSide {
    /// The four sides.
    pub const ALL: [PatchSide; 4] = [
        PatchSide::UMin,
        PatchSide::UMax,
        PatchSide::VMin,
        PatchSide::VMax,
    ];

    /// Parameter range of the running parameter t on `s`.
    pub fn range(self, s: &BSplineSurface) -> [f64; 2] {
        match self {
            PatchSide::UMin | PatchSide::UMax => s.domain_v(),
            PatchSide::VMin | PatchSide::VMax => s.domain_u(),
        }
    }

    /// The (u, v) of running parameter t.
    pub fn uv(self, s: &BSplineSurface, t: f64) -> (f64, f64) {
        let (du, dv) = (s.domain_u(), s.domain_v());
        match self {
            PatchSide::UMin => (du[0], t),
            PatchSide::UMax => (du[1], t),
            PatchSide::VMin => (t, dv[0]),
            PatchSide::VMax => (t, dv[1]),
        }
    }

    /// Tangent dS/dt, its derivative, and the inward cross-boundary partial
    /// derivative (±S_u or ±S_v) from the surface derivatives.
    fn frame(self, d: &SurfaceDerivatives) -> (Vec3, Vec3, Vec3) {
        match self {
            PatchSide::UMin => (d.sv, d.svv, d.su),
            PatchSide::UMax => (d.sv, d.svv, -d.su),
            PatchSide::VMin => (d.su, d.suu, d.sv),
            PatchSide::VMax => (d.su, d.suu, -d.sv),
        }
    }
}

/// One trimming curve of a trimmed patch: curve `curve` of loop
/// `loop_index` (0 = outer) of its [`BSplineSurface::trims`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub struct TrimCurveId {
    /// The loop (0 = outer).
    #[serde(rename = "loop")]
    pub loop_index: usize,
    /// The curve within the loop.
    pub curve: usize,
}

/// A piece of a patch's boundary: a side of the parameter rectangle of an
/// untrimmed patch, or a trimming curve of a trimmed one. In JSON a side is
/// its name (`"u_min"`), a trimming curve `{"loop": L, "curve": C}`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(untagged)]
pub enum Boundary {
    /// A side of the parameter rectangle.
    Side(PatchSide),
    /// A trimming curve.
    Trim(TrimCurveId),
}

impl std::fmt::Display for Boundary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Boundary::Side(PatchSide::UMin) => f.write_str("u_min"),
            Boundary::Side(PatchSide::UMax) => f.write_str("u_max"),
            Boundary::Side(PatchSide::VMin) => f.write_str("v_min"),
            Boundary::Side(PatchSide::VMax) => f.write_str("v_max"),
            Boundary::Trim(t) => write!(f, "trim loop {} curve {}", t.loop_index, t.curve),
        }
    }
}

impl Boundary {
    /// The boundary pieces of `s`: its trimming curves when it is trimmed,
    /// else the four sides.
    pub fn all(s: &BSplineSurface) -> Vec<Boundary> {
        if !s.is_trimmed() {
            return PatchSide::ALL.into_iter().map(Boundary::Side).collect();
        }
        s.trims()
            .iter()
            .enumerate()
            .flat_map(|(l, lp)| {
                (0..lp.curves.len()).map(move |c| {
                    Boundary::Trim(TrimCurveId {
                        loop_index: l,
                        curve: c,
                    })
                })
            })
            .collect()
    }
}

/// Continuity class of a shared edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub enum SeamClass {
    /// The sides are near each other but further apart than the position
    /// tolerance.
    #[serde(rename = "gap")]
    Gap,
    /// Closed, but the tangent planes differ by more than the angle tolerance.
    G0,
    /// Tangent-plane continuous, curvature differs.
    G1,
    /// Curvature continuous within the tolerances.
    G2,
}

impl SeamClass {
    /// "gap", "G0", "G1" or "G2".
    pub fn name(self) -> &'static str {
        match self {
            SeamClass::Gap => "gap",
            SeamClass::G0 => "G0",
            SeamClass::G1 => "G1",
            SeamClass::G2 => "G2",
        }
    }
}

/// Options of [`continuity`]. Lengths are in model units; `None` derives
/// them from the diagonal D of the bounding box of all control points.
/// Build them with `ContinuityOptions::default()` and the setters.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct ContinuityOptions {
    /// Position tolerance for G0 (default 1e-4 D).
    pub tolerance: Option<f64>,
    /// Angle tolerance for G1, degrees (0.5°).
    pub angle_tolerance_deg: f64,
    /// Relative curvature tolerance for G2 (0.05 = 5 %).
    pub curvature_tolerance: f64,
    /// Two sides closer than this are taken as one shared edge (default
    /// 10 × tolerance); farther apart they are not neighbours.
    pub match_distance: Option<f64>,
    /// Samples per side when matching sides (64).
    pub match_samples: usize,
    /// Samples along each shared edge for the measures (64).
    pub samples: usize,
    /// Progress (per phase: sampling the boundary pieces, pairing them,
    /// measuring the shared edges) and cancellation.
    pub control: Control,
}

setters!(ContinuityOptions {
    tolerance: Option<f64>,
    angle_tolerance_deg: f64,
    curvature_tolerance: f64,
    match_distance: Option<f64>,
    match_samples: usize,
    samples: usize,
    control: Control,
});

impl Default for ContinuityOptions {
    fn default() -> Self {
        ContinuityOptions {
            tolerance: None,
            angle_tolerance_deg: 0.5,
            curvature_tolerance: 0.05,
            match_distance: None,
            match_samples: 64,
            samples: 64,
            control: Control::default(),
        }
    }
}

/// Why [`continuity`] could not run.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ContinuityError {
    /// An option is out of range.
    #[error("invalid option: {0}")]
    Invalid(String),
    /// Cancelled through [`ContinuityOptions::control`].
    #[error(transparent)]
    Cancelled(#[from] crate::Cancelled),
}

/// One shared edge between boundary piece `sides[0]` of surface
/// `surfaces[0]` and `sides[1]` of surface `surfaces[1]` (the same surface
/// for a closed patch), over the running-parameter range `range` of the
/// first (a side's u or v, a trimming curve's own parameter). It
/// serialises to one entry of the `edges` of `fairline continuity
/// --report` (DESIGN.md §5; without `samples` and `points`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Seam {
    /// The two surfaces (indices in the input).
    pub surfaces: [usize; 2],
    /// Their boundary pieces (sides or trimming curves).
    pub sides: [Boundary; 2],
    /// Running-parameter range on the first surface's boundary piece.
    pub range: [f64; 2],
    /// Length of the shared stretch (model units).
    pub length: f64,
    /// Largest position gap (model units).
    pub g0_max: f64,
    /// Largest angle between the tangent planes (degrees).
    pub g1_max_deg: f64,
    /// Largest normal-curvature difference across the edge (1 / model units).
    pub g2_max: f64,
    /// Largest relative normal-curvature difference.
    pub g2_max_relative: f64,
    /// The class.
    pub class: SeamClass,
    /// Where the measure that decides the class is largest.
    #[serde(serialize_with = "serialize_point")]
    pub worst: Vec3,
    /// Samples measured.
    #[serde(skip)]
    pub samples: usize,
    /// Samples where a normal is undefined (poles): G0 only.
    pub degenerate_samples: usize,
    /// Points of the edge on the first surface (for pictures).
    #[serde(skip)]
    pub points: Vec<Vec3>,
}

/// A point as `[x, y, z]`.
fn serialize_point<S: Serializer>(p: &Vec3, s: S) -> Result<S::Ok, S::Error> {
    p.to_array().serialize(s)
}

/// Number of shared edges of each class.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ClassCounts {
    /// Edges with a gap above the position tolerance.
    pub gap: usize,
    /// Closed edges with a tangent-plane angle above the angle tolerance.
    #[serde(rename = "G0")]
    pub g0: usize,
    /// Tangent-plane continuous edges whose curvature differs.
    #[serde(rename = "G1")]
    pub g1: usize,
    /// Curvature-continuous edges.
    #[serde(rename = "G2")]
    pub g2: usize,
}

impl ClassCounts {
    /// The counts of `seams`.
    pub fn of(seams: &[Seam]) -> ClassCounts {
        let mut c = ClassCounts::default();
        for s in seams {
            match s.class {
                SeamClass::Gap => c.gap += 1,
                SeamClass::G0 => c.g0 += 1,
                SeamClass::G1 => c.g1 += 1,
                SeamClass::G2 => c.g2 += 1,
            }
        }
        c
    }

    /// The count of class `c`.
    pub fn get(&self, c: SeamClass) -> usize {
        match c {
            SeamClass::Gap => self.gap,
            SeamClass::G0 => self.g0,
            SeamClass::G1 => self.g1,
            SeamClass::G2 => self.g2,
        }
    }
}

/// What [`continuity`] found. It serialises to the keys of `fairline
/// continuity --report`: `edges` (the seams), `classes`, `tolerance`,
/// `match_distance`, `degenerate_sides` (DESIGN.md §5).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ContinuityReport {
    /// The shared edges, ordered by (surfaces, sides, range).
    #[serde(rename = "edges")]
    pub seams: Vec<Seam>,
    /// Number of edges of each class.
    pub classes: ClassCounts,
    /// Position tolerance used.
    pub tolerance: f64,
    /// Matching distance used.
    pub match_distance: f64,
    /// Boundary pieces shorter than the matching distance (collapsed to a
    /// point: poles), not analysed.
    pub degenerate_sides: usize,
}

/// A sampled boundary piece.
struct SideSamples {
    surface: usize,
    side: Boundary,
    /// For a trimming curve: whether the face lies to the left of the curve
    /// in its own direction (in the (u, v) plane).
    inside_left: bool,
    ts: Vec<f64>,
    points: Vec<Vec3>,
    lo: Vec3,
    hi: Vec3,
    length: f64,
}

impl SideSamples {
    /// The trimming curve of a [`Boundary::Trim`] piece.
    fn trim_curve<'s>(&self, s: &'s BSplineSurface) -> Option<&'s TrimCurve> {
        match self.side {
            Boundary::Trim(id) => s.trims().get(id.loop_index)?.curves.get(id.curve),
            Boundary::Side(_) => None,
        }
    }

    /// Range of the running parameter t.
    fn range(&self, s: &BSplineSurface) -> [f64; 2] {
        match (self.side, self.trim_curve(s)) {
            (Boundary::Side(side), _) => side.range(s),
            (Boundary::Trim(_), Some(c)) => c.domain(),
            (Boundary::Trim(_), None) => [0.0, 0.0],
        }
    }

    /// The (u, v) of running parameter t (trimming curves clamped to the
    /// surface's domain).
    fn uv(&self, s: &BSplineSurface, t: f64) -> (f64, f64) {
        match (self.side, self.trim_curve(s)) {
            (Boundary::Side(side), _) => side.uv(s, t),
            (Boundary::Trim(_), Some(c)) => {
                let [u, v] = c.eval(t);
                s.clamp_parameters(u, v)
            }
            (Boundary::Trim(_), None) => s.domain_center(),
        }
    }

    /// Tangent dS/dt, its derivative (zero on trimming curves: the closest
    /// point search is then Gauss–Newton) and a cross-boundary direction
    /// pointing into the face, from the surface derivatives at `uv(t)`. On
    /// a trimming curve c(t) = (u(t), v(t)) the tangent is S_u u' + S_v v'
    /// and the inward direction S_u w_u + S_v w_v with w the (u, v) normal
    /// of the curve on the face's side; (u', v') by central differences.
    fn frame(&self, s: &BSplineSurface, t: f64, d: &SurfaceDerivatives) -> (Vec3, Vec3, Vec3) {
        let c = match (self.side, self.trim_curve(s)) {
            (Boundary::Side(side), _) => return side.frame(d),
            (Boundary::Trim(_), Some(c)) => c,
            (Boundary::Trim(_), None) => return (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO),
        };
        let [t0, t1] = c.domain();
        let h = 1e-6 * (t1 - t0);
        let (ta, tb) = ((t - h).max(t0), (t + h).min(t1));
        let (pa, pb) = (c.eval(ta), c.eval(tb));
        let dt = tb - ta;
        let (du, dv) = if dt > 0.0 {
            ((pb[0] - pa[0]) / dt, (pb[1] - pa[1]) / dt)
        } else {
            (0.0, 0.0)
        };
        let w = if self.inside_left {
            (-dv, du)
        } else {
            (dv, -du)
        };
        (d.su * du + d.sv * dv, Vec3::ZERO, d.su * w.0 + d.sv * w.1)
    }
}

/// Whether the face of `s` lies to the left of the curves of trimming loop
/// `l` in their given direction: the loop as given winds counter-clockwise
/// and is the outer one, or clockwise and a hole (the face is left of
/// [`super::TrimmedDomain::polylines`], which are oriented that way).
fn inside_is_left(s: &BSplineSurface, l: usize) -> bool {
    let Some(lp) = s.trims().get(l) else {
        return true;
    };
    let mut pts = Vec::new();
    let [u0, u1] = s.domain_u();
    let [v0, v1] = s.domain_v();
    let tolerance = 1e-4 * (u1 - u0).hypot(v1 - v0);
    for c in &lp.curves {
        c.flatten_into(tolerance, &mut pts);
    }
    (super::polygon_signed_area2(&pts) > 0.0) == (l == 0)
}

fn sample_side(s: &BSplineSurface, k: usize, side: Boundary, n: usize) -> SideSamples {
    let inside_left = match side {
        Boundary::Trim(id) => inside_is_left(s, id.loop_index),
        Boundary::Side(_) => true,
    };
    let mut b = SideSamples {
        surface: k,
        side,
        inside_left,
        ts: Vec::new(),
        points: Vec::new(),
        lo: Vec3::splat(f64::INFINITY),
        hi: Vec3::splat(f64::NEG_INFINITY),
        length: 0.0,
    };
    let r = b.range(s);
    b.ts = (0..=n)
        .map(|m| r[0] + (r[1] - r[0]) * m as f64 / n as f64)
        .collect();
    b.points =
        b.ts.iter()
            .map(|&t| {
                let (u, v) = b.uv(s, t);
                s.eval(u, v)
            })
            .collect();
    for p in &b.points {
        b.lo = b.lo.min(*p);
        b.hi = b.hi.max(*p);
    }
    b.length = b.points.windows(2).map(|w| (w[1] - w[0]).length()).sum();
    b
}

/// Closest point of boundary piece `b` to `p`: (running parameter,
/// distance). Starts from the nearest sample and refines by Newton on
/// |C(t) − p|² (Gauss–Newton on trimming curves).
fn closest_on_side(s: &BSplineSurface, b: &SideSamples, p: Vec3) -> (f64, f64) {
    let mut best = 0;
    let mut bd = f64::INFINITY;
    for (k, q) in b.points.iter().enumerate() {
        let d = (*q - p).length_squared();
        if d < bd {
            bd = d;
            best = k;
        }
    }
    let r = b.range(s);
    let mut t = b.ts[best];
    for _ in 0..20 {
        let (u, v) = b.uv(s, t);
        let d = s.derivatives(u, v);
        let (c1, c2, _) = b.frame(s, t, &d);
        let e = d.point - p;
        let g = e.dot(c1);
        let h = c1.dot(c1) + e.dot(c2);
        let h = if h > 0.0 { h } else { c1.dot(c1) };
        if !(h > 0.0 && h.is_finite()) {
            break;
        }
        let step = g / h;
        let nt = (t - step).clamp(r[0], r[1]);
        if !nt.is_finite() {
            break;
        }
        let done = (nt - t).abs() <= 1e-14 * (r[1] - r[0]).abs().max(1e-300);
        t = nt;
        if done {
            break;
        }
    }
    let (u, v) = b.uv(s, t);
    let d = (s.eval(u, v) - p).length();
    // Gauss–Newton on a trimming curve may stop short of a nearer sample.
    if matches!(b.side, Boundary::Trim(_)) && bd.sqrt() < d {
        return (b.ts[best], bd.sqrt());
    }
    (t, d)
}

/// Normal curvature of `s` in the tangent direction `dir` at `d`, with
/// normal `n` (II(d, d) / I(d, d)); `None` where the first fundamental form
/// is singular.
fn normal_curvature(d: &SurfaceDerivatives, n: Vec3, dir: Vec3) -> Option<f64> {
    let (e, f, g) = (d.su.dot(d.su), d.su.dot(d.sv), d.sv.dot(d.sv));
    let det = e * g - f * f;
    if !(det > 1e-300 && det.is_finite()) {
        return None;
    }
    let (x, y) = (dir.dot(d.su), dir.dot(d.sv));
    let a = (g * x - f * y) / det;
    let b = (e * y - f * x) / det;
    let (l, m, nn) = (d.suu.dot(n), d.suv.dot(n), d.svv.dot(n));
    let first = a * a * e + 2.0 * a * b * f + b * b * g;
    if !(first > 0.0) {
        return None;
    }
    let k = (a * a * l + 2.0 * a * b * m + b * b * nn) / first;
    k.is_finite().then_some(k)
}

/// The unit inward cross-boundary direction (tangent to the surface,
/// orthogonal to the boundary) and the unit normal at running parameter t
/// of boundary piece `b`.
fn cross_direction(
    s: &BSplineSurface,
    b: &SideSamples,
    t: f64,
    d: &SurfaceDerivatives,
) -> Option<(Vec3, Vec3)> {
    let (tan, _, cross) = b.frame(s, t, d);
    let n = d.normal()?;
    let tl = tan.length_squared();
    let c = if tl > 0.0 {
        cross - (cross.dot(tan) / tl) * tan
    } else {
        cross
    };
    let c = c.try_normalize()?;
    Some((c, n))
}

/// Measures of one sample: (gap, angle°, |Δκ|, relative Δκ) — the last
/// three `None` at a pole.
type SampleMeasure = (f64, Option<(f64, f64, f64)>);

fn measure(
    sa: &BSplineSurface,
    a: &SideSamples,
    sb: &BSplineSurface,
    b: &SideSamples,
    t: f64,
    model: f64,
) -> (Vec3, SampleMeasure) {
    let (u, v) = a.uv(sa, t);
    let da = sa.derivatives(u, v);
    let (tb, gap) = closest_on_side(sb, b, da.point);
    let (ub, vb) = b.uv(sb, tb);
    let db = sb.derivatives(ub, vb);
    let rest = (|| {
        let (ca, na) = cross_direction(sa, a, t, &da)?;
        let (cb, nb) = cross_direction(sb, b, tb, &db)?;
        // atan2(|a × b|, a · b): accurate near 0° where acos is not
        let angle = ca.cross(-cb).length().atan2(ca.dot(-cb)).to_degrees();
        let nb_aligned = if na.dot(nb) < 0.0 { -nb } else { nb };
        let ka = normal_curvature(&da, na, ca)?;
        let kb = normal_curvature(&db, nb_aligned, cb)?;
        let diff = (ka - kb).abs();
        let scale = ka.abs().max(kb.abs()).max(1.0 / model);
        Some((angle, diff, diff / scale))
    })();
    (da.point, (gap, rest))
}

/// Shared edges of `surfaces` and their continuity; see the module
/// documentation. Deterministic (the pairs are searched in parallel and
/// sorted).
pub fn continuity(
    surfaces: &[BSplineSurface],
    opts: &ContinuityOptions,
) -> Result<ContinuityReport, ContinuityError> {
    let bad = |m: &str| Err(ContinuityError::Invalid(m.to_string()));
    if !(opts.angle_tolerance_deg >= 0.0 && opts.angle_tolerance_deg.is_finite()) {
        return bad("angle tolerance must be finite and not negative");
    }
    if !(opts.curvature_tolerance >= 0.0 && opts.curvature_tolerance.is_finite()) {
        return bad("curvature tolerance must be finite and not negative");
    }
    if !(2..=100_000).contains(&opts.match_samples) || !(2..=100_000).contains(&opts.samples) {
        return bad("sample counts must be between 2 and 100000");
    }
    let (mut lo, mut hi) = (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY));
    for s in surfaces {
        let (a, b) = s.control_bounding_box();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    let diag = if surfaces.is_empty() {
        1.0
    } else {
        (hi - lo).length()
    };
    let model = if diag > 0.0 && diag.is_finite() {
        diag
    } else {
        1.0
    };
    let tol = opts.tolerance.unwrap_or(1e-4 * model);
    if !(tol > 0.0 && tol.is_finite()) {
        return bad("position tolerance must be positive");
    }
    let matching = opts.match_distance.unwrap_or(10.0 * tol);
    if !(matching >= tol && matching.is_finite()) {
        return bad("match distance must be finite and at least the tolerance");
    }
    opts.control.step("sampling boundaries", 0, 3)?;
    let sides: Vec<SideSamples> = surfaces
        .par_iter()
        .enumerate()
        .flat_map_iter(|(k, s)| {
            Boundary::all(s)
                .into_iter()
                .map(move |side| sample_side(s, k, side, opts.match_samples))
        })
        .collect();
    let (live, dead): (Vec<&SideSamples>, Vec<&SideSamples>) =
        sides.iter().partition(|s| s.length > matching);
    opts.control.step("pairing boundaries", 1, 3)?;
    let pairs: Vec<(usize, usize)> = (0..live.len())
        .flat_map(|a| (a + 1..live.len()).map(move |b| (a, b)))
        .filter(|&(a, b)| {
            let (x, y) = (live[a], live[b]);
            let m = Vec3::splat(matching);
            let overlap = (x.lo - m).cmple(y.hi).all() && (y.lo - m).cmple(x.hi).all();
            // the same patch: only opposite sides (a closed patch's seam)
            // or two trimming curves (a closed face's seam edge)
            let same_ok = x.surface != y.surface
                || matches!(
                    (x.side, y.side),
                    (
                        Boundary::Side(PatchSide::UMin),
                        Boundary::Side(PatchSide::UMax)
                    ) | (
                        Boundary::Side(PatchSide::VMin),
                        Boundary::Side(PatchSide::VMax)
                    ) | (Boundary::Trim(_), Boundary::Trim(_))
                );
            overlap && same_ok
        })
        .collect();
    opts.control.step("measuring shared edges", 2, 3)?;
    let mut seams: Vec<Seam> = pairs
        .par_iter()
        .flat_map_iter(|&(ia, ib)| {
            seams_between(surfaces, live[ia], live[ib], tol, matching, model, opts)
        })
        .collect();
    seams.sort_by(|x, y| {
        (x.surfaces, x.sides)
            .cmp(&(y.surfaces, y.sides))
            .then(x.range[0].total_cmp(&y.range[0]))
    });
    opts.control.step("measuring shared edges", 3, 3)?;
    Ok(ContinuityReport {
        classes: ClassCounts::of(&seams),
        seams,
        tolerance: tol,
        match_distance: matching,
        degenerate_sides: dead.len(),
    })
}

/// The shared stretches of sides `a` and `b`, measured.
fn seams_between(
    surfaces: &[BSplineSurface],
    a: &SideSamples,
    b: &SideSamples,
    tol: f64,
    matching: f64,
    model: f64,
    opts: &ContinuityOptions,
) -> Vec<Seam> {
    let (sa, sb) = (&surfaces[a.surface], &surfaces[b.surface]);
    let rb = b.range(sb);
    // A point of a is on the shared stretch when b passes within the
    // matching distance, and not only past b's end (then the closest point
    // is b's end point, unless it is within the tolerance).
    let on = |t: f64| -> bool {
        let (u, v) = a.uv(sa, t);
        let (tb, d) = closest_on_side(sb, b, sa.eval(u, v));
        let end = (tb - rb[0]).abs() <= 1e-12 * (rb[1] - rb[0]).abs()
            || (tb - rb[1]).abs() <= 1e-12 * (rb[1] - rb[0]).abs();
        d <= matching && (!end || d <= tol)
    };
    let flags: Vec<bool> = a.ts.iter().map(|&t| on(t)).collect();
    let mut out = Vec::new();
    let n = flags.len();
    let mut k = 0;
    while k < n {
        if !flags[k] {
            k += 1;
            continue;
        }
        let s = k;
        while k < n && flags[k] {
            k += 1;
        }
        let e = k - 1; // last flagged
        // refine the ends by bisection between a flagged and an unflagged sample
        let refine = |inside: f64, outside: f64| {
            let (mut i, mut o) = (inside, outside);
            for _ in 0..30 {
                let m = 0.5 * (i + o);
                if on(m) { i = m } else { o = m }
            }
            i
        };
        let t0 = if s > 0 {
            refine(a.ts[s], a.ts[s - 1])
        } else {
            a.ts[s]
        };
        let t1 = if e + 1 < n {
            refine(a.ts[e], a.ts[e + 1])
        } else {
            a.ts[e]
        };
        if !(t1 > t0) {
            continue;
        }
        let m = opts.samples;
        let ts: Vec<f64> = (0..=m)
            .map(|j| t0 + (t1 - t0) * j as f64 / m as f64)
            .collect();
        let measured: Vec<(Vec3, SampleMeasure)> = ts
            .iter()
            .map(|&t| measure(sa, a, sb, b, t, model))
            .collect();
        let points: Vec<Vec3> = measured.iter().map(|x| x.0).collect();
        let length: f64 = points.windows(2).map(|w| (w[1] - w[0]).length()).sum();
        // a corner touch or a crossing, not an edge
        if length <= 2.0 * matching {
            continue;
        }
        let mut g0 = (0.0f64, points[0]);
        let mut g1 = (0.0f64, points[0]);
        let mut g2 = 0.0f64;
        let mut g2r = (0.0f64, points[0]);
        let mut degenerate = 0;
        for (p, (gap, rest)) in &measured {
            if *gap > g0.0 {
                g0 = (*gap, *p);
            }
            match rest {
                Some((ang, diff, rel)) => {
                    if *ang > g1.0 {
                        g1 = (*ang, *p);
                    }
                    g2 = g2.max(*diff);
                    if *rel > g2r.0 {
                        g2r = (*rel, *p);
                    }
                }
                None => degenerate += 1,
            }
        }
        let class = if g0.0 > tol {
            SeamClass::Gap
        } else if g1.0 > opts.angle_tolerance_deg {
            SeamClass::G0
        } else if g2r.0 > opts.curvature_tolerance {
            SeamClass::G1
        } else {
            SeamClass::G2
        };
        let worst = match class {
            SeamClass::Gap => g0.1,
            SeamClass::G0 => g1.1,
            SeamClass::G1 | SeamClass::G2 => g2r.1,
        };
        out.push(Seam {
            surfaces: [a.surface, b.surface],
            sides: [a.side, b.side],
            range: [t0, t1],
            length,
            g0_max: g0.0,
            g1_max_deg: g1.0,
            g2_max: g2,
            g2_max_relative: g2r.0,
            class,
            worst,
            samples: measured.len(),
            degenerate_samples: degenerate,
            points,
        });
    }
    out
}

#[cfg(test)]
mod tests;
