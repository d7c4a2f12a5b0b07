//! BSDFs and textures with Mitsuba 3's parameters and defaults.
//!
//! Defaults (Mitsuba 3): `diffuse` reflectance 0.5; `plastic`/`roughplastic` diffuse 0.5,
//! specular 1, int_ior polypropylene (1.49), ext_ior air (1.000277); `roughplastic` and
//! `roughconductor` Beckmann with α = 0.1; `conductor`/`roughconductor` material "none"
//! (η = 0, k = 1: a perfect mirror); `dielectric`/`roughdielectric`/`thindielectric` int_ior BK7
//! (1.5046), ext_ior air; `roughdielectric` Beckmann with α = 0.1. A bitmap's `to_uv` 4×4 transform acts on (u, v) through its x/y rows and columns
//! and its translation column.

use super::props::{Plugin, Prop, Value};
use super::{expect_tag, Ctx};
use crate::desc::{
    BitmapDesc, BsdfDesc, MicrofacetDistribution, TextureDesc, TextureFilter, WrapMode,
    PRINCIPLED_PARAMETERS, PRINCIPLED_SPEC_TRANS,
};
use crate::error::SceneError;
use crate::ior;
use ircache_math::{Mat3, Rgb, Vec3};
use std::rc::Rc;
use std::sync::Arc;

const BSDFS: &[&str] = &[
    "diffuse",
    "twosided",
    "plastic",
    "roughplastic",
    "conductor",
    "roughconductor",
    "dielectric",
    "roughdielectric",
    "thindielectric",
    "normalmap",
    "bumpmap",
    "mask",
    "null",
    "blendbsdf",
    "principled",
];
const TEXTURES: &[&str] = &["bitmap", "checkerboard"];

/// Builds (once per plugin) a BSDF.
pub(crate) fn build_bsdf(ctx: &Ctx, p: &Rc<Plugin>) -> Result<Arc<BsdfDesc>, SceneError> {
    let key = Rc::as_ptr(p);
    if let Some(b) = ctx.bsdfs.borrow().get(&key) {
        return Ok(b.clone());
    }
    let b = Arc::new(build_bsdf_uncached(ctx, p)?);
    ctx.bsdfs.borrow_mut().insert(key, b.clone());
    Ok(b)
}

