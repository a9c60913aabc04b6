//! Typed access to a STEP instance's parameters: references, numbers,
//! integers, lists, flags, and the points, directions and placements they make.

use super::{R, Reader};
use crate::Vec3;
use crate::io::step::StepError;
use crate::io::step::p21::{Instance, Value};

impl<'a> Reader<'a> {
    fn get(&self, id: u64, from: &Instance) -> R<&'a Instance> {
        self.ex
            .instances
            .get(&id)
            .ok_or_else(|| self.err(from, format!("refers to #{id}, which is not defined")))
    }

    pub(super) fn err(&self, i: &Instance, message: String) -> StepError {
        StepError::Entity {
            id: i.id,
            line: i.line,
            message: format!("{}: {message}", i.type_name()),
        }
    }

    /// The parameters of a simple instance of one of `types`.
    pub(super) fn params(&self, i: &'a Instance, types: &[&str]) -> R<&'a [Value]> {
        match i.parts.as_slice() {
            [(n, p)] if types.contains(&n.as_str()) => Ok(p),
            _ => Err(self.err(i, format!("expected {}", types.join(" or ")))),
        }
    }

    fn at<'v>(&self, i: &Instance, p: &'v [Value], k: usize) -> R<&'v Value> {
        p.get(k).ok_or_else(|| {
            self.err(
                i,
                format!("has {} parameters, needs at least {}", p.len(), k + 1),
            )
        })
    }

    pub(super) fn num(&self, i: &Instance, p: &[Value], k: usize) -> R<f64> {
        self.at(i, p, k)?
            .number()
            .filter(|x| x.is_finite())
            .ok_or_else(|| self.err(i, format!("parameter {k} is not a number")))
    }

    pub(super) fn int(&self, i: &Instance, p: &[Value], k: usize) -> R<usize> {
        let x = self.num(i, p, k)?;
        if x >= 0.0 && x.fract() == 0.0 && x < 1e9 {
            Ok(x as usize)
        } else {
            Err(self.err(i, format!("parameter {k} is not a count ({x})")))
        }
    }

    pub(super) fn refer(&self, i: &'a Instance, p: &[Value], k: usize) -> R<&'a Instance> {
        match self.at(i, p, k)? {
            Value::Ref(id) => self.get(*id, i),
            _ => Err(self.err(i, format!("parameter {k} is not an entity reference"))),
        }
    }

    pub(super) fn list<'v>(&self, i: &Instance, p: &'v [Value], k: usize) -> R<&'v [Value]> {
        match self.at(i, p, k)? {
            Value::List(l) => Ok(l),
            _ => Err(self.err(i, format!("parameter {k} is not a list"))),
        }
    }

    pub(super) fn flag(&self, i: &Instance, p: &[Value], k: usize) -> R<bool> {
        match self.at(i, p, k)? {
            Value::Enum(e) if e == "T" => Ok(true),
            Value::Enum(e) if e == "F" => Ok(false),
            _ => Err(self.err(i, format!("parameter {k} is not .T. or .F."))),
        }
    }

    pub(super) fn numbers(&self, i: &Instance, l: &[Value]) -> R<Vec<f64>> {
        l.iter()
            .map(|v| {
                v.number()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| self.err(i, "a list holds something other than numbers".into()))
            })
            .collect()
    }

    pub(super) fn refs(&self, i: &'a Instance, l: &[Value]) -> R<Vec<&'a Instance>> {
        l.iter()
            .map(|v| match v {
                Value::Ref(id) => self.get(*id, i),
                _ => Err(self.err(
                    i,
                    "a list holds something other than entity references".into(),
                )),
            })
            .collect()
    }

    /// CARTESIAN_POINT (2-D points get `z = 0`).
    pub(super) fn point(&self, i: &'a Instance) -> R<Vec3> {
        let p = self.params(i, &["CARTESIAN_POINT"])?;
        let c = self.numbers(i, self.list(i, p, 1)?)?;
        match c.as_slice() {
            [x, y] => Ok(Vec3::new(*x, *y, 0.0)),
            [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
            _ => Err(self.err(i, format!("{} coordinates", c.len()))),
        }
    }

    /// DIRECTION, normalised.
    pub(super) fn direction(&self, i: &'a Instance) -> R<Vec3> {
        let p = self.params(i, &["DIRECTION"])?;
        let c = self.numbers(i, self.list(i, p, 1)?)?;
        let d = match c.as_slice() {
            [x, y] => Vec3::new(*x, *y, 0.0),
            [x, y, z] => Vec3::new(*x, *y, *z),
            _ => return Err(self.err(i, format!("{} components", c.len()))),
        };
        let l = d.length();
        if l > 0.0 && l.is_finite() {
            Ok(d / l)
        } else {
            Err(self.err(i, "the direction has no length".into()))
        }
    }

    /// AXIS2_PLACEMENT_3D / _2D: origin and the axes x, y, z.
    pub(super) fn placement(&self, i: &'a Instance) -> R<(Vec3, Vec3, Vec3, Vec3)> {
        let p = self.params(i, &["AXIS2_PLACEMENT_3D", "AXIS2_PLACEMENT_2D"])?;
        let o = self.point(self.refer(i, p, 1)?)?;
        let opt_dir = |k: usize| -> R<Option<Vec3>> {
            match p.get(k) {
                Some(Value::Ref(_)) => Ok(Some(self.direction(self.refer(i, p, k)?)?)),
                _ => Ok(None),
            }
        };
        let (z, xr) = if i.type_name() == "AXIS2_PLACEMENT_2D" {
            (Vec3::Z, opt_dir(2)?)
        } else {
            (opt_dir(2)?.unwrap_or(Vec3::Z), opt_dir(3)?)
        };
        let xr = xr.unwrap_or_else(|| if z.x.abs() < 0.9 { Vec3::X } else { Vec3::Y });
        let x = xr - xr.dot(z) * z;
        let l = x.length();
        if l <= 1e-12 || !l.is_finite() {
            return Err(self.err(i, "the reference direction is parallel to the axis".into()));
        }
        let x = x / l;
        Ok((o, x, z.cross(x), z))
    }
}
