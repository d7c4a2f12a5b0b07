//! Mitsuba's serialized meshes (`.serialized`, the `serialized` shape of Mitsuba 0.4 to 3, the
//! format its exporters write): per mesh a little-endian header (`u16` 0x041C, `u16` version 3 or
//! 4) and a zlib stream holding `u32` flags, the mesh's name (version 4, NUL-terminated), `u64`
//! vertex and triangle counts, then positions, normals, texture coordinates and colours (as the
//! flags say, in single or double precision) and `u32` index triples. Several meshes are
//! concatenated; the file ends with each mesh's byte offset (`u64` in version 4, `u32` in 3) and
//! the count (`u32`), which `shape_index` reads.
//!
//! As Mitsuba 3 (`src/shapes/serialized.cpp`): texture coordinates are kept as written, colours
//! are skipped, the face-normals flag drops the vertex normals. As the other readers here: normals
//! are normalised (a zero-length or non-finite one is an error), degenerate triangles are dropped
//! and counted, an index past the vertices or a non-finite value is an error, and the declared counts never allocate
//! more than the compressed bytes can hold (deflate expands at most 1032:1).

use super::is_degenerate;
use crate::desc::TriangleMesh;
use crate::error::SceneError;
use ircache_math::{Vec2, Vec3};
use std::io::Read;
use std::path::Path;

const FORMAT: u16 = 0x041C;
const HAS_NORMALS: u32 = 0x0001;
const HAS_TEXCOORDS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const FACE_NORMALS: u32 = 0x0010;
const DOUBLE_PRECISION: u32 = 0x2000;

/// Most bytes deflate can expand one compressed byte to (RFC 1951's longest match per bit pair).
const MAX_EXPANSION: usize = 1032;

/// One mesh of a serialized file.
#[derive(Clone, Debug)]
pub struct SerializedMesh {
    /// The geometry (normals absent when the file asks for face normals or has none).
    pub mesh: TriangleMesh,
    /// The mesh's name (empty in version 3 files).
    pub name: String,
    /// Degenerate triangles dropped.
    pub degenerate_dropped: usize,
}

/// Reads mesh `shape_index` of the serialized file at `path`.
pub fn read_serialized(path: &Path, shape_index: usize) -> Result<SerializedMesh, SceneError> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_serialized(&bytes, shape_index).map_err(|message| SceneError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, message),
    })
}

fn u16_at(bytes: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(bytes.get(at..at + 2)?.try_into().ok()?))
}

fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?))
}

fn u64_at(bytes: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(bytes.get(at..at + 8)?.try_into().ok()?))
}

/// The version of the mesh header at byte `at`.
fn header(bytes: &[u8], at: usize) -> Result<u16, String> {
    let (Some(format), Some(version)) = (u16_at(bytes, at), u16_at(bytes, at + 2)) else {
        return Err(format!("truncated mesh header at byte {at}"));
    };
    if format != FORMAT {
        return Err(format!(
            "not a Mitsuba serialized mesh: format identifier {format:#06x} at byte {at}, expected 0x041c"
        ));
    }
    if version != 3 && version != 4 {
        return Err(format!(
            "unsupported serialized version {version} at byte {at} (3 or 4 expected)"
        ));
    }
    Ok(version)
}

/// The byte offset of mesh `shape_index`, from the end-of-file dictionary.
fn mesh_offset(bytes: &[u8], version: u16, shape_index: usize) -> Result<usize, String> {
    if shape_index == 0 {
        return Ok(0);
    }
    let end = bytes.len();
    let count = end
        .checked_sub(4)
        .and_then(|at| u32_at(bytes, at))
        .ok_or("no end-of-file dictionary")? as usize;
    if shape_index >= count {
        return Err(format!(
            "shape_index {shape_index} is out of range: the file holds {count} mesh{}",
            if count == 1 { "" } else { "es" }
        ));
    }
    let width = if version == 4 { 8 } else { 4 };
    let entry = (count - shape_index)
        .checked_mul(width)
        .and_then(|d| end.checked_sub(4 + d))
        .ok_or("the end-of-file dictionary is longer than the file")?;
    let offset = if version == 4 {
        u64_at(bytes, entry).map(|o| usize::try_from(o).unwrap_or(usize::MAX))
    } else {
        u32_at(bytes, entry).map(|o| o as usize)
    }
    .ok_or("truncated end-of-file dictionary")?;
    if offset >= end {
        return Err(format!(
            "mesh {shape_index}'s offset {offset} lies past the end of the file ({end} bytes)"
        ));
    }
    Ok(offset)
}

