//! The job of one part: the single-file commands with their default
//! settings, each run as a child process of the same `fairline` binary in
//! the part's folder, and the record of what they found.
//!
//! Mesh parts: `info --json`; `repair` when the mesh is not a manifold
//! (detection then judges the repaired mesh); `detect` with its picture.
//! CAD parts: `info --json --area`; `continuity` with its picture;
//! `convert` to a tessellated mesh and `detect` on it. A thumbnail is cut
//! from the detection picture.
//!
//! Everything written is deterministic: the commands' reports lose their
//! `time_s`, the terminal's summary lines (which carry times) are left
//! out, only its `warning:`/`note:`/`error:`/`hint:` lines are kept.

use super::plan::{PartKind, PartSpec};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::ffi::OsString;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::output::MEMORY_LIMIT_ENV;

/// Per-part limits.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// Wall time for all steps of one part together.
    pub timeout: Duration,
    /// Address-space cap of each step's process, in MiB.
    pub memory_mb: Option<u64>,
    /// Worker threads of each step's process (0: its default).
    pub threads: usize,
}

/// How a part's job ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Status {
    /// Every step ran.
    Ok,
    /// A step failed: the file could not be read or judged.
    Error,
    /// The part ran out of its time.
    Timeout,
    /// A step ran out of its memory.
    OutOfMemory,
}

/// One command a part's job ran.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StepRecord {
    /// The command's name (`info`, `detect`, …).
    pub name: String,
    /// The command line that reproduces it, run in the part's report
    /// folder (the input as given to `inspect`).
    pub command: String,
    /// Its exit status (None when it was killed).
    pub exit: Option<i32>,
}

/// What one part's job found: `parts/ID/part.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PartRecord {
    /// The part as planned.
    #[serde(flatten)]
    pub spec: PartSpec,
    /// Its content key (see [`super::plan::content_key`]).
    pub key: String,
    /// How the job ended.
    pub status: Status,
    /// Why it failed, when it did: the failing command's error lines.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// The commands run, in order.
    pub steps: Vec<StepRecord>,
    /// The commands' warning, note, error and hint lines.
    pub messages: Vec<String>,
    /// Numbers for the summary table.
    pub numbers: Numbers,
    /// The pictures written (file names in the part's folder).
    pub pictures: Vec<String>,
}

/// The numbers of a part the summary table shows.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Numbers {
    /// Vertices and faces of the judged mesh (the repaired or tessellated
    /// one where there is one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vertices: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub faces: Option<u64>,
    /// Surfaces of a CAD part.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surfaces: Option<u64>,
    /// Why the mesh is not a manifold, when it is not.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub manifold_error: Option<String>,
    /// Whether detection judged a repaired copy.
    pub repaired: bool,
    /// Suggested fairing regions.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub regions: Option<u64>,
    /// The largest region severity (how far its strongest site exceeds its
    /// measure's threshold).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub worst_severity: Option<f64>,
    /// The best region's score.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub best_score: Option<f64>,
    /// Share of detection sites not judged (shape finer than the measure).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_judged: Option<f64>,
    /// Patch-boundary classes of a CAD part (`gap`, `G0`, `G1`, `G2`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub continuity: Option<Value>,
    /// Warnings the commands reported.
    pub warnings: u64,
}

/// One step to run: its name, the arguments after `fairline`, the same
/// with the input as given (for the reproducing command line), and the
/// file its standard output goes to.
struct Step {
    name: &'static str,
    args: Vec<OsString>,
    shown: Vec<String>,
    stdout_to: Option<&'static str>,
}

impl Step {
    /// `fairline NAME INPUT REST…`.
    fn new(name: &'static str, input: (&Path, &str), rest: &[&str]) -> Self {
        let mut args = vec![OsString::from(name), input.0.as_os_str().to_owned()];
        let mut shown = vec![name.to_string(), shell_quote(input.1)];
        for r in rest {
            args.push(OsString::from(r));
            shown.push(shell_quote(r));
        }
        Step {
            name,
            args,
            shown,
            stdout_to: None,
        }
    }

    fn arg(mut self, a: impl Into<String>) -> Self {
        let a = a.into();
        self.shown.push(shell_quote(&a));
        self.args.push(OsString::from(a));
        self
    }

    /// `--flag value` with a path value: the real path, shown as given.
    fn path_arg(mut self, flag: &str, real: &Path, shown: &str) -> Self {
        self.args.push(flag.into());
        self.args.push(real.as_os_str().to_owned());
        self.shown.push(flag.into());
        self.shown.push(shell_quote(shown));
        self
    }

    fn stdout(mut self, file: &'static str) -> Self {
        self.stdout_to = Some(file);
        self
    }

