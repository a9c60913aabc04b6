//! The SINTEF GoTools text format (`.g2`, also written by G+Smo): a
//! sequence of objects, each a header `class major minor n_aux aux…`
//! followed by the object's data, whitespace-separated.
//!
//! Read (after GoTools' `ObjectHeader::read`, `SplineSurface::read`,
//! `BsplineBasis::read`, `BoundedSurface::read`, `CurveOnSurface::read` and
//! `ClassType.h`, gotools-core/src/geometry):
//!
//! * class 200, `SplineSurface`: `dim rational`, then per direction (u,
//!   then v) `n k` (coefficient count, order = degree + 1) and the `n + k`
//!   knots, then the `n_u · n_v` coefficients with u running fastest
//!   (coefficient `(i, j)` at `i + n_u · j`), each `dim` numbers, or
//!   `dim + 1` when rational: `(w·x, w·y, w·z, w)`, the projective point.
//!   Dimension 3 is read; dimension 2 is read in the plane z = 0.
//! * class 210, `BoundedSurface` over a `SplineSurface`: the surface's class
//!   and data, then `n_loops`, each `n_curves space_epsilon` and the
//!   curves, each `prefer_parameter pcurve_class spacecurve_class` and the
//!   curves' data (class 0: absent). Read as a trimmed surface (first loop
//!   the outer boundary) when every curve has a 2-D `SplineCurve` (class
//!   100) in the parameter plane.
//!
//! Any other object (curves, elementary surfaces, meshes, …) and a bounded
//! surface that cannot be read as above is listed in
//! [`GoToolsImport::unreadable`], never dropped silently. Classes whose
//! layout fairline does not know are passed by looking for the next line
//! that holds a header of a known class (four integers: a GoTools class,
//! version `1 0`, no auxiliary data).

use std::path::{Path, PathBuf};

use thiserror::Error;

use super::unreadable::Unreadable;
use crate::Vec3;
use crate::bspline::{BSplineError, BSplineSurface, TrimCurve, TrimLoop};

/// Why a GoTools file could not be read.
#[derive(Debug, Error)]
pub enum GoToolsError {
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The data of an object is malformed.
    #[error("line {line}: object {object} (class {class}): {message}")]
    Object {
        /// 1-based line number in the file.
        line: usize,
        /// 1-based index of the object in the file.
        object: usize,
        /// The object's class number.
        class: i64,
        /// What is wrong.
        message: String,
    },
    /// A spline surface's data is well formed but not a valid surface.
    #[error("line {line}: object {object} (class {class}): {source}")]
    Surface {
        /// 1-based line number of the object's header.
        line: usize,
        /// 1-based index of the object in the file.
        object: usize,
        /// The object's class number.
        class: i64,
        /// The validation error.
        source: BSplineError,
    },
    /// An error of the content of a file, with the file's name.
    #[error("{}: {error}", path.display())]
    InFile {
        /// The file.
        path: PathBuf,
        /// What is wrong in it (line, object).
        error: Box<GoToolsError>,
    },
}

/// The surfaces of a GoTools file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GoToolsImport {
    /// Every spline surface (class 200) and bounded spline surface (class
    /// 210, trimmed), in file order.
    pub surfaces: Vec<BSplineSurface>,
    /// Every object not read, with its class and why.
    pub unreadable: Vec<Unreadable>,
}

/// The GoTools class names (`ClassType.h`), for messages.
fn class_name(class: i64) -> Option<&'static str> {
    Some(match class {
        100 => "SplineCurve",
        110 => "CurveOnSurface",
        111 => "CurveOnVolume",
        120 => "Line",
        130 => "Circle",
        140 => "Ellipse",
        150 => "BoundedCurve",
        160 => "Hyperbola",
        170 => "Parabola",
        200 => "SplineSurface",
        210 => "BoundedSurface",
        211 => "SurfaceOnVolume",
        220 => "GoBaryPolSurface",
        230 => "GoHBSplineParamSurface",
        240 => "CompositeSurface",
        250 => "Plane",
        260 => "Cylinder",
        261 => "SurfaceOfLinearExtrusion",
        270 => "Sphere",
        280 => "Cone",
        290 => "Torus",
        291 => "SurfaceOfRevolution",
        292 => "Disc",
        293 => "LRSplineSurface",
        294 => "TSplineSurface",
        300 => "Go3dsObject",
        310 => "GoHeTriang",
        320 => "GoSdTriang",
        330 => "GoQuadMesh",
        340 => "GoHybridMesh",
        350 => "ParamTriang",
        360 => "GoVrmlGeometry",
        400 => "PointCloud",
        410 => "LineCloud",
        500 => "GoTriangleSets",
        510 => "RectGrid",
        700 => "SplineVolume",
        710 => "BoundedVolume",
        720 => "Parallelepiped",
        721 => "SphereVolume",
        722 => "CylinderVolume",
        723 => "ConeVolume",
        724 => "TorusVolume",
        _ => return None,
    })
}

