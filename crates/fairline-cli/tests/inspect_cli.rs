//! `fairline inspect`: a folder of parts (real meshes of ../shared/data, a
//! generated dented panel, a CAD part, a broken file) judged into a report
//! that is the same bytes for any number of jobs, survives the broken
//! file, redoes only what changed and keeps to its per-part limits.

mod common;
use common::*;
use std::collections::BTreeMap;
use std::path::Path;

/// Every file under `dir` (relative path → bytes), hidden ones left out.
fn tree(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let e = e.unwrap();
            let p = e.path();
            if e.file_name().to_string_lossy().starts_with('.') {
                continue;
            }
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    out
}

/// The parts folder: two real meshes (one not a manifold), the demo's
/// dented panel, the teapot's patches and a file that is no mesh.
fn parts(dir: &Path) -> Option<()> {
    let parts = dir.join("parts");
    std::fs::create_dir_all(parts.join("sub")).unwrap();
    std::fs::copy(data("meshes/bob_small.ply")?, parts.join("bob.ply")).unwrap();
    std::fs::copy(
        data("meshes/bunny_res4.ply")?,
        parts.join("sub/bunny_res4.ply"),
    )
    .unwrap();
    std::fs::copy(data("surfaces/teapot.json")?, parts.join("teapot.json")).unwrap();
    std::fs::write(
        parts.join("broken.ply"),
        "ply\nformat ascii 1.0\nelement vertex 3\n",
    )
    .unwrap();
    std::fs::write(parts.join("notes.txt"), "not a part").unwrap();
    let demo = dir.join("demo");
    ok(&run(&["demo", "--out", s(&demo)]));
    std::fs::copy(
        demo.join("dented-panel.obj"),
        parts.join("dented-panel.obj"),
    )
    .unwrap();
    Some(())
}

fn summary(dir: &Path) -> serde_json::Value {
    json(&dir.join("summary.json"))
}

fn row<'a>(summary: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    summary["parts"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["path"].as_str().unwrap().ends_with(name))
        .unwrap_or_else(|| panic!("no row for {name}: {summary}"))
}

