//! STEP export (ISO 10303-21, AP214 `AUTOMOTIVE_DESIGN` schema) of
//! (trimmed) B-spline surfaces.
//!
//! - An untrimmed surface is a `B_SPLINE_SURFACE_WITH_KNOTS` (rational: the
//!   complex instance with `RATIONAL_B_SPLINE_SURFACE`), an element of a
//!   `GEOMETRIC_SET` in a `GEOMETRICALLY_BOUNDED_SURFACE_SHAPE_REPRESENTATION`.
//! - A trimmed surface is an `ADVANCED_FACE` on it, in an `OPEN_SHELL` of a
//!   `SHELL_BASED_SURFACE_MODEL` (`MANIFOLD_SURFACE_SHAPE_REPRESENTATION`).
//!   Each trim loop is an `EDGE_LOOP`; each of its curves an `EDGE_CURVE`
//!   whose `SURFACE_CURVE` carries the exact trim curve as a `PCURVE` (a 2-D
//!   B-spline curve) and, as the 3-D curve, a B-spline curve with the trim
//!   curve's parameter (see `edge_curve`): exact where the curve on the
//!   surface is one (on a plane, along an iso-parameter line), elsewhere a
//!   cubic fitted to [`FIT_TOLERANCE`] × the part's size. Kernels such as
//!   OpenCASCADE build the faces' edges from the 3-D curves and check that
//!   the p-curves agree with them within the file's uncertainty, which is
//!   written as at least 10 × that tolerance and at least the largest
//!   distance a fitted curve has from the curve on the surface. Vertices
//!   lie exactly on the surface at the curves' ends.
//!
//! Reals are written in the shortest form that reads back to the same
//! `f64` (the syntax is the same as IGES's), knots as distinct values with
//! multiplicities (equal only when bit-identical), so that
//! [`super::read_step`] gives every control point, knot, weight and trim
//! curve back bit-identical. Complex instances list their partial entities
//! in alphabetical order (ISO 10303-21 §11.2.5.3).

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use crate::Vec3;

use super::edge_curve::edge_curve;
use crate::bspline::{BSplineSurface, TrimCurve, control_diagonal};
use crate::io::iges_write::{iges_real as real, iges_timestamp};
use crate::io::model_curve::ModelCurve;
use crate::io::units::LengthUnit;
use crate::io::{IoError, atomic_write};

/// The tolerance of fitted 3-D edge curves, relative to the diagonal of
/// the control points' bounding box of all surfaces written.
pub const FIT_TOLERANCE: f64 = 1e-8;

/// What the header and unit context of a written STEP file say.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct StepWriteOptions {
    /// The length unit of the coordinates.
    pub unit: LengthUnit,
    /// Time stamp `YYYY-MM-DDTHH:MM:SS` of FILE_NAME.
    pub timestamp: String,
    /// Product name.
    pub product: String,
}

crate::control::setters!(StepWriteOptions {
    unit: LengthUnit,
    timestamp: String,
    product: String,
});

impl Default for StepWriteOptions {
    fn default() -> Self {
        let t = iges_timestamp(std::time::SystemTime::now());
        Self {
            unit: LengthUnit::millimetre(),
            timestamp: format!(
                "{}-{}-{}T{}:{}:{}",
                &t[0..4],
                &t[4..6],
                &t[6..8],
                &t[9..11],
                &t[11..13],
                &t[13..15]
            ),
            product: "fairline".into(),
        }
    }
}

/// Instances being written: `#id=` text, ids handed out in order.
#[derive(Default)]
struct Data {
    text: String,
    next: u64,
}

impl Data {
    fn add(&mut self, body: impl AsRef<str>) -> u64 {
        self.next += 1;
        let _ = writeln!(self.text, "#{}={};", self.next, body.as_ref());
        self.next
    }

    fn point(&mut self, p: Vec3) -> u64 {
        self.add(format!(
            "CARTESIAN_POINT('',({},{},{}))",
            real(p.x),
            real(p.y),
            real(p.z)
        ))
    }

    fn point2(&mut self, p: [f64; 2]) -> u64 {
        self.add(format!(
            "CARTESIAN_POINT('',({},{}))",
            real(p[0]),
            real(p[1])
        ))
    }
}

fn refs(ids: &[u64]) -> String {
    let v: Vec<String> = ids.iter().map(|i| format!("#{i}")).collect();
    format!("({})", v.join(","))
}

fn reals(xs: &[f64]) -> String {
    let v: Vec<String> = xs.iter().map(|&x| real(x)).collect();
    format!("({})", v.join(","))
}

