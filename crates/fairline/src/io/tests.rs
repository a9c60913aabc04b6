//! Tests of the mesh formats (reading, writing, round trips and the errors
//! of malformed files) and of the atomic writer.

use std::io::Write;
use std::sync::atomic::Ordering;

use super::atomic::TEMP_COUNTER;
use super::text::{FORMAT_CHUNK, FORMAT_GROUP, Lines, parse_i64, write_formatted};
use super::*;
use crate::Vec3;

#[test]
fn integer_tokens_read_as_rust_reads_them() {
    let cases: &[&[u8]] = &[
        b"0",
        b"7",
        b"-7",
        b"+7",
        b"0042",
        b"-0",
        b"9223372036854775807",
        b"-9223372036854775808",
        b"9223372036854775808",
        b"-9223372036854775809",
        b"99999999999999999999",
        b"",
        b"-",
        b"+",
        b"1.0",
        b"1e3",
        b"12a",
        b" 1",
        b"--1",
        b"+-1",
        b"\xd9\xa3",
        b"\xff",
    ];
    for &tok in cases {
        let std = std::str::from_utf8(tok)
            .ok()
            .and_then(|s| s.parse::<i64>().ok());
        assert_eq!(parse_i64(tok), std, "{:?}", String::from_utf8_lossy(tok));
    }
    assert_eq!(parse_i64(b"-9223372036854775808"), Some(i64::MIN));
    assert_eq!(parse_i64(b"123456"), Some(123_456));
}

fn temp_dir(tag: &str) -> PathBuf {
    let n = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("fairline-io-{tag}-{}-{n}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn quad_soup() -> Soup {
    Soup::from_polygons(
        vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.1),
            Vec3::new(0.0, 1.0, 0.0),
        ],
        &[[0u32, 1, 2, 3]],
    )
}

