//! Unidirectional path tracing, step for step Mitsuba 3's `path` integrator: emitter sampling and
//! BSDF sampling combined by the power heuristic, Russian roulette from `rr_depth` on with
//! probability min(max(β)·η², 0.95), and `max_depth` counting path vertices (1: emitters seen
//! directly, 2: direct light, 3: one indirect bounce).

use super::{mis_weight, RayCounts};
use crate::scene::Scene;
use ircache_embree::Hit;
use ircache_math::{Ray, Rgb, Rng};

/// Parameters of the path tracer.
#[derive(Clone, Debug)]
pub struct PathIntegrator {
    /// Longest path (−1: unbounded).
    pub max_depth: i32,
    /// Depth from which Russian roulette runs.
    pub rr_depth: u32,
    /// Hide emitters seen directly by the camera.
    pub hide_emitters: bool,
}

impl PathIntegrator {
    /// Radiance along the camera ray `ray`, whose closest hit `first_hit` the caller traced.
    pub fn li(
        &self,
        scene: &Scene,
        ray: &Ray,
        first_hit: Option<&Hit>,
        rng: &mut Rng,
        rays: &mut RayCounts,
    ) -> Rgb {
        let max_depth = if self.max_depth < 0 {
            u32::MAX
        } else {
            self.max_depth as u32
        };
        if max_depth == 0 {
            return Rgb::ZERO;
        }
        let mut l = Rgb::ZERO;
        let mut beta = Rgb::ONE;
        let mut eta = 1.0f32;
        let mut ray = *ray;
        let mut depth = 0u32;
        // The previous vertex and its BSDF sample, for MIS on emitters hit by chance.
        let mut prev_p = ray.o;
        let mut prev_pdf = 1.0f32;
        let mut prev_delta = true;
        loop {
            let hit = if depth == 0 {
                first_hit.map(|h| scene.interaction(&ray, h))
            } else {
                scene.intersect(&ray)
            };
            // Emission found by the BSDF-sampled ray.
            let Some(it) = hit else {
                if scene.lights.has_environment() && !(depth == 0 && self.hide_emitters) {
                    let le = scene.lights.environment_radiance(ray.d);
                    let w = if prev_delta {
                        1.0
                    } else {
                        mis_weight(prev_pdf, scene.lights.pdf_environment(ray.d))
                    };
                    l += beta * le * w;
                }
                break;
            };
            let wo = -ray.d;
            let shape = &scene.shapes[it.shape as usize];
            if let Some(light) = shape.area_light {
                if !(depth == 0 && self.hide_emitters) {
                    let le = scene.lights.area_radiance(light, it.frame.n, wo);
                    if !le.is_black() {
                        let w = if prev_delta {
                            1.0
                        } else {
                            mis_weight(
                                prev_pdf,
                                scene
                                    .lights
                                    .pdf_area(light, it.prim, prev_p, it.p, it.frame.n),
                            )
                        };
                        l += beta * le * w;
                    }
                }
            }
            if depth + 1 >= max_depth {
                break;
            }
            let bsdf = scene.materials[shape.material].at(it.uv);
            let wo_local = it.frame.to_local(wo);

            // Emitter sampling.
            let p_ref = it.p;
            if bsdf.has_smooth() && !scene.lights.is_empty() {
                let u_sel = rng.next_f32();
                let u = rng.next_2d();
                if let Some(ls) = scene.lights.sample(p_ref, u_sel, u) {
                    let wi_local = it.frame.to_local(ls.wi);
                    let f = bsdf.eval(wo_local, wi_local);
                    if !f.is_black() && ls.pdf > 0.0 {
                        rays.shadow += 1;
                        if !scene
                            .accel
                            .occluded(&scene.shadow_ray(&it, ls.wi, ls.distance))
                        {
                            let w = if ls.is_delta {
                                1.0
                            } else {
                                mis_weight(ls.pdf, bsdf.pdf(wo_local, wi_local))
                            };
                            l += beta * f * ls.radiance * (w / ls.pdf);
                        }
                    }
                }
            } else {
                // Keep the random stream aligned whatever the material.
                rng.next_f32();
                rng.next_2d();
            }

            // BSDF sampling.
            let u_lobe = rng.next_f32();
            let u = rng.next_2d();
            let Some(bs) = bsdf.sample(wo_local, u_lobe, u) else {
                break;
            };
            let wi = it.frame.from_local(bs.wi);
            // Reject samples whose geometric and shading hemispheres disagree (light leaks).
            if (wi.dot(it.ng) > 0.0) != (bs.wi.z > 0.0) && !bs.delta {
                break;
            }
            beta *= bs.weight;
            eta *= bs.eta;
            prev_p = p_ref;
            prev_pdf = bs.pdf;
            prev_delta = bs.delta;
            // The next vertex would only add emission found by this ray: skip it when nothing
            // emissive can be hit (e.g. a sun-lit scene without sky).
            if depth + 2 >= max_depth && !scene.has_hittable_emitters {
                break;
            }
            ray = scene.spawn_ray(&it, wi);
            rays.bounce += 1;

            // Russian roulette.
            depth += 1;
            let beta_max = beta.max_channel();
            if beta_max <= 0.0 || !beta_max.is_finite() {
                break;
            }
            if depth >= self.rr_depth {
                let q = (beta_max * eta * eta).min(0.95);
                if rng.next_f32() >= q {
                    break;
                }
                beta /= q;
            }
        }
        l
    }
}
