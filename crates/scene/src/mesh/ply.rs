//! Stanford PLY reader: `ascii`, `binary_little_endian` and `binary_big_endian` bodies.
//!
//! From the `vertex` element it reads `x y z`, optionally `nx ny nz` (normalised; a zero-length
//! normal is an error) and texture coordinates named `u v`, `s t`, `texture_u texture_v` or
//! `texture_s texture_t` (kept as written: Mitsuba 3's `ply` plugin does not flip them). From the
//! `face` element it reads the `vertex_indices` (or `vertex_index`) list, of any integer types;
//! polygons are triangulated by [`triangulate_polygon`]. Every other element and property, lists
//! included, is skipped. Degenerate triangles are dropped; a file whose every triangle is
//! degenerate is an error.
//!
//! Errors name the header line and column (`file:3:10: unknown property type 'flaot'`), the token
//! of an ASCII body (`file:12:5: vertex 3: expected a number for property 'y', found 'x'`), or
//! the element and byte offset of a binary body (`file: cannot read: vertex 17: truncated binary
//! data (at byte 412)`). The reader never panics on malformed input and never allocates more than
//! the file's size allows: declared counts only bound loops that consume input.

use super::{is_degenerate, triangulate_polygon};
use crate::desc::TriangleMesh;
use crate::error::{SceneError, SourceLocation};
use ircache_math::{Vec2, Vec3};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Reads a PLY file into one mesh; see the [module documentation](self).
pub fn read_ply(path: &Path) -> Result<TriangleMesh, SceneError> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_ply(&bytes, Arc::new(path.to_path_buf()))
}

/// Parses the bytes of a PLY file; `file` is the name used in errors.
pub fn parse_ply(bytes: &[u8], file: Arc<PathBuf>) -> Result<TriangleMesh, SceneError> {
    let header = parse_header(bytes, &file)?;
    read_body(bytes, &header, &file)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
    fn range(self) -> (f64, f64) {
        match self {
            Scalar::I8 => (i8::MIN.into(), i8::MAX.into()),
            Scalar::U8 => (0.0, u8::MAX.into()),
            Scalar::I16 => (i16::MIN.into(), i16::MAX.into()),
            Scalar::U16 => (0.0, u16::MAX.into()),
            Scalar::I32 => (i32::MIN.into(), i32::MAX.into()),
            Scalar::U32 => (0.0, u32::MAX.into()),
            Scalar::F32 | Scalar::F64 => (f64::NEG_INFINITY, f64::INFINITY),
        }
    }
}

#[derive(Clone, Debug)]
enum PropKind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    kind: PropKind,
    location: SourceLocation,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
    location: SourceLocation,
}

struct Header {
    format: Format,
    elements: Vec<Element>,
    body_start: usize,
    /// Line number of the first body line (for ASCII bodies).
    body_line: u32,
}

fn loc(file: &Arc<PathBuf>, line: u32, column: usize) -> SourceLocation {
    SourceLocation {
        file: file.clone(),
        line,
        column: u32::try_from(column).unwrap_or(u32::MAX),
    }
}

