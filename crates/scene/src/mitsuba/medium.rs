//! Media: `homogeneous` and `heterogeneous` with their volumes (`constvolume`, `gridvolume`) and
//! phase functions (`isotropic`, `hg`), read with Mitsuba 3's defaults (albedo 0.75, sigma_t 1,
//! scale 1, `hg`'s g 0.8, volumes over the unit cube mapped by `to_world`). A medium referenced
//! several times is built once and shared. `emission` on a medium is an ircache extension.

use super::props::{Plugin, Value};
use super::{expect_tag, Ctx};
use crate::desc::{
    GridVolumeDesc, MediumDesc, MediumKind, PhaseDesc, TextureFilter, VolumeDesc, WrapMode,
};
use crate::error::SceneError;
use ircache_math::{Mat4, Rgb, Vec3};
use std::rc::Rc;
use std::sync::Arc;

const MEDIA: &[&str] = &["homogeneous", "heterogeneous"];
const VOLUMES: &[&str] = &["constvolume", "gridvolume"];
const PHASES: &[&str] = &["isotropic", "hg"];

/// Builds (once per plugin) a medium; returns its index in the scene's media.
pub(crate) fn build_medium(ctx: &Ctx, p: &Rc<Plugin>) -> Result<usize, SceneError> {
    let key = Rc::as_ptr(p);
    if let Some(&i) = ctx.medium_ids.borrow().get(&key) {
        return Ok(i);
    }
    let m = build_medium_uncached(ctx, p)?;
    let mut media = ctx.media.borrow_mut();
    media.push(m);
    ctx.medium_ids.borrow_mut().insert(key, media.len() - 1);
    Ok(media.len() - 1)
}

fn build_medium_uncached(ctx: &Ctx, p: &Plugin) -> Result<MediumDesc, SceneError> {
    p.expect_type(MEDIA)?;
    let kind = if p.ty == "homogeneous" {
        MediumKind::Homogeneous
    } else {
        MediumKind::Heterogeneous
    };
    let sigma_t = volume_param(ctx, p, "sigma_t", 1.0, "extinction")?;
    if kind == MediumKind::Homogeneous && matches!(sigma_t, VolumeDesc::Grid(_)) {
        let loc = p.get("sigma_t").map_or(p.loc.clone(), |q| q.loc.clone());
        return Err(SceneError::at(
            loc,
            "a homogeneous medium needs a constant sigma_t (use type=\"heterogeneous\" for a grid)",
        ));
    }
    let albedo = volume_param(ctx, p, "albedo", 0.75, "albedo")?;
    check_volume_range(&albedo, 0.0, 1.0, "albedo", p, "albedo")?;
    let emission = if p.has("emission") {
        Some(volume_param(ctx, p, "emission", 0.0, "emitted radiance")?)
    } else {
        None
    };
    let scale = p.float("scale", 1.0)?;
    if !(scale >= 0.0 && scale.is_finite()) {
        return Err(p.error(format!("scale {scale} must be finite and non-negative")));
    }
    let sample_emitters = p.boolean("sample_emitters", true)?;
    let mut phase = None;
    for (obj, prop) in p.objects(&ctx.ids)? {
        match obj.tag.as_str() {
            "phase" if phase.is_none() => phase = Some(build_phase(&obj)?),
            "phase" => {
                return Err(SceneError::at(
                    prop.loc.clone(),
                    "a medium can have only one phase function",
                ))
            }
            // Volumes are read by name above.
            "volume" if p.is_used(&prop.name) => {}
            _ => expect_tag(&obj, prop, "phase")?,
        }
    }
    p.check_unused()?;
    Ok(MediumDesc {
        id: p.id.clone(),
        kind,
        sigma_t,
        albedo,
        emission,
        scale,
        phase: phase.unwrap_or(PhaseDesc::Isotropic),
        sample_emitters,
        location: p.loc.clone(),
    })
}

/// A medium parameter that may be a float, an `<rgb>` or a nested/referenced `<volume>`;
/// checked to be finite and non-negative.
fn volume_param(
    ctx: &Ctx,
    p: &Plugin,
    name: &str,
    default: f32,
    what: &str,
) -> Result<VolumeDesc, SceneError> {
    let Some(prop) = p.get(name) else {
        return Ok(VolumeDesc::constant(Rgb::splat(default)));
    };
    let v = match &prop.value {
        Value::Object(_) | Value::Ref(_) => {
            let obj = super::props::resolve(prop, &ctx.ids)?
                .ok_or_else(|| SceneError::at(prop.loc.clone(), "expected a volume"))?;
            expect_tag(&obj, prop, "volume")?;
            build_volume(ctx, &obj)?
        }
        _ => VolumeDesc::constant(p.rgb(name, Rgb::ZERO)?),
    };
    check_volume_range(&v, 0.0, f32::INFINITY, name, p, what)?;
    Ok(v)
}

