//! Animations with a cache kept over time (001 ch. 5, 000 §3.7.3) on the repository's "Cube in a
//! Box" (`scenes/cube-in-box`), at small sizes:
//! - a still box: the temporal cache's flicker index is at most a tenth of a new cache per frame's
//!   (issue 13's target); its records live on without estimates, and where the cache is told
//!   something moves, each record's estimate of the next frame, gathered with the same random
//!   numbers, equals it, so records live the longest life;
//! - the moving cube: records on the cube stay on its faces as it moves and turns; interpolated
//!   temporal gradients run each record exactly into its successor's value; the temporal cache
//!   gathers at most 0.3× the records of a new cache per frame.

use ircache_image::flicker::flicker_index;
use ircache_image::Image;
use ircache_math::{Mat4, Vec3};
use ircache_render::integrators::Integrator;
use ircache_render::render::{render, RenderSettings};
use ircache_render::scene::Scene;
use ircache_render::temporal::record::SlopeKind;
use ircache_render::temporal::{
    CacheMode, FrameStats, Motion, NextFrame, SequenceCache, TemporalParams,
};
use ircache_scene::animation::{load_animation, Animation};
use ircache_scene::SceneDesc;

fn load(file: &str, size: u32, spp: u32) -> (SceneDesc, Animation) {
    let path = ircache_testing::project_scenes()
        .join("cube-in-box")
        .join(file);
    let (mut desc, anim) = load_animation(&path, &[]).expect("loads");
    desc.sensor.film.width = size;
    desc.sensor.film.height = size;
    desc.sensor.spp = spp;
    (desc, anim)
}

fn settings(desc: &SceneDesc) -> RenderSettings {
    RenderSettings::from_desc(desc, 3, 0).expect("sampler")
}

/// Fills (and with `images`, renders) `frames` frames; returns the cache, the frames and the
/// fill figures.
fn run(
    desc: &SceneDesc,
    anim: &Animation,
    params: TemporalParams,
    frames: u32,
    images: bool,
) -> (SequenceCache, Vec<Image>, Vec<FrameStats>) {
    run_with(desc, anim, anim, params, frames, images)
}

/// [`run`] with the cache told of `motion` instead of `anim`'s.
fn run_with(
    desc: &SceneDesc,
    anim: &Animation,
    motion: &dyn Motion,
    params: TemporalParams,
    frames: u32,
    images: bool,
) -> (SequenceCache, Vec<Image>, Vec<FrameStats>) {
    let s = settings(desc);
    let Integrator::Ic(ic) = Integrator::from_desc(&desc.integrator).expect("ic") else {
        panic!("the scene's integrator is the cache");
    };
    let pool = rayon::ThreadPoolBuilder::new().build().expect("pool");
    let mut cache = SequenceCache::new(&ic, params, (s.width, s.height), s.seed).expect("cache");
    let scene_at = |f: u32| Scene::build(&anim.scene_at(desc, f as f32)).expect("scene");
    let mut stats = Vec::new();
    let mut next = Some(scene_at(0));
    for f in 0..frames {
        let scene = next.take().expect("scene");
        next = (f + 1 < frames).then(|| scene_at(f + 1));
        stats.push(
            cache
                .fill_frame(f, &scene, next.as_ref(), motion, &pool)
                .expect("fills"),
        );
    }
    let mut out = Vec::new();
    if images {
        for f in 0..frames {
            let scene = scene_at(f);
            let mut ic = ic.clone();
            ic.seed = s.seed;
            ic.cache = Some(std::sync::Arc::new(
                cache.cache_at(f, &scene, motion, &pool).expect("cache"),
            ));
            out.push(
                render(&scene, &Integrator::Ic(ic), &s, &|_| {})
                    .expect("renders")
                    .image,
            );
        }
    }
    (cache, out, stats)
}

/// Motion that says shape 0 moves, and moves nothing: the temporal cache then estimates its
/// records' next frames, as wherever something moves, in a scene whose light does not change.
struct SaidToMove;

impl Motion for SaidToMove {
    fn motion(&self, _: u32, _: u32, _: u32) -> Option<Mat4> {
        None
    }
    fn moving_shapes(&self) -> Vec<u32> {
        vec![0]
    }
}

fn params(mode: CacheMode) -> TemporalParams {
    TemporalParams {
        mode,
        ..TemporalParams::default()
    }
}

