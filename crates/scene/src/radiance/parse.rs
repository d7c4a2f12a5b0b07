//! Reading Radiance scene files into primitives: `modifier type identifier` and three argument
//! lists (strings, integers, reals), `#` comments, and `!` command lines (Radiance's
//! `src/common/readobj.c`).
//!
//! `!xform` is carried out here (translations, rotations, scales, mirrors, `-i` iterations, `-a`
//! arrays, `-n` identifier prefixes, `-m` modifiers, `-I`), so that the usual way of placing one
//! file in another needs no Radiance installation; its transform is kept with each primitive,
//! applied by the loader. `!genbox` without bevels or rounding and `!gensky` (but for `-y`) are
//! made here too. Any other command runs through `sh -c` in the directory of the file
//! that names it, as `oconv` runs it, and its output is read as scene text; a command that fails
//! is an error at its line.

use super::xform::Transform;
use crate::error::SourceLocation;
use crate::SceneError;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// One primitive as written, with the transform of the `!xform` commands around it.
#[derive(Clone, Debug)]
pub struct Primitive {
    /// The modifier's identifier (`void` for none).
    pub modifier: String,
    /// The type (`polygon`, `plastic`, ...).
    pub kind: String,
    /// The identifier.
    pub id: String,
    /// String arguments (for `alias`, the one it refers to).
    pub strings: Vec<String>,
    /// Integer arguments.
    pub integers: Vec<i64>,
    /// Real arguments.
    pub reals: Vec<f64>,
    /// Object to world.
    pub transform: Transform,
    /// Where it starts.
    pub location: SourceLocation,
}

/// How the primitives of one file or command are to be changed (an `!xform`'s options).
#[derive(Clone, Debug, Default)]
struct Context {
    transform: Transform,
    prefix: Option<String>,
    modifier: Option<String>,
    depth: usize,
}

/// Nested files and commands deeper than this are an error (a file that includes itself).
const MAX_DEPTH: usize = 32;

/// Reads `path` and everything it includes: a scene file, or an octree (`.oct`) for the scene
/// it holds.
pub fn read(path: &Path) -> Result<Vec<Primitive>, SceneError> {
    let mut out = Vec::new();
    if is_octree(path) {
        let prims = super::octree::read(path, &Transform::default(), 0)?;
        expand_instances(prims, &Context::default(), &mut out)?;
        return Ok(out);
    }
    read_file(path, &Context::default(), &mut out)?;
    Ok(out)
}

/// Reads the scene file `path` (text) into `out` with `transform`, `depth` deep in files and
/// instances (an octree's list of the files it was made from).
pub fn read_nested(
    path: &Path,
    transform: &Transform,
    depth: usize,
    out: &mut Vec<Primitive>,
) -> Result<(), SceneError> {
    if depth >= MAX_DEPTH {
        return Err(SceneError::at(
            SourceLocation::start_of(path),
            format!("files, octrees and instances nest deeper than {MAX_DEPTH}"),
        ));
    }
    let ctx = Context {
        transform: *transform,
        depth,
        ..Context::default()
    };
    read_file(path, &ctx, out)
}

/// True for a file named as an octree.
pub fn is_octree(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("oct"))
}

/// Moves `prims` to `out`, each `instance` replaced by its octree's surfaces.
fn expand_instances(
    prims: Vec<Primitive>,
    ctx: &Context,
    out: &mut Vec<Primitive>,
) -> Result<(), SceneError> {
    for p in prims {
        if p.kind == "instance" {
            instance(&p, ctx, out)?;
        } else {
            out.push(p);
        }
    }
    Ok(())
}

/// An `instance`: the surfaces of an octree, moved by the transform after its name (then by the
/// `!xform`s around it), with the instance's modifier in place of their own unless it is void.
/// The octree's own modifiers keep to themselves: their names (and the references to them)
/// get the instance's name as a prefix, `instance/name`.
fn instance(p: &Primitive, ctx: &Context, out: &mut Vec<Primitive>) -> Result<(), SceneError> {
    let err = |m: String| SceneError::at(p.location.clone(), format!("instance '{}': {m}", p.id));
    if ctx.depth >= MAX_DEPTH {
        return Err(err(format!(
            "instances nest deeper than {MAX_DEPTH} (does an octree hold itself?)"
        )));
    }
    let (path, transform) = placed_file(p, "octree")?;
    let prims = super::octree::read(&path, &transform, ctx.depth + 1)
        .map_err(|e| e.referenced_from(&p.location))?;
    let renamed = localised(prims, p);
    let inner = Context {
        depth: ctx.depth + 1,
        ..ctx.clone()
    };
    expand_instances(renamed, &inner, out)
}

