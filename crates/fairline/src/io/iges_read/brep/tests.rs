//! Tests of the B-rep reading on hand-made faces: exactness with and
//! without parameter-space curves, composite edges, unreadable surfaces.

use std::f64::consts::PI;

use super::super::parse_iges;
use super::super::tests::{GLOBAL, iges_file};
use crate::bspline::trimmed_area;

/// A cylinder face of radius 2 and height 3 as OpenCASCADE writes it
/// in B-rep mode: a 510 on a 192 bounded by one loop of the two end
/// circles and the seam used in both directions, with p-curves in
/// (degrees, height).
fn cylinder(pcurves: bool, surface_type: i64) -> String {
    let surface = format!("{surface_type},7,9,2.,11;");
    let lp = if pcurves {
        "508,4,0,15,1,1,1,0,25,0,15,3,1,1,0,27,0,15,2,0,1,0,29,0,15,3,0,1,0,31;"
    } else {
        "508,4,0,15,1,1,0,0,15,3,1,0,0,15,2,0,0,0,15,3,0,0;"
    };
    let entities = [
        (514, 0, 1, "514,1,3,1;"),
        (510, 0, 1, "510,5,1,1,13;"),
        (surface_type, 0, 1, surface.as_str()),
        (116, 0, 0, "116,0.,0.,0.,0;"),
        (123, 0, 0, "123,0.,0.,1.;"),
        (123, 0, 0, "123,1.,0.,0.;"),
        (508, 0, 1, lp),
        (504, 0, 1, "504,3,17,19,1,19,1,21,19,2,19,2,23,19,1,19,2;"),
        (100, 0, 0, "100,0.,0.,0.,2.,0.,2.,0.;"),
        (502, 0, 1, "502,2,2.,0.,0.,2.,0.,3.;"),
        (100, 0, 0, "100,3.,0.,0.,2.,0.,2.,0.;"),
        (110, 0, 0, "110,2.,0.,0.,2.,0.,3.;"),
        (110, 0, 0, "110,0.,0.,0.,360.,0.,0.;"),
        (110, 0, 0, "110,360.,0.,0.,360.,3.,0.;"),
        (110, 0, 0, "110,360.,3.,0.,0.,3.,0.;"),
        (110, 0, 0, "110,0.,3.,0.,0.,0.,0.;"),
    ];
    iges_file(GLOBAL, &entities)
}

#[test]
fn iges_brep_cylinder_face_is_exact_with_and_without_pcurves() {
    for pcurves in [true, false] {
        let imp = parse_iges(&cylinder(pcurves, 192)).unwrap();
        assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
        assert_eq!(imp.surfaces.len(), 1);
        let face = &imp.surfaces[0];
        assert_eq!((face.entity_type, face.form), (510, 192));
        assert_eq!(face.trim_entity, Some(3));
        let area = trimmed_area(&face.surface, 64, 64);
        let want = 2.0 * PI * 2.0 * 3.0;
        assert!(
            (area - want).abs() <= 1e-6 * want,
            "p-curves {pcurves}: {area} vs {want}"
        );
    }
}

#[test]
fn iges_brep_edge_on_a_composite_curve_is_read() {
    // the cylinder face with its bottom circle given as a composite
    // curve (102) of two half circles
    for pcurves in [true, false] {
        let text = cylinder(pcurves, 192);
        let mut entities: Vec<(i64, i64, i64, String)> = Vec::new();
        // re-made by hand: the fixture's list with DE 17 replaced
        let lp = if pcurves {
            "508,4,0,15,1,1,1,0,25,0,15,3,1,1,0,27,0,15,2,0,1,0,29,0,15,3,0,1,0,31;"
        } else {
            "508,4,0,15,1,1,0,0,15,3,1,0,0,15,2,0,0,0,15,3,0,0;"
        };
        for (t, tr, form, data) in [
            (514, 0, 1, "514,1,3,1;"),
            (510, 0, 1, "510,5,1,1,13;"),
            (192, 0, 1, "192,7,9,2.,11;"),
            (116, 0, 0, "116,0.,0.,0.,0;"),
            (123, 0, 0, "123,0.,0.,1.;"),
            (123, 0, 0, "123,1.,0.,0.;"),
            (508, 0, 1, lp),
            (504, 0, 1, "504,3,17,19,1,19,1,21,19,2,19,2,23,19,1,19,2;"),
            (102, 0, 0, "102,2,33,35;"),
            (502, 0, 1, "502,2,2.,0.,0.,2.,0.,3.;"),
            (100, 0, 0, "100,3.,0.,0.,2.,0.,2.,0.;"),
            (110, 0, 0, "110,2.,0.,0.,2.,0.,3.;"),
            (110, 0, 0, "110,0.,0.,0.,360.,0.,0.;"),
            (110, 0, 0, "110,360.,0.,0.,360.,3.,0.;"),
            (110, 0, 0, "110,360.,3.,0.,0.,3.,0.;"),
            (110, 0, 0, "110,0.,3.,0.,0.,0.,0.;"),
            (100, 0, 0, "100,0.,0.,0.,2.,0.,-2.,0.;"),
            (100, 0, 0, "100,0.,0.,0.,-2.,0.,2.,0.;"),
        ] {
            entities.push((t, tr, form, data.to_string()));
        }
        let list: Vec<(i64, i64, i64, &str)> = entities
            .iter()
            .map(|(a, b, c, d)| (*a, *b, *c, d.as_str()))
            .collect();
        let composite = iges_file(GLOBAL, &list);
        assert_ne!(composite, text);
        let imp = parse_iges(&composite).unwrap();
        assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
        assert_eq!(imp.surfaces.len(), 1);
        let area = trimmed_area(&imp.surfaces[0].surface, 64, 64);
        let want = 2.0 * PI * 2.0 * 3.0;
        assert!(
            (area - want).abs() <= 1e-6 * want,
            "p-curves {pcurves}: {area} vs {want}"
        );
    }
}