#[test]
fn a_folder_with_a_broken_file_gives_a_full_report_the_same_for_any_jobs() {
    let dir = tmp("inspect-folder");
    if parts(&dir).is_none() {
        return;
    }
    let run_in = |out: &str, jobs: &str| {
        bin()
            .current_dir(&dir)
            .args(["inspect", "parts", "-o", out, "--jobs", jobs])
            .output()
            .unwrap()
    };
    let one = run_in("report1", "1");
    // the broken file fails its part, not the run: exit 1, every row there
    assert_eq!(
        one.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&one.stderr)
    );
    let err = String::from_utf8_lossy(&one.stderr);
    assert!(
        err.contains("parts/broken.ply") && err.contains("1 failed"),
        "{err}"
    );
    let s1 = summary(&dir.join("report1"));
    assert_eq!(s1["totals"]["parts"], 4 + 1, "{s1}");
    assert_eq!(s1["files_left_out"], 1);
    let broken = row(&s1, "broken.ply");
    assert_eq!(broken["status"], "error");
    assert!(
        broken["error"].as_str().unwrap().contains("broken.ply"),
        "{broken}"
    );
    // failed parts are listed first, then the worst severity
    assert_eq!(s1["parts"][0]["status"], "error");
    // the dented panel's dent is found and ranks it above the clean meshes
    let panel = row(&s1, "dented-panel.obj");
    assert_eq!(panel["status"], "ok", "{panel}");
    assert!(
        panel["numbers"]["regions"].as_u64().unwrap() >= 1,
        "{panel}"
    );
    let rank = |name: &str| {
        s1["parts"]
            .as_array()
            .unwrap()
            .iter()
            .position(|r| r["path"].as_str().unwrap().ends_with(name))
            .unwrap()
    };
    assert!(rank("dented-panel.obj") < rank("bob.ply"), "{s1}");
    assert!(rank("dented-panel.obj") < rank("bunny_res4.ply"), "{s1}");
    // the non-manifold scan is repaired before it is judged
    let bunny = row(&s1, "bunny_res4.ply");
    assert_eq!(bunny["numbers"]["repaired"], true, "{bunny}");
    // the CAD part's patches are checked for continuity and judged
    let teapot = row(&s1, "teapot.json");
    assert_eq!(teapot["status"], "ok", "{teapot}");
    assert_eq!(teapot["numbers"]["surfaces"], 32, "{teapot}");
    assert!(teapot["numbers"]["continuity"].is_object(), "{teapot}");
    // the report: pages, pictures and the commands that reproduce a part
    let index = std::fs::read_to_string(dir.join("report1/index.html")).unwrap();
    assert!(index.contains("thumb.png") && index.contains("<th>worst severity</th>"));
    let id = panel["id"].as_str().unwrap();
    let page = std::fs::read_to_string(dir.join(format!("report1/parts/{id}/index.html"))).unwrap();
    assert!(
        page.contains("fairline detect parts/dented-panel.obj -o regions.json --png detect.png --report detect.json"),
        "{page}"
    );
    assert!(dir.join(format!("report1/parts/{id}/detect.png")).is_file());
    let csv = std::fs::read_to_string(dir.join("report1/summary.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 5);
    // the same report, byte for byte, with two jobs
    let two = run_in("report2", "2");
    assert_eq!(two.status.code(), Some(1));
    let (t1, t2) = (tree(&dir.join("report1")), tree(&dir.join("report2")));
    assert_eq!(t1.keys().collect::<Vec<_>>(), t2.keys().collect::<Vec<_>>());
    for (k, v) in &t1 {
        assert!(v == &t2[k], "{k} differs between --jobs 1 and --jobs 2");
    }
}

#[test]
fn a_rerun_redoes_only_the_changed_parts() {
    let dir = tmp("inspect-rerun");
    let Some(bob) = data("meshes/bob_small.ply") else {
        return;
    };
    let Some(bunny) = data("meshes/bunny_npm.obj") else {
        return;
    };
    std::fs::copy(&bob, dir.join("a.ply")).unwrap();
    std::fs::copy(&bunny, dir.join("b.obj")).unwrap();
    let go = || {
        bin()
            .current_dir(&dir)
            .args(["inspect", "a.ply", "b.obj", "-o", "report"])
            .output()
            .unwrap()
    };
    ok(&go());
    let part_json = |name: &str| {
        let s = summary(&dir.join("report"));
        let id = row(&s, name)["id"].as_str().unwrap().to_string();
        dir.join("report/parts").join(id).join("part.json")
    };
    let stamp = |p: &Path| std::fs::metadata(p).unwrap().modified().unwrap();
    let (a0, b0) = (stamp(&part_json("a.ply")), stamp(&part_json("b.obj")));
    let second = go();
    ok(&second);
    assert!(
        String::from_utf8_lossy(&second.stderr).contains("2 part(s) unchanged"),
        "{}",
        String::from_utf8_lossy(&second.stderr)
    );
    assert_eq!(stamp(&part_json("a.ply")), a0);
    // a changed file is redone, the other is not
    let mut text = std::fs::read_to_string(dir.join("b.obj")).unwrap();
    text.push_str("# changed\n");
    std::fs::write(dir.join("b.obj"), text).unwrap();
    ok(&go());
    assert_eq!(stamp(&part_json("a.ply")), a0);
    assert_ne!(stamp(&part_json("b.obj")), b0);
}

#[test]
fn a_part_past_its_limits_gets_its_row_and_the_manifest_sets_its_options() {
    let dir = tmp("inspect-limits");
    let Some(bob) = data("meshes/bob_small.ply") else {
        return;
    };
    std::fs::copy(&bob, dir.join("bob.ply")).unwrap();
    std::fs::write(dir.join("m.csv"), "path,up,threshold\nbob.ply,y,3\n").unwrap();
    // 1 ms is too short for any part
    let o = bin()
        .current_dir(&dir)
        .args([
            "inspect",
            "--manifest",
            "m.csv",
            "-o",
            "r1",
            "--part-timeout",
            "0.001",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let s1 = summary(&dir.join("r1"));
    assert_eq!(s1["parts"][0]["status"], "timeout", "{s1}");
    // 8 MiB of address space is too little for a fairline process (how
    // much more it needs depends on the build and on the threads it starts)
    let o = bin()
        .current_dir(&dir)
        .args([
            "inspect",
            "--manifest",
            "m.csv",
            "-o",
            "r2",
            "--part-memory",
            "8",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let s2 = summary(&dir.join("r2"));
    assert_eq!(s2["parts"][0]["status"], "out-of-memory", "{s2}");
    // with room, the manifest's settings reach `detect`
    let o = bin()
        .current_dir(&dir)
        .args(["inspect", "--manifest", "m.csv", "-o", "r3"])
        .output()
        .unwrap();
    ok(&o);
    let s3 = summary(&dir.join("r3"));
    let id = s3["parts"][0]["id"].as_str().unwrap();
    let part = json(&dir.join(format!("r3/parts/{id}/part.json")));
    let detect = part["steps"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["name"] == "detect")
        .unwrap();
    assert!(
        detect["command"]
            .as_str()
            .unwrap()
            .ends_with("--up y --threshold 3"),
        "{detect}"
    );
}

#[test]
fn bad_arguments_write_nothing() {
    let dir = tmp("inspect-bad");
    std::fs::write(dir.join("x.txt"), "x").unwrap();
    let o = bin()
        .current_dir(&dir)
        .args(["inspect", "x.txt", "-o", "r"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("x.txt"));
    assert!(!dir.join("r").exists());
    // a folder not made by fairline is never filled
    std::fs::create_dir(dir.join("mine")).unwrap();
    std::fs::write(dir.join("mine/keep.txt"), "mine").unwrap();
    std::fs::write(dir.join("a.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let o = bin()
        .current_dir(&dir)
        .args(["inspect", "a.obj", "-o", "mine"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(std::fs::read_dir(dir.join("mine")).unwrap().count(), 1);
}
