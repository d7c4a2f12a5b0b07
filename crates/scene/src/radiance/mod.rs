//! Radiance scene files (`ircache render scene.rad`): the primitives lighting designers write
//! and `oconv` reads (Ward's `ray(1)` reference manual), turned into a [`SceneDesc`].
//!
//! - **Surfaces**: `polygon` (triangulated by ear clipping; the front is where its vertices turn
//!   counter-clockwise), `sphere` and `bubble` (analytic), `cylinder`, `tube`, `cone`, `cup` and
//!   `ring` (tessellated into 64 segments whose polygons keep the exact areas), `instance`
//!   (an octree's surfaces placed by its transform, [`octree`]), `mesh` (an `obj2mesh` file's
//!   triangles with their normals, (u, v) and materials, [`mesh`]).
//! - **Octrees**: `ircache render scene.oct` reads the scene an octree holds (frozen by
//!   `oconv -f`) or the scene files it names ([`octree`]).
//! - **Materials**: `plastic`, `metal` and `trans` as Radiance's isotropic Gaussian model
//!   ([`BsdfDesc::Ward`]; a smooth `trans`'s straight transmission passes the light samples of
//!   distant, point and spot lights, as Radiance's shadow rays), `mirror` (a perfect mirror of its colour), `glass` (Radiance's thin pane,
//!   [`BsdfDesc::Glass`]), `dielectric` and `interface` without absorption (a smooth
//!   interface of their indices, a dielectric's at 500 nm by its Hartmann constant),
//!   `BRTDfunc` without non-specular BRTD functions ([`BsdfDesc::RadianceBrtd`]: coated
//!   glazings), `plastic2`, `metal2` and `trans2` (`aniso.c`'s anisotropic Gaussian, its orientation vector a
//!   constant, [`crate::desc::Anisotropy`]), `BSDF` of zero thickness with the Klems matrices of an XML file ([`bsdf_xml`],
//!   [`BsdfDesc::Klems`]; tensor trees, proxies of non-zero thickness and `aBSDF` are refused).
//!   Radiance shades both sides of a surface alike, so the opaque ones are `twosided`.
//! - **Light**: `light` and `glow` surfaces emit their radiance (W sr⁻¹ m⁻², as ircache's RGB) from
//!   their front and reflect nothing; a glow's maximum radius only steers Radiance's choice of
//!   sources, which a path tracer does not need. `spotlight` emits within its cone, with the
//!   focus its orientation vector's length sets ([`pattern::Spot`]). `illum` is a secondary source standing for the
//!   light behind it: here it is its alternate material, or nothing where that is `void`, so the
//!   light it stood for is traced. A distant `source` of material `light` narrower than 10° is a
//!   directional light of the same irradiance (L·Ω, Ω its solid angle; sharp shadows); wider ones
//!   and `glow` sources (skies, grounds) are baked into a latitude–longitude environment,
//!   including gensky's `skyfunc` (`brightfunc skybr skybright.cal`, evaluated natively).
//! - **Patterns**: `brightfunc`, `colorfunc`, `brightdata`, `colordata` and `colorpict`
//!   ([`pattern`]), with their function files in Radiance's language ([`cal`]), data files and
//!   pictures ([`data`]), on the radiance of `light`, `glow` and `spotlight` (the luminaires
//!   `ies2rad` makes render as their candela tables say), on the colour of `plastic`, `metal`
//!   and `trans` (evaluated at each hit) and on what `glass` transmits; `mixfunc`, `mixdata`
//!   and `mixpict` blend two such materials by their coefficient at each hit. Textures
//!   (`texfunc`, `texdata`) displace the normals of `plastic`, `metal`, `trans`, `plastic2` and
//!   `metal2` as Radiance's `raynormal` does ([`pattern::Pattern::Texture`]); `noise3`, its
//!   derivatives and `fnoise3` are the function language's ([`cal::noise`]).
//! - **Commands**: `!xform` is carried out here, other commands are run (see [`parse`]).
//! - **Integrator**: the irradiance cache (`irrcache`), as rpict computes, with unbounded bounces
//!   unless `-ab` or `--max-depth` bounds them.
//! - **Camera**: a Radiance view ([`view`]: perspective, parallel, fisheye or panoramic) given
//!   with the scene (`--view`), else `eye`, `target` and `fov` as for OBJ scenes, else the whole
//!   scene framed from Radiance's default direction (+y, up +z). The picture fits 512 × 512 (or
//!   `width` × `height`) with square pixels, as rpict.
//! - Everything else (textures on other materials, `mixtext`,
//!   `aBSDF`, `antimatter`, `prism1`, `mist`, ...) is an error at the first surface that needs it,
//!   naming the primitive. Nothing is skipped without a note: surfaces of `void` are dropped
//!   with a count in the scene's notes.

pub mod bsdf_xml;
pub mod cal;
pub mod data;
pub mod mesh;
pub mod octree;
pub mod parse;
pub mod pattern;
pub mod sky;
pub mod view;
pub mod xform;

use crate::desc::{
    BsdfDesc, EmitterDesc, FovAxis, Geometry, IntegratorDesc, PanoramicMapping, Projection,
    SensorDesc, ShapeDesc, SurfacePattern, TextureDesc, TriangleMesh,
};
use crate::error::SourceLocation;
use crate::obj_scene::ObjCamera;
use crate::{SceneDesc, SceneError};
use ircache_math::{DVec3, Mat3, Mat4, Rgb, Vec3};
use parse::Primitive;
use pattern::{FunctionPattern, Pattern, PatternChain, PatternFiles, Spot};
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;
use view::{View, ViewType};

/// Segments of a tessellated cylinder, cone or ring.
const SEGMENTS: u32 = 64;
/// A `light` source narrower than this (full angle, degrees) becomes a directional light.
const DIRECTIONAL_MAX_ANGLE: f64 = 10.0;
/// Width of the baked environment (height half of it).
const ENVIRONMENT_WIDTH: usize = 1024;
/// rpict's default picture size.
const DEFAULT_SIZE: u32 = 512;
/// Default samples per pixel.
const DEFAULT_SPP: u32 = 16;

/// True for the types that are modifiers (materials, patterns, textures, mixtures, `alias`):
/// `!xform -n` and `-m` leave them alone.
#[must_use]
pub fn is_modifier_type(kind: &str) -> bool {
    !matches!(
        kind,
        "polygon"
            | "sphere"
            | "bubble"
            | "cone"
            | "cup"
            | "cylinder"
            | "tube"
            | "ring"
            | "source"
            | "mesh"
            | "instance"
    )
}

/// What a modifier is, once read.
#[derive(Clone, Debug)]
enum Modifier {
    /// A reflecting or transmitting material.
    Bsdf(Arc<BsdfDesc>),
    /// `light`, `glow` or `spotlight` (the kind kept for sources), with the patterns on its
    /// radiance and a spotlight's cone.
    Light {
        radiance: Rgb,
        kind: &'static str,
        pattern: PatternChain,
    },
    /// `illum`: its alternate material (`None` for void).
    Illum(Option<String>),
    /// A pattern (gensky's `skyfunc`, a function or data pattern) with the patterns modifying
    /// it, outermost first.
    Pattern(Vec<Pattern>),
    /// A type ircache does not render; an error where a surface uses it.
    Unsupported(String),
}

