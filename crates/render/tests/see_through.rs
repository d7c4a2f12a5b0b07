//! Surfaces that let light through without a bounce. Window panes (`thindielectric` sheets):
//! light samples see through them with their transmittance τ(1 − R'), R' = 2R/(1 + R) of the
//! Fresnel reflectance R at the angle crossed, and paths cross them without a bounce. A sun
//! behind a pane lights a floor by exactly that factor (against the open floor and the closed
//! form), two panes by its square, in every integrator; an area light behind a pane, found by
//! light samples and by BSDF samples through the pane together (MIS), matches a quadrature of its
//! irradiance. Masks (Mitsuba's `mask`): a sun behind one lights the floor by 1 − opacity, and
//! a camera sees the mask's surface in that share of its samples.

mod common;
use common::{diffuse, quad, scene, sensor};
use ircache_math::{Rgb, Vec3, PI};
use ircache_render::integrators::Integrator;
use ircache_render::render::{render, RenderSettings};
use ircache_render::scene::Scene;
use ircache_scene::*;
use std::sync::Arc;

const RHO: f32 = 0.5;
const ETA: f32 = 1.5;

/// The sheet's transmittance at incidence cosine `c`, written out here (unpolarised Fresnel,
/// inter-reflections summed) apart from the renderer's code.
fn sheet_transmittance(c: f64) -> f64 {
    let eta = f64::from(ETA);
    let sin_t = (1.0 - c * c).sqrt() / eta;
    let ct = (1.0 - sin_t * sin_t).sqrt();
    let rs = ((c - eta * ct) / (c + eta * ct)).powi(2);
    let rp = ((ct - eta * c) / (ct + eta * c)).powi(2);
    let r = 0.5 * (rs + rp);
    1.0 - 2.0 * r / (1.0 + r)
}

/// A horizontal square at height `y`, wider than every view here.
fn horizontal(y: f32, bsdf: Arc<BsdfDesc>) -> ShapeDesc {
    quad(
        [
            Vec3::new(-50.0, y, -50.0),
            Vec3::new(50.0, y, -50.0),
            Vec3::new(50.0, y, 50.0),
            Vec3::new(-50.0, y, 50.0),
        ],
        bsdf,
        None,
    )
}

fn pane(y: f32) -> ShapeDesc {
    let bsdf = Arc::new(BsdfDesc::ThinDielectric {
        int_ior: ETA,
        ext_ior: 1.0,
        specular_reflectance: Rgb::ONE,
        specular_transmittance: Rgb::ONE,
    });
    horizontal(y, bsdf)
}

fn floor() -> ShapeDesc {
    quad(
        [
            Vec3::new(-50.0, 0.0, -50.0),
            Vec3::new(-50.0, 0.0, 50.0),
            Vec3::new(50.0, 0.0, 50.0),
            Vec3::new(50.0, 0.0, -50.0),
        ],
        diffuse(Rgb::splat(RHO)),
        None,
    )
}

/// The mean of the image's green channel, rendered with `integrator` at `max_depth` by a camera
/// between the floor and the panes, looking down at a small patch.
fn floor_radiance(
    shapes: Vec<ShapeDesc>,
    emitters: Vec<EmitterDesc>,
    (integrator, max_depth): (&str, i32),
    fov: f32,
    spp: u32,
) -> f64 {
    let mut desc = scene(
        sensor(Vec3::new(0.0, 0.5, 0.0), Vec3::ZERO, fov, 4, spp),
        common::path(max_depth),
        shapes,
        emitters,
    );
    desc.integrator.kind = integrator.into();
    let built = Scene::build(&desc).expect("scene builds");
    let integ = Integrator::from_desc(&desc.integrator).expect("integrator");
    let settings = RenderSettings::from_desc(&desc, 3, 2).expect("sampler");
    let out = render(&built, &integ, &settings, &|_| {}).expect("render");
    let pixels = &out.image.pixels;
    pixels.iter().map(|p| f64::from(p[1])).sum::<f64>() / pixels.len() as f64
}

#[test]
fn a_sun_behind_panes_lights_the_floor_by_their_transmittance() {
    let theta = 40f32.to_radians();
    let irradiance = 3.0;
    let sun = || EmitterDesc::Directional {
        direction: Vec3::new(theta.sin(), -theta.cos(), 0.0),
        irradiance: Rgb::splat(irradiance),
    };
    let open = f64::from(RHO / PI * irradiance * theta.cos());
    let t = sheet_transmittance(f64::from(theta.cos()));
    for integrator in ["path", "direct", "volpath", "ic"] {
        let direct = (integrator, 2);
        let bare = floor_radiance(vec![floor()], vec![sun()], direct, 20.0, 4);
        let one = floor_radiance(vec![floor(), pane(1.0)], vec![sun()], direct, 20.0, 4);
        let two = floor_radiance(
            vec![floor(), pane(1.0), pane(1.2)],
            vec![sun()],
            direct,
            20.0,
            4,
        );
        // One light sample of a delta light: no noise, only rounding.
        assert!(
            (bare / open - 1.0).abs() < 1e-5,
            "{integrator}: {bare} against {open}"
        );
        assert!(
            (one / (open * t) - 1.0).abs() < 1e-5,
            "{integrator}: through one pane {one} against {}",
            open * t
        );
        assert!(
            (two / (open * t * t) - 1.0).abs() < 1e-5,
            "{integrator}: through two panes {two} against {}",
            open * t * t
        );
    }
}

