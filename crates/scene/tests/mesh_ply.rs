//! PLY reader tests: round trips through files written in all three formats, and errors.

use ircache_math::{Vec2, Vec3};
use ircache_scene::mesh::{parse_ply, read_ply};
use ircache_scene::TriangleMesh;
use ircache_testing::ScratchDir;
use std::path::PathBuf;
use std::sync::Arc;

fn temp_dir(name: &str) -> ScratchDir {
    ScratchDir::new(&format!("mesh-ply-{name}"))
}

fn sample() -> TriangleMesh {
    let positions = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.5, 0.0, 0.0),
        Vec3::new(1.5, 2.0, 0.0),
        Vec3::new(0.0, 2.0, 0.25),
        Vec3::new(-1.0, 1.0, 0.125),
    ];
    let normals = vec![
        Vec3::Z,
        Vec3::Z,
        Vec3::Z,
        Vec3::new(0.0, 0.6, 0.8),
        Vec3::new(0.0, 0.0, -1.0),
    ];
    let uvs = vec![
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(0.0, 1.0),
        Vec2::new(0.5, 0.5),
    ];
    TriangleMesh {
        positions,
        normals: Some(normals),
        uvs: Some(uvs),
        indices: vec![[0, 1, 2], [0, 2, 3], [3, 4, 0]],
    }
}

/// Writes `m` as PLY: a uchar/int face list (as a quad plus a triangle), plus an unknown vertex
/// property, an unknown list on faces and an unknown element, all of which must be skipped.
fn write_ply(m: &TriangleMesh, format: &str) -> Vec<u8> {
    let mut out = format!(
        "ply\r\nformat {format} 1.0\ncomment written by the test\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nproperty uchar alpha\nproperty float nx\nproperty float ny\nproperty float nz\n\
         property double s\nproperty double t\nelement face 2\nproperty list uchar int vertex_indices\n\
         property list ushort short junk\nelement material 2\nproperty list uint double coeffs\nproperty int id\nend_header\n",
        m.positions.len()
    )
    .into_bytes();
    let faces: [&[u32]; 2] = [&[0, 1, 2, 3], &[3, 4, 0]];
    let big = format == "binary_big_endian";
    macro_rules! put {
        ($v:expr) => {{
            let v = $v;
            out.extend_from_slice(&if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            });
        }};
    }
    if format == "ascii" {
        use std::fmt::Write;
        let mut s = String::new();
        for i in 0..m.positions.len() {
            let (p, n, uv) = (
                m.positions[i],
                m.normals.as_ref().unwrap()[i],
                m.uvs.as_ref().unwrap()[i],
            );
            writeln!(
                s,
                "{} {} {} 255 {} {} {} {} {}",
                p.x, p.y, p.z, n.x, n.y, n.z, uv.x, uv.y
            )
            .unwrap();
        }
        for f in faces {
            let idx: Vec<String> = f.iter().map(|i| i.to_string()).collect();
            writeln!(s, "{} {} 2 -1 7", f.len(), idx.join(" ")).unwrap();
        }
        s.push_str("3 0.5 1e-3 2 17\n0 18\n");
        out.extend_from_slice(s.as_bytes());
    } else {
        for i in 0..m.positions.len() {
            let (p, n, uv) = (
                m.positions[i],
                m.normals.as_ref().unwrap()[i],
                m.uvs.as_ref().unwrap()[i],
            );
            for c in p.to_array() {
                put!(c);
            }
            out.push(255);
            for c in n.to_array() {
                put!(c);
            }
            put!(f64::from(uv.x));
            put!(f64::from(uv.y));
        }
        for f in faces {
            out.push(f.len() as u8);
            for &i in f {
                put!(i as i32);
            }
            put!(2u16);
            put!(-1i16);
            put!(7i16);
        }
        put!(3u32);
        put!(0.5f64);
        put!(1e-3f64);
        put!(2f64);
        put!(17i32);
        put!(0u32);
        put!(18i32);
    }
    out
}

