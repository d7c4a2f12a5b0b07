//! Agreement with the Mitsuba 3 path-traced references in `shared/references/` (README there
//! defines relMSE_trim). The default run checks the Cornell box at 64 spp and Sponza at 16 spp
//! against the error Mitsuba's own path tracer reaches at that spp (its relMSE_trim falls as
//! 2.8e-5 + 0.114/spp on the Cornell box and 1e-3 + 4.0/spp on Sponza), with 30 % headroom for
//! noise; the issue's full figures (256 spp) run with `--ignored`. The irradiance cache (`ic`,
//! one bounce) must reach at least the error of Radiance's "high" settings (references README:
//! Cornell box 3.7e-4, Sponza 1.04e-2) at its default settings.

use ircache_image::compare::compare;
use ircache_render::film::Filter;
use ircache_render::integrators::Integrator;
use ircache_render::render::{render, RenderSettings};
use ircache_render::scene::Scene;
use ircache_scene::obj_scene::ObjCamera;
use std::path::PathBuf;

fn shared() -> PathBuf {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared");
    assert!(
        p.join("references").is_dir(),
        "the shared folder with references/ must sit beside the checkout: {}",
        p.display()
    );
    p
}

/// A scene or reference path: the project's own (`scenes/` of this checkout) where it exists
/// there, else the shared folder's.
fn resolve(path: &str) -> PathBuf {
    let own = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(path);
    if own.exists() {
        own
    } else {
        shared().join(path)
    }
}

/// Renders `scene` with max_depth 3 at `spp` and returns (relMSE_trim, luminance ratio).
fn against_reference(scene: &str, reference: &str, spp: u32) -> (f64, f64) {
    render_against_reference(scene, reference, spp, None)
}

/// The same with the `ic` integrator and cache parameters `ic` (max_depth 3: one bounce).
fn render_against_reference(
    scene: &str,
    reference: &str,
    spp: u32,
    ic: Option<&[(&str, &str)]>,
) -> (f64, f64) {
    let root = shared();
    let defines = vec![("max_depth".to_string(), "3".to_string())];
    let mut desc = ircache_scene::load_scene(&root.join(scene), &defines, &ObjCamera::default())
        .expect("scene loads");
    if ic.is_some() {
        desc.integrator.kind = "ic".into();
    }
    let built = Scene::build(&desc).expect("scene builds");
    let mut integrator = Integrator::from_desc(&desc.integrator).expect("integrator");
    if let (Integrator::Ic(i), Some(params)) = (&mut integrator, ic) {
        for (k, v) in params {
            i.params.set(k, v).expect("parameter");
        }
    }
    let settings = RenderSettings {
        width: desc.sensor.film.width as usize,
        height: desc.sensor.film.height as usize,
        spp,
        seed: 11,
        threads: 0,
        filter: Filter::from_desc(&desc.sensor.film.filter),
        band: None,
        sampling: ircache_render::render::Sampling::default(),
    };
    let out = render(&built, &integrator, &settings, &|_| {}).expect("render");
    let reference = ircache_image::read_image(&root.join(reference)).expect("reference reads");
    let m = compare(&out.image, &reference).expect("same size");
    if let Some(c) = &out.cache {
        eprintln!("{} records, {:.2} s", c.stats.records(), out.seconds);
    }
    eprintln!(
        "{scene} at {spp} spp: relMSE_trim {:.3e}, lum ratio {:.4}",
        m.rel_mse_trim, m.lum_ratio
    );
    assert_eq!(m.nonfinite_a, 0);
    (m.rel_mse_trim, m.lum_ratio)
}

#[test]
fn cornell_box_matches_mitsuba_at_64_spp() {
    let (e, lum) = against_reference(
        "scenes/cornell-box/scene.xml",
        "references/cornell-box-d3.exr",
        64,
    );
    let mitsuba = 2.8e-5 + 0.114 / 64.0;
    assert!(
        e < 1.3 * mitsuba,
        "relMSE_trim {e:.3e} vs Mitsuba's {mitsuba:.3e}"
    );
    assert!((lum - 1.0).abs() < 0.01, "mean luminance ratio {lum}");
}

#[test]
fn sponza_matches_mitsuba_at_16_spp() {
    let (e, lum) = against_reference(
        "scenes/sponza-sun/scene.xml",
        "references/sponza-sun-d3.exr",
        16,
    );
    let mitsuba = 1e-3 + 4.0 / 16.0;
    assert!(
        e < 1.3 * mitsuba,
        "relMSE_trim {e:.3e} vs Mitsuba's {mitsuba:.3e}"
    );
    assert!((lum - 1.0).abs() < 0.02, "mean luminance ratio {lum}");
}

#[test]
#[ignore = "long: 256 spp, run with --ignored"]
fn cornell_box_256_spp_meets_the_issue_target() {
    let (e, lum) = against_reference(
        "scenes/cornell-box/scene.xml",
        "references/cornell-box-d3.exr",
        256,
    );
    assert!(
        e <= 1e-3,
        "relMSE_trim {e:.3e} (target 1e-3, Mitsuba 4.8e-4)"
    );
    assert!((lum - 1.0).abs() < 0.01, "mean luminance ratio {lum}");
}

#[test]
#[ignore = "long: 256 spp, run with --ignored"]
fn sponza_256_spp_meets_the_issue_target() {
    let (e, lum) = against_reference(
        "scenes/sponza-sun/scene.xml",
        "references/sponza-sun-d3.exr",
        256,
    );
    assert!(
        e <= 0.04,
        "relMSE_trim {e:.3e} (target 0.04, Mitsuba 0.017)"
    );
    assert!((lum - 1.0).abs() < 0.01, "mean luminance ratio {lum}");
}

#[test]
fn cornell_box_irradiance_cache_reaches_radiance_high() {
    let (e, lum) = render_against_reference(
        "scenes/cornell-box/scene.xml",
        "references/cornell-box-d3.exr",
        16,
        Some(&[]),
    );
    assert!(e <= 3.7e-4, "relMSE_trim {e:.3e} vs Radiance high's 3.7e-4");
    assert!((lum - 1.0).abs() < 0.01, "mean luminance ratio {lum}");
}

