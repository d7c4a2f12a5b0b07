//! Filling the cache in parallel and deterministically.
//!
//! Record positions are decided in a fixed order by a coarse-to-fine pre-pass: the image is
//! visited on grids of pixel centres with strides 32, 16, ..., 1; each stride is split into
//! phases whose points are at least two strides and [`BATCH_SPACING`] pixels apart. A phase is
//! one batch: every point it holds is checked against the cache as it stood before the batch,
//! the uncovered ones gather their records in parallel (deeper levels go to private overlays),
//! and then the new records are inserted one after the other in pixel order (one that a record
//! inserted before it in the same batch already covers is kept, and counted as overlapping).
//! Nothing is locked on the hot path (the cache is read-only during a batch), tiles do not exist
//! here so no border duplicates, and the result depends only on the seed.

use super::file::Stored;
use super::gather::{
    mix, GatherCounts, Gatherer, IrradianceCache, NextEstimate, NextFrameEstimator, SceneRadiance,
    ShadingPoint, WorkState,
};
use super::params::RecordSource;
use super::plane::PlaneMeasure;
use super::record::{Record, NO_RADIANCE};
use crate::radiance_cache::RadianceCache;
use crate::scene::Scene;
use ircache_math::{Ray, Vec2, Vec3};
use rayon::prelude::*;
use std::time::Instant;

/// What filling the cache did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CacheStats {
    /// Records in each level's store at the end.
    pub records_per_level: Vec<usize>,
    /// Records gathered.
    pub records_computed: u64,
    /// Records that an earlier record of the same batch already covered when they were
    /// inserted (Ward's sequential algorithm would not have made them; they are kept, as their
    /// gather is paid for and they lower the interpolation's noise).
    pub records_overlapping: u64,
    /// Gather (hemisphere) rays traced.
    pub gather_rays: u64,
    /// Shadow rays traced for surfaces that gather rays found.
    pub shadow_rays: u64,
    /// Seconds spent filling the cache.
    pub gather_seconds: f64,
    /// Batches run.
    pub batches: u32,
    /// Records read from a cache file before the pre-pass.
    pub records_loaded: u64,
    /// Records other processes sharing the cache file made during the pre-pass.
    pub records_from_others: u64,
    /// Hemisphere cells adaptive super-sampling refined (three more rays each).
    pub supersampled_cells: u64,
    /// What a user should hear of (a cache file made for another view, damaged records).
    pub notes: Vec<String>,
    /// Records gathered again with more rays because their neighbourhood was noisy.
    pub records_regathered: u64,
    /// Records that also hold their incoming radiance in HSH (`--radiance-cache auto|on`).
    pub radiance_records: usize,
    /// Seconds spent making radiance caching's tables (BRDFs in HSH, tilt matrices).
    pub radiance_table_seconds: f64,
    /// Records made from photons before the pre-pass (`--photon-records on`).
    pub photon_records: u64,
    /// Seconds spent making them.
    pub photon_record_seconds: f64,
}

/// Where and how the pre-pass gathered a record it made: enough to gather it again with the
/// same random numbers (temporal caching estimates a record's next frame that way).
#[derive(Clone, Copy, Debug)]
pub struct Site {
    /// Index in its level's store.
    pub index: usize,
    /// The point it was gathered at.
    pub point: ShadingPoint,
    /// The gather's key.
    pub key: u64,
    /// Rays of a re-gather ([`regather_noisy`]); 0 for the cache's own divisions
    /// ([`Gatherer::record_at`]).
    pub rays: usize,
}

/// The records the pre-pass made, per level, and with a [`NextFrameEstimator`] their next-frame
/// estimates. Records read from a file or made by other processes have none.
#[derive(Clone, Debug, Default)]
pub struct Sites {
    /// Per level, the sites in the order the records were made.
    pub levels: Vec<Vec<Site>>,
    /// Per level, each site's next-frame estimate (`None` for records the gatherer's paths
    /// made at deeper levels, or without an estimator).
    pub estimates: Vec<Vec<Option<NextEstimate>>>,
}

impl Sites {
    fn add(
        &mut self,
        level: usize,
        index: usize,
        point: ShadingPoint,
        key: u64,
        estimate: Option<NextEstimate>,
    ) {
        if self.levels.len() <= level {
            self.levels.resize(level + 1, Vec::new());
            self.estimates.resize(level + 1, Vec::new());
        }
        self.levels[level].push(Site {
            index,
            point,
            key,
            rays: 0,
        });
        self.estimates[level].push(estimate);
    }
}

