//! `obj_scene::load`: a bare OBJ + MTL as a whole scene.

use ircache_math::{Rgb, Vec3};
use ircache_scene::obj_scene::{load, ObjCamera};
use ircache_scene::{BsdfDesc, EmitterDesc, FilterDesc, FovAxis, Geometry, TextureDesc};
use ircache_testing::ScratchDir;
use std::path::Path;

const SCENES: &str = "/work/shared/scenes";

fn temp_dir(name: &str) -> ScratchDir {
    ScratchDir::new(&format!("mesh-scene-{name}"))
}

const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

#[test]
fn mcguire_box_scene() {
    let path = Path::new(SCENES).join("cornell-box-mcguire/CornellBox-Original.obj");
    let s = load(&path, &ObjCamera::default()).unwrap();
    assert_eq!(s.shapes.len(), 8);
    let emitting: Vec<_> = s.shapes.iter().filter(|sh| sh.emitter.is_some()).collect();
    assert_eq!(emitting.len(), 1);
    assert_eq!(emitting[0].id.as_deref(), Some("light"));
    assert_eq!(emitting[0].emitter, Some(Rgb::new(17.0, 12.0, 4.0)));
    assert!(s.emitters.is_empty(), "a lit model gets no environment");
    // Materials: two-sided diffuse with the MTL's Kd.
    let left = s
        .shapes
        .iter()
        .find(|sh| sh.id.as_deref() == Some("leftWall"))
        .unwrap();
    match &*left.bsdf {
        BsdfDesc::TwoSided { front, back: None } => match &**front {
            BsdfDesc::Diffuse {
                reflectance: TextureDesc::Constant(c),
            } => {
                assert_eq!(*c, Rgb::new(0.63, 0.065, 0.05))
            }
            other => panic!("{other:?}"),
        },
        other => panic!("{other:?}"),
    }
    // Camera: in front of the open (+z) side, looking along −z at the box's centre, box filter,
    // 640×480, 16 spp, path tracer with Mitsuba's defaults.
    let m = s.sensor.to_world;
    let eye = m.w_axis.truncate();
    let dir = m.z_axis.truncate();
    assert!(eye.z > 0.99 + 1.0, "{eye:?}");
    assert!(
        (eye.x - 0.0).abs() < 0.05 && (eye.y - 0.995).abs() < 0.01,
        "{eye:?}"
    );
    assert!((dir - Vec3::NEG_Z).length() < 1e-5, "{dir:?}");
    assert!((m.y_axis.truncate() - Vec3::Y).length() < 1e-5);
    // Mitsuba's convention: camera +x = up × dir = Y × (−Z) = −X.
    assert!((m.x_axis.truncate() - Vec3::NEG_X).length() < 1e-5);
    // The whole bounding sphere is inside the vertical field of view.
    let half = (s.sensor.fov_degrees / 2.0).to_radians();
    let radius = Vec3::new(2.02, 1.99, 2.03).length() / 2.0;
    assert!(radius / (eye - Vec3::new(-0.01, 0.995, -0.025)).length() <= half.sin() + 1e-4);
    assert_eq!(s.sensor.fov_axis, FovAxis::Y);
    assert_eq!((s.sensor.film.width, s.sensor.film.height), (640, 480));
    assert_eq!(s.sensor.film.filter, FilterDesc::Box);
    assert_eq!(s.sensor.spp, 16);
    assert_eq!(s.integrator.kind, "path");
    assert_eq!((s.integrator.max_depth, s.integrator.rr_depth), (-1, 5));
    let tris: usize = s
        .shapes
        .iter()
        .map(|sh| match &sh.geometry {
            Geometry::Mesh(m) => m.indices.len(),
            _ => 0,
        })
        .sum();
    assert_eq!(tris, 36);
}

#[test]
fn explicit_camera() {
    let path = Path::new(SCENES).join("cornell-box-mcguire/CornellBox-Original.obj");
    let cam = ObjCamera {
        eye: Some(Vec3::new(0.0, 1.0, 3.0)),
        target: Some(Vec3::new(0.0, 1.0, 0.0)),
        fov: Some(40.0),
        width: Some(100),
        height: Some(50),
        ..ObjCamera::default()
    };
    let s = load(&path, &cam).unwrap();
    assert_eq!(
        s.sensor.to_world.w_axis.truncate(),
        Vec3::new(0.0, 1.0, 3.0)
    );
    assert_eq!(s.sensor.fov_degrees, 40.0);
    assert_eq!((s.sensor.film.width, s.sensor.film.height), (100, 50));
}

