//! Where light goes through media: free-flight sampling by delta tracking with spectral weights
//! (Kutz et al. 2017: scattering or a null collision chosen by channel-mean probabilities, the
//! path weight corrected per channel, absorption carried as a weight), emission gathered by the collision estimator (β σ_a L_e / σ̄ at every
//! tentative collision), and transmittance in closed form (homogeneous) or by ratio tracking
//! (grids), both against local majorants in grids ([`super::majorant`]). [`transmittance_along`] follows a shadow ray through `null` boundaries, changing
//! medium where a shape declares one (Mitsuba 3's `target_medium`).

use super::{Coefficients, Medium};
use crate::integrators::RayCounts;
use crate::scene::{Interaction, Scene};
use ircache_math::{offset_ray_origin, Ray, Rgb, Rng, Vec3};
use ircache_scene::MediumInterface;

/// Most null boundaries a ray crosses before it is taken as blocked (a guard against rays
/// trapped between coincident surfaces).
pub const MAX_CROSSINGS: u32 = 256;

/// What free-flight sampling found on a segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Flight {
    /// No real collision before the segment's end.
    Passed,
    /// Absorbed: the path ends.
    Absorbed,
    /// A scattering event at distance `t`.
    Scattered {
        /// Distance along the ray.
        t: f32,
        /// The coefficients there.
        coefficients: Coefficients,
    },
}

/// A distance drawn with density σ̄ e^{−σ̄ t}.
#[inline]
fn exponential(rng: &mut Rng, majorant: f32) -> f32 {
    -(1.0 - rng.next_f32()).ln() / majorant
}

/// Tentative collisions along `o + t d` for t in `[t0, t1]`: distances drawn against each
/// piece's majorant ([`Medium::for_each_segment`]), `f(t, coefficients, majorant)` called at each
/// in order until it returns false. The one sampling loop of delta and ratio tracking.
fn for_each_tentative_collision(
    medium: &Medium,
    (o, d): (Vec3, Vec3),
    (t0, t1): (f32, f32),
    rng: &mut Rng,
    mut f: impl FnMut(f32, Coefficients, f32, &mut Rng) -> bool,
) {
    medium.for_each_segment(o, d, t0, t1, |a, b, majorant| {
        if majorant <= 0.0 {
            return true;
        }
        let mut t = a;
        loop {
            t += exponential(rng, majorant);
            if t >= b || !t.is_finite() {
                return true;
            }
            if !f(t, medium.at(o + d * t), majorant, rng) {
                return false;
            }
        }
    });
}

/// Samples the first real collision along `o + t d`, `t < t_max`, updating the path weight
/// `beta` and adding the medium's emission met on the way (weighted by `beta`) to `emitted`.
pub fn sample_flight(
    medium: &Medium,
    o: Vec3,
    d: Vec3,
    t_max: f32,
    beta: &mut Rgb,
    emitted: &mut Rgb,
    rng: &mut Rng,
) -> Flight {
    let Some((t0, t1)) = medium.clip(o, d, t_max) else {
        return Flight::Passed;
    };
    let emits = medium.emits();
    let mut flight = Flight::Passed;
    for_each_tentative_collision(medium, (o, d), (t0, t1), rng, |t, c, majorant, rng| {
        if emits {
            *emitted += *beta * c.sigma_a() * c.emission / majorant;
        }
        let sigma_n = (Rgb::splat(majorant) - c.sigma_t).max(Rgb::ZERO);
        // Absorption is a weight, not an event (Mitsuba's albedo factor): scattering and null
        // collisions are chosen by their channel means, the weights correct each channel.
        let (ps, pn) = (c.sigma_s.mean(), sigma_n.mean());
        if ps + pn <= 0.0 {
            flight = Flight::Absorbed;
            return false;
        }
        if rng.next_f32() * (ps + pn) < ps {
            *beta *= c.sigma_s * ((ps + pn) / (ps * majorant));
            flight = Flight::Scattered { t, coefficients: c };
            return false;
        }
        *beta *= sigma_n * ((ps + pn) / (pn * majorant));
        if beta.is_black() {
            flight = Flight::Absorbed;
            return false;
        }
        true
    });
    flight
}

