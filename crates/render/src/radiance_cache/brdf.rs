//! BRDFs in hemispherical harmonics (001 eqs. 3.33–3.36, NOTES-001 §A.6, §B.5): for each outgoing
//! direction ωo the coefficients c_i(ωo) = ∫_H f_r(ωo, ωi) cos θi H_i(ωi) dωi of the
//! cosine-weighted glossy lobe (3.34 leaves out the cosine; shading needs it), so that the light
//! a surface reflects from incoming radiance with coefficients λ is L_o(ωo) = Σ_i λ_i c_i(ωo).
//!
//! The models are isotropic, so the coefficients are tabulated over cos θo alone at φo = 0 and
//! turned to φo exactly about the normal at lookup (NOTES-001 §A.6 [P]; the thesis's 32 × 32
//! paraboloid map is for anisotropic BRDFs). Only the glossy part is tabulated: the Lambertian
//! part k/π has the exact coefficients (k/π)(√(π/2), 0, √(π/6), 0, …) (NOTES-001 §B.4), and an
//! irradiance record serves it.
//!
//! [`order_for`] chooses a material's order by the energy its lobe keeps (3.32): the smallest
//! order keeping ≥ 95 % at every θo ≤ 60°; a lobe needing more than the highest order stays
//! traced. NOTES-001 §B.5 asks for 75°, which only Phong lobes meet: a microfacet lobe seen at
//! grazing angles narrows towards the horizon, where every HSH function of m ≠ 0 vanishes (§A.8-1),
//! and keeps 82 % at order 10 where it keeps 99 % at 45° (rough plastic, Beckmann α 0.3, measured).
//! So the table also marks, per θo, whether the chosen order keeps enough there (80 %, measured:
//! `ENERGY_SERVED`); where it does not (the most grazing views), the lobe is traced
//! ([`BrdfCoefficients::serves`]).

use crate::bsdf::Bsdf;
use ircache_math::harmonics::hsh::HshBasis;
use ircache_math::harmonics::{band_and_degree, coefficient_count, quadrature, rotate_about_z};
use ircache_math::{Rgb, Vec3};
use rayon::prelude::*;

/// Outgoing directions tabulated, uniform in cos θo over [0, 1].
pub const OUTGOING_SAMPLES: usize = 64;

/// Gauss–Legendre nodes in cos θi of the projection rule (twice as many in φi): resolves lobes
/// down to about 0.1 rad, sharper than any the order rule lets through at order 10.
const PROJECTION_NODES: usize = 96;

/// Most times an irradiance record's rays a radiance record takes.
pub const MAX_RAY_FACTOR: f64 = 8.0;

/// The factor on 1/η: a record's glossy noise shows as a patch of its radius, more than its
/// irradiance's does. Measured on cornell-rough (16 spp, blurred relMSE_trim): 1/η 9.0 s,
/// 3.2e-4, blurred 8.2e-5; 2/η 9.4 s, 2.9e-4, 6.7e-5; 4/η 11.0 s, 2.7e-4, 5.2e-5.
pub const RAY_FACTOR_SCALE: f64 = 2.0;

/// Largest θo at which [`order_for`] demands the energy.
const ORDER_MAX_THETA_DEGREES: f64 = 60.0;

/// The HSH coefficients of a BSDF's cosine-weighted glossy lobe over the outgoing directions.
#[derive(Clone, Debug)]
pub struct BrdfCoefficients {
    order: usize,
    /// `[sample][channel][coefficient]`: c_i(θo_k, φo = 0), cos θo_k = k / (OUTGOING_SAMPLES − 1).
    table: Vec<f32>,
    /// Per sample: whether the order keeps the energy asked for there.
    kept: Vec<bool>,
    /// The lobe's share η of a cosine-weighted gather's cells at normal view.
    share: f64,
}