impl CacheStats {
    /// Records in the cache.
    #[must_use]
    pub fn records(&self) -> usize {
        self.records_per_level.iter().sum()
    }
}

/// Most record sites one camera ray yields.
const MAX_SITES: usize = 8;

/// The surfaces a camera ray reaches whose Lambertian part the cache serves, each with its depth
/// (the cache level the pixel pass looks up there): the first surface; through mirrors and glass
/// every lobe (reflection and refraction); and one central direction of each glossy lobe; down to
/// depth `levels` − 1. The pre-pass places records at these points, so that the pixel pass, which
/// follows the same paths, finds them. With `radiance` tables, surfaces whose glossy lobe is
/// radiance-cached are sites too, and paths end there as the pixel pass's do.
#[must_use]
pub fn record_sites(
    scene: &Scene,
    ray: &Ray,
    levels: u32,
    radiance: Option<&RadianceCache>,
) -> Vec<(u32, ShadingPoint)> {
    let mut sites = Vec::new();
    // Depth-first, reflection before refraction: a fixed order, so the same sites every time.
    let mut stack = vec![(*ray, 0u32, 0.0f32)];
    while let Some((ray, depth, travelled)) = stack.pop() {
        if depth >= levels || sites.len() >= MAX_SITES {
            continue;
        }
        let Some(it) = scene.intersect(&ray) else {
            continue;
        };
        let bsdf = it.bsdf(
            &scene.materials[scene.shapes[it.shape as usize].material],
            ray.d,
        );
        let wo = -ray.d;
        let wo_local = it.frame.to_local(wo);
        let travelled = travelled + it.t;
        let mut sp = ShadingPoint::facing(it, wo);
        sp.travelled = travelled;
        let glossy_cached = radiance.is_some_and(|r| r.brdf_at(&sp).is_some());
        if is_record_site(&bsdf, wo_local, glossy_cached) {
            sites.push((depth, sp));
        }
        if depth + 1 >= levels || !bsdf.has_glossy() || glossy_cached {
            continue;
        }
        // Delta lobes: each one (u_lobe picks reflection or transmission); glossy lobes: the
        // sample at the centre of the unit square.
        let mut next: Vec<Vec3> = Vec::with_capacity(2);
        for u_lobe in [0.999, 0.0] {
            if let Some(bs) = bsdf.sample_glossy(wo_local, u_lobe, Vec2::splat(0.5)) {
                let d = it.frame.from_local(bs.wi);
                if !next.iter().any(|n| n.dot(d) > 0.9999) {
                    next.push(d);
                }
            }
        }
        for d in next {
            stack.push((scene.spawn_ray(&it, d), depth + 1, travelled));
        }
    }
    sites
}

/// Whether records serve a surface with BSDF `bsdf` seen from the local direction `wo_local`:
/// its smooth part has a Lambertian part, or a glossy lobe that radiance caching serves
/// (`glossy_cached`).
#[must_use]
pub fn is_record_site(bsdf: &crate::bsdf::Bsdf, wo_local: Vec3, glossy_cached: bool) -> bool {
    bsdf.has_smooth() && (glossy_cached || !bsdf.lambertian_albedo(wo_local).is_black())
}

/// The first record site of a camera ray (see [`record_sites`]).
#[must_use]
pub fn first_diffuse_point(scene: &Scene, ray: &Ray, levels: u32) -> Option<ShadingPoint> {
    record_sites(scene, ray, levels, None)
        .into_iter()
        .min_by_key(|(depth, _)| *depth)
        .map(|(_, sp)| sp)
}

/// Hooks around each batch of the pre-pass; a cache file shared with other processes uses them
/// to bring in their records and hand out this process's.
pub trait BatchHook {
    /// Before a batch: records made elsewhere, to add to the cache.
    fn before(&mut self) -> Vec<Stored> {
        Vec::new()
    }
    /// After a batch, with the records it added (in order): more records made elsewhere.
    fn after(&mut self, added: &[Stored]) -> Vec<Stored> {
        let _ = added;
        Vec::new()
    }
}

impl BatchHook for () {}

