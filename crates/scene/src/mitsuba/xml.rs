//! Reading Mitsuba XML files into an owned element tree, as Mitsuba 3's parser sees it:
//! `$name` substituted in every attribute value, `<default>` elements consumed, `<include>`
//! elements replaced by the included file's content, and files older than version 2.0.0
//! upgraded in memory (camelCase parameter names to snake_case, `lookAt` to `lookat`).
//!
//! Substitution follows Mitsuba: parameters come from the command line (`-D name=value`) first,
//! then from `<default>` elements in document order (a `<default>` never overrides an existing
//! value, and applies only to elements after it); longer names are substituted first. Anything
//! left starting with `$` is an undefined parameter and an error at its position.

use crate::error::{SceneError, SourceLocation};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// An attribute after substitution.
#[derive(Clone, Debug)]
pub(crate) struct Attr {
    /// Attribute name.
    pub name: String,
    /// Value after `$name` substitution.
    pub value: String,
    /// Where the attribute starts.
    pub loc: SourceLocation,
}

/// An element after substitution, defaults and includes.
#[derive(Clone, Debug)]
pub(crate) struct Element {
    /// Tag name.
    pub tag: String,
    /// Attributes, in document order.
    pub attrs: Vec<Attr>,
    /// Child elements (comments and whitespace dropped).
    pub children: Vec<Element>,
    /// Where the element starts (its `<`).
    pub loc: SourceLocation,
}

impl Element {
    /// The attribute `name`, if present.
    pub fn attr(&self, name: &str) -> Option<&Attr> {
        self.attrs.iter().find(|a| a.name == name)
    }

    /// The value of attribute `name`, if present.
    pub fn attr_value(&self, name: &str) -> Option<&str> {
        self.attr(name).map(|a| a.value.as_str())
    }

    /// Errors unless every attribute is in `allowed` and every one of `required` is present.
    pub fn check_attributes(&self, allowed: &[&str], required: &[&str]) -> Result<(), SceneError> {
        for a in &self.attrs {
            if !allowed.contains(&a.name.as_str()) {
                return Err(SceneError::at(
                    a.loc.clone(),
                    format!(
                        "unexpected attribute \"{}\" in element <{}> (expected {})",
                        a.name,
                        self.tag,
                        quoted_list(allowed)
                    ),
                ));
            }
        }
        for r in required {
            if self.attr(r).is_none() {
                return Err(SceneError::at(
                    self.loc.clone(),
                    format!("missing attribute \"{r}\" in element <{}>", self.tag),
                ));
            }
        }
        Ok(())
    }
}

/// `"a", "b" or "c"`.
pub(crate) fn quoted_list(items: &[&str]) -> String {
    let q: Vec<String> = items.iter().map(|s| format!("\"{s}\"")).collect();
    match q.len() {
        0 => String::new(),
        1 => q[0].clone(),
        n => format!("{} or {}", q[..n - 1].join(", "), q[n - 1]),
    }
}

/// Deepest element nesting accepted (bounds recursion on hostile input).
const MAX_DEPTH: usize = 128;
/// Deepest chain of `<include>`s accepted (Mitsuba's limit is 15).
const MAX_INCLUDE_DEPTH: usize = 15;

/// One file being read.
struct Source<'a> {
    file: Arc<PathBuf>,
    text: &'a str,
    doc: &'a roxmltree::Document<'a>,
    /// Version < 2.0.0: apply Mitsuba's in-memory upgrade.
    upgrade: bool,
}

impl Source<'_> {
    fn loc(&self, byte: usize) -> SourceLocation {
        let pos = self.doc.text_pos_at(byte.min(self.text.len()));
        SourceLocation {
            file: self.file.clone(),
            line: pos.row,
            column: pos.col,
        }
    }
}

