//! Integrators: estimators of the radiance arriving along a camera ray.
//!
//! A closed set dispatched by `match` (no virtual call per sample). Each takes the scene, a ray and
//! the pixel's random stream, and counts the rays it traces.

pub mod direct;
pub mod equiangular;
pub mod ic;
pub mod light_sampling;
pub mod media_march;
pub mod path;
pub mod path_continuation;
pub mod volpath;

use crate::sampler::Sampler;
use crate::scene::Scene;
use ircache_embree::Hit;
use ircache_math::{Ray, Rgb};
use ircache_scene::IntegratorDesc;
use light_sampling::DeferredShadows;

/// Rays traced, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// Camera rays.
    pub camera: u64,
    /// Closest-hit rays after the first hit (BSDF-sampled continuations).
    pub bounce: u64,
    /// Shadow (occlusion) rays.
    pub shadow: u64,
    /// Hemisphere gather rays of irradiance cache records made while rendering.
    pub gather: u64,
}

impl RayCounts {
    /// All rays.
    #[must_use]
    pub fn total(&self) -> u64 {
        self.camera + self.bounce + self.shadow + self.gather
    }
    /// Adds another count.
    pub fn add(&mut self, o: &RayCounts) {
        self.camera += o.camera;
        self.bounce += o.bounce;
        self.shadow += o.shadow;
        self.gather += o.gather;
    }
}

/// An integrator with its parameters.
// One lives per render, so the cache integrator's larger settings cost nothing worth a box.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum Integrator {
    /// Direct illumination only (Mitsuba's `direct`).
    Direct(direct::DirectIntegrator),
    /// Unidirectional path tracing with MIS and Russian roulette (Mitsuba's `path`).
    Path(path::PathIntegrator),
    /// Direct light per sample, diffuse indirect light from the irradiance cache.
    Ic(ic::IcIntegrator),
    /// Volumetric path tracing through participating media (Mitsuba's `volpath`).
    VolPath(volpath::VolPathIntegrator),
}

/// The integrator names this renderer knows.
pub const INTEGRATOR_NAMES: &[&str] = &["path", "volpath", "direct", "ic (irrcache)", "splat"];

impl Integrator {
    /// Builds the integrator named in `desc`.
    pub fn from_desc(desc: &IntegratorDesc) -> Result<Integrator, String> {
        if let Some(why) = &desc.unusable {
            return Err(why.clone());
        }
        match desc.kind.as_str() {
            "path" => Ok(Integrator::Path(path::PathIntegrator {
                max_depth: desc.max_depth,
                rr_depth: desc.rr_depth,
                hide_emitters: desc.hide_emitters,
            })),
            "volpath" => Ok(Integrator::VolPath(volpath::VolPathIntegrator {
                rr_depth: desc.rr_depth,
                hide_emitters: desc.hide_emitters,
                ..volpath::VolPathIntegrator::plain(desc.max_depth)
            })),
            "direct" => Ok(Integrator::Direct(direct::DirectIntegrator {
                emitter_samples: desc.emitter_samples.max(1),
                bsdf_samples: desc.bsdf_samples,
                hide_emitters: desc.hide_emitters,
            })),
            "ic" | "irrcache" => Ok(Integrator::Ic(ic::IcIntegrator::from_desc(desc)?)),
            // The irradiance cache with its first vertices served by splatting (001 ch. 4).
            "splat" => {
                let mut ic = ic::IcIntegrator::from_desc(desc)?;
                ic.pixel_pass = ic::PixelPass::Splat;
                Ok(Integrator::Ic(ic))
            }
            other => Err(format!(
                "unknown integrator \"{other}\" (known: {})",
                INTEGRATOR_NAMES.join(", ")
            )),
        }
    }

