//! Unit tests of the renderer on procedural fixtures.

use super::*;

/// A UV sphere of radius `r` at `c`: positions, outward normals, CCW triangles.
pub(crate) fn uv_sphere(
    c: Vec3,
    r: f64,
    nu: u32,
    nv: u32,
) -> (Vec<Vec3>, Vec<Vec3>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    let mut n = Vec::new();
    for j in 0..=nv {
        let theta = std::f64::consts::PI * j as f64 / nv as f64;
        for i in 0..nu {
            let phi = 2.0 * std::f64::consts::PI * i as f64 / nu as f64;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            p.push(c + d * r);
            n.push(d);
        }
    }
    let mut t = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let a = j * nu + i;
            let b = j * nu + (i + 1) % nu;
            let cc = a + nu;
            let d = b + nu;
            // Theta grows downwards from the north pole; this order is CCW outside.
            t.push([a, cc, d]);
            t.push([a, d, b]);
        }
    }
    (p, n, t)
}

fn is_bg(img: &Image, x: u32, y: u32, bg: [u8; 4]) -> bool {
    img.get(x, y).unwrap() == bg
}

fn sphere_opts(w: u32, h: u32) -> RenderOptions {
    RenderOptions {
        width: w,
        height: h,
        supersample: 2,
        view_dir: Vec3::new(-1.0, 0.3, -0.4),
        ..Default::default()
    }
}

#[test]
fn sphere_covers_expected_fraction_and_is_centred() {
    let p0 = Vec3::new(3.0, -2.0, 1.0);
    let (p, n, t) = uv_sphere(p0, 1.0, 96, 48);
    let scene = Scene {
        meshes: vec![MeshLayer::new(&p, &t).with_normals(&n)],
        ..Default::default()
    };
    let opts = sphere_opts(200, 160);
    let img = render(&scene, &opts).unwrap();
    let bg = linear_to_srgb8(opts.background);
    let (mut count, mut sx, mut sy) = (0usize, 0.0, 0.0);
    for y in 0..img.height {
        for x in 0..img.width {
            if !is_bg(&img, x, y, bg) {
                count += 1;
                sx += x as f64 + 0.5;
                sy += y as f64 + 0.5;
            }
        }
    }
    let frac = count as f64 / (200.0 * 160.0);
    // The view is tightened to the object: the silhouette (a circle, seen
    // from the front it is a disc) then touches the 6% margin in the
    // narrower (vertical) direction: radius 0.94 * 80 px.
    let r_img = (frac * 200.0 * 160.0 / std::f64::consts::PI).sqrt();
    assert!(
        (r_img - 0.94 * 80.0).abs() < 2.0,
        "disc radius {r_img} (fraction {frac})"
    );
    let (cx, cy) = (sx / count as f64, sy / count as f64);
    assert!(
        (cx - 100.0).abs() < 1.5 && (cy - 80.0).abs() < 1.5,
        "centre {cx} {cy}"
    );
}

#[test]
fn lit_side_is_brighter_than_shadow_side() {
    let (p, n, t) = uv_sphere(Vec3::ZERO, 1.0, 48, 24);
    let scene = Scene {
        meshes: vec![MeshLayer::new(&p, &t).with_normals(&n)],
        ..Default::default()
    };
    let img = render(&scene, &sphere_opts(160, 160)).unwrap();
    // Key light is upper left (camera space), so upper-left of the disc is brighter.
    let ul = img.get(62, 62).unwrap();
    let lr = img.get(98, 98).unwrap();
    assert!(ul[0] as i32 > lr[0] as i32 + 30, "{ul:?} vs {lr:?}");
}

