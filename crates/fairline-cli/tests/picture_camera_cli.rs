//! The pictures of a part, measured from their pixels: every real mesh of
//! ../shared/data/meshes (the two dirty ones repaired first) and two
//! generated shapes (a torus and a blob) drawn by `render`, `highlight`,
//! `render --scalar mean` and `smooth --png` (its input's panel) with no
//! view option.
//!
//! - the part covers a reasonable share of the frame;
//! - one camera: the silhouettes of the three pictures, each cropped to
//!   its bounding box, agree (intersection over union);
//! - upright: the up axis the report gives is the part's known up;
//! - the highlight lines cross most of the part (share of part pixels
//!   within a few pixels of a line) and isolated specks are a small share
//!   of the line pixels;
//! - so do the dark stripes of `render --zebra` (the reflection zebra,
//!   default period), seen from the same camera.

mod common;
use common::*;

use fairline::render::Image;
use std::path::{Path, PathBuf};

/// Side of the pictures (small: the measures are about shares of pixels).
const SIZE: &str = "480x360";
/// Smallest share of the frame the part's silhouette covers.
const MIN_COVER: f64 = 0.12;
/// Smallest intersection over union of two commands' normalised silhouettes.
const MIN_IOU: f64 = 0.85;
/// Smallest share of the part's pixels within [`NEAR_LINE_PX`] of a line.
const MIN_LINE_REACH: f64 = 0.4;
/// Distance (pixels) at which a part pixel counts as near a line.
const NEAR_LINE_PX: i64 = 12;
/// Largest share of the line pixels in specks (pieces under 15 pixels).
const MAX_SPECKS: f64 = 0.25;

/// The pixels of a picture: part mask, line mask, width and height.
struct Masks {
    w: usize,
    h: usize,
    part: Vec<bool>,
    line: Vec<bool>,
}

/// The masks of the picture in `path`; `left_half`: of its left half only
/// (the input's panel of a before | after picture).
fn masks(path: &Path, left_half: bool) -> Masks {
    let img = Image::decode_png(&std::fs::read(path).unwrap()).unwrap();
    let (w, h) = (img.width as usize, img.height as usize);
    let w = if left_half { w / 2 - 4 } else { w };
    let px = |x: usize, y: usize| img.get(x as u32, y as u32).unwrap();
    // the background: the most frequent colour (the part is shaded)
    let mut count = std::collections::HashMap::new();
    for i in 0..w * h {
        *count.entry(px(i % w, i / w)).or_insert(0usize) += 1;
    }
    let bg = count
        .into_iter()
        .max_by_key(|&(c, n)| (n, c))
        .map(|(c, _)| c)
        .unwrap();
    let differs = |c: [u8; 4]| (0..3).any(|k| c[k].abs_diff(bg[k]) > 3);
    let mut raw: Vec<bool> = (0..w * h).map(|i| differs(px(i % w, i / w))).collect();
    // the key of a highlight picture (a light panel that may touch the
    // part): the bounding box of its panel colour is left out
    let panel: Vec<bool> = (0..w * h)
        .map(|i| px(i % w, i / w)[..3] == [250, 250, 250])
        .collect();
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
    // the part: the largest 8-connected piece that is not background (the
    // title, the key and the legend are pieces of their own)
    let part = largest_piece(&raw, w, h);
    let line: Vec<bool> = (0..w * h)
        .map(|i| {
            let c = px(i % w, i / w);
            part[i] && (c[0] as u32 + c[1] as u32 + c[2] as u32) < 3 * 90
        })
        .collect();
    Masks { w, h, part, line }
}

