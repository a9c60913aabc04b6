//! Pictures of real CAD parts with default options: every
//! STEP/IGES part in the repository and the shared data is drawn by
//! `highlight`, `render` and `continuity`; the teapot's default highlight
//! picture has readable line spacing in pixels; the impeller's default
//! picture is seen from its blades' side.

mod common;

use common::{data, json, ok, run, s, tmp};
use fairline::render::{Image, linear_to_srgb8};
use std::path::{Path, PathBuf};

/// The STEP and IGES parts of the repository and of the shared data.
fn real_parts() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fairline/tests");
    let mut parts = vec![
        root.join("data/step/featuretype.STEP"),
        root.join("data/step/red_cube_blue_cylinder.step"),
        root.join("corpus/step/ok-plane-hole-half-cylinder.step"),
    ];
    parts.extend(data("surfaces/impeller.igs"));
    parts
}

/// Pixels of a PNG that are not the background colour of its top-left
/// corner.
fn drawn_pixels(path: &Path) -> usize {
    let img = Image::decode_png(&std::fs::read(path).unwrap()).unwrap();
    let bg = img.get(0, 0).unwrap();
    (0..img.height)
        .flat_map(|y| (0..img.width).map(move |x| (x, y)))
        .filter(|&(x, y)| img.get(x, y) != Some(bg))
        .count()
}

/// `highlight`, `render` and `continuity` with defaults exit 0 on every
/// real part and write a picture with the part in it (featuretype.STEP
/// failed with "edge … is non-manifold": a trimmed face's tessellation had
/// a sliver on a grid corner's edge).
#[test]
fn every_real_cad_part_is_drawn_with_defaults() {
    let d = tmp("real-cad-parts");
    for part in real_parts() {
        let name = part.file_name().unwrap().to_string_lossy().into_owned();
        let out = |what: &str| d.join(format!("{name}-{what}"));
        let (lines, hl_png, render_png, seams, seams_png) = (
            out("lines.json"),
            out("highlight.png"),
            out("render.png"),
            out("seams.json"),
            out("seams.png"),
        );
        ok(&run(&[
            "highlight",
            s(&part),
            "-o",
            s(&lines),
            "--png",
            s(&hl_png),
        ]));
        ok(&run(&["render", s(&part), "--png", s(&render_png)]));
        ok(&run(&[
            "continuity",
            s(&part),
            "--report",
            s(&seams),
            "--png",
            s(&seams_png),
        ]));
        let l = json(&lines);
        assert!(
            l["lines"].as_array().is_some_and(|a| !a.is_empty()),
            "{name}: no highlight line"
        );
        for png in [&hl_png, &render_png, &seams_png] {
            let n = drawn_pixels(png);
            assert!(n > 50_000, "{name}: {} shows {n} pixels", png.display());
        }
    }
}

/// The six line colours of surface highlight pictures (the CLI's palette,
/// linear light) in sRGB.
fn palette() -> Vec<[u8; 3]> {
    [
        [0.75, 0.05, 0.05],
        [0.05, 0.15, 0.70],
        [0.05, 0.45, 0.10],
        [0.60, 0.25, 0.00],
        [0.45, 0.05, 0.55],
        [0.00, 0.40, 0.45],
    ]
    .iter()
    .map(|&c| {
        let p = linear_to_srgb8(c);
        [p[0], p[1], p[2]]
    })
    .collect()
}

/// For line pixels of a highlight picture (every 4th of the pixels within
/// 12 of a palette colour in each channel), the distance in pixels to the
/// nearest pixel of another palette colour — neighbouring lights have
/// different colours, so this is the spacing of neighbouring lines on the
/// screen (up to 40 px; farther counts as 40).
fn neighbour_line_distances(path: &Path) -> Vec<f64> {
    let img = Image::decode_png(&std::fs::read(path).unwrap()).unwrap();
    let pal = palette();
    let (w, h) = (img.width as i64, img.height as i64);
    let colour = |x: i64, y: i64| -> Option<usize> {
        if x < 0 || y < 0 || x >= w || y >= h {
            return None;
        }
        let p = img.get(x as u32, y as u32)?;
        pal.iter()
            .position(|c| (0..3).all(|k| c[k].abs_diff(p[k]) <= 12))
    };
    let mut out = Vec::new();
    let mut count = 0usize;
    for y in 0..h {
        for x in 0..w {
            let Some(k) = colour(x, y) else { continue };
            count += 1;
            if !count.is_multiple_of(4) {
                continue;
            }
            let mut best = 40.0f64;
            for dy in -40i64..=40 {
                for dx in -40i64..=40 {
                    let r = ((dx * dx + dy * dy) as f64).sqrt();
                    if r < best && colour(x + dx, y + dy).is_some_and(|j| j != k) {
                        best = r;
                    }
                }
            }
            out.push(best);
        }
    }
    out
}

