//! geomdl (NURBS-Python 5.3.1) JSON files, written by
//! `scripts/geomdl_fixtures.py` with `exchange.export_json`, read through
//! the surface-file dispatch: every point fairline evaluates agrees with
//! geomdl's `evaluate_single` (the numbers below, printed by that script)
//! to 1e-12.

// the reference numbers are geomdl's output verbatim (1.414213562373095 is
// geomdl's √2, one unit in the last place below `SQRT_2`)
#![allow(clippy::approx_constant)]

use std::path::PathBuf;

use fairline::bspline::BSplineSurface;
use fairline::io::surface_file::read_surface_file;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/geomdl")
        .join(name)
}

type Reference = [((f64, f64), [f64; 3])];

/// The rational quarter cylinder (radius 2, height 3).
const CYLINDER: &Reference = &[
    ((0.0, 0.0), [2.0, 0.0, 0.0]),
    ((0.3, 0.7), [1.7947512999907453, 0.8825348555051692, 2.1]),
    (
        (0.5, 0.5),
        [1.414213562373095, 1.414213562373095, 1.5000000000000002],
    ),
    (
        (0.9, 0.15),
        [0.28983897804632314, 1.9788869009635348, 0.44999999999999996],
    ),
    ((1.0, 1.0), [0.0, 2.0, 3.0]),
    (
        (0.123, 0.987),
        [1.9677010497183736, 0.35798404843960774, 2.9610000000000003],
    ),
];

/// The non-rational bicubic (6 × 4 control points).
const BICUBIC: &Reference = &[
    ((0.0, 0.0), [0.0, 0.0, 0.0]),
    (
        (0.3, 0.7),
        [2.9466666666666663, 2.296444444444444, -0.030362188434509132],
    ),
    ((0.5, 0.5), [4.0, 1.7666666666666666, 0.3387970652833129]),
    (
        (0.9, 0.15),
        [6.496979166666666, 0.8831319444444444, 0.17119425249548526],
    ),
    ((1.0, 1.0), [7.5, 3.5, 1.0671333440410131]),
    (
        (0.123, 0.987),
        [1.670384772, 3.0723589847999997, -0.3946027533637535],
    ),
];

fn assert_matches(s: &BSplineSurface, reference: &Reference, name: &str) {
    for &((u, v), want) in reference {
        let p = s.eval(u, v).to_array();
        for d in 0..3 {
            assert!(
                (p[d] - want[d]).abs() <= 1e-12,
                "{name} at ({u}, {v}): fairline {p:?}, geomdl {want:?}"
            );
        }
    }
}

#[test]
fn geomdl_surfaces_evaluate_as_geomdl_evaluates_them() {
    let f = read_surface_file(data("cylinder_and_bicubic.json")).unwrap();
    assert!(f.unreadable.is_empty(), "{:?}", f.unreadable);
    assert_eq!(f.surfaces.len(), 2);
    let (cyl, bic) = (&f.surfaces[0], &f.surfaces[1]);
    assert!(cyl.is_rational() && !bic.is_rational());
    assert_eq!((cyl.degree_u(), cyl.degree_v()), (2, 1));
    assert_eq!((bic.count_u(), bic.count_v()), (6, 4));
    assert_matches(cyl, CYLINDER, "cylinder");
    assert_matches(bic, BICUBIC, "bicubic");

    let single = read_surface_file(data("bicubic.json")).unwrap();
    assert_eq!(single.surfaces.len(), 1);
    assert_eq!(&single.surfaces[0], bic);
}

#[test]
fn geomdl_files_convert_to_fairline_json_unchanged() {
    let f = read_surface_file(data("cylinder_and_bicubic.json")).unwrap();
    let dir = std::env::temp_dir().join(format!("fairline-geomdl-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("part.json");
    fairline::io::surface_file::write_surface_file(&out, &f.surfaces, None).unwrap();
    let back = read_surface_file(&out).unwrap();
    assert_eq!(back.surfaces, f.surfaces);
    std::fs::remove_dir_all(&dir).unwrap();
}
