//! Tests of the PLY reader and writer: every encoding and scalar type, lists
//! and unknown elements, values that do not fit their type, round trips.

use super::*;
use crate::Vec3;

fn parse(bytes: &[u8]) -> Result<Soup, IoError> {
    read(bytes, Path::new("t.ply"), false).map(|(s, _)| s)
}

fn err(bytes: &[u8]) -> String {
    parse(bytes).unwrap_err().to_string()
}

/// A tiny byte writer for binary test files.
struct Bin {
    out: Vec<u8>,
    big: bool,
}

impl Bin {
    fn new(header: &str, big: bool) -> Self {
        Bin {
            out: header.as_bytes().to_vec(),
            big,
        }
    }
    fn f32(&mut self, v: f32) -> &mut Self {
        let b = if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.out.extend_from_slice(&b);
        self
    }
    fn f64(&mut self, v: f64) -> &mut Self {
        let b = if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.out.extend_from_slice(&b);
        self
    }
    fn i32(&mut self, v: i32) -> &mut Self {
        let b = if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.out.extend_from_slice(&b);
        self
    }
    fn u16(&mut self, v: u16) -> &mut Self {
        let b = if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.out.extend_from_slice(&b);
        self
    }
    fn u8(&mut self, v: u8) -> &mut Self {
        self.out.push(v);
        self
    }
}

const ASCII: &str = "ply\r\nformat ascii 1.0\r\ncomment hello\r\nobj_info made by hand\r\n\
    element vertex 4\r\nproperty float y\r\nproperty float x\r\nproperty uchar red\r\n\
    property float z\r\nelement face 2\r\nproperty list uchar int vertex_indices\r\n\
    end_header\r\n0 0 255 0\r\n0 1 0 0\r\n1 1 3 0\r\n1 0 4 0.5\r\n4 0 1 2 3\r\n3 0 2 3\r\n";

#[test]
fn ascii_with_permuted_properties_comments_crlf_and_quads() {
    let s = parse(ASCII.as_bytes()).unwrap();
    assert_eq!(s.vertex_count(), 4);
    assert_eq!(s.positions[1], Vec3::new(1.0, 0.0, 0.0));
    assert_eq!(s.positions[3], Vec3::new(0.0, 1.0, 0.5));
    assert_eq!(s.face(0), &[0, 1, 2, 3]);
    assert_eq!(s.face(1), &[0, 2, 3]);
    let (_, extra) = read(ASCII.as_bytes(), Path::new("t.ply"), true).unwrap();
    assert_eq!(extra, vec![("red".to_string(), vec![255.0, 0.0, 3.0, 4.0])]);
}

/// A binary file with faces before vertices, an edge element with a
/// list, a material element, a list in the vertex element, and face
/// properties around the index list.
fn tricky_binary(big: bool) -> Vec<u8> {
    let header = format!(
        "ply\nformat binary_{}_endian 1.0\ncomment tricky\n\
         element material 1\nproperty uchar r\nproperty double shininess\n\
         element face 2\nproperty ushort flags\nproperty list uchar int vertex_index\n\
         property list int float texcoord\n\
         element vertex 4\nproperty double z\nproperty list uchar uchar tags\n\
         property float x\nproperty double y\nproperty float quality\n\
         element edge 1\nproperty list uchar int vertex_indices\nproperty uchar crease\n\
         end_header\n",
        if big { "big" } else { "little" }
    );
    let mut b = Bin::new(&header, big);
    b.u8(7).f64(0.5);
    b.u16(1).u8(4).i32(0).i32(1).i32(2).i32(3);
    b.i32(2).f32(0.25).f32(0.75);
    b.u16(2).u8(3).i32(3).i32(2).i32(1);
    b.i32(0);
    let xyz = [
        [0.0, 0.0, 0.1],
        [1.0, 0.0, 0.2],
        [1.0, 1.0, 0.3],
        [0.0, 1.0, 0.4],
    ];
    for (i, p) in xyz.iter().enumerate() {
        b.f64(p[2]).u8(i as u8);
        for _ in 0..i {
            b.u8(9);
        }
        b.f32(p[0] as f32).f64(p[1]).f32(i as f32 * 10.0);
    }
    b.u8(2).i32(0).i32(1).u8(1);
    b.out
}

