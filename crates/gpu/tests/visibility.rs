//! Records from a rasterised plane (issue 12): the triangles the GPU rasterises into a record's
//! plane are the ones Embree's ray through each pixel centre hits, and the plane's irradiance
//! shaded from them equals the ray-cast plane's, on the Cornell box at visible points. On
//! lavapipe where there is no GPU; with no device the test fails and says so, unless
//! `IRCACHE_GPU_TESTS=skip`.

mod common;

use ircache_gpu::visibility::{pixels_seeing_the_rays, PlaneVisibility};
use ircache_render::irradiance_cache::gather::{Gatherer, SceneRadiance, WorkState};
use ircache_render::irradiance_cache::plane::{HemispherePlane, PlaneEstimator};
use ircache_render::irradiance_cache::points::visible_sites;
use ircache_render::irradiance_cache::{IcParams, IrradianceCache};
use ircache_render::scene::Scene;

#[test]
fn rasterised_planes_see_what_the_rays_see() {
    let Some(gpu) = common::gpu() else { return };
    let desc = common::shared("cornell-box");
    let scene = Scene::build(&desc).expect("scene builds");
    let visibility = PlaneVisibility::new(gpu, &scene);
    assert_eq!(visibility.spheres, 0);
    let cache = IrradianceCache::new(&scene, &IcParams::default());
    let light = SceneRadiance::path_traced(&scene);
    let g = Gatherer::new(&light, &cache, 3);
    let plane = HemispherePlane::new(64, 2.0);
    let (mut pixels, mut agree, mut points) = (0usize, 0usize, 0usize);
    let mut squared = 0.0f64;
    for sp in visible_sites(&scene, 12, 5) {
        points += 1;
        let seen = visibility.triangles(&plane, &sp).expect("rasterised");
        pixels += plane.pixels * plane.pixels;
        agree += pixels_seeing_the_rays(&scene, &plane, &sp, &seen);
        let key = points as u64;
        let mut st = WorkState::new(1);
        let (raster, _) = visibility
            .record_plane(&scene, &light, &g, &mut st, &plane, &sp, 0, key)
            .expect("shaded");
        let traced = plane.sample(&g, &mut st, &sp, 0, key);
        let e = |l: &[ircache_math::Rgb]| {
            f64::from(
                plane
                    .irradiance(l, PlaneEstimator::BorderCompensation)
                    .luminance(),
            )
        };
        let (a, b) = (e(&raster.radiance), e(&traced.radiance));
        squared += ((a - b) / b).powi(2);
    }
    let share = agree as f64 / pixels as f64;
    eprintln!(
        "{agree} of {pixels} pixels agree; RMS {}",
        (squared / points as f64).sqrt()
    );
    assert!(
        share > 0.99,
        "{agree} of {pixels} pixels see the rays' triangle"
    );
    let rms = (squared / points as f64).sqrt();
    assert!(rms < 0.01, "rasterised against ray-cast planes: RMS {rms}");
}

/// Planes rasterised side by side in batches (more than one atlas: 4 096 planes fill one) see
/// what the rays see, at both ends of each batch; so does the camera's view, pixel centre by
/// pixel centre, at an odd film size.
#[test]
fn batched_planes_and_the_camera_view_see_what_the_rays_see() {
    let Some(gpu) = common::gpu() else { return };
    let desc = common::shared("cornell-box");
    let scene = Scene::build(&desc).expect("scene builds");
    let visibility = PlaneVisibility::new(gpu, &scene);
    let plane = HemispherePlane::new(16, 2.0);
    let points = visible_sites(&scene, 4100, 9);
    assert_eq!(points.len(), 4100);
    let planes = visibility.planes(&plane, &points).expect("rasterised");
    assert_eq!(planes.len(), points.len());
    let (mut pixels, mut agree) = (0usize, 0usize);
    for k in (0..8).chain(4088..4100) {
        pixels += plane.pixels * plane.pixels;
        agree += pixels_seeing_the_rays(&scene, &plane, &points[k], &planes[k]);
    }
    assert!(
        agree as f64 > 0.99 * pixels as f64,
        "{agree} of {pixels} batched plane pixels see the rays' triangle"
    );
    let (w, h) = (97u32, 61u32);
    let camera = ircache_render::camera::Camera::new(&desc.sensor, w, h);
    let ids = visibility.camera_view(&camera, w, h).expect("rasterised");
    assert_eq!(ids.len(), (w * h) as usize);
    let mut agree = 0;
    let mut seen_something = 0;
    for y in 0..h {
        for x in 0..w {
            let film =
                ircache_math::Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
            let hit = scene.intersect(&camera.generate_ray(film));
            let id = ids[(y * w + x) as usize];
            seen_something += usize::from(id.is_some());
            agree += usize::from(hit.map(|h| (h.shape, h.prim)) == id);
        }
    }
    let n = (w * h) as usize;
    assert!(seen_something > n / 2, "the camera sees the box");
    assert!(
        agree as f64 > 0.99 * n as f64,
        "{agree} of {n} camera pixels see the ray's triangle"
    );
}