fn parse_header(bytes: &[u8], file: &Arc<PathBuf>) -> Result<Header, SceneError> {
    let mut pos = 0;
    let mut line_no = 0u32;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        if pos >= bytes.len() {
            return Err(SceneError::at(
                loc(file, line_no.max(1), 1),
                "PLY header has no 'end_header' line",
            ));
        }
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| pos + i);
        let raw = &bytes[pos..end];
        pos = (end + 1).min(bytes.len());
        line_no += 1;
        let line = String::from_utf8_lossy(raw);
        let line = line.strip_suffix('\r').unwrap_or(&line);
        // Words with their 1-based columns.
        let mut words = Vec::new();
        {
            let mut start = None;
            for (ci, (bi, c)) in line.char_indices().enumerate() {
                if c.is_ascii_whitespace() {
                    if let Some((sb, sc)) = start.take() {
                        words.push((&line[sb..bi], sc + 1));
                    }
                } else if start.is_none() {
                    start = Some((bi, ci));
                }
            }
            if let Some((sb, sc)) = start {
                words.push((&line[sb..], sc + 1));
            }
        }
        let at = |w: usize| {
            loc(
                file,
                line_no,
                words.get(w).map_or(line.chars().count() + 1, |x| x.1),
            )
        };
        if line_no == 1 {
            if words.len() != 1 || words[0].0 != "ply" {
                return Err(SceneError::at(
                    loc(file, 1, 1),
                    "not a PLY file (the first line must be 'ply')",
                ));
            }
            continue;
        }
        let Some(&(kw, _)) = words.first() else {
            continue;
        };
        match kw {
            "comment" | "obj_info" => {}
            "format" => {
                if format.is_some() {
                    return Err(SceneError::at(at(0), "second 'format' line"));
                }
                let f = match words.get(1).map(|w| w.0) {
                    Some("ascii") => Format::Ascii,
                    Some("binary_little_endian") => Format::BinaryLittleEndian,
                    Some("binary_big_endian") => Format::BinaryBigEndian,
                    other => {
                        return Err(SceneError::at(
                            at(1),
                            format!(
                                "expected 'ascii', 'binary_little_endian' or 'binary_big_endian' after 'format', found '{}'",
                                other.unwrap_or("")
                            ),
                        ))
                    }
                };
                if words.len() != 3 {
                    return Err(SceneError::at(at(2), "expected 'format <type> 1.0'"));
                }
                format = Some(f);
            }
            "element" => {
                if words.len() != 3 {
                    return Err(SceneError::at(
                        at(words.len().min(3)),
                        "expected 'element <name> <count>'",
                    ));
                }
                let Ok(count) = words[2].0.parse::<u64>() else {
                    return Err(SceneError::at(
                        at(2),
                        format!("expected an element count, found '{}'", words[2].0),
                    ));
                };
                if elements.iter().any(|e| e.name == words[1].0) {
                    return Err(SceneError::at(
                        at(1),
                        format!("second element named '{}'", words[1].0),
                    ));
                }
                elements.push(Element {
                    name: words[1].0.to_string(),
                    count,
                    properties: Vec::new(),
                    location: at(0),
                });
            }
            "property" => {
                let Some(element) = elements.last_mut() else {
                    return Err(SceneError::at(at(0), "'property' before any 'element'"));
                };
                let scalar = |w: usize| {
                    let name = words.get(w).map_or("", |x| x.0);
                    Scalar::parse(name).ok_or_else(|| {
                        SceneError::at(at(w), format!("expected a property type (char, uchar, short, ushort, int, uint, float, double, or int8 ... float64), found '{name}'"))
                    })
                };
                let (kind, name_word) = if words.get(1).map(|w| w.0) == Some("list") {
                    let count = scalar(2)?;
                    if !count.is_integer() {
                        return Err(SceneError::at(
                            at(2),
                            "a list's count type must be an integer type",
                        ));
                    }
                    (
                        PropKind::List {
                            count,
                            item: scalar(3)?,
                        },
                        4,
                    )
                } else {
                    (PropKind::Scalar(scalar(1)?), 2)
                };
                if words.len() != name_word + 1 {
                    return Err(SceneError::at(
                        at(name_word.min(words.len())),
                        "expected 'property <type> <name>' or 'property list <count type> <item type> <name>'",
                    ));
                }
                let name = words[name_word].0;
                if element.properties.iter().any(|p| p.name == name) {
                    return Err(SceneError::at(
                        at(name_word),
                        format!("second property named '{name}'"),
                    ));
                }
                element.properties.push(Property {
                    name: name.to_string(),
                    kind,
                    location: at(0),
                });
            }
            "end_header" => break,
            other => {
                return Err(SceneError::at(
                    at(0),
                    format!("unknown PLY header keyword '{other}'"),
                ));
            }
        }
    }
    let Some(format) = format else {
        return Err(SceneError::at(
            loc(file, line_no, 1),
            "PLY header has no 'format' line",
        ));
    };
    Ok(Header {
        format,
        elements,
        body_start: pos,
        body_line: line_no + 1,
    })
}

