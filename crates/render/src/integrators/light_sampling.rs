//! Next-event estimation: the one light-sampling estimator that every integrator and every cache
//! uses. Light samples are combined with the BSDF sampling of the same vertex by the power
//! heuristic (Veach 1997 §9.2), weighted by the sample counts; where the path continues through
//! only part of the BSDF (the glossy part, when a cache serves the Lambertian part), the rest of
//! the BSDF has no second strategy and the light samples estimate it alone.

use super::{mis_weight, RayCounts};
use crate::bsdf::{Bsdf, BsdfSample};
use crate::lights::{Receiver, SharedSetUp};
use crate::sampler::{dims, Sampler};
use crate::scene::{Interaction, Scene};
use ircache_math::{Ray, Rgb, Vec2, Vec3};

/// Light samples whose shadow rays are traced later, together: the first vertices of a pixel's
/// camera paths lie close to each other and their shadow rays head for the same lights, so a
/// 16-wide Embree packet traces them 2.7–4.4× faster per ray than one at a time (Cornell box,
/// Sponza). Each entry is a shadow ray, what it brings if unoccluded, and which path it is
/// for.
#[derive(Clone, Debug, Default)]
pub struct DeferredShadows {
    rays: Vec<Ray>,
    light: Vec<(Rgb, u32)>,
    /// The path whose light samples are being deferred.
    pub owner: u32,
}

impl DeferredShadows {
    /// Forgets every entry.
    pub fn clear(&mut self) {
        self.rays.clear();
        self.light.clear();
    }

    /// Traces the shadow rays in packets of 16 and adds what each unoccluded one brings to its
    /// path's radiance in `l` (indexed by owner), in the order the samples were taken.
    pub fn resolve(&mut self, scene: &Scene, l: &mut [Rgb]) {
        if scene.has_see_through {
            // Rays that cross window panes carry their transmittance: one at a time.
            for (ray, &(value, owner)) in self.rays.iter().zip(&self.light) {
                l[owner as usize] += value * scene.shadow_transmittance(ray);
            }
            self.clear();
            return;
        }
        let mut occluded = [false; 16];
        for (rays, light) in self.rays.chunks(16).zip(self.light.chunks(16)) {
            let occluded = &mut occluded[..rays.len()];
            scene.accel.occluded16(rays, occluded);
            for (&(value, owner), &o) in light.iter().zip(occluded.iter()) {
                if !o {
                    l[owner as usize] += value;
                }
            }
        }
        self.clear();
    }
}

/// True where a vertex's light samples alone estimate its direct light, without a BSDF sample
/// to combine them with: the path ends after the vertex (`last`), so that sample would serve
/// only to find emitters, and the BSDF is Lambertian and every light sampled in proportion to
/// what such a surface receives from it ([`crate::lights::LightSet::samples_diffuse_well`]),
/// so the light samples are as good as the combination. It saves the path's last ray: the
/// Cornell box's path tracer at `max_depth` 3 0.78× the time at the same error.
#[inline]
#[must_use]
pub fn light_samples_suffice(scene: &Scene, bsdf: &Bsdf, last: bool) -> bool {
    last && bsdf.is_diffuse_only() && scene.lights.samples_diffuse_well()
}

/// The vertex `it` as its light samples see it, viewed from `wo` (local frame): a surface that
/// reflects only, towards the side of `wo`, unless its BSDF transmits (then a point: light
/// from either side counts). An environment's samples keep to the hemisphere a reflecting
/// receiver faces ([`Receiver`]); a BSDF sample leaving the vertex must be weighed against the
/// same receiver.
#[inline]
#[must_use]
pub fn receiver(it: &Interaction, bsdf: &Bsdf, wo: Vec3) -> Receiver {
    if bsdf.transmits() {
        Receiver::point(it.p)
    } else {
        Receiver::reflecting(it.p, it.frame.n * 1.0f32.copysign(wo.z))
    }
}

/// Where a light sample's shadow ray is traced.
pub enum Shadows<'a> {
    /// At once, alone.
    Traced,
    /// Later, with others ([`DeferredShadows`]); the path's throughput at the vertex.
    Deferred(&'a mut DeferredShadows, Rgb),
}