/// The file an `instance` or a `mesh` (`p`) names, a `what` file: its first string, found
/// beside the file naming it, and the transform after it followed by the `!xform`s around `p`.
pub(super) fn placed_file(p: &Primitive, what: &str) -> Result<(PathBuf, Transform), SceneError> {
    let err = |m: String| SceneError::at(p.location.clone(), format!("{} '{}': {m}", p.kind, p.id));
    let Some(file) = p.strings.first() else {
        return Err(err(format!(
            "expected the {what} file as its first string argument"
        )));
    };
    let own = super::xform::parse_plain(&p.strings[1..]).map_err(err)?;
    let dir = p.location.file.parent().unwrap_or(Path::new(""));
    Ok((dir.join(file), own.then(&p.transform)))
}

/// The primitives of the file `owner` (an `instance` or a `mesh`) places, kept apart from the
/// scene's: every name and every reference to a modifier prefixed `owner/`, surfaces given
/// `owner`'s modifier instead of their own unless it is void.
pub(super) fn localised(prims: Vec<Primitive>, owner: &Primitive) -> Vec<Primitive> {
    let local = |name: &str| format!("{}/{name}", owner.id);
    prims
        .into_iter()
        .map(|mut q| {
            let surface = !super::is_modifier_type(&q.kind) || q.kind == "instance";
            if surface && owner.modifier != "void" {
                q.modifier = owner.modifier.clone();
            } else if q.modifier != "void" {
                q.modifier = local(&q.modifier);
            }
            q.id = local(&q.id);
            q
        })
        .collect()
}

fn read_file(path: &Path, ctx: &Context, out: &mut Vec<Primitive>) -> Result<(), SceneError> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let text = String::from_utf8_lossy(&bytes);
    read_text(&text, Arc::new(path.to_path_buf()), ctx, out)
}

/// A cursor over a file's text that knows its line.
struct Cursor<'a> {
    text: &'a [u8],
    pos: usize,
    line: u32,
    line_start: usize,
    file: Arc<PathBuf>,
}

impl Cursor<'_> {
    fn location(&self) -> SourceLocation {
        SourceLocation {
            file: self.file.clone(),
            line: self.line,
            column: (self.pos - self.line_start + 1) as u32,
        }
    }

    fn skip_space(&mut self) {
        while let Some(&c) = self.text.get(self.pos) {
            if !c.is_ascii_whitespace() {
                break;
            }
            self.advance();
        }
    }

    fn advance(&mut self) {
        if self.text[self.pos] == b'\n' {
            self.line += 1;
            self.line_start = self.pos + 1;
        }
        self.pos += 1;
    }

    fn peek(&self) -> Option<u8> {
        self.text.get(self.pos).copied()
    }

    /// The rest of the line (joining lines that end in `\`), without the newline.
    fn rest_of_line(&mut self) -> String {
        let mut s = Vec::new();
        while let Some(c) = self.peek() {
            if c == b'\n' {
                if s.last() == Some(&b'\\') {
                    s.pop();
                    self.advance();
                    continue;
                }
                break;
            }
            s.push(c);
            self.advance();
        }
        String::from_utf8_lossy(&s).into_owned()
    }

    /// The next whitespace-separated word and where it starts; `None` at the end. A word in
    /// single or double quotes may hold white space; the quotes are not part of it (as
    /// Radiance's `fgetword`; `ies2rad` quotes its names).
    fn word(&mut self) -> Option<(String, SourceLocation)> {
        self.skip_space();
        let at = self.location();
        if let Some(q @ (b'"' | b'\'')) = self.peek() {
            self.advance();
            let start = self.pos;
            while self.peek().is_some_and(|c| c != q) {
                self.advance();
            }
            let word = String::from_utf8_lossy(&self.text[start..self.pos]).into_owned();
            if self.peek() == Some(q) {
                self.advance();
            }
            return Some((word, at));
        }
        let start = self.pos;
        while let Some(c) = self.peek() {
            if c.is_ascii_whitespace() {
                break;
            }
            self.advance();
        }
        (self.pos > start).then(|| {
            (
                String::from_utf8_lossy(&self.text[start..self.pos]).into_owned(),
                at,
            )
        })
    }

    fn expect_word(
        &mut self,
        what: &str,
        after: &SourceLocation,
    ) -> Result<(String, SourceLocation), SceneError> {
        self.word().ok_or_else(|| {
            SceneError::at(
                after.clone(),
                format!("the file ends where {what} was expected"),
            )
        })
    }

    fn count(&mut self, what: &str, after: &SourceLocation) -> Result<usize, SceneError> {
        let (w, at) = self.expect_word(what, after)?;
        w.parse::<usize>().map_err(|_| {
            SceneError::at(
                at,
                format!("expected {what} (a count of arguments), found \"{w}\""),
            )
        })
    }
}

