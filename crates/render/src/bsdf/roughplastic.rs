//! Rough plastic (Mitsuba 3's `roughplastic`): a diffuse base under a rough dielectric coating.
//!
//! - Specular part: the microfacet reflection of the coating,
//!   `F(wo·h) D(h) G(wo, wi, h) / (4 cos θ_o cos θ_i) · specular_reflectance` (isotropic
//!   Beckmann or GGX, Walter et al. 2007).
//! - Diffuse part: `ρ / (1 − R_int·[ρ if nonlinear else 1]) · T(θ_o) T(θ_i) / (η² π)`, where
//!   `T(μ) = E_{m ∼ D_wi}[(1 − F(wi·m)) G1(wt, m)]` is the coating's transmittance (`wt` the
//!   refracted direction; tabulated over 64 values of `μ = cos θ` at build time, interpolated
//!   linearly) and `R_int = 2 ∫ R_{1/η}(μ) μ dμ` the coating's internal diffuse reflectance, with
//!   `R(μ) = E_{m ∼ D_wi}[F(wi·m) G1(wo, m)]` the directional albedo of the rough reflection. Both
//!   are integrated with Gauss–Legendre quadrature over the visible-normal sampler's unit square
//!   (32² nodes for `η > 1`, 128² otherwise), as Mitsuba 3's `eval_transmittance` and
//!   `eval_reflectance`.
//!
//! Sampling chooses the specular lobe (visible normals) with probability proportional to
//! `(1 − T(θ_o)) · w_s` against `T(θ_o) · (1 − w_s)`, otherwise the cosine-weighted diffuse lobe;
//! `pdf` is the mixture of both densities, and the weight is `eval / pdf`.

use super::fresnel::{fresnel_dielectric, reflect_about};
use super::microfacet::Microfacet;
use super::BsdfSample;
use ircache_math::{sampling, Rgb, Vec2, Vec3, INV_PI};
use ircache_scene::MicrofacetDistribution;
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

/// Resolution of the external transmittance table.
pub const TRANSMITTANCE_RES: usize = 64;

/// A rough plastic at one surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughPlastic {
    /// Microfacet distribution of the coating (isotropic).
    pub distr: Microfacet,
    /// Base albedo `ρ`.
    pub diffuse_reflectance: Rgb,
    /// Specular scale.
    pub specular_reflectance: Rgb,
    /// Relative index (interior / exterior).
    pub eta: f32,
    /// Specular sampling weight `w_s`.
    pub specular_sampling_weight: f32,
    /// Colour shift from internal scattering.
    pub nonlinear: bool,
    /// The coating's tables (interned: one per distinct distribution, roughness and index).
    pub tables: &'static RoughPlasticTables,
}

/// Precomputed transmittance of a rough dielectric coating.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughPlasticTables {
    /// `T(μ_j)` for `μ_j = j / 63` (the first clamped to 10⁻⁶).
    pub external_transmittance: [f32; TRANSMITTANCE_RES],
    /// Internal diffuse reflectance `R_int`.
    pub internal_reflectance: f32,
    /// Cosine-weighted mean transmittance `2 ∫ T(μ) μ dμ` (what diffuse light entering the
    /// coating keeps under uniform incident radiance).
    pub mean_transmittance: f32,
}

impl RoughPlasticTables {
    /// The tables of the coating of distribution `distr` and relative index `eta`, interned:
    /// computed once per distinct `(distribution, α, η)` in the process (in parallel over μ) and
    /// kept for its lifetime, so that a [`RoughPlastic`] can refer to them without a lifetime or
    /// reference count (each is 260 bytes; scenes have a handful).
    #[must_use]
    pub fn interned(distr: &Microfacet, eta: f32) -> &'static RoughPlasticTables {
        type Key = (u8, u32, u32);
        static CACHE: OnceLock<Mutex<HashMap<Key, &'static RoughPlasticTables>>> = OnceLock::new();
        let key = (
            u8::from(matches!(distr.kind, MicrofacetDistribution::Ggx)),
            distr.alpha_u.to_bits(),
            eta.to_bits(),
        );
        let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
        if let Some(t) = cache.lock().ok().and_then(|c| c.get(&key).copied()) {
            return t;
        }
        let t: &'static RoughPlasticTables = Box::leak(Box::new(Self::new(distr, eta)));
        match cache.lock() {
            Ok(mut c) => c.entry(key).or_insert(t),
            Err(_) => t,
        }
    }

    /// Computes the tables of the coating of distribution `distr` and relative index `eta`.
    #[must_use]
    pub fn new(distr: &Microfacet, eta: f32) -> Self {
        let (nodes_ext, weights_ext) = gauss_legendre(if eta > 1.0 { 32 } else { 128 });
        let (nodes_int, weights_int) = gauss_legendre(if 1.0 / eta > 1.0 { 32 } else { 128 });
        let rows: Vec<(f32, f64)> = (0..TRANSMITTANCE_RES)
            .into_par_iter()
            .map(|j| {
                let mu = (j as f32 / (TRANSMITTANCE_RES - 1) as f32).max(1e-6);
                let wi = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
                let t = eval_transmittance(distr, wi, eta, &nodes_ext, &weights_ext) as f32;
                let r_int = eval_reflectance(distr, wi, 1.0 / eta, &nodes_int, &weights_int)
                    * f64::from(mu);
                (t, r_int)
            })
            .collect();
        let mut external_transmittance = [0.0f32; TRANSMITTANCE_RES];
        let mut internal = 0.0f64;
        for (j, (t, r)) in rows.into_iter().enumerate() {
            external_transmittance[j] = t;
            internal += r;
        }
        // 2 ∫ T(μ) μ dμ by the trapezoid rule over the table's nodes.
        let h = 1.0 / (TRANSMITTANCE_RES - 1) as f64;
        let mean_transmittance = (0..TRANSMITTANCE_RES - 1)
            .map(|j| {
                let (m0, m1) = (j as f64 * h, (j + 1) as f64 * h);
                let (t0, t1) = (
                    f64::from(external_transmittance[j]),
                    f64::from(external_transmittance[j + 1]),
                );
                h * (t0 * m0 + t1 * m1)
            })
            .sum::<f64>();
        RoughPlasticTables {
            external_transmittance,
            internal_reflectance: (2.0 * internal / TRANSMITTANCE_RES as f64) as f32,
            mean_transmittance: mean_transmittance as f32,
        }
    }

    /// `T(μ)` by linear interpolation.
    #[must_use]
    pub fn transmittance(&self, mu: f32) -> f32 {
        let x = mu.clamp(0.0, 1.0) * (TRANSMITTANCE_RES - 1) as f32;
        let i = (x as usize).min(TRANSMITTANCE_RES - 2);
        let w1 = x - i as f32;
        (1.0 - w1) * self.external_transmittance[i] + w1 * self.external_transmittance[i + 1]
    }
}

