//! IGES export of (trimmed) B-spline surfaces: the way back to CAD.
//!
//! Writes fixed-format ASCII IGES 5.3 (§2): 80-column records, section
//! letter in column 73 and sequence number in columns 74–80; parameter data
//! in columns 1–64 with the directory-entry back-pointer in columns 66–72.
//! Delimiters are the defaults `,` and `;`, strings are Hollerith `nH…`, and
//! no parameter is split over two records.
//!
//! Every surface becomes an entity 128 (rational B-spline surface, IGES 5.3
//! §4.24: `K1 K2 M1 M2 PROP1..5`, knots, weights and control points with the
//! u index fastest, `U0 U1 V0 V1`). A trimmed surface additionally gets an
//! entity 144 (trimmed parametric surface, §4.34) whose outer and inner
//! boundaries are entities 142 (curve on a parametric surface, §4.32) with
//! the loop's parameter-space curves as entities 126 (rational B-spline
//! curve, §4.23, `z = 0`, planar), joined by an entity 102 (composite curve,
//! §4.4) when a loop has more than one. The model-space copy of a boundary
//! (142's `CPTR`) is not written (`CPTR = 0`, `PREF = 1`: the parameter
//! space curve is the preferred representation).
//!
//! [`curves_to_iges`] writes model-space curves instead (highlight lines
//! as curves): each an independent entity 126, not planar, named by the
//! directory entry's label and subscript (fields 18–19).
//!
//! Reals are written in Rust's shortest round-trip form (`{:?}`, with the
//! exponent as `E` and a decimal point always present), so that reading the
//! file back with [`crate::io::read_iges`] gives every control point,
//! knot and weight bit-identical, and the same trimming curves.

use std::io::Write;
use std::path::Path;

use super::model_curve::ModelCurve;
use super::units::LengthUnit;
use super::{IoError, atomic_write};
use crate::bspline::{BSplineSurface, TrimCurve};

/// What the Global section of a written IGES file says.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct IgesWriteOptions {
    /// The length unit of the coordinates (Global fields 14–15).
    pub unit: LengthUnit,
    /// Date and time of generation, `YYYYMMDD.HHNNSS` (Global field 18).
    pub timestamp: String,
    /// Product name (Global fields 3 and 12).
    pub product: String,
}

crate::control::setters!(IgesWriteOptions {
    unit: LengthUnit,
    timestamp: String,
    product: String,
});

impl Default for IgesWriteOptions {
    fn default() -> Self {
        Self {
            unit: LengthUnit::millimetre(),
            timestamp: iges_timestamp(std::time::SystemTime::now()),
            product: "fairline".into(),
        }
    }
}

/// `YYYYMMDD.HHNNSS` (UTC) of a system time (IGES 5.3 §2.2.4.3 field 18).
pub fn iges_timestamp(t: std::time::SystemTime) -> String {
    let secs = t
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    // Civil date from days since 1970-01-01 (H. Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}{month:02}{day:02}.{:02}{:02}{:02}",
        rem / 3600,
        (rem / 60) % 60,
        rem % 60
    )
}

/// An IGES real in the shortest form that reads back to the same `f64`:
/// `1.0`, `0.125`, `1.E-7`, `-2.5E20`.
pub fn iges_real(x: f64) -> String {
    let s = format!("{x:?}");
    match s.split_once('e') {
        None => s,
        Some((mantissa, exponent)) => {
            let dot = if mantissa.contains('.') { "" } else { "." };
            format!("{mantissa}{dot}E{exponent}")
        }
    }
}

/// A Hollerith string `nH…`.
fn hollerith(s: &str) -> String {
    format!("{}H{s}", s.len())
}

/// One entity to be written: type, form, status number and parameters
/// (without the leading entity type and the record delimiter).
struct Entity {
    entity_type: i64,
    form: i64,
    status: &'static str,
    params: Vec<String>,
    /// Entity label and subscript (directory fields 18 and 19), shown
    /// by CAD systems as the entity's name.
    name: Option<(String, usize)>,
}

/// Status numbers (IGES 5.3 §2.2.4.4.9): visible; independent or physically
/// dependent; geometry or 2-D parametric use; global top-down hierarchy.
const INDEPENDENT: &str = "00000000";
const DEPENDENT: &str = "00010000";
const DEPENDENT_PARAMETRIC: &str = "00010500";

