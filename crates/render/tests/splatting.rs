//! Radiance cache splatting (001 ch. 4, NOTES-001 §C.9) against the lookup it replaces, on the
//! repository's moderately glossy Cornell box with radiance caching on (irradiance and radiance
//! records, occluders, corners):
//! - C-T1: at every sample, splatting gives the lookup's irradiance and glossy radiance to
//!   float rounding, and calls a sample uncovered exactly where the spatial index does;
//! - C-T2: splatting the records in another order changes nothing beyond rounding, and the
//!   render is the same bit for bit on one thread and two;
//! - C-T3: from an empty cache, the miss search leaves no sample uncovered, and a budget caps
//!   the records it adds.

mod common;
use common::*;
use ircache_render::integrators::Integrator;
use ircache_render::irradiance_cache::IrradianceCache;
use ircache_render::radiance_cache::lookup;
use ircache_render::render::RenderSettings;
use ircache_render::scene::Scene;
use ircache_render::splatting::buffer::{splat, CpuSplatter};
use ircache_render::splatting::{fill_misses, GBuffer, SplatBuffer};
use ircache_scene::SceneDesc;

fn cornell_rough(kind: &str, size: u32, spp: u32) -> SceneDesc {
    let path = ircache_testing::project_scenes().join("cornell-rough/scene.xml");
    let mut desc = ircache_scene::load_scene(
        &path,
        &[("max_depth".into(), "3".into())],
        &ircache_scene::obj_scene::ObjCamera::default(),
    )
    .expect("cornell-rough loads");
    desc.integrator.kind = kind.into();
    desc.integrator.extra.push((
        "radiance_cache".into(),
        ircache_scene::ParamValue::String("on".into()),
        here(),
    ));
    desc.sensor.film.width = size;
    desc.sensor.film.height = size;
    desc.sensor.spp = spp;
    desc
}

fn settings(desc: &SceneDesc, threads: usize) -> RenderSettings {
    RenderSettings::from_desc(desc, 5, threads).expect("sampler")
}

/// The scene and its cache filled by the `ic` pre-pass.
fn prepared(desc: &SceneDesc, s: &RenderSettings) -> (Scene, IrradianceCache) {
    let scene = Scene::build(desc).expect("scene builds");
    let integrator = Integrator::from_desc(&desc.integrator).expect("integrator");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("pool");
    let (ready, _) = integrator.prepare(&scene, s, &pool).expect("pre-pass");
    let Integrator::Ic(ic) = ready else {
        panic!("not the cache's integrator")
    };
    let cache = (*ic.cache.expect("filled")).clone();
    (scene, cache)
}

fn close(a: ircache_math::Rgb, b: ircache_math::Rgb, rel: f32) -> bool {
    let scale = a.max_channel().max(b.max_channel()).max(1e-30);
    let d = a - b;
    d.r.abs().max(d.g.abs()).max(d.b.abs()) <= rel * scale
}

#[test]
fn splatting_equals_the_lookup_at_every_sample() {
    equal_at_every_sample("tabellion", 48, 2000, 300);
}

/// The same under the other error metrics: any metric with a distance bound splats.
#[test]
fn splatting_equals_the_lookup_under_ward_and_hessian_metrics() {
    equal_at_every_sample("ward", 32, 800, 100);
    equal_at_every_sample("hessian", 32, 800, 100);
}

