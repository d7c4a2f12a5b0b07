//! Photon mapping against closed forms and the path tracer (issue 14, NOTES-001 E.6): emitted
//! power, irradiance on a plane under a constant sky (inside and at the edge, disc and hull
//! estimates), photon-cell gradients against Lambert's formula, and caustics through a glass
//! sphere.

mod common;

use common::*;
use ircache_math::{Rgb, Rng, Vec3};
use ircache_render::lights::LightSet;
use ircache_render::photon_map::records::zone_cells;
use ircache_render::photon_map::{MapKind, Photon, PhotonMap, PhotonTag};
use ircache_render::scene::Scene;
use ircache_scene::*;
use std::f32::consts::PI;
use std::sync::Arc;

/// The square `|x|, |z| ≤ half` at height 0, facing up.
fn floor(half: f32) -> ShapeDesc {
    let h = half;
    quad(
        [
            Vec3::new(-h, 0.0, -h),
            Vec3::new(-h, 0.0, h),
            Vec3::new(h, 0.0, h),
            Vec3::new(h, 0.0, -h),
        ],
        diffuse(Rgb::splat(0.5)),
        None,
    )
}

/// Mean flux weight of `n` emission samples.
fn mean_flux(set: &LightSet, n: u32) -> Rgb {
    let mut rng = Rng::new(7, 0);
    let mut sum = [0.0f64; 3];
    for _ in 0..n {
        if let Some(s) = set.sample_emission(rng.next_f32(), rng.next_2d(), rng.next_2d()) {
            assert!((s.direction.length() - 1.0).abs() < 1e-4);
            for (acc, c) in sum.iter_mut().zip(s.flux.to_array()) {
                *acc += f64::from(c);
            }
        }
    }
    let m = sum.map(|v| (v / f64::from(n)) as f32);
    Rgb::new(m[0], m[1], m[2])
}

fn assert_close(a: Rgb, b: Rgb, tol: f32, what: &str) {
    for (x, y) in a.to_array().into_iter().zip(b.to_array()) {
        assert!((x / y - 1.0).abs() < tol, "{what}: {a:?} against {b:?}");
    }
}

fn lights(shapes: Vec<ShapeDesc>, emitters: Vec<EmitterDesc>) -> LightSet {
    LightSet::new(
        &light_scene(shapes, emitters),
        Vec3::new(0.5, 0.0, 0.0),
        2.0,
    )
}

