//! The one output policy of every `fairline` command, and what a command
//! says on the terminal.
//!
//! # Declaring inputs and outputs
//!
//! A command declares every file it reads and every file it writes before
//! it does any work, and checks them in one call:
//!
//! ```ignore
//! let job = Job::new("smooth")
//!     .input(&args.mesh)
//!     .input_opt(args.fixed.as_deref())
//!     .output("-o", &args.output)
//!     .output_opt("--png", args.png.as_deref())
//!     .output_opt("--report", args.report.as_deref())
//!     .check()?;
//! // ... read, compute, write ...
//! job.finish(format_args!("taubin, 10 iterations on {n} vertices"))?;
//! ```
//!
//! [`Job::check`] refuses (exit status 2, the path named, nothing read or
//! written) an input that exists and is not a regular file (a directory, a
//! FIFO, a device such as `/dev/zero`: reading one would wait or never
//! end), and (its option named too) an output that
//! - is one of the command's inputs: the same canonical path, or on Unix
//!   the same device and inode (hard links, symbolic links, `./x.obj`
//!   against `x.obj` are all caught — [`fairline::io::same_file`]);
//! - is the same file as another output of the command;
//! - exists and is not a regular file: a directory, a device node such as
//!   `/dev/null`, a FIFO or a socket (writing goes through a temporary file
//!   and a rename, which would replace it with a regular file);
//! - is a regular file with more than one hard link (the rename would
//!   give this name a new file and leave the other names with the old
//!   content: the links would silently break);
//! - is `-` or anything under `/dev` or `/proc` (`/dev/stdout`): the
//!   commands write files, never standard output;
//! - lies in a folder that does not exist or cannot be written to.
//!
//! A symbolic link to a regular file is allowed: its target gets the new
//! content and the link stays. Every write is atomic
//! ([`fairline::io::atomic_write`]: temporary file `.NAME.PID.N.tmp` in the
//! same folder, then a rename), and a command's outputs are written all or
//! none: `main` stages the writes of every command but `view`, `inspect`
//! and `demo` ([`fairline::io::stage_writes`]: each file is written in
//! full under its temporary name), and [`Job::finish`] renames them all
//! into place; a command that fails before (an error, a signal) leaves
//! none of them. The temporary files in progress are removed
//! when a write fails and when the process gets SIGINT or SIGTERM
//! ([`install_signal_handler`]; exit status 130 or 143).
//!
//! # Terminal
//!
//! Every command ends with one summary line on standard error
//! ([`Job::finish`]: `fairline smooth: … in 0.42 s; wrote out.obj, r.json`),
//! prints `warning: …` lines ([`warn`]) when something did not converge or
//! a measure got worse, and shows a progress bar or spinner ([`progress`],
//! [`spinner`]) only when standard error is a terminal; otherwise (a log, a
//! pipe) a long run prints a line `progress: …` every few seconds instead. Standard output
//! carries data only (`info`); when the reader of a pipe goes away
//! (`fairline info x.obj | head -1`) the command stops quietly with exit
//! status 0 ([`print_stdout`]), as ripgrep does.

use crate::error::bad_input;
use anyhow::Result;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One command's declared inputs and outputs, and its start time.
#[derive(Debug)]
pub struct Job {
    command: &'static str,
    inputs: Vec<PathBuf>,
    outputs: Vec<(String, PathBuf)>,
    started: Instant,
}

impl Job {
    /// A job of the command `command` (its name on the command line),
    /// started now.
    pub fn new(command: &'static str) -> Self {
        Job {
            command,
            inputs: Vec::new(),
            outputs: Vec::new(),
            started: Instant::now(),
        }
    }

    /// Declares a file the command reads.
    pub fn input(mut self, path: impl AsRef<Path>) -> Self {
        self.inputs.push(path.as_ref().to_path_buf());
        self
    }