/// The part of the BSDF that the vertex's BSDF sample draws from (the MIS partner of the light
/// samples).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BsdfStrategy {
    /// The whole BSDF (path tracing).
    All,
    /// The glossy part only: a cache serves the Lambertian part (see [`Bsdf::lambertian_albedo`]).
    Glossy,
}

impl BsdfStrategy {
    /// Solid-angle density of the sampled part.
    #[inline]
    #[must_use]
    pub fn pdf(self, bsdf: &Bsdf, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            BsdfStrategy::All => bsdf.pdf(wo, wi),
            BsdfStrategy::Glossy => bsdf.pdf_glossy(wo, wi),
        }
    }

    /// A sample of the part.
    #[inline]
    #[must_use]
    pub fn sample(self, bsdf: &Bsdf, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        match self {
            BsdfStrategy::All => bsdf.sample(wo, u_lobe, u),
            BsdfStrategy::Glossy => bsdf.sample_glossy(wo, u_lobe, u),
        }
    }
}

/// What a cache served at a vertex with the environment's light in it (see
/// `irradiance_cache::environment`): light samples of the environment estimate the rest.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnvironmentServed {
    /// `k(wo)` of the Lambertian part served as `k E/π` (black: not served).
    pub lambertian: Rgb,
    /// The glossy part was served by radiance records.
    pub glossy: bool,
}

impl EnvironmentServed {
    /// True when nothing was served with the environment in it.
    #[inline]
    #[must_use]
    pub fn is_none(&self) -> bool {
        self.lambertian.is_black() && !self.glossy
    }

    /// `f·|cos θᵢ|` less the parts served: `f − k |cos θᵢ|/π − f_glossy` (where served); may be
    /// negative (the BSDF's diffuse part against its Lambertian stand-in), zero for a served
    /// Lambertian surface.
    #[inline]
    #[must_use]
    pub fn remainder(&self, bsdf: &Bsdf, wo: Vec3, wi: Vec3, f: Rgb) -> Rgb {
        let mut rest = f - self.lambertian * (wi.z.abs() * ircache_math::INV_PI);
        if self.glossy {
            rest = rest - bsdf.eval_glossy(wo, wi);
        }
        // What is left of a served Lambertian surface is rounding.
        let scale = f.max_channel().max(f32::MIN_POSITIVE);
        if rest.r.abs().max(rest.g.abs()).max(rest.b.abs()) <= 1e-5 * scale {
            Rgb::ZERO
        } else {
            rest
        }
    }
}

/// How [`sample_lights`] picks the light of each sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Selection {
    /// One light per sample, chosen by its estimated contribution (`lights::selection`).
    Chosen,
    /// Every light in turn, `ne` samples each (as Radiance samples each source): for the few
    /// points of `ircache irradiance`, where a light that selection starves (a lamp's bulb hidden
    /// in its shade takes the samples of the panel beside it) must not leave noise; used up to
    /// `lights::selection::MAX_ESTIMATED` lights.
    EachLight,
}