/// Loads a Radiance scene; see the [module documentation](self).
pub fn load(path: &Path, camera: &ObjCamera) -> Result<SceneDesc, SceneError> {
    let primitives = parse::read(path)?;
    let mut files = PatternFiles::new(path.parent().unwrap_or(Path::new(".")));
    let mut modifiers: HashMap<String, (Modifier, SourceLocation)> = HashMap::new();
    let mut shapes = Vec::new();
    let mut sources = Vec::new();
    let mut notes = Vec::new();
    let mut void_surfaces = 0usize;
    let mut illum_surfaces = 0usize;
    for p in &primitives {
        if is_modifier_type(&p.kind) {
            let m = modifier(p, &modifiers, &mut files)?;
            modifiers.insert(p.id.clone(), (m, p.location.clone()));
            continue;
        }
        if p.kind == "mesh" {
            for (q, geometry) in mesh_surfaces(p, &mut modifiers, &mut files, &mut notes)? {
                let Some(material) = surface_material(&q, &modifiers, &mut illum_surfaces)? else {
                    void_surfaces += 1;
                    continue;
                };
                push_surface(&q, material, geometry, &mut shapes, &mut notes)?;
            }
            continue;
        }
        let Some(material) = surface_material(p, &modifiers, &mut illum_surfaces)? else {
            void_surfaces += 1;
            continue;
        };
        if p.kind == "source" {
            sources.push(source(p, material)?);
            continue;
        }
        let Some(geometry) = geometry(p)? else {
            notes.push(format!(
                "{}: {} '{}' has no area and was dropped",
                p.location, p.kind, p.id
            ));
            continue;
        };
        push_surface(p, material, geometry, &mut shapes, &mut notes)?;
    }
    if void_surfaces > 0 {
        notes.push(format!(
            "{void_surfaces} surface(s) with the modifier 'void' are invisible in Radiance and \
             were left out"
        ));
    }
    if illum_surfaces > 0 {
        notes.push(format!(
            "{illum_surfaces} 'illum' surface(s) render as their alternate material (or not at \
             all, for void): the light they stand for is traced instead"
        ));
    }
    let emitters = environment(&sources, &mut notes);
    if shapes.is_empty() {
        return Err(SceneError::at(
            SourceLocation::start_of(path),
            "the scene has no surfaces ircache can render",
        ));
    }
    let sensor = sensor(&shapes, camera, path)?;
    Ok(SceneDesc {
        source: path.to_path_buf(),
        sensor,
        // rpict's way: the irradiance cache, its bounces unbounded unless -ab or --max-depth
        // says otherwise.
        integrator: IntegratorDesc {
            kind: "irrcache".into(),
            ..IntegratorDesc::default()
        },
        shapes,
        emitters,
        media: Vec::new(),
        notes,
    })
}

/// The patterns a Radiance material carries (on its colour, a mixture's weight).
fn bsdf_patterns(b: &BsdfDesc) -> Vec<Arc<dyn SurfacePattern>> {
    match b {
        BsdfDesc::TwoSided { front, .. } => bsdf_patterns(front),
        BsdfDesc::Ward { pattern, .. } | BsdfDesc::Glass { pattern, .. } => {
            pattern.iter().cloned().collect()
        }
        BsdfDesc::Blend {
            pattern,
            first,
            second,
            ..
        } => pattern
            .iter()
            .cloned()
            .chain(bsdf_patterns(first))
            .chain(bsdf_patterns(second))
            .collect(),
        _ => Vec::new(),
    }
}

/// Adds the surface `p` of `material` and `geometry` to `shapes`.
fn push_surface(
    p: &Primitive,
    material: Modifier,
    geometry: Geometry,
    shapes: &mut Vec<ShapeDesc>,
    notes: &mut Vec<String>,
) -> Result<(), SceneError> {
    let (bsdf, emitter, pattern) = match material {
        Modifier::Bsdf(b) => (b, None, None),
        Modifier::Light {
            radiance, pattern, ..
        } => (
            black(),
            Some(radiance),
            Some(pattern).filter(|p| !p.is_empty()),
        ),
        _ => unreachable!("surface_material resolves the rest"),
    };
    let finite = match &geometry {
        Geometry::Mesh(m) => m.positions.iter().all(|v| v.is_finite()),
        Geometry::Sphere { center, radius, .. } => center.is_finite() && radius.is_finite(),
    };
    if !finite {
        return Err(SceneError::at(
            p.location.clone(),
            format!(
                "{} '{}': its coordinates, transformed, exceed single precision",
                p.kind, p.id
            ),
        ));
    }
    if let Some(pattern) = &pattern {
        probe(p, &geometry, pattern, notes)?;
    }
    // Lu and Lv exist on meshes with (u, v) only.
    let has_uv = matches!(&geometry, Geometry::Mesh(m) if m.uvs.is_some());
    let material_reads_uv = bsdf_patterns(&bsdf).iter().any(|p| p.reads_uv());
    if !has_uv && (material_reads_uv || pattern.as_ref().is_some_and(SurfacePattern::reads_uv)) {
        return Err(SceneError::at(
            p.location.clone(),
            format!(
                "{} '{}': its patterns read Lu or Lv, which only a mesh with (u, v) has",
                p.kind, p.id
            ),
        ));
    }
    shapes.push(ShapeDesc {
        id: Some(p.id.clone()),
        geometry,
        bsdf,
        emitter,
        emitter_texture: None,
        emitter_pattern: pattern.map(|p| Arc::new(p) as Arc<dyn SurfacePattern>),
        media: Default::default(),
        location: p.location.clone(),
    });
    Ok(())
}

/// A `mesh` (an `obj2mesh` file moved by the transform after its name): its own materials
/// registered under `mesh/name` (as an instance's), and one surface per material, each a
/// primitive of the mesh's location whose modifier is the instance's, or the mesh's own where
/// that is void. Degenerate triangles are dropped with a note.
fn mesh_surfaces(
    p: &Primitive,
    modifiers: &mut HashMap<String, (Modifier, SourceLocation)>,
    files: &mut PatternFiles,
    notes: &mut Vec<String>,
) -> Result<Vec<(Primitive, Geometry)>, SceneError> {
    let (path, transform) = parse::placed_file(p, "mesh")?;
    let m = mesh::read(&path, &transform).map_err(|e| e.referenced_from(&p.location))?;
    let materials = parse::localised(m.materials, p);
    for q in &materials {
        let modifier = modifier(q, modifiers, files)?;
        modifiers.insert(q.id.clone(), (modifier, q.location.clone()));
    }
    let mut out = Vec::new();
    for (material, mut triangles) in m.groups {
        let name = match (&*p.modifier, material) {
            ("void", Some(i)) => materials[i].id.clone(),
            ("void", None) => "void".to_string(),
            (given, _) => given.to_string(),
        };
        let before = triangles.indices.len();
        triangles.indices.retain(|t| {
            let [a, b, c] = t.map(|i| triangles.positions[i as usize]);
            (b - a).cross(c - a).length_squared() > 0.0
        });
        let dropped = before - triangles.indices.len();
        let mut q = p.clone();
        q.modifier = name;
        q.id = format!("{}#{}", p.id, q.modifier);
        if dropped > 0 {
            notes.push(format!(
                "{}: mesh '{}': {dropped} triangle(s) of '{}' have no area and were dropped",
                p.location, p.id, q.modifier
            ));
        }
        if !triangles.indices.is_empty() {
            out.push((q, Geometry::Mesh(triangles)));
        }
    }
    Ok(out)
}

