//! The irradiance cache in participating media, stage 1 (NOTES-002 §2.8): records on surfaces,
//! placed and interpolated as Ward's (002 §7: "the resulting cache point locations are kept
//! exactly the same"), each gathered through the media with [`super::gradient`] and carrying E =
//! E_s + E_m, the 002 translational gradient of the chosen form and the rotational gradient of
//! the total cell radiance. A record's gather marches its first bounce: surfaces lit by direct
//! light with transmittance, the media's single scattering of the lights and their emission;
//! deeper bounces (`max_depth` above 3) are the volumetric records' light along the gather ray
//! and `volpath` paths per gather ray on from its opaque hit ([`SceneMedium::with_deeper_bounces`],
//! [`SceneMedium::with_volume_records`]). The `ic` integrator in a media scene is
//! therefore `volpath` at `max_depth` whose first surface vertex takes its Lambertian indirect
//! light from here.
//!
//! Records use the error metric asked for, Tabellion's (the default: half the nearest opaque hit
//! within `--footprint-limits` pixel footprints, which a camera ray keeps through null boundaries
//! and media) or Ward's; the Hessian metric's reprojection has no transmittance (NOTES-002
//! §2.8), so Ward's stands in for it and [`METRIC_NOTE`] says so.
//!
//! Records are made in a pre-pass over the image's pixel centres, one row at a time: the row's
//! uncovered first hits are gathered in parallel and inserted in row order, so the cache is the
//! same at any thread count.

use super::gradient::{gather, March, MediaGradient};
use super::scene_medium::SceneMedium;
use super::volume_records::VolumeCache;
use crate::integrators::RayCounts;
use crate::irradiance_cache::gather::ShadingPoint;
use crate::irradiance_cache::hemisphere::{to_world, Stratification};
use crate::irradiance_cache::record::{
    limit_radius_by_gradient, pixel_footprint, tabellion_radius, ErrorMetric, GradientMode, Record,
    NO_RADIANCE,
};
use crate::irradiance_cache::store::RecordStore;
use crate::irradiance_cache::IcParams;
use crate::media::tracking::{first_opaque, medium_after};
use crate::photon_map::ServingMap;
use crate::scene::Scene;
use ircache_math::{offset_ray_origin, Frame, Rgb, Rng, Vec3};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// What building the cache did.
#[derive(Clone, Debug, Default)]
pub struct MediaCacheStats {
    /// Records made.
    pub records: usize,
    /// Of them, at each level ([`MediaCache`]).
    pub per_level: Vec<usize>,
    /// Records read from a cache file before the pre-pass.
    pub loaded: usize,
    /// What a user should hear of the cache file
    /// ([`crate::irradiance_cache::file::Contents::notes`]).
    pub notes: Vec<String>,
    /// Gather rays (to the first opaque hit, through null boundaries).
    pub gather_rays: u64,
    /// Shadow rays of the gathers (surface hits' direct light, single scattering).
    pub shadow_rays: u64,
    /// March steps in all gathers.
    pub march_steps: u64,
    /// Seconds of the pre-pass.
    pub seconds: f64,
    /// Ward's metric was used in place of the one asked for ([`METRIC_NOTE`]).
    pub metric_replaced: bool,
    /// The caustic map beside the records, if one was made.
    pub caustic_map: Option<crate::photon_map::MapSummary>,
    /// The global map beside the records, if one was made.
    pub global_map: Option<crate::photon_map::MapSummary>,
}

/// Records in media scenes, by level: level d serves surface vertices at depth d, each record
/// holding the bounces a path may still take there (`bounces − d`). Level 0 serves the camera
/// rays' first surfaces; deeper levels those a camera path reaches through surfaces without a
/// Lambertian part (glass, mirrors, metals), one level deeper at each.
#[derive(Debug)]
pub struct MediaCache {
    levels: Vec<RecordStore<Record>>,
    /// Of each level's records, how many came from a cache file (they come first).
    loaded: Vec<usize>,
    /// Interpolation mode.
    mode: GradientMode,
    /// What building it did.
    pub stats: MediaCacheStats,
}