/// The teapot's default highlight picture has readable lines: measured on
/// the PNG, the distance on the screen from a line pixel to the nearest
/// pixel of a neighbouring line (another colour) has a median of at least
/// 6.5 px (the readable drawing's limit is 1/150 of the part's width, 6 px
/// at 900 px) and an upper quartile of at least 11 px (measured: 8.5 and
/// 13.6 px with the gaps measured on the screen; 7 and 12 px with the gaps
/// on the surface). The same picture with every light of the mesh default
/// spacing (8; before the readable lights, k = 4) fails: lines crowd
/// (measured 6 / 7.3 px). Twice as dense again is crowded or thinned by the
/// readable drawing to fewer line pixels than the default picture.
#[test]
fn the_teapots_default_picture_has_readable_line_spacing_in_pixels() {
    let Some(teapot) = data("surfaces/teapot.json") else {
        return; // fails under CI; said loudly otherwise (shared_data.rs)
    };
    let d = tmp("teapot-spacing");
    let quartiles = |extra: &[&str], name: &str| {
        let png = d.join(format!("{name}.png"));
        let lines = d.join("l.json");
        let mut args = vec!["highlight", s(&teapot), "-o", s(&lines), "--png", s(&png)];
        args.extend_from_slice(extra);
        ok(&run(&args));
        let mut v = neighbour_line_distances(&png);
        assert!(v.len() > 400, "{name}: {} line pixels", v.len());
        v.sort_by(f64::total_cmp);
        let q = |f: f64| v[((v.len() - 1) as f64 * f) as usize];
        eprintln!(
            "teapot {name}: {} line pixels sampled, neighbour line distance median {} px, upper quartile {} px",
            v.len(),
            q(0.5),
            q(0.75)
        );
        (q(0.5), q(0.75), v.len())
    };
    let readable = |(median, upper, _): (f64, f64, usize)| median >= 6.5 && upper >= 11.0;
    let default = quartiles(&[], "default");
    assert!(readable(default), "{default:?}");
    assert!(default.2 > 1000, "{default:?}");
    // twice the mesh default's density crowds the picture; four times as
    // dense is either crowded too or thinned by the readable drawing to
    // fewer line pixels than the default picture draws
    let dense = quartiles(&["--spacing", "8"], "dense");
    assert!(!readable(dense), "dense: {dense:?}");
    let denser = quartiles(&["--spacing", "4"], "denser");
    assert!(
        !readable(denser) || denser.2 < default.2,
        "denser: {denser:?} against {default:?}"
    );
}

/// The impeller's default picture thins its lines by their gaps on the
/// screen, not on the surface: blades seen at a grazing angle show no
/// bands of lines a pixel or two apart. Measured on the PNG
/// as in the teapot test: fewer than 5 % of the sampled line pixels have a
/// neighbouring line within 4 px, and the lowest tenth of the gaps is at
/// least 4 px (measured 1.9 % and 6 px; with the gaps on the surface the
/// picture had 28.3 % and 2 px).
#[test]
fn the_impellers_default_picture_has_no_lines_crowded_on_the_screen() {
    let Some(imp) = data("surfaces/impeller.igs") else {
        return; // fails under CI; said loudly otherwise (shared_data.rs)
    };
    let d = tmp("impeller-crowded");
    let (lines, png, rep) = (d.join("l.json"), d.join("p.png"), d.join("r.json"));
    ok(&run(&[
        "highlight",
        s(&imp),
        "-o",
        s(&lines),
        "--png",
        s(&png),
        "--report",
        s(&rep),
    ]));
    let mut v = neighbour_line_distances(&png);
    assert!(v.len() > 1000, "{} line pixels", v.len());
    v.sort_by(f64::total_cmp);
    let crowded = v.iter().filter(|&&x| x < 4.0).count() as f64 / v.len() as f64;
    let p10 = v[(v.len() - 1) / 10];
    eprintln!(
        "impeller: {} line pixels sampled, {:.1} % with a neighbour line within 4 px, lowest tenth {p10} px",
        v.len(),
        100.0 * crowded
    );
    assert!(crowded < 0.05, "{crowded}");
    assert!(p10 >= 4.0, "{p10}");
    // the lines file keeps every line: the thinning is the picture's
    let r = json(&rep);
    let n = json(&lines)["lines"].as_array().map_or(0, |a| a.len());
    assert_eq!(r["lines"].as_u64(), Some(n as u64), "{r}");
    assert!(r["drawn"]["pieces"].as_u64().unwrap() < n as u64, "{r}");
}

/// The impeller's default picture shows the side with the blades: the
/// lights and the view face −z (the blades stand on the −z side of the
/// dish; from +z the picture showed the dish's flat back), and many
/// patches carry drawn lines.
#[test]
fn the_impellers_default_picture_shows_the_blades() {
    let Some(imp) = data("surfaces/impeller.igs") else {
        return; // fails under CI; said loudly otherwise (shared_data.rs)
    };
    let d = tmp("impeller-side");
    let (lines, png, rep) = (d.join("l.json"), d.join("p.png"), d.join("r.json"));
    ok(&run(&[
        "highlight",
        s(&imp),
        "-o",
        s(&lines),
        "--png",
        s(&png),
        "--report",
        s(&rep),
    ]));
    let r = json(&rep);
    let z = &r["light"]["array"]["plane_normal"];
    assert_eq!(z[2].as_f64(), Some(-1.0), "{r}");
    assert!(r["view"]["dir"][2].as_f64().unwrap() > 0.0, "{r}");
    assert!(std::fs::metadata(&lines).unwrap().len() < 50_000_000);
}