#[test]
fn sponza_irradiance_cache_reaches_radiance_high() {
    let (e, lum) = render_against_reference(
        "scenes/sponza-sun/scene.xml",
        "references/sponza-sun-d3.exr",
        8,
        Some(&[]),
    );
    assert!(
        e <= 1.04e-2,
        "relMSE_trim {e:.3e} vs Radiance high's 1.04e-2"
    );
    assert!((lum - 1.0).abs() < 0.01, "mean luminance ratio {lum}");
}

/// Renders the Cornell box with integrator `kind` at `size`², `spp` and `seed` (all cores);
/// `ic` adjusts the cache integrator before rendering.
fn render_cornell(
    kind: &str,
    max_depth: Option<i32>,
    hide_emitters: bool,
    (size, spp, seed): (u32, u32, u64),
    ic: impl FnOnce(&mut ircache_render::integrators::ic::IcIntegrator),
) -> Result<ircache_render::render::RenderOutput, ircache_render::scene::RenderError> {
    let root = shared();
    let mut desc = ircache_scene::load_scene(
        &root.join("scenes/cornell-box/scene.xml"),
        &[],
        &ObjCamera::default(),
    )
    .expect("scene loads");
    desc.integrator.kind = kind.into();
    if let Some(d) = max_depth {
        desc.integrator.max_depth = d;
    }
    desc.integrator.hide_emitters = hide_emitters;
    desc.sensor.film.width = size;
    desc.sensor.film.height = size;
    let built = Scene::build(&desc).expect("scene builds");
    let mut integrator = Integrator::from_desc(&desc.integrator).expect("integrator");
    if let Integrator::Ic(i) = &mut integrator {
        ic(i);
    }
    let settings = RenderSettings {
        width: size as usize,
        height: size as usize,
        spp,
        seed,
        threads: 0,
        filter: Filter::Box,
        band: None,
        sampling: ircache_render::render::Sampling::default(),
    };
    render(&built, &integrator, &settings, &|_| {})
}

/// The Cornell box at 96×96 with the given integrator and cache parameters, its light hidden
/// (pixels on the light's edge are so bright that their noise moves the mean by ~1 % at this
/// size).
fn small_cornell(
    kind: &str,
    max_depth: i32,
    spp: u32,
    ic: &[(&str, &str)],
) -> ircache_image::Image {
    render_cornell(kind, Some(max_depth), true, (96, spp, 3), |i| {
        for (k, v) in ic {
            i.params.set(k, v).expect("parameter");
        }
    })
    .expect("render")
    .image
}

#[test]
fn two_bounce_cache_equals_path_tracing_at_max_depth_4() {
    // --bounces N equals path tracing with max_depth N + 2 (one cache per bounce level).
    let ic = small_cornell("ic", 4, 64, &[]);
    let path = small_cornell("path", 4, 1024, &[]);
    let m = compare(&ic, &path).expect("same size");
    eprintln!(
        "ic -ab 2 vs path max_depth 4: relMSE_trim {:.3e}, lum ratio {:.4}",
        m.rel_mse_trim, m.lum_ratio
    );
    // Record noise and interpolation move the mean by a few tenths of a percent at this size.
    assert!(
        (m.lum_ratio - 1.0).abs() < 0.015,
        "lum ratio {}",
        m.lum_ratio
    );
    assert!(m.rel_mse_trim < 5e-3, "relMSE_trim {}", m.rel_mse_trim);
    // And one bounce less is visibly darker: the second bounce is there.
    let one = small_cornell("ic", 3, 64, &[]);
    let m1 = compare(&one, &path).expect("same size");
    assert!(
        m1.lum_ratio < 0.97,
        "one bounce: lum ratio {}",
        m1.lum_ratio
    );
}

#[test]
fn supersampling_lowers_record_error_at_equal_rays_on_sponza() {
    // 003 item 2: 1024 stratified rays + 512 adaptive super-samples against 1536 stratified
    // rays, at 300 points in Sponza's courtyard, each against a 65536-ray gather.
    use ircache_math::Vec3;
    use ircache_render::irradiance_cache::points::{irradiance_at_points, PointMethod};
    use ircache_render::irradiance_cache::IcParams;
    let root = shared();
    let desc = ircache_scene::load_scene(
        &root.join("scenes/sponza-sun/scene.xml"),
        &[],
        &ObjCamera::default(),
    )
    .expect("scene loads");
    let scene = Scene::build(&desc).expect("scene builds");
    let mut rng = ircache_math::Rng::keyed(1, &[]);
    let points: Vec<(Vec3, Vec3)> = (0..300)
        .map(|_| {
            let u = rng.next_2d();
            (
                Vec3::new(-12.0 + 24.0 * u.x, 0.5, -5.5 + 11.0 * u.y),
                Vec3::Y,
            )
        })
        .collect();
    use ircache_render::irradiance_cache::params::GatherPattern;
    let run = |samples: usize, supersamples: usize, pattern: GatherPattern, seed: u64| {
        let p = IcParams {
            supersamples,
            gather_pattern: pattern,
            ..IcParams::default()
        };
        let (r, _) = irradiance_at_points(
            &scene,
            &p,
            &points,
            PointMethod::BruteForce { samples },
            0,
            seed,
        );
        r.iter().map(|x| x.indirect.g).collect::<Vec<f32>>()
    };
    let truth = run(65536, 0, GatherPattern::Multijittered, 100);
    let mean_truth = truth.iter().sum::<f32>() / truth.len() as f32;
    let error = |e: &[f32]| -> (f32, f32) {
        let mse = e
            .iter()
            .zip(&truth)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f32>()
            / e.len() as f32;
        let mean = e.iter().sum::<f32>() / e.len() as f32;
        (mse.sqrt() / mean_truth, mean / mean_truth)
    };
    // Radiance's jittered gathers gain more than 5 %; multi-jittered ones already meet a
    // patch's edges more evenly with plain rays, and gain less (4 % here; in renders at the
    // defaults, where super-samples go only to records that need them, they still halve the
    // records' noise: BENCHMARKS.md).
    let mut super_sampled = Vec::new();
    for (pattern, gain) in [
        (GatherPattern::Jittered, 0.95),
        (GatherPattern::Multijittered, 1.0),
    ] {
        let (mut plain, mut adaptive) = (0.0, 0.0);
        for seed in 1..=3 {
            let (ep, mp) = error(&run(1536, 0, pattern, seed));
            let (ea, ma) = error(&run(1024, 512, pattern, seed));
            eprintln!(
                "{pattern:?} seed {seed}: plain {ep:.4} (mean {mp:.4}), super-sampled {ea:.4} \
                 (mean {ma:.4})"
            );
            // Unbiased: the choice of cells never looks at their own samples.
            assert!((ma - 1.0).abs() < 0.03, "super-sampled mean ratio {ma}");
            plain += ep;
            adaptive += ea;
        }
        assert!(
            adaptive < gain * plain,
            "{pattern:?}: super-sampling {adaptive:.4} vs plain {plain:.4} (sum over 3 seeds)"
        );
        super_sampled.push(adaptive);
    }
    // The same rays, multi-jittered, err less (6 % here).
    assert!(
        super_sampled[1] < 0.98 * super_sampled[0],
        "multi-jittered {:.4} against jittered {:.4}",
        super_sampled[1],
        super_sampled[0]
    );
}