/// Reads the scene file at `path` with `-D` overrides; returns its root `<scene>` element.
pub(crate) fn read_scene(path: &Path, defines: &[(String, String)]) -> Result<Element, SceneError> {
    let mut reader = Reader {
        params: defines.to_vec(),
        used: vec![false; defines.len()],
        stack: Vec::new(),
    };
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let file = Arc::new(path.to_path_buf());
    reader.stack.push(canonical(path));
    let doc = parse_document(&file, &text)?;
    let root = doc.root_element();
    let root_loc = location_of(&file, &doc, &text, root.range().start);
    if root.tag_name().name() != "scene" {
        // An ircache animation names its scene and frames: `ircache animate` renders it.
        let hint = if root.tag_name().name() == "animation" {
            " (this is an animation file: render its frames with `ircache animate`)"
        } else {
            ""
        };
        return Err(SceneError::at(
            root_loc,
            format!(
                "root element <{}> must be <scene version=\"3.0.0\">{hint}",
                root.tag_name().name()
            ),
        ));
    }
    let version = root.attribute("version").ok_or_else(|| {
        SceneError::at(
            root_loc.clone(),
            "missing version attribute in root element <scene> (e.g. version=\"3.0.0\")",
        )
    })?;
    let upgrade = parse_version(version).ok_or_else(|| {
        SceneError::at(
            root_loc.clone(),
            format!("could not parse version number \"{version}\" (expected major.minor.patch)"),
        )
    })? < (2, 0, 0);
    let src = Source {
        file,
        text: &text,
        doc: &doc,
        upgrade,
    };
    let mut attrs = Vec::new();
    for a in root.attributes() {
        if a.name() != "version" {
            attrs.push(Attr {
                name: a.name().to_string(),
                value: reader.substitute(&src, &a)?,
                loc: src.loc(a.range().start),
            });
        }
    }
    let mut children = Vec::new();
    reader.convert_children(&src, root, &mut children)?;
    reader.check_all_used(root_loc.clone())?;
    Ok(Element {
        tag: "scene".into(),
        attrs,
        children,
        loc: root_loc,
    })
}

fn parse_document<'a>(
    file: &Arc<PathBuf>,
    text: &'a str,
) -> Result<roxmltree::Document<'a>, SceneError> {
    // roxmltree recurses per nesting level: refuse absurd nesting before it overflows the stack.
    if let Some(byte) = too_deep(text, MAX_DEPTH + 8) {
        let (line, column) = line_column(text, byte);
        return Err(SceneError::at(
            SourceLocation {
                file: file.clone(),
                line,
                column,
            },
            format!("elements nested more than {MAX_DEPTH} deep"),
        ));
    }
    roxmltree::Document::parse(text).map_err(|e| {
        let pos = e.pos();
        let text = e.to_string();
        let suffix = format!(" at {}:{}", pos.row, pos.col);
        let text = text.strip_suffix(&suffix).unwrap_or(&text);
        SceneError::at(
            SourceLocation {
                file: file.clone(),
                line: pos.row,
                column: pos.col,
            },
            format!("malformed XML: {text}"),
        )
    })
}

/// The byte offset of the first element opened deeper than `limit`, by a quick scan that skips
/// comments, CDATA, processing instructions, declarations and quoted attribute values.
fn too_deep(text: &str, limit: usize) -> Option<usize> {
    let b = text.as_bytes();
    let skip_to = |from: usize, pat: &[u8]| -> usize {
        let from = from.min(b.len());
        b[from..]
            .windows(pat.len())
            .position(|w| w == pat)
            .map_or(b.len(), |p| from + p + pat.len())
    };
    let mut depth = 0usize;
    let mut i = 0;
    while i < b.len() {
        if b[i] != b'<' {
            i += 1;
            continue;
        }
        let rest = &b[i..];
        if rest.starts_with(b"<!--") {
            i = skip_to(i + 4, b"-->");
        } else if rest.starts_with(b"<![CDATA[") {
            i = skip_to(i + 9, b"]]>");
        } else if rest.starts_with(b"<?") {
            i = skip_to(i + 2, b"?>");
        } else if rest.starts_with(b"<!") {
            i = skip_to(i + 2, b">");
        } else if rest.starts_with(b"</") {
            depth = depth.saturating_sub(1);
            i = skip_to(i + 2, b">");
        } else {
            // Scan the tag, honouring quotes, to see whether it closes itself.
            let mut j = i + 1;
            let mut quote = None;
            while j < b.len() {
                match (quote, b[j]) {
                    (None, q @ (b'"' | b'\'')) => quote = Some(q),
                    (Some(q), c) if c == q => quote = None,
                    (None, b'>') => break,
                    _ => {}
                }
                j += 1;
            }
            if j >= b.len() || b[j - 1] != b'/' {
                depth += 1;
                if depth > limit {
                    return Some(i);
                }
            }
            i = j + 1;
        }
    }
    None
}

