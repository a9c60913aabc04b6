//! The CLI's modules, and the command layer's, import each other in one
//! direction only (no `demo` ↔ `smooth`, `highlight` ↔ `surface_highlight`
//! or `common` ↔ `output` cycles). Reads the sources as text: every
//! `crate::NAME` outside comments is an arrow from the file's top-level
//! module to the module NAME; a cycle in that graph fails the test, with
//! the modules of the cycle and the lines that make its arrows.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// The top-level module a source file belongs to (`output.rs` → `output`,
/// `demo/mod.rs` and `demo/smooth.rs` → `demo`); `None` for the crate root.
fn top_module(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).ok()?;
    let first = rel.components().next()?.as_os_str().to_string_lossy();
    let name = first.strip_suffix(".rs").unwrap_or(&first).to_string();
    (name != "main" && name != "lib").then_some(name)
}

/// The modules named after `crate::` on one line of code: `crate::a::b`
/// gives `a`, `crate::{a, b::c}` gives `a` and `b`. Text after `//` is a
/// comment and is left out.
fn crate_paths(line: &str) -> Vec<String> {
    let code = line.split("//").next().unwrap_or("");
    let ident = |s: &str| -> String {
        s.trim_start()
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find("crate::") {
        let before = rest[..at].chars().next_back();
        rest = &rest[at + "crate::".len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue; // e.g. `mycrate::`
        }
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            out.extend(group[..end].split(',').map(ident).filter(|s| !s.is_empty()));
        } else {
            let name = ident(rest);
            if !name.is_empty() {
                out.push(name);
            }
        }
    }
    out
}

/// Arrows between modules: for each (from, to), the first line making it.
type Graph = BTreeMap<String, BTreeMap<String, String>>;

/// A cycle of `graph` as the list of its modules (first repeated last), or
/// `None` when the graph has none.
fn find_cycle(graph: &Graph) -> Option<Vec<String>> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        New,
        Open,
        Done,
    }
    let nodes: BTreeSet<&String> = graph
        .iter()
        .flat_map(|(a, tos)| std::iter::once(a).chain(tos.keys()))
        .collect();
    let mut mark: BTreeMap<&String, Mark> = nodes.iter().map(|n| (*n, Mark::New)).collect();
    fn visit<'a>(
        n: &'a String,
        graph: &'a Graph,
        mark: &mut BTreeMap<&'a String, Mark>,
        path: &mut Vec<&'a String>,
    ) -> Option<Vec<String>> {
        mark.insert(n, Mark::Open);
        path.push(n);
        for m in graph.get(n).into_iter().flat_map(|t| t.keys()) {
            match mark.get(m).copied().unwrap_or(Mark::New) {
                Mark::Open => {
                    let start = path.iter().position(|p| *p == m).unwrap_or(0);
                    let mut cycle: Vec<String> =
                        path[start..].iter().map(|s| s.to_string()).collect();
                    cycle.push(m.clone());
                    return Some(cycle);
                }
                Mark::New => {
                    if let Some(c) = visit(m, graph, mark, path) {
                        return Some(c);
                    }
                }
                Mark::Done => {}
            }
        }
        path.pop();
        mark.insert(n, Mark::Done);
        None
    }
    for n in &nodes {
        if mark[*n] == Mark::New
            && let Some(c) = visit(n, graph, &mut mark, &mut Vec::new())
        {
            return Some(c);
        }
    }
    None
}

/// The module graph of the sources under `src`.
fn module_graph(src: &Path) -> Graph {
    let files = rust_files(src);
    let modules: BTreeSet<String> = files.iter().filter_map(|f| top_module(src, f)).collect();
    let mut graph = Graph::new();
    for file in &files {
        let Some(from) = top_module(src, file) else {
            continue;
        };
        let text = std::fs::read_to_string(file).unwrap();
        for (k, line) in text.lines().enumerate() {
            for to in crate_paths(line) {
                if to != from && modules.contains(&to) {
                    let rel = file.strip_prefix(src).unwrap_or(file).display();
                    graph
                        .entry(from.clone())
                        .or_default()
                        .entry(to)
                        .or_insert_with(|| format!("src/{rel}:{}: {}", k + 1, line.trim()));
                }
            }
        }
    }
    graph
}

#[test]
fn the_cli_modules_import_each_other_in_one_direction_only() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let graph = module_graph(&src);
    // the graph is not empty: the parser sees the imports
    let arrows: usize = graph.values().map(|t| t.len()).sum();
    assert!(arrows > 20, "only {arrows} arrows found: {graph:?}");
    assert!(graph["highlight"].contains_key("surface_highlight"));
    assert!(graph["common"].contains_key("output"));
    if let Some(cycle) = find_cycle(&graph) {
        let lines: Vec<&String> = cycle.windows(2).map(|w| &graph[&w[0]][&w[1]]).collect();
        panic!(
            "import cycle {}:\n  {}",
            cycle.join(" → "),
            lines
                .iter()
                .map(|s| s.as_str())
                .collect::<Vec<_>>()
                .join("\n  ")
        );
    }
}

#[test]
fn the_command_layer_modules_import_each_other_in_one_direction_only() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fairline-commands/src");
    let graph = module_graph(&src);
    let arrows: usize = graph.values().map(|t| t.len()).sum();
    assert!(arrows > 10, "only {arrows} arrows found: {graph:?}");
    assert!(graph["fair"].contains_key("regions"));
    assert!(graph["detect"].contains_key("lights"));
    if let Some(cycle) = find_cycle(&graph) {
        let lines: Vec<&String> = cycle.windows(2).map(|w| &graph[&w[0]][&w[1]]).collect();
        panic!(
            "import cycle {}:\n  {}",
            cycle.join(" → "),
            lines
                .iter()
                .map(|s| s.as_str())
                .collect::<Vec<_>>()
                .join("\n  ")
        );
    }
}

#[test]
fn the_cycle_check_finds_cycles_and_reads_every_import_form() {
    assert_eq!(
        crate_paths("use crate::common::{Report, bad_input}; // crate::demo"),
        ["common"]
    );
    assert_eq!(
        crate_paths("    let x = crate::output::say(crate::{args, error::bad_input});"),
        ["output", "args", "error"]
    );
    assert!(crate_paths("use fairline::mycrate::x; // crate::a").is_empty());
    let edge = |a: &str, b: &str| (a.to_string(), b.to_string());
    let build = |edges: &[(String, String)]| {
        let mut g = Graph::new();
        for (a, b) in edges {
            g.entry(a.clone())
                .or_default()
                .insert(b.clone(), String::new());
        }
        g
    };
    let line = build(&[edge("a", "b"), edge("b", "c"), edge("a", "c")]);
    assert_eq!(find_cycle(&line), None);
    let ring = build(&[
        edge("a", "b"),
        edge("b", "c"),
        edge("c", "a"),
        edge("x", "a"),
    ]);
    let cycle = find_cycle(&ring).expect("a → b → c → a");
    assert_eq!(cycle.first(), cycle.last());
    assert_eq!(cycle.len(), 4, "{cycle:?}");
}