#[test]
fn ambient_average_raises_the_truncated_image_without_overshooting() {
    // 003 item 1: with -aw, the light beyond the last bounce is estimated from what the cache
    // computed; one bounce gets brighter, towards the converged image, and stays below it.
    let mean = |img: &ircache_image::Image| {
        img.pixels.iter().map(|p| p.luminance() as f64).sum::<f64>() / img.pixels.len() as f64
    };
    let plain = mean(&small_cornell("ic", 3, 16, &[]));
    let averaged = mean(&small_cornell("ic", 3, 16, &[("ambient_weight", "32")]));
    let converged = mean(&small_cornell("path", 12, 512, &[]));
    eprintln!("one bounce {plain:.5}, with -aw {averaged:.5}, converged {converged:.5}");
    assert!(averaged > plain * 1.01, "{averaged} vs {plain}");
    assert!(averaged < converged, "{averaged} vs {converged}");
}

#[test]
fn no_minimum_spacing_resolves_corners_further() {
    // 003 items 3–4: -ar 0 means no minimum record radius, so corners get more records.
    let records = |ar: &str| {
        let out = render_cornell("ic", None, false, (128, 1, 1), |i| {
            i.params.set("error_metric", "ward").unwrap();
            i.params.set("resolution", ar).unwrap();
            i.params.set("divisions", "128").unwrap();
        })
        .expect("render");
        let c = out.cache.expect("cache");
        let min_r = c.cache.levels[0]
            .records()
            .iter()
            .map(|r| r.r)
            .fold(f32::INFINITY, f32::min);
        (c.stats.records(), min_r, c.cache.r_min)
    };
    let (coarse, coarse_min, floor) = records("16");
    let (free, free_min, zero) = records("0");
    eprintln!("ar 16: {coarse} records, smallest radius {coarse_min} (floor {floor}); ar 0: {free}, {free_min}");
    assert_eq!(zero, 0.0);
    assert!(coarse_min >= floor * 0.999);
    assert!(free_min < floor);
    assert!(free > coarse, "{free} vs {coarse}");
}

#[test]
fn excluded_surfaces_take_no_records_and_included_ones_take_all() {
    use ircache_render::integrators::ic::Exclusions;
    let run = |ex: Exclusions| {
        render_cornell("ic", None, false, (96, 2, 1), |i| {
            i.params.set("divisions", "128").unwrap();
            i.exclusions = ex;
        })
        .expect("render")
    };
    let on_floor =
        |r: &ircache_render::irradiance_cache::Record| r.p.y.abs() < 1e-3 && r.n.y > 0.99;
    let all = run(Exclusions::None);
    let no_floor = run(Exclusions::Exclude(vec!["Floor".into()]));
    let only_floor = run(Exclusions::Include(vec!["Floor".into()]));
    let recs = |o: &ircache_render::render::RenderOutput| {
        o.cache.as_ref().unwrap().cache.levels[0].records().to_vec()
    };
    let (a, b, c) = (recs(&all), recs(&no_floor), recs(&only_floor));
    assert!(a.iter().any(on_floor));
    assert!(!b.iter().any(on_floor) && b.len() < a.len());
    assert!(!c.is_empty() && c.iter().all(on_floor));
    // The excluded floor gets the ambient value (0 here) as its indirect light: darker.
    let bottom = |o: &ircache_render::render::RenderOutput| -> f32 {
        (0..96).map(|x| o.image.get(x, 92).luminance()).sum()
    };
    assert!(
        bottom(&no_floor) < 0.97 * bottom(&all),
        "{} vs {}",
        bottom(&no_floor),
        bottom(&all)
    );
    // Unknown names are an error that lists the known ones.
    let e = render_cornell("ic", None, false, (8, 1, 1), |i| {
        i.exclusions = Exclusions::Exclude(vec!["Flor".into()]);
    })
    .expect_err("refused")
    .to_string();
    assert!(e.contains("\"Flor\"") && e.contains("Floor"), "{e}");
}

#[test]
fn the_full_overture_lowers_the_error() {
    // 002 / Mitsuba's irrcache: the pre-pass fills the cache so the pixels interpolate; stopping
    // it at every fourth pixel leaves more to extrapolation. (Without any pre-pass every sample
    // gathers a small record of its own: accurate but many times slower; see BENCHMARKS.md.)
    // Blurred (σ = 1.5 px): the extrapolation error is low-frequency, while the 1024-spp
    // reference's own pixel noise, which dominates the unblurred error at 96 px, fades.
    use ircache_image::blur::gaussian_blur;
    let path = gaussian_blur(&small_cornell("path", 3, 1024, &[]), 1.5);
    let err = |overture: &str| {
        let img = gaussian_blur(&small_cornell("ic", 3, 4, &[("overture", overture)]), 1.5);
        compare(&img, &path).expect("same size").rel_mse_trim
    };
    let (full, coarse) = (err("full"), err("coarse"));
    eprintln!("overture full {full:.3e}, coarse {coarse:.3e}");
    assert!(full < 0.95 * coarse, "{full} vs {coarse}");
}

/// The reference averaged over `k`×`k` blocks: the same image as a render at 1/k the size with a
/// box pixel filter (each pixel integrates its area).
fn downsample(img: &ircache_image::Image, k: usize) -> ircache_image::Image {
    let mut out = ircache_image::Image::new(img.width / k, img.height / k);
    for y in 0..out.height {
        for x in 0..out.width {
            let mut sum = ircache_math::Rgb::ZERO;
            for j in 0..k {
                for i in 0..k {
                    sum += img.get(k * x + i, k * y + j);
                }
            }
            out.set(x, y, sum / (k * k) as f32);
        }
    }
    out
}