fn black() -> Arc<BsdfDesc> {
    Arc::new(BsdfDesc::TwoSided {
        front: Arc::new(BsdfDesc::Diffuse {
            reflectance: TextureDesc::Constant(Rgb::ZERO),
        }),
        back: None,
    })
}

fn two_sided(b: BsdfDesc) -> Arc<BsdfDesc> {
    Arc::new(BsdfDesc::TwoSided {
        front: Arc::new(b),
        back: None,
    })
}

fn rgb(r: &[f64]) -> Rgb {
    Rgb::new(r[0] as f32, r[1] as f32, r[2] as f32)
}

/// Reads a modifier primitive.
fn modifier(
    p: &Primitive,
    known: &HashMap<String, (Modifier, SourceLocation)>,
    files: &mut PatternFiles,
) -> Result<Modifier, SceneError> {
    let err = |m: String| SceneError::at(p.location.clone(), format!("{} '{}': {m}", p.kind, p.id));
    let reals = |n: &[usize]| -> Result<(), SceneError> {
        if n.contains(&p.reals.len()) {
            Ok(())
        } else {
            Err(err(format!(
                "expected {} real arguments, found {}",
                n.iter()
                    .map(usize::to_string)
                    .collect::<Vec<_>>()
                    .join(" or "),
                p.reals.len()
            )))
        }
    };
    if p.kind == "alias" {
        let target = &p.strings[0];
        return known.get(target).map(|(m, _)| m.clone()).ok_or_else(|| {
            err(format!(
                "refers to '{target}', which is not defined before it"
            ))
        });
    }
    // A material's own modifier: the patterns on it.
    let chain = if p.modifier == "void" {
        Vec::new()
    } else {
        match known.get(&p.modifier) {
            None => return Err(err(format!("undefined modifier '{}'", p.modifier))),
            Some((Modifier::Pattern(chain), _)) => chain.clone(),
            Some((Modifier::Unsupported(what), at)) => {
                return Err(err(format!(
                    "its modifier '{}' ({what}, at {at}) is not supported",
                    p.modifier
                )))
            }
            Some(_) => {
                return Err(err(format!(
                    "its modifier '{}' is a material; only patterns and textures modify materials",
                    p.modifier
                )))
            }
        }
    };
    let patterned = FunctionPattern::is_function_pattern(&p.kind);
    if !chain.is_empty()
        && !patterned
        && !matches!(
            p.kind.as_str(),
            "glow"
                | "light"
                | "spotlight"
                | "plastic"
                | "metal"
                | "trans"
                | "glass"
                | "plastic2"
                | "metal2"
                | "trans2"
                | "mirror"
                | "texfunc"
                | "texdata"
        )
    {
        return Err(err(format!(
            "its modifier '{}' is a pattern; ircache reads patterns on plastic, metal, trans, \
             plastic2, metal2, trans2, mirror, glass, light, glow and spotlight materials (and on \
             other patterns), not on {}",
            p.modifier, p.kind
        )));
    }
    let textured = chain.iter().any(|l| matches!(l, Pattern::Texture(_)));
    if textured
        && !patterned
        && !matches!(
            p.kind.as_str(),
            "plastic"
                | "metal"
                | "trans"
                | "plastic2"
                | "metal2"
                | "trans2"
                | "light"
                | "glow"
                | "spotlight"
                | "texfunc"
                | "texdata"
        )
    {
        return Err(err(format!(
            "its modifiers include a texture (texfunc or texdata); ircache perturbs the normals \
             of plastic, metal, trans, plastic2, metal2 and trans2 with them, not of {}",
            p.kind
        )));
    }
    let pattern = PatternChain { chain, spot: None };
    let m = match p.kind.as_str() {
        "plastic" | "metal" | "trans" => {
            let trans = p.kind == "trans";
            reals(if trans { &[7] } else { &[5] })?;
            let r = &p.reals;
            if !(0.0..=1.0).contains(&r[3]) || r[4] < 0.0 {
                return Err(err(format!(
                    "specularity {} must be in [0, 1] and roughness {} at least 0",
                    r[3], r[4]
                )));
            }
            let (t, ts) = if trans { (r[5], r[6]) } else { (0.0, 0.0) };
            if !(0.0..=1.0).contains(&t) || !(0.0..=1.0).contains(&ts) {
                return Err(err(format!(
                    "transmissivity {t} and transmitted specular {ts} must be in [0, 1]"
                )));
            }
            gaussian(r, p.kind == "metal", (t, ts), &pattern, None)
        }
        "plastic2" | "metal2" | "trans2" => {
            // aniso.c: ux uy uz funcfile [transform]; r g b specularity u-roughness v-roughness
            // (trans2: then transmissivity and transmitted specularity).
            let trans = p.kind == "trans2";
            reals(if trans { &[8] } else { &[6] })?;
            let (s, r) = (&p.strings, &p.reals);
            if s.len() < 4 {
                return Err(err(format!(
                    "expected at least 4 string arguments (ux uy uz funcfile), found {}",
                    s.len()
                )));
            }
            if !(0.0..=1.0).contains(&r[3]) || r[4] <= 0.0 || r[5] <= 0.0 {
                return Err(err(format!(
                    "specularity {} must be in [0, 1] and the roughnesses {} {} above 0",
                    r[3], r[4], r[5]
                )));
            }
            let (t, ts) = if trans { (r[6], r[7]) } else { (0.0, 0.0) };
            if !(0.0..=1.0).contains(&t) || !(0.0..=1.0).contains(&ts) {
                return Err(err(format!(
                    "transmissivity {t} and transmitted specular {ts} must be in [0, 1]"
                )));
            }
            let v = constants(
                files,
                p,
                &s[3],
                &[(&s[0], "ux"), (&s[1], "uy"), (&s[2], "uz")],
            )?;
            let own = xform::parse_plain(&s[4..]).map_err(|e| err(format!("transform: {e}")))?;
            let u = own.then(&p.transform).vector(DVec3::new(v[0], v[1], v[2]));
            if u.length() == 0.0 {
                return Err(err("its orientation vector is zero".into()));
            }
            // Equal roughnesses are the isotropic model, whatever u.
            let anisotropy = crate::desc::Anisotropy {
                roughness_v: r[5] as f32,
                u: u.normalize().as_vec3(),
            };
            gaussian(r, p.kind == "metal2", (t, ts), &pattern, Some(anisotropy))
        }
        "mirror" => {
            reals(&[3])?;
            if !p.strings.is_empty() {
                return Err(err(
                    "a mirror's alternate material (for virtual sources) is not supported".into(),
                ));
            }
            Modifier::Bsdf(two_sided(BsdfDesc::RadianceMirror {
                reflectance: rgb(&p.reals),
                pattern: (!pattern.is_empty())
                    .then(|| Arc::new(pattern.clone()) as Arc<dyn SurfacePattern>),
            }))
        }
        "glass" => {
            reals(&[3, 4])?;
            let ior = p.reals.get(3).copied().unwrap_or(1.52);
            if ior <= 0.0 {
                return Err(err(format!("refractive index {ior} must be positive")));
            }
            Modifier::Bsdf(Arc::new(BsdfDesc::Glass {
                transmissivity: rgb(&p.reals),
                ior: ior as f32,
                pattern: (!pattern.is_empty())
                    .then(|| Arc::new(pattern.clone()) as Arc<dyn SurfacePattern>),
            }))
        }
        "dielectric" | "interface" => {
            // dielectric.c: transmission per unit length and index inside (and, for an
            // interface, outside); a dielectric's index at 500 nm by its Hartmann constant.
            let interface = p.kind == "interface";
            reals(if interface { &[8] } else { &[5] })?;
            let r = &p.reals;
            let media: &[&[f64]] = if interface {
                &[&r[0..3], &r[4..7]]
            } else {
                &[&r[0..3]]
            };
            if let Some(t) = media.iter().find(|t| t.iter().any(|&t| t < 0.999)) {
                return Err(err(format!(
                    "absorption inside a dielectric (transmission per unit length {} {} {}) is \
                     not supported; give 1 1 1",
                    t[0], t[1], t[2]
                )));
            }
            let (inside, outside) = if interface {
                (r[3], r[7])
            } else {
                (r[3] + r[4] / 500.0, 1.0)
            };
            if !(inside > 0.0 && outside > 0.0) {
                return Err(err(format!(
                    "refractive indices {inside} and {outside} must be positive"
                )));
            }
            Modifier::Bsdf(Arc::new(BsdfDesc::Dielectric {
                int_ior: inside as f32,
                ext_ior: outside as f32,
                specular_reflectance: Rgb::ONE,
                specular_transmittance: Rgb::ONE,
            }))
        }
        "BRTDfunc" => {
            // m_brdf.c: 10+ strings (mirror r g b, straight r g b, BRTD r g b, funcfile,
            // transform); 9+ reals (diffuse front, back, transmitted; then A10 …).
            if !pattern.is_empty() {
                return Err(err("patterns on a BRTDfunc are not supported".into()));
            }
            let s = &p.strings;
            if s.len() < 10 || p.reals.len() < 9 {
                return Err(err(format!(
                    "expected at least 10 string and 9 real arguments, found {} and {}",
                    s.len(),
                    p.reals.len()
                )));
            }
            let brtd = constants(
                files,
                p,
                &s[9],
                &[(&s[6], "BRTD r"), (&s[7], "BRTD g"), (&s[8], "BRTD b")],
            )
            .ok()
            .filter(|v| v.iter().all(|&x| x == 0.0));
            if brtd.is_none() {
                return Err(err(format!(
                    "non-specular BRTD functions ({} {} {}) are not supported; give 0 0 0",
                    s[6], s[7], s[8]
                )));
            }
            // Each triple read as a colorfunc of the same file, transform and arguments.
            let mut coefficients = |first: usize| -> Result<Arc<dyn SurfacePattern>, SceneError> {
                let q = Primitive {
                    kind: "colorfunc".into(),
                    strings: s[first..first + 3].iter().chain(&s[9..]).cloned().collect(),
                    ..p.clone()
                };
                let f = FunctionPattern::from_primitive(&q, files)
                    .map_err(|e| err(format!("its coefficients: {e}")))?;
                Ok(Arc::new(PatternChain {
                    chain: vec![Pattern::Function(Arc::new(f))],
                    spot: None,
                }))
            };
            let r = &p.reals;
            if r[..9].iter().any(|&v| v < 0.0) {
                return Err(err("negative diffuse reflectance or transmittance".into()));
            }
            Modifier::Bsdf(Arc::new(BsdfDesc::RadianceBrtd {
                reflect: coefficients(0)?,
                transmit: coefficients(3)?,
                diffuse_front: rgb(&r[0..3]),
                diffuse_back: rgb(&r[3..6]),
                diffuse_transmit: rgb(&r[6..9]),
            }))
        }
        "BSDF" => {
            if !pattern.is_empty() {
                return Err(err("patterns on a BSDF material are not supported".into()));
            }
            if !p.integers.is_empty() {
                return Err(err("expected no integer arguments".into()));
            }
            reals(&[0, 3, 6, 9])?;
            let s = &p.strings;
            if s.len() < 6 {
                return Err(err(format!(
                    "expected at least 6 string arguments (thickness BSDFfile ux uy uz \
                     funcfile), found {}",
                    s.len()
                )));
            }
            // Thickness and up vector: expressions in the function file (or rayinit's).
            let v = constants(
                files,
                p,
                &s[5],
                &[
                    (&s[0], "thickness"),
                    (&s[2], "up vector's x"),
                    (&s[3], "up vector's y"),
                    (&s[4], "up vector's z"),
                ],
            )?;
            let thickness = v[0];
            if thickness != 0.0 {
                return Err(err(format!(
                    "thickness {thickness}: a BSDF proxy for geometry behind it is not \
                     supported; give 0"
                )));
            }
            let up = DVec3::new(v[1], v[2], v[3]);
            let own = xform::parse_plain(&s[6..]).map_err(|e| err(format!("transform: {e}")))?;
            let up = own.then(&p.transform).vector(up);
            if up.length() == 0.0 {
                return Err(err("its up vector is zero".into()));
            }
            let path = files.locate(&s[1], "BSDF file", p)?;
            let data = files
                .klems(&path)
                .map_err(|message| SceneError::Referenced {
                    location: p.location.clone(),
                    path: path.clone(),
                    message,
                })?;
            let r = &p.reals;
            let color = |k: usize| {
                if r.len() >= k + 3 {
                    rgb(&r[k..])
                } else {
                    Rgb::ZERO
                }
            };
            if r.iter().any(|&v| v < 0.0) {
                return Err(err("negative diffuse reflectance or transmittance".into()));
            }
            Modifier::Bsdf(Arc::new(BsdfDesc::Klems {
                data,
                up: up.normalize().as_vec3(),
                reflect_front: color(0),
                reflect_back: color(3),
                transmit: color(6),
            }))
        }
        "light" | "glow" | "spotlight" => {
            reals(match p.kind.as_str() {
                "light" => &[3],
                "glow" => &[4],
                _ => &[7],
            })?;
            if p.reals[..3].iter().any(|&v| v < 0.0) {
                return Err(err("negative radiance".into()));
            }
            let mut pattern = pattern;
            if p.kind == "spotlight" {
                // The cone's full angle and the direction light leaves along, turned by the
                // !xform around it as xform's m_spot does.
                let angle = p.reals[3];
                let aim = p
                    .transform
                    .vector(DVec3::new(p.reals[4], p.reals[5], p.reals[6]));
                if angle.is_nan() || angle <= 0.0 || aim.length() == 0.0 {
                    return Err(err(
                        "a spotlight needs a positive angle and a non-zero direction".into(),
                    ));
                }
                pattern.spot = Some(Spot {
                    aim: aim.normalize(),
                    cos_half: (angle.min(360.0) * 0.5).to_radians().cos(),
                    focus: aim.length(),
                });
            }
            Modifier::Light {
                radiance: rgb(&p.reals),
                kind: match p.kind.as_str() {
                    "light" => "light",
                    "glow" => "glow",
                    _ => "spotlight",
                },
                pattern,
            }
        }
        "illum" => {
            reals(&[3])?;
            Modifier::Illum(p.strings.first().filter(|s| *s != "void").cloned())
        }
        "mixfunc" | "mixdata" | "mixpict" => {
            if !pattern.is_empty() {
                return Err(err("patterns on a mixture are not supported".into()));
            }
            if p.strings.len() < 4 {
                return Err(err(format!(
                    "expected at least 4 string arguments (foreground background coefficient \
                     file), found {}",
                    p.strings.len()
                )));
            }
            // Both parts opaque or transmitting Radiance materials without patterns: the
            // mixture is then the twosided blend of the two.
            let part = |name: &str| -> Result<Arc<BsdfDesc>, SceneError> {
                let plain = match known.get(name) {
                    Some((Modifier::Bsdf(b), _)) => match b.as_ref() {
                        BsdfDesc::TwoSided { front, back: None }
                            if !matches!(
                                front.as_ref(),
                                BsdfDesc::Ward {
                                    pattern: Some(_),
                                    ..
                                } | BsdfDesc::Blend { .. }
                            ) =>
                        {
                            Some(front.clone())
                        }
                        _ => None,
                    },
                    None if name != "void" => {
                        return Err(err(format!("undefined modifier '{name}'")))
                    }
                    _ => None,
                };
                plain.ok_or_else(|| {
                    err(format!(
                        "'{name}': a mixture's parts must be plastic, metal, trans or mirror \
                         materials without patterns (not void, lights, glass or mixtures)"
                    ))
                })
            };
            let (foreground, background) = (part(&p.strings[0])?, part(&p.strings[1])?);
            // The coefficient: mixfunc's expression; mixdata's function of a table (as
            // brightdata after the two materials); mixpict's function of a picture's channels
            // (as colorpict, that one function for each channel).
            let coefficient = match p.kind.as_str() {
                "mixfunc" => FunctionPattern::from_primitive(p, files)?,
                kind => {
                    let rest = &p.strings[2..];
                    let (as_kind, strings) = if kind == "mixdata" {
                        ("brightdata", rest.to_vec())
                    } else {
                        let f = rest[0].clone();
                        let strings = [f.clone(), f.clone(), f]
                            .into_iter()
                            .chain(rest[1..].iter().cloned())
                            .collect();
                        ("colorpict", strings)
                    };
                    let q = Primitive {
                        kind: as_kind.into(),
                        strings,
                        ..p.clone()
                    };
                    FunctionPattern::from_primitive(&q, files)
                        .map_err(|e| err(format!("its coefficient (read as {as_kind}): {e}")))?
                }
            };
            Modifier::Bsdf(Arc::new(BsdfDesc::TwoSided {
                front: Arc::new(BsdfDesc::Blend {
                    weight: TextureDesc::Constant(Rgb::splat(0.5)),
                    first: background,
                    second: foreground,
                    pattern: Some(Arc::new(PatternChain {
                        chain: vec![Pattern::Function(Arc::new(coefficient))],
                        spot: None,
                    })),
                }),
                back: None,
            }))
        }
        "texfunc" | "texdata" => {
            let own = Pattern::Texture(Arc::new(FunctionPattern::from_primitive(p, files)?));
            let mut chain = pattern.chain;
            chain.push(own);
            Modifier::Pattern(chain)
        }
        kind if FunctionPattern::is_function_pattern(kind) => {
            let own = match sky::SkyBrightness::from_primitive(p) {
                Some(s) => Pattern::Sky(s.map_err(err)?),
                None => Pattern::Function(Arc::new(FunctionPattern::from_primitive(p, files)?)),
            };
            let mut chain = pattern.chain;
            chain.push(own);
            Modifier::Pattern(chain)
        }
        other => Modifier::Unsupported(format!("{other}, not rendered by ircache")),
    };
    Ok(m)
}

