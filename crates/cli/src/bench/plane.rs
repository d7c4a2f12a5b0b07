//! `ircache bench --only plane`: records from a rasterised plane against the stratified gather,
//! by Table 4.1's protocol (001 §4.4.2; NOTES-001 §C.4): the RMS relative error of the
//! irradiance at many visible points against a converged full-hemisphere estimate, for the
//! plane alone, the coverage division and border compensation
//! ([`ircache_render::irradiance_cache::plane`]). The thesis (Sibenik): 18.1 %, 10.4 %, 5.8 %.
//!
//! Sponza with its sun, the Cornell box and the lamp room, one bounce (the pixels' radiance is
//! the direct light at what they see: under Sponza's directional sun one shadow ray, no noise, as
//! a rasteriser with shadow maps gives it; under area lights one light sample, noisy), 1 500 points where random camera rays first meet a surface the cache serves (the thesis
//! took 10 000; a converged reference costs more here); the plane is the cache's, 64 × 64 pixels
//! of half-size 3 (143°; the notes infer 2, 127°, from 1 − F(2) = 16.9 %, but 3 errs less on all
//! three scenes, BENCHMARKS.md), one ray through each pixel centre; the
//! reference is the mean of two independent gathers of the cache's own kind with 16 384 cells
//! each and its adaptive super-sampling, whose own error is estimated from their difference. Also
//! the cache's default gather (512 cells) by the same measure.

use anyhow::Result;
use ircache_math::rgb::luminance_of;
use ircache_math::Vec3;
use ircache_render::irradiance_cache::gather::{
    Gatherer, SceneRadiance, ShadingPoint, WorkState, PLANE_HALF_SIZE, PLANE_PIXELS,
};
use ircache_render::irradiance_cache::hemisphere::{to_world, Stratification};
use ircache_render::irradiance_cache::plane::{HemispherePlane, PlaneEstimator};
use ircache_render::irradiance_cache::points::visible_sites;
use ircache_render::irradiance_cache::{IcParams, IrradianceCache};
use ircache_render::scene::Scene;
use ircache_scene::obj_scene::ObjCamera;
use rayon::prelude::*;
use std::path::Path;
use std::time::Instant;

/// Points measured.
const POINTS: usize = 1_500;

/// Cells of each of the two reference gathers.
const REFERENCE_CELLS: usize = 16_384;

/// Runs the comparison on Sponza with its sun, the Cornell box and the lamp room (an interior lit
/// by shaded lamps, the nearest of ircache's scenes to the thesis's Sibenik).
pub fn run_all(shared: &Path) -> Result<()> {
    let own = super::radiance::own_scenes();
    for (name, path) in [
        ("sponza-sun", shared.join("scenes/sponza-sun/scene.xml")),
        ("cornell-box", shared.join("scenes/cornell-box/scene.xml")),
        ("lamp-room", own.join("lamp-room/scene.xml")),
    ] {
        scene_table(name, &path)?;
    }
    println!(
        "  [the thesis, Sibenik: plane only 18.1 %, [LC04] 10.4 %, border compensation 5.8 %]"
    );
    Ok(())
}

