//! `--zebra` in the pictures of every command that shades the part, and
//! the pictures without it left as they were.
//!
//! - refused alike everywhere: a `--zebra-period` outside (0, 180] or not
//!   a number, and `--zebra` without `--png`, exit 2 naming the option,
//!   nothing written;
//! - the default pictures (no `--zebra`) of real data are byte for byte the
//!   recorded ones (FNV-1a of the PNG files);
//! - `render`, `highlight`, `detect`, `section`, `smooth` and `fair` with
//!   `--zebra` on Spot: measured from the pixels as the picture test
//!   measures `render --zebra` (dark stripes reach most of the part, specks
//!   a small share of the dark pixels), seen from one camera (silhouettes
//!   of the part agree with `render --zebra`'s), and the report gives the
//!   zebra drawn.

mod common;
use common::*;

use fairline::render::Image;
use std::path::Path;

/// Smallest share of the part's pixels within [`NEAR_PX`] of a dark pixel.
const MIN_REACH: f64 = 0.4;
/// Distance (pixels) at which a part pixel counts as near a dark pixel.
const NEAR_PX: i64 = 12;
/// Largest share of the dark pixels in specks (pieces under 15 pixels).
const MAX_SPECKS: f64 = 0.25;
/// Smallest intersection over union of two pictures' normalised
/// silhouettes.
const MIN_IOU: f64 = 0.85;

/// FNV-1a (64 bits) of `bytes`.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Whether this CPU takes the SIMD path the fingerprints were recorded
/// with (the lights and detection solve small systems with faer, whose
/// kernels pick their vector width at run time).
fn same_simd_as_recorded() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

#[test]
fn zebra_period_out_of_range_is_refused_by_every_command_nothing_written() {
    let Some(mesh) = data("meshes/bob_small.ply") else {
        return;
    };
    let Some(teapot) = data("surfaces/teapot.json") else {
        return;
    };
    let dir = tmp("zebra-refused");
    let (m, t) = (s(&mesh).to_string(), s(&teapot).to_string());
    let out = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let commands: Vec<Vec<String>> = vec![
        vec!["render".into(), m.clone()],
        vec!["highlight".into(), m.clone(), "-o".into(), out("l.json")],
        vec!["detect".into(), m.clone(), "-o".into(), out("r.json")],
        vec![
            "fair".into(),
            m.clone(),
            "--auto".into(),
            "-o".into(),
            out("f.ply"),
        ],
        vec!["smooth".into(), m.clone(), "-o".into(), out("s.ply")],
        vec!["enhance".into(), m.clone(), "-o".into(), out("e.ply")],
        vec![
            "section".into(),
            m.clone(),
            "--plane-point".into(),
            "0,0,0".into(),
            "--plane-normal".into(),
            "0,1,0".into(),
        ],
        vec!["continuity".into(), t.clone()],
        vec!["highlight".into(), t.clone(), "-o".into(), out("t.json")],
    ];
    for cmd in &commands {
        for bad in ["0", "-5", "180.5", "nan", "inf", "wide"] {
            let png = out("z.png");
            let mut args: Vec<&str> = cmd.iter().map(String::as_str).collect();
            args.extend(["--png", &png, "--zebra", "--zebra-period", bad]);
            let o = run(&args);
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
            assert!(err.contains("--zebra-period"), "{args:?}: {err}");
            assert!(
                std::fs::read_dir(&dir).unwrap().next().is_none(),
                "{args:?} wrote something"
            );
        }
        // --zebra means a picture: without --png it is refused too
        if cmd[0] != "render" {
            let mut args: Vec<&str> = cmd.iter().map(String::as_str).collect();
            args.push("--zebra");
            let o = run(&args);
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
            assert!(err.contains("--png"), "{args:?}: {err}");
            assert!(std::fs::read_dir(&dir).unwrap().next().is_none());
        }
    }
    // the bounds themselves are accepted
    let png = dir.join("ok.png");
    for good in ["180", "0.01"] {
        ok(&run(&[
            "render",
            s(&mesh),
            "--png",
            s(&png),
            "--size",
            "160x120",
            "--zebra",
            "--zebra-period",
            good,
        ]));
    }
    // --help says the same of both options in every command that has them
    // (whatever the layout of its columns)
    let help = |c: &str| {
        let o = run(&[c, "--help"]);
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        ["--zebra", "--zebra-period"].map(|opt| option_help(&text, opt))
    };
    let reference = help("render");
    for c in [
        "highlight",
        "detect",
        "fair",
        "smooth",
        "fair-quad",
        "enhance",
        "section",
        "continuity",
        "fair-surface",
    ] {
        assert_eq!(help(c), reference, "{c} --help");
    }
    for c in ["deviation", "draft"] {
        let o = run(&[c, "--help"]);
        assert!(
            !String::from_utf8_lossy(&o.stdout).contains("--zebra"),
            "{c}"
        );
    }
}

