//! The tile loop: all cores render 16×16-pixel tiles; every pixel draws its sample coordinates
//! from the sampler as a function of (seed, pixel, sample, dimension) (see [`crate::sampler`]),
//! so the image is the same bit for bit for a given seed whatever the thread count or the order
//! in which tiles finish.

use crate::film::Filter;
use crate::integrators::{Integrator, RayCounts};
use crate::irradiance_cache::{CacheStats, IrradianceCache};
use crate::sampler::{dims, Sampler, SamplerKind, SamplerSettings};
use crate::scene::{RenderError, Scene};
use ircache_image::Image;
use ircache_math::{Ray, Rgb, Vec2, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// Edge length of a tile in pixels.
pub const TILE: usize = 16;

/// What to render.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    /// Image width.
    pub width: usize,
    /// Image height.
    pub height: usize,
    /// Samples per pixel as requested (the sampler may round it up:
    /// [`SamplerKind::sample_count`]).
    pub spp: u32,
    /// How pixel samples are placed.
    pub sampling: Sampling,
    /// Seed of all random streams.
    pub seed: u64,
    /// Worker threads (0: all cores).
    pub threads: usize,
    /// Pixel filter.
    pub filter: Filter,
    /// Render only band `i` of `n` equal bands of rows (`--tile i/n`); the other pixels stay
    /// black, so the bands of `n` processes sum to the whole image.
    pub band: Option<(usize, usize)>,
}

/// How a pixel's samples are placed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampling {
    /// The sampler.
    pub sampler: SamplerKind,
    /// Jitter within strata (Mitsuba's `jitter`).
    pub jitter: bool,
    /// Adaptive pixel sampling (off: every pixel takes `spp` samples).
    pub adaptive: Option<Adaptive>,
}

/// Adaptive pixel sampling: a pixel takes `spp` samples, then doubles them while its estimated
/// relative error exceeds `target`, up to `max_spp`. The samples are the prefixes of one
/// progressive sequence (the `sobol` sampler at `max_spp`: its prefixes stay stratified), so
/// the added samples extend the stratification instead of starting another (independent
/// extra passes of a multi-jittered set lose to one set of their total size: stratification
/// is worth more than adaptivity there). The error is estimated from the variance of the
/// samples' luminance, relative as the error measure is: √(var/n) / √(mean² + 0.01); for
/// stratified samples this overestimates the error where the integrand is smooth, so it ranks
/// pixels by how hard they are (edges, penumbrae, glossy highlights) rather than promising the
/// target. (Judging by the difference of the two halves' means instead, an estimate that knows
/// stratification, is too noisy with one degree of freedom: measured worse on the Cornell box.)
/// Deterministic: each pixel's decision depends on its own samples alone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    /// Target relative error of a pixel.
    pub target: f32,
    /// Most samples a pixel takes.
    pub max_spp: u32,
}

impl Sampling {
    /// The sampler a scene's sensor names.
    ///
    /// # Errors
    /// An unknown sampler name.
    pub fn from_desc(sensor: &ircache_scene::SensorDesc) -> Result<Sampling, String> {
        let sampler = SamplerKind::from_name(&sensor.sampler).ok_or_else(|| {
            let names: Vec<&str> = SamplerKind::ALL.iter().map(|(_, n)| *n).collect();
            format!(
                "unknown sampler \"{}\": expected one of {}",
                sensor.sampler,
                names.join(", ")
            )
        })?;
        Ok(Sampling {
            sampler,
            jitter: sensor.jitter,
            adaptive: None,
        })
    }
}

impl Default for Sampling {
    /// Correlated multi-jittered samples: the lowest per-pixel error of the samplers at equal
    /// time on the shared scenes (BENCHMARKS.md; `sobol` is lower after a blur).
    fn default() -> Self {
        Sampling {
            sampler: SamplerKind::MultiJitter,
            jitter: true,
            adaptive: None,
        }
    }
}

impl RenderSettings {
    /// The sampler of this render's pixels (under adaptive sampling, the progressive sequence
    /// whose prefixes the pixels take).
    #[must_use]
    pub fn sampler(&self) -> SamplerSettings {
        let (kind, spp) = match self.sampling.adaptive {
            None => (self.sampling.sampler, self.spp),
            Some(a) => (SamplerKind::Sobol, a.max_spp.max(self.spp)),
        };
        let mut s =
            SamplerSettings::new(kind, spp, self.seed, self.width as u32, self.height as u32);
        s.jitter = self.sampling.jitter;
        s
    }

