//! Participating media against closed forms (NOTES-002 §1.4): transmittance through slabs and
//! grids, volumetric furnaces, an emitting slab, single scattering from a point light against
//! 1-D quadrature; `volpath` equal to `path` without media; integrators without media support
//! refuse such scenes.

mod common;
use common::*;
use ircache_math::{Mat4, Ray, Rgb, Rng, Vec3};
use ircache_render::integrators::{Integrator, RayCounts};
use ircache_render::media::tracking::transmittance_along;
use ircache_render::scene::Scene;
use ircache_scene::*;
use std::sync::Arc;

/// The unit cube [−1, 1]³ scaled by `half` and moved to `center` (outward normals unless
/// `flip`).
fn cube(
    center: Vec3,
    half: Vec3,
    bsdf: Arc<BsdfDesc>,
    media: MediumInterface,
    flip: bool,
) -> ShapeDesc {
    let mut mesh = shapes::cube();
    assert!(shapes::transform_mesh(
        &mut mesh,
        &(Mat4::from_translation(center) * Mat4::from_scale(half))
    ));
    if flip {
        shapes::flip_mesh(&mut mesh);
    }
    ShapeDesc {
        id: None,
        geometry: Geometry::Mesh(mesh),
        bsdf,
        emitter: None,
        emitter_texture: None,
        emitter_pattern: None,
        media,
        location: here(),
    }
}

fn null() -> Arc<BsdfDesc> {
    Arc::new(BsdfDesc::Null)
}

fn interior(m: usize) -> MediumInterface {
    MediumInterface {
        interior: Some(m),
        exterior: None,
    }
}

fn medium(sigma_t: VolumeDesc, albedo: Rgb, emission: Option<Rgb>, phase: PhaseDesc) -> MediumDesc {
    MediumDesc {
        id: None,
        kind: if matches!(sigma_t, VolumeDesc::Grid(_)) {
            MediumKind::Heterogeneous
        } else {
            MediumKind::Homogeneous
        },
        sigma_t,
        albedo: VolumeDesc::constant(albedo),
        emission: emission.map(VolumeDesc::constant),
        scale: 1.0,
        phase,
        sample_emitters: true,
        location: here(),
    }
}

fn volpath(max_depth: i32) -> IntegratorDesc {
    IntegratorDesc {
        kind: "volpath".into(),
        max_depth,
        ..IntegratorDesc::default()
    }
}

/// Mean transmittance along `ray` over `n` estimates (one stream each), with its standard error.
fn mean_transmittance(scene: &Scene, ray: Ray, medium: Option<usize>, n: u32) -> (Rgb, Rgb) {
    let (mut s, mut s2) = (Rgb::ZERO, Rgb::ZERO);
    let mut rays = RayCounts::default();
    for i in 0..n {
        let mut rng = Rng::new(11, u64::from(i));
        let t = transmittance_along(scene, ray, medium, &mut rng, &mut rays);
        s += t;
        s2 += t * t;
    }
    let m = s / n as f32;
    let var = (s2 / n as f32 - m * m).max(Rgb::ZERO);
    (m, (var / n as f32).sqrt())
}

/// A homogeneous slab x ∈ [1, 3] behind a null boundary: e^{−σ_t·2} per channel, exactly; a
/// grid of the same constant by ratio tracking, within 3 standard errors; a linear ramp
/// σ = a + b·x sampled at cell centres, ratio-tracked between the outermost centres:
/// τ = s·σ(midpoint).
#[test]
fn transmittance_through_slabs_and_grids() {
    let sigma = Rgb::new(0.5, 1.0, 2.0);
    let slab = |m: MediumDesc| {
        let mut desc = scene(
            sensor(Vec3::new(0.0, 0.0, -5.0), Vec3::ZERO, 30.0, 4, 1),
            volpath(-1),
            vec![cube(
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(1.0, 4.0, 4.0),
                null(),
                interior(0),
                false,
            )],
            vec![],
        );
        desc.media = vec![m];
        Scene::build(&desc).expect("scene")
    };
    let ray = Ray {
        o: Vec3::new(0.0, 0.3, 0.2),
        d: Vec3::X,
        t_min: 0.0,
        t_max: 5.0,
    };
    let homogeneous = slab(medium(
        VolumeDesc::constant(sigma),
        Rgb::splat(0.5),
        None,
        PhaseDesc::Isotropic,
    ));
    let (t, e) = mean_transmittance(&homogeneous, ray, None, 4);
    let expect = (sigma * -2.0).exp();
    for c in 0..3 {
        // Within the ray-origin offsets at the two crossings (a relative 1e-5 of the scene).
        assert!(
            (t[c] - expect[c]).abs() <= 1e-4 * expect[c],
            "channel {c}: {} vs {}",
            t[c],
            expect[c]
        );
        assert_eq!(e[c], 0.0, "closed form is deterministic");
    }
    // The same medium seen from inside (the ray starts in it) and a blocked ray.
    let inside = Ray {
        o: Vec3::new(2.5, 0.0, 0.0),
        ..ray
    };
    let (t, _) = mean_transmittance(&homogeneous, inside, Some(0), 1);
    assert!((t[1] - (-0.5f32).exp() * 1.0).abs() < 1e-5, "{t:?}");

    // A constant grid over the slab: ratio tracking is unbiased.
    let lo = Vec3::new(1.0, -4.0, -4.0);
    let hi = Vec3::new(3.0, 4.0, 4.0);
    let constant = slab(medium(
        grid([4, 4, 4], lo, hi, |_| 1.5),
        Rgb::splat(0.5),
        None,
        PhaseDesc::Isotropic,
    ));
    let (t, e) = mean_transmittance(&constant, ray, None, 40_000);
    let expect = (-1.5f32 * 2.0).exp();
    assert!(
        (t[0] - expect).abs() < 3.0 * e[0] + 1e-4,
        "{} vs {expect} ± {}",
        t[0],
        e[0]
    );

    // A linear ramp in x: exact between the first and last sample centres (x ∈ [1.125, 2.875]
    // for 8 cells over [1, 3]); the ray runs from x = 1.25 to 2.75.
    let (a, b) = (0.2, 0.6);
    let ramp = slab(medium(
        grid([8, 2, 2], lo, hi, |p| a + b * p.x),
        Rgb::splat(0.5),
        None,
        PhaseDesc::Isotropic,
    ));
    let inner = Ray {
        o: Vec3::new(1.25, 0.1, 0.3),
        t_max: 1.5,
        ..ray
    };
    let (t, e) = mean_transmittance(&ramp, inner, Some(0), 200_000);
    let expect = (-(1.5 * (a + b * 2.0))).exp();
    assert!(
        (t[0] - expect).abs() < 3.0 * e[0] + 1e-4 && e[0] < 0.01 * expect,
        "ramp: {} vs {expect} ± {}",
        t[0],
        e[0]
    );
}

/// A closed box of black walls emitting L0 inwards, filled with a non-absorbing medium, camera
/// inside: radiance L0 everywhere, whatever the phase function and the density. With walls of
/// albedo ρ emitting (1 − ρ)L0 the same holds.
#[test]
fn volumetric_furnaces_are_uniform() {
    let l0 = 0.7;
    let cases: Vec<(&str, VolumeDesc, PhaseDesc, f32)> = vec![
        (
            "homogeneous isotropic",
            VolumeDesc::constant(Rgb::splat(2.0)),
            PhaseDesc::Isotropic,
            0.0,
        ),
        (
            "homogeneous hg 0.8",
            VolumeDesc::constant(Rgb::new(1.0, 2.0, 3.0)),
            PhaseDesc::HenyeyGreenstein { g: 0.8 },
            0.5,
        ),
        (
            "grid hg -0.8",
            grid([6, 6, 6], Vec3::splat(-1.0), Vec3::splat(1.0), |p| {
                1.0 + p.x * p.x + 0.5 * p.y
            }),
            PhaseDesc::HenyeyGreenstein { g: -0.8 },
            0.0,
        ),
    ];
    for (name, sigma_t, phase, rho) in cases {
        let mut walls = cube(
            Vec3::ZERO,
            Vec3::ONE,
            diffuse(Rgb::splat(rho)),
            MediumInterface::default(),
            true,
        );
        walls.emitter = Some(Rgb::splat((1.0 - rho) * l0));
        let mut cam = sensor(
            Vec3::new(0.1, -0.2, 0.05),
            Vec3::new(1.0, 0.3, 0.4),
            90.0,
            12,
            32,
        );
        cam.medium = Some(0);
        let mut desc = scene(cam, volpath(-1), vec![walls], vec![]);
        desc.media = vec![medium(sigma_t, Rgb::ONE, None, phase)];
        let out = render_desc(&desc, 2, 3);
        let (m, e) = mean_and_error(&out.image);
        for c in 0..3 {
            assert!(
                (m[c] - l0).abs() < (4.0 * e[c]).max(0.005 * l0),
                "{name}, channel {c}: {} vs {l0} (σ {})",
                m[c],
                e[c]
            );
        }
        assert_eq!(out.invalid_samples, 0, "{name}");
    }
}

/// An absorbing, emitting slab of optical depth τ seen at normal incidence against black:
/// L_e (1 − e^{−τ}) per channel (the emission convention σ_a L_e per unit length).
#[test]
fn emitting_slab_shows_le_times_one_minus_transmittance() {
    let sigma = Rgb::new(0.3, 1.0, 2.5);
    let le = Rgb::new(1.0, 2.0, 0.5);
    let slab = cube(
        Vec3::ZERO,
        Vec3::new(20.0, 20.0, 0.5),
        null(),
        interior(0),
        false,
    );
    let mut desc = scene(
        sensor(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, 1.0, 4, 256),
        volpath(1),
        vec![slab],
        vec![],
    );
    desc.media = vec![medium(
        VolumeDesc::constant(sigma),
        Rgb::ZERO,
        Some(le),
        PhaseDesc::Isotropic,
    )];
    let out = render_desc(&desc, 2, 5);
    let (m, e) = mean_and_error(&out.image);
    let expect = le * (Rgb::ONE - (sigma * -1.0).exp());
    for c in 0..3 {
        assert!(
            (m[c] - expect[c]).abs() < (4.0 * e[c]).max(0.005 * expect[c]),
            "channel {c}: {} vs {} (σ {})",
            m[c],
            expect[c],
            e[c]
        );
    }
}