    /// Declares a file the command reads, when given.
    pub fn input_opt(self, path: Option<&Path>) -> Self {
        match path {
            Some(p) => self.input(p),
            None => self,
        }
    }

    /// Declares a file the command writes; `option` is how the user gave it
    /// (`-o`, `--report`, `OUT`), used in messages.
    pub fn output(mut self, option: &str, path: impl AsRef<Path>) -> Self {
        self.outputs
            .push((option.to_string(), path.as_ref().to_path_buf()));
        self
    }

    /// Declares a file the command writes, when given.
    pub fn output_opt(self, option: &str, path: Option<&Path>) -> Self {
        match path {
            Some(p) => self.output(option, p),
            None => self,
        }
    }

    /// Checks every declared output against the policy of this module
    /// (exit status 2 and nothing written on a violation) and returns the
    /// checked job.
    pub fn check(self) -> Result<Self> {
        for input in &self.inputs {
            // a missing file is left to its reader, whose error names it
            if let Err(e) = fairline::io::require_regular_file(input)
                && e.kind() == std::io::ErrorKind::InvalidInput
            {
                return Err(bad_input(format!(
                    "{}: {e}; nothing written",
                    input.display()
                )));
            }
        }
        for (k, (option, out)) in self.outputs.iter().enumerate() {
            for input in &self.inputs {
                if fairline::io::same_file(input, out) {
                    return Err(bad_input(format!(
                        "refusing to write {} ({option}): it is the input file {}; nothing written",
                        out.display(),
                        input.display()
                    )));
                }
            }
            for (other_option, other) in &self.outputs[..k] {
                if fairline::io::same_file(other, out) {
                    return Err(bad_input(format!(
                        "{} ({option}) and {} ({other_option}) are the same file; give each output its own path; nothing written",
                        out.display(),
                        other.display()
                    )));
                }
            }
            check_output_path(option, out)?;
        }
        Ok(self)
    }

    /// Seconds since the job started.
    pub fn elapsed_s(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }

    /// The summary line: `fairline COMMAND: WHAT in T s; wrote A, B`.
    pub fn summary(&self, what: impl std::fmt::Display) -> String {
        let written: Vec<String> = self
            .outputs
            .iter()
            .map(|(_, p)| p.display().to_string())
            .collect();
        let mut line = format!(
            "fairline {}: {what} in {}",
            self.command,
            seconds(self.elapsed_s())
        );
        if !written.is_empty() {
            line.push_str("; wrote ");
            line.push_str(&written.join(", "));
        }
        line
    }

    /// Puts the outputs written so far in place, all together
    /// ([`fairline::io::commit_staged_writes`]), and prints the summary
    /// line on standard error.
    pub fn finish(&self, what: impl std::fmt::Display) -> Result<()> {
        fairline::io::commit_staged_writes()?;
        say(&self.summary(what));
        Ok(())
    }
}

/// The name of the marker file [`owned_folder`] leaves in a folder it made.
pub const OWNED_FOLDER_MARKER: &str = ".fairline-owned";

/// Prepares `dir` for a command that fills a whole folder with files of
/// fixed names (`demo --out DIR`). The folder is created when missing; an
/// existing folder is used only when it is empty or was made by fairline
/// before (it holds the marker file [`OWNED_FOLDER_MARKER`]), so that
/// files fairline did not create are never overwritten. Anything else is
/// refused with exit status 2 before any work.
pub fn owned_folder(option: &str, dir: &Path) -> Result<()> {
    let shown = dir.display();
    let marker = dir.join(OWNED_FOLDER_MARKER);
    match std::fs::metadata(dir) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            std::fs::create_dir_all(dir).map_err(|e| {
                bad_input(format!("{shown} ({option}): cannot create the folder: {e}"))
            })?;
        }
        Err(e) => return Err(bad_input(format!("{shown} ({option}): {e}"))),
        Ok(m) if !m.is_dir() => {
            return Err(bad_input(format!(
                "{shown} ({option}): exists and is not a folder; nothing written"
            )));
        }
        Ok(_) => {
            if marker.is_file() {
                return Ok(());
            }
            let mut entries = std::fs::read_dir(dir)
                .map_err(|e| bad_input(format!("{shown} ({option}): {e}")))?;
            if entries.next().is_some() {
                return Err(bad_input(format!(
                    "{shown} ({option}): the folder is not empty and was not made by fairline; give a new or empty folder so that no file of yours is overwritten (nothing written)"
                )));
            }
        }
    }
    std::fs::write(
        &marker,
        "made by fairline; files here may be overwritten by the next run\n",
    )
    .map_err(|e| bad_input(format!("{} ({option}): {e}", marker.display())))?;
    Ok(())
}

