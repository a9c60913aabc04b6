//! Staged writes: after `stage_writes`, files written with `atomic_write`
//! appear at their paths only on `commit_staged_writes`, all together, and
//! `discard_staged_writes` leaves the paths as they were. One test in its
//! own binary: staging is a setting of the whole process.

use fairline::io::{atomic_write, commit_staged_writes, discard_staged_writes, stage_writes};
use std::io::Write;
use std::path::Path;

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn staged_files_appear_together_on_commit_and_never_on_discard() {
    let dir = std::env::temp_dir().join(format!("fairline-staged-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let (a, b) = (dir.join("a.txt"), dir.join("b.txt"));
    std::fs::write(&b, "old b").unwrap();

    // discarded: nothing new, the old content kept, no temporary file
    stage_writes();
    atomic_write(&a, |w| w.write_all(b"new a")).unwrap();
    atomic_write(&b, |w| w.write_all(b"new b")).unwrap();
    assert!(!a.exists());
    assert_eq!(std::fs::read_to_string(&b).unwrap(), "old b");
    assert_eq!(names(&dir).len(), 3, "{:?}", names(&dir));
    assert_eq!(discard_staged_writes(), 2);
    assert_eq!(names(&dir), ["b.txt"]);
    assert_eq!(std::fs::read_to_string(&b).unwrap(), "old b");

    // committed: both in place, in the order written; a second write of
    // one path wins
    stage_writes();
    atomic_write(&a, |w| w.write_all(b"first a")).unwrap();
    atomic_write(&b, |w| w.write_all(b"new b")).unwrap();
    atomic_write(&a, |w| w.write_all(b"second a")).unwrap();
    assert!(!a.exists());
    let written = commit_staged_writes().unwrap();
    assert_eq!(written, [a.clone(), b.clone(), a.clone()]);
    assert_eq!(names(&dir), ["a.txt", "b.txt"]);
    assert_eq!(std::fs::read_to_string(&a).unwrap(), "second a");
    assert_eq!(std::fs::read_to_string(&b).unwrap(), "new b");

    // staging ended with the commit: the next write is in place at once
    atomic_write(&b, |w| w.write_all(b"at once")).unwrap();
    assert_eq!(std::fs::read_to_string(&b).unwrap(), "at once");
    assert!(commit_staged_writes().unwrap().is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}
