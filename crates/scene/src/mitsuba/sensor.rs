//! Sensors (`perspective`, `thinlens`, `orthographic`), film (`hdrfilm`), reconstruction filters, samplers and integrators,
//! with Mitsuba 3's defaults.

use super::props::{Plugin, Value};
use super::{expect_tag, Ctx};
use crate::desc::{
    FilmDesc, FilterDesc, FovAxis, IntegratorDesc, ParamValue, Projection, SensorDesc,
};
use crate::error::SceneError;
use ircache_math::{Mat4, Rgb};

const SENSORS: &[&str] = &["perspective", "thinlens", "orthographic"];
const FILMS: &[&str] = &["hdrfilm"];
const FILTERS: &[&str] = &[
    "box",
    "tent",
    "gaussian",
    "mitchell",
    "catmullrom",
    "lanczos",
];
const SAMPLERS: &[&str] = &[
    "independent",
    "stratified",
    "multijitter",
    "ldsampler",
    "orthogonal",
    "sobol",
];
const INTEGRATORS: &[&str] = &[
    "path",
    "volpath",
    "direct",
    "irrcache",
    "volpathmis",
    "prb",
    "prbvolpath",
];

/// Mitsuba integrators that render what one of ours renders, by another sampling (spectral MIS)
/// or for derivatives, with the same parameters: read as that one.
const SAME_IMAGE_AS: &[(&str, &str)] = &[
    ("volpathmis", "volpath"),
    ("prb", "path"),
    ("prbvolpath", "volpath"),
];