/// Single scattering from a point light of intensity I in an infinite homogeneous medium
/// (`max_depth` 2), camera ray passing the light at distance D with its foot a distance C ahead:
/// L = ∫_{−C}^{∞} σ_s p(θ) I e^{−σ_t (C + t)} e^{−σ_t ℓ}/ℓ² dt, ℓ = √(D² + t²), by quadrature.
///
/// With the light 0.02 from the ray, free-flight sampling alone puts a vertex near the light
/// rarely and then weighs it by 1/r²: its estimate's spread over 4096 samples was 6.1 %
/// (isotropic) and 1.8 % (g = 0.5), against the 1 % asked here, which equiangular sampling of
/// the light meets (0.32 % and 0.86 %; `integrators::equiangular`). A spot light that lights
/// part of the ray checks that its equiangular samples, kept to its cone, and the free flight's
/// are weighed consistently; the same medium as a grid of equal voxels, that the weights' stand-in
/// for the free flight's density there keeps the sum unbiased (1 % asked: ratio tracking adds its
/// own noise).
#[test]
fn single_scattering_matches_quadrature() {
    let (sigma_t, albedo, intensity, c) = (0.5f64, 0.6f64, 3.0f64, 2.0f64);
    // A spot light aimed 45° down and ahead (cutoff 30°, beam 20°) lights only part of the ray.
    let (cutoff, beam) = (30f64.to_radians(), 20f64.to_radians());
    // The same medium as a grid of equal voxels: ratio tracking, majorant cells, lookups.
    for (d, phase, spot, grid) in [
        (1.0f64, PhaseDesc::Isotropic, false, false),
        (1.0, PhaseDesc::HenyeyGreenstein { g: 0.5 }, false, false),
        (0.02, PhaseDesc::Isotropic, false, false),
        (0.02, PhaseDesc::HenyeyGreenstein { g: 0.5 }, false, false),
        (0.02, PhaseDesc::HenyeyGreenstein { g: 0.5 }, true, false),
        (0.3, PhaseDesc::Isotropic, true, false),
        (0.02, PhaseDesc::Isotropic, false, true),
        (0.3, PhaseDesc::HenyeyGreenstein { g: 0.5 }, true, true),
    ] {
        let g = match phase {
            PhaseDesc::Isotropic => 0.0,
            PhaseDesc::HenyeyGreenstein { g } => f64::from(g),
        };
        let integrand = |t: f64| {
            let l = (d * d + t * t).sqrt();
            // cos θ between the ray (+z) and the direction towards the light.
            let cos = -t / l;
            let p = (1.0 - g * g)
                / (4.0 * std::f64::consts::PI * (1.0 + g * g - 2.0 * g * cos).powf(1.5));
            // The spot's falloff, linear in the angle off its axis (0, −1, 1)/√2.
            let falloff = if spot {
                let angle = ((d + t) / (std::f64::consts::SQRT_2 * l))
                    .clamp(-1.0, 1.0)
                    .acos();
                ((cutoff - angle) / (cutoff - beam)).clamp(0.0, 1.0)
            } else {
                1.0
            };
            sigma_t
                * albedo
                * p
                * intensity
                * falloff
                * (-sigma_t * (c + t)).exp()
                * (-sigma_t * l).exp()
                / (l * l)
        };
        // In pieces, so that the spot's lit stretch near the light is not stepped over.
        let mut cuts = [-c, -d, 0.0, d, 2.0 * d, 4.0 * d, 10.0 * d, 1.0, 80.0];
        cuts.sort_by(f64::total_cmp);
        let reference: f64 = cuts
            .windows(2)
            .filter(|w| w[1] > w[0])
            .map(|w| ircache_render::testing::adaptive_simpson(&integrand, w[0], w[1], 1e-11, 40))
            .sum();
        // Something to trace against, far off the ray.
        let speck = ShapeDesc {
            id: None,
            geometry: Geometry::Sphere {
                center: Vec3::new(500.0, 500.0, -500.0),
                radius: 0.01,
                flip_normals: false,
                orientation: ircache_math::Mat3::IDENTITY,
            },
            bsdf: diffuse(Rgb::ZERO),
            emitter: None,
            emitter_texture: None,
            emitter_pattern: None,
            media: MediumInterface::default(),
            location: here(),
        };
        let mut cam = sensor(
            Vec3::new(0.0, 0.0, -c as f32),
            Vec3::new(0.0, 0.0, 1.0),
            0.01,
            2,
            4096,
        );
        cam.medium = Some(0);
        let light = if spot {
            EmitterDesc::Spot {
                to_world: Mat4::from_translation(Vec3::new(0.0, d as f32, 0.0))
                    * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_4),
                intensity: Rgb::splat(intensity as f32),
                cutoff_angle: cutoff.to_degrees() as f32,
                beam_width: beam.to_degrees() as f32,
            }
        } else {
            EmitterDesc::Point {
                position: Vec3::new(0.0, d as f32, 0.0),
                intensity: Rgb::splat(intensity as f32),
            }
        };
        // `volpath`, and the cache's pixel pass, which marches the camera ray to infinity.
        for integrator in ["volpath", "ic"] {
            let mut desc = scene(
                cam.clone(),
                IntegratorDesc {
                    kind: integrator.into(),
                    ..volpath(2)
                },
                vec![speck.clone()],
                vec![light.clone()],
            );
            let extinction = if grid {
                VolumeDesc::Grid(Arc::new(GridVolumeDesc {
                    path: "<test>".into(),
                    resolution: [2, 2, 2],
                    channels: 1,
                    data: vec![sigma_t as f32; 8],
                    to_world: Mat4::from_translation(Vec3::splat(-100.0))
                        * Mat4::from_scale(Vec3::splat(200.0)),
                    filter: TextureFilter::Bilinear,
                    wrap: WrapMode::Clamp,
                }))
            } else {
                VolumeDesc::constant(Rgb::splat(sigma_t as f32))
            };
            desc.media = vec![medium(extinction, Rgb::splat(albedo as f32), None, phase)];
            let out = render_desc(&desc, 2, 9);
            let (m, e) = mean_and_error(&out.image);
            let got = f64::from(m.g);
            assert!(
                (got - reference).abs() < (4.0 * f64::from(e.g)).max(0.01 * reference),
                "{integrator}, {phase:?}, spot {spot}, grid {grid}, light {d} from the ray: {got} vs \
                 quadrature {reference} (σ {})",
                e.g
            );
            assert!(
                f64::from(e.g) < if d < 0.1 || grid { 0.01 } else { 0.005 } * reference,
                "{integrator}, {phase:?}, spot {spot}, grid {grid}, light {d} from the ray: too noisy, \
                 σ {} of {reference}",
                e.g
            );
        }
    }
}

/// Without media, `volpath` is path tracing: the sphere furnace (ρ = 0.5, L_e = 0.5) gives
/// L_e/(1 − ρ), and a null sphere inside it changes nothing.
#[test]
fn volpath_without_media_is_path_tracing() {
    let furnace = ShapeDesc {
        id: None,
        geometry: Geometry::Sphere {
            center: Vec3::ZERO,
            radius: 5.0,
            flip_normals: true,
            orientation: ircache_math::Mat3::IDENTITY,
        },
        bsdf: diffuse(Rgb::splat(0.5)),
        emitter: Some(Rgb::splat(0.5)),
        emitter_texture: None,
        emitter_pattern: None,
        media: MediumInterface::default(),
        location: here(),
    };
    let ghost = cube(
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::splat(0.5),
        null(),
        MediumInterface::default(),
        false,
    );
    let desc = scene(
        sensor(
            Vec3::new(-2.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            60.0,
            12,
            32,
        ),
        volpath(-1),
        vec![furnace, ghost],
        vec![],
    );
    let out = render_desc(&desc, 2, 1);
    let (m, e) = mean_and_error(&out.image);
    assert!(
        (m.r - 1.0).abs() < (4.0 * e.r).max(0.005),
        "{} ± {}",
        m.r,
        e.r
    );
}

/// `path` and `direct` refuse a scene with media (naming `volpath`) rather than render it as if
/// the medium were not there (the irradiance cache renders it through the media: the tests
/// below); the same image comes back at 1 and 2 threads.
#[test]
fn media_scenes_need_volpath_and_render_deterministically() {
    let fog = cube(Vec3::ZERO, Vec3::splat(1.0), null(), interior(0), false);
    let light = EmitterDesc::Point {
        position: Vec3::new(0.0, 2.0, 0.0),
        intensity: Rgb::splat(5.0),
    };
    let floor = quad(
        [
            Vec3::new(-3.0, -1.5, -3.0),
            Vec3::new(-3.0, -1.5, 3.0),
            Vec3::new(3.0, -1.5, 3.0),
            Vec3::new(3.0, -1.5, -3.0),
        ],
        diffuse(Rgb::splat(0.5)),
        None,
    );
    let mut desc = scene(
        sensor(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, 45.0, 8, 4),
        volpath(4),
        vec![fog, floor],
        vec![light],
    );
    desc.media = vec![medium(
        VolumeDesc::constant(Rgb::splat(0.8)),
        Rgb::splat(0.9),
        None,
        PhaseDesc::Isotropic,
    )];
    let scene_built = Scene::build(&desc).expect("scene");
    let settings =
        ircache_render::render::RenderSettings::from_desc(&desc, 1, 1).expect("settings");
    for kind in ["path", "direct"] {
        let integrator = Integrator::from_desc(&IntegratorDesc {
            kind: kind.into(),
            ..IntegratorDesc::default()
        })
        .expect("integrator");
        let err = ircache_render::render::render(&scene_built, &integrator, &settings, &|_| {})
            .err()
            .unwrap_or_else(|| panic!("{kind} rendered a scene with media"));
        assert!(err.to_string().contains("volpath"), "{kind}: {err}");
    }
    let one = render_desc(&desc, 1, 4);
    let two = render_desc(&desc, 2, 4);
    assert_eq!(one.image.pixels, two.image.pixels);
    assert!(one.image.pixels.iter().any(|p| p.g > 0.0));
}

/// Shadow rays through a null box whose top face lies just under an area light (Cornell box
/// proportions: face 2 cm below, wall 2 cm behind the box): after a grazing crossing, each
/// segment still ends short of the light, so no sample of the light is lost.
#[test]
fn shadow_rays_through_grazing_crossings_reach_the_light() {
    let light = quad(
        [
            Vec3::new(-0.24, 1.98, -0.22),
            Vec3::new(0.23, 1.98, -0.22),
            Vec3::new(0.23, 1.98, 0.16),
            Vec3::new(-0.24, 1.98, 0.16),
        ],
        diffuse(Rgb::ZERO),
        Some(Rgb::splat(10.0)),
    );
    let wall = quad(
        [
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(1.0, 2.0, -1.0),
            Vec3::new(-1.0, 2.0, -1.0),
        ],
        diffuse(Rgb::splat(0.5)),
        None,
    );
    let fog = cube(
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.98, 0.96, 0.98),
        null(),
        interior(0),
        false,
    );
    let mut desc = scene(
        sensor(
            Vec3::new(0.0, 1.0, 6.8),
            Vec3::new(0.0, 1.0, 0.0),
            20.0,
            4,
            1,
        ),
        volpath(2),
        vec![light, wall, fog],
        vec![],
    );
    desc.media = vec![medium(
        VolumeDesc::constant(Rgb::ZERO),
        Rgb::ZERO,
        None,
        PhaseDesc::Isotropic,
    )];
    let scene = Scene::build(&desc).expect("scene");
    let mut rays = RayCounts::default();
    for y in [1.7f32, 1.8, 1.85, 1.9, 1.95] {
        let probe = Ray::new(Vec3::new(0.1, y, -0.99), Vec3::new(0.0, 0.0, -1.0));
        let hit = scene.accel.intersect(&probe).expect("the wall");
        let it = scene.interaction(&probe, &hit);
        for i in 0..8 {
            for j in 0..8 {
                let u = ircache_math::Vec2::new((i as f32 + 0.5) / 8.0, (j as f32 + 0.5) / 8.0);
                let Some(ls) = scene.lights.sample(it.p, 0.5, u) else {
                    continue;
                };
                let ray = scene.shadow_ray(&it, ls.wi, ls.distance);
                let t = transmittance_along(&scene, ray, None, &mut Rng::new(1, 1), &mut rays);
                assert_eq!(
                    t,
                    Rgb::ONE,
                    "wall point at y = {y}, light sample {u}: blocked"
                );
            }
        }
    }
}