fn equal_at_every_sample(metric: &str, size: u32, min_irradiance: usize, min_glossy: usize) {
    let mut desc = cornell_rough("splat", size, 2);
    desc.integrator.extra.push((
        "error_metric".into(),
        ircache_scene::ParamValue::String(metric.into()),
        here(),
    ));
    let s = settings(&desc, 2);
    let (scene, cache) = prepared(&desc, &s);
    let samplers = s.sampler();
    let store = &cache.levels[0];
    let (mut irradiance, mut glossy, mut uncovered) = (0, 0, 0);
    for layer in 0..2 {
        let g = GBuffer::build(&scene, &cache, &s, &samplers, layer);
        let mut buffer = SplatBuffer::new(&g);
        splat(
            &mut buffer,
            &g,
            &cache,
            0..store.len(),
            &scene.camera,
            s.filter.radius(),
        );
        // The same records in two pieces, the later half first.
        let mut halves = SplatBuffer::new(&g);
        let half = store.len() / 2;
        splat(
            &mut halves,
            &g,
            &cache,
            half..store.len(),
            &scene.camera,
            s.filter.radius(),
        );
        splat(
            &mut halves,
            &g,
            &cache,
            0..half,
            &scene.camera,
            s.filter.radius(),
        );
        for ((sample, px), other) in g.samples.iter().zip(&buffer.pixels).zip(&halves.pixels) {
            let Some(sp) = &sample.point else {
                assert_eq!(px.count, 0, "a splat reached a sample no record may serve");
                continue;
            };
            assert_eq!(px.count, other.count);
            let looked_up = store
                .interpolate(sp.it.p, sp.n, sp.n_bump, 1.0, cache.params.gradients)
                .map(|i| i.e);
            match (px.irradiance(), looked_up) {
                (Some(a), Some(b)) => {
                    assert!(close(a, b, 1e-5), "splat {a:?}, lookup {b:?}");
                    assert!(close(a, other.irradiance().expect("same records"), 1e-5));
                    irradiance += 1;
                }
                (None, None) => {}
                (a, b) => panic!("splat {a:?}, lookup {b:?} at {:?}", sp.it.p),
            }
            let threshold = cache.coverage_threshold(sp);
            let covered = store.covers_within(sp.it.p, sp.n, threshold);
            assert_eq!(covered, px.min_error <= threshold, "coverage differs");
            uncovered += usize::from(!covered);
            if let Some(a) = px.glossy() {
                let b = lookup::glossy(&cache, sp, 0, -sample.ray.d)
                    .expect("the lookup serves where a splat did");
                assert!(close(a, b, 1e-4), "glossy splat {a:?}, lookup {b:?}");
                glossy += 1;
            }
        }
    }
    // Enough of each kind that the comparison means something.
    assert!(
        irradiance > min_irradiance,
        "{metric}: {irradiance} irradiance comparisons"
    );
    assert!(glossy > min_glossy, "{metric}: {glossy} glossy comparisons");
    eprintln!("{metric}: {irradiance} irradiance, {glossy} glossy, {uncovered} uncovered samples");
}

#[test]
fn the_miss_search_covers_every_sample_and_keeps_its_budget() {
    let desc = cornell_rough("splat", 40, 1);
    let s = settings(&desc, 2);
    let (scene, filled) = prepared(&desc, &s);
    // Algorithm 4's first frame: the tables, no records.
    let mut empty = filled.clone();
    for level in &mut empty.levels {
        *level = filled.empty_store();
    }
    empty.radiance_records.clear();
    let samplers = s.sampler();
    let g = GBuffer::build(&scene, &empty, &s, &samplers, 0);
    let sites = g.samples.iter().filter(|x| x.point.is_some()).count();
    assert!(sites > 1000);

    let mut budgeted = empty.clone();
    let mut buffer = SplatBuffer::new(&g);
    let mut stats = Default::default();
    let added = fill_misses(
        &scene,
        &mut budgeted,
        &g,
        &mut buffer,
        &CpuSplatter,
        3,
        7,
        s.filter.radius(),
        &mut stats,
    );
    assert!(
        (1..=7).contains(&added),
        "{added} records under a budget of 7"
    );

    let mut full = empty.clone();
    let mut buffer = SplatBuffer::new(&g);
    let added = fill_misses(
        &scene,
        &mut full,
        &g,
        &mut buffer,
        &CpuSplatter,
        3,
        usize::MAX,
        s.filter.radius(),
        &mut stats,
    );
    assert!(added > 20);
    for (sample, px) in g.samples.iter().zip(&buffer.pixels) {
        if let Some(sp) = &sample.point {
            assert!(
                px.min_error <= full.coverage_threshold(sp),
                "a sample left uncovered at {:?}",
                sp.it.p
            );
        }
    }
    // Splatting the final cache from scratch gives what the incremental splats summed.
    let mut again = SplatBuffer::new(&g);
    splat(
        &mut again,
        &g,
        &full,
        0..full.levels[0].len(),
        &scene.camera,
        s.filter.radius(),
    );
    for (a, b) in again.pixels.iter().zip(&buffer.pixels) {
        assert_eq!(a.count, b.count);
        if let (Some(x), Some(y)) = (a.irradiance(), b.irradiance()) {
            assert!(close(x, y, 1e-5));
        }
    }
}

