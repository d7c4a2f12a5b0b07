//! Spheres take Mitsuba 3's uv parametrisation in their own frame (`to_world`'s rotation):
//! u the azimuth from the object's x axis over 2π, v the polar angle from its z axis over π.
//! Checked at points whose values follow by hand from a rotation of −90° about x (object y to
//! world −z, object z to world y); before, ircache measured the poles on the world's y axis
//! whatever the rotation, and a checkerboard sphere differed from Mitsuba's by relMSE 0.7.

use ircache_math::{Ray, Vec2, Vec3};
use ircache_render::scene::Scene;

fn sphere_scene(transform: &str) -> Scene {
    let dir = ircache_testing::ScratchDir::new("sphere-uv");
    let path = dir.join(format!("scene-{}.xml", transform.len()));
    std::fs::write(
        &path,
        format!(
            "<scene version=\"3.0.0\"><sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/></sensor>\
             <shape type=\"sphere\"><transform name=\"to_world\">{transform}<scale value=\"2\"/>\
             <translate x=\"1\" y=\"2\" z=\"3\"/></transform></shape></scene>"
        ),
    )
    .unwrap();
    let desc = ircache_scene::mitsuba::load(&path, &[]).unwrap();
    Scene::build(&desc).unwrap()
}

/// The uv where a ray from far along `world_dir` towards the centre (1, 2, 3) meets the sphere.
fn uv_towards(scene: &Scene, world_dir: Vec3) -> Vec2 {
    let centre = Vec3::new(1.0, 2.0, 3.0);
    let ray = Ray::new(centre + world_dir * 10.0, -world_dir);
    scene.intersect(&ray).expect("the sphere is hit").uv
}

#[test]
fn sphere_uv_follows_mitsuba_in_the_spheres_frame() {
    let close = |a: Vec2, b: Vec2| (a - b).abs().max_element() < 1e-4;
    let rotated = sphere_scene("<rotate x=\"1\" angle=\"-90\"/>");
    for (world, expect) in [
        // Object +x stays world +x: azimuth 0 on the equator.
        (Vec3::X, Vec2::new(0.0, 0.5)),
        // Object +y is world −z: a quarter turn.
        (Vec3::new(0.0, 0.0, -1.0), Vec2::new(0.25, 0.5)),
        // Object −x: half a turn.
        (Vec3::new(-1.0, 0.0, 0.0), Vec2::new(0.5, 0.5)),
        // Object −y is world +z: three quarters.
        (Vec3::new(0.0, 0.0, 1.0), Vec2::new(0.75, 0.5)),
        // Halfway between object +x and +z (world +x and +y): v = ¼.
        (Vec3::new(1.0, 1.0, 0.0).normalize(), Vec2::new(0.0, 0.25)),
    ] {
        let uv = uv_towards(&rotated, world);
        // u = 0 and u = 1 are the same meridian.
        let uv = if uv.x > 0.999 {
            Vec2::new(uv.x - 1.0, uv.y)
        } else {
            uv
        };
        assert!(close(uv, expect), "towards {world}: {uv} against {expect}");
    }
    // Unrotated: the poles on world z, u from world x.
    let plain = sphere_scene("");
    assert!(uv_towards(&plain, Vec3::Z).y < 1e-3, "the pole");
    assert!(close(uv_towards(&plain, Vec3::Y), Vec2::new(0.25, 0.5)));
    assert!(close(
        uv_towards(&plain, -Vec3::Z),
        Vec2::new(uv_towards(&plain, -Vec3::Z).x, 1.0)
    ));
}
