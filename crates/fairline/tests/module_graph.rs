//! The library's modules import each other in one direction only: no
//! cycle between its top-level modules (`mesh`, `geom`, `highlight`, `io`,
//! …), and none between the files of one module (`mesh/build.rs`,
//! `mesh/inspect.rs`, …). Reads the sources as text, leaving out test code
//! (modules declared under `#[cfg(test)]` and inline `#[cfg(test)] mod`
//! blocks) and comments: `crate::NAME` is an arrow to the top-level module
//! NAME; inside module M, `super::NAME` (in M's own files) and
//! `crate::M::NAME` are arrows between M's files. A cycle fails the test
//! with its modules and the lines that make its arrows. Arrows through
//! re-exports (`super::Type` where `Type` is re-exported by `mod.rs`) are
//! not seen.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`, relative to it, with `/` separators.
fn rust_files(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let rel = path.strip_prefix(dir).unwrap();
                out.push(rel.to_string_lossy().replace('\\', "/"));
            }
        }
    }
    out.sort();
    out
}

/// The module name a `mod NAME;` or `mod NAME {` line declares.
fn declared_mod(line: &str) -> Option<(String, bool)> {
    let mut t = line.trim_start();
    if let Some(rest) = t.strip_prefix("pub") {
        t = rest.trim_start();
        if t.starts_with('(') {
            t = t[t.find(')')? + 1..].trim_start();
        }
    }
    let rest = t.strip_prefix("mod ")?;
    let name: String = rest
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect();
    let after = rest[name.len()..].trim_start();
    match after.chars().next() {
        Some(';') => Some((name, false)),
        Some('{') => Some((name, true)),
        _ => None,
    }
}

/// The files of test-only modules (declared after `#[cfg(test)]`), as
/// paths or path prefixes relative to `src`.
fn test_only(src: &Path, files: &[String]) -> Vec<String> {
    let mut out = Vec::new();
    for f in files {
        let text = std::fs::read_to_string(src.join(f)).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        let dir = Path::new(f).parent().unwrap_or(Path::new(""));
        let base = Path::new(f).file_name().unwrap().to_string_lossy();
        let child_dir: PathBuf = if base == "mod.rs" || base == "lib.rs" {
            dir.to_path_buf()
        } else {
            dir.join(base.trim_end_matches(".rs"))
        };
        for (i, line) in lines.iter().enumerate() {
            if line.trim() != "#[cfg(test)]" {
                continue;
            }
            let mut k = i + 1;
            let mut path_attr = None;
            while k < lines.len() {
                let t = lines[k].trim();
                if let Some(p) = t.strip_prefix("#[path = \"") {
                    path_attr = p.split('"').next().map(str::to_string);
                } else if !(t.starts_with("#[") || t.starts_with("///")) {
                    break;
                }
                k += 1;
            }
            if let Some((name, false)) = lines.get(k).and_then(|l| declared_mod(l)) {
                let norm = |p: PathBuf| p.to_string_lossy().replace('\\', "/");
                match path_attr {
                    Some(p) => out.push(norm(dir.join(p))),
                    None => {
                        out.push(norm(child_dir.join(format!("{name}.rs"))));
                        out.push(norm(child_dir.join(&name)) + "/");
                    }
                }
            }
        }
    }
    out
}

/// The code of a file: comments left out, and nothing from the first
/// inline `#[cfg(test)] mod … {` on.
fn code_lines(text: &str) -> Vec<String> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        if line.trim() == "#[cfg(test)]" {
            let mut k = i + 1;
            while k < lines.len() && lines[k].trim().starts_with("#[") {
                k += 1;
            }
            if lines
                .get(k)
                .and_then(|l| declared_mod(l))
                .is_some_and(|(_, inline)| inline)
            {
                break;
            }
        }
        out.push(line.split("//").next().unwrap_or("").to_string());
    }
    out
}

/// The names after a path prefix: `a::b` gives `a`, `{a, b::c}` gives `a`
/// and `b`.
fn names_after(rest: &str) -> Vec<String> {
    let ident = |s: &str| -> String {
        s.trim_start()
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    if let Some(group) = rest.strip_prefix('{') {
        let end = group.find('}').unwrap_or(group.len());
        group[..end]
            .split(',')
            .map(ident)
            .filter(|s| !s.is_empty())
            .collect()
    } else {
        let n = ident(rest);
        if n.is_empty() { Vec::new() } else { vec![n] }
    }
}

/// Every occurrence of `prefix` in `line` not preceded by an identifier
/// character or `:`, with the text after it.
fn after<'a>(line: &'a str, prefix: &str) -> Vec<&'a str> {
    let mut out = Vec::new();
    let mut start = 0;
    while let Some(at) = line[start..].find(prefix) {
        let at = start + at;
        let before = line[..at].chars().next_back();
        if !before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
            out.push(&line[at + prefix.len()..]);
        }
        start = at + prefix.len();
    }
    out
}

