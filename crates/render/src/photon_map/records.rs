//! Photon-mapped irradiance caching (001 ch. 6, NOTES-001 E): irradiance records computed from
//! the photons around them instead of gather rays.
//!
//! - [`photon_record`] is Algorithm 7: the harmonic mean `h` of the nearest photons' flight
//!   distances sets the zone radius `a·h` (4.4); the photons of the zone (same side, bounces
//!   within the depth) give `E = Σ Φ / Â` (6.2) over their Efron-corrected hull area
//!   ([`super::hull`]); binned by arrival direction into Ward's cells of equal projected solid
//!   angle, `L_jk = Φ_jk / (Â π / MN)` (6.5–6.11 for those cells), from which the rotational
//!   and translational gradients follow as for a gathered record (000 eqs. 3.29, 3.48), each
//!   cell at the harmonic mean distance of its photons (NOTES-001 E.3 [P]; empty cells at
//!   their neighbours').
//! - [`place_records`] is Algorithm 6: photons in their stored order, a record wherever no
//!   record reaches yet.
//!
//! Photons straight from the emitters are never in the global map (the direct light is
//! sampled), and caustic photons are left out when a caustic map serves caustics.

use super::estimate::same_side;
use super::hull::corrected_area_on_plane;
use super::kd_tree::{KdTree, Neighbour};
use super::photon::{Photon, PhotonTag};
use crate::irradiance_cache::hemisphere::{to_world, HemisphereSamples, Stratification};
use crate::irradiance_cache::record::{ErrorMetric, Record, NO_RADIANCE};
use crate::irradiance_cache::store::RecordStore;
use crate::lights::is_positive_finite;
use ircache_math::{Frame, Rgb, Vec3};

/// What records are made from and how far they reach.
#[derive(Clone, Copy, Debug)]
pub struct PhotonRecordSettings {
    /// Accuracy `a`: the zone radius is `a·h`.
    pub accuracy: f32,
    /// Photons of the first query (for `h`).
    pub lookup: usize,
    /// Smallest and largest zone radius.
    pub zone_limits: (f32, f32),
    /// Photons of more bounces are left out.
    pub max_bounces: u16,
    /// Leave caustic photons out (a caustic map serves them).
    pub without_caustics: bool,
    /// The store's metric: the record's radius is set so that it reaches the zone's radius.
    pub metric: ErrorMetric,
}

/// Harmonic mean of the photons' flight distances, `n / Σ 1/dᵢ` (NOTES-001 E.3).
fn harmonic_mean(tree: &KdTree, found: &[Neighbour]) -> f32 {
    let inv: f64 = found
        .iter()
        .map(|f| {
            1.0 / f64::from(
                tree.photons[f.index as usize]
                    .distance
                    .max(f32::MIN_POSITIVE),
            )
        })
        .sum();
    if inv > 0.0 {
        (found.len() as f64 / inv) as f32
    } else {
        f32::INFINITY
    }
}

/// The cells a record of `photons` photons bins them into: about eight photons a cell, at least
/// 2 × 6 cells, at most 16 × 50.
#[must_use]
pub fn cells_for(photons: usize) -> Stratification {
    let s = Stratification::from_divisions((photons / 8).clamp(12, 800));
    Stratification {
        polar: s.polar.max(2),
        azimuthal: s.azimuthal.max(6),
    }
}

/// The photons of a zone binned into the cells of `frame`'s hemisphere, as radiance over the
/// zone's area `area` (6.11), each cell at the harmonic mean distance of its photons.
#[must_use]
pub fn bin_photons(
    photons: &[&Photon],
    frame: &Frame,
    area: f32,
    strata: Stratification,
) -> HemisphereSamples {
    let (m, n) = (strata.polar, strata.azimuthal);
    let mut h = HemisphereSamples::new(strata);
    let mut inverse_distance = vec![0.0f64; strata.cells()];
    let mut count = vec![0u32; strata.cells()];
    let mut flux = vec![Rgb::ZERO; strata.cells()];
    for ph in photons {
        let local = frame.to_local(ph.incoming);
        if local.z <= 0.0 {
            continue;
        }
        let sin2 = (1.0 - local.z * local.z).max(0.0);
        let j = ((sin2 * m as f32) as usize).min(m - 1);
        let phi = local.y.atan2(local.x).rem_euclid(std::f32::consts::TAU);
        let k = ((phi / std::f32::consts::TAU * n as f32) as usize).min(n - 1);
        let c = j * n + k;
        flux[c] += ph.flux;
        inverse_distance[c] += 1.0 / f64::from(ph.distance.max(f32::MIN_POSITIVE));
        count[c] += 1;
    }
    // Φ_jk = E_jk A and E_jk = L_jk ∫_cell cos θ dω = L_jk π/(MN).
    let to_radiance = strata.cells() as f32 / (std::f32::consts::PI * area);
    for c in 0..strata.cells() {
        h.radiance[c] = flux[c] * to_radiance;
        if count[c] > 0 {
            h.distance[c] = (f64::from(count[c]) / inverse_distance[c]) as f32;
        }
    }
    // Empty cells take the mean distance of their non-empty neighbours (NOTES-001 E.3).
    let filled = h.distance.clone();
    for j in 0..m {
        for k in 0..n {
            if count[j * n + k] > 0 {
                continue;
            }
            let mut near = [(j, (k + 1) % n), (j, (k + n - 1) % n)].to_vec();
            if j > 0 {
                near.push((j - 1, k));
            }
            if j + 1 < m {
                near.push((j + 1, k));
            }
            let d: Vec<f32> = near
                .into_iter()
                .map(|(a, b)| filled[a * n + b])
                .filter(|d| d.is_finite())
                .collect();
            if !d.is_empty() {
                h.distance[j * n + k] = d.iter().sum::<f32>() / d.len() as f32;
            }
        }
    }
    h
}