/// The projection rule over the incoming hemisphere and, at each node, the basis functions of
/// degree m ≥ 0. The lobe is tabulated at φo = 0, where an isotropic f_r(ωo, ωi) is even in
/// φi: its m < 0 (sin |m|φ) coefficients vanish, and the rule needs only the nodes with φi in
/// (0, π), each weighing twice (a quarter of the work of the whole rule and every function).
struct Projection {
    rule: quadrature::Rule,
    /// The linear indices of the m ≥ 0 coefficients.
    even: Vec<usize>,
    /// Per node, the values of those functions.
    values: Vec<Vec<f64>>,
    /// Coefficients in all.
    n: usize,
}

impl Projection {
    fn new(order: usize) -> Projection {
        let rule = quadrature::hemisphere_fine_mirrored(PROJECTION_NODES);
        let even: Vec<usize> = (0..coefficient_count(order))
            .filter(|&i| band_and_degree(i).1 >= 0)
            .collect();
        let mut basis = HshBasis::new(order);
        let values = rule
            .directions
            .iter()
            .map(|&d| {
                let all = basis.values(d);
                even.iter().map(|&i| all[i]).collect()
            })
            .collect();
        Projection {
            rule,
            even,
            values,
            n: coefficient_count(order),
        }
    }

    /// Projections of the glossy lobe at one θo: per channel, the coefficients, ∫ (f cos)² dωi,
    /// and the lobe's share of the cells of a cosine-weighted gather
    /// η = (∫ f cos dωi)² / (π ∫ f² cos dωi) (1 for a constant f).
    fn slice(&self, bsdf: &Bsdf, cos_theta_o: f64) -> ([Vec<f64>; 3], [f64; 3], f64) {
        let (mut first, mut second) = (0.0, 0.0);
        let sin_theta_o = (1.0 - cos_theta_o * cos_theta_o).max(0.0).sqrt();
        let wo = Vec3::new(sin_theta_o as f32, 0.0, cos_theta_o as f32);
        let m = self.even.len();
        let mut even = [vec![0.0; m], vec![0.0; m], vec![0.0; m]];
        let mut energy = [0.0; 3];
        for ((d, &w), h) in self
            .rule
            .directions
            .iter()
            .zip(&self.rule.weights)
            .zip(&self.values)
        {
            let f = bsdf.eval_glossy(wo, d.as_vec3());
            let y = f64::from(f.g);
            first += w * y;
            second += w * y * y / d.z.max(1e-9);
            for (ch, v) in [f.r, f.g, f.b].into_iter().enumerate() {
                let v = f64::from(v);
                if v == 0.0 {
                    continue;
                }
                energy[ch] += w * v * v;
                let wv = w * v;
                for (ci, hi) in even[ch].iter_mut().zip(h) {
                    *ci += wv * hi;
                }
            }
        }
        let share = if second > 0.0 {
            (first * first / (std::f64::consts::PI * second)).min(1.0)
        } else {
            1.0
        };
        let c = even.map(|channel| {
            let mut all = vec![0.0; self.n];
            for (&i, v) in self.even.iter().zip(channel) {
                all[i] = v;
            }
            all
        });
        (c, energy, share)
    }
}

/// Outgoing angles at which [`glossy_albedo`] measures the directional albedo.
const ALBEDO_VIEWS: usize = 8;

/// The share of uniform incoming light `bsdf`'s glossy lobe reflects, averaged over the outgoing
/// hemisphere with its cosine: 2∫ρ(μ) μ dμ (luminance), ρ(μ) = ∫ f cos θi dωi the directional
/// albedo at cos θo = μ, by the projection rule (Gauss–Legendre in μ).
#[must_use]
pub fn glossy_albedo(bsdf: &Bsdf) -> f64 {
    // Even in φi at φo = 0 (see [`Projection`]).
    let rule = quadrature::hemisphere_fine_mirrored(PROJECTION_NODES);
    quadrature::gauss_legendre(ALBEDO_VIEWS, 0.0, 1.0)
        .into_iter()
        .map(|(mu, w_mu)| {
            let sin = (1.0 - mu * mu).max(0.0).sqrt();
            let wo = Vec3::new(sin as f32, 0.0, mu as f32);
            let rho: f64 = rule
                .directions
                .iter()
                .zip(&rule.weights)
                .map(|(d, &w)| w * f64::from(bsdf.eval_glossy(wo, d.as_vec3()).luminance()))
                .sum();
            2.0 * w_mu * mu * rho
        })
        .sum()
}

