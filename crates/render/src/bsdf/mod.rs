//! Materials (BSDFs) with Mitsuba 3's models, parameters and conventions.
//!
//! A [`Material`] is compiled once per scene from a [`BsdfDesc`]; at a shading point,
//! [`Material::at`] looks its textures up and returns a small, allocation-free [`Bsdf`] that can be
//! evaluated and sampled.
//!
//! Conventions (as Mitsuba 3, `src/bsdfs/*.cpp`):
//! - all directions are in the local shading frame, normal = +z, both pointing away from the
//!   surface: `wo` towards the viewer (Mitsuba's `si.wi`), `wi` towards the light (Mitsuba's `wo`);
//! - [`Bsdf::eval`] returns `f(wo, wi) · |cos θ_i|`, zero for delta lobes;
//! - one-sided models (diffuse, plastic, roughplastic, conductor, roughconductor, the OBJ Phong
//!   material) are black unless both `wo.z > 0` and `wi.z > 0`; `twosided` mirrors both directions
//!   to the upper hemisphere when `wo.z < 0` and uses its `back` model there if one was given;
//!   dielectric and thin dielectric act on both sides;
//! - [`Bsdf::sample`] returns `weight = eval / pdf` for smooth lobes and, for delta lobes, the
//!   delta's weight with `pdf` the probability of having chosen that lobe;
//! - transmission through a dielectric scales radiance by `(η_i/η_t)²` (radiance transport).
//!
//! - `blendbsdf` ([`Bsdf::Blend`]) mixes two models by a weight; a sample from a delta lobe
//!   keeps its model's weight (Mitsuba 3.9.1 divides it by a mixed density and loses light).
//!
//! Models, one file each: [`diffuse`], [`plastic`], [`roughplastic`], [`conductor`],
//! [`roughconductor`], [`dielectric`], [`roughdielectric`], [`thindielectric`], [`phong`],
//! [`principled`], Radiance's [`ward`] and [`klems`] (tabulated `BSDF` files); shared: [`microfacet`]
//! (Beckmann and GGX, Walter et al. 2007; visible normals, Heitz 2018) and [`fresnel`].

pub mod brtd;
pub mod conductor;
pub mod dielectric;
pub mod diffuse;
pub mod fresnel;
pub mod klems;
pub mod microfacet;
pub mod phong;
pub mod plastic;
pub mod principled;
pub mod roughconductor;
pub mod roughdielectric;
pub mod roughplastic;
pub mod thindielectric;
pub mod ward;

use crate::texture::Texture;
use ircache_math::{Frame, Rgb, Vec2, Vec3};
use ircache_scene::{BsdfDesc, SurfacePattern};
use std::sync::Arc;

pub use brtd::Brtd;
pub use conductor::Conductor;
pub use dielectric::Dielectric;
pub use diffuse::Diffuse;
pub use klems::{Klems, KlemsTables};
pub use microfacet::Microfacet;
pub use phong::Phong;
pub use plastic::Plastic;
pub use principled::Principled;
pub use roughconductor::RoughConductor;
pub use roughdielectric::RoughDielectric;
pub use roughplastic::{RoughPlastic, RoughPlasticTables};
pub use thindielectric::ThinDielectric;
pub use ward::Ward;

/// A sampled direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The sampled direction towards the light, local frame, unit length.
    pub wi: Vec3,
    /// Solid-angle density of `wi` for smooth lobes (equal to [`Bsdf::pdf`]); for a delta lobe,
    /// the probability of having chosen it.
    pub pdf: f32,
    /// `eval / pdf` for smooth lobes; the delta lobe's throughput divided by its probability.
    pub weight: Rgb,
    /// True when `wi` was produced by a Dirac delta lobe (no MIS, no next-event estimation).
    pub delta: bool,
    /// Relative index of refraction `η_t/η_i` crossed by the sample (1 for reflection).
    pub eta: f32,
}

impl BsdfSample {
    /// A sample `wi` of a smooth reflection lobe with density `pdf` and `f · cos θ_i` = `eval`:
    /// weight `eval / pdf`; `None` below the surface or where the density vanishes.
    #[inline]
    #[must_use]
    pub fn smooth_reflection(wi: Vec3, pdf: f32, eval: impl FnOnce() -> Rgb) -> Option<Self> {
        if wi.z <= 0.0 {
            return None;
        }
        Self::smooth(wi, pdf, eval, 1.0)
    }

    /// A sample `wi` of a smooth lobe crossing relative index `eta` (1 for reflection), density
    /// `pdf`, weight `eval / pdf`; `None` where the density is zero, infinite or not a number.
    #[inline]
    #[must_use]
    pub fn smooth(wi: Vec3, pdf: f32, eval: impl FnOnce() -> Rgb, eta: f32) -> Option<Self> {
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(BsdfSample {
            wi,
            pdf,
            weight: eval() / pdf,
            delta: false,
            eta,
        })
    }
}

/// One BSDF model evaluated at a surface point (textures already looked up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lobe {
    /// Lambertian.
    Diffuse(Diffuse),
    /// Smooth plastic.
    Plastic(Plastic),
    /// Rough plastic.
    RoughPlastic(RoughPlastic),
    /// Smooth conductor.
    Conductor(Conductor),
    /// Rough conductor.
    RoughConductor(RoughConductor),
    /// Smooth dielectric.
    Dielectric(Dielectric),
    /// Rough dielectric.
    RoughDielectric(RoughDielectric),
    /// Thin dielectric.
    ThinDielectric(ThinDielectric),
    /// OBJ diffuse + normalised Phong.
    Phong(Phong),
    /// Mitsuba's principled BSDF.
    Principled(Principled),
    /// Radiance's `plastic` and `metal`.
    Ward(Ward),
    /// Radiance's `BSDF` with Klems matrices.
    Klems(Klems),
    /// Radiance's `BRTDfunc` (specular parts and Lambertian ones).
    Brtd(Brtd),
}