/// Direct light reflected at `it` towards `wo` (local frame) by `ne` light samples (jittered over
/// a √ne × √ne grid when `ne` > 1 is a square). Each is weighted against `nb` samples of
/// `strategy` at the same vertex (`nb` = 0: the light samples estimate everything): a light
/// sample contributes `L/(ne·p_l) · (f − f_s·(1 − w))` with `f_s` the strategy's part of the BSDF
/// and `w = w_power(ne·p_l, nb·p_s)`; the BSDF samples that find an emitter add the rest.
/// `depth` is the vertex's depth in the path (which of the sampler's dimensions it draws).
/// Where the cache served parts of the BSDF with the environment's light in them (`served`),
/// samples of the environment estimate the rest ([`EnvironmentServed::remainder`]). With
/// [`Shadows::Deferred`], what the samples bring goes, times the throughput, to the deferred
/// shadows instead of the result.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn sample_lights<S: Sampler + ?Sized>(
    scene: &Scene,
    it: &Interaction,
    bsdf: &Bsdf,
    wo: Vec3,
    (ne, selection): (u32, Selection),
    (strategy, nb): (BsdfStrategy, u32),
    served: EnvironmentServed,
    depth: u32,
    sampler: &mut S,
    rays: &mut RayCounts,
    mut shadows: Shadows,
) -> Rgb {
    let mut l = Rgb::ZERO;
    if ne == 0 || !bsdf.has_smooth() || scene.lights.is_empty() {
        return l;
    }
    let (fe, fb) = (ne as f32, nb as f32);
    // One sample (every vertex but a first one given more) needs no grid, nor its square root.
    let side = if ne > 1 { (ne as f32).sqrt() as u32 } else { 1 };
    let grid = ne > 1 && side * side == ne;
    let mut shared = SharedSetUp::default();
    let at = receiver(it, bsdf, wo);
    for i in 0..ne {
        sampler.set_dimension(if i == 0 {
            dims::vertex(depth, dims::LIGHT)
        } else {
            dims::extra(depth, i)
        });
        let u_sel = if scene.lights.len() > 1 {
            sampler.next_1d()
        } else {
            sampler.skip_1d();
            0.0
        };
        let mut u = sampler.next_2d();
        if grid {
            u = (Vec2::new((i % side) as f32, (i / side) as f32) + u) / side as f32;
        }
        let lights = match selection {
            Selection::Chosen => 0..1,
            Selection::EachLight => 0..scene.lights.len(),
        };
        for light in lights {
            let ls = match selection {
                // Several samples share a rectangle's set-up; one needs no memo.
                Selection::Chosen if ne > 1 => {
                    scene.lights.sample_sharing(at, u_sel, u, &mut shared)
                }
                Selection::Chosen => scene.lights.sample(at, u_sel, u),
                Selection::EachLight => scene.lights.sample_light(light, 1.0, at, u),
            };
            let Some(ls) = ls else {
                continue;
            };
            let wi = it.frame.to_local(ls.wi);
            let f = bsdf.eval(wo, wi) * scene.perturbed_shadowing(it, ls.wi);
            if f.is_black() || ls.pdf <= 0.0 {
                continue;
            }
            let environment = !served.is_none() && scene.lights.is_environment(ls.light);
            // Of the environment, the sample estimates what the cache did not serve.
            let rest = if environment {
                served.remainder(bsdf, wo, wi, f)
            } else {
                f
            };
            if rest.is_black() {
                continue;
            }
            rays.shadow += 1;
            let shadow_ray = scene.shadow_ray(it, ls.wi, ls.distance);
            // Window panes on the way pass what they transmit (`Scene::shadow_transmittance`).
            let mut through_sheets = None;
            if matches!(shadows, Shadows::Traced) {
                if scene.has_see_through || (ls.is_delta && scene.has_straight_trans) {
                    let tr = if ls.is_delta {
                        scene.delta_shadow_transmittance(&shadow_ray)
                    } else {
                        scene.shadow_transmittance(&shadow_ray)
                    };
                    if tr.is_black() {
                        continue;
                    }
                    through_sheets = Some(tr);
                } else if scene.accel.occluded(&shadow_ray) {
                    continue;
                }
            }
            // With the served parts off (`rest`), the traced glossy part is weighed against its BSDF
            // sample as ever; only a remainder of the environment may be negative.
            let weighted = if ls.is_delta || nb == 0 {
                rest
            } else {
                let w = mis_weight(fe * ls.pdf, fb * strategy.pdf(bsdf, wo, wi));
                match strategy {
                    // The strategy's part is the whole BSDF: f·w, without evaluating it twice.
                    BsdfStrategy::All => rest * w,
                    BsdfStrategy::Glossy => {
                        let x = rest - bsdf.eval_glossy(wo, wi) * (1.0 - w);
                        if environment {
                            x
                        } else {
                            x.max(Rgb::ZERO)
                        }
                    }
                }
            };
            let mut value = weighted * ls.radiance / (fe * ls.pdf);
            if let Some(tr) = through_sheets {
                value *= tr;
            }
            match &mut shadows {
                Shadows::Traced => l += value,
                // Through smooth `trans` surfaces: traced now, one ray at a time.
                Shadows::Deferred(..) if ls.is_delta && scene.has_straight_trans => {
                    l += value * scene.delta_shadow_transmittance(&shadow_ray);
                }
                Shadows::Deferred(deferred, beta) => {
                    deferred.rays.push(shadow_ray);
                    deferred.light.push((*beta * value, deferred.owner));
                }
            }
        }
    }
    l
}