fn read_text(
    text: &str,
    file: Arc<PathBuf>,
    ctx: &Context,
    out: &mut Vec<Primitive>,
) -> Result<(), SceneError> {
    let mut c = Cursor {
        text: text.as_bytes(),
        pos: 0,
        line: 1,
        line_start: 0,
        file,
    };
    loop {
        c.skip_space();
        let Some(first) = c.peek() else {
            return Ok(());
        };
        let at = c.location();
        match first {
            b'#' => {
                c.rest_of_line();
            }
            b'!' => {
                c.advance();
                let command = c.rest_of_line();
                run_command(command.trim(), &at, ctx, out)?;
            }
            _ => {
                let p = primitive(&mut c, ctx)?;
                if p.kind == "instance" {
                    instance(&p, ctx, out)?;
                } else {
                    out.push(p);
                }
            }
        }
    }
}

fn primitive(c: &mut Cursor, ctx: &Context) -> Result<Primitive, SceneError> {
    let (modifier, location) = c.word().expect("a word starts here");
    let (kind, kind_at) = c.expect_word("a primitive type after the modifier", &location)?;
    let (id, id_at) = c.expect_word("an identifier after the type", &kind_at)?;
    let modifier_type = super::is_modifier_type(&kind);
    let mut p = Primitive {
        modifier: match &ctx.modifier {
            Some(m) if !modifier_type => m.clone(),
            _ => modifier,
        },
        id: match &ctx.prefix {
            Some(prefix) if !modifier_type => format!("{prefix}.{id}"),
            _ => id,
        },
        kind,
        strings: Vec::new(),
        integers: Vec::new(),
        reals: Vec::new(),
        transform: ctx.transform,
        location,
    };
    if p.kind == "alias" {
        let (target, _) = c.expect_word("the identifier an alias refers to", &id_at)?;
        p.strings.push(target);
        return Ok(p);
    }
    let n = c.count("the number of string arguments", &id_at)?;
    for _ in 0..n {
        p.strings
            .push(c.expect_word("a string argument", &id_at)?.0);
    }
    let n = c.count("the number of integer arguments", &id_at)?;
    for _ in 0..n {
        let (w, at) = c.expect_word("an integer argument", &id_at)?;
        p.integers.push(w.parse().map_err(|_| {
            SceneError::at(at, format!("expected an integer argument, found \"{w}\""))
        })?);
    }
    let n = c.count("the number of real arguments", &id_at)?;
    for _ in 0..n {
        let (w, at) = c.expect_word("a real argument", &id_at)?;
        let v: f64 = w.parse().map_err(|_| {
            SceneError::at(
                at.clone(),
                format!("expected a real argument, found \"{w}\""),
            )
        })?;
        if !v.is_finite() {
            return Err(SceneError::at(
                at,
                format!("real argument \"{w}\" is not finite"),
            ));
        }
        p.reals.push(v);
    }
    Ok(p)
}

/// Splits a command line into words (no quoting beyond what Radiance's scene commands use).
fn split_command(command: &str) -> Vec<String> {
    let mut words = Vec::new();
    let mut cur = String::new();
    let mut quote: Option<char> = None;
    for ch in command.chars() {
        match quote {
            Some(q) if ch == q => quote = None,
            Some(_) => cur.push(ch),
            None if ch == '"' || ch == '\'' => quote = Some(ch),
            None if ch.is_whitespace() => {
                if !cur.is_empty() {
                    words.push(std::mem::take(&mut cur));
                }
            }
            None => cur.push(ch),
        }
    }
    if !cur.is_empty() {
        words.push(cur);
    }
    words
}

fn run_command(
    command: &str,
    at: &SourceLocation,
    ctx: &Context,
    out: &mut Vec<Primitive>,
) -> Result<(), SceneError> {
    if ctx.depth >= MAX_DEPTH {
        return Err(SceneError::at(
            at.clone(),
            format!(
                "files and commands nest deeper than {MAX_DEPTH} (does a file include itself?)"
            ),
        ));
    }
    let dir = at.file.parent().unwrap_or(Path::new("")).to_path_buf();
    let words = split_command(command);
    if words.first().map(String::as_str) == Some("xform")
        && !command.contains(['|', '<', '>', ';', '`', '$'])
    {
        return xform(&words[1..], &dir, at, ctx, out);
    }
    if words.is_empty() {
        return Err(SceneError::at(at.clone(), "an empty '!' command line"));
    }
    let generated = match super::sky::gensky(&words) {
        Some(Err(e)) => return Err(SceneError::at(at.clone(), e)),
        Some(Ok(text)) => Some(text),
        None => genbox(&words),
    };
    if let Some(text) = generated {
        let name = Arc::new(PathBuf::from(format!("{at} (!{command})")));
        let inner = Context {
            depth: ctx.depth + 1,
            ..ctx.clone()
        };
        return read_text(&text, name, &inner, out);
    }
    let output = std::process::Command::new("sh")
        .arg("-c")
        .arg(command)
        .current_dir(if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            &dir
        })
        .output()
        .map_err(|e| SceneError::at(at.clone(), format!("cannot run \"{command}\": {e}")))?;
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        let hint = if output.status.code() == Some(127) {
            " (is Radiance installed and on the PATH? ircache carries out '!xform' itself, \
             but not other Radiance commands)"
        } else {
            ""
        };
        return Err(SceneError::at(
            at.clone(),
            format!(
                "the command \"{command}\" failed ({}){hint}: {}",
                output.status,
                stderr.trim()
            ),
        ));
    }
    let text = String::from_utf8_lossy(&output.stdout).into_owned();
    let name = Arc::new(PathBuf::from(format!("{} (output of !{command})", at)));
    let inner = Context {
        depth: ctx.depth + 1,
        ..ctx.clone()
    };
    read_text(&text, name, &inner, out)
}

