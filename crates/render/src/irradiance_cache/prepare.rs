//! Filling the cache for an image before its pixels: records from a cache file first (shared
//! with other processes), then the pre-pass ([`super::build::fill_for_image`]), whose new records
//! go to the file batch by batch.

use super::build::{fill_for_image, BatchHook};
use super::file::{self, CacheFile, Header, Stored};
use super::{CacheStats, IrradianceCache};
use crate::integrators::ic::IcIntegrator;
use crate::photon_map::{bounce_limit, Lookup, PhotonMaps};
use crate::radiance_cache::RadianceCache;
use crate::render::RenderSettings;
use crate::scene::{RenderError, Scene};
use std::sync::Arc;

/// Fills the irradiance cache for the image: records from the cache file first (if any), then
/// the pre-pass, whose new records are appended to the file batch by batch.
pub fn prepare_cache(
    scene: &Scene,
    ic: &IcIntegrator,
    settings: &RenderSettings,
    pool: &rayon::ThreadPool,
) -> Result<(IrradianceCache, CacheStats), RenderError> {
    let tables_start = std::time::Instant::now();
    let mut cache = empty_cache(scene, ic, settings.width, None, None, settings.seed, pool)?;
    // The photon maps, built alongside, report their own time.
    let maps_seconds: f64 = cache
        .photons
        .as_ref()
        .map_or(0.0, |m| m.maps().map(|map| map.seconds).sum());
    let radiance_table_seconds = (tables_start.elapsed().as_secs_f64() - maps_seconds).max(0.0);
    let header = header(scene, ic, settings.width, cache.environment);
    let mut loaded = 0u64;
    let mut notes: Vec<String> = super::environment::auto_note(
        ic.params.cached_environment,
        cache.environment,
        cache.environment_visibility,
    )
    .into_iter()
    .collect();
    let mut shared = match &ic.cache_file {
        None => None,
        Some(path) => {
            let (f, contents) = CacheFile::open(path, &header, ic.force_reuse)?;
            notes.extend(contents.notes(path, &header));
            for stored in contents.records {
                if cache.insert_stored(stored) {
                    loaded += 1;
                }
            }
            Some(SharedFile {
                file: f,
                failure: None,
            })
        }
    };
    let photon_start = std::time::Instant::now();
    let placed = photon_records(&mut cache);
    let photon_record_seconds = photon_start.elapsed().as_secs_f64();
    let mut stats = if ic.params.bounces > 0 {
        let mut none = ();
        let hook: &mut (dyn BatchHook + Send) = match shared.as_mut() {
            Some(s) => s,
            None => &mut none,
        };
        let stats = pool.install(|| {
            fill_for_image(
                scene,
                &mut cache,
                settings.width,
                settings.height,
                settings.rows(),
                settings.seed,
                hook,
                None,
            )
            .0
        });
        if let Some(e) = shared.and_then(|s| s.failure) {
            return Err(e.into());
        }
        stats
    } else {
        CacheStats::default()
    };
    if ic.params.spatial_order {
        for store in &mut cache.levels {
            store.sort_spatially();
        }
    }
    stats.records_loaded = loaded;
    stats.photon_records = placed.records;
    stats.photon_record_seconds = photon_record_seconds;
    notes.extend(photon_note(&ic.params));
    let made = cache.photons.as_ref().is_some_and(|m| m.caustic.is_some());
    notes.extend(caustic_note(&ic.params, made));
    stats.notes = notes;
    stats.records_per_level = cache.levels.iter().map(|s| s.len()).collect();
    stats.radiance_records = cache.radiance_records.len();
    stats.radiance_table_seconds = radiance_table_seconds;
    Ok((cache, stats))
}

/// An empty cache for a `width`-pixel-wide view of `scene` with `ic`'s settings: radiance
/// caching's tables made (or `tables`, made for the same materials, reused), exclusions
/// resolved, the pixel footprint set, the photon maps traced (on streams of `seed`; or `maps`,
/// traced so for this scene and these settings, reused).
pub fn empty_cache(
    scene: &Scene,
    ic: &IcIntegrator,
    width: usize,
    tables: Option<&Arc<RadianceCache>>,
    maps: Option<Arc<PhotonMaps>>,
    seed: u64,
    pool: &rayon::ThreadPool,
) -> Result<IrradianceCache, RenderError> {
    let mut cache = IrradianceCache::new(scene, &ic.params);
    if let Some(min_albedo) = ic.params.radiance_cache.min_glossy_albedo() {
        let tables = match tables {
            Some(t) => t.clone(),
            None => Arc::new(
                pool.install(|| RadianceCache::new(scene, ic.params.radiance_order, min_albedo)),
            ),
        };
        // No lobe to cache (`auto` in a scene without rough metals): no tables, as off.
        cache.radiance = tables.caches_any().then_some(tables);
    }
    cache.excluded = ic.exclusions.resolve(scene).map_err(RenderError::Invalid)?;
    cache.pixel_spread = scene.camera.pixel_spread(width);
    cache.plane_source = ic.plane_source.clone();
    if ic.params.record_source == super::params::RecordSource::GpuPlane
        && cache.plane_source.is_none()
    {
        return Err(RenderError::Invalid(
            "--record-source gpu-plane needs the GPU's planes: `ircache render` attaches them \
             when built with the gpu feature and a device exists (else use --record-source \
             plane, the same records ray cast on the CPU)"
                .into(),
        ));
    }
    cache.photons = maps.or_else(|| {
        pool.install(|| photon_maps(scene, &ic.params, seed))
            .map(Arc::new)
    });
    Ok(cache)
}

