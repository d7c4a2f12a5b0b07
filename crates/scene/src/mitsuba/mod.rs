//! Mitsuba 3 XML scenes: the subset of the format this renderer supports, read with Mitsuba 3's
//! conventions and defaults so that the same file renders the same here and in Mitsuba.
//!
//! Stages: `xml` reads files into an element tree (`$name` substitution, `<default>`,
//! `<include>`, old-version upgrade); `props` turns elements into plugins with typed, located
//! properties; the builders (`sensor`, `bsdf`, `shape`, `emitter`) read those properties
//! into the [`SceneDesc`], and every property a builder did not read is an error, as Mitsuba's
//! "unreferenced property". Every error names file:line:column.
//!
//! Supported plugins: sensors `perspective`, `thinlens`, `orthographic`; film `hdrfilm`;
//! rfilters `box`, `tent`, `gaussian`, `mitchell`, `catmullrom`, `lanczos`; samplers `independent`, `stratified`, `multijitter`,
//! `ldsampler`, `orthogonal`; integrators `path`, `volpath`, `direct`, `irrcache`, and
//! `volpathmis`, `prb`, `prbvolpath` read as the one that renders the same image; shapes `obj`,
//! `ply`, `serialized`, `rectangle`, `cube`, `disk` and `cylinder` (tessellated), `sphere`,
//! `shapegroup` and `instance` (flattened); BSDFs `diffuse`, `twosided`, `blendbsdf`, `plastic`,
//! `roughplastic`, `conductor`, `roughconductor`, `dielectric`, `roughdielectric`,
//! `thindielectric`, `principled`, `bumpmap`, `normalmap`, `mask`, `null`; textures `bitmap`,
//! `checkerboard`; emitters `area`, `point`, `spot`, `directional`, `constant`, `envmap`; media
//! `homogeneous`, `heterogeneous` with volumes `constvolume`, `gridvolume` and phase functions
//! `isotropic`, `hg`.

mod bsdf;
mod cie;
mod emitter;
mod medium;
mod props;
mod sensor;
mod shape;
pub mod transform;
mod xml;

