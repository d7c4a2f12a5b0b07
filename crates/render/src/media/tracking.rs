//! Where light goes through media: free-flight sampling by delta tracking with spectral weights
//! (Kutz et al. 2017: scattering or a null collision chosen by channel-mean probabilities, the
//! path weight corrected per channel, absorption carried as a weight), emission gathered by the collision estimator (β σ_a L_e / σ̄ at every
//! tentative collision), and transmittance in closed form (homogeneous) or by ratio tracking
//! (grids), both against local majorants in grids ([`super::majorant`]). [`transmittance_along`] follows a shadow ray through `null` boundaries, changing
//! medium where a shape declares one (Mitsuba 3's `target_medium`).

use super::{Coefficients, Medium};
use crate::integrators::RayCounts;
use crate::scene::{ray_on_to, Interaction, Scene};
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

/// The medium containing `p`: a ray along `dir` to the first surface that bounds a medium tells
/// by its facing; where none is met, the camera's medium (the one around the scene).
#[must_use]
pub fn medium_at(scene: &Scene, p: Vec3, dir: Vec3) -> Option<usize> {
    let mut ray = Ray::new(p, dir);
    for _ in 0..MAX_CROSSINGS {
        let Some(hit) = scene.accel.intersect(&ray) else {
            return scene.camera_medium;
        };
        let shape = &scene.shapes[hit.geom_id as usize];
        if shape.media.is_transition() {
            // Leaving through the front (along the normal): inside, the interior.
            return if dir.dot(hit.ng) > 0.0 {
                shape.media.interior
            } else {
                shape.media.exterior
            };
        }
        let q = ray.at(hit.t);
        ray = Ray::new(
            offset_ray_origin(q, hit.ng.normalize_or(dir), dir, scene.scale),
            dir,
        );
    }
    scene.camera_medium
}

/// The ray on past the `null` boundary at `it` along `d` (no bounce), with the medium beyond;
/// `None` once `crossings`, which counts them, passes [`MAX_CROSSINGS`].
#[must_use]
pub fn across_boundary(
    scene: &Scene,
    it: &Interaction,
    d: Vec3,
    medium: Option<usize>,
    crossings: &mut u32,
) -> Option<(Ray, Option<usize>)> {
    *crossings += 1;
    if *crossings > MAX_CROSSINGS {
        return None;
    }
    let shape = &scene.shapes[it.shape as usize];
    Some((
        scene.spawn_ray(it, d),
        medium_after(shape.media, it.ng, d, medium),
    ))
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
    ray: Ray,
    medium: Option<usize>,
    rng: &mut Rng,
    rays: &mut RayCounts,
) -> Rgb {
    transmittance_crossing(scene, ray, medium, rng, rays, |_| {})
}

/// What a shadow ray met, told as it goes.
#[derive(Clone, Copy, Debug)]
enum Passage {
    /// A piece `[0, length]` along `o + t d` in `medium`, `start` from the ray's origin, with
    /// the geometric normals of the null boundaries it began and ended at, if any.
    Segment {
        medium: usize,
        o: Vec3,
        d: Vec3,
        length: f32,
        start: f32,
        from_boundary: Option<Vec3>,
        to_boundary: Option<Vec3>,
    },
    /// A null boundary, `t` from the ray's origin, with its geometric normal, the ray's
    /// direction there and the media before and after.
    Boundary {
        t: f32,
        ng: Vec3,
        d: Vec3,
        media: (Option<usize>, Option<usize>),
    },
}