/// Directional transmittance into a rough dielectric at `wi` (Mitsuba 3's `eval_transmittance`):
/// `E_{m ∼ D_wi}[(1 − F(wi·m)) G1(wt, m)]` with `wt` the refraction of `wi` about `m`. Smaller
/// than `1 − R(μ)` (the refracted light the microsurface masks is lost too): at grazing angles
/// by 10–15 % for GGX α = 0.1, which once made our rough plastic that much brighter there.
fn eval_transmittance(
    distr: &Microfacet,
    wi: Vec3,
    eta: f32,
    nodes: &[f64],
    weights: &[f64],
) -> f64 {
    let mut acc = 0.0f64;
    for (a, wa) in nodes.iter().zip(weights) {
        for (b, wb) in nodes.iter().zip(weights) {
            let u = Vec2::new((0.5 * a + 0.5) as f32, (0.5 * b + 0.5) as f32);
            let m = distr.sample_visible(wi, u);
            let fresnel = fresnel_dielectric(wi.dot(m), eta);
            // Refraction about the microfacet normal m (Mitsuba's `refract(wi, m, cos_t, η_ti)`).
            let wt = m * (wi.dot(m) * fresnel.eta_ti + fresnel.cos_theta_t) - wi * fresnel.eta_ti;
            if wt.z * wi.z >= 0.0 {
                continue;
            }
            acc += f64::from(distr.smith_g1(wt, m) * (1.0 - fresnel.r)) * wa * wb;
        }
    }
    acc * 0.25
}

/// Directional albedo of rough dielectric reflection at `wi` (Mitsuba's `eval_reflectance`).
fn eval_reflectance(distr: &Microfacet, wi: Vec3, eta: f32, nodes: &[f64], weights: &[f64]) -> f64 {
    let mut acc = 0.0f64;
    for (a, wa) in nodes.iter().zip(weights) {
        for (b, wb) in nodes.iter().zip(weights) {
            let u = Vec2::new((0.5 * a + 0.5) as f32, (0.5 * b + 0.5) as f32);
            let m = distr.sample_visible(wi, u);
            let wo = reflect_about(wi, m);
            if wo.z <= 0.0 || wi.z <= 0.0 {
                continue;
            }
            let f = fresnel_dielectric(wi.dot(m), eta).r;
            acc += f64::from(distr.smith_g1(wo, m) * f) * wa * wb;
        }
    }
    acc * 0.25
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton iteration on the Legendre recurrence).
#[must_use]
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = vec![0.0; n];
    let mut weights = vec![0.0; n];
    for i in 0..n {
        // Initial guess (Tricomi).
        let mut x = -(std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 0 { 1.0 } else { p1 };
            let pn1 = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (x * pn - pn1) / (x * x - 1.0);
            let dx = pn / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        nodes[i] = x;
        weights[i] = 2.0 / ((1.0 - x * x) * dp * dp);
    }
    (nodes, weights)
}

impl RoughPlastic {
    fn diffuse_term(&self) -> Rgb {
        let d = self.diffuse_reflectance;
        let r = self.tables.internal_reflectance;
        if self.nonlinear {
            Rgb::new(
                d.r / (1.0 - d.r * r),
                d.g / (1.0 - d.g * r),
                d.b / (1.0 - d.b * r),
            )
        } else {
            d / (1.0 - r)
        }
    }

