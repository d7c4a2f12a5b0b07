//! Lambertian reflection (Mitsuba 3's `diffuse`): `f = ρ/π`, one-sided, sampled by the cosine
//! hemisphere warp so that every sample's weight is exactly `ρ`.

use super::BsdfSample;
use ircache_math::{sampling, Rgb, Vec2, Vec3, INV_PI};

/// A Lambertian reflector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Diffuse {
    /// Albedo `ρ`.
    pub reflectance: Rgb,
}

impl Diffuse {
    /// `ρ/π · cos θ_i` on the front side.
    #[must_use]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        self.reflectance * (wi.z * INV_PI)
    }

    /// Cosine-weighted density.
    #[must_use]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        sampling::cosine_hemisphere_pdf(wi)
    }

    /// Cosine-weighted sample.
    #[must_use]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = sampling::square_to_cosine_hemisphere(u);
        let pdf = sampling::cosine_hemisphere_pdf(wi);
        if wi.z <= 0.0 || pdf <= 0.0 {
            return None;
        }
        Some(BsdfSample {
            wi,
            pdf,
            weight: self.reflectance,
            delta: false,
            eta: 1.0,
        })
    }
}
