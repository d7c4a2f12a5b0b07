//! Camera rays marched through media: the pixel pass of the cache in media (NOTES-002 §2.8,
//! "Rendering"). Delta tracking (`volpath`) lets each camera sample find one collision or none,
//! so the fog's single scattering gets one light sample per pixel sample and a surface behind
//! fog is seen or not (a binary weight). Here the light the medium scatters towards the camera
//! is split as 002 eqs. 2–4 split a gather ray's:
//!
//! - **single scattering and emission**, ∫ T(0,t) [σ_s ∫ f_p L_direct dω + σ_a L_e] dt, by
//!   stratified quadrature: `points` distances per segment, one in each stratum of equal
//!   scattering probability (the inverse of 1 − T̄ in homogeneous media; in grids under a
//!   piecewise-constant model of the extinction along the ray, so that the points fall in the
//!   smoke, not in the air around it), each with a light sample from a randomly shifted rank-1
//!   lattice (unbiased for a random shift: Cranley–Patterson);
//! - **the surface behind**, weighted by the transmittance T(0,s) (closed form, or the grid
//!   model's) instead of a survival test, shaded as `volpath` shades it (direct light and the
//!   media cache's records);
//! - **the in-scattered indirect light**, ∫ T σ_s ∫ f_p L_indirect dω dt, by one delta-tracking
//!   collision per camera sample whose phase-sampled path leaves out the emitters it reaches
//!   directly (the quadrature's light samples hold them).
//!
//! The camera path is a camera ray until its first surface with a part that is not a delta lobe:
//! at smooth glass and mirrors the march goes on along the lobe the sampler picks (its weight
//! in the throughput, the vertices beyond one deeper each), so that fog seen through glass or in
//! a mirror is marched as fog seen directly (scenes/glass-in-fog: relMSE_trim −10 %, blurred
//! −27 %, same time). Beyond one or two such vertices the volumetric records serve with their
//! light one or two bounces shorter, the light of paths as many vertices shorter, which is what
//! a point as many vertices deeper receives
//! ([`crate::media_cache::volume_records::VolumeCache::in_scattered_shorter`]); beyond that the
//! records' depth is no longer the path's: they give way to one tracked collision. The surface
//! behind is `volpath`'s.
//!
//! In homogeneous media the three are unbiased and their sum converges to `volpath` (tested
//! against it). In grids the transmittance is the model's: the optical depth by midpoints of
//! pieces of a quarter of the local majorants' optical depth, whose error is second order in
//! the piece (the smoke plume's single scattering within 0.02 % of `volpath`'s mean, blocks within
//! 0.7 %; ratio tracking from point to point, before, had twice the noise).

use super::equiangular::{DistanceDensity, Segment};
use super::light_sampling::BsdfStrategy;
use super::path_continuation::{count_and_roulette, sample_continuation, Arrival};
use super::volpath::{light_sample_with, PathState, Vertex, VolPathIntegrator, SHORTER};
use super::RayCounts;
use crate::media::tracking::{medium_after, sample_flight, Flight, MAX_CROSSINGS};
use crate::media::Medium;
use crate::sampler::Sampler;
use crate::scene::{Interaction, Scene};
use ircache_embree::Hit;
use ircache_math::sampling::ONE_MINUS_EPSILON;
use ircache_math::{Ray, Rgb, Rng, Vec2, Vec3};

/// How camera rays are marched.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CameraMarch {
    /// Quadrature points per medium segment of a camera ray where it is opaque (fewer where
    /// the segment scatters little: a point per 1/`points` of scattering probability).
    pub points: u32,
}

/// The generator of the light samples' lattice: 1/φ₃, 1/φ₃², 1/φ₃³ with φ₃ the plastic number
/// (Roberts' R₃ sequence, well spread in every projection).
const LATTICE: [f32; 3] = [0.819_172_5, 0.671_043_5, 0.549_700_5];

/// Point `i` of the lattice shifted by `shift` (light choice, position on the light).
#[must_use]
pub fn lattice_point(shift: [f32; 3], i: u32) -> (f32, Vec2) {
    let at = |k: usize| (shift[k] + i as f32 * LATTICE[k]).fract();
    (at(0), Vec2::new(at(1), at(2)))
}

