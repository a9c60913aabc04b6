//! `fairline demo`: built-in surfaces through every pipeline, with
//! pictures, `report.json` and `index.html`.

use crate::common::{Report, progress, write_json};
use anyhow::{Context, Result};
use fairline::Vec3;
use fairline::geom::{CurvatureMethod, principal_curvatures};
use fairline::mesh::{Stats, SurfaceMesh, structure_lines};
use fairline::picture::{Picture, ScalarField, mesh_picture};
use fairline::render::{Colormap, PolylineLayer, RenderOptions};
use fairline::shapes;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// Runs built-in example surfaces (sphere, torus, a wavy height field, a
/// quad grid, ...) through every pipeline and writes pictures, meshes,
/// `report.json` and `index.html` (open it in a browser) to the output folder.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example:\n  fairline demo --out fairline-demo\n  (then open fairline-demo/index.html)"
)]
pub struct Args {
    /// Output folder (created if missing).
    #[arg(long, default_value = "fairline-demo")]
    pub out: PathBuf,
    /// Size of each picture, WxH.
    #[arg(long, value_parser = crate::common::parse_size, default_value = "900x700")]
    pub size: (u32, u32),
}

/// One part of the demo: a heading, text, pictures and report values.
pub struct Section {
    /// Heading.
    pub title: String,
    /// What the pictures show (HTML-escaped text).
    pub text: String,
    /// Picture file names (in the output folder) with captions.
    pub images: Vec<(String, String)>,
    /// Numbers for report.json.
    pub values: Value,
}

/// Shared state of a demo run.
pub struct Demo {
    /// Output folder.
    pub out: PathBuf,
    /// Picture options.
    pub opts: RenderOptions,
}

impl Demo {
    /// Writes a picture into the output folder and returns its file name.
    pub fn save(&self, name: &str, image: &fairline::render::Image) -> Result<String> {
        image.write_png(self.out.join(name))?;
        Ok(name.to_string())
    }
}

type Step = fn(&Demo) -> Result<Section>;

