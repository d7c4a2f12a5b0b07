//! Radiance caching against independent computations: in a closed box whose diffuse walls send
//! back the ambient value (ρ · av from every direction), a rough-metal floor seen by the camera
//! reflects uniform incoming radiance; shaded from radiance records (HSH, 001 ch. 3) it must match
//! the same floor's glossy lobe traced by the path loop, pixel by pixel, and be free of noise.

mod common;
use common::*;
use ircache_math::{Rgb, Vec3};
use ircache_scene::*;
use std::sync::Arc;

fn quad(c: [Vec3; 4], bsdf: Arc<BsdfDesc>) -> ShapeDesc {
    two_sided_quad(c, bsdf)
}

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

/// The unit box, walls diffuse ρ = 0.6, floor rough aluminium-like metal (GGX α 0.5), a camera
/// above the floor looking down at it; `ic` with ambient value 0.5 and one bounce.
fn furnace(radiance_cache: &str, spp: u32) -> SceneDesc {
    let wall = diffuse(Rgb::splat(0.6));
    let metal = Arc::new(BsdfDesc::RoughConductor {
        distribution: MicrofacetDistribution::Ggx,
        alpha_u: 0.5,
        alpha_v: 0.5,
        eta: Rgb::new(1.66, 0.88, 0.52),
        k: Rgb::new(9.2, 6.3, 4.8),
        specular_reflectance: Rgb::ONE,
    });
    let shapes = vec![
        quad(
            [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
            metal,
        ),
        quad(
            [v(0., 0., 1.), v(1., 0., 1.), v(1., 1., 1.), v(0., 1., 1.)],
            wall.clone(),
        ),
        quad(
            [v(0., 0., 0.), v(1., 0., 0.), v(1., 0., 1.), v(0., 0., 1.)],
            wall.clone(),
        ),
        quad(
            [v(0., 1., 0.), v(1., 1., 0.), v(1., 1., 1.), v(0., 1., 1.)],
            wall.clone(),
        ),
        quad(
            [v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)],
            wall.clone(),
        ),
        quad(
            [v(1., 0., 0.), v(1., 1., 0.), v(1., 1., 1.), v(1., 0., 1.)],
            wall,
        ),
    ];
    let ic = IntegratorDesc {
        kind: "ic".into(),
        max_depth: 3,
        extra: [
            ("ambient_value", "0.5"),
            ("divisions", "256"),
            ("radiance_cache", radiance_cache),
        ]
        .iter()
        .map(|(k, val)| (k.to_string(), ParamValue::String(val.to_string()), here()))
        .collect(),
        ..IntegratorDesc::default()
    };
    // Half-way up, tilted, seeing only the floor at viewing angles from 0° to about 32°.
    scene(
        sensor(v(0.5, 0.5, 0.5), v(0.55, 0.6, 0.0), 40.0, 24, spp),
        ic,
        shapes,
        vec![],
    )
}

#[test]
fn cached_glossy_light_equals_the_traced_lobe_in_a_furnace() {
    let cached = render_desc(&furnace("on", 4), 2, 1);
    // Same seed, same image, whatever the thread count.
    let one_thread = render_desc(&furnace("on", 4), 1, 1);
    assert_eq!(cached.image.pixels, one_thread.image.pixels);
    let traced = render_desc(&furnace("off", 256), 2, 1);
    let stats = &cached.cache.as_ref().expect("cache").stats;
    assert!(stats.radiance_records > 0, "no radiance records");
    let (w, px) = (24, |img: &ircache_image::Image, x: usize, y: usize| {
        img.pixels[y * 24 + x]
    });
    let row_mean = |img: &ircache_image::Image, y: usize| -> f64 {
        (0..w).map(|x| f64::from(px(img, x, y).r)).sum::<f64>() / w as f64
    };
    let (mut sum_c, mut sum_t) = (0.0, 0.0);
    for y in 0..w {
        let (c, t) = (row_mean(&cached.image, y), row_mean(&traced.image, y));
        // A row of the traced image averages 24 × 256 samples of the lobe: about 1 % noise.
        assert!(
            (c / t - 1.0).abs() < 0.03,
            "row {y}: cached {c}, traced {t}"
        );
        sum_c += c;
        sum_t += t;
        for x in 1..w {
            // Cached: no noise, the albedo changes slowly with the viewing angle.
            let (a, b) = (px(&cached.image, x - 1, y).r, px(&cached.image, x, y).r);
            assert!(
                a.is_finite() && a > 0.0 && (a / b - 1.0).abs() < 0.005,
                "({x}, {y}): {a} {b}"
            );
        }
    }
    let ratio = sum_c / sum_t;
    assert!((ratio - 1.0).abs() < 0.01, "mean cached / traced = {ratio}");
}
