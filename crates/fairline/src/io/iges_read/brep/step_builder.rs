//! An in-memory STEP exchange written instance by instance: the entities a
//! B-rep face becomes (points, placements, B-spline curves and surfaces).

use std::collections::HashMap;

use crate::Vec3;
use crate::bspline::BSplineSurface;
use crate::io::step::nurbs::Nurbs3;
use crate::io::step::p21::{Exchange, Instance, Value};

/// An in-memory STEP exchange being written, instance by instance.
pub(super) struct StepBuilder {
    pub(super) ex: Exchange,
    next: u64,
    /// EDGE_CURVE and its SURFACE_CURVE of each edge-list entry
    /// `(504 index, entry)`.
    pub(super) edges: HashMap<(usize, usize), (u64, u64)>,
    /// VERTEX_POINT of each vertex-list entry `(502 index, entry)`.
    pub(super) vertices: HashMap<(usize, usize), u64>,
    /// Dense points of each EDGE_CURVE's curve.
    pub(super) edge_points: HashMap<u64, Vec<Vec3>>,
    /// The edge curves' points of each ADVANCED_FACE's bounds.
    pub(super) boundaries: HashMap<u64, Vec<Vec<Vec3>>>,
}

pub(super) fn text(s: &str) -> Value {
    Value::Text(s.into())
}

pub(super) fn flag(b: bool) -> Value {
    Value::Enum(if b { "T" } else { "F" }.into())
}

fn reals(xs: impl IntoIterator<Item = f64>) -> Value {
    Value::List(xs.into_iter().map(Value::Real).collect())
}

pub(super) fn refs(ids: impl IntoIterator<Item = u64>) -> Value {
    Value::List(ids.into_iter().map(Value::Ref).collect())
}

/// Distinct knot values and their multiplicities.
fn knot_runs(knots: &[f64]) -> (Value, Value) {
    let mut runs: Vec<(f64, i64)> = Vec::new();
    for &k in knots {
        match runs.last_mut() {
            Some((value, count)) if *value == k => *count += 1,
            _ => runs.push((k, 1)),
        }
    }
    let (values, mults): (Vec<f64>, Vec<i64>) = runs.into_iter().unzip();
    (
        Value::List(mults.into_iter().map(Value::Integer).collect()),
        reals(values),
    )
}

impl StepBuilder {
    pub(super) fn new() -> Self {
        StepBuilder {
            ex: Exchange::default(),
            next: 1,
            edges: HashMap::new(),
            vertices: HashMap::new(),
            edge_points: HashMap::new(),
            boundaries: HashMap::new(),
        }
    }

    fn add(&mut self, parts: Vec<(&str, Vec<Value>)>, line: usize) -> u64 {
        let id = self.reserve();
        self.insert(id, parts, line);
        id
    }

    /// An id for an instance written later with [`Self::insert`].
    pub(super) fn reserve(&mut self) -> u64 {
        let id = self.next;
        self.next += 1;
        id
    }

    pub(super) fn insert(&mut self, id: u64, parts: Vec<(&str, Vec<Value>)>, line: usize) {
        self.ex.instances.insert(
            id,
            Instance {
                id,
                parts: parts.into_iter().map(|(n, v)| (n.to_string(), v)).collect(),
                line,
            },
        );
        self.ex.order.push(id);
    }

    /// Adds a p-curve (a 2-D B-spline curve in the surface's ISO 10303-42
    /// parameters) on surface `surface` to the SURFACE_CURVE `sc`.
    pub(super) fn pcurve(&mut self, sc: u64, surface: u64, c: &Nurbs3, line: usize) {
        let curve = self.curve2(c, line);
        let dr = self.simple(
            "DEFINITIONAL_REPRESENTATION",
            vec![text(""), refs([curve]), Value::Unset],
            line,
        );
        let pc = self.simple(
            "PCURVE",
            vec![text(""), Value::Ref(surface), Value::Ref(dr)],
            line,
        );
        if let Some(Value::List(l)) = self
            .ex
            .instances
            .get_mut(&sc)
            .and_then(|i| i.parts.first_mut())
            .and_then(|(_, p)| p.get_mut(2))
        {
            l.push(Value::Ref(pc));
        }
    }

    pub(super) fn simple(&mut self, name: &str, params: Vec<Value>, line: usize) -> u64 {
        self.add(vec![(name, params)], line)
    }

