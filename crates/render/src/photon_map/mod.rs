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
pub use photon::{PackedUnit, Photon, PhotonTag};
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
    /// Irradiance estimated in advance at every [`PRECOMPUTED_STRIDE`]th photon (Christensen,
    /// "Faster photon map global illumination", JGT 1999): the nearest such photon on the same
    /// side answers a lookup, one nearest-neighbour search instead of a density estimate.
    pub precomputed: Option<Precomputed>,
    /// How it was traced.
    pub stats: TraceStats,
    /// Seconds spent tracing and building it.
    pub seconds: f64,
}

/// Where an irradiance estimate was made in advance: a photon's position and normal (compact,
/// for a fast nearest search).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimatePoint {
    /// Position.
    pub position: Vec3,
    /// The photon's normal.
    pub normal: Vec3,
}

impl kd_tree::Located for EstimatePoint {
    type Tag = PackedUnit;
    #[inline]
    fn key(&self) -> [f32; 3] {
        self.position.to_array()
    }
    #[inline]
    fn tag(&self) -> PackedUnit {
        PackedUnit::new(self.normal)
    }
}

/// Precomputed irradiance: for each point of `tree`, one estimate per bounce limit `0..C`
/// (photons of at most that many bounces, over the disc of the nearest photons of all
/// bounces), the last column all of the map's photons.
#[derive(Clone, Debug)]
pub struct Precomputed {
    /// Where the estimates were made.
    pub tree: KdTree<EstimatePoint>,
    /// `tree.len() × columns` estimates, row by row in tree order.
    pub irradiance: Vec<Rgb>,
    /// Radius of each estimate's disc.
    pub radii: Vec<f32>,
    /// Bounce limits per row.
    pub columns: usize,
}

/// One photon in this many gets its irradiance estimated in advance.
pub const PRECOMPUTED_STRIDE: usize = 4;

/// Bounce limits the precomputed table tells apart (beyond, all photons: by then their share
/// of the light is small).
const PRECOMPUTED_LIMITS: u16 = 16;

impl PhotonMap {
    /// Traces `wanted` photons of `kind` that serve paths of up to `max_bounces` bounces before
    /// they land, and builds their tree; with `precompute`, the irradiance at every
    /// [`PRECOMPUTED_STRIDE`]th photon with those lookups.
    #[must_use]
    pub fn build(
        scene: &Scene,
        kind: MapKind,
        wanted: u64,
        max_bounces: u16,
        seed: u64,
        precompute: Option<&Lookup>,
    ) -> Self {
        let cap = trace::MAX_EMITTED_PER_STORED;
        Self::build_within(scene, kind, (wanted, cap), max_bounces, seed, precompute)
    }

    /// [`PhotonMap::build`], emitting at most `emitted_per_stored` photons per photon wanted
    /// ([`trace::trace_photons_within`]).
    #[must_use]
    pub fn build_within(
        scene: &Scene,
        kind: MapKind,
        (wanted, emitted_per_stored): (u64, u64),
        max_bounces: u16,
        seed: u64,
        precompute: Option<&Lookup>,
    ) -> Self {
        let start = std::time::Instant::now();
        let (photons, stats) =
            trace::trace_photons_within(scene, kind, wanted, max_bounces, seed, emitted_per_stored);
        let tree = KdTree::build(photons);
        let precomputed = precompute
            .filter(|_| !tree.is_empty())
            .map(|lookup| precompute_irradiance(&tree, max_bounces, lookup));
        PhotonMap {
            kind,
            tree,
            max_bounces,
            precomputed,
            stats,
            seconds: start.elapsed().as_secs_f64(),
        }
    }

    /// Irradiance at `p` on the side of unit normal `n` from photons that landed after at most
    /// `max_bounces` bounces (see [`estimate`]): from the precomputed estimate nearest `p`
    /// where there is one, else a density estimate.
    #[must_use]
    pub fn irradiance(&self, p: Vec3, n: Vec3, max_bounces: u16, lookup: &Lookup) -> Rgb {
        self.irradiance_and_radius(p, n, max_bounces, lookup).0
    }