/// [`transmittance_along`], telling `visit` of each medium segment and null boundary passed.
fn transmittance_crossing(
    scene: &Scene,
    mut ray: Ray,
    mut medium: Option<usize>,
    rng: &mut Rng,
    rays: &mut RayCounts,
    mut visit: impl FnMut(Passage),
) -> Rgb {
    let mut tr = Rgb::ONE;
    let start = ray.o;
    let end = ray.t_max.is_finite().then(|| ray.at(ray.t_max));
    let mut from_boundary = None;
    for _ in 0..MAX_CROSSINGS {
        rays.shadow += 1;
        let hit = scene.accel.intersect(&ray);
        let segment = hit.as_ref().map_or(ray.t_max, |h| h.t);
        if let Some(m) = medium {
            tr *= transmittance(&scene.media[m], ray.o, ray.d, segment, rng);
            if tr.is_black() {
                return Rgb::ZERO;
            }
            visit(Passage::Segment {
                medium: m,
                o: ray.o,
                d: ray.d,
                length: segment,
                start: (ray.o - start).length(),
                from_boundary,
                to_boundary: hit.as_ref().map(|h| h.ng),
            });
        }
        let Some(hit) = hit else {
            return tr;
        };
        let shape = &scene.shapes[hit.geom_id as usize];
        if shape.thin_sheet || shape.masked {
            // A window pane or a mask: what it lets pass (`Scene::shadow_transmittance`).
            let Some(passed) = scene.passed_by(&scene.interaction(&ray, &hit), ray.d) else {
                return Rgb::ZERO;
            };
            tr *= passed;
            if tr.is_black() {
                return Rgb::ZERO;
            }
        } else if !shape.null {
            return Rgb::ZERO;
        }
        let before = medium;
        medium = medium_after(shape.media, hit.ng, ray.d, medium);
        let p = ray.at(hit.t);
        visit(Passage::Boundary {
            t: (p - start).length(),
            ng: hit.ng,
            d: ray.d,
            media: (before, medium),
        });
        from_boundary = Some(hit.ng);
        let o = offset_ray_origin(p, hit.ng.normalize_or(ray.d), ray.d, scene.scale);
        let Some(next) = ray_on_to(o, ray.d, end) else {
            return tr;
        };
        ray = next;
    }
    Rgb::ZERO
}

/// `g[c] += v · s_c` for each channel c.
fn add_per_channel(g: &mut [Vec3; 3], v: Vec3, s: Rgb) {
    g[0] += v * s.r;
    g[1] += v * s.g;
    g[2] += v * s.b;
}

/// An interface's term of the optical depth's gradient, `jump · weight · n/(n·d)` (the jump
/// σ₂ − σ₁ in σ_t, the pivot weight at the interface), added to `g`; none for a ray along it.
fn add_interface(g: &mut [Vec3; 3], n: Vec3, d: Vec3, weight: f32, jump: Rgb) {
    let cos = n.dot(d);
    if cos != 0.0 {
        add_per_channel(g, n * (weight / cos), jump);
    }
}

/// The pivot form's weight 1 − t/r of a point `t` along a ray of length `r` as its origin moves
/// with the far end held (1 for a ray to infinity, which moves whole).
fn lever(t: f32, r: f32) -> f32 {
    if r.is_finite() {
        1.0 - t / r
    } else {
        1.0
    }
}

/// Strata of a grid piece's depth integrals in [`grid_depth_gradient`], one jittered point each.
const DEPTH_STRATA: u32 = 2;

