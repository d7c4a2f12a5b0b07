//! Thin dielectric sheet (Mitsuba 3's `thindielectric`): two parallel interfaces with no
//! refraction offset. Summing the inter-reflections inside the sheet gives the total reflectance
//! `R' = R + T²R/(1 − R²) = 2R/(1 + R)` and transmittance `1 − R'`; transmission continues in the
//! direction `−wo`. Both lobes are Dirac deltas, chosen with probabilities `R'` and `1 − R'`.
//!
//! Radiance's `glass` (`src/rt/glass.c`) is the same sheet with absorption: a transmissivity `t`
//! per pass at normal incidence, `d = t^{1/cos θ_t}` at the refraction angle, and the
//! inter-reflections summed per polarisation (reflectance `r` each) and averaged:
//! `T = ½ Σ (1 − r)² d / (1 − r² d²)`, `R = ½ Σ r (1 + (1 − 2r) d²) / (1 − r² d²)` (with `d = 1`
//! these are `(1 − r)/(1 + r)` and `2r/(1 + r)`). Its lobes are chosen by their mean shares.

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
    /// Radiance's `glass`: the transmissivity per pass at normal incidence (absorption inside
    /// the sheet, polarisations kept apart); `None` for Mitsuba's model.
    pub transmissivity: Option<Rgb>,
}

/// Which way a path leaves a sheet, chosen by [`ThinDielectric::choose`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SheetChoice {
    /// Mirror reflection rather than straight transmission.
    pub reflected: bool,
    /// The throughput of the choice divided by its probability.
    pub weight: Rgb,
    /// The probability of the choice.
    pub prob: f32,
}

impl ThinDielectric {
    /// Total reflectance `R'` of Mitsuba's sheet at incidence cosine `cos_theta` (either side).
    #[must_use]
    pub fn reflectance(&self, cos_theta: f32) -> f32 {
        let r = fresnel_dielectric(cos_theta.abs(), self.eta).r;
        if r < 1.0 {
            r * 2.0 / (1.0 + r)
        } else {
            r
        }
    }

    /// Radiance's reflectance and transmittance `(R, T)` of a sheet of transmissivity `t` at
    /// incidence cosine `cos_theta` (`m_glass`).
    fn radiance_glass(&self, t: Rgb, cos_theta: f32) -> (Rgb, Rgb) {
        let n = self.eta;
        let ci = cos_theta.abs().max(1e-6);
        let ct = ((1.0 - 1.0 / (n * n)) + ci * ci / (n * n)).sqrt();
        let re = ((ci - n * ct) / (ci + n * ct)).powi(2);
        let rm = ((1.0 / ci - n / ct) / (1.0 / ci + n / ct)).powi(2);
        let per_channel = |tn: f32| {
            let d = tn.max(1e-15).powf(1.0 / ct);
            let d2 = d * d;
            let trans = |r: f32| (1.0 - r) * (1.0 - r) * d / (1.0 - r * r * d2);
            let refl = |r: f32| r * (1.0 + (1.0 - 2.0 * r) * d2) / (1.0 - r * r * d2);
            (0.5 * (refl(re) + refl(rm)), 0.5 * (trans(re) + trans(rm)))
        };
        let (r0, t0) = per_channel(t.r);
        let (r1, t1) = per_channel(t.g);
        let (r2, t2) = per_channel(t.b);
        (Rgb::new(r0, r1, r2), Rgb::new(t0, t1, t2))
    }

    /// What passes straight through at incidence cosine `cos_theta` (either side):
    /// `specular_transmittance · (1 − R')` (Radiance's `T`), the light a shadow ray carries
    /// across the sheet.
    #[must_use]
    pub fn transmittance(&self, cos_theta: f32) -> Rgb {
        match self.transmissivity {
            None => self.specular_transmittance * (1.0 - self.reflectance(cos_theta)),
            Some(t) => self.radiance_glass(t, cos_theta).1 * self.specular_transmittance,
        }
    }

    /// Chooses reflection or transmission at incidence cosine `cos_theta` with `u` in [0, 1):
    /// Mitsuba's sheet reflects with probability `R'`, Radiance's with `R̄ / (R̄ + T̄)`.
    #[must_use]
    pub fn choose(&self, cos_theta: f32, u: f32) -> SheetChoice {
        match self.transmissivity {
            None => {
                let r = self.reflectance(cos_theta);
                if u < r {
                    SheetChoice {
                        reflected: true,
                        weight: self.specular_reflectance,
                        prob: r,
                    }
                } else {
                    SheetChoice {
                        reflected: false,
                        weight: self.specular_transmittance,
                        prob: 1.0 - r,
                    }
                }
            }
            Some(t) => {
                let (r, tr) = self.radiance_glass(t, cos_theta);
                let (r, tr) = (
                    r * self.specular_reflectance,
                    tr * self.specular_transmittance,
                );
                let (mr, mt) = (r.mean().max(0.0), tr.mean().max(0.0));
                let p = if mr + mt > 0.0 { mr / (mr + mt) } else { 0.0 };
                if u < p {
                    SheetChoice {
                        reflected: true,
                        weight: r / p,
                        prob: p,
                    }
                } else {
                    SheetChoice {
                        reflected: false,
                        weight: tr / (1.0 - p),
                        prob: 1.0 - p,
                    }
                }
            }
        }
    }

    /// Reflects or transmits as [`Self::choose`] decides.
    #[must_use]
    pub fn sample(&self, wo: Vec3, u_lobe: f32) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let c = self.choose(wo.z, u_lobe);
        (c.prob > 0.0).then(|| BsdfSample {
            wi: if c.reflected { reflect(wo) } else { -wo },
            pdf: c.prob,
            weight: c.weight,
            delta: true,
            eta: 1.0,
        })
    }
}