    /// [`PhotonMap::irradiance`] with the radius of the disc its photons came from.
    #[must_use]
    pub fn irradiance_and_radius(
        &self,
        p: Vec3,
        n: Vec3,
        max_bounces: u16,
        lookup: &Lookup,
    ) -> (Rgb, f32) {
        if let Some((row, radius)) = self.precomputed_row(p, n, lookup) {
            return (row[usize::from(max_bounces).min(row.len() - 1)], radius);
        }
        estimate::irradiance(&self.tree, p, n, max_bounces, lookup)
    }

    /// The precomputed estimates nearest `p` on the side of `n` (one per bounce limit) and
    /// their disc's radius; `None` where none lies within the lookup's reach.
    fn precomputed_row(&self, p: Vec3, n: Vec3, lookup: &Lookup) -> Option<(&[Rgb], f32)> {
        let pre = self.precomputed.as_ref()?;
        let radius2 = lookup.max_radius * lookup.max_radius;
        let same_side = |normal: &PackedUnit| normal.dot(n) > 0.5;
        let i = pre.tree.nearest_one(p.to_array(), radius2, &same_side)?;
        Some((
            &pre.irradiance[i * pre.columns..(i + 1) * pre.columns],
            pre.radii[i],
        ))
    }

    /// [`PhotonMap::irradiance_and_radius`] at `max_bounces` and at one and two bounces fewer,
    /// from the same estimate: what photons of exactly `max_bounces` (or one fewer) bounces bring
    /// is a difference.
    #[must_use]
    pub fn irradiance_by_last_bounces(
        &self,
        p: Vec3,
        n: Vec3,
        max_bounces: u16,
        lookup: &Lookup,
    ) -> ([Rgb; 3], f32) {
        if let Some((row, radius)) = self.precomputed_row(p, n, lookup) {
            let at = |fewer: u16| {
                max_bounces
                    .checked_sub(fewer)
                    .map_or(Rgb::ZERO, |b| row[usize::from(b).min(row.len() - 1)])
            };
            return ([at(0), at(1), at(2)], radius);
        }
        estimate::irradiance_by_last_bounces(&self.tree, p, n, max_bounces, lookup)
    }

    /// The caustic map of `wanted` photons of up to `max_bounces` bounces, on a stream of its
    /// own of `seed`; `None` when `wanted` is 0 or nothing was stored, so that the paths keep
    /// the light it would hold. Caustics are sharp and seen directly: estimated where they are
    /// asked for, never precomputed.
    #[must_use]
    pub fn caustic(scene: &Scene, wanted: u64, max_bounces: u16, seed: u64) -> Option<PhotonMap> {
        (wanted > 0)
            .then(|| {
                let seed = seed ^ CAUSTIC_SALT;
                PhotonMap::build(scene, MapKind::Caustic, wanted, max_bounces, seed, None)
            })
            .filter(|m| !m.tree.is_empty())
    }

    /// What making it did.
    #[must_use]
    pub fn summary(&self) -> MapSummary {
        MapSummary {
            kind: self.kind,
            stats: self.stats,
            seconds: self.seconds,
        }
    }
}

/// A photon map with its lookup size, as the cache in media reads it: the caustic map at the
/// Lambertian surfaces of its paths (see [`crate::integrators::volpath`]), the global map at its
/// records' gather hits (see [`crate::media_cache::scene_medium`]).
#[derive(Clone, Debug)]
pub struct ServingMap {
    /// The photons ([`trace`] says which a medium scatters).
    pub map: PhotonMap,
    /// Its lookups.
    pub lookup: Lookup,
}

impl ServingMap {
    /// Irradiance at `p` on the side of `n` from photons of at most `max_bounces` bounces.
    #[must_use]
    pub fn irradiance(&self, p: Vec3, n: Vec3, max_bounces: u16) -> Rgb {
        self.map.irradiance(p, n, max_bounces, &self.lookup)
    }