/// Reads every surface of a GoTools `.g2` file; see the module
/// documentation for what is read. Errors name the file, line and object.
pub fn read_gotools(path: impl AsRef<Path>) -> Result<GoToolsImport, GoToolsError> {
    let path = path.as_ref();
    let read_err = |source| GoToolsError::Read {
        path: path.to_path_buf(),
        source,
    };
    super::require_regular_file(path).map_err(read_err)?;
    let bytes = std::fs::read(path).map_err(read_err)?;
    let text = String::from_utf8_lossy(&bytes);
    parse_gotools(&text).map_err(|error| GoToolsError::InFile {
        path: path.to_path_buf(),
        error: Box::new(error),
    })
}

/// Parses GoTools text; see [`read_gotools`].
pub fn parse_gotools(text: &str) -> Result<GoToolsImport, GoToolsError> {
    let mut lx = Lexer {
        text,
        pos: 0,
        line: 1,
        object: 0,
        class: 0,
        header_line: 1,
    };
    let mut out = GoToolsImport::default();
    while lx.skip_space() {
        lx.object += 1;
        lx.header_line = lx.line;
        lx.class = 0;
        lx.class = lx.int("the class number")?;
        let _major = lx.int("the major version")?;
        let _minor = lx.int("the minor version")?;
        let n_aux = lx.int("the auxiliary data count")?;
        if n_aux < 0 {
            return Err(lx.err(format!("auxiliary data count {n_aux}")));
        }
        for _ in 0..n_aux {
            lx.token("auxiliary data")?;
        }
        let entity = format!(
            "object {} (class {} {}, line {})",
            lx.object,
            lx.class,
            class_name(lx.class).unwrap_or("unknown"),
            lx.header_line
        );
        let read: Result<BSplineSurface, String> = match lx.class {
            200 => lx.spline_surface()?,
            210 => lx.bounded_surface()?,
            100 => {
                lx.spline_curve()?;
                Err("a curve, not a surface".into())
            }
            c => {
                lx.resync();
                Err(match c {
                    100..=199 => "a curve, not a surface",
                    200..=299 => {
                        "a surface of a kind fairline does not read (only SplineSurface 200 and BoundedSurface 210 over one)"
                    }
                    _ => "not a B-spline surface",
                }
                .into())
            }
        };
        match read {
            Ok(s) => out.surfaces.push(s),
            Err(reason) => out.unreadable.push(Unreadable {
                entity,
                reason,
                estimated_area: None,
            }),
        }
    }
    Ok(out)
}

/// A 2-D or 3-D spline curve as read: degree, knots, points, weights.
struct Curve {
    dim: usize,
    degree: usize,
    knots: Vec<f64>,
    points: Vec<[f64; 3]>,
    weights: Option<Vec<f64>>,
}

/// Control points (divided by their weight) and weights, when rational.
type Coefficients = (Vec<[f64; 3]>, Option<Vec<f64>>);

/// A whitespace tokenizer that tracks lines and the object being read.
struct Lexer<'a> {
    text: &'a str,
    pos: usize,
    line: usize,
    object: usize,
    class: i64,
    header_line: usize,
}

impl<'a> Lexer<'a> {
    fn err(&self, message: String) -> GoToolsError {
        GoToolsError::Object {
            line: self.line,
            object: self.object,
            class: self.class,
            message,
        }
    }

    /// Skips whitespace; false at the end of the text.
    fn skip_space(&mut self) -> bool {
        let rest = &self.text.as_bytes()[self.pos..];
        for &b in rest {
            if !b.is_ascii_whitespace() {
                return true;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        false
    }

    fn token(&mut self, what: &str) -> Result<&'a str, GoToolsError> {
        if !self.skip_space() {
            return Err(self.err(format!("the file ends before {what}")));
        }
        let rest = &self.text[self.pos..];
        let len = rest
            .find(|c: char| c.is_ascii_whitespace())
            .unwrap_or(rest.len());
        self.pos += len;
        Ok(&rest[..len])
    }

    fn int(&mut self, what: &str) -> Result<i64, GoToolsError> {
        let t = self.token(what)?;
        t.parse()
            .map_err(|_| self.err(format!("{what}: expected an integer, found `{t}`")))
    }

    /// A count of items of at least `min_bytes` each that must fit in the
    /// rest of the text: memory stays linear in the file size.
    fn count(&mut self, what: &str, items_each: usize) -> Result<usize, GoToolsError> {
        let n = self.int(what)?;
        let left = self.text.len() - self.pos;
        let fits = usize::try_from(n)
            .ok()
            .filter(|&n| n.saturating_mul(items_each.max(1)) <= left / 2 + 1);
        fits.ok_or_else(|| {
            self.err(format!(
                "{what} {n}: negative or more than the {left} bytes left can hold"
            ))
        })
    }

    fn number(&mut self, what: &dyn Fn() -> String) -> Result<f64, GoToolsError> {
        let t = self.token(&what())?;
        match t.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(self.err(format!("{}: expected a finite number, found `{t}`", what()))),
        }
    }

