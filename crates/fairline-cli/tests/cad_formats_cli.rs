//! Command-line tests of the way back to CAD:
//! `convert` between surface JSON, IGES and STEP keeps every number and
//! trim; `fair-surface -o OUT.igs|.step` writes the faired part; commands
//! that take surfaces take STEP files; bad STEP input exits 2 naming the
//! entity, nothing written.

mod common;

use common::{json, ok, run, s, tmp};
use fairline::Vec3;
use fairline::bspline::{BSplineSurface, TrimCurve, TrimLoop};
use fairline::io::read_surfaces_json;
use fairline::io::surface_file::read_surface_file;

/// A rational trimmed patch and an untrimmed bicubic one.
fn part() -> Vec<BSplineSurface> {
    let net = |f: &dyn Fn(usize, usize) -> f64| -> Vec<Vec<Vec3>> {
        (0..4)
            .map(|i| {
                (0..4)
                    .map(|j| Vec3::new(i as f64 / 3.0, j as f64 / 3.0, f(i, j)))
                    .collect()
            })
            .collect()
    };
    let w: Vec<Vec<f64>> = (0..4)
        .map(|i| (0..4).map(|j| 1.0 + 0.1 * ((i * j) % 3) as f64).collect())
        .collect();
    let a = BSplineSurface::bezier(net(&|i, j| 0.1 * (i * j) as f64 / 7.0), Some(w))
        .unwrap()
        .with_trims(vec![
            TrimLoop::polygon(&[[0.1, 0.1], [0.9, 0.1], [0.9, 0.9], [0.1, 0.9]]).unwrap(),
            TrimLoop {
                curves: vec![
                    TrimCurve::new(
                        2,
                        vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
                        vec![[0.4, 0.4], [0.5, 0.7], [0.6, 0.4]],
                        Some(vec![1.0, 0.7, 1.0]),
                    )
                    .unwrap(),
                    TrimCurve::line([0.6, 0.4], [0.4, 0.4]).unwrap(),
                ],
            },
        ])
        .unwrap();
    let b = BSplineSurface::bezier(net(&|i, j| ((i + j) as f64 / 3.0).sin()), None).unwrap();
    vec![a, b]
}

#[test]
fn convert_between_json_iges_and_step_keeps_every_number() {
    let d = tmp("cad-convert");
    let src = d.join("part.json");
    fairline::io::write_surfaces_json(&src, &part()).unwrap();
    let (igs, stp, back) = (d.join("part.igs"), d.join("part.step"), d.join("back.json"));
    let rep = d.join("rep.json");
    let o = run(&["convert", s(&src), s(&igs), "--report", s(&rep)]);
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stderr).contains("2 surface(s) converted (1 trimmed)"));
    assert_eq!(json(&rep)["trimmed"], 1);
    ok(&run(&["convert", s(&igs), s(&stp)]));
    ok(&run(&["convert", s(&stp), s(&back)]));
    assert_eq!(read_surfaces_json(&back).unwrap(), part());
    // Both CAD files hold the same surfaces, in millimetres.
    for f in [&igs, &stp] {
        let file = read_surface_file(f).unwrap();
        assert_eq!(file.surfaces, part());
        assert_eq!(file.unit.map(|u| u.name), Some("MM".to_string()));
    }
    // A STEP file can be drawn, checked for continuity and tessellated.
    let png = d.join("part.png");
    ok(&run(&["render", s(&stp), "--png", s(&png)]));
    assert!(png.metadata().unwrap().len() > 1000);
    ok(&run(&["continuity", s(&stp)]));
    let mesh = d.join("part.obj");
    ok(&run(&["convert", s(&stp), s(&mesh)]));
    // `info` describes a surface file.
    let info = d.join("info.json");
    ok(&run(&["info", s(&stp), "--area", "--report", s(&info)]));
    let r = json(&info);
    assert_eq!(
        (r["surfaces"].as_u64(), r["trimmed"].as_u64()),
        (Some(2), Some(1))
    );
    assert_eq!(
        (r["rational"].as_u64(), r["unit"].as_str()),
        (Some(1), Some("MM"))
    );
    let area = r["area"].as_f64().unwrap();
    let want: f64 = part()
        .iter()
        .map(|s| fairline::bspline::trimmed_area(s, 64, 64))
        .sum();
    assert!((area - want).abs() <= 1e-12 * want, "{area} vs {want}");
}

#[test]
fn fair_surface_writes_iges_and_step() {
    let d = tmp("cad-fair");
    let o = common::bin()
        .current_dir(&d)
        .args(["demo", "--out", "demo"])
        .output()
        .unwrap();
    ok(&o);
    let dented = d.join("demo/bspline-panel-dented.json");
    let lights = d.join("demo/bspline-panel-lights.json");
    let ends = d.join("demo/bspline-panel-endpoints.json");
    let mut results = Vec::new();
    for name in ["out.json", "out.igs", "out.step"] {
        let out = d.join(name);
        let o = run(&[
            "fair-surface",
            s(&dented),
            "--lights",
            s(&lights),
            "--endpoints",
            s(&ends),
            "-o",
            s(&out),
        ]);
        ok(&o);
        results.push(read_surface_file(&out).unwrap().surfaces);
    }
    assert_eq!(results[0], results[1]);
    assert_eq!(results[0], results[2]);
    assert_ne!(results[0], read_surfaces_json(&dented).unwrap());
}

