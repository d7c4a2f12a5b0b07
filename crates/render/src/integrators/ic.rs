//! The irradiance-cache integrator (`ic`, `<integrator type="irrcache">`): per pixel sample, a
//! path as the path tracer follows it ([`super::path_continuation`]), with emission, direct light
//! (light samples and BSDF samples combined by MIS), specular and glossy lobes traced; at each
//! vertex with a Lambertian part, that part's indirect light is `k(wo)/π` times the irradiance
//! interpolated from the cache of the vertex's depth (000 eq. 3.15), and the path continues
//! through the glossy part alone. So every lobe is accounted for: whatever the cache does not
//! hold is traced. The cache is filled before the pixels are rendered (see
//! [`crate::irradiance_cache::build`]).

use super::light_sampling::DeferredShadows;
use super::path_continuation::{
    trace_path_deferring, FirstVertex, IndirectSource, PathSettings, PathStart,
};
use super::RayCounts;
use crate::irradiance_cache::environment::HeldEnvironment;
use crate::irradiance_cache::gather::{mix, Gatherer, SceneRadiance, ShadingPoint, WorkState};
use crate::irradiance_cache::hemisphere::Stratification;
use crate::irradiance_cache::{IcParams, IrradianceCache};
use crate::sampler::Sampler;
use crate::scene::Scene;
use ircache_embree::Hit;
use ircache_math::{Ray, Rgb, Vec3};
use ircache_scene::{IntegratorDesc, ParamValue};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// The `ic` integrator with its cache (filled by the renderer before the pixel pass).
#[derive(Clone, Debug)]
pub struct IcIntegrator {
    /// Cache settings.
    pub params: IcParams,
    /// Hide emitters seen directly.
    pub hide_emitters: bool,
    /// The filled cache; `None` until the pre-pass has run.
    pub cache: Option<Arc<IrradianceCache>>,
    /// Seed of the records made during the pixel pass.
    pub seed: u64,
    /// Pixel samples no record reached even at twice the accuracy (a record was gathered for
    /// them alone and not kept).
    pub uncached_samples: Arc<AtomicU64>,
    /// Persistent cache file: read before the pre-pass, new records appended batch by batch.
    pub cache_file: Option<std::path::PathBuf>,
    /// Use a cache file made for another scene or with other settings anyway.
    pub force_reuse: bool,
    /// Surfaces excluded from the cache (003 item 6).
    pub exclusions: Exclusions,
    /// How the pixel pass finds the records of a camera path's first vertex.
    pub pixel_pass: PixelPass,
    /// Where `splat` splats its records (`None`: on the CPU).
    pub splatter: Option<Arc<dyn crate::splatting::buffer::Splatter>>,
    /// Where `--record-source gpu-plane` has its planes made (the caller attaches the GPU's).
    pub plane_source: Option<Arc<dyn crate::irradiance_cache::plane::PlaneSource>>,
}

/// Which parts of a pixel sample's light [`IcIntegrator::li`] computes (its second value is
/// always what the cache gave of what it computed).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Parts {
    /// All of it.
    #[default]
    All,
    /// What the cache gives, alone: no light samples.
    Served,
    /// All of it for a pixel whose earlier frames' samples are kept (a still run's later
    /// frames, [`crate::render::render_runs`]): in a scene of one light, a quarter of
    /// `direct_samples` at the first vertex (one by default), for the run's many pixel samples
    /// stratify the light already.
    Continuing,
}

/// How the pixel pass finds the records serving a camera path's first vertex.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PixelPass {
    /// Each pixel sample looks the records up in the cache's spatial index (`ic`).
    #[default]
    Lookup,
    /// Records are splatted over the image's samples (`splat`, 001 ch. 4; see
    /// [`crate::splatting`]); deeper vertices still look up.
    Splat,
}

