//! Every command checks the type of its outputs in one place
//! (`output::require_extension`): a wrong extension is refused before
//! anything is read or written, with exit status 2 and one message shape.

mod common;

use common::{run, s, tmp};

#[test]
fn a_wrong_output_extension_is_refused_the_same_way_by_every_command() {
    let d = tmp("extensions");
    let input = d.join("in.obj");
    std::fs::write(
        &input,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0.1\nf 1 2 3\nf 2 4 3\n",
    )
    .unwrap();
    let bad = |name: &str| s(&d.join(name)).to_string();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec![
                "curvature".into(),
                s(&input).into(),
                "-o".into(),
                bad("c.obj"),
            ],
            "-o must name a .ply file",
        ),
        (
            vec![
                "render".into(),
                s(&input).into(),
                "--png".into(),
                bad("r.jpg"),
            ],
            "--png must name a .png file",
        ),
        (
            vec![
                "detect".into(),
                s(&input).into(),
                "-o".into(),
                bad("region.txt"),
            ],
            "-o must name a .json file",
        ),
        (
            vec![
                "highlight".into(),
                s(&input).into(),
                "-o".into(),
                bad("lines.txt"),
            ],
            "-o must name a .json, .obj, .igs or .iges file",
        ),
        (
            vec![
                "highlight".into(),
                s(&input).into(),
                "-o".into(),
                bad("lines.json"),
                "--png".into(),
                bad("l.svg"),
            ],
            "--png must name a .png file",
        ),
        (
            vec![
                "enhance".into(),
                s(&input).into(),
                "-o".into(),
                bad("e.obj"),
                "--png".into(),
                bad("e.jpg"),
            ],
            "--png must name a .png file",
        ),
    ];
    for (args, message) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = run(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
        assert!(err.contains("nothing written"), "{args:?}: {err}");
    }
    // nothing but the input was written
    let names: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("in.obj")]);
    std::fs::remove_dir_all(&d).unwrap();
}