impl Lobe {
    fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        match self {
            Lobe::Diffuse(b) => b.eval(wo, wi),
            Lobe::Plastic(b) => b.eval(wo, wi),
            Lobe::RoughPlastic(b) => b.eval(wo, wi),
            Lobe::RoughConductor(b) => b.eval(wo, wi),
            Lobe::RoughDielectric(b) => b.eval(wo, wi),
            Lobe::Phong(b) => b.eval(wo, wi),
            Lobe::Principled(b) => b.eval(wo, wi),
            Lobe::Ward(b) => b.eval(wo, wi),
            Lobe::Klems(b) => b.eval(wo, wi),
            Lobe::Brtd(b) => b.eval(wo, wi),
            Lobe::Conductor(_) | Lobe::Dielectric(_) | Lobe::ThinDielectric(_) => Rgb::ZERO,
        }
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Lobe::Diffuse(b) => b.pdf(wo, wi),
            Lobe::Plastic(b) => b.pdf(wo, wi),
            Lobe::RoughPlastic(b) => b.pdf(wo, wi),
            Lobe::RoughConductor(b) => b.pdf(wo, wi),
            Lobe::RoughDielectric(b) => b.pdf(wo, wi),
            Lobe::Phong(b) => b.pdf(wo, wi),
            Lobe::Principled(b) => b.pdf(wo, wi),
            Lobe::Ward(b) => b.pdf(wo, wi),
            Lobe::Klems(b) => b.pdf(wo, wi),
            Lobe::Brtd(b) => b.pdf(wo, wi),
            Lobe::Conductor(_) | Lobe::Dielectric(_) | Lobe::ThinDielectric(_) => 0.0,
        }
    }

    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        match self {
            Lobe::Diffuse(b) => b.sample(wo, u),
            Lobe::Plastic(b) => b.sample(wo, u_lobe, u),
            Lobe::RoughPlastic(b) => b.sample(wo, u_lobe, u),
            Lobe::Conductor(b) => b.sample(wo),
            Lobe::RoughConductor(b) => b.sample(wo, u),
            Lobe::Dielectric(b) => b.sample(wo, u_lobe),
            Lobe::RoughDielectric(b) => b.sample(wo, u_lobe, u),
            Lobe::ThinDielectric(b) => b.sample(wo, u_lobe),
            Lobe::Phong(b) => b.sample(wo, u_lobe, u),
            Lobe::Principled(b) => b.sample(wo, u_lobe, u),
            Lobe::Ward(b) => b.sample(wo, u_lobe, u),
            Lobe::Klems(b) => b.sample(wo, u_lobe, u),
            Lobe::Brtd(b) => b.sample(wo, u_lobe, u),
        }
    }

    fn has_smooth(&self) -> bool {
        !matches!(
            self,
            Lobe::Conductor(_) | Lobe::Dielectric(_) | Lobe::ThinDielectric(_)
        )
    }

    /// Lambertian albedo seen from `wo` (upper hemisphere), the part a cache serves.
    fn lambertian_albedo(&self, wo: Vec3) -> Rgb {
        if wo.z <= 0.0 {
            return Rgb::ZERO;
        }
        match self {
            Lobe::Diffuse(b) => b.reflectance,
            Lobe::Plastic(b) => b.lambertian_albedo(wo),
            Lobe::RoughPlastic(b) => b.lambertian_albedo(wo),
            Lobe::Phong(b) => b.diffuse,
            Lobe::Principled(b) => b.lambertian_albedo(wo),
            Lobe::Ward(b) => b.lambertian_albedo(wo),
            _ => Rgb::ZERO,
        }
    }

    fn eval_glossy(&self, wo: Vec3, wi: Vec3) -> Rgb {
        match self {
            Lobe::Diffuse(_) | Lobe::Plastic(_) => Rgb::ZERO,
            Lobe::RoughPlastic(b) => b.eval_specular(wo, wi),
            Lobe::Phong(b) => b.eval_specular(wo, wi),
            Lobe::Principled(b) => b.eval_glossy(wo, wi),
            Lobe::Ward(b) => b.eval_specular(wo, wi),
            other => other.eval(wo, wi),
        }
    }

    fn pdf_glossy(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Lobe::Diffuse(_) | Lobe::Plastic(_) => 0.0,
            Lobe::RoughPlastic(b) => b.pdf_specular(wo, wi),
            Lobe::Phong(b) => b.pdf_specular(wo, wi),
            Lobe::Ward(b) => b.pdf_specular(wo, wi),
            other => other.pdf(wo, wi),
        }
    }

    fn sample_glossy(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        match self {
            Lobe::Diffuse(_) => None,
            Lobe::Plastic(b) => b.sample_specular(wo),
            Lobe::RoughPlastic(b) => b.sample_specular(wo, u),
            Lobe::Phong(b) => b.sample_specular(wo, u),
            Lobe::Ward(b) => b.sample_specular(wo, u_lobe, u),
            // The whole mixture's directions, weighed by the glossy part alone.
            Lobe::Principled(b) => b.sample(wo, u_lobe, u).and_then(|s| {
                let weight = b.eval_glossy(wo, s.wi) / s.pdf;
                weight
                    .is_valid_radiance()
                    .then_some(BsdfSample { weight, ..s })
            }),
            other => other.sample(wo, u_lobe, u),
        }
    }

    fn has_glossy(&self) -> bool {
        match self {
            Lobe::Diffuse(_) => false,
            Lobe::Phong(b) => !b.specular.is_black(),
            Lobe::Ward(b) => b.has_specular(),
            _ => true,
        }
    }

    fn diffuse_reflectance(&self) -> Rgb {
        match self {
            Lobe::Diffuse(b) => b.reflectance,
            Lobe::Plastic(b) => b.diffuse_reflectance,
            Lobe::RoughPlastic(b) => b.diffuse_reflectance,
            Lobe::Phong(b) => b.diffuse,
            Lobe::Principled(b) => b.diffuse_reflectance(),
            Lobe::Ward(b) => b.diffuse_reflectance(),
            _ => Rgb::ZERO,
        }
    }
}

/// A BSDF at one surface point: small, `Copy`, no allocation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    /// A model used as it is (one-sided models are black from below).
    Single(Lobe),
    /// Mitsuba's `twosided`: `front` for `wo.z > 0`; for `wo.z < 0`, `back` evaluated with both
    /// directions mirrored through the surface.
    TwoSided {
        /// Model seen from the front.
        front: Lobe,
        /// Model seen from the back (the front one when only one was given).
        back: Lobe,
    },
    /// Mitsuba's `blendbsdf`: `(1 − weight) · first + weight · second`, one-sided models black
    /// from below unless `two_sided` (then both mirrored as `twosided` does). Sampling picks
    /// `second` with probability `weight` and weighs the sample by the mixture's own
    /// eval / pdf (a delta sample by its model's weight).
    Blend {
        /// The model weighted by `1 − weight`.
        first: Lobe,
        /// The model weighted by `weight`.
        second: Lobe,
        /// The weight of `second`, in [0, 1].
        weight: f32,
        /// Whether the blend is wrapped in `twosided`.
        two_sided: bool,
    },
}

/// A blend's two models as seen from `wo` (see [`Bsdf::Blend`]).
#[derive(Clone, Copy)]
struct Mixture<'a> {
    first: &'a Lobe,
    second: &'a Lobe,
    weight: f32,
}

impl Mixture<'_> {
    /// `(1 − w) · a + w · b`.
    #[inline]
    fn mix<T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>>(&self, a: T, b: T) -> T {
        a * (1.0 - self.weight) + b * self.weight
    }

    fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        self.mix(self.first.eval(wo, wi), self.second.eval(wo, wi))
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.mix(self.first.pdf(wo, wi), self.second.pdf(wo, wi))
    }

    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let w = self.weight;
        let (model, chosen, u_lobe) = if u_lobe < w {
            (self.second, w, u_lobe / w)
        } else {
            (self.first, 1.0 - w, (u_lobe - w) / (1.0 - w))
        };
        let s = model.sample(wo, u_lobe.min(ONE_MINUS_EPSILON), u)?;
        if s.delta {
            // Chosen with the probability of its weight: the weights cancel.
            return Some(BsdfSample {
                pdf: chosen * s.pdf,
                ..s
            });
        }
        let pdf = self.pdf(wo, s.wi);
        (pdf > 0.0).then(|| BsdfSample {
            pdf,
            weight: self.eval(wo, s.wi) / pdf,
            ..s
        })
    }

    /// The probability of sampling the second model's glossy part among the glossy parts.
    fn glossy_second(&self) -> f32 {
        let a = if self.first.has_glossy() {
            1.0 - self.weight
        } else {
            0.0
        };
        let b = if self.second.has_glossy() {
            self.weight
        } else {
            0.0
        };
        if a + b > 0.0 {
            b / (a + b)
        } else {
            0.0
        }
    }

    fn eval_glossy(&self, wo: Vec3, wi: Vec3) -> Rgb {
        self.mix(
            self.first.eval_glossy(wo, wi),
            self.second.eval_glossy(wo, wi),
        )
    }

    fn pdf_glossy(&self, wo: Vec3, wi: Vec3) -> f32 {
        let q = self.glossy_second();
        self.first.pdf_glossy(wo, wi) * (1.0 - q) + self.second.pdf_glossy(wo, wi) * q
    }

    fn sample_glossy(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let q = self.glossy_second();
        let (model, chosen, share, u_lobe) = if u_lobe < q {
            (self.second, q, self.weight, u_lobe / q)
        } else {
            (
                self.first,
                1.0 - q,
                1.0 - self.weight,
                (u_lobe - q) / (1.0 - q),
            )
        };
        let s = model.sample_glossy(wo, u_lobe.min(ONE_MINUS_EPSILON), u)?;
        if s.delta {
            return Some(BsdfSample {
                pdf: chosen * s.pdf,
                weight: s.weight * (share / chosen),
                ..s
            });
        }
        let pdf = self.pdf_glossy(wo, s.wi);
        (pdf > 0.0).then(|| BsdfSample {
            pdf,
            weight: self.eval_glossy(wo, s.wi) / pdf,
            ..s
        })
    }
}

