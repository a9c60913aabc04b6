//! `fairline inspect`: the single-file commands over many parts, with a
//! report a person reads in a minute and a machine reads too.
//!
//! A run plans its parts ([`plan`]), runs each part's job ([`part`]) on
//! the local cores — every part in its own child processes, with a time
//! and a memory limit, so a broken or hostile file gets its row with the
//! error and never stops the run — and writes the report ([`page`]).
//! Parts whose content key (file bytes, settings, fairline version) did
//! not change since the last run into the same folder are not redone.
//!
//! The Python package runs the same jobs on a Dask cluster through the
//! hidden modes `--plan` (the parts and whether each is up to date, as
//! JSON on standard output), `--run-part SPEC --part-dir DIR` (one part's
//! job) and `--assemble` (the report from the part folders): the same
//! binary does the same work, so the report is the same bytes.

mod page;
mod part;
mod plan;
mod thumb;

use crate::error::bad_input;
use crate::output::{Job, say};
use anyhow::{Context, Result};
use part::{Limits, PartRecord, Status};
use plan::PartSpec;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Version of the report layout; part of every content key, so a layout
/// change redoes every part.
pub const SCHEMA: &str = "fairline-inspect-1";

/// Judges many parts — meshes and CAD files — with the default settings
/// of the single-file commands, and writes a report folder:
/// `index.html` (a static page that opens from disk: a sortable table of
/// the parts, worst first, with thumbnails, and one page per part with
/// its pictures, regions, numbers and the exact commands that reproduce
/// it), `summary.json`, `summary.csv` and `parts/ID/` with each part's
/// reports and pictures. Meshes: `info`, `repair` when not a manifold,
/// `detect`; CAD parts: `info --area`, `continuity`, `convert` to a mesh
/// and `detect`. Folders are searched recursively by extension; a
/// manifest (CSV or JSON) lists parts with their own settings (up axis,
/// lights, detection threshold, G0 tolerance). Every part runs in its own
/// processes with a time and a memory limit; a file that cannot be read
/// gets its row with the error. A re-run into the same folder redoes only
/// the parts whose file, settings or fairline version changed. The
/// report's bytes do not depend on --jobs. Exit status 1 when any part
/// failed (its row says why).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  fairline inspect ../shared/data -o report\n  fairline inspect parts/ --manifest settings.csv --jobs 4 -o report\n  fairline inspect a.ply b.igs -o report --part-timeout 120\n\nManifest (CSV, paths relative to the manifest):\n  path,up,lights,threshold,tolerance\n  door.ply,y,,,\n  hood.step,,,,0.01\n\nOn a Dask cluster, from Python:\n  from dask.distributed import Client\n  fairline.inspect([\"parts/\"], \"report\", client=Client(\"tcp://scheduler:8786\"))"
)]
pub struct Args {
    /// Part files (.obj .ply .off .stl .igs .iges .step .stp .json) and
    /// folders to search.
    pub paths: Vec<PathBuf>,
    /// Manifest of parts with per-part settings (CSV with a header naming
    /// path, up, lights, threshold, tolerance; or JSON). May be repeated.
    #[arg(long, value_name = "FILE")]
    pub manifest: Vec<PathBuf>,
    /// Report folder (created; an existing one must be empty or made by
    /// an earlier fairline run).
    #[arg(
        short,
        long,
        value_name = "REPORT_DIR",
        required_unless_present = "run_part"
    )]
    pub output: Option<PathBuf>,
    /// Parts judged at the same time (default: the number of cores).
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Wall time for one part's commands together, in seconds.
    #[arg(long, value_name = "S", default_value_t = 600.0)]
    pub part_timeout: f64,
    /// Memory of each of a part's processes, in MiB (0: no limit).
    #[arg(long, value_name = "MIB", default_value_t = 8192)]
    pub part_memory: u64,
    /// Redo every part, also those that did not change.
    #[arg(long)]
    pub force: bool,
    /// Print the planned parts as JSON on standard output and stop.
    #[arg(long, hide = true)]
    pub plan: bool,
    /// Run one part's job (its plan entry as JSON) into --part-dir.
    #[arg(long, hide = true, value_name = "SPEC")]
    pub run_part: Option<String>,
    /// The folder --run-part writes into (created; must not exist).
    #[arg(long, hide = true, value_name = "DIR", requires = "run_part")]
    pub part_dir: Option<PathBuf>,
    /// Write the report from the part folders already in REPORT_DIR.
    #[arg(long, hide = true)]
    pub assemble: bool,
}

/// One planned part with its key and whether its folder is up to date.
#[derive(serde::Serialize, serde::Deserialize)]
struct Planned {
    #[serde(flatten)]
    spec: PartSpec,
    key: String,
    up_to_date: bool,
}

