//! Times the renderer on a ~1M-triangle torus at 1600×1200 with 3× supersampling.
//!
//! `cargo run --release -p fairline --example render_bench [OUT.png]`

use fairline::Vec3;
use fairline::render::{Colormap, Legend, MeshLayer, RenderOptions, Scene, render, scalar_colors};
use std::f64::consts::PI;
use std::time::Instant;

fn main() {
    let (nu, nv) = (1000u32, 500u32);
    let mut p = Vec::new();
    let mut n = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let (a, b) = (
                2.0 * PI * i as f64 / nu as f64,
                2.0 * PI * j as f64 / nv as f64,
            );
            let d = Vec3::new(b.cos() * a.cos(), b.cos() * a.sin(), b.sin());
            p.push(Vec3::new(a.cos(), a.sin(), 0.0) * 1.0 + d * (0.35 + 0.01 * (20.0 * a).sin()));
            n.push(d);
        }
    }
    let mut t = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let id = |i: u32, j: u32| (j % nv) * nu + (i % nu);
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let values: Vec<f64> = p.iter().map(|q| q.z).collect();
    let (colors, (lo, hi)) = scalar_colors(&values, Colormap::Viridis, None);
    let scene = Scene {
        meshes: vec![MeshLayer::new(&p, &t).with_normals(&n).with_colors(&colors)],
        legend: Some(Legend {
            title: "z".into(),
            colormap: Colormap::Viridis,
            min: lo,
            max: hi,
            clipped: false,
        }),
        title: Some(format!("{} triangles", t.len())),
        ..Default::default()
    };
    let opts = RenderOptions::with_size(1600, 1200);
    for _ in 0..3 {
        let start = Instant::now();
        let img = render(&scene, &opts).expect("render");
        let dt = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let png = img.encode_png();
        let de = start.elapsed().as_secs_f64();
        println!(
            "{} triangles, {}x{} x{}: render {dt:.3} s, png {de:.3} s ({} bytes)",
            t.len(),
            opts.width,
            opts.height,
            opts.supersample,
            png.len()
        );
        if let Some(out) = std::env::args().nth(1) {
            img.write_png(out).expect("write");
        }
    }
}