/// The table for one scene.
fn scene_table(name: &str, path: &Path) -> Result<()> {
    let defines = vec![("max_depth".to_string(), "3".to_string())];
    let desc = ircache_scene::load_scene(path, &defines, &ObjCamera::default())?;
    let scene = Scene::build(&desc)?;
    let params = IcParams::default();
    let cache = IrradianceCache::new(&scene, &params);
    let light = SceneRadiance::path_traced(&scene);
    let g = Gatherer::new(&light, &cache, 7);
    // The points: first record sites of random camera rays.
    let points = visible_sites(&scene, POINTS, 11);
    let plane = HemispherePlane::new(PLANE_PIXELS, PLANE_HALF_SIZE);
    let estimators = [
        ("plane only", PlaneEstimator::PlaneOnly),
        ("coverage division [LC04]", PlaneEstimator::Coverage),
        ("border compensation", PlaneEstimator::BorderCompensation),
    ];
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    let t = Instant::now();
    // Per point: the reference, the default gather, and each estimator's irradiance (luminance);
    // and the gradients' squared errors against the reference gathers' (luminance).
    let rows: Vec<([f64; 6], Gradients)> = pool.install(|| {
        points
            .par_iter()
            .enumerate()
            .map(|(k, sp)| {
                let mut st = WorkState::new(cache.levels.len());
                let key = k as u64;
                let fine = Stratification::from_divisions(REFERENCE_CELLS);
                let ra = g.record_with(&mut st, sp, 0, key, fine);
                let rb = g.record_with(&mut st, sp, 0, !key, fine);
                let (a, b) = (ra.e.luminance(), rb.e.luminance());
                let reference = 0.5 * (a + b);
                let gathered = g.record_with(
                    &mut st,
                    sp,
                    0,
                    key ^ 0x5555,
                    Stratification::from_divisions(params.divisions),
                );
                let default = gathered.e.luminance();
                let pixels = plane.sample(&g, &mut st, sp, 0, key);
                let frame = ircache_math::Frame::from_z(sp.n);
                let (t, r) = plane.gradients(&pixels);
                let world = |g: &[Vec3; 3]| to_world(g, frame.s, frame.t);
                let gradients = Gradients::of(
                    [
                        (luminance_of(&ra.grad_t) + luminance_of(&rb.grad_t)) * 0.5,
                        (luminance_of(&ra.grad_r) + luminance_of(&rb.grad_r)) * 0.5,
                    ],
                    [
                        luminance_of(&gathered.grad_t),
                        luminance_of(&gathered.grad_r),
                    ],
                    [luminance_of(&world(&t)), luminance_of(&world(&r))],
                    [
                        (luminance_of(&ra.grad_t) - luminance_of(&rb.grad_t)) * 0.5,
                        (luminance_of(&ra.grad_r) - luminance_of(&rb.grad_r)) * 0.5,
                    ],
                );
                let mut row = [
                    f64::from(reference),
                    f64::from(default),
                    0.0,
                    0.0,
                    0.0,
                    0.5 * f64::from(a - b),
                ];
                for (slot, (_, e)) in row[2..].iter_mut().zip(&estimators) {
                    *slot = f64::from(plane.irradiance(&pixels.radiance, *e).luminance());
                }
                (row, gradients)
            })
            .collect()
    });
    let seconds = t.elapsed().as_secs_f64();
    let (rows, gradients): (Vec<[f64; 6]>, Vec<Gradients>) = rows.into_iter().unzip();
    let lit: Vec<&[f64; 6]> = rows.iter().filter(|r| r[0] > 0.0).collect();
    let rms_of = |f: &dyn Fn(&[f64; 6]) -> f64| {
        (lit.iter().map(|r| f(r).powi(2)).sum::<f64>() / lit.len() as f64).sqrt()
    };
    let rms = |c: usize| rms_of(&|r| (r[c] - r[0]) / r[0]);
    // Half the difference of the two halves: the mean's own error.
    let reference_error = rms_of(&|r| r[5] / r[0]);
    println!(
        "\nRecords from a rasterised plane (Table 4.1's protocol) on {name}, one bounce: {} points \
         ({} with indirect light), plane {PLANE_PIXELS} × {PLANE_PIXELS} at half-size \
         {PLANE_HALF_SIZE} ({:.0}°), {seconds:.1} s",
        rows.len(),
        lit.len(),
        2.0 * PLANE_HALF_SIZE.atan().to_degrees()
    );
    println!(
        "  RMS relative error of the irradiance against the reference (two {REFERENCE_CELLS}-cell \
         gathers; its own error {:.1} %):",
        100.0 * reference_error
    );
    for (c, (name, _)) in estimators.iter().enumerate() {
        println!("    {name:<28} {:>6.1} %", 100.0 * rms(c + 2));
    }
    println!(
        "    {:<28} {:>6.1} %   (the cache's gather, {} cells, super-sampled)",
        "stratified gather",
        100.0 * rms(1),
        params.divisions
    );
    let sum = gradients
        .iter()
        .fold(Gradients::default(), |a, b| a.plus(b));
    // The points with the 1 % largest reference gradients left out (beside geometry nearer than
    // the plane's pixels resolve, a few of them dominate every sum, as a few pixels do relMSE).
    let kept = |k: usize| {
        let mut order: Vec<&Gradients> = gradients.iter().collect();
        order.sort_by(|a, b| a.reference[k].total_cmp(&b.reference[k]));
        order.truncate(order.len() - order.len() / 100);
        order
            .into_iter()
            .fold(Gradients::default(), |a, b| a.plus(b))
    };
    for (kind, k) in [("translational", 0), ("rotational", 1)] {
        let rel = |e: f64| 100.0 * (e / sum.reference[k]).sqrt();
        let trim = kept(k);
        let rel_kept = |e: f64| 100.0 * (e / trim.reference[k]).sqrt();
        println!(
            "  {kind} gradient, RMS error over the RMS length of the reference's (two \
             {REFERENCE_CELLS}-cell gathers, Ward–Heckbert; its own {:.1} %), all points / the \
             1 % of largest reference gradients left out: border-compensated plane {:.1} / {:.1} \
             %, the cache's gather {:.1} / {:.1} %",
            rel(sum.own[k]),
            rel(sum.plane[k]),
            rel_kept(trim.plane[k]),
            rel(sum.gather[k]),
            rel_kept(trim.gather[k]),
        );
    }
    let references: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    on_the_gpu(&scene, &cache, &plane, &points, &references)?;
    rasterised(&scene, &light, &g, &plane, &points[..RASTERISED])
}

