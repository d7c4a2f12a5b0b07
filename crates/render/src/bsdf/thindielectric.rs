//! Thin dielectric sheet (Mitsuba 3's `thindielectric`): two parallel interfaces with no
//! refraction offset. Summing the inter-reflections inside the sheet gives the total reflectance
//! `R' = R + T²R/(1 − R²) = 2R/(1 + R)` and transmittance `1 − R'`; transmission continues in the
//! direction `−wo`. Both lobes are Dirac deltas, chosen with probabilities `R'` and `1 − R'`.

use super::fresnel::{fresnel_dielectric, reflect};
use super::BsdfSample;
use ircache_math::{Rgb, Vec3};

/// A thin dielectric sheet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinDielectric {
    /// Relative index of refraction of the sheet (interior / exterior).
    pub eta: f32,
    /// Reflection scale.
    pub specular_reflectance: Rgb,
    /// Transmission scale.
    pub specular_transmittance: Rgb,
}

impl ThinDielectric {
    /// Total reflectance `R'` of the sheet at incidence cosine `cos_theta` (either side).
    #[must_use]
    pub fn reflectance(&self, cos_theta: f32) -> f32 {
        let r = fresnel_dielectric(cos_theta.abs(), self.eta).r;
        if r < 1.0 {
            r * 2.0 / (1.0 + r)
        } else {
            r
        }
    }

    /// What passes straight through at incidence cosine `cos_theta` (either side):
    /// `specular_transmittance · (1 − R')`, the light a shadow ray carries across the sheet.
    #[must_use]
    pub fn transmittance(&self, cos_theta: f32) -> Rgb {
        self.specular_transmittance * (1.0 - self.reflectance(cos_theta))
    }

    /// Chooses reflection with probability `R'`, otherwise straight transmission.
    #[must_use]
    pub fn sample(&self, wo: Vec3, u_lobe: f32) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let r = self.reflectance(wo.z);
        if u_lobe < r {
            Some(BsdfSample {
                wi: reflect(wo),
                pdf: r,
                weight: self.specular_reflectance,
                delta: true,
                eta: 1.0,
            })
        } else {
            Some(BsdfSample {
                wi: -wo,
                pdf: 1.0 - r,
                weight: self.specular_transmittance,
                delta: true,
                eta: 1.0,
            })
        }
    }
}