fn build_bsdf_uncached(ctx: &Ctx, p: &Plugin) -> Result<BsdfDesc, SceneError> {
    p.expect_type(BSDFS)?;
    let b = match p.ty.as_str() {
        "null" => BsdfDesc::Null,
        "diffuse" => {
            let reflectance = texture_param(ctx, p, "reflectance", 0.5)?;
            if let (TextureDesc::Constant(c), Some(prop)) = (&reflectance, p.get("reflectance")) {
                check_unit_range(*c, "reflectance", prop)?;
            }
            BsdfDesc::Diffuse { reflectance }
        }
        "normalmap" | "bumpmap" => {
            let mut texture = None;
            let mut nested = None;
            for (obj, prop) in p.objects(&ctx.ids)? {
                match obj.tag.as_str() {
                    "texture" if texture.is_none() => texture = Some(build_texture(ctx, &obj)?),
                    "bsdf" if nested.is_none() => nested = Some(build_bsdf(ctx, &obj)?),
                    _ => expect_tag(&obj, prop, "one texture and one bsdf")?,
                }
            }
            let texture = texture.ok_or_else(|| p.error("a nested bitmap texture is required"))?;
            let nested = nested.ok_or_else(|| p.error("a nested BSDF is required"))?;
            let shading = crate::desc::PerturbedShading {
                shadowing: p.boolean("use_shadowing_function", true)?,
                flip_invalid_normals: p.boolean("flip_invalid_normals", true)?,
            };
            if p.ty == "normalmap" {
                BsdfDesc::NormalMap {
                    normals: texture,
                    nested,
                    shading,
                }
            } else {
                let scale = p.float("scale", 1.0)?;
                if !scale.is_finite() {
                    return Err(p.error("scale must be finite"));
                }
                BsdfDesc::BumpMap {
                    height: texture,
                    scale,
                    nested,
                    shading,
                }
            }
        }
        "mask" => {
            let opacity = texture_param(ctx, p, "opacity", 0.5)?;
            if let (TextureDesc::Constant(c), Some(prop)) = (&opacity, p.get("opacity")) {
                check_unit_range(*c, "opacity", prop)?;
            }
            let mut nested = None;
            for (obj, prop) in p.objects(&ctx.ids)? {
                match obj.tag.as_str() {
                    "bsdf" if nested.is_none() => nested = Some(build_bsdf(ctx, &obj)?),
                    "texture" if prop.name == "opacity" => {}
                    _ => expect_tag(&obj, prop, "one nested bsdf and an opacity texture")?,
                }
            }
            let nested = nested.ok_or_else(|| p.error("a nested BSDF is required"))?;
            BsdfDesc::Mask { opacity, nested }
        }
        "blendbsdf" => build_blend(ctx, p)?,
        "principled" => build_principled(ctx, p)?,
        "twosided" => {
            let nested = p.objects(&ctx.ids)?;
            let mut bsdfs = Vec::new();
            for (obj, prop) in &nested {
                expect_tag(obj, prop, "bsdf")?;
                if bsdfs.len() == 2 {
                    return Err(SceneError::at(
                        prop.loc.clone(),
                        "twosided: cannot have more than two nested BSDFs",
                    ));
                }
                let b = build_bsdf(ctx, obj)?;
                let transmits = |b: &BsdfDesc| match b {
                    BsdfDesc::Dielectric { .. }
                    | BsdfDesc::RoughDielectric { .. }
                    | BsdfDesc::ThinDielectric { .. } => true,
                    BsdfDesc::Principled { parameters, .. } => {
                        !parameters[PRINCIPLED_SPEC_TRANS].is_zero()
                    }
                    _ => false,
                };
                let blend_transmits = matches!(&*b, BsdfDesc::Blend { first, second, .. }
                    if transmits(first) || transmits(second));
                if transmits(&b) || blend_transmits || matches!(*b, BsdfDesc::TwoSided { .. }) {
                    return Err(SceneError::at(
                        prop.loc.clone(),
                        format!(
                            "twosided: only materials without transmission can be nested (got \"{}\")",
                            obj.ty
                        ),
                    ));
                }
                bsdfs.push(b);
            }
            let mut it = bsdfs.into_iter();
            let Some(front) = it.next() else {
                return Err(p.error("a nested one-sided BSDF is required"));
            };
            BsdfDesc::TwoSided {
                front,
                back: it.next(),
            }
        }
        "plastic" | "roughplastic" => {
            let diffuse_reflectance = texture_param(ctx, p, "diffuse_reflectance", 0.5)?;
            if let (TextureDesc::Constant(c), Some(prop)) =
                (&diffuse_reflectance, p.get("diffuse_reflectance"))
            {
                check_unit_range(*c, "diffuse_reflectance", prop)?;
            }
            let specular_reflectance = nonnegative_rgb(p, "specular_reflectance", 1.0)?;
            let (int_ior, ext_ior) = iors(p, "polypropylene")?;
            let nonlinear = p.boolean("nonlinear", false)?;
            if p.ty == "plastic" {
                BsdfDesc::Plastic {
                    diffuse_reflectance,
                    specular_reflectance,
                    int_ior,
                    ext_ior,
                    nonlinear,
                }
            } else {
                let distribution = distribution(p)?;
                let alpha = alpha_param(p, "alpha")?.unwrap_or(0.1);
                let _ = p.boolean("sample_visible", true)?;
                BsdfDesc::RoughPlastic {
                    distribution,
                    alpha,
                    diffuse_reflectance,
                    specular_reflectance,
                    int_ior,
                    ext_ior,
                    nonlinear,
                }
            }
        }
        "conductor" | "roughconductor" => {
            let (eta, k) = conductor_ior(p)?;
            let specular_reflectance = nonnegative_rgb(p, "specular_reflectance", 1.0)?;
            if p.ty == "conductor" {
                BsdfDesc::Conductor {
                    eta,
                    k,
                    specular_reflectance,
                }
            } else {
                let (distribution, alpha_u, alpha_v) = anisotropic_microfacet(p)?;
                BsdfDesc::RoughConductor {
                    distribution,
                    alpha_u,
                    alpha_v,
                    eta,
                    k,
                    specular_reflectance,
                }
            }
        }
        _ => {
            // dielectric, roughdielectric, thindielectric
            let (int_ior, ext_ior) = iors(p, "bk7")?;
            let specular_reflectance = nonnegative_rgb(p, "specular_reflectance", 1.0)?;
            let specular_transmittance = nonnegative_rgb(p, "specular_transmittance", 1.0)?;
            if p.ty == "roughdielectric" {
                let (distribution, alpha_u, alpha_v) = anisotropic_microfacet(p)?;
                BsdfDesc::RoughDielectric {
                    distribution,
                    alpha_u,
                    alpha_v,
                    int_ior,
                    ext_ior,
                    specular_reflectance,
                    specular_transmittance,
                }
            } else if p.ty == "dielectric" {
                BsdfDesc::Dielectric {
                    int_ior,
                    ext_ior,
                    specular_reflectance,
                    specular_transmittance,
                }
            } else {
                BsdfDesc::ThinDielectric {
                    int_ior,
                    ext_ior,
                    specular_reflectance,
                    specular_transmittance,
                }
            }
        }
    };
    p.check_unused()?;
    Ok(b)
}