/// A point's gradients against the reference's: squared lengths of the reference (per kind:
/// translational, rotational), of the plane's and the default gather's differences from it, and
/// of the reference's own half-difference.
#[derive(Clone, Copy, Debug, Default)]
struct Gradients {
    reference: [f64; 2],
    plane: [f64; 2],
    gather: [f64; 2],
    own: [f64; 2],
}

impl Gradients {
    fn of(reference: [Vec3; 2], gather: [Vec3; 2], plane: [Vec3; 2], own: [Vec3; 2]) -> Self {
        let sq = |v: Vec3| f64::from(v.length_squared());
        Gradients {
            reference: [sq(reference[0]), sq(reference[1])],
            plane: [sq(plane[0] - reference[0]), sq(plane[1] - reference[1])],
            gather: [sq(gather[0] - reference[0]), sq(gather[1] - reference[1])],
            own: [sq(own[0]), sq(own[1])],
        }
    }

    fn plus(&self, o: &Gradients) -> Gradients {
        let add = |a: [f64; 2], b: [f64; 2]| [a[0] + b[0], a[1] + b[1]];
        Gradients {
            reference: add(self.reference, o.reference),
            plane: add(self.plane, o.plane),
            gather: add(self.gather, o.gather),
            own: add(self.own, o.own),
        }
    }
}

/// Border compensation with each record computed whole on the GPU (`ircache_gpu::records`:
/// rasterised, shaded through the shadow map, summed), by the same protocol: where the scene is
/// one the GPU frame serves and a device exists.
#[cfg(feature = "gpu")]
fn on_the_gpu(
    scene: &Scene,
    cache: &IrradianceCache,
    plane: &HemispherePlane,
    points: &[ShadingPoint],
    references: &[f64],
) -> Result<()> {
    use ircache_gpu::frame::GpuFrame;
    if GpuFrame::serves(scene).is_err() {
        return Ok(());
    }
    let gpu = match ircache_gpu::Gpu::new() {
        Ok(gpu) => std::sync::Arc::new(gpu),
        Err(e) => {
            println!("    on the GPU: not measured ({e})");
            return Ok(());
        }
    };
    let splatter = std::sync::Arc::new(ircache_gpu::splat::GpuSplatter::new(gpu.clone()));
    let frame = GpuFrame::new(
        gpu.clone(),
        splatter,
        scene,
        cache,
        ircache_gpu::frame::SHADOW_MAP,
    )?;
    let t = Instant::now();
    let records = frame.plane_records(&frame.plane_tables(plane), points)?;
    let seconds = t.elapsed().as_secs_f64();
    let (mut squared, mut lit) = (0.0f64, 0usize);
    for (r, &reference) in records.iter().zip(references) {
        if reference > 0.0 {
            squared += ((f64::from(r.irradiance.luminance()) - reference) / reference).powi(2);
            lit += 1;
        }
    }
    println!(
        "    {:<28} {:>6.1} %   (each record rasterised, shaded and summed on {}: {:.0} records/s)",
        "border compensation, GPU",
        100.0 * (squared / lit.max(1) as f64).sqrt(),
        gpu.describe(),
        points.len() as f64 / seconds
    );
    Ok(())
}

