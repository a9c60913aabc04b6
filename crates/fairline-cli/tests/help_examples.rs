//! Every example in every command's `--help` runs as printed on the files
//! `fairline demo` writes: the help refers only to files a newcomer has
//! after running `fairline demo` as the README's set-up does, and its
//! examples work.

mod common;

use common::{bin, ok, tmp};

/// The example command lines of `fairline CMD --help`: the lines after the
/// `Examples …:` heading that start with `fairline `, split at `&&`.
fn examples(command: &str) -> Vec<Vec<String>> {
    let out = bin()
        .args([command, "--help"])
        .output()
        .expect("run --help");
    ok(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    let mut lines = text
        .lines()
        .skip_while(|l| !l.starts_with("Example"))
        .skip(1);
    let mut found = Vec::new();
    for l in lines.by_ref() {
        let l = l.trim();
        if !l.starts_with("fairline ") {
            break;
        }
        for part in l.split("&&") {
            let words: Vec<String> = part.split_whitespace().map(str::to_string).collect();
            assert_eq!(words[0], "fairline", "{command}: {part}");
            found.push(words[1..].to_vec());
        }
    }
    assert!(!found.is_empty(), "{command} --help shows no example");
    found
}

#[test]
fn every_help_example_runs_on_the_demo_files() {
    let dir = tmp("help-examples");
    let demo = bin()
        .current_dir(&dir)
        .args(["demo", "--out", "fairline-demo"])
        .output()
        .expect("run demo");
    ok(&demo);
    let commands = [
        "info",
        "convert",
        "repair",
        "curvature",
        "highlight",
        "detect",
        "fair",
        "render",
        "smooth",
        "fair-quad",
        "enhance",
        "fair-surface",
        "continuity",
        "deviation",
        "section",
        "draft",
        "view",
    ];
    let mut ran = 0;
    for command in commands {
        for args in examples(command) {
            if args[0] == "demo" {
                continue; // already run above
            }
            for a in &args {
                if a.starts_with("fairline-demo/") {
                    assert!(
                        dir.join(a).is_file(),
                        "`fairline {command} --help` names {a}, which `fairline demo` does not write"
                    );
                }
            }
            if args[0] == "view" {
                continue; // a server that runs until interrupted (tested in view.rs)
            }
            let out = bin()
                .current_dir(&dir)
                .args(&args)
                .output()
                .expect("run example");
            assert!(
                out.status.success(),
                "`fairline {}` (from `fairline {command} --help`) failed: {}",
                args.join(" "),
                String::from_utf8_lossy(&out.stderr)
            );
            ran += 1;
        }
    }
    assert!(ran >= 20, "only {ran} examples ran");
}
