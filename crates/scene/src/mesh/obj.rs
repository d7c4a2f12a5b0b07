//! Wavefront OBJ reader.
//!
//! Reads `v` (3 coordinates; a 4th `w` or trailing vertex-colour values are checked to be numbers
//! and ignored), `vt` (1 to 3 values; `u`, `v` kept), `vn`, `f` (and the obsolete `fo`) with
//! `v`, `v/vt`, `v//vn`, `v/vt/vn` corners and negative (relative) indices, `usemtl` and `mtllib`.
//! `g`, `o`, `s`, `l`, `p` and every statement this reader does not know are ignored without error,
//! as OBJ files are full of them. Comments (`#` to the end of the line), CRLF line ends, tabs, and
//! line continuation with a trailing `\` are accepted. Malformed numbers and indices are errors
//! naming `file:line:column`.
//!
//! Output: one [`ObjGroup`] per run of faces sharing a `usemtl` material, each a self-contained
//! [`TriangleMesh`] whose vertices are de-duplicated by their `(v, vt, vn)` index triple (as in
//! Mitsuba 3). Polygons are triangulated by [`triangulate_polygon`].
//!
//! Decisions:
//! - **Texture coordinates** in the meshes are `(u, 1 − v)`, as Mitsuba 3's `obj` plugin does by
//!   default (`flip_tex_coords = true`): image row 0 is the top, while OBJ's `v` runs upwards.
//!   [`ObjData::uvs`] keeps the values as written.
//! - **Normals** from `vn` are normalised; a non-finite `vn` is an error. A zero-length `vn` is
//!   *not* an error, because the real Dabrovic Sponza has one (line 232,670, used by four faces):
//!   it is counted in [`ObjData::zero_normals`], and the corners that use it are treated as having
//!   no `vn`. A mesh
//!   without any `vn` has no normals (flat shading unless the caller computes some, e.g. with
//!   [`super::compute_vertex_normals`]); in a mesh where only some corners have one, the others get
//!   the mesh's angle-weighted vertex normal.
//! - **Degenerate triangles** (zero area) are dropped, counted in [`ObjData::degenerate_dropped`]
//!   and the first one's `f` statement is kept in [`ObjData::first_degenerate`] so that callers can
//!   report them; real files contain some. A file with faces of which *every* triangle is degenerate
//!   is an error naming the first face.
//! - A file without any face is not an error here (its [`ObjData`] has no groups).
//! - Indices are resolved when the face is read, so a face may only refer to vertices defined
//!   above it (as the OBJ specification requires).

use super::{is_degenerate, triangulate_polygon, MeshBuilder, NO_INDEX};
use crate::desc::TriangleMesh;
use crate::error::{SceneError, SourceLocation};
use ircache_math::{Vec2, Vec3};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Everything read from an OBJ file.
#[derive(Clone, Debug, Default)]
pub struct ObjData {
    /// Every `v` position, in file order.
    pub positions: Vec<Vec3>,
    /// Every `vn` normal, normalised, in file order.
    pub normals: Vec<Vec3>,
    /// Every `vt` texture coordinate as written (not flipped), in file order.
    pub uvs: Vec<Vec2>,
    /// One group per run of faces with the same `usemtl` material, in file order. Groups whose
    /// faces were all dropped as degenerate are left out.
    pub groups: Vec<ObjGroup>,
    /// Every `mtllib` file name as written (relative to the OBJ file's folder unless absolute),
    /// with where it was named.
    pub mtllibs: Vec<(PathBuf, SourceLocation)>,
    /// Number of degenerate (zero-area) triangles dropped.
    pub degenerate_dropped: usize,
    /// The `f` statement of the first dropped degenerate triangle.
    pub first_degenerate: Option<SourceLocation>,
    /// Number of zero-length `vn` statements (kept as zero vectors in [`ObjData::normals`]; face
    /// corners that use one are treated as having no `vn`).
    pub zero_normals: usize,
    /// The first zero-length `vn` statement.
    pub first_zero_normal: Option<SourceLocation>,
}