#[test]
fn an_area_light_behind_a_pane_matches_its_quadrature() {
    // A 1 × 1 light at height 2 facing down, the pane at 1: the floor's irradiance under its
    // centre is ∫ L τ(cos θ) cos² θ / r² dA (cos θ = 2/r at the floor and the light alike).
    let radiance = 10.0f32;
    let light = quad(
        [
            Vec3::new(-0.5, 2.0, -0.5),
            Vec3::new(0.5, 2.0, -0.5),
            Vec3::new(0.5, 2.0, 0.5),
            Vec3::new(-0.5, 2.0, 0.5),
        ],
        diffuse(Rgb::ZERO),
        Some(Rgb::splat(radiance)),
    );
    let n = 400;
    let mut e = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let x = (i as f64 + 0.5) / n as f64 - 0.5;
            let z = (j as f64 + 0.5) / n as f64 - 0.5;
            let r2 = x * x + z * z + 4.0;
            let c = 2.0 / r2.sqrt();
            e += sheet_transmittance(c) * c * c / r2;
        }
    }
    let e = e * f64::from(radiance) / (n * n) as f64;
    let expected = f64::from(RHO) / f64::from(PI) * e;
    // `path` at max_depth 3 takes a BSDF sample beside the light sample (at 2 the light samples
    // stand alone), which finds nothing but the light through the pane: the pane reflects
    // floor light only back to the floor, one bounce too deep.
    for integrator in [("path", 3), ("volpath", 3), ("direct", 2)] {
        // Light samples through the pane and BSDF samples that cross it, weighed by MIS: a
        // double count or a miss would be off by their share (tens of per cent).
        let got = floor_radiance(
            vec![floor(), pane(1.0), light.clone()],
            Vec::new(),
            integrator,
            0.5,
            4096,
        );
        assert!(
            (got / expected - 1.0).abs() < 0.01,
            "{integrator:?}: {got} against the quadrature's {expected}"
        );
    }
}

/// `shapes` under a `constant` sky of radiance `sky`.
fn under_a_constant_sky(shapes: Vec<ShapeDesc>, sky: f32) -> Scene {
    let desc = scene(
        sensor(Vec3::new(0.0, 0.5, 0.0), Vec3::ZERO, 40.0, 4, 1),
        common::path(3),
        shapes,
        vec![EmitterDesc::Constant {
            radiance: Rgb::splat(sky),
        }],
    );
    Scene::build(&desc).expect("scene builds")
}

#[test]
fn records_hold_a_sky_seen_through_a_pane() {
    use ircache_render::irradiance_cache::environment::{held_environment, HeldEnvironment};
    use ircache_render::irradiance_cache::params::CachedEnvironment;
    use ircache_render::irradiance_cache::points::{irradiance_at_points, PointMethod};
    use ircache_render::irradiance_cache::IcParams;
    // A floor under a pane and a constant sky L: the gathers cross the pane, so the records
    // hold the sky through it and the pane's reflection of the floor. Over infinite planes, at
    // one bounce, E = π L T̄; at two, E = π L T̄ (1 + ρ R̄), T̄ and R̄ = 1 − T̄ the pane's
    // cosine-weighted means: the pane that mirrors the floor is a bounce, as `path` counts it.
    let sky = 0.8f32;
    let built = under_a_constant_sky(vec![floor(), pane(1.0)], sky);
    assert_eq!(
        held_environment(&built, CachedEnvironment::All),
        HeldEnvironment::All
    );
    let n = 20_000;
    let t_mean: f64 = (0..n)
        .map(|i| {
            let mu = (i as f64 + 0.5) / n as f64;
            sheet_transmittance(mu) * 2.0 * mu / n as f64
        })
        .sum();
    let direct = std::f64::consts::PI * f64::from(sky) * t_mean;
    let queries = [
        (Vec3::new(0.0, 1e-3, 0.0), Vec3::Y),
        (Vec3::new(3.0, 1e-3, -2.0), Vec3::Y),
    ];
    // Held (all), or left to light samples through the pane (off): the same light.
    for (mode, bounces) in [
        (CachedEnvironment::All, 1),
        (CachedEnvironment::Off, 1),
        (CachedEnvironment::All, 2),
        (CachedEnvironment::Off, 2),
    ] {
        let expected = if bounces == 1 {
            direct
        } else {
            direct * (1.0 + f64::from(RHO) * (1.0 - t_mean))
        };
        let params = IcParams {
            bounces,
            cached_environment: mode,
            photons: Some(0),
            ..IcParams::default()
        };
        let (results, _) =
            irradiance_at_points(&built, &params, &queries, PointMethod::Cache, 4096, 3);
        for r in &results {
            if mode == CachedEnvironment::All {
                // Lambertian: the light samples leave the held sky to the records.
                assert_eq!(r.direct, Rgb::ZERO, "{r:?}");
            }
            let got = f64::from((r.direct + r.indirect).g);
            assert!(
                (got / expected - 1.0).abs() < 0.02,
                "{mode:?}, {bounces} bounces: {got} against {expected}"
            );
        }
    }
}