/// What a user should hear of when the Hessian metric was asked for.
pub const METRIC_NOTE: &str =
    "in media the records use Ward's split-sphere metric in place of the Hessian one (its reprojection does not see media)";

/// The error metric records in media use: Tabellion's or Ward's as asked, Ward's for the
/// Hessian's (NOTES-002 §2.8: its reprojection has no transmittance).
#[must_use]
pub fn media_metric(asked: ErrorMetric) -> ErrorMetric {
    match asked {
        ErrorMetric::Tabellion => ErrorMetric::Tabellion,
        ErrorMetric::Ward | ErrorMetric::Hessian => ErrorMetric::Ward,
    }
}

/// A refusal of something the cache in media does not do, naming it (`what`).
#[must_use]
pub fn unavailable(what: &str) -> String {
    format!(
        "in scenes with participating media the irradiance cache keeps Ward's records of the \
         first bounce (issue 15): {what}"
    )
}

/// The irradiance cache's settings that records in media do not read (their gathers take
/// `--media-divisions` rays, without super-samples, re-gathers, radiance records or photon
/// records): given other than their defaults, they are refused rather than ignored.
const UNUSED_IN_MEDIA: [&str; 12] = [
    "divisions",
    "record_source",
    "supersamples",
    "record_error",
    "regather_at",
    "gradient_formula",
    "overture",
    "record_order",
    "radiance_order",
    "radiance_accuracy",
    "cached_environment",
    "photon_records",
];

/// Refuses by name the cache's settings that records in media do not take yet (`auto` photon
/// maps and radiance caching make none there), and those they do not read.
pub fn available(params: &IcParams) -> Result<(), String> {
    use crate::irradiance_cache::params::{Deeper, RadianceCaching};
    let unused = params.given_among(&UNUSED_IN_MEDIA);
    if !unused.is_empty() {
        return Err(unavailable(&format!(
            "{} not used there (a record's gather takes --media-divisions rays)",
            IcParams::named(&unused)
        )));
    }
    let what = if params.bounces > 1 && params.deeper == Deeper::Cache {
        "a cache per bounce (--deeper-bounces cache) is not available there: give --deeper-bounces traced"
    } else if params.radiance_cache == RadianceCaching::On {
        "radiance caching is not available there yet"
    } else if params.uses_ambient() {
        "an ambient value (-av, -aw) is not available there: the deeper bounces are traced"
    } else {
        return Ok(());
    };
    Err(unavailable(what))
}

/// What a record's gather takes from elsewhere instead of tracing it.
#[derive(Clone, Copy, Debug, Default)]
pub struct RecordSources<'a> {
    /// The caustic map: the receiver's caustics are the map's, left out of the gather, and the
    /// deeper paths take those of their own Lambertian vertices from it.
    pub caustics: Option<&'a Arc<ServingMap>>,
    /// The global map: the light the deeper bounces bring to a gather ray's diffuse opaque hit
    /// ([`SceneMedium::with_deeper_bounces`]).
    pub global: Option<&'a Arc<ServingMap>>,
    /// The volumetric records: the light the deeper bounces scatter along the gather rays
    /// ([`SceneMedium::with_volume_records`]).
    pub volume: Option<&'a Arc<VolumeCache>>,
}

/// Where a record is wanted: a surface point, the normal of the side it serves, the medium on
/// that side.
#[derive(Clone, Copy, Debug)]
pub struct RecordSite {
    /// Position.
    pub p: Vec3,
    /// Geometric normal (for the ray offset).
    pub ng: Vec3,
    /// Shading normal on the served side.
    pub n: Vec3,
    /// The medium on that side.
    pub medium: Option<usize>,
    /// The pixel's footprint there for a site the camera sees (bounds Tabellion's radii), else 0.
    pub footprint: f32,
}

/// The key of a record's layout stream (beyond every cell's index).
const LAYOUT_KEY: u64 = u64::MAX;