/// A run of faces with one material.
#[derive(Clone, Debug)]
pub struct ObjGroup {
    /// The `usemtl` material name; `None` for faces before any `usemtl`.
    pub material: Option<String>,
    /// The faces, triangulated, with their own de-duplicated vertices.
    pub mesh: TriangleMesh,
    /// The `usemtl` statement (or the first face when there is none).
    pub location: SourceLocation,
    /// For each vertex of `mesh`, its 0-based `[v, vt, vn]` indices into [`ObjData`]'s arrays
    /// (`u32::MAX` where the corner had no `vt` or `vn`).
    pub vertex_keys: Vec<[u32; 3]>,
}

/// Reads an OBJ file. See the [module documentation](self) for what is accepted.
pub fn read_obj(path: &Path) -> Result<ObjData, SceneError> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let text = String::from_utf8_lossy(&bytes);
    parse_obj(&text, Arc::new(path.to_path_buf()))
}

/// Parses OBJ text; `file` is the name used in error locations.
pub fn parse_obj(text: &str, file: Arc<PathBuf>) -> Result<ObjData, SceneError> {
    Parser::new(file).run(text)
}

/// Merges all groups of `data` into one mesh (what Mitsuba's `obj` shape loads), de-duplicating
/// vertices across groups by their `(v, vt, vn)` triple as Mitsuba 3 does.
#[must_use]
pub fn obj_to_mesh(data: &ObjData) -> TriangleMesh {
    let flipped = flip_uvs(&data.uvs);
    let mut builder = MeshBuilder::new();
    let valid = |k: &[u32; 3]| {
        (k[0] as usize) < data.positions.len()
            && (k[1] == NO_INDEX || (k[1] as usize) < data.uvs.len())
            && (k[2] == NO_INDEX || (k[2] as usize) < data.normals.len())
    };
    let mut extra = TriangleMesh::default();
    for group in &data.groups {
        let keys_ok = group.vertex_keys.len() == group.mesh.positions.len()
            && group.vertex_keys.iter().all(valid);
        if keys_ok {
            for tri in &group.mesh.indices {
                let ids = tri.map(|i| {
                    let key = group.vertex_keys[i as usize];
                    builder.vertex(key, &data.positions, &flipped, &data.normals)
                });
                builder.triangle(ids);
            }
        } else {
            append_mesh(&mut extra, &group.mesh);
        }
    }
    let (mut mesh, _) = builder.finish();
    if !extra.indices.is_empty() {
        append_mesh(&mut mesh, &extra);
    }
    mesh
}

/// Appends `b` to `a` (groups built by hand, without vertex keys). Attributes present in only one of
/// them are dropped.
fn append_mesh(a: &mut TriangleMesh, b: &TriangleMesh) {
    let offset = a.positions.len() as u32;
    let a_empty = a.positions.is_empty();
    a.positions.extend_from_slice(&b.positions);
    a.indices
        .extend(b.indices.iter().map(|t| t.map(|i| i + offset)));
    a.normals = match (a.normals.take(), &b.normals) {
        (Some(mut x), Some(y)) => {
            x.extend_from_slice(y);
            Some(x)
        }
        (None, Some(y)) if a_empty => Some(y.clone()),
        _ => None,
    };
    a.uvs = match (a.uvs.take(), &b.uvs) {
        (Some(mut x), Some(y)) => {
            x.extend_from_slice(y);
            Some(x)
        }
        (None, Some(y)) if a_empty => Some(y.clone()),
        _ => None,
    };
}

fn flip_uvs(uvs: &[Vec2]) -> Vec<Vec2> {
    uvs.iter().map(|uv| Vec2::new(uv.x, 1.0 - uv.y)).collect()
}

/// A whitespace-separated word with where it is.
#[derive(Clone, Copy)]
pub(crate) struct Token<'a> {
    pub(crate) text: &'a str,
    line: u32,
    line_text: &'a str,
    offset: usize,
}