/// With `--photon-records on`, fills the first level with records made from the global map's
/// photons (001 Algorithm 6).
pub fn photon_records(cache: &mut IrradianceCache) -> crate::photon_map::records::PlacementStats {
    use crate::photon_map::records::{place_records, PhotonRecordSettings};
    let params = &cache.params;
    let Some(maps) = cache.photons.clone().filter(|_| params.photon_records) else {
        return Default::default();
    };
    if cache.levels.is_empty() {
        return Default::default();
    }
    let settings = PhotonRecordSettings {
        accuracy: params.accuracy,
        lookup: params.photon_lookup,
        // From the smallest record's reach to the photon lookups' largest radius.
        zone_limits: (
            params.accuracy * cache.r_min,
            maps.global_lookup
                .max_radius
                .max(params.accuracy * cache.r_min),
        ),
        max_bounces: bounce_limit(params.bounces),
        without_caustics: maps.caustic.is_some(),
        metric: params.error_metric,
    };
    place_records(&maps.global.tree, &mut cache.levels[0], &settings)
}

/// What a user should hear when `--photons` has nothing to serve: with fewer than two bounces a
/// gather hit has no indirect light of its own (and without photon records the map stays
/// empty).
#[must_use]
pub fn photon_note(params: &super::IcParams) -> Option<String> {
    let photons = params.photons.unwrap_or(0);
    (photons > 0 && params.bounces < 2 && !params.photon_records).then(|| {
        format!(
            "--photons {} does nothing at {} bounce(s): the surfaces records' gather rays hit \
             have no indirect light to read from photons (give -ab 2 or more, or \
             --photon-records on)",
            photons, params.bounces
        )
    })
}

/// What a user should hear when `--caustic-photons N` made no caustic map: no surface that
/// makes caustics, or none that light reaches (the gathers then keep those paths).
#[must_use]
pub fn caustic_note(params: &super::IcParams, made: bool) -> Option<String> {
    let asked = params.caustic_photons.unwrap_or(0);
    (asked > 0 && !made).then(|| {
        format!(
            "--caustic-photons {asked} stored none: no surface with a delta lobe (smooth glass, \
             a mirror, a smooth coating) sends light onto the others, so caustics stay with \
             the gathers"
        )
    })
}

/// The photon maps `params` ask for (`None` for none): the global map's photons serve vertices
/// one bounce beyond a record, so they need at most `bounces − 1` bounces of their own.
#[must_use]
pub fn photon_maps(scene: &Scene, params: &super::IcParams, seed: u64) -> Option<PhotonMaps> {
    // No caustic map where no surface makes caustics: the gathers keep every path, as without.
    let caustic_photons = if params.caustic_photons() > 0
        && crate::photon_map::trace::caustic_targets(scene).is_empty()
    {
        0
    } else {
        params.caustic_photons()
    };
    if params.global_photons() == 0 && caustic_photons == 0 {
        return None;
    }
    let (global, caustic) = photon_lookups(scene, params);
    // Gather hits, one bounce beyond the camera's surfaces, take photons of up to `bounces − 1`
    // bounces; photon records at the camera's surfaces up to `bounces`.
    let gather_bounces = bounce_limit(params.bounces.saturating_sub(1));
    let bounces = if params.photon_records {
        bounce_limit(params.bounces)
    } else {
        gather_bounces
    };
    let photons = if bounces >= 1 {
        params.global_photons()
    } else {
        0
    };
    Some(PhotonMaps::build(
        scene,
        (photons, caustic_photons),
        (bounces, gather_bounces),
        (global, caustic),
        photon_seed(seed),
    ))
}

/// The lookups of the global and caustic maps: the `--photon-lookup` nearest photons within
/// `--photon-radius` of the scene's size, half as many within a quarter of that for caustics.
fn photon_lookups(scene: &Scene, params: &super::IcParams) -> (Lookup, Lookup) {
    let radius = params.photon_radius * super::gather::scene_size(scene);
    let global = Lookup {
        count: params.photon_lookup,
        max_radius: radius,
        hull: true,
    };
    let caustic = Lookup {
        count: (params.photon_lookup / 2).max(1),
        max_radius: radius * 0.25,
        hull: false,
    };
    (global, caustic)
}

