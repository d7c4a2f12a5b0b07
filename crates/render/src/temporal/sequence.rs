//! The cache of an animation, frame by frame (001 Algorithm 5 as `NOTES-001.md` D.6 completes
//! it; 000 §3.7.3): which records go on to the next frame, which are gathered again at their
//! place, which are dropped, and where new ones are needed.
//!
//! Each frame, the records that serve it are put into an ordinary [`IrradianceCache`] at their
//! value for that frame (5.11) and moved with their shapes; the pre-pass
//! ([`fill_for_image`]) then gathers records only where none serves, so an unchanged
//! scene costs nothing after its first frame but the records' renewal. What renews them is the
//! [`CacheMode`]:
//! - `Temporal`: each new record's value in the next frame is estimated, by gathering it once
//!   more in the next frame's scene with the same random numbers (the default: a whole gather,
//!   but no holes) or with `--next-frame reproject` by reprojecting its gather as the record is
//!   made (§5.2.4, [`super::reprojection`]: no hemisphere rays, its hits shaded again); that
//!   gives its lifespan (5.3–5.8) and its extrapolated temporal gradients (5.12–5.14). When it expires having served its last frame,
//!   a successor is gathered at the same place (§5.2.3: the pattern of records, and so of
//!   errors, stays still); one that served no pixel is dropped (§5.3's deletion). With
//!   interpolated gradients (5.15–5.17) a record's slope runs to its successor's value, which
//!   needs the whole sequence filled before any frame is rendered (two passes).
//! - `Age`: records keep their value; each frame the oldest share (1/δt_max of them) is gathered
//!   again at its place, those that may see a moving thing first (000 §3.7.3), and records that
//!   served no pixel are dropped.
//! - `PerFrame`: a new cache each frame (the baseline).
//!
//! Every frame's gathers draw on a seed of their own, as independent renders of the frames
//! would; the pixel samples keep the animation's seed.

use super::lifespan::{coefficient_change, lifespan, relative_change};
use super::record::{move_point, move_record, RadianceTrack, Slope, SlopeKind, TemporalRecord};
use super::reprojection::Reprojection;
use crate::integrators::ic::IcIntegrator;
use crate::irradiance_cache::build::{fill_for_image, record_sites, Site};
use crate::irradiance_cache::gather::{
    mix, Gatherer, NextEstimate, NextFrameEstimator, SceneRadiance, WorkState,
};
use crate::irradiance_cache::hemisphere::Stratification;
use crate::irradiance_cache::prepare::{empty_cache, photon_maps};
use crate::irradiance_cache::record::NO_RADIANCE;
use crate::irradiance_cache::{IrradianceCache, Record};
use crate::photon_map::PhotonMaps;
use crate::radiance_cache::record::RadianceRecord;
use crate::scene::{RenderError, Scene, ShapeGeometry};
use ircache_math::{Mat4, Rgb, Vec2, Vec3};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// How an animation's cache is kept over time (`--cache-mode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum CacheMode {
    /// Temporal radiance caching (001 ch. 5).
    #[default]
    Temporal,
    /// Age-based invalidation (000 §3.7.3).
    Age,
    /// A new cache every frame.
    PerFrame,
}

impl CacheMode {
    /// Parses `temporal`, `age` or `per-frame`.
    pub fn parse(s: &str) -> Result<CacheMode, String> {
        match s {
            "temporal" => Ok(CacheMode::Temporal),
            "age" => Ok(CacheMode::Age),
            "per-frame" => Ok(CacheMode::PerFrame),
            _ => Err(format!(
                "unknown cache mode \"{s}\" (expected temporal, age or per-frame)"
            )),
        }
    }

    /// The name `parse` accepts.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            CacheMode::Temporal => "temporal",
            CacheMode::Age => "age",
            CacheMode::PerFrame => "per-frame",
        }
    }
}

/// How the temporal cache estimates a new record's next frame (`--next-frame`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum NextFrame {
    /// Reprojecting the record's gather (001 §5.2.4): the default, by measurement (BENCHMARKS.md,
    /// 2026-12-07: 0.36–0.53× the estimates' rays; the box scenes' sequences 0.87–0.98× the time
    /// and the lamp room's 0.97×, at the same error within 2 % and the same flicker).
    #[default]
    Reproject,
    /// Gathering it again in the next frame with the same random numbers (a whole gather, no
    /// holes).
    Regather,
}

impl NextFrame {
    /// Parses `reproject` or `regather`.
    pub fn parse(s: &str) -> Result<NextFrame, String> {
        match s {
            "reproject" => Ok(NextFrame::Reproject),
            "regather" => Ok(NextFrame::Regather),
            _ => Err(format!(
                "unknown next-frame estimate \"{s}\" (expected reproject or regather)"
            )),
        }
    }

    /// The name `parse` accepts.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            NextFrame::Reproject => "reproject",
            NextFrame::Regather => "regather",
        }
    }
}

