//! The progressive walkthrough (001 §4.7.2, NOTES-001 §C.7): each frame renders one layer of
//! samples by splatting the cache, adds at most a budget of new records at misses (the thesis's
//! 100), and adds the layer to a running mean that restarts when the view or the accuracy
//! changes. Samples no record covers yet have their Lambertian part traced (noisy until a later
//! frame's record covers them), never a gather of their own. Records do not depend on the view,
//! so they are kept across camera moves; changing the accuracy re-indexes them (the splat radius
//! a·R and the threshold follow it, nothing is gathered again).

use super::pass::Layer;
use crate::camera::Camera;
use crate::integrators::ic::IcIntegrator;
use crate::integrators::RayCounts;
use crate::irradiance_cache::file::CacheFile;
use crate::irradiance_cache::params::Overture;
use crate::irradiance_cache::{CacheStats, IrradianceCache};
use crate::render::{RenderSettings, Sampling};
use crate::sampler::{SamplerKind, SamplerSettings};
use crate::scene::{RenderError, Scene};
use ircache_image::Image;
use ircache_math::{Mat4, Rgb, Vec3};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Light samples a walkthrough frame takes at each first vertex by default: frames are averaged,
/// so one a frame gives the same image sooner and keeps the frames quick.
pub const WALKTHROUGH_LIGHT_SAMPLES: u32 = 1;

/// Layers a view accumulates before it stops refining (the samples of one pixel sequence).
pub const MAX_LAYERS: u32 = 1024;

/// What one frame did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameReport {
    /// Layers in the running mean after this frame.
    pub layers: u32,
    /// Level-0 records in the cache.
    pub records: usize,
    /// Records this frame added at misses.
    pub new_records: usize,
    /// Samples of this frame no record covered after its misses were filled.
    pub uncovered: usize,
    /// Seconds the frame took.
    pub seconds: f64,
}

/// A walkthrough of one scene: the cache, the view and the running mean.
pub struct Walkthrough {
    scene: Scene,
    ic: IcIntegrator,
    cache: IrradianceCache,
    settings: RenderSettings,
    samplers: SamplerSettings,
    /// Most records one frame adds.
    pub budget: usize,
    sum: Vec<Rgb>,
    irradiance_sum: Vec<Rgb>,
    layers: u32,
    pass: Layer,
    /// The cache file records are saved to, and how many records of each level it holds.
    file: Option<(PathBuf, Vec<usize>)>,
    /// What the gathers at misses did, all frames together.
    pub stats: CacheStats,
}

impl Walkthrough {
    /// A walkthrough of `scene` at `width × height` with the cache settings of `ic` (its cache
    /// file, if any, is read first), run in `pool`; no pre-pass: records come from misses.
    pub fn new(
        scene: Scene,
        ic: &IcIntegrator,
        width: usize,
        height: usize,
        seed: u64,
        pool: &rayon::ThreadPool,
    ) -> Result<Walkthrough, RenderError> {
        let mut ic = ic.clone();
        ic.params.overture = Overture::Off;
        ic.seed = seed;
        let settings = RenderSettings {
            width,
            height,
            spp: MAX_LAYERS,
            seed,
            threads: pool.current_num_threads(),
            filter: crate::film::Filter::Box,
            band: None,
            // Every prefix of a Sobol' sequence is well stratified: each frame refines the last.
            sampling: Sampling {
                sampler: SamplerKind::Sobol,
                jitter: true,
                adaptive: None,
            },
        };
        let (cache, _) =
            crate::irradiance_cache::prepare::prepare_cache(&scene, &ic, &settings, pool)?;
        let file = ic
            .cache_file
            .clone()
            .map(|p| (p, cache.levels.iter().map(|l| l.len()).collect()));
        let samplers = settings.sampler();
        let pass = Layer::with_splatter(ic.splatter.clone());
        Ok(Walkthrough {
            scene,
            ic,
            cache,
            samplers,
            budget: 100,
            sum: vec![Rgb::ZERO; width * height],
            irradiance_sum: vec![Rgb::ZERO; width * height],
            layers: 0,
            pass,
            file,
            settings,
            stats: CacheStats::default(),
        })
    }

    /// The scene (its camera is the current view).
    #[must_use]
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The cache.
    #[must_use]
    pub fn cache(&self) -> &IrradianceCache {
        &self.cache
    }

    /// Layers in the running mean.
    #[must_use]
    pub fn layers(&self) -> u32 {
        self.layers
    }

    /// The accuracy records are splatted at.
    #[must_use]
    pub fn accuracy(&self) -> f32 {
        self.cache.params.accuracy
    }

    fn restart(&mut self) {
        self.layers = 0;
        self.sum.iter_mut().for_each(|s| *s = Rgb::ZERO);
        self.irradiance_sum.iter_mut().for_each(|s| *s = Rgb::ZERO);
    }

    /// Moves the camera to `to_world` (camera-to-world); the mean restarts.
    pub fn set_camera(&mut self, to_world: Mat4) {
        let c = &mut self.scene.camera;
        c.to_world = to_world;
        c.origin = to_world.transform_point3(Vec3::ZERO);
        self.restart();
    }