/// Delta vertices past which the volumetric records still serve a camera path's march: their
/// light, and that one and two bounces shorter.
const RECORD_DEPTHS: u32 = SHORTER as u32;

/// Radiance along the camera ray `ray` (closest hit `first_hit`), marched (see the module).
#[allow(clippy::too_many_arguments)]
pub(crate) fn li(
    integrator: &VolPathIntegrator,
    march: CameraMarch,
    scene: &Scene,
    ray: &Ray,
    first_hit: Option<&Hit>,
    arrival: Arrival,
    sampler: &mut dyn Sampler,
    rng: &mut Rng,
    rays: &mut RayCounts,
) -> Rgb {
    let max_depth = integrator.depth_limit();
    let mut l = Rgb::ZERO;
    let mut ray = *ray;
    let mut hit = first_hit.copied();
    let mut medium = scene.camera_medium;
    let mut arrival = arrival;
    // Smooth glass and mirrors passed so far: the depth of the segment's scattering vertices.
    let mut depth = 0u32;
    // Transmittance (times the delta lobes' weights) from the camera to the current segment.
    let mut tr = Rgb::ONE;
    // The delta-tracking walk that finds the in-scattered indirect light's collision.
    let mut collision_beta = Rgb::ONE;
    let mut collision: Option<MarchPoint> = None;
    // (The volumetric records serve it at the quadrature's points instead, where they exist:
    // up to two delta vertices deep, with their light as many bounces shorter.)
    let mut tracking = max_depth > 2 && integrator.volume_records.is_none();
    let mut walk_begun = tracking;
    let mut crossings = 0u32;
    loop {
        let t_hit = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
        if let Some(m) = medium {
            let med = &scene.media[m];
            let (light, segment) = march_segment(
                integrator,
                scene,
                m,
                &ray,
                t_hit,
                march.points,
                (depth, max_depth),
                rng,
                rays,
            );
            l += tr * light;
            if tracking {
                let mut ignored = Rgb::ZERO;
                match sample_flight(
                    med,
                    ray.o,
                    ray.d,
                    t_hit,
                    &mut collision_beta,
                    &mut ignored,
                    rng,
                ) {
                    Flight::Absorbed => tracking = false,
                    Flight::Passed => {}
                    Flight::Scattered { t, .. } => {
                        collision = Some(MarchPoint {
                            p: ray.at(t),
                            d: ray.d,
                            medium: m,
                            depth,
                        });
                        tracking = false;
                    }
                }
            }
            tr *= segment;
            if tr.is_black() && !tracking {
                break;
            }
        }
        let Some(h) = hit else {
            break;
        };
        crossings += 1;
        if crossings > MAX_CROSSINGS {
            break;
        }
        let shape = &scene.shapes[h.geom_id as usize];
        let it = scene.interaction(&ray, &h);
        let next = if shape.null {
            ray.d
        } else {
            match delta_continuation(integrator, scene, &it, ray.d, (depth, max_depth), sampler) {
                Continuation::Surface => break,
                Continuation::Ends => {
                    tr = Rgb::ZERO;
                    break;
                }
                Continuation::Along(wi, weight, pdf) => {
                    tr *= weight;
                    collision_beta *= weight;
                    arrival = Arrival::Bsdf {
                        from: it.p.into(),
                        pdf,
                        delta: true,
                        light_samples: 0,
                    };
                    depth += 1;
                    // Past the records' depths the records' depth is not the path's:
                    // from there the in-scattered indirect light is tracked to one collision,
                    // the walk weighted by the transmittance so far.
                    if !walk_begun && depth > RECORD_DEPTHS && depth + 2 < max_depth {
                        (tracking, walk_begun) = (true, true);
                        collision_beta = tr;
                    }
                    wi
                }
            }
        };
        medium = medium_after(shape.media, it.ng, next, medium);
        ray = scene.spawn_ray(&it, next);
        rays.bounce += 1;
        hit = scene.accel.intersect(&ray);
    }

    // The surface behind the fog (or the environment), seen through it.
    if !tr.is_black() {
        let start = PathState {
            ray,
            medium,
            beta: tr,
            depth,
            arrival,
            caustic_chain: false,
        };
        l += integrator
            .trace(scene, start, Some(hit), true, sampler, rng, rays)
            .all;
    }

    // The in-scattered indirect light from the collision, on a stream of its own (its
    // dimensions would repeat the surface path's).
    if let Some(at) = collision {
        let key = u64::from(rng.next_u32());
        l += collision_beta * in_scattered_by_path(integrator, scene, &at, key, rng, rays);
    }
    l
}