/// The project's media scene `name` at `size`² with `spp` samples and `integrator` at
/// `max_depth`.
fn fog_scene(name: &str, integrator: &str, max_depth: i32, size: u32, spp: u32) -> SceneDesc {
    let defines: Vec<(String, String)> = [
        ("integrator", integrator.to_string()),
        ("max_depth", max_depth.to_string()),
        ("resx", size.to_string()),
        ("resy", size.to_string()),
        ("spp", spp.to_string()),
    ]
    .into_iter()
    .map(|(a, b)| (a.to_string(), b))
    .collect();
    project_scene(name, &defines)
}

/// The shared fog Cornell box at `size`² with `spp` samples and `integrator` at `max_depth`.
fn cornell_fog(integrator: &str, max_depth: i32, size: u32, spp: u32) -> SceneDesc {
    fog_scene("cornell-fog", integrator, max_depth, size, spp)
}

/// `desc` with string parameters added to its integrator.
fn with_params(mut desc: SceneDesc, params: &[(&str, &str)]) -> SceneDesc {
    for (key, value) in params {
        desc.integrator
            .extra
            .push(((*key).into(), ParamValue::String((*value).into()), here()));
    }
    desc
}

/// `image` against `reference` as it is and after a blur of σ = 2 pixels (where blotches, leaks
/// and bias show).
fn against(
    image: &ircache_image::Image,
    reference: &ircache_image::Image,
) -> (
    ircache_image::compare::Metrics,
    ircache_image::compare::Metrics,
) {
    let blur = |i| ircache_image::blur::gaussian_blur(i, 2.0);
    (
        ircache_image::compare::compare(image, reference).expect("same size"),
        ircache_image::compare::compare(&blur(image), &blur(reference)).expect("same size"),
    )
}

/// The irradiance cache in the fog Cornell box (one bounce, records gathered through the fog
/// with 002's gradients) agrees with volpath at `max_depth` 3: the same mean luminance within
/// 1.5 % and, after a 2-pixel blur (blotches, leaks, bias), a relMSE below 2e-3, for every
/// gradient form; the same image at 1 and 2 threads.
#[test]
fn media_cache_agrees_with_volpath_at_one_bounce() {
    let reference = render_desc(&cornell_fog("volpath", 3, 32, 1024), 2, 1).image;
    for gradient in ["corrected", "none"] {
        // Ward's records, as 002 places them (Tabellion's, the default, span ten pixel
        // footprints: coarse at 32², +1.8 % here, +0.2 % at 128²).
        let desc = with_params(
            cornell_fog("irrcache", 3, 32, 64),
            &[("media_gradient", gradient), ("error_metric", "ward")],
        );
        let out = render_desc(&desc, 2, 2);
        assert!(
            out.media_cache.is_some_and(|s| s.records > 20),
            "{gradient}: records were made"
        );
        let (m, mb) = against(&out.image, &reference);
        assert!(
            (m.lum_ratio - 1.0).abs() < 0.015,
            "{gradient}: luminance ratio {}",
            m.lum_ratio
        );
        assert!(
            mb.rel_mse < 2e-3,
            "{gradient}: blurred relMSE {}",
            mb.rel_mse
        );
        if gradient == "corrected" {
            let one = render_desc(&desc, 1, 2);
            assert_eq!(
                one.image.pixels, out.image.pixels,
                "thread count changed the image"
            );
        }
    }
}

/// `scenes/open-fog`: a camera standing in unbounded fog under a sky, lit by a point lamp and a
/// spot light. The cache's pixel pass marches rays that leave through the fog to the sky (it
/// once gave them no points and no transmittance: the sky black) and samples the lamps
/// equiangularly, and its volumetric records, whose gathers mostly escape, take their size from
/// the distance to the lamps (unbounded by it they read 0.86 in the upper half here): its mean
/// luminance within 5 % of `volpath`'s, over the whole image and over the upper half, where the
/// sky and the lamps' glow are.
#[test]
fn media_cache_sees_open_fog_and_its_lamps() {
    let size = 40;
    let reference = render_desc(&fog_scene("open-fog", "volpath", 5, size, 512), 2, 1).image;
    let out = render_desc(&fog_scene("open-fog", "irrcache", 5, size, 64), 2, 2);
    let upper: Vec<usize> = (0..size as usize * size as usize / 2).collect();
    let all: Vec<usize> = (0..reference.pixels.len()).collect();
    for (what, pixels) in [("image", &all), ("upper half", &upper)] {
        let ratio = luminance_ratio_over(pixels, &out.image, &reference);
        assert!(
            (ratio - 1.0).abs() < 0.05,
            "{what}: luminance ratio {ratio} against volpath"
        );
    }
}

/// Deeper bounces in media (`-ab` above 1), in closed form: a white plane in an unbounded medium
/// that emits (σ_a L_e with L_e = 1) and scatters isotropically (albedo α = 0.8), no lights.
/// With one bounce a record's gather sees the medium's emission alone, E = π(1 − α); with every
/// bounce the field is in equilibrium (the white plane and the scattering return all they
/// receive), L = L_e in every direction, so E = π. The records' gathers, their deeper bounces by
/// a path per gather ray, within 3 % of both, at points across the plane; and `-ab 0` reads no
/// indirect light.
#[test]
fn media_records_gather_every_bounce_of_an_emitting_medium() {
    use ircache_render::irradiance_cache::points::PointMethod;
    use ircache_render::irradiance_cache::IcParams;
    use ircache_render::media_cache::points::media_irradiance_at_points;
    let half = 200.0;
    let plane = quad(
        [
            Vec3::new(-half, 0.0, -half),
            Vec3::new(-half, 0.0, half),
            Vec3::new(half, 0.0, half),
            Vec3::new(half, 0.0, -half),
        ],
        diffuse(Rgb::ONE),
        None,
    );
    let mut cam = sensor(Vec3::new(0.0, 2.0, 5.0), Vec3::ZERO, 40.0, 8, 1);
    cam.medium = Some(0);
    let mut desc = scene(cam, volpath(-1), vec![plane], vec![]);
    let albedo = 0.8;
    desc.media = vec![medium(
        VolumeDesc::constant(Rgb::ONE),
        Rgb::splat(albedo),
        Some(Rgb::ONE),
        PhaseDesc::Isotropic,
    )];
    let scene = Scene::build(&desc).expect("scene");
    let points: Vec<(Vec3, Vec3)> = [(0.0, 0.0), (1.5, -0.7), (-3.0, 2.0), (0.3, 4.0)]
        .into_iter()
        .map(|(x, z)| (Vec3::new(x, 0.0, z), Vec3::Y))
        .collect();
    let pi = std::f32::consts::PI;
    for (bounces, want) in [
        (0, 0.0),
        (1, pi * (1.0 - albedo)),
        (ircache_render::irradiance_cache::params::UNBOUNDED, pi),
    ] {
        let params = IcParams {
            bounces,
            media_divisions: 4096,
            ..IcParams::default()
        };
        let got = media_irradiance_at_points(&scene, &params, &points, PointMethod::Cache, 0, 5);
        for (r, (p, _)) in got.iter().zip(&points) {
            for c in 0..3 {
                let e = r.indirect[c];
                assert!(
                    (e - want).abs() <= 0.03 * want.max(1e-6),
                    "bounces {bounces} at {p}, channel {c}: E {e} against {want}"
                );
            }
        }
    }
}

/// The cache in the fog Cornell box at `max_depth` 5 and unbounded, against `volpath` at the
/// same depth: the same mean luminance within 2 % and a blurred relMSE below 1e-3, where the
/// one-bounce cache misses the deeper light (more than 5 % dark); the same image at 1 and 2
/// threads; a cache per bounce is refused by name.
#[test]
fn media_cache_follows_deeper_bounces() {
    for depth in [5, -1] {
        let reference = render_desc(&cornell_fog("volpath", depth, 32, 1024), 2, 1).image;
        // Ward's records, as in the one-bounce test (Tabellion's are coarse at 32²).
        let with_ward = |desc: SceneDesc| with_params(desc, &[("error_metric", "ward")]);
        let desc = with_ward(cornell_fog("irrcache", depth, 32, 64));
        let out = render_desc(&desc, 2, 2);
        let (m, mb) = against(&out.image, &reference);
        assert!(
            (m.lum_ratio - 1.0).abs() < 0.02,
            "max_depth {depth}: luminance ratio {}",
            m.lum_ratio
        );
        assert!(
            mb.rel_mse < 1e-3,
            "max_depth {depth}: blurred relMSE {}",
            mb.rel_mse
        );
        let one_bounce = render_desc(&with_ward(cornell_fog("irrcache", 3, 32, 64)), 2, 2);
        let m1 = ircache_image::compare::compare(&one_bounce.image, &reference).expect("same size");
        assert!(
            m1.lum_ratio < 0.95,
            "max_depth {depth}: one bounce reads {} of it",
            m1.lum_ratio
        );
        if depth == 5 {
            let one = render_desc(&desc, 1, 2);
            assert_eq!(
                one.image.pixels, out.image.pixels,
                "thread count changed the image"
            );
        }
    }
    let per_bounce = with_params(
        cornell_fog("irrcache", 5, 8, 1),
        &[("deeper_bounces", "cache")],
    );
    let scene = Scene::build(&per_bounce).expect("scene");
    let settings =
        ircache_render::render::RenderSettings::from_desc(&per_bounce, 1, 1).expect("settings");
    let integrator = Integrator::from_desc(&per_bounce.integrator).expect("integrator");
    let Err(err) = ircache_render::render::render(&scene, &integrator, &settings, &|_| {}) else {
        panic!("a cache per bounce was not refused");
    };
    assert!(err.to_string().contains("--deeper-bounces traced"), "{err}");
}