#[test]
fn render_is_deterministic_across_runs_and_thread_counts() {
    let (p, n, t) = uv_sphere(Vec3::ZERO, 1.0, 40, 20);
    let values: Vec<f64> = p.iter().map(|q| q.x * q.y).collect();
    let (colors, (lo, hi)) = scalar_colors(&values, Colormap::Coolwarm, None);
    let scene = Scene {
        meshes: vec![
            MeshLayer::new(&p, &t)
                .with_normals(&n)
                .with_colors(&colors)
                .with_wireframe([0.0; 3]),
        ],
        polylines: vec![PolylineLayer {
            points: (0..50)
                .map(|i| Vec3::new((i as f64 * 0.13).cos(), (i as f64 * 0.13).sin(), 0.0) * 1.001)
                .collect(),
            closed: true,
            color: [0.0, 0.0, 0.0],
            width_px: 2.0,
        }],
        legend: Some(Legend {
            title: "xy".into(),
            colormap: Colormap::Coolwarm,
            min: lo,
            max: hi,
            clipped: false,
        }),
        title: Some("determinism".into()),
        ..Default::default()
    };
    let opts = RenderOptions::with_size(240, 190);
    let a = render(&scene, &opts).unwrap().encode_png();
    let b = render(&scene, &opts).unwrap().encode_png();
    assert_eq!(a, b);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let c = pool.install(|| render(&scene, &opts).unwrap().encode_png());
    assert_eq!(a, c);
    let pool3 = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap();
    let d = pool3.install(|| render(&scene, &opts).unwrap().encode_png());
    assert_eq!(a, d);
}

#[test]
fn polyline_behind_object_is_hidden_and_in_front_is_visible() {
    let (p, n, t) = uv_sphere(Vec3::ZERO, 1.0, 48, 24);
    let red = [1.0, 0.0, 0.0];
    // Looking along +Y: a horizontal line across the sphere at y = +1.5
    // (behind) and one at y = -1.5 (in front), at different heights.
    let line = |y: f64, z: f64| PolylineLayer {
        points: vec![Vec3::new(-0.5, y, z), Vec3::new(0.5, y, z)],
        closed: false,
        color: red,
        width_px: 3.0,
    };
    let mut opts = RenderOptions::with_size(200, 200);
    opts.view_dir = Vec3::Y;
    opts.supersample = 2;
    let is_red = |px: [u8; 4]| px[0] > 200 && px[1] < 60 && px[2] < 60;
    for (y, visible) in [(1.5, false), (-1.5, true)] {
        let scene = Scene {
            meshes: vec![MeshLayer::new(&p, &t).with_normals(&n)],
            polylines: vec![line(y, 0.0)],
            ..Default::default()
        };
        let img = render(&scene, &opts).unwrap();
        let reds = img.pixels.iter().filter(|&&px| is_red(px)).count();
        if visible {
            assert!(
                reds > 50,
                "front line should be visible ({reds} red pixels)"
            );
        } else {
            assert_eq!(reds, 0, "back line should be hidden");
        }
    }
    // A line lying on the surface (the equator seen from above on the front half) is visible.
    let equator: Vec<Vec3> = (0..=64)
        .map(|i| {
            let a = std::f64::consts::PI * i as f64 / 64.0;
            Vec3::new(a.cos(), -a.sin(), 0.0)
        })
        .collect();
    let scene = Scene {
        meshes: vec![MeshLayer::new(&p, &t).with_normals(&n)],
        polylines: vec![PolylineLayer {
            points: equator,
            closed: false,
            color: red,
            width_px: 2.0,
        }],
        ..Default::default()
    };
    let img = render(&scene, &opts).unwrap();
    let mid_row = (90..110).flat_map(|y| (20..180).map(move |x| (x, y)));
    let reds = mid_row
        .filter(|&(x, y)| is_red(img.get(x, y).unwrap()))
        .count();
    assert!(reds > 150, "surface line visible ({reds})");
}

#[test]
fn legend_and_title_draw_in_their_strips() {
    let scene = Scene {
        legend: Some(Legend {
            title: "H".into(),
            colormap: Colormap::Viridis,
            min: -1.0,
            max: 2.5,
            clipped: false,
        }),
        title: Some("Title".into()),
        ..Default::default()
    };
    let opts = RenderOptions::with_size(400, 300);
    let img = render(&scene, &opts).unwrap();
    let bg = linear_to_srgb8(opts.background);
    let right = (300..400).flat_map(|x| (0..300).map(move |y| (x, y)));
    let legend_px = right.filter(|&(x, y)| !is_bg(&img, x, y, bg)).count();
    assert!(legend_px > 500, "legend pixels {legend_px}");
    let top = (0..400).flat_map(|x| (0..20).map(move |y| (x, y)));
    assert!(top.filter(|&(x, y)| !is_bg(&img, x, y, bg)).count() > 20);
    // The legend's bar shows both ends of the map.
    let top_colour = linear_to_srgb8(Colormap::Viridis.map(1.0));
    let low_colour = linear_to_srgb8(Colormap::Viridis.map(0.0));
    assert!(img.pixels.contains(&top_colour) && img.pixels.contains(&low_colour));
}

