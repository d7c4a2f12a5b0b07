//! Irradiance from photons by density estimation (Jensen, *Realistic Image Synthesis Using
//! Photon Mapping*, eq. 7.6 with `cos`-free flux): `E(x) ≈ Σ Φ_p / (π r²)` over the `k` photons
//! nearest to `x` that landed on the same side of the same surface, `r` the distance to the
//! farthest of them, or the largest radius when fewer are found there.
//!
//! A photon counts when its stored normal is within 60° of the query's (`n_p · n > ½`: the
//! same side of a thin wall, not the neighbouring wall of a corner) and it arrived from above
//! the query's surface.

use super::kd_tree::{KdTree, Neighbour};
use super::photon::Photon;
use crate::lights::is_positive_finite;
use ircache_math::{Rgb, Vec3};
use std::cell::RefCell;

/// How many photons a lookup takes and how far it looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lookup {
    /// Photons per estimate.
    pub count: usize,
    /// Largest radius searched (world units).
    pub max_radius: f32,
}

thread_local! {
    static FOUND: RefCell<Vec<Neighbour>> = const { RefCell::new(Vec::new()) };
}

/// Calls `f` with the photons a density estimate at `p` takes (the `lookup.count` nearest that
/// `accept`, within the largest radius) and the squared radius of their disc: the farthest
/// one's, or the largest radius when fewer are found. `None` for an empty disc.
fn with_disc<T>(
    tree: &KdTree,
    p: Vec3,
    accept: &dyn Fn(&Photon) -> bool,
    lookup: &Lookup,
    f: impl FnOnce(&[Neighbour], f32) -> T,
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
        is_positive_finite(r2).then(|| f(found, r2))
    })
}

/// A photon lands on the side of `n` of the same surface: normals within 60°, arriving from
/// above.
#[inline]
fn same_side(ph: &Photon, n: Vec3) -> bool {
    ph.normal.dot(n) > 0.5 && ph.incoming.dot(n) > 0.0
}

/// `E(p)` for each bounce limit `0..columns` (the last: every photon), over the one disc of the
/// `lookup.count` nearest photons of any bounces.
#[must_use]
pub fn irradiance_by_bounces(
    tree: &KdTree,
    p: Vec3,
    n: Vec3,
    columns: usize,
    lookup: &Lookup,
) -> Vec<Rgb> {
    let mut by = vec![Rgb::ZERO; columns];
    with_disc(tree, p, &|ph| same_side(ph, n), lookup, |found, r2| {
        for f in found {
            let ph = &tree.photons[f.index as usize];
            by[usize::from(ph.bounces).min(columns - 1)] += ph.flux;
        }
        let norm = 1.0 / (std::f32::consts::PI * r2);
        let mut acc = Rgb::ZERO;
        for e in &mut by {
            acc += *e * norm;
            *e = acc;
        }
    });
    by
}

/// `E(p)` on the side of unit normal `n` from photons of at most `max_bounces` bounces.
#[must_use]
pub fn irradiance(tree: &KdTree, p: Vec3, n: Vec3, max_bounces: u16, lookup: &Lookup) -> Rgb {
    let accept = |ph: &Photon| ph.bounces <= max_bounces && same_side(ph, n);
    with_disc(tree, p, &accept, lookup, |found, r2| {
        let sum = found
            .iter()
            .fold(Rgb::ZERO, |s, f| s + tree.photons[f.index as usize].flux);
        sum / (std::f32::consts::PI * r2)
    })
    .unwrap_or(Rgb::ZERO)
}