#[test]
fn bad_step_input_exits_2_naming_the_entity() {
    let d = tmp("cad-bad");
    let f = d.join("bad.stp");
    std::fs::write(
        &f,
        "ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=CARTESIAN_POINT('',(0.,0.,0.));\n\
         #2=DIRECTION('',(0.,0.,1.));\n#3=AXIS2_PLACEMENT_3D('',#1,#2,$);\n\
         #4=DEGENERATE_TOROIDAL_SURFACE('',#3,1.,2.,.T.);\n#5=OFFSET_SURFACE('',#4,1.,.F.);\n#6=ADVANCED_FACE('',(),#5,.T.);\n\
         ENDSEC;\nEND-ISO-10303-21;\n",
    )
    .unwrap();
    let out = d.join("out.igs");
    let o = run(&["convert", s(&f), s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.stp") && err.contains("#5 OFFSET_SURFACE"),
        "{err}"
    );
    assert!(!out.exists());
    let o = run(&["convert", s(&d.join("missing.step")), s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!out.exists());
}

/// Third-party STEP parts (crates/fairline/tests/data/step, SOURCE.md
/// there): trimesh's featuretype.STEP (SolidWorks AP214, inches) — `info`
/// reads its 96 faces, `render` draws it, `convert` writes it back as STEP
/// and it reads back identical — and CadQuery's cube and full-turn
/// cylinder, on which `highlight` draws lines.
#[test]
fn real_step_parts_are_read_drawn_and_written_back() {
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fairline/tests/data/step");
    let (part, cube) = (
        data.join("featuretype.STEP"),
        data.join("red_cube_blue_cylinder.step"),
    );
    let d = tmp("real-step");
    let (rep, lines, png, render, back) = (
        d.join("info.json"),
        d.join("lines.json"),
        d.join("lines.png"),
        d.join("render.png"),
        d.join("back.step"),
    );
    ok(&run(&["info", s(&part), "--area", "--report", s(&rep)]));
    let r = json(&rep);
    assert_eq!(r["surfaces"].as_u64(), Some(96), "{r}");
    ok(&run(&["render", s(&part), "--png", s(&render)]));
    assert!(std::fs::metadata(&render).unwrap().len() > 10_000);
    ok(&run(&["convert", s(&part), s(&back)]));
    let a = read_surface_file(&part).unwrap();
    let b = read_surface_file(&back).unwrap();
    assert_eq!(a.surfaces.len(), 96);
    assert_eq!(a.surfaces, b.surfaces);
    ok(&run(&[
        "highlight",
        s(&cube),
        "-o",
        s(&lines),
        "--png",
        s(&png),
    ]));
    let l = json(&lines);
    let count = l["lines"].as_array().map_or(0, |a| a.len());
    assert!(count > 20, "{count} lines");
    assert!(std::fs::metadata(&png).unwrap().len() > 10_000);
}

/// A STEP file whose p-curve disagrees with its 3-D edge (the p-curves
/// are used when they agree, else the 3-D edge, with a warning):
/// fairline writes `part()` with a p-curve per trim curve; the corner
/// (0.9, 0.9) of the outer loop moved to (0.95, 0.85) in the two p-curves
/// that end and start there makes them leave their written 3-D edges. `info` reads the file (exit 0), warns naming the
/// edge, and the face is trimmed by the 3-D edge: its trims lie on the
/// original loop (the untouched file reads back the original trims
/// exactly).
#[test]
fn a_step_pcurve_that_disagrees_with_its_edge_is_not_used_and_warned() {
    let d = tmp("cad-pcurve");
    let (src, stp, bad) = (d.join("part.json"), d.join("part.step"), d.join("bad.step"));
    fairline::io::write_surfaces_json(&src, &part()).unwrap();
    ok(&run(&["convert", s(&src), s(&stp)]));
    let o = run(&["info", s(&stp)]);
    ok(&o);
    assert!(!String::from_utf8_lossy(&o.stderr).contains("warning"));
    assert_eq!(read_surface_file(&stp).unwrap().surfaces, part());
    // The 2-D point (0.9, 0.9) of the outer polygon's p-curve.
    let text = std::fs::read_to_string(&stp).unwrap();
    let mut moved = 0;
    let lines: Vec<String> = text
        .lines()
        .map(|l| {
            let Some(inner) = l
                .split_once("CARTESIAN_POINT('',(")
                .and_then(|(_, r)| r.split_once("))"))
                .map(|(c, _)| c)
            else {
                return l.to_string();
            };
            let c: Vec<f64> = inner
                .split(',')
                .filter_map(|x| x.trim().parse().ok())
                .collect();
            if c == [0.9, 0.9] {
                moved += 1;
                l.replace(inner, "0.95,0.85")
            } else {
                l.to_string()
            }
        })
        .collect();
    assert_eq!(moved, 2, "the corner (0.9, 0.9) of two p-curves");
    std::fs::write(&bad, lines.join("\n")).unwrap();
    let o = run(&["info", s(&bad)]);
    ok(&o);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("warning")
            && err.contains("bad.step")
            && err.contains("disagree")
            && err.contains("EDGE_CURVE #"),
        "{err}"
    );
    // The face is trimmed by its 3-D edges: the outer loop still passes
    // through (0.9, 0.9), not (0.95, 0.85).
    let back = read_surface_file(&bad).unwrap();
    assert_eq!(back.warnings.len(), 1);
    assert!(
        back.warnings[0].starts_with("2 p-curve(s)"),
        "{}",
        back.warnings[0]
    );
    let face = &back.surfaces[0];
    assert!(face.contains_uv(0.85, 0.85) && !face.contains_uv(0.93, 0.87));
}
