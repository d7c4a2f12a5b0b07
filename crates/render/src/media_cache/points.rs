//! Irradiance and its gradients at given points in scenes with media (`ircache irradiance`):
//! by one record's gather with 002's gradients (the cache's own computation), or by brute force:
//! the value from `volpath`'s paths over the hemisphere, which share nothing with the records'
//! march (its steps, transmittance quadrature and light streams), and the translational
//! gradient by central differences of the march's gather with common random numbers (NOTES-002
//! §3.3; paths would need far more rays for a difference). The direct part is light sampling
//! with transmittance.

use super::cache::{make_record, RecordSite};
use super::gradient::{gather, March};
use super::scene_medium::SceneMedium;
use crate::integrators::path_continuation::Arrival;
use crate::integrators::volpath::{PathState, VolPathIntegrator};
use crate::integrators::RayCounts;
use crate::irradiance_cache::hemisphere::{to_world, Stratification};
use crate::irradiance_cache::points::{PointIrradiance, PointMethod};
use crate::irradiance_cache::IcParams;
use crate::media::tracking::medium_at;
use crate::media::tracking::transmittance_along;
use crate::scene::Scene;
use ircache_math::{offset_ray_origin, Frame, Ray, Rgb, Rng, Vec3, PI};
use rayon::prelude::*;

/// Direct irradiance at `p` (normal `n`, in `medium`) from `samples` light samples with
/// transmittance.
#[must_use]
pub fn direct_irradiance(
    scene: &Scene,
    p: Vec3,
    n: Vec3,
    medium: Option<usize>,
    samples: u32,
    rng: &mut Rng,
) -> Rgb {
    let mut sum = Rgb::ZERO;
    let mut rays = RayCounts::default();
    for _ in 0..samples {
        let (u_sel, u) = (rng.next_f32(), rng.next_2d());
        let Some(ls) = scene.lights.sample(p, u_sel, u) else {
            continue;
        };
        let cos = ls.wi.dot(n);
        if cos <= 0.0 || ls.pdf <= 0.0 {
            continue;
        }
        let ray = scene.shadow_ray_at(p, Some(n), ls.wi, ls.distance);
        let tr = transmittance_along(scene, ray, medium, rng, &mut rays);
        sum += tr * ls.radiance * (cos / ls.pdf);
    }
    sum / samples.max(1) as f32
}

/// Irradiance at each `(point, normal)`.
#[must_use]
pub fn media_irradiance_at_points(
    scene: &Scene,
    params: &IcParams,
    queries: &[(Vec3, Vec3)],
    method: PointMethod,
    direct_samples: u32,
    seed: u64,
) -> Vec<PointIrradiance> {
    queries
        .par_iter()
        .enumerate()
        .map(|(i, &(p, n))| {
            let medium = medium_at(scene, offset_ray_origin(p, n, n, scene.scale), n);
            let mut rng = Rng::keyed(seed, &[0x006d_6564_6961, i as u64]);
            let direct = if direct_samples > 0 {
                direct_irradiance(scene, p, n, medium, direct_samples, &mut rng)
            } else {
                Rgb::ZERO
            };
            let site = RecordSite {
                p,
                ng: n,
                n,
                medium,
                footprint: 0.0,
            };
            let (indirect, grad_t, grad_r) = match method {
                // No bounce (`-ab 0`): direct light alone.
                _ if params.bounces == 0 => (Rgb::ZERO, [Vec3::ZERO; 3], [Vec3::ZERO; 3]),
                PointMethod::Cache => {
                    let (r, _) = make_record(
                        scene,
                        params,
                        &site,
                        rng.next_u32().into(),
                        Default::default(),
                    );
                    (r.e, r.grad_t, r.grad_r)
                }
                PointMethod::BruteForce { samples } => {
                    brute_force(scene, &site, samples, params, seed ^ i as u64)
                }
            };
            PointIrradiance {
                direct,
                indirect,
                grad_t,
                grad_r,
            }
        })
        .collect()
}