/// Radiance's Gaussian material (`normal.c`, `aniso.c`) of colour, specularity and roughness
/// `r[..5]`, transmissivity and transmitted specularity `(t, ts)`, twosided, its colour under
/// `pattern`.
fn gaussian(
    r: &[f64],
    metal: bool,
    (t, ts): (f64, f64),
    pattern: &PatternChain,
    anisotropy: Option<crate::desc::Anisotropy>,
) -> Modifier {
    Modifier::Bsdf(two_sided(BsdfDesc::Ward {
        color: rgb(r),
        specularity: r[3] as f32,
        roughness: r[4] as f32,
        metal,
        transmissivity: t as f32,
        transmitted_specular: ts as f32,
        pattern: (!pattern.is_empty())
            .then(|| Arc::new(pattern.clone()) as Arc<dyn SurfacePattern>),
        anisotropy,
    }))
}

/// The values of the constant expressions `texts` (each with what it is, for errors) in the
/// function file `file` (`.` for `rayinit.cal`'s alone) that material `p` names; an error
/// where one depends on the ray.
fn constants(
    files: &mut PatternFiles,
    p: &Primitive,
    file: &str,
    texts: &[(&str, &str)],
) -> Result<Vec<f64>, SceneError> {
    let err = |m: String| SceneError::at(p.location.clone(), format!("{} '{}': {m}", p.kind, p.id));
    let program = files.functions.program(file, &p.location)?;
    let every_channel: Vec<u8> = (0..=u8::MAX).collect();
    texts
        .iter()
        .map(|(text, what)| {
            let e = cal::parse::parse_expression(text, &p.location)?;
            let node = program
                .compile(&e, &p.location)
                .map_err(|e| err(format!("{what} \"{text}\": {e}")))?;
            if program.reads_channels(&node, &every_channel) {
                return Err(err(format!(
                    "{what} \"{text}\" depends on the ray; ircache takes constant ones"
                )));
            }
            let v = program.eval(&node, &cal::eval::Channels::default(), &p.reals);
            if v.is_finite() {
                Ok(v)
            } else {
                Err(err(format!("{what} \"{text}\" is {v}")))
            }
        })
        .collect()
}

