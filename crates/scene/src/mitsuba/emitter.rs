//! Emitters with Mitsuba 3's defaults: `area` (radiance 1, attached to a shape), `point`
//! (intensity 1, `position` or `to_world`), `spot` (intensity 1, cutoff 20°, beam width ¾ of the
//! cutoff, shining along `to_world`'s +z), `directional` (irradiance 1, `direction` or
//! `to_world`'s +z), `constant` (radiance 1) and `envmap` (`filename`, scale 1, `to_world`).
//! Radiance, irradiance and intensity must be finite and non-negative.

use super::props::{Plugin, Value};
use super::{check_emission, Ctx};
use crate::desc::{EmitterDesc, TextureDesc};
use crate::error::SceneError;
use ircache_math::{Mat4, Rgb, Vec3};

const EMITTERS: &[&str] = &["area", "point", "spot", "directional", "constant", "envmap"];

fn emission(p: &Plugin, name: &str) -> Result<Rgb, SceneError> {
    match p.emission_opt(name)? {
        None => Ok(Rgb::ONE),
        Some((v, prop)) => {
            check_emission(v, name, &prop.loc)?;
            Ok(v)
        }
    }
}

/// An `area` emitter attached to a shape: its radiance, and where that is a texture (Mitsuba's
/// spatially varying `radiance`), the texture with its mean as the radiance.
pub(crate) fn build_area(ctx: &Ctx, p: &Plugin) -> Result<(Rgb, Option<TextureDesc>), SceneError> {
    p.expect_type(EMITTERS)?;
    if p.ty != "area" {
        return Err(p.error("only area emitters can be attached to a shape"));
    }
    let area = match p.get("radiance") {
        Some(prop) if matches!(prop.value, Value::Object(_) | Value::Ref(_)) => {
            let texture = super::bsdf::texture_param(ctx, p, "radiance", 1.0)?;
            (texture_mean(&texture, &prop.loc)?, Some(texture))
        }
        _ => (emission(p, "radiance")?, None),
    };
    p.check_unused()?;
    Ok(area)
}

/// The mean of an emission texture, its values checked as an emission's (finite, non-negative).
fn texture_mean(
    texture: &TextureDesc,
    loc: &crate::error::SourceLocation,
) -> Result<Rgb, SceneError> {
    match texture {
        TextureDesc::Constant(c) => {
            check_emission(*c, "radiance", loc)?;
            Ok(*c)
        }
        TextureDesc::Checkerboard { color0, color1, .. } => {
            check_emission(*color0, "radiance's color0", loc)?;
            check_emission(*color1, "radiance's color1", loc)?;
            Ok((*color0 + *color1) * 0.5)
        }
        TextureDesc::Bitmap(b) => {
            let mut sum = [0.0f64; 3];
            for (i, t) in b.image.pixels.iter().enumerate() {
                if t.to_array().iter().any(|v| !v.is_finite() || *v < 0.0) {
                    let (x, y) = (i % b.image.width, i / b.image.width);
                    check_emission(
                        *t,
                        &format!("radiance texel ({x}, {y}) of {}", b.path.display()),
                        loc,
                    )?;
                }
                for (s, v) in sum.iter_mut().zip(t.to_array()) {
                    *s += f64::from(v);
                }
            }
            let n = b.image.pixels.len().max(1) as f64;
            Ok(Rgb::new(
                (sum[0] / n) as f32,
                (sum[1] / n) as f32,
                (sum[2] / n) as f32,
            ))
        }
    }
}