/// In media the records serve the Lambertian part of glossy surfaces too, the glossy part
/// traced from the first surface (as `path`'s split): the fog box with a rough plastic floor
/// (GGX α 0.2) and a smooth plastic short box, two bounces, takes records on the floor and
/// agrees with `volpath` (mean luminance within 2 %, blurred relMSE below 1e-3).
#[test]
fn media_cache_serves_the_lambertian_part_of_glossy_surfaces() {
    let glossy = |mut desc: SceneDesc| {
        for shape in &mut desc.shapes {
            match shape.id.as_deref() {
                Some("Floor") => {
                    shape.bsdf = Arc::new(BsdfDesc::RoughPlastic {
                        distribution: MicrofacetDistribution::Ggx,
                        alpha: 0.2,
                        diffuse_reflectance: TextureDesc::Constant(Rgb::splat(0.6)),
                        specular_reflectance: Rgb::ONE,
                        int_ior: 1.49,
                        ext_ior: 1.000_277,
                        nonlinear: false,
                    });
                }
                Some("ShortBox") => {
                    shape.bsdf = Arc::new(BsdfDesc::Plastic {
                        diffuse_reflectance: TextureDesc::Constant(Rgb::new(0.2, 0.3, 0.6)),
                        specular_reflectance: Rgb::ONE,
                        int_ior: 1.49,
                        ext_ior: 1.000_277,
                        nonlinear: false,
                    });
                }
                _ => {}
            }
        }
        desc
    };
    let reference_desc = glossy(cornell_fog("volpath", 4, 32, 1024));
    let reference = render_desc(&reference_desc, 2, 1).image;
    let desc = with_params(
        glossy(cornell_fog("irrcache", 4, 32, 64)),
        &[("error_metric", "ward")],
    );
    let scene = Scene::build(&desc).expect("scene");
    let params = ircache_render::integrators::ic::IcIntegrator::from_desc(&desc.integrator)
        .expect("ic")
        .params;
    let cache = ircache_render::media_cache::cache::MediaCache::build(
        &scene,
        &params,
        (32, 32),
        2,
        Vec::new(),
        Default::default(),
    );
    let on_floor = cache
        .records()
        .iter()
        .filter(|r| r.p.y.abs() < 1e-3 && r.n.y > 0.99)
        .count();
    assert!(
        on_floor > 3,
        "{on_floor} records on the rough plastic floor"
    );
    let out = render_desc(&desc, 2, 2);
    let (m, mb) = against(&out.image, &reference);
    assert!(
        (m.lum_ratio - 1.0).abs() < 0.02,
        "luminance ratio {}",
        m.lum_ratio
    );
    assert!(mb.rel_mse < 1e-3, "blurred relMSE {}", mb.rel_mse);
}

/// The cache's pixel pass in media (`integrators::media_march`), in the fog Cornell box at one
/// bounce against volpath: camera rays marched without volumetric records are unbiased (mean
/// luminance within 2 %, the surface records' budget at this size) and, at equal samples, less
/// noisy than tracked ones; the volumetric records then take the in-scattered indirect light's
/// noise away (relMSE under half the marched render's) and move the mean by under 1 %; the
/// image is the same at 1 and 2 threads.
#[test]
fn marched_camera_rays_and_volumetric_records_agree_with_volpath() {
    let reference = render_desc(&cornell_fog("volpath", 3, 32, 1024), 2, 1).image;
    let run = |extra: &[(&str, &str)], threads: usize| {
        let desc = with_params(cornell_fog("irrcache", 3, 32, 64), extra);
        render_desc(
            &with_params(desc, &[("media_gradient", "none")]),
            threads,
            3,
        )
    };
    let error = |out: &ircache_render::render::RenderOutput| {
        ircache_image::compare::compare(&out.image, &reference).expect("same size")
    };
    let tracked = error(&run(&[("media_march", "0")], 2));
    let marched = error(&run(&[("media_volume_records", "off")], 2));
    let cached_out = run(&[], 2);
    let cached = error(&cached_out);
    // (At 32² the surface records sit 1–2 % above volpath in every variant: the budget below;
    // at 128² they agree within 0.1 %, BENCHMARKS.md.)
    assert!(
        (marched.lum_ratio - 1.0).abs() < 0.02,
        "marched: luminance ratio {}",
        marched.lum_ratio
    );
    assert!(
        marched.rel_mse_trim < tracked.rel_mse_trim,
        "marched {} against tracked {}",
        marched.rel_mse_trim,
        tracked.rel_mse_trim
    );
    assert!(
        (cached.lum_ratio / marched.lum_ratio - 1.0).abs() < 0.01,
        "volumetric records: luminance {} against the marched render's {}",
        cached.lum_ratio,
        marched.lum_ratio
    );
    assert!(
        cached.rel_mse_trim < 0.5 * marched.rel_mse_trim,
        "volumetric records {} against marched {}",
        cached.rel_mse_trim,
        marched.rel_mse_trim
    );
    assert!(cached_out.volume_records.is_some_and(|s| s.records > 10));
    let one = run(&[], 1);
    assert_eq!(
        one.image.pixels, cached_out.image.pixels,
        "thread count changed the image"
    );
}

/// `scenes/glass-in-fog` (the fog box with a glass sphere and a gold one) at `max_depth`
/// `depth`, `size`² and `spp`.
fn glass_in_fog(integrator: &str, depth: i32, size: u32, spp: u32) -> SceneDesc {
    fog_scene("glass-in-fog", integrator, depth, size, spp)
}

/// The pixel pass's march goes on through smooth glass (`media_march`'s delta continuation):
/// in the fog box with a glass sphere at `max_depth` 4 (where no path through the sphere can
/// reach the lamp after a bounce: no caustics there), the pixels that see the fog and the room
/// through the sphere (two refractions; the vertices behind them two deeper, where the records
/// do not serve) agree with `volpath` in mean luminance within 8 % (renders of other seeds
/// spread by ±4 %; the delta vertices left uncounted read 2.6–2.9×), and the whole image within
/// 2 % (seeds 2, 3 and 4 read 0.985, 1.000 and 0.991 at this size).
#[test]
fn marched_camera_rays_go_on_through_glass() {
    let size = 32u32;
    let reference = render_desc(&glass_in_fog("volpath", 4, size, 4096), 2, 1).image;
    let desc = with_params(
        glass_in_fog("irrcache", 4, size, 256),
        &[("error_metric", "ward")],
    );
    let image = render_desc(&desc, 2, 2).image;
    let scene = Scene::build(&desc).expect("scene");
    // The pixels whose camera ray meets the glass first.
    let glass = pixels_first_meeting(&scene, size, &reference, |_, bsdf, _| !bsdf.has_smooth());
    assert!(glass.len() > 20, "{} pixels see the glass", glass.len());
    let ratio = luminance_ratio_over(&glass, &image, &reference);
    assert!(
        (ratio - 1.0).abs() < 0.08,
        "through the glass: luminance ratio {ratio}"
    );
    let (m, _) = against(&image, &reference);
    assert!(
        (m.lum_ratio - 1.0).abs() < 0.02,
        "whole image: luminance ratio {}",
        m.lum_ratio
    );
}

/// The pixels of `scene`'s `size`² image whose camera ray (through null boundaries) first meets
/// an opaque surface that emits nothing and whose BSDF there, seen along the ray (local `wo`),
/// satisfies `first`; less the few that see the lamp's small images in it (brighter than four
/// times the median of `reference` over them), whose coverage by a pixel's samples would
/// decide their mean.
fn pixels_first_meeting(
    scene: &Scene,
    size: u32,
    reference: &ircache_image::Image,
    first: impl Fn(&Scene, &ircache_render::bsdf::Bsdf, Vec3) -> bool,
) -> Vec<usize> {
    let meets = |x: u32, y: u32| {
        let film = ircache_math::Vec2::new(
            (x as f32 + 0.5) / size as f32,
            (y as f32 + 0.5) / size as f32,
        );
        let mut ray = scene.camera.generate_ray(film);
        for _ in 0..8 {
            let Some(it) = scene.intersect(&ray) else {
                return false;
            };
            let shape = &scene.shapes[it.shape as usize];
            if !shape.null {
                let bsdf = it.bsdf(&scene.materials[shape.material], ray.d);
                return shape.area_light.is_none()
                    && first(scene, &bsdf, it.frame.to_local(-ray.d));
            }
            ray = scene.spawn_ray(&it, ray.d);
        }
        false
    };
    let pixels: Vec<usize> = (0..size * size)
        .filter(|&i| meets(i % size, i / size))
        .map(|i| i as usize)
        .collect();
    let mut seen: Vec<f64> = pixels
        .iter()
        .map(|&i| luminance(reference.pixels[i]))
        .collect();
    seen.sort_by(f64::total_cmp);
    let Some(&median) = seen.get(seen.len() / 2) else {
        return pixels;
    };
    pixels
        .into_iter()
        .filter(|&i| luminance(reference.pixels[i]) < 4.0 * median)
        .collect()
}

/// Luminance (Rec. 709).
fn luminance(p: Rgb) -> f64 {
    f64::from(0.2126 * p.r + 0.7152 * p.g + 0.0722 * p.b)
}

/// The summed luminance of `image` over `pixels` against `reference`'s.
fn luminance_ratio_over(
    pixels: &[usize],
    image: &ircache_image::Image,
    reference: &ircache_image::Image,
) -> f64 {
    let sum =
        |im: &ircache_image::Image| pixels.iter().map(|&i| luminance(im.pixels[i])).sum::<f64>();
    sum(image) / sum(reference)
}

/// Records by depth in media (`MediaCache`'s levels): in `scenes/glass-in-fog` at its own
/// `max_depth` 6, the surfaces seen in the gold sphere (one level deeper) and through the glass
/// one (two deeper) are served by records that hold the bounces a path may still take there.
/// The pixels whose camera ray meets a surface without a Lambertian part first (the two spheres
/// but for the lamp's small images in them) agree with `volpath` in mean luminance within 6 %
/// (1.021 here, 1.036 at another seed; level-0 records serving every depth read 1.124), the
/// whole image within 1.5 %; records were made at both deeper levels. 15 s on two cores.
#[test]
#[ignore = "15 s: cargo test --release -p ircache-render --test media -- --ignored"]
fn media_records_by_depth_serve_what_glass_and_metal_show() {
    let size = 48u32;
    let reference = render_desc(&glass_in_fog("volpath", 6, size, 2048), 2, 1).image;
    let desc = with_params(
        glass_in_fog("irrcache", 6, size, 256),
        &[("error_metric", "ward")],
    );
    let out = render_desc(&desc, 2, 2);
    let per_level = out
        .media_cache
        .as_ref()
        .expect("media cache")
        .per_level
        .clone();
    assert!(
        per_level.len() == 3 && per_level.iter().all(|&n| n > 5),
        "records per level {per_level:?}"
    );
    let scene = Scene::build(&desc).expect("scene");
    // The pixels whose camera ray meets a surface without a Lambertian part first.
    let spheres = pixels_first_meeting(&scene, size, &reference, |_, bsdf, wo| {
        bsdf.lambertian_albedo(wo).is_black()
    });
    assert!(
        spheres.len() > 30,
        "{} pixels see the spheres",
        spheres.len()
    );
    let ratio = luminance_ratio_over(&spheres, &out.image, &reference);
    assert!(
        (ratio - 1.0).abs() < 0.06,
        "on the spheres: luminance ratio {ratio}"
    );
    let (m, _) = against(&out.image, &reference);
    assert!(
        (m.lum_ratio - 1.0).abs() < 0.02,
        "whole image: luminance ratio {}",
        m.lum_ratio
    );
}