#[test]
fn still_box_temporal_cache_flickers_a_tenth_of_a_cache_per_frame() {
    let (desc, anim) = load("still.xml", 48, 2);
    let frames = anim.frames;
    assert_eq!(frames, 30);
    let (_, temporal, _) = run(&desc, &anim, params(CacheMode::Temporal), frames, true);
    let (_, per_frame, _) = run(&desc, &anim, params(CacheMode::PerFrame), frames, true);
    let (t, p) = (
        flicker_index(&temporal).unwrap(),
        flicker_index(&per_frame).unwrap(),
    );
    eprintln!("flicker index: temporal {t:.3e}, per frame {p:.3e}");
    assert!(p > 1e-4, "a cache per frame flickers ({p})");
    assert!(t <= 0.1 * p, "temporal {t} against per frame {p}");
}

/// `scenes/{scene}/scene.xml` with the shape `shape` sliding by `translate` ("x y z") over
/// `frames` frames, from an animation file written to a temporary folder (removed once read;
/// its path returned), with `overrides` and the cache as its integrator.
fn sliding(
    scene: &str,
    shape: &str,
    translate: &str,
    frames: u32,
    overrides: &[(String, String)],
) -> (SceneDesc, Animation, std::path::PathBuf) {
    let scene = ircache_testing::project_scenes()
        .join(scene)
        .join("scene.xml");
    let scene = scene.display();
    let dir = ircache_testing::ScratchDir::new(&format!("temporal-{shape}"));
    let path = dir.join("animation.xml");
    std::fs::write(
        &path,
        format!(
            "<animation version=\"1\" scene=\"{scene}\" frames=\"{frames}\">\n\
             <move shape=\"{shape}\"><key frame=\"0\"/><key frame=\"{}\" translate=\"{translate}\"/></move>\n\
             </animation>\n",
            frames - 1
        ),
    )
    .unwrap();
    let loaded = load_animation(&path, overrides);
    drop(dir);
    let (mut desc, anim) = loaded.expect("loads");
    desc.integrator.kind = "irrcache".into();
    (desc, anim, path)
}

/// Records at deeper levels serve pixels past delta vertices (through cornell-glass's sphere,
/// here moving): at their end those that served a pixel centre are renewed at their place and
/// the others dropped, as at the first level (counted as used whatever they served, they were
/// renewed without end).
#[test]
fn deeper_levels_records_end_as_they_serve() {
    let (mut desc, anim, _) = sliding("cornell-glass", "GlassSphere", "0.3 0 0", 8, &[]);
    desc.sensor.film.width = 24;
    desc.sensor.film.height = 24;
    desc.sensor.spp = 1;
    let p = TemporalParams {
        max_lifespan: 2,
        ..params(CacheMode::Temporal)
    };
    let (cache, _, _) = run(&desc, &anim, p, 8, false);
    let deeper_ended = || {
        cache
            .records
            .iter()
            .filter(|r| r.record.level > 0 && r.last < 7)
    };
    let renewed = deeper_ended().filter(|r| r.successor.is_some()).count();
    let dropped = deeper_ended().filter(|r| r.successor.is_none()).count();
    assert!(
        renewed > 0 && dropped > 0,
        "deeper records renewed {renewed}, dropped {dropped}"
    );
}

#[test]
fn still_box_records_live_the_longest_life() {
    let (desc, still) = load("still.xml", 32, 1);
    // Where nothing moves, records live on without estimates (their light is the same in
    // every frame); a renewal would only draw their noise again.
    let (cache, _, stats) = run(&desc, &still, params(CacheMode::Temporal), 12, false);
    assert!(cache.records.len() > 50);
    assert!(cache.records.iter().all(|r| r.last == u32::MAX));
    assert!(
        cache.records.iter().all(|r| r.born == 0),
        "a record renewed"
    );
    assert_eq!(stats.iter().map(|s| s.estimates).sum::<usize>(), 0);
    // Told that something moves, the cache estimates their next frames.
    for next_frame in [NextFrame::Regather, NextFrame::Reproject] {
        let p = TemporalParams {
            next_frame,
            ..params(CacheMode::Temporal)
        };
        let (cache, _, stats) = run_with(&desc, &still, &SaidToMove, p, 12, false);
        // Frames 0..10 made records whose next frame is known; the same random numbers in the
        // same scene give the same value (gathered again, or reprojected: nothing moved), so
        // no change and the longest life (δt_max − 1 after their own frame), and a successor
        // at frame 10 for those that served a pixel.
        let made: Vec<_> = cache.records.iter().filter(|r| r.born < 11).collect();
        assert!(made.len() > 50);
        for r in &made {
            assert_eq!(
                r.last - r.born,
                p.max_lifespan - 1,
                "born {} ({next_frame:?})",
                r.born
            );
        }
        assert!(cache.records.iter().any(|r| r.born == p.max_lifespan));
        let estimated: usize = stats.iter().map(|s| s.estimates).sum();
        assert_eq!(
            estimated,
            cache.records.iter().filter(|r| r.born < 11).count()
        );
    }
}