    pub(super) fn point(&mut self, p: Vec3, line: usize) -> u64 {
        self.simple(
            "CARTESIAN_POINT",
            vec![text(""), reals([p.x, p.y, p.z])],
            line,
        )
    }

    pub(super) fn direction(&mut self, d: Vec3, line: usize) -> u64 {
        self.simple("DIRECTION", vec![text(""), reals([d.x, d.y, d.z])], line)
    }

    /// AXIS2_PLACEMENT_3D at `o` with axis `z` and reference direction `x`
    /// (the placement's default when `None`).
    pub(super) fn placement(&mut self, o: Vec3, z: Vec3, x: Option<Vec3>, line: usize) -> u64 {
        let o = self.point(o, line);
        let z = self.direction(z, line);
        let x = match x {
            Some(x) => Value::Ref(self.direction(x, line)),
            None => Value::Unset,
        };
        self.simple(
            "AXIS2_PLACEMENT_3D",
            vec![text(""), Value::Ref(o), Value::Ref(z), x],
            line,
        )
    }

    /// A B-spline curve instance (complex with RATIONAL_B_SPLINE_CURVE when
    /// it has weights).
    pub(super) fn curve(&mut self, c: &Nurbs3, line: usize) -> u64 {
        let pts: Vec<u64> = c.points.iter().map(|p| self.point(*p, line)).collect();
        self.bspline_curve(c, pts, line)
    }

    /// [`Self::curve`] of a curve in a plane of parameters (`z` left out).
    fn curve2(&mut self, c: &Nurbs3, line: usize) -> u64 {
        let pts: Vec<u64> = c
            .points
            .iter()
            .map(|p| self.simple("CARTESIAN_POINT", vec![text(""), reals([p.x, p.y])], line))
            .collect();
        self.bspline_curve(c, pts, line)
    }

    fn bspline_curve(&mut self, c: &Nurbs3, pts: Vec<u64>, line: usize) -> u64 {
        let (mults, knots) = knot_runs(&c.knots);
        let head = vec![
            Value::Integer(c.degree as i64),
            refs(pts),
            Value::Enum("UNSPECIFIED".into()),
            flag(false),
            flag(false),
        ];
        let tail = vec![mults, knots, Value::Enum("UNSPECIFIED".into())];
        match &c.weights {
            None => {
                let mut p = vec![text("")];
                p.extend(head);
                p.extend(tail);
                self.simple("B_SPLINE_CURVE_WITH_KNOTS", p, line)
            }
            Some(w) => self.add(
                vec![
                    ("B_SPLINE_CURVE", head),
                    ("B_SPLINE_CURVE_WITH_KNOTS", tail),
                    ("RATIONAL_B_SPLINE_CURVE", vec![reals(w.iter().copied())]),
                ],
                line,
            ),
        }
    }

    /// A B-spline surface instance (complex with RATIONAL_B_SPLINE_SURFACE
    /// when it has weights); rows are the `u` index.
    pub(super) fn bspline_surface(
        &mut self,
        s: &BSplineSurface,
        line: usize,
    ) -> Vec<(&'static str, Vec<Value>)> {
        let (nu, nv) = (s.count_u(), s.count_v());
        let rows: Vec<Value> = (0..nu)
            .map(|i| refs((0..nv).map(|j| self.point(s.control_point(i, j), line))))
            .collect();
        let (mu, ku) = knot_runs(s.knots_u());
        let (mv, kv) = knot_runs(s.knots_v());
        let head = vec![
            Value::Integer(s.degree_u() as i64),
            Value::Integer(s.degree_v() as i64),
            Value::List(rows),
            Value::Enum("UNSPECIFIED".into()),
            flag(false),
            flag(false),
            flag(false),
        ];
        let tail = vec![mu, mv, ku, kv, Value::Enum("UNSPECIFIED".into())];
        if s.is_rational() {
            let w: Vec<Value> = (0..nu)
                .map(|i| reals((0..nv).map(|j| s.weight(i, j))))
                .collect();
            vec![
                ("B_SPLINE_SURFACE", head),
                ("B_SPLINE_SURFACE_WITH_KNOTS", tail),
                ("RATIONAL_B_SPLINE_SURFACE", vec![Value::List(w)]),
            ]
        } else {
            let mut p = vec![text("")];
            p.extend(head);
            p.extend(tail);
            vec![("B_SPLINE_SURFACE_WITH_KNOTS", p)]
        }
    }
}