/// Settings of an animation's cache.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemporalParams {
    /// How records are kept over time.
    pub mode: CacheMode,
    /// Temporal accuracy a_t (5.6): the relative change a record may accumulate.
    pub accuracy: f32,
    /// Longest life δt_max in frames (5.8); for the age-based cache, 1/δt_max of the records is
    /// renewed each frame.
    pub max_lifespan: u32,
    /// Temporal gradients: [`SlopeKind::Interpolated`] (two passes) or
    /// [`SlopeKind::Extrapolated`] (one); [`SlopeKind::Constant`] turns them off.
    pub gradients: SlopeKind,
    /// How a new record's next frame is estimated.
    pub next_frame: NextFrame,
}

impl Default for TemporalParams {
    /// `NOTES-001.md` G: a_t = 0.05 (the thesis's), δt_max = 10, interpolated gradients (the
    /// thesis's Table 5.2).
    fn default() -> Self {
        TemporalParams {
            mode: CacheMode::Temporal,
            accuracy: 0.05,
            max_lifespan: 10,
            gradients: SlopeKind::Interpolated,
            next_frame: NextFrame::default(),
        }
    }
}

impl TemporalParams {
    /// Whether the frames can only be rendered after the whole sequence is filled.
    #[must_use]
    pub fn two_passes(&self) -> bool {
        self.mode == CacheMode::Temporal && self.gradients == SlopeKind::Interpolated
    }
}

/// Where shapes go between frames.
pub trait Motion: Sync {
    /// The transform taking shape `shape` from frame `from` to frame `to`; `None` for a shape
    /// that does not move.
    fn motion(&self, shape: u32, from: u32, to: u32) -> Option<Mat4>;
    /// The shapes that move.
    fn moving_shapes(&self) -> Vec<u32>;
    /// Whether any shape moves (else the scene's light is the same in every frame: only the
    /// camera may move).
    fn moves_shapes(&self) -> bool {
        !self.moving_shapes().is_empty()
    }
}

impl Motion for ircache_scene::animation::Animation {
    fn motion(&self, shape: u32, from: u32, to: u32) -> Option<Mat4> {
        self.is_moving(shape as usize)
            .then(|| self.shape_motion(shape as usize, from as f32, to as f32))
    }
    fn moving_shapes(&self) -> Vec<u32> {
        self.tracks
            .iter()
            .filter_map(|t| match t.target {
                ircache_scene::animation::Target::Shape(i) => Some(i as u32),
                ircache_scene::animation::Target::Camera => None,
            })
            .collect()
    }
    fn moves_shapes(&self) -> bool {
        ircache_scene::animation::Animation::moves_shapes(self)
    }
}

/// No motion (a still scene rendered as a sequence).
impl Motion for () {
    fn motion(&self, _: u32, _: u32, _: u32) -> Option<Mat4> {
        None
    }
    fn moving_shapes(&self) -> Vec<u32> {
        Vec::new()
    }
}

/// What filling one frame did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameStats {
    /// The frame.
    pub frame: u32,
    /// Records serving the frame.
    pub live: usize,
    /// Records carried over from earlier frames.
    pub carried: usize,
    /// Records gathered at the place of an expired one.
    pub renewed: usize,
    /// Records gathered where none served.
    pub new: usize,
    /// Records that expired (or were picked for renewal) without having served a pixel in
    /// their last frame, and were dropped.
    pub dropped: usize,
    /// Next-frame estimates for lifespans (temporal mode).
    pub estimates: usize,
    /// Rays those estimates traced (gather and shadow rays, and their paths' bounces).
    pub estimate_rays: u64,
    /// Hemisphere rays traced (all gathers).
    pub gather_rays: u64,
    /// Seconds.
    pub seconds: f64,
}

impl FrameStats {
    /// Every hemisphere gathered: records and next-frame estimates.
    #[must_use]
    pub fn gathers(&self) -> usize {
        self.renewed + self.new + self.estimates
    }
}

/// An animation's cache: every record any frame used, with its life.
pub struct SequenceCache {
    /// Temporal settings.
    pub params: TemporalParams,
    /// The cache's own settings (accuracy, divisions, exclusions ...).
    pub ic: IcIntegrator,
    /// Image width and height (the pre-pass's pixel grid).
    pub size: (usize, usize),
    /// The animation's seed.
    pub seed: u64,
    /// Every record made so far, by creation.
    pub records: Vec<TemporalRecord>,
    /// The radiance coefficients of each record of `records` that holds them.
    pub radiance: Vec<Option<RadianceTrack>>,
    /// Whether each record served a pixel in the last frame filled.
    used: Vec<bool>,
    /// Radiance caching's tables, made with the first frame's cache.
    tables: std::sync::OnceLock<Arc<crate::radiance_cache::RadianceCache>>,
    /// The photon maps of the frame after the last filled, traced for its estimates and
    /// reused by its own cache.
    next_photons: Option<(u32, Arc<PhotonMaps>)>,
    /// Where no shape moves, every frame's photon maps (they do not depend on the view): traced
    /// once.
    still_photons: std::sync::OnceLock<Option<Arc<PhotonMaps>>>,
    /// The maps of frames filled and not yet asked for ([`Self::cache_at`] takes them), up to
    /// [`PHOTON_MAPS_HELD`] bytes.
    frame_photons: std::sync::Mutex<std::collections::BTreeMap<u32, Arc<PhotonMaps>>>,
}

/// Bytes of frames' photon maps a [`SequenceCache`] holds between filling the frames and
/// rendering them (beyond, a frame's maps are traced again for its render).
const PHOTON_MAPS_HELD: usize = 512 << 20;

