//! Irradiance at given points and normals (what Radiance users run `rtrace -I` for): by the
//! cache (records placed coarse to fine over the points, then interpolated) or by brute force
//! (one stratified gather of many samples per point, deeper bounces path-traced), with the
//! indirect part's gradients either way.

use super::build::{fill_for_points, CacheStats};
use super::environment::HeldEnvironment;
use super::gather::{mix, Gatherer, IrradianceCache, SceneRadiance, ShadingPoint, WorkState};
use super::hemisphere::{to_world, Stratification};
use super::params::{IcParams, TranslationalFormula};
use crate::scene::{Interaction, Scene};
use ircache_math::{Frame, Rgb, Rng, Vec2, Vec3};
use rayon::prelude::*;

/// How irradiance at points is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointMethod {
    /// Records and interpolation.
    Cache,
    /// One gather of `samples` stratified rays per point.
    BruteForce {
        /// Hemisphere samples per point.
        samples: usize,
    },
}

/// Irradiance at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointIrradiance {
    /// Direct irradiance from the light sources (zero when only the indirect part was asked).
    pub direct: Rgb,
    /// Indirect irradiance (what the cache holds).
    pub indirect: Rgb,
    /// World-space translational gradient of the indirect part, per channel.
    pub grad_t: [Vec3; 3],
    /// World-space rotational gradient of the indirect part, per channel.
    pub grad_r: [Vec3; 3],
}

/// `count` record sites where camera rays through random film positions (a stream seeded by
/// `seed`) first meet a surface the cache serves: the visible points of Table 4.1's protocol.
#[must_use]
pub fn visible_sites(scene: &Scene, count: usize, seed: u64) -> Vec<ShadingPoint> {
    let mut rng = Rng::new(seed, 0);
    let mut sites = Vec::with_capacity(count);
    // A scene that shows no such surface gives what a bounded number of tries found.
    let mut tries = 0usize;
    while sites.len() < count && tries < 1000 * count.max(1) {
        tries += 1;
        let ray = scene
            .camera
            .generate_ray(Vec2::new(rng.next_f32(), rng.next_f32()));
        let Some(it) = scene.intersect(&ray) else {
            continue;
        };
        let bsdf = it.bsdf(
            &scene.materials[scene.shapes[it.shape as usize].material],
            ray.d,
        );
        if super::build::is_record_site(&bsdf, it.frame.to_local(-ray.d), false) {
            sites.push(ShadingPoint::facing(it, -ray.d));
        }
    }
    sites
}

/// A query point as a surface interaction that rays can leave from.
#[must_use]
pub fn query_point(p: Vec3, n: Vec3) -> ShadingPoint {
    let n = n.normalize();
    ShadingPoint {
        it: Interaction {
            p,
            ng: n,
            frame: Frame::from_z(n),
            base_n: n,
            uv: Vec2::ZERO,
            shape: u32::MAX,
            prim: 0,
            t: 0.0,
        },
        n,
        n_bump: n,
        cos_view: 1.0,
        travelled: 0.0,
    }
}

/// Direct irradiance at `sp` from `samples` light samples: π times the radiance a white
/// Lambertian surface there reflects, by the one light-sampling estimator. Where the cache
/// holds the environment (`environment`), its light is in the indirect part and left out here.
fn direct_irradiance(
    scene: &Scene,
    sp: &ShadingPoint,
    samples: u32,
    environment: bool,
    rng: &mut Rng,
) -> Rgb {
    use crate::bsdf::{Bsdf, Diffuse, Lobe};
    use crate::integrators::light_sampling::{
        sample_lights, BsdfStrategy, EnvironmentServed, Selection, Shadows,
    };
    let white = Bsdf::Single(Lobe::Diffuse(Diffuse {
        reflectance: Rgb::ONE,
    }));
    let mut rays = crate::integrators::RayCounts::default();
    let wo = sp.it.frame.to_local(sp.n);
    sample_lights(
        scene,
        &sp.it,
        &white,
        wo,
        (
            samples,
            // Every light in turn, as rtrace does, while that costs less than a selection's
            // estimate would (beyond, per-sample selection).
            if scene.lights.len() <= crate::lights::selection::MAX_ESTIMATED {
                Selection::EachLight
            } else {
                Selection::Chosen
            },
        ),
        (BsdfStrategy::All, 0),
        EnvironmentServed {
            lambertian: if environment { Rgb::ONE } else { Rgb::ZERO },
            glossy: false,
        },
        0,
        rng,
        &mut rays,
        Shadows::Traced,
    ) * std::f32::consts::PI
}

