//! Plugins and their property bags: the element tree of [`super::xml`] turned into objects
//! (`<bsdf type="diffuse">` ...) with typed, located properties.
//!
//! Every read of a property marks it used; [`Plugin::check_unused`] then reports what a plugin
//! did not read, as Mitsuba's "unreferenced property" error. Ids are global: a duplicate id is an
//! error, and `<ref id>` is resolved when the referring plugin is built, so forward references
//! work as in Mitsuba.

use super::transform;
use super::xml::{quoted_list, Element};
use crate::error::{SceneError, SourceLocation};
use ircache_math::{Mat4, Rgb, Vec3};
use std::cell::Cell;
use std::collections::HashMap;
use std::rc::Rc;

/// Element tags that are plugins (objects) and that this loader builds.
pub(crate) const OBJECT_TAGS: &[&str] = &[
    "integrator",
    "sensor",
    "film",
    "rfilter",
    "sampler",
    "shape",
    "bsdf",
    "emitter",
    "texture",
    "medium",
    "phase",
    "volume",
];

/// Mitsuba object tags that this loader does not support.
const UNSUPPORTED_OBJECT_TAGS: &[&str] = &["spectrum"];

/// Value tags.
const VALUE_TAGS: &[&str] = &[
    "float",
    "integer",
    "boolean",
    "string",
    "rgb",
    "vector",
    "point",
    "spectrum",
    "transform",
];

/// A property value.
#[derive(Debug)]
pub(crate) enum Value {
    /// `<float>`.
    Float(f64),
    /// `<integer>`.
    Integer(i64),
    /// `<boolean>`.
    Boolean(bool),
    /// `<string>`.
    String(String),
    /// `<rgb>`.
    Rgb([f64; 3]),
    /// A constant `<spectrum value="v">`: v in every channel, except where it is an emitter's
    /// radiance ([`Plugin::emission_opt`]).
    Spectrum(f64),
    /// `<spectrum value="w₁:v₁, w₂:v₂, …">` (nm, increasing): its colour as Mitsuba 3's RGB
    /// variants compute it ([`super::cie`]).
    SpectrumList(Vec<(f64, f64)>),
    /// `<vector>` or `<point>`.
    Vector([f64; 3]),
    /// `<transform>`.
    Transform(Mat4),
    /// A nested plugin.
    Object(Rc<Plugin>),
    /// `<ref id>`.
    Ref(String),
}

impl Value {
    /// The value's type as Mitsuba's XML names it.
    pub fn type_name(&self) -> &'static str {
        match self {
            Value::Float(_) => "float",
            Value::Integer(_) => "integer",
            Value::Boolean(_) => "boolean",
            Value::String(_) => "string",
            Value::Rgb(_) => "rgb",
            Value::Spectrum(_) | Value::SpectrumList(_) => "spectrum",
            Value::Vector(_) => "vector",
            Value::Transform(_) => "transform",
            Value::Object(_) | Value::Ref(_) => "object",
        }
    }
}

/// A named property of a plugin.
#[derive(Debug)]
pub(crate) struct Prop {
    /// Its name (`_arg_N` for unnamed nested objects).
    pub name: String,
    /// Its value.
    pub value: Value,
    /// Where it was written.
    pub loc: SourceLocation,
    used: Cell<bool>,
}

/// A plugin: `<tag type="..." id="...">` with its properties.
#[derive(Debug)]
pub(crate) struct Plugin {
    /// Element tag (`bsdf`, `shape`, ...; `scene` for the root).
    pub tag: String,
    /// Plugin type (`diffuse`, ...).
    pub ty: String,
    /// `id` attribute.
    pub id: Option<String>,
    /// Where it was declared.
    pub loc: SourceLocation,
    /// Properties in document order.
    pub props: Vec<Prop>,
}

/// All plugins with an id.
pub(crate) type Ids = HashMap<String, Rc<Plugin>>;