impl<'a> Token<'a> {
    /// The location of the token's character at byte `extra` within it.
    pub(crate) fn location_at(&self, file: &Arc<PathBuf>, extra: usize) -> SourceLocation {
        let end = (self.offset + extra).min(self.line_text.len());
        let column = self.line_text.get(..end).map_or(end, |s| s.chars().count()) + 1;
        SourceLocation {
            file: file.clone(),
            line: self.line,
            column: column as u32,
        }
    }
    pub(crate) fn location(&self, file: &Arc<PathBuf>) -> SourceLocation {
        self.location_at(file, 0)
    }
    /// The location just after the token (for "expected more" errors).
    pub(crate) fn end_location(&self, file: &Arc<PathBuf>) -> SourceLocation {
        self.location_at(file, self.text.len())
    }
}

/// Splits text into logical statements (physical lines joined by trailing `\`), without comments,
/// calling `f` with each non-empty statement's tokens. Shared with the MTL reader.
pub(crate) fn for_each_statement<'a>(
    text: &'a str,
    mut f: impl FnMut(&[Token<'a>]) -> Result<(), SceneError>,
) -> Result<(), SceneError> {
    let mut tokens: Vec<Token<'a>> = Vec::new();
    let mut line_no: u32 = 0;
    for raw in text.split('\n') {
        line_no = line_no.saturating_add(1);
        let line = raw.strip_suffix('\r').unwrap_or(raw);
        let content = match line.find('#') {
            Some(i) => &line[..i],
            None => line,
        };
        let trimmed = content.trim_end_matches(is_space);
        let (content, continued) = match trimmed.strip_suffix('\\') {
            Some(rest) => (rest, true),
            None => (content, false),
        };
        let bytes = content.as_bytes();
        let mut i = 0;
        while i < bytes.len() {
            if is_space(bytes[i] as char) {
                i += 1;
                continue;
            }
            let start = i;
            while i < bytes.len() && !is_space(bytes[i] as char) {
                i += 1;
            }
            tokens.push(Token {
                text: &content[start..i],
                line: line_no,
                line_text: line,
                offset: start,
            });
        }
        if !continued {
            if !tokens.is_empty() {
                f(&tokens)?;
            }
            tokens.clear();
        }
    }
    if !tokens.is_empty() {
        f(&tokens)?;
    }
    Ok(())
}

fn is_space(c: char) -> bool {
    matches!(c, ' ' | '\t' | '\r' | '\x0b' | '\x0c')
}

/// Parses a finite `f32`, or says what was expected.
pub(crate) fn parse_number(
    tok: &Token,
    file: &Arc<PathBuf>,
    after: &str,
) -> Result<f32, SceneError> {
    match tok.text.parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(SceneError::at(
            tok.location(file),
            format!(
                "expected a finite number after '{after}', found '{}'",
                tok.text
            ),
        )),
        Err(_) => Err(SceneError::at(
            tok.location(file),
            format!("expected a number after '{after}', found '{}'", tok.text),
        )),
    }
}

/// Parses `count..=max` numbers after the keyword `toks[0]`, checking that any further ones
/// (up to `max`) are numbers too; more than `max` is an error.
pub(crate) fn parse_numbers<const N: usize>(
    toks: &[Token],
    file: &Arc<PathBuf>,
    required: usize,
    max: usize,
) -> Result<[f32; N], SceneError> {
    let kw = toks[0].text;
    let args = &toks[1..];
    if args.len() < required {
        let last = toks.last().unwrap_or(&toks[0]);
        let what = if required == 1 {
            "number".to_string()
        } else {
            format!("{required} numbers")
        };
        return Err(SceneError::at(
            last.end_location(file),
            format!("expected {what} after '{kw}', found {}", args.len()),
        ));
    }
    if args.len() > max {
        return Err(SceneError::at(
            args[max].location(file),
            format!(
                "expected at most {max} numbers after '{kw}', found '{}'",
                args[max].text
            ),
        ));
    }
    let mut out = [0.0; N];
    for (i, tok) in args.iter().enumerate() {
        let v = parse_number(tok, file, kw)?;
        if i < N {
            out[i] = v;
        }
    }
    Ok(out)
}

/// The tokens after the keyword joined by single spaces (file and material names may contain
/// spaces).
pub(crate) fn rest_of_statement(toks: &[Token]) -> String {
    toks[1..]
        .iter()
        .map(|t| t.text)
        .collect::<Vec<_>>()
        .join(" ")
}