    /// `dim rational`: the dimension and whether coefficients carry a weight.
    fn dim_rational(&mut self) -> Result<(usize, bool), GoToolsError> {
        let dim = self.int("the dimension")?;
        let dim = match usize::try_from(dim) {
            Ok(d @ 1..=64) => d,
            _ => return Err(self.err(format!("dimension {dim}, expected 1 to 64"))),
        };
        let rational = match self.int("the rational flag")? {
            0 => false,
            1 => true,
            r => return Err(self.err(format!("rational flag {r}, expected 0 or 1"))),
        };
        Ok((dim, rational))
    }

    /// `n k` and the `n + k` knots of one direction: (n, degree, knots).
    fn basis(&mut self, dir: &str) -> Result<(usize, usize, Vec<f64>), GoToolsError> {
        let n = self.count(&format!("the coefficient count in {dir}"), 1)?;
        let k = self.count(&format!("the order in {dir}"), 1)?;
        if k == 0 {
            return Err(self.err(format!("order 0 in {dir}")));
        }
        let m = n + k;
        if m > (self.text.len() - self.pos) / 2 + 1 {
            return Err(self.err(format!(
                "{m} knots in {dir} cannot fit in the rest of the file"
            )));
        }
        let mut knots = Vec::with_capacity(m);
        for i in 0..m {
            knots.push(self.number(&|| format!("knot {i} of {m} in {dir}"))?);
        }
        Ok((n, k - 1, knots))
    }

    /// `count` coefficients of `dim` (+ 1 when rational) numbers: points
    /// (projective ones divided by their weight) and weights.
    fn coefficients(
        &mut self,
        count: usize,
        dim: usize,
        rational: bool,
    ) -> Result<Coefficients, GoToolsError> {
        let each = dim + usize::from(rational);
        if count.saturating_mul(each) > (self.text.len() - self.pos) / 2 + 1 {
            return Err(self.err(format!(
                "{count} coefficients of {each} numbers cannot fit in the rest of the file"
            )));
        }
        let mut points = Vec::with_capacity(count);
        let mut weights = Vec::with_capacity(if rational { count } else { 0 });
        let mut c = vec![0.0; each];
        for k in 0..count {
            for (d, x) in c.iter_mut().enumerate() {
                *x = self.number(&|| format!("coefficient {k} of {count}, number {d}"))?;
            }
            let w = if rational { c[dim] } else { 1.0 };
            if w.is_nan() || w <= 0.0 {
                return Err(self.err(format!(
                    "coefficient {k} of {count}: weight {w}, weights must be positive"
                )));
            }
            let mut p = [0.0; 3];
            for d in 0..dim.min(3) {
                p[d] = c[d] / w;
            }
            if p.iter().any(|x| !x.is_finite()) {
                return Err(self.err(format!(
                    "coefficient {k} of {count}: not finite after division by its weight"
                )));
            }
            points.push(p);
            if rational {
                weights.push(w);
            }
        }
        Ok((points, rational.then_some(weights)))
    }

    /// The data of a `SplineSurface` (after its header or class number):
    /// the surface, or why it is not read when the data is well formed.
    fn spline_surface(&mut self) -> Result<Result<BSplineSurface, String>, GoToolsError> {
        let (dim, rational) = self.dim_rational()?;
        let (nu, pu, ku) = self.basis("u")?;
        let (nv, pv, kv) = self.basis("v")?;
        let count = nu
            .checked_mul(nv)
            .ok_or_else(|| self.err(format!("{nu} × {nv} coefficients overflow")))?;
        let (pts, w) = self.coefficients(count, dim, rational)?;
        if dim != 2 && dim != 3 {
            return Ok(Err(format!("dimension {dim}: only 2 and 3 are read")));
        }
        // GoTools runs u fastest; fairline stores i * count_v + j
        let mut points = Vec::with_capacity(count);
        let mut weights = w.as_ref().map(|_| Vec::with_capacity(count));
        for i in 0..nu {
            for j in 0..nv {
                let p = pts[i + nu * j];
                points.push(Vec3::new(p[0], p[1], p[2]));
                if let (Some(out), Some(w)) = (weights.as_mut(), w.as_ref()) {
                    out.push(w[i + nu * j]);
                }
            }
        }
        BSplineSurface::from_flat(pu, pv, ku, kv, [nu, nv], points, weights)
            .map(Ok)
            .map_err(|source| GoToolsError::Surface {
                line: self.header_line,
                object: self.object,
                class: self.class,
                source,
            })
    }

