//! Radiance's octree files (`oconv`'s output; `src/common/readoct.c`, `sceneio.c`,
//! `portio.c`), read for the scene they hold: `ircache render scene.oct`, and the `instance`
//! primitive, which places an octree's surfaces in a scene.
//!
//! After a text header (`FORMAT=Radiance_octree`, ended by an empty line) come, in Radiance's
//! portable binary: the object size (`2` bytes, minus 283), the cube's origin and size (four
//! strings), the names of the scene files it was made from (`oconv -f`; then those files are
//! read instead), the object count, the octree itself (skipped: ircache builds its own), and the
//! primitives: the type names, then per object its type, modifier (an object number, −1 for
//! void), name, strings and reals (a 4-byte mantissa and a 1-byte exponent).
//!
//! Errors name the file and the object's number, from 1, as the "line" (1 for the file as a
//! whole).

use super::parse::{self, Primitive};
use super::xform::Transform;
use crate::error::SourceLocation;
use crate::SceneError;
use std::path::Path;
use std::sync::Arc;

/// Radiance's `OCTMAGIC`: `4 · MAXOBJSIZ + 251`.
const OCTMAGIC: i64 = 4 * 8 + 251;

/// Reads the primitives of the octree at `path`, each with the transform `transform`; `depth`
/// counts the files and instances it is nested in (the scene files an octree names are read at
/// the next depth, so that files naming each other end in an error).
pub fn read(
    path: &Path,
    transform: &Transform,
    depth: usize,
) -> Result<Vec<Primitive>, SceneError> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let file = Arc::new(path.to_path_buf());
    let err = |object: usize, m: String| at_object(&file, object, m);
    let start = header_end(&bytes, "Radiance_octree").ok_or_else(|| {
        err(
            1,
            "not a Radiance octree (its header does not say FORMAT=Radiance_octree)".into(),
        )
    })?;
    let mut r = Reader::new(&bytes, start);
    let truncated = |r: &Reader| err(1, format!("the octree is truncated at byte {}", r.pos));
    let size = r.int(2).ok_or_else(|| truncated(&r))? - OCTMAGIC;
    if !(1..=8).contains(&size) {
        return Err(err(1, "incompatible octree format".into()));
    }
    let size = size as usize;
    for _ in 0..4 {
        r.string().ok_or_else(|| truncated(&r))?;
    }
    let mut files = Vec::new();
    loop {
        let s = r.string().ok_or_else(|| truncated(&r))?;
        if s.is_empty() {
            break;
        }
        files.push(s);
    }
    let count = r.int(size).ok_or_else(|| truncated(&r))?;
    if !files.is_empty() {
        // `oconv -f`: the octree names its scene files instead of holding them.
        let dir = path.parent().unwrap_or(Path::new("."));
        let mut out = Vec::new();
        for f in files {
            parse::read_nested(&dir.join(&f), transform, depth + 1, &mut out)?;
        }
        return Ok(out);
    }
    r.skip_tree(size).ok_or_else(|| truncated(&r))?;
    let mut out = read_scene(&mut r, size, &file)?;
    for p in &mut out {
        p.transform = *transform;
    }
    if out.len() as i64 != count {
        return Err(err(
            1,
            format!("the octree says {count} objects and holds {}", out.len()),
        ));
    }
    Ok(out)
}