/// Renders `scene` (its defaults `defines` overridden) at 1/`k` of its film size with
/// `integrator` (max_depth `depth`, cache parameters `params`) and compares it with the reference averaged to that size: returns
/// (relMSE_trim, relMSE_trim after a Gaussian blur of σ = 1 px, luminance ratio, seconds).
#[allow(clippy::too_many_arguments)]
fn small_against_reference(
    scene: &str,
    defines: &[(&str, &str)],
    reference: &str,
    k: usize,
    depth: i32,
    spp: u32,
    integrator: &str,
    params: &[(&str, &str)],
) -> (f64, f64, f64, f64) {
    use ircache_image::blur::gaussian_blur;
    let mut defines: Vec<(String, String)> = defines
        .iter()
        .map(|(n, v)| (n.to_string(), v.to_string()))
        .collect();
    defines.push(("max_depth".to_string(), depth.to_string()));
    let mut desc = ircache_scene::load_scene(&resolve(scene), &defines, &ObjCamera::default())
        .expect("scene loads");
    desc.integrator.kind = integrator.into();
    let built = Scene::build(&desc).expect("scene builds");
    let mut integ = Integrator::from_desc(&desc.integrator).expect("integrator");
    if let Integrator::Ic(i) = &mut integ {
        for (n, v) in params {
            i.params.set(n, v).expect("parameter");
        }
    }
    let settings = RenderSettings {
        width: desc.sensor.film.width as usize / k,
        height: desc.sensor.film.height as usize / k,
        spp,
        seed: 5,
        threads: 0,
        filter: Filter::from_desc(&desc.sensor.film.filter),
        band: None,
        sampling: ircache_render::render::Sampling::default(),
    };
    let out = render(&built, &integ, &settings, &|_| {}).expect("render");
    let reference = downsample(
        &ircache_image::read_image(&resolve(reference)).expect("reference reads"),
        k,
    );
    let m = compare(&out.image, &reference).expect("same size");
    let b = compare(
        &gaussian_blur(&out.image, 1.0),
        &gaussian_blur(&reference, 1.0),
    )
    .expect("same size");
    eprintln!(
        "{scene} 1/{k} d{depth} {integrator} {spp} spp: relMSE_trim {:.3e}, blurred {:.3e}, \
         lum {:.4}, {:.2} s",
        m.rel_mse_trim, b.rel_mse_trim, m.lum_ratio, out.seconds
    );
    assert_eq!(m.nonfinite_a, 0);
    (m.rel_mse_trim, b.rel_mse_trim, m.lum_ratio, out.seconds)
}

#[test]
fn the_cache_keeps_the_glossy_light_of_cornell_glossy() {
    // Rough metal, rough plastic: their glossy lobes are traced, the Lambertian parts cached.
    // Dropping the glossy light (the cache's old behaviour) darkens the metal box to black.
    for (depth, reference) in [
        (3, "references/cornell-glossy-d3.exr"),
        (5, "references/cornell-glossy-d5.exr"),
    ] {
        let (e, blurred, lum, _) = small_against_reference(
            "scenes/cornell-glossy/scene.xml",
            &[],
            reference,
            4,
            depth,
            16,
            "ic",
            &[],
        );
        let (pe, pblurred, _, _) = small_against_reference(
            "scenes/cornell-glossy/scene.xml",
            &[],
            reference,
            4,
            depth,
            16,
            "path",
            &[],
        );
        // At equal samples the cache's error, noise and low-frequency error alike, is a small
        // part of the path tracer's (measured: 0.05–0.06 of it, 0.14–0.23 blurred).
        assert!((lum - 1.0).abs() < 0.01, "d{depth}: lum ratio {lum}");
        assert!(e < 0.2 * pe, "d{depth}: {e:.3e} vs path {pe:.3e}");
        assert!(
            blurred < 0.4 * pblurred,
            "d{depth}: blurred {blurred:.3e} vs path {pblurred:.3e}"
        );
    }
}

#[test]
fn deep_bounces_match_the_max_depth_10_references() {
    // `-ab 8`: the bounces beyond the records' own are path-traced from their gather hits.
    for (scene, reference, k) in [
        (
            "scenes/cornell-box/scene.xml",
            "references/cornell-box-d10.exr",
            4,
        ),
        (
            "scenes/sponza-sun/scene.xml",
            "references/sponza-sun-d10.exr",
            4,
        ),
    ] {
        let (e, blurred, lum, _) =
            small_against_reference(scene, &[], reference, k, 10, 16, "ic", &[]);
        let (pe, pblurred, _, _) =
            small_against_reference(scene, &[], reference, k, 10, 16, "path", &[]);
        // Measured: 0.06–0.11 of the path tracer's error at equal samples; blurred, 0.5–0.8 of
        // the path tracer's with multi-jittered samples (0.31–0.52 of it with independent ones).
        assert!((lum - 1.0).abs() < 0.01, "{scene}: lum ratio {lum}");
        assert!(e < 0.25 * pe, "{scene}: {e:.3e} vs path {pe:.3e}");
        assert!(
            blurred < pblurred,
            "{scene}: blurred {blurred:.3e} vs path {pblurred:.3e}"
        );
    }
}

#[test]
fn path_tracing_at_quarter_size_meets_mitsubas_error_law() {
    // A pixel of the 1/4-size image integrates 16 reference pixels, so at N spp its variance is
    // a full-size pixel's at N spp: Mitsuba's relMSE_trim law (2.8e-5 + 0.114/N on the Cornell
    // box, 1e-3 + 4.0/N on Sponza, the constants the reference's own noise, 16 times smaller
    // here) with 30 % headroom. Blurred by 1 px, what is left is mostly bias: a local one of
    // 25 % over a twentieth of the image would add 3e-3 (measured: 9e-6 and 1.3e-3).
    for (scene, reference, spp, law, blur_bound) in [
        (
            "scenes/cornell-box/scene.xml",
            "references/cornell-box-d3.exr",
            1024,
            2.8e-5 / 16.0 + 0.114 / 1024.0,
            3e-5,
        ),
        (
            "scenes/sponza-sun/scene.xml",
            "references/sponza-sun-d3.exr",
            256,
            1e-3 / 16.0 + 4.0 / 256.0,
            2e-3,
        ),
    ] {
        let (e, blurred, lum, _) =
            small_against_reference(scene, &[], reference, 4, 3, spp, "path", &[]);
        assert!(e < 1.3 * law, "{scene}: {e:.3e} vs Mitsuba's {law:.3e}");
        assert!(blurred < blur_bound, "{scene}: blurred {blurred:.3e}");
        assert!((lum - 1.0).abs() < 0.005, "{scene}: lum ratio {lum}");
    }
}