/// Mitsuba 3's `principled`: the base colour and the scalar parameters of
/// [`PRINCIPLED_PARAMETERS`] (floats or textures, constants checked to lie in [0, 1]), and the
/// index of refraction from `eta` or `specular` (not both). Mitsuba's sampling rates only tune its
/// own lobe choice; they are read and said to be unused.
fn build_principled(ctx: &Ctx, p: &Plugin) -> Result<BsdfDesc, SceneError> {
    let base_color = texture_param(ctx, p, "base_color", 0.5)?;
    let mut parameters: [TextureDesc; 10] =
        std::array::from_fn(|_| TextureDesc::Constant(Rgb::ZERO));
    for ((name, default), slot) in PRINCIPLED_PARAMETERS.iter().zip(&mut parameters) {
        let t = texture_param(ctx, p, name, *default)?;
        if let (TextureDesc::Constant(c), Some(prop)) = (&t, p.get(name)) {
            check_unit_range(*c, name, prop)?;
        }
        *slot = t;
    }
    for (obj, prop) in p.objects(&ctx.ids)? {
        let named =
            prop.name == "base_color" || PRINCIPLED_PARAMETERS.iter().any(|(n, _)| *n == prop.name);
        if !(obj.tag == "texture" && named) {
            expect_tag(&obj, prop, "textures for principled's parameters")?;
        }
    }
    let transmits = !parameters[PRINCIPLED_SPEC_TRANS].is_zero();
    let eta = match (p.get("eta"), p.get("specular")) {
        (Some(_), Some(prop)) => {
            return Err(SceneError::at(
                prop.loc.clone(),
                "principled takes either \"eta\" or \"specular\", not both",
            ))
        }
        (Some(prop), None) => {
            let eta = p.float("eta", 1.5)?;
            if !(eta.is_finite() && eta > 0.0) {
                return Err(SceneError::at(
                    prop.loc.clone(),
                    format!("eta {eta} must be finite and greater than zero"),
                ));
            }
            // As Mitsuba: an interface that refracts needs η ≠ 1.
            if transmits && eta == 1.0 {
                1.001
            } else {
                eta
            }
        }
        (None, prop) => {
            let specular = p.float("specular", 0.5)?;
            if !(0.0..=1.0).contains(&specular) {
                return Err(SceneError::at(
                    prop.map_or(p.loc.clone(), |q| q.loc.clone()),
                    format!("specular {specular} must lie in [0, 1]"),
                ));
            }
            let specular = if transmits && specular == 0.0 {
                1e-3
            } else {
                specular
            };
            2.0 / (1.0 - (0.08 * specular).sqrt()) - 1.0
        }
    };
    let rates = [
        "main_specular_sampling_rate",
        "clearcoat_sampling_rate",
        "diffuse_reflectance_sampling_rate",
    ];
    for rate in rates {
        if let Some((_, prop)) = p.float_opt(rate)? {
            ctx.notes.borrow_mut().push(format!(
                "{}: principled's \"{rate}\" tunes Mitsuba's own lobe choice; ircache \
                 chooses lobes by its own estimate (the image is the same)",
                prop.loc
            ));
        }
    }
    Ok(BsdfDesc::Principled {
        base_color,
        parameters: Box::new(parameters),
        eta,
    })
}