/// Adds records made elsewhere to their levels' stores.
fn take_in(cache: &mut IrradianceCache, records: Vec<Stored>, stats: &mut CacheStats) {
    for stored in records {
        if cache.insert_stored(stored) {
            stats.records_from_others += 1;
        }
    }
}

/// Runs one batch: `points[i] = (key, level, point)`; hands the new records to `hook` and
/// notes where each was gathered in `sites`, with its next-frame estimate where `next` makes
/// them.
#[allow(clippy::too_many_arguments)]
pub fn run_batch(
    scene: &Scene,
    cache: &mut IrradianceCache,
    seed: u64,
    points: &[(u64, u32, ShadingPoint)],
    stats: &mut CacheStats,
    sites: &mut Sites,
    hook: &mut (dyn BatchHook + Send),
    next: Option<&dyn NextFrameEstimator>,
) {
    take_in(cache, hook.before(), stats);
    // With `--record-source gpu-plane`, the first level's planes of the batch at once.
    let planes = gpu_planes(cache, points, stats);
    // Per point: the record gathered there (with its point and key) and its work state.
    type Gathered = Option<((Record, ShadingPoint, u64), WorkState)>;
    let results: Vec<Gathered> = {
        let light = SceneRadiance {
            scene,
            deeper: cache.params.deeper,
        };
        let g = Gatherer {
            light: &light,
            cache,
            seed,
            next,
        };
        // Small pieces: the points that need records cluster (edges, corners), and rayon
        // cannot steal from inside a piece a thread has started.
        points
            .par_iter()
            .with_max_len(4)
            .enumerate()
            .map(|(i, &(key, level, ref sp))| {
                let mut st = WorkState::new(cache.levels.len());
                let rec = match planes.as_ref().and_then(|p| p[i]) {
                    Some(Some(m)) => g.record_from_plane(&mut st, sp, level, &m),
                    Some(None) => return None,
                    None => {
                        let threshold = cache.coverage_threshold(sp);
                        if cache.levels[level as usize].covers_within(sp.it.p, sp.n, threshold) {
                            return None;
                        }
                        g.record_at(&mut st, sp, level, key)
                    }
                };
                Some(((rec, *sp, key), st))
            })
            .collect()
    };
    let mut counts = GatherCounts::default();
    let mut added = Vec::new();
    for (rec, mut st) in results.into_iter().flatten() {
        counts.add(&st.counts);
        let mut radiance = std::mem::take(&mut st.radiance);
        let deeper = st.new_records.len();
        let mut estimate = st.estimates.pop();
        // Deeper records first: they were made for the level-0 record's gather.
        for (i, (mut r, sp, key)) in st
            .new_records
            .into_iter()
            .chain(std::iter::once(rec))
            .enumerate()
        {
            cache.adopt_radiance(&mut r, &mut radiance, NO_RADIANCE);
            let store = &mut cache.levels[r.level as usize];
            if store.covers(r.p, r.n) {
                stats.records_overlapping += 1;
            }
            let estimate = if i == deeper { estimate.take() } else { None };
            sites.add(r.level as usize, store.len(), sp, key, estimate);
            store.insert(r);
            added.push(cache.stored(&r));
        }
    }
    stats.records_computed += counts.records;
    stats.supersampled_cells += counts.supersampled_cells;
    stats.gather_rays += counts.gather_rays;
    stats.shadow_rays += counts.shadow_rays;
    stats.batches += 1;
    let others = hook.after(&added);
    take_in(cache, others, stats);
    cache.update_ambient();
}