/// 1-based line and column (in characters) of a byte offset.
fn line_column(text: &str, byte: usize) -> (u32, u32) {
    let mut byte = byte.min(text.len());
    while !text.is_char_boundary(byte) {
        byte -= 1;
    }
    let before = &text[..byte];
    let line = before.matches('\n').count() as u32 + 1;
    let col_start = before.rfind('\n').map_or(0, |p| p + 1);
    (line, before[col_start..].chars().count() as u32 + 1)
}

fn location_of(
    file: &Arc<PathBuf>,
    doc: &roxmltree::Document<'_>,
    text: &str,
    byte: usize,
) -> SourceLocation {
    let pos = doc.text_pos_at(byte.min(text.len()));
    SourceLocation {
        file: file.clone(),
        line: pos.row,
        column: pos.col,
    }
}

fn canonical(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
}

/// `"major.minor.patch"` (Mitsuba splits on spaces and dots and wants exactly three numbers).
fn parse_version(v: &str) -> Option<(u32, u32, u32)> {
    let parts: Vec<&str> = v.split([' ', '.']).filter(|s| !s.is_empty()).collect();
    if parts.len() != 3 {
        return None;
    }
    Some((
        parts[0].parse().ok()?,
        parts[1].parse().ok()?,
        parts[2].parse().ok()?,
    ))
}

/// Mitsuba's camelCase → snake_case upgrade of a parameter name (`toWorld` → `to_world`,
/// `sampleCount` → `sample_count`, `intIOR` → `int_ior`).
fn upgrade_name(name: &str) -> String {
    let mut chars: Vec<char> = name.chars().collect();
    let mut i = 0;
    while i + 1 < chars.len() {
        if chars[i].is_ascii_lowercase() && chars[i + 1].is_ascii_uppercase() {
            chars.insert(i + 1, '_');
            i += 2;
            while i < chars.len() && chars[i].is_ascii_uppercase() {
                chars[i] = chars[i].to_ascii_lowercase();
                i += 1;
            }
        } else {
            i += 1;
        }
    }
    chars.into_iter().collect()
}

struct Reader {
    /// Substitution parameters: `-D` values first, then `<default>`s in document order.
    params: Vec<(String, String)>,
    /// Per `-D` value (the first entries of `params`): whether some attribute used it.
    used: Vec<bool>,
    /// Canonical paths of the files being read, outermost first (include-cycle detection).
    stack: Vec<PathBuf>,
}

impl Reader {
    fn substitute(
        &mut self,
        src: &Source<'_>,
        attr: &roxmltree::Attribute<'_, '_>,
    ) -> Result<String, SceneError> {
        let value = attr.value();
        if !value.contains('$') {
            return Ok(value.to_string());
        }
        // Longest names first, so that $resx is not read as $res followed by "x".
        let mut order: Vec<usize> = (0..self.params.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(self.params[i].0.len()));
        let mut out = value.to_string();
        for i in order {
            let (k, v) = &self.params[i];
            let pattern = format!("${k}");
            if out.contains(&pattern) {
                out = out.replace(&pattern, v);
                if let Some(used) = self.used.get_mut(i) {
                    *used = true;
                }
            }
        }
        if let Some(i) = out.find('$') {
            let name: String = out[i + 1..]
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            let raw_range = attr.range_value();
            let raw = src.text.get(raw_range.clone()).unwrap_or("");
            let pattern = format!("${name}");
            let byte = raw
                .find(&pattern)
                .map_or(attr.range().start, |o| raw_range.start + o);
            let message = if name.is_empty() {
                format!(
                    "stray '$' in attribute {}=\"{}\" (expected $name)",
                    attr.name(),
                    value
                )
            } else {
                format!(
                    "undefined parameter \"${name}\" in attribute {}=\"{}\" (define it with <default name=\"{name}\" \
                     value=\"...\"/> or -D {name}=...)",
                    attr.name(),
                    value
                )
            };
            return Err(SceneError::at(src.loc(byte), message));
        }
        Ok(out)
    }