pub fn run(args: Args) -> Result<()> {
    if !(args.part_timeout.is_finite() && args.part_timeout > 0.0) {
        return Err(bad_input(format!(
            "--part-timeout {}: give a positive number of seconds",
            args.part_timeout
        )));
    }
    let limits = Limits {
        timeout: Duration::from_secs_f64(args.part_timeout.min(1e7)),
        memory_mb: (args.part_memory > 0).then_some(args.part_memory),
        threads: 0,
    };
    let exe = std::env::current_exe().context("cannot find the fairline binary itself")?;
    if let Some(spec) = &args.run_part {
        return run_one(&exe, spec, args.part_dir.as_deref(), &limits);
    }
    if args.paths.is_empty() && args.manifest.is_empty() {
        return Err(bad_input(
            "give part files, folders or --manifest FILE (see fairline inspect --help)",
        ));
    }
    let output = args
        .output
        .clone()
        .ok_or_else(|| bad_input("give the report folder with -o REPORT_DIR"))?;
    let job = Job::new("inspect");
    let (specs, ignored) = plan::plan(&args.paths, &args.manifest)?;
    crate::output::owned_folder("-o", &output)?;
    let parts_dir = output.join("parts");
    std::fs::create_dir_all(&parts_dir)
        .map_err(|e| bad_input(format!("{}: {e}", parts_dir.display())))?;
    let planned = keyed(&parts_dir, args.force, specs);
    if args.plan {
        let text = serde_json::to_string_pretty(&planned)? + "\n";
        return crate::output::print_stdout(&text);
    }
    let records = if args.assemble {
        load_all(&parts_dir, &planned)?
    } else {
        run_all(&exe, &parts_dir, &planned, &limits, jobs(args.jobs))
    };
    page::write_report(&output, &records, ignored)?;
    finish(&job, &output, &records, &planned)
}

/// Each spec with its content key and whether the part's folder already
/// holds a record of that key (never, with --force).
fn keyed(parts_dir: &Path, force: bool, specs: Vec<PartSpec>) -> Vec<Planned> {
    let mut planned = Vec::with_capacity(specs.len());
    for spec in specs {
        // an unreadable file still gets a row: its key is its path's
        let key = plan::content_key(&spec).unwrap_or_else(|e| format!("unreadable: {e}"));
        let up_to_date =
            !force && load_record(&parts_dir.join(&spec.id)).is_some_and(|r| r.key == key);
        planned.push(Planned {
            spec,
            key,
            up_to_date,
        });
    }
    planned
}

fn jobs(requested: Option<usize>) -> usize {
    requested
        .filter(|&n| n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

fn load_record(dir: &Path) -> Option<PartRecord> {
    serde_json::from_slice(&std::fs::read(dir.join("part.json")).ok()?).ok()
}

/// `--run-part`: one part's job into a new folder.
fn run_one(exe: &Path, spec: &str, dir: Option<&Path>, limits: &Limits) -> Result<()> {
    let planned: Planned =
        serde_json::from_str(spec).map_err(|e| bad_input(format!("--run-part: {e}")))?;
    let dir = dir.ok_or_else(|| bad_input("--run-part needs --part-dir"))?;
    std::fs::create_dir(dir).map_err(|e| bad_input(format!("{}: {e}", dir.display())))?;
    part::run_part(exe, &planned.spec, &planned.key, dir, limits);
    Ok(())
}

/// `--assemble`: every part's record from its folder.
fn load_all(parts_dir: &Path, planned: &[Planned]) -> Result<Vec<PartRecord>> {
    planned
        .iter()
        .map(|p| {
            load_record(&parts_dir.join(&p.spec.id))
                .filter(|r| r.key == p.key)
                .ok_or_else(|| {
                    anyhow::anyhow!(
                        "{}: no up-to-date result in {} (run the part first)",
                        p.spec.path.display(),
                        parts_dir.join(&p.spec.id).display()
                    )
                })
        })
        .collect()
}

/// Runs the parts that are not up to date on `jobs` threads (each part in
/// its own processes), with progress on standard error; returns every
/// part's record in plan order.
fn run_all(
    exe: &Path,
    parts_dir: &Path,
    planned: &[Planned],
    limits: &Limits,
    jobs: usize,
) -> Vec<PartRecord> {
    let todo: Vec<usize> = (0..planned.len())
        .filter(|&k| !planned[k].up_to_date)
        .collect();
    let progress = Progress::new(todo.len(), planned.len() - todo.len());
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<PartRecord>>> = Mutex::new(vec![None; planned.len()]);
    // each part's commands use the cores left to it
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads_each = (cores / jobs.max(1)).max(1);
    std::thread::scope(|s| {
        for _ in 0..jobs.min(todo.len()) {
            s.spawn(|| {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&i) = todo.get(k) else { break };
                    let p = &planned[i];
                    let record = run_into_place(exe, parts_dir, p, limits, threads_each);
                    progress.done(&record);
                    if let Ok(mut r) = results.lock() {
                        r[i] = Some(record);
                    }
                }
            });
        }
    });
    progress.finish();
    let mut results = results.into_inner().unwrap_or_default();
    planned
        .iter()
        .enumerate()
        .map(|(i, p)| {
            results[i]
                .take()
                .or_else(|| load_record(&parts_dir.join(&p.spec.id)))
                .unwrap_or_else(|| failed_record(p, "the part's result went missing"))
        })
        .collect()
}

