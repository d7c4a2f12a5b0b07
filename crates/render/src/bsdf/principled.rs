//! Mitsuba 3's `principled` BSDF (Burley 2012 and 2015, "Physically Based Shading at Disney" and
//! "Extending the Disney BRDF to a BSDF with Integrated Subsurface Scattering"), its value as
//! Mitsuba 3.9.1's `src/bsdfs/principled.cpp` computes it, with `V` the direction to the viewer
//! (our `wo`), `L` the one to the light (our `wi`), `h` their (generalised) half vector:
//! - specular reflection `F D G / (4 |cos θ_V|)`, GGX with `α = max(0.001, roughness²)`
//!   (stretched by `√(1 − 0.9 anisotropic)`), `F` the dielectric Fresnel term mixed with Schlick's
//!   metal and tinted terms on the front, `spec_trans · F` from the back;
//! - specular transmission (weight `(1 − metallic) spec_trans`) as `roughdielectric`'s, times
//!   `√base_color`, with the radiance scaling `1/η²`;
//! - clearcoat `0.25 clearcoat F_c D_c G_c |cos θ_L|`: GTR1 normals (α from 0.1 to 0.001 with
//!   `clearcoat_gloss`), Schlick's `F` from 0.04, Smith GGX masking at α 0.25, and, as in Mitsuba,
//!   no `1/(4 cos θ_V cos θ_L)`;
//! - diffuse (weight `(1 − metallic)(1 − spec_trans)`) `base/π · ((1 − F_V/2)(1 − F_L/2) + R_R
//!   (F_L + F_V + F_L F_V (R_R − 1)))`, `R_R = 2 roughness (h·L)²`, blended towards Hanrahan–Krueger's
//!   flattened term by `flatness`; sheen `sheen (1 − metallic) F_D c_sheen |cos θ_L|`.
//!
//! The index of refraction is `eta`, or from `specular` as `2/(1 − √(0.08 specular)) − 1`.
//!
//! Sampling (ours, not Mitsuba's, whose lobe probabilities depend on the sampled microfacet and
//! so are not the density it reports): the diffuse lobe by the cosine, the clearcoat's normals by
//! GTR1, the specular pair by visible GGX normals then reflection or refraction by their share of
//! the Fresnel split, each lobe chosen with a probability fixed by the view; the density is the
//! mixture's, the weight eval / pdf.
//!
//! For the caches the diffuse term splits exactly: `(1 − F_V/2)(1 − F_L/2) ≥ (1 − F_V/2)/2`, so
//! `k(V) = (1 − metallic)(1 − spec_trans)(1 − flatness) base (1 − F_V/2)/2` is a Lambertian part
//! (served by records) and the rest, never negative, is traced with everything else.

use super::fresnel::{fresnel_dielectric, reflect_about};
use super::microfacet::Microfacet;
use super::BsdfSample;
use ircache_math::sampling::sin_cos_turn;
use ircache_math::{Rgb, Vec2, Vec3};
use ircache_scene::MicrofacetDistribution;
use std::f32::consts::{FRAC_1_PI, PI};

/// The principled BSDF at a surface point (textures looked up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Principled {
    /// Base colour.
    pub base_color: Rgb,
    /// Roughness in [0, 1].
    pub roughness: f32,
    /// Anisotropy in [0, 1].
    pub anisotropic: f32,
    /// Metallic share.
    pub metallic: f32,
    /// Specular transmission share.
    pub spec_trans: f32,
    /// Tint of the dielectric specular towards the base colour.
    pub spec_tint: f32,
    /// Sheen strength.
    pub sheen: f32,
    /// Tint of the sheen towards the base colour.
    pub sheen_tint: f32,
    /// Blend of the diffuse towards the flattened (subsurface-like) term.
    pub flatness: f32,
    /// Clearcoat strength.
    pub clearcoat: f32,
    /// Clearcoat glossiness.
    pub clearcoat_gloss: f32,
    /// Relative index of refraction (interior / exterior).
    pub eta: f32,
}