/// `0.42 s`, `12.3 s`, `3 min 05 s`.
pub fn seconds(s: f64) -> String {
    if !s.is_finite() || s < 0.0 {
        return "? s".into();
    }
    if s < 10.0 {
        format!("{s:.2} s")
    } else if s < 120.0 {
        format!("{s:.1} s")
    } else {
        let m = (s / 60.0).floor();
        format!("{m:.0} min {:02.0} s", s - 60.0 * m)
    }
}

/// Checks one output path on its own: a file name, not `-` or a special
/// file, a regular file or absent, its folder present and writable.
fn check_output_path(option: &str, out: &Path) -> Result<()> {
    let shown = out.display();
    if out.as_os_str() == "-" {
        return Err(bad_input(format!(
            "{option} -: writing to standard output is not supported; give a file name"
        )));
    }
    if out.file_name().is_none() {
        return Err(bad_input(format!("{shown} ({option}): not a file name")));
    }
    let canonical = std::fs::canonicalize(out).ok();
    if let Some(c) = &canonical
        && (c.starts_with("/dev") || c.starts_with("/proc"))
    {
        return Err(bad_input(format!(
            "{shown} ({option}): is a special file; outputs must be regular files"
        )));
    }
    match std::fs::symlink_metadata(out) {
        Ok(link_meta) => {
            let meta = match std::fs::metadata(out) {
                Ok(m) => m,
                Err(_) if link_meta.file_type().is_symlink() => {
                    return Err(bad_input(format!(
                        "{shown} ({option}): is a symbolic link to nothing; refusing to replace it"
                    )));
                }
                Err(e) => return Err(bad_input(format!("{shown} ({option}): {e}"))),
            };
            if meta.is_dir() {
                return Err(bad_input(format!(
                    "{shown} ({option}): is a directory; give a file name"
                )));
            }
            if !meta.is_file() {
                return Err(bad_input(format!(
                    "{shown} ({option}): is not a regular file (a device, FIFO or socket); refusing to replace it"
                )));
            }
            let links = fairline::io::hard_links(&meta);
            if links > 1 {
                return Err(bad_input(format!(
                    "{shown} ({option}): {}",
                    fairline::io::hard_link_refusal(links)
                )));
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(bad_input(format!("{shown} ({option}): {e}"))),
    }
    // The folder the file is written in (the link's target's folder for a
    // symbolic link): it must exist and accept a new file.
    let target = canonical.unwrap_or_else(|| out.to_path_buf());
    let dir = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(bad_input(format!(
            "{shown} ({option}): the folder {} does not exist; nothing written",
            dir.display()
        )));
    }
    let probe = dir.join(format!(".fairline-probe.{}.tmp", std::process::id()));
    match std::fs::File::options()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(f) => {
            drop(f);
            let _ = std::fs::remove_file(&probe);
        }
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
        Err(e) => {
            return Err(bad_input(format!(
                "{shown} ({option}): cannot write in the folder {}: {e}; nothing written",
                dir.display()
            )));
        }
    }
    Ok(())
}

