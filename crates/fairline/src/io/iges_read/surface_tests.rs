//! Tests of the converted surface entities (114, 118, 122, 140) and curves
//! (112, 102) against closed forms.

use super::tests::{GLOBAL, iges_file};
use super::{IgesError, parse_iges};
use crate::Vec3;
use crate::bspline::{BSplineSurface, trimmed_area};
use std::f64::consts::PI;

fn grid(s: &BSplineSurface, n: usize) -> Vec<(f64, f64, Vec3)> {
    let (du, dv) = (s.domain_u(), s.domain_v());
    let mut out = Vec::new();
    for i in 0..=n {
        for j in 0..=n {
            let u = du[0] + (du[1] - du[0]) * i as f64 / n as f64;
            let v = dv[0] + (dv[1] - dv[0]) * j as f64 / n as f64;
            out.push((u, v, s.eval(u, v)));
        }
    }
    out
}

fn only_surface(text: &str) -> BSplineSurface {
    let imp = parse_iges(text).unwrap();
    assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
    assert_eq!(imp.surfaces.len(), 1, "{:?}", imp.surfaces);
    imp.surfaces[0].surface.clone()
}

#[test]
fn iges_tabulated_cylinder_of_a_full_circle_is_an_exact_cylinder() {
    // a full circle of radius 3 (start = end) swept 4 along z, alone and
    // trimmed by a 144 whose boundary is the unit square of (u, v)
    let alone = iges_file(
        GLOBAL,
        &[
            (122, 0, 0, "122,3,3.,0.,4.;"),
            (100, 0, 0, "100,0.,0.,0.,3.,0.,3.,0.;"),
        ],
    );
    let s = only_surface(&alone);
    for (_, _, p) in grid(&s, 40) {
        assert!((p.x.hypot(p.y) - 3.0).abs() < 1e-12, "{p}");
        assert!((-1e-12..=4.0 + 1e-12).contains(&p.z));
    }
    let want = 2.0 * PI * 3.0 * 4.0;
    let area = trimmed_area(&s, 64, 64);
    assert!((area - want).abs() < 1e-9 * want, "{area} vs {want}");

    // trimmed by a 144 whose boundary is a rectangle of (u, v)
    let trimmed = |u: f64, v: f64| {
        let lines = [
            format!("110,0.,0.,0.,{u},0.,0.;"),
            format!("110,{u},0.,0.,{u},{v},0.;"),
            format!("110,{u},{v},0.,0.,{v},0.;"),
            format!("110,0.,{v},0.,0.,0.,0.;"),
        ];
        iges_file(
            GLOBAL,
            &[
                (144, 0, 0, "144,3,1,0,7;"),
                (122, 0, 0, "122,5,3.,0.,4.;"),
                (100, 0, 0, "100,0.,0.,0.,3.,0.,3.,0.;"),
                (142, 0, 0, "142,0,3,9,0,2;"),
                (102, 0, 0, "102,4,11,13,15,17;"),
                (110, 0, 0, &lines[0]),
                (110, 0, 0, &lines[1]),
                (110, 0, 0, &lines[2]),
                (110, 0, 0, &lines[3]),
            ],
        )
    };
    // the whole of it, and half the circle (angles 0 to π) by half the
    // height
    for (u, v, want) in [(1.0, 1.0, want), (0.5, 0.5, PI * 3.0 * 2.0)] {
        let imp = parse_iges(&trimmed(u, v)).unwrap();
        assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
        assert_eq!(imp.surfaces.len(), 1);
        assert_eq!(imp.surfaces[0].trim_entity, Some(1));
        // the quadrature of trimmed cells is good to about 1e-7 here
        let area = trimmed_area(&imp.surfaces[0].surface, 64, 64);
        assert!(
            (area - want).abs() < 1e-6 * want,
            "{u} {v}: {area} vs {want}"
        );
        // the trims are the rectangle in the surface's parameters: the
        // corner (u, v) of the file lies at angle π·2u, height 4v
        let s = &imp.surfaces[0].surface;
        let corner = s.trims()[0].curves[2].eval(s.trims()[0].curves[2].domain()[0]);
        let p = s.eval(corner[0], corner[1]);
        let a = 2.0 * PI * u;
        assert!(
            p.distance(Vec3::new(3.0 * a.cos(), 3.0 * a.sin(), 4.0 * v)) < 1e-12,
            "{p}"
        );
    }
}

