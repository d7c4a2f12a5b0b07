//! The samplers in the renderer: the image is bit-identical for any thread count with every
//! sampler (and with adaptive sampling), every sampler's image is unbiased, and stratified
//! samples lower the error of the direct light at equal samples, on a scene whose answer is
//! known in closed form.

mod common;
use common::{diffuse, emitting_shape, here, path, render_desc, render_sampled, scene, sensor};
use ircache_math::{Rgb, Vec3, PI};
use ircache_render::render::{Adaptive, Sampling};
use ircache_render::sampler::SamplerKind;
use ircache_scene::*;

/// A diffuse floor (albedo 0.5) under a spherical emitter of radiance `L` and radius r whose
/// centre is at height h above the origin; a camera sees a patch around the origin so small that
/// every pixel's value is ρ/π · E with E = π L r²/h² (direct light only).
fn floor_under_a_sphere(spp: u32, sampler: &str) -> (SceneDesc, f64) {
    let (l, r, h) = (4.0f32, 0.4f32, 1.5f32);
    let floor = TriangleMesh {
        positions: vec![
            Vec3::new(-5.0, -5.0, 0.0),
            Vec3::new(5.0, -5.0, 0.0),
            Vec3::new(5.0, 5.0, 0.0),
            Vec3::new(-5.0, 5.0, 0.0),
        ],
        normals: None,
        uvs: None,
        indices: vec![[0, 1, 2], [0, 2, 3]],
    };
    let shapes = vec![
        ShapeDesc {
            media: Default::default(),
            id: None,
            geometry: Geometry::Mesh(floor),
            bsdf: diffuse(Rgb::splat(0.5)),
            emitter: None,
            emitter_texture: None,
            emitter_pattern: None,
            location: here(),
        },
        emitting_shape(
            Geometry::Sphere {
                center: Vec3::new(0.0, 0.0, h),
                radius: r,
                flip_normals: false,
                orientation: ircache_math::Mat3::IDENTITY,
            },
            Rgb::splat(l),
        ),
    ];
    let mut cam = sensor(Vec3::new(3.0, 0.5, 1.0), Vec3::ZERO, 0.002, 16, spp);
    cam.sampler = sampler.into();
    let e = f64::from(PI * l * (r / h).powi(2));
    (scene(cam, path(2), shapes, vec![]), 0.5 / f64::from(PI) * e)
}

/// Mean squared relative error of the pixels against `expect`.
fn mse(img: &ircache_image::Image, expect: f64) -> f64 {
    img.pixels
        .iter()
        .map(|p| ((f64::from(p.g) - expect) / expect).powi(2))
        .sum::<f64>()
        / img.pixels.len() as f64
}

/// The light samples alone (`direct`, no BSDF samples): their 2-D coordinates are what the
/// samplers stratify, and the integrand over them is smooth, so stratification must pay.
fn light_samples_only(spp: u32, sampler: &str) -> (SceneDesc, f64) {
    let (mut desc, expect) = floor_under_a_sphere(spp, sampler);
    desc.integrator = IntegratorDesc {
        kind: "direct".into(),
        emitter_samples: 1,
        bsdf_samples: 0,
        ..IntegratorDesc::default()
    };
    (desc, expect)
}

fn pixel_mean(img: &ircache_image::Image) -> f64 {
    img.pixels.iter().map(|p| f64::from(p.g)).sum::<f64>() / img.pixels.len() as f64
}

#[test]
fn stratified_samples_lower_the_direct_lights_error_at_equal_samples() {
    let (desc, expect) = light_samples_only(16, "independent");
    let independent = mse(&render_desc(&desc, 2, 1).image, expect);
    // Independent samples: the error is the light estimator's variance over 16 samples.
    assert!(independent > 1e-7, "independent {independent:.3e}");
    for (sampler, at_most) in [
        // Measured: 0.06, 0.004, 0.001, 0.06, 0.001.
        ("stratified", 0.2),
        ("multijitter", 0.05),
        ("orthogonal", 0.05),
        ("ldsampler", 0.2),
        ("sobol", 0.05),
    ] {
        let (desc, _) = light_samples_only(16, sampler);
        let e = mse(&render_desc(&desc, 2, 1).image, expect);
        assert!(
            e < at_most * independent,
            "{sampler}: {e:.3e} against independent {independent:.3e}"
        );
    }
}

/// With MIS against BSDF samples (the path tracer), every sampler is unbiased: the mean over
/// the pixels is the closed form within four standard errors of that mean. (A shadow ray that
/// stopped at its own light's silhouette once made every sampler 2 % dark here.)
#[test]
fn every_sampler_gives_the_closed_form_direct_light_on_average() {
    for (_, sampler) in SamplerKind::ALL {
        let (desc, expect) = floor_under_a_sphere(16, sampler);
        let img = render_desc(&desc, 2, 1).image;
        let n = img.pixels.len() as f64;
        let mean = pixel_mean(&img);
        let standard_error = (mse(&img, expect) / n).sqrt();
        assert!(
            (mean / expect - 1.0).abs() < 4.0 * standard_error + 1e-4,
            "{sampler}: mean {mean} against {expect} (standard error {standard_error:.2e})"
        );
    }
}

