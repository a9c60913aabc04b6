//! Renderer integration tests; `sample_pictures` also writes the pictures to
//! `$TMPDIR/render-samples/` for a visual check.

use fairline::Vec3;
use fairline::render::*;
use std::f64::consts::PI;

type Mesh = (Vec<Vec3>, Vec<Vec3>, Vec<[u32; 3]>);

/// A grid surface `f(i/nu, j/nv) -> (position, normal)` with CCW triangles.
fn grid(
    nu: u32,
    nv: u32,
    wrap_u: bool,
    wrap_v: bool,
    f: impl Fn(f64, f64) -> (Vec3, Vec3),
) -> Mesh {
    let (cu, cv) = (
        if wrap_u { nu } else { nu + 1 },
        if wrap_v { nv } else { nv + 1 },
    );
    let mut p = Vec::new();
    let mut n = Vec::new();
    for j in 0..cv {
        for i in 0..cu {
            let (q, m) = f(i as f64 / nu as f64, j as f64 / nv as f64);
            p.push(q);
            n.push(m);
        }
    }
    let id = |i: u32, j: u32| (j % cv) * cu + (i % cu);
    let mut t = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            t.push([a, b, c]);
            t.push([a, c, d]);
        }
    }
    (p, n, t)
}

fn sphere(c: Vec3, r: f64, nu: u32, nv: u32) -> Mesh {
    grid(nu, nv, true, false, |u, v| {
        let (phi, theta) = (2.0 * PI * u, PI * (1.0 - v));
        let d = Vec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        );
        (c + d * r, d)
    })
}

fn torus(c: Vec3, big: f64, small: f64, nu: u32, nv: u32) -> Mesh {
    grid(nu, nv, true, true, |u, v| {
        let (a, b) = (2.0 * PI * u, 2.0 * PI * v);
        let d = Vec3::new(b.cos() * a.cos(), b.cos() * a.sin(), b.sin());
        let ring = Vec3::new(a.cos(), a.sin(), 0.0) * big;
        (c + ring + d * small, d)
    })
}

fn height(x: f64, y: f64) -> f64 {
    0.12 * (3.0 * x).sin() * (2.0 * y).cos() + 0.05 * x * x - 0.04 * y
}

fn panel(n: u32) -> Mesh {
    grid(n, n * 3 / 4, false, false, |u, v| {
        let (x, y) = (-2.0 + 4.0 * u, -1.5 + 3.0 * v);
        let h = 1e-5;
        let dx = (height(x + h, y) - height(x - h, y)) / (2.0 * h);
        let dy = (height(x, y + h) - height(x, y - h)) / (2.0 * h);
        (
            Vec3::new(x, y, height(x, y)),
            Vec3::new(-dx, -dy, 1.0).normalize(),
        )
    })
}

