//! Background jobs: smoothing, fairing and enhancement of a mesh, and the
//! fairing of a surface, run on a worker thread with progress and cancellation.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use fairline::fair::FairMethod;
use fairline::highlight::{CircularLights, LightArray};
use fairline::mesh::{FaceId, VertexId};
use fairline::smooth::SmoothMethod;
use fairline::{Control, SurfaceMesh, Vec3};
use fairline_commands::enhance::EnhanceSettings;
use fairline_commands::fair::{FairInput, FairSettings};
use fairline_commands::fair_quad::QuadSettings;
use fairline_commands::smooth::SmoothSettings;
use fairline_commands::{
    Choice, CommandError, ErrorKind, FrontEnd, Lights, Subject, Weights, enhance, fair, fair_quad,
    smooth,
};
use serde::Deserialize;
use serde_json::{Value, json};

use super::regions::{inside_vertices, to_faces};
use super::{Answer, Job, Shared, bad, error, json_answer, lock, parse};
use crate::view::doc::Step;

#[derive(Deserialize, Default)]
#[serde(default)]
struct RunOptions {
    method: Option<String>,
    max_iterations: Option<usize>,
    epsilon: Option<f64>,
    least_change: Option<bool>,
    iterations: Option<usize>,
    lambda: Option<f64>,
    mu: Option<f64>,
    weights: Option<String>,
    weight: Option<f64>,
}

#[derive(Deserialize)]
struct RunRequest {
    method: String,
    /// fair-surface: the patch, the circular lights and the endpoints
    /// `[{"radius","start":[u,v],"end":[u,v]}]` (DESIGN.md §5).
    #[serde(default)]
    patch: usize,
    circular: Option<CircularLights>,
    endpoints: Option<Value>,
    #[serde(default)]
    faces: Option<Vec<u32>>,
    light: Option<LightArray>,
    #[serde(default)]
    options: RunOptions,
}

/// What a finished job gives: new positions, report, command, label.
struct Outcome {
    positions: Vec<Vec3>,
    surfaces: Option<Arc<Vec<fairline::bspline::BSplineSurface>>>,
    report: Value,
    command: String,
    label: String,
}

pub(super) fn start_job(shared: &Arc<Shared>, k: usize, body: &[u8]) -> Answer {
    let req: RunRequest = match parse(body) {
        Ok(r) => r,
        Err(a) => return a,
    };
    let mut st = lock(shared);
    if st
        .job
        .as_ref()
        .is_some_and(|j| matches!(j.state, "running" | "cancelling"))
    {
        return error(409, "a job is still running; wait for it or cancel it");
    }
    let d = &st.docs[k];
    if d.is_surface() != (req.method == "fair-surface") {
        return bad(if d.is_surface() {
            "this document is a B-spline surface: its method is fair-surface"
        } else {
            "fair-surface needs a B-spline surface document"
        });
    }
    let surface_input = d.current().surfaces.clone().map(|s| (s, d.grid));
    let tri = d.tri_at(None);
    let mesh = d.mesh_now();
    let file = d.current_file();
    let out = d.next_file();
    let id = st.next_job;
    st.next_job += 1;
    let cancel = Arc::new(AtomicBool::new(false));
    st.job = Some(Job {
        id,
        doc: k,
        label: req.method.clone(),
        state: "running",
        progress: 0.0,
        stage: "",
        message: format!("{} running", req.method),
        report: Value::Null,
        command: String::new(),
        cancel: Arc::clone(&cancel),
        started: Instant::now(),
    });
    drop(st);
    let ctx = JobContext {
        id,
        doc: k,
        cancel,
        progress: Arc::new(Mutex::new(JobProgress::default())),
    };
    let shared = Arc::clone(shared);
    std::thread::spawn(move || {
        let control = job_control(&ctx);
        let (tx, rx) = std::sync::mpsc::channel();
        let worker = std::thread::spawn(move || {
            let r = match surface_input {
                Some((surfaces, grid)) => {
                    run_fair_surface(&req, &surfaces, grid, &file, &out, &control)
                }
                None => run_method(&req, &tri, &mesh, &file, &out, &control),
            };
            let _ = tx.send(());
            r
        });
        // copy the progress into the job while it runs
        while rx
            .recv_timeout(std::time::Duration::from_millis(100))
            .is_err()
            && !worker.is_finished()
        {
            let p = *ctx.progress.lock().unwrap_or_else(|e| e.into_inner());
            let mut st = lock(&shared);
            if let Some(j) = st.job.as_mut()
                && j.id == ctx.id
                && j.state == "running"
            {
                j.progress = p.fraction;
                j.stage = p.stage;
            }
        }
        let result = worker
            .join()
            .unwrap_or_else(|_| Err("the computation panicked".to_string()));
        finish_job(&shared, &ctx, result);
    });
    json_answer(&json!({"job": id}))
}