/// Refuses (exit status 2, before anything is read or written) an output
/// `path`, given as `option` (`-o`, `--png`), whose extension is none of
/// `allowed` (without the dot, compared ignoring ASCII case): the one check
/// of output file types of every command.
pub fn require_extension(option: &str, path: &Path, allowed: &[&str]) -> Result<()> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if allowed.iter().any(|a| a.eq_ignore_ascii_case(ext)) {
        return Ok(());
    }
    let names: Vec<String> = allowed.iter().map(|a| format!(".{a}")).collect();
    let listed = match names.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => names.join(""),
    };
    Err(bad_input(format!(
        "{}: {option} must name a {listed} file; nothing written",
        path.display()
    )))
}

/// `err` with the file named: unchanged when its message (with its
/// causes) already names `path`, else with `path` as context, so that the
/// error line reads `PATH: message`. The causes
/// are kept, so the exit status does not change.
pub fn name_file(path: &Path, err: impl Into<anyhow::Error>) -> anyhow::Error {
    let err = err.into();
    let shown = path.display().to_string();
    if format!("{err:#}").contains(&shown) {
        err
    } else {
        err.context(shown)
    }
}

/// Writes a line on standard error, ignoring a closed standard error.
pub fn say(line: &str) {
    let mut e = std::io::stderr().lock();
    let _ = writeln!(e, "{line}");
}

/// Prints `warning: MSG` on standard error.
pub fn warn(msg: impl std::fmt::Display) {
    say(&format!("warning: {msg}"));
}

/// Writes `text` on standard output. When the reader has gone away (a
/// closed pipe: `fairline info x.obj | head -1`), the process ends quietly
/// with exit status 0: what the reader wanted, it got. Other write errors
/// are returned.
pub fn print_stdout(text: &str) -> Result<()> {
    let mut out = std::io::stdout().lock();
    let r = out.write_all(text.as_bytes()).and_then(|_| out.flush());
    match r {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => std::process::exit(0),
        Err(e) => Err(anyhow::Error::new(e).context("writing to standard output")),
    }
}

/// Removes the temporary files of the writes in progress and exits with
/// 128 + the signal number (130 for SIGINT, 143 for SIGTERM) when the
/// process gets SIGINT or SIGTERM. Written with `signal-hook`: the signal
/// only wakes a thread, which does the work outside the signal handler.
pub fn install_signal_handler() {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
        return;
    };
    let spawned = std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            if let Some(signal) = signals.forever().next() {
                let removed = fairline::io::remove_temporary_files();
                let name = if signal == SIGINT {
                    "interrupted"
                } else {
                    "terminated"
                };
                let files = if removed == 1 { "file" } else { "files" };
                say(&format!(
                    "\nfairline: {name}; {removed} temporary {files} removed, unfinished outputs not written"
                ));
                std::process::exit(128 + signal);
            }
        });
    drop(spawned);
}

/// The environment variable that caps a process's address space in MiB
/// (set by `fairline inspect` for each part's commands).
pub const MEMORY_LIMIT_ENV: &str = "FAIRLINE_MEMORY_LIMIT_MB";

/// Caps this process's address space at the number of MiB in the
/// environment variable `FAIRLINE_MEMORY_LIMIT_MB`, when it is set (how
/// `fairline inspect` limits each part's processes): an allocation beyond
/// it aborts the process instead of exhausting the machine.
pub fn apply_memory_limit() -> Result<()> {
    let Some(value) = std::env::var_os(MEMORY_LIMIT_ENV) else {
        return Ok(());
    };
    let mb: u64 = value
        .to_str()
        .and_then(|v| v.trim().parse().ok())
        .filter(|&mb| mb > 0)
        .ok_or_else(|| {
            bad_input(format!(
                "{}={}: give a positive number of MiB",
                MEMORY_LIMIT_ENV,
                value.to_string_lossy()
            ))
        })?;
    let bytes = mb.saturating_mul(1 << 20);
    rlimit::setrlimit(rlimit::Resource::AS, bytes, bytes)
        .map_err(|e| anyhow::anyhow!("cannot limit the memory to {mb} MiB: {e}"))
}