/// 8-connected pieces of `mask` (label per pixel, 0 = not in the mask) and
/// their sizes (index = label − 1).
fn pieces(mask: &[bool], w: usize, h: usize) -> (Vec<u32>, Vec<usize>) {
    let mut label = vec![0u32; mask.len()];
    let mut sizes = Vec::new();
    let mut stack = Vec::new();
    for s in 0..mask.len() {
        if !mask[s] || label[s] != 0 {
            continue;
        }
        sizes.push(0);
        let l = sizes.len() as u32;
        label[s] = l;
        stack.push(s);
        while let Some(i) = stack.pop() {
            sizes[l as usize - 1] += 1;
            let (x, y) = ((i % w) as i64, (i / w) as i64);
            for dy in -1..=1 {
                for dx in -1..=1 {
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
    }
    (label, sizes)
}

fn largest_piece(mask: &[bool], w: usize, h: usize) -> Vec<bool> {
    let (label, sizes) = pieces(mask, w, h);
    let Some(best) = (0..sizes.len()).max_by_key(|&k| sizes[k]) else {
        return vec![false; mask.len()];
    };
    label.iter().map(|&l| l as usize == best + 1).collect()
}

fn share(m: &[bool]) -> f64 {
    m.iter().filter(|&&b| b).count() as f64 / m.len() as f64
}

/// The mask cropped to its bounding box and resampled to 64 × 64 (the
/// silhouette's shape, whatever the framing).
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

/// Share of the part pixels within [`NEAR_LINE_PX`] of a line pixel and
/// share of the line pixels in pieces of fewer than 15 pixels.
fn line_measures(m: &Masks) -> (f64, f64) {
    // distance to the nearest line pixel by two passes of a chamfer sweep
    let big = i64::MAX / 4;
    let mut d: Vec<i64> = m.line.iter().map(|&l| if l { 0 } else { big }).collect();
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
    let near = part.iter().filter(|&&i| d[i] <= NEAR_LINE_PX).count() as f64;
    let (label, sizes) = pieces(&m.line, m.w, m.h);
    let lines = label.iter().filter(|&&l| l != 0).count() as f64;
    let specks = label
        .iter()
        .filter(|&&l| l != 0 && sizes[l as usize - 1] < 15)
        .count() as f64;
    (
        near / part.len().max(1) as f64,
        if lines > 0.0 { specks / lines } else { 1.0 },
    )
}

/// The parts: (name, file, known up axis). The animals and scans are
/// modelled y-up; lego_open is a flat sheet in the xz plane, its normals
/// along +y (its face is seen from above).
fn parts(dir: &Path) -> Vec<(String, PathBuf, [f64; 3])> {
    let mut out = Vec::new();
    for (name, up, dirty) in [
        ("spot.ply", [0.0, 1.0, 0.0], false),
        ("bunny_npm.obj", [0.0, 1.0, 0.0], false),
        ("bob_small.ply", [0.0, 1.0, 0.0], false),
        ("bunny_zipper.ply", [0.0, 1.0, 0.0], false),
        ("lego_open.ply", [0.0, 1.0, 0.0], false),
        ("bunny_res4.ply", [0.0, 1.0, 0.0], true),
        ("elephant_nonmanifold.obj", [0.0, 1.0, 0.0], true),
    ] {
        let Some(src) = data(&format!("meshes/{name}")) else {
            continue;
        };
        let file = if dirty {
            let fixed = dir.join(format!("repaired-{name}"));
            ok(&run(&["repair", s(&src), s(&fixed)]));
            fixed
        } else {
            src
        };
        out.push((name.to_string(), file, up));
    }
    let torus = dir.join("torus.obj");
    fairline::io::write_mesh(&torus, &fairline::shapes::torus(1.0, 0.35, 64, 24)).unwrap();
    out.push(("torus".into(), torus, [0.0, 0.0, 1.0]));
    let mut blob = fairline::shapes::icosphere(1.0, 4);
    let moved: Vec<fairline::Vec3> = blob
        .positions()
        .iter()
        .map(|p| {
            let r = 1.0 + 0.25 * (3.0 * p.x).sin() * (2.0 * p.y).cos() + 0.15 * p.z * p.z;
            *p * r * fairline::Vec3::new(1.4, 1.0, 0.8)
        })
        .collect();
    blob.set_positions(moved).unwrap();
    let blob_file = dir.join("blob.obj");
    fairline::io::write_mesh(&blob_file, &blob).unwrap();
    out.push(("blob".into(), blob_file, [0.0, 0.0, 1.0]));
    out
}

#[test]
fn every_picture_of_a_part_shows_it_upright_from_one_camera_with_readable_lines() {
    let dir = tmp("picture-camera");
    let mut failures = Vec::new();
    let mut table = String::new();
    for (name, file, up) in parts(&dir) {
        let png = |cmd: &str| dir.join(format!("{name}-{cmd}.png"));
        let report = |cmd: &str| dir.join(format!("{name}-{cmd}.json"));
        ok(&run(&[
            "render",
            s(&file),
            "--png",
            s(&png("render")),
            "--size",
            SIZE,
            "--report",
            s(&report("render")),
        ]));
        ok(&run(&[
            "highlight",
            s(&file),
            "-o",
            s(&dir.join(format!("{name}-lines.json"))),
            "--png",
            s(&png("highlight")),
            "--size",
            SIZE,
            "--report",
            s(&report("highlight")),
        ]));
        ok(&run(&[
            "render",
            s(&file),
            "--scalar",
            "mean",
            "--png",
            s(&png("mean")),
            "--size",
            SIZE,
        ]));
        ok(&run(&[
            "smooth",
            s(&file),
            "-o",
            s(&dir.join(format!("{name}-smooth.ply"))),
            "--iterations",
            "1",
            "--png",
            s(&png("smooth")),
        ]));
        ok(&run(&[
            "render",
            s(&file),
            "--zebra",
            "--png",
            s(&png("zebra")),
            "--size",
            SIZE,
        ]));
        let m: Vec<Masks> = ["render", "highlight", "mean", "smooth", "zebra"]
            .iter()
            .map(|c| masks(&png(c), *c == "smooth"))
            .collect();
        let cover = share(&m[0].part);
        let n: Vec<Vec<bool>> = m.iter().map(normalised).collect();
        let (iou_h, iou_d) = (iou(&n[0], &n[1]), iou(&n[0], &n[2]));
        let iou_s = iou(&n[0], &n[3]);
        let (reach, specks) = line_measures(&m[1]);
        let iou_z = iou(&n[0], &n[4]);
        let (zebra_reach, zebra_specks) = line_measures(&m[4]);
        let reported: Vec<f64> = json(&report("render"))["view"]["up"]
            .as_array()
            .map(|a| a.iter().filter_map(|v| v.as_f64()).collect())
            .unwrap_or_default();
        let upright =
            reported.len() == 3 && reported.iter().zip(up).map(|(a, b)| a * b).sum::<f64>() > 0.95;
        table.push_str(&format!(
            "{name:26} cover {cover:.3} iou(render,highlight) {iou_h:.3} iou(render,mean curvature) {iou_d:.3} iou(render,smooth) {iou_s:.3} line reach {reach:.3} specks {specks:.3} zebra: iou {iou_z:.3} reach {zebra_reach:.3} specks {zebra_specks:.3} up {reported:?}\n"
        ));
        if cover < MIN_COVER {
            failures.push(format!("{name}: the part covers {cover:.3} of the frame"));
        }
        if iou_h < MIN_IOU || iou_d < MIN_IOU || iou_s < MIN_IOU || iou_z < MIN_IOU {
            failures.push(format!(
                "{name}: silhouettes differ between commands (IoU {iou_h:.3}, {iou_d:.3}, {iou_s:.3}, {iou_z:.3})"
            ));
        }
        if zebra_reach < MIN_LINE_REACH {
            failures.push(format!(
                "{name}: zebra stripes reach {zebra_reach:.3} of the part"
            ));
        }
        if zebra_specks > MAX_SPECKS {
            failures.push(format!(
                "{name}: specks are {zebra_specks:.3} of the zebra's dark pixels"
            ));
        }
        if !upright {
            failures.push(format!("{name}: up {reported:?}, the part's up is {up:?}"));
        }
        if reach < MIN_LINE_REACH {
            failures.push(format!("{name}: lines reach {reach:.3} of the part"));
        }
        if specks > MAX_SPECKS {
            failures.push(format!("{name}: specks are {specks:.3} of the line pixels"));
        }
    }
    eprintln!("{table}");
    assert!(failures.is_empty(), "{}\n{table}", failures.join("\n"));
}