/// What the library last reported of a running job.
#[derive(Clone, Copy, Default)]
struct JobProgress {
    /// Fraction done, 0..1.
    fraction: f64,
    /// The stage ("iterations" …).
    stage: &'static str,
}

struct JobContext {
    id: u64,
    doc: usize,
    cancel: Arc<AtomicBool>,
    progress: Arc<Mutex<JobProgress>>,
}

/// The [`fairline::Control`] of a job: the job's cancel flag (raised by
/// `POST /api/job/cancel`, the library stops at its next
/// `control.step(..)`) and a progress callback writing the fraction done
/// into the job. Every job's options get it through their builder
/// `.control(..)` where the library's options have one.
fn job_control(ctx: &JobContext) -> Control {
    let progress = Arc::clone(&ctx.progress);
    Control::new()
        .cancel_flag(Arc::clone(&ctx.cancel))
        .on_progress(move |p| {
            let mut slot = progress.lock().unwrap_or_else(|e| e.into_inner());
            slot.stage = p.stage;
            if p.total > 0 {
                slot.fraction = (p.done as f64 / p.total as f64).clamp(0.0, 1.0);
            }
        })
}

fn finish_job(shared: &Shared, ctx: &JobContext, result: Result<Outcome, String>) {
    let mut st = lock(shared);
    let cancelled = ctx.cancel.load(Ordering::SeqCst);
    if cancelled {
        // stopped by the library (its Cancelled error) or finished after
        // the flag was raised: the result is thrown away either way
        if let Some(j) = st.job.as_mut()
            && j.id == ctx.id
        {
            j.state = "cancelled";
            j.message = match &result {
                Err(e) if e == "cancelled" => format!(
                    "{} cancelled after {:.2} s",
                    j.label,
                    j.started.elapsed().as_secs_f64()
                ),
                _ => format!("{} cancelled; its result was discarded", j.label),
            };
        }
        return;
    }
    match result {
        Ok(o) => {
            let d = &mut st.docs[ctx.doc];
            let surfaces = o.surfaces.or_else(|| d.current().surfaces.clone());
            d.push(Step::new(
                o.label.clone(),
                o.command.clone(),
                o.report.clone(),
                Arc::new(o.positions),
                surfaces,
            ));
            if let Some(j) = st.job.as_mut()
                && j.id == ctx.id
            {
                j.state = "done";
                j.progress = 1.0;
                j.message = format!("{} done", o.label);
                j.report = o.report;
                j.command = o.command;
            }
        }
        Err(e) => {
            if let Some(j) = st.job.as_mut()
                && j.id == ctx.id
            {
                j.state = "failed";
                j.message = e;
            }
        }
    }
}

/// Runs a mesh job: the command of the request with the job's `control`
/// (see [`job_control`]: progress and cancellation).
fn run_method(
    req: &RunRequest,
    tri: &SurfaceMesh,
    mesh: &SurfaceMesh,
    file: &str,
    out: &str,
    control: &Control,
) -> Result<Outcome, String> {
    let job = MeshJob {
        req,
        tri,
        mesh,
        file,
        out,
        control,
        faces: req.faces.as_ref().map(|f| to_faces(tri, f)),
    };
    match req.method.as_str() {
        "fair" => job.fair(),
        "smooth" => job.smooth(),
        "fair-quad" => job.fair_quad(),
        "enhance" => job.enhance(),
        other => Err(format!(
            "unknown method `{other}` (fair, smooth, fair-quad, enhance)"
        )),
    }
}