/// What splatting found for a sample's first vertex (see [`crate::splatting`]): the blended
/// irradiance and the light the radiance-cached glossy lobe reflects towards the camera, each
/// `None` where no record reaches the vertex at the accuracy.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Splatted {
    /// Irradiance (000 eq. 3.15), as the lookup at threshold 1 gives it.
    pub irradiance: Option<Rgb>,
    /// Glossy radiance towards the camera (000 eq. 3.19), as the glossy lookup gives it.
    pub glossy: Option<Rgb>,
    /// Where splatting found no irradiance, trace the Lambertian part (the walkthrough: a
    /// miss waits for a record of a later frame) instead of looking up at relaxed thresholds
    /// or gathering a record for the sample alone.
    pub trace_misses: bool,
}

/// Which surfaces take no cache records (Radiance's `-ae`/`-aE` and `-ai`/`-aI`): they get the
/// ambient value as their indirect light, a much cheaper estimate.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum Exclusions {
    /// Every surface takes records.
    #[default]
    None,
    /// These names (shape ids in XML, material names in OBJ) take none.
    Exclude(Vec<String>),
    /// Only these names take records.
    Include(Vec<String>),
}

impl Exclusions {
    /// Per shape, whether it is excluded; names that match no shape are an error.
    pub fn resolve(&self, scene: &Scene) -> Result<Vec<bool>, String> {
        let names = match self {
            Exclusions::None => return Ok(vec![false; scene.shapes.len()]),
            Exclusions::Exclude(n) | Exclusions::Include(n) => n,
        };
        for n in names {
            if !scene.shapes.iter().any(|s| s.name.as_deref() == Some(n)) {
                let mut known: Vec<&str> = scene
                    .shapes
                    .iter()
                    .filter_map(|s| s.name.as_deref())
                    .collect();
                known.sort_unstable();
                known.dedup();
                return Err(format!(
                    "no surface is named \"{n}\" (names: {})",
                    if known.is_empty() {
                        "none".into()
                    } else {
                        known.join(", ")
                    }
                ));
            }
        }
        let listed = |s: &crate::scene::Shape| s.name.as_ref().is_some_and(|x| names.contains(x));
        Ok(scene
            .shapes
            .iter()
            .map(|s| match self {
                Exclusions::Include(_) => !listed(s),
                _ => listed(s),
            })
            .collect())
    }

    /// A hash of the list, folded into a cache file's scene hash (exclusions change records).
    #[must_use]
    pub fn hash(&self) -> u64 {
        use std::fmt::Write;
        let mut h = crate::irradiance_cache::file::Fnv::default();
        let _ = write!(h, "{self:?}");
        if *self == Exclusions::None {
            0
        } else {
            h.0
        }
    }
}

impl IcIntegrator {
    /// Builds the integrator from a scene's `<integrator type="irrcache">` (or any integrator
    /// description whose type was overridden to `ic`): `max_depth` N gives N − 2 bounces unless
    /// `bounces` is given; further parameters are [`IcParams::set`]'s names.
    pub fn from_desc(desc: &IntegratorDesc) -> Result<IcIntegrator, String> {
        let mut params = IcParams::default();
        params.bounces = if desc.max_depth >= 0 {
            (desc.max_depth - 2).max(0) as u32
        } else {
            crate::irradiance_cache::params::UNBOUNDED
        };
        for (name, value, loc) in &desc.extra {
            let text = match value {
                ParamValue::Integer(v) => v.to_string(),
                ParamValue::Float(v) => v.to_string(),
                ParamValue::Boolean(v) => v.to_string(),
                ParamValue::String(v) => v.clone(),
                ParamValue::Rgb(c) => format!("{} {} {}", c.r, c.g, c.b),
            };
            params.set(name, &text).map_err(|e| format!("{loc}: {e}"))?;
        }
        params.check()?;
        Ok(IcIntegrator {
            params,
            hide_emitters: desc.hide_emitters,
            cache: None,
            seed: 0,
            uncached_samples: Arc::new(AtomicU64::new(0)),
            cache_file: None,
            force_reuse: false,
            exclusions: Exclusions::None,
            pixel_pass: PixelPass::Lookup,
            splatter: None,
            plane_source: None,
        })
    }