/// Parses mesh `shape_index` of a serialized file's bytes; the error says what and where.
pub fn parse_serialized(bytes: &[u8], shape_index: usize) -> Result<SerializedMesh, String> {
    let version = header(bytes, 0)?;
    let offset = mesh_offset(bytes, version, shape_index)?;
    let version = header(bytes, offset)?;
    let compressed = &bytes[offset + 4..];
    let mut z = flate2::read::ZlibDecoder::new(compressed);
    let corrupt = |what: &str, e: std::io::Error| {
        format!("mesh {shape_index} (at byte {offset}): {what}: corrupt or truncated compressed data ({e})")
    };
    let mut word = [0u8; 8];
    z.read_exact(&mut word[..4])
        .map_err(|e| corrupt("flags", e))?;
    let flags = u32::from_le_bytes(word[..4].try_into().expect("four bytes"));
    let mut name = Vec::new();
    if version == 4 {
        let mut byte = [0u8; 1];
        loop {
            z.read_exact(&mut byte).map_err(|e| corrupt("name", e))?;
            if byte[0] == 0 {
                break;
            }
            name.push(byte[0]);
            if name.len() > 1 << 16 {
                return Err(format!("mesh {shape_index}: its name runs past 64 KiB"));
            }
        }
    }
    let name = String::from_utf8_lossy(&name).into_owned();
    z.read_exact(&mut word)
        .map_err(|e| corrupt("vertex count", e))?;
    let vertex_count = u64::from_le_bytes(word);
    z.read_exact(&mut word)
        .map_err(|e| corrupt("triangle count", e))?;
    let triangle_count = u64::from_le_bytes(word);
    let what = format!(
        "mesh {shape_index} (\"{name}\", {vertex_count} vertices, {triangle_count} triangles)"
    );
    if vertex_count > u64::from(u32::MAX) {
        return Err(format!("{what}: more vertices than 32-bit indices address"));
    }

    let double = flags & DOUBLE_PRECISION != 0;
    let float_size = if double { 8 } else { 4 };
    let has = |flag: u32| flags & flag != 0;
    let per_vertex = 3
        + 3 * usize::from(has(HAS_NORMALS))
        + 2 * usize::from(has(HAS_TEXCOORDS))
        + 3 * usize::from(has(HAS_COLORS));
    let needed = usize::try_from(vertex_count)
        .ok()
        .and_then(|v| v.checked_mul(per_vertex * float_size))
        .zip(
            usize::try_from(triangle_count)
                .ok()
                .and_then(|t| t.checked_mul(12)),
        )
        .and_then(|(v, t)| v.checked_add(t));
    let Some(needed) = needed.filter(|&n| n <= compressed.len().saturating_mul(MAX_EXPANSION))
    else {
        return Err(format!(
            "{what}: more data than its {} compressed bytes can hold",
            compressed.len()
        ));
    };
    let mut data = vec![0u8; needed];
    z.read_exact(&mut data)
        .map_err(|e| corrupt("vertex and triangle data", e))?;

    let vertex_count = vertex_count as usize;
    let mut at = 0usize;
    let mut floats = |n: usize| -> Vec<f64> {
        let values = data[at..at + n * float_size]
            .chunks_exact(float_size)
            .map(|c| {
                if double {
                    f64::from_le_bytes(c.try_into().expect("eight bytes"))
                } else {
                    f64::from(f32::from_le_bytes(c.try_into().expect("four bytes")))
                }
            })
            .collect();
        at += n * float_size;
        values
    };
    let vec3s = |v: Vec<f64>| -> Vec<Vec3> {
        v.chunks_exact(3)
            .map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
            .collect()
    };
    let positions = vec3s(floats(3 * vertex_count));
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("{what}: vertex {i}'s position is not finite"));
    }
    let normals = if has(HAS_NORMALS) {
        let mut normals = vec3s(floats(3 * vertex_count));
        for (i, n) in normals.iter_mut().enumerate() {
            let length = n.length();
            if !(length.is_finite() && length > 0.0) {
                return Err(format!("{what}: vertex {i}'s normal has zero or no length"));
            }
            *n /= length;
        }
        Some(normals)
    } else {
        None
    };
    let uvs = if has(HAS_TEXCOORDS) {
        let uvs: Vec<Vec2> = floats(2 * vertex_count)
            .chunks_exact(2)
            .map(|c| Vec2::new(c[0] as f32, c[1] as f32))
            .collect();
        if let Some(i) = uvs.iter().position(|uv| !uv.is_finite()) {
            return Err(format!(
                "{what}: vertex {i}'s texture coordinates are not finite"
            ));
        }
        Some(uvs)
    } else {
        None
    };
    if has(HAS_COLORS) {
        floats(3 * vertex_count);
    }
    let mut indices = Vec::with_capacity(triangle_count as usize);
    let mut degenerate_dropped = 0;
    for (t, chunk) in data[at..].chunks_exact(12).enumerate() {
        let tri: [u32; 3] = std::array::from_fn(|k| {
            u32::from_le_bytes(chunk[4 * k..4 * k + 4].try_into().expect("four bytes"))
        });
        if let Some(&v) = tri.iter().find(|&&v| v as usize >= vertex_count) {
            return Err(format!(
                "{what}: triangle {t} names vertex {v}, past the last"
            ));
        }
        let [a, b, c] = tri.map(|v| positions[v as usize]);
        if is_degenerate(a, b, c) {
            degenerate_dropped += 1;
        } else {
            indices.push(tri);
        }
    }
    if triangle_count > 0 && indices.is_empty() {
        return Err(format!("{what}: every triangle is degenerate (zero area)"));
    }
    Ok(SerializedMesh {
        mesh: TriangleMesh {
            positions,
            normals: normals.filter(|_| !has(FACE_NORMALS)),
            uvs,
            indices,
        },
        name,
        degenerate_dropped,
    })
}