struct OpenGroup {
    material: Option<String>,
    location: SourceLocation,
    builder: MeshBuilder,
}

struct Parser {
    file: Arc<PathBuf>,
    data: ObjData,
    flipped_uvs: Vec<Vec2>,
    current: Option<OpenGroup>,
    triangles_seen: usize,
    corners: Vec<[u32; 3]>,
    points: Vec<Vec3>,
}

impl Parser {
    fn new(file: Arc<PathBuf>) -> Parser {
        Parser {
            file,
            data: ObjData::default(),
            flipped_uvs: Vec::new(),
            current: None,
            triangles_seen: 0,
            corners: Vec::new(),
            points: Vec::new(),
        }
    }

    fn run(mut self, text: &str) -> Result<ObjData, SceneError> {
        for_each_statement(text, |toks| self.statement(toks))?;
        self.close_group();
        if self.triangles_seen > 0 && self.data.degenerate_dropped == self.triangles_seen {
            let location = self
                .data
                .first_degenerate
                .clone()
                .expect("a dropped triangle has a location");
            return Err(SceneError::at(
                location,
                format!(
                    "every triangle of the file is degenerate (zero area): {} dropped, none left",
                    self.triangles_seen
                ),
            ));
        }
        Ok(self.data)
    }

    fn statement(&mut self, toks: &[Token]) -> Result<(), SceneError> {
        let file = &self.file.clone();
        match toks[0].text {
            "v" => {
                let [x, y, z] = parse_numbers::<3>(toks, file, 3, usize::MAX)?;
                self.data.positions.push(Vec3::new(x, y, z));
            }
            "vt" => {
                let [u, v] = parse_numbers::<2>(toks, file, 1, 3)?;
                self.data.uvs.push(Vec2::new(u, v));
                self.flipped_uvs.push(Vec2::new(u, 1.0 - v));
            }
            "vn" => {
                let [x, y, z] = parse_numbers::<3>(toks, file, 3, 3)?;
                let n = Vec3::new(x, y, z);
                let len = n.as_dvec3().length();
                if len > 0.0 && len.is_finite() {
                    self.data.normals.push((n.as_dvec3() / len).as_vec3());
                } else {
                    self.data.zero_normals += 1;
                    self.data
                        .first_zero_normal
                        .get_or_insert_with(|| toks[0].location(file));
                    self.data.normals.push(Vec3::ZERO);
                }
            }
            "f" | "fo" => self.face(toks)?,
            "usemtl" => {
                if toks.len() < 2 {
                    return Err(SceneError::at(
                        toks[0].end_location(file),
                        "expected a material name after 'usemtl'",
                    ));
                }
                let name = rest_of_statement(toks);
                let same = self
                    .current
                    .as_ref()
                    .is_some_and(|g| g.material.as_deref() == Some(name.as_str()));
                if !same {
                    self.close_group();
                    self.current = Some(OpenGroup {
                        material: Some(name),
                        location: toks[0].location(file),
                        builder: MeshBuilder::new(),
                    });
                }
            }
            "mtllib" => {
                if toks.len() < 2 {
                    return Err(SceneError::at(
                        toks[0].end_location(file),
                        "expected a file name after 'mtllib'",
                    ));
                }
                self.data.mtllibs.push((
                    PathBuf::from(rest_of_statement(toks)),
                    toks[1].location(file),
                ));
            }
            _ => {} // g, o, s, l, p, vp, curves, ... and anything unknown
        }
        Ok(())
    }

    fn close_group(&mut self) {
        if let Some(g) = self.current.take() {
            if g.builder.triangle_count() > 0 {
                let (mesh, vertex_keys) = g.builder.finish();
                self.data.groups.push(ObjGroup {
                    material: g.material,
                    mesh,
                    location: g.location,
                    vertex_keys,
                });
            }
        }
    }

