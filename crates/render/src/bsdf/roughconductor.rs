//! Rough conductor (Mitsuba 3's `roughconductor`): a Torrance–Sparrow microfacet BRDF
//! `f = F(wo·h) D(h) G(wo, wi, h) / (4 cos θ_o cos θ_i)` with Beckmann or GGX normals (Walter et
//! al. 2007), the conductor Fresnel term and Smith's separable shadowing–masking. Sampled by
//! visible normals (Heitz 2018 for GGX), so that the weight is `F · G1(wi, h) · specular_reflectance`.
//! One-sided; samples reflected below the horizon are rejected (they carry no energy: this is
//! the energy loss of single-scattering microfacet models at high roughness).

use super::fresnel::{fresnel_conductor, reflect_about};
use super::microfacet::Microfacet;
use super::BsdfSample;
use ircache_math::{Rgb, Vec2, Vec3};

/// A rough conductor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughConductor {
    /// Microfacet distribution.
    pub distr: Microfacet,
    /// Real part of the relative index.
    pub eta: Rgb,
    /// Imaginary part.
    pub k: Rgb,
    /// Scale.
    pub specular_reflectance: Rgb,
}

impl RoughConductor {
    /// `f · cos θ_i = F D G / (4 cos θ_o)`.
    #[must_use]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let h = (wo + wi).normalize();
        let d = self.distr.eval(h);
        if d == 0.0 {
            return Rgb::ZERO;
        }
        let g = self.distr.g(wo, wi, h);
        let f = fresnel_conductor(wo.dot(h), self.eta, self.k);
        self.specular_reflectance * f * (d * g / (4.0 * wo.z))
    }

    /// Visible-normal density mapped to `wi`: `D(h) G1(wo, h) / (4 cos θ_o)`.
    #[must_use]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        if wo.dot(h) <= 0.0 || wi.dot(h) <= 0.0 {
            return 0.0;
        }
        self.distr.eval(h) * self.distr.smith_g1(wo, h) / (4.0 * wo.z)
    }

    /// Samples a visible normal and reflects `wo` about it.
    #[must_use]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let m = self.distr.sample_visible(wo, u);
        let wi = reflect_about(wo, m).normalize();
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let h = (wo + wi).normalize();
        let f = fresnel_conductor(wo.dot(h), self.eta, self.k);
        let weight = self.specular_reflectance * f * self.distr.smith_g1(wi, h);
        Some(BsdfSample {
            wi,
            pdf,
            weight,
            delta: false,
            eta: 1.0,
        })
    }
}