/// The caustic map in fog (`photon_map::trace` through media, `VolPathIntegrator::trace`'s
/// split), against paths through the glass: `scenes/glass-in-fog` (`max_depth` 4) with its
/// glass sphere raised to (−0.2, 0.7, 0.2), where it spreads the lamp's light over the floor
/// below through the fog. On a 4 × 4 grid of floor points in that caustic, a record's gather
/// without the caustics plus the map's caustic irradiance, and a record's gather that follows
/// the paths through the sphere itself (two independent estimates of the same irradiance),
/// agree in their mean within 5 % (the map's own noise there about 2 %, the gathers' 1 %); the
/// caustic is more than half of it (so leaving either half out, or counting it twice, fails).
/// Away from the sphere the two gathers agree within 2 % and the map reads almost nothing.
#[test]
fn caustic_photons_in_fog_replace_the_gathers_caustic_paths() {
    use ircache_render::irradiance_cache::prepare::media_caustic_map;
    use ircache_render::irradiance_cache::IcParams;
    use ircache_render::media::tracking::medium_at;
    use ircache_render::media_cache::cache::{make_record, RecordSite, RecordSources};
    let desc = project_scene(
        "glass-in-fog",
        &[
            ("max_depth".into(), "4".into()),
            ("glass_center".into(), "-0.2, 0.7, 0.2".into()),
        ],
    );
    let scene = Scene::build(&desc).expect("scene");
    let params = IcParams {
        bounces: 2,
        media_divisions: 2048,
        media_deeper_paths: 2,
        caustic_photons: Some(400_000),
        photon_lookup: 400,
        ..IcParams::default()
    };
    let map = Arc::new(media_caustic_map(&scene, &params, 5).expect("a caustic map"));
    let up = Vec3::Y;
    // (whole gather, gather without caustics, map) at a floor point.
    let at = |x: f32, z: f32, key: u64| {
        let p = Vec3::new(x, 0.0, z);
        let site = RecordSite {
            p,
            ng: up,
            n: up,
            medium: medium_at(&scene, p + up * 1e-3, up),
            footprint: 0.0,
        };
        let whole = luminance(
            make_record(&scene, &params, &site, key, Default::default())
                .0
                .e,
        );
        let gathered = luminance(
            make_record(
                &scene,
                &params,
                &site,
                key,
                RecordSources {
                    caustics: Some(&map),
                    ..Default::default()
                },
            )
            .0
            .e,
        );
        (whole, gathered, luminance(map.irradiance(p, up, 2)))
    };
    let (mut whole, mut gathered, mut caustic) = (0.0, 0.0, 0.0);
    for i in 0..16 {
        let (x, z) = (
            -0.4 + 0.2 * (i % 4) as f32 / 3.0,
            0.2 + 0.2 * (i / 4) as f32 / 3.0,
        );
        let (w, g, c) = at(x, z, 11 + i as u64);
        (whole, gathered, caustic) = (whole + w, gathered + g, caustic + c);
    }
    let split = gathered + caustic;
    assert!(
        caustic > 0.5 * whole,
        "the caustic {caustic} of {whole} (16 points)"
    );
    assert!(
        (split / whole - 1.0).abs() < 0.05,
        "gathered {gathered} + caustic {caustic} = {split} against {whole} (16 points)"
    );
    let (w, g, c) = at(0.3, -0.4, 3);
    assert!(c < 0.01 * w, "away from the sphere: caustic {c} of {w}");
    assert!(
        (g / w - 1.0).abs() < 0.02,
        "away from the sphere: {g} against {w}"
    );
}

/// Interpolation quality of each gradient form (NOTES-002 §3.3): the cache's interpolated
/// irradiance at the first hits of a `size`² grid of pixel centres against a gather at each of
/// those points with many rays. Returns relMSE per form (corrected, paper, jdzj08, none).
fn interpolation_errors(size: u32, reference_divisions: usize) -> Vec<(&'static str, f64, usize)> {
    use ircache_render::irradiance_cache::IcParams;
    use ircache_render::media_cache::cache::{first_site, make_record, MediaCache};
    let desc = cornell_fog("irrcache", 3, size, 1);
    let scene = Scene::build(&desc).expect("scene");
    let mut sites = Vec::new();
    for y in 0..size {
        for x in 0..size {
            let film = ircache_math::Vec2::new(
                (x as f32 + 0.37) / size as f32,
                (y as f32 + 0.61) / size as f32,
            );
            if let Some(site) = first_site(&scene, scene.camera.generate_ray(film)) {
                sites.push(site);
            }
        }
    }
    let fine = IcParams {
        bounces: 1,
        divisions: reference_divisions,
        ..IcParams::default()
    };
    let reference: Vec<Rgb> = sites
        .iter()
        .enumerate()
        .map(|(i, s)| {
            make_record(&scene, &fine, s, 7 + i as u64, Default::default())
                .0
                .e
        })
        .collect();
    let mut out = Vec::new();
    for (name, form) in [
        (
            "corrected",
            ircache_render::media_cache::gradient::MediaGradient::Corrected,
        ),
        (
            "paper",
            ircache_render::media_cache::gradient::MediaGradient::Paper,
        ),
        (
            "jdzj08",
            ircache_render::media_cache::gradient::MediaGradient::Jdzj08,
        ),
        (
            "none",
            ircache_render::media_cache::gradient::MediaGradient::None,
        ),
    ] {
        let params = IcParams {
            bounces: 1,
            media_gradient: form,
            ..IcParams::default()
        };
        let cache = MediaCache::build(
            &scene,
            &params,
            (size as usize / 2, size as usize / 2),
            3,
            Vec::new(),
            Default::default(),
        );
        let (mut sum, mut n) = (0.0f64, 0usize);
        for (s, r) in sites.iter().zip(&reference) {
            if let Some(e) = cache.irradiance(0, s.p, s.n, s.n) {
                let (a, b) = (f64::from(e.luminance()), f64::from(r.luminance()));
                sum += (a - b).powi(2) / (b * b + 1e-4);
                n += 1;
            }
        }
        out.push((name, sum / n.max(1) as f64, cache.records().len()));
    }
    out
}

#[test]
#[ignore = "prints the interpolation errors of the gradient forms: cargo test --release -- --ignored"]
fn gradient_forms_interpolation_quality() {
    for (name, err, records) in interpolation_errors(64, 4096) {
        eprintln!("{name:>9}: relMSE {err:.3e} ({records} records)");
    }
}

/// 002's gradients against central differences (NOTES-002 §3.3) at `points` of `desc`: the
/// consistent form's gradient from gathers of each count of cells in `divisions` and the brute
/// force's differences (100 000 cells, common random numbers), each the mean of 8 seeds; four
/// light samples per march step (with one the source-gradient term is too noisy to tell). At
/// the largest count each component must lie within `tolerance` of the differences' length or
/// three standard errors of the two means, and media-blind Ward–Heckbert (`none`) must fail
/// that somewhere. Returns the consistent form's error (the largest component's, over the
/// differences' length) per count and point. `FOG_SEEDS=1` prints each seed's gradients.
fn gradients_against_finite_differences(
    desc: &SceneDesc,
    points: &[(Vec3, Vec3)],
    divisions: &[usize],
    tolerance: f32,
) -> Vec<Vec<f32>> {
    use ircache_render::irradiance_cache::params::GatherPattern;
    use ircache_render::irradiance_cache::points::PointMethod;
    use ircache_render::irradiance_cache::IcParams;
    use ircache_render::media_cache::gradient::MediaGradient;
    use ircache_render::media_cache::points::media_irradiance_at_points;
    let scene = Scene::build(desc).expect("scene");
    const SEEDS: u64 = 8;
    // The mean of the seeds' green gradients at each point and its standard error per axis.
    let mean_and_error = |method: PointMethod, form: MediaGradient, cells: usize| {
        let params = IcParams {
            bounces: 1,
            divisions: cells,
            media_divisions: cells,
            media_gradient: form,
            media_light_samples: 4,
            // The differences' gathers jitter each cell's ray on its own: so do the records'
            // here (multi-jittered cells read the walls' gradients up to 12 % higher).
            gather_pattern: GatherPattern::Jittered,
            ..IcParams::default()
        };
        let runs: Vec<Vec<Vec3>> = (0..SEEDS)
            .map(|seed| {
                let r = media_irradiance_at_points(&scene, &params, points, method, 0, seed);
                let g: Vec<Vec3> = r.iter().map(|r| r.grad_t[1]).collect();
                if std::env::var("FOG_SEEDS").is_ok() {
                    eprintln!("{form:?} {method:?} seed {seed}: {g:?}");
                }
                g
            })
            .collect();
        (0..points.len())
            .map(|i| {
                let n = SEEDS as f32;
                let mean = runs.iter().map(|r| r[i]).sum::<Vec3>() / n;
                let variance = runs
                    .iter()
                    .map(|r| (r[i] - mean) * (r[i] - mean))
                    .sum::<Vec3>()
                    / (n - 1.0);
                (mean, (variance / n).map(f32::sqrt))
            })
            .collect::<Vec<(Vec3, Vec3)>>()
    };
    let brute_force = PointMethod::BruteForce { samples: 100_000 };
    let differences = mean_and_error(brute_force, MediaGradient::Corrected, 20_000);
    let largest = divisions.iter().copied().max().expect("a count of cells");
    let mut failures = Vec::new();
    let mut errors = Vec::new();
    for &cells in divisions {
        let forms: &[MediaGradient] = if cells == largest {
            &[MediaGradient::Corrected, MediaGradient::None]
        } else {
            &[MediaGradient::Corrected]
        };
        for &form in forms {
            let cache = mean_and_error(PointMethod::Cache, form, cells);
            let mut relative = Vec::new();
            for (i, (p, _)) in points.iter().enumerate() {
                let ((g, g_se), (fd, fd_se)) = (cache[i], differences[i]);
                let allowed = (tolerance * fd.length())
                    .max(3.0 * (g_se * g_se + fd_se * fd_se).map(f32::sqrt).max_element());
                let off = (g - fd).abs().max_element();
                eprintln!(
                    "{p}, {cells} cells: {form:>10?} {g} ± {g_se}, differences {fd} ± {fd_se}: \
                     off {off:.4} ({:.1} % of its length; allowed {allowed:.4})",
                    100.0 * off / fd.length()
                );
                relative.push(off / fd.length());
                if cells == largest && off > allowed {
                    failures.push((form, i));
                }
            }
            if form == MediaGradient::Corrected {
                errors.push(relative);
            }
        }
    }
    assert!(
        failures
            .iter()
            .all(|(form, _)| *form == MediaGradient::None),
        "the consistent form is off the differences: {failures:?}"
    );
    assert!(
        !failures.is_empty(),
        "media-blind Ward–Heckbert should be off the differences somewhere"
    );
    errors
}