/// The photons' streams of a render's `seed`.
fn photon_seed(seed: u64) -> u64 {
    crate::irradiance_cache::gather::mix(seed, 0x7068_6f74_6f6e)
}

/// The caustic map of the cache in media (`None` without caustic photons, or where no surface
/// makes caustics, whose tracing stores none): photons of up to `bounces` bounces, as a first
/// surface's caustic may take at `max_depth` = bounces + 2.
#[must_use]
pub fn media_caustic_map(
    scene: &Scene,
    params: &super::IcParams,
    seed: u64,
) -> Option<crate::photon_map::ServingMap> {
    if params.bounces == 0 {
        return None;
    }
    let bounces = crate::photon_map::bounce_limit(params.bounces);
    let map = crate::photon_map::PhotonMap::caustic(
        scene,
        params.caustic_photons(),
        bounces,
        photon_seed(seed),
    )?;
    Some(crate::photon_map::ServingMap {
        map,
        lookup: photon_lookups(scene, params).1,
    })
}

/// The global map of the cache in media (`None` without global photons, with one bounce, or
/// where a medium emits: photons leave the lights alone): photons of up to `bounces − 1`
/// bounces, as the records' gather hits take them (a scattering in a medium counts), their
/// irradiance estimated in advance. With `--photons auto`, only where it pays: emitting at
/// most [`AUTO_EMITTED_PER_STORED`] photons per photon asked for, and dropped if that stored
/// under half of them (lamps in open fog, where most light leaves the scene).
#[must_use]
pub fn media_global_map(
    scene: &Scene,
    params: &super::IcParams,
    seed: u64,
) -> Option<crate::photon_map::ServingMap> {
    let photons = params.global_photons();
    if photons == 0 || params.bounces < 2 || scene.media.iter().any(|m| m.emits()) {
        return None;
    }
    let auto = params.photons.is_none();
    let cap = if auto {
        AUTO_EMITTED_PER_STORED
    } else {
        crate::photon_map::trace::MAX_EMITTED_PER_STORED
    };
    let lookup = photon_lookups(scene, params).0;
    let map = crate::photon_map::PhotonMap::build_within(
        scene,
        crate::photon_map::MapKind::Global,
        (photons, cap),
        bounce_limit(params.bounces.saturating_sub(1)),
        photon_seed(seed),
        Some(&lookup),
    );
    let pays = !map.tree.is_empty() && (!auto || 2 * map.stats.stored >= photons);
    pays.then_some(crate::photon_map::ServingMap { map, lookup })
}

/// Photons emitted per photon asked for, at most, by the media cache's global map at
/// `--photons auto` (see [`media_global_map`]): the fog box stores two of every three it
/// emits, open fog under-lit by its lamps one in 180.
pub const AUTO_EMITTED_PER_STORED: u64 = 4;

/// The header of a cache file for `scene` rendered by `ic` at `width` pixels across, its records
/// holding the environment as `held` says.
#[must_use]
pub fn header(
    scene: &Scene,
    ic: &IcIntegrator,
    width: usize,
    held: super::environment::HeldEnvironment,
) -> Header {
    Header {
        version: file::VERSION,
        scene_hash: scene.content_hash ^ ic.exclusions.hash(),
        view_hash: view_hash(scene, &ic.params, width),
        params: super::IcParams {
            cached_environment: super::environment::resolved(ic.params.cached_environment, held),
            ..ic.params.clone()
        },
    }
}

/// What records' radii depend on besides the scene and settings: with Tabellion's metric the
/// pixel footprint, so the camera and the film width; otherwise nothing (0).
fn view_hash(scene: &Scene, params: &super::IcParams, width: usize) -> u64 {
    use super::record::ErrorMetric;
    use std::fmt::Write;
    if params.error_metric != ErrorMetric::Tabellion {
        return 0;
    }
    let mut h = file::Fnv::default();
    let c = &scene.camera;
    let _ = write!(h, "{:?} {} {width}", c.to_world, c.tan_half_x);
    if !c.is_pinhole() {
        let _ = write!(h, " {:?}", c.projection);
    }
    h.0
}

/// The pre-pass's link to a cache file shared with other processes: their records come in
/// before and after each batch, this process's go out after it.
struct SharedFile {
    file: CacheFile,
    failure: Option<file::CacheFileError>,
}

impl BatchHook for SharedFile {
    fn before(&mut self) -> Vec<Stored> {
        if self.failure.is_some() {
            return Vec::new();
        }
        self.file.read_new().unwrap_or_else(|e| {
            self.failure = Some(e);
            Vec::new()
        })
    }

    fn after(&mut self, added: &[Stored]) -> Vec<Stored> {
        if self.failure.is_some() {
            return Vec::new();
        }
        self.file.append(added).unwrap_or_else(|e| {
            self.failure = Some(e);
            Vec::new()
        })
    }
}