#[test]
fn binary_little_and_big_endian_with_lists_and_extra_elements() {
    for big in [false, true] {
        let bytes = tricky_binary(big);
        let (s, extra) = read(&bytes, Path::new("t.ply"), true).unwrap();
        assert_eq!(s.vertex_count(), 4, "big={big}");
        assert_eq!(s.positions[2], Vec3::new(1.0, 1.0, 0.3));
        assert_eq!(s.face(0), &[0, 1, 2, 3]);
        assert_eq!(s.face(1), &[3, 2, 1]);
        assert_eq!(
            extra,
            vec![("quality".to_string(), vec![0.0, 10.0, 20.0, 30.0])]
        );
        // every truncation is an error, never a panic
        for cut in 0..bytes.len() {
            assert!(parse(&bytes[..cut]).is_err(), "cut {cut} big={big}");
        }
    }
}

#[test]
fn write_then_read_is_bit_exact_with_properties_and_big_faces() {
    let n = 300;
    let positions: Vec<Vec3> = (0..n)
        .map(|i| {
            let t = i as f64 * 0.1;
            Vec3::new(t.sin() / 3.0, -0.0, t.cos() * 1e-310)
        })
        .collect();
    let ring: Vec<u32> = (0..n as u32).collect();
    let soup = Soup::from_polygons(positions, &[ring, vec![0, 1, 2, 3]]);
    let k: Vec<f64> = (0..n).map(|i| i as f64 / 7.0).collect();
    let mut out = Vec::new();
    write(&mut out, &soup, &[("k1", &k)]).unwrap();
    let text = String::from_utf8_lossy(&out[..400]).to_string();
    assert!(
        text.contains("property list uint int vertex_indices"),
        "{text}"
    );
    let (back, extra) = read(&out, Path::new("x.ply"), true).unwrap();
    assert_eq!(back.offsets, soup.offsets);
    assert_eq!(back.indices, soup.indices);
    for (a, b) in back.positions.iter().zip(&soup.positions) {
        assert_eq!(
            a.to_array().map(f64::to_bits),
            b.to_array().map(f64::to_bits)
        );
    }
    assert_eq!(extra[0].0, "k1");
    assert!(
        extra[0]
            .1
            .iter()
            .zip(&k)
            .all(|(a, b)| a.to_bits() == b.to_bits())
    );
    let small = Soup::from_polygons(soup.positions.clone(), &[[0u32, 1, 2]]);
    let mut out = Vec::new();
    write(&mut out, &small, &[]).unwrap();
    assert!(String::from_utf8_lossy(&out[..300]).contains("list uchar int vertex_indices"));
}