type Graph = BTreeMap<String, BTreeMap<String, Vec<String>>>;

/// A cycle of `graph`, if it has one.
fn find_cycle(graph: &Graph) -> Option<Vec<String>> {
    fn visit(
        v: &str,
        graph: &Graph,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(v.to_string(), 1);
        stack.push(v.to_string());
        for w in graph
            .get(v)
            .map(|m| m.keys().cloned().collect::<Vec<String>>())
            .unwrap_or_default()
        {
            match state.get(&w) {
                Some(1) => {
                    let from = stack.iter().position(|s| *s == w).unwrap();
                    let mut cycle = stack[from..].to_vec();
                    cycle.push(w);
                    return Some(cycle);
                }
                Some(_) => {}
                None => {
                    if let Some(c) = visit(&w, graph, state, stack) {
                        return Some(c);
                    }
                }
            }
        }
        stack.pop();
        state.insert(v.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for v in graph.keys() {
        if !state.contains_key(v) {
            let mut stack = Vec::new();
            if let Some(c) = visit(v, graph, &mut state, &mut stack) {
                return Some(c);
            }
        }
    }
    None
}

fn describe(graph: &Graph, cycle: &[String]) -> String {
    let arrows: Vec<String> = cycle
        .windows(2)
        .map(|w| format!("{} -> {} at {:?}", w[0], w[1], &graph[&w[0]][&w[1]][..1]))
        .collect();
    arrows.join("; ")
}

#[test]
fn the_library_modules_have_no_cycle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let files = rust_files(&src);
    let tests = test_only(&src, &files);
    let is_test = |f: &str| {
        tests
            .iter()
            .any(|t| f == t || (t.ends_with('/') && f.starts_with(t.as_str())))
    };
    let tops: BTreeSet<String> = files
        .iter()
        .map(|f| {
            f.split('/')
                .next()
                .unwrap()
                .trim_end_matches(".rs")
                .to_string()
        })
        .filter(|t| t != "lib")
        .collect();
    let mut top = Graph::new();
    let mut inner: BTreeMap<String, Graph> = BTreeMap::new();
    for f in files
        .iter()
        .filter(|f| !is_test(f) && f.as_str() != "lib.rs")
    {
        let parts: Vec<&str> = f.split('/').collect();
        let module = parts[0].trim_end_matches(".rs").to_string();
        let node = parts.get(1).map(|p| p.trim_end_matches(".rs").to_string());
        let node = node.filter(|n| n != "mod" && parts.len() >= 2);
        let text = std::fs::read_to_string(src.join(f)).unwrap();
        for (n, line) in code_lines(&text).iter().enumerate() {
            let at = format!("{f}:{}", n + 1);
            for rest in after(line, "crate::") {
                for name in names_after(rest) {
                    if tops.contains(&name) && name != module {
                        top.entry(module.clone())
                            .or_default()
                            .entry(name)
                            .or_default()
                            .push(at.clone());
                    }
                }
                if let (Some(node), Some(sub)) = (&node, rest.strip_prefix(&format!("{module}::")))
                {
                    for name in names_after(sub).into_iter().filter(|s| s != node) {
                        let g = inner.entry(module.clone()).or_default();
                        g.entry(node.clone())
                            .or_default()
                            .entry(name)
                            .or_default()
                            .push(at.clone());
                    }
                }
            }
            if let (Some(node), 2) = (&node, parts.len()) {
                for rest in after(line, "super::") {
                    for name in names_after(rest).into_iter().filter(|s| s != node) {
                        let g = inner.entry(module.clone()).or_default();
                        g.entry(node.clone())
                            .or_default()
                            .entry(name)
                            .or_default()
                            .push(at.clone());
                    }
                }
            }
        }
    }
    assert!(top.len() > 5, "the graph was read: {top:?}");
    if let Some(c) = find_cycle(&top) {
        panic!(
            "top-level modules import each other in a cycle: {}",
            describe(&top, &c)
        );
    }
    for (module, graph) in &mut inner {
        // only arrows to the module's own files
        let prefix = format!("{module}/");
        let own: BTreeSet<String> = files
            .iter()
            .filter_map(|f| f.strip_prefix(&prefix))
            .map(|r| {
                r.split('/')
                    .next()
                    .unwrap()
                    .trim_end_matches(".rs")
                    .to_string()
            })
            .collect();
        for targets in graph.values_mut() {
            targets.retain(|t, _| own.contains(t));
        }
        if let Some(c) = find_cycle(graph) {
            panic!(
                "the files of `{module}` import each other in a cycle: {}",
                describe(graph, &c)
            );
        }
    }
}