#[test]
fn invalid_sizes_are_errors_and_empty_scene_is_background() {
    let scene = Scene::default();
    for (w, h) in [(0, 10), (10, 0), (16385, 10), (10, 20000)] {
        let e = render(&scene, &RenderOptions::with_size(w, h));
        assert!(matches!(e, Err(RenderError::InvalidSize { .. })));
    }
    let mut opts = RenderOptions::with_size(10, 10);
    opts.supersample = 0;
    assert!(matches!(
        render(&scene, &opts),
        Err(RenderError::InvalidSupersample(0))
    ));
    let opts = RenderOptions::with_size(33, 17);
    let img = render(&scene, &opts).unwrap();
    assert_eq!((img.width, img.height), (33, 17));
    let bg = linear_to_srgb8(opts.background);
    assert!(img.pixels.iter().all(|&p| p == bg));
}

#[test]
fn degenerate_and_nan_input_does_not_panic() {
    let nan = f64::NAN;
    let p = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(nan, 0.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(f64::INFINITY, 1.0, 1.0),
        Vec3::new(1e300, -1e300, 0.0),
    ];
    let t = vec![
        [0, 1, 2],
        [0, 1, 3],
        [0, 1, 4],
        [0, 0, 0],
        [1, 2, 5],
        [0, 2, 99],
        [0, 1, 6],
    ];
    let normals = vec![Vec3::new(nan, 0.0, 0.0); 3];
    let colors = vec![[f32::NAN, 0.0, 0.0]; 7];
    let scene = Scene {
        meshes: vec![MeshLayer {
            normals: Some(&normals),
            colors: Some(&colors),
            wireframe: Some([0.0; 3]),
            two_sided: false,
            ..MeshLayer::new(&p, &t)
        }],
        polylines: vec![PolylineLayer {
            points: vec![Vec3::ZERO, Vec3::splat(nan), Vec3::ONE, Vec3::ONE],
            closed: true,
            color: [1.0, 0.0, 0.0],
            width_px: f32::NAN,
        }],
        points: vec![PointMarker {
            position: Vec3::new(0.2, 0.2, 0.0),
            color: [0.0, 0.0, 1.0],
            radius_px: 1e9,
        }],
        legend: Some(Legend {
            title: String::new(),
            colormap: Colormap::Turbo,
            min: nan,
            max: f64::INFINITY,
            clipped: false,
        }),
        title: None,
    };
    for view in [Vec3::NEG_Z, Vec3::Z, Vec3::X, Vec3::ZERO, Vec3::splat(nan)] {
        let mut opts = RenderOptions::with_size(64, 48);
        opts.view_dir = view;
        let img = render(&scene, &opts).unwrap();
        assert_eq!(img.pixels.len(), 64 * 48);
        opts.orthographic = true;
        render(&scene, &opts).unwrap();
    }
    // Camera inside the object: triangles crossing the near plane are skipped.
    let (sp, _, st) = uv_sphere(Vec3::ZERO, 1.0, 16, 8);
    let mut opts = RenderOptions::with_size(50, 50);
    opts.camera = Some(Camera::framing(
        Vec3::splat(-0.01),
        Vec3::splat(0.01),
        Vec3::X,
        Vec3::Z,
        1.0,
    ));
    render(
        &Scene {
            meshes: vec![MeshLayer::new(&sp, &st)],
            ..Default::default()
        },
        &opts,
    )
    .unwrap();
}

#[test]
fn closed_mesh_has_no_cracks() {
    // A finely tessellated sphere seen head on: no background sample may
    // show through inside the silhouette.
    let (p, n, t) = uv_sphere(Vec3::ZERO, 1.0, 97, 61);
    // Saturated colour so that no shaded sample can equal the background.
    let scene = Scene {
        meshes: vec![
            MeshLayer::new(&p, &t)
                .with_normals(&n)
                .with_base_color([1.0, 0.0, 0.0]),
        ],
        ..Default::default()
    };
    let mut opts = RenderOptions::with_size(300, 300);
    opts.supersample = 1;
    opts.view_dir = Vec3::new(0.3, 1.0, -0.2);
    let img = render(&scene, &opts).unwrap();
    let bg = linear_to_srgb8(opts.background);
    let cam = Camera::framing(
        Vec3::splat(-1.0),
        Vec3::splat(1.0),
        opts.view_dir,
        opts.up,
        1.0,
    );
    let centre = cam.project(Vec3::ZERO).unwrap();
    let (cx, cy) = ((centre.x + 1.0) * 150.0, (1.0 - centre.y) * 150.0);
    let mut holes = 0;
    for y in 0..300u32 {
        for x in 0..300u32 {
            let d = ((x as f64 + 0.5 - cx).powi(2) + (y as f64 + 0.5 - cy).powi(2)).sqrt();
            if d < 120.0 && is_bg(&img, x, y, bg) {
                holes += 1;
            }
        }
    }
    assert_eq!(holes, 0);
}