/// Writes meshes in the serialized format (version 4, single precision): the tests' and the
/// benchmarks' way to make files that exercise [`parse_serialized`].
#[must_use]
pub fn write_serialized(meshes: &[(&str, &TriangleMesh, bool)]) -> Vec<u8> {
    use std::io::Write;
    let mut out = Vec::new();
    let mut offsets = Vec::new();
    for (name, mesh, face_normals) in meshes {
        offsets.push(out.len() as u64);
        out.extend_from_slice(&FORMAT.to_le_bytes());
        out.extend_from_slice(&4u16.to_le_bytes());
        let mut flags = 0x1000;
        flags |= if mesh.normals.is_some() {
            HAS_NORMALS
        } else {
            0
        };
        flags |= if mesh.uvs.is_some() { HAS_TEXCOORDS } else { 0 };
        flags |= if *face_normals { FACE_NORMALS } else { 0 };
        let mut body = Vec::new();
        body.extend_from_slice(&u32::to_le_bytes(flags));
        body.extend_from_slice(name.as_bytes());
        body.push(0);
        body.extend_from_slice(&(mesh.positions.len() as u64).to_le_bytes());
        body.extend_from_slice(&(mesh.indices.len() as u64).to_le_bytes());
        let mut put = |values: &[f32]| {
            for v in values {
                body.extend_from_slice(&v.to_le_bytes());
            }
        };
        for p in &mesh.positions {
            put(&p.to_array());
        }
        for n in mesh.normals.iter().flatten() {
            put(&n.to_array());
        }
        for uv in mesh.uvs.iter().flatten() {
            put(&uv.to_array());
        }
        for tri in &mesh.indices {
            for v in tri {
                body.extend_from_slice(&v.to_le_bytes());
            }
        }
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&body).expect("writing to memory");
        out.extend_from_slice(&z.finish().expect("writing to memory"));
    }
    for o in &offsets {
        out.extend_from_slice(&o.to_le_bytes());
    }
    out.extend_from_slice(&(offsets.len() as u32).to_le_bytes());
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(offset: f32) -> TriangleMesh {
        TriangleMesh {
            positions: vec![
                Vec3::new(offset, 0.0, 0.0),
                Vec3::new(offset + 1.0, 0.0, 0.0),
                Vec3::new(offset + 1.0, 1.0, 0.0),
                Vec3::new(offset, 1.0, 0.0),
            ],
            normals: Some(vec![Vec3::new(0.0, 0.0, 2.0); 4]),
            uvs: Some(vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(0.0, 1.0),
            ]),
            indices: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    #[test]
    fn meshes_are_read_back_by_index() {
        let (a, mut b) = (quad(0.0), quad(5.0));
        b.uvs = None;
        // A degenerate triangle in the second mesh is dropped and counted.
        b.indices.push([0, 0, 1]);
        let file = write_serialized(&[("first", &a, false), ("second", &b, true)]);
        let first = parse_serialized(&file, 0).unwrap();
        assert_eq!(first.name, "first");
        assert_eq!(first.mesh.positions, a.positions);
        assert_eq!(first.mesh.indices, a.indices);
        assert_eq!(first.mesh.uvs, a.uvs);
        // Normals normalised.
        assert_eq!(first.mesh.normals, Some(vec![Vec3::Z; 4]));
        let second = parse_serialized(&file, 1).unwrap();
        assert_eq!(second.name, "second");
        assert_eq!(second.mesh.positions[0], Vec3::new(5.0, 0.0, 0.0));
        assert_eq!(second.mesh.indices.len(), 2);
        assert_eq!(second.degenerate_dropped, 1);
        // The face-normals flag drops the vertex normals; no texture coordinates were written.
        assert!(second.mesh.normals.is_none() && second.mesh.uvs.is_none());
        let e = parse_serialized(&file, 2).unwrap_err();
        assert!(
            e.contains("shape_index 2 is out of range: the file holds 2 meshes"),
            "{e}"
        );
    }

    #[test]
    fn version_3_double_precision_and_colours() {
        use std::io::Write;
        // Hand-made: version 3 (no name, u32 offsets), doubles, vertex colours to skip.
        let mut body = Vec::new();
        body.extend_from_slice(&(DOUBLE_PRECISION | HAS_COLORS).to_le_bytes());
        body.extend_from_slice(&3u64.to_le_bytes());
        body.extend_from_slice(&1u64.to_le_bytes());
        for v in [0.0f64, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1e-300, 1.0] {
            body.extend_from_slice(&v.to_le_bytes());
        }
        for v in [0.5f64; 9] {
            body.extend_from_slice(&v.to_le_bytes());
        }
        for i in [0u32, 1, 2] {
            body.extend_from_slice(&i.to_le_bytes());
        }
        let mut file = vec![0x1C, 0x04, 3, 0];
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
        z.write_all(&body).unwrap();
        file.extend_from_slice(&z.finish().unwrap());
        let second = file.len() as u32;
        file.extend_from_slice(&file.clone());
        file.extend_from_slice(&0u32.to_le_bytes());
        file.extend_from_slice(&second.to_le_bytes());
        file.extend_from_slice(&2u32.to_le_bytes());
        for index in [0, 1] {
            let m = parse_serialized(&file, index).unwrap();
            assert_eq!(m.mesh.positions[2], Vec3::new(0.0, 0.0, 1.0));
            assert_eq!(m.mesh.indices, vec![[0, 1, 2]]);
            assert!(m.mesh.normals.is_none() && m.name.is_empty());
        }
    }

    #[test]
    fn corrupt_files_are_errors_that_say_what() {
        let good = write_serialized(&[("q", &quad(0.0), false)]);
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (b"PLY\n".to_vec(), "not a Mitsuba serialized mesh"),
            (vec![0x1C, 0x04, 9, 0], "unsupported serialized version 9"),
            (good[..good.len() / 2].to_vec(), "corrupt or truncated"),
            (
                {
                    let mut bad = good.clone();
                    bad[20] ^= 0xFF;
                    bad
                },
                "corrupt or truncated",
            ),
            (
                {
                    let mut q = quad(0.0);
                    q.indices[1] = [0, 2, 7];
                    write_serialized(&[("q", &q, false)])
                },
                "triangle 1 names vertex 7, past the last",
            ),
            (
                {
                    let mut q = quad(0.0);
                    q.normals.as_mut().unwrap()[3] = Vec3::ZERO;
                    write_serialized(&[("q", &q, false)])
                },
                "vertex 3's normal has zero or no length",
            ),
        ];
        for (bytes, expected) in cases {
            let e = parse_serialized(&bytes, 0).unwrap_err();
            assert!(e.contains(expected), "{e:?} should say {expected:?}");
        }
    }

    #[test]
    fn huge_counts_do_not_allocate() {
        use std::io::Write;
        let mut body = Vec::new();
        body.extend_from_slice(&0x1000u32.to_le_bytes());
        body.push(0);
        body.extend_from_slice(&(u64::from(u32::MAX)).to_le_bytes());
        body.extend_from_slice(&(u64::MAX / 2).to_le_bytes());
        let mut file = vec![0x1C, 0x04, 4, 0];
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
        z.write_all(&body).unwrap();
        file.extend_from_slice(&z.finish().unwrap());
        let e = parse_serialized(&file, 0).unwrap_err();
        assert!(e.contains("more data than its"), "{e}");
    }
}