impl SequenceCache {
    /// A cache for frames of `size` pixels.
    ///
    /// # Errors
    /// A cache file, or temporal settings out of range.
    pub fn new(
        ic: &IcIntegrator,
        params: TemporalParams,
        size: (usize, usize),
        seed: u64,
    ) -> Result<SequenceCache, RenderError> {
        if ic.cache_file.is_some() {
            return Err(RenderError::Invalid(
                "--cache FILE holds one frame's records: an animation keeps its own".into(),
            ));
        }
        if !(params.accuracy > 0.0 && params.accuracy.is_finite()) || params.max_lifespan == 0 {
            return Err(RenderError::Invalid(format!(
                "temporal accuracy {} and longest life {}: expected a_t > 0 and δt_max ≥ 1",
                params.accuracy, params.max_lifespan
            )));
        }
        Ok(SequenceCache {
            params,
            ic: ic.clone(),
            size,
            seed,
            records: Vec::new(),
            radiance: Vec::new(),
            used: Vec::new(),
            tables: std::sync::OnceLock::new(),
            next_photons: None,
            still_photons: std::sync::OnceLock::new(),
            frame_photons: std::sync::Mutex::default(),
        })
    }

    /// The seed of frame `frame`'s gathers.
    fn frame_seed(&self, frame: u32) -> u64 {
        mix(self.seed ^ 0x7465_6d70_6f72_616c, u64::from(frame))
    }

    /// The cache serving `frame`: the records alive then at their value for it (5.11).
    ///
    /// # Errors
    /// As [`empty_cache`].
    pub fn cache_at(
        &self,
        frame: u32,
        scene: &Scene,
        motion: &dyn Motion,
        pool: &rayon::ThreadPool,
    ) -> Result<IrradianceCache, RenderError> {
        scene.require_no_media("the temporal cache (ircache animate with a cache mode)")?;
        Ok(self.seeded(frame, scene, motion, pool)?.0)
    }

    /// Whether every frame takes the same photon maps, traced once: no shape moves (the maps do
    /// not depend on the view), and the frames share a cache's work (not per frame).
    fn shares_photons(&self, motion: &dyn Motion) -> bool {
        self.params.mode != CacheMode::PerFrame && !motion.moves_shapes()
    }

    /// [`Self::cache_at`] and, per level, the record behind each store index.
    fn seeded(
        &self,
        frame: u32,
        scene: &Scene,
        motion: &dyn Motion,
        pool: &rayon::ThreadPool,
    ) -> Result<(IrradianceCache, Vec<Vec<u32>>), RenderError> {
        // Radiance caching's tables depend on the materials only, which do not move.
        let tables = self.tables.get();
        let still = self.shares_photons(motion);
        let held = || {
            self.frame_photons
                .lock()
                .ok()
                .and_then(|mut held| held.remove(&frame))
        };
        let maps = match self.still_photons.get() {
            Some(maps) if still => maps.clone(),
            _ => held().or_else(|| {
                self.next_photons
                    .as_ref()
                    .filter(|(f, _)| *f == frame)
                    .map(|(_, m)| m.clone())
            }),
        };
        let cache = empty_cache(scene, &self.ic, self.size.0, tables, maps, self.seed, pool)?;
        if let (None, Some(t)) = (tables, &cache.radiance) {
            let _ = self.tables.set(t.clone());
        }
        if still {
            let _ = self.still_photons.set(cache.photons.clone());
        }
        let mut cache = cache;
        let mut slots = vec![Vec::new(); cache.levels.len()];
        for (i, tr) in self.records.iter().enumerate() {
            if tr.live_at(frame) {
                // Moved with its shape.
                let m = motion.motion(tr.site.point.it.shape, tr.born, frame);
                let mut r = tr.at(frame, m.as_ref());
                r.radiance = NO_RADIANCE;
                if let Some(track) = &self.radiance[i] {
                    r.radiance = cache.radiance_records.len() as u32;
                    cache
                        .radiance_records
                        .push(track.at(frame - tr.born, m.as_ref()));
                }
                let level = r.level as usize;
                cache.levels[level].insert(r);
                slots[level].push(i as u32);
            }
        }
        Ok((cache, slots))
    }