/// `(1 − c)⁵` for `c` clamped to [0, 1] (Schlick's weight).
fn schlick_weight(c: f32) -> f32 {
    let m = (1.0 - c).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// Schlick's approximation from `r0` at signed incidence cosine `cos_i` on an interface of
/// index `eta`: the weight from the cosine on the optically thinner side (Mitsuba's
/// `calc_schlick`).
fn schlick(r0: Rgb, cos_i: f32, eta: f32) -> Rgb {
    let eta_it = if cos_i >= 0.0 { eta } else { 1.0 / eta };
    let w = if eta_it > 1.0 {
        schlick_weight(cos_i.abs())
    } else {
        let eta_ti = 1.0 / eta_it;
        let cos_t2 = 1.0 - eta_ti * eta_ti * (1.0 - cos_i * cos_i);
        schlick_weight(cos_t2.max(0.0).sqrt())
    };
    r0 * (1.0 - w) + Rgb::splat(w)
}

/// `((η − 1)/(η + 1))²`.
fn r0_of_eta(eta: f32) -> f32 {
    let r = (eta - 1.0) / (eta + 1.0);
    r * r
}

/// Smith's GGX masking `G1` at roughness `alpha` (isotropic), zero where `v` sees the back of `m`.
fn smith_ggx1(v: Vec3, m: Vec3, alpha: f32) -> f32 {
    if v.dot(m) * v.z <= 0.0 {
        return 0.0;
    }
    let cos2 = v.z * v.z;
    if cos2 >= 1.0 {
        return 1.0;
    }
    let tan2 = (1.0 - cos2) / cos2;
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// The clearcoat's GTR1 distribution (Burley 2012, `γ = 1`).
#[derive(Clone, Copy)]
struct Gtr1 {
    alpha: f32,
}

impl Gtr1 {
    fn eval(self, m: Vec3) -> f32 {
        let a2 = self.alpha * self.alpha;
        let d = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * m.z * m.z));
        if d * m.z > 1e-20 {
            d
        } else {
            0.0
        }
    }

    /// Density of [`Self::sample`] per solid angle of `m`: `D(m) cos θ_m`.
    fn pdf(self, m: Vec3) -> f32 {
        if m.z < 0.0 {
            0.0
        } else {
            m.z * self.eval(m)
        }
    }

    fn sample(self, u: Vec2) -> Vec3 {
        let a2 = self.alpha * self.alpha;
        let cos2 = (1.0 - a2.powf(1.0 - u.y)) / (1.0 - a2);
        let sin = (1.0 - cos2).max(0.0).sqrt();
        let (s, c) = sin_cos_turn(u.x);
        Vec3::new(c * sin, s * sin, cos2.max(0.0).sqrt())
    }
}

/// What eval and pdf share for a pair of directions.
struct Geometry {
    /// `cos θ_V · cos θ_L > 0`.
    reflect: bool,
    /// The half vector, upper hemisphere.
    h: Vec3,
    /// `η_t/η_i` on the viewer's side.
    eta_path: f32,
    /// The dielectric Fresnel reflectance at `V·h`.
    fresnel: f32,
    /// Whether neither direction sees the back of `h` (for reflection, resp. refraction).
    compatible: bool,
}

impl Principled {
    /// The weights of the diffuse and transmission terms.
    fn weights(&self) -> (f32, f32) {
        let dielectric = 1.0 - self.metallic;
        (
            dielectric * (1.0 - self.spec_trans),
            dielectric * self.spec_trans,
        )
    }

    fn distribution(&self) -> Microfacet {
        let r2 = self.roughness * self.roughness;
        let aspect = (1.0 - 0.9 * self.anisotropic).sqrt();
        Microfacet::new(
            MicrofacetDistribution::Ggx,
            (r2 / aspect).max(0.001),
            (r2 * aspect).max(0.001),
        )
    }

    fn clearcoat_distribution(&self) -> Gtr1 {
        Gtr1 {
            alpha: 0.1 + (0.001 - 0.1) * self.clearcoat_gloss,
        }
    }

    fn geometry(&self, v: Vec3, l: Vec3) -> Option<Geometry> {
        if v.z == 0.0 || l.z == 0.0 {
            return None;
        }
        let reflect = v.z * l.z > 0.0;
        let eta_path = if v.z > 0.0 { self.eta } else { 1.0 / self.eta };
        let h = (v + l * if reflect { 1.0 } else { eta_path }).normalize();
        if !h.is_finite() {
            return None;
        }
        let h = if h.z < 0.0 { -h } else { h };
        let fresnel = fresnel_dielectric(v.dot(h), self.eta).r;
        // Mitsuba's `mac_mic_compatibility`, with h turned to the viewer's side.
        let side = if v.z >= 0.0 { h } else { -h };
        let compatible = v.dot(side) > 0.0
            && if reflect {
                l.dot(side) > 0.0
            } else {
                l.dot(side) < 0.0
            };
        Some(Geometry {
            reflect,
            h,
            eta_path,
            fresnel,
            compatible,
        })
    }