/// Mitsuba's `blendbsdf`: a weight (float or texture, required) and two nested BSDFs. Both
/// must be plain models, or both `twosided` with one model each (made the `twosided` of the
/// blend); anything else is an error naming the nested BSDF's line.
fn build_blend(ctx: &Ctx, p: &Plugin) -> Result<BsdfDesc, SceneError> {
    if !p.has("weight") {
        return Err(p.error("blendbsdf needs a \"weight\" (a float or a texture in [0, 1])"));
    }
    let weight = texture_param(ctx, p, "weight", 0.5)?;
    if let (TextureDesc::Constant(c), Some(prop)) = (&weight, p.get("weight")) {
        check_unit_range(*c, "weight", prop)?;
    }
    let mut nested = Vec::new();
    for (obj, prop) in p.objects(&ctx.ids)? {
        match obj.tag.as_str() {
            "texture" if prop.name == "weight" => {}
            "bsdf" if nested.len() < 2 => nested.push((build_bsdf(ctx, &obj)?, prop.loc.clone())),
            "bsdf" => {
                return Err(SceneError::at(
                    prop.loc.clone(),
                    "blendbsdf: cannot have more than two nested BSDFs",
                ))
            }
            _ => expect_tag(&obj, prop, "two nested bsdfs and a weight texture")?,
        }
    }
    let [(first, first_loc), (second, second_loc)]: [_; 2] = nested
        .try_into()
        .map_err(|_| p.error("blendbsdf: two nested BSDFs must be given"))?;
    let plain = |b: &BsdfDesc| {
        !matches!(
            b,
            BsdfDesc::Blend { .. }
                | BsdfDesc::TwoSided { .. }
                | BsdfDesc::Mask { .. }
                | BsdfDesc::NormalMap { .. }
                | BsdfDesc::BumpMap { .. }
                | BsdfDesc::Null
        )
    };
    let one_model = |b: &Arc<BsdfDesc>| match b.as_ref() {
        BsdfDesc::TwoSided { front, back: None } if plain(front) => Some(front.clone()),
        _ => None,
    };
    let unsupported = |loc: &crate::error::SourceLocation| {
        SceneError::at(
            loc.clone(),
            "blendbsdf: each nested BSDF must be a plain model (not a blend, mask, normal or \
             bump map, or null), or both twosided around one such model",
        )
    };
    match (one_model(&first), one_model(&second)) {
        (Some(a), Some(b)) => Ok(BsdfDesc::TwoSided {
            front: Arc::new(BsdfDesc::Blend {
                weight,
                first: a,
                second: b,
                pattern: None,
            }),
            back: None,
        }),
        _ if !plain(&first) => Err(unsupported(&first_loc)),
        _ if !plain(&second) => Err(unsupported(&second_loc)),
        _ => Ok(BsdfDesc::Blend {
            weight,
            first,
            second,
            pattern: None,
        }),
    }
}

fn check_unit_range(c: Rgb, name: &str, prop: &Prop) -> Result<(), SceneError> {
    let a = c.to_array();
    if a.iter().any(|v| !(0.0..=1.0).contains(v)) {
        return Err(SceneError::at(
            prop.loc.clone(),
            format!("{name} ({}, {}, {}) must lie in [0, 1]", a[0], a[1], a[2]),
        ));
    }
    Ok(())
}

fn nonnegative_rgb(p: &Plugin, name: &str, default: f32) -> Result<Rgb, SceneError> {
    match p.rgb_opt(name)? {
        None => Ok(Rgb::splat(default)),
        Some((c, prop)) => {
            let a = c.to_array();
            if a.iter().any(|v| !v.is_finite() || *v < 0.0) {
                return Err(SceneError::at(
                    prop.loc.clone(),
                    format!(
                        "{name} ({}, {}, {}) must be finite and non-negative",
                        a[0], a[1], a[2]
                    ),
                ));
            }
            Ok(c)
        }
    }
}

fn distribution(p: &Plugin) -> Result<MicrofacetDistribution, SceneError> {
    match p.string_opt("distribution")? {
        None => Ok(MicrofacetDistribution::Beckmann),
        Some((s, prop)) => match s.to_ascii_lowercase().as_str() {
            "beckmann" => Ok(MicrofacetDistribution::Beckmann),
            "ggx" => Ok(MicrofacetDistribution::Ggx),
            _ => Err(SceneError::at(
                prop.loc.clone(),
                format!("invalid distribution \"{s}\" (must be \"beckmann\" or \"ggx\")"),
            )),
        },
    }
}

/// `alpha`, or `alpha_u` and `alpha_v` together (default 0.1), as Mitsuba 3's rough models.
/// A rough conductor's or dielectric's microfacets: the distribution and (α_u, α_v); Mitsuba's
/// `sample_visible` is read (ircache always samples visible normals).
fn anisotropic_microfacet(p: &Plugin) -> Result<(MicrofacetDistribution, f32, f32), SceneError> {
    let distribution = distribution(p)?;
    let _ = p.boolean("sample_visible", true)?;
    let (alpha_u, alpha_v) = anisotropic_alpha(p)?;
    Ok((distribution, alpha_u, alpha_v))
}