fn assert_same(a: &TriangleMesh, b: &TriangleMesh) {
    assert_eq!(a.positions, b.positions);
    assert_eq!(a.uvs, b.uvs);
    assert_eq!(a.indices, b.indices);
    let (na, nb) = (a.normals.as_ref().unwrap(), b.normals.as_ref().unwrap());
    for (x, y) in na.iter().zip(nb) {
        assert!((*x - *y).length() < 1e-6, "{x:?} {y:?}");
    }
}

#[test]
fn round_trip_all_formats() {
    let m = sample();
    let dir = temp_dir("rt");
    for format in ["ascii", "binary_little_endian", "binary_big_endian"] {
        let path = dir.join(format!("{format}.ply"));
        std::fs::write(&path, write_ply(&m, format)).unwrap();
        let back = read_ply(&path).unwrap_or_else(|e| panic!("{format}: {e}"));
        assert_same(&m, &back);
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn truncated_binary() {
    let m = sample();
    let bytes = write_ply(&m, "binary_little_endian");
    let header_len = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    // Cut inside vertex 3 (each vertex is 3·4 + 1 + 3·4 + 2·8 = 41 bytes).
    let cut = header_len + 3 * 41 + 10;
    let e = parse_ply(&bytes[..cut], Arc::new(PathBuf::from("cut.ply")))
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        format!(
            "cut.ply: cannot read: vertex 3: truncated binary data (property 'z') (at byte {})",
            header_len + 3 * 41 + 8
        )
    );
    // Cut inside the face list.
    let cut = header_len + 5 * 41 + 3;
    let e = parse_ply(&bytes[..cut], Arc::new(PathBuf::from("cut.ply")))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("cut.ply: cannot read: face 0: truncated binary data"),
        "{e}"
    );
}

#[test]
fn bad_headers() {
    let parse = |s: &str| {
        parse_ply(s.as_bytes(), Arc::new(PathBuf::from("h.ply")))
            .unwrap_err()
            .to_string()
    };
    assert_eq!(
        parse("ply\nformat ascii 1.0\nelement vertex x3\n"),
        "h.ply:3:16: expected an element count, found 'x3'"
    );
    assert_eq!(
        parse("ply\nformat binary_middle_endian 1.0\nend_header\n"),
        "h.ply:2:8: expected 'ascii', 'binary_little_endian' or 'binary_big_endian' after 'format', found 'binary_middle_endian'"
    );
    assert_eq!(
        parse("ply\nformat ascii 1.0\nproperty float x\n"),
        "h.ply:3:1: 'property' before any 'element'"
    );
    assert_eq!(
        parse("ply\nformat ascii 1.0\nelement vertex 0\n"),
        "h.ply:3:1: PLY header has no 'end_header' line"
    );
    assert_eq!(
        parse("ply\nformat ascii 1.0\nelemnt vertex 0\nend_header\n"),
        "h.ply:3:1: unknown PLY header keyword 'elemnt'"
    );
    assert_eq!(
        parse("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n"),
        "h.ply:3:1: the 'vertex' element has no property 'z'"
    );
}

#[test]
fn face_errors() {
    let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                element face 1\nproperty list uchar uint vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
    let parse = |s: &str| {
        parse_ply(s.as_bytes(), Arc::new(PathBuf::from("f.ply")))
            .unwrap_err()
            .to_string()
    };
    assert_eq!(
        parse(&format!("{head}3 0 1 7\n")),
        "f.ply:13:7: face 0: vertex index 7 out of range (file has 3 vertices)"
    );
    assert_eq!(
        parse(&format!("{head}2 0 1\n")),
        "f.ply:13:1: face 0: face with 2 vertices (at least 3 needed)"
    );
    assert_eq!(
        parse(&format!("{head}3 0 1\n")),
        "f.ply:14:1: face 0: unexpected end of file (property 'vertex_indices')"
    );
}