/// Where in the body a value was read.
#[derive(Clone, Copy)]
enum Pos {
    Text { line: u32, column: u32 },
    Byte(usize),
}

/// A reader of body values.
struct Body<'a> {
    data: &'a [u8],
    pos: usize,
    format: Format,
    line: u32,
    line_start: usize,
}

impl<'a> Body<'a> {
    fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }

    fn here(&self) -> Pos {
        match self.format {
            Format::Ascii => {
                let col = String::from_utf8_lossy(&self.data[self.line_start..self.pos])
                    .chars()
                    .count()
                    + 1;
                Pos::Text {
                    line: self.line,
                    column: u32::try_from(col).unwrap_or(u32::MAX),
                }
            }
            _ => Pos::Byte(self.pos),
        }
    }

    /// Next whitespace-separated token of an ASCII body, with its position.
    fn token(&mut self) -> Option<(&'a str, Pos)> {
        while self.pos < self.data.len() && self.data[self.pos].is_ascii_whitespace() {
            if self.data[self.pos] == b'\n' {
                self.line = self.line.saturating_add(1);
                self.line_start = self.pos + 1;
            }
            self.pos += 1;
        }
        if self.pos >= self.data.len() {
            return None;
        }
        let here = self.here();
        let start = self.pos;
        while self.pos < self.data.len() && !self.data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        // Invalid UTF-8 can only make the token unparsable, which the caller reports.
        Some((
            std::str::from_utf8(&self.data[start..self.pos]).unwrap_or("\u{fffd}"),
            here,
        ))
    }

    /// Reads one value of type `ty` as f64 (exact for every PLY type).
    fn read(&mut self, ty: Scalar) -> Result<f64, (Pos, String)> {
        self.read_at(ty).map(|(v, _)| v)
    }

    /// Reads one value with the position where it starts.
    fn read_at(&mut self, ty: Scalar) -> Result<(f64, Pos), (Pos, String)> {
        match self.format {
            Format::Ascii => {
                let Some((tok, pos)) = self.token() else {
                    return Err((self.here(), "unexpected end of file".into()));
                };
                let value = if ty.is_integer() {
                    tok.parse::<i64>().ok().map(|v| v as f64)
                } else {
                    tok.parse::<f64>().ok()
                };
                let (lo, hi) = ty.range();
                match value {
                    Some(v) if v >= lo && v <= hi || v.is_nan() => Ok((v, pos)),
                    _ => {
                        let what = if ty.is_integer() {
                            format!("an integer ({ty:?})")
                        } else {
                            "a number".into()
                        };
                        Err((pos, format!("expected {what}, found '{tok}'")))
                    }
                }
            }
            Format::BinaryLittleEndian | Format::BinaryBigEndian => {
                let size = ty.size();
                let start = self.pos;
                let Some(b) = self.data.get(self.pos..self.pos + size) else {
                    return Err((self.here(), "truncated binary data".into()));
                };
                self.pos += size;
                let big = self.format == Format::BinaryBigEndian;
                let mut a = [0u8; 8];
                a[..size].copy_from_slice(b);
                if big {
                    a[..size].reverse();
                }
                let value = match ty {
                    Scalar::I8 => f64::from(a[0] as i8),
                    Scalar::U8 => f64::from(a[0]),
                    Scalar::I16 => f64::from(i16::from_le_bytes([a[0], a[1]])),
                    Scalar::U16 => f64::from(u16::from_le_bytes([a[0], a[1]])),
                    Scalar::I32 => f64::from(i32::from_le_bytes([a[0], a[1], a[2], a[3]])),
                    Scalar::U32 => f64::from(u32::from_le_bytes([a[0], a[1], a[2], a[3]])),
                    Scalar::F32 => f64::from(f32::from_le_bytes([a[0], a[1], a[2], a[3]])),
                    Scalar::F64 => f64::from_le_bytes(a),
                };
                Ok((value, Pos::Byte(start)))
            }
        }
    }
}