/// With `--record-source gpu-plane` and a source attached: per point of the batch at the first
/// level, `Some` of the plane made on the GPU (all in one call) where it needs a record, of
/// `None` where one covers it; `None` for the deeper levels' points, which gather. `None`
/// altogether otherwise, or where the GPU failed (a note says so; the points then take records
/// one at a time, ray cast on the CPU where the GPU fails again).
#[allow(clippy::option_option)]
fn gpu_planes(
    cache: &IrradianceCache,
    points: &[(u64, u32, ShadingPoint)],
    stats: &mut CacheStats,
) -> Option<Vec<Option<Option<PlaneMeasure>>>> {
    let source = cache.plane_source.as_ref()?;
    if cache.params.record_source != RecordSource::GpuPlane {
        return None;
    }
    let needed: Vec<bool> = points
        .par_iter()
        .map(|&(_, level, ref sp)| {
            let threshold = cache.coverage_threshold(sp);
            level == 0 && !cache.levels[0].covers_within(sp.it.p, sp.n, threshold)
        })
        .collect();
    let wanted: Vec<ShadingPoint> = points
        .iter()
        .zip(&needed)
        .filter(|(_, &n)| n)
        .map(|((_, _, sp), _)| *sp)
        .collect();
    match source.measure(&wanted) {
        Ok(measures) => {
            let mut m = measures.into_iter();
            Some(
                points
                    .iter()
                    .zip(&needed)
                    .map(|(&(_, level, _), &n)| {
                        (level == 0).then(|| if n { m.next() } else { None })
                    })
                    .collect(),
            )
        }
        Err(e) => {
            if stats.notes.len() < 8 {
                stats
                    .notes
                    .push(format!("the GPU's record planes failed ({e})"));
            }
            None
        }
    }
}

/// Fewest pixels between two points of one batch on the finer strides. A batch's records are
/// gathered before any of them is in the cache, so two points closer than a record's reach both
/// get one where Ward's sequential order would make one; at two strides apart (2 px on stride 1)
/// a quarter of Sponza's records overlapped another of their batch, nearly all on strides 1 and
/// 2. Eight pixels leave 5 % and still give each batch tens of records to gather in parallel
/// (BENCHMARKS.md, 2026-12-04).
pub const BATCH_SPACING: usize = 8;

/// One batch of a stride's points: the pixels whose grid coordinates (x/stride, y/stride)
/// leave `residue` modulo `modulus`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Phase {
    /// The grid period, in strides (1 on the coarsest stride: every point).
    pub modulus: usize,
    /// The grid coordinates' residues.
    pub residue: (usize, usize),
}

impl Phase {
    /// Whether the pixel (x, y) of `stride`'s grid belongs to this phase.
    #[must_use]
    pub fn holds(&self, x: usize, y: usize, stride: usize) -> bool {
        (x / stride) % self.modulus == self.residue.0
            && (y / stride) % self.modulus == self.residue.1
    }
}

/// The phases of a stride of the coarse-to-fine search: on the coarsest stride one, every
/// point of the grid; below it the points not on the coarser grid (grid coordinates not both
/// even), split so that each batch's points are at least two strides and [`BATCH_SPACING`]
/// pixels apart: by their coordinates modulo m = max(2, BATCH_SPACING / stride), the odd–odd
/// residues first, then odd–even, then even–odd (with m = 2 the three phases (1, 1), (1, 0),
/// (0, 1)).
#[must_use]
pub fn phases(stride: usize, coarsest: bool) -> Vec<Phase> {
    if coarsest {
        return vec![Phase {
            modulus: 1,
            residue: (0, 0),
        }];
    }
    let modulus = (BATCH_SPACING / stride.max(1)).max(2).next_power_of_two();
    let mut out = Vec::with_capacity(3 * modulus * modulus / 4);
    for parity in [(1, 1), (1, 0), (0, 1)] {
        for a in (parity.0..modulus).step_by(2) {
            for b in (parity.1..modulus).step_by(2) {
                out.push(Phase {
                    modulus,
                    residue: (a, b),
                });
            }
        }
    }
    out
}

/// The pixels of phase `phase` (see [`phases`]) of `stride` on a `width`×`height` image, row by
/// row.
pub fn phase_pixels(
    width: usize,
    height: usize,
    stride: usize,
    phase: Phase,
) -> impl Iterator<Item = (usize, usize)> {
    (0..height)
        .step_by(stride)
        .flat_map(move |y| (0..width).step_by(stride).map(move |x| (x, y)))
        .filter(move |&(x, y)| phase.holds(x, y, stride))
}