/// What a camera ray's march does at an opaque surface.
enum Continuation {
    /// The surface is shaded there (by `volpath`'s loop, the records' where they serve).
    Surface,
    /// Along a delta lobe's sample: direction, weight, density.
    Along(Vec3, Rgb, f32),
    /// Nothing goes on (no sample).
    Ends,
}

/// At a surface of only delta lobes (smooth glass, a mirror) that emits nothing, the march
/// goes on along the lobe the sampler picks, as `volpath`'s path would, so that the fog seen in
/// glass or a mirror is marched too (vertex `depth` of at most `max_depth`, before Russian
/// roulette begins: `volpath`'s own loop takes over from there).
fn delta_continuation(
    integrator: &VolPathIntegrator,
    scene: &Scene,
    it: &Interaction,
    d: Vec3,
    (depth, max_depth): (u32, u32),
    sampler: &mut dyn Sampler,
) -> Continuation {
    let shape = &scene.shapes[it.shape as usize];
    if shape.area_light.is_some()
        || (scene.has_see_through && (shape.thin_sheet || shape.masked))
        || depth + 2 > max_depth
        || depth + 1 >= integrator.rr_depth
    {
        return Continuation::Surface;
    }
    let bsdf = it.bsdf(&scene.materials[shape.material], d);
    if bsdf.has_smooth() {
        return Continuation::Surface;
    }
    let wo_local = it.frame.to_local(-d);
    match sample_continuation(
        scene,
        it,
        &bsdf,
        wo_local,
        BsdfStrategy::All,
        depth,
        sampler,
    ) {
        Some((bs, wi)) if bs.delta => Continuation::Along(wi, bs.weight, bs.pdf),
        Some(_) => Continuation::Surface,
        None => Continuation::Ends,
    }
}

/// The light `medium` sends towards the camera along `ray` up to `t_hit` (from the segment's
/// start, without the transmittance before it) and the segment's transmittance: the quadrature
/// of [`quadrature_points`], each point's source from [`source`].
#[allow(clippy::too_many_arguments)]
fn march_segment(
    integrator: &VolPathIntegrator,
    scene: &Scene,
    medium: usize,
    ray: &Ray,
    t_hit: f32,
    points: u32,
    (depth, max_depth): (u32, u32),
    rng: &mut Rng,
    rays: &mut RayCounts,
) -> (Rgb, Rgb) {
    let med = &scene.media[medium];
    let mut jitter = Rng::new(u64::from(rng.next_u32()), 0x6a69_7474);
    let (quadrature, segment, density) =
        quadrature_points(med, ray, t_hit, points, || jitter.next_f32());
    let shift = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
    // Point and spot lights' single scattering also by as many equiangular samples, each
    // strategy's light samples weighed against the other's.
    let equiangular = density
        .filter(|_| depth + 2 <= max_depth && scene.samples_lights_in(medium))
        .and_then(|density| {
            Segment::for_density(scene, medium, ray, t_hit, density, quadrature.len() as u32)
        });
    let mut sum = Rgb::ZERO;
    for (i, &(t, weight)) in quadrature.iter().enumerate() {
        let u = lattice_point(shift, i as u32);
        let at = MarchPoint {
            p: ray.at(t),
            d: ray.d,
            medium,
            depth,
        };
        sum += weight
            * source(
                integrator,
                scene,
                &at,
                equiangular.as_ref(),
                max_depth,
                u,
                rng,
                rays,
            );
    }
    if let Some(equiangular) = &equiangular {
        let n = equiangular.samples;
        let (u_select, u_t) = (rng.next_f32(), rng.next_f32());
        for i in 0..n {
            // Stratified distances, the light choices a lattice across them.
            let u = (
                (u_select + i as f32 * LATTICE[0]).fract(),
                (i as f32 + (u_t + i as f32 * LATTICE[1]).fract()) / n as f32,
            );
            sum += equiangular.estimate(scene, u, rng, rays);
        }
    }
    (sum, segment)
}

