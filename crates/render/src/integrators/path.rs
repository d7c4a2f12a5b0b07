//! Unidirectional path tracing, step for step Mitsuba 3's `path` integrator: emitter sampling and
//! BSDF sampling combined by the power heuristic, Russian roulette from `rr_depth` on with
//! probability min(max(β)·η², 0.95), and `max_depth` counting path vertices (1: emitters seen
//! directly, 2: direct light, 3: one indirect bounce). One difference: at a path's last vertex,
//! where the BSDF sample would only look for emitters, a Lambertian surface under lights that are
//! sampled in proportion to what it receives takes its light samples alone and traces no BSDF
//! ray ([`super::light_sampling::light_samples_suffice`]). The loop itself is
//! [`super::path_continuation::trace_path`] with no cache.

use super::light_sampling::DeferredShadows;
use super::path_continuation::{
    trace_path_deferring, FirstVertex, PathSettings, PathStart, Traced,
};
use super::RayCounts;
use crate::sampler::Sampler;
use crate::scene::Scene;
use ircache_embree::Hit;
use ircache_math::{Ray, Rgb};

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
    /// Radiance along the camera ray `ray`, whose closest hit `first_hit` the caller traced;
    /// with `deferred`, the first vertex's light samples wait there for their shadow rays.
    pub fn li<S: Sampler + ?Sized>(
        &self,
        scene: &Scene,
        ray: &Ray,
        first_hit: Option<&Hit>,
        sampler: &mut S,
        rays: &mut RayCounts,
        deferred: Option<&mut DeferredShadows>,
    ) -> Rgb {
        let settings = PathSettings {
            max_depth: u32::try_from(self.max_depth).unwrap_or(u32::MAX),
            rr_depth: self.rr_depth,
            first_light_samples: 1,
        };
        let start = PathStart::camera(*ray, self.hide_emitters);
        trace_path_deferring(
            scene,
            start,
            FirstVertex::Hit(first_hit),
            &mut Traced,
            &settings,
            sampler,
            rays,
            deferred,
        )
    }
}