/// Gathers a record at `site` (deterministic for a given `key`), with the rays it traced,
/// taking from `sources` what they serve ([`RecordSources`]).
#[must_use]
pub fn make_record(
    scene: &Scene,
    params: &IcParams,
    site: &RecordSite,
    key: u64,
    sources: RecordSources,
) -> (Record, MediaCacheStats) {
    make_record_at(scene, params, site, key, sources, 0)
}

/// [`make_record`] for a surface vertex at `depth`: the bounces a path may still take there.
fn make_record_at(
    scene: &Scene,
    params: &IcParams,
    site: &RecordSite,
    key: u64,
    sources: RecordSources,
    depth: u32,
) -> (Record, MediaCacheStats) {
    let bounces = if params.bounces == crate::irradiance_cache::params::UNBOUNDED {
        params.bounces
    } else {
        params.bounces.saturating_sub(depth)
    };
    let level = u8::try_from(depth).unwrap_or(u8::MAX);
    let strata = Stratification::from_divisions(params.media_divisions);
    let frame = Frame::from_z(site.n);
    let origin = offset_ray_origin(site.p, site.ng, site.n, scene.scale);
    // Ward–Heckbert's walls need no per-cell gradients.
    let gradients = params.media_gradient != MediaGradient::None;
    let view = SceneMedium::new(scene, site.medium, false, params.media_light_samples)
        .with_tangents([frame.s.as_dvec3(), frame.t.as_dvec3()])
        .with_gradients(gradients)
        .with_deeper_bounces(
            bounces,
            params.media_deeper_paths,
            sources.caustics,
            sources.global,
        )
        .with_volume_records(sources.volume);
    let d = |v: Vec3| v.as_dvec3();
    let n = strata.azimuthal;
    let layout = params
        .gather_pattern
        .layout(strata, &mut Rng::keyed(key, &[LAYOUT_KEY]));
    let g = gather(
        &view,
        d(origin),
        [d(frame.s), d(frame.t), d(frame.n)],
        strata,
        &March {
            gradients,
            ..March::default()
        },
        |j, k| layout.jitter(j, k, Rng::keyed(key, &[(j * n + k) as u64]).next_2d()),
    );
    let total = g.total_irradiance();
    let e = Rgb::new(total[0] as f32, total[1] as f32, total[2] as f32);
    let samples = g.hemisphere_samples();
    let mut grad_t = to_world(
        &g.gradient_parts().total(params.media_gradient),
        frame.s,
        frame.t,
    );
    let grad_r = to_world(&samples.rotational_gradient(), frame.s, frame.t);
    // Radii as the irradiance cache's (000 eq. 3.60 for Tabellion's: half the nearest opaque
    // hit within `--footprint-limits` pixel footprints); Ward's harmonic mean otherwise.
    let limits = params.radius_limits(2.0 * scene.radius);
    let (r, (r_min, r_max)) = if params.error_metric == ErrorMetric::Tabellion {
        let footprint = (site.footprint > 0.0).then_some(site.footprint);
        tabellion_radius(
            &samples.distance,
            limits,
            footprint,
            params.footprint_limits,
        )
    } else {
        (samples.harmonic_mean_distance(), limits)
    };
    let r = limit_radius_by_gradient(
        e,
        &mut grad_t,
        r.min(r_max),
        r_min,
        media_metric(params.error_metric).gradient_limit_scale(params.accuracy),
    );
    let rays: RayCounts = view.rays();
    let stats = MediaCacheStats {
        records: 1,
        gather_rays: rays.gather,
        shadow_rays: rays.shadow,
        march_steps: g.march_steps as u64,
        ..MediaCacheStats::default()
    };
    let record = Record {
        p: site.p,
        n: site.n,
        e,
        r,
        grad_t,
        grad_r,
        level,
        ray_variance: 0.0,
        radiance: NO_RADIANCE,
    };
    (record, stats)
}