/// The largest `f32` below 1 (a remapped sample stays in [0, 1)).
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

fn flip(w: Vec3) -> Vec3 {
    Vec3::new(w.x, w.y, -w.z)
}

/// Whether directions are mirrored through the surface to reach the model seen from `wo`.
#[derive(Clone, Copy)]
struct Side(bool);

impl Side {
    #[inline]
    fn apply(self, w: Vec3) -> Vec3 {
        if self.0 {
            flip(w)
        } else {
            w
        }
    }
}

/// What a BSDF shows towards `wo`: one model, or a blend's two.
#[derive(Clone, Copy)]
enum Facing<'a> {
    One(&'a Lobe),
    Two(Mixture<'a>),
}

impl Facing<'_> {
    fn eval(self, wo: Vec3, wi: Vec3) -> Rgb {
        match self {
            Facing::One(l) => l.eval(wo, wi),
            Facing::Two(m) => m.eval(wo, wi),
        }
    }

    fn pdf(self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Facing::One(l) => l.pdf(wo, wi),
            Facing::Two(m) => m.pdf(wo, wi),
        }
    }

    fn sample(self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        match self {
            Facing::One(l) => l.sample(wo, u_lobe, u),
            Facing::Two(m) => m.sample(wo, u_lobe, u),
        }
    }

    fn eval_glossy(self, wo: Vec3, wi: Vec3) -> Rgb {
        match self {
            Facing::One(l) => l.eval_glossy(wo, wi),
            Facing::Two(m) => m.eval_glossy(wo, wi),
        }
    }

    fn pdf_glossy(self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Facing::One(l) => l.pdf_glossy(wo, wi),
            Facing::Two(m) => m.pdf_glossy(wo, wi),
        }
    }

    fn sample_glossy(self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        match self {
            Facing::One(l) => l.sample_glossy(wo, u_lobe, u),
            Facing::Two(m) => m.sample_glossy(wo, u_lobe, u),
        }
    }

    fn lambertian_albedo(self, wo: Vec3) -> Rgb {
        match self {
            Facing::One(l) => l.lambertian_albedo(wo),
            Facing::Two(m) => m.mix(
                m.first.lambertian_albedo(wo),
                m.second.lambertian_albedo(wo),
            ),
        }
    }
}

/// The weight pattern of a Radiance mixture (a blend, alone or in `twosided`).
fn blend_pattern(desc: &BsdfDesc) -> Option<Arc<dyn SurfacePattern>> {
    match desc {
        BsdfDesc::TwoSided { front, .. } => blend_pattern(front),
        BsdfDesc::Blend { pattern, .. } => pattern.clone(),
        _ => None,
    }
}

/// The patterns on a Radiance material's colour (Ward's model, alone or in `twosided`) or on
/// what its pane transmits (glass).
fn color_pattern(desc: &BsdfDesc) -> Option<Arc<dyn SurfacePattern>> {
    match desc {
        BsdfDesc::TwoSided { front, .. } => color_pattern(front),
        BsdfDesc::Ward { pattern, .. }
        | BsdfDesc::Glass { pattern, .. }
        | BsdfDesc::RadianceMirror { pattern, .. } => pattern.clone(),
        _ => None,
    }
}

/// Scales what a Radiance pane transmits, not what it reflects (`glass.c`); other thin sheets
/// carry no pattern.
fn tint_pane(t: &mut ThinDielectric, factor: Rgb) {
    if t.transmissivity.is_some() {
        t.specular_transmittance *= factor;
    }
}

impl Bsdf {
    /// Multiplies the colour of its Ward models and Radiance mirrors and what its Radiance
    /// panes transmit (not what they reflect, as `glass.c`) by `factor`.
    fn tint(&mut self, factor: Rgb) {
        let tint = |l: &mut Lobe| match l {
            Lobe::Ward(w) => w.color *= factor,
            Lobe::ThinDielectric(t) => tint_pane(t, factor),
            Lobe::Conductor(c) => c.specular_reflectance *= factor,
            _ => {}
        };
        match self {
            Bsdf::Single(l) => tint(l),
            Bsdf::TwoSided { front, back } => {
                tint(front);
                tint(back);
            }
            Bsdf::Blend { first, second, .. } => {
                tint(first);
                tint(second);
            }
        }
    }

    /// The model seen from `wo`: one-sided models as they are (they are black from below on
    /// their own); `twosided` the front above, the back (directions mirrored) below, none on the
    /// surface itself.
    #[inline]
    fn facing(&self, wo: Vec3) -> Option<(Facing<'_>, Side)> {
        let below = match self {
            Bsdf::Single(_)
            | Bsdf::Blend {
                two_sided: false, ..
            } => false,
            _ if wo.z > 0.0 => false,
            _ if wo.z < 0.0 => true,
            _ => return None,
        };
        let facing = match self {
            Bsdf::Single(l) => Facing::One(l),
            Bsdf::TwoSided { front, back } => Facing::One(if below { back } else { front }),
            Bsdf::Blend {
                first,
                second,
                weight,
                ..
            } => Facing::Two(Mixture {
                first,
                second,
                weight: *weight,
            }),
        };
        Some((facing, Side(below)))
    }

    /// The models of the BSDF (both sides, both parts of a blend).
    fn lobes(&self) -> [&Lobe; 2] {
        match self {
            Bsdf::Single(l) => [l, l],
            Bsdf::TwoSided { front, back } => [front, back],
            Bsdf::Blend { first, second, .. } => [first, second],
        }
    }