    /// [`Self::irradiance`] at `max_bounces` and at one and two bounces fewer, and the radius
    /// of the disc they came from ([`PhotonMap::irradiance_by_last_bounces`]).
    #[must_use]
    pub fn irradiance_by_last_bounces(
        &self,
        p: Vec3,
        n: Vec3,
        max_bounces: u16,
    ) -> ([Rgb; 3], f32) {
        self.map
            .irradiance_by_last_bounces(p, n, max_bounces, &self.lookup)
    }
}

/// Estimates the irradiance at every [`PRECOMPUTED_STRIDE`]th photon of `tree`, per bounce
/// limit.
fn precompute_irradiance(tree: &KdTree, max_bounces: u16, lookup: &Lookup) -> Precomputed {
    use rayon::prelude::*;
    let at = KdTree::build(
        tree.photons
            .iter()
            .step_by(PRECOMPUTED_STRIDE)
            .map(|ph| EstimatePoint {
                position: ph.position,
                normal: ph.normal,
            })
            .collect(),
    );
    let columns = usize::from(max_bounces.min(PRECOMPUTED_LIMITS)) + 1;
    let rows: Vec<(Vec<Rgb>, f32)> = at
        .photons
        .par_iter()
        .map(|ph| estimate::irradiance_by_bounces(tree, ph.position, ph.normal, columns, lookup))
        .collect();
    let radii = rows.iter().map(|(_, r)| *r).collect();
    let irradiance = rows.into_iter().flat_map(|(row, _)| row).collect();
    Precomputed {
        tree: at,
        irradiance,
        radii,
        columns,
    }
}

/// A bounce count as photons store it (`u32::MAX`, unbounded, and anything past `u16::MAX`
/// become `u16::MAX`).
#[must_use]
pub fn bounce_limit(bounces: u32) -> u16 {
    u16::try_from(bounces).unwrap_or(u16::MAX)
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

/// What making a map did, for reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapSummary {
    /// Which photons it keeps.
    pub kind: MapKind,
    /// How it was traced.
    pub stats: TraceStats,
    /// Seconds spent tracing and building it.
    pub seconds: f64,
}

impl std::fmt::Display for MapSummary {
    /// `Global map: N photons stored of M emitted, R M rays, S s`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:?} map: {} photons stored of {} emitted, {:.1} M rays, {:.2} s",
            self.kind,
            self.stats.stored,
            self.stats.emitted,
            self.stats.rays as f64 * 1e-6,
            self.seconds
        )
    }
}

impl std::fmt::Display for PhotonMap {
    /// See [`MapSummary`].
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.summary().fmt(f)
    }
}

impl PhotonMaps {
    /// Bytes the maps hold (their trees and precomputed estimates).
    #[must_use]
    pub fn bytes(&self) -> usize {
        let map = |m: &PhotonMap| {
            m.tree.bytes()
                + m.precomputed.as_ref().map_or(0, |p| {
                    p.tree.bytes()
                        + p.irradiance.capacity() * std::mem::size_of::<Rgb>()
                        + p.radii.capacity() * std::mem::size_of::<f32>()
                })
        };
        map(&self.global) + self.caustic.as_ref().map_or(0, map)
    }

    /// The global map, then the caustic map if there is one.
    pub fn maps(&self) -> impl Iterator<Item = &PhotonMap> {
        std::iter::once(&self.global).chain(&self.caustic)
    }

    /// Traces `global` photons of up to `max_bounces` bounces, their irradiance precomputed,
    /// and, when `caustic` > 0, that many caustic photons of up to `gather_bounces + 1` (a
    /// caustic lands one bounce nearer the camera than the gather hits of records), on
    /// independent streams of `seed`.
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
            Some(&global_lookup),
        );
        let caustic = PhotonMap::caustic(scene, caustic, gather_bounces.saturating_add(1), seed);
        PhotonMaps {
            global: global_map,
            caustic,
            global_lookup,
            caustic_lookup,
        }
    }
}

const CAUSTIC_SALT: u64 = 0x0063_6175_7374_6963;
