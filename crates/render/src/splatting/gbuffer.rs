//! The G-buffer (NOTES-001 §C.1): for one layer of pixel samples (sample `k` of every pixel),
//! the camera ray, its first hit and, where the cache serves that surface, its shading point
//! exactly as the path loop makes it for the first vertex. The rays are those of the `ic`
//! pixel pass (same sampler dimensions), so both passes shade the same vertices.

use crate::irradiance_cache::build::is_record_site;
use crate::irradiance_cache::gather::{IrradianceCache, ShadingPoint};
use crate::render::{camera_ray, RenderSettings};
use crate::sampler::SamplerSettings;
use crate::scene::Scene;
use ircache_embree::Hit;
use ircache_math::{Ray, Vec3};
use rayon::prelude::*;
use std::sync::Arc;

/// One pixel's sample of the layer.
#[derive(Clone, Copy, Debug)]
pub struct GSample {
    /// The camera ray.
    pub ray: Ray,
    /// Its first hit.
    pub hit: Option<Hit>,
    /// The first vertex, where records serve it (a Lambertian part or a radiance-cached glossy
    /// lobe on a surface not excluded from the cache): a record site of level 0.
    pub point: Option<ShadingPoint>,
}

/// One layer of samples, row-major, `width × height` (rows outside the render's band hold no
/// ray and no point).
#[derive(Clone, Debug)]
pub struct GBuffer {
    /// Image width.
    pub width: usize,
    /// Image height.
    pub height: usize,
    /// Sample index of this layer in every pixel.
    pub layer: u32,
    /// The samples. Filled by [`GBuffer::build`] and [`GBuffer::rebuild`] only: each filling
    /// has its own [`GBuffer::filling`].
    pub samples: Vec<GSample>,
    /// A token of this filling, renewed by each: a splatter that keeps the samples elsewhere
    /// (the GPU's) holds a weak reference to it and knows its copy current while that upgrades
    /// to this very token (the allocation a weak reference keeps alive is never reused).
    filling: Arc<()>,
}

impl GBuffer {
    /// Layer `layer` of the render `settings` with pixel samplers `samplers`; `cache` decides
    /// which vertices are record sites.
    #[must_use]
    pub fn build(
        scene: &Scene,
        cache: &IrradianceCache,
        settings: &RenderSettings,
        samplers: &SamplerSettings,
        layer: u32,
    ) -> GBuffer {
        let empty = GSample {
            ray: Ray::new(Vec3::ZERO, Vec3::Z),
            hit: None,
            point: None,
        };
        let mut g = GBuffer {
            width: settings.width,
            height: settings.height,
            layer,
            samples: vec![empty; settings.width * settings.height],
            filling: Arc::new(()),
        };
        g.rebuild(scene, cache, settings, samplers, layer);
        g
    }

    /// The token of this filling of the samples (see the field).
    #[must_use]
    pub fn filling(&self) -> &Arc<()> {
        &self.filling
    }

    /// Makes this buffer (of the same size) hold layer `layer` instead, reusing its memory.
    pub fn rebuild(
        &mut self,
        scene: &Scene,
        cache: &IrradianceCache,
        settings: &RenderSettings,
        samplers: &SamplerSettings,
        layer: u32,
    ) {
        let (w, h) = (settings.width, settings.height);
        assert_eq!(self.samples.len(), w * h, "G-buffer of another size");
        let rows = settings.rows();
        self.layer = layer;
        self.filling = Arc::new(());
        self.samples
            .par_chunks_mut(w)
            .enumerate()
            .filter(|(y, _)| rows.contains(y))
            .for_each(|(y, row)| {
                for (x16, chunk) in row.chunks_mut(16).enumerate() {
                    let mut camera = [Ray::new(Vec3::ZERO, Vec3::Z); 16];
                    let mut hits = [None; 16];
                    let n = chunk.len();
                    for (i, ray) in camera[..n].iter_mut().enumerate() {
                        let x = x16 * 16 + i;
                        let mut sampler = samplers.pixel(x as u32, y as u32);
                        // Splatting takes the filters sampled exactly (weight 1).
                        *ray = camera_ray(scene, settings, &mut sampler, x, y, layer).0;
                    }
                    scene.accel.intersect16(&camera[..n], &mut hits[..n]);
                    for ((s, ray), hit) in chunk.iter_mut().zip(&camera).zip(&hits) {
                        *s = GSample {
                            ray: *ray,
                            hit: *hit,
                            point: hit.as_ref().and_then(|h| record_site(scene, cache, ray, h)),
                        };
                    }
                }
            });
    }
}

/// The first vertex of `ray` at `hit` as the path loop makes it, when records serve it.
fn record_site(
    scene: &Scene,
    cache: &IrradianceCache,
    ray: &Ray,
    hit: &Hit,
) -> Option<ShadingPoint> {
    if cache.levels.is_empty() {
        return None;
    }
    let it = scene.interaction(ray, hit);
    if cache.is_excluded(it.shape) {
        return None;
    }
    let bsdf = it.bsdf(
        &scene.materials[scene.shapes[it.shape as usize].material],
        ray.d,
    );
    let wo = -ray.d;
    // As `trace_path` makes the first vertex of a camera path.
    let mut sp = ShadingPoint::facing(it, wo);
    sp.travelled = it.t;
    let glossy = cache
        .radiance
        .as_deref()
        .is_some_and(|r| r.brdf_at(&sp).is_some());
    is_record_site(&bsdf, it.frame.to_local(wo), glossy).then_some(sp)
}