    /// `f(wo, wi) · |cos θ_i|` in the local frame; zero for delta lobes.
    #[must_use]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        self.facing(wo)
            .map_or(Rgb::ZERO, |(l, f)| l.eval(f.apply(wo), f.apply(wi)))
    }

    /// Solid-angle density with which [`Self::sample`] produces `wi` through its smooth lobes.
    #[must_use]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.facing(wo)
            .map_or(0.0, |(l, f)| l.pdf(f.apply(wo), f.apply(wi)))
    }

    /// Samples `wi` given `wo`: `u_lobe` chooses among lobes, `u` samples the chosen one. `None`
    /// when no direction could be produced (wrong side, below the horizon, zero density).
    #[must_use]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let (l, f) = self.facing(wo)?;
        l.sample(f.apply(wo), u_lobe, u).map(|mut s| {
            s.wi = f.apply(s.wi);
            s
        })
    }

    /// Samples the direction light arriving from `wl` (local frame, towards where it came from)
    /// leaves in, weight `f(wo, wl) |cos θₒ| / pdf` with `wo` the sampled direction: the photon
    /// passes' sampling. The same as [`Self::sample`] for every reciprocal model; Klems matrices
    /// are not reciprocal ([`Klems::sample_adjoint`]).
    #[must_use]
    pub fn sample_adjoint(&self, wl: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        match self {
            Bsdf::Single(Lobe::Klems(k)) => k.sample_adjoint(wl, u_lobe, u),
            _ => self.sample(wl, u_lobe, u),
        }
    }

    /// What a smooth Radiance `trans` or a `BRTDfunc` passes straight through to a ray
    /// crossing it at cosine `cos` with its normal (its patterns applied where the BSDF was
    /// looked up): `c T t_s` at that angle for `trans`, what its expressions gave for
    /// `BRTDfunc`; `None` for other models.
    #[must_use]
    pub fn straight_transmittance(&self, cos: f32) -> Option<Rgb> {
        match self {
            Bsdf::TwoSided {
                front: Lobe::Ward(w),
                ..
            }
            | Bsdf::Single(Lobe::Ward(w)) => w.straight_transmittance(cos),
            Bsdf::Single(Lobe::Brtd(b)) => Some(b.transmit),
            _ => None,
        }
    }

    /// True when the BSDF has a non-delta component (next-event estimation is worthwhile).
    #[must_use]
    pub fn has_smooth(&self) -> bool {
        self.lobes().iter().any(|l| l.has_smooth())
    }

    /// True when the BSDF has a Dirac delta lobe (smooth glass, mirrors, a smooth coating):
    /// light through it makes caustics.
    #[must_use]
    pub fn has_delta(&self) -> bool {
        self.lobes().iter().any(|l| match l {
            Lobe::Conductor(_)
            | Lobe::Dielectric(_)
            | Lobe::ThinDielectric(_)
            | Lobe::Plastic(_)
            | Lobe::Brtd(_) => true,
            Lobe::Ward(w) => w.has_delta(),
            _ => false,
        })
    }

    /// True when the BSDF sends light through the surface (smooth, rough or thin dielectrics).
    #[must_use]
    pub fn transmits(&self) -> bool {
        self.lobes().iter().any(|l| match l {
            Lobe::Dielectric(_) | Lobe::RoughDielectric(_) | Lobe::ThinDielectric(_) => true,
            Lobe::Principled(p) => p.transmits(),
            Lobe::Ward(w) => w.transmits(),
            Lobe::Klems(k) => k.transmits(),
            Lobe::Brtd(_) => true,
            _ => false,
        })
    }

    /// True when a lobe depends on the azimuth about the normal (two roughnesses, tabulated
    /// matrices): the radiance cache's tables, made at one azimuth, do not hold it.
    #[must_use]
    pub fn is_anisotropic(&self) -> bool {
        self.lobes().iter().any(|l| match l {
            Lobe::RoughConductor(b) => b.distr.alpha_u != b.distr.alpha_v,
            Lobe::RoughDielectric(b) => b.distr.alpha_u != b.distr.alpha_v,
            Lobe::Principled(b) => b.anisotropic > 0.0,
            Lobe::Ward(w) => w.roughness_v != w.roughness,
            Lobe::Klems(_) => true,
            _ => false,
        })
    }

    /// True when the BSDF is purely Lambertian (on both sides, for `twosided`; both models of
    /// a blend).
    #[must_use]
    pub fn is_diffuse_only(&self) -> bool {
        self.lobes().iter().all(|l| matches!(l, Lobe::Diffuse(_)))
    }

    /// The BSDF split for caching: `f = k(wo)/π + f_glossy`, where the Lambertian part `k/π`
    /// times the irradiance is what an irradiance cache serves and the glossy part (every
    /// non-Lambertian lobe: specular and rough reflection, refraction, plastic coatings) is
    /// traced. This is `k(wo)` (local frame): the back model's for `twosided` seen from below,
    /// zero for one-sided models seen from below, a blend's weighted sum. For plastics the
    /// coating's transmittance towards the light is replaced by its cosine-weighted mean (exact
    /// under uniform incident light); see [`plastic`] and [`roughplastic`].
    #[must_use]
    pub fn lambertian_albedo(&self, wo: Vec3) -> Rgb {
        // On the surface itself (wo.z = 0) every model's is zero.
        let Some((l, f)) = self.facing(wo) else {
            return Rgb::ZERO;
        };
        l.lambertian_albedo(f.apply(wo))
    }

    /// The glossy part alone, `f_glossy(wo, wi) · |cos θ_i|` (zero for delta lobes).
    #[must_use]
    pub fn eval_glossy(&self, wo: Vec3, wi: Vec3) -> Rgb {
        self.facing(wo)
            .map_or(Rgb::ZERO, |(l, f)| l.eval_glossy(f.apply(wo), f.apply(wi)))
    }

    /// Solid-angle density with which [`Self::sample_glossy`] produces `wi` (smooth lobes).
    #[must_use]
    pub fn pdf_glossy(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.facing(wo)
            .map_or(0.0, |(l, f)| l.pdf_glossy(f.apply(wo), f.apply(wi)))
    }

    /// Samples the glossy part alone, weight `f_glossy · |cos θ_i| / pdf` (for delta lobes the
    /// delta's weight over the probability of its choice among the glossy lobes).
    #[must_use]
    pub fn sample_glossy(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let (l, f) = self.facing(wo)?;
        l.sample_glossy(f.apply(wo), u_lobe, u).map(|mut s| {
            s.wi = f.apply(s.wi);
            s
        })
    }

    /// True when the BSDF has a glossy (non-Lambertian) part.
    #[must_use]
    pub fn has_glossy(&self) -> bool {
        self.lobes().iter().any(|l| l.has_glossy())
    }

    /// Albedo of the Lambertian part (the base of plastics, `K_d` of OBJ materials, zero for
    /// purely specular models; the front model's for `twosided`, a blend's weighted sum).
    #[must_use]
    pub fn diffuse_reflectance(&self) -> Rgb {
        match self {
            Bsdf::Single(l) | Bsdf::TwoSided { front: l, .. } => l.diffuse_reflectance(),
            Bsdf::Blend {
                first,
                second,
                weight,
                ..
            } => {
                first.diffuse_reflectance() * (1.0 - weight)
                    + second.diffuse_reflectance() * *weight
            }
        }
    }
}

/// A model with its textures, before lookup.
#[derive(Clone, Debug)]
enum Compiled {
    Diffuse {
        reflectance: Texture,
    },
    Plastic {
        diffuse: Texture,
        proto: Plastic,
    },
    RoughPlastic {
        diffuse: Texture,
        proto: RoughPlastic,
    },
    Phong {
        diffuse: Texture,
        proto: Phong,
    },
    Principled {
        base_color: Texture,
        /// In the order of [`ircache_scene::PRINCIPLED_PARAMETERS`].
        parameters: Box<[Texture; 10]>,
        eta: f32,
    },
    Fixed(Lobe),
}