/// Transmittance along `o + t d` for `t` in `[0, t_max]` inside `medium`: closed form where σ_t
/// is constant, ratio tracking (Cramer 1978; Novák et al. 2014) in grids.
pub fn transmittance(medium: &Medium, o: Vec3, d: Vec3, t_max: f32, rng: &mut Rng) -> Rgb {
    let Some((t0, t1)) = medium.clip(o, d, t_max) else {
        return Rgb::ONE;
    };
    if medium.homogeneous {
        let sigma_t = medium.at(o + d * t0).sigma_t;
        return (sigma_t * -(t1 - t0))
            .exp()
            .map(|x| if x.is_nan() { 0.0 } else { x });
    }
    let mut tr = Rgb::ONE;
    for_each_tentative_collision(medium, (o, d), (t0, t1), rng, |_, c, majorant, rng| {
        tr *= (Rgb::ONE - c.sigma_t / majorant).max(Rgb::ZERO);
        // Russian roulette once the estimate is small keeps long rays cheap and unbiased.
        let m = tr.max_channel();
        if m < 0.1 {
            if rng.next_f32() >= m {
                tr = Rgb::ZERO;
                return false;
            }
            tr /= m;
        }
        true
    });
    tr
}

/// The medium a ray is in after crossing a surface with `interface` and geometric normal `ng`
/// along `d`, coming from `current`.
#[inline]
#[must_use]
pub fn medium_after(
    interface: MediumInterface,
    ng: Vec3,
    d: Vec3,
    current: Option<usize>,
) -> Option<usize> {
    if !interface.is_transition() {
        current
    } else if d.dot(ng) > 0.0 {
        interface.exterior
    } else {
        interface.interior
    }
}

/// The first opaque surface a ray meets, past any null boundaries.
#[derive(Clone, Copy, Debug)]
pub struct OpaqueHit {
    /// The interaction, on the last ray segment.
    pub it: Interaction,
    /// Where that segment starts (the ray's origin when no boundary was crossed).
    pub segment_origin: Vec3,
    /// The medium in front of the surface.
    pub medium: Option<usize>,
}

/// The first opaque surface along `ray` from a point in `medium`, passing through null
/// boundaries (each segment after a crossing starts at the crossing, offset, in the same
/// direction); `crossed(segment origin, crossing, medium beyond)` hears of every boundary and
/// `intersections` counts the rays traced. `None` when the ray escapes (or stays trapped past
/// [`MAX_CROSSINGS`]).
pub fn first_opaque(
    scene: &Scene,
    mut ray: Ray,
    mut medium: Option<usize>,
    intersections: &mut u64,
    mut crossed: impl FnMut(Vec3, &Interaction, Option<usize>),
) -> Option<OpaqueHit> {
    for _ in 0..MAX_CROSSINGS {
        *intersections += 1;
        let hit = scene.accel.intersect(&ray)?;
        let it = scene.interaction(&ray, &hit);
        let shape = &scene.shapes[it.shape as usize];
        if !shape.null {
            return Some(OpaqueHit {
                it,
                segment_origin: ray.o,
                medium,
            });
        }
        medium = medium_after(shape.media, it.ng, ray.d, medium);
        crossed(ray.o, &it, medium);
        ray = scene.spawn_ray(&it, ray.d);
    }
    None
}

/// Transmittance along a shadow ray from `ray.o` (in `medium`) to `ray.t_max`, passing through
/// null boundaries; zero when an opaque surface is in the way.
pub fn transmittance_along(
    scene: &Scene,
    mut ray: Ray,
    mut medium: Option<usize>,
    rng: &mut Rng,
    rays: &mut RayCounts,
) -> Rgb {
    let mut tr = Rgb::ONE;
    let end = ray.t_max.is_finite().then(|| ray.at(ray.t_max));
    for _ in 0..MAX_CROSSINGS {
        rays.shadow += 1;
        let hit = scene.accel.intersect(&ray);
        let segment = hit.as_ref().map_or(ray.t_max, |h| h.t);
        if let Some(m) = medium {
            tr *= transmittance(&scene.media[m], ray.o, ray.d, segment, rng);
            if tr.is_black() {
                return Rgb::ZERO;
            }
        }
        let Some(hit) = hit else {
            return tr;
        };
        let shape = &scene.shapes[hit.geom_id as usize];
        if !shape.null {
            return Rgb::ZERO;
        }
        medium = medium_after(shape.media, hit.ng, ray.d, medium);
        let p = ray.at(hit.t);
        let o = offset_ray_origin(p, hit.ng.normalize_or(ray.d), ray.d, scene.scale);
        // Aimed from the offset origin at the same end point (as `Scene::shadow_ray`): a ray
        // kept parallel would pass the end at the offset's distance and, after a grazing
        // crossing, reach the light's own surface before it.
        match end {
            Some(end) => {
                let to_end = end - o;
                let left = to_end.length();
                if left <= 0.0 || to_end.dot(ray.d) <= 0.0 {
                    return tr;
                }
                ray = Ray {
                    o,
                    d: to_end / left,
                    t_min: 0.0,
                    t_max: left,
                };
            }
            None => ray = Ray::new(o, ray.d),
        }
    }
    Rgb::ZERO
}