#[test]
fn iges_tabulated_cylinder_of_a_closed_composite_and_a_spline_directrix() {
    // a 2 × 2 square of four lines (102), swept 3 along z: 24; a
    // parametric spline curve (112) of two cubic segments as directrix
    let square = iges_file(
        GLOBAL,
        &[
            (122, 0, 0, "122,3,0.,0.,3.;"),
            (102, 0, 0, "102,4,5,7,9,11;"),
            (110, 0, 0, "110,0.,0.,0.,2.,0.,0.;"),
            (110, 0, 0, "110,2.,0.,0.,2.,2.,0.;"),
            (110, 0, 0, "110,2.,2.,0.,0.,2.,0.;"),
            (110, 0, 0, "110,0.,2.,0.,0.,0.,0.;"),
        ],
    );
    let s = only_surface(&square);
    let area = trimmed_area(&s, 64, 64);
    assert!((area - 24.0).abs() < 1e-12, "{area}");

    // x = t, y = t² on [0, 1], then x = 1 + s, y = 1 + 2s + s³ … as
    // power coefficients per segment (A B C D for x, y, z)
    let spline = iges_file(
        GLOBAL,
        &[
            (122, 0, 0, "122,3,0.,0.,2.;"),
            (
                112,
                0,
                0,
                "112,3,1,3,2,0.,1.,2.,0.,1.,0.,0.,0.,0.,1.,0.,0.,0.,0.,0.,\
                 1.,1.,0.,0.,1.,2.,0.,1.,0.,0.,0.,0.,\
                 2.,1.,0.,0.,4.,5.,0.,3.,0.,0.,0.,0.;",
            ),
        ],
    );
    let s = only_surface(&spline);
    for (u, v, p) in grid(&s, 20) {
        // the directrix's parameter [0, 2] is the surface's [0, 1]
        let t = 2.0 * u;
        let (x, y) = if t <= 1.0 {
            (t, t * t)
        } else {
            let r = t - 1.0;
            (1.0 + r, 1.0 + 2.0 * r + r * r * r)
        };
        assert!(p.distance(Vec3::new(x, y, 2.0 * v)) < 1e-12, "{u} {v} {p}");
    }
}

#[test]
fn iges_ruled_surfaces_are_exact_planes_and_cylinders() {
    // two parallel lines 4 long, 2 apart across and 1 up: a plane strip of
    // area 4·√5, by equal parameter (form 1) and equal arc length (form
    // 0); with DIRFLG = 1 and the second line given backwards, the same
    let lines = |form: i64, second: &'static str, flag: &'static str| {
        iges_file(
            GLOBAL,
            &[
                (118, 0, form, flag),
                (110, 0, 0, "110,0.,0.,0.,4.,0.,0.;"),
                (110, 0, 0, second),
            ],
        )
    };
    let want = 4.0 * 5.0_f64.sqrt();
    for (form, second, flag) in [
        (1, "110,0.,2.,1.,4.,2.,1.;", "118,3,5,0,1;"),
        (0, "110,0.,2.,1.,4.,2.,1.;", "118,3,5,0,1;"),
        (1, "110,4.,2.,1.,0.,2.,1.;", "118,3,5,1,1;"),
    ] {
        let s = only_surface(&lines(form, second, flag));
        for (u, v, p) in grid(&s, 10) {
            assert!(p.distance(Vec3::new(4.0 * u, 2.0 * v, v)) < 1e-12, "{p}");
        }
        let area = trimmed_area(&s, 16, 16);
        assert!((area - want).abs() < 1e-12 * want, "form {form}: {area}");
    }
    // without the flag, the second line backwards twists the strip
    let twisted = only_surface(&lines(1, "110,4.,2.,1.,0.,2.,1.;", "118,3,5,0,1;"));
    assert!(twisted.eval(0.0, 1.0).distance(Vec3::new(4.0, 2.0, 1.0)) < 1e-12);

    // two half circles of radius 2 at z = 0 and z = 3 (the second by its
    // transformation): half a cylinder, area 6π, by either form
    for form in [0, 1] {
        let s = only_surface(&iges_file(
            GLOBAL,
            &[
                (118, 0, form, "118,3,5,0,0;"),
                (100, 0, 0, "100,0.,0.,0.,2.,0.,-2.,0.;"),
                (100, 7, 0, "100,0.,0.,0.,2.,0.,-2.,0.;"),
                (124, 0, 0, "124,1.,0.,0.,0.,0.,1.,0.,0.,0.,0.,1.,3.;"),
            ],
        ));
        for (_, _, p) in grid(&s, 20) {
            assert!((p.x.hypot(p.y) - 2.0).abs() < 1e-12, "{p}");
        }
        let area = trimmed_area(&s, 64, 64);
        assert!(
            (area - 6.0 * PI).abs() < 1e-9 * 6.0 * PI,
            "form {form}: {area}"
        );
    }

    // equal arc length between a line and a quarter circle: no exact NURBS;
    // fitted within 1e-7 of the size, on the file's parameters (u the
    // relative arc length of both rails), and warned naming the entity
    ruled_line_to_arc_is_fitted(0, "118,3,5,0,0;", "equal arc length", false);
}