fn anisotropic_alpha(p: &Plugin) -> Result<(f32, f32), SceneError> {
    if p.has("alpha") {
        if p.has("alpha_u") || p.has("alpha_v") {
            return Err(p.error("specify either \"alpha\" or \"alpha_u\"/\"alpha_v\", not both"));
        }
        let a = alpha_param(p, "alpha")?.unwrap_or(0.1);
        Ok((a, a))
    } else if p.has("alpha_u") || p.has("alpha_v") {
        match (alpha_param(p, "alpha_u")?, alpha_param(p, "alpha_v")?) {
            (Some(u), Some(v)) => Ok((u, v)),
            _ => Err(p.error("both \"alpha_u\" and \"alpha_v\" must be specified")),
        }
    } else {
        Ok((0.1, 0.1))
    }
}

fn alpha_param(p: &Plugin, name: &str) -> Result<Option<f32>, SceneError> {
    if let Some(prop) = p.get(name) {
        if matches!(prop.value, Value::Object(_) | Value::Ref(_)) {
            return Err(SceneError::at(
                prop.loc.clone(),
                format!("a textured \"{name}\" is not supported"),
            ));
        }
    }
    match p.float_opt(name)? {
        None => Ok(None),
        Some((a, _)) if a.is_finite() && a > 0.0 => Ok(Some(a)),
        Some((a, prop)) => Err(SceneError::at(
            prop.loc.clone(),
            format!("{name} {a} must be positive"),
        )),
    }
}

/// `int_ior` and `ext_ior` (numbers or names), defaults `int_default` and air.
fn iors(p: &Plugin, int_default: &str) -> Result<(f32, f32), SceneError> {
    let int_ior = ior_param(p, "int_ior", int_default)?;
    let ext_ior = ior_param(p, "ext_ior", "air")?;
    let valid = |v: f32| v > 0.0 && v.is_finite();
    if !valid(int_ior) || !valid(ext_ior) || int_ior == ext_ior {
        return Err(p.error(format!(
            "the interior and exterior indices of refraction must be positive and differ (int_ior {int_ior}, ext_ior {ext_ior})"
        )));
    }
    Ok((int_ior, ext_ior))
}

fn ior_param(p: &Plugin, name: &str, default: &str) -> Result<f32, SceneError> {
    if let Some(prop) = p.get(name) {
        if let Value::String(s) = &prop.value {
            return ior::dielectric_ior(s).ok_or_else(|| {
                SceneError::at(
                    prop.loc.clone(),
                    format!(
                        "unknown IOR name \"{s}\" (valid choices: {})",
                        ior::dielectric_names().join(", ")
                    ),
                )
            });
        }
    }
    match p.float_opt(name)? {
        Some((v, _)) => Ok(v),
        None => Ok(ior::dielectric_ior(default).expect("default IOR names are in the table")),
    }
}

fn conductor_ior(p: &Plugin) -> Result<(Rgb, Rgb), SceneError> {
    let material = p.string_opt("material")?;
    let is_none = !matches!(&material, Some((m, _)) if *m != "none");
    if p.has("eta") || is_none {
        if let Some((m, prop)) = &material {
            if *m != "none" {
                return Err(SceneError::at(
                    prop.loc.clone(),
                    "specify either (eta, k) or material, not both",
                ));
            }
        }
        let eta = p.rgb("eta", Rgb::splat(0.0))?;
        let k = p.rgb("k", Rgb::splat(1.0))?;
        for (name, v) in [("eta", eta), ("k", k)] {
            if v.to_array().iter().any(|x| !x.is_finite()) {
                let loc = p.get(name).map_or(p.loc.clone(), |q| q.loc.clone());
                return Err(SceneError::at(loc, format!("{name} must be finite")));
            }
        }
        return Ok((eta, k));
    }
    let (m, prop) = material.expect("checked above");
    ior::conductor_ior(m).ok_or_else(|| {
        SceneError::at(
            prop.loc.clone(),
            format!(
                "unknown conductor material \"{m}\" (valid choices: {})",
                ior::conductor_names().join(", ")
            ),
        )
    })
}