impl Compiled {
    fn new(desc: &BsdfDesc) -> Compiled {
        match desc {
            BsdfDesc::Diffuse { reflectance } => Compiled::Diffuse {
                reflectance: Texture::from_desc(reflectance),
            },
            // A null surface is never shaded: `volpath` passes through it (`Shape::null`) and
            // the other integrators refuse such scenes (`Scene::require_no_media`). Black in case.
            BsdfDesc::Null => Compiled::Diffuse {
                reflectance: Texture::from_desc(&ircache_scene::TextureDesc::Constant(Rgb::ZERO)),
            },
            // Nested twosided: the inner front model (Mitsuba does not nest them either).
            BsdfDesc::TwoSided { front, .. } => Compiled::new(front),
            // A blend's second model and weight are the material's (`Material::blend`); the
            // loader puts blends nowhere else.
            BsdfDesc::Blend { first, .. } => Compiled::new(first),
            // Normal and bump maps act on the shading frame (`Material::perturb`); a mask's
            // opacity on the path (`Material::opacity`), where it wraps the material.
            BsdfDesc::NormalMap { nested, .. }
            | BsdfDesc::BumpMap { nested, .. }
            | BsdfDesc::Mask { nested, .. } => Compiled::new(nested),
            BsdfDesc::Plastic {
                diffuse_reflectance,
                specular_reflectance,
                int_ior,
                ext_ior,
                nonlinear,
            } => {
                let diffuse = Texture::from_desc(diffuse_reflectance);
                let eta = int_ior / ext_ior;
                let proto = Plastic {
                    diffuse_reflectance: Rgb::ZERO,
                    specular_reflectance: *specular_reflectance,
                    eta,
                    fdr_int: fresnel::fresnel_diffuse_reflectance(1.0 / eta),
                    specular_sampling_weight: sampling_weight(
                        specular_reflectance.mean(),
                        diffuse.mean_scalar(),
                    ),
                    nonlinear: *nonlinear,
                };
                Compiled::Plastic { diffuse, proto }
            }
            BsdfDesc::RoughPlastic {
                distribution,
                alpha,
                diffuse_reflectance,
                specular_reflectance,
                int_ior,
                ext_ior,
                nonlinear,
            } => {
                let diffuse = Texture::from_desc(diffuse_reflectance);
                let eta = int_ior / ext_ior;
                let distr = Microfacet::new(*distribution, *alpha, *alpha);
                let proto = RoughPlastic {
                    distr,
                    diffuse_reflectance: Rgb::ZERO,
                    specular_reflectance: *specular_reflectance,
                    eta,
                    specular_sampling_weight: sampling_weight(
                        specular_reflectance.mean(),
                        diffuse.mean_scalar(),
                    ),
                    nonlinear: *nonlinear,
                    tables: RoughPlasticTables::interned(&distr, eta),
                };
                Compiled::RoughPlastic { diffuse, proto }
            }
            BsdfDesc::Conductor {
                eta,
                k,
                specular_reflectance,
            } => Compiled::Fixed(Lobe::Conductor(Conductor {
                eta: *eta,
                k: *k,
                specular_reflectance: *specular_reflectance,
            })),
            BsdfDesc::RoughConductor {
                distribution,
                alpha_u,
                alpha_v,
                eta,
                k,
                specular_reflectance,
            } => Compiled::Fixed(Lobe::RoughConductor(RoughConductor {
                distr: Microfacet::new(*distribution, *alpha_u, *alpha_v),
                eta: *eta,
                k: *k,
                specular_reflectance: *specular_reflectance,
            })),
            BsdfDesc::Dielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } => Compiled::Fixed(Lobe::Dielectric(Dielectric {
                eta: int_ior / ext_ior,
                specular_reflectance: *specular_reflectance,
                specular_transmittance: *specular_transmittance,
            })),
            BsdfDesc::RoughDielectric {
                distribution,
                alpha_u,
                alpha_v,
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } => Compiled::Fixed(Lobe::RoughDielectric(RoughDielectric {
                distr: Microfacet::new(*distribution, *alpha_u, *alpha_v),
                eta: int_ior / ext_ior,
                specular_reflectance: *specular_reflectance,
                specular_transmittance: *specular_transmittance,
            })),
            BsdfDesc::Ward {
                color,
                specularity,
                roughness,
                metal,
                transmissivity,
                transmitted_specular,
                anisotropy,
                ..
            } => Compiled::Fixed(Lobe::Ward(Ward {
                color: *color,
                specularity: *specularity,
                roughness: *roughness,
                roughness_v: anisotropy.map_or(*roughness, |a| a.roughness_v),
                axis: [1.0, 0.0],
                metal: *metal,
                transmissivity: *transmissivity,
                transmitted_specular: *transmitted_specular,
            })),
            BsdfDesc::RadianceMirror { reflectance, .. } => {
                Compiled::Fixed(Lobe::Conductor(Conductor {
                    eta: Rgb::ZERO,
                    k: Rgb::ONE,
                    specular_reflectance: *reflectance,
                }))
            }
            BsdfDesc::RadianceBrtd {
                diffuse_front,
                diffuse_back,
                diffuse_transmit,
                ..
            } => Compiled::Fixed(Lobe::Brtd(Brtd {
                reflect: Rgb::ZERO,
                transmit: Rgb::ZERO,
                diffuse_front: *diffuse_front,
                diffuse_back: *diffuse_back,
                diffuse_transmit: *diffuse_transmit,
            })),
            BsdfDesc::Klems {
                data,
                reflect_front,
                reflect_back,
                transmit,
                ..
            } => Compiled::Fixed(Lobe::Klems(Klems {
                tables: KlemsTables::interned(data),
                axis: [1.0, 0.0],
                reflect_front: *reflect_front,
                reflect_back: *reflect_back,
                transmit: *transmit,
            })),
            BsdfDesc::ThinDielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } => Compiled::Fixed(Lobe::ThinDielectric(ThinDielectric {
                eta: int_ior / ext_ior,
                specular_reflectance: *specular_reflectance,
                specular_transmittance: *specular_transmittance,
                transmissivity: None,
            })),
            BsdfDesc::Glass {
                transmissivity,
                ior,
                ..
            } => Compiled::Fixed(Lobe::ThinDielectric(ThinDielectric {
                eta: *ior,
                specular_reflectance: Rgb::ONE,
                specular_transmittance: Rgb::ONE,
                transmissivity: Some(*transmissivity),
            })),
            BsdfDesc::Principled {
                base_color,
                parameters,
                eta,
            } => Compiled::Principled {
                base_color: Texture::from_desc(base_color),
                parameters: Box::new(parameters.each_ref().map(Texture::from_desc)),
                eta: *eta,
            },
            BsdfDesc::ObjPhong {
                diffuse,
                specular,
                exponent,
            } => Compiled::Phong {
                diffuse: Texture::from_desc(diffuse),
                proto: Phong {
                    diffuse: Rgb::ZERO,
                    specular: *specular,
                    exponent: exponent.max(0.0),
                },
            },
        }
    }

    fn at(&self, uv: Vec2) -> Lobe {
        match self {
            Compiled::Diffuse { reflectance } => Lobe::Diffuse(Diffuse {
                reflectance: reflectance.eval(uv),
            }),
            Compiled::Plastic { diffuse, proto } => Lobe::Plastic(Plastic {
                diffuse_reflectance: diffuse.eval(uv),
                ..*proto
            }),
            Compiled::RoughPlastic { diffuse, proto } => Lobe::RoughPlastic(RoughPlastic {
                diffuse_reflectance: diffuse.eval(uv),
                ..*proto
            }),
            Compiled::Phong { diffuse, proto } => Lobe::Phong(Phong {
                diffuse: diffuse.eval(uv),
                ..*proto
            }),
            Compiled::Principled {
                base_color,
                parameters,
                eta,
            } => {
                let [roughness, anisotropic, metallic, spec_trans, spec_tint, sheen, sheen_tint, flatness, clearcoat, clearcoat_gloss] =
                    parameters
                        .each_ref()
                        .map(|t| t.eval(uv).luminance().clamp(0.0, 1.0));
                Lobe::Principled(Principled {
                    base_color: base_color.eval(uv),
                    roughness,
                    anisotropic,
                    metallic,
                    spec_trans,
                    spec_tint,
                    sheen,
                    sheen_tint,
                    flatness,
                    clearcoat,
                    clearcoat_gloss,
                    eta: *eta,
                })
            }
            Compiled::Fixed(l) => *l,
        }
    }

    fn mean_diffuse(&self) -> Rgb {
        match self {
            Compiled::Diffuse { reflectance: t }
            | Compiled::Plastic { diffuse: t, .. }
            | Compiled::RoughPlastic { diffuse: t, .. }
            | Compiled::Phong { diffuse: t, .. } => t.mean(),
            Compiled::Principled {
                base_color,
                parameters,
                ..
            } => {
                // (1 − metallic)(1 − spec_trans) at the parameters' means.
                let mean = |t: &Texture| t.mean().luminance().clamp(0.0, 1.0);
                {
                    let metallic = mean(&parameters[ircache_scene::PRINCIPLED_METALLIC]);
                    let spec_trans = mean(&parameters[ircache_scene::PRINCIPLED_SPEC_TRANS]);
                    base_color.mean() * ((1.0 - metallic) * (1.0 - spec_trans))
                }
            }
            Compiled::Fixed(l) => l.diffuse_reflectance(),
        }
    }
}

/// Mitsuba's specular sampling weight `s̄ / (d̄ + s̄)`.
fn sampling_weight(s_mean: f32, d_mean: f32) -> f32 {
    let (s, d) = (s_mean.max(0.0), d_mean.max(0.0));
    if s + d > 0.0 {
        s / (s + d)
    } else {
        0.5
    }
}