/// Distinct knots (bit-identical runs) and their multiplicities.
fn knot_runs(knots: &[f64]) -> (String, String) {
    let mut values: Vec<f64> = Vec::new();
    let mut mults: Vec<usize> = Vec::new();
    for &k in knots {
        match values.last() {
            Some(l) if l.to_bits() == k.to_bits() => {
                if let Some(m) = mults.last_mut() {
                    *m += 1;
                }
            }
            _ => {
                values.push(k);
                mults.push(1);
            }
        }
    }
    let m: Vec<String> = mults.iter().map(usize::to_string).collect();
    (format!("({})", m.join(",")), reals(&values))
}

fn step_string(s: &str) -> String {
    s.replace('\'', "''")
}

/// Writes the B-spline surface and returns its id.
fn surface(d: &mut Data, s: &BSplineSurface) -> u64 {
    let (nu, nv) = (s.count_u(), s.count_v());
    let mut rows = Vec::with_capacity(nu);
    for i in 0..nu {
        let row: Vec<u64> = (0..nv).map(|j| d.point(s.control_point(i, j))).collect();
        rows.push(refs(&row));
    }
    let net = format!("({})", rows.join(","));
    let (mu, ku) = knot_runs(s.knots_u());
    let (mv, kv) = knot_runs(s.knots_v());
    let (p, q) = (s.degree_u(), s.degree_v());
    if s.is_rational() {
        let w: Vec<String> = (0..nu)
            .map(|i| reals(&(0..nv).map(|j| s.weight(i, j)).collect::<Vec<_>>()))
            .collect();
        d.add(format!(
            "(BOUNDED_SURFACE()B_SPLINE_SURFACE({p},{q},{net},.UNSPECIFIED.,.F.,.F.,.F.)\
             B_SPLINE_SURFACE_WITH_KNOTS({mu},{mv},{ku},{kv},.UNSPECIFIED.)\
             GEOMETRIC_REPRESENTATION_ITEM()RATIONAL_B_SPLINE_SURFACE(({}))\
             REPRESENTATION_ITEM('')SURFACE())",
            w.join(",")
        ))
    } else {
        d.add(format!(
            "B_SPLINE_SURFACE_WITH_KNOTS('',{p},{q},{net},.UNSPECIFIED.,.F.,.F.,.F.,{mu},{mv},{ku},{kv},.UNSPECIFIED.)"
        ))
    }
}

/// Writes a 2-D trim curve as a B-spline curve and returns its id.
fn curve2(d: &mut Data, c: &TrimCurve) -> u64 {
    let pts: Vec<u64> = c.control_points().iter().map(|&p| d.point2(p)).collect();
    let (m, k) = knot_runs(c.knots());
    let deg = c.degree();
    let pts = refs(&pts);
    match c.weights() {
        Some(w) => d.add(format!(
            "(BOUNDED_CURVE()B_SPLINE_CURVE({deg},{pts},.UNSPECIFIED.,.F.,.F.)\
             B_SPLINE_CURVE_WITH_KNOTS({m},{k},.UNSPECIFIED.)CURVE()\
             GEOMETRIC_REPRESENTATION_ITEM()RATIONAL_B_SPLINE_CURVE({})REPRESENTATION_ITEM(''))",
            reals(w)
        )),
        None => d.add(format!(
            "B_SPLINE_CURVE_WITH_KNOTS('',{deg},{pts},.UNSPECIFIED.,.F.,.F.,{m},{k},.UNSPECIFIED.)"
        )),
    }
}

/// Writes a 3-D (rational) B-spline curve and returns its id.
fn curve3(d: &mut Data, c: &ModelCurve) -> u64 {
    let pts: Vec<u64> = c.points.iter().map(|&p| d.point(p)).collect();
    let closed = match (c.points.first(), c.points.last()) {
        (Some(a), Some(b)) if a == b && c.points.len() > 2 => ".T.",
        _ => ".F.",
    };
    let (m, k) = knot_runs(&c.knots);
    let deg = c.degree;
    let pts = refs(&pts);
    match &c.weights {
        Some(w) => d.add(format!(
            "(BOUNDED_CURVE()B_SPLINE_CURVE({deg},{pts},.UNSPECIFIED.,{closed},.F.)\
             B_SPLINE_CURVE_WITH_KNOTS({m},{k},.UNSPECIFIED.)CURVE()\
             GEOMETRIC_REPRESENTATION_ITEM()RATIONAL_B_SPLINE_CURVE({})REPRESENTATION_ITEM(''))",
            reals(w)
        )),
        None => d.add(format!(
            "B_SPLINE_CURVE_WITH_KNOTS('',{deg},{pts},.UNSPECIFIED.,{closed},.F.,{m},{k},.UNSPECIFIED.)"
        )),
    }
}