    fn face(&mut self, toks: &[Token]) -> Result<(), SceneError> {
        let file = self.file.clone();
        let kw = &toks[0];
        if toks.len() < 4 {
            let n = toks.len() - 1;
            return Err(SceneError::at(
                kw.location(&file),
                format!("face with {n} vertices (at least 3 needed)"),
            ));
        }
        self.corners.clear();
        self.points.clear();
        for tok in &toks[1..] {
            let key = self.corner(tok, &file)?;
            self.points.push(self.data.positions[key[0] as usize]);
            self.corners.push(key);
        }
        let location = kw.location(&file);
        if self.current.is_none() {
            self.current = Some(OpenGroup {
                material: None,
                location: location.clone(),
                builder: MeshBuilder::new(),
            });
        }
        let group = self.current.as_mut().expect("just created");
        for tri in triangulate_polygon(&self.points) {
            self.triangles_seen += 1;
            let [a, b, c] = tri.map(|i| self.points[i]);
            if is_degenerate(a, b, c) {
                self.data.degenerate_dropped += 1;
                if self.data.first_degenerate.is_none() {
                    self.data.first_degenerate = Some(location.clone());
                }
                continue;
            }
            let ids = tri.map(|i| {
                group.builder.vertex(
                    self.corners[i],
                    &self.data.positions,
                    &self.flipped_uvs,
                    &self.data.normals,
                )
            });
            group.builder.triangle(ids);
        }
        Ok(())
    }

    /// Parses one `v[/vt[/vn]]` corner into 0-based indices.
    fn corner(&self, tok: &Token, file: &Arc<PathBuf>) -> Result<[u32; 3], SceneError> {
        let mut key = [NO_INDEX; 3];
        let mut offset = 0;
        let parts: Vec<&str> = tok.text.split('/').collect();
        if parts.len() > 3 {
            return Err(SceneError::at(
                tok.location(file),
                format!(
                    "expected a face vertex 'v', 'v/vt', 'v//vn' or 'v/vt/vn', found '{}'",
                    tok.text
                ),
            ));
        }
        let kinds = [
            ("vertex", "vertices", self.data.positions.len()),
            (
                "texture coordinate",
                "texture coordinates",
                self.data.uvs.len(),
            ),
            ("normal", "normals", self.data.normals.len()),
        ];
        for (k, part) in parts.iter().enumerate() {
            let loc = || tok.location_at(file, offset);
            let (what, plural, len) = kinds[k];
            if part.is_empty() {
                if k == 1 && parts.len() == 3 {
                    offset += 1;
                    continue; // v//vn
                }
                return Err(SceneError::at(
                    loc(),
                    format!("expected a {what} index in face vertex '{}'", tok.text),
                ));
            }
            let Ok(index) = part.parse::<i64>() else {
                return Err(SceneError::at(
                    loc(),
                    format!("expected a {what} index after 'f', found '{part}'"),
                ));
            };
            let resolved = if index > 0 && (index as u64) <= len as u64 {
                Some(index as u64 - 1)
            } else if index < 0 && index.unsigned_abs() <= len as u64 {
                Some(len as u64 - index.unsigned_abs())
            } else {
                None
            };
            match resolved {
                // A zero-length `vn` counts as no normal for this corner.
                Some(i) if k == 2 && self.data.normals[i as usize] == Vec3::ZERO => {}
                Some(i) if i < u64::from(NO_INDEX) => key[k] = i as u32,
                _ if index == 0 => {
                    return Err(SceneError::at(
                        loc(),
                        format!("{what} index 0 is invalid (OBJ indices start at 1)"),
                    ))
                }
                _ => {
                    return Err(SceneError::at(
                        loc(),
                        format!(
                            "{what} index {index} out of range (file has {len} {plural} so far)"
                        ),
                    ))
                }
            }
            offset += part.len() + 1;
        }
        Ok(key)
    }
}