fn render_with(desc: &SceneDesc, sampling: Sampling, threads: usize) -> Vec<Rgb> {
    render_sampled(desc, sampling, threads, 9).image.pixels
}

#[test]
fn every_sampler_gives_the_same_image_for_any_thread_count() {
    let (mut desc, _) = floor_under_a_sphere(8, "independent");
    desc.sensor.to_world = sensor(Vec3::new(3.0, 0.5, 1.0), Vec3::ZERO, 60.0, 24, 8).to_world;
    desc.sensor.fov_degrees = 60.0;
    desc.integrator = path(4);
    let mut images = Vec::new();
    for (kind, _) in SamplerKind::ALL {
        for adaptive in [
            None,
            Some(Adaptive {
                target: 0.05,
                max_spp: 32,
            }),
        ] {
            let sampling = Sampling {
                sampler: kind,
                jitter: true,
                adaptive,
            };
            let one = render_with(&desc, sampling, 1);
            let two = render_with(&desc, sampling, 2);
            assert!(
                one == two,
                "{kind:?} {adaptive:?}: thread count changed the image"
            );
            images.push(one);
        }
    }
    // The samplers differ.
    assert!(images[0] != images[2] && images[2] != images[4]);
}

/// The floor under the sphere seen widely, lit by BSDF samples alone: a pixel's relative
/// variance grows with its distance from the sphere's foot (the sphere covers less of its
/// hemisphere), from about 10 to over 1000, so adaptive sampling has something to find.
fn floor_by_bsdf_samples(spp: u32) -> SceneDesc {
    let (mut desc, _) = floor_under_a_sphere(spp, "sobol");
    desc.sensor = sensor(
        Vec3::new(4.0, 0.0, 3.0),
        Vec3::new(1.0, 0.0, 0.0),
        70.0,
        24,
        spp,
    );
    desc.sensor.sampler = "multijitter".into();
    desc.integrator = IntegratorDesc {
        kind: "direct".into(),
        emitter_samples: 0,
        bsdf_samples: 1,
        ..IntegratorDesc::default()
    };
    desc
}

/// Mean squared relative error against `reference`, with the floor `(0.1 ȳ)²` of adaptive
/// sampling's own measure.
fn relative_mse(img: &ircache_image::Image, reference: &ircache_image::Image) -> f64 {
    let mean = reference.pixels.iter().map(|p| f64::from(p.g)).sum::<f64>()
        / reference.pixels.len() as f64;
    img.pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(a, b)| {
            let (a, b) = (f64::from(a.g), f64::from(b.g));
            (a - b).powi(2) / (b * b + (0.1 * mean).powi(2))
        })
        .sum::<f64>()
        / img.pixels.len() as f64
}

#[test]
fn adaptive_sampling_lowers_the_error_at_equal_samples_and_stays_unbiased() {
    // Prefixes of `sobol` (the default) and of `lattice`.
    adaptive_against_uniform(SamplerKind::Sobol);
    adaptive_against_uniform(SamplerKind::Lattice);
}

fn adaptive_against_uniform(kind: SamplerKind) {
    let reference = render_desc(&floor_by_bsdf_samples(4096), 2, 1).image;
    let adaptive = Sampling {
        sampler: kind,
        jitter: true,
        adaptive: Some(Adaptive {
            target: 0.03,
            max_spp: 1024,
        }),
    };
    let (mut uniform_error, mut adaptive_error, mut spp_sum) = (0.0, 0.0, 0.0);
    let (mut mean_adaptive, mut mean_reference) = (0.0, 0.0);
    for seed in 2..6 {
        let out = render_sampled(&floor_by_bsdf_samples(8), adaptive, 2, seed);
        let pixels = out.image.pixels.len() as f64;
        let spp = out.samples as f64 / pixels;
        // Uniform sampling at the adaptive run's mean count rounded up (in its favour).
        let uniform_spp = spp.ceil() as u32;
        let uniform = render_desc(&floor_by_bsdf_samples(uniform_spp), 2, seed).image;
        let (e_u, e_a) = (
            relative_mse(&uniform, &reference),
            relative_mse(&out.image, &reference),
        );
        eprintln!(
            "{kind:?} seed {seed}: adaptive {spp:.1} spp {e_a:.3e}, uniform {uniform_spp} spp {e_u:.3e}"
        );
        uniform_error += e_u;
        adaptive_error += e_a;
        spp_sum += spp;
        mean_adaptive += pixel_mean(&out.image);
        mean_reference += pixel_mean(&reference);
    }
    assert!(
        spp_sum / 4.0 > 12.0,
        "the target asked for more than the pilot"
    );
    assert!(
        adaptive_error < 0.7 * uniform_error,
        "adaptive {adaptive_error:.3e} against uniform {uniform_error:.3e} at equal samples"
    );
    // Counts never depend on a pixel's own samples directly: no bias towards dark.
    let ratio = mean_adaptive / mean_reference;
    assert!((ratio - 1.0).abs() < 0.01, "mean {ratio}");
}