/// Radiance's `genbox mat name x y z [-i]` (`src/gen/genbox.c`) as the text it prints: six
/// polygons named by their corners, corner `v` at coordinate `i` being the size where bit `i` of
/// `v` is set (the other way round with `-i`, which turns the box inside out). `None` for other
/// commands and for genbox's bevels and rounded edges, which run as commands.
fn genbox(words: &[String]) -> Option<String> {
    let inverted = match words {
        [g, _, _, _, _, _] if g == "genbox" => false,
        [g, _, _, _, _, _, i] if g == "genbox" && i == "-i" => true,
        _ => return None,
    };
    let size: Vec<f64> = words[3..6].iter().filter_map(|w| w.parse().ok()).collect();
    if size.len() != 3 || size.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
        return None;
    }
    let mut text = String::new();
    for face in ["1540", "4620", "2310", "3267", "5137", "6457"] {
        text.push_str(&format!(
            "{} polygon {}.{face}\n0\n0\n12\n",
            words[1], words[2]
        ));
        for c in face.bytes() {
            let v = u32::from(c - b'0');
            for (i, s) in size.iter().enumerate() {
                let set = (v >> i) & 1 == 1;
                text.push_str(&format!(" {}", if set != inverted { *s } else { 0.0 }));
            }
            text.push('\n');
        }
    }
    Some(text)
}

/// Carries out `!xform` (see `xform.1`): options, then the files to read.
fn xform(
    args: &[String],
    dir: &Path,
    at: &SourceLocation,
    ctx: &Context,
    out: &mut Vec<Primitive>,
) -> Result<(), SceneError> {
    let err = |m: String| SceneError::at(at.clone(), format!("!xform: {m}"));
    let mut prefix = ctx.prefix.clone();
    let mut new_prefix: Option<String> = None;
    let mut modifier = None;
    let mut invert = false;
    let mut i = 0;
    // Identifier prefixes, modifiers and flags come first; then the transform.
    while i < args.len() {
        match args[i].as_str() {
            "-n" | "-m" => {
                let v = args
                    .get(i + 1)
                    .ok_or_else(|| err(format!("{} needs a name", args[i])))?
                    .clone();
                if args[i] == "-n" {
                    new_prefix = Some(match new_prefix {
                        Some(p) => format!("{p}.{v}"),
                        None => v,
                    });
                } else if modifier.is_none() {
                    modifier = Some(v);
                }
                i += 2;
            }
            "-c" | "-e" => i += 1,
            "-I" => {
                invert = !invert;
                i += 1;
            }
            "-f" => return Err(err("argument files (-f) are not supported".into())),
            _ => break,
        }
    }
    let (arrays, files) = super::xform::parse_options(&args[i..]).map_err(err)?;
    if files.is_empty() {
        return Err(err(
            "no file named: reading the standard input is not possible in a scene file".into(),
        ));
    }
    if let Some(p) = new_prefix {
        prefix = Some(match prefix {
            // The outer prefix wraps the inner one.
            Some(outer) => format!("{outer}.{p}"),
            None => p,
        });
    }
    for (copy, mut transform) in arrays {
        if invert {
            transform.reverse = !transform.reverse;
        }
        let inner = Context {
            transform: transform.then(&ctx.transform),
            prefix: match (&prefix, copy) {
                (Some(p), Some(k)) => Some(format!("{p}.{k}")),
                (None, Some(k)) => Some(k.to_string()),
                (p, None) => p.clone(),
            },
            modifier: ctx.modifier.clone().or_else(|| modifier.clone()),
            depth: ctx.depth + 1,
        };
        for f in &files {
            let path = dir.join(f);
            read_file(&path, &inner, out).map_err(|e| e.referenced_from(at))?;
        }
    }
    Ok(())
}