/// The ruled surface of `form` and parameters `record` between the line
/// (0, 0, 5)–(2, 0, 5) and the quarter circle of radius 2 about z at z = 0
/// (from angle 0, or backwards from π/2 when `reversed`): read with one
/// warning naming `kind`, and within 1e-7 of the size of the surface whose
/// ruling at u joins (2u, 0, 5) to the arc's point at angle πu/2 (the
/// arc's relative arc length and its angle are the same).
fn ruled_line_to_arc_is_fitted(form: i64, record: &'static str, kind: &str, reversed: bool) {
    let imp = parse_iges(&iges_file(
        GLOBAL,
        &[
            (118, 0, form, record),
            (110, 0, 0, "110,0.,0.,5.,2.,0.,5.;"),
            (100, 0, 0, "100,0.,0.,0.,2.,0.,0.,2.;"),
        ],
    ))
    .unwrap();
    assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
    assert!(
        imp.warnings.len() == 1
            && imp.warnings[0].contains(&format!("ruled surface of {kind} is approximated")),
        "{:?}",
        imp.warnings
    );
    let s = &imp.surfaces[0].surface;
    let size = Vec3::new(2.0, 2.0, 5.0).length();
    for (u, v, p) in grid(s, 16) {
        let a = 0.5 * PI * if reversed { 1.0 - u } else { u };
        let want = (1.0 - v) * Vec3::new(2.0 * u, 0.0, 5.0)
            + v * Vec3::new(2.0 * a.cos(), 2.0 * a.sin(), 0.0);
        assert!(p.distance(want) < 1e-7 * size, "{u} {v}: {p} vs {want}");
    }
}

#[test]
fn iges_ruled_surface_of_equal_parameter_between_a_line_and_an_arc_is_fitted() {
    // form 1 between a line (parameter linear in length) and a quarter
    // circle (parameter the angle): the ruling at file parameter u joins
    // (2u, 0, 5) to the point at angle πu/2 — no rational parametrisation
    // of the circle is linear in its angle, so the surface is fitted within
    // 1e-7 of the size and warned; the same with the arc reversed by DIRFLG
    for (flag, reversed) in [("118,3,5,0,1;", false), ("118,3,5,1,1;", true)] {
        ruled_line_to_arc_is_fitted(1, flag, "equal parameter", reversed);
    }
}

