//! GPU splatting against the CPU splatter on the same cache and G-buffer (issue 12: "GPU
//! splatting equals the CPU splatter within float-blending tolerance"), under each error metric
//! and gradient mode, on the Cornell box with its `ic` pre-pass, and with records split over
//! several calls as the miss search splats them. On a machine without a GPU the device is Mesa's
//! lavapipe (`scripts/setup.sh` installs it); with no device at all the test fails and says so,
//! unless `IRCACHE_GPU_TESTS=skip`.

mod common;

use ircache_gpu::splat::GpuSplatter;
use ircache_render::integrators::Integrator;
use ircache_render::irradiance_cache::record::ErrorMetric;
use ircache_render::irradiance_cache::IrradianceCache;
use ircache_render::render::RenderSettings;
use ircache_render::scene::Scene;
use ircache_render::splatting::buffer::{CpuSplatter, Splatter};
use ircache_render::splatting::{GBuffer, SplatBuffer};
use ircache_scene::{ParamValue, SceneDesc, SourceLocation};
use std::sync::atomic::Ordering;
use std::sync::Arc;

fn cornell(size: u32, params: &[(&str, &str)]) -> SceneDesc {
    splat_at(common::shared("cornell-box"), size, params)
}

fn splat_at(mut desc: SceneDesc, size: u32, params: &[(&str, &str)]) -> SceneDesc {
    desc.integrator.kind = "splat".into();
    for (n, v) in params {
        desc.integrator.extra.push((
            (*n).into(),
            ParamValue::String((*v).into()),
            SourceLocation {
                file: Arc::new(std::path::PathBuf::from("<test>")),
                line: 1,
                column: 1,
            },
        ));
    }
    desc.sensor.film.width = size;
    desc.sensor.film.height = size;
    desc.sensor.spp = 2;
    desc
}

fn prepared(desc: &SceneDesc) -> (Scene, IrradianceCache, RenderSettings) {
    let s = RenderSettings::from_desc(desc, 5, 2).expect("sampler");
    let scene = Scene::build(desc).expect("scene builds");
    let integrator = Integrator::from_desc(&desc.integrator).expect("integrator");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("pool");
    let (ready, _) = integrator.prepare(&scene, &s, &pool).expect("pre-pass");
    let Integrator::Ic(ic) = ready else {
        panic!("not the cache's integrator")
    };
    let cache = (*ic.cache.expect("filled")).clone();
    (scene, cache, s)
}

