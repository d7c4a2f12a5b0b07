//! Smooth conductor (Mitsuba 3's `conductor`): a perfect mirror whose reflectance is the
//! conductor Fresnel term of the complex index `η + i k`, times `specular_reflectance`.
//! One-sided; the only lobe is a Dirac delta, so `eval` and `pdf` are zero.

use super::fresnel::{fresnel_conductor, reflect};
use super::BsdfSample;
use ircache_math::{Rgb, Vec3};

/// A smooth conductor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    /// Real part of the relative index of refraction.
    pub eta: Rgb,
    /// Imaginary part (absorption).
    pub k: Rgb,
    /// Scale.
    pub specular_reflectance: Rgb,
}

impl Conductor {
    /// The mirror direction with weight `F(cos θ_o) · specular_reflectance` and probability 1.
    #[must_use]
    pub fn sample(&self, wo: Vec3) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let weight = self.specular_reflectance * fresnel_conductor(wo.z, self.eta, self.k);
        Some(BsdfSample {
            wi: reflect(wo),
            pdf: 1.0,
            weight,
            delta: true,
            eta: 1.0,
        })
    }
}