    /// Radiance along the camera ray `ray`, whose closest hit `first_hit` the caller traced: a
    /// path traced to `max_depth` = bounces + 2 whose vertices take their Lambertian indirect
    /// light from the cache of their depth where it has records, and continue through the
    /// glossy part of the BSDF. With `deferred`, the first vertex's light samples wait there for
    /// their shadow rays. Second, the part the cache gave ([`IcIntegrator::li_parts`]).
    #[allow(clippy::too_many_arguments)]
    pub fn li<S: Sampler + ?Sized>(
        &self,
        scene: &Scene,
        ray: &Ray,
        first_hit: Option<&Hit>,
        sampler: &mut S,
        rays: &mut RayCounts,
        deferred: Option<&mut DeferredShadows>,
        parts: Parts,
    ) -> (Rgb, Rgb) {
        let fresh;
        let cache = match &self.cache {
            Some(c) => c.as_ref(),
            None => {
                fresh = IrradianceCache::new(scene, &self.params);
                &fresh
            }
        };
        self.li_parts(
            scene, cache, ray, first_hit, None, sampler, rays, deferred, parts,
        )
    }

    /// [`IcIntegrator::li`] with the cache `cache` and, for the first vertex, what splatting
    /// found there (`splatted`; where it found nothing, the vertex looks up as any other), and,
    /// second, the part of it that came from the cache (the
    /// records' irradiance and glossy light, caustic and global maps, the ambient value): the
    /// rest, emission and direct light and the lobes traced, is what the path sampled. Light
    /// samples left to `deferred` add to the first part only. `parts` may leave some out.
    #[allow(clippy::too_many_arguments)]
    pub fn li_parts<S: Sampler + ?Sized>(
        &self,
        scene: &Scene,
        cache: &IrradianceCache,
        ray: &Ray,
        first_hit: Option<&Hit>,
        splatted: Option<Splatted>,
        sampler: &mut S,
        rays: &mut RayCounts,
        deferred: Option<&mut DeferredShadows>,
        parts: Parts,
    ) -> (Rgb, Rgb) {
        // One light sample when the only light is a delta light (all samples are alike).
        let first_light_samples = if scene.lights.all_delta() && scene.lights.len() == 1 {
            1
        } else if parts == Parts::Continuing && scene.lights.len() == 1 {
            // Only with one light: where several compete, the samples' stratified choice
            // among them is what the four carry (Veach's scene: 1.5x the noise with one).
            self.params.direct_samples.div_ceil(4)
        } else {
            self.params.direct_samples.max(1)
        };
        let settings = PathSettings {
            max_depth: self.params.max_depth(),
            rr_depth: RR_DEPTH,
            first_light_samples,
        };
        let start = PathStart::camera(*ray, self.hide_emitters);
        let mut source = PixelLookup {
            ic: self,
            cache,
            splatted: splatted.unwrap_or_default(),
            took: Rgb::ZERO,
            parts,
        };
        let l = trace_path_deferring(
            scene,
            start,
            FirstVertex::Hit(first_hit),
            &mut source,
            &settings,
            sampler,
            rays,
            deferred,
        );
        (l, source.took)
    }
}

/// Russian roulette depth of camera paths (Mitsuba's default).
const RR_DEPTH: u32 = 5;

/// The pixel pass's lookups: the cache of the vertex's depth, interpolated at the accuracy `a`,
/// else from records up to 4a away (pixel samples off the pre-pass's pixel centres); else, at
/// depth 0, from a record gathered for this sample alone, and deeper (surfaces seen in glossy
/// reflections, which the pre-pass does not visit) by tracing. At depth 0, what splatting found
/// comes first.
struct PixelLookup<'a> {
    ic: &'a IcIntegrator,
    cache: &'a IrradianceCache,
    splatted: Splatted,
    /// The path's radiance from what it served so far.
    took: Rgb,
    /// Which parts of the light are asked for.
    parts: Parts,
}