/// The material a surface uses, aliases and `illum` resolved; `None` for void.
fn surface_material(
    p: &Primitive,
    known: &HashMap<String, (Modifier, SourceLocation)>,
    illums: &mut usize,
) -> Result<Option<Modifier>, SceneError> {
    if p.modifier == "void" {
        return Ok(None);
    }
    let mut name = p.modifier.clone();
    for _ in 0..16 {
        let Some((m, at)) = known.get(&name) else {
            return Err(SceneError::at(
                p.location.clone(),
                format!("{} '{}': undefined modifier '{name}'", p.kind, p.id),
            ));
        };
        match m {
            Modifier::Illum(alt) if p.kind != "source" => {
                *illums += 1;
                match alt {
                    None => return Ok(None),
                    Some(a) => name = a.clone(),
                }
            }
            Modifier::Illum(_) => {
                return Err(SceneError::at(
                    p.location.clone(),
                    format!(
                        "source '{}': its material '{name}' (at {at}) is an illum, which a \
                         distant source cannot be",
                        p.id
                    ),
                ))
            }
            Modifier::Unsupported(what) => {
                return Err(SceneError::at(
                    p.location.clone(),
                    format!(
                        "{} '{}': its material '{name}' (at {at}) is {what}",
                        p.kind, p.id
                    ),
                ))
            }
            Modifier::Pattern(_) => {
                return Err(SceneError::at(
                    p.location.clone(),
                    format!(
                        "{} '{}': '{name}' is a pattern, not a material",
                        p.kind, p.id
                    ),
                ))
            }
            other => return Ok(Some(other.clone())),
        }
    }
    Err(SceneError::at(
        p.location.clone(),
        format!("{} '{}': illum alternates loop", p.kind, p.id),
    ))
}