/// Collects entities and hands out their directory-entry pointers.
#[derive(Default)]
struct Model {
    entities: Vec<Entity>,
}

impl Model {
    /// Adds an entity and returns its directory-entry pointer (odd).
    fn push(&mut self, entity: Entity) -> usize {
        self.entities.push(entity);
        2 * self.entities.len() - 1
    }

    fn add_surface(&mut self, s: &BSplineSurface) {
        let trimmed = s.is_trimmed();
        let surface = self.push(Entity {
            entity_type: 128,
            form: 0,
            status: if trimmed { DEPENDENT } else { INDEPENDENT },
            params: entity_128(s),
            name: None,
        });
        if !trimmed {
            return;
        }
        let mut boundaries = Vec::with_capacity(s.trims().len());
        for lp in s.trims() {
            let members: Vec<usize> = lp
                .curves
                .iter()
                .map(|c| {
                    self.push(Entity {
                        entity_type: 126,
                        form: 0,
                        status: DEPENDENT_PARAMETRIC,
                        params: entity_126(c),
                        name: None,
                    })
                })
                .collect();
            let curve = if members.len() == 1 {
                members[0]
            } else {
                let mut params = vec![members.len().to_string()];
                params.extend(members.iter().map(usize::to_string));
                self.push(Entity {
                    entity_type: 102,
                    form: 0,
                    status: DEPENDENT_PARAMETRIC,
                    params,
                    name: None,
                })
            };
            // CRTN = 0 (unspecified), SPTR, BPTR, CPTR = 0, PREF = 1.
            boundaries.push(self.push(Entity {
                entity_type: 142,
                form: 0,
                status: DEPENDENT,
                params: vec![
                    "0".into(),
                    surface.to_string(),
                    curve.to_string(),
                    "0".into(),
                    "1".into(),
                ],
                name: None,
            }));
        }
        // PTS, N1 = 1 (outer boundary given), N2 holes, PTO, PTI…
        let mut params = vec![
            surface.to_string(),
            "1".into(),
            (boundaries.len() - 1).to_string(),
        ];
        params.extend(boundaries.iter().map(usize::to_string));
        self.push(Entity {
            entity_type: 144,
            form: 0,
            status: INDEPENDENT,
            params,
            name: None,
        });
    }
}

/// Parameters of entity 128 (IGES 5.3 §4.24).
fn entity_128(s: &BSplineSurface) -> Vec<String> {
    let (nu, nv) = (s.count_u(), s.count_v());
    let closed_u = (0..nv).all(|j| s.control_point(0, j) == s.control_point(nu - 1, j));
    let closed_v = (0..nu).all(|i| s.control_point(i, 0) == s.control_point(i, nv - 1));
    let mut p = Vec::with_capacity(14 + s.knots_u().len() + s.knots_v().len() + 4 * nu * nv);
    for x in [nu - 1, nv - 1, s.degree_u(), s.degree_v()] {
        p.push(x.to_string());
    }
    p.push(u8::from(closed_u).to_string());
    p.push(u8::from(closed_v).to_string());
    p.push(u8::from(!s.is_rational()).to_string());
    p.push("0".into());
    p.push("0".into());
    p.extend(s.knots_u().iter().map(|&k| iges_real(k)));
    p.extend(s.knots_v().iter().map(|&k| iges_real(k)));
    // Weights and control points with the u index fastest.
    for j in 0..nv {
        for i in 0..nu {
            p.push(iges_real(s.weight(i, j)));
        }
    }
    for j in 0..nv {
        for i in 0..nu {
            let q = s.control_point(i, j);
            p.extend([q.x, q.y, q.z].map(iges_real));
        }
    }
    let ([u0, u1], [v0, v1]) = (s.domain_u(), s.domain_v());
    p.extend([u0, u1, v0, v1].map(iges_real));
    p
}

/// Parameters of entity 126 (IGES 5.3 §4.23) for a parameter-space curve:
/// planar in `z = 0`, normal `(0, 0, 1)`.
fn entity_126(c: &TrimCurve) -> Vec<String> {
    let pts = c.control_points();
    let n = pts.len();
    let closed = pts.first() == pts.last();
    let mut p = Vec::with_capacity(12 + c.knots().len() + 4 * n);
    p.push((n - 1).to_string());
    p.push(c.degree().to_string());
    p.push("1".into());
    p.push(u8::from(closed).to_string());
    p.push(u8::from(c.weights().is_none()).to_string());
    p.push("0".into());
    p.extend(c.knots().iter().map(|&k| iges_real(k)));
    match c.weights() {
        Some(w) => p.extend(w.iter().map(|&w| iges_real(w))),
        None => p.extend(std::iter::repeat_n("1.0".to_string(), n)),
    }
    for q in pts {
        p.extend([q[0], q[1], 0.0].map(iges_real));
    }
    let [t0, t1] = c.domain();
    p.extend([t0, t1, 0.0, 0.0, 1.0].map(iges_real));
    p
}