impl IndirectSource for PixelLookup<'_> {
    fn took(&mut self, light: Rgb) {
        self.took += light;
    }

    fn samples_lights(&self) -> bool {
        self.parts != Parts::Served
    }

    fn irradiance(
        &mut self,
        scene: &Scene,
        sp: &ShadingPoint,
        depth: u32,
        sampler: &mut dyn Sampler,
        rays: &mut RayCounts,
    ) -> Option<Rgb> {
        let cache = self.cache;
        if cache.is_excluded(sp.it.shape) {
            return Some(cache.ambient * std::f32::consts::PI);
        }
        // Caustics where records serve; the global map holds its own.
        Some(match self.cached(scene, sp, depth, sampler, rays)? {
            Served::Records(e) => e + cache.caustic_irradiance(sp, depth),
            Served::Photons(e) => e,
        })
    }

    fn glossy(&mut self, _: &Scene, sp: &ShadingPoint, depth: u32, wo: Vec3) -> Option<Rgb> {
        if let (0, Some(l)) = (depth, self.splatted.glossy) {
            return Some(l);
        }
        crate::radiance_cache::lookup::glossy(self.cache, sp, depth, wo)
    }

    fn held_environment(&self, sp: &ShadingPoint) -> HeldEnvironment {
        self.cache.held_environment_at(sp)
    }

    fn ambient(&self) -> Rgb {
        self.cache.ambient
    }

    fn caustics_served(&self) -> bool {
        self.cache.caustics_served()
    }
}

impl PixelLookup<'_> {
    /// The irradiance records serve at `sp` (caustics aside), or from the global photon map at a
    /// vertex two or more bounces beyond the camera's first that no record reaches (the first
    /// such vertex of a path seen through glossy or specular reflection is traced: its hits,
    /// one bounce further, read the map, as a final gather).
    fn cached(
        &mut self,
        scene: &Scene,
        sp: &ShadingPoint,
        depth: u32,
        sampler: &mut dyn Sampler,
        rays: &mut RayCounts,
    ) -> Option<Served> {
        let cache = self.cache;
        if depth == 0 {
            if let Some(e) = self.splatted.irradiance {
                return Some(Served::Records(e));
            }
            if self.splatted.trace_misses {
                return None;
            }
        }
        if let Some(store) = cache.levels.get(depth as usize) {
            for threshold in [1.0, 2.0, 4.0] {
                if let Some(i) =
                    store.interpolate(sp.it.p, sp.n, sp.n_bump, threshold, cache.params.gradients)
                {
                    return Some(Served::Records(i.e));
                }
            }
        }
        if depth >= 2 {
            return cache.photon_irradiance(sp, depth).map(Served::Photons);
        }
        if depth > 0 {
            return None;
        }
        self.ic.uncached_samples.fetch_add(1, Ordering::Relaxed);
        let light = SceneRadiance {
            scene,
            deeper: cache.params.deeper,
        };
        let g = Gatherer::new(&light, cache, self.ic.seed);
        let mut st = WorkState::new(cache.levels.len());
        let key = mix(0x0070_6978_656c, sampler.next_key());
        // It serves this sample alone (thin or newly seen geometry): a quarter of the divisions.
        let strata = Stratification::from_divisions((self.ic.params.divisions / 4).max(16));
        let rec = g.record_with(&mut st, sp, 0, key, strata);
        rays.gather += st.counts.gather_rays;
        rays.shadow += st.counts.shadow_rays;
        Some(Served::Records(rec.e))
    }
}

/// Where a pixel-pass vertex's Lambertian indirect light came from.
enum Served {
    /// Irradiance records (caustics left to the caustic map).
    Records(Rgb),
    /// The global photon map (caustics included).
    Photons(Rgb),
}