impl BrdfCoefficients {
    /// Tabulates `bsdf`'s glossy part (a one-sided or front-side model, seen from above) to
    /// `order`, marking the outgoing directions where it keeps at least `threshold` of the
    /// lobe's energy.
    #[must_use]
    pub fn new(bsdf: &Bsdf, order: usize, threshold: f64) -> BrdfCoefficients {
        let projection = Projection::new(order);
        let mut table = Vec::with_capacity(OUTGOING_SAMPLES * 3 * projection.n);
        let mut kept = Vec::with_capacity(OUTGOING_SAMPLES);
        let mut share = 1.0;
        // One outgoing angle per task (the caller's thread pool), collected in order.
        let slices: Vec<_> = (0..OUTGOING_SAMPLES)
            .into_par_iter()
            .map(|k| projection.slice(bsdf, k as f64 / (OUTGOING_SAMPLES - 1) as f64))
            .collect();
        for (c, energy, eta) in slices {
            // The last sample is the normal view.
            share = eta;
            let total: f64 = energy.iter().sum();
            let captured: f64 = c.iter().flatten().map(|v| v * v).sum();
            kept.push(total <= 0.0 || captured >= threshold * total);
            for channel in &c {
                table.extend(channel.iter().map(|&v| v as f32));
            }
        }
        BrdfCoefficients {
            order,
            table,
            kept,
            share,
        }
    }

    /// How many times an irradiance record's rays a radiance record for this lobe takes:
    /// [`RAY_FACTOR_SCALE`]/η, η the lobe's share of a cosine-weighted gather's cells at normal
    /// view (a record's glossy estimate Σ L_c g_c weighs the cells by the lobe, so for iid cell
    /// noise its relative variance is 1/η times the irradiance's), between 1 and
    /// [`MAX_RAY_FACTOR`].
    #[must_use]
    pub fn ray_factor(&self) -> f64 {
        (RAY_FACTOR_SCALE / self.share.max(1e-6)).clamp(1.0, MAX_RAY_FACTOR)
    }

    /// The coefficients at normal view (green channel).
    #[must_use]
    pub fn normal_view(&self) -> Vec<f64> {
        let n = coefficient_count(self.order);
        let start = (OUTGOING_SAMPLES - 1) * 3 * n + n;
        self.table[start..start + n]
            .iter()
            .map(|&v| f64::from(v))
            .collect()
    }

    /// Whether the table serves the outgoing direction `wo` (local): above the surface, and the
    /// order keeps the energy asked for at both tabulated angles around it.
    #[must_use]
    pub fn serves(&self, wo: Vec3) -> bool {
        if wo.z <= 0.0 {
            return false;
        }
        let position = f64::from(wo.z.min(1.0)) * (OUTGOING_SAMPLES - 1) as f64;
        let k = (position.floor() as usize).min(OUTGOING_SAMPLES - 2);
        self.kept[k] && self.kept[k + 1]
    }

    /// The order tabulated.
    #[must_use]
    pub fn order(&self) -> usize {
        self.order
    }

    /// c_i(ωo) per channel for a local outgoing direction above the surface (zero below), into
    /// `out` (`[channel][coefficient]`, 3 × order²): lerped in cos θo, turned by φo.
    pub fn at(&self, wo: Vec3, out: &mut [f64]) {
        let n = coefficient_count(self.order);
        assert!(out.len() >= 3 * n, "BRDF coefficient output too short");
        if wo.z <= 0.0 {
            out[..3 * n].iter_mut().for_each(|v| *v = 0.0);
            return;
        }
        let position = f64::from(wo.z.min(1.0)) * (OUTGOING_SAMPLES - 1) as f64;
        let k = (position.floor() as usize).min(OUTGOING_SAMPLES - 2);
        let t = position - k as f64;
        let (a, b) = (
            &self.table[k * 3 * n..(k + 1) * 3 * n],
            &self.table[(k + 1) * 3 * n..(k + 2) * 3 * n],
        );
        for ((o, &x), &y) in out.iter_mut().zip(a).zip(b) {
            *o = f64::from(x) + t * (f64::from(y) - f64::from(x));
        }
        let phi = f64::from(wo.y).atan2(f64::from(wo.x));
        if phi != 0.0 {
            for channel in out[..3 * n].chunks_mut(n) {
                rotate_about_z(self.order, channel, phi);
            }
        }
    }