/// Builds the plugin tree of a `<scene>` element and its id table.
pub(crate) fn build_tree(scene: &Element) -> Result<(Rc<Plugin>, Ids), SceneError> {
    let mut ids = Ids::new();
    let mut props = Vec::new();
    scene.check_attributes(&[], &[])?;
    let mut arg = 0;
    for ch in &scene.children {
        if let Some(p) = convert_child(ch, &mut ids, &mut arg)? {
            push_prop(&mut props, p)?;
        }
    }
    let root = Rc::new(Plugin {
        tag: "scene".into(),
        ty: "scene".into(),
        id: None,
        loc: scene.loc.clone(),
        props,
    });
    Ok((root, ids))
}

fn push_prop(props: &mut Vec<Prop>, p: Prop) -> Result<(), SceneError> {
    if let Some(prev) = props.iter().find(|q| q.name == p.name) {
        return Err(SceneError::at(
            p.loc,
            format!(
                "property \"{}\" was specified multiple times (first at {})",
                p.name, prev.loc
            ),
        ));
    }
    props.push(p);
    Ok(())
}

fn convert_object(el: &Element, ids: &mut Ids) -> Result<Rc<Plugin>, SceneError> {
    el.check_attributes(&["type", "id", "name"], &["type"])?;
    let ty = el.attr_value("type").unwrap_or_default().to_string();
    let id = el.attr_value("id").map(str::to_string);
    if let Some(id) = &id {
        if id.starts_with('_') {
            return Err(SceneError::at(
                el.attr("id").map_or(el.loc.clone(), |a| a.loc.clone()),
                format!("invalid id \"{id}\": leading underscores are reserved"),
            ));
        }
        if id.is_empty() {
            return Err(SceneError::at(el.loc.clone(), "empty id"));
        }
    }
    let mut props = Vec::new();
    let mut arg = 0;
    for ch in &el.children {
        if let Some(p) = convert_child(ch, ids, &mut arg)? {
            push_prop(&mut props, p)?;
        }
    }
    let plugin = Rc::new(Plugin {
        tag: el.tag.clone(),
        ty,
        id: id.clone(),
        loc: el.loc.clone(),
        props,
    });
    if let Some(id) = id {
        if let Some(prev) = ids.get(&id) {
            return Err(SceneError::at(
                el.loc.clone(),
                format!(
                    "<{}> has duplicate id \"{id}\" (previous was at {})",
                    el.tag, prev.loc
                ),
            ));
        }
        ids.insert(id, plugin.clone());
    }
    Ok(plugin)
}