    /// What the integrator does once before the pixels: the cache's pre-pass for `ic` (run in
    /// `pool`), nothing for the others. Returns the integrator ready for the pixels and the
    /// pre-pass's figures.
    pub fn prepare(
        &self,
        scene: &Scene,
        settings: &crate::render::RenderSettings,
        pool: &rayon::ThreadPool,
    ) -> Result<(Integrator, Option<crate::irradiance_cache::CacheStats>), crate::scene::RenderError>
    {
        if let Integrator::Ic(ic) = self {
            if !scene.has_media() {
                ic.params
                    .check_without_media()
                    .map_err(crate::scene::RenderError::Invalid)?;
            }
        }
        match self {
            Integrator::VolPath(_) => {}
            Integrator::Direct(_) => scene.require_no_media("the direct integrator")?,
            Integrator::Path(_) => scene.require_no_media("the path integrator")?,
            Integrator::Ic(ic) if scene.has_media() => {
                let volpath = media_cache_integrator(scene, ic, settings, pool)?;
                return Ok((Integrator::VolPath(volpath), None));
            }
            Integrator::Ic(ic)
                if ic.pixel_pass != ic::PixelPass::Lookup && settings.filter.is_weighted() =>
            {
                return Err(crate::scene::RenderError::Invalid(
                    "splatting takes the box, tent and gaussian pixel filters, not ones with \
                     negative lobes (render it with --integrator ic)"
                        .into(),
                ));
            }
            Integrator::Ic(ic)
                if ic.pixel_pass != ic::PixelPass::Lookup && !scene.camera.is_pinhole() =>
            {
                return Err(crate::scene::RenderError::Invalid(format!(
                    "splatting projects records onto the film through a pinhole; the scene's \
                     camera is {} (render it with --integrator ic)",
                    scene.camera.projection.name()
                )));
            }
            Integrator::Ic(_) => {}
        }
        match self {
            Integrator::Ic(ic) if ic.cache.is_none() => {
                let (cache, stats) =
                    crate::irradiance_cache::prepare::prepare_cache(scene, ic, settings, pool)?;
                let mut ic = ic.clone();
                ic.cache = Some(std::sync::Arc::new(cache));
                ic.seed = settings.seed;
                Ok((Integrator::Ic(ic), Some(stats)))
            }
            other => Ok((other.clone(), None)),
        }
    }

    /// The filled cache and the pixel samples that no record reached, for integrators with one.
    #[must_use]
    pub fn cache(
        &self,
    ) -> Option<(
        std::sync::Arc<crate::irradiance_cache::IrradianceCache>,
        u64,
    )> {
        match self {
            Integrator::Ic(ic) => ic.cache.clone().map(|c| {
                (
                    c,
                    ic.uncached_samples
                        .load(std::sync::atomic::Ordering::Relaxed),
                )
            }),
            _ => None,
        }
    }

    /// The media cache serving the first surfaces (the `ic` integrator in a media scene).
    #[must_use]
    pub fn media_cache(&self) -> Option<&crate::media_cache::cache::MediaCache> {
        match self {
            Integrator::VolPath(v) => v.cache.as_deref(),
            _ => None,
        }
    }

    /// The volumetric records serving the media's in-scattered light (the `ic` integrator in a
    /// media scene).
    #[must_use]
    pub fn volume_records(&self) -> Option<&crate::media_cache::volume_records::VolumeCache> {
        match self {
            Integrator::VolPath(v) => v.volume_records.as_deref(),
            _ => None,
        }
    }

    /// The integrator whose pixel pass splats records (see [`crate::splatting`]), if it is one.
    #[must_use]
    pub fn splatting(&self) -> Option<&ic::IcIntegrator> {
        match self {
            Integrator::Ic(ic) if ic.pixel_pass == ic::PixelPass::Splat => Some(ic),
            _ => None,
        }
    }

    /// Radiance arriving along the camera ray `ray`, whose closest hit `first_hit` the caller
    /// traced (camera rays go to Embree in coherent packets; see [`crate::render`]).
    #[inline]
    pub fn li<S: Sampler + ?Sized>(
        &self,
        scene: &Scene,
        ray: &Ray,
        first_hit: Option<&Hit>,
        sampler: &mut S,
        rays: &mut RayCounts,
    ) -> Rgb {
        self.li_deferring(scene, ray, first_hit, sampler, rays, None, ic::Parts::All)
            .0
    }