#[cfg(unix)]
#[test]
fn special_files_are_refused_before_they_are_read() {
    let dir = temp_dir("special-input");
    // a device that never ends, under a mesh file name
    let zero = dir.join("zero.stl");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let e = read_soup(&zero).unwrap_err();
    assert!(matches!(e, IoError::Io { .. }), "{e}");
    assert_eq!(
        e.to_string(),
        format!(
            "{}: is a device, not a regular file; give a file",
            zero.display()
        )
    );
    // a directory
    let sub = dir.join("sub.obj");
    std::fs::create_dir(&sub).unwrap();
    let e = read_mesh(&sub).unwrap_err().to_string();
    assert!(
        e.contains("sub.obj: is a directory, not a regular file"),
        "{e}"
    );
    // a FIFO: opening it would wait for a writer, so it must be refused
    // without being opened; a writer unblocks a reader that hangs
    let fifo = dir.join("pipe.obj");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    assert!(made.unwrap().success(), "mkfifo");
    let (tx, rx) = std::sync::mpsc::channel();
    let reading = fifo.clone();
    std::thread::spawn(move || tx.send(read_soup(&reading).map(|_| ())));
    let got = rx.recv_timeout(std::time::Duration::from_secs(10));
    if got.is_err() {
        drop(std::fs::OpenOptions::new().write(true).open(&fifo));
        panic!("reading a FIFO waited for a writer");
    }
    let e = got.unwrap().unwrap_err().to_string();
    assert!(
        e.contains("pipe.obj: is a FIFO (named pipe), not a regular file"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn input_files_are_read_up_to_a_cap() {
    let dir = temp_dir("cap");
    let path = dir.join("ten.bin");
    std::fs::write(&path, [7u8; 10]).unwrap();
    assert_eq!(read_input_file(&path, 10).unwrap(), vec![7u8; 10]);
    let e = read_input_file(&path, 9).unwrap_err();
    assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
    assert_eq!(
        e.to_string(),
        "is 10 bytes, more than the 9 bytes fairline reads"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn format_from_extension_is_case_insensitive() {
    assert_eq!(MeshFormat::from_path("a/B.OBJ").unwrap(), MeshFormat::Obj);
    assert_eq!(MeshFormat::from_path("x.Ply").unwrap(), MeshFormat::Ply);
    assert_eq!(MeshFormat::from_path("x.off").unwrap(), MeshFormat::Off);
    assert_eq!(MeshFormat::from_path("x.sTl").unwrap(), MeshFormat::Stl);
    let e = MeshFormat::from_path("dir/mesh.xyz").unwrap_err();
    assert!(e.to_string().contains("mesh.xyz"), "{e}");
    assert!(MeshFormat::from_path("noext").is_err());
}

#[test]
fn error_display_names_file_line_and_element() {
    let e = format_err(
        Path::new("bunny.ply"),
        Location::Line(12),
        "vertex 3: expected 3 coordinates, found 2",
    );
    assert_eq!(
        e.to_string(),
        "bunny.ply:12: vertex 3: expected 3 coordinates, found 2"
    );
    assert_eq!(e.line(), Some(12));
    let e = format_err(Path::new("b.stl"), Location::Byte(84), "triangle 0: x");
    assert_eq!(e.to_string(), "b.stl: byte 84: triangle 0: x");
}

#[test]
fn empty_file_is_an_error_in_every_format() {
    for f in [
        MeshFormat::Obj,
        MeshFormat::Ply,
        MeshFormat::Off,
        MeshFormat::Stl,
    ] {
        let e = read_soup_bytes(b"", f, "empty").unwrap_err();
        assert!(e.to_string().contains("empty file"), "{e}");
        assert!(read_soup_bytes(b" \n\r\n", f, "empty").is_err());
    }
}

/// Parallel formatting writes the same bytes as formatting one item
/// after another, across chunk and group boundaries, and passes on a
/// formatting error.
#[test]
fn formatted_writing_keeps_the_order() {
    let count = FORMAT_CHUNK * FORMAT_GROUP + FORMAT_CHUNK + 7;
    let line = |i: usize| format!("{i} {}\n", (i as f64).sqrt());
    let mut written = Vec::new();
    write_formatted(&mut written, count, |i, out| {
        out.write_all(line(i).as_bytes())
    })
    .unwrap();
    let expected: String = (0..count).map(line).collect();
    assert!(written == expected.as_bytes());
    let failing = write_formatted(&mut Vec::new(), count, |i, out| {
        if i == count - 3 {
            Err(std::io::Error::other("bad item"))
        } else {
            out.write_all(b"x")
        }
    });
    assert_eq!(failing.unwrap_err().to_string(), "bad item");
}

#[test]
fn atomic_write_failure_leaves_nothing() {
    let dir = temp_dir("atomic");
    let path = dir.join("out.obj");
    let failures = write_failures();
    let r = atomic_write(&path, |w| {
        w.write_all(b"partial")?;
        Err(std::io::Error::other("boom"))
    });
    assert!(r.is_err());
    // counted as a write that failed (other tests may add theirs)
    assert!(write_failures() > failures);
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
    // success replaces the file, failure keeps the old content
    atomic_write(&path, |w| w.write_all(b"one")).unwrap();
    assert!(atomic_write(&path, |_| Err(std::io::Error::other("no"))).is_err());
    assert_eq!(std::fs::read(&path).unwrap(), b"one");
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    // an unwritable directory is an error naming the path
    let e = atomic_write(dir.join("missing/x.obj"), |w| w.write_all(b"x")).unwrap_err();
    assert!(e.to_string().contains("missing"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn ensure_distinct_catches_same_file() {
    let dir = temp_dir("distinct");
    let input = dir.join("in.obj");
    write_soup(&input, &quad_soup()).unwrap();
    assert!(matches!(
        ensure_distinct(&input, &input),
        Err(IoError::SameFile { .. })
    ));
    let dotted = dir.join(".").join("in.obj");
    assert!(ensure_distinct(&input, &dotted).is_err());
    assert!(ensure_distinct(&input, dir.join("out.obj")).is_ok());
    std::fs::create_dir(dir.join("sub")).unwrap();
    assert!(ensure_distinct(&input, dir.join("sub/../in.obj")).is_err());
    #[cfg(unix)]
    {
        let link = dir.join("link.obj");
        std::fs::hard_link(&input, &link).unwrap();
        assert!(ensure_distinct(&input, &link).is_err());
    }
    // a missing input is an I/O error
    assert!(matches!(
        ensure_distinct(dir.join("nope.obj"), &input),
        Err(IoError::Io { .. })
    ));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn same_file_sees_symlinks_and_planned_paths() {
    let dir = temp_dir("samefile");
    let input = dir.join("in.obj");
    write_soup(&input, &quad_soup()).unwrap();
    #[cfg(unix)]
    {
        let sym = dir.join("sym.obj");
        std::os::unix::fs::symlink(&input, &sym).unwrap();
        assert!(same_file(&input, &sym));
    }
    // two spellings of a file that does not exist yet
    assert!(same_file(dir.join("new.obj"), dir.join("./new.obj")));
    assert!(!same_file(dir.join("new.obj"), dir.join("other.obj")));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[cfg(unix)]
#[test]
fn atomic_write_refuses_special_files_and_follows_symlinks() {
    let dir = temp_dir("special");
    // a directory is refused, not replaced
    let sub = dir.join("sub");
    std::fs::create_dir(&sub).unwrap();
    let e = atomic_write(&sub, |w| w.write_all(b"x")).unwrap_err();
    assert!(e.to_string().contains("directory"), "{e}");
    assert!(sub.is_dir());
    // a FIFO is refused and stays a FIFO
    let fifo = dir.join("fifo");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.map(|s| s.success()).unwrap_or(false) {
        let e = atomic_write(&fifo, |w| w.write_all(b"x")).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
        use std::os::unix::fs::FileTypeExt;
        assert!(
            std::fs::symlink_metadata(&fifo)
                .unwrap()
                .file_type()
                .is_fifo()
        );
    }
    // /dev/null is a character device: refused, never replaced
    assert!(atomic_write("/dev/null", |w| w.write_all(b"x")).is_err());
    // a symbolic link keeps being a link; its target gets the content
    let target = dir.join("target.txt");
    std::fs::write(&target, b"old").unwrap();
    let link = dir.join("link.txt");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    atomic_write(&link, |w| w.write_all(b"new")).unwrap();
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert_eq!(std::fs::read(&target).unwrap(), b"new");
    // a dangling link is refused
    let dangling = dir.join("dangling.txt");
    std::os::unix::fs::symlink(dir.join("nothing"), &dangling).unwrap();
    assert!(atomic_write(&dangling, |w| w.write_all(b"x")).is_err());
    // no temporary file is left anywhere
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_panic_while_writing_leaves_no_temporary_file() {
    let dir = temp_dir("panic");
    let path = dir.join("out.obj");
    let r = std::panic::catch_unwind(|| {
        let _ = atomic_write(&path, |w| {
            w.write_all(b"partial")?;
            panic!("writer failed");
        });
    });
    assert!(r.is_err());
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn writers_refuse_invalid_soups() {
    let dir = temp_dir("invalid");
    let mut soup = quad_soup();
    soup.positions[2].y = f64::NAN;
    let e = write_soup(dir.join("a.obj"), &soup).unwrap_err();
    assert!(e.to_string().contains("vertex 2"), "{e}");
    let soup = Soup::from_polygons(quad_soup().positions, &[[0u32, 1, 7]]);
    let e = write_soup(dir.join("a.off"), &soup).unwrap_err();
    assert!(e.to_string().contains("face 0"), "{e}");
    let soup = Soup::from_polygons(quad_soup().positions, &[[0u32, 1]]);
    assert!(write_soup(dir.join("a.ply"), &soup).is_err());
    let e = write_ply_with_vertex_properties(
        dir.join("b.ply"),
        &quad_soup(),
        &[("k", &[1.0, 2.0][..])],
    )
    .unwrap_err();
    assert!(e.to_string().contains("2 values for 4 vertices"), "{e}");
    let v = [0.0; 4];
    assert!(
        write_ply_with_vertex_properties(dir.join("b.ply"), &quad_soup(), &[("x", &v[..])])
            .is_err()
    );
    assert!(
        write_ply_with_vertex_properties(dir.join("b.ply"), &quad_soup(), &[("a b", &v[..])])
            .is_err()
    );
    assert!(write_soup(dir.join("a.xyz"), &quad_soup()).is_err());
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn lines_handle_crlf_and_missing_final_newline() {
    let v: Vec<_> = Lines::new(b"a\r\nb\n\nc", 1).collect();
    assert_eq!(
        v,
        vec![
            (1, &b"a"[..]),
            (2, &b"b"[..]),
            (3, &b""[..]),
            (4, &b"c"[..])
        ]
    );
}
