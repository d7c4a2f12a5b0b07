//! Analytic integrator tests: white furnaces (a closed, emitting, diffusely reflecting enclosure
//! has radiance Le/(1 − ρ) everywhere inside), determinism, and max_depth semantics.

mod common;
use common::*;
use ircache_math::{Mat4, Rgb, Vec3};
use ircache_scene::*;

fn sphere_furnace(rho: f32, le: f32, max_depth: i32, spp: u32) -> SceneDesc {
    let shape = ShapeDesc {
        media: Default::default(),
        id: None,
        geometry: Geometry::Sphere {
            center: Vec3::new(1.0, 2.0, 3.0),
            radius: 5.0,
            flip_normals: true,
            orientation: ircache_math::Mat3::IDENTITY,
        },
        bsdf: diffuse(Rgb::splat(rho)),
        emitter: Some(Rgb::splat(le)),
        emitter_texture: None,
        emitter_pattern: None,
        location: here(),
    };
    scene(
        sensor(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(2.0, 2.5, 3.0),
            60.0,
            16,
            spp,
        ),
        path(max_depth),
        vec![shape],
        vec![],
    )
}

#[test]
fn sphere_furnace_radiance_is_le_over_one_minus_rho() {
    let (rho, le) = (0.5, 0.5);
    let out = render_desc(&sphere_furnace(rho, le, -1, 64), 2, 1);
    let (m, e) = mean_and_error(&out.image);
    let expect = le / (1.0 - rho);
    for c in 0..3 {
        assert!(
            (m[c] - expect).abs() < 4.0 * e[c] + 2e-3,
            "channel {c}: {} vs {expect} (σ {})",
            m[c],
            e[c]
        );
    }
    assert_eq!(out.invalid_samples, 0);
}

#[test]
fn truncated_furnace_sums_the_geometric_series() {
    // max_depth d: emission plus d − 1 reflections: Le (1 + ρ + … + ρ^(d−1)).
    let (rho, le) = (0.8, 1.0);
    for d in [1, 2, 3, 5] {
        let out = render_desc(&sphere_furnace(rho, le, d, 16), 2, 7);
        let (m, e) = mean_and_error(&out.image);
        let expect: f32 = (0..d).map(|k| le * rho.powi(k)).sum();
        assert!(
            (m.g - expect).abs() < 4.0 * e.g + 1e-3 * expect,
            "max_depth {d}: {} vs {expect}",
            m.g
        );
    }
}

#[test]
fn box_furnace_with_scaled_geometry_is_scale_free() {
    // A closed cube (flip_normals: facing inwards) in millimetres and in kilometres.
    for scale in [1e-3f32, 1e3] {
        let mut mesh = ircache_scene::shapes::cube();
        assert!(ircache_scene::shapes::transform_mesh(
            &mut mesh,
            &Mat4::from_scale(Vec3::splat(scale))
        ));
        ircache_scene::shapes::flip_mesh(&mut mesh);
        let shape = ShapeDesc {
            media: Default::default(),
            id: None,
            geometry: Geometry::Mesh(mesh),
            bsdf: diffuse(Rgb::splat(0.5)),
            emitter: Some(Rgb::splat(1.0)),
            emitter_texture: None,
            emitter_pattern: None,
            location: here(),
        };
        let desc = scene(
            sensor(
                Vec3::new(0.1, 0.2, 0.3) * scale,
                Vec3::new(1.0, 0.1, 0.2) * scale,
                70.0,
                16,
                32,
            ),
            path(-1),
            vec![shape],
            vec![],
        );
        let out = render_desc(&desc, 2, 3);
        let (m, e) = mean_and_error(&out.image);
        assert!(
            (m.r - 2.0).abs() < 4.0 * e.r + 4e-3,
            "scale {scale}: {} vs 2",
            m.r
        );
    }
}

#[test]
fn same_seed_same_image_for_any_thread_count() {
    let desc = sphere_furnace(0.7, 1.0, -1, 4);
    let a = render_desc(&desc, 1, 42);
    let b = render_desc(&desc, 2, 42);
    let c = render_desc(&desc, 2, 43);
    assert!(
        a.image.pixels == b.image.pixels,
        "thread count changed the image"
    );
    assert!(a.image.pixels != c.image.pixels, "the seed had no effect");
}