    /// [`Integrator::li`], the first vertex's light samples leaving their shadow rays to
    /// `deferred` where the integrator can (`path`, `ic`: [`DeferredShadows::resolve`] adds
    /// their light); the others trace them at once. Second, the part of the radiance a cache
    /// gave (`ic`: [`ic::IcIntegrator::li_parts`]; zero for the others): the rest was traced.
    /// `parts` is for `ic` alone (the others compute all of it).
    #[allow(clippy::too_many_arguments)]
    pub fn li_deferring<S: Sampler + ?Sized>(
        &self,
        scene: &Scene,
        ray: &Ray,
        first_hit: Option<&Hit>,
        sampler: &mut S,
        rays: &mut RayCounts,
        deferred: Option<&mut DeferredShadows>,
        parts: ic::Parts,
    ) -> (Rgb, Rgb) {
        let traced = |l| (l, Rgb::ZERO);
        match self {
            Integrator::Direct(d) => traced(d.li(scene, ray, first_hit, sampler.as_dyn(), rays)),
            Integrator::Path(p) => traced(p.li(scene, ray, first_hit, sampler, rays, deferred)),
            Integrator::Ic(c) => c.li(scene, ray, first_hit, sampler, rays, deferred, parts),
            Integrator::VolPath(v) => traced(v.li(scene, ray, first_hit, sampler.as_dyn(), rays)),
        }
    }

    /// Radiance arriving along `ray`, tracing its first hit too.
    pub fn li_ray<S: Sampler + ?Sized>(
        &self,
        scene: &Scene,
        ray: &Ray,
        sampler: &mut S,
        rays: &mut RayCounts,
    ) -> Rgb {
        rays.camera += 1;
        let hit = scene.accel.intersect(ray);
        self.li(scene, ray, hit.as_ref(), sampler, rays)
    }
}