#[test]
fn emitted_photons_carry_each_lights_power() {
    let i = Rgb::new(1.0, 2.0, 3.0);
    let point = lights(
        vec![],
        vec![EmitterDesc::Point {
            position: Vec3::ZERO,
            intensity: i,
        }],
    );
    assert_close(mean_flux(&point, 1000), i * (4.0 * PI), 1e-5, "point");

    // Spot: the falloff, integrated by the samples, against the closed form.
    let spot = lights(
        vec![],
        vec![EmitterDesc::Spot {
            to_world: ircache_math::Mat4::from_rotation_x(0.7),
            intensity: i,
            cutoff_angle: 40.0,
            beam_width: 15.0,
        }],
    );
    let expect =
        ircache_render::lights::emission::spot_power(i, 15f32.to_radians(), 40f32.to_radians());
    assert_close(mean_flux(&spot, 400_000), expect, 5e-3, "spot");

    // Distant lights through the disc of the bounding sphere (radius 2).
    let e = Rgb::new(2.0, 1.0, 0.5);
    let sun = lights(
        vec![],
        vec![EmitterDesc::Directional {
            direction: Vec3::new(1.0, -2.0, 0.5),
            irradiance: e,
        }],
    );
    assert_close(mean_flux(&sun, 1000), e * (PI * 4.0), 1e-5, "directional");
    let l = Rgb::new(0.5, 0.25, 1.0);
    let sky = lights(vec![], vec![EmitterDesc::Constant { radiance: l }]);
    assert_close(
        mean_flux(&sky, 1000),
        l * (4.0 * PI * PI * 4.0),
        1e-5,
        "constant",
    );

    // An emitting sphere (radius 0.5) and quad (area 2): π L A each. Selected by power, the
    // set's mean is their sum; each light's power() says the same.
    let sphere = emitting_shape(
        Geometry::Sphere {
            center: Vec3::new(3.0, 0.0, 0.0),
            radius: 0.5,
            flip_normals: false,
            orientation: ircache_math::Mat3::IDENTITY,
        },
        l,
    );
    let panel = quad(
        [
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(2.0, 1.0, 0.0),
            Vec3::new(2.0, 1.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
        ],
        diffuse(Rgb::ZERO),
        Some(e),
    );
    let both = lights(vec![sphere, panel], vec![]);
    let expect = l * (PI * 4.0 * PI * 0.25) + e * (PI * 2.0);
    assert_close(both.power(0) + both.power(1), expect, 1e-5, "power()");
    assert_close(mean_flux(&both, 400_000), expect, 1e-2, "sphere and quad");
}

/// The photons of `map` within `radius` of `p` on the side of `n`.
fn zone(map: &PhotonMap, p: Vec3, n: Vec3, radius: f32) -> Vec<&Photon> {
    let mut found = Vec::new();
    let accept = |ph: &PhotonTag| ph.normal.dot(n) > 0.5;
    map.tree.nearest(
        p.to_array(),
        usize::MAX,
        radius * radius,
        &accept,
        &mut found,
    );
    found
        .iter()
        .map(|f| &map.tree.photons[f.index as usize])
        .collect()
}

fn flux_sum(photons: &[&Photon]) -> Rgb {
    photons.iter().fold(Rgb::ZERO, |s, p| s + p.flux)
}

/// NOTES-001 E-T2: under a constant sky of radiance L a plane receives E = πL. Inside, the disc
/// and hull estimates agree with it; at the edge the disc estimate sees half the photons over
/// the whole disc (E/2), the Efron-corrected hull all of E. Each ring of photon cells holds
/// radiance L.
#[test]
fn a_plane_under_a_constant_sky_gets_pi_l_from_photons_at_its_edge_too() {
    let l = 0.5;
    let desc = light_scene(
        vec![floor(1.0)],
        vec![EmitterDesc::Constant {
            radiance: Rgb::splat(l),
        }],
    );
    let scene = Scene::build(&desc).expect("scene");
    let map = PhotonMap::build(&scene, MapKind::All, 200_000, 0, 5, None);
    assert!(map.tree.len() >= 200_000);
    assert!(map.tree.photons.iter().all(|p| p.bounces == 0));
    let expect = Rgb::splat(PI * l);
    let r = 0.2;
    let up = Vec3::Y;

    let inside = zone(&map, Vec3::ZERO, up, r);
    let disc = flux_sum(&inside) / (PI * r * r);
    assert_close(disc, expect, 0.04, "disc estimate inside");
    let (_, cells) = zone_cells(&inside, Vec3::ZERO, up).expect("cells");
    assert_close(cells.irradiance(), expect, 0.04, "hull estimate inside");
    let (m, n) = (cells.strata.polar, cells.strata.azimuthal);
    for j in 0..m {
        let ring = (0..n).fold(Rgb::ZERO, |s, k| s + cells.radiance[j * n + k]) / n as f32;
        assert_close(ring, Rgb::splat(l), 0.12, &format!("radiance of ring {j}"));
    }

    let edge = Vec3::new(1.0 - 1e-4, 0.0, 0.3);
    let half = zone(&map, edge, up, r);
    let disc = flux_sum(&half) / (PI * r * r);
    assert_close(disc, expect * 0.5, 0.06, "disc estimate at the edge (half)");
    let (_, cells) = zone_cells(&half, edge, up).expect("cells");
    assert_close(
        cells.irradiance(),
        expect,
        0.05,
        "hull estimate at the edge",
    );
    // The density estimate the renderer uses takes the hull where the photons fill clearly less
    // than their disc: no edge darkening either.
    let lookup = ircache_render::photon_map::Lookup {
        count: 200,
        max_radius: 0.5,
        hull: true,
    };
    assert_close(
        map.irradiance(Vec3::ZERO, up, 0, &lookup),
        expect,
        0.05,
        "estimate inside",
    );
    assert_close(
        map.irradiance(edge, up, 0, &lookup),
        expect,
        0.06,
        "estimate at the edge",
    );
    // At a corner a quarter of the disc holds photons: the hull still finds the area.
    let corner = Vec3::new(1.0 - 1e-4, 0.0, 1.0 - 1e-4);
    let quarter = zone(&map, corner, up, r);
    let (_, cells) = zone_cells(&quarter, corner, up).expect("cells");
    assert_close(
        cells.irradiance(),
        expect,
        0.06,
        "hull estimate at a corner",
    );
}

/// A unit square emitter of radiance `le` facing down at height 1 over a floor, and its corners.
fn panel_over_floor(le: f32) -> (Scene, [Vec3; 4]) {
    let panel = [
        Vec3::new(0.0, 1.0, -0.5),
        Vec3::new(1.0, 1.0, -0.5),
        Vec3::new(1.0, 1.0, 0.5),
        Vec3::new(0.0, 1.0, 0.5),
    ];
    let light = quad(panel, diffuse(Rgb::ZERO), Some(Rgb::splat(le)));
    let desc = light_scene(vec![floor(2.0), light], vec![]);
    (Scene::build(&desc).expect("scene"), panel)
}

/// NOTES-001 E-T3: the translational and rotational gradients from photon cells (Ward–Heckbert
/// from the photons' arrival directions and flight distances) against central differences of
/// the exact irradiance under a square emitter (Lambert's formula).
#[test]
fn photon_cell_gradients_match_central_differences_of_the_exact_irradiance() {
    let le = 2.0;
    let (scene, panel) = panel_over_floor(le);
    let map = PhotonMap::build(&scene, MapKind::All, 600_000, 0, 9, None);
    let exact = |x: Vec3, n: Vec3| PI * le * form_factor(x, n, &panel);

    let p = Vec3::new(-0.1, 0.0, 0.1);
    let up = Vec3::Y;
    let photons = zone(&map, p, up, 0.12);
    let (frame, cells) = zone_cells(&photons, p, up).expect("cells");
    let e = cells.irradiance().g;
    assert!(
        (e / exact(p, up) - 1.0).abs() < 0.04,
        "E {e} against {}",
        exact(p, up)
    );

    let local = cells.translational_gradient_ward_heckbert()[1];
    let grad_t = frame.s * local.x + frame.t * local.y;
    let h = 1e-3;
    let fd = Vec3::new(
        (exact(p + Vec3::X * h, up) - exact(p - Vec3::X * h, up)) / (2.0 * h),
        0.0,
        (exact(p + Vec3::Z * h, up) - exact(p - Vec3::Z * h, up)) / (2.0 * h),
    );
    assert!(
        (grad_t - fd).length() < 0.15 * fd.length(),
        "translational gradient {grad_t:?} against {fd:?}"
    );

    let local = cells.rotational_gradient()[1];
    let grad_r = frame.s * local.x + frame.t * local.y;
    // E(n) ≈ E + (n_i × n)·∇_r: a rotation by ε about the unit axis a gives n_i × n = ε a.
    let tilt = |axis: Vec3, angle: f32| {
        let n = ircache_math::Mat3::from_axis_angle(axis, angle) * up;
        exact(p, n)
    };
    let fd_r = Vec3::new(
        (tilt(Vec3::X, h) - tilt(Vec3::X, -h)) / (2.0 * h),
        0.0,
        (tilt(Vec3::Z, h) - tilt(Vec3::Z, -h)) / (2.0 * h),
    );
    assert!(
        (grad_r - fd_r).length() < 0.15 * fd_r.length(),
        "rotational gradient {grad_r:?} against {fd_r:?}"
    );
}

/// An `ic` description with cache parameters.
fn ic(max_depth: i32, params: &[(&str, &str)]) -> IntegratorDesc {
    IntegratorDesc {
        kind: "ic".into(),
        max_depth,
        extra: params
            .iter()
            .map(|(k, v)| (k.to_string(), ParamValue::String(v.to_string()), here()))
            .collect(),
        ..IntegratorDesc::default()
    }
}

/// Mean luminance of the pixels `mask` selects.
fn masked_mean(img: &ircache_image::Image, mask: &[bool]) -> f64 {
    let (sum, n) = img
        .pixels
        .iter()
        .zip(mask)
        .filter(|(_, &m)| m)
        .fold((0.0f64, 0u32), |(s, n), (p, _)| {
            (s + f64::from(p.luminance()), n + 1)
        });
    sum / f64::from(n.max(1))
}

/// A glass sphere over `floor`, focusing a small spherical light onto it near (−0.35, 0, 0),
/// and a camera at `eye` looking at `target` (32 × 32 pixels, 1024 spp).
fn glass_sphere_over(floor: ShapeDesc, eye: Vec3, target: Vec3) -> (SensorDesc, Vec<ShapeDesc>) {
    let glass = Arc::new(BsdfDesc::Dielectric {
        int_ior: 1.5,
        ext_ior: 1.0,
        specular_reflectance: Rgb::ONE,
        specular_transmittance: Rgb::ONE,
    });
    let sphere = ShapeDesc {
        media: Default::default(),
        id: None,
        geometry: Geometry::Sphere {
            center: Vec3::new(0.0, 0.9, 0.0),
            radius: 0.5,
            flip_normals: false,
            orientation: ircache_math::Mat3::IDENTITY,
        },
        bsdf: glass,
        emitter: None,
        emitter_texture: None,
        emitter_pattern: None,
        location: here(),
    };
    let light = emitting_shape(
        Geometry::Sphere {
            center: Vec3::new(0.8, 3.0, 0.0),
            radius: 0.15,
            flip_normals: false,
            orientation: ircache_math::Mat3::IDENTITY,
        },
        Rgb::splat(100.0),
    );
    let camera = sensor(eye, target, 40.0, 32, 1024);
    (camera, vec![floor, sphere, light])
}

/// What the path tracer gives in the caustic and over the whole image.
struct CausticReference {
    /// The caustic's pixels: floor pixels much brighter than the floor around them, chosen on
    /// an independent render (choosing on the reference would pick its upward noise).
    mask: Vec<bool>,
    /// The reference's mean luminance there.
    caustic: f64,
    /// Its mean luminance over the image.
    mean: f64,
}

impl CausticReference {
    /// From the path tracer's renders of `desc`.
    fn of(desc: &SceneDesc) -> CausticReference {
        let reference = render_desc(desc, 0, 1).image;
        let lum: Vec<f32> = render_desc(desc, 0, 2)
            .image
            .pixels
            .iter()
            .map(|p| p.luminance())
            .collect();
        let mut sorted = lum.clone();
        sorted.sort_by(f32::total_cmp);
        let median = sorted[sorted.len() / 2];
        let mask: Vec<bool> = lum
            .iter()
            .map(|&l| l > 2.5 * median && l < 20.0 * median)
            .collect();
        let caustic_pixels = mask.iter().filter(|&&m| m).count();
        assert!(caustic_pixels >= 8, "{caustic_pixels} caustic pixels");
        CausticReference {
            caustic: masked_mean(&reference, &mask),
            mean: masked_mean(&reference, &vec![true; mask.len()]),
            mask,
        }
    }

    /// Asserts `image` within 8 % of the reference in the caustic and 2 % over the image.
    fn assert_matched_by(&self, image: &ircache_image::Image, what: &str) {
        let caustic = masked_mean(image, &self.mask);
        let mean = masked_mean(image, &vec![true; self.mask.len()]);
        assert!(
            (caustic / self.caustic - 1.0).abs() < 0.08,
            "{what}: caustic {caustic} against the path tracer's {}",
            self.caustic
        );
        assert!(
            (mean / self.mean - 1.0).abs() < 0.02,
            "{what}: mean {mean} against the path tracer's {}",
            self.mean
        );
    }
}

/// A glass sphere focuses a small spherical light onto a plane. The caustic from the caustic
/// map (the gather leaving those paths out) agrees with the path tracer, in the caustic and over
/// the whole image. (The gather alone finds the caustic through a few of its rays and blurs it
/// into blotches: 8–17 % short over the whole image on this scene, measured.)
#[test]
fn caustics_through_a_glass_sphere_match_the_path_tracer() {
    let (camera, shapes) = glass_sphere_over(
        floor(2.0),
        Vec3::new(0.0, 2.2, 3.0),
        Vec3::new(-0.3, 0.2, 0.0),
    );
    let reference = CausticReference::of(&scene(camera.clone(), path(6), shapes.clone(), vec![]));

    let mut few = camera;
    few.spp = 64;
    // The defaults make a caustic map here (a surface with a delta lobe).
    for (what, params) in [
        ("caustic map", vec![("caustic_photons", "200000")]),
        ("defaults", vec![]),
    ] {
        let out = render_desc(
            &scene(few.clone(), ic(6, &params), shapes.clone(), vec![]),
            0,
            1,
        );
        let maps = out.cache.as_ref().and_then(|c| c.cache.photons.clone());
        assert!(
            maps.is_some_and(|m| m.caustic.is_some()),
            "{what}: a caustic map"
        );
        reference.assert_matched_by(&out.image, what);
    }
}

/// The same caustic on a rough metal floor whose glossy lobe radiance records serve, seen
/// from where the floor reflects the light through the sphere towards the camera. The caustic
/// map (on, as the sphere makes caustics) gives irradiance, which a metal does not reflect, and
/// the records' gathers leave those paths to it: the pixel traces them through the glossy lobe.
/// The image agrees with the path tracer (measured at 256 spp: the caustic +0.5 %, the mean
/// +0.3 %). Without that trace the caustic reads half (0.47×); radiance records that hold the
/// caustics themselves (`--caustic-photons 0`) spread them over the floor: 4.5× in the caustic.
#[test]
fn radiance_records_leave_caustics_to_the_pixel_through_the_glossy_lobe() {
    let metal = Arc::new(BsdfDesc::RoughConductor {
        distribution: MicrofacetDistribution::Ggx,
        alpha_u: 0.3,
        alpha_v: 0.3,
        eta: Rgb::new(1.66, 0.88, 0.52),
        k: Rgb::new(9.2, 6.3, 4.8),
        specular_reflectance: Rgb::ONE,
    });
    let mut glossy_floor = floor(2.0);
    glossy_floor.bsdf = metal;
    let (camera, shapes) = glass_sphere_over(
        glossy_floor,
        Vec3::new(-1.5, 3.0, 0.0),
        Vec3::new(-0.35, 0.0, 0.0),
    );
    let reference = CausticReference::of(&scene(camera.clone(), path(6), shapes.clone(), vec![]));

    let mut fewer = camera;
    fewer.spp = 256;
    let out = render_desc(
        &scene(fewer, ic(6, &[("radiance_cache", "on")]), shapes, vec![]),
        0,
        1,
    );
    let cache = &out.cache.as_ref().expect("a cache").cache;
    assert!(
        cache.photons.as_ref().is_some_and(|m| m.caustic.is_some()),
        "a caustic map beside the radiance records"
    );
    assert!(
        cache.radiance_records.len() >= 8,
        "{} radiance records",
        cache.radiance_records.len()
    );
    reference.assert_matched_by(&out.image, "radiance records");
}

/// A closed diffuse room lit by a small ceiling panel: inward-facing walls, floor and ceiling.
fn room() -> Vec<ShapeDesc> {
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let wall = |c: [Vec3; 4], rho: Rgb| quad(c, diffuse(rho), None);
    let grey = Rgb::splat(0.6);
    vec![
        wall(
            [
                v(-1., 0., -1.),
                v(-1., 0., 1.),
                v(1., 0., 1.),
                v(1., 0., -1.),
            ],
            grey,
        ),
        wall(
            [
                v(-1., 2., -1.),
                v(1., 2., -1.),
                v(1., 2., 1.),
                v(-1., 2., 1.),
            ],
            grey,
        ),
        wall(
            [
                v(-1., 0., -1.),
                v(1., 0., -1.),
                v(1., 2., -1.),
                v(-1., 2., -1.),
            ],
            grey,
        ),
        wall(
            [v(-1., 0., 1.), v(-1., 2., 1.), v(1., 2., 1.), v(1., 0., 1.)],
            grey,
        ),
        wall(
            [
                v(-1., 0., -1.),
                v(-1., 2., -1.),
                v(-1., 2., 1.),
                v(-1., 0., 1.),
            ],
            Rgb::new(0.6, 0.1, 0.1),
        ),
        wall(
            [v(1., 0., -1.), v(1., 0., 1.), v(1., 2., 1.), v(1., 2., -1.)],
            Rgb::new(0.1, 0.6, 0.1),
        ),
        quad(
            [
                v(-0.2, 1.99, -0.2),
                v(0.2, 1.99, -0.2),
                v(0.2, 1.99, 0.2),
                v(-0.2, 1.99, 0.2),
            ],
            diffuse(Rgb::ZERO),
            Some(Rgb::splat(20.0)),
        ),
    ]
}

/// The cached final gather (gather hits read the global map; on by default at three bounces)
/// and photon-mapped records (001 ch. 6) converge to the path tracer in a closed room with three
/// bounces: the mean within 1.5 % and each channel within 2 %.
#[test]
fn final_gather_and_photon_records_match_the_path_tracer_in_a_room() {
    let camera = sensor(
        Vec3::new(0.0, 1.0, 0.95),
        Vec3::new(0.0, 0.9, -1.0),
        70.0,
        24,
        2048,
    );
    let reference = render_desc(&scene(camera.clone(), path(5), room(), vec![]), 0, 3);
    let (expect, _) = mean_and_error(&reference.image);
    let mut few = camera;
    few.spp = 16;
    for (what, params) in [
        // Three bounces: the defaults read the gather hits' light from 100 000 photons.
        ("defaults", vec![]),
        ("final gather", vec![("photons", "100000")]),
        (
            "photon records",
            vec![("photons", "100000"), ("photon_records", "on")],
        ),
        // Nothing in the room makes caustics: no map, and a note says so.
        (
            "caustic photons asked",
            vec![("photons", "100000"), ("caustic_photons", "5000")],
        ),
    ] {
        let out = render_desc(&scene(few.clone(), ic(5, &params), room(), vec![]), 0, 3);
        let cache = out.cache.as_ref().expect("a cache");
        let maps = cache.cache.photons.as_ref().expect("photon maps");
        assert!(maps.global.tree.len() >= 100_000, "{what}: photons stored");
        assert!(maps.caustic.is_none(), "{what}: no caustic map");
        let noted = cache.stats.notes.iter().any(|n| n.contains("stored none"));
        assert_eq!(noted, what == "caustic photons asked", "{what}: notes");
        if params.contains(&("photon_records", "on")) {
            assert!(
                cache.stats.photon_records > 0,
                "{what}: records from photons"
            );
        }
        let (mean, _) = mean_and_error(&out.image);
        assert!(
            (mean.luminance() / expect.luminance() - 1.0).abs() < 0.015,
            "{what}: mean {mean:?} against the path tracer's {expect:?}"
        );
        assert_close(mean, expect, 0.02, what);
    }
}

/// Same seed, same image: photon tracing, the trees, the precomputed irradiance and the photon
/// records do not depend on the threads.
#[test]
fn photon_mapped_images_do_not_depend_on_the_threads() {
    let mut camera = sensor(
        Vec3::new(0.0, 1.0, 0.95),
        Vec3::new(0.0, 0.9, -1.0),
        70.0,
        16,
        4,
    );
    camera.spp = 4;
    let params = [
        ("photons", "30000"),
        ("caustic_photons", "2000"),
        ("photon_records", "on"),
    ];
    let desc = scene(camera, ic(5, &params), room(), vec![]);
    let one = render_desc(&desc, 1, 7);
    let two = render_desc(&desc, 2, 7);
    assert_eq!(one.image.pixels, two.image.pixels);
}

/// Caustic photons are aimed at the bounding spheres of delta surfaces: their mean flux is the
/// flux the lights send into those spheres (a point light: I times the cones' solid angle; a
/// directional light: E times the cross-sections), as the mixture's density promises. (The
/// choice between two targets of unequal size leaves the mean a standard error of 0.13 % at
/// 200 000 samples: 1 % is seven of them.)
#[test]
fn aimed_photons_carry_the_flux_that_enters_their_targets() {
    use ircache_render::lights::emission::Targets;
    let spheres = vec![
        (Vec3::new(2.0, 0.0, 0.0), 0.5),
        (Vec3::new(0.0, 3.0, 0.0), 1.0),
    ];
    let targets = Targets::new(spheres.clone(), Vec3::ZERO, 5.0);
    let mean = |set: &LightSet| {
        let mut rng = Rng::new(3, 1);
        let n = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let u = (rng.next_f32(), rng.next_f32());
            if let Some(s) = set.sample_emission_towards(&targets, u, rng.next_2d(), rng.next_2d())
            {
                sum += f64::from(s.flux.g);
            }
        }
        sum / f64::from(n)
    };
    let i = 2.0;
    let point = lights(
        vec![],
        vec![EmitterDesc::Point {
            position: Vec3::ZERO,
            intensity: Rgb::splat(i),
        }],
    );
    let cone = |d: f32, r: f32| {
        2.0 * std::f64::consts::PI * f64::from(1.0 - (1.0 - r * r / (d * d)).sqrt())
    };
    let expect = f64::from(i) * (cone(2.0, 0.5) + cone(3.0, 1.0));
    let got = mean(&point);
    assert!(
        (got / expect - 1.0).abs() < 1e-2,
        "point: {got} against {expect}"
    );

    let e = 1.5;
    let sun = lights(
        vec![],
        vec![EmitterDesc::Directional {
            direction: Vec3::new(0.0, 0.0, -1.0),
            irradiance: Rgb::splat(e),
        }],
    );
    let expect = f64::from(e) * std::f64::consts::PI * (0.25 + 1.0);
    let got = mean(&sun);
    assert!(
        (got / expect - 1.0).abs() < 1e-2,
        "directional: {got} against {expect}"
    );
}