/// Errors when a volume's values leave `[lo, hi]` (or are not finite).
fn check_volume_range(
    v: &VolumeDesc,
    lo: f32,
    hi: f32,
    name: &str,
    p: &Plugin,
    what: &str,
) -> Result<(), SceneError> {
    let loc = p.get(name).map_or(p.loc.clone(), |q| q.loc.clone());
    let bad = |x: f32| !(x.is_finite() && x >= lo && x <= hi);
    let range = if hi.is_finite() {
        format!("within [{lo}, {hi}]")
    } else {
        "finite and non-negative".into()
    };
    match v {
        VolumeDesc::Constant { value, .. } => {
            if value.to_array().iter().any(|&x| bad(x)) {
                let a = value.to_array();
                return Err(SceneError::at(
                    loc,
                    format!(
                        "{what} \"{name}\" ({}, {}, {}) must be {range}",
                        a[0], a[1], a[2]
                    ),
                ));
            }
        }
        VolumeDesc::Grid(g) => {
            if let Some(i) = g.data.iter().position(|&x| bad(x)) {
                return Err(SceneError::at(
                    loc,
                    format!(
                        "{what} \"{name}\": sample {i} of {} is {}, it must be {range}",
                        g.path.display(),
                        g.data[i]
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// A `constvolume` or `gridvolume`.
pub(crate) fn build_volume(ctx: &Ctx, p: &Plugin) -> Result<VolumeDesc, SceneError> {
    p.expect_type(VOLUMES)?;
    let to_world = p
        .transform_opt("to_world")?
        .map_or(Mat4::IDENTITY, |(m, _)| m);
    let v = if p.ty == "constvolume" {
        VolumeDesc::Constant {
            value: p.rgb("value", Rgb::splat(0.5))?,
            to_world,
        }
    } else {
        let (name, prop) = p
            .string_opt("filename")?
            .ok_or_else(|| p.error("missing \"filename\""))?;
        let path = ctx.resolve_file(name, prop)?;
        let file =
            crate::volume_file::read_vol(&path).map_err(|message| SceneError::Referenced {
                location: prop.loc.clone(),
                path: path.clone(),
                message,
            })?;
        let filter = match p.string_opt("filter_type")? {
            None | Some(("trilinear", _)) => TextureFilter::Bilinear,
            Some(("nearest", _)) => TextureFilter::Nearest,
            Some((s, q)) => {
                return Err(SceneError::at(
                    q.loc.clone(),
                    format!("invalid filter_type \"{s}\" (must be \"trilinear\" or \"nearest\")"),
                ))
            }
        };
        let wrap = match p.string_opt("wrap_mode")? {
            None | Some(("clamp", _)) => WrapMode::Clamp,
            Some(("repeat", _)) => WrapMode::Repeat,
            Some(("mirror", _)) => WrapMode::Mirror,
            Some((s, q)) => {
                return Err(SceneError::at(
                    q.loc.clone(),
                    format!(
                        "invalid wrap_mode \"{s}\" (must be \"clamp\", \"repeat\" or \"mirror\")"
                    ),
                ))
            }
        };
        // `raw` only changes spectral upsampling, which an RGB renderer does not do.
        let _ = p.boolean("raw", false)?;
        let _ = p.boolean("accel", true)?;
        let to_world = if p.boolean("use_grid_bbox", false)? {
            let (lo, hi) = file.bounds;
            let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
            if !(hi - lo).cmpgt(Vec3::ZERO).all() {
                return Err(p.error("use_grid_bbox: the file's bounding box is empty"));
            }
            to_world * Mat4::from_translation(lo) * Mat4::from_scale(hi - lo)
        } else {
            to_world
        };
        VolumeDesc::Grid(Arc::new(GridVolumeDesc {
            path,
            resolution: file.resolution,
            channels: file.channels,
            data: file.data,
            to_world,
            filter,
            wrap,
        }))
    };
    let to_world = match &v {
        VolumeDesc::Constant { to_world, .. } => *to_world,
        VolumeDesc::Grid(g) => g.to_world,
    };
    if to_world.determinant().abs() <= 0.0 || !to_world.is_finite() {
        return Err(p.error("to_world is singular (the volume has no extent)"));
    }
    p.check_unused()?;
    Ok(v)
}

/// A phase function.
fn build_phase(p: &Plugin) -> Result<PhaseDesc, SceneError> {
    p.expect_type(PHASES)?;
    let phase = if p.ty == "isotropic" {
        PhaseDesc::Isotropic
    } else {
        let g = p.float("g", 0.8)?;
        if !(g > -1.0 && g < 1.0) {
            let loc = p.get("g").map_or(p.loc.clone(), |q| q.loc.clone());
            return Err(SceneError::at(
                loc,
                format!("hg: g = {g} must lie in (−1, 1)"),
            ));
        }
        PhaseDesc::HenyeyGreenstein { g }
    };
    p.check_unused()?;
    Ok(phase)
}