/// A child element as a property; `None` for elements that define nothing (`<alias>`).
fn convert_child(el: &Element, ids: &mut Ids, arg: &mut usize) -> Result<Option<Prop>, SceneError> {
    let tag = el.tag.as_str();
    let mut next_arg = || {
        let n = format!("_arg_{arg}");
        *arg += 1;
        n
    };
    let name_of = |el: &Element, anon: &mut dyn FnMut() -> String| -> Result<String, SceneError> {
        match el.attr("name") {
            Some(a) if a.value.starts_with('_') => Err(SceneError::at(
                a.loc.clone(),
                format!(
                    "invalid parameter name \"{}\": leading underscores are reserved",
                    a.value
                ),
            )),
            Some(a) if a.value.is_empty() => {
                Err(SceneError::at(a.loc.clone(), "empty parameter name"))
            }
            Some(a) => Ok(a.value.clone()),
            None => Ok(anon()),
        }
    };
    if OBJECT_TAGS.contains(&tag) || (tag == "spectrum" && el.attr("type").is_some()) {
        if tag == "spectrum" {
            return Err(SceneError::at(
                el.loc.clone(),
                "spectrum plugins are not supported (use <rgb>)",
            ));
        }
        let name = name_of(el, &mut next_arg)?;
        let plugin = convert_object(el, ids)?;
        return Ok(Some(Prop {
            name,
            value: Value::Object(plugin),
            loc: el.loc.clone(),
            used: Cell::new(false),
        }));
    }
    if tag == "ref" {
        el.check_attributes(&["id", "name"], &["id"])?;
        if let Some(c) = el.children.first() {
            return Err(SceneError::at(
                c.loc.clone(),
                "<ref> cannot have child elements",
            ));
        }
        let name = name_of(el, &mut next_arg)?;
        let id = el.attr_value("id").unwrap_or_default().to_string();
        return Ok(Some(Prop {
            name,
            value: Value::Ref(id),
            loc: el.loc.clone(),
            used: Cell::new(false),
        }));
    }
    if tag == "alias" {
        el.check_attributes(&["id", "as"], &["id", "as"])?;
        let src = el.attr_value("id").unwrap_or_default();
        let dst = el.attr_value("as").unwrap_or_default().to_string();
        let target = ids.get(src).cloned().ok_or_else(|| {
            SceneError::at(
                el.loc.clone(),
                format!("<alias>: referenced id \"{src}\" not found"),
            )
        })?;
        if let Some(prev) = ids.get(&dst) {
            return Err(SceneError::at(
                el.loc.clone(),
                format!(
                    "<alias> has duplicate id \"{dst}\" (previous was at {})",
                    prev.loc
                ),
            ));
        }
        ids.insert(dst, target);
        return Ok(None);
    }
    if UNSUPPORTED_OBJECT_TAGS.contains(&tag) && !(tag == "spectrum" && el.attr("type").is_none()) {
        return Err(SceneError::at(
            el.loc.clone(),
            format!("<{tag}> objects are not supported by this renderer"),
        ));
    }
    if !VALUE_TAGS.contains(&tag) {
        let hint = match tag {
            "translate" | "rotate" | "scale" | "matrix" | "lookat" => {
                " (transform operations can only occur inside <transform>)".to_string()
            }
            "path" => " (<path> resource folders are not supported; give paths relative to the scene file)".into(),
            _ => String::new(),
        };
        return Err(SceneError::at(
            el.loc.clone(),
            format!(
                "unexpected tag <{tag}>{hint}; expected one of {}, ref, include, default, alias",
                OBJECT_TAGS
                    .iter()
                    .chain(VALUE_TAGS.iter())
                    .copied()
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ));
    }
    // Value tags.
    if let Some(c) = el.children.first() {
        if tag != "transform" {
            return Err(SceneError::at(
                c.loc.clone(),
                format!("node <{}> cannot occur as child of <{tag}>", c.tag),
            ));
        }
    }
    let value = match tag {
        "float" => {
            el.check_attributes(&["name", "value"], &["name", "value"])?;
            Value::Float(parse_float(el, "value")?)
        }
        "integer" => {
            el.check_attributes(&["name", "value"], &["name", "value"])?;
            let a = el.attr("value").unwrap();
            let v = a.value.trim().parse::<i64>().map_err(|_| {
                SceneError::at(
                    a.loc.clone(),
                    format!("could not parse integer value \"{}\"", a.value),
                )
            })?;
            Value::Integer(v)
        }
        "boolean" => {
            el.check_attributes(&["name", "value"], &["name", "value"])?;
            let a = el.attr("value").unwrap();
            match a.value.trim().to_ascii_lowercase().as_str() {
                "true" => Value::Boolean(true),
                "false" => Value::Boolean(false),
                _ => {
                    return Err(SceneError::at(
                        a.loc.clone(),
                        format!(
                            "could not parse boolean value \"{}\" (must be \"true\" or \"false\")",
                            a.value
                        ),
                    ))
                }
            }
        }
        "string" => {
            el.check_attributes(&["name", "value"], &["name", "value"])?;
            Value::String(el.attr_value("value").unwrap_or_default().to_string())
        }
        "rgb" => {
            el.check_attributes(&["name", "value"], &["name", "value"])?;
            let a = el.attr("value").unwrap();
            let v = parse_numbers(&a.value).map_err(|t| {
                SceneError::at(
                    a.loc.clone(),
                    format!(
                        "could not parse RGB value \"{}\" (bad number \"{t}\")",
                        a.value
                    ),
                )
            })?;
            match v.len() {
                1 => Value::Rgb([v[0]; 3]),
                3 => Value::Rgb([v[0], v[1], v[2]]),
                _ => {
                    return Err(SceneError::at(
                        a.loc.clone(),
                        format!("<rgb> requires one or three values (got \"{}\")", a.value),
                    ))
                }
            }
        }
        "spectrum" => {
            el.check_attributes(&["name", "value", "filename"], &["name"])?;
            let Some(a) = el.attr("value") else {
                return Err(SceneError::at(
                    el.loc.clone(),
                    "spectrum files are not read: give the spectrum as value=\"v\" or value=\"w1:v1, w2:v2, ...\"",
                ));
            };
            if a.value.contains(':') {
                Value::SpectrumList(parse_spectrum_pairs(&a.value).map_err(|m| {
                    SceneError::at(
                        a.loc.clone(),
                        format!("<spectrum value=\"{}\">: {m}", a.value),
                    )
                })?)
            } else {
                match parse_numbers(&a.value) {
                    Ok(v) if v.len() == 1 => Value::Spectrum(v[0]),
                    _ => {
                        return Err(SceneError::at(
                            a.loc.clone(),
                            format!(
                                "a <spectrum> value is one number or wavelength:value pairs, got \"{}\"",
                                a.value
                            ),
                        ))
                    }
                }
            }
        }
        "vector" | "point" => {
            el.check_attributes(&["name", "value", "x", "y", "z"], &["name"])?;
            Value::Vector(parse_xyz(el, 0.0)?)
        }
        "transform" => {
            el.check_attributes(&["name"], &["name"])?;
            Value::Transform(parse_transform(el)?)
        }
        _ => unreachable!("value tags are listed"),
    };
    let name = name_of(el, &mut next_arg)?;
    Ok(Some(Prop {
        name,
        value,
        loc: el.loc.clone(),
        used: Cell::new(false),
    }))
}

/// `w:v` pairs separated by commas or whitespace: at least two, wavelengths increasing and
/// positive, values finite.
fn parse_spectrum_pairs(s: &str) -> Result<Vec<(f64, f64)>, String> {
    let mut pairs: Vec<(f64, f64)> = Vec::new();
    for token in s
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
    {
        let (w, v) = token
            .split_once(':')
            .and_then(|(w, v)| Some((parse_f64(w)?, parse_f64(v)?)))
            .ok_or_else(|| format!("\"{token}\" is not a wavelength:value pair"))?;
        if !(w.is_finite() && w > 0.0 && v.is_finite()) {
            return Err(format!(
                "\"{token}\" needs a positive wavelength and a finite value"
            ));
        }
        if pairs.last().is_some_and(|&(last, _)| w <= last) {
            return Err(format!("wavelengths must increase (at \"{token}\")"));
        }
        pairs.push((w, v));
    }
    if pairs.len() < 2 {
        return Err("a spectrum needs at least two wavelength:value pairs".into());
    }
    Ok(pairs)
}

/// Notes for the spectra of the tree whose colour leaves sRGB's gamut below zero: Mitsuba 3
/// raises the negative channels to zero with a warning, and so does ircache (an emitter's
/// spectra read as emissions, the others as reflectances weighted by D65).
pub(crate) fn out_of_gamut_notes(root: &Rc<Plugin>, ids: &Ids) -> Vec<String> {
    let mut notes = Vec::new();
    let mut seen: Vec<*const Plugin> = Vec::new();
    let mut stack: Vec<Rc<Plugin>> = vec![root.clone()];
    stack.extend(ids.values().cloned());
    while let Some(p) = stack.pop() {
        if seen.contains(&Rc::as_ptr(&p)) {
            continue;
        }
        seen.push(Rc::as_ptr(&p));
        for prop in &p.props {
            match &prop.value {
                Value::Object(o) => stack.push(o.clone()),
                Value::SpectrumList(pairs) => {
                    use super::cie::{spectrum_to_srgb, SpectrumUse};
                    let (usage, what) = if p.tag == "emitter" {
                        (SpectrumUse::Emission, "an emission")
                    } else {
                        (SpectrumUse::Ratio, "a reflectance (weighted by D65)")
                    };
                    if spectrum_to_srgb(pairs, usage).1 {
                        notes.push(format!(
                            "{}: the spectrum \"{}\" lies outside sRGB's gamut as {what}; its negative channels are raised to zero, as Mitsuba 3 does",
                            prop.loc, prop.name
                        ));
                    }
                }
                _ => {}
            }
        }
    }
    notes
}

/// Splits on commas and whitespace and parses each number; `Err(token)` names a bad one.
pub(crate) fn parse_numbers(s: &str) -> Result<Vec<f64>, String> {
    s.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| parse_f64(t).ok_or_else(|| t.to_string()))
        .collect()
}