/// The words `--help` gives for the option `opt` (the line it starts and
/// those continuing it, up to the next option), whitespace collapsed.
fn option_help(help: &str, opt: &str) -> String {
    let mut lines = help
        .lines()
        .skip_while(|l| l.split_whitespace().next() != Some(opt));
    let first = lines
        .next()
        .unwrap_or_else(|| panic!("{opt} in --help:\n{help}"));
    let rest = lines.take_while(|l| {
        let t = l.trim_start();
        !t.is_empty() && !t.starts_with('-')
    });
    std::iter::once(first)
        .chain(rest)
        .flat_map(str::split_whitespace)
        .collect::<Vec<_>>()
        .join(" ")
}

/// The default pictures of real data, byte for byte: (name, FNV-1a of the
/// PNG file, the command's arguments with `{M}` the mesh, `{T}` the teapot,
/// `{D}` the output folder).
const FINGERPRINTS: &[(&str, u64, &[&str])] = &[
    (
        "render",
        0xff1f_a493_1ed2_bc8e,
        &[
            "render",
            "{M}",
            "--png",
            "{D}/render.png",
            "--size",
            "480x360",
        ],
    ),
    (
        "highlight",
        0xeb47_1d5b_5dfc_48a4,
        &[
            "highlight",
            "{M}",
            "-o",
            "{D}/l.json",
            "--png",
            "{D}/highlight.png",
            "--size",
            "480x360",
        ],
    ),
    (
        "detect",
        0x8008_6fce_f8bb_af4a,
        &[
            "detect",
            "{M}",
            "-o",
            "{D}/r.json",
            "--png",
            "{D}/detect.png",
            "--size",
            "480x360",
        ],
    ),
    (
        "smooth",
        0x02b6_0800_65e0_9910,
        &[
            "smooth",
            "{M}",
            "-o",
            "{D}/s.ply",
            "--iterations",
            "1",
            "--png",
            "{D}/smooth.png",
        ],
    ),
    (
        "section",
        0x3f17_44b0_8c51_44fa,
        &[
            "section",
            "{M}",
            "--plane-point",
            "0,0,0",
            "--plane-normal",
            "0,1,0",
            "--count",
            "3",
            "--spacing",
            "0.2",
            "--png",
            "{D}/section.png",
            "--size",
            "480x360",
        ],
    ),
    (
        "fair",
        0x7529_43b5_9d83_7154,
        &[
            "fair",
            "{M}",
            "--auto",
            "-o",
            "{D}/f.ply",
            "--png",
            "{D}/fair.png",
        ],
    ),
    (
        "continuity",
        0xad92_1f66_e4c9_e4fc,
        &["continuity", "{T}", "--png", "{D}/continuity.png"],
    ),
    (
        "surface highlight",
        0x1688_2181_05c1_4dd6,
        &[
            "highlight",
            "{T}",
            "-o",
            "{D}/t.json",
            "--png",
            "{D}/surface-highlight.png",
            "--grid",
            "60",
        ],
    ),
];