/// The first opaque surface a camera ray finds (through null boundaries), as a record site, if
/// its BSDF has a Lambertian part seen from the ray's side (the part the cache serves).
#[must_use]
pub fn first_site(scene: &Scene, ray: ircache_math::Ray) -> Option<RecordSite> {
    site_at_depth(scene, ray, 0, 0)
}

/// Most levels of records ([`MediaCache`]): the first surface and two deeper (a glass sphere's
/// two refractions, or a metal's reflection).
pub const MAX_LEVELS: u32 = 3;

/// The surface a camera ray's path reaches at depth `depth` through surfaces without a
/// Lambertian part, each passed along a sample of its BSDF drawn from `key` (none at depth 0:
/// the first opaque surface), as a record site, if it has a Lambertian part seen from the
/// path's side; `None` where the path meets such a part sooner, meets an emitter, a window pane
/// or a mask past the first surface, or meets nothing.
#[must_use]
pub fn site_at_depth(
    scene: &Scene,
    mut ray: ircache_math::Ray,
    depth: u32,
    key: u64,
) -> Option<RecordSite> {
    let mut medium = scene.camera_medium;
    let mut rng = Rng::keyed(key, &[SITE_KEY]);
    for d in 0..=depth {
        let hit = first_opaque(scene, ray, medium, &mut 0, |_, _, _| {})?;
        let it = hit.it;
        let shape = &scene.shapes[it.shape as usize];
        // Past lobe samples, an emitter, a pane or a mask ends the path (the first surface may
        // be any).
        if depth > 0 && (shape.area_light.is_some() || shape.thin_sheet || shape.masked) {
            return None;
        }
        let bsdf = it.bsdf(&scene.materials[shape.material], ray.d);
        let wo = it.frame.to_local(-ray.d);
        if !bsdf.lambertian_albedo(wo).is_black() {
            if d < depth {
                return None;
            }
            let n = ShadingPoint::facing(it, -ray.d).n;
            return Some(RecordSite {
                p: it.p,
                ng: it.ng,
                n,
                medium: medium_after(shape.media, it.ng, n, hit.medium),
                footprint: 0.0,
            });
        }
        if d == depth {
            return None;
        }
        let bs = bsdf.sample(wo, rng.next_f32(), rng.next_2d())?;
        let wi = it.frame.from_local(bs.wi);
        medium = medium_after(shape.media, it.ng, wi, hit.medium);
        ray = scene.spawn_ray(&it, wi);
    }
    None
}

/// The key of a deeper site's lobe samples.
const SITE_KEY: u64 = 0x7369_7465;

impl MediaCache {
    /// An empty cache, with a level for each depth that has a bounce left, at most
    /// [`MAX_LEVELS`].
    #[must_use]
    pub fn new(scene: &Scene, params: &IcParams) -> MediaCache {
        let (r_min, _) = params.radius_limits(2.0 * scene.radius);
        let min_validity = (params.accuracy * r_min).max(scene.radius * 1e-4);
        let levels = params.bounces.clamp(1, MAX_LEVELS) as usize;
        MediaCache {
            levels: (0..levels)
                .map(|_| {
                    RecordStore::new(
                        min_validity,
                        params.accuracy,
                        media_metric(params.error_metric),
                        params.neighbour_clamp,
                    )
                })
                .collect(),
            loaded: vec![0; levels],
            mode: params.gradients,
            stats: MediaCacheStats {
                per_level: vec![0; levels],
                ..MediaCacheStats::default()
            },
        }
    }