/// Parses a number as C's `strtod` would for a whole token (so `1e-008`, `nan`, `inf` work).
fn parse_f64(t: &str) -> Option<f64> {
    let t = t.trim();
    t.parse::<f64>()
        .ok()
        .or_else(|| t.strip_suffix(['f', 'F']).and_then(|s| s.parse().ok()))
}

fn parse_float(el: &Element, attr: &str) -> Result<f64, SceneError> {
    let a = el.attr(attr).ok_or_else(|| {
        SceneError::at(
            el.loc.clone(),
            format!("missing attribute \"{attr}\" in <{}>", el.tag),
        )
    })?;
    parse_f64(&a.value).ok_or_else(|| {
        SceneError::at(
            a.loc.clone(),
            format!("could not parse floating point value \"{}\"", a.value),
        )
    })
}

/// `value="x y z"` (one value: all three) or `x`, `y`, `z` attributes (missing ones `default`).
fn parse_xyz(el: &Element, default: f64) -> Result<[f64; 3], SceneError> {
    if let Some(a) = el.attr("value") {
        if let Some(b) = ["x", "y", "z"].iter().find_map(|n| el.attr(n)) {
            return Err(SceneError::at(
                b.loc.clone(),
                "can't mix and match \"value\" and \"x\"/\"y\"/\"z\" attributes",
            ));
        }
        let v = parse_numbers(&a.value).map_err(|t| {
            SceneError::at(
                a.loc.clone(),
                format!("could not parse floating point value \"{t}\""),
            )
        })?;
        return match v.len() {
            1 => Ok([v[0]; 3]),
            3 => Ok([v[0], v[1], v[2]]),
            _ => Err(SceneError::at(
                a.loc.clone(),
                format!(
                    "\"value\" must have exactly 1 or 3 elements (got \"{}\")",
                    a.value
                ),
            )),
        };
    }
    let mut out = [default; 3];
    for (i, n) in ["x", "y", "z"].iter().enumerate() {
        if el.attr(n).is_some() {
            out[i] = parse_float(el, n)?;
        }
    }
    Ok(out)
}