    /// Samples every pixel takes: all the sampler's without adaptive sampling.
    #[must_use]
    pub fn first_samples(&self) -> u32 {
        let s = self.sampler();
        match self.sampling.adaptive {
            None => s.spp,
            Some(_) => self.spp.max(1).min(s.spp),
        }
    }

    /// The rows this render covers.
    #[must_use]
    pub fn rows(&self) -> std::ops::Range<usize> {
        match self.band {
            Some((i, n)) if n > 0 => (i * self.height / n)..((i + 1) * self.height / n),
            _ => 0..self.height,
        }
    }
}

/// A finished render.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// The image.
    pub image: Image,
    /// Rays traced.
    pub rays: RayCounts,
    /// Samples dropped because the integrator returned a non-finite or negative value.
    pub invalid_samples: u64,
    /// Pixel samples taken (all pixels).
    pub samples: u64,
    /// Wall-clock seconds of the render loop (cache pre-pass included).
    pub seconds: f64,
    /// What the irradiance cache pre-pass did (`ic` integrator only).
    pub cache: Option<CacheReport>,
}

/// The irradiance cache after a render.
#[derive(Clone, Debug)]
pub struct CacheReport {
    /// The filled cache.
    pub cache: Arc<IrradianceCache>,
    /// Pre-pass figures.
    pub stats: CacheStats,
    /// Pixel samples that no record reached (each gathered a record of its own).
    pub uncached_samples: u64,
    /// Seconds of the pixel pass (interpolation, direct light).
    pub pixel_seconds: f64,
}