/// A texture-valued parameter: a constant (`<rgb>`, `<float>`) or a nested/referenced texture.
pub(crate) fn texture_param(
    ctx: &Ctx,
    p: &Plugin,
    name: &str,
    default: f32,
) -> Result<TextureDesc, SceneError> {
    let Some(prop) = p.get(name) else {
        return Ok(TextureDesc::Constant(Rgb::splat(default)));
    };
    if let Some(obj) = super::props::resolve(prop, &ctx.ids)? {
        expect_tag(&obj, prop, "texture")?;
        return build_any_texture(ctx, &obj);
    }
    Ok(TextureDesc::Constant(p.rgb(name, Rgb::splat(default))?))
}

/// A texture's `to_uv`: the 4×4 transform acting on (u, v) through its x/y rows and columns.
fn to_uv(p: &Plugin) -> Result<Mat3, SceneError> {
    Ok(match p.transform_opt("to_uv")? {
        None => Mat3::IDENTITY,
        Some((m, _)) => Mat3::from_cols(
            Vec3::new(m.x_axis.x, m.x_axis.y, 0.0),
            Vec3::new(m.y_axis.x, m.y_axis.y, 0.0),
            Vec3::new(m.w_axis.x, m.w_axis.y, 1.0),
        ),
    })
}

/// A texture of any kind this loader reads.
pub(crate) fn build_any_texture(ctx: &Ctx, p: &Rc<Plugin>) -> Result<TextureDesc, SceneError> {
    if p.ty == "checkerboard" {
        build_checkerboard(p)
    } else {
        Ok(TextureDesc::Bitmap(build_texture(ctx, p)?))
    }
}

/// Mitsuba's `checkerboard` (colours 0.4 and 0.2 by default; constant colours only).
fn build_checkerboard(p: &Plugin) -> Result<TextureDesc, SceneError> {
    let colour = |name: &str, default: f32| -> Result<Rgb, SceneError> {
        if let Some(prop) = p.get(name) {
            if matches!(prop.value, Value::Ref(_) | Value::Object(_)) {
                return Err(SceneError::at(
                    prop.loc.clone(),
                    format!("checkerboard's {name} must be a colour or a float, not a texture"),
                ));
            }
        }
        p.rgb(name, Rgb::splat(default))
    };
    let (color0, color1) = (colour("color0", 0.4)?, colour("color1", 0.2)?);
    let to_uv = to_uv(p)?;
    p.check_unused()?;
    Ok(TextureDesc::Checkerboard {
        color0,
        color1,
        to_uv,
    })
}

/// Builds (once per plugin) a `bitmap` texture.
pub(crate) fn build_texture(ctx: &Ctx, p: &Rc<Plugin>) -> Result<Arc<BitmapDesc>, SceneError> {
    let key = Rc::as_ptr(p);
    if let Some(b) = ctx.bitmaps.borrow().get(&key) {
        return Ok(b.clone());
    }
    p.expect_type(TEXTURES)?;
    if p.ty != "bitmap" {
        return Err(p.error(format!(
            "a {} texture cannot serve here: normal and bump maps read a bitmap",
            p.ty
        )));
    }
    let (name, prop) = p
        .string_opt("filename")?
        .ok_or_else(|| p.error("missing \"filename\""))?;
    let path = ctx.resolve_file(name, prop)?;
    let raw = p.boolean("raw", false)?;
    let filter = match p.string_opt("filter_type")? {
        None => TextureFilter::Bilinear,
        Some((s, q)) => match s {
            "bilinear" => TextureFilter::Bilinear,
            "nearest" => TextureFilter::Nearest,
            _ => {
                return Err(SceneError::at(
                    q.loc.clone(),
                    format!("invalid filter_type \"{s}\" (must be \"bilinear\" or \"nearest\")"),
                ))
            }
        },
    };
    let wrap = match p.string_opt("wrap_mode")? {
        None => WrapMode::Repeat,
        Some((s, q)) => match s {
            "repeat" => WrapMode::Repeat,
            "mirror" => WrapMode::Mirror,
            "clamp" => WrapMode::Clamp,
            _ => {
                return Err(SceneError::at(
                    q.loc.clone(),
                    format!(
                        "invalid wrap_mode \"{s}\" (must be \"repeat\", \"mirror\" or \"clamp\")"
                    ),
                ))
            }
        },
    };
    let to_uv = to_uv(p)?;
    let loc = prop.loc.clone();
    p.check_unused()?;
    let image = ctx.image(&path, raw, &loc)?;
    let b = Arc::new(BitmapDesc {
        path,
        image,
        filter,
        wrap,
        to_uv,
    });
    ctx.bitmaps.borrow_mut().insert(key, b.clone());
    Ok(b)
}