/// Runs one part into a hidden folder beside its final one, then puts it
/// in place (the old result is replaced whole, never mixed).
fn run_into_place(
    exe: &Path,
    parts_dir: &Path,
    p: &Planned,
    limits: &Limits,
    threads: usize,
) -> PartRecord {
    let tmp = parts_dir.join(format!(".{}.{}.tmp", p.spec.id, std::process::id()));
    let dest = parts_dir.join(&p.spec.id);
    let _ = std::fs::remove_dir_all(&tmp);
    if let Err(e) = std::fs::create_dir(&tmp) {
        return failed_record(p, &format!("cannot create {}: {e}", tmp.display()));
    }
    let limits = Limits { threads, ..*limits };
    let record = part::run_part(exe, &p.spec, &p.key, &tmp, &limits);
    let _ = std::fs::remove_dir_all(&dest);
    if let Err(e) = std::fs::rename(&tmp, &dest) {
        let _ = std::fs::remove_dir_all(&tmp);
        return failed_record(
            p,
            &format!("cannot move the result to {}: {e}", dest.display()),
        );
    }
    record
}

fn failed_record(p: &Planned, why: &str) -> PartRecord {
    PartRecord {
        spec: p.spec.clone(),
        key: p.key.clone(),
        status: Status::Error,
        error: Some(why.to_string()),
        steps: Vec::new(),
        messages: Vec::new(),
        numbers: Default::default(),
        pictures: Vec::new(),
    }
}

/// The summary line and the exit status: 1 when any part failed.
fn finish(job: &Job, output: &Path, records: &[PartRecord], planned: &[Planned]) -> Result<()> {
    let t = page::totals(records);
    let reused = planned.iter().filter(|p| p.up_to_date).count();
    for r in records.iter().filter(|r| r.status != Status::Ok) {
        crate::output::warn(format!(
            "{}: {}: {}",
            r.spec.path.display(),
            page::verdict(r),
            r.error.as_deref().unwrap_or("")
        ));
    }
    let what = format!(
        "{} part(s): {} with regions, {} mostly not judged, {} failed{}; report {}",
        t["parts"],
        t["with_regions"],
        t["mostly_not_judged"],
        t["failed"],
        if reused > 0 {
            format!(" ({reused} unchanged, not redone)")
        } else {
            String::new()
        },
        output.join("index.html").display()
    );
    let failed = t["failed"].as_u64().unwrap_or(0);
    if failed > 0 {
        say(&job.summary(what));
        return Err(anyhow::Error::new(crate::error::PartsFailed(failed)));
    }
    job.finish(what)?;
    Ok(())
}

/// Progress of a run: a bar with an ETA on a terminal, a line every few
/// seconds otherwise.
struct Progress {
    bar: indicatif::ProgressBar,
    total: usize,
    done: AtomicUsize,
    failed: AtomicUsize,
    started: Instant,
    last_line: Mutex<Instant>,
    terminal: bool,
}

impl Progress {
    fn new(todo: usize, reused: usize) -> Self {
        let terminal = std::io::stderr().is_terminal();
        let bar = if terminal {
            let bar = indicatif::ProgressBar::new(todo as u64);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{spinner} inspecting [{bar:32}] {pos}/{len} parts ({elapsed}, ETA {eta})",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
                .progress_chars("=> "),
            );
            bar
        } else {
            indicatif::ProgressBar::hidden()
        };
        if reused > 0 {
            say(&format!(
                "fairline inspect: {reused} part(s) unchanged since the last run, {todo} to do"
            ));
        }
        Progress {
            bar,
            total: todo,
            done: AtomicUsize::new(0),
            failed: AtomicUsize::new(0),
            started: Instant::now(),
            last_line: Mutex::new(Instant::now()),
            terminal,
        }
    }

    fn done(&self, record: &PartRecord) {
        let done = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        if record.status != Status::Ok {
            self.failed.fetch_add(1, Ordering::Relaxed);
        }
        if self.terminal {
            self.bar.inc(1);
            return;
        }
        let Ok(mut last) = self.last_line.lock() else {
            return;
        };
        if last.elapsed() >= Duration::from_secs(5) || done == self.total {
            *last = Instant::now();
            let elapsed = self.started.elapsed().as_secs_f64();
            let eta = elapsed / done as f64 * (self.total - done) as f64;
            say(&format!(
                "fairline inspect: {done}/{} parts, {} failed, {} elapsed, about {} left",
                self.total,
                self.failed.load(Ordering::Relaxed),
                crate::output::seconds(elapsed),
                crate::output::seconds(eta)
            ));
        }
    }

    fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
