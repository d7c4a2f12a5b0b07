//! Smooth dielectric interface (Mitsuba 3's `dielectric`), two-sided: `η = int_ior/ext_ior`
//! seen from the front (+z) side, `1/η` from the back. Reflection is chosen with probability
//! equal to the Fresnel reflectance `R`, refraction with `1 − R`, so the weights are
//! `specular_reflectance` and `specular_transmittance · η_ti²`: radiance is scaled by `1/η²` when
//! entering a denser medium (Mitsuba's radiance transport mode; `η_ti = η_i/η_t`). The sample's
//! `eta` is the relative index `η_t/η_i` crossed (1 for reflection), for Russian roulette.

use super::fresnel::{fresnel_dielectric, reflect, refract};
use super::BsdfSample;
use ircache_math::{Rgb, Vec3};

/// A smooth dielectric interface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    /// Relative index of refraction (interior / exterior).
    pub eta: f32,
    /// Reflection scale.
    pub specular_reflectance: Rgb,
    /// Transmission scale.
    pub specular_transmittance: Rgb,
}

impl Dielectric {
    /// Chooses reflection with probability `R(cos θ_o)`, otherwise refraction.
    #[must_use]
    pub fn sample(&self, wo: Vec3, u_lobe: f32) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let f = fresnel_dielectric(wo.z, self.eta);
        if u_lobe < f.r {
            Some(BsdfSample {
                wi: reflect(wo),
                pdf: f.r,
                weight: self.specular_reflectance,
                delta: true,
                eta: 1.0,
            })
        } else {
            let wi = refract(wo, f.cos_theta_t, f.eta_ti);
            Some(BsdfSample {
                wi: wi.normalize(),
                pdf: 1.0 - f.r,
                weight: self.specular_transmittance * (f.eta_ti * f.eta_ti),
                delta: true,
                eta: f.eta_it,
            })
        }
    }
}