    /// Every `-D` value must have been used, as Mitsuba 3 requires: a parameter the scene never
    /// names (a misspelt `-D max_detph=7`) is an error, not a value silently dropped.
    fn check_all_used(&self, root: SourceLocation) -> Result<(), SceneError> {
        let unused: Vec<String> = self
            .params
            .iter()
            .zip(&self.used)
            .filter(|(_, used)| !**used)
            .map(|((k, v), _)| format!("-D {k}={v}"))
            .collect();
        if unused.is_empty() {
            return Ok(());
        }
        let mut known: Vec<&str> = self.params[self.used.len()..]
            .iter()
            .map(|(k, _)| k.as_str())
            .chain(
                self.params
                    .iter()
                    .zip(&self.used)
                    .filter(|(_, used)| **used)
                    .map(|((k, _), _)| k.as_str()),
            )
            .collect();
        known.sort_unstable();
        known.dedup();
        Err(SceneError::at(
            root,
            format!(
                "{}: the scene names no such parameter (its parameters: {}; the command line's \
                 --width, --height, --spp, --max-depth, --sampler set any scene's)",
                unused.join(", "),
                if known.is_empty() {
                    "none".to_string()
                } else {
                    known
                        .iter()
                        .map(|k| format!("${k}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                }
            ),
        ))
    }

    fn convert_children(
        &mut self,
        src: &Source<'_>,
        node: roxmltree::Node<'_, '_>,
        out: &mut Vec<Element>,
    ) -> Result<(), SceneError> {
        for ch in node.children() {
            match ch.node_type() {
                roxmltree::NodeType::Element => self.convert_element(src, ch, out)?,
                roxmltree::NodeType::Text => {
                    let t = ch.text().unwrap_or("");
                    if let Some(off) = t.find(|c: char| !c.is_whitespace()) {
                        // Text nodes may hold expanded entities; positions are best effort.
                        return Err(SceneError::at(
                            src.loc(ch.range().start + off.min(ch.range().len())),
                            format!("unexpected text \"{}\" (only elements and comments may appear here)", t.trim()),
                        ));
                    }
                }
                _ => {}
            }
        }
        Ok(())
    }

    fn convert_element(
        &mut self,
        src: &Source<'_>,
        node: roxmltree::Node<'_, '_>,
        out: &mut Vec<Element>,
    ) -> Result<(), SceneError> {
        let loc = src.loc(node.range().start);
        if node.ancestors().count() > MAX_DEPTH {
            return Err(SceneError::at(
                loc,
                format!("elements nested more than {MAX_DEPTH} deep"),
            ));
        }
        let mut tag = node.tag_name().name().to_string();
        if src.upgrade && tag == "lookAt" {
            tag = "lookat".into();
        }
        let mut attrs = Vec::new();
        for a in node.attributes() {
            let mut value = self.substitute(src, &a)?;
            if src.upgrade && a.name() == "name" && tag != "default" {
                value = upgrade_name(&value);
            }
            attrs.push(Attr {
                name: a.name().to_string(),
                value,
                loc: src.loc(a.range().start),
            });
        }
        let mut el = Element {
            tag,
            attrs,
            children: Vec::new(),
            loc,
        };
        match el.tag.as_str() {
            "default" => {
                el.check_attributes(&["name", "value"], &["name", "value"])?;
                let name = el.attr_value("name").unwrap_or_default().to_string();
                if name.is_empty() {
                    return Err(SceneError::at(el.loc, "<default>: name must be nonempty"));
                }
                if node.children().any(|c| c.is_element()) {
                    return Err(SceneError::at(
                        el.loc,
                        "<default> cannot have child elements",
                    ));
                }
                if !self.params.iter().any(|(k, _)| *k == name) {
                    let value = el.attr_value("value").unwrap_or_default().to_string();
                    self.params.push((name, value));
                }
                Ok(())
            }
            "include" => self.include(src, &el, out),
            _ => {
                if node.attribute("version").is_some() {
                    el.attrs.retain(|a| a.name != "version");
                }
                let mut children = Vec::new();
                self.convert_children(src, node, &mut children)?;
                el.children = children;
                out.push(el);
                Ok(())
            }
        }
    }

    fn include(
        &mut self,
        src: &Source<'_>,
        el: &Element,
        out: &mut Vec<Element>,
    ) -> Result<(), SceneError> {
        el.check_attributes(&["filename"], &["filename"])?;
        let name = el.attr_value("filename").unwrap_or_default();
        let dir = src.file.parent().unwrap_or(Path::new(""));
        let path = dir.join(name);
        if !path.is_file() {
            return Err(SceneError::at(
                el.loc.clone(),
                format!("included file \"{}\" not found", path.display()),
            ));
        }
        let canon = canonical(&path);
        if self.stack.len() > MAX_INCLUDE_DEPTH {
            return Err(SceneError::at(
                el.loc.clone(),
                format!("<include> nested more than {MAX_INCLUDE_DEPTH} files deep"),
            ));
        }
        if let Some(first) = self.stack.iter().position(|p| *p == canon) {
            let chain: Vec<String> = self.stack[first..]
                .iter()
                .chain(std::iter::once(&canon))
                .map(|p| p.display().to_string())
                .collect();
            return Err(SceneError::at(
                el.loc.clone(),
                format!("include cycle: {}", chain.join(" includes ")),
            ));
        }
        let text = std::fs::read_to_string(&path).map_err(|e| SceneError::Referenced {
            location: el.loc.clone(),
            path: path.clone(),
            message: e.to_string(),
        })?;
        let file = Arc::new(path);
        let doc = parse_document(&file, &text)?;
        let root = doc.root_element();
        let root_loc = location_of(&file, &doc, &text, root.range().start);
        let upgrade = match root.attribute("version") {
            Some(v) => {
                parse_version(v).ok_or_else(|| {
                    SceneError::at(
                        root_loc.clone(),
                        format!("could not parse version number \"{v}\""),
                    )
                })? < (2, 0, 0)
            }
            None => false,
        };
        let nested = Source {
            file: file.clone(),
            text: &text,
            doc: &doc,
            upgrade,
        };
        self.stack.push(canon);
        let result = if root.tag_name().name() == "scene" {
            for a in root.attributes() {
                if a.name() != "version" {
                    return Err(SceneError::at(
                        nested.loc(a.range().start),
                        format!(
                            "unexpected attribute \"{}\" on an included <scene>",
                            a.name()
                        ),
                    ));
                }
            }
            self.convert_children(&nested, root, out)
        } else {
            self.convert_element(&nested, root, out)
        };
        self.stack.pop();
        result
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camel_case_upgrade() {
        assert_eq!(upgrade_name("toWorld"), "to_world");
        assert_eq!(upgrade_name("sampleCount"), "sample_count");
        assert_eq!(upgrade_name("intIOR"), "int_ior");
        assert_eq!(upgrade_name("max_depth"), "max_depth");
        assert_eq!(upgrade_name("fov"), "fov");
    }

    #[test]
    fn nesting_scan() {
        assert_eq!(too_deep("<a><b/><c x='>'><!-- <d> --></c></a>", 2), None);
        assert_eq!(too_deep("<a><b><c></c></b></a>", 2), Some(6));
        assert_eq!(line_column("ab\ncd", 4), (2, 2));
    }

    #[test]
    fn versions() {
        assert_eq!(parse_version("3.0.0"), Some((3, 0, 0)));
        assert_eq!(parse_version("0.5.0"), Some((0, 5, 0)));
        assert_eq!(parse_version("3.0"), None);
        assert_eq!(parse_version("a.b.c"), None);
    }

    #[test]
    fn list_formatting() {
        assert_eq!(quoted_list(&["a"]), "\"a\"");
        assert_eq!(quoted_list(&["a", "b", "c"]), "\"a\", \"b\" or \"c\"");
    }
}