/// How long work runs before its progress bar or spinner appears.
const PROGRESS_DELAY: std::time::Duration = std::time::Duration::from_millis(800);

/// Shows `bar` on standard error once the work has taken
/// [`PROGRESS_DELAY`] and is not finished, so that quick work draws
/// nothing; `bar` must have been made hidden.
fn show_later(bar: &indicatif::ProgressBar, tick: bool) {
    let later = bar.clone();
    let spawned = std::thread::Builder::new()
        .name("progress".into())
        .spawn(move || {
            std::thread::sleep(PROGRESS_DELAY);
            if !later.is_finished() {
                later.set_draw_target(indicatif::ProgressDrawTarget::stderr_with_hz(8));
                if tick {
                    later.enable_steady_tick(std::time::Duration::from_millis(120));
                }
            }
        });
    drop(spawned);
}

/// How often a line of progress is printed when standard error is not a
/// terminal (a log file, a pipe, CI): often enough to show that a long run
/// is alive, seldom enough not to fill the log.
const PROGRESS_LINE_INTERVAL: std::time::Duration = std::time::Duration::from_secs(5);

/// The environment variable that sets [`PROGRESS_LINE_INTERVAL`] in
/// milliseconds instead (a positive integer; anything else is ignored).
/// For the tests, which need a run shorter than five seconds to print;
/// deliberately not in `--help`.
pub const PROGRESS_INTERVAL_ENV: &str = "FAIRLINE_PROGRESS_INTERVAL_MS";

/// The interval of the progress lines: [`PROGRESS_INTERVAL_ENV`] when it
/// holds a positive number of milliseconds, else [`PROGRESS_LINE_INTERVAL`].
fn progress_line_interval() -> std::time::Duration {
    std::env::var(PROGRESS_INTERVAL_ENV)
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
        .filter(|&ms| ms > 0)
        .map_or(PROGRESS_LINE_INTERVAL, std::time::Duration::from_millis)
}

/// The progress of work when standard error is not a terminal: a line
/// `progress: MESSAGE, DONE/TOTAL steps, T elapsed` (the steps when `bar`
/// has a length) on standard error after every interval
/// ([`progress_line_interval`]) the work has run, until `bar` is finished
/// or dropped. Quick work prints nothing; nothing is redrawn in place.
fn print_progress_lines(bar: &indicatif::ProgressBar) {
    let weak = bar.downgrade();
    let every = progress_line_interval();
    let spawned = std::thread::Builder::new()
        .name("progress-lines".into())
        .spawn(move || {
            loop {
                std::thread::sleep(every);
                let Some(bar) = weak.upgrade() else { return };
                if bar.is_finished() {
                    return;
                }
                let steps = match bar.length() {
                    Some(len) if len > 0 => format!(", {}/{len} steps", bar.position()),
                    _ => String::new(),
                };
                say(&format!(
                    "progress: {}{steps}, {} elapsed",
                    bar.message(),
                    seconds(bar.elapsed().as_secs_f64())
                ));
            }
        });
    drop(spawned);
}

/// A progress bar of `len` steps on standard error when it is a terminal,
/// drawn once the work has taken about a second; otherwise a line of
/// progress every few seconds ([`print_progress_lines`]).
pub fn progress(len: u64, message: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::hidden();
    bar.set_length(len);
    bar.set_message(message.to_string());
    if !std::io::stderr().is_terminal() {
        print_progress_lines(&bar);
        return bar;
    }
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} {msg:<24} [{bar:32}] {pos}/{len} ({elapsed})",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    show_later(&bar, false);
    bar
}