/// Writes the face of a trimmed surface and returns its id; `fit` is the
/// tolerance of fitted edge curves, `deviation` grows to the largest
/// distance of a written edge curve from its curve on the surface.
fn face(d: &mut Data, s: &BSplineSurface, ctx2: u64, fit: f64, deviation: &mut f64) -> u64 {
    let sid = surface(d, s);
    let mut bounds = Vec::new();
    for (l, lp) in s.trims().iter().enumerate() {
        let n = lp.curves.len();
        // One vertex per curve start; a curve ends at the next one's start
        // vertex when their points coincide to rounding (1e-12 of the
        // parameter domain's diagonal: a closed curve is one edge from its
        // vertex back to it, not an edge between two vertices at one place).
        let (du, dv) = (s.domain_u(), s.domain_v());
        let joint = 1e-12 * (du[1] - du[0]).hypot(dv[1] - dv[0]);
        let starts: Vec<[f64; 2]> = lp.curves.iter().map(|c| c.eval(c.domain()[0])).collect();
        let verts: Vec<u64> = starts
            .iter()
            .map(|&[u, v]| {
                let p = d.point(s.eval(u, v));
                d.add(format!("VERTEX_POINT('',#{p})"))
            })
            .collect();
        let mut edges = Vec::with_capacity(n);
        for (k, c) in lp.curves.iter().enumerate() {
            let end2 = c.eval(c.domain()[1]);
            let next = starts[(k + 1) % n];
            let v_end = if (end2[0] - next[0]).hypot(end2[1] - next[1]) <= joint {
                verts[(k + 1) % n]
            } else {
                let p = d.point(s.eval(end2[0], end2[1]));
                d.add(format!("VERTEX_POINT('',#{p})"))
            };
            let (e3, _, dev) = edge_curve(s, c, fit);
            if dev.is_finite() {
                *deviation = deviation.max(dev);
            }
            let c3 = curve3(d, &e3);
            let c2 = curve2(d, c);
            let dr = d.add(format!("DEFINITIONAL_REPRESENTATION('',(#{c2}),#{ctx2})"));
            let pc = d.add(format!("PCURVE('',#{sid},#{dr})"));
            let sc = d.add(format!("SURFACE_CURVE('',#{c3},(#{pc}),.PCURVE_S1.)"));
            let ec = d.add(format!("EDGE_CURVE('',#{},#{v_end},#{sc},.T.)", verts[k]));
            edges.push(d.add(format!("ORIENTED_EDGE('',*,*,#{ec},.T.)")));
        }
        let el = d.add(format!("EDGE_LOOP('',{})", refs(&edges)));
        let kind = if l == 0 {
            "FACE_OUTER_BOUND"
        } else {
            "FACE_BOUND"
        };
        bounds.push(d.add(format!("{kind}('',#{el},.T.)")));
    }
    d.add(format!("ADVANCED_FACE('',{},#{sid},.T.)", refs(&bounds)))
}

/// The length unit instance(s); returns the id of the unit.
fn length_unit(d: &mut Data, unit: &LengthUnit) -> u64 {
    let si = [
        (1e-3, ".MILLI."),
        (1e-2, ".CENTI."),
        (1.0, "$"),
        (1e3, ".KILO."),
        (1e-6, ".MICRO."),
    ];
    if let Some((_, prefix)) = si
        .iter()
        .find(|(m, _)| (m - unit.metres).abs() <= 1e-12 * m)
    {
        return d.add(format!(
            "(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT({prefix},.METRE.))"
        ));
    }
    let metre = d.add("(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT($,.METRE.))");
    let m = d.add(format!(
        "LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE({}),#{metre})",
        real(unit.metres)
    ));
    let dims = d.add("DIMENSIONAL_EXPONENTS(1.,0.,0.,0.,0.,0.,0.)");
    let name = if unit.iges_name() == "IN" {
        "INCH".to_string()
    } else {
        unit.name.clone()
    };
    d.add(format!(
        "(CONVERSION_BASED_UNIT('{}',#{m})LENGTH_UNIT()NAMED_UNIT(#{dims}))",
        step_string(&name)
    ))
}