/// Irradiance at each `(p, n)`; `direct_samples` = 0 leaves the direct part out.
pub fn irradiance_at_points(
    scene: &Scene,
    params: &IcParams,
    queries: &[(Vec3, Vec3)],
    method: PointMethod,
    direct_samples: u32,
    seed: u64,
) -> (Vec<PointIrradiance>, Option<CacheStats>) {
    let points: Vec<ShadingPoint> = queries.iter().map(|&(p, n)| query_point(p, n)).collect();
    let mut cache = IrradianceCache::new(scene, params);
    // No caustic map: a query point need not lie on a surface where photons land (a workplane
    // in the air), so the gathers keep the caustic paths.
    let without_caustics = IcParams {
        caustic_photons: Some(0),
        ..params.clone()
    };
    cache.photons =
        super::prepare::photon_maps(scene, &without_caustics, seed).map(std::sync::Arc::new);
    let stats = match method {
        PointMethod::Cache if params.bounces > 0 => {
            let placed = super::prepare::photon_records(&mut cache);
            let mut stats = fill_for_points(scene, &mut cache, &points, seed);
            stats.photon_records = placed.records;
            stats.notes.extend(super::prepare::photon_note(params));
            if params.caustic_photons.is_some_and(|n| n > 0) {
                stats.notes.push(
                    "--caustic-photons is not used at points (they need not lie on a surface \
                     where photons land): the gathers trace the caustics"
                        .into(),
                );
            }
            Some(stats)
        }
        _ => None,
    };
    let results = points
        .par_iter()
        .with_max_len(4)
        .enumerate()
        .map(|(i, sp)| {
            let mut rng = Rng::keyed(seed, &[0x6469_7265_6374, i as u64]);
            let direct = if direct_samples > 0 {
                // With no bounce the cache gathers nothing: the environment stays direct.
                let environment = cache.environment == HeldEnvironment::All && params.bounces > 0;
                direct_irradiance(scene, sp, direct_samples, environment, &mut rng)
            } else {
                Rgb::ZERO
            };
            let (indirect, grad_t, grad_r) = if params.bounces == 0 {
                (
                    params.ambient_value * std::f32::consts::PI,
                    [Vec3::ZERO; 3],
                    [Vec3::ZERO; 3],
                )
            } else {
                match method {
                    PointMethod::Cache => interpolate_with_gradients(&cache, sp),
                    PointMethod::BruteForce { samples } => {
                        brute_force(scene, &cache, sp, samples, mix(seed, i as u64))
                    }
                }
            };
            PointIrradiance {
                direct,
                indirect,
                grad_t,
                grad_r,
            }
        })
        .collect();
    (results, stats)
}

/// Weighted mean of the records' extrapolated values and of their gradients.
pub fn interpolate_with_gradients(
    cache: &IrradianceCache,
    sp: &ShadingPoint,
) -> (Rgb, [Vec3; 3], [Vec3; 3]) {
    let store = &cache.levels[0];
    for threshold in [1.0, 2.0, 4.0, 16.0] {
        let (mut e, mut gt, mut gr, mut wsum) =
            (Rgb::ZERO, [Vec3::ZERO; 3], [Vec3::ZERO; 3], 0.0f32);
        store.for_each_serving(sp.it.p, sp.n, threshold, |rec, w| {
            e += super::record::extrapolate(rec, sp.it.p, sp.n, cache.params.gradients) * w;
            for c in 0..3 {
                gt[c] += rec.grad_t[c] * w;
                gr[c] += rec.grad_r[c] * w;
            }
            wsum += w;
        });
        if wsum > 0.0 {
            return (
                (e / wsum).max(Rgb::ZERO),
                gt.map(|g| g / wsum),
                gr.map(|g| g / wsum),
            );
        }
    }
    (Rgb::ZERO, [Vec3::ZERO; 3], [Vec3::ZERO; 3])
}

/// One gather of `samples` rays, deeper bounces path-traced.
fn brute_force(
    scene: &Scene,
    cache: &IrradianceCache,
    sp: &ShadingPoint,
    samples: usize,
    key: u64,
) -> (Rgb, [Vec3; 3], [Vec3; 3]) {
    let light = SceneRadiance::path_traced(scene);
    let g = Gatherer::new(&light, cache, key);
    let mut st = WorkState::new(cache.levels.len());
    let (h, frame) = g.gather(
        &mut st,
        sp,
        Stratification::from_divisions(samples),
        0,
        key,
        None,
    );
    let gt = match cache.params.formula {
        TranslationalFormula::WardHeckbert => h.translational_gradient_ward_heckbert(),
        TranslationalFormula::Krivanek => h.translational_gradient_krivanek(),
    };
    (
        h.irradiance(),
        to_world(&gt, frame.s, frame.t),
        to_world(&h.rotational_gradient(), frame.s, frame.t),
    )
}