/// Packs delimited parameters into records of `width` columns without
/// splitting a parameter (one longer than a record is cut, which only a
/// Hollerith string can be).
fn pack(params: &[String], width: usize) -> Vec<String> {
    let mut lines = Vec::new();
    let mut cur = String::new();
    let last = params.len().saturating_sub(1);
    for (k, p) in params.iter().enumerate() {
        let item = format!("{p}{}", if k == last { ';' } else { ',' });
        if cur.len() + item.len() > width && !cur.is_empty() {
            lines.push(std::mem::take(&mut cur));
        }
        if item.len() > width {
            let mut rest = item.as_str();
            while rest.len() > width {
                let (a, b) = rest.split_at(width);
                lines.push(a.to_string());
                rest = b;
            }
            cur.push_str(rest);
        } else {
            cur.push_str(&item);
        }
    }
    if !cur.is_empty() {
        lines.push(cur);
    }
    lines
}

/// The whole IGES file for `surfaces`; see the module documentation.
/// Fails when a string of the options is not plain printable ASCII.
pub fn surfaces_to_iges(
    surfaces: &[BSplineSurface],
    options: &IgesWriteOptions,
) -> Result<String, String> {
    check_options(options)?;
    let mut model = Model::default();
    for s in surfaces {
        model.add_surface(s);
    }
    Ok(model_text(
        &model,
        options,
        "fairline: B-spline surfaces (entity 128, trims as 144/142/126)",
    ))
}

/// Fails when a string of the options is not plain printable ASCII of at
/// most 60 characters.
fn check_options(options: &IgesWriteOptions) -> Result<(), String> {
    for (what, s) in [
        ("unit name", &options.unit.name),
        ("timestamp", &options.timestamp),
        ("product name", &options.product),
    ] {
        if !s.bytes().all(|c| (b' '..=b'~').contains(&c)) || s.len() > 60 {
            return Err(format!(
                "the {what} `{s}` is not plain ASCII of at most 60 characters"
            ));
        }
    }
    Ok(())
}

/// A model-space curve to be written, with the name a CAD system shows
/// for it: a label of at most 8 printable ASCII characters and a number.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedCurve {
    /// The curve.
    pub curve: ModelCurve,
    /// Label (directory field 18; cut to 8 characters, spaces removed).
    pub label: String,
    /// Subscript (directory field 19).
    pub number: usize,
}

/// The whole IGES file for model-space curves: each an independent entity
/// 126 (rational B-spline curve, IGES 5.3 §4.23, non-planar) named by its
/// label and number. Fails when a string of the options is not plain
/// printable ASCII, or a curve's knot vector does not fit its points.
pub fn curves_to_iges(curves: &[NamedCurve], options: &IgesWriteOptions) -> Result<String, String> {
    check_options(options)?;
    let mut model = Model::default();
    for (k, c) in curves.iter().enumerate() {
        let m = &c.curve;
        if m.points.len() < 2
            || m.knots.len() != m.points.len() + m.degree + 1
            || m.weights
                .as_ref()
                .is_some_and(|w| w.len() != m.points.len())
        {
            return Err(format!(
                "curve {k} ({} {}): {} control points, degree {}, {} knots",
                c.label,
                c.number,
                m.points.len(),
                m.degree,
                m.knots.len()
            ));
        }
        let label: String = c
            .label
            .chars()
            .filter(|ch| ch.is_ascii_graphic())
            .take(8)
            .collect();
        model.push(Entity {
            entity_type: 126,
            form: 0,
            status: INDEPENDENT,
            params: entity_126_model(m),
            name: Some((label, c.number)),
        });
    }
    Ok(model_text(
        &model,
        options,
        "fairline: model-space curves (entity 126)",
    ))
}

