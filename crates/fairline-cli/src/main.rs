//! `fairline`: highlight lines, fairing and smoothing of surfaces from the
//! shell. Each subcommand lives in its own module; this file only dispatches.
//!
//! Exit status: 0 success, 1 the run failed or an output could not be
//! written, 2 bad input or arguments (error.rs, `exit_code`).

#![forbid(unsafe_code)]

mod args;
mod common;
mod continuity;
mod convert;
mod curvature;
mod demo;
mod detect;
mod deviation;
mod draft;
mod enhance;
mod error;
mod fair;
mod fair_surface;
mod highlight;
mod highlight_png;
mod info;
mod input;
mod inspect;
mod lines_file;
mod output;
mod render;
mod repair;
mod section;
mod smooth;
mod surface;
mod surface_highlight;
mod view;

use clap::{Parser, Subcommand};

/// Shows and repairs the shape quality of surfaces: highlight lines,
/// highlight-line fairing, smoothing, structure-line fairing of quad meshes
/// and feature enhancement by vertex flow.
#[derive(Parser, Debug)]
#[command(
    name = "fairline",
    version,
    about,
    after_help = "Examples:\n  fairline demo --out fairline-demo\n  fairline info fairline-demo/sphere.ply --json\n  fairline curvature fairline-demo/sphere.ply -o sphere-curvature.ply\n\nExit status: 0 success; 1 the run failed or an output could not be written; 2 bad input or arguments. Nothing is written unless the command succeeds."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Surface files (IGES, STEP): go on without the faces that cannot be
    /// read (each is still named in a warning) instead of failing with
    /// exit status 1.
    #[arg(long, global = true)]
    skip_unreadable: bool,
}

#[derive(Subcommand, Debug)]
enum Command {
    Info(info::Args),
    Convert(convert::Args),
    Curvature(curvature::Args),
    Highlight(args::HighlightArgs),
    Detect(detect::Args),
    FairSurface(fair_surface::Args),
    Continuity(continuity::Args),
    Deviation(deviation::Args),
    Draft(draft::Args),
    Enhance(enhance::Args),
    Fair(fair::Args),
    Render(render::Args),
    Smooth(smooth::Args),
    FairQuad(smooth::QuadArgs),
    Demo(demo::Args),
    View(view::Args),
    Repair(repair::Args),
    Section(section::Args),
    Inspect(inspect::Args),
}

fn run(cli: Cli) -> anyhow::Result<()> {
    // A command's outputs are written all or none: staged until its job
    // finishes (output.rs). Not the workbench, whose saves are immediate,
    // nor the commands that fill a folder of their own (a part's files are
    // read back by `inspect`).
    if !matches!(
        cli.command,
        Command::View(_) | Command::Inspect(_) | Command::Demo(_)
    ) {
        fairline::io::stage_writes();
    }
    match cli.command {
        Command::Info(a) => info::run(a),
        Command::Convert(a) => convert::run(a),
        Command::Curvature(a) => curvature::run(a),
        Command::Highlight(a) => highlight::run(a),
        Command::Detect(a) => detect::run(a),
        Command::FairSurface(a) => fair_surface::run(a),
        Command::Continuity(a) => continuity::run(a),
        Command::Deviation(a) => deviation::run(a),
        Command::Draft(a) => draft::run(a),
        Command::Enhance(a) => enhance::run(a),
        Command::Fair(a) => fair::run(a),
        Command::Render(a) => render::run(a),
        Command::Smooth(a) => smooth::run(a),
        Command::FairQuad(a) => smooth::run_quad(a),
        Command::Demo(a) => demo::run(a),
        Command::View(a) => view::run(a),
        Command::Repair(a) => repair::run(a),
        Command::Section(a) => section::run(a),
        Command::Inspect(a) => inspect::run(a),
    }
}

/// The error and its causes joined by ": ", leaving out a cause whose text
/// the message already ends with (library errors often include their
/// source in their own text).
fn error_message(e: &anyhow::Error) -> String {
    let mut msg = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if msg.ends_with(&text) {
            continue;
        }
        if !msg.is_empty() {
            msg.push_str(": ");
        }
        msg.push_str(&text);
    }
    msg
}

fn main() {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() {
                error::EXIT_BAD_INPUT
            } else {
                0
            };
            let _ = e.print();
            std::process::exit(code);
        }
    };
    surface::set_skip_unreadable(cli.skip_unreadable);
    output::install_signal_handler();
    if let Err(e) = output::apply_memory_limit() {
        output::say(&format!("error: {e}"));
        std::process::exit(error::EXIT_BAD_INPUT);
    }
    // The command runs on a worker of rayon's pool: its parallel loops then
    // start from a worker and split work with the other threads directly,
    // instead of handing every loop to the pool and sleeping until it is
    // done (two thread wake-ups per loop, thousands per second in the
    // conjugate-gradient solves; 10k-vertex `enhance`: 0.17 s, against
    // 0.20 s when the command runs outside the pool).
    // a checked job's outputs are staged until it finishes: those of a
    // command that failed are removed, those of one that returned without
    // finishing are put in place
    let result = rayon::scope(|_| run(cli)).and_then(|()| {
        fairline::io::commit_staged_writes()?;
        Ok(())
    });
    if let Err(e) = result {
        let discarded = fairline::io::discard_staged_writes();
        output::say(&format!("error: {}", error_message(&e)));
        if discarded > 0 {
            output::say(&format!(
                "note: the {discarded} output(s) finished before the error were not put in place; nothing written"
            ));
        }
        if let Some(hint) = repair::hint(&e) {
            output::say(&format!("hint: {hint}"));
        }
        std::process::exit(error::exit_code(&e));
    }
}