/// A projective sensor (`perspective`, `thinlens` or `orthographic`) with its film and sampler.
pub(crate) fn build_sensor(ctx: &Ctx, p: &Plugin) -> Result<SensorDesc, SceneError> {
    p.expect_type(SENSORS)?;
    let to_world = p
        .transform_opt("to_world")?
        .map_or(Mat4::IDENTITY, |(m, _)| m);
    let films = p.objects_of(&ctx.ids, "film")?;
    if films.len() > 1 {
        return Err(SceneError::at(
            films[1].1.loc.clone(),
            "a sensor can have only one <film>",
        ));
    }
    let film = match films.first() {
        Some((f, _)) => build_film(ctx, f)?,
        None => FilmDesc {
            width: 768,
            height: 576,
            filter: FilterDesc::Gaussian { stddev: 0.5 },
        },
    };
    let samplers = p.objects_of(&ctx.ids, "sampler")?;
    if samplers.len() > 1 {
        return Err(SceneError::at(
            samplers[1].1.loc.clone(),
            "a sensor can have only one <sampler>",
        ));
    }
    let sampler = match samplers.first() {
        Some((s, _)) => build_sampler(s)?,
        None => SamplerParams::default(),
    };
    // The medium the camera sits in (Mitsuba: a bare `<ref id>` or nested `<medium>`).
    let mut medium = None;
    for (obj, prop) in p.objects(&ctx.ids)? {
        match obj.tag.as_str() {
            "film" | "sampler" => {}
            "medium" if medium.is_none() => {
                medium = Some(super::medium::build_medium(ctx, &obj)?);
            }
            "medium" => {
                return Err(SceneError::at(
                    prop.loc.clone(),
                    "a sensor can be inside only one medium",
                ))
            }
            _ => expect_tag(&obj, prop, "film, sampler or medium")?,
        }
    }

    let (fov_degrees, fov_axis) = if p.ty == "orthographic" {
        // Unused: the to_world scale sets an orthographic camera's extent.
        (90.0, FovAxis::X)
    } else if p.has("fov") && p.has("focal_length") {
        let loc = p
            .get("focal_length")
            .map(|q| q.loc.clone())
            .unwrap_or(p.loc.clone());
        return Err(SceneError::at(loc, "specify either a focal length (\"focal_length\") or a field of view (\"fov\"), not both"));
    } else if let Some((fov, prop)) = p.float_opt("fov")? {
        if !(fov > 0.0 && fov < 180.0) {
            return Err(SceneError::at(
                prop.loc.clone(),
                format!("fov {fov} must lie in (0, 180) degrees"),
            ));
        }
        let axis = match p.string_opt("fov_axis")? {
            None => FovAxis::X,
            Some((s, prop)) => match s.to_ascii_lowercase().as_str() {
                "x" => FovAxis::X,
                "y" => FovAxis::Y,
                "diagonal" => FovAxis::Diagonal,
                "smaller" => FovAxis::Smaller,
                "larger" => FovAxis::Larger,
                _ => {
                    return Err(SceneError::at(
                        prop.loc.clone(),
                        format!("fov_axis \"{s}\" must be one of \"x\", \"y\", \"diagonal\", \"smaller\" or \"larger\""),
                    ))
                }
            },
        };
        (fov, axis)
    } else {
        let (text, loc) = match p.string_opt("focal_length")? {
            Some((s, prop)) => (s.to_string(), prop.loc.clone()),
            None => ("50mm".to_string(), p.loc.clone()),
        };
        let num = text.trim().strip_suffix("mm").unwrap_or(text.trim());
        let f: f64 = num
            .trim()
            .parse()
            .ok()
            .filter(|f: &f64| *f > 0.0 && f.is_finite())
            .ok_or_else(|| {
                SceneError::at(
                    loc,
                    format!("could not parse focal_length \"{text}\" (expected e.g. \"50mm\")"),
                )
            })?;
        // Mitsuba: a 35 mm film's diagonal field of view.
        let fov = 2.0
            * ((36.0f64 * 36.0 + 24.0 * 24.0).sqrt() / (2.0 * f))
                .atan()
                .to_degrees();
        (fov as f32, FovAxis::Diagonal)
    };
    let near_clip = p.float("near_clip", 1e-2)?;
    let far_clip = p.float("far_clip", 1e4)?;
    if near_clip.is_nan() || near_clip <= 0.0 {
        return Err(p.error(format!("near_clip {near_clip} must be greater than zero")));
    }
    if far_clip.is_nan() || near_clip >= far_clip {
        return Err(p.error(format!(
            "near_clip {near_clip} must be smaller than far_clip {far_clip}"
        )));
    }
    // Read by all of Mitsuba's projective cameras, used by the thin lens alone.
    let (focus_distance, focus_prop) = match p.float_opt("focus_distance")? {
        Some((f, prop)) => (f, Some(prop.loc.clone())),
        None => (far_clip, None),
    };
    let projection = match p.ty.as_str() {
        "thinlens" => {
            let (aperture_radius, prop) = p.float_opt("aperture_radius")?.ok_or_else(|| {
                p.error("a thinlens sensor needs an \"aperture_radius\" (Mitsuba has no default)")
            })?;
            if !(aperture_radius.is_finite() && aperture_radius >= 0.0) {
                return Err(SceneError::at(
                    prop.loc.clone(),
                    format!("aperture_radius {aperture_radius} must be finite and not negative"),
                ));
            }
            if !(focus_distance.is_finite() && focus_distance > 0.0) {
                return Err(SceneError::at(
                    focus_prop.unwrap_or(p.loc.clone()),
                    format!("focus_distance {focus_distance} must be finite and greater than zero"),
                ));
            }
            // As Mitsuba: a scale would change the aperture and the focus with the frame.
            if has_scale(&to_world) {
                return Err(p.error(
                    "a thinlens sensor's to_world must not scale (Mitsuba refuses it too)",
                ));
            }
            Projection::ThinLens {
                aperture_radius,
                focus_distance,
            }
        }
        "orthographic" => Projection::Orthographic,
        _ => Projection::Pinhole,
    };
    p.check_unused()?;
    Ok(SensorDesc {
        to_world,
        fov_degrees,
        fov_axis,
        near_clip,
        far_clip,
        film,
        spp: sampler.spp,
        sampler: sampler.kind,
        sampler_seed: sampler.seed,
        jitter: sampler.jitter,
        medium,
        projection,
    })
}

/// Whether the linear part of `m` changes lengths (a column's length off 1 by more than 10⁻³).
fn has_scale(m: &Mat4) -> bool {
    [m.x_axis, m.y_axis, m.z_axis]
        .iter()
        .any(|c| (c.truncate().length() - 1.0).abs() > 1e-3)
}

fn build_film(ctx: &Ctx, p: &Plugin) -> Result<FilmDesc, SceneError> {
    p.expect_type(FILMS)?;
    let width = positive_size(p, "width", 768)?;
    let height = positive_size(p, "height", 576)?;
    check_choice(p, "file_format", &["openexr", "exr", "rgbe", "hdr", "pfm"])?;
    check_choice(
        p,
        "pixel_format",
        &["luminance", "luminance_alpha", "rgb", "rgba", "xyz", "xyza"],
    )?;
    check_choice(p, "component_format", &["float16", "float32", "uint32"])?;
    if p.boolean("sample_border", false)? {
        return Err(p.error("sample_border=true is not supported"));
    }
    let filters = p.objects_of(&ctx.ids, "rfilter")?;
    if filters.len() > 1 {
        return Err(SceneError::at(
            filters[1].1.loc.clone(),
            "a film can have only one <rfilter>",
        ));
    }
    let filter = match filters.first() {
        Some((f, _)) => build_filter(f)?,
        None => FilterDesc::Gaussian { stddev: 0.5 },
    };
    p.check_unused()?;
    Ok(FilmDesc {
        width,
        height,
        filter,
    })
}

