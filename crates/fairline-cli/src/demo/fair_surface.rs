//! Demo section of `fairline fair-surface`: circular-highlight fairing of a
//! dented B-spline panel (Nishiyama et al. §3).

use super::{Demo, Section};
use crate::common::write_json;
use crate::surface_highlight::{
    PALETTE, UvLine, palette_srgb, plot_lines, polylines, surface_picture, uv_picture, uv_plot,
};
use anyhow::Result;
use fairline::bspline::BSplineSurface;
use fairline::fair::{SurfaceFairOptions, fair_surface};
use fairline::highlight::{
    CircularLight, SurfaceHighlightOptions, SurfaceLight, surface_highlight_lines,
};
use fairline::io::write_surfaces_json;
use fairline::render::side_by_side;
use serde_json::json;

/// Demo section: a roof-panel-like bicubic surface (21 × 22 control points,
/// clamped uniform knots) with a planted dent, its circular highlight lines
/// before and after fairing the stretches around the dent.
pub fn section(demo: &Demo) -> Result<Section> {
    use fairline::Vec3;
    use fairline::bspline::clamped_uniform_knots;
    use fairline::fair::endpoints_around;
    let (nu, nv) = (21, 22);
    let net: Vec<Vec<Vec3>> = (0..nu)
        .map(|i| {
            (0..nv)
                .map(|j| {
                    let x = -1.5 + 3.0 * i as f64 / (nu - 1) as f64;
                    let y = -1.0 + 2.0 * j as f64 / (nv - 1) as f64;
                    Vec3::new(x, y, 0.3 - 0.12 * x * x - 0.05 * y * y + 0.02 * x * y)
                })
                .collect()
        })
        .collect();
    let clean = BSplineSurface::new(
        3,
        3,
        clamped_uniform_knots(nu, 3),
        clamped_uniform_knots(nv, 3),
        net,
        None,
    )?;
    let (bi, bj) = (8, 12);
    let mut dented = clean.clone();
    dented.set_control_point(
        bi,
        bj,
        clean.control_point(bi, bj) - Vec3::new(0.0, 0.0, 0.015),
    )?;
    let greville = |k: &[f64], i: usize| (k[i + 1] + k[i + 2] + k[i + 3]) / 3.0;
    let centre = [greville(clean.knots_u(), bi), greville(clean.knots_v(), bj)];
    // Lights: concentric circles above the panel whose lines pass the dent.
    let a = Vec3::new(2.0, 1.5, 2.5);
    let q = clean.eval(centre[0], centre[1]);
    let n = clean
        .normal(centre[0], centre[1])
        .ok_or_else(|| anyhow::anyhow!("degenerate demo surface"))?;
    let x = q + (a.z - q.z) / n.z * n;
    let r0 = (x.x - a.x).hypot(x.y - a.y);
    let lights: Vec<CircularLight> = (0..11)
        .map(|k| CircularLight::new(a, Vec3::Z, r0 * (1.0 + 0.3 * (k as f64 / 10.0 - 0.5))))
        .collect::<Result<_, _>>()?;
    let opts = SurfaceFairOptions::default();
    let endpoints = endpoints_around(&dented, &lights, centre, 0.2, opts.grid);
    let opts = opts.lights(lights.clone()).endpoints(endpoints.clone());
    let out = fair_surface(&dented, &opts)?;
    let (faired, rep) = (out.surfaces, out.report);
    let slights: Vec<SurfaceLight> = lights.iter().map(|l| SurfaceLight::Circular(*l)).collect();
    let hopts = SurfaceHighlightOptions::default().grid(opts.grid);
    let before = surface_highlight_lines(&dented, &slights, &hopts);
    let after = surface_highlight_lines(&faired, &slights, &hopts);
    let mut ropts = demo.opts.clone();
    ropts.view_dir = Vec3::new(-0.3, 0.5, -0.8);
    let pic = |s: &BSplineSurface, h: &fairline::highlight::SurfaceHighlights, t: &str| {
        surface_picture(
            std::slice::from_ref(s),
            polylines(&h.lines.iter().collect::<Vec<_>>(), 2.0),
            t,
            None,
            &ropts,
        )
    };
    let img = side_by_side(
        &[
            pic(&dented, &before, "dented panel")?,
            pic(&faired, &after, "after fairing")?,
        ],
        &["before", "after"],
    );
    let file = demo.save("bspline-fairing.png", &img)?;
    let mut plot = uv_plot(
        &dented,
        "pre-images: before (grey), after (colour), targets (black)",
    );
    for l in &before.lines {
        plot.polyline(&l.uv, [170, 170, 170], 2.5);
    }
    plot_lines(&mut plot, &after.lines.iter().collect::<Vec<_>>(), 1.2);
    for t in &rep.targets {
        plot.polyline(&t.samples, [0, 0, 0], 0.8);
        plot.marker(t.start, palette_srgb(t.light), "");
        plot.marker(t.end, palette_srgb(t.light), "");
    }
    plot.write(demo.out.join("bspline-fairing-uv.svg"))?;
    // The same pre-images as a picture: before (grey), after (colour),
    // targets (black).
    let mut uv_lines: Vec<UvLine> = Vec::new();
    for l in &before.lines {
        uv_lines.push((l.uv.clone(), [0.95, 0.75, 0.2], 5.0));
    }
    for l in &after.lines {
        uv_lines.push((l.uv.clone(), PALETTE[l.light % PALETTE.len()], 1.6));
    }
    for t in &rep.targets {
        uv_lines.push((t.samples.clone(), [0.0, 0.0, 0.0], 1.0));
    }
    let uv_file = demo.save(
        "bspline-fairing-uv.png",
        &uv_picture(
            &dented,
            &uv_lines,
            "(u, v) pre-images: before amber, after colour, targets black",
            (900, 900),
        )?,
    )?;
    write_surfaces_json(demo.out.join("bspline-panel-dented.json"), &[dented])?;
    write_surfaces_json(demo.out.join("bspline-panel-faired.json"), &[faired])?;
    // the lights and endpoints as files, so that the same fairing can be
    // run from the shell: fairline fair-surface bspline-panel-dented.json
    //   --lights bspline-panel-lights.json --endpoints bspline-panel-endpoints.json
    let light_file = fairline::highlight::CircularLights {
        center: a.to_array(),
        axis: [0.0, 0.0, 1.0],
        radii: lights.iter().map(|l| l.radius()).collect(),
    };
    write_json(&demo.out.join("bspline-panel-lights.json"), &light_file)?;
    write_json(
        &demo.out.join("bspline-panel-endpoints.json"),
        &fairline::fair::Endpoints { endpoints },
    )?;
    Ok(Section {
        title: "B-spline fairing".into(),
        text: "A bicubic roof-panel-like B-spline surface (21 x 22 control points) with one control point pushed down: 11 concentric circular lights above it show the dent as kinks in their highlight lines. The stretches around the dent are replaced by cubic Hermite targets in (u, v) and the control points over the knot box of the endpoints are moved by Gauss-Newton with a truncated SVD (Nishiyama et al.); everything else is unchanged. ".into(),
        images: vec![
            (file, "circular highlight lines before | after".into()),
            (uv_file, "(u, v) pre-images".into()),
            ("bspline-fairing-uv.svg".into(), "(u, v) pre-images, SVG".into()),
        ],
        values: json!({
            "stretches": rep.targets.len(),
            "modified_control_points": rep.modified_control_points,
            "iterations": rep.iterations,
            "converged": rep.converged,
            "stop": rep.stop,
            "residual_before_mean": rep.residual_before.mean,
            "residual_after_mean": rep.residual_after.mean,
            "residual_before_max": rep.residual_before.max,
            "residual_after_max": rep.residual_after.max,
        }),
    })
}