    /// Fills frame `frame` (pass 1 of Algorithm 5): renews or drops the records that expired,
    /// gathers where no record serves, and (temporal mode) estimates the new records' next
    /// frame in `next`, the scene one frame later (`None` at the sequence's end).
    ///
    /// # Errors
    /// As [`empty_cache`].
    pub fn fill_frame(
        &mut self,
        frame: u32,
        scene: &Scene,
        next: Option<&Scene>,
        motion: &dyn Motion,
        pool: &rayon::ThreadPool,
    ) -> Result<FrameStats, RenderError> {
        let start = Instant::now();
        let mut stats = FrameStats {
            frame,
            ..FrameStats::default()
        };
        let renew = self.expire(frame, scene, motion, &mut stats);
        // Where no shape moves (the camera may), a record's light is the same in every frame:
        // it lives on, with no estimate of its next frame (a renewal would only draw its noise
        // again, and flicker); the photon maps are traced once (`Self::seeded`).
        let light_moves = motion.moves_shapes();
        let (mut cache, mut slots) = self.seeded(frame, scene, motion, pool)?;
        // The frame's maps, kept for its render.
        if let (false, Some(maps), Ok(held)) = (
            self.shares_photons(motion),
            &cache.photons,
            self.frame_photons.get_mut(),
        ) {
            let bytes: usize = held.values().map(|m| m.bytes()).sum();
            if bytes + maps.bytes() <= PHOTON_MAPS_HELD {
                held.insert(frame, maps.clone());
            }
        }
        stats.carried = slots.iter().map(Vec::len).sum();
        let seed = self.frame_seed(frame);
        let first_new = self.records.len();
        let deeper = cache.params.deeper;
        // Temporal mode: the next frame's scene and photon maps, for the estimates; with
        // `--next-frame reproject` they are made during the pre-pass from a copy of this frame's
        // cache lit by those maps.
        let ahead = match (self.params.mode, next) {
            (CacheMode::Temporal, Some(next)) if light_moves => {
                Some((next, self.next_photon_maps(&cache, next, frame, pool)))
            }
            _ => None,
        };
        let reprojection_cache = ahead
            .as_ref()
            .filter(|_| self.params.next_frame == NextFrame::Reproject)
            .map(|(_, maps)| lit_by(&cache, maps.as_ref()));
        let reprojection = match (&ahead, &reprojection_cache) {
            (Some((next, _)), Some(next_cache)) => Some(Reprojection {
                light: SceneRadiance {
                    scene: next,
                    deeper,
                },
                cache: next_cache,
                motion,
                frame,
            }),
            _ => None,
        };
        let estimator = reprojection.as_ref().map(|r| r as &dyn NextFrameEstimator);
        // The estimates of the records made this frame, in the order of `self.records`.
        let mut pending: Vec<Option<NextEstimate>> = Vec::new();

        // Successors at the places of the renewed records (§5.2.3).
        let gathered: Vec<(usize, Record, WorkState, Site)> = {
            let light = SceneRadiance { scene, deeper };
            let g = Gatherer {
                light: &light,
                cache: &cache,
                seed,
                next: estimator,
            };
            pool.install(|| {
                renew
                    .par_iter()
                    .with_max_len(1)
                    .map(|&k| {
                        let old = &self.records[k];
                        let m = motion.motion(old.site.point.it.shape, old.born, frame);
                        let point = m.map_or(old.site.point, |m| move_point(&old.site.point, &m));
                        let site = Site { point, ..old.site };
                        let mut st = WorkState::new(cache.levels.len());
                        let rec = gather(&g, &mut st, &site, old.record.level);
                        (k, rec, st, site)
                    })
                    .collect()
            })
        };
        for (k, rec, mut st, site) in gathered {
            stats.gather_rays += st.counts.gather_rays;
            let estimate = st.estimates.pop();
            // Deeper records the gather made first, as the pre-pass inserts them.
            let made = |r: &Record| st.radiance.get(r.radiance as usize).cloned();
            for (r, point, key) in &st.new_records {
                let level = r.level as usize;
                let site = Site {
                    index: cache.levels[level].len(),
                    point: *point,
                    key: *key,
                    rays: 0,
                };
                self.add(&mut cache, &mut slots, *r, made(r), site, seed, frame);
                pending.push(None);
            }
            let level = rec.level as usize;
            let site = Site {
                index: cache.levels[level].len(),
                ..site
            };
            let l = self.add(&mut cache, &mut slots, rec, made(&rec), site, seed, frame);
            pending.push(estimate);
            self.records[k].successor = Some(l as u32);
            stats.renewed += 1;
            if self.params.two_passes() {
                // 5.15–5.17: k's slope runs to its successor's value, in k's orientation.
                let old = self.records[k];
                let back = motion.motion(old.site.point.it.shape, frame, old.born);
                let succ = back.map_or(rec, |m| move_record(&rec, &m));
                self.records[k].slope = Slope::between(&old.record, &succ, frame - old.born);
                self.records[k].kind = SlopeKind::Interpolated;
                // Coefficients in the same frame only where neither moved.
                if back.is_none() {
                    let later = self.radiance[l].as_ref().map(|t| t.born.radiance.clone());
                    if let (Some(track), Some(later)) = (&mut self.radiance[k], later) {
                        track.slope_to(&later, frame - old.born);
                    }
                }
            }
        }

        // Records where none serves: the ordinary pre-pass over the frame's pixels.
        let first_filled = self.records.len();
        let (w, h) = self.size;
        let (fill, mut sites) = pool
            .install(|| fill_for_image(scene, &mut cache, w, h, 0..h, seed, &mut (), estimator));
        stats.gather_rays += fill.gather_rays;
        for (level, (level_sites, estimates)) in sites
            .levels
            .iter()
            .zip(sites.estimates.iter_mut())
            .enumerate()
        {
            for (site, estimate) in level_sites.iter().zip(estimates.iter_mut()) {
                pending.push(estimate.take());
                let r = cache.levels[level].records()[site.index];
                slots[level].push(self.records.len() as u32);
                self.records.push(self.born(r, *site, seed, frame));
                self.radiance.push(
                    cache
                        .radiance_records
                        .get(r.radiance as usize)
                        .cloned()
                        .map(RadianceTrack::constant),
                );
                stats.new += 1;
            }
        }
        // The successors' radii as the pre-pass's records, inserted after them, clamped them
        // (the pre-pass's own records were read after it, as they stay).
        for (level, ids) in slots.iter().enumerate() {
            for (index, &id) in ids.iter().enumerate() {
                if (first_new..first_filled).contains(&(id as usize)) {
                    self.records[id as usize].record = cache.levels[level].records()[index];
                }
            }
        }

        if self.params.mode == CacheMode::Temporal && !light_moves {
            for tr in &mut self.records[first_new..] {
                tr.last = u32::MAX;
            }
        }
        self.set_lives(
            frame, first_new, &cache, ahead, motion, pool, &mut stats, pending,
        );
        self.mark_used(scene, &cache, &slots, pool);
        stats.live = slots.iter().map(Vec::len).sum();
        stats.seconds = start.elapsed().as_secs_f64();
        Ok(stats)
    }