#[test]
fn unlit_model_gets_environment_and_phong() {
    let dir = temp_dir("unlit");
    std::fs::write(
        dir.join("m.mtl"),
        "newmtl shiny\nKd 0.2 0.3 0.4\nKs 0.5 0.5 0.5\nNs 30\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("m.obj"),
        format!("mtllib m.mtl\n{TRIANGLE}usemtl shiny\nf 1 2 3\n"),
    )
    .unwrap();
    let s = load(&dir.join("m.obj"), &ObjCamera::default()).unwrap();
    assert!(matches!(s.emitters[..], [EmitterDesc::Constant { radiance }] if radiance == Rgb::ONE));
    match &*s.shapes[0].bsdf {
        BsdfDesc::TwoSided { front, .. } => {
            assert!(
                matches!(&**front, BsdfDesc::ObjPhong { specular, exponent, .. } if *specular == Rgb::splat(0.5) && *exponent == 30.0)
            )
        }
        other => panic!("{other:?}"),
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn missing_mtl_names_the_mtllib_line() {
    let dir = temp_dir("missing");
    std::fs::write(
        dir.join("m.obj"),
        format!("# model\n{TRIANGLE}\n  mtllib nothere.mtl\nf 1 2 3\n"),
    )
    .unwrap();
    let e = load(&dir.join("m.obj"), &ObjCamera::default())
        .unwrap_err()
        .to_string();
    let obj = dir.join("m.obj");
    let prefix = format!(
        "{}:6:10: cannot read {}: ",
        obj.display(),
        dir.join("nothere.mtl").display()
    );
    assert!(e.starts_with(&prefix), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn unknown_material_names_the_usemtl_line() {
    let dir = temp_dir("unknown");
    std::fs::write(dir.join("m.mtl"), "newmtl a\nKd 1 1 1\n").unwrap();
    std::fs::write(
        dir.join("m.obj"),
        format!("mtllib m.mtl\n{TRIANGLE}\tusemtl b\nf 1 2 3\n"),
    )
    .unwrap();
    let e = load(&dir.join("m.obj"), &ObjCamera::default())
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        format!(
            "{}:5:2: unknown material 'b' (not defined in m.mtl)",
            dir.join("m.obj").display()
        )
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn missing_texture_names_the_map_kd_line() {
    let dir = temp_dir("tex");
    std::fs::write(
        dir.join("m.mtl"),
        "newmtl a\nKd 1 1 1\n map_Kd -bm 1 gone.png\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("m.obj"),
        format!("mtllib m.mtl\n{TRIANGLE}usemtl a\nf 1 2 3\n"),
    )
    .unwrap();
    let e = load(&dir.join("m.obj"), &ObjCamera::default())
        .unwrap_err()
        .to_string();
    let prefix = format!(
        "{}:3:2: cannot read {}",
        dir.join("m.mtl").display(),
        dir.join("gone.png").display()
    );
    assert!(e.starts_with(&prefix), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn textured_sponza() {
    let path = Path::new(SCENES).join("sponza-dabrovic/sponza.obj");
    let s = load(&path, &ObjCamera::default()).unwrap();
    assert_eq!(s.emitters.len(), 1);
    // `map_bump` wraps the material in a bump map.
    let unwrap = |b: &std::sync::Arc<BsdfDesc>| match &**b {
        BsdfDesc::BumpMap { nested, .. } => nested.clone(),
        _ => b.clone(),
    };
    let bumped = s
        .shapes
        .iter()
        .filter(|sh| matches!(&*sh.bsdf, BsdfDesc::BumpMap { scale, .. } if *scale > 0.0))
        .count();
    assert!(bumped > 0, "no map_bump became a bump map");
    let textured = s
        .shapes
        .iter()
        .filter(|sh| match &*unwrap(&sh.bsdf) {
            BsdfDesc::TwoSided { front, .. } => {
                matches!(
                    &**front,
                    BsdfDesc::Diffuse {
                        reflectance: TextureDesc::Bitmap(_)
                    }
                )
            }
            _ => false,
        })
        .count();
    println!("sponza: {} shapes, {textured} textured", s.shapes.len());
    assert!(textured > 10);
}