/// One mesh job of [`run_method`]: the request, the document's meshes
/// (`tri` triangulated, `mesh` as loaded), the file names the equivalent
/// command line uses, the job's control and the region's faces (of `tri`).
struct MeshJob<'j> {
    req: &'j RunRequest,
    tri: &'j SurfaceMesh,
    mesh: &'j SurfaceMesh,
    file: &'j str,
    out: &'j str,
    control: &'j Control,
    faces: Option<Vec<FaceId>>,
}

impl MeshJob<'_> {
    /// With a region: every vertex outside it is fixed (none without).
    fn fixed_outside(&self) -> Vec<VertexId> {
        match &self.faces {
            None => Vec::new(),
            Some(f) => {
                let inside = inside_vertices(self.tri, f);
                (0..inside.len() as u32)
                    .filter(|&v| !inside[v as usize])
                    .map(VertexId)
                    .collect()
            }
        }
    }

    /// Highlight-line fairing of the region: the `fair` command with the
    /// page's lights and options, detection before and after included.
    fn fair(&self) -> Result<Outcome, String> {
        let o = &self.req.options;
        let faces = self
            .faces
            .as_ref()
            .ok_or("fairing needs a region (faces)")?;
        let light = self.req.light.ok_or("fairing needs the light array")?;
        let method = match o.method.as_deref() {
            Some(m) => FairMethod::parse(m).map_err(job_error)?,
            None => FairMethod::Highlight,
        };
        let d = FairSettings::default();
        let settings = FairSettings {
            lights: Lights::exactly(&light),
            method,
            max_iterations: o.max_iterations.unwrap_or(d.max_iterations),
            epsilon: o.epsilon.unwrap_or(d.epsilon),
            least_change: o.least_change.unwrap_or(d.least_change),
            ..d
        };
        let input = FairInput {
            mesh: self.tri,
            region: Some(faces),
            name: Some(self.file),
        };
        let out = fair::run(input, &settings, self.control).map_err(job_error)?;
        Ok(Outcome {
            surfaces: None,
            positions: out.mesh.positions().to_vec(),
            report: out.report.to_json(),
            command: settings.command_line(self.file, self.out),
            label: format!("fair ({})", method.name()),
        })
    }

    /// One of the smoothing methods, outside the region fixed: the
    /// `smooth` command with the page's options (cotangent weights unless
    /// the page says otherwise; λ for Laplace smoothing only, Taubin's
    /// comes from the pass band).
    fn smooth(&self) -> Result<Outcome, String> {
        let o = &self.req.options;
        let method =
            SmoothMethod::parse(o.method.as_deref().unwrap_or("taubin")).map_err(job_error)?;
        let weights = Weights::parse(o.weights.as_deref().unwrap_or("cotan")).map_err(job_error)?;
        let settings = SmoothSettings {
            method,
            weights,
            iterations: o.iterations,
            lambda: o.lambda.filter(|_| method == SmoothMethod::Laplace),
            fixed: self.fixed_outside(),
            ..SmoothSettings::default()
        };
        let out = smooth::run(self.mesh, &settings, self.control).map_err(job_error)?;
        // a run that stopped unconverged is not what was asked for: the
        // job fails with the reason, the document keeps its state (so a
        // save cannot write the unconverged result)
        if let Some(e) = out.stopped_error(fairline_commands::FrontEnd::Workbench) {
            return Err(job_error(e));
        }
        Ok(Outcome {
            surfaces: None,
            positions: out.positions,
            report: out.report.to_json(),
            command: settings.command_line(self.file, self.out),
            label: format!("smooth ({})", method.name()),
        })
    }

    /// Structure-line fairing of a quad mesh, outside the region fixed:
    /// the `fair-quad` command with the page's weight and iterations.
    fn fair_quad(&self) -> Result<Outcome, String> {
        let o = &self.req.options;
        let d = QuadSettings::default();
        let settings = QuadSettings {
            weight: o.weight.unwrap_or(d.weight),
            iterations: o.iterations.unwrap_or(d.iterations),
            fixed: self.fixed_outside(),
            ..d
        };
        let out = fair_quad::run(self.mesh, &settings, self.control).map_err(job_error)?;
        Ok(Outcome {
            surfaces: None,
            positions: out.positions,
            report: out.report.to_json(),
            command: settings.command_line(self.file, self.out),
            label: "fair-quad".into(),
        })
    }

    /// Feature enhancement by vertex flow, outside the region fixed: the
    /// `enhance` command with the page's λ, μ and iterations.
    fn enhance(&self) -> Result<Outcome, String> {
        let o = &self.req.options;
        let d = EnhanceSettings::default();
        let settings = EnhanceSettings {
            lambda: o.lambda.unwrap_or(d.lambda),
            mu: o.mu.unwrap_or(d.mu),
            iterations: o.iterations.unwrap_or(d.iterations),
            fixed: self.fixed_outside(),
            ..d
        };
        let out = enhance::run(self.tri, &settings, self.control).map_err(job_error)?;
        Ok(Outcome {
            surfaces: None,
            positions: out.positions,
            report: out.report.to_json(),
            command: settings.command_line(self.file, self.out),
            label: "enhance".into(),
        })
    }
}