/// Fills `cache` for a `width`×`height` view of `scene` (run inside the caller's thread pool);
/// says where and how each new record was gathered, and with `next` estimates each one's
/// next frame.
#[allow(clippy::too_many_arguments)]
pub fn fill_for_image(
    scene: &Scene,
    cache: &mut IrradianceCache,
    width: usize,
    height: usize,
    rows: std::ops::Range<usize>,
    seed: u64,
    hook: &mut (dyn BatchHook + Send),
    next: Option<&dyn NextFrameEstimator>,
) -> (CacheStats, Sites) {
    let start = Instant::now();
    let mut stats = CacheStats::default();
    let coarsest = 32usize;
    let mut stride = coarsest;
    let inv = Vec2::new(1.0 / width as f32, 1.0 / height as f32);
    let finest = cache.params.overture.finest_stride();
    let mut sites = Sites::default();
    while stride >= finest.max(1) && finest > 0 {
        for phase in phases(stride, stride == coarsest) {
            let pixels: Vec<(usize, usize)> = phase_pixels(width, height, stride, phase)
                .filter(|(_, y)| rows.contains(y))
                .collect();
            let levels = cache.levels.len() as u32;
            let points: Vec<(u64, u32, ShadingPoint)> = pixels
                .par_iter()
                .flat_map_iter(|&(x, y)| {
                    let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) * inv;
                    let ray = scene.camera.generate_ray(film);
                    let key = mix(0x0070_7265_7061_7373, (y * width + x) as u64);
                    record_sites(scene, &ray, levels, cache.radiance.as_deref())
                        .into_iter()
                        .enumerate()
                        .filter(|(_, (_, sp))| !cache.is_excluded(sp.it.shape))
                        .map(move |(i, (level, sp))| (mix(key, i as u64), level, sp))
                })
                .collect();
            run_batch(
                scene, cache, seed, &points, &mut stats, &mut sites, hook, next,
            );
        }
        stride /= 2;
    }
    regather_noisy(scene, cache, seed, &mut sites, &mut stats, next);
    stats.records_per_level = cache.levels.iter().map(|s| s.len()).collect();
    stats.gather_seconds = start.elapsed().as_secs_f64();
    (stats, sites)
}

/// Fills `cache` for a list of query points, coarse to fine over their order (every 64th
/// point first, then every 32nd, ...), so that nearby points share records.
pub fn fill_for_points(
    scene: &Scene,
    cache: &mut IrradianceCache,
    points: &[ShadingPoint],
    seed: u64,
) -> CacheStats {
    let start = Instant::now();
    let mut stats = CacheStats::default();
    let mut sites = Sites::default();
    let mut stride = 64usize;
    while stride >= 1 {
        let batch: Vec<(u64, u32, ShadingPoint)> = points
            .iter()
            .enumerate()
            .filter(|(i, _)| i % stride == 0 && (stride == 64 || i % (2 * stride) != 0))
            .map(|(i, sp)| (mix(0x706f_696e_7473, i as u64), 0, *sp))
            .collect();
        run_batch(
            scene,
            cache,
            seed,
            &batch,
            &mut stats,
            &mut sites,
            &mut (),
            None,
        );
        stride /= 2;
    }
    regather_noisy(scene, cache, seed, &mut sites, &mut stats, None);
    stats.records_per_level = cache.levels.iter().map(|s| s.len()).collect();
    stats.gather_seconds = start.elapsed().as_secs_f64();
    stats
}