#[test]
fn malformed_headers_name_the_line() {
    let e = err(b"plx\nformat ascii 1.0\nend_header\n");
    assert!(e.starts_with("t.ply:1: not a PLY file"), "{e}");
    let e = err(b"ply\nformat binary_middle_endian 1.0\nend_header\n");
    assert_eq!(e, "t.ply:2: unknown PLY format 'binary_middle_endian'");
    let e = err(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\nend_header\n");
    assert_eq!(e, "t.ply:4: unknown property type 'real'");
    let e = err(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n");
    assert_eq!(e, "t.ply:3: element vertex has no property z");
    let e = err(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n");
    assert!(e.contains("no end_header"), "{e}");
    let e = err(b"ply\nformat ascii 1.0\nelement vertex -1\nend_header\n");
    assert!(
        e.starts_with("t.ply:3: element vertex: cannot read count"),
        "{e}"
    );
    let e = err(b"ply\nelement vertex 1\nproperty float x\nend_header\n");
    assert!(e.contains("no format line"), "{e}");
    let e = err(b"ply\nformat ascii 1.0\nbogus line\nend_header\n");
    assert!(e.starts_with("t.ply:3: unexpected header line"), "{e}");
    let e = err(b"ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n");
    assert!(e.contains("no vertex element"), "{e}");
}

const HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

#[test]
fn malformed_ascii_bodies_name_line_and_element() {
    let f = |body: &str| err(format!("{HEAD}{body}").as_bytes());
    assert_eq!(
        f("0 0 0\n1 0\n0 1 0\n3 0 1 2\n"),
        "t.ply:11: vertex 1: expected 3 values, found 2"
    );
    assert!(
        f("0 0 0\n1 0 abc\n0 1 0\n3 0 1 2\n").starts_with("t.ply:11: vertex 1: cannot read 'abc'")
    );
    assert!(
        f("0 0 0\n1 0 0\nnan 1 0\n3 0 1 2\n")
            .starts_with("t.ply:12: vertex 2: coordinate is not finite")
    );
    assert!(
        f("0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n")
            .starts_with("t.ply:13: face 0: vertex index 3 out of range (3 vertices)")
    );
    assert!(
        f("0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n")
            .starts_with("t.ply:13: face 0: vertex index -1 out of range")
    );
    assert_eq!(
        f("0 0 0\n1 0 0\n0 1 0\n2 0 1\n"),
        "t.ply:13: face 0: has 2 vertices; a face needs at least 3"
    );
    assert_eq!(
        f("0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n"),
        "t.ply:13: face 0: expected 5 values, found 4"
    );
    assert_eq!(
        f("0 0 0\n1 0 0 7\n0 1 0\n3 0 1 2\n"),
        "t.ply:11: vertex 1: expected 3 values, found 4"
    );
    assert!(
        f("0 0 0\n1 0 0\n0 1 0\nx 0 1 2\n")
            .starts_with("t.ply:13: face 0: cannot read list length 'x'")
    );
    // the header announces more rows than the file has
    assert!(f("0 0 0\n1 0 0\n").starts_with("t.ply:11: vertex 2: unexpected end of file"));
    let huge = HEAD.replace("vertex 3", "vertex 4000000000000");
    let e = err(format!("{huge}0 0 0\n").as_bytes());
    assert!(e.contains("vertex 1: unexpected end of file"), "{e}");
}

#[test]
fn malformed_binary_bodies_name_byte_and_element() {
    let head = HEAD.replace("ascii", "binary_little_endian");
    let mut b = Bin::new(&head, false);
    b.f32(0.0).f32(0.0).f32(0.0).f32(1.0).f32(f32::NAN).f32(0.0);
    b.f32(0.0).f32(1.0).f32(0.0).u8(3).i32(0).i32(1).i32(2);
    let e = err(&b.out);
    assert!(
        e.contains(&format!(
            "byte {}: vertex 1: coordinate is not finite",
            head.len() + 12
        )),
        "{e}"
    );
    let mut b = Bin::new(&head, false);
    for v in [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        b.f32(v);
    }
    let good_vertices = b.out.clone();
    b.u8(3).i32(0).i32(1).i32(5);
    assert!(err(&b.out).contains("face 0: vertex index 5 out of range (3 vertices)"));
    let mut b = Bin {
        out: good_vertices.clone(),
        big: false,
    };
    b.u8(2).i32(0).i32(1);
    assert!(err(&b.out).contains("face 0: has 2 vertices"));
    let mut b = Bin {
        out: good_vertices.clone(),
        big: false,
    };
    b.u8(3).i32(0).i32(1);
    let e = err(&b.out);
    assert!(e.contains("face 0: file ends inside the element"), "{e}");
    // counts larger than the file are refused before allocating
    let huge = head.replace("vertex 3", "vertex 18446744073709551615");
    let e = err(&[huge.as_bytes(), &good_vertices[head.len()..]].concat());
    assert!(
        e.contains("element vertex: the header announces 18446744073709551615 rows"),
        "{e}"
    );
    let huge = head.replace("face 1", "face 3000000000");
    let e = err(&[huge.as_bytes(), &good_vertices[head.len()..]].concat());
    assert!(
        e.contains("element face: the header announces 3000000000 rows"),
        "{e}"
    );
}
