//! A bare Wavefront OBJ + MTL as a whole scene (`ircache render model.obj`): materials from the
//! MTL (`Kd`/`map_Kd`, `Ks`/`Ns`, `Ke` as an area light), a camera from the command line or an
//! automatic framing of the model's bounds.
//!
//! What the loader decides, since an OBJ file says nothing about it:
//! - **Shapes**: one [`ShapeDesc`] per `usemtl` run ([`ObjGroup`]), with the material's name as id.
//! - **Materials** are two-sided ([`BsdfDesc::TwoSided`]), as OBJ models have no consistent
//!   orientation: [`BsdfDesc::Diffuse`] when `Ks` is absent or black, else [`BsdfDesc::ObjPhong`]
//!   with `Ks` and `Ns` (1 when absent). The diffuse albedo is `Kd` (0.5, Mitsuba's default, when
//!   absent); `map_Kd` is read with [`ircache_image::read_texture`] (sRGB to linear) and multiplied
//!   by `Kd` when `Kd` is written, as the MTL format defines (and as the shared `sponza-sun` scene's
//!   flat albedos are computed). Faces before any `usemtl` get a two-sided diffuse 0.5. `d`/`Tr`,
//!   `illum`, `Ni` and bump maps are read but not used.
//! - **Lights**: a material with a positive `Ke` makes its shapes one-sided area emitters of
//!   radiance `Ke` (emitting on the side their winding's normal points to). A model without any
//!   emitter gets a [`EmitterDesc::Constant`] environment of radiance 1, so that it is visible.
//! - **Camera**: `eye`, `target`, `up` (+y) and the vertical `fov` (45°) of [`ObjCamera`] where
//!   given. Otherwise the camera looks at the centre of the model's bounding box from along +z, at
//!   the distance where the bounding sphere fits both the vertical and horizontal fields of view.
//!   (McGuire's Cornell box is open towards +z, so this looks into the box.)
//! - **Film, sampler, integrator**: 640 × 480 (or `width`/`height`), box filter, 16 samples per
//!   pixel with the `independent` sampler, and Mitsuba's `path` defaults (`max_depth` −1,
//!   `rr_depth` 5).
//! - **Errors**: a `mtllib` file that cannot be read is an error at the `mtllib` line; a `usemtl`
//!   naming a material no `mtllib` defines is an error at the `usemtl` line; an unreadable `map_Kd`
//!   image is an error at the `map_Kd` line of the MTL file; a file without any face is an error.

#![deny(missing_docs)]