/// Parameters of entity 126 for a model-space curve (not planar).
fn entity_126_model(c: &ModelCurve) -> Vec<String> {
    let n = c.points.len();
    let closed = c.points.first() == c.points.last();
    let mut p = Vec::with_capacity(12 + c.knots.len() + 4 * n);
    p.push((n - 1).to_string());
    p.push(c.degree.to_string());
    p.push("0".into());
    p.push(u8::from(closed).to_string());
    p.push(u8::from(c.weights.is_none()).to_string());
    p.push("0".into());
    p.extend(c.knots.iter().map(|&k| iges_real(k)));
    match &c.weights {
        Some(w) => p.extend(w.iter().map(|&w| iges_real(w))),
        None => p.extend(std::iter::repeat_n("1.0".to_string(), n)),
    }
    for q in &c.points {
        p.extend([q.x, q.y, q.z].map(iges_real));
    }
    let (t0, t1) = (c.knots[c.degree], c.knots[n]);
    p.extend([t0, t1, 0.0, 0.0, 0.0].map(iges_real));
    p
}

/// Writes `curves` as an IGES file ([`curves_to_iges`]), atomically.
pub fn write_curves_iges(
    path: impl AsRef<Path>,
    curves: &[NamedCurve],
    options: &IgesWriteOptions,
) -> Result<(), IoError> {
    let path = path.as_ref();
    let text = curves_to_iges(curves, options).map_err(|message| IoError::InvalidData {
        path: path.to_path_buf(),
        message,
    })?;
    atomic_write(path, |w| w.write_all(text.as_bytes()))
}

/// The text of an IGES file of `model`: start section `summary`, the
/// global section of `options`, directory and parameter data, terminate.
fn model_text(model: &Model, options: &IgesWriteOptions, summary: &str) -> String {
    let mut out = String::new();
    let record = |out: &mut String, data: &str, letter: char, seq: usize| {
        out.push_str(&format!("{data:<72}{letter}{seq:>7}\n"));
    };
    record(&mut out, summary, 'S', 1);
    let product = hollerith(&options.product);
    let unit = options.unit.iges_name();
    let global: Vec<String> = vec![
        "1H,".into(),
        "1H;".into(),
        product.clone(),
        hollerith(&format!("{}.igs", options.product)),
        hollerith("fairline"),
        hollerith(env!("CARGO_PKG_VERSION")),
        "32".into(),
        "308".into(),
        "15".into(),
        "308".into(),
        "15".into(),
        product,
        "1.0".into(),
        options.unit.iges_flag().to_string(),
        hollerith(&unit),
        "1".into(),
        "0.0".into(),
        hollerith(&options.timestamp),
        "1.E-10".into(),
        "0.0".into(),
        hollerith(""),
        hollerith(""),
        "11".into(),
        "0".into(),
        hollerith(&options.timestamp),
    ];
    let g_lines = pack(&global, 72);
    for (k, l) in g_lines.iter().enumerate() {
        record(&mut out, l, 'G', k + 1);
    }
    let mut dir = String::new();
    let mut par = String::new();
    let mut pseq = 1;
    for (k, e) in model.entities.iter().enumerate() {
        let de = 2 * k + 1;
        let mut params = Vec::with_capacity(e.params.len() + 1);
        params.push(e.entity_type.to_string());
        params.extend(e.params.iter().cloned());
        let lines = pack(&params, 64);
        let t = e.entity_type;
        dir.push_str(&format!(
            "{t:>8}{pseq:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}D{de:>7}\n",
            0, 0, 0, 0, 0, 0, e.status
        ));
        let (label, number) = match &e.name {
            Some((l, n)) => (l.as_str(), *n),
            None => ("", 0),
        };
        dir.push_str(&format!(
            "{t:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{label:>8}{number:>8}D{:>7}\n",
            0,
            0,
            lines.len(),
            e.form,
            "",
            "",
            de + 1
        ));
        for l in lines {
            par.push_str(&format!("{l:<64} {de:>7}P{pseq:>7}\n"));
            pseq += 1;
        }
    }
    out.push_str(&dir);
    out.push_str(&par);
    let terminate = format!(
        "S{:>7}G{:>7}D{:>7}P{:>7}",
        1,
        g_lines.len(),
        2 * model.entities.len(),
        pseq - 1
    );
    record(&mut out, &terminate, 'T', 1);
    out
}