#[test]
fn iges_parametric_spline_surface_reproduces_its_polynomials() {
    // 2 × 1 bicubic patches on u ∈ [0, 1, 3], v ∈ [-1, 1]; the surface
    // x = u, y = v, z = u²v − v³ + u³ written per patch in s = u − TU(i),
    // t = v + 1: z = (TU+s)²(t−1) − (t−1)³ + (TU+s)³
    let z = |u: f64, v: f64| u * u * v - v * v * v + u * u * u;
    let mut coefficients = Vec::new();
    for &tu in &[0.0_f64, 1.0] {
        // x: TU + s; y: t − 1; z expanded in powers s^m t^n (m fastest)
        let mut x = [0.0; 16];
        x[0] = tu;
        x[1] = 1.0;
        let mut y = [0.0; 16];
        y[0] = -1.0;
        y[4] = 1.0;
        let mut zc = [0.0; 16];
        // (TU+s)²(t−1) = (TU² + 2TU s + s²)(t − 1)
        for (m, c) in [(0, tu * tu), (1, 2.0 * tu), (2, 1.0)] {
            zc[m + 4] += c;
            zc[m] -= c;
        }
        // −(t−1)³ = −t³ + 3t² − 3t + 1
        zc[12] -= 1.0;
        zc[8] += 3.0;
        zc[4] -= 3.0;
        zc[0] += 1.0;
        // (TU+s)³
        zc[0] += tu * tu * tu;
        zc[1] += 3.0 * tu * tu;
        zc[2] += 3.0 * tu;
        zc[3] += 1.0;
        coefficients.push([x, y, zc]);
    }
    let mut data = String::from("114,3,1,2,1,0.,1.,3.,-1.,1.");
    for patch in &coefficients {
        for axis in patch {
            for c in axis {
                data.push_str(&format!(",{c:.1}"));
            }
        }
        // the arbitrary values after each u segment (one per v segment +1)
        data.push_str(&",0.".repeat(48));
    }
    data.push_str(&",0.".repeat(48 * 2));
    data.push(';');
    let s = only_surface(&iges_file(GLOBAL, &[(114, 0, 0, &data)]));
    assert_eq!((s.domain_u(), s.domain_v()), ([0.0, 3.0], [-1.0, 1.0]));
    for (u, v, p) in grid(&s, 24) {
        assert!(p.distance(Vec3::new(u, v, z(u, v))) < 1e-12, "{u} {v}: {p}");
    }
    // hostile counts: negative, huge, truncated
    for bad in [
        "114,3,1,-2,1,0.;",
        "114,3,1,99999999,1,0.;",
        "114,3,1,2,1,0.,1.,3.,-1.,1.,0.;",
    ] {
        let e = parse_iges(&iges_file(GLOBAL, &[(114, 0, 0, bad)])).unwrap_err();
        assert!(matches!(e, IgesError::Entity { entity: 1, .. }), "{e}");
    }
}

#[test]
fn iges_offset_surfaces_of_a_plane_and_a_cylinder() {
    // a plane 128 (z = 0, normal +z) offset by 2.5: z = 2.5, exact
    let plane = "128,1,1,1,1,0,0,1,0,0,0.,0.,1.,1.,0.,0.,1.,1.,1.,1.,1.,1.,\
                 0.,0.,0.,3.,0.,0.,0.,2.,0.,3.,2.,0.,0.,1.,0.,1.;";
    let imp = parse_iges(&iges_file(
        GLOBAL,
        &[(140, 0, 0, "140,0.,0.,1.,2.5,3;"), (128, 0, 0, plane)],
    ))
    .unwrap();
    assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
    assert!(imp.warnings.is_empty(), "{:?}", imp.warnings);
    assert_eq!(imp.surfaces.len(), 1, "the base is not a face of its own");
    let s = &imp.surfaces[0].surface;
    assert_eq!(imp.surfaces[0].entity_type, 140);
    for (u, v, p) in grid(s, 8) {
        assert!(p.distance(Vec3::new(3.0 * u, 2.0 * v, 2.5)) < 1e-14, "{p}");
    }

    // a cylinder of radius 10 (a line revolved 2 rad about z) offset by 2:
    // the line moved out by 2 and revolved, exact
    let imp = parse_iges(&iges_file(
        GLOBAL,
        &[
            (140, 0, 0, "140,1.,0.,0.,2.,3;"),
            (120, 0, 0, "120,5,7,0.,2.;"),
            (110, 0, 0, "110,0.,0.,0.,0.,0.,1.;"),
            (110, 0, 0, "110,10.,0.,5.,10.,0.,0.;"),
        ],
    ))
    .unwrap();
    assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
    assert!(imp.warnings.is_empty(), "{:?}", imp.warnings);
    assert_eq!(imp.surfaces.len(), 1);
    let s = &imp.surfaces[0].surface;
    for (_, _, p) in grid(s, 30) {
        assert!((p.x.hypot(p.y) - 12.0).abs() < 1e-12, "{p}");
    }
    let area = trimmed_area(s, 64, 64);
    assert!((area - 120.0).abs() < 1e-9 * 120.0, "{area}");

    // a cylinder as a tabulated cylinder (122) of a full circle of radius
    // 3, offset by 1: fitted within its tolerance of radius 4, with a
    // warning naming the entity
    let imp = parse_iges(&iges_file(
        GLOBAL,
        &[
            (140, 0, 0, "140,1.,0.,0.,1.,3;"),
            (122, 0, 0, "122,5,3.,0.,4.;"),
            (100, 0, 0, "100,0.,0.,0.,3.,0.,3.,0.;"),
        ],
    ))
    .unwrap();
    assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
    assert_eq!(imp.surfaces.len(), 1);
    assert_eq!(imp.warnings.len(), 1);
    assert!(
        imp.warnings[0].contains("entity 140 (DE 1"),
        "{:?}",
        imp.warnings
    );
    let s = &imp.surfaces[0].surface;
    // 1e-7 of the base's control net diagonal (√(6² + 6² + 4²)) plus 2·|d|
    let tol = 1e-7 * (88.0_f64.sqrt() + 2.0);
    let mut worst = 0.0_f64;
    for (_, _, p) in grid(s, 60) {
        worst = worst.max((p.x.hypot(p.y) - 4.0).abs());
    }
    assert!(worst < 2.0 * tol, "{worst} vs {tol}");
    let area = trimmed_area(s, 64, 64);
    let want = 2.0 * PI * 4.0 * 4.0;
    assert!((area - want).abs() < 1e-6 * want, "{area}");

    // an offset of itself: an error naming it, no panic
    let e = parse_iges(&iges_file(GLOBAL, &[(140, 0, 0, "140,0.,0.,1.,1.,1;")])).unwrap_err();
    assert!(e.to_string().contains("directory entry 1"), "{e}");
}