use crate::desc::{
    BitmapDesc, BsdfDesc, EmitterDesc, FovAxis, Geometry, IntegratorDesc, SensorDesc, ShapeDesc,
    TextureDesc, TextureFilter, WrapMode,
};
use crate::error::SourceLocation;
use crate::mesh::{read_obj, MtlMaterial, ObjGroup};
use crate::{SceneDesc, SceneError};
use ircache_image::{Image, ImageError};
use ircache_math::{Mat3, Mat4, Rgb, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Camera settings for an OBJ scene; anything left `None` is chosen automatically.
#[derive(Clone, Debug, Default)]
pub struct ObjCamera {
    /// Eye position.
    pub eye: Option<Vec3>,
    /// Point looked at.
    pub target: Option<Vec3>,
    /// Up vector (default +y).
    pub up: Option<Vec3>,
    /// Vertical field of view in degrees (default 45).
    pub fov: Option<f32>,
    /// Image width (default 640).
    pub width: Option<u32>,
    /// Image height (default 480).
    pub height: Option<u32>,
    /// Radiance view options (`-vp … -vd … -vh …`) or a view file, for Radiance scenes.
    pub radiance_view: Option<String>,
}

/// Default diffuse albedo (Mitsuba's `diffuse` default).
const DEFAULT_ALBEDO: f32 = 0.5;
/// Default samples per pixel.
const DEFAULT_SPP: u32 = 16;
/// Default vertical field of view in degrees.
const DEFAULT_FOV: f32 = 45.0;

/// Loads an OBJ file as a scene; see the [module documentation](self) for the choices made.
pub fn load(path: &Path, camera: &ObjCamera) -> Result<SceneDesc, SceneError> {
    let data = read_obj(path)?;
    let dir = path.parent().unwrap_or(Path::new(""));

    // Materials of every mtllib, later definitions replacing earlier ones of the same name.
    let mut materials: HashMap<String, MtlMaterial> = HashMap::new();
    let mut mtl_names = Vec::new();
    for (lib, location) in &data.mtllibs {
        let lib_path = resolve(dir, lib);
        let bytes = std::fs::read(&lib_path).map_err(|e| SceneError::Referenced {
            location: location.clone(),
            path: lib_path.clone(),
            message: e.to_string(),
        })?;
        let text = String::from_utf8_lossy(&bytes);
        for m in crate::mesh::parse_mtl(&text, Arc::new(lib_path.clone()))? {
            materials.insert(m.name.clone(), m);
        }
        mtl_names.push(lib.display().to_string());
    }

    let mut bsdfs: HashMap<Option<String>, (Arc<BsdfDesc>, Option<Rgb>)> = HashMap::new();
    let mut textures: HashMap<PathBuf, Arc<Image>> = HashMap::new();
    let mut shapes = Vec::with_capacity(data.groups.len());
    for group in &data.groups {
        if !bsdfs.contains_key(&group.material) {
            let entry = match &group.material {
                None => (
                    two_sided(diffuse(TextureDesc::Constant(Rgb::splat(DEFAULT_ALBEDO)))),
                    None,
                ),
                Some(name) => {
                    let Some(m) = materials.get(name) else {
                        let known = if mtl_names.is_empty() {
                            "the file has no 'mtllib'".to_string()
                        } else {
                            format!("not defined in {}", mtl_names.join(", "))
                        };
                        return Err(SceneError::at(
                            group.location.clone(),
                            format!("unknown material '{name}' ({known})"),
                        ));
                    };
                    material(m, &mut textures)?
                }
            };
            bsdfs.insert(group.material.clone(), entry);
        }
        let (bsdf, emitter) = bsdfs[&group.material].clone();
        shapes.push(shape(group, bsdf, emitter));
    }
    if shapes.is_empty() {
        return Err(SceneError::at(
            SourceLocation::start_of(path),
            "the OBJ file has no faces",
        ));
    }

    let mut emitters = Vec::new();
    if shapes.iter().all(|s| s.emitter.is_none()) {
        emitters.push(EmitterDesc::Constant { radiance: Rgb::ONE });
    }
    let sensor = sensor(&shapes, camera);
    Ok(SceneDesc {
        media: Vec::new(),
        source: path.to_path_buf(),
        sensor,
        integrator: IntegratorDesc::default(),
        shapes,
        emitters,
        notes: crate::mesh::obj::degenerate_note(&data)
            .into_iter()
            .collect(),
    })
}

/// A path relative to `dir` unless absolute; Windows separators are accepted when the path as
/// written does not exist.
fn resolve(dir: &Path, p: &Path) -> PathBuf {
    let direct = dir.join(p);
    if direct.exists() {
        return direct;
    }
    let s = p.to_string_lossy();
    if s.contains('\\') {
        let alt = dir.join(s.replace('\\', "/"));
        if alt.exists() {
            return alt;
        }
    }
    direct
}

fn diffuse(reflectance: TextureDesc) -> BsdfDesc {
    BsdfDesc::Diffuse { reflectance }
}

fn two_sided(front: BsdfDesc) -> Arc<BsdfDesc> {
    Arc::new(BsdfDesc::TwoSided {
        front: Arc::new(front),
        back: None,
    })
}

/// Reads an MTL texture (once per file and decoding: `raw` skips the sRGB decoding).
fn load_texture(
    tex: &crate::mesh::mtl::MtlTexture,
    raw: bool,
    textures: &mut HashMap<PathBuf, Arc<Image>>,
) -> Result<(PathBuf, Arc<Image>), SceneError> {
    let dir = tex
        .location
        .file
        .parent()
        .unwrap_or(Path::new(""))
        .to_path_buf();
    let tex_path = resolve(&dir, &tex.path);
    // Raw and decoded reads of one file are different images.
    let key = if raw {
        tex_path.with_extension(format!(
            "{}#raw",
            tex_path.extension().and_then(|e| e.to_str()).unwrap_or("")
        ))
    } else {
        tex_path.clone()
    };
    if let Some(img) = textures.get(&key) {
        return Ok((tex_path, img.clone()));
    }
    let img = ircache_image::read_texture(&tex_path, raw).map_err(|e| SceneError::Referenced {
        location: tex.location.clone(),
        path: tex_path.clone(),
        message: match e {
            ImageError::Read { message, .. } => message,
            other => other.to_string(),
        },
    })?;
    let img = Arc::new(img);
    textures.insert(key, img.clone());
    Ok((tex_path, img))
}

/// The BSDF and emitted radiance of an MTL material.
fn material(
    m: &MtlMaterial,
    textures: &mut HashMap<PathBuf, Arc<Image>>,
) -> Result<(Arc<BsdfDesc>, Option<Rgb>), SceneError> {
    let albedo = match &m.map_kd {
        Some(tex) => {
            let (tex_path, image) = load_texture(tex, false, textures)?;
            let image = match m.diffuse {
                Some(kd) if kd != Rgb::ONE => {
                    let mut scaled = (*image).clone();
                    for p in &mut scaled.pixels {
                        *p = Rgb::new(p.r * kd.r, p.g * kd.g, p.b * kd.b);
                    }
                    Arc::new(scaled)
                }
                _ => image,
            };
            TextureDesc::Bitmap(Arc::new(BitmapDesc {
                path: tex_path,
                image,
                filter: TextureFilter::Bilinear,
                wrap: WrapMode::Repeat,
                to_uv: Mat3::IDENTITY,
            }))
        }
        None => TextureDesc::Constant(m.diffuse.unwrap_or(Rgb::splat(DEFAULT_ALBEDO))),
    };
    let front = match m.specular {
        Some(ks) if !ks.is_black() => BsdfDesc::ObjPhong {
            diffuse: albedo,
            specular: ks,
            exponent: m.shininess.unwrap_or(1.0),
        },
        _ => diffuse(albedo),
    };
    let emission = m.emission.filter(|e| e.max_channel() > 0.0);
    let mut bsdf = two_sided(front);
    if let Some(tex) = &m.map_bump {
        // `bump`/`map_bump`: heights (luminance, raw) times -bm, as Mitsuba's bumpmap.
        let (tex_path, image) = load_texture(tex, true, textures)?;
        bsdf = Arc::new(BsdfDesc::BumpMap {
            height: Arc::new(BitmapDesc {
                path: tex_path,
                image,
                filter: TextureFilter::Bilinear,
                wrap: WrapMode::Repeat,
                to_uv: Mat3::IDENTITY,
            }),
            scale: tex.bump_multiplier.unwrap_or(1.0),
            nested: bsdf,
            // As a Mitsuba bumpmap at its defaults.
            shading: crate::desc::PerturbedShading::default(),
        });
    }
    Ok((bsdf, emission))
}

fn shape(group: &ObjGroup, bsdf: Arc<BsdfDesc>, emitter: Option<Rgb>) -> ShapeDesc {
    ShapeDesc {
        media: Default::default(),
        id: group.material.clone(),
        geometry: Geometry::Mesh(group.mesh.clone()),
        bsdf,
        emitter,
        emitter_texture: None,
        emitter_pattern: None,
        location: group.location.clone(),
    }
}

/// Mitsuba's `look_at`: camera +z along the view direction, +y up, +x to the left.
fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> Mat4 {
    let dir = (target - eye).try_normalize().unwrap_or(Vec3::NEG_Z);
    let left = up
        .cross(dir)
        .try_normalize()
        .or_else(|| Vec3::Z.cross(dir).try_normalize())
        .or_else(|| Vec3::X.cross(dir).try_normalize())
        .unwrap_or(Vec3::X);
    let new_up = dir.cross(left);
    Mat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        eye.extend(1.0),
    )
}