#[test]
fn radiance_records_hold_a_smooth_sky_and_leave_a_sun_to_the_light_samples() {
    use ircache_render::irradiance_cache::environment::{
        held_environment, HeldEnvironment, MAX_RELATIVE_VARIANCE,
    };
    use ircache_render::irradiance_cache::params::CachedEnvironment;
    let scene = "scenes/sky-glossy/scene.xml";
    // `auto` decides by the sky's relative variance: the smooth sky goes to the radiance
    // records, the one with a sun stays with the light samples.
    for (sky, held) in [
        ("sky.exr", HeldEnvironment::Glossy),
        ("sky-sun.exr", HeldEnvironment::None),
    ] {
        let defines = vec![("sky".to_string(), sky.to_string())];
        let desc = ircache_scene::load_scene(&resolve(scene), &defines, &ObjCamera::default())
            .expect("scene loads");
        let built = Scene::build(&desc).expect("scene builds");
        let v = built.lights.environment_relative_variance();
        eprintln!("{sky}: relative variance {v:.3}");
        assert_eq!(v <= MAX_RELATIVE_VARIANCE, held == HeldEnvironment::Glossy);
        assert_eq!(held_environment(&built, CachedEnvironment::Auto), held);
    }
    // One bounce, radiance records on the glossy surfaces, 128 × 128 at 16 spp. With the smooth
    // sky in the records, the glossy lobes lose the noise of light samples that have no BSDF
    // sample to combine with (measured: 0.54 of it), at no cost in low-frequency error
    // (measured: 0.88 of it); both converge.
    let render = |sky: &str, reference: &str, environment: &str| {
        small_against_reference(
            scene,
            &[("sky", sky)],
            reference,
            2,
            3,
            16,
            "ic",
            &[
                ("radiance_cache", "on"),
                ("cached_environment", environment),
            ],
        )
    };
    let smooth = "scenes/sky-glossy/reference-d3.exr";
    let (held, held_blurred, held_lum, _) = render("sky.exr", smooth, "auto");
    let (sampled, sampled_blurred, sampled_lum, _) = render("sky.exr", smooth, "off");
    assert!((held_lum - 1.0).abs() < 0.01, "held: lum {held_lum}");
    assert!(
        (sampled_lum - 1.0).abs() < 0.01,
        "sampled: lum {sampled_lum}"
    );
    assert!(
        held < 0.7 * sampled,
        "held {held:.3e} vs sampled {sampled:.3e}"
    );
    assert!(
        held_blurred < 1.2 * sampled_blurred,
        "blurred: held {held_blurred:.3e} vs sampled {sampled_blurred:.3e}"
    );
    // With a sun, the records' few hundred rays miss it or catch it: blotches (measured: 20×
    // the low-frequency error at 256 × 256), which `auto` avoids.
    let sun = "scenes/sky-glossy/reference-sun-d3.exr";
    let (_, auto_blurred, auto_lum, _) = render("sky-sun.exr", sun, "auto");
    let (_, forced_blurred, _, _) = render("sky-sun.exr", sun, "glossy");
    assert!((auto_lum - 1.0).abs() < 0.01, "sun: lum {auto_lum}");
    assert!(
        forced_blurred > 4.0 * auto_blurred,
        "sun: held {forced_blurred:.3e} vs auto {auto_blurred:.3e}"
    );
}

/// Table 4.1's protocol (001 §4.4.2) on the Cornell box at 300 visible points: a record's
/// irradiance from a 64 × 64 plane of half-size 2 (one ray per pixel centre, as a rasteriser
/// samples it) against a 8192-cell gather, for the plane alone, the coverage division and
/// border compensation. The thesis's order holds with its proportions (measured at 1,500
/// points: 21.3 %, 13.4 %, 8.2 %; the thesis on Sibenik: 18.1 %, 10.4 %, 5.8 %).
#[test]
fn plane_estimators_keep_the_thesis_order_on_the_cornell_box() {
    use ircache_render::irradiance_cache::gather::{Gatherer, SceneRadiance, WorkState};
    use ircache_render::irradiance_cache::hemisphere::Stratification;
    use ircache_render::irradiance_cache::plane::{HemispherePlane, PlaneEstimator};
    use ircache_render::irradiance_cache::points::visible_sites;
    use ircache_render::irradiance_cache::{IcParams, IrradianceCache};
    let defines = vec![("max_depth".to_string(), "3".to_string())];
    let desc = ircache_scene::load_scene(
        &resolve("scenes/cornell-box/scene.xml"),
        &defines,
        &ObjCamera::default(),
    )
    .expect("scene loads");
    let scene = Scene::build(&desc).expect("scene builds");
    let cache = IrradianceCache::new(&scene, &IcParams::default());
    let light = SceneRadiance::path_traced(&scene);
    let g = Gatherer::new(&light, &cache, 9);
    let plane = HemispherePlane::new(64, 2.0);
    let estimators = [
        PlaneEstimator::PlaneOnly,
        PlaneEstimator::Coverage,
        PlaneEstimator::BorderCompensation,
    ];
    let mut squared = [0.0f64; 3];
    let sites = visible_sites(&scene, 300, 13);
    for (k, sp) in sites.iter().enumerate() {
        let mut st = WorkState::new(1);
        let reference = f64::from(
            g.record_with(
                &mut st,
                sp,
                0,
                k as u64,
                Stratification::from_divisions(8192),
            )
            .e
            .luminance(),
        );
        let pixels = plane.sample(&g, &mut st, sp, 0, k as u64);
        for (s, e) in squared.iter_mut().zip(estimators) {
            let x = f64::from(plane.irradiance(&pixels.radiance, e).luminance());
            *s += ((x - reference) / reference).powi(2);
        }
    }
    let [only, coverage, border] = squared.map(|s| (s / sites.len() as f64).sqrt());
    eprintln!("plane only {only:.3}, coverage {coverage:.3}, border compensation {border:.3}");
    assert!(
        border < 0.75 * coverage && coverage < 0.8 * only && border < 0.12,
        "plane only {only:.3}, coverage {coverage:.3}, border compensation {border:.3}"
    );
}