#[test]
fn default_pictures_are_the_recorded_bytes() {
    let Some(mesh) = data("meshes/bob_small.ply") else {
        return;
    };
    let Some(teapot) = data("surfaces/teapot.json") else {
        return;
    };
    let dir = tmp("zebra-fingerprints");
    let mut failures = Vec::new();
    for (name, recorded, args) in FINGERPRINTS {
        let args: Vec<String> = args
            .iter()
            .map(|a| {
                a.replace("{M}", s(&mesh))
                    .replace("{T}", s(&teapot))
                    .replace("{D}", s(&dir))
            })
            .collect();
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        ok(&run(&args));
        let png = args[args.iter().position(|a| *a == "--png").unwrap() + 1];
        let bytes = std::fs::read(png).unwrap();
        assert!(Image::decode_png(&bytes).is_ok(), "{name}: not a PNG");
        let got = fnv1a(&bytes);
        if got != *recorded {
            failures.push(format!("{name}: {got:#018x}, recorded {recorded:#018x}"));
        }
    }
    if !same_simd_as_recorded() {
        eprintln!(
            "note: fingerprints recorded with AVX-512: hashes not compared on this CPU ({} differ)",
            failures.len()
        );
        return;
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The part and its dark pixels in a picture (its left panel when
/// `left_half`): the part is the largest 8-connected piece of pixels that
/// differ from the background (the most frequent colour), the key's panel
/// left out; dark is a channel sum under 270.
struct Masks {
    w: usize,
    h: usize,
    part: Vec<bool>,
    dark: Vec<bool>,
}

fn masks(path: &Path, left_half: bool) -> Masks {
    let img = Image::decode_png(&std::fs::read(path).unwrap()).unwrap();
    let (w, h) = (img.width as usize, img.height as usize);
    let w = if left_half { w / 2 - 4 } else { w };
    let px = |i: usize| img.get((i % w) as u32, (i / w) as u32).unwrap();
    let mut count = std::collections::HashMap::new();
    for i in 0..w * h {
        *count.entry(px(i)).or_insert(0usize) += 1;
    }
    let bg = count
        .into_iter()
        .max_by_key(|&(c, n)| (n, c))
        .map(|(c, _)| c)
        .unwrap();
    let mut raw: Vec<bool> = (0..w * h)
        .map(|i| (0..3).any(|k| px(i)[k].abs_diff(bg[k]) > 3))
        .collect();
    // the key's light panel (it may touch the part): its bounding box out
    let panel: Vec<bool> = (0..w * h).map(|i| px(i)[..3] == [250, 250, 250]).collect();
    let (label, sizes) = pieces(&panel, w, h);
    if let Some(k) = (0..sizes.len())
        .filter(|&k| sizes[k] >= 200)
        .max_by_key(|&k| sizes[k])
    {
        let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
        for i in (0..w * h).filter(|&i| label[i] as usize == k + 1) {
            let (x, y) = (i % w, i / w);
            (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
        }
        for y in y0..=y1 {
            for x in x0..=x1 {
                raw[y * w + x] = false;
            }
        }
    }
    let (label, sizes) = pieces(&raw, w, h);
    let best = (0..sizes.len()).max_by_key(|&k| sizes[k]).unwrap();
    let part: Vec<bool> = label.iter().map(|&l| l as usize == best + 1).collect();
    let dark = (0..w * h)
        .map(|i| {
            let c = px(i);
            part[i] && (c[0] as u32 + c[1] as u32 + c[2] as u32) < 3 * 90
        })
        .collect();
    Masks { w, h, part, dark }
}

/// 8-connected pieces of `mask`: a label per pixel (0 = not in the mask)
/// and the pieces' sizes (index = label − 1).
fn pieces(mask: &[bool], w: usize, h: usize) -> (Vec<u32>, Vec<usize>) {
    let mut label = vec![0u32; mask.len()];
    let mut sizes = Vec::new();
    let mut stack = Vec::new();
    for start in 0..mask.len() {
        if !mask[start] || label[start] != 0 {
            continue;
        }
        sizes.push(0);
        let l = sizes.len() as u32;
        label[start] = l;
        stack.push(start);
        while let Some(i) = stack.pop() {
            sizes[l as usize - 1] += 1;
            let (x, y) = ((i % w) as i64, (i / w) as i64);
            for (dx, dy) in (-1..=1).flat_map(|dy| (-1..=1).map(move |dx| (dx, dy))) {
                let (nx, ny) = (x + dx, y + dy);
                if nx < 0 || ny < 0 || nx >= w as i64 || ny >= h as i64 {
                    continue;
                }
                let j = ny as usize * w + nx as usize;
                if mask[j] && label[j] == 0 {
                    label[j] = l;
                    stack.push(j);
                }
            }
        }
    }
    (label, sizes)
}

/// Share of the part's pixels within [`NEAR_PX`] of a dark pixel, and share
/// of the dark pixels in pieces of fewer than 15 pixels.
fn stripe_measures(m: &Masks) -> (f64, f64) {
    let big = i64::MAX / 4;
    let mut d: Vec<i64> = m.dark.iter().map(|&l| if l { 0 } else { big }).collect();
    let (w, h) = (m.w as i64, m.h as i64);
    let at = |x: i64, y: i64| (y * w + x) as usize;
    for y in 0..h {
        for x in 0..w {
            let mut v = d[at(x, y)];
            for (dx, dy) in [(-1, 0), (0, -1), (-1, -1), (1, -1)] {
                let (nx, ny) = (x + dx, y + dy);
                if nx >= 0 && ny >= 0 && nx < w {
                    v = v.min(d[at(nx, ny)] + 1);
                }
            }
            d[at(x, y)] = v;
        }
    }
    for y in (0..h).rev() {
        for x in (0..w).rev() {
            let mut v = d[at(x, y)];
            for (dx, dy) in [(1, 0), (0, 1), (1, 1), (-1, 1)] {
                let (nx, ny) = (x + dx, y + dy);
                if nx >= 0 && ny < h && nx < w {
                    v = v.min(d[at(nx, ny)] + 1);
                }
            }
            d[at(x, y)] = v;
        }
    }
    let part: Vec<usize> = (0..m.part.len()).filter(|&i| m.part[i]).collect();
    let near = part.iter().filter(|&&i| d[i] <= NEAR_PX).count() as f64;
    let (label, sizes) = pieces(&m.dark, m.w, m.h);
    let dark = label.iter().filter(|&&l| l != 0).count() as f64;
    let specks = label
        .iter()
        .filter(|&&l| l != 0 && sizes[l as usize - 1] < 15)
        .count() as f64;
    (
        near / part.len().max(1) as f64,
        if dark > 0.0 { specks / dark } else { 1.0 },
    )
}

/// The part's silhouette cropped to its bounding box, resampled to 64 × 64.
fn normalised(m: &Masks) -> Vec<bool> {
    let (mut x0, mut y0, mut x1, mut y1) = (m.w, m.h, 0, 0);
    for i in (0..m.part.len()).filter(|&i| m.part[i]) {
        let (x, y) = (i % m.w, i / m.w);
        (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
    }
    let n = 64;
    (0..n * n)
        .map(|k| {
            let (u, v) = ((k % n) as f64 + 0.5, (k / n) as f64 + 0.5);
            let x = x0 + ((u / n as f64) * (x1 + 1 - x0) as f64) as usize;
            let y = y0 + ((v / n as f64) * (y1 + 1 - y0) as f64) as usize;
            m.part[y.min(m.h - 1) * m.w + x.min(m.w - 1)]
        })
        .collect()
}

fn iou(a: &[bool], b: &[bool]) -> f64 {
    let i = a.iter().zip(b).filter(|(x, y)| **x && **y).count() as f64;
    let u = a.iter().zip(b).filter(|(x, y)| **x || **y).count() as f64;
    if u > 0.0 { i / u } else { 0.0 }
}

#[test]
fn zebra_pictures_of_every_command_reach_the_part_without_specks_from_one_camera() {
    let Some(mesh) = data("meshes/spot.ply") else {
        return;
    };
    let dir = tmp("zebra-commands");
    let d = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let m = s(&mesh);
    let size = ["--size", "480x360"];
    // (name, arguments, left panel only)
    let runs: Vec<(&str, Vec<String>, bool)> = vec![
        ("render", vec!["render".into(), m.into()], false),
        (
            "highlight",
            vec!["highlight".into(), m.into(), "-o".into(), d("l.json")],
            false,
        ),
        (
            "detect",
            vec!["detect".into(), m.into(), "-o".into(), d("r.json")],
            false,
        ),
        (
            "section",
            [
                "section",
                m,
                "--plane-point",
                "0,0,0",
                "--plane-normal",
                "0,0,1",
            ]
            .map(String::from)
            .into(),
            false,
        ),
        (
            "smooth",
            ["smooth", m, "--iterations", "1", "-o", &d("s.ply")]
                .map(String::from)
                .into(),
            true,
        ),
        (
            "fair",
            ["fair", m, "--auto", "-o", &d("f.ply")]
                .map(String::from)
                .into(),
            false,
        ),
    ];
    let mut failures = Vec::new();
    let mut table = String::new();
    let mut reference = None;
    for (name, args, left) in runs {
        let png = d(&format!("{name}.png"));
        let report = d(&format!("{name}.json"));
        let mut args: Vec<&str> = args.iter().map(String::as_str).collect();
        args.extend(["--png", &png, "--zebra", "--report", &report]);
        if !matches!(name, "smooth" | "fair") {
            args.extend(size);
        }
        ok(&run(&args));
        let period = json(Path::new(&report))["zebra"]["period_deg"].as_f64();
        let masks = masks(Path::new(&png), left);
        let (reach, specks) = stripe_measures(&masks);
        let silhouette = normalised(&masks);
        let agree = iou(
            reference.get_or_insert_with(|| silhouette.clone()),
            &silhouette,
        );
        table.push_str(&format!(
            "{name:10} period {period:?} reach {reach:.3} specks {specks:.3} iou(render) {agree:.3}\n"
        ));
        if !period.is_some_and(|p| p > 0.0 && p <= 180.0) {
            failures.push(format!("{name}: the report's zebra period is {period:?}"));
        }
        if reach < MIN_REACH {
            failures.push(format!(
                "{name}: zebra stripes reach {reach:.3} of the part"
            ));
        }
        if specks > MAX_SPECKS {
            failures.push(format!("{name}: specks are {specks:.3} of the dark pixels"));
        }
        if agree < MIN_IOU {
            failures.push(format!(
                "{name}: silhouette differs from render's (IoU {agree:.3})"
            ));
        }
    }
    eprintln!("{table}");
    assert!(failures.is_empty(), "{}\n{table}", failures.join("\n"));
}
