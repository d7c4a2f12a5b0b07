//! Cache-miss detection on the splat buffer (Algorithm 4 step 4, NOTES-001 §C.3, §C.6) and the
//! `splat` integrator's pixel pass.
//!
//! Misses are found coarse to fine: the samples on grids of strides 16, 8, …, 1, each stride
//! split into phases two strides apart as in the cache's pre-pass, that no splatted record
//! covers (their smallest normalised error above the cache's coverage threshold there, the
//! rule of [`crate::irradiance_cache::store::RecordStore::covers_within`]) gather records in
//! parallel ([`crate::irradiance_cache::build::run_batch`], which drops a record an earlier one
//! of its batch covers); the new records are splatted at once, so finer strides see them. This
//! replaces the thesis's sequential scan, which biases placement towards the first pixel of each
//! uncovered run, and makes the result independent of the thread count. A budget caps the
//! records one call may add (the walkthrough's 100 per frame, §C.7).
//!
//! The pixel pass renders one layer of samples at a time (sample k of every pixel): G-buffer,
//! splat every level-0 record, fill the misses, then shade each sample with
//! [`IcIntegrator::li_splatted`], which takes the first vertex's indirect light from the splat
//! buffer. The cache is filled first by the same pre-pass as `ic` (records at pixel centres,
//! deeper levels, the cache file, the re-gathering of noisy records); the layers' misses are
//! the samples off those centres that it left uncovered.

use super::buffer::{splat, SplatBuffer};
use super::gbuffer::GBuffer;
use crate::integrators::ic::{IcIntegrator, Splatted};
use crate::integrators::RayCounts;
use crate::irradiance_cache::build::{run_batch, Sites};
use crate::irradiance_cache::gather::{mix, IrradianceCache, ShadingPoint};
use crate::irradiance_cache::CacheStats;
use crate::render::RenderSettings;
use crate::sampler::{dims, SamplerSettings};
use crate::scene::Scene;
use ircache_math::Rgb;
use rayon::prelude::*;
use std::time::Instant;

/// What the splatting pixel pass did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SplatStats {
    /// Layers rendered (samples per pixel).
    pub layers: u32,
    /// Record splats made (each record once per layer, and each new record once).
    pub splats: u64,
    /// Records gathered at misses.
    pub miss_records: u64,
    /// Seconds building G-buffers.
    pub gbuffer_seconds: f64,
    /// Seconds splatting.
    pub splat_seconds: f64,
    /// Seconds finding and filling misses (gathers included).
    pub miss_seconds: f64,
    /// Seconds shading samples.
    pub shade_seconds: f64,
    /// What the gathers at misses did.
    pub cache: CacheStats,
}

/// Strides of the miss search, coarse to fine.
const STRIDES: [usize; 5] = [16, 8, 4, 2, 1];

/// Finds the samples of `g` that no record in `buffer` covers and gathers records there, coarse
/// to fine, splatting each batch's new records into `buffer` before the next; at most `budget`
/// records are gathered (in the search's order). Returns the records added to level 0.
#[allow(clippy::too_many_arguments)]
pub fn fill_misses(
    scene: &Scene,
    cache: &mut IrradianceCache,
    g: &GBuffer,
    buffer: &mut SplatBuffer,
    seed: u64,
    budget: usize,
    filter_reach: f32,
    stats: &mut CacheStats,
) -> usize {
    if cache.levels.is_empty() {
        return 0;
    }
    let w = g.width;
    let key = mix(0x7370_6c61_7473, u64::from(g.layer));
    let before = cache.levels[0].len();
    let mut asked = 0usize;
    for (s, &stride) in STRIDES.iter().enumerate() {
        // Phases: (x/stride mod 2, y/stride mod 2); (0, 0) belongs to the coarser grid.
        let phases: &[(usize, usize)] = if s == 0 {
            &[(0, 0)]
        } else {
            &[(1, 1), (1, 0), (0, 1)]
        };
        for &(px, py) in phases {
            if asked >= budget {
                return cache.levels[0].len() - before;
            }
            let mut points: Vec<(u64, u32, ShadingPoint)> = (0..g.height)
                .step_by(stride)
                .flat_map(|y| (0..w).step_by(stride).map(move |x| (x, y)))
                .filter(|&(x, y)| s == 0 || ((x / stride) % 2 == px && (y / stride) % 2 == py))
                .filter_map(|(x, y)| {
                    let i = y * w + x;
                    let sp = g.samples[i].point?;
                    (buffer.pixels[i].min_error > cache.coverage_threshold(&sp))
                        .then(|| (mix(key, i as u64), 0, sp))
                })
                .collect();
            points.truncate(budget - asked);
            if points.is_empty() {
                continue;
            }
            asked += points.len();
            let first_new = cache.levels[0].len();
            run_batch(
                scene,
                cache,
                seed,
                &points,
                stats,
                &mut Sites::default(),
                &mut (),
            );
            let end = cache.levels[0].len();
            splat(
                buffer,
                g,
                cache,
                first_new..end,
                &scene.camera,
                filter_reach,
            );
        }
    }
    cache.levels[0].len() - before
}