    /// Ends the lives that end before `frame`: returns the records to renew at their place;
    /// the others that ended are dropped.
    fn expire(
        &mut self,
        frame: u32,
        scene: &Scene,
        motion: &dyn Motion,
        stats: &mut FrameStats,
    ) -> Vec<usize> {
        let Some(prev) = frame.checked_sub(1) else {
            return Vec::new();
        };
        let used = |i: usize| self.used.get(i).copied().unwrap_or(false);
        let mut renew = Vec::new();
        match self.params.mode {
            CacheMode::PerFrame => {}
            CacheMode::Temporal => {
                for (i, tr) in self.records.iter().enumerate() {
                    if tr.last == prev && tr.successor.is_none() {
                        if used(i) {
                            renew.push(i);
                        } else {
                            stats.dropped += 1;
                        }
                    }
                }
            }
            CacheMode::Age => {
                let movers = movers(scene, motion);
                let mut live = Vec::new();
                for i in 0..self.records.len() {
                    if !self.records[i].live_at(prev) || self.records[i].last != u32::MAX {
                        continue;
                    }
                    // Dropped the frame they serve no pixel centre; deeper levels' records
                    // (past delta vertices, where the centres are a sparse sample of the
                    // pixels' paths) only when their turn to be renewed comes, as in the
                    // temporal mode: dropped each frame they were made again the next (the
                    // lamp room's FHP 1.5×).
                    if used(i) || self.records[i].record.level > 0 {
                        live.push(i);
                    } else {
                        self.records[i].last = prev;
                        stats.dropped += 1;
                    }
                }
                // Those that may see moving things first, then by age (000 §3.7.3); any record
                // twice δt_max old is renewed whatever the share.
                live.sort_by_cached_key(|&i| {
                    let tr = &self.records[i];
                    (!sees_moving(&movers, tr), tr.born, i)
                });
                let share = live.len().div_ceil(self.params.max_lifespan as usize);
                let too_old = 2 * self.params.max_lifespan;
                for (rank, &i) in live.iter().enumerate() {
                    if rank < share || frame - self.records[i].born >= too_old {
                        self.records[i].last = prev;
                        if used(i) {
                            renew.push(i);
                        } else {
                            stats.dropped += 1;
                        }
                    }
                }
                renew.sort_unstable();
            }
        }
        renew
    }

    /// Adds a record made at `frame` (with its radiance coefficients, if any) to the cache and
    /// the list; returns its index.
    #[allow(clippy::too_many_arguments)]
    fn add(
        &mut self,
        cache: &mut IrradianceCache,
        slots: &mut [Vec<u32>],
        mut r: Record,
        radiance: Option<RadianceRecord>,
        site: Site,
        seed: u64,
        frame: u32,
    ) -> usize {
        r.radiance = NO_RADIANCE;
        if let Some(c) = &radiance {
            r.radiance = cache.radiance_records.len() as u32;
            cache.radiance_records.push(c.clone());
        }
        let level = r.level as usize;
        cache.levels[level].insert(r);
        let i = self.records.len();
        slots[level].push(i as u32);
        self.records.push(self.born(r, site, seed, frame));
        self.radiance.push(radiance.map(RadianceTrack::constant));
        i
    }

    /// A record born at `frame`, serving that frame only until [`Self::set_lives`] says more.
    fn born(&self, record: Record, site: Site, seed: u64, frame: u32) -> TemporalRecord {
        TemporalRecord {
            record,
            site,
            seed,
            born: frame,
            last: frame,
            slope: Slope::default(),
            kind: SlopeKind::Constant,
            successor: None,
        }
    }

    /// With photons, the next frame's maps (this frame's would light the moved scene with where
    /// its photons landed before), traced on the seed the next frame's own cache takes and kept
    /// for it.
    fn next_photon_maps(
        &mut self,
        cache: &IrradianceCache,
        next: &Scene,
        frame: u32,
        pool: &rayon::ThreadPool,
    ) -> Option<Arc<PhotonMaps>> {
        self.next_photons = None;
        cache.photons.as_ref()?;
        let maps = pool
            .install(|| photon_maps(next, &cache.params, self.seed))
            .map(Arc::new);
        self.next_photons = maps.clone().map(|m| (frame + 1, m));
        maps
    }