/// The scene data after an octree or mesh (`sceneio.c`'s `readscene`): the type names, then the
/// objects until the terminator; their transforms are the identity.
pub(super) fn read_scene(
    r: &mut Reader,
    size: usize,
    file: &Arc<std::path::PathBuf>,
) -> Result<Vec<Primitive>, SceneError> {
    let err = |object: usize, m: String| at_object(file, object, m);
    let truncated = |r: &Reader| err(1, format!("the file is truncated at byte {}", r.pos()));
    // The type names, in the writer's order.
    let mut types = Vec::new();
    loop {
        let s = r.string().ok_or_else(|| truncated(r))?;
        if s.is_empty() {
            break;
        }
        types.push(s);
    }
    let mut out: Vec<Primitive> = Vec::new();
    loop {
        let object = out.len();
        let t = r.int(1).ok_or_else(|| truncated(r))?;
        if t == -1 {
            break;
        }
        let kind = types
            .get(t as usize)
            .ok_or_else(|| err(object + 1, format!("object of unknown type number {t}")))?
            .clone();
        let m = r.int(size).ok_or_else(|| truncated(r))?;
        let modifier = if m == -1 {
            "void".to_string()
        } else {
            out.get(m as usize).map(|p| p.id.clone()).ok_or_else(|| {
                err(
                    object + 1,
                    format!("{kind}: modifier object {m} comes later"),
                )
            })?
        };
        let id = r.string().ok_or_else(|| truncated(r))?;
        let n = r.int(2).ok_or_else(|| truncated(r))?;
        let mut strings = Vec::new();
        for _ in 0..n.max(0) {
            strings.push(r.string().ok_or_else(|| truncated(r))?);
        }
        let n = r.int(2).ok_or_else(|| truncated(r))?;
        let mut reals = Vec::new();
        for _ in 0..n.max(0) {
            let v = r.real().ok_or_else(|| truncated(r))?;
            if !v.is_finite() {
                return Err(err(
                    object + 1,
                    format!("{kind} '{id}': a real argument is not finite"),
                ));
            }
            reals.push(v);
        }
        out.push(Primitive {
            modifier,
            kind,
            id,
            strings,
            integers: Vec::new(),
            reals,
            transform: Transform::default(),
            location: SourceLocation {
                file: file.clone(),
                line: object as u32 + 1,
                column: 1,
            },
        });
    }
    Ok(out)
}

/// An error about object `object` (from 1; 1 also for the file as a whole) of `file`.
pub(super) fn at_object(
    file: &Arc<std::path::PathBuf>,
    object: usize,
    message: String,
) -> SceneError {
    SceneError::at(
        SourceLocation {
            file: file.clone(),
            line: object as u32,
            column: 1,
        },
        message,
    )
}

/// Where the binary part starts: after the header's empty line, if the header names the
/// format `format`.
pub(super) fn header_end(bytes: &[u8], format: &str) -> Option<usize> {
    let end = bytes.windows(2).position(|w| w == b"\n\n")? + 2;
    let header = String::from_utf8_lossy(&bytes[..end]);
    header
        .lines()
        .any(|l| l.trim().strip_prefix("FORMAT=") == Some(format))
        .then_some(end)
}

/// Radiance's portable binary (`portio.c`).
pub(super) struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    /// Reading `bytes` from `pos`.
    pub(super) fn new(bytes: &'a [u8], pos: usize) -> Reader<'a> {
        Reader { bytes, pos }
    }

    /// Where it is.
    pub(super) fn pos(&self) -> usize {
        self.pos
    }

    fn byte(&mut self) -> Option<u8> {
        let b = *self.bytes.get(self.pos)?;
        self.pos += 1;
        Some(b)
    }

    /// A big-endian, sign-extended integer of `n` bytes.
    pub(super) fn int(&mut self, n: usize) -> Option<i64> {
        let first = self.byte()?;
        let mut r = i64::from(first as i8);
        for _ in 1..n {
            r = (r << 8) | i64::from(self.byte()?);
        }
        Some(r)
    }

    /// A mantissa of 4 bytes over 2³¹ − 1 and an exponent of 1.
    pub(super) fn real(&mut self) -> Option<f64> {
        let m = self.int(4)?;
        let e = self.int(1)?;
        if m == 0 {
            return Some(0.0);
        }
        let d = (m as f64 + 0.5 - f64::from(u8::from(m < 0))) / f64::from(0x7fff_ffff);
        Some(d * 2f64.powi(e as i32))
    }

    /// A NUL-terminated string.
    pub(super) fn string(&mut self) -> Option<String> {
        let len = self.bytes[self.pos..].iter().position(|&b| b == 0)?;
        let s = String::from_utf8_lossy(&self.bytes[self.pos..self.pos + len]).into_owned();
        self.pos += len + 1;
        Some(s)
    }

    /// Skips a pre-ordered octree (without recursion: a damaged file cannot exhaust the stack).
    pub(super) fn skip_tree(&mut self, size: usize) -> Option<()> {
        let mut pending = 1usize;
        while pending > 0 {
            pending -= 1;
            match self.byte()? {
                0 => {}
                1 => {
                    let n = self.int(size)?;
                    let skip = usize::try_from(n).ok()?.checked_mul(size)?;
                    if self.pos + skip > self.bytes.len() {
                        return None;
                    }
                    self.pos += skip;
                }
                2 => pending += 8,
                _ => return None,
            }
        }
        Some(())
    }
}
