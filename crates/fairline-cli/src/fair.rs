//! `fairline fair`: highlight-line fairing of a triangle mesh (Yong et al.
//! §3, Algorithm 2) inside a region, with the surface-diffusion-flow
//! baseline for comparison.

use crate::args::{LightArgs, choice};
use crate::common::{print_warnings, write_report};
use crate::error::bad_input;
use crate::output::{progress, say};
use anyhow::Result;
use fairline::fair::{FairMethod, FairOptions, FairReport};
use fairline::mesh::FaceId;
use fairline::picture::{
    FAIRING_DESIRED_COLOR, FAIRING_LINE_COLOR, FAIRING_OUTLINE_COLOR, fairing_picture,
};
use fairline::render::{ReflectionZebra, RenderOptions};
use fairline::{Control, SurfaceMesh};
use fairline_commands::fair::{self, FairInput, FairSettings};
use fairline_commands::{CommandError, FrontEnd, Note, Subject};
use std::path::{Path, PathBuf};

/// Removes a local irregularity so that the highlight lines inside a region
/// follow smooth desired curves (optimized geometric Hermite curves between
/// the nodes just outside the region), moving only vertices whose motion
/// changes nothing outside the region: every vertex, normal and highlight
/// node outside stays bit-identical. The region is region JSON
/// ({"faces":[..]}, {"vertices":[..]} or {"sphere":{"center":[x,y,z],"radius":r}}),
/// e.g. the output of `fairline detect` (which already holds the two rings
/// of support faces fairing needs: a vertex can move only when all faces
/// around it and around its neighbours are in the region); --grow N adds N
/// rings of faces to any region. With --auto the irregular regions are
/// detected, grown by four rings and faired in turn. The report measures
/// the detection score (`fairline detect`) inside the region before and
/// after with the same lights, and runs detection on the result: when it
/// still flags a region (inside or outside the faired one, each site
/// against its own threshold, exactly as `detect` on the output would), a
/// warning names it and says what to do. Use the same light options as for
/// `highlight`/`detect`: the detection scores are measured with those
/// lights (report key "light"), the fairing works on the lines `highlight`
/// and `detect` draw ("fairing_light": every k-th line on round parts,
/// whose detail lines lie a fraction of an edge apart; the same lights on
/// panels and whenever --spacing or --lights is given).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline fair fairline-demo/dented-panel.obj --region fairline-demo/dented-panel-region.json -o panel-faired.obj --png fair.png --report fair.json\n  fairline detect fairline-demo/dented-panel.obj -o region.json && fairline fair fairline-demo/dented-panel.obj --region region.json -o faired.obj\n  fairline fair fairline-demo/dented-panel.obj --auto -o faired-auto.obj\n  fairline fair fairline-demo/dented-panel.obj --region fairline-demo/dented-panel-region.json --method diffusion-flow -o flow.obj\n  fairline fair fairline-demo/dented-panel.obj --region fairline-demo/dented-panel-region.json --method paper -o paper.obj"
)]
pub struct Args {
    /// Input triangle mesh.
    pub mesh: PathBuf,
    /// Region JSON.
    #[arg(
        long,
        value_name = "REGION.json",
        required_unless_present = "auto",
        conflicts_with = "auto"
    )]
    pub region: Option<PathBuf>,
    /// Detect irregular regions and fair each in turn.
    #[arg(long)]
    pub auto: bool,
    /// Grow the region by N rings of faces (faces sharing a vertex with it)
    /// before fairing.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub grow: usize,
    #[command(flatten)]
    pub light: LightArgs,
    /// Output mesh (.obj .ply .off .stl).
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// Most iterations N_max.
    #[arg(long, default_value_t = FairOptions::default().max_iterations)]
    pub max_iterations: usize,
    /// Stop when max|x_i| / mean edge length < epsilon (Eq. (17)).
    #[arg(long, default_value_t = FairOptions::default().epsilon)]
    pub epsilon: f64,
    /// Energy to minimise: highlight (Yong et al.'s energy with the desired
    /// curves' end tangents from a smooth surface fitted beyond the
    /// defect's footprint, then ¾ of that result + ¼ of the diffusion-flow
    /// result; --laplacian-weight adds a curvature-Laplacian term), paper
    /// (Yong et al. exactly, Algorithm 2), diffusion-flow (the baseline,
    /// Xu et al.), or an energy of the Grüner thesis minimised over the
    /// movable vertices without lights: membrane (ΔX = 0), thin-plate
    /// (Δ²X = 0) or mvs (minimum variation of curvature, Δ³X = 0).
    #[arg(long, value_parser = choice::<FairMethod>(), default_value = "highlight")]
    pub method: FairMethod,
    /// Weight ω1 of the Willmore (fairness) energy.
    #[arg(long, default_value_t = FairOptions::default().fair_weight)]
    pub fair_weight: f64,
    /// Weight ω2 of the highlight-line difference energy.
    #[arg(long, default_value_t = FairOptions::default().diff_weight)]
    pub diff_weight: f64,
    /// Weight ω3 of the curvature-Laplacian fairness term
    /// D⁴ ∫(Δ_B H)² dA (D the region's diameter); --method highlight only.
    #[arg(long, default_value_t = FairOptions::default().laplacian_weight)]
    pub laplacian_weight: f64,
    /// Keep the highlight-line result (¾ highlight + ¼ diffusion flow)
    /// even where it does not dominate the diffusion-flow state; by
    /// default (least change) the flow state is kept unless the highlight
    /// result's lines are nearer the desired curves and it moves the
    /// region at least 1 % less. --method highlight only.
    #[arg(long)]
    pub no_least_change: bool,
    /// Before/after picture with highlight lines, region outline and
    /// desired curves.
    #[arg(long, value_name = "IMG.png")]
    pub png: Option<PathBuf>,
    #[command(flatten)]
    pub zebra: crate::args::ZebraArgs,
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