#[test]
fn iges_bounded_surface_is_read_from_model_or_parameter_space_boundaries() {
    // a plane 3 × 2 (128, u = x/3, v = y/2) bounded by the unit square
    // (1, 0.5)–(2, 1.5), given in model space only (143 TYPE 0: projected)
    // or with parameter-space curves (TYPE 1)
    let plane = "128,1,1,1,1,0,0,1,0,0,0.,0.,1.,1.,0.,0.,1.,1.,1.,1.,1.,1.,\
                 0.,0.,0.,3.,0.,0.,0.,2.,0.,3.,2.,0.,0.,1.,0.,1.;";
    let model = [
        "110,1.,.5,0.,2.,.5,0.;",
        "110,2.,.5,0.,2.,1.5,0.;",
        "110,2.,1.5,0.,1.,1.5,0.;",
        "110,1.,1.5,0.,1.,.5,0.;",
    ];
    let (a, b) = (1.0 / 3.0, 2.0 / 3.0);
    let pcurves = [
        format!("110,{a},.25,0.,{b},.25,0.;"),
        format!("110,{b},.25,0.,{b},.75,0.;"),
        format!("110,{b},.75,0.,{a},.75,0.;"),
        format!("110,{a},.75,0.,{a},.25,0.;"),
    ];
    for with_pcurves in [false, true] {
        let (t, boundary) = if with_pcurves {
            (1, "141,1,1,3,1,7,1,1,17;")
        } else {
            (0, "141,0,0,3,1,7,1,0;")
        };
        let head = format!("143,{t},3,1,5;");
        let imp = parse_iges(&iges_file(
            GLOBAL,
            &[
                (143, 0, 0, &head),
                (128, 0, 0, plane),
                (141, 0, 0, boundary),
                (102, 0, 0, "102,4,9,11,13,15;"),
                (110, 0, 0, model[0]),
                (110, 0, 0, model[1]),
                (110, 0, 0, model[2]),
                (110, 0, 0, model[3]),
                (102, 0, 0, "102,4,19,21,23,25;"),
                (110, 0, 0, &pcurves[0]),
                (110, 0, 0, &pcurves[1]),
                (110, 0, 0, &pcurves[2]),
                (110, 0, 0, &pcurves[3]),
            ],
        ))
        .unwrap();
        assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
        assert_eq!(imp.surfaces.len(), 1);
        assert_eq!(imp.surfaces[0].trim_entity, Some(1));
        let area = trimmed_area(&imp.surfaces[0].surface, 64, 64);
        assert!((area - 1.0).abs() < 1e-9, "p-curves {with_pcurves}: {area}");
    }

    // a plane (108, z = 0) bounded by the same square (a composite curve)
    // with a square hole 0.5 wide whose four lines are listed last to
    // first, each reversed (SENSE = 2)
    let hole = [
        "110,1.25,.75,0.,1.75,.75,0.;",
        "110,1.75,.75,0.,1.75,1.25,0.;",
        "110,1.75,1.25,0.,1.25,1.25,0.;",
        "110,1.25,1.25,0.,1.25,.75,0.;",
    ];
    let imp = parse_iges(&iges_file(
        GLOBAL,
        &[
            (143, 0, 0, "143,0,3,2,5,7;"),
            (108, 0, 0, "108,0.,0.,1.,0.,0,0.,0.,0.,0.;"),
            (141, 0, 0, "141,0,0,3,1,9,1,0;"),
            (141, 0, 0, "141,0,0,3,4,25,2,0,23,2,0,21,2,0,19,2,0;"),
            (102, 0, 0, "102,4,11,13,15,17;"),
            (110, 0, 0, model[0]),
            (110, 0, 0, model[1]),
            (110, 0, 0, model[2]),
            (110, 0, 0, model[3]),
            (110, 0, 0, hole[0]),
            (110, 0, 0, hole[1]),
            (110, 0, 0, hole[2]),
            (110, 0, 0, hole[3]),
        ],
    ))
    .unwrap();
    assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
    assert_eq!(imp.surfaces.len(), 1);
    let plane = &imp.surfaces[0];
    assert_eq!((plane.entity_type, plane.trim_entity), (108, Some(1)));
    assert_eq!(plane.surface.trims().len(), 2);
    let area = trimmed_area(&plane.surface, 64, 64);
    assert!((area - 0.75).abs() < 1e-9, "{area}");

    // a bounded surface on what is not a surface is listed
    let imp = parse_iges(&iges_file(
        GLOBAL,
        &[
            (143, 0, 0, "143,0,3,1,5;"),
            (110, 0, 0, "110,0.,0.,0.,1.,0.,0.;"),
            (141, 0, 0, "141,0,0,3,1,7,1,0;"),
            (110, 0, 0, "110,0.,0.,0.,1.,0.,0.;"),
        ],
    ))
    .unwrap();
    assert!(imp.surfaces.is_empty());
    assert_eq!(imp.unreadable.len(), 1, "{:?}", imp.unreadable);
    assert!(imp.unreadable[0].reason.contains("bounded surface (143)"));
}