    /// Mitsuba's `principled_fresnel`: on the front the dielectric term mixed with Schlick's
    /// metal and tinted terms; from the back the true dielectric term times `spec_trans`'s weight.
    fn specular_fresnel(&self, dielectric: f32, cos_i: f32, front: bool) -> Rgb {
        let (_, transmission) = self.weights();
        if !front {
            return Rgb::splat(transmission * dielectric);
        }
        let eta_it = if cos_i >= 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let lum = self.base_color.luminance();
        let tint = if lum > 0.0 {
            self.base_color / lum
        } else {
            Rgb::ONE
        };
        let metal = schlick(self.base_color, cos_i, self.eta) * self.metallic;
        let tinted = schlick(tint * r0_of_eta(eta_it), cos_i, self.eta)
            * ((1.0 - self.metallic) * self.spec_tint);
        Rgb::splat((1.0 - self.metallic) * (1.0 - self.spec_tint) * dielectric) + metal + tinted
    }

    /// `f · |cos θ_L|` (module doc).
    #[must_use]
    pub fn eval(&self, v: Vec3, l: Vec3) -> Rgb {
        let Some(g) = self.geometry(v, l) else {
            return Rgb::ZERO;
        };
        let (diffuse, transmission) = self.weights();
        let front = v.z > 0.0;
        let (cos_v, cos_l) = (v.z.abs(), l.z.abs());
        let distr = self.distribution();
        let (d, masking) = (distr.eval(g.h), distr.g(v, l, g.h));
        let mut value = Rgb::ZERO;
        if g.reflect && g.compatible && g.fresnel > 0.0 {
            let f = self.specular_fresnel(g.fresnel, v.dot(g.h), front);
            value += f * (d * masking / (4.0 * cos_v));
        }
        if !g.reflect && g.compatible && transmission > 0.0 && g.fresnel < 1.0 {
            let (v_h, l_h) = (v.dot(g.h), l.dot(g.h));
            let denom = v_h + g.eta_path * l_h;
            // η² of Walter's eq. 21 cancelled by the radiance scaling 1/η².
            let t = transmission * (1.0 - g.fresnel) * d * masking * (v_h * l_h).abs()
                / (cos_v * denom * denom);
            if t.is_finite() {
                value += self.base_color.map(f32::sqrt) * t;
            }
        }
        if !(g.reflect && front) {
            return value;
        }
        if self.clearcoat > 0.0 && g.compatible {
            let f = schlick(Rgb::splat(0.04), v.dot(g.h), self.eta).r;
            let dc = self.clearcoat_distribution().eval(g.h);
            let gc = smith_ggx1(v, g.h, 0.25) * smith_ggx1(l, g.h, 0.25);
            value += Rgb::splat(0.25 * self.clearcoat * f * dc * gc * cos_l);
        }
        let (f_l, f_v) = (schlick_weight(cos_l), schlick_weight(cos_v));
        let cos_d = g.h.dot(l);
        if diffuse > 0.0 {
            let lambert = (1.0 - 0.5 * f_v) * (1.0 - 0.5 * f_l);
            let rr = 2.0 * self.roughness * cos_d * cos_d;
            let retro = rr * (f_l + f_v + f_l * f_v * (rr - 1.0));
            let fss90 = 0.5 * rr;
            let fss = (1.0 + (fss90 - 1.0) * f_l) * (1.0 + (fss90 - 1.0) * f_v);
            let flat = 1.25 * (fss * (1.0 / (cos_l + cos_v) - 0.5) + 0.5);
            let shape = (lambert + retro) * (1.0 - self.flatness) + flat * self.flatness;
            value += self.base_color * (diffuse * cos_l * FRAC_1_PI * shape);
        }
        if self.sheen > 0.0 && self.metallic < 1.0 {
            let lum = self.base_color.luminance();
            let tint = if lum > 0.0 {
                self.base_color / lum
            } else {
                Rgb::ONE
            };
            let colour = Rgb::ONE * (1.0 - self.sheen_tint) + tint * self.sheen_tint;
            value +=
                colour * (self.sheen * (1.0 - self.metallic) * schlick_weight(cos_d.abs()) * cos_l);
        }
        value
    }

    /// The probabilities of the diffuse, clearcoat and specular lobes seen from `v` (they sum
    /// to 1; all specular from the back, where only the dielectric interface acts).
    fn lobe_probabilities(&self, v: Vec3) -> (f32, f32, f32) {
        let (diffuse, transmission) = self.weights();
        if v.z <= 0.0 {
            return (0.0, 0.0, if transmission > 0.0 { 1.0 } else { 0.0 });
        }
        let f = fresnel_dielectric(v.z, self.eta).r;
        let specular = (self.specular_fresnel(f, v.z, true).luminance()
            + transmission * (1.0 - f) * self.base_color.map(f32::sqrt).luminance())
        .max(0.1);
        let diffuse = diffuse + 0.25 * self.sheen * (1.0 - self.metallic);
        let clearcoat = 0.25 * self.clearcoat;
        let total = diffuse + clearcoat + specular;
        (diffuse / total, clearcoat / total, specular / total)
    }