    /// Light reflected towards `wo` from incoming radiance with coefficients `radiance`
    /// (`[channel][coefficient]`): Σ_i λ_i c_i(ωo), clamped at zero.
    #[must_use]
    pub fn reflect(&self, wo: Vec3, radiance: &[f64]) -> Rgb {
        let mut c = vec![0.0; 3 * coefficient_count(self.order)];
        self.at(wo, &mut c);
        clamped(dot_per_channel(&c, radiance))
    }
}

/// Σ_i a_i b_i per channel of two coefficient vectors laid out `[channel][coefficient]`.
#[must_use]
pub fn dot_per_channel(a: &[f64], b: &[f64]) -> [f64; 3] {
    let n = a.len() / 3;
    std::array::from_fn(|c| {
        a[c * n..(c + 1) * n]
            .iter()
            .zip(&b[c * n..(c + 1) * n])
            .map(|(x, y)| x * y)
            .sum()
    })
}

/// Reflected light per channel, clamped at zero: a truncated expansion can ring negative
/// (NOTES-001 §B.3).
#[must_use]
pub fn clamped(l: [f64; 3]) -> Rgb {
    let c = l.map(|v| v.max(0.0) as f32);
    Rgb::new(c[0], c[1], c[2])
}

/// The fraction of the cosine-weighted glossy lobe's energy ∫ (f cos)² (3.32) that each order
/// 1 … `max_order` keeps at outgoing angle θo (degrees), the channels summed.
#[must_use]
pub fn energy_kept(bsdf: &Bsdf, max_order: usize, theta_o_degrees: f64) -> Vec<f64> {
    energy_kept_with(
        bsdf,
        max_order,
        theta_o_degrees,
        &Projection::new(max_order),
    )
}

/// [`energy_kept`] with the projection made once.
fn energy_kept_with(
    bsdf: &Bsdf,
    max_order: usize,
    theta_o_degrees: f64,
    projection: &Projection,
) -> Vec<f64> {
    let (c, energy, _) = projection.slice(bsdf, theta_o_degrees.to_radians().cos());
    let total: f64 = energy.iter().sum();
    (1..=max_order)
        .map(|order| {
            let kept: f64 = c
                .iter()
                .map(|ch| {
                    ch[..coefficient_count(order)]
                        .iter()
                        .map(|v| v * v)
                        .sum::<f64>()
                })
                .sum();
            if total > 0.0 {
                kept / total
            } else {
                1.0
            }
        })
        .collect()
}

