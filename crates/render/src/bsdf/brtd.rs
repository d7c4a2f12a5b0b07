//! Radiance's `BRTDfunc` (`src/rt/m_brdf.c`, `m_brdf`) without its non-specular BRTD
//! functions: a thin surface that mirrors `R` and passes `T` straight through, both computed
//! at each hit from the ray by the material's expressions (so they may depend on the angle,
//! as `glaze1.cal`'s coated glazings do), plus Lambertian reflection on each side and
//! Lambertian transmission.
//!
//! `R` and `T` are set per hit by [`crate::bsdf::Material::at_hit`]; light samples of distant,
//! point and spot lights pass the straight part (`Scene::delta_shadow_transmittance`), as
//! Radiance's shadow rays do. Sampling picks a part by its luminance.

use super::fresnel::reflect;
use super::BsdfSample;
use ircache_math::{sampling, Rgb, Vec2, Vec3, INV_PI};

/// A `BRTDfunc` at one hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Brtd {
    /// Mirror reflectance for the ray that met the surface.
    pub reflect: Rgb,
    /// Straight transmittance for that ray.
    pub transmit: Rgb,
    /// Lambertian reflectance on the front (the side the normal points to).
    pub diffuse_front: Rgb,
    /// Lambertian reflectance on the back.
    pub diffuse_back: Rgb,
    /// Lambertian transmittance.
    pub diffuse_transmit: Rgb,
}

impl Brtd {
    /// The Lambertian reflectance on the side of `wo`.
    fn diffuse_reflect(&self, wo: Vec3) -> Rgb {
        if wo.z > 0.0 {
            self.diffuse_front
        } else {
            self.diffuse_back
        }
    }

    /// `f · |cos θᵢ|` of the Lambertian parts (the deltas have none).
    #[must_use]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z == 0.0 || wi.z == 0.0 {
            return Rgb::ZERO;
        }
        let albedo = if (wo.z > 0.0) == (wi.z > 0.0) {
            self.diffuse_reflect(wo)
        } else {
            self.diffuse_transmit
        };
        albedo * (wi.z.abs() * INV_PI)
    }

    /// The parts' sampling weights: mirror, straight, diffuse reflection, diffuse transmission.
    fn weights(&self, wo: Vec3) -> [f32; 4] {
        [
            self.reflect,
            self.transmit,
            self.diffuse_reflect(wo),
            self.diffuse_transmit,
        ]
        .map(|c| c.luminance().max(0.0))
    }

    /// The density of the Lambertian parts' sampling (the mixture's smooth share).
    #[must_use]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z == 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        let w = self.weights(wo);
        let total: f32 = w.iter().sum();
        if total <= 0.0 {
            return 0.0;
        }
        let share = if (wo.z > 0.0) == (wi.z > 0.0) {
            w[2]
        } else {
            w[3]
        };
        share / total * wi.z.abs() * INV_PI
    }

    /// Picks a part by its luminance (`u_lobe`) and samples it.
    #[must_use]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let w = self.weights(wo);
        let total: f32 = w.iter().sum();
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let mut target = u_lobe * total;
        let mut part = 3;
        for (k, &x) in w.iter().enumerate() {
            if x > 0.0 {
                part = k;
                if target < x {
                    break;
                }
                target -= x;
            }
        }
        let prob = w[part] / total;
        match part {
            0 | 1 => {
                let (wi, value) = if part == 0 {
                    (reflect(wo), self.reflect)
                } else {
                    (-wo, self.transmit)
                };
                Some(BsdfSample {
                    wi,
                    pdf: prob,
                    weight: value / prob,
                    delta: true,
                    eta: 1.0,
                })
            }
            _ => {
                let d = sampling::square_to_cosine_hemisphere(u);
                let same = (part == 2) == (wo.z > 0.0);
                let wi = Vec3::new(d.x, d.y, if same { d.z } else { -d.z });
                let pdf = self.pdf(wo, wi);
                let eval = self.eval(wo, wi);
                BsdfSample::smooth(wi, pdf, || eval, 1.0)
            }
        }
    }
}