/// Mean luminance of the pixels in `x0..x1` × `y0..y1`.
fn region_luminance(
    img: &ircache_image::Image,
    (x0, x1): (usize, usize),
    (y0, y1): (usize, usize),
) -> f64 {
    let mut sum = 0.0;
    for y in y0..y1 {
        for x in x0..x1 {
            sum += f64::from(img.get(x, y).luminance());
        }
    }
    sum / ((x1 - x0) * (y1 - y0)) as f64
}

/// No pixel of the render `m` compares is NaN or infinite, and its mean luminance is within 1 %
/// of the reference's.
fn assert_no_nan_and_lum_within_1_percent(m: &ircache_image::compare::Metrics, label: &str) {
    assert_eq!(m.nonfinite_a, 0, "{label}");
    assert!(
        (m.lum_ratio - 1.0).abs() < 0.01,
        "{label}: lum {}",
        m.lum_ratio
    );
}

/// `scene` (with `defines`) rendered at 256 × 256 by `integrator` at `spp` with `seed`.
fn render_256(
    scene: &str,
    defines: &[(&str, &str)],
    integrator: &str,
    spp: u32,
    seed: u64,
) -> ircache_image::Image {
    render_at(scene, defines, integrator, 256, spp, seed)
}

/// `scene` (with `defines`) rendered at `size` × `size` by `integrator` at `spp` with `seed`.
fn render_at(
    scene: &str,
    defines: &[(&str, &str)],
    integrator: &str,
    size: usize,
    spp: u32,
    seed: u64,
) -> ircache_image::Image {
    render_with(scene, defines, (integrator, &[]), size, spp, seed)
}

/// [`render_at`] with the integrator's parameters `params` added to the scene's.
fn render_with(
    scene: &str,
    defines: &[(&str, &str)],
    (integrator, params): (&str, &[(&str, &str)]),
    size: usize,
    spp: u32,
    seed: u64,
) -> ircache_image::Image {
    let defines: Vec<(String, String)> = defines
        .iter()
        .map(|(n, v)| (n.to_string(), v.to_string()))
        .collect();
    let mut desc = ircache_scene::load_scene(&resolve(scene), &defines, &ObjCamera::default())
        .expect("scene loads");
    desc.integrator.kind = integrator.into();
    let here = ircache_scene::SourceLocation {
        file: std::sync::Arc::new(PathBuf::from("<test>")),
        line: 1,
        column: 1,
    };
    desc.integrator.extra.extend(params.iter().map(|(k, v)| {
        (
            k.to_string(),
            ircache_scene::ParamValue::String(v.to_string()),
            here.clone(),
        )
    }));
    let built = Scene::build(&desc).expect("scene builds");
    let integ = Integrator::from_desc(&desc.integrator).expect("integrator");
    let settings = RenderSettings {
        width: size,
        height: size,
        spp,
        seed,
        threads: 0,
        filter: Filter::from_desc(&desc.sensor.film.filter),
        band: None,
        sampling: ircache_render::render::Sampling::default(),
    };
    render(&built, &integ, &settings, &|_| {})
        .expect("render")
        .image
}

#[test]
fn rough_glass_matches_mitsuba() {
    // `scenes/cornell-frosted`: a rough-glass sphere (GGX α 0.2) in front of the tall box,
    // against Mitsuba 3's `roughdielectric` at 8192 spp. The whole image and, apart, a block of
    // pixels inside the sphere (what is seen through it: refraction in and out, the rough
    // interior's reflections) must agree, with the path tracer and with the cache alike.
    let scene = "scenes/cornell-frosted/scene.xml";
    let reference = "scenes/cornell-frosted/reference-d5.exr";
    let defines = [("resx", "256"), ("resy", "256")];
    let full = ircache_image::read_image(&resolve(reference)).expect("reference reads");
    // Inside the sphere's outline (centre near pixel (71, 210), radius 33).
    let inside = ((50, 92), (190, 230));
    let expected = region_luminance(&full, inside.0, inside.1);
    // Measured (three seeds each at 64 spp): the block within 1.5 % for `path`, 0.7 % for `ic`;
    // smooth glass there reads 10 % darker.
    for (integrator, spp) in [("path", 128), ("ic", 64)] {
        let image = render_256(scene, &defines, integrator, spp, 7);
        let m = compare(&image, &full).expect("same size");
        let region = region_luminance(&image, inside.0, inside.1);
        eprintln!(
            "{integrator}: relMSE_trim {:.3e}, lum {:.4}, sphere {region:.5} against {expected:.5}",
            m.rel_mse_trim, m.lum_ratio
        );
        assert_no_nan_and_lum_within_1_percent(&m, integrator);
        assert!(
            (region / expected - 1.0).abs() < 0.03,
            "{integrator}: through the sphere {region} against Mitsuba's {expected}"
        );
    }
}

#[test]
fn lens_and_orthographic_cameras_match_mitsuba() {
    // `scenes/cornell-cameras`: the Cornell box through Mitsuba 3's `thinlens` (aperture 0.25,
    // the short box in focus, the back wall ~10 px out of focus) and `orthographic` sensors,
    // against Mitsuba at 8192 spp. After a 2-px blur (the reference's and the render's pixel
    // noise fade, a wrong blur or framing stays) both must agree with the path tracer and with
    // the cache, whose records are placed through the lens's centre. A pinhole in place of the
    // lens reads 4.4e-4 blurred, a focus 0.5 off 6.3e-3.
    for camera in ["thinlens", "orthographic"] {
        let scene = format!("scenes/cornell-cameras/{camera}.xml");
        matches_mitsuba_reference(
            &scene,
            &format!("scenes/cornell-cameras/reference-{camera}.exr"),
            &[((96, 160), (96, 160))],
            6e-5,
        );
        // Splatting projects records through a pinhole: refused, not a wrong image.
        let mut desc = ircache_scene::load_scene(&resolve(&scene), &[], &ObjCamera::default())
            .expect("scene loads");
        desc.integrator.kind = "splat".into();
        let built = Scene::build(&desc).expect("scene builds");
        let integ = Integrator::from_desc(&desc.integrator).expect("integrator");
        let settings = RenderSettings {
            width: 32,
            height: 32,
            spp: 1,
            seed: 1,
            threads: 0,
            filter: Filter::Box,
            band: None,
            sampling: ircache_render::render::Sampling::default(),
        };
        let err = render(&built, &integ, &settings, &|_| {}).expect_err("splatting refuses");
        assert!(err.to_string().contains("pinhole"), "{err}");
    }
}