    /// Probability of choosing the specular lobe.
    #[must_use]
    pub fn prob_specular(&self, t_o: f32) -> f32 {
        let ps = (1.0 - t_o) * self.specular_sampling_weight;
        let pd = t_o * (1.0 - self.specular_sampling_weight);
        if ps + pd > 0.0 {
            ps / (ps + pd)
        } else {
            0.0
        }
    }

    /// `f · cos θ_i`, both parts.
    #[must_use]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let h = (wo + wi).normalize();
        let d = self.distr.eval(h);
        let f = fresnel_dielectric(wo.dot(h), self.eta).r;
        let g = self.distr.g(wo, wi, h);
        let spec = self.specular_reflectance * (f * d * g / (4.0 * wo.z));
        let t_o = self.tables.transmittance(wo.z);
        let t_i = self.tables.transmittance(wi.z);
        let inv_eta_2 = 1.0 / (self.eta * self.eta);
        spec + self.diffuse_term() * (INV_PI * inv_eta_2 * wi.z * t_o * t_i)
    }

    /// The Lambertian albedo a cache serves (`k` in `k E / π`): the diffuse part with the
    /// entering transmittance `T(θ_i)` replaced by its cosine-weighted mean (exact under uniform
    /// incident light; the direct term uses the exact form).
    #[must_use]
    pub fn lambertian_albedo(&self, wo: Vec3) -> Rgb {
        if wo.z <= 0.0 {
            return Rgb::ZERO;
        }
        let t_o = self.tables.transmittance(wo.z);
        self.diffuse_term() * (t_o * self.tables.mean_transmittance / (self.eta * self.eta))
    }

    /// The specular (coating) part alone, `f_s · cos θ_i`.
    #[must_use]
    pub fn eval_specular(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let h = (wo + wi).normalize();
        let f = fresnel_dielectric(wo.dot(h), self.eta).r;
        self.specular_reflectance
            * (f * self.distr.eval(h) * self.distr.g(wo, wi, h) / (4.0 * wo.z))
    }

    /// Density of the specular part's sampling (visible normals) alone.
    #[must_use]
    pub fn pdf_specular(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        if wo.dot(h) > 0.0 && wi.dot(h) > 0.0 {
            self.distr.eval(h) * self.distr.smith_g1(wo, h) / (4.0 * wo.z)
        } else {
            0.0
        }
    }

    /// Samples the specular part alone (visible normals), weight `eval_specular / pdf_specular`.
    #[must_use]
    pub fn sample_specular(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = reflect_about(wo, self.distr.sample_visible(wo, u)).normalize();
        BsdfSample::smooth_reflection(wi, self.pdf_specular(wo, wi), || self.eval_specular(wo, wi))
    }

    /// Mixture density of the two lobes.
    #[must_use]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let p_spec = self.prob_specular(self.tables.transmittance(wo.z));
        let h = (wo + wi).normalize();
        let spec = if wo.dot(h) > 0.0 && wi.dot(h) > 0.0 {
            self.distr.eval(h) * self.distr.smith_g1(wo, h) / (4.0 * wo.z)
        } else {
            0.0
        };
        p_spec * spec + (1.0 - p_spec) * sampling::cosine_hemisphere_pdf(wi)
    }

    /// Chooses a lobe, samples it, and weights by `eval / pdf` of the mixture.
    #[must_use]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let p_spec = self.prob_specular(self.tables.transmittance(wo.z));
        let wi = if u_lobe < p_spec {
            let m = self.distr.sample_visible(wo, u);
            reflect_about(wo, m).normalize()
        } else {
            sampling::square_to_cosine_hemisphere(u)
        };
        BsdfSample::smooth_reflection(wi, self.pdf(wo, wi), || self.eval(wo, wi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials() {
        let (x, w) = gauss_legendre(8);
        let s: f64 = w.iter().sum();
        assert!((s - 2.0).abs() < 1e-12);
        // ∫ x^14 over [−1, 1] = 2/15: exact for 8 nodes (degree ≤ 15).
        let p: f64 = x.iter().zip(&w).map(|(x, w)| x.powi(14) * w).sum();
        assert!((p - 2.0 / 15.0).abs() < 1e-12, "{p}");
    }

    #[test]
    fn smooth_limit_of_the_coating_matches_fresnel() {
        // As α → 0 the coating's albedo is the smooth Fresnel reflectance.
        let d = Microfacet::new(MicrofacetDistribution::Ggx, 0.001, 0.001);
        let t = RoughPlasticTables::new(&d, 1.5);
        for mu in [0.3f32, 0.7, 1.0] {
            let r = fresnel_dielectric(mu, 1.5).r;
            assert!((1.0 - t.transmittance(mu) - r).abs() < 2e-3, "{mu}");
        }
        let fdr = super::super::fresnel::fresnel_diffuse_reflectance(1.0 / 1.5);
        assert!(
            (t.internal_reflectance - fdr).abs() < 0.02,
            "{} vs {fdr}",
            t.internal_reflectance
        );
    }
}