    /// Fills the cache from the camera paths through the centres of a `width` × `height` image
    /// (run inside a rayon pool), level by level, after the records `loaded` (from a cache
    /// file); their gathers take from `sources` what they serve.
    #[must_use]
    pub fn build(
        scene: &Scene,
        params: &IcParams,
        (width, height): (usize, usize),
        seed: u64,
        loaded: Vec<Record>,
        sources: RecordSources,
    ) -> MediaCache {
        let start = Instant::now();
        let mut cache = MediaCache::new(scene, params);
        cache.stats.loaded = loaded.len();
        for record in loaded {
            let level = usize::from(record.level);
            if let Some(store) = cache.levels.get_mut(level) {
                store.insert(record);
                cache.loaded[level] += 1;
            }
        }
        let pixel_spread = scene.camera.pixel_spread(width);
        // Sites of one row closer than this (and facing alike) share a record.
        let spacing = params
            .radius_limits(2.0 * scene.radius)
            .0
            .max(scene.radius * 1e-3)
            * params.accuracy;
        for level in 0..cache.levels.len() {
            for y in 0..height {
                // The row's sites that no record covers yet, thinned against each other by the
                // smallest record spacing.
                let mut wanted: Vec<(u64, RecordSite)> = Vec::new();
                for x in 0..width {
                    let film = ircache_math::Vec2::new(
                        (x as f32 + 0.5) / width as f32,
                        (y as f32 + 0.5) / height as f32,
                    );
                    let ray = scene.camera.generate_ray(film);
                    let pixel = (y * width + x) as u64;
                    let key = ircache_math::rng::mix64(
                        seed ^ pixel.wrapping_mul(0x9E37_79B9_7F4A_7C15)
                            ^ (level as u64).wrapping_mul(0xD1B5_4A32_D192_ED03),
                    );
                    let site = if level == 0 {
                        first_site(scene, ray).map(|mut site| {
                            // The pixel's footprint at the site (000 eq. 3.60): the camera ray
                            // is straight through null boundaries and media.
                            site.footprint = pixel_footprint(
                                pixel_spread,
                                (site.p - ray.o).length(),
                                site.n.dot(ray.d).abs(),
                            );
                            site
                        })
                    } else {
                        site_at_depth(scene, ray, level as u32, key)
                    };
                    let Some(site) = site else {
                        continue;
                    };
                    if cache.levels[level].covers(site.p, site.n) {
                        continue;
                    }
                    if wanted
                        .iter()
                        .any(|(_, w)| (w.p - site.p).length() < spacing && w.n.dot(site.n) > 0.9)
                    {
                        continue;
                    }
                    wanted.push((key, site));
                }
                let made: Vec<(Record, MediaCacheStats)> = wanted
                    .par_iter()
                    .map(|(key, site)| {
                        make_record_at(scene, params, site, *key, sources, level as u32)
                    })
                    .collect();
                for (record, st) in made {
                    // A record an earlier one of this row already covers is dropped (the row
                    // was chosen before any of its records existed).
                    if cache.levels[level].covers(record.p, record.n) {
                        continue;
                    }
                    cache.levels[level].insert(record);
                    cache.stats.records += 1;
                    cache.stats.per_level[level] += 1;
                    cache.stats.gather_rays += st.gather_rays;
                    cache.stats.shadow_rays += st.shadow_rays;
                    cache.stats.march_steps += st.march_steps;
                }
            }
        }
        cache.stats.seconds = start.elapsed().as_secs_f64();
        cache.stats.metric_replaced = params.error_metric == ErrorMetric::Hessian;
        cache
    }

    /// Interpolated irradiance at `p` with normal `n` (bump-mapped `n_rot`) for a surface
    /// vertex at `depth`, relaxing the accuracy up to twice where no record reaches at once;
    /// `None` where none does.
    #[must_use]
    pub fn irradiance(&self, depth: u32, p: Vec3, n: Vec3, n_rot: Vec3) -> Option<Rgb> {
        let level = self.levels.get(depth as usize)?;
        [1.0, 2.0]
            .into_iter()
            .find_map(|threshold| level.interpolate(p, n, n_rot, threshold, self.mode))
            .map(|i| i.e)
    }

    /// The records of the camera rays' first surfaces (level 0).
    #[must_use]
    pub fn records(&self) -> &[Record] {
        self.levels[0].records()
    }

    /// The records made by [`Self::build`], level by level.
    pub fn made(&self) -> impl Iterator<Item = &Record> {
        self.levels
            .iter()
            .zip(&self.loaded)
            .flat_map(|(store, &loaded)| &store.records()[loaded..])
    }
}
