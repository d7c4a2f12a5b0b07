//! Irradiance cache records (plain data) and Ward's split-sphere weight (000 eqs. 3.7–3.10,
//! 3.15).

use ircache_math::{Rgb, Vec3};

/// One cached irradiance value with what is needed to interpolate it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    /// Position.
    pub p: Vec3,
    /// Unit normal of the side the hemisphere was gathered on.
    pub n: Vec3,
    /// Indirect irradiance.
    pub e: Rgb,
    /// Harmonic mean distance (3.8) after the spacing and gradient limits.
    pub r: f32,
    /// World-space translational gradient per channel (R, G, B).
    pub grad_t: [Vec3; 3],
    /// World-space rotational gradient per channel (R, G, B).
    pub grad_r: [Vec3; 3],
    /// Bounce level: 0 for irradiance seen by the camera's surfaces, 1 for the surfaces seen by
    /// level-0 gather rays, ...
    pub level: u8,
}

/// Which gradients interpolation uses (`--gradients`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum GradientMode {
    /// Plain weighted average (3.9).
    None,
    /// Rotational gradient only.
    Rotation,
    /// Rotational and translational gradients (3.15).
    #[default]
    Full,
}

impl GradientMode {
    /// Parses `none`, `rotation` or `full`.
    pub fn parse(s: &str) -> Result<GradientMode, String> {
        match s {
            "none" => Ok(GradientMode::None),
            "rotation" => Ok(GradientMode::Rotation),
            "full" => Ok(GradientMode::Full),
            _ => Err(format!(
                "unknown gradient mode \"{s}\" (expected none, rotation or full)"
            )),
        }
    }

    /// The name `parse` accepts.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            GradientMode::None => "none",
            GradientMode::Rotation => "rotation",
            GradientMode::Full => "full",
        }
    }
}

/// The split-sphere error ε_i(x, n) = ‖x − x_i‖/R_i + √(1 − n·n_i) (3.10's denominator), or
/// `None` when the record lies in front of the query point (Ward 1988: it would see occluders
/// the point does not). The test is an angle, so it is scale-free: the record is rejected when
/// it sits more than about 3° above the mean tangent plane as seen from x.
#[inline]
#[must_use]
pub fn split_sphere_error(rec: &Record, p: Vec3, n: Vec3) -> Option<f32> {
    let d = p - rec.p;
    let dist2 = d.length_squared();
    let cos = n.dot(rec.n).min(1.0);
    let e = dist2.sqrt() / rec.r + (1.0 - cos).max(0.0).sqrt();
    let front = d.dot(n + rec.n);
    if front < -0.1 * dist2.sqrt() {
        return None;
    }
    Some(e)
}

/// Weight 1/ε (3.10), bounded where ε vanishes.
#[inline]
#[must_use]
pub fn weight(error: f32, accuracy: f32) -> f32 {
    1.0 / error.max(1e-4 * accuracy)
}

/// The record's value extrapolated to (p, n) by 3.15 with the gradients `mode` selects.
#[inline]
#[must_use]
pub fn extrapolate(rec: &Record, p: Vec3, n: Vec3, mode: GradientMode) -> Rgb {
    let mut e = rec.e;
    if mode != GradientMode::None {
        let axis = rec.n.cross(n);
        e += Rgb::new(
            axis.dot(rec.grad_r[0]),
            axis.dot(rec.grad_r[1]),
            axis.dot(rec.grad_r[2]),
        );
    }
    if mode == GradientMode::Full {
        let d = p - rec.p;
        e += Rgb::new(
            d.dot(rec.grad_t[0]),
            d.dot(rec.grad_t[1]),
            d.dot(rec.grad_t[2]),
        );
    }
    e
}
