//! STEP reading against exact constructions (areas in closed form to
//! 0.1 %), errors naming the entity, units, and read → write → read round
//! trips that keep every number bit-identical.

use std::f64::consts::PI;

use super::*;
use crate::Vec3;
use crate::bspline::{BSplineSurface, TrimCurve, TrimLoop, trimmed_area};
use crate::io::units::LengthUnit;
use crate::io::{read_iges, read_surfaces_json};

/// Builds the DATA section of a hand-written STEP file.
#[derive(Default)]
struct File {
    lines: Vec<String>,
}

impl File {
    fn add(&mut self, body: &str) -> u64 {
        self.lines.push(body.to_string());
        self.lines.len() as u64
    }
    fn point(&mut self, p: [f64; 3]) -> u64 {
        self.add(&format!(
            "CARTESIAN_POINT('',({:?},{:?},{:?}))",
            p[0], p[1], p[2]
        ))
    }
    fn dir(&mut self, d: [f64; 3]) -> u64 {
        self.add(&format!("DIRECTION('',({:?},{:?},{:?}))", d[0], d[1], d[2]))
    }
    fn frame(&mut self, o: [f64; 3], z: [f64; 3], x: [f64; 3]) -> u64 {
        let (o, z, x) = (self.point(o), self.dir(z), self.dir(x));
        self.add(&format!("AXIS2_PLACEMENT_3D('',#{o},#{z},#{x})"))
    }
    fn vertex(&mut self, p: [f64; 3]) -> u64 {
        let p = self.point(p);
        self.add(&format!("VERTEX_POINT('',#{p})"))
    }
    fn line(&mut self, a: [f64; 3], b: [f64; 3], va: u64, vb: u64) -> u64 {
        let p = self.point(a);
        let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let dir = self.dir([d[0] / len, d[1] / len, d[2] / len]);
        let v = self.add(&format!("VECTOR('',#{dir},{len:?})"));
        let l = self.add(&format!("LINE('',#{p},#{v})"));
        self.add(&format!("EDGE_CURVE('',#{va},#{vb},#{l},.T.)"))
    }
    #[allow(clippy::too_many_arguments)]
    fn circle(
        &mut self,
        c: [f64; 3],
        z: [f64; 3],
        x: [f64; 3],
        r: f64,
        va: u64,
        vb: u64,
        same: bool,
    ) -> u64 {
        let f = self.frame(c, z, x);
        let ci = self.add(&format!("CIRCLE('',#{f},{r:?})"));
        let s = if same { ".T." } else { ".F." };
        self.add(&format!("EDGE_CURVE('',#{va},#{vb},#{ci},{s})"))
    }
    fn bound(&mut self, edges: &[(u64, bool)], outer: bool) -> u64 {
        let oe: Vec<String> = edges
            .iter()
            .map(|&(e, o)| {
                let s = if o { ".T." } else { ".F." };
                format!("#{}", self.add(&format!("ORIENTED_EDGE('',*,*,#{e},{s})")))
            })
            .collect();
        let lp = self.add(&format!("EDGE_LOOP('',({}))", oe.join(",")));
        let kind = if outer {
            "FACE_OUTER_BOUND"
        } else {
            "FACE_BOUND"
        };
        self.add(&format!("{kind}('',#{lp},.T.)"))
    }
    fn face(&mut self, bounds: &[u64], surface: u64) -> u64 {
        let b: Vec<String> = bounds.iter().map(|b| format!("#{b}")).collect();
        self.add(&format!(
            "ADVANCED_FACE('',({}),#{surface},.T.)",
            b.join(",")
        ))
    }
    /// A SURFACE_OF_REVOLUTION about the z axis of the B_SPLINE_CURVE
    /// `profile` (its body after the name: degree, points, …).
    fn revolution_about_z(&mut self, profile: &str) -> u64 {
        let profile = self.add(&format!("B_SPLINE_CURVE_WITH_KNOTS('',{profile})"));
        let (o, z) = (self.point([0.0; 3]), self.dir([0.0, 0.0, 1.0]));
        let axis = self.add(&format!("AXIS1_PLACEMENT('',#{o},#{z})"));
        self.add(&format!("SURFACE_OF_REVOLUTION('',#{profile},#{axis})"))
    }
    fn text(&self) -> String {
        let mut s = String::from(
            "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('test'),'2;1');\n\
             FILE_NAME('t.stp','2026-01-01T00:00:00',(''),(''),'','','');\n\
             FILE_SCHEMA(('CONFIG_CONTROL_DESIGN'));\nENDSEC;\nDATA;\n",
        );
        for (k, l) in self.lines.iter().enumerate() {
            s.push_str(&format!("#{}={l};\n", k + 1));
        }
        s.push_str("ENDSEC;\nEND-ISO-10303-21;\n");
        s
    }
}

fn area(s: &BSplineSurface) -> f64 {
    trimmed_area(s, 96, 96)
}

fn assert_close(got: f64, want: f64, rel: f64) {
    assert!(
        (got - want).abs() <= rel * want.abs(),
        "got {got}, want {want} (relative error {:.2e})",
        (got - want).abs() / want.abs()
    );
}