fn parse_named_vector(el: &Element, name: &str) -> Result<Vec3, SceneError> {
    let a = el.attr(name).unwrap();
    let v = parse_numbers(&a.value).map_err(|t| {
        SceneError::at(
            a.loc.clone(),
            format!("could not parse floating point value \"{t}\" in \"{name}\""),
        )
    })?;
    if v.len() != 3 {
        return Err(SceneError::at(
            a.loc.clone(),
            format!("\"{name}\" attribute must have exactly 3 elements"),
        ));
    }
    Ok(vec3(v[0], v[1], v[2]))
}

fn vec3(x: f64, y: f64, z: f64) -> Vec3 {
    Vec3::new(x as f32, y as f32, z as f32)
}

fn parse_transform(el: &Element) -> Result<Mat4, SceneError> {
    let mut m = Mat4::IDENTITY;
    for op in &el.children {
        let step = match op.tag.as_str() {
            "translate" => {
                op.check_attributes(&["value", "x", "y", "z"], &[])?;
                let v = parse_xyz(op, 0.0)?;
                transform::translate(vec3(v[0], v[1], v[2]))
            }
            "scale" => {
                op.check_attributes(&["value", "x", "y", "z"], &[])?;
                let v = parse_xyz(op, 1.0)?;
                transform::scale(vec3(v[0], v[1], v[2]))
            }
            "rotate" => {
                op.check_attributes(&["value", "x", "y", "z", "angle"], &["angle"])?;
                let v = parse_xyz(op, 0.0)?;
                let angle = parse_float(op, "angle")?;
                transform::rotate(vec3(v[0], v[1], v[2]), angle as f32).ok_or_else(|| {
                    SceneError::at(op.loc.clone(), "rotation axis must be a nonzero vector (x, y, z or value)")
                })?
            }
            "lookat" => {
                op.check_attributes(&["origin", "target", "up"], &["origin", "target"])?;
                let origin = parse_named_vector(op, "origin")?;
                let target = parse_named_vector(op, "target")?;
                let up = if op.attr("up").is_some() { parse_named_vector(op, "up")? } else { Vec3::ZERO };
                transform::look_at(origin, target, up).ok_or_else(|| {
                    SceneError::at(op.loc.clone(), "invalid lookat transformation (origin = target, or up parallel to the view direction)")
                })?
            }
            "matrix" => {
                op.check_attributes(&["value"], &["value"])?;
                let a = op.attr("value").unwrap();
                let v = parse_numbers(&a.value)
                    .map_err(|t| SceneError::at(a.loc.clone(), format!("could not parse floating point value \"{t}\"")))?;
                let f: Vec<f32> = v.iter().map(|&x| x as f32).collect();
                match f.len() {
                    16 => transform::matrix_row_major(f.as_slice().try_into().unwrap()),
                    9 => transform::matrix3_row_major(f.as_slice().try_into().unwrap()),
                    n => {
                        return Err(SceneError::at(
                            a.loc.clone(),
                            format!("<matrix> expects 16 (or 9) values in row-major order, got {n}"),
                        ))
                    }
                }
            }
            other => {
                return Err(SceneError::at(
                    op.loc.clone(),
                    format!(
                        "unexpected <{other}> in <transform> (expected translate, rotate, scale, lookat or matrix)"
                    ),
                ))
            }
        };
        if let Some(c) = op.children.first() {
            return Err(SceneError::at(
                c.loc.clone(),
                format!("<{}> cannot have child elements", op.tag),
            ));
        }
        m = step * m;
    }
    if !m.is_finite() {
        return Err(SceneError::at(
            el.loc.clone(),
            "transform has non-finite entries",
        ));
    }
    Ok(m)
}

