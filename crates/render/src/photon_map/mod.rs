//! Photon mapping (001 §2.4 and ch. 6; Jensen, *Realistic Image Synthesis Using Photon
//! Mapping*): photons traced from the lights, stored in kd-trees, read back as irradiance by
//! density estimation.
//!
//! - [`photon`]: the photon (plain data).
//! - [`trace`]: emission and tracing, parallel and deterministic; the global and caustic maps.
//! - [`kd_tree`]: the balanced kd-tree with filtered nearest-neighbour queries.
//! - [`estimate`]: irradiance from the nearest photons (Jensen eq. 7.6 with the disc area).
//! - [`records`]: photon-mapped irradiance records, Algorithms 6 and 7 of 001 ch. 6.
//! - [`hull`]: the convex hull of photons on a tangent plane with Efron's correction
//!   (NOTES-001 E.4), for photon-mapped irradiance records.
//!
//! The cache uses the maps in two ways ([`crate::irradiance_cache`]): the **cached final
//! gather** (Jensen's; Radiance's `-ap`, Mitsuba 0.6's `photonmapper`), where a record's gather
//! rays read the global map's irradiance at the surfaces they hit instead of tracing on, and
//! **caustics** from the caustic map at the pixel.

pub mod estimate;
pub mod hull;
pub mod kd_tree;
pub mod photon;
pub mod records;
pub mod trace;

pub use estimate::Lookup;
pub use kd_tree::KdTree;
pub use photon::Photon;
pub use trace::{trace_photons, MapKind, TraceStats};

use crate::scene::Scene;
use ircache_math::{Rgb, Vec3};

/// A photon map: the photons of one kind in their kd-tree.
#[derive(Clone, Debug)]
pub struct PhotonMap {
    /// Which photons it keeps.
    pub kind: MapKind,
    /// The photons.
    pub tree: KdTree,
    /// The most bounces its photons took.
    pub max_bounces: u16,
    /// The bounces the precomputed irradiance takes.
    pub precomputed_bounces: u16,
    /// Irradiance estimated in advance at every [`PRECOMPUTED_STRIDE`]th photon (in the
    /// photons' `flux`), for lookups that take all the map's bounces (Christensen, "Faster
    /// photon map global illumination", JGT 1999): the nearest such photon on the same side
    /// answers, one nearest-neighbour search instead of a density estimate.
    pub precomputed: Option<KdTree>,
    /// How it was traced.
    pub stats: TraceStats,
    /// Seconds spent tracing and building it.
    pub seconds: f64,
}

/// One photon in this many gets its irradiance estimated in advance.
pub const PRECOMPUTED_STRIDE: usize = 4;

impl PhotonMap {
    /// Traces `wanted` photons of `kind` that serve paths of up to `max_bounces` bounces before
    /// they land, and builds their tree; with `precompute`, the irradiance from photons of up
    /// to its bounces at every [`PRECOMPUTED_STRIDE`]th photon, looked up as it says.
    #[must_use]
    pub fn build(
        scene: &Scene,
        kind: MapKind,
        wanted: u64,
        max_bounces: u16,
        seed: u64,
        precompute: Option<(&Lookup, u16)>,
    ) -> Self {
        use rayon::prelude::*;
        let start = std::time::Instant::now();
        let (photons, stats) = trace_photons(scene, kind, wanted, max_bounces, seed);
        let tree = KdTree::build(photons);
        let precomputed_bounces = precompute.map_or(max_bounces, |(_, b)| b.min(max_bounces));
        let precomputed = precompute.filter(|_| !tree.is_empty()).map(|(lookup, _)| {
            let at: Vec<Photon> = tree
                .photons
                .par_iter()
                .step_by(PRECOMPUTED_STRIDE)
                .map(|ph| Photon {
                    flux: estimate::irradiance(
                        &tree,
                        ph.position,
                        ph.normal,
                        precomputed_bounces,
                        lookup,
                    ),
                    ..*ph
                })
                .collect();
            KdTree::build(at)
        });
        PhotonMap {
            kind,
            tree,
            max_bounces,
            precomputed_bounces,
            precomputed,
            stats,
            seconds: start.elapsed().as_secs_f64(),
        }
    }

    /// Irradiance at `p` on the side of unit normal `n` from photons that landed after 1 to
    /// `max_bounces` bounces (see [`estimate`]): the precomputed estimate nearest `p` where it
    /// takes the same bounces, else a density estimate.
    #[must_use]
    pub fn irradiance(&self, p: Vec3, n: Vec3, max_bounces: u16, lookup: &Lookup) -> Rgb {
        if let Some(pre) = self.precomputed.as_ref().filter(|_| {
            max_bounces == self.precomputed_bounces
                || (max_bounces >= self.max_bounces && self.precomputed_bounces == self.max_bounces)
        }) {
            if let Some(e) = estimate::nearest_precomputed(pre, p, n, lookup.max_radius) {
                return e;
            }
        }
        estimate::irradiance(&self.tree, p, n, max_bounces, lookup)
    }
}

/// The global and caustic maps of a scene with their lookup sizes.
#[derive(Clone, Debug)]
pub struct PhotonMaps {
    /// Photons after one or more bounces of any kind: indirect light at gather hits.
    pub global: PhotonMap,
    /// Photons through delta lobes only: caustics at the pixel (`None`: caustics stay with the
    /// gather).
    pub caustic: Option<PhotonMap>,
    /// Lookups in the global map.
    pub global_lookup: Lookup,
    /// Lookups in the caustic map.
    pub caustic_lookup: Lookup,
}

impl PhotonMaps {
    /// Traces `global` photons of up to `max_bounces` bounces, their irradiance precomputed for
    /// lookups of `gather_bounces` (at gather hits), and, when `caustic` > 0, that many
    /// caustic photons of up to `gather_bounces + 1` (a caustic lands one bounce nearer the
    /// camera than the gather hits), on independent streams of `seed`.
    #[must_use]
    pub fn build(
        scene: &Scene,
        (global, caustic): (u64, u64),
        (max_bounces, gather_bounces): (u16, u16),
        (global_lookup, caustic_lookup): (Lookup, Lookup),
        seed: u64,
    ) -> PhotonMaps {
        let global_map = PhotonMap::build(
            scene,
            MapKind::Global,
            global,
            max_bounces,
            seed,
            Some((&global_lookup, gather_bounces)),
        );
        // Caustics are sharp and seen directly: estimated at the pixel, never precomputed.
        let caustic = (caustic > 0).then(|| {
            let bounces = gather_bounces.saturating_add(1);
            let seed = seed ^ CAUSTIC_SALT;
            PhotonMap::build(scene, MapKind::Caustic, caustic, bounces, seed, None)
        });
        PhotonMaps {
            global: global_map,
            caustic,
            global_lookup,
            caustic_lookup,
        }
    }
}

const CAUSTIC_SALT: u64 = 0x6361_7573_7469_63;