/// The fog Cornell box ([`gradients_against_finite_differences`]) at points on the floor and on
/// two walls, two of them in the boxes' volumetric shadows: within 5 % from gathers of 80 000
/// cells (4.2 %, 4.1 %, 4.3 %); from 5 000 cells 19 %, 8 % and 9 % (20 000: 11 %, 5 %, 7 %),
/// the walls' terms at the boxes' silhouettes a cell's width off, so the error must fall with
/// the cells. `none` reads 16–61 % off. The floor read 25 % off (20 000 cells) without the
/// shadow-edge term of the sources' gradients, 60 % before the boundaries' sources were read
/// clear of them, and at 80 000 cells one seed in eight read it 25 times over while area
/// sampling weighed a march point under the lamp's corner 200 times over. `FOG_NO_BOXES=1`
/// takes the two boxes out (no volumetric shadows).
#[test]
#[ignore = "the fog Cornell box's gradients against finite differences (two minutes): cargo test --release -- --ignored"]
fn fog_cornell_gradients_against_finite_differences() {
    let mut desc = cornell_fog("irrcache", 3, 8, 1);
    if std::env::var("FOG_NO_BOXES").is_ok() {
        desc.shapes
            .retain(|s| !matches!(s.id.as_deref(), Some("ShortBox" | "TallBox")));
    }
    if let Some(albedo) = std::env::var("FOG_ALBEDO")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        desc.media[0].albedo = VolumeDesc::constant(Rgb::splat(albedo));
    }
    if let Some(scale) = std::env::var("FOG_SCALE").ok().and_then(|v| v.parse().ok()) {
        desc.media[0].scale = scale;
    }
    let points = [
        (Vec3::new(-0.5, 0.001, 0.5), Vec3::Y),
        (Vec3::new(-0.99, 1.0, 0.0), Vec3::X),
        (Vec3::new(0.0, 1.0, -0.99), Vec3::Z),
    ];
    let errors = gradients_against_finite_differences(&desc, &points, &[5_000, 80_000], 0.05);
    let (coarse, fine) = (&errors[0], &errors[1]);
    assert!(
        fine.iter().sum::<f32>() < 0.6 * coarse.iter().sum::<f32>(),
        "the error should fall from 5 000 to 80 000 cells: {coarse:?} → {fine:?}"
    );
}

/// The project's smoke box, its plume replaced by homogeneous fog (σ_t 3) filling the null box
/// when `homogeneous`, its two boxes taken out unless `boxes`.
fn smoke_box(homogeneous: bool, boxes: bool) -> SceneDesc {
    let mut desc = project_scene("smoke-box", &[]);
    if homogeneous {
        desc.media[0].kind = ircache_scene::desc::MediumKind::Homogeneous;
        desc.media[0].sigma_t = VolumeDesc::constant(Rgb::splat(3.0));
        desc.media[0].scale = 1.0;
    }
    if !boxes {
        desc.shapes
            .retain(|s| !matches!(s.id.as_deref(), Some("ShortBox" | "TallBox")));
    }
    desc
}

/// The smoke box ([`gradients_against_finite_differences`]): its plume, a 32³ grid filling its
/// null box, round the two boxes, which cast volumetric shadows in it and hide parts of it; at
/// points on the left and back walls behind it, within 5 % (1.7 % and 4.1 %; without the boxes
/// 2.8 % and 4.0 %); `none` reads 18–47 % off. They read 4 % and 33 % off while a march step
/// begun on the grid's box was sized by σ_t = 0 there and strode the whole grid, and 53–63 %
/// while the grid's box, on the null box's faces, added each face's jump a second time.
/// `SMOKE_HOMOGENEOUS=1` fills the null box with homogeneous fog (σ_t 3) instead (2 %);
/// `SMOKE_NO_BOXES=1` takes the boxes out.
#[test]
#[ignore = "the smoke box's gradients against finite differences (minutes): cargo test --release -- --ignored"]
fn smoke_box_gradients_against_finite_differences() {
    let desc = smoke_box(
        std::env::var("SMOKE_HOMOGENEOUS").is_ok(),
        std::env::var("SMOKE_NO_BOXES").is_err(),
    );
    let points = [
        (Vec3::new(-0.99, 1.0, 0.0), Vec3::X),
        (Vec3::new(0.0, 1.0, -0.99), Vec3::Z),
    ];
    gradients_against_finite_differences(&desc, &points, &[20_000], 0.05);
}

/// The medium's source and its gradient in closed form, each light sample's point on the light
/// held (NOTES-002 §2.7), against central differences of the source itself (its light samples
/// stratified and fixed: common random numbers), at a point of the fog Cornell box that sees
/// the whole light unoccluded: the ceiling's area light with isotropic and Henyey–Greenstein
/// fog, and a point light in its place, and a spot light whose falloff (linear in the angle
/// from its axis) passes the point, their sources also over a march step (1024 light samples,
/// steps of 1e-3, within 3 % of the gradient's length per component); and inside the smoke plume (`smoke-box`), its optical
/// depth's gradient marched through the grid, against differences at a fifth of a voxel (ratio
/// tracking makes smaller steps noise; 4096 light samples, within 5 %).
#[test]
fn source_gradient_matches_differences_of_the_source() {
    use ircache_math::DVec3;
    use ircache_render::media::tracking::medium_at;
    use ircache_render::media_cache::gradient::{GatherMedium, StepExtent};
    use ircache_render::media_cache::scene_medium::SceneMedium;
    // (label, phase, lamp: none (the area light), a point or a spot light, smoke).
    let cases = [
        ("area light, isotropic", PhaseDesc::Isotropic, "", false),
        (
            "area light, g = 0.6",
            PhaseDesc::HenyeyGreenstein { g: 0.6 },
            "",
            false,
        ),
        (
            "point light, g = −0.4",
            PhaseDesc::HenyeyGreenstein { g: -0.4 },
            "point",
            false,
        ),
        (
            "spot light, p in its falloff, g = 0.3",
            PhaseDesc::HenyeyGreenstein { g: 0.3 },
            "spot",
            false,
        ),
        ("smoke, area light", PhaseDesc::Isotropic, "", true),
    ];
    for (label, phase, lamp, smoke) in cases {
        let point = !lamp.is_empty();
        let mut desc = if smoke {
            project_scene("smoke-box", &[])
        } else {
            cornell_fog("volpath", 3, 8, 1)
        };
        desc.media[0].phase = phase;
        if point {
            for shape in &mut desc.shapes {
                shape.emitter = None;
            }
            let position = Vec3::new(0.1, 1.8, -0.2);
            if lamp == "spot" {
                // Aimed 20° off the point, between its beam (10°) and cutoff (30°).
                let towards = (Vec3::new(0.3, 1.2, 0.2) - position).normalize();
                let turn = ircache_math::Quat::from_axis_angle(
                    towards.cross(Vec3::X).normalize(),
                    20f32.to_radians(),
                );
                let axis = turn * towards;
                desc.emitters.push(EmitterDesc::Spot {
                    to_world: Mat4::from_translation(position)
                        * Mat4::from_quat(ircache_math::Quat::from_rotation_arc(Vec3::Z, axis)),
                    intensity: Rgb::splat(3.0),
                    cutoff_angle: 30.0,
                    beam_width: 10.0,
                });
            } else {
                desc.emitters.push(EmitterDesc::Point {
                    position,
                    intensity: Rgb::splat(3.0),
                });
            }
        }
        let scene = Scene::build(&desc).expect("scene");
        let p = if smoke {
            DVec3::new(0.1, 1.0, 0.05)
        } else {
            DVec3::new(0.3, 1.2, 0.2)
        };
        let medium = medium_at(&scene, p.as_vec3(), Vec3::Y);
        assert!(medium.is_some(), "{label}: the point is in the fog");
        // Smoke: the means over four gather directions (light samples rotated by each; the
        // isotropic phase function makes the source the same).
        let (samples, h, tolerance) = if smoke {
            (2048, 8e-3, 0.05)
        } else {
            (1024, 1e-3, 0.03)
        };
        // A view per evaluation: its light samples' tracking streams are keyed by the march
        // step along the gather direction, the first here, as for receivers a step apart.
        // The closed form with each sample's visibility held: no shadow-edge term (the
        // smoke's point sees the tall box's corner cut into the light).
        let view = || SceneMedium::new(&scene, medium, false, samples).with_shadow_edges(false);
        let directions = [
            DVec3::new(0.0, -1.0, 0.0),
            DVec3::new(0.6, 0.0, 0.8),
            DVec3::new(-0.48, 0.6, -0.64),
            DVec3::new(0.0, 0.6, -0.8),
        ];
        let groups: Vec<&[DVec3]> = if smoke {
            vec![&directions[..]]
        } else {
            directions[..3].chunks(1).collect()
        };
        // A point light's source is also taken over a march step about p (its light samples'
        // distances drawn on the step towards the light, the same draws for every view).
        let t = 0.3;
        let sigma = scene.media[medium.expect("fog")].at(p.as_vec3()).sigma_t;
        let step = StepExtent {
            t0: t - 0.1,
            t1: t + 0.1,
            sigma: [sigma.r, sigma.g, sigma.b].map(f64::from),
        };
        let spans: &[Option<&StepExtent>] = if point { &[None, Some(&step)] } else { &[None] };
        for (group, &span) in groups
            .iter()
            .flat_map(|g| spans.iter().map(move |s| (g, s)))
        {
            let source = |at: &SceneMedium, o: DVec3, w: DVec3| match span {
                Some(step) => at.step_source(o, w, step)[1],
                None => at.source(o, w, t)[1],
            };
            let n = group.len() as f64;
            let (mut q, mut gradient) = (0.0, DVec3::ZERO);
            let mut fd = DVec3::ZERO;
            for &w in group.iter() {
                let o = p - w * t;
                let at = view();
                q += source(&at, o, w) / n;
                gradient += match span {
                    Some(step) => at.step_source_gradient(o, w, step)[1],
                    None => at.source_gradient(o, w, t)[1],
                } / n;
                for e in [DVec3::X, DVec3::Y, DVec3::Z] {
                    let d = source(&view(), o + e * h, w) - source(&view(), o - e * h, w);
                    fd += e * (d / (2.0 * h) / n);
                }
            }
            assert!(q > 0.0, "{label}: lit");
            for e in [DVec3::X, DVec3::Y, DVec3::Z] {
                let (got, fd) = (gradient.dot(e), fd.dot(e));
                assert!(
                    (got - fd).abs() <= tolerance * gradient.length(),
                    "{label}, ω {group:?}, step {span:?}, along {e}: {got} against differences {fd} (|∇q| {})",
                    gradient.length()
                );
            }
        }
    }
}