/// Circular-highlight fairing of one patch (Nishiyama et al. §3): the
/// command layer's `fair_surface` with the page's lights and endpoints and
/// the library's defaults but for the iterations and ε; the patch is
/// replaced and re-tessellated.
fn run_fair_surface(
    req: &RunRequest,
    surfaces: &Arc<Vec<fairline::bspline::BSplineSurface>>,
    grid: usize,
    file: &str,
    out: &str,
    control: &Control,
) -> Result<Outcome, String> {
    use fairline::fair::Endpoints;
    use fairline_commands::fair_surface::{FairSurfaceInput, FairSurfaceSettings, run};
    let circular = req
        .circular
        .as_ref()
        .ok_or("fair-surface needs the circular lights")?;
    let ends: Endpoints =
        serde_json::from_value(json!({"endpoints": req.endpoints.clone().unwrap_or(Value::Null)}))
            .map_err(|e| format!("endpoints: {e}"))?;
    if req.patch >= surfaces.len() {
        return Err("no such patch".into());
    }
    let d = FairSurfaceSettings::default();
    let settings = FairSurfaceSettings {
        surface: req.patch,
        max_iterations: req.options.max_iterations.unwrap_or(d.max_iterations),
        epsilon: req.options.epsilon.unwrap_or(d.epsilon),
        ..d
    };
    let input = FairSurfaceInput {
        surfaces: surfaces.as_slice(),
        lights: Some(circular),
        endpoints: &ends.endpoints,
    };
    let faired = run(input, &settings, control).map_err(job_error)?;
    let (mesh, _) =
        crate::view::doc::tessellate_all(&faired.surfaces, grid).map_err(|e| e.to_string())?;
    Ok(Outcome {
        positions: mesh.positions().to_vec(),
        surfaces: Some(Arc::new(faired.surfaces)),
        report: faired.report.to_json(),
        command: settings.command_line(file, out),
        label: format!("fair-surface (patch {})", req.patch),
    })
}

/// A failure of the command layer as the job's message: `cancelled` for a
/// cancelled run, else the message worded for the workbench, with the
/// region named when it is about the region.
fn job_error(e: CommandError) -> String {
    match (e.kind(), e.subject()) {
        (ErrorKind::Cancelled, _) => "cancelled".into(),
        (_, Some(Subject::Region)) => format!("region: {}", e.message(FrontEnd::Workbench)),
        (_, Some(Subject::Lights)) => format!("lights: {}", e.message(FrontEnd::Workbench)),
        _ => e.message(FrontEnd::Workbench),
    }
}