/// A spinner for work of unknown length on standard error when it is a
/// terminal, drawn once the work has taken about a second; otherwise a
/// line of progress every few seconds ([`print_progress_lines`]).
pub fn spinner(message: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::hidden();
    bar.set_message(message.to_string());
    if !std::io::stderr().is_terminal() {
        print_progress_lines(&bar);
        return bar;
    }
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    show_later(&bar, true);
    bar
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("fairline-output-{}-{tag}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn outputs_clashing_with_inputs_or_each_other_are_refused() {
        let d = dir("clash");
        let input = d.join("in.obj");
        std::fs::write(&input, "v 0 0 0\n").unwrap();
        let job = |out: &Path, report: &Path| {
            Job::new("t")
                .input(&input)
                .output("-o", out)
                .output("--report", report)
                .check()
        };
        assert!(job(&d.join("a.obj"), &d.join("r.json")).is_ok());
        let e = job(&d.join("a.obj"), &input).unwrap_err().to_string();
        assert!(e.contains("in.obj") && e.contains("--report"), "{e}");
        assert!(job(&d.join("./in.obj"), &d.join("r.json")).is_err());
        let e = job(&d.join("a.obj"), &d.join("./a.obj"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("same file"), "{e}");
        // missing folder, directory, /dev/null, "-"
        assert!(job(&d.join("a.obj"), &d.join("missing/r.json")).is_err());
        assert!(job(&d, &d.join("r.json")).is_err());
        assert!(job(Path::new("/dev/null"), &d.join("r.json")).is_err());
        assert!(job(Path::new("-"), &d.join("r.json")).is_err());
        // the check writes nothing
        let names: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("in.obj")]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn owned_folders_are_made_reused_and_foreign_ones_refused() {
        let d = dir("owned");
        let fresh = d.join("fresh");
        owned_folder("--out", &fresh).unwrap();
        assert!(fresh.join(OWNED_FOLDER_MARKER).is_file());
        std::fs::write(fresh.join("picture.png"), "old").unwrap();
        owned_folder("--out", &fresh).unwrap(); // made by fairline: reused
        let empty = d.join("empty");
        std::fs::create_dir(&empty).unwrap();
        owned_folder("--out", &empty).unwrap();
        let foreign = d.join("foreign");
        std::fs::create_dir(&foreign).unwrap();
        std::fs::write(foreign.join("scan.ply"), "mine").unwrap();
        let e = owned_folder("--out", &foreign).unwrap_err().to_string();
        assert!(e.contains("not empty"), "{e}");
        assert!(!foreign.join(OWNED_FOLDER_MARKER).exists());
        assert!(owned_folder("--out", &foreign.join("scan.ply")).is_err());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn output_extensions_are_checked_ignoring_case() {
        assert!(require_extension("--png", Path::new("a/b.PNG"), &["png"]).is_ok());
        assert!(require_extension("-o", Path::new("l.obj"), &["json", "obj"]).is_ok());
        let e = require_extension("--png", Path::new("b.jpg"), &["png"]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "b.jpg: --png must name a .png file; nothing written"
        );
        assert_eq!(crate::error::exit_code(&e), crate::error::EXIT_BAD_INPUT);
        let e = require_extension("-o", Path::new("noext"), &["json", "obj"]).unwrap_err();
        assert!(
            e.to_string()
                .ends_with("-o must name a .json or .obj file; nothing written")
        );
        let e = require_extension("-o", Path::new("x.gif"), &["png", "svg", "pdf"]).unwrap_err();
        assert!(e.to_string().contains("a .png, .svg or .pdf file"), "{e}");
    }

    #[test]
    fn summary_names_what_was_written() {
        let job = Job::new("smooth")
            .output("-o", "a.obj")
            .output("--png", "b.png");
        let s = job.summary("did it");
        assert!(s.starts_with("fairline smooth: did it in "), "{s}");
        assert!(s.ends_with("; wrote a.obj, b.png"), "{s}");
        assert_eq!(seconds(0.123), "0.12 s");
        assert_eq!(seconds(185.0), "3 min 05 s");
    }
}