/// The photons of a zone around `p` (unit normal `n`) in [`cells_for`] their number, over
/// their Efron-corrected hull area on the tangent plane; `None` for a degenerate hull.
/// `irradiance()` of the cells is 6.2's `Σ Φ / Â`.
#[must_use]
pub fn zone_cells(photons: &[&Photon], p: Vec3, n: Vec3) -> Option<(Frame, HemisphereSamples)> {
    let frame = Frame::from_z(n);
    let area = corrected_area_on_plane(&frame, p, photons.iter().map(|ph| ph.position));
    if !is_positive_finite(area) {
        return None;
    }
    Some((
        frame,
        bin_photons(photons, &frame, area, cells_for(photons.len())),
    ))
}

/// Algorithm 7: the record at `p` (unit normal `n`, the side photons land on), or `None` where
/// fewer than three photons lie in its zone.
#[must_use]
pub fn photon_record(
    tree: &KdTree,
    p: Vec3,
    n: Vec3,
    settings: &PhotonRecordSettings,
    found: &mut Vec<Neighbour>,
) -> Option<Record> {
    let accept = |ph: &PhotonTag| {
        ph.bounces() <= settings.max_bounces
            && !(settings.without_caustics && ph.caustic())
            && same_side(ph, n)
    };
    let (lo, hi) = settings.zone_limits;
    tree.nearest(p.to_array(), settings.lookup, hi * hi, &accept, found);
    if found.len() < settings.lookup {
        return None;
    }
    let h = harmonic_mean(tree, found);
    // The zone holds at least the first query's photons: where a·h would hold fewer, their
    // noise, not the geometry, would set the record's error ([P], not in the thesis).
    let nearest = found.last().map_or(0.0, |f| f.distance2.sqrt());
    let mut zone = (settings.accuracy * h).max(nearest).clamp(lo, hi);
    tree.nearest(p.to_array(), usize::MAX, zone * zone, &accept, found);
    // The zone's own photons may see nearer surfaces: the zone shrinks with them (E.3 [P]).
    let h2 = harmonic_mean(tree, found);
    if h2 < h {
        zone = (settings.accuracy * h2).max(nearest).clamp(lo, hi);
        found.retain(|f| f.distance2 <= zone * zone);
    }
    if found.len() < 3 {
        return None;
    }
    let photons: Vec<&Photon> = found
        .iter()
        .map(|f| &tree.photons[f.index as usize])
        .collect();
    let (frame, cells) = zone_cells(&photons, p, n)?;
    let e = cells.irradiance();
    let mut grad_t = to_world(
        &cells.translational_gradient_ward_heckbert(),
        frame.s,
        frame.t,
    );
    // Gradient limit (003 item 4): no channel may be predicted to change by more than itself
    // within the zone.
    for c in 0..3 {
        let g = grad_t[c].length() * zone;
        if g > e[c] {
            grad_t[c] *= if g > 0.0 { e[c] / g } else { 0.0 };
        }
    }
    let grad_r = to_world(&cells.rotational_gradient(), frame.s, frame.t);
    // R such that the record reaches as far as its zone under the store's metric.
    let per_unit = settings.metric.validity_radius(
        &Record {
            r: 1.0,
            ..empty_record(p, n)
        },
        settings.accuracy,
    );
    Some(Record {
        e,
        r: zone / per_unit,
        grad_t,
        grad_r,
        ray_variance: 1.0,
        ..empty_record(p, n)
    })
}

fn empty_record(p: Vec3, n: Vec3) -> Record {
    Record {
        p,
        n,
        e: Rgb::ZERO,
        r: 1.0,
        grad_t: [Vec3::ZERO; 3],
        grad_r: [Vec3::ZERO; 3],
        level: 0,
        ray_variance: 0.0,
        radiance: NO_RADIANCE,
    }
}

/// What [`place_records`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PlacementStats {
    /// Photons visited.
    pub visited: u64,
    /// Records made.
    pub records: u64,
    /// Photons where a record was due but its zone held too few photons.
    pub skipped: u64,
}

/// Algorithm 6: walks the photons in their stored order and makes a record at each one that no
/// record of `store` reaches yet (photons that `settings` leave out make none).
pub fn place_records(
    tree: &KdTree,
    store: &mut RecordStore,
    settings: &PhotonRecordSettings,
) -> PlacementStats {
    let mut stats = PlacementStats::default();
    let mut found = Vec::new();
    for ph in &tree.photons {
        if ph.bounces > settings.max_bounces || (settings.without_caustics && ph.caustic) {
            continue;
        }
        stats.visited += 1;
        let covered = store
            .interpolate(ph.position, ph.normal, ph.normal, 1.0, Default::default())
            .is_some();
        if covered {
            continue;
        }
        match photon_record(tree, ph.position, ph.normal, settings, &mut found) {
            Some(rec) => {
                store.insert(rec);
                stats.records += 1;
            }
            None => stats.skipped += 1,
        }
    }
    stats
}