/// A quadrature point of a camera ray.
pub(crate) struct MarchPoint {
    /// Where.
    pub p: Vec3,
    /// The camera ray's direction.
    pub d: Vec3,
    /// The medium there.
    pub medium: usize,
    /// Its depth as a path vertex (0 on the camera ray; one more past each delta vertex).
    pub depth: u32,
}

/// The light a point of its medium sends back along the camera ray per unit length: emission σ_a L_e,
/// single scattering σ_s ∫ f_p L_direct by a light sample drawn with `u`, and where paths go on
/// (`max_depth` > 2) the in-scattered indirect light from the volumetric records, or where
/// none serves, by a phase-sampled path that leaves out the emitters it meets directly.
#[allow(clippy::too_many_arguments)]
fn source(
    integrator: &VolPathIntegrator,
    scene: &Scene,
    at: &MarchPoint,
    equiangular: Option<&Segment>,
    max_depth: u32,
    u: (f32, Vec2),
    rng: &mut Rng,
    rays: &mut RayCounts,
) -> Rgb {
    let med = &scene.media[at.medium];
    let c = med.at(at.p);
    let mut q = if med.emits() {
        c.sigma_a() * c.emission
    } else {
        Rgb::ZERO
    };
    if c.sigma_s.is_black() || at.depth + 2 > max_depth {
        return q;
    }
    if scene.samples_lights_in(at.medium) {
        let vertex = Vertex::Medium(at.p, at.d, med.phase, equiangular);
        q += c.sigma_s * light_sample_with(scene, &vertex, Some(at.medium), None, u, rng, rays);
    }
    if at.depth + 2 < max_depth {
        // Deeper, the caller tracks the indirect light to one collision.
        let records = integrator.volume_records.as_ref();
        if let Some(records) = records.filter(|_| at.depth <= RECORD_DEPTHS) {
            let served = match at.depth {
                0 => records.in_scattered(at.p, at.medium, at.d, med.phase),
                k => records.in_scattered_shorter(at.p, at.medium, at.d, med.phase, k as usize),
            };
            let indirect = served.unwrap_or_else(|| {
                let key = u64::from(rng.next_u32());
                in_scattered_by_path(integrator, scene, at, key, rng, rays)
            });
            q += c.sigma_s * indirect;
        }
    }
    q
}

/// The in-scattered indirect light at `at` towards the camera by one phase-sampled path on a
/// stream of its own (keyed by `key`), leaving out the emitters it meets directly where light
/// samples in the medium hold them.
pub(crate) fn in_scattered_by_path(
    integrator: &VolPathIntegrator,
    scene: &Scene,
    at: &MarchPoint,
    key: u64,
    rng: &mut Rng,
    rays: &mut RayCounts,
) -> Rgb {
    let mut stream = Rng::new(key, 0x006d_6172_6368);
    let phase = scene.media[at.medium].phase;
    let (w, pdf) = phase.sample(at.d, stream.next_2d());
    let mut beta = Rgb::ONE;
    let mut depth = at.depth;
    if !count_and_roulette(&mut depth, &mut beta, 1.0, integrator.rr_depth, &mut stream) {
        return Rgb::ZERO;
    }
    let start = PathState {
        ray: Ray::new(at.p, w),
        medium: Some(at.medium),
        beta,
        depth,
        arrival: indirect_arrival(at.p, pdf, scene.samples_lights_in(at.medium)),
        caustic_chain: false,
    };
    integrator
        .trace(scene, start, None, false, &mut stream, rng, rays)
        .all
}

/// How a path that carries only indirect light arrives at its next vertex: emitters found there
/// count nothing where light samples took them (`sample_emitters`), fully where none did.
pub(crate) fn indirect_arrival(p: Vec3, pdf: f32, sample_emitters: bool) -> Arrival {
    if sample_emitters {
        Arrival::Gather
    } else {
        Arrival::Bsdf {
            from: p.into(),
            pdf,
            delta: false,
            light_samples: 0,
        }
    }
}