/// In heterogeneous `medium` along `o + t d`, t ∈ [0, `length`] (`start` from the shadow ray's
/// origin, `r` its length): the optical depth inside the medium's box and the pivot integral
/// ∫ (1 − t/r) ∇σ_t dt, each estimated without bias from [`DEPTH_STRATA`] jittered points
/// (`rng`; a march fine enough for a dense grid cost twice the render), ∇σ_t the interpolant's
/// own ([`Medium::at_with_gradient`]), plus the jumps of σ_t where the piece enters and leaves the medium: at the box's faces
/// inside the piece, else at the null boundaries it began or ended on (normals `from_boundary`,
/// `to_boundary`; [`transmittance_with_depth_gradient`] then counts the grid as empty there).
#[allow(clippy::too_many_arguments)]
fn grid_depth_gradient(
    medium: &Medium,
    o: Vec3,
    d: Vec3,
    length: f32,
    start: f32,
    r: f32,
    from_boundary: Option<Vec3>,
    to_boundary: Option<Vec3>,
    rng: &mut Rng,
) -> (Rgb, [Vec3; 3]) {
    let mut tau = Rgb::ZERO;
    let mut g = [Vec3::ZERO; 3];
    let Some((t0, t1)) = medium.clip(o, d, length) else {
        return (tau, g);
    };
    let dt = (t1 - t0) / DEPTH_STRATA as f32;
    for k in 0..DEPTH_STRATA {
        let t = t0 + (k as f32 + rng.next_f32()) * dt;
        let (c, gradients) = medium.at_with_gradient(o + d * t);
        tau += c.sigma_t * dt;
        let weight = lever(start + t, r) * dt;
        for (sum, grad) in g.iter_mut().zip(gradients.sigma_t) {
            *sum += grad * weight;
        }
    }
    // The jumps where the piece enters (σ from 0 to σ(t0)) and leaves (σ(t1) to 0) the box:
    // (σ₂ − σ₁)(1 − t/r) n/(n·d).
    let mut jump = |t: f32, n: Vec3, into: bool| {
        let sigma = medium.at(o + d * t).sigma_t;
        let jump = if into { sigma } else { sigma * -1.0 };
        add_interface(&mut g, n, d, lever(start + t, r), jump);
    };
    let entry = if t0 > 0.0 {
        Some(medium.box_face_normal(o + d * t0))
    } else {
        from_boundary
    };
    if let Some(n) = entry {
        jump(t0, n, true);
    }
    let exit = if t1 < length {
        Some(medium.box_face_normal(o + d * t1))
    } else {
        to_boundary
    };
    if let Some(n) = exit {
        jump(t1, n, false);
    }
    (tau, g)
}

/// [`transmittance_along`] and the gradient per channel of the optical depth τ with respect to
/// the ray's origin, its far end held (the pivot form of NOTES-002 §2.4 with §2.7's interface
/// terms): ∇τ = −d τ/r + ∫ (1 − t/r) ∇σ_t dt + Σ_b (σ₂ − σ₁)(1 − t_b/r) n_b/(n_b·d) over the
/// boundaries b crossed from σ₁ to σ₂, the integral zero in homogeneous media and marched in
/// grids ([`grid_depth_gradient`], which also takes τ there); a ray to infinity (a distant
/// light) moves with its origin: no first term, and 1 − t/r = 1. The gradient is zero where
/// the ray is blocked. `depth_rng` places the grids' depth estimates, apart from `rng`'s
/// transmittance (the two multiply: independent, their product keeps its mean).
pub fn transmittance_with_depth_gradient(
    scene: &Scene,
    ray: Ray,
    medium: Option<usize>,
    rng: &mut Rng,
    depth_rng: &mut Rng,
    rays: &mut RayCounts,
) -> (Rgb, [Vec3; 3]) {
    // σ_t on a boundary's side: a grid counts as empty there (its segment adds its own jumps).
    let sigma = |m: Option<usize>, p: Vec3| -> Rgb {
        match m.map(|m| &scene.media[m]) {
            Some(m) if m.homogeneous => m.at(p).sigma_t,
            _ => Rgb::ZERO,
        }
    };
    let r = ray.t_max;
    let (o, d) = (ray.o, ray.d);
    let mut tau = Rgb::ZERO;
    let mut sum = [Vec3::ZERO; 3];
    let tr = transmittance_crossing(scene, ray, medium, rng, rays, |passage| match passage {
        Passage::Segment {
            medium,
            o,
            d,
            length,
            start,
            from_boundary,
            to_boundary,
        } => {
            let m = &scene.media[medium];
            if m.homogeneous {
                tau += m.at(o).sigma_t * length;
            } else {
                let (t, g) = grid_depth_gradient(
                    m,
                    o,
                    d,
                    length,
                    start,
                    r,
                    from_boundary,
                    to_boundary,
                    depth_rng,
                );
                tau += t;
                for c in 0..3 {
                    sum[c] += g[c];
                }
            }
        }
        Passage::Boundary { t, ng, d, media } => {
            let p = o + d * t;
            let jump = sigma(media.1, p) - sigma(media.0, p);
            add_interface(&mut sum, ng, d, lever(t, r), jump);
        }
    });
    if tr.is_black() {
        return (tr, [Vec3::ZERO; 3]);
    }
    if r.is_finite() {
        add_per_channel(&mut sum, -d / r, tau);
    }
    (tr, sum)
}