/// Renders the image. `progress` is called (from worker threads) with the number of pixels done
/// so far, after each tile.
pub fn render(
    scene: &Scene,
    integrator: &Integrator,
    settings: &RenderSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RenderOutput, RenderError> {
    let (w, h) = (settings.width, settings.height);
    let tiles_x = w.div_ceil(TILE);
    let tiles_y = h.div_ceil(TILE);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(settings.threads)
        .build()?;
    let done = AtomicU64::new(0);
    let start = Instant::now();
    // What an integrator does once before the pixels (the cache's pre-pass).
    let (prepared, cache_stats) = integrator.prepare(scene, settings, &pool)?;
    let integrator = &prepared;
    let sampler = settings.sampler();
    let pixel_start = Instant::now();
    let results: Vec<(Vec<Rgb>, RayCounts, u64, u64)> = pool.install(|| {
        (0..tiles_x * tiles_y)
            .into_par_iter()
            .with_max_len(1)
            .map(|tile| {
                let (tx, ty) = (tile % tiles_x, tile / tiles_x);
                let (x0, y0) = (tx * TILE, ty * TILE);
                let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
                let mut pixels = Vec::with_capacity((x1 - x0) * (y1 - y0));
                let mut rays = RayCounts::default();
                let mut invalid = 0u64;
                let mut samples = 0u64;
                let rows = settings.rows();
                for y in y0..y1 {
                    for x in x0..x1 {
                        if !rows.contains(&y) {
                            pixels.push(Rgb::ZERO);
                            continue;
                        }
                        let p =
                            render_pixel(scene, integrator, settings, &sampler, x, y, &mut rays);
                        invalid += p.invalid;
                        samples += u64::from(p.samples);
                        pixels.push(p.value);
                    }
                }
                let n =
                    done.fetch_add(pixels.len() as u64, Ordering::Relaxed) + pixels.len() as u64;
                progress(n);
                (pixels, rays, invalid, samples)
            })
            .collect()
    });
    let mut image = Image::new(w, h);
    let mut rays = RayCounts::default();
    let mut invalid_samples = 0;
    let mut samples = 0;
    for (tile, (pixels, r, bad, n)) in results.into_iter().enumerate() {
        let (tx, ty) = (tile % tiles_x, tile / tiles_x);
        let (x0, y0) = (tx * TILE, ty * TILE);
        let x1 = (x0 + TILE).min(w);
        for (i, c) in pixels.into_iter().enumerate() {
            let (x, y) = (x0 + i % (x1 - x0), y0 + i / (x1 - x0));
            image.set(x, y, c);
        }
        rays.add(&r);
        invalid_samples += bad;
        samples += n;
    }
    let pixel_seconds = pixel_start.elapsed().as_secs_f64();
    let cache = match (integrator.cache(), cache_stats) {
        (Some((cache, uncached_samples)), Some(stats)) => {
            rays.gather += stats.gather_rays;
            rays.shadow += stats.shadow_rays;
            Some(CacheReport {
                cache,
                stats,
                uncached_samples,
                pixel_seconds,
            })
        }
        _ => None,
    };
    Ok(RenderOutput {
        image,
        rays,
        invalid_samples,
        samples,
        seconds: start.elapsed().as_secs_f64(),
        cache,
    })
}

/// A rendered pixel.
struct Pixel {
    value: Rgb,
    samples: u32,
    invalid: u64,
}

/// One pixel: the mean of the sampler's filter-importance-sampled estimates, doubled while
/// needed under adaptive sampling (see [`Adaptive`]). Samples that the integrator returns as
/// non-finite or negative count as zero and are counted (Mitsuba drops them too).
fn render_pixel(
    scene: &Scene,
    integrator: &Integrator,
    settings: &RenderSettings,
    samplers: &SamplerSettings,
    x: usize,
    y: usize,
    rays: &mut RayCounts,
) -> Pixel {
    let mut sum = Rgb::ZERO;
    let mut invalid = 0;
    // Sums of the samples' luminance and its square: their variance estimates the error.
    let mut lum = (0.0f64, 0.0f64);
    let mut sampler = samplers.pixel(x as u32, y as u32);
    let mut samples = 0u32;
    let mut next = settings.first_samples();
    loop {
        let (s, bad) = pixel_pass(
            scene,
            integrator,
            settings,
            &mut sampler,
            samples..next,
            x,
            y,
            &mut lum,
            rays,
        );
        sum += s;
        invalid += bad;
        samples = next;
        let Some(a) = settings.sampling.adaptive else {
            break;
        };
        if samples >= samplers.spp {
            break;
        }
        let n = f64::from(samples);
        let mean = lum.0 / n;
        let var = ((lum.1 - lum.0 * mean) / (n - 1.0).max(1.0)).max(0.0);
        if var / n / (mean * mean + 0.01) <= f64::from(a.target) * f64::from(a.target) {
            break;
        }
        next = (samples * 2).min(samplers.spp);
    }
    Pixel {
        value: sum / samples.max(1) as f32,
        samples,
        invalid,
    }
}

/// The sum of the values of samples `range` at pixel (x, y), and the samples dropped as
/// invalid; adds the samples' luminance and its square to `lum`.
#[allow(clippy::too_many_arguments)]
fn pixel_pass(
    scene: &Scene,
    integrator: &Integrator,
    settings: &RenderSettings,
    sampler: &mut crate::sampler::PixelSampler<'_>,
    range: std::ops::Range<u32>,
    x: usize,
    y: usize,
    lum: &mut (f64, f64),
    rays: &mut RayCounts,
) -> (Rgb, u64) {
    let end = range.end;
    let mut sum = Rgb::ZERO;
    let mut invalid = 0;
    let inv_size = Vec2::new(1.0 / settings.width as f32, 1.0 / settings.height as f32);
    // Camera rays of one pixel are nearly parallel: trace them in 16-wide packets.
    let mut camera = [Ray::new(Vec3::ZERO, Vec3::Z); 16];
    let mut hits = [None; 16];
    let mut done = range.start;
    while done < end {
        let n = (end - done).min(16);
        for (k, ray) in (done..done + n).zip(&mut camera) {
            sampler.set_sample(k, dims::FILM);
            let offset = settings.filter.sample(sampler.next_2d());
            let film = (Vec2::new(x as f32 + 0.5, y as f32 + 0.5) + offset) * inv_size;
            *ray = scene.camera.generate_ray(film);
        }
        let n = n as usize;
        scene.accel.intersect16(&camera[..n], &mut hits[..n]);
        rays.camera += n as u64;
        for ((k, ray), hit) in (done..).zip(&camera[..n]).zip(&hits[..n]) {
            sampler.set_sample(k, dims::vertex(0, 0));
            let l = integrator.li(scene, ray, hit.as_ref(), sampler, rays);
            if l.is_valid_radiance() {
                sum += l;
                let y = f64::from(l.luminance());
                lum.0 += y;
                lum.1 += y * y;
            } else {
                invalid += 1;
            }
        }
        done += n as u32;
    }
    (sum, invalid)
}