/// A material compiled from a [`BsdfDesc`] at scene load (textures built, tables precomputed).
#[derive(Clone, Debug)]
pub struct Material {
    front: Compiled,
    /// `Some` for `twosided` (the back model, or a copy of the front one).
    back: Option<Compiled>,
    /// A normal or bump map.
    perturbation: Option<Perturbation>,
    /// A mask's opacity (Mitsuba's `mask` around the material, or around both sides of a
    /// `twosided`): the share of paths that meet the surface, the rest passing through.
    opacity: Option<Texture>,
    /// A `blendbsdf`'s second model and its weight (`front` then is the first model, and
    /// `back`, for a `twosided` blend, a copy of it).
    blend: Option<(Compiled, Texture)>,
    /// Patterns on a Radiance material's colour, by where and from where it is seen
    /// ([`Material::at_hit`]).
    pattern: Option<Arc<dyn SurfacePattern>>,
    /// A Radiance mixture's weight of the second model at each hit ([`Material::at_hit`]).
    blend_pattern: Option<Arc<dyn SurfacePattern>>,
    /// A world direction that orients the model about the normal at each hit.
    orientation: Option<Orientation>,
    /// A `BRTDfunc`'s mirror reflectance and straight transmittance, functions of the ray
    /// evaluated at each hit.
    brtd: Option<[Arc<dyn SurfacePattern>; 2]>,
}

/// A world direction that orients a model about the normal ([`Material::at_hit`]).
#[derive(Clone, Copy, Debug)]
enum Orientation {
    /// A Klems BSDF's up vector: its matrices' x axis is `up × n`.
    KlemsUp(Vec3),
    /// `plastic2`'s and `metal2`'s `u`: the first roughness lies along its projection.
    WardU(Vec3),
}

/// `u` projected onto the tangent plane of `frame` (`aniso.c`'s `getacoords`), as (cos, sin)
/// of its angle from the frame's first tangent; `None` where `u` is along the normal.
fn tangent_axis(u: Vec3, frame: &Frame) -> Option<[f32; 2]> {
    let (c, s) = (u.dot(frame.s), u.dot(frame.t));
    let len = c.hypot(s);
    (len > 1e-6 * u.length()).then(|| [c / len, s / len])
}

/// The Klems matrices' x axis, `up × n`, in `frame` as (cos, sin) of its angle from the frame's
/// first tangent; the tangent itself where `up` is along the normal (Radiance warns there and
/// leaves the surface black).
fn klems_axis(up: Vec3, frame: &Frame) -> [f32; 2] {
    tangent_axis(up.cross(frame.n), frame).unwrap_or([1.0, 0.0])
}

/// A perturbation of the shading normal by a texture (normal or bump map), shaded as Mitsuba 3's
/// `normalmap` and `bumpmap` do.
#[derive(Clone, Debug)]
pub struct Perturbation {
    /// The texture and how it perturbs.
    pub map: PerturbationMap,
    /// The shadowing function and the flipping of normals that face away.
    pub shading: ircache_scene::PerturbedShading,
    /// [`lambertian_share_table`], where the shadowing function is on.
    lambertian_share: Option<[f32; LAMBERTIAN_SHARE_SAMPLES]>,
}

/// Samples of [`lambertian_share_table`] over the tilt's cosine in [0, 1].
const LAMBERTIAN_SHARE_SAMPLES: usize = 129;

/// ∫₀^2π max(0, a cos φ + b) dφ for a ≥ 0: the azimuthal integral of a tilted cosine lobe
/// (2πb where the lobe covers the whole circle, 0 where it misses it).
fn clipped_cosine_circle(a: f64, b: f64) -> f64 {
    if a <= b.abs() {
        return if b > 0.0 {
            2.0 * std::f64::consts::PI * b
        } else {
            0.0
        };
    }
    2.0 * (a * a - b * b).sqrt() + 2.0 * b * (-b / a).acos()
}

/// [`Perturbation::lambertian_share`] with Estevez et al.'s shadowing, tabulated over the
/// tilt's cosine: (1/π)∫ G(μ) max(0, n_p·ω) dω over the hemisphere of the unperturbed normal,
/// μ = cos θ from it, α² = min(tan²β / 8, 1), by Gauss–Legendre in μ with the azimuth in closed
/// form ([`clipped_cosine_circle`]).
fn lambertian_share_table() -> [f32; LAMBERTIAN_SHARE_SAMPLES] {
    let nodes = ircache_math::harmonics::quadrature::gauss_legendre(96, 0.0, 1.0);
    std::array::from_fn(|i| {
        let cos_b = i as f64 / (LAMBERTIAN_SHARE_SAMPLES - 1) as f64;
        let sin_b = (1.0 - cos_b * cos_b).max(0.0).sqrt();
        let alpha2 = if cos_b > 0.0 {
            (0.125 * sin_b * sin_b / (cos_b * cos_b)).min(1.0)
        } else {
            1.0
        };
        nodes
            .iter()
            .map(|&(mu, w)| {
                let sin_t = (1.0 - mu * mu).max(0.0).sqrt();
                let tan2 = sin_t * sin_t / (mu * mu);
                let g = 2.0 / (1.0 + (1.0 + alpha2 * tan2).sqrt());
                w * g * clipped_cosine_circle(sin_b * sin_t, cos_b * mu)
            })
            .sum::<f64>() as f32
            / std::f32::consts::PI
    })
}

/// tan²θ from cos θ (infinite at the horizon).
#[inline]
fn tan2_from_cos(c: f32) -> f32 {
    let c2 = (c * c).min(1.0);
    (1.0 - c2) / c2
}

/// Estevez et al.'s roughness of the bump terminator, `α² = min(tan²θₚ / 8, 1)`, θₚ the angle
/// of the perturbed normal `n_p` from the unperturbed `n`.
#[inline]
fn terminator_alpha2(n: Vec3, n_p: Vec3) -> f32 {
    (0.125 * tan2_from_cos(n.dot(n_p))).min(1.0)
}

/// The texture of a [`Perturbation`].
#[derive(Clone, Debug)]
pub enum PerturbationMap {
    /// Tangent-space normals n = 2·rgb − 1 along (dp/du, dp/dv, n).
    NormalMap(Texture),
    /// Heights scale × luminance; the normal of the displaced surface.
    BumpMap(Texture, f32),
}

impl Perturbation {
    /// A perturbation by `map`, shaded as `shading` says.
    #[must_use]
    pub fn new(map: PerturbationMap, shading: ircache_scene::PerturbedShading) -> Perturbation {
        Perturbation {
            map,
            shading,
            lambertian_share: shading.shadowing.then(lambertian_share_table),
        }
    }