/// The whole STEP file for `surfaces`; see the module documentation.
/// Fails when a string of the options is not plain printable ASCII.
pub fn surfaces_to_step(
    surfaces: &[BSplineSurface],
    options: &StepWriteOptions,
) -> Result<String, String> {
    for (what, s) in [
        ("unit name", &options.unit.name),
        ("timestamp", &options.timestamp),
        ("product name", &options.product),
    ] {
        if !s.bytes().all(|c| (b' '..=b'~').contains(&c) && c != b'\\') {
            return Err(format!(
                "the {what} `{s}` is not plain printable ASCII (no backslash)"
            ));
        }
    }
    if !(options.unit.metres > 0.0 && options.unit.metres.is_finite()) {
        return Err(format!(
            "the unit size {} m is not positive",
            options.unit.metres
        ));
    }
    let product = step_string(&options.product);
    let mut d = Data::default();
    let app = d.add("APPLICATION_CONTEXT('automotive design')");
    d.add(format!(
        "APPLICATION_PROTOCOL_DEFINITION('international standard','automotive_design',2000,#{app})"
    ));
    let pc = d.add(format!("PRODUCT_CONTEXT('',#{app},'mechanical')"));
    let prod = d.add(format!("PRODUCT('{product}','{product}','',(#{pc}))"));
    let pdf = d.add(format!("PRODUCT_DEFINITION_FORMATION('','',#{prod})"));
    let pdc = d.add(format!(
        "PRODUCT_DEFINITION_CONTEXT('part definition',#{app},'design')"
    ));
    let pd = d.add(format!("PRODUCT_DEFINITION('design','',#{pdf},#{pdc})"));
    let pds = d.add(format!("PRODUCT_DEFINITION_SHAPE('','',#{pd})"));
    let ctx2 = d.add(
        "(GEOMETRIC_REPRESENTATION_CONTEXT(2)PARAMETRIC_REPRESENTATION_CONTEXT()\
         REPRESENTATION_CONTEXT('2D SPACE',''))",
    );
    let fit = FIT_TOLERANCE * control_diagonal(surfaces);
    let mut deviation = 0.0f64;
    let mut faces = Vec::new();
    let mut free = Vec::new();
    for s in surfaces {
        if s.is_trimmed() {
            faces.push(face(&mut d, s, ctx2, fit, &mut deviation));
        } else {
            free.push(surface(&mut d, s));
        }
    }
    // The uncertainty: at least 1e-7 (of the file's unit) and 10 times the
    // fitting tolerance, and never less than the largest distance of a
    // written edge curve from its curve on the surface.
    let uncertainty = (10.0 * fit).max(1e-7).max(deviation);
    let lu = length_unit(&mut d, &options.unit);
    let au = d.add("(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.))");
    let su = d.add("(NAMED_UNIT(*)SI_UNIT($,.STERADIAN.)SOLID_ANGLE_UNIT())");
    let unc = d.add(format!(
        "UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE({}),#{lu},'distance_accuracy_value','')",
        real(uncertainty)
    ));
    let ctx = d.add(format!(
        "(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#{unc}))\
         GLOBAL_UNIT_ASSIGNED_CONTEXT((#{lu},#{au},#{su}))REPRESENTATION_CONTEXT('',''))"
    ));
    if !faces.is_empty() {
        let shell = d.add(format!("OPEN_SHELL('',{})", refs(&faces)));
        let model = d.add(format!("SHELL_BASED_SURFACE_MODEL('',(#{shell}))"));
        let rep = d.add(format!(
            "MANIFOLD_SURFACE_SHAPE_REPRESENTATION('{product}',(#{model}),#{ctx})"
        ));
        d.add(format!("SHAPE_DEFINITION_REPRESENTATION(#{pds},#{rep})"));
    }
    if !free.is_empty() {
        let set = d.add(format!("GEOMETRIC_SET('',{})", refs(&free)));
        let rep = d.add(format!(
            "GEOMETRICALLY_BOUNDED_SURFACE_SHAPE_REPRESENTATION('{product}',(#{set}),#{ctx})"
        ));
        d.add(format!("SHAPE_DEFINITION_REPRESENTATION(#{pds},#{rep})"));
    }
    let mut out = String::new();
    out.push_str("ISO-10303-21;\nHEADER;\n");
    let _ = writeln!(
        out,
        "FILE_DESCRIPTION(('fairline B-spline surfaces'),'2;1');\n\
         FILE_NAME('{product}.step','{}',(''),(''),'fairline {}','fairline','');\n\
         FILE_SCHEMA(('AUTOMOTIVE_DESIGN {{ 1 0 10303 214 1 1 1 1 }}'));\nENDSEC;\nDATA;",
        options.timestamp,
        env!("CARGO_PKG_VERSION")
    );
    out.push_str(&d.text);
    out.push_str("ENDSEC;\nEND-ISO-10303-21;\n");
    Ok(out)
}

/// Writes `surfaces` as a STEP file (see the module documentation),
/// atomically through [`atomic_write`].
pub fn write_step(
    path: impl AsRef<Path>,
    surfaces: &[BSplineSurface],
    options: &StepWriteOptions,
) -> Result<(), IoError> {
    let path = path.as_ref();
    let text = surfaces_to_step(surfaces, options).map_err(|message| IoError::InvalidData {
        path: path.to_path_buf(),
        message,
    })?;
    atomic_write(path, |w| w.write_all(text.as_bytes()))
}