use crate::desc::{BsdfDesc, IntegratorDesc, SceneDesc};
use crate::error::{SceneError, SourceLocation};
use ircache_image::Image;
use props::{Ids, Plugin, Prop};
use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Loads a Mitsuba 3 XML scene; `defines` are `-D name=value` overrides of `<default>`s.
///
/// # Errors
/// Any problem with the file or the files it references, located at file:line:column where it
/// concerns a place in a file.
pub fn load(path: &Path, defines: &[(String, String)]) -> Result<SceneDesc, SceneError> {
    let root = xml::read_scene(path, defines)?;
    let (scene, ids) = props::build_tree(&root)?;
    let gamut_notes = props::out_of_gamut_notes(&scene, &ids);
    let ctx = Ctx::new(ids, path);
    ctx.notes.borrow_mut().extend(gamut_notes);
    let mut sensor = None;
    let mut integrator: Option<IntegratorDesc> = None;
    let mut shapes = Vec::new();
    let mut emitters = Vec::new();
    for prop in &scene.props {
        let Some(obj) = props::resolve(prop, &ctx.ids)? else {
            return Err(SceneError::at(
                prop.loc.clone(),
                format!(
                    "unreferenced property \"{}\" in the scene (properties belong inside a plugin)",
                    prop.name
                ),
            ));
        };
        if matches!(prop.value, props::Value::Ref(_)) {
            return Err(SceneError::at(
                prop.loc.clone(),
                "a <ref> directly inside <scene> is not supported",
            ));
        }
        match obj.tag.as_str() {
            "sensor" => {
                if sensor.is_some() {
                    return Err(SceneError::at(
                        obj.loc.clone(),
                        "more than one <sensor>: only one is supported",
                    ));
                }
                sensor = Some(sensor::build_sensor(&ctx, &obj)?);
            }
            "integrator" => {
                if integrator.is_some() {
                    return Err(SceneError::at(
                        obj.loc.clone(),
                        "more than one <integrator>",
                    ));
                }
                let built = sensor::build_integrator(&obj)?;
                if built.unusable.is_none() && built.kind != obj.ty {
                    ctx.notes.borrow_mut().push(format!(
                        "{}: Mitsuba's \"{}\" integrator renders the same image as \"{}\", which \
                         renders it here",
                        obj.loc, obj.ty, built.kind
                    ));
                }
                integrator = Some(built);
            }
            "shape" => match obj.ty.as_str() {
                // A group is drawn only through its instances.
                "shapegroup" => {
                    shape::build_group(&ctx, &obj)?;
                }
                "instance" => shapes.extend(shape::build_instance(&ctx, &obj)?),
                _ => shapes.push(shape::build_shape(&ctx, &obj)?),
            },
            "emitter" => emitters.push(emitter::build_emitter(&ctx, &obj)?),
            "bsdf" => {
                bsdf::build_bsdf(&ctx, &obj)?;
            }
            "texture" => {
                bsdf::build_any_texture(&ctx, &obj)?;
            }
            "medium" => {
                medium::build_medium(&ctx, &obj)?;
            }
            "volume" => {
                medium::build_volume(&ctx, &obj)?;
            }
            other => {
                return Err(SceneError::at(
                    obj.loc.clone(),
                    format!(
                    "<{other}> cannot appear directly in <scene> (it belongs inside a <sensor>)"
                ),
                ))
            }
        }
    }
    let Some(sensor) = sensor else {
        return Err(SceneError::at(
            scene.loc.clone(),
            "scene has no <sensor> (add <sensor type=\"perspective\">; Mitsuba's implicit default camera is not supported)",
        ));
    };
    if shapes.is_empty() {
        return Err(SceneError::at(scene.loc.clone(), "scene has no shapes"));
    }
    Ok(SceneDesc {
        source: path.to_path_buf(),
        sensor,
        integrator: integrator.unwrap_or_default(),
        shapes,
        emitters,
        media: ctx.media.take(),
        notes: ctx.notes.take(),
    })
}

/// State shared by the builders.
pub(crate) struct Ctx {
    /// Plugins by id.
    pub ids: Ids,
    /// The main scene file's folder (fallback for relative file names).
    pub scene_dir: PathBuf,
    /// What the builders changed and a user should hear of ([`SceneDesc::notes`]).
    pub notes: RefCell<Vec<String>>,
    /// Built BSDFs by plugin, so `<ref>`s share one `Arc`.
    pub bsdfs: RefCell<HashMap<*const Plugin, Arc<BsdfDesc>>>,
    /// Built shape groups by plugin, so their instances read each mesh once.
    pub groups: RefCell<HashMap<*const Plugin, std::rc::Rc<Vec<crate::desc::ShapeDesc>>>>,
    /// Built bitmap textures by plugin.
    pub bitmaps: RefCell<HashMap<*const Plugin, Arc<crate::desc::BitmapDesc>>>,
    /// Images by (path, raw), shared between textures and environment maps.
    pub images: RefCell<HashMap<(PathBuf, bool), Arc<Image>>>,
    /// The default BSDF (diffuse 0.5) shared by shapes without one.
    pub default_bsdf: Arc<BsdfDesc>,
    /// Media built so far ([`SceneDesc::media`]).
    pub media: RefCell<Vec<crate::desc::MediumDesc>>,
    /// Built media by plugin, so `<ref>`s share one.
    pub medium_ids: RefCell<HashMap<*const Plugin, usize>>,
}