/// Lamps over an open floor: light reflected once leaves the scene, so a global map (photons
/// after a bounce) keeps almost nothing. The pass stops once its rate says so instead of
/// emitting up to its cap (64 per photon asked for).
#[test]
fn a_pass_that_keeps_nothing_stops_early() {
    let le = 2.0;
    let (scene, _) = panel_over_floor(le);
    let wanted = 50_000;
    let map = PhotonMap::build(&scene, MapKind::Global, wanted, 4, 3, None);
    assert_eq!(map.stats.stored, 0);
    assert!(
        map.stats.emitted <= 2 * wanted,
        "emitted {} for a map that keeps nothing",
        map.stats.emitted
    );
    // A map that keeps first hits too fills up and is not cut short.
    let all = PhotonMap::build(&scene, MapKind::All, wanted, 4, 3, None);
    assert!(all.stats.stored >= wanted, "{:?}", all.stats);
}

/// A sun overhead, a smooth Radiance `trans` roof (straight transmission, a Lambertian
/// reflection) and a grey floor. The sun's light straight through the roof is direct light:
/// light samples pass it, as Radiance's shadow rays do. Photons that cross the roof that way
/// must not land on the floor as one-bounce (global) or caustic photons, or every map would
/// count the sunlit floor twice; light the floor sends back up and the roof returns is kept.
#[test]
fn sunlight_straight_through_a_smooth_trans_is_in_no_photon_map() {
    let dir = ircache_testing::ScratchDir::new("trans-sun");
    let path = dir.join("roof.rad");
    std::fs::write(
        &path,
        "void light solar\n0\n0\n3 1e4 1e4 1e4\nsolar source sun\n0\n0\n4 0 0 1 0.5\n\
         void trans tr\n0\n0\n7 1 1 1 0 0 .6 1\n\
         tr polygon roof\n0\n0\n12 -5 -5 1 5 -5 1 5 5 1 -5 5 1\n\
         void plastic grey\n0\n0\n5 .5 .5 .5 0 0\n\
         grey polygon floor\n0\n0\n12 -5 -5 0 5 -5 0 5 5 0 -5 5 0\n",
    )
    .unwrap();
    let desc = ircache_scene::load_scene(&path, &[], &Default::default()).unwrap();
    let scene = Scene::build(&desc).unwrap();
    let global = PhotonMap::build(&scene, MapKind::Global, 20_000, 4, 3, None);
    let on_floor = |p: &&Photon| p.position.z.abs() < 1e-3;
    let photons = &global.tree.photons;
    let first = photons.iter().filter(on_floor).filter(|p| p.bounces == 1);
    assert_eq!(first.count(), 0, "one-bounce photons on the floor");
    // The floor's light, sent back down by the roof, is kept (bounce 2 at the floor).
    assert!(
        photons.iter().filter(on_floor).any(|p| p.bounces == 2),
        "no photon the roof returned"
    );
    let caustic = PhotonMap::build(&scene, MapKind::Caustic, 20_000, 4, 3, None);
    assert_eq!(
        caustic.tree.len(),
        0,
        "caustic photons of the sun's direct light"
    );
}