    /// The perturbed unit shading normal at `uv` for the unperturbed normal `n`, the geometric
    /// normal `ng`, the surface derivatives `dpdu`, `dpdv` and the unit direction `wi` towards
    /// the viewer; `n` itself where the derivatives are degenerate. As Mitsuba: a bump map's
    /// normal is turned to the geometric normal's side, and with `flip_invalid_normals` a normal
    /// facing away from the viewer is mirrored about `n`.
    #[must_use]
    pub fn normal(&self, uv: Vec2, n: Vec3, ng: Vec3, dpdu: Vec3, dpdv: Vec3, wi: Vec3) -> Vec3 {
        // An orthonormal tangent frame around n, with s along dp/du.
        let s = (dpdu - n * n.dot(dpdu)).normalize_or_zero();
        if s == Vec3::ZERO {
            return n;
        }
        let t = n.cross(s);
        let out = match &self.map {
            // In the shading frame (s, n × s, n), as Mitsuba's: its y is n × s whichever side
            // dp/dv lies on (on a sphere, the opposite of increasing v).
            PerturbationMap::NormalMap(tex) => {
                let c = tex.eval(uv);
                s * (2.0 * c.r - 1.0) + t * (2.0 * c.g - 1.0) + n * (2.0 * c.b - 1.0)
            }
            PerturbationMap::BumpMap(tex, scale) => {
                // Central differences of the height, one texel apart.
                let (du, dv) = tex.texel_size();
                let h = |uv: Vec2| tex.eval(uv).luminance() * *scale;
                let dhdu = (h(uv + Vec2::new(du, 0.0)) - h(uv - Vec2::new(du, 0.0))) / (2.0 * du);
                let dhdv = (h(uv + Vec2::new(0.0, dv)) - h(uv - Vec2::new(0.0, dv))) / (2.0 * dv);
                let (lu, lv) = (dpdu.length(), dpdv.length());
                if lu <= 0.0 || lv <= 0.0 {
                    return n;
                }
                // The displaced surface p + h n has tangents dp/du + h_u n, dp/dv + h_v n:
                // its normal leans against the height's gradient along dp/du and dp/dv.
                let tv = if t.dot(dpdv) < 0.0 { -t } else { t };
                let out = n - s * (dhdu / lu) - tv * (dhdv / lv);
                if out.dot(ng) < 0.0 {
                    -out
                } else {
                    out
                }
            }
        };
        let mut out = out.normalize_or_zero();
        if out == Vec3::ZERO {
            return n;
        }
        if self.shading.flip_invalid_normals && wi.dot(n) * wi.dot(out) <= 0.0 {
            // Mirrored about n: its tangential part negated.
            out = (2.0 * out.dot(n)) * n - out;
        }
        out
    }

    /// The share of a Lambertian lobe about the perturbed normal `n_p` that light arriving
    /// evenly over the hemisphere of the unperturbed `n` reaches: (1/π)∫ S(ω) max(0, n_p·ω) dω
    /// over that hemisphere, S [`Self::shadowing`] (Mitsuba's perturbed BSDFs are 0 for light
    /// from the other side of `n`). The factor for a Lambertian part whose irradiance, held
    /// for `n` and turned to `n_p` by its rotational gradient to first order, comes from a
    /// cache: exact under uniform light. Without the shadowing function (1 + cos β)/2, β the
    /// tilt; with it, tabulated over cos β. 1 without a tilt.
    #[must_use]
    pub fn lambertian_share(&self, n: Vec3, n_p: Vec3) -> f32 {
        let cos_b = n.dot(n_p).clamp(0.0, 1.0);
        let Some(table) = &self.lambertian_share else {
            return 0.5 * (1.0 + cos_b);
        };
        let x = cos_b * (table.len() - 1) as f32;
        let i = (x as usize).min(table.len() - 2);
        let f = x - i as f32;
        table[i] * (1.0 - f) + table[i + 1] * f
    }

    /// Estevez et al. 2019's shadowing of a perturbed normal `n_p` for light along `wi` (both
    /// unit, world), with `n` the unperturbed normal: `2 / (1 + √(1 + α² tan²θᵢ))`,
    /// `α² = min(tan²θₚ / 8, 1)`, angles measured from `n` (Mitsuba's
    /// `eval_shadow_terminator`); 1 where the shadowing function is off.
    #[inline]
    #[must_use]
    pub fn shadowing(&self, n: Vec3, n_p: Vec3, wi: Vec3) -> f32 {
        if !self.shading.shadowing {
            return 1.0;
        }
        let alpha2 = terminator_alpha2(n, n_p);
        if alpha2 <= 0.0 {
            return 1.0;
        }
        let g = 2.0 / (1.0 + (1.0 + alpha2 * tan2_from_cos(n.dot(wi))).sqrt());
        if g.is_finite() {
            g
        } else {
            0.0
        }
    }
}

impl Material {
    /// The sheet when this material is an untextured, unperturbed thin dielectric (a window
    /// pane): rays and shadow rays pass through it (see [`crate::scene::Scene::shadow_transmittance`]).
    #[must_use]
    pub fn thin_sheet(&self) -> Option<ThinDielectric> {
        match (&self.front, &self.back, &self.perturbation) {
            (Compiled::Fixed(Lobe::ThinDielectric(t)), None, None)
                if self.opacity.is_none() && self.blend.is_none() =>
            {
                Some(*t)
            }
            _ => None,
        }
    }

    /// True for a smooth Radiance `trans` or a `BRTDfunc` (straight transmission): light
    /// samples from lights that paths cannot hit pass through it
    /// ([`Bsdf::straight_transmittance`]).
    #[must_use]
    pub fn has_straight_transmission(&self) -> bool {
        self.brtd.is_some()
            || matches!(&self.front, Compiled::Fixed(Lobe::Ward(w)) if w.straight_transmittance(1.0).is_some())
    }

    /// [`Material::thin_sheet`] where a ray along the unit `d` crosses it at the point `p`
    /// (unit geometric normal `ng`, texture coordinates `uv`, `t` from the ray's start): a
    /// Radiance pane's patterns tint what it transmits there (`glass.c`).
    #[must_use]
    pub fn thin_sheet_at(
        &self,
        uv: Vec2,
        p: Vec3,
        ng: Vec3,
        d: Vec3,
        t: f32,
    ) -> Option<ThinDielectric> {
        let mut sheet = self.thin_sheet()?;
        if let Some(pattern) = &self.pattern {
            tint_pane(&mut sheet, pattern.factor(p, ng, d, t, uv));
        }
        Some(sheet)
    }

    /// Compiles a description.
    #[must_use]
    pub fn from_desc(desc: &BsdfDesc) -> Material {
        let (mut m, opacity) = match desc {
            BsdfDesc::Mask { opacity, nested } => (Material::from_unmasked(nested), Some(opacity)),
            // A mask inside `twosided` masks both sides.
            BsdfDesc::TwoSided { front, back: None } => match front.as_ref() {
                BsdfDesc::Mask { opacity, nested } => {
                    let unmasked = BsdfDesc::TwoSided {
                        front: nested.clone(),
                        back: None,
                    };
                    (Material::from_unmasked(&unmasked), Some(opacity))
                }
                _ => (Material::from_unmasked(desc), None),
            },
            d => (Material::from_unmasked(d), None),
        };
        m.opacity = opacity.map(Texture::from_desc);
        m
    }

    /// The share of paths that meet the surface at `uv` (its mask's opacity, a texture's
    /// luminance clamped to [0, 1]); 1 without a mask.
    #[must_use]
    pub fn opacity(&self, uv: Vec2) -> f32 {
        self.opacity
            .as_ref()
            .map_or(1.0, |t| t.eval(uv).luminance().clamp(0.0, 1.0))
    }

    /// True when the material has a mask.
    #[must_use]
    pub fn is_masked(&self) -> bool {
        self.opacity.is_some()
    }