/// The `splat` integrator's pixel pass (run inside the caller's thread pool): for each layer
/// k < spp, `sample(k, values)` receives every pixel's value (row-major; `None` outside the
/// rendered rows). Returns the cache with the records the misses added.
pub fn render_layers(
    scene: &Scene,
    ic: &IcIntegrator,
    settings: &RenderSettings,
    samplers: &SamplerSettings,
    rays: &mut RayCounts,
    sample: &mut dyn FnMut(u32, Vec<Option<Rgb>>),
) -> (IrradianceCache, SplatStats) {
    let mut cache = match &ic.cache {
        Some(c) => (**c).clone(),
        None => IrradianceCache::new(scene, &ic.params),
    };
    let mut stats = SplatStats::default();
    let reach = settings.filter.radius();
    let rows = settings.rows();
    let w = settings.width;
    let (mut g, mut buffer): (Option<GBuffer>, Option<SplatBuffer>) = (None, None);
    for layer in 0..samplers.spp {
        let t = Instant::now();
        let g = match &mut g {
            Some(g) => {
                g.rebuild(scene, &cache, settings, samplers, layer);
                g
            }
            None => g.insert(GBuffer::build(scene, &cache, settings, samplers, layer)),
        };
        rays.camera += (rows.len() * w) as u64;
        stats.gbuffer_seconds += t.elapsed().as_secs_f64();

        let t = Instant::now();
        let buffer = match &mut buffer {
            Some(b) => {
                b.clear();
                b
            }
            None => buffer.insert(SplatBuffer::new(g)),
        };
        let existing = cache.levels.first().map_or(0, |s| s.len());
        splat(buffer, g, &cache, 0..existing, &scene.camera, reach);
        stats.splats += existing as u64;
        stats.splat_seconds += t.elapsed().as_secs_f64();

        let t = Instant::now();
        let added = fill_misses(
            scene,
            &mut cache,
            g,
            buffer,
            settings.seed,
            usize::MAX,
            reach,
            &mut stats.cache,
        );
        stats.miss_records += added as u64;
        stats.splats += added as u64;
        stats.miss_seconds += t.elapsed().as_secs_f64();

        let t = Instant::now();
        let cache_ref = &cache;
        let shaded: Vec<(Vec<Option<Rgb>>, RayCounts)> = g
            .samples
            .par_chunks(w)
            .zip(buffer.pixels.par_chunks(w))
            .enumerate()
            .map(|(y, (samples, splats))| {
                let mut r = RayCounts::default();
                if !rows.contains(&y) {
                    return (vec![None; w], r);
                }
                let values = samples
                    .iter()
                    .zip(splats)
                    .enumerate()
                    .map(|(x, (s, px))| {
                        let mut sampler = samplers.pixel(x as u32, y as u32);
                        sampler.set_sample(layer, dims::vertex(0, 0));
                        let splatted = s.point.map(|_| Splatted {
                            irradiance: px.irradiance(),
                            glossy: px.glossy(),
                            trace_misses: false,
                        });
                        Some(ic.li_splatted(
                            scene,
                            cache_ref,
                            &s.ray,
                            s.hit.as_ref(),
                            splatted,
                            &mut sampler,
                            &mut r,
                        ))
                    })
                    .collect();
                (values, r)
            })
            .collect();
        let mut values = Vec::with_capacity(w * settings.height);
        for (row, r) in shaded {
            values.extend(row);
            rays.add(&r);
        }
        stats.shade_seconds += t.elapsed().as_secs_f64();
        stats.layers += 1;
        sample(layer, values);
    }
    (cache, stats)
}