#[cfg(not(feature = "gpu"))]
fn on_the_gpu(
    _: &Scene,
    _: &IrradianceCache,
    _: &HemispherePlane,
    _: &[ShadingPoint],
    _: &[f64],
) -> Result<()> {
    Ok(())
}

/// Points whose planes are also rasterised.
const RASTERISED: usize = 200;

/// The same planes rasterised on the GPU (`ircache-gpu`'s visibility pass; lavapipe where there
/// is no GPU): planes per second, rasterised alone and shaded, against one ray per pixel, and
/// the border-compensated irradiance against the ray-cast plane's.
#[cfg(feature = "gpu")]
fn rasterised(
    scene: &Scene,
    light: &SceneRadiance,
    g: &Gatherer,
    plane: &HemispherePlane,
    points: &[ShadingPoint],
) -> Result<()> {
    use ircache_gpu::visibility::PlaneVisibility;
    let gpu = match ircache_gpu::Gpu::new() {
        Ok(gpu) => std::sync::Arc::new(gpu),
        Err(e) => {
            println!("  rasterised: not measured ({e})");
            return Ok(());
        }
    };
    let device = gpu.describe();
    let visibility = PlaneVisibility::new(gpu, scene);
    let t = Instant::now();
    for sp in points {
        visibility.triangles(plane, sp)?;
    }
    let raster = t.elapsed().as_secs_f64();
    let mut st = WorkState::new(1);
    let mut squared = 0.0f64;
    let mut fallbacks = 0;
    let mut shaded = 0.0;
    let mut traced = 0.0;
    for (k, sp) in points.iter().enumerate() {
        let t = Instant::now();
        let (pixels, missed) =
            visibility.record_plane(scene, light, g, &mut st, plane, sp, 0, k as u64)?;
        shaded += t.elapsed().as_secs_f64();
        fallbacks += missed;
        let t = Instant::now();
        let rays = plane.sample(g, &mut st, sp, 0, k as u64);
        traced += t.elapsed().as_secs_f64();
        let e = |l: &[ircache_math::Rgb]| {
            f64::from(
                plane
                    .irradiance(l, PlaneEstimator::BorderCompensation)
                    .luminance(),
            )
        };
        let (a, b) = (e(&pixels.radiance), e(&rays.radiance));
        if b > 0.0 {
            squared += ((a - b) / b).powi(2);
        }
    }
    let n = points.len() as f64;
    println!(
        "  rasterised on {device} ({} spheres as shells): {:.0} planes/s rasterised, {:.0} \
         shaded (one thread), against {:.0} ray-cast (one thread); irradiance RMS {:.2} % from the \
         ray-cast planes; {fallbacks} pixels traced (triangle edges, spheres)",
        visibility.spheres,
        n / raster,
        n / shaded,
        n / traced,
        100.0 * (squared / n).sqrt()
    );
    Ok(())
}

#[cfg(not(feature = "gpu"))]
fn rasterised(
    _: &Scene,
    _: &SceneRadiance,
    _: &Gatherer,
    _: &HemispherePlane,
    _: &[ShadingPoint],
) -> Result<()> {
    println!("  rasterised: not measured (built without the gpu feature)");
    Ok(())
}