    fn from_unmasked(desc: &BsdfDesc) -> Material {
        let (desc, perturbation) = match desc {
            BsdfDesc::NormalMap {
                normals,
                nested,
                shading,
            } => (
                nested.as_ref(),
                Some(Perturbation::new(
                    PerturbationMap::NormalMap(Texture::from_desc(
                        &ircache_scene::TextureDesc::Bitmap(normals.clone()),
                    )),
                    *shading,
                )),
            ),
            BsdfDesc::BumpMap {
                height,
                scale,
                nested,
                shading,
            } => (
                nested.as_ref(),
                Some(Perturbation::new(
                    PerturbationMap::BumpMap(
                        Texture::from_desc(&ircache_scene::TextureDesc::Bitmap(height.clone())),
                        *scale,
                    ),
                    *shading,
                )),
            ),
            d => (d, None),
        };
        // A blend, or the single model of a twosided.
        let blend = match desc {
            BsdfDesc::Blend { weight, second, .. } => Some((weight, second)),
            BsdfDesc::TwoSided { front, back: None } => match front.as_ref() {
                BsdfDesc::Blend { weight, second, .. } => Some((weight, second)),
                _ => None,
            },
            _ => None,
        };
        let mut m = match desc {
            BsdfDesc::TwoSided { front, back } => {
                let f = Compiled::new(front);
                let b = match back {
                    Some(b) => Compiled::new(b),
                    None => f.clone(),
                };
                Material {
                    front: f,
                    back: Some(b),
                    perturbation: None,
                    opacity: None,
                    blend: None,
                    pattern: None,
                    blend_pattern: None,
                    orientation: None,
                    brtd: None,
                }
            }
            d => Material {
                front: Compiled::new(d),
                back: None,
                perturbation: None,
                opacity: None,
                blend: None,
                pattern: None,
                blend_pattern: None,
                orientation: None,
                brtd: None,
            },
        };
        if let BsdfDesc::RadianceBrtd {
            reflect, transmit, ..
        } = desc
        {
            m.brtd = Some([reflect.clone(), transmit.clone()]);
        }
        m.orientation = match desc {
            BsdfDesc::Klems { up, .. } => Some(Orientation::KlemsUp(*up)),
            BsdfDesc::TwoSided { front, .. } => match front.as_ref() {
                BsdfDesc::Ward {
                    anisotropy: Some(a),
                    ..
                } => Some(Orientation::WardU(a.u)),
                _ => None,
            },
            _ => None,
        };
        m.pattern = color_pattern(desc);
        m.blend_pattern = blend_pattern(desc);
        m.blend = blend.map(|(w, second)| (Compiled::new(second), Texture::from_desc(w)));
        // A normal or bump map inside twosided applies to both sides.
        m.perturbation = perturbation.or_else(|| match desc {
            BsdfDesc::TwoSided { front, .. } => match front.as_ref() {
                BsdfDesc::NormalMap { .. } | BsdfDesc::BumpMap { .. } => {
                    Material::from_desc(front).perturbation
                }
                _ => None,
            },
            _ => None,
        });
        m
    }

    /// The normal or bump map, if any.
    #[must_use]
    pub fn perturbation(&self) -> Option<&Perturbation> {
        self.perturbation.as_ref()
    }

    /// Radiance's textures on the material (`texfunc`, `texdata` among its patterns), which
    /// displace its normal at each hit ([`crate::scene::Scene::interaction`]).
    #[must_use]
    pub fn radiance_texture(&self) -> Option<&Arc<dyn SurfacePattern>> {
        self.pattern.as_ref().filter(|p| p.perturbs())
    }

    /// The BSDF met at a hit: at texture coordinates `uv` and point `p` with unit geometric
    /// normal `ng` (unflipped) and shading `frame`, by a ray along the unit `d`, `t` from its
    /// start. Radiance's patterns multiply the material's colour there, as `normal.c` does, and
    /// a Klems BSDF's azimuth is set from its up vector and the frame's normal.
    #[must_use]
    pub fn at_hit(&self, uv: Vec2, p: Vec3, ng: Vec3, d: Vec3, t: f32, frame: &Frame) -> Bsdf {
        if self.brtd.is_none()
            && self.orientation.is_none()
            && self.pattern.is_none()
            && self.blend_pattern.is_none()
        {
            // Returned as `at` writes it: the edits below made a 136-byte copy (a `memcpy`
            // call, 3 % of the Cornell box) on every hit.
            return self.at(uv);
        }
        let mut bsdf = self.at(uv);
        if let (Some([reflect, transmit]), Bsdf::Single(Lobe::Brtd(b))) = (&self.brtd, &mut bsdf) {
            b.reflect = reflect.factor(p, ng, d, t, uv);
            b.transmit = transmit.factor(p, ng, d, t, uv);
        }
        match (self.orientation, &mut bsdf) {
            (Some(Orientation::KlemsUp(up)), Bsdf::Single(Lobe::Klems(k))) => {
                k.axis = klems_axis(up, frame);
            }
            (
                Some(Orientation::WardU(u)),
                Bsdf::TwoSided {
                    front: Lobe::Ward(f),
                    back: Lobe::Ward(b),
                },
            ) => {
                let axis = tangent_axis(u, frame);
                for w in [f, b] {
                    match axis {
                        Some(axis) => w.axis = axis,
                        // u along the normal: Radiance's punt, one rms roughness.
                        None => {
                            let rms = (0.5 * (w.roughness.powi(2) + w.roughness_v.powi(2))).sqrt();
                            w.roughness = rms;
                            w.roughness_v = rms;
                        }
                    }
                }
            }
            _ => {}
        }
        if let Some(pattern) = &self.pattern {
            bsdf.tint(pattern.factor(p, ng, d, t, uv));
        }
        if let (Some(pattern), Bsdf::Blend { weight, .. }) = (&self.blend_pattern, &mut bsdf) {
            *weight = pattern.factor(p, ng, d, t, uv).r.clamp(0.0, 1.0);
        }
        bsdf
    }

    /// The BSDF at texture coordinates `uv`, without the patterns that need the hit's point
    /// ([`Material::at_hit`]): for the properties all its points share.
    #[must_use]
    pub fn at(&self, uv: Vec2) -> Bsdf {
        if let Some((second, weight)) = &self.blend {
            return Bsdf::Blend {
                first: self.front.at(uv),
                second: second.at(uv),
                weight: weight.eval(uv).luminance().clamp(0.0, 1.0),
                two_sided: self.back.is_some(),
            };
        }
        match &self.back {
            None => Bsdf::Single(self.front.at(uv)),
            Some(b) => Bsdf::TwoSided {
                front: self.front.at(uv),
                back: b.at(uv),
            },
        }
    }

    /// True when every model of the material is isotropic about the normal, so the shading
    /// frame's tangent does not matter.
    #[must_use]
    pub fn is_tangent_free(&self) -> bool {
        let free = |c: &Compiled| {
            matches!(
                c,
                Compiled::Diffuse { .. }
                    | Compiled::Plastic { .. }
                    | Compiled::RoughPlastic { .. }
                    | Compiled::Phong { .. }
            )
        };
        free(&self.front)
            && self.back.as_ref().is_none_or(free)
            && self.blend.as_ref().is_none_or(|(b, _)| free(b))
            && self.perturbation.is_none()
    }

    /// True when some model of the material reads an image texture (it needs texture
    /// coordinates).
    #[must_use]
    pub fn is_textured(&self) -> bool {
        if self.pattern.is_some() || self.blend_pattern.is_some() {
            return true;
        }
        let textured = |c: &Compiled| match c {
            Compiled::Diffuse { reflectance: t }
            | Compiled::Plastic { diffuse: t, .. }
            | Compiled::RoughPlastic { diffuse: t, .. }
            | Compiled::Phong { diffuse: t, .. } => !matches!(t, Texture::Constant(_)),
            Compiled::Principled {
                base_color,
                parameters,
                ..
            } => std::iter::once(base_color)
                .chain(parameters.iter())
                .any(|t| !matches!(t, Texture::Constant(_))),
            Compiled::Fixed(_) => false,
        };
        textured(&self.front)
            || self.back.as_ref().is_some_and(textured)
            || self
                .blend
                .as_ref()
                .is_some_and(|(b, w)| textured(b) || !matches!(w, Texture::Constant(_)))
            || self.perturbation.is_some()
            || self
                .opacity
                .as_ref()
                .is_some_and(|t| !matches!(t, Texture::Constant(_)))
    }

    /// True for Mitsuba's `twosided` wrapper.
    #[must_use]
    pub fn is_two_sided(&self) -> bool {
        self.back.is_some()
    }

    /// Average albedo of the Lambertian part over the textures (front model; zero if none), for
    /// caches that need a texture-independent estimate.
    #[must_use]
    pub fn mean_diffuse_reflectance(&self) -> Rgb {
        match &self.blend {
            None => self.front.mean_diffuse(),
            Some((second, weight)) => {
                let w = weight.mean().luminance().clamp(0.0, 1.0);
                self.front.mean_diffuse() * (1.0 - w) + second.mean_diffuse() * w
            }
        }
    }
}

#[cfg(test)]
mod tests;