/// The note a loader passes on when triangles were dropped as degenerate: how many, and where
/// the first one is.
#[must_use]
pub fn degenerate_note(data: &ObjData) -> Option<String> {
    (data.degenerate_dropped > 0).then(|| {
        let at = data
            .first_degenerate
            .as_ref()
            .map_or(String::new(), |l| format!(" (the first at {l})"));
        format!(
            "{} degenerate (zero-area) triangle{} dropped{at}",
            data.degenerate_dropped,
            if data.degenerate_dropped == 1 {
                ""
            } else {
                "s"
            }
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<ObjData, SceneError> {
        parse_obj(text, Arc::new(PathBuf::from("t.obj")))
    }

    #[test]
    fn triangle_and_quad() {
        let d = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 2 3 4\n").unwrap();
        assert_eq!(d.groups.len(), 1);
        assert_eq!(d.groups[0].mesh.indices.len(), 3);
        assert_eq!(d.groups[0].mesh.positions.len(), 4);
        assert!(d.groups[0].mesh.normals.is_none());
        assert!(d.groups[0].mesh.uvs.is_none());
    }

    #[test]
    fn corner_forms_and_uv_flip() {
        let d =
            parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0.25\nvn 0 0 2\nf 1/1/1 2//1 3/1\n").unwrap();
        let m = &d.groups[0].mesh;
        assert_eq!(m.uvs.as_ref().unwrap()[0], Vec2::new(0.0, 0.75));
        assert_eq!(d.uvs[0], Vec2::new(0.0, 0.25));
        let n = m.normals.as_ref().unwrap();
        assert_eq!(n[0], Vec3::Z);
        assert!((n[2] - Vec3::Z).length() < 1e-6); // computed for the corner without vn
    }

    #[test]
    fn errors_name_line_and_column() {
        let e = parse("v 0 0 0\nv 1 x 0\n").unwrap_err().to_string();
        assert_eq!(e, "t.obj:2:5: expected a number after 'v', found 'x'");
        let e = parse("v 0 0 0\nv 1 0 0\nf 1 2\n").unwrap_err().to_string();
        assert_eq!(e, "t.obj:3:1: face with 2 vertices (at least 3 needed)");
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 12\n")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "t.obj:4:7: vertex index 12 out of range (file has 3 vertices so far)"
        );
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2 3\n")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "t.obj:4:5: texture coordinate index 1 out of range (file has 0 texture coordinates so far)");
        let d = parse("vn 0 0 0\nvn 0 0 1\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//2 3//2\n").unwrap();
        assert_eq!((d.zero_normals, d.first_zero_normal.unwrap().line), (1, 1));
        assert_eq!(d.groups[0].vertex_keys[0], [0, NO_INDEX, NO_INDEX]);
        assert_eq!(d.groups[0].mesh.normals.as_ref().unwrap()[0], Vec3::Z);
        let e = parse("v 1 2\n").unwrap_err().to_string();
        assert_eq!(e, "t.obj:1:6: expected 3 numbers after 'v', found 2");
    }

    #[test]
    fn continuation_comments_and_unknown_statements() {
        let d =
            parse("# c\nv 0 0 0 # x\nv 1 0 0\nv 0 1 0\ncstype bezier\nf 1 \\\n  2 3\n").unwrap();
        assert_eq!(d.groups[0].mesh.indices.len(), 1);
        let e = parse("v 0 0 0\nv 1 0 0\nf 1 \\\n 2 x\n")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "t.obj:4:4: expected a vertex index after 'f', found 'x'");
    }

    #[test]
    fn degenerate_triangles_dropped_or_rejected() {
        let d = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n").unwrap();
        assert_eq!(d.degenerate_dropped, 1);
        assert_eq!(d.first_degenerate.unwrap().line, 6);
        let e = parse("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("t.obj:4:1: every triangle of the file is degenerate"),
            "{e}"
        );
    }

    #[test]
    fn groups_by_material_and_merge() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl a\nf 1 2 3\nusemtl a\nf 2 4 3\nusemtl b\nf 1 2 4\n";
        let d = parse(text).unwrap();
        assert_eq!(d.groups.len(), 2);
        assert_eq!(d.groups[0].material.as_deref(), Some("a"));
        assert_eq!(d.groups[0].mesh.indices.len(), 2);
        assert_eq!(d.groups[0].location.line, 5);
        let m = obj_to_mesh(&d);
        assert_eq!(m.indices.len(), 3);
        assert_eq!(m.positions.len(), 4);
    }
}