#[test]
fn iges_brep_face_on_a_surface_not_read_is_listed_not_dropped() {
    // the same face on a plane (108), which is read only under a 144
    let imp = parse_iges(&cylinder(true, 108)).unwrap();
    assert!(imp.surfaces.is_empty());
    assert_eq!(imp.unreadable.len(), 1, "{:?}", imp.unreadable);
    let u = &imp.unreadable[0];
    assert!(u.entity.starts_with("entity 510 (DE 3"), "{u:?}");
    assert!(u.reason.contains("surface entity 108"), "{u:?}");
}

/// A bounded surface (143) on a right circular cylinder (192) of radius 2:
/// half of it between z = 0 and 3, its one boundary (141) made of two half
/// circles (the top one listed forwards and used reversed, SENSE = 2) and
/// two lines: read through the B-rep path, area 6π.
#[test]
fn iges_bounded_surface_on_an_analytic_cylinder_is_read() {
    let entities = [
        (143, 0, 0, "143,0,3,1,11;"),
        (192, 0, 1, "192,5,7,2.,9;"),
        (116, 0, 0, "116,0.,0.,0.,0;"),
        (123, 0, 0, "123,0.,0.,1.;"),
        (123, 0, 0, "123,1.,0.,0.;"),
        (141, 0, 0, "141,0,0,3,4,13,1,0,15,1,0,17,2,0,19,1,0;"),
        (100, 0, 0, "100,0.,0.,0.,2.,0.,-2.,0.;"),
        (110, 0, 0, "110,-2.,0.,0.,-2.,0.,3.;"),
        (100, 0, 0, "100,3.,0.,0.,2.,0.,-2.,0.;"),
        (110, 0, 0, "110,2.,0.,3.,2.,0.,0.;"),
    ];
    let imp = parse_iges(&iges_file(GLOBAL, &entities)).unwrap();
    assert!(imp.unreadable.is_empty(), "{:?}", imp.unreadable);
    assert_eq!(imp.surfaces.len(), 1);
    let s = &imp.surfaces[0].surface;
    let want = 6.0 * PI;
    let area = trimmed_area(s, 64, 64);
    assert!((area - want).abs() <= 1e-6 * want, "{area} vs {want}");
    let (du, dv) = (s.domain_u(), s.domain_v());
    for i in 0..=8 {
        for j in 0..=8 {
            let u = du[0] + (du[1] - du[0]) * i as f64 / 8.0;
            let v = dv[0] + (dv[1] - dv[0]) * j as f64 / 8.0;
            let p = s.eval(u, v);
            assert!((p.x.hypot(p.y) - 2.0).abs() < 1e-12, "{p}");
        }
    }
    // the same boundary with the top circle's SENSE 1: the loop does not
    // close, and the face is listed with the reason, not dropped
    let mut broken = entities;
    broken[5] = (141, 0, 0, "141,0,0,3,4,13,1,0,15,1,0,17,1,0,19,1,0;");
    let imp = parse_iges(&iges_file(GLOBAL, &broken)).unwrap();
    assert!(imp.surfaces.is_empty(), "{:?}", imp.surfaces.len());
    assert_eq!(imp.unreadable.len(), 1, "{:?}", imp.unreadable);
    assert!(
        imp.unreadable[0].reason.contains("bounded surface (143)"),
        "{:?}",
        imp.unreadable
    );
}