impl Plugin {
    /// What this plugin is, for messages: `bsdf plugin of type "diffuse"`.
    pub fn describe(&self) -> String {
        format!("{} plugin of type \"{}\"", self.tag, self.ty)
    }

    /// The property `name`, marking it used.
    pub fn get(&self, name: &str) -> Option<&Prop> {
        let p = self.props.iter().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }

    /// Whether `name` has been read.
    pub fn is_used(&self, name: &str) -> bool {
        self.props.iter().any(|p| p.name == name && p.used.get())
    }

    /// Whether `name` is present (without marking it used).
    pub fn has(&self, name: &str) -> bool {
        self.props.iter().any(|p| p.name == name)
    }

    fn wrong_type(&self, p: &Prop, expected: &str) -> SceneError {
        SceneError::at(
            p.loc.clone(),
            format!(
                "property \"{}\" of the {} has the wrong type: expected {expected}, got {}",
                p.name,
                self.describe(),
                p.value.type_name()
            ),
        )
    }

    /// A float (an `<integer>` is accepted too).
    pub fn float_opt(&self, name: &str) -> Result<Option<(f32, &Prop)>, SceneError> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match p.value {
                Value::Float(v) => Ok(Some((v as f32, p))),
                Value::Integer(v) => Ok(Some((v as f32, p))),
                _ => Err(self.wrong_type(p, "float")),
            },
        }
    }

    /// A float with a default.
    pub fn float(&self, name: &str, default: f32) -> Result<f32, SceneError> {
        Ok(self.float_opt(name)?.map_or(default, |(v, _)| v))
    }

    /// An integer.
    pub fn integer_opt(&self, name: &str) -> Result<Option<(i64, &Prop)>, SceneError> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match p.value {
                Value::Integer(v) => Ok(Some((v, p))),
                _ => Err(self.wrong_type(p, "integer")),
            },
        }
    }

    /// A boolean with a default.
    pub fn boolean(&self, name: &str, default: bool) -> Result<bool, SceneError> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Boolean(v) => Ok(v),
                _ => Err(self.wrong_type(p, "boolean")),
            },
        }
    }

    /// A string.
    pub fn string_opt(&self, name: &str) -> Result<Option<(&str, &Prop)>, SceneError> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match &p.value {
                Value::String(v) => Ok(Some((v.as_str(), p))),
                _ => Err(self.wrong_type(p, "string")),
            },
        }
    }

    /// A colour: `<rgb>`, or a `<float>`/`<integer>` used for all three channels.
    pub fn rgb_opt(&self, name: &str) -> Result<Option<(Rgb, &Prop)>, SceneError> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match p.value {
                Value::Rgb(v) => Ok(Some((Rgb::new(v[0] as f32, v[1] as f32, v[2] as f32), p))),
                Value::Spectrum(v) | Value::Float(v) => Ok(Some((Rgb::splat(v as f32), p))),
                Value::SpectrumList(ref pairs) => Ok(Some((
                    super::cie::spectrum_to_srgb(pairs, super::cie::SpectrumUse::Ratio).0,
                    p,
                ))),
                Value::Integer(v) => Ok(Some((Rgb::splat(v as f32), p))),
                Value::Object(_) | Value::Ref(_) => Err(SceneError::at(
                    p.loc.clone(),
                    format!(
                        "property \"{}\" of the {}: textures are not supported here (give an <rgb> value)",
                        p.name,
                        self.describe()
                    ),
                )),
                _ => Err(self.wrong_type(p, "rgb")),
            },
        }
    }

    /// An emitter's radiance, irradiance or intensity: as [`Self::rgb_opt`], except that a
    /// constant `<spectrum value="v">` is an equal-energy spectrum, which Mitsuba 3's RGB
    /// variants turn into `v · xyz_to_srgb(1, 1, 1)` (sRGB's white is D65, so equal energy is
    /// slightly red; `<rgb>` and `<float>` values stay as they are).
    pub fn emission_opt(&self, name: &str) -> Result<Option<(Rgb, &Prop)>, SceneError> {
        match self.get(name) {
            Some(p) => match p.value {
                Value::Spectrum(v) => Ok(Some((super::cie::equal_energy_srgb() * v as f32, p))),
                Value::SpectrumList(ref pairs) => Ok(Some((
                    super::cie::spectrum_to_srgb(pairs, super::cie::SpectrumUse::Emission).0,
                    p,
                ))),
                _ => self.rgb_opt(name),
            },
            None => Ok(None),
        }
    }

    /// A colour with a default.
    pub fn rgb(&self, name: &str, default: Rgb) -> Result<Rgb, SceneError> {
        Ok(self.rgb_opt(name)?.map_or(default, |(v, _)| v))
    }

    /// A `<vector>` or `<point>`.
    pub fn vector_opt(&self, name: &str) -> Result<Option<(Vec3, &Prop)>, SceneError> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match p.value {
                Value::Vector(v) => Ok(Some((vec3(v[0], v[1], v[2]), p))),
                _ => Err(self.wrong_type(p, "vector or point")),
            },
        }
    }

    /// A `<transform>`.
    pub fn transform_opt(&self, name: &str) -> Result<Option<(Mat4, &Prop)>, SceneError> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match p.value {
                Value::Transform(m) => Ok(Some((m, p))),
                _ => Err(self.wrong_type(p, "transform")),
            },
        }
    }

    /// Nested and referenced objects of any name, in document order, resolved through `ids`,
    /// with the property that holds each; marks them used.
    pub fn objects<'a>(&'a self, ids: &Ids) -> Result<Vec<(Rc<Plugin>, &'a Prop)>, SceneError> {
        let mut out = Vec::new();
        for p in &self.props {
            if let Some(o) = resolve(p, ids)? {
                p.used.set(true);
                out.push((o, p));
            }
        }
        Ok(out)
    }

    /// Nested/referenced objects whose tag is `tag`, marking only those used.
    pub fn objects_of<'a>(
        &'a self,
        ids: &Ids,
        tag: &str,
    ) -> Result<Vec<(Rc<Plugin>, &'a Prop)>, SceneError> {
        let mut out = Vec::new();
        for p in &self.props {
            if let Some(o) = resolve(p, ids)? {
                if o.tag == tag {
                    p.used.set(true);
                    out.push((o, p));
                }
            }
        }
        Ok(out)
    }

    /// Errors for the first property this plugin did not read (Mitsuba's "unreferenced property").
    pub fn check_unused(&self) -> Result<(), SceneError> {
        if let Some(p) = self.props.iter().find(|p| !p.used.get()) {
            let what = match &p.value {
                Value::Object(o) => format!("unreferenced object <{} type=\"{}\">", o.tag, o.ty),
                Value::Ref(id) => format!("unreferenced object <ref id=\"{id}\">"),
                _ => format!("unreferenced property \"{}\"", p.name),
            };
            return Err(SceneError::at(
                p.loc.clone(),
                format!(
                    "{what} in {} (not a parameter of this plugin, or not used by it)",
                    self.describe()
                ),
            ));
        }
        Ok(())
    }

    /// An error about this plugin, at its declaration.
    pub fn error(&self, message: impl std::fmt::Display) -> SceneError {
        SceneError::at(self.loc.clone(), format!("{}: {message}", self.describe()))
    }

    /// Errors unless `self.ty` is one of `known`: Mitsuba's "plugin not found".
    pub fn expect_type(&self, known: &[&str]) -> Result<(), SceneError> {
        if known.contains(&self.ty.as_str()) {
            return Ok(());
        }
        Err(SceneError::at(
            self.loc.clone(),
            format!(
                "{} plugin \"{}\" not found (known {} plugins: {})",
                self.tag,
                self.ty,
                self.tag,
                known.join(", ")
            ),
        ))
    }
}

/// Resolves an object or reference property; `Ok(None)` for plain values.
pub(crate) fn resolve(p: &Prop, ids: &Ids) -> Result<Option<Rc<Plugin>>, SceneError> {
    match &p.value {
        Value::Object(o) => Ok(Some(o.clone())),
        Value::Ref(id) => match ids.get(id) {
            Some(o) => Ok(Some(o.clone())),
            None => {
                let mut known: Vec<&str> = ids.keys().map(String::as_str).collect();
                known.sort_unstable();
                let hint = if known.is_empty() {
                    "no ids are defined".to_string()
                } else if known.len() > 12 {
                    format!(
                        "known ids include: {}, ...",
                        quoted_list(&known[..12]).replace(" or ", ", ")
                    )
                } else {
                    format!("known ids: {}", quoted_list(&known))
                };
                Err(SceneError::at(
                    p.loc.clone(),
                    format!("reference to unknown id \"{id}\" ({hint})"),
                ))
            }
        },
        _ => Ok(None),
    }
}