fn positive_size(p: &Plugin, name: &str, default: i64) -> Result<u32, SceneError> {
    match p.integer_opt(name)? {
        None => Ok(default as u32),
        Some((v, prop)) if (1..=65536).contains(&v) => {
            let _ = prop;
            Ok(v as u32)
        }
        Some((v, prop)) => Err(SceneError::at(
            prop.loc.clone(),
            format!("{name} {v} must lie in 1..=65536"),
        )),
    }
}

fn check_choice(p: &Plugin, name: &str, allowed: &[&str]) -> Result<(), SceneError> {
    if let Some((v, prop)) = p.string_opt(name)? {
        if !allowed.contains(&v.to_ascii_lowercase().as_str()) {
            return Err(SceneError::at(
                prop.loc.clone(),
                format!("{name} \"{v}\" is not one of {}", allowed.join(", ")),
            ));
        }
    }
    Ok(())
}

fn build_filter(p: &Plugin) -> Result<FilterDesc, SceneError> {
    p.expect_type(FILTERS)?;
    let positive = |name: &str, default: f32| -> Result<f32, SceneError> {
        match p.float_opt(name)? {
            None => Ok(default),
            Some((v, _)) if v > 0.0 && v.is_finite() => Ok(v),
            Some((v, prop)) => Err(SceneError::at(
                prop.loc.clone(),
                format!("{name} {v} must be positive"),
            )),
        }
    };
    let f = match p.ty.as_str() {
        "box" => {
            let r = positive("radius", 0.5)?;
            if r != 0.5 {
                return Err(p.error(format!(
                    "radius {r}: Mitsuba 3's box filter has no radius (it is the pixel's own box, \
                     0.5); a wider filter is a tent or a gaussian"
                )));
            }
            FilterDesc::Box
        }
        "tent" => FilterDesc::Tent {
            radius: positive("radius", 1.0)?,
        },
        "mitchell" => FilterDesc::Mitchell {
            b: p.float("B", 1.0 / 3.0)?,
            c: p.float("C", 1.0 / 3.0)?,
        },
        "catmullrom" => FilterDesc::Mitchell { b: 0.0, c: 0.5 },
        "lanczos" => match p.integer_opt("lobes")? {
            None => FilterDesc::Lanczos { lobes: 3 },
            Some((n, _)) if (1..=16).contains(&n) => FilterDesc::Lanczos { lobes: n as u32 },
            Some((n, prop)) => {
                return Err(SceneError::at(
                    prop.loc.clone(),
                    format!("lobes {n} must lie in [1, 16]"),
                ))
            }
        },
        _ => FilterDesc::Gaussian {
            stddev: positive("stddev", 0.5)?,
        },
    };
    p.check_unused()?;
    Ok(f)
}

/// A `<sampler>`'s parameters.
struct SamplerParams {
    kind: String,
    spp: u32,
    seed: u64,
    jitter: bool,
}

impl Default for SamplerParams {
    /// Mitsuba's: `independent`, 4 samples.
    fn default() -> Self {
        SamplerParams {
            kind: "independent".into(),
            spp: 4,
            seed: 0,
            jitter: true,
        }
    }
}

fn build_sampler(p: &Plugin) -> Result<SamplerParams, SceneError> {
    p.expect_type(SAMPLERS)?;
    let spp = match p.integer_opt("sample_count")? {
        None => 4,
        Some((v, _)) if (1..=i64::from(u32::MAX)).contains(&v) => v as u32,
        Some((v, prop)) => {
            return Err(SceneError::at(
                prop.loc.clone(),
                format!("sample_count {v} must be positive"),
            ))
        }
    };
    let seed = match p.integer_opt("seed")? {
        None => 0,
        Some((v, prop)) => u64::try_from(v).map_err(|_| {
            SceneError::at(prop.loc.clone(), format!("seed {v} must not be negative"))
        })?,
    };
    let jitter = match p.ty.as_str() {
        "stratified" | "multijitter" | "orthogonal" => p.boolean("jitter", true)?,
        _ => true,
    };
    if p.ty == "orthogonal" {
        if let Some((v, prop)) = p.integer_opt("strength")? {
            if v != 2 {
                return Err(SceneError::at(
                    prop.loc.clone(),
                    format!("orthogonal strength {v}: only strength 2 is supported"),
                ));
            }
        }
    }
    p.check_unused()?;
    Ok(SamplerParams {
        kind: p.ty.clone(),
        spp,
        seed,
        jitter,
    })
}