/// A distant source: direction towards it (unit), full angle in degrees, its material.
struct Source {
    direction: DVec3,
    angle: f64,
    material: Modifier,
    location: SourceLocation,
}

fn source(p: &Primitive, material: Modifier) -> Result<Source, SceneError> {
    let err = |m: &str| SceneError::at(p.location.clone(), format!("source '{}': {m}", p.id));
    if p.reals.len() != 4 {
        return Err(err("expected 4 real arguments: direction x y z and angle"));
    }
    let d = p
        .transform
        .vector(DVec3::new(p.reals[0], p.reals[1], p.reals[2]));
    let angle = p.reals[3];
    if d.length() == 0.0 || angle <= 0.0 {
        return Err(err("needs a non-zero direction and a positive angle"));
    }
    match &material {
        Modifier::Light { kind, .. } if *kind != "spotlight" => {}
        Modifier::Light { .. } => {
            return Err(err("a distant source cannot be a spotlight"));
        }
        _ => {
            return Err(err(
                "a distant source must be of a 'light' or 'glow' material",
            ))
        }
    }
    Ok(Source {
        direction: d.normalize(),
        angle: angle.min(360.0),
        material,
        location: p.location.clone(),
    })
}

/// Directional lights for narrow `light` sources; the rest baked into one environment.
fn environment(sources: &[Source], notes: &mut Vec<String>) -> Vec<EmitterDesc> {
    let mut emitters = Vec::new();
    let mut baked = Vec::new();
    for s in sources {
        let Modifier::Light {
            radiance,
            kind,
            pattern,
        } = &s.material
        else {
            continue;
        };
        let half = (s.angle * 0.5).to_radians();
        let solid_angle = 2.0 * std::f64::consts::PI * (1.0 - half.cos());
        if *kind == "light" && pattern.is_empty() && s.angle < DIRECTIONAL_MAX_ANGLE {
            emitters.push(EmitterDesc::Directional {
                direction: (-s.direction).as_vec3(),
                irradiance: *radiance * solid_angle as f32,
            });
            notes.push(format!(
                "{}: the {}° source is a directional light of the same irradiance (its \
                 shadows are sharp)",
                s.location, s.angle
            ));
        } else {
            baked.push((s.direction, half.cos(), *radiance, pattern));
        }
    }
    if baked.is_empty() {
        return emitters;
    }
    if let [(_, cos, radiance, pattern)] = baked[..] {
        if cos <= -1.0 + 1e-12 && pattern.is_empty() {
            emitters.push(EmitterDesc::Constant { radiance });
            return emitters;
        }
    }
    let (w, h) = (ENVIRONMENT_WIDTH, ENVIRONMENT_WIDTH / 2);
    let mut image = ircache_image::Image::new(w, h);
    for j in 0..h {
        let theta = std::f64::consts::PI * j as f64 / (h - 1) as f64;
        for i in 0..w {
            let phi = 2.0 * std::f64::consts::PI * (i as f64 + 0.5) / w as f64;
            // The inverse of the environment's lat-long mapping (lights/environment.rs).
            let d = DVec3::new(
                phi.sin() * theta.sin(),
                theta.cos(),
                -phi.cos() * theta.sin(),
            );
            let mut sum = Rgb::ZERO;
            for (dir, cos, radiance, pattern) in &baked {
                if d.dot(*dir) >= *cos {
                    // Seen from inside the scene, far away (Radiance's FHUGE).
                    let [r, g, b] = pattern.factor_f64(d * 1e10, -d, d, 1e10, [0.0; 2]);
                    sum += *radiance * Rgb::new(r as f32, g as f32, b as f32);
                }
            }
            image.set(i, j, sum);
        }
    }
    emitters.push(EmitterDesc::Envmap {
        path: "(Radiance sources baked)".into(),
        image: Arc::new(image),
        to_world: Mat4::IDENTITY,
        scale: 1.0,
    });
    emitters
}

/// Evaluates a patterned light at a point of its surface over its front hemisphere: an error
/// where the patterns give no number (Radiance's compute error: an argument or `select` index
/// out of range, a domain error), a note where they are negative (counted as zero).
fn probe(
    p: &Primitive,
    geometry: &Geometry,
    pattern: &PatternChain,
    notes: &mut Vec<String>,
) -> Result<(), SceneError> {
    let (point, normal) = match geometry {
        Geometry::Mesh(m) => {
            let [a, b, c] = m.indices[0].map(|i| m.positions[i as usize].as_dvec3());
            ((a + b + c) / 3.0, (b - a).cross(c - a).normalize_or_zero())
        }
        Geometry::Sphere { center, radius, .. } => {
            ((*center + Vec3::Z * *radius).as_dvec3(), DVec3::Z)
        }
    };
    let (t, b) = basis(normal);
    let mut negative = None;
    for i in 0..16 {
        let phi = std::f64::consts::TAU * (f64::from(i) + 0.5) / 16.0;
        for j in 0..8 {
            let cos = (f64::from(j) + 0.5) / 8.0;
            let leaving = normal * cos + (t * phi.cos() + b * phi.sin()) * (1.0 - cos * cos).sqrt();
            let v = pattern.raw(point, normal, -leaving, 1.0, [0.5; 2]);
            let angle = cos.acos().to_degrees();
            if v.iter().any(|x| !x.is_finite()) {
                return Err(SceneError::at(
                    p.location.clone(),
                    format!(
                        "{} '{}': its light's patterns give no number ({v:?}) for light leaving \
                         {angle:.0}° from its normal: check their arguments and files",
                        p.kind, p.id
                    ),
                ));
            }
            if v.iter().any(|&x| x < 0.0) {
                negative.get_or_insert(angle);
            }
        }
    }
    if let Some(angle) = negative {
        notes.push(format!(
            "{}: {} '{}': its light's patterns are negative for light leaving {angle:.0}° from \
             its normal; ircache counts that as no light",
            p.location, p.kind, p.id
        ));
    }
    Ok(())
}

fn v3(v: DVec3) -> Vec3 {
    v.as_vec3()
}

