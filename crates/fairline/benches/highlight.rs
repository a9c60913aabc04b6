//! Benchmarks of highlight lines (Yong et al. Algorithm 1) on smooth,
//! irregularly triangulated height fields of about 110k, 450k, 1M and 2M
//! vertices: the whole model (normals, distances, nodes, polylines), the
//! incremental update after a local change of a few hundred vertices,
//! circular lights (Nishiyama et al. Eq. (2.18) per vertex), bands and
//! irregularity detection. Prints Markdown tables of median wall times.
//!
//! Run: `cargo bench -p fairline --bench highlight`
//! (`FAIRLINE_BENCH_RUNS`, `FAIRLINE_BENCH_SIZES` override runs and sizes;
//! `FAIRLINE_BENCH_ONLY=model` runs only the whole-model table;
//! `FAIRLINE_BENCH_ONLY=defaults` only the table with the default lights a
//! command chooses for a part, on the 450k height field, on the
//! Stanford bunny scan of ../shared/data split to 557k vertices, and on
//! that split scan cut to about 450k vertices, in the scan's own order).

mod common;

use common::{cpu_ns, cut_to, median_secs, row, runs, sizes, split4, test_surface};
use fairline::Vec3;
use fairline::geom;
use fairline::highlight::{
    CircularLight, DetectOptions, HighlightModel, HighlightOptions, LightArray, Readability,
    UpAxis, circular_highlight_lines, detect_irregularities,
};
use fairline::mesh::{SurfaceMesh, VertexId, bounding_box};

fn light_for(mesh: &SurfaceMesh) -> LightArray {
    let (lo, hi) = bounding_box(mesh.positions()).expect("vertices");
    // about 40 lights across the panel: a dense array, as used for judging
    let l = LightArray::default_for(lo, hi, None);
    l.with_spacing(l.spacing() / 2.0).expect("spacing")
}

fn ms(s: f64) -> String {
    format!("{:.1}", s * 1e3)
}

/// "wall median (CPU per run)" in ms over `runs` calls of `f` after a warm-up.
fn timed<T>(runs: usize, mut f: impl FnMut() -> T) -> String {
    std::hint::black_box(f());
    let c0 = cpu_ns();
    let wall = median_secs(runs, f);
    // median_secs makes one extra warm-up call
    let cpu = (cpu_ns() - c0) as f64 * 1e-9 / (runs + 1) as f64;
    format!("{} ({})", ms(wall), ms(cpu))
}

/// The default lights of a part, as `fairline highlight` chooses them with
/// no options: the readable spacing, and the model with all its nodes.
fn default_lights_table(runs: usize, opts: HighlightOptions) {
    let mut meshes: Vec<(String, SurfaceMesh)> =
        vec![("height field".into(), test_surface(450_000))];
    let bunny = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/meshes/bunny_zipper.ply");
    match fairline::io::read_mesh(&bunny) {
        Ok(m) => {
            let split = split4(&m, 2);
            let cut = cut_to(&split, 450_000);
            meshes.push(("bunny_zipper split 4x4".into(), split));
            meshes.push(("bunny_zipper split 4x4, cut to 450k".into(), cut));
        }
        Err(e) => println!("(bunny scan skipped: {e})"),
    }
    println!(
        "\nDefault lights of the part (readable_for_mesh, up auto): wall median of {runs} runs (CPU per run), ms\n"
    );
    row(&[
        "mesh".into(),
        "vertices".into(),
        "choose lights ms".into(),
        "model ms".into(),
        "model + polylines ms".into(),
        "readable drawing ms".into(),
        "spacing / width".into(),
        "lines".into(),
        "nodes".into(),
    ]);
    row(&vec!["---".to_string(); 9]);
    for (name, mesh) in &meshes {
        let t_choose = timed(runs, || LightArray::readable_for_mesh(mesh, UpAxis::Auto));
        let light = LightArray::readable_for_mesh(mesh, UpAxis::Auto).expect("vertices");
        let t_model = timed(runs, || {
            HighlightModel::new(mesh, light, opts.clone()).expect("tri")
        });
        let t_total = timed(runs, || {
            HighlightModel::new(mesh, light, opts.clone())
                .expect("tri")
                .lines(mesh)
        });
        let model = HighlightModel::new(mesh, light, opts.clone()).expect("tri");
        let lines = model.lines(mesh);
        let r = Readability::for_part(mesh, &light);
        let t_draw = timed(runs, || model.readable_lines(mesh, &lines, &r));
        let width = fairline::highlight::readable::part_width(mesh.positions(), light.across());
        row(&[
            name.clone(),
            mesh.vertex_count().to_string(),
            t_choose,
            t_model,
            t_total,
            t_draw,
            format!("1/{:.1}", width / light.spacing()),
            lines.lines.len().to_string(),
            lines.node_count().to_string(),
        ]);
    }
}