/// The quadrature of a medium segment of `ray` up to `t_hit`: distances with weights
/// T(t₀, t)/(n pdf(t)) (`jitter` places each in its stratum), the segment's transmittance, and
/// the points' density n pdf(t) (in grids a stand-in for it) for the weights against
/// equiangular samples ([`super::equiangular`]).
/// Homogeneous media: one distance per stratum of equal scattering probability under the
/// channels' mean extinction σ̄, pdf = σ̄ e^{−σ̄ s}/(1 − e^{−σ̄ L}); grids: the same under a
/// piecewise-constant model of σ̄ ([`grid_quadrature`]). `points` strata where the segment is
/// opaque, fewer where it scatters little ([`strata`]).
pub(crate) fn quadrature_points(
    med: &Medium,
    ray: &Ray,
    t_hit: f32,
    points: u32,
    mut jitter: impl FnMut() -> f32,
) -> (Vec<(f32, Rgb)>, Rgb, Option<DistanceDensity>) {
    let Some((t0, t1)) = med.clip(ray.o, ray.d, t_hit) else {
        return (Vec::new(), Rgb::ONE, None);
    };
    let length = t1 - t0;
    if med.homogeneous {
        let sigma_t = med.at(ray.at(t0)).sigma_t;
        let segment = (sigma_t * -length)
            .exp()
            .map(|x| if x.is_nan() { 0.0 } else { x });
        let mean = sigma_t.mean();
        // An unbounded segment (a camera in fog looking at the sky) has mass 1 and finite points.
        if mean <= 0.0 {
            return (Vec::new(), segment, None);
        }
        let mass = -(-mean * length).exp_m1();
        let n = strata(points, mass);
        let out = (0..n)
            .map(|i| {
                // Below 1: (n − 1 + u)/n rounds to 1 for u near 1, a point at infinity on an
                // unbounded segment (open fog: an invalid shadow ray).
                let xi = ((i as f32 + jitter()) / n as f32).min(ONE_MINUS_EPSILON);
                let s = (-(-xi * mass).ln_1p() / mean).min(length);
                let weight = (sigma_t * -s).exp() * (mass / (n as f32 * mean * (-mean * s).exp()));
                (t0 + s, weight)
            })
            .collect();
        let density = DistanceDensity::Quadrature {
            count: n,
            mean,
            mass,
        };
        return (out, segment, Some(density));
    }
    if !length.is_finite() {
        return (Vec::new(), Rgb::ONE, None);
    }
    let (out, segment) = grid_quadrature(med, ray, (t0, t1), points, jitter);
    // The weights against equiangular samples take a homogeneous medium of the segment's mean
    // extinction in place of the model's density (any density both sides compute keeps the
    // weights a partition of unity).
    let through = segment.mean().max(1e-6);
    let density = (!out.is_empty()).then(|| DistanceDensity::Quadrature {
        count: out.len() as u32,
        mean: -through.ln() / length,
        mass: 1.0 - through,
    });
    (out, segment, density)
}

/// Majorant optical depth per piece of a grid's extinction model along a ray (0.5: the smoke
/// plume's blurred error against `volpath` 1.7× this one's; 0.25 costs 4 % more time).
const MODEL_DEPTH: f32 = 0.25;

/// One piece of a grid's extinction along a ray: constant σ_t (its midpoint's) on `[a, b)`, the
/// rate points are drawn at there, and the cumulative rate Λ and optical depth τ at `a`.
#[derive(Clone, Copy)]
struct Piece {
    a: f32,
    b: f32,
    sigma: Rgb,
    rate: f32,
    big_lambda: f32,
    tau: Rgb,
}