    /// The data of a `SplineCurve`.
    fn spline_curve(&mut self) -> Result<Curve, GoToolsError> {
        let (dim, rational) = self.dim_rational()?;
        let (n, degree, knots) = self.basis("the curve")?;
        let (points, weights) = self.coefficients(n, dim, rational)?;
        Ok(Curve {
            dim,
            degree,
            knots,
            points,
            weights,
        })
    }

    /// The data of a `BoundedSurface`: the trimmed surface, or why not
    /// (the rest of the object is passed when its layout is unknown).
    fn bounded_surface(&mut self) -> Result<Result<BSplineSurface, String>, GoToolsError> {
        let under = self.int("the class of the underlying surface")?;
        if under != 200 {
            self.resync();
            return Ok(Err(format!(
                "the underlying surface is class {under} {}, not a SplineSurface (200)",
                class_name(under).unwrap_or("unknown")
            )));
        }
        let surface = match self.spline_surface()? {
            Ok(s) => s,
            Err(reason) => {
                self.resync();
                return Ok(Err(format!("the underlying surface: {reason}")));
            }
        };
        let n_loops = self.count("the boundary loop count", 2)?;
        let mut loops = Vec::with_capacity(n_loops);
        let mut missing = None;
        for l in 0..n_loops {
            let n_curves = self.count(&format!("the curve count of loop {l}"), 3)?;
            self.number(&|| format!("the space epsilon of loop {l}"))?;
            let mut curves = Vec::with_capacity(n_curves);
            for c in 0..n_curves {
                let _prefer = self.int(&format!("loop {l} curve {c}: the preferred flag"))?;
                let pclass = self.int(&format!("loop {l} curve {c}: the parameter curve class"))?;
                let sclass = self.int(&format!("loop {l} curve {c}: the space curve class"))?;
                let mut pcurve = None;
                for (class, is_p) in [(pclass, true), (sclass, false)] {
                    match class {
                        0 => {}
                        1 | 100 => {
                            let cv = self.spline_curve()?;
                            if is_p {
                                pcurve = Some(cv);
                            }
                        }
                        other => {
                            self.resync();
                            return Ok(Err(format!(
                                "loop {l} curve {c}: a curve of class {other} {}, only SplineCurve (100) is read",
                                class_name(other).unwrap_or("unknown")
                            )));
                        }
                    }
                }
                match pcurve {
                    Some(cv) if cv.dim == 2 => {
                        let pts = cv.points.iter().map(|p| [p[0], p[1]]).collect();
                        match TrimCurve::new(cv.degree, cv.knots, pts, cv.weights) {
                            Ok(t) => curves.push(t),
                            Err(m) => {
                                missing.get_or_insert(format!("loop {l} curve {c}: {m}"));
                            }
                        }
                    }
                    Some(cv) => {
                        missing.get_or_insert(format!(
                            "loop {l} curve {c}: a parameter curve of dimension {}",
                            cv.dim
                        ));
                    }
                    None => {
                        missing.get_or_insert(format!(
                            "loop {l} curve {c}: no parameter curve (only a space curve)"
                        ));
                    }
                }
            }
            loops.push(TrimLoop { curves });
        }
        if let Some(reason) = missing {
            return Ok(Err(reason));
        }
        Ok(surface.with_trims(loops).map_err(|e| e.to_string()))
    }

    /// Moves to the next line that holds a header of a known class (four
    /// integers: class, `1 0`, `0`), or to the end of the text.
    fn resync(&mut self) {
        let bytes = self.text.as_bytes();
        // finish the current line
        while self.pos < bytes.len() && bytes[self.pos] != b'\n' {
            self.pos += 1;
        }
        while self.pos < bytes.len() {
            // at a '\n': look at the next line
            self.pos += 1;
            self.line += 1;
            let rest = &self.text[self.pos..];
            let end = rest.find('\n').unwrap_or(rest.len());
            let tokens: Vec<&str> = rest[..end].split_whitespace().collect();
            if let [c, "1", "0", "0"] = tokens.as_slice()
                && c.parse::<i64>().ok().and_then(class_name).is_some()
            {
                return;
            }
            self.pos += end;
        }
    }
}

#[cfg(test)]
#[path = "gotools_tests.rs"]
mod tests;