    /// Splats at accuracy `a` from now on (0 < a ≤ 1): the records are indexed anew at it;
    /// the mean restarts.
    pub fn set_accuracy(&mut self, a: f32) -> Result<(), String> {
        if !(a > 0.0 && a <= 1.0) {
            return Err(format!("accuracy {a}: expected a value in (0, 1]"));
        }
        self.cache.params.accuracy = a;
        self.ic.params.accuracy = a;
        // Radiance records keep their own accuracy unless it would exceed the new one.
        self.cache.params.radiance_accuracy = self.cache.params.radiance_accuracy.min(a);
        for level in 0..self.cache.levels.len() {
            let records = self.cache.levels[level].records().to_vec();
            self.cache.reindex(level, records);
        }
        self.restart();
        Ok(())
    }

    /// Renders one frame and adds it to the running mean (nothing once [`MAX_LAYERS`] are in).
    pub fn frame(&mut self, rays: &mut RayCounts) -> FrameReport {
        let start = Instant::now();
        let records = |c: &IrradianceCache| c.levels.first().map_or(0, |s| s.len());
        if self.layers >= MAX_LAYERS {
            return FrameReport {
                layers: self.layers,
                records: records(&self.cache),
                ..FrameReport::default()
            };
        }
        let layer = self.layers;
        let times = self.pass.prepare(
            &self.scene,
            &mut self.cache,
            &self.settings,
            &self.samplers,
            layer,
            self.budget,
            &mut self.stats,
        );
        let values = self.pass.shade(
            &self.scene,
            &self.ic,
            &self.cache,
            &self.settings,
            &self.samplers,
            true,
            rays,
        );
        let (Some(g), Some(splats)) = (self.pass.gbuffer(), self.pass.splats()) else {
            return FrameReport::default();
        };
        let mut uncovered = 0;
        for (i, l) in values.into_iter().enumerate() {
            // A sample that is not finite radiance counts as black (never a NaN pixel).
            let l = l.filter(|l| l.is_valid_radiance()).unwrap_or(Rgb::ZERO);
            let px = &splats.pixels[i];
            self.sum[i] += l;
            self.irradiance_sum[i] += px.irradiance().unwrap_or(Rgb::ZERO);
            uncovered += usize::from(
                g.samples[i]
                    .point
                    .is_some_and(|sp| px.min_error > self.cache.coverage_threshold(&sp)),
            );
        }
        let new_records = times.added;
        let cache = &self.cache;
        self.layers += 1;
        FrameReport {
            layers: self.layers,
            records: records(cache),
            new_records,
            uncovered,
            seconds: start.elapsed().as_secs_f64(),
        }
    }

    /// The running mean: the image, or the splatted irradiance of the first surfaces.
    #[must_use]
    pub fn image(&self, irradiance: bool) -> Image {
        let (w, h) = (self.settings.width, self.settings.height);
        let sums = if irradiance {
            &self.irradiance_sum
        } else {
            &self.sum
        };
        let n = self.layers.max(1) as f32;
        let mut img = Image::new(w, h);
        for (i, s) in sums.iter().enumerate() {
            img.set(i % w, i / w, *s / n);
        }
        img
    }

    /// Appends the records made since the cache file was read or last saved to it; an error
    /// without a cache file.
    pub fn save(&mut self) -> Result<usize, String> {
        let Some((path, saved)) = &mut self.file else {
            return Err("no cache file: start the walkthrough with --cache FILE to save".into());
        };
        let header = crate::irradiance_cache::prepare::header(
            &self.scene,
            &self.ic,
            self.settings.width,
            self.cache.environment,
        );
        let (mut file, _) =
            CacheFile::open(Path::new(path), &header, true).map_err(|e| e.to_string())?;
        let mut new = Vec::new();
        for (level, store) in self.cache.levels.iter().enumerate() {
            let from = saved.get(level).copied().unwrap_or(0);
            new.extend(
                store.records()[from.min(store.len())..]
                    .iter()
                    .map(|r| self.cache.stored(r)),
            );
        }
        file.append(&new).map_err(|e| e.to_string())?;
        *saved = self.cache.levels.iter().map(|l| l.len()).collect();
        Ok(new.len())
    }
}

impl std::fmt::Debug for Walkthrough {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Walkthrough")
            .field("layers", &self.layers)
            .field("records", &self.cache.levels.first().map(|s| s.len()))
            .finish_non_exhaustive()
    }
}

/// A camera at the eye of `camera` turned by `yaw` about its up axis and `pitch` about its
/// right axis (radians), then moved by `step` in its own axes (x left, y up, z forward).
#[must_use]
pub fn moved(camera: &Camera, yaw: f32, pitch: f32, step: Vec3) -> Mat4 {
    let turned = camera.to_world * Mat4::from_rotation_y(yaw) * Mat4::from_rotation_x(pitch);
    Mat4::from_translation(turned.transform_vector3(step)) * turned
}