fn main() {
    let runs = runs(7);
    let opts = HighlightOptions::default();
    if std::env::var("FAIRLINE_BENCH_ONLY").is_ok_and(|s| s == "defaults") {
        default_lights_table(runs, opts);
        return;
    }
    let sizes = sizes(&[110_000, 450_000, 1_000_000, 2_000_000]);
    let meshes: Vec<SurfaceMesh> = sizes.iter().map(|&n| test_surface(n)).collect();

    println!(
        "\nWhole model (normals + distances + nodes + polylines): wall median of {runs} runs (CPU time per run, all threads), ms\n"
    );
    row(&[
        "vertices".into(),
        "normals ms".into(),
        "model (normals, distances, segments) ms".into(),
        "polylines ms".into(),
        "total ms".into(),
        "CPU ns / vertex".into(),
        "lines".into(),
        "nodes".into(),
    ]);
    row(&vec!["---".to_string(); 8]);
    for mesh in &meshes {
        let light = light_for(mesh);
        let t_norm = timed(runs, || geom::vertex_normals(mesh));
        let t_model = timed(runs, || {
            HighlightModel::new(mesh, light, opts.clone()).expect("tri")
        });
        let model = HighlightModel::new(mesh, light, opts.clone()).expect("tri");
        let t_lines = timed(runs, || model.lines(mesh));
        let c0 = cpu_ns();
        let w_total = median_secs(runs, || {
            HighlightModel::new(mesh, light, opts.clone())
                .expect("tri")
                .lines(mesh)
        });
        let c_total = (cpu_ns() - c0) as f64 * 1e-9 / (runs + 1) as f64;
        let lines = model.lines(mesh);
        row(&[
            mesh.vertex_count().to_string(),
            t_norm,
            t_model,
            t_lines,
            format!("{} ({})", ms(w_total), ms(c_total)),
            format!("{:.0}", c_total * 1e9 / mesh.vertex_count() as f64),
            lines.lines.len().to_string(),
            lines.node_count().to_string(),
        ]);
    }

    if std::env::var("FAIRLINE_BENCH_ONLY").is_ok_and(|s| s == "model") {
        return;
    }

    println!(
        "\nIncremental update after moving a disc of vertices along their normals: wall median of {runs} runs (CPU per run), ms\n"
    );
    row(&[
        "vertices".into(),
        "moved".into(),
        "recomputed".into(),
        "update ms".into(),
        "update + polylines ms".into(),
        "full rebuild + polylines ms".into(),
    ]);
    row(&vec!["---".to_string(); 6]);
    for mesh in &meshes {
        let light = light_for(mesh);
        let p = mesh.positions();
        // the ~300 vertices nearest to a point of the panel
        let c = Vec3::new(0.3, -0.2, 0.0);
        let mut by_dist: Vec<(f64, u32)> = p
            .iter()
            .enumerate()
            .map(|(i, q)| (((q.x - c.x).powi(2) + (q.y - c.y).powi(2)), i as u32))
            .collect();
        by_dist.select_nth_unstable_by(300, |a, b| a.0.total_cmp(&b.0));
        let moved: Vec<VertexId> = by_dist[..300].iter().map(|&(_, i)| VertexId(i)).collect();
        let normals = geom::vertex_normals(mesh);
        let mut moved_mesh = mesh.clone();
        for &v in &moved {
            moved_mesh.positions_mut()[v.idx()] += 1e-3 * normals[v.idx()];
        }
        let base = HighlightModel::new(mesh, light, opts.clone()).expect("tri");
        let mut recomputed = 0;
        let mut only = Vec::new();
        let mut both = Vec::new();
        for _ in 0..runs {
            let mut m = base.clone();
            let t = std::time::Instant::now();
            recomputed = m.update(&moved_mesh, &moved).expect("update");
            only.push(t.elapsed().as_secs_f64());
            std::hint::black_box(m.lines(&moved_mesh));
            both.push(t.elapsed().as_secs_f64());
        }
        only.sort_by(f64::total_cmp);
        both.sort_by(f64::total_cmp);
        let t_full = timed(runs, || {
            HighlightModel::new(&moved_mesh, light, opts.clone())
                .expect("tri")
                .lines(&moved_mesh)
        });
        row(&[
            mesh.vertex_count().to_string(),
            moved.len().to_string(),
            recomputed.to_string(),
            format!("{:.3}", only[only.len() / 2] * 1e3),
            ms(both[both.len() / 2]),
            t_full,
        ]);
    }

    println!(
        "\nCircular lights (3 radii), bands and detection: wall median (CPU per run), ms; {} runs for circular and detect\n",
        runs.min(3)
    );
    row(&[
        "vertices".into(),
        "circular, 3 radii ms".into(),
        "linear bands ±ρ ms".into(),
        "detect (model + detection) ms".into(),
    ]);
    row(&vec!["---".to_string(); 4]);
    for mesh in &meshes {
        let light = light_for(mesh);
        let circles: Vec<CircularLight> = [0.3, 0.6, 0.9]
            .iter()
            .map(|&r| CircularLight::new(Vec3::new(0.0, 0.0, 3.0), Vec3::Z, r).expect("light"))
            .collect();
        let heavy = runs.min(3);
        let t_circ = timed(heavy, || {
            circular_highlight_lines(mesh, &circles, &HighlightOptions::default()).expect("tri")
        });
        let model = HighlightModel::new(mesh, light, opts.clone()).expect("tri");
        let t_band = timed(runs, || model.bands(mesh, 0.1 * light.spacing()));
        let det_opts = DetectOptions::default();
        let t_det = timed(heavy, || {
            let m = HighlightModel::new(mesh, light, opts.clone()).expect("tri");
            let lines = m.lines(mesh);
            detect_irregularities(mesh, &light, &lines, &det_opts).expect("detect")
        });
        row(&[mesh.vertex_count().to_string(), t_circ, t_band, t_det]);
    }
}