pub fn run(args: Args) -> Result<()> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let demo = Demo {
        out: args.out.clone(),
        opts: RenderOptions::with_size(args.size.0, args.size.1),
    };
    let steps: Vec<(&str, Step)> = vec![
        ("sphere curvature", sphere_section),
        ("torus curvature", torus_section),
        ("wavy panel", wavy_section),
        ("quad grid", quad_section),
        ("smoothing", crate::smooth::demo_section),
    ];
    let bar = progress(steps.len() as u64, "demo");
    let mut report = Report::new("demo");
    let mut sections = Vec::new();
    for (name, step) in steps {
        bar.set_message(name.to_string());
        let section = report
            .time(|| step(&demo))
            .with_context(|| format!("demo step `{name}`"))?;
        sections.push(section);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let mut parts = serde_json::Map::new();
    for s in &sections {
        parts.insert(s.title.clone(), s.values.clone());
    }
    report.set("sections", Value::Object(parts));
    report.set("out", args.out.display().to_string());
    write_json(&args.out.join("report.json"), &report.to_json())?;
    write_index(&args.out, &sections)?;
    println!(
        "demo written to {} (open {})",
        args.out.display(),
        args.out.join("index.html").display()
    );
    Ok(())
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn write_index(out: &Path, sections: &[Section]) -> Result<()> {
    let mut html = String::from(
        "<!doctype html>\n<html><head><meta charset=\"utf-8\"><title>fairline demo</title>\n<style>body{font-family:sans-serif;max-width:1400px;margin:2em auto;color:#222}img{max-width:660px;margin:4px;border:1px solid #ccc}figure{display:inline-block;margin:0 8px}pre{background:#f4f4f4;padding:8px;overflow:auto}</style></head><body>\n<h1>fairline demo</h1>\n<p>Built-in surfaces through fairline's pipelines. Numbers are in <a href=\"report.json\">report.json</a>.</p>\n",
    );
    for s in sections {
        html.push_str(&format!(
            "<h2>{}</h2>\n<p>{}</p>\n",
            escape(&s.title),
            escape(&s.text)
        ));
        for (img, caption) in &s.images {
            html.push_str(&format!(
                "<figure><img src=\"{img}\" alt=\"{c}\"><figcaption>{c}</figcaption></figure>\n",
                c = escape(caption)
            ));
        }
        html.push_str(&format!(
            "<pre>{}</pre>\n",
            escape(&serde_json::to_string_pretty(&s.values)?)
        ));
    }
    html.push_str("</body></html>\n");
    fairline::io::atomic_write(out.join("index.html"), |w| {
        use std::io::Write;
        w.write_all(html.as_bytes())
    })?;
    Ok(())
}

fn curvature_picture(
    demo: &Demo,
    mesh: &SurfaceMesh,
    values: &[f64],
    name: &str,
    title: &str,
    file: &str,
    wireframe: bool,
) -> Result<String> {
    let picture = Picture {
        scalar: Some(ScalarField {
            name: name.into(),
            values,
            colormap: Colormap::Coolwarm,
            range: None,
        }),
        wireframe,
        title: Some(title.into()),
        ..Default::default()
    };
    demo.save(file, &mesh_picture(mesh, &picture, &demo.opts)?)
}

fn sphere_section(demo: &Demo) -> Result<Section> {
    let r = 1.0;
    let mesh = shapes::icosphere(r, 4);
    let c = principal_curvatures(&mesh, CurvatureMethod::Rusinkiewicz);
    let m = principal_curvatures(&mesh, CurvatureMethod::Meyer);
    let err = |k: &[f64]| k.iter().map(|k| (k - 1.0 / r).abs()).fold(0.0, f64::max);
    let img = curvature_picture(
        demo,
        &mesh,
        &c.mean(),
        "mean curvature",
        "icosphere r = 1: mean curvature",
        "sphere-mean-curvature.png",
        false,
    )?;
    fairline::io::write_mesh(demo.out.join("sphere.ply"), &mesh)?;
    Ok(Section {
        title: "Sphere".into(),
        text: "Icosphere of radius 1 (2562 vertices). Both estimators should give k1 = k2 = 1; the legend shows how close the mean curvature is.".into(),
        images: vec![(img, "mean curvature, Rusinkiewicz".into())],
        values: json!({
            "vertices": mesh.vertex_count(),
            "rusinkiewicz_max_abs_error_k1": err(&c.k1),
            "rusinkiewicz_max_abs_error_k2": err(&c.k2),
            "meyer_max_abs_error_k1": err(&m.k1),
            "meyer_max_abs_error_k2": err(&m.k2),
        }),
    })
}

fn torus_section(demo: &Demo) -> Result<Section> {
    let (big_r, r) = (1.0, 0.4);
    let mesh = shapes::torus(big_r, r, 96, 40);
    let c = principal_curvatures(&mesh, CurvatureMethod::Rusinkiewicz);
    let k2_err = mesh
        .vertices()
        .map(|v| {
            let p = mesh.position(v);
            let rho = (p.x * p.x + p.y * p.y).sqrt();
            let cos_v = (rho - big_r) / r;
            (c.k2[v.idx()] - cos_v / (big_r + r * cos_v)).abs()
        })
        .fold(0.0, f64::max);
    let k1_err = c.k1.iter().map(|k| (k - 1.0 / r).abs()).fold(0.0, f64::max);
    let img = curvature_picture(
        demo,
        &mesh,
        &c.gauss(),
        "Gaussian curvature",
        "torus: Gaussian curvature (+ outside, - inside)",
        "torus-gauss.png",
        false,
    )?;
    Ok(Section {
        title: "Torus".into(),
        text: "Torus R = 1, r = 0.4. Closed forms: k1 = 1/r, k2 = cos v / (R + r cos v); Gaussian curvature is positive on the outer half and negative on the inner half.".into(),
        images: vec![(img, "Gaussian curvature".into())],
        values: json!({
            "vertices": mesh.vertex_count(),
            "max_abs_error_k1": k1_err,
            "max_abs_error_k2": k2_err,
            "gauss": Stats::of(c.gauss()),
        }),
    })
}

fn wavy_section(demo: &Demo) -> Result<Section> {
    let mesh = shapes::height_field(60, 60, (-1.0, 1.0), (-1.0, 1.0), |x, y| {
        0.2 * (3.0 * x).sin() * (2.0 * y).cos()
    });
    let c = principal_curvatures(&mesh, CurvatureMethod::Rusinkiewicz);
    let img = curvature_picture(
        demo,
        &mesh,
        &c.mean(),
        "mean curvature",
        "wavy panel: mean curvature",
        "wavy-mean-curvature.png",
        true,
    )?;
    fairline::io::write_mesh(demo.out.join("wavy.obj"), &mesh)?;
    Ok(Section {
        title: "Wavy panel".into(),
        text: "A height field z = 0.2 sin 3x cos 2y, triangulated with alternating diagonals, coloured by mean curvature.".into(),
        images: vec![(img, "mean curvature with wireframe".into())],
        values: json!({
            "vertices": mesh.vertex_count(),
            "mean": Stats::of(c.mean()),
        }),
    })
}

fn quad_section(demo: &Demo) -> Result<Section> {
    let mesh = shapes::quad_grid(16, 16, (-1.0, 1.0), (-1.0, 1.0), |x, y| {
        0.3 * (x * x - y * y)
    });
    let lines = structure_lines(&mesh);
    let polylines: Vec<PolylineLayer> = lines
        .iter()
        .enumerate()
        .map(|(i, l)| PolylineLayer {
            points: l
                .vertices
                .iter()
                .map(|&v| mesh.position(v))
                .collect::<Vec<Vec3>>(),
            closed: l.closed,
            color: if i % 2 == 0 {
                [0.05, 0.2, 0.7]
            } else {
                [0.7, 0.1, 0.1]
            },
            width_px: 2.0,
        })
        .collect();
    let picture = Picture {
        polylines,
        title: Some("quad saddle: structure lines".into()),
        ..Default::default()
    };
    let img = demo.save(
        "quad-structure-lines.png",
        &mesh_picture(&mesh, &picture, &demo.opts)?,
    )?;
    fairline::io::write_mesh(demo.out.join("quad-saddle.obj"), &mesh)?;
    Ok(Section {
        title: "Quad grid".into(),
        text: "A 16 × 16 quad saddle z = 0.3 (x² − y²); its structure lines are traced straight through the regular vertices.".into(),
        images: vec![(img, "structure lines".into())],
        values: json!({
            "vertices": mesh.vertex_count(),
            "quads": mesh.face_count(),
            "structure_lines": lines.len(),
        }),
    })
}