fn sensor(shapes: &[ShapeDesc], camera: &ObjCamera) -> SensorDesc {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for s in shapes {
        if let Geometry::Mesh(m) = &s.geometry {
            for t in &m.indices {
                for &i in t {
                    let p = m.positions[i as usize];
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
            }
        }
    }
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    let width = camera.width.unwrap_or(640).max(1);
    let height = camera.height.unwrap_or(480).max(1);
    let fov = camera.fov.unwrap_or(DEFAULT_FOV).clamp(1e-3, 179.0);
    let half_v = (fov * 0.5).to_radians();
    let half_h = (half_v.tan() * width as f32 / height as f32).atan();
    let fit = radius / half_v.min(half_h).sin();
    let up = camera.up.unwrap_or(Vec3::Y);
    let (eye, target) = match (camera.eye, camera.target) {
        (Some(e), Some(t)) => (e, t),
        (Some(e), None) => (e, centre),
        (None, Some(t)) => (t + Vec3::Z * ((centre - t).length() + fit), t),
        (None, None) => (centre + Vec3::Z * fit, centre),
    };
    let distance = (eye - centre).length() + radius;
    SensorDesc::standard(
        look_at(eye, target, up),
        (fov, FovAxis::Y),
        crate::desc::Projection::Pinhole,
        (width, height),
        DEFAULT_SPP,
        distance,
        1e-3,
    )
}
