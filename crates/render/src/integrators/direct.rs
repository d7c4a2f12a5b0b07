//! Direct illumination (Mitsuba 3's `direct`): at the first surface, `emitter_samples` light
//! samples and `bsdf_samples` BSDF samples combined with the power heuristic, weighted by their
//! sample counts; emitters seen directly are added as they are. Where the light samples suffice
//! (a Lambertian surface under lights sampled in proportion to what it receives,
//! [`light_samples_suffice`]) they stand alone, as in `path`.

use super::light_sampling::{
    light_samples_suffice, receiver, sample_lights, BsdfStrategy, EnvironmentServed, Selection,
    Shadows,
};
use super::{mis_weight, RayCounts};
use crate::bsdf::Bsdf;
use crate::sampler::{dims, Sampler};
use crate::scene::{Interaction, Scene};
use ircache_embree::Hit;
use ircache_math::{Ray, Rgb, Vec3};

/// Parameters of the direct-illumination integrator.
#[derive(Clone, Debug)]
pub struct DirectIntegrator {
    /// Light samples per shading point.
    pub emitter_samples: u32,
    /// BSDF samples per shading point.
    pub bsdf_samples: u32,
    /// Hide emitters seen directly.
    pub hide_emitters: bool,
}

impl DirectIntegrator {
    /// Radiance along the camera ray `ray`, whose closest hit `first_hit` the caller traced.
    pub fn li(
        &self,
        scene: &Scene,
        ray: &Ray,
        first_hit: Option<&Hit>,
        sampler: &mut dyn Sampler,
        rays: &mut RayCounts,
    ) -> Rgb {
        let Some(it) = first_hit.map(|h| scene.interaction(ray, h)) else {
            return if self.hide_emitters {
                Rgb::ZERO
            } else {
                scene.lights.environment_radiance(ray.d)
            };
        };
        let wo = -ray.d;
        let shape = &scene.shapes[it.shape as usize];
        let mut l = Rgb::ZERO;
        if let (Some(light), false) = (shape.area_light, self.hide_emitters) {
            l += scene
                .lights
                .area_radiance(light, it.p, it.frame.n, it.uv, wo, it.t);
        }
        let bsdf = it.bsdf(&scene.materials[shape.material], ray.d);
        let wo_local = it.frame.to_local(wo);
        l + estimate_direct(
            scene,
            &it,
            &bsdf,
            wo_local,
            self.emitter_samples,
            self.bsdf_samples,
            sampler,
            rays,
        )
    }
}

/// Direct light reflected at `it` towards `wo_local`: `ne` light samples
/// ([`sample_lights`]) and `nb` BSDF samples combined by the power heuristic weighted by the
/// sample counts (Veach 1997 §9.2); emission found by BSDF samples through delta lobes counts
/// fully. No BSDF samples where the light samples suffice.
#[allow(clippy::too_many_arguments)]
pub fn estimate_direct(
    scene: &Scene,
    it: &Interaction,
    bsdf: &Bsdf,
    wo_local: Vec3,
    ne: u32,
    nb: u32,
    sampler: &mut dyn Sampler,
    rays: &mut RayCounts,
) -> Rgb {
    let nb = if light_samples_suffice(scene, bsdf, true) {
        0
    } else {
        nb
    };
    let mut l = sample_lights(
        scene,
        it,
        bsdf,
        wo_local,
        (ne, Selection::Chosen),
        (BsdfStrategy::All, nb),
        EnvironmentServed::default(),
        0,
        sampler,
        rays,
        Shadows::Traced,
    );
    let (fe, fb) = (ne as f32, nb as f32);
    let at = receiver(it, bsdf, wo_local);
    for i in 0..nb {
        sampler.set_dimension(if i == 0 {
            dims::vertex(0, dims::BSDF)
        } else {
            dims::extra(0, dims::EXTRA_BSDF + i)
        });
        let u_lobe = sampler.next_1d();
        let u = sampler.next_2d();
        let Some(mut bs) = bsdf.sample(wo_local, u_lobe, u) else {
            continue;
        };
        let wi = it.frame.from_local(bs.wi);
        bs.weight *= scene.perturbed_shadowing(it, wi);
        let next = scene.spawn_ray(it, wi);
        rays.bounce += 1;
        // Through window panes, as the light samples see (`Scene::shadow_transmittance`).
        let (found, through) = scene.intersect_opaque(&next);
        if through.is_black() {
            continue;
        }
        match found {
            None => {
                if scene.lights.has_environment() {
                    let le = scene.lights.environment_radiance(wi) * through;
                    let w = if bs.delta {
                        1.0 / fb
                    } else {
                        mis_weight(fb * bs.pdf, fe * scene.lights.pdf_environment(at, wi)) / fb
                    };
                    l += bs.weight * le * w;
                }
            }
            Some(hit_it) => {
                if let Some(light) = scene.shapes[hit_it.shape as usize].area_light {
                    let le = scene.lights.area_radiance(
                        light,
                        hit_it.p,
                        hit_it.frame.n,
                        hit_it.uv,
                        -wi,
                        hit_it.t,
                    ) * through;
                    if le.is_black() {
                        continue;
                    }
                    let w = if bs.delta {
                        1.0 / fb
                    } else {
                        let pdf_l = scene.lights.pdf_area(
                            light,
                            hit_it.prim,
                            at.p,
                            hit_it.p,
                            hit_it.frame.n,
                        );
                        mis_weight(fb * bs.pdf, fe * pdf_l) / fb
                    };
                    l += bs.weight * le * w;
                }
            }
        }
    }
    l
}