/// [`quadrature_points`] in a grid: the extinction along `[t0, t1]` modelled piecewise constant
/// (its value at the midpoint of pieces of majorant optical depth [`MODEL_DEPTH`], none in empty
/// majorant cells), points drawn in strata of equal probability under that model (so they fall
/// where the medium scatters and light still reaches, not in the air around a plume), and
/// weighted with the model's transmittance.
fn grid_quadrature(
    med: &Medium,
    ray: &Ray,
    (t0, t1): (f32, f32),
    points: u32,
    mut jitter: impl FnMut() -> f32,
) -> (Vec<(f32, Rgb)>, Rgb) {
    let mut pieces: Vec<Piece> = Vec::new();
    let (mut big_lambda, mut tau) = (0.0f32, Rgb::ZERO);
    med.for_each_segment(ray.o, ray.d, t0, t1, |a, b, majorant| {
        if majorant > 0.0 {
            let k = ((majorant * (b - a) / MODEL_DEPTH).ceil() as usize).clamp(1, 64);
            let h = (b - a) / k as f32;
            for i in 0..k {
                let (pa, pb) = (a + i as f32 * h, a + (i + 1) as f32 * h);
                let sigma = med.at(ray.at(0.5 * (pa + pb))).sigma_t;
                // A floor on the rate: a piece whose midpoint is clear may hold smoke.
                let rate = sigma.mean().max(0.05 * majorant);
                pieces.push(Piece {
                    a: pa,
                    b: pb,
                    sigma,
                    rate,
                    big_lambda,
                    tau,
                });
                big_lambda += rate * (pb - pa);
                tau += sigma * (pb - pa);
            }
        }
        true
    });
    let segment = (tau * -1.0).exp();
    let mass = -(-big_lambda).exp_m1();
    if pieces.is_empty() || mass <= 0.0 {
        return (Vec::new(), segment);
    }
    let n = strata(points, mass);
    let mut out = Vec::with_capacity(n as usize);
    let mut j = 0;
    for i in 0..n {
        let u = ((i as f32 + jitter()) / n as f32 * mass).min(mass * (1.0 - f32::EPSILON));
        let target = -(-u).ln_1p();
        while j + 1 < pieces.len() && pieces[j + 1].big_lambda <= target {
            j += 1;
        }
        let piece = pieces[j];
        let t = (piece.a + (target - piece.big_lambda) / piece.rate).min(piece.b);
        let pdf = piece.rate * (-target).exp() / mass;
        let transmittance = (piece.tau + piece.sigma * (t - piece.a)).map(|x| (-x).exp());
        out.push((t, transmittance / (n as f32 * pdf)));
    }
    (out, segment)
}