/// Gathers again, with more rays, the records whose neighbourhood is noisy: where a small bright
/// patch is seen from afar, a gather of the base divisions catches it in a ray or none, and
/// interpolation turns that noise into blotches. A record's need is judged from its
/// *neighbours'* own estimates of their noise ([`Record::ray_variance`], the records serving
/// its position within twice their reach), never from its own samples: the record's value is
/// then either its first gather or an independent new one, chosen independently of both, so it
/// stays unbiased (choosing by a record's own value would bias it, as re-sampling only the
/// cells that look bright does). The new gather has the rays that bring the worst neighbour's
/// relative error to `record_error × accuracy`, at most `divisions + supersamples`; it is
/// done when that is at least `regather_at` times the divisions (16: a neighbour's error four
/// times the target; off by default, see [`super::params::IcParams::regather_at`]). Records made
/// by other processes or read from a file are left as they are; records a new gather makes at
/// deeper levels are not kept. With `next`, a record gathered again gets the new gather's
/// next-frame estimate.
pub fn regather_noisy(
    scene: &Scene,
    cache: &mut IrradianceCache,
    seed: u64,
    sites: &mut Sites,
    stats: &mut CacheStats,
    next: Option<&dyn NextFrameEstimator>,
) {
    let params = cache.params.clone();
    let target = params.record_error * params.accuracy;
    if target <= 0.0 || params.supersamples == 0 || params.regather_at <= 0.0 {
        return;
    }
    let cap = params.divisions + params.supersamples;
    for (level, (level_sites, level_estimates)) in sites
        .levels
        .iter_mut()
        .zip(sites.estimates.iter_mut())
        .enumerate()
    {
        let jobs: Vec<(usize, usize, ShadingPoint, usize)> = {
            let store = &cache.levels[level];
            let recs = store.records();
            level_sites
                .par_iter()
                .enumerate()
                .filter_map(
                    |(
                        site,
                        &Site {
                            index: i,
                            point: sp,
                            ..
                        },
                    )| {
                        let r = &recs[i];
                        let worst = store
                            .serving(r.p, r.n, 2.0)
                            .into_iter()
                            .filter(|&j| j as usize != i)
                            .map(|j| recs[j as usize].ray_variance)
                            .fold(0.0f32, f32::max);
                        let need = (f64::from(worst) / f64::from(target * target)).ceil();
                        (need >= f64::from(params.regather_at) * params.divisions as f64)
                            .then(|| (site, i, sp, (need as usize).min(cap)))
                    },
                )
                .collect()
        };
        if jobs.is_empty() {
            continue;
        }
        let light = SceneRadiance {
            scene,
            deeper: params.deeper,
        };
        let g = Gatherer {
            light: &light,
            cache,
            seed,
            next,
        };
        let fresh: Vec<(usize, usize, Record, WorkState, u64, usize)> = jobs
            .par_iter()
            .with_max_len(1)
            .map(|&(site, i, sp, rays)| {
                let mut st = WorkState::new(cache.levels.len());
                let key = mix(0x7265_6761_7468_6572 ^ level as u64, i as u64);
                let strata = super::hemisphere::Stratification::from_divisions(rays);
                let rec = g.record_with(&mut st, &sp, level as u32, key, strata);
                (site, i, rec, st, key, rays)
            })
            .collect();
        let mut records = cache.levels[level].records().to_vec();
        for (site, i, mut rec, mut st, key, rays) in fresh {
            (level_sites[site].key, level_sites[site].rays) = (key, rays);
            level_estimates[site] = st.estimates.pop();
            // The new coefficients take the old record's place in the list.
            cache.adopt_radiance(&mut rec, &mut st.radiance, records[i].radiance);
            let counts = st.counts;
            records[i] = rec;
            stats.records_regathered += 1;
            stats.records_computed += counts.records;
            stats.gather_rays += counts.gather_rays;
            stats.shadow_rays += counts.shadow_rays;
            stats.supersampled_cells += counts.supersampled_cells;
        }
        // Radii changed: index the level anew, in the same order.
        cache.reindex(level, records);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each stride's phases hold every point of its grid not on the coarser grid exactly once
    /// (every point on the coarsest), and two points of one phase are at least two strides and
    /// `BATCH_SPACING` pixels apart on some axis.
    #[test]
    fn phases_partition_each_stride_and_keep_their_points_apart() {
        let (w, h) = (203, 157);
        for (stride, coarsest) in [
            (32, true),
            (16, false),
            (8, false),
            (4, false),
            (2, false),
            (1, false),
        ] {
            let mut seen = vec![0u32; w * h];
            for phase in phases(stride, coarsest) {
                let pixels: Vec<_> = phase_pixels(w, h, stride, phase).collect();
                for &(x, y) in &pixels {
                    seen[y * w + x] += 1;
                }
                let apart = (2 * stride).max(if coarsest { stride } else { BATCH_SPACING });
                for (i, &(xa, ya)) in pixels.iter().enumerate() {
                    for &(xb, yb) in &pixels[i + 1..] {
                        let d = xa.abs_diff(xb).max(ya.abs_diff(yb));
                        assert!(
                            coarsest || d >= apart,
                            "stride {stride}: ({xa},{ya}) and ({xb},{yb}) in one phase"
                        );
                    }
                }
            }
            for y in 0..h {
                for x in 0..w {
                    let on_grid = x % stride == 0 && y % stride == 0;
                    let on_coarser = !coarsest && x % (2 * stride) == 0 && y % (2 * stride) == 0;
                    let expected = u32::from(on_grid && !on_coarser);
                    assert_eq!(
                        seen[y * w + x],
                        expected,
                        "stride {stride}, pixel ({x}, {y})"
                    );
                }
            }
        }
    }
}