/// Two unit squares side by side in the plane z = 0 (regions 0 and 1) and a
/// small square under the first one (region 2, hidden), seen from above.
fn labelled_squares() -> (Vec<Vec3>, Vec<[u32; 3]>, RegionLabels) {
    let mut p = Vec::new();
    let mut t = Vec::new();
    let mut region = Vec::new();
    let mut square = |x0: f64, y0: f64, size: f64, z: f64, r: u32| {
        let b = p.len() as u32;
        p.extend([
            Vec3::new(x0, y0, z),
            Vec3::new(x0 + size, y0, z),
            Vec3::new(x0 + size, y0 + size, z),
            Vec3::new(x0, y0 + size, z),
        ]);
        t.push([b, b + 1, b + 2]);
        t.push([b, b + 2, b + 3]);
        region.extend([r, r]);
    };
    square(0.0, 0.0, 1.0, 0.0, 0);
    square(1.0, 0.0, 1.0, 0.0, 1);
    square(0.3, 0.3, 0.4, -0.5, 2);
    let labels = RegionLabels {
        triangle_region: region,
        texts: vec!["0".into(), "1".into(), "2".into()],
    };
    (p, t, labels)
}

#[test]
fn region_labels_sit_at_the_visible_centres_and_hidden_regions_get_none() {
    let (p, t, labels) = labelled_squares();
    let scene = Scene {
        meshes: vec![MeshLayer::new(&p, &t)],
        ..Default::default()
    };
    let opts = RenderOptions {
        width: 400,
        height: 240,
        view_dir: Vec3::new(0.0, 0.0, -1.0),
        up: Vec3::Y,
        orthographic: true,
        ..Default::default()
    };
    let plain = render(&scene, &opts).unwrap();
    let (img, placed) = render_labelled(&scene, &opts, &labels).unwrap();
    // Regions 0 and 1 are labelled, the hidden region 2 is not.
    let mut regions: Vec<u32> = placed.iter().map(|l| l.region).collect();
    regions.sort_unstable();
    assert_eq!(regions, vec![0, 1]);
    // Each anchor is the centre of its square's image (the point farthest
    // from the square's outline): the squares' images meet at the centre
    // column, so the anchors lie symmetrically about it, on one row.
    let mid = plain.width as f64 / 2.0;
    let at = |r: u32| placed.iter().find(|l| l.region == r).unwrap().anchor;
    let (a0, a1) = (at(0), at(1));
    assert!(
        (a0[0] as f64) < mid && (a1[0] as f64) > mid,
        "{a0:?} {a1:?}"
    );
    assert!(
        ((a0[0] + a1[0]) as f64 / 2.0 - mid).abs() <= 1.5,
        "{a0:?} {a1:?}"
    );
    assert!(a0[1].abs_diff(a1[1]) <= 1, "{a0:?} {a1:?}");
    assert!(((a0[1] as f64) - plain.height as f64 / 2.0).abs() <= 2.0);
    for l in &placed {
        assert!(l.depth_px > 20.0);
        // The label changed the picture where it was drawn, nowhere else.
        let [left, top, w, h] = l.bounds;
        let changed = (top..top + h)
            .flat_map(|y| (left..left + w).map(move |x| (x, y)))
            .filter(|&(x, y)| img.get(x as u32, y as u32) != plain.get(x as u32, y as u32))
            .count();
        assert!(changed as i64 > w * h / 2, "label box drawn");
    }
    let outside_changed = (0..img.height)
        .flat_map(|y| (0..img.width).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            !placed.iter().any(|l| {
                let [left, top, w, h] = l.bounds;
                (x as i64) >= left
                    && (x as i64) < left + w
                    && (y as i64) >= top
                    && (y as i64) < top + h
            })
        })
        .filter(|&(x, y)| img.get(x, y) != plain.get(x, y))
        .count();
    assert_eq!(outside_changed, 0);
    // Both label boxes are disjoint.
    let [a, b] = [&placed[0].bounds, &placed[1].bounds];
    assert!(
        a[0] + a[2] <= b[0] || b[0] + b[2] <= a[0] || a[1] + a[3] <= b[1] || b[1] + b[3] <= a[1]
    );
}