/// Which vertex properties feed which attribute.
struct VertexLayout {
    position: [usize; 3],
    normal: Option<[usize; 3]>,
    uv: Option<[usize; 2]>,
}

fn find_scalar(
    e: &Element,
    name: &str,
    file_err: &dyn Fn(&Property) -> SceneError,
) -> Result<Option<usize>, SceneError> {
    match e.properties.iter().position(|p| p.name == name) {
        Some(i) => match e.properties[i].kind {
            PropKind::Scalar(_) => Ok(Some(i)),
            PropKind::List { .. } => Err(file_err(&e.properties[i])),
        },
        None => Ok(None),
    }
}

fn read_body(
    bytes: &[u8],
    header: &Header,
    file: &Arc<PathBuf>,
) -> Result<TriangleMesh, SceneError> {
    let list_err = |p: &Property| {
        SceneError::at(
            p.location.clone(),
            format!("property '{}' must not be a list", p.name),
        )
    };
    let vertex = header.elements.iter().find(|e| e.name == "vertex");
    let Some(vertex_el) = vertex else {
        let at = header
            .elements
            .first()
            .map_or(loc(file, 1, 1), |e| e.location.clone());
        return Err(SceneError::at(at, "PLY file has no 'vertex' element"));
    };
    let mut position = [0; 3];
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        position[k] = find_scalar(vertex_el, name, &list_err)?.ok_or_else(|| {
            SceneError::at(
                vertex_el.location.clone(),
                format!("the 'vertex' element has no property '{name}'"),
            )
        })?;
    }
    let mut normal = [0; 3];
    let mut has_normal = true;
    for (k, name) in ["nx", "ny", "nz"].iter().enumerate() {
        match find_scalar(vertex_el, name, &list_err)? {
            Some(i) => normal[k] = i,
            None => has_normal = false,
        }
    }
    let mut uv = None;
    for (a, b) in [
        ("u", "v"),
        ("s", "t"),
        ("texture_u", "texture_v"),
        ("texture_s", "texture_t"),
    ] {
        if let (Some(i), Some(j)) = (
            find_scalar(vertex_el, a, &list_err)?,
            find_scalar(vertex_el, b, &list_err)?,
        ) {
            uv = Some([i, j]);
            break;
        }
    }
    let layout = VertexLayout {
        position,
        normal: has_normal.then_some(normal),
        uv,
    };
    let vertex_count = vertex_el.count;

    let mut body = Body {
        data: bytes,
        pos: header.body_start,
        format: header.format,
        line: header.body_line,
        line_start: header.body_start,
    };
    let body_err = |pos: Pos, what: String| -> SceneError {
        match pos {
            Pos::Text { line, column } => SceneError::at(
                SourceLocation {
                    file: file.clone(),
                    line,
                    column,
                },
                what,
            ),
            Pos::Byte(offset) => SceneError::Io {
                path: file.as_ref().clone(),
                source: std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!("{what} (at byte {offset})"),
                ),
            },
        }
    };

    let mut positions: Vec<Vec3> = Vec::new();
    let mut normals: Vec<Vec3> = Vec::new();
    let mut uvs: Vec<Vec2> = Vec::new();
    let mut face_sizes: Vec<u32> = Vec::new();
    let mut face_indices: Vec<u32> = Vec::new();
    let mut triangles_seen = 0usize;
    let mut values: Vec<f64> = Vec::new();
    let mut polygon: Vec<u32> = Vec::new();
    let mut points: Vec<Vec3> = Vec::new();

    for element in &header.elements {
        if element.properties.is_empty() || element.count == 0 {
            continue; // nothing to read
        }
        let is_vertex = std::ptr::eq(element, vertex_el);
        let is_face = element.name == "face" && !is_vertex;
        let face_prop = if is_face {
            let i = element
                .properties
                .iter()
                .position(|p| p.name == "vertex_indices" || p.name == "vertex_index");
            match i.map(|i| (i, &element.properties[i])) {
                Some((
                    i,
                    Property {
                        kind: PropKind::List { item, .. },
                        ..
                    },
                )) if item.is_integer() => Some(i),
                Some((_, p)) => {
                    return Err(SceneError::at(
                        p.location.clone(),
                        format!("property '{}' must be a list of an integer type", p.name),
                    ))
                }
                None => {
                    return Err(SceneError::at(
                        element.location.clone(),
                        "the 'face' element has no 'vertex_indices' list",
                    ))
                }
            }
        } else {
            None
        };
        // Every element consumes at least one byte (binary) or token (ASCII), so the loop below
        // is bounded by the input; capacities are bounded the same way.
        let min_size: usize = match header.format {
            Format::Ascii => 2 * element.properties.len(),
            _ => element
                .properties
                .iter()
                .map(|p| match p.kind {
                    PropKind::Scalar(s) => s.size(),
                    PropKind::List { count, .. } => count.size(),
                })
                .sum(),
        };
        let cap = usize::try_from(element.count)
            .unwrap_or(usize::MAX)
            .min(body.remaining() / min_size.max(1) + 1);
        if is_vertex {
            positions.reserve(cap);
            if layout.normal.is_some() {
                normals.reserve(cap);
            }
            if layout.uv.is_some() {
                uvs.reserve(cap);
            }
        }
        for index in 0..element.count {
            let ctx = |e: (Pos, String), prop: &str| {
                body_err(
                    e.0,
                    format!("{} {index}: {} (property '{prop}')", element.name, e.1),
                )
            };
            values.clear();
            for (pi, p) in element.properties.iter().enumerate() {
                match p.kind {
                    PropKind::Scalar(s) => values.push(body.read(s).map_err(|e| ctx(e, &p.name))?),
                    PropKind::List { count, item } => {
                        let (n, start) = body.read_at(count).map_err(|e| ctx(e, &p.name))?;
                        if n < 0.0 {
                            return Err(body_err(
                                start,
                                format!(
                                    "{} {index}: negative list length {n} (property '{}')",
                                    element.name, p.name
                                ),
                            ));
                        }
                        let n = n as u64;
                        if header.format != Format::Ascii
                            && n.saturating_mul(item.size() as u64) > body.remaining() as u64
                        {
                            return Err(body_err(
                                body.here(),
                                format!(
                                    "{} {index}: truncated binary data (a list of {n} items, property '{}')",
                                    element.name, p.name
                                ),
                            ));
                        }
                        let wanted = face_prop == Some(pi);
                        if wanted {
                            polygon.clear();
                        }
                        for _ in 0..n {
                            let (v, pos) = body.read_at(item).map_err(|e| ctx(e, &p.name))?;
                            if wanted {
                                if v < 0.0 || v >= vertex_count as f64 {
                                    return Err(body_err(
                                        pos,
                                        format!(
                                            "{} {index}: vertex index {v} out of range (file has {vertex_count} vertices)",
                                            element.name
                                        ),
                                    ));
                                }
                                polygon.push(v as u32);
                            }
                        }
                        if wanted && n < 3 {
                            return Err(body_err(
                                start,
                                format!(
                                    "{} {index}: face with {n} vertices (at least 3 needed)",
                                    element.name
                                ),
                            ));
                        }
                    }
                }
            }
            if is_vertex {
                let p = layout.position.map(|i| values[i] as f32);
                if !p.iter().all(|c| c.is_finite()) {
                    return Err(body_err(
                        body.here(),
                        format!("vertex {index}: non-finite position {p:?}"),
                    ));
                }
                positions.push(Vec3::from_array(p));
                if let Some(ni) = layout.normal {
                    let n = glam::DVec3::from_array(ni.map(|i| values[i]));
                    let len = n.length();
                    if !(len > 0.0 && len.is_finite()) {
                        return Err(body_err(
                            body.here(),
                            format!("vertex {index}: zero-length or non-finite normal"),
                        ));
                    }
                    normals.push((n / len).as_vec3());
                }
                if let Some([ui, vi]) = layout.uv {
                    let uv = Vec2::new(values[ui] as f32, values[vi] as f32);
                    if !uv.is_finite() {
                        return Err(body_err(
                            body.here(),
                            format!("vertex {index}: non-finite texture coordinates {uv:?}"),
                        ));
                    }
                    uvs.push(uv);
                }
            } else if face_prop.is_some() {
                // Vertices may come after faces; positions are looked up at the end.
                face_sizes.push(polygon.len() as u32);
                face_indices.extend_from_slice(&polygon);
            }
        }
    }

    // Triangulate the recorded polygons now that every position is known.
    let mut tris = Vec::with_capacity(face_indices.len().saturating_sub(2 * face_sizes.len()));
    let mut first_degenerate = None;
    let mut start = 0usize;
    for (face_index, &n) in face_sizes.iter().enumerate() {
        let polygon = &face_indices[start..start + n as usize];
        start += n as usize;
        points.clear();
        for &v in polygon {
            match positions.get(v as usize) {
                Some(&p) => points.push(p),
                None => {
                    return Err(SceneError::at(
                        vertex_el.location.clone(),
                        format!(
                        "face {face_index}: vertex index {v} out of range (file has {} vertices)",
                        positions.len()
                    ),
                    ))
                }
            }
        }
        for t in triangulate_polygon(&points) {
            triangles_seen += 1;
            if is_degenerate(points[t[0]], points[t[1]], points[t[2]]) {
                first_degenerate.get_or_insert(face_index);
                continue;
            }
            tris.push(t.map(|k| polygon[k]));
        }
    }
    if triangles_seen > 0 && tris.is_empty() {
        return Err(SceneError::Io {
            path: file.as_ref().clone(),
            source: std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "every triangle is degenerate (zero area), first in face {}",
                    first_degenerate.unwrap_or(0)
                ),
            ),
        });
    }
    Ok(TriangleMesh {
        positions,
        normals: layout.normal.map(|_| normals),
        uvs: layout.uv.map(|_| uvs),
        indices: tris,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(bytes: &[u8]) -> Result<TriangleMesh, SceneError> {
        parse_ply(bytes, Arc::new(PathBuf::from("t.ply")))
    }

    #[test]
    fn ascii_quad_with_extra_element() {
        let text = "ply\nformat ascii 1.0\ncomment hi\nelement vertex 4\nproperty float x\nproperty float y\n\
                    property float z\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_indices\n\
                    property list uchar float junk\nelement edge 1\nproperty int a\nend_header\n\
                    0 0 0 1\n1 0 0 2\n1 1 0 3\n0 1 0 4\n4 0 1 2 3 2 0.5 0.25\n7\n";
        let m = parse(text.as_bytes()).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3]]);
        assert!(m.normals.is_none() && m.uvs.is_none());
    }

    #[test]
    fn header_errors() {
        let e = parse(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty flaot x\nend_header\n")
            .unwrap_err();
        assert!(
            e.to_string()
                .starts_with("t.ply:4:10: expected a property type"),
            "{e}"
        );
        let e = parse(b"plx\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.ply:1:1: not a PLY file (the first line must be 'ply')"
        );
    }

    #[test]
    fn ascii_body_error_location() {
        let text = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n\
                    end_header\n0 0 0\n1 x 0\n";
        let e = parse(text.as_bytes()).unwrap_err().to_string();
        assert_eq!(
            e,
            "t.ply:9:3: vertex 1: expected a number, found 'x' (property 'y')"
        );
    }

    #[test]
    fn huge_counts_do_not_allocate() {
        let text = "ply\nformat binary_little_endian 1.0\nelement vertex 18446744073709551615\nproperty float x\n\
                    property float y\nproperty float z\nelement face 4294967295\nproperty list uint uint vertex_indices\nend_header\n";
        let e = parse(text.as_bytes()).unwrap_err().to_string();
        assert!(e.contains("vertex 0: truncated binary data"), "{e}");
    }
}
