//! Rough dielectric interface (Mitsuba 3's `roughdielectric`): microfacet reflection and
//! refraction (Walter, Marschner, Li, Torrance 2007, "Microfacet Models for Refraction through
//! Rough Surfaces", eqs. 16–21) with Beckmann or GGX normals and Smith's separable masking.
//!
//! Seen from `wo` with `η = η_t/η_i` (`int_ior/ext_ior` from the front, its reciprocal from the
//! back), the generalised half-vector is `m ∝ wo + η_w wi` (`η_w` 1 for reflection, η for
//! refraction; Walter eq. 16), turned to the upper hemisphere. With `f · |cos θ_i|` returned:
//! - reflection `F D G / (4 |cos θ_o|)`;
//! - refraction `(1 − F) D G |wo·m| |wi·m| / (|cos θ_o| (wo·m + η wi·m)²)`: Walter's eq. 21 times
//!   `|cos θ_i|` and the radiance scaling `1/η²` (which cancels his `η²`), as Mitsuba's radiance
//!   mode; a photon undoes `1/η²` through the sample's `eta`.
//!
//! Sampling draws a normal visible from `wo` (Heitz 2018), then reflection with probability
//! `F(wo·m)`, else refraction; the density maps through `|∂m/∂wi|` (`1/(4 |wi·m|)`, or
//! `η² |wi·m| / (wo·m + η wi·m)²`; Walter eqs. 14, 17), and the weight, `eval / pdf`, is `G1(wi, m)`
//! times the scale (and `1/η²` for refraction). A direction sent to the wrong side of the macro-surface
//! carries no light (its masking vanishes) and is rejected.

use super::fresnel::{fresnel_dielectric, reflect_about};
use super::microfacet::Microfacet;
use super::BsdfSample;
use ircache_math::{Rgb, Vec2, Vec3};

/// A rough dielectric interface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric {
    /// Microfacet distribution.
    pub distr: Microfacet,
    /// Relative index of refraction (interior / exterior).
    pub eta: f32,
    /// Reflection scale.
    pub specular_reflectance: Rgb,
    /// Transmission scale.
    pub specular_transmittance: Rgb,
}

/// The microfacet normal joining `wo` and `wi`, with what eval and pdf share; `None` where no
/// microfacet can join them from the sides they are on.
struct HalfVector {
    m: Vec3,
    reflect: bool,
    /// `η_t/η_i` seen from `wo`.
    eta: f32,
    /// `wo·m`, `wi·m`.
    o_m: f32,
    i_m: f32,
}

impl RoughDielectric {
    fn half_vector(&self, wo: Vec3, wi: Vec3) -> Option<HalfVector> {
        if wo.z == 0.0 || wi.z == 0.0 {
            return None;
        }
        let reflect = wo.z * wi.z > 0.0;
        let eta = if wo.z > 0.0 { self.eta } else { 1.0 / self.eta };
        let h = wo + wi * if reflect { 1.0 } else { eta };
        let length = h.length();
        if length.is_nan() || length <= 0.0 {
            return None;
        }
        let m = h / length;
        let m = if m.z < 0.0 { -m } else { m };
        let (o_m, i_m) = (wo.dot(m), wi.dot(m));
        // Neither direction may see the back of the microfacet.
        if o_m * wo.z <= 0.0 || i_m * wi.z <= 0.0 {
            return None;
        }
        Some(HalfVector {
            m,
            reflect,
            eta,
            o_m,
            i_m,
        })
    }

    /// `f · |cos θ_i|` (module doc).
    #[must_use]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        let Some(hv) = self.half_vector(wo, wi) else {
            return Rgb::ZERO;
        };
        let d = self.distr.eval(hv.m);
        if d == 0.0 {
            return Rgb::ZERO;
        }
        let g = self.distr.g(wo, wi, hv.m);
        let f = fresnel_dielectric(hv.o_m, self.eta).r;
        if hv.reflect {
            self.specular_reflectance * (f * d * g / (4.0 * wo.z.abs()))
        } else {
            let denom = hv.o_m + hv.eta * hv.i_m;
            let value = (1.0 - f) * d * g * (hv.o_m * hv.i_m).abs() / (wo.z.abs() * denom * denom);
            if value.is_finite() {
                self.specular_transmittance * value
            } else {
                Rgb::ZERO
            }
        }
    }

    /// Solid-angle density of [`Self::sample`] at `wi`.
    #[must_use]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some(hv) = self.half_vector(wo, wi) else {
            return 0.0;
        };
        let up = if wo.z > 0.0 { wo } else { -wo };
        let visible = self.distr.pdf_visible(up, hv.m);
        let f = fresnel_dielectric(hv.o_m, self.eta).r;
        let pdf = if hv.reflect {
            visible * f / (4.0 * hv.i_m.abs())
        } else {
            let denom = hv.o_m + hv.eta * hv.i_m;
            visible * (1.0 - f) * hv.eta * hv.eta * hv.i_m.abs() / (denom * denom)
        };
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// Samples a visible normal, then reflection or refraction about it by Fresnel.
    #[must_use]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let up = if wo.z > 0.0 { wo } else { -wo };
        let m = self.distr.sample_visible(up, u);
        let fresnel = fresnel_dielectric(wo.dot(m), self.eta);
        let (wi, eta) = if u_lobe < fresnel.r {
            let wi = reflect_about(wo, m).normalize();
            if wi.z * wo.z <= 0.0 {
                return None;
            }
            (wi, 1.0)
        } else {
            // Refraction about m (Walter eq. 40, as Mitsuba's `refract`).
            let wi = (m * (wo.dot(m) * fresnel.eta_ti + fresnel.cos_theta_t) - wo * fresnel.eta_ti)
                .normalize();
            if wi.z * wo.z >= 0.0 {
                return None;
            }
            (wi, fresnel.eta_it)
        };
        // eval / pdf is the scale times G1(wi, m) (times 1/η² for refraction), but near grazing
        // views m recomputed from (wo, wi) differs from the sampled one by rounding: the
        // quotient keeps the weight consistent with eval and pdf.
        BsdfSample::smooth(wi, self.pdf(wo, wi), || self.eval(wo, wi), eta)
    }
}