impl Args {
    /// The command layer's settings of these arguments.
    fn settings(&self, lights: fairline_commands::Lights) -> FairSettings {
        FairSettings {
            auto: self.auto,
            grow: self.grow,
            lights,
            max_iterations: self.max_iterations,
            epsilon: self.epsilon,
            method: self.method,
            fair_weight: self.fair_weight,
            diff_weight: self.diff_weight,
            laplacian_weight: self.laplacian_weight,
            least_change: !self.no_least_change,
        }
    }
}

/// The region file's faces on `mesh`; errors name the file.
fn read_region(path: &Path, mesh: &SurfaceMesh) -> Result<Vec<FaceId>> {
    let spec = fairline::io::read_region(path).map_err(|e| bad_input(e.to_string()))?;
    spec.faces(mesh)
        .map_err(|e| bad_input(format!("{}: {e}", path.display())))
}

/// A failure of the command layer with the input it is about named: the
/// mesh or the region file.
fn name_subject(e: CommandError, args: &Args) -> anyhow::Error {
    let path = match e.subject() {
        Some(Subject::Input) => Some(args.mesh.as_path()),
        Some(Subject::Region) => args.region.as_deref(),
        _ => None,
    };
    match path {
        Some(p) => anyhow::Error::new(e).context(p.display().to_string()),
        None => anyhow::Error::new(e),
    }
}