/// Points for a segment whose scattering probability is `mass`: one per 1/`points` of it, at
/// least one.
fn strata(points: u32, mass: f32) -> u32 {
    ((points as f32 * mass).ceil() as u32).clamp(1, points.max(1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use ircache_math::Mat4;
    use ircache_scene::{
        GridVolumeDesc, MediumDesc, MediumKind, PhaseDesc, SourceLocation, TextureFilter,
        VolumeDesc, WrapMode,
    };
    use std::sync::Arc;

    fn medium(sigma_t: VolumeDesc) -> Medium {
        Medium::from_desc(&MediumDesc {
            id: None,
            kind: if matches!(sigma_t, VolumeDesc::Grid(_)) {
                MediumKind::Heterogeneous
            } else {
                MediumKind::Homogeneous
            },
            sigma_t,
            albedo: VolumeDesc::constant(Rgb::splat(0.5)),
            emission: None,
            scale: 1.0,
            phase: PhaseDesc::Isotropic,
            sample_emitters: true,
            location: SourceLocation {
                file: Arc::new("<test>".into()),
                line: 1,
                column: 1,
            },
        })
    }

    /// On a segment without end (a camera in fog looking at the sky) every point is finite,
    /// with a finite weight, however near 1 the jitter: (n − 1 + u)/n rounded to 1 for the
    /// largest u below 1 and put the last point at infinity.
    #[test]
    fn an_unbounded_segment_has_finite_points_for_any_jitter() {
        let ray = Ray::new(Vec3::new(0.0, 2.0, 10.0), Vec3::new(0.0, 0.6, -0.8));
        let med = medium(VolumeDesc::constant(Rgb::splat(0.05)));
        let below_one = f32::from_bits(1.0f32.to_bits() - 1);
        for jitter in [0.0, 0.5, 0.999, below_one] {
            for n in [1, 7, 16, 64] {
                let (points, _, _) = quadrature_points(&med, &ray, f32::INFINITY, n, || jitter);
                assert!(!points.is_empty());
                for (t, w) in points {
                    assert!(
                        t.is_finite() && ray.at(t).is_finite() && w.max_channel().is_finite(),
                        "{n} points, jitter {jitter}: t {t}, weight {w:?}"
                    );
                }
            }
        }
    }

    /// The mean over jitters of the quadrature's weights is ∫ T dt per channel, and the
    /// segment's transmittance is T(L): a homogeneous medium with different extinctions per
    /// channel (closed form (1 − e^{−σL})/σ), a thin one, and a grid whose extinction rises
    /// along the ray (∫ e^{−τ(t)} dt by fine midpoint sums; the grid's model within 1 %).
    #[test]
    fn quadrature_weights_integrate_the_transmittance() {
        let ray = Ray::new(Vec3::ZERO, Vec3::X);
        let mut rng = Rng::new(3, 4);
        let runs = 20_000;
        for (sigma, length) in [(Rgb::new(0.5, 1.0, 3.0), 2.0f32), (Rgb::splat(0.01), 1.0)] {
            let med = medium(VolumeDesc::constant(sigma));
            let mut sum = Rgb::ZERO;
            for _ in 0..runs {
                let mut jitter = Rng::new(u64::from(rng.next_u32()), 1);
                let (points, segment, _) =
                    quadrature_points(&med, &ray, length, 8, || jitter.next_f32());
                let expected = (sigma * -length).exp();
                assert!((0..3).all(|c| (segment[c] - expected[c]).abs() < 1e-6));
                for (_, w) in points {
                    sum += w;
                }
            }
            let mean = sum / runs as f32;
            let exact = (Rgb::ONE - (sigma * -length).exp()) / sigma;
            for c in 0..3 {
                let rel = (mean[c] - exact[c]).abs() / exact[c];
                assert!(
                    rel < 0.01,
                    "σ {sigma:?}: channel {c} mean {} exact {}",
                    mean[c],
                    exact[c]
                );
            }
        }
        // σ_t(x) = 0.2 + 1.8 x on [0, 1]³ (linear in x, so trilinear filtering is exact).
        let res = [16, 2, 2];
        let mut data = Vec::new();
        for _z in 0..2 {
            for _y in 0..2 {
                for x in 0..16 {
                    data.push(0.2 + 1.8 * (x as f32 + 0.5) / 16.0);
                }
            }
        }
        let med = medium(VolumeDesc::Grid(Arc::new(GridVolumeDesc {
            path: "<test>".into(),
            resolution: res,
            channels: 1,
            data,
            to_world: Mat4::IDENTITY,
            filter: TextureFilter::Bilinear,
            wrap: WrapMode::Clamp,
        })));
        let ray = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::X);
        let sigma = |x: f32| 0.2 + 1.8 * x.clamp(1.0 / 32.0, 31.0 / 32.0);
        let (mut exact, mut tau, steps) = (0.0f64, 0.0f64, 100_000);
        for i in 0..steps {
            let x = (i as f32 + 0.5) / steps as f32;
            let dt = 1.0 / f64::from(steps);
            exact += (-(tau + 0.5 * f64::from(sigma(x)) * dt)).exp() * dt;
            tau += f64::from(sigma(x)) * dt;
        }
        let (mut sum, mut segment_sum) = (0.0f64, 0.0f64);
        for _ in 0..runs {
            let mut jitter = Rng::new(u64::from(rng.next_u32()), 2);
            let (points, segment, _) = quadrature_points(&med, &ray, 5.0, 8, || jitter.next_f32());
            segment_sum += f64::from(segment.g);
            sum += points.iter().map(|&(_, w)| f64::from(w.g)).sum::<f64>();
        }
        let (mean, mean_segment) = (sum / f64::from(runs), segment_sum / f64::from(runs));
        assert!(
            (mean - exact).abs() / exact < 0.01,
            "grid: {mean} against {exact}"
        );
        assert!(
            (mean_segment - (-tau).exp()).abs() < 0.01,
            "grid transmittance {mean_segment} against {}",
            (-tau).exp()
        );
    }
}
