//! `fairline demo`: built-in surfaces through every pipeline, with
//! pictures, `report.json` and `index.html`.

mod fair_surface;
mod smooth;

use crate::args::parse_size;
use crate::common::{Report, write_json};
use crate::output::progress;
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
    #[arg(long, value_parser = parse_size, default_value = "900x700")]
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
    let job = crate::output::Job::new("demo");
    crate::output::owned_folder("--out", &args.out)?;
    let demo = Demo {
        out: args.out.clone(),
        opts: RenderOptions::with_size(args.size.0, args.size.1),
    };
    let steps: Vec<(&str, Step)> = vec![
        ("sphere curvature", sphere_section),
        ("torus curvature", torus_section),
        ("wavy panel", wavy_section),
        ("quad grid", quad_section),
        ("vertex flow", enhance_section),
        ("highlight lines", highlight_section),
        ("detection on curved shape", detect_section),
        ("highlight-line fairing", fair_section),
        ("B-spline fairing", fair_surface::section),
        ("smoothing", smooth::section),
        ("structure lines vs Taubin", structure_line_section),
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
    job.finish(format_args!(
        "{} sections written to {} (open {})",
        sections.len(),
        args.out.display(),
        args.out.join("index.html").display()
    ))?;
    crate::output::say(&format!(
        "look at a result interactively (lights, marking, fairing): fairline view {}",
        args.out.join("dented-panel.obj").display()
    ));
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

/// A gently curved panel z = 0.15 sin(1.3x) cos(0.9y) (about 4 × 4 units).
fn panel_height(x: f64, y: f64) -> f64 {
    0.15 * (1.3 * x).sin() * (0.9 * y).cos()
}

/// Depth, centre and width of the dent planted in the highlight demo panel.
const DENT: (f64, f64, f64, f64) = (0.01, 0.5, -0.4, 0.16);

fn dented_height(x: f64, y: f64) -> f64 {
    let (depth, cx, cy, w) = DENT;
    panel_height(x, y) - depth * (-((x - cx).powi(2) + (y - cy).powi(2)) / (w * w)).exp()
}

fn highlight_section(demo: &Demo) -> Result<Section> {
    use crate::highlight_png::{Overlay, image};
    use fairline::highlight::{DetectOptions, HighlightModel, LightArray, detect_irregularities};
    let n = 201;
    let build = |f: fn(f64, f64) -> f64| shapes::height_field(n, n, (-2.0, 2.0), (-2.0, 2.0), f);
    let dented = build(dented_height);
    let clean = build(panel_height);
    let light = LightArray::new(Vec3::new(0.0, 0.0, 6.0), Vec3::Z, Vec3::X, 0.1)?;
    let opts = DetectOptions::default();
    let t = std::time::Instant::now();
    let model = HighlightModel::new(&dented, light, Default::default())?;
    let lines = model.lines(&dented);
    let model_ms = t.elapsed().as_secs_f64() * 1e3;
    let det = detect_irregularities(&dented, &light, &lines, &opts)?;
    let clean_lines = HighlightModel::new(&clean, light, Default::default())?.lines(&clean);
    let clean_det = detect_irregularities(&clean, &light, &clean_lines, &opts)?;
    let stretches: Vec<Vec<Vec3>> = det
        .lines
        .iter()
        .flat_map(|l| l.stretches.iter().cloned())
        .collect();
    let faces = det.all_faces();
    let view = crate::render::camera(&dented, None);
    let size = (demo.opts.width, demo.opts.height);
    let img_lines = demo.save(
        "highlight-dent-lines.png",
        &image(
            &dented,
            Overlay {
                lines: &lines,
                bands: None,
                flagged: &stretches,
                region: None,
                unjudged: None,
                view,
                spacing: Some(light.spacing()),
                zebra: None,
                title: format!(
                    "dented panel: {} highlight lines, irregular stretches in red",
                    lines.lines.len()
                ),
            },
            size,
        )?,
    )?;
    let img_region = demo.save(
        "highlight-dent-region.png",
        &image(
            &dented,
            Overlay {
                lines: &lines,
                bands: None,
                flagged: &[],
                region: Some(&faces),
                unjudged: None,
                view,
                spacing: Some(light.spacing()),
                zebra: None,
                title: format!("suggested fairing region: {} faces", faces.len()),
            },
            size,
        )?,
    )?;
    let img_clean = demo.save(
        "highlight-clean-lines.png",
        &image(
            &clean,
            Overlay {
                lines: &clean_lines,
                bands: None,
                flagged: &[],
                region: None,
                unjudged: None,
                view,
                spacing: Some(light.spacing()),
                zebra: None,
                title: format!(
                    "same panel without the dent: {} region(s)",
                    clean_det.regions.len()
                ),
            },
            size,
        )?,
    )?;
    fairline::io::write_mesh(demo.out.join("dented-panel.obj"), &dented)?;
    write_json(
        &demo.out.join("dented-panel-region.json"),
        &json!({"faces": faces.iter().map(|f| f.0).collect::<Vec<_>>()}),
    )?;
    let (depth, cx, cy, w) = DENT;
    let top = det.regions.first();
    let centre_error = top.map(|r| (r.center.x - cx).hypot(r.center.y - cy));
    Ok(Section {
        title: "Highlight lines and a planted dent".into(),
        text: format!(
            "A gently curved panel (201 × 201 vertices, 4 × 4 units) with a dent {depth} deep and {w} wide planted at ({cx}, {cy}), under parallel lights along x spaced 0.1 apart in the plane z = 6 (Yong et al. Algorithm 1). The dent is hard to see in the shading but bends the highlight lines; `detect` flags the bent stretches (red) and grows them into a suggested fairing region (orange). The same panel without the dent gets no region. Try: fairline detect dented-panel.obj --spacing 0.1 --plane-point 0,0,6 -o region.json --png detect.png"
        ),
        images: vec![
            (
                img_lines,
                "highlight lines, irregular stretches in red".into(),
            ),
            (img_region, "detected region".into()),
            (img_clean, "the clean panel".into()),
        ],
        values: json!({
            "vertices": dented.vertex_count(),
            "lines": lines.lines.len(),
            "nodes": lines.node_count(),
            "model_ms": model_ms,
            "regions": det.regions.len(),
            "region_faces": faces.len(),
            "top_region_score": top.map(|r| r.score),
            "top_region_centre_distance_from_dent": centre_error,
            "clean_panel_regions": clean_det.regions.len(),
        }),
    })
}

/// Strongly curved sin·sin hills z = 0.12 sin(1.5πx) sin(1.5πy) over
/// [−1, 1]² (summits, saddles and valleys; the normal turns by up to 30°).
fn hills_height(x: f64, y: f64) -> f64 {
    use std::f64::consts::PI;
    0.12 * (1.5 * PI * x).sin() * (1.5 * PI * y).sin()
}

/// Centre and width σ of the bump planted on the hills; its height is
/// 0.1 % of the bounding-box diagonal.
const HILL_BUMP: (f64, f64, f64) = (0.3, -0.2, 0.1);

/// Detection with default options on a clean, strongly curved surface next
/// to the same surface with a small planted bump: the curved shape stays
/// quiet, the bump is found.
fn detect_section(demo: &Demo) -> Result<Section> {
    use crate::highlight_png::{Overlay, detect_with_lines, image, stretches};
    use fairline::highlight::{DetectOptions, LightArray, UpAxis};
    let n = 161;
    let clean = shapes::height_field(n, n, (-1.0, 1.0), (-1.0, 1.0), hills_height);
    let (lo, hi) =
        fairline::mesh::bounding_box(clean.positions()).context("the hills have no vertices")?;
    let amplitude = 1e-3 * (hi - lo).length();
    let (cx, cy, sigma) = HILL_BUMP;
    let bumped = shapes::height_field(n, n, (-1.0, 1.0), (-1.0, 1.0), move |x, y| {
        hills_height(x, y)
            + amplitude * (-((x - cx).powi(2) + (y - cy).powi(2)) / (sigma * sigma)).exp()
    });
    let size = (demo.opts.width, demo.opts.height);
    let mut values = Vec::new();
    let mut images = Vec::new();
    // the lights `fairline detect` chooses with no options for the clean
    // hills, the same for both (one camera, one scale)
    let light = LightArray::default_for_mesh(&clean, UpAxis::Auto)
        .context("the hills have no finite vertices")?;
    let k = light.readable_multiple(&clean);
    let shown_light = light.with_spacing(light.spacing() * f64::from(k))?;
    for (mesh, file, what) in [
        (&clean, "detect-curved-clean.png", "clean hills"),
        (&bumped, "detect-curved-bump.png", "hills with a small bump"),
    ] {
        let (_, shown, det) = detect_with_lines(
            mesh,
            &light,
            &shown_light,
            Default::default(),
            &DetectOptions::default(),
        )?;
        let faces = det.all_faces();
        let unjudged = det.shape_faces(mesh);
        let flagged = stretches(&det);
        let title = format!(
            "{what}: {} region(s){}",
            det.regions.len(),
            det.best_summary()
                .map(|b| format!(", best {b}"))
                .unwrap_or_default()
        );
        images.push((
            demo.save(
                file,
                &image(
                    mesh,
                    Overlay {
                        lines: &shown,
                        bands: None,
                        flagged: &flagged,
                        region: Some(&faces),
                        unjudged: Some(&unjudged),
                        view: crate::render::camera(&clean, None),
                        title: title.clone(),
                        spacing: Some(shown_light.spacing()),
                        zebra: None,
                    },
                    size,
                )?,
            )?,
            title,
        ));
        let mut value = json!({
            "surface": what,
            "vertices": mesh.vertex_count(),
            "regions": det.regions.len(),
            "flagged_area_fraction": det.flagged_area_fraction,
            "median_score": det.median_score,
        });
        // the clean hills have no region: the keys are left out, not null
        if let Some(top) = det.regions.first() {
            value["top_region_score"] = json!(top.score);
            value["top_region_centre_distance_from_bump"] =
                json!((top.center.x - cx).hypot(top.center.y - cy));
        }
        values.push(value);
    }
    Ok(Section {
        title: "Detection: quiet on curved shape, finds a small defect".into(),
        text: format!(
            "Strongly curved sin·sin hills ({n} × {n} vertices over [−1, 1]², summits, saddles and valleys) checked with the lights `fairline detect` chooses for them with no options: the clean surface gets no region — strong but smooth curvature is shape, not a defect. The same hills with a bump {amplitude:.4} high (0.1 % of the bounding-box diagonal) and σ = {sigma} wide at ({cx}, {cy}) get one region, ranked first, around the bump. The measure compares the surface's normals with a smooth cubic fit over 1.5 light spacings (guide: Inspect a mesh, Highlight lines)."
        ),
        images,
        values: json!(values),
    })
}

/// Feature enhancement by vertex flow (Ji et al. 2011) on a coarse rounded
/// cube: the vertices sit evenly over the flat faces and the rounded edges
/// before, and gather on the rounded edges after.
fn enhance_section(demo: &Demo) -> Result<Section> {
    use fairline::enhance::{EnhanceOptions, enhance_features};
    let radius = 0.25;
    let mesh = shapes::rounded_cube(10, radius);
    let options = EnhanceOptions::default().lambda(0.5);
    let result = enhance_features(&mesh, &options)?;
    let mut out = mesh.clone();
    out.set_positions(result.positions)?;
    // share of vertices on the rounded part (distance to the inner box ≈ r
    // and not on a flat face)
    let a = 1.0 - radius;
    let on_feature = |m: &SurfaceMesh| {
        let n = m
            .positions()
            .iter()
            .filter(|p| p.abs().to_array().iter().filter(|x| **x > a + 1e-9).count() >= 2)
            .count();
        n as f64 / m.vertex_count() as f64
    };
    // distance of the mesh (points on every triangle) to the true rounded
    // cube: the exact distance to the offset of the inner box [-a, a]³
    let to_truth = |m: &SurfaceMesh| {
        let p = m.positions();
        let distance = |x: fairline::Vec3| {
            let q = x.abs() - fairline::Vec3::splat(a);
            let outside = q.max(fairline::Vec3::ZERO).length();
            (outside + q.max_element().min(0.0) - radius).abs()
        };
        let (mut max, mut sum, mut count) = (0.0f64, 0.0, 0usize);
        for f in m.faces() {
            let [x, y, z] = m.triangle(f).map(|v| p[v.idx()]);
            for (u, v) in [(1.0 / 3.0, 1.0 / 3.0), (0.5, 0.0), (0.0, 0.5), (0.5, 0.5)] {
                let d = distance((1.0 - u - v) * x + u * y + v * z);
                max = max.max(d);
                sum += d * d;
                count += 1;
            }
        }
        (max, (sum / count.max(1) as f64).sqrt())
    };
    let (truth_before, truth_after) = (to_truth(&mesh), to_truth(&out));
    let img = demo.save(
        "vertex-flow.png",
        &crate::enhance::picture(
            &mesh,
            &out,
            (demo.opts.width, demo.opts.height),
            &crate::args::ZebraArgs::default(),
        )?
        .0,
    )?;
    fairline::io::write_mesh(demo.out.join("rounded-cube.obj"), &mesh)?;
    fairline::io::write_mesh(demo.out.join("rounded-cube-enhanced.obj"), &out)?;
    let r = &result.report;
    Ok(Section {
        title: "Vertex flow".into(),
        text: format!(
            "A coarse cube with rounded edges (radius {radius}, {} vertices) before and after feature enhancement by vertex flow (Ji et al. 2011, lambda 0.5, mu 0.5): the vertices slide from the flat faces onto the rounded edges and corners without new vertices, and each moved vertex is put back onto a smooth fit of the input surface, so the same budget carries more of the shape: the largest distance of the triangles to the true rounded cube goes from {:.4} to {:.4}, the RMS distance from {:.4} to {:.4}. Same command: fairline enhance rounded-cube.obj --lambda 0.5 -o out.obj --png out.png.",
            mesh.vertex_count(),
            truth_before.0,
            truth_after.0,
            truth_before.1,
            truth_after.1
        ),
        images: vec![(
            img,
            "input (left) and after vertex flow (right), mean curvature".into(),
        )],
        values: json!({
            "vertices": mesh.vertex_count(),
            "share_on_rounded_edges_before": on_feature(&mesh),
            "share_on_rounded_edges_after": on_feature(&out),
            "flipped_triangles": r.flipped_triangles,
            "quality_before": r.quality_before,
            "quality_after": r.quality_after,
            "max_displacement": r.max_displacement,
            "max_distance_to_true_surface_before": truth_before.0,
            "max_distance_to_true_surface_after": truth_after.0,
            "rms_distance_to_true_surface_before": truth_before.1,
            "rms_distance_to_true_surface_after": truth_after.1,
        }),
    })
}

/// The dent-removal story (Yong et al. §3): a roof-like panel with a
/// planted dent, the region `detect` suggests, the desired lines, and the
/// faired panel beside the diffusion-flow baseline.
fn fair_section(demo: &Demo) -> Result<Section> {
    use fairline::fair::{FairMethod, FairOptions, fair_highlight_lines, grow_region};
    use fairline::highlight::{DetectOptions, HighlightModel, LightArray, detect_irregularities};
    use fairline::picture::fairing_picture;
    let roof = |x: f64, y: f64| 0.25 * (1.0 - 0.4 * x * x) * (1.0 - 0.3 * y * y);
    let mesh = shapes::height_field(61, 61, (-1.0, 1.0), (-1.0, 1.0), move |x, y| {
        let (dx, dy) = (x - 0.15, y + 0.1);
        roof(x, y) - 0.02 * (-(dx * dx + dy * dy) / (2.0 * 0.1 * 0.1)).exp()
    });
    let light = LightArray::new(
        Vec3::new(0.0, 0.0, 3.0),
        Vec3::new(0.0, 0.15, 1.0),
        Vec3::X,
        0.08,
    )?;
    let model = HighlightModel::new(&mesh, light, Default::default())?;
    let lines = model.lines(&mesh);
    let det = detect_irregularities(&mesh, &light, &lines, &DetectOptions::default())?;
    let best = det
        .regions
        .first()
        .ok_or_else(|| anyhow::anyhow!("detect found no irregular region on the dented panel"))?;
    let faces = grow_region(&mesh, &best.faces, 4);
    // the highlight-line result itself (`fair --no-least-change`); the
    // report says what the default's least change keeps
    let options = FairOptions::default()
        .region(faces)
        .light(light)
        .least_change(false);
    let with_positions = |positions: Vec<Vec3>| -> Result<SurfaceMesh> {
        let mut m = mesh.clone();
        m.set_positions(positions)?;
        Ok(m)
    };
    let out = fair_highlight_lines(&mesh, &options)?;
    let (r, faired) = (out.report, with_positions(out.positions)?);
    let out = fair_highlight_lines(&mesh, &options.method(FairMethod::DiffusionFlow))?;
    let (flow, flow_mesh) = (out.report, with_positions(out.positions)?);
    let mut opts = demo.opts.clone();
    (opts.view_dir, opts.up) = crate::render::camera(&mesh, None);
    let img = demo.save(
        "fair-before-after.png",
        &fairing_picture(&mesh, &faired, &r, None, &opts)?,
    )?;
    let img_flow = demo.save(
        "fair-diffusion-flow.png",
        &fairing_picture(&mesh, &flow_mesh, &flow, None, &opts)?,
    )?;
    let truth = |m: &SurfaceMesh| {
        r.region
            .movable
            .iter()
            .map(|v| (m.position(*v).z - roof(m.position(*v).x, m.position(*v).y)).abs())
            .fold(0.0, f64::max)
    };
    fairline::io::write_mesh(demo.out.join("dented-roof.obj"), &mesh)?;
    fairline::io::write_mesh(demo.out.join("dented-roof-faired.obj"), &faired)?;
    Ok(Section {
        title: "Highlight-line fairing".into(),
        text: "A roof-like panel z = 0.25 (1 - 0.4 x²)(1 - 0.3 y²) with a planted dent of depth 0.02. `detect` finds the wobbling highlight lines; its region, grown by four rings of faces, is faired by highlight-line fairing (Yong et al. Algorithm 2 with the desired curves' end tangents taken from a smooth surface fitted beyond the defect's footprint, then a quarter of the diffusion-flow state mixed in; `fair --no-least-change`): the blue desired lines are optimized geometric Hermite curves between the nodes just outside the red region. Only vertices whose motion changes nothing outside the region move. Second picture: the surface-diffusion-flow baseline on the same region; the values compare both with the defect-free panel. The default `fair` keeps the highlight-line result only where it dominates the flow state (lines nearer the desired curves and a change of the part at least 1 % smaller, least change): `default_keeps` says which it keeps here.".into(),
        images: vec![
            (img, "highlight-line fairing: before (with region and desired lines) and after".into()),
            (img_flow, "baseline: surface diffusion flow on the same region".into()),
        ],
        values: json!({
            "vertices": mesh.vertex_count(),
            "detected_regions": det.regions.len(),
            "movable_vertices": r.region.movable.len(),
            "iterations": r.iterations,
            "converged": r.converged,
            "willmore_before": r.willmore_before,
            "willmore_after": r.willmore_after,
            "highlight_deviation_before": r.deviation_before.rms,
            "highlight_deviation_after": r.deviation_after.rms,
            "diffusion_flow_highlight_deviation_after": flow.deviation_after.rms,
            "distance_to_panel_before": truth(&mesh),
            "distance_to_panel_after": truth(&faired),
            "diffusion_flow_distance_to_panel_after": truth(&flow_mesh),
            "default_keeps": if r.least_change.keeps_highlight() {
                "highlight-line result"
            } else {
                "diffusion-flow state"
            },
            "least_change": r.least_change,
        }),
    })
}

/// Quad grid of the graph of `f` over [−1, 1]² with `n` × `n` points and a
/// planted zigzag (interior points shifted by ±0.2 of the spacing across
/// the lines of one family and ±0.1 across the other, then put back onto
/// the graph): (truth, zigzag).
fn zigzag_quad_grid(n: u32, f: impl Fn(f64, f64) -> f64) -> (SurfaceMesh, SurfaceMesh) {
    let truth = shapes::quad_grid(n, n, (-1.0, 1.0), (-1.0, 1.0), &f);
    let mut zigzag = truth.clone();
    let h = 2.0 / (n - 1) as f64;
    for (k, p) in zigzag.positions_mut().iter_mut().enumerate() {
        let (i, j) = (k as u32 % n, k as u32 / n);
        if i > 0 && j > 0 && i < n - 1 && j < n - 1 {
            let x = p.x + if j % 2 == 0 { 0.2 * h } else { -0.2 * h };
            let y = p.y + if i % 2 == 0 { 0.1 * h } else { -0.1 * h };
            *p = Vec3::new(x, y, f(x, y));
        }
    }
    (truth, zigzag)
}

/// Distance of every vertex to the graph of `f`: the vertical gap divided
/// by √(1 + |∇f|²) (the closest-point distance to second order in the gap;
/// ∇f by central differences).
fn graph_distance(m: &SurfaceMesh, f: &dyn Fn(f64, f64) -> f64) -> Vec<f64> {
    let e = 1e-6;
    m.positions()
        .iter()
        .map(|p| {
            let fx = (f(p.x + e, p.y) - f(p.x - e, p.y)) / (2.0 * e);
            let fy = (f(p.x, p.y + e) - f(p.x, p.y - e)) / (2.0 * e);
            (p.z - f(p.x, p.y)).abs() / (1.0 + fx * fx + fy * fy).sqrt()
        })
        .collect()
}

/// (mean, max) turning angle in degrees of the structure lines at their
/// interior points (the angle between consecutive edges).
fn line_turning(m: &SurfaceMesh) -> (f64, f64) {
    let p = m.positions();
    let mut angles = Vec::new();
    for line in structure_lines(m) {
        let v = &line.vertices;
        for w in v.windows(3) {
            let a = (p[w[1].idx()] - p[w[0].idx()]).normalize_or_zero();
            let b = (p[w[2].idx()] - p[w[1].idx()]).normalize_or_zero();
            if a != Vec3::ZERO && b != Vec3::ZERO {
                angles.push(a.dot(b).clamp(-1.0, 1.0).acos().to_degrees());
            }
        }
    }
    let mean = angles.iter().sum::<f64>() / angles.len().max(1) as f64;
    (mean, angles.iter().copied().fold(0.0, f64::max))
}

/// Structure-line fairing against its baseline: a
/// zigzag quad grid of a Gaussian bump, faired by fairline (points sliding
/// along the input surface, Grüner thesis ch. 4) and by Taubin with 50
/// iterations; distance to the true surface and straightness of the lines.
fn structure_line_section(demo: &Demo) -> Result<Section> {
    use fairline::fair::{QuadFairOptions, fair_structure_lines};
    use fairline::picture::ScalarField;
    use fairline::render::side_by_side;
    use fairline::smooth::{TaubinOptions, taubin_smooth};
    let bump = |x: f64, y: f64| 0.4 * (-1.5 * (x * x + y * y)).exp();
    let (truth, zigzag) = zigzag_quad_grid(25, bump);
    let mut taubin = zigzag.clone();
    taubin.set_positions(
        taubin_smooth(&zigzag, &TaubinOptions::default().iterations(50))?.positions,
    )?;
    let mut faired = zigzag.clone();
    faired.set_positions(fair_structure_lines(&zigzag, &QuadFairOptions::default())?.positions)?;
    let meshes = [
        ("input", &zigzag),
        ("taubin_50", &taubin),
        ("fairline", &faired),
    ];
    let distances: Vec<Vec<f64>> = meshes
        .iter()
        .map(|(_, m)| graph_distance(m, &bump))
        .collect();
    let largest = distances
        .iter()
        .flatten()
        .copied()
        .fold(0.0f64, f64::max)
        .max(1e-12);
    let images = meshes
        .iter()
        .zip(&distances)
        .map(|((_, m), d)| {
            let picture = Picture {
                scalar: Some(ScalarField {
                    name: "distance to truth".into(),
                    values: d,
                    colormap: Colormap::Viridis,
                    range: Some((0.0, largest)),
                }),
                wireframe: true,
                ..Default::default()
            };
            mesh_picture(m, &picture, &demo.opts)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let img = demo.save(
        "structure-lines-vs-taubin.png",
        &side_by_side(
            &images,
            &["zigzag input", "Taubin 50", "fairline fair-quad"],
        ),
    )?;
    fairline::io::write_mesh(demo.out.join("zigzag-bump.obj"), &zigzag)?;
    let mut distance = serde_json::Map::new();
    let mut turning = serde_json::Map::new();
    for ((name, m), d) in meshes.iter().zip(&distances) {
        let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len().max(1) as f64).sqrt();
        let max = d.iter().copied().fold(0.0f64, f64::max);
        distance.insert((*name).into(), json!({ "max": max, "rms": rms }));
        let (mean, max) = line_turning(m);
        turning.insert((*name).into(), json!({ "mean": mean, "max": max }));
    }
    let (mean, max) = line_turning(&truth);
    turning.insert("truth".into(), json!({ "mean": mean, "max": max }));
    let at = |map: &serde_json::Map<String, Value>, k: &str, f: &str| {
        map.get(k)
            .and_then(|v| v.get(f))
            .and_then(Value::as_f64)
            .unwrap_or(f64::NAN)
    };
    Ok(Section {
        title: "Structure-line fairing vs Taubin".into(),
        text: format!(
            "A 25 × 25 quad grid of the Gaussian bump z = 0.4 exp(−1.5 (x² + y²)) with zigzag structure lines, faired by structure-line fairing (Grüner thesis ch. 4, the points sliding along the input surface) and by Taubin smoothing with 50 iterations, the usual baseline. Colour: distance of the vertices to the true bump (common scale). Largest distance: input {:.2e}, Taubin 50 {:.2e}, fairline {:.2e}; RMS {:.2e}, {:.2e}, {:.2e}. Mean turning angle of the lines (degrees; the true bump's own lines turn by {:.2}°): input {:.2}, Taubin 50 {:.2}, fairline {:.2}; largest {:.2}, {:.2}, {:.2}. Same command: fairline fair-quad zigzag-bump.obj -o out.obj --png out.png.",
            at(&distance, "input", "max"),
            at(&distance, "taubin_50", "max"),
            at(&distance, "fairline", "max"),
            at(&distance, "input", "rms"),
            at(&distance, "taubin_50", "rms"),
            at(&distance, "fairline", "rms"),
            at(&turning, "truth", "mean"),
            at(&turning, "input", "mean"),
            at(&turning, "taubin_50", "mean"),
            at(&turning, "fairline", "mean"),
            at(&turning, "input", "max"),
            at(&turning, "taubin_50", "max"),
            at(&turning, "fairline", "max"),
        ),
        images: vec![(
            img,
            "zigzag input, Taubin 50 and structure-line fairing, coloured by the distance to the true surface".into(),
        )],
        values: json!({
            "vertices": zigzag.vertex_count(),
            "distance_to_true_surface": distance,
            "turning_angle_deg": turning,
        }),
    })
}