/// The surface's geometry in world space; `None` when it has no area.
fn geometry(p: &Primitive) -> Result<Option<Geometry>, SceneError> {
    let err = |m: String| SceneError::at(p.location.clone(), format!("{} '{}': {m}", p.kind, p.id));
    let expect = |n: usize| -> Result<(), SceneError> {
        if p.reals.len() == n {
            Ok(())
        } else {
            Err(err(format!(
                "expected {n} real arguments, found {}",
                p.reals.len()
            )))
        }
    };
    let r = &p.reals;
    let t = &p.transform;
    let point = |i: usize| t.point(DVec3::new(r[i], r[i + 1], r[i + 2]));
    match p.kind.as_str() {
        "polygon" => {
            if r.len() < 9 || !r.len().is_multiple_of(3) {
                return Err(err(format!(
                    "expected 3 real arguments per vertex and at least 3 vertices, found {}",
                    r.len()
                )));
            }
            let mut pts: Vec<DVec3> = (0..r.len() / 3).map(|k| point(3 * k)).collect();
            if t.reverse {
                pts.reverse();
            }
            Ok(polygon(&pts).map(Geometry::Mesh))
        }
        "sphere" | "bubble" => {
            expect(4)?;
            let radius = r[3] * t.scale;
            if radius == 0.0 {
                return Ok(None);
            }
            Ok(Some(Geometry::Sphere {
                center: v3(point(0)),
                radius: radius.abs() as f32,
                // A negative radius turns a sphere inside out, as a bubble.
                flip_normals: (p.kind == "bubble") != (radius < 0.0),
                orientation: Mat3::IDENTITY,
            }))
        }
        "cylinder" | "tube" | "cone" | "cup" => {
            let cylinder = matches!(p.kind.as_str(), "cylinder" | "tube");
            expect(if cylinder { 7 } else { 8 })?;
            let (r0, r1) = if cylinder { (r[6], r[6]) } else { (r[6], r[7]) };
            let inward = matches!(p.kind.as_str(), "tube" | "cup");
            if r0 < 0.0 || r1 < 0.0 {
                return Err(err("negative radius".into()));
            }
            let (a, b) = (point(0), point(3));
            if (a - b).length() == 0.0 || (r0 == 0.0 && r1 == 0.0) {
                return Ok(None);
            }
            Ok(Some(Geometry::Mesh(cone(
                a,
                b,
                r0 * t.scale,
                r1 * t.scale,
                inward,
            ))))
        }
        "ring" => {
            expect(8)?;
            let n = t.vector(DVec3::new(r[3], r[4], r[5]));
            let (r0, r1) = (r[6] * t.scale, r[7] * t.scale);
            if n.length() == 0.0 || r0 < 0.0 || r1 <= r0 {
                return Err(err(format!(
                    "needs a non-zero normal and radii 0 ≤ r0 < r1, found {} {}",
                    r[6], r[7]
                )));
            }
            Ok(Some(Geometry::Mesh(ring(point(0), n.normalize(), r0, r1))))
        }
        "mesh" => unreachable!("meshes are read by mesh_surfaces"),
        other => Err(err(format!("unknown surface type '{other}'"))),
    }
}

/// An orthonormal pair perpendicular to unit `n`.
fn basis(n: DVec3) -> (DVec3, DVec3) {
    let a = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let u = n.cross(a).normalize();
    (u, n.cross(u))
}

/// A cone (or cylinder) from `a` (radius `r0`) to `b` (radius `r1`), normals outward or inward,
/// the polygon radii enlarged so the lateral area is the exact cone's.
fn cone(a: DVec3, b: DVec3, r0: f64, r1: f64, inward: bool) -> TriangleMesh {
    let n = SEGMENTS;
    let nf = f64::from(n);
    let k = std::f64::consts::PI / (nf * (std::f64::consts::PI / nf).sin());
    let axis = (b - a).normalize();
    let len = (b - a).length();
    let (u, v) = basis(axis);
    // Outward normal of the slanted side: radial tilted by the radius change.
    let slope = (r0 - r1) / len;
    let mut mesh = TriangleMesh::default();
    let mut normals = Vec::new();
    for i in 0..n {
        let phi = 2.0 * std::f64::consts::PI * f64::from(i) / nf;
        let radial = u * phi.cos() + v * phi.sin();
        let normal = (radial + axis * slope).normalize();
        for (c, r) in [(a, r0), (b, r1)] {
            mesh.positions.push(v3(c + radial * (r * k)));
            normals.push(v3(if inward { -normal } else { normal }));
        }
    }
    for i in 0..n {
        let j = (i + 1) % n;
        let (a0, b0, a1, b1) = (2 * i, 2 * i + 1, 2 * j, 2 * j + 1);
        // Counter-clockwise seen from outside: a0, a1, b1 and a0, b1, b0.
        let mut tris = Vec::new();
        if r0 > 0.0 {
            tris.push([a0, a1, b1]);
        }
        if r1 > 0.0 {
            tris.push([a0, b1, b0]);
        }
        for mut t in tris {
            if inward {
                t.swap(1, 2);
            }
            mesh.indices.push(t);
        }
    }
    mesh.normals = Some(normals);
    mesh
}

/// A ring (annulus, or disc when `r0` = 0) at `c` facing unit `n`, radii enlarged so the area is
/// the exact ring's.
fn ring(c: DVec3, n: DVec3, r0: f64, r1: f64) -> TriangleMesh {
    let segs = SEGMENTS;
    let nf = f64::from(segs);
    let k = (2.0 * std::f64::consts::PI / (nf * (2.0 * std::f64::consts::PI / nf).sin())).sqrt();
    let (u, v) = basis(n);
    let mut mesh = TriangleMesh::default();
    for i in 0..segs {
        let phi = 2.0 * std::f64::consts::PI * f64::from(i) / nf;
        let radial = u * phi.cos() + v * phi.sin();
        mesh.positions.push(v3(c + radial * (r0 * k)));
        mesh.positions.push(v3(c + radial * (r1 * k)));
    }
    for i in 0..segs {
        let j = (i + 1) % segs;
        let (i0, o0, i1, o1) = (2 * i, 2 * i + 1, 2 * j, 2 * j + 1);
        // u × v = n: increasing φ turns counter-clockwise seen from the front.
        mesh.indices.push([o0, o1, i1]);
        if r0 > 0.0 {
            mesh.indices.push([o0, i1, i0]);
        }
    }
    mesh
}