/// A block of pixels: its x range and y range.
type Block = ((usize, usize), (usize, usize));

/// `image` against `reference` as it is and after a 2-px Gaussian blur of both, printed under
/// `label`.
fn compare_plain_and_blurred(
    image: &ircache_image::Image,
    reference: &ircache_image::Image,
    label: &str,
) -> (
    ircache_image::compare::Metrics,
    ircache_image::compare::Metrics,
) {
    use ircache_image::blur::gaussian_blur;
    let m = compare(image, reference).expect("same size");
    let blurred =
        compare(&gaussian_blur(image, 2.0), &gaussian_blur(reference, 2.0)).expect("same size");
    eprintln!(
        "{label}: relMSE_trim {:.3e}, blurred {:.3e}, lum {:.4}",
        m.rel_mse_trim, blurred.rel_mse_trim, m.lum_ratio
    );
    (m, blurred)
}

/// Renders `scene` (256 × 256, seed 5) with `path` at 32 spp and `ic` at 16 and checks each
/// against Mitsuba's `reference`: mean luminance within 1 %, each block of `regions` (x and y
/// ranges) within 2 %, relMSE_trim after a 2-px blur below `blurred_limit`.
fn matches_mitsuba_reference(scene: &str, reference: &str, regions: &[Block], blurred_limit: f64) {
    let reference = ircache_image::read_image(&resolve(reference)).expect("reference reads");
    for (integrator, spp) in [("path", 32), ("ic", 16)] {
        let image = render_256(scene, &[], integrator, spp, 5);
        let (m, blurred) =
            compare_plain_and_blurred(&image, &reference, &format!("{scene} {integrator}"));
        assert_no_nan_and_lum_within_1_percent(&m, integrator);
        for &(xs, ys) in regions {
            let expected = region_luminance(&reference, xs, ys);
            let block = region_luminance(&image, xs, ys);
            eprintln!("  region {xs:?} × {ys:?}: {:.4}", block / expected);
            assert!(
                (block / expected - 1.0).abs() < 0.02,
                "{integrator}: region {xs:?} × {ys:?} {block} against Mitsuba's {expected}"
            );
        }
        assert!(
            blurred.rel_mse_trim < blurred_limit,
            "{integrator}: blurred relMSE_trim {:.3e}",
            blurred.rel_mse_trim
        );
    }
}

#[test]
fn blended_materials_match_mitsuba() {
    // `scenes/cornell-blend`: `blendbsdf` in its three forms (a twosided blend, a blend of two
    // twosided models, a one-sided blend) of diffuse, rough plastic and rough metals, against
    // Mitsuba 3 at 8192 spp; the path tracer and the cache (the blends' Lambertian parts from
    // records, the rest traced) alike, over the image and through the tall box's face. The
    // limit is twice the path tracer's blurred error (measured 9.5e-5; `ic` 1.7e-5).
    matches_mitsuba_reference(
        "scenes/cornell-blend/scene.xml",
        "scenes/cornell-blend/reference-d5.exr",
        &[((62, 128), (110, 230))],
        2e-4,
    );
}

#[test]
fn textured_emitters_match_mitsuba() {
    // `scenes/cornell-emission`: area emitters whose radiance is a texture (the ceiling light a
    // bilinear checkerboard, a panel on the back wall a small HDR image with nearest lookups, a
    // small sphere turned on its side with a checkerboard over its uv), against Mitsuba 3 at
    // 8192 spp (which samples such emitters through their texture; ours by area or cone, the
    // same expectation). The blocks are the panel's one bright texel as the camera sees it (a
    // texture turned or mirrored puts a texel 1/8 as bright there; uvs from the triangles'
    // barycentrics, diagonal bands) and a dim square of the sphere's checkerboard (a sphere
    // parametrised about another axis shows a bright one there); the limit is twice the path
    // tracer's blurred error (measured 2.3e-4; `ic` 1.3e-4).
    matches_mitsuba_reference(
        "scenes/cornell-emission/scene.xml",
        "scenes/cornell-emission/reference-d5.exr",
        &[((135, 142), (89, 95)), ((58, 63), (89, 95))],
        4.5e-4,
    );
}

#[test]
fn bump_and_normal_maps_match_mitsuba() {
    // `scenes/bumps`: Mitsuba 3's `bumpmap` on a turned sphere and a floor and its `normalmap`
    // on a sphere, at their defaults (Estevez et al.'s shadowing function, invalid normals
    // mirrored), under a low sun; against Mitsuba 3 at 32768 spp. Before ircache followed those
    // defaults (and the normal map's frame, (s, n × s, n) whichever way dp/dv runs, and the
    // sphere's uv) the blurred error read 7.3e-2 at 1024 spp; the blocks are the normal-mapped
    // sphere's lit side and the bumped sphere's, where those differences showed (20 % and
    // more). The cache's records carry the unperturbed normal's irradiance, turned to the
    // bumped one by the rotational gradient (003 item 5) and scaled by the share of the bumped
    // lobe that light from above the unperturbed surface reaches (`lambertian_share`); before
    // that share, and before light samples kept Mitsuba's side test, `ic` read 1.2–1.5 %
    // bright, 3.5 % on the bumped sphere, blurred 9.4e-4.
    let reference = ircache_image::read_image(&resolve("scenes/bumps/reference-d3.exr"))
        .expect("reference reads");
    // (integrator, spp, blurred limit, luminance and block tolerance): measured blurred
    // relMSE_trim 3.8e-5 and 1.2e-4, luminance 1.0027 and 1.0026, blocks within 0.8 % and
    // 1.7 %.
    for (integrator, spp, limit, tolerance) in [("path", 256, 1e-4, 0.02), ("ic", 64, 3e-4, 0.03)] {
        let image = render_at("scenes/bumps/scene.xml", &[], integrator, 128, spp, 5);
        let (m, blurred) =
            compare_plain_and_blurred(&image, &reference, &format!("bumps {integrator}"));
        assert!(
            m.nonfinite_a == 0 && (m.lum_ratio - 1.0).abs() < tolerance / 2.0,
            "{integrator}: lum {:.4}, {} non-finite",
            m.lum_ratio,
            m.nonfinite_a
        );
        assert!(
            blurred.rel_mse_trim < limit,
            "{integrator}: blurred relMSE_trim {:.3e}",
            blurred.rel_mse_trim
        );
        for (xs, ys) in [((78, 100), (38, 62)), ((22, 44), (38, 62))] {
            let (got, want) = (
                region_luminance(&image, xs, ys),
                region_luminance(&reference, xs, ys),
            );
            eprintln!("  region {xs:?} × {ys:?}: {:.4}", got / want);
            assert!(
                (got / want - 1.0).abs() < tolerance,
                "{integrator}: region {xs:?} × {ys:?} {got} against Mitsuba's {want}"
            );
        }
    }
}