#[test]
fn records_on_the_cube_stay_on_its_faces_and_slopes_reach_the_successors() {
    let (desc, anim) = load("animation.xml", 48, 1);
    let cube = desc
        .shapes
        .iter()
        .position(|s| s.id.as_deref() == Some("Cube"))
        .unwrap() as u32;
    let (cache, _, _) = run(&desc, &anim, params(CacheMode::Temporal), 16, false);
    let on_cube: Vec<usize> = (0..cache.records.len())
        .filter(|&i| cache.records[i].site.point.it.shape == cube)
        .collect();
    assert!(on_cube.len() > 10, "{} records on the cube", on_cube.len());
    // The cube at frame f, from the animation's keys written out: centre (−0.55 + 1.1 f/47,
    // 0.25, 0.2), turned by 90° f/47 about +y, half-side 0.25.
    let pose = |f: u32| {
        let s = f as f32 / 47.0;
        (
            Vec3::new(-0.55 + 1.1 * s, 0.25, 0.2),
            (90.0 * s).to_radians(),
        )
    };
    let pool = rayon::ThreadPoolBuilder::new().build().unwrap();
    for f in [3u32, 9, 15] {
        let scene = Scene::build(&anim.scene_at(&desc, f as f32)).unwrap();
        let c = cache.cache_at(f, &scene, &anim, &pool).unwrap();
        let (centre, angle) = pose(f);
        let mut checked = 0;
        for r in c.levels[0].records() {
            let local = r.p - centre;
            // Undo the turn about +y.
            let (sin, cos) = (-angle).sin_cos();
            let local = Vec3::new(
                cos * local.x + sin * local.z,
                local.y,
                -sin * local.x + cos * local.z,
            );
            // Not on the cube: beyond its box, or on the floor it rests on (y = 0, where its
            // bottom face, which takes no records, lies).
            if local.abs().max_element() > 0.3 || r.p.y.abs() < 1e-3 {
                continue;
            }
            assert!(
                (local.abs().max_element() - 0.25).abs() < 1e-3,
                "frame {f}: a record {local} off the cube's faces"
            );
            checked += 1;
        }
        assert!(checked > 5, "frame {f}: {checked} records on the cube");
    }
    // 5.15–5.17: a renewed record's slope runs to its successor's value at the successor's
    // frame (both moved to that frame, for records on the cube).
    let mut linked = 0;
    for (i, r) in cache.records.iter().enumerate() {
        let Some(l) = r.successor else { continue };
        let l = &cache.records[l as usize];
        assert_eq!(r.kind, SlopeKind::Interpolated);
        use ircache_render::temporal::Motion;
        let m = anim.motion(r.site.point.it.shape, r.born, l.born);
        let reached = r.at(l.born, m.as_ref());
        let tol = 1e-4 * l.record.e.max_channel().max(1e-3);
        assert!(
            (reached.e - l.record.e).max_channel().abs() < tol
                && (l.record.e - reached.e).max_channel().abs() < tol,
            "record {i}: {:?} against its successor's {:?}",
            reached.e,
            l.record.e
        );
        assert!((reached.p - l.record.p).length() < 1e-4);
        linked += 1;
    }
    assert!(linked > 10, "{linked} renewed records");
}