    /// Lives and slopes of the records made at `frame` (from index `first`) in `cache`, from
    /// their next-frame estimates (`estimates`, one per record); those without are gathered
    /// again in the next frame's scene, lit by its photon maps (`ahead`).
    #[allow(clippy::too_many_arguments)]
    fn set_lives(
        &mut self,
        frame: u32,
        first: usize,
        cache: &IrradianceCache,
        ahead: Option<(&Scene, Option<Arc<PhotonMaps>>)>,
        motion: &dyn Motion,
        pool: &rayon::ThreadPool,
        stats: &mut FrameStats,
        estimates: Vec<Option<NextEstimate>>,
    ) {
        match (self.params.mode, ahead) {
            (CacheMode::PerFrame, _) | (CacheMode::Temporal, None) => {}
            (CacheMode::Age, _) => {
                // Until picked for renewal.
                for tr in &mut self.records[first..] {
                    tr.last = u32::MAX;
                }
            }
            (CacheMode::Temporal, Some((next, maps))) => {
                // Records without an estimate: the next frame gathered with the same random
                // numbers.
                let lit = maps.map(|m| lit_by(cache, Some(&m)));
                let cache = lit.as_ref().unwrap_or(cache);
                let light = SceneRadiance {
                    scene: next,
                    deeper: cache.params.deeper,
                };
                let estimates: Vec<(Record, Option<RadianceRecord>, bool, u64)> =
                    pool.install(|| {
                        self.records[first..]
                            .par_iter()
                            .zip(estimates.into_par_iter())
                            .with_max_len(1)
                            .map(|(tr, estimate)| {
                                let shape = tr.site.point.it.shape;
                                let ahead = motion.motion(shape, frame, frame + 1);
                                let (rec, radiance, counts) = match estimate {
                                    Some(e) => (e.record, e.radiance, e.counts),
                                    None => {
                                        let g = Gatherer::new(&light, cache, tr.seed);
                                        let point = ahead.map_or(tr.site.point, |m| {
                                            move_point(&tr.site.point, &m)
                                        });
                                        let site = Site { point, ..tr.site };
                                        let mut st = WorkState::new(cache.levels.len());
                                        let rec = gather(&g, &mut st, &site, tr.record.level);
                                        let radiance =
                                            st.radiance.get(rec.radiance as usize).cloned();
                                        (rec, radiance, st.counts)
                                    }
                                };
                                let back = motion.motion(shape, frame + 1, frame);
                                (
                                    back.map_or(rec, |m| move_record(&rec, &m)),
                                    radiance,
                                    ahead.is_some(),
                                    counts.gather_rays + counts.shadow_rays,
                                )
                            })
                            .collect()
                    });
                let floor = change_floor(&self.records[first..]);
                let params = self.params;
                for (i, (next_rec, next_radiance, moving, rays)) in (first..).zip(estimates) {
                    stats.estimates += 1;
                    stats.estimate_rays += rays;
                    let tr = &mut self.records[i];
                    let mut change = relative_change(tr.record.e, next_rec.e, floor);
                    if let Some(track) = &mut self.radiance[i] {
                        match next_radiance {
                            // 5.7 with the norm ratio; the coefficients compare in one frame
                            // only where the record did not turn.
                            Some(next) if !moving => {
                                let (a, b) = (&track.born.radiance, &next.radiance);
                                change = change.max(coefficient_change(
                                    &a.coefficients,
                                    &b.coefficients,
                                    3,
                                ));
                                if params.gradients != SlopeKind::Constant {
                                    track.slope_to(b, 1);
                                }
                            }
                            _ => change = f32::INFINITY,
                        }
                    }
                    tr.last = frame + lifespan(change, params.accuracy, params.max_lifespan);
                    if params.gradients != SlopeKind::Constant {
                        tr.slope = Slope::between(&tr.record, &next_rec, 1);
                        tr.kind = SlopeKind::Extrapolated;
                    }
                }
            }
        }
    }

    /// Marks the records that serve some pixel centre's record site in the frame of `scene`
    /// (the CPU's stand-in for §5.3's occlusion query), at every level: deeper levels' sites lie
    /// past the pixel's delta vertices (in mirrors, through glass). (Deeper records counted as
    /// used whatever they served were renewed without end: the lamp room's live records grew
    /// from 1 603 to 3 681 over 23 frames.)
    fn mark_used(
        &mut self,
        scene: &Scene,
        cache: &IrradianceCache,
        slots: &[Vec<u32>],
        pool: &rayon::ThreadPool,
    ) {
        let (w, h) = self.size;
        let levels = cache.levels.len() as u32;
        let inv = Vec2::new(1.0 / w as f32, 1.0 / h as f32);
        let hits: Vec<(usize, u32)> = pool.install(|| {
            (0..w * h)
                .into_par_iter()
                .fold(Vec::new, |mut acc, i| {
                    let film = Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5) * inv;
                    let ray = scene.camera.generate_ray(film);
                    // The pixel's sites at every level (past delta vertices), radiance-cached
                    // glossy surfaces included.
                    let sites = record_sites(scene, &ray, levels, cache.radiance.as_deref());
                    for (depth, sp) in &sites {
                        let level = *depth as usize;
                        if let Some(store) = cache.levels.get(level) {
                            acc.extend(
                                store
                                    .serving(sp.it.p, sp.n, 1.0)
                                    .into_iter()
                                    .map(|id| (level, id)),
                            );
                        }
                    }
                    acc
                })
                .reduce(Vec::new, |mut a, b| {
                    a.extend(b);
                    a
                })
        });
        self.used = vec![false; self.records.len()];
        for (level, id) in hits {
            self.used[slots[level][id as usize] as usize] = true;
        }
    }
}

