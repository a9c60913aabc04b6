//! geomdl (NURBS-Python 5.3.1) JSON files, written by
//! `scripts/geomdl_fixtures.py` with `exchange.export_json`, read through
//! the surface-file dispatch: every point fairline evaluates agrees with
//! geomdl's `evaluate_single` (the numbers below, printed by that script)
//! to 1e-12.

// the reference numbers are geomdl's output verbatim (1.414213562373095 is
// geomdl's √2, one unit in the last place below `SQRT_2`)
#![allow(clippy::approx_constant)]

use std::path::PathBuf;

use fairline::bspline::{BSplineSurface, trimmed_area};
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

/// Whether geomdl's trimmed tessellator keeps each point of a 16 × 16 grid
/// of parameters `(i/16 + 0.01, j/16 + 0.013)`, index `16 i + j` (printed
/// by `scripts/geomdl_fixtures.py`: 1 kept, 0 trimmed away).
const PLATE_KEPT: &str = "1111111111111111111111111111111111111100001111111111110000011111111110000001111111111000000111111111100000011111111111000011111111111111111111111111111111111111111111111110011111100011111001111110000011111111111001111111111111111111111111111111111111111111";
const BAND_KEPT: &str = "0001111111100000000111111110000000011111111000000001111111100000000111111110000000011111111000000001111111100000000111111110000000011111111000000001111111100000000111111110000000011111111000000001111111100000000111111110000000011111111000000001111111100000";
const ISLANDS_KEPT: &str = "0000000000000000000000000000000000011110000000000011111100000000001111110000000000111111000000000011111100000000000111100000000000000000000000000000000000111000000000000111110000000000011011000000000001111100000000000011100000000000000000000000000000000000";

fn grid() -> impl Iterator<Item = (f64, f64)> {
    (0..16).flat_map(|i| (0..16).map(move |j| (i as f64 / 16.0 + 0.01, j as f64 / 16.0 + 0.013)))
}

fn kept(faces: &[&BSplineSurface], u: f64, v: f64) -> bool {
    faces
        .iter()
        .any(|f| f.trim().is_some_and(|t| t.contains(u, v)))
}

#[test]
fn geomdl_trims_make_the_faces_geomdl_keeps() {
    let f = read_surface_file(data("trimmed.json")).unwrap();
    assert!(f.unreadable.is_empty(), "{:?}", f.unreadable);
    // the plate with three holes, the cylinder band, two islands
    assert_eq!(f.surfaces.len(), 4);
    let loops: Vec<usize> = f
        .surfaces
        .iter()
        .map(|s| s.trim().map_or(0, |t| t.loops().len()))
        .collect();
    assert_eq!(loops, [4, 1, 1, 2]);
    let cases: [(&[&BSplineSurface], &str, &str); 3] = [
        (&[&f.surfaces[0]], PLATE_KEPT, "plate"),
        (&[&f.surfaces[1]], BAND_KEPT, "band"),
        (&[&f.surfaces[2], &f.surfaces[3]], ISLANDS_KEPT, "islands"),
    ];
    for (faces, want, name) in cases {
        for ((u, v), bit) in grid().zip(want.bytes()) {
            assert_eq!(
                kept(faces, u, v),
                bit == b'1',
                "{name} at ({u}, {v}): geomdl keeps it: {}",
                bit == b'1'
            );
        }
    }
    // closed forms (the script's docstrings): the plate is (2u, 3v, 0)
    let pi = std::f64::consts::PI;
    let areas = [
        6.0 * (1.0 - 0.04 * pi - 0.03 - 0.01),
        1.5 * pi,
        6.0 * 0.04 * pi,
        6.0 * 0.02 * pi,
    ];
    // The trims are flattened to within 1e-6 of the domain's diagonal
    // (√2 here): a loop of parameter length L then loses at most
    // L · 1.42e-6 of parameter area, × 6 on the plate; on the smallest
    // island (L = 1.26, area 0.75) that is 1.4e-5 of its area.
    for (s, want) in f.surfaces.iter().zip(areas) {
        let got = trimmed_area(s, 64, 64);
        assert!(
            (got - want).abs() <= 1.5e-5 * want,
            "area {got}, closed form {want}"
        );
    }
}