/// A gather's march step near a point or spot light: its source is sampled over the step
/// towards the light (equiangular), so its mean over 65 536 steps' streams is the step's
/// ∫ T q dt / ∫ T dt (T from the step's start), here by 20 000 midpoints, within 1 %: a ray
/// passing 0.02 from a point light in the fog box (the source at the step's middle alone, what
/// the march took before, is off by more than half), and a ray across the edge of spot-fog's
/// cone 0.6 from its lamp.
#[test]
fn a_march_step_near_a_lamp_samples_its_light_over_the_step() {
    use ircache_render::media::tracking::medium_at;
    use ircache_render::media_cache::gradient::{GatherMedium, StepExtent};
    use ircache_render::media_cache::scene_medium::SceneMedium;
    let lamp = Vec3::new(0.1, 1.8, -0.2);
    let mut point = cornell_fog("volpath", 3, 8, 1);
    for shape in &mut point.shapes {
        shape.emitter = None;
    }
    point.emitters.push(EmitterDesc::Point {
        position: lamp,
        intensity: Rgb::splat(3.0),
    });
    let spot = project_scene("spot-fog", &[]);
    let spot_lamp = Vec3::new(0.3, 1.9, 0.2);
    let axis = (Vec3::new(-0.3, 0.0, -0.2) - spot_lamp).normalize();
    let across = axis.cross(Vec3::Y).normalize();
    // (scene, ray origin, direction, the step's length, whether the middle alone misses)
    let cases = [
        (
            "point light, 0.02 from the ray",
            point,
            lamp - Vec3::Y * 0.02 - Vec3::X * 0.1,
            Vec3::X,
            true,
        ),
        (
            "spot light, across its cone's edge",
            spot,
            spot_lamp + axis * 0.6 - across * 0.1,
            across,
            false,
        ),
    ];
    for (label, desc, o, w, middle_misses) in cases {
        let scene = Scene::build(&desc).expect("scene");
        let medium = medium_at(&scene, o, w).expect("in the fog");
        let c = scene.media[medium].at(o);
        let (sigma_t, sigma_s) = (f64::from(c.sigma_t.g), f64::from(c.sigma_s.g));
        let phase = scene.media[medium].phase;
        let length = 0.4;
        // q(t) towards the receiver at o, from the light's own evaluation at each point.
        let q = |t: f64| {
            let x = o + w * t as f32;
            scene
                .lights
                .sample_light(0, 1.0, x, ircache_math::Vec2::ZERO)
                .map_or(0.0, |ls| {
                    sigma_s
                        * f64::from(phase.eval(-ls.wi, -w) * ls.radiance.g)
                        * (-sigma_t * f64::from(ls.distance)).exp()
                })
        };
        let n = 20_000;
        let (mut integral, mut weight) = (0.0, 0.0);
        for k in 0..n {
            let t = length * (f64::from(k) + 0.5) / f64::from(n);
            let tr = (-sigma_t * t).exp();
            integral += tr * q(t);
            weight += tr;
        }
        let want = integral / weight;
        let view = SceneMedium::new(&scene, Some(medium), false, 1);
        let step = StepExtent {
            t0: 0.0,
            t1: length,
            sigma: [f64::from(c.sigma_t.r), sigma_t, f64::from(c.sigma_t.b)],
        };
        let (o, w) = (o.as_dvec3(), w.as_dvec3());
        let steps = 65536;
        let got = (0..steps)
            .map(|_| view.step_source(o, w, &step)[1])
            .sum::<f64>()
            / f64::from(steps);
        assert!(
            (got / want - 1.0).abs() < 0.01,
            "{label}: the step's mean source {got} against {want}"
        );
        let middle = SceneMedium::new(&scene, Some(medium), false, 1).source(o, w, 0.5 * length)[1];
        assert_eq!(
            (middle / want - 1.0).abs() > 0.5,
            middle_misses,
            "{label}: the source at the middle {middle} against the step's {want}"
        );
    }
}

/// A gather's march in a grid takes its light samples' transmittance by ratio tracking: each
/// step's an estimate of its own (streams keyed by the gather direction and the step), so
/// their mean over the steps converges. Inside the smoke plume under a point light, the mean
/// source of 4096 steps at one point against σ_s I/r² T/(4π) with T from the density
/// integrated along the shadow ray by 20 000 midpoints, within 2 %. (One fixed stream for every
/// step, as before, put the tracking's collisions at the same distances each time: the mean
/// was that one estimate, and the smoke's ceiling read 3–5 % dark.)
#[test]
fn march_light_samples_through_a_grid_converge_to_its_transmittance() {
    use ircache_math::DVec3;
    use ircache_render::media::tracking::medium_at;
    use ircache_render::media_cache::gradient::GatherMedium;
    use ircache_render::media_cache::scene_medium::SceneMedium;
    let mut desc = project_scene("smoke-box", &[]);
    for shape in &mut desc.shapes {
        shape.emitter = None;
    }
    let light = Vec3::new(0.1, 1.8, -0.2);
    let intensity = 3.0f32;
    desc.emitters.push(EmitterDesc::Point {
        position: light,
        intensity: Rgb::splat(intensity),
    });
    let scene = Scene::build(&desc).expect("scene");
    let p = Vec3::new(0.1, 1.0, 0.05);
    let medium = medium_at(&scene, p, Vec3::Y).expect("the point is in the smoke");
    let smoke = &scene.media[medium];
    // The optical depth to the light (the grid's box ends at y = 1.6: clear air beyond).
    let n = 20_000;
    let depth: f64 = (0..n)
        .map(|i| {
            let x = p + (light - p) * ((i as f32 + 0.5) / n as f32);
            let inside = x.y <= 1.6;
            if inside {
                f64::from(smoke.at(x).sigma_t.g)
            } else {
                0.0
            }
        })
        .sum::<f64>()
        * f64::from((light - p).length())
        / f64::from(n);
    let c = smoke.at(p);
    let r2 = f64::from((light - p).length_squared());
    let want = f64::from(c.sigma_s.g) * f64::from(intensity) / r2 * (-depth).exp()
        / (4.0 * std::f64::consts::PI);
    assert!(
        (-depth).exp() > 0.05 && (-depth).exp() < 0.95,
        "the shadow ray's transmittance {} is neither clear nor black",
        (-depth).exp()
    );
    let view = SceneMedium::new(&scene, Some(medium), false, 1);
    let w = DVec3::new(0.6, 0.0, 0.8);
    let t = 0.3;
    let o = p.as_dvec3() - w * t;
    let steps = 4096;
    let got = (0..steps).map(|_| view.source(o, w, t)[1]).sum::<f64>() / f64::from(steps);
    assert!(
        (got / want - 1.0).abs() < 0.02,
        "mean source {got} against {want} (T = {})",
        (-depth).exp()
    );
}

/// The records' gathers against paths that share nothing with their march: on the smoke box's
/// ceiling (lit only by the walls and the plume below it, through the grid), one bounce and
/// five, each record's irradiance averaged over 12 seeds, against `volpath`'s paths over the
/// hemisphere (`ircache irradiance --integrator path` in media), within 3 % summed over three
/// points per channel. (With the march's light samples on one fixed tracking stream, or with
/// steps begun in thin air striding over the plume, the records read 5–8 % low here, and the
/// march's own brute force, which `ircache irradiance` used until then, with them.)
#[test]
fn media_records_agree_with_volpath_paths_in_a_grid() {
    use ircache_render::irradiance_cache::points::PointMethod;
    use ircache_render::irradiance_cache::IcParams;
    use ircache_render::media_cache::points::media_irradiance_at_points;
    let desc = project_scene("smoke-box", &[]);
    let scene = Scene::build(&desc).expect("scene");
    let down = Vec3::new(0.0, -1.0, 0.0);
    let points = [
        (Vec3::new(-0.5, 1.99, 0.3), down),
        (Vec3::new(0.6, 1.99, -0.4), down),
        (Vec3::new(0.0, 1.99, 0.6), down),
    ];
    for bounces in [1, 5] {
        let params = IcParams {
            bounces,
            ..IcParams::default()
        };
        let seeds = 12;
        let mut cache = Rgb::ZERO;
        for seed in 0..seeds {
            for r in
                media_irradiance_at_points(&scene, &params, &points, PointMethod::Cache, 0, seed)
            {
                cache += r.indirect / seeds as f32;
            }
        }
        let paths = media_irradiance_at_points(
            &scene,
            &params,
            &points,
            PointMethod::BruteForce { samples: 16_384 },
            0,
            99,
        )
        .iter()
        .fold(Rgb::ZERO, |sum, r| sum + r.indirect);
        for (c, (got, want)) in [(cache.r, paths.r), (cache.g, paths.g), (cache.b, paths.b)]
            .into_iter()
            .enumerate()
        {
            assert!(
                (got / want - 1.0).abs() < 0.03,
                "{bounces} bounce(s), channel {c}: records {got} against paths {want}"
            );
        }
    }
}

/// The pixel pass's march in a grid (`media_march`'s model of the extinction along each camera
/// ray): the smoke box at `max_depth` 2 (single scattering and direct light, no records) at 32²
/// against `volpath` at 1 024 spp, both `multijitter`: the mean within 1 %, the blurred relMSE
/// (σ = 2 px) under 5e-5, and at 64 spp a relMSE_trim under 0.6× `volpath`'s at 64 spp.
/// (Measured: lum 1.000, blurred 7e-6, 0.48×; points at equal lengths with ratio-tracked
/// transmittance, before, read 0.69×.)
#[test]
fn marched_grid_single_scattering_agrees_with_volpath() {
    let scene = |integrator: &str, spp: u32| {
        let mut desc = fog_scene("smoke-box", integrator, 2, 32, spp);
        desc.sensor.sampler = "multijitter".into();
        desc
    };
    let reference = render_desc(&scene("volpath", 1024), 2, 1).image;
    let marched = render_desc(&scene("irrcache", 64), 2, 3).image;
    let tracked = render_desc(&scene("volpath", 64), 2, 3).image;
    let ((m, mb), (t, _)) = (against(&marched, &reference), against(&tracked, &reference));
    assert!(
        (m.lum_ratio - 1.0).abs() < 0.01,
        "luminance ratio {}",
        m.lum_ratio
    );
    assert!(
        mb.rel_mse_trim < 5e-5,
        "blurred relMSE_trim {}",
        mb.rel_mse_trim
    );
    assert!(
        m.rel_mse_trim < 0.6 * t.rel_mse_trim,
        "marched {} against volpath {}",
        m.rel_mse_trim,
        t.rel_mse_trim
    );
}

/// A surface record whose deeper bounces take the light scattered along its gather rays from
/// the volumetric records (their light one bounce shorter, at quadrature points, the paths
/// going on from the opaque hit alone through the transmittance) gathers the same irradiance
/// as one whose deeper paths find their collisions by free flights: in the fog box and the
/// smoke box at `max_depth` 6, the mean over 12 camera-seen sites × 8 keys agrees within
/// three standard errors of the difference and within 3 %, and the records' own spread
/// (between keys) does not grow.
#[test]
fn surface_records_take_the_light_in_the_medium_from_volumetric_records() {
    use ircache_render::irradiance_cache::IcParams;
    use ircache_render::media_cache::cache::{make_record, RecordSources};
    for name in ["cornell-fog", "smoke-box"] {
        let scene = Scene::build(&fog_scene(name, "irrcache", 6, 16, 1)).expect("scene");
        let params = IcParams {
            bounces: 4,
            ..IcParams::default()
        };
        let volume = volume_records_of(&scene, params.accuracy);
        let sites = camera_sites(&scene);
        assert!(sites.len() >= 10, "{name}: {} sites", sites.len());
        // Per key, the sum over sites of each way's irradiance (luminance).
        let keys = 8u64;
        let mut sums = [Vec::new(), Vec::new()];
        for key in 0..keys {
            for (way, served) in [None, Some(&volume)].into_iter().enumerate() {
                let total: f64 = sites
                    .iter()
                    .enumerate()
                    .map(|(i, s)| {
                        let k = 100 * key + i as u64;
                        let sources = RecordSources {
                            volume: served,
                            ..Default::default()
                        };
                        luminance(make_record(&scene, &params, s, k, sources).0.e)
                    })
                    .sum();
                sums[way].push(total);
            }
        }
        let (traced, traced_var) = mean_and_variance(&sums[0]);
        let (served, served_var) = mean_and_variance(&sums[1]);
        let error = ((traced_var + served_var) / keys as f64).sqrt();
        assert!(
            (served - traced).abs() < 3.0 * error && (served / traced - 1.0).abs() < 0.03,
            "{name}: served {served}, traced {traced} ± {error}"
        );
        assert!(
            served_var < 1.5 * traced_var,
            "{name}: spread {} against {}",
            served_var.sqrt(),
            traced_var.sqrt()
        );
    }
}