#[test]
fn principled_materials_match_mitsuba() {
    // `scenes/cornell-principled`: Mitsuba's `principled` with every reflection term (a
    // clear-coated, sheened, partly metallic tall box with flatness and spec_tint), as rough
    // glass (the short box, spec_trans 0.8), and clear-coated (the floor), against Mitsuba 3 at
    // 8192 spp; the cache serves the diffuse term's Lambertian part. The limit is twice the
    // path tracer's blurred error (measured 1.6e-4; `ic` 5.4e-5).
    matches_mitsuba_reference(
        "scenes/cornell-principled/scene.xml",
        "scenes/cornell-principled/reference-d5.exr",
        &[((62, 128), (110, 230))],
        3.2e-4,
    );
}

#[test]
fn principled_materials_with_radiance_records_match_mitsuba() {
    // The same scene with radiance caching on: the floor's clear coat and rough base
    // (α 0.36) and the tall box are radiance-cached. Near the walls a record's high-order
    // coefficients had gradients many times their size, and extrapolated over its reach they
    // drew bright streaks on the floor (measured without the gradient limit: blurred
    // relMSE_trim 0.41, mean luminance +7.6 %; with it 8.3e-5 and +0.06 %). Same limit as above.
    let reference =
        ircache_image::read_image(&resolve("scenes/cornell-principled/reference-d5.exr"))
            .expect("reference reads");
    let image = render_with(
        "scenes/cornell-principled/scene.xml",
        &[],
        ("ic", &[("radiance_cache", "on")]),
        256,
        16,
        5,
    );
    let (m, blurred) = compare_plain_and_blurred(&image, &reference, "radiance records");
    assert_no_nan_and_lum_within_1_percent(&m, "ic, radiance cache on");
    assert!(
        m.rel_mse < 0.05 && blurred.rel_mse_trim < 3.2e-4,
        "relMSE {:.3e}, blurred relMSE_trim {:.3e}",
        m.rel_mse,
        blurred.rel_mse_trim
    );
}

#[test]
fn negative_lobed_filters_match_mitsuba() {
    // `scenes/cornell-cameras/filters.xml` (64 × 64, where the filter shows) with Mitsuba's
    // `mitchell` and `lanczos` against its own renders (16384 spp): the path tracer's signed
    // filter weights (`film`) must reproduce them far better than a box filter does (measured
    // at 1024 spp: 1.7e-4 and 0.6–1.0e-3; a box filter reads 8.6e-3 and 1.2e-2).
    for (filter, limit) in [("mitchell", 1e-3), ("lanczos", 3e-3)] {
        let reference = ircache_image::read_image(&resolve(&format!(
            "scenes/cornell-cameras/reference-{filter}.exr"
        )))
        .expect("reference reads");
        let image = render_at(
            "scenes/cornell-cameras/filters.xml",
            &[("rfilter", filter)],
            "path",
            64,
            1024,
            1,
        );
        let m = compare(&image, &reference).expect("same size");
        eprintln!(
            "{filter}: relMSE_trim {:.3e}, lum {:.4}",
            m.rel_mse_trim, m.lum_ratio
        );
        assert_no_nan_and_lum_within_1_percent(&m, filter);
        assert!(
            m.rel_mse_trim < limit,
            "{filter}: relMSE_trim {:.3e}",
            m.rel_mse_trim
        );
    }
}

#[test]
fn two_small_lamps_in_sponza_match_mitsuba() {
    // `scenes/sponza-lamps`, the stand-in for issue 9's kept-back cathedral: Sponza lit only by
    // two small spherical lamps in view, against Mitsuba 3 at 8448 spp (320 × 240, d3). The
    // cache at its defaults (16 spp) measured relMSE_trim 7.1e-5, blurred 5.7e-6 to 1.3e-5
    // over four seeds (the lamps' anti-aliasing carries most of the blurred error), lum within
    // 0.5 %; the path tracer at 32 spp 3.1e-4, blurred 7.3e-6. The limits are about twice those.
    let meshes = shared().join("scenes/sponza-sun/meshes");
    let defines = vec![("meshes".to_string(), meshes.display().to_string())];
    let desc = ircache_scene::load_scene(
        &resolve("scenes/sponza-lamps/scene.xml"),
        &defines,
        &ObjCamera::default(),
    )
    .expect("scene loads");
    let reference = ircache_image::read_image(&resolve("scenes/sponza-lamps/reference-d3.exr"))
        .expect("reference reads");
    for (integrator, spp, limit, blurred_limit) in
        [("ic", 16, 1.5e-4, 3e-5), ("path", 32, 6.5e-4, 3e-5)]
    {
        let mut desc = desc.clone();
        desc.integrator.kind = integrator.into();
        let built = Scene::build(&desc).expect("scene builds");
        let integ = Integrator::from_desc(&desc.integrator).expect("integrator");
        let settings = RenderSettings {
            width: 320,
            height: 240,
            spp,
            seed: 5,
            threads: 0,
            filter: Filter::from_desc(&desc.sensor.film.filter),
            band: None,
            sampling: ircache_render::render::Sampling::default(),
        };
        let image = render(&built, &integ, &settings, &|_| {})
            .expect("render")
            .image;
        let (m, blurred) =
            compare_plain_and_blurred(&image, &reference, &format!("sponza-lamps {integrator}"));
        assert_no_nan_and_lum_within_1_percent(&m, integrator);
        assert!(
            m.rel_mse_trim < limit,
            "{integrator}: relMSE_trim {:.3e}",
            m.rel_mse_trim
        );
        assert!(
            blurred.rel_mse_trim < blurred_limit,
            "{integrator}: blurred relMSE_trim {:.3e}",
            blurred.rel_mse_trim
        );
    }
}