#[test]
fn moving_cube_temporal_cache_gathers_under_a_third_of_a_cache_per_frame() {
    let (desc, anim) = load("animation.xml", 48, 1);
    let frames = 24;
    let (_, _, temporal) = run(&desc, &anim, params(CacheMode::Temporal), frames, false);
    let (_, _, per_frame) = run(&desc, &anim, params(CacheMode::PerFrame), frames, false);
    let records = |s: &[FrameStats]| s.iter().map(|f| f.renewed + f.new).sum::<usize>();
    let gathers = |s: &[FrameStats]| s.iter().map(FrameStats::gathers).sum::<usize>();
    let (t, p) = (records(&temporal), records(&per_frame));
    eprintln!(
        "records: temporal {t} (+{} next-frame estimates), per frame {p}",
        gathers(&temporal) - t
    );
    assert!(t as f64 <= 0.3 * p as f64, "{t} against {p}");
    // With the estimates, every hemisphere gathered still stays below the per-frame cache's.
    assert!(gathers(&temporal) < p);
}

/// `scenes/cornell-rough` (rough metal, rough plastics) with radiance caching on, its short box
/// sliding 0.1 over `frames` frames.
fn rough_with_radiance(frames: u32) -> (SceneDesc, Animation) {
    let (mut desc, anim, path) = sliding(
        "cornell-rough",
        "ShortBox",
        "0.1 0 0",
        frames,
        &[("max_depth".into(), "3".into())],
    );
    desc.integrator.extra.push((
        "radiance_cache".into(),
        ircache_scene::ParamValue::String("on".into()),
        ircache_scene::SourceLocation {
            file: std::sync::Arc::new(path),
            line: 1,
            column: 1,
        },
    ));
    desc.sensor.film.width = 32;
    desc.sensor.film.height = 32;
    desc.sensor.spp = 1;
    (desc, anim)
}

#[test]
fn radiance_records_keep_their_coefficients_over_time_and_renew_on_moving_shapes() {
    let (desc, anim) = rough_with_radiance(6);
    let short_box = desc
        .shapes
        .iter()
        .position(|s| s.id.as_deref() == Some("ShortBox"))
        .unwrap() as u32;
    let p = params(CacheMode::Temporal);
    // Still (told that something moves, so that estimates are made): the coefficients'
    // estimate of the next frame equals them, so radiance records live the longest life too.
    let (still, _, _) = run_with(&desc, &Animation::default(), &SaidToMove, p, 12, false);
    let with = |c: &SequenceCache| {
        (0..c.records.len())
            .filter(|&i| c.radiance[i].is_some())
            .count()
    };
    assert!(with(&still) > 10, "{} radiance records", with(&still));
    for (r, c) in still.records.iter().zip(&still.radiance) {
        if c.is_some() && r.born < 11 {
            assert_eq!(r.last - r.born, p.max_lifespan - 1);
        }
    }
    // Records on the rough-aluminium back wall hold radiance alone (no Lambertian part): they
    // serve pixels too, so they are renewed at their place when they expire, not dropped.
    let back_wall = desc
        .shapes
        .iter()
        .position(|s| s.id.as_deref() == Some("BackWall"))
        .unwrap() as u32;
    let renewed_on_wall = still
        .records
        .iter()
        .zip(&still.radiance)
        .filter(|(r, c)| c.is_some() && r.site.point.it.shape == back_wall && r.born == 0)
        .filter(|(r, _)| r.successor.is_some())
        .count();
    assert!(renewed_on_wall > 0, "no back-wall record renewed");
    // Moving: records on the sliding box that hold radiance live one frame; the frames' caches
    // point every record at its own coefficients; the images are finite.
    let (moving, images, _) = run(&desc, &anim, p, 6, true);
    let mut on_box = 0;
    for (r, c) in moving.records.iter().zip(&moving.radiance) {
        if c.is_some() && r.site.point.it.shape == short_box {
            assert_eq!(
                r.last, r.born,
                "a radiance record on the moving box lived on"
            );
            on_box += 1;
        }
    }
    assert!(on_box > 0);
    let pool = rayon::ThreadPoolBuilder::new().build().unwrap();
    let scene = Scene::build(&anim.scene_at(&desc, 4.0)).unwrap();
    let c = moving.cache_at(4, &scene, &anim, &pool).unwrap();
    let held = c.levels[0]
        .records()
        .iter()
        .filter(|r| r.radiance != ircache_render::irradiance_cache::record::NO_RADIANCE)
        .count();
    assert_eq!(held, c.radiance_records.len());
    assert!(held > 10);
    for img in &images {
        assert!(img.pixels.iter().all(|p| p.is_finite()));
    }
}

