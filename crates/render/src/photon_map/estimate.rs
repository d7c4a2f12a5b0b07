//! Irradiance from photons by density estimation (Jensen, *Realistic Image Synthesis Using
//! Photon Mapping*, eq. 7.6 with `cos`-free flux): `E(x) ≈ Σ Φ_p / (π r²)` over the `k` photons
//! nearest to `x` that landed on the same side of the same surface, `r` the distance to the
//! farthest of them, or the largest radius when fewer are found there.
//!
//! A photon counts when its stored normal is within 60° of the query's (`n_p · n > ½`: the
//! same side of a thin wall, not the neighbouring wall of a corner) and it arrived from above
//! the query's surface.
//!
//! At an edge or a corner the photons fill only part of the disc, and the disc's area darkens
//! the estimate there (Jensen's boundary bias; gather rays meet such places often). Where the
//! photons' convex hull on the tangent plane, corrected by Efron's identity ([`super::hull`]),
//! covers clearly less than the disc (under 70 %: ten times the corrected hull's spread at a
//! hundred photons), it takes the disc's place, for smooth light only ([`Lookup::hull`]).

use super::hull::corrected_area_on_plane;
use super::kd_tree::{KdTree, Neighbour};
use super::photon::PhotonTag;
use crate::lights::is_positive_finite;
use ircache_math::{Frame, Rgb, Vec3};
use std::cell::RefCell;

/// How many photons a lookup takes and how far it looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lookup {
    /// Photons per estimate.
    pub count: usize,
    /// Largest radius searched (world units).
    pub max_radius: f32,
    /// Where the photons cover clearly less than their disc, divide by their corrected hull's
    /// area (smooth light: the global map); a caustic's photons crowd where it is bright, and
    /// their hull would concentrate it further.
    pub hull: bool,
}

thread_local! {
    static FOUND: RefCell<Vec<Neighbour>> = const { RefCell::new(Vec::new()) };
}

/// Calls `f` with the photons a density estimate at `p` takes (the `lookup.count` nearest that
/// `accept`, within the largest radius) and the area they cover: their disc's (out to the
/// farthest, or the largest radius when fewer are found), or their corrected hull's where that
/// is clearly smaller. `None` for an empty disc.
fn with_disc<T>(
    tree: &KdTree,
    p: Vec3,
    n: Vec3,
    accept: &dyn Fn(&PhotonTag) -> bool,
    lookup: &Lookup,
    f: impl FnOnce(&[Neighbour], f32, f32) -> T,
) -> Option<T> {
    if tree.is_empty() || lookup.count == 0 {
        return None;
    }
    FOUND.with_borrow_mut(|found| {
        let max2 = lookup.max_radius * lookup.max_radius;
        tree.nearest(p.to_array(), lookup.count, max2, accept, found);
        let r2 = if found.len() == lookup.count {
            found.last().map_or(max2, |n| n.distance2)
        } else {
            max2
        };
        if !is_positive_finite(r2) {
            return None;
        }
        let area = covered_area(tree, found, p, n, r2, lookup.hull);
        Some(f(found, area, r2.sqrt()))
    })
}

/// Fewest photons whose hull is trusted (E.4's table: the corrected hull's spread is 11 % at
/// 30, 36 % at 10).
const HULL_MIN_PHOTONS: usize = 30;

/// The area the disc's photons cover: `π r²`, or their corrected hull where it is clearly
/// smaller (see the module documentation).
fn covered_area(tree: &KdTree, found: &[Neighbour], p: Vec3, n: Vec3, r2: f32, hull: bool) -> f32 {
    let disc = std::f32::consts::PI * r2;
    if !hull || found.len() < HULL_MIN_PHOTONS {
        return disc;
    }
    let positions = found
        .iter()
        .map(|f| tree.photons[f.index as usize].position);
    let covered = corrected_area_on_plane(&Frame::from_z(n), p, positions);
    if covered > 0.0 && covered < 0.7 * disc {
        covered
    } else {
        disc
    }
}

/// A photon lands on the side of `n` of the same surface: normals within 60°, arriving from
/// above.
#[inline]
#[must_use]
pub fn same_side(ph: &PhotonTag, n: Vec3) -> bool {
    ph.normal.dot(n) > 0.5 && ph.incoming.dot(n) > 0.0
}

/// `E(p)` for each bounce limit `0..columns` (the last: every photon), over the one disc of the
/// `lookup.count` nearest photons of any bounces, and the disc's radius.
#[must_use]
pub fn irradiance_by_bounces(
    tree: &KdTree,
    p: Vec3,
    n: Vec3,
    columns: usize,
    lookup: &Lookup,
) -> (Vec<Rgb>, f32) {
    let mut by = vec![Rgb::ZERO; columns];
    let mut radius = lookup.max_radius;
    with_disc(
        tree,
        p,
        n,
        &|ph| same_side(ph, n),
        lookup,
        |found, area, r| {
            radius = r;
            for f in found {
                let ph = &tree.photons[f.index as usize];
                by[usize::from(ph.bounces).min(columns - 1)] += ph.flux;
            }
            let norm = 1.0 / area;
            let mut acc = Rgb::ZERO;
            for e in &mut by {
                acc += *e * norm;
                *e = acc;
            }
        },
    );
    (by, radius)
}

/// `E(p)` on the side of unit normal `n` from photons of at most `max_bounces` bounces, and the
/// radius of the disc it took them from.
#[must_use]
pub fn irradiance(
    tree: &KdTree,
    p: Vec3,
    n: Vec3,
    max_bounces: u16,
    lookup: &Lookup,
) -> (Rgb, f32) {
    let accept = |ph: &PhotonTag| ph.bounces() <= max_bounces && same_side(ph, n);
    with_disc(tree, p, n, &accept, lookup, |found, area, r| {
        let sum = found
            .iter()
            .fold(Rgb::ZERO, |s, f| s + tree.photons[f.index as usize].flux);
        (sum / area, r)
    })
    .unwrap_or((Rgb::ZERO, lookup.max_radius))
}

/// [`irradiance`] at `max_bounces` and, over the same disc, from the photons of one and of two
/// bounces fewer at most.
#[must_use]
pub fn irradiance_by_last_bounces(
    tree: &KdTree,
    p: Vec3,
    n: Vec3,
    max_bounces: u16,
    lookup: &Lookup,
) -> ([Rgb; 3], f32) {
    let accept = |ph: &PhotonTag| ph.bounces() <= max_bounces && same_side(ph, n);
    with_disc(tree, p, n, &accept, lookup, |found, area, r| {
        let mut sums = [Rgb::ZERO; 3];
        for f in found {
            let photon = &tree.photons[f.index as usize];
            for (fewer, sum) in sums.iter_mut().enumerate() {
                if u32::from(photon.bounces) + fewer as u32 <= u32::from(max_bounces) {
                    *sum += photon.flux;
                }
            }
        }
        (sums.map(|s| s / area), r)
    })
    .unwrap_or(([Rgb::ZERO; 3], lookup.max_radius))
}
