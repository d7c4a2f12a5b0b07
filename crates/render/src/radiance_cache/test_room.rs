//! A closed-form room for the radiance cache's tests: no ray tracer involved. Seen from the floor
//! z = 0: a ceiling at z = 1 whose radiance is 3 over the square [−0.3, 0.5]² and 0.5 elsewhere,
//! and a black occluding square [0.2, 0.9] × [−0.6, 0.1] at z = 0.4.

use crate::irradiance_cache::hemisphere::{HemisphereSamples, Stratification};
use ircache_math::{DMat3, DVec3, Rgb, Rng};

/// Radiance and distance along the unit direction `d` from `p`.
pub fn room(p: DVec3, d: DVec3) -> (f64, f64) {
    if d.z <= 0.0 {
        return (0.0, f64::INFINITY);
    }
    let t = (0.4 - p.z) / d.z;
    let q = p + d * t;
    if t > 0.0 && (0.2..=0.9).contains(&q.x) && (-0.6..=0.1).contains(&q.y) {
        return (0.0, t);
    }
    let t = (1.0 - p.z) / d.z;
    let q = p + d * t;
    let bright = (-0.3..=0.5).contains(&q.x) && (-0.3..=0.5).contains(&q.y);
    (if bright { 3.0 } else { 0.5 }, t)
}

/// A gather at `p` in `frame` ([t b n] columns): one jittered direction per cell, radiance
/// (L, L/2, L/4) so the channels differ.
pub fn gather(p: DVec3, frame: DMat3, strata: Stratification, seed: u64) -> HemisphereSamples {
    let mut s = HemisphereSamples::new(strata);
    let mut rng = Rng::new(seed, 3);
    let mut cells = Vec::new();
    strata.for_each_direction(|_, _| rng.next_2d(), |j, k, _, d| cells.push((j, k, d)));
    for (j, k, d) in cells {
        let (l, r) = room(p, frame * d.as_dvec3().normalize());
        let cell = j * strata.azimuthal + k;
        s.radiance[cell] = Rgb::new(l as f32, (0.5 * l) as f32, (0.25 * l) as f32);
        s.distance[cell] = r as f32;
    }
    s
}