/// The integrator: `path`, `direct`, or `irrcache` (whose extra parameters are kept).
pub(crate) fn build_integrator(p: &Plugin) -> Result<IntegratorDesc, SceneError> {
    // An integrator this renderer lacks (another renderer's plugin) does not stop the scene from
    // loading: the command line may name another; rendering with it is the error.
    if let Err(e) = p.expect_type(INTEGRATORS) {
        return Ok(IntegratorDesc {
            kind: p.ty.clone(),
            unusable: Some(e.to_string()),
            ..IntegratorDesc::default()
        });
    }
    let kind = SAME_IMAGE_AS
        .iter()
        .find(|(theirs, _)| *theirs == p.ty)
        .map_or(p.ty.as_str(), |(_, ours)| ours);
    let mut d = IntegratorDesc {
        kind: kind.to_string(),
        ..IntegratorDesc::default()
    };
    d.hide_emitters = p.boolean("hide_emitters", false)?;
    // Mitsuba's differentiable integrators stop at depth 6 unless told otherwise.
    if matches!(p.ty.as_str(), "prb" | "prbvolpath") {
        d.max_depth = 6;
    }
    // Spectral MIS acts only between wavelengths, which an RGB renderer does not sample.
    if p.ty == "volpathmis" {
        let _ = p.boolean("use_spectral_mis", true)?;
    }
    match p.ty.as_str() {
        "direct" => {
            let shading = count(p, "shading_samples", 1)?;
            d.emitter_samples = count(p, "emitter_samples", shading)?;
            d.bsdf_samples = count(p, "bsdf_samples", shading)?;
            // Direct illumination: emitters seen directly plus one bounce to a light.
            d.max_depth = 2;
        }
        _ => {
            if let Some((v, prop)) = p.integer_opt("max_depth")? {
                if v < -1 || v > i64::from(i32::MAX) {
                    return Err(SceneError::at(
                        prop.loc.clone(),
                        format!("max_depth {v} must be -1 (unbounded) or a value >= 0"),
                    ));
                }
                d.max_depth = v as i32;
            }
            if let Some((v, prop)) = p.integer_opt("rr_depth")? {
                if v <= 0 || v > i64::from(u32::MAX) {
                    return Err(SceneError::at(
                        prop.loc.clone(),
                        format!("rr_depth {v} must be greater than zero"),
                    ));
                }
                d.rr_depth = v as u32;
            }
        }
    }
    if p.ty == "irrcache" {
        for prop in &p.props {
            if p.has(&prop.name) && !prop_used(p, &prop.name) {
                let value = match &prop.value {
                    Value::Float(v) => ParamValue::Float(*v),
                    Value::Integer(v) => ParamValue::Integer(*v),
                    Value::Boolean(v) => ParamValue::Boolean(*v),
                    Value::String(v) => ParamValue::String(v.clone()),
                    Value::Rgb(v) => ParamValue::Rgb(Rgb::new(v[0] as f32, v[1] as f32, v[2] as f32)),
                    Value::Spectrum(v) => ParamValue::Rgb(Rgb::splat(*v as f32)),
                    other => {
                        return Err(SceneError::at(
                            prop.loc.clone(),
                            format!(
                                "parameter \"{}\" of the irrcache integrator: values of type {} are not supported",
                                prop.name,
                                other.type_name()
                            ),
                        ))
                    }
                };
                let _ = p.get(&prop.name);
                d.extra.push((prop.name.clone(), value, prop.loc.clone()));
            }
        }
    }
    p.check_unused()?;
    Ok(d)
}

/// Whether the builder has read `name` yet: probe without marking.
fn prop_used(p: &Plugin, name: &str) -> bool {
    p.is_used(name)
}

fn count(p: &Plugin, name: &str, default: u32) -> Result<u32, SceneError> {
    match p.integer_opt(name)? {
        None => Ok(default),
        Some((v, _)) if (1..=i64::from(u32::MAX)).contains(&v) => Ok(v as u32),
        Some((v, prop)) => Err(SceneError::at(
            prop.loc.clone(),
            format!("{name} {v} must be positive"),
        )),
    }
}