#[test]
fn region_labels_that_would_overlap_are_left_out() {
    // Fifty thin strips side by side: far too narrow for a label each.
    let mut p = Vec::new();
    let mut t = Vec::new();
    let mut region = Vec::new();
    for k in 0..50u32 {
        let x0 = k as f64 * 0.02;
        let b = p.len() as u32;
        p.extend([
            Vec3::new(x0, 0.0, 0.0),
            Vec3::new(x0 + 0.02, 0.0, 0.0),
            Vec3::new(x0 + 0.02, 1.0, 0.0),
            Vec3::new(x0, 1.0, 0.0),
        ]);
        t.push([b, b + 1, b + 2]);
        t.push([b, b + 2, b + 3]);
        region.extend([k, k]);
    }
    let labels = RegionLabels {
        triangle_region: region,
        texts: (0..50).map(|k| format!("{k}")).collect(),
    };
    let scene = Scene {
        meshes: vec![MeshLayer::new(&p, &t)],
        ..Default::default()
    };
    let opts = RenderOptions {
        width: 300,
        height: 300,
        view_dir: Vec3::new(0.0, 0.0, -1.0),
        up: Vec3::Y,
        orthographic: true,
        ..Default::default()
    };
    let (_, placed) = render_labelled(&scene, &opts, &labels).unwrap();
    assert!(
        !placed.is_empty() && placed.len() < 50,
        "{} labels",
        placed.len()
    );
    for (i, a) in placed.iter().enumerate() {
        for b in &placed[i + 1..] {
            let (a, b) = (a.bounds, b.bounds);
            assert!(
                a[0] + a[2] <= b[0]
                    || b[0] + b[2] <= a[0]
                    || a[1] + a[3] <= b[1]
                    || b[1] + b[3] <= a[1],
                "{a:?} overlaps {b:?}"
            );
        }
    }
}

/// A mirror facing +z, tubes along x seen from +z: a ray tilted by α in
/// the yz plane reflects to the angle −α about the tubes; at a stripe's
/// centre the coverage is 1 where the stripes are wide on the screen and
/// falls to the band share (the mean) where they are denser than the
/// pixels.
#[test]
fn reflection_zebra_measures_the_reflected_angle_and_fades_to_its_mean() {
    use super::ReflectionZebra;
    let z = ReflectionZebra::new(Vec3::X, Vec3::Z, 10.0).unwrap();
    for alpha in [0.0f64, 5.0, 23.0, -40.0] {
        let a = alpha.to_radians();
        let ray = Vec3::new(0.0, a.sin(), -a.cos());
        let t = z.stripe(ray, Vec3::Z);
        assert!((t + alpha / 10.0).abs() < 1e-12, "{alpha}: {t}");
    }
    // a zenith not orthogonal to the axis is made so; parallel ones refused
    let tilted = ReflectionZebra::new(Vec3::X, Vec3::new(0.3, 0.0, 1.0), 10.0).unwrap();
    assert!(tilted.zenith.dot(Vec3::X).abs() < 1e-15);
    assert!(ReflectionZebra::new(Vec3::X, Vec3::X, 10.0).is_none());
    assert!(ReflectionZebra::new(Vec3::X, Vec3::Z, 0.0).is_none());
    // coverage: dark at the stripe's centre, light half a period off, the
    // band share where one pixel spans a third of a period or more
    assert!((z.coverage(3.0, 0.01) - 1.0).abs() < 1e-12);
    assert!(z.coverage(3.5, 0.01).abs() < 1e-12);
    assert!((z.coverage(3.0, 0.4) - 0.5).abs() < 1e-12);
    assert!((z.coverage(3.5, 0.4) - 0.5).abs() < 1e-12);
    // a whole turn between two pixels (the jump behind the axis) is no step
    assert!((z.coverage(3.0, 36.0 + 0.01) - 1.0).abs() < 1e-12);
}