/// The global map serves the light the deeper bounces bring to a record's gather hits: the
/// part of a record's irradiance beyond its first bounce (the same record at `max_depth` 6
/// less at 3, on the same streams; the volumetric records serve the light along the rays
/// either way) is the same whether the diffuse hits reflect the map's photons, which scatter
/// in the media as paths do, or trace their paths on: in the fog box and the smoke box, the
/// mean over 12 camera-seen sites × 6 keys agrees within three standard errors of the
/// difference plus 3 % (the density estimate's bias), and within 6 %. (A map of photons that
/// cross the fog without scattering reads 0.94 against the paths' 1.50 in the fog box.)
#[test]
fn the_global_map_serves_the_deeper_light_at_the_records_gather_hits() {
    use ircache_render::irradiance_cache::prepare::media_global_map;
    use ircache_render::irradiance_cache::IcParams;
    use ircache_render::media_cache::cache::{make_record, RecordSources};
    for name in ["cornell-fog", "smoke-box"] {
        let scene = Scene::build(&fog_scene(name, "irrcache", 6, 16, 1)).expect("scene");
        let params = IcParams {
            bounces: 4,
            photons: Some(200_000),
            ..IcParams::default()
        };
        let first = IcParams {
            bounces: 1,
            ..params.clone()
        };
        let map = Arc::new(media_global_map(&scene, &params, 3).expect("a global map"));
        let volume = volume_records_of(&scene, params.accuracy);
        let sites = camera_sites(&scene);
        assert!(sites.len() >= 10, "{name}: {} sites", sites.len());
        let keys = 6u64;
        // Per key, the sums over sites of the first bounce and of the deeper part each way.
        let (mut first_sums, mut deeper) = (Vec::new(), [Vec::new(), Vec::new()]);
        for key in 0..keys {
            let mut sums = [0.0f64; 3];
            for (i, s) in sites.iter().enumerate() {
                let k = 100 * key + i as u64;
                let e = |p: &IcParams, global| {
                    let sources = RecordSources {
                        global,
                        volume: Some(&volume),
                        ..Default::default()
                    };
                    luminance(make_record(&scene, p, s, k, sources).0.e)
                };
                let one = e(&first, None);
                sums[0] += one;
                sums[1] += e(&params, None) - one;
                sums[2] += e(&params, Some(&map)) - one;
            }
            first_sums.push(sums[0]);
            deeper[0].push(sums[1]);
            deeper[1].push(sums[2]);
        }
        let (once, _) = mean_and_variance(&first_sums);
        let (traced, traced_var) = mean_and_variance(&deeper[0]);
        let (photons, photons_var) = mean_and_variance(&deeper[1]);
        let error = ((traced_var + photons_var) / keys as f64).sqrt();
        assert!(
            traced > 0.1 * once,
            "{name}: deeper {traced} against {once}"
        );
        assert!(
            (photons - traced).abs() < 3.0 * error + 0.03 * traced
                && (photons / traced - 1.0).abs() < 0.06,
            "{name}: photons {photons}, paths {traced} ± {error}"
        );
    }
}

/// Volumetric records of `scene` at `max_depth` 6 for a 32 × 32 image, 256 paths each, 16 march
/// points (the surface-record tests' stand-in for the pre-pass's).
fn volume_records_of(
    scene: &Scene,
    accuracy: f32,
) -> Arc<ircache_render::media_cache::volume_records::VolumeCache> {
    use ircache_render::integrators::volpath::VolPathIntegrator;
    Arc::new(
        ircache_render::media_cache::volume_records::VolumeCache::build(
            &VolPathIntegrator::plain(6),
            scene,
            accuracy,
            256,
            16,
            32,
            32,
            1,
            Vec::new(),
        ),
    )
}

/// The first record sites of 12 camera rays spread over the film (4 × 3).
fn camera_sites(scene: &Scene) -> Vec<ircache_render::media_cache::cache::RecordSite> {
    (0..12)
        .filter_map(|i| {
            let film = ircache_math::Vec2::new(
                0.1 + 0.8 * (i % 4) as f32 / 3.0,
                0.15 + 0.7 * (i / 4) as f32 / 2.0,
            );
            ircache_render::media_cache::cache::first_site(scene, scene.camera.generate_ray(film))
        })
        .collect()
}

/// The mean of `v` and its sample variance.
fn mean_and_variance(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var)
}

/// Past one delta vertex the march takes the volumetric records' light one bounce shorter
/// (`media_march`): in the fog box whose gold sphere is made a smooth mirror, at `max_depth`
/// 4 and 48², the 57 pixels that see the fog in the mirror agree with `volpath` in mean
/// luminance within 2.5 % (0.982; the records' whole light there, a bounce too long, reads
/// 1.031, and with the tracked collision kept as well 1.062).
#[test]
fn marched_camera_rays_in_a_mirror_take_the_records_shorter_light() {
    let size = 48u32;
    let dir = ircache_testing::ScratchDir::new("mirror-fog");
    let text =
        std::fs::read_to_string(ircache_testing::project_scenes().join("glass-in-fog/scene.xml"))
            .unwrap()
            .replace(
                "<bsdf type=\"roughconductor\">",
                "<bsdf type=\"conductor\">",
            )
            .replace("<float name=\"alpha\" value=\"0.2\" />", "");
    assert!(text.contains("<bsdf type=\"conductor\">"));
    let path = dir.join("scene.xml");
    std::fs::write(&path, text).unwrap();
    let load = |integrator: &str, spp: u32| {
        let defines: Vec<(String, String)> = [
            ("integrator", integrator.to_string()),
            ("max_depth", "4".to_string()),
            ("resx", size.to_string()),
            ("resy", size.to_string()),
            ("spp", spp.to_string()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
        ircache_scene::mitsuba::load(&path, &defines).expect("the mirror scene")
    };
    let reference = render_desc(&load("volpath", 4096), 2, 1).image;
    let desc = load("irrcache", 256);
    let image = render_desc(&desc, 2, 2).image;
    let scene = Scene::build(&desc).expect("scene");
    let mirror = pixels_first_meeting(&scene, size, &reference, |_, bsdf, _| {
        !bsdf.has_smooth() && !bsdf.transmits()
    });
    assert!(mirror.len() > 40, "{} pixels see the mirror", mirror.len());
    let ratio = luminance_ratio_over(&mirror, &image, &reference);
    assert!(
        (ratio - 1.0).abs() < 0.025,
        "in the mirror: luminance ratio {ratio}"
    );
}

/// A gather ray through a null box of homogeneous fog (the smoke box's, made homogeneous, σ_t 3,
/// its boxes taken out) from a receiver on the wall outside it: the consistent form's medium
/// gradient along the wall's vertical tangent (the march inside, the jumps at the faces it
/// enters and leaves by) against central differences of the medium irradiance, common random
/// numbers, within 5 % for each of eight rays' groups (1 024 light samples). The sources on the
/// faces' two sides must be read clear of the faces: within a few ulps the light samples' shadow rays miss the face,
/// and the leaving ray's jump came out a third of its size (0.53 against 0.15).
#[test]
fn medium_gradient_through_a_null_box_matches_differences() {
    use ircache_math::{DVec3, Frame, Rng};
    use ircache_render::irradiance_cache::hemisphere::Stratification;
    use ircache_render::media_cache::gradient::{gather, March};
    use ircache_render::media_cache::scene_medium::SceneMedium;
    let scene = Scene::build(&smoke_box(true, false)).expect("scene");
    let n = Vec3::X;
    let frame = Frame::from_z(n);
    let axes = [frame.s.as_dvec3(), frame.t.as_dvec3(), frame.n.as_dvec3()];
    let origin = DVec3::new(-0.99, 1.0, 0.0);
    // One division: four rays a quarter turn apart about the normal.
    let strata = Stratification::from_divisions(1);
    let mut rng = Rng::new(3, 4);
    let mut crossing = 0;
    for _ in 0..8 {
        let u = rng.next_2d();
        let view = SceneMedium::new(&scene, None, false, 1024).with_tangents([axes[0], axes[1]]);
        let g = gather(&view, origin, axes, strata, &March::default(), |_, _| u);
        let parts = g.gradient_parts();
        let closed = [
            parts.interior_rigid,
            parts.interfaces,
            parts.medium_walls,
            parts.radial,
        ]
        .iter()
        .map(|p| f64::from(p[1].y))
        .sum::<f64>();
        crossing += usize::from(parts.interfaces[1].y != 0.0);
        let medium_at = |x: DVec3| {
            let view = SceneMedium::new(&scene, None, false, 1024).with_gradients(false);
            let march = March {
                gradients: false,
                ..March::default()
            };
            gather(&view, x, axes, strata, &march, |_, _| u)
                .irradiance()
                .1[1]
        };
        let h = 0.01;
        let fd = (medium_at(origin + axes[1] * h) - medium_at(origin - axes[1] * h)) / (2.0 * h);
        assert!(
            (closed - fd).abs() <= 0.05 * fd.abs().max(0.05),
            "u {u}: {closed} against differences {fd}"
        );
    }
    assert!(crossing >= 4, "rays leave by the top or bottom face");
}

/// Gather rays through the smoke box's null box (its boxes taken out), which its grid fills: each
/// face they cross is
/// one boundary, not the null face and the grid's box face beside it (each jump then counted
/// twice: the records' vertical gradients read 2.5× their differences).
#[test]
fn a_grid_filling_its_null_box_crosses_each_face_once() {
    use ircache_math::DVec3;
    use ircache_render::media_cache::gradient::GatherMedium;
    use ircache_render::media_cache::scene_medium::SceneMedium;
    let scene = Scene::build(&smoke_box(false, false)).expect("scene");
    let view = SceneMedium::new(&scene, None, false, 1);
    let o = DVec3::new(-0.99, 1.0, 0.0);
    let mut crossed = 0;
    for w in [
        DVec3::new(0.776, 0.623, -0.099),
        DVec3::new(0.776, -0.623, 0.099),
        DVec3::new(0.776, 0.099, 0.623),
        DVec3::new(1.0, 0.0, 0.0),
    ] {
        let w = w.normalize();
        let (s, _) = view.surface(o, w);
        let b = view.boundaries(o, w, s);
        assert_eq!(b.len(), 2, "{w}: in and out of the box, once each: {b:?}");
        crossed += b.len();
    }
    assert_eq!(crossed, 8);
}