    fn command_line(&self) -> String {
        let mut line = format!("fairline {}", self.shown.join(" "));
        if let Some(f) = self.stdout_to {
            line.push_str(&format!(" > {f}"));
        }
        line
    }
}

/// A word quoted for a POSIX shell when it needs to be.
pub fn shell_quote(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "._-/,=+:@%".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

/// What one child process did.
struct Ran {
    exit: Option<i32>,
    killed_by_deadline: bool,
    out_of_memory: bool,
    stdout: Vec<u8>,
    stderr: String,
}

/// Runs `exe ARGS` in `dir` until it exits or `deadline` passes (then
/// kills it), with the memory cap of `limits` in its environment.
fn run_child(
    exe: &Path,
    step: &Step,
    dir: &Path,
    deadline: Instant,
    limits: &Limits,
) -> std::io::Result<Ran> {
    let mut cmd = Command::new(exe);
    cmd.args(&step.args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        // the children must not draw progress bars into a pipe
        .env("NO_COLOR", "1");
    match limits.memory_mb {
        Some(mb) => cmd.env(MEMORY_LIMIT_ENV, mb.to_string()),
        None => cmd.env_remove(MEMORY_LIMIT_ENV),
    };
    if limits.threads > 0 {
        cmd.env("RAYON_NUM_THREADS", limits.threads.to_string());
    }
    let mut child = cmd.spawn()?;
    let mut out_pipe = child.stdout.take();
    let mut err_pipe = child.stderr.take();
    let out_reader = std::thread::spawn(move || {
        let mut buf = Vec::new();
        if let Some(p) = out_pipe.as_mut() {
            let _ = p.read_to_end(&mut buf);
        }
        buf
    });
    let err_reader = std::thread::spawn(move || {
        let mut buf = Vec::new();
        if let Some(p) = err_pipe.as_mut() {
            let _ = p.read_to_end(&mut buf);
        }
        buf
    });
    let mut killed = false;
    let status = loop {
        if let Some(s) = child.try_wait()? {
            break s;
        }
        if Instant::now() >= deadline {
            let _ = child.kill();
            killed = true;
            break child.wait()?;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let stdout = out_reader.join().unwrap_or_default();
    let stderr = String::from_utf8_lossy(&err_reader.join().unwrap_or_default()).into_owned();
    // past an address-space cap an allocation aborts the process, and a
    // thread's stack cannot be mapped (a panic while building the pool)
    let out_of_memory = !killed
        && limits.memory_mb.is_some()
        && (aborted(&status)
            || (status.code() == Some(101)
                && [
                    "memory allocation",
                    "Cannot allocate memory",
                    "Resource temporarily unavailable",
                ]
                .iter()
                .any(|m| stderr.contains(m))));
    Ok(Ran {
        exit: status.code(),
        killed_by_deadline: killed,
        out_of_memory,
        stdout,
        stderr,
    })
}

#[cfg(unix)]
fn aborted(status: &std::process::ExitStatus) -> bool {
    use std::os::unix::process::ExitStatusExt;
    matches!(status.signal(), Some(6) | Some(9))
}

#[cfg(not(unix))]
fn aborted(_: &std::process::ExitStatus) -> bool {
    false
}

/// The part's job, run into the empty folder `dir`: returns the record
/// (also written there as `part.json`). `exe` is the `fairline` binary.
pub fn run_part(exe: &Path, spec: &PartSpec, key: &str, dir: &Path, limits: &Limits) -> PartRecord {
    let mut job = PartJob {
        exe,
        dir,
        limits,
        deadline: Instant::now() + limits.timeout,
        record: PartRecord {
            spec: spec.clone(),
            key: key.to_string(),
            status: Status::Ok,
            error: None,
            steps: Vec::new(),
            messages: Vec::new(),
            numbers: Numbers::default(),
            pictures: Vec::new(),
        },
        real_input: absolute(&spec.path),
        shown_input: spec.path.to_string_lossy().into_owned(),
    };
    match spec.kind {
        PartKind::Mesh => job.mesh_steps(),
        PartKind::Cad => job.cad_steps(),
    }
    job.thumbnail();
    let record = job.record;
    let text = serde_json::to_string_pretty(&record).unwrap_or_default() + "\n";
    if let Err(e) = std::fs::write(dir.join("part.json"), text) {
        let mut r = record;
        r.status = Status::Error;
        r.error = Some(format!("cannot write part.json: {e}"));
        return r;
    }
    record
}

/// `path` made absolute against the current folder (the children run in
/// the part's folder).
fn absolute(path: &Path) -> PathBuf {
    if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir()
            .map(|d| d.join(path))
            .unwrap_or_else(|_| path.to_path_buf())
    }
}

/// A part's job in progress.
struct PartJob<'a> {
    exe: &'a Path,
    dir: &'a Path,
    limits: &'a Limits,
    deadline: Instant,
    record: PartRecord,
    real_input: PathBuf,
    shown_input: String,
}

impl PartJob<'_> {
    fn input(&self) -> (&Path, &str) {
        (&self.real_input, &self.shown_input)
    }

    /// The light and threshold options of the part's settings, for
    /// `detect`.
    fn detect_options(&self, mut step: Step) -> Step {
        let s = &self.record.spec.settings;
        if let Some(up) = &s.up {
            step = step.arg("--up").arg(up.clone());
        }
        if let Some(l) = &s.lights {
            let shown = l.to_string_lossy().into_owned();
            step = step.path_arg("--lights", &absolute(l), &shown);
        }
        if let Some(t) = s.threshold {
            step = step.arg("--threshold").arg(format!("{t}"));
        }
        step
    }

    fn mesh_steps(&mut self) {
        let info = Step::new("info", self.input(), &["--json"]).stdout("info.json");
        let Some(info) = self.run(info) else { return };
        self.mesh_numbers(&info);
        let detect_input = if info.get("manifold_error").is_some() {
            let repair = Step::new(
                "repair",
                self.input(),
                &["repaired.ply", "--report", "repair.json"],
            );
            if self.run(repair).is_none() {
                return;
            }
            self.record.numbers.repaired = true;
            (PathBuf::from("repaired.ply"), "repaired.ply".to_string())
        } else {
            (self.real_input.clone(), self.shown_input.clone())
        };
        self.detect((&detect_input.0, &detect_input.1));
    }

    fn cad_steps(&mut self) {
        let info = Step::new("info", self.input(), &["--json", "--area"]).stdout("info.json");
        let Some(info) = self.run(info) else { return };
        self.record.numbers.surfaces = info
            .get("surfaces")
            .and_then(|s| s.as_array().map(|a| a.len() as u64).or(s.as_u64()));
        let mut continuity = Step::new(
            "continuity",
            self.input(),
            &["--report", "continuity.json", "--png", "continuity.png"],
        );
        if let Some(t) = self.record.spec.settings.tolerance {
            continuity = continuity.arg("--tolerance").arg(format!("{t}"));
        }
        let Some(c) = self.run(continuity) else {
            return;
        };
        self.record.numbers.continuity = c.get("classes").cloned();
        self.record.pictures.push("continuity.png".into());
        let convert = Step::new("convert", self.input(), &["tessellated.ply"]);
        if self.run(convert).is_none() {
            return;
        }
        self.detect((Path::new("tessellated.ply"), "tessellated.ply"));
    }

    fn detect(&mut self, input: (&Path, &str)) {
        let step = Step::new(
            "detect",
            input,
            &[
                "-o",
                "regions.json",
                "--png",
                "detect.png",
                "--report",
                "detect.json",
            ],
        );
        let step = self.detect_options(step);
        let Some(d) = self.run(step) else { return };
        self.record.pictures.insert(0, "detect.png".into());
        let n = &mut self.record.numbers;
        n.vertices = d.get("vertices").and_then(Value::as_u64).or(n.vertices);
        let regions = d.get("regions").and_then(Value::as_array);
        n.regions = regions.map(|r| r.len() as u64);
        let field = |key: &str| {
            regions.and_then(|r| {
                r.iter()
                    .filter_map(|x| x.get(key).and_then(Value::as_f64))
                    .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v))))
            })
        };
        n.worst_severity = field("severity");
        n.best_score = field("score");
        // the command's own share (by area, after its finer light arrays
        // re-judged what the first could not); the share of sites of the
        // first array only where a report lacks it
        let sites = d.get("sites").and_then(Value::as_f64).unwrap_or(0.0);
        let judged = d.get("judged_sites").and_then(Value::as_f64).unwrap_or(0.0);
        n.not_judged = d
            .get("not_judged_fraction")
            .and_then(Value::as_f64)
            .filter(|f| f.is_finite())
            .map(|f| f.clamp(0.0, 1.0))
            .or_else(|| (sites > 0.0).then(|| ((sites - judged) / sites).clamp(0.0, 1.0)));
        n.warnings += d
            .get("warnings")
            .and_then(Value::as_array)
            .map_or(0, |w| w.len() as u64);
    }

    fn mesh_numbers(&mut self, info: &Value) {
        let n = &mut self.record.numbers;
        n.vertices = info.get("vertices").and_then(Value::as_u64);
        n.faces = info.get("faces").and_then(Value::as_u64);
        n.manifold_error = info.get("manifold_error").map(|e| {
            e.as_str()
                .map(String::from)
                .unwrap_or_else(|| e.to_string())
        });
    }

    /// Runs one step; on success returns its JSON (standard output or the
    /// report it wrote, `time_s` removed and the file rewritten), None
    /// when the part's job must stop (the record then says why).
    fn run(&mut self, step: Step) -> Option<Value> {
        let command = step.command_line();
        let ran = run_child(self.exe, &step, self.dir, self.deadline, self.limits);
        let ran = match ran {
            Ok(r) => r,
            Err(e) => {
                self.fail(Status::Error, format!("cannot run `{command}`: {e}"));
                return None;
            }
        };
        self.record.steps.push(StepRecord {
            name: step.name.into(),
            command: command.clone(),
            exit: ran.exit,
        });
        self.keep_messages(&ran.stderr);
        if ran.killed_by_deadline {
            let t = self.limits.timeout.as_secs_f64();
            self.fail(
                Status::Timeout,
                format!("`{}` ran past the part's time limit of {t} s", step.name),
            );
            return None;
        }
        if ran.out_of_memory {
            let mb = self.limits.memory_mb.unwrap_or(0);
            self.fail(
                Status::OutOfMemory,
                format!("`{}` ran out of its memory limit of {mb} MiB", step.name),
            );
            return None;
        }
        if ran.exit != Some(0) {
            let why = error_lines(&ran.stderr)
                .replace(&*self.real_input.to_string_lossy(), &self.shown_input);
            let code = ran
                .exit
                .map_or_else(|| "a signal".to_string(), |c| format!("exit status {c}"));
            self.fail(
                Status::Error,
                format!("`{}` failed ({code}): {why}", step.name),
            );
            return None;
        }
        let json_file = match step.stdout_to {
            Some(f) => {
                let _ = std::fs::write(self.dir.join(f), &ran.stdout);
                Some(f.to_string())
            }
            None => report_file(&step),
        };
        let value = json_file.and_then(|f| self.clean_json(&f));
        Some(value.unwrap_or(Value::Null))
    }

    /// Reads a JSON file of the part's folder, removes `time_s` and writes
    /// it back (deterministic reports).
    fn clean_json(&mut self, file: &str) -> Option<Value> {
        let path = self.dir.join(file);
        let mut value: Value = serde_json::from_slice(&std::fs::read(&path).ok()?).ok()?;
        if let Value::Object(m) = &mut value {
            m.remove("time_s");
        }
        let text = serde_json::to_string_pretty(&value).ok()? + "\n";
        std::fs::write(&path, text).ok()?;
        Some(value)
    }

    fn keep_messages(&mut self, stderr: &str) {
        for line in stderr.lines() {
            let line = line.trim_end();
            if ["warning:", "note:", "error:", "hint:"]
                .iter()
                .any(|p| line.starts_with(p))
                && !line.contains("RUST_BACKTRACE")
            {
                let line = line.replace(&*self.real_input.to_string_lossy(), &self.shown_input);
                if line.starts_with("warning:") {
                    self.record.numbers.warnings += 1;
                }
                self.record.messages.push(line);
            }
        }
    }

    fn fail(&mut self, status: Status, why: String) {
        self.record.status = status;
        self.record.error = Some(why);
    }

    /// `thumb.png`: the first picture scaled down to 320 pixels across.
    fn thumbnail(&mut self) {
        let Some(first) = self.record.pictures.first() else {
            return;
        };
        if super::thumb::write_thumbnail(&self.dir.join(first), &self.dir.join("thumb.png"), 320)
            .is_ok()
        {
            self.record.pictures.push("thumb.png".into());
        }
    }
}

/// The `--report` file a step names, if any.
fn report_file(step: &Step) -> Option<String> {
    let k = step.args.iter().position(|a| a == "--report")?;
    step.args
        .get(k + 1)
        .map(|a| a.to_string_lossy().into_owned())
}

/// The `error:` and `hint:` lines of a command's standard error, joined;
/// its last line when it has none.
fn error_lines(stderr: &str) -> String {
    // a panic: its message, the line after `panicked at`
    let mut it = stderr.lines();
    if it.any(|l| l.contains("panicked at"))
        && let Some(msg) = it.next()
    {
        return format!("the command stopped on an internal error: {}", msg.trim());
    }
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("error:") || l.starts_with("hint:"))
        .map(|l| l.trim_start_matches("error:").trim())
        .collect();
    if lines.is_empty() {
        stderr
            .lines()
            .last()
            .unwrap_or("no message")
            .trim()
            .to_string()
    } else {
        lines.join("; ")
    }
}