    /// The share of the specular lobe that reflects about a normal with dielectric Fresnel `f`
    /// (the rest refracts).
    fn reflect_share(&self, f: f32, front: bool) -> f32 {
        let (_, transmission) = self.weights();
        if transmission <= 0.0 {
            1.0
        } else if front {
            1.0 - transmission * (1.0 - f)
        } else {
            f
        }
    }

    /// Solid-angle density of [`Self::sample`] at `l`.
    #[must_use]
    pub fn pdf(&self, v: Vec3, l: Vec3) -> f32 {
        let Some(g) = self.geometry(v, l) else {
            return 0.0;
        };
        let (p_diffuse, p_clearcoat, p_specular) = self.lobe_probabilities(v);
        let front = v.z > 0.0;
        let mut pdf = 0.0;
        if g.compatible {
            let up = if front { v } else { -v };
            let visible = self.distribution().pdf_visible(up, g.h);
            let l_h = l.dot(g.h);
            let share = self.reflect_share(g.fresnel, front);
            pdf += p_specular
                * if g.reflect {
                    visible * share / (4.0 * l_h.abs())
                } else {
                    let denom = v.dot(g.h) + g.eta_path * l_h;
                    visible * (1.0 - share) * g.eta_path * g.eta_path * l_h.abs() / (denom * denom)
                };
            if g.reflect && front && p_clearcoat > 0.0 {
                pdf += p_clearcoat * self.clearcoat_distribution().pdf(g.h) / (4.0 * l_h.abs());
            }
        }
        if g.reflect && front {
            pdf += p_diffuse * l.z * FRAC_1_PI;
        }
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// Chooses a lobe with `u_lobe` and samples it with `u` (module doc).
    #[must_use]
    pub fn sample(&self, v: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if v.z == 0.0 {
            return None;
        }
        let front = v.z > 0.0;
        let (p_diffuse, p_clearcoat, p_specular) = self.lobe_probabilities(v);
        // (direction, refracted, η_t/η_i of a refraction)
        let (l, refracted, eta) = if u_lobe < p_diffuse {
            (
                ircache_math::sampling::square_to_cosine_hemisphere(u),
                false,
                1.0,
            )
        } else if u_lobe < p_diffuse + p_clearcoat {
            let m = self.clearcoat_distribution().sample(u);
            (reflect_about(v, m).normalize(), false, 1.0)
        } else {
            if p_specular <= 0.0 {
                return None;
            }
            let up = if front { v } else { -v };
            let m = self.distribution().sample_visible(up, u);
            let fresnel = fresnel_dielectric(v.dot(m), self.eta);
            let u_reflect = (u_lobe - p_diffuse - p_clearcoat) / p_specular;
            if u_reflect < self.reflect_share(fresnel.r, front) {
                (reflect_about(v, m).normalize(), false, 1.0)
            } else {
                let l = (m * (v.dot(m) * fresnel.eta_ti + fresnel.cos_theta_t)
                    - v * fresnel.eta_ti)
                    .normalize();
                (l, true, fresnel.eta_it)
            }
        };
        // A direction on the wrong side for its lobe carries nothing.
        if l.z * v.z == 0.0 || refracted != (l.z * v.z < 0.0) {
            return None;
        }
        BsdfSample::smooth(l, self.pdf(v, l), || self.eval(v, l), eta)
    }

    /// The Lambertian part `k(V)` (module doc), zero from the back.
    #[must_use]
    pub fn lambertian_albedo(&self, v: Vec3) -> Rgb {
        if v.z <= 0.0 {
            return Rgb::ZERO;
        }
        let (diffuse, _) = self.weights();
        self.base_color
            * (diffuse * (1.0 - self.flatness) * 0.5 * (1.0 - 0.5 * schlick_weight(v.z)))
    }

    /// Everything but the Lambertian part, `f · |cos θ_L| − k/π cos θ_L` (never negative).
    #[must_use]
    pub fn eval_glossy(&self, v: Vec3, l: Vec3) -> Rgb {
        let all = self.eval(v, l);
        if v.z > 0.0 && l.z > 0.0 {
            (all - self.lambertian_albedo(v) * (l.z * FRAC_1_PI)).max(Rgb::ZERO)
        } else {
            all
        }
    }

    /// True when light passes through the surface.
    #[must_use]
    pub fn transmits(&self) -> bool {
        self.weights().1 > 0.0
    }

    /// The diffuse term's weight times the base colour.
    #[must_use]
    pub fn diffuse_reflectance(&self) -> Rgb {
        self.base_color * self.weights().0
    }
}