pub fn run(args: Args) -> Result<()> {
    let job = crate::output::Job::new("fair")
        .input(&args.mesh)
        .input_opt(args.region.as_deref())
        .input_opt(args.light.lights.as_deref())
        .output("-o", &args.output)
        .output_opt("--png", args.png.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    let mesh = crate::input::read_mesh(&args.mesh)?;
    crate::input::note_split_vertices(&args.mesh, &mesh);
    let region = match &args.region {
        Some(path) => Some(read_region(path, &mesh)?),
        None => None,
    };
    let settings = args.settings(args.light.lights()?);
    let name = args.mesh.display().to_string();
    let input = FairInput {
        mesh: &mesh,
        region: region.as_deref(),
        name: Some(&name),
    };
    let bar = progress(0, "fairing");
    let shown = bar.clone();
    let control = Control::new().on_progress(move |p| {
        shown.set_length(p.total);
        shown.set_position(p.done);
    });
    let mut out = fair::run(input, &settings, &control).map_err(|e| name_subject(e, &args))?;
    bar.finish_and_clear();
    for note in &out.notes {
        if *note == Note::NothingDetected {
            continue; // the summary line says it
        }
        say(&format!(
            "note: {}",
            note.message(FrontEnd::Cli, Some(&name))
        ));
    }
    fairline::io::write_mesh(&args.output, &out.mesh)?;
    print_warnings(&out.report);
    let zebra = match (&args.png, &out.first) {
        (Some(png), Some((positions, r))) => {
            let mut faired = mesh.clone();
            faired.set_positions(positions.clone())?;
            write_picture(png, &mesh, out.fairing_light, r, &faired, &args.zebra)?
        }
        (Some(png), None) => {
            write_unchanged_picture(png, &args.mesh, &mesh, out.fairing_light, &args.zebra)?
        }
        _ => None,
    };
    if let Some(z) = &zebra {
        out.report.set("zebra", crate::args::zebra_json(z));
    }
    write_report(args.report.as_deref(), &out.report)?;
    if out.nothing_to_fair() {
        // what was asked: fair what detection finds; it found nothing
        job.finish(format_args!(
            "nothing to fair (--auto found no defect above the detection threshold {:.2}; the output is the input unchanged)",
            out.before.threshold
        ))?;
        return Ok(());
    }
    if out.nothing_faired() {
        job.finish(format_args!(
            "no region faired of the {} detected (none has a vertex free to move; the output is the input unchanged)",
            out.regions
        ))?;
        anyhow::bail!(
            "{}: detection found {} region(s) to fair, but none has a vertex free to move; {} is the input unchanged",
            args.mesh.display(),
            out.regions,
            args.output.display()
        );
    }
    let (before, after) = (&out.before, &out.after);
    let (floor, flat_before) = (before.detection.flat_spot_floor, before.flat_spot);
    let flat_spot = if floor > 0.0 && flat_before > floor {
        format!(
            ", flat spot {flat_before:.2} → {:.2} (floor {floor:.2})",
            after.flat_spot
        )
    } else {
        String::new()
    };
    let (dev_before, dev_after) = out.deviation();
    let kept_flow = out.results.iter().filter(|r| r.kept_flow).count();
    let least_change = if kept_flow > 0 {
        format!(
            ", diffusion-flow state kept in {kept_flow} of {} (least change)",
            out.results.len()
        )
    } else {
        String::new()
    };
    job.finish(format_args!(
        "{} region(s) faired, {}, detection score {:.2} → {:.2} (threshold {:.2}){flat_spot}, highlight deviation {dev_before:.3e} → {dev_after:.3e}, largest move {:.3e}{least_change}",
        out.results.len(),
        if out.converged() { "converged" } else { "not converged" },
        before.score,
        after.score,
        before.threshold,
        out.largest_move
    ))?;
    if out.made_worse() {
        // the output is written so that it can be looked at, but it is not
        // what was asked for: exit 1 (the warning above says what got worse)
        anyhow::bail!(
            "{}: fairing made the highlight lines worse (deviation {dev_before:.4e} -> {dev_after:.4e}) and detection still flags the region (score {:.2}, threshold {:.2}); {} was written for inspection only",
            args.mesh.display(),
            after.score,
            before.threshold,
            args.output.display()
        );
    }
    Ok(())
}

/// The --png picture when no region was faired: the input's highlight
/// lines under the fairing lights (drawn readable), titled with why the
/// output is the input unchanged; with --zebra the reflection zebra under
/// them, which is returned.
fn write_unchanged_picture(
    png: &std::path::Path,
    path: &std::path::Path,
    mesh: &SurfaceMesh,
    light: fairline::highlight::LightArray,
    zebra: &crate::args::ZebraArgs,
) -> Result<Option<ReflectionZebra>> {
    let model = fairline::highlight::HighlightModel::new(mesh, light, Default::default())?;
    let lines = model.lines(mesh);
    let shown = model.readable_lines(
        mesh,
        &lines,
        &fairline::highlight::Readability::for_part(mesh, &light),
    );
    let mut title = format!(
        "{}: nothing faired, the output is the input unchanged",
        path.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    let (size, view) = ((900, 700), crate::render::camera(mesh, None));
    let zebra = zebra.reflection_zebra(
        mesh,
        Some(&light),
        &crate::highlight_png::render_options(size, view),
    )?;
    if let Some(z) = &zebra {
        title.push_str(&format!("; {}", crate::args::zebra_title(z)));
    }
    crate::highlight_png::write(
        size,
        png,
        mesh,
        crate::highlight_png::Overlay {
            lines: &shown,
            bands: None,
            flagged: &[],
            region: None,
            unjudged: None,
            view,
            title,
            spacing: Some(light.spacing()),
            zebra,
        },
    )?;
    Ok(zebra)
}

/// The --png before/after picture of the first region with the lines of
/// the lights it was faired with, `light` (the readable lights: the lines
/// `highlight` and `detect` show with the same options) and their desired
/// curves; with --zebra the reflection zebra of the input's panel under
/// both panels' lines, which is returned.
fn write_picture(
    png: &std::path::Path,
    mesh: &SurfaceMesh,
    light: fairline::highlight::LightArray,
    r: &FairReport,
    faired: &SurfaceMesh,
    zebra: &crate::args::ZebraArgs,
) -> Result<Option<ReflectionZebra>> {
    let mut opts = RenderOptions::with_size(900, 700);
    (opts.view_dir, opts.up) = crate::render::camera(mesh, None);
    let zebra = zebra.reflection_zebra(mesh, Some(&light), &opts)?;
    let mut img = fairing_picture(mesh, faired, r, zebra, &opts)?;
    let mut key = vec![
        (
            FAIRING_LINE_COLOR,
            format!(
                "highlight lines, light spacing {}",
                crate::highlight_png::fmt_len(light.spacing())
            ),
        ),
        (FAIRING_OUTLINE_COLOR, "region outline".into()),
        (FAIRING_DESIRED_COLOR, "desired lines (before)".into()),
    ];
    if let Some(z) = &zebra {
        key.push(([0.02, 0.02, 0.02], crate::args::zebra_title(z)));
    }
    crate::highlight_png::draw_key(&mut img, &key);
    img.write_png(png)?;
    Ok(zebra)
}