/// A 4 × 3 rectangle on the plane z = 0 with a circular hole of radius 1.
fn plane_with_hole(f: &mut File) -> u64 {
    let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let plane = f.add(&format!("PLANE('',#{frame})"));
    let c = [
        [0.0, 0.0, 0.0],
        [4.0, 0.0, 0.0],
        [4.0, 3.0, 0.0],
        [0.0, 3.0, 0.0],
    ];
    let v: Vec<u64> = c.iter().map(|&p| f.vertex(p)).collect();
    let e0 = f.line(c[0], c[1], v[0], v[1]);
    let e1 = f.line(c[1], c[2], v[1], v[2]);
    let e2 = f.line(c[2], c[3], v[2], v[3]);
    // The last side is defined the other way round and used reversed.
    let e3 = f.line(c[0], c[3], v[0], v[3]);
    let outer = f.bound(&[(e0, true), (e1, true), (e2, true), (e3, false)], true);
    let vh = f.vertex([3.0, 1.5, 0.0]);
    let hole = f.circle(
        [2.0, 1.5, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        1.0,
        vh,
        vh,
        true,
    );
    let inner = f.bound(&[(hole, false)], false);
    f.face(&[outer, inner], plane)
}

#[test]
fn step_plane_face_with_a_hole_has_the_exact_area() {
    let mut f = File::default();
    let id = plane_with_hole(&mut f);
    let imp = parse_step(&f.text()).unwrap();
    assert_eq!(imp.surfaces.len(), 1);
    let s = &imp.surfaces[0];
    assert_eq!((s.entity, s.surface_type.as_str()), (id, "PLANE"));
    assert!(s.surface.is_trimmed());
    // The hole is an exact rational circle: the area agrees to 1e-6.
    assert_close(area(&s.surface), 12.0 - PI, 1e-6);
    assert!(!s.surface.contains_uv(2.0, 1.5));
    assert!(s.surface.contains_uv(0.5, 0.5));
    assert_eq!(s.surface.eval(4.0, 3.0), Vec3::new(4.0, 3.0, 0.0));
}

#[test]
fn step_half_cylinder_face_has_the_exact_area() {
    let mut f = File::default();
    let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let cyl = f.add(&format!("CYLINDRICAL_SURFACE('',#{frame},2.)"));
    let (a, b, c, d) = (
        [2.0, 0.0, 0.0],
        [-2.0, 0.0, 0.0],
        [-2.0, 0.0, 5.0],
        [2.0, 0.0, 5.0],
    );
    let (va, vb, vc, vd) = (f.vertex(a), f.vertex(b), f.vertex(c), f.vertex(d));
    let bottom = f.circle(
        [0.0; 3],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        2.0,
        va,
        vb,
        true,
    );
    let side1 = f.line(b, c, vb, vc);
    let top = f.circle(
        [0.0, 0.0, 5.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        2.0,
        vd,
        vc,
        true,
    );
    let side2 = f.line(d, a, vd, va);
    let outer = f.bound(
        &[(bottom, true), (side1, true), (top, false), (side2, true)],
        true,
    );
    f.face(&[outer], cyl);
    let imp = parse_step(&f.text()).unwrap();
    let s = &imp.surfaces[0].surface;
    assert_close(area(s), 10.0 * PI, 1e-3);
    // Every point of the NURBS lies on the cylinder.
    let ([u0, u1], [v0, v1]) = (s.domain_u(), s.domain_v());
    for k in 0..=20 {
        let p = s.eval(
            u0 + (u1 - u0) * k as f64 / 20.0,
            v0 + (v1 - v0) * (k % 7) as f64 / 6.0,
        );
        assert!((p.x.hypot(p.y) - 2.0).abs() < 1e-12, "{p:?}");
        assert!(p.y >= -1e-12 && p.z >= -1e-12 && p.z <= 5.0 + 1e-12);
    }
}

/// The sphere patch of radius 3 between longitudes 0 and 90° and latitudes
/// 0 and 60°.
fn sphere_patch(f: &mut File) -> u64 {
    let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let sph = f.add(&format!("SPHERICAL_SURFACE('',#{frame},3.)"));
    let h = 3.0 * (PI / 3.0).sin();
    let (e0, e1, n1, n2) = (
        [3.0, 0.0, 0.0],
        [0.0, 3.0, 0.0],
        [1.5, 0.0, h],
        [0.0, 1.5, h],
    );
    let (ve0, ve1, vn1, vn2) = (f.vertex(e0), f.vertex(e1), f.vertex(n1), f.vertex(n2));
    let equator = f.circle(
        [0.0; 3],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        3.0,
        ve0,
        ve1,
        true,
    );
    let m90 = f.circle(
        [0.0; 3],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        3.0,
        ve1,
        vn2,
        true,
    );
    let lat = f.circle(
        [0.0, 0.0, h],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        1.5,
        vn1,
        vn2,
        true,
    );
    let m0 = f.circle(
        [0.0; 3],
        [0.0, -1.0, 0.0],
        [1.0, 0.0, 0.0],
        3.0,
        ve0,
        vn1,
        true,
    );
    let outer = f.bound(
        &[(equator, true), (m90, true), (lat, false), (m0, false)],
        true,
    );
    f.face(&[outer], sph)
}

#[test]
fn step_sphere_patch_has_the_exact_area() {
    let mut f = File::default();
    sphere_patch(&mut f);
    let imp = parse_step(&f.text()).unwrap();
    let s = &imp.surfaces[0].surface;
    assert_close(area(s), 9.0 * (PI / 2.0) * (PI / 3.0).sin(), 1e-3);
    let (u, v) = s.domain_center();
    assert!((s.eval(u, v).length() - 3.0).abs() < 1e-12);
}

#[test]
fn step_bspline_face_without_pcurves_is_trimmed_by_projection() {
    // The bilinear patch S(u, v) = (4u, 3v, 0) cut by the circle of radius 1
    // around (2, 1.5): the face is the disk, area π.
    let mut f = File::default();
    let pts: Vec<u64> = [[0.0, 0.0], [0.0, 3.0], [4.0, 0.0], [4.0, 3.0]]
        .iter()
        .map(|p| f.point([p[0], p[1], 0.0]))
        .collect();
    let surf = f.add(&format!(
        "B_SPLINE_SURFACE_WITH_KNOTS('',1,1,((#{},#{}),(#{},#{})),.UNSPECIFIED.,.F.,.F.,.F.,(2,2),(2,2),(0.,1.),(0.,1.),.UNSPECIFIED.)",
        pts[0], pts[1], pts[2], pts[3]
    ));
    let v = f.vertex([3.0, 1.5, 0.0]);
    let c = f.circle(
        [2.0, 1.5, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        1.0,
        v,
        v,
        true,
    );
    let b = f.bound(&[(c, true)], true);
    f.face(&[b], surf);
    let imp = parse_step(&f.text()).unwrap();
    let s = &imp.surfaces[0];
    assert_eq!(s.surface_type, "B_SPLINE_SURFACE_WITH_KNOTS");
    assert_close(area(&s.surface), PI, 1e-3);
    assert!(s.surface.contains_uv(0.5, 0.5) && !s.surface.contains_uv(0.1, 0.1));
}

#[test]
fn step_units_and_errors_name_the_entity() {
    let mut f = File::default();
    plane_with_hole(&mut f);
    let mm = f.add("(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.))");
    let m = f.add(&format!(
        "LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4),#{mm})"
    ));
    let inch = f.add(&format!(
        "(CONVERSION_BASED_UNIT('INCH',#{m})LENGTH_UNIT()NAMED_UNIT(*))"
    ));
    f.add(&format!(
        "(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNIT_ASSIGNED_CONTEXT((#{inch}))REPRESENTATION_CONTEXT('',''))"
    ));
    let imp = parse_step(&f.text()).unwrap();
    assert_eq!(imp.unit, Some(LengthUnit::from_iges_name("IN").unwrap()));
    // An unsupported surface type: the offset of a degenerate torus.
    let mut g = File::default();
    let frame = g.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let plane = g.add(&format!(
        "DEGENERATE_TOROIDAL_SURFACE('',#{frame},1.,2.,.T.)"
    ));
    let off = g.add(&format!("OFFSET_SURFACE('',#{plane},1.,.F.)"));
    let v = g.vertex([1.0, 0.0, 0.0]);
    let c = g.circle([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], 1.0, v, v, true);
    let b = g.bound(&[(c, true)], true);
    g.face(&[b], off);
    let err = parse_step(&g.text()).unwrap_err().to_string();
    assert!(
        err.contains(&format!(
            "#{off} OFFSET_SURFACE: an offset of a DEGENERATE_TOROIDAL_SURFACE is not supported"
        )),
        "{err}"
    );
    // A reference to an instance that is not there.
    let bad = g.text().replace(
        &format!("OFFSET_SURFACE('',#{plane}"),
        "OFFSET_SURFACE('',#999",
    );
    let bad = bad.replace(&format!(",#{off},.T.)"), ",#999,.T.)");
    let err = parse_step(&bad).unwrap_err().to_string();
    assert!(
        err.contains("refers to #999, which is not defined"),
        "{err}"
    );
    let err = read_step("/nonexistent.step").unwrap_err().to_string();
    assert!(err.contains("/nonexistent.step"), "{err}");
}

fn options() -> StepWriteOptions {
    StepWriteOptions {
        timestamp: "2026-01-01T12:00:00".into(),
        ..StepWriteOptions::default()
    }
}

/// Writes, reads back, and checks every number bit for bit.
fn round_trip(surfaces: &[BSplineSurface]) -> String {
    let text = surfaces_to_step(surfaces, &options()).unwrap();
    let back = parse_step(&text).unwrap();
    assert_eq!(back.unit, Some(LengthUnit::millimetre()));
    assert_eq!(back.surfaces.len(), surfaces.len());
    for (a, b) in surfaces.iter().zip(&back.surfaces) {
        assert_eq!(a, &b.surface);
        assert_eq!(bits(a), bits(&b.surface));
    }
    assert_trims_from_pcurves(surfaces, &back);
    text
}

/// Every trim curve of a written file is read from its p-curve (the 3-D
/// curves the writer puts beside them are the curves on the surface, exact
/// or fitted within the file's uncertainty, which the p-curves agree with).
fn assert_trims_from_pcurves(surfaces: &[BSplineSurface], back: &StepImport) {
    let curves: usize = surfaces
        .iter()
        .flat_map(|s| s.trims())
        .map(|l| l.curves.len())
        .sum();
    assert_eq!(
        back.trim_sources,
        TrimSources {
            pcurve: curves,
            edge: 0,
            pcurve_rejected: 0
        },
        "{:?}",
        back.warnings
    );
    assert!(back.warnings.is_empty(), "{:?}", back.warnings);
}

fn bits(s: &BSplineSurface) -> Vec<u64> {
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
}

#[test]
fn step_write_round_trip_of_generated_and_read_surfaces() {
    let generated = crate::io::iges_write::tests::generated();
    let text = round_trip(&generated);
    assert!(text.contains("RATIONAL_B_SPLINE_SURFACE") && text.contains("ADVANCED_FACE"));
    // The 3-D edge curves are the curves on the surfaces (cubics, conics,
    // iso-curves), no polylines sampled from them.
    assert!(!text.contains(".POLYLINE_FORM."));
    // Faces read from hand-written files (exact conics, projected
    // polylines) come back bit-identical after writing.
    let mut f = File::default();
    plane_with_hole(&mut f);
    sphere_patch(&mut f);
    let read: Vec<BSplineSurface> = parse_step(&f.text())
        .unwrap()
        .surfaces
        .into_iter()
        .map(|s| s.surface)
        .collect();
    assert_eq!(read.len(), 2);
    let text = round_trip(&read);
    // And the written file's areas are the closed forms.
    let again = parse_step(&text).unwrap();
    assert_close(area(&again.surfaces[0].surface), 12.0 - PI, 1e-6);
    assert_close(
        area(&again.surfaces[1].surface),
        9.0 * (PI / 2.0) * (PI / 3.0).sin(),
        1e-3,
    );
    // Inch files say so.
    let inch = StepWriteOptions {
        unit: LengthUnit::inch(),
        ..options()
    };
    let t = surfaces_to_step(&read, &inch).unwrap();
    assert_eq!(parse_step(&t).unwrap().unit, Some(LengthUnit::inch()));
}

#[test]
fn step_write_round_trip_of_the_impeller_and_teapot() {
    if let Some(path) = crate::shared_data::shared_data("surfaces/impeller.igs") {
        let s: Vec<BSplineSurface> = read_iges(path)
            .unwrap()
            .surfaces
            .into_iter()
            .map(|s| s.surface)
            .collect();
        round_trip(&s);
    }
    if let Some(path) = crate::shared_data::shared_data("surfaces/teapot.json") {
        round_trip(&read_surfaces_json(path).unwrap());
    }
}

#[test]
fn step_reader_never_panics_on_mutations() {
    let mut f = File::default();
    plane_with_hole(&mut f);
    sphere_patch(&mut f);
    let text = f.text().into_bytes();
    let mut rng = crate::bspline::tests::Rng::new(7);
    let alphabet = b"0123456789#,;.()'$*-E TF";
    for _ in 0..2000 {
        let mut t = text.clone();
        for _ in 0..1 + (rng.unit() * 3.0) as usize {
            let at = (rng.unit() * t.len() as f64) as usize % t.len();
            t[at] = alphabet[(rng.unit() * alphabet.len() as f64) as usize % alphabet.len()];
        }
        if let Ok(imp) = parse_step_bytes(&t) {
            for s in &imp.surfaces {
                let (u, v) = s.surface.domain_center();
                assert!(s.surface.eval(u, v).is_finite());
            }
        }
    }
}

/// Edges of the quarter (0 ≤ angle ≤ 90°) of a surface of revolution about
/// z between two parallel circles: `(r0, z0)` and `(r1, z1)`, the
/// generators straight lines in the planes y = 0 and x = 0.
fn quarter_loop(f: &mut File, (r0, z0): (f64, f64), (r1, z1): (f64, f64)) -> u64 {
    let (a, b) = ([r0, 0.0, z0], [0.0, r0, z0]);
    let (c, dd) = ([0.0, r1, z1], [r1, 0.0, z1]);
    let (va, vb, vc, vd) = (f.vertex(a), f.vertex(b), f.vertex(c), f.vertex(dd));
    let bottom = f.circle(
        [0.0, 0.0, z0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        r0,
        va,
        vb,
        true,
    );
    let side1 = f.line(b, c, vb, vc);
    let top = f.circle(
        [0.0, 0.0, z1],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        r1,
        vd,
        vc,
        true,
    );
    let side0 = f.line(a, dd, va, vd);
    f.bound(
        &[(bottom, true), (side1, true), (top, false), (side0, false)],
        true,
    )
}

#[test]
fn step_cone_torus_revolution_and_extrusion_faces_have_exact_areas() {
    // Cone: radius 1 at z = 0, semi-angle 30° (given in degrees through a
    // conversion-based plane angle unit), quarter between z = 0 and z = 2.
    let mut f = File::default();
    let rad = f.add("(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.))");
    let m = f.add(&format!(
        "PLANE_ANGLE_MEASURE_WITH_UNIT(PLANE_ANGLE_MEASURE({:?}),#{rad})",
        PI / 180.0
    ));
    let deg = f.add(&format!(
        "(CONVERSION_BASED_UNIT('DEGREE',#{m})NAMED_UNIT(*)PLANE_ANGLE_UNIT())"
    ));
    f.add(&format!(
        "(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNIT_ASSIGNED_CONTEXT((#{deg}))REPRESENTATION_CONTEXT('',''))"
    ));
    let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let cone = f.add(&format!("CONICAL_SURFACE('',#{frame},1.,30.)"));
    let t = (PI / 6.0).tan();
    let r1 = 1.0 + 2.0 * t;
    let b = quarter_loop(&mut f, (1.0, 0.0), (r1, 2.0));
    f.face(&[b], cone);
    let imp = parse_step(&f.text()).unwrap();
    let slant = 2.0 / (PI / 6.0).cos();
    assert_close(
        area(&imp.surfaces[0].surface),
        PI * (1.0 + r1) * slant / 4.0,
        1e-3,
    );

    // Torus R = 3, r = 1: u and v (the minor angle) both in [0, 90°].
    let mut f = File::default();
    let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let torus = f.add(&format!("TOROIDAL_SURFACE('',#{frame},3.,1.)"));
    let (a, bb, c, d) = (
        [4.0, 0.0, 0.0],
        [0.0, 4.0, 0.0],
        [0.0, 3.0, 1.0],
        [3.0, 0.0, 1.0],
    );
    let (va, vb, vc, vd) = (f.vertex(a), f.vertex(bb), f.vertex(c), f.vertex(d));
    let equator = f.circle(
        [0.0; 3],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        4.0,
        va,
        vb,
        true,
    );
    let minor90 = f.circle(
        [0.0, 3.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        1.0,
        vb,
        vc,
        true,
    );
    let top = f.circle(
        [0.0, 0.0, 1.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        3.0,
        vd,
        vc,
        true,
    );
    let minor0 = f.circle(
        [3.0, 0.0, 0.0],
        [0.0, -1.0, 0.0],
        [1.0, 0.0, 0.0],
        1.0,
        va,
        vd,
        true,
    );
    let b = f.bound(
        &[
            (equator, true),
            (minor90, true),
            (top, false),
            (minor0, false),
        ],
        true,
    );
    f.face(&[b], torus);
    let imp = parse_step(&f.text()).unwrap();
    let s = &imp.surfaces[0].surface;
    assert_close(area(s), (PI / 2.0) * (3.0 * PI / 2.0 + 1.0), 1e-3);
    let (u, v) = s.domain_center();
    let p = s.eval(u, v);
    assert!(
        ((p.x.hypot(p.y) - 3.0).hypot(p.z) - 1.0).abs() < 1e-12,
        "{p:?}"
    );

    // Surface of revolution of the B-spline segment (1, 0, 0)–(2, 0, 2): a
    // frustum, radii 1 and 2, slant √5.
    let mut f = File::default();
    let (p0, p1) = (f.point([1.0, 0.0, 0.0]), f.point([2.0, 0.0, 2.0]));
    let rev = f.revolution_about_z(&format!(
        "1,(#{p0},#{p1}),.UNSPECIFIED.,.F.,.F.,(2,2),(0.,1.),.UNSPECIFIED."
    ));
    let b = quarter_loop(&mut f, (1.0, 0.0), (2.0, 2.0));
    f.face(&[b], rev);
    let imp = parse_step(&f.text()).unwrap();
    assert_close(
        area(&imp.surfaces[0].surface),
        PI * 3.0 * 5f64.sqrt() / 4.0,
        1e-3,
    );

    // Linear extrusion of the circle of radius 2 along z: a quarter of the
    // cylinder between z = 0 and z = 3.
    let mut f = File::default();
    let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let circle = f.add(&format!("CIRCLE('',#{frame},2.)"));
    let z = f.dir([0.0, 0.0, 1.0]);
    let vec = f.add(&format!("VECTOR('',#{z},1.)"));
    let ext = f.add(&format!("SURFACE_OF_LINEAR_EXTRUSION('',#{circle},#{vec})"));
    let b = quarter_loop(&mut f, (2.0, 0.0), (2.0, 3.0));
    f.face(&[b], ext);
    let imp = parse_step(&f.text()).unwrap();
    // Lateral area 2π·r·h over four.
    assert_close(
        area(&imp.surfaces[0].surface),
        2.0 * PI * 2.0 * 3.0 / 4.0,
        1e-3,
    );
}

#[test]
fn step_full_cylinder_with_a_seam_edge() {
    // The whole lateral surface of a cylinder r = 1, h = 2: two full
    // circles joined by a seam line used in both directions.
    let mut f = File::default();
    let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let cyl = f.add(&format!("CYLINDRICAL_SURFACE('',#{frame},1.)"));
    let (a, b) = ([1.0, 0.0, 0.0], [1.0, 0.0, 2.0]);
    let (va, vb) = (f.vertex(a), f.vertex(b));
    let bottom = f.circle(
        [0.0; 3],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        1.0,
        va,
        va,
        true,
    );
    let top = f.circle(
        [0.0, 0.0, 2.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        1.0,
        vb,
        vb,
        true,
    );
    let seam = f.line(a, b, va, vb);
    let l = f.bound(
        &[(bottom, true), (seam, true), (top, false), (seam, false)],
        true,
    );
    f.face(&[l], cyl);
    let imp = parse_step(&f.text()).unwrap();
    assert_close(area(&imp.surfaces[0].surface), 2.0 * PI * 2.0, 1e-3);
}

impl File {
    /// A face bound with the given orientation flag.
    fn bound_oriented(&mut self, edges: &[(u64, bool)], outer: bool, orientation: bool) -> u64 {
        let b = self.bound(edges, outer);
        let last = self.lines.len() - 1;
        if !orientation {
            self.lines[last] = self.lines[last].replace(",.T.)", ",.F.)");
        }
        b
    }
    /// A face with the given `same_sense`.
    fn face_sense(&mut self, bounds: &[u64], surface: u64, same_sense: bool) -> u64 {
        let f = self.face(bounds, surface);
        if !same_sense {
            let last = self.lines.len() - 1;
            self.lines[last] = self.lines[last].replace(",.T.)", ",.F.)");
        }
        f
    }
    /// The full circle of radius `r` about the z axis at height `z` as a
    /// closed edge (vertex at angle 0).
    fn full_circle(&mut self, r: f64, z: f64) -> u64 {
        let v = self.vertex([r, 0.0, z]);
        self.circle(
            [0.0, 0.0, z],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            r,
            v,
            v,
            true,
        )
    }
}

fn only_surface(text: &str) -> StepSurface {
    let imp = parse_step(text).unwrap();
    assert_eq!(imp.surfaces.len(), 1);
    imp.surfaces.into_iter().next().unwrap()
}

#[test]
fn step_full_turn_faces_without_a_seam_edge_have_exact_areas() {
    // A cylinder r = 1 between z = 0 and z = 2 bounded by two full circles
    // (two outer bounds, as OCCT writes them): the face is left of each
    // bound seen from outside — the bottom runs counter-clockwise seen from
    // above, the top clockwise. Written three ways round that all mean the
    // same face: flags on the oriented edges, on the bounds, or on the edge
    // curve itself.
    for variant in 0..4 {
        let mut f = File::default();
        let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
        let cyl = f.add(&format!("CYLINDRICAL_SURFACE('',#{frame},1.)"));
        let bottom = f.full_circle(1.0, 0.0);
        let top = f.full_circle(1.0, 2.0);
        let (b0, b1) = match variant {
            0 => (
                f.bound(&[(bottom, true)], true),
                f.bound(&[(top, false)], true),
            ),
            1 => (
                f.bound(&[(bottom, true)], true),
                f.bound_oriented(&[(top, true)], true, false),
            ),
            2 => {
                // The edge curve runs against its (counter-clockwise)
                // circle.
                let v = f.vertex([1.0, 0.0, 2.0]);
                let against = f.circle(
                    [0.0, 0.0, 2.0],
                    [0.0, 0.0, 1.0],
                    [1.0, 0.0, 0.0],
                    1.0,
                    v,
                    v,
                    false,
                );
                (
                    f.bound(&[(bottom, true)], true),
                    f.bound(&[(against, true)], true),
                )
            }
            _ => {
                // The top circle defined clockwise (axis −z): its edge
                // curve runs with it.
                let v = f.vertex([1.0, 0.0, 2.0]);
                let cw = f.circle(
                    [0.0, 0.0, 2.0],
                    [0.0, 0.0, -1.0],
                    [1.0, 0.0, 0.0],
                    1.0,
                    v,
                    v,
                    true,
                );
                (
                    f.bound(&[(bottom, true)], true),
                    f.bound(&[(cw, true)], true),
                )
            }
        };
        f.face(&[b0, b1], cyl);
        let s = only_surface(&f.text()).surface;
        assert_close(area(&s), 4.0 * PI, 1e-6);
        let (u, v) = s.domain_center();
        let p = s.eval(u, v);
        assert!((p.x.hypot(p.y) - 1.0).abs() < 1e-12, "{p:?}");
    }
}

/// A sphere of radius 2 about the origin cut by the circle of latitude 30°
/// (z = 1), traversed counter-clockwise seen from above, with the face's
/// `same_sense`.
fn sphere_cut(same_sense: bool) -> String {
    let mut f = File::default();
    let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let sph = f.add(&format!("SPHERICAL_SURFACE('',#{frame},2.)"));
    let c = f.full_circle(3f64.sqrt(), 1.0);
    let b = f.bound(&[(c, true)], true);
    f.face_sense(&[b], sph, same_sense);
    f.text()
}

#[test]
fn step_sphere_cap_bounded_by_one_circle_and_same_sense() {
    // With same_sense the face normal is the sphere's (outward): seen from
    // outside above, the counter-clockwise circle has the cap on its left —
    // the cap above z = 1, area 2πRh = 2π·2·1. Without, the face normal
    // points inwards and the face is the rest of the sphere, 16π − 4π.
    let cap = only_surface(&sphere_cut(true));
    assert!(cap.same_sense);
    assert_close(area(&cap.surface), 4.0 * PI, 1e-6);
    let (u, v) = cap.surface.domain_center();
    assert!(cap.surface.eval(u, v).z > 1.0);
    let rest = only_surface(&sphere_cut(false));
    assert!(!rest.same_sense);
    assert_close(area(&rest.surface), 12.0 * PI, 1e-6);
    // A cone (radius 1 at z = 0, semi-angle 45°) bounded by that one
    // circle, apex below at z = −1: the face is the part towards the apex
    // (clockwise seen from above), lateral area π r l = π √2.
    let mut f = File::default();
    let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let cone = f.add(&format!("CONICAL_SURFACE('',#{frame},1.,{:?})", PI / 4.0));
    let c = f.full_circle(1.0, 0.0);
    let b = f.bound(&[(c, false)], true);
    f.face(&[b], cone);
    assert_close(
        area(&only_surface(&f.text()).surface),
        PI * 2f64.sqrt(),
        1e-6,
    );
    // The other way round the face would be the unbounded rest of the
    // cone: refused, naming the face.
    let mut g = File::default();
    let frame = g.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let cone = g.add(&format!("CONICAL_SURFACE('',#{frame},1.,{:?})", PI / 4.0));
    let c = g.full_circle(1.0, 0.0);
    let b = g.bound(&[(c, true)], true);
    let face = g.face(&[b], cone);
    let err = parse_step(&g.text()).unwrap_err().to_string();
    assert!(
        err.contains(&format!(
            "#{face} ADVANCED_FACE: a single bound winds around"
        )),
        "{err}"
    );
}

#[test]
fn step_torus_and_sphere_without_bounds_are_whole() {
    let mut f = File::default();
    let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let torus = f.add(&format!("TOROIDAL_SURFACE('',#{frame},3.,1.)"));
    f.face(&[], torus);
    let frame = f.frame([5.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let sph = f.add(&format!("SPHERICAL_SURFACE('',#{frame},2.)"));
    // A sphere bounded by a vertex loop at its pole only.
    let v = f.vertex([5.0, 0.0, 2.0]);
    let vl = f.add(&format!("VERTEX_LOOP('',#{v})"));
    let b = f.add(&format!("FACE_BOUND('',#{vl},.T.)"));
    f.face(&[b], sph);
    let imp = parse_step(&f.text()).unwrap();
    assert_eq!(imp.surfaces.len(), 2);
    // 4π² R r and 4π R².
    assert_close(area(&imp.surfaces[0].surface), 4.0 * PI * PI * 3.0, 1e-6);
    assert_close(area(&imp.surfaces[1].surface), 16.0 * PI, 1e-6);
    // A plane has no whole: refused.
    let mut g = File::default();
    let frame = g.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let plane = g.add(&format!("PLANE('',#{frame})"));
    let face = g.face(&[], plane);
    let err = parse_step(&g.text()).unwrap_err().to_string();
    assert!(err.contains(&format!("#{face} ADVANCED_FACE")), "{err}");
}

/// A plane z = 0 face over [−2, 2]² with a circular hole of radius 1 about
/// the origin, and a face `inside` filling the hole: both trimmed, meeting
/// along the hole's circle. Returns the file's surfaces.
fn plane_with_a_filled_hole(inside: &dyn Fn(&mut File, u64) -> u64) -> Vec<BSplineSurface> {
    let mut f = File::default();
    let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let plane = f.add(&format!("PLANE('',#{frame})"));
    let c = [
        [-2.0, -2.0, 0.0],
        [2.0, -2.0, 0.0],
        [2.0, 2.0, 0.0],
        [-2.0, 2.0, 0.0],
    ];
    let v: Vec<u64> = c.iter().map(|&p| f.vertex(p)).collect();
    let sides: Vec<(u64, bool)> = (0..4)
        .map(|k| (f.line(c[k], c[(k + 1) % 4], v[k], v[(k + 1) % 4]), true))
        .collect();
    let outer = f.bound(&sides, true);
    let hole = f.full_circle(1.0, 0.0);
    let inner = f.bound(&[(hole, false)], false);
    f.face(&[outer, inner], plane);
    inside(&mut f, hole);
    parse_step(&f.text())
        .unwrap()
        .surfaces
        .into_iter()
        .map(|s| s.surface)
        .collect()
}

#[test]
fn continuity_along_trims_of_step_faces() {
    use crate::bspline::continuity::{Boundary, ContinuityOptions, Seam, SeamClass, continuity};
    let opts = ContinuityOptions::default();
    // The one seam: the plane's hole (loop 1) against the filling face's
    // circle.
    let seam = |surfaces: &[BSplineSurface]| {
        assert_eq!(surfaces.len(), 2);
        assert!(surfaces[0].is_trimmed());
        let r = continuity(surfaces, &opts).unwrap();
        // Besides it, only the seam of a closed filling face with itself
        // (the cone's and torus's u = u0 / u1 sides).
        let between: Vec<&Seam> = r.seams.iter().filter(|s| s.surfaces == [0, 1]).collect();
        assert_eq!(
            between.len(),
            1,
            "{:?}",
            r.seams
                .iter()
                .map(|s| (s.surfaces, s.sides))
                .collect::<Vec<_>>()
        );
        assert!(
            r.seams
                .iter()
                .all(|s| s.surfaces == [0, 1] || s.surfaces == [1, 1])
        );
        let s = between[0].clone();
        assert_eq!(s.surfaces, [0, 1]);
        assert!(
            matches!(s.sides[0], Boundary::Trim(t) if t.loop_index == 1),
            "{:?}",
            s.sides
        );
        // The filling face's circle: a trimming curve of the disk; a side
        // of the cone and torus faces, which are whole NURBS patches.
        assert_eq!(
            matches!(s.sides[1], Boundary::Trim(_)),
            surfaces[1].is_trimmed(),
            "{:?}",
            s.sides
        );
        // The whole circle, closed: measured as 64 chords (of a rational
        // parameterisation), just under 2π.
        assert!(
            s.length < 2.0 * PI && s.length > 2.0 * PI * (1.0 - 1e-3),
            "{}",
            s.length
        );
        assert!(s.g0_max < r.tolerance, "{} vs {}", s.g0_max, r.tolerance);
        s
    };
    // G2: the disk of the same plane.
    let s = seam(&plane_with_a_filled_hole(&|f, hole| {
        let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
        let plane = f.add(&format!("PLANE('',#{frame})"));
        let b = f.bound(&[(hole, true)], true);
        f.face(&[b], plane)
    }));
    assert_eq!(s.class, SeamClass::G2, "{s:?}");
    assert!(s.g1_max_deg < 1e-3 && s.g2_max < 1e-9, "{s:?}");
    // G0: a cone rising 20° towards its apex above the centre (radius 1 at
    // z = 0, semi-angle −70°: the radius shrinks as z grows): the tangent
    // planes meet at 20° all round.
    let s = seam(&plane_with_a_filled_hole(&|f, hole| {
        let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
        let cone = f.add(&format!(
            "CONICAL_SURFACE('',#{frame},1.,{:?})",
            -(70f64.to_radians())
        ));
        let b = f.bound(&[(hole, true)], true);
        f.face(&[b], cone)
    }));
    assert_eq!(s.class, SeamClass::G0, "{s:?}");
    assert!((s.g1_max_deg - 20.0).abs() < 0.05, "{s:?}");
    // G1: the upper inner quarter of a torus tube (major radius 1, minor
    // 0.25, centre circle 0.25 below the plane): tangent to the plane along
    // the hole's circle, curvature 1/0.25 across it against the plane's 0.
    // Its second bound, the tube's innermost circle, winds round too.
    let s = seam(&plane_with_a_filled_hole(&|f, hole| {
        let frame = f.frame([0.0, 0.0, -0.25], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
        let torus = f.add(&format!("TOROIDAL_SURFACE('',#{frame},1.,0.25)"));
        let inner = f.full_circle(0.75, -0.25);
        let b0 = f.bound(&[(hole, true)], true);
        let b1 = f.bound(&[(inner, false)], true);
        f.face(&[b0, b1], torus)
    }));
    assert_eq!(s.class, SeamClass::G1, "{s:?}");
    assert!(s.g1_max_deg < 0.05, "{s:?}");
    assert!((s.g2_max - 4.0).abs() < 0.05, "{s:?}");
}

#[test]
fn step_conic_pcurve_on_a_bspline_surface_is_exact() {
    // The bilinear patch S(u, v) = (4u, 3v, 0) bounded by an ellipse in 3-D
    // whose p-curve is the circle of radius 1/4 about (½, ½) in (u, v): the
    // face is the ellipse with semi-axes 1 and ¾, area ¾π. The arc is exact
    // (a 256-gon would miss the area by 1e-4).
    for (forward, orientation) in [(true, true), (false, true), (true, false)] {
        let mut f = File::default();
        let pts: Vec<u64> = [[0.0, 0.0], [0.0, 3.0], [4.0, 0.0], [4.0, 3.0]]
            .iter()
            .map(|p| f.point([p[0], p[1], 0.0]))
            .collect();
        let surf = f.add(&format!(
            "B_SPLINE_SURFACE_WITH_KNOTS('',1,1,((#{},#{}),(#{},#{})),.UNSPECIFIED.,.F.,.F.,.F.,(2,2),(2,2),(0.,1.),(0.,1.),.UNSPECIFIED.)",
            pts[0], pts[1], pts[2], pts[3]
        ));
        let frame = f.frame([2.0, 1.5, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
        let ellipse = f.add(&format!("ELLIPSE('',#{frame},1.,0.75)"));
        let c2 = f.add("CARTESIAN_POINT('',(0.5,0.5))");
        let d2 = f.add("DIRECTION('',(1.,0.))");
        let a2 = f.add(&format!("AXIS2_PLACEMENT_2D('',#{c2},#{d2})"));
        let circle = f.add(&format!("CIRCLE('',#{a2},0.25)"));
        let ctx = f.add(
            "(GEOMETRIC_REPRESENTATION_CONTEXT(2)PARAMETRIC_REPRESENTATION_CONTEXT()REPRESENTATION_CONTEXT('2D SPACE',''))",
        );
        let dr = f.add(&format!(
            "DEFINITIONAL_REPRESENTATION('',(#{circle}),#{ctx})"
        ));
        let pc = f.add(&format!("PCURVE('',#{surf},#{dr})"));
        let sc = f.add(&format!("SURFACE_CURVE('',#{ellipse},(#{pc}),.PCURVE_S1.)"));
        let v = f.vertex([3.0, 1.5, 0.0]);
        let same = if forward { ".T." } else { ".F." };
        let e = f.add(&format!("EDGE_CURVE('',#{v},#{v},#{sc},{same})"));
        let b = f.bound_oriented(&[(e, forward)], true, orientation);
        f.face(&[b], surf);
        let s = only_surface(&f.text()).surface;
        assert_close(area(&s), 0.75 * PI, 1e-5);
        let c = &s.trims()[0].curves;
        assert_eq!(c.len(), 1);
        assert!(c[0].weights().is_some(), "a rational arc, not a polyline");
        assert!(s.contains_uv(0.5, 0.5) && !s.contains_uv(0.5, 0.2));
    }
}

/// A third-party file of `tests/data/step` (see SOURCE.md there).
fn real_step(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/step")
        .join(name)
}

/// Instances of a simple entity `name` in STEP text, counted by scanning
/// the text (`#id = NAME (`, any spacing) — independently of the parser.
fn count_instances(text: &str, name: &str) -> usize {
    text.split(';')
        .filter(|inst| {
            inst.split_once('=').is_some_and(|(_, rest)| {
                rest.trim_start()
                    .strip_prefix(name)
                    .is_some_and(|r| r.trim_start().starts_with('('))
            })
        })
        .count()
}

#[test]
fn real_step_cube_and_full_turn_cylinder_have_exact_areas() {
    // CadQuery's test file: a 10 mm cube and a cylinder r = 5 mm, h = 10 mm
    // whose side is one face bounded by two full circles without a seam.
    let path = real_step("red_cube_blue_cylinder.step");
    let text = std::fs::read_to_string(&path).unwrap();
    assert_eq!(count_instances(&text, "ADVANCED_FACE"), 9);
    let imp = read_step(&path).unwrap();
    assert_eq!(imp.unit.as_ref().map(|u| u.metres), Some(1.0));
    assert_eq!(imp.surfaces.len(), 9);
    let (r, h, side) = (0.005, 0.01, 0.01);
    let mut by_type: std::collections::BTreeMap<&str, Vec<f64>> = Default::default();
    for s in &imp.surfaces {
        by_type
            .entry(s.surface_type.as_str())
            .or_default()
            .push(area(&s.surface));
    }
    let planes = &by_type["PLANE"];
    let cylinder = &by_type["CYLINDRICAL_SURFACE"];
    assert_eq!((planes.len(), cylinder.len()), (8, 1));
    assert_close(cylinder[0], 2.0 * PI * r * h, 1e-6);
    let mut planes = planes.clone();
    planes.sort_by(f64::total_cmp);
    for (k, a) in planes.iter().enumerate() {
        // two discs π r² (< side²; exact rational circles, integrated to
        // the quadrature's 3e-6 where the trim cuts cells), then six squares
        let (want, rel) = if k < 2 {
            (PI * r * r, 1e-5)
        } else {
            (side * side, 1e-6)
        };
        assert_close(*a, want, rel);
    }
    let surfaces: Vec<BSplineSurface> = imp.surfaces.into_iter().map(|s| s.surface).collect();
    round_trip_in_unit(&surfaces, imp.unit.unwrap_or_else(LengthUnit::millimetre));
}

#[test]
fn real_step_featuretype_reads_with_the_publishers_area() {
    // trimesh's SolidWorks part (inches): 96 faces, planes, cylinders and
    // one ruled B-spline surface; no p-curves.
    let path = real_step("featuretype.STEP");
    let text = std::fs::read_to_string(&path).unwrap();
    let faces = count_instances(&text, "ADVANCED_FACE");
    assert_eq!(faces, 96);
    let imp = read_step(&path).unwrap();
    assert_eq!(imp.unit, Some(LengthUnit::inch()));
    assert_eq!(imp.surfaces.len(), faces);
    let count = |t: &str| imp.surfaces.iter().filter(|s| s.surface_type == t).count();
    assert_eq!(
        (
            count("PLANE"),
            count("CYLINDRICAL_SURFACE"),
            count("B_SPLINE_SURFACE_WITH_KNOTS")
        ),
        (49, 46, 1)
    );
    let total: f64 = imp.surfaces.iter().map(|s| area(&s.surface)).sum();
    // The publisher's tessellation of the same part (featuretype.STL).
    let stl = crate::io::read_soup(real_step("featuretype.STL")).unwrap();
    let stl_area: f64 = stl
        .offsets
        .windows(2)
        .map(|w| {
            let t = &stl.indices[w[0] as usize..w[1] as usize];
            let [a, b, c] = [0, 1, 2].map(|k| stl.positions[t[k] as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    eprintln!(
        "featuretype: area {total} in², the publisher's STL {stl_area} in² ({:+.3e} relative)",
        (total - stl_area) / stl_area
    );
    // The tessellation's chords cut the 46 cylindrical faces short, so it
    // lies a little below the exact area: measured +1.8e-4.
    assert!(total > stl_area, "{total} vs {stl_area}");
    assert_close(total, stl_area, 5e-4);
    let surfaces: Vec<BSplineSurface> = imp.surfaces.into_iter().map(|s| s.surface).collect();
    round_trip_in_unit(&surfaces, LengthUnit::inch());
}

/// [`round_trip`] written in `unit`.
fn round_trip_in_unit(surfaces: &[BSplineSurface], unit: LengthUnit) {
    let o = StepWriteOptions {
        unit: unit.clone(),
        ..options()
    };
    let text = surfaces_to_step(surfaces, &o).unwrap();
    let back = parse_step(&text).unwrap();
    assert_eq!(back.unit, Some(unit));
    assert_eq!(back.surfaces.len(), surfaces.len());
    for (a, b) in surfaces.iter().zip(&back.surfaces) {
        assert_eq!(bits(a), bits(&b.surface));
        assert_eq!(a, &b.surface);
    }
    assert_trims_from_pcurves(surfaces, &back);
}

// ---------------------------------------------------------------------
// P-curves (ADVANCED_FACE bounds as trimming loops, using the
// p-curves when present).

impl File {
    /// A 2-D LINE `p + t·d` (the VECTOR's magnitude is `|d|`).
    fn line2(&mut self, p: [f64; 2], d: [f64; 2]) -> u64 {
        let pt = self.add(&format!("CARTESIAN_POINT('',({:?},{:?}))", p[0], p[1]));
        let len = d[0].hypot(d[1]);
        let dir = self.add(&format!(
            "DIRECTION('',({:?},{:?}))",
            d[0] / len,
            d[1] / len
        ));
        let v = self.add(&format!("VECTOR('',#{dir},{len:?})"));
        self.add(&format!("LINE('',#{pt},#{v})"))
    }
    /// A 2-D CIRCLE about `c` (reference direction +u).
    fn circle2(&mut self, c: [f64; 2], r: f64) -> u64 {
        let pt = self.add(&format!("CARTESIAN_POINT('',({:?},{:?}))", c[0], c[1]));
        let d = self.add("DIRECTION('',(1.,0.))");
        let a = self.add(&format!("AXIS2_PLACEMENT_2D('',#{pt},#{d})"));
        self.add(&format!("CIRCLE('',#{a},{r:?})"))
    }
    /// Gives the curve of EDGE_CURVE `edge` the p-curves `curves2` (2-D
    /// curve ids) on `surface`: a SURFACE_CURVE (SEAM_CURVE for two) whose
    /// 3-D curve is the edge's curve.
    fn pcurves(&mut self, edge: u64, surface: u64, curves2: &[u64]) {
        let ctx = self.add(
            "(GEOMETRIC_REPRESENTATION_CONTEXT(2)PARAMETRIC_REPRESENTATION_CONTEXT()REPRESENTATION_CONTEXT('2D SPACE',''))",
        );
        let pcs: Vec<String> = curves2
            .iter()
            .map(|c| {
                let dr = self.add(&format!("DEFINITIONAL_REPRESENTATION('',(#{c}),#{ctx})"));
                format!("#{}", self.add(&format!("PCURVE('',#{surface},#{dr})")))
            })
            .collect();
        let line = self.lines[edge as usize - 1].clone();
        let parts: Vec<&str> = line.split(',').collect();
        assert!(parts[0].starts_with("EDGE_CURVE"), "{line}");
        let kind = if curves2.len() == 2 {
            "SEAM_CURVE"
        } else {
            "SURFACE_CURVE"
        };
        let sc = self.add(&format!(
            "{kind}('',{},({}),.CURVE_3D.)",
            parts[3],
            pcs.join(",")
        ));
        let mut parts: Vec<String> = parts.iter().map(|p| p.to_string()).collect();
        parts[3] = format!("#{sc}");
        self.lines[edge as usize - 1] = parts.join(",");
    }
}

/// An L-shaped face on the cylinder r = 2 about z (angles 0..π, heights
/// 0..5, less the corner angles 0..π/2 × heights 2.5..5), area
/// 2·(5π − 1.25π) = 7.5π. Every edge gets its p-curve (ISO (u, v) = (angle,
/// height), the 3-D curves' parameters) unless `skip` names it; the p-curve
/// of the edge `distort` is moved by `offset` in (u, v). Returns the text
/// and the EDGE_CURVE ids in loop order.
fn cylinder_l_face(
    distort: Option<usize>,
    offset: [f64; 2],
    skip: Option<usize>,
) -> (String, Vec<u64>) {
    let mut f = File::default();
    let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let cyl = f.add(&format!("CYLINDRICAL_SURFACE('',#{frame},2.)"));
    let at = |a: f64, z: f64| [2.0 * a.cos(), 2.0 * a.sin(), z];
    let h = PI / 2.0;
    let corners = [
        at(0.0, 0.0),
        at(PI, 0.0),
        at(PI, 5.0),
        at(h, 5.0),
        at(h, 2.5),
        at(0.0, 2.5),
    ];
    let v: Vec<u64> = corners.iter().map(|&c| f.vertex(c)).collect();
    let zx = ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let e = [
        f.circle([0.0; 3], zx.0, zx.1, 2.0, v[0], v[1], true),
        f.line(corners[1], corners[2], v[1], v[2]),
        f.circle([0.0, 0.0, 5.0], zx.0, zx.1, 2.0, v[3], v[2], true),
        f.line(corners[3], corners[4], v[3], v[4]),
        f.circle([0.0, 0.0, 2.5], zx.0, zx.1, 2.0, v[5], v[4], true),
        f.line(corners[5], corners[0], v[5], v[0]),
    ];
    // P-curves in the 3-D curves' parameters: circles by their angle,
    // lines p + t·(b − a), t ∈ [0, 1].
    let pc = [
        ([0.0, 0.0], [1.0, 0.0]),
        ([PI, 0.0], [0.0, 5.0]),
        ([0.0, 5.0], [1.0, 0.0]),
        ([h, 5.0], [0.0, -2.5]),
        ([0.0, 2.5], [1.0, 0.0]),
        ([0.0, 2.5], [0.0, -2.5]),
    ];
    for (k, (p, d)) in pc.into_iter().enumerate() {
        if skip == Some(k) {
            continue;
        }
        let p = if distort == Some(k) {
            [p[0] + offset[0], p[1] + offset[1]]
        } else {
            p
        };
        let l2 = f.line2(p, d);
        f.pcurves(e[k], cyl, &[l2]);
    }
    let outer = f.bound(
        &[
            (e[0], true),
            (e[1], true),
            (e[2], false),
            (e[3], true),
            (e[4], false),
            (e[5], true),
        ],
        true,
    );
    f.face(&[outer], cyl);
    (f.text(), e.to_vec())
}

/// The 3-D distance from the surface along every trim curve (101 samples
/// each) to the nearest of `edges` (closed forms: points on the cylinder
/// r = 2 about z whose angle or height is that of the edge).
fn largest_distance_from_l_face_edges(s: &BSplineSurface) -> f64 {
    let h = PI / 2.0;
    // (angle range, height) of the arcs; (angle, height range) of the lines.
    let arcs = [((0.0, PI), 0.0), ((h, PI), 5.0), ((0.0, h), 2.5)];
    let lines = [(PI, (0.0, 5.0)), (h, (2.5, 5.0)), (0.0, (0.0, 2.5))];
    let mut worst: f64 = 0.0;
    for l in s.trims() {
        for c in &l.curves {
            let [a, b] = c.domain();
            for k in 0..=100 {
                let [u, v] = c.eval(a + (b - a) * k as f64 / 100.0);
                let p = s.eval(u, v);
                let (ang, z) = (p.y.atan2(p.x), p.z);
                let on_cyl = (p.x.hypot(p.y) - 2.0).abs();
                let d_arc = arcs
                    .iter()
                    .filter(|((a0, a1), _)| ang >= a0 - 1e-9 && ang <= a1 + 1e-9)
                    .map(|(_, hz)| (z - hz).abs())
                    .fold(f64::INFINITY, f64::min);
                let d_line = lines
                    .iter()
                    .filter(|(_, (z0, z1))| z >= z0 - 1e-9 && z <= z1 + 1e-9)
                    .map(|(la, _)| 2.0 * (ang - la).abs())
                    .fold(f64::INFINITY, f64::min);
                worst = worst.max(on_cyl + d_arc.min(d_line));
            }
        }
    }
    worst
}

#[test]
fn step_pcurves_on_a_cylinder_are_used_and_map_exactly_onto_the_edges() {
    let (text, _) = cylinder_l_face(None, [0.0; 2], None);
    let imp = parse_step(&text).unwrap();
    assert_eq!(
        imp.trim_sources,
        TrimSources {
            pcurve: 6,
            edge: 0,
            pcurve_rejected: 0
        }
    );
    assert!(imp.warnings.is_empty(), "{:?}", imp.warnings);
    let s = &imp.surfaces[0].surface;
    let curves = &s.trims()[0].curves;
    assert_eq!(curves.len(), 6, "one trim curve per edge");
    // Lines along parameter lines of (angle, height) stay straight through
    // the angle → rational-parameter map: exact two-point lines.
    assert!(
        curves
            .iter()
            .all(|c| c.degree() == 1 && c.control_points().len() == 2)
    );
    // The NURBS along every trim curve lies on its 3-D edge: the angle
    // passed through ArcMap::param and evaluated on the rational arcs comes
    // back to the angle exactly.
    let worst = largest_distance_from_l_face_edges(s);
    assert!(
        worst < 1e-12,
        "largest distance from the 3-D edges {worst:e}"
    );
    assert_close(area(s), 7.5 * PI, 1e-6);
    // The same face without p-curves: the same area from the 3-D edges.
    let (computed, _) = cylinder_l_face(Some(0), [0.0; 2], Some(0));
    let imp2 = parse_step(&computed).unwrap();
    assert_eq!(
        (imp2.trim_sources.pcurve, imp2.trim_sources.edge),
        (5, 1),
        "edge 0 has no p-curve"
    );
    assert_close(area(&imp2.surfaces[0].surface), 7.5 * PI, 1e-6);
}

#[test]
fn step_a_distorted_pcurve_is_rejected_for_its_3d_edge_with_a_warning() {
    // The middle arc's p-curve raised by 0.2 (4 % of the height), and the
    // inner vertical line's moved by 0.05 rad: both disagree with their
    // 3-D edges; the face is trimmed by the 3-D edges there, with the same
    // area.
    for (edge, offset) in [(4, [0.0, 0.2]), (3, [0.05, 0.0])] {
        let (text, ids) = cylinder_l_face(Some(edge), offset, None);
        let imp = parse_step(&text).unwrap();
        assert_eq!(
            imp.trim_sources,
            TrimSources {
                pcurve: 5,
                edge: 0,
                pcurve_rejected: 1
            },
            "edge {edge}"
        );
        assert_eq!(imp.warnings.len(), 1);
        let w = &imp.warnings[0];
        assert!(
            w.contains(&format!("#{}", ids[edge])) && w.contains("disagree"),
            "{w}"
        );
        let s = &imp.surfaces[0].surface;
        let worst = largest_distance_from_l_face_edges(s);
        assert!(
            worst < 1e-9,
            "edge {edge}: distance from the 3-D edges {worst:e}"
        );
        assert_close(area(s), 7.5 * PI, 1e-6);
    }
}

#[test]
fn step_pcurves_on_a_sphere_octant_close_through_the_pole() {
    // The octant of the sphere r = 3: equator 0..90°, the meridian at 90°
    // up to the pole, the meridian at 0° down again. P-curves (u, v) =
    // (longitude, latitude) in DEGREES (the file's plane angle unit), the
    // meridians reaching the pole at their own longitudes: the loop in
    // (u, v) has the pole's stretch between them, degenerate in 3-D. Area
    // 4π·9/8 = 4.5π.
    let mut f = File::default();
    let deg = f.add("(CONVERSION_BASED_UNIT('DEGREE',#1000)NAMED_UNIT(*)PLANE_ANGLE_UNIT())");
    let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let sph = f.add(&format!("SPHERICAL_SURFACE('',#{frame},3.)"));
    let (e0, e1, pole) = ([3.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, 3.0]);
    let (v0, v1, vp) = (f.vertex(e0), f.vertex(e1), f.vertex(pole));
    let equator = f.circle(
        [0.0; 3],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        3.0,
        v0,
        v1,
        true,
    );
    let m90 = f.circle(
        [0.0; 3],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        3.0,
        v1,
        vp,
        true,
    );
    let m0 = f.circle(
        [0.0; 3],
        [0.0, -1.0, 0.0],
        [1.0, 0.0, 0.0],
        3.0,
        v0,
        vp,
        true,
    );
    // The 3-D circles' parameter is in radians; p-curves in degrees run
    // u = (180/π)·t: the LINE's direction has that length.
    let k = 180.0 / PI;
    let l_eq = f.line2([0.0, 0.0], [k, 0.0]);
    let l_90 = f.line2([90.0, 0.0], [0.0, k]);
    let l_0 = f.line2([0.0, 0.0], [0.0, k]);
    f.pcurves(equator, sph, &[l_eq]);
    f.pcurves(m90, sph, &[l_90]);
    f.pcurves(m0, sph, &[l_0]);
    let outer = f.bound(&[(equator, true), (m90, true), (m0, false)], true);
    f.face(&[outer], sph);
    let mut text = f.text();
    // The unit instance refers to a measure with unit: 1° = π/180 rad.
    let rad = "#1000=PLANE_ANGLE_MEASURE_WITH_UNIT(PLANE_ANGLE_MEASURE(0.017453292519943295),#1001);\n#1001=(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.));\n";
    text = text.replace("ENDSEC;\nEND-ISO", &format!("{rad}ENDSEC;\nEND-ISO"));
    let _ = deg;
    let imp = parse_step(&text).unwrap();
    assert_eq!(
        imp.trim_sources,
        TrimSources {
            pcurve: 3,
            edge: 0,
            pcurve_rejected: 0
        },
        "{:?}",
        imp.warnings
    );
    let s = &imp.surfaces[0].surface;
    assert_close(area(s), 4.5 * PI, 1e-6);
    for c in &s.trims()[0].curves {
        let [a, b] = c.domain();
        for j in 0..=50 {
            let [u, v] = c.eval(a + (b - a) * j as f64 / 50.0);
            let p = s.eval(u, v);
            // On the sphere and on one of the three great-circle arcs.
            assert!((p.length() - 3.0).abs() < 1e-12, "{p}");
            assert!(p.x.abs().min(p.y.abs()).min(p.z.abs()) < 1e-12, "{p}");
        }
    }
}

#[test]
fn step_pcurves_on_a_plane_replace_the_edges_and_a_wrong_radius_is_rejected() {
    // The plane with a hole of radius 1 about (2, 1.5): the hole's circle
    // gets a p-curve CIRCLE in the plane frame's (u, v) — radius 1 (used,
    // exact rational arc) or 1.1 (rejected: the hole is the 3-D circle).
    for (r2, used) in [(1.0, true), (1.1, false)] {
        let mut f = File::default();
        let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
        let plane = f.add(&format!("PLANE('',#{frame})"));
        let c = [
            [0.0, 0.0, 0.0],
            [4.0, 0.0, 0.0],
            [4.0, 3.0, 0.0],
            [0.0, 3.0, 0.0],
        ];
        let v: Vec<u64> = c.iter().map(|&p| f.vertex(p)).collect();
        let e: Vec<u64> = (0..4)
            .map(|k| f.line(c[k], c[(k + 1) % 4], v[k], v[(k + 1) % 4]))
            .collect();
        let outer = f.bound(
            &[(e[0], true), (e[1], true), (e[2], true), (e[3], true)],
            true,
        );
        let vh = f.vertex([3.0, 1.5, 0.0]);
        let hole = f.circle(
            [2.0, 1.5, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            1.0,
            vh,
            vh,
            true,
        );
        let c2 = f.circle2([2.0, 1.5], r2);
        f.pcurves(hole, plane, &[c2]);
        let inner = f.bound(&[(hole, false)], false);
        f.face(&[outer, inner], plane);
        let imp = parse_step(&f.text()).unwrap();
        let want = if used {
            TrimSources {
                pcurve: 1,
                edge: 4,
                pcurve_rejected: 0,
            }
        } else {
            TrimSources {
                pcurve: 0,
                edge: 4,
                pcurve_rejected: 1,
            }
        };
        assert_eq!(imp.trim_sources, want, "radius {r2}");
        assert_eq!(imp.warnings.len(), usize::from(!used));
        let s = &imp.surfaces[0].surface;
        assert_close(area(s), 12.0 - PI, 1e-6);
        assert!(s.trims()[1].curves[0].weights().is_some(), "an exact arc");
    }
}

#[test]
fn step_partial_bspline_pcurve_is_an_exact_piece() {
    // The bilinear patch S(u, v) = (4u, 3v, 0) and an edge along the middle
    // part t ∈ [0.2, 0.8] of a quadratic B-spline p-curve (its 3-D curve the
    // same B-spline mapped by S), closed by a straight edge. The trim is
    // the exact piece (degree 2, split by knot insertion), not samples: the
    // area agrees with the closed form of the piece's region.
    let mut f = File::default();
    let pts: Vec<u64> = [[0.0, 0.0], [0.0, 3.0], [4.0, 0.0], [4.0, 3.0]]
        .iter()
        .map(|p| f.point([p[0], p[1], 0.0]))
        .collect();
    let surf = f.add(&format!(
        "B_SPLINE_SURFACE_WITH_KNOTS('',1,1,((#{},#{}),(#{},#{})),.UNSPECIFIED.,.F.,.F.,.F.,(2,2),(2,2),(0.,1.),(0.,1.),.UNSPECIFIED.)",
        pts[0], pts[1], pts[2], pts[3]
    ));
    // Quadratic, knots (0,0,0,0.5,1,1,1): control points in (u, v).
    let ctrl = [[0.1, 0.2], [0.3, 0.9], [0.7, 0.95], [0.9, 0.3]];
    let curve = |f: &mut File, dim3: bool| {
        let ids: Vec<String> = ctrl
            .iter()
            .map(|c| {
                let id = if dim3 {
                    f.point([4.0 * c[0], 3.0 * c[1], 0.0])
                } else {
                    f.add(&format!("CARTESIAN_POINT('',({:?},{:?}))", c[0], c[1]))
                };
                format!("#{id}")
            })
            .collect();
        f.add(&format!(
            "B_SPLINE_CURVE_WITH_KNOTS('',2,({}),.UNSPECIFIED.,.F.,.F.,(3,1,3),(0.,0.5,1.),.UNSPECIFIED.)",
            ids.join(",")
        ))
    };
    let c3 = curve(&mut f, true);
    let c2 = curve(&mut f, false);
    let n = crate::io::step::nurbs::Nurbs3 {
        degree: 2,
        knots: vec![0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0],
        points: ctrl.iter().map(|c| Vec3::new(c[0], c[1], 0.0)).collect(),
        weights: None,
    };
    let (a, b) = (n.eval(0.2), n.eval(0.8));
    let to3 = |p: Vec3| [4.0 * p.x, 3.0 * p.y, 0.0];
    let (va, vb) = (f.vertex(to3(a)), f.vertex(to3(b)));
    let arc = f.add(&format!("EDGE_CURVE('',#{va},#{vb},#{c3},.T.)"));
    f.pcurves(arc, surf, &[c2]);
    let chord = f.line(to3(b), to3(a), vb, va);
    let outer = f.bound(&[(arc, true), (chord, true)], true);
    f.face(&[outer], surf);
    let imp = parse_step(&f.text()).unwrap();
    assert_eq!(
        imp.trim_sources,
        TrimSources {
            pcurve: 1,
            edge: 1,
            pcurve_rejected: 0
        },
        "{:?}",
        imp.warnings
    );
    let s = &imp.surfaces[0].surface;
    let piece = &s.trims()[0].curves[0];
    assert_eq!(piece.degree(), 2, "the exact piece");
    for j in 0..=40 {
        let t = 0.2 + 0.6 * j as f64 / 40.0;
        let [pa, pb] = piece.domain();
        let [u, v] = piece.eval(pa + (pb - pa) * (t - 0.2) / 0.6);
        let q = n.eval(t);
        assert!((u - q.x).abs() < 1e-14 && (v - q.y).abs() < 1e-14, "{t}");
    }
    // The region between the piece and its chord, by Green's theorem on a
    // fine polygon of the exact curve (2e5 chords: exact to ~1e-11), times
    // the patch's Jacobian 12.
    let m = 200_000;
    let mut poly: Vec<[f64; 2]> = (0..=m)
        .map(|j| {
            let q = n.eval(0.2 + 0.6 * j as f64 / m as f64);
            [q.x, q.y]
        })
        .collect();
    poly.push([a.x, a.y]);
    let want = 12.0 * 0.5 * crate::bspline::polygon_signed_area2(&poly).abs();
    // (the trim is flattened to 1e-6 of the domain diagonal for the area)
    assert_close(area(s), want, 2e-5);
}

#[test]
fn real_step_files_have_no_pcurves_and_read_from_their_edges() {
    // Neither real part carries p-curves (SolidWorks and the CadQuery
    // export): every trim comes from the 3-D edges, as before; their
    // written copies (tests above) read every trim from its p-curve.
    for name in ["featuretype.STEP", "red_cube_blue_cylinder.step"] {
        let imp = read_step(real_step(name)).unwrap();
        let t = imp.trim_sources;
        assert_eq!((t.pcurve, t.pcurve_rejected), (0, 0), "{name}");
        assert!(t.edge > 0, "{name}");
        assert!(imp.warnings.is_empty(), "{name}");
    }
}

// The p-curve check tracks the nearest edge point along the edge (cheap
// and still exact enough).

/// A square plate [0, 10]² (bilinear) trimmed by one loop: a cubic
/// B-spline from (1, 1) to (9, 1) through a wave, then straight back
/// round (9, 9) and (1, 9); the B-spline's middle control point moved by
/// `bump` in v.
fn plate_with_a_wavy_side(bump: f64) -> BSplineSurface {
    let corner = |u: f64, v: f64| Vec3::new(u, v, 0.0);
    let s = BSplineSurface::from_flat(
        1,
        1,
        vec![0.0, 0.0, 10.0, 10.0],
        vec![0.0, 0.0, 10.0, 10.0],
        [2, 2],
        vec![
            corner(0.0, 0.0),
            corner(0.0, 10.0),
            corner(10.0, 0.0),
            corner(10.0, 10.0),
        ],
        None,
    )
    .unwrap();
    let wave = TrimCurve::new(
        3,
        vec![0.0, 0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0, 1.0],
        vec![
            [1.0, 1.0],
            [3.0, 0.5],
            [5.0, 1.5 + bump],
            [7.0, 0.5],
            [9.0, 1.0],
        ],
        None,
    )
    .unwrap();
    let curves = vec![
        wave,
        TrimCurve::line([9.0, 1.0], [9.0, 9.0]).unwrap(),
        TrimCurve::line([9.0, 9.0], [1.0, 9.0]).unwrap(),
        TrimCurve::line([1.0, 9.0], [1.0, 1.0]).unwrap(),
    ];
    s.with_trims(vec![TrimLoop { curves }]).unwrap()
}

/// The plate written as STEP with its 3-D edges (the exact curves on the
/// plane: the trim curves mapped by the planar surface) and, from a second writing with the wave's middle
/// control point moved by `bump`, the p-curves: the lines holding 2-D
/// points are taken from the second text (both writings number their
/// instances alike).
fn plate_with_a_bumped_pcurve(bump: f64) -> String {
    let exact = surfaces_to_step(&[plate_with_a_wavy_side(0.0)], &options()).unwrap();
    let moved = surfaces_to_step(&[plate_with_a_wavy_side(bump)], &options()).unwrap();
    let two_d = |l: &str| l.contains("CARTESIAN_POINT") && l.matches(',').count() == 2;
    let (a, b): (Vec<&str>, Vec<&str>) = (exact.lines().collect(), moved.lines().collect());
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(&b)
        .map(|(x, y)| if two_d(x) { *y } else { *x })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn step_pcurve_check_along_written_edges_accepts_within_and_rejects_beyond_the_tolerance() {
    // The tolerance here is 1e-6 of the plate's control box diagonal
    // (1.4e-5; the writer's uncertainty is 1e-7). The middle control point
    // of a cubic with knots 0,0,0,0,½,1,1,1,1 moves the curve by at most
    // bump · N₂(½) = bump / 2, across the curve there (its tangent is
    // level at t = ½ by symmetry). The 3-D edge is the writer's exact
    // cubic (the unbumped wave mapped by the plane): bumps of 1e-7 and 1e-6
    // are accepted, 0.1 and 0.3 (0.05, 0.15 across) rejected, with the
    // largest distance about bump/2 (the distance to the nearest point of
    // the edge, a little less than the offset across it).
    let tolerance = 1e-6 * 200f64.sqrt();
    for (bump, used) in [
        (0.0, true),
        (1e-7, true),
        (1e-6, true),
        (0.1, false),
        (0.3, false),
    ] {
        let text = plate_with_a_bumped_pcurve(bump);
        let imp = parse_step(&text).unwrap();
        let want = if used {
            TrimSources {
                pcurve: 4,
                edge: 0,
                pcurve_rejected: 0,
            }
        } else {
            TrimSources {
                pcurve: 3,
                edge: 0,
                pcurve_rejected: 1,
            }
        };
        assert_eq!(imp.trim_sources, want, "bump {bump}: {:?}", imp.warnings);
        let s = &imp.surfaces[0].surface;
        if used {
            // The p-curve is the trim curve, bit for bit.
            assert_eq!(
                s.trims()[0].curves[0],
                plate_with_a_wavy_side(bump).trims()[0].curves[0]
            );
        } else {
            // The warning states the largest distance: half the bump (the
            // check samples t = ½), the nearest point of the edge a little
            // along it making it less by at most 0.004.
            let w = &imp.warnings[0];
            let largest: f64 = w
                .split("largest ")
                .nth(1)
                .and_then(|r| r.split(' ').next())
                .and_then(|x| x.parse().ok())
                .unwrap_or_else(|| panic!("{w}"));
            assert!(largest > tolerance, "{w}");
            assert!(
                largest <= bump / 2.0 + tolerance && largest >= bump / 2.0 - 0.004,
                "bump {bump}: {w}"
            );
        }
        // Either way the face's area is the plate's (the wave changes it
        // by less than 0.1 %): from the 3-D edge where the p-curve is
        // rejected.
        assert_close(area(s), area(&plate_with_a_wavy_side(0.0)), 1e-3);
    }
}

// Faces whose bounds wind around their surface without a seam edge, with
// p-curves (use them there too when valid).

impl File {
    /// A closed 2-D cubic B-spline p-curve `(u, v) = (θ, g(θ))` for
    /// θ ∈ [θ0, θ0 + 2π], uniform unclamped knots (128 spans), control
    /// points by the cubic quasi-interpolant `(−g₋ + 8g₀ − g₊)/6`
    /// (error O(h⁴): about 1e-7 times the largest fourth derivative of
    /// g); u is linear in θ exactly.
    fn closed_pcurve(&mut self, theta0: f64, g: impl Fn(f64) -> f64) -> u64 {
        let n = 128;
        let h = 2.0 * PI / n as f64;
        let pts: Vec<String> = (0..n + 3)
            .map(|i| {
                let x = theta0 + (i as f64 - 1.0) * h;
                let v = (-g(x - h) + 8.0 * g(x) - g(x + h)) / 6.0;
                format!(
                    "#{}",
                    self.add(&format!("CARTESIAN_POINT('',({x:?},{v:?}))"))
                )
            })
            .collect();
        let knots: Vec<String> = (0..n + 7)
            .map(|j| format!("{:?}", theta0 + (j as f64 - 3.0) * h))
            .collect();
        let mults = vec!["1"; n + 7].join(",");
        self.add(&format!(
            "B_SPLINE_CURVE_WITH_KNOTS('',3,({}),.UNSPECIFIED.,.F.,.F.,({mults}),({}),.UNSPECIFIED.)",
            pts.join(","),
            knots.join(",")
        ))
    }
}

/// The cylinder r = 1 about z between the circle z = 0 and its cut by the
/// plane z = 2 + x/2 (an ellipse, semi-axes √1.25 and 1): the bottom circle
/// with the p-curve LINE (θ, 0), the ellipse starting at angle `theta0`
/// with its B-spline p-curve (θ, 2 + cos θ / 2) (unless `pcurves` is
/// false). Area ∫(2 + cos θ / 2) dθ = 4π.
fn cylinder_under_an_inclined_cut(theta0: f64, pcurves: bool) -> String {
    let mut f = File::default();
    let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let cyl = f.add(&format!("CYLINDRICAL_SURFACE('',#{frame},1.)"));
    let bottom = f.full_circle(1.0, 0.0);
    let (c0, s0) = (theta0.cos(), theta0.sin());
    let v = f.vertex([c0, s0, 2.0 + 0.5 * c0]);
    let a = 1.25f64.sqrt();
    let ef = f.frame(
        [0.0, 0.0, 2.0],
        [-0.5 / a, 0.0, 1.0 / a],
        [1.0 / a, 0.0, 0.5 / a],
    );
    let el = f.add(&format!("ELLIPSE('',#{ef},{a:?},1.)"));
    let top = f.add(&format!("EDGE_CURVE('',#{v},#{v},#{el},.T.)"));
    if pcurves {
        let l = f.line2([0.0, 0.0], [1.0, 0.0]);
        f.pcurves(bottom, cyl, &[l]);
        let c = f.closed_pcurve(theta0, |t| 2.0 + 0.5 * t.cos());
        f.pcurves(top, cyl, &[c]);
    }
    let b0 = f.bound(&[(bottom, true)], true);
    let b1 = f.bound(&[(top, false)], true);
    f.face(&[b0, b1], cyl);
    f.text()
}

#[test]
fn step_winding_bounds_take_their_pcurves_with_the_closed_form_area() {
    // Both bounds have a vertex at angle 0, where the surface is cut open:
    // both trims from the p-curves (the circle's LINE p-curve a straight
    // trim line at v = 0, the ellipse's B-spline p-curve mapped through the
    // angle → rational-parameter map), the loop closed along the cut.
    let imp = parse_step(&cylinder_under_an_inclined_cut(0.0, true)).unwrap();
    assert_eq!(
        imp.trim_sources,
        TrimSources {
            pcurve: 2,
            edge: 0,
            pcurve_rejected: 0
        },
        "{:?}",
        imp.warnings
    );
    let s = &imp.surfaces[0].surface;
    assert_close(area(s), 4.0 * PI, 1e-3);
    // The trim runs along the ellipse: the surface along every trim curve
    // lies on the cylinder between z = 0 and the plane, within the reader's
    // tolerance for p-curves (1e-6 of the NURBS's control box diagonal,
    // √(2² + 2² + 2.5²)).
    let tolerance = 1e-6 * (8.0f64 + 6.25).sqrt();
    for c in &s.trims()[0].curves {
        let [a, b] = c.domain();
        for k in 0..=200 {
            let [u, v] = c.eval(a + (b - a) * k as f64 / 200.0);
            let p = s.eval(u, v);
            assert!((p.x.hypot(p.y) - 1.0).abs() < 1e-9, "{p:?}");
            assert!(p.z > -1e-9 && p.z < 2.0 + 0.5 * p.x + tolerance, "{p:?}");
        }
    }
    // Without p-curves the same face from the 3-D edges.
    let from_edges = parse_step(&cylinder_under_an_inclined_cut(0.0, false)).unwrap();
    assert_eq!(from_edges.trim_sources.edge, 2);
    assert_close(area(&from_edges.surfaces[0].surface), 4.0 * PI, 1e-3);
    // The ellipse's vertex a quarter turn away from the cut: its p-curve
    // would cross the cut, so both bounds come from the 3-D edges (no
    // warning: the p-curves are not wrong).
    let off = parse_step(&cylinder_under_an_inclined_cut(PI / 2.0, true)).unwrap();
    assert_eq!(
        off.trim_sources,
        TrimSources {
            pcurve: 0,
            edge: 2,
            pcurve_rejected: 0
        }
    );
    assert!(off.warnings.is_empty(), "{:?}", off.warnings);
    assert_close(area(&off.surfaces[0].surface), 4.0 * PI, 1e-3);
}

/// The sphere R = 2 about the origin cut by a plane whose normal leans
/// β = 20° from z, the cap of angular radius α = 50° around it (it holds
/// the pole, so its one bound winds once round the sphere). The bound: the
/// circle in that plane, vertex at longitude 0 (latitude 20°),
/// counter-clockwise seen from above (the cap on its left), with its
/// B-spline p-curve (θ, φ(θ) + offset): φ solves cos φ cos θ sin β +
/// sin φ cos β = cos α. Returns the text, the EDGE_CURVE's id and the
/// cap's area 2πR²(1 − cos α).
fn tilted_sphere_cap(offset: f64) -> (String, u64, f64) {
    let (r, alpha, beta) = (2.0f64, 50f64.to_radians(), 20f64.to_radians());
    let lat = |t: f64| {
        let (a, b) = (t.cos() * beta.sin(), beta.cos());
        (alpha.cos() / a.hypot(b)).asin() - a.atan2(b)
    };
    let mut f = File::default();
    let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let sph = f.add(&format!("SPHERICAL_SURFACE('',#{frame},{r:?})"));
    let n = [beta.sin(), 0.0, beta.cos()];
    let h = r * alpha.cos();
    let c = [h * n[0], 0.0, h * n[2]];
    let phi0 = lat(0.0);
    let v = [r * phi0.cos(), 0.0, r * phi0.sin()];
    let rad = r * alpha.sin();
    let x = [(v[0] - c[0]) / rad, 0.0, (v[2] - c[2]) / rad];
    let vid = f.vertex(v);
    let circle = f.circle(c, n, x, rad, vid, vid, true);
    let pc = f.closed_pcurve(0.0, |t| lat(t) + offset);
    f.pcurves(circle, sph, &[pc]);
    let b = f.bound(&[(circle, true)], true);
    f.face(&[b], sph);
    (f.text(), circle, 2.0 * PI * r * r * (1.0 - alpha.cos()))
}

#[test]
fn step_tilted_sphere_cap_takes_its_pcurve_and_closes_through_the_pole() {
    let (text, _, want) = tilted_sphere_cap(0.0);
    let imp = parse_step(&text).unwrap();
    let t = imp.trim_sources;
    assert_eq!(
        (t.pcurve, t.edge, t.pcurve_rejected),
        (1, 0, 0),
        "{:?}",
        imp.warnings
    );
    assert!(imp.warnings.is_empty(), "{:?}", imp.warnings);
    let s = &imp.surfaces[0].surface;
    assert_close(area(s), want, 1e-3);
    // The pole is inside the face.
    let ([u0, u1], [_, v1]) = (s.domain_u(), s.domain_v());
    assert!(s.eval(0.5 * (u0 + u1), v1).z > 2.0 - 1e-12);
}

#[test]
fn step_tilted_sphere_cap_with_a_raised_pcurve_is_read_from_its_circle() {
    // The p-curve raised by 0.01 rad is rejected, the trim comes from the
    // 3-D circle, the same area.
    let (text, circle, want) = tilted_sphere_cap(0.01);
    let imp = parse_step(&text).unwrap();
    let t = imp.trim_sources;
    assert_eq!((t.pcurve, t.edge, t.pcurve_rejected), (0, 0, 1));
    assert!(
        imp.warnings[0].contains(&format!("#{circle}")),
        "{:?}",
        imp.warnings
    );
    assert_close(area(&imp.surfaces[0].surface), want, 1e-3);
}

/// OFFSET_SURFACE of a sphere, a torus and a plane: the surface of the same
/// kind grown (or moved) by the distance, exactly; nested offsets add up;
/// an offset that would turn a radius negative is refused naming it.
#[test]
fn step_offsets_of_elementary_surfaces_are_exact() {
    for (basis, d, want) in [
        ("SPHERICAL_SURFACE('',#F,1.)", 0.5, 4.0 * PI * 1.5 * 1.5),
        (
            "TOROIDAL_SURFACE('',#F,3.,1.)",
            0.25,
            4.0 * PI * PI * 3.0 * 1.25,
        ),
    ] {
        let mut g = File::default();
        let frame = g.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
        let b = g.add(&basis.replace("#F", &format!("#{frame}")));
        // half the distance twice: nested offsets
        let o1 = g.add(&format!("OFFSET_SURFACE('',#{b},{},.F.)", d / 2.0));
        let o2 = g.add(&format!("OFFSET_SURFACE('',#{o1},{},.F.)", d / 2.0));
        g.face(&[], o2);
        let imp = parse_step(&g.text()).unwrap();
        let a = area(&imp.surfaces[0].surface);
        assert!((a - want).abs() < 1e-6 * want, "{basis}: {a} vs {want}");
        let text = g.text().replace(&format!("{},.F.)", d / 2.0), "-0.75,.F.)");
        let err = parse_step(&text).unwrap_err().to_string();
        assert!(err.contains("not positive"), "{err}");
    }
    // a plane moved along its normal: the square of side 2 at z = 0.3
    let mut g = File::default();
    let frame = g.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let plane = g.add(&format!("PLANE('',#{frame})"));
    let off = g.add(&format!("OFFSET_SURFACE('',#{plane},0.3,.F.)"));
    let corners = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    let p: Vec<[f64; 3]> = corners.iter().map(|c| [c[0], c[1], 0.3]).collect();
    let v: Vec<u64> = p.iter().map(|q| g.vertex(*q)).collect();
    let edges: Vec<(u64, bool)> = (0..4)
        .map(|k| (g.line(p[k], p[(k + 1) % 4], v[k], v[(k + 1) % 4]), true))
        .collect();
    let b = g.bound(&edges, true);
    g.face(&[b], off);
    let imp = parse_step(&g.text()).unwrap();
    let s = &imp.surfaces[0].surface;
    assert!((area(s) - 4.0).abs() < 1e-9, "{}", area(s));
    let (du, dv) = (s.domain_u(), s.domain_v());
    let mid = s.eval(0.5 * (du[0] + du[1]), 0.5 * (dv[0] + dv[1]));
    assert!((mid.z - 0.3).abs() < 1e-12, "{mid:?}");
}

/// The largest distance of the surface's points on a 9 × 9 parameter grid
/// from `d` off the surface of revolution about z of the meridian curve
/// `meridian` (ρ, z) over [0, 1], measured in the meridian plane.
fn off_revolution_error(s: &BSplineSurface, meridian: impl Fn(f64) -> (f64, f64), d: f64) -> f64 {
    let (du, dv) = (s.domain_u(), s.domain_v());
    let mut worst = 0.0f64;
    for i in 0..9 {
        for j in 0..9 {
            let u = du[0] + (du[1] - du[0]) * i as f64 / 8.0;
            let v = dv[0] + (dv[1] - dv[0]) * j as f64 / 8.0;
            let p = s.eval(u, v);
            let (rho, z) = (p.x.hypot(p.y), p.z);
            let dist = |t: f64| {
                let (r, h) = meridian(t);
                (r - rho).hypot(h - z)
            };
            let mut best = (0..=2000)
                .map(|k| k as f64 / 2000.0)
                .min_by(|a, b| dist(*a).total_cmp(&dist(*b)))
                .unwrap();
            let mut step = 1.0 / 2000.0;
            for _ in 0..60 {
                for cand in [best - step, best + step] {
                    if (0.0..=1.0).contains(&cand) && dist(cand) < dist(best) {
                        best = cand;
                    }
                }
                step *= 0.6;
            }
            worst = worst.max((dist(best) - d).abs());
        }
    }
    worst
}

/// OFFSET_SURFACE of a cone (a cone of the same angle, exactly), of a
/// surface of revolution of a line (the line moved and revolved, exactly),
/// of a curved surface of revolution and of an extrusion (the face's NURBS
/// offset on its parameters, fitted within 1e-7 and warned).
#[test]
fn step_offsets_of_cones_and_swept_surfaces() {
    // Cone r = 1, α = 0.3 rad, height 0 to 1.5, offset by 0.2: radius
    // 1 + 0.2 cos α at height −0.2 sin α.
    let (alpha, d, h) = (0.3f64, 0.2, 1.5);
    let (c, sn, t) = (alpha.cos(), alpha.sin(), alpha.tan());
    let mut g = File::default();
    let frame = g.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let cone = g.add(&format!("CONICAL_SURFACE('',#{frame},1.,{alpha:?})"));
    let off = g.add(&format!("OFFSET_SURFACE('',#{cone},{d:?},.F.)"));
    let (r0, z0) = (1.0 + d * c, -d * sn);
    let (r1, z1) = (1.0 + h * t + d * c, h - d * sn);
    let b = quarter_loop(&mut g, (r0, z0), (r1, z1));
    g.face(&[b], off);
    let imp = parse_step(&g.text()).unwrap();
    assert!(imp.warnings.is_empty(), "{:?}", imp.warnings);
    let s = &imp.surfaces[0].surface;
    assert_close(area(s), PI * (r0 + r1) * (h / c) / 4.0, 1e-3);
    let err = off_revolution_error(s, |x| (1.0 + x * h * t, x * h), d);
    assert!(err < 1e-12, "cone: {err}");

    // The segment (1, 0, 0)–(2, 0, 2) revolved, offset by 0.1 along
    // (z × ρ) × P' ∝ (2, 0, −1): the segment moved, exactly.
    let d = 0.1;
    let n = [2.0 / 5f64.sqrt(), -1.0 / 5f64.sqrt()];
    let mut g = File::default();
    let (p0, p1) = (g.point([1.0, 0.0, 0.0]), g.point([2.0, 0.0, 2.0]));
    let rev = g.revolution_about_z(&format!(
        "1,(#{p0},#{p1}),.UNSPECIFIED.,.F.,.F.,(2,2),(0.,1.),.UNSPECIFIED."
    ));
    let off = g.add(&format!("OFFSET_SURFACE('',#{rev},{d:?},.F.)"));
    let b = quarter_loop(
        &mut g,
        (1.0 + d * n[0], d * n[1]),
        (2.0 + d * n[0], 2.0 + d * n[1]),
    );
    g.face(&[b], off);
    let imp = parse_step(&g.text()).unwrap();
    assert!(imp.warnings.is_empty(), "{:?}", imp.warnings);
    let s = &imp.surfaces[0].surface;
    assert_close(
        area(s),
        PI * (3.0 + 2.0 * d * n[0]) * 5f64.sqrt() / 4.0,
        1e-3,
    );
    let err = off_revolution_error(s, |x| (1.0 + x, 2.0 * x), d);
    assert!(err < 1e-12, "revolved line: {err}");

    // A quadratic bulge (1, 0)–(1.5, 1)–(1, 2) (ρ, z) revolved, offset by
    // 0.1: fitted, within 1e-7 of the size, warned naming the offset.
    let mut g = File::default();
    let q: Vec<u64> = [[1.0, 0.0, 0.0], [1.5, 0.0, 1.0], [1.0, 0.0, 2.0]]
        .iter()
        .map(|p| g.point(*p))
        .collect();
    let rev = g.revolution_about_z(&format!(
        "2,(#{},#{},#{}),.UNSPECIFIED.,.F.,.F.,(3,3),(0.,1.),.UNSPECIFIED.",
        q[0], q[1], q[2]
    ));
    let off = g.add(&format!("OFFSET_SURFACE('',#{rev},{d:?},.F.)"));
    let s5 = 5f64.sqrt();
    let b = quarter_loop(
        &mut g,
        (1.0 + 2.0 * d / s5, -d / s5),
        (1.0 + 2.0 * d / s5, 2.0 + d / s5),
    );
    g.face(&[b], off);
    let imp = parse_step(&g.text()).unwrap();
    assert!(
        imp.warnings.len() == 1 && imp.warnings[0].contains(&format!("#{off} OFFSET_SURFACE")),
        "{:?}",
        imp.warnings
    );
    let bulge = |x: f64| {
        let (a, b, c) = ((1.0 - x) * (1.0 - x), 2.0 * x * (1.0 - x), x * x);
        (a + 1.5 * b + c, b + 2.0 * c)
    };
    let err = off_revolution_error(&imp.surfaces[0].surface, bulge, d);
    assert!(err < 1e-6, "revolved bulge: {err}");

    // The circle of radius 2 extruded along z, offset by 0.25: a quarter
    // of the cylinder of radius 2.25, fitted and warned.
    let mut g = File::default();
    let frame = g.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let circle = g.add(&format!("CIRCLE('',#{frame},2.)"));
    let z = g.dir([0.0, 0.0, 1.0]);
    let vec = g.add(&format!("VECTOR('',#{z},1.)"));
    let ext = g.add(&format!("SURFACE_OF_LINEAR_EXTRUSION('',#{circle},#{vec})"));
    let off = g.add(&format!("OFFSET_SURFACE('',#{ext},0.25,.F.)"));
    let b = quarter_loop(&mut g, (2.25, 0.0), (2.25, 3.0));
    g.face(&[b], off);
    let imp = parse_step(&g.text()).unwrap();
    assert!(
        imp.warnings.len() == 1 && imp.warnings[0].contains(&format!("#{off} OFFSET_SURFACE")),
        "{:?}",
        imp.warnings
    );
    let s = &imp.surfaces[0].surface;
    assert_close(area(s), 2.0 * PI * 2.25 * 3.0 / 4.0, 1e-3);
    let err = off_revolution_error(s, |x| (2.0, 3.0 * x), 0.25);
    assert!(err < 1e-6, "extruded circle: {err}");
}

/// An edge on a closed B-spline curve that ends at the curve's closure
/// point runs forward to the end of the curve's domain, not back to its
/// start: the lower triangle (−1, 0), (0, −2), (1, 0) of a closed polygon
/// (1, 0), (0, 1), (−1, 0), (0, −2), closed by the chord along y = 0 —
/// area 2 (the way back would be the upper triangle, area 1).
#[test]
fn step_edge_ending_at_the_closure_of_a_closed_curve_runs_forward() {
    let mut f = File::default();
    let frame = f.frame([0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    let plane = f.add(&format!("PLANE('',#{frame})"));
    let corners = [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, -2.0, 0.0],
        [1.0, 0.0, 0.0],
    ];
    let pts: Vec<String> = corners
        .iter()
        .map(|c| format!("#{}", f.point(*c)))
        .collect();
    let polygon = f.add(&format!(
        "B_SPLINE_CURVE_WITH_KNOTS('',1,({}),.POLYLINE_FORM.,.T.,.F.,(2,1,1,1,2),(0.,0.25,0.5,0.75,1.),.UNSPECIFIED.)",
        pts.join(",")
    ));
    let (left, right) = (f.vertex([-1.0, 0.0, 0.0]), f.vertex([1.0, 0.0, 0.0]));
    let lower = f.add(&format!("EDGE_CURVE('',#{left},#{right},#{polygon},.T.)"));
    let chord = f.line([1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], right, left);
    let b = f.bound(&[(lower, true), (chord, true)], true);
    f.face(&[b], plane);
    let imp = parse_step(&f.text()).unwrap();
    assert_close(area(&imp.surfaces[0].surface), 2.0, 1e-9);
}