/// Entity type, transformation, form and parameters, as `iges_file` takes.
type Entity<'a> = (i64, i64, i64, &'a str);

#[test]
fn iges_hostile_surface_entities_fail_naming_the_entity() {
    let cases: [(&[Entity<'_>], usize); 6] = [
        // a tabulated cylinder whose directrix is itself
        (&[(122, 0, 0, "122,1,0.,0.,1.;")], 1),
        // a composite directrix that contains itself
        (
            &[(122, 0, 0, "122,3,0.,0.,1.;"), (102, 0, 0, "102,1,3;")],
            3,
        ),
        // a ruled surface without its second rail
        (
            &[
                (118, 0, 1, "118,3,0,0,0;"),
                (110, 0, 0, "110,0.,0.,0.,1.,0.,0.;"),
            ],
            1,
        ),
        // a ruled surface whose parameters end early
        (
            &[(118, 0, 1, "118,3;"), (110, 0, 0, "110,0.,0.,0.,1.,0.,0.;")],
            1,
        ),
        // a bounded surface with a negative number of boundaries
        (
            &[
                (143, 0, 0, "143,0,3,-1,5;"),
                (122, 0, 0, "122,5,0.,0.,1.;"),
                (110, 0, 0, "110,0.,0.,0.,1.,0.,0.;"),
            ],
            1,
        ),
        // a parametric spline curve of no segments as a directrix
        (
            &[
                (122, 0, 0, "122,3,0.,0.,1.;"),
                (112, 0, 0, "112,3,1,3,0,0.;"),
            ],
            3,
        ),
    ];
    for (entities, de) in cases {
        let e = parse_iges(&iges_file(GLOBAL, entities)).unwrap_err();
        let text = e.to_string();
        assert!(
            text.contains(&format!("directory entry {de})")) && text.contains("line "),
            "{entities:?}: {text}"
        );
    }
}