/// Triangulates a planar polygon by ear clipping (its vertex order kept, so the triangles face
/// where it faces); `None` when it has no area.
fn polygon(pts: &[DVec3]) -> Option<TriangleMesh> {
    // Newell's normal: the polygon's area vector.
    let mut normal = DVec3::ZERO;
    for (k, p) in pts.iter().enumerate() {
        let q = pts[(k + 1) % pts.len()];
        normal += p.cross(q);
    }
    if normal.length() <= 1e-12 * bounds_scale(pts).powi(2) {
        return None;
    }
    let normal = normal.normalize();
    let (u, v) = basis(normal);
    let flat: Vec<(f64, f64)> = pts.iter().map(|p| (p.dot(u), p.dot(v))).collect();
    let mut mesh = TriangleMesh {
        positions: pts.iter().map(|&p| v3(p)).collect(),
        ..TriangleMesh::default()
    };
    let mut left: Vec<u32> = (0..pts.len() as u32).collect();
    let cross = |a: (f64, f64), b: (f64, f64), c: (f64, f64)| {
        (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
    };
    // Closed: a vertex on the ear's new edge (a reflex corner collinear with it) blocks it.
    let inside = |p: (f64, f64), a, b, c| {
        cross(a, b, p) >= 0.0 && cross(b, c, p) >= 0.0 && cross(c, a, p) >= 0.0
    };
    let mut guard = 0;
    while left.len() > 3 && guard < 4 * pts.len() * pts.len() {
        guard += 1;
        let m = left.len();
        let mut clipped = false;
        for k in 0..m {
            let (ia, ib, ic) = (left[(k + m - 1) % m], left[k], left[(k + 1) % m]);
            let (a, b, c) = (flat[ia as usize], flat[ib as usize], flat[ic as usize]);
            if cross(a, b, c) <= 0.0 {
                continue;
            }
            let blocked = left.iter().any(|&q| {
                q != ia && q != ib && q != ic && {
                    let p = flat[q as usize];
                    p != a && p != b && p != c && inside(p, a, b, c)
                }
            });
            if !blocked {
                mesh.indices.push([ia, ib, ic]);
                left.remove(k);
                clipped = true;
                break;
            }
        }
        if !clipped {
            break;
        }
    }
    if left.len() > 3 {
        // Not simple (self-intersecting): a fan over what is left.
        for k in 1..left.len() - 1 {
            mesh.indices.push([left[0], left[k], left[k + 1]]);
        }
    } else if left.len() == 3 {
        mesh.indices.push([left[0], left[1], left[2]]);
    }
    // Drop slivers of collinear vertices.
    mesh.indices.retain(|t| {
        let [a, b, c] = t.map(|i| flat[i as usize]);
        cross(a, b, c).abs() > 1e-12 * bounds_scale(pts).powi(2)
    });
    (!mesh.indices.is_empty()).then_some(mesh)
}

fn bounds_scale(pts: &[DVec3]) -> f64 {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for p in pts {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    (hi - lo).length()
}

/// The camera: the Radiance view if one was given, else the OBJ-style camera settings or the
/// whole scene framed from +y.
fn sensor(shapes: &[ShapeDesc], camera: &ObjCamera, path: &Path) -> Result<SensorDesc, SceneError> {
    let (max_w, max_h) = (
        camera.width.unwrap_or(DEFAULT_SIZE).max(1),
        camera.height.unwrap_or(DEFAULT_SIZE).max(1),
    );
    let view = match &camera.radiance_view {
        Some(text) => View::parse(text, Path::new("."))
            .map_err(|e| SceneError::at(SourceLocation::start_of(path), format!("--view: {e}")))?,
        None => default_view(shapes, camera),
    };
    let (width, height) =
        if camera.width.is_some() && camera.height.is_some() && camera.radiance_view.is_none() {
            (max_w, max_h)
        } else {
            view.fit(max_w, max_h)
        };
    let dir = view.direction.normalize();
    let right = dir.cross(view.up).normalize();
    let up = right.cross(dir);
    let to_world = Mat4::from_cols(
        v3(-right).extend(0.0),
        v3(up).extend(0.0),
        v3(dir).extend(0.0),
        v3(view.position).extend(1.0),
    );
    let scale = bounds(shapes).1.max(1e-6);
    let panoramic = |mapping| {
        (
            to_world,
            Projection::Panoramic {
                mapping,
                horizontal: view.horizontal as f32,
                vertical: view.vertical as f32,
            },
            1.0,
        )
    };
    let (to_world, projection, fov) = match view.kind {
        ViewType::Parallel => {
            // Orthographic film [−1, 1] × [−1/aspect, 1/aspect] scaled to the view's width.
            let s = (view.horizontal * 0.5) as f32;
            (
                to_world * Mat4::from_scale(Vec3::splat(s)),
                Projection::Orthographic,
                1.0,
            )
        }
        ViewType::Perspective => (to_world, Projection::Pinhole, view.horizontal as f32),
        ViewType::Hemispherical => panoramic(PanoramicMapping::Hemispherical),
        ViewType::Angular => panoramic(PanoramicMapping::Angular),
        ViewType::Planispheric => panoramic(PanoramicMapping::Planispheric),
        ViewType::Cylindrical => panoramic(PanoramicMapping::Cylindrical),
    };
    let distance = (bounds(shapes).0 - v3(view.position)).length() + scale;
    Ok(SensorDesc::standard(
        to_world,
        (fov, FovAxis::X),
        projection,
        (width, height),
        DEFAULT_SPP,
        distance,
        1e-4,
    ))
}

/// Centre and radius of the scene's bounding sphere.
fn bounds(shapes: &[ShapeDesc]) -> (Vec3, f32) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for s in shapes {
        match &s.geometry {
            Geometry::Mesh(m) => {
                for p in &m.positions {
                    lo = lo.min(*p);
                    hi = hi.max(*p);
                }
            }
            Geometry::Sphere { center, radius, .. } => {
                lo = lo.min(*center - Vec3::splat(*radius));
                hi = hi.max(*center + Vec3::splat(*radius));
            }
        }
    }
    ((lo + hi) * 0.5, (hi - lo).length() * 0.5)
}

/// Without a view: `eye`, `target`, `up` and `fov` where given, the rest framing the scene from
/// Radiance's default direction (+y, up +z).
fn default_view(shapes: &[ShapeDesc], camera: &ObjCamera) -> View {
    let (centre, radius) = bounds(shapes);
    let fov = f64::from(camera.fov.unwrap_or(45.0).clamp(1e-3, 179.0));
    let fit = f64::from(radius.max(1e-6)) / (fov.to_radians() * 0.5).sin();
    let d = |v: Vec3| v.as_dvec3();
    let up = camera.up.map_or(DVec3::Z, d);
    let centre = d(centre);
    let (eye, target) = match (camera.eye.map(d), camera.target.map(d)) {
        (Some(e), Some(t)) => (e, t),
        (Some(e), None) => (e, centre),
        (None, Some(t)) => (t - DVec3::Y * ((centre - t).length() + fit), t),
        (None, None) => (centre - DVec3::Y * fit, centre),
    };
    let w = f64::from(camera.width.unwrap_or(DEFAULT_SIZE));
    let h = f64::from(camera.height.unwrap_or(DEFAULT_SIZE));
    // The fov is vertical, as for OBJ scenes; the horizontal one follows from the size.
    let vertical = fov;
    let horizontal = 2.0 * ((fov.to_radians() * 0.5).tan() * w / h).atan().to_degrees();
    let mut direction = target - eye;
    if direction.length() == 0.0 {
        direction = DVec3::Y;
    }
    let up = if up.cross(direction).length() <= 1e-9 * direction.length() {
        DVec3::X
    } else {
        up
    };
    View {
        kind: ViewType::Perspective,
        position: eye,
        direction,
        up,
        horizontal: horizontal.min(179.0),
        vertical,
    }
}