/// A pane over open ground under a constant sky L: every direction from a point below it brings
/// L, straight from the sky below the horizon, through the pane (T) or mirrored by it (R' =
/// 1 − T) from the sky below, so E = π L whatever the receiver's tilt. The mirrored sky is
/// found by the gathers alone (light samples cross a pane only straight): where records leave
/// the sky to light samples (`off`) it was lost, E = 0.84 π L for a vertical receiver.
#[test]
fn records_keep_the_sky_a_pane_mirrors() {
    use ircache_render::irradiance_cache::params::CachedEnvironment;
    use ircache_render::irradiance_cache::points::{irradiance_at_points, PointMethod};
    use ircache_render::irradiance_cache::IcParams;
    let sky = 0.8f32;
    let built = under_a_constant_sky(vec![pane(1.0)], sky);
    let queries = [
        (Vec3::ZERO, Vec3::Z),
        (
            Vec3::new(1.0, 0.2, 0.0),
            Vec3::new(1.0, 1.0, 0.0).normalize(),
        ),
    ];
    for mode in [CachedEnvironment::All, CachedEnvironment::Off] {
        let params = IcParams {
            bounces: 1,
            cached_environment: mode,
            divisions: 8192,
            photons: Some(0),
            ..IcParams::default()
        };
        let (results, _) =
            irradiance_at_points(&built, &params, &queries, PointMethod::Cache, 4096, 3);
        for (r, q) in results.iter().zip(&queries) {
            let got = (r.direct + r.indirect).g;
            assert!(
                (got / (PI * sky) - 1.0).abs() < 0.02,
                "{mode:?} at {q:?}: {got} against πL = {}",
                PI * sky
            );
        }
    }
}

fn masked_quad(y: f32, opacity: f32, albedo: f32) -> ShapeDesc {
    let bsdf = Arc::new(BsdfDesc::Mask {
        opacity: TextureDesc::Constant(Rgb::splat(opacity)),
        nested: Arc::new(BsdfDesc::TwoSided {
            front: diffuse(Rgb::splat(albedo)),
            back: None,
        }),
    });
    horizontal(y, bsdf)
}

#[test]
fn a_sun_behind_a_mask_lights_the_floor_by_what_it_leaves_open() {
    let theta = 30f32.to_radians();
    let irradiance = 2.0;
    let sun = || EmitterDesc::Directional {
        direction: Vec3::new(0.0, -theta.cos(), theta.sin()),
        irradiance: Rgb::splat(irradiance),
    };
    let open = f64::from(RHO / PI * irradiance * theta.cos());
    for integrator in ["path", "direct", "volpath", "ic"] {
        let got = floor_radiance(
            vec![floor(), masked_quad(1.0, 0.3, 0.8)],
            vec![sun()],
            (integrator, 2),
            20.0,
            4,
        );
        assert!(
            (got / (0.7 * open) - 1.0).abs() < 1e-5,
            "{integrator}: {got} against {}",
            0.7 * open
        );
    }
}

#[test]
fn a_camera_sees_a_mask_in_the_share_of_its_opacity() {
    // Looking up from the lit floor's height at a masked ceiling under a bright sky: the sky is
    // seen through the open part, the ceiling (black, lit by nothing above) in the rest.
    let sky = EmitterDesc::Constant {
        radiance: Rgb::splat(2.0),
    };
    let mut desc = scene(
        sensor(
            Vec3::new(0.0, 0.5, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
            10.0,
            8,
            4096,
        ),
        common::path(2),
        vec![masked_quad(1.0, 0.25, 0.0)],
        vec![sky],
    );
    desc.integrator.kind = "path".into();
    let built = Scene::build(&desc).expect("scene builds");
    let integ = Integrator::from_desc(&desc.integrator).expect("integrator");
    let settings = RenderSettings::from_desc(&desc, 3, 2).expect("sampler");
    let out = render(&built, &integ, &settings, &|_| {}).expect("render");
    let (mean, error) = common::mean_and_error(&out.image);
    let expected = 0.75 * 2.0;
    assert!(
        (mean.g - expected).abs() < 4.0 * error.g.max(1e-4) + 5e-3,
        "{} ± {} against {expected}",
        mean.g,
        error.g
    );
}