/// An emitter declared directly in the scene.
pub(crate) fn build_emitter(ctx: &Ctx, p: &Plugin) -> Result<EmitterDesc, SceneError> {
    p.expect_type(EMITTERS)?;
    let e = match p.ty.as_str() {
        "area" => return Err(p.error("an area emitter must be nested inside a <shape>")),
        "point" => {
            let to_world = p.transform_opt("to_world")?;
            let position = p.vector_opt("position")?;
            let position = match (to_world, position) {
                (Some(_), Some((_, prop))) => {
                    return Err(SceneError::at(
                        prop.loc.clone(),
                        "only one of \"position\" and \"to_world\" can be specified",
                    ))
                }
                (Some((m, _)), None) => m.transform_point3(Vec3::ZERO),
                (None, Some((v, _))) => v,
                (None, None) => Vec3::ZERO,
            };
            EmitterDesc::Point {
                position,
                intensity: emission(p, "intensity")?,
            }
        }
        "spot" => {
            let to_world = p
                .transform_opt("to_world")?
                .map_or(Mat4::IDENTITY, |(m, _)| m);
            let intensity = emission(p, "intensity")?;
            let cutoff_angle = match p.float_opt("cutoff_angle")? {
                None => 20.0,
                Some((a, _)) if a > 0.0 && a <= 180.0 => a,
                Some((a, prop)) => {
                    return Err(SceneError::at(
                        prop.loc.clone(),
                        format!("cutoff_angle {a} must lie in (0, 180]"),
                    ))
                }
            };
            let beam_width = match p.float_opt("beam_width")? {
                None => cutoff_angle * 0.75,
                Some((b, _)) if b > 0.0 && b <= cutoff_angle => b,
                Some((b, prop)) => {
                    return Err(SceneError::at(
                        prop.loc.clone(),
                        format!("beam_width {b} must lie in (0, cutoff_angle = {cutoff_angle}]"),
                    ))
                }
            };
            EmitterDesc::Spot {
                to_world,
                intensity,
                cutoff_angle,
                beam_width,
            }
        }
        "directional" => {
            let to_world = p.transform_opt("to_world")?;
            let direction = p.vector_opt("direction")?;
            let (d, loc) = match (to_world, direction) {
                (Some(_), Some((_, prop))) => {
                    return Err(SceneError::at(
                        prop.loc.clone(),
                        "only one of \"direction\" and \"to_world\" can be specified",
                    ))
                }
                (Some((m, prop)), None) => (m.transform_vector3(Vec3::Z), prop.loc.clone()),
                (None, Some((v, prop))) => (v, prop.loc.clone()),
                (None, None) => (Vec3::Z, p.loc.clone()),
            };
            let len = d.length();
            if !(len > 0.0 && len.is_finite()) {
                return Err(SceneError::at(
                    loc,
                    "direction must be a nonzero, finite vector",
                ));
            }
            EmitterDesc::Directional {
                direction: d / len,
                irradiance: emission(p, "irradiance")?,
            }
        }
        "constant" => EmitterDesc::Constant {
            radiance: emission(p, "radiance")?,
        },
        _ => {
            // envmap
            let (name, prop) = p
                .string_opt("filename")?
                .ok_or_else(|| p.error("missing \"filename\""))?;
            let path = ctx.resolve_file(name, prop)?;
            let loc = prop.loc.clone();
            let scale = match p.float_opt("scale")? {
                None => 1.0,
                Some((s, _)) if s >= 0.0 && s.is_finite() => s,
                Some((s, prop)) => {
                    return Err(SceneError::at(
                        prop.loc.clone(),
                        format!("scale {s} must be finite and non-negative"),
                    ))
                }
            };
            let to_world = p
                .transform_opt("to_world")?
                .map_or(Mat4::IDENTITY, |(m, _)| m);
            p.check_unused()?;
            let image = ctx.image(&path, false, &loc)?;
            if let Some(bad) = image
                .pixels
                .iter()
                .find(|c| c.to_array().iter().any(|v| !v.is_finite() || *v < 0.0))
            {
                return Err(SceneError::Referenced {
                    location: loc,
                    path,
                    message: format!(
                        "environment map has a NaN, infinite or negative pixel {bad:?}"
                    ),
                });
            }
            EmitterDesc::Envmap {
                path,
                image,
                to_world,
                scale,
            }
        }
    };
    p.check_unused()?;
    Ok(e)
}
