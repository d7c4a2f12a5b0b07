//! Wavefront MTL material: a Lambertian lobe plus the normalised modified Phong lobe (Lafortune
//! and Willems 1994, "Using the modified Phong reflectance model for physically based rendering"):
//!
//! `f = K_d/π + K_s (n + 2)/(2π) cos^n α`, with `α` the angle between `wi` and the mirror
//! reflection of `wo`. The `(n + 2)/(2π)` normalisation makes the specular albedo at normal
//! incidence exactly `K_s` (and less elsewhere), so `K_d + K_s ≤ 1` conserves energy.
//!
//! Sampling picks the specular lobe with probability `k̄_s/(k̄_d + k̄_s)` (mean albedos), drawing
//! `cos α = u^{1/(n+1)}` around the mirror direction (density `(n + 1)/(2π) cos^n α`), otherwise a
//! cosine-weighted direction; the pdf is the mixture and the weight `eval / pdf`. One-sided.

use super::fresnel::reflect;
use super::BsdfSample;
use ircache_math::sampling::sin_cos_turn;
use ircache_math::{sampling, Frame, Rgb, Vec2, Vec3, INV_PI, PI};

/// A diffuse + normalised Phong material at one surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phong {
    /// Diffuse albedo `K_d`.
    pub diffuse: Rgb,
    /// Specular albedo `K_s`.
    pub specular: Rgb,
    /// Exponent `n ≥ 0`.
    pub exponent: f32,
}

impl Phong {
    fn prob_specular(&self) -> f32 {
        let (d, s) = (self.diffuse.mean().max(0.0), self.specular.mean().max(0.0));
        if d + s > 0.0 {
            s / (d + s)
        } else {
            0.0
        }
    }

    fn cos_alpha(wo: Vec3, wi: Vec3) -> f32 {
        wi.dot(reflect(wo)).clamp(0.0, 1.0)
    }

    /// `f · cos θ_i`.
    #[must_use]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let c = Self::cos_alpha(wo, wi);
        let spec = if c > 0.0 {
            (self.exponent + 2.0) / (2.0 * PI) * c.powf(self.exponent)
        } else {
            0.0
        };
        (self.diffuse * INV_PI + self.specular * spec) * wi.z
    }

    /// The Phong lobe alone, `f_s · cos θ_i`.
    #[must_use]
    pub fn eval_specular(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let c = Self::cos_alpha(wo, wi);
        if c <= 0.0 {
            return Rgb::ZERO;
        }
        self.specular * ((self.exponent + 2.0) / (2.0 * PI) * c.powf(self.exponent) * wi.z)
    }

    /// Density of the Phong lobe's sampling alone.
    #[must_use]
    pub fn pdf_specular(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let c = Self::cos_alpha(wo, wi);
        if c > 0.0 {
            (self.exponent + 1.0) / (2.0 * PI) * c.powf(self.exponent)
        } else {
            0.0
        }
    }

    /// Samples the Phong lobe alone, weight `eval_specular / pdf_specular`.
    #[must_use]
    pub fn sample_specular(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 || self.specular.is_black() {
            return None;
        }
        let wi = self.sample_lobe(wo, u);
        BsdfSample::smooth_reflection(wi, self.pdf_specular(wo, wi), || self.eval_specular(wo, wi))
    }

    /// A direction around the mirror direction with density ∝ cos^n α.
    fn sample_lobe(&self, wo: Vec3, u: Vec2) -> Vec3 {
        let cos_a = u.x.powf(1.0 / (self.exponent + 1.0));
        let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
        let (sin, cos) = sin_cos_turn(u.y);
        let local = Vec3::new(sin_a * cos, sin_a * sin, cos_a);
        Frame::from_z(reflect(wo).normalize()).from_local(local)
    }

    /// Mixture density.
    #[must_use]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let ps = self.prob_specular();
        let c = Self::cos_alpha(wo, wi);
        let spec = if c > 0.0 {
            (self.exponent + 1.0) / (2.0 * PI) * c.powf(self.exponent)
        } else {
            0.0
        };
        ps * spec + (1.0 - ps) * sampling::cosine_hemisphere_pdf(wi)
    }

    /// Chooses a lobe by albedo and samples it.
    #[must_use]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if u_lobe < self.prob_specular() {
            self.sample_lobe(wo, u)
        } else {
            sampling::square_to_cosine_hemisphere(u)
        };
        BsdfSample::smooth_reflection(wi, self.pdf(wo, wi), || self.eval(wo, wi))
    }
}
