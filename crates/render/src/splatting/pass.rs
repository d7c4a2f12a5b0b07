//! Cache-miss detection on the splat buffer (Algorithm 4 step 4, NOTES-001 §C.3, §C.6) and the
//! `splat` integrator's pixel pass.
//!
//! Misses are found coarse to fine: the samples on grids of strides 16, 8, …, 1, each stride
//! split into the cache pre-pass's phases ([`phases`]), that no splatted record
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
//! [`IcIntegrator::li_parts`], which takes the first vertex's indirect light from the splat
//! buffer. The cache is filled first by the same pre-pass as `ic` (records at pixel centres,
//! deeper levels, the cache file, the re-gathering of noisy records); the layers' misses are
//! the samples off those centres that it left uncovered.

use super::buffer::{CpuSplatter, SplatBuffer, Splatter};
use super::gbuffer::GBuffer;
use crate::integrators::ic::{IcIntegrator, Parts, Splatted};
use crate::integrators::RayCounts;
use crate::irradiance_cache::build::{phase_pixels, phases, run_batch, Sites};
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
    splatter: &dyn Splatter,
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
        for phase in phases(stride, s == 0) {
            if asked >= budget {
                return cache.levels[0].len() - before;
            }
            let mut points: Vec<(u64, u32, ShadingPoint)> =
                phase_pixels(w, g.height, stride, phase)
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
                None,
            );
            let end = cache.levels[0].len();
            splatter.splat(
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

/// One layer of samples and its splat buffer, reused from layer to layer.
#[derive(Debug, Default)]
pub struct Layer {
    g: Option<GBuffer>,
    buffer: Option<SplatBuffer>,
    /// Where records are splatted (`None`: [`CpuSplatter`]).
    pub splatter: Option<std::sync::Arc<dyn Splatter>>,
}

/// How the time of [`Layer::prepare`] went.
#[derive(Clone, Copy, Debug, Default)]
pub struct LayerTimes {
    /// Seconds building the G-buffer.
    pub gbuffer: f64,
    /// Seconds splatting the records there were.
    pub splat: f64,
    /// Seconds finding and filling misses.
    pub misses: f64,
    /// Records splatted before the misses.
    pub splatted: usize,
    /// Records the misses added.
    pub added: usize,
}

impl Layer {
    /// A layer whose records are splatted by `splatter` (`None`: on the CPU).
    #[must_use]
    pub fn with_splatter(splatter: Option<std::sync::Arc<dyn Splatter>>) -> Layer {
        Layer {
            splatter,
            ..Layer::default()
        }
    }

    /// The G-buffer (after [`Layer::prepare`]).
    #[must_use]
    pub fn gbuffer(&self) -> Option<&GBuffer> {
        self.g.as_ref()
    }

    /// The splat buffer (after [`Layer::prepare`]).
    #[must_use]
    pub fn splats(&self) -> Option<&SplatBuffer> {
        self.buffer.as_ref()
    }

    /// Layer `layer`: its G-buffer, every level-0 record splatted, then at most `budget` records
    /// added at its misses (and splatted).
    #[allow(clippy::too_many_arguments)]
    pub fn prepare(
        &mut self,
        scene: &Scene,
        cache: &mut IrradianceCache,
        settings: &RenderSettings,
        samplers: &SamplerSettings,
        layer: u32,
        budget: usize,
        stats: &mut CacheStats,
    ) -> LayerTimes {
        let t = Instant::now();
        let g = match &mut self.g {
            Some(g) => {
                g.rebuild(scene, cache, settings, samplers, layer);
                g
            }
            None => self
                .g
                .insert(GBuffer::build(scene, cache, settings, samplers, layer)),
        };
        let gbuffer = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let buffer = match &mut self.buffer {
            Some(b) => {
                b.clear();
                b
            }
            None => self.buffer.insert(SplatBuffer::new(g)),
        };
        let reach = settings.filter.radius();
        let splatted = cache.levels.first().map_or(0, |s| s.len());
        let splatter: &dyn Splatter = self.splatter.as_deref().unwrap_or(&CpuSplatter);
        splatter.splat(buffer, g, cache, 0..splatted, &scene.camera, reach);
        let splat_seconds = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let added = fill_misses(
            scene,
            cache,
            g,
            buffer,
            splatter,
            settings.seed,
            budget,
            reach,
            stats,
        );
        LayerTimes {
            gbuffer,
            splat: splat_seconds,
            misses: t.elapsed().as_secs_f64(),
            splatted,
            added,
        }
    }

    /// Shades the samples of the rendered rows with `ic`, their first vertices from the splat
    /// buffer (misses traced when `trace_misses`, else looked up as `ic` does); row-major, `None`
    /// outside the rows. Call after [`Layer::prepare`].
    #[allow(clippy::too_many_arguments)]
    #[must_use]
    pub fn shade(
        &self,
        scene: &Scene,
        ic: &IcIntegrator,
        cache: &IrradianceCache,
        settings: &RenderSettings,
        samplers: &SamplerSettings,
        trace_misses: bool,
        rays: &mut RayCounts,
    ) -> Vec<Option<Rgb>> {
        let (Some(g), Some(buffer)) = (&self.g, &self.buffer) else {
            return Vec::new();
        };
        let (w, rows) = (settings.width, settings.rows());
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
                        sampler.set_sample(g.layer, dims::vertex(0, 0));
                        let splatted = s.point.map(|_| Splatted {
                            irradiance: px.irradiance(),
                            glossy: px.glossy(),
                            trace_misses,
                        });
                        let (l, _) = ic.li_parts(
                            scene,
                            cache,
                            &s.ray,
                            s.hit.as_ref(),
                            splatted,
                            &mut sampler,
                            &mut r,
                            None,
                            Parts::All,
                        );
                        Some(l)
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
        rays.camera += (rows.len() * w) as u64;
        values
    }
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
    let mut pass = Layer::with_splatter(ic.splatter.clone());
    for layer in 0..samplers.spp {
        let times = pass.prepare(
            scene,
            &mut cache,
            settings,
            samplers,
            layer,
            usize::MAX,
            &mut stats.cache,
        );
        stats.gbuffer_seconds += times.gbuffer;
        stats.splat_seconds += times.splat;
        stats.miss_seconds += times.misses;
        stats.splats += (times.splatted + times.added) as u64;
        stats.miss_records += times.added as u64;
        let t = Instant::now();
        let values = pass.shade(scene, ic, &cache, settings, samplers, false, rays);
        stats.shade_seconds += t.elapsed().as_secs_f64();
        stats.layers += 1;
        sample(layer, values);
    }
    (cache, stats)
}