/// A gather of `samples` rays (`params`' light samples per hit and march step, its bounces) and
/// central differences of it along the tangents, with the same cells' jitter at both points, at
/// a step of 1 % of the nearest opaque hit.
fn brute_force(
    scene: &Scene,
    site: &RecordSite,
    samples: usize,
    params: &IcParams,
    seed: u64,
) -> (Rgb, [Vec3; 3], [Vec3; 3]) {
    let strata = Stratification::from_divisions(samples);
    let frame = Frame::from_z(site.n);
    let axes = [frame.s.as_dvec3(), frame.t.as_dvec3(), frame.n.as_dvec3()];
    let origin = offset_ray_origin(site.p, site.ng, site.n, scene.scale).as_dvec3();
    let n = strata.azimuthal;
    let at = |x| {
        let view = SceneMedium::new(scene, site.medium, false, params.media_light_samples)
            .with_gradients(false)
            .with_deeper_bounces(params.bounces, params.media_deeper_paths, None, None);
        let march = March {
            gradients: false,
            ..March::default()
        };
        gather(&view, x, axes, strata, &march, |j, k| {
            Rng::keyed(seed, &[(j * n + k) as u64]).next_2d()
        })
    };
    let here = at(origin);
    let samples_here = here.hemisphere_samples();
    let nearest = samples_here
        .distance
        .iter()
        .copied()
        .fold(f32::INFINITY, f32::min);
    let h = if nearest.is_finite() {
        0.01 * f64::from(nearest)
    } else {
        1e-3 * f64::from(scene.radius)
    };
    let mut grad = [Vec3::ZERO; 3];
    for axis in [axes[0], axes[1]] {
        let (plus, minus) = (
            at(origin + axis * h).total_irradiance(),
            at(origin - axis * h).total_irradiance(),
        );
        for c in 0..3 {
            grad[c] += axis.as_vec3() * ((plus[c] - minus[c]) / (2.0 * h)) as f32;
        }
    }
    let grad_r = to_world(&samples_here.rotational_gradient(), frame.s, frame.t);
    let e = volpath_irradiance(
        scene,
        site.medium,
        origin.as_vec3(),
        frame,
        strata,
        params.bounces,
        seed,
    );
    (e, grad, grad_r)
}

/// E at `origin` (in `medium`, around `frame`'s normal) by `volpath`: a path along a
/// cosine-weighted direction in each cell of `strata` (jittered), through `bounces` bounces, the
/// emitters it meets directly left out as the records' gathers leave them (the medium's
/// emission along it counts, as theirs does).
fn volpath_irradiance(
    scene: &Scene,
    medium: Option<usize>,
    origin: Vec3,
    frame: Frame,
    strata: Stratification,
    bounces: u32,
    seed: u64,
) -> Rgb {
    const KEY: u64 = 0x0076_6f6c_7061_7468;
    let integrator = VolPathIntegrator::plain(VolPathIntegrator::depth_of_bounces(bounces));
    let mut rays = RayCounts::default();
    let mut sum = Rgb::ZERO;
    for j in 0..strata.polar {
        for k in 0..strata.azimuthal {
            let mut stream = Rng::keyed(seed ^ KEY, &[(j * strata.azimuthal + k) as u64]);
            let w = frame.from_local(strata.direction(j, k, stream.next_2d()));
            let mut rng = Rng::new(u64::from(stream.next_u32()), KEY);
            let start = PathState {
                ray: Ray::new(origin, w),
                medium,
                beta: Rgb::ONE,
                depth: 1,
                arrival: Arrival::Gather,
                caustic_chain: false,
            };
            sum += integrator
                .trace(scene, start, None, false, &mut stream, &mut rng, &mut rays)
                .all;
        }
    }
    sum * (PI / strata.cells() as f32)
}
