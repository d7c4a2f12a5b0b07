//! The shared benchmark and source scenes load through the Mitsuba 3 XML loader with the
//! expected content.

use ircache_math::{Mat4, Rgb, Vec3, Vec4};
use ircache_scene::shapes::{mesh_area, triangle_normal};
use ircache_scene::{mitsuba, BsdfDesc, EmitterDesc, FilterDesc, FovAxis, Geometry, TextureDesc};
use std::path::PathBuf;

fn scenes() -> PathBuf {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes");
    assert!(
        p.is_dir(),
        "the shared folder with scenes/ must sit beside the checkout: {}",
        p.display()
    );
    p
}

fn defines(d: &[(&str, &str)]) -> Vec<(String, String)> {
    d.iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

fn row_major(v: [f32; 16]) -> Mat4 {
    Mat4::from_cols_array(&v).transpose()
}

fn triangles(g: &Geometry) -> usize {
    match g {
        Geometry::Mesh(m) => m.indices.len(),
        Geometry::Sphere { .. } => 0,
    }
}

#[test]
fn cornell_box() {
    let path = scenes().join("cornell-box/scene.xml");
    let s = mitsuba::load(&path, &[]).unwrap();
    assert_eq!(s.shapes.len(), 8);
    let ids: Vec<&str> = s
        .shapes
        .iter()
        .map(|sh| sh.id.as_deref().unwrap())
        .collect();
    assert_eq!(
        ids,
        [
            "Floor",
            "Ceiling",
            "BackWall",
            "RightWall",
            "LeftWall",
            "ShortBox",
            "TallBox",
            "Light"
        ]
    );
    for sh in &s.shapes {
        let expected = if sh.id.as_deref().unwrap().ends_with("Box") {
            12
        } else {
            2
        };
        assert_eq!(triangles(&sh.geometry), expected, "{:?}", sh.id);
        // Two-sided diffuse everywhere.
        assert!(matches!(*sh.bsdf, BsdfDesc::TwoSided { back: None, .. }));
    }
    let emitting: Vec<_> = s.shapes.iter().filter(|sh| sh.emitter.is_some()).collect();
    assert_eq!(emitting.len(), 1);
    assert_eq!(emitting[0].emitter, Some(Rgb::new(17.0, 12.0, 4.0)));
    assert!(s.emitters.is_empty());

    // Camera.
    let cam = &s.sensor;
    assert_eq!(
        cam.to_world,
        row_major([-1., 0., 0., 0., 0., 1., 0., 1., 0., 0., -1., 6.8, 0., 0., 0., 1.])
    );
    assert_eq!(cam.fov_degrees, 19.5);
    assert_eq!(cam.fov_axis, FovAxis::X);
    assert_eq!((cam.film.width, cam.film.height), (512, 512));
    assert_eq!(cam.film.filter, FilterDesc::Box);
    assert_eq!(cam.spp, 16);
    assert_eq!(cam.sampler, "independent");
    assert_eq!((cam.near_clip, cam.far_clip), (0.01, 10000.0));

    // Integrator: defaults from <default>, overridable with -D.
    assert_eq!(s.integrator.kind, "path");
    assert_eq!(s.integrator.max_depth, 3);
    assert_eq!(s.integrator.rr_depth, 5);
    assert!(!s.integrator.hide_emitters);
    let s5 = mitsuba::load(
        &path,
        &defines(&[("max_depth", "5"), ("spp", "4"), ("rfilter", "tent")]),
    )
    .unwrap();
    assert_eq!(s5.integrator.max_depth, 5);
    assert_eq!(s5.sensor.spp, 4);
    assert_eq!(s5.sensor.film.filter, FilterDesc::Tent { radius: 1.0 });

    // The light: area = |M·(2,0,0) × M·(0,2,0)| of its to_world, normal M⁻ᵀ·z (pointing down).
    let m = row_major([
        0.235,
        -1.66103e-008,
        -7.80685e-009,
        -0.005,
        -2.05444e-008,
        3.90343e-009,
        -0.0893,
        1.98,
        2.05444e-008,
        0.19,
        8.30516e-009,
        -0.03,
        0.,
        0.,
        0.,
        1.,
    ]);
    let du = m.transform_vector3(Vec3::new(2.0, 0.0, 0.0));
    let dv = m.transform_vector3(Vec3::new(0.0, 2.0, 0.0));
    let expected_area = f64::from(du.cross(dv).length());
    let Geometry::Mesh(light) = &emitting[0].geometry else {
        panic!("light is a mesh")
    };
    let area = mesh_area(light);
    assert!(
        (area - expected_area).abs() < 1e-6 * expected_area,
        "{area} vs {expected_area}"
    );
    let n_expected = (ircache_math::Mat3::from_mat4(m).inverse().transpose() * Vec3::Z).normalize();
    for t in 0..2 {
        let n = triangle_normal(light, t);
        assert!((n - n_expected).length() < 1e-4, "{n} vs {n_expected}");
        assert!(n.y < -0.99, "the light faces down");
    }
    // The back wall (z = −1) faces −z, away from the box, exactly as in Mitsuba (its normal is
    // to_world⁻ᵀ·z; the BSDF is two-sided).
    let Geometry::Mesh(back) = &s.shapes[2].geometry else {
        panic!()
    };
    assert!(back.positions.iter().all(|p| (p.z + 1.0).abs() < 1e-5));
    assert!((triangle_normal(back, 0) + Vec3::Z).length() < 1e-5);
    // The floor (y = 0) faces up.
    let Geometry::Mesh(floor) = &s.shapes[0].geometry else {
        panic!()
    };
    assert!((triangle_normal(floor, 1) - Vec3::Y).length() < 1e-5);
    // Shared BSDFs by reference: the two boxes have distinct BSDF objects with the same values.
    let BsdfDesc::TwoSided { front, .. } = &*s.shapes[4].bsdf else {
        panic!()
    };
    let BsdfDesc::Diffuse {
        reflectance: TextureDesc::Constant(c),
    } = &**front
    else {
        panic!()
    };
    assert_eq!(*c, Rgb::new(0.63, 0.065, 0.05));
}

#[test]
fn sponza_sun() {
    let s = mitsuba::load(&scenes().join("sponza-sun/scene.xml"), &[]).unwrap();
    assert_eq!(s.shapes.len(), 20);
    // The files hold 66,454 triangles; exactly one has zero area, which the OBJ reader drops
    // (TriangleMesh promises no degenerate triangles; Mitsuba keeps it, but it is never hit).
    let total: usize = s.shapes.iter().map(|sh| triangles(&sh.geometry)).sum();
    let mut dropped = 0;
    for sh in &s.shapes {
        let file = scenes().join(format!(
            "sponza-sun/meshes/{}.obj",
            sh.id.as_deref().unwrap()
        ));
        dropped += ircache_scene::mesh::read_obj(&file)
            .unwrap()
            .degenerate_dropped;
    }
    assert_eq!(dropped, 1);
    assert_eq!(total + dropped, 66_454);
    for sh in &s.shapes {
        let Geometry::Mesh(m) = &sh.geometry else {
            panic!()
        };
        assert!(m.normals.is_none(), "face_normals drops normals");
    }
    assert_eq!(s.emitters.len(), 1);
    let EmitterDesc::Directional {
        direction,
        irradiance,
    } = &s.emitters[0]
    else {
        panic!("{:?}", s.emitters[0])
    };
    assert_eq!(*irradiance, Rgb::new(64.0, 60.8, 57.6));
    assert!((direction.length() - 1.0).abs() < 1e-6);
    let expected = -Vec3::new(0.35, 1.0, 0.1).normalize();
    assert!((*direction - expected).length() < 1e-4, "{direction}");
    assert_eq!(s.sensor.fov_axis, FovAxis::Y);
    assert_eq!(s.sensor.fov_degrees, 60.0);
    assert_eq!((s.sensor.film.width, s.sensor.film.height), (640, 480));
    // lookat: origin (−14, 1.8, 0), looking along +z of the camera towards (14, 4.5, 0).
    let m = s.sensor.to_world;
    assert_eq!(m.w_axis, Vec4::new(-14.0, 1.8, 0.0, 1.0));
    let dir = Vec3::new(28.0, 2.7, 0.0).normalize();
    assert!((m.z_axis.truncate() - dir).length() < 1e-6);
    assert_eq!(s.integrator.max_depth, 3);
}

#[test]
fn veach_mis() {
    let path = scenes().join("bitterli-veach-mis/scene.xml");
    // As published, the scene names an integrator neither renderer has: it loads (the command
    // line may name another), and its integrator says why it cannot be used, and where.
    let s = mitsuba::load(&path, &[]).unwrap();
    let err = s.integrator.unusable.expect("unusable integrator");
    assert!(
        err.contains("scene.xml:8:2: integrator plugin \"path_guiding_integrator\" not found"),
        "{err}"
    );
    let s = mitsuba::load(&path, &defines(&[("integrator", "path")])).unwrap();
    assert_eq!(s.shapes.len(), 9);
    let spheres: Vec<(Vec3, f32)> = s
        .shapes
        .iter()
        .filter_map(|sh| match sh.geometry {
            Geometry::Sphere {
                center,
                radius,
                flip_normals,
                orientation,
            } => {
                assert!(!flip_normals);
                assert_eq!(orientation, ircache_math::Mat3::IDENTITY);
                Some((center, radius))
            }
            _ => None,
        })
        .collect();
    assert_eq!(
        spheres,
        [
            (Vec3::new(0.0, 6.5, -2.8), 1.0),
            (Vec3::new(0.0, 6.5, 0.0), 0.5),
            (Vec3::new(0.0, 6.5, 2.7), 0.05)
        ]
    );
    let lights: Vec<Rgb> = s.shapes.iter().filter_map(|sh| sh.emitter).collect();
    assert_eq!(lights.len(), 3);
    assert_eq!(lights[2], Rgb::splat(3039.64));
    let total: usize = s.shapes.iter().map(|sh| triangles(&sh.geometry)).sum();
    assert_eq!(total, 52);
    let BsdfDesc::TwoSided { front, .. } = &*s.shapes[0].bsdf else {
        panic!()
    };
    let BsdfDesc::RoughConductor {
        alpha_u,
        alpha_v,
        eta,
        ..
    } = &**front
    else {
        panic!("{front:?}")
    };
    assert_eq!((*alpha_u, *alpha_v), (0.01, 0.01));
    assert_eq!(*eta, Rgb::new(0.200438, 0.924033, 1.10221));
    assert_eq!((s.sensor.film.width, s.sensor.film.height), (1280, 720));
    assert!(matches!(s.sensor.film.filter, FilterDesc::Tent { radius } if radius == 1.0));
}

#[test]
fn bitterli_cornell_v3_and_old_version() {
    let dir = scenes().join("cornell-box-bitterli");
    let s = mitsuba::load(&dir.join("scene_v3.xml"), &[]).unwrap();
    assert_eq!(s.shapes.len(), 8);
    assert_eq!(s.integrator.max_depth, 65);
    // The 0.5.0 file is upgraded in memory (maxDepth → max_depth, toWorld → to_world) as in
    // Mitsuba 3, which then rejects Mitsuba 0.6's `strictNormals` just as Mitsuba 3 does.
    let err = mitsuba::load(&dir.join("scene_v0.6.xml"), &[])
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("scene_v0.6.xml:6:3: unreferenced property \"strict_normals\""),
        "{err}"
    );
}