/// A copy of `cache` lit by the photon maps `maps` where there are some.
fn lit_by(cache: &IrradianceCache, maps: Option<&Arc<PhotonMaps>>) -> IrradianceCache {
    let mut c = cache.clone();
    if let Some(m) = maps {
        c.photons = Some(m.clone());
    }
    c
}

/// Gathers a record at `site` for `level` as the site's gather did: its key, its rays.
fn gather(g: &Gatherer, st: &mut WorkState, site: &Site, level: u8) -> Record {
    let level = u32::from(level);
    if site.rays > 0 {
        let strata = Stratification::from_divisions(site.rays);
        g.record_with(st, &site.point, level, site.key, strata)
    } else {
        g.record_at(st, &site.point, level, site.key)
    }
}

/// The irradiance below which changes count against this floor instead (2 % of the records'
/// mean, per channel's largest): a nearly black record's relative change is noise.
fn change_floor(records: &[TemporalRecord]) -> f32 {
    let sum = records
        .iter()
        .fold(Rgb::ZERO, |s, tr| s + tr.record.e.max(Rgb::ZERO));
    0.02 * sum.max_channel() / records.len().max(1) as f32
}

/// A moving shape's bounding sphere at a frame.
struct Mover {
    shape: u32,
    center: Vec3,
    radius: f32,
    emits: bool,
}

impl Mover {
    /// Whether a record at (p, n) may see it: an emitter anywhere above the record's plane, any
    /// other mover if it covers more than 1 % of the hemisphere's solid angle there (its bounding
    /// sphere, occluders ignored: the test errs towards renewing).
    fn seen_from(&self, p: Vec3, n: Vec3) -> bool {
        let d = self.center - p;
        let dist = d.length();
        if dist <= self.radius {
            return true;
        }
        if d.dot(n) < -self.radius {
            return false;
        }
        let sin2 = (self.radius / dist).powi(2);
        let solid_angle = 2.0 * std::f32::consts::PI * (1.0 - (1.0 - sin2).max(0.0).sqrt());
        self.emits || solid_angle > 0.01 * 2.0 * std::f32::consts::PI
    }
}

/// Whether the record may see something that moves: it sits on a moving shape, or a mover is
/// [`Mover::seen_from`] its position.
fn sees_moving(movers: &[Mover], tr: &TemporalRecord) -> bool {
    let (p, n) = (tr.site.point.it.p, tr.record.n);
    movers
        .iter()
        .any(|m| m.shape == tr.site.point.it.shape || m.seen_from(p, n))
}