/// The smallest order ≤ `max_order` whose expansion keeps at least `threshold` of the glossy
/// lobe's energy at every θo from 0° to 60° (every 5°); `None` when none does (the lobe stays
/// traced) or the BSDF has no glossy part.
#[must_use]
pub fn order_for(bsdf: &Bsdf, max_order: usize, threshold: f64) -> Option<usize> {
    // Light through the surface is outside the hemisphere the harmonics cover, and the tables
    // are made at one azimuth: transmitting and anisotropic lobes are traced.
    if !bsdf.has_glossy() || bsdf.transmits() || bsdf.is_anisotropic() {
        return None;
    }
    let steps = (ORDER_MAX_THETA_DEGREES / 5.0) as usize;
    let projection = Projection::new(max_order);
    let mut needed = 1;
    for k in 0..=steps {
        let kept = energy_kept_with(bsdf, max_order, 5.0 * k as f64, &projection);
        needed = needed.max(kept.iter().position(|&e| e >= threshold)? + 1);
    }
    Some(needed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::Material;
    use ircache_math::harmonics::hsh;
    use ircache_math::{Rng, Vec2};
    use ircache_scene::{BsdfDesc, MicrofacetDistribution, TextureDesc};

    fn phong(exponent: f32) -> Bsdf {
        Material::from_desc(&BsdfDesc::ObjPhong {
            diffuse: TextureDesc::Constant(Rgb::ZERO),
            specular: Rgb::ONE,
            exponent,
        })
        .at(Vec2::ZERO)
    }

    fn rough_conductor(alpha: f32) -> Bsdf {
        Material::from_desc(&BsdfDesc::RoughConductor {
            distribution: MicrofacetDistribution::Ggx,
            alpha_u: alpha,
            alpha_v: alpha,
            eta: Rgb::new(0.143, 0.374, 1.442),
            k: Rgb::new(3.983, 2.385, 1.603),
            specular_reflectance: Rgb::ONE,
        })
        .at(Vec2::ZERO)
    }

    fn rough_plastic(alpha: f32) -> Bsdf {
        Material::from_desc(&BsdfDesc::RoughPlastic {
            distribution: MicrofacetDistribution::Beckmann,
            alpha,
            diffuse_reflectance: TextureDesc::Constant(Rgb::new(0.2, 0.5, 0.3)),
            specular_reflectance: Rgb::ONE,
            int_ior: 1.49,
            ext_ior: 1.000_277,
            nonlinear: false,
        })
        .at(Vec2::ZERO)
    }

    /// The energy a Phong lobe keeps at orders 3, 5, 7, 10 (NOTES-001 §B.5's table, two
    /// decimals), and the orders the rule picks from it.
    #[test]
    fn phong_energy_matches_the_notes() {
        let table: [(f32, f64, [f64; 4]); 6] = [
            (20.0, 0.0, [0.57, 0.90, 0.990, 1.0]),
            (20.0, 45.0, [0.56, 0.90, 0.988, 1.0]),
            (20.0, 75.0, [0.49, 0.83, 0.96, 0.997]),
            (50.0, 0.0, [0.30, 0.62, 0.85, 0.98]),
            (50.0, 75.0, [0.26, 0.55, 0.76, 0.93]),
            (10.0, 75.0, [0.70, 0.96, 0.997, 1.0]),
        ];
        for (e, theta, want) in table {
            let kept = energy_kept(&phong(e), 10, theta);
            for (order, w) in [3usize, 5, 7, 10].into_iter().zip(want) {
                let got = kept[order - 1];
                assert!(
                    (got - w).abs() < 0.01,
                    "e {e} θ {theta} order {order}: {got} vs {w}"
                );
            }
        }
        // Phong 20 needs order 7 (0.96 at 75°), Phong 100 more than 10 (0.86 at 0°); Phong 5
        // order 4 (order 3 keeps 0.94 at 0°).
        assert_eq!(order_for(&phong(20.0), 10, 0.95), Some(7));
        assert_eq!(order_for(&phong(100.0), 10, 0.95), None);
        assert_eq!(order_for(&phong(5.0), 10, 0.95), Some(4));
        // The grazing views a chosen order does not serve: Phong 50 at order 10 keeps 0.93 at
        // 75° (traced there), 0.98 at 0°.
        let table = BrdfCoefficients::new(&phong(50.0), 10, 0.95);
        let at = |deg: f32| Vec3::new(deg.to_radians().sin(), 0.0, deg.to_radians().cos());
        assert!(table.serves(at(0.0)) && !table.serves(at(75.0)));
    }

    /// Under uniform incoming radiance 1 (λ = √(2π) δ_i0), the reflected light is the lobe's
    /// directional albedo, here estimated independently by sampling the BSDF.
    #[test]
    fn white_furnace_gives_the_directional_albedo() {
        let bsdfs = [
            ("phong 20", phong(20.0), 7),
            ("rough gold α 0.3", rough_conductor(0.3), 8),
            ("rough plastic α 0.3", rough_plastic(0.3), 8),
        ];
        for (name, bsdf, order) in bsdfs {
            let table = BrdfCoefficients::new(&bsdf, order, 0.95);
            let n = coefficient_count(order);
            let mut uniform = vec![0.0; 3 * n];
            for ch in 0..3 {
                uniform[ch * n] = (2.0 * std::f64::consts::PI).sqrt();
            }
            for theta in [0.0f32, 30.0, 60.0] {
                // A φo off the tabulated plane: the turn about the normal must not change it.
                let (t, p) = (theta.to_radians(), 1.3f32);
                let wo = Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
                let reflected = table.reflect(wo, &uniform);
                let mut rng = Rng::new(7, 1);
                let samples = 200_000;
                let mut albedo = Rgb::ZERO;
                for _ in 0..samples {
                    if let Some(s) = bsdf.sample_glossy(wo, rng.next_f32(), rng.next_2d()) {
                        albedo += s.weight;
                    }
                }
                let albedo = albedo / samples as f32;
                for (got, want) in [(reflected.r, albedo.r), (reflected.g, albedo.g)] {
                    assert!(
                        (got - want).abs() < 0.01 * want.max(0.05),
                        "{name} θo {theta}: {got} vs {want}"
                    );
                }
            }
        }
    }

    /// The hemispherical glossy albedo by quadrature equals an independent estimate: views
    /// drawn cosine-distributed, the glossy lobe sampled at each. It ranks rough metals far
    /// above rough plastics' coatings (what `--radiance-cache auto` caches).
    #[test]
    fn hemispherical_albedo_matches_sampling_the_lobe() {
        let mut albedos = Vec::new();
        for (name, bsdf) in [
            ("rough gold α 0.3", rough_conductor(0.3)),
            ("rough plastic α 0.3", rough_plastic(0.3)),
        ] {
            let got = glossy_albedo(&bsdf);
            let mut rng = Rng::new(11, 2);
            let samples = 400_000;
            let mut sum = 0.0f64;
            for _ in 0..samples {
                let u = rng.next_2d();
                let (r, phi) = (u.x.sqrt(), 2.0 * std::f32::consts::PI * u.y);
                let wo = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u.x).sqrt());
                if let Some(s) = bsdf.sample_glossy(wo, rng.next_f32(), rng.next_2d()) {
                    sum += f64::from(s.weight.luminance());
                }
            }
            let want = sum / f64::from(samples);
            assert!(
                (got - want).abs() < 0.02 * want.max(0.05),
                "{name}: {got} against {want}"
            );
            albedos.push(got);
        }
        assert!(
            albedos[0] > crate::irradiance_cache::params::AUTO_GLOSSY_ALBEDO
                && albedos[1] < crate::irradiance_cache::params::AUTO_GLOSSY_ALBEDO,
            "{albedos:?}"
        );
    }

    /// The coefficients at φo equal projecting the lobe seen from φo directly (the exact turn
    /// about the normal, and its sign).
    #[test]
    fn turning_about_the_normal_equals_projecting() {
        let bsdf = rough_conductor(0.4);
        let order = 6;
        let n = coefficient_count(order);
        let table = BrdfCoefficients::new(&bsdf, order, 0.95);
        // A tabulated cos θo, so the lerp does not enter.
        let cos_theta = 40.0 / (OUTGOING_SAMPLES - 1) as f32;
        let (s, p) = ((1.0 - cos_theta * cos_theta).sqrt(), 2.1f32);
        let wo = Vec3::new(s * p.cos(), s * p.sin(), cos_theta);
        let mut c = vec![0.0; 3 * n];
        table.at(wo, &mut c);
        let direct = hsh::project(order, &quadrature::hemisphere_fine(PROJECTION_NODES), |d| {
            f64::from(bsdf.eval_glossy(wo, d.as_vec3()).r)
        });
        for (a, b) in c[..n].iter().zip(&direct) {
            assert!((a - b).abs() < 1e-5, "{a} vs {b}");
        }
    }
}