fn out_dir() -> std::path::PathBuf {
    let dir = std::env::temp_dir().join("render-samples");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn render_sample_pictures() {
    let dir = out_dir();

    // 1. Sphere + torus with a signed scalar field (Gaussian curvature of the torus).
    let (sp, sn, st) = sphere(Vec3::new(-2.2, 0.0, 0.0), 1.0, 96, 48);
    let (tp, tn, tt) = torus(Vec3::new(1.4, 0.0, 0.0), 1.3, 0.45, 128, 48);
    let gauss: Vec<f64> = tn
        .iter()
        .zip(&tp)
        .map(|(n, p)| {
            let cos_b = (Vec3::new(p.x - 1.4, p.y, 0.0).length() - 1.3) / 0.45;
            let _ = n;
            cos_b / (0.45 * (1.3 + 0.45 * cos_b))
        })
        .collect();
    let (tc, (lo, hi)) = scalar_colors(&gauss, Colormap::Coolwarm, None);
    let sphere_vals = vec![1.0; sp.len()];
    let (sc, _) = scalar_colors(&sphere_vals, Colormap::Coolwarm, Some((lo, hi)));
    let scene = Scene {
        meshes: vec![
            MeshLayer::new(&sp, &st).with_normals(&sn).with_colors(&sc),
            MeshLayer::new(&tp, &tt).with_normals(&tn).with_colors(&tc),
        ],
        legend: Some(Legend {
            title: "Gauss K (1/m^2)".into(),
            colormap: Colormap::Coolwarm,
            min: lo,
            max: hi,
            clipped: false,
        }),
        title: Some("sphere + torus: Gaussian curvature".into()),
        ..Default::default()
    };
    let opts = RenderOptions::with_size(960, 600).view_dir(Vec3::new(0.2, 1.0, -0.6));
    let curv = render(&scene, &opts).unwrap();
    curv.write_png(dir.join("sphere_torus_coolwarm.png"))
        .unwrap();

    // 2. Wavy panel with polylines (stand-ins for highlight lines) on it.
    let (pp, pn, pt) = panel(160);
    let lines: Vec<PolylineLayer> = (0..9)
        .map(|k| {
            let y = -1.2 + 0.3 * k as f64;
            PolylineLayer {
                points: (0..=200)
                    .map(|i| {
                        let x = -2.0 + 4.0 * i as f64 / 200.0;
                        let yy = y + 0.1 * (2.0 * x).sin();
                        Vec3::new(x, yy, height(x, yy))
                    })
                    .collect(),
                closed: false,
                color: if k == 4 {
                    [0.9, 0.05, 0.02]
                } else {
                    [0.02, 0.02, 0.02]
                },
                width_px: 2.0,
            }
        })
        .collect();
    let scene = Scene {
        meshes: vec![
            MeshLayer::new(&pp, &pt)
                .with_normals(&pn)
                .with_base_color([0.25, 0.32, 0.45]),
        ],
        polylines: lines,
        points: vec![PointMarker {
            position: Vec3::new(0.0, 0.0, height(0.0, 0.0)),
            color: [1.0, 0.8, 0.0],
            radius_px: 5.0,
        }],
        title: Some("panel with highlight-like lines".into()),
        ..Default::default()
    };
    let opts = RenderOptions::with_size(960, 640).view_dir(Vec3::new(-0.4, 1.0, -0.7));
    let panel_img = render(&scene, &opts).unwrap();
    panel_img.write_png(dir.join("panel_lines.png")).unwrap();
    // Close-up of the same scene: line anti-aliasing, joins and depth test.
    let c0 = Vec3::new(0.0, 0.0, height(0.0, 0.0));
    let close = opts
        .clone()
        .width(320)
        .height(240)
        .camera(Some(Camera::framing(
            c0 - Vec3::splat(0.25),
            c0 + Vec3::splat(0.25),
            opts.view_dir,
            opts.up,
            4.0 / 3.0,
        )));
    let closeup = render(&scene, &close).unwrap();
    closeup.write_png(dir.join("panel_closeup.png")).unwrap();

    // 3. Wireframe of a coarse torus and panel, plus one-sided back faces.
    let (cp, cn, ct) = torus(Vec3::ZERO, 1.0, 0.4, 36, 14);
    let scene = Scene {
        meshes: vec![
            MeshLayer::new(&cp, &ct)
                .with_normals(&cn)
                .with_wireframe([0.02, 0.02, 0.05])
                .with_base_color([0.7, 0.55, 0.3]),
        ],
        title: Some("wireframe, smooth shading".into()),
        ..Default::default()
    };
    let opts = RenderOptions::with_size(800, 600).view_dir(Vec3::new(0.3, 1.0, -0.9));
    let wire = render(&scene, &opts).unwrap();
    wire.write_png(dir.join("wireframe.png")).unwrap();
    let flat = Scene {
        meshes: vec![MeshLayer::new(&cp, &ct).with_wireframe([0.0; 3])],
        title: Some("flat, orthographic".into()),
        ..Default::default()
    };
    let ortho = render(&flat, &opts.clone().orthographic(true)).unwrap();

    // 4. Side by side with labels.
    let both = side_by_side(
        &[wire.clone(), ortho],
        &["before: perspective", "after: ortho (x=1.5e-3)"],
    );
    both.write_png(dir.join("side_by_side.png")).unwrap();

    // 4b. Small picture, view parallel to the up hint, sequential map with legend.
    let (hp, hn, ht) = panel(60);
    let z: Vec<f64> = hp.iter().map(|p| p.z).collect();
    let (hc, (zl, zh)) = scalar_colors(&z, Colormap::Viridis, None);
    let scene = Scene {
        meshes: vec![MeshLayer::new(&hp, &ht).with_normals(&hn).with_colors(&hc)],
        legend: Some(Legend {
            title: "height".into(),
            colormap: Colormap::Viridis,
            min: zl,
            max: zh,
            clipped: false,
        }),
        title: Some("top view".into()),
        ..Default::default()
    };
    let small = render(
        &scene,
        &RenderOptions::with_size(400, 300)
            .view_dir(Vec3::NEG_Z)
            .up(Vec3::Z),
    )
    .unwrap();
    small.write_png(dir.join("small_top_view.png")).unwrap();

    // 5. Font sheet.
    let mut sheet = Image::new(620, 130, [255, 255, 255, 255]);
    let chars: String = (32u8..=126).map(|c| c as char).collect();
    for (i, chunk) in chars.as_bytes().chunks(32).enumerate() {
        let line = std::str::from_utf8(chunk).unwrap();
        sheet.draw_text(10, 10 + 30 * i as i64, line, [0, 0, 0, 255], 3);
    }
    sheet.draw_text(
        10,
        100,
        "k1 = -1.25e-3 (mm)/[x] +0.5 E:2",
        [180, 0, 0, 255],
        2,
    );
    sheet.write_png(dir.join("font.png")).unwrap();

    // 6. SVG plot.
    let mut plot = SvgPlot::new(500, 400, (0.0, 1.0), (0.0, 1.0));
    plot.axes("u", "v")
        .title("pre-images")
        .polyline(
            &(0..=50)
                .map(|i| {
                    let u = i as f64 / 50.0;
                    [u, 0.5 + 0.3 * (6.0 * u).sin()]
                })
                .collect::<Vec<_>>(),
            [200, 30, 30],
            1.5,
        )
        .marker([0.5, 0.5], [0, 0, 200], "P");
    plot.write(dir.join("plot.svg")).unwrap();

    for name in [
        "sphere_torus_coolwarm.png",
        "panel_lines.png",
        "wireframe.png",
        "side_by_side.png",
        "font.png",
    ] {
        let bytes = std::fs::read(dir.join(name)).unwrap();
        let img = Image::decode_png(&bytes).unwrap();
        assert!(img.width > 0 && img.height > 0);
    }
}

#[test]
fn render_png_file_decodes_with_the_right_size() {
    let (p, n, t) = sphere(Vec3::ZERO, 1.0, 32, 16);
    let scene = Scene {
        meshes: vec![MeshLayer::new(&p, &t).with_normals(&n)],
        ..Default::default()
    };
    let img = render(&scene, &RenderOptions::with_size(123, 77)).unwrap();
    let path = out_dir().join("decode_check.png");
    img.write_png(&path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (123, 77));
    assert_eq!(info.color_type, png::ColorType::Rgba);
    assert_eq!(&buf[..info.buffer_size()], img.pixels.concat().as_slice());
}

#[test]
fn render_write_png_to_missing_directory_is_an_error() {
    let img = Image::new(2, 2, [0, 0, 0, 255]);
    let err = img
        .write_png("/nonexistent-dir-fairline/x.png")
        .unwrap_err();
    assert!(matches!(err, RenderError::Io { .. }));
}

#[test]
fn render_panel_seen_from_behind_is_drawn() {
    // One-sided layers show back faces in a dark colour; two-sided ones shade them.
    let (p, n, t) = panel(20);
    for two_sided in [false, true] {
        let scene = Scene {
            meshes: vec![
                MeshLayer::new(&p, &t)
                    .with_normals(&n)
                    .with_two_sided(two_sided),
            ],
            ..Default::default()
        };
        let mut opts = RenderOptions::with_size(100, 80);
        opts.view_dir = Vec3::new(0.0, 0.3, 1.0);
        let img = render(&scene, &opts).unwrap();
        let c = img.get(50, 40).unwrap();
        if two_sided {
            assert!(c[0] > 80 && (c[0] as i32 - c[2] as i32).abs() < 15, "{c:?}");
        } else {
            assert!(c[0] < 140 && c[0] as i32 > c[2] as i32 + 15, "{c:?}");
        }
    }
}
