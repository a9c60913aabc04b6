//! Command-line tests of faces a CAD file holds that fairline cannot read:
//! every command that reads the file names them and exits 1 unless
//! `--skip-unreadable` is given (which still warns, on stderr and in the
//! report); `info` lists them; `convert` never writes a partial part
//! without the flag. Surface formats fairline does not read (Rhino .3dm)
//! get an error that lists the ones it does.

mod common;

use common::{json, ok, run, s, tmp};

/// A fixed-format IGES file of `(type, form, parameter data)` entities
/// (each parameter record at most 64 columns, all entities independent).
fn iges(entities: &[(i64, i64, &str)]) -> String {
    let mut out = String::new();
    out.push_str(&format!("{:<72}S{:>7}\n", "hand-made", 1));
    out.push_str(&format!(
        "{:<72}G{:>7}\n",
        "1H,,1H;,,,,,32,308,15,308,15,,1.,2,2HMM,1,0.1,,1E-8,100.,,,11,0,;", 1
    ));
    let (mut d, mut p) = (String::new(), String::new());
    for (k, &(ty, form, data)) in entities.iter().enumerate() {
        let pseq = k + 1;
        let de = 2 * k + 1;
        assert!(data.len() <= 64);
        d.push_str(&format!(
            "{ty:>8}{pseq:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}D{de:>7}\n",
            0, 0, 0, 0, 0, 0, "00000000"
        ));
        d.push_str(&format!(
            "{ty:>8}{:>8}{:>8}{:>8}{form:>8}{:>8}{:>8}{:>8}{:>8}D{:>7}\n",
            0,
            0,
            1,
            "",
            "",
            "",
            0,
            de + 1
        ));
        p.push_str(&format!("{data:<64} {de:>7}P{pseq:>7}\n"));
    }
    out.push_str(&d);
    out.push_str(&p);
    out.push_str(&format!("{:<72}T{:>7}\n", "S      1G      1", 1));
    out
}

/// A 10 × 5 planar face (108 trimmed by a 144) and a B-rep face (510) on
/// the plane 108, a surface fairline does not read under a 510.
fn part_with_a_brep_face() -> String {
    iges(&[
        (108, 0, "108,0.,0.,1.,0.,0,0.,0.,0.,0.;"),
        (110, 0, "110,0.,0.,0.,10.,0.,0.;"),
        (110, 0, "110,10.,0.,0.,10.,5.,0.;"),
        (110, 0, "110,10.,5.,0.,0.,5.,0.;"),
        (110, 0, "110,0.,5.,0.,0.,0.,0.;"),
        (102, 0, "102,4,3,5,7,9;"),
        (142, 0, "142,0,1,0,11,2;"),
        (144, 0, "144,1,1,0,13;"),
        (510, 1, "510,1,0,0;"),
    ])
}

#[test]
fn unreadable_faces_fail_every_reading_command_unless_skipped() {
    let d = tmp("cad-unreadable");
    let f = d.join("part.igs");
    std::fs::write(&f, part_with_a_brep_face()).unwrap();

    // info: lists the face, exits 1
    let o = run(&["info", "--json", "--area", s(&f)]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("could not read 1 face(s)"), "{err}");
    assert!(err.contains("entity 510 (DE 17"), "{err}");
    assert!(err.contains("--skip-unreadable"), "{err}");
    let info: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(info["surfaces"], 1);
    assert_eq!(info["unreadable_faces"], 1);
    assert!(
        info["unreadable"][0]["entity"]
            .as_str()
            .unwrap()
            .contains("510")
    );
    assert!((info["area"].as_f64().unwrap() - 50.0).abs() < 1e-9);

    // with --skip-unreadable: exit 0, still warned in the report
    let rep = d.join("info.json");
    let o = run(&[
        "info",
        "--json",
        s(&f),
        "--skip-unreadable",
        "--report",
        s(&rep),
    ]);
    ok(&o);
    let r = json(&rep);
    let w = r["warnings"].as_array().unwrap();
    assert!(
        w.iter().any(|w| w.as_str().unwrap().contains("entity 510")),
        "{w:?}"
    );

    // convert: nothing written without the flag
    let out = d.join("part.step");
    let o = run(&["convert", s(&f), s(&out)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("entity 510"));
    assert!(!out.exists(), "a partial part was written");
    let rep = d.join("convert.json");
    let o = run(&[
        "--skip-unreadable",
        "convert",
        s(&f),
        s(&out),
        "--report",
        s(&rep),
    ]);
    ok(&o);
    assert!(out.exists());
    assert!(
        json(&rep)["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w.as_str().unwrap().contains("written without them"))
    );

    // another command that reads surfaces
    let o = run(&["continuity", s(&f)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("could not read 1 face(s)"));
}

#[test]
fn surface_formats_fairline_does_not_read_are_named() {
    let d = tmp("cad-foreign");
    let f = d.join("part.3dm");
    std::fs::write(&f, "not read").unwrap();
    let o = run(&["info", s(&f)]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(".igs/.iges") && err.contains(".step/.stp") && err.contains(".g2"),
        "{err}"
    );
    assert!(err.contains("export IGES or STEP"), "{err}");
}