#[test]
fn a_splatted_render_is_the_same_on_one_thread_and_two_and_matches_ic() {
    let desc = cornell_rough("splat", 32, 2);
    let one = render_desc(&desc, 1, 9);
    let two = render_desc(&desc, 2, 9);
    assert_eq!(one.image.pixels, two.image.pixels);
    assert!(one.image.pixels.iter().all(|p| p.is_valid_radiance()));
    let splat = one
        .cache
        .as_ref()
        .and_then(|c| c.splat.clone())
        .expect("splat stats");
    assert_eq!(splat.layers, 2);
    // The lookup's image: the same but where splatting filled misses with records.
    let ic = render_desc(&cornell_rough("ic", 32, 2), 2, 9);
    let m = ircache_image::compare::compare(&one.image, &ic.image).expect("same size");
    assert!(
        m.rel_mse < 1e-3 && (m.lum_ratio - 1.0).abs() < 0.005,
        "{m:?}"
    );
}

/// The walkthrough (NOTES-001 §C.7): each frame adds at most its budget of records; frames fill
/// every hole; a finer accuracy opens holes that later frames fill, a coarser one opens none;
/// the running mean converges to the image `splat` renders of the same view.
#[test]
fn the_walkthrough_fills_its_holes_within_budget_and_converges() {
    use ircache_render::integrators::RayCounts;
    use ircache_render::splatting::walkthrough::Walkthrough;
    let desc = cornell_rough("splat", 32, 64);
    let scene = Scene::build(&desc).expect("scene builds");
    let Integrator::Ic(ic) = Integrator::from_desc(&desc.integrator).expect("integrator") else {
        panic!("not the cache's integrator")
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("pool");
    let mut walk = pool
        .install(|| Walkthrough::new(scene, &ic, 32, 32, 3, &pool))
        .expect("walkthrough");
    walk.budget = 40;
    let mut rays = RayCounts::default();
    let mut frames = Vec::new();
    for _ in 0..64 {
        frames.push(pool.install(|| walk.frame(&mut rays)));
    }
    assert!(frames.iter().all(|f| f.new_records <= 40));
    assert_eq!(
        frames[0].new_records, 40,
        "the first frame spends its budget"
    );
    let last = frames.last().expect("frames");
    assert_eq!(last.uncovered, 0, "holes left after 64 frames");
    assert_eq!(last.layers, 64);

    // Coarser: no new records; finer: holes, filled again by later frames.
    walk.set_accuracy(0.7).expect("accuracy");
    let coarser = pool.install(|| walk.frame(&mut rays));
    assert_eq!(
        (coarser.layers, coarser.new_records, coarser.uncovered),
        (1, 0, 0)
    );
    walk.set_accuracy(0.15).expect("accuracy");
    assert!(walk.set_accuracy(1.5).is_err() && walk.set_accuracy(f32::NAN).is_err());
    let finer = pool.install(|| walk.frame(&mut rays));
    assert!(finer.new_records > 0);
    let mut report = finer;
    for _ in 0..200 {
        if report.uncovered == 0 {
            break;
        }
        report = pool.install(|| walk.frame(&mut rays));
    }
    assert_eq!(
        report.uncovered, 0,
        "the finer accuracy's holes were never filled"
    );

    // Converged against the splat integrator's own render at the same view and accuracy.
    walk.set_accuracy(ic.params.accuracy).expect("accuracy");
    for _ in 0..64 {
        pool.install(|| walk.frame(&mut rays));
    }
    let mean = walk.image(false);
    assert!(mean.pixels.iter().all(|p| p.is_valid_radiance()));
    let rendered = render_desc(&desc, 2, 3);
    let m = ircache_image::compare::compare(&mean, &rendered.image).expect("same size");
    assert!((m.lum_ratio - 1.0).abs() < 0.02, "{m:?}");
}