/// The pixels the reuse test calls still between two frames of the moving cube
/// (`temporal::pixel_reuse`) render the same direct light in both frames, bit for bit (the
/// `direct` integrator with the same seed: emission, light samples and BSDF samples, rendered
/// on its own), at the start, the middle and the end of the move; what changed lies among the
/// others. The cube's pixels and its shadow's are not still; most of the room is.
#[test]
fn still_pixels_render_the_same_direct_light_in_both_frames() {
    use ircache_render::temporal::pixel_reuse::{still_pixels, Change};
    let (mut desc, anim) = load("animation.xml", 48, 4);
    desc.integrator.kind = "direct".into();
    let s = settings(&desc);
    let integrator = Integrator::from_desc(&desc.integrator).expect("direct");
    let frame = |f: u32| {
        let scene = Scene::build(&anim.scene_at(&desc, f as f32)).expect("scene");
        let image = render(&scene, &integrator, &s, &|_| {})
            .expect("renders")
            .image;
        (scene, image)
    };
    for f in [0, 23, 46] {
        let (_, before) = frame(f);
        let (scene, after) = frame(f + 1);
        let change = Change::between(&anim, &desc, f as f32, (f + 1) as f32);
        let still = still_pixels(&scene, &change, (s.width, s.height), s.filter.radius());
        let (mut kept, mut changed) = (0, 0);
        for (i, &st) in still.iter().enumerate() {
            let (x, y) = (i % s.width, i / s.width);
            let same = before.get(x, y) == after.get(x, y);
            changed += usize::from(!same);
            if st {
                kept += 1;
                assert!(same, "frame {f}: pixel ({x}, {y}) called still changed");
            }
        }
        let share = kept as f64 / still.len() as f64;
        assert!(changed > 20, "frame {f}: {changed} pixels changed");
        assert!((0.6..0.98).contains(&share), "frame {f}: {share} kept");
        // Nothing moves between two equal poses past the last key.
        let change = Change::between(&anim, &desc, 47.0, 48.0);
        assert!(change.is_none());
    }
}

/// A still run's later frames take one light sample at each pixel sample's first vertex, where
/// a pixel of its own takes `direct_samples` (4): the run's many pixel samples stratify the
/// light already (BENCHMARKS.md, thirty-first session); under adaptive sampling they keep
/// all four. Counted by the pixel pass's shadow rays on the still box (every first vertex
/// diffuse and served by the cache, so no deeper vertex samples the light), and the two
/// renders agree in the mean.
#[test]
fn a_still_runs_later_frames_take_one_light_sample_a_pixel_sample() {
    use ircache_render::render::{render_runs, Adaptive};
    let (desc, anim) = load("still.xml", 32, 16);
    let mut s = settings(&desc);
    let integrator = Integrator::from_desc(&desc.integrator).expect("ic");
    let scene = Scene::build(&anim.scene_at(&desc, 0.0)).expect("scene");
    let pixels = s.width * s.height;
    let pass = |s: &RenderSettings, drawn: u32| {
        let out = render_runs(&scene, &integrator, s, &|_| {}, Some(&vec![drawn; pixels]))
            .expect("renders");
        let pre_pass = out.cache.as_ref().expect("the cache").stats.shadow_rays;
        let per_sample = (out.rays.shadow - pre_pass) as f64 / out.samples as f64;
        let mean = out
            .image
            .pixels
            .iter()
            .map(|c| f64::from(c.luminance()))
            .sum::<f64>()
            / pixels as f64;
        (per_sample, mean)
    };
    let (own, own_mean) = pass(&s, 0);
    let (continuing, continuing_mean) = pass(&s, 16);
    assert!(own > 2.5, "a pixel of its own: {own} shadow rays a sample");
    assert!(
        continuing > 0.5 && continuing <= 1.0,
        "a run's later frame: {continuing} shadow rays a sample"
    );
    assert!(
        (continuing_mean / own_mean - 1.0).abs() < 0.02,
        "means {continuing_mean} and {own_mean}"
    );
    s.sampling.adaptive = Some(Adaptive {
        target: 0.01,
        max_spp: 64,
    });
    let (adaptive, _) = pass(&s, 16);
    assert!(adaptive > 2.5, "adaptive: {adaptive} shadow rays a sample");
}