#[test]
fn gpu_splatting_equals_the_cpu_splatter() {
    let Some(gpu) = common::gpu() else { return };
    let splatter = GpuSplatter::new(gpu);
    for params in [
        &[][..],
        &[("error_metric", "ward")],
        &[("error_metric", "hessian")],
        &[("gradients", "rotation")],
        &[("gradients", "none")],
    ] {
        let desc = cornell(48, params);
        let (scene, cache, s) = prepared(&desc);
        let n = cache.levels[0].len();
        assert!(n > 100, "{params:?}: {n} records");
        let reach = s.filter.radius();
        let samplers = s.sampler();
        let (mut compared, mut covered, mut far) = (0usize, 0usize, 0usize);
        let (metric, accuracy) = cache.levels[0].metric();
        // The error's coefficient of √(1 − n·n′) (`ErrorMetric::error`).
        let normal_scale = match metric {
            ErrorMetric::Tabellion => 0.2 / accuracy / 0.123_257_4,
            ErrorMetric::Ward | ErrorMetric::Hessian => 1.0 / accuracy,
        };
        let min_error_tolerance = 1e-4 + normal_scale * (4.0 * f32::EPSILON).sqrt();
        // Layer 1 refills layer 0's G-buffer in place, as the splat pass does: the GPU's copy
        // of the samples must follow.
        let mut g = GBuffer::build(&scene, &cache, &s, &samplers, 0);
        for layer in 0..2 {
            if layer > 0 {
                g.rebuild(&scene, &cache, &s, &samplers, layer);
            }
            let mut cpu = SplatBuffer::new(&g);
            CpuSplatter.splat(&mut cpu, &g, &cache, 0..n, &scene.camera, reach);
            // On the GPU in three calls, as the miss search splats batches.
            let mut gpu = SplatBuffer::new(&g);
            for ids in [0..n / 3, n / 3..n / 2, n / 2..n] {
                splatter.splat(&mut gpu, &g, &cache, ids, &scene.camera, reach);
            }
            for (i, (a, b)) in cpu.pixels.iter().zip(&gpu.pixels).enumerate() {
                compared += 1;
                // A record at the edge of its influence (error ≈ 1) may fall either side of
                // it with the GPU's rounding: its weight there is nearly zero.
                assert!(
                    a.count.abs_diff(b.count) <= 1,
                    "{params:?} sample {i}: {} vs {} records",
                    a.count,
                    b.count
                );
                match (a.irradiance(), b.irradiance()) {
                    (Some(x), Some(y)) => {
                        covered += 1;
                        let scale = x.max_channel().max(y.max_channel()).max(1e-30);
                        let d = x - y;
                        let gap = d.r.abs().max(d.g.abs()).max(d.b.abs()) / scale;
                        // Bit for bit on lavapipe; a GPU that fuses multiply-adds rounds the
                        // normals' dot product differently, and √(1 − n·n′) magnifies a
                        // rounding near n = n′ to √ε: the error, and so the weights, differ
                        // by up to the normal term's scale times √(4 ε).
                        assert!(gap <= 1e-2, "{params:?} sample {i}: {x:?} vs {y:?}");
                        let close =
                            gap <= 1e-4 && (a.min_error - b.min_error).abs() <= min_error_tolerance;
                        far += usize::from(!close);
                    }
                    (None, None) => {}
                    (x, y) => assert!(
                        a.count + b.count == 1,
                        "{params:?} sample {i}: {x:?} vs {y:?}"
                    ),
                }
            }
        }
        assert!(
            far * 1000 <= covered,
            "{params:?}: {far} of {covered} samples differ by more than rounding"
        );
        assert!(
            covered > compared / 2,
            "{params:?}: {covered} of {compared} covered"
        );
    }
    assert_eq!(
        splatter.failures.load(Ordering::Relaxed),
        0,
        "{:?}",
        splatter.first_failure.lock().map(|l| l.clone())
    );
    assert_eq!(splatter.glossy_on_cpu.load(Ordering::Relaxed), 0);
    assert!(splatter.gpu_calls.load(Ordering::Relaxed) >= 30);
}

/// With radiance records (ircache's cornell-rough, radiance cache on), the GPU's irradiance sums
/// and the CPU's glossy sums together equal the CPU splatter's.
#[test]
fn gpu_splatting_with_radiance_records_equals_the_cpu_splatter() {
    let Some(gpu) = common::gpu() else { return };
    let splatter = GpuSplatter::new(gpu);
    let desc = splat_at(
        common::load(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenes/cornell-rough/scene.xml"
        )),
        40,
        &[("radiance_cache", "on")],
    );
    let (scene, cache, s) = prepared(&desc);
    let n = cache.levels[0].len();
    assert!(!cache.radiance_records.is_empty());
    let g = GBuffer::build(&scene, &cache, &s, &s.sampler(), 0);
    let reach = s.filter.radius();
    let mut cpu = SplatBuffer::new(&g);
    CpuSplatter.splat(&mut cpu, &g, &cache, 0..n, &scene.camera, reach);
    let mut on_gpu = SplatBuffer::new(&g);
    splatter.splat(&mut on_gpu, &g, &cache, 0..n, &scene.camera, reach);
    assert_eq!(splatter.glossy_on_cpu.load(Ordering::Relaxed), 1);
    let mut glossy = 0;
    for (i, (a, b)) in cpu.pixels.iter().zip(&on_gpu.pixels).enumerate() {
        let near = |x: Option<ircache_math::Rgb>, y: Option<ircache_math::Rgb>| match (x, y) {
            (Some(x), Some(y)) => {
                let d = x - y;
                d.r.abs().max(d.g.abs()).max(d.b.abs())
                    <= 1e-4 * x.max_channel().max(y.max_channel()).max(1e-30)
            }
            (x, y) => x.is_none() && y.is_none(),
        };
        assert!(
            near(a.irradiance(), b.irradiance()),
            "sample {i}: irradiance"
        );
        assert!(near(a.glossy(), b.glossy()), "sample {i}: glossy");
        glossy += usize::from(a.glossy().is_some());
    }
    assert!(glossy > 200, "{glossy} samples with glossy light");
}