/// The shapes of `scene` that move, as bounding spheres.
fn movers(scene: &Scene, motion: &dyn Motion) -> Vec<Mover> {
    motion
        .moving_shapes()
        .into_iter()
        .map(|shape| {
            let s = &scene.shapes[shape as usize];
            let (center, radius) = match &s.geometry {
                ShapeGeometry::Sphere { center, radius, .. } => (*center, *radius),
                ShapeGeometry::Mesh(m) => {
                    let (lo, hi) = m.positions.iter().fold(
                        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                        |(lo, hi), &p| (lo.min(p), hi.max(p)),
                    );
                    (0.5 * (lo + hi), 0.5 * (hi - lo).length())
                }
            };
            Mover {
                shape,
                center,
                radius,
                emits: s.area_light.is_some(),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrators::Integrator;

    /// `scenes/cube-in-box/FILE` at `size`² with photons (`max_depth` 4), the cache at 64
    /// divisions, and a pool of two threads.
    fn cube_in_box(
        file: &str,
        size: u32,
    ) -> (
        ircache_scene::SceneDesc,
        ircache_scene::animation::Animation,
        IcIntegrator,
        rayon::ThreadPool,
    ) {
        let path = ircache_testing::project_scenes()
            .join("cube-in-box")
            .join(file);
        let (mut desc, anim) = ircache_scene::animation::load_animation(&path, &[]).expect("loads");
        desc.sensor.film.width = size;
        desc.sensor.film.height = size;
        desc.integrator.max_depth = 4;
        let Integrator::Ic(mut ic) = Integrator::from_desc(&desc.integrator).expect("ic") else {
            panic!("the scene's integrator is the cache");
        };
        ic.params.set("divisions", "64").unwrap();
        assert!(
            ic.params.global_photons() > 0,
            "photons by default at two bounces"
        );
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        (desc, anim, ic, pool)
    }

    /// Where no shape moves, the photon maps are traced once: the caches of the frames filled
    /// and of those asked for afterwards hold the same maps, whose photons are those a frame
    /// traces alone (the maps do not depend on the frame).
    #[test]
    fn a_still_scenes_photon_maps_are_traced_once() {
        let (desc, _, ic, pool) = cube_in_box("still.xml", 24);
        let scene = Scene::build(&desc).expect("scene");
        let mut seq =
            SequenceCache::new(&ic, TemporalParams::default(), (24, 24), 1).expect("cache");
        for f in 0..3 {
            seq.fill_frame(f, &scene, (f < 2).then_some(&scene), &(), &pool)
                .expect("fills");
        }
        let maps = |f: u32| {
            seq.cache_at(f, &scene, &(), &pool)
                .expect("cache")
                .photons
                .expect("maps")
        };
        let (first, last) = (maps(0), maps(2));
        assert!(Arc::ptr_eq(&first, &last), "the maps traced again");
        let alone = empty_cache(&scene, &ic, 24, None, None, seq.seed, &pool)
            .expect("cache")
            .photons
            .expect("maps");
        assert_eq!(first.global.stats, alone.global.stats);
        for (p, n) in [
            (Vec3::new(0.0, 0.0, 0.0), Vec3::Y),
            (Vec3::new(-0.6, 0.0, -0.5), Vec3::Y),
        ] {
            let lookup = &first.global_lookup;
            let e = first.global.irradiance(p, n, 8, lookup);
            assert!(e.max_channel() > 0.0, "no photons at {p}");
            assert_eq!(e, alone.global.irradiance(p, n, 8, lookup));
        }
    }

    /// Where shapes move, each frame's maps are kept from its filling for its render (once:
    /// the render takes them), the same maps a frame traces alone.
    #[test]
    fn a_frames_photon_maps_serve_its_render() {
        let (desc, anim, ic, pool) = cube_in_box("animation.xml", 16);
        let scene_at = |f: u32| Scene::build(&anim.scene_at(&desc, f as f32)).expect("scene");
        for mode in [CacheMode::Temporal, CacheMode::PerFrame] {
            let params = TemporalParams {
                mode,
                gradients: SlopeKind::Extrapolated,
                ..TemporalParams::default()
            };
            let mut seq = SequenceCache::new(&ic, params, (16, 16), 1).expect("cache");
            for f in 0..3 {
                let next = (f < 2).then(|| scene_at(f + 1));
                seq.fill_frame(f, &scene_at(f), next.as_ref(), &anim, &pool)
                    .expect("fills");
            }
            let held = |f: u32| seq.frame_photons.lock().unwrap().get(&f).cloned();
            let kept = held(1).expect("frame 1's maps held");
            let scene = scene_at(1);
            let maps = seq.cache_at(1, &scene, &anim, &pool).unwrap().photons;
            assert!(Arc::ptr_eq(&kept, &maps.expect("maps")), "{mode:?}");
            assert!(held(1).is_none() && held(2).is_some());
            let alone = empty_cache(&scene, &ic, 16, None, None, seq.seed, &pool)
                .unwrap()
                .photons
                .expect("maps");
            assert_eq!(kept.global.stats, alone.global.stats);
        }
    }

    /// With photons (two bounces), a record's estimate of the next frame gathered again is
    /// exactly what the next frame's cache gathers at the moved site with the same key: the next frame's photon
    /// maps, not this frame's (which lit the moved cube's scene with where photons landed
    /// before).
    #[test]
    fn next_frame_estimates_read_the_next_frames_photons() {
        let (desc, anim, mut ic, pool) = cube_in_box("animation.xml", 24);
        ic.params.set("supersamples", "0").unwrap();
        let params = TemporalParams {
            mode: CacheMode::Temporal,
            gradients: SlopeKind::Extrapolated,
            next_frame: NextFrame::Regather,
            ..TemporalParams::default()
        };
        let scene_at = |f: u32| Scene::build(&anim.scene_at(&desc, f as f32)).expect("scene");
        let (now, next) = (scene_at(5), scene_at(6));
        let mut seq = SequenceCache::new(&ic, params, (24, 24), 1).expect("cache");
        seq.fill_frame(5, &now, Some(&next), &anim, &pool)
            .expect("fills");
        let later = empty_cache(&next, &ic, 24, None, None, seq.seed, &pool).expect("cache");
        let light = SceneRadiance {
            scene: &next,
            deeper: later.params.deeper,
        };
        let mut checked = 0;
        let mut differ = 0;
        for tr in seq
            .records
            .iter()
            .filter(|tr| tr.kind == SlopeKind::Extrapolated)
        {
            let shape = tr.site.point.it.shape;
            let ahead = anim.motion(shape, 5, 6);
            let point = ahead.map_or(tr.site.point, |m| move_point(&tr.site.point, &m));
            let g = Gatherer::new(&light, &later, tr.seed);
            let mut st = WorkState::new(later.levels.len());
            let site = Site { point, ..tr.site };
            let fresh = gather(&g, &mut st, &site, tr.record.level);
            let estimate = tr.at(6, ahead.as_ref());
            let tol = 1e-5 * fresh.e.max_channel().max(1e-6);
            assert!(
                (estimate.e - fresh.e).max_channel() <= tol
                    && (fresh.e - estimate.e).max_channel() <= tol,
                "estimate {:?} against the next frame's gather {:?}",
                estimate.e,
                fresh.e
            );
            differ += usize::from(tr.record.e != fresh.e);
            checked += 1;
        }
        assert!(checked > 20, "{checked} estimates");
        // The photons matter: the light changed between the frames.
        assert!(
            differ > checked / 2,
            "{differ} of {checked} records changed"
        );
    }
}
