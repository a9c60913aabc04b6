//! Command-line tests of the B-spline surface commands as a user drives
//! them from the shell: default circular lights derived
//! from the part and printed, line ids in the lines JSON and in the SVG
//! with a legend of the lights, `fair-surface --lines --from ID:T --to ID:T`
//! (and its JSON form) instead of (u, v) read off a picture, and the warning
//! for an endpoint that snaps far from where it was given.

mod common;
use common::*;

use fairline::bspline::BSplineSurface;
use fairline::io::{read_surfaces_json, write_surfaces_json};

fn dome() -> BSplineSurface {
    dome_surface(true)
}

const BUMP: [f64; 2] = DOME_BUMP_UV;

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The JSON object printed on the "default circular lights" line of stderr.
fn printed_lights(err: &str) -> serde_json::Value {
    let line = err
        .lines()
        .find(|l| l.starts_with("default circular lights"))
        .unwrap_or_else(|| panic!("no default lights printed: {err}"));
    let json = &line[line.find('{').unwrap()..];
    serde_json::from_str(json).unwrap()
}

#[test]
fn circular_defaults_are_derived_from_the_part_printed_and_reusable() {
    let d = tmp("defaults");
    let f = d.join("dome.json");
    write_surfaces_json(&f, &[dome()]).unwrap();
    let (out, rep) = (d.join("lines.json"), d.join("r.json"));
    let o = run(&[
        "highlight",
        s(&f),
        "--circular",
        "-o",
        s(&out),
        "--report",
        s(&rep),
    ]);
    ok(&o);
    let printed = printed_lights(&stderr(&o));
    let r = json(&rep);
    assert_eq!(r["light"]["kind"], "circular");
    assert_eq!(r["light"]["derived"], true);
    for key in ["center", "axis", "radii"] {
        assert_eq!(r["light"][key], printed[key], "{key}");
    }
    // The dome is symmetric about the z axis: the lights face it from
    // above, centred on the axis.
    let axis: Vec<f64> = serde_json::from_value(printed["axis"].clone()).unwrap();
    let centre: Vec<f64> = serde_json::from_value(printed["center"].clone()).unwrap();
    assert!(axis[2] > 0.999, "axis {axis:?}");
    assert!(
        centre[0].abs() < 0.01 && centre[1].abs() < 0.01,
        "{centre:?}"
    );
    assert!(
        centre[2] > 0.83,
        "centre {centre:?} above the top of the dome"
    );
    let radii: Vec<f64> = serde_json::from_value(printed["radii"].clone()).unwrap();
    assert_eq!(radii.len(), 10);
    assert!(radii.windows(2).all(|w| w[1] > w[0]));
    // The radii span the part: every light draws a line on it.
    let lines = json(&out);
    for r in &radii {
        assert!(
            lines["lines"]
                .as_array()
                .unwrap()
                .iter()
                .any(|l| l["radius"].as_f64() == Some(*r)),
            "radius {r} draws no line"
        );
    }
    // The printed line is a LIGHTS.json: given back, the same lines.
    let lf = d.join("lights.json");
    std::fs::write(&lf, serde_json::to_string(&printed).unwrap()).unwrap();
    let again = d.join("again.json");
    ok(&run(&[
        "highlight",
        s(&f),
        "--lights",
        s(&lf),
        "-o",
        s(&again),
    ]));
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&again).unwrap());
    // --circular and explicit lights exclude each other.
    let o = run(&[
        "highlight",
        s(&f),
        "--circular",
        "--lights",
        s(&lf),
        "-o",
        s(&d.join("x.json")),
    ]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn lines_carry_ids_and_the_svg_has_a_legend_of_radii_and_the_ids() {
    let d = tmp("legend");
    let f = d.join("dome.json");
    write_surfaces_json(&f, &[dome()]).unwrap();
    let (out, svg) = (d.join("lines.json"), d.join("uv.svg"));
    let radii = [2.0, 2.2, 2.4];
    ok(&run(&[
        "highlight",
        s(&f),
        "--circle-center",
        "0,0,3",
        "--circle-axis",
        "0,0,1",
        "--radii",
        "2,2.2,2.4",
        "-o",
        s(&out),
        "--svg",
        s(&svg),
    ]));
    let lines = json(&out);
    let lines = lines["lines"].as_array().unwrap();
    assert!(lines.len() >= 3);
    for (k, l) in lines.iter().enumerate() {
        assert_eq!(l["id"].as_u64(), Some(k as u64));
    }
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains(r#"class="legend""#));
    for r in radii {
        assert!(
            text.contains(&format!(">R = {r}<")),
            "legend entry of R = {r}"
        );
    }
    for k in 0..lines.len() {
        assert!(text.contains(&format!(">#{k}<")), "id #{k} in the SVG");
    }
    assert!(!text.contains(&format!(">#{}<", lines.len())));
    // Linear lights: the legend names the lights by index.
    let svg2 = d.join("uv2.svg");
    ok(&run(&[
        "highlight",
        s(&f),
        "-o",
        s(&d.join("lin.json")),
        "--svg",
        s(&svg2),
    ]));
    let lin = json(&d.join("lin.json"));
    let text = std::fs::read_to_string(&svg2).unwrap();
    let first = lin["lines"][0]["index"].as_i64().unwrap();
    assert!(
        text.contains(&format!(">light {first}<")),
        "legend of light {first}"
    );
}

/// (u, v) at fraction `t` of the length in space of a JSON line: computed
/// here independently of the command.
fn uv_at(line: &serde_json::Value, t: f64) -> [f64; 2] {
    let pts: Vec<[f64; 3]> = serde_json::from_value(line["points"].clone()).unwrap();
    let uv: Vec<[f64; 2]> = serde_json::from_value(line["uv"].clone()).unwrap();
    let closed = line["closed"].as_bool().unwrap();
    let n = pts.len();
    let segs: Vec<(usize, usize)> = (0..if closed { n } else { n - 1 })
        .map(|k| (k, (k + 1) % n))
        .collect();
    let len = |(a, b): (usize, usize)| {
        let d: f64 = (0..3).map(|c| (pts[b][c] - pts[a][c]).powi(2)).sum();
        d.sqrt()
    };
    let total: f64 = segs.iter().map(|&s| len(s)).sum();
    let mut left = t * total;
    for &(a, b) in &segs {
        let l = len((a, b));
        if left <= l {
            let f = left / l;
            return [
                uv[a][0] + f * (uv[b][0] - uv[a][0]),
                uv[a][1] + f * (uv[b][1] - uv[a][1]),
            ];
        }
        left -= l;
    }
    uv[segs.last().unwrap().1]
}

/// The line of `lines` passing nearest `p` in (u, v), with the fraction of
/// its length at the nearest vertex.
fn line_near(lines: &[serde_json::Value], p: [f64; 2]) -> (usize, f64) {
    let mut best = (f64::INFINITY, 0, 0.0);
    for l in lines {
        let uv: Vec<[f64; 2]> = serde_json::from_value(l["uv"].clone()).unwrap();
        let pts: Vec<[f64; 3]> = serde_json::from_value(l["points"].clone()).unwrap();
        let mut acc = vec![0.0];
        for k in 1..pts.len() {
            let d: f64 = (0..3).map(|c| (pts[k][c] - pts[k - 1][c]).powi(2)).sum();
            acc.push(acc[k - 1] + d.sqrt());
        }
        let total = if l["closed"].as_bool().unwrap() {
            let d: f64 = (0..3)
                .map(|c| (pts[0][c] - pts[pts.len() - 1][c]).powi(2))
                .sum();
            acc[pts.len() - 1] + d.sqrt()
        } else {
            acc[pts.len() - 1]
        };
        for (k, q) in uv.iter().enumerate() {
            let d = (q[0] - p[0]).hypot(q[1] - p[1]);
            if d < best.0 {
                best = (d, l["id"].as_u64().unwrap() as usize, acc[k] / total);
            }
        }
    }
    (best.1, best.2)
}

#[test]
fn fair_surface_takes_endpoints_as_line_id_and_parameter() {
    let d = tmp("by-line");
    let f = d.join("dome.json");
    write_surfaces_json(&f, &[dome()]).unwrap();
    let lf = d.join("lights.json");
    std::fs::write(
        &lf,
        r#"{"center":[0,0,3],"axis":[0,0,1],"radii":[2.1,2.2,2.3,2.4,2.5,2.6]}"#,
    )
    .unwrap();
    let lines_file = d.join("lines.json");
    ok(&run(&[
        "highlight",
        s(&f),
        "--lights",
        s(&lf),
        "-o",
        s(&lines_file),
    ]));
    let doc = json(&lines_file);
    let lines = doc["lines"].as_array().unwrap();
    let (id, t) = line_near(lines, BUMP);
    let line = &lines[id];
    let (t0, t1) = ((t - 0.08).max(0.0), (t + 0.08).min(1.0));
    let (from, to) = (format!("{id}:{t0}"), format!("{id}:{t1}"));
    // 1. --from/--to on the lines file.
    let (out1, rep1) = (d.join("out1.json"), d.join("rep1.json"));
    let o = run(&[
        "fair-surface",
        s(&f),
        "--lights",
        s(&lf),
        "--lines",
        s(&lines_file),
        "--from",
        &from,
        "--to",
        &to,
        "-o",
        s(&out1),
        "--report",
        s(&rep1),
    ]);
    ok(&o);
    assert!(!stderr(&o).contains("warning: endpoint"), "{}", stderr(&o));
    // 2. the JSON form {"line":ID,"from":T,"to":T}.
    let ef = d.join("ends-line.json");
    std::fs::write(
        &ef,
        format!(r#"{{"endpoints":[{{"line":{id},"from":{t0},"to":{t1}}}]}}"#),
    )
    .unwrap();
    let out2 = d.join("out2.json");
    ok(&run(&[
        "fair-surface",
        s(&f),
        "--lights",
        s(&lf),
        "--lines",
        s(&lines_file),
        "--endpoints",
        s(&ef),
        "-o",
        s(&out2),
    ]));
    // 3. the same points as (u, v), computed here from the lines file.
    let (a, b) = (uv_at(line, t0), uv_at(line, t1));
    let radius = line["radius"].as_f64().unwrap();
    let eu = d.join("ends-uv.json");
    std::fs::write(
        &eu,
        serde_json::json!({"endpoints":[{"radius":radius,"start":a,"end":b}]}).to_string(),
    )
    .unwrap();
    let out3 = d.join("out3.json");
    ok(&run(&[
        "fair-surface",
        s(&f),
        "--lights",
        s(&lf),
        "--endpoints",
        s(&eu),
        "-o",
        s(&out3),
    ]));
    let bytes = std::fs::read(&out1).unwrap();
    assert_eq!(bytes, std::fs::read(&out2).unwrap());
    assert_eq!(bytes, std::fs::read(&out3).unwrap());
    // The stretch lies on the line: the endpoints snap by (almost) nothing,
    // and the fairing moved control points near the bump.
    let r = json(&rep1);
    let snaps: Vec<[f64; 2]> = serde_json::from_value(r["snap_distances"].clone()).unwrap();
    assert!(snaps[0][0] < 1e-9 && snaps[0][1] < 1e-9, "{snaps:?}");
    assert!(r["modified_control_points"].as_u64().unwrap() > 0);
    assert_ne!(
        read_surfaces_json(&out1).unwrap()[0].control_point(11, 7),
        dome().control_point(11, 7)
    );
}

#[test]
fn fair_surface_line_endpoints_refuse_bad_ids_and_mixed_lines() {
    let d = tmp("by-line-bad");
    let f = d.join("dome.json");
    write_surfaces_json(&f, &[dome()]).unwrap();
    let lf = d.join("lights.json");
    std::fs::write(
        &lf,
        r#"{"center":[0,0,3],"axis":[0,0,1],"radii":[2.2,2.4]}"#,
    )
    .unwrap();
    let lines_file = d.join("lines.json");
    ok(&run(&[
        "highlight",
        s(&f),
        "--lights",
        s(&lf),
        "-o",
        s(&lines_file),
    ]));
    let n = json(&lines_file)["lines"].as_array().unwrap().len();
    assert!(n >= 2);
    let out = d.join("out.json");
    let attempt = |extra: &[&str]| {
        let mut a = vec!["fair-surface", s(&f), "--lights", s(&lf), "-o", s(&out)];
        a.extend_from_slice(extra);
        run(&a)
    };
    let bad_id = format!("{n}:0.2");
    let bad_id_to = format!("{n}:0.4");
    for (extra, says) in [
        (
            vec![
                "--lines",
                s(&lines_file),
                "--from",
                &bad_id,
                "--to",
                &bad_id_to,
            ],
            "no line has id",
        ),
        (
            vec![
                "--lines",
                s(&lines_file),
                "--from",
                "0:0.2",
                "--to",
                "1:0.4",
            ],
            "different lines",
        ),
        (
            vec![
                "--lines",
                s(&lines_file),
                "--from",
                "0:1.5",
                "--to",
                "0:0.4",
            ],
            "0..1",
        ),
        (vec!["--from", "0:0.2", "--to", "0:0.4"], "--lines"),
    ] {
        let o = attempt(&extra);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(says), "{extra:?}: {}", stderr(&o));
        assert!(!out.exists());
    }
    // A linear-light line has no radius: not a stretch fair-surface fairs.
    let lin = d.join("lin.json");
    ok(&run(&["highlight", s(&f), "-o", s(&lin)]));
    let o = attempt(&["--lines", s(&lin), "--from", "0:0.2", "--to", "0:0.4"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("no radius"), "{}", stderr(&o));
    assert!(!out.exists());
}

#[test]
fn fair_surface_warns_when_a_uv_endpoint_snaps_far() {
    let d = tmp("snap");
    let f = d.join("dome.json");
    write_surfaces_json(&f, &[dome()]).unwrap();
    let lf = d.join("lights.json");
    std::fs::write(
        &lf,
        r#"{"center":[0,0,3],"axis":[0,0,1],"radii":[2.2,2.3,2.4,2.5]}"#,
    )
    .unwrap();
    let lines_file = d.join("lines.json");
    ok(&run(&[
        "highlight",
        s(&f),
        "--lights",
        s(&lf),
        "-o",
        s(&lines_file),
    ]));
    let doc = json(&lines_file);
    let lines = doc["lines"].as_array().unwrap();
    let (id, t) = line_near(lines, BUMP);
    let line = &lines[id];
    let radius = line["radius"].as_f64().unwrap();
    let (t0, t1) = ((t - 0.08).max(0.0), (t + 0.08).min(1.0));
    let (a, b) = (uv_at(line, t0), uv_at(line, t1));
    // The domain is [0, 1]²: its diagonal is √2, the tolerance 2 % of it.
    let tolerance = 0.02 * 2f64.sqrt();
    let ends = d.join("ends.json");
    let fair = |start: [f64; 2], tag: &str| {
        std::fs::write(
            &ends,
            serde_json::json!({"endpoints":[{"radius":radius,"start":start,"end":b}]}).to_string(),
        )
        .unwrap();
        let rep = d.join(format!("rep-{tag}.json"));
        let o = run(&[
            "fair-surface",
            s(&f),
            "--lights",
            s(&lf),
            "--endpoints",
            s(&ends),
            "-o",
            s(&d.join(format!("out-{tag}.json"))),
            "--report",
            s(&rep),
        ]);
        ok(&o);
        (stderr(&o), json(&rep))
    };
    // On the line: no warning.
    let (err, rep) = fair(a, "on");
    assert!(!err.contains("warning: endpoint"), "{err}");
    let no_snap = rep["warnings"].as_array().is_none_or(|w| {
        !w.iter()
            .any(|x| x.as_str().unwrap_or_default().contains("endpoint"))
    });
    assert!(no_snap, "{rep}");
    // Moved off the line, across it, by twice the tolerance: a warning on
    // stderr and in the report, naming the endpoint and the distance.
    let uv: Vec<[f64; 2]> = serde_json::from_value(line["uv"].clone()).unwrap();
    let k = uv
        .iter()
        .enumerate()
        .min_by(|x, y| {
            let dx = (x.1[0] - a[0]).hypot(x.1[1] - a[1]);
            let dy = (y.1[0] - a[0]).hypot(y.1[1] - a[1]);
            dx.total_cmp(&dy)
        })
        .unwrap()
        .0;
    let (p, q) = (uv[k.saturating_sub(1)], uv[(k + 1).min(uv.len() - 1)]);
    let (tx, ty) = (q[0] - p[0], q[1] - p[1]);
    let len = tx.hypot(ty);
    let off = [
        a[0] - ty / len * 2.0 * tolerance,
        a[1] + tx / len * 2.0 * tolerance,
    ];
    let (err, rep) = fair(off, "off");
    assert!(
        err.contains("warning: endpoint 0 start") && err.contains("snapped"),
        "{err}"
    );
    let warnings = rep["warnings"].as_array().expect("warnings in the report");
    assert!(
        warnings
            .iter()
            .any(|w| w.as_str().unwrap().contains("endpoint 0 start"))
    );
    let snaps: Vec<[f64; 2]> = serde_json::from_value(rep["snap_distances"].clone()).unwrap();
    assert!(snaps[0][0] > tolerance, "{snaps:?}");
}

/// RGBA pixels and width of a PNG file.
fn read_png(path: &std::path::Path) -> (Vec<u8>, usize) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgba, "{}", path.display());
    buf.truncate(info.buffer_size());
    (buf, info.width as usize)
}

/// The PNG of a part's circular highlight lines has a key like the mesh
/// pictures: a light panel in a corner holding one swatch per radius drawn,
/// in that light's colour; the same picture without lines has no panel.
#[test]
fn the_surface_highlight_picture_has_a_key_of_the_radii() {
    let d = tmp("png-key");
    let f = d.join("dome.json");
    write_surfaces_json(&f, &[dome()]).unwrap();
    let picture = |radii: &str, name: &str| {
        let png = d.join(name);
        ok(&run(&[
            "highlight",
            s(&f),
            "--circle-center",
            "0,0,3",
            "--circle-axis",
            "0,0,1",
            "--radii",
            radii,
            "-o",
            s(&d.join("lines.json")),
            "--png",
            s(&png),
        ]));
        let n = json(&d.join("lines.json"))["lines"]
            .as_array()
            .unwrap()
            .len();
        (read_png(&png), n)
    };
    // pixels of the key panel's background (250, 250, 250)
    let panel = |(px, _): &(Vec<u8>, usize)| {
        px.chunks(4)
            .filter(|p| p[0] == 250 && p[1] == 250 && p[2] == 250)
            .count()
    };
    let (with, n) = picture("2,2.2,2.4", "with.png");
    assert!(n >= 3, "{n} lines");
    assert!(panel(&with) > 2000, "key panel: {} pixels", panel(&with));
    // far outside the dome: no line, no key
    let (without, n0) = picture("900", "without.png");
    assert_eq!(n0, 0);
    assert_eq!(panel(&without), 0);
}