impl Ctx {
    fn new(ids: Ids, path: &Path) -> Ctx {
        Ctx {
            ids,
            scene_dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
            notes: RefCell::default(),
            bsdfs: RefCell::default(),
            groups: RefCell::default(),
            bitmaps: RefCell::default(),
            images: RefCell::default(),
            media: RefCell::default(),
            medium_ids: RefCell::default(),
            default_bsdf: Arc::new(BsdfDesc::Diffuse {
                reflectance: crate::desc::TextureDesc::Constant(ircache_math::Rgb::splat(0.5)),
            }),
        }
    }

    /// Resolves a file name written at `prop`: relative to the file it was written in, then to
    /// the main scene's folder (as Mitsuba's file resolver, which searches the scene folder).
    /// Errors (at the property) when the file does not exist.
    pub fn resolve_file(&self, name: &str, prop: &Prop) -> Result<PathBuf, SceneError> {
        let p = Path::new(name);
        if name.is_empty() {
            return Err(SceneError::at(prop.loc.clone(), "empty file name"));
        }
        let candidates: Vec<PathBuf> = if p.is_absolute() {
            vec![p.to_path_buf()]
        } else {
            let here = prop.loc.file.parent().unwrap_or(Path::new("")).join(p);
            vec![here, self.scene_dir.join(p)]
        };
        for c in &candidates {
            if c.is_file() {
                return Ok(c.clone());
            }
        }
        Err(SceneError::Referenced {
            location: prop.loc.clone(),
            path: candidates[0].clone(),
            message: "file not found".into(),
        })
    }

    /// Reads an image (cached), mapping failures to an error at `loc`.
    pub fn image(
        &self,
        path: &Path,
        raw: bool,
        loc: &SourceLocation,
    ) -> Result<Arc<Image>, SceneError> {
        let key = (path.to_path_buf(), raw);
        if let Some(img) = self.images.borrow().get(&key) {
            return Ok(img.clone());
        }
        let img = ircache_image::read_texture(path, raw).map_err(|e| SceneError::Referenced {
            location: loc.clone(),
            path: path.to_path_buf(),
            message: match e {
                ircache_image::ImageError::Read { message, .. }
                | ircache_image::ImageError::Write { message, .. } => message,
            },
        })?;
        if img.width == 0 || img.height == 0 || img.pixels.len() != img.width * img.height {
            return Err(SceneError::Referenced {
                location: loc.clone(),
                path: path.to_path_buf(),
                message: format!("image has an invalid size {}×{}", img.width, img.height),
            });
        }
        let img = Arc::new(img);
        self.images.borrow_mut().insert(key, img.clone());
        Ok(img)
    }
}

/// Checks a radiometric quantity (radiance, irradiance, intensity): finite and non-negative.
pub(crate) fn check_emission(
    value: ircache_math::Rgb,
    what: &str,
    loc: &SourceLocation,
) -> Result<(), SceneError> {
    let a = value.to_array();
    if a.iter().any(|v| v.is_nan()) {
        return Err(SceneError::at(
            loc.clone(),
            format!("{what} ({}, {}, {}) is NaN", a[0], a[1], a[2]),
        ));
    }
    if a.iter().any(|v| !v.is_finite() || *v < 0.0) {
        return Err(SceneError::at(
            loc.clone(),
            format!(
                "{what} ({}, {}, {}) must be finite and non-negative",
                a[0], a[1], a[2]
            ),
        ));
    }
    Ok(())
}

/// Errors when a plugin holds an object that is not of the expected tag: a `<ref>` of the
/// wrong kind.
pub(crate) fn expect_tag(obj: &Plugin, prop: &Prop, tag: &str) -> Result<(), SceneError> {
    if obj.tag == tag {
        return Ok(());
    }
    let via = match &prop.value {
        props::Value::Ref(id) => format!("reference \"{id}\" names a <{}>", obj.tag),
        _ => format!("found a <{}>", obj.tag),
    };
    Err(SceneError::at(
        prop.loc.clone(),
        format!(
            "expected a <{tag}> here, but the {via} (declared at {})",
            obj.loc
        ),
    ))
}
