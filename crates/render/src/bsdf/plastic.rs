//! Smooth plastic (Mitsuba 3's `plastic`): a diffuse base under a smooth dielectric coating of
//! relative index `η`. The coating reflects specularly with Fresnel reflectance `F(cos θ_o)`; light
//! entering it scatters diffusely, bounces inside with the diffuse internal reflectance
//! `F_dr,int = F_dr(1/η)`, and leaves scaled by `1/η²`:
//!
//! `f_diffuse = ρ / (1 − F_dr,int·[ρ if nonlinear else 1]) · (1 − F(θ_o)) (1 − F(θ_i)) / (η² π)`.
//!
//! Sampling picks the delta lobe with probability proportional to `F(θ_o) · w_s` against
//! `(1 − F(θ_o)) · (1 − w_s)`, where the specular sampling weight `w_s = s̄/(d̄ + s̄)` is computed
//! from the mean specular and diffuse reflectances when the material is built.

use super::fresnel::{fresnel_dielectric, reflect};
use super::BsdfSample;
use ircache_math::{sampling, Rgb, Vec2, Vec3, INV_PI};

/// A smooth plastic at one surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plastic {
    /// Base albedo `ρ`.
    pub diffuse_reflectance: Rgb,
    /// Specular scale.
    pub specular_reflectance: Rgb,
    /// Relative index (interior / exterior).
    pub eta: f32,
    /// Diffuse internal Fresnel reflectance `F_dr(1/η)`.
    pub fdr_int: f32,
    /// Specular sampling weight `w_s`.
    pub specular_sampling_weight: f32,
    /// Colour shift from internal scattering.
    pub nonlinear: bool,
}

impl Plastic {
    /// The diffuse base with internal scattering: `ρ / (1 − F_dr,int·[ρ or 1])`.
    fn diffuse_term(&self) -> Rgb {
        let d = self.diffuse_reflectance;
        if self.nonlinear {
            Rgb::new(
                d.r / (1.0 - d.r * self.fdr_int),
                d.g / (1.0 - d.g * self.fdr_int),
                d.b / (1.0 - d.b * self.fdr_int),
            )
        } else {
            d / (1.0 - self.fdr_int)
        }
    }

    /// Probability of choosing the specular (delta) lobe for `cos θ_o` with Fresnel `f_o`.
    #[must_use]
    pub fn prob_specular(&self, f_o: f32) -> f32 {
        let ps = f_o * self.specular_sampling_weight;
        let pd = (1.0 - f_o) * (1.0 - self.specular_sampling_weight);
        if ps + pd > 0.0 {
            ps / (ps + pd)
        } else {
            0.0
        }
    }

    /// The diffuse part times `cos θ_i` (the specular part is a delta).
    #[must_use]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta).r;
        let f_i = fresnel_dielectric(wi.z, self.eta).r;
        let inv_eta_2 = 1.0 / (self.eta * self.eta);
        self.diffuse_term() * (wi.z * INV_PI * inv_eta_2 * (1.0 - f_o) * (1.0 - f_i))
    }

    /// Density of the diffuse part: `(1 − P_spec) cos θ_i / π`.
    #[must_use]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta).r;
        (1.0 - self.prob_specular(f_o)) * sampling::cosine_hemisphere_pdf(wi)
    }

    /// The Lambertian albedo a cache serves (`k` in `k E / π`): the diffuse part with the
    /// entering transmittance `1 − F(θ_i)` replaced by its cosine-weighted mean `1 − F_dr(η)`
    /// (exact under uniform incident light; the direct term uses the exact form).
    #[must_use]
    pub fn lambertian_albedo(&self, wo: Vec3) -> Rgb {
        if wo.z <= 0.0 {
            return Rgb::ZERO;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta).r;
        let t_mean = 1.0 - super::fresnel::fresnel_diffuse_reflectance(self.eta);
        self.diffuse_term() * ((1.0 - f_o) * t_mean / (self.eta * self.eta))
    }

    /// The coating's specular reflection alone (a delta lobe, chosen with probability 1).
    #[must_use]
    pub fn sample_specular(&self, wo: Vec3) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta).r;
        Some(BsdfSample {
            wi: reflect(wo),
            pdf: 1.0,
            weight: self.specular_reflectance * f_o,
            delta: true,
            eta: 1.0,
        })
    }

    /// Chooses the specular delta or the diffuse lobe.
    #[must_use]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta).r;
        let p_spec = self.prob_specular(f_o);
        if u_lobe < p_spec {
            return Some(BsdfSample {
                wi: reflect(wo),
                pdf: p_spec,
                weight: self.specular_reflectance * (f_o / p_spec),
                delta: true,
                eta: 1.0,
            });
        }
        let wi = sampling::square_to_cosine_hemisphere(u);
        let pdf = (1.0 - p_spec) * sampling::cosine_hemisphere_pdf(wi);
        if wi.z <= 0.0 || pdf <= 0.0 {
            return None;
        }
        let f_i = fresnel_dielectric(wi.z, self.eta).r;
        let inv_eta_2 = 1.0 / (self.eta * self.eta);
        let weight = self.diffuse_term() * (inv_eta_2 * (1.0 - f_o) * (1.0 - f_i) / (1.0 - p_spec));
        Some(BsdfSample {
            wi,
            pdf,
            weight,
            delta: false,
            eta: 1.0,
        })
    }
}