/// The `ic` integrator in a scene with media: `volpath` at `max_depth` bounces + 2 with the
/// first surface's diffuse indirect light from records gathered through the media (002; see
/// [`crate::media_cache::cache`]), the bounces beyond a record's own path traced from its
/// gathers. What the media cache does not do yet is refused by name.
fn media_cache_integrator(
    scene: &Scene,
    ic: &ic::IcIntegrator,
    settings: &crate::render::RenderSettings,
    pool: &rayon::ThreadPool,
) -> Result<volpath::VolPathIntegrator, crate::scene::RenderError> {
    let p = &ic.params;
    let refuse = |what: &str| {
        Err(crate::scene::RenderError::Invalid(
            crate::media_cache::cache::unavailable(what),
        ))
    };
    crate::media_cache::cache::available(p).map_err(crate::scene::RenderError::Invalid)?;
    if p.photons.is_some_and(|n| n > 0) && scene.media.iter().any(crate::media::Medium::emits) {
        return refuse(
            "a global photon map is not available in a scene whose media emit (photons leave \
             the lights alone): give --photons 0",
        );
    }
    if ic.pixel_pass != ic::PixelPass::Lookup {
        return refuse("splatting is not available there yet");
    }
    // The cache file's records first (surface and volumetric), the pre-passes' new ones
    // appended after them.
    let mut file = None;
    let (mut surface, mut volume, mut notes) = (Vec::new(), Vec::new(), Vec::new());
    if let Some(path) = &ic.cache_file {
        let header =
            crate::irradiance_cache::prepare::header(scene, ic, settings.width, Default::default());
        let (f, contents) =
            crate::irradiance_cache::file::CacheFile::open(path, &header, ic.force_reuse)?;
        notes = contents.notes(path, &header);
        // A media scene's file holds first-bounce records without radiance alone (a forced
        // file of another scene may hold others).
        surface = contents
            .records
            .into_iter()
            .filter(|(r, c)| {
                u32::from(r.level) < crate::media_cache::cache::MAX_LEVELS && c.is_none()
            })
            .map(|(r, _)| r)
            .collect();
        // A forced file of another scene may name media this one lacks.
        volume = contents
            .volume
            .into_iter()
            .filter(|v| v.medium < scene.media.len())
            .collect();
        file = Some(f);
    }
    // Caustics from photons, where a surface makes them (see `VolPathIntegrator::trace`).
    let caustics = pool
        .install(|| crate::irradiance_cache::prepare::media_caustic_map(scene, p, settings.seed))
        .map(std::sync::Arc::new);
    notes.extend(crate::irradiance_cache::prepare::caustic_note(
        p,
        caustics.is_some(),
    ));
    // The light after a bounce at the Lambertian surfaces of the records' paths, from photons
    // where asked (never at the camera paths' own).
    let global = pool
        .install(|| crate::irradiance_cache::prepare::media_global_map(scene, p, settings.seed))
        .map(std::sync::Arc::new);
    // Volumetric records first: their paths are `volpath`'s own, and the surface records'
    // gathers take the light scattered along their rays from them.
    // `volpath` at the depth asked, as the records' paths take it (without records of any kind).
    let gatherer = volpath::VolPathIntegrator {
        hide_emitters: ic.hide_emitters,
        first_light_samples: p.direct_samples,
        global: global.clone(),
        ..volpath::VolPathIntegrator::plain(volpath::VolPathIntegrator::depth_of_bounces(p.bounces))
    };
    let volume_records =
        (p.media_volume_records && p.media_march > 0 && p.bounces > 0).then(|| {
            let records = pool.install(|| {
                crate::media_cache::volume_records::VolumeCache::build(
                    &gatherer,
                    scene,
                    p.accuracy,
                    p.media_volume_divisions,
                    p.media_march,
                    settings.width,
                    settings.height,
                    settings.seed,
                    std::mem::take(&mut volume),
                )
            });
            std::sync::Arc::new(records)
        });
    // No bounce (`max_depth` 2): direct light alone, no records.
    let cache = if p.bounces > 0 {
        let mut cache = pool.install(|| {
            crate::media_cache::cache::MediaCache::build(
                scene,
                p,
                (settings.width, settings.height),
                settings.seed,
                surface,
                crate::media_cache::cache::RecordSources {
                    caustics: caustics.as_ref(),
                    global: global.as_ref(),
                    volume: volume_records.as_ref(),
                },
            )
        });
        cache.stats.notes = notes;
        cache.stats.caustic_map = caustics.as_ref().map(|c| c.map.summary());
        cache.stats.global_map = global.as_ref().map(|g| g.map.summary());
        if let Some(f) = file.as_mut() {
            let new: Vec<_> = cache.made().map(|&r| (r, None)).collect();
            f.append(&new)?;
        }
        Some(std::sync::Arc::new(cache))
    } else {
        None
    };
    if let (Some(f), Some(records)) = (file.as_mut(), volume_records.as_ref()) {
        f.append_volume(&records.records()[records.stats.loaded..])?;
    }
    let integrator = volpath::VolPathIntegrator {
        cache,
        camera_march: (p.media_march > 0).then_some(media_march::CameraMarch {
            points: p.media_march,
        }),
        caustics,
        volume_records,
        global: None,
        ..gatherer
    };
    Ok(integrator)
}

/// Power heuristic with β = 2 (Veach 1997), as Mitsuba 3's `mis_weight`.
#[inline]
#[must_use]
pub fn mis_weight(pdf_a: f32, pdf_b: f32) -> f32 {
    let (a, b) = (pdf_a * pdf_a, pdf_b * pdf_b);
    if a + b > 0.0 && a.is_finite() {
        a / (a + b)
    } else if a.is_infinite() {
        1.0
    } else {
        0.0
    }
}