/// Writes `surfaces` as an IGES file (see the module documentation),
/// atomically through [`atomic_write`].
pub fn write_iges(
    path: impl AsRef<Path>,
    surfaces: &[BSplineSurface],
    options: &IgesWriteOptions,
) -> Result<(), IoError> {
    let path = path.as_ref();
    let text = surfaces_to_iges(surfaces, options).map_err(|message| IoError::InvalidData {
        path: path.to_path_buf(),
        message,
    })?;
    atomic_write(path, |w| w.write_all(text.as_bytes()))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::Vec3;
    use crate::bspline::TrimLoop;
    use crate::bspline::tests::{Rng, full_circle, torus};
    use crate::io::{parse_iges, read_iges, read_surfaces_json};

    fn options() -> IgesWriteOptions {
        IgesWriteOptions {
            timestamp: "20260101.120000".into(),
            ..IgesWriteOptions::default()
        }
    }

    /// Writes, reads back, and checks every surface is equal (control
    /// points, knots, weights and trimming curves compared with `==` on the
    /// `f64`s: bit-identical apart from the sign of zero, which
    /// `iges_real` keeps too).
    fn round_trip(surfaces: &[BSplineSurface]) -> String {
        let text = surfaces_to_iges(surfaces, &options()).unwrap();
        for (n, line) in text.lines().enumerate() {
            assert_eq!(line.len(), 80, "record {} is not 80 columns: {line}", n + 1);
        }
        let back = parse_iges(&text).unwrap();
        assert_eq!(back.surfaces.len(), surfaces.len());
        assert_eq!(back.units.as_deref(), Some("MM"));
        for (a, b) in surfaces.iter().zip(&back.surfaces) {
            assert_eq!(a, &b.surface);
            let bits = |s: &BSplineSurface| -> Vec<u64> {
                let mut v: Vec<u64> = s.knots_u().iter().map(|k| k.to_bits()).collect();
                v.extend(s.knots_v().iter().map(|k| k.to_bits()));
                v.extend(s.weights().unwrap_or(&[]).iter().map(|w| w.to_bits()));
                for p in s.control_points() {
                    v.extend([p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]);
                }
                for l in s.trims() {
                    for c in &l.curves {
                        v.extend(c.knots().iter().map(|k| k.to_bits()));
                        v.extend(c.weights().unwrap_or(&[]).iter().map(|w| w.to_bits()));
                        for p in c.control_points() {
                            v.extend([p[0].to_bits(), p[1].to_bits()]);
                        }
                    }
                }
                v
            };
            assert_eq!(bits(a), bits(&b.surface));
            assert_eq!(a.is_rational(), b.rational);
            assert_eq!(b.trim_entity.is_some(), a.is_trimmed());
        }
        text
    }

    #[test]
    fn iges_real_is_shortest_round_trip_with_a_decimal_point() {
        assert_eq!(iges_real(1.0), "1.0");
        assert_eq!(iges_real(1e-7), "1.E-7");
        assert_eq!(iges_real(-2.5e20), "-2.5E20");
        assert_eq!(iges_real(-0.0), "-0.0");
        let mut rng = Rng::new(5);
        for _ in 0..10_000 {
            let x = (rng.unit() - 0.5) * 10f64.powi((rng.unit() * 600.0) as i32 - 300);
            let s = iges_real(x);
            assert!(s.contains('.'), "{s}");
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{s}");
        }
        assert_eq!(iges_timestamp(std::time::UNIX_EPOCH), "19700101.000000");
        let t = std::time::UNIX_EPOCH + std::time::Duration::from_secs(1_709_210_096);
        assert_eq!(iges_timestamp(t), "20240229.123456");
    }

    /// A random rational surface of degrees (3, 5) with interior knots and
    /// full-precision coordinates, trimmed by a rectangle with a circular
    /// hole and a triangular hole (a loop of three separate lines).
    pub(crate) fn generated() -> Vec<BSplineSurface> {
        let mut rng = Rng::new(20);
        let (nu, nv) = (7, 8);
        let knots = |n: usize, p: usize, rng: &mut Rng| {
            let mut k = vec![0.0; p + 1];
            let inner: Vec<f64> = {
                let mut v: Vec<f64> = (0..n - p - 1).map(|_| rng.unit()).collect();
                v.sort_by(f64::total_cmp);
                v
            };
            k.extend(inner);
            k.extend(vec![1.0; p + 1]);
            k
        };
        let ku = knots(nu, 3, &mut rng);
        let kv = knots(nv, 5, &mut rng);
        let pts: Vec<Vec3> = (0..nu * nv).map(|_| rng.vec3() * 123.456_789).collect();
        let w: Vec<f64> = (0..nu * nv).map(|_| 0.3 + rng.unit()).collect();
        let rational =
            BSplineSurface::from_flat(3, 5, ku.clone(), kv.clone(), [nu, nv], pts.clone(), Some(w))
                .unwrap();
        let (cp, cw, ck) = full_circle();
        let hole = TrimCurve::new(
            2,
            ck,
            cp.iter()
                .rev()
                .map(|p| [0.3 + 0.1 * p[0], 0.6 + 0.1 / 3.0 * p[1]])
                .collect(),
            Some(cw.into_iter().rev().collect()),
        )
        .unwrap();
        let tri = [[0.7, 0.2], [0.8, 0.4], [0.6, 0.35]];
        let triangle = TrimLoop {
            curves: (0..3)
                .map(|k| TrimCurve::line(tri[k], tri[(k + 1) % 3]).unwrap())
                .collect(),
        };
        let trimmed = rational
            .clone()
            .with_trims(vec![
                TrimLoop::polygon(&[[0.05, 0.05], [0.95, 0.05], [0.95, 0.95], [0.05, 0.95]])
                    .unwrap(),
                TrimLoop { curves: vec![hole] },
                triangle,
            ])
            .unwrap();
        let polynomial = BSplineSurface::from_flat(3, 5, ku, kv, [nu, nv], pts, None).unwrap();
        vec![rational, trimmed, polynomial, torus(3.0, 1.0)]
    }

    #[test]
    fn iges_write_round_trip_of_generated_rational_and_trimmed_surfaces() {
        let surfaces = generated();
        let text = round_trip(&surfaces);
        // One 144 with three 142 boundaries; the outer loop of four lines and
        // the triangle are composite curves (102) of 126 lines.
        let count = |t: i64| {
            text.lines()
                .filter(|l| l.as_bytes()[72] == b'D' && l[..8].trim() == t.to_string())
                .count()
                / 2
        };
        assert_eq!(count(128), 4);
        assert_eq!(count(144), 1);
        assert_eq!(count(142), 3);
        assert_eq!(count(102), 2);
        assert_eq!(count(126), 4 + 1 + 3);
        // Writing what was read gives the same text again.
        let back: Vec<BSplineSurface> = parse_iges(&text)
            .unwrap()
            .surfaces
            .into_iter()
            .map(|s| s.surface)
            .collect();
        assert_eq!(surfaces_to_iges(&back, &options()).unwrap(), text);
    }

    #[test]
    fn iges_write_units_and_bad_options() {
        let s = &generated()[..1];
        let inch = IgesWriteOptions {
            unit: crate::io::units::LengthUnit::inch(),
            ..options()
        };
        let text = surfaces_to_iges(s, &inch).unwrap();
        assert_eq!(parse_iges(&text).unwrap().units.as_deref(), Some("IN"));
        let bad = IgesWriteOptions {
            product: "caf\u{e9}".into(),
            ..options()
        };
        assert!(
            surfaces_to_iges(s, &bad)
                .unwrap_err()
                .contains("product name")
        );
        let dir = std::env::temp_dir().join(format!("fairline-iges-write-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("out.igs");
        write_iges(&path, s, &options()).unwrap();
        assert_eq!(read_iges(&path).unwrap().surfaces[0].surface, s[0]);
        assert!(write_iges(dir.join("missing/out.igs"), s, &options()).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn iges_write_round_trip_of_the_impeller_keeps_every_trim() {
        let Some(path) = crate::shared_data::shared_data("surfaces/impeller.igs") else {
            return;
        };
        let imp = read_iges(path).unwrap();
        let surfaces: Vec<BSplineSurface> = imp.surfaces.into_iter().map(|s| s.surface).collect();
        let trimmed = surfaces.iter().filter(|s| s.is_trimmed()).count();
        assert!(trimmed > 200, "{trimmed}");
        round_trip(&surfaces);
    }

    #[test]
    fn iges_write_round_trip_of_the_teapot() {
        let Some(path) = crate::shared_data::shared_data("surfaces/teapot.json") else {
            return;
        };
        let surfaces = read_surfaces_json(path).unwrap();
        assert_eq!(surfaces.len(), 32);
        round_trip(&surfaces);
    }
}
